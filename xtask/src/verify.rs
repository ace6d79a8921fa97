//! `cargo xtask verify`: run the registered cases, print and write the table.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use thm_verify::{Case, CaseOutput, ErrorKind, Row};

/// Every crate registers its own cases; this list only collects them.
pub fn all_cases() -> Vec<Case> {
    let mut cases = Vec::new();
    cases.extend(thm_eos::verification::cases());
    cases.extend(thm_dem::verification::cases());
    cases.extend(thm_vpn_mesh::verification::cases());
    cases.extend(thm_vpn_flow::verification::cases());
    cases.extend(thm_fvm_heat::verification::cases());
    cases.extend(thm_mpm::verification::cases());
    cases.extend(thm_rve::verification::cases());
    cases.extend(thm_coupling::verification::cases());
    cases
}

#[derive(Debug, Default)]
pub struct Options {
    pub quick: bool,
    pub list: bool,
    pub filters: Vec<String>,
    pub out: Option<PathBuf>,
}

impl Options {
    pub fn parse(args: &[String]) -> Result<Self, String> {
        let mut o = Options::default();
        let mut it = args.iter();
        while let Some(a) = it.next() {
            match a.as_str() {
                "--quick" => o.quick = true,
                "--list" => o.list = true,
                "--case" => o.filters.push(
                    it.next()
                        .ok_or_else(|| "--case needs a NAME".to_string())?
                        .clone(),
                ),
                "--out" => {
                    o.out = Some(PathBuf::from(
                        it.next().ok_or_else(|| "--out needs a DIR".to_string())?,
                    ))
                }
                other => return Err(format!("unknown argument `{other}`")),
            }
        }
        Ok(o)
    }

    fn selects(&self, case: &Case) -> bool {
        (!self.quick || case.quick)
            && (self.filters.is_empty() || self.filters.iter().any(|f| case.name.contains(f)))
    }
}

struct Outcome {
    case: Case,
    result: Result<CaseOutput, String>,
    seconds: f64,
}

fn fmt_num(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if !x.is_finite() {
        format!("{x}")
    } else if x.abs() >= 1e-3 && x.abs() < 1e6 {
        let s = format!("{x:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{x:.4e}")
    }
}

fn fmt_tol(r: &Row) -> String {
    match r.kind {
        ErrorKind::Absolute => format!("≤ {}", fmt_num(r.tolerance)),
        ErrorKind::Relative => format!("≤ {} rel", fmt_num(r.tolerance)),
        ErrorKind::AtMost => format!("≤ {} (bound)", fmt_num(r.reference)),
        ErrorKind::AtLeast => format!("≥ {} (bound)", fmt_num(r.reference)),
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

pub fn workspace_target() -> PathBuf {
    crate::tidy::workspace_root().join("target")
}

pub fn run(opts: &Options) -> ExitCode {
    let cases: Vec<Case> = all_cases()
        .into_iter()
        .filter(|c| opts.selects(c))
        .collect();
    if opts.list {
        for c in &cases {
            println!(
                "{:<40} {}{}",
                c.name,
                c.description,
                if c.quick { " [quick]" } else { "" }
            );
        }
        return ExitCode::SUCCESS;
    }
    if cases.is_empty() {
        eprintln!("verify: no case matches the selection");
        return ExitCode::FAILURE;
    }
    let out_dir = opts
        .out
        .clone()
        .unwrap_or_else(|| workspace_target().join("verify"));

    let mut outcomes = Vec::new();
    for case in cases {
        eprintln!("verify: running {} ...", case.name);
        let t0 = Instant::now();
        let result = std::panic::catch_unwind(case.run)
            .map_err(|p| {
                let msg = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                format!("panicked: {msg}")
            })
            .and_then(|r| r.map_err(|e| e.to_string()));
        outcomes.push(Outcome {
            case,
            result,
            seconds: t0.elapsed().as_secs_f64(),
        });
    }

    // Table.
    let header = [
        "case",
        "quantity",
        "unit",
        "measured",
        "reference",
        "error",
        "tolerance",
        "pass",
    ];
    let mut table: Vec<[String; 8]> = Vec::new();
    let mut all_pass = true;
    for o in &outcomes {
        match &o.result {
            Ok(out) => {
                if out.rows.is_empty() {
                    all_pass = false;
                    table.push([
                        o.case.name.into(),
                        "(no rows)".into(),
                        String::new(),
                        String::new(),
                        String::new(),
                        String::new(),
                        String::new(),
                        "FAIL".into(),
                    ]);
                }
                for r in &out.rows {
                    all_pass &= r.pass;
                    table.push([
                        o.case.name.into(),
                        r.quantity.clone(),
                        r.unit.clone(),
                        fmt_num(r.measured),
                        fmt_num(r.reference),
                        fmt_num(r.error),
                        fmt_tol(r),
                        if r.pass { "pass" } else { "FAIL" }.into(),
                    ]);
                }
            }
            Err(e) => {
                all_pass = false;
                table.push([
                    o.case.name.into(),
                    format!("error: {e}"),
                    String::new(),
                    String::new(),
                    String::new(),
                    String::new(),
                    String::new(),
                    "FAIL".into(),
                ]);
            }
        }
    }

    // Console.
    let mut widths = header.map(str::len);
    for row in &table {
        for (w, c) in widths.iter_mut().zip(row) {
            *w = (*w).max(c.chars().count());
        }
    }
    let line = |cells: &[String]| {
        let mut s = String::new();
        for (c, w) in cells.iter().zip(widths) {
            let pad = w.saturating_sub(c.chars().count());
            let _ = write!(s, "{c}{}  ", " ".repeat(pad));
        }
        s.trim_end().to_string()
    };
    let head: Vec<String> = header.iter().map(|s| s.to_string()).collect();
    println!("{}", line(&head));
    for row in &table {
        println!("{}", line(row));
    }

    // Markdown and CSV.
    let mut md = String::from("# Verification\n\n");
    let _ = writeln!(md, "| {} |", header.join(" | "));
    let _ = writeln!(md, "|{}", "---|".repeat(header.len()));
    for row in &table {
        let _ = writeln!(md, "| {} |", row.join(" | ").replace('\n', " "));
    }
    md.push_str("\n## Cases\n\n");
    for o in &outcomes {
        let _ = writeln!(
            md,
            "### `{}`\n\n{} ({:.2} s)\n",
            o.case.name, o.case.description, o.seconds
        );
        if let Ok(out) = &o.result {
            for n in &out.notes {
                let _ = writeln!(md, "- {n}");
            }
            md.push('\n');
        }
    }
    let mut csv = header.join(",");
    csv.push('\n');
    for row in &table {
        let cells: Vec<String> = row.iter().map(|c| csv_field(c)).collect();
        csv.push_str(&cells.join(","));
        csv.push('\n');
    }
    let written = std::fs::create_dir_all(&out_dir)
        .and_then(|_| std::fs::write(out_dir.join("verify.md"), &md))
        .and_then(|_| std::fs::write(out_dir.join("verify.csv"), &csv));
    match written {
        Ok(()) => eprintln!("verify: table written to {}", out_dir.display()),
        Err(e) => {
            eprintln!("verify: cannot write {}: {e}", out_dir.display());
            return ExitCode::FAILURE;
        }
    }

    let n_fail = table.iter().filter(|r| r[7] == "FAIL").count();
    println!("\n{} cases, {} rows", outcomes.len(), table.len());
    println!("verify: {} passed, {} failed", table.len() - n_fail, n_fail);
    if all_pass {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}
