//! Verification cases of the column collapse of B-Sect. 5.3.3 ([`crate::multiscale::column`]), collected
//! by `thm_coupling::verification`.
//!
//! Both run a reduced column: 4 × 4 cells of 0.5 m with 2 × 2 points each (64 RVEs),
//! Δt = 10⁻³ s, density scaling 10⁵ (N = 3 DEM steps per MPM step), 1 s of settling; the quick
//! case with RVEs of 60 disks ([`reduced_column`]), the full one with 100 ([`full_column`]).
//! The RVE size matters for β_b = 0.02 without melting: with 60 disks (coordination number
//! 2.97 after consolidation) that column stands for 20 s, with 100 (2.88) it deforms
//! plastically and fails suddenly about 2.5 s after the release, as the paper describes; the
//! other four variants behave alike with both.
//!
//! 1. `coupling/mpm_dem_column_quick`: the unbonded column for 3 s, β_b = 0.1 without
//!    melting for 3 s, β_b = 0.1 with melting for 14 s (it fails at 12.7 s). Pass/fail: the unbonded column
//!    collapses (`E_p` drops by at least 0.1 `E_p0`, `E_k` peaks above 0.005 `E_p0` and has
//!    decayed below a tenth of its peak at the end); the bonded column without melting
//!    stands (corner displacement ≤ 0.05 m, `|1 − E_p/E_p0| ≤ 0.01`); the bonded column with
//!    melting fails (`E_p` drops by at least 0.1 `E_p0`) and loses more bonds on the heated
//!    half than on the other; heat balance stored = plate + sources to 10⁻⁹ of the summed
//!    per-step heat in every run.
//! 2. `coupling/mpm_dem_column` (not quick): the five paper variants to the paper's times
//!    (3 s, 20 s) with reported rows against B-Fig. 20: final `E_p/E_p0`, peak `E_k/E_p0`,
//!    the failure time (first time `E_p/E_p0 < 0.95`), the largest difference of `E_p/E_p0`
//!    between melting and no melting for β_b = 0.02 in the first 3 s, and the same pass/fail
//!    rows as the quick case.
//!
//! Bounds. The stored heat `Σ m c (T − T₀)` and the plate and source heats are sums of
//! per-step terms whose rounding is relative to the terms themselves: the balance is
//! compared with the sum of the magnitudes of the per-step terms, and each step contributes
//! a few ε of it, so 10⁻⁹ holds for up to ~10⁶ steps.

use thm_verify::{Case, CaseError, CaseOutput, Plot, Row, Series, SeriesRole};

use crate::multiscale::column::{ColumnModel, ColumnRecord, ColumnTest};

/// The cases of this module.
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "coupling/mpm_dem_column_quick",
            description: "B-Sect. 5.3.3 column collapse, 4 x 4 cells x 4 points, 60-disk RVEs: unbonded collapses, beta_b = 0.1 stands without melting and fails with melting (more bonds lost on the heated side), heat balance",
            quick: true,
            run: quick_case,
        },
        Case {
            name: "coupling/mpm_dem_column",
            description: "B-Sect. 5.3.3 column collapse, the five variants at 4 x 4 cells x 4 points, 60-disk RVEs, to the paper's 3 s / 20 s: energies against B-Fig. 20, failure times, heat balance",
            quick: false,
            run: full_case,
        },
    ]
}

/// The reduced column of the quick case (60-disk RVEs).
pub fn reduced_column(bond_strength: f64, melting: bool) -> ColumnTest {
    ColumnTest::reduced(bond_strength, melting, 4, 60, 1e-3, 1e5)
}

/// The reduced column of the full case and of the shipped scenario files (100-disk RVEs:
/// with 60 disks β_b = 0.02 without melting stands, see the module docs).
pub fn full_column(bond_strength: f64, melting: bool) -> ColumnTest {
    ColumnTest::reduced(bond_strength, melting, 4, 100, 1e-3, 1e5)
}

/// A run: its history (every `every` steps after the release, and the last), wall time.
#[derive(Debug)]
pub struct ColumnRun {
    /// Records from the release on, every step.
    pub history: Vec<ColumnRecord>,
    /// Wall time (s).
    pub wall: f64,
    /// The model at the end.
    pub model: ColumnModel,
}

impl ColumnRun {
    /// The last record.
    pub fn last(&self) -> Result<ColumnRecord, CaseError> {
        self.history
            .last()
            .copied()
            .ok_or_else(|| CaseError("empty history".into()))
    }
    /// Peak `E_k / E_p0`.
    pub fn peak_kinetic(&self) -> f64 {
        self.history
            .iter()
            .fold(0.0_f64, |m, r| m.max(r.kinetic_ratio))
    }
    /// Lowest `E_p / E_p0`.
    pub fn lowest_potential(&self) -> f64 {
        self.history
            .iter()
            .fold(f64::INFINITY, |m, r| m.min(r.potential_ratio))
    }
    /// First time after the release at which `E_p/E_p0 < threshold` (NaN if never).
    pub fn failure_time(&self, threshold: f64) -> f64 {
        self.history
            .iter()
            .find(|r| r.potential_ratio < threshold)
            .map_or(f64::NAN, |r| r.time_after_release)
    }
    /// Largest `|heat balance residual|` over the history.
    pub fn worst_heat_residual(&self) -> f64 {
        self.history
            .iter()
            .fold(0.0_f64, |m, r| m.max(r.heat_balance_residual.abs()))
    }
}

/// Runs `t` to its end, recording every step from the release on.
pub fn run_column(t: &ColumnTest) -> Result<ColumnRun, CaseError> {
    let start = std::time::Instant::now();
    let mut m = ColumnModel::new(t).map_err(CaseError::from_display)?;
    let mut history = Vec::new();
    while !m.finished() {
        m.step().map_err(CaseError::from_display)?;
        if m.totals.released {
            history.push(m.record());
        }
    }
    Ok(ColumnRun {
        history,
        wall: start.elapsed().as_secs_f64(),
        model: m,
    })
}

/// Pass/fail rows of the unbonded column.
fn collapse_rows(name: &str, run: &ColumnRun, out: &mut CaseOutput) -> Result<(), CaseError> {
    let last = run.last()?;
    let peak = run.peak_kinetic();
    out.rows.push(Row::at_least(
        format!("{name}: E_p drop 1 - E_p/E_p0 at the end (collapses)"),
        "-",
        1.0 - last.potential_ratio,
        0.1,
    ));
    out.rows.push(Row::at_least(
        format!("{name}: peak E_k/E_p0"),
        "-",
        peak,
        0.005,
    ));
    out.rows.push(Row::at_most(
        format!("{name}: E_k at the end over its peak (comes to rest)"),
        "-",
        last.kinetic_ratio / peak,
        0.1,
    ));
    Ok(())
}

/// Pass/fail rows of a column that stands.
fn stand_rows(name: &str, run: &ColumnRun, out: &mut CaseOutput) -> Result<(), CaseError> {
    let last = run.last()?;
    let worst = run
        .history
        .iter()
        .fold(0.0_f64, |m, r| m.max((1.0 - r.potential_ratio).abs()));
    out.rows.push(Row::at_most(
        format!("{name}: corner displacement at the end (stands)"),
        "m",
        last.corner_displacement,
        0.05,
    ));
    out.rows.push(Row::at_most(
        format!("{name}: largest |1 - E_p/E_p0|"),
        "-",
        worst,
        0.01,
    ));
    Ok(())
}

/// Pass/fail rows of a column that fails by melting.
fn melt_rows(name: &str, run: &ColumnRun, out: &mut CaseOutput) -> Result<(), CaseError> {
    let last = run.last()?;
    out.rows.push(Row::at_least(
        format!("{name}: E_p drop 1 - E_p/E_p0 at the end (fails)"),
        "-",
        1.0 - last.potential_ratio,
        0.1,
    ));
    // Bonds lost on the heated half minus those lost on the other, as fractions of the
    // installed ones, when the column fails.
    let at_failure = run
        .history
        .iter()
        .find(|r| r.potential_ratio < 0.95)
        .copied()
        .unwrap_or(last);
    let installed = run.model.totals.bonds_installed;
    let frac = |broken: u64, n: u64| broken as f64 / n.max(1) as f64;
    let heated = frac(at_failure.bonds_broken_heated, installed[0]);
    let other = frac(at_failure.bonds_broken_other, installed[1]);
    out.rows.push(Row::at_least(
        format!(
            "{name}: fraction of bonds broken on the heated half minus on the other, when E_p/E_p0 first < 0.95"
        ),
        "-",
        heated - other,
        0.1,
    ));
    out.rows.push(Row::reported(
        format!("{name}: failure time (E_p/E_p0 first < 0.95) after the release"),
        "s",
        at_failure.time_after_release,
        15.0,
    ));
    Ok(())
}

/// The heat balance row of a run.
fn heat_row(name: &str, run: &ColumnRun, out: &mut CaseOutput) {
    out.rows.push(Row::at_most(
        format!("{name}: largest |stored - plate - sources| / Σ|per-step heat|"),
        "-",
        run.worst_heat_residual(),
        1e-9,
    ));
}

fn energy_plot(name: &str, title: &str, runs: &[(String, &ColumnRun)]) -> Plot {
    let mut series = Vec::new();
    for (label, run) in runs {
        let step = (run.history.len() / 400).max(1);
        let pts: Vec<&ColumnRecord> = run.history.iter().step_by(step).collect();
        let x: Vec<f64> = pts.iter().map(|r| r.time_after_release).collect();
        series.push(Series {
            label: format!("{label} E_p/E_p0"),
            x: x.clone(),
            y: pts.iter().map(|r| r.potential_ratio).collect(),
            role: SeriesRole::Measured,
        });
        series.push(Series {
            label: format!("{label} E_k/E_p0"),
            x,
            y: pts.iter().map(|r| r.kinetic_ratio).collect(),
            role: SeriesRole::Measured,
        });
    }
    Plot {
        name: name.to_string(),
        title: title.to_string(),
        x_label: "time after release (s)".into(),
        y_label: "energy / E_p0".into(),
        series,
    }
}

fn quick_case() -> Result<CaseOutput, CaseError> {
    let mut out = CaseOutput::default();
    let mut unbonded = reduced_column(0.0, false);
    unbonded.collapse_time = 3.0;
    let mut stands = reduced_column(0.1, false);
    stands.collapse_time = 3.0;
    let mut melts = reduced_column(0.1, true);
    melts.collapse_time = 14.0;
    let a = run_column(&unbonded)?;
    collapse_rows("unbonded", &a, &mut out)?;
    heat_row("unbonded", &a, &mut out);
    let b = run_column(&stands)?;
    stand_rows("beta_b = 0.1, no melting", &b, &mut out)?;
    heat_row("beta_b = 0.1, no melting", &b, &mut out);
    let c = run_column(&melts)?;
    melt_rows("beta_b = 0.1, melting", &c, &mut out)?;
    heat_row("beta_b = 0.1, melting", &c, &mut out);
    out.notes.push(format!(
        "64 points x 60 disks, dt = 1e-3 s, density scaling 1e5; wall {:.1} s (unbonded 3 s), {:.1} s (0.1 no melting 3 s), {:.1} s (0.1 melting 14 s).",
        a.wall, b.wall, c.wall
    ));
    Ok(out)
}

fn full_case() -> Result<CaseOutput, CaseError> {
    let mut out = CaseOutput::default();
    let variants = [
        (0.0, false),
        (0.02, false),
        (0.02, true),
        (0.1, false),
        (0.1, true),
    ];
    let mut runs = Vec::new();
    for (beta, melt) in variants {
        let t = full_column(beta, melt);
        let run = run_column(&t)?;
        let name = t.label();
        let last = run.last()?;
        out.rows.push(Row::reported(
            format!("{name}: E_p/E_p0 at the end ({} s)", t.collapse_time),
            "-",
            last.potential_ratio,
            f64::NAN,
        ));
        out.rows.push(Row::reported(
            format!("{name}: peak E_k/E_p0"),
            "-",
            run.peak_kinetic(),
            f64::NAN,
        ));
        heat_row(&name, &run, &mut out);
        out.notes.push(format!("{name}: wall {:.1} s", run.wall));
        runs.push((name, beta, melt, run));
    }
    for (name, beta, melt, run) in &runs {
        match (*beta, *melt) {
            (0.0, _) => collapse_rows(name, run, &mut out)?,
            (b, false) if b >= 0.1 => stand_rows(name, run, &mut out)?,
            (b, true) if b >= 0.1 => melt_rows(name, run, &mut out)?,
            _ => {
                let t_fail = run.failure_time(0.95);
                out.rows.push(Row::reported(
                    format!("{name}: failed (1) or stood (0), E_p/E_p0 < 0.95; the paper: fails"),
                    "-",
                    if t_fail.is_nan() { 0.0 } else { 1.0 },
                    1.0,
                ));
                if t_fail.is_finite() {
                    out.rows.push(Row::reported(
                        format!("{name}: failure time (E_p/E_p0 first < 0.95) after the release"),
                        "s",
                        t_fail,
                        f64::NAN,
                    ));
                }
                out.rows.push(Row::reported(
                    format!("{name}: lowest E_p/E_p0"),
                    "-",
                    run.lowest_potential(),
                    f64::NAN,
                ));
            }
        }
    }
    // β_b = 0.02: melting and no melting "almost identical during the beginning 3 s".
    let find = |b: f64, m: bool| runs.iter().find(|r| r.1 == b && r.2 == m);
    if let (Some(nm), Some(me)) = (find(0.02, false), find(0.02, true)) {
        let diff =
            nm.3.history
                .iter()
                .zip(&me.3.history)
                .filter(|(a, _)| a.time_after_release <= 3.0)
                .fold(0.0_f64, |m, (a, b)| {
                    m.max((a.potential_ratio - b.potential_ratio).abs())
                });
        out.rows.push(Row::reported(
            "beta_b = 0.02: largest |E_p/E_p0 (melting) - E_p/E_p0 (no melting)| in the first 3 s (paper: almost identical)",
            "-",
            diff,
            0.0,
        ));
    }
    let refs: Vec<(String, &ColumnRun)> = runs.iter().map(|r| (r.0.clone(), &r.3)).collect();
    out.plots.push(energy_plot(
        "column_energies",
        "Column collapse: E_p/E_p0 and E_k/E_p0 (B-Fig. 20)",
        &refs,
    ));
    Ok(out)
}
