//! Checkpoints: any `serde` state saved with a container format version, a kind tag and the
//! state's own layout version.
//!
//! The file is JSON: `{"format":"thm-checkpoint","format_version":1,"kind":"…",
//! "state_version":n,"state":…}`. Every `f64` is written in its shortest exact decimal form and
//! parsed back exactly (serde_json's `float_roundtrip`), so a resumed run continues bit for bit.
//! Non-finite floats cannot be stored (JSON has no NaN): a state holding one fails to load
//! with [`IoError::CheckpointState`], never silently. Loading checks the header first: another
//! container version, another kind or another state version is a typed error.

use std::io::Write;
use std::path::Path;

use serde::de::{DeserializeOwned, IgnoredAny};
use serde::{Deserialize, Serialize};

use crate::IoError;
use crate::fsutil::write_atomically;

/// Version of the checkpoint container written by this crate.
pub const CHECKPOINT_FORMAT_VERSION: u32 = 1;

const FORMAT_TAG: &str = "thm-checkpoint";

#[derive(Serialize)]
struct EnvelopeOut<'a, T> {
    format: &'a str,
    format_version: u32,
    kind: &'a str,
    state_version: u32,
    state: &'a T,
}

#[derive(Deserialize)]
struct Header {
    format: String,
    format_version: u32,
    kind: String,
    state_version: u32,
    #[allow(dead_code)]
    state: IgnoredAny,
}

#[derive(Deserialize)]
struct EnvelopeIn<T> {
    state: T,
}

/// Saves `state` (atomically) under the tag `kind` and layout version `state_version`.
pub fn save_checkpoint<T: Serialize>(
    path: &Path,
    kind: &str,
    state_version: u32,
    state: &T,
) -> Result<(), IoError> {
    let envelope = EnvelopeOut {
        format: FORMAT_TAG,
        format_version: CHECKPOINT_FORMAT_VERSION,
        kind,
        state_version,
        state,
    };
    write_atomically(path, |w| {
        serde_json::to_writer(&mut *w, &envelope).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
}

/// Reads the kind tag of a checkpoint (to dispatch on it before loading the state).
pub fn checkpoint_kind(path: &Path) -> Result<String, IoError> {
    Ok(read_header(path)?.1.kind)
}

fn read_header(path: &Path) -> Result<(Vec<u8>, Header), IoError> {
    let bytes = std::fs::read(path).map_err(|e| IoError::file(path, "read", e))?;
    let header: Header = serde_json::from_slice(&bytes).map_err(|e| IoError::NotACheckpoint {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    if header.format != FORMAT_TAG {
        return Err(IoError::NotACheckpoint {
            path: path.to_path_buf(),
            message: format!("format tag `{}`", header.format),
        });
    }
    if header.format_version != CHECKPOINT_FORMAT_VERSION {
        return Err(IoError::CheckpointFormatVersion {
            path: path.to_path_buf(),
            found: header.format_version,
            expected: CHECKPOINT_FORMAT_VERSION,
        });
    }
    Ok((bytes, header))
}

/// Loads a state saved by [`save_checkpoint`] with the same `kind` and `state_version`.
pub fn load_checkpoint<T: DeserializeOwned>(
    path: &Path,
    kind: &str,
    state_version: u32,
) -> Result<T, IoError> {
    let (bytes, header) = read_header(path)?;
    if header.kind != kind {
        return Err(IoError::CheckpointKind {
            path: path.to_path_buf(),
            found: header.kind,
            expected: kind.to_string(),
        });
    }
    if header.state_version != state_version {
        return Err(IoError::CheckpointStateVersion {
            path: path.to_path_buf(),
            kind: header.kind,
            found: header.state_version,
            expected: state_version,
        });
    }
    let envelope: EnvelopeIn<T> =
        serde_json::from_slice(&bytes).map_err(|e| IoError::CheckpointState {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    Ok(envelope.state)
}
