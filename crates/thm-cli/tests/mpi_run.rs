//! `mpirun -np N thm run` (feature `mpi`; needs Open MPI's `mpirun`, run by `.ci/run`):
//!
//! - a tiny forced silo and a tiny bonded column (its release installs bonds in every RVE, a
//!   synchronisation inside a step) on 1, 2 and 3 processes write the same files, byte for
//!   byte (the summary aside: it records wall time), as `thm run` without MPI;
//! - a checkpoint of a 2-process run resumes on 3 processes and on 1 (without MPI) to the same
//!   last checkpoint;
//! - an output folder that already holds a run (process 0 alone touches it) ends every
//!   process with process 0's message;
//! - a write that fails on process 0 alone part-way ends every process at that step with its
//!   message, and the last checkpoint continues;
//! - a killed process ends the job with a non-zero status, and the last checkpoint written
//!   before it is intact and continues (without MPI) to the bits of the run never killed.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn thm() -> &'static str {
    env!("CARGO_BIN_EXE_thm")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("thm-mpi-test-{}-{name}", std::process::id()));
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

fn shipped(name: &str) -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../../scenarios/{name}"));
    std::fs::read_to_string(path).unwrap()
}

/// The forced silo: 0.2 m cells, 30-disk RVEs, 10 ms settling and 10 ms after the opening.
fn tiny_silo(dir: &Path) -> PathBuf {
    let t = shipped("mpm_dem_silo_forced.toml");
    let t = edit(t, "end = \"2.2 s\"", "end = \"20 ms\"");
    let t = edit(t, "settle_time = \"0.2 s\"", "settle_time = \"10 ms\"");
    let t = edit(t, "history_every = 20", "history_every = 2");
    let t = edit(t, "frame_every = 200", "frame_every = 5");
    let t = edit(t, "checkpoint_every = 1000", "checkpoint_every = 6");
    let t = edit(t, "cell_size = \"0.1 m\"", "cell_size = \"0.2 m\"");
    let t = edit(t, "disks = 400", "disks = 30");
    let file = dir.join("silo.toml");
    std::fs::write(&file, t).unwrap();
    file
}

/// The bonded column: 2 × 2 cells, 30-disk RVEs, the release (bonds installed) at step 10.
fn tiny_column(dir: &Path) -> PathBuf {
    let t = shipped("mpm_dem_column_b0.02_melting.toml");
    let t = edit(t, "end = \"21 s\"", "end = \"20 ms\"");
    let t = edit(t, "settle_time = \"1 s\"", "settle_time = \"10 ms\"");
    let t = edit(t, "history_every = 20", "history_every = 2");
    let t = edit(t, "frame_every = 500", "frame_every = 5");
    let t = edit(t, "checkpoint_every = 2000", "checkpoint_every = 6");
    let t = edit(t, "cells = 4", "cells = 2");
    let t = edit(t, "disks = 100", "disks = 30");
    let file = dir.join("column.toml");
    std::fs::write(&file, t).unwrap();
    file
}

fn mpirun(np: usize) -> Command {
    let mut c = Command::new("mpirun");
    c.arg("--oversubscribe");
    // Open MPI refuses root unless told; CI containers run as root.
    if std::env::var("USER").as_deref() == Ok("root") || is_root() {
        c.arg("--allow-run-as-root");
    }
    c.arg("-np").arg(np.to_string()).arg(thm());
    c.env("RAYON_NUM_THREADS", "1");
    c
}

fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("Uid:"))
                .map(|l| l.split_whitespace().nth(1) == Some("0"))
        })
        .unwrap_or(false)
}

fn run(np: Option<usize>, file: &Path, out: &Path, resume: Option<&Path>) -> Output {
    run_threads(np, 1, file, out, resume)
}

fn run_threads(
    np: Option<usize>,
    threads: usize,
    file: &Path,
    out: &Path,
    resume: Option<&Path>,
) -> Output {
    let mut c = match np {
        Some(np) => {
            let mut c = mpirun(np);
            c.env("RAYON_NUM_THREADS", threads.to_string());
            c
        }
        None => {
            let mut c = Command::new(thm());
            c.env("RAYON_NUM_THREADS", "2");
            c
        }
    };
    c.arg("run").arg(file).arg("--out").arg(out);
    if let Some(r) = resume {
        c.arg("--resume").arg(r);
    }
    c.output().unwrap()
}

fn ok(o: &Output, what: &str) {
    assert!(
        o.status.success(),
        "{what}: {}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Every file under `dir` but the summary, relative path → bytes.
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<(PathBuf, Vec<u8>)>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else if p.file_name().is_some_and(|n| n != "summary.md") {
                let rel = p.strip_prefix(root).unwrap().to_path_buf();
                out.push((rel, std::fs::read(&p).unwrap()));
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

fn same_files(a: &Path, b: &Path, what: &str) {
    let (fa, fb) = (files(a), files(b));
    let names = |f: &[(PathBuf, Vec<u8>)]| f.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&fa), names(&fb), "{what}: different files");
    for ((name, x), (_, y)) in fa.iter().zip(&fb) {
        assert!(x == y, "{what}: {} differs", name.display());
    }
}

#[test]
fn one_two_and_three_processes_write_the_files_of_a_run_without_mpi() {
    let dir = scratch("parity");
    for (name, file) in [("silo", tiny_silo(&dir)), ("column", tiny_column(&dir))] {
        let serial = dir.join(format!("{name}-serial"));
        ok(&run(None, &file, &serial, None), "serial");
        for np in 1..=3 {
            let out = dir.join(format!("{name}-{np}"));
            // 2 ranks run 2 threads each: any thread count inside a rank.
            let o = run_threads(Some(np), if np == 2 { 2 } else { 1 }, &file, &out, None);
            ok(&o, &format!("{name} on {np} processes"));
            same_files(&serial, &out, &format!("{name} on {np} processes"));
            let summary = std::fs::read_to_string(out.join("summary.md")).unwrap();
            assert_eq!(
                summary.contains(&format!("RVE stage on {np} processes")),
                np > 1,
                "{summary}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_two_process_checkpoint_resumes_on_three_and_on_one() {
    let dir = scratch("resume");
    let file = tiny_silo(&dir);
    let two = dir.join("two");
    ok(&run(Some(2), &file, &two, None), "2 processes");
    let ckpt = two.join("checkpoints/step_0000000012.ckpt");
    let last = "checkpoints/step_0000000020.ckpt";
    for np in [Some(3), None] {
        let out = dir.join(format!("from-two-{np:?}"));
        ok(&run(np, &file, &out, Some(&ckpt)), "resumed");
        assert_eq!(
            std::fs::read(out.join(last)).unwrap(),
            std::fs::read(two.join(last)).unwrap(),
            "resumed on {np:?}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_output_folder_only_process_zero_refuses_ends_every_process() {
    let dir = scratch("refused");
    let file = tiny_silo(&dir);
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("scenario.toml"), "kind = \"earlier\"\n").unwrap();
    let start = Instant::now();
    let o = run(Some(2), &file, &out, None);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("error: ") && err.contains("scenario.toml"),
        "{err}"
    );
    assert!(start.elapsed() < Duration::from_secs(120));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The newest complete checkpoint of `out` continues (without MPI) to the bits of the run
/// of `file` never stopped, 6 steps further.
fn newest_checkpoint_continues(dir: &Path, file: &Path, out: &Path) {
    let newest = thm_scenarios::last_complete_checkpoint(out).expect("a complete checkpoint");
    let step: u64 = newest
        .file_stem()
        .unwrap()
        .to_string_lossy()
        .trim_start_matches("step_")
        .parse()
        .unwrap();
    let upto = step + 6;
    let t = std::fs::read_to_string(file).unwrap();
    let short = dir.join("short.toml");
    std::fs::write(
        &short,
        edit(t, "end = \"2 s\"", &format!("end = \"{upto} ms\"")),
    )
    .unwrap();
    let resumed = dir.join("resumed");
    ok(&run(None, &short, &resumed, Some(&newest)), "resumed");
    let whole = dir.join("whole");
    ok(&run(None, &short, &whole, None), "whole");
    let last = format!("checkpoints/step_{upto:010}.ckpt");
    assert_eq!(
        std::fs::read(resumed.join(&last)).unwrap(),
        std::fs::read(whole.join(&last)).unwrap()
    );
}

/// The tiny silo for 2 s (long enough to be stopped part-way), started on 2 ranks; returns
/// the file and the job once it has written 3 checkpoints.
fn long_job(dir: &Path, out: &Path) -> (PathBuf, std::process::Child) {
    let text = std::fs::read_to_string(tiny_silo(dir)).unwrap();
    let file = dir.join("long.toml");
    std::fs::write(&file, edit(text, "end = \"20 ms\"", "end = \"2 s\"")).unwrap();
    let mut c = mpirun(2);
    c.arg("run").arg(&file).arg("--out").arg(out);
    let mut job = c
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    let ckpts = |out: &Path| {
        std::fs::read_dir(out.join("checkpoints"))
            .map(|d| d.count())
            .unwrap_or(0)
    };
    while ckpts(out) < 3 {
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "no checkpoints after 300 s"
        );
        assert!(job.try_wait().unwrap().is_none(), "the job ended early");
        std::thread::sleep(Duration::from_millis(50));
    }
    (file, job)
}

fn wait_for(job: &mut std::process::Child, what: &str) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(s) = job.try_wait().unwrap() {
            return s;
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "the job did not end after {what}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A write that fails on rank 0 alone (its frame folder replaced by a file part-way) ends
/// both ranks at that step with rank 0's message, instead of leaving rank 1 waiting in the
/// next exchange; the last checkpoint is intact and continues.
#[test]
fn a_write_only_rank_zero_fails_ends_every_rank() {
    let dir = scratch("write-fails");
    let out = dir.join("out");
    let (file, mut job) = long_job(&dir, &out);
    let frames = out.join("material_points");
    std::fs::rename(&frames, dir.join("moved_frames")).unwrap();
    std::fs::write(&frames, b"not a folder").unwrap();
    let status = wait_for(&mut job, "its frame folder was replaced");
    assert!(!status.success());
    let mut err = String::new();
    std::io::Read::read_to_string(job.stderr.as_mut().unwrap(), &mut err).unwrap();
    assert!(
        err.contains("error: ") && err.contains("material_points"),
        "{err}"
    );
    assert!(err.contains("the last complete checkpoint is"), "{err}");
    newest_checkpoint_continues(&dir, &file, &out);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The pids of `thm` processes whose environment says they are MPI rank `rank`, children of
/// the job started by this test (found through /proc).
fn rank_pids(rank: usize, out: &Path) -> Vec<u32> {
    let mut pids = Vec::new();
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return pids;
    };
    for e in entries.flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let cmdline = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
        let cmdline = String::from_utf8_lossy(&cmdline);
        if !cmdline.contains(&*out.to_string_lossy()) || !cmdline.starts_with(thm()) {
            continue;
        }
        let environ = std::fs::read(format!("/proc/{pid}/environ")).unwrap_or_default();
        let wanted = format!("OMPI_COMM_WORLD_RANK={rank}");
        if environ.split(|b| *b == 0).any(|v| v == wanted.as_bytes()) {
            pids.push(pid);
        }
    }
    pids
}

#[test]
fn a_killed_process_ends_the_job_and_leaves_the_last_checkpoint_intact() {
    let dir = scratch("killed");
    let out = dir.join("out");
    let (file, mut job) = long_job(&dir, &out);
    let victims = rank_pids(1, &out);
    assert_eq!(victims.len(), 1, "rank 1 of the job: {victims:?}");
    Command::new("kill")
        .arg("-9")
        .arg(victims[0].to_string())
        .status()
        .unwrap();
    let status = wait_for(&mut job, "its rank 1 was killed");
    assert!(!status.success());
    // The newest checkpoint is intact and continues (without MPI) to the bits of the run
    // never killed.
    newest_checkpoint_continues(&dir, &file, &out);
    std::fs::remove_dir_all(&dir).unwrap();
}
