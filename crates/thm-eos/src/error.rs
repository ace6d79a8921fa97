//! The error type of `thm-eos`.

use std::fmt;

use thiserror::Error;

/// A number in an error message: as `{}` writes it in the ordinary range, in exponent form
/// outside it, so that no message grows with the input (`{}` writes 1e-300 with 300 digits,
/// and a message holding four such numbers passed 1000 characters: fuzz finding
/// `eos_state/crash-1885…`).
#[derive(Debug, Clone, Copy)]
struct Num(f64);

fn num(x: &f64) -> Num {
    Num(*x)
}

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || !a.is_finite() || (1e-5..1e16).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// Everything that can go wrong when evaluating an equation of state or closing a pore.
///
/// Every variant names the quantity and carries the offending value and, where one exists, the
/// admissible range, so that a caller can report it without re-deriving the context.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EosError {
    /// An input is not finite or lies outside its admissible range.
    #[error("{quantity} = {} is outside the admissible range {allowed}", num(.value))]
    InvalidInput {
        /// Name of the input, e.g. `"temperature"`.
        quantity: &'static str,
        /// The value received.
        value: f64,
        /// The admissible range in words, e.g. `"(0, inf) K"`.
        allowed: &'static str,
    },
    /// A fluid parameter (critical point, acentric factor, …) is invalid.
    #[error("fluid parameter {parameter} = {} is invalid: allowed {allowed}", num(.value))]
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
        "molar volume {} m³/kmol (density {} kg/m³) is at or below the \
         co-volume b = {} m³/kmol: the largest admissible density is {} kg/m³",
        num(.molar_volume), num(.density), num(.covolume), num(.max_density)
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
    #[error(
        "no molar volume above the co-volume at T = {} K, P = {} Pa",
        num(.temperature), num(.pressure)
    )]
    NoRoot {
        /// Temperature (K).
        temperature: f64,
        /// Pressure (Pa).
        pressure: f64,
    },
    /// A state outside the validity range of a reference equation (IAPWS-IF97).
    #[error(
        "state T = {} K, {quantity} = {} is outside the range of {model}: {allowed}",
        num(.temperature), num(.value)
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
        "{quantity} = {} at T = {} K, {input} = {} is not \
         representable in double precision (the state is outside the range the equation can be \
         evaluated in)",
        num(.value), num(.temperature), num(.input_value)
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
        "no two-phase state with equal pressures on stable branches: T = {} K, \
         V = {} m³, m_liquid = {} kg, m_gas = {} kg ({reason})",
        num(.temperature), num(.pore_volume), num(.liquid_mass), num(.gas_mass)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every message stays short whatever its numbers; ordinary numbers read as `{}` writes them.
    #[test]
    fn messages_are_short_for_any_number() {
        for x in [5e-324, -1e-300, 1e-6, 1.7e308, f64::NAN, 0.0] {
            let errors = [
                EosError::InvalidInput {
                    quantity: "temperature",
                    value: x,
                    allowed: "(0, inf) K",
                },
                EosError::BelowCovolume {
                    molar_volume: x,
                    density: x,
                    covolume: x,
                    max_density: x,
                },
                EosError::Unrepresentable {
                    quantity: "pressure",
                    value: x,
                    temperature: x,
                    input: "density",
                    input_value: x,
                },
                EosError::NoClosure {
                    temperature: x,
                    pore_volume: x,
                    liquid_mass: x,
                    gas_mass: x,
                    reason: "none",
                },
            ];
            for e in errors {
                let m = e.to_string();
                assert!(m.len() < 300, "{m}");
            }
        }
        let e = EosError::NoRoot {
            temperature: 300.5,
            pressure: 1e-9,
        };
        assert_eq!(
            e.to_string(),
            "no molar volume above the co-volume at T = 300.5 K, P = 1e-9 Pa"
        );
    }
}
