//! CSV sink: `history.csv`, one row per recorded step: `step, time` and the named series of the
//! view ([`StepView::series`]: Newton iterations, hub forces and torque, energies, contact
//! resultants, …; the columns are fixed by the first recorded step). Every row is flushed, so a
//! killed run leaves a complete file up to its last recorded step. Non-finite values are empty
//! fields.

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
        }
    }

    fn write_row(
        &mut self,
        info: &StepInfo,
        series: &[(&'static str, f64)],
    ) -> std::io::Result<()> {
        if self.out.is_none() {
            let mut w = BufWriter::new(File::create(&self.path)?);
            self.columns = series.iter().map(|(n, _)| *n).collect();
            write!(w, "step,time")?;
            for c in &self.columns {
                write!(w, ",{c}")?;
            }
            writeln!(w)?;
            self.out = Some(w);
        }
        let Some(w) = self.out.as_mut() else {
            return Ok(());
        };
        write!(w, "{},{}", info.index, fmt(info.time))?;
        for c in &self.columns {
            let v = series
                .iter()
                .find(|(n, _)| n == c)
                .map_or(f64::NAN, |(_, v)| *v);
            write!(w, ",{}", fmt(v))?;
        }
        writeln!(w)?;
        w.flush()?;
        self.rows += 1;
        Ok(())
    }
}

fn fmt(v: f64) -> String {
    if v.is_finite() {
        // `+ 0.0` turns −0 into 0.
        format!("{:.12e}", v + 0.0)
    } else {
        String::new()
    }
}

impl Recorder for CsvSink {
    fn wants_view(&self, _info: &StepInfo) -> bool {
        self.error.is_none()
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
        self.error.take().into_iter().collect()
    }
}
