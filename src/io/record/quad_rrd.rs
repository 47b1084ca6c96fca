//! Rerun recording of the quadrilateral meshes of the model problems (`run.rrd`, cargo
//! feature `rerun`): one frame per step or adaptive pass on the `step` timeline (and
//! `sim_time` for a time-stepping problem).
//!
//! | entity | archetype | content |
//! |---|---|---|
//! | `scene` | TextDocument (static) | the resolved scene TOML and what the colours mean |
//! | `solution/mesh` | Mesh3D | every cell split into sub-quads (two triangles each), vertex colours = the drawn scalar (viridis, frame minimum … maximum) |
//! | `solution/edges` | LineStrips3D | the cell edges |
//! | `error/mesh` | Mesh3D | the same cells beside the solution (shifted by 1.15 × the mesh width in x1), each filled by the viridis colour of log10 of its error indicator over at most 6 decades below the largest |
//! | `error/edges` | LineStrips3D | the cell edges of that copy |
//! | `series/<name>` | Scalars | the step's numbers (equations, error, estimate, …) |
//!
//! The file is written on the logging thread through [`super::rrd::RrdFile`] (a write error is
//! kept and reported by [`QuadRecording::finish`]).

use super::colormap;
use super::quad::{log_range, QuadCells};
use super::rrd::{file_recording, RrdFile};
use rerun::RecordingStream;
use std::path::Path;

/// One frame: the cells, the drawn scalar, the indicators and the series.
pub struct QuadFrame<'a> {
    pub index: i64,
    /// Simulated time (time-stepping problems).
    pub time: Option<f64>,
    pub cells: &'a QuadCells<'a>,
    pub sub: &'a dyn Fn(usize) -> usize,
    pub value: &'a dyn Fn(usize, f64, f64) -> f64,
    pub indicators: &'a [f64],
    pub scalars: &'a [(&'a str, f64)],
}

/// An open recording.
pub struct QuadRecording {
    rec: RecordingStream,
    file: RrdFile,
    error: Option<String>,
}

impl QuadRecording {
    /// Create `path`, name the recording `name` and log the scene text `doc` (Markdown).
    pub fn create(path: &Path, name: &str, doc: &str) -> Result<Self, String> {
        let builder = rerun::RecordingStreamBuilder::new("tread")
            .recording_name(name)
            .send_properties(false);
        let (rec, file) = file_recording(builder, path)?;
        rec.set_log_time_enabled(false);
        rec.set_log_tick_enabled(false);
        let _ = rec.send_recording_name(name);
        let mut me = Self {
            rec,
            file,
            error: None,
        };
        let r = me.rec.log_static(
            "scene",
            &rerun::TextDocument::new(doc).with_media_type(rerun::MediaType::markdown()),
        );
        me.check(r);
        Ok(me)
    }

    fn check(&mut self, r: Result<(), rerun::RecordingStreamError>) {
        if let Err(e) = r {
            self.error.get_or_insert(e.to_string());
        }
    }

    /// Log one frame.
    pub fn frame(&mut self, f: &QuadFrame) {
        self.rec.set_time_sequence("step", f.index);
        if let Some(t) = f.time {
            self.rec
                .set_duration_secs("sim_time", if t.is_finite() { t } else { 0.0 });
        }
        let n = f.cells.n_cells;
        // Solution: sub-quads, vertex values.
        let (mut pos, mut val, mut tri) = (Vec::new(), Vec::new(), Vec::new());
        let mut rings = Vec::with_capacity(n);
        let (mut x0, mut x1) = (f64::INFINITY, f64::NEG_INFINITY);
        for k in 0..n {
            let s = (f.sub)(k).max(1);
            let base = pos.len() as u32;
            for j in 0..=s {
                for i in 0..=s {
                    let xi = -1.0 + 2.0 * i as f64 / s as f64;
                    let eta = -1.0 + 2.0 * j as f64 / s as f64;
                    let p = (f.cells.map)(k, xi, eta);
                    x0 = x0.min(p[0]);
                    x1 = x1.max(p[0]);
                    pos.push([p[0] as f32, p[1] as f32, 0.0]);
                    val.push((f.value)(k, xi, eta));
                }
            }
            let m = (s + 1) as u32;
            for j in 0..s as u32 {
                for i in 0..s as u32 {
                    let a = base + i + m * j;
                    tri.push([a, a + 1, a + m + 1]);
                    tri.push([a, a + m + 1, a + m]);
                }
            }
            rings.push(
                [
                    (-1.0, -1.0),
                    (1.0, -1.0),
                    (1.0, 1.0),
                    (-1.0, 1.0),
                    (-1.0, -1.0),
                ]
                .map(|(a, b)| (f.cells.map)(k, a, b)),
            );
        }
        let (lo, hi) = val
            .iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let span = if hi > lo { hi - lo } else { 1.0 };
        let colour = |t: f64| {
            let c = colormap(t.clamp(0.0, 1.0));
            rerun::Color::from_rgb(c[0], c[1], c[2])
        };
        let colours: Vec<rerun::Color> = val
            .iter()
            .map(|&v| colour(if v.is_finite() { (v - lo) / span } else { 0.0 }))
            .collect();
        let r = self.rec.log(
            "solution/mesh",
            &rerun::Mesh3D::new(pos)
                .with_triangle_indices(tri)
                .with_vertex_colors(colours),
        );
        self.check(r);
        let strip = |shift: f64| -> Vec<Vec<[f32; 3]>> {
            rings
                .iter()
                .map(|r| {
                    r.iter()
                        .map(|p| [(p[0] + shift) as f32, p[1] as f32, 0.0])
                        .collect()
                })
                .collect()
        };
        let grey = rerun::Color::from_rgb(40, 40, 40);
        let r = self.rec.log(
            "solution/edges",
            &rerun::LineStrips3D::new(strip(0.0)).with_colors([grey]),
        );
        self.check(r);
        // Error level: one flat-coloured quad per cell, beside the solution.
        let shift = 1.15 * (x1 - x0).max(f64::MIN_POSITIVE);
        let range = log_range(f.indicators, 6.0);
        let (mut epos, mut ecol, mut etri) = (Vec::new(), Vec::new(), Vec::new());
        for (k, r) in rings.iter().enumerate() {
            let v = f.indicators.get(k).copied().unwrap_or(f64::NAN);
            let t = match range {
                Some((a, b)) if v.is_finite() && v > 0.0 => (v.log10() - a) / (b - a),
                _ => 0.0,
            };
            let base = epos.len() as u32;
            for p in &r[..4] {
                epos.push([(p[0] + shift) as f32, p[1] as f32, 0.0]);
                ecol.push(colour(t));
            }
            etri.push([base, base + 1, base + 2]);
            etri.push([base, base + 2, base + 3]);
        }
        let r = self.rec.log(
            "error/mesh",
            &rerun::Mesh3D::new(epos)
                .with_triangle_indices(etri)
                .with_vertex_colors(ecol),
        );
        self.check(r);
        let r = self.rec.log(
            "error/edges",
            &rerun::LineStrips3D::new(strip(shift)).with_colors([grey]),
        );
        self.check(r);
        for (name, v) in f.scalars {
            if v.is_finite() {
                let r = self
                    .rec
                    .log(format!("series/{name}"), &rerun::Scalars::single(*v));
                self.check(r);
            }
        }
    }

    /// Flush and close the file: `Err` with the first error when it is not complete.
    pub fn finish(mut self) -> Result<(), String> {
        if let Err(e) = self.rec.flush_blocking() {
            self.error.get_or_insert(e.to_string());
        }
        let done = self.file.finish();
        match (self.error.take(), done) {
            (Some(e), _) | (None, Err(e)) => Err(e),
            (None, Ok(())) => Ok(()),
        }
    }
}
