//! Steady spinning of the hollow cylinder (paper Fig. 2): A(χ, η) = ω² B(χ, η), hub rim bonded,
//! outer surface free, ω reached by load stepping in ω².
//!
//! Reported quantities (summary.json `results`):
//! * `u_r_outer`: mean radial displacement of the outer surface, (1/L) ∫ u · e_R ds over the
//!   outer boundary in the reference configuration (e_R = X/|X|);
//! * `sigma_r_inner`, `sigma_theta_inner`, `sigma_r_outer`, `sigma_theta_outer`: ring averages
//!   of the Cauchy stress components e_R·σ e_R and e_Θ·σ e_Θ (reference polar basis; for an
//!   axisymmetric deformation it coincides with the current one) on the hub and outer surfaces,
//!   evaluated on the boundary facets of the cells and averaged with facet Gauss weights;
//! * `recovered_stress`: the same four ring averages of the recovered (superconvergent patch
//!   recovery, [`crate::physics::recovery`]) nodal Cauchy stress, interpolated along the facets
//!   by the cells' shape functions: about one order of h more accurate than the element stresses
//!   evaluated on the boundary.
//! * `error_estimate`: a posteriori estimates of the energy error of the solution
//!   ([`crate::physics::estimate`]): the Zienkiewicz–Zhu recovery estimate (asymptotically
//!   exact), the explicit residual indicator with the outer surface traction-free (its unknown
//!   constant taken as 1: an upper indicator, ≈ 14–19 times the error on the annulus), the
//!   energy norm of the solution and the relative recovery estimate.

use crate::element::gauss_1d;
use crate::io::record::Recorder;
use crate::math::{Mat2, Vec2};
use crate::mesh::Facet;
use crate::model::system::SolidSystem;
use crate::solver::stepping::{solve_load_steps, StepOptions, StepReport};
use crate::solver::{LinearKind, Newton, NewtonOptions, SolveError};

/// Ring-averaged results of a spinning solution.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SpinningResults {
    pub omega: f64,
    pub u_r_outer: f64,
    pub sigma_r_inner: f64,
    pub sigma_theta_inner: f64,
    pub sigma_r_outer: f64,
    pub sigma_theta_outer: f64,
    pub max_displacement: f64,
    pub recovered_stress: RecoveredRing,
    pub error_estimate: ErrorEstimate,
}

/// A posteriori estimates of the energy error ‖u − u_h‖_A ([`crate::physics::estimate`]).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ErrorEstimate {
    /// Zienkiewicz–Zhu recovery estimate.
    pub recovery: f64,
    /// Explicit residual indicator (outer surface traction-free, constant 1).
    pub explicit_residual: f64,
    /// Energy norm ‖u_h‖_A of the solution.
    pub energy_norm: f64,
    /// `recovery / energy_norm`.
    pub relative: f64,
}

impl ErrorEstimate {
    pub fn of(sys: &SolidSystem) -> Self {
        use crate::physics::estimate;
        let (m, d, x) = (&sys.model, &sys.dofs, &sys.x);
        let recovery = estimate::recovery(m, d, x).global;
        let energy_norm = estimate::energy_norm(m, d, x);
        Self {
            recovery,
            explicit_residual: estimate::explicit_residual(m, d, x, &["outer"]).global,
            energy_norm,
            relative: if energy_norm > 0.0 {
                recovery / energy_norm
            } else {
                0.0
            },
        }
    }
}

/// Ring averages of the recovered nodal Cauchy stress on the hub and outer surfaces.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct RecoveredRing {
    pub sigma_r_inner: f64,
    pub sigma_theta_inner: f64,
    pub sigma_r_outer: f64,
    pub sigma_theta_outer: f64,
}

/// One row of the radial profile: averages over a ring of quadrature points.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ProfileRow {
    pub r: f64,
    pub u_r: f64,
    pub sigma_r: f64,
    pub sigma_theta: f64,
    pub sigma_r_theta: f64,
}

fn polar_components(x: &Vec2, s: &Mat2) -> (f64, f64, f64) {
    let er = x / x.norm();
    let et = Vec2::new(-er[1], er[0]);
    (
        (er.transpose() * s * er)[0],
        (et.transpose() * s * et)[0],
        (er.transpose() * s * et)[0],
    )
}

/// Average of (u_r, σ_r, σ_θ) along the facets `facets` (any mesh: the facet sets `hub` and
/// `outer`).
fn side_average(sys: &SolidSystem, facets: &[Facet], nq: usize) -> (f64, f64, f64, f64) {
    let (pts, ws) = gauss_1d(nq);
    let (mut len, mut ur, mut sr, mut st) = (0.0, 0.0, 0.0, 0.0);
    for f in facets {
        let c = f.cell as usize;
        let k = f.tangent_column();
        for (s, w) in pts.iter().zip(&ws) {
            let (xi, eta) = f.ref_point(*s);
            if let Some(pv) = sys.model.point_values(c, &sys.dofs, &sys.x, xi, eta) {
                let ds = Vec2::new(pv.jac[(0, k)], pv.jac[(1, k)]).norm() * w;
                let (a, b, _) = polar_components(&pv.x, &pv.sigma);
                len += ds;
                ur += pv.u.dot(&(pv.x / pv.x.norm())) * ds;
                sr += a * ds;
                st += b * ds;
            }
        }
    }
    (len, ur / len, sr / len, st / len)
}

/// Average of (σ_r, σ_θ) of the nodal field `nodal` ([σ11, σ22, σ12, σ33] per node),
/// interpolated along the facets `facets` by the side's Lagrange basis, with `nq` Gauss points
/// per facet and the facet length element of the cell's geometry.
fn side_average_nodal(
    sys: &SolidSystem,
    nodal: &[[f64; 4]],
    facets: &[Facet],
    nq: usize,
) -> (f64, f64) {
    let mesh = &sys.model.mesh;
    let (pts, ws) = gauss_1d(nq);
    let (mut len, mut sr, mut st) = (0.0, 0.0, 0.0);
    for f in facets {
        let c = f.cell as usize;
        let p = mesh.degree[c] as usize;
        let nodes = mesh.cell_nodes(c);
        let ln = f.local_nodes(p);
        let k = f.tangent_column();
        for (s, w) in pts.iter().zip(&ws) {
            let (xi, eta) = f.ref_point(*s);
            let Some(jac) = sys.model.point_values_geometry(c, xi, eta) else {
                continue;
            };
            let ds = Vec2::new(jac[(0, k)], jac[(1, k)]).norm() * w;
            let (lv, _) = crate::element::lagrange_1d(p, *s);
            let mut x = Vec2::zeros();
            let mut sig = Mat2::zeros();
            for (i, &l) in ln.iter().enumerate().take(p + 1) {
                let n = nodes[l] as usize;
                let v = nodal[n];
                x += mesh.nodes[n] * lv[i];
                sig += Mat2::new(v[0], v[2], v[2], v[1]) * lv[i];
            }
            let (a, b, _) = polar_components(&x, &sig);
            if ds.is_finite() && a.is_finite() && b.is_finite() {
                len += ds;
                sr += a * ds;
                st += b * ds;
            }
        }
    }
    if len > 0.0 {
        (sr / len, st / len)
    } else {
        (0.0, 0.0)
    }
}

/// Ring averages of the recovered stress `nodal` (from
/// [`crate::physics::recovery::recover_cauchy`]) on the hub and outer surfaces.
pub fn recovered_ring(sys: &SolidSystem, nodal: &[[f64; 4]]) -> RecoveredRing {
    let mesh = &sys.model.mesh;
    if nodal.len() != mesh.n_nodes() {
        return RecoveredRing::default();
    }
    let (sri, sti) = side_average_nodal(sys, nodal, mesh.facet_set("hub"), 4);
    let (sro, sto) = side_average_nodal(sys, nodal, mesh.facet_set("outer"), 4);
    RecoveredRing {
        sigma_r_inner: sri,
        sigma_theta_inner: sti,
        sigma_r_outer: sro,
        sigma_theta_outer: sto,
    }
}

pub fn results(sys: &SolidSystem) -> SpinningResults {
    let mesh = &sys.model.mesh;
    if mesh.facet_set("hub").is_empty() || mesh.facet_set("outer").is_empty() {
        return SpinningResults::default();
    }
    let (_, _, sri, sti) = side_average(sys, mesh.facet_set("hub"), 4);
    let (_, uro, sro, sto) = side_average(sys, mesh.facet_set("outer"), 4);
    let max_u = (0..sys.model.mesh.n_nodes())
        .map(|n| Vec2::new(sys.x[2 * n], sys.x[2 * n + 1]).norm())
        .fold(0.0, f64::max);
    SpinningResults {
        omega: sys.model.omega2.max(0.0).sqrt(),
        u_r_outer: uro,
        sigma_r_inner: sri,
        sigma_theta_inner: sti,
        sigma_r_outer: sro,
        sigma_theta_outer: sto,
        max_displacement: max_u,
        recovered_stress: recovered_ring(
            sys,
            &crate::physics::recovery::recover_cauchy(&sys.model, &sys.dofs, &sys.x),
        ),
        error_estimate: ErrorEstimate::of(sys),
    }
}

/// Radial profile: ring averages at the radial Gauss points of every layer of cells.
pub fn profile(sys: &SolidSystem) -> Vec<ProfileRow> {
    let Some(rl) = sys.model.mesh.rings else {
        return Vec::new();
    };
    let nq = 3;
    let (pts, ws) = gauss_1d(nq);
    let mut rows = Vec::new();
    for j in 0..rl.n_r {
        for &xi in &pts {
            let (mut len, mut ur, mut sr, mut st, mut srt, mut r) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            for k in 0..rl.n_theta {
                let c = j * rl.n_theta + k;
                for (eta, w) in pts.iter().zip(&ws) {
                    if let Some(pv) = sys.model.point_values(c, &sys.dofs, &sys.x, xi, *eta) {
                        let ds = Vec2::new(pv.jac[(0, 1)], pv.jac[(1, 1)]).norm() * w;
                        let (a, b, cc) = polar_components(&pv.x, &pv.sigma);
                        len += ds;
                        r += pv.x.norm() * ds;
                        ur += pv.u.dot(&(pv.x / pv.x.norm())) * ds;
                        sr += a * ds;
                        st += b * ds;
                        srt += cc * ds;
                    }
                }
            }
            if len > 0.0 {
                rows.push(ProfileRow {
                    r: r / len,
                    u_r: ur / len,
                    sigma_r: sr / len,
                    sigma_theta: st / len,
                    sigma_r_theta: srt / len,
                });
            }
        }
    }
    rows
}

/// Solve steady spinning at `omega` (rad/s) by load stepping in ω² from rest.
pub fn solve_spinning(
    sys: &mut SolidSystem,
    omega: f64,
    kind: LinearKind,
    newton_opts: NewtonOptions,
    step_opts: &StepOptions,
    report: &mut StepReport,
    rec: &mut dyn Recorder,
) -> Result<(), SolveError> {
    sys.omega2_target = omega * omega;
    sys.loading = crate::model::system::Loading::Spin {
        omega2: omega * omega,
    };
    // Reference force: the centrifugal load at the target speed on the undeformed body.
    let saved = sys.model.omega2;
    sys.model.omega2 = sys.omega2_target;
    let x0 = sys.x.clone();
    let mut zero = x0.clone();
    for v in zero[..sys.dofs.n_u].iter_mut() {
        *v = 0.0;
    }
    sys.x.copy_from_slice(&zero);
    let f_spin = sys.residual_norm();
    sys.model.omega2 = 0.0;
    let f_rest = sys.residual_norm();
    sys.x.copy_from_slice(&x0);
    sys.model.omega2 = saved;
    sys.set_reference_force((f_spin - f_rest).abs().max(f_rest).max(f64::MIN_POSITIVE));
    let mut newton = Newton::new(sys, kind, newton_opts)?;
    solve_load_steps(sys, &mut newton, step_opts, report, rec)
}
