//! A-Sect. 6 case a (Krzaczek et al. 2023) on several packings: `scenarios/bar_contraction_free.toml`
//! as it is shipped, with only `[bar] seed` changed, each run to its 17 s, and the crack and
//! fluid figures of every run in one Markdown table with the mean, the range and the paper's
//! value.
//!
//! `cargo run --release -p thm-benchmarks --bin case_a_ensemble -- [--seeds 1,2,3,4,5]
//! [--out DIR] [--doc FILE]`
//!
//! Each run goes into `DIR/seed_N` (default `DIR` = `runs/case_a_ensemble`). A run whose
//! summary says it finished is read, not rerun; one that stopped (or was stopped) continues
//! from its last complete checkpoint (written every 1 s of simulated time). With `--doc`, the
//! table replaces the lines between `<!-- case_a_ensemble begin -->` and
//! `<!-- case_a_ensemble end -->` of FILE. The wall time of each run is the one its summary
//! gives (that of the invocation that finished it).

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use thm_scenarios::scenario::Progress;
use thm_scenarios::{last_complete_checkpoint, run_file};

const SCENARIO: &str = "scenarios/bar_contraction_free.toml";
const BEGIN: &str = "<!-- case_a_ensemble begin -->";
const END: &str = "<!-- case_a_ensemble end -->";

/// A column of the table: the summary row, its heading, a scale and the paper's value.
struct Column {
    row: &'static str,
    heading: &'static str,
    scale: f64,
    digits: usize,
    paper: &'static str,
}

const COLUMNS: [Column; 12] = [
    col("broken_bonds", "broken bonds", 1.0, 0, "34"),
    col("cracks", "cracks", 1.0, 0, "1 (macro-crack)"),
    col(
        "broken_bonds_in_macro_crack_band",
        "bonds in the macro-crack",
        1.0,
        0,
        "5",
    ),
    col(
        "crack_height_over_bar_length",
        "crack height / L",
        1.0,
        3,
        "near the top edge",
    ),
    col("crack_inclination", "inclination [°]", 1.0, 1, "–"),
    col("crack_span_over_width", "span / W", 1.0, 2, "across"),
    col(
        "temperature_step_across_broken_bonds",
        "T step across [K]",
        1.0,
        1,
        "20.9",
    ),
    col(
        "lowest_pore_pressure",
        "lowest pressure [kPa]",
        1e-3,
        1,
        "11.6",
    ),
    col(
        "liquid_speed_at_end",
        "liquid speed at 17 s [m/s]",
        1.0,
        4,
        "0.0057",
    ),
    col("max_temperature", "T_max [K]", 1.0, 2, "328.1 / 333.44"),
    col("d50_initial", "d50 start [mm]", 1.0, 3, "6.032"),
    col("d50_final", "d50 end [mm]", 1.0, 3, "5.837"),
];

const fn col(
    row: &'static str,
    heading: &'static str,
    scale: f64,
    digits: usize,
    paper: &'static str,
) -> Column {
    Column {
        row,
        heading,
        scale,
        digits,
        paper,
    }
}

struct Args {
    seeds: Vec<u64>,
    out: PathBuf,
    doc: Option<PathBuf>,
}

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        seeds: (1..=5).collect(),
        out: PathBuf::from("runs/case_a_ensemble"),
        doc: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut value = || it.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--seeds" => {
                let list = value()?;
                args.seeds = list
                    .split(',')
                    .map(str::parse)
                    .collect::<Result<_, _>>()
                    .map_err(|e| {
                        format!("--seeds: comma-separated u64 seeds, got `{list}`: {e}")
                    })?;
            }
            "--out" => args.out = PathBuf::from(value()?),
            "--doc" => args.doc = Some(PathBuf::from(value()?)),
            other => {
                return Err(format!(
                    "unknown argument `{other}` (--seeds, --out, --doc)"
                ));
            }
        }
    }
    Ok(args)
}

/// The summary's figures (`| name | unit | measured | ...`) and its wall time.
struct Summary {
    finished: bool,
    wall: f64,
    rows: Vec<(String, f64)>,
}

fn read_summary(dir: &Path) -> Option<Summary> {
    let text = std::fs::read_to_string(dir.join("summary.md")).ok()?;
    let mut s = Summary {
        finished: text.lines().any(|l| l.trim() == "- finished"),
        wall: f64::NAN,
        rows: Vec::new(),
    };
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("- wall-clock time of this invocation: ") {
            s.wall = rest.trim_end_matches(" s").parse().unwrap_or(f64::NAN);
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() >= 5
            && let Ok(v) = cells[3].parse::<f64>()
        {
            s.rows.push((cells[1].to_string(), v));
        }
    }
    Some(s)
}

fn run_seed(seed: u64, out: &Path) -> Result<Summary, String> {
    let dir = out.join(format!("seed_{seed}"));
    if let Some(s) = read_summary(&dir).filter(|s| s.finished) {
        return Ok(s);
    }
    let text = std::fs::read_to_string(SCENARIO).map_err(|e| format!("{SCENARIO}: {e}"))?;
    let seeded = text.replacen("seed = 1 ", &format!("seed = {seed} "), 1);
    if seeded == text && seed != 1 {
        return Err(format!("{SCENARIO}: no `seed = 1` line to change"));
    }
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let file = out.join(format!("seed_{seed}.toml"));
    std::fs::write(&file, seeded).map_err(|e| format!("{}: {e}", file.display()))?;
    let resume = last_complete_checkpoint(&dir);
    if let Some(r) = &resume {
        eprintln!("seed {seed}: continuing from {}", r.display());
    }
    let interrupt = AtomicBool::new(false);
    run_file(&file, &dir, resume.as_deref(), &interrupt, Progress::Auto)
        .map_err(|e| format!("seed {seed}: {e}"))?;
    read_summary(&dir).filter(|s| s.finished).ok_or(format!(
        "seed {seed}: no finished summary in {}",
        dir.display()
    ))
}

fn table(seeds: &[u64], runs: &[Summary]) -> String {
    let mut t = String::new();
    let head: Vec<&str> = COLUMNS.iter().map(|c| c.heading).collect();
    t += &format!("| packing | wall [s] | {} |\n", head.join(" | "));
    t += &format!("|{}\n", " --- |".repeat(COLUMNS.len() + 2));
    let value = |r: &Summary, c: &Column| {
        r.rows
            .iter()
            .find(|(n, _)| n == c.row)
            .map_or(f64::NAN, |(_, v)| v * c.scale)
    };
    for (seed, r) in seeds.iter().zip(runs) {
        let cells: Vec<String> = COLUMNS
            .iter()
            .map(|c| format!("{:.*}", c.digits, value(r, c)))
            .collect();
        t += &format!("| seed {seed} | {:.0} | {} |\n", r.wall, cells.join(" | "));
    }
    let stats = |c: &Column| {
        let v: Vec<f64> = runs
            .iter()
            .map(|r| value(r, c))
            .filter(|v| v.is_finite())
            .collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        [mean, lo, hi]
    };
    let walls: Vec<f64> = runs.iter().map(|r| r.wall).collect();
    let wall_mean = walls.iter().sum::<f64>() / walls.len() as f64;
    let cells: Vec<String> = COLUMNS
        .iter()
        .map(|c| format!("{:.*}", c.digits, stats(c)[0]))
        .collect();
    t += &format!("| mean | {wall_mean:.0} | {} |\n", cells.join(" | "));
    let cells: Vec<String> = COLUMNS
        .iter()
        .map(|c| {
            let [_, lo, hi] = stats(c);
            format!("{lo:.*}–{hi:.*}", c.digits, c.digits)
        })
        .collect();
    let [wlo, whi] = [
        walls.iter().copied().fold(f64::INFINITY, f64::min),
        walls.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    ];
    t += &format!("| range | {wlo:.0}–{whi:.0} | {} |\n", cells.join(" | "));
    let paper: Vec<&str> = COLUMNS.iter().map(|c| c.paper).collect();
    t += &format!("| paper (A-Sect. 6) | ~1 day | {} |\n", paper.join(" | "));
    t
}

fn write_doc(doc: &Path, table: &str) -> Result<(), String> {
    let text = std::fs::read_to_string(doc).map_err(|e| format!("{}: {e}", doc.display()))?;
    let (Some(b), Some(e)) = (text.find(BEGIN), text.find(END)) else {
        return Err(format!("{}: no `{BEGIN}` … `{END}` lines", doc.display()));
    };
    if e < b {
        return Err(format!("{}: `{END}` before `{BEGIN}`", doc.display()));
    }
    let new = format!("{}{BEGIN}\n{table}{}", &text[..b], &text[e..]);
    std::fs::write(doc, new).map_err(|e| format!("{}: {e}", doc.display()))
}

fn main() {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let mut runs = Vec::new();
    for &seed in &args.seeds {
        match run_seed(seed, &args.out) {
            Ok(s) => runs.push(s),
            Err(e) => {
                eprintln!("error: {e}");
                std::process::exit(1);
            }
        }
    }
    let t = table(&args.seeds, &runs);
    print!("{t}");
    if let Some(doc) = &args.doc
        && let Err(e) = write_doc(doc, &t)
    {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
