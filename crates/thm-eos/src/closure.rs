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
/// relative round-off. The first guess is the liquid's volume at 0.1 MPa; a typical closure
/// takes 3–6 iterations. On the admissible interval (both molar volumes above the co-volume, both phases
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

/// Which phase's volume fraction the solver iterates on.
#[derive(Debug, Clone, Copy)]
enum Unknown {
    /// x = α.
    Liquid,
    /// x = 1 − α.
    Gas,
}

impl Unknown {
    /// (α, 1 − α) from the unknown, each computed without subtracting a small number from 1
    /// where that phase's fraction is the unknown.
    #[inline]
    fn fractions(self, x: f64) -> (f64, f64) {
        match self {
            Unknown::Liquid => (x, 1.0 - x),
            Unknown::Gas => (1.0 - x, x),
        }
    }

    /// The other phase's fraction as the unknown.
    #[inline]
    fn flip(self) -> Self {
        match self {
            Unknown::Liquid => Unknown::Gas,
            Unknown::Gas => Unknown::Liquid,
        }
    }

    /// `g = ±(P_l − P_g)`, oriented to decrease with x (P_l − P_g decreases with α).
    #[inline]
    fn orient(self, f: f64) -> f64 {
        match self {
            Unknown::Liquid => f,
            Unknown::Gas => -f,
        }
    }
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
    Unstable,
}

impl<L: EquationOfState, G: EquationOfState> TwoPhaseClosure<L, G> {
    /// A closure from the two equations of state.
    pub fn new(liquid: L, gas: G) -> Self {
        Self { liquid, gas }
    }

    #[inline]
    fn trial(
        &self,
        t: f64,
        c_l: f64,
        c_g: f64,
        alpha: f64,
        gas_fraction: f64,
    ) -> Result<Trial, EosError> {
        let rho_l = c_l / alpha;
        let rho_g = c_g / gas_fraction;
        // A trial rounded onto a co-volume (only possible within an ulp of a bracket end, where
        // that phase's pressure is unbounded) says which side of the root it is on.
        let (p_l, dpl) = match self.liquid.pressure_and_dp_drho(t, rho_l) {
            Err(EosError::BelowCovolume { .. }) => return Ok(Trial::LiquidTooDense),
            other => other?,
        };
        let (p_g, dpg) = match self.gas.pressure_and_dp_drho(t, rho_g) {
            Err(EosError::BelowCovolume { .. }) => return Ok(Trial::Unstable),
            other => other?,
        };
        let stable = dpl > 0.0
            && dpg > 0.0
            && self.liquid.on_branch(t, rho_l, Branch::Liquid)?
            && self.gas.on_branch(t, rho_g, Branch::Gas)?;
        if !stable {
            return Ok(Trial::Unstable);
        }
        // d/dα of P_l(c_l/α) − P_g(c_g/(1 − α)).
        let df = -dpl * rho_l / alpha - dpg * rho_g / gas_fraction;
        Ok(Trial::Stable {
            f: p_l - p_g,
            df,
            p_liquid: p_l,
            p_gas: p_g,
        })
    }

    fn single_phase_density<E: EquationOfState>(
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
}

impl<L: EquationOfState, G: EquationOfState> PoreClosure for TwoPhaseClosure<L, G> {
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
        let no_closure = |reason| EosError::NoClosure {
            temperature,
            pore_volume,
            liquid_mass,
            gas_mass,
            reason,
        };
        if m_l == 0.0 && m_g == 0.0 {
            return Err(no_closure("the pore holds no mass"));
        }

        // Single-phase limits: exact, no iteration.
        if m_g == 0.0 {
            let rho_l = m_l / pore_volume;
            let (p, dp) = self.liquid.pressure_and_dp_drho(t, rho_l)?;
            if dp <= 0.0 {
                return Err(no_closure(
                    "the liquid alone is past its spinodal (dP/drho <= 0)",
                ));
            }
            return Ok(ClosureState {
                liquid_fraction: 1.0,
                gas_fraction: 0.0,
                pressure: p,
                liquid_density: rho_l,
                gas_density: Self::single_phase_density(&self.gas, t, p, Branch::Gas)?,
            });
        }
        if m_l == 0.0 {
            let rho_g = m_g / pore_volume;
            let (p, dp) = self.gas.pressure_and_dp_drho(t, rho_g)?;
            if dp <= 0.0 {
                return Err(no_closure(
                    "the gas alone is past its spinodal (dP/drho <= 0)",
                ));
            }
            return Ok(ClosureState {
                liquid_fraction: 0.0,
                gas_fraction: 1.0,
                pressure: p,
                liquid_density: Self::single_phase_density(&self.liquid, t, p, Branch::Liquid)?,
                gas_density: rho_g,
            });
        }

        // Masses per unit pore volume: ρ_l = c_l/α, ρ_g = c_g/(1 − α).
        let c_l = m_l / pore_volume;
        let c_g = m_g / pore_volume;
        let rho_l_max = self.liquid.max_density(t);
        let rho_g_max = self.gas.max_density(t);
        if c_l / rho_l_max + c_g / rho_g_max >= 1.0 {
            return Err(no_closure(
                "the phases do not fit in the pore even at their co-volumes",
            ));
        }

        // First guess: the liquid at 0.1 MPa (it is nearly incompressible, so this is close).
        let alpha_guess = match self.liquid.density(t, GUESS_PRESSURE, Branch::Liquid) {
            Ok(rho) if self.liquid.on_branch(t, rho, Branch::Liquid)? => c_l / rho,
            _ => f64::NAN,
        };
        // The unknown is the fraction of the phase that takes less room, so that a small
        // fraction is resolved to its own round-off rather than to that of 1 − it.
        let mut unknown = if alpha_guess > 0.5 {
            Unknown::Gas
        } else {
            Unknown::Liquid
        };
        let (mut lo, mut hi, guess) = match unknown {
            Unknown::Liquid => (c_l / rho_l_max, 1.0 - c_g / rho_g_max, alpha_guess),
            Unknown::Gas => (c_g / rho_g_max, 1.0 - c_l / rho_l_max, 1.0 - alpha_guess),
        };
        let mut x = if guess > lo && guess < hi {
            guess
        } else {
            0.5 * (lo + hi)
        };

        // Safeguarded Newton on g(x) = ±(P_l − P_g), oriented so that g decreases with x.
        let mut seen_liquid_below_gas = false;
        let mut converged = false;
        let mut last: Option<(f64, f64, f64)> = None; // (x, p_liquid, p_gas) of the last stable trial
        for _ in 0..MAX_ITERATIONS {
            // Keep the unknown the smaller fraction: 1 − x is exact for x in [1/2, 1]
            // (Sterbenz), so switching loses nothing.
            if x > 0.5 {
                x = 1.0 - x;
                (lo, hi) = (1.0 - hi, 1.0 - lo);
                unknown = unknown.flip();
            }
            let (alpha, gamma) = unknown.fractions(x);
            let next = match self.trial(t, c_l, c_g, alpha, gamma)? {
                Trial::Unstable => {
                    // α is too large: x too large for the liquid, too small for the gas.
                    match unknown {
                        Unknown::Liquid => hi = x,
                        Unknown::Gas => lo = x,
                    }
                    0.5 * (lo + hi)
                }
                Trial::LiquidTooDense => {
                    match unknown {
                        Unknown::Liquid => lo = x,
                        Unknown::Gas => hi = x,
                    }
                    0.5 * (lo + hi)
                }
                Trial::Stable {
                    f,
                    df,
                    p_liquid,
                    p_gas,
                } => {
                    last = Some((x, p_liquid, p_gas));
                    if f == 0.0 {
                        converged = true;
                        break;
                    }
                    if f < 0.0 {
                        seen_liquid_below_gas = true;
                    }
                    let g = unknown.orient(f);
                    if g > 0.0 {
                        lo = x;
                    } else {
                        hi = x;
                    }
                    // dg/dx = df/dα for both orientations.
                    let newton = x - g / df;
                    // Converged when the Newton correction is at the round-off of x itself
                    // (checked before the bracket test: at convergence the correction may
                    // point just outside a bracket end set to x itself).
                    if (newton - x).abs() <= 4.0 * f64::EPSILON * x {
                        converged = true;
                        break;
                    }
                    if newton > lo && newton < hi {
                        newton
                    } else {
                        0.5 * (lo + hi)
                    }
                }
            };
            // The bracket has collapsed to round-off: stop.
            if hi - lo <= 4.0 * f64::EPSILON * x {
                x = next;
                let (alpha, gamma) = unknown.fractions(x);
                if let Trial::Stable {
                    p_liquid, p_gas, ..
                } = self.trial(t, c_l, c_g, alpha, gamma)?
                {
                    last = Some((x, p_liquid, p_gas));
                }
                converged = true;
                break;
            }
            x = next;
        }

        if !converged {
            return Err(no_closure("the solver did not converge"));
        }
        let Some((x, p_l, p_g)) = last else {
            return Err(no_closure("both phases cannot be on stable branches"));
        };
        let (alpha, gamma) = unknown.fractions(x);
        // A root needs a sign change or a vanishing Newton correction; a bracket that collapsed
        // on a spinodal with the liquid still above the gas pressure has none.
        let converged_to_root = seen_liquid_below_gas || {
            match self.trial(t, c_l, c_g, alpha, gamma)? {
                Trial::Stable { f, df, .. } => (f / df).abs() <= 8.0 * f64::EPSILON * x,
                Trial::Unstable | Trial::LiquidTooDense => false,
            }
        };
        if !converged_to_root {
            return Err(no_closure(
                "the liquid pressure exceeds the gas pressure up to the liquid's spinodal",
            ));
        }
        Ok(ClosureState {
            liquid_fraction: alpha,
            gas_fraction: gamma,
            pressure: 0.5 * (p_l + p_g),
            liquid_density: c_l / alpha,
            gas_density: c_g / gamma,
        })
    }
}
