//! `thm run` killed with SIGKILL at random (seeded) moments and resumed from its last
//! checkpoint ends with the same bits as a run never interrupted: history, frames, collection
//! files and final checkpoint. Every checkpoint file present at a kill must be complete.
//!
//! The default test kills a few moments to stay fast; the ignored
//! `kill_and_resume_at_24_moments` runs the full set (`cargo test -p thm-cli --test
//! kill_resume -- --ignored`), and `THM_KILL_MOMENTS=n` sets the count of either.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// 200 spheres, 3200 steps; a checkpoint every 80 steps, a frame every 100.
const SCENARIO: &str = r#"
kind = "lumped_cooling"

[time]
step = "0.25 s"
end = "800 s"

[output]
history_every = 3
frame_every = 100
checkpoint_every = 80
encoding = "raw"

[particles]
lattice = [20, 10]
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
    let dir = std::env::temp_dir().join(format!("thm-kill-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn thm_run(file: &Path, out: &Path, resume: Option<&Path>) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_thm"));
    cmd.arg("run").arg(file).arg("--out").arg(out);
    if let Some(r) = resume {
        cmd.arg("--resume").arg(r);
    }
    cmd.stdout(Stdio::null()).stderr(Stdio::piped());
    cmd
}

fn run_to_end(file: &Path, out: &Path, resume: Option<&Path>) {
    let result = thm_run(file, out, resume).output().unwrap();
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
}

/// Every file under `dir` (relative path → bytes), except the summary, which records the
/// wall-clock time.
fn files(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, into: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, into);
            } else {
                let rel = p.strip_prefix(root).unwrap().to_path_buf();
                if rel != Path::new("summary.md") {
                    into.insert(rel, std::fs::read(&p).unwrap());
                }
            }
        }
    }
    let mut map = BTreeMap::new();
    walk(dir, dir, &mut map);
    map
}

/// The newest checkpoint in `out`, after checking that every checkpoint there is complete.
fn last_checkpoint(out: &Path) -> Option<PathBuf> {
    let dir = out.join("checkpoints");
    let mut found: Vec<PathBuf> = std::fs::read_dir(&dir)
        .ok()?
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ckpt"))
        .collect();
    found.sort();
    for p in &found {
        if let Err(e) = thm_io::checkpoint_info(p) {
            panic!("a killed run left an incomplete checkpoint in place: {e}");
        }
    }
    found.pop()
}

/// splitmix64: a seeded, dependency-free source of kill moments.
struct Moments(u64);

impl Moments {
    fn next_fraction(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn kill_and_resume(moments: usize, seed: u64) {
    let moments = std::env::var("THM_KILL_MOMENTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(moments);
    let dir = scratch(&format!("seed{seed}"));
    let file = dir.join("scenario_in.toml");
    std::fs::write(&file, SCENARIO).unwrap();
    let reference = dir.join("reference");
    let started = Instant::now();
    run_to_end(&file, &reference, None);
    let span = started.elapsed();
    let expected = files(&reference);
    assert!(expected.contains_key(Path::new("checkpoints/step_0000003200.ckpt")));

    let mut rng = Moments(seed);
    let mut resumed_from = Vec::new();
    for k in 0..moments {
        let out = dir.join(format!("killed_{k}"));
        // Anywhere in the reference run's length (a loaded machine lets some runs finish
        // first; those must match too).
        let delay = span.mul_f64(0.9 * rng.next_fraction());
        let mut child = thm_run(&file, &out, None).spawn().unwrap();
        std::thread::sleep(delay);
        child.kill().unwrap(); // SIGKILL; an error only if it already ended.
        let status = child.wait().unwrap();
        let killed = !status.success();
        let from = if killed { last_checkpoint(&out) } else { None };
        match &from {
            Some(ckpt) => run_to_end(&file, &out, Some(ckpt)),
            None if killed => {
                // Killed before its first checkpoint (perhaps before creating its folder):
                // nothing to resume, start again.
                let _ = std::fs::remove_dir_all(&out);
                run_to_end(&file, &out, None);
            }
            None => {}
        }
        let got = files(&out);
        let label = format!(
            "kill {k} after {:.0} ms ({}, resumed from {})",
            delay.as_secs_f64() * 1e3,
            if killed { "killed" } else { "had finished" },
            from.as_ref()
                .map_or("nothing".into(), |p| p.display().to_string())
        );
        let names = |m: &BTreeMap<PathBuf, Vec<u8>>| m.keys().cloned().collect::<Vec<_>>();
        assert_eq!(names(&got), names(&expected), "{label}: other files");
        for (name, bytes) in &expected {
            assert!(&got[name] == bytes, "{label}: {} differs", name.display());
        }
        println!("{label}: identical");
        resumed_from.push(from);
        std::fs::remove_dir_all(&out).unwrap();
    }
    // The moments must have exercised resuming, not only restarts or finished runs.
    let mid_run = resumed_from.iter().filter(|f| f.is_some()).count();
    assert!(
        mid_run * 2 >= moments,
        "only {mid_run} of {moments} kills resumed from a checkpoint (run took {span:?})"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn kill_and_resume_at_a_few_moments() {
    kill_and_resume(4, 0x5EED_0001);
}

#[test]
#[ignore = "24 kills take about a minute; run with --ignored"]
fn kill_and_resume_at_24_moments() {
    kill_and_resume(24, 0x5EED_0024);
}

#[test]
fn a_kill_never_leaves_a_partial_checkpoint_under_its_final_name() {
    // Short delays concentrated where checkpoints are written densely.
    let dir = scratch("dense");
    let file = dir.join("scenario_in.toml");
    std::fs::write(
        &file,
        SCENARIO.replace("checkpoint_every = 80", "checkpoint_every = 1"),
    )
    .unwrap();
    let mut rng = Moments(7);
    for k in 0..3 {
        let out = dir.join(format!("run{k}"));
        let mut child = thm_run(&file, &out, None).spawn().unwrap();
        std::thread::sleep(Duration::from_millis(
            30 + (rng.next_fraction() * 200.0) as u64,
        ));
        let _ = child.kill();
        let _ = child.wait();
        last_checkpoint(&out);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
