//! Cost of A-Sect. 6 case a (Krzaczek et al. 2023) by stage, and how it grows with the bar:
//! the scenario's settings (`scenarios/bar_contraction_free.toml`: calibrated bonds, DEM
//! masses ×100, corner forces with implicit undrained pores, the case's mesher) on bars of
//! the A-Fig. 8 recipe (4–8 mm spheres, about 10 % porosity) whose sides are `s` times the
//! paper's 20 × 80 mm, i.e. `s²` times its area.
//!
//! `cargo run --release -p thm-benchmarks --bin case_a_scaling [-- END [SCALES]]`: simulated
//! time END in seconds (default 0.5) from the start, in 0.01 s intervals as `thm run` takes
//! them; SCALES the side factors, comma-separated (default `1,2,4`: 1×, 4×, 16× the area).
//! Prints a Markdown table (wall seconds, per simulated second, per coupled step and per
//! sphere, the share of every stage); not a timed test.

use std::time::Instant;

use thm_coupling::bar::water_air;
use thm_coupling::bar::{
    BarCase, BarEnds, CASE_A_BOND_TENSILE_STRENGTH, CASE_A_DENSITY_SCALE, PAPER_BAR,
    bar_params_sized, bar_state_sized, case_a_coupling_step, scale_sphere_density,
};
use thm_coupling::pore_scale::{PoreScaleStepper, StageSeconds};

struct Measured {
    spheres: usize,
    cells: usize,
    pores: usize,
    steps: u64,
    rejected: u64,
    remeshes: u64,
    broken: usize,
    wall: f64,
    stages: StageSeconds,
    retakes: f64,
}

fn run(scale: f64, end: f64) -> Result<Measured, String> {
    let case = BarCase::ContractionFree;
    let size = [scale * PAPER_BAR[0], scale * PAPER_BAR[1]];
    let mut params = bar_params_sized(case, 32, size, BarEnds::Cut);
    params.dem.time_step *= CASE_A_DENSITY_SCALE.sqrt();
    params.contact.tensile_strength = CASE_A_BOND_TENSILE_STRENGTH;
    params.contact.cohesion = 5.0 * CASE_A_BOND_TENSILE_STRENGTH;
    let config = params.validate().map_err(|e| e.to_string())?;
    let mut s = bar_state_sized(case, &config, 1, &water_air(), size, BarEnds::Cut)
        .map_err(|e| e.to_string())?;
    scale_sphere_density(&mut s, CASE_A_DENSITY_SCALE).map_err(|e| e.to_string())?;
    let rule = case_a_coupling_step()
        .validate()
        .map_err(|e| e.to_string())?;
    let mut stepper = PoreScaleStepper::new(config, water_air(), &s).map_err(|e| e.to_string())?;
    let mut m = Measured {
        spheres: s.dem.particles.len(),
        cells: s.mesh.mesh.n_cells(),
        pores: s.flow.pressure.len(),
        steps: 0,
        rejected: 0,
        remeshes: 0,
        broken: 0,
        wall: 0.0,
        stages: StageSeconds::default(),
        retakes: 0.0,
    };
    let clock = Instant::now();
    for k in 0..(end / 0.01).round() as usize {
        let r = stepper
            .advance(&mut s, 0.01, &rule)
            .map_err(|e| format!("side × {scale}, interval {k}: {e}"))?;
        m.steps += r.steps;
        m.rejected += r.rejected;
        m.remeshes += r.remeshes;
        m.stages.accumulate(&r.stage_seconds);
        m.retakes += r.retake_seconds;
    }
    m.wall = clock.elapsed().as_secs_f64();
    m.broken = s.dem.bond_breaks.len();
    Ok(m)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let end: f64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(0.5);
    let scales: Vec<f64> = args
        .get(1)
        .map(|a| a.split(',').filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_else(|| vec![1.0, 2.0, 4.0]);
    println!(
        "case a, 0 to {end} s, {} rayon threads\n",
        rayon::current_num_threads()
    );
    println!(
        "| area | spheres | cells | pores | coupled steps (retaken) | remeshes | broken bonds | wall [s] | wall per simulated s | ms per coupled step | µs per sphere-step | DEM | mesh | flow | heat | radii+remesh | forces | retakes |"
    );
    println!("|{}", "---|".repeat(18));
    for scale in scales {
        match run(scale, end) {
            Ok(m) => {
                let share = |x: f64| format!("{:.0} %", 100.0 * x / m.wall);
                let tried = (m.steps + m.rejected) as f64;
                println!(
                    "| {:.0}× | {} | {} | {} | {} ({}) | {} | {} | {:.1} | {:.1} | {:.2} | {:.1} | {} | {} | {} | {} | {} | {} | {} |",
                    scale * scale,
                    m.spheres,
                    m.cells,
                    m.pores,
                    m.steps,
                    m.rejected,
                    m.remeshes,
                    m.broken,
                    m.wall,
                    m.wall / end,
                    1e3 * m.wall / tried,
                    1e6 * m.wall / tried / m.spheres as f64,
                    share(m.stages.dem),
                    share(m.stages.mesh),
                    share(m.stages.flow),
                    share(m.stages.heat),
                    share(m.stages.radii_and_remesh),
                    share(m.stages.fluid_forces),
                    share(m.retakes),
                );
            }
            Err(e) => println!("| {:.0}× | error: {e} |", scale * scale),
        }
    }
}
