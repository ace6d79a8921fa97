//! Point-steps per second of the column-collapse benchmark measured against process CPU time
//! as well as wall time, for a machine shared with other work (where wall-clock medians
//! understate the per-thread rate). Linux only (reads `/proc/self/stat`).
//!
//! Run: `cargo run --release -p thm-benchmarks --example mpm_rate -- [steps] [--stages | --matrix]`
//!
//! Default: Drucker–Prager at 40 000 and 99 856 points and the stress-free conductor at
//! 99 856 points, 1 and 2 threads. `--stages`: CPU time per stage (1 thread). `--matrix`: all
//! three materials of the criterion bench at 10⁴ and 10⁵ points, 1 and 2 threads.

use std::time::Instant;
use thm_benchmarks::mpm_column::column;
use thm_mpm::{
    Constitutive, DruckerPrager, DruckerPragerParameters, LinearThermoElastic, StresslessConductor,
    ThermoElasticParameters,
};

fn cpu_seconds() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = s.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    // Fields 14 (utime) and 15 (stime), counted from 1; `rest` starts at field 3.
    (ticks(11) + ticks(12)) / 100.0
}

fn run<M: Constitutive>(name: &str, material: &M, side: usize, threads: usize, steps: usize) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let (mut mpm, mut st) = column(side, material);
        for _ in 0..10 {
            mpm.step(&mut st, material, 1e-4).expect("step");
        }
        let (w0, c0) = (Instant::now(), cpu_seconds());
        for _ in 0..steps {
            mpm.step(&mut st, material, 1e-4).expect("step");
        }
        let wall = w0.elapsed().as_secs_f64();
        let cpu = cpu_seconds() - c0;
        let work = (st.points.len() * steps) as f64;
        println!(
            "{name:15} {:7} pts {threads}t: {:6.2} M pt-steps/s wall, {:6.2} M pt-steps per CPU-s",
            st.points.len(),
            work / wall / 1e6,
            work / cpu / 1e6
        );
    });
}

/// CPU seconds per stage over `steps` steps (1 thread), to see where the time goes.
fn stages<M: Constitutive>(material: &M, side: usize, steps: usize) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    pool.install(|| {
        let (mut mpm, mut st) = column(side, material);
        let dt = 1e-4;
        let mut t = [0.0f64; 5];
        for _ in 0..steps {
            let c0 = cpu_seconds();
            mpm.check_time_step(&st, material, dt).expect("dt");
            let c1 = cpu_seconds();
            mpm.reset_grid();
            mpm.particle_to_grid(&st.points, st.step).expect("p2g");
            let c2 = cpu_seconds();
            mpm.grid_update(dt, st.time, st.step).expect("grid");
            let c3 = cpu_seconds();
            mpm.grid_to_particle(&mut st.points, dt, st.step)
                .expect("g2p");
            let c4 = cpu_seconds();
            mpm.constitutive_update(&mut st, material, dt)
                .expect("material");
            let c5 = cpu_seconds();
            st.time += dt;
            st.step += 1;
            for (k, (a, b)) in [(c0, c1), (c1, c2), (c2, c3), (c3, c4), (c4, c5)]
                .iter()
                .enumerate()
            {
                t[k] += b - a;
            }
        }
        let total: f64 = t.iter().sum();
        let names = [
            "check_time_step",
            "reset+P2G",
            "grid_update",
            "G2P",
            "constitutive",
        ];
        for (n, v) in names.iter().zip(t) {
            println!(
                "{n:16} {:5.1} %  ({:.1} ns/pt-step)",
                100.0 * v / total,
                1e9 * v / (steps * st.points.len()) as f64
            );
        }
    });
}

fn main() {
    let steps: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(200);
    if std::env::args().any(|a| a == "--stages") {
        let dp = DruckerPrager::new(&DruckerPragerParameters {
            youngs_modulus: 1e6,
            poisson_ratio: 0.3,
            friction_angle_deg: 30.0,
            dilatancy_angle_deg: 0.0,
            cohesion: 0.0,
            thermal_expansion: 0.0,
            conductivity: [1.0, 1.0, 0.0],
        })
        .expect("valid");
        stages(&dp, 158, steps);
        return;
    }
    let dp = DruckerPrager::new(&DruckerPragerParameters {
        youngs_modulus: 1e6,
        poisson_ratio: 0.3,
        friction_angle_deg: 30.0,
        dilatancy_angle_deg: 0.0,
        cohesion: 0.0,
        thermal_expansion: 0.0,
        conductivity: [1.0, 1.0, 0.0],
    })
    .expect("valid");
    let cheap = StresslessConductor::new([1.0, 1.0, 0.0]).expect("valid");
    if std::env::args().any(|a| a == "--matrix") {
        let el = LinearThermoElastic::new(&ThermoElasticParameters {
            youngs_modulus: 1e6,
            poisson_ratio: 0.3,
            thermal_expansion: 1e-5,
            conductivity: [1.0, 1.0, 0.0],
        })
        .expect("valid");
        for (side, n) in [(50, steps * 4), (158, steps / 2)] {
            for threads in [1, 2] {
                run("drucker_prager", &dp, side, threads, n);
                run("elastic", &el, side, threads, n);
                run("stressless", &cheap, side, threads, n);
            }
        }
        return;
    }
    for threads in [1, 2] {
        run("drucker_prager", &dp, 100, threads, steps);
        run("drucker_prager", &dp, 158, threads, steps / 4);
        run("stressless", &cheap, 158, threads, steps / 4);
    }
}
