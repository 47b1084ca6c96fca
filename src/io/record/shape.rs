//! Deformed-shape pictures with stress contours (`[output] snapshot_omegas`, steady mode with a
//! continuation in ω): for each requested speed the branch point nearest to it is kept, and at
//! the end of the run each is drawn to `shape_omega_<ω>.png`, all of them side by side to
//! `shape_montage.png`.
//!
//! A picture is the deformed mesh (reference position plus `[output] displacement_scale` times
//! the displacement) filled by the von Mises Cauchy stress at the nodes (the nodal stresses of
//! the recorder's view, the same ones the VTU files hold), linearly interpolated over the
//! display triangles of the cells ([`super::display_triangles`]), with the outline of the body,
//! the rigid hub (grey), the road line (at x2 = −Ro + k (Ro − H) with k the magnification, so
//! the magnified body still meets it), and a colour bar in the scene's stress unit. Every
//! picture of a run shares one colour scale (0 to the largest stress of all snapshots) and one
//! length scale, so they compare directly. The speed is given in rad/s and rpm, with the
//! standing-wave amplitude of that point (`wave_amplitude` of `branch.csv`).
//!
//! The triangles are rasterised here ([`Raster`]); plotters draws the text and lines on top.

use super::png::{register_font, Units};
use super::{boundary_loops, colormap, display_triangles, StepView};
use crate::mesh::Mesh;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Von Mises stress of the Cauchy stress `[σ11, σ22, σ12]` with the out-of-plane σ33:
/// √(½((σ11 − σ22)² + (σ22 − σ33)² + (σ33 − σ11)²) + 3 σ12²).
pub fn von_mises(s: [f64; 3], s33: f64) -> f64 {
    let [a, b, c] = s;
    (0.5 * ((a - b).powi(2) + (b - s33).powi(2) + (s33 - a).powi(2)) + 3.0 * c * c).sqrt()
}

/// An RGB image (row-major, top row first, 3 bytes per pixel).
#[derive(Clone, Debug, PartialEq)]
pub struct Raster {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
}

impl Raster {
    /// A `width` × `height` image filled with `bg`.
    pub fn new(width: usize, height: usize, bg: [u8; 3]) -> Self {
        let mut rgb = Vec::with_capacity(3 * width * height);
        for _ in 0..width * height {
            rgb.extend_from_slice(&bg);
        }
        Raster { width, height, rgb }
    }

    /// The colour of pixel (x, y) (x to the right, y down), `None` outside.
    pub fn pixel(&self, x: usize, y: usize) -> Option<[u8; 3]> {
        (x < self.width && y < self.height).then(|| {
            let i = 3 * (y * self.width + x);
            [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
        })
    }

    fn put(&mut self, x: usize, y: usize, c: [u8; 3]) {
        let i = 3 * (y * self.width + x);
        self.rgb[i..i + 3].copy_from_slice(&c);
    }

    /// Fill the triangle with corners `p` (pixel coordinates; pixel (x, y) covers
    /// [x, x + 1) × [y, y + 1)) by the colour of the scalar `v` interpolated linearly from its
    /// corners, mapped by [`colormap`] from [`lo`, `hi`] to [0, 1]. A pixel is covered when its
    /// centre lies in the triangle (edges included). Degenerate or non-finite triangles draw
    /// nothing; a non-finite corner value draws the low end of the map.
    pub fn fill_triangle(&mut self, p: [[f64; 2]; 3], v: [f64; 3], lo: f64, hi: f64) {
        if p.iter().flatten().any(|c| !c.is_finite()) {
            return;
        }
        let area =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
        if area.abs() < 1e-12 {
            return;
        }
        let span = if hi > lo { hi - lo } else { 1.0 };
        let v = v.map(|x| if x.is_finite() { x } else { lo });
        let (xmin, xmax) = (
            p[0][0].min(p[1][0]).min(p[2][0]),
            p[0][0].max(p[1][0]).max(p[2][0]),
        );
        let (ymin, ymax) = (
            p[0][1].min(p[1][1]).min(p[2][1]),
            p[0][1].max(p[1][1]).max(p[2][1]),
        );
        let x0 = (xmin - 0.5).ceil().max(0.0) as usize;
        let y0 = (ymin - 0.5).ceil().max(0.0) as usize;
        let x1 = ((xmax - 0.5).floor() + 1.0).clamp(0.0, self.width as f64) as usize;
        let y1 = ((ymax - 0.5).floor() + 1.0).clamp(0.0, self.height as f64) as usize;
        // Barycentric weight of corner k: the signed area opposite it over the whole area.
        let w = |k: usize, x: f64, y: f64| {
            let (a, b) = (p[(k + 1) % 3], p[(k + 2) % 3]);
            ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / area
        };
        const EDGE: f64 = -1e-9;
        for y in y0..y1 {
            let yc = y as f64 + 0.5;
            for x in x0..x1 {
                let xc = x as f64 + 0.5;
                let (l0, l1, l2) = (w(0, xc, yc), w(1, xc, yc), w(2, xc, yc));
                if l0 < EDGE || l1 < EDGE || l2 < EDGE {
                    continue;
                }
                let s = l0 * v[0] + l1 * v[1] + l2 * v[2];
                self.put(x, y, colormap((s - lo) / span));
            }
        }
    }

    /// A vertical colour bar in the rectangle [x, x + w) × [y, y + h): `hi` at the top row,
    /// `lo` at the bottom row, linear in between.
    pub fn colour_bar(&mut self, x: usize, y: usize, w: usize, h: usize) {
        for j in 0..h {
            let t = if h > 1 {
                1.0 - j as f64 / (h - 1) as f64
            } else {
                1.0
            };
            let c = colormap(t);
            for i in 0..w {
                if x + i < self.width && y + j < self.height {
                    self.put(x + i, y + j, c);
                }
            }
        }
    }
}

/// One kept branch point: what a picture needs.
#[derive(Clone, Debug)]
pub struct ShapeSnapshot {
    /// The requested speed this point is nearest to, and the point's own speed (rad/s).
    pub requested: f64,
    pub omega: f64,
    /// Standing-wave amplitude of the point (length).
    pub wave_amplitude: f64,
    /// Deformed (magnified) node positions.
    pub points: Vec<[f64; 2]>,
    /// Von Mises stress at the nodes.
    pub value: Vec<f64>,
    /// Road height H (road at x2 = −H).
    pub road_height: Option<f64>,
}

/// The snapshots of a run: for each requested speed, the offered point nearest to it.
pub struct ShapeSnapshots {
    requested: Vec<f64>,
    scale: f64,
    taken: Vec<Option<ShapeSnapshot>>,
    tris: Vec<[u32; 3]>,
    loops: Vec<Vec<u32>>,
    /// Outer radius of the reference mesh.
    ro: f64,
}

/// Size of a single picture and of one montage panel (pixels).
const SINGLE: (usize, usize) = (780, 680);
const PANEL: (usize, usize) = (360, 380);
/// Width of the colour-bar column at the right of a picture.
const BAR_COLUMN: usize = 150;
const MONTAGE_COLUMNS: usize = 5;

/// `10` → `10`, `45.25` → `45.25`, `-3.5` → `m3.5`: a file-name friendly speed.
pub fn omega_tag(omega: f64) -> String {
    let t = format!("{:.2}", omega);
    let t = t.trim_end_matches('0').trim_end_matches('.').to_string();
    t.replace('-', "m")
}

impl ShapeSnapshots {
    /// Snapshots of `mesh` at the points nearest to the `requested` speeds (rad/s), the
    /// displacement magnified by `displacement_scale`.
    pub fn new(mesh: &Mesh, requested: &[f64], displacement_scale: f64) -> Self {
        ShapeSnapshots {
            requested: requested.to_vec(),
            scale: displacement_scale,
            taken: vec![None; requested.len()],
            tris: display_triangles(mesh),
            loops: boundary_loops(mesh),
            ro: mesh.nodes.iter().map(|x| x.norm()).fold(0.0, f64::max),
        }
    }

    /// Whether a point at `omega` would be kept (it is nearer to some requested speed than the
    /// point kept so far); the caller builds the stresses only then.
    pub fn wants(&self, omega: f64) -> bool {
        omega.is_finite()
            && self.requested.iter().zip(&self.taken).any(|(r, t)| {
                t.as_ref()
                    .is_none_or(|s| (omega - r).abs() < (s.omega - r).abs())
            })
    }

    /// Offer the point at `omega` (its view and wave amplitude); it replaces the kept point of
    /// every requested speed it is nearer to.
    pub fn offer(&mut self, omega: f64, view: &StepView, wave_amplitude: f64) {
        let Some(mesh) = view.mesh else { return };
        if !self.wants(omega) || view.stress.len() != mesh.n_nodes() {
            return;
        }
        let mut shot: Option<ShapeSnapshot> = None;
        for (r, t) in self.requested.iter().zip(self.taken.iter_mut()) {
            if t.as_ref()
                .is_some_and(|s| (omega - r).abs() >= (s.omega - r).abs())
            {
                continue;
            }
            let s = shot.get_or_insert_with(|| {
                let points = (0..mesh.n_nodes())
                    .map(|n| {
                        let u = view.u(n);
                        let x = mesh.nodes[n];
                        [x[0] + self.scale * u[0], x[1] + self.scale * u[1]]
                    })
                    .collect();
                let value = (0..mesh.n_nodes())
                    .map(|n| {
                        let s33 = view.sigma_33.get(n).copied().unwrap_or(0.0);
                        von_mises(view.stress[n], s33)
                    })
                    .collect();
                ShapeSnapshot {
                    requested: *r,
                    omega,
                    wave_amplitude,
                    points,
                    value,
                    road_height: view.road_height,
                }
            });
            *t = Some(ShapeSnapshot {
                requested: *r,
                ..s.clone()
            });
        }
    }

    /// The kept snapshots, in the order of the requested speeds.
    pub fn snapshots(&self) -> impl Iterator<Item = &ShapeSnapshot> {
        self.taken.iter().flatten()
    }

    /// The common colour range (0 to the largest finite stress) and world bounding box
    /// `[x_min, x_max, y_min, y_max]` of every snapshot.
    fn extents(&self) -> ((f64, f64), [f64; 4]) {
        let mut hi: f64 = 0.0;
        let mut b = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for s in self.snapshots() {
            for v in s.value.iter().filter(|v| v.is_finite()) {
                hi = hi.max(*v);
            }
            for p in s
                .points
                .iter()
                .filter(|p| p[0].is_finite() && p[1].is_finite())
            {
                b = [
                    b[0].min(p[0]),
                    b[1].max(p[0]),
                    b[2].min(p[1]),
                    b[3].max(p[1]),
                ];
            }
            if let Some(h) = s.road_height.filter(|h| h.is_finite()) {
                b[2] = b[2].min(-self.ro + self.scale * (self.ro - h));
            }
        }
        if !(b[0].is_finite() && b[2].is_finite()) {
            b = [-1.0, 1.0, -1.0, 1.0];
        }
        // A margin of 2 % of the size, so that the outline and the road line show.
        let pad = 0.02 * (b[1] - b[0]).max(b[3] - b[2]);
        b = [b[0] - pad, b[1] + pad, b[2] - pad, b[3] + pad];
        if hi <= 0.0 {
            hi = 1.0;
        }
        ((0.0, hi), b)
    }

    /// Write `shape_omega_<ω>.png` per snapshot and `shape_montage.png`; returns the files
    /// written. Nothing is written without snapshots.
    pub fn write(&self, dir: &Path, units: &Units) -> Result<Vec<PathBuf>, String> {
        let shots: Vec<&ShapeSnapshot> = self.snapshots().collect();
        if shots.is_empty() {
            return Ok(Vec::new());
        }
        register_font()?;
        let (range, bbox) = self.extents();
        let mut files = Vec::new();
        let mut written: Vec<String> = Vec::new();
        for s in &shots {
            let name = format!("shape_omega_{}.png", omega_tag(s.requested));
            if written.contains(&name) {
                continue;
            }
            let path = dir.join(&name);
            super::png::draw_atomic(&path, |tmp| {
                self.draw(tmp, &[s], 1, SINGLE, range, bbox, units)
            })?;
            written.push(name);
            files.push(path);
        }
        let path = dir.join("shape_montage.png");
        let cols = shots.len().min(MONTAGE_COLUMNS);
        super::png::draw_atomic(&path, |tmp| {
            self.draw(tmp, &shots, cols, PANEL, range, bbox, units)
        })?;
        files.push(path);
        Ok(files)
    }

    /// Draw `shots` in a grid of `cols` columns of `panel`-sized pictures, with one colour bar
    /// at the right, to `path`.
    #[allow(clippy::too_many_arguments)]
    fn draw(
        &self,
        path: &Path,
        shots: &[&ShapeSnapshot],
        cols: usize,
        panel: (usize, usize),
        (lo, hi): (f64, f64),
        bbox: [f64; 4],
        units: &Units,
    ) -> Result<(), String> {
        let cols = cols.max(1);
        let rows = shots.len().div_ceil(cols);
        let top = if shots.len() > 1 { 46 } else { 0 };
        let (w, h) = (cols * panel.0 + BAR_COLUMN, top + rows * panel.1);
        let mut img = Raster::new(w, h, [255, 255, 255]);
        // Panel layout: a title band, then the square-ish plot region with a margin.
        let title_h = if shots.len() > 1 { 52 } else { 74 };
        let margin = 12.0;
        let (bw, bh) = (
            (bbox[1] - bbox[0]).max(1e-300),
            (bbox[3] - bbox[2]).max(1e-300),
        );
        let avail = (
            panel.0 as f64 - 2.0 * margin,
            panel.1 as f64 - title_h as f64 - 2.0 * margin,
        );
        let px_per = (avail.0 / bw).min(avail.1 / bh);
        let origin = |k: usize| {
            let (c, r) = (k % cols, k / cols);
            let x0 = (c * panel.0) as f64 + margin + 0.5 * (avail.0 - px_per * bw);
            let y0 = (top + r * panel.1 + title_h) as f64 + margin + 0.5 * (avail.1 - px_per * bh);
            (x0, y0)
        };
        let to_px = |k: usize, p: [f64; 2]| {
            let (x0, y0) = origin(k);
            [
                x0 + (p[0] - bbox[0]) * px_per,
                y0 + (bbox[3] - p[1]) * px_per,
            ]
        };
        for (k, s) in shots.iter().enumerate() {
            for t in &self.tris {
                let [a, b, c] = t.map(|n| n as usize);
                if a.max(b).max(c) >= s.points.len() {
                    continue;
                }
                img.fill_triangle(
                    [
                        to_px(k, s.points[a]),
                        to_px(k, s.points[b]),
                        to_px(k, s.points[c]),
                    ],
                    [s.value[a], s.value[b], s.value[c]],
                    lo,
                    hi,
                );
            }
        }
        let bar = (
            w - BAR_COLUMN + 24,
            top + 60,
            26,
            h.saturating_sub(top + 120).max(20),
        );
        img.colour_bar(bar.0, bar.1, bar.2, bar.3);

        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        let mut backend = BitMapBackend::new(path, (w as u32, h as u32));
        backend
            .blit_bitmap((0, 0), (w as u32, h as u32), &img.rgb)
            .map_err(|e| e.to_string())?;
        let root = backend.into_drawing_area();
        let font = |size: u32| ("sans-serif", size).into_font().color(&BLACK);
        if shots.len() > 1 {
            root.draw(&Text::new(
                "Steady rolling: deformed shape and von Mises stress at increasing speed",
                (12, 12),
                font(24),
            ))
            .map_err(e)?;
        }
        let px = |p: [f64; 2]| (p[0].round() as i32, p[1].round() as i32);
        for (k, s) in shots.iter().enumerate() {
            let (c, r) = (k % cols, k / cols);
            let (tx, ty) = ((c * panel.0 + 12) as i32, (top + r * panel.1 + 8) as i32);
            let rpm = s.omega * 60.0 / (2.0 * std::f64::consts::PI);
            let big = if shots.len() > 1 { 20 } else { 26 };
            let head = if shots.len() > 1 {
                format!("ω = {:.1} rad/s ({:.0} rpm)", s.omega, rpm)
            } else {
                format!(
                    "Steady rolling at ω = {:.2} rad/s ({:.1} rpm)",
                    s.omega, rpm
                )
            };
            root.draw(&Text::new(head, (tx, ty), font(big)))
                .map_err(e)?;
            let sub = format!(
                "wave amplitude {:.2e} {}{}",
                s.wave_amplitude,
                units.length,
                if self.scale != 1.0 {
                    format!(", displacement × {}", self.scale)
                } else {
                    String::new()
                }
            );
            root.draw(&Text::new(sub, (tx, ty + big as i32 + 6), font(15)))
                .map_err(e)?;
            if shots.len() == 1 {
                root.draw(&Text::new(
                    "colour: von Mises Cauchy stress (same scale in every picture of the run)",
                    (tx, ty + big as i32 + 26),
                    font(15),
                ))
                .map_err(e)?;
            }
            // Hub (grey) and outline.
            if let Some(inner) = self.loops.first() {
                let hub: Vec<(i32, i32)> = inner
                    .iter()
                    .filter_map(|&n| s.points.get(n as usize))
                    .map(|p| px(to_px(k, *p)))
                    .collect();
                root.draw(&Polygon::new(hub, RGBColor(200, 200, 200).filled()))
                    .map_err(e)?;
            }
            for l in &self.loops {
                let pts: Vec<(i32, i32)> = l
                    .iter()
                    .filter_map(|&n| s.points.get(n as usize))
                    .map(|p| px(to_px(k, *p)))
                    .collect();
                root.draw(&PathElement::new(pts, BLACK.stroke_width(1)))
                    .map_err(e)?;
            }
            if let Some(hr) = s.road_height.filter(|v| v.is_finite()) {
                // The road moved with the magnified body: at x2 = −Ro + k (Ro − H), where the
                // undeformed bottom lands when moved k times the penetration.
                let (x0, _) = origin(k);
                let y_road = -self.ro + self.scale * (self.ro - hr);
                let y = to_px(k, [0.0, y_road])[1].round() as i32;
                let xa = x0.round() as i32 - 4;
                let xb = (x0 + px_per * bw).round() as i32 + 4;
                root.draw(&PathElement::new(
                    vec![(xa, y), (xb, y)],
                    RGBColor(90, 90, 90).stroke_width(3),
                ))
                .map_err(e)?;
            }
        }
        // Colour bar: frame, ticks and labels, unit.
        let (bx, by, bwid, bht) = (bar.0 as i32, bar.1 as i32, bar.2 as i32, bar.3 as i32);
        root.draw(&Rectangle::new(
            [(bx - 1, by - 1), (bx + bwid, by + bht)],
            BLACK.stroke_width(1),
        ))
        .map_err(e)?;
        root.draw(&Text::new("von Mises", (bx - 16, by - 46), font(16)))
            .map_err(e)?;
        root.draw(&Text::new(
            format!("[{}]", units.stress()),
            (bx - 16, by - 26),
            font(16),
        ))
        .map_err(e)?;
        let ticks = 5;
        for i in 0..=ticks {
            let f = i as f64 / ticks as f64;
            let y = by + ((1.0 - f) * (bht - 1) as f64).round() as i32;
            let v = lo + f * (hi - lo);
            root.draw(&PathElement::new(
                vec![(bx + bwid, y), (bx + bwid + 6, y)],
                BLACK.stroke_width(1),
            ))
            .map_err(e)?;
            root.draw(&Text::new(
                tick_label(v, hi - lo),
                (bx + bwid + 9, y - 8),
                font(15),
            ))
            .map_err(e)?;
        }
        root.present().map_err(|e| e.to_string())?;
        Ok(())
    }
}

/// A colour-bar label: as many decimals as the span needs.
fn tick_label(v: f64, span: f64) -> String {
    let step = (span / 5.0).abs();
    if !(step.is_finite() && step > 0.0) {
        return format!("{v}");
    }
    if !(1e-3..1e6).contains(&v.abs().max(step)) {
        return format!("{v:.2e}");
    }
    let decimals = (-(step.log10().floor())).clamp(0.0, 6.0) as usize;
    format!("{v:.decimals$}")
}
