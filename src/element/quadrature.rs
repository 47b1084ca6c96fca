//! Gauss–Legendre rules on [-1, 1] and their tensor products on [-1, 1]².
//!
//! ∫_{-1}^{1} f(ξ) dξ ≈ Σ_q w_q f(ξ_q), exact for polynomials of degree ≤ 2n − 1 with n
//! points; the weights sum to 2 (4 on the square). Reference coordinates are dimensionless: a
//! physical integral takes the Jacobian determinant of the cell map as a factor.

/// Gauss–Legendre points and weights with `n` points (1 ≤ n ≤ 6; larger n is clamped to 6),
/// exact for polynomials of degree 2n − 1.
pub fn gauss_1d(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (x, w): (&[f64], &[f64]) = match n {
        0 | 1 => (&[0.0], &[2.0]),
        2 => {
            const A: f64 = 0.577_350_269_189_625_8;
            (&[-A, A], &[1.0, 1.0])
        }
        3 => {
            const A: f64 = 0.774_596_669_241_483_4;
            (&[-A, 0.0, A], &[5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0])
        }
        4 => (
            &[
                -0.861_136_311_594_052_6,
                -0.339_981_043_584_856_3,
                0.339_981_043_584_856_3,
                0.861_136_311_594_052_6,
            ],
            &[
                0.347_854_845_137_453_9,
                0.652_145_154_862_546_1,
                0.652_145_154_862_546_1,
                0.347_854_845_137_453_9,
            ],
        ),
        5 => (
            &[
                -0.906_179_845_938_664,
                -0.538_469_310_105_683_1,
                0.0,
                0.538_469_310_105_683_1,
                0.906_179_845_938_664,
            ],
            &[
                0.236_926_885_056_189_1,
                0.478_628_670_499_366_5,
                0.568_888_888_888_888_9,
                0.478_628_670_499_366_5,
                0.236_926_885_056_189_1,
            ],
        ),
        _ => (
            &[
                -0.932_469_514_203_152,
                -0.661_209_386_466_264_5,
                -0.238_619_186_083_196_9,
                0.238_619_186_083_196_9,
                0.661_209_386_466_264_5,
                0.932_469_514_203_152,
            ],
            &[
                0.171_324_492_379_170_3,
                0.360_761_573_048_138_6,
                0.467_913_934_572_691,
                0.467_913_934_572_691,
                0.360_761_573_048_138_6,
                0.171_324_492_379_170_3,
            ],
        ),
    };
    (x.to_vec(), w.to_vec())
}

/// A 2D quadrature rule on [-1, 1]².
#[derive(Clone, Debug)]
pub struct QuadRule {
    pub points: Vec<(f64, f64)>,
    pub weights: Vec<f64>,
    /// Points per direction (tensor rules); point `(i, j)` has index `i + q·j`, i along ξ.
    pub q: usize,
}

impl QuadRule {
    pub fn gauss_2d(q: usize) -> Self {
        let (x, w) = gauss_1d(q);
        let q = x.len();
        let mut points = Vec::with_capacity(q * q);
        let mut weights = Vec::with_capacity(q * q);
        for j in 0..q {
            for i in 0..q {
                points.push((x[i], x[j]));
                weights.push(w[i] * w[j]);
            }
        }
        Self { points, weights, q }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_rules_integrate_monomials_exactly() {
        for n in 1..=6 {
            let (x, w) = gauss_1d(n);
            for deg in 0..(2 * n) {
                let num: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(deg as i32)).sum();
                let exact = if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg as f64 + 1.0)
                };
                assert!(
                    (num - exact).abs() < 1e-14,
                    "n={n} deg={deg}: {num} vs {exact}"
                );
            }
        }
        let r = QuadRule::gauss_2d(3);
        let s: f64 = r.weights.iter().sum();
        assert!((s - 4.0).abs() < 1e-14);
    }
}
