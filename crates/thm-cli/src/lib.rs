//! # thm-cli
//!
//! The `thm` command-line tool's subcommands as a library, so that tests and fuzz targets
//! drive exactly what the binary runs: [`eos`] (equation of state over CSV), [`run`] (scenario
//! files: reading, validation, the driver, checkpoints and resume) and [`calibrate`].
//!
//! Every input (a scenario file, a packing CSV, an EOS CSV row, a checkpoint) gives a typed
//! error naming the key, line or field and the allowed range, never a panic; messages quote at
//! most a short excerpt of the input.

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod calibrate;
pub mod eos;
#[cfg(feature = "mpi")]
pub mod mpi_rve;
pub mod run;
