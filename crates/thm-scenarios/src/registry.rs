//! The scenario kinds by their `kind` tag: reading a scenario document (whose messages name
//! the known kinds), checking it, running it with the driver of its kind, and opening it as a
//! [`DynRun`] for front ends that step it themselves (the Python module).

use std::path::{Path, PathBuf};

use crate::arrays::StateArray;
use crate::config::{Common, OutputSection, ScenarioDocument, TimeSection, from_toml};
use crate::error::{ConfigError, RunError};
use crate::kinds::{
    dem_uniaxial_tension_bar, lumped_cooling, mpm_dem_biaxial, mpm_dem_column, mpm_dem_rod,
    mpm_dem_silo, mpm_dem_square, mpm_semi_infinite_bar, pore_scale_bar,
};
use crate::scenario::{self, DriveOptions, Outcome, Run, Scenario, drive};

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
    let message = crate::error::shorten(e.message().trim());
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
                format!("missing key; one of {}", names()),
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
        if is_known(&kind) {
            cfg(e)
        } else {
            cfg(ConfigError::new(
                "kind",
                format!("unknown scenario kind `{kind}`; one of {}", names()),
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
