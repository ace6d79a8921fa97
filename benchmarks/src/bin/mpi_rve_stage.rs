//! The biaxial test's RVE stage (Zhao et al. 2022, B-Sect. 5.3.1; the exchange of
//! B-Algorithm 1, lines 12–19) spread over MPI ranks (feature `mpi`). Run under
//! `mpirun -np R` with `RAYON_NUM_THREADS=T`; every rank builds the same specimen, the RVEs are
//! spread over the ranks (`thm_coupling::multiscale::distributed`), and rank 0 prints one
//! line of per-step medians: the whole step, the MPM part (repeated on every rank), the RVE
//! part (the exchange as the MPM step sees it: this rank's block, the failure agreement, the
//! outcome gather and their application), its block compute and its communication (the
//! agreement and the gather, waiting for the slowest rank included), and the RVE part's
//! throughput in disk-steps per second; then one synchronisation of the RVEs (what a frame or
//! a checkpoint costs: its time and the bytes rank 0 received) and rank 0's peak resident
//! memory. `benchmarks/mpi/run.sh` alternates rank and thread
//! counts and prints their ratios. Not a timed test.
//!
//! `mpirun -np R target/release/mpi_rve_stage [STEPS [NX NY [DISKS]]]`: STEPS timed steps
//! (default 4, after 1 warm-up step), `NX × NY` cells with 2 × 2 points each (default the
//! paper's 10 × 20, 800 RVEs) and DISKS disks per RVE (default 400).

use std::sync::Arc;
use std::time::Instant;

use thm_coupling::multiscale::{
    BiaxialModel, BiaxialTest, Compaction, Distribution, MultiscaleError, RveMaterial, RvePoint,
    distributed,
};
use thm_mpm::{BatchConstitutive, MaterialInput, MaterialResponse};

/// The model's material with its exchange timed.
struct Timed<'a> {
    inner: &'a mut RveMaterial,
    exchange: f64,
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
        let r = self.inner.respond_batch(states, inputs, responses);
        self.exchange += t.elapsed().as_secs_f64();
        r
    }

    fn wave_modulus(&self, state: &RvePoint) -> f64 {
        self.inner.wave_modulus(state)
    }
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

/// One sample per step: step, RVE part, block compute, communication \[s\], disk-steps.
type Sample = [f64; 5];

fn step(model: &mut BiaxialModel) -> Result<Sample, Box<dyn std::error::Error>> {
    let before = model.materials[0]
        .distribution()
        .map(|d| distributed::lock(d).stats());
    let dt = model.case.test.time_step;
    let t = Instant::now();
    model.update_confinement()?;
    let mut timed = Timed {
        inner: &mut model.materials[0],
        exchange: 0.0,
    };
    model.phases[0]
        .mpm
        .step_batch(&mut model.state, &mut timed, dt)?;
    let exchange = timed.exchange;
    let total = t.elapsed().as_secs_f64();
    let after = model.materials[0]
        .distribution()
        .map(|d| distributed::lock(d).stats());
    let (compute, comm) = match (before, after) {
        (Some(b), Some(a)) => (
            a.compute_seconds - b.compute_seconds,
            a.comm_seconds - b.comm_seconds,
        ),
        _ => (exchange, 0.0),
    };
    let disk_steps = model
        .state
        .material
        .iter()
        .map(|s| s.rve.len() as f64 * f64::from(s.substeps))
        .sum();
    Ok([total, exchange, compute, comm, disk_steps])
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some((_universe, collective)) = thm_cli::mpi_rve::init() else {
        return Err("MPI was already initialised".into());
    };
    let (rank, size) = collective.as_ref().map_or((0, 1), |c| (c.rank(), c.size()));
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse())
        .collect::<Result<_, _>>()?;
    let steps = args.first().copied().unwrap_or(4).max(1);
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
    let mut model = BiaxialModel::new(&test)?;
    let built = t.elapsed().as_secs_f64();
    if let Some(c) = &collective {
        model.distribute(&Distribution::shared(Arc::clone(c)));
    }
    step(&mut model)?;
    let samples = (0..steps)
        .map(|_| step(&mut model))
        .collect::<Result<Vec<_>, _>>()?;
    let med = |k: usize| median(samples.iter().map(|s| s[k]).collect());
    let (total, rve, compute, comm, disk_steps) = (med(0), med(1), med(2), med(3), med(4));
    // One synchronisation (what a frame or a checkpoint costs): every rank takes the others'
    // RVEs.
    let (mut sync_ms, mut sync_mb) = (0.0, 0.0);
    if let Some(d) = model.materials[0].distribution() {
        let mut g = distributed::lock(d);
        let t = Instant::now();
        g.synchronise(&mut model.state.material)?;
        sync_ms = 1e3 * t.elapsed().as_secs_f64();
        sync_mb = g.stats().sync_bytes as f64 / 1e6;
    }
    let peak_mb = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1e3);
    let threads = rayon::current_num_threads();
    if rank == 0 {
        println!(
            "ranks {size} threads {threads} points {} disks {disks} steps {steps} \
             step_ms {:.2} mpm_ms {:.2} rve_ms {:.2} block_ms {:.2} comm_ms {:.3} \
             rve_mdisk_steps_per_s {:.3} sync_ms {sync_ms:.1} sync_mb_received {sync_mb:.2} \
             peak_rss_mb {peak_mb:.0} built_s {built:.1}",
            model.state.points.len(),
            1e3 * total,
            1e3 * (total - rve),
            1e3 * rve,
            1e3 * compute,
            1e3 * comm,
            1e-6 * disk_steps / rve,
        );
    }
    Ok(())
}
