//! The scene schema and the output reference are generated from the program's own tables:
//! - `docs/reference.md` equals what `tread schema --markdown` prints now;
//! - the JSON Schema of `tread schema` accepts every scene under `scenarios/` and rejects a
//!   misspelt key, a wrong type and an unknown keyword (checked by a small validator of the
//!   draft 2020-12 keywords that the schema uses; an unknown keyword fails the test);
//! - every `summary.json` key and CSV column that runs write is in the reference: the committed
//!   regression summaries (which tests/regression.rs keeps equal to what the runs write) and
//!   runs made here (compare, a viscoelastic transient, a two-region static scene, a steady sweep,
//!   a steady creep-controlled sweep, a stick-slip, a spinning and an indentation run, all with
//!   their CSV tables).

#[path = "common/tempdir.rs"]
mod tempdir;

use serde_json::Value;
use std::collections::BTreeSet;
use std::path::Path;
use std::process::Command;
use tempdir::TestDir;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn tread(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_tread"))
        .args(args)
        .output()
        .expect("run tread")
}

#[test]
fn committed_reference_is_what_the_program_generates() {
    let out = tread(&["schema", "--markdown"]);
    assert!(out.status.success());
    let generated = String::from_utf8(out.stdout).expect("utf-8");
    let committed =
        std::fs::read_to_string(root().join("docs/reference.md")).expect("docs/reference.md");
    assert!(
        generated.trim_end() == committed.trim_end(),
        "docs/reference.md is out of date: run `tread schema --markdown --out docs/reference.md`"
    );
    // The library function and the command agree, and every section of the schema is there.
    assert_eq!(
        tread::io::reference::markdown().trim_end(),
        committed.trim_end()
    );
    for sec in ["[scene]", "[material]", "[time]", "[output]"] {
        assert!(committed.contains(&format!("### `{sec}`")), "{sec}");
    }
}

// --- a small JSON Schema validator (the keywords `tread schema` uses) -------------------------

fn type_ok(t: &str, v: &Value) -> bool {
    match t {
        "object" => v.is_object(),
        "array" => v.is_array(),
        "string" => v.is_string(),
        "boolean" => v.is_boolean(),
        "number" => v.is_number(),
        "integer" => v.is_i64() || v.is_u64(),
        other => panic!("type {other} not handled"),
    }
}

fn validate(schema: &Value, v: &Value, path: &str, errs: &mut Vec<String>) {
    let s = schema.as_object().expect("a schema is an object");
    for key in s.keys() {
        assert!(
            [
                "$schema",
                "title",
                "description",
                "default",
                "type",
                "enum",
                "properties",
                "additionalProperties",
                "required",
                "items",
                "prefixItems",
                "minItems",
                "maxItems",
                "uniqueItems",
                "minimum",
                "maximum",
                "const",
                "if",
                "then",
                "else",
                "oneOf",
            ]
            .contains(&key.as_str()),
            "keyword {key} not handled by the test's validator"
        );
    }
    if let Some(t) = s.get("type").and_then(Value::as_str) {
        if !type_ok(t, v) {
            errs.push(format!("{path}: expected {t}, found {v}"));
            return;
        }
    }
    if let Some(e) = s.get("enum").and_then(Value::as_array) {
        if !e.contains(v) {
            errs.push(format!("{path}: {v} not in {e:?}"));
        }
    }
    if let (Some(m), Some(x)) = (s.get("minimum").and_then(Value::as_f64), v.as_f64()) {
        if x < m {
            errs.push(format!("{path}: {x} < {m}"));
        }
    }
    if let (Some(m), Some(x)) = (s.get("maximum").and_then(Value::as_f64), v.as_f64()) {
        if x > m {
            errs.push(format!("{path}: {x} > {m}"));
        }
    }
    if let Some(c) = s.get("const") {
        if c != v {
            errs.push(format!("{path}: {v} is not {c}"));
        }
    }
    if let Some(cond) = s.get("if") {
        let mut e = Vec::new();
        validate(cond, v, path, &mut e);
        let branch = if e.is_empty() {
            s.get("then")
        } else {
            s.get("else")
        };
        if let Some(b) = branch {
            validate(b, v, path, errs);
        }
    }
    if let Some(o) = v.as_object() {
        let props = s.get("properties").and_then(Value::as_object);
        for (k, x) in o {
            match props.and_then(|p| p.get(k)) {
                Some(sub) => validate(sub, x, &format!("{path}.{k}"), errs),
                None => {
                    if s.get("additionalProperties") == Some(&Value::Bool(false)) {
                        errs.push(format!("{path}.{k}: unknown key"));
                    }
                }
            }
        }
        for r in s
            .get("required")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            let r = r.as_str().expect("string");
            if !o.contains_key(r) {
                errs.push(format!("{path}.{r}: required key missing"));
            }
        }
    }
    if let Some(a) = v.as_array() {
        let n = a.len() as u64;
        if s.get("minItems")
            .and_then(Value::as_u64)
            .is_some_and(|m| n < m)
        {
            errs.push(format!("{path}: too few items"));
        }
        if s.get("maxItems")
            .and_then(Value::as_u64)
            .is_some_and(|m| n > m)
        {
            errs.push(format!("{path}: too many items"));
        }
        if s.get("uniqueItems") == Some(&Value::Bool(true)) {
            let set: BTreeSet<String> = a.iter().map(Value::to_string).collect();
            if set.len() != a.len() {
                errs.push(format!("{path}: repeated items"));
            }
        }
        let prefix = s.get("prefixItems").and_then(Value::as_array);
        for (i, x) in a.iter().enumerate() {
            let sub = prefix.and_then(|p| p.get(i)).or(s.get("items"));
            if let Some(sub) = sub {
                validate(sub, x, &format!("{path}[{i}]"), errs);
            }
        }
    }
    if let Some(alts) = s.get("oneOf").and_then(Value::as_array) {
        let ok = alts
            .iter()
            .filter(|alt| {
                let mut e = Vec::new();
                validate(alt, v, path, &mut e);
                e.is_empty()
            })
            .count();
        if ok != 1 {
            errs.push(format!("{path}: matches {ok} of the oneOf alternatives"));
        }
    }
}

fn schema() -> Value {
    let out = tread(&["schema"]);
    assert!(out.status.success());
    let s: Value = serde_json::from_slice(&out.stdout).expect("tread schema prints JSON");
    assert_eq!(s["$schema"], "https://json-schema.org/draft/2020-12/schema");
    assert_eq!(s, tread::io::scene::json_schema());
    s
}

fn scene_json(text: &str) -> Value {
    let t: toml::Table = text.parse().expect("TOML");
    serde_json::to_value(t).expect("JSON")
}

fn errors_of(schema: &Value, text: &str) -> Vec<String> {
    let mut errs = Vec::new();
    validate(schema, &scene_json(text), "", &mut errs);
    errs
}

#[test]
fn json_schema_accepts_every_scenario_and_rejects_mistakes() {
    let schema = schema();
    let mut n = 0;
    for entry in std::fs::read_dir(root().join("scenarios")).expect("scenarios/") {
        let path = entry.expect("entry").path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).expect("read");
        if text
            .parse::<toml::Table>()
            .is_ok_and(|t| t.contains_key("sweep"))
        {
            continue; // a sweep file (`tread sweep`), not a scene
        }
        let errs = errors_of(&schema, &text);
        assert!(errs.is_empty(), "{}: {errs:?}", path.display());
        // The program accepts it too (schema and loader agree on these files).
        let check = tread(&["check", path.to_str().expect("utf-8")]);
        assert!(check.status.success(), "{}", path.display());
        n += 1;
    }
    assert!(n >= 20, "only {n} scenes");

    let text =
        std::fs::read_to_string(root().join("scenarios/oden_hollow_cylinder.toml")).expect("read");
    let misspelt = text.replacen("\nn_theta", "\nn_thetta", 1);
    assert_ne!(misspelt, text);
    let errs = errors_of(&schema, &misspelt);
    assert!(
        errs.iter()
            .any(|e| e.contains(".mesh.n_thetta: unknown key")),
        "{errs:?}"
    );

    let wrong_type = text.replacen("\nn_theta = ", "\nn_theta = \"x\" # ", 1);
    assert!(!errors_of(&schema, &wrong_type).is_empty());
    let bad_keyword = text.replacen("mode = \"", "mode = \"x", 1);
    assert!(!errors_of(&schema, &bad_keyword).is_empty());
    let no_geometry = format!("{}\n", text.replace("[geometry]", "[geometryy]"));
    let errs = errors_of(&schema, &no_geometry);
    assert!(
        errs.iter().any(|e| e.contains(".geometry: required")),
        "{errs:?}"
    );
    // `[time]` keys of the transient mode: required unless the scene is steady, as the loader
    // has it; integer bounds as the loader's.
    let transient =
        std::fs::read_to_string(root().join("scenarios/rolling_frictionless.toml")).expect("read");
    let no_dt: String = transient
        .lines()
        .filter(|l| !l.trim_start().starts_with("dt ="))
        .collect::<Vec<_>>()
        .join("\n");
    let errs = errors_of(&schema, &no_dt);
    assert!(
        errs.iter().any(|e| e.contains(".time.dt: required")),
        "{errs:?}"
    );
    let steady = no_dt.replacen("mode = \"transient\"", "mode = \"steady\"", 1);
    assert_ne!(steady, no_dt);
    let errs = errors_of(&schema, &steady);
    assert!(!errs.iter().any(|e| e.contains(".time.dt")), "{errs:?}");
    let errs = errors_of(&schema, &text.replacen("\nn_r = ", "\nn_r = 0 # ", 1));
    assert!(
        errs.iter().any(|e| e.contains(".mesh.n_r: 0 < 1")),
        "{errs:?}"
    );
    // `[[material]]`: each entry needs its region.
    let two =
        std::fs::read_to_string(root().join("scenarios/two_layer_cylinder.toml")).expect("read");
    let errs = errors_of(&schema, &two.replacen("region =", "regio =", 1));
    assert!(!errs.is_empty());
}

// --- every summary key and CSV column documented --------------------------------------------

fn keys(v: &Value, path: &str, out: &mut BTreeSet<String>) {
    match v {
        Value::Object(o) => {
            for (k, x) in o {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                out.insert(p.clone());
                keys(x, &p, out);
            }
        }
        Value::Array(a) => {
            for x in a {
                if x.is_object() || x.is_array() {
                    keys(x, &format!("{path}[]"), out);
                }
            }
        }
        _ => {}
    }
}

fn undocumented_in(dir: &Path, missing: &mut BTreeSet<String>, seen: &mut usize) {
    for entry in std::fs::read_dir(dir).expect("dir") {
        let path = entry.expect("entry").path();
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("")
            .to_string();
        if path.is_dir() {
            undocumented_in(&path, missing, seen);
        } else if name == "summary.json" {
            let v: Value =
                serde_json::from_str(&std::fs::read_to_string(&path).expect("read")).expect("JSON");
            let mut ks = BTreeSet::new();
            keys(&v, "", &mut ks);
            for k in ks {
                *seen += 1;
                if !tread::io::reference::summary_key_documented(&k) {
                    missing.insert(format!("summary.json {k}"));
                }
            }
        } else if name.ends_with(".csv") {
            let text = std::fs::read_to_string(&path).expect("read");
            for col in text.lines().next().unwrap_or("").split(',') {
                *seen += 1;
                if !tread::io::reference::csv_column_documented(&name, col) {
                    missing.insert(format!("{name} {col}"));
                }
            }
        }
    }
}

#[test]
fn every_summary_key_in_the_regression_data_is_documented() {
    let mut missing = BTreeSet::new();
    let mut n = 0;
    for entry in std::fs::read_dir(root().join("tests/regression")).expect("dir") {
        let path = entry.expect("entry").path();
        if path.extension().and_then(|e| e.to_str()) != Some("json") {
            continue;
        }
        let v: Value =
            serde_json::from_str(&std::fs::read_to_string(&path).expect("read")).expect("JSON");
        let mut ks = BTreeSet::new();
        keys(&v, "", &mut ks);
        for k in ks {
            n += 1;
            if !tread::io::reference::summary_key_documented(&k) {
                missing.insert(format!("{}: {k}", path.display()));
            }
        }
    }
    assert!(n > 300, "{n}");
    assert!(missing.is_empty(), "undocumented: {missing:#?}");
}

#[test]
fn every_summary_key_and_csv_column_that_runs_write_is_documented() {
    let dir = TestDir::new("schema_docs", "runs");
    let sc = |f: &str| root().join("scenarios").join(f).display().to_string();
    let runs: Vec<(&str, Vec<String>)> = vec![
        (
            "compare",
            vec!["compare".into(), sc("rolling_frictionless.toml")],
        ),
        (
            "compare_3d",
            vec![
                "compare".into(),
                sc("transient_cornering_3d.toml"),
                "--set".into(),
                "mesh.n_theta=32".into(),
                "--set".into(),
                "time.t_end=0.3".into(),
            ],
        ),
        (
            "visco",
            vec![
                "run".into(),
                sc("viscoelastic_rolling.toml"),
                "--set".into(),
                "mesh.n_theta=16".into(),
            ],
        ),
        (
            "two_layer",
            vec!["run".into(), sc("two_layer_cylinder.toml")],
        ),
        (
            "sweep",
            vec![
                "run".into(),
                sc("oden_steady_sweep.toml"),
                "--set".into(),
                "continuation.max_steps=3".into(),
            ],
        ),
        ("stick_slip", vec!["run".into(), sc("stick_slip.toml")]),
        (
            "creep",
            vec![
                "run".into(),
                sc("creep_force_curve.toml"),
                "--set".into(),
                "mesh.n_theta=32".into(),
                "--set".into(),
                "continuation.max_steps=3".into(),
            ],
        ),
        (
            "spinning",
            vec!["run".into(), sc("spinning_incompressible.toml")],
        ),
        (
            "indentation",
            vec!["run".into(), sc("indentation_friction.toml")],
        ),
    ];
    for (name, args) in &runs {
        let out_dir = dir.join(name);
        let mut all: Vec<&str> = args.iter().map(String::as_str).collect();
        let out_s = out_dir.display().to_string();
        all.extend([
            "--threads",
            "1",
            "-q",
            "--set",
            "output.sinks=summary,csv",
            "--out",
            &out_s,
        ]);
        let out = tread(&all);
        assert!(
            out_dir.join("summary.json").exists(),
            "{name}: no summary.json; stderr: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let mut missing = BTreeSet::new();
    let mut seen = 0;
    undocumented_in(&dir, &mut missing, &mut seen);
    assert!(seen > 300, "{seen}");
    assert!(missing.is_empty(), "undocumented: {missing:#?}");
}
