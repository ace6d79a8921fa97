//! Developer tasks for the THM workspace.
//!
//! - `cargo xtask verify [--quick] [--case NAME]... [--list]`: runs every registered
//!   verification case of every crate, prints the table (case, quantity, measured, reference,
//!   error, tolerance, pass), writes it as Markdown and CSV under `target/verify/`, writes each
//!   case's plots through `thm-io` as `target/verify/<case>/<plot>.png` and `.csv`, and a
//!   `report.md` showing each case's plots next to its table rows; exits non-zero if any case
//!   fails or errors or a plot cannot be drawn.
//! - `cargo xtask tidy`: checks the architecture invariants of `docs/ARCHITECTURE.md` (also run
//!   by `cargo test -p xtask`).

mod tidy;
mod verify;

use std::process::ExitCode;

fn usage() -> &'static str {
    "usage:\n  cargo xtask verify [--quick] [--case NAME]... [--list] [--out DIR]\n  cargo xtask tidy [ROOT]\n"
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("verify") => match verify::Options::parse(&args[1..]) {
            Ok(opts) => verify::run(&opts),
            Err(msg) => {
                eprintln!("error: {msg}\n{}", usage());
                ExitCode::from(2)
            }
        },
        Some("tidy") => {
            // An optional workspace root (another checkout); this one by default.
            let root = args
                .get(1)
                .map(std::path::PathBuf::from)
                .unwrap_or_else(tidy::workspace_root);
            let problems = tidy::check(&root);
            if problems.is_empty() {
                println!("tidy: ok");
                ExitCode::SUCCESS
            } else {
                for p in &problems {
                    eprintln!("tidy: {p}");
                }
                ExitCode::FAILURE
            }
        }
        _ => {
            eprint!("{}", usage());
            ExitCode::from(2)
        }
    }
}
