//! Footprint maps of a three-dimensional contact patch: PNG pictures over the road plane
//! (x1 along the road to the right, x3 across it upward) of the contact pressure, the
//! tangential traction (magnitude, with arrows of its direction) and the stick and slip zones,
//! drawn from the facet quadrature points of [`ContactSample3D`].
//!
//! Each quadrature point in contact is a filled square centred at its current (x1, x3), of side
//! √dA0 (its reference area weight), coloured on a linear viridis scale from 0 to the largest
//! value (colour bar with the unit at the right); points out of contact are not drawn.

use crate::contact::facet3d::ContactSample3D;
use std::path::Path;

/// What a footprint map shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FootprintField {
    /// Contact pressure t_n.
    Pressure,
    /// |t_T| with arrows of t_T.
    Traction,
    /// Stick (|w| < ε, blue) and slip (orange).
    StickSlip,
}

/// Draw the footprint map of `field` to `path` (PNG). `stress_unit` labels the colour bar
/// (F/L²) and `length_unit` the axes. An error when no point is in contact.
pub fn footprint_png(
    path: &Path,
    title: &str,
    samples: &[ContactSample3D],
    field: FootprintField,
    stress_unit: &str,
    length_unit: &str,
) -> Result<(), String> {
    use plotters::prelude::*;
    super::png::register_font()?;
    let pts: Vec<&ContactSample3D> = samples.iter().filter(|s| s.p > 0.0).collect();
    if pts.is_empty() {
        return Err("no point in contact: no footprint to draw".into());
    }
    let half = |s: &ContactSample3D| 0.5 * s.da0.max(0.0).sqrt();
    let (mut x0, mut x1, mut z0, mut z1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for s in &pts {
        let h = half(s);
        x0 = x0.min(s.x1 - h);
        x1 = x1.max(s.x1 + h);
        z0 = z0.min(s.x3 - h);
        z1 = z1.max(s.x3 + h);
    }
    if !(x1 > x0 && z1 > z0) {
        return Err("the contact patch has no extent to draw".into());
    }
    let value = |s: &ContactSample3D| match field {
        FootprintField::Pressure => s.p,
        FootprintField::Traction => s.t1.hypot(s.t3),
        FootprintField::StickSlip => f64::from(u8::from(s.stick)),
    };
    let vmax = pts.iter().map(|s| value(s)).fold(0.0f64, f64::max);
    let (w, top, margin, bar) = (700.0, 50.0, 40.0, 170.0);
    let scale = w / (x1 - x0).max(z1 - z0);
    let (wpx, hpx) = ((x1 - x0) * scale, (z1 - z0) * scale);
    let size = (
        (2.0 * margin + wpx + bar) as u32,
        (top + hpx + 2.0 * margin + 20.0) as u32,
    );
    let px = |x: f64, z: f64| -> (i32, i32) {
        (
            (margin + (x - x0) * scale).round() as i32,
            (top + margin + (z1 - z) * scale).round() as i32,
        )
    };
    let colour = |v: f64| -> RGBColor {
        if field == FootprintField::StickSlip {
            return if v > 0.5 {
                RGBColor(31, 119, 180)
            } else {
                RGBColor(255, 127, 14)
            };
        }
        let t = if vmax > 0.0 { v / vmax } else { 0.0 };
        let [r, g, b] = super::colormap(t.clamp(0.0, 1.0));
        RGBColor(r, g, b)
    };
    super::png::draw_atomic(path, |tmp| {
        let root = BitMapBackend::new(tmp, size).into_drawing_area();
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let font = ("sans-serif", 16).into_font();
        root.draw(&Text::new(
            title.to_string(),
            (margin as i32, 12),
            ("sans-serif", 20).into_font(),
        ))
        .map_err(e)?;
        for s in &pts {
            let h = half(s);
            let (a, b) = (px(s.x1 - h, s.x3 + h), px(s.x1 + h, s.x3 - h));
            root.draw(&Rectangle::new([a, b], colour(value(s)).filled()))
                .map_err(e)?;
        }
        if field == FootprintField::Traction && vmax > 0.0 {
            // Arrows of t_T, the largest as long as the largest square.
            let hmax = pts.iter().map(|s| half(s)).fold(0.0f64, f64::max);
            for s in &pts {
                let (t1, t3) = (s.t1, s.t3);
                let len = 1.8 * hmax / vmax;
                let (a, b) = (px(s.x1, s.x3), px(s.x1 + len * t1, s.x3 + len * t3));
                root.draw(&PathElement::new(vec![a, b], BLACK.stroke_width(1)))
                    .map_err(e)?;
                root.draw(&Circle::new(b, 1, BLACK.filled())).map_err(e)?;
            }
        }
        // Frame and axis labels.
        let (fa, fb) = (px(x0, z1), px(x1, z0));
        root.draw(&Rectangle::new([fa, fb], BLACK.stroke_width(1)))
            .map_err(e)?;
        let label = |v: f64| format!("{v:.3}");
        root.draw(&Text::new(
            format!("x1 [{length_unit}]: {} … {}", label(x0), label(x1)),
            (fa.0, fb.1 + 8),
            font.clone(),
        ))
        .map_err(e)?;
        root.draw(&Text::new(
            format!("x3: {} … {}", label(z0), label(z1)),
            (fa.0, fb.1 + 26),
            font.clone(),
        ))
        .map_err(e)?;
        // Colour bar (or the stick/slip legend).
        let bx = (2.0 * margin + wpx + 10.0) as i32;
        let (by0, by1) = (
            (top + margin) as i32,
            (top + margin + hpx.max(120.0)) as i32,
        );
        if field == FootprintField::StickSlip {
            for (k, (name, v)) in [("stick (|w| < eps)", 1.0), ("slip", 0.0)]
                .into_iter()
                .enumerate()
            {
                let y = by0 + 30 * k as i32;
                root.draw(&Rectangle::new(
                    [(bx, y), (bx + 20, y + 20)],
                    colour(v).filled(),
                ))
                .map_err(e)?;
                root.draw(&Text::new(name, (bx + 26, y + 2), font.clone()))
                    .map_err(e)?;
            }
        } else {
            let n = 100;
            for i in 0..n {
                let t = i as f64 / n as f64;
                let ya = by1 - ((by1 - by0) as f64 * (t + 1.0 / n as f64)) as i32 - 1;
                let yb = by1 - ((by1 - by0) as f64 * t) as i32;
                let [r, g, b] = super::colormap(t);
                root.draw(&Rectangle::new(
                    [(bx, ya), (bx + 24, yb)],
                    RGBColor(r, g, b).filled(),
                ))
                .map_err(e)?;
            }
            let what = match field {
                FootprintField::Pressure => "t_n",
                _ => "|t_T|",
            };
            root.draw(&Text::new(
                format!("{vmax:.4e}"),
                (bx + 30, by0 - 6),
                font.clone(),
            ))
            .map_err(e)?;
            root.draw(&Text::new("0", (bx + 30, by1 - 12), font.clone()))
                .map_err(e)?;
            root.draw(&Text::new(
                format!("{what} [{stress_unit}]"),
                (bx, by1 + 8),
                font.clone(),
            ))
            .map_err(e)?;
        }
        root.present().map_err(e)?;
        Ok(())
    })
}
