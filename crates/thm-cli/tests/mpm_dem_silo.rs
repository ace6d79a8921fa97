//! `thm run` of the `mpm_dem_silo` kind (B-Sect. 5.3.2 on the MPM×DEM scheme): both shipped
//! files are read and their silos built and stepped past the gate's opening, a tiny copy
//! resumed from a checkpoint before the opening ends with the same bits, 1 and 2 threads write
//! the same checkpoint, and bad values name their key.

use std::path::{Path, PathBuf};
use std::process::Command;

fn thm() -> Command {
    Command::new(env!("CARGO_BIN_EXE_thm"))
}

fn shipped(mode: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join(format!("../../scenarios/mpm_dem_silo_{mode}.toml"))
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thm-silo-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn edit(text: String, from: &str, to: &str) -> String {
    assert!(
        text.contains(from),
        "the shipped file changed: `{from}` not found"
    );
    text.replace(from, to)
}

/// A shipped file shortened to 10 ms of settling and 10 ms after the opening (the 400-disk
/// RVEs take a second to build and a few more to step).
fn short(dir: &Path, mode: &str, more: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(shipped(mode)).unwrap();
    let end = if mode == "free" {
        "end = \"12.2 s\""
    } else {
        "end = \"2.2 s\""
    };
    let text = edit(text, end, "end = \"20 ms\"");
    let text = edit(text, "settle_time = \"0.2 s\"", "settle_time = \"10 ms\"");
    let text = edit(text, "history_every = 20", "history_every = 2");
    let text = edit(text, "frame_every = 200", "frame_every = 10");
    let text = edit(text, "checkpoint_every = 1000", "checkpoint_every = 6");
    let file = dir.join(format!("{mode}.toml"));
    std::fs::write(&file, more(text)).unwrap();
    file
}

fn run(
    file: &Path,
    out: &Path,
    resume: Option<&Path>,
    threads: Option<usize>,
) -> std::process::Output {
    let mut c = thm();
    c.arg("run").arg(file).arg("--out").arg(out);
    if let Some(r) = resume {
        c.arg("--resume").arg(r);
    }
    if let Some(n) = threads {
        c.env("RAYON_NUM_THREADS", n.to_string());
    }
    c.output().unwrap()
}

#[test]
fn shipped_files_run_past_the_opening() {
    let dir = scratch("shipped");
    for mode in ["free", "forced"] {
        let file = short(&dir, mode, |t| t);
        let out = dir.join(mode);
        let o = run(&file, &out, None, None);
        assert!(
            o.status.success(),
            "{mode}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
        let header = history.lines().next().unwrap();
        for c in [
            "discharged_fraction",
            "heat_balance_residual",
            "points_through_walls",
            "plate_force",
        ] {
            assert!(header.contains(c), "{mode}: {header}");
        }
        assert!(out.join("rve_0_disks.pvd").is_file() && out.join("rve_1_disks.pvd").is_file());
        // The material-point frames carry the per-point RVE fields.
        let frames: Vec<PathBuf> = std::fs::read_dir(out.join("material_points"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        assert!(!frames.is_empty());
        let vtu = std::fs::read(&frames[0]).unwrap();
        let text = String::from_utf8_lossy(&vtu);
        for field in [
            "deviatoric_strain",
            "rve_void_ratio",
            "rve_coordination",
            "rve_intact_bonds",
            "temperature_rise",
        ] {
            assert!(
                text.contains(field),
                "{mode}: {field} missing from {}",
                frames[0].display()
            );
        }
        assert!(out.join("summary.md").is_file());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A tiny forced silo (0.2 m cells, 30-disk RVEs) resumed from the checkpoint at step 6,
/// before the gate opens at step 10, ends with the same bytes as the run not interrupted; the
/// same run on 1 and on 2 threads writes the same last checkpoint.
#[test]
fn resumed_across_the_opening_and_thread_counts_give_the_same_bits() {
    let dir = scratch("resume");
    let file = short(&dir, "forced", |t| {
        let t = edit(t, "cell_size = \"0.1 m\"", "cell_size = \"0.2 m\"");
        edit(t, "disks = 400", "disks = 30")
    });
    let full = dir.join("full");
    let o = run(&file, &full, None, Some(2));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let again = dir.join("again");
    let o = run(
        &file,
        &again,
        Some(&full.join("checkpoints/step_0000000006.ckpt")),
        Some(2),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let one = dir.join("one");
    let o = run(&file, &one, None, Some(1));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let last = "checkpoints/step_0000000020.ckpt";
    let bytes = |d: &Path| std::fs::read(d.join(last)).unwrap();
    assert_eq!(bytes(&full), bytes(&again));
    assert_eq!(bytes(&full), bytes(&one));
    // The resumed run's history starts at the checkpoint: its rows equal the last ones.
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
fn bad_silo_values_name_their_key() {
    let dir = scratch("bad");
    for (from, to, key) in [
        (
            "cell_size = \"0.1 m\"",
            "cell_size = \"0.03 m\"",
            "silo.cell_size",
        ),
        (
            "cell_size = \"0.1 m\"",
            "cell_size = \"3 MPa\"",
            "silo.cell_size",
        ),
        ("disks = 400", "disks = 5", "silo.disks"),
        (
            "density_scaling = 1e5",
            "density_scaling = 0.5",
            "silo.density_scaling",
        ),
        (
            "points_per_cell = 2",
            "points_per_cell = 9",
            "silo.points_per_cell",
        ),
        (
            "settle_time = \"10 ms\"",
            "settle_time = \"1 s\"",
            "silo.settle_time",
        ),
        (
            "plate_speed = \"0.2 m/s\"",
            "plate_speed = \"-1 m/s\"",
            "silo.plate_speed",
        ),
        ("forced = true", "forced = 1", "forced"),
        ("seed = 1", "seed = 1\ncolour = 2", "colour"),
    ] {
        let file = short(&dir, "forced", |t| edit(t, from, to));
        let o = run(&file, &dir.join("out"), None, None);
        assert!(!o.status.success(), "{key}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(key), "{key}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every file under `dir` but the summary (it records wall time), relative path → bytes.
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(PathBuf, Vec<u8>)>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else if p.file_name().is_some_and(|n| n != "summary.md") {
                out.push((
                    p.strip_prefix(root).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// `thm run` on `size` processes that are threads of this test
/// (`thm_coupling::multiscale::ThreadGroup`, the same driver code as under `mpirun`).
fn run_on_threads(size: usize, file: &Path, out: &Path, resume: Option<&Path>) {
    use std::sync::Arc;
    use std::sync::atomic::AtomicBool;
    use thm_coupling::multiscale::{Collective, ThreadGroup};
    let handles: Vec<_> = ThreadGroup::new(size)
        .into_iter()
        .map(|h| {
            let (file, out) = (file.to_path_buf(), out.to_path_buf());
            let resume = resume.map(Path::to_path_buf);
            std::thread::spawn(move || {
                let c: Arc<dyn Collective> = Arc::new(h);
                thm_scenarios::run_file_on(
                    &file,
                    &out,
                    resume.as_deref(),
                    &AtomicBool::new(false),
                    thm_scenarios::scenario::Progress::Quiet,
                    Some(c),
                )
            })
        })
        .collect();
    for h in handles {
        h.join().unwrap().unwrap();
    }
}

/// The tiny forced silo with its RVE stage spread over 3 processes (threads here, MPI ranks
/// under `mpirun`) writes every file of the run on one process, byte for byte; its
/// checkpoint before the opening resumes on 2 processes to the same last checkpoint.
#[test]
fn processes_sharing_the_rves_write_the_files_of_one_process() {
    let dir = scratch("processes");
    let file = short(&dir, "forced", |t| {
        let t = edit(t, "cell_size = \"0.1 m\"", "cell_size = \"0.2 m\"");
        edit(t, "disks = 400", "disks = 30")
    });
    let one = dir.join("one");
    let o = run(&file, &one, None, Some(2));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let three = dir.join("three");
    run_on_threads(3, &file, &three, None);
    let (a, b) = (files(&one), files(&three));
    assert_eq!(
        a.iter().map(|f| &f.0).collect::<Vec<_>>(),
        b.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(x == y, "{} differs", name.display());
    }
    let summary = std::fs::read_to_string(three.join("summary.md")).unwrap();
    assert!(summary.contains("RVE stage on 3 processes"), "{summary}");
    let two = dir.join("two");
    run_on_threads(
        2,
        &file,
        &two,
        Some(&three.join("checkpoints/step_0000000006.ckpt")),
    );
    let last = "checkpoints/step_0000000020.ckpt";
    assert_eq!(
        std::fs::read(two.join(last)).unwrap(),
        std::fs::read(one.join(last)).unwrap()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
