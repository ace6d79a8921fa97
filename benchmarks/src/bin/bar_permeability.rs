//! A-Sect. 3.2's Darcy permeability (A-Eq. 56, Krzaczek et al. 2023) of the meshes the
//! coupled bar cases run on (`thm_coupling::bar::bar_state_sized`, cut or film ends, 32
//! points per circle, A-Table 1's γ = 0.0115) beside the Darcy test's own packings
//! (`thm_vpn_flow::permeability::DarcyTest::paper_a`, the 9-packing ensemble of the
//! verification case `vpn_flow/darcy_permeability`). The paper's κ is 2.47·10⁻¹⁶ m².
//!
//! `cargo run --release -p thm-benchmarks --bin bar_permeability [-- SEEDS]`: SEEDS
//! comma-separated (default `1,…,9`). Prints a Markdown table: κ of every packing and the
//! mean and range of each family, and of the two mesh variants that tell the cut ends' share
//! from that of the Steiner points on the box sides; then the γ that gives the paper's mean κ
//! on the cut family (bisection on log γ).

use thm_coupling::bar::{
    BAR_LENGTH, BAR_WIDTH, BarCase, BarEnds, PAPER_BAR, bar_params_sized, bar_state_sized,
    water_air,
};
use thm_vpn_flow::Network;
use thm_vpn_flow::permeability::{DarcyTest, incompressible_steady_flow};

/// A-Table 1's T2T reduction factor γ (A-Eq. 9).
const GAMMA: f64 = 0.0115;

/// κ of the coupled bar's mesh; `side_points` overrides the mesher's Steiner points on the box
/// sides (on with cut ends, off with film ends), to tell the ends' share from the sides'.
fn coupled_kappa(
    test: &DarcyTest,
    seed: u64,
    ends: BarEnds,
    side_points: Option<bool>,
) -> Result<f64, String> {
    coupled_kappa_at(test, seed, ends, side_points, GAMMA)
}

/// [`coupled_kappa`] with the T2T reduction factor `gamma` (mesh and boundary links).
fn coupled_kappa_at(
    test: &DarcyTest,
    seed: u64,
    ends: BarEnds,
    side_points: Option<bool>,
    gamma: f64,
) -> Result<f64, String> {
    let case = BarCase::Cooling;
    let mut params = bar_params_sized(case, 32, PAPER_BAR, ends);
    params.mesh.t2t_reduction_factor = gamma;
    if let Some(on) = side_points {
        params.mesh.side_points = on;
    }
    let config = params.validate().map_err(|e| e.to_string())?;
    let s = bar_state_sized(case, &config, seed, &water_air(), PAPER_BAR, ends)
        .map_err(|e| e.to_string())?;
    let mesh = &s.mesh.mesh;
    let net = Network::from_mesh(mesh, &test.reservoirs(), gamma).map_err(|e| e.to_string())?;
    let steady = incompressible_steady_flow(&net, test.viscosity).map_err(|e| e.to_string())?;
    Ok(test.kappa_of_rate(steady.group_rate[1], BAR_LENGTH, BAR_WIDTH, mesh.thickness))
}

fn main() {
    let seeds: Vec<u64> = match std::env::args().nth(1) {
        None => (1..=9).collect(),
        Some(list) => match list.split(',').map(str::parse).collect() {
            Ok(s) => s,
            Err(e) => {
                eprintln!("SEEDS: comma-separated packing seeds (u64), got `{list}`: {e}");
                std::process::exit(2);
            }
        },
    };
    let test = DarcyTest::paper_a();
    let mut columns: Vec<(&str, Vec<f64>)> = vec![
        ("Darcy test's packings", Vec::new()),
        ("coupled bar, cut ends", Vec::new()),
        ("coupled bar, film ends", Vec::new()),
        ("film ends with side points", Vec::new()),
        ("cut ends without side points", Vec::new()),
    ];
    for &seed in &seeds {
        let kappas = [
            test.bar_permeability(seed, GAMMA)
                .map(|b| b.kappa)
                .map_err(|e| e.to_string()),
            coupled_kappa(&test, seed, BarEnds::Cut, None),
            coupled_kappa(&test, seed, BarEnds::Film, None),
            coupled_kappa(&test, seed, BarEnds::Film, Some(true)),
            coupled_kappa(&test, seed, BarEnds::Cut, Some(false)),
        ];
        for (col, k) in columns.iter_mut().zip(kappas) {
            match k {
                Ok(k) => col.1.push(k),
                Err(e) => eprintln!("{} seed {seed}: {e}", col.0),
            }
        }
    }
    println!("| packings | κ at γ = 0.0115 per seed [1e-16 m²] | mean | range |");
    println!("| --- | --- | --- | --- |");
    for (name, k) in &columns {
        let each: Vec<String> = k.iter().map(|k| format!("{:.2}", k / 1e-16)).collect();
        let mean = k.iter().sum::<f64>() / k.len() as f64;
        let lo = k.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = k.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        println!(
            "| {name} | {} | {:.2} | {:.2}–{:.2} |",
            each.join(" / "),
            mean / 1e-16,
            lo / 1e-16,
            hi / 1e-16
        );
    }
    println!("| paper (A-Sect. 3.2) | | 2.47 | |");
    // γ for the paper's mean κ on the cut family: bisection on log γ (κ grows with γ).
    let mean_kappa = |gamma: f64| -> Result<f64, String> {
        let k = seeds
            .iter()
            .map(|&seed| coupled_kappa_at(&test, seed, BarEnds::Cut, None, gamma))
            .collect::<Result<Vec<f64>, String>>()?;
        Ok(k.iter().sum::<f64>() / k.len() as f64)
    };
    let (mut lo, mut hi) = (GAMMA / 100.0, GAMMA);
    for _ in 0..30 {
        let mid = (lo * hi).sqrt();
        match mean_kappa(mid) {
            Ok(k) if k > PAPER_KAPPA => hi = mid,
            Ok(_) => lo = mid,
            Err(e) => {
                eprintln!("cut ends at γ = {mid:e}: {e}");
                return;
            }
        }
    }
    let gamma = (lo * hi).sqrt();
    let k: Vec<f64> = seeds
        .iter()
        .filter_map(|&seed| coupled_kappa_at(&test, seed, BarEnds::Cut, None, gamma).ok())
        .collect();
    let each: Vec<String> = k.iter().map(|k| format!("{:.2}", k / 1e-16)).collect();
    println!();
    println!(
        "cut ends: γ = {gamma:.5} gives a mean κ of {:.3}e-16 m² (per seed {})",
        k.iter().sum::<f64>() / k.len() as f64 / 1e-16,
        each.join(" / ")
    );
}

/// A-Sect. 3.2's permeability of the bar \[m²\].
const PAPER_KAPPA: f64 = 2.47e-16;
