//! The `thm` command-line tool.

// The subcommands arrive with the crates that implement them; until then the enum is empty.
#![allow(unreachable_code, unused_variables)]

mod run;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Coupled thermo-hydro-mechanical simulation of granular and porous materials.
#[derive(Debug, Parser)]
#[command(name = "thm", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a scenario file: histories, ParaView series, checkpoints and a summary.
    Run(run::RunArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Run(args) => run::run(&args),
    }
}
