//! Parameters of the pore-scale coupled step (`serde`, as read from a scenario) and their
//! validated form.

use serde::{Deserialize, Serialize};
use thm_dem::{CohesiveFrictional, CohesiveFrictionalParams, StepperParams};
use thm_fvm_heat::HeatParams;
use thm_vpn_flow::{BoundaryCondition, FlowConfig, FlowParameters};
use thm_vpn_mesh::{BoundarySide, MeshParams, MeshSettings, RemeshCriteria, RemeshCriteriaParams};

use super::error::CouplingError;

/// How the spheres move.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Skeleton {
    /// Every sphere is held: no DEM step, no mesh motion, no change of radius, no remesh
    /// (A-Sect. 6 case b, and the fluid–heat cases of A-Sects. 4–5). Fluid forces are still
    /// computed (they are reported), but nothing moves.
    #[default]
    Fixed,
    /// Spheres move under contact and fluid forces and change radius with their temperature
    /// (A-Eq. 55); the mesh follows them and is rebuilt on its trigger (A-Sect. 6 case a).
    /// Spheres flagged `fixed` in the DEM state stay where they are.
    Free,
}

/// How heat is advanced over one coupled step.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum HeatScheme {
    /// Explicit sub-steps under the stability limit of `thm-fvm-heat` (conduction and
    /// advection).
    #[default]
    Explicit,
    /// One backward-Euler step per coupled step (`HeatStepper::implicit_step`): conduction
    /// with the deferred cross terms, and first-order upwind advection by the step's mean
    /// channel and boundary mass rates.
    Implicit,
}

/// How the pore pressures are advanced over one coupled step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FlowScheme {
    /// Explicit sub-steps under the stability and positivity limits of `thm-vpn-flow`
    /// (~10⁻⁸ s for water-filled pores).
    #[default]
    Explicit,
    /// Linearly implicit pressure sub-steps (`FlowStepper::implicit_step`): one per coupled
    /// step unless positivity or the closure asks for shorter ones. Mass is conserved to
    /// round-off either way; the time error is first order in Δt_C.
    Implicit,
}

/// How the pore pressures push the spheres.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PressureForce {
    /// A-Eqs. 52–53: `P_i e_k w n` on the sphere behind every wall face, held over the
    /// coupled step.
    #[default]
    WallFaces,
    /// `P_i ∂V_i/∂c_s` through every cell corner anchored to a sphere, with each pore's
    /// undrained response updated before every DEM sub-step and its spring integrated
    /// implicitly after it (`pore_forces` module docs). Used only with a free skeleton; the
    /// S2S shear of A-Eq. 54 is unchanged.
    CellCorners,
}

/// A fluid boundary condition on one side of the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlowBoundary {
    /// Side of the mesh (`left`, `right`, `bottom`, `top`, `outline`).
    pub side: BoundarySide,
    /// The condition (pressure, mass rate, impermeable).
    pub condition: BoundaryCondition,
}

fn default_boundary_reduction_factor() -> f64 {
    0.0115
}

/// All parameters of the pore-scale coupled step (A-Fig. 7).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoreScaleParams {
    /// Fixed or free skeleton.
    #[serde(default)]
    pub skeleton: Skeleton,
    /// DEM stepper: `time_step` is Δt_D; a coupled step of length Δt_C takes
    /// `ceil(Δt_C / Δt_D)` equal DEM steps (used only with a free skeleton).
    pub dem: StepperParams,
    /// Contact law of the spheres (A-Eqs. 1–7).
    pub contact: CohesiveFrictionalParams,
    /// Linear thermal expansion coefficient of the solid α_exp \[1/K\] (A-Eq. 55; Table 1:
    /// 8·10⁻⁶, A-Sect. 6: 8.3·10⁻⁴).
    pub thermal_expansion: f64,
    /// Mesher settings (outline, resolution, γ of A-Eq. 9, the S2S law A-Eq. 8).
    pub mesh: MeshParams,
    /// When the mesh is rebuilt.
    #[serde(default)]
    pub remesh: RemeshCriteriaParams,
    /// Channel flow (viscosities, sub-step safety factors).
    pub flow: FlowParameters,
    /// How the pressures are advanced (default explicit).
    #[serde(default)]
    pub flow_scheme: FlowScheme,
    /// Whether pores that hold only liquid may go into tension (a negative pressure on the
    /// liquid branch of the EOS; cavitation is not modelled). Default false: any negative
    /// pressure after the flow stage stops the run. Water sealed in pores that the network
    /// does not connect to a reservoir contracts at fixed mass when it cools (A-Sects. 4–5).
    #[serde(default)]
    pub liquid_tension: bool,
    /// Fluid boundary conditions by side; sides not listed are impermeable.
    #[serde(default)]
    pub flow_boundaries: Vec<FlowBoundary>,
    /// Reduction factor of the half-channels to prescribed-pressure reservoirs (A-Eq. 9 form).
    #[serde(default = "default_boundary_reduction_factor")]
    pub boundary_reduction_factor: f64,
    /// How the pore pressures push the spheres (default: A-Eqs. 52–53).
    #[serde(default)]
    pub pressure_force: PressureForce,
    /// Heat transfer (properties, boundary conditions, interface model).
    pub heat: HeatParams,
    /// How heat is advanced.
    #[serde(default)]
    pub heat_scheme: HeatScheme,
}

/// Validated [`PoreScaleParams`].
#[derive(Debug, Clone)]
pub struct PoreScaleConfig {
    pub(crate) params: PoreScaleParams,
    pub(crate) law: CohesiveFrictional,
    pub(crate) mesh: MeshSettings,
    pub(crate) remesh: RemeshCriteria,
    pub(crate) flow: FlowConfig,
}

impl PoreScaleParams {
    /// Validates every part once; errors name the field.
    pub fn validate(&self) -> Result<PoreScaleConfig, CouplingError> {
        self.dem.validate().map_err(CouplingError::Dem)?;
        let law = self.contact.validate().map_err(CouplingError::Dem)?;
        if !(self.thermal_expansion.is_finite() && self.thermal_expansion.abs() < 0.1) {
            return Err(CouplingError::Parameter {
                field: "thermal_expansion",
                range: "finite, |α_exp| < 0.1 1/K",
                value: self.thermal_expansion,
            });
        }
        if !(self.boundary_reduction_factor.is_finite() && self.boundary_reduction_factor > 0.0) {
            return Err(CouplingError::Parameter {
                field: "boundary_reduction_factor",
                range: "> 0",
                value: self.boundary_reduction_factor,
            });
        }
        let mesh = self.mesh.validate().map_err(CouplingError::Mesh)?;
        let remesh = self.remesh.validate().map_err(CouplingError::Mesh)?;
        let flow = FlowConfig::new(self.flow).map_err(CouplingError::Flow)?;
        Ok(PoreScaleConfig {
            params: self.clone(),
            law,
            mesh,
            remesh,
            flow,
        })
    }
}

impl PoreScaleConfig {
    /// The parameters this configuration was validated from.
    pub fn params(&self) -> &PoreScaleParams {
        &self.params
    }

    /// The validated flow configuration.
    pub fn flow(&self) -> &FlowConfig {
        &self.flow
    }

    /// The fluid boundary conditions in the form `thm-vpn-flow` takes.
    pub(crate) fn flow_boundaries(&self) -> Vec<(BoundarySide, BoundaryCondition)> {
        self.params
            .flow_boundaries
            .iter()
            .map(|b| (b.side, b.condition))
            .collect()
    }
}
