//! # thm-io
//!
//! The result files every THM crate and the `thm` binary share, so that no crate writes its
//! own format. No physics lives here.
//!
//! - [`vtu`]: VTK XML unstructured grids (`.vtu`) of particles and material points (vertex
//!   cells), line networks, triangle meshes and quad grids, with any number of scalar, vector and integer
//!   point and cell fields; appended raw binary, appended base64 or inline ASCII.
//! - [`pvd`]: ParaView collections (`.pvd`) indexing a time series of frames in time order;
//!   every change rewrites the file atomically; [`pvd::VtuSeries`] names and indexes frames.
//! - [`csv`]: time histories whose header names every column with its unit, `name [unit]`.
//! - [`plot`]: PNG line plots of a [`thm_verify::Plot`] (measured markers, reference lines,
//!   axes labelled with units) with an embedded font, and the plot's curves as CSV.
//! - [`picture`]: PNG pictures of filled polygons and segments in world coordinates at equal
//!   axis scales (a mesh coloured by cell type and owner).
//! - [`checkpoint`]: `serde` save/load of any state with a container version, a kind tag,
//!   a state layout version and a CRC-32, as one line of JSON for small states and a compact
//!   binary form for large ones; a mismatch, a truncated file or an altered byte is a typed
//!   error, never a misread.
//!
//! Units: files store what the caller gives (SI throughout the workspace); names of fields
//! and columns should carry the unit (`temperature [K]`, `radius_m`).
//!
//! The VTU writer is written here rather than taken from `vtkio` 0.7.0-rc2: vtkio's writer
//! needs every array copied into its own owned buffer (a 10⁶-particle frame would be copied
//! before writing), and its reader of raw appended data is compiled out. vtkio serves as the
//! independent reader in this crate's tests (ASCII and base64 files); raw files are checked to
//! carry the same bytes as their base64 twins.
//!
//! Every file is written to a temporary sibling and renamed into place, so an interrupted
//! write never destroys a file written before. Numbers in text formats (ASCII VTU, CSV, PVD
//! times, checkpoints) are written in their shortest exact decimal form and read back to the
//! same bits.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod checkpoint;
pub mod csv;
mod error;
pub mod fsutil;
pub mod picture;
pub mod plot;
pub mod pvd;
pub mod vtu;

pub use checkpoint::{
    CHECKPOINT_FORMAT_VERSION, CheckpointEncoding, CheckpointInfo, checkpoint_from_bytes,
    checkpoint_info, checkpoint_kind, load_checkpoint, save_checkpoint, save_checkpoint_as,
};
pub use csv::{Column, CsvHistory, write_csv};
pub use error::IoError;
pub use picture::{
    ColourBar, FilledPolygon, Picture, Segment, render_picture_png, write_picture_png,
};
pub use plot::{render_plot_png, write_plot_csv, write_plot_png};
pub use pvd::{PvdCollection, PvdFrame, VtuSeries};
pub use vtu::{CellIndices, Cells, Encoding, Field, FieldValues, Points, UnstructuredGrid};
