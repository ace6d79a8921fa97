//! The column collapse of B-Sect. 5.3.3 (`thm_coupling::multiscale::column`): the heat
//! balance to round-off, thread-count independence and save/restore across the release on a
//! tiny column; the unbonded column collapses and the bonded one stands on the reduced column
//! of the verification case (about 3 s each in the test profile, 1.5 s in release); the
//! verification cases themselves run in release builds only.

use thm_coupling::multiscale::column::{ColumnModel, ColumnTest};
use thm_coupling::verification::column::{reduced_column, run_column};

/// 2 × 2 cells of 1 m with 2 × 2 points each (16 RVEs of 30 disks), Δt = 10⁻³ s, 50 steps
/// of settling and `collapse` steps after the release, β_b = 0.1 with melting (bonds,
/// heating plate and friction heat all active).
fn tiny(collapse: u64) -> ColumnTest {
    let mut t = ColumnTest::reduced(0.1, true, 2, 30, 1e-3, 1e5);
    t.settle_time = 0.05;
    t.collapse_time = collapse as f64 * t.time_step;
    t
}

fn json(m: &ColumnModel) -> String {
    serde_json::to_string(&(&m.state, &m.totals)).unwrap()
}

/// 1 and 2 rayon threads give the same bits: points, RVEs and the running sums.
#[test]
fn one_and_two_threads_give_the_same_bits() {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut m = ColumnModel::new(&tiny(30)).unwrap();
                while !m.finished() {
                    m.step().unwrap();
                }
                json(&m)
            })
    };
    assert_eq!(run(1), run(2));
}

/// A state and running sums saved before the release and restored into a freshly built
/// model continue bit for bit through the release (bond installation, plate heating).
#[test]
fn save_and_restore_continue_bit_for_bit() {
    let t = tiny(30);
    let mut m = ColumnModel::new(&t).unwrap();
    for _ in 0..40 {
        m.step().unwrap();
    }
    assert!(!m.totals.released);
    let saved = json(&m);
    while !m.finished() {
        m.step().unwrap();
    }
    assert!(m.totals.released);
    let mut m2 = ColumnModel::new(&t).unwrap();
    let (state, totals) = serde_json::from_str(&saved).unwrap();
    m2.restore(state, totals).unwrap();
    while !m2.finished() {
        m2.step().unwrap();
    }
    assert_eq!(json(&m), json(&m2));
}

/// Stored heat `Σ m c (T − T₀)` = heat in from the plate + the friction heat of the RVEs,
/// to 10⁻¹² of the summed per-step heat at every step (a few ε per step, 80 steps); the plate
/// does heat the column (more than a kelvin on the heated half) and the bonds there are
/// installed and start to melt.
#[test]
fn heat_balance_holds_to_round_off() {
    let mut m = ColumnModel::new(&tiny(30)).unwrap();
    while !m.finished() {
        m.step().unwrap();
        let r = m.record();
        assert!(
            r.heat_balance_residual.abs() <= 1e-12,
            "step {}: residual {:e}",
            m.state.step,
            r.heat_balance_residual
        );
    }
    let r = m.record();
    assert!(r.plate_heat > 0.0, "plate heat {}", r.plate_heat);
    assert!(r.mean_rise_heated > 1.0, "rise {}", r.mean_rise_heated);
    assert!(m.totals.bonds_installed[0] > 0 && m.totals.bonds_installed[1] > 0);
    assert!(
        r.bonds_broken_heated > r.bonds_broken_other,
        "broken heated {} other {}",
        r.bonds_broken_heated,
        r.bonds_broken_other
    );
}

/// Without melting β_b of B-Eq. 40 stays β_a at any temperature, so the heated half keeps
/// its bonds over the same history that melts them with melting.
#[test]
fn bonds_do_not_melt_without_melting() {
    let mut t = tiny(30);
    t.melting = false;
    let mut m = ColumnModel::new(&t).unwrap();
    while !m.finished() {
        m.step().unwrap();
    }
    let r = m.record();
    assert!(r.mean_rise_heated > 1.0);
    assert_eq!(r.bonds_broken_heated, 0, "{r:?}");
}

/// The unbonded reduced column collapses within 3 s of the release: `E_p` drops by more than
/// 0.1 `E_p0` and the runout passes the removed plate by more than a metre.
#[test]
fn unbonded_column_collapses() {
    let mut t = reduced_column(0.0, false);
    t.collapse_time = 3.0;
    let run = run_column(&t).unwrap();
    let last = run.last().unwrap();
    assert!(last.potential_ratio < 0.9, "{last:?}");
    assert!(last.runout > t.width + 1.0, "{last:?}");
}

/// β_b = 0.1 without melting stands for 3 s after the release: corner displacement below
/// 5 cm and `E_p` within 1 % of `E_p0`.
#[test]
fn bonded_column_stands() {
    let mut t = reduced_column(0.1, false);
    t.collapse_time = 3.0;
    let run = run_column(&t).unwrap();
    let last = run.last().unwrap();
    assert!(last.corner_displacement <= 0.05, "{last:?}");
    assert!((1.0 - last.potential_ratio).abs() <= 0.01, "{last:?}");
}

/// Runs the verification case `name`, prints its rows and notes, and asserts that it passed.
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
    for n in &out.notes {
        eprintln!("{n}");
    }
    assert!(out.passed());
}

/// The quick verification case passes every row (release only; it runs three reduced
/// columns, about 15 s).
#[test]
#[cfg_attr(
    debug_assertions,
    ignore = "about 15 s in release, about twice that in the test profile"
)]
fn quick_verification_case_passes() {
    case_passes("coupling/mpm_dem_column_quick");
}

/// The full verification case passes every row (five reduced columns to the paper's times,
/// about a minute in release; run with `--ignored`).
#[test]
#[ignore = "about a minute in release: the full verification case"]
fn full_verification_case_passes() {
    case_passes("coupling/mpm_dem_column");
}

/// The paper's column (B-Sect. 5.3.3) is a valid set-up: 20 × 20 cells, 1 s of settling and
/// 20 s after the release at Δt = 10⁻⁴ s; bad fields are refused naming the field.
#[test]
fn paper_setup_is_valid_and_bad_fields_name_themselves() {
    use thm_coupling::multiscale::MultiscaleError;
    let t = ColumnTest::paper(0.1, true);
    t.validate().unwrap();
    assert_eq!(t.steps(), 210_000);
    assert_eq!(ColumnTest::paper(0.0, false).steps(), 40_000);
    let field_of = |t: &ColumnTest| match t.validate() {
        Err(MultiscaleError::InvalidParameter { field, .. }) => field,
        other => panic!("{other:?}"),
    };
    let mut bad = t;
    bad.bond_strength = -0.1;
    assert_eq!(field_of(&bad), "bond_strength");
    let mut bad = t;
    bad.melting_threshold = 0.0;
    assert_eq!(field_of(&bad), "melting_threshold");
    let mut bad = t;
    bad.height = 3.0;
    assert_eq!(field_of(&bad), "height");
    let mut bad = t;
    bad.pic_fraction = f64::NAN;
    assert_eq!(field_of(&bad), "pic_fraction");
    let mut bad = t;
    bad.runout_cells = 0;
    assert!(matches!(
        bad.validate(),
        Err(MultiscaleError::InvalidParameter {
            field: "runout_cells",
            allowed: "[1, 100000]",
            ..
        })
    ));
}

/// A rank-one fabric conductivity (one heat pipe) whose rounding left `k_xx k_yy < k_xy²` is
/// made positive semi-definite with `k_xy` changed by a few ulps only; a positive definite
/// one is unchanged.
#[test]
fn rank_one_conductivity_is_kept_positive_semi_definite() {
    use thm_coupling::multiscale::stages::psd_conductivity;
    let (a, b) = (0.7_f64, -1.3_f64);
    let k = [a * a, b * b, a * b * (1.0 + 4.0 * f64::EPSILON)];
    assert!(k[0] * k[1] < k[2] * k[2]);
    let p = psd_conductivity(k);
    assert!(p[0] * p[1] >= p[2] * p[2]);
    assert_eq!([p[0], p[1]], [k[0], k[1]]);
    assert!((p[2] - a * b).abs() <= 1e-14 * (a * b).abs());
    let pd = [2.0, 3.0, 0.5];
    assert_eq!(psd_conductivity(pd), pd);
}
