//! Verification cases of this crate, collected by `cargo xtask verify`.
use thm_verify::Case;

/// All verification cases of `thm-rve`.
pub fn cases() -> Vec<Case> {
    Vec::new()
}
