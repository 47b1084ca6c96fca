//! `tread sweep collect` and `tread sweep status`: read the run folders (never a scheduler) and
//! make one table of the sweep.
//!
//! `<sweep>/results.csv` has one row per run: `run` (index), `state` (`done`, `failed`,
//! `killed`, `running`, `queued`, `not_started`, or `outdated` for a folder left by another
//! base scene or other values), one column per swept key (the value given to the scene), one
//! column per result (summary.json `results`, nested objects flattened as `a.b`; lists left
//! out; written exactly as summary.json has them), `wall_time_s` of `tread run`, and `error`
//! (why a run failed or was killed). Results are filled for done runs only: a failed run's
//! summary.json holds the last converged step, which is not the run's answer.
//!
//! Each `[[plot]]` of the spec becomes `<sweep>/plots/<file>`: every result of `y` against the
//! swept key `x`, one curve per combination of the other swept keys, done runs only, axes
//! labelled with their units; a geometric axis (or `log_x`/`log_y`) is drawn on a log scale.

use super::plan::ranges;
use super::run_one::run_dir;
use super::spec::{cell_text, Spec};
use super::status::{self, State};
use crate::io::record::png::{chart, Axis};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One row of the table.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub index: usize,
    /// `done`, `failed`, … as in the module docs.
    pub state: String,
    pub params: Vec<String>,
    pub results: BTreeMap<String, String>,
    pub wall_time_s: Option<f64>,
    pub error: Option<String>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub keys: Vec<String>,
    pub result_columns: Vec<String>,
    pub rows: Vec<Row>,
    /// Problems met while reading (unreadable status or summary files).
    pub warnings: Vec<String>,
}

impl Table {
    pub fn count(&self, state: &str) -> usize {
        self.rows.iter().filter(|r| r.state == state).count()
    }

    /// One line: `8 runs: 7 done, 1 failed` (states with a zero count left out).
    pub fn counts_line(&self) -> String {
        let mut parts = Vec::new();
        for s in [
            "done",
            "failed",
            "killed",
            "running",
            "queued",
            "not_started",
            "outdated",
        ] {
            let n = self.count(s);
            if n > 0 {
                parts.push(format!("{n} {}", s.replace('_', " ")));
            }
        }
        format!("{} runs: {}", self.rows.len(), parts.join(", "))
    }

    /// The header and cells of results.csv.
    pub fn csv_header(&self) -> Vec<String> {
        let mut h = vec!["run".to_string(), "state".to_string()];
        h.extend(self.keys.iter().cloned());
        h.extend(self.result_columns.iter().cloned());
        h.push("wall_time_s".into());
        h.push("error".into());
        h
    }

    pub fn csv_row(&self, r: &Row) -> Vec<String> {
        let mut c = vec![r.index.to_string(), r.state.clone()];
        c.extend(r.params.iter().cloned());
        for k in &self.result_columns {
            c.push(r.results.get(k).cloned().unwrap_or_default());
        }
        c.push(r.wall_time_s.map(|w| format!("{w:.3}")).unwrap_or_default());
        c.push(r.error.clone().unwrap_or_default());
        c
    }

    /// Numeric value of a swept key or result in a row.
    pub fn number(&self, r: &Row, key: &str) -> Option<f64> {
        let text = match self.keys.iter().position(|k| k == key) {
            Some(i) => r.params.get(i)?,
            None => r.results.get(key)?,
        };
        text.parse::<f64>().ok().filter(|x| x.is_finite())
    }
}

/// Flatten a JSON object into dotted scalar cells (lists are left out).
fn flatten(prefix: &str, v: &serde_json::Value, out: &mut BTreeMap<String, String>) {
    use serde_json::Value as J;
    let name = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match v {
        J::Object(m) => {
            for (k, x) in m {
                match x {
                    J::Object(_) => flatten(&name(k), x, out),
                    J::Array(_) => {}
                    J::Null => {
                        out.insert(name(k), String::new());
                    }
                    J::Bool(b) => {
                        out.insert(name(k), b.to_string());
                    }
                    J::Number(n) => {
                        out.insert(name(k), n.to_string());
                    }
                    J::String(s) => {
                        out.insert(name(k), s.clone());
                    }
                }
            }
        }
        _ => {
            out.insert(prefix.to_string(), v.to_string());
        }
    }
}

/// Read every run folder of the sweep.
pub fn gather(spec: &Spec, root: &Path) -> Table {
    let keys: Vec<String> = spec.keys().into_iter().map(str::to_string).collect();
    let mut rows = Vec::with_capacity(spec.n_runs());
    let mut warnings = Vec::new();
    let mut seen_cols: Vec<String> = Vec::new();
    for i in 0..spec.n_runs() {
        let run = spec.run(i);
        let params: Vec<String> = run.params.iter().map(|(_, v)| cell_text(v)).collect();
        let dir = run_dir(spec, root, i);
        let mut row = Row {
            index: i,
            state: "not_started".into(),
            params,
            results: BTreeMap::new(),
            wall_time_s: None,
            error: None,
        };
        match status::read_effective(&dir) {
            Ok(None) => {}
            Err(e) => {
                warnings.push(e.clone());
                row.state = "failed".into();
                row.error = Some(e);
            }
            Ok(Some(st)) if st.fingerprint != spec.run_fingerprint(&run) => {
                row.state = "outdated".into();
            }
            Ok(Some(st)) => {
                row.state = st.state.as_str().into();
                row.wall_time_s = st.wall_time_s;
                row.error = st.error.clone();
                if st.state == State::Done {
                    let p = dir.join("summary.json");
                    match std::fs::read_to_string(&p)
                        .map_err(|e| e.to_string())
                        .and_then(|t| {
                            serde_json::from_str::<serde_json::Value>(&t).map_err(|e| e.to_string())
                        }) {
                        Ok(v) => {
                            if let Some(r) = v.get("results") {
                                flatten("", r, &mut row.results);
                            }
                            for k in row.results.keys() {
                                if !seen_cols.contains(k) {
                                    seen_cols.push(k.clone());
                                }
                            }
                        }
                        Err(e) => warnings.push(format!("{}: {e}", p.display())),
                    }
                }
            }
        }
        rows.push(row);
    }
    let result_columns = if spec.results.is_empty() {
        seen_cols.sort();
        seen_cols
    } else {
        for k in &spec.results {
            let any_done = rows.iter().any(|r| r.state == "done");
            if any_done && !rows.iter().any(|r| r.results.contains_key(k)) {
                warnings.push(format!(
                    "result `{k}` ([outputs] results) is in no run's summary.json `results`"
                ));
            }
        }
        spec.results.clone()
    };
    Table {
        keys,
        result_columns,
        rows,
        warnings,
    }
}

/// Write the table as CSV, atomically (through [`crate::io::output::write_text_csv`]: fields
/// with commas, quotes or line breaks are quoted).
pub fn write_csv(table: &Table, path: &Path) -> Result<(), String> {
    let header = table.csv_header();
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    crate::io::output::write_text_csv(path, &header, table.rows.iter().map(|r| table.csv_row(r)))
        .map_err(|e| e.to_string())
}

/// Read a CSV written by [`write_csv`] back into rows of fields (the csv crate's reader, no
/// header row taken out).
pub fn read_csv(text: &str) -> Vec<Vec<String>> {
    csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(text.as_bytes())
        .records()
        .filter_map(Result::ok)
        .map(|r| r.iter().map(str::to_string).collect())
        .collect()
}

/// Draw the spec's plots into `dir`. Returns the files written and the problems met.
pub fn draw_plots(spec: &Spec, table: &Table, dir: &Path) -> (Vec<PathBuf>, Vec<String>) {
    let mut files = Vec::new();
    let mut problems = Vec::new();
    if spec.plots.is_empty() {
        return (files, problems);
    }
    if let Err(e) = std::fs::create_dir_all(dir) {
        problems.push(format!("cannot create {}: {e}", dir.display()));
        return (files, problems);
    }
    for p in &spec.plots {
        // Keys that move with x (x and its zip partners) do not split the curves.
        let with_x: Vec<&str> = spec
            .axes
            .iter()
            .find(|a| a.columns.iter().any(|c| c.key == p.x))
            .map(|a| a.columns.iter().map(|c| c.key.as_str()).collect())
            .unwrap_or_default();
        let others: Vec<usize> = (0..table.keys.len())
            .filter(|&i| !with_x.contains(&table.keys[i].as_str()))
            .collect();
        let mut curves: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        for y in &p.y {
            let mut groups: BTreeMap<Vec<String>, Vec<(f64, f64)>> = BTreeMap::new();
            let mut order: Vec<Vec<String>> = Vec::new();
            for r in table.rows.iter().filter(|r| r.state == "done") {
                let (Some(xv), Some(yv)) = (table.number(r, &p.x), table.number(r, y)) else {
                    continue;
                };
                let g: Vec<String> = others.iter().map(|&i| r.params[i].clone()).collect();
                if !groups.contains_key(&g) {
                    order.push(g.clone());
                }
                groups.entry(g).or_default().push((xv, yv));
            }
            for g in order {
                let mut pts = groups.remove(&g).unwrap_or_default();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                let mut label: Vec<String> = Vec::new();
                if p.y.len() > 1 {
                    label.push(y.clone());
                }
                for (&i, v) in others.iter().zip(&g) {
                    let k = &table.keys[i];
                    match spec.unit_of(k) {
                        Some(u) if u != "1" => label.push(format!("{k} = {v} {u}")),
                        _ => label.push(format!("{k} = {v}")),
                    }
                }
                let label = if label.is_empty() {
                    y.clone()
                } else {
                    label.join(", ")
                };
                curves.push((label, pts));
            }
        }
        let path = dir.join(&p.file);
        if curves.iter().all(|(_, c)| c.is_empty()) {
            problems.push(format!(
                "{}: no done run has numeric values of {} and {}",
                path.display(),
                p.x,
                p.y.join(", ")
            ));
            continue;
        }
        let unit = |k: &str| spec.unit_of(k).unwrap_or("?").to_string();
        let x_label = format!("{} [{}]", p.x, unit(&p.x));
        let y_label = format!("{} [{}]", p.y.join(", "), unit(&p.y[0]));
        let geometric = spec.column(&p.x).is_some_and(|c| c.geometric);
        let x_axis = if p.log_x || geometric {
            Axis::log10(&x_label)
        } else {
            Axis::linear(&x_label)
        };
        let y_axis = if p.log_y {
            Axis::log10(&y_label)
        } else {
            Axis::linear(&y_label)
        };
        let title = if p.title.is_empty() {
            format!("{}: {} against {}", spec.name, p.y.join(", "), p.x)
        } else {
            p.title.clone()
        };
        let series: Vec<(&str, &[(f64, f64)])> = curves
            .iter()
            .map(|(n, c)| (n.as_str(), c.as_slice()))
            .collect();
        match chart(&path, &title, x_axis, y_axis, &series) {
            Ok(notes) => {
                problems.extend(
                    notes
                        .into_iter()
                        .map(|n| format!("{}: {n}", path.display())),
                );
                files.push(path);
            }
            Err(e) => problems.push(format!("{}: {e}", path.display())),
        }
    }
    (files, problems)
}

/// What `collect` wrote.
#[derive(Debug)]
pub struct Collected {
    pub table: Table,
    pub csv: PathBuf,
    pub plots: Vec<PathBuf>,
    pub problems: Vec<String>,
}

/// Gather the table, write `<root>/results.csv` and the plots.
pub fn collect(spec: &Spec, root: &Path) -> Result<Collected, String> {
    std::fs::create_dir_all(root).map_err(|e| format!("cannot create {}: {e}", root.display()))?;
    let table = gather(spec, root);
    let csv = root.join("results.csv");
    write_csv(&table, &csv)?;
    let (plots, mut problems) = draw_plots(spec, &table, &root.join("plots"));
    problems.splice(0..0, table.warnings.iter().cloned());
    Ok(Collected {
        table,
        csv,
        plots,
        problems,
    })
}

/// The status report: counts, then failed and killed runs with their errors, then the runs
/// still running or waiting (as ranges).
pub fn render_status(spec: &Spec, table: &Table) -> String {
    let mut s = format!("sweep `{}`: {}\n", spec.name, table.counts_line());
    for state in ["failed", "killed"] {
        for r in table.rows.iter().filter(|r| r.state == state) {
            let vals: Vec<String> = table
                .keys
                .iter()
                .zip(&r.params)
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            let err = r.error.as_deref().unwrap_or("(no error recorded)");
            let err = err.replace('\n', "\n    ");
            s.push_str(&format!(
                "  {state} {} ({}): {err}\n",
                spec.run_name(r.index),
                vals.join(", ")
            ));
        }
    }
    for state in ["running", "queued", "not_started", "outdated"] {
        let idx: Vec<usize> = table
            .rows
            .iter()
            .filter(|r| r.state == state)
            .map(|r| r.index)
            .collect();
        if !idx.is_empty() {
            s.push_str(&format!(
                "  {}: {}\n",
                state.replace('_', " "),
                ranges(spec, &idx)
            ));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trip_with_quotes_commas_and_newlines() {
        let t = "a,\"b,1\",\"say \"\"hi\"\"\nthere\"\n1,,x\n";
        let rows = read_csv(t);
        assert_eq!(
            rows,
            vec![vec!["a", "b,1", "say \"hi\"\nthere"], vec!["1", "", "x"]]
        );
        let back = crate::io::output::csv_line(&rows[0]);
        assert_eq!(back, "a,\"b,1\",\"say \"\"hi\"\"\nthere\"\n");
    }

    #[test]
    fn flatten_keeps_scalars_and_nests_objects() {
        let v = serde_json::json!({"a": 1.5, "b": {"c": true, "d": [1, 2]}, "e": null, "f": "x"});
        let mut m = BTreeMap::new();
        flatten("", &v, &mut m);
        let got: Vec<(&str, &str)> = m.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
        assert_eq!(
            got,
            vec![("a", "1.5"), ("b.c", "true"), ("e", ""), ("f", "x")]
        );
    }
}
