//! Closed-form solutions of the TM-MPM problems of Zhao et al. (2022), in the default build
//! because scenarios compare with them as they run: the complementary error function, the
//! temperature of the semi-infinite bar (B-Eq. 52), of the slab heated on one side and
//! insulated on the other, and of the heated square (B-Eq. 59, with the exponent corrected
//! to `π²((2m+1)² + (2n+1)²) κ t/L²`).

use std::f64::consts::PI;

/// `erfc(x)` to about 1e-14 relative: Taylor series of erf for |x| < 2.5, Lentz's continued
/// fraction beyond.
pub fn erfc(x: f64) -> f64 {
    if x < 0.0 {
        return 2.0 - erfc(-x);
    }
    if x < 2.5 {
        // erf(x) = 2/√π Σ (−1)^n x^(2n+1) / (n! (2n+1))
        let x2 = x * x;
        let mut term = x;
        let mut sum = x;
        let mut n = 0.0;
        loop {
            n += 1.0;
            term *= -x2 / n;
            let t = term / (2.0 * n + 1.0);
            sum += t;
            if t.abs() <= 1e-17 * sum.abs() {
                break;
            }
        }
        1.0 - 2.0 / PI.sqrt() * sum
    } else {
        // erfc(x) = exp(−x²)/√π · 1/(x + 1/2/(x + 1/(x + 3/2/(x + ...))))
        let tiny = 1e-300;
        let mut f = x;
        let mut c = x;
        let mut d = 0.0;
        for k in 1..200 {
            let a = k as f64 * 0.5;
            d = x + a * d;
            d = if d.abs() < tiny { tiny } else { d };
            c = x + a / c;
            c = if c.abs() < tiny { tiny } else { c };
            d = 1.0 / d;
            let delta = c * d;
            f *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (-x * x).exp() / (PI.sqrt() * f)
    }
}

/// B-Eq. 52: temperature of the semi-infinite bar heated at `x = 0` from `t0` to `t1`.
pub fn semi_infinite_temperature(x: f64, t: f64, diffusivity: f64, t0: f64, t1: f64) -> f64 {
    if t <= 0.0 {
        return if x <= 0.0 { t1 } else { t0 };
    }
    erfc(x / (2.0 * (diffusivity * t).sqrt())) * (t1 - t0) + t0
}

/// Dimensionless 1D profile `θ(ξ, t)` on `0 ≤ ξ ≤ L` with `θ(0) = 0`, `∂θ/∂ξ(L) = 0`,
/// `θ(ξ, 0) = 1`: `θ = Σ_n 4/((2n+1)π) sin(λ_n ξ) exp(−λ_n² α t)`, `λ_n = (2n+1)π/(2L)`.
pub fn heated_insulated_profile(xi: f64, length: f64, diffusivity: f64, t: f64) -> f64 {
    let mut s = 0.0;
    for n in 0..2000 {
        let k = (2 * n + 1) as f64;
        let lam = k * PI / (2.0 * length);
        let e = (-lam * lam * diffusivity * t).exp();
        s += 4.0 / (k * PI) * (lam * xi).sin() * e;
        if e < 1e-18 {
            break;
        }
    }
    s
}

/// B-Eq. 59 with the exponent read as `π² ((2m+1)² + (2n+1)²) k t / (L² ρ c)`: temperature
/// of the square `[0, L]²` at `t0` whose sides are held at `t1` from `t = 0`.
pub fn heated_square_temperature(
    x: f64,
    y: f64,
    length: f64,
    diffusivity: f64,
    t: f64,
    t0: f64,
    t1: f64,
) -> f64 {
    let mut s = 0.0;
    for m in 0..400 {
        let a = (2 * m + 1) as f64;
        let em = (-PI * PI * a * a * diffusivity * t / (length * length)).exp();
        if em < 1e-18 {
            break;
        }
        for n in 0..400 {
            let b = (2 * n + 1) as f64;
            let e = em * (-PI * PI * b * b * diffusivity * t / (length * length)).exp();
            if e < 1e-18 {
                break;
            }
            s += e / (a * b) * (a * PI * x / length).sin() * (b * PI * y / length).sin();
        }
    }
    t1 - 16.0 * (t1 - t0) / (PI * PI) * s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// erfc against tabulated values (Abramowitz and Stegun, Table 7.1).
    #[test]
    fn erfc_matches_tables() {
        let table = [
            (0.0, 1.0),
            (0.5, 0.479_500_122_186_953_5),
            (1.0, 0.157_299_207_050_285_13),
            (2.0, 0.004_677_734_981_047_266),
            (3.0, 2.209_049_699_858_544e-5),
            (5.0, 1.537_459_794_428_035e-12),
        ];
        for (x, e) in table {
            assert!(
                (erfc(x) - e).abs() <= 1e-13 * e.max(1e-300) + 1e-16,
                "erfc({x})"
            );
        }
    }

    /// The square series satisfies the boundary value and the initial value (away from the
    /// edges) and approaches the boundary value at late time.
    #[test]
    fn square_series_limits() {
        let f = |x, y, t| heated_square_temperature(x, y, 1.0, 0.1, t, 0.0, 100.0);
        assert!((f(0.0, 0.5, 0.3) - 100.0).abs() < 1e-9);
        assert!(f(0.5, 0.5, 1e-4).abs() < 1e-6);
        assert!((f(0.5, 0.5, 20.0) - 100.0).abs() < 1e-3);
    }
}
