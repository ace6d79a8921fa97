//! `thm run FILE.toml [--out DIR] [--resume CHECKPOINT]`: runs a scenario file with
//! [`thm_scenarios::run_file_on`] and turns how it ended into a message and an exit code.
//!
//! Built with the feature `mpi`, it starts MPI; under `mpirun -np N` (N > 1) the material
//! points' RVEs are spread over the N processes, process 0 writes every output and reports how
//! the run ended. Ctrl-C stops after the current step with a checkpoint.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use thm_scenarios::error::RunError;
use thm_scenarios::scenario::{Outcome, Progress};
use thm_scenarios::{default_out, last_complete_checkpoint, run_file_on};

/// Arguments of `thm run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// The scenario file (TOML).
    pub file: PathBuf,
    /// Output folder (default: `runs/<file stem>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Continue from this checkpoint (written by an earlier run of the same scenario).
    #[arg(long)]
    pub resume: Option<PathBuf>,
}

/// `thm run`.
pub fn run(args: &RunArgs) -> ExitCode {
    #[cfg(feature = "mpi")]
    let mpi = crate::mpi_rve::init();
    #[cfg(feature = "mpi")]
    let processes = mpi.as_ref().and_then(|(_, c)| c.clone());
    #[cfg(not(feature = "mpi"))]
    let processes: Option<Arc<dyn thm_coupling::multiscale::Collective>> = None;
    #[cfg(not(feature = "mpi"))]
    if let Some(n) = launched_processes().filter(|&n| n > 1) {
        // N copies of a build without MPI would each run the whole scenario into one folder.
        eprintln!(
            "error: this thm was built without the feature `mpi` but was started as one of {n} \
             MPI processes; build it with `cargo build --release -p thm-cli --features mpi` \
             (docs/cluster.md) or run it without mpirun"
        );
        return ExitCode::FAILURE;
    }
    let primary = processes.as_ref().is_none_or(|c| c.rank() == 0);

    let interrupt = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&interrupt);
    if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed)) {
        eprintln!("warning: Ctrl-C will not write a checkpoint ({e})");
    }
    let out = args.out.clone().unwrap_or_else(|| default_out(&args.file));
    let result = run_file_on(
        &args.file,
        &out,
        args.resume.as_deref(),
        &interrupt,
        Progress::Auto,
        processes,
    );
    if !primary {
        // Process 0 reports for all: every error of a distributed run is agreed between the
        // processes at the step it happens (see `scenario::drive`).
        return if result.is_ok() {
            ExitCode::SUCCESS
        } else {
            ExitCode::FAILURE
        };
    }
    report(args, &out, result)
}

/// The process count an MPI launcher (Open MPI, MPICH/Hydra) announced in the
/// environment, if any.
pub fn launched_processes() -> Option<usize> {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"]
        .iter()
        .find_map(|k| std::env::var(k).ok()?.parse().ok())
}

/// Prints how a run ended and returns the exit code.
fn report(args: &RunArgs, out: &Path, result: Result<Outcome, RunError>) -> ExitCode {
    match result {
        Ok(Outcome::Finished { steps, checkpoint }) => {
            eprintln!(
                "finished {steps} steps; results in {} (last checkpoint {})",
                out.display(),
                checkpoint.display()
            );
            ExitCode::SUCCESS
        }
        Ok(Outcome::Interrupted { steps, checkpoint }) => {
            eprintln!(
                "interrupted after {steps} steps; continue with: thm run {} --out {} --resume {}",
                args.file.display(),
                out.display(),
                checkpoint.display()
            );
            ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {e}");
            // A run that stopped part-way (a full disk, an unstable step) keeps its last
            // complete checkpoint: say which one and how to continue from it.
            let stopped = matches!(
                e,
                RunError::Io(_)
                    | RunError::OutputFolder { .. }
                    | RunError::Physics { .. }
                    | RunError::Unstable { .. }
            );
            if stopped && let Some(ckpt) = last_complete_checkpoint(out) {
                eprintln!(
                    "the last complete checkpoint is {}; once the cause is fixed, continue with: thm run {} --out {} --resume {}",
                    ckpt.display(),
                    args.file.display(),
                    out.display(),
                    ckpt.display()
                );
            }
            ExitCode::FAILURE
        }
    }
}
