//! The `thm` command-line tool.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod eos;
mod run;

/// Coupled thermo-hydro-mechanical simulation of granular and porous materials.
#[derive(Debug, Parser)]
#[command(name = "thm", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Equation of state over CSV: reads standard input, writes standard output.
    #[command(subcommand)]
    Eos(eos::EosCommand),
    /// Run a scenario file: histories, ParaView series, checkpoints and a summary.
    Run(run::RunArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Eos(command) => eos::run(command),
        Command::Run(args) => run::run(&args),
    }
}
