//! Elastic-slip Coulomb friction in the steady (θ-referential) mode: the tangential relative
//! displacement transported along the contact boundary and a Coulomb return mapping marched
//! from where the material enters the patch ([`super::laws::CoulombElastic`]).
//!
//! # Why not the slip velocity
//!
//! A velocity-regularised law t_T = −μ t_n φ(w/ε) acts, in the stick zone, as a tangential
//! penalty of stiffness μ t_n / ε on the slip w = ω ∂θχ1 − v0, i.e. on a θ-derivative of the
//! displacement trace. Any centred derivative of the trace (the facet-wise ∂θu_h, or the
//! five-point nodal stencil of [`super::steady_slip`], whose weights (1, −8, 0, 8, −1)/12h
//! annihilate (−1)^k) leaves an odd–even mode of the trace free, and the stick condition
//! w ≈ 0 at more quadrature points than the trace has nodes does not control it: as ε → 0 the
//! stick-zone traction alternates between neighbouring points while its facet averages stay
//! right. Measured on `scenarios/carter_tractive_rolling.toml` (`tests/carter_pointwise.rs`):
//! the largest |t_i − (t_{i−1} + t_{i+1})/2| over the stick zone is 0.029 μp0 at ε = 3e-4 V and
//! 0.18 μp0 at ε = 1e-4 V with 4 Gauss points per Q2 facet, and 0.27 μp0 with 3 points: fewer
//! constraint points per facet do not cure it (2 points do not converge), so it is the
//! derivative's free mode rather than the count of points alone.
//!
//! # The displacement form
//!
//! In steady rolling the material point at reference angle θ arrived there from θ − ω s a
//! time s ago; its relative tangential displacement against the road since it entered the
//! patch at θ_e is (ω ∂θ g = w integrated along the streamline)
//!
//! ```text
//! g(θ) = G(θ) − G(θ_e),   G(θ) = χ1(θ) − (v0/ω) θ,
//! ```
//!
//! a function of the displacement trace itself, with no derivative. The interface has a
//! tangential stiffness k_T and a Coulomb bound; the discrete law is the return mapping
//! marched along the points of the contact facets in flow order (increasing θ for ω > 0),
//! k → k+1:
//!
//! ```text
//! trial   t* = t_k − k_T (G_{k+1} − G_k)
//! stick   t_{k+1} = t*                      if |t*| ≤ μ t_n(k+1)
//! slip    t_{k+1} = μ t_n(k+1) sign(t*)     otherwise
//! ```
//!
//! with t = 0 at a point out of contact and at the first point in contact (the entry; the
//! material enters the patch in stick). The sum telescopes: a stick point's traction is
//! t_i = A_s − k_T G_i with A_s = t_s + k_T G_s of its anchor s, the last slipping or entry
//! point upstream. As k_T → ∞ the law is exact Coulomb (no ε), and the stick condition is a
//! penalty on the trace itself (like the normal penalty), which controls every mode.
//!
//! # Tangent
//!
//! A point's traction depends on its own facet's nodes (assembled in the contact element:
//! −k_T N_j on u1 in stick; μ sign ∂t_n in slip) and, in stick, on its anchor's facet (the
//! anchor moves during Newton, so the sparsity pattern cannot hold it). That coupling is a
//! rank-one term per anchor, ∂R_i = r_i ⊗ ∇A_s, applied matrix-free
//! ([`ElasticMarch::apply_correction`]): Newton solves with the exact tangent by GMRES
//! preconditioned with the factorization of the assembled part, which needs about one
//! iteration per anchor.
//!
//! Units: t_T, t_n traction (force per reference length), G and g lengths, k_T traction per
//! length, ω rad/s, v0 length/s.

use crate::assembly::{DofMap, CONSTRAINED, FIXED};

/// The state of a facet point after the march.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PointState {
    /// Not in contact (t_n = 0): t_T = 0.
    Out,
    /// First point in contact after one out of contact: t_T = 0, the anchor of what follows.
    Entry,
    /// Stick: t_T = A_s − k_T G_i, `anchor` an index into [`ElasticMarch::anchors`].
    Stick { anchor: u32 },
    /// Slip: t_T = sign μ t_n, itself an anchor.
    Slip { sign: f64 },
}

/// One facet quadrature point of the march.
#[derive(Clone, Copy, Debug)]
pub struct MarchPoint {
    /// Tangential traction on the body.
    pub t: f64,
    pub state: PointState,
}

/// The gradient of an anchor's A_s = t_s + k_T G_s: (full dof, coefficient), at most the
/// facet's three nodes (u1, u2) and the road height.
#[derive(Clone, Debug, Default)]
pub struct AnchorGradient {
    pub n: usize,
    pub entries: [(u32, f64); 7],
}

impl AnchorGradient {
    pub fn push(&mut self, dof: u32, c: f64) {
        self.entries[self.n] = (dof, c);
        self.n += 1;
    }
}

/// Per stick point: its anchor and its residual rows ∂R/∂A_s = −N_a ds (full u1 dofs of its
/// facet's nodes).
#[derive(Clone, Debug)]
pub struct StickRows {
    pub anchor: u32,
    pub n: usize,
    pub rows: [(u32, f64); 3],
}

/// The marched tractions of every facet point (facet `e`, point `q` at `e · n_q + q`) and the
/// anchor coupling of the tangent.
#[derive(Clone, Debug, Default)]
pub struct ElasticMarch {
    pub points: Vec<MarchPoint>,
    pub n_q: usize,
    pub anchors: Vec<AnchorGradient>,
    pub stick: Vec<StickRows>,
    /// Factor of the contact block's residual (the assembly's force scale).
    pub scale: f64,
}

/// The value of full dof `d` of an equation-numbered vector `v` (0 when fixed; a hanging dof
/// from its masters).
fn dof_value(dofs: &DofMap, v: &[f64], d: u32) -> f64 {
    let e = dofs.eq[d as usize];
    if e == FIXED {
        0.0
    } else if e < CONSTRAINED {
        v[e as usize]
    } else {
        dofs.expansion(d)
            .unwrap_or(&[])
            .iter()
            .map(|&(m, w)| {
                let em = dofs.eq[m as usize];
                if em < CONSTRAINED {
                    w * v[em as usize]
                } else {
                    0.0
                }
            })
            .sum()
    }
}

/// `out[d] += y` for full dof `d` (a hanging dof's row goes to its masters, Cᵀ).
fn dof_add(dofs: &DofMap, out: &mut [f64], d: u32, y: f64) {
    let e = dofs.eq[d as usize];
    if e == FIXED {
    } else if e < CONSTRAINED {
        out[e as usize] += y;
    } else {
        for &(m, w) in dofs.expansion(d).unwrap_or(&[]) {
            let em = dofs.eq[m as usize];
            if em < CONSTRAINED {
                out[em as usize] += w * y;
            }
        }
    }
}

impl ElasticMarch {
    /// The point of facet `e`, quadrature point `q`.
    #[inline]
    pub fn point(&self, e: usize, q: usize) -> &MarchPoint {
        &self.points[e * self.n_q + q]
    }

    /// Whether the tangent has an anchor coupling (some point sticks).
    pub fn has_coupling(&self) -> bool {
        !self.stick.is_empty()
    }

    /// `out += C v`: the anchor coupling of the tangent beyond the contact elements (see the
    /// module docs); `v`, `out` in equation numbering.
    pub fn apply_correction(&self, dofs: &DofMap, v: &[f64], out: &mut [f64]) {
        if self.stick.is_empty() {
            return;
        }
        let dot: Vec<f64> = self
            .anchors
            .iter()
            .map(|a| {
                a.entries[..a.n]
                    .iter()
                    .map(|&(d, c)| c * dof_value(dofs, v, d))
                    .sum::<f64>()
            })
            .collect();
        for s in &self.stick {
            let y = dot[s.anchor as usize] * self.scale;
            if y == 0.0 {
                continue;
            }
            for &(d, c) in &s.rows[..s.n] {
                dof_add(dofs, out, d, c * y);
            }
        }
    }
}
