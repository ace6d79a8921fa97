//! `thm calibrate`: the bond strengths and the T2T reduction factor of the pore-scale model
//! for a measured tensile strength and permeability, as A-Sect. 3 calibrates DEM and CFD
//! separately. The DEM part finds the bond tensile strength `T` (with `C/T` fixed, 5 in
//! A-Table 1) for which the mean strength of the seeded 20 × 80 mm bars in uniaxial tension
//! (A-Sect. 3.1) is the target; the CFD part finds γ (A-Eq. 9) for which the geometric mean
//! permeability of the bars' pore networks (A-Sect. 3.2, A-Eq. 56) is the target. Both print
//! every iteration and the result beside A-Table 1.
//!
//! `--packings` says on which bars: `coupled-bar` (default), the packing family the coupled
//! bar cases run on (`thm_coupling::calibration::BarFamily::coupled_cases`: cut ends, every
//! overlapping pair bonded, meshed as the cases mesh it), so that what is calibrated is what
//! runs; `tension-bar`, `thm-dem`'s tension-bar generator (bonds within 4 mm,
//! [`thm_dem::calibration::calibrate_bond_strength`]) and the Darcy test's packings
//! ([`thm_vpn_flow::permeability::calibrate_t2t_factor`]).

use std::process::ExitCode;

use clap::{Args, ValueEnum};
use serde::Deserialize;
use thm_coupling::calibration::BarFamily;
use thm_dem::calibration::{StrengthCalibration, calibrate_bond_strength};
use thm_vpn_flow::permeability::{PermeabilityCalibration, calibrate_t2t_factor};

use thm_scenarios::units::{Pressure, Quantity};

/// Which calibration to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Part {
    /// Bond strengths T, C against the tensile strength.
    Bar,
    /// T2T reduction factor γ against the permeability.
    Flow,
}

/// Which packings the calibration runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Packings {
    /// The coupled bar cases' own packings (cut ends, overlap bonds, the cases' mesh).
    CoupledBar,
    /// `thm-dem`'s tension-bar generator and the Darcy test's packings.
    TensionBar,
}

/// Arguments of `thm calibrate`.
#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// Target mean tensile strength of the bar packings: Pa, or with a unit ("8.8 MPa").
    /// Paper A: 8.8 MPa (A-Sect. 3.1).
    #[arg(long, default_value = "8.8 MPa", allow_hyphen_values = true)]
    strength: String,
    /// Target permeability [m^2]. Paper A: 2.47e-16 m^2 (A-Sect. 3.2).
    #[arg(long, default_value_t = 2.47e-16, allow_hyphen_values = true)]
    permeability: f64,
    /// Which packings: the coupled bar cases' own (default) or `thm-dem`'s tension bars and
    /// the Darcy test's.
    #[arg(long, value_enum, default_value = "coupled-bar")]
    packings: Packings,
    /// Packing seeds of the tension bars (comma-separated); their mean strength is matched.
    #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5")]
    seeds: Vec<u64>,
    /// Packing seeds of the permeability bars (comma-separated); the geometric mean of their
    /// permeabilities is matched. Default: those of `--seeds` on the coupled bar; packing 1
    /// (the paper calibrated on its one packing) on the Darcy test's.
    #[arg(long, value_delimiter = ',')]
    flow_seeds: Option<Vec<u64>>,
    /// C/T, held fixed. A-Table 1: 150/30 = 5.
    #[arg(long, default_value_t = 5.0)]
    cohesion_ratio: f64,
    /// The pore mesher's snap tolerance (× the radius) for the permeability bars; the
    /// default is the mesher's, 1e-6 (a scenario's `snap_tolerance`).
    #[arg(long, default_value_t = 1e-6)]
    snap_tolerance: f64,
    /// T2T faces shorter than this [m] carry at least the zero-stress S2S aperture in the
    /// permeability bars; 0 (default): A-Eq. 9 alone (a scenario's `narrow_gap_length`).
    #[arg(long, default_value_t = 0.0)]
    narrow_gap_length: f64,
    /// Run only one of the two calibrations.
    #[arg(long, value_enum)]
    only: Option<Part>,
}

/// A-Table 1 and A-Sect. 3.1.
const PAPER_T: f64 = 30e6;
const PAPER_C: f64 = 150e6;
const PAPER_GAMMA: f64 = 0.0115;
const PAPER_MODULUS: f64 = 3.5e9;
const PAPER_STRAIN_AT_PEAK: f64 = 0.0028;
const PAPER_COORDINATION: f64 = 6.53;

/// A strength given as a number (Pa) or a string with a unit.
fn parse_strength(text: &str) -> Result<f64, String> {
    let value = match text.trim().parse::<f64>() {
        Ok(v) => toml::Value::Float(v),
        Err(_) => toml::Value::String(text.trim().to_string()),
    };
    let q = Quantity::<Pressure>::deserialize(value).map_err(|e| e.to_string())?;
    q.positive("--strength").map_err(|e| e.to_string())
}

fn bar(args: &CalibrateArgs, target: f64) -> Result<(), String> {
    let settings = StrengthCalibration {
        target_strength: target,
        seeds: args.seeds.clone(),
        cohesion_ratio: args.cohesion_ratio,
        ..StrengthCalibration::paper_a()
    };
    println!(
        "## Bond strengths: mean tensile strength of {} {} packing(s) (seeds {:?}) = {:.4} MPa, C = {} T",
        args.seeds.len(),
        packings_name(args.packings),
        args.seeds,
        target / 1e6,
        args.cohesion_ratio
    );
    let cal = match args.packings {
        Packings::CoupledBar => BarFamily::coupled_cases().calibrate_bond_strength(&settings),
        Packings::TensionBar => calibrate_bond_strength(&settings),
    }
    .map_err(|e| format!("--strength {}: {e}", args.strength))?;
    println!("iteration  T [MPa]     C [MPa]     mean strength [MPa]");
    for (i, it) in cal.iterations.iter().enumerate() {
        println!(
            "{i:9}  {:10.4}  {:10.4}  {:10.4}",
            it.tensile_strength / 1e6,
            it.cohesion / 1e6,
            it.mean_strength / 1e6
        );
    }
    println!("quantity                 calibrated   paper (A-Table 1, A-Sect. 3.1)");
    let row = |name: &str, unit: &str, value: f64, paper: f64| {
        println!(
            "{:<24} {value:>10.4}   {paper:.4} {unit} ({:+.1} %)",
            format!("{name} [{unit}]"),
            100.0 * (value / paper - 1.0)
        );
    };
    row("T", "MPa", cal.tensile_strength() / 1e6, PAPER_T / 1e6);
    row("C", "MPa", cal.cohesion() / 1e6, PAPER_C / 1e6);
    row(
        "tensile strength",
        "MPa",
        cal.calibrated().mean_strength / 1e6,
        8.8,
    );
    row(
        "Young's modulus",
        "GPa",
        cal.young_modulus() / 1e9,
        PAPER_MODULUS / 1e9,
    );
    row(
        "strain at peak",
        "%",
        100.0 * cal.strain_at_peak(),
        100.0 * PAPER_STRAIN_AT_PEAK,
    );
    row("coordination", "-", cal.coordination(), PAPER_COORDINATION);
    println!();
    Ok(())
}

/// How the printed headings name the packings.
fn packings_name(packings: Packings) -> &'static str {
    match packings {
        Packings::CoupledBar => "coupled-bar",
        Packings::TensionBar => "tension-bar",
    }
}

fn flow(args: &CalibrateArgs) -> Result<(), String> {
    let seeds = match (&args.flow_seeds, args.packings) {
        (Some(seeds), _) => seeds.clone(),
        (None, Packings::CoupledBar) => args.seeds.clone(),
        (None, Packings::TensionBar) => vec![1],
    };
    let mut settings = PermeabilityCalibration {
        target_permeability: args.permeability,
        seeds: seeds.clone(),
        ..PermeabilityCalibration::paper_a()
    };
    settings.test.snap_tolerance = args.snap_tolerance;
    settings.test.narrow_gap_length = args.narrow_gap_length;
    println!(
        "## T2T reduction factor: geometric mean permeability of {} {} pore network(s) (seeds {:?}) = {:e} m^2",
        seeds.len(),
        packings_name(args.packings),
        seeds,
        args.permeability
    );
    let cal = match args.packings {
        Packings::CoupledBar => BarFamily {
            snap_tolerance: args.snap_tolerance,
            narrow_gap_length: args.narrow_gap_length,
            ..BarFamily::coupled_cases()
        }
        .calibrate_t2t_factor(&settings)
        .map_err(|e| e.to_string()),
        Packings::TensionBar => calibrate_t2t_factor(&settings).map_err(|e| e.to_string()),
    }
    .map_err(|e| format!("--permeability {:e}: {e}", args.permeability))?;
    println!("iteration  gamma        permeability [m^2]");
    for (i, it) in cal.iterations.iter().enumerate() {
        println!("{i:9}  {:.6e}  {:.6e}", it.gamma, it.kappa);
    }
    println!(
        "gamma                    {:>10.6}   {PAPER_GAMMA} (A-Table 1) ({:+.1} %)",
        cal.gamma(),
        100.0 * (cal.gamma() / PAPER_GAMMA - 1.0)
    );
    println!();
    Ok(())
}

/// Runs `thm calibrate`.
pub fn run(args: &CalibrateArgs) -> ExitCode {
    let strength = match parse_strength(&args.strength) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    if !(args.permeability > 0.0 && args.permeability.is_finite()) {
        eprintln!(
            "error: --permeability: must be > 0 m^2 and finite, got {}",
            args.permeability
        );
        return ExitCode::FAILURE;
    }
    let mut result = Ok(());
    if args.only != Some(Part::Flow) {
        result = bar(args, strength);
    }
    if result.is_ok() && args.only != Some(Part::Bar) {
        result = flow(args);
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
