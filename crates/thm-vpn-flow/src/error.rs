//! The crate's error type.

/// Which fluid phase a quantity belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Phase {
    /// The liquid phase `q` of paper A (water).
    Liquid,
    /// The gas phase `p` of paper A (air).
    Gas,
}

/// Why a pore closure (A-Eq. 29) failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClosureFailure {
    /// A phase mass is negative or not finite.
    #[error("{phase:?} mass {value:e} kg: must be finite and >= 0")]
    NegativeMass {
        /// Which phase.
        phase: Phase,
        /// The mass \[kg\].
        value: f64,
    },
    /// The pore volume is zero, negative or not finite.
    #[error("pore volume {value:e} m³: must be finite and > 0")]
    NonPositiveVolume {
        /// The volume \[m³\].
        value: f64,
    },
    /// The temperature is zero, negative or not finite.
    #[error("temperature {value} K: must be finite and > 0")]
    NonPositiveTemperature {
        /// The temperature \[K\].
        value: f64,
    },
    /// The pore holds no mass of either phase: no pressure is defined.
    #[error("empty pore (no liquid and no gas): pressure undefined")]
    Empty,
    /// A failure reported by the fluid model (e.g. an equation of state), in its own words.
    #[error("fluid model: {message}")]
    Model {
        /// The model's message.
        message: String,
    },
    /// No state of the fluid model satisfies the closure (e.g. a pure liquid stretched to a
    /// pressure below the model's lower limit).
    #[error("no solution: {reason} (value {value:e})")]
    NoSolution {
        /// Why, in words.
        reason: &'static str,
        /// The offending value (a pressure in Pa or a density in kg/m³, as `reason` says).
        value: f64,
    },
}

/// Errors of the flow solver. Every variant names the pore, channel or boundary link and,
/// during a step, the step and sub-step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlowError {
    /// A channel aperture is negative or not finite.
    #[error("channel {channel}: aperture {value:e} m must be finite and >= 0")]
    NegativeAperture {
        /// Channel index.
        channel: usize,
        /// The aperture \[m\].
        value: f64,
    },
    /// A boundary link aperture is negative or not finite.
    #[error("boundary link {link}: aperture {value:e} m must be finite and >= 0")]
    NegativeLinkAperture {
        /// Boundary link index.
        link: usize,
        /// The aperture \[m\].
        value: f64,
    },
    /// A channel or boundary link length is zero, negative or not finite.
    #[error("{what} {index}: length {value:e} m must be finite and > 0")]
    NonPositiveLength {
        /// `"channel"` or `"boundary link"`.
        what: &'static str,
        /// Its index.
        index: usize,
        /// The length \[m\].
        value: f64,
    },
    /// A channel or link refers to a pore that does not exist, or joins a pore to itself.
    #[error("{what} {index}: pore index {pore} invalid (network has {n_pores} pores)")]
    BadPoreIndex {
        /// `"channel"`, `"boundary link"` or `"wall face"`.
        what: &'static str,
        /// Its index.
        index: usize,
        /// The offending pore index.
        pore: usize,
        /// Number of pores.
        n_pores: usize,
    },
    /// A pore volume is zero, negative or not finite (at construction or after a volume
    /// update `V += dV/dt·Δt`, A-Eq. 25).
    #[error(
        "pore {pore}: volume {value:e} m³ must be finite and > 0 (step {step}, sub-step {substep})"
    )]
    NonPositiveVolume {
        /// Pore index.
        pore: usize,
        /// The volume \[m³\].
        value: f64,
        /// Outer step counter of the state (0 before the first step).
        step: u64,
        /// Sub-step within the outer step.
        substep: u32,
    },
    /// The closure (A-Eq. 29) found no state for a pore.
    #[error("pore {pore}: closure failed at step {step}, sub-step {substep}: {cause}")]
    Closure {
        /// Pore index.
        pore: usize,
        /// Outer step counter.
        step: u64,
        /// Sub-step within the outer step.
        substep: u32,
        /// Why.
        cause: ClosureFailure,
    },
    /// A quantity became NaN or infinite.
    #[error("non-finite {quantity} = {value} at {place} {index} (step {step}, sub-step {substep})")]
    NonFinite {
        /// Which quantity (e.g. `"liquid mass rate"`).
        quantity: &'static str,
        /// `"pore"`, `"channel"` or `"boundary link"`.
        place: &'static str,
        /// Its index.
        index: usize,
        /// The value.
        value: f64,
        /// Outer step counter.
        step: u64,
        /// Sub-step within the outer step.
        substep: u32,
    },
    /// A parameter outside its allowed range.
    #[error("{name}: must be {range}, got {value}")]
    OutOfRange {
        /// Parameter name.
        name: &'static str,
        /// Allowed range, in words.
        range: &'static str,
        /// The value.
        value: f64,
    },
    /// An input array has the wrong length.
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// The explicit update needed more sub-steps than allowed inside one outer step.
    #[error(
        "step {step}: {substeps} sub-steps did not cover Δt (stable sub-step {dt_limit:e} s, \
         limited by {limit} at pore {pore})"
    )]
    TooManySubsteps {
        /// Outer step counter.
        step: u64,
        /// Sub-steps taken.
        substeps: u32,
        /// The last sub-step limit \[s\].
        dt_limit: f64,
        /// `"stability"` or `"liquid positivity"` / `"gas positivity"`.
        limit: &'static str,
        /// The pore that set the limit.
        pore: usize,
    },
    /// The pore mesh of a permeability test could not be built.
    #[error("pore mesh: {0}")]
    Mesh(#[from] thm_vpn_mesh::MeshError),
    /// The direct steady-state solve met a non-positive pivot (a pore cluster without a
    /// conducting path to a boundary that the ordering did not exclude).
    #[error("steady solve: matrix not positive definite at row {row} (pivot {pivot:e})")]
    SteadySolve {
        /// Row of the ordered matrix.
        row: usize,
        /// The pivot.
        pivot: f64,
    },
    /// A packing of a permeability calibration has no pore path between the reservoirs.
    #[error("packing {seed}: no pore path joins the two reservoirs (permeability 0)")]
    NoPorePath {
        /// The packing seed.
        seed: u64,
    },
    /// A calibration target that no γ in `(0, 1]` searched reaches.
    #[error(
        "calibration: no T2T reduction factor gamma in [{lower:e}, {upper:e}] gives \
         `{field}` = {target:e} m^2; the permeabilities reached span [{reached_min:e}, \
         {reached_max:e}] m^2"
    )]
    CalibrationUnreachable {
        /// The target's name.
        field: &'static str,
        /// The target value.
        target: f64,
        /// Smallest γ searched.
        lower: f64,
        /// Largest γ searched.
        upper: f64,
        /// Smallest permeability reached \[m²\].
        reached_min: f64,
        /// Largest permeability reached \[m²\].
        reached_max: f64,
    },
    /// A calibration that brackets its target but does not meet the tolerance.
    #[error(
        "calibration: `{field}` = {target:e} not reached within a relative tolerance of \
         {tolerance:e} in {iterations} evaluations (last gamma = {gamma:e} gave {value:e})"
    )]
    CalibrationNotConverged {
        /// The target's name.
        field: &'static str,
        /// The target value.
        target: f64,
        /// The relative tolerance asked for.
        tolerance: f64,
        /// Evaluations done.
        iterations: usize,
        /// The last γ.
        gamma: f64,
        /// κ there \[m²\].
        value: f64,
    },
    /// The sparse solve of the implicit pressure step failed.
    #[error("step {step}: implicit pressure solve failed: {message}")]
    Solver {
        /// Outer step counter.
        step: u64,
        /// The solver's message.
        message: String,
    },
}
