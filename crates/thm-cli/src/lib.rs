//! # thm-cli
//!
//! The `thm` command: argument parsing, MPI start-up and exit codes over
//! [`thm_scenarios`], which holds everything a run does. The subcommands live here as a
//! library so that tests drive exactly what the binary runs: [`eos`] (equation of state over
//! CSV), [`run`] (scenario files) and [`calibrate`].

#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod calibrate;
pub mod eos;
#[cfg(feature = "mpi")]
pub mod mpi_rve;
pub mod run;
