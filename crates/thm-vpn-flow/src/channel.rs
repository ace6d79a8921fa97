//! Closed-form laminar flow between two parallel plates (A-Eqs. 10–15).
//!
//! Everything here is per unit width of the channel (the out-of-plane direction): volumetric
//! flow rates in m²/s, shear stresses in Pa. The solver multiplies by the specimen thickness.
//!
//! ## Two-layer flow (A-Eqs. 11–15)
//!
//! The liquid `q` fills `0 ≤ y ≤ a` (bottom wall at `y = 0`), the gas `p` fills `a ≤ y ≤ h`
//! (top wall at `y = h`), the interface is flat and the flow fully developed, driven by the
//! pressure gradient `G = (P_i − P_j)/L`. In steady plane-parallel flow A-Eq. 12 reduces in
//! each layer to `μ_k u_k'' = −G`, so each velocity profile is a parabola:
//!
//! ```text
//! u_q(y) = −G y²/(2μ_q) + A y              (u_q(0) = 0, A-Eq. 13)
//! u_p(y) = −G (y−h)²/(2μ_p) + B (y−h)      (u_p(h) = 0, A-Eq. 13)
//! ```
//!
//! Continuity of velocity (A-Eq. 14) and of shear stress (A-Eq. 15) at `y = a`, with
//! `b = h − a`, give
//!
//! ```text
//! μ_q A − μ_p B = G h
//! A = G [a² μ_p/μ_q + b (2a + b)] / (2 (a μ_p + b μ_q))
//! ```
//!
//! and the layer flow rates and wall shear stresses (positive in the flow direction):
//!
//! ```text
//! Q_q = −G a³/(6μ_q) + A a²/2,    Q_p = −G b³/(6μ_p) − B b²/2,
//! τ_bottom = μ_q A,               τ_top = −μ_p B = G h − τ_bottom.
//! ```
//!
//! The two wall stresses together balance the pressure drop: `τ_bottom + τ_top = G h`. With
//! `a = 0` or `a = h` the formulas reduce to Poiseuille flow (A-Eq. 10), `Q = G h³/(12 μ)` and
//! `τ = G h/2` on each wall.

/// Single-phase plane Poiseuille flow (A-Eq. 10): volumetric flow rate per unit width
/// `Q = h³ G/(12 μ)` [m²/s] for aperture `h` \[m\], pressure gradient `G = (P_i − P_j)/L` [Pa/m]
/// and viscosity `μ` [Pa·s]. The mass flow rate per unit width of A-Eq. 10 is `ρ Q`.
pub fn poiseuille_flow_rate(aperture: f64, pressure_gradient: f64, viscosity: f64) -> f64 {
    aperture * aperture * aperture * pressure_gradient / (12.0 * viscosity)
}

/// The two-layer solution of one channel (per unit width). Positive values point from the
/// high-pressure end to the low-pressure end when `G > 0` (i.e. the sign follows `G`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoLayerFlow {
    /// Volumetric flow rate of the liquid layer per unit width [m²/s].
    pub liquid_flow_rate: f64,
    /// Volumetric flow rate of the gas layer per unit width [m²/s].
    pub gas_flow_rate: f64,
    /// Shear stress the fluid exerts on the wall in contact with the liquid \[Pa\].
    pub liquid_wall_shear: f64,
    /// Shear stress the fluid exerts on the wall in contact with the gas \[Pa\].
    pub gas_wall_shear: f64,
    /// Velocity at the interface [m/s] (the centreline-plane velocity in single-phase limits).
    pub interface_velocity: f64,
}

impl TwoLayerFlow {
    /// Mean of the two wall shear stresses, `G h / 2` \[Pa\]: the stress given to each of the
    /// two spheres bounding an S2S channel (see the crate docs).
    pub fn mean_wall_shear(&self) -> f64 {
        0.5 * (self.liquid_wall_shear + self.gas_wall_shear)
    }
}

/// Solves the stratified two-layer flow of A-Eqs. 11–15 in closed form.
///
/// - `aperture` `h` \[m\] (≥ 0; zero gives no flow),
/// - `liquid_fraction` `α_q ∈ [0, 1]`: the liquid layer has thickness `a = α_q h` (the rule
///   that sets `α_q` from the two pores is the solver's, see the crate docs),
/// - `pressure_gradient` `G = (P_i − P_j)/L` [Pa/m],
/// - viscosities `μ_q`, `μ_p` [Pa·s] (> 0).
///
/// Inputs are assumed validated by the caller (the solver checks apertures and viscosities
/// once); `α_q` is clamped to `[0, 1]`.
pub fn two_layer_flow(
    aperture: f64,
    liquid_fraction: f64,
    pressure_gradient: f64,
    liquid_viscosity: f64,
    gas_viscosity: f64,
) -> TwoLayerFlow {
    let h = aperture;
    if h <= 0.0 {
        return TwoLayerFlow {
            liquid_flow_rate: 0.0,
            gas_flow_rate: 0.0,
            liquid_wall_shear: 0.0,
            gas_wall_shear: 0.0,
            interface_velocity: 0.0,
        };
    }
    let g = pressure_gradient;
    let (mq, mp) = (liquid_viscosity, gas_viscosity);
    let a = liquid_fraction.clamp(0.0, 1.0) * h;
    let b = h - a;
    let coef_a = g * (a * a * mp / mq + b * (2.0 * a + b)) / (2.0 * (a * mp + b * mq));
    let coef_b = (mq * coef_a - g * h) / mp;
    let liquid_flow_rate = -g * a * a * a / (6.0 * mq) + 0.5 * coef_a * a * a;
    let gas_flow_rate = -g * b * b * b / (6.0 * mp) - 0.5 * coef_b * b * b;
    let liquid_wall_shear = mq * coef_a;
    let gas_wall_shear = g * h - liquid_wall_shear;
    let interface_velocity = -g * a * a / (2.0 * mq) + coef_a * a;
    TwoLayerFlow {
        liquid_flow_rate,
        gas_flow_rate,
        liquid_wall_shear,
        gas_wall_shear,
        interface_velocity,
    }
}

/// The layer flow rates per unit width and unit pressure gradient, `(Q_q/G, Q_p/G)`
/// [m³/(Pa·s)], of a channel of aperture `h` holding a liquid layer `α_q h`: the same closed
/// form as [`two_layer_flow`] without the shear stresses, with fast single-phase paths
/// (`h³/(12 μ)` for the phase that fills the channel).
#[inline]
pub fn two_layer_conductances(
    aperture: f64,
    liquid_fraction: f64,
    liquid_viscosity: f64,
    gas_viscosity: f64,
) -> (f64, f64) {
    let h = aperture;
    if h <= 0.0 {
        return (0.0, 0.0);
    }
    let h3 = h * h * h / 12.0;
    if liquid_fraction >= 1.0 {
        return (h3 / liquid_viscosity, 0.0);
    }
    if liquid_fraction <= 0.0 {
        return (0.0, h3 / gas_viscosity);
    }
    let (mq, mp) = (liquid_viscosity, gas_viscosity);
    let (inv_mq, inv_mp) = (1.0 / mq, 1.0 / mp);
    let a = liquid_fraction * h;
    let b = h - a;
    let coef_a = (a * a * mp * inv_mq + b * (2.0 * a + b)) / (2.0 * (a * mp + b * mq));
    let coef_b = (mq * coef_a - h) * inv_mp;
    (
        a * a * (0.5 * coef_a - a * inv_mq / 6.0),
        -b * b * (b * inv_mp / 6.0 + 0.5 * coef_b),
    )
}

/// Total volumetric conductance per unit width `(Q_q + Q_p)/G` [m³/(Pa·s)] of a channel of
/// aperture `h` holding a liquid layer `α_q h`. It decreases monotonically with `α_q` when
/// `μ_q ≥ μ_p`, from `h³/(12 μ_p)` to `h³/(12 μ_q)`.
pub fn two_layer_conductance(
    aperture: f64,
    liquid_fraction: f64,
    liquid_viscosity: f64,
    gas_viscosity: f64,
) -> f64 {
    let (cq, cp) =
        two_layer_conductances(aperture, liquid_fraction, liquid_viscosity, gas_viscosity);
    cq + cp
}

#[cfg(test)]
mod tests {
    use super::*;

    const MU_WATER: f64 = 10.02e-4;
    const MU_AIR: f64 = 2.0507e-5;

    /// Independent reference from the integrated momentum balance, without the closed-form
    /// algebra: the shear stress across the gap is `τ(y) = τ_w − G y` whatever the layers, the
    /// velocity is `u(y) = ∫₀^y τ/μ ds` (no slip at `y = 0`) and no slip at `y = h` fixes
    /// `τ_w = G ∫ s/μ ds / ∫ 1/μ ds`. The integrals are evaluated numerically on `n` intervals
    /// (the interface on a node): the trapezoid rule for `u` (exact: the integrand is linear in
    /// each layer) and Simpson's rule for the layer flow rates.
    fn quadrature_reference(
        h: f64,
        intervals_liquid: usize,
        n: usize,
        g: f64,
        mq: f64,
        mp: f64,
    ) -> (f64, f64, f64, f64) {
        let dy = h / n as f64;
        let mu = |k: usize| if k < intervals_liquid { mq } else { mp };
        let (mut i0, mut i1) = (0.0, 0.0);
        for k in 0..n {
            let (y0, y1) = (k as f64 * dy, (k + 1) as f64 * dy);
            i0 += dy / mu(k);
            i1 += 0.5 * dy * (y0 + y1) / mu(k);
        }
        let tau_w = g * i1 / i0;
        let mut u = vec![0.0; n + 1];
        for k in 0..n {
            let (y0, y1) = (k as f64 * dy, (k + 1) as f64 * dy);
            let (t0, t1) = (tau_w - g * y0, tau_w - g * y1);
            u[k + 1] = u[k] + 0.5 * dy * (t0 + t1) / mu(k);
        }
        let simpson = |from: usize, to: usize| -> f64 {
            let mut s = 0.0;
            let mut k = from;
            while k < to {
                s += dy / 3.0 * (u[k] + 4.0 * u[k + 1] + u[k + 2]);
                k += 2;
            }
            s
        };
        let qq = simpson(0, intervals_liquid);
        let qp = simpson(intervals_liquid, n);
        (qq, qp, tau_w, -(tau_w - g * h))
    }

    #[test]
    fn poiseuille_is_exact() {
        // A-Eq. 10 against the integral of the parabolic profile u = G y (h − y)/(2μ).
        let (h, g, mu) = (3.25e-6, 4.9e6 / 0.08, MU_WATER);
        let q = poiseuille_flow_rate(h, g, mu);
        let exact_integral = g / (2.0 * mu) * (h * h * h / 2.0 - h * h * h / 3.0);
        assert!((q - exact_integral).abs() <= 1e-14 * exact_integral.abs());
        // The two-layer model with one phase is Poiseuille, and the wall shear is G h / 2.
        for alpha in [0.0, 1.0] {
            let f = two_layer_flow(h, alpha, g, mu, mu);
            assert!((f.liquid_flow_rate + f.gas_flow_rate - q).abs() <= 1e-13 * q);
            assert!((f.liquid_wall_shear - 0.5 * g * h).abs() <= 1e-13 * g * h);
            assert!((f.gas_wall_shear - 0.5 * g * h).abs() <= 1e-13 * g * h);
        }
    }

    #[test]
    fn two_layer_matches_quadrature_of_momentum_balance_for_water_and_air() {
        let ratio = MU_WATER / MU_AIR;
        assert!((ratio - 48.86).abs() < 0.01, "viscosity ratio {ratio}");
        let (h, g) = (1.0e-5, 1.0e7);
        let n = 4000;
        for liquid_cells in [0, 400, 1000, 2000, 3000, 3600, 4000] {
            let alpha = liquid_cells as f64 / n as f64;
            let f = two_layer_flow(h, alpha, g, MU_WATER, MU_AIR);
            let (qq, qp, tb, tt) = quadrature_reference(h, liquid_cells, n, g, MU_WATER, MU_AIR);
            let q_scale = poiseuille_flow_rate(h, g, MU_AIR);
            assert!(
                (f.liquid_flow_rate - qq).abs() <= 1e-9 * q_scale,
                "α={alpha}: Q_q {} vs {qq}",
                f.liquid_flow_rate
            );
            assert!(
                (f.gas_flow_rate - qp).abs() <= 1e-9 * q_scale,
                "α={alpha}: Q_p {} vs {qp}",
                f.gas_flow_rate
            );
            let tau_scale = g * h;
            assert!((f.liquid_wall_shear - tb).abs() <= 1e-9 * tau_scale);
            assert!((f.gas_wall_shear - tt).abs() <= 1e-9 * tau_scale);
            // Force balance on the fluid slab: walls carry the whole pressure drop.
            assert!((f.liquid_wall_shear + f.gas_wall_shear - g * h).abs() <= 1e-12 * g * h);
        }
        // Single-phase limits.
        let f = two_layer_flow(h, 0.0, g, MU_WATER, MU_AIR);
        assert_eq!(f.liquid_flow_rate, 0.0);
        assert!((f.gas_flow_rate / poiseuille_flow_rate(h, g, MU_AIR) - 1.0).abs() < 1e-13);
        let f = two_layer_flow(h, 1.0, g, MU_WATER, MU_AIR);
        assert_eq!(f.gas_flow_rate, 0.0);
        assert!((f.liquid_flow_rate / poiseuille_flow_rate(h, g, MU_WATER) - 1.0).abs() < 1e-13);
    }

    #[test]
    fn conductances_are_the_flow_rates_at_unit_gradient() {
        for k in 0..=10 {
            let alpha = k as f64 / 10.0;
            let f = two_layer_flow(2e-6, alpha, 1.0, MU_WATER, MU_AIR);
            let (cq, cp) = two_layer_conductances(2e-6, alpha, MU_WATER, MU_AIR);
            let scale = poiseuille_flow_rate(2e-6, 1.0, MU_AIR);
            assert!((cq - f.liquid_flow_rate).abs() <= 1e-14 * scale);
            assert!((cp - f.gas_flow_rate).abs() <= 1e-14 * scale);
        }
    }

    #[test]
    fn conductance_decreases_with_liquid_fraction() {
        let h = 2e-6;
        let mut last = f64::INFINITY;
        for k in 0..=20 {
            let c = two_layer_conductance(h, k as f64 / 20.0, MU_WATER, MU_AIR);
            assert!(c < last);
            last = c;
        }
        assert!((last - h.powi(3) / (12.0 * MU_WATER)).abs() < 1e-12 * last);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]
        #[test]
        fn walls_balance_the_pressure_drop_and_flow_lies_between_the_single_phase_limits(
            h in 1e-7f64..1e-4,
            alpha in 0.0f64..=1.0,
            g in -1e9f64..1e9,
            mq in 1e-5f64..1e-2,
            ratio in 1.0f64..100.0,
        ) {
            let mp = mq / ratio;
            let f = two_layer_flow(h, alpha, g, mq, mp);
            let scale = (g * h).abs().max(f64::MIN_POSITIVE);
            proptest::prop_assert!(
                (f.liquid_wall_shear + f.gas_wall_shear - g * h).abs() <= 1e-11 * scale
            );
            let total = f.liquid_flow_rate + f.gas_flow_rate;
            let (slow, fast) = (poiseuille_flow_rate(h, g, mq), poiseuille_flow_rate(h, g, mp));
            let tol = 1e-12 * fast.abs();
            proptest::prop_assert!(total.abs() >= slow.abs() - tol && total.abs() <= fast.abs() + tol);
            // Each layer flows down the gradient.
            proptest::prop_assert!(f.liquid_flow_rate * g >= 0.0 && f.gas_flow_rate * g >= 0.0);
        }
    }

    #[test]
    fn reversing_the_gradient_reverses_the_flow() {
        let a = two_layer_flow(1e-6, 0.3, 5e6, MU_WATER, MU_AIR);
        let b = two_layer_flow(1e-6, 0.3, -5e6, MU_WATER, MU_AIR);
        assert_eq!(a.liquid_flow_rate, -b.liquid_flow_rate);
        assert_eq!(a.gas_flow_rate, -b.gas_flow_rate);
        assert_eq!(a.liquid_wall_shear, -b.liquid_wall_shear);
    }
}
