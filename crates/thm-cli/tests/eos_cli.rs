//! `thm eos …` run as a user runs it: the built binary, CSV on stdin, CSV on stdout.

#[path = "../../thm-eos/tests/independent/mod.rs"]
mod independent;

use independent::Fluid;
use std::io::Write;
use std::process::{Command, Output, Stdio};

fn thm(args: &[&str], input: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_thm"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // A command that fails before reading its input (a usage error) closes the pipe: a
    // failed write is then expected and not an error of the test.
    let _ = child.stdin.take().unwrap().write_all(input.as_bytes());
    child.wait_with_output().unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).unwrap()
}

/// Data rows of a CSV output, split into fields (header checked and dropped).
fn rows(o: &Output, header: &str) -> Vec<Vec<String>> {
    let text = stdout(o);
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(header));
    lines
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect()
}

/// Significant digits of a number written in scientific notation.
fn significant_digits(field: &str) -> usize {
    let mantissa = field.split(['e', 'E']).next().unwrap();
    mantissa.chars().filter(char::is_ascii_digit).count()
}

const TEMPERATURES: [f64; 7] = [278.15, 300.0, 368.16, 450.0, 550.0, 650.0, 700.0];
const PRESSURES: [f64; 8] = [1e4, 1e5, 1e6, 5e6, 1e7, 2.5e7, 5e7, 7e7];

fn reference(fluid: &str, model: &str) -> Fluid {
    match (fluid, model) {
        ("air", _) => independent::AIR,
        ("water", "pr") => independent::WATER_PR,
        _ => independent::WATER_PR_CORRECTED,
    }
}

/// Density and pressure agree with the independent implementation to 1e-9 relative, for both
/// models, both fluids and both branches over 278–700 K and 0.01–70 MPa; every number has at
/// least 12 significant digits.
#[test]
fn density_and_pressure_agree_with_independent_implementation() {
    for model in ["pr", "pr-corrected"] {
        let mut input = String::from("fluid,T,P,branch\n");
        for fluid in ["water", "air"] {
            for t in TEMPERATURES {
                for p in PRESSURES {
                    for branch in ["liquid", "gas"] {
                        input += &format!("{fluid},{t},{p},{branch}\n");
                    }
                }
            }
        }
        let out = thm(&["eos", "density", "--model", model], &input);
        assert!(out.status.success(), "{}", stderr(&out));
        let density_rows = rows(&out, "fluid,T,P,branch,rho");
        assert_eq!(
            density_rows.len(),
            2 * TEMPERATURES.len() * PRESSURES.len() * 2
        );
        let mut pressure_input = String::from("fluid,T,rho\n");
        for r in &density_rows {
            let (t, p): (f64, f64) = (r[1].parse().unwrap(), r[2].parse().unwrap());
            let rho: f64 = r[4].parse().unwrap();
            assert!(significant_digits(&r[4]) >= 12, "{}", r[4]);
            let want = reference(&r[0], model).density(t, p, r[3] == "liquid");
            assert!(
                (rho / want - 1.0).abs() <= 1e-9,
                "{model} {r:?}: rho {rho} vs independent {want}"
            );
            pressure_input += &format!("{},{},{}\n", r[0], r[1], r[4]);
        }
        let out = thm(&["eos", "pressure", "--model", model], &pressure_input);
        assert!(out.status.success(), "{}", stderr(&out));
        for r in rows(&out, "fluid,T,rho,P") {
            let (t, rho, p): (f64, f64, f64) = (
                r[1].parse().unwrap(),
                r[2].parse().unwrap(),
                r[3].parse().unwrap(),
            );
            assert!(significant_digits(&r[3]) >= 12, "{}", r[3]);
            let want = reference(&r[0], model).pressure(t, rho);
            assert!(
                (p / want - 1.0).abs() <= 1e-9,
                "{model} {r:?}: P {p} vs {want}"
            );
        }
    }
}

/// The closure's α agrees to 1e-10 with pores built at known (T, P, α) from the independent
/// densities, and its pressure to 1e-9.
#[test]
fn closure_agrees_with_independent_implementation() {
    for model in ["pr", "pr-corrected"] {
        let water = reference("water", model);
        let mut input = String::from("T,V,m_liquid,m_gas\n");
        let mut expected = Vec::new();
        for t in [278.15, 300.0, 368.16, 450.0, 700.0] {
            for p in [1e4, 1e5, 1e6, 1e7, 7e7] {
                for alpha in [0.05, 0.5, 0.8, 0.95] {
                    let v = 2e-9;
                    let m_l = alpha * v * water.density(t, p, true);
                    let m_g = (1.0 - alpha) * v * independent::AIR.density(t, p, false);
                    input += &format!("{t},{v:e},{m_l:.17e},{m_g:.17e}\n");
                    expected.push((alpha, p));
                }
            }
        }
        let out = thm(&["eos", "closure", "--model", model], &input);
        assert!(out.status.success(), "{}", stderr(&out));
        let got = rows(&out, "T,V,m_liquid,m_gas,alpha,P,rho_liquid,rho_gas");
        assert_eq!(got.len(), expected.len());
        for (r, (alpha, p)) in got.iter().zip(expected) {
            let a: f64 = r[4].parse().unwrap();
            let pressure: f64 = r[5].parse().unwrap();
            assert!((4..8).all(|i| significant_digits(&r[i]) >= 12), "{r:?}");
            assert!(
                (a - alpha).abs() <= 1e-10,
                "{model} {r:?}: alpha {a} vs {alpha}"
            );
            assert!(
                (pressure / p - 1.0).abs() <= 1e-9,
                "{model} {r:?}: P vs {p}"
            );
        }
    }
}

/// The default model is the corrected one.
#[test]
fn default_model_is_pr_corrected() {
    let input = "fluid,T,P,branch\nwater,300,1e5,liquid\n";
    let default = stdout(&thm(&["eos", "density"], input));
    let corrected = stdout(&thm(&["eos", "density", "--model", "pr-corrected"], input));
    let plain = stdout(&thm(&["eos", "density", "--model", "pr"], input));
    assert_eq!(default, corrected);
    assert_ne!(default, plain);
}

/// Runs a command whose second data row is bad: exit non-zero, the first row written, the
/// error naming line 3 (row 2) and the column.
fn assert_row_error(args: &[&str], input: &str, column: &str) {
    let out = thm(args, input);
    assert!(!out.status.success(), "{args:?} should fail");
    let text = stdout(&out);
    assert_eq!(
        text.lines().count(),
        2,
        "header and first row stay written: {text}"
    );
    let err = stderr(&out);
    assert!(err.contains("line 3 (row 2)"), "{err}");
    assert!(err.contains(&format!("column `{column}`")), "{err}");
}

#[test]
fn malformed_number_names_row_and_column() {
    assert_row_error(
        &["eos", "pressure"],
        "fluid,T,rho\nwater,300,1000\nwater,300,abc\n",
        "rho",
    );
    assert_row_error(
        &["eos", "density"],
        "fluid,T,P,branch\nair,300,1e5,gas\nair,3x0,1e5,gas\n",
        "T",
    );
    assert_row_error(
        &["eos", "closure"],
        "T,V,m_liquid,m_gas\n300,1,700,1\n300,1,,1\n",
        "m_liquid",
    );
}

#[test]
fn unknown_fluid_and_branch_are_errors() {
    assert_row_error(
        &["eos", "pressure"],
        "fluid,T,rho\nair,300,1.2\nhelium,300,0.2\n",
        "fluid",
    );
    assert_row_error(
        &["eos", "density"],
        "fluid,T,P,branch\nair,300,1e5,gas\nair,300,1e5,vapour\n",
        "branch",
    );
}

#[test]
fn wrong_column_count_is_an_error() {
    assert_row_error(
        &["eos", "pressure"],
        "fluid,T,rho\nair,300,1.2\nair,300\n",
        "rho",
    );
    assert_row_error(
        &["eos", "closure"],
        "T,V,m_liquid,m_gas\n300,1,700,1\n300,1,700,1,5\n",
        "(extra)",
    );
}

#[test]
fn states_without_physical_solution_are_errors() {
    // Denser than the co-volume allows.
    assert_row_error(
        &["eos", "pressure"],
        "fluid,T,rho\nwater,300,1000\nwater,300,2000\n",
        "rho",
    );
    // Non-positive pressure, non-positive temperature.
    assert_row_error(
        &["eos", "density"],
        "fluid,T,P,branch\nwater,300,1e5,liquid\nwater,300,-1,liquid\n",
        "P",
    );
    assert_row_error(
        &["eos", "density"],
        "fluid,T,P,branch\nwater,300,1e5,liquid\nwater,0,1e5,liquid\n",
        "T",
    );
    // A pore whose phases do not fit, an empty pore, a negative mass, a zero volume.
    let ok = "T,V,m_liquid,m_gas\n300,1,700,1\n";
    assert_row_error(
        &["eos", "closure"],
        &format!("{ok}300,1,1200,1\n"),
        "T,V,m_liquid,m_gas",
    );
    assert_row_error(
        &["eos", "closure"],
        &format!("{ok}300,1,0,0\n"),
        "T,V,m_liquid,m_gas",
    );
    assert_row_error(&["eos", "closure"], &format!("{ok}300,1,700,-1\n"), "m_gas");
    assert_row_error(&["eos", "closure"], &format!("{ok}300,0,700,1\n"), "V");
}

#[test]
fn bad_header_is_an_error() {
    let out = thm(&["eos", "pressure"], "fluid,T,density\nwater,300,1000\n");
    assert!(!out.status.success());
    assert_eq!(stdout(&out), "");
    let err = stderr(&out);
    assert!(
        err.contains("line 1 (header)") && err.contains("column `density`"),
        "{err}"
    );
    let out = thm(&["eos", "closure"], "");
    assert!(!out.status.success());
    assert!(stderr(&out).contains("missing header"));
}

#[test]
fn unknown_model_is_a_usage_error() {
    let out = thm(&["eos", "pressure", "--model", "srk"], "fluid,T,rho\n");
    assert!(!out.status.success());
    assert!(stderr(&out).contains("srk"));
}

/// Blank lines are skipped; input fields are echoed as given; fluid and branch names are
/// case-insensitive and echoed in lower case.
#[test]
fn echo_and_blank_lines() {
    let out = thm(
        &["eos", "density"],
        "fluid,T,P,branch\n\nWater, 300 ,1e5,LIQUID\n\n",
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let r = rows(&out, "fluid,T,P,branch,rho");
    assert_eq!(r.len(), 1);
    assert_eq!(&r[0][..4], ["water", "300", "1e5", "liquid"]);
}
