//! The granular rod of B-Sect. 5.2.1 (Zhao et al. 2022): a 1 m rod fixed at both ends, 50
//! cells with one material point each, every point carrying an RVE of 400 disks (r = 5 mm)
//! in a regular (square) packing under 100 kPa, heated from 0 °C to 100 °C at `x = L`; and
//! the quasi-static solutions B-Eqs. 55–57 it is checked against.

use serde::{Deserialize, Serialize};
use thm_dem::Vec3;
use thm_mpm::{
    GridParameters, LinearThermoElastic, MaterialPoints, Mpm, MpmConfig, MpmParameters, MpmState,
    NodeSet, PointProperties, TemperatureCondition, ThermoElasticParameters, VelocityCondition,
};
use thm_rve::{Mat2, PeriodicCell, RveParams, RveState, RveStepper, measure};

use super::error::MultiscaleError;
use super::material::RveMaterial;
use super::params::{DemTimeRule, MultiscaleParams};
use super::point::RvePoint;

/// The granular rod's parameters (SI; temperatures in °C on the MPM side).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GranularRod {
    /// Rod length L (m).
    pub length: f64,
    /// Cells (one material point each) along the rod.
    pub cells: usize,
    /// Bulk density of the material points ρ (kg/m³).
    pub density: f64,
    /// Specific heat capacity c (J/(kg K)).
    pub specific_heat: f64,
    /// Initial and cold-end temperature T₀ (°C).
    pub cold_temperature: f64,
    /// Hot-end temperature (°C), `T₁` of B-Eqs. 55–57.
    pub hot_temperature: f64,
    /// Confining (consolidation) stress of every RVE σ₀ (Pa).
    pub confining_stress: f64,
    /// Disks along each side of the square packing (20 × 20 = 400).
    pub disks_per_side: usize,
    /// Disk radius r (m).
    pub disk_radius: f64,
    /// Rod conductivity k (W/(m K)) that sets the heat-pipe resistance α of B-Eq. 34.
    pub conductivity: f64,
    /// MPM time step (s).
    pub time_step: f64,
    /// PIC fraction α_PIC of B-Eq. 26 (the paper does not state it for this case).
    pub pic_fraction: f64,
    /// Grid damping α_g of B-Eq. 26 (the paper does not state it for this case).
    pub grid_damping: f64,
    /// RVE contact law, density, expansion, thickness and damping (α is replaced).
    pub rve: RveParams,
    /// The DEM time rule.
    pub dem_time: DemTimeRule,
}

impl GranularRod {
    /// B-Sect. 5.2.1 with B-Table 1: L = 1 m, 50 cells, ρ = 2650 kg/m³, c = 1/2650 J/(kg K),
    /// k = 0.1 W/(m K), β = 10⁻⁴ /K, k_n = k_t = 10⁶ N/m, μ = 0.001, z_p = 75 mm, 20 × 20 disks of
    /// r = 5 mm under 100 kPa, Δt = 10⁻⁴ s, 0 → 100 °C. Where the paper is silent: α_PIC = 0,
    /// grid damping α_g = 0.01 (the stress wave of the sudden heating decays in about 10 ms, as
    /// B-Fig. 9's "relaxes with time"; undamped, it rings at ±20 kPa around B-Eq. 56 for the
    /// whole second) and the DEM time rule's defaults (c = 0.2, no density scaling).
    pub fn paper() -> Self {
        Self {
            length: 1.0,
            cells: 50,
            density: 2650.0,
            specific_heat: 1.0 / 2650.0,
            cold_temperature: 0.0,
            hot_temperature: 100.0,
            confining_stress: 1e5,
            disks_per_side: 20,
            disk_radius: 5e-3,
            conductivity: 0.1,
            time_step: 1e-4,
            pic_fraction: 0.0,
            grid_damping: 0.01,
            rve: RveParams::paper_b_table_1(),
            dem_time: DemTimeRule::default(),
        }
    }

    /// Thermal diffusivity `k / (ρ c)` (m²/s).
    pub fn diffusivity(&self) -> f64 {
        self.conductivity / (self.density * self.specific_heat)
    }

    /// Cell size `L / cells` (m).
    pub fn cell_size(&self) -> f64 {
        self.length / self.cells as f64
    }
}

/// The regular packing of B-Fig. 8(c): `n × n` disks of radius `r` on a square lattice in a
/// square periodic cell, at the reference temperature, with the overlap
/// `δ = σ₀ z_p 2r / (k_n + σ₀ z_p)` that makes both normal stresses σ₀ (B-Eq. 49:
/// `σ = k_n δ / (a z_p)` for the spacing `a = 2r − δ`), its contacts evaluated. Built at the
/// consolidated state directly: a perfect lattice consolidated by the servo of `thm-rve`
/// ends in this state.
pub fn square_lattice(
    params: &RveParams,
    per_side: usize,
    radius: f64,
    confining_stress: f64,
) -> Result<RveState, MultiscaleError> {
    let config = params.validate().map_err(MultiscaleError::RveSetup)?;
    if per_side < 2 {
        return Err(MultiscaleError::InvalidParameter {
            field: "disks_per_side",
            value: per_side as f64,
            allowed: "[2, inf)",
        });
    }
    for (field, v) in [
        ("disk_radius", radius),
        ("confining_stress", confining_stress),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(MultiscaleError::InvalidParameter {
                field,
                value: v,
                allowed: "(0, inf)",
            });
        }
    }
    let kn = params.contact.normal_stiffness;
    let sz = confining_stress * params.thickness;
    let overlap = sz * 2.0 * radius / (kn + sz);
    let a = 2.0 * radius - overlap;
    let side = per_side as f64 * a;
    let cell = PeriodicCell::rectangle(side, side).map_err(MultiscaleError::RveSetup)?;
    let mut centres = Vec::with_capacity(per_side * per_side);
    for j in 0..per_side {
        for i in 0..per_side {
            centres.push(Vec3::new((i as f64 + 0.5) * a, (j as f64 + 0.5) * a, 0.0));
        }
    }
    let radii = vec![radius; centres.len()];
    let mut state = RveState::new(
        cell,
        &centres,
        &radii,
        params.density,
        params.thickness,
        params.reference_temperature,
    )
    .map_err(MultiscaleError::RveSetup)?;
    let mut stepper = RveStepper::new(config);
    stepper
        .update_neighbours(&mut state)
        .map_err(MultiscaleError::RveSetup)?;
    stepper.compute_contact_forces(&mut state, &Mat2::ZERO, 1e-9);
    Ok(state)
}

/// The rod's RVE parameters: `params.rve` with the heat-pipe resistance α of B-Eq. 34 set so
/// that the packing conducts `k` along the rod (B-Table 1 gives k = 0.1 W/(m K) for both
/// models, not α).
pub fn rod_rve_params(rod: &GranularRod) -> Result<(RveParams, RveState), MultiscaleError> {
    let mut p = rod.rve;
    p.thermal_resistance = 1.0;
    let lattice = square_lattice(
        &p,
        rod.disks_per_side,
        rod.disk_radius,
        rod.confining_stress,
    )?;
    let k1 = measure::conductivity(&lattice, &p).at(0, 0);
    if !(rod.conductivity.is_finite() && rod.conductivity > 0.0) {
        return Err(MultiscaleError::InvalidParameter {
            field: "conductivity",
            value: rod.conductivity,
            allowed: "(0, inf) W/(m K)",
        });
    }
    p.thermal_resistance = k1 / rod.conductivity;
    Ok((p, lattice))
}

/// The rod as a coupled model: stepper, state (an RVE per point) and material.
#[derive(Debug, Clone)]
pub struct RodModel {
    /// The MPM stepper.
    pub mpm: Mpm,
    /// The state: material points with their RVEs.
    pub state: MpmState<RvePoint>,
    /// The RVE-backed material.
    pub material: RveMaterial,
    /// The parameters.
    pub rod: GranularRod,
}

impl RodModel {
    /// The rod of B-Fig. 8(b): grid of `cells + 2` × 2 cells of `h = L/cells` with one padding
    /// cell beyond each end; one row of points filling `[0, L] × [0, h]`; `v_x = 0` and the end
    /// temperatures on the nodes at and beyond each end; `v_y = 0` everywhere (see the module
    /// docs: with ν = 0 of the square packing, σ_x does not depend on the lateral condition).
    pub fn new(rod: &GranularRod) -> Result<Self, MultiscaleError> {
        let config = rod_grid(rod)?;
        let (rve, lattice) = rod_rve_params(rod)?;
        let material = RveMaterial::new(
            &MultiscaleParams {
                rve,
                dem_time: rod.dem_time,
                kelvin_offset: rve.reference_temperature - rod.cold_temperature,
                quasi_static: None,
            },
            lattice,
        )?;
        let state = material.state(rod_points(rod, &config)?);
        Ok(Self {
            mpm: Mpm::new(config),
            state,
            material,
            rod: *rod,
        })
    }

    /// One coupled step of the rod's time step.
    pub fn step(&mut self) -> Result<(), MultiscaleError> {
        self.mpm
            .step_batch(&mut self.state, &mut self.material, self.rod.time_step)
    }

    /// Axial stiffness `K = D_xxxx` of B-Eq. 58 measured on the template RVE (Pa).
    pub fn axial_stiffness(&self) -> f64 {
        let p = self.material.config().rve().params();
        measure::stiffness(&self.material.initial_point().rve, p)[0][0][0][0]
    }

    /// Displacement `u_x = x_p − X_p` of every point (m), with `X_p` its initial position.
    pub fn displacements(&self) -> Vec<f64> {
        rod_displacements(&self.rod, &self.state.points)
    }
}

/// Young's modulus of the TM-MPM column of B-Table 1 (Pa).
pub const TWIN_YOUNGS_MODULUS: f64 = 1.33e7;

/// The TM-MPM rod of B-Fig. 9(a–c): the grid, boundary conditions, damping, time step and
/// points of [`RodModel`], every point linear thermo-elastic with B-Table 1's TM-MPM column
/// (E = 13.3 MPa, ν = 0, β = the RVE's expansion coefficient, k and ρ c as the rod), starting
/// stress-free (with ν = 0 the 100 kPa confinement does not change σ_x or u_x).
#[derive(Debug, Clone)]
pub struct RodTwin {
    /// The MPM stepper.
    pub mpm: Mpm,
    /// The state: material points, no history.
    pub state: MpmState<()>,
    /// The thermo-elastic material.
    pub material: LinearThermoElastic,
    /// The parameters.
    pub rod: GranularRod,
}

impl RodTwin {
    /// The twin of [`RodModel::new`]`(rod)`.
    pub fn new(rod: &GranularRod) -> Result<Self, MultiscaleError> {
        let config = rod_grid(rod)?;
        let material = LinearThermoElastic::new(&ThermoElasticParameters {
            youngs_modulus: TWIN_YOUNGS_MODULUS,
            poisson_ratio: 0.0,
            thermal_expansion: rod.rve.thermal_expansion_coefficient,
            conductivity: [rod.conductivity, rod.conductivity, 0.0],
        })?;
        let points = rod_points(rod, &config)?;
        let n = points.len();
        Ok(Self {
            mpm: Mpm::new(config),
            state: MpmState {
                points,
                material: vec![(); n],
                time: 0.0,
                step: 0,
            },
            material,
            rod: *rod,
        })
    }

    /// One step of the rod's time step.
    pub fn step(&mut self) -> Result<(), MultiscaleError> {
        self.mpm
            .step(&mut self.state, &self.material, self.rod.time_step)?;
        Ok(())
    }

    /// Displacement `u_x = x_p − X_p` of every point (m).
    pub fn displacements(&self) -> Vec<f64> {
        rod_displacements(&self.rod, &self.state.points)
    }
}

/// The rod's grid of B-Fig. 8(b): `cells + 2` × 2 cells of `h = L/cells` with one padding cell
/// beyond each end; `v_x = 0` and the end temperatures on the nodes at and beyond each end;
/// `v_y = 0` everywhere (with ν = 0, σ_x does not depend on the lateral condition).
fn rod_grid(rod: &GranularRod) -> Result<MpmConfig, MultiscaleError> {
    if rod.cells < 2 {
        return Err(MultiscaleError::InvalidParameter {
            field: "cells",
            value: rod.cells as f64,
            allowed: "[2, inf)",
        });
    }
    let h = rod.cell_size();
    let l = rod.length;
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [-h, 0.0],
        cell_size: h,
        cells: [rod.cells + 2, 2],
    });
    params.pic_fraction = rod.pic_fraction;
    params.grid_damping = rod.grid_damping;
    let eps = 1e-9 * h;
    let cold = NodeSet::Region {
        lower: [-2.0 * h, -1.0],
        upper: [eps, 1.0],
    };
    let hot = NodeSet::Region {
        lower: [l - eps, -1.0],
        upper: [l + 2.0 * h, 1.0],
    };
    params.velocity_conditions = vec![
        VelocityCondition {
            nodes: NodeSet::All,
            fix_x: false,
            fix_y: true,
        },
        VelocityCondition {
            nodes: cold,
            fix_x: true,
            fix_y: true,
        },
        VelocityCondition {
            nodes: hot,
            fix_x: true,
            fix_y: true,
        },
    ];
    params.temperature_conditions = vec![
        TemperatureCondition {
            nodes: cold,
            temperature: rod.cold_temperature,
        },
        TemperatureCondition {
            nodes: hot,
            temperature: rod.hot_temperature,
        },
    ];
    Ok(MpmConfig::new(params)?)
}

/// One row of points (one per cell) filling `[0, L] × [0, h]` at the cold temperature.
fn rod_points(rod: &GranularRod, config: &MpmConfig) -> Result<MaterialPoints, MultiscaleError> {
    let mut points = MaterialPoints::new();
    points.fill_rectangle(
        config.grid(),
        [0.0, 0.0],
        [rod.length, rod.cell_size()],
        1,
        &PointProperties {
            density: rod.density,
            specific_heat: rod.specific_heat,
            conductivity: [rod.conductivity, rod.conductivity, 0.0],
            temperature: rod.cold_temperature,
            velocity: [0.0; 2],
        },
    )?;
    Ok(points)
}

/// `u_x = x_p − X_p` of the rod's points, `X_p = (p + ½) h`.
pub fn rod_displacements(rod: &GranularRod, points: &MaterialPoints) -> Vec<f64> {
    let h = rod.cell_size();
    points
        .position
        .iter()
        .enumerate()
        .map(|(i, x)| x[0] - (i as f64 + 0.5) * h)
        .collect()
}

/// Terms of the series of B-Eqs. 55–57 (the slowest, `n = 1`, decays as `e^{−π² κ t/L²}`;
/// 4000 terms resolve `t ≥ 10⁻⁴ s` on the rod to round-off).
const SERIES_TERMS: usize = 4000;

/// B-Eq. 55: temperature of the rod at `x`, time `t`, with `T(0) = T₀` (initial and cold end),
/// `T(L) = T₁` (the printed `T₁ − T₀ = 0` of the set-up text is read as the hot-end rise) and
/// diffusivity `κ = k/(ρ c)`.
pub fn rod_temperature(x: f64, t: f64, length: f64, t0: f64, t1: f64, kappa: f64) -> f64 {
    use std::f64::consts::PI;
    let dt = t1 - t0;
    let mut s = 0.0;
    for n in 1..=SERIES_TERMS {
        let nf = n as f64;
        let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
        let decay = (-(nf * PI / length).powi(2) * kappa * t).exp();
        if decay == 0.0 {
            break;
        }
        s += sign / nf * decay * (nf * PI * x / length).sin();
    }
    t0 + dt * x / length + 2.0 * dt / PI * s
}

/// B-Eq. 56: the quasi-static axial stress `σ_x(t) = −K β (T̄ − T₀)` (tension positive,
/// relative to the initial stress), `T̄` the mean temperature of the rod:
/// `−K β ΔT/2 + (4 K β ΔT/π²) Σ_k e^{−(2k+1)² π² κ t/L²}/(2k+1)²`.
pub fn rod_stress(t: f64, length: f64, t0: f64, t1: f64, kappa: f64, k: f64, beta: f64) -> f64 {
    use std::f64::consts::PI;
    let dt = t1 - t0;
    let mut s = 0.0;
    for j in 0..SERIES_TERMS {
        let m = (2 * j + 1) as f64;
        let decay = (-(m * m) * PI * PI / (length * length) * kappa * t).exp();
        if decay == 0.0 {
            break;
        }
        s += decay / (m * m);
    }
    -k * beta * dt / 2.0 + 4.0 * k * beta * dt / (PI * PI) * s
}

/// B-Eq. 57 as derived, `u = β ∫₀ˣ (T − T₀) dx − (x/L) β ∫₀ᴸ (T − T₀) dx`:
/// `β ΔT x (x − L)/(2L) − (2 β L ΔT/π²) Σ_n (−1)ⁿ/n² e^{−(nπ/L)² κ t}
/// (cos(nπx/L) − (x/L) cos nπ + x/L − 1)`. The printed form has `cos(nπx/x)` for
/// `cos(nπx/L)`.
pub fn rod_displacement(
    x: f64,
    t: f64,
    length: f64,
    t0: f64,
    t1: f64,
    kappa: f64,
    beta: f64,
) -> f64 {
    use std::f64::consts::PI;
    let dt = t1 - t0;
    let xi = x / length;
    let mut s = 0.0;
    for n in 1..=SERIES_TERMS {
        let nf = n as f64;
        let cos_n = if n % 2 == 0 { 1.0 } else { -1.0 };
        let decay = (-(nf * PI / length).powi(2) * kappa * t).exp();
        if decay == 0.0 {
            break;
        }
        s += cos_n / (nf * nf) * decay * ((nf * PI * xi).cos() - xi * cos_n + xi - 1.0);
    }
    beta * dt * x * (x - length) / (2.0 * length) - 2.0 * beta * length * dt / (PI * PI) * s
}
