//! Property tests of the invariants `thm-eos` promises.

use proptest::prelude::*;
use thm_eos::{
    Branch, EquationOfState, Model, PengRobinson, PoreClosure, TwoPhaseClosure, water_air_closure,
};

fn fluid(k: usize) -> PengRobinson {
    match k {
        0 => PengRobinson::water(Model::Pr),
        1 => PengRobinson::water(Model::PrCorrected),
        _ => PengRobinson::air(),
    }
}

fn branch(liquid: bool) -> Branch {
    if liquid { Branch::Liquid } else { Branch::Gas }
}

/// Round-off scale of a pressure evaluated at (T, ρ) when ρ itself carries a relative error of
/// one ulp: the two terms of A-Eq. 16 (which cancel in a dense liquid) plus ρ ∂P/∂ρ.
fn pressure_roundoff(eos: &PengRobinson, t: f64, rho: f64) -> f64 {
    let terms = eos.pressure_term_scale(t, rho).unwrap();
    let stiffness = rho * eos.dp_drho(t, rho).unwrap().abs();
    f64::EPSILON * (terms + stiffness)
}

proptest! {
    // 256 cases each; rejections (pores whose water is not a liquid) are a few per cent.
    #![proptest_config(ProptestConfig {
        cases: 256,
        max_global_rejects: 1 << 20,
        ..ProptestConfig::default()
    })]

    /// P(ρ(T, P)) = P to round-off, on both branches, for water (both models) and air.
    #[test]
    fn density_pressure_round_trip(
        k in 0usize..3,
        t in 278.0f64..700.0,
        log_p in 4.0f64..(7e7f64).log10(),
        liquid in any::<bool>(),
    ) {
        let eos = fluid(k);
        let p = 10f64.powf(log_p);
        let rho = eos.density(t, p, branch(liquid)).unwrap();
        let back = eos.pressure(t, rho).unwrap();
        let tol = 16.0 * pressure_roundoff(&eos, t, rho);
        prop_assert!((back - p).abs() <= tol, "P = {p}, back {back}, tol {tol}");
    }

    /// The roots chosen on either branch are mechanically stable: ∂P/∂ρ > 0.
    #[test]
    fn chosen_roots_are_stable(
        k in 0usize..3,
        t in 278.0f64..700.0,
        log_p in 4.0f64..(7e7f64).log10(),
        liquid in any::<bool>(),
    ) {
        let eos = fluid(k);
        let rho = eos.density(t, 10f64.powf(log_p), branch(liquid)).unwrap();
        prop_assert!(eos.dp_drho(t, rho).unwrap() > 0.0);
    }

    /// The liquid root is never less dense than the gas root.
    #[test]
    fn liquid_root_is_the_densest(
        k in 0usize..3,
        t in 278.0f64..700.0,
        log_p in 4.0f64..(7e7f64).log10(),
    ) {
        let eos = fluid(k);
        let p = 10f64.powf(log_p);
        let l = eos.density(t, p, Branch::Liquid).unwrap();
        let g = eos.density(t, p, Branch::Gas).unwrap();
        prop_assert!(l >= g);
    }

    /// The analytic ∂P/∂ρ and ∂P/∂T match central differences of P(T, ρ).
    #[test]
    fn analytic_derivatives_match_differences(
        k in 0usize..3,
        t in 278.0f64..700.0,
        log_p in 4.0f64..(7e7f64).log10(),
        liquid in any::<bool>(),
    ) {
        let eos = fluid(k);
        let rho = eos.density(t, 10f64.powf(log_p), branch(liquid)).unwrap();
        let h = 1e-5 * rho;
        let fd = (eos.pressure(t, rho + h).unwrap() - eos.pressure(t, rho - h).unwrap()) / (2.0 * h);
        let an = eos.dp_drho(t, rho).unwrap();
        // Truncation O(h²) plus cancellation of the pressure round-off over 2h.
        let tol = 1e-6 * an.abs() + 4.0 * pressure_roundoff(&eos, t, rho) / h;
        prop_assert!((fd - an).abs() <= tol, "dP/drho {an} vs {fd}");
        let dt = 1e-4 * t;
        let fd = (eos.pressure(t + dt, rho).unwrap() - eos.pressure(t - dt, rho).unwrap()) / (2.0 * dt);
        let an = eos.dp_dt(t, rho).unwrap();
        let tol = 1e-6 * an.abs() + 4.0 * pressure_roundoff(&eos, t, rho) / dt;
        prop_assert!((fd - an).abs() <= tol, "dP/dT {an} vs {fd}");
    }

    /// The closure conserves both masses, equalises the two pressures to round-off and gives
    /// back the liquid fraction of a pore built at a known (T, P, α).
    #[test]
    fn closure_conserves_masses_and_equalises_pressures(
        corrected in any::<bool>(),
        t in 278.0f64..700.0,
        log_p in 4.0f64..(7e7f64).log10(),
        alpha in 0.001f64..0.999,
        log_v in -15.0f64..-3.0,
    ) {
        let model = if corrected { Model::PrCorrected } else { Model::Pr };
        let water = PengRobinson::water(model);
        let air = PengRobinson::air();
        let p = 10f64.powf(log_p);
        let v = 10f64.powf(log_v);
        let rho_l = water.density(t, p, Branch::Liquid).unwrap();
        // Only pores whose water is a liquid (the cubic's smallest root on the dense branch).
        prop_assume!(water.on_branch(t, rho_l, Branch::Liquid).unwrap());
        let m_l = alpha * v * rho_l;
        let m_g = (1.0 - alpha) * v * air.density(t, p, Branch::Gas).unwrap();
        let s = water_air_closure(model).close(t, v, m_l, m_g).unwrap();
        let a = s.liquid_fraction;
        prop_assert!((0.0..=1.0).contains(&a));
        prop_assert!((a * s.liquid_density * v - m_l).abs() <= 4.0 * f64::EPSILON * m_l);
        prop_assert!((s.gas_fraction * s.gas_density * v - m_g).abs() <= 4.0 * f64::EPSILON * m_g);
        prop_assert!((s.gas_fraction - (1.0 - a)).abs() <= f64::EPSILON);
        let p_l = water.pressure(t, s.liquid_density).unwrap();
        let p_g = air.pressure(t, s.gas_density).unwrap();
        // Round-off: each pressure's own evaluation, plus the pressure change of one ulp of α.
        let slope = water.dp_drho(t, s.liquid_density).unwrap() * s.liquid_density / a
            + air.dp_drho(t, s.gas_density).unwrap() * s.gas_density / s.gas_fraction;
        let tol = 8.0 * (pressure_roundoff(&water, t, s.liquid_density)
            + pressure_roundoff(&air, t, s.gas_density)
            + f64::EPSILON * a.min(s.gas_fraction) * slope);
        prop_assert!((p_l - p_g).abs() <= tol, "P_l {p_l} P_g {p_g} tol {tol}");
        prop_assert!((a - alpha).abs() <= 1e-10, "alpha {a} vs {alpha}");
    }

    /// Single-phase limits are exact: no gas gives α = 1 and the liquid's own P(T, m/V); no
    /// liquid gives α = 0 and the gas's P(T, m/V), bit for bit.
    #[test]
    fn single_phase_limits_are_exact(
        t in 278.0f64..700.0,
        log_p in 4.0f64..(7e7f64).log10(),
        log_v in -15.0f64..-3.0,
        liquid_only in any::<bool>(),
    ) {
        let v = 10f64.powf(log_v);
        let p = 10f64.powf(log_p);
        let pore = water_air_closure(Model::PrCorrected);
        if liquid_only {
            let water = PengRobinson::water(Model::PrCorrected);
            let m = v * water.density(t, p, Branch::Liquid).unwrap();
            let s = pore.close(t, v, m, 0.0).unwrap();
            prop_assert_eq!(s.liquid_fraction, 1.0);
            prop_assert_eq!(s.gas_fraction, 0.0);
            prop_assert_eq!(s.liquid_density, m / v);
            prop_assert_eq!(s.pressure, water.pressure(t, m / v).unwrap());
        } else {
            let air = PengRobinson::air();
            let m = v * air.density(t, p, Branch::Gas).unwrap();
            let s = pore.close(t, v, 0.0, m).unwrap();
            prop_assert_eq!(s.liquid_fraction, 0.0);
            prop_assert_eq!(s.gas_fraction, 1.0);
            prop_assert_eq!(s.gas_density, m / v);
            prop_assert_eq!(s.pressure, air.pressure(t, m / v).unwrap());
        }
    }

    /// Density is continuous across the critical temperature above the critical pressure.
    #[test]
    fn continuous_across_the_critical_temperature(
        p in 1.05 * 22.064e6f64..7e7,
        liquid in any::<bool>(),
    ) {
        let water = PengRobinson::water(Model::PrCorrected);
        let tc = 647.096;
        let below = water.density(tc * (1.0 - 1e-9), p, branch(liquid)).unwrap();
        let above = water.density(tc * (1.0 + 1e-9), p, branch(liquid)).unwrap();
        prop_assert!((below / above - 1.0).abs() <= 1e-6, "{below} vs {above}");
    }
}

/// A closure with a gas that is not air, to check the closure is generic: two identical
/// supercritical fluids share the pore in proportion to their masses.
#[test]
fn identical_phases_share_the_pore_by_mass() {
    let air = PengRobinson::air();
    let pore = TwoPhaseClosure::new(air, air);
    let s = pore.close(300.0, 2.0, 3.0, 1.0).unwrap();
    assert!((s.liquid_fraction - 0.75).abs() <= 1e-15);
    assert!((s.liquid_density - s.gas_density).abs() <= 1e-14 * s.gas_density);
}
