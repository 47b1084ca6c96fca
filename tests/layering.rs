//! One-way layering of the library's source files, read from the `use` lines under `src/`.
//!
//! Every file of the library (not the `tread` binary's `main.rs`) is a node; a `use crate::…`,
//! `use super::…`, `use self::…` or child-module `use name::…` line, and a `crate::…`,
//! `super::…` or `self::…` path written inline in code, is an edge to the file that defines the item. A name a `mod.rs`
//! re-exports (`pub use child::Item`) is followed to the child that defines it, and a module's
//! own re-exports of its descendants are its façade, not a dependency. Comments and
//! `#[cfg(test)] mod … { … }` blocks are ignored (test code may reach anywhere).
//!
//! The rules: no cycle between files; nothing in `solver/` imports from `io/` (the solvers
//! report to their own observer trait, which the recorder implements); nothing below the
//! application face `app.rs` imports it (the drivers are called by the face, never the reverse);
//! nothing in `setup.rs`, `model/` or `io/` imports from `driver/` (the scene holds the
//! integrators' names and declarations from `solver::integrators`, the drivers implement them).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Source files by path relative to `src/` (e.g. `driver/steady.rs`).
type Sources = BTreeMap<String, String>;
/// File → files it imports from.
type Graph = BTreeMap<String, BTreeSet<String>>;

fn read_sources(dir: &Path, rel: &str, out: &mut Sources) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        let r = if rel.is_empty() {
            name.clone()
        } else {
            format!("{rel}/{name}")
        };
        if p.is_dir() {
            if r != "bin" {
                read_sources(&p, &r, out);
            }
        } else if name.ends_with(".rs") && r != "main.rs" {
            out.insert(r, std::fs::read_to_string(&p).expect("readable source"));
        }
    }
}

/// Module path of a file: `driver/steady.rs` → [driver, steady]; `io/record/mod.rs` → [io,
/// record]; `lib.rs` → [].
fn module_of(file: &str) -> Vec<String> {
    let stem = file.trim_end_matches(".rs");
    let mut parts: Vec<String> = stem.split('/').map(str::to_string).collect();
    if parts.last().is_some_and(|p| p == "mod") || parts == ["lib"] {
        parts.pop();
    }
    parts
}

/// The code without comments and without `#[cfg(test)] mod … { … }` blocks.
fn strip(src: &str) -> String {
    let lines: Vec<&str> = src.lines().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < lines.len() {
        let next_is_mod = lines.get(i + 1).is_some_and(|l| {
            let t = l.trim_start();
            (t.starts_with("mod ") || t.starts_with("pub mod ")) && t.ends_with('{')
        });
        if lines[i].trim() == "#[cfg(test)]" && next_is_mod {
            let mut depth = 0i64;
            i += 1;
            while i < lines.len() {
                depth +=
                    lines[i].matches('{').count() as i64 - lines[i].matches('}').count() as i64;
                i += 1;
                if depth <= 0 {
                    break;
                }
            }
            continue;
        }
        let code = match lines[i].find("//") {
            Some(k) => &lines[i][..k],
            None => lines[i],
        };
        out.push_str(code);
        out.push('\n');
        i += 1;
    }
    out
}

/// Split `a, b::{c, d}, e` at top-level commas.
fn split_top(s: &str) -> Vec<&str> {
    let (mut depth, mut start, mut out) = (0, 0, Vec::new());
    for (k, ch) in s.char_indices() {
        match ch {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                out.push(&s[start..k]);
                start = k + 1;
            }
            _ => {}
        }
    }
    out.push(&s[start..]);
    out
}

/// The paths of a use tree, each with the name it is bound to (its alias or last segment).
fn expand(prefix: &[String], tree: &str, out: &mut Vec<(Vec<String>, Option<String>)>) {
    let tree = tree.trim();
    if tree.is_empty() {
        return;
    }
    if let Some(inner) = tree.strip_prefix('{').and_then(|t| t.strip_suffix('}')) {
        for part in split_top(inner) {
            expand(prefix, part, out);
        }
        return;
    }
    if let Some(k) = tree.find("::{") {
        let mut p = prefix.to_vec();
        p.extend(tree[..k].split("::").map(|s| s.trim().to_string()));
        expand(&p, &tree[k + 2..], out);
        return;
    }
    let (path, alias) = match tree.split_once(" as ") {
        Some((p, a)) => (p.trim(), Some(a.trim().to_string())),
        None => (tree, None),
    };
    let mut p = prefix.to_vec();
    p.extend(
        path.split("::")
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty()),
    );
    if p.last().is_some_and(|s| s == "self") {
        p.pop();
    }
    out.push((p, alias));
}

struct Parsed {
    /// (is a `pub use`, absolute module path of the item) per import of the file.
    uses: Vec<(bool, Vec<String>)>,
    /// Names the file re-exports, with the absolute path they stand for.
    reexports: BTreeMap<String, Vec<String>>,
}

fn parse(file: &str, src: &str, modules: &BTreeSet<Vec<String>>) -> Parsed {
    let module = module_of(file);
    let code = strip(src);
    let absolute = |p: &[String]| -> Option<Vec<String>> {
        let first = p.first()?;
        match first.as_str() {
            "crate" => Some(p[1..].to_vec()),
            "super" => {
                let mut base = module.clone();
                let mut rest = p;
                while rest.first().is_some_and(|s| s == "super") {
                    base.pop();
                    rest = &rest[1..];
                }
                base.extend_from_slice(rest);
                Some(base)
            }
            "self" => {
                let mut base = module.clone();
                base.extend_from_slice(&p[1..]);
                Some(base)
            }
            _ => {
                // `use child::Item` in a module with that child.
                let mut base = module.clone();
                base.push(first.clone());
                modules.contains(&base).then(|| {
                    let mut b = module.clone();
                    b.extend_from_slice(p);
                    b
                })
            }
        }
    };
    let mut uses = Vec::new();
    let mut reexports = BTreeMap::new();
    // `use` statements (possibly over several lines).
    let mut rest = code.as_str();
    while let Some(k) = rest.find("use ") {
        let before = &rest[..k];
        let at_word = before
            .chars()
            .last()
            .is_none_or(|c| c.is_whitespace() || c == ';' || c == '{' || c == '}');
        let line_head = before.rsplit('\n').next().unwrap_or("").trim();
        let is_pub = line_head.starts_with("pub");
        let after = &rest[k + 4..];
        let Some(end) = after.find(';') else { break };
        if at_word && (line_head.is_empty() || line_head.starts_with("pub")) {
            let mut trees = Vec::new();
            expand(&[], &after[..end], &mut trees);
            for (p, alias) in trees {
                if p.last().is_some_and(|s| s == "*") {
                    let mut q = p.clone();
                    q.pop();
                    if let Some(a) = absolute(&q) {
                        uses.push((is_pub, a));
                    }
                    continue;
                }
                if let Some(a) = absolute(&p) {
                    if is_pub {
                        if let Some(name) = alias.or_else(|| a.last().cloned()) {
                            reexports.insert(name, a.clone());
                        }
                    }
                    uses.push((is_pub, a));
                }
            }
            rest = &after[end + 1..];
        } else {
            rest = after;
        }
    }
    // Inline `crate::a::b`, `super::a::b` and `self::a::b` paths.
    let bytes = code.as_bytes();
    for head in ["crate::", "super::", "self::"] {
        let mut from = 0;
        while let Some(k) = code[from..].find(head) {
            let at = from + k;
            let prev = at.checked_sub(1).map(|j| bytes[j] as char);
            from = at + head.len();
            if prev.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                continue;
            }
            let tail: String = code[at..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
                .collect();
            let path: Vec<String> = tail
                .split("::")
                .filter(|s| !s.is_empty())
                .map(str::to_string)
                .collect();
            if let Some(a) = absolute(&path) {
                if !a.is_empty() {
                    uses.push((false, a));
                }
            }
        }
    }
    Parsed { uses, reexports }
}

/// The import graph of a source tree.
fn graph(sources: &Sources) -> Graph {
    let files: BTreeMap<Vec<String>, String> =
        sources.keys().map(|f| (module_of(f), f.clone())).collect();
    let modules: BTreeSet<Vec<String>> = files.keys().cloned().collect();
    let parsed: BTreeMap<&String, Parsed> = sources
        .iter()
        .map(|(f, s)| (f, parse(f, s, &modules)))
        .collect();
    // The file defining `path`: the longest module prefix, then through its re-exports.
    let resolve = |path: &[String]| -> Option<String> {
        let mut path = path.to_vec();
        for _ in 0..16 {
            let n = (0..=path.len())
                .rev()
                .find(|&n| files.contains_key(&path[..n]))?;
            let file = &files[&path[..n]];
            let rest = &path[n..];
            match rest
                .first()
                .and_then(|name| parsed[file].reexports.get(name))
            {
                Some(target) if *target != path => {
                    let mut t = target.clone();
                    t.extend_from_slice(&rest[1..]);
                    path = t;
                }
                _ => return Some(file.clone()),
            }
        }
        None
    };
    let mut g = Graph::new();
    for (file, p) in &parsed {
        let module = module_of(file);
        let facade = file.ends_with("mod.rs") || file.as_str() == "lib.rs";
        let targets = g.entry((*file).clone()).or_default();
        for (is_pub, path) in &p.uses {
            let descendant = path.len() > module.len() && path[..module.len()] == module[..];
            if facade && *is_pub && descendant {
                continue;
            }
            if let Some(t) = resolve(path) {
                if t != **file {
                    targets.insert(t);
                }
            }
        }
    }
    g
}

/// Strongly connected components with more than one file (Tarjan).
fn cycles(g: &Graph) -> Vec<Vec<String>> {
    struct T<'a> {
        g: &'a Graph,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a str) {
        let i = t.index.len();
        t.index.insert(v, i);
        t.low.insert(v, i);
        t.stack.push(v);
        t.on.insert(v);
        let g = t.g;
        for w in g.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !t.index.contains_key(w) {
                visit(t, w);
                let lw = t.low[w];
                let lv = t.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if t.on.contains(w) {
                let iw = t.index[w];
                let lv = t.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(w);
                comp.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in g.keys() {
        if !t.index.contains_key(v.as_str()) {
            visit(&mut t, v);
        }
    }
    t.out
}

fn solver_to_io(g: &Graph) -> Vec<String> {
    g.iter()
        .filter(|(f, _)| f.starts_with("solver/"))
        .flat_map(|(f, ts)| {
            ts.iter()
                .filter(|t| t.starts_with("io/"))
                .map(move |t| format!("{f} -> {t}"))
        })
        .collect()
}

/// Imports of the application face (`app.rs`) from below it: only the binary and the face
/// itself may use it.
fn below_the_face_to_app(g: &Graph) -> Vec<String> {
    g.iter()
        .filter(|(f, _)| f.as_str() != "app.rs" && f.as_str() != "lib.rs")
        .flat_map(|(f, ts)| {
            ts.iter()
                .filter(|t| t.as_str() == "app.rs")
                .map(move |t| format!("{f} -> {t}"))
        })
        .collect()
}

/// Imports of `driver/` from the scene translation (`setup.rs`) and the model layer
/// (`model/`): both sit below the drivers, which take a model and return outcomes.
fn below_the_drivers_to_driver(g: &Graph) -> Vec<String> {
    g.iter()
        .filter(|(f, _)| {
            f.as_str() == "setup.rs" || f.starts_with("model/") || f.starts_with("io/")
        })
        .flat_map(|(f, ts)| {
            ts.iter()
                .filter(|t| t.starts_with("driver/"))
                .map(move |t| format!("{f} -> {t}"))
        })
        .collect()
}

fn describe(g: &Graph, comps: &[Vec<String>]) -> String {
    let mut s = String::new();
    for c in comps {
        s.push_str(&format!("cycle among {c:?}:\n"));
        for a in c {
            for b in &g[a] {
                if c.contains(b) {
                    s.push_str(&format!("    {a} -> {b}\n"));
                }
            }
        }
    }
    s
}

fn crate_graph() -> Graph {
    let mut sources = Sources::new();
    read_sources(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
        "",
        &mut sources,
    );
    graph(&sources)
}

#[test]
fn no_import_cycle_between_source_files() {
    let g = crate_graph();
    let c = cycles(&g);
    assert!(c.is_empty(), "{}", describe(&g, &c));
}

#[test]
fn solver_imports_nothing_from_io() {
    let bad = solver_to_io(&crate_graph());
    assert!(bad.is_empty(), "solver/ imports from io/: {bad:#?}");
}

#[test]
fn nothing_below_the_face_imports_app() {
    let bad = below_the_face_to_app(&crate_graph());
    assert!(bad.is_empty(), "imports of app.rs below it: {bad:#?}");
}

#[test]
fn setup_the_model_and_io_import_no_driver() {
    let bad = below_the_drivers_to_driver(&crate_graph());
    assert!(bad.is_empty(), "imports of driver/ below it: {bad:#?}");
}

/// The parser sees the crate's real imports (an empty graph would pass both checks).
#[test]
fn the_graph_holds_known_imports() {
    let g = crate_graph();
    for (a, b) in [
        // `use super::steady::{press, SteadyRolling}`.
        ("driver/steady_recovery.rs", "driver/steady.rs"),
        // `use crate::model::SolidSystem` through model/mod.rs's re-export.
        ("app.rs", "model/system.rs"),
        // The recorder re-exports the solvers' step events.
        ("io/record/mod.rs", "solver/observe.rs"),
        // `use super::newton::…` inside solver/.
        ("solver/stepping.rs", "solver/newton.rs"),
        // An inline `super::run_one::run_dir(…)` call.
        ("sweep/slurm.rs", "sweep/run_one.rs"),
        // An inline `crate::physics::recovery::recover_cauchy(…)` call.
        ("driver/frame.rs", "physics/recovery.rs"),
    ] {
        assert!(
            g.get(a).is_some_and(|t| t.contains(b)),
            "{a} -> {b} not seen; {a} imports {:?}",
            g.get(a)
        );
    }
    assert!(g.len() > 50, "only {} files read", g.len());
}

/// Both rules fail on a made-up tree that breaks them.
#[test]
fn the_checks_catch_a_cycle_and_a_solver_to_io_import() {
    let mut s = Sources::new();
    s.insert(
        "lib.rs".into(),
        "pub mod a;\npub mod app;\npub mod driver;\npub mod io;\npub mod setup;\npub mod solver;\n"
            .into(),
    );
    s.insert(
        "a/mod.rs".into(),
        "pub mod b;\npub mod c;\npub mod d;\npub mod e;\npub use b::Thing;\n".into(),
    );
    // b → c through an inline path, c → b through the façade's re-export.
    s.insert(
        "a/b.rs".into(),
        "pub struct Thing;\nfn f() { crate::a::c::g() }\n".into(),
    );
    s.insert(
        "a/c.rs".into(),
        "use super::{Thing as T};\npub fn g() {}\n#[cfg(test)]\nmod tests {\n    use crate::io::X;\n}\n"
            .into(),
    );
    s.insert(
        "a/d.rs".into(),
        "fn h() { super::b::Thing; self::inner(); }\nfn inner() {}\n".into(),
    );
    s.insert("app.rs".into(), "pub fn run() {}\n".into());
    s.insert("a/e.rs".into(), "fn k() { crate::app::run() }\n".into());
    s.insert("setup.rs".into(), "use crate::driver::Summary;\n".into());
    s.insert("driver/mod.rs".into(), "pub struct Summary;\n".into());
    s.insert("io/mod.rs".into(), "pub mod record;\n".into());
    s.insert(
        "io/record.rs".into(),
        "pub trait Recorder {}\nfn s() { crate::driver::Summary; }\n".into(),
    );
    s.insert("solver/mod.rs".into(), "pub mod stepping;\n".into());
    s.insert(
        "solver/stepping.rs".into(),
        "// use crate::io::nothing;\nuse crate::{\n    io::record::Recorder,\n};\n".into(),
    );
    let g = graph(&s);
    assert_eq!(
        cycles(&g),
        vec![vec!["a/b.rs".to_string(), "a/c.rs".to_string()]],
        "{g:#?}"
    );
    assert_eq!(solver_to_io(&g), vec!["solver/stepping.rs -> io/record.rs"]);
    // An inline `super::` path is an edge; an inline `self::` path stays in the file.
    assert!(g["a/d.rs"].contains("a/b.rs"), "{g:#?}");
    assert_eq!(below_the_face_to_app(&g), vec!["a/e.rs -> app.rs"]);
    assert_eq!(
        below_the_drivers_to_driver(&g),
        vec!["io/record.rs -> driver/mod.rs", "setup.rs -> driver/mod.rs"]
    );
    // Neither the façade's `pub use` nor the test module's import is an edge.
    assert!(!g["a/mod.rs"].contains("a/b.rs"), "{g:#?}");
    assert!(!g["a/c.rs"].iter().any(|t| t.starts_with("io/")), "{g:#?}");
}
