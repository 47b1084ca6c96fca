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
//! A plot without data is not written. Non-finite points are skipped. The histories
//! (`hub_forces.png`, `hub_torque.png`, `energy.png`) need two or more distinct times: a steady
//! solve pressed in one load step has a single state, and writes none of them. A run with
//! continuation points records its load steps (load factor) and its branch points (the
//! continuation parameter) on one clock, so its histories are not written either; `branch.png`
//! draws its loads against the parameter.
//!
//! Every axis carries its unit, derived from `[scene] units` (`"L-F-T"`, e.g. `in-lbf-s`:
//! length L, force F, time T; stresses and tractions F/L², forces per unit thickness F/L,
//! torques and energies per unit thickness F·L/L). Tick labels are plain numbers (`60`, `0.25`,
//! `1.5e-7` only when the numbers need it). Quantities of different units never share an axis:
//! `series.png` and `branch.png` draw one panel per quantity. A hub force or torque whose
//! largest magnitude is below [`ROUND_OFF`] times its natural scale (the largest nodal stress
//! magnitude times the outer radius, squared for the torque) is round-off, not a signal: it is
//! drawn as a flat line at zero, and its legend says so.

use super::{ContinuationPoint, RecordError, Recorder, RunEnd, RunMeta, StepInfo, StepView};
use crate::contact::ContactSample;
use plotters::coord::ranged1d::{
    BoldPoints, DefaultFormatting, KeyPointHint, LightPoints, ValueFormatter,
};
use plotters::coord::types::RangedCoordf64;
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
    units: Units,
    /// Largest nodal stress magnitude seen and the outer radius of the mesh (scales of the
    /// hub resultants).
    stress_scale: f64,
    radius: f64,
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
            units: Units::default(),
            stress_scale: 0.0,
            radius: 0.0,
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

/// How an axis maps data values to the plot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// The value itself.
    Linear,
    /// log10 of the value: only positive values can be shown.
    Log10,
}

impl Scale {
    /// The plot coordinate of `v`, or `None` when `v` cannot be shown on this axis (not finite,
    /// or not positive on a log axis).
    pub fn to_plot(self, v: f64) -> Option<f64> {
        match self {
            Scale::Linear => v.is_finite().then_some(v),
            Scale::Log10 => (v.is_finite() && v > 0.0).then(|| v.log10()),
        }
    }
}

/// One axis of a chart: its label and scale.
#[derive(Clone, Copy, Debug)]
pub struct Axis<'a> {
    pub label: &'a str,
    pub scale: Scale,
}

impl<'a> Axis<'a> {
    pub fn linear(label: &'a str) -> Self {
        Axis {
            label,
            scale: Scale::Linear,
        }
    }
    pub fn log10(label: &'a str) -> Self {
        Axis {
            label,
            scale: Scale::Log10,
        }
    }
}

/// Bold (labelled) tick marks plotters draws by default on each axis, and light grid lines.
const BOLD_TICKS: usize = 11;
const LIGHT_TICKS: usize = 10 * BOLD_TICKS;
/// A log axis spanning more decades than this labels every second (third, …) decade only.
const MAX_DECADE_LABELS: f64 = 10.0;

/// Range, major (labelled) ticks and minor ticks (light grid lines) of one axis, all in plot
/// coordinates (log10 of the value on a log axis).
///
/// A linear axis is what plotters draws by default: the data range padded by 5 % and plotters'
/// own "nice" key points. A log axis spans whole decades, from the decade at or below the
/// smallest value to the one at or above the largest (at least one decade); the majors are the
/// decades (every k-th when there are more than ten), the minors 2…9 × each decade, or the
/// skipped decades.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisLayout {
    pub scale: Scale,
    pub lo: f64,
    pub hi: f64,
    pub major: Vec<f64>,
    pub minor: Vec<f64>,
}

impl AxisLayout {
    /// The layout for plot coordinates `vals` (already mapped by [`Scale::to_plot`]).
    pub fn new(scale: Scale, vals: impl Iterator<Item = f64>) -> Self {
        match scale {
            Scale::Linear => {
                let (lo, hi) = range(vals);
                let c = RangedCoordf64::from(lo..hi);
                AxisLayout {
                    scale,
                    lo,
                    hi,
                    major: c.key_points(BoldPoints(BOLD_TICKS)),
                    minor: c.key_points(LightPoints::new(BOLD_TICKS, LIGHT_TICKS)),
                }
            }
            Scale::Log10 => {
                let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
                for v in vals.filter(|v| v.is_finite()) {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                if !lo.is_finite() {
                    (lo, hi) = (0.0, 1.0);
                }
                // A value within rounding of a decade belongs to it (log10(1e-3) = -2.9999…).
                let snap = |x: f64| {
                    if (x - x.round()).abs() < 1e-9 {
                        x.round()
                    } else {
                        x
                    }
                };
                let a = snap(lo).floor();
                let b = snap(hi).ceil().max(a + 1.0);
                let step = ((b - a) / MAX_DECADE_LABELS).ceil().max(1.0);
                let decades: Vec<f64> = (0..=(b - a) as i64).map(|k| a + k as f64).collect();
                let major: Vec<f64> = decades
                    .iter()
                    .copied()
                    .filter(|d| d.rem_euclid(step) == 0.0)
                    .collect();
                let minor: Vec<f64> = if step == 1.0 {
                    decades[..decades.len() - 1]
                        .iter()
                        .flat_map(|d| (2..10).map(move |m| d + (m as f64).log10()))
                        .collect()
                } else {
                    decades
                        .iter()
                        .copied()
                        .filter(|d| d.rem_euclid(step) != 0.0)
                        .collect()
                };
                AxisLayout {
                    scale,
                    lo: a,
                    hi: b,
                    major,
                    minor,
                }
            }
        }
    }

    /// A plain tick label: as many decimals as the tick spacing needs (`60`, `0.25`,
    /// `-98.42`), scientific notation (`1.5e-7`) only for very large or very small numbers.
    pub fn plain_label(&self, v: f64) -> String {
        if self.scale == Scale::Log10 {
            return self.label(v, false);
        }
        let step = self
            .major
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(f64::INFINITY, f64::min);
        let step = if step.is_finite() && step > 0.0 {
            step
        } else {
            (self.hi - self.lo)
                .abs()
                .max(v.abs())
                .max(f64::MIN_POSITIVE)
        };
        let big = v.abs().max(self.lo.abs()).max(self.hi.abs());
        if big >= 1e7 || step < 1e-5 * big.max(1e-300) || big < 1e-4 {
            // Scientific, with the digits the spacing needs relative to the value.
            if v == 0.0 {
                return "0".into();
            }
            let digits = ((v.abs() / step).log10().ceil().max(0.0) as usize).min(12);
            let t = format!("{v:.digits$e}");
            return t.replace("e0", "").replace("e-0", "e-");
        }
        let decimals = (-step.log10().floor()).max(0.0) as usize;
        let t = format!("{:.*}", decimals.min(12), v);
        if t.trim_start_matches('-')
            .chars()
            .all(|c| c == '0' || c == '.')
        {
            "0".into()
        } else {
            t
        }
    }

    /// The tick label at plot coordinate `v`: `1e-3` for a decade of a log axis; on a linear
    /// axis plotters' default format (`sci = false`) or `{:.3e}` (`sci = true`).
    pub fn label(&self, v: f64, sci: bool) -> String {
        match self.scale {
            Scale::Log10 if (v - v.round()).abs() < 1e-9 => format!("1e{}", v.round() as i64),
            Scale::Log10 => format!("{:.1e}", 10f64.powf(v)),
            Scale::Linear if sci => format!("{v:.3e}"),
            Scale::Linear => <RangedCoordf64 as ValueFormatter<f64>>::format(&v),
        }
    }
}

/// The layout is the plotters coordinate of its axis: its range, mapped linearly to pixels,
/// with its own ticks.
impl Ranged for AxisLayout {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        RangedCoordf64::from(self.lo..self.hi).map(value, limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.minor.clone()
        } else {
            self.major.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

/// Register the embedded font as `sans-serif` (once per process); for tools that draw their
/// own charts with plotters.
pub fn register_font() -> Result<(), String> {
    ensure_font()
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// A line chart of named series (each drawn with markers) to `path`, both axes linear.
pub fn line_chart(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(&str, &[(f64, f64)])],
) -> Result<(), String> {
    chart(
        path,
        title,
        Axis::linear(x_label),
        Axis::linear(y_label),
        series,
    )
    .map(|_| ())
}

/// Each series mapped to plot coordinates, and a note per series that lost points (not finite,
/// or not positive on a log axis).
type Mapped<'s> = (Vec<(&'s str, Vec<(f64, f64)>)>, Vec<String>);

fn map_series<'s>(x: Axis, y: Axis, series: &[(&'s str, &[(f64, f64)])]) -> Mapped<'s> {
    let mut notes = Vec::new();
    let mapped = series
        .iter()
        .map(|(name, s)| {
            let pts: Vec<(f64, f64)> = s
                .iter()
                .filter_map(|&(a, b)| Some((x.scale.to_plot(a)?, y.scale.to_plot(b)?)))
                .collect();
            if pts.len() < s.len() {
                let log = |a: Axis, c: char| {
                    (a.scale == Scale::Log10).then(|| format!(", or ≤ 0 on the log {c} axis"))
                };
                notes.push(format!(
                    "series `{name}`: {} of {} points left out (not finite{})",
                    s.len() - pts.len(),
                    s.len(),
                    [log(x, 'x'), log(y, 'y')]
                        .into_iter()
                        .flatten()
                        .collect::<String>()
                ));
            }
            (*name, pts)
        })
        .collect();
    (mapped, notes)
}

/// A line chart of named series (each drawn with markers) to `path`, each axis linear or log10.
/// On a log axis the ticks are decades labelled `1e-3`, with light grid lines at 2…9 × each
/// decade.
///
/// Points that cannot be shown (non-finite, or ≤ 0 on a log axis) are left out; the returned
/// notes name each series that lost points and how many. With a log axis and no point left,
/// nothing is drawn and the result is an error.
pub fn chart(
    path: &Path,
    title: &str,
    x: Axis,
    y: Axis,
    series: &[(&str, &[(f64, f64)])],
) -> Result<Vec<String>, String> {
    draw_atomic(path, |tmp| chart_to(tmp, title, x, y, series))
}

/// `dir/.stem.tmp.png`: where a PNG is drawn before it is renamed (the encoder picks the format
/// from the extension, so it stays `.png`).
pub fn tmp_png_path(path: &Path) -> std::path::PathBuf {
    let stem = path
        .file_stem()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    path.with_file_name(format!(".{stem}.tmp.png"))
}

/// Draw a PNG with `draw` into [`tmp_png_path`], then rename it to `path`: a full disk or a
/// failed drawing never leaves a partial or empty PNG under the final name, nor the temporary.
pub fn draw_atomic<T>(
    path: &Path,
    draw: impl FnOnce(&Path) -> Result<T, String>,
) -> Result<T, String> {
    let tmp = tmp_png_path(path);
    let done = draw(&tmp).and_then(|v| {
        let len = std::fs::metadata(&tmp).map_err(|e| e.to_string())?.len();
        if len == 0 {
            return Err("the PNG encoder wrote nothing (disk full?)".into());
        }
        std::fs::rename(&tmp, path).map_err(|e| e.to_string())?;
        Ok(v)
    });
    if done.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    done
}

fn chart_to(
    path: &Path,
    title: &str,
    x: Axis,
    y: Axis,
    series: &[(&str, &[(f64, f64)])],
) -> Result<Vec<String>, String> {
    let (mapped, notes) = map_series(x, y, series);
    let any = mapped.iter().any(|(_, p)| !p.is_empty());
    if !any && (x.scale == Scale::Log10 || y.scale == Scale::Log10) {
        return Err(format!(
            "nothing to draw: no point with positive values on the log axes ({})",
            notes.join("; ")
        ));
    }
    ensure_font()?;
    let pts = || mapped.iter().flat_map(|(_, s)| s.iter());
    let xa = AxisLayout::new(x.scale, pts().map(|p| p.0));
    let ya = AxisLayout::new(y.scale, pts().map(|p| p.1));
    let root = BitMapBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(90)
        .build_cartesian_2d(xa.clone(), ya.clone())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(x.label)
        .y_desc(y.label)
        .x_label_formatter(&|v| xa.plain_label(*v))
        .y_label_formatter(&|v| ya.plain_label(*v))
        .draw()
        .map_err(|e| e.to_string())?;
    for (k, (name, s)) in mapped.iter().enumerate() {
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
    root.present().map_err(|e| e.to_string())?;
    Ok(notes)
}

/// One panel of [`panels`]: the y-axis label (with its unit) and the series drawn in it.
pub type Panel<'a> = (String, Vec<(&'a str, &'a [(f64, f64)])>);

/// Panels stacked vertically over a shared x quantity, each with its own y axis (for
/// quantities of different units), written to `path`.
pub fn panels(path: &Path, title: &str, x_label: &str, panels: &[Panel]) -> Result<(), String> {
    if panels.is_empty() {
        return Ok(());
    }
    draw_atomic(path, |tmp| panels_to(tmp, title, x_label, panels))
}

fn panels_to(path: &Path, title: &str, x_label: &str, panels: &[Panel]) -> Result<(), String> {
    ensure_font()?;
    let h = (220 * panels.len()).clamp(560, 1400) as u32;
    let root = BitMapBackend::new(path, (900, h)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let root = root
        .titled(title, ("sans-serif", 22))
        .map_err(|e| e.to_string())?;
    let areas = root.split_evenly((panels.len(), 1));
    for (area, (y_label, series)) in areas.iter().zip(panels) {
        let pts = || series.iter().flat_map(|(_, s)| s.iter());
        let xa = AxisLayout::new(Scale::Linear, pts().map(|p| p.0));
        let ya = AxisLayout::new(Scale::Linear, pts().map(|p| p.1));
        let mut chart = ChartBuilder::on(area)
            .margin(8)
            .x_label_area_size(40)
            .y_label_area_size(90)
            .build_cartesian_2d(xa.clone(), ya.clone())
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label.as_str())
            .x_label_formatter(&|v| xa.plain_label(*v))
            .y_label_formatter(&|v| ya.plain_label(*v))
            .draw()
            .map_err(|e| e.to_string())?;
        for (k, (name, s)) in series.iter().enumerate() {
            let c = COLORS[k % COLORS.len()];
            chart
                .draw_series(LineSeries::new(s.iter().copied(), c.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(*name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())?;
    Ok(())
}

/// A resultant below this fraction of its natural scale is plotted as zero (round-off).
pub const ROUND_OFF: f64 = 1e-9;

/// Units of the axes, from `[scene] units = "L-F-T"`.
#[derive(Clone, Debug, PartialEq)]
pub struct Units {
    pub length: String,
    pub force: String,
    pub time: String,
}

impl Default for Units {
    fn default() -> Self {
        Units::parse(crate::io::scene::DEFAULT_UNITS)
    }
}

impl Units {
    /// `"in-lbf-s"` → in, lbf, s. Anything else keeps the text as the name of each base unit
    /// (`length [u]`), so no axis is left without one.
    pub fn parse(text: &str) -> Self {
        let parts: Vec<&str> = text.split('-').map(str::trim).collect();
        match parts.as_slice() {
            [l, f, t] if !l.is_empty() && !f.is_empty() && !t.is_empty() => Units {
                length: l.to_string(),
                force: f.to_string(),
                time: t.to_string(),
            },
            _ => {
                let u = if text.trim().is_empty() {
                    "?"
                } else {
                    text.trim()
                };
                Units {
                    length: format!("length of {u}"),
                    force: format!("force of {u}"),
                    time: format!("time of {u}"),
                }
            }
        }
    }
    /// Stress and traction: F/L².
    pub fn stress(&self) -> String {
        format!("{}/{}²", self.force, self.length)
    }
    /// Force per unit thickness: F/L.
    pub fn force_per_thickness(&self) -> String {
        format!("{}/{}", self.force, self.length)
    }
    /// Torque or energy per unit thickness: F·L/L.
    pub fn moment_per_thickness(&self) -> String {
        format!("{}·{}/{}", self.force, self.length, self.length)
    }
    /// Unit of a named model scalar or continuation measure ("1" when dimensionless).
    pub fn of_scalar(&self, name: &str) -> String {
        match name {
            "x" | "u_r_outer" | "patch_x_min" | "patch_x_max" | "road_height" | "penetration" => {
                self.length.clone()
            }
            "v" | "belt_speed" | "speed" => format!("{}/{}", self.length, self.time),
            "friction_force" | "normal_force" => self.force.clone(),
            "slipping" => "0 = stick, 1 = slip".into(),
            "phi" => "rad".into(),
            "omega" => format!("rad/{}", self.time),
            "revolutions" => "revolutions".into(),
            "hub_force_x" | "hub_force_y" | "contact_force_x" | "contact_force_y" => {
                self.force_per_thickness()
            }
            "hub_torque" | "energy_strain" | "energy_kinetic" | "energy_total" => {
                self.moment_per_thickness()
            }
            "max_pressure" | "max_shear_stress" => self.stress(),
            "newton_iterations" => "iterations".into(),
            _ => "1".into(),
        }
    }
}

/// Points (x, y) of one plotted curve.
pub type Curve = Vec<(f64, f64)>;

/// The curves t_n(x1) and t_T(x1) of contact samples, sorted by x1 (the samples come in facet
/// order around the body, which would draw each curve as a closed loop back to its start).
pub fn contact_curves<'a>(samples: impl Iterator<Item = &'a ContactSample>) -> (Curve, Curve) {
    let mut pts: Vec<&ContactSample> = samples.collect();
    pts.sort_by(|p, q| p.x1.total_cmp(&q.x1));
    (
        pts.iter().map(|s| (s.x1, s.t_n)).collect(),
        pts.iter().map(|s| (s.x1, s.t_t)).collect(),
    )
}

/// `name [unit]`.
pub fn with_unit(name: &str, unit: &str) -> String {
    format!("{name} [{unit}]")
}

/// The series with values below `ROUND_OFF × scale` replaced by zeros, and its legend name.
pub fn clamp_round_off(name: &str, s: &[(f64, f64)], scale: f64) -> (String, Vec<(f64, f64)>) {
    let max = s.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    if scale > 0.0 && scale.is_finite() && max <= ROUND_OFF * scale {
        (
            format!("{name} = 0 (|{name}| ≤ {max:.0e}: round-off)"),
            s.iter().map(|p| (p.0, 0.0)).collect(),
        )
    } else {
        (name.to_string(), s.to_vec())
    }
}

impl Recorder for PngSink {
    fn run_started(&mut self, meta: &RunMeta) {
        let units = meta
            .scene_toml
            .parse::<toml::Table>()
            .ok()
            .and_then(|t| t.get("scene")?.get("units")?.as_str().map(Units::parse));
        self.units = units.unwrap_or_default();
        self.time_name = if meta.time_name == "load_factor" {
            "load factor λ [1]".into()
        } else {
            with_unit("time", &self.units.time)
        };
        if let Some(m) = meta.mesh {
            self.radius = m.nodes.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
        }
    }
    fn wants_view(&self, _info: &StepInfo) -> bool {
        true
    }
    fn step(&mut self, info: &StepInfo, view: Option<&StepView>) {
        let Some(v) = view else { return };
        let t = info.time;
        for st in v.stress {
            for c in st {
                if c.is_finite() {
                    self.stress_scale = self.stress_scale.max(c.abs());
                }
            }
        }
        if self.radius == 0.0 {
            if let Some(m) = v.mesh {
                self.radius = m.nodes.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
            }
        }
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
        let u = self.units.clone();
        // Histories: two distinct times or more, on one clock (no continuation points).
        let history = |s: &[(f64, f64)]| {
            self.branch.is_empty() && s.iter().any(|p| s.first().is_some_and(|q| p.0 != q.0))
        };
        let draw_hub = history(&self.hub[0]);
        let draw_energy = history(&self.energy[0]);
        if draw_hub {
            let fscale = self.stress_scale * self.radius;
            let (nx, fx) = clamp_round_off("F_x", &self.hub[0], fscale);
            let (ny, fy) = clamp_round_off("F_y", &self.hub[1], fscale);
            let (nm, m) = clamp_round_off("M", &self.hub[2], fscale * self.radius);
            let p = self.dir.join("hub_forces.png");
            draw(
                "hub_forces.png",
                line_chart(
                    &p,
                    "Hub force on the body",
                    &tn,
                    &with_unit("force per unit thickness", &u.force_per_thickness()),
                    &[(nx.as_str(), fx.as_slice()), (ny.as_str(), fy.as_slice())],
                ),
            );
            let p = self.dir.join("hub_torque.png");
            draw(
                "hub_torque.png",
                line_chart(
                    &p,
                    "Hub torque on the body",
                    &tn,
                    &with_unit("torque per unit thickness", &u.moment_per_thickness()),
                    &[(nm.as_str(), m.as_slice())],
                ),
            );
        }
        if draw_energy {
            let p = self.dir.join("energy.png");
            draw(
                "energy.png",
                line_chart(
                    &p,
                    "Energy",
                    &tn,
                    &with_unit("energy per unit thickness", &u.moment_per_thickness()),
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
            let pts: Vec<&ContactSample> = self
                .contact
                .iter()
                .filter(|s| s.x1 >= a - m && s.x1 <= b + m && s.x2 < 0.0)
                .collect();
            let (n, t) = contact_curves(pts.into_iter());
            let p = self.dir.join("contact.png");
            // Six significant digits, and the unit.
            let tc = self.contact_time;
            let dec = (5.0 - tc.abs().max(1e-300).log10().floor()).clamp(0.0, 12.0) as usize;
            let title = format!(
                "Contact tractions at {} = {:.*}{}",
                self.time_name.split(" [").next().unwrap_or("time"),
                dec,
                tc,
                if self.time_name.starts_with("time") {
                    format!(" {}", u.time)
                } else {
                    String::new()
                }
            );
            draw(
                "contact.png",
                line_chart(
                    &p,
                    &title,
                    &with_unit("x1", &u.length),
                    &with_unit("traction", &u.stress()),
                    &[("t_n", &n), ("t_T", &t)],
                ),
            );
        }
        if !self.branch.is_empty() {
            let p = self.dir.join("branch.png");
            let x = with_unit(&self.branch_param, &u.of_scalar(&self.branch_param));
            let ps: Vec<Panel> = self
                .branch
                .iter()
                .map(|(n, v)| {
                    (
                        with_unit(n, &u.of_scalar(n)),
                        vec![(n.as_str(), v.as_slice())],
                    )
                })
                .collect();
            draw("branch.png", panels(&p, "Solution branch", &x, &ps));
        }
        if !self.model.is_empty() {
            let p = self.dir.join("series.png");
            let ps: Vec<Panel> = self
                .model
                .iter()
                .map(|(n, v)| {
                    (
                        with_unit(n, &u.of_scalar(n)),
                        vec![(n.as_str(), v.as_slice())],
                    )
                })
                .collect();
            draw("series.png", panels(&p, "Model scalars", &tn, &ps));
        }
        errors
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn log_layout(lo: f64, hi: f64) -> AxisLayout {
        AxisLayout::new(
            Scale::Log10,
            [lo, hi].into_iter().filter_map(|v| Scale::Log10.to_plot(v)),
        )
    }

    #[test]
    fn log_axis_spans_the_enclosing_decades() {
        let a = log_layout(3e-4, 2e1);
        assert_eq!((a.lo, a.hi), (-4.0, 2.0));
        assert_eq!(a.major, vec![-4.0, -3.0, -2.0, -1.0, 0.0, 1.0, 2.0]);
        let labels: Vec<String> = a.major.iter().map(|v| a.label(*v, true)).collect();
        assert_eq!(
            labels,
            ["1e-4", "1e-3", "1e-2", "1e-1", "1e0", "1e1", "1e2"]
        );
        // Minor ticks: 2…9 × each of the six decades, strictly inside the range.
        assert_eq!(a.minor.len(), 6 * 8);
        assert!((a.minor[0] - 2e-4f64.log10()).abs() < 1e-12);
        assert!((a.minor[47] - 9e1f64.log10()).abs() < 1e-12);
        assert!(a.minor.iter().all(|m| *m > a.lo && *m < a.hi));
    }

    #[test]
    fn log_axis_on_exact_decades_and_single_values() {
        // log10(1e-3) is not exactly -3 in floating point: it must still be the bottom decade.
        let a = log_layout(1e-3, 1e-1);
        assert_eq!((a.lo, a.hi), (-3.0, -1.0));
        // One value: at least one decade.
        let a = log_layout(5e-3, 5e-3);
        assert_eq!((a.lo, a.hi), (-3.0, -2.0));
        let a = log_layout(1e-2, 1e-2);
        assert_eq!((a.lo, a.hi), (-2.0, -1.0));
        assert_eq!(a.major, vec![-2.0, -1.0]);
    }

    #[test]
    fn log_axis_over_many_decades_labels_every_other_decade() {
        let a = log_layout(1e-16, 1e2);
        assert_eq!((a.lo, a.hi), (-16.0, 2.0));
        assert!(a.major.len() <= 11, "{:?}", a.major);
        assert!(a.major.iter().all(|d| d.rem_euclid(2.0) == 0.0));
        assert_eq!(a.major.first(), Some(&-16.0));
        assert_eq!(a.major.last(), Some(&2.0));
        // The skipped decades are the minor ticks.
        assert_eq!(a.minor.len(), 9);
        assert!(a.minor.iter().all(|d| d.rem_euclid(2.0) == 1.0));
    }

    #[test]
    fn linear_axis_is_plotters_default() {
        let vals = [-3.0, 0.5, 7.0];
        let a = AxisLayout::new(Scale::Linear, vals.iter().copied());
        assert_eq!((a.lo, a.hi), range(vals.iter().copied()));
        assert_eq!((a.lo, a.hi), (-3.5, 7.5));
        let c = RangedCoordf64::from(a.lo..a.hi);
        assert_eq!(a.major, c.key_points(BoldPoints(11)));
        assert!(a.major.contains(&0.0) && a.major.contains(&5.0));
        assert_eq!(a.label(5.0, false), "5.0");
        assert_eq!(a.label(5.0, true), "5.000e0");
        for v in [-2.0, 0.0, 1e-300, 4.5] {
            assert_eq!(Scale::Linear.to_plot(v), Some(v));
        }
        assert_eq!(Scale::Linear.to_plot(f64::NAN), None);
    }

    #[test]
    fn log_scale_refuses_non_positive_values() {
        assert_eq!(Scale::Log10.to_plot(1e3), Some(3.0));
        for v in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert_eq!(Scale::Log10.to_plot(v), None, "{v}");
        }
        let s: &[(f64, f64)] = &[(1.0, 1e-2), (2.0, 0.0), (3.0, -1e-3), (4.0, 1e-4)];
        let (m, notes) = map_series(Axis::log10("x"), Axis::log10("y"), &[("err", s)]);
        assert_eq!(m[0].1.len(), 2);
        assert_eq!(notes.len(), 1);
        assert!(
            notes[0].contains("`err`") && notes[0].contains("2 of 4"),
            "{notes:?}"
        );
        // A linear y axis keeps the same points.
        let (m, notes) = map_series(Axis::linear("x"), Axis::linear("y"), &[("err", s)]);
        assert_eq!(m[0].1.len(), 4);
        assert!(notes.is_empty());
    }

    #[test]
    fn chart_draws_log_axes_and_refuses_an_empty_log_chart() {
        let dir = std::env::temp_dir().join(format!("tread-png-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let ok = dir.join("loglog.png");
        let s: &[(f64, f64)] = &[(0.01, 3e-4), (0.1, 2e-2), (1.0, 0.0), (2.0, 2e1)];
        let notes = chart(
            &ok,
            "t",
            Axis::log10("wall"),
            Axis::log10("error"),
            &[("a", s)],
        )
        .unwrap();
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(std::fs::metadata(&ok).unwrap().len() > 1000);
        let bad = dir.join("empty.png");
        let z: &[(f64, f64)] = &[(1.0, 0.0), (2.0, -1.0)];
        let e = chart(&bad, "t", Axis::linear("x"), Axis::log10("y"), &[("z", z)]).unwrap_err();
        assert!(e.contains("nothing to draw"), "{e}");
        assert!(!bad.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
