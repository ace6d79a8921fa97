//! Reading a scenario file: TOML → the common sections and a kind's own parameters, with every
//! error naming its dotted key path.

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::error::ConfigError;
use crate::units::{Quantity, Time};

/// `[time]`: the time step and the simulated duration.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSection {
    /// Time step.
    pub step: Quantity<Time>,
    /// Simulated time at which the run ends.
    pub end: Quantity<Time>,
}

/// Output encoding of the VTU frames.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EncodingChoice {
    /// Appended raw binary (smallest, fastest).
    #[default]
    Raw,
    /// Appended base64.
    Base64,
    /// Inline text.
    Ascii,
}

impl From<EncodingChoice> for thm_io::Encoding {
    fn from(e: EncodingChoice) -> Self {
        match e {
            EncodingChoice::Raw => thm_io::Encoding::Raw,
            EncodingChoice::Base64 => thm_io::Encoding::Base64,
            EncodingChoice::Ascii => thm_io::Encoding::Ascii,
        }
    }
}

fn one() -> u64 {
    1
}

fn hundred() -> u64 {
    100
}

fn thousand() -> u64 {
    1000
}

/// `[output]`: how often the run records what.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    /// Steps between rows of `history.csv` (≥ 1).
    #[serde(default = "one")]
    pub history_every: u64,
    /// Steps between VTU frames (0: first and last only).
    #[serde(default = "hundred")]
    pub frame_every: u64,
    /// Steps between checkpoints (0: last only).
    #[serde(default = "thousand")]
    pub checkpoint_every: u64,
    /// Encoding of the VTU frames.
    #[serde(default)]
    pub encoding: EncodingChoice,
}

impl Default for OutputSection {
    fn default() -> Self {
        Self {
            history_every: one(),
            frame_every: hundred(),
            checkpoint_every: thousand(),
            encoding: EncodingChoice::default(),
        }
    }
}

/// The validated time control.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeControl {
    /// Time step \[s\].
    pub dt: f64,
    /// Number of steps to reach the end time.
    pub n_steps: u64,
}

/// Largest number of steps a run may have.
pub const MAX_STEPS: f64 = 1e12;

impl TimeSection {
    /// Checks the time step and end time.
    pub fn validate(&self) -> Result<TimeControl, ConfigError> {
        let dt = self.step.positive("time.step")?;
        let end = self.end.above("time.end", 0.0)?;
        let steps = (end / dt * (1.0 - 1e-12)).ceil();
        if steps > MAX_STEPS {
            return Err(ConfigError::new(
                "time.end",
                format!("needs {steps:e} steps of time.step; at most {MAX_STEPS:e} allowed"),
            ));
        }
        Ok(TimeControl {
            dt,
            n_steps: (steps as u64).max(1),
        })
    }
}

impl OutputSection {
    /// Checks the output intervals.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.history_every == 0 {
            return Err(ConfigError::new(
                "output.history_every",
                "must be ≥ 1 step, got 0",
            ));
        }
        Ok(())
    }
}

/// The sections every scenario file has besides the kind's own.
#[derive(Debug, Clone, Serialize)]
pub struct Common {
    /// Scenario kind.
    pub kind: String,
    /// Free title shown in the summary.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub title: Option<String>,
    /// `[time]`.
    pub time: TimeSection,
    /// `[output]`.
    pub output: OutputSection,
}

/// A parsed scenario: the common sections and the rest of the table (the kind's own part).
#[derive(Debug, Clone)]
pub struct ScenarioDocument {
    /// `kind`, `title`, `[time]`, `[output]`.
    pub common: Common,
    /// Every other key, to be read by the kind.
    pub rest: toml::Table,
}

/// Deserializes `value` into `T`; an error names the key path below `prefix`.
pub fn from_toml<T: DeserializeOwned>(value: toml::Value, prefix: &str) -> Result<T, ConfigError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let mut key = prefix.to_string();
        let inner = e.path().to_string();
        if inner != "." && !inner.is_empty() {
            if !key.is_empty() {
                key.push('.');
            }
            key.push_str(&inner);
        }
        // toml appends "in `key`" to its messages; the key path is given once, in front.
        let full = e.into_inner().to_string();
        let message = full
            .split("\nin `")
            .next()
            .unwrap_or(&full)
            .trim()
            .to_string();
        // "missing field `x`" and "unknown field `x`, …" belong to the key `x` itself.
        for (head, what) in [
            ("missing field `", "missing key"),
            ("unknown field `", "unknown key"),
        ] {
            if let Some(rest) = message.strip_prefix(head)
                && let Some(end) = rest.find('`')
            {
                let name = &rest[..end];
                if !key.ends_with(name) {
                    if !key.is_empty() {
                        key.push('.');
                    }
                    key.push_str(name);
                }
                let allowed = rest[end + 1..].trim_start_matches(',').trim();
                let allowed = allowed.strip_prefix("in `").map_or(allowed, |_| "");
                let message = if allowed.is_empty() {
                    what.to_string()
                } else {
                    format!("{what}; {allowed}")
                };
                return ConfigError::new(key, message);
            }
        }
        ConfigError::new(
            if key.is_empty() {
                "(top level)".into()
            } else {
                key
            },
            message,
        )
    })
}

/// `v` finite and in `[lo, hi]`, else an error at `key` naming the range.
pub fn check_range(key: &str, v: f64, lo: f64, hi: f64) -> Result<(), ConfigError> {
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
pub fn check_count(key: &str, v: usize, lo: usize, hi: usize) -> Result<(), ConfigError> {
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(ConfigError::new(
            key,
            format!("must be in [{lo}, {hi}], got {v}"),
        ))
    }
}

/// File names inside the output folder.
pub const SCENARIO_FILE: &str = "scenario.toml";
/// The CSV history.
pub const HISTORY_FILE: &str = "history.csv";
/// The summary.
pub const SUMMARY_FILE: &str = "summary.md";
