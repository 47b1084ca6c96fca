//! Drawings shared by the `rerun` sink ([`super::rrd`]) and the MCAP → `.rrd` conversion
//! ([`crate::io::replay`]): the colour scale beside the body, the contact tractions as curves
//! below the road and as arrows, and the contact pressure and shear charts against x1.
//!
//! # The contact charts
//!
//! Rerun 0.36's bar chart view cannot set its x axis (ticks at integer abscissae, bars that
//! overlap when the view is large), and its time-series view plots against a timeline only. So
//! the charts are drawn in a 2D view: a frame [`CHART_W`] × [`CHART_H`] (view units, x2 down as
//! in every Rerun 2D view, so a value v is drawn at −v), grid lines at round values of x1 and
//! of the traction, each labelled, the curve through the contact points and a marker at each.
//! The ranges follow the step: x1 over the patch (padded to round ticks), the traction from 0
//! (or its minimum, for the shear) to its maximum. The view bounds are fixed
//! ([`chart_bounds`]) so the frame fills the view at every step.

use super::png::Units;
use super::{colormap, or_zero};
use rerun::{RecordingStream, RecordingStreamResult};

/// Width of a contact chart's frame (view units).
pub const CHART_W: f32 = 1.6;
/// Height of a contact chart's frame (view units).
pub const CHART_H: f32 = 1.0;

/// The 2D view bounds of a contact chart: `(min, max)` corners, with room for the tick labels
/// left of and below the frame and for the title above it.
pub fn chart_bounds() -> ([f32; 2], [f32; 2]) {
    ([-0.42, -CHART_H - 0.28], [CHART_W + 0.08, 0.38])
}

/// Light text on the viewer's dark background.
pub fn label_colour() -> rerun::Color {
    rerun::Color::from_rgb(235, 235, 235)
}

/// Colour of the pressure curves.
pub fn pressure_colour() -> rerun::Color {
    rerun::Color::from_rgb(235, 90, 60)
}

/// Colour of the shear curves.
pub fn shear_colour() -> rerun::Color {
    rerun::Color::from_rgb(80, 150, 255)
}

/// `v` rounded to `digits` significant digits (for labels).
pub fn round_sig(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return 0.0;
    }
    let e = v.abs().log10().floor() as i32;
    let f = 10f64.powi(digits - 1 - e);
    (v * f).round() / f
}

fn fmt(v: f64) -> String {
    crate::io::output::fmt_num(round_sig(v, 4))
}

/// Round ticks covering `[lo, hi]`: `(first, step, count)` with a step of 1, 2, 2.5 or 5 × 10ᵏ
/// and 3 to about 7 ticks; `first` ≤ `lo` and `first + (count − 1) step` ≥ `hi`.
pub fn nice_ticks(lo: f64, hi: f64) -> (f64, f64, usize) {
    let (lo, hi) = if lo.is_finite() && hi.is_finite() {
        (lo.min(hi), lo.max(hi))
    } else {
        (0.0, 1.0)
    };
    let span = if hi > lo {
        hi - lo
    } else {
        lo.abs().max(1.0) * 1e-3
    };
    let raw = span / 5.0;
    let p = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * p)
        .find(|s| span / s <= 6.0)
        .unwrap_or(10.0 * p);
    let first = (lo / step).floor() * step;
    let mut count = ((hi - first) / step - 1e-9).ceil() as usize + 1;
    count = count.max(2);
    (first, step, count)
}

/// The colour scale of the body's colours at `{prefix}/colour_scale` (and its labels at
/// `{prefix}/colour_scale/labels`): a vertical bar right of the body (x1 from 1.15 Ro to
/// 1.25 Ro, x2 from −0.6 Ro to Ro) in the same piecewise-linear viridis as the mesh (its five
/// stops are the bar's vertices, so the GPU's linear interpolation reproduces the map exactly),
/// labelled beside the bar, right of it, at its ends: 0 at the bottom, the frame's maximum τ at
/// the top, in light text.
pub fn colour_scale(
    rec: &RecordingStream,
    prefix: &str,
    ro: f64,
    max: f64,
    units: &Units,
) -> RecordingStreamResult<()> {
    let ro = ro as f32;
    let (x0, x1) = (1.15 * ro, 1.25 * ro);
    let y = |t: f32| -0.6 * ro + 1.6 * ro * t;
    let mut pos = Vec::with_capacity(10);
    let mut colors = Vec::with_capacity(10);
    for k in 0..5 {
        let t = k as f32 / 4.0;
        let c = colormap(f64::from(t));
        for x in [x0, x1] {
            pos.push([x, y(t), 0.0]);
            colors.push(rerun::Color::from_rgb(c[0], c[1], c[2]));
        }
    }
    let tris: Vec<[u32; 3]> = (0..4u32)
        .flat_map(|k| {
            let a = 2 * k;
            [[a, a + 1, a + 3], [a, a + 3, a + 2]]
        })
        .collect();
    rec.log(
        format!("{prefix}/colour_scale"),
        &rerun::Mesh3D::new(pos)
            .with_triangle_indices(tris)
            .with_vertex_colors(colors),
    )?;
    let unit = units.stress();
    let labels = [format!("τ 0 {unit}"), format!("τ max {} {unit}", fmt(max))];
    // Labels are drawn centred on their point: far enough right that the text clears the bar.
    let xl = x1 + 0.42 * ro;
    rec.log(
        format!("{prefix}/colour_scale/labels"),
        &rerun::Points3D::new([[xl, y(0.0), 0.0], [xl, y(1.0), 0.0]])
            .with_radii([rerun::Radius::new_ui_points(0.5)])
            .with_colors([label_colour()])
            .with_labels(labels)
            .with_show_labels(true),
    )
}

/// A contact point for the drawings: `(x1, t_n, t_T)`.
pub type TractionPoint = (f64, f64, f64);

/// The points in contact (t_n > 0, finite x1) sorted along x1.
pub fn sorted_patch(points: impl IntoIterator<Item = TractionPoint>) -> Vec<TractionPoint> {
    let mut p: Vec<TractionPoint> = points
        .into_iter()
        .filter(|p| p.1 > 0.0 && p.0.is_finite() && p.1.is_finite())
        .map(|p| (p.0, p.1, or_zero(p.2)))
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    p
}

/// t_n and t_T drawn as curves against x1 below the road and the body (under `prefix`:
/// `pressure`, `shear`, `axis`, `labels`), baseline at x2 = `base`, one scale for both (peak
/// |t| = 0.3 Ro); the labels give the peak values and the x1 range.
pub fn contact_curves(
    rec: &RecordingStream,
    prefix: &str,
    pts: &[TractionPoint],
    base: f64,
    ro: f64,
    units: &Units,
) -> RecordingStreamResult<()> {
    let (Some(first), Some(last)) = (pts.first(), pts.last()) else {
        return Ok(());
    };
    let (a, b) = (first.0, last.0);
    let peak = pts
        .iter()
        .flat_map(|p| [p.1.abs(), p.2.abs()])
        .fold(0.0, f64::max);
    let scale = if peak > 0.0 { 0.3 * ro / peak } else { 0.0 };
    let curve = |f: fn(&TractionPoint) -> f64| -> Vec<[f32; 3]> {
        pts.iter()
            .map(|p| [p.0 as f32, (base - scale * f(p)) as f32, 0.0])
            .collect()
    };
    rec.log(
        format!("{prefix}/pressure"),
        &rerun::LineStrips3D::new([curve(|p| p.1)]).with_colors([pressure_colour()]),
    )?;
    rec.log(
        format!("{prefix}/shear"),
        &rerun::LineStrips3D::new([curve(|p| p.2)]).with_colors([shear_colour()]),
    )?;
    rec.log(
        format!("{prefix}/axis"),
        &rerun::LineStrips3D::new([[[a as f32, base as f32, 0.0], [b as f32, base as f32, 0.0]]])
            .with_colors([rerun::Color::from_rgb(150, 150, 150)]),
    )?;
    let kmax = (0..pts.len())
        .max_by(|&i, &j| pts[i].1.total_cmp(&pts[j].1))
        .unwrap_or(0);
    let pmax = pts[kmax].1;
    let tabs = pts.iter().map(|p| p.2.abs()).fold(0.0, f64::max);
    let unit = units.stress();
    // Labels apart from each other (drawn centred on their point): t_n under its peak, the x1
    // range under that, t_T right of the patch.
    rec.log(
        format!("{prefix}/labels"),
        &rerun::Points3D::new([
            [
                pts[kmax].0 as f32,
                (base - scale * pmax - 0.08 * ro) as f32,
                0.0,
            ],
            [(b + 0.45 * ro) as f32, base as f32, 0.0],
            [
                pts[kmax].0 as f32,
                (base - scale * pmax - 0.2 * ro) as f32,
                0.0,
            ],
        ])
        .with_radii([rerun::Radius::new_ui_points(0.5)])
        .with_colors([pressure_colour(), shear_colour(), label_colour()])
        .with_labels([
            format!("t_n against x1, max {} {unit}", fmt(pmax)),
            format!("t_T, max |t_T| {} {unit}", fmt(tabs)),
            format!("x1 {} … {} {}", fmt(a), fmt(b), units.length),
        ])
        .with_show_labels(true),
    )
}

/// Traction vectors (t_T, t_n) at `origins` (display coordinates), scaled to 0.2 Ro at the
/// largest |t|.
pub fn traction_arrows(
    rec: &RecordingStream,
    entity: &str,
    origins: &[[f32; 3]],
    t: &[(f64, f64)],
    ro: f64,
) -> RecordingStreamResult<()> {
    let tmax = t.iter().map(|(n, s)| n.hypot(*s)).fold(0.0, f64::max);
    let scale = if tmax > 0.0 { 0.2 * ro / tmax } else { 0.0 };
    let vectors: Vec<[f32; 3]> = t
        .iter()
        .map(|(n, s)| {
            [
                (or_zero(*s) * scale) as f32,
                (or_zero(*n) * scale) as f32,
                0.0,
            ]
        })
        .collect();
    rec.log(
        entity,
        &rerun::Arrows3D::from_vectors(vectors).with_origins(origins.to_vec()),
    )
}

/// One contact chart (see the module docs) at `entity` (`frame`, `grid`, `curve`, `points`,
/// `ticks` under it): `values` against x1 of the sorted points `pts`, named `title`.
pub fn contact_chart(
    rec: &RecordingStream,
    entity: &str,
    pts: &[TractionPoint],
    values: &[f64],
    title: &str,
    units: &Units,
    colour: rerun::Color,
) -> RecordingStreamResult<()> {
    if pts.is_empty() || values.len() != pts.len() {
        return Ok(());
    }
    let (xa, xb) = (pts[0].0, pts[pts.len() - 1].0);
    let (x0, xs, xn) = nice_ticks(xa, xb);
    let x_end = x0 + xs * (xn - 1) as f64;
    let vmin = values.iter().copied().fold(0.0, f64::min);
    let vmax = values.iter().copied().fold(0.0, f64::max);
    let (y0, ys, yn) = nice_ticks(vmin, vmax);
    let y_end = y0 + ys * (yn - 1) as f64;
    let px = |x: f64| (f64::from(CHART_W) * (x - x0) / (x_end - x0)) as f32;
    let py = |v: f64| -(f64::from(CHART_H) * (v - y0) / (y_end - y0)) as f32;
    let (w, h) = (CHART_W, -CHART_H);
    rec.log(
        format!("{entity}/frame"),
        &rerun::LineStrips2D::new([[[0.0, 0.0], [w, 0.0], [w, h], [0.0, h], [0.0, 0.0]]])
            .with_colors([rerun::Color::from_rgb(170, 170, 170)])
            .with_radii([rerun::Radius::new_ui_points(1.0)]),
    )?;
    let mut grid: Vec<Vec<[f32; 2]>> = Vec::new();
    let mut tick_pos: Vec<[f32; 2]> = Vec::new();
    let mut tick_txt: Vec<String> = Vec::new();
    for k in 0..xn {
        let x = x0 + xs * k as f64;
        grid.push(vec![[px(x), 0.0], [px(x), h]]);
        tick_pos.push([px(x), 0.07]);
        tick_txt.push(crate::io::output::fmt_num(round_sig(x, 6)));
    }
    for k in 0..yn {
        let v = y0 + ys * k as f64;
        grid.push(vec![[0.0, py(v)], [w, py(v)]]);
        tick_pos.push([-0.17, py(v)]);
        tick_txt.push(crate::io::output::fmt_num(round_sig(v, 6)));
    }
    rec.log(
        format!("{entity}/grid"),
        &rerun::LineStrips2D::new(grid)
            .with_colors([rerun::Color::from_rgb(80, 80, 80)])
            .with_radii([rerun::Radius::new_ui_points(0.5)]),
    )?;
    // Axis names: x1 below the middle of the x ticks, the title above the frame.
    tick_pos.push([0.5 * w, 0.2]);
    tick_txt.push(format!("x1 [{}]", units.length));
    tick_pos.push([0.5 * w, h - 0.14]);
    tick_txt.push(format!("{title} [{}]", units.stress()));
    rec.log(
        format!("{entity}/ticks"),
        &rerun::Points2D::new(tick_pos)
            .with_radii([rerun::Radius::new_ui_points(0.5)])
            .with_colors([label_colour()])
            .with_labels(tick_txt)
            .with_show_labels(true),
    )?;
    let curve: Vec<[f32; 2]> = pts
        .iter()
        .zip(values)
        .map(|(p, v)| [px(p.0), py(*v)])
        .collect();
    rec.log(
        format!("{entity}/curve"),
        &rerun::LineStrips2D::new([curve.clone()])
            .with_colors([colour])
            .with_radii([rerun::Radius::new_ui_points(2.0)]),
    )?;
    rec.log(
        format!("{entity}/points"),
        &rerun::Points2D::new(curve)
            .with_colors([colour])
            .with_radii([rerun::Radius::new_ui_points(3.5)]),
    )
}

/// The pressure and shear charts of the sorted points `pts` at `pressure` and `shear`.
pub fn contact_charts(
    rec: &RecordingStream,
    pressure: &str,
    shear: &str,
    pts: &[TractionPoint],
    units: &Units,
) -> RecordingStreamResult<()> {
    let tn: Vec<f64> = pts.iter().map(|p| p.1).collect();
    let tt: Vec<f64> = pts.iter().map(|p| p.2).collect();
    contact_chart(rec, pressure, pts, &tn, "t_n", units, pressure_colour())?;
    contact_chart(rec, shear, pts, &tt, "t_T", units, shear_colour())
}

#[cfg(test)]
mod tests {
    use super::nice_ticks;

    #[test]
    fn ticks_cover_the_range_with_round_steps() {
        for (lo, hi) in [
            (-0.31, 0.33),
            (0.0, 47.3),
            (-2.2e-3, 5e-3),
            (1.0, 1.0),
            (-7.0, 0.0),
        ] {
            let (a, s, n) = nice_ticks(lo, hi);
            let b = a + s * (n - 1) as f64;
            assert!(a <= lo + 1e-12 && b >= hi - 1e-12, "{lo} {hi}: {a} {s} {n}");
            assert!((3..=8).contains(&n) || lo == hi, "{lo} {hi}: {n}");
            let m = s / 10f64.powf(s.log10().floor());
            assert!(
                [1.0, 2.0, 2.5, 5.0].iter().any(|r| (m - r).abs() < 1e-9),
                "step {s}"
            );
        }
    }
}
