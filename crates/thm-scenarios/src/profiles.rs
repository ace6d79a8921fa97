//! Profiles: a quantity along a line through the state (the temperature on a bar's
//! centreline, say), written at every frame as `profiles/NAME_STEP.csv` and drawn in the
//! summary, one curve per time, as the papers draw their profile figures.
//!
//! One file per frame step: a resumed run rewrites the files of the steps it repeats with the
//! same bits, and the summary draws only the steps up to the end of the run it describes.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use thm_io::IoError;
use thm_verify::{Plot, Series, SeriesRole};

use crate::error::RunError;

/// The folder of the profile files inside the output folder.
pub const PROFILE_DIR: &str = "profiles";

/// A quantity along a line through the state at one time.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    /// File stem and, with `_` read as spaces, the plot title: ASCII letters, digits and `_`
    /// (e.g. `centreline_temperature`).
    pub name: String,
    /// The position along the line, with its unit (e.g. `y [m]`); no commas.
    pub x_label: String,
    /// The quantity, with its unit (e.g. `T [K]`); no commas.
    pub y_label: String,
    /// Positions.
    pub x: Vec<f64>,
    /// Values at `x`.
    pub y: Vec<f64>,
    /// A reference (analytical) value at each `x` and what it is, when one is known.
    pub reference: Option<(String, Vec<f64>)>,
}

fn file_of(out: &Path, name: &str, step: u64) -> PathBuf {
    out.join(PROFILE_DIR).join(format!("{name}_{step:010}.csv"))
}

pub(crate) fn io_error(
    path: &Path,
    action: &'static str,
) -> impl FnOnce(std::io::Error) -> IoError {
    let path = path.to_path_buf();
    move |source| IoError::File {
        path,
        action,
        source,
    }
}

/// Writes the profiles of one frame (`time` of step `step`).
pub fn write_profiles(
    out: &Path,
    step: u64,
    time: f64,
    profiles: &[Profile],
) -> Result<(), RunError> {
    if profiles.is_empty() {
        return Ok(());
    }
    let dir = out.join(PROFILE_DIR);
    std::fs::create_dir_all(&dir).map_err(io_error(&dir, "create"))?;
    for p in profiles {
        let mut text = format!("time [s],{},{}", p.x_label, p.y_label);
        if let Some((label, _)) = &p.reference {
            let _ = write!(text, ",{label}");
        }
        text.push('\n');
        for (i, (&x, &y)) in p.x.iter().zip(&p.y).enumerate() {
            let _ = write!(text, "{time},{x},{y}");
            if let Some((_, r)) = &p.reference {
                let _ = write!(text, ",{}", r.get(i).copied().unwrap_or(f64::NAN));
            }
            text.push('\n');
        }
        thm_io::fsutil::write_atomically(&file_of(out, &p.name, step), |w| {
            std::io::Write::write_all(w, text.as_bytes())
        })?;
    }
    Ok(())
}

/// One profile file read back.
struct ProfileFile {
    time: f64,
    header: Vec<String>,
    columns: Vec<Vec<f64>>,
}

fn read_profile(path: &Path) -> Result<ProfileFile, RunError> {
    let (header, rows) = read_history(path)?;
    let columns: Vec<Vec<f64>> = (0..header.len())
        .map(|k| {
            rows.iter()
                .map(|r| r.get(k).copied().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    let time = rows
        .first()
        .and_then(|r| r.first())
        .copied()
        .unwrap_or(f64::NAN);
    Ok(ProfileFile {
        time,
        header,
        columns,
    })
}

/// The profile files under `out`, by name, with their steps (at most `last_step`), sorted.
fn profile_files(out: &Path, last_step: u64) -> BTreeMap<String, Vec<(u64, PathBuf)>> {
    step_files(&out.join(PROFILE_DIR), "csv", last_step)
}

/// The files `NAME_STEP.EXT` of `dir` with `STEP <= last_step`, by name, in step order (the
/// per-frame files of profiles and pictures; later steps are left by an interrupted run).
pub(crate) fn step_files(
    dir: &Path,
    ext: &str,
    last_step: u64,
) -> BTreeMap<String, Vec<(u64, PathBuf)>> {
    let mut by_name: BTreeMap<String, Vec<(u64, PathBuf)>> = BTreeMap::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return by_name;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let Some(stem) = path
            .extension()
            .filter(|e| *e == ext)
            .and_then(|_| path.file_stem())
            .and_then(|s| s.to_str())
        else {
            continue;
        };
        let Some((name, step)) = stem.rsplit_once('_') else {
            continue;
        };
        if let Ok(step) = step.parse::<u64>()
            && step <= last_step
        {
            by_name
                .entry(name.to_string())
                .or_default()
                .push((step, path.clone()));
        }
    }
    for files in by_name.values_mut() {
        files.sort();
    }
    by_name
}

/// Plots the profiles of steps up to `last_step` into `out` and appends them to the summary:
/// per profile, one plot of (at most) five times spread over the run and, where a reference is
/// known, one plot per such time of the profile against its reference.
pub fn plot_profiles(out: &Path, last_step: u64, md: &mut String) -> Result<(), RunError> {
    let by_name = profile_files(out, last_step);
    if by_name.is_empty() {
        return Ok(());
    }
    let _ = writeln!(
        md,
        "## Profiles\n\nEvery frame's profiles are in [`{PROFILE_DIR}/`]({PROFILE_DIR}/) as CSV.\n"
    );
    for (name, files) in &by_name {
        let chosen = thin(files, 5);
        let mut read = Vec::with_capacity(chosen.len());
        for (_, path) in &chosen {
            read.push(read_profile(path)?);
        }
        let Some(first) = read.first() else {
            continue;
        };
        let (x_label, y_label) = (
            first.header.get(1).cloned().unwrap_or_default(),
            first.header.get(2).cloned().unwrap_or_default(),
        );
        let title = name.replace('_', " ");
        let at = |f: &ProfileFile| format!("t = {} s", f.time);
        let measured = |f: &ProfileFile| Series {
            label: at(f),
            role: SeriesRole::Measured,
            x: f.columns.get(1).cloned().unwrap_or_default(),
            y: f.columns.get(2).cloned().unwrap_or_default(),
        };
        let mut plots = vec![Plot {
            name: format!("profile_{name}"),
            title: title.clone(),
            x_label: x_label.clone(),
            y_label: y_label.clone(),
            series: read.iter().map(measured).collect(),
        }];
        for ((step, _), f) in chosen
            .iter()
            .zip(&read)
            .filter(|(_, f)| f.columns.len() > 3)
        {
            plots.push(Plot {
                name: format!("profile_{name}_{step}"),
                title: format!("{title}, {}", at(f)),
                x_label: x_label.clone(),
                y_label: y_label.clone(),
                series: vec![
                    Series {
                        label: f.header.get(3).cloned().unwrap_or_default(),
                        role: SeriesRole::Reference,
                        x: f.columns[1].clone(),
                        y: f.columns[3].clone(),
                    },
                    measured(f),
                ],
            });
        }
        for plot in &plots {
            // A profile can be all non-finite early in a run (a ratio before its reference
            // exists): say so instead of failing the summary.
            let drawable = plot.series.iter().any(|s| {
                s.x.iter()
                    .zip(&s.y)
                    .any(|(x, y)| x.is_finite() && y.is_finite())
            });
            if !drawable {
                let _ = writeln!(md, "- {}: no finite value to draw yet\n", plot.title);
                continue;
            }
            let png = format!("{}.png", plot.name);
            thm_io::write_plot_png(plot, &out.join(&png))?;
            let _ = writeln!(md, "![{}]({png})\n", plot.title);
        }
    }
    Ok(())
}

/// Reads a CSV written by the driver (a history or a profile): header cells and rows.
pub(crate) fn read_history(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), RunError> {
    let text = std::fs::read_to_string(path).map_err(|e| thm_io::IoError::File {
        path: path.to_path_buf(),
        action: "read",
        source: e,
    })?;
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or("")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    Ok((header, rows))
}

/// Every `k`-th element so that at most `max` remain (always keeping the last).
pub(crate) fn thin<T: Clone>(v: &[T], max: usize) -> Vec<T> {
    let k = v.len().div_ceil(max.max(1)).max(1);
    let mut out: Vec<T> = v.iter().step_by(k).cloned().collect();
    if let Some(last) = v.last()
        && !(v.len() - 1).is_multiple_of(k)
    {
        out.push(last.clone());
    }
    out
}
