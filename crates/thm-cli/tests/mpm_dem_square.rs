//! `thm run` of the `mpm_dem_square` kind (B-Sect. 5.2.2 on the MPM×DEM scheme): the shipped
//! file's keys, a reduced copy runs and writes its outputs, a run resumed from a checkpoint
//! ends with the same history, and bad values name their key.

use std::path::{Path, PathBuf};
use std::process::Command;

fn thm() -> Command {
    Command::new(env!("CARGO_BIN_EXE_thm"))
}

fn shipped() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/mpm_dem_square.toml")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thm-square-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The shipped file with 4 × 4 points of 30-disk RVEs, density-scaled by 1000, for 20 ms.
fn reduced(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(shipped())
        .unwrap()
        .replace("end = \"1 s\"", "end = \"20 ms\"")
        .replace("cells = 40", "cells = 4")
        .replace("disks = 400", "disks = 30")
        .replace("density_scaling = 100.0", "density_scaling = 1000.0")
        .replace("history_every = 50", "history_every = 10")
        .replace("frame_every = 500", "frame_every = 50")
        .replace("checkpoint_every = 2500", "checkpoint_every = 50");
    // Every edit must have matched the shipped file, or the run would not be the reduced one.
    for key in [
        "end = \"20 ms\"",
        "cells = 4\n",
        "disks = 30\n",
        "checkpoint_every = 50\n",
    ] {
        assert!(
            text.contains(key),
            "the shipped file changed: {key} not set"
        );
    }
    let file = dir.join("square.toml");
    std::fs::write(&file, edit(text)).unwrap();
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

#[test]
fn reduced_square_runs_writes_outputs_and_resumes_bit_for_bit() {
    let dir = scratch("run");
    let file = reduced(&dir, |t| t);
    let out = dir.join("out");
    let o = run(&file, &out, None);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "scenario.toml",
        "history.csv",
        "summary.md",
        "material_points.pvd",
        "twin_points.pvd",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let header = history.lines().next().unwrap();
    for c in ["centre_temperature", "twin_centre_stress_yy"] {
        assert!(header.contains(c), "{header}");
    }
    let frame = std::fs::read(out.join("material_points/material_points_00000100.vtu")).unwrap();
    let frame = String::from_utf8_lossy(&frame);
    for f in [
        "void_ratio",
        "coordination_number",
        "heat_source",
        "temperature_change",
    ] {
        assert!(frame.contains(f), "{f} not in the last frame");
    }
    // Resume from the checkpoint at step 50 into a fresh folder: the same history rows after it.
    let again = dir.join("again");
    let ckpt = out.join("checkpoints/step_0000000050.ckpt");
    assert!(ckpt.is_file());
    let o = run(&file, &again, Some(&ckpt));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let resumed = std::fs::read_to_string(again.join("history.csv")).unwrap();
    let tail = |s: &str| {
        s.lines()
            .rev()
            .take(5)
            .map(str::to_string)
            .collect::<Vec<_>>()
    };
    assert_eq!(tail(&history), tail(&resumed));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_square_values_name_their_key() {
    let dir = scratch("bad");
    for (from, to, key) in [
        ("cells = 4", "cells = 1", "square.cells"),
        ("disks = 30", "disks = 5", "square.disks"),
        (
            "density_scaling = 1000.0",
            "density_scaling = 0.5",
            "square.density_scaling",
        ),
        ("step = \"0.2 ms\"", "step = \"50 ms\"", "time.step"),
        ("seed = 1", "seed = 1\nextra = 2", "extra"),
    ] {
        let file = reduced(&dir, |t| t.replace(from, to));
        let o = run(&file, &dir.join("out"), None);
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(key), "{key}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
