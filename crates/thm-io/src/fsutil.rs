//! Writing a file so that a reader never sees it half-written.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::IoError;

/// The temporary sibling a file is written to before it is renamed into place.
fn temporary_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".partial");
    path.with_file_name(name)
}

/// Writes `path` through `fill` into a temporary sibling, then renames it over `path`.
///
/// A crash or an error while writing leaves the previous content of `path` untouched (the
/// rename is atomic on POSIX file systems; no `fsync` is issued, so this protects against a
/// killed process, not against power loss).
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<(), IoError> {
    let tmp = temporary_path(path);
    let file = File::create(&tmp).map_err(|e| IoError::file(&tmp, "create", e))?;
    let mut w = BufWriter::with_capacity(1 << 20, file);
    let written = fill(&mut w).and_then(|()| w.flush());
    drop(w);
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(IoError::file(path, "write", e));
    }
    std::fs::rename(&tmp, path).map_err(|e| IoError::file(path, "rename", e))
}

/// Creates `dir` and its parents.
pub fn create_dir_all(dir: &Path) -> Result<(), IoError> {
    std::fs::create_dir_all(dir).map_err(|e| IoError::file(dir, "create folder", e))
}
