//! `thm calibrate` run as a user runs it: targets in, calibrated parameters and iterations
//! out, and a clear error for a target that no parameter reaches.

use std::process::{Command, Output};

fn thm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_thm"))
        .args(args)
        .output()
        .unwrap()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8(bytes.to_vec()).unwrap()
}

/// The γ calibration meets the paper's permeability (the last iteration's κ) and prints it
/// beside A-Table 1's γ.
#[test]
fn the_flow_calibration_reaches_the_papers_permeability() {
    let out = thm(&["calibrate", "--only", "flow"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    let iterations: Vec<Vec<f64>> = stdout
        .lines()
        .skip_while(|l| !l.starts_with("iteration"))
        .skip(1)
        .take_while(|l| !l.starts_with("gamma"))
        .map(|l| l.split_whitespace().map(|f| f.parse().unwrap()).collect())
        .collect();
    assert!(iterations.len() >= 2, "{stdout}");
    assert_eq!(iterations[0][1], 0.0115, "starts from A-Table 1's gamma");
    let last = &iterations[iterations.len() - 1];
    assert!((last[2] / 2.47e-16 - 1.0).abs() < 1e-6, "{stdout}");
    let gamma_line = stdout.lines().find(|l| l.starts_with("gamma ")).unwrap();
    assert!(gamma_line.contains("0.0115 (A-Table 1)"), "{gamma_line}");
}

#[test]
fn an_unreachable_permeability_names_the_option_and_the_range_reached() {
    let out = thm(&["calibrate", "--only", "flow", "--permeability", "1e-6"]);
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert!(stderr.contains("--permeability 1e-6"), "{stderr}");
    assert!(stderr.contains("target_permeability"), "{stderr}");
    assert!(stderr.contains("permeabilities reached span"), "{stderr}");
}

/// A strength below what the weakest bonds searched (T = 0.3 MPa) give: the search walks
/// down to the end of its range and reports the strengths it reached.
#[test]
fn an_unreachable_strength_names_the_option_and_the_range_reached() {
    let out = thm(&[
        "calibrate",
        "--only",
        "bar",
        "--strength",
        "1 Pa",
        "--seeds",
        "1",
    ]);
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert!(stderr.contains("--strength 1 Pa"), "{stderr}");
    assert!(stderr.contains("target_strength"), "{stderr}");
    assert!(stderr.contains("[3e5, 3e9]"), "{stderr}");
    assert!(stderr.contains("values reached span"), "{stderr}");
}

#[test]
fn a_negative_target_is_refused_before_any_run() {
    let out = thm(&["calibrate", "--strength", "-3 MPa"]);
    assert!(!out.status.success());
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("--strength: must be > 0 MPa, got -3 MPa"),
        "{stderr}"
    );
    let out = thm(&["calibrate", "--permeability", "0"]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("--permeability: must be > 0"));
}

/// The value on the line of `quantity` in the calibration's result table.
fn calibrated(stdout: &str, quantity: &str) -> f64 {
    let line = stdout
        .lines()
        .find(|l| l.starts_with(quantity))
        .unwrap_or_else(|| panic!("no {quantity} line in\n{stdout}"));
    line[quantity.len()..]
        .split_whitespace()
        .next()
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{line}"))
}

/// By default `thm calibrate` runs on the coupled bar cases' own packings, and what it finds
/// is what those cases run with: T and γ within the four digits the constants keep.
#[test]
fn the_default_calibration_gives_the_bar_cases_parameters() {
    let out = thm(&["calibrate"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("5 coupled-bar packing(s)"), "{stdout}");
    let t = calibrated(&stdout, "T [MPa]");
    let cases_t = thm_coupling::bar::CASE_A_BOND_TENSILE_STRENGTH / 1e6;
    assert!((t / cases_t - 1.0).abs() < 1e-4, "T {t} vs {cases_t}");
    let gamma = calibrated(&stdout, "gamma ");
    let cases_gamma = thm_coupling::bar::BAR_T2T_REDUCTION_FACTOR;
    assert!(
        (gamma / cases_gamma - 1.0).abs() < 1e-4,
        "gamma {gamma} vs {cases_gamma}"
    );
}

/// `--packings tension-bar` keeps the calibration on `thm-dem`'s tension bars, whose T is the
/// one `dem/uniaxial_tension_bar` checks (48.29 MPa).
#[test]
fn the_tension_bar_packings_give_their_own_t() {
    let out = thm(&["calibrate", "--only", "bar", "--packings", "tension-bar"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", text(&out.stderr));
    assert!(stdout.contains("tension-bar packing(s)"), "{stdout}");
    let t = calibrated(&stdout, "T [MPa]");
    assert!((t / 48.29 - 1.0).abs() < 5e-3, "{stdout}");
}
