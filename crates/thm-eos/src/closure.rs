//! The two-phase pore closure, A-Eq. 29.

use crate::peng_robinson::check_temperature;
use crate::{Branch, EosError, EquationOfState};
use serde::{Deserialize, Serialize};

/// The state of a pore after the closure: phase fractions, densities and the common pressure.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ClosureState {
    /// Liquid volume fraction α ∈ [0, 1].
    pub liquid_fraction: f64,
    /// Gas volume fraction `1 − α`, computed directly where it is the smaller one (so a trace
    /// of gas keeps its own relative precision): `(gas_fraction) · gas_density · V = m_gas`.
    pub gas_fraction: f64,
    /// The common pressure of both phases (Pa).
    pub pressure: f64,
    /// Liquid density (kg/m³): `m_liquid / (α V)`; with no liquid (α = 0), the liquid's
    /// density at the pore pressure (0 when that pressure is not positive).
    pub liquid_density: f64,
    /// Gas density (kg/m³): `m_gas / ((1 − α) V)`; with no gas (α = 1), the gas's density at
    /// the pore pressure (0 when that pressure is not positive).
    pub gas_density: f64,
}

/// Phase fractions and pressure of a pore from its phase masses, volume and temperature.
pub trait PoreClosure {
    /// Closes a pore of volume `pore_volume` (m³) at `temperature` (K) holding `liquid_mass`
    /// and `gas_mass` (kg).
    fn close(
        &self,
        temperature: f64,
        pore_volume: f64,
        liquid_mass: f64,
        gas_mass: f64,
    ) -> Result<ClosureState, EosError>;
}

/// A-Eq. 29 for a liquid and a gas, each described by its own equation of state.
///
/// Solves `P_l(m_l/(αV)) = P_g(m_g/((1 − α)V))` for α by a safeguarded Newton iteration with
/// the analytic `∂P/∂ρ` of both phases, keeping a bracket `[lo, hi]` in which the difference
/// changes sign (a step that would leave it is replaced by bisection). The unknown is the
/// volume fraction of the phase that takes less room (α, or 1 − α for a nearly full liquid
/// pore), so that it converges to its own round-off: α to ~1e-16, a trace gas fraction to its
/// relative round-off. The first guess is the liquid's volume at 0.1 MPa (at 70 MPa where that
/// would not fit in the pore); the closures seen take 1 to 10 iterations, the most near the
/// critical point. On the admissible interval (both molar volumes above the co-volume, both phases
/// on their mechanically stable branches, `∂P/∂ρ > 0`) the pressure difference decreases
/// strictly with α, so the root there is unique. The liquid must be on its dense branch and the
/// gas on its dilute one ([`EquationOfState::on_branch`]): where the liquid's cubic also has a
/// vapour branch, a second root with the "liquid" expanded into vapour may exist, and it is
/// never taken. Trial states past a spinodal or on the other branch lie above the wanted root
/// (their α is too large) and shrink the bracket from above; if the difference stays positive up
/// to the liquid's spinodal, no state with equal pressures on the stable branches exists and a
/// [`EosError::NoClosure`] is returned.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoPhaseClosure<L, G> {
    /// The liquid's equation of state (water in paper A).
    pub liquid: L,
    /// The gas's equation of state (air in paper A).
    pub gas: G,
}

/// Largest number of iterations of the safeguarded Newton solver (bisection alone halves the
/// bracket 64 times in this budget, more than enough to reach round-off on [0, 1]).
const MAX_ITERATIONS: usize = 200;

/// Pressure at which the first guess of the liquid density is taken (Pa).
const GUESS_PRESSURE: f64 = 1.0e5;

/// Pressure of the second guess, where the liquid at [`GUESS_PRESSURE`] would not fit (Pa).
const HIGH_GUESS_PRESSURE: f64 = 7.0e7;

fn check_nonnegative(
    quantity: &'static str,
    value: f64,
    allowed: &'static str,
) -> Result<f64, EosError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(EosError::InvalidInput {
            quantity,
            value,
            allowed,
        })
    }
}

/// Why a pore has no closure (turned into [`EosError::NoClosure`] with the pore's data).
type Reason = &'static str;

/// Which phase's volume fraction the solver iterates on.
#[derive(Debug, Clone, Copy)]
enum Unknown {
    /// x = α.
    Liquid,
    /// x = 1 − α.
    Gas,
}

/// What one evaluation of the pressure difference found.
enum Trial {
    /// Both phases on stable branches: `f = P_l − P_g`, `df/dα`, and the two pressures.
    Stable {
        f: f64,
        df: f64,
        p_liquid: f64,
        p_gas: f64,
    },
    /// The liquid is at or above its co-volume density: α is too small.
    LiquidTooDense,
    /// A phase is past its spinodal (`∂P/∂ρ ≤ 0`) or on its other branch, or the gas is at its
    /// co-volume: α is too large.
    AlphaTooLarge,
}

/// The state of the root search: the unknown, its value and its bracket.
///
/// The unknown is kept the smaller of α and 1 − α, so that a small fraction is resolved to its
/// own round-off rather than to that of 1 minus it. `g = ±(P_l − P_g)` is oriented to decrease
/// with x, so `g > 0` moves `lo` up and `g < 0` moves `hi` down in both representations.
#[derive(Debug, Clone, Copy)]
struct Search {
    unknown: Unknown,
    x: f64,
    lo: f64,
    hi: f64,
}

impl Search {
    /// (α, 1 − α), each computed without subtracting a small number from 1 where that phase's
    /// fraction is the unknown.
    #[inline]
    fn fractions(&self) -> (f64, f64) {
        match self.unknown {
            Unknown::Liquid => (self.x, 1.0 - self.x),
            Unknown::Gas => (1.0 - self.x, self.x),
        }
    }

    /// Switches to the other phase's fraction when x > 1/2. `1 − x` is exact for x in
    /// [1/2, 1] (Sterbenz), so the switch loses nothing.
    #[inline]
    fn keep_smaller(&mut self) {
        if self.x > 0.5 {
            self.x = 1.0 - self.x;
            (self.lo, self.hi) = (1.0 - self.hi, 1.0 - self.lo);
            self.unknown = match self.unknown {
                Unknown::Liquid => Unknown::Gas,
                Unknown::Gas => Unknown::Liquid,
            };
        }
    }

    /// `g` from `f = P_l − P_g` (P_l − P_g decreases with α).
    #[inline]
    fn orient(&self, f: f64) -> f64 {
        match self.unknown {
            Unknown::Liquid => f,
            Unknown::Gas => -f,
        }
    }

    /// The current x lies at too large an α: shrink the bracket on that side; bisect.
    #[inline]
    fn alpha_too_large(&mut self) {
        match self.unknown {
            Unknown::Liquid => self.hi = self.x,
            Unknown::Gas => self.lo = self.x,
        }
        self.x = 0.5 * (self.lo + self.hi);
    }

    /// The current x lies at too small an α: shrink the bracket on that side; bisect.
    #[inline]
    fn alpha_too_small(&mut self) {
        match self.unknown {
            Unknown::Liquid => self.lo = self.x,
            Unknown::Gas => self.hi = self.x,
        }
        self.x = 0.5 * (self.lo + self.hi);
    }

    /// Whether the bracket has shrunk to the round-off of x.
    #[inline]
    fn collapsed(&self) -> bool {
        self.hi - self.lo <= 4.0 * f64::EPSILON * self.x
    }
}

/// The last state with both phases stable: fractions and the two pressures.
#[derive(Debug, Clone, Copy)]
struct StableState {
    alpha: f64,
    gamma: f64,
    p_liquid: f64,
    p_gas: f64,
}

impl<L: EquationOfState, G: EquationOfState> TwoPhaseClosure<L, G> {
    /// A closure from the two equations of state.
    pub fn new(liquid: L, gas: G) -> Self {
        Self { liquid, gas }
    }

    /// Evaluates the pressure difference at liquid fraction α (gas fraction γ = 1 − α).
    #[inline]
    fn trial(&self, t: f64, c_l: f64, c_g: f64, alpha: f64, gamma: f64) -> Result<Trial, EosError> {
        let rho_l = c_l / alpha;
        let rho_g = c_g / gamma;
        // A trial rounded onto a co-volume (only possible within an ulp of a bracket end, where
        // that phase's pressure is unbounded) says which side of the root it is on.
        let (p_l, dpl) = match self.liquid.pressure_and_dp_drho(t, rho_l) {
            Err(EosError::BelowCovolume { .. }) => return Ok(Trial::LiquidTooDense),
            other => other?,
        };
        let (p_g, dpg) = match self.gas.pressure_and_dp_drho(t, rho_g) {
            Err(EosError::BelowCovolume { .. }) => return Ok(Trial::AlphaTooLarge),
            other => other?,
        };
        let stable = dpl > 0.0
            && dpg > 0.0
            && self.liquid.on_branch(t, rho_l, Branch::Liquid)?
            && self.gas.on_branch(t, rho_g, Branch::Gas)?;
        if !stable {
            return Ok(Trial::AlphaTooLarge);
        }
        Ok(Trial::Stable {
            f: p_l - p_g,
            // d/dα of P_l(c_l/α) − P_g(c_g/(1 − α)).
            df: -dpl * rho_l / alpha - dpg * rho_g / gamma,
            p_liquid: p_l,
            p_gas: p_g,
        })
    }

    /// Stage: a pore holding only liquid (exact: α = 1, `P = P_l(T, m/V)`).
    fn liquid_only(
        &self,
        t: f64,
        volume: f64,
        mass: f64,
    ) -> Result<Result<ClosureState, Reason>, EosError> {
        let rho = mass / volume;
        let (p, dp) = self.liquid.pressure_and_dp_drho(t, rho)?;
        if dp <= 0.0 {
            return Ok(Err("the liquid alone is past its spinodal (dP/drho <= 0)"));
        }
        Ok(Ok(ClosureState {
            liquid_fraction: 1.0,
            gas_fraction: 0.0,
            pressure: p,
            liquid_density: rho,
            gas_density: absent_phase_density(&self.gas, t, p, Branch::Gas)?,
        }))
    }

    /// Stage: a pore holding only gas (exact: α = 0, `P = P_g(T, m/V)`).
    fn gas_only(
        &self,
        t: f64,
        volume: f64,
        mass: f64,
    ) -> Result<Result<ClosureState, Reason>, EosError> {
        let rho = mass / volume;
        let (p, dp) = self.gas.pressure_and_dp_drho(t, rho)?;
        if dp <= 0.0 {
            return Ok(Err("the gas alone is past its spinodal (dP/drho <= 0)"));
        }
        Ok(Ok(ClosureState {
            liquid_fraction: 0.0,
            gas_fraction: 1.0,
            pressure: p,
            liquid_density: absent_phase_density(&self.liquid, t, p, Branch::Liquid)?,
            gas_density: rho,
        }))
    }

    /// Stage: the admissible bracket (both molar volumes above their co-volumes) and the first
    /// guess (the liquid's volume at 0.1 MPa: it is nearly incompressible).
    fn start(&self, t: f64, c_l: f64, c_g: f64) -> Result<Result<Search, Reason>, EosError> {
        let alpha_min = c_l / self.liquid.max_density(t);
        let gamma_min = c_g / self.gas.max_density(t);
        if alpha_min + gamma_min >= 1.0 {
            return Ok(Err(
                "the phases do not fit in the pore even at their co-volumes",
            ));
        }
        let liquid_fraction_at = |p: f64| -> Result<f64, EosError> {
            Ok(match self.liquid.density(t, p, Branch::Liquid) {
                Ok(rho) if self.liquid.on_branch(t, rho, Branch::Liquid)? => c_l / rho,
                _ => f64::NAN,
            })
        };
        let mut alpha_guess = liquid_fraction_at(GUESS_PRESSURE)?;
        if alpha_guess >= 1.0 - gamma_min {
            // The liquid at 0.1 MPa does not fit: the pore is at high pressure. Start from the
            // liquid at the top of the validated range instead (it fits if any state does
            // below that pressure).
            alpha_guess = liquid_fraction_at(HIGH_GUESS_PRESSURE)?;
        }
        let (unknown, lo, hi, guess) = if alpha_guess > 0.5 {
            (Unknown::Gas, gamma_min, 1.0 - alpha_min, 1.0 - alpha_guess)
        } else {
            (Unknown::Liquid, alpha_min, 1.0 - gamma_min, alpha_guess)
        };
        let x = if guess > lo && guess < hi {
            guess
        } else {
            0.5 * (lo + hi)
        };
        Ok(Ok(Search { unknown, x, lo, hi }))
    }

    /// Stage: safeguarded Newton on g(x) with the analytic derivative, bisection where a step
    /// would leave the bracket or a trial is unstable.
    fn solve(
        &self,
        t: f64,
        c_l: f64,
        c_g: f64,
        mut search: Search,
    ) -> Result<Result<ClosureState, Reason>, EosError> {
        let mut seen_liquid_below_gas = false;
        let mut last: Option<StableState> = None;
        let mut converged = false;
        for _ in 0..MAX_ITERATIONS {
            search.keep_smaller();
            let (alpha, gamma) = search.fractions();
            match self.trial(t, c_l, c_g, alpha, gamma)? {
                Trial::AlphaTooLarge => search.alpha_too_large(),
                Trial::LiquidTooDense => search.alpha_too_small(),
                Trial::Stable {
                    f,
                    df,
                    p_liquid,
                    p_gas,
                } => {
                    last = Some(StableState {
                        alpha,
                        gamma,
                        p_liquid,
                        p_gas,
                    });
                    seen_liquid_below_gas |= f < 0.0;
                    let g = search.orient(f);
                    // dg/dx = df/dα in both orientations.
                    let newton = search.x - g / df;
                    // Converged when the correction is at the round-off of x (tested before the
                    // bracket: at the root it may point just outside an end set to x itself).
                    if f == 0.0 || (newton - search.x).abs() <= 4.0 * f64::EPSILON * search.x {
                        converged = true;
                        break;
                    }
                    if g > 0.0 {
                        search.lo = search.x;
                    } else {
                        search.hi = search.x;
                    }
                    search.x = if newton > search.lo && newton < search.hi {
                        newton
                    } else {
                        0.5 * (search.lo + search.hi)
                    };
                }
            }
            if search.collapsed() {
                let (alpha, gamma) = search.fractions();
                if let Trial::Stable {
                    p_liquid, p_gas, ..
                } = self.trial(t, c_l, c_g, alpha, gamma)?
                {
                    last = Some(StableState {
                        alpha,
                        gamma,
                        p_liquid,
                        p_gas,
                    });
                }
                converged = true;
                break;
            }
        }
        if !converged {
            return Ok(Err("the solver did not converge"));
        }
        let Some(state) = last else {
            return Ok(Err("both phases cannot be on stable branches"));
        };
        // A root needs a sign change or a vanishing Newton correction; a bracket that collapsed
        // on a spinodal with the liquid still above the gas pressure has none.
        let at_root = seen_liquid_below_gas || {
            let x = state.alpha.min(state.gamma);
            match self.trial(t, c_l, c_g, state.alpha, state.gamma)? {
                Trial::Stable { f, df, .. } => (f / df).abs() <= 8.0 * f64::EPSILON * x,
                Trial::AlphaTooLarge | Trial::LiquidTooDense => false,
            }
        };
        if !at_root {
            return Ok(Err(
                "the liquid pressure exceeds the gas pressure up to the liquid's spinodal",
            ));
        }
        Ok(Ok(ClosureState {
            liquid_fraction: state.alpha,
            gas_fraction: state.gamma,
            pressure: 0.5 * (state.p_liquid + state.p_gas),
            liquid_density: c_l / state.alpha,
            gas_density: c_g / state.gamma,
        }))
    }
}

/// The density of a phase absent from the pore: its density at the pore pressure on its
/// branch, 0 when that pressure is not positive (no such phase can exist there).
fn absent_phase_density<E: EquationOfState>(
    eos: &E,
    t: f64,
    p: f64,
    branch: Branch,
) -> Result<f64, EosError> {
    if p > 0.0 {
        eos.density(t, p, branch)
    } else {
        Ok(0.0)
    }
}

impl<L: EquationOfState, G: EquationOfState> PoreClosure for TwoPhaseClosure<L, G> {
    /// Validates the inputs, then takes the single-phase limit or solves A-Eq. 29.
    fn close(
        &self,
        temperature: f64,
        pore_volume: f64,
        liquid_mass: f64,
        gas_mass: f64,
    ) -> Result<ClosureState, EosError> {
        let t = check_temperature(temperature)?;
        if !(pore_volume.is_finite() && pore_volume > 0.0) {
            return Err(EosError::InvalidInput {
                quantity: "pore_volume",
                value: pore_volume,
                allowed: "(0, inf) m³",
            });
        }
        let m_l = check_nonnegative("liquid_mass", liquid_mass, "[0, inf) kg")?;
        let m_g = check_nonnegative("gas_mass", gas_mass, "[0, inf) kg")?;
        let outcome = match (m_l > 0.0, m_g > 0.0) {
            (false, false) => Err("the pore holds no mass"),
            (true, false) => self.liquid_only(t, pore_volume, m_l)?,
            (false, true) => self.gas_only(t, pore_volume, m_g)?,
            (true, true) => {
                // Masses per unit pore volume: ρ_l = c_l/α, ρ_g = c_g/(1 − α).
                let (c_l, c_g) = (m_l / pore_volume, m_g / pore_volume);
                match self.start(t, c_l, c_g)? {
                    Ok(search) => self.solve(t, c_l, c_g, search)?,
                    Err(reason) => Err(reason),
                }
            }
        };
        // Every input is finite and each phase's pressure is checked, but the combination
        // (e.g. a fraction near an ulp of 0 against an extreme mass) could still overflow.
        let outcome = outcome.and_then(|s| {
            let values = [
                s.liquid_fraction,
                s.gas_fraction,
                s.pressure,
                s.liquid_density,
                s.gas_density,
            ];
            if values.iter().all(|x| x.is_finite()) {
                Ok(s)
            } else {
                Err("a computed fraction, density or pressure is not finite")
            }
        });
        outcome.map_err(|reason| EosError::NoClosure {
            temperature,
            pore_volume,
            liquid_mass,
            gas_mass,
            reason,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::{Branch, EquationOfState, GAS_CONSTANT, Model, PoreClosure, water_air_closure};

    /// The fuzz finding `eos_csv/crash-c109…`: T = 300 K, V = 1e-9 m³, no liquid and
    /// m_gas = 1e-251 kg closed with pressure NaN (the gas's V² overflowed). It is a gas-only pore
    /// at the ideal-gas pressure m R T/(w V), and the absent liquid's density is the liquid's at
    /// that pressure (its P → 0 limit), not the vapour's.
    #[test]
    fn a_vanishing_gas_mass_is_an_ideal_gas() {
        for model in [Model::Pr, Model::PrCorrected] {
            let closure = water_air_closure(model);
            let s = closure.close(300.0, 1e-9, 0.0, 1e-251).unwrap();
            let ideal = 1e-251 / 1e-9 * GAS_CONSTANT * 300.0 / closure.gas.molar_mass();
            assert!((s.pressure / ideal - 1.0).abs() < 1e-12, "{s:?}");
            assert_eq!((s.liquid_fraction, s.gas_fraction), (0.0, 1.0));
            let liquid = closure.liquid.density(300.0, 1.0, Branch::Liquid).unwrap();
            assert!((s.liquid_density / liquid - 1.0).abs() < 1e-9, "{s:?}");
            // With a little liquid as well, the two-phase solver reaches the same pressure scale.
            let s = closure.close(300.0, 1e-9, 1e-15, 1e-251).unwrap();
            assert!(s.pressure.is_finite() && s.liquid_fraction > 0.0, "{s:?}");
        }
    }

    /// The fuzz finding `eos_state/crash-1885…`: T = 647.1 K, V = 6.3e-226 m³ and subnormal
    /// masses have no closure, and the error wrote V and both masses with every digit (1033
    /// characters). Numbers far from 1 are now written in exponent form.
    #[test]
    fn extreme_inputs_give_a_short_message() {
        for model in [Model::Pr, Model::PrCorrected] {
            let r = water_air_closure(model).close(
                647.1,
                6.341723685788695e-226,
                1.49554e-319,
                1.6664e-319,
            );
            let e = r.unwrap_err().to_string();
            assert!(e.len() < 300, "{} characters: {e}", e.len());
            assert!(e.contains("V = 6.341723685788695e-226 m³"), "{e}");
        }
    }
}
