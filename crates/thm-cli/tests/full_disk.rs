//! `thm run` writing into a small tmpfs that fills up part-way: a clear error naming the file
//! and the cause, the last complete checkpoint readable, and resuming from it (with room to
//! write) ends with the same bits as a run that never ran out of space.
//!
//! Mounting a tmpfs needs root (or CAP_SYS_ADMIN). Where it cannot be mounted this test fails
//! with the reason, unless `THM_SKIP_TMPFS=1` says to skip it, in which case it prints the skip
//! on standard error. The same failure is simulated without a mount in thm-io's unit test
//! `fsutil::tests::a_full_disk_keeps_the_previous_content_and_names_the_file`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// 200 spheres; every frame (ASCII, about 40 KB) and checkpoint (about 10 KB) kept.
const SCENARIO: &str = r#"
kind = "lumped_cooling"

[time]
step = "0.25 s"
end = "100 s"

[output]
history_every = 1
frame_every = 10
checkpoint_every = 20
encoding = "ascii"

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

/// Size of the tmpfs: room for the first few frames and checkpoints, not for the run.
const TMPFS_SIZE: &str = "640k";

/// A mounted tmpfs, unmounted when dropped (also when the test fails).
struct Tmpfs(PathBuf);

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

fn mount_tmpfs(at: &Path) -> Result<Tmpfs, String> {
    std::fs::create_dir_all(at).map_err(|e| e.to_string())?;
    let out = Command::new("mount")
        .args(["-t", "tmpfs", "-o", &format!("size={TMPFS_SIZE}"), "tmpfs"])
        .arg(at)
        .output()
        .map_err(|e| format!("cannot start `mount`: {e}"))?;
    if out.status.success() {
        Ok(Tmpfs(at.to_path_buf()))
    } else {
        Err(String::from_utf8_lossy(&out.stderr).trim().to_string())
    }
}

fn thm_run(file: &Path, out: &Path, resume: Option<&Path>) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_thm"));
    cmd.arg("run").arg(file).arg("--out").arg(out);
    if let Some(r) = resume {
        cmd.arg("--resume").arg(r);
    }
    cmd.output().unwrap()
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

#[test]
fn a_full_disk_is_a_clear_error_and_the_last_checkpoint_resumes() {
    let dir = std::env::temp_dir().join(format!("thm-full-disk-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("scenario_in.toml");
    std::fs::write(&file, SCENARIO).unwrap();
    let disk = dir.join("disk");
    let tmpfs = match mount_tmpfs(&disk) {
        Ok(t) => t,
        Err(why) => {
            if std::env::var("THM_SKIP_TMPFS").is_ok_and(|v| v == "1") {
                eprintln!(
                    "SKIPPED: the full-disk test needs a tmpfs and mounting one failed ({why}); \
                     THM_SKIP_TMPFS=1 is set, so this test checked nothing"
                );
                return;
            }
            panic!(
                "cannot mount a {TMPFS_SIZE} tmpfs at {} ({why}); the full-disk test needs root \
                 or CAP_SYS_ADMIN. Set THM_SKIP_TMPFS=1 to skip it knowingly.",
                disk.display()
            );
        }
    };

    // The run fills the disk part-way and stops with a clear error.
    let out = disk.join("out");
    let result = thm_run(&file, &out, None);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("No space left on device"), "{stderr}");
    assert!(stderr.contains(&out.display().to_string()), "{stderr}");
    assert!(
        stderr.contains("the last complete checkpoint is"),
        "{stderr}"
    );
    assert!(stderr.len() < 1000, "{stderr}");

    // Every checkpoint left is complete; the newest is the one the message names.
    let mut checkpoints: Vec<PathBuf> = std::fs::read_dir(out.join("checkpoints"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ckpt"))
        .collect();
    checkpoints.sort();
    assert!(!checkpoints.is_empty(), "no checkpoint fitted: {stderr}");
    for p in &checkpoints {
        let info = thm_io::checkpoint_info(p)
            .unwrap_or_else(|e| panic!("a full disk left a damaged checkpoint: {e}"));
        assert_eq!(info.kind, "lumped_cooling");
    }
    let last = checkpoints.last().unwrap();
    assert!(
        stderr.contains(&format!("--resume {}", last.display())),
        "{stderr}"
    );
    assert!(
        !last.ends_with("step_0000000400.ckpt"),
        "the disk did not fill up: enlarge the scenario or shrink TMPFS_SIZE"
    );

    // With room to write, resuming from it ends exactly as an uninterrupted run.
    let roomy = dir.join("roomy");
    copy_dir(&out, &roomy);
    drop(tmpfs);
    let resume_from = roomy.join(last.strip_prefix(&out).unwrap());
    let result = thm_run(&file, &roomy, Some(&resume_from));
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let reference = dir.join("reference");
    let result = thm_run(&file, &reference, None);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let final_ckpt = |d: &Path| std::fs::read(d.join("checkpoints/step_0000000400.ckpt")).unwrap();
    assert!(final_ckpt(&roomy) == final_ckpt(&reference));
    assert!(
        std::fs::read(roomy.join("history.csv")).unwrap()
            == std::fs::read(reference.join("history.csv")).unwrap()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
