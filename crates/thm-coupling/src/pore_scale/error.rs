//! Errors of the coupled schemes.

use thiserror::Error;

/// What went wrong in a coupled step: a parameter out of range, an error of one of the
/// composed crates (wrapped with the stage it came from), or an unphysical state caught at a
/// stage boundary (naming the quantity, the place and the step).
#[derive(Debug, Error)]
pub enum CouplingError {
    /// A parameter is out of its allowed range.
    #[error("parameter `{field}` = {value} is out of range: {range}")]
    Parameter {
        /// The parameter's name.
        field: &'static str,
        /// The allowed range.
        range: &'static str,
        /// The value given.
        value: f64,
    },
    /// The DEM (contact law, stepper, particle state).
    #[error("DEM: {0}")]
    Dem(#[from] thm_dem::DemError),
    /// The mesher, mesh motion or remap.
    #[error("pore mesh: {0}")]
    Mesh(#[from] thm_vpn_mesh::MeshError),
    /// The flow solver or the fluid model.
    #[error("flow: {0}")]
    Flow(#[from] thm_vpn_flow::FlowError),
    /// The heat solver.
    #[error("heat: {0}")]
    Heat(#[from] thm_fvm_heat::HeatError),
    /// An unphysical or non-finite value at a stage boundary.
    #[error("{stage}: {quantity} = {value} in {place} {index} at coupled step {step} is {why}")]
    Unphysical {
        /// The stage that produced it.
        stage: &'static str,
        /// The quantity.
        quantity: &'static str,
        /// Kind of place (`pore`, `cell`, `sphere`).
        place: &'static str,
        /// Its index.
        index: usize,
        /// The value.
        value: f64,
        /// The coupled step.
        step: u64,
        /// What is wrong with it.
        why: &'static str,
    },
    /// The state does not fit the stepper (sizes differ).
    #[error("state does not match the stepper: {what} has {got} entries, expected {expected}")]
    StateMismatch {
        /// The array.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The expected length.
        expected: usize,
    },
    /// Two flow boundaries at different pressures that no chain of pores and channels joins:
    /// the pressure drop between them could drive no flow (a network cut in two, or a side
    /// whose pores are all sealed).
    #[error(
        "no path of pores and channels joins flow boundary {first} ({first_pressure} Pa) and \
         flow boundary {second} ({second_pressure} Pa) (`flow_boundaries` entries)"
    )]
    NoPressurePath {
        /// Index of the first boundary in `flow_boundaries`.
        first: usize,
        /// Its pressure \[Pa\].
        first_pressure: f64,
        /// Index of the second boundary.
        second: usize,
        /// Its pressure \[Pa\].
        second_pressure: f64,
    },
    /// The adaptive coupled step reached its smallest step and a sphere still moved more
    /// than the rule allows in one step.
    #[error(
        "sphere {sphere} moved {displacement} m in one coupled step of {step_length} s at t =          {time} s, more than the allowed {limit} m, and the step cannot be shortened below          `min_step` = {min_step} s"
    )]
    CouplingStepTooSmall {
        /// The sphere that moved furthest.
        sphere: usize,
        /// How far it moved \[m\].
        displacement: f64,
        /// The allowed displacement \[m\].
        limit: f64,
        /// The step tried \[s\].
        step_length: f64,
        /// The smallest step of the rule \[s\].
        min_step: f64,
        /// Simulated time at the start of the step \[s\].
        time: f64,
    },
}
