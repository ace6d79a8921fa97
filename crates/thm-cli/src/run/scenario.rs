//! The seam between `thm run` and a physics: the [`Scenario`] trait, and the driver that steps
//! any scenario, records its histories, frames and checkpoints, and resumes it.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use thm_io::{Column, CsvHistory, IoError, UnstructuredGrid, VtuSeries};

use super::config::{ScenarioDocument, TimeControl, from_toml};
use super::error::{ConfigError, RunError};
use super::profiles::{Profile, write_profiles};
use super::summary::{RunInfo, SummaryRow, write_summary};

/// Receives the grids of one frame: `(series name, grid)`.
pub type FrameSink<'a> = dyn FnMut(&str, &UnstructuredGrid<'_>) -> Result<(), IoError> + 'a;

/// A scenario kind: how to build a physics from its parameters, step it and observe it.
///
/// The stepper (`Self`) holds parameters and scratch; the evolving state is the separate
/// `State`, which is all a checkpoint saves: restoring it into a freshly built stepper must
/// continue the run bit for bit.
pub trait Scenario: Sized {
    /// The `kind` tag in scenario files and checkpoints.
    const KIND: &'static str;
    /// Layout version of `State` in checkpoints (bump when `State` changes).
    const STATE_VERSION: u32;
    /// The kind's own sections of the scenario file (`deny_unknown_fields`).
    type Params: DeserializeOwned + Serialize;
    /// The evolving state.
    type State: Serialize + DeserializeOwned;

    /// Validates the parameters (errors name the key path) and builds the stepper and the
    /// initial state.
    fn init(params: &Self::Params, time: &TimeControl) -> Result<(Self, Self::State), ConfigError>;

    /// Rebuilds whatever the stepper derives from the state (neighbour lists, caches) after a
    /// checkpoint was loaded. Default: nothing to rebuild.
    fn restore(&mut self, _state: &Self::State) -> Result<(), RunError> {
        Ok(())
    }

    /// Advances the state by one step; `step` is the index of the step being completed and
    /// `dt` its length \[s\].
    fn step(&mut self, state: &mut Self::State, step: u64, dt: f64) -> Result<(), RunError>;

    /// The monitored quantities (time is added by the driver as the first column).
    fn monitor_columns(&self) -> Vec<Column>;

    /// Current values of the monitored quantities, in the order of [`Self::monitor_columns`].
    fn monitor(&self, state: &Self::State, values: &mut Vec<f64>);

    /// The reference (analytical) value of monitored quantity `column` at `time`, if known;
    /// drawn against the measured history in the summary plots.
    fn reference(&self, _column: usize, _time: f64) -> Option<f64> {
        None
    }

    /// Hands the grids of the current state to `sink`, one call per series.
    fn frame(&mut self, state: &Self::State, sink: &mut FrameSink<'_>) -> Result<(), IoError>;

    /// The figures of merit reported in `summary.md` at the end of the run.
    fn summary(&self, state: &Self::State, time: f64) -> Vec<SummaryRow>;

    /// Quantities along lines through the state at `time`, written at every frame and drawn
    /// in the summary (see [`super::profiles`]). Default: none.
    fn profiles(&self, _state: &Self::State, _time: f64) -> Vec<Profile> {
        Vec::new()
    }

    /// Pictures of the state at `time`, `(name, picture)`, written at every frame as
    /// `pictures/NAME_STEP.png` and shown in the summary (see [`super::pictures`]). Names
    /// are file-name safe. Default: none.
    fn pictures(&self, _state: &Self::State, _time: f64) -> Vec<(String, thm_io::Picture)> {
        Vec::new()
    }
}

/// What a checkpoint holds besides the state: enough to refuse a foreign scenario.
#[derive(Serialize, Deserialize)]
struct RunCheckpoint<S> {
    /// The kind's parameters, resolved, as TOML text.
    params: String,
    /// The time step \[s\] (bits must match).
    dt: f64,
    /// Completed steps.
    step: u64,
    state: S,
}

/// How progress is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// A progress bar on a terminal, periodic lines otherwise.
    Auto,
    /// Nothing (tests).
    #[cfg_attr(not(test), allow(dead_code))]
    Quiet,
}

/// Where and how to run.
#[derive(Debug)]
pub struct DriveOptions<'a> {
    /// The output folder.
    pub out: PathBuf,
    /// A checkpoint to continue from.
    pub resume: Option<PathBuf>,
    /// Set (by Ctrl-C) to stop after the current step with a final checkpoint.
    pub interrupt: &'a AtomicBool,
    /// Progress display.
    pub progress: Progress,
}

/// How a run ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Reached the end time.
    Finished {
        /// Steps done.
        steps: u64,
        /// The last checkpoint.
        checkpoint: PathBuf,
    },
    /// Stopped by an interrupt, with a checkpoint to resume from.
    Interrupted {
        /// Steps done.
        steps: u64,
        /// The checkpoint written.
        checkpoint: PathBuf,
    },
}

/// File names inside the output folder.
pub const SCENARIO_FILE: &str = "scenario.toml";
/// The CSV history.
pub const HISTORY_FILE: &str = "history.csv";
/// The summary.
pub const SUMMARY_FILE: &str = "summary.md";

/// The checkpoint file of `step`.
pub fn checkpoint_path(out: &Path, step: u64) -> PathBuf {
    out.join("checkpoints")
        .join(format!("step_{step:010}.ckpt"))
}

fn folder_error(path: &Path) -> impl FnOnce(std::io::Error) -> RunError + '_ {
    move |source| RunError::OutputFolder {
        path: path.to_path_buf(),
        source,
    }
}

/// Creates the output folder and checks it can be written (without touching earlier results).
fn prepare_output(out: &Path, resuming: bool) -> Result<(), RunError> {
    std::fs::create_dir_all(out.join("checkpoints")).map_err(folder_error(out))?;
    if !resuming && out.join(SCENARIO_FILE).exists() {
        return Err(RunError::OutputNotEmpty {
            path: out.to_path_buf(),
            marker: SCENARIO_FILE.into(),
        });
    }
    let probe = out.join(".thm-write-probe");
    std::fs::write(&probe, b"").map_err(folder_error(out))?;
    std::fs::remove_file(&probe).map_err(folder_error(out))
}

/// The resolved scenario: the common sections and the kind's parameters, defaults filled in.
fn resolved_toml<P: Serialize>(
    doc: &ScenarioDocument,
    params: &P,
) -> Result<(String, String), RunError> {
    let ser = |e: toml::ser::Error| RunError::Config {
        path: PathBuf::new(),
        error: ConfigError::new("(resolved scenario)", e.to_string()),
    };
    let params_text = toml::to_string(params).map_err(ser)?;
    let mut table = toml::Table::try_from(&doc.common).map_err(ser)?;
    let params_table = toml::Table::try_from(params).map_err(ser)?;
    table.extend(params_table);
    Ok((toml::to_string(&table).map_err(ser)?, params_text))
}

/// The first key whose value differs between the resolved parameters of a checkpoint and of
/// the scenario file, in words (values cut to a short excerpt).
fn params_difference(saved: &str, now: &str) -> String {
    fn walk(prefix: &str, a: &toml::Table, b: &toml::Table) -> Option<String> {
        let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
        keys.sort();
        keys.dedup();
        for k in keys {
            let key = if prefix.is_empty() {
                k.clone()
            } else {
                format!("{prefix}.{k}")
            };
            match (a.get(k), b.get(k)) {
                (Some(toml::Value::Table(x)), Some(toml::Value::Table(y))) => {
                    if let Some(d) = walk(&key, x, y) {
                        return Some(d);
                    }
                }
                (x, y) if x != y => {
                    let show = |v: Option<&toml::Value>| {
                        v.map_or_else(|| "absent".to_string(), |v| format!("`{v}`"))
                    };
                    return Some(format!("{key} was {}, now {}", show(x), show(y)));
                }
                _ => {}
            }
        }
        None
    }
    let parse = |t: &str| t.parse::<toml::Table>().ok();
    let found = match (parse(saved), parse(now)) {
        (Some(a), Some(b)) => walk("", &a, &b),
        _ => None,
    };
    super::error::shorten(&found.unwrap_or_else(|| "the parameters differ".into()))
}

/// Reads and validates the kind's parameters and the common sections and builds the stepper
/// and the initial state: everything a run checks before it touches the disk.
fn build<S: Scenario>(
    doc: &ScenarioDocument,
) -> Result<(S::Params, TimeControl, S, S::State), ConfigError> {
    let params: S::Params = from_toml(toml::Value::Table(doc.rest.clone()), "")?;
    let tc = doc.common.time.validate()?;
    doc.common.output.validate()?;
    let (scenario, state) = S::init(&params, &tc)?;
    Ok((params, tc, scenario, state))
}

/// Checks a parsed document for kind `S` as a run does before writing anything (see
/// [`super::kinds::validate`]).
pub fn validate<S: Scenario>(doc: &ScenarioDocument) -> Result<(), ConfigError> {
    build::<S>(doc).map(|_| ())
}

/// Runs scenario kind `S` from a parsed document.
pub fn drive<S: Scenario>(
    doc: ScenarioDocument,
    file: &Path,
    opts: &DriveOptions<'_>,
) -> Result<Outcome, RunError> {
    let config = |error: ConfigError| RunError::Config {
        path: file.to_path_buf(),
        error,
    };
    let (params, tc, mut scenario, mut state) = build::<S>(&doc).map_err(config)?;
    let (resolved, params_text) = resolved_toml(&doc, &params)?;
    let out = opts.out.as_path();
    prepare_output(out, opts.resume.is_some())?;

    // Resume: the state and step of the checkpoint, checked against this scenario.
    let mut start = 0u64;
    if let Some(ckpt) = &opts.resume {
        let saved: RunCheckpoint<S::State> =
            thm_io::load_checkpoint(ckpt, S::KIND, S::STATE_VERSION)?;
        let mismatch = |detail: String| RunError::CheckpointMismatch {
            path: ckpt.clone(),
            detail,
        };
        if saved.params != params_text {
            return Err(mismatch(params_difference(&saved.params, &params_text)));
        }
        if saved.dt.to_bits() != tc.dt.to_bits() {
            return Err(mismatch(format!(
                "time.step was {} s, now {} s",
                saved.dt, tc.dt
            )));
        }
        start = saved.step;
        state = saved.state;
        scenario.restore(&state)?;
    }
    thm_io::fsutil::write_atomically(&out.join(SCENARIO_FILE), |w| {
        std::io::Write::write_all(w, resolved.as_bytes())
    })?;

    let output = &doc.common.output;
    let dt = tc.dt;
    let n = tc.n_steps.max(start);
    let time_of = |step: u64| step as f64 * dt;
    let mut columns = vec![Column::new("time", "s")];
    columns.extend(scenario.monitor_columns());
    let mut history = if opts.resume.is_some() {
        CsvHistory::resume(&out.join(HISTORY_FILE), &columns, time_of(start))?
    } else {
        CsvHistory::create(&out.join(HISTORY_FILE), &columns)?
    };
    let mut series: Vec<VtuSeries> = Vec::new();
    let encoding: thm_io::Encoding = output.encoding.into();
    let resuming = opts.resume.is_some();
    let mut row = Vec::with_capacity(columns.len());

    // Computes the monitored values and stops on a non-finite one. This is the driver's
    // backstop, run at every history row and before every checkpoint; a physics checks its own
    // stages every step and reports the exact place and step.
    let observe =
        |scenario: &S, state: &S::State, step: u64, row: &mut Vec<f64>| -> Result<(), RunError> {
            row.clear();
            row.push(time_of(step));
            scenario.monitor(state, row);
            if let Some(k) = row.iter().position(|v| !v.is_finite()) {
                return Err(RunError::Unstable {
                    quantity: columns[k].header(),
                    place: "monitored quantities".into(),
                    step,
                    time: time_of(step),
                    value: row[k],
                });
            }
            Ok(())
        };
    let mut write_frame = |scenario: &mut S, state: &S::State, step: u64| -> Result<(), RunError> {
        let t = time_of(step);
        scenario.frame(state, &mut |name: &str, grid: &UnstructuredGrid<'_>| {
            let k = match series.iter().position(|s| s.name() == name) {
                Some(k) => k,
                None => {
                    let mut s = VtuSeries::new(out, name, encoding)?;
                    if resuming {
                        s.retain_until(time_of(start))?;
                    }
                    series.push(s);
                    series.len() - 1
                }
            };
            series[k].write_frame(step, t, grid)
        })?;
        write_profiles(out, step, t, &scenario.profiles(state, t))?;
        super::pictures::write_pictures(out, step, &scenario.pictures(state, t))
    };
    let save = |state: &S::State, step: u64| -> Result<PathBuf, RunError> {
        let path = checkpoint_path(out, step);
        let ckpt = RunCheckpoint {
            params: params_text.clone(),
            dt,
            step,
            state,
        };
        thm_io::save_checkpoint(&path, S::KIND, S::STATE_VERSION, &ckpt)?;
        Ok(path)
    };

    if start == 0 {
        observe(&scenario, &state, 0, &mut row)?;
        history.push(&row)?;
        write_frame(&mut scenario, &state, 0)?;
    }
    let wall = Instant::now();
    let mut progress = ProgressDisplay::new(opts.progress, start, n, dt);
    let mut last_checkpoint = None;
    for step in start + 1..=n {
        scenario.step(&mut state, step, dt)?;
        let last = step == n;
        let checkpoint_due = output.checkpoint_every > 0 && step % output.checkpoint_every == 0;
        let interrupted = opts.interrupt.load(Ordering::Relaxed);
        // Rows follow the schedule only (an interrupted and resumed run writes the same
        // rows); on checkpoint steps the values are still checked, so a non-finite state is
        // never checkpointed.
        if step % output.history_every == 0 || last {
            observe(&scenario, &state, step, &mut row)?;
            history.push(&row)?;
        } else if checkpoint_due || interrupted {
            observe(&scenario, &state, step, &mut row)?;
        }
        if (output.frame_every > 0 && step % output.frame_every == 0) || last {
            write_frame(&mut scenario, &state, step)?;
        }
        if checkpoint_due || last || interrupted {
            history.flush()?;
            last_checkpoint = Some(save(&state, step)?);
        }
        progress.update(step);
        if interrupted && !last {
            progress.finish();
            let checkpoint = last_checkpoint.unwrap_or_default();
            let info = RunInfo {
                common: &doc.common,
                file,
                steps_done: step,
                n_steps: n,
                dt,
                wall_seconds: wall.elapsed().as_secs_f64(),
                interrupted: Some(&checkpoint),
            };
            write_summary(out, &info, &scenario, &state)?;
            return Ok(Outcome::Interrupted {
                steps: step,
                checkpoint,
            });
        }
    }
    progress.finish();
    history.flush()?;
    let checkpoint = match last_checkpoint {
        Some(c) => c,
        None => save(&state, n)?,
    };
    let info = RunInfo {
        common: &doc.common,
        file,
        steps_done: n,
        n_steps: n,
        dt,
        wall_seconds: wall.elapsed().as_secs_f64(),
        interrupted: None,
    };
    write_summary(out, &info, &scenario, &state)?;
    Ok(Outcome::Finished {
        steps: n,
        checkpoint,
    })
}

/// A progress bar on a terminal; plain lines every 10 % (at most every few seconds) otherwise.
struct ProgressDisplay {
    bar: Option<indicatif::ProgressBar>,
    plain: bool,
    n: u64,
    dt: f64,
    last_line: Instant,
    next_tenth: u64,
}

impl ProgressDisplay {
    fn new(mode: Progress, start: u64, n: u64, dt: f64) -> Self {
        let tty = std::io::stderr().is_terminal();
        let bar = (mode == Progress::Auto && tty).then(|| {
            let bar = indicatif::ProgressBar::new(n);
            let style = indicatif::ProgressStyle::with_template(
                "{bar:40} {pos}/{len} steps  {msg}  ETA {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
            bar.set_style(style);
            bar.set_position(start);
            bar
        });
        Self {
            bar,
            plain: mode == Progress::Auto && !tty,
            n,
            dt,
            last_line: Instant::now(),
            next_tenth: start * 10 / n.max(1) + 1,
        }
    }

    fn update(&mut self, step: u64) {
        let t = step as f64 * self.dt;
        let end = self.n as f64 * self.dt;
        if let Some(bar) = &self.bar {
            bar.set_position(step);
            bar.set_message(format!("t = {t:.4e} s of {end:.4e} s"));
        } else if self.plain && step * 10 >= self.next_tenth * self.n {
            self.next_tenth = step * 10 / self.n.max(1) + 1;
            if self.last_line.elapsed().as_secs_f64() >= 2.0 || step == self.n {
                self.last_line = Instant::now();
                eprintln!("step {step}/{}  t = {t:.4e} s of {end:.4e} s", self.n);
            }
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish();
        }
    }
}
