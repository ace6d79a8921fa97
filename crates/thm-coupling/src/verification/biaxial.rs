//! Verification cases of the biaxial test of B-Sect. 5.3.1 ([`crate::multiscale::biaxial`]), collected by
//! `thm_coupling::verification`.
//!
//! 1. `coupling/mpm_dem_biaxial_quick`: the dense specimen at 2 × 4 cells with 2 × 2 points
//!    per cell (32 RVEs of 50 disks, density-scaled by 10⁴, N = 8 DEM steps per MPM step) to
//!    3 % axial strain. Pass/fail: the heat generated `Σ Q_p V_p Δt` equals the friction work
//!    summed over all RVEs (upscaled by `V_p/V_RVE`) to 10⁻¹² relative; and, the boundaries
//!    being adiabatic, the thermal energy of the points `Σ m c (T − T₀)` equals the heat
//!    delivered to the grid (all steps but the last) to 10⁻⁹ relative.
//! 2. `coupling/mpm_dem_biaxial` (not quick): dense and loose at the same reduced size to the
//!    paper's 20 %: peak and residual stress ratio of each, softening of the dense specimen
//!    and none of the loose one, largest ΔT against the paper's "up to 1.6 °C" (reported), and
//!    the same heat rows.
//! 3. `coupling/mpm_dem_biaxial_bonded_quick`: the bonded test of B-Fig. 18 at 25 kPa, the same
//!    reduced specimen consolidated with μ = 0.5, without bonds and with β_b = 0.02, to 3 %.
//!    Pass/fail: bonds are installed, at least 1 % of them break, the bonded peak plate
//!    stress is at least 5 % above the unbonded one, and the heat rows of both.
//! 4. `coupling/mpm_dem_biaxial_bonded` (not quick): 10, 25 and 50 kPa with β_b = 0, 0.01 and
//!    0.02 to 10 %: the peak plate stress rises with β_b at each stress (pass/fail: the same
//!    packing with stronger bonds), peak and residual stresses and broken-bond fractions
//!    (reported), the heat rows of every run.
//!
//! Bounds. The heat source of a step is the step's friction heat over `V_RVE Δt`, the
//! friction work the change of the RVE's running total of B-Eq. 32: the two differ by the
//! rounding of that running total, about `ε · total / per-step heat ≤ ε · steps` relative per
//! step, below 10⁻¹² for fewer than 10⁴ steps (the full case runs 2 × 10⁴: its bound is
//! `steps × 4 ε`, 8.9 · 10⁻¹²). The thermal energy is `Σ m c (T − T₀)` with `T ≈ 20 °C` and
//! rises of about 10⁻³ K: the subtraction alone loses `ε T₀ / ΔT ≈ 10⁻¹²`, and each step's
//! increment rounds against `T`, so the bound is 10⁻⁹.

use thm_verify::{Case, CaseError, CaseOutput, Plot, Row, Series, SeriesRole};

use crate::multiscale::biaxial::{BiaxialModel, BiaxialRecord, BiaxialTest, Compaction};

/// The cases of this module.
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "coupling/mpm_dem_biaxial_quick",
            description: "B-Sect. 5.3.1 biaxial test, dense, 2 x 4 cells x 4 points, 50-disk RVEs, 3 % strain: heat generated = friction work over all RVEs; thermal energy = heat (adiabatic)",
            quick: true,
            run: quick_case,
        },
        Case {
            name: "coupling/mpm_dem_biaxial",
            description: "B-Sect. 5.3.1 biaxial test, dense and loose, 2 x 4 cells x 4 points, 50-disk RVEs, to 20 % strain: peak and residual stress ratio, softening, largest temperature rise, heat = friction work",
            quick: false,
            run: full_case,
        },
    ]
}

/// The reduced test of both cases.
pub fn reduced_test(compaction: Compaction) -> BiaxialTest {
    BiaxialTest::reduced(compaction, [2, 4], 2, 50, 1e4)
}

/// A run: its history (every step) and wall time.
#[derive(Debug)]
pub struct BiaxialRun {
    /// One record per step (after the step), the initial state first.
    pub history: Vec<BiaxialRecord>,
    /// Wall time (s).
    pub wall: f64,
    /// The model at the end.
    pub model: BiaxialModel,
}

/// Runs `t` to its target strain.
pub fn run_test(t: &BiaxialTest) -> Result<BiaxialRun, CaseError> {
    let start = std::time::Instant::now();
    let mut m = BiaxialModel::new(t).map_err(CaseError::from_display)?;
    let mut history = vec![m.record()];
    while !m.finished() {
        m.step().map_err(CaseError::from_display)?;
        history.push(m.record());
    }
    Ok(BiaxialRun {
        history,
        wall: start.elapsed().as_secs_f64(),
        model: m,
    })
}

/// The two heat rows of a run.
fn heat_rows(name: &str, run: &BiaxialRun, out: &mut CaseOutput) {
    let last = run.history.last().copied();
    let Some(r) = last else { return };
    let steps = run.model.state.step as f64;
    let bound = (4.0 * f64::EPSILON * steps).max(1e-12);
    out.rows.push(Row::relative(
        format!("{name}: heat generated Σ Q_p V_p Δt vs friction work summed over all RVEs (x V_p/V_RVE)"),
        "J/m",
        r.heat_generated,
        r.friction_work_upscaled,
        bound,
    ));
    let delivered = r.heat_generated - run.model.totals.last_heat;
    out.rows.push(Row::relative(
        format!("{name}: thermal energy Σ m c (T - T0) vs heat delivered (adiabatic)"),
        "J/m",
        r.thermal_energy,
        delivered,
        1e-9,
    ));
}

/// The quasi-static measures over a history: largest inertial number and kinetic ratio of
/// the RVEs that carry pressure, and the largest number of RVEs that do not.
fn quasi_static_rows(name: &str, history: &[BiaxialRecord], out: &mut CaseOutput) {
    let (i_max, k_max, lost) = history
        .iter()
        .fold((0.0_f64, 0.0_f64, 0usize), |(i, k, n), r| {
            (
                i.max(r.max_inertial_number),
                k.max(r.max_kinetic_ratio),
                n.max(r.rves_without_pressure),
            )
        });
    out.rows.push(Row::reported(
        format!("{name}: largest inertial number of the RVEs carrying pressure"),
        "-",
        i_max,
        1e-3,
    ));
    out.rows.push(Row::reported(
        format!("{name}: largest kinetic/elastic energy ratio of the RVEs carrying pressure"),
        "-",
        k_max,
        1e-2,
    ));
    out.rows.push(Row::reported(
        format!("{name}: most RVEs without any force-carrying contact at once"),
        "-",
        lost as f64,
        0.0,
    ));
}

fn quick_case() -> Result<CaseOutput, CaseError> {
    let mut t = reduced_test(Compaction::Dense);
    t.target_strain = 0.03;
    let run = run_test(&t)?;
    let mut out = CaseOutput::default();
    heat_rows("dense", &run, &mut out);
    let last = run.history.last().copied();
    if let Some(r) = last {
        out.rows.push(Row::reported(
            "friction work summed over all RVEs as they are (RVE thickness z_p)",
            "J",
            r.friction_work_rves,
            f64::NAN,
        ));
        out.rows.push(Row::reported(
            "stress ratio (plate) at 3 %",
            "-",
            r.stress_ratio,
            f64::NAN,
        ));
    }
    quasi_static_rows("dense", &run.history, &mut out);
    out.notes.push(format!(
        "{} MPM steps, {} points x {} disks, density scaling {}, {:.1} s wall.",
        run.model.state.step,
        run.model.state.points.len(),
        t.disks,
        t.dem_time.density_scaling,
        run.wall
    ));
    Ok(out)
}

/// Peak, residual (mean over the last 2 % of strain) and the strain at the peak of the plate
/// stress ratio.
pub fn peak_and_residual(history: &[BiaxialRecord], window: f64) -> (f64, f64, f64) {
    let (mut peak, mut at) = (f64::NEG_INFINITY, 0.0);
    for r in history {
        if r.stress_ratio > peak {
            peak = r.stress_ratio;
            at = r.axial_strain;
        }
    }
    let end = history.last().map_or(0.0, |r| r.axial_strain);
    let tail: Vec<f64> = history
        .iter()
        .filter(|r| r.axial_strain >= end - window)
        .map(|r| r.stress_ratio)
        .collect();
    let residual = tail.iter().sum::<f64>() / tail.len().max(1) as f64;
    (peak, residual, at)
}

fn full_case() -> Result<CaseOutput, CaseError> {
    let mut out = CaseOutput::default();
    let mut series = Vec::new();
    let mut vol_series = Vec::new();
    let mut dt_max = 0.0_f64;
    for c in [Compaction::Dense, Compaction::Loose] {
        let t = reduced_test(c);
        let run = run_test(&t)?;
        let name = c.name();
        let (peak, residual, at) = peak_and_residual(&run.history, 0.02);
        out.rows.push(Row::reported(
            format!("{name}: peak stress ratio (σ_yy - σ_c)/(σ_yy + σ_c), plate"),
            "-",
            peak,
            f64::NAN,
        ));
        out.rows.push(Row::reported(
            format!("{name}: axial strain at the peak"),
            "-",
            at,
            f64::NAN,
        ));
        out.rows.push(Row::reported(
            format!("{name}: residual stress ratio (mean over the last 2 % strain)"),
            "-",
            residual,
            f64::NAN,
        ));
        let (label, value, reference) = match c {
            Compaction::Dense => (
                "dense: residual / peak (softens: < 0.9)",
                residual / peak,
                0.9,
            ),
            Compaction::Loose => (
                "loose: residual / peak (no softening: > 0.95)",
                residual / peak,
                0.95,
            ),
        };
        out.rows.push(Row::reported(label, "-", value, reference));
        let last = run.history.last().copied();
        if let Some(r) = last {
            out.rows.push(Row::reported(
                format!("{name}: volumetric strain at the end (dilation positive)"),
                "-",
                r.volumetric_strain,
                f64::NAN,
            ));
            dt_max = dt_max.max(r.max_temperature_rise);
            let rho_c = run.model.case.packing.bulk_density * t.specific_heat;
            out.rows.push(Row::reported(
                format!("{name}: mean temperature rise if all plate work became heat, W/(ρ c A0)"),
                "K",
                r.plate_work / (rho_c * t.width * t.height),
                1.6,
            ));
            out.rows.push(Row::reported(
                format!("{name}: heat generated / plate work"),
                "-",
                r.heat_generated / r.plate_work,
                f64::NAN,
            ));
            out.rows.push(Row::reported(
                format!("{name}: largest temperature rise at the end"),
                "K",
                r.max_temperature_rise,
                1.6,
            ));
        }
        quasi_static_rows(name, &run.history, &mut out);
        let before: Vec<BiaxialRecord> = run
            .history
            .iter()
            .filter(|r| r.axial_strain <= at)
            .copied()
            .collect();
        quasi_static_rows(&format!("{name} up to the peak"), &before, &mut out);
        heat_rows(name, &run, &mut out);
        out.rows.push(Row::reported(
            format!("{name}: consolidated void ratio vs the paper's (400 disks)"),
            "-",
            run.model.case.packing.void_ratio,
            c.paper_void_ratio(),
        ));
        out.notes.push(format!(
            "{name}: {} MPM steps, {} points x {} disks, density scaling {}, {:.1} s wall.",
            run.model.state.step,
            run.model.state.points.len(),
            t.disks,
            t.dem_time.density_scaling,
            run.wall
        ));
        let every = (run.history.len() / 400).max(1);
        let pick = |f: fn(&BiaxialRecord) -> f64| -> (Vec<f64>, Vec<f64>) {
            run.history
                .iter()
                .step_by(every)
                .map(|r| (r.axial_strain, f(r)))
                .unzip()
        };
        let (x, y) = pick(|r| r.plate_stress);
        series.push(Series {
            label: format!("{name} (plate σ_yy)"),
            role: SeriesRole::Measured,
            x,
            y,
        });
        let (x, y) = pick(|r| r.volumetric_strain);
        vol_series.push(Series {
            label: name.into(),
            role: SeriesRole::Measured,
            x,
            y,
        });
    }
    out.rows.push(Row::reported(
        "largest temperature rise, both specimens, vs the paper's up to 1.6 °C",
        "K",
        dt_max,
        1.6,
    ));
    out.plots.push(Plot {
        name: "biaxial_stress_strain".into(),
        title: "B-Fig. 13: plate stress σ_yy vs axial strain, dense and loose".into(),
        x_label: "axial strain (-)".into(),
        y_label: "σ_yy (Pa)".into(),
        series,
    });
    out.plots.push(Plot {
        name: "biaxial_volumetric_strain".into(),
        title: "Volumetric strain (dilation positive) vs axial strain".into(),
        x_label: "axial strain (-)".into(),
        y_label: "ε_v (-)".into(),
        series: vol_series,
    });
    out.notes.push(
        "Reduced size: 2 x 4 cells x 4 points (32 RVEs of 50 disks) against the paper's 10 x 20 x 4 (800 RVEs of 400 disks); the dense/loose packings are consolidated with μ = 0.01 / 0.5 and sheared with μ = 0.5 as in the paper; their void ratios at 50 disks are reported against the paper's 400-disk values."
            .into(),
    );
    out.notes.push(
        "Softening criterion: dense softens when the residual (mean over the last 2 % strain) is below 90 % of its peak; loose does not when its residual is within 5 % of its peak. Reported, not pass/fail: 50-disk RVEs are noisy."
            .into(),
    );
    Ok(out)
}

/// The bonded biaxial test of B-Fig. 18 at the reduced size of the cases above: the loose
/// protocol consolidated to `confining_stress`, bonds of strength `bond_strength` (β_b).
pub fn reduced_bonded_test(confining_stress: f64, bond_strength: f64) -> BiaxialTest {
    let mut t = reduced_test(Compaction::Loose);
    t.confining_stress = confining_stress;
    t.bond_strength = bond_strength;
    t
}

/// Intact bonds over all RVEs of `model`.
pub fn intact_bonds(model: &BiaxialModel) -> usize {
    model
        .state
        .material
        .iter()
        .map(|p| {
            p.rve
                .contacts
                .history
                .iter()
                .filter(|h| h.bond == thm_dem::BondState::Intact)
                .count()
        })
        .sum()
}

/// Peak plate stress σ_yy over a history (Pa).
fn peak_plate_stress(history: &[BiaxialRecord]) -> f64 {
    history
        .iter()
        .fold(f64::NEG_INFINITY, |m, r| m.max(r.plate_stress))
}

/// The cases of the bonded biaxial tests (B-Fig. 18).
pub fn bonded_cases() -> Vec<Case> {
    vec![
        Case {
            name: "coupling/mpm_dem_biaxial_bonded_quick",
            description: "B-Fig. 18 bonded biaxial test at 25 kPa, 2 x 4 cells x 4 points, 50-disk RVEs, beta_b = 0 and 0.02 to 3 % strain: bonds raise the peak, bonds break, heat generated = friction work",
            quick: true,
            run: bonded_quick_case,
        },
        Case {
            name: "coupling/mpm_dem_biaxial_bonded",
            description: "B-Fig. 18 bonded biaxial tests at 10, 25, 50 kPa with beta_b = 0, 0.01, 0.02 (reduced size, to 10 % strain): the peak rises with beta_b, residual plate stress, bonds broken, heat generated = friction work",
            quick: false,
            run: bonded_full_case,
        },
    ]
}

fn bonded_quick_case() -> Result<CaseOutput, CaseError> {
    let mut out = CaseOutput::default();
    let mut peaks = Vec::new();
    for beta in [0.0, 0.02] {
        let mut t = reduced_bonded_test(25e3, beta);
        t.target_strain = 0.03;
        let initial = BiaxialModel::new(&t).map_err(CaseError::from_display)?;
        let installed = intact_bonds(&initial);
        let run = run_test(&t)?;
        let name = format!("25 kPa, β_b = {beta}");
        peaks.push(peak_plate_stress(&run.history));
        out.rows.push(Row::reported(
            format!("{name}: peak plate stress σ_yy to 3 %"),
            "Pa",
            peaks[peaks.len() - 1],
            f64::NAN,
        ));
        if beta > 0.0 {
            let intact = intact_bonds(&run.model);
            out.rows.push(Row::at_least(
                format!("{name}: bonds installed after the consolidation"),
                "-",
                installed as f64,
                1.0,
            ));
            out.rows.push(Row::at_least(
                format!("{name}: fraction of the bonds broken by 3 % strain"),
                "-",
                1.0 - intact as f64 / installed.max(1) as f64,
                0.01,
            ));
        }
        heat_rows(&name, &run, &mut out);
        out.notes.push(format!(
            "{name}: {} MPM steps, {:.1} s wall.",
            run.model.state.step, run.wall
        ));
    }
    out.rows.push(Row::at_least(
        "25 kPa: peak plate stress with β_b = 0.02 over that without bonds",
        "-",
        peaks[1] / peaks[0],
        1.05,
    ));
    Ok(out)
}

fn bonded_full_case() -> Result<CaseOutput, CaseError> {
    let mut out = CaseOutput::default();
    for stress in [10e3, 25e3, 50e3] {
        let mut series = Vec::new();
        let mut peaks = Vec::new();
        for beta in [0.0, 0.01, 0.02] {
            let mut t = reduced_bonded_test(stress, beta);
            t.target_strain = 0.1;
            let initial = BiaxialModel::new(&t).map_err(CaseError::from_display)?;
            let installed = intact_bonds(&initial);
            let run = run_test(&t)?;
            let name = format!("{} kPa, β_b = {beta}", stress / 1e3);
            let peak = peak_plate_stress(&run.history);
            peaks.push(peak);
            let end = run.history.last().map_or(0.0, |r| r.axial_strain);
            let tail: Vec<f64> = run
                .history
                .iter()
                .filter(|r| r.axial_strain >= end - 0.02)
                .map(|r| r.plate_stress)
                .collect();
            let residual = tail.iter().sum::<f64>() / tail.len().max(1) as f64;
            out.rows.push(Row::reported(
                format!("{name}: peak plate stress σ_yy"),
                "Pa",
                peak,
                f64::NAN,
            ));
            out.rows.push(Row::reported(
                format!("{name}: residual plate stress (mean over the last 2 % strain)"),
                "Pa",
                residual,
                f64::NAN,
            ));
            if beta > 0.0 {
                let intact = intact_bonds(&run.model);
                out.rows.push(Row::reported(
                    format!("{name}: fraction of the {installed} bonds broken at 10 %"),
                    "-",
                    1.0 - intact as f64 / installed.max(1) as f64,
                    f64::NAN,
                ));
            } else {
                let paper = t.paper_void_ratio().unwrap_or(f64::NAN);
                out.rows.push(Row::reported(
                    format!("{name}: consolidated void ratio vs the paper's (400 disks)"),
                    "-",
                    run.model.case.packing.void_ratio,
                    paper,
                ));
            }
            heat_rows(&name, &run, &mut out);
            out.notes.push(format!(
                "{name}: {} MPM steps, {:.1} s wall.",
                run.model.state.step, run.wall
            ));
            let every = (run.history.len() / 400).max(1);
            let (x, y) = run
                .history
                .iter()
                .step_by(every)
                .map(|r| (r.axial_strain, r.plate_stress))
                .unzip();
            series.push(Series {
                label: format!("β_b = {beta}"),
                role: SeriesRole::Measured,
                x,
                y,
            });
        }
        // The same packing with more bond strength: the peak can only rise (B-Fig. 18: "both
        // the peak and residual stresses increase with the bond strength parameter").
        for (k, (lo, hi)) in [(0.0, 0.01), (0.01, 0.02)].into_iter().enumerate() {
            out.rows.push(Row::at_least(
                format!(
                    "{} kPa: peak σ_yy with β_b = {hi} over that with β_b = {lo}",
                    stress / 1e3
                ),
                "-",
                peaks[k + 1] / peaks[k],
                1.0,
            ));
        }
        out.plots.push(Plot {
            name: format!("bonded_biaxial_{}kPa", stress / 1e3),
            title: format!(
                "B-Fig. 18: plate stress σ_yy vs axial strain at {} kPa",
                stress / 1e3
            ),
            x_label: "axial strain (-)".into(),
            y_label: "σ_yy (Pa)".into(),
            series,
        });
    }
    out.notes.push(
        "Reduced size (2 x 4 cells x 4 points, 50-disk RVEs, to 10 % strain) against the paper's 10 x 20 x 4 with 400 disks to 20 %. The packings are consolidated with μ = 0.5 (the loose protocol of B-Sect. 5.3.1; the paper calls its 10/25/50 kPa packings medium-dense with void ratios 0.251/0.240/0.232) and bonds (μ_b = 0.5, no melting) installed after the consolidation at every contact carrying force."
            .into(),
    );
    Ok(out)
}
