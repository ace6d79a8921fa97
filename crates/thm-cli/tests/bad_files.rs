//! Hostile or mistaken files given to `thm`: each is refused with a short message that names
//! what is wrong, quoting at most an excerpt of the file, and nothing already written is lost.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Longest error message any of these files may produce on standard error \[bytes\].
const SHORT: usize = 600;

const SCENARIO: &str = r#"
kind = "lumped_cooling"

[time]
step = "0.25 s"
end = "5 s"

[output]
history_every = 2
frame_every = 0
checkpoint_every = 8

[particles]
lattice = [3, 2]
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
    let dir = std::env::temp_dir().join(format!("thm-bad-files-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn thm(args: &[&std::ffi::OsStr], stdin: Option<&[u8]>) -> Output {
    use std::io::Write;
    let mut child = Command::new(env!("CARGO_BIN_EXE_thm"))
        .args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let input = stdin.unwrap_or(b"").to_vec();
    let mut pipe = child.stdin.take().unwrap();
    let writer = std::thread::spawn(move || {
        let _ = pipe.write_all(&input);
    });
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap();
    out
}

/// Runs `thm run FILE --out OUT [--resume CKPT]`, expects failure, returns standard error.
fn run_fails(file: &Path, out: &Path, resume: Option<&Path>) -> String {
    let mut args = vec![
        "run".as_ref(),
        file.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ];
    if let Some(r) = resume {
        args.extend(["--resume".as_ref(), r.as_os_str()]);
    }
    let result = thm(&args, None);
    let stderr = String::from_utf8_lossy(&result.stderr).into_owned();
    assert!(!result.status.success(), "accepted: {stderr}");
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.len() <= SHORT,
        "{} bytes of error message: {}…",
        stderr.len(),
        &stderr[..SHORT]
    );
    stderr
}

fn scenario_fails(name: &str, content: &[u8]) -> String {
    let dir = scratch(name);
    let file = dir.join("scenario.toml");
    std::fs::write(&file, content).unwrap();
    let out = dir.join("out");
    let stderr = run_fails(&file, &out, None);
    assert!(
        !out.exists(),
        "a refused scenario created its output folder"
    );
    std::fs::remove_dir_all(&dir).unwrap();
    stderr
}

#[test]
fn a_checkpoint_given_as_the_scenario_is_named_as_such_not_printed() {
    let dir = scratch("ckpt-as-scenario");
    // 60 KB of state, like the 53-sphere bar's checkpoint.
    let state: Vec<f64> = (0..3000).map(|i| f64::from(i) / 7.0).collect();
    for encoding in [
        thm_io::CheckpointEncoding::Json,
        thm_io::CheckpointEncoding::Binary,
    ] {
        let ckpt = dir.join("step_0000000002.ckpt");
        thm_io::save_checkpoint_as(&ckpt, encoding, "pore_scale_bar", 1, &state).unwrap();
        let stderr = run_fails(&ckpt, &dir.join("out"), None);
        assert!(
            stderr.contains("this is a thm checkpoint, not a scenario file"),
            "{stderr}"
        );
        assert!(stderr.contains("--resume"), "{stderr}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_large_file_that_is_not_toml_is_quoted_by_excerpt_with_line_and_column() {
    // One 60 KB line of JSON.
    let json = format!("{{\"a\":[{}0]}}", "1.5,".repeat(15_000));
    let stderr = scenario_fails("json", json.as_bytes());
    assert!(
        stderr.contains("not valid TOML: line 1, column"),
        "{stderr}"
    );
    // 60 KB on line 3, the error near its end.
    let long = format!(
        "kind = \"lumped_cooling\"\n\nx = [{}1 2]\n",
        "1,".repeat(30_000)
    );
    let stderr = scenario_fails("long-line", long.as_bytes());
    assert!(stderr.contains("line 3, column 6000"), "{stderr}");
    assert!(stderr.contains("1,1,1 2]`"), "{stderr}");
    // Binary junk.
    let junk: Vec<u8> = (0..60_000u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8)
        .collect();
    let stderr = scenario_fails("binary", &junk);
    assert!(stderr.contains("not UTF-8 text"), "{stderr}");
}

#[test]
fn an_unknown_kind_is_named_before_any_missing_section() {
    let stderr = scenario_fails("kind", b"kind = \"no_such_kind\"\n");
    assert!(
        stderr.contains("kind: unknown scenario kind `no_such_kind`; one of `lumped_cooling`"),
        "{stderr}"
    );
    assert!(!stderr.contains("[time]"), "{stderr}");
    // A 60 KB kind is cut.
    let huge = format!("kind = \"{}\"\n", "k".repeat(60_000));
    let stderr = scenario_fails("huge-kind", huge.as_bytes());
    assert!(stderr.contains("unknown scenario kind `kkkk"), "{stderr}");
    assert!(stderr.contains("k…`"), "{stderr}");
    // A known kind still names its first missing section.
    let stderr = scenario_fails("no-time", b"kind = \"lumped_cooling\"\n");
    assert!(stderr.contains("time: missing section [time]"), "{stderr}");
}

#[test]
fn huge_values_and_keys_are_quoted_by_excerpt() {
    let value = SCENARIO.replace("\"25 mm\"", &format!("\"{} mm\"", "9".repeat(60_000) + "x"));
    let stderr = scenario_fails("value", value.as_bytes());
    assert!(stderr.contains("particles.spacing"), "{stderr}");
    let key = SCENARIO.replace("radius_spread", &"r".repeat(60_000));
    let stderr = scenario_fails("key", key.as_bytes());
    assert!(stderr.contains("unknown key"), "{stderr}");
}

#[test]
fn eos_rows_are_quoted_by_excerpt() {
    let header = format!("{}\n", "T,".repeat(30_000));
    let result = thm(
        &["eos".as_ref(), "pressure".as_ref()],
        Some(header.as_bytes()),
    );
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success());
    assert!(stderr.contains("line 1 (header)"), "{stderr}");
    assert!(
        stderr.len() <= SHORT,
        "{} bytes: {}",
        stderr.len(),
        &stderr[..SHORT]
    );
    let row = format!("fluid,T,rho\nwater,{},1000\n", "3".repeat(60_000) + "x");
    let result = thm(&["eos".as_ref(), "pressure".as_ref()], Some(row.as_bytes()));
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success());
    assert!(stderr.contains("line 2 (row 1), column `T`"), "{stderr}");
    assert!(
        stderr.len() <= SHORT,
        "{} bytes: {}",
        stderr.len(),
        &stderr[..SHORT]
    );
    let row = format!("fluid,T,rho\n{},300,1000\n", "w".repeat(60_000));
    let result = thm(&["eos".as_ref(), "pressure".as_ref()], Some(row.as_bytes()));
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(stderr.contains("unknown fluid `www"), "{stderr}");
    assert!(
        stderr.len() <= SHORT,
        "{} bytes: {}",
        stderr.len(),
        &stderr[..SHORT]
    );
}

/// A run of [`SCENARIO`] in `dir/out`, returning its output folder.
fn finished_run(dir: &Path) -> (PathBuf, PathBuf) {
    let file = dir.join("scenario_in.toml");
    std::fs::write(&file, SCENARIO).unwrap();
    let out = dir.join("out");
    let result = thm(
        &[
            "run".as_ref(),
            file.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ],
        None,
    );
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    (file, out)
}

fn checkpoint(out: &Path, step: u64) -> PathBuf {
    out.join("checkpoints")
        .join(format!("step_{step:010}.ckpt"))
}

/// Every damaged, foreign or future checkpoint is refused before anything in the output
/// folder changes.
#[test]
fn damaged_foreign_and_future_checkpoints_are_refused() {
    let dir = scratch("refuse");
    let (file, out) = finished_run(&dir);
    let history = std::fs::read(out.join("history.csv")).unwrap();
    let good = std::fs::read(checkpoint(&out, 8)).unwrap();
    let bad = dir.join("bad.ckpt");
    let refused = |content: &[u8], expect: &str| {
        std::fs::write(&bad, content).unwrap();
        let stderr = run_fails(&file, &out, Some(&bad));
        assert!(stderr.contains(expect), "expected `{expect}`: {stderr}");
        assert!(stderr.contains("bad.ckpt"), "{stderr}");
        assert_eq!(std::fs::read(out.join("history.csv")).unwrap(), history);
    };
    // Truncated: cut in the middle, and cut just before its last byte.
    refused(&good[..good.len() / 2], "checkpoint is truncated");
    refused(&good[..good.len() - 1], "checkpoint is truncated");
    // Altered: one digit of the state.
    let mut altered = good.clone();
    let at = good.len() / 2
        + good[good.len() / 2..]
            .iter()
            .position(u8::is_ascii_digit)
            .unwrap();
    altered[at] = if altered[at] == b'7' { b'8' } else { b'7' };
    refused(&altered, "checksum mismatch");
    // Another container version, sealed with a valid checksum.
    let text = std::str::from_utf8(&good).unwrap();
    let body = text[..text.rfind(",\"crc32\"").unwrap()]
        .replace("\"format_version\":2", "\"format_version\":9");
    let crc = crc32(body.as_bytes());
    refused(
        format!("{body},\"crc32\":\"{crc:08x}\"}}\n").as_bytes(),
        "checkpoint format version 9",
    );
    // Another kind of scenario.
    let foreign = dir.join("foreign.ckpt");
    thm_io::save_checkpoint(&foreign, "dem_uniaxial_tension_bar", 1, &vec![1.0, 2.0]).unwrap();
    refused(
        &std::fs::read(&foreign).unwrap(),
        "holds a `dem_uniaxial_tension_bar` state",
    );
    // Another state version of this kind.
    thm_io::save_checkpoint(&foreign, "lumped_cooling", 99, &vec![1.0, 2.0]).unwrap();
    refused(&std::fs::read(&foreign).unwrap(), "state version 99");
    // The same kind with other parameters: the differing key is named.
    let other = dir.join("other.toml");
    std::fs::write(
        &other,
        SCENARIO.replace("lattice = [3, 2]", "lattice = [2, 3]"),
    )
    .unwrap();
    let stderr = run_fails(&other, &out, Some(&checkpoint(&out, 8)));
    assert!(stderr.contains("written for another scenario"), "{stderr}");
    assert!(
        stderr.contains("particles.lattice was `[3, 2]`, now `[2, 3]`"),
        "{stderr}"
    );
    // Another time step.
    std::fs::write(
        &other,
        SCENARIO.replace("step = \"0.25 s\"", "step = \"0.125 s\""),
    )
    .unwrap();
    let stderr = run_fails(&other, &out, Some(&checkpoint(&out, 8)));
    assert!(
        stderr.contains("time.step was 0.25 s, now 0.125 s"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(out.join("history.csv")).unwrap(), history);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// CRC-32 (IEEE), as the checkpoint writer computes it, written out to keep this test
/// independent of the writer's code.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}
