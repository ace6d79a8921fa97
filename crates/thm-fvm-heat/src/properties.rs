//! Effective mixture properties (A-Eqs. 32–36) and the fluid–solid heat transfer coefficient
//! from Nusselt correlations (A-Eqs. 43–45).

use crate::params::{HeatModel, Phase};

/// Effective properties of the homogenised two-phase fluid in one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MixtureProperties {
    /// ρ_eff = α_q ρ_q + α_p ρ_p (A-Eq. 32) [kg/m³].
    pub density: f64,
    /// Volumetric heat capacity Σ α_k ρ_k c_p,k [J/(m³ K)].
    pub volumetric_heat_capacity: f64,
    /// Mass-weighted specific heat c_p,eff = Σ α_k ρ_k c_p,k / ρ_eff [J/(kg K)] (our reading
    /// of A-Eq. 36; see the crate docs).
    pub specific_heat: f64,
    /// λ_eff = Σ α_k λ_k (A-Eq. 34) [W/(m K)].
    pub conductivity: f64,
    /// μ_eff = Σ α_k μ_k (A-Eq. 35) [Pa s].
    pub dynamic_viscosity: f64,
}

/// Mixture properties from the liquid fraction and the phase densities.
pub fn mixture(
    liquid: &Phase,
    gas: &Phase,
    liquid_fraction: f64,
    liquid_density: f64,
    gas_density: f64,
) -> MixtureProperties {
    let (aq, ap) = (liquid_fraction, 1.0 - liquid_fraction);
    let density = aq * liquid_density + ap * gas_density;
    let rho_c = aq * liquid_density * liquid.specific_heat + ap * gas_density * gas.specific_heat;
    MixtureProperties {
        density,
        volumetric_heat_capacity: rho_c,
        specific_heat: if density > 0.0 { rho_c / density } else { 0.0 },
        conductivity: aq * liquid.conductivity + ap * gas.conductivity,
        dynamic_viscosity: aq * liquid.dynamic_viscosity + ap * gas.dynamic_viscosity,
    }
}

/// Reynolds number above which A-Eq. 44 (Wakao & Kaguei) replaces A-Eq. 43 (Tavassoli et al.).
pub const REYNOLDS_SWITCH: f64 = 100.0;

/// Nusselt number of the fluid–particle exchange: A-Eq. 43 for Re ≤ 100, A-Eq. 44 above.
pub fn nusselt(porosity: f64, reynolds: f64, prandtl: f64) -> f64 {
    let (e, re) = (porosity, reynolds.max(0.0));
    let a = 7.0 - 10.0 * e + 5.0 * e * e;
    if re == 0.0 {
        return a;
    }
    let pr3 = prandtl.max(0.0).cbrt();
    let ln_re = re.ln();
    if re <= REYNOLDS_SWITCH {
        a * (1.0 + 0.1 * (0.2 * ln_re).exp() * pr3)
            + (1.33 - 2.19 * e + 1.15 * e * e) * (0.7 * ln_re).exp() * pr3
    } else {
        2.0 + 1.1 * (0.6 * ln_re).exp() * pr3
    }
}

/// Fluid-side heat transfer coefficient h_f = Nu λ_eff / (2 r) (A-Eq. 45) [W/(m² K)], with
/// Re = ρ_eff v (2 r) / μ_eff and Pr = c_p,eff μ_eff / λ_eff.
pub fn interface_coefficient(
    mix: &MixtureProperties,
    porosity: f64,
    speed: f64,
    sphere_radius: f64,
) -> f64 {
    if mix.conductivity <= 0.0 || sphere_radius <= 0.0 {
        return 0.0;
    }
    let d = 2.0 * sphere_radius;
    let re = mix.density * speed * d / mix.dynamic_viscosity;
    let pr = mix.specific_heat * mix.dynamic_viscosity / mix.conductivity;
    nusselt(porosity, re, pr) * mix.conductivity / d
}

/// Powers of one sphere diameter d = 2r [m] used by the Nusselt correlations.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct DiameterPowers {
    pub d: f64,
    pub d02: f64,
    pub d06: f64,
    pub d07: f64,
}

impl DiameterPowers {
    pub(crate) fn new(radius: f64) -> Self {
        let d = 2.0 * radius;
        if d <= 0.0 {
            return Self::default();
        }
        let ln_d = d.ln();
        Self {
            d,
            d02: (0.2 * ln_d).exp(),
            d06: (0.6 * ln_d).exp(),
            d07: (0.7 * ln_d).exp(),
        }
    }
}

/// ∛p: for positive normal `p`, Newton's method on y³ = p from a first guess read off the
/// bits (exponent divided by three, relative error below 4 %; four steps bring it to
/// round-off), a few multiplications and divisions instead of the library routine;
/// `f64::cbrt` for zero, subnormal, infinite or NaN `p`.
#[inline]
pub(crate) fn cube_root(p: f64) -> f64 {
    if !(p.is_normal() && p > 0.0) {
        return p.cbrt();
    }
    let mut y = f64::from_bits(p.to_bits() / 3 + 0x2A9F_7893_782D_A1CE);
    for _ in 0..4 {
        let y2 = y * y;
        y -= (y2 * y - p) / (3.0 * y2);
    }
    y
}

/// The fluid cell's part of A-Eqs. 43–45: with x = ρ_eff v / μ_eff (Re per unit diameter),
/// Re^p Pr^{1/3} = (x^p Pr^{1/3}) d^p, so the coefficient of every interface face of the cell
/// is a few products with the sphere's [`DiameterPowers`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct ExchangeFactors {
    /// λ_eff [W/(m K)].
    pub conductivity: f64,
    /// ρ_eff v / μ_eff [1/m].
    pub x: f64,
    /// x^0.2 Pr^{1/3}, x^0.6 Pr^{1/3}, x^0.7 Pr^{1/3}.
    pub x02: f64,
    pub x06: f64,
    pub x07: f64,
}

impl ExchangeFactors {
    pub(crate) fn new(mix: &MixtureProperties, speed: f64) -> Self {
        if mix.conductivity <= 0.0 {
            return Self::default();
        }
        let x = (mix.density * speed / mix.dynamic_viscosity).max(0.0);
        if x == 0.0 {
            return Self {
                conductivity: mix.conductivity,
                ..Self::default()
            };
        }
        let pr3 =
            cube_root((mix.specific_heat * mix.dynamic_viscosity / mix.conductivity).max(0.0));
        // x^0.6 = (x^0.2)^3 and x^0.7 = x^0.2 x^0.5: one exp, one ln, one sqrt.
        let x02 = (0.2 * x.ln()).exp();
        Self {
            conductivity: mix.conductivity,
            x,
            x02: x02 * pr3,
            x06: x02 * x02 * x02 * pr3,
            x07: x02 * x.sqrt() * pr3,
        }
    }

    /// h_f = Nu λ_eff / d (A-Eq. 45) for a sphere of diameter `dp.d`: the same value as
    /// [`interface_coefficient`] up to round-off.
    pub(crate) fn coefficient(&self, porosity: f64, dp: &DiameterPowers) -> f64 {
        if self.conductivity <= 0.0 || dp.d <= 0.0 {
            return 0.0;
        }
        let e = porosity;
        let a = 7.0 - 10.0 * e + 5.0 * e * e;
        let nu = if self.x == 0.0 {
            a
        } else if self.x * dp.d <= REYNOLDS_SWITCH {
            a * (1.0 + 0.1 * self.x02 * dp.d02)
                + (1.33 - 2.19 * e + 1.15 * e * e) * self.x07 * dp.d07
        } else {
            2.0 + 1.1 * self.x06 * dp.d06
        };
        nu * self.conductivity / dp.d
    }
}

impl HeatModel {
    /// Mixture properties of a fluid cell.
    pub fn fluid_mixture(
        &self,
        liquid_fraction: f64,
        liquid_density: f64,
        gas_density: f64,
    ) -> MixtureProperties {
        mixture(
            &self.liquid,
            &self.gas,
            liquid_fraction,
            liquid_density,
            gas_density,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Newton cube root agrees with the library's to a few units in the last place over
    /// the whole normal range.
    #[test]
    fn cube_root_matches_the_library() {
        let mut worst = 0.0f64;
        let mut p = f64::MIN_POSITIVE;
        while p < 1e300 {
            for q in [p, p * 1.37, p * 2.9, p * 5.1] {
                let (a, b) = (cube_root(q), q.cbrt());
                worst = worst.max(((a - b) / b).abs());
            }
            p *= 7.3;
        }
        assert!(
            worst <= 4.0 * f64::EPSILON,
            "worst relative difference {worst:e}"
        );
        for q in [0.0, f64::INFINITY, 1e-310] {
            assert_eq!(cube_root(q), q.cbrt());
        }
        assert!(cube_root(f64::NAN).is_nan());
    }

    /// The factored form used by the stepper equals A-Eqs. 43–45 evaluated directly, in both
    /// Reynolds ranges and at rest.
    #[test]
    fn factored_coefficient_matches_direct_evaluation() {
        let liquid = Phase {
            specific_heat: 4187.0,
            conductivity: 0.6,
            dynamic_viscosity: 1.002e-3,
        };
        let gas = Phase {
            specific_heat: 1006.0,
            conductivity: 0.0262,
            dynamic_viscosity: 2.05e-5,
        };
        let mut checked = [0usize; 3];
        for alpha in [0.0, 0.3, 1.0] {
            let mix = mixture(&liquid, &gas, alpha, 998.0, 1.2);
            for speed in [0.0, 1e-5, 1e-3, 0.05, 2.0, 40.0] {
                for radius in [1e-4, 2e-3, 4e-3] {
                    for porosity in [0.05, 0.1, 0.4] {
                        let direct = interface_coefficient(&mix, porosity, speed, radius);
                        let f = ExchangeFactors::new(&mix, speed);
                        let factored = f.coefficient(porosity, &DiameterPowers::new(radius));
                        assert!(
                            (factored - direct).abs() <= 1e-12 * direct,
                            "alpha {alpha} v {speed} r {radius}: {factored} vs {direct}"
                        );
                        let re = mix.density * speed * 2.0 * radius / mix.dynamic_viscosity;
                        checked[if re == 0.0 {
                            0
                        } else if re <= REYNOLDS_SWITCH {
                            1
                        } else {
                            2
                        }] += 1;
                    }
                }
            }
        }
        assert!(checked.iter().all(|&n| n > 0), "{checked:?}");
    }
}
