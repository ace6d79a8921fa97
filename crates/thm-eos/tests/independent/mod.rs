//! An independent Peng–Robinson implementation, written from A-Eqs. 16–21, 23, 27–28 alone.
//!
//! It shares no code with `thm-eos` and uses a different method: molar volumes are found by
//! scanning `P(V) − P` on a geometric grid of `V − b` and bisecting every sign change to the last
//! bit, instead of solving the cubic in closed form. Only c1 = c2 = c3 = 0 (both models of the
//! paper) is covered.
#![allow(dead_code)]

pub const R: f64 = 8314.4598;

#[derive(Debug, Clone, Copy)]
pub struct Fluid {
    pub tc: f64,
    pub pc: f64,
    pub omega: f64,
    pub w: f64,
    pub s: f64,
}

pub const WATER_PR: Fluid = Fluid {
    tc: 647.096,
    pc: 22.064e6,
    omega: 0.344,
    w: 18.01528,
    s: 0.0,
};
pub const WATER_PR_CORRECTED: Fluid = Fluid {
    s: -0.0034,
    ..WATER_PR
};
pub const AIR: Fluid = Fluid {
    tc: 132.63,
    pc: 3.786e6,
    omega: 0.035,
    w: 28.9647,
    s: 0.0,
};

impl Fluid {
    pub fn b(&self) -> f64 {
        0.07780 * R * self.tc / self.pc
    }

    pub fn a(&self, t: f64) -> f64 {
        let n = 0.37464 + 1.54226 * self.omega - 0.26992 * self.omega.powi(2);
        let ac = 0.457247 * (R * self.tc).powi(2) / self.pc;
        ac * (1.0 + n * (1.0 - (t / self.tc).sqrt())).powi(2)
    }

    /// A-Eq. 16.
    pub fn p_of_v(&self, t: f64, v: f64) -> f64 {
        let b = self.b();
        R * t / (v - b) - self.a(t) / (v * v + 2.0 * b * v - b * b)
    }

    /// Pressure at density: the cubic's molar volume is `w/ρ − s` (A-Eq. 28).
    pub fn pressure(&self, t: f64, rho: f64) -> f64 {
        self.p_of_v(t, self.w / rho - self.s)
    }

    /// All molar volumes above b with `P(V) = p`, ascending.
    pub fn roots(&self, t: f64, p: f64) -> Vec<f64> {
        let b = self.b();
        let g = |v: f64| self.p_of_v(t, v) - p;
        let n = 20_000;
        let (lo_exp, hi_exp) = (-12.0f64, 10.0f64);
        let v_at =
            |k: usize| b * (1.0 + 10f64.powf(lo_exp + (hi_exp - lo_exp) * k as f64 / n as f64));
        let mut roots = Vec::new();
        let mut v0 = v_at(0);
        let mut g0 = g(v0);
        for k in 1..=n {
            let v1 = v_at(k);
            let g1 = g(v1);
            if g0 == 0.0 {
                roots.push(v0);
            } else if g0 * g1 < 0.0 {
                let (mut lo, mut hi, mut glo) = (v0, v1, g0);
                loop {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    let gm = g(mid);
                    if gm == 0.0 {
                        lo = mid;
                        hi = mid;
                        break;
                    }
                    if (gm > 0.0) == (glo > 0.0) {
                        lo = mid;
                        glo = gm;
                    } else {
                        hi = mid;
                    }
                }
                roots.push(0.5 * (lo + hi));
            }
            v0 = v1;
            g0 = g1;
        }
        roots
    }

    /// Density on the liquid (smallest V) or gas (largest V) root, A-Eq. 23: `ρ = w/(V + s)`.
    pub fn density(&self, t: f64, p: f64, liquid: bool) -> f64 {
        let r = self.roots(t, p);
        let v = if liquid { r[0] } else { r[r.len() - 1] };
        self.w / (v + self.s)
    }
}
