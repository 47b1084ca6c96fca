//! Result files: `summary.json`, CSV tables. Every writer creates the output directory and
//! reports failures as typed errors naming the file.

use std::io::Write;
use std::path::{Path, PathBuf};

#[cfg(test)]
mod tests {
    use super::fmt_num;

    #[test]
    fn numbers_round_trip_and_integers_stay_integers() {
        for v in [
            0.1,
            86.6,
            -97.84,
            1.0 / 3.0,
            1e-14,
            6.02214076e23,
            f64::MIN_POSITIVE,
            f64::MAX,
            -1.5e-7,
            123456.789,
        ] {
            let t = fmt_num(v);
            assert_eq!(t.parse::<f64>().unwrap(), v, "{t}");
            assert!(t.len() <= 24, "{t}");
        }
        assert_eq!(fmt_num(60.0), "60");
        assert_eq!(fmt_num(-0.0), "0");
        assert_eq!(fmt_num(1.0), "1");
        assert_eq!(fmt_num(1e300), "1e300");
    }

    #[test]
    fn long_numbers_in_messages_are_shortened() {
        let long = format!("ri = {}, ro = 2, n_r = 12345678", 1e300);
        assert_eq!(
            super::tidy_numbers(&long),
            "ri = 1e300, ro = 2, n_r = 12345678"
        );
        let tiny = format!("x = {} in", 1e-300);
        assert_eq!(super::tidy_numbers(&tiny), "x = 1e-300 in");
        assert_eq!(super::tidy_numbers("θ: é 3.5"), "θ: é 3.5");
    }
}

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
    let text = serde_json::to_string_pretty(value).map_err(|e| OutputError {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    })?;
    write_atomic(path, (text + "\n").as_bytes())
}

/// A number as the shortest text that reads back to the same `f64` (Rust's `Display`/`LowerExp`
/// give the shortest round-trip digits): integers as integers (`60`), moderate magnitudes in
/// plain decimal (`86.6`, `0.0125`), others in exponent form (`1.5e-7`, `2e20`); −0 as `0`;
/// non-finite values as `NaN`, `inf`, `-inf`.
pub fn fmt_num(v: f64) -> String {
    let v = v + 0.0;
    let a = v.abs();
    if !v.is_finite() {
        if v.is_nan() {
            "NaN".into()
        } else if v > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        }
    } else if v == v.trunc() && a < 1e15 {
        format!("{}", v as i64)
    } else if (1e-4..1e15).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// `text` with every decimal number longer than 17 digits (how `{}` prints 1e300 or 1e-300)
/// rewritten by [`fmt_num`] (`1e300`), for messages shown to a user.
pub fn tidy_numbers(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
        if !starts {
            let ch = text[i..].chars().next().unwrap_or(' ');
            out.push(ch);
            i += ch.len_utf8();
            continue;
        }
        let mut j = i;
        while j < b.len() && (b[j].is_ascii_digit() || b[j] == b'.') {
            j += 1;
        }
        let tok = &text[i..j];
        let digits = tok.bytes().filter(u8::is_ascii_digit).count();
        match tok.parse::<f64>() {
            Ok(v) if digits > 17 => out.push_str(&fmt_num(v)),
            _ => out.push_str(tok),
        }
        i = j;
    }
    out
}

/// One CSV line (with its line break) of `fields`, quoted by the csv crate where a field
/// needs it (RFC 4180: a comma, a quote or a line break).
pub fn csv_line<S: AsRef<str>>(fields: &[S]) -> String {
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    // Writing into memory cannot fail.
    let _ = w.write_record(fields.iter().map(|f| f.as_ref()));
    let bytes = w.into_inner().unwrap_or_default();
    String::from_utf8(bytes).unwrap_or_default()
}

/// Write a CSV of text fields with a header through the csv crate (fields quoted where they
/// need it), under a temporary name renamed when complete (a full disk or a crash never
/// leaves a truncated table under the final name).
pub fn write_text_csv<S: AsRef<str>>(
    path: &Path,
    header: &[&str],
    rows: impl IntoIterator<Item = Vec<S>>,
) -> Result<(), OutputError> {
    let tmp = tmp_path(path);
    let written = write_text_csv_to(&tmp, header, rows);
    if written.is_err() {
        // A full disk: no partial temporary left behind.
        let _ = std::fs::remove_file(&tmp);
    }
    written?;
    std::fs::rename(&tmp, path).map_err(wrap(path))
}

fn write_text_csv_to<S: AsRef<str>>(
    tmp: &Path,
    header: &[&str],
    rows: impl IntoIterator<Item = Vec<S>>,
) -> Result<(), OutputError> {
    let tmp = tmp.to_path_buf();
    let f = std::fs::File::create(&tmp).map_err(wrap(&tmp))?;
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .flexible(true)
        .from_writer(std::io::BufWriter::new(f));
    let io = |e: csv::Error| match e.into_kind() {
        csv::ErrorKind::Io(e) => e,
        k => std::io::Error::other(format!("{k:?}")),
    };
    w.write_record(header).map_err(io).map_err(wrap(&tmp))?;
    for row in rows {
        w.write_record(row.iter().map(|f| f.as_ref()))
            .map_err(io)
            .map_err(wrap(&tmp))?;
    }
    let f = w
        .into_inner()
        .map_err(|e| OutputError {
            path: tmp.clone(),
            source: std::io::Error::other(e.to_string()),
        })?
        .into_inner()
        .map_err(|e| OutputError {
            path: tmp.clone(),
            source: e.into_error(),
        })?;
    f.sync_all().map_err(wrap(&tmp))
}

/// Read a CSV (header and rows of text fields) through the csv crate.
pub fn read_text_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<String>>), String> {
    let mut r = csv::ReaderBuilder::new()
        .flexible(true)
        .from_path(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let header = r
        .headers()
        .map_err(|e| format!("{}: {e}", path.display()))?
        .iter()
        .map(|s| s.trim().to_string())
        .collect();
    let mut rows = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(|e| format!("{}: {e}", path.display()))?;
        rows.push(rec.iter().map(str::to_string).collect());
    }
    Ok((header, rows))
}

/// Write a CSV of numbers with a header ([`write_text_csv`]); non-finite values are written as
/// empty fields (never "NaN"). Numbers are written by [`fmt_num`] (round trip).
pub fn write_csv(
    path: &Path,
    header: &[&str],
    rows: impl Iterator<Item = Vec<f64>>,
) -> Result<(), OutputError> {
    write_text_csv(
        path,
        header,
        rows.map(|row| {
            row.iter()
                .map(|v| {
                    if v.is_finite() {
                        fmt_num(*v)
                    } else {
                        String::new()
                    }
                })
                .collect::<Vec<String>>()
        }),
    )
}

/// `dir/.name.tmp`: where a file is written before it is renamed to `path`.
pub fn tmp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp"))
}

/// Write `bytes` to `path` through a temporary file and a rename (never a partial file under
/// the final name).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let tmp = tmp_path(path);
    let r = std::fs::File::create(&tmp).and_then(|mut f| {
        f.write_all(bytes)?;
        f.sync_all()
    });
    if let Err(e) = r {
        let _ = std::fs::remove_file(&tmp);
        return Err(OutputError {
            path: tmp,
            source: e,
        });
    }
    std::fs::rename(&tmp, path).map_err(wrap(path))
}

/// Replace non-finite numbers in a JSON tree by null (JSON has no NaN).
pub fn sanitize(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Number(n) if n.as_f64().is_some_and(|x| !x.is_finite()) => {
            *v = serde_json::Value::Null;
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(sanitize),
        serde_json::Value::Object(o) => o.values_mut().for_each(sanitize),
        _ => {}
    }
}

/// Name of the lock file a run keeps in its output folder.
pub const LOCK_FILE: &str = ".tread.lock";

/// Files (and `*.png`, `fields/step_*.vtu`) a run writes into its output folder (the rolling
/// scenes' and the model problems'); a new run
/// removes those an earlier run left, so the folder holds only this run's results.
const OUTPUT_NAMES: &[&str] = &[
    "summary.json",
    "history.csv",
    "nodes.csv",
    "profile.csv",
    "contact.csv",
    "convergence.csv",
    "passages.csv",
    "steady_field.csv",
    "branch.csv",
    "compare.csv",
    "increments.sta",
    "run.sta",
    "fields.pvd",
    "steady.vtu",
    "contact.pvd",
    "run.mcap",
    "run.rrd",
    "steps.csv",
    "solution.vtu",
];

/// The output folder of a run, held for its duration: created, checked writable, locked
/// against a second run (`.tread.lock` holds the process id; a lock left by a process that no
/// longer exists is taken over) and cleared of an earlier run's result files. The lock is
/// removed when the value is dropped.
#[derive(Debug)]
pub struct OutDirLock {
    lock: PathBuf,
    /// Result files of an earlier run that were removed.
    pub removed: usize,
}

impl OutDirLock {
    /// Take the folder `dir` (see the type's docs). Errors say what is wrong in plain words.
    pub fn take(dir: &Path) -> Result<Self, String> {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create it: {e}"))?;
        let lock = dir.join(LOCK_FILE);
        let me = std::process::id();
        for _ in 0..2 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&lock)
            {
                Ok(mut f) => {
                    f.write_all(format!("{me}\n").as_bytes())
                        .and_then(|()| f.sync_all())
                        .map_err(|e| format!("cannot write into it: {e}"))?;
                    let removed = clear_outputs(dir);
                    return Ok(Self { lock, removed });
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let text = std::fs::read_to_string(&lock).unwrap_or_default();
                    let pid: Option<u32> = text.trim().parse().ok();
                    match pid {
                        Some(p) if p != me && process_alive(p) => {
                            return Err(format!(
                                "another tread run (process {p}) is writing into it; wait for it to finish or choose another --out"
                            ));
                        }
                        // A lock left by a run that was killed: take it over.
                        _ => {
                            let _ = std::fs::remove_file(&lock);
                        }
                    }
                }
                Err(e) => return Err(format!("cannot write into it: {e}")),
            }
        }
        Err("cannot take its lock file".into())
    }
}

impl Drop for OutDirLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.lock);
    }
}

fn process_alive(pid: u32) -> bool {
    let proc = Path::new("/proc");
    if proc.join("self").exists() {
        proc.join(pid.to_string()).exists()
    } else {
        // Without /proc the owner cannot be checked: assume it runs.
        true
    }
}

/// Remove the result files an earlier run left in `dir` (and in the `transient/` and
/// `steady/` folders of a comparison). Returns how many were removed.
fn clear_outputs(dir: &Path) -> usize {
    let mut n = 0;
    for d in [dir.to_path_buf(), dir.join("transient"), dir.join("steady")] {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().to_string();
            let ours = OUTPUT_NAMES.contains(&name.as_str())
                || name.ends_with(".png")
                || (name.starts_with('.')
                    && (name.ends_with(".tmp") || name.ends_with(".tmp.png")));
            if ours && e.path().is_file() && std::fs::remove_file(e.path()).is_ok() {
                n += 1;
            }
        }
        let Ok(entries) = std::fs::read_dir(d.join("fields")) else {
            continue;
        };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().to_string();
            if name.starts_with("step_")
                && (name.ends_with(".vtu") || name.ends_with(".tmp"))
                && std::fs::remove_file(e.path()).is_ok()
            {
                n += 1;
            }
        }
    }
    n
}
