//! Small writers for the quadrilateral meshes of the model problems (`src/adapt/`): a VTU of
//! the cells, each sampled on a `s × s` grid of sub-quads with point fields evaluated there
//! (the solution), or with one quad per cell and cell fields only (the mesh with its error
//! indicator); a PNG of the mesh with every cell shaded by the base-10 logarithm of a cell
//! value (the local error level), with a colour bar; and a PNG of a scalar over the mesh,
//! shaded, with contour lines (marching squares on the sub-quads), with a colour bar.
//!
//! A cell is given by its map from the reference square [−1, 1]² (ξ, η) to the plane; its
//! corners are the images of (±1, ±1), its edges straight lines between them (true for the
//! squares of a quadtree and for bilinear cells). VTU files are ASCII `UnstructuredGrid`s of
//! `VTK_QUAD` cells (type 9), with points repeated per cell (fields may jump between cells);
//! non-finite values are written as 0.

use super::colormap;
use crate::io::output::{write_atomic, OutputError};
use std::fmt::Write as _;
use std::path::Path;

/// The cells of a mesh: their number and the map of cell `k` from (ξ, η) ∈ [−1, 1]².
pub struct QuadCells<'a> {
    pub n_cells: usize,
    pub map: &'a dyn Fn(usize, f64, f64) -> [f64; 2],
}

/// `eval(k, ξ, η, out)`: the components of a field at (ξ, η) of cell `k`.
pub type PointEval<'a> = &'a dyn Fn(usize, f64, f64, &mut [f64]);

/// A field sampled at points: `eval(k, ξ, η, out)` writes its `n_comp` components in cell `k`.
pub struct PointField<'a> {
    pub name: &'a str,
    pub n_comp: usize,
    pub eval: PointEval<'a>,
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:e}")
    } else {
        "0".into()
    }
}

/// Write a VTU of `cells`, cell `k` split into `sub(k) × sub(k)` quads (at least 1), with the
/// point fields evaluated at the sub-quads' vertices and the cell fields (one value per cell of
/// `cells`, repeated on its sub-quads).
pub fn write_vtu(
    path: &Path,
    cells: &QuadCells,
    sub: &dyn Fn(usize) -> usize,
    point_fields: &[PointField],
    cell_fields: &[(&str, &[f64])],
) -> Result<(), OutputError> {
    let mut points: Vec<[f64; 2]> = Vec::new();
    let mut values: Vec<Vec<f64>> = vec![Vec::new(); point_fields.len()];
    let mut conn: Vec<usize> = Vec::new();
    let mut parent: Vec<usize> = Vec::new();
    let mut buf = Vec::new();
    for k in 0..cells.n_cells {
        let s = sub(k).max(1);
        let base = points.len();
        for j in 0..=s {
            for i in 0..=s {
                let xi = -1.0 + 2.0 * i as f64 / s as f64;
                let eta = -1.0 + 2.0 * j as f64 / s as f64;
                points.push((cells.map)(k, xi, eta));
                for (f, v) in point_fields.iter().zip(values.iter_mut()) {
                    buf.clear();
                    buf.resize(f.n_comp, 0.0);
                    (f.eval)(k, xi, eta, &mut buf);
                    v.extend_from_slice(&buf);
                }
            }
        }
        for j in 0..s {
            for i in 0..s {
                let a = base + i + (s + 1) * j;
                conn.extend_from_slice(&[a, a + 1, a + s + 2, a + s + 1]);
                parent.push(k);
            }
        }
    }
    let mut x = String::new();
    let _ = write!(
        x,
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
         byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n<Piece \
         NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
        points.len(),
        parent.len()
    );
    x.push_str("<PointData>\n");
    for (f, v) in point_fields.iter().zip(&values) {
        let _ = writeln!(
            x,
            "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"ascii\">",
            f.name, f.n_comp
        );
        for row in v.chunks(f.n_comp.max(1)) {
            let line: Vec<String> = row.iter().map(|&a| num(a)).collect();
            x.push_str(&line.join(" "));
            x.push('\n');
        }
        x.push_str("</DataArray>\n");
    }
    x.push_str("</PointData>\n<CellData>\n");
    for (name, v) in cell_fields {
        let _ = writeln!(
            x,
            "<DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
        );
        for &k in &parent {
            x.push_str(&num(v.get(k).copied().unwrap_or(f64::NAN)));
            x.push('\n');
        }
        x.push_str("</DataArray>\n");
    }
    x.push_str(
        "</CellData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" \
         format=\"ascii\">\n",
    );
    for p in &points {
        let _ = writeln!(x, "{} {} 0", num(p[0]), num(p[1]));
    }
    x.push_str(
        "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" \
         format=\"ascii\">\n",
    );
    for c in conn.chunks(4) {
        let _ = writeln!(x, "{} {} {} {}", c[0], c[1], c[2], c[3]);
    }
    x.push_str("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for i in 0..parent.len() {
        let _ = writeln!(x, "{}", 4 * (i + 1));
    }
    x.push_str("</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for _ in 0..parent.len() {
        x.push_str("9\n");
    }
    x.push_str("</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    write_atomic(path, x.as_bytes())
}

/// The range of log10 of the positive values, at most `decades` wide below the largest.
pub fn log_range(values: &[f64], decades: f64) -> Option<(f64, f64)> {
    let logs = values
        .iter()
        .filter(|v| v.is_finite() && **v > 0.0)
        .map(|v| v.log10());
    let (lo, hi) = logs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), l| {
        (a.min(l), b.max(l))
    });
    if !hi.is_finite() {
        return None;
    }
    let lo = lo.max(hi - decades);
    Some(if hi - lo < 1e-12 {
        (lo - 0.5, hi + 0.5)
    } else {
        (lo, hi)
    })
}

/// Draw the mesh to `path` (PNG, width 900 px) with every cell filled by the viridis colour of
/// log10 of its value (values ≤ 0 or below the range in the darkest colour; the range spans at
/// most 6 decades below the largest value), its edges in black, `title` above and a colour bar
/// labelled `label` at the right.
pub fn mesh_png(
    path: &Path,
    title: &str,
    cells: &QuadCells,
    values: &[f64],
    label: &str,
) -> Result<(), String> {
    use plotters::prelude::*;
    super::png::register_font()?;
    let corners: Vec<[[f64; 2]; 4]> = (0..cells.n_cells)
        .map(|k| {
            [
                (cells.map)(k, -1.0, -1.0),
                (cells.map)(k, 1.0, -1.0),
                (cells.map)(k, 1.0, 1.0),
                (cells.map)(k, -1.0, 1.0),
            ]
        })
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for c in &corners {
        for p in c {
            x0 = x0.min(p[0]);
            x1 = x1.max(p[0]);
            y0 = y0.min(p[1]);
            y1 = y1.max(p[1]);
        }
    }
    if !(x1 > x0 && y1 > y0) {
        return Err("the mesh has no extent to draw".into());
    }
    let range = log_range(values, 6.0);
    let (w, top, margin, bar) = (700.0, 50.0, 20.0, 160.0);
    let scale = w / (x1 - x0).max(y1 - y0);
    let hpx = (y1 - y0) * scale;
    let size = (
        (2.0 * margin + (x1 - x0) * scale + bar) as u32,
        (top + hpx + 2.0 * margin) as u32,
    );
    let px = |p: [f64; 2]| -> (i32, i32) {
        (
            (margin + (p[0] - x0) * scale).round() as i32,
            (top + margin + (y1 - p[1]) * scale).round() as i32,
        )
    };
    let colour = |v: f64| -> RGBColor {
        let t = match range {
            Some((lo, hi)) if v.is_finite() && v > 0.0 => (v.log10() - lo) / (hi - lo),
            _ => 0.0,
        };
        let [r, g, b] = colormap(t.clamp(0.0, 1.0));
        RGBColor(r, g, b)
    };
    super::png::draw_atomic(path, |tmp| {
        let root = BitMapBackend::new(tmp, size).into_drawing_area();
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        root.draw(&Text::new(
            title.to_string(),
            (margin as i32, 12),
            ("sans-serif", 20).into_font(),
        ))
        .map_err(e)?;
        let thin = corners.len() > 4096;
        for (c, &v) in corners.iter().zip(values) {
            let poly: Vec<(i32, i32)> = c.iter().map(|&p| px(p)).collect();
            root.draw(&Polygon::new(poly.clone(), colour(v).filled()))
                .map_err(e)?;
            let mut ring = poly;
            ring.push(ring[0]);
            let edge = if thin { BLACK.mix(0.4) } else { BLACK.mix(0.9) };
            root.draw(&PathElement::new(ring, edge.stroke_width(1)))
                .map_err(e)?;
        }
        // Colour bar.
        let bx = (2.0 * margin + (x1 - x0) * scale + 10.0) as i32;
        let (by0, by1) = ((top + margin) as i32, (top + margin + hpx) as i32);
        let n = 100;
        for i in 0..n {
            let t = i as f64 / n as f64;
            let ya = by1 - ((by1 - by0) as f64 * (t + 1.0 / n as f64)) as i32 - 1;
            let yb = by1 - ((by1 - by0) as f64 * t) as i32;
            let [r, g, b] = colormap(t);
            root.draw(&Rectangle::new(
                [(bx, ya), (bx + 24, yb)],
                RGBColor(r, g, b).filled(),
            ))
            .map_err(e)?;
        }
        let font = ("sans-serif", 14).into_font();
        if let Some((lo, hi)) = range {
            root.draw(&Text::new(
                format!("{:.1e}", 10f64.powf(hi)),
                (bx + 30, by0),
                font.clone(),
            ))
            .map_err(e)?;
            root.draw(&Text::new(
                format!("{:.1e}", 10f64.powf(lo)),
                (bx + 30, by1 - 14),
                font.clone(),
            ))
            .map_err(e)?;
        }
        root.draw(&Text::new(
            label.to_string(),
            (bx, by1 + 4),
            ("sans-serif", 13).into_font(),
        ))
        .map_err(e)?;
        root.present().map_err(e)?;
        Ok(())
    })
}

/// A scalar drawn by [`solution_png`]: `eval(k, ξ, η)` in cell `k`, each cell sampled on a
/// `sub(k) × sub(k)` grid of sub-quads.
pub struct Shading<'a> {
    pub eval: &'a dyn Fn(usize, f64, f64) -> f64,
    pub sub: &'a dyn Fn(usize) -> usize,
    /// Contour levels; empty: 12 levels evenly spaced between the extremes.
    pub levels: &'a [f64],
}

/// The crossings of the level `c` on the sub-quad with corner values `v` (counter-clockwise
/// from the lower left, at the points `p`): zero, one or two segments. A saddle (all four
/// edges crossed) is split by the mean of the corners.
fn contour_segments(p: &[[f64; 2]; 4], v: &[f64; 4], c: f64, out: &mut Vec<[[f64; 2]; 2]>) {
    let mut cut: [Option<[f64; 2]>; 4] = [None; 4];
    for (a, x) in cut.iter_mut().enumerate() {
        let b = (a + 1) % 4;
        let (va, vb) = (v[a] - c, v[b] - c);
        if (va < 0.0) != (vb < 0.0) {
            let t = va / (va - vb);
            *x = Some([
                p[a][0] + t * (p[b][0] - p[a][0]),
                p[a][1] + t * (p[b][1] - p[a][1]),
            ]);
        }
    }
    let hits: Vec<(usize, [f64; 2])> = cut
        .iter()
        .enumerate()
        .filter_map(|(e, x)| x.map(|x| (e, x)))
        .collect();
    match hits.len() {
        2 => out.push([hits[0].1, hits[1].1]),
        4 => {
            // Corners 0 and 2 lie on one side of c, 1 and 3 on the other. When the cell
            // mean is on the side of corner 0, corners 0 and 2 connect through the centre and
            // the lines cut off corners 1 and 3; else they cut off corners 0 and 2.
            let mean = v.iter().sum::<f64>() / 4.0;
            let c4 = cut.map(|x| x.unwrap_or_default());
            if (v[0] < c) == (mean < c) {
                out.push([c4[0], c4[1]]);
                out.push([c4[2], c4[3]]);
            } else {
                out.push([c4[3], c4[0]]);
                out.push([c4[1], c4[2]]);
            }
        }
        _ => {}
    }
}

/// Draw a scalar over the mesh to `path` (PNG, width about 900 px): every sub-quad filled by
/// the viridis colour of its mean corner value (linear between the extremes), the contour
/// lines of `shading.levels` in black, the cell edges in light grey when `edges`, `title`
/// above and a colour bar labelled `label`.
pub fn solution_png(
    path: &Path,
    title: &str,
    cells: &QuadCells,
    shading: &Shading,
    edges: bool,
    label: &str,
) -> Result<(), String> {
    use plotters::prelude::*;
    super::png::register_font()?;
    // Sample every cell.
    struct Sampled {
        s: usize,
        pts: Vec<[f64; 2]>,
        vals: Vec<f64>,
    }
    let mut cells_s = Vec::with_capacity(cells.n_cells);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for k in 0..cells.n_cells {
        let s = (shading.sub)(k).max(1);
        let mut pts = Vec::with_capacity((s + 1) * (s + 1));
        let mut vals = Vec::with_capacity((s + 1) * (s + 1));
        for j in 0..=s {
            for i in 0..=s {
                let xi = -1.0 + 2.0 * i as f64 / s as f64;
                let eta = -1.0 + 2.0 * j as f64 / s as f64;
                let p = (cells.map)(k, xi, eta);
                let v = (shading.eval)(k, xi, eta);
                x0 = x0.min(p[0]);
                x1 = x1.max(p[0]);
                y0 = y0.min(p[1]);
                y1 = y1.max(p[1]);
                if v.is_finite() {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                pts.push(p);
                vals.push(v);
            }
        }
        cells_s.push(Sampled { s, pts, vals });
    }
    if !(x1 > x0 && y1 > y0) {
        return Err("the mesh has no extent to draw".into());
    }
    if lo > hi {
        // No finite value.
        (lo, hi) = (0.0, 1.0);
    }
    if hi - lo < 1e-300 {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    // Given levels closer to zero than 1e-4 of the range are left out: at the resolution of
    // the mesh they trace the rounding noise of a field that vanishes on the boundary.
    let levels: Vec<f64> = if shading.levels.is_empty() {
        (1..=12)
            .map(|i| lo + (hi - lo) * (i as f64 - 0.5) / 12.0)
            .collect()
    } else {
        shading
            .levels
            .iter()
            .copied()
            .filter(|c| c.abs() >= 1e-4 * (hi - lo))
            .collect()
    };
    let (w, top, margin, bar) = (700.0, 50.0, 20.0, 160.0);
    let scale = w / (x1 - x0).max(y1 - y0);
    let hpx = (y1 - y0) * scale;
    let size = (
        (2.0 * margin + (x1 - x0) * scale + bar) as u32,
        (top + hpx + 2.0 * margin) as u32,
    );
    let px = |p: [f64; 2]| -> (i32, i32) {
        (
            (margin + (p[0] - x0) * scale).round() as i32,
            (top + margin + (y1 - p[1]) * scale).round() as i32,
        )
    };
    let colour = |v: f64| -> RGBColor {
        let t = if v.is_finite() {
            (v - lo) / (hi - lo)
        } else {
            0.0
        };
        let [r, g, b] = colormap(t.clamp(0.0, 1.0));
        RGBColor(r, g, b)
    };
    super::png::draw_atomic(path, |tmp| {
        let root = BitMapBackend::new(tmp, size).into_drawing_area();
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        root.draw(&Text::new(
            title.to_string(),
            (margin as i32, 12),
            ("sans-serif", 20).into_font(),
        ))
        .map_err(e)?;
        let mut segs = Vec::new();
        for c in &cells_s {
            let m = c.s + 1;
            for j in 0..c.s {
                for i in 0..c.s {
                    let id = [
                        i + m * j,
                        i + 1 + m * j,
                        i + 1 + m * (j + 1),
                        i + m * (j + 1),
                    ];
                    let p = id.map(|a| c.pts[a]);
                    let v = id.map(|a| c.vals[a]);
                    let mean = v.iter().sum::<f64>() / 4.0;
                    let poly: Vec<(i32, i32)> = p.iter().map(|&q| px(q)).collect();
                    let fill = colour(mean);
                    root.draw(&Polygon::new(poly.clone(), fill.filled()))
                        .map_err(e)?;
                    // The outline in the same colour: the fill leaves out the right and lower
                    // pixel rows of a polygon, which would show as white seams.
                    let mut ring = poly;
                    ring.push(ring[0]);
                    root.draw(&PathElement::new(ring, fill.stroke_width(1)))
                        .map_err(e)?;
                    if v.iter().all(|x| x.is_finite()) {
                        for &lv in &levels {
                            contour_segments(&p, &v, lv, &mut segs);
                        }
                    }
                }
            }
        }
        if edges {
            for k in 0..cells.n_cells {
                let ring: Vec<(i32, i32)> = [
                    (-1.0, -1.0),
                    (1.0, -1.0),
                    (1.0, 1.0),
                    (-1.0, 1.0),
                    (-1.0, -1.0),
                ]
                .iter()
                .map(|&(a, b)| px((cells.map)(k, a, b)))
                .collect();
                root.draw(&PathElement::new(
                    ring,
                    RGBColor(200, 200, 200).stroke_width(1),
                ))
                .map_err(e)?;
            }
        }
        for s in &segs {
            root.draw(&PathElement::new(
                vec![px(s[0]), px(s[1])],
                BLACK.mix(0.85).stroke_width(1),
            ))
            .map_err(e)?;
        }
        // Colour bar.
        let bx = (2.0 * margin + (x1 - x0) * scale + 10.0) as i32;
        let (by0, by1) = ((top + margin) as i32, (top + margin + hpx) as i32);
        let n = 100;
        for i in 0..n {
            let t = i as f64 / n as f64;
            let ya = by1 - ((by1 - by0) as f64 * (t + 1.0 / n as f64)) as i32 - 1;
            let yb = by1 - ((by1 - by0) as f64 * t) as i32;
            let [r, g, b] = colormap(t);
            root.draw(&Rectangle::new(
                [(bx, ya), (bx + 24, yb)],
                RGBColor(r, g, b).filled(),
            ))
            .map_err(e)?;
        }
        let font = ("sans-serif", 14).into_font();
        root.draw(&Text::new(
            format!("{hi:.3e}"),
            (bx + 30, by0),
            font.clone(),
        ))
        .map_err(e)?;
        root.draw(&Text::new(
            format!("{lo:.3e}"),
            (bx + 30, by1 - 14),
            font.clone(),
        ))
        .map_err(e)?;
        root.draw(&Text::new(
            label.to_string(),
            (bx, by1 + 4),
            ("sans-serif", 13).into_font(),
        ))
        .map_err(e)?;
        root.present().map_err(e)?;
        Ok(())
    })
}
