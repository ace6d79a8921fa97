//! # thm-eos — Peng–Robinson equation of state and the two-phase pore closure
//!
//! (module doc written below)

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

mod closure;
mod error;
mod iapws;
mod peng_robinson;
pub mod verification;

pub use closure::{ClosureState, PoreClosure, TwoPhaseClosure};
pub use error::EosError;
pub use iapws::Iapws97Water;
pub use peng_robinson::{FluidParameters, GAS_CONSTANT, Model, PengRobinson, WATER_VOLUME_SHIFT};

/// Which root of the cubic is wanted where several exist.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Branch {
    /// The smallest molar volume above the co-volume b (the dense, liquid-like root).
    Liquid,
    /// The largest molar volume (the vapour-like root).
    Gas,
}

/// A fluid's pressure–density–temperature relation: the seam between `thm-eos` and its users.
///
/// Temperatures in K, densities in kg/m³, pressures in Pa. Every method checks its inputs and
/// returns a typed [`EosError`] for non-finite or out-of-range values and for states outside the
/// equation's domain.
pub trait EquationOfState {
    /// Pressure at temperature `T` and density `ρ` [Pa].
    fn pressure(&self, temperature: f64, density: f64) -> Result<f64, EosError>;

    /// Density at (T, P > 0) on the requested branch [kg/m³]. Where only one state exists
    /// (one real root, or a supercritical temperature) both branches give it.
    fn density(&self, temperature: f64, pressure: f64, branch: Branch) -> Result<f64, EosError>;

    /// `∂P/∂ρ` at constant temperature [Pa·m³/kg]. Positive on mechanically stable states.
    fn dp_drho(&self, temperature: f64, density: f64) -> Result<f64, EosError>;

    /// `∂P/∂T` at constant density [Pa/K]: the pressure rise per kelvin of a sealed pore.
    fn dp_dt(&self, temperature: f64, density: f64) -> Result<f64, EosError>;

    /// Pressure and `∂P/∂ρ` together (one evaluation where the model allows it).
    fn pressure_and_dp_drho(&self, temperature: f64, density: f64) -> Result<(f64, f64), EosError> {
        Ok((
            self.pressure(temperature, density)?,
            self.dp_drho(temperature, density)?,
        ))
    }

    /// Whether a state that is mechanically stable (`∂P/∂ρ > 0`) lies on the requested branch:
    /// on a subcritical isotherm the dense (`Liquid`) or dilute (`Gas`) stable branch, on a
    /// supercritical isotherm (one stable branch) always. The default is for models with a
    /// single stable branch: always true.
    fn on_branch(&self, temperature: f64, density: f64, branch: Branch) -> Result<bool, EosError> {
        let _ = (temperature, density, branch);
        Ok(true)
    }

    /// The density at which the equation's domain ends at this temperature [kg/m³]
    /// (`f64::INFINITY` if none). For Peng–Robinson, where the molar volume reaches `b`.
    fn max_density(&self, temperature: f64) -> f64;

    /// Molar mass [kg/kmol].
    fn molar_mass(&self) -> f64;
}

impl<E: EquationOfState + ?Sized> EquationOfState for &E {
    #[inline]
    fn pressure(&self, temperature: f64, density: f64) -> Result<f64, EosError> {
        (**self).pressure(temperature, density)
    }
    #[inline]
    fn density(&self, temperature: f64, pressure: f64, branch: Branch) -> Result<f64, EosError> {
        (**self).density(temperature, pressure, branch)
    }
    #[inline]
    fn dp_drho(&self, temperature: f64, density: f64) -> Result<f64, EosError> {
        (**self).dp_drho(temperature, density)
    }
    #[inline]
    fn dp_dt(&self, temperature: f64, density: f64) -> Result<f64, EosError> {
        (**self).dp_dt(temperature, density)
    }
    #[inline]
    fn pressure_and_dp_drho(&self, temperature: f64, density: f64) -> Result<(f64, f64), EosError> {
        (**self).pressure_and_dp_drho(temperature, density)
    }
    #[inline]
    fn on_branch(&self, temperature: f64, density: f64, branch: Branch) -> Result<bool, EosError> {
        (**self).on_branch(temperature, density, branch)
    }
    #[inline]
    fn max_density(&self, temperature: f64) -> f64 {
        (**self).max_density(temperature)
    }
    #[inline]
    fn molar_mass(&self) -> f64 {
        (**self).molar_mass()
    }
}

/// Paper A's pore closure: water (in the chosen model) as the liquid, air as the gas.
pub fn water_air_closure(model: Model) -> TwoPhaseClosure<PengRobinson, PengRobinson> {
    TwoPhaseClosure::new(PengRobinson::water(model), PengRobinson::air())
}
