//! The fuzz targets' checks (`fuzz/src/checks.rs`) over the committed corpus and every crash
//! the fuzzers found (`fuzz/regressions/`), on stable: the CI smoke run of the fuzz targets.
//! `fuzz/run.sh` runs the targets themselves for longer (nightly).

#[allow(dead_code, missing_docs)]
#[path = "../../../fuzz/src/checks.rs"]
mod checks;

use std::path::{Path, PathBuf};

/// A target's name and its check.
type Target = (&'static str, fn(&[u8]));

const TARGETS: [Target; 6] = [
    ("scenario", checks::scenario),
    ("packing_csv", checks::packing_csv),
    ("checkpoint", checks::checkpoint),
    ("eos_csv", checks::eos_csv),
    ("mesher", checks::mesher),
    ("eos_state", checks::eos_state),
];

fn fuzz_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fuzz")
}

fn inputs(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = match std::fs::read_dir(dir) {
        Ok(entries) => entries
            .map(|e| e.unwrap().path())
            .filter(|p| p.is_file())
            .collect(),
        Err(_) => Vec::new(),
    };
    files.sort();
    files
}

/// Runs every input of `kind` (`corpus` or `regressions`) through its target's check; a
/// failure names the file.
fn replay(kind: &str) -> usize {
    let mut count = 0;
    for (target, check) in TARGETS {
        for file in inputs(&fuzz_dir().join(kind).join(target)) {
            let data = std::fs::read(&file).unwrap();
            let outcome = std::panic::catch_unwind(|| check(&data));
            assert!(
                outcome.is_ok(),
                "{target}: {} fails its check",
                file.display()
            );
            count += 1;
        }
    }
    count
}

#[test]
fn the_committed_corpus_passes_every_check() {
    for (target, _) in TARGETS {
        assert!(
            !inputs(&fuzz_dir().join("corpus").join(target)).is_empty(),
            "no committed corpus for {target}"
        );
    }
    let n = replay("corpus");
    println!("{n} corpus inputs replayed");
}

#[test]
fn every_crash_found_so_far_stays_fixed() {
    let n = replay("regressions");
    println!("{n} regression inputs replayed");
}
