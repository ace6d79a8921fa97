//! `cargo xtask tidy`: mechanical checks of the invariants stated in `docs/ARCHITECTURE.md`.
//! Also runs as a unit test, so `cargo test --workspace` enforces it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The workspace root (the parent of this crate's manifest directory).
pub fn workspace_root() -> PathBuf {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    here.parent().map(Path::to_path_buf).unwrap_or(here)
}

/// Workspace crates each crate may depend on (normal dependencies). A crate missing from this
/// table may depend on no workspace crate except `thm-verify`.
const ALLOWED_WORKSPACE_DEPS: &[(&str, &[&str])] = &[
    ("thm-verify", &[]),
    ("thm-io", &["thm-verify"]),
    ("thm-eos", &["thm-verify"]),
    ("thm-dem", &["thm-verify", "thm-io"]),
    ("thm-vpn-mesh", &["thm-verify", "thm-io"]),
    (
        "thm-vpn-flow",
        &["thm-verify", "thm-io", "thm-eos", "thm-vpn-mesh"],
    ),
    ("thm-fvm-heat", &["thm-verify", "thm-io", "thm-vpn-mesh"]),
    ("thm-mpm", &["thm-verify", "thm-io"]),
    ("thm-rve", &["thm-verify", "thm-io", "thm-dem"]),
];

/// External crates that only one workspace crate may use.
const EXCLUSIVE_EXTERNAL: &[(&str, &str)] = &[
    ("spade", "thm-vpn-mesh"),
    ("pyo3", "thm-py"),
    ("numpy", "thm-py"),
    ("mpi", "thm-cli"),
];

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_default()
}

/// Names listed under `[dependencies]` of a manifest (not dev- or build-dependencies).
fn normal_dependencies(manifest: &str) -> Vec<String> {
    let mut deps = Vec::new();
    let mut in_deps = false;
    for line in manifest.lines() {
        let t = line.trim();
        if t.starts_with('[') {
            in_deps = t == "[dependencies]";
            continue;
        }
        if in_deps && !t.is_empty() && !t.starts_with('#') {
            let name: String = t
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '_')
                .collect();
            if !name.is_empty() {
                deps.push(name);
            }
        }
    }
    deps
}

fn crate_dirs(root: &Path) -> BTreeMap<String, PathBuf> {
    let mut out = BTreeMap::new();
    if let Ok(entries) = std::fs::read_dir(root.join("crates")) {
        for e in entries.flatten() {
            let p = e.path();
            if p.join("Cargo.toml").is_file()
                && let Some(name) = p.file_name().and_then(|n| n.to_str())
            {
                out.insert(name.to_string(), p);
            }
        }
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                if p.file_name().is_some_and(|n| n == "target") {
                    continue;
                }
                rust_files(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
}

/// Runs every check and returns the problems found (empty when tidy).
pub fn check(root: &Path) -> Vec<String> {
    let mut problems = Vec::new();
    let crates = crate_dirs(root);
    let allowed: BTreeMap<&str, &[&str]> = ALLOWED_WORKSPACE_DEPS.iter().copied().collect();

    for (name, dir) in &crates {
        let manifest = read(&dir.join("Cargo.toml"));
        let deps = normal_dependencies(&manifest);

        // 1. Physics crates depend on each other only along the documented edges.
        if let Some(ok) = allowed.get(name.as_str()) {
            for d in deps.iter().filter(|d| d.starts_with("thm-")) {
                if !ok.contains(&d.as_str()) {
                    problems.push(format!(
                        "crates/{name}: depends on `{d}`, which ARCHITECTURE.md does not allow"
                    ));
                }
            }
        }
        // 2. Exclusive external dependencies.
        for (ext, owner) in EXCLUSIVE_EXTERNAL {
            if deps.iter().any(|d| d == ext) && name != owner {
                problems.push(format!(
                    "crates/{name}: depends on `{ext}`; only `{owner}` may"
                ));
            }
        }
        // 3. Each library opens with a module doc.
        let lib = dir.join("src/lib.rs");
        if lib.is_file() && !read(&lib).trim_start().starts_with("//!") {
            problems.push(format!(
                "crates/{name}/src/lib.rs: must open with a `//!` module doc"
            ));
        }
    }

    // 4. `unsafe` only with a SAFETY comment right above it.
    let mut files = Vec::new();
    for sub in ["crates", "xtask", "benchmarks"] {
        rust_files(&root.join(sub), &mut files);
    }
    for f in &files {
        if f.ends_with("tidy.rs") {
            continue;
        }
        let text = read(f);
        let lines: Vec<&str> = text.lines().collect();
        for (i, l) in lines.iter().enumerate() {
            let code = l.split("//").next().unwrap_or("");
            if code.contains("unsafe ") || code.contains("unsafe{") {
                let has_safety = lines[..i]
                    .iter()
                    .rev()
                    .take(6)
                    .any(|p| p.contains("SAFETY:"));
                if !has_safety {
                    problems.push(format!(
                        "{}:{}: `unsafe` without a `// SAFETY:` comment above it",
                        f.strip_prefix(root).unwrap_or(f).display(),
                        i + 1
                    ));
                }
            }
        }
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn workspace_is_tidy() {
        let problems = check(&workspace_root());
        assert!(
            problems.is_empty(),
            "tidy problems:\n{}",
            problems.join("\n")
        );
    }

    #[test]
    fn dependency_parser_reads_only_normal_dependencies() {
        let m = "[package]\nname = \"x\"\n[dependencies]\nspade.workspace = true\nthm-eos = { path = \"a\" }\n\n[dev-dependencies]\nproptest = \"1\"\n";
        assert_eq!(normal_dependencies(m), vec!["spade", "thm-eos"]);
    }

    #[test]
    fn tidy_flags_a_forbidden_edge() {
        let dir = std::env::temp_dir().join(format!("thm-tidy-{}", std::process::id()));
        let c = dir.join("crates/thm-eos/src");
        std::fs::create_dir_all(&c).unwrap();
        std::fs::write(
            dir.join("crates/thm-eos/Cargo.toml"),
            "[dependencies]\nthm-dem.workspace = true\nspade.workspace = true\n",
        )
        .unwrap();
        std::fs::write(c.join("lib.rs"), "pub fn f() {}\n").unwrap();
        let problems = check(&dir);
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!(problems.len(), 3, "{problems:?}");
    }
}
