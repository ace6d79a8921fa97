//! Effective mixture properties (A-Eqs. 32–36) and the fluid–solid heat transfer coefficient
//! from Nusselt correlations (A-Eqs. 43–45).

/// Validated fluid-phase properties.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phase {
    pub(crate) specific_heat: f64,
    pub(crate) conductivity: f64,
    pub(crate) dynamic_viscosity: f64,
}

/// Effective properties of the homogenised two-phase fluid in one cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MixtureProperties {
    /// ρ_eff = α_q ρ_q + α_p ρ_p (A-Eq. 32) \[kg/m³\].
    pub density: f64,
    /// Volumetric heat capacity Σ α_k ρ_k c_p,k \[J/(m³ K)\].
    pub volumetric_heat_capacity: f64,
    /// Mass-weighted specific heat c_p,eff = Σ α_k ρ_k c_p,k / ρ_eff \[J/(kg K)\] (our reading
    /// of A-Eq. 36; see the crate docs).
    pub specific_heat: f64,
    /// λ_eff = Σ α_k λ_k (A-Eq. 34) \[W/(m K)\].
    pub conductivity: f64,
    /// μ_eff = Σ α_k μ_k (A-Eq. 35) \[Pa s\].
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

/// Fluid-side heat transfer coefficient h_f = Nu λ_eff / (2 r) (A-Eq. 45) \[W/(m² K)\], with
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

/// Powers of one sphere diameter d = 2r \[m\] used by the Nusselt correlations.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct DiameterPowers {
    pub d: f64,
    /// 1 / d \[1/m\].
    pub inv_d: f64,
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
        let d02 = fifth_root(d);
        Self {
            d,
            inv_d: 1.0 / d,
            d02,
            d06: d02 * d02 * d02,
            d07: d02 * d.sqrt(),
        }
    }
}

/// Range of arguments where the division-free roots below run their fixed number of
/// iterations: p z^n stays a normal number of order one, and the first guess read off the
/// bits is within 5 %. Outside it (and for zero, NaN, infinity) the library routines answer.
const ROOT_RANGE: std::ops::RangeInclusive<f64> = 1e-300..=1e300;

/// ∛p by Newton's method on the inverse root w = p^{-1/3}: w ← w + w (1 − p w³) / 3 needs no
/// division; the first guess is read off the bits (exponent times −1/3, relative error below
/// 3.5 %) and four steps take it to round-off (the error squares and triples each step).
/// ∛p = p w². Within two units in the last place of `f64::cbrt`; the library routine outside
/// [`ROOT_RANGE`].
#[inline]
pub(crate) fn cube_root(p: f64) -> f64 {
    if !ROOT_RANGE.contains(&p) {
        return p.cbrt();
    }
    let mut w = f64::from_bits(0x553E_F0FE_5647_37D8u64.wrapping_sub(p.to_bits() / 3));
    for _ in 0..4 {
        let w3 = w * w * w;
        w += w * (1.0 - p * w3) * (1.0 / 3.0);
    }
    p * (w * w)
}

/// x^{1/5} from the inverse root z = x^{-1/5}, without division: with the residual
/// r = 1 − x z⁵ the exact root is z (1 − r)^{-1/5} = z (1 + r/5 + 3r²/25 + …); the first two
/// terms of the series (Halley's order: the error is cubed each step) from a first guess
/// read off the bits (exponent times −1/5, within 5.1 %) reach round-off in three steps;
/// x^{1/5} = x z⁴. Exact 1/5, not the binary 0.2 of `powf(0.2)` (which differs by
/// x^{1.1e-17}, a few units in the last place at the ends of the range); `powf(0.2)` outside
/// [`ROOT_RANGE`].
#[inline]
pub(crate) fn fifth_root(x: f64) -> f64 {
    if !ROOT_RANGE.contains(&x) {
        return x.powf(0.2);
    }
    let mut z = f64::from_bits(0x4CB9_1893_74BC_6A80u64.wrapping_sub(x.to_bits() / 5));
    for _ in 0..3 {
        let z2 = z * z;
        let r = 1.0 - x * (z2 * z2 * z);
        z += z * r * (0.2 + 0.12 * r);
    }
    let z2 = z * z;
    x * (z2 * z2)
}

/// Pr^{1/3} = (c_p μ / λ)^{1/3} of a fluid (A-Eqs. 43–44); 0 for one that does not conduct
/// (its interface coefficient is zero).
#[inline]
pub(crate) fn prandtl_cube_root(specific_heat: f64, viscosity: f64, conductivity: f64) -> f64 {
    if conductivity > 0.0 {
        cube_root((specific_heat * viscosity / conductivity).max(0.0))
    } else {
        0.0
    }
}

/// The fluid cell's part of A-Eqs. 43–45: with x = ρ_eff v / μ_eff (Re per unit diameter),
/// Re^p Pr^{1/3} = (x^p Pr^{1/3}) d^p, so the coefficient of every interface face of the cell
/// is a few products with the sphere's [`DiameterPowers`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct ExchangeFactors {
    /// λ_eff \[W/(m K)\].
    pub conductivity: f64,
    /// ρ_eff v / μ_eff \[1/m\].
    pub x: f64,
    /// x^0.2 Pr^{1/3}, x^0.6 Pr^{1/3}, x^0.7 Pr^{1/3}.
    pub x02: f64,
    pub x06: f64,
    pub x07: f64,
}

impl ExchangeFactors {
    /// The factors of a cell with mixture `mix` and x = ρ_eff v / μ_eff. `prandtl_cbrt` is
    /// Pr^{1/3} where the caller knows it (a pure phase, whose Prandtl number is a model
    /// constant); `None` computes it from the mixture.
    #[cfg(test)]
    pub(crate) fn new(mix: &MixtureProperties, x: f64, prandtl_cbrt: Option<f64>) -> Self {
        let mut f = Self::pending(mix, x, prandtl_cbrt);
        f.complete_powers();
        f
    }

    /// The first half of [`Self::new`]: everything but the powers of x. Until
    /// [`Self::complete_powers`] runs, `x02` holds Pr^{1/3} and `x06`, `x07` are zero. The
    /// powers (a chain of some sixty dependent floating-point operations) are left to a
    /// separate loop over many cells, whose independent chains the processor overlaps.
    #[inline]
    pub(crate) fn pending(mix: &MixtureProperties, x: f64, prandtl_cbrt: Option<f64>) -> Self {
        if mix.conductivity <= 0.0 {
            return Self::default();
        }
        let x = x.max(0.0);
        if x == 0.0 {
            return Self {
                conductivity: mix.conductivity,
                ..Self::default()
            };
        }
        let pr3 = prandtl_cbrt.unwrap_or_else(|| {
            prandtl_cube_root(mix.specific_heat, mix.dynamic_viscosity, mix.conductivity)
        });
        Self {
            conductivity: mix.conductivity,
            x,
            x02: pr3,
            x06: 0.0,
            x07: 0.0,
        }
    }

    /// The second half of [`Self::new`]: x^0.2 Pr^{1/3}, x^0.6 Pr^{1/3} = (x^0.2)^3 Pr^{1/3}
    /// and x^0.7 Pr^{1/3} = x^0.2 x^0.5 Pr^{1/3}; nothing to do at rest.
    #[inline]
    pub(crate) fn complete_powers(&mut self) {
        if self.x > 0.0 {
            let (x, pr3) = (self.x, self.x02);
            let x02 = fifth_root(x);
            self.x02 = x02 * pr3;
            self.x06 = x02 * x02 * x02 * pr3;
            self.x07 = x02 * x.sqrt() * pr3;
        }
    }

    /// The factors of a cell with mixture `mix` whose fastest channel carries speed `speed`
    /// \[m/s\]: x = ρ_eff v / μ_eff.
    #[cfg(test)]
    pub(crate) fn from_speed(mix: &MixtureProperties, speed: f64) -> Self {
        Self::new(mix, mix.density * speed / mix.dynamic_viscosity, None)
    }

    /// h_f = Nu λ_eff / d (A-Eq. 45) for a sphere of diameter `dp.d`: the same value as
    /// [`interface_coefficient`] up to round-off.
    #[inline]
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
        nu * self.conductivity * dp.inv_d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The division-free cube root agrees with the library's to two units in the last place,
    /// and the fifth root y satisfies y⁵ = x to the round-off of the fifth power (y⁵ carries
    /// five times y's relative error plus four roundings), over the whole normal range,
    /// across the edges of the iterated range, and at the special values.
    #[test]
    fn division_free_roots_are_accurate() {
        let (mut worst3, mut worst5) = (0.0f64, 0.0f64);
        let mut p = f64::MIN_POSITIVE;
        while p < 1e307 {
            for q in [p, p * 1.37, p * 2.9, p * 5.1, p * 6.99] {
                let (a, b) = (cube_root(q), q.cbrt());
                worst3 = worst3.max(((a - b) / b).abs());
                let y = fifth_root(q);
                if ROOT_RANGE.contains(&q) {
                    worst5 = worst5.max(((y.powi(5) - q) / q).abs());
                } else {
                    // Outside the iterated range: the library's x^0.2.
                    assert_eq!(y, q.powf(0.2));
                }
            }
            p *= 7.3;
        }
        assert!(
            worst3 <= 2.0 * f64::EPSILON,
            "cube root: worst relative difference {worst3:e}"
        );
        // y = x z⁴ carries four times z's last rounding plus three products, about 3.5 units
        // in the last place; y⁵ (powi: four more products) five times that: 22 units at most.
        assert!(
            worst5 <= 22.0 * f64::EPSILON,
            "fifth root: worst relative residual of y^5 = x: {worst5:e}"
        );
        for (x, y) in [(1.0, 1.0), (32.0, 2.0), (243.0, 3.0), (1e10, 100.0)] {
            assert_eq!(fifth_root(x), y);
        }
        for q in [0.0, f64::INFINITY, 1e-310, 1e-301, 1e301] {
            assert_eq!(cube_root(q), q.cbrt());
            assert_eq!(fifth_root(q), q.powf(0.2));
        }
        assert!(cube_root(f64::NAN).is_nan());
        assert!(fifth_root(f64::NAN).is_nan());
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
                        let f = ExchangeFactors::from_speed(&mix, speed);
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
