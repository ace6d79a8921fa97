//! Errors of `thm run`.

use std::path::PathBuf;

/// A scenario file value that is missing, unknown, of the wrong type or unit, or out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{key}: {message}")]
pub struct ConfigError {
    /// Dotted key path in the TOML file, e.g. `solid.contact.tensile_strength`.
    pub key: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl ConfigError {
    /// An error at `key`. Quoted input in the key or message (between backticks or double
    /// quotes) is cut to a short excerpt, so a huge value is never echoed whole.
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            key: shorten(&key.into()),
            message: shorten(&message.into()),
        }
    }
}

/// Longest quoted excerpt of user input kept in a message \[characters\].
pub const MAX_QUOTE: usize = 48;

/// Longest message kept whole \[characters\].
pub const MAX_MESSAGE: usize = 400;

/// Cuts every quoted span (`` `…` `` or `"…"`) longer than [`MAX_QUOTE`] characters, and the
/// whole text beyond [`MAX_MESSAGE`] characters, marking each cut with `…`.
pub fn shorten(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len().min(4 * MAX_MESSAGE));
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        out.push(c);
        i += 1;
        if (c == '`' || c == '"')
            && let Some(len) = chars[i..].iter().position(|&d| d == c)
        {
            if len > MAX_QUOTE {
                out.extend(&chars[i..i + MAX_QUOTE]);
                out.push('…');
            } else {
                out.extend(&chars[i..i + len]);
            }
            out.push(c);
            i += len + 1;
        }
    }
    if out.chars().count() > MAX_MESSAGE {
        out = out.chars().take(MAX_MESSAGE).collect();
        out.push('…');
    }
    out
}

/// Everything that stops a run.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario file cannot be read.
    #[error("{path}: cannot read scenario: {source}")]
    ReadScenario {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The scenario file is not valid TOML.
    #[error("{path}: not valid TOML: {message}")]
    Syntax {
        /// The file.
        path: PathBuf,
        /// The parser's message (with line and column).
        message: String,
    },
    /// A value of the scenario file is wrong.
    #[error("{path}: {error}")]
    Config {
        /// The file.
        path: PathBuf,
        /// The key path and what is wrong.
        error: ConfigError,
    },
    /// The scenario file is a checkpoint (a common slip: `thm run CHECKPOINT`).
    #[error(
        "{path}: this is a thm checkpoint, not a scenario file; continue its run with: thm run SCENARIO.toml --out FOLDER --resume {path}"
    )]
    CheckpointGivenAsScenario {
        /// The file.
        path: PathBuf,
    },
    /// The output folder cannot be created or written.
    #[error("output folder {path} cannot be written: {source}")]
    OutputFolder {
        /// The folder.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The output folder already holds a run, which a fresh run would overwrite.
    #[error(
        "output folder {path} already holds a run ({marker}); choose another --out, remove it, or continue it with --resume"
    )]
    OutputNotEmpty {
        /// The folder.
        path: PathBuf,
        /// The file that shows a run is there.
        marker: String,
    },
    /// Writing a result file failed.
    #[error(transparent)]
    Io(#[from] thm_io::IoError),
    /// The checkpoint does not belong to this scenario file.
    #[error(
        "{path}: checkpoint was written for another scenario ({detail}); resume with the scenario file of that run"
    )]
    CheckpointMismatch {
        /// The checkpoint.
        path: PathBuf,
        /// What differs.
        detail: String,
    },
    /// The physics refused to step (its own typed error, e.g. a time step above the stability
    /// limit or a point leaving the grid).
    #[error("step {step} (t = {time} s): {message}")]
    Physics {
        /// The step that failed.
        step: u64,
        /// The simulated time at its start \[s\].
        time: f64,
        /// The physics crate's error message.
        message: String,
    },
    /// The simulation went unstable: a non-finite or impossible value.
    #[error("unstable at step {step} (t = {time} s): {quantity} = {value} at {place}")]
    Unstable {
        /// The quantity.
        quantity: String,
        /// Where (particle, cell, monitor).
        place: String,
        /// The step.
        step: u64,
        /// The simulated time \[s\].
        time: f64,
        /// The offending value.
        value: f64,
    },
    /// New values for a state array between steps were refused.
    #[error("state array `{array}`: {detail}")]
    Input {
        /// The array's name.
        array: String,
        /// What is wrong and what is allowed.
        detail: String,
    },
    /// Another process of a distributed run (`mpirun -np N thm run`) failed (opening the run,
    /// or writing at a step); that process prints why.
    #[error("process {process} of the distributed run failed (its message says why)")]
    OtherProcess {
        /// The lowest failing process.
        process: usize,
    },
    /// The kind has no RVE stage to spread over processes.
    #[error(
        "kind `{kind}` has no RVE stage to spread over {processes} processes; run it without mpirun (or with -np 1)"
    )]
    NotDistributable {
        /// The kind.
        kind: &'static str,
        /// The processes the run was started on.
        processes: usize,
    },
    /// A step was asked of a run that has reached its end time.
    #[error("the run has reached its end time after {steps} steps; nothing left to step")]
    Ended {
        /// Steps of the whole run.
        steps: u64,
    },
}

/// The error of a physics that refused a step (or a synchronisation) at `step`, `time`.
pub fn physics_error<E: std::fmt::Display>(step: u64, time: f64) -> impl FnOnce(E) -> RunError {
    move |e| RunError::Physics {
        step,
        time,
        message: e.to_string(),
    }
}
