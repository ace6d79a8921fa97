//! A-Sect. 4 (Krzaczek et al. 2023) on the network, for several packings and both readings of
//! the bar's ends (`thm_coupling::bar::BarEnds`): the cooling bar of A-Fig. 8 (single-phase
//! water, 323.16 K, ends held at 293.16 K and open to reservoirs at 0.1 MPa, every sphere
//! held, 400 s, Δt_C = 1 s) against A-Eqs. 60–61 with A-Eq. 63's conductivity (the paper's
//! comparison) and with the network's own, measured by a steady conduction run through the
//! same bar (`steady_conductivity`). Also the pores no chain of channels joins to a reservoir.
//!
//! `cargo run --release -p thm-benchmarks --bin bar_ends [-- SEEDS]`: SEEDS comma-separated
//! (default `1,2,3,4,5`). Prints a Markdown table; the verification case
//! `coupling/bar_cooling_advection` checks seed 1 (pass/fail with cut ends).

use thm_coupling::bar::{
    BAR_LENGTH, BAR_WIDTH, BarCase, BarEnds, EquivalentMedium, PAPER_BAR, bar_params_sized,
    bar_state_sized, centreline_cells, steady_conductivity, water_air,
};
use thm_coupling::pore_scale::{PoreScaleStepper, unconnected_pores};

const REPORT_TIMES: [f64; 4] = [100.0, 200.0, 300.0, 400.0];

struct Measured {
    spheres: usize,
    porosity: f64,
    sealed: usize,
    lambda_63: f64,
    lambda_net: f64,
    /// Largest centreline |T − T_Fourier| at the report times, A-Eq. 63's conductivity.
    error_63: [f64; 4],
    /// The same with the network's own conductivity.
    error_net: [f64; 4],
}

fn run(seed: u64, ends: BarEnds) -> Result<Measured, String> {
    let case = BarCase::Cooling;
    let config = bar_params_sized(case, 32, PAPER_BAR, ends)
        .validate()
        .map_err(|e| e.to_string())?;
    let heat = config.params().heat.clone();
    let mut s = bar_state_sized(case, &config, seed, &water_air(), PAPER_BAR, ends)
        .map_err(|e| e.to_string())?;
    let mesh = &s.mesh.mesh;
    let equivalent = EquivalentMedium::of(&s, &heat);
    let porosity = mesh.fluid_area() / (BAR_WIDTH * BAR_LENGTH);
    let lambda_net = steady_conductivity(&s, &heat, PAPER_BAR).map_err(|e| e.to_string())?;
    let network = EquivalentMedium {
        conductivity: lambda_net,
        ..equivalent
    };
    let centre = centreline_cells(mesh);
    let mut stepper = PoreScaleStepper::new(config, water_air(), &s).map_err(|e| e.to_string())?;
    let sealed = unconnected_pores(stepper.network());
    let (mut error_63, mut error_net) = ([0.0; 4], [0.0; 4]);
    for (k, &t_report) in REPORT_TIMES.iter().enumerate() {
        while s.time < t_report - 1e-9 {
            stepper.step(&mut s, 1.0).map_err(|e| e.to_string())?;
        }
        let mesh = &s.mesh.mesh;
        let error = |m: &EquivalentMedium| {
            centre
                .iter()
                .map(|&c| {
                    let exact = m.temperature(case, mesh.cell_centroid[c][1], s.time, 0.0);
                    (s.heat.temperature[c] - exact).abs()
                })
                .fold(0.0, f64::max)
        };
        error_63[k] = error(&equivalent);
        error_net[k] = error(&network);
    }
    Ok(Measured {
        spheres: s.dem.particles.len(),
        porosity,
        sealed,
        lambda_63: equivalent.conductivity,
        lambda_net,
        error_63,
        error_net,
    })
}

fn main() {
    let seeds: Vec<u64> = match std::env::args().nth(1) {
        None => (1..=5).collect(),
        Some(list) => match list.split(',').map(str::parse).collect() {
            Ok(seeds) => seeds,
            Err(e) => {
                eprintln!("SEEDS: comma-separated packing seeds (u64), got `{list}`: {e}");
                std::process::exit(2);
            }
        },
    };
    println!(
        "| ends | seed | spheres | porosity | unconnected pores | λ A-Eq. 63 [W/(m K)] | λ network | max \\|ΔT\\| vs A-Eq. 63 at 100/200/300/400 s [K] | vs network λ [K] |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    let fmt = |e: &[f64; 4]| format!("{:.2} / {:.2} / {:.2} / {:.2}", e[0], e[1], e[2], e[3]);
    for ends in [BarEnds::Cut, BarEnds::Film] {
        for &seed in &seeds {
            match run(seed, ends) {
                Ok(m) => println!(
                    "| {ends:?} | {seed} | {} | {:.4} | {} | {:.3} | {:.3} | {} | {} |",
                    m.spheres,
                    m.porosity,
                    m.sealed,
                    m.lambda_63,
                    m.lambda_net,
                    fmt(&m.error_63),
                    fmt(&m.error_net),
                ),
                Err(e) => println!("| {ends:?} | {seed} | failed: {e} | | | | | | |"),
            }
        }
    }
}
