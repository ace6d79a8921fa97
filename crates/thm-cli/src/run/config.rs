//! Reading a scenario file: TOML → the common sections and a kind's own parameters, with every
//! error naming its dotted key path.

use std::path::Path;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::error::{ConfigError, RunError};
use super::units::{Quantity, Time};

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

fn take(table: &mut toml::Table, key: &str) -> Option<toml::Value> {
    table.remove(key)
}

/// Reads and parses a scenario file into its common sections and the kind's part.
pub fn read_document(path: &Path) -> Result<ScenarioDocument, RunError> {
    let bytes = std::fs::read(path).map_err(|source| RunError::ReadScenario {
        path: path.to_path_buf(),
        source,
    })?;
    if bytes.starts_with(thm_io::checkpoint::BINARY_MAGIC)
        || bytes.starts_with(b"{\"format\":\"thm-checkpoint\"")
    {
        return Err(RunError::CheckpointGivenAsScenario {
            path: path.to_path_buf(),
        });
    }
    let text = std::str::from_utf8(&bytes).map_err(|e| RunError::Syntax {
        path: path.to_path_buf(),
        message: format!(
            "not UTF-8 text (invalid byte at offset {}, after `{}`)",
            e.valid_up_to(),
            thm_io::checkpoint::excerpt(
                &bytes[e.valid_up_to().saturating_sub(24)..e.valid_up_to()]
            )
        ),
    })?;
    parse_document(text).map_err(|e| match e {
        DocError::Syntax(message) => RunError::Syntax {
            path: path.to_path_buf(),
            message,
        },
        DocError::Config(error) => RunError::Config {
            path: path.to_path_buf(),
            error,
        },
    })
}

/// The parser's message with its line and column and a short excerpt of the line around the
/// column (the parser's own rendering quotes the whole line, which can be the whole file).
fn syntax_message(text: &str, e: &toml::de::Error) -> String {
    let message = super::error::shorten(e.message().trim());
    let Some(span) = e.span() else {
        return message;
    };
    let at = (0..=span.start.min(text.len()))
        .rev()
        .find(|&i| text.is_char_boundary(i))
        .unwrap_or(0);
    let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line_no = text[..at].matches('\n').count() + 1;
    let column = text[line_start..at].chars().count() + 1;
    let line = text[line_start..].split('\n').next().unwrap_or("");
    let before: String = {
        let head: Vec<char> = text[line_start..at].chars().collect();
        head[head.len().saturating_sub(20)..].iter().collect()
    };
    let after: String = line[at - line_start..].chars().take(28).collect();
    let cut_before = before.chars().count() < column - 1;
    let cut_after = after.chars().count() < line[at - line_start..].chars().count();
    format!(
        "line {line_no}, column {column}: {message} (at `{}{before}{after}{}`)",
        if cut_before { "…" } else { "" },
        if cut_after { "…" } else { "" },
    )
}

/// Why a document does not parse.
#[derive(Debug)]
pub enum DocError {
    /// Not TOML.
    Syntax(String),
    /// A value is wrong.
    Config(ConfigError),
}

/// Parses scenario text (see [`read_document`]).
pub fn parse_document(text: &str) -> Result<ScenarioDocument, DocError> {
    let mut table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| DocError::Syntax(syntax_message(text, &e)))?;
    let cfg = DocError::Config;
    let kind: String = match take(&mut table, "kind") {
        Some(v) => from_toml(v, "kind").map_err(cfg)?,
        None => {
            return Err(cfg(ConfigError::new(
                "kind",
                format!("missing key; one of {}", super::kinds::names()),
            )));
        }
    };
    let common = |table: &mut toml::Table| -> Result<_, ConfigError> {
        let title: Option<String> = take(table, "title")
            .map(|v| from_toml(v, "title"))
            .transpose()?;
        let time: TimeSection = match take(table, "time") {
            Some(v) => from_toml(v, "time")?,
            None => return Err(ConfigError::new("time", "missing section [time]")),
        };
        let output: OutputSection = take(table, "output")
            .map(|v| from_toml(v, "output"))
            .transpose()?
            .unwrap_or_default();
        Ok((title, time, output))
    };
    let (title, time, output) = common(&mut table).map_err(|e| {
        // The sections only mean something for a known kind: an unknown one is named first.
        // (A kind unknown here but complete is still refused by the dispatch.)
        if super::kinds::is_known(&kind) {
            cfg(e)
        } else {
            cfg(ConfigError::new(
                "kind",
                format!(
                    "unknown scenario kind `{kind}`; one of {}",
                    super::kinds::names()
                ),
            ))
        }
    })?;
    Ok(ScenarioDocument {
        common: Common {
            kind,
            title,
            time,
            output,
        },
        rest: table,
    })
}
