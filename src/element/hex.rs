//! Reference hexahedra: tensor-product Lagrange shape functions on [-1, 1]³, tensor Gauss
//! rules, the six faces with their facet quadrature (Gauss and Gauss–Lobatto) and the surface
//! map (area element and outward normal) of a cell map.
//!
//! # Conventions
//!
//! Reference coordinates (ξ, η, ζ) = (ξ0, ξ1, ξ2): ξ radial, η circumferential, ζ axial (the
//! axle x3), extending the 2D order of [`super::Lagrange2D`]. Local node
//! `a = i + m·j + m²·k` with m = p + 1, i along ξ, j along η, k along ζ; so the k-th axial layer
//! of a hexahedron, nodes `m²·k .. m²·(k+1)`, is a 2D quadrilateral in the 2D ordering. Hex8 has
//! p = 1 (8 nodes), Hex27 p = 2 (27 nodes). Nodes sit at ξ ∈ {-1, 1} (p = 1), {-1, 0, 1} (p = 2).
//!
//! A cell map X(ξ) has the Jacobian J with `J[(i, k)] = ∂X_i/∂ξ_k`; its columns t_k = ∂X/∂ξ_k are
//! the tangent vectors. Reference coordinates are dimensionless; lengths are those of X.
//!
//! # Faces
//!
//! Face `f` (0..6) fixes the reference coordinate `f / 2` at `-1` (f even) or `+1` (f odd):
//! 0: ξ = −1 (hub side), 1: ξ = +1 (outer side), 2: η = −1, 3: η = +1, 4: ζ = −1, 5: ζ = +1.
//! The face's free coordinates (u, v) are the two others in increasing order, and its local
//! nodes ([`face_nodes`]) are listed in the 2D tensor order `iu + m·iv`. The area vector of the
//! face at a point is `n dA = s · (t_{k+1} × t_{k+2})` (indices cyclic mod 3, k the fixed
//! coordinate, s = ±1 its side): for a map with det J > 0 this is the outward normal times the
//! area element per unit reference area du dv.

use super::quadrature::gauss_1d;
use nalgebra::{Matrix3, Vector3};

/// Values and derivatives of the 1D Lagrange basis of degree `p` at `x` (see
/// [`super::lagrange_1d`]).
pub use super::lagrange_1d;

/// Tensor-product Lagrange hexahedron of degree `P` with `N = (P + 1)³` nodes.
pub trait Lagrange3D: Copy + Send + Sync + 'static {
    const P: usize;
    const N: usize;
    /// Shape values `n[a]` and reference gradients `dn[a] = ∂N_a/∂(ξ, η, ζ)` at `x`.
    /// `n` and `dn` hold at least `N` entries.
    fn eval(x: [f64; 3], n: &mut [f64], dn: &mut [[f64; 3]]) {
        let (n0, d0) = lagrange_1d(Self::P, x[0]);
        let (n1, d1) = lagrange_1d(Self::P, x[1]);
        let (n2, d2) = lagrange_1d(Self::P, x[2]);
        let m = Self::P + 1;
        for k in 0..m {
            for j in 0..m {
                for i in 0..m {
                    let a = i + m * (j + m * k);
                    n[a] = n0[i] * n1[j] * n2[k];
                    dn[a] = [
                        d0[i] * n1[j] * n2[k],
                        n0[i] * d1[j] * n2[k],
                        n0[i] * n1[j] * d2[k],
                    ];
                }
            }
        }
    }
    /// Tensor indices (i, j, k) of local node `a`.
    fn node_index(a: usize) -> [usize; 3] {
        let m = Self::P + 1;
        [a % m, (a / m) % m, a / (m * m)]
    }
    /// Reference coordinates of local node `a`.
    fn node_ref(a: usize) -> [f64; 3] {
        let h = 2.0 / Self::P as f64;
        Self::node_index(a).map(|i| -1.0 + h * i as f64)
    }
}

/// Trilinear 8-node hexahedron.
#[derive(Clone, Copy, Debug)]
pub struct Hex8;
/// Triquadratic 27-node hexahedron.
#[derive(Clone, Copy, Debug)]
pub struct Hex27;

impl Lagrange3D for Hex8 {
    const P: usize = 1;
    const N: usize = 8;
}
impl Lagrange3D for Hex27 {
    const P: usize = 2;
    const N: usize = 27;
}

/// Gauss–Lobatto points and weights with `n` points (2 ≤ n ≤ 4; other n are clamped), exact for
/// polynomials of degree 2n − 3. The end points ±1 are included.
pub fn gauss_lobatto_1d(n: usize) -> (Vec<f64>, Vec<f64>) {
    match n {
        0..=2 => (vec![-1.0, 1.0], vec![1.0, 1.0]),
        3 => (vec![-1.0, 0.0, 1.0], vec![1.0 / 3.0, 4.0 / 3.0, 1.0 / 3.0]),
        _ => {
            let a = (0.2f64).sqrt();
            (
                vec![-1.0, -a, a, 1.0],
                vec![1.0 / 6.0, 5.0 / 6.0, 5.0 / 6.0, 1.0 / 6.0],
            )
        }
    }
}

/// A quadrature rule on [-1, 1]³ (tensor Gauss): point `(i, j, k)` has index `i + q·(j + q·k)`.
#[derive(Clone, Debug)]
pub struct QuadRule3D {
    pub points: Vec<[f64; 3]>,
    pub weights: Vec<f64>,
    /// Points per direction.
    pub q: usize,
}

impl QuadRule3D {
    /// Tensor Gauss rule with `q` points per direction (exact for degree 2q − 1 in each
    /// coordinate; 1 ≤ q ≤ 6).
    pub fn gauss_3d(q: usize) -> Self {
        let (x, w) = gauss_1d(q);
        let q = x.len();
        let mut points = Vec::with_capacity(q * q * q);
        let mut weights = Vec::with_capacity(q * q * q);
        for k in 0..q {
            for j in 0..q {
                for i in 0..q {
                    points.push([x[i], x[j], x[k]]);
                    weights.push(w[i] * w[j] * w[k]);
                }
            }
        }
        Self { points, weights, q }
    }
}

/// Which 1D rule a facet rule is built from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FacetPoints {
    Gauss,
    GaussLobatto,
}

/// The fixed reference coordinate of face `f` and its side (−1 or +1).
#[inline]
pub fn face_axis(f: usize) -> (usize, f64) {
    (f / 2, if f.is_multiple_of(2) { -1.0 } else { 1.0 })
}

/// The free reference coordinates (u, v) of face `f`, in increasing order.
#[inline]
pub fn face_free_axes(f: usize) -> [usize; 2] {
    match f / 2 {
        0 => [1, 2],
        1 => [0, 2],
        _ => [0, 1],
    }
}

/// Local nodes of face `f` of element `E`, in the 2D tensor order `iu + m·iv` of the face's free
/// coordinates (u, v) (see the module docs).
pub fn face_nodes<E: Lagrange3D>(f: usize) -> Vec<usize> {
    let m = E::P + 1;
    let (k, s) = face_axis(f);
    let fixed = if s < 0.0 { 0 } else { E::P };
    let [u, v] = face_free_axes(f);
    let mut out = Vec::with_capacity(m * m);
    for iv in 0..m {
        for iu in 0..m {
            let mut idx = [0usize; 3];
            idx[k] = fixed;
            idx[u] = iu;
            idx[v] = iv;
            out.push(idx[0] + m * (idx[1] + m * idx[2]));
        }
    }
    out
}

/// Quadrature on one face: 3D reference points on the face and weights per unit reference area
/// du dv (tensor order `iu + q·iv`).
#[derive(Clone, Debug)]
pub struct FacetRule3D {
    pub face: usize,
    pub points: Vec<[f64; 3]>,
    pub weights: Vec<f64>,
}

impl FacetRule3D {
    /// Tensor rule with `q` points per free direction on face `f`.
    pub fn new(f: usize, q: usize, kind: FacetPoints) -> Self {
        let (x, w) = match kind {
            FacetPoints::Gauss => gauss_1d(q),
            FacetPoints::GaussLobatto => gauss_lobatto_1d(q),
        };
        let (k, s) = face_axis(f);
        let [u, v] = face_free_axes(f);
        let mut points = Vec::with_capacity(x.len() * x.len());
        let mut weights = Vec::with_capacity(x.len() * x.len());
        for (iv, &xv) in x.iter().enumerate() {
            for (iu, &xu) in x.iter().enumerate() {
                let mut p = [0.0; 3];
                p[k] = s;
                p[u] = xu;
                p[v] = xv;
                points.push(p);
                weights.push(w[iu] * w[iv]);
            }
        }
        Self {
            face: f,
            points,
            weights,
        }
    }
}

/// Surface map of face `f` at a point with cell Jacobian `jac` (`jac[(i, k)] = ∂X_i/∂ξ_k`):
/// the area element dA per unit reference area and the unit outward normal (outward for
/// det J > 0). A degenerate face gives dA = 0 and a zero normal.
#[inline]
pub fn surface_map(jac: &Matrix3<f64>, f: usize) -> (f64, Vector3<f64>) {
    let (k, s) = face_axis(f);
    let a: Vector3<f64> = jac.column((k + 1) % 3).into();
    let b: Vector3<f64> = jac.column((k + 2) % 3).into();
    let nv = (a.cross(&b)) * s;
    let da = nv.norm();
    if da > 0.0 {
        (da, nv / da)
    } else {
        (0.0, Vector3::zeros())
    }
}

/// Isoparametric map of element `E` with nodal positions `x` at reference point `xi`: position
/// and Jacobian ∂X/∂ξ. `n`, `dn` are caller-provided buffers of at least `E::N` entries.
pub fn iso_map<E: Lagrange3D>(
    x: &[Vector3<f64>],
    xi: [f64; 3],
    n: &mut [f64],
    dn: &mut [[f64; 3]],
) -> (Vector3<f64>, Matrix3<f64>) {
    E::eval(xi, n, dn);
    let mut p = Vector3::zeros();
    let mut j = Matrix3::zeros();
    for a in 0..E::N {
        p += x[a] * n[a];
        for k in 0..3 {
            for i in 0..3 {
                j[(i, k)] += x[a][i] * dn[a][k];
            }
        }
    }
    (p, j)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[allow(clippy::needless_range_loop)] // dn[a][e]: derivative index as in the formulas
    fn basis_properties<E: Lagrange3D, const N: usize>() {
        let mut n = [0.0; N];
        let mut dn = [[0.0; 3]; N];
        for &x in &[[0.3, -0.7, 0.2], [-0.9, 0.1, 0.95], [0.0, 0.0, 0.0]] {
            E::eval(x, &mut n, &mut dn);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            for d in 0..3 {
                assert!(dn.iter().map(|g| g[d]).sum::<f64>().abs() < 1e-14);
                // Linear reproduction: Σ N_a ξ_a = ξ, Σ ∂N_a ξ_a = e_d.
                let lin: f64 = (0..N).map(|a| n[a] * E::node_ref(a)[d]).sum();
                assert!((lin - x[d]).abs() < 1e-14);
                for e in 0..3 {
                    let g: f64 = (0..N).map(|a| dn[a][e] * E::node_ref(a)[d]).sum();
                    let want = if d == e { 1.0 } else { 0.0 };
                    assert!((g - want).abs() < 1e-14);
                }
            }
        }
        for b in 0..N {
            E::eval(E::node_ref(b), &mut n, &mut dn);
            for (a, &na) in n.iter().enumerate() {
                assert!((na - if a == b { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
        let x = [0.23, -0.41, 0.67];
        let h = 1e-6;
        let (mut np, mut nm, mut d) = ([0.0; N], [0.0; N], [[0.0; 3]; N]);
        E::eval(x, &mut n, &mut dn);
        for dir in 0..3 {
            let (mut xp, mut xm) = (x, x);
            xp[dir] += h;
            xm[dir] -= h;
            E::eval(xp, &mut np, &mut d);
            E::eval(xm, &mut nm, &mut d);
            for a in 0..N {
                assert!(((np[a] - nm[a]) / (2.0 * h) - dn[a][dir]).abs() < 1e-9);
            }
        }
        // The k-th axial layer is a 2D quad in 2D order.
        let m = E::P + 1;
        for k in 0..m {
            for a2 in 0..m * m {
                let r = E::node_ref(a2 + m * m * k);
                assert_eq!(r[0], -1.0 + (2.0 / E::P as f64) * (a2 % m) as f64);
                assert_eq!(r[1], -1.0 + (2.0 / E::P as f64) * (a2 / m) as f64);
            }
        }
    }

    #[test]
    fn hex8_hex27_basis_properties() {
        basis_properties::<Hex8, 8>();
        basis_properties::<Hex27, 27>();
    }

    /// ∫_{-1}^{1} x^a dx.
    fn mono(a: i32) -> f64 {
        if a % 2 == 1 {
            0.0
        } else {
            2.0 / (a + 1) as f64
        }
    }

    #[test]
    fn gauss_3d_and_lobatto_exactness() {
        for q in 1..=6 {
            let r = QuadRule3D::gauss_3d(q);
            let deg = 2 * q as i32 - 1;
            for (a, b, c) in [(deg, 0, 0), (0, deg, 1), (deg - 1, deg, deg), (2, deg, 0)] {
                let num: f64 = r
                    .points
                    .iter()
                    .zip(&r.weights)
                    .map(|(p, w)| w * p[0].powi(a) * p[1].powi(b) * p[2].powi(c))
                    .sum();
                assert!((num - mono(a) * mono(b) * mono(c)).abs() < 1e-13, "q={q}");
            }
            // One degree too many is not integrated exactly (the rule is as claimed, not better).
            let e = 2 * q as i32;
            let num: f64 = r
                .points
                .iter()
                .zip(&r.weights)
                .map(|(p, w)| w * p[0].powi(e))
                .sum();
            assert!((num - 4.0 * mono(e)).abs() > 1e-6, "q={q}");
        }
        for n in 2..=4 {
            let (x, w) = gauss_lobatto_1d(n);
            for a in 0..=(2 * n as i32 - 3) {
                let s: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(a)).sum();
                assert!((s - mono(a)).abs() < 1e-14, "n={n} a={a}");
            }
        }
    }

    /// The map (u, v, w) ∈ [0, 1]³ ↦ (u, v(1 + a u), w(1 + c u² + d v²)) with u = (1 + ξ)/2 etc.
    fn curved(xi: [f64; 3], a: f64, c: f64, d: f64) -> Vector3<f64> {
        let [u, v, w] = xi.map(|s| 0.5 * (1.0 + s));
        Vector3::new(u, v * (1.0 + a * u), w * (1.0 + c * u * u + d * v * v))
    }

    fn volume_and_flux<E: Lagrange3D, const N: usize>(x: &[Vector3<f64>]) -> (f64, f64, f64) {
        let (mut n, mut dn) = ([0.0; N], [[0.0; 3]; N]);
        let r = QuadRule3D::gauss_3d(5);
        let mut vol = 0.0;
        let mut min_det = f64::INFINITY;
        for (p, w) in r.points.iter().zip(&r.weights) {
            let (_, j) = iso_map::<E>(x, *p, &mut n, &mut dn);
            min_det = min_det.min(j.determinant());
            vol += w * j.determinant();
        }
        // Divergence theorem: Σ_faces ∫ X·n dA = 3 V.
        let mut flux = 0.0;
        for f in 0..6 {
            let fr = FacetRule3D::new(f, 5, FacetPoints::Gauss);
            for (p, w) in fr.points.iter().zip(&fr.weights) {
                let (pos, j) = iso_map::<E>(x, *p, &mut n, &mut dn);
                let (da, nn) = surface_map(&j, f);
                flux += w * da * pos.dot(&nn);
            }
        }
        (vol, flux, min_det)
    }

    #[test]
    fn distorted_hex_volumes_match_closed_forms() {
        let (a, c, d) = (0.4, 0.3, -0.25);
        // Trilinear: d = 0 and c u² → c u v: use the trilinear map directly.
        let tri = |xi: [f64; 3]| {
            let [u, v, w] = xi.map(|s| 0.5 * (1.0 + s));
            Vector3::new(u, v * (1.0 + a * u), w * (1.0 + c * u * v))
        };
        // ∫_0^1 ∫_0^{1+ax} (1 + c x y/(1 + a x)) dy dx = 1 + a/2 + c (1/4 + a/6).
        let v_tri = 1.0 + a / 2.0 + c * (0.25 + a / 6.0);
        let x8: Vec<_> = (0..8).map(|n| tri(Hex8::node_ref(n))).collect();
        let (v8, f8, m8) = volume_and_flux::<Hex8, 8>(&x8);
        assert!((v8 - v_tri).abs() < 1e-14 && (f8 - 3.0 * v_tri).abs() < 1e-13 && m8 > 0.0);
        let x27: Vec<_> = (0..27).map(|n| tri(Hex27::node_ref(n))).collect();
        let (v27, f27, _) = volume_and_flux::<Hex27, 27>(&x27);
        assert!((v27 - v_tri).abs() < 1e-14 && (f27 - 3.0 * v_tri).abs() < 1e-13);
        // Curved (quadratic, reproduced exactly by Hex27):
        // ∫_0^1 ∫_0^{1+ax} (1 + c x² + d (y/(1+ax))²) dy dx = (1 + d/3)(1 + a/2) + c (1/3 + a/4).
        let v_curv = (1.0 + d / 3.0) * (1.0 + a / 2.0) + c * (1.0 / 3.0 + a / 4.0);
        let x27: Vec<_> = (0..27)
            .map(|n| curved(Hex27::node_ref(n), a, c, d))
            .collect();
        let (v, f, m) = volume_and_flux::<Hex27, 27>(&x27);
        assert!((v - v_curv).abs() < 1e-14, "{v} vs {v_curv}");
        assert!((f - 3.0 * v_curv).abs() < 1e-13, "{f}");
        assert!(m > 0.0);
    }

    #[test]
    fn skewed_hex_facet_areas_and_normals() {
        let a = Matrix3::new(1.2, 0.3, -0.2, 0.1, 0.9, 0.4, -0.3, 0.2, 1.5);
        assert!(a.determinant() > 0.0);
        let b = Vector3::new(0.5, -1.0, 2.0);
        let map = |xi: [f64; 3]| a * Vector3::from(xi) + b;
        let x8: Vec<_> = (0..8).map(|n| map(Hex8::node_ref(n))).collect();
        let centre = x8.iter().sum::<Vector3<f64>>() / 8.0;
        let (mut n, mut dn) = ([0.0; 8], [[0.0; 3]; 8]);
        for f in 0..6 {
            let fnodes = face_nodes::<Hex8>(f);
            let (k, s) = face_axis(f);
            for &q in &fnodes {
                assert_eq!(Hex8::node_ref(q)[k], s);
            }
            // Parallelogram from its corners (tensor order: 0, 1 along u, 2 along v).
            let p: Vec<_> = fnodes.iter().map(|&q| x8[q]).collect();
            let e1 = p[1] - p[0];
            let e2 = p[2] - p[0];
            let area = e1.cross(&e2).norm();
            let fc = p.iter().sum::<Vector3<f64>>() / 4.0;
            for kind in [FacetPoints::Gauss, FacetPoints::GaussLobatto] {
                let fr = FacetRule3D::new(f, 3, kind);
                let mut sum = 0.0;
                for (pt, w) in fr.points.iter().zip(&fr.weights) {
                    let (_, j) = iso_map::<Hex8>(&x8, *pt, &mut n, &mut dn);
                    let (da, nn) = surface_map(&j, f);
                    sum += w * da;
                    assert!(nn.dot(&e1).abs() < 1e-14 && nn.dot(&e2).abs() < 1e-14);
                    assert!(nn.dot(&(fc - centre)) > 0.0, "face {f} normal not outward");
                    assert!((nn.norm() - 1.0).abs() < 1e-15);
                }
                assert!(
                    (sum - area).abs() < 1e-13 * area,
                    "face {f}: {sum} vs {area}"
                );
            }
        }
        // Hex27 face nodes: 9 per face, the centre of face f is the node at the face centre.
        for f in 0..6 {
            let fnodes = face_nodes::<Hex27>(f);
            assert_eq!(fnodes.len(), 9);
            let r = Hex27::node_ref(fnodes[4]);
            let (k, s) = face_axis(f);
            for (d, &rd) in r.iter().enumerate() {
                assert_eq!(rd, if d == k { s } else { 0.0 });
            }
        }
    }
}
