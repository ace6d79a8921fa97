//! Checkpoint size and write/read time against the time of one DEM step, at 10⁴–10⁶
//! particles, for the JSON and the binary checkpoint forms of `thm-io`.
//!
//! `cargo run --release -p thm-benchmarks --bin checkpoint_scale [-- SIZES]`, SIZES a comma
//! list of particle counts (default `10000,100000,1000000`); files go to `$TMPDIR`. The state is
//! a bonded plane-constrained lattice (`thm_dem::packing::lattice_packing`) after a few steps,
//! so contacts and bonds are populated as in a run. Prints a Markdown table; not a timed test.

use std::path::Path;
use std::time::Instant;

use thm_dem::packing::lattice_packing;
use thm_dem::*;
use thm_io::{CheckpointEncoding, load_checkpoint, save_checkpoint_as};

fn state_of(n: usize) -> Result<(DemState, f64), Box<dyn std::error::Error>> {
    let side = (n as f64).sqrt().round() as usize;
    let packing = lattice_packing(Kinematics::SpheresInPlane, [side, side, 1], 1e-3, 42)?;
    let mut state = packing.to_state(2600.0, 293.15)?;
    for (i, v) in state.particles.velocity.iter_mut().enumerate() {
        let s = ((i * 7919) % 101) as f64 / 101.0 - 0.5;
        *v = Vec3::new(0.02 * s, -0.015 * s, 0.0);
    }
    let law = CohesiveFrictionalParams::paper_a_table_1().validate()?;
    let dt = 0.5 * critical_time_step(&state, &law);
    let params = StepperParams {
        time_step: dt,
        damping: 0.08,
        gravity: [0.0; 3],
        verlet_skin: 5e-5,
    };
    let mut stepper = Stepper::new(law, params.validate()?);
    stepper.run(&mut state, 2)?;
    let steps = 3;
    let t = Instant::now();
    stepper.run(&mut state, steps)?;
    Ok((state, t.elapsed().as_secs_f64() / steps as f64))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let sizes: Vec<usize> = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "10000,100000,1000000".into())
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    let dir = std::env::temp_dir().join(format!("thm-ckpt-scale-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    println!(
        "| particles | contacts | form | size [MB] | bytes/particle | write [s] | write [MB/s] | read [s] | DEM step [s] | write / step |"
    );
    println!("|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|");
    for &n in &sizes {
        let (state, step) = state_of(n)?;
        for (name, encoding) in [
            ("json", CheckpointEncoding::Json),
            ("binary", CheckpointEncoding::Binary),
        ] {
            let path = dir.join(format!("{n}.{name}.ckpt"));
            let t = Instant::now();
            save_checkpoint_as(&path, encoding, "dem", 1, &state)?;
            let write = t.elapsed().as_secs_f64();
            let size = std::fs::metadata(&path)?.len() as f64;
            let t = Instant::now();
            let back: DemState = load_checkpoint(&path, "dem", 1)?;
            let read = t.elapsed().as_secs_f64();
            if back != state {
                return Err(
                    format!("{name} checkpoint of {n} particles did not round-trip").into(),
                );
            }
            drop(back);
            println!(
                "| {} | {} | {name} | {:.1} | {:.0} | {:.2} | {:.0} | {:.2} | {:.3} | {:.1} |",
                state.particles.len(),
                state.contacts.len(),
                size / 1e6,
                size / state.particles.len() as f64,
                write,
                size / 1e6 / write,
                read,
                step,
                write / step
            );
            remove(&path);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

fn remove(path: &Path) {
    let _ = std::fs::remove_file(path);
}
