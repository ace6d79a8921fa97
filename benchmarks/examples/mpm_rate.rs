//! Point-steps per second of the column-collapse benchmark measured against process CPU time
//! as well as wall time, for a machine shared with other work (where wall-clock medians
//! understate the per-thread rate). Linux only (reads `/proc/self/stat`).
//!
//! Run: `cargo run --release -p thm-benchmarks --example mpm_rate -- [steps]`

use std::time::Instant;
use thm_mpm::{
    Constitutive, DruckerPrager, DruckerPragerParameters, GridParameters, MaterialPoints, Mpm,
    MpmConfig, MpmParameters, MpmState, PointProperties, RigidWall, StresslessConductor,
};

fn cpu_seconds() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = s.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    // Fields 14 (utime) and 15 (stime), counted from 1; `rest` starts at field 3.
    (ticks(11) + ticks(12)) / 100.0
}

fn column<M: Constitutive>(side: usize, material: &M) -> (Mpm, MpmState<M::PointState>) {
    let h = 0.01;
    let mut params = MpmParameters::on_grid(GridParameters {
        origin: [0.0, 0.0],
        cell_size: h,
        cells: [4 * side + 2, side + 4],
    });
    params.gravity = [0.0, -9.81];
    params.pic_fraction = 0.05;
    params.walls = vec![
        RigidWall {
            point: [0.0, h],
            normal: [0.0, 1.0],
            velocity: [0.0; 2],
            friction: 0.5,
            removal_time: None,
        },
        RigidWall {
            point: [h, 0.0],
            normal: [1.0, 0.0],
            velocity: [0.0; 2],
            friction: 0.0,
            removal_time: None,
        },
    ];
    let config = MpmConfig::new(params).expect("valid");
    let mut points = MaterialPoints::new();
    points
        .fill_rectangle(
            config.grid(),
            [h, h],
            [h * (side + 1) as f64, h * (side + 1) as f64],
            2,
            &PointProperties {
                density: 1500.0,
                specific_heat: 800.0,
                conductivity: [1.0, 1.0, 0.0],
                temperature: 20.0,
                velocity: [0.0; 2],
            },
        )
        .expect("valid");
    let state = MpmState::new(points, material);
    (Mpm::new(config), state)
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

fn main() {
    let steps: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(200);
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
    for threads in [1, 2] {
        run("drucker_prager", &dp, 100, threads, steps);
        run("drucker_prager", &dp, 158, threads, steps / 4);
        run("stressless", &cheap, 158, threads, steps / 4);
    }
}
