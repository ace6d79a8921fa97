//! Real water behind [`EquationOfState`]: the IAPWS-IF97 industrial formulation (via `seuif97`).
//!
//! Beyond paper A, which uses the corrected Peng–Robinson equation for water: a user who wants
//! the liquid's thermal pressurisation right (the cubic overstates ∂P/∂T at constant density by
//! a factor of several, see the `eos/thermal_pressurisation` verification case) can close pores
//! with real water instead, e.g. `TwoPhaseClosure::new(Iapws97Water, PengRobinson::air())`.
//!
//! Range: 273.15 K ≤ T ≤ 623.15 K and pressures up to 100 MPa (IF97 regions 1 and 2, where the
//! branch is honoured by evaluating region 1 for the liquid and region 2 for the gas, including
//! their metastable extensions near saturation). Outside, a typed error.

use crate::peng_robinson::{check_density, check_pressure, check_temperature};
use crate::{Branch, EosError, EquationOfState};

/// Molar mass of water used by IAPWS (kg/kmol).
const WATER_MOLAR_MASS: f64 = 18.015268;
/// Lowest and highest temperature accepted (K) (IF97 regions 1 and 2 below the region-3 boundary).
const T_MIN: f64 = 273.15;
const T_MAX: f64 = 623.15;
/// Highest pressure of IF97 (Pa).
const P_MAX: f64 = 100.0e6;
/// Highest liquid density accepted (kg/m³) (the compressed liquid at 100 MPa and 273.15 K is
/// about 1050 kg/m³).
const RHO_MAX: f64 = 1.0 / 0.00095;
const RANGE: &str = "273.15 K <= T <= 623.15 K, 0 < P <= 100 MPa";

/// Liquid water (and steam) from IAPWS-IF97 (Wagner et al. 2000), evaluated by `seuif97`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Iapws97Water;

fn check_range(temperature: f64) -> Result<f64, EosError> {
    let t = check_temperature(temperature)?;
    if (T_MIN..=T_MAX).contains(&t) {
        Ok(t)
    } else {
        Err(EosError::OutsideModelRange {
            model: "IAPWS-IF97 water",
            temperature: t,
            quantity: "temperature",
            value: t,
            allowed: RANGE,
        })
    }
}

/// A seuif97 result is valid when finite and positive (it signals errors with negative codes).
fn valid(
    model_value: f64,
    temperature: f64,
    quantity: &'static str,
    value: f64,
) -> Result<f64, EosError> {
    if model_value.is_finite() && model_value > 0.0 {
        Ok(model_value)
    } else {
        Err(EosError::OutsideModelRange {
            model: "IAPWS-IF97 water",
            temperature,
            quantity,
            value,
            allowed: RANGE,
        })
    }
}

impl Iapws97Water {
    /// Pressure (Pa) at (T, ρ): IF97's (T, v) backward evaluation.
    fn pressure_checked(&self, temperature: f64, density: f64) -> Result<(f64, f64), EosError> {
        let t = check_range(temperature)?;
        let rho = check_density(density)?;
        let p_mpa = seuif97::tv(t - 273.15, 1.0 / rho, seuif97::OP);
        let p = valid(p_mpa, t, "density", rho)? * 1.0e6;
        if p > P_MAX {
            return Err(EosError::OutsideModelRange {
                model: "IAPWS-IF97 water",
                temperature: t,
                quantity: "density",
                value: rho,
                allowed: RANGE,
            });
        }
        Ok((t, p))
    }

    /// The region IF97 evaluates for a branch.
    fn region(branch: Branch) -> i32 {
        match branch {
            Branch::Liquid => 1,
            Branch::Gas => 2,
        }
    }

    /// The region of the stable phase at (T, P).
    fn region_at(t: f64, p: f64) -> i32 {
        let r = seuif97::pt(p * 1.0e-6, t - 273.15, seuif97::OR);
        if r == 2.0 { 2 } else { 1 }
    }
}

impl EquationOfState for Iapws97Water {
    fn pressure(&self, temperature: f64, density: f64) -> Result<f64, EosError> {
        Ok(self.pressure_checked(temperature, density)?.1)
    }

    fn density(&self, temperature: f64, pressure: f64, branch: Branch) -> Result<f64, EosError> {
        let t = check_range(temperature)?;
        let p = check_pressure(pressure)?;
        if p > P_MAX {
            return Err(EosError::OutsideModelRange {
                model: "IAPWS-IF97 water",
                temperature: t,
                quantity: "pressure",
                value: p,
                allowed: RANGE,
            });
        }
        let rho = seuif97::pt(p * 1.0e-6, t - 273.15, (seuif97::OD, Self::region(branch)));
        valid(rho, t, "pressure", p)
    }

    fn dp_drho(&self, temperature: f64, density: f64) -> Result<f64, EosError> {
        Ok(self.pressure_and_dp_drho(temperature, density)?.1)
    }

    fn pressure_and_dp_drho(&self, temperature: f64, density: f64) -> Result<(f64, f64), EosError> {
        let (t, p) = self.pressure_checked(temperature, density)?;
        // ∂P/∂ρ|_T = 1/(ρ κ_T), κ_T in 1/MPa from IF97.
        let region = Self::region_at(t, p);
        let kappa_t = seuif97::pt(p * 1.0e-6, t - 273.15, (seuif97::OKT, region));
        let kappa_t = valid(kappa_t, t, "density", density)?;
        Ok((p, 1.0e6 / (density * kappa_t)))
    }

    fn dp_dt(&self, temperature: f64, density: f64) -> Result<f64, EosError> {
        let (t, p) = self.pressure_checked(temperature, density)?;
        // ∂P/∂T|_v = α_v/κ_T (cubic expansion coefficient over isothermal compressibility).
        let region = Self::region_at(t, p);
        let kappa_t = valid(
            seuif97::pt(p * 1.0e-6, t - 273.15, (seuif97::OKT, region)),
            t,
            "density",
            density,
        )?;
        let expansion = seuif97::pt(p * 1.0e-6, t - 273.15, (seuif97::OEC, region));
        if !expansion.is_finite() || expansion <= -1.0 {
            return Err(EosError::OutsideModelRange {
                model: "IAPWS-IF97 water",
                temperature: t,
                quantity: "density",
                value: density,
                allowed: RANGE,
            });
        }
        Ok(1.0e6 * expansion / kappa_t)
    }

    fn on_branch(&self, temperature: f64, density: f64, branch: Branch) -> Result<bool, EosError> {
        let t = check_range(temperature)?;
        let rho = check_density(density)?;
        // Below the critical temperature the liquid branch ends at the saturated liquid and the
        // vapour branch at the saturated vapour (IF97's metastable extensions are not used for
        // a phase's own state in a pore).
        Ok(match branch {
            Branch::Liquid => rho >= seuif97::tx(t - 273.15, 0.0, seuif97::OD),
            Branch::Gas => rho <= seuif97::tx(t - 273.15, 1.0, seuif97::OD),
        })
    }

    fn max_density(&self, _temperature: f64) -> f64 {
        RHO_MAX
    }

    fn molar_mass(&self) -> f64 {
        WATER_MOLAR_MASS
    }
}
