//! Solver parameters (serde form) and their validated counterpart.

use crate::boundary::{RigidWall, SurfaceLoad, TemperatureCondition, VelocityCondition};
use crate::error::MpmError;
use crate::grid::{Grid, GridParameters};
use serde::{Deserialize, Serialize};

fn one() -> f64 {
    1.0
}

/// Parameters of an MPM model (serde form; validated by [`MpmConfig::new`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MpmParameters {
    /// The background grid.
    pub grid: GridParameters,
    /// PIC fraction `α_PIC ∈ [0, 1]` of B-Eqs. 25–27 (0 = pure FLIP).
    #[serde(default)]
    pub pic_fraction: f64,
    /// Grid damping `α_g ∈ [0, 1]` of B-Eqs. 26–27.
    #[serde(default)]
    pub grid_damping: f64,
    /// Particle damping `α_p ∈ [0, 1]` of B-Eqs. 26–27.
    #[serde(default)]
    pub particle_damping: f64,
    /// Local non-viscous damping `α_l ∈ [0, 1)` of the nodal forces (Cundall's local damping
    /// carried to the grid): each component of a node's force (internal, external and
    /// gravity) is reduced by `α_l |f_i|` against the node's velocity, `f_i − α_l |f_i|
    /// sgn(v_i)`. Unlike B-Eq. 26's `α_g` and `α_p`, which damp the velocity itself and so
    /// resist a steady motion, it removes energy only while the forces are out of balance:
    /// the choice for quasi-static loading. Not in the paper; 0 (the default) leaves the
    /// update as B-Eqs. 20–22.
    #[serde(default)]
    pub local_damping: f64,
    /// The factor `b > 0` of the thermal time-step limit B-Eq. 31 (paper default 1).
    #[serde(default = "one")]
    pub thermal_time_step_factor: f64,
    /// Nodes whose mass is at most this (kg per metre of thickness) are left out of the
    /// velocity update (velocity 0, like an empty node). A node that a point's domain only
    /// grazes at a free surface gets a tiny mass but a finite share of the point's internal
    /// force, and its velocity, hence the point's velocity gradient, blows up (the small-mass
    /// problem of GIMP). 0 (the default): every node with mass is updated.
    #[serde(default)]
    pub node_mass_tolerance: f64,
    /// Instead of leaving a node at or below `node_mass_tolerance` out, merge it with the
    /// heavier of its two neighbours along its node row whose mass is above the tolerance:
    /// both take the acceleration of their summed force over their summed mass, so the force
    /// the small node carries (a share of its points' internal force and of their loads) is
    /// kept and its velocity does not run away from its neighbour's. A small node with no
    /// such neighbour is left out as without merging. Along rows only: the
    /// sides of a specimen that bulges sideways (a biaxial test's confined sides). Default
    /// false: left out, as above.
    #[serde(default)]
    pub merge_small_mass_nodes: bool,
    /// Body force per unit mass `b_i` (m/s²), e.g. gravity.
    #[serde(default)]
    pub gravity: [f64; 2],
    /// Prescribed nodal velocities.
    #[serde(default)]
    pub velocity_conditions: Vec<VelocityCondition>,
    /// Prescribed nodal temperatures.
    #[serde(default)]
    pub temperature_conditions: Vec<TemperatureCondition>,
    /// Tractions and heat fluxes through the virtual boundary layer.
    #[serde(default)]
    pub surface_loads: Vec<SurfaceLoad>,
    /// Rigid walls and plates.
    #[serde(default)]
    pub walls: Vec<RigidWall>,
}

impl MpmParameters {
    /// Parameters with the given grid and everything else at its default (pure FLIP, no
    /// damping, `b = 1`, no gravity, no boundary conditions).
    pub fn on_grid(grid: GridParameters) -> Self {
        Self {
            grid,
            pic_fraction: 0.0,
            grid_damping: 0.0,
            particle_damping: 0.0,
            local_damping: 0.0,
            thermal_time_step_factor: 1.0,
            node_mass_tolerance: 0.0,
            merge_small_mass_nodes: false,
            gravity: [0.0; 2],
            velocity_conditions: Vec::new(),
            temperature_conditions: Vec::new(),
            surface_loads: Vec::new(),
            walls: Vec::new(),
        }
    }
}

/// Validated parameters. Construct with [`MpmConfig::new`]; serialisable for the record, but
/// not deserialisable (rebuild it from [`MpmParameters`], which validates).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MpmConfig {
    pub(crate) grid: Grid,
    pub(crate) params: MpmParameters,
    /// Per node: bit 0 = hold v_x, bit 1 = hold v_y.
    pub(crate) velocity_mask: Vec<u8>,
    /// Per node: the prescribed temperature, NaN where free.
    pub(crate) fixed_temperature: Vec<f64>,
}

fn unit_interval(name: &str, v: f64) -> Result<(), MpmError> {
    if (0.0..=1.0).contains(&v) {
        Ok(())
    } else {
        Err(MpmError::InvalidParameter {
            name: name.into(),
            value: v,
            allowed: "[0, 1]",
        })
    }
}

/// Checks every surface load (positive layer thickness, finite traction and flux), naming
/// the first bad one by its key path.
pub(crate) fn check_surface_loads(loads: &[SurfaceLoad]) -> Result<(), MpmError> {
    for (k, s) in loads.iter().enumerate() {
        if !(s.layer_thickness.is_finite() && s.layer_thickness > 0.0) {
            return Err(MpmError::InvalidParameter {
                name: format!("surface_loads[{k}].layer_thickness"),
                value: s.layer_thickness,
                allowed: "(0, inf) m",
            });
        }
        let vals = [s.traction[0], s.traction[1], s.inward_heat_flux];
        if let Some(v) = vals.iter().find(|v| !v.is_finite()) {
            return Err(MpmError::InvalidParameter {
                name: format!("surface_loads[{k}].traction/inward_heat_flux"),
                value: *v,
                allowed: "finite",
            });
        }
    }
    Ok(())
}

impl MpmConfig {
    /// Validates the parameters.
    pub fn new(params: MpmParameters) -> Result<Self, MpmError> {
        let grid = Grid::new(&params.grid)?;
        unit_interval("pic_fraction", params.pic_fraction)?;
        unit_interval("grid_damping", params.grid_damping)?;
        unit_interval("particle_damping", params.particle_damping)?;
        let ld = params.local_damping;
        if !(0.0..1.0).contains(&ld) {
            return Err(MpmError::InvalidParameter {
                name: "local_damping".into(),
                value: ld,
                allowed: "[0, 1)",
            });
        }
        let b = params.thermal_time_step_factor;
        if !(b.is_finite() && b > 0.0) {
            return Err(MpmError::InvalidParameter {
                name: "thermal_time_step_factor".into(),
                value: b,
                allowed: "(0, inf)",
            });
        }
        let tol = params.node_mass_tolerance;
        if !(tol.is_finite() && tol >= 0.0) {
            return Err(MpmError::InvalidParameter {
                name: "node_mass_tolerance".into(),
                value: tol,
                allowed: "[0, inf) kg/m",
            });
        }
        for (k, g) in params.gravity.iter().enumerate() {
            if !g.is_finite() {
                return Err(MpmError::InvalidParameter {
                    name: format!("gravity[{k}]"),
                    value: *g,
                    allowed: "finite m/s^2",
                });
            }
        }
        for (k, t) in params.temperature_conditions.iter().enumerate() {
            if !t.temperature.is_finite() {
                return Err(MpmError::InvalidParameter {
                    name: format!("temperature_conditions[{k}].temperature"),
                    value: t.temperature,
                    allowed: "finite",
                });
            }
        }
        check_surface_loads(&params.surface_loads)?;
        let mut params = params;
        for (k, w) in params.walls.iter_mut().enumerate() {
            *w = w.validated(k)?;
        }
        let [nx, ny] = grid.nodes();
        let mut velocity_mask = vec![0u8; nx * ny];
        let mut fixed_temperature = vec![f64::NAN; nx * ny];
        for j in 0..ny {
            for i in 0..nx {
                let n = grid.node_index(i, j);
                for c in &params.velocity_conditions {
                    if c.nodes.contains(&grid, i, j) {
                        velocity_mask[n] |= u8::from(c.fix_x) | (u8::from(c.fix_y) << 1);
                    }
                }
                for c in &params.temperature_conditions {
                    if c.nodes.contains(&grid, i, j) {
                        fixed_temperature[n] = c.temperature;
                    }
                }
            }
        }
        Ok(Self {
            grid,
            params,
            velocity_mask,
            fixed_temperature,
        })
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }
    /// The (validated) parameters.
    pub fn parameters(&self) -> &MpmParameters {
        &self.params
    }
}
