//! Rolling resistance along a steady branch in ω (viscoelastic rolling).
//!
//! The rolling-resistance coefficient of a steady state is
//!
//! ```text
//! C_rr = sign(ω) T / (P Ro),     P = −F_y (the hub load, > 0 when pressed),
//! ```
//!
//! with T the hub torque and Ro the outer radius (dimensionless). The hub's power is ω T, so
//! C_rr > 0 means the hub feeds energy that the material dissipates: in steady rolling of a
//! frictionless viscoelastic body ω T equals the hysteresis loss per unit time.
//!
//! Along an arc-length branch in ω ([`crate::solver::continuation`], `[continuation] parameter
//! = "omega"`) the steady mode writes `resistance.png` (C_rr against ω, log ω axis, the peak
//! marked) and `results.rolling_resistance` in summary.json: the coefficient at every branch
//! point and the peak, located by a parabola in log ω through the largest sampled value and
//! its two neighbours (the peak of a standard linear solid lies near ω τ a / Ro ≈ 1, where a is
//! the contact half-width and τ the relaxation time; Hunter 1961). A maximum at either end of
//! the branch is reported as not found: the branch does not bracket the peak.

use crate::io::record::png;
use std::path::Path;

/// What the coefficient needs of one branch point (the steady mode builds these from its
/// branch rows).
#[derive(Clone, Copy, Debug)]
pub struct BranchLoad {
    /// Continuation step.
    pub step: usize,
    /// Angular speed (rad/s).
    pub omega: f64,
    /// Vertical hub force F_y (force per unit thickness; < 0 when pressed).
    pub hub_force_y: f64,
    /// Hub torque T (counter-clockwise positive, per unit thickness).
    pub hub_torque: f64,
}

/// The peak of C_rr(ω) on a branch.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ResistancePeak {
    /// ω at the peak (rad/s), from the parabola in log ω.
    pub omega: f64,
    /// C_rr at the peak (the parabola's maximum).
    pub coefficient: f64,
    /// Branch step of the largest sampled C_rr.
    pub step: usize,
}

/// C_rr of one branch point (NaN without a load: P ≤ 0).
pub fn coefficient(row: &BranchLoad, ro: f64) -> f64 {
    let p = -row.hub_force_y;
    if p > 0.0 && ro > 0.0 {
        row.omega.signum() * row.hub_torque / (p * ro)
    } else {
        f64::NAN
    }
}

/// (ω, C_rr) of every branch point with a finite coefficient and ω ≠ 0.
pub fn curve(rows: &[BranchLoad], ro: f64) -> Vec<(f64, f64)> {
    rows.iter()
        .map(|r| (r.omega, coefficient(r, ro)))
        .filter(|(w, c)| w.is_finite() && *w != 0.0 && c.is_finite())
        .collect()
}

/// The interior maximum of C_rr along the branch (see the module docs), or None when the
/// largest value is at an end of the branch or there are fewer than three points. Points are
/// taken in the order of |ω| (a branch in ω may be walked either way).
pub fn peak(rows: &[BranchLoad], ro: f64) -> Option<ResistancePeak> {
    let mut pts: Vec<(f64, f64, usize, f64)> = rows
        .iter()
        .map(|r| (r.omega.abs(), coefficient(r, ro), r.step, r.omega.signum()))
        .filter(|(w, c, _, _)| w.is_finite() && *w > 0.0 && c.is_finite())
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    if pts.len() < 3 {
        return None;
    }
    let i = (0..pts.len()).max_by(|&a, &b| pts[a].1.total_cmp(&pts[b].1))?;
    if i == 0 || i + 1 == pts.len() {
        return None;
    }
    let (x0, x1, x2) = (pts[i - 1].0.ln(), pts[i].0.ln(), pts[i + 1].0.ln());
    let (y0, y1, y2) = (pts[i - 1].1, pts[i].1, pts[i + 1].1);
    // Parabola through the three points (divided differences); its vertex.
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let a = (d12 - d01) / (x2 - x0);
    let (x, y) = if a < 0.0 {
        let b = d01 - a * (x0 + x1);
        let xv = (-b / (2.0 * a)).clamp(x0, x2);
        (xv, y0 + d01 * (xv - x0) + a * (xv - x0) * (xv - x1))
    } else {
        (x1, y1)
    };
    Some(ResistancePeak {
        omega: x.exp() * pts[i].3,
        coefficient: y,
        step: pts[i].2,
    })
}

/// `results.rolling_resistance` of the steady mode: the coefficient along a branch in ω.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct RollingResistance {
    /// The formula of the coefficient.
    pub definition: String,
    /// ω of the branch points with a finite coefficient (rad/s).
    pub omega: Vec<f64>,
    /// C_rr at those points (dimensionless).
    pub coefficient: Vec<f64>,
    /// The interior peak (null when the branch does not bracket one).
    pub peak: Option<ResistancePeak>,
}

/// The rolling resistance of a branch: the definition, the curve and the peak.
pub fn rolling_resistance(rows: &[BranchLoad], ro: f64) -> RollingResistance {
    let c = curve(rows, ro);
    RollingResistance {
        definition: "C_rr = sign(omega) T / (P Ro), P = -F_y".to_string(),
        omega: c.iter().map(|p| p.0).collect(),
        coefficient: c.iter().map(|p| p.1).collect(),
        peak: peak(rows, ro),
    }
}

/// [`rolling_resistance`] as JSON (`results.rolling_resistance`).
pub fn summary(rows: &[BranchLoad], ro: f64) -> serde_json::Value {
    serde_json::to_value(rolling_resistance(rows, ro)).unwrap_or_default()
}

/// `resistance.png`: C_rr against |ω| (log axis), with the peak as its own marked series.
pub fn plot(path: &Path, rows: &[BranchLoad], ro: f64) -> Result<(), String> {
    let c: Vec<(f64, f64)> = curve(rows, ro)
        .into_iter()
        .map(|(w, v)| (w.abs(), v))
        .collect();
    let pk: Vec<(f64, f64)> = peak(rows, ro)
        .map(|p| vec![(p.omega.abs(), p.coefficient)])
        .unwrap_or_default();
    let peak_name = match pk.first() {
        Some((w, v)) => format!("peak: C_rr = {v:.4e} at omega = {w:.4} rad/s"),
        None => "no interior peak on this branch".to_string(),
    };
    png::chart(
        path,
        "Rolling resistance along the steady branch",
        png::Axis::log10("omega (rad/s)"),
        png::Axis::linear("C_rr = T / (P Ro) (dimensionless)"),
        &[("C_rr", &c), (&peak_name, &pk)],
    )
    .map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;
    fn row(step: usize, omega: f64, torque: f64) -> BranchLoad {
        BranchLoad {
            step,
            omega,
            hub_force_y: -4.0,
            hub_torque: torque,
        }
    }

    #[test]
    fn peak_of_a_parabola_in_log_omega_is_exact() {
        // C_rr(ω) = 0.01 − 0.002 (ln ω − ln 1.7)², sampled unevenly: the vertex is recovered.
        let c = |w: f64| 0.01 - 0.002 * (w.ln() - 1.7f64.ln()).powi(2);
        let ws = [0.3, 0.5, 1.1, 2.4, 4.0, 9.0];
        let rows: Vec<BranchLoad> = ws
            .iter()
            .enumerate()
            .map(|(i, &w)| row(i, w, c(w) * 4.0 * 2.0))
            .collect();
        let p = peak(&rows, 2.0).expect("a peak");
        assert!((p.omega - 1.7).abs() < 1e-12, "{p:?}");
        assert!((p.coefficient - 0.01).abs() < 1e-15, "{p:?}");
        assert_eq!(p.step, 3);
        // Walked the other way (decreasing ω), and at negative ω (clockwise, T < 0 dissipates).
        let rev: Vec<BranchLoad> = rows.iter().rev().cloned().collect();
        assert_eq!(peak(&rev, 2.0), Some(p));
        let neg: Vec<BranchLoad> = rows
            .iter()
            .map(|r| row(r.step, -r.omega, -r.hub_torque))
            .collect();
        let q = peak(&neg, 2.0).expect("a peak");
        assert!((q.omega + 1.7).abs() < 1e-12 && (q.coefficient - 0.01).abs() < 1e-15);
    }

    #[test]
    fn a_monotone_branch_has_no_peak() {
        let rows: Vec<BranchLoad> = (1..6).map(|i| row(i, i as f64, 0.1 * i as f64)).collect();
        assert_eq!(peak(&rows, 2.0), None);
        assert_eq!(peak(&rows[..2], 2.0), None);
        // Unloaded points have no coefficient.
        let mut r = row(0, 1.0, 0.1);
        r.hub_force_y = 0.0;
        assert!(coefficient(&r, 2.0).is_nan());
        assert!(summary(&rows, 2.0)["peak"].is_null());
    }
}
