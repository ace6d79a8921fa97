//! The bar tension driver on a chain of three bonded spheres, where the answer is analytical:
//! two bonds of stiffness `K_n = E_c R` in series break at `T·R²` (A-Eqs. 1, 3, 6).

use thm_dem::packing::Packing;
use thm_dem::tension::{BarLoading, BarTension, Grip};
use thm_dem::*;

fn chain(r: f64) -> Packing {
    Packing {
        kinematics: Kinematics::SpheresInPlane,
        centres: (0..3)
            .map(|k| Vec3::new(0.0, r + 2.0 * r * k as f64, 0.0))
            .collect(),
        radii: vec![r; 3],
        bonds: vec![(0, 1), (1, 2)],
    }
}

fn pull(grip: Grip) -> (f64, f64, f64, f64) {
    let r = 3e-3;
    let law = CohesiveFrictionalParams::paper_a_table_1()
        .validate()
        .unwrap();
    let loading = BarLoading {
        grip,
        ..BarLoading::paper_a()
    };
    let (length, width) = (6.0 * r, 2.0 * r);
    let (mut bar, mut state) =
        BarTension::new(&chain(r), law, 2600.0, &loading, 0.0, length, width).unwrap();
    assert_eq!(bar.grips(), (&[0usize][..], &[2usize][..]));
    let (mut peak, mut strain_at_peak) = (0.0_f64, 0.0);
    while state.bond_breaks.is_empty() {
        let s = bar.step(&mut state).unwrap();
        if s.stress > peak {
            peak = s.stress;
            strain_at_peak = s.strain;
        }
    }
    let area = width * loading.thickness;
    (
        peak * area,
        strain_at_peak,
        length,
        state.particles.position[1].x,
    )
}

#[test]
fn a_bonded_chain_breaks_at_t_r_squared_after_two_bond_elongations() {
    for grip in [Grip::Smooth, Grip::Clamped] {
        let (force, strain, length, x_mid) = pull(grip);
        let (r, t, e_c) = (3e-3, 30e6, 3.36e9);
        let limit = t * r * r;
        // Quasi-static: the plate force at the peak is the bond limit within the force of one
        // step's plate travel on the two springs in series.
        assert!(
            (force / limit - 1.0).abs() < 0.01,
            "{grip:?}: {force} vs {limit}"
        );
        // Two bonds, each stretched by T R² / K_n = T R / E_c.
        let expected = 2.0 * t * r / e_c / length;
        assert!(
            (strain / expected - 1.0).abs() < 0.01,
            "{grip:?}: {strain} vs {expected}"
        );
        // Axial loading of a straight chain: no lateral motion.
        assert_eq!(x_mid, 0.0);
    }
}

#[test]
fn smooth_grips_follow_the_plates_axially_only() {
    let r = 3e-3;
    // A bent chain: the top sphere sits off-axis, so the bond pulls it sideways.
    let mut packing = chain(r);
    packing.centres[2].x = 1e-3;
    packing.centres[2].y -= 2.0 * r - (4.0 * r * r - 1e-6_f64).sqrt();
    let law = CohesiveFrictionalParams::paper_a_table_1()
        .validate()
        .unwrap();
    let loading = BarLoading::paper_a();
    let y_top = packing.centres[2].y + r;
    let (mut bar, mut state) =
        BarTension::new(&packing, law, 2600.0, &loading, 0.0, y_top, 2.0 * r).unwrap();
    let y0 = [state.particles.position[0].y, state.particles.position[2].y];
    for _ in 0..2000 {
        bar.step(&mut state).unwrap();
    }
    let p = &state.particles;
    let travel = loading.plate_speed * state.time;
    assert!((p.position[0].y - (y0[0] - travel)).abs() < 1e-15);
    assert!((p.position[2].y - (y0[1] + travel)).abs() < 1e-15);
    assert!(
        p.position[2].x < 1e-3,
        "the top grip must slide towards the axis"
    );
}

#[test]
fn bar_tension_rejects_bad_loading() {
    let base = BarLoading::paper_a();
    let cases = [
        (
            BarLoading {
                plate_speed: -1.0,
                ..base
            },
            0.0,
            "plate_speed",
        ),
        (
            BarLoading {
                end_strain: 0.0,
                ..base
            },
            0.0,
            "end_strain",
        ),
        (
            BarLoading {
                end_strain: f64::NAN,
                ..base
            },
            0.0,
            "end_strain",
        ),
        (
            BarLoading {
                thickness: 0.0,
                ..base
            },
            0.0,
            "thickness",
        ),
        // Grip depth 0 grips nothing when the bar ends lie 1 mm beyond the spheres.
        (
            BarLoading {
                grip_depth: 0.0,
                ..base
            },
            1e-3,
            "grip_depth",
        ),
    ];
    for (loading, margin, expected) in cases {
        let law = CohesiveFrictionalParams::paper_a_table_1()
            .validate()
            .unwrap();
        let err = BarTension::new(
            &chain(3e-3),
            law,
            2600.0,
            &loading,
            -margin,
            0.018 + margin,
            0.006,
        )
        .unwrap_err();
        assert!(
            matches!(err, DemError::InvalidParameter { field, .. } if field == expected),
            "{expected}: {err}"
        );
    }
}

#[test]
fn plates_stop_at_the_end_strain_and_hold() {
    let r = 3e-3;
    let law = CohesiveFrictionalParams::paper_a_table_1()
        .validate()
        .unwrap();
    let loading = BarLoading {
        end_strain: 1e-3,
        ..BarLoading::paper_a()
    };
    let length = 6.0 * r;
    let (mut bar, mut state) =
        BarTension::new(&chain(r), law, 2600.0, &loading, 0.0, length, 2.0 * r).unwrap();
    let stop = 1e-3 * length / (2.0 * loading.plate_speed);
    while state.time < 2.0 * stop {
        bar.step(&mut state).unwrap();
    }
    let s = bar.sample(&state);
    assert_eq!(s.strain, 1e-3);
    let top = state.particles.position[2].y;
    assert!((top - (5.0 * r + 0.5 * 1e-3 * length)).abs() < 1e-15);
    assert_eq!(state.particles.velocity[2].y, 0.0);
    // Below the break strain (0.30 %): the bonds hold, the stress is positive.
    assert!(state.bond_breaks.is_empty() && s.stress > 0.0);
}

/// The post-peak reload of packing 3 with A-Table 1's bond strengths (module docs of
/// `thm_dem::tension`): after the first drop the stress climbs again, and wherever it
/// does a path of intact bonds (a ligament the first crack left) still joins the two grips.
#[test]
fn the_post_peak_reload_is_carried_by_an_intact_ligament() {
    use thm_dem::packing::{PackingParams, random_packing};
    use thm_dem::tension::GENERATOR_POROSITY;
    let params = PackingParams {
        bond_gap: 4e-3,
        porosity: GENERATOR_POROSITY,
        ..PackingParams::paper_a_bar(3)
    };
    let (packing, _) = random_packing(&params, 2600.0).unwrap();
    let law = CohesiveFrictionalParams::paper_a_table_1()
        .validate()
        .unwrap();
    let (y0, y1) = (params.box_min[1], params.box_max[1]);
    let width = params.box_max[0] - params.box_min[0];
    let (mut bar, mut state) =
        BarTension::new(&packing, law, 2600.0, &BarLoading::paper_a(), y0, y1, width).unwrap();
    let mut peak: f64 = 0.0;
    // Lowest stress after the first drop (below half the peak).
    let mut trough = f64::INFINITY;
    let mut reload: f64 = 0.0;
    let mut strain = 0.0;
    while strain < 0.0035 {
        let s = bar.step(&mut state).unwrap();
        strain = s.strain;
        if trough.is_infinite() {
            peak = peak.max(s.stress);
            if s.stress < 0.5 * peak {
                trough = s.stress;
            }
            continue;
        }
        trough = trough.min(s.stress);
        if s.stress > trough + 0.2 * peak {
            reload = reload.max(s.stress);
            assert!(
                bar.grips_bonded(&state),
                "{:e} Pa at strain {strain:e} with no intact path between the grips",
                s.stress
            );
        }
    }
    assert!(trough.is_finite(), "no drop");
    assert!(
        reload > trough + 0.2 * peak,
        "no reload: trough {trough:e}, reload {reload:e}, peak {peak:e}"
    );
}
