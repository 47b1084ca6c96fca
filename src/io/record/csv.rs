//! CSV sink: `history.csv`, one row per accepted step (not decimated by `[output] every`, which
//! thins the fields only): `step, time` and the named series of the view
//! ([`StepView::series`]: Newton iterations, hub forces and torque, energies, contact
//! resultants, …; the columns are fixed by the first recorded step). Numbers are written by
//! [`crate::io::output::fmt_num`] (shortest text that reads back to the same value; integers as
//! integers). Every row is flushed, so a killed run leaves a complete file up to its last
//! step; a failed write (full disk) truncates the file back to its last complete row.
//! Non-finite values are empty fields. Lines are written by the csv crate
//! ([`crate::io::output::csv_line`]).

use super::{RecordError, Recorder, RunEnd, StepInfo, StepView};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

pub struct CsvSink {
    path: PathBuf,
    out: Option<BufWriter<File>>,
    columns: Vec<&'static str>,
    error: Option<RecordError>,
    rows: u64,
    /// Bytes of the header and the complete rows written so far.
    bytes_ok: u64,
    line: String,
}

impl CsvSink {
    /// Writes `dir/history.csv`.
    pub fn new(dir: &Path) -> Self {
        Self {
            path: dir.join("history.csv"),
            out: None,
            columns: Vec::new(),
            error: None,
            rows: 0,
            bytes_ok: 0,
            line: String::new(),
        }
    }

    fn write_row(
        &mut self,
        info: &StepInfo,
        series: &[(&'static str, f64)],
    ) -> std::io::Result<()> {
        use crate::io::output::csv_line;
        self.line.clear();
        if self.out.is_none() {
            self.out = Some(BufWriter::new(File::create(&self.path)?));
            self.columns = series.iter().map(|(n, _)| *n).collect();
            let mut head = vec!["step", "time"];
            head.extend(self.columns.iter().copied());
            self.line.push_str(&csv_line(&head));
        }
        let mut row = vec![info.index.to_string(), fmt(info.time)];
        for c in &self.columns {
            let v = series
                .iter()
                .find(|(n, _)| n == c)
                .map_or(f64::NAN, |(_, v)| *v);
            row.push(fmt(v));
        }
        self.line.push_str(&csv_line(&row));
        let Some(w) = self.out.as_mut() else {
            return Ok(());
        };
        let r = w.write_all(self.line.as_bytes()).and_then(|()| w.flush());
        if let Err(e) = r {
            // Drop the partial row (and what is still buffered, which dropping the writer would
            // try to flush): the file stays a valid table up to its last whole row.
            if let Some(w) = self.out.take() {
                let (f, _) = w.into_parts();
                let _ = f.set_len(self.bytes_ok);
            }
            return Err(e);
        }
        self.bytes_ok += self.line.len() as u64;
        self.rows += 1;
        Ok(())
    }
}

fn fmt(v: f64) -> String {
    if v.is_finite() {
        crate::io::output::fmt_num(v)
    } else {
        String::new()
    }
}

impl Recorder for CsvSink {
    fn wants_view(&self, _info: &StepInfo) -> bool {
        self.error.is_none()
    }
    /// The scalars of every step ([`StepView::series`]): no recovered fields.
    fn wants_fields(&self, _info: &StepInfo) -> bool {
        false
    }
    fn step(&mut self, info: &StepInfo, view: Option<&StepView>) {
        let Some(view) = view else { return };
        if self.error.is_some() {
            return;
        }
        let series = view.series(info);
        if let Err(e) = self.write_row(info, &series) {
            self.error = Some(RecordError::new("csv", &self.path, e));
        }
    }
    fn run_finished(&mut self, _end: &RunEnd) -> Vec<RecordError> {
        if let Some(mut w) = self.out.take() {
            if let Err(e) = w.flush() {
                self.error
                    .get_or_insert(RecordError::new("csv", &self.path, e));
            }
        }
        // A table that could not get even its header (a full disk) is removed rather than left
        // empty under its name; summary.json lists it as incomplete.
        if self.error.is_some() && std::fs::metadata(&self.path).is_ok_and(|m| m.len() == 0) {
            let _ = std::fs::remove_file(&self.path);
        }
        self.error.take().into_iter().collect()
    }
}
