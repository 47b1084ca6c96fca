//! One-dimensional bases for tensor-product cells of per-cell degree, and Gauss rules of any
//! order.
//!
//! A 1D basis of degree `p` on [-1, 1] has `p + 1` functions in a fixed *entity order*:
//! index 0 is the end function of s = -1, index 1 the end function of s = +1, indices
//! 2..=p are interior functions (they vanish at both ends). A 2D cell function is the tensor
//! product `b_i(ξ) b_j(η)`; `(i, j)` with both `< 2` belong to a vertex, one `< 2` to an edge,
//! none to the interior.
//!
//! * [`Basis1d::Lagrange`] (p = 1 or 2): nodal at s = -1, 1, 0; the Q1 and 9-node Q2 spaces.
//! * [`Basis1d::Hierarchical`] (p = 1..=[`MAX_DEGREE`]): the end functions (1 ∓ s)/2 and the
//!   integrated Legendre polynomials
//!   φ_k(s) = (P_k(s) − P_{k−2}(s)) / √(2(2k − 1)), k ≥ 2,
//!   whose derivatives φ_k' = √((2k − 1)/2) P_{k−1} are L²-orthonormal on [-1, 1]. The basis of
//!   degree p is the basis of degree p − 1 plus one function (hierarchical), and φ_k(−s) =
//!   (−1)^k φ_k(s).

/// Largest polynomial degree of a hierarchical cell (local error problems use up to this too).
pub const MAX_DEGREE: usize = 10;
/// Largest number of 1D functions.
pub const MAX_1D: usize = MAX_DEGREE + 1;

/// Kind of 1D basis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Basis1d {
    Lagrange,
    Hierarchical,
}

/// Legendre polynomials P_0..=P_n and their first and second derivatives at `s`.
fn legendre(n: usize, s: f64, p: &mut [f64], dp: &mut [f64], d2p: &mut [f64]) {
    p[0] = 1.0;
    dp[0] = 0.0;
    d2p[0] = 0.0;
    if n >= 1 {
        p[1] = s;
        dp[1] = 1.0;
        d2p[1] = 0.0;
    }
    for k in 2..=n {
        let kf = k as f64;
        p[k] = ((2.0 * kf - 1.0) * s * p[k - 1] - (kf - 1.0) * p[k - 2]) / kf;
        dp[k] = ((2.0 * kf - 1.0) * (p[k - 1] + s * dp[k - 1]) - (kf - 1.0) * dp[k - 2]) / kf;
        d2p[k] =
            ((2.0 * kf - 1.0) * (2.0 * dp[k - 1] + s * d2p[k - 1]) - (kf - 1.0) * d2p[k - 2]) / kf;
    }
}

impl Basis1d {
    /// Values, first and second derivatives of the `p + 1` functions at `s` (entity order).
    #[inline]
    pub fn eval(self, p: usize, s: f64) -> ([f64; MAX_1D], [f64; MAX_1D], [f64; MAX_1D]) {
        let mut v = [0.0; MAX_1D];
        let mut d = [0.0; MAX_1D];
        let mut d2 = [0.0; MAX_1D];
        match self {
            Basis1d::Lagrange if p == 2 => {
                v[0] = 0.5 * s * (s - 1.0);
                v[1] = 0.5 * s * (s + 1.0);
                v[2] = 1.0 - s * s;
                d[0] = s - 0.5;
                d[1] = s + 0.5;
                d[2] = -2.0 * s;
                d2[0] = 1.0;
                d2[1] = 1.0;
                d2[2] = -2.0;
            }
            _ => {
                v[0] = 0.5 * (1.0 - s);
                v[1] = 0.5 * (1.0 + s);
                d[0] = -0.5;
                d[1] = 0.5;
                if p >= 2 {
                    let mut lp = [0.0; MAX_1D];
                    let mut ld = [0.0; MAX_1D];
                    let mut ld2 = [0.0; MAX_1D];
                    legendre(p, s, &mut lp, &mut ld, &mut ld2);
                    for k in 2..=p {
                        let c = 1.0 / (2.0 * (2.0 * k as f64 - 1.0)).sqrt();
                        v[k] = c * (lp[k] - lp[k - 2]);
                        d[k] = c * (ld[k] - ld[k - 2]);
                        d2[k] = c * (ld2[k] - ld2[k - 2]);
                    }
                }
            }
        }
        (v, d, d2)
    }
    /// Largest degree this kind supports.
    pub fn max_degree(self) -> usize {
        match self {
            Basis1d::Lagrange => 2,
            Basis1d::Hierarchical => MAX_DEGREE,
        }
    }
}

/// Gauss–Legendre points and weights on [-1, 1] with `n ≥ 1` points (Newton on P_n, exact for
/// degree 2n − 1).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let n = n.max(1);
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        // Chebyshev-like initial guess of the i-th largest root.
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let kf = k as f64;
                let p2 = ((2.0 * kf - 1.0) * z * p1 - (kf - 1.0) * p0) / kf;
                p0 = p1;
                p1 = p2;
            }
            if n == 1 {
                p1 = z;
                p0 = 1.0;
            }
            dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                break;
            }
        }
        if n == 1 {
            z = 0.0;
            dp = 1.0;
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        let wi = 2.0 / ((1.0 - z * z) * dp * dp);
        w[i] = wi;
        w[n - 1 - i] = wi;
    }
    (x, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_rules_exact() {
        for n in 1..=12 {
            let (x, w) = gauss_legendre(n);
            for deg in 0..(2 * n) {
                let num: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(deg as i32)).sum();
                let exact = if deg % 2 == 1 {
                    0.0
                } else {
                    2.0 / (deg as f64 + 1.0)
                };
                assert!((num - exact).abs() < 1e-13, "n={n} deg={deg}");
            }
        }
    }

    #[test]
    fn integrated_legendre_properties() {
        let (x, w) = gauss_legendre(12);
        let p = MAX_DEGREE;
        // Interior functions vanish at both ends; derivatives L²-orthonormal.
        let (v0, _, _) = Basis1d::Hierarchical.eval(p, -1.0);
        let (v1, _, _) = Basis1d::Hierarchical.eval(p, 1.0);
        for k in 2..=p {
            assert!(v0[k].abs() < 1e-14 && v1[k].abs() < 1e-14);
        }
        for k in 2..=p {
            for l in 2..=p {
                let s: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(&s, &w)| {
                        let (_, d, _) = Basis1d::Hierarchical.eval(p, s);
                        w * d[k] * d[l]
                    })
                    .sum();
                let e = if k == l { 1.0 } else { 0.0 };
                assert!((s - e).abs() < 1e-12, "k={k} l={l} {s}");
            }
        }
        // Derivatives against differences, both kinds.
        for (kind, p) in [(Basis1d::Hierarchical, p), (Basis1d::Lagrange, 2)] {
            let (s, h) = (0.37, 1e-6);
            let (_, d, d2) = kind.eval(p, s);
            let (vp, dp, _) = kind.eval(p, s + h);
            let (vm, dm, _) = kind.eval(p, s - h);
            for k in 0..=p {
                assert!(((vp[k] - vm[k]) / (2.0 * h) - d[k]).abs() < 1e-7);
                assert!(((dp[k] - dm[k]) / (2.0 * h) - d2[k]).abs() < 1e-6);
            }
        }
    }
}
