//! Result files: `summary.json`, CSV tables. Every writer creates the output directory and
//! reports failures as typed errors naming the file.

use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {source}")]
pub struct OutputError {
    pub path: PathBuf,
    #[source]
    pub source: std::io::Error,
}

fn wrap(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError {
        path: path.to_path_buf(),
        source,
    }
}

pub fn ensure_dir(dir: &Path) -> Result<(), OutputError> {
    std::fs::create_dir_all(dir).map_err(wrap(dir))
}

/// Write pretty JSON atomically (temporary file, then rename) so a crash never leaves a
/// truncated summary.
pub fn write_json(path: &Path, value: &serde_json::Value) -> Result<(), OutputError> {
    let tmp = path.with_extension("json.tmp");
    let text = serde_json::to_string_pretty(value).map_err(|e| OutputError {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    })?;
    std::fs::write(&tmp, text + "\n").map_err(wrap(&tmp))?;
    std::fs::rename(&tmp, path).map_err(wrap(path))
}

/// Write a CSV with a header; non-finite values are written as empty fields (never "NaN").
pub fn write_csv(
    path: &Path,
    header: &[&str],
    rows: impl Iterator<Item = Vec<f64>>,
) -> Result<(), OutputError> {
    let f = std::fs::File::create(path).map_err(wrap(path))?;
    let mut w = std::io::BufWriter::new(f);
    writeln!(w, "{}", header.join(",")).map_err(wrap(path))?;
    for row in rows {
        let cells: Vec<String> = row
            .iter()
            .map(|v| {
                if v.is_finite() {
                    format!("{v:.12e}")
                } else {
                    String::new()
                }
            })
            .collect();
        writeln!(w, "{}", cells.join(",")).map_err(wrap(path))?;
    }
    w.flush().map_err(wrap(path))
}

/// Replace non-finite numbers in a JSON tree by null (JSON has no NaN).
pub fn sanitize(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Number(n) => {
            if n.as_f64().is_some_and(|x| !x.is_finite()) {
                *v = serde_json::Value::Null;
            }
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(sanitize),
        serde_json::Value::Object(o) => o.values_mut().for_each(sanitize),
        _ => {}
    }
}
