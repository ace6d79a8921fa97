//! `cargo xtask verify`: run the registered cases, print and write the table.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use thm_verify::{Case, CaseOutput, ErrorKind, Plot, Row};

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
        ErrorKind::Reported => "reported (paper figure)".to_string(),
    }
}

/// A Markdown table cell: pipes escaped, on one line.
fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A plot written for the report: its title and the PNG/CSV paths relative to the output folder.
struct WrittenPlot {
    title: String,
    png: String,
    csv: String,
}

/// Writes each plot of a case as `<out>/<case>/<plot>.png` and `.csv` through `thm-io`.
fn write_case_plots(out_dir: &Path, case: &str, plots: &[Plot]) -> (Vec<WrittenPlot>, Vec<String>) {
    let mut written = Vec::new();
    let mut errors = Vec::new();
    if plots.is_empty() {
        return (written, errors);
    }
    let dir = out_dir.join(case);
    if let Err(e) = std::fs::create_dir_all(&dir) {
        errors.push(format!("cannot create {}: {e}", dir.display()));
        return (written, errors);
    }
    for plot in plots {
        let png = format!("{case}/{}.png", plot.name);
        let csv = format!("{case}/{}.csv", plot.name);
        let result = thm_io::write_plot_png(plot, &out_dir.join(&png))
            .and_then(|()| thm_io::write_plot_csv(plot, &out_dir.join(&csv)));
        match result {
            Ok(()) => written.push(WrittenPlot {
                title: plot.title.clone(),
                png,
                csv,
            }),
            Err(e) => errors.push(format!("plot `{}`: {e}", plot.name)),
        }
    }
    (written, errors)
}

/// `report.md`: for each case, its description, table rows, plots and notes together.
fn report_md(
    header: &[&str],
    table: &[[String; 8]],
    outcomes: &[Outcome],
    plots: &[(Vec<WrittenPlot>, Vec<String>)],
) -> String {
    let mut md = String::from("# Verification report\n\n");
    let n_fail = table.iter().filter(|r| r[7] == "FAIL").count();
    let _ = writeln!(
        md,
        "{} cases, {} rows: {} passed, {} failed.\n",
        outcomes.len(),
        table.len(),
        table.len() - n_fail,
        n_fail
    );
    for (o, (written, errors)) in outcomes.iter().zip(plots) {
        let _ = writeln!(
            md,
            "## `{}`\n\n{} ({:.2} s)\n",
            o.case.name, o.case.description, o.seconds
        );
        let _ = writeln!(md, "| {} |", header[1..].join(" | "));
        let _ = writeln!(md, "|{}", "---|".repeat(header.len() - 1));
        for row in table.iter().filter(|r| r[0] == o.case.name) {
            let cells: Vec<String> = row[1..].iter().map(|c| md_cell(c)).collect();
            let _ = writeln!(md, "| {} |", cells.join(" | "));
        }
        md.push('\n');
        for p in written {
            let _ = writeln!(md, "![{}]({})\n\n[data]({})\n", p.title, p.png, p.csv);
        }
        for e in errors {
            let _ = writeln!(md, "- **plot error**: {e}");
        }
        if let Ok(out) = &o.result {
            for n in &out.notes {
                let _ = writeln!(md, "- {n}");
            }
        }
        md.push('\n');
    }
    md
}

pub fn workspace_target() -> PathBuf {
    crate::tidy::workspace_root().join("target")
}

/// Where a worker leaves a case's result and its wall time.
type Slot = std::sync::Mutex<Option<(Result<CaseOutput, String>, f64)>>;

fn run_case(case: &Case) -> Result<CaseOutput, String> {
    std::panic::catch_unwind(case.run)
        .map_err(|p| {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            format!("panicked: {msg}")
        })
        .and_then(|r| r.map_err(|e| e.to_string()))
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

    // Cases are independent: run them on as many workers as the machine has cores, longest
    // first is not known in advance, so workers take the next case from a shared index. The
    // report keeps the registration order whatever the finishing order.
    let workers = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
        .min(cases.len());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let slots: Vec<Slot> = cases.iter().map(|_| std::sync::Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(case) = cases.get(i) else { break };
                    eprintln!("verify: running {} ...", case.name);
                    let t0 = Instant::now();
                    let result = run_case(case);
                    if let Ok(mut slot) = slots[i].lock() {
                        *slot = Some((result, t0.elapsed().as_secs_f64()));
                    }
                }
            });
        }
    });
    let mut outcomes = Vec::new();
    for (case, slot) in cases.into_iter().zip(slots) {
        let (result, seconds) = slot
            .into_inner()
            .ok()
            .flatten()
            .unwrap_or_else(|| (Err("case did not report".to_string()), 0.0));
        outcomes.push(Outcome {
            case,
            result,
            seconds,
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
        let cells: Vec<String> = row.iter().map(|c| md_cell(c)).collect();
        let _ = writeln!(md, "| {} |", cells.join(" | "));
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
    // Plots (PNG + CSV per plot) and the report that shows them next to their rows.
    let plots: Vec<(Vec<WrittenPlot>, Vec<String>)> = outcomes
        .iter()
        .map(|o| match &o.result {
            Ok(out) => write_case_plots(&out_dir, o.case.name, &out.plots),
            Err(_) => (Vec::new(), Vec::new()),
        })
        .collect();
    for (o, (_, errors)) in outcomes.iter().zip(&plots) {
        for e in errors {
            all_pass = false;
            eprintln!("verify: {}: {e}", o.case.name);
        }
    }
    let report = report_md(&header, &table, &outcomes, &plots);
    let written = written.and_then(|_| std::fs::write(out_dir.join("report.md"), &report));
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

#[cfg(test)]
mod tests {
    use super::*;
    use thm_verify::{Series, SeriesRole};

    #[test]
    fn case_names_are_unique_and_prefixed_by_their_crate() {
        let cases = all_cases();
        let mut names: Vec<&str> = cases.iter().map(|c| c.name).collect();
        for n in &names {
            let (prefix, rest) = n
                .split_once('/')
                .unwrap_or_else(|| panic!("case `{n}` must be named `crate/short_name`"));
            assert!(!prefix.is_empty() && !rest.is_empty(), "case `{n}`");
        }
        names.sort_unstable();
        let before = names.len();
        names.dedup();
        assert_eq!(before, names.len(), "duplicate case names");
    }

    #[test]
    fn options_parse_and_select() {
        let args: Vec<String> = ["--quick", "--case", "eos/"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let o = Options::parse(&args).unwrap();
        assert!(o.quick && o.filters == ["eos/"]);
        assert!(Options::parse(&["--bogus".to_string()]).is_err());
        assert!(Options::parse(&["--case".to_string()]).is_err());
    }

    #[test]
    fn a_case_plot_is_written_as_non_empty_png_and_csv_and_linked_from_the_report() {
        let out = std::env::temp_dir().join(format!("xtask-verify-plot-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&out);
        let x: Vec<f64> = (0..10).map(f64::from).collect();
        let plot = Plot {
            name: "line".into(),
            title: "y = 2x".into(),
            x_label: "x [m]".into(),
            y_label: "y [m]".into(),
            series: vec![
                Series {
                    label: "reference".into(),
                    role: SeriesRole::Reference,
                    x: x.clone(),
                    y: x.iter().map(|v| 2.0 * v).collect(),
                },
                Series {
                    label: "measured".into(),
                    role: SeriesRole::Measured,
                    x: x.clone(),
                    y: x.iter().map(|v| 2.0 * v + 0.1).collect(),
                },
            ],
        };
        let (written, errors) = write_case_plots(&out, "demo/case", std::slice::from_ref(&plot));
        assert!(errors.is_empty(), "{errors:?}");
        assert_eq!(written.len(), 1);
        let png = std::fs::read(out.join(&written[0].png)).unwrap();
        assert!(
            png.len() > 1000 && png.starts_with(b"\x89PNG"),
            "{} bytes",
            png.len()
        );
        let csv = std::fs::read_to_string(out.join(&written[0].csv)).unwrap();
        assert_eq!(csv.lines().count(), 1 + 2 * x.len());

        fn run_ok() -> Result<CaseOutput, thm_verify::CaseError> {
            Ok(CaseOutput::default())
        }
        let outcome = Outcome {
            case: Case {
                name: "demo/case",
                description: "a demo",
                quick: true,
                run: run_ok,
            },
            result: Ok(CaseOutput::default()),
            seconds: 0.0,
        };
        let row: [String; 8] =
            ["demo/case", "y(1)", "m", "2.1", "2", "0.1", "≤ 0.2", "pass"].map(String::from);
        let md = report_md(
            &[
                "case",
                "quantity",
                "unit",
                "measured",
                "reference",
                "error",
                "tolerance",
                "pass",
            ],
            &[row],
            &[outcome],
            &[(written, errors)],
        );
        assert!(md.contains("![y = 2x](demo/case/line.png)"), "{md}");
        assert!(md.contains("| y(1) | m | 2.1 |"), "{md}");
        assert_eq!(md_cell("max |T| a\nb"), "max \\|T\\| a b");
        std::fs::remove_dir_all(&out).unwrap();
    }
}
