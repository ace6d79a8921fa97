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

/// Writes `path` through `fill` into a temporary sibling, flushes it to the disk (`fsync`), then
/// renames it over `path` and flushes the folder entry.
///
/// A crash, a kill or an error while writing (a full disk included) leaves the previous content
/// of `path` untouched and removes the temporary file; once this returns `Ok`, the new content
/// survives a power loss on file systems that honour `fsync`.
pub fn write_atomically(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<(), IoError> {
    let tmp = temporary_path(path);
    let file = File::create(&tmp).map_err(|e| IoError::file(&tmp, "create", e))?;
    let mut w = BufWriter::with_capacity(1 << 20, file);
    let written = fill(&mut w)
        .and_then(|()| w.flush())
        .and_then(|()| w.get_ref().sync_all());
    drop(w);
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(IoError::file(path, "write", e));
    }
    if let Err(e) = std::fs::rename(&tmp, path) {
        let _ = std::fs::remove_file(&tmp);
        return Err(IoError::file(path, "rename", e));
    }
    sync_folder_of(path);
    Ok(())
}

/// Flushes the folder entry of `path` (so a rename survives a power loss). Best effort: some
/// file systems refuse to sync a folder, which loses nothing a killed process could lose.
fn sync_folder_of(path: &Path) {
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if let Ok(dir) = File::open(folder) {
        let _ = dir.sync_all();
    }
}

/// Creates `dir` and its parents.
pub fn create_dir_all(dir: &Path) -> Result<(), IoError> {
    std::fs::create_dir_all(dir).map_err(|e| IoError::file(dir, "create folder", e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("thm-io-fsutil-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// A disk that fills up half-way through a write: the error names the file and says why,
    /// the previous content is intact and no temporary file is left behind.
    #[test]
    fn a_full_disk_keeps_the_previous_content_and_names_the_file() {
        let dir = scratch("enospc");
        let path = dir.join("state.ckpt");
        write_atomically(&path, |w| w.write_all(b"complete checkpoint\n")).unwrap();
        let err = write_atomically(&path, |w| {
            w.write_all(&[b'x'; 3 << 20])?;
            Err(std::io::Error::from_raw_os_error(28))
        })
        .unwrap_err();
        let message = err.to_string();
        assert!(
            matches!(&err, IoError::File { action: "write", source, .. }
                if source.kind() == std::io::ErrorKind::StorageFull),
            "{message}"
        );
        assert!(message.contains("state.ckpt"), "{message}");
        assert!(message.contains("No space left on device"), "{message}");
        assert_eq!(std::fs::read(&path).unwrap(), b"complete checkpoint\n");
        assert!(!temporary_path(&path).exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
