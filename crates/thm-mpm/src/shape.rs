//! uGIMP weighting functions and their gradients (B-Eqs. 12–13).
//!
//! With the bilinear grid shape function `N_I` and the top-hat particle characteristic
//! function `χ_p` of half-width `l_p` (B-Eq. 8), the averages of B-Eqs. 12–13 factor into 1D
//! terms, `φ_Ip = S(x_p − x_I) S(y_p − y_I)`, `∇φ_Ip = (S'(Δx) S(Δy), S(Δx) S'(Δy))`, where for
//! cell size `h` and `0 < l_p ≤ h/2` (Bardenhagen and Kober, 2004):
//!
//! ```text
//! |d| < l_p          : S = 1 − (d² + l_p²) / (2 h l_p)      S' = −d / (h l_p)
//! l_p ≤ |d| < h − l_p : S = 1 − |d| / h                      S' = −sign(d) / h
//! h − l_p ≤ |d| < h + l_p : S = (h + l_p − |d|)² / (4 h l_p)  S' = −sign(d)(h + l_p − |d|) / (2 h l_p)
//! otherwise          : S = 0                                 S' = 0
//! ```
//!
//! A point with `l_p ≤ h/2` touches at most three nodes per direction: those of index
//! `base, base+1, base+2` with `base = round((x_p − x_0)/h) − 1`.

use crate::grid::Grid;

/// 1D uGIMP weight `S(d)` and derivative `S'(d)` for node distance `d = x_p − x_I`.
#[inline]
pub fn gimp_1d(d: f64, h: f64, lp: f64) -> (f64, f64) {
    let a = d.abs();
    let s = d.signum();
    if a < lp {
        (1.0 - (d * d + lp * lp) / (2.0 * h * lp), -d / (h * lp))
    } else if a < h - lp {
        (1.0 - a / h, -s / h)
    } else if a < h + lp {
        let r = h + lp - a;
        (r * r / (4.0 * h * lp), -s * r / (2.0 * h * lp))
    } else {
        (0.0, 0.0)
    }
}

/// The three 1D weights and derivatives of a point along one axis, with the first node index.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Axis3 {
    /// Index (along this axis) of the first of the three nodes.
    pub base: usize,
    /// Weights `S` of nodes `base..base+3`.
    pub w: [f64; 3],
    /// Derivatives `S'` of nodes `base..base+3` (1/m).
    pub g: [f64; 3],
}

/// `x` limited to `[lo, hi]`, written so that it compiles to one max and one min instruction
/// (no NaN handling: positions are validated finite).
#[inline(always)]
fn clamp(x: f64, lo: f64, hi: f64) -> f64 {
    let y = if x > lo { x } else { lo };
    if y < hi { y } else { hi }
}

/// 1D weights along one axis. `nodes` is the number of nodes along the axis (≥ 3); the caller
/// guarantees `x0 + lp ≤ xp ≤ x0 + (nodes−1) h − lp`, so clamping `base` loses no weight.
///
/// Hot-loop form of [`gimp_1d`], free of branches. In cell units (`l = l_p/h`, node distance
/// `d`), `S(d)` is the average of the hat `N(t) = 1 − |t|` over `[d − l, d + l]`. The first
/// node lies at `d ≥ l`, where the domain meets only the falling flank `t ∈ [0, 1]`: with
/// `p, q` the ends of the domain clamped to that flank, `S = (q − p)(2 − p − q)/(4l)` and
/// `S' = (p − q)/(2 l h)`; the third node mirrors it on the rising flank. The middle node
/// follows from the partition of unity, `S₁ = 1 − S₀ − S₂`, `S₁' = −S₀' − S₂'`. Each outer
/// weight is a product of non-negative factors, so it vanishes exactly (or to `O(ε²)`) where
/// the domain ends at the edge of the node's support, as the piecewise formula does.
#[inline]
pub fn axis3(xp: f64, x0: f64, h: f64, lp: f64, nodes: usize) -> Axis3 {
    let inv_h = 1.0 / h;
    let u = (xp - x0) * inv_h;
    // `as usize` floors a non-negative value and saturates a negative or NaN one to 0.
    let base = ((u + 0.5) as usize).saturating_sub(1).min(nodes - 3);
    let l = lp * inv_h;
    let inv_4l = 0.25 / l;
    let inv_2lh = 2.0 * inv_4l * inv_h;
    let xi = u - base as f64;
    // First node, d = ξ: falling flank.
    let (p0, q0) = (clamp(xi - l, 0.0, 1.0), clamp(xi + l, 0.0, 1.0));
    let w0 = (q0 - p0) * (2.0 - p0 - q0) * inv_4l;
    let g0 = (p0 - q0) * inv_2lh;
    // Third node, d = ξ − 2: rising flank.
    let d2 = xi - 2.0;
    let (p2, q2) = (clamp(d2 - l, -1.0, 0.0), clamp(d2 + l, -1.0, 0.0));
    let w2 = (q2 - p2) * (2.0 + p2 + q2) * inv_4l;
    let g2 = (q2 - p2) * inv_2lh;
    Axis3 {
        base,
        w: [w0, 1.0 - w0 - w2, w2],
        g: [g0, -(g0 + g2), g2],
    }
}

/// The 3 × 3 stencil of one point: `φ_Ip = wx[a] · wy[b]` for node `(bx + a, by + b)`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Stencil {
    /// Along x.
    pub x: Axis3,
    /// Along y.
    pub y: Axis3,
}

impl Stencil {
    /// Stencil of a point at `pos` with half-sizes `half` on `grid`.
    #[inline]
    pub fn new(grid: &Grid, pos: [f64; 2], half: [f64; 2]) -> Self {
        let o = grid.origin();
        let h = grid.cell_size();
        let n = grid.nodes();
        Self {
            x: axis3(pos[0], o[0], h, half[0], n[0]),
            y: axis3(pos[1], o[1], h, half[1], n[1]),
        }
    }
    /// Weight `φ` of local node `(a, b)`.
    #[inline]
    pub fn weight(&self, a: usize, b: usize) -> f64 {
        self.x.w[a] * self.y.w[b]
    }
    /// Gradient `∇φ` of local node `(a, b)` (1/m).
    #[inline]
    pub fn gradient(&self, a: usize, b: usize) -> [f64; 2] {
        [self.x.g[a] * self.y.w[b], self.x.w[a] * self.y.g[b]]
    }
}

/// A [`Stencil`] in 72 bytes instead of 112, for storing one per point between the binning
/// and the scatter and gather passes: per axis the first node index and the outer weights and
/// gradients. [`PackedStencil::unpack`] forms the middle ones with the expressions of
/// [`axis3`] (`1 − w₀ − w₂`, `−(g₀ + g₂)`), so a stencil of [`axis3`] comes back bit for bit.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PackedStencil {
    base: [u32; 2],
    /// `[w₀, w₂, g₀, g₂]` along x, then along y.
    outer: [[f64; 4]; 2],
}

impl PackedStencil {
    /// Packs a stencil whose axis bases fit in 32 bits (grids have at most 2²⁴ cells a side).
    #[inline]
    pub fn pack(s: &Stencil) -> Self {
        let outer = |a: &Axis3| [a.w[0], a.w[2], a.g[0], a.g[2]];
        Self {
            base: [s.x.base as u32, s.y.base as u32],
            outer: [outer(&s.x), outer(&s.y)],
        }
    }

    /// The stencil, middle weights and gradients formed as [`axis3`] forms them.
    #[inline]
    pub fn unpack(&self) -> Stencil {
        let axis = |base: u32, [w0, w2, g0, g2]: [f64; 4]| Axis3 {
            base: base as usize,
            w: [w0, 1.0 - w0 - w2, w2],
            g: [g0, -(g0 + g2), g2],
        };
        Stencil {
            x: axis(self.base[0], self.outer[0]),
            y: axis(self.base[1], self.outer[1]),
        }
    }

    /// First node row (the stencil's base along y).
    #[inline]
    pub fn base_row(&self) -> usize {
        self.base[1] as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Partition of unity, zero-sum gradients, linear reproduction and the derivative
        /// matching a central difference of the weight.
        #[test]
        fn weights_partition_unity_and_reproduce_linear(
            xp in 0.26f64..9.74, frac in 0.05f64..0.5
        ) {
            let h = 1.0;
            let lp = frac * h;
            prop_assume!(xp - lp >= 0.0 && xp + lp <= 10.0);
            let a = axis3(xp, 0.0, h, lp, 11);
            let sw: f64 = a.w.iter().sum();
            let sg: f64 = a.g.iter().sum();
            let sx: f64 = (0..3).map(|k| a.w[k] * (a.base + k) as f64 * h).sum();
            let sgx: f64 = (0..3).map(|k| a.g[k] * (a.base + k) as f64 * h).sum();
            prop_assert!((sw - 1.0).abs() < 1e-14);
            prop_assert!(sg.abs() < 1e-14);
            prop_assert!((sx - xp).abs() < 1e-13);
            prop_assert!((sgx - 1.0).abs() < 1e-13);
            // Derivative against a central difference of the weight (away from kinks).
            for k in 0..3 {
                let xi = (a.base + k) as f64 * h;
                let eps = 1e-7;
                let (wp, _) = gimp_1d(xp + eps - xi, h, lp);
                let (wm, _) = gimp_1d(xp - eps - xi, h, lp);
                let fd = (wp - wm) / (2.0 * eps);
                prop_assert!((fd - a.g[k]).abs() < 1e-5, "node {k}: fd {fd} vs {}", a.g[k]);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// The branch-free stencil equals the piecewise uGIMP formula node by node, on a grid
        /// with an offset origin and a non-unit cell.
        #[test]
        fn branch_free_weights_equal_piecewise_formula(
            xp in -0.9f64..1.9, frac in 0.05f64..0.5
        ) {
            let (x0, h) = (-1.0, 0.25);
            let lp = frac * h;
            prop_assume!(xp - lp >= x0 && xp + lp <= x0 + 12.0 * h);
            let a = axis3(xp, x0, h, lp, 13);
            for k in 0..3 {
                let (w, g) = gimp_1d(xp - (x0 + (a.base + k) as f64 * h), h, lp);
                prop_assert!((a.w[k] - w).abs() < 1e-14, "w[{k}] {} vs {w}", a.w[k]);
                prop_assert!((a.g[k] - g).abs() < 1e-13 / h, "g[{k}] {} vs {g}", a.g[k]);
            }
            // Nodes outside the stencil carry no weight.
            for k in [-1.0, 3.0] {
                let (w, _) = gimp_1d(xp - (x0 + (a.base as f64 + k) * h), h, lp);
                prop_assert!(w == 0.0, "node {k} outside the stencil has weight {w}");
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Packing and unpacking a stencil returns it bit for bit.
        #[test]
        fn packed_stencil_round_trips_bit_for_bit(
            x in 0.3f64..9.7, y in 0.3f64..4.7, fx in 0.05f64..0.5, fy in 0.05f64..0.5
        ) {
            let grid = Grid::new(&crate::grid::GridParameters {
                origin: [0.0, 0.0],
                cell_size: 1.0,
                cells: [10, 5],
            })
            .unwrap();
            let s = Stencil::new(&grid, [x, y], [0.2 * fx, 0.2 * fy]);
            let u = PackedStencil::pack(&s).unpack();
            let bits = |s: &Stencil| {
                [s.x.w, s.x.g, s.y.w, s.y.g].concat().iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            };
            prop_assert_eq!((u.x.base, u.y.base), (s.x.base, s.y.base));
            prop_assert_eq!(bits(&u), bits(&s));
        }
    }

    /// The weight is continuous across the three breakpoints of the piecewise formula.
    #[test]
    fn weight_continuous_at_breakpoints() {
        let (h, lp) = (1.0, 0.3);
        for d in [lp, h - lp, h + lp] {
            let (a, _) = gimp_1d(d - 1e-12, h, lp);
            let (b, _) = gimp_1d(d + 1e-12, h, lp);
            assert!((a - b).abs() < 1e-10, "jump at {d}: {a} vs {b}");
        }
    }
}
