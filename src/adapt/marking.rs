//! The part every adapt loop shares: a per-cell estimate, the estimator interface that produces
//! it, and the marking that turns it into the cells to refine (or coarsen).
//!
//! **Estimate.** [`CellEstimate`] holds one indicator η_K ≥ 0 per cell (in the loop's cell
//! order) and the global estimate η = (Σ_K η_K²)^{1/2}; where the exact error ‖e‖ of the same
//! norm is known it also carries it, and the effectivity index is η / ‖e‖. Indicators are
//! built from their squares ([`CellEstimate::from_squares`]): a negative square (round-off of a
//! quadratic form that vanishes, or a tangent that is not positive) or a non-finite one counts
//! as 0.
//!
//! **Estimators.** [`CellEstimator`] is implemented by the quadtree estimators of the model
//! problems ([`super::estimate`], context [`super::estimate::Context`]) and by the estimators
//! of the finite-strain solid ([`crate::physics::estimate`], context
//! [`crate::physics::estimate::SolidContext`]); the adapt loops of both
//! ([`super::driver`], [`crate::driver::adaptive`]) call `estimator.estimate(&context)`.
//!
//! **Marking.** With indicators η_K and θ ∈ (0, 1]:
//! * Dörfler's bulk criterion ([`dorfler`]): the smallest set M with
//!   Σ_{K ∈ M} η_K² ≥ θ Σ_K η_K². Taking the cells by decreasing η_K until the sum is reached
//!   gives a set of minimal size; among cells of equal η_K the lower index is taken first, so
//!   the set is deterministic. Cells with η_K = 0 are never marked (they add nothing), so a
//!   zero estimate marks nothing. [`dorfler_among`] takes the cells from a list of candidates
//!   only (e.g. cells whose degree can still be raised), the total still over all cells.
//! * maximum marking ([`maximum`]): every cell with η_K ≥ θ max_K η_K (and η_K > 0).
//! * coarsening: a cell (or a family of cells) is a candidate when its (predicted) share of the
//!   squared estimate is below c η² / N, a fraction c of the equal share of N cells
//!   ([`coarsening_limit`]).

/// Indicators per cell and the global estimate; optionally the exact error of the same norm.
#[derive(Clone, Debug, PartialEq)]
pub struct CellEstimate {
    /// η_K ≥ 0 per cell.
    pub indicators: Vec<f64>,
    /// η = (Σ η_K²)^{1/2}.
    pub global: f64,
    /// The exact error ‖e‖ where a reference solution is known.
    pub exact_error: Option<f64>,
}

impl CellEstimate {
    /// The estimate of the squared indicators `sq` (negative or non-finite squares count as 0).
    pub fn from_squares(sq: Vec<f64>) -> Self {
        let sq: Vec<f64> = sq
            .into_iter()
            .map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 })
            .collect();
        Self {
            global: sq.iter().sum::<f64>().sqrt(),
            indicators: sq.into_iter().map(f64::sqrt).collect(),
            exact_error: None,
        }
    }

    /// The same estimate with the exact error `error` attached.
    pub fn with_exact_error(mut self, error: f64) -> Self {
        self.exact_error = Some(error);
        self
    }

    /// The effectivity index η / ‖e‖ (`None` without an exact error).
    pub fn effectivity(&self) -> Option<f64> {
        self.exact_error.map(|e| self.global / e)
    }

    /// Σ η_K², summed from the indicators in cell order (the total the marking uses).
    pub fn squared_total(&self) -> f64 {
        squared_total(&self.indicators)
    }

    /// The cells marked by `marking`.
    pub fn mark(&self, marking: Marking) -> Vec<usize> {
        mark(&self.indicators, marking)
    }
}

/// One estimator interface: a per-cell estimate of the state described by the context `C`.
pub trait CellEstimator<C: ?Sized> {
    /// Why an estimate can fail ([`std::convert::Infallible`] if it cannot).
    type Error;
    fn name(&self) -> &'static str;
    fn estimate(&self, ctx: &C) -> Result<CellEstimate, Self::Error>;
}

/// Marking strategy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Marking {
    /// Dörfler bulk criterion with parameter θ ∈ (0, 1] on the squared indicators.
    Dorfler(f64),
    /// Mark η_K ≥ θ max η.
    Maximum(f64),
}

/// The cells (indices into `eta`) marked by `marking`.
pub fn mark(eta: &[f64], marking: Marking) -> Vec<usize> {
    match marking {
        Marking::Dorfler(theta) => dorfler(eta, theta),
        Marking::Maximum(theta) => maximum(eta, theta),
    }
}

/// Σ η_K² in cell order.
pub fn squared_total(eta: &[f64]) -> f64 {
    eta.iter().map(|e| e * e).sum()
}

/// Dörfler marking: the fewest cells whose squared indicators make up θ of the total (see the
/// module docs), by decreasing indicator.
pub fn dorfler(eta: &[f64], theta: f64) -> Vec<usize> {
    dorfler_among(eta, theta, 0..eta.len())
}

/// [`dorfler`] choosing among `candidates` only; the total Σ η_K² is over all cells, so when
/// the candidates cannot reach θ of it they are all marked (those with η_K > 0).
pub fn dorfler_among(
    eta: &[f64],
    theta: f64,
    candidates: impl IntoIterator<Item = usize>,
) -> Vec<usize> {
    let total = squared_total(eta);
    let mut idx: Vec<usize> = candidates.into_iter().collect();
    // Stable: equal indicators keep their (increasing) index order.
    idx.sort_by(|&a, &b| eta[b].total_cmp(&eta[a]));
    let mut acc = 0.0;
    let mut out = Vec::new();
    for k in idx {
        if acc >= theta * total || eta[k] <= 0.0 {
            break;
        }
        acc += eta[k] * eta[k];
        out.push(k);
    }
    out
}

/// Maximum marking: the cells with η_K ≥ θ max η and η_K > 0, in increasing index order.
pub fn maximum(eta: &[f64], theta: f64) -> Vec<usize> {
    let m = eta.iter().copied().fold(0.0, f64::max);
    (0..eta.len())
        .filter(|&k| eta[k] >= theta * m && eta[k] > 0.0)
        .collect()
}

/// The coarsening threshold c η² / N of the indicators `eta` (N cells): a fraction `fraction`
/// of the equal share of the squared estimate.
pub fn coarsening_limit(eta: &[f64], fraction: f64) -> f64 {
    fraction * squared_total(eta) / eta.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The smallest size of a set with Σ η² ≥ θ Σ η², by trying every subset.
    fn brute_force_size(eta: &[f64], theta: f64) -> usize {
        let total = squared_total(eta);
        let n = eta.len();
        (0u32..1 << n)
            .filter(|&m| {
                let s: f64 = (0..n)
                    .filter(|&k| m >> k & 1 == 1)
                    .map(|k| eta[k] * eta[k])
                    .sum();
                s >= theta * total
            })
            .map(|m| m.count_ones() as usize)
            .min()
            .unwrap_or(0)
    }

    fn sum_sq(eta: &[f64], set: &[usize]) -> f64 {
        set.iter().map(|&k| eta[k] * eta[k]).sum()
    }

    /// Pseudo-random indicators (a fixed linear congruential sequence), some repeated, some 0.
    fn sample(seed: u64, n: usize) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let r = (s >> 33) % 7;
                // Values in {0, 0.5, 1, 1.5, 2, 2.5, 3}: ties and zeros are common.
                0.5 * r as f64
            })
            .collect()
    }

    #[test]
    fn dorfler_marks_a_smallest_set_reaching_the_fraction() {
        for seed in 0..200 {
            let eta = sample(seed, 1 + (seed as usize % 11));
            let total = squared_total(&eta);
            for theta in [0.1, 0.25, 0.5, 0.7, 0.9, 1.0] {
                let m = dorfler(&eta, theta);
                let best = brute_force_size(&eta, theta);
                // A minimal set reaching θ (round-off aside: the values are multiples of 0.5,
                // so the sums are exact).
                assert!(
                    sum_sq(&eta, &m) >= theta * total,
                    "{eta:?} θ = {theta}: {m:?}"
                );
                // Zero-indicator cells never needed: the brute force needs no more of them.
                assert_eq!(m.len(), best, "{eta:?} θ = {theta}: {m:?}");
                assert!(m.iter().all(|&k| eta[k] > 0.0), "{eta:?}: {m:?}");
                let mut sorted = m.clone();
                sorted.sort_unstable();
                sorted.dedup();
                assert_eq!(sorted.len(), m.len(), "a cell marked twice: {m:?}");
            }
        }
    }

    #[test]
    fn dorfler_ties_take_the_lower_index_first() {
        // Four equal indicators, θ = 0.5: two cells, the first two.
        assert_eq!(dorfler(&[1.0, 1.0, 1.0, 1.0], 0.5), vec![0, 1]);
        // Larger first, then ties by index.
        assert_eq!(dorfler(&[1.0, 2.0, 1.0, 1.0], 0.6), vec![1, 0]);
        assert_eq!(dorfler(&[1.0, 2.0, 1.0, 1.0], 0.75), vec![1, 0, 2]);
    }

    #[test]
    fn dorfler_with_zero_indicators_and_theta_one() {
        // All zero: nothing to mark.
        assert!(dorfler(&[0.0; 5], 0.5).is_empty());
        assert!(dorfler(&[0.0; 5], 1.0).is_empty());
        assert!(dorfler(&[], 0.5).is_empty());
        // θ = 1: every cell with a positive indicator, none of the zero ones.
        let eta = [0.3, 0.0, 1e-3, 2.0, 0.0, 0.7];
        let mut m = dorfler(&eta, 1.0);
        m.sort_unstable();
        assert_eq!(m, vec![0, 2, 3, 5]);
        // θ = 1 with indicators in no particular order (the sum by decreasing η_K and the
        // total in cell order may round differently): still every cell.
        let eta: Vec<f64> = (0..50)
            .map(|k| 1.0 / (1.0 + ((17 * k) % 50) as f64).sqrt())
            .collect();
        assert_eq!(dorfler(&eta, 1.0).len(), 50);
    }

    #[test]
    fn dorfler_among_candidates_keeps_the_total_over_all_cells() {
        let eta = [3.0, 1.0, 1.0, 1.0];
        // Without cell 0 the candidates hold 3 of 12: θ = 0.5 marks all of them.
        assert_eq!(dorfler_among(&eta, 0.5, [1, 2, 3]), vec![1, 2, 3]);
        // θ = 0.1 of 12 is 1.2: two candidates.
        assert_eq!(dorfler_among(&eta, 0.1, [1, 2, 3]), vec![1, 2]);
        assert_eq!(dorfler_among(&eta, 0.5, [0, 1, 2, 3]), dorfler(&eta, 0.5));
    }

    #[test]
    fn maximum_marking_and_the_coarsening_limit() {
        let eta = [0.1, 1.0, 0.5, 0.0, 0.8];
        assert_eq!(maximum(&eta, 0.5), vec![1, 2, 4]);
        assert_eq!(maximum(&eta, 1.0), vec![1]);
        assert_eq!(maximum(&eta, 0.0), vec![0, 1, 2, 4]);
        assert!(maximum(&[0.0, 0.0], 0.5).is_empty());
        let total = 0.01 + 1.0 + 0.25 + 0.64;
        assert!((coarsening_limit(&eta, 0.1) - 0.1 * total / 5.0).abs() < 1e-15);
        assert_eq!(coarsening_limit(&[], 0.1), 0.0);
    }

    #[test]
    fn estimate_from_squares_clamps_and_reports_the_effectivity() {
        let e = CellEstimate::from_squares(vec![4.0, -1e-30, f64::NAN, 9.0]);
        assert_eq!(e.indicators, vec![2.0, 0.0, 0.0, 3.0]);
        assert_eq!(e.global, 13f64.sqrt());
        assert_eq!(e.effectivity(), None);
        let e = e.with_exact_error(13f64.sqrt() / 2.0);
        assert!((e.effectivity().unwrap() - 2.0).abs() < 1e-15);
    }
}
