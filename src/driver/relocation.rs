//! Moving-mesh (r-) adaptivity of the solid's annulus (`tread adapt --refine r`): the cell
//! boundaries of the structured annulus are moved toward the contact patch (same cells, same
//! connectivity, same number of unknowns) by equidistributing a monitor built from the error
//! indicator, and the problem is solved again on the moved mesh, N times.
//!
//! The annulus is a tensor product of radial and circumferential cell boundaries, so each
//! direction is relocated by the one-dimensional equidistribution: with the squared indicators
//! η_K² summed over the cells between two consecutive boundaries (a circumferential column of
//! cells, or a radial layer) and divided by the width of the slab (an angle, or a radius
//! difference), d_k = (Σ η_K² / Δ_k)^{1/2} is the indicator density of slab k, and
//!
//! ```text
//! M_k = 1 + α ê_k^{1/β},   ê_k = d_k / max d,   w_k = (1 − γ) M_k + γ M̄
//! ```
//!
//! (M̄ the mean of M over the slabs) is a piecewise constant weight on the current slabs. The new
//! boundaries put an equal share of ∫ w over the slab width on every slab (the exact solution of
//! the 1D mesh equation w x_ξ = const). α, β and γ have the meanings of the moving mesh of the
//! cavity ([`crate::adapt::moving_mesh`]): α the monitor amplitude (slab sizes vary by at most a
//! factor 1 + α between the largest and the smallest), β ≥ 1 the root spreading the monitor
//! away from its maximum, γ ∈ [0, 1] the uniform part (γ = 1: no motion). A 1D equidistribution
//! keeps the boundaries in order, so no cell inverts; the node rings stay circles, so the
//! steady mode's ring derivatives and ring history apply on every moved mesh. The first
//! circumferential boundary stays at θ = −π/2 (the bottom of the body, where the road is) and
//! the radii Ri and Ro stay put.

use crate::adapt::moving_mesh::MonitorParams;
use crate::mesh::{annulus_with_breaks, AnnulusSpec, Mesh};

/// The new boundaries of the slabs `breaks` (increasing) that equidistribute the monitor of the
/// squared indicators `sq[k]` summed over slab k (see the module docs). Returns `breaks` when
/// every indicator vanishes.
pub fn equidistribute(breaks: &[f64], sq: &[f64], m: &MonitorParams) -> Vec<f64> {
    let n = breaks.len().saturating_sub(1);
    if n == 0 || sq.len() != n {
        return breaks.to_vec();
    }
    let width: Vec<f64> = breaks.windows(2).map(|w| w[1] - w[0]).collect();
    let d: Vec<f64> = sq
        .iter()
        .zip(&width)
        .map(|(&s, &h)| {
            if s > 0.0 && h > 0.0 {
                (s / h).sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let dmax = d.iter().copied().fold(0.0, f64::max);
    if !(dmax > 0.0 && dmax.is_finite()) {
        return breaks.to_vec();
    }
    let mon: Vec<f64> = d
        .iter()
        .map(|&v| 1.0 + m.alpha * (v / dmax).powf(1.0 / m.beta))
        .collect();
    let mean = mon.iter().sum::<f64>() / n as f64;
    let w: Vec<f64> = mon
        .iter()
        .map(|&v| (1.0 - m.gamma) * v + m.gamma * mean)
        .collect();
    // Cumulative ∫ w over the slabs, then its inverse at n equal shares.
    let mut cum = vec![0.0; n + 1];
    for k in 0..n {
        cum[k + 1] = cum[k] + w[k] * width[k];
    }
    let total = cum[n];
    let mut out = Vec::with_capacity(n + 1);
    out.push(breaks[0]);
    let mut k = 0;
    for j in 1..n {
        let target = total * j as f64 / n as f64;
        while k + 1 < n && cum[k + 1] < target {
            k += 1;
        }
        let frac = (target - cum[k]) / (cum[k + 1] - cum[k]);
        out.push(breaks[k] + frac.clamp(0.0, 1.0) * width[k]);
    }
    out.push(breaks[n]);
    out
}

/// The annulus of `spec` with its boundaries moved by one relocation from the squared
/// indicators `sq` of the current mesh of boundaries (`rb`, `tb`) (cell j · n_theta + k in
/// radial layer j, column k): the new boundaries and the mesh.
pub fn relocate(
    spec: &AnnulusSpec,
    rb: &[f64],
    tb: &[f64],
    sq: &[f64],
    m: &MonitorParams,
) -> (Vec<f64>, Vec<f64>, Mesh) {
    let (n_r, n_t) = (rb.len() - 1, tb.len() - 1);
    let (mut rows, mut cols) = (vec![0.0; n_r], vec![0.0; n_t]);
    for (c, &s) in sq.iter().enumerate().take(n_r * n_t) {
        rows[c / n_t] += s;
        cols[c % n_t] += s;
    }
    let rb = equidistribute(rb, &rows, m);
    let tb = equidistribute(tb, &cols, m);
    let mesh = annulus_with_breaks(spec, &rb, &tb);
    (rb, tb, mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(alpha: f64, beta: f64, gamma: f64) -> MonitorParams {
        MonitorParams {
            alpha,
            beta,
            gamma,
            ..Default::default()
        }
    }

    #[test]
    fn equidistribution_puts_equal_weight_on_every_slab() {
        let breaks: Vec<f64> = (0..=10).map(|k| k as f64 * 0.1).collect();
        // A peak in slab 3.
        let sq: Vec<f64> = (0..10).map(|k| if k == 3 { 1.0 } else { 1e-4 }).collect();
        let m = params(4.0, 1.0, 0.0);
        let out = equidistribute(&breaks, &sq, &m);
        assert_eq!(out.len(), 11);
        assert_eq!(out[0], 0.0);
        assert_eq!(out[10], 1.0);
        assert!(out.windows(2).all(|w| w[1] > w[0]), "{out:?}");
        // The old weight w (piecewise constant on the old slabs) integrates to the same share
        // over every new slab.
        let d: Vec<f64> = sq.iter().map(|s| (s / 0.1f64).sqrt()).collect();
        let dmax = d.iter().copied().fold(0.0, f64::max);
        let w = |x: f64| {
            let k = ((x / 0.1).floor() as usize).min(9);
            1.0 + 4.0 * d[k] / dmax
        };
        let share = |a: f64, b: f64| {
            let n = 20000;
            (0..n)
                .map(|i| w(a + (b - a) * (i as f64 + 0.5) / n as f64) * (b - a) / n as f64)
                .sum::<f64>()
        };
        let s0 = share(out[0], out[1]);
        for j in 1..10 {
            let sj = share(out[j], out[j + 1]);
            assert!((sj - s0).abs() < 1e-3 * s0, "slab {j}: {sj} vs {s0}");
        }
        // The slab of the peak shrinks by the factor of its weight: 1 + α.
        let h: Vec<f64> = out.windows(2).map(|w| w[1] - w[0]).collect();
        let (hmin, hmax) = (
            h.iter().copied().fold(f64::INFINITY, f64::min),
            h.iter().copied().fold(0.0, f64::max),
        );
        assert!(hmax / hmin <= 5.0 + 1e-9, "{hmax} / {hmin}");
        assert!(hmax / hmin > 2.0, "{hmax} / {hmin}");
    }

    #[test]
    fn no_motion_without_alpha_or_with_full_smoothing_or_zero_indicators() {
        let breaks = [0.0, 0.2, 0.5, 0.9, 1.0];
        let sq = [1.0, 0.0, 3.0, 0.5];
        for m in [params(0.0, 4.0, 0.0), params(4.0, 4.0, 1.0)] {
            let out = equidistribute(&breaks, &sq, &m);
            // A uniform weight: equal slabs.
            for (j, x) in out.iter().enumerate() {
                assert!((x - j as f64 * 0.25).abs() < 1e-12, "{out:?}");
            }
        }
        let out = equidistribute(&breaks, &[0.0; 4], &params(4.0, 4.0, 0.0));
        assert_eq!(out, breaks.to_vec());
    }
}
