//! ParaView collections (`.pvd`): a time series of `.vtu` frames opened at once.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::IoError;
use crate::fsutil::{create_dir_all, write_atomically};
use crate::vtu::{Encoding, UnstructuredGrid, xml_escape, xml_unescape};

/// One frame of a collection.
#[derive(Debug, Clone, PartialEq)]
pub struct PvdFrame {
    /// Simulated time of the frame \[s\].
    pub time: f64,
    /// Part number (several grids at one time, e.g. particles and cells).
    pub part: u32,
    /// The frame's file, relative to the `.pvd` file's folder.
    pub file: String,
}

/// A `.pvd` collection kept in time order; every change rewrites the file atomically.
#[derive(Debug, Clone)]
pub struct PvdCollection {
    path: PathBuf,
    frames: Vec<PvdFrame>,
}

impl PvdCollection {
    /// A new, empty collection at `path` (the file is written on the first [`Self::add`]).
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            frames: Vec::new(),
        }
    }

    /// Reads an existing collection (written by this crate), e.g. to continue a resumed run.
    pub fn open(path: impl Into<PathBuf>) -> Result<Self, IoError> {
        let path = path.into();
        let text = std::fs::read_to_string(&path).map_err(|e| IoError::file(&path, "read", e))?;
        let frames = parse_frames(&text).map_err(|message| IoError::Malformed {
            path: path.clone(),
            message,
        })?;
        Ok(Self { path, frames })
    }

    /// Opens `path` if it exists, otherwise starts an empty collection there.
    pub fn open_or_new(path: impl Into<PathBuf>) -> Result<Self, IoError> {
        let path = path.into();
        if path.exists() {
            Self::open(path)
        } else {
            Ok(Self::new(path))
        }
    }

    /// The collection's file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The frames, in time order (then part order).
    pub fn frames(&self) -> &[PvdFrame] {
        &self.frames
    }

    /// Adds a frame in time order (a frame with the same time and part replaces the old one)
    /// and rewrites the file.
    pub fn add(&mut self, time: f64, part: u32, file: impl Into<String>) -> Result<(), IoError> {
        if !time.is_finite() {
            return Err(IoError::BadValue {
                quantity: "frame time",
                requirement: "finite",
                value: time,
            });
        }
        let frame = PvdFrame {
            time,
            part,
            file: file.into(),
        };
        let key = |f: &PvdFrame| (f.time, f.part);
        match self.frames.binary_search_by(|f| {
            key(f)
                .partial_cmp(&key(&frame))
                .unwrap_or(std::cmp::Ordering::Less)
        }) {
            Ok(i) => self.frames[i] = frame,
            Err(i) => self.frames.insert(i, frame),
        }
        self.write()
    }

    /// Drops the frames later than `time` (a run resumed from a checkpoint at `time` writes
    /// them again) and rewrites the file.
    pub fn retain_until(&mut self, time: f64) -> Result<(), IoError> {
        self.frames.retain(|f| f.time <= time);
        self.write()
    }

    /// Writes the collection (atomically).
    pub fn write(&self) -> Result<(), IoError> {
        write_atomically(&self.path, |w| {
            writeln!(w, "<?xml version=\"1.0\"?>")?;
            writeln!(
                w,
                "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">"
            )?;
            writeln!(w, "  <Collection>")?;
            for f in &self.frames {
                writeln!(
                    w,
                    "    <DataSet timestep=\"{:?}\" group=\"\" part=\"{}\" file=\"{}\"/>",
                    f.time,
                    f.part,
                    xml_escape(&f.file)
                )?;
            }
            writeln!(w, "  </Collection>")?;
            writeln!(w, "</VTKFile>")
        })
    }
}

/// Reads the `DataSet` entries of a collection file.
fn parse_frames(text: &str) -> Result<Vec<PvdFrame>, String> {
    if !text.contains("type=\"Collection\"") {
        return Err("not a VTK collection file".into());
    }
    let mut frames = Vec::new();
    for piece in text.split("<DataSet").skip(1) {
        let element = piece.split("/>").next().unwrap_or("");
        let attr = |name: &str| -> Result<String, String> {
            let key = format!("{name}=\"");
            let start = element
                .find(&key)
                .ok_or_else(|| format!("a DataSet has no `{name}` attribute"))?
                + key.len();
            let len = element[start..]
                .find('"')
                .ok_or_else(|| format!("unterminated `{name}` attribute"))?;
            Ok(xml_unescape(&element[start..start + len]))
        };
        let time_text = attr("timestep")?;
        let time = time_text
            .parse::<f64>()
            .map_err(|_| format!("timestep `{time_text}` is not a number"))?;
        let part = attr("part")
            .ok()
            .and_then(|p| p.parse::<u32>().ok())
            .unwrap_or(0);
        frames.push(PvdFrame {
            time,
            part,
            file: attr("file")?,
        });
    }
    frames.sort_by(|a, b| {
        (a.time, a.part)
            .partial_cmp(&(b.time, b.part))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    Ok(frames)
}

/// A series of frames of one grid: `<dir>/<name>.pvd` indexing `<dir>/<name>/<name>_<step>.vtu`.
#[derive(Debug, Clone)]
pub struct VtuSeries {
    dir: PathBuf,
    name: String,
    encoding: Encoding,
    collection: PvdCollection,
}

impl VtuSeries {
    /// Starts (or, when `<dir>/<name>.pvd` exists, continues) a series.
    pub fn new(dir: &Path, name: &str, encoding: Encoding) -> Result<Self, IoError> {
        create_dir_all(&dir.join(name))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            name: name.to_string(),
            encoding,
            collection: PvdCollection::open_or_new(dir.join(format!("{name}.pvd")))?,
        })
    }

    /// Writes the frame of `step` at simulated `time` and indexes it.
    pub fn write_frame(
        &mut self,
        step: u64,
        time: f64,
        grid: &UnstructuredGrid<'_>,
    ) -> Result<(), IoError> {
        let rel = format!("{0}/{0}_{step:08}.vtu", self.name);
        grid.write_vtu(&self.dir.join(&rel), self.encoding)?;
        self.collection.add(time, 0, rel)
    }

    /// Forgets frames later than `time` (on resume).
    pub fn retain_until(&mut self, time: f64) -> Result<(), IoError> {
        self.collection.retain_until(time)
    }

    /// The series name (stem of the `.pvd` and of the frames).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The collection.
    pub fn collection(&self) -> &PvdCollection {
        &self.collection
    }
}
