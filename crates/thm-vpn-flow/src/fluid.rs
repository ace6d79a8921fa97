//! The seam to the thermodynamics: [`PoreFluid`] closes a pore (A-Eq. 29) and gives phase
//! densities and bulk moduli. [`LinearLiquidIdealGas`] is a simple model with an exact closure,
//! used by the tests and verification cases; the Peng–Robinson closure of `thm-eos` plugs in
//! through the same trait.

use crate::error::{ClosureFailure, Phase};
use serde::{Deserialize, Serialize};

/// The thermodynamic state of one pore after the closure.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoreState {
    /// Liquid volume fraction `α_q ∈ [0, 1]`.
    pub liquid_fraction: f64,
    /// Common pressure of both phases \[Pa\].
    pub pressure: f64,
    /// Liquid density [kg/m³] (meaningful also when `α_q = 0`: the density the liquid would
    /// have at `pressure`).
    pub liquid_density: f64,
    /// Gas density [kg/m³] (meaningful also when `α_q = 1`).
    pub gas_density: f64,
}

/// Pore thermodynamics: the two-phase closure and the phase properties the solver needs.
///
/// Implementations must be deterministic and thread-safe (`Sync`): the solver closes pores in
/// parallel.
pub trait PoreFluid: Sync {
    /// The closure (A-Eq. 29): from the liquid and gas masses \[kg\] in a pore of `volume` \[m³\]
    /// at `temperature` \[K\], the liquid fraction at which both phases have the same pressure,
    /// that pressure and the phase densities. Must satisfy, to round-off,
    /// `α_q ρ_q V = m_q` and `(1 − α_q) ρ_p V = m_p`; a pore with one phase has `α_q ∈ {0, 1}`.
    fn close(
        &self,
        liquid_mass: f64,
        gas_mass: f64,
        volume: f64,
        temperature: f64,
    ) -> Result<PoreState, ClosureFailure>;

    /// Density of one phase at `pressure` \[Pa\] and `temperature` \[K\] (used for fluid entering
    /// through a prescribed-pressure boundary and for initial states).
    fn density(&self, phase: Phase, pressure: f64, temperature: f64)
    -> Result<f64, ClosureFailure>;

    /// Isothermal bulk modulus `K = ρ ∂P/∂ρ` \[Pa\] of one phase at `density` and `temperature`
    /// (used for the stable time step). Must be finite and positive on the phase's stable
    /// branch; an error stops the step naming the pore.
    fn bulk_modulus(
        &self,
        phase: Phase,
        density: f64,
        temperature: f64,
    ) -> Result<f64, ClosureFailure>;
}

/// Parameters of [`LinearLiquidIdealGas`] (serde, validated by
/// [`LinearLiquidIdealGas::new`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearLiquidIdealGasParameters {
    /// Liquid density at the reference pressure `ρ₀` [kg/m³].
    pub liquid_reference_density: f64,
    /// Reference pressure `P₀` \[Pa\].
    pub liquid_reference_pressure: f64,
    /// Liquid bulk modulus `K` \[Pa\] (must exceed `P₀`).
    pub liquid_bulk_modulus: f64,
    /// Molar mass of the gas `w_p` [kg/kmol] (Table 1: air 28.9647).
    pub gas_molar_mass: f64,
    /// Universal gas constant `R` [J/(kmol·K)] (Table 1: 8314.4598).
    pub gas_constant: f64,
}

impl LinearLiquidIdealGasParameters {
    /// Water (ρ₀ = 1000 kg/m³ at P₀ = 0.1 MPa, K = 2.2 GPa) and air of Table 1.
    pub fn water_air() -> Self {
        Self {
            liquid_reference_density: 1000.0,
            liquid_reference_pressure: 1.0e5,
            liquid_bulk_modulus: 2.2e9,
            gas_molar_mass: 28.9647,
            gas_constant: 8314.4598,
        }
    }
}

/// A weakly compressible liquid `ρ_q = ρ₀ (1 + (P − P₀)/K)` and an ideal gas
/// `ρ_p = P w_p/(R T)`. Their closure is exact: the common pressure solves
/// `m_q/ρ_q(P) + m_p/ρ_p(P) = V`, a quadratic in `P` with one positive root.
///
/// Validity: the liquid law is linear in `P` (good for water within a few tens of MPa of `P₀`);
/// a pure-liquid pore stretched below zero pressure has no solution (this model has no
/// cavitation) and is reported as [`ClosureFailure::NoSolution`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearLiquidIdealGas {
    p: LinearLiquidIdealGasParameters,
    /// `ρ_q = a + b P`.
    a: f64,
    b: f64,
    /// `1/b = K/ρ₀`.
    inv_b: f64,
    /// `R/w_p`.
    r_over_w: f64,
}

impl LinearLiquidIdealGas {
    /// Validates the parameters.
    pub fn new(p: LinearLiquidIdealGasParameters) -> Result<Self, crate::FlowError> {
        let check = |name: &'static str, v: f64, range: &'static str, ok: bool| {
            if v.is_finite() && ok {
                Ok(())
            } else {
                Err(crate::FlowError::OutOfRange {
                    name,
                    range,
                    value: v,
                })
            }
        };
        check(
            "liquid_reference_density",
            p.liquid_reference_density,
            "> 0 kg/m³",
            p.liquid_reference_density > 0.0,
        )?;
        check(
            "liquid_reference_pressure",
            p.liquid_reference_pressure,
            ">= 0 Pa",
            p.liquid_reference_pressure >= 0.0,
        )?;
        check(
            "liquid_bulk_modulus",
            p.liquid_bulk_modulus,
            "> liquid_reference_pressure",
            p.liquid_bulk_modulus > p.liquid_reference_pressure,
        )?;
        check(
            "gas_molar_mass",
            p.gas_molar_mass,
            "> 0 kg/kmol",
            p.gas_molar_mass > 0.0,
        )?;
        check(
            "gas_constant",
            p.gas_constant,
            "> 0 J/(kmol K)",
            p.gas_constant > 0.0,
        )?;
        let b = p.liquid_reference_density / p.liquid_bulk_modulus;
        let a = p.liquid_reference_density - b * p.liquid_reference_pressure;
        Ok(Self {
            p,
            a,
            b,
            inv_b: p.liquid_bulk_modulus / p.liquid_reference_density,
            r_over_w: p.gas_constant / p.gas_molar_mass,
        })
    }

    /// The parameters.
    pub fn parameters(&self) -> &LinearLiquidIdealGasParameters {
        &self.p
    }

    fn liquid_density_at(&self, pressure: f64) -> f64 {
        self.a + self.b * pressure
    }

    fn gas_density_at(&self, pressure: f64, temperature: f64) -> f64 {
        pressure / (self.r_over_w * temperature)
    }
}

/// The error for closure inputs outside their ranges (the first offending one).
#[cold]
fn invalid_input(liquid_mass: f64, gas_mass: f64, volume: f64, temperature: f64) -> ClosureFailure {
    if !(liquid_mass.is_finite() && liquid_mass >= 0.0) {
        ClosureFailure::NegativeMass {
            phase: Phase::Liquid,
            value: liquid_mass,
        }
    } else if !(gas_mass.is_finite() && gas_mass >= 0.0) {
        ClosureFailure::NegativeMass {
            phase: Phase::Gas,
            value: gas_mass,
        }
    } else if !(volume.is_finite() && volume > 0.0) {
        ClosureFailure::NonPositiveVolume { value: volume }
    } else {
        ClosureFailure::NonPositiveTemperature { value: temperature }
    }
}

impl PoreFluid for LinearLiquidIdealGas {
    fn close(
        &self,
        liquid_mass: f64,
        gas_mass: f64,
        volume: f64,
        temperature: f64,
    ) -> Result<PoreState, ClosureFailure> {
        let inputs_valid = (0.0..f64::INFINITY).contains(&liquid_mass)
            && (0.0..f64::INFINITY).contains(&gas_mass)
            && volume > 0.0
            && volume < f64::INFINITY
            && temperature > 0.0
            && temperature < f64::INFINITY;
        if !inputs_valid {
            return Err(invalid_input(liquid_mass, gas_mass, volume, temperature));
        }
        if gas_mass == 0.0 {
            if liquid_mass == 0.0 {
                return Err(ClosureFailure::Empty);
            }
            let rho = liquid_mass / volume;
            let pressure = (rho - self.a) * self.inv_b;
            if pressure <= 0.0 {
                return Err(ClosureFailure::NoSolution {
                    reason: "pure liquid below zero pressure (pressure in Pa)",
                    value: pressure,
                });
            }
            return Ok(PoreState {
                liquid_fraction: 1.0,
                pressure,
                liquid_density: rho,
                gas_density: self.gas_density_at(pressure, temperature),
            });
        }
        let g = gas_mass * self.r_over_w * temperature;
        if liquid_mass == 0.0 {
            let pressure = g / volume;
            return Ok(PoreState {
                liquid_fraction: 0.0,
                pressure,
                liquid_density: self.liquid_density_at(pressure),
                gas_density: gas_mass / volume,
            });
        }
        // V b P² + (V a − m_q − g b) P − g a = 0; the product of the roots is −g a/(V b) < 0,
        // so exactly one root is positive. Written in the cancellation-free form.
        let qa = volume * self.b;
        let qb = volume * self.a - liquid_mass - g * self.b;
        let qc = -g * self.a;
        let disc = qb * qb - 4.0 * qa * qc;
        let pressure = if qb <= 0.0 {
            (-qb + disc.sqrt()) / (2.0 * qa)
        } else {
            2.0 * qc / (-qb - disc.sqrt())
        };
        if !(pressure.is_finite() && pressure > 0.0) {
            return Err(ClosureFailure::NoSolution {
                reason: "no positive common pressure (pressure in Pa)",
                value: pressure,
            });
        }
        let liquid_volume = liquid_mass / self.liquid_density_at(pressure);
        let gas_volume = gas_mass / self.gas_density_at(pressure, temperature);
        let liquid_fraction = liquid_volume / (liquid_volume + gas_volume);
        // Densities from the masses and the fraction, so that α ρ V = m holds to round-off,
        // unless a phase's fraction is below round-off (then from the pressure).
        let gas_fraction = 1.0 - liquid_fraction;
        let liquid_density = if liquid_fraction > 0.0 {
            liquid_mass / (liquid_fraction * volume)
        } else {
            self.liquid_density_at(pressure)
        };
        let gas_density = if gas_fraction > 0.0 {
            gas_mass / (gas_fraction * volume)
        } else {
            self.gas_density_at(pressure, temperature)
        };
        Ok(PoreState {
            liquid_fraction,
            pressure,
            liquid_density,
            gas_density,
        })
    }

    fn density(
        &self,
        phase: Phase,
        pressure: f64,
        temperature: f64,
    ) -> Result<f64, ClosureFailure> {
        if !(temperature.is_finite() && temperature > 0.0) {
            return Err(ClosureFailure::NonPositiveTemperature { value: temperature });
        }
        let rho = match phase {
            Phase::Liquid => self.liquid_density_at(pressure),
            Phase::Gas => self.gas_density_at(pressure, temperature),
        };
        if rho.is_finite() && rho > 0.0 {
            Ok(rho)
        } else {
            Err(ClosureFailure::NoSolution {
                reason: "non-positive density at this pressure (density in kg/m³)",
                value: rho,
            })
        }
    }

    fn bulk_modulus(
        &self,
        phase: Phase,
        density: f64,
        temperature: f64,
    ) -> Result<f64, ClosureFailure> {
        Ok(match phase {
            // K = ρ dP/dρ = ρ / b.
            Phase::Liquid => density * self.inv_b,
            // P = ρ R T / w ⇒ K = P.
            Phase::Gas => density * self.r_over_w * temperature,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> LinearLiquidIdealGas {
        LinearLiquidIdealGas::new(LinearLiquidIdealGasParameters::water_air()).unwrap()
    }

    #[test]
    fn closure_conserves_masses_and_equalises_pressure() {
        let m = model();
        let t = 293.15;
        for &(alpha, p) in &[(0.5, 1e6), (0.99, 3e5), (0.01, 5e7), (0.3, 1.2e5)] {
            let v = 2.0e-9;
            let rq = m.density(Phase::Liquid, p, t).unwrap();
            let rp = m.density(Phase::Gas, p, t).unwrap();
            let (mq, mp) = (alpha * rq * v, (1.0 - alpha) * rp * v);
            let s = m.close(mq, mp, v, t).unwrap();
            assert!((s.pressure - p).abs() <= 1e-9 * p, "{} vs {p}", s.pressure);
            assert!((s.liquid_fraction - alpha).abs() <= 1e-9);
            assert!((s.liquid_fraction * s.liquid_density * v - mq).abs() <= 1e-14 * mq);
            assert!((s.gas_density * (1.0 - s.liquid_fraction) * v - mp).abs() <= 1e-14 * mp);
            // Both phases at the closure pressure.
            let pq = (s.liquid_density - m.a) / m.b;
            let pp = s.gas_density * 8314.4598 * t / 28.9647;
            assert!((pq - pp).abs() <= 1e-6 * p);
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]
        #[test]
        fn closure_conserves_both_masses_for_any_pore(
            liquid_mass in 0.0f64..2e-6,
            gas_mass in 0.0f64..1e-7,
            volume in 1e-10f64..1e-8,
            temperature in 250.0f64..400.0,
        ) {
            let m = model();
            match m.close(liquid_mass, gas_mass, volume, temperature) {
                Ok(s) => {
                    proptest::prop_assert!((0.0..=1.0).contains(&s.liquid_fraction));
                    proptest::prop_assert!(s.pressure > 0.0);
                    let mq = s.liquid_fraction * s.liquid_density * volume;
                    let mp = (1.0 - s.liquid_fraction) * s.gas_density * volume;
                    proptest::prop_assert!((mq - liquid_mass).abs() <= 1e-12 * liquid_mass.max(1e-30));
                    proptest::prop_assert!((mp - gas_mass).abs() <= 1e-12 * gas_mass.max(1e-30));
                }
                // Only an empty pore or stretched pure liquid have no solution.
                Err(ClosureFailure::Empty) => proptest::prop_assert!(liquid_mass == 0.0 && gas_mass == 0.0),
                Err(ClosureFailure::NoSolution { .. }) => proptest::prop_assert!(gas_mass == 0.0),
                Err(e) => proptest::prop_assert!(false, "{e}"),
            }
        }
    }

    #[test]
    fn single_phase_limits() {
        let m = model();
        let s = m.close(1.0e-6, 0.0, 1.0e-9, 300.0).unwrap();
        assert_eq!(s.liquid_fraction, 1.0);
        assert!((s.pressure - 1.0e5).abs() < 1e-3);
        let s = m.close(0.0, 1.0e-9, 1.0e-9, 300.0).unwrap();
        assert_eq!(s.liquid_fraction, 0.0);
        assert!((s.pressure - 8314.4598 * 300.0 / 28.9647).abs() < 1e-6);
    }

    #[test]
    fn impossible_states_are_typed_errors() {
        let m = model();
        assert_eq!(m.close(0.0, 0.0, 1.0, 300.0), Err(ClosureFailure::Empty));
        assert!(matches!(
            m.close(-1.0, 0.0, 1.0, 300.0),
            Err(ClosureFailure::NegativeMass {
                phase: Phase::Liquid,
                ..
            })
        ));
        // Pure water at 900 kg/m³ would be at −220 MPa.
        assert!(matches!(
            m.close(900.0e-9, 0.0, 1.0e-9, 300.0),
            Err(ClosureFailure::NoSolution { .. })
        ));
        assert!(matches!(
            m.close(1.0, 1.0, 0.0, 300.0),
            Err(ClosureFailure::NonPositiveVolume { .. })
        ));
    }
}
