//! The error type of `thm-eos`.

use thiserror::Error;

/// Everything that can go wrong when evaluating an equation of state or closing a pore.
///
/// Every variant names the quantity and carries the offending value and, where one exists, the
/// admissible range, so that a caller can report it without re-deriving the context.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EosError {
    /// An input is not finite or lies outside its admissible range.
    #[error("{quantity} = {value} is outside the admissible range {allowed}")]
    InvalidInput {
        /// Name of the input, e.g. `"temperature"`.
        quantity: &'static str,
        /// The value received.
        value: f64,
        /// The admissible range in words, e.g. `"(0, inf) K"`.
        allowed: &'static str,
    },
    /// A fluid parameter (critical point, acentric factor, …) is invalid.
    #[error("fluid parameter {parameter} = {value} is invalid: allowed {allowed}")]
    InvalidParameter {
        /// Name of the parameter, e.g. `"critical_temperature"`.
        parameter: &'static str,
        /// The value received.
        value: f64,
        /// The admissible range in words.
        allowed: &'static str,
    },
    /// The state lies outside the domain of the cubic: the Peng–Robinson molar volume is at or
    /// below the co-volume `b` (A-Eq. 16 is singular at `V = b` and meaningless below).
    #[error(
        "molar volume {molar_volume} m³/kmol (density {density} kg/m³) is at or below the \
         co-volume b = {covolume} m³/kmol: the largest admissible density is {max_density} kg/m³"
    )]
    BelowCovolume {
        /// The equation's molar volume `V` (uncorrected, m³/kmol).
        molar_volume: f64,
        /// The density that was asked for (kg/m³).
        density: f64,
        /// The co-volume `b` (m³/kmol).
        covolume: f64,
        /// The density at which `V = b` (kg/m³).
        max_density: f64,
    },
    /// The cubic has no root above the co-volume at this pressure (only for pressures so large
    /// that the liquid root cannot be separated from `b` in floating point).
    #[error("no molar volume above the co-volume at T = {temperature} K, P = {pressure} Pa")]
    NoRoot {
        /// Temperature (K).
        temperature: f64,
        /// Pressure (Pa).
        pressure: f64,
    },
    /// A state outside the validity range of a reference equation (IAPWS-IF97).
    #[error(
        "state T = {temperature} K, {quantity} = {value} is outside the range of {model}: {allowed}"
    )]
    OutsideModelRange {
        /// Which model refused the state.
        model: &'static str,
        /// Temperature (K).
        temperature: f64,
        /// The other state variable's name.
        quantity: &'static str,
        /// Its value.
        value: f64,
        /// The model's range in words.
        allowed: &'static str,
    },
    /// A computed quantity is not finite (or a density underflowed to zero) although every
    /// input passed its checks: the state lies where the equation cannot be evaluated in double
    /// precision (subnormal or astronomically large temperatures, densities or pressures).
    #[error(
        "{quantity} = {value} at T = {temperature} K, {input} = {input_value} is not \
         representable in double precision (the state is outside the range the equation can be \
         evaluated in)"
    )]
    Unrepresentable {
        /// Name of the computed quantity, e.g. `"pressure"`.
        quantity: &'static str,
        /// The value computed (infinite, NaN, or zero for an underflowed density).
        value: f64,
        /// Temperature (K).
        temperature: f64,
        /// The other input's name, e.g. `"density"`.
        input: &'static str,
        /// Its value.
        input_value: f64,
    },
    /// The two-phase pore closure has no state with equal phase pressures on the mechanically
    /// stable branches (∂P/∂ρ > 0) of both phases.
    #[error(
        "no two-phase state with equal pressures on stable branches: T = {temperature} K, \
         V = {pore_volume} m³, m_liquid = {liquid_mass} kg, m_gas = {gas_mass} kg ({reason})"
    )]
    NoClosure {
        /// Temperature (K).
        temperature: f64,
        /// Pore volume (m³).
        pore_volume: f64,
        /// Liquid mass (kg).
        liquid_mass: f64,
        /// Gas mass (kg).
        gas_mass: f64,
        /// Why, in words.
        reason: &'static str,
    },
}
