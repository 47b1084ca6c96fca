//! PNG plots (plotters, bitmap backend, text with an embedded DejaVu Sans font through
//! ab_glyph, so it works headless without system fonts). Drawn at the end of the run from the
//! recorded steps:
//!
//! * `hub_forces.png` — hub force x1, x2 and torque against time (or load factor);
//! * `energy.png` — strain, kinetic and total energy against time;
//! * `contact.png` — normal and tangential traction t_n, t_T against x1 at the last recorded
//!   step (the patch and a margin around it);
//! * `branch.png` — continuation branch: each measure against the parameter;
//! * `series.png` — the model's own scalars (e.g. stick-slip x, v) against time.
//!
//! A plot without data is not written. Non-finite points are skipped.

use super::{ContinuationPoint, RecordError, Recorder, RunEnd, RunMeta, StepInfo, StepView};
use crate::contact::ContactSample;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");

fn ensure_font() -> Result<(), String> {
    static DONE: OnceLock<Result<(), String>> = OnceLock::new();
    DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
            .map_err(|_| "the embedded font is invalid".to_string())
    })
    .clone()
}

type Series = (String, Vec<(f64, f64)>);

pub struct PngSink {
    dir: PathBuf,
    time_name: String,
    hub: [Vec<(f64, f64)>; 3],
    energy: [Vec<(f64, f64)>; 3],
    model: Vec<Series>,
    contact: Vec<ContactSample>,
    contact_time: f64,
    branch_param: String,
    branch: Vec<Series>,
}

impl PngSink {
    pub fn new(dir: &Path) -> Self {
        Self {
            dir: dir.to_path_buf(),
            time_name: "time".into(),
            hub: Default::default(),
            energy: Default::default(),
            model: Vec::new(),
            contact: Vec::new(),
            contact_time: 0.0,
            branch_param: String::new(),
            branch: Vec::new(),
        }
    }
}

fn push(v: &mut Vec<(f64, f64)>, x: f64, y: f64) {
    if x.is_finite() && y.is_finite() {
        v.push((x, y));
    }
}

fn push_named(list: &mut Vec<Series>, name: &str, x: f64, y: f64) {
    match list.iter_mut().find(|(n, _)| n == name) {
        Some((_, v)) => push(v, x, y),
        None => {
            let mut v = Vec::new();
            push(&mut v, x, y);
            list.push((name.to_string(), v));
        }
    }
}

fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = 0.05
        * (hi - lo)
            .abs()
            .max(1e-12 * hi.abs().max(lo.abs()))
            .max(f64::MIN_POSITIVE);
    if hi - lo <= 0.0 {
        let d = if lo == 0.0 { 1.0 } else { 0.05 * lo.abs() };
        return (lo - d, hi + d);
    }
    (lo - pad, hi + pad)
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// A line chart of named series (each drawn with markers) to `path`.
pub fn line_chart(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(&str, &[(f64, f64)])],
) -> Result<(), String> {
    ensure_font()?;
    let pts = || series.iter().flat_map(|(_, s)| s.iter());
    let (x0, x1) = range(pts().map(|p| p.0));
    let (y0, y1) = range(pts().map(|p| p.1));
    let root = BitMapBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(90)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .y_label_formatter(&|v| format!("{v:.3e}"))
        .draw()
        .map_err(|e| e.to_string())?;
    for (k, (name, s)) in series.iter().enumerate() {
        let c = COLORS[k % COLORS.len()];
        chart
            .draw_series(LineSeries::new(s.iter().copied(), c.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(*name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
        if s.len() <= 400 {
            chart
                .draw_series(s.iter().map(|p| Circle::new(*p, 2, c.filled())))
                .map_err(|e| e.to_string())?;
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

impl Recorder for PngSink {
    fn run_started(&mut self, meta: &RunMeta) {
        self.time_name = if meta.time_name == "load_factor" {
            "load factor λ".into()
        } else {
            "time".into()
        };
    }
    fn wants_view(&self, _info: &StepInfo) -> bool {
        true
    }
    fn step(&mut self, info: &StepInfo, view: Option<&StepView>) {
        let Some(v) = view else { return };
        let t = info.time;
        if let Some(h) = v.hub {
            push(&mut self.hub[0], t, h.force[0]);
            push(&mut self.hub[1], t, h.force[1]);
            push(&mut self.hub[2], t, h.torque);
        }
        if let Some(e) = v.energy {
            push(&mut self.energy[0], t, e.strain);
            push(&mut self.energy[1], t, e.kinetic);
            push(&mut self.energy[2], t, e.total());
        }
        for (n, y) in v.scalars {
            push_named(&mut self.model, n, t, *y);
        }
        if !v.contact.is_empty() {
            self.contact = v.contact.to_vec();
            self.contact_time = t;
        }
    }
    fn continuation_point(&mut self, p: &ContinuationPoint) {
        self.branch_param = p.parameter_name.to_string();
        for (n, y) in p.measures {
            push_named(&mut self.branch, n, p.parameter, *y);
        }
    }
    fn run_finished(&mut self, _end: &RunEnd) -> Vec<RecordError> {
        let mut errors = Vec::new();
        let mut draw = |name: &str, r: Result<(), String>| {
            if let Err(e) = r {
                errors.push(RecordError::new("png", self.dir.join(name), e));
            }
        };
        let tn = self.time_name.clone();
        if !self.hub[0].is_empty() {
            let p = self.dir.join("hub_forces.png");
            draw(
                "hub_forces.png",
                line_chart(
                    &p,
                    "Hub force on the body",
                    &tn,
                    "force per unit thickness",
                    &[("F_x", &self.hub[0]), ("F_y", &self.hub[1])],
                ),
            );
            let p = self.dir.join("hub_torque.png");
            draw(
                "hub_torque.png",
                line_chart(
                    &p,
                    "Hub torque on the body",
                    &tn,
                    "torque",
                    &[("M", &self.hub[2])],
                ),
            );
        }
        if !self.energy[0].is_empty() {
            let p = self.dir.join("energy.png");
            draw(
                "energy.png",
                line_chart(
                    &p,
                    "Energy",
                    &tn,
                    "energy per unit thickness",
                    &[
                        ("strain", &self.energy[0]),
                        ("kinetic", &self.energy[1]),
                        ("total", &self.energy[2]),
                    ],
                ),
            );
        }
        let active: Vec<&ContactSample> = self.contact.iter().filter(|s| s.t_n > 0.0).collect();
        if !active.is_empty() {
            // The patch and a margin of half its width on each side.
            let (a, b) = range(active.iter().map(|s| s.x1));
            let m = 0.5 * (b - a);
            let mut pts: Vec<&ContactSample> = self
                .contact
                .iter()
                .filter(|s| s.x1 >= a - m && s.x1 <= b + m && s.x2 < 0.0)
                .collect();
            pts.sort_by(|p, q| p.x1.total_cmp(&q.x1));
            let n: Vec<(f64, f64)> = pts.iter().map(|s| (s.x1, s.t_n)).collect();
            let t: Vec<(f64, f64)> = pts.iter().map(|s| (s.x1, s.t_t)).collect();
            let p = self.dir.join("contact.png");
            let title = format!("Contact tractions at {tn} = {:.4e}", self.contact_time);
            draw(
                "contact.png",
                line_chart(
                    &p,
                    &title,
                    "x1",
                    "traction per unit reference length",
                    &[("t_n", &n), ("t_T", &t)],
                ),
            );
        }
        if !self.branch.is_empty() {
            let p = self.dir.join("branch.png");
            let s: Vec<(&str, &[(f64, f64)])> = self
                .branch
                .iter()
                .map(|(n, v)| (n.as_str(), v.as_slice()))
                .collect();
            draw(
                "branch.png",
                line_chart(&p, "Solution branch", &self.branch_param, "measure", &s),
            );
        }
        if !self.model.is_empty() {
            let p = self.dir.join("series.png");
            let s: Vec<(&str, &[(f64, f64)])> = self
                .model
                .iter()
                .map(|(n, v)| (n.as_str(), v.as_slice()))
                .collect();
            draw(
                "series.png",
                line_chart(&p, "Model scalars", &tn, "value", &s),
            );
        }
        errors
    }
}
