//! # thm-scenarios — scenario files as a library
//!
//! What the front ends run, with no front end in it: the `thm` binary (`thm-cli`: argument
//! parsing, MPI start-up, exit codes) and the Python module (`thm-py`) both open, step and
//! finish the same [`scenario::Run`], so a run from either writes the same files, bit for
//! bit, and their checkpoints cross.
//!
//! A scenario file (TOML) names its `kind`; the common sections are `[time]` (step, end) and
//! `[output]` (history_every, frame_every, checkpoint_every, encoding); every other section
//! belongs to the kind. Quantities are numbers in SI units or strings `"value unit"`
//! ([`units`]). Unknown keys, missing keys, wrong types or units and out-of-range values are
//! errors naming the key path ([`error::ConfigError`]).
//!
//! The output folder receives `scenario.toml` (the resolved scenario), `history.csv`, one
//! `.pvd` + folder of `.vtu` frames per series, `checkpoints/step_*.ckpt`, the kind's profiles
//! (`profiles/*.csv`, see [`profiles`]), pictures (`pictures/*.png`, see [`pictures`]) and
//! `summary.md` with history and profile plots ([`summary`]). A fresh run refuses a folder
//! that already holds a run; an interrupt stops after the current step with a checkpoint, and
//! a run resumed from any checkpoint continues bit for bit.
//!
//! Also here, for the same front ends: the equation of state over CSV ([`eos_csv`]).
//!
//! ## Layers
//!
//! Each module imports only from the modules before it in this list (checked by
//! `cargo xtask tidy`):
//!
//! 1. [`error`], [`units`]: typed errors naming the key, quantities with units;
//! 2. [`config`]: the common sections of a scenario document, and range checks;
//! 3. [`arrays`]: named state arrays for front ends ([`arrays::StateArray`]);
//! 4. [`profiles`], [`pictures`], [`summary`]: what a run writes besides frames and
//!    checkpoints;
//! 5. [`scenario`]: the [`scenario::Scenario`] trait (the seam to a physics), the
//!    steppable [`scenario::Run`] and [`scenario::drive`];
//! 6. [`rve_frames`]: an RVE's disks, contacts and cell as frames;
//! 7. [`kinds`]: one module per kind (`kinds::multiscale` holds the skeleton the MPM×DEM kinds
//!    share);
//! 8. [`registry`]: the kinds by their `kind` tag, reading a document, dispatching it;
//! 9. this file: [`run_file`].
//!
//! [`eos_csv`] stands apart (it needs [`error`] only).
//!
//! Every input (a scenario file, a packing CSV, an EOS CSV row, a checkpoint) gives a typed
//! error naming the key, line or field and the allowed range, never a panic; messages quote at
//! most a short excerpt of the input.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod error;
pub mod units;

pub mod config;

pub mod arrays;

pub mod pictures;
pub mod profiles;
pub mod summary;

pub mod scenario;

pub mod rve_frames;

pub mod kinds;

pub mod registry;

pub mod eos_csv;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use error::RunError;
use scenario::{DriveOptions, Outcome, Progress};

/// The default output folder of a scenario file: `runs/<file stem>`.
pub fn default_out(file: &Path) -> PathBuf {
    let stem = file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    PathBuf::from("runs").join(stem)
}

/// Runs a scenario file to its end (or to an interrupt) into `out`, continuing from `resume`
/// if given.
pub fn run_file(
    file: &Path,
    out: &Path,
    resume: Option<&Path>,
    interrupt: &AtomicBool,
    progress: Progress,
) -> Result<Outcome, RunError> {
    run_file_on(file, out, resume, interrupt, progress, None)
}

/// [`run_file`] on the processes of a distributed run (every process calls it; see
/// [`scenario::Run::open_on`]).
pub fn run_file_on(
    file: &Path,
    out: &Path,
    resume: Option<&Path>,
    interrupt: &AtomicBool,
    progress: Progress,
    processes: Option<Arc<dyn thm_coupling::multiscale::Collective>>,
) -> Result<Outcome, RunError> {
    let doc = registry::read_document(file);
    // A file that one process cannot read must stop every process.
    if let Some(c) = &processes
        && let Some(process) = c.first_failed(doc.is_err())
        && doc.is_ok()
    {
        return Err(RunError::OtherProcess { process });
    }
    let opts = DriveOptions {
        out: out.to_path_buf(),
        resume: resume.map(Path::to_path_buf),
        interrupt,
        progress,
        processes,
    };
    registry::dispatch(doc?, file, &opts)
}

/// The newest checkpoint in `out` that is complete and intact (checked, not only listed).
pub fn last_complete_checkpoint(out: &Path) -> Option<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(out.join("checkpoints"))
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "ckpt"))
        .collect();
    found.sort();
    found
        .into_iter()
        .rev()
        .find(|p| thm_io::checkpoint_info(p).is_ok())
}

#[cfg(test)]
mod tests;
