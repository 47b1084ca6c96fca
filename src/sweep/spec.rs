//! Sweep specs: the TOML file naming a base scene, the axes swept over it, the outputs kept,
//! the plots drawn and the cluster resources of a run.
//!
//! ```toml
//! [sweep]
//! name = "creep_force"                  # [A-Za-z0-9_-]+, names the sweep folder out/<name>/
//! scene = "creep_force_base.toml"       # base scene, relative to this file
//! description = ""                      # free text
//!
//! [[axis]]                              # a list of values (any TOML value the key accepts)
//! key = "friction.mu"
//! values = [0.2, 0.3, 0.5]
//!
//! [[axis]]                              # a linear range: num points from start to stop,
//! key = "road.v0"                       # both included (or `step = ` instead of `num`)
//! linear = { start = 3.5, stop = 4.3, num = 9 }
//! unit = "in/s"                         # for plots and the table's documentation
//!
//! [[axis]]                              # a geometric range (start, stop > 0 or both < 0)
//! key = "mesh.n_theta"                  # integers stay integers (rounded)
//! geometric = { start = 8, stop = 64, num = 4 }
//!
//! [[axis]]                              # zipped: several keys move together (same lengths)
//! zip = [
//!   { key = "motion.omega", values = [10.0, 20.0, 30.0] },
//!   { key = "road.v0", linear = { start = 19.67, stop = 59.0, num = 3 } },
//! ]
//!
//! [outputs]
//! sinks = ["summary", "csv"]            # what each run writes (the scene's `output.sinks`)
//! results = ["hub_force_x"]             # summary.json `results` keys in the table (default:
//!                                       # every scalar; nested objects as dotted names)
//! [units]                               # units of results (axes carry their own `unit`)
//! hub_force_x = "lbf/in"
//!
//! [[plot]]                              # one PNG per plot in <sweep>/plots/
//! x = "road.v0"                         # a swept key
//! y = ["hub_force_x"]                   # result keys (one unit for all), one curve per
//!                                       # value of the other swept keys
//! file = "creep.png"                    # optional; title = "" optional; log_x, log_y optional
//!                                       # (a geometric axis is drawn on a log axis anyway)
//!
//! [slurm]                               # defaults of `tread sweep run --backend slurm`
//! partition = "compute"
//! time = "00:30:00"                     # per array task
//! cpus_per_task = 1
//! mem = "2G"
//! throttle = 16                         # at most 16 array tasks at once (%16)
//! pack = 1                              # runs per array task
//! max_array_size = 1001                 # the site's MaxArraySize (asked from scontrol if absent)
//! extra = ["--account=proj42"]          # further #SBATCH lines, verbatim
//! ```
//!
//! The runs are the Cartesian product of the axes (a zipped axis counts as one), the **last
//! axis varying fastest**: run `i` has the mixed-radix digits of `i` in the axis lengths. Each
//! run is the base scene with one `--set key=value` override per swept key (plus
//! `output.sinks` from `[outputs] sinks`); the scene loader ([`crate::io::Scene`], or
//! [`crate::io::scene::model_problem::ModelScene`] for a scene with `[problem]`) validates it
//! exactly as `tread run --set` does.
//!
//! Range values are rounded to 15 significant digits so that `0.1 + 2·0.1` reads `0.3`; the end
//! points are exact.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One swept key and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct Column {
    pub key: String,
    pub values: Vec<toml::Value>,
    /// Given as a geometric range (plots use a log axis for it).
    pub geometric: bool,
    pub unit: Option<String>,
}

/// One axis of the product: one column, or several zipped columns of equal length.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    pub columns: Vec<Column>,
}

impl Axis {
    pub fn len(&self) -> usize {
        self.columns.first().map_or(0, |c| c.values.len())
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A plot of results against a swept key.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotSpec {
    pub x: String,
    pub y: Vec<String>,
    pub file: String,
    pub title: String,
    pub log_x: bool,
    pub log_y: bool,
}

/// Slurm resources and array layout (every field optional; the CLI overrides each).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SlurmSpec {
    pub partition: Option<String>,
    pub time: Option<String>,
    pub cpus_per_task: Option<usize>,
    pub mem: Option<String>,
    pub throttle: Option<usize>,
    pub pack: Option<usize>,
    pub max_array_size: Option<usize>,
    pub extra: Vec<String>,
}

/// A loaded sweep spec.
#[derive(Clone, Debug)]
pub struct Spec {
    pub name: String,
    pub description: String,
    /// The spec file (absolute).
    pub path: PathBuf,
    /// The base scene file (absolute) and its text.
    pub scene_path: PathBuf,
    pub scene_text: String,
    pub axes: Vec<Axis>,
    /// `[outputs] sinks`: becomes an `output.sinks` override of every run.
    pub sinks: Option<Vec<String>>,
    /// `[outputs] results`: the result columns of the table (empty: every scalar result).
    pub results: Vec<String>,
    pub units: BTreeMap<String, String>,
    pub plots: Vec<PlotSpec>,
    pub slurm: SlurmSpec,
}

/// One run of the sweep: its index and the value of every swept key.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    pub index: usize,
    pub params: Vec<(String, toml::Value)>,
}

/// Problems in a spec file, all at once.
#[derive(Clone, Debug, PartialEq)]
pub struct SpecErrors {
    pub source: String,
    pub errors: Vec<String>,
}

impl std::fmt::Display for SpecErrors {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, e) in self.errors.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{}: {e}", self.source)?;
        }
        Ok(())
    }
}

impl std::error::Error for SpecErrors {}

/// Render a TOML value as the right-hand side of a `--set key=value` override (strings quoted,
/// so that the scene loader reads them as strings whatever their text).
pub fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::Float(x) => float_text(*x),
        toml::Value::Array(a) => {
            let items: Vec<String> = a.iter().map(value_text).collect();
            format!("[{}]", items.join(", "))
        }
        other => other.to_string(),
    }
}

/// A value for a table cell: strings without quotes.
pub fn cell_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => value_text(other),
    }
}

/// Shortest text that reads back as the same f64, always with a `.` or exponent (a TOML float).
fn float_text(x: f64) -> String {
    if !x.is_finite() {
        return if x.is_nan() {
            "nan".into()
        } else if x > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        };
    }
    let s = format!("{x}");
    if s.contains(['.', 'e', 'E']) {
        s
    } else {
        format!("{s}.0")
    }
}

/// Round to 15 significant digits (removes the last-bit noise of `start + i·step`).
fn tidy(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    format!("{x:.14e}").parse().unwrap_or(x)
}

struct Walker {
    errors: Vec<String>,
}

impl Walker {
    fn err(&mut self, key: &str, msg: impl std::fmt::Display) {
        self.errors.push(format!("key `{key}`: {msg}"));
    }

    fn unknown_keys(&mut self, t: &toml::Table, at: &str, known: &[&str]) {
        for k in t.keys() {
            if !known.contains(&k.as_str()) {
                let key = if at.is_empty() {
                    k.clone()
                } else {
                    format!("{at}.{k}")
                };
                self.err(
                    &key,
                    format!("unknown key (expected one of: {})", known.join(", ")),
                );
            }
        }
    }

    fn string(&mut self, t: &toml::Table, at: &str, k: &str) -> Option<String> {
        match t.get(k) {
            None => None,
            Some(toml::Value::String(s)) => Some(s.clone()),
            Some(v) => {
                self.err(
                    &join(at, k),
                    format!("must be a string, got {}", v.type_str()),
                );
                None
            }
        }
    }

    fn count(&mut self, t: &toml::Table, at: &str, k: &str, min: i64) -> Option<usize> {
        match t.get(k) {
            None => None,
            Some(toml::Value::Integer(i)) if *i >= min => Some(*i as usize),
            Some(v) => {
                self.err(
                    &join(at, k),
                    format!("must be an integer >= {min}, got {v}"),
                );
                None
            }
        }
    }

    fn bool(&mut self, t: &toml::Table, at: &str, k: &str) -> bool {
        match t.get(k) {
            None => false,
            Some(toml::Value::Boolean(b)) => *b,
            Some(v) => {
                self.err(&join(at, k), format!("must be true or false, got {v}"));
                false
            }
        }
    }

    fn strings(&mut self, t: &toml::Table, at: &str, k: &str) -> Option<Vec<String>> {
        match t.get(k) {
            None => None,
            Some(toml::Value::String(s)) => Some(vec![s.clone()]),
            Some(toml::Value::Array(a)) => {
                let mut out = Vec::new();
                for (i, v) in a.iter().enumerate() {
                    match v {
                        toml::Value::String(s) => out.push(s.clone()),
                        _ => self.err(&format!("{}[{i}]", join(at, k)), "must be a string"),
                    }
                }
                Some(out)
            }
            Some(v) => {
                self.err(
                    &join(at, k),
                    format!("must be a list of strings, got {}", v.type_str()),
                );
                None
            }
        }
    }

    fn number(&mut self, t: &toml::Table, at: &str, k: &str) -> Option<(f64, bool)> {
        match t.get(k) {
            Some(toml::Value::Integer(i)) => Some((*i as f64, true)),
            Some(toml::Value::Float(x)) if x.is_finite() => Some((*x, false)),
            Some(v) => {
                self.err(&join(at, k), format!("must be a finite number, got {v}"));
                None
            }
            None => {
                self.err(&join(at, k), "missing");
                None
            }
        }
    }

    /// One column: `key` plus exactly one of `values`, `linear`, `geometric`.
    fn column(&mut self, t: &toml::Table, at: &str, zipped: bool) -> Option<Column> {
        let mut known = vec!["key", "values", "linear", "geometric", "unit"];
        if !zipped {
            known.push("zip");
        }
        self.unknown_keys(t, at, &known);
        let key = match t.get("key") {
            Some(toml::Value::String(s)) if valid_scene_key(s) => Some(s.clone()),
            Some(toml::Value::String(s)) => {
                self.err(
                    &join(at, "key"),
                    format!("`{s}` is not a dotted scene key like `road.v0`"),
                );
                None
            }
            Some(v) => {
                self.err(
                    &join(at, "key"),
                    format!("must be a string, got {}", v.type_str()),
                );
                None
            }
            None => {
                self.err(
                    &join(at, "key"),
                    "missing (the scene key to sweep, e.g. `road.v0`)",
                );
                None
            }
        };
        let unit = self.string(t, at, "unit");
        let given: Vec<&str> = ["values", "linear", "geometric"]
            .into_iter()
            .filter(|k| t.contains_key(*k))
            .collect();
        if given.len() != 1 {
            self.err(
                at,
                format!(
                    "give exactly one of `values`, `linear`, `geometric` (got {})",
                    if given.is_empty() {
                        "none".to_string()
                    } else {
                        given.join(", ")
                    }
                ),
            );
            return None;
        }
        let (values, geometric) = match given[0] {
            "values" => match t.get("values") {
                Some(toml::Value::Array(a)) if !a.is_empty() => (a.clone(), false),
                Some(v) => {
                    self.err(
                        &join(at, "values"),
                        format!("must be a non-empty list, got {v}"),
                    );
                    return None;
                }
                None => return None,
            },
            which => {
                let at_r = join(at, which);
                let Some(toml::Value::Table(r)) = t.get(which) else {
                    self.err(
                        &at_r,
                        "must be a table like { start = 1.0, stop = 2.0, num = 5 }",
                    );
                    return None;
                };
                (
                    self.range(r, &at_r, which == "geometric")?,
                    which == "geometric",
                )
            }
        };
        Some(Column {
            key: key?,
            values,
            geometric,
            unit,
        })
    }

    fn range(&mut self, r: &toml::Table, at: &str, geometric: bool) -> Option<Vec<toml::Value>> {
        let known: &[&str] = if geometric {
            &["start", "stop", "num"]
        } else {
            &["start", "stop", "num", "step"]
        };
        self.unknown_keys(r, at, known);
        let start = self.number(r, at, "start");
        let stop = self.number(r, at, "stop");
        let (Some((a, ai)), Some((b, bi))) = (start, stop) else {
            return None;
        };
        let ints;
        let xs: Vec<f64> = if !geometric && r.contains_key("step") {
            if r.contains_key("num") {
                self.err(at, "give `num` or `step`, not both");
                return None;
            }
            let (s, si) = self.number(r, at, "step")?;
            if s == 0.0 || (b - a) * s < 0.0 {
                self.err(
                    &join(at, "step"),
                    format!("{s} does not lead from {a} to {b}"),
                );
                return None;
            }
            let n = ((b - a) / s + 1e-9).floor() as usize + 1;
            if n > 1_000_000 {
                self.err(at, format!("{n} values: too many"));
                return None;
            }
            ints = ai && bi && si;
            (0..n).map(|i| tidy(a + i as f64 * s)).collect()
        } else {
            let n = match r.get("num") {
                Some(toml::Value::Integer(n)) if (1..=1_000_000).contains(n) => *n as usize,
                Some(v) => {
                    self.err(
                        &join(at, "num"),
                        format!("must be an integer in 1..=1000000, got {v}"),
                    );
                    return None;
                }
                None => {
                    self.err(&join(at, "num"), "missing (the number of values)");
                    return None;
                }
            };
            if geometric && (a == 0.0 || b == 0.0 || (a < 0.0) != (b < 0.0)) {
                self.err(
                    at,
                    format!("a geometric range needs start and stop of the same sign, non-zero; got {a} and {b}"),
                );
                return None;
            }
            ints = ai && bi;
            if ints && !geometric && n > 1 && (b - a) % (n as f64 - 1.0) != 0.0 {
                self.err(
                    at,
                    format!("integer range {a}..{b} cannot be split into {n} equal integer steps (write start or stop as a float)"),
                );
                return None;
            }
            (0..n)
                .map(|i| {
                    if n == 1 {
                        a
                    } else if i == n - 1 {
                        b
                    } else {
                        let s = i as f64 / (n - 1) as f64;
                        if geometric {
                            tidy(a * (b / a).powf(s))
                        } else {
                            tidy(a + s * (b - a))
                        }
                    }
                })
                .collect()
        };
        if ints {
            let v: Vec<i64> = xs.iter().map(|x| x.round() as i64).collect();
            if v.windows(2).any(|w| w[0] == w[1]) {
                self.err(
                    at,
                    format!("rounding to integers gives repeated values {v:?}: use fewer points"),
                );
                return None;
            }
            Some(v.into_iter().map(toml::Value::Integer).collect())
        } else {
            Some(xs.into_iter().map(toml::Value::Float).collect())
        }
    }
}

fn join(at: &str, k: &str) -> String {
    if at.is_empty() {
        k.to_string()
    } else {
        format!("{at}.{k}")
    }
}

fn valid_scene_key(s: &str) -> bool {
    let parts: Vec<&str> = s.split('.').collect();
    parts.len() >= 2
        && parts.iter().all(|p| {
            !p.is_empty()
                && p.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        })
}

pub(crate) fn valid_name(s: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

impl Spec {
    /// Read and check a spec file (every problem at once). The base scene is read too but not
    /// validated here: see [`super::plan::check`].
    pub fn load(path: &Path) -> Result<Spec, SpecErrors> {
        let source = path.display().to_string();
        let fail = |e: String| SpecErrors {
            source: source.clone(),
            errors: vec![e],
        };
        let text = std::fs::read_to_string(path)
            .map_err(|e| fail(format!("cannot read the sweep spec: {e}")))?;
        let abs =
            std::path::absolute(path).map_err(|e| fail(format!("cannot resolve the path: {e}")))?;
        Spec::from_toml_str(&text, &abs)
    }

    /// Parse a spec whose file is `path` (absolute; the base scene is relative to its folder).
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Spec, SpecErrors> {
        let source = path.display().to_string();
        let doc: toml::Table = text.parse().map_err(|e: toml::de::Error| SpecErrors {
            source: source.clone(),
            errors: vec![format!("TOML syntax: {}", e.to_string().trim_end())],
        })?;
        let mut w = Walker { errors: Vec::new() };
        w.unknown_keys(
            &doc,
            "",
            &["sweep", "axis", "outputs", "units", "plot", "slurm"],
        );
        let empty = toml::Table::new();
        let table = |w: &mut Walker, k: &str| -> toml::Table {
            match doc.get(k) {
                None => empty.clone(),
                Some(toml::Value::Table(t)) => t.clone(),
                Some(_) => {
                    w.err(k, "must be a table ([section])");
                    empty.clone()
                }
            }
        };

        let sw = table(&mut w, "sweep");
        if !doc.contains_key("sweep") {
            w.err("sweep", "missing section [sweep] (with `name` and `scene`)");
        }
        w.unknown_keys(&sw, "sweep", &["name", "scene", "description"]);
        let name = w.string(&sw, "sweep", "name");
        match &name {
            Some(n) if !valid_name(n) => w.err(
                "sweep.name",
                format!("`{n}` must be letters, digits, `_` or `-` (it names the sweep folder)"),
            ),
            None if doc.contains_key("sweep") => w.err("sweep.name", "missing"),
            _ => {}
        }
        let description = w.string(&sw, "sweep", "description").unwrap_or_default();
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut scene_path = PathBuf::new();
        let mut scene_text = String::new();
        match w.string(&sw, "sweep", "scene") {
            Some(s) => {
                scene_path = dir.join(&s);
                match std::fs::read_to_string(&scene_path) {
                    Ok(t) => scene_text = t,
                    Err(e) => w.err(
                        "sweep.scene",
                        format!("cannot read the base scene {}: {e}", scene_path.display()),
                    ),
                }
            }
            None if doc.contains_key("sweep") => {
                w.err("sweep.scene", "missing (the base scene file)")
            }
            None => {}
        }

        let mut axes = Vec::new();
        match doc.get("axis") {
            None => w.err("axis", "missing: give at least one [[axis]]"),
            Some(toml::Value::Array(a)) if !a.is_empty() => {
                for (i, v) in a.iter().enumerate() {
                    let at = format!("axis[{i}]");
                    let Some(t) = v.as_table() else {
                        w.err(&at, "must be a table ([[axis]])");
                        continue;
                    };
                    if let Some(z) = t.get("zip") {
                        w.unknown_keys(t, &at, &["zip"]);
                        let Some(items) = z.as_array().filter(|a| !a.is_empty()) else {
                            w.err(&format!("{at}.zip"), "must be a non-empty list of tables");
                            continue;
                        };
                        let mut cols = Vec::new();
                        for (j, item) in items.iter().enumerate() {
                            let at_j = format!("{at}.zip[{j}]");
                            match item.as_table() {
                                Some(ct) => cols.extend(w.column(ct, &at_j, true)),
                                None => w.err(&at_j, "must be a table { key = …, values = … }"),
                            }
                        }
                        if cols.len() == items.len() {
                            let n = cols[0].values.len();
                            if let Some(c) = cols.iter().find(|c| c.values.len() != n) {
                                w.err(
                                    &format!("{at}.zip"),
                                    format!(
                                        "zipped keys need equal lengths: `{}` has {n} values, `{}` has {}",
                                        cols[0].key,
                                        c.key,
                                        c.values.len()
                                    ),
                                );
                            } else {
                                axes.push(Axis { columns: cols });
                            }
                        }
                    } else if let Some(c) = w.column(t, &at, false) {
                        axes.push(Axis { columns: vec![c] });
                    }
                }
            }
            Some(_) => w.err("axis", "must be a list of tables ([[axis]])"),
        }
        // A key swept twice would make the later override silently win.
        let mut seen = BTreeMap::new();
        for c in axes.iter().flat_map(|a| a.columns.iter()) {
            if seen.insert(c.key.clone(), ()).is_some() {
                w.err(&c.key, "is swept by two axes");
            }
        }
        let n_runs = axes
            .iter()
            .try_fold(1usize, |acc, a| acc.checked_mul(a.len()));
        match n_runs {
            Some(n) if n <= 10_000_000 => {}
            _ => w.err(
                "axis",
                "the product of the axes has more than 10 million runs",
            ),
        }

        let out = table(&mut w, "outputs");
        w.unknown_keys(&out, "outputs", &["sinks", "results"]);
        let sinks = w.strings(&out, "outputs", "sinks");
        if seen.contains_key("output.sinks") && sinks.is_some() {
            w.err("outputs.sinks", "`output.sinks` is also swept by an axis");
        }
        let results = w.strings(&out, "outputs", "results").unwrap_or_default();

        let mut units = BTreeMap::new();
        for (k, v) in table(&mut w, "units") {
            match v {
                toml::Value::String(s) => {
                    units.insert(k, s);
                }
                _ => w.err(&format!("units.{k}"), "must be a string like \"lbf/in\""),
            }
        }

        let mut plots = Vec::new();
        match doc.get("plot") {
            None => {}
            Some(toml::Value::Array(a)) => {
                for (i, v) in a.iter().enumerate() {
                    let at = format!("plot[{i}]");
                    let Some(t) = v.as_table() else {
                        w.err(&at, "must be a table ([[plot]])");
                        continue;
                    };
                    w.unknown_keys(t, &at, &["x", "y", "file", "title", "log_x", "log_y"]);
                    let x = w.string(t, &at, "x");
                    let y = w.strings(t, &at, "y").unwrap_or_default();
                    if x.is_none() {
                        w.err(&join(&at, "x"), "missing (a swept key)");
                    }
                    if y.is_empty() {
                        w.err(&join(&at, "y"), "missing (result keys)");
                    }
                    let file = w.string(t, &at, "file");
                    let title = w.string(t, &at, "title").unwrap_or_default();
                    let log_x = w.bool(t, &at, "log_x");
                    let log_y = w.bool(t, &at, "log_y");
                    if let Some(f) = &file {
                        let stem = f.strip_suffix(".png").unwrap_or("");
                        if !valid_name(stem) {
                            w.err(
                                &join(&at, "file"),
                                format!("`{f}` must be a plain file name ending in .png"),
                            );
                        }
                    }
                    if let Some(x) = x {
                        let file = file.unwrap_or_else(|| {
                            format!("{}_vs_{}.png", y.first().map_or("y", |s| s.as_str()), x)
                                .replace(['.', '/', ' '], "_")
                                .replacen("_png", ".png", 1)
                        });
                        plots.push(PlotSpec {
                            x,
                            y,
                            file,
                            title,
                            log_x,
                            log_y,
                        });
                    }
                }
            }
            Some(_) => w.err("plot", "must be a list of tables ([[plot]])"),
        }
        // Plots name swept keys and results, each with a unit.
        let unit_of = |k: &str| -> Option<String> {
            axes.iter()
                .flat_map(|a| a.columns.iter())
                .find(|c| c.key == k)
                .and_then(|c| c.unit.clone())
                .or_else(|| units.get(k).cloned())
        };
        for (i, p) in plots.iter().enumerate() {
            let at = format!("plot[{i}]");
            if !seen.contains_key(&p.x) {
                w.err(&join(&at, "x"), format!("`{}` is not a swept key", p.x));
            }
            if seen.contains_key(&p.x) && unit_of(&p.x).is_none() {
                w.err(
                    &join(&at, "x"),
                    format!(
                        "`{}` has no unit: give the axis a `unit` (\"1\" if dimensionless)",
                        p.x
                    ),
                );
            }
            for y in &p.y {
                if !results.is_empty() && !results.contains(y) {
                    w.err(
                        &join(&at, "y"),
                        format!("`{y}` is not in [outputs] results"),
                    );
                }
                if unit_of(y).is_none() {
                    w.err(
                        &join(&at, "y"),
                        format!("`{y}` has no unit: add `{y} = \"…\"` to [units] (\"1\" if dimensionless)"),
                    );
                }
            }
            let ys: Vec<String> = p.y.iter().filter_map(|y| unit_of(y)).collect();
            if ys.windows(2).any(|u| u[0] != u[1]) {
                w.err(
                    &join(&at, "y"),
                    format!("the results of one plot share its y axis, so they need one unit (got {}): make one plot per unit", ys.join(", ")),
                );
            }
        }
        for (i, a) in plots.iter().enumerate() {
            if plots[..i].iter().any(|b| b.file == a.file) {
                w.err(
                    &format!("plot[{i}].file"),
                    format!("`{}` is used by two plots", a.file),
                );
            }
        }

        let sl = table(&mut w, "slurm");
        w.unknown_keys(
            &sl,
            "slurm",
            &[
                "partition",
                "time",
                "cpus_per_task",
                "mem",
                "throttle",
                "pack",
                "max_array_size",
                "extra",
            ],
        );
        let slurm = SlurmSpec {
            partition: w.string(&sl, "slurm", "partition"),
            time: w.string(&sl, "slurm", "time"),
            cpus_per_task: w.count(&sl, "slurm", "cpus_per_task", 1),
            mem: w.string(&sl, "slurm", "mem"),
            throttle: w.count(&sl, "slurm", "throttle", 1),
            pack: w.count(&sl, "slurm", "pack", 1),
            max_array_size: w.count(&sl, "slurm", "max_array_size", 1),
            extra: w.strings(&sl, "slurm", "extra").unwrap_or_default(),
        };
        for e in check_resources(&slurm) {
            w.errors.push(e);
        }

        if !w.errors.is_empty() {
            return Err(SpecErrors {
                source,
                errors: w.errors,
            });
        }
        Ok(Spec {
            name: name.unwrap_or_default(),
            description,
            path: path.to_path_buf(),
            scene_path,
            scene_text,
            axes,
            sinks,
            results,
            units,
            plots,
            slurm,
        })
    }

    /// Number of runs (the product of the axis lengths).
    pub fn n_runs(&self) -> usize {
        self.axes.iter().map(Axis::len).product()
    }

    /// The swept keys in table order (axes in order, zipped keys in order).
    pub fn keys(&self) -> Vec<&str> {
        self.axes
            .iter()
            .flat_map(|a| a.columns.iter().map(|c| c.key.as_str()))
            .collect()
    }

    /// The column of a swept key.
    pub fn column(&self, key: &str) -> Option<&Column> {
        self.axes
            .iter()
            .flat_map(|a| a.columns.iter())
            .find(|c| c.key == key)
    }

    /// Unit of a swept key or of a result, if given.
    pub fn unit_of(&self, key: &str) -> Option<&str> {
        self.column(key)
            .and_then(|c| c.unit.as_deref())
            .or_else(|| self.units.get(key).map(String::as_str))
    }

    /// Run `index` (last axis fastest). Panics if `index >= n_runs()`: callers check.
    pub fn run(&self, index: usize) -> Run {
        let mut params = Vec::new();
        let mut rest = index;
        let mut digits = vec![0; self.axes.len()];
        for (k, a) in self.axes.iter().enumerate().rev() {
            digits[k] = rest % a.len();
            rest /= a.len();
        }
        for (a, d) in self.axes.iter().zip(digits) {
            for c in &a.columns {
                params.push((c.key.clone(), c.values[d].clone()));
            }
        }
        Run { index, params }
    }

    /// The `--set` overrides of a run: its swept values, then `output.sinks` if given.
    pub fn overrides(&self, run: &Run) -> Vec<String> {
        let mut v: Vec<String> = run
            .params
            .iter()
            .map(|(k, x)| format!("{k}={}", value_text(x)))
            .collect();
        if let Some(s) = &self.sinks {
            let list: Vec<String> = s.iter().map(|x| format!("\"{x}\"")).collect();
            v.push(format!("output.sinks=[{}]", list.join(", ")));
        }
        v
    }

    /// Width of the run folder names (`runs/0007`): at least 4 digits.
    pub fn index_width(&self) -> usize {
        let n = self.n_runs().max(1) - 1;
        n.to_string().len().max(4)
    }

    /// Folder name of run `index`.
    pub fn run_name(&self, index: usize) -> String {
        format!("{index:0w$}", w = self.index_width())
    }

    /// A fingerprint of what a run computes: the base scene text and its overrides. A run
    /// folder marked done counts as done only while this matches (editing the base scene or
    /// the values reruns it; editing plots or resources does not).
    pub fn run_fingerprint(&self, run: &Run) -> String {
        let mut s = String::new();
        let _ = write!(s, "{}\u{0}", self.scene_text);
        for o in self.overrides(run) {
            let _ = write!(s, "{o}\u{0}");
        }
        format!("{:016x}", fnv1a(s.as_bytes()))
    }
}

/// 64-bit FNV-1a.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

pub(super) fn valid_time(t: &str) -> bool {
    let num = |s: &str| !s.is_empty() && s.len() <= 4 && s.chars().all(|c| c.is_ascii_digit());
    let (days, rest) = match t.split_once('-') {
        Some((d, r)) => (Some(d), r),
        None => (None, t),
    };
    if days.is_some_and(|d| !num(d)) {
        return false;
    }
    let parts: Vec<&str> = rest.split(':').collect();
    if !parts.iter().all(|p| num(p)) {
        return false;
    }
    (1..=3).contains(&parts.len())
}

pub(super) fn valid_mem(m: &str) -> bool {
    let digits = m.trim_end_matches(['K', 'M', 'G', 'T', 'k', 'm', 'g', 't']);
    !digits.is_empty() && digits.chars().all(|c| c.is_ascii_digit()) && m.len() - digits.len() <= 1
}

/// Problems with the Slurm resources (as `key `slurm.x`: …` lines).
pub fn check_resources(s: &SlurmSpec) -> Vec<String> {
    let mut e = Vec::new();
    if let Some(p) = &s.partition {
        if p.is_empty()
            || !p
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "_-.,".contains(c))
        {
            e.push(format!(
                "key `slurm.partition`: `{p}` is not a partition name"
            ));
        }
    }
    if let Some(t) = &s.time {
        if !valid_time(t) {
            e.push(format!(
                "key `slurm.time`: `{t}` is not a Slurm time (MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS)"
            ));
        }
    }
    if let Some(m) = &s.mem {
        if !valid_mem(m) {
            e.push(format!(
                "key `slurm.mem`: `{m}` is not a memory size (megabytes, or a number with K, M, G or T)"
            ));
        }
    }
    for (i, x) in s.extra.iter().enumerate() {
        if !x.starts_with("--") || x.contains('\n') {
            e.push(format!(
                "key `slurm.extra[{i}]`: `{x}` must be one sbatch option like `--account=proj`"
            ));
        }
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(text: &str) -> Result<Spec, SpecErrors> {
        let dir = std::env::temp_dir().join(format!("tread-spec-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("base.toml"), "[scene]\nname = \"x\"\n").unwrap();
        Spec::from_toml_str(text, &dir.join("spec.toml"))
    }

    const HEAD: &str = "[sweep]\nname = \"t\"\nscene = \"base.toml\"\n";

    #[test]
    fn product_order_last_axis_fastest_and_zip() {
        let s = spec(&format!(
            "{HEAD}[[axis]]\nkey = \"a.x\"\nvalues = [1, 2]\n[[axis]]\nzip = [{{ key = \"b.y\", values = [\"p\", \"q\", \"r\"] }}, {{ key = \"c.z\", linear = {{ start = 0.0, stop = 1.0, num = 3 }} }}]\n"
        ))
        .unwrap();
        assert_eq!(s.n_runs(), 6);
        assert_eq!(s.keys(), vec!["a.x", "b.y", "c.z"]);
        let r = s.run(4);
        assert_eq!(s.overrides(&r), vec!["a.x=2", "b.y=\"q\"", "c.z=0.5"]);
        let r = s.run(2);
        assert_eq!(s.overrides(&r), vec!["a.x=1", "b.y=\"r\"", "c.z=1.0"]);
    }

    #[test]
    fn ranges_are_tidy_and_typed() {
        let s = spec(&format!(
            "{HEAD}[[axis]]\nkey = \"a.x\"\nlinear = {{ start = 0.1, stop = 0.5, step = 0.1 }}\n[[axis]]\nkey = \"b.n\"\ngeometric = {{ start = 8, stop = 64, num = 4 }}\n[[axis]]\nkey = \"c.g\"\ngeometric = {{ start = 1e-3, stop = 1e-1, num = 3 }}\n"
        ))
        .unwrap();
        let a: Vec<String> = s.axes[0].columns[0].values.iter().map(value_text).collect();
        assert_eq!(a, vec!["0.1", "0.2", "0.3", "0.4", "0.5"]);
        assert_eq!(
            s.axes[1].columns[0].values,
            [8, 16, 32, 64].map(toml::Value::Integer).to_vec()
        );
        let g: Vec<String> = s.axes[2].columns[0].values.iter().map(value_text).collect();
        assert_eq!(g, vec!["0.001", "0.01", "0.1"]);
        assert!(s.axes[2].columns[0].geometric);
        // Every value reads back through the scene's override parser as the same number.
        for v in &s.axes[0].columns[0].values {
            let t: toml::Table = format!("v = {}", value_text(v)).parse().unwrap();
            assert_eq!(&t["v"], v);
        }
    }

    #[test]
    fn every_error_at_once_with_its_key() {
        let e = spec(
            "[sweep]\nname = \"bad name\"\nscene = \"missing.toml\"\nfoo = 1\n[[axis]]\nkey = \"nodot\"\nvalues = [1]\n[[axis]]\nkey = \"a.b\"\nlinear = { start = 1.0, stop = 2.0 }\n[[axis]]\nzip = [{ key = \"c.d\", values = [1, 2] }, { key = \"e.f\", values = [1] }]\n[[plot]]\nx = \"a.b\"\ny = [\"r\"]\n[slurm]\ntime = \"forever\"\n",
        )
        .unwrap_err();
        let all = e.to_string();
        for k in [
            "key `sweep.name`",
            "key `sweep.scene`: cannot read",
            "key `sweep.foo`: unknown key",
            "key `axis[0].key`",
            "key `axis[1].linear.num`: missing",
            "key `axis[2].zip`: zipped keys need equal lengths",
            "key `plot[0].x`: `a.b` is not a swept key",
            "key `plot[0].y`: `r` has no unit",
            "key `slurm.time`",
        ] {
            assert!(all.contains(k), "missing `{k}` in:\n{all}");
        }
        assert_eq!(e.errors.len(), 9, "{all}");
    }

    #[test]
    fn integer_ranges_that_do_not_split_evenly_are_rejected() {
        let e = spec(&format!(
            "{HEAD}[[axis]]\nkey = \"a.n\"\nlinear = {{ start = 1, stop = 4, num = 3 }}\n"
        ))
        .unwrap_err();
        assert!(e.to_string().contains("equal integer steps"), "{e}");
        let e = spec(&format!(
            "{HEAD}[[axis]]\nkey = \"a.n\"\ngeometric = {{ start = 1, stop = 3, num = 5 }}\n"
        ))
        .unwrap_err();
        assert!(e.to_string().contains("repeated values"), "{e}");
    }
}
