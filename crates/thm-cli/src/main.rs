//! The `thm` command-line tool.

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use thm_cli::{calibrate, eos, run};

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
    /// Calibrate the bond strengths (T, C = 5 T) and the T2T factor γ for a tensile strength
    /// and a permeability, as A-Sect. 3 (defaults: the paper's 8.8 MPa and 2.47e-16 m^2).
    Calibrate(calibrate::CalibrateArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Eos(command) => eos::run(command),
        Command::Run(args) => run::run(&args),
        Command::Calibrate(args) => calibrate::run(&args),
    }
}
