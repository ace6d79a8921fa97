//! CSV time histories: a header naming each column and its unit, one row per record.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::IoError;
use crate::fsutil::write_atomically;

/// A column of a history: a quantity and its unit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Column {
    /// The quantity, e.g. `axial_stress`.
    pub name: String,
    /// Its unit, e.g. `Pa` (empty when dimensionless).
    pub unit: String,
}

impl Column {
    /// A column `name [unit]`.
    pub fn new(name: impl Into<String>, unit: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            unit: unit.into(),
        }
    }

    /// The header cell: `name [unit]`, or `name` when dimensionless.
    pub fn header(&self) -> String {
        let cell = if self.unit.is_empty() {
            self.name.clone()
        } else {
            format!("{} [{}]", self.name, self.unit)
        };
        csv_field(&cell)
    }
}

/// Quotes a CSV cell if it needs it.
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The header line of `columns`.
pub fn header_line(columns: &[Column]) -> String {
    columns
        .iter()
        .map(Column::header)
        .collect::<Vec<_>>()
        .join(",")
}

/// Writes a number so that it reads back to the same `f64` (shortest exact form).
fn number(x: f64) -> String {
    format!("{x:?}")
}

/// A CSV history being appended to, row by row.
#[derive(Debug)]
pub struct CsvHistory {
    path: PathBuf,
    n_columns: usize,
    out: BufWriter<File>,
}

impl CsvHistory {
    /// Creates (or truncates) `path` and writes the header.
    pub fn create(path: &Path, columns: &[Column]) -> Result<Self, IoError> {
        let file = File::create(path).map_err(|e| IoError::file(path, "create", e))?;
        let mut out = BufWriter::new(file);
        writeln!(out, "{}", header_line(columns)).map_err(|e| IoError::file(path, "write", e))?;
        out.flush().map_err(|e| IoError::file(path, "write", e))?;
        Ok(Self {
            path: path.to_path_buf(),
            n_columns: columns.len(),
            out,
        })
    }

    /// Continues an existing history after a resume: checks the header, keeps the rows whose
    /// first column is `<= until` (the checkpoint's time), drops the later ones (they will be
    /// recomputed) and appends from there. A missing file is created.
    pub fn resume(path: &Path, columns: &[Column], until: f64) -> Result<Self, IoError> {
        if !path.exists() {
            return Self::create(path, columns);
        }
        let text = std::fs::read_to_string(path).map_err(|e| IoError::file(path, "read", e))?;
        // Only complete lines count: a run killed while appending leaves a last line without
        // its newline, whose leading digits could otherwise read as an earlier time.
        let mut lines = text
            .split_inclusive('\n')
            .filter_map(|l| l.strip_suffix('\n'));
        let header = header_line(columns);
        if lines.next() != Some(header.as_str()) {
            return Err(IoError::Malformed {
                path: path.to_path_buf(),
                message: format!("header differs from `{header}`"),
            });
        }
        let kept: Vec<&str> = lines
            .take_while(|l| {
                let mut values = l.split(',');
                let time = values.next().and_then(|t| t.parse::<f64>().ok());
                1 + values.count() == columns.len() && time.is_some_and(|t| t <= until)
            })
            .collect();
        write_atomically(path, |w| {
            writeln!(w, "{header}")?;
            for l in &kept {
                writeln!(w, "{l}")?;
            }
            Ok(())
        })?;
        let file = std::fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(|e| IoError::file(path, "open", e))?;
        Ok(Self {
            path: path.to_path_buf(),
            n_columns: columns.len(),
            out: BufWriter::new(file),
        })
    }

    /// Appends one row (buffered; see [`Self::flush`]).
    pub fn push(&mut self, row: &[f64]) -> Result<(), IoError> {
        if row.len() != self.n_columns {
            return Err(IoError::RowLength {
                path: self.path.clone(),
                len: row.len(),
                expected: self.n_columns,
            });
        }
        let line = row.iter().map(|&x| number(x)).collect::<Vec<_>>().join(",");
        writeln!(self.out, "{line}").map_err(|e| IoError::file(&self.path, "write", e))
    }

    /// Writes buffered rows to the file.
    pub fn flush(&mut self) -> Result<(), IoError> {
        self.out
            .flush()
            .map_err(|e| IoError::file(&self.path, "write", e))
    }
}

/// Writes a whole table at once (atomically).
pub fn write_csv(path: &Path, columns: &[Column], rows: &[Vec<f64>]) -> Result<(), IoError> {
    if let Some(r) = rows.iter().find(|r| r.len() != columns.len()) {
        return Err(IoError::RowLength {
            path: path.to_path_buf(),
            len: r.len(),
            expected: columns.len(),
        });
    }
    write_atomically(path, |w| {
        writeln!(w, "{}", header_line(columns))?;
        for r in rows {
            let line = r.iter().map(|&x| number(x)).collect::<Vec<_>>().join(",");
            writeln!(w, "{line}")?;
        }
        Ok(())
    })
}
