//! Verification-case types shared by every physics crate and by `cargo xtask verify`.
//!
//! Each physics crate keeps its verification cases next to its physics, in a
//! `verification` module with a `pub fn cases() -> Vec<Case>`. A case runs a simulation or an
//! evaluation and returns [`CaseOutput`]: table rows (measured against reference with a stated
//! tolerance), optional curves (measured against reference, for plots) and notes. The
//! `xtask` binary collects the cases of all crates, runs them, prints the table and writes it
//! (with plots) under `target/verify/`.
//!
//! This crate has no dependencies and holds no physics: it is the seam between a crate's own
//! checks and the report.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

use std::fmt;

/// How a row's error is measured and compared with its tolerance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// `|measured − reference|`, in the row's unit.
    Absolute,
    /// `|measured − reference| / |reference|`.
    Relative,
    /// The measured value must not exceed the reference (an upper bound); error = measured.
    AtMost,
    /// The measured value must be at least the reference (a lower bound); error = measured.
    AtLeast,
    /// A paper figure that cannot be a check (the paper leaves a parameter unstated or the
    /// setups differ): shown next to the paper's value with the signed difference
    /// `measured − reference` as error; passes whenever the measured value is finite. The
    /// case's notes say why it is not a check.
    Reported,
}

/// One line of the verification table.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// What is measured, e.g. `"T(x=0.04 m, t=400 s)"`.
    pub quantity: String,
    /// Unit of `measured` and `reference` (empty for dimensionless).
    pub unit: String,
    /// The value the code produced.
    pub measured: f64,
    /// The analytical or reference value (or the bound, for [`ErrorKind::AtMost`]/[`ErrorKind::AtLeast`]).
    pub reference: f64,
    /// The error as defined by `kind`.
    pub error: f64,
    /// The largest admissible error (for bounds: unused, reported as the bound itself).
    pub tolerance: f64,
    /// How `error` is defined.
    pub kind: ErrorKind,
    /// Whether the row passes. Non-finite measured values never pass.
    pub pass: bool,
}

impl Row {
    /// A row compared by absolute error.
    pub fn absolute(
        quantity: impl Into<String>,
        unit: impl Into<String>,
        measured: f64,
        reference: f64,
        tolerance: f64,
    ) -> Self {
        let error = (measured - reference).abs();
        Self {
            quantity: quantity.into(),
            unit: unit.into(),
            measured,
            reference,
            error,
            tolerance,
            kind: ErrorKind::Absolute,
            pass: error.is_finite() && error <= tolerance,
        }
    }

    /// A row compared by relative error `|m − r| / |r|`.
    pub fn relative(
        quantity: impl Into<String>,
        unit: impl Into<String>,
        measured: f64,
        reference: f64,
        tolerance: f64,
    ) -> Self {
        let error = (measured - reference).abs() / reference.abs();
        Self {
            quantity: quantity.into(),
            unit: unit.into(),
            measured,
            reference,
            error,
            tolerance,
            kind: ErrorKind::Relative,
            pass: error.is_finite() && error <= tolerance,
        }
    }

    /// A row that passes when `measured <= bound`.
    pub fn at_most(
        quantity: impl Into<String>,
        unit: impl Into<String>,
        measured: f64,
        bound: f64,
    ) -> Self {
        Self {
            quantity: quantity.into(),
            unit: unit.into(),
            measured,
            reference: bound,
            error: measured,
            tolerance: bound,
            kind: ErrorKind::AtMost,
            pass: measured.is_finite() && measured <= bound,
        }
    }

    /// A row that passes when `measured >= bound`.
    pub fn at_least(
        quantity: impl Into<String>,
        unit: impl Into<String>,
        measured: f64,
        bound: f64,
    ) -> Self {
        Self {
            quantity: quantity.into(),
            unit: unit.into(),
            measured,
            reference: bound,
            error: measured,
            tolerance: bound,
            kind: ErrorKind::AtLeast,
            pass: measured.is_finite() && measured >= bound,
        }
    }
}

impl Row {
    /// A reported comparison with a paper figure (see [`ErrorKind::Reported`]).
    pub fn reported(
        quantity: impl Into<String>,
        unit: impl Into<String>,
        measured: f64,
        reference: f64,
    ) -> Self {
        Self {
            quantity: quantity.into(),
            unit: unit.into(),
            measured,
            reference,
            error: measured - reference,
            tolerance: f64::NAN,
            kind: ErrorKind::Reported,
            pass: measured.is_finite(),
        }
    }
}

/// Whether a series is the code's result or the reference it is compared with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesRole {
    /// Produced by the code under test (drawn as markers or a solid line).
    Measured,
    /// Analytical or reference solution (drawn as a line).
    Reference,
}

/// One curve of a plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Measured or reference.
    pub role: SeriesRole,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates, same length as `x`.
    pub y: Vec<f64>,
}

/// A line plot of measured curves against reference curves.
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    /// File stem of the PNG/CSV (unique within the case), e.g. `"centreline_400s"`.
    pub name: String,
    /// Title shown above the plot.
    pub title: String,
    /// X-axis label with unit, e.g. `"x [m]"`.
    pub x_label: String,
    /// Y-axis label with unit, e.g. `"T [K]"`.
    pub y_label: String,
    /// The curves.
    pub series: Vec<Series>,
}

/// What a verification case returns.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CaseOutput {
    /// Table rows.
    pub rows: Vec<Row>,
    /// Plots of measured against reference curves.
    pub plots: Vec<Plot>,
    /// Free-text notes shown under the case in the report (choices, known gaps).
    pub notes: Vec<String>,
}

impl CaseOutput {
    /// True when every row passes (and there is at least one row).
    pub fn passed(&self) -> bool {
        !self.rows.is_empty() && self.rows.iter().all(|r| r.pass)
    }
}

/// A case that failed to run at all (the simulation returned an error).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CaseError(pub String);

impl fmt::Display for CaseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CaseError {}

impl CaseError {
    /// Wraps any displayable error.
    pub fn from_display(e: impl fmt::Display) -> Self {
        Self(e.to_string())
    }
}

/// A registered verification case.
#[derive(Debug, Clone, Copy)]
pub struct Case {
    /// Unique name, `crate/short_name`, e.g. `"eos/critical_point_water"`.
    pub name: &'static str,
    /// One line saying what is checked against what.
    pub description: &'static str,
    /// Part of the `--quick` subset that CI runs (keep each quick case under a few seconds).
    pub quick: bool,
    /// Runs the case.
    pub run: fn() -> Result<CaseOutput, CaseError>,
}
