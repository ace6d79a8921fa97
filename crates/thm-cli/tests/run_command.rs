//! The `thm run` command as a user runs it: exit status and messages.

use std::path::PathBuf;
use std::process::Command;

fn thm() -> Command {
    Command::new(env!("CARGO_BIN_EXE_thm"))
}

fn shipped(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(name)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thm-cmd-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn shipped_scenario_runs_and_writes_every_output() {
    let dir = scratch("ok");
    let out = dir.join("out");
    let status = thm()
        .args(["run"])
        .arg(shipped("lumped_cooling.toml"))
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    for f in [
        "scenario.toml",
        "history.csv",
        "particles.pvd",
        "summary.md",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    assert!(out.join("particles/particles_00003600.vtu").is_file());
    assert!(out.join("checkpoints/step_0000003600.ckpt").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_bad_value_fails_with_the_key_path_and_writes_nothing() {
    let dir = scratch("bad");
    let text = std::fs::read_to_string(shipped("lumped_cooling.toml"))
        .unwrap()
        .replace("spacing = \"25 mm\"", "spacing = \"-25 mm\"");
    let file = dir.join("bad.toml");
    std::fs::write(&file, text).unwrap();
    let out = dir.join("out");
    let result = thm()
        .arg("run")
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!result.status.success());
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(
        stderr.contains("particles.spacing: must be > 0 mm, got -25 mm"),
        "{stderr}"
    );
    assert!(
        !out.exists(),
        "an invalid scenario created its output folder"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A build without the feature `mpi` started by an MPI launcher as one of several processes
/// refuses to run (each copy would run the whole scenario into the same folder) and says how
/// to build the one that spreads the RVEs; it writes nothing.
#[cfg(not(feature = "mpi"))]
#[test]
fn a_build_without_mpi_under_mpirun_refuses_and_writes_nothing() {
    let dir = scratch("no-mpi");
    let out = dir.join("out");
    for var in ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"] {
        let o = thm()
            .args(["run"])
            .arg(shipped("lumped_cooling.toml"))
            .arg("--out")
            .arg(&out)
            .env(var, "2")
            .output()
            .unwrap();
        assert!(!o.status.success(), "{var}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("one of 2 MPI processes") && err.contains("--features mpi"),
            "{var}: {err}"
        );
        assert!(!out.exists(), "{var}: wrote {}", out.display());
    }
    // One process announced is a plain run.
    let o = thm()
        .args(["run"])
        .arg(shipped("lumped_cooling.toml"))
        .arg("--out")
        .arg(&out)
        .env("OMPI_COMM_WORLD_SIZE", "1")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_dir_all(&dir).unwrap();
}
