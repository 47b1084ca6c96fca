//! `tread sweep plan`: the table of runs, and the check of every run's scene before anything
//! starts. Each run's scene is loaded by the scene loader itself ([`Scene::from_toml_str`] with
//! the run's overrides, as `tread run --set` does; [`ModelScene::from_toml_str`] for a
//! model-problem scene), so a sweep accepts exactly what `tread run` accepts. All problems are reported at once; a problem shared by several runs (say, a bad
//! key in the base scene) is reported once with the list of runs.

use super::spec::{cell_text, Spec};
use crate::io::scene::model_problem::{is_model_problem, overrides_set_problem, ModelScene};
use crate::io::Scene;
use rayon::prelude::*;

/// The problems of one or more runs with the same message.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanError {
    pub runs: Vec<usize>,
    /// The scene key at fault (may be empty).
    pub key: String,
    pub message: String,
}

/// Check every run's scene; `Err` lists every problem (grouped by message).
pub fn check(spec: &Spec) -> Result<(), Vec<PlanError>> {
    let source = spec.scene_path.display().to_string();
    let per_run: Vec<Vec<(String, String)>> = (0..spec.n_runs())
        .into_par_iter()
        .map(|i| {
            let ov = spec.overrides(&spec.run(i));
            // A model-problem scene (`[problem]`, or `--set problem.…`) goes to its own loader,
            // as `tread run` sends it.
            let loaded = if is_model_problem(&spec.scene_text) || overrides_set_problem(&ov) {
                ModelScene::from_toml_str(&spec.scene_text, &source, &ov).map(|_| ())
            } else {
                Scene::from_toml_str(&spec.scene_text, &source, &ov).map(|_| ())
            };
            match loaded {
                Ok(()) => Vec::new(),
                Err(errs) => errs
                    .0
                    .into_iter()
                    .map(|e| (e.key.clone(), e.to_string()))
                    .collect(),
            }
        })
        .collect();
    let mut groups: Vec<PlanError> = Vec::new();
    let mut by_msg = std::collections::HashMap::new();
    for (i, errs) in per_run.into_iter().enumerate() {
        for (key, message) in errs {
            let slot = *by_msg.entry(message.clone()).or_insert_with(|| {
                groups.push(PlanError {
                    runs: Vec::new(),
                    key,
                    message,
                });
                groups.len() - 1
            });
            groups[slot].runs.push(i);
        }
    }
    if groups.is_empty() {
        Ok(())
    } else {
        Err(groups)
    }
}

/// Indices as compact ranges: `0003-0005, 0009`.
pub fn ranges(spec: &Spec, idx: &[usize]) -> String {
    let mut out: Vec<String> = Vec::new();
    let mut k = 0;
    while k < idx.len() {
        let mut j = k;
        while j + 1 < idx.len() && idx[j + 1] == idx[j] + 1 {
            j += 1;
        }
        out.push(if j == k {
            spec.run_name(idx[k])
        } else {
            format!("{}-{}", spec.run_name(idx[k]), spec.run_name(idx[j]))
        });
        k = j + 1;
    }
    out.join(", ")
}

/// The plan errors as lines: `run 0003 (road.v0=-1.0): <scene error>`, or for a message shared
/// by several runs `runs 0000-0999 (all 1000 runs): <scene error>`.
pub fn render_errors(spec: &Spec, errors: &[PlanError]) -> String {
    let n = spec.n_runs();
    let mut s = String::new();
    for e in errors {
        let who = if e.runs.len() == 1 {
            let r = spec.run(e.runs[0]);
            let vals: Vec<String> = spec
                .overrides(&r)
                .into_iter()
                .take(r.params.len())
                .collect();
            format!("run {} ({})", spec.run_name(e.runs[0]), vals.join(", "))
        } else if e.runs.len() == n {
            format!("all {n} runs")
        } else {
            format!("runs {} ({} runs)", ranges(spec, &e.runs), e.runs.len())
        };
        s.push_str(&format!("{who}: {}\n", e.message));
    }
    s
}

/// The plan as an aligned text table: index, then one column per swept key.
pub fn render_table(spec: &Spec) -> String {
    let keys = spec.keys();
    let n = spec.n_runs();
    let mut rows: Vec<Vec<String>> = Vec::with_capacity(n + 1);
    let mut head = vec!["run".to_string()];
    head.extend(keys.iter().map(|k| match spec.unit_of(k) {
        Some(u) => format!("{k} [{u}]"),
        None => k.to_string(),
    }));
    rows.push(head);
    for i in 0..n {
        let r = spec.run(i);
        let mut row = vec![spec.run_name(i)];
        row.extend(r.params.iter().map(|(_, v)| cell_text(v)));
        rows.push(row);
    }
    let cols = rows[0].len();
    let width: Vec<usize> = (0..cols)
        .map(|c| rows.iter().map(|r| r[c].chars().count()).max().unwrap_or(0))
        .collect();
    let mut s = String::new();
    for r in &rows {
        let line: Vec<String> = r
            .iter()
            .zip(&width)
            .map(|(c, w)| format!("{c:<w$}"))
            .collect();
        s.push_str(line.join("  ").trim_end());
        s.push('\n');
    }
    s
}
