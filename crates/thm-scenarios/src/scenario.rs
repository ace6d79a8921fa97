//! The seam between `thm run` and a physics: the [`Scenario`] trait, and the driver that steps
//! any scenario, records its histories, frames and checkpoints, and resumes it.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use thm_coupling::multiscale::{Collective, Distribution, SharedDistribution};
use thm_io::{Column, CsvHistory, IoError, UnstructuredGrid, VtuSeries};

use crate::arrays::{StateArray, not_writable};
use crate::config::{
    Common, HISTORY_FILE, SCENARIO_FILE, ScenarioDocument, TimeControl, from_toml,
};
use crate::error::{ConfigError, RunError};
use crate::profiles::{Profile, write_profiles};
use crate::summary::{RunInfo, SummaryRow, write_summary};

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
    /// in the summary (see [`crate::profiles`]). Default: none.
    fn profiles(&self, _state: &Self::State, _time: f64) -> Vec<Profile> {
        Vec::new()
    }

    /// Pictures of the state at `time`, `(name, picture)`, written at every frame as
    /// `pictures/NAME_STEP.png` and shown in the summary (see [`crate::pictures`]). Names
    /// are file-name safe. Default: none.
    fn pictures(&self, _state: &Self::State, _time: f64) -> Vec<(String, thm_io::Picture)> {
        Vec::new()
    }

    /// The state's named arrays (positions, temperatures, pressures, stresses), for front
    /// ends that read the state between steps. Default: none.
    fn arrays<'s>(&'s self, _state: &'s Self::State) -> Vec<StateArray<'s>> {
        Vec::new()
    }

    /// Spreads the kind's RVE stage over the processes of `distribution` (`mpirun -np N thm
    /// run`; see `thm_coupling::multiscale::distributed`). Default: the kind has none, refused.
    fn distribute(&mut self, distribution: &SharedDistribution) -> Result<(), RunError> {
        Err(RunError::NotDistributable {
            kind: Self::KIND,
            processes: thm_coupling::multiscale::distributed::lock(distribution)
                .collective()
                .size(),
        })
    }

    /// Brings every process's RVEs up to date in a distributed run; the driver calls it, on
    /// every process, before anything reads the RVEs' disks (a frame, a checkpoint, the
    /// summary). Default: nothing to bring.
    fn synchronise(&mut self, _state: &mut Self::State) -> Result<(), RunError> {
        Ok(())
    }

    /// Replaces the values of the writable array `name` between steps (a load, a
    /// temperature). What is written is part of the state, so a checkpoint keeps it. Errors
    /// name the array and the allowed range. Default: no writable arrays.
    fn set_array(
        &mut self,
        _state: &mut Self::State,
        name: &str,
        _values: &[f64],
    ) -> Result<(), RunError> {
        Err(not_writable(name, &[]))
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
    /// Nothing (tests, and the processes of a distributed run other than 0).
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
    /// The processes of a distributed run (`mpirun -np N thm run`, feature `mpi`); `None`
    /// runs on this process alone.
    pub processes: Option<Arc<dyn Collective>>,
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
    crate::error::shorten(&found.unwrap_or_else(|| "the parameters differ".into()))
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
/// [`crate::registry::validate`]).
pub fn validate<S: Scenario>(doc: &ScenarioDocument) -> Result<(), ConfigError> {
    build::<S>(doc).map(|_| ())
}

/// A run of scenario kind `S` that is stepped from outside: opened (validated, output folder
/// prepared, resumed if asked), advanced one step at a time on the file's output schedule,
/// checkpointed on request and finished with its summary. `thm run` ([`drive`]) and the Python
/// module step the same object, so both write the same files bit for bit.
pub struct Run<S: Scenario> {
    common: Common,
    file: PathBuf,
    out: PathBuf,
    params_text: String,
    dt: f64,
    n: u64,
    start: u64,
    step: u64,
    scenario: S,
    state: S::State,
    columns: Vec<Column>,
    /// `None` on the processes of a distributed run other than 0, which write nothing.
    history: Option<CsvHistory>,
    series: Vec<VtuSeries>,
    parallel: Option<Parallel>,
    synced_at: Option<u64>,
    encoding: thm_io::Encoding,
    row: Vec<f64>,
    wall: Instant,
    last_checkpoint: Option<PathBuf>,
}

/// A distributed run's processes and its RVE stage.
struct Parallel {
    collective: Arc<dyn Collective>,
    distribution: SharedDistribution,
}

impl<S: Scenario> std::fmt::Debug for Run<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Run")
            .field("kind", &S::KIND)
            .field("file", &self.file)
            .field("out", &self.out)
            .field("step", &self.step)
            .field("n_steps", &self.n)
            .finish_non_exhaustive()
    }
}

impl<S: Scenario> Run<S> {
    /// Validates the document, prepares `out` (a fresh run refuses a folder holding a run),
    /// loads `resume` if given (refusing a checkpoint of another scenario), writes the resolved
    /// scenario and, on a fresh run, the first history row and frame.
    pub fn open(
        doc: ScenarioDocument,
        file: &Path,
        out: &Path,
        resume: Option<&Path>,
    ) -> Result<Self, RunError> {
        Self::open_on(doc, file, out, resume, None)
    }

    /// [`Run::open`] on the processes of `processes` (every process calls it): each builds
    /// the scenario and loads the checkpoint, the kind spreads its RVE stage over them
    /// ([`Scenario::distribute`]), and only process 0 writes. If any process fails to open,
    /// every process returns an error (the failing one its cause).
    pub fn open_on(
        doc: ScenarioDocument,
        file: &Path,
        out: &Path,
        resume: Option<&Path>,
        processes: Option<Arc<dyn Collective>>,
    ) -> Result<Self, RunError> {
        let opened = Self::open_here(doc, file, out, resume, processes.clone());
        if let Some(c) = &processes
            && let Some(process) = c.first_failed(opened.is_err())
            && opened.is_ok()
        {
            return Err(RunError::OtherProcess { process });
        }
        opened
    }

    fn open_here(
        doc: ScenarioDocument,
        file: &Path,
        out: &Path,
        resume: Option<&Path>,
        processes: Option<Arc<dyn Collective>>,
    ) -> Result<Self, RunError> {
        let config = |error: ConfigError| RunError::Config {
            path: file.to_path_buf(),
            error,
        };
        let (params, tc, mut scenario, mut state) = build::<S>(&doc).map_err(config)?;
        let (resolved, params_text) = resolved_toml(&doc, &params)?;
        let parallel = match processes {
            Some(collective) => {
                let distribution = Distribution::shared(Arc::clone(&collective));
                scenario.distribute(&distribution)?;
                Some(Parallel {
                    collective,
                    distribution,
                })
            }
            None => None,
        };
        let primary = parallel.as_ref().is_none_or(|p| p.collective.rank() == 0);
        if primary {
            prepare_output(out, resume.is_some())?;
        }

        // Resume: the state and step of the checkpoint, checked against this scenario.
        let mut start = 0u64;
        if let Some(ckpt) = resume {
            let saved: RunCheckpoint<S::State> =
                thm_io::load_checkpoint(ckpt, S::KIND, S::STATE_VERSION)?;
            let mismatch = |detail: String| RunError::CheckpointMismatch {
                path: ckpt.to_path_buf(),
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
        if primary {
            thm_io::fsutil::write_atomically(&out.join(SCENARIO_FILE), |w| {
                std::io::Write::write_all(w, resolved.as_bytes())
            })?;
        }

        let dt = tc.dt;
        let mut columns = vec![Column::new("time", "s")];
        columns.extend(scenario.monitor_columns());
        let history = match (primary, resume.is_some()) {
            (false, _) => None,
            (true, true) => Some(CsvHistory::resume(
                &out.join(HISTORY_FILE),
                &columns,
                start as f64 * dt,
            )?),
            (true, false) => Some(CsvHistory::create(&out.join(HISTORY_FILE), &columns)?),
        };
        let encoding: thm_io::Encoding = doc.common.output.encoding.into();
        let row = Vec::with_capacity(columns.len());
        let mut run = Self {
            common: doc.common,
            file: file.to_path_buf(),
            out: out.to_path_buf(),
            params_text,
            dt,
            n: tc.n_steps.max(start),
            start,
            step: start,
            scenario,
            state,
            columns,
            history,
            series: Vec::new(),
            parallel,
            synced_at: None,
            encoding,
            row,
            wall: Instant::now(),
            last_checkpoint: None,
        };
        if start == 0 {
            run.observe()?;
            run.push_row()?;
            run.write_frame()?;
        }
        run.wall = Instant::now();
        Ok(run)
    }

    fn time_of(&self, step: u64) -> f64 {
        step as f64 * self.dt
    }

    /// Steps completed (the checkpoint's step after a resume).
    pub fn steps_done(&self) -> u64 {
        self.step
    }

    /// Steps of the whole run.
    pub fn n_steps(&self) -> u64 {
        self.n
    }

    /// The time step \[s\].
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The stepper (parameters and scratch).
    pub fn scenario(&self) -> &S {
        &self.scenario
    }

    /// The state.
    pub fn state(&self) -> &S::State {
        &self.state
    }

    /// Computes the monitored values into `self.row` and stops on a non-finite one. This is
    /// the driver's backstop, run at every history row and before every checkpoint; a physics
    /// checks its own stages every step and reports the exact place and step.
    fn observe(&mut self) -> Result<(), RunError> {
        let step = self.step;
        self.row.clear();
        self.row.push(self.time_of(step));
        self.scenario.monitor(&self.state, &mut self.row);
        if let Some(k) = self.row.iter().position(|v| !v.is_finite()) {
            return Err(RunError::Unstable {
                quantity: self.columns[k].header(),
                place: "monitored quantities".into(),
                step,
                time: self.time_of(step),
                value: self.row[k],
            });
        }
        Ok(())
    }

    /// Whether this process writes the outputs (always, unless it is a distributed run's
    /// process other than 0).
    pub fn is_primary(&self) -> bool {
        self.history.is_some()
    }

    fn push_row(&mut self) -> Result<(), RunError> {
        if let Some(h) = &mut self.history {
            h.push(&self.row)?;
        }
        Ok(())
    }

    /// In a distributed run, brings every process's RVEs up to date (once per step: a frame
    /// and a checkpoint of the same step share it).
    fn synchronise(&mut self) -> Result<(), RunError> {
        if self.parallel.is_some() && self.synced_at != Some(self.step) {
            self.scenario.synchronise(&mut self.state)?;
            self.synced_at = Some(self.step);
        }
        Ok(())
    }

    fn write_frame(&mut self) -> Result<(), RunError> {
        self.synchronise()?;
        if !self.is_primary() {
            return Ok(());
        }
        let (step, t) = (self.step, self.time_of(self.step));
        let (out, encoding, resume_time) = (&self.out, self.encoding, self.time_of(self.start));
        let resuming = self.start > 0;
        let series = &mut self.series;
        self.scenario.frame(
            &self.state,
            &mut |name: &str, grid: &UnstructuredGrid<'_>| {
                let k = match series.iter().position(|s| s.name() == name) {
                    Some(k) => k,
                    None => {
                        let mut s = VtuSeries::new(out, name, encoding)?;
                        if resuming {
                            s.retain_until(resume_time)?;
                        }
                        series.push(s);
                        series.len() - 1
                    }
                };
                series[k].write_frame(step, t, grid)
            },
        )?;
        write_profiles(out, step, t, &self.scenario.profiles(&self.state, t))?;
        crate::pictures::write_pictures(out, step, &self.scenario.pictures(&self.state, t))
    }

    fn save(&mut self) -> Result<PathBuf, RunError> {
        self.synchronise()?;
        let path = checkpoint_path(&self.out, self.step);
        let Some(history) = &mut self.history else {
            self.last_checkpoint = Some(path.clone());
            return Ok(path);
        };
        history.flush()?;
        let ckpt = RunCheckpoint {
            params: self.params_text.clone(),
            dt: self.dt,
            step: self.step,
            state: &self.state,
        };
        thm_io::save_checkpoint(&path, S::KIND, S::STATE_VERSION, &ckpt)?;
        self.last_checkpoint = Some(path.clone());
        Ok(path)
    }

    /// Advances one step and records what the output schedule asks for at it (history row,
    /// frame, checkpoint; all three at the last step). `interrupted` adds a checkpoint.
    /// Refuses to step past the end time.
    pub fn advance(&mut self, interrupted: bool) -> Result<(), RunError> {
        if self.step >= self.n {
            return Err(RunError::Ended { steps: self.n });
        }
        let step = self.step + 1;
        self.scenario.step(&mut self.state, step, self.dt)?;
        self.step = step;
        let output = &self.common.output;
        let (history_every, frame_every, checkpoint_every) = (
            output.history_every,
            output.frame_every,
            output.checkpoint_every,
        );
        let last = step == self.n;
        let checkpoint_due = checkpoint_every > 0 && step.is_multiple_of(checkpoint_every);
        // Rows follow the schedule only (an interrupted and resumed run writes the same
        // rows); on checkpoint steps the values are still checked, so a non-finite state is
        // never checkpointed.
        if step.is_multiple_of(history_every) || last {
            self.observe()?;
            self.push_row()?;
        } else if checkpoint_due || interrupted {
            self.observe()?;
        }
        if (frame_every > 0 && step.is_multiple_of(frame_every)) || last {
            self.write_frame()?;
        }
        if checkpoint_due || last || interrupted {
            self.save()?;
        }
        Ok(())
    }

    /// Writes a checkpoint of the current step (after checking the monitored values are
    /// finite) and returns its path; the run goes on.
    pub fn checkpoint(&mut self) -> Result<PathBuf, RunError> {
        self.observe()?;
        self.save()
    }

    /// The monitored values now: `(headers "name [unit]", values)`, time first.
    pub fn monitor(&mut self) -> (Vec<String>, Vec<f64>) {
        self.row.clear();
        self.row.push(self.time_of(self.step));
        self.scenario.monitor(&self.state, &mut self.row);
        (
            self.columns.iter().map(Column::header).collect(),
            self.row.clone(),
        )
    }

    /// The state's named arrays (see [`Scenario::arrays`]).
    pub fn arrays(&self) -> Vec<StateArray<'_>> {
        self.scenario.arrays(&self.state)
    }

    /// Replaces the values of writable array `name` (see [`Scenario::set_array`]).
    pub fn set_array(&mut self, name: &str, values: &[f64]) -> Result<(), RunError> {
        self.scenario.set_array(&mut self.state, name, values)
    }

    /// Ends the run: at the end time, the last checkpoint (written at the last step) and the
    /// summary; before it, a checkpoint of the current step and the summary of an interrupted
    /// run, which `--resume` continues.
    pub fn finish(&mut self) -> Result<Outcome, RunError> {
        let step = self.step;
        if step < self.n {
            let checkpoint = match &self.last_checkpoint {
                Some(c) if *c == checkpoint_path(&self.out, step) => c.clone(),
                _ => self.checkpoint()?,
            };
            self.write_summary(Some(&checkpoint))?;
            return Ok(Outcome::Interrupted {
                steps: step,
                checkpoint,
            });
        }
        if let Some(h) = &mut self.history {
            h.flush()?;
        }
        let checkpoint = match self.last_checkpoint.clone() {
            Some(c) => c,
            None => self.save()?,
        };
        self.write_summary(None)?;
        Ok(Outcome::Finished {
            steps: step,
            checkpoint,
        })
    }

    fn write_summary(&mut self, interrupted: Option<&Path>) -> Result<(), RunError> {
        self.synchronise()?;
        if !self.is_primary() {
            return Ok(());
        }
        let processes = self.parallel.as_ref().map(|p| {
            (
                p.collective.size(),
                thm_coupling::multiscale::distributed::lock(&p.distribution).stats(),
            )
        });
        let info = RunInfo {
            common: &self.common,
            file: &self.file,
            steps_done: self.step,
            n_steps: self.n,
            dt: self.dt,
            wall_seconds: self.wall.elapsed().as_secs_f64(),
            interrupted,
            processes,
        };
        let summary = self
            .scenario
            .summary(&self.state, self.step as f64 * self.dt);
        write_summary(&self.out, &info, &summary, &|column, time| {
            self.scenario.reference(column, time)
        })
    }
}

/// Runs scenario kind `S` from a parsed document.
pub fn drive<S: Scenario>(
    doc: ScenarioDocument,
    file: &Path,
    opts: &DriveOptions<'_>,
) -> Result<Outcome, RunError> {
    let mut run = Run::<S>::open_on(
        doc,
        file,
        &opts.out,
        opts.resume.as_deref(),
        opts.processes.clone(),
    )?;
    let mode = if run.is_primary() {
        opts.progress
    } else {
        Progress::Quiet
    };
    let mut progress = ProgressDisplay::new(mode, run.start, run.n, run.dt);
    while run.steps_done() < run.n_steps() {
        let mut interrupted = opts.interrupt.load(Ordering::Relaxed);
        // Every process stops at the same step (a signal may reach only some of them).
        if let Some(c) = &opts.processes {
            interrupted = c.any(interrupted);
        }
        let advanced = run.advance(interrupted);
        // An error one process alone saw (process 0's disk) stops every process at this step.
        if let Some(c) = &opts.processes
            && let Some(process) = c.first_failed(advanced.is_err())
        {
            advanced?;
            return Err(RunError::OtherProcess { process });
        }
        advanced?;
        progress.update(run.steps_done());
        if interrupted && run.steps_done() < run.n_steps() {
            progress.finish();
            return run.finish();
        }
    }
    progress.finish();
    run.finish()
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
