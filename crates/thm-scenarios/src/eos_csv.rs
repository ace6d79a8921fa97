//! The equation of state over CSV (`thm eos pressure|density|closure`).
//!
//! Each table reads CSV with a fixed header and writes CSV: the input columns (as given, fluid
//! and branch names in lower case) followed by the computed ones, written with 17 significant
//! digits (enough to round-trip an `f64`). Each row is flushed as soon as it is written, so on
//! an error (a malformed row, an unknown fluid, a state with no physical solution) the rows
//! before it stay written; the error names the line, the data row and the column.

use std::fmt;
use std::io::{self, BufRead, Write};
use thm_eos::{
    Branch, EosError, EquationOfState, Model, PengRobinson, PoreClosure, water_air_closure,
};

/// Which table a CSV run computes (the subcommand).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Table {
    /// `fluid,T,rho` → `P`.
    Pressure,
    /// `fluid,T,P,branch` → `rho`.
    Density,
    /// `T,V,m_liquid,m_gas` → `alpha,P,rho_liquid,rho_gas`.
    Closure,
}

/// Reads CSV `input` and writes the computed table to `out`, as the subcommand does: every
/// input gives rows or a [`CsvError`] naming line, row and column, never a panic.
pub fn process_csv<R: BufRead, W: Write>(
    table: Table,
    model: Model,
    input: R,
    out: &mut W,
) -> Result<(), CsvError> {
    match table {
        Table::Pressure => pressure(input, out, model),
        Table::Density => density(input, out, model),
        Table::Closure => closure(input, out, model),
    }
}

/// Where in the input an error occurred and what it was.
#[derive(Debug)]
pub enum CsvError {
    /// A problem with one row (or the header, row 0).
    Row {
        /// Line of the input (from 1).
        line: usize,
        /// Data row (from 1; 0 is the header).
        row: usize,
        /// The column at fault.
        column: String,
        /// What is wrong and what is allowed.
        message: String,
    },
    /// Reading standard input or writing standard output failed.
    Io(io::Error),
}

impl fmt::Display for CsvError {
    /// Quoted input (a field, a header) is cut to a short excerpt: a row can be megabytes.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use crate::error::shorten;
        match self {
            CsvError::Row {
                line,
                row: 0,
                column,
                message,
            } => f.write_str(&shorten(&format!(
                "line {line} (header), column `{column}`: {message}"
            ))),
            CsvError::Row {
                line,
                row,
                column,
                message,
            } => f.write_str(&shorten(&format!(
                "line {line} (row {row}), column `{column}`: {message}"
            ))),
            CsvError::Io(e) => write!(f, "i/o error: {e}"),
        }
    }
}

impl From<io::Error> for CsvError {
    fn from(e: io::Error) -> Self {
        CsvError::Io(e)
    }
}

/// A data row split into trimmed fields, with its position for error messages.
struct Record<'a> {
    line: usize,
    row: usize,
    columns: &'static [&'static str],
    fields: Vec<&'a str>,
}

impl Record<'_> {
    fn error(&self, column: &str, message: impl Into<String>) -> CsvError {
        CsvError::Row {
            line: self.line,
            row: self.row,
            column: column.to_owned(),
            message: message.into(),
        }
    }

    fn text(&self, i: usize) -> &str {
        self.fields[i]
    }

    fn number(&self, i: usize) -> Result<f64, CsvError> {
        let s = self.fields[i];
        s.parse::<f64>()
            .map_err(|_| self.error(self.columns[i], format!("`{s}` is not a number")))
    }

    fn fluid(&self, i: usize, model: Model) -> Result<(&'static str, PengRobinson), CsvError> {
        match self.fields[i].to_ascii_lowercase().as_str() {
            "water" => Ok(("water", PengRobinson::water(model))),
            "air" => Ok(("air", PengRobinson::air())),
            other => Err(self.error(
                self.columns[i],
                format!("unknown fluid `{other}` (allowed: water, air)"),
            )),
        }
    }

    fn branch(&self, i: usize) -> Result<(&'static str, Branch), CsvError> {
        match self.fields[i].to_ascii_lowercase().as_str() {
            "liquid" => Ok(("liquid", Branch::Liquid)),
            "gas" => Ok(("gas", Branch::Gas)),
            other => Err(self.error(
                self.columns[i],
                format!("unknown branch `{other}` (allowed: liquid, gas)"),
            )),
        }
    }

    /// An EOS error, attributed to the column of the quantity it names.
    fn eos_error(&self, e: &EosError, column_of: impl Fn(&str) -> &'static str) -> CsvError {
        let column = match e {
            EosError::InvalidInput { quantity, .. } => column_of(quantity),
            EosError::BelowCovolume { .. } => column_of("density"),
            EosError::NoRoot { .. } => column_of("pressure"),
            EosError::Unrepresentable { input, .. } => column_of(input),
            EosError::OutsideModelRange { quantity, .. } => column_of(quantity),
            EosError::NoClosure { .. } | EosError::InvalidParameter { .. } => column_of("state"),
        };
        self.error(column, e.to_string())
    }
}

/// Reads the header and then calls `row` for each non-blank data line, flushing after each.
fn process<R: BufRead, W: Write>(
    input: R,
    out: &mut W,
    columns: &'static [&'static str],
    extra: &[&str],
    mut row: impl FnMut(&Record<'_>, &mut W) -> Result<(), CsvError>,
) -> Result<(), CsvError> {
    let mut lines = input.lines().enumerate();
    let header = loop {
        match lines.next() {
            Some((_, line)) => {
                let line = line?;
                if !line.trim().is_empty() {
                    break line;
                }
            }
            None => {
                return Err(CsvError::Row {
                    line: 1,
                    row: 0,
                    column: columns[0].to_owned(),
                    message: format!("missing header, expected `{}`", columns.join(",")),
                });
            }
        }
    };
    let found: Vec<&str> = header.split(',').map(str::trim).collect();
    for (i, want) in columns.iter().enumerate() {
        if found.get(i) != Some(want) || found.len() != columns.len() {
            return Err(CsvError::Row {
                line: 1,
                row: 0,
                column: found.get(i).copied().unwrap_or("").to_owned(),
                message: format!(
                    "header must be `{}`, found `{}`",
                    columns.join(","),
                    header.trim()
                ),
            });
        }
    }
    writeln!(out, "{},{}", columns.join(","), extra.join(","))?;
    out.flush()?;
    let mut data_row = 0;
    for (index, line) in lines {
        let line = line?;
        if line.trim().is_empty() {
            continue;
        }
        data_row += 1;
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let record = Record {
            line: index + 1,
            row: data_row,
            columns,
            fields,
        };
        if record.fields.len() != columns.len() {
            let column = columns
                .get(record.fields.len())
                .copied()
                .unwrap_or("(extra)");
            return Err(record.error(
                column,
                format!(
                    "expected {} columns ({}), found {}",
                    columns.len(),
                    columns.join(","),
                    record.fields.len()
                ),
            ));
        }
        row(&record, out)?;
        out.flush()?;
    }
    Ok(())
}

/// 17 significant digits: every `f64` round-trips.
fn num(x: f64) -> String {
    format!("{x:.16e}")
}

fn pressure<R: BufRead, W: Write>(input: R, out: &mut W, model: Model) -> Result<(), CsvError> {
    const COLUMNS: &[&str] = &["fluid", "T", "rho"];
    process(input, out, COLUMNS, &["P"], |r, out| {
        let (fluid, eos) = r.fluid(0, model)?;
        let t = r.number(1)?;
        let rho = r.number(2)?;
        let p = eos
            .pressure(t, rho)
            .map_err(|e| r.eos_error(&e, |q| if q == "temperature" { "T" } else { "rho" }))?;
        writeln!(out, "{fluid},{},{},{}", r.text(1), r.text(2), num(p))?;
        Ok(())
    })
}

fn density<R: BufRead, W: Write>(input: R, out: &mut W, model: Model) -> Result<(), CsvError> {
    const COLUMNS: &[&str] = &["fluid", "T", "P", "branch"];
    process(input, out, COLUMNS, &["rho"], |r, out| {
        let (fluid, eos) = r.fluid(0, model)?;
        let t = r.number(1)?;
        let p = r.number(2)?;
        let (branch_name, branch) = r.branch(3)?;
        let rho = eos
            .density(t, p, branch)
            .map_err(|e| r.eos_error(&e, |q| if q == "temperature" { "T" } else { "P" }))?;
        writeln!(
            out,
            "{fluid},{},{},{branch_name},{}",
            r.text(1),
            r.text(2),
            num(rho)
        )?;
        Ok(())
    })
}

fn closure<R: BufRead, W: Write>(input: R, out: &mut W, model: Model) -> Result<(), CsvError> {
    const COLUMNS: &[&str] = &["T", "V", "m_liquid", "m_gas"];
    let pore = water_air_closure(model);
    process(
        input,
        out,
        COLUMNS,
        &["alpha", "P", "rho_liquid", "rho_gas"],
        |r, out| {
            let t = r.number(0)?;
            let v = r.number(1)?;
            let m_l = r.number(2)?;
            let m_g = r.number(3)?;
            let s = pore.close(t, v, m_l, m_g).map_err(|e| {
                r.eos_error(&e, |q| match q {
                    "temperature" => "T",
                    "pore_volume" => "V",
                    "liquid_mass" => "m_liquid",
                    "gas_mass" => "m_gas",
                    // No single column is at fault: the state as a whole has no solution.
                    _ => "T,V,m_liquid,m_gas",
                })
            })?;
            writeln!(
                out,
                "{},{},{},{},{},{},{},{}",
                r.text(0),
                r.text(1),
                r.text(2),
                r.text(3),
                num(s.liquid_fraction),
                num(s.pressure),
                num(s.liquid_density),
                num(s.gas_density)
            )?;
            Ok(())
        },
    )
}
