//! Wall time of the pore-scale coupled step (Krzaczek et al. 2023, A-Fig. 7) on the bar of
//! A-Fig. 8, by stage, on 1 and 2 threads: the A-Sect. 4 cooling bar end to end (400 s in
//! 400 coupled steps), A-Sect. 6 case b (17 s in 170 steps), and short runs of case b's bar
//! with free spheres (DEM, mesh motion, radii and remesh stages).
//!
//! `cargo run --profile bench -p thm-benchmarks --example coupled_bar [REPS]`
//!
//! Each line is the median over `REPS` repetitions (default 3) of the whole run; the stage
//! columns are the sums over its steps from `StepReport::stage_seconds`.

use std::time::Instant;
use thm_coupling::bar::water_air;
use thm_coupling::bar::{BarCase, bar_params, bar_state};
use thm_coupling::pore_scale::{PoreScaleStepper, Skeleton, StageSeconds};

struct Timing {
    total: f64,
    stages: StageSeconds,
    steps: usize,
}

fn run(
    case: BarCase,
    free: bool,
    dt: f64,
    steps: usize,
) -> Result<Timing, Box<dyn std::error::Error + Send + Sync>> {
    let mut params = bar_params(case, 32);
    if free {
        params.skeleton = Skeleton::Free;
    }
    let config = params.validate()?;
    let mut s = bar_state(case, &config, 1, &water_air())?;
    let start = Instant::now();
    let mut stepper = PoreScaleStepper::new(config, water_air(), &s)?;
    let mut sum = StageSeconds::default();
    for _ in 0..steps {
        let r = stepper.step(&mut s, dt)?;
        let t = r.stage_seconds;
        sum.fluid_forces += t.fluid_forces;
        sum.dem += t.dem;
        sum.mesh += t.mesh;
        sum.flow += t.flow;
        sum.heat += t.heat;
        sum.radii_and_remesh += t.radii_and_remesh;
    }
    Ok(Timing {
        total: start.elapsed().as_secs_f64(),
        stages: sum,
        steps,
    })
}

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let reps: usize = std::env::args().nth(1).map_or(Ok(3), |s| s.parse())?;
    let cases: [(&str, BarCase, bool, f64, usize); 3] = [
        (
            "A-Sect. 4 cooling, 400 s",
            BarCase::Cooling,
            false,
            1.0,
            400,
        ),
        (
            "A-Sect. 6 case b, 17 s",
            BarCase::ContractionFixed,
            false,
            0.1,
            170,
        ),
        (
            "case b bar, free spheres, 20 x 1e-5 s",
            BarCase::ContractionFixed,
            true,
            1e-5,
            20,
        ),
    ];
    println!(
        "| run | threads | steps | total [s] | per step [ms] | forces | DEM | mesh | flow | heat | radii+remesh [s] |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for (label, case, free, dt, steps) in cases {
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()?;
            let mut runs = (0..reps)
                .map(|_| pool.install(|| run(case, free, dt, steps)))
                .collect::<Result<Vec<_>, _>>()?;
            runs.sort_by(|a, b| a.total.total_cmp(&b.total));
            let m = &runs[runs.len() / 2];
            let t = m.stages;
            println!(
                "| {label} | {threads} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |",
                m.steps,
                m.total,
                1e3 * m.total / m.steps as f64,
                t.fluid_forces,
                t.dem,
                t.mesh,
                t.flow,
                t.heat,
                t.radii_and_remesh
            );
        }
    }
    Ok(())
}
