//! Reference elements: tensor-product Lagrange shape functions on [-1, 1]², Gauss rules,
//! and tabulated cell / facet values.
//!
//! Local node ordering is tensor-product: node `a = i + (p + 1)·j`, where `i` runs along the
//! first reference coordinate ξ (radial direction in the annulus) and `j` along η
//! (circumferential direction, counter-clockwise). Q1 has p = 1 (4 nodes), Q2 has p = 2 (9 nodes,
//! the centre node is `a = 4`). Nodes sit at ξ ∈ {-1, 1} (Q1) and {-1, 0, 1} (Q2).

pub mod hex;
pub mod hierarchical;
pub mod quadrature;

pub use quadrature::{gauss_1d, QuadRule};

/// Values of the 1D Lagrange basis of degree `p` (1 or 2) and of its derivative at `x`.
#[inline]
pub fn lagrange_1d(p: usize, x: f64) -> ([f64; 3], [f64; 3]) {
    match p {
        1 => ([0.5 * (1.0 - x), 0.5 * (1.0 + x), 0.0], [-0.5, 0.5, 0.0]),
        _ => (
            [0.5 * x * (x - 1.0), 1.0 - x * x, 0.5 * x * (x + 1.0)],
            [x - 0.5, -2.0 * x, x + 0.5],
        ),
    }
}

/// Tensor-product Lagrange element of degree `P` with `N = (P + 1)²` nodes.
pub trait Lagrange2D: Copy + Send + Sync + 'static {
    const P: usize;
    const N: usize;
    /// Shape values and reference gradients at (ξ, η).
    fn eval(xi: f64, eta: f64, n: &mut [f64], dn: &mut [[f64; 2]]) {
        let (nx, dx) = lagrange_1d(Self::P, xi);
        let (ny, dy) = lagrange_1d(Self::P, eta);
        let m = Self::P + 1;
        for j in 0..m {
            for i in 0..m {
                let a = i + m * j;
                n[a] = nx[i] * ny[j];
                dn[a] = [dx[i] * ny[j], nx[i] * dy[j]];
            }
        }
    }
    /// Reference coordinate of node `a`.
    fn node_ref(a: usize) -> (f64, f64) {
        let m = Self::P + 1;
        let (i, j) = (a % m, a / m);
        let h = 2.0 / Self::P as f64;
        (-1.0 + h * i as f64, -1.0 + h * j as f64)
    }
}

/// Bilinear 4-node quadrilateral.
#[derive(Clone, Copy, Debug)]
pub struct Q1;
/// Biquadratic 9-node quadrilateral.
#[derive(Clone, Copy, Debug)]
pub struct Q2;

impl Lagrange2D for Q1 {
    const P: usize = 1;
    const N: usize = 4;
}
impl Lagrange2D for Q2 {
    const P: usize = 2;
    const N: usize = 9;
}

/// Shape values and reference gradients tabulated at the points of a rule.
#[derive(Clone, Debug)]
pub struct ShapeTable<const N: usize> {
    pub points: Vec<(f64, f64)>,
    pub weights: Vec<f64>,
    pub n: Vec<[f64; N]>,
    pub dn: Vec<[[f64; 2]; N]>,
    /// Second reference derivatives (∂ξξ, ∂ξη, ∂ηη).
    pub d2n: Vec<[[f64; 3]; N]>,
}

/// Second derivatives of the 1D Lagrange basis of degree `p` (1 or 2) on [-1, 1].
pub fn lagrange_1d_second(p: usize) -> [f64; 3] {
    match p {
        1 => [0.0; 3],
        _ => [1.0, -2.0, 1.0],
    }
}

impl<const N: usize> ShapeTable<N> {
    /// Tabulate element `E` (with `E::N == N`) at arbitrary reference points.
    pub fn new<E: Lagrange2D>(points: Vec<(f64, f64)>, weights: Vec<f64>) -> Self {
        assert_eq!(E::N, N, "element/node-count mismatch");
        let mut n = Vec::with_capacity(points.len());
        let mut dn = Vec::with_capacity(points.len());
        let mut d2n = Vec::with_capacity(points.len());
        let m = E::P + 1;
        let dd = lagrange_1d_second(E::P);
        for &(x, y) in &points {
            let mut nv = [0.0; N];
            let mut dv = [[0.0; 2]; N];
            E::eval(x, y, &mut nv, &mut dv);
            let (nx, dx) = lagrange_1d(E::P, x);
            let (ny, dy) = lagrange_1d(E::P, y);
            let mut d2 = [[0.0; 3]; N];
            for j in 0..m {
                for i in 0..m {
                    d2[i + m * j] = [dd[i] * ny[j], dx[i] * dy[j], nx[i] * dd[j]];
                }
            }
            n.push(nv);
            dn.push(dv);
            d2n.push(d2);
        }
        Self {
            points,
            weights,
            n,
            dn,
            d2n,
        }
    }
    /// Tabulate at a tensor Gauss rule with `q` points per direction.
    pub fn gauss<E: Lagrange2D>(q: usize) -> Self {
        let r = QuadRule::gauss_2d(q);
        Self::new::<E>(r.points, r.weights)
    }
    /// Tabulate on the facet ξ = `xi` (radial boundary of a cell; `xi = 1` is the outer side)
    /// at `q` Gauss points in η. The weights are the 1D weights in η.
    pub fn facet_xi<E: Lagrange2D>(xi: f64, q: usize) -> Self {
        let (x, w) = gauss_1d(q);
        Self::new::<E>(x.iter().map(|&e| (xi, e)).collect(), w)
    }
    pub fn len(&self) -> usize {
        self.weights.len()
    }
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[allow(clippy::needless_range_loop)] // dn[a][dir]: derivative index as in the formulas
    fn partition_and_nodality<E: Lagrange2D, const N: usize>() {
        let mut n = [0.0; N];
        let mut dn = [[0.0; 2]; N];
        for &(x, y) in &[(0.3, -0.7), (-0.9, 0.1), (0.0, 0.0)] {
            E::eval(x, y, &mut n, &mut dn);
            let s: f64 = n.iter().sum();
            let sx: f64 = dn.iter().map(|d| d[0]).sum();
            let sy: f64 = dn.iter().map(|d| d[1]).sum();
            assert!((s - 1.0).abs() < 1e-14 && sx.abs() < 1e-14 && sy.abs() < 1e-14);
            // Reproduce a linear field exactly: Σ N_a ξ_a = ξ.
            let lin: f64 = (0..N).map(|a| n[a] * E::node_ref(a).0).sum();
            assert!((lin - x).abs() < 1e-14);
        }
        for b in 0..N {
            let (x, y) = E::node_ref(b);
            E::eval(x, y, &mut n, &mut dn);
            for (a, &na) in n.iter().enumerate() {
                let expect = if a == b { 1.0 } else { 0.0 };
                assert!((na - expect).abs() < 1e-14);
            }
        }
        // Derivatives against central differences.
        let (x, y) = (0.23, -0.41);
        let h = 1e-6;
        let (mut np, mut nm) = ([0.0; N], [0.0; N]);
        let mut d = [[0.0; 2]; N];
        E::eval(x, y, &mut n, &mut dn);
        for dir in 0..2 {
            let (dx, dy) = if dir == 0 { (h, 0.0) } else { (0.0, h) };
            E::eval(x + dx, y + dy, &mut np, &mut d);
            E::eval(x - dx, y - dy, &mut nm, &mut d);
            for a in 0..N {
                assert!(((np[a] - nm[a]) / (2.0 * h) - dn[a][dir]).abs() < 1e-8);
            }
        }
    }

    #[test]
    fn q1_q2_basis_properties() {
        partition_and_nodality::<Q1, 4>();
        partition_and_nodality::<Q2, 9>();
    }
}
