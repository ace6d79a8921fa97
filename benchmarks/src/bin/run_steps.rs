//! The Rust side of the Python-overhead benchmark (`benchmarks/python/step_overhead.py`): opens
//! a scenario with the driver `thm run` and the Python module share
//! (`thm_scenarios::registry::open`), steps it in rounds and prints the seconds per step of each
//! round, one per line, so that the script can take medians beside the Python runs.
//!
//! `cargo run --release -p thm-benchmarks --bin run_steps -- SCENARIO.toml OUT_DIR STEPS ROUNDS`
//! (each round opens a fresh run in `OUT_DIR/round_K` and times `STEPS` steps after opening).

use std::path::PathBuf;
use std::time::Instant;

use thm_scenarios::registry::{self, read_document};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [file, out, steps, rounds] = args.as_slice() else {
        return Err("usage: run_steps SCENARIO.toml OUT_DIR STEPS ROUNDS".into());
    };
    let file = PathBuf::from(file);
    let (steps, rounds): (u64, usize) = (steps.parse()?, rounds.parse()?);
    for k in 0..rounds {
        let doc = read_document(&file)?;
        let dir = PathBuf::from(out).join(format!("round_{k}"));
        let mut run = registry::open(doc, &file, &dir, None)?;
        let n = steps.min(run.n_steps());
        let t = Instant::now();
        for _ in 0..n {
            run.advance(false)?;
        }
        println!("{:.9e}", t.elapsed().as_secs_f64() / n as f64);
    }
    Ok(())
}
