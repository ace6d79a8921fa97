//! Verification cases of this crate, collected by `cargo xtask verify`.
//!
//! 1. `mpm/semi_infinite_bar` — B-Sect. 5.1.1: temperature at x = 1 m against B-Eq. 52;
//!    dimensionless stress and displacement (B-Eq. 54) against a converged staggered-grid
//!    finite-difference solution of the dynamic thermo-elastic bar (convergence shown).
//! 2. `mpm/heated_plate` — B-Sect. 5.1.2: temperature at A, B, C against the exact product
//!    series; stresses against a finer MPM run (80 × 80 cells, 2 × 2 points per cell) and an
//!    independent staggered-grid finite-difference solution (160 and 320 cells).
//! 3. `mpm/heated_square` — B-Sect. 5.2.2 with the TM-MPM properties: centre temperature
//!    against the double series B-Eq. 59; σxx = σyy by symmetry.

use crate::analytical::{
    heated_insulated_profile, heated_square_temperature, semi_infinite_temperature,
};
use crate::error::MpmError;
use crate::reference::{thermoelastic_bar_fd, thermoelastic_plate_fd};
use crate::setups::{heated_plate, heated_square, semi_infinite_bar};
use thm_verify::{Case, CaseError, CaseOutput, Plot, Row, Series, SeriesRole};

/// All verification cases of this crate.
pub fn cases() -> Vec<Case> {
    vec![
        Case {
            name: "mpm/semi_infinite_bar",
            description: "B-Sect. 5.1.1 bar: T(1 m, t) vs B-Eq. 52; σ, u (B-Eq. 54) vs converged 1D FD",
            quick: false,
            run: run_semi_infinite_bar,
        },
        Case {
            name: "mpm/heated_plate",
            description: "B-Sect. 5.1.2 plate: T at A, B, C vs exact series; σ vs 80x80x4 MPM and 2D FD",
            quick: false,
            run: run_heated_plate,
        },
        Case {
            name: "mpm/heated_square",
            description: "B-Sect. 5.2.2 square (TM-MPM): centre T vs B-Eq. 59; σxx = σyy",
            quick: false,
            run: run_heated_square,
        },
        Case {
            name: "mpm/heated_square_convergence",
            description: "B-Sect. 5.2.2 square on 10x10 and 20x20 cells: centre T error vs B-Eq. 59 falls at second order",
            quick: true,
            run: run_heated_square_convergence,
        },
    ]
}

fn case_err(e: MpmError) -> CaseError {
    CaseError::from_display(e)
}

/// Linear interpolation of a point field along the bar at `x` (points in one row, ordered by x,
/// reference positions `(i + 1/2) h`).
fn bar_sample(values: &[f64], h: f64, x: f64) -> f64 {
    let s = x / h - 0.5;
    let i = (s.floor().max(0.0) as usize).min(values.len() - 2);
    let f = s - i as f64;
    (1.0 - f) * values[i] + f * values[i + 1]
}

/// Half-width of the time window around the passage of the stress discontinuity at x = 1 m
/// (t = 1 s) excluded from pointwise stress comparisons (s).
const FRONT_WINDOW: f64 = 0.2;

fn run_semi_infinite_bar() -> Result<CaseOutput, CaseError> {
    let mut m = semi_infinite_bar(300).map_err(case_err)?;
    let dt = 1e-4;
    let h = 6.0 / 300.0;
    let x_a = 1.0;
    let beta_t1 = 1e-6 * 100.0;
    let x0: Vec<f64> = m.state.points.position.iter().map(|p| p[0]).collect();
    let (mut ts, mut temp, mut sig, mut disp) = (vec![], vec![], vec![], vec![]);
    let steps = 30_000;
    let every = 100;
    for n in 1..=steps {
        m.mpm
            .step(&mut m.state, &m.material, dt)
            .map_err(case_err)?;
        if n % every == 0 {
            let p = &m.state.points;
            let tv: Vec<f64> = p.temperature.clone();
            let sv: Vec<f64> = p.stress.iter().map(|s| s[0]).collect();
            let uv: Vec<f64> = p
                .position
                .iter()
                .zip(&x0)
                .map(|(x, x0)| x[0] - x0)
                .collect();
            ts.push(n as f64 * dt);
            temp.push(bar_sample(&tv, h, x_a));
            sig.push(bar_sample(&sv, h, x_a) / beta_t1);
            disp.push(bar_sample(&uv, h, x_a) / beta_t1);
        }
    }
    let t_ref: Vec<f64> = ts
        .iter()
        .map(|&t| semi_infinite_temperature(x_a, t, 1.0, 0.0, 100.0))
        .collect();
    // Converged FD reference: four resolutions, the finest as reference.
    let resolutions = [300usize, 600, 1200, 2400];
    let fd: Vec<_> = resolutions
        .iter()
        .map(|&c| thermoelastic_bar_fd(6.0, c, 1.0, 1.0, 1e-6, 1.0, 100.0, 1.0, x_a, &ts))
        .collect();
    let finest = &fd[resolutions.len() - 1];
    let s_ref: Vec<f64> = finest.stress.iter().map(|s| s / beta_t1).collect();
    let u_ref: Vec<f64> = finest.displacement.iter().map(|u| u / beta_t1).collect();
    let max_abs = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f64, f64::max)
    };
    let mut out = CaseOutput::default();
    let s_scale = s_ref.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let u_scale = u_ref.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    // The stress jumps at the wave front x = c t (c = 1 m/s, Danilovskaya's solution), which
    // passes x = 1 m at t = 1 s: pointwise stress errors are measured outside that window.
    let away = |t: f64| (t - 1.0).abs() > FRONT_WINDOW;
    let rms_away = |a: &[f64], b: &[f64]| {
        let (mut s, mut n) = (0.0, 0usize);
        for ((x, y), &t) in a.iter().zip(b).zip(&ts) {
            if away(t) {
                s += (x - y) * (x - y);
                n += 1;
            }
        }
        (s / n.max(1) as f64).sqrt()
    };
    let max_away = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .zip(&ts)
            .filter(|(_, t)| away(**t))
            .map(|((x, y), _)| (x - y).abs())
            .fold(0.0f64, f64::max)
    };
    let fd_err: Vec<f64> = fd[..resolutions.len() - 1]
        .iter()
        .map(|r| max_away(&r.stress, &finest.stress) / beta_t1 / s_scale)
        .collect();
    for (k, &c) in resolutions[..resolutions.len() - 1].iter().enumerate() {
        out.notes.push(format!(
            "FD (Courant 1) convergence, {c} vs {} cells: max|Δσ|/max|σ| = {:.3e} outside the \
             front window, {:.3e} including it; max|Δu|/max|u| = {:.3e}",
            resolutions[resolutions.len() - 1],
            fd_err[k],
            max_abs(&fd[k].stress, &finest.stress) / beta_t1 / s_scale,
            max_abs(&fd[k].displacement, &finest.displacement) / beta_t1 / u_scale
        ));
    }
    out.rows.push(Row::at_most(
        "FD reference: max|σ(1200) − σ(2400)|/max|σ| outside the front window",
        "",
        fd_err[2],
        1e-3,
    ));
    out.rows.push(Row::at_most(
        "FD reference: error(1200 cells)/error(300 cells) vs 2400 cells",
        "",
        fd_err[2] / fd_err[0],
        0.25,
    ));
    for &tq in &[0.5, 1.0, 1.5, 2.0, 3.0] {
        let i = ts
            .iter()
            .position(|&t| (t - tq).abs() < 1e-9)
            .unwrap_or(ts.len() - 1);
        out.rows.push(Row::absolute(
            format!("T(x = 1 m, t = {tq} s)"),
            "°C",
            temp[i],
            t_ref[i],
            1.0,
        ));
        if away(tq) {
            out.rows.push(Row::absolute(
                format!("σx/(βT1) at x = 1 m, t = {tq} s"),
                "",
                sig[i],
                s_ref[i],
                0.1 * s_scale,
            ));
        }
        out.rows.push(Row::absolute(
            format!("ux/(βT1) at x = 1 m, t = {tq} s"),
            "",
            disp[i],
            u_ref[i],
            0.05 * u_scale,
        ));
    }
    out.rows.push(Row::at_most(
        "max over 0–3 s |T − B-Eq. 52| at x = 1 m",
        "°C",
        max_abs(&temp, &t_ref),
        0.5,
    ));
    out.rows.push(Row::at_most(
        "RMS over 0–3 s (outside front window) |σ − σ_FD| / max|σ_FD|",
        "",
        rms_away(&sig, &s_ref) / s_scale,
        0.05,
    ));
    out.rows.push(Row::at_most(
        "max over 0–3 s |u − u_FD| / max|u_FD|",
        "",
        max_abs(&disp, &u_ref) / u_scale,
        0.05,
    ));
    out.plots.push(Plot {
        name: "bar_temperature".into(),
        title: "Semi-infinite bar: temperature at x = 1 m".into(),
        x_label: "t [s]".into(),
        y_label: "T [°C]".into(),
        series: vec![
            Series {
                label: "MPM".into(),
                role: SeriesRole::Measured,
                x: ts.clone(),
                y: temp,
            },
            Series {
                label: "B-Eq. 52".into(),
                role: SeriesRole::Reference,
                x: ts.clone(),
                y: t_ref,
            },
        ],
    });
    out.plots.push(Plot {
        name: "bar_stress_displacement".into(),
        title: "Semi-infinite bar: dimensionless σ and u at x = 1 m (B-Eq. 54)".into(),
        x_label: "t [s]".into(),
        y_label: "σx/(βT1), ux/(βT1)".into(),
        series: vec![
            Series {
                label: "σ MPM".into(),
                role: SeriesRole::Measured,
                x: ts.clone(),
                y: sig,
            },
            Series {
                label: "σ FD (2400 cells)".into(),
                role: SeriesRole::Reference,
                x: ts.clone(),
                y: s_ref,
            },
            Series {
                label: "u MPM".into(),
                role: SeriesRole::Measured,
                x: ts.clone(),
                y: disp,
            },
            Series {
                label: "u FD (2400 cells)".into(),
                role: SeriesRole::Reference,
                x: ts,
                y: u_ref,
            },
        ],
    });
    out.notes.push(
        "The bar is free at both ends (σ = 0); the wave reflected at x = 6 m reaches x = 1 m \
         only after 11 s. The FD solver uses the exact temperature B-Eq. 52 (the problem is \
         uncoupled: temperature does not depend on deformation)."
            .into(),
    );
    Ok(out)
}

/// Bilinear interpolation of a point field on a regular lattice of `n × n` points of spacing
/// `d` whose first point sits at `lower + d/2` (points stored row by row).
fn lattice_sample(values: &[f64], n: usize, lower: [f64; 2], d: f64, x: [f64; 2]) -> f64 {
    let s = [(x[0] - lower[0]) / d - 0.5, (x[1] - lower[1]) / d - 0.5];
    let i = (s[0].floor().max(0.0) as usize).min(n - 2);
    let j = (s[1].floor().max(0.0) as usize).min(n - 2);
    let fx = s[0] - i as f64;
    let fy = s[1] - j as f64;
    let v = |a: usize, b: usize| values[(j + b) * n + i + a];
    (1.0 - fx) * (1.0 - fy) * v(0, 0)
        + fx * (1.0 - fy) * v(1, 0)
        + (1.0 - fx) * fy * v(0, 1)
        + fx * fy * v(1, 1)
}

/// Histories of T, σxx, σyy at probes.
struct ProbeHistory {
    time: Vec<f64>,
    /// `[probe][sample]`.
    temperature: Vec<Vec<f64>>,
    sxx: Vec<Vec<f64>>,
    syy: Vec<Vec<f64>>,
}

fn run_plate(
    cells: usize,
    per_cell: usize,
    dt: f64,
    t_end: f64,
    probes: &[[f64; 2]],
    samples: usize,
) -> Result<ProbeHistory, MpmError> {
    let mut m = heated_plate(cells, per_cell)?;
    let steps = (t_end / dt).round() as usize;
    let every = steps / samples;
    let n = cells * per_cell;
    let d = 1.0 / n as f64;
    let mut hist = ProbeHistory {
        time: vec![],
        temperature: vec![vec![]; probes.len()],
        sxx: vec![vec![]; probes.len()],
        syy: vec![vec![]; probes.len()],
    };
    for s in 1..=steps {
        m.mpm.step(&mut m.state, &m.material, dt)?;
        if s % every == 0 {
            hist.time.push(s as f64 * dt);
            let p = &m.state.points;
            let sx: Vec<f64> = p.stress.iter().map(|s| s[0]).collect();
            let sy: Vec<f64> = p.stress.iter().map(|s| s[1]).collect();
            for (k, x) in probes.iter().enumerate() {
                hist.temperature[k].push(lattice_sample(&p.temperature, n, [-0.5; 2], d, *x));
                hist.sxx[k].push(lattice_sample(&sx, n, [-0.5; 2], d, *x));
                hist.syy[k].push(lattice_sample(&sy, n, [-0.5; 2], d, *x));
            }
        }
    }
    Ok(hist)
}

/// The dilatational wave sent by the sudden heating of the left and bottom sides reaches A
/// and B at t = 0.5 m / c_p = 0.456 s (c_p = √((λ+2G)/ρ) = 1.095 m/s); the stress jumps there,
/// so stress comparisons with the FD reference stop at 0.4 s (s).
const PLATE_FRONT_TIME: f64 = 0.4;

fn run_heated_plate() -> Result<CaseOutput, CaseError> {
    let probes = [[0.0, 0.0], [0.1, 0.0], [0.1, 0.1]];
    let names = ["A", "B", "C"];
    let coarse = run_plate(40, 1, 1e-3, 0.5, &probes, 50).map_err(case_err)?;
    let fine = run_plate(80, 2, 5e-4, 0.5, &probes, 50).map_err(case_err)?;
    // Independent finite-difference references on 160 and 320 cells.
    let fd: Vec<_> = [160usize, 320]
        .iter()
        .map(|&c| thermoelastic_plate_fd(c, 1.0, 0.25, 1.0, 1e-6, 0.1, 0.5, &probes, &coarse.time))
        .collect();
    let before_front = |t: f64| t <= PLATE_FRONT_TIME;
    let max_diff_before = |a: &[f64], b: &[f64], times: &[f64]| {
        a.iter()
            .zip(b)
            .zip(times)
            .filter(|(_, t)| before_front(**t))
            .map(|((x, y), _)| (x - y).abs())
            .fold(0.0f64, f64::max)
    };
    let alpha = 0.1;
    let exact_t = |x: [f64; 2], t: f64| {
        1.0 - heated_insulated_profile(x[0] + 0.5, 1.0, alpha, t)
            * heated_insulated_profile(x[1] + 0.5, 1.0, alpha, t)
    };
    let mut out = CaseOutput::default();
    let sscale = fine
        .sxx
        .iter()
        .chain(fine.syy.iter())
        .flatten()
        .fold(0.0f64, |a, &b| a.max(b.abs()));
    // Scale for the pre-front window: the largest |σ| of the FD reference up to then.
    let fd_scale = fd[1]
        .sxx
        .iter()
        .chain(fd[1].syy.iter())
        .flat_map(|v| v.iter().zip(&fd[1].time))
        .filter(|(_, t)| before_front(**t))
        .fold(0.0f64, |a, (b, _)| a.max(b.abs()));
    let mut fd_conv = 0.0f64;
    for k in 0..probes.len() {
        fd_conv = fd_conv
            .max(max_diff_before(&fd[0].sxx[k], &fd[1].sxx[k], &fd[1].time))
            .max(max_diff_before(&fd[0].syy[k], &fd[1].syy[k], &fd[1].time));
    }
    out.rows.push(Row::at_most(
        "FD reference: max|σ(160) − σ(320)|/max|σ| at A, B, C for t ≤ 0.4 s",
        "",
        fd_conv / fd_scale,
        0.02,
    ));
    for (k, x) in probes.iter().enumerate() {
        let i = coarse.time.len() - 1;
        let t = coarse.time[i];
        let te = exact_t(*x, t);
        out.rows.push(Row::absolute(
            format!("T at {} ({}, {}) m, t = 0.5 s", names[k], x[0], x[1]),
            "°C",
            coarse.temperature[k][i],
            te,
            0.01,
        ));
        let max_dt = coarse.temperature[k]
            .iter()
            .zip(&coarse.time)
            .map(|(v, &t)| (v - exact_t(*x, t)).abs())
            .fold(0.0f64, f64::max);
        out.rows.push(Row::at_most(
            format!("max over 0–0.5 s |T − exact| at {}", names[k]),
            "°C",
            max_dt,
            0.01,
        ));
        let dsx = coarse.sxx[k]
            .iter()
            .zip(&fine.sxx[k])
            .chain(coarse.syy[k].iter().zip(&fine.syy[k]))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f64, f64::max);
        out.rows.push(Row::at_most(
            format!(
                "max over 0–0.5 s |σ(40x40) − σ(80x80x4)| / max|σ| at {}",
                names[k]
            ),
            "",
            dsx / sscale,
            0.15,
        ));
        let dfd = max_diff_before(&coarse.sxx[k], &fd[1].sxx[k], &coarse.time)
            .max(max_diff_before(&coarse.syy[k], &fd[1].syy[k], &coarse.time));
        out.rows.push(Row::at_most(
            format!(
                "max over 0–0.4 s |σ(MPM 40x40) − σ(FD 320)| / max|σ_FD| at {}",
                names[k]
            ),
            "",
            dfd / fd_scale,
            0.1,
        ));
        let tex: Vec<f64> = coarse.time.iter().map(|&t| exact_t(*x, t)).collect();
        out.plots.push(Plot {
            name: format!("plate_{}", names[k]),
            title: format!("2D plate: point {} ({}, {}) m", names[k], x[0], x[1]),
            x_label: "t [s]".into(),
            y_label: "T [°C], σ/(1e-7 Pa)".into(),
            series: vec![
                Series {
                    label: "T MPM 40x40".into(),
                    role: SeriesRole::Measured,
                    x: coarse.time.clone(),
                    y: coarse.temperature[k].clone(),
                },
                Series {
                    label: "T exact".into(),
                    role: SeriesRole::Reference,
                    x: coarse.time.clone(),
                    y: tex,
                },
                Series {
                    label: "σxx MPM 40x40".into(),
                    role: SeriesRole::Measured,
                    x: coarse.time.clone(),
                    y: coarse.sxx[k].iter().map(|s| s * 1e7).collect(),
                },
                Series {
                    label: "σxx MPM 80x80x4".into(),
                    role: SeriesRole::Reference,
                    x: fine.time.clone(),
                    y: fine.sxx[k].iter().map(|s| s * 1e7).collect(),
                },
                Series {
                    label: "σxx FD 320x320".into(),
                    role: SeriesRole::Reference,
                    x: fd[1].time.clone(),
                    y: fd[1].sxx[k].iter().map(|s| s * 1e7).collect(),
                },
                Series {
                    label: "σyy FD 320x320".into(),
                    role: SeriesRole::Reference,
                    x: fd[1].time.clone(),
                    y: fd[1].syy[k].iter().map(|s| s * 1e7).collect(),
                },
                Series {
                    label: "σyy MPM 40x40".into(),
                    role: SeriesRole::Measured,
                    x: coarse.time.clone(),
                    y: coarse.syy[k].iter().map(|s| s * 1e7).collect(),
                },
                Series {
                    label: "σyy MPM 80x80x4".into(),
                    role: SeriesRole::Reference,
                    x: fine.time.clone(),
                    y: fine.syy[k].iter().map(|s| s * 1e7).collect(),
                },
            ],
        });
    }
    out.notes.push(
        "The origin is the plate centre (A = (0, 0) is 'the plate center' of B-Sect. 5.1.2). \
         The temperature problem separates: T = 1 − θ(x)θ(y), θ the 1D heated/insulated series."
            .into(),
    );
    Ok(out)
}

fn run_heated_square() -> Result<CaseOutput, CaseError> {
    run_square(40, 1.0)
}

/// Centre temperature of the square on `cells × cells` at `t_end`, with the series value.
fn square_centre_temperature(cells: usize, t_end: f64) -> Result<(f64, f64), CaseError> {
    let mut m = heated_square(cells).map_err(case_err)?;
    let dt = 1e-4;
    let steps = (t_end / dt).round() as usize;
    for _ in 0..steps {
        m.mpm
            .step(&mut m.state, &m.material, dt)
            .map_err(case_err)?;
    }
    let d = 1.0 / cells as f64;
    let t = steps as f64 * dt;
    Ok((
        lattice_sample(&m.state.points.temperature, cells, [0.0; 2], d, [0.5, 0.5]),
        heated_square_temperature(0.5, 0.5, 1.0, 0.1, t, 0.0, 100.0),
    ))
}

/// Quick: the square on 10 × 10 and 20 × 20 cells to 0.25 s; the centre-temperature error
/// against B-Eq. 59 must fall at second order (ratio ≈ 4 per halving of the cell size).
fn run_heated_square_convergence() -> Result<CaseOutput, CaseError> {
    let t_end = 0.25;
    let (t10, r10) = square_centre_temperature(10, t_end)?;
    let (t20, r20) = square_centre_temperature(20, t_end)?;
    let (e10, e20) = ((t10 - r10).abs(), (t20 - r20).abs());
    let mut out = CaseOutput::default();
    out.rows.push(Row::absolute(
        "T centre, 20x20 cells, t = 0.25 s",
        "°C",
        t20,
        r20,
        2.0,
    ));
    out.rows.push(Row::at_least(
        "error ratio |T − B-Eq. 59| 10x10 / 20x20 (≥ 3: about second order or better)",
        "",
        e10 / e20,
        3.0,
    ));
    out.notes.push(format!(
        "centre T at 0.25 s: 10x10 {t10:.4}, 20x20 {t20:.4}, series {r20:.4} °C"
    ));
    Ok(out)
}

fn run_square(cells: usize, t_end: f64) -> Result<CaseOutput, CaseError> {
    let mut m = heated_square(cells).map_err(case_err)?;
    let dt = 1e-4;
    let steps = (t_end / dt).round() as usize;
    let every = 100;
    let d = 1.0 / cells as f64;
    let (mut ts, mut tc, mut tref, mut sx, mut sy) = (vec![], vec![], vec![], vec![], vec![]);
    for s in 1..=steps {
        m.mpm
            .step(&mut m.state, &m.material, dt)
            .map_err(case_err)?;
        if s % every == 0 {
            let t = s as f64 * dt;
            let p = &m.state.points;
            let sxx: Vec<f64> = p.stress.iter().map(|s| s[0]).collect();
            let syy: Vec<f64> = p.stress.iter().map(|s| s[1]).collect();
            ts.push(t);
            tc.push(lattice_sample(
                &p.temperature,
                cells,
                [0.0; 2],
                d,
                [0.5, 0.5],
            ));
            tref.push(heated_square_temperature(0.5, 0.5, 1.0, 0.1, t, 0.0, 100.0));
            sx.push(lattice_sample(&sxx, cells, [0.0; 2], d, [0.5, 0.5]));
            sy.push(lattice_sample(&syy, cells, [0.0; 2], d, [0.5, 0.5]));
        }
    }
    let mut out = CaseOutput::default();
    for tq in [0.25, 0.5, 1.0].into_iter().filter(|&t| t <= t_end + 1e-9) {
        let i = ts
            .iter()
            .position(|&t| (t - tq).abs() < 1e-9)
            .unwrap_or(ts.len() - 1);
        out.rows.push(Row::absolute(
            format!("T centre, {cells}x{cells} cells, t = {tq} s"),
            "°C",
            tc[i],
            tref[i],
            1.0,
        ));
    }
    let smax = sx.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let asym = sx
        .iter()
        .zip(&sy)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f64, f64::max);
    out.rows.push(Row::at_most(
        "max over the run |σxx − σyy| / max|σxx| at the centre",
        "",
        asym / smax,
        1e-9,
    ));
    out.plots.push(Plot {
        name: format!("square_centre_{cells}"),
        title: "Heated square: centre temperature".into(),
        x_label: "t [s]".into(),
        y_label: "T [°C]".into(),
        series: vec![
            Series {
                label: format!("MPM {cells}x{cells}"),
                role: SeriesRole::Measured,
                x: ts.clone(),
                y: tc,
            },
            Series {
                label: "B-Eq. 59".into(),
                role: SeriesRole::Reference,
                x: ts.clone(),
                y: tref,
            },
        ],
    });
    out.plots.push(Plot {
        name: format!("square_centre_stress_{cells}"),
        title: "Heated square: centre stress (MPM)".into(),
        x_label: "t [s]".into(),
        y_label: "σ [Pa]".into(),
        series: vec![
            Series {
                label: "σxx".into(),
                role: SeriesRole::Measured,
                x: ts.clone(),
                y: sx,
            },
            Series {
                label: "σyy".into(),
                role: SeriesRole::Measured,
                x: ts,
                y: sy,
            },
        ],
    });
    out.notes.push(
        "B-Eq. 59 is garbled in the source: the exponent is read as \
         π²((2m+1)² + (2n+1)²) k t / (L² ρ c), the only reading that solves the heat equation \
         with the sine modes of the sum."
            .into(),
    );
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs each case and prints its rows (for development: `--ignored --nocapture`).
    #[test]
    #[ignore]
    fn print_cases() {
        let filter = std::env::var("MPM_CASE").unwrap_or_default();
        for c in cases().into_iter().filter(|c| c.name.contains(&filter)) {
            let t = std::time::Instant::now();
            let out = (c.run)().unwrap();
            println!("== {} ({:.1} s)", c.name, t.elapsed().as_secs_f64());
            for r in &out.rows {
                println!(
                    "{:70} m={:+.5e} r={:+.5e} err={:.3e} tol={:.3e} {}",
                    r.quantity,
                    r.measured,
                    r.reference,
                    r.error,
                    r.tolerance,
                    if r.pass { "ok" } else { "FAIL" }
                );
            }
            for n in &out.notes {
                println!("  note: {n}");
            }
        }
    }
}
