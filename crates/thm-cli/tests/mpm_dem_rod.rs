//! `thm run` of the `mpm_dem_rod` kind (B-Sect. 5.2.1 on the MPM×DEM scheme): the shipped
//! file validates, a reduced copy runs and writes its outputs, a run resumed from a checkpoint
//! ends with the same history, and bad values name their key.

use std::path::{Path, PathBuf};
use std::process::Command;

fn thm() -> Command {
    Command::new(env!("CARGO_BIN_EXE_thm"))
}

fn shipped() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/mpm_dem_rod.toml")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thm-rod-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The shipped file with 10 points of 4 × 4 disks, density-scaled by 20, for 20 ms.
fn reduced(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(shipped())
        .unwrap()
        .replace("end = \"1 s\"", "end = \"20 ms\"")
        .replace("cells = 50", "cells = 10")
        .replace("disks_per_side = 20", "disks_per_side = 4")
        .replace("density_scaling = 1.0", "density_scaling = 20.0")
        .replace("probe = \"0.5 m\"", "probe = \"0.85 m\"")
        .replace("history_every = 100", "history_every = 10")
        .replace("checkpoint_every = 2000", "checkpoint_every = 100");
    let file = dir.join("rod.toml");
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
fn reduced_rod_runs_writes_outputs_and_resumes_bit_for_bit() {
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
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    assert!(
        history
            .lines()
            .next()
            .unwrap()
            .contains("stress_change_xx_at_probe")
    );
    // Resume from the checkpoint at step 100 into a fresh folder: the same final history rows.
    let again = dir.join("again");
    let ckpt = out.join("checkpoints/step_0000000100.ckpt");
    assert!(ckpt.is_file());
    let o = run(&file, &again, Some(&ckpt));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let resumed = std::fs::read_to_string(again.join("history.csv")).unwrap();
    let last = |s: &str| s.lines().last().unwrap().to_string();
    assert_eq!(last(&history), last(&resumed));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_rod_values_name_their_key() {
    let dir = scratch("bad");
    for (from, to, key) in [
        ("cells = 10", "cells = 1", "rod.cells"),
        (
            "density_scaling = 20.0",
            "density_scaling = 0.5",
            "rod.density_scaling",
        ),
        ("probe = \"0.85 m\"", "probe = \"2 m\"", "rod.probe"),
        ("step = \"0.1 ms\"", "step = \"5 ms\"", "time.step"),
    ] {
        let file = reduced(&dir, |t| t.replace(from, to));
        let o = run(&file, &dir.join("out"), None);
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(key), "{key}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
