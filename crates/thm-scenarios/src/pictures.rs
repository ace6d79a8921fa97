//! Pictures of the state at every frame (`pictures/NAME_STEP.png`), drawn by the kind
//! ([`crate::scenario::Scenario::pictures`]) and shown in `summary.md`.

use std::fmt::Write as _;
use std::path::Path;

use thm_io::Picture;

use crate::error::RunError;
use crate::profiles::{io_error, step_files, thin};

/// Folder of the pictures in the output folder.
pub const PICTURE_DIR: &str = "pictures";

/// How many pictures of each name the summary shows (evenly spaced, the last included).
const SHOWN: usize = 6;

/// Writes each `(name, picture)` as `pictures/NAME_STEP.png` (atomically).
pub fn write_pictures(
    out: &Path,
    step: u64,
    pictures: &[(String, Picture)],
) -> Result<(), RunError> {
    if pictures.is_empty() {
        return Ok(());
    }
    let dir = out.join(PICTURE_DIR);
    std::fs::create_dir_all(&dir).map_err(io_error(&dir, "create"))?;
    for (name, picture) in pictures {
        thm_io::write_picture_png(picture, &dir.join(format!("{name}_{step:010}.png")))?;
    }
    Ok(())
}

/// A section of `md` showing up to six pictures of each name, from the frames up to
/// `last_step`.
pub fn embed_pictures(out: &Path, last_step: u64, md: &mut String) {
    let by_name = step_files(&out.join(PICTURE_DIR), "png", last_step);
    if by_name.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "## Pictures\n\nEvery frame's pictures are in [`{PICTURE_DIR}/`]({PICTURE_DIR}/).\n"
    );
    for (name, files) in &by_name {
        let _ = writeln!(md, "### {}\n", name.replace('_', " "));
        for (step, path) in thin(files, SHOWN) {
            if let Some(file) = path.file_name().and_then(|f| f.to_str()) {
                let _ = write!(md, "![{name} at step {step}]({PICTURE_DIR}/{file}) ");
            }
        }
        let _ = writeln!(md, "\n");
    }
}
