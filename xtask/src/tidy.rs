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

/// Crates whose verification cases and reference solvers must compile only with their
/// feature `verification` (ARCHITECTURE.md, invariant 5).
const PHYSICS_CRATES: &[&str] = &[
    "thm-eos",
    "thm-dem",
    "thm-vpn-mesh",
    "thm-vpn-flow",
    "thm-fvm-heat",
    "thm-mpm",
    "thm-rve",
    "thm-coupling",
];

/// Module names that hold verification cases, their set-ups or reference solvers: declared in
/// a physics crate's `lib.rs` only under `#[cfg(feature = "verification")]`.
const VERIFICATION_MODULES: &[&str] = &["verification", "reference"];

/// Sibling modules that import each other and are one unit split for length; each of their
/// module docs says so ("one unit"). Every other import circle between sibling modules is a
/// tidy error (ARCHITECTURE.md, invariant 6).
const ONE_UNIT: &[(&str, &[&str])] = &[("thm-vpn-flow", &["implicit", "stepper"])];

/// The layers of `thm-scenarios`, bottom first: a module imports only modules before it
/// (ARCHITECTURE.md, invariant 7; the crate's module docs give the same list).
const SCENARIO_LAYERS: &[&str] = &[
    "error",
    "units",
    "eos_csv",
    "config",
    "arrays",
    "profiles",
    "pictures",
    "summary",
    "scenario",
    "rve_frames",
    "kinds",
    "registry",
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

/// The lines under `[dependencies]` of a manifest (not dev- or build-dependencies), comments
/// and blank lines left out.
fn normal_dependency_lines(manifest: &str) -> Vec<&str> {
    let mut lines = Vec::new();
    let mut in_deps = false;
    for line in manifest.lines() {
        let t = line.trim();
        if t.starts_with('[') {
            in_deps = t == "[dependencies]";
            continue;
        }
        if in_deps && !t.is_empty() && !t.starts_with('#') {
            lines.push(t);
        }
    }
    lines
}

/// Names listed under `[dependencies]` of a manifest (not dev- or build-dependencies).
fn normal_dependencies(manifest: &str) -> Vec<String> {
    normal_dependency_lines(manifest)
        .into_iter()
        .map(|t| {
            t.chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '_')
                .collect::<String>()
        })
        .filter(|n| !n.is_empty())
        .collect()
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

/// A crate's modules: path inside the crate (`["multiscale", "model"]`; the crate root is
/// `[]`) and file. Modules named `tests` are left out (test code may import anything).
fn crate_modules(src: &Path) -> BTreeMap<Vec<String>, PathBuf> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut out = BTreeMap::new();
    for f in files {
        let Ok(rel) = f.strip_prefix(src) else {
            continue;
        };
        let mut parts: Vec<String> = rel
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        if let Some(last) = parts.last_mut() {
            *last = last.trim_end_matches(".rs").to_string();
        }
        if parts
            .last()
            .is_some_and(|l| l == "mod" || l == "lib" || l == "main")
        {
            parts.pop();
        }
        if parts.iter().any(|p| p == "tests" || p == "bin") {
            continue;
        }
        out.insert(parts, f);
    }
    out
}

/// The code of a module file: comments and the `#[cfg(test)]` test module left out.
fn module_code(text: &str) -> String {
    let mut code = String::new();
    let mut lines = text.lines().peekable();
    while let Some(l) = lines.next() {
        let t = l.trim_start();
        if t.starts_with("#[cfg(test)]") && lines.peek().is_some_and(|n| n.contains("mod tests")) {
            break;
        }
        if t.starts_with("//") {
            continue;
        }
        code.push_str(l.split(" //").next().unwrap_or(""));
        code.push('\n');
    }
    code
}

/// The identifier at the start of `s` (letters, digits, `_`).
fn ident(s: &str) -> &str {
    let end = s
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(s.len());
    &s[..end]
}

/// The module paths a module's code names: `crate::a::b` as `[a, b]`, `super::x` from the
/// module `m` as `m`'s parent + `[x]`, and the first names of `crate::{...}` and
/// `super::{...}` groups.
fn referenced_paths(code: &str, module: &[String]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for (prefix, base) in [
        ("crate::", Vec::new()),
        ("super::", module[..module.len().saturating_sub(1)].to_vec()),
    ] {
        let mut rest = code;
        while let Some(i) = rest.find(prefix) {
            let before = rest[..i].chars().last();
            rest = &rest[i + prefix.len()..];
            if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':') {
                continue;
            }
            if let Some(group) = rest.strip_prefix('{') {
                // `crate::{a, b::c}`: the first name of each top-level entry.
                let mut depth = 0;
                let mut entry_start = true;
                for (k, c) in group.char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' if depth == 0 => break,
                        '}' => depth -= 1,
                        ',' if depth == 0 => entry_start = true,
                        c if entry_start && !c.is_whitespace() => {
                            entry_start = false;
                            let name = ident(&group[k..]);
                            if !name.is_empty() {
                                let mut p = base.clone();
                                p.push(name.to_string());
                                out.push(p);
                            }
                        }
                        _ => {}
                    }
                }
                continue;
            }
            let mut p = base.clone();
            let mut tail = rest;
            loop {
                let name = ident(tail);
                if name.is_empty() {
                    break;
                }
                p.push(name.to_string());
                match tail[name.len()..].strip_prefix("::") {
                    Some(t) => tail = t,
                    None => break,
                }
            }
            if p.len() > base.len() {
                out.push(p);
            }
        }
    }
    out
}

/// Imports between sibling modules: `m → s` where `m` names `s` (or an item inside it) and
/// both have the same parent.
fn sibling_imports(
    modules: &BTreeMap<Vec<String>, PathBuf>,
) -> BTreeMap<Vec<String>, Vec<Vec<String>>> {
    let mut edges: BTreeMap<Vec<String>, Vec<Vec<String>>> = BTreeMap::new();
    for (m, file) in modules {
        if m.is_empty() {
            continue;
        }
        let parent = &m[..m.len() - 1];
        let code = module_code(&read(file));
        for r in referenced_paths(&code, m) {
            if r.len() > parent.len() && r[..parent.len()] == *parent {
                let sibling = r[..=parent.len()].to_vec();
                if sibling != *m && modules.contains_key(&sibling) {
                    let list = edges.entry(m.clone()).or_default();
                    if !list.contains(&sibling) {
                        list.push(sibling);
                    }
                }
            }
        }
    }
    edges
}

/// The strongly connected components of more than one module (Tarjan), each sorted.
fn import_circles(edges: &BTreeMap<Vec<String>, Vec<Vec<String>>>) -> Vec<Vec<Vec<String>>> {
    struct Walk<'a> {
        edges: &'a BTreeMap<Vec<String>, Vec<Vec<String>>>,
        index: BTreeMap<Vec<String>, usize>,
        low: BTreeMap<Vec<String>, usize>,
        stack: Vec<Vec<String>>,
        circles: Vec<Vec<Vec<String>>>,
    }
    fn visit(w: &mut Walk<'_>, v: &Vec<String>) {
        let n = w.index.len();
        w.index.insert(v.clone(), n);
        w.low.insert(v.clone(), n);
        w.stack.push(v.clone());
        for t in w.edges.get(v).cloned().unwrap_or_default() {
            if !w.index.contains_key(&t) {
                visit(w, &t);
                let lt = w.low[&t];
                let lv = w.low.get_mut(v).expect("visited");
                *lv = (*lv).min(lt);
            } else if w.stack.contains(&t) {
                let it = w.index[&t];
                let lv = w.low.get_mut(v).expect("visited");
                *lv = (*lv).min(it);
            }
        }
        if w.low[v] == w.index[v] {
            let mut comp = Vec::new();
            while let Some(x) = w.stack.pop() {
                let done = x == *v;
                comp.push(x);
                if done {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                w.circles.push(comp);
            }
        }
    }
    let mut w = Walk {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        circles: Vec::new(),
    };
    for v in edges.keys() {
        if !w.index.contains_key(v) {
            visit(&mut w, v);
        }
    }
    w.circles
}

/// Invariants 5–7 for one crate: verification behind its feature, no import circle between
/// sibling modules but the documented units, and `thm-scenarios`' layers.
fn check_modules(name: &str, dir: &Path, manifest: &str, problems: &mut Vec<String>) {
    let src = dir.join("src");
    let modules = crate_modules(&src);

    // 5. Verification modules only under the feature, which the crate declares, with
    //    thm-verify optional.
    if PHYSICS_CRATES.contains(&name) {
        let lib = read(&src.join("lib.rs"));
        let lines: Vec<&str> = lib.lines().collect();
        for (i, l) in lines.iter().enumerate() {
            let t = l.trim();
            let declared = VERIFICATION_MODULES
                .iter()
                .find(|m| t == format!("pub mod {m};") || t == format!("mod {m};"));
            if let Some(m) = declared {
                let gated = i > 0 && lines[i - 1].trim() == "#[cfg(feature = \"verification\")]";
                if !gated {
                    problems.push(format!(
                        "crates/{name}/src/lib.rs:{}: module `{m}` must be declared under `#[cfg(feature = \"verification\")]`",
                        i + 1
                    ));
                }
            }
        }
        if !manifest.contains("\nverification = [") {
            problems.push(format!(
                "crates/{name}/Cargo.toml: needs a feature `verification` for its cases"
            ));
        }
        if normal_dependencies(manifest)
            .iter()
            .any(|d| d == "thm-verify")
            && !manifest.contains("thm-verify = { workspace = true, optional = true }")
        {
            problems.push(format!(
                "crates/{name}/Cargo.toml: `thm-verify` must be an optional dependency (enabled by `verification`)"
            ));
        }
    }

    // 6. No import circle between sibling modules, but the units named in ONE_UNIT, whose
    //    module docs say so.
    let edges = sibling_imports(&modules);
    for circle in import_circles(&edges) {
        let names: Vec<String> = circle.iter().map(|m| m.join("/")).collect();
        let documented = ONE_UNIT.iter().any(|(c, unit)| {
            *c == name
                && unit.len() == names.len()
                && names.iter().all(|n| unit.contains(&n.as_str()))
        });
        if !documented {
            problems.push(format!(
                "crates/{name}: modules {} import each other; move what both need below them, or \
                 list them in ONE_UNIT with a module doc that says why they are one unit",
                names.join(" <-> ")
            ));
        }
    }
    for (c, unit) in ONE_UNIT.iter().filter(|(c, _)| *c == name) {
        for m in *unit {
            let file = modules.get(&vec![(*m).to_string()]);
            let doc: String = file
                .map(|f| read(f))
                .unwrap_or_default()
                .lines()
                .take_while(|l| l.starts_with("//!"))
                .collect::<Vec<_>>()
                .join(" ")
                .to_lowercase();
            if !doc.contains("one unit") {
                problems.push(format!(
                    "crates/{c}/src/{m}.rs: listed in ONE_UNIT, so its module doc must say why it is one unit with its siblings"
                ));
            }
        }
    }

    // 7. The layers of thm-scenarios.
    if name == "thm-scenarios" {
        let layer = |m: &str| SCENARIO_LAYERS.iter().position(|l| *l == m);
        for (m, file) in &modules {
            let Some(top) = m.first() else {
                continue;
            };
            let Some(here) = layer(top) else {
                problems.push(format!(
                    "crates/thm-scenarios/src: module `{top}` is in no layer of SCENARIO_LAYERS"
                ));
                continue;
            };
            let code = module_code(&read(file));
            for r in referenced_paths(&code, m) {
                let target = if r.len() > 1 && m.len() > 1 && r[0] == m[0] {
                    continue;
                } else {
                    &r[0]
                };
                if let Some(there) = layer(target)
                    && there >= here
                    && target != top
                {
                    problems.push(format!(
                        "{}: `{top}` imports `{target}`, a layer above it (SCENARIO_LAYERS)",
                        file.strip_prefix(dir).unwrap_or(file).display()
                    ));
                }
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
        check_modules(name, dir, &manifest, &mut problems);
        // 8. No crate but xtask (and the benchmarks) builds another's verification cases.
        for line in normal_dependency_lines(&manifest) {
            if line.contains("features") && line.contains("\"verification\"") {
                problems.push(format!(
                    "crates/{name}/Cargo.toml: `{line}` enables verification cases outside xtask; \
                     tests enable them as dev-dependencies"
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
            "[dependencies]\nthm-dem.workspace = true\nspade.workspace = true\n\n[features]\nverification = []\n",
        )
        .unwrap();
        std::fs::write(c.join("lib.rs"), "pub fn f() {}\n").unwrap();
        let problems = check(&dir);
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!(problems.len(), 3, "{problems:?}");
    }

    /// A physics crate whose verification is in the default build, whose `a` and `b` import
    /// each other, and a dependent that builds its verification cases: four problems.
    #[test]
    fn tidy_flags_verification_in_the_default_build_and_an_import_circle() {
        let dir = std::env::temp_dir().join(format!("thm-tidy-modules-{}", std::process::id()));
        let c = dir.join("crates/thm-mpm/src");
        std::fs::create_dir_all(c.join("a")).unwrap();
        std::fs::write(
            dir.join("crates/thm-mpm/Cargo.toml"),
            "[dependencies]\nthm-verify.workspace = true\n\n[features]\nverification = []\n",
        )
        .unwrap();
        std::fs::write(
            c.join("lib.rs"),
            "//! doc\npub mod a;\npub mod b;\npub mod verification;\n",
        )
        .unwrap();
        // `a` (a folder module) names `b` through a group, `b` names an item of `a`.
        std::fs::write(c.join("a/mod.rs"), "use crate::{b::f, x};\npub fn g() {}\n").unwrap();
        std::fs::write(c.join("b.rs"), "pub fn f() { super::a::g() }\n").unwrap();
        std::fs::write(c.join("verification.rs"), "pub fn cases() {}\n").unwrap();
        let d = dir.join("crates/thm-other/src");
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(
            dir.join("crates/thm-other/Cargo.toml"),
            "[dependencies]\nthm-mpm = { workspace = true, features = [\"verification\"] }\n",
        )
        .unwrap();
        std::fs::write(d.join("lib.rs"), "//! doc\n").unwrap();
        let problems = check(&dir);
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!(problems.len(), 4, "{problems:?}");
        assert!(
            problems.iter().any(|p| p.contains("a <-> b")),
            "{problems:?}"
        );
        assert!(
            problems
                .iter()
                .any(|p| p.contains("`verification` must be declared")),
            "{problems:?}"
        );
        assert!(
            problems.iter().any(|p| p.contains("optional")),
            "{problems:?}"
        );
        assert!(
            problems
                .iter()
                .any(|p| p.contains("enables verification cases")),
            "{problems:?}"
        );
    }

    #[test]
    fn references_resolve_groups_and_super() {
        let m = vec!["x".to_string(), "y".to_string()];
        let refs = referenced_paths(
            "use crate::{a::b, c};\nlet v = super::z::w(); crate::d::e;\n",
            &m,
        );
        let want: Vec<Vec<String>> = [vec!["a"], vec!["c"], vec!["d", "e"], vec!["x", "z", "w"]]
            .iter()
            .map(|p| p.iter().map(|s| s.to_string()).collect())
            .collect();
        assert_eq!(refs, want);
    }
}
