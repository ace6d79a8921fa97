//! Cost of one MPM×DEM step of the biaxial test (Zhao et al. 2022, B-Sect. 5.3.1): the MPM
//! part, the RVE part (the exchange of B-Algorithm 1, lines 12–19: loads, the RVE batch,
//! responses) and, for the same RVE states and loads, the bare `thm_rve::RveBatch` call.
//! The ratio of the two RVE throughputs is what the coupling costs on top of the RVEs.
//!
//! `cargo run --release -p thm-benchmarks --bin mpm_dem_step [-- STEPS [NX NY [DISKS]]]`:
//! STEPS timed steps per thread count (default 6, after 2 warm-up steps), the grid
//! `NX × NY` cells with 2 × 2 points each (default the paper's 10 × 20, 800 RVEs) and DISKS
//! disks per RVE (default 400). The dense specimen, 1 and 2 threads. Prints a Markdown table
//! of per-step medians; not a timed test.

use std::time::Instant;

use thm_coupling::multiscale::stages::rve_loads;
use thm_coupling::multiscale::{
    BiaxialModel, BiaxialTest, Compaction, MultiscaleError, RveMaterial, RvePoint,
};
use thm_mpm::{BatchConstitutive, MaterialInput, MaterialResponse};
use thm_rve::{RveBatch, RveLoad, RveResponse};

/// The model's material with its exchange timed, and the states and inputs it was handed
/// kept for the bare replay.
struct Timed<'a> {
    inner: &'a mut RveMaterial,
    exchange: f64,
    copy: f64,
    saved: Vec<RvePoint>,
    inputs: Vec<MaterialInput>,
}

impl BatchConstitutive for Timed<'_> {
    type PointState = RvePoint;
    type Error = MultiscaleError;

    fn respond_batch(
        &mut self,
        states: &mut [RvePoint],
        inputs: &[MaterialInput],
        responses: &mut [MaterialResponse],
    ) -> Result<(), MultiscaleError> {
        let t = Instant::now();
        self.saved.clear();
        self.saved.extend_from_slice(states);
        self.inputs.clear();
        self.inputs.extend_from_slice(inputs);
        self.copy += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let r = self.inner.respond_batch(states, inputs, responses);
        self.exchange += t.elapsed().as_secs_f64();
        r
    }

    fn wave_modulus(&self, state: &RvePoint) -> f64 {
        self.inner.wave_modulus(state)
    }
}

/// Per-step times \[s\] and disk-steps of one coupled step.
struct Sample {
    mpm: f64,
    exchange: f64,
    bare: f64,
    disk_steps: f64,
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn step(
    model: &mut BiaxialModel,
    batch: &mut RveBatch,
    loads: &mut Vec<RveLoad>,
    responses: &mut Vec<RveResponse>,
) -> Result<Sample, Box<dyn std::error::Error + Send + Sync>> {
    let dt = model.case.test.time_step;
    let t = Instant::now();
    model.update_confinement()?;
    let mut timed = Timed {
        inner: &mut model.materials[0],
        exchange: 0.0,
        copy: 0.0,
        saved: Vec::new(),
        inputs: Vec::new(),
    };
    model.phases[0]
        .mpm
        .step_batch(&mut model.state, &mut timed, dt)?;
    let total = t.elapsed().as_secs_f64();
    let Timed {
        exchange,
        copy,
        mut saved,
        inputs,
        ..
    } = timed;
    let config = *model.material().config();
    let p = config.rve().params();
    let params = config.params();
    rve_loads(
        &inputs,
        &saved,
        p,
        params.kelvin_offset,
        params.dem_time.step_fraction,
        loads,
    );
    responses.resize(saved.len(), RveResponse::default());
    let t = Instant::now();
    batch
        .respond_into(&mut saved, loads, responses)
        .map_err(|(point, e)| format!("bare batch, point {point}: {e}"))?;
    let bare = t.elapsed().as_secs_f64();
    let disk_steps = saved
        .iter()
        .zip(loads.iter())
        .map(|(s, l)| s.rve.len() as f64 * f64::from(l.substeps))
        .sum();
    Ok(Sample {
        mpm: total - exchange - copy,
        exchange,
        bare,
        disk_steps,
    })
}

fn main() -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse())
        .collect::<Result<_, _>>()?;
    let steps = args.first().copied().unwrap_or(6).max(1);
    let cells = [
        args.get(1).copied().unwrap_or(10),
        args.get(2).copied().unwrap_or(20),
    ];
    let disks = args.get(3).copied().unwrap_or(400);
    let paper = BiaxialTest::paper(Compaction::Dense);
    let test = BiaxialTest::reduced(
        Compaction::Dense,
        cells,
        paper.points_per_cell,
        disks,
        paper.dem_time.density_scaling,
    );
    let t = Instant::now();
    let template = BiaxialModel::new(&test)?;
    eprintln!(
        "specimen {}x{} cells, {} RVEs x {} disks, built in {:.1} s",
        cells[0],
        cells[1],
        template.state.points.len(),
        template.state.material[0].rve.len(),
        t.elapsed().as_secs_f64()
    );
    println!(
        "| threads | step [ms] | MPM part [ms] | RVE part [ms] | bare RveBatch [ms] | RVE part M disk-steps/s | bare M disk-steps/s | RVE part / bare throughput | MPM share of the step |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        let mut model = template.clone();
        let n = model.state.points.len();
        let mut batch = RveBatch::new(*model.material().config().rve(), n);
        let (mut loads, mut responses) = (Vec::new(), Vec::new());
        let samples = pool.install(
            || -> Result<Vec<Sample>, Box<dyn std::error::Error + Send + Sync>> {
                for _ in 0..2 {
                    step(&mut model, &mut batch, &mut loads, &mut responses)?;
                }
                (0..steps)
                    .map(|_| step(&mut model, &mut batch, &mut loads, &mut responses))
                    .collect()
            },
        )?;
        let med = |f: fn(&Sample) -> f64| median(samples.iter().map(f).collect());
        let (mpm, exchange, bare) = (med(|s| s.mpm), med(|s| s.exchange), med(|s| s.bare));
        let disk_steps = med(|s| s.disk_steps);
        let coupled_rate = med(|s| s.disk_steps / s.exchange);
        let bare_rate = med(|s| s.disk_steps / s.bare);
        println!(
            "| {threads} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} | {:.3} | {:.1} % |",
            1e3 * (mpm + exchange),
            1e3 * mpm,
            1e3 * exchange,
            1e3 * bare,
            1e-6 * coupled_rate,
            1e-6 * bare_rate,
            coupled_rate / bare_rate,
            100.0 * mpm / (mpm + exchange),
        );
        eprintln!(
            "threads {threads}: {steps} timed steps after 2 warm-up steps, {:.3e} disk-steps per step (median)",
            disk_steps
        );
    }
    Ok(())
}
