//! Point-steps per second of the column-collapse benchmark measured against process CPU time
//! as well as wall time, for a machine shared with other work (where wall-clock medians
//! understate the per-thread rate). Linux only (reads `/proc/self/stat`).
//!
//! Run: `cargo run --release -p thm-benchmarks --example mpm_rate -- [steps] [MODE]`
//!
//! Default: Drucker–Prager at 40 000 and 99 856 points and the stress-free conductor at
//! 99 856 points, 1 and 2 threads. Modes: `--stages`, wall time per stage at 10⁴ and 10⁵
//! points on 1 and 2 threads (the stage functions called one by one, not the fused step);
//! `--matrix`, all three materials of the criterion bench at 10⁴ and 10⁵ points, 1 and 2
//! threads; `--one SIDE THREADS`, one Drucker–Prager column of `SIDE × SIDE` cells (50: 10⁴
//! points, 158: 10⁵), for alternating runs and callgrind; `--hash`, a hash of every point's
//! state after `steps` steps at 10⁴ points on 1 and 2 threads, to compare builds bit for bit.

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

/// Wall seconds per stage over `steps` steps on `threads` threads, to see which stages scale.
fn stages<M: Constitutive>(material: &M, side: usize, threads: usize, steps: usize) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let (mut mpm, mut st) = column(side, material);
        let dt = 1e-4;
        for _ in 0..10 {
            mpm.step(&mut st, material, dt).expect("step");
        }
        let mut t = [0.0f64; 6];
        for _ in 0..steps {
            let c0 = Instant::now();
            mpm.check_time_step(&st, material, dt).expect("dt");
            let c1 = Instant::now();
            mpm.reset_grid();
            let c2 = Instant::now();
            mpm.particle_to_grid(&st.points, st.step).expect("p2g");
            let c3 = Instant::now();
            mpm.grid_update(dt, st.time, st.step).expect("grid");
            let c4 = Instant::now();
            mpm.grid_to_particle(&mut st.points, dt, st.step)
                .expect("g2p");
            let c5 = Instant::now();
            mpm.constitutive_update(&mut st, material, dt)
                .expect("material");
            let c6 = Instant::now();
            st.time += dt;
            st.step += 1;
            let c = [c0, c1, c2, c3, c4, c5, c6];
            for (k, v) in t.iter_mut().enumerate() {
                *v += (c[k + 1] - c[k]).as_secs_f64();
            }
        }
        let total: f64 = t.iter().sum();
        let names = [
            "check_time_step",
            "reset_grid",
            "P2G",
            "grid_update",
            "G2P",
            "constitutive",
        ];
        println!(
            "{} pts, {threads}t: {:.2} M pt-steps/s",
            st.points.len(),
            (steps * st.points.len()) as f64 / total / 1e6
        );
        for (n, v) in names.iter().zip(t) {
            println!(
                "  {n:16} {:5.1} %  ({:.2} ns/pt-step, {:.1} us/step)",
                100.0 * v / total,
                1e9 * v / (steps * st.points.len()) as f64,
                1e6 * v / steps as f64
            );
        }
    });
}

/// A hash of every point's state after `steps` steps (to compare builds bit for bit).
fn state_hash<M: Constitutive>(material: &M, side: usize, threads: usize, steps: usize) -> u64 {
    use std::hash::{Hash, Hasher};
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let (mut mpm, mut st) = column(side, material);
        for _ in 0..steps {
            mpm.step(&mut st, material, 1e-4).expect("step");
        }
        let p = &st.points;
        let mut h = std::collections::hash_map::DefaultHasher::new();
        for i in 0..p.len() {
            let vals = [
                p.position[i][0],
                p.position[i][1],
                p.velocity[i][0],
                p.velocity[i][1],
            ];
            let more = [
                p.stress[i][0],
                p.stress[i][1],
                p.stress[i][2],
                p.temperature[i],
            ];
            for v in vals
                .iter()
                .chain(&more)
                .chain(&[p.volume[i], p.remapped_temperature[i]])
            {
                v.to_bits().hash(&mut h);
            }
        }
        for r in mpm.wall_reactions() {
            r[0].to_bits().hash(&mut h);
            r[1].to_bits().hash(&mut h);
        }
        h.finish()
    })
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let steps: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(200);
    let has = |flag: &str| args.iter().any(|a| a == flag);
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
    if let Some(k) = args.iter().position(|a| a == "--one") {
        let arg = |i: usize, default| {
            args.get(k + i)
                .and_then(|s| s.parse().ok())
                .unwrap_or(default)
        };
        run("drucker_prager", &dp, arg(1, 158), arg(2, 1), steps);
        return;
    }
    if has("--hash") {
        for threads in [1, 2] {
            println!(
                "hash 50x50, {steps} steps, {threads}t: {:016x}",
                state_hash(&dp, 50, threads, steps)
            );
        }
        return;
    }
    if has("--stages") {
        for side in [50, 158] {
            for threads in [1, 2] {
                stages(&dp, side, threads, steps);
            }
        }
        return;
    }
    let cheap = StresslessConductor::new([1.0, 1.0, 0.0]).expect("valid");
    if has("--matrix") {
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
