//! The scenario kinds `thm run` knows, dispatched on the file's `kind` key.

pub mod dem_uniaxial_tension_bar;
pub mod lumped_cooling;
pub mod mpm_dem_biaxial;
pub mod mpm_dem_column;
pub mod mpm_dem_rod;
pub mod mpm_dem_silo;
pub mod mpm_dem_square;
pub mod mpm_semi_infinite_bar;
pub mod pore_scale_bar;

use std::path::{Path, PathBuf};

use super::config::ScenarioDocument;
use super::error::{ConfigError, RunError};
use super::scenario::{self, DriveOptions, Outcome, Run, Scenario, StateArray, drive};

/// The `kind` tags.
const KINDS: [&str; 9] = [
    lumped_cooling::LumpedCooling::KIND,
    mpm_dem_rod::MpmDemRod::KIND,
    mpm_dem_square::MpmDemSquare::KIND,
    mpm_semi_infinite_bar::SemiInfiniteBar::KIND,
    dem_uniaxial_tension_bar::DemTensionBar::KIND,
    pore_scale_bar::PoreScaleBar::KIND,
    mpm_dem_biaxial::MpmDemBiaxial::KIND,
    mpm_dem_column::MpmDemColumn::KIND,
    mpm_dem_silo::MpmDemSilo::KIND,
];

/// The `kind` tags, for error messages.
pub fn names() -> String {
    KINDS
        .iter()
        .map(|k| format!("`{k}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Whether `kind` names a scenario kind.
pub fn is_known(kind: &str) -> bool {
    KINDS.contains(&kind)
}

/// Expands `$body` with `$S` bound to the scenario type of kind tag `$kind`, or `$other`
/// for an unknown tag.
macro_rules! with_kind {
    ($kind:expr, $S:ident => $body:expr, $other:ident => $fallback:expr) => {
        match $kind {
            lumped_cooling::LumpedCooling::KIND => {
                type $S = lumped_cooling::LumpedCooling;
                $body
            }
            mpm_semi_infinite_bar::SemiInfiniteBar::KIND => {
                type $S = mpm_semi_infinite_bar::SemiInfiniteBar;
                $body
            }
            mpm_dem_rod::MpmDemRod::KIND => {
                type $S = mpm_dem_rod::MpmDemRod;
                $body
            }
            mpm_dem_square::MpmDemSquare::KIND => {
                type $S = mpm_dem_square::MpmDemSquare;
                $body
            }
            mpm_dem_biaxial::MpmDemBiaxial::KIND => {
                type $S = mpm_dem_biaxial::MpmDemBiaxial;
                $body
            }
            mpm_dem_column::MpmDemColumn::KIND => {
                type $S = mpm_dem_column::MpmDemColumn;
                $body
            }
            mpm_dem_silo::MpmDemSilo::KIND => {
                type $S = mpm_dem_silo::MpmDemSilo;
                $body
            }
            dem_uniaxial_tension_bar::DemTensionBar::KIND => {
                type $S = dem_uniaxial_tension_bar::DemTensionBar;
                $body
            }
            pore_scale_bar::PoreScaleBar::KIND => {
                type $S = pore_scale_bar::PoreScaleBar;
                $body
            }
            $other => $fallback,
        }
    };
}

/// `v` finite and in `[lo, hi]`, else an error at `key` naming the range.
pub(crate) fn check_range(key: &str, v: f64, lo: f64, hi: f64) -> Result<(), ConfigError> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(())
    } else {
        Err(ConfigError::new(
            key,
            format!("must be in [{lo}, {hi}], got {v}"),
        ))
    }
}

/// `v` in `[lo, hi]`, else an error at `key` naming the range.
pub(crate) fn check_count(key: &str, v: usize, lo: usize, hi: usize) -> Result<(), ConfigError> {
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(ConfigError::new(
            key,
            format!("must be in [{lo}, {hi}], got {v}"),
        ))
    }
}

/// The error of a physics that refused a step (or a synchronisation) at `step`, `time`.
pub(crate) fn physics_error<E: std::fmt::Display>(
    step: u64,
    time: f64,
) -> impl FnOnce(E) -> RunError {
    move |e| RunError::Physics {
        step,
        time,
        message: e.to_string(),
    }
}

/// Brings every process's copy of `points` up to date when `material` is distributed (see
/// `thm_coupling::multiscale::distributed`); nothing otherwise.
pub(crate) fn synchronise_points(
    material: &thm_coupling::multiscale::RveMaterial,
    points: &mut [thm_coupling::multiscale::RvePoint],
    step: u64,
    time: f64,
) -> Result<(), RunError> {
    match material.distribution() {
        Some(d) => thm_coupling::multiscale::distributed::lock(d)
            .synchronise(points)
            .map_err(physics_error(step, time)),
        None => Ok(()),
    }
}

fn unknown_kind(other: &str) -> ConfigError {
    ConfigError::new(
        "kind",
        format!("unknown scenario kind `{other}`; one of {}", names()),
    )
}

/// Checks the document as its kind's run does before writing anything: parameters, time and
/// output sections, and building the initial state. Every document gives `Ok` or an error
/// naming the key path, never a panic.
pub fn validate(doc: &ScenarioDocument) -> Result<(), ConfigError> {
    with_kind!(doc.common.kind.as_str(),
        S => scenario::validate::<S>(doc),
        other => Err(unknown_kind(other)))
}

/// Runs the document with the driver of its kind.
pub fn dispatch(
    doc: ScenarioDocument,
    file: &Path,
    opts: &DriveOptions<'_>,
) -> Result<Outcome, RunError> {
    with_kind!(doc.common.kind.as_str(),
    S => drive::<S>(doc, file, opts),
    other => Err(RunError::Config {
        path: file.to_path_buf(),
        error: unknown_kind(other),
    }))
}

/// A [`Run`] of any kind, stepped through one interface (the Python module's `Run`).
pub trait DynRun: Send {
    /// The kind tag.
    fn kind(&self) -> &'static str;
    /// Steps completed.
    fn steps_done(&self) -> u64;
    /// Steps of the whole run.
    fn n_steps(&self) -> u64;
    /// The time step \[s\].
    fn dt(&self) -> f64;
    /// One step on the output schedule (see [`Run::advance`]).
    fn advance(&mut self, interrupted: bool) -> Result<(), RunError>;
    /// A checkpoint of the current step (see [`Run::checkpoint`]).
    fn checkpoint(&mut self) -> Result<PathBuf, RunError>;
    /// Ends the run (see [`Run::finish`]).
    fn finish(&mut self) -> Result<Outcome, RunError>;
    /// Monitored headers and values, time first.
    fn monitor(&mut self) -> (Vec<String>, Vec<f64>);
    /// The state's named arrays.
    fn arrays(&self) -> Vec<StateArray<'_>>;
    /// Replaces a writable array.
    fn set_array(&mut self, name: &str, values: &[f64]) -> Result<(), RunError>;
}

impl<S> DynRun for Run<S>
where
    S: Scenario + Send,
    S::State: Send,
{
    fn kind(&self) -> &'static str {
        S::KIND
    }
    fn steps_done(&self) -> u64 {
        Run::steps_done(self)
    }
    fn n_steps(&self) -> u64 {
        Run::n_steps(self)
    }
    fn dt(&self) -> f64 {
        Run::dt(self)
    }
    fn advance(&mut self, interrupted: bool) -> Result<(), RunError> {
        Run::advance(self, interrupted)
    }
    fn checkpoint(&mut self) -> Result<PathBuf, RunError> {
        Run::checkpoint(self)
    }
    fn finish(&mut self) -> Result<Outcome, RunError> {
        Run::finish(self)
    }
    fn monitor(&mut self) -> (Vec<String>, Vec<f64>) {
        Run::monitor(self)
    }
    fn arrays(&self) -> Vec<StateArray<'_>> {
        Run::arrays(self)
    }
    fn set_array(&mut self, name: &str, values: &[f64]) -> Result<(), RunError> {
        Run::set_array(self, name, values)
    }
}

/// Opens a run of the document's kind (see [`Run::open`]).
pub fn open(
    doc: ScenarioDocument,
    file: &Path,
    out: &Path,
    resume: Option<&Path>,
) -> Result<Box<dyn DynRun>, RunError> {
    with_kind!(doc.common.kind.as_str(),
    S => Ok(Box::new(Run::<S>::open(doc, file, out, resume)?)),
    other => Err(RunError::Config {
        path: file.to_path_buf(),
        error: unknown_kind(other),
    }))
}
