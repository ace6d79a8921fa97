//! `thm run` of the `mpm_dem_column` kind (B-Sect. 5.3.3 on the MPM×DEM scheme): every
//! shipped variant's keys are read and its model is built and stepped through the release, a
//! tiny copy resumed from a checkpoint before the release ends with the same bits, and bad
//! values name their key.

use std::path::{Path, PathBuf};
use std::process::Command;

const VARIANTS: [&str; 5] = [
    "unbonded",
    "b0.02_no_melting",
    "b0.02_melting",
    "b0.1_no_melting",
    "b0.1_melting",
];

fn thm() -> Command {
    Command::new(env!("CARGO_BIN_EXE_thm"))
}

fn shipped(variant: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join(format!("../../scenarios/mpm_dem_column_{variant}.toml"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thm-column-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Replaces `from` by `to` in `text`, failing loudly when the shipped file no longer has it.
fn edit(text: String, from: &str, to: &str) -> String {
    assert!(
        text.contains(from),
        "the shipped file changed: `{from}` not found"
    );
    text.replace(from, to)
}

/// A shipped variant shortened to 10 ms of settling and 10 ms after the release, written
/// into `dir`.
fn short(dir: &Path, variant: &str, more: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(shipped(variant)).unwrap();
    let end = if variant == "unbonded" {
        "end = \"4 s\""
    } else {
        "end = \"21 s\""
    };
    let text = edit(text, end, "end = \"20 ms\"");
    let text = edit(text, "settle_time = \"1 s\"", "settle_time = \"10 ms\"");
    let text = edit(text, "history_every = 20", "history_every = 2");
    let text = edit(text, "frame_every = 500", "frame_every = 10");
    let text = edit(text, "checkpoint_every = 2000", "checkpoint_every = 6");
    let file = dir.join(format!("{variant}.toml"));
    std::fs::write(&file, more(text)).unwrap();
    file
}

fn run(file: &Path, out: &Path, resume: Option<&Path>) -> std::process::Output {
    let mut c = thm();
    c.arg("run").arg(file).arg("--out").arg(out);
    if let Some(r) = resume {
        c.arg("--resume").arg(r);
    }
    c.output().unwrap()
}

/// Every shipped variant is read, builds its column and runs through the release, writing
/// its history with the energy and bond columns.
#[test]
fn shipped_variants_run_through_the_release() {
    let dir = scratch("shipped");
    for v in VARIANTS {
        let file = short(&dir, v, |t| t);
        let out = dir.join(v);
        let o = run(&file, &out, None);
        assert!(
            o.status.success(),
            "{v}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
        let header = history.lines().next().unwrap();
        for c in [
            "potential_energy_ratio",
            "kinetic_energy_ratio",
            "bonds_broken_heated_half",
            "heat_balance_residual",
        ] {
            assert!(header.contains(c), "{v}: {header}");
        }
        assert!(out.join("summary.md").is_file());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A tiny β_b = 0.1 melting column (2 × 2 cells, 30-disk RVEs) resumed from the checkpoint
/// at step 6, before the release at step 10, ends with the same checkpoint bytes and history
/// as the run that was not interrupted.
#[test]
fn resumed_across_the_release_is_bitwise_identical() {
    let dir = scratch("resume");
    let file = short(&dir, "b0.1_melting", |t| {
        let t = edit(t, "cells = 4", "cells = 2");
        edit(t, "disks = 100", "disks = 30")
    });
    let full = dir.join("full");
    let o = run(&file, &full, None);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let again = dir.join("again");
    let o = run(
        &file,
        &again,
        Some(&full.join("checkpoints/step_0000000006.ckpt")),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let last = "checkpoints/step_0000000020.ckpt";
    assert_eq!(
        std::fs::read(full.join(last)).unwrap(),
        std::fs::read(again.join(last)).unwrap()
    );
    let tail = |d: &Path| {
        let h = std::fs::read_to_string(d.join("history.csv")).unwrap();
        h.lines()
            .rev()
            .take(4)
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    assert_eq!(tail(&full), tail(&again));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_column_values_name_their_key() {
    let dir = scratch("bad");
    for (from, to, key) in [
        (
            "bond_strength = 0.1",
            "bond_strength = -1",
            "column.bond_strength",
        ),
        ("cells = 4", "cells = 0", "column.cells"),
        ("disks = 100", "disks = 5", "column.disks"),
        (
            "density_scaling = 1e5",
            "density_scaling = 0.5",
            "column.density_scaling",
        ),
        (
            "points_per_cell = 2",
            "points_per_cell = 9",
            "column.points_per_cell",
        ),
        (
            "settle_time = \"10 ms\"",
            "settle_time = \"1 s\"",
            "column.settle_time",
        ),
        ("step = \"1 ms\"", "step = \"0.5 s\"", "time"),
        ("melting = true", "melting = 1", "melting"),
        ("seed = 1", "seed = 1\ncolour = 2", "colour"),
    ] {
        let file = short(&dir, "b0.1_melting", |t| edit(t, from, to));
        let o = run(&file, &dir.join("out"), None);
        assert!(!o.status.success(), "{key}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(key), "{key}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
