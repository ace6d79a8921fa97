//! # thm-fvm-heat
//!
//! See `Cargo.toml` for the crate's role; the full module documentation (equations by paper
//! and number, units, validity range, public seam) arrives with the crate's implementation.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod verification {
    //! Verification cases of this crate, collected by `cargo xtask verify`.
    use thm_verify::Case;

    /// All verification cases of this crate.
    pub fn cases() -> Vec<Case> {
        Vec::new()
    }
}
