//! The Peng–Robinson equation (A-Eqs. 16–22) with the Péneloux volume correction (A-Eq. 23).

use crate::{Branch, EosError, EquationOfState};
use serde::{Deserialize, Serialize};

/// Universal gas constant of paper A, Table 1 (J/(kmol·K)).
pub const GAS_CONSTANT: f64 = 8314.4598;

/// Coefficient of the critical attraction, A-Eq. 20.
const OMEGA_A: f64 = 0.457247;
/// Coefficient of the co-volume, A-Eq. 21.
const OMEGA_B: f64 = 0.07780;

/// The Péneloux volume shift of liquid water, A-Eq. 23 and Sect. 2.2.2 (m³/kmol).
pub const WATER_VOLUME_SHIFT: f64 = -0.0034;

/// `x_m = V/b` at which `L(x) = (x² + 2x − 1)² / ((x + 1)(x − 1)²)` is smallest.
///
/// `∂P/∂V < 0` (A-Eq. 16) is equivalent to `L(V/b) > θ(T) = 2a(T)/(R T b)`. `L` falls from
/// +∞ at `x = 1` to its minimum at `x_m` and rises again, so on a subcritical isotherm
/// (`θ > L(x_m)`) the liquid spinodal lies below `x_m` and the vapour spinodal above it: a stable
/// state with `V/b < x_m` is on the dense branch, one with `V/b > x_m` on the dilute branch. The
/// number is universal (independent of the fluid and of Ω_a, Ω_b); its stationarity is checked
/// by a unit test.
pub(crate) const BRANCH_SPLIT: f64 = 3.951_373_035_591_441;
/// `L(x_m)`: the value of θ at the equation's own critical temperature.
pub(crate) const CRITICAL_THETA: f64 = 11.754_719_897_208_806;

/// Parameters of one fluid for the Peng–Robinson equation, as read from a file or a preset.
///
/// Validated once into a [`PengRobinson`] by [`PengRobinson::new`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluidParameters {
    /// Critical temperature `T_c` (K).
    pub critical_temperature: f64,
    /// Critical pressure `P_c` (Pa).
    pub critical_pressure: f64,
    /// Acentric factor `ω` (-).
    pub acentric_factor: f64,
    /// Molar mass `w` (kg/kmol).
    pub molar_mass: f64,
    /// The c1, c2, c3 of the alpha extension β(T), A-Eq. 22 (zeros give the original equation).
    #[serde(default)]
    pub alpha_extension: [f64; 3],
    /// Péneloux volume shift `s` (m³/kmol), A-Eq. 23: `V_corr = V + s` (negative for water).
    #[serde(default)]
    pub volume_shift: f64,
}

/// Which form of the equation a preset uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Model {
    /// The plain Peng–Robinson equation: no volume correction, c1 = c2 = c3 = 0.
    Pr,
    /// Paper A's model: Peng–Robinson with the liquid (water) volume correction
    /// s = −0.0034 m³/kmol; the gas (air) is uncorrected.
    PrCorrected,
}

impl FluidParameters {
    /// Water, paper A Table 1 (T_c = 647.096 K, P_c = 22.064 MPa, ω = 0.344,
    /// w = 18.01528 kg/kmol), with the volume shift of the chosen model.
    pub fn water(model: Model) -> Self {
        Self {
            critical_temperature: 647.096,
            critical_pressure: 22.064e6,
            acentric_factor: 0.344,
            molar_mass: 18.01528,
            alpha_extension: [0.0; 3],
            volume_shift: match model {
                Model::Pr => 0.0,
                Model::PrCorrected => WATER_VOLUME_SHIFT,
            },
        }
    }

    /// Air, paper A Table 1 (T_c = 132.63 K, P_c = 3.786 MPa, ω = 0.035, w = 28.9647 kg/kmol).
    /// The gas phase is never volume-corrected (s = 0 in both models).
    pub fn air() -> Self {
        Self {
            critical_temperature: 132.63,
            critical_pressure: 3.786e6,
            acentric_factor: 0.035,
            molar_mass: 28.9647,
            alpha_extension: [0.0; 3],
            volume_shift: 0.0,
        }
    }
}

/// A validated Peng–Robinson fluid: constants of A-Eqs. 18, 20, 21 precomputed.
///
/// Densities are mass densities (kg/m³); the cubic works in the equation's own molar volume
/// `V` (m³/kmol), related to the (corrected) density by A-Eq. 28: `V = w/ρ − s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PengRobinson {
    params: FluidParameters,
    /// a_c, A-Eq. 20 (Pa·(m³/kmol)²).
    critical_attraction: f64,
    /// b, A-Eq. 21 (m³/kmol).
    covolume: f64,
    /// n, A-Eq. 18 (-).
    kappa: f64,
    /// 1/T_c (1/K).
    inv_critical_temperature: f64,
}

/// Molar volume (m³/kmol) above which A-Eq. 16 is evaluated in the inverse molar volume
/// `u = 1/V` ([`PengRobinson::dilute`]): the form in `V` squares and cubes it (`V⁶` in ∂P/∂V)
/// and divides by `ρ²`, which overflow or underflow for very dilute states (`V` ≳ 1e51, or
/// `ρ` subnormal, where `w/ρ` itself is infinite). Below it the `V` form is used, bit for bit as
/// before; at it both agree to round-off (`b/V` < 1e-31).
const DILUTE_MOLAR_VOLUME: f64 = 1e30;

/// Pressure (Pa) below which [`PengRobinson::density`] does not solve the cubic in `Z`: its
/// coefficients `AB`, `B²`, `B³` scale as `P²` and lose their digits to underflow below about
/// 1e-144 Pa (the liquid root then comes out as the vapour's). Below this pressure a root differs
/// from its `P → 0` limit by a relative `P/K` < 1e-100 (`K` the bulk modulus), far below round-off,
/// so the limits are used ([`PengRobinson::low_pressure_density`]).
const LOW_PRESSURE: f64 = 1e-100;

/// `value` if finite, else [`EosError::Unrepresentable`] naming it and the state.
#[inline]
fn representable(
    quantity: &'static str,
    value: f64,
    temperature: f64,
    input: &'static str,
    input_value: f64,
) -> Result<f64, EosError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(EosError::Unrepresentable {
            quantity,
            value,
            temperature,
            input,
            input_value,
        })
    }
}

/// Checks that `value` is finite and satisfies `ok`, else an `InvalidParameter` error.
fn parameter(
    parameter: &'static str,
    value: f64,
    ok: bool,
    allowed: &'static str,
) -> Result<f64, EosError> {
    if value.is_finite() && ok {
        Ok(value)
    } else {
        Err(EosError::InvalidParameter {
            parameter,
            value,
            allowed,
        })
    }
}

/// Checks that an input state variable is finite and positive.
#[inline]
fn check_positive_input(
    quantity: &'static str,
    allowed: &'static str,
    value: f64,
) -> Result<f64, EosError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(EosError::InvalidInput {
            quantity,
            value,
            allowed,
        })
    }
}

/// Checks a temperature (K): finite and positive.
#[inline]
pub(crate) fn check_temperature(temperature: f64) -> Result<f64, EosError> {
    check_positive_input("temperature", "(0, inf) K", temperature)
}

/// Checks a density (kg/m³): finite and positive.
#[inline]
pub(crate) fn check_density(density: f64) -> Result<f64, EosError> {
    check_positive_input("density", "(0, inf) kg/m³", density)
}

/// Checks a pressure (Pa): finite and positive.
#[inline]
pub(crate) fn check_pressure(pressure: f64) -> Result<f64, EosError> {
    check_positive_input("pressure", "(0, inf) Pa", pressure)
}

impl PengRobinson {
    /// Validates the parameters and precomputes the constants of A-Eqs. 18, 20 and 21.
    ///
    /// Requires `T_c > 0`, `P_c > 0`, `w > 0`, finite ω and c1..c3, and a volume shift with
    /// `b + s > 0` (otherwise the corrected molar volume `V + s` could vanish on the liquid
    /// branch and the density would be unbounded).
    pub fn new(params: FluidParameters) -> Result<Self, EosError> {
        let tc = params.critical_temperature;
        let pc = params.critical_pressure;
        parameter("critical_temperature", tc, tc > 0.0, "(0, inf) K")?;
        parameter("critical_pressure", pc, pc > 0.0, "(0, inf) Pa")?;
        parameter(
            "molar_mass",
            params.molar_mass,
            params.molar_mass > 0.0,
            "(0, inf) kg/kmol",
        )?;
        let omega = parameter("acentric_factor", params.acentric_factor, true, "finite")?;
        for c in params.alpha_extension {
            parameter("alpha_extension", c, true, "finite")?;
        }
        let covolume = OMEGA_B * GAS_CONSTANT * tc / pc;
        let s = params.volume_shift;
        parameter(
            "volume_shift",
            s,
            covolume + s > 0.0,
            "finite with b + s > 0 (b = 0.07780 R T_c / P_c)",
        )?;
        Ok(Self {
            params,
            critical_attraction: OMEGA_A * GAS_CONSTANT * GAS_CONSTANT * tc * tc / pc,
            covolume,
            kappa: 0.37464 + 1.54226 * omega - 0.26992 * omega * omega,
            inv_critical_temperature: 1.0 / tc,
        })
    }

    /// Water of paper A Table 1 in the chosen model.
    pub fn water(model: Model) -> Self {
        // The preset is valid by construction (checked by a unit test); build it directly so
        // that no fallible call is needed.
        Self::from_valid(FluidParameters::water(model))
    }

    /// Air of paper A Table 1.
    pub fn air() -> Self {
        Self::from_valid(FluidParameters::air())
    }

    fn from_valid(params: FluidParameters) -> Self {
        let tc = params.critical_temperature;
        let pc = params.critical_pressure;
        let omega = params.acentric_factor;
        Self {
            params,
            critical_attraction: OMEGA_A * GAS_CONSTANT * GAS_CONSTANT * tc * tc / pc,
            covolume: OMEGA_B * GAS_CONSTANT * tc / pc,
            kappa: 0.37464 + 1.54226 * omega - 0.26992 * omega * omega,
            inv_critical_temperature: 1.0 / tc,
        }
    }

    /// The parameters this fluid was built from.
    pub fn parameters(&self) -> &FluidParameters {
        &self.params
    }

    /// Co-volume `b`, A-Eq. 21 (m³/kmol).
    pub fn covolume(&self) -> f64 {
        self.covolume
    }

    /// Molar mass `w` (kg/kmol).
    pub fn molar_mass(&self) -> f64 {
        self.params.molar_mass
    }

    /// Volume shift `s` (m³/kmol).
    pub fn volume_shift(&self) -> f64 {
        self.params.volume_shift
    }

    /// Attraction `a(T)` (A-Eqs. 17, 19, 20, 22) and its temperature derivative `da/dT`.
    ///
    /// `a = a_c · β(T) · [1 + n(1 − √T_r)]²`, with
    /// `β = [1 + c1 u + c2 u² + c3 u³]²`, `u = 1 − √T_r`.
    #[inline]
    pub fn attraction_and_derivative(&self, temperature: f64) -> (f64, f64) {
        let sqrt_tr = (temperature * self.inv_critical_temperature).sqrt();
        let u = 1.0 - sqrt_tr;
        // du/dT = −1 / (2 √(T T_c)) = −√T_r / (2 T).
        let du_dt = -0.5 * sqrt_tr / temperature;
        let soave = 1.0 + self.kappa * u;
        let [c1, c2, c3] = self.params.alpha_extension;
        let poly = 1.0 + u * (c1 + u * (c2 + u * c3));
        let dpoly_du = c1 + u * (2.0 * c2 + 3.0 * c3 * u);
        let beta = poly * poly;
        let kappa_term = soave * soave;
        let a = self.critical_attraction * beta * kappa_term;
        let da_du =
            self.critical_attraction * 2.0 * poly * soave * (dpoly_du * soave + poly * self.kappa);
        (a, da_du * du_dt)
    }

    /// Attraction `a(T)` alone (Pa·(m³/kmol)²).
    #[inline]
    pub fn attraction(&self, temperature: f64) -> f64 {
        let sqrt_tr = (temperature * self.inv_critical_temperature).sqrt();
        let u = 1.0 - sqrt_tr;
        let soave = 1.0 + self.kappa * u;
        let [c1, c2, c3] = self.params.alpha_extension;
        let poly = 1.0 + u * (c1 + u * (c2 + u * c3));
        self.critical_attraction * (poly * soave) * (poly * soave)
    }

    /// The equation's molar volume `V = w/ρ − s` (A-Eq. 28), checked against the co-volume.
    #[inline]
    pub fn molar_volume(&self, density: f64) -> Result<f64, EosError> {
        let v = self.params.molar_mass / density - self.params.volume_shift;
        if v > self.covolume {
            Ok(v)
        } else {
            Err(EosError::BelowCovolume {
                molar_volume: v,
                density,
                covolume: self.covolume,
                max_density: self.max_density_value(),
            })
        }
    }

    #[inline]
    fn max_density_value(&self) -> f64 {
        self.params.molar_mass / (self.covolume + self.params.volume_shift)
    }

    /// A-Eq. 16 in the inverse molar volume `u = 1/V = ρ/(w − sρ)` for a dilute state
    /// (`V` ≥ [`DILUTE_MOLAR_VOLUME`]): `P = u [RT/(1 − x) − a u/q]` with `x = bu`,
    /// `q = 1 + 2x − x²`, and `∂P/∂ρ = [RT/(1 − x)² − 2au(1 + x)/q²] · w/(w − sρ)²`. Nothing
    /// here squares a large number, so the pressure of a trace of gas is its (tiny) finite value,
    /// `≈ ρRT/w`, not `∞ − ∞`. Returns (P, ∂P/∂ρ).
    #[inline]
    fn dilute(&self, temperature: f64, density: f64) -> (f64, f64) {
        let w_eff = self.params.molar_mass - self.params.volume_shift * density;
        let u = density / w_eff;
        let x = self.covolume * u;
        let q = 1.0 + 2.0 * x - x * x;
        let rt = GAS_CONSTANT * temperature;
        let a = self.attraction(temperature);
        let p = u * (rt / (1.0 - x) - a * u / q);
        let dp_du = rt / ((1.0 - x) * (1.0 - x)) - 2.0 * a * u * (1.0 + x) / (q * q);
        let du_drho = self.params.molar_mass / w_eff / w_eff;
        (p, dp_du * du_drho)
    }

    /// Pressure from A-Eq. 16 at molar volume `V > b` (not checked) (Pa).
    #[inline]
    pub fn pressure_at_molar_volume(&self, temperature: f64, molar_volume: f64) -> f64 {
        let b = self.covolume;
        let v = molar_volume;
        let vb = v - b;
        let denom = v * (v + 2.0 * b) - b * b;
        // RT/(V − b) − a/denom over one division.
        let rt = GAS_CONSTANT * temperature;
        let d = vb * denom;
        (rt * denom - self.attraction(temperature) * vb) / d
    }

    /// Pressure and `∂P/∂V` at molar volume `V > b` (not checked). The pressure is computed by
    /// exactly the expression of [`Self::pressure_at_molar_volume`], so both give the same bits.
    #[inline]
    fn pressure_and_dp_dv(&self, temperature: f64, v: f64) -> (f64, f64) {
        let b = self.covolume;
        let a = self.attraction(temperature);
        let vb = v - b;
        let denom = v * (v + 2.0 * b) - b * b;
        let rt = GAS_CONSTANT * temperature;
        let d = vb * denom;
        let p = (rt * denom - a * vb) / d;
        // −RT/(V − b)² + 2a(V + b)/denom² over one (independent) division.
        let dp_dv = (2.0 * a * (v + b) * vb * vb - rt * denom * denom) / (d * d);
        (p, dp_dv)
    }

    /// The sum of the magnitudes of the two terms of A-Eq. 16 at this state (Pa): the scale of
    /// the round-off in a computed pressure (the terms cancel in a dense liquid).
    pub fn pressure_term_scale(&self, temperature: f64, density: f64) -> Result<f64, EosError> {
        let v = self.molar_volume(density)?;
        let b = self.covolume;
        Ok(GAS_CONSTANT * temperature / (v - b)
            + self.attraction(temperature).abs() / (v * (v + 2.0 * b) - b * b))
    }

    /// The real roots above the co-volume of the cubic in `Z = PV/(RT)` at (T, P), ascending.
    ///
    /// `Z³ − (1 − B)Z² + (A − 3B² − 2B)Z − (AB − B² − B³) = 0`, `A = aP/(RT)²`, `B = bP/(RT)`
    /// (A-Eq. 16 multiplied out). Returns the roots (as molar volumes `V`, m³/kmol) and their
    /// number (1 to 3).
    pub fn molar_volume_roots(&self, temperature: f64, pressure: f64) -> ([f64; 3], usize) {
        let rt = GAS_CONSTANT * temperature;
        let big_a = self.attraction(temperature) * pressure / (rt * rt);
        let big_b = self.covolume * pressure / rt;
        let a2 = -(1.0 - big_b);
        let a1 = big_a - 3.0 * big_b * big_b - 2.0 * big_b;
        let a0 = -(big_a * big_b - big_b * big_b - big_b * big_b * big_b);
        let (roots, n) = cubic_real_roots(a2, a1, a0);
        let mut out = [0.0; 3];
        let mut k = 0;
        for &z in &roots[..n] {
            let z = polish_cubic_root(a2, a1, a0, z);
            if z > big_b {
                out[k] = z * rt / pressure;
                k += 1;
            }
        }
        (out, k)
    }

    /// Density at a pressure below [`LOW_PRESSURE`], exact to round-off: the liquid root is the
    /// smaller root of A-Eq. 16 at `P = 0`, `V² − (k − 2b)V + b(k − b) = 0` with `k = a/(RT)`
    /// (where the isotherm dips below zero; elsewhere there is no dense root and both branches
    /// take the gas), and the gas is the ideal gas `V = RT/P` (`Z − 1 = O(P)`), computed as
    /// `ρ = wP/(RT + sP)` so that a huge `V` never appears.
    fn low_pressure_density(&self, temperature: f64, pressure: f64, branch: Branch) -> f64 {
        let rt = GAS_CONSTANT * temperature;
        let (w, s, b) = (
            self.params.molar_mass,
            self.params.volume_shift,
            self.covolume,
        );
        if branch == Branch::Liquid {
            let k = self.attraction(temperature) / rt;
            let disc = k * k - 8.0 * k * b + 8.0 * b * b;
            if k > 2.0 * b && disc >= 0.0 {
                // Product of the roots b(k − b) over the larger root: no cancellation.
                let v = 2.0 * b * (k - b) / ((k - 2.0 * b) + disc.sqrt());
                if v > b && v < BRANCH_SPLIT * b {
                    return w / (v + s);
                }
            }
        }
        w * pressure / (rt + s * pressure)
    }

    /// Density on the requested branch at (T, P > 0), unchecked inputs.
    ///
    /// Same roots as [`Self::molar_volume_roots`], but only the wanted one is computed and
    /// polished: the liquid is the smallest root above `B`, the gas the largest.
    #[inline]
    fn density_unchecked(
        &self,
        temperature: f64,
        pressure: f64,
        branch: Branch,
    ) -> Result<f64, EosError> {
        if pressure < LOW_PRESSURE {
            return Ok(self.low_pressure_density(temperature, pressure, branch));
        }
        let rt = GAS_CONSTANT * temperature;
        let big_a = self.attraction(temperature) * pressure / (rt * rt);
        let big_b = self.covolume * pressure / rt;
        let a2 = -(1.0 - big_b);
        let a1 = big_a - 3.0 * big_b * big_b - 2.0 * big_b;
        let a0 = -(big_a * big_b - big_b * big_b - big_b * big_b * big_b);
        let depressed = depressed_cubic(a2, a1, a0);
        // Which side of the inflection point the wanted root lies on. With one root above B both
        // branches take the same path, so they give the same bits.
        let side = match depressed {
            Depressed::One(_) => {
                let zi = -a2 / 3.0;
                if ((zi + a2) * zi + a1) * zi + a0 < 0.0 {
                    Branch::Gas
                } else {
                    Branch::Liquid
                }
            }
            Depressed::Three { .. } => {
                // p(B) < 0 puts B left of the smallest root or between the middle and the
                // largest; left of the local maximum it is the former (three roots above B),
                // right of it only the largest root lies above B.
                // The smaller root of p' = 3Z² + 2a2 Z + a1. At low pressure it is of the order
                // of B while −a2 ≈ 1: `(−a2 − s)/3` would cancel to 0 (and send the liquid to
                // the gas root below about 0.1 Pa for water at 300 K), so it is taken as the
                // product of the roots, a1/3, over the larger one.
                let s = (a2 * a2 - 3.0 * a1).max(0.0).sqrt();
                let local_max = if -a2 + s > 0.0 {
                    a1 / (-a2 + s)
                } else {
                    (-a2 - s) / 3.0
                };
                if big_b < local_max {
                    branch
                } else {
                    Branch::Gas
                }
            }
        };
        // Fast path: Newton from a bound on that side, monotone where the cubic keeps its
        // curvature; the closed form otherwise.
        // Between about 1e-10 and 1 Pa (water at 300 K) the liquid and middle roots are too
        // close to each other, against the closed form's shift −a2/3 ≈ 1/3, for `depressed` to
        // resolve: it sees one root where there are three. Newton from B on the liquid side finds
        // the smallest root if one lies left of the inflection and returns `None` otherwise (the
        // cubic is negative there), so the liquid is tried that way first; with a single root
        // right of the inflection both branches still take the gas path, bit for bit.
        let liquid_first = match (branch, side, depressed) {
            (Branch::Liquid, Branch::Gas, Depressed::One(_)) => {
                monotone_newton(a2, a1, a0, big_b, Branch::Liquid)
            }
            _ => None,
        };
        let z = liquid_first
            .or_else(|| monotone_newton(a2, a1, a0, big_b, side))
            .or_else(|| match depressed {
                Depressed::One(t) => Some(polish_cubic_root(a2, a1, a0, t - a2 / 3.0)),
                Depressed::Three { r, phi } => {
                    let shift = a2 / 3.0;
                    let root = |offset: f64| {
                        polish_cubic_root(a2, a1, a0, 2.0 * r * (phi + offset).cos() - shift)
                    };
                    match branch {
                        // Smallest, then middle, then largest: the first above B.
                        Branch::Liquid => [TWO_PI_3, -TWO_PI_3, 0.0]
                            .into_iter()
                            .map(root)
                            .find(|&z| z > big_b),
                        Branch::Gas => Some(root(0.0)),
                    }
                }
            });
        match z {
            Some(z) if z > big_b => {
                let v = z * rt / pressure;
                Ok(if v.is_finite() {
                    self.params.molar_mass / (v + self.params.volume_shift)
                } else {
                    // V = ZRT/P overflowed (P tiny against T): ρ = wP/(ZRT + sP).
                    self.params.molar_mass * pressure
                        / (z * rt + self.params.volume_shift * pressure)
                })
            }
            _ => Err(EosError::NoRoot {
                temperature,
                pressure,
            }),
        }
    }
}

/// Newton's method on the cubic in Z from a bound on the wanted side of the wanted root, used
/// only where it is monotone.
///
/// The cubic `p(Z)` has `p(B) = −2B² < 0`, and its largest root is at most `1 + B` (from
/// A-Eq. 16, `P ≤ RT/(V − b)`), where `p ≥ 0`. Left of the inflection point `Z_i = −a2/3` the
/// cubic is concave: from `Z = B` with `p'(B) > 0`, Newton's iterates rise monotonically to the
/// smallest root above B (the liquid). Right of it the cubic is convex: from `1 + B`, they fall
/// monotonically to the largest root (the gas). If an iterate would cross `Z_i` the wanted root
/// is on the other side of the inflection and `None` sends the caller to the closed form.
#[inline]
fn monotone_newton(a2: f64, a1: f64, a0: f64, big_b: f64, branch: Branch) -> Option<f64> {
    let inflection = -a2 / 3.0;
    let mut z = match branch {
        Branch::Liquid => big_b,
        Branch::Gas => 1.0 + big_b,
    };
    let on_side = |z: f64| match branch {
        Branch::Liquid => z < inflection,
        Branch::Gas => z > inflection,
    };
    if !on_side(z) {
        return None;
    }
    for _ in 0..MAX_NEWTON {
        let f = ((z + a2) * z + a1) * z + a0;
        let df = (3.0 * z + 2.0 * a2) * z + a1;
        if df <= 0.0 {
            return None;
        }
        let step = f / df;
        let next = z - step;
        if !on_side(next) {
            return None;
        }
        // Monotone: the step points towards the root; a step that does not (round-off at the
        // root) or that is at the round-off of z ends the iteration.
        let towards = match branch {
            Branch::Liquid => step <= 0.0,
            Branch::Gas => step >= 0.0,
        };
        if !towards || step.abs() <= 2.0 * f64::EPSILON * z {
            return Some(if towards { next } else { z });
        }
        z = next;
    }
    None
}

/// Iteration limit of [`monotone_newton`] (it needs fewer than 10 away from a spinodal).
const MAX_NEWTON: usize = 40;

/// 2π/3.
const TWO_PI_3: f64 = 2.0 * std::f64::consts::PI / 3.0;

/// The real roots of a depressed cubic `t³ + p t + q = 0` (with `x = t − a2/3`).
#[derive(Debug, Clone, Copy)]
enum Depressed {
    /// One real root `t`.
    One(f64),
    /// Three real roots `t_k = 2r cos(φ − 2πk/3)`: k = 0 largest, `φ + 2π/3` smallest.
    Three { r: f64, phi: f64 },
}

#[inline]
fn depressed_cubic(a2: f64, a1: f64, a0: f64) -> Depressed {
    let shift = a2 / 3.0;
    let p = a1 - a2 * shift;
    let q = (2.0 * shift * shift - a1) * shift + a0;
    let half_q = 0.5 * q;
    let third_p = p / 3.0;
    let disc = half_q * half_q + third_p * third_p * third_p;
    if disc > 0.0 || third_p >= 0.0 {
        // t = u − (p/3)/u, u = cbrt(−q/2 ∓ √disc) with the sign that avoids cancellation.
        let sq = disc.max(0.0).sqrt();
        let u = if half_q > 0.0 {
            (-half_q - sq).cbrt()
        } else {
            (-half_q + sq).cbrt()
        };
        Depressed::One(if u != 0.0 { u - third_p / u } else { 0.0 })
    } else {
        let r = (-third_p).sqrt();
        let cos_arg = (-half_q / (r * r * r)).clamp(-1.0, 1.0);
        Depressed::Three {
            r,
            phi: cos_arg.acos() / 3.0,
        }
    }
}

/// Real roots of `x³ + a2 x² + a1 x + a0 = 0`, ascending, and their number (1 or 3).
///
/// Trigonometric form for three real roots, Cardano's with the cancellation-free choice of sign
/// for one. Double roots are returned twice.
#[inline]
pub(crate) fn cubic_real_roots(a2: f64, a1: f64, a0: f64) -> ([f64; 3], usize) {
    let shift = a2 / 3.0;
    match depressed_cubic(a2, a1, a0) {
        Depressed::One(t) => ([t - shift; 3], 1),
        Depressed::Three { r, phi } => {
            let root = |offset: f64| 2.0 * r * (phi + offset).cos() - shift;
            ([root(TWO_PI_3), root(-TWO_PI_3), root(0.0)], 3)
        }
    }
}

/// Two Newton steps on the cubic, keeping the root if a step would not improve it.
#[inline]
fn polish_cubic_root(a2: f64, a1: f64, a0: f64, mut x: f64) -> f64 {
    for _ in 0..2 {
        let f = ((x + a2) * x + a1) * x + a0;
        let df = (3.0 * x + 2.0 * a2) * x + a1;
        if df == 0.0 || f == 0.0 {
            break;
        }
        let next = x - f / df;
        if !next.is_finite() {
            break;
        }
        let fnext = ((next + a2) * next + a1) * next + a0;
        if fnext.abs() >= f.abs() {
            break;
        }
        x = next;
    }
    x
}

impl EquationOfState for PengRobinson {
    #[inline]
    fn pressure(&self, temperature: f64, density: f64) -> Result<f64, EosError> {
        let t = check_temperature(temperature)?;
        let rho = check_density(density)?;
        let v = self.molar_volume(rho)?;
        let p = if v < DILUTE_MOLAR_VOLUME {
            self.pressure_at_molar_volume(t, v)
        } else {
            self.dilute(t, rho).0
        };
        representable("pressure", p, t, "density", rho)
    }

    fn density(&self, temperature: f64, pressure: f64, branch: Branch) -> Result<f64, EosError> {
        let t = check_temperature(temperature)?;
        let p = check_pressure(pressure)?;
        let rho = self.density_unchecked(t, p, branch)?;
        // A density that overflowed, or underflowed to zero (a gas at a pressure so low, or a
        // temperature so high, that ρ = Pw/(ZRT) is below the smallest double), is no state.
        if rho > 0.0 {
            representable("density", rho, t, "pressure", p)
        } else {
            Err(EosError::Unrepresentable {
                quantity: "density",
                value: rho,
                temperature: t,
                input: "pressure",
                input_value: p,
            })
        }
    }

    #[inline]
    fn dp_drho(&self, temperature: f64, density: f64) -> Result<f64, EosError> {
        Ok(self.pressure_and_dp_drho(temperature, density)?.1)
    }

    #[inline]
    fn pressure_and_dp_drho(&self, temperature: f64, density: f64) -> Result<(f64, f64), EosError> {
        let t = check_temperature(temperature)?;
        let rho = check_density(density)?;
        let v = self.molar_volume(rho)?;
        let (p, dp_drho) = if v < DILUTE_MOLAR_VOLUME {
            let (p, dp_dv) = self.pressure_and_dp_dv(t, v);
            // dV/dρ = −w/ρ² (A-Eq. 28 with constant s).
            (p, -dp_dv * self.params.molar_mass / (rho * rho))
        } else {
            self.dilute(t, rho)
        };
        Ok((
            representable("pressure", p, t, "density", rho)?,
            representable("dP/drho", dp_drho, t, "density", rho)?,
        ))
    }

    fn dp_dt(&self, temperature: f64, density: f64) -> Result<f64, EosError> {
        let t = check_temperature(temperature)?;
        let rho = check_density(density)?;
        let v = self.molar_volume(rho)?;
        let b = self.covolume;
        let (_, da_dt) = self.attraction_and_derivative(t);
        let dp_dt = if v < DILUTE_MOLAR_VOLUME {
            GAS_CONSTANT / (v - b) - da_dt / (v * (v + 2.0 * b) - b * b)
        } else {
            // In u = 1/V, as in `dilute`: R u/(1 − x) − (da/dT) u²/q.
            let u = rho / (self.params.molar_mass - self.params.volume_shift * rho);
            let x = b * u;
            GAS_CONSTANT * u / (1.0 - x) - da_dt * u * u / (1.0 + 2.0 * x - x * x)
        };
        representable("dP/dT", dp_dt, t, "density", rho)
    }

    #[inline]
    fn on_branch(&self, temperature: f64, density: f64, branch: Branch) -> Result<bool, EosError> {
        let t = check_temperature(temperature)?;
        let v = self.molar_volume(check_density(density)?)?;
        let theta = 2.0 * self.attraction(t) / (GAS_CONSTANT * t * self.covolume);
        if theta <= CRITICAL_THETA {
            return Ok(true);
        }
        let x = v / self.covolume;
        Ok(match branch {
            Branch::Liquid => x < BRANCH_SPLIT,
            Branch::Gas => x > BRANCH_SPLIT,
        })
    }

    fn max_density(&self, _temperature: f64) -> f64 {
        self.max_density_value()
    }

    fn molar_mass(&self) -> f64 {
        self.params.molar_mass
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate() {
        for p in [
            FluidParameters::water(Model::Pr),
            FluidParameters::water(Model::PrCorrected),
            FluidParameters::air(),
        ] {
            assert_eq!(PengRobinson::new(p), Ok(PengRobinson::from_valid(p)));
        }
    }

    #[test]
    fn cubic_roots_of_known_polynomials() {
        // (x − 1)(x − 2)(x − 3) = x³ − 6x² + 11x − 6.
        let (r, n) = cubic_real_roots(-6.0, 11.0, -6.0);
        assert_eq!(n, 3);
        for (got, want) in r.iter().zip([1.0, 2.0, 3.0]) {
            assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        }
        // (x − 2)(x² + 1) = x³ − 2x² + x − 2: one real root.
        let (r, n) = cubic_real_roots(-2.0, 1.0, -2.0);
        assert_eq!(n, 1);
        assert!((r[0] - 2.0).abs() < 1e-12);
    }

    #[test]
    fn branch_split_is_the_minimum_of_l() {
        let l = |x: f64| (x * x + 2.0 * x - 1.0).powi(2) / ((x + 1.0) * (x - 1.0).powi(2));
        let h = 1e-5;
        let slope = (l(BRANCH_SPLIT + h) - l(BRANCH_SPLIT - h)) / (2.0 * h);
        assert!(slope.abs() < 1e-8, "dL/dx at x_m = {slope}");
        assert!(
            l(BRANCH_SPLIT + 1e-3) > l(BRANCH_SPLIT) && l(BRANCH_SPLIT - 1e-3) > l(BRANCH_SPLIT)
        );
        assert!((l(BRANCH_SPLIT) / CRITICAL_THETA - 1.0).abs() < 1e-14);
    }

    #[test]
    fn bad_parameters_are_typed_errors() {
        let mut p = FluidParameters::water(Model::Pr);
        p.critical_pressure = -1.0;
        assert!(matches!(
            PengRobinson::new(p),
            Err(EosError::InvalidParameter {
                parameter: "critical_pressure",
                ..
            })
        ));
        let mut p = FluidParameters::water(Model::Pr);
        p.volume_shift = -1.0;
        assert!(matches!(
            PengRobinson::new(p),
            Err(EosError::InvalidParameter {
                parameter: "volume_shift",
                ..
            })
        ));
        let mut p = FluidParameters::air();
        p.alpha_extension[1] = f64::NAN;
        assert!(matches!(
            PengRobinson::new(p),
            Err(EosError::InvalidParameter {
                parameter: "alpha_extension",
                ..
            })
        ));
    }

    /// The fuzz finding `eos_state/crash-23dd…`: T = 4.1e-314 K, ρ = 5.2e-315 kg/m³ (both
    /// subnormal). `w/ρ` is infinite there and the form in V gave ∞ − ∞ = NaN; the dilute form
    /// gives the pressure, which underflows to a signed zero, and finite derivatives.
    #[test]
    fn subnormal_state_is_finite_not_nan() {
        let t = f64::from_le_bytes([0xcd, 0x83, 0x0d, 0xf4, 0x01, 0, 0, 0]);
        let rho = f64::from_le_bytes([0xf5, 0x21, 0x94, 0x3e, 0, 0, 0, 0]);
        assert!(t > 0.0 && !t.is_normal() && rho > 0.0 && !rho.is_normal());
        for eos in [
            PengRobinson::water(Model::Pr),
            PengRobinson::water(Model::PrCorrected),
            PengRobinson::air(),
        ] {
            let p = eos.pressure(t, rho).unwrap();
            assert!(p.is_finite() && p.abs() < 1e-300, "{p}");
            let (p2, dp) = eos.pressure_and_dp_drho(t, rho).unwrap();
            assert_eq!(p.to_bits(), p2.to_bits());
            assert!(dp.is_finite());
            assert!(eos.dp_dt(t, rho).unwrap().is_finite());
        }
    }

    /// A trace of gas: A-Eq. 16 in 1/V is the ideal gas to round-off, and it meets the form in
    /// V at the switch.
    #[test]
    fn dilute_pressure_is_the_ideal_gas_and_continuous() {
        let air = PengRobinson::air();
        let w = air.molar_mass();
        for rho in [1e-30, 1e-100, 1e-242, 1e-310] {
            let p = air.pressure(300.0, rho).unwrap();
            let ideal = rho * GAS_CONSTANT * 300.0 / w;
            assert!((p / ideal - 1.0).abs() < 1e-12, "ρ = {rho}: {p} vs {ideal}");
            let dp = air.dp_drho(300.0, rho).unwrap();
            assert!(
                (dp / (GAS_CONSTANT * 300.0 / w) - 1.0).abs() < 1e-12,
                "{dp}"
            );
        }
        // Either side of V = DILUTE_MOLAR_VOLUME.
        for eos in [PengRobinson::water(Model::PrCorrected), air] {
            let rho_switch = eos.molar_mass() / (DILUTE_MOLAR_VOLUME + eos.volume_shift());
            let below = eos.pressure(650.0, rho_switch * (1.0 + 1e-9)).unwrap();
            let above = eos.pressure(650.0, rho_switch * (1.0 - 1e-9)).unwrap();
            assert!((below / above - 1.0).abs() < 3e-9, "{below} vs {above}");
            let dt_below = eos.dp_dt(650.0, rho_switch * (1.0 + 1e-9)).unwrap();
            let dt_above = eos.dp_dt(650.0, rho_switch * (1.0 - 1e-9)).unwrap();
            assert!((dt_below / dt_above - 1.0).abs() < 3e-9);
        }
    }

    /// What cannot be represented is a typed error naming the quantity, not NaN or ∞.
    #[test]
    fn overflow_is_a_typed_error() {
        let water = PengRobinson::water(Model::PrCorrected);
        match water.pressure(f64::MAX, 1.0) {
            Err(EosError::Unrepresentable {
                quantity: "pressure",
                input: "density",
                value,
                ..
            }) => assert!(!value.is_finite()),
            other => panic!("{other:?}"),
        }
        // ρ = Pw/(RT) below the smallest double.
        match PengRobinson::air().density(1e300, 1e-300, Branch::Gas) {
            Err(EosError::Unrepresentable {
                quantity: "density",
                input: "pressure",
                value,
                ..
            }) => assert_eq!(value, 0.0),
            other => panic!("{other:?}"),
        }
        let e = water.pressure(f64::MAX, 1.0).unwrap_err().to_string();
        assert!(e.contains("pressure") && e.contains("density = 1"), "{e}");
    }

    /// The liquid root at low pressure: it tends to its P → 0 limit (the smaller root of the
    /// quadratic at P = 0), instead of jumping to the vapour's root below about 0.1 Pa.
    #[test]
    fn liquid_at_low_pressure_stays_liquid() {
        for model in [Model::Pr, Model::PrCorrected] {
            let water = PengRobinson::water(model);
            let at_10_pa = water.density(300.0, 10.0, Branch::Liquid).unwrap();
            for e in -300..=0 {
                let p = 10f64.powi(e);
                let rho = water.density(300.0, p, Branch::Liquid).unwrap();
                assert!(
                    (rho / at_10_pa - 1.0).abs() < 1e-8,
                    "{model:?}, P = {p}: ρ = {rho}, {at_10_pa} at 10 Pa"
                );
                assert!(water.on_branch(300.0, rho, Branch::Liquid).unwrap());
                let gas = water.density(300.0, p, Branch::Gas).unwrap();
                let ideal = p * water.molar_mass() / (GAS_CONSTANT * 300.0);
                assert!((gas / ideal - 1.0).abs() < 1e-6, "P = {p}: gas {gas}");
            }
            // Continuous across LOW_PRESSURE.
            let below = water.density(300.0, LOW_PRESSURE * 0.999, Branch::Liquid);
            let above = water.density(300.0, LOW_PRESSURE * 1.001, Branch::Liquid);
            assert!((below.unwrap() / above.unwrap() - 1.0).abs() < 1e-14);
        }
        // Above the temperature where the isotherm stays positive there is no dense root at
        // P → 0: both branches give the gas.
        let air = PengRobinson::air();
        assert_eq!(
            air.density(300.0, 1e-200, Branch::Liquid),
            air.density(300.0, 1e-200, Branch::Gas)
        );
    }
}
