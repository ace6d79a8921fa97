//! # thm-eos — Peng–Robinson equation of state and the two-phase pore closure
//!
//! The fluid thermodynamics of Krzaczek, Nitka & Tejchman (2023), *A novel DEM-based
//! pore-scale thermal-hydro-mechanical model for fractured non-saturated porous materials*,
//! Acta Geotechnica (paper "A", Sect. 2.2.2): pressure, density and their derivatives for
//! water and air from the Peng–Robinson equation with a volume correction, and the closure that
//! turns the phase masses of a virtual pore into its liquid fraction and common pressure.
//!
//! It does **not** transport anything (mass balance and channel flow are `thm-vpn-flow`), has
//! no temperature dependence of viscosity or conductivity, and models no mass transfer between
//! the phases (no evaporation or dissolution), as in paper A.
//!
//! ## Equations
//!
//! - **A-Eq. 16**, the Peng & Robinson (1976) cubic in the molar volume `V`:
//!   `P = RT/(V − b) − a(T)/(V² + 2bV − b²)`, with `R = 8314.4598 J/(kmol·K)` (Table 1).
//! - **A-Eqs. 17–22**: `a(T) = a_c β(T) [1 + n(1 − √T_r)]²`, `n = 0.37464 + 1.54226ω −
//!   0.26992ω²`, `a_c = 0.457247 R²T_c²/P_c`, `b = 0.07780 RT_c/P_c`,
//!   `β = [1 + c1(1 − √T_r) + c2(1 − √T_r)² + c3(1 − √T_r)³]²`. As printed, β multiplies the
//!   Soave factor (A-Eq. 19), so c1 = c2 = c3 = 0 gives the original equation; both presets use
//!   c = 0 (Table 1 gives none). The printed Ω_a = 0.457247 and Ω_b = 0.07780 are rounded
//!   (exact: 0.4572355, 0.0777961): the equation's own critical point differs from Table 1's
//!   (T_c, P_c) by about 1e-5 and 6e-5 relative (verification case `eos/critical_point_*`).
//! - **A-Eq. 23**, the Péneloux volume translation `V_corr = V + s`, and **A-Eqs. 27–28**,
//!   the link to density: `V = w/ρ − s` (gas: s = 0, so `V = w/ρ`).
//! - **A-Eq. 29**, the closure: `P(T, V_liquid) = P(T, V_gas)` with
//!   `ρ_l = m_l/(αV_pore)`, `ρ_g = m_g/((1 − α)V_pore)`, solved for the liquid fraction α.
//!
//! ## The sign of the volume correction (established by test)
//!
//! Paper A gives s = −0.0034 m³/kmol for liquid water and 0 for the gas. A-Eq. 23 says the
//! *corrected* molar volume is `V + s`, i.e. the real volume `w/ρ` is the cubic's volume plus s,
//! which is A-Eq. 28 (`V = w/ρ − s`). With s < 0 this makes the liquid denser: the plain cubic
//! gives 851 kg/m³ at 293.15 K and 0.1 MPa (−14.7 % against IAPWS-95), the corrected one
//! 1014 kg/m³ (+1.6 %); the opposite reading (`V = w/ρ + s`) gives 733 kg/m³ (−26.5 %) and is
//! rejected (test `volume_correction_sign_makes_water_dense`, case `eos/water_density_0.1MPa`).
//! The shift is a property of the fluid (Péneloux's translation is per component): it applies
//! to water on either branch, so `pressure(T, density(T, P, branch)) = P` holds for both, and it
//! leaves the vapour pressure unchanged. The presets: [`Model::Pr`] (no correction) and
//! [`Model::PrCorrected`] (paper A: water s = −0.0034 m³/kmol; air is never corrected).
//!
//! **How good is it?** Against IAPWS-95 (Wagner & Pruß 2002) at 0.1 MPa, the corrected liquid
//! density is +2.6 % at 278 K, +1.6 % at 293 K, +1.34 % at 298 K, within ±1.3 % from about 299 K
//! to 363 K, and −1.4 % at 368 K. Paper A's "less than 1.3 %" therefore holds only from about
//! 299 to 363 K. Its thermal pressurisation is poor: ∂P/∂T at constant density in a sealed
//! water-filled pore is 6.0 MPa/K at 278 K against 0.033 MPa/K for real water (×181), ×12 at
//! 293 K, ×4.5 at 323 K, ×2.5 at 368 K (case `eos/thermal_pressurisation`). Where that matters,
//! use [`Iapws97Water`] as the liquid.
//!
//! ## Root selection and domain
//!
//! `density(T, P, branch)` solves A-Eq. 16 as the cubic in `Z = PV/(RT)`. Of its real roots
//! above `B = bP/(RT)` the **liquid** branch takes the smallest and the **gas** branch the
//! largest; where only one exists (one real root, or supercritical T) both give it, bit for
//! bit. Both chosen roots are mechanically stable (∂P/∂ρ > 0, property-tested); the middle root
//! never is. The roots come from a monotone Newton iteration started at the bounds `Z = B`
//! (where the cubic is −2B²) and `Z = 1 + B` (an upper bound of every root, since
//! `P ≤ RT/(V − b)`), used where the cubic keeps its curvature up to the root; elsewhere from the
//! trigonometric/Cardano closed form, polished by Newton. States with `V ≤ b` (density at or
//! above `w/(b + s)`) are [`EosError::BelowCovolume`]; non-positive or non-finite inputs are
//! [`EosError::InvalidInput`].
//!
//! Extreme but finite inputs: a very dilute state (`V` ≥ 1e30 m³/kmol, down to subnormal
//! densities) is evaluated in `1/V`, so a trace of gas has its finite ideal-gas pressure instead
//! of `∞ − ∞`; below 1e-100 Pa the densities are their `P → 0` limits (the cubic's coefficients
//! underflow there); a result that still cannot be represented in double precision (an
//! overflow, or a density below the smallest double) is [`EosError::Unrepresentable`], never a
//! NaN or an infinity.
//!
//! ## The closure
//!
//! [`TwoPhaseClosure`] solves A-Eq. 29 by a safeguarded Newton iteration on the pressure
//! difference with the analytic ∂P/∂ρ, inside a bracket where both molar volumes exceed their
//! co-volumes. The liquid must be on its dense stable branch and the gas on its dilute one
//! ([`EquationOfState::on_branch`]; for Peng–Robinson decided exactly by `V/b` against the
//! universal 3.9514, see `peng_robinson`): where the water's cubic also has a vapour branch, a
//! second equal-pressure state with the "liquid" expanded into vapour exists and is never
//! taken. The unknown is the smaller of α and 1 − α, so a trace phase keeps its own relative
//! precision; α converges to a few ulps (tested: 1e-10 absolute against an independent
//! implementation). Single-phase pores (no gas, or no liquid) are exact: α = 1 or 0 and the
//! phase's own `P(T, m/V)`, bit for bit. A pore whose phases cannot share a pressure on those
//! branches (they do not fit above the co-volumes, or the liquid stays above the gas pressure up
//! to its spinodal) is [`EosError::NoClosure`].
//!
//! ## Units
//!
//! SI: T in K, P in Pa, ρ in kg/m³, masses in kg, pore volumes in m³; molar volumes in
//! **m³/kmol** and molar masses in kg/kmol, as in paper A (so R is per kmol).
//!
//! ## Validity range
//!
//! Tested over 278–700 K and 0.01–70 MPa on both branches (the range of paper A's cases, up to
//! supercritical air and water). [`Iapws97Water`] covers 273.15–623.15 K up to 100 MPa.
//!
//! ## Public seam
//!
//! - [`EquationOfState`]: pressure from (T, ρ), density from (T, P, branch), ∂P/∂ρ and ∂P/∂T
//!   (at constant density), branch membership and the domain's density limit. Implemented by
//!   [`PengRobinson`] and [`Iapws97Water`] (real water, IAPWS-IF97 via `seuif97`).
//! - [`PoreClosure`]: phase fractions, densities and the common pressure from phase masses,
//!   pore volume and temperature. Implemented by [`TwoPhaseClosure`] over any two equations of
//!   state; [`water_air_closure`] builds paper A's.
//!
//! Parameters are [`FluidParameters`] (serde, `deny_unknown_fields`), validated once by
//! [`PengRobinson::new`].

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

mod closure;
mod error;
mod iapws;
mod peng_robinson;
#[cfg(feature = "verification")]
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
    /// Pressure at temperature `T` and density `ρ` (Pa).
    fn pressure(&self, temperature: f64, density: f64) -> Result<f64, EosError>;

    /// Density at (T, P > 0) on the requested branch (kg/m³). Where only one state exists
    /// (one real root, or a supercritical temperature) both branches give it.
    fn density(&self, temperature: f64, pressure: f64, branch: Branch) -> Result<f64, EosError>;

    /// `∂P/∂ρ` at constant temperature (Pa·m³/kg). Positive on mechanically stable states.
    fn dp_drho(&self, temperature: f64, density: f64) -> Result<f64, EosError>;

    /// `∂P/∂T` at constant density (Pa/K): the pressure rise per kelvin of a sealed pore.
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

    /// The density at which the equation's domain ends at this temperature (kg/m³)
    /// (`f64::INFINITY` if none). For Peng–Robinson, where the molar volume reaches `b`.
    fn max_density(&self, temperature: f64) -> f64;

    /// Molar mass (kg/kmol).
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
