//! `summary.md`: what was run, the figures the scenario monitors, and plots of the histories.

use std::fmt::Write as _;
use std::path::Path;

use thm_verify::{Plot, Series, SeriesRole};

use crate::config::Common;
use crate::config::{HISTORY_FILE, SCENARIO_FILE, SUMMARY_FILE};
use crate::error::RunError;
use crate::profiles::{read_history, thin};

/// A figure of merit: measured at the end of the run, with its reference when one is known.
#[derive(Debug, Clone, PartialEq)]
pub struct SummaryRow {
    /// What is measured.
    pub quantity: String,
    /// Its unit.
    pub unit: String,
    /// The value at the end of the run.
    pub measured: f64,
    /// The analytical or reference value, if any.
    pub reference: Option<f64>,
}

impl SummaryRow {
    /// A row of `quantity` \[`unit`\] measured `measured`, against `reference` if any.
    pub fn new(quantity: &str, unit: &str, measured: f64, reference: Option<f64>) -> Self {
        Self {
            quantity: quantity.into(),
            unit: unit.into(),
            measured,
            reference,
        }
    }
}

/// The facts about the run shown at the top of the summary.
#[derive(Debug)]
pub struct RunInfo<'a> {
    /// The common sections of the scenario.
    pub common: &'a Common,
    /// The scenario file.
    pub file: &'a Path,
    /// Steps completed.
    pub steps_done: u64,
    /// Steps of the whole run.
    pub n_steps: u64,
    /// Time step \[s\].
    pub dt: f64,
    /// Wall-clock seconds of this invocation.
    pub wall_seconds: f64,
    /// The checkpoint written on interruption, if the run was interrupted.
    pub interrupted: Option<&'a Path>,
    /// In a distributed run: the process count and what process 0 measured.
    pub processes: Option<(
        usize,
        thm_coupling::multiscale::distributed::DistributionStats,
    )>,
}

fn file_stem(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect::<String>()
        .split('_')
        .filter(|p| !p.is_empty())
        .collect::<Vec<_>>()
        .join("_")
}

pub(crate) fn fmt(x: f64) -> String {
    if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e6) {
        format!("{x:.6e}")
    } else {
        format!("{x:.6}")
    }
}

/// Writes `summary.md` with the figures of merit `summary` (the scenario's, at the end time
/// `info.steps_done × info.dt`) and one PNG per monitored quantity: the measured history
/// against `reference(column, time)`, the monitored quantity's reference where one is known.
pub fn write_summary(
    out: &Path,
    info: &RunInfo<'_>,
    summary: &[SummaryRow],
    reference: &dyn Fn(usize, f64) -> Option<f64>,
) -> Result<(), RunError> {
    let (header, rows) = read_history(&out.join(HISTORY_FILE))?;
    let time: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    let t_end = info.steps_done as f64 * info.dt;
    let mut md = String::new();
    let title = info.common.title.as_deref().unwrap_or(&info.common.kind);
    let _ = writeln!(md, "# {title}\n");
    let _ = writeln!(
        md,
        "- scenario: `{}` (kind `{}`), resolved copy in [`{SCENARIO_FILE}`]({SCENARIO_FILE})",
        info.file.display(),
        info.common.kind
    );
    let _ = writeln!(
        md,
        "- steps: {} of {} (time step {} s), simulated time {} s",
        info.steps_done,
        info.n_steps,
        info.dt,
        fmt(t_end)
    );
    let _ = writeln!(
        md,
        "- wall-clock time of this invocation: {:.2} s",
        info.wall_seconds
    );
    match info.interrupted {
        Some(c) => {
            let _ = writeln!(
                md,
                "- **interrupted**; continue with `--resume {}`",
                c.display()
            );
        }
        None => {
            let _ = writeln!(md, "- finished");
        }
    }
    if let Some((size, st)) = &info.processes {
        let per_step = |x: f64| x / st.exchanges.max(1) as f64;
        let _ = writeln!(
            md,
            "- RVE stage on {size} processes (MPI): process 0 spent {:.3} s stepping its RVE \
             block and {:.3} s exchanging outcomes ({:.3e} s per step, waiting for the slowest \
             process included) over {} exchanges; {} synchronisations of the RVEs took {:.3} s \
             and brought {:.3} MB; imbalance, largest over mean: {:.3} by the cost of the \
             current blocks, {:.3} measured (block seconds between the last two \
             synchronisations)",
            st.compute_seconds,
            st.comm_seconds,
            per_step(st.comm_seconds),
            st.exchanges,
            st.syncs,
            st.sync_seconds,
            st.sync_bytes as f64 / 1e6,
            st.predicted_imbalance,
            st.measured_imbalance,
        );
    }
    let _ = writeln!(
        md,
        "- histories: [`{HISTORY_FILE}`]({HISTORY_FILE}); ParaView series: the `.pvd` files\n"
    );

    if !summary.is_empty() {
        let _ = writeln!(md, "## Figures at t = {} s\n", fmt(t_end));
        let _ = writeln!(md, "| quantity | unit | measured | reference | error |");
        let _ = writeln!(md, "|---|---|---|---|---|");
        for r in summary {
            let (reference, err) = match r.reference {
                Some(x) if x != 0.0 => {
                    (fmt(x), format!("{:.3e} rel", ((r.measured - x) / x).abs()))
                }
                Some(x) => (fmt(x), format!("{:.3e} abs", (r.measured - x).abs())),
                None => ("–".into(), "–".into()),
            };
            let _ = writeln!(
                md,
                "| {} | {} | {} | {reference} | {err} |",
                r.quantity,
                r.unit,
                fmt(r.measured)
            );
        }
        md.push('\n');
    }

    let _ = writeln!(md, "## Histories\n");
    for (k, name) in header.iter().enumerate().skip(1) {
        let measured: Vec<(f64, f64)> = rows.iter().map(|r| (r[0], r[k])).collect();
        let measured = thin(&measured, 60);
        let mut series = vec![Series {
            label: "measured".into(),
            role: SeriesRole::Measured,
            x: measured.iter().map(|p| p.0).collect(),
            y: measured.iter().map(|p| p.1).collect(),
        }];
        let ref_times = thin(&time, 1000);
        let reference: Vec<(f64, f64)> = ref_times
            .iter()
            .filter_map(|&t| reference(k - 1, t).map(|y| (t, y)))
            .collect();
        if !reference.is_empty() {
            series.insert(
                0,
                Series {
                    label: "analytical".into(),
                    role: SeriesRole::Reference,
                    x: reference.iter().map(|p| p.0).collect(),
                    y: reference.iter().map(|p| p.1).collect(),
                },
            );
        }
        let plot = Plot {
            name: format!("history_{}", file_stem(name)),
            title: format!("{title}: {name}"),
            x_label: "time [s]".into(),
            y_label: name.clone(),
            series,
        };
        let png = format!("{}.png", plot.name);
        thm_io::write_plot_png(&plot, &out.join(&png))?;
        let _ = writeln!(md, "![{name}]({png})\n");
    }
    crate::profiles::plot_profiles(out, info.steps_done, &mut md)?;
    crate::pictures::embed_pictures(out, info.steps_done, &mut md);
    thm_io::fsutil::write_atomically(&out.join(SUMMARY_FILE), |w| {
        std::io::Write::write_all(w, md.as_bytes())
    })?;
    Ok(())
}
