//! The silo discharge of B-Sect. 5.3.2 (`thm_coupling::multiscale::silo`) on a tiny silo:
//! heat equals the RVEs' friction work to round-off, the gate holds the sample and the
//! opened silo discharges, no point goes through a wall, 1 and 2 threads give the same bits,
//! a restored run continues bit for bit across the gate's opening, and the paper's set-up is
//! valid with bad fields named; the verification cases run in release builds only.

use thm_coupling::multiscale::silo::{SiloModel, SiloTest};

/// 0.2 m cells with 2 × 2 points each, 30-disk RVEs, Δt = 10⁻³ s, 20 steps of settling and
/// `discharge` steps after the gate opens.
fn tiny(forced: bool, discharge: u64) -> SiloTest {
    let mut t = SiloTest::reduced(forced, 0.2, 30, discharge as f64 * 1e-3, 1e-3);
    t.settle_time = 0.02;
    t.dem_time.density_scaling = 1e5;
    t
}

fn json(m: &SiloModel) -> String {
    serde_json::to_string(&(&m.state, &m.totals)).unwrap()
}

#[test]
fn one_and_two_threads_give_the_same_bits() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut m = SiloModel::new(&tiny(true, 30)).unwrap();
                while !m.finished() {
                    m.step().unwrap();
                }
                json(&m)
            })
    };
    assert_eq!(run(1), run(2));
}

/// Saved before the gate opens, restored into a freshly built model: the same bits after
/// the opening and the plate's first steps.
#[test]
fn save_and_restore_continue_bit_for_bit() {
    let t = tiny(true, 30);
    let mut m = SiloModel::new(&t).unwrap();
    for _ in 0..15 {
        m.step().unwrap();
    }
    assert!(!m.totals.released);
    let saved = json(&m);
    while !m.finished() {
        m.step().unwrap();
    }
    assert!(m.totals.released);
    let mut m2 = SiloModel::new(&t).unwrap();
    let (state, totals) = serde_json::from_str(&saved).unwrap();
    m2.restore(state, totals).unwrap();
    while !m2.finished() {
        m2.step().unwrap();
    }
    assert_eq!(json(&m), json(&m2));
}

/// Stored heat = friction heat of the RVEs at every step, within the rounding of the stored
/// heat itself: temperatures are held absolute (20 °C here) while the rises are 10⁻⁷ K, so each
/// step's update of `T` rounds by up to ε |T| per point and `Σ m c (T − T₀)` carries
/// `ε Σ m c |T|` per step of it; a loss of heat of a few 10⁻⁶ of a step's friction heat would
/// exceed that budget. Friction does heat the sample; nothing passes the closed gate while
/// settling and nothing goes through a wall; the points' mass is unchanged.
#[test]
fn heat_is_the_friction_work_and_the_walls_hold() {
    let t = tiny(false, 60);
    let mut m = SiloModel::new(&t).unwrap();
    let mass0: f64 = m.state.points.mass.iter().sum();
    let mut budget = 0.0;
    let mut b_at_release = None;
    while !m.finished() {
        m.step().unwrap();
        let p = &m.state.points;
        budget += f64::EPSILON
            * (0..p.len())
                .map(|i| p.mass[i] * p.specific_heat[i] * p.temperature[i].abs())
                .sum::<f64>();
        let r = m.record();
        assert!(
            (r.stored_heat - r.source_heat).abs() <= 4.0 * budget,
            "stored - friction heat = {:e} J/m, rounding budget {budget:e}: {r:?}",
            r.stored_heat - r.source_heat
        );
        assert_eq!(r.escaped, 0, "{r:?}");
        if !m.totals.released {
            assert_eq!(r.discharged_fraction, 0.0, "{r:?}");
        } else if b_at_release.is_none() {
            b_at_release = Some(r.point_b);
        }
    }
    let r = m.record();
    assert!(r.source_heat > 0.0 && r.max_rise > 0.0, "{r:?}");
    // Point B, just above the opening, falls once the gate opens (0.06 s: g t²/2 = 18 mm).
    let b0 = b_at_release.unwrap();
    assert!(
        b0[1] - r.point_b[1] > 0.005,
        "B from {b0:?} to {:?}",
        r.point_b
    );
    let mass: f64 = m.state.points.mass.iter().sum();
    assert_eq!(mass, mass0);
}

/// The paper's silo is a valid set-up with about the paper's 1 088 points; bad fields are
/// refused by name.
#[test]
fn paper_setup_is_valid_and_bad_fields_name_themselves() {
    use thm_coupling::multiscale::MultiscaleError;
    let t = SiloTest::paper(false);
    t.validate().unwrap();
    assert!((t.hopper_height() - 0.4).abs() < 1e-12);
    assert_eq!(t.steps(), 125_000);
    let field_of = |t: &SiloTest| match t.validate() {
        Err(MultiscaleError::InvalidParameter { field, .. }) => field,
        other => panic!("{other:?}"),
    };
    let mut bad = t;
    bad.opening = 1.0;
    assert_eq!(field_of(&bad), "opening");
    let mut bad = t;
    bad.cell_size = 0.03;
    assert_eq!(field_of(&bad), "opening");
    let mut bad = t;
    bad.hopper_angle_deg = 90.0;
    assert_eq!(field_of(&bad), "hopper_angle_deg");
    let mut bad = t;
    bad.plate_speed = -1.0;
    assert_eq!(field_of(&bad), "plate_speed");
    let mut bad = t;
    bad.disks = 1;
    assert!(matches!(
        bad.validate(),
        Err(MultiscaleError::InvalidParameter {
            field: "disks",
            allowed: "[2, 1000000]",
            ..
        })
    ));
}

/// Runs the verification case `name` and asserts that it passed.
fn case_passes(name: &str) {
    let case = thm_coupling::verification::cases()
        .into_iter()
        .find(|c| c.name == name)
        .unwrap();
    let out = (case.run)().unwrap();
    for r in &out.rows {
        eprintln!(
            "{} | {} | {:.6e} | {:.3e} | {}",
            r.quantity,
            r.unit,
            r.measured,
            r.reference,
            if r.pass { "pass" } else { "FAIL" }
        );
    }
    assert!(out.passed());
}

/// The quick verification case passes every row (release only).
#[test]
#[cfg_attr(debug_assertions, ignore = "a few seconds in release")]
fn quick_verification_case_passes() {
    case_passes("coupling/mpm_dem_silo_quick");
}
