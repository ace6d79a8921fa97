//! `thm eos pressure|density|closure`: the equation of state over CSV, from standard input to
//! standard output (the tables are [`thm_scenarios::eos_csv`]); on an error the rows before it
//! stay written, the error names the line, the data row and the column, and the exit status
//! is 1.

use clap::{Args, Subcommand, ValueEnum};
use std::io::{self, BufWriter, Write};
use std::process::ExitCode;
use thm_eos::Model;
use thm_scenarios::eos_csv::{CsvError, Table, process_csv};

/// The three EOS subcommands.
#[derive(Debug, Subcommand)]
pub enum EosCommand {
    /// Pressure from temperature and density. Input `fluid,T,rho` (K, kg/m³); output
    /// `fluid,T,rho,P` (Pa).
    Pressure(ModelArg),
    /// Density from temperature and pressure on a branch. Input `fluid,T,P,branch` (K, Pa,
    /// `liquid` = smallest molar volume above b, `gas` = largest); output `fluid,T,P,branch,rho`.
    Density(ModelArg),
    /// Two-phase pore closure (liquid = water, gas = air). Input `T,V,m_liquid,m_gas`
    /// (K, m³, kg, kg); output `T,V,m_liquid,m_gas,alpha,P,rho_liquid,rho_gas`.
    Closure(ModelArg),
}

/// The `--model` option.
#[derive(Debug, Args)]
pub struct ModelArg {
    /// `pr`: plain Peng–Robinson; `pr-corrected`: with the liquid water volume correction
    /// s = −0.0034 m³/kmol (paper A's model).
    #[arg(long, value_enum, default_value_t = ModelChoice::PrCorrected)]
    model: ModelChoice,
}

/// The models a user can choose on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ModelChoice {
    Pr,
    PrCorrected,
}

impl From<ModelChoice> for Model {
    fn from(m: ModelChoice) -> Self {
        match m {
            ModelChoice::Pr => Model::Pr,
            ModelChoice::PrCorrected => Model::PrCorrected,
        }
    }
}

/// Runs one subcommand on standard input and output.
pub fn run(command: EosCommand) -> ExitCode {
    let stdin = io::stdin();
    let stdout = io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let (name, table, model) = match command {
        EosCommand::Pressure(m) => ("pressure", Table::Pressure, m.model),
        EosCommand::Density(m) => ("density", Table::Density, m.model),
        EosCommand::Closure(m) => ("closure", Table::Closure, m.model),
    };
    let result = process_csv(table, model.into(), stdin.lock(), &mut out);
    let flushed = out.flush();
    match result.and(flushed.map_err(CsvError::from)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("thm eos {name}: {e}");
            ExitCode::FAILURE
        }
    }
}
