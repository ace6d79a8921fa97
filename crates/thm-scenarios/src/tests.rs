//! `thm run` machinery: resume bit for bit, Ctrl-C checkpoint, and every kind of bad input.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use crate::error::RunError;
use crate::run_file;
use crate::scenario::{Outcome, Progress, checkpoint_path};

const SCENARIO: &str = r#"
kind = "lumped_cooling"
title = "test"

[time]
step = "0.25 s"
end = "25 s"

[output]
history_every = 3
frame_every = 25
checkpoint_every = 30
encoding = "raw"

[particles]
lattice = [4, 3]
spacing = "25 mm"
radius = "8 mm"
radius_spread = 0.5
density = "7850 kg/m^3"
specific_heat = "460 J/(kg K)"
initial_temperature = "600 degC"

[fluid]
temperature = "20 degC"
heat_transfer_coefficient = "2500 W/(m^2 K)"
"#;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thm-run-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write_scenario(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("scenario_in.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn run(file: &Path, out: &Path, resume: Option<&Path>) -> Result<Outcome, RunError> {
    run_file(file, out, resume, &AtomicBool::new(false), Progress::Quiet)
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The files that must agree byte for byte between two runs of the same scenario: the
/// history, the series index, the resolved scenario, the frames of `frames` of series
/// `series`, and the checkpoint of the last step `n`.
fn assert_same_results(a: &Path, b: &Path, series: &str, frames: &[u64], n: u64) {
    let mut files = vec![
        "history.csv".to_string(),
        format!("{series}.pvd"),
        "scenario.toml".to_string(),
    ];
    files.extend(
        frames
            .iter()
            .map(|f| format!("{series}/{series}_{f:08}.vtu")),
    );
    for rel in files {
        assert!(read(&a.join(&rel)) == read(&b.join(&rel)), "{rel} differs");
    }
    assert!(
        read(&checkpoint_path(a, n)) == read(&checkpoint_path(b, n)),
        "final checkpoint differs"
    );
}

#[test]
fn resume_from_a_mid_run_checkpoint_is_bitwise_identical() {
    let dir = scratch("resume");
    let file = write_scenario(&dir, SCENARIO);
    let full = dir.join("full");
    let Outcome::Finished { steps, .. } = run(&file, &full, None).unwrap() else {
        panic!("not finished")
    };
    assert_eq!(steps, 100);
    // A crashed run: everything the full run wrote (later frames and rows included) is there;
    // resuming from the checkpoint at step 60 must rewrite the rest identically.
    let resumed = dir.join("resumed");
    copy_dir(&full, &resumed);
    std::fs::remove_file(checkpoint_path(&resumed, 100)).unwrap();
    std::fs::remove_file(resumed.join("particles/particles_00000100.vtu")).unwrap();
    let mid = checkpoint_path(&resumed, 60);
    assert!(matches!(
        run(&file, &resumed, Some(&mid)).unwrap(),
        Outcome::Finished { steps: 100, .. }
    ));
    assert_same_results(&full, &resumed, "particles", &[75, 100], 100);
    // The history has every recorded step exactly once, in time order.
    let text = std::fs::read_to_string(resumed.join("history.csv")).unwrap();
    let times: Vec<f64> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
    assert_eq!(times.len(), 1 + 33 + 1); // step 0, every 3rd step to 99, the last step
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn interrupt_writes_a_checkpoint_and_resuming_it_matches_the_uninterrupted_run() {
    let dir = scratch("interrupt");
    let file = write_scenario(&dir, SCENARIO);
    let full = dir.join("full");
    run(&file, &full, None).unwrap();
    let cut = dir.join("cut");
    let outcome = run_file(&file, &cut, None, &AtomicBool::new(true), Progress::Quiet).unwrap();
    let Outcome::Interrupted { steps, checkpoint } = outcome else {
        panic!("not interrupted: {outcome:?}")
    };
    assert_eq!(steps, 1);
    assert_eq!(checkpoint, checkpoint_path(&cut, 1));
    let summary = std::fs::read_to_string(cut.join("summary.md")).unwrap();
    assert!(summary.contains("--resume"), "{summary}");
    run(&file, &cut, Some(&checkpoint)).unwrap();
    assert_same_results(&full, &cut, "particles", &[75, 100], 100);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Runs `text` (the test scenario with one edit) and returns the error message.
fn error_of(name: &str, text: &str) -> String {
    let dir = scratch(name);
    let file = write_scenario(&dir, text);
    let err = run(&file, &dir.join("out"), None).unwrap_err().to_string();
    std::fs::remove_dir_all(&dir).unwrap();
    err
}

fn edit(from: &str, to: &str) -> String {
    assert!(SCENARIO.contains(from), "{from}");
    SCENARIO.replacen(from, to, 1)
}

#[test]
fn bad_scenario_files_name_the_key_path() {
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "unknown_key",
            edit("radius_spread = 0.5", "radius_sprad = 0.5"),
            "particles.radius_sprad: unknown key",
        ),
        (
            "unknown_section",
            edit("[fluid]", "[fluidd]"),
            "fluidd: unknown key",
        ),
        (
            "unknown_output_key",
            edit("history_every = 3", "history_evry = 3"),
            "output.history_evry: unknown key",
        ),
        (
            "missing_key",
            edit("density = \"7850 kg/m^3\"\n", ""),
            "particles.density: missing key",
        ),
        (
            "missing_kind",
            edit("kind = \"lumped_cooling\"", ""),
            "kind: missing key",
        ),
        (
            "unknown_kind",
            edit("kind = \"lumped_cooling\"", "kind = \"lumped_coolin\""),
            "kind: unknown scenario kind `lumped_coolin`",
        ),
        (
            "wrong_type",
            edit("lattice = [4, 3]", "lattice = \"4 by 3\""),
            "particles.lattice: invalid type",
        ),
        (
            "wrong_type_count",
            edit("history_every = 3", "history_every = 2.5"),
            "output.history_every: invalid type",
        ),
        (
            "wrong_unit",
            edit("radius = \"8 mm\"", "radius = \"8 MPa\""),
            "particles.radius: unit `MPa` is not a length",
        ),
        (
            "out_of_range",
            edit("\"2500 W/(m^2 K)\"", "\"-3 W/(m^2 K)\""),
            "fluid.heat_transfer_coefficient: must be > 0 W/(m^2 K), got -3 W/(m^2 K)",
        ),
        (
            "out_of_range_temperature",
            edit(
                "initial_temperature = \"600 degC\"",
                "initial_temperature = \"-300 degC\"",
            ),
            "particles.initial_temperature: must be > -273.15 degC, got -300 degC",
        ),
        (
            "out_of_range_time",
            edit("step = \"0.25 s\"", "step = \"-1 ms\""),
            "time.step: must be > 0 ms, got -1 ms",
        ),
        (
            "zero_history",
            edit("history_every = 3", "history_every = 0"),
            "output.history_every: must be ≥ 1 step, got 0",
        ),
        (
            "spread",
            edit("radius_spread = 0.5", "radius_spread = 1.5"),
            "particles.radius_spread: must be in [0, 1), got 1.5",
        ),
        (
            "not_a_number",
            edit("radius_spread = 0.5", "radius_spread = nan"),
            "particles.radius_spread: must be in [0, 1), got NaN",
        ),
        ("syntax", edit("[fluid]", "[fluid"), "not valid TOML"),
    ];
    for (name, text, expected) in cases {
        let err = error_of(name, &text);
        assert!(err.contains(expected), "{name}: `{err}` lacks `{expected}`");
        assert!(
            err.contains("scenario_in.toml"),
            "{name}: `{err}` lacks the file"
        );
    }
}

#[test]
fn an_unwritable_output_folder_is_an_error_naming_it() {
    let dir = scratch("unwritable");
    let file = write_scenario(&dir, SCENARIO);
    // A regular file where a folder must be: fails for every user, root included.
    let blocker = dir.join("blocker");
    std::fs::write(&blocker, "keep me").unwrap();
    let out = blocker.join("out");
    let err = run(&file, &out, None).unwrap_err();
    assert!(matches!(err, RunError::OutputFolder { .. }), "{err}");
    assert!(
        err.to_string().contains(&out.display().to_string()),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&blocker).unwrap(), "keep me");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn nothing_already_written_is_lost() {
    let dir = scratch("keep");
    let file = write_scenario(&dir, SCENARIO);
    let out = dir.join("out");
    run(&file, &out, None).unwrap();
    let before = read(&out.join("history.csv"));
    // A fresh run into a folder holding a run is refused, not overwritten.
    let err = run(&file, &out, None).unwrap_err();
    assert!(matches!(err, RunError::OutputNotEmpty { .. }), "{err}");
    assert!(err.to_string().contains(&out.display().to_string()));
    // Resuming with a scenario whose parameters differ is refused before touching anything.
    let other = write_scenario(&dir, &edit("\"2500 W/(m^2 K)\"", "\"2000 W/(m^2 K)\""));
    let err = run(&other, &out, Some(&checkpoint_path(&out, 60))).unwrap_err();
    assert!(matches!(err, RunError::CheckpointMismatch { .. }), "{err}");
    // A bad value is reported before the folder is touched.
    let bad = write_scenario(&dir, &edit("lattice = [4, 3]", "lattice = [0, 3]"));
    let err = run(&bad, &out, Some(&checkpoint_path(&out, 60))).unwrap_err();
    assert!(err.to_string().contains("particles.lattice"), "{err}");
    assert!(read(&out.join("history.csv")) == before);
    assert!(read(&out.join("scenario.toml")).starts_with(b"kind = \"lumped_cooling\""));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn checkpoint_of_another_kind_or_version_is_refused() {
    let dir = scratch("ckpt_kind");
    let file = write_scenario(&dir, SCENARIO);
    let foreign = dir.join("foreign.ckpt");
    thm_io::save_checkpoint(&foreign, "dem_tension", 1, &vec![1.0, 2.0]).unwrap();
    let err = run(&file, &dir.join("out"), Some(&foreign)).unwrap_err();
    assert!(
        matches!(err, RunError::Io(thm_io::IoError::CheckpointKind { .. })),
        "{err}"
    );
    thm_io::save_checkpoint(&foreign, "lumped_cooling", 99, &vec![1.0, 2.0]).unwrap();
    let err = run(&file, &dir.join("out"), Some(&foreign)).unwrap_err();
    assert!(
        matches!(
            err,
            RunError::Io(thm_io::IoError::CheckpointStateVersion { found: 99, .. })
        ),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_shipped_scenario_runs_and_matches_its_exact_solution() {
    let dir = scratch("shipped");
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/lumped_cooling.toml");
    let out = dir.join("out");
    run(&file, &out, None).unwrap();
    // Final row of the history against the closed form (exact step factor: round-off only).
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let last: Vec<f64> = text
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|c| c.parse().unwrap())
        .collect();
    let (rho, c, h, t0, tf) = (7850.0, 460.0, 25.0, 873.15, 293.15);
    let t = last[0];
    assert_eq!(t, 1800.0);
    // Min temperature: the smallest sphere, r = 6 mm.
    let tau_small = rho * c * 6e-3 / (3.0 * h);
    let exact_min = tf + (t0 - tf) * f64::exp(-t / tau_small);
    assert!(
        ((last[2] - exact_min) / (exact_min - tf)).abs() < 1e-12,
        "{} vs {exact_min}",
        last[2]
    );
    // Energy: heat released equals the heat-capacity-weighted temperature drop (monitored) and
    // is positive and below the total available Σ mᵢ c (T₀ − T∞).
    assert!(last[4] > 0.0);
    let summary = std::fs::read_to_string(out.join("summary.md")).unwrap();
    assert!(summary.contains("history_mean_temperature_K.png"));
    assert!(out.join("history_mean_temperature_K.png").is_file());
    assert!(out.join("particles.pvd").is_file());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A test double whose state grows without bound: the driver must stop at the first
/// non-finite monitored value, name it with its step, and keep the last good checkpoint.
mod unstable {
    use super::*;
    use crate::config::TimeControl;
    use crate::error::ConfigError;
    use crate::registry::parse_document;
    use crate::scenario::{DriveOptions, FrameSink, Scenario, drive};
    use crate::summary::SummaryRow;
    use serde::{Deserialize, Serialize};
    use thm_io::{Column, IoError};

    #[derive(Debug, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Params {
        growth: f64,
    }

    #[derive(Debug)]
    struct Exploding {
        growth: f64,
    }

    impl Scenario for Exploding {
        const KIND: &'static str = "exploding";
        const STATE_VERSION: u32 = 1;
        type Params = Params;
        type State = f64;

        fn init(p: &Params, _: &TimeControl) -> Result<(Self, f64), ConfigError> {
            Ok((Self { growth: p.growth }, 1.0))
        }

        fn step(&mut self, x: &mut f64, _: u64, _: f64) -> Result<(), RunError> {
            *x *= self.growth;
            Ok(())
        }

        fn monitor_columns(&self) -> Vec<Column> {
            vec![Column::new("x", "m")]
        }

        fn monitor(&self, x: &f64, values: &mut Vec<f64>) {
            values.push(*x);
        }

        fn frame(&mut self, _: &f64, _: &mut FrameSink<'_>) -> Result<(), IoError> {
            Ok(())
        }

        fn summary(&self, _: &f64, _: f64) -> Vec<SummaryRow> {
            Vec::new()
        }
    }

    #[test]
    fn a_run_that_blows_up_stops_naming_quantity_and_step_and_keeps_its_checkpoint() {
        let dir = scratch("unstable");
        let doc = parse_document(
            "kind = \"exploding\"\ngrowth = 1e100\n[time]\nstep = 1\nend = 10\n\
             [output]\ncheckpoint_every = 2\nhistory_every = 5\n",
        )
        .unwrap();
        let out = dir.join("out");
        let opts = DriveOptions {
            out: out.clone(),
            resume: None,
            interrupt: &AtomicBool::new(false),
            progress: Progress::Quiet,
            processes: None,
        };
        let err = drive::<Exploding>(doc, Path::new("x.toml"), &opts).unwrap_err();
        // x = 1e100, 1e200, inf: step 3 is not a history step, but it is checked before the
        // checkpoint of step 4 would be written.
        match &err {
            RunError::Unstable {
                quantity,
                step,
                value,
                ..
            } => {
                assert_eq!(quantity, "x [m]");
                assert_eq!(*step, 4);
                assert!(value.is_infinite());
            }
            other => panic!("{other}"),
        }
        assert!(err.to_string().contains("step 4"), "{err}");
        let kept: f64 = {
            #[derive(Deserialize)]
            struct Ckpt {
                state: f64,
            }
            thm_io::load_checkpoint::<Ckpt>(&checkpoint_path(&out, 2), "exploding", 1)
                .unwrap()
                .state
        };
        assert_eq!(kept, 1e200);
        assert!(!checkpoint_path(&out, 4).exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// The MPM bar of B-Sect. 5.1.1, short and coarse: a checkpoint written mid-run and resumed
/// gives the same bits as the run that was not interrupted.
mod mpm_bar {
    use super::*;

    const BAR: &str = r#"
kind = "mpm_semi_infinite_bar"

[time]
step = "0.1 ms"
end = "0.2 s"

[output]
history_every = 50
frame_every = 500
checkpoint_every = 700
encoding = "raw"

[bar]
cells = 60
probe = "1 m"
"#;

    #[test]
    fn resumed_mid_run_is_bitwise_identical() {
        let dir = scratch("mpm_bar");
        let file = write_scenario(&dir, BAR);
        let full = dir.join("full");
        let Outcome::Finished { steps, .. } = run(&file, &full, None).unwrap() else {
            panic!("not finished")
        };
        assert_eq!(steps, 2000);
        let resumed = dir.join("resumed");
        copy_dir(&full, &resumed);
        std::fs::remove_file(checkpoint_path(&resumed, 2000)).unwrap();
        std::fs::remove_file(resumed.join("material_points/material_points_00002000.vtu")).unwrap();
        run(&file, &resumed, Some(&checkpoint_path(&resumed, 1400))).unwrap();
        assert_same_results(&full, &resumed, "material_points", &[1500, 2000], 2000);
        // Interrupted at the first step and resumed: the same bits again.
        let cut = dir.join("cut");
        let outcome = run_file(&file, &cut, None, &AtomicBool::new(true), Progress::Quiet).unwrap();
        let Outcome::Interrupted { checkpoint, .. } = outcome else {
            panic!("not interrupted")
        };
        run(&file, &cut, Some(&checkpoint)).unwrap();
        assert_same_results(&full, &cut, "material_points", &[1500, 2000], 2000);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_time_step_above_the_stability_limit_names_the_key() {
        let text = BAR.replace("step = \"0.1 ms\"", "step = \"1 s\"");
        let err = error_of("mpm_bar_dt", &text);
        assert!(err.contains("time.step: must be ≤"), "{err}");
        let text = BAR.replace("probe = \"1 m\"", "probe = \"7 m\"");
        let err = error_of("mpm_bar_probe", &text);
        assert!(err.contains("bar.probe: must be in"), "{err}");
        let text = BAR.replace("cells = 60", "cells = 1");
        let err = error_of("mpm_bar_cells", &text);
        assert!(
            err.contains("bar.cells: must be in [2, 100000], got 1"),
            "{err}"
        );
    }
}

/// The bonded bar of A-Sect. 3.1 (`dem_uniaxial_tension_bar`): analytical break of a
/// three-sphere chain read from a packing file, the generated bar against the verification
/// driver, bit-for-bit resume, and bad fields.
mod dem_bar {
    use super::*;
    use crate::kinds::dem_uniaxial_tension_bar::State;
    use serde::Deserialize;

    const BAR: &str = r#"
kind = "dem_uniaxial_tension_bar"

[time]
step = "0.2 us"
end = "2 ms"

[output]
history_every = 100
frame_every = 2500
checkpoint_every = 3000
encoding = "raw"

[packing]
seed = 2

[loading]
plate_speed = "10 mm/s"
end_strain = 0.0005
"#;

    fn final_state(out: &Path, step: u64) -> State {
        #[derive(Deserialize)]
        struct Ckpt {
            state: State,
        }
        thm_io::load_checkpoint::<Ckpt>(&checkpoint_path(out, step), "dem_uniaxial_tension_bar", 1)
            .unwrap()
            .state
    }

    #[test]
    fn a_chain_from_a_packing_file_breaks_at_t_r_squared() {
        let dir = scratch("dem_chain");
        let r = 3e-3;
        let packing = thm_dem::packing::Packing {
            kinematics: thm_dem::Kinematics::SpheresInPlane,
            centres: (0..3)
                .map(|k| thm_dem::Vec3::new(0.0, r + 2.0 * r * k as f64, 0.0))
                .collect(),
            radii: vec![r; 3],
            bonds: vec![(0, 1), (1, 2)],
        };
        let csv = dir.join("chain.csv");
        packing.write_csv(&csv).unwrap();
        // 18 mm chain to 0.4 % strain at ±10 mm/s: 3.6 ms.
        let text = BAR
            .replace(
                "seed = 2",
                &format!("file = {:?}", csv.display().to_string()),
            )
            .replace("end = \"2 ms\"", "end = \"3.6 ms\"")
            .replace("end_strain = 0.0005", "end_strain = 0.004");
        let file = write_scenario(&dir, &text);
        let out = dir.join("out");
        let Outcome::Finished { steps, .. } = run(&file, &out, None).unwrap() else {
            panic!("not finished")
        };
        let state = final_state(&out, steps);
        let (t, e_c, length) = (30e6, 3.36e9, 6.0 * r);
        // Plate force at the peak (stress × 6 mm width × 8 mm thickness) = T·R²; the two
        // bonds in series (K_n = E_c R each) have stretched by T R / E_c each.
        let force = state.peak_stress * (2.0 * r) * 8e-3;
        assert!((force / (t * r * r) - 1.0).abs() < 0.01, "{force}");
        let strain = 2.0 * t * r / e_c / length;
        assert!(
            (state.strain_at_peak / strain - 1.0).abs() < 0.01,
            "{} vs {strain}",
            state.strain_at_peak
        );
        assert!(!state.dem.bond_breaks.is_empty());
        assert!(out.join("spheres.pvd").is_file() && out.join("bonds.pvd").is_file());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_shipped_scenario_finds_the_strength_of_the_verification_driver() {
        let dir = scratch("dem_shipped");
        let file = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenarios/dem_uniaxial_tension_bar.toml");
        let out = dir.join("out");
        let Outcome::Finished { steps, .. } = run(&file, &out, None).unwrap() else {
            panic!("not finished")
        };
        let state = final_state(&out, steps);
        // Same packing, law, plates and time step through the crate's own driver.
        let reference = thm_dem::tension::uniaxial_tension(&thm_dem::tension::TensionTest {
            seed: 1,
            ..Default::default()
        })
        .unwrap();
        assert_eq!(state.peak_stress, reference.strength);
        assert_eq!(state.strain_at_peak, reference.strain_at_peak);
        assert_eq!(state.coordination_initial, reference.coordination_initial);
        let summary = std::fs::read_to_string(out.join("summary.md")).unwrap();
        assert!(summary.contains("| tensile strength | MPa |"), "{summary}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn resumed_mid_run_is_bitwise_identical() {
        let dir = scratch("dem_bar");
        let file = write_scenario(&dir, BAR);
        let full = dir.join("full");
        let Outcome::Finished { steps, .. } = run(&file, &full, None).unwrap() else {
            panic!("not finished")
        };
        assert_eq!(steps, 10_000);
        let resumed = dir.join("resumed");
        copy_dir(&full, &resumed);
        std::fs::remove_file(checkpoint_path(&resumed, 10_000)).unwrap();
        std::fs::remove_file(resumed.join("spheres/spheres_00010000.vtu")).unwrap();
        run(&file, &resumed, Some(&checkpoint_path(&resumed, 6000))).unwrap();
        assert_same_results(&full, &resumed, "spheres", &[7500, 10_000], 10_000);
        assert_same_results(&full, &resumed, "bonds", &[7500, 10_000], 10_000);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_packing_file_must_hold_one_layer_of_spheres() {
        let dir = scratch("dem_3d_file");
        let csv = dir.join("ball.csv");
        thm_dem::packing::Packing {
            kinematics: thm_dem::Kinematics::Spheres3d,
            centres: vec![thm_dem::Vec3::ZERO],
            radii: vec![1e-3],
            bonds: Vec::new(),
        }
        .write_csv(&csv)
        .unwrap();
        let text = BAR.replace(
            "seed = 2",
            &format!("file = {:?}", csv.display().to_string()),
        );
        let err = error_of("dem_3d_file_run", &text);
        assert!(
            err.contains(
                "packing.file: must hold one layer of spheres (kinematics=spheres_in_plane)"
            ),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn bar_error(name: &str, from: &str, to: &str) -> String {
        assert!(BAR.contains(from), "{from}");
        error_of(name, &BAR.replacen(from, to, 1))
    }

    #[test]
    fn bad_fields_name_the_key_and_the_allowed_range() {
        let cases = [
            (
                "seed = 2",
                "seed = 2\nfile = \"x.csv\"",
                "packing: give exactly one of",
            ),
            (
                "seed = 2",
                "seed = 2\nporosity = 0.9",
                "packing.porosity: must be in [0, 0.5], got 0.9",
            ),
            (
                "seed = 2",
                "file = \"no_such_packing.csv\"",
                "packing.file: no_such_packing.csv",
            ),
            (
                "plate_speed = \"10 mm/s\"",
                "plate_speed = \"-1 mm/s\"",
                "loading.plate_speed: must be in [0.000001 mm/s, 10000 mm/s], got -1 mm/s",
            ),
            (
                "plate_speed = \"10 mm/s\"",
                "plate_speed = \"10 mm\"",
                "loading.plate_speed",
            ),
            (
                "end_strain = 0.0005",
                "end_strain = 2",
                "loading.end_strain: must be in [0.000000001, 0.5], got 2",
            ),
            (
                "end_strain = 0.0005",
                "end_strain = 0.0005\ngrip = \"glued\"",
                "loading.grip",
            ),
            (
                "end_strain = 0.0005",
                "end_strain = 0.0005\ndamping = 1.5",
                "loading.damping: must be in [0, 0.99], got 1.5",
            ),
            (
                "end_strain = 0.0005",
                "end_strain = 0.0005\nspeed = 1",
                "loading.speed: unknown key",
            ),
            (
                "step = \"0.2 us\"",
                "step = \"10 us\"",
                "time.step: must be ≤",
            ),
            (
                "end = \"2 ms\"",
                "end = \"1 ms\"",
                "time.end: must be ≥ 2e-3 s",
            ),
            (
                "[loading]",
                "[material]\nbond_radius = \"largest\"\n[loading]",
                "material.bond_radius",
            ),
            (
                "[loading]",
                "[material]\ntensile_strength = \"-30 MPa\"\n[loading]",
                "material.tensile_strength: must be in [0 MPa",
            ),
        ];
        for (k, (from, to, expected)) in cases.iter().enumerate() {
            let err = bar_error(&format!("dem_bad_{k}"), from, to);
            assert!(
                err.contains(expected),
                "case {k}: `{err}` lacks `{expected}`"
            );
        }
    }
}

mod pore_scale_bar {
    use super::*;

    const CASE_B: &str = r#"
kind = "pore_scale_bar"
[time]
step = "0.1 s"
end = "0.6 s"
[output]
frame_every = 2
checkpoint_every = 2
encoding = "ascii"
[bar]
case = "contraction_fixed"
segments = 16
"#;

    #[test]
    fn resumed_mid_run_is_bitwise_identical() {
        let dir = scratch("pore_bar");
        let file = write_scenario(&dir, CASE_B);
        let full = dir.join("full");
        let Outcome::Finished { steps, .. } = run(&file, &full, None).unwrap() else {
            panic!("not finished")
        };
        assert_eq!(steps, 6);
        assert!(full.join("cells.pvd").is_file() && full.join("spheres.pvd").is_file());
        let resumed = dir.join("resumed");
        copy_dir(&full, &resumed);
        std::fs::remove_file(checkpoint_path(&resumed, 6)).unwrap();
        std::fs::remove_file(resumed.join("cells/cells_00000006.vtu")).unwrap();
        let profile = |out: &Path, name: &str, step: u64| {
            out.join("profiles")
                .join(format!("centreline_{name}_{step:010}.csv"))
        };
        std::fs::remove_file(profile(&resumed, "temperature", 6)).unwrap();
        run(&file, &resumed, Some(&checkpoint_path(&resumed, 2))).unwrap();
        assert_same_results(&full, &resumed, "cells", &[4, 6], 6);
        assert_same_results(&full, &resumed, "spheres", &[4, 6], 6);
        for name in ["temperature", "pore_pressure"] {
            for step in [4, 6] {
                let (a, b) = (profile(&full, name, step), profile(&resumed, name, step));
                assert!(read(&a) == read(&b), "{} differs", a.display());
            }
        }
        let summary = std::fs::read_to_string(resumed.join("summary.md")).unwrap();
        for png in [
            "profile_centreline_temperature.png",
            "profile_centreline_pore_pressure.png",
        ] {
            assert!(
                summary.contains(png) && resumed.join(png).is_file(),
                "{png}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The A-Sect. 4 profile: after 2 s the heat has moved about 2 sqrt(alpha t) ~ 3 mm into
    /// the bar, so at mid-height both the network and its reference (the equivalent bar of
    /// A-Eq. 63) are still at the initial 323.16 K, while the end cells have cooled.
    #[test]
    fn cooling_profile_carries_the_equivalent_bar_as_reference() {
        let dir = scratch("pore_bar_profile");
        let text = CASE_B
            .replace("case = \"contraction_fixed\"", "case = \"cooling\"")
            .replace("end = \"0.6 s\"", "end = \"2 s\"")
            .replace("step = \"0.1 s\"", "step = \"1 s\"");
        let file = write_scenario(&dir, &text);
        let out = dir.join("out");
        run(&file, &out, None).unwrap();
        let csv = std::fs::read_to_string(
            out.join("profiles")
                .join("centreline_temperature_0000000002.csv"),
        )
        .unwrap();
        let mut lines = csv.lines();
        let header = lines.next().unwrap();
        assert!(
            header.starts_with("time [s],y [m],T [K],equivalent bar"),
            "{header}"
        );
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        let mid = rows
            .iter()
            .min_by(|a, b| (a[1] - 0.04).abs().total_cmp(&(b[1] - 0.04).abs()))
            .unwrap();
        assert_eq!(mid[0], 2.0);
        assert!((mid[2] - 323.16).abs() < 1e-3, "{mid:?}");
        assert!((mid[3] - 323.16).abs() < 1e-9, "{mid:?}");
        let coldest = rows.iter().map(|r| r[2]).fold(f64::MAX, f64::min);
        assert!(coldest < 322.0, "{coldest}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_fields_name_the_key() {
        let cases = [
            (
                "case = \"contraction_fixed\"",
                "case = \"advection\"",
                "bar.pressure_drop: required for case = \"advection\"",
            ),
            (
                "case = \"contraction_fixed\"",
                "case = \"contraction_fixed\"\npressure_drop = \"1 MPa\"",
                "bar.pressure_drop: only for case = \"advection\"",
            ),
            (
                "case = \"contraction_fixed\"",
                "case = \"advection\"\npressure_drop = \"-1 MPa\"",
                "bar.pressure_drop",
            ),
            (
                "segments = 16",
                "segments = 4",
                "bar.segments: must be in 8 … 256, got 4",
            ),
            (
                "case = \"contraction_fixed\"",
                "case = \"melting\"",
                "bar.case",
            ),
        ];
        for (k, (from, to, expected)) in cases.iter().enumerate() {
            assert!(CASE_B.contains(from), "{from}");
            let err = error_of(&format!("pore_bar_bad_{k}"), &CASE_B.replacen(from, to, 1));
            assert!(
                err.contains(expected),
                "case {k}: `{err}` lacks `{expected}`"
            );
        }
    }

    /// Case a with weak bonds (T = 1 MPa), so that bonds break within the first steps: the
    /// run takes adaptive coupled steps, records the breaks, keeps the phase masses, and a
    /// resumed run ends on the same bits.
    const CASE_A: &str = r#"
kind = "pore_scale_bar"
[time]
step = "0.005 s"
end = "0.03 s"
[output]
frame_every = 2
checkpoint_every = 2
encoding = "ascii"
[bar]
case = "contraction_free"
segments = 16
bond_tensile_strength = "1 MPa"
[bar.coupling_step]
max = "0.005 s"
min = "1e-7 s"
max_displacement = 0.01
growth = 1.2
"#;

    #[test]
    fn case_a_breaks_bonds_keeps_mass_and_resumes_bitwise() {
        let dir = scratch("pore_bar_case_a");
        let file = write_scenario(&dir, CASE_A);
        let full = dir.join("full");
        let Outcome::Finished { steps, .. } = run(&file, &full, None).unwrap() else {
            panic!("not finished")
        };
        assert_eq!(steps, 6);
        let history = std::fs::read_to_string(full.join("history.csv")).unwrap();
        let mut lines = history.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name: &str| {
            header
                .iter()
                .position(|h| h.starts_with(name))
                .unwrap_or_else(|| panic!("no {name} in {header:?}"))
        };
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        let last = rows.last().unwrap();
        assert!(last[col("broken_bonds")] >= 1.0, "{last:?}");
        for name in ["liquid_mass", "gas_mass"] {
            let (m0, m1) = (rows[0][col(name)], last[col(name)]);
            assert!(((m1 - m0) / m0).abs() <= 1e-12, "{name}: {m0} -> {m1}");
        }
        // The temperature stays between the ends' 278.16 K and the initial 368.16 K.
        for r in &rows {
            let (lo, hi) = (r[col("min_temperature")], r[col("max_temperature")]);
            assert!(
                lo >= 278.16 && hi <= 368.16 + 1e-9,
                "t = {}: T in [{lo}, {hi}]",
                r[0]
            );
        }
        let summary = std::fs::read_to_string(full.join("summary.md")).unwrap();
        for row in [
            "broken_bonds",
            "d50_final",
            "largest_bond_tension_before_breakage",
        ] {
            assert!(summary.contains(row), "{row}");
        }
        // A-Figs. 19-22: a picture per frame, shown in the summary.
        for step in [0, 2, 4, 6] {
            let png = format!("pictures/state_{step:010}.png");
            assert!(full.join(&png).is_file(), "{png}");
            assert!(summary.contains(&png), "{png} not in the summary");
        }
        let resumed = dir.join("resumed");
        copy_dir(&full, &resumed);
        std::fs::remove_file(checkpoint_path(&resumed, 6)).unwrap();
        std::fs::remove_file(resumed.join("cells/cells_00000006.vtu")).unwrap();
        run(&file, &resumed, Some(&checkpoint_path(&resumed, 2))).unwrap();
        assert_same_results(&full, &resumed, "cells", &[4, 6], 6);
        assert_same_results(&full, &resumed, "spheres", &[4, 6], 6);
        if std::env::var_os("THM_KEEP_TEST_OUTPUT").is_none() {
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }

    #[test]
    fn case_a_fields_name_the_key() {
        let cases = [
            (
                "case = \"contraction_free\"",
                "case = \"contraction_fixed\"",
                "bar.bond_tensile_strength: only for case = \"contraction_free\"",
            ),
            (
                "segments = 16",
                "segments = 16\ndensity_scale = 0.5",
                "bar.density_scale: must be in 1 … 1e6, got 0.5",
            ),
            (
                "segments = 16",
                "segments = 16\npressure_force = \"cell_edges\"",
                "bar.pressure_force",
            ),
            (
                "segments = 16",
                "segments = 16\nends = \"alpha\"",
                "bar.ends: unknown variant `alpha`, expected `cut` or `film`",
            ),
            ("growth = 1.2", "growth = 20", "bar.coupling_step.growth"),
            ("min = \"1e-7 s\"", "min = \"1 s\"", "bar.coupling_step.min"),
            (
                "bond_tensile_strength = \"1 MPa\"",
                "bond_tensile_strength = \"-1 MPa\"",
                "bar.bond_tensile_strength",
            ),
        ];
        for (k, (from, to, expected)) in cases.iter().enumerate() {
            assert!(CASE_A.contains(from), "{from}");
            let err = error_of(
                &format!("pore_bar_a_bad_{k}"),
                &CASE_A.replacen(from, to, 1),
            );
            assert!(
                err.contains(expected),
                "case {k}: `{err}` lacks `{expected}`"
            );
        }
    }

    #[test]
    fn sealed_water_without_tension_stops_naming_the_pore_and_keeps_its_checkpoint() {
        let dir = scratch("pore_bar_tension");
        let text = CASE_B
            .replace("case = \"contraction_fixed\"", "case = \"cooling\"")
            .replace("step = \"0.1 s\"", "step = \"1 s\"")
            .replace("end = \"0.6 s\"", "end = \"20 s\"")
            .replace(
                "segments = 16",
                "segments = 32\nliquid_tension = false\nends = \"film\"",
            )
            .replace("checkpoint_every = 2", "checkpoint_every = 1");
        let file = write_scenario(&dir, &text);
        let out = dir.join("out");
        let err = run(&file, &out, None).unwrap_err();
        let RunError::Unstable {
            quantity,
            place,
            step,
            ..
        } = &err
        else {
            panic!("expected an unstable stop, got {err}")
        };
        assert_eq!(quantity, "pressure");
        assert!(place.starts_with("pore "), "{place}");
        assert!(out.join("history.csv").is_file());
        // The last completed step's checkpoint is kept.
        assert!(
            checkpoint_path(&out, step - 1).is_file(),
            "step {step}: {err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// The biaxial test of B-Sect. 5.3.1 (`mpm_dem_biaxial`), tiny: a checkpoint written mid-run
/// (with every RVE and the running sums) and resumed gives the same bits as the run that was
/// not interrupted; bad fields name their key.
mod mpm_biaxial {
    use super::*;

    const BIAXIAL: &str = r#"
kind = "mpm_dem_biaxial"

[time]
step = "1 ms"
end = "60 ms"

[output]
history_every = 5
frame_every = 20
checkpoint_every = 30
encoding = "raw"

[biaxial]
compaction = "dense"
cells = [2, 4]
points_per_cell = 2
disks = 30
density_scaling = 1e4
confining_stress = "100 kPa"
plate_speed = "0.02 m/s"
initial_temperature = "20 degC"
track = [[0.25, 0.5]]
"#;

    #[test]
    fn resumed_mid_run_is_bitwise_identical() {
        let dir = scratch("mpm_biaxial");
        let file = write_scenario(&dir, BIAXIAL);
        let full = dir.join("full");
        let Outcome::Finished { steps, .. } = run(&file, &full, None).unwrap() else {
            panic!("not finished")
        };
        assert_eq!(steps, 60);
        let resumed = dir.join("resumed");
        copy_dir(&full, &resumed);
        std::fs::remove_file(checkpoint_path(&resumed, 60)).unwrap();
        std::fs::remove_file(resumed.join("material_points/material_points_00000060.vtu")).unwrap();
        for series in ["rve_0_disks", "rve_0_contacts", "rve_0_cell"] {
            std::fs::remove_file(resumed.join(format!("{series}/{series}_00000060.vtu"))).unwrap();
        }
        run(&file, &resumed, Some(&checkpoint_path(&resumed, 30))).unwrap();
        assert_same_results(&full, &resumed, "material_points", &[40, 60], 60);
        assert_same_results(&full, &resumed, "rve_0_contacts", &[40, 60], 60);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_fields_name_the_key() {
        let text = BIAXIAL.replace("points_per_cell = 2", "points_per_cell = 1");
        let err = error_of("mpm_biaxial_ppc", &text);
        assert!(
            err.contains("biaxial.points_per_cell: must be in [2, 4], got 1"),
            "{err}"
        );
        let text = BIAXIAL.replace("cells = [2, 4]", "cells = [2, 0]");
        let err = error_of("mpm_biaxial_cells", &text);
        assert!(err.contains("biaxial.cells[1]"), "{err}");
        let text = BIAXIAL.replace("density_scaling = 1e4", "density_scaling = 0.5");
        let err = error_of("mpm_biaxial_scaling", &text);
        assert!(err.contains("biaxial.density_scaling"), "{err}");
        let text = BIAXIAL.replace("end = \"60 ms\"", "end = \"100 s\"");
        let err = error_of("mpm_biaxial_end", &text);
        assert!(err.contains("time.end"), "{err}");
        let text = BIAXIAL.replace("step = \"1 ms\"", "step = \"1 s\"");
        let err = error_of("mpm_biaxial_dt", &text);
        assert!(
            err.contains("biaxial.plate_speed") || err.contains("time.step"),
            "{err}"
        );
        let text = BIAXIAL.replace("disks = 30", "disks = 30\nbond_strength = -0.01");
        let err = error_of("mpm_biaxial_bond", &text);
        assert!(
            err.contains("biaxial.bond_strength: must be in [0, 10]"),
            "{err}"
        );
        let text = BIAXIAL.replace("[[0.25, 0.5]]", "[[0.25, 0.5], [1.5, 0.5]]");
        let err = error_of("mpm_biaxial_track", &text);
        assert!(
            err.contains("biaxial.track[1]: must lie in the specimen"),
            "{err}"
        );
        let text = BIAXIAL.replace("disks = 30", "disks = 30\ncolour = 1");
        let err = error_of("mpm_biaxial_unknown", &text);
        assert!(err.contains("colour"), "{err}");
        for field in ["rve_local_damping", "mpm_local_damping"] {
            let text = BIAXIAL.replace("disks = 30", &format!("disks = 30\n{field} = 1.0"));
            let err = error_of("mpm_biaxial_damping", &text);
            assert!(
                err.contains(&format!("biaxial.{field}: must be in [0, 1), got 1")),
                "{err}"
            );
        }
        let text = BIAXIAL.replace(
            "disks = 30",
            "disks = 30\nquasi_static = { max_inertial_number = 2.0, max_kinetic_ratio = 1e-2 }",
        );
        let err = error_of("mpm_biaxial_qs_range", &text);
        assert!(err.contains("quasi_static.max_inertial_number"), "{err}");
    }

    /// Quasi-statics enforced: an inertial-number bound below what the plate's start gives
    /// stops the run at the first step past it, naming the point, the step and the
    /// quantity, with the history written so far kept.
    #[test]
    fn an_rve_past_the_quasi_static_bound_stops_the_run_naming_it() {
        let text = BIAXIAL.replace(
            "disks = 30",
            "disks = 30\nquasi_static = { max_inertial_number = 1e-9, max_kinetic_ratio = 1.0 }",
        );
        let err = error_of("mpm_biaxial_qs", &text);
        assert!(
            err.contains("point") && err.contains("step") && err.contains("inertial number"),
            "{err}"
        );
    }
}

/// The steppable run front ends use: a written temperature field cools exactly as the lumped
/// solution says, is checkpointed with the state, and bad writes are refused by name and
/// range without touching the state.
#[test]
fn written_state_arrays_follow_the_physics_and_are_checkpointed() {
    use crate::registry;
    use crate::registry::parse_document;

    let dir = scratch("arrays");
    let file = write_scenario(&dir, SCENARIO);
    let open = |resume: Option<&Path>| {
        registry::open(
            parse_document(SCENARIO).unwrap(),
            &file,
            &dir.join("out"),
            resume,
        )
        .unwrap()
    };
    let mut run = open(None);
    for _ in 0..5 {
        run.advance(false).unwrap();
    }
    let radius: Vec<f64> = {
        let arrays = run.arrays();
        let r = arrays.iter().find(|a| a.name == "sphere_radius").unwrap();
        assert_eq!((r.unit, r.columns, r.writable), ("m", 1, false));
        r.values.to_vec()
    };
    let n = radius.len();
    let written: Vec<f64> = (0..n).map(|i| 500.0 + 40.0 * i as f64).collect();
    run.set_array("sphere_temperature", &written).unwrap();
    run.advance(false).unwrap();
    // T = T_f + (T_0 − T_f) exp(−Δt/τ), τ = ρ c r / (3 h).
    let t = run
        .arrays()
        .into_iter()
        .find(|a| a.name == "sphere_temperature")
        .unwrap()
        .values
        .to_vec();
    for i in 0..n {
        let tau = 7850.0 * 460.0 * radius[i] / (3.0 * 2500.0);
        let exact = 293.15 + (written[i] - 293.15) * (-0.25 / tau).exp();
        assert!(
            (t[i] / exact - 1.0).abs() < 1e-14,
            "sphere {i}: {} vs {exact}",
            t[i]
        );
    }
    // Refused writes: a read-only array, a wrong length, a temperature ≤ 0; the state stays.
    let err = run.set_array("sphere_radius", &radius).unwrap_err();
    assert!(
        err.to_string().contains("writable: `sphere_temperature`"),
        "{err}"
    );
    let err = run
        .set_array("sphere_temperature", &written[1..])
        .unwrap_err();
    assert!(
        err.to_string()
            .contains(&format!("needs {n} values, got {}", n - 1)),
        "{err}"
    );
    let mut bad = t.clone();
    bad[2] = 0.0;
    let err = run.set_array("sphere_temperature", &bad).unwrap_err();
    assert!(
        err.to_string()
            .contains("value 2 must be finite and in (0, 100000] K"),
        "{err}"
    );
    let kept = run
        .arrays()
        .into_iter()
        .find(|a| a.name == "sphere_temperature")
        .unwrap();
    assert_eq!(kept.values.to_vec(), t);

    let ckpt = run.checkpoint().unwrap();
    assert_eq!(ckpt, checkpoint_path(&dir.join("out"), 6));
    let resumed = open(Some(&ckpt));
    assert_eq!(resumed.steps_done(), 6);
    let again = resumed
        .arrays()
        .into_iter()
        .find(|a| a.name == "sphere_temperature")
        .unwrap();
    assert_eq!(again.values.to_vec(), t);
}
