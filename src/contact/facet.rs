//! The contact element: integration of normal compliance and friction over the outer facets
//! of the mesh (the facet set `outer`: side ξ = +1 of the outer layer of cells of the generated
//! annulus, any side of any cell in a mesh read from a file).
//!
//! Residual contribution (R = internal − external, the contact traction being external):
//!
//! ```text
//! R_a −= ∫Γc N_a (t_T, t_n) ds0,     t_n = t_n(δ, δ̇),  t_T = t_T(w, t_n, δ)
//! ```
//!
//! with δ = −H − x2, x = X + u on the facet. The slip velocity w depends on the analysis
//! ([`SlipKinematics`]): in a static analysis it is measured in the pseudo-time τ ∈ [0, 1] of the
//! load stepping, w = (x1 − x1_prev)/Δτ − v0 (so the friction regularisation ε is a slip length
//! over the whole loading). Under load control the road height H is a global unknown with the
//! equation R_H = P − ∫ t_n ds0 = 0 (P: downward hub load per unit thickness), which keeps the
//! tangent symmetric when friction is off (it is the Hessian of W + Φ_c(δ) + P H).
//!
//! Only facets that can reach the road are integrated: a facet is skipped when all its nodes
//! are higher than the road by more than a margin of 10 % of its chord (a Q2 facet bulges by
//! at most ~chord²/(8 R) ≪ 0.1 chord). The number of facets integrated per assembly is counted.
//!
//! Facet quadrature: Gauss (default) or Gauss–Lobatto with 2–6 points. The penalty pressure is
//! smooth inside the patch and has a kink at its edges; Gauss points (exact to degree 2n − 1)
//! integrate the smooth part best, Lobatto points coincide with the nodes (node-to-surface-like)
//! and give a pressure that is blind between them: see the Hertz test for the measured
//! difference.

use super::laws::{Friction, FrictionLaw, NormalCompliance};
use super::steady_elastic::{AnchorGradient, ElasticMarch, MarchPoint, PointState, StickRows};
use super::steady_slip::{SteadySlip, MAX_EXT};
use crate::assembly::{DofMap, LocalSystem};
use crate::element::gauss_1d;
use crate::element::lagrange_1d;
use crate::math::Vec2;
use crate::mesh::{Facet, Mesh};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Facet quadrature rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FacetRule {
    Gauss(usize),
    Lobatto(usize),
}

impl FacetRule {
    pub fn points(&self) -> (Vec<f64>, Vec<f64>) {
        match *self {
            FacetRule::Gauss(n) => gauss_1d(n),
            FacetRule::Lobatto(n) => lobatto_1d(n),
        }
    }
}

/// Gauss–Lobatto points and weights on [-1, 1] (2 ≤ n ≤ 6; clamped).
pub fn lobatto_1d(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (x, w): (&[f64], &[f64]) = match n {
        0..=2 => (&[-1.0, 1.0], &[1.0, 1.0]),
        3 => (&[-1.0, 0.0, 1.0], &[1.0 / 3.0, 4.0 / 3.0, 1.0 / 3.0]),
        4 => {
            const A: f64 = 0.447_213_595_499_958; // 1/√5
            (
                &[-1.0, -A, A, 1.0],
                &[1.0 / 6.0, 5.0 / 6.0, 5.0 / 6.0, 1.0 / 6.0],
            )
        }
        5 => {
            const A: f64 = 0.654_653_670_707_977_1; // √(3/7)
            (
                &[-1.0, -A, 0.0, A, 1.0],
                &[0.1, 49.0 / 90.0, 32.0 / 45.0, 49.0 / 90.0, 0.1],
            )
        }
        _ => (
            &[
                -1.0,
                -0.765_055_323_929_464_7,
                -0.285_231_516_480_645_1,
                0.285_231_516_480_645_1,
                0.765_055_323_929_464_7,
                1.0,
            ],
            &[
                1.0 / 15.0,
                0.378_474_956_297_847,
                0.554_858_377_035_486_4,
                0.554_858_377_035_486_4,
                0.378_474_956_297_847,
                1.0 / 15.0,
            ],
        ),
    };
    (x.to_vec(), w.to_vec())
}

/// How the slip velocity and the penetration rate are obtained: supplied by the driver with
/// every evaluation ([`ContactModel::kernel`], [`ContactModel::samples`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SlipKinematics<'a> {
    /// Static analysis: `x_prev` is the state of the last converged load step; velocity
    /// v = (x − x_prev)/Δτ in load-stepping pseudo-time, w = v1 − v0; no normal damping (δ̇ is
    /// not a physical rate).
    Static { x_prev: &'a [f64], dtau: f64 },
    /// Dynamic analysis: `v` is the velocity field; the unknown moves the positions by `kx`
    /// and the velocities by `kv` per unit change (e.g. generalized-α: kx = 1 − α_f,
    /// kv = (1 − α_f) γ / (β Δt)). w = v1 − v0, δ̇ = −v2.
    Dynamic { v: &'a [f64], kx: f64, kv: f64 },
    /// Steady rolling on the referential (spatial) mesh: the unknown is the motion
    /// χ(r, θ) = X + u, the velocity is v = ω ∂θχ, differentiated along the facet
    /// (∂θ = (d/dη) / (dθ/dη), θ the polar angle of the reference facet point), so
    /// w = ω ∂θχ1 − v0 and δ̇ = −ω ∂θχ2. With [`ContactModel::steady_slip`] set, ∂θu1 in w
    /// comes from nodal derivatives instead (continuous across facets, [`super::steady_slip`]).
    Steady { omega: f64 },
}

impl SlipKinematics<'_> {
    /// (kx, kv, damping active).
    fn factors(&self) -> (f64, f64, bool) {
        match *self {
            SlipKinematics::Static { dtau, .. } => (1.0, 1.0 / dtau.max(f64::MIN_POSITIVE), false),
            SlipKinematics::Dynamic { kx, kv, .. } => (kx, kv, true),
            SlipKinematics::Steady { omega } => (1.0, omega, true),
        }
    }
}

/// Contact of the outer facets with the road.
pub struct ContactModel {
    /// Road height H (hub centre to road); under load control the current value is the global
    /// unknown and this field is only its initial guess.
    pub h: f64,
    /// Road speed along +x1.
    pub v0: f64,
    pub normal: NormalCompliance,
    pub friction: Friction,
    pub rule: FacetRule,
    /// Downward hub load P (force per unit thickness) under load control.
    pub load: Option<f64>,
    pub facets: Vec<Facet>,
    /// Steady mode: continuous slip velocity from nodal θ-derivatives along the contact
    /// boundary ([`super::steady_slip`]); set by [`Self::enable_steady_slip`]. Changes the
    /// element dof lists: build the assembler after setting it.
    pub steady_slip: Option<SteadySlip>,
    /// Steady mode with [`super::laws::CoulombElastic`]: the tractions marched along the
    /// contact boundary at the state of the last [`Self::prepare_steady`] (the kernel reads
    /// them; [`super::steady_elastic`]).
    pub elastic: Option<ElasticMarch>,
    visited: AtomicUsize,
    pts: Vec<f64>,
    wts: Vec<f64>,
}

/// Traction sample at a facet quadrature point.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ContactSample {
    /// Reference polar angle of the point (rad; −π/2 is the bottom).
    pub theta: f64,
    pub x1: f64,
    pub x2: f64,
    pub delta: f64,
    pub t_n: f64,
    pub t_t: f64,
    pub w: f64,
    /// Reference length weight of the point (ds0).
    pub ds0: f64,
}

/// Resultants of the contact tractions on the body.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct ContactTotals {
    pub force_x: f64,
    pub force_y: f64,
    /// Moment about the hub centre (counter-clockwise positive).
    pub moment: f64,
    pub x_min: f64,
    pub x_max: f64,
    pub max_pressure: f64,
    /// Second moment ⟨x1²⟩ of the normal traction about its centroid (Hertz: a²/4).
    pub pressure_second_moment: f64,
    pub centroid: f64,
}

struct FacetPoint {
    x: Vec2,
    ds0: f64,
    theta: f64,
    /// ∂θX = (dX/dη)/(dθ/dη) of the reference facet at the point.
    dx_dtheta: Vec2,
    /// ∂θN_j = (dN_j/dη)/(dθ/dη) of the facet shape functions.
    dn_dtheta: [f64; 3],
}

impl ContactModel {
    pub fn new(
        mesh: &Mesh,
        h: f64,
        v0: f64,
        normal: NormalCompliance,
        friction: Friction,
        rule: FacetRule,
        load: Option<f64>,
    ) -> Self {
        let (pts, wts) = rule.points();
        Self {
            h,
            v0,
            normal,
            friction,
            rule,
            load,
            facets: mesh.facet_set("outer").to_vec(),
            steady_slip: None,
            elastic: None,
            visited: AtomicUsize::new(0),
            pts,
            wts,
        }
    }

    /// Local node indices of facet `f` of a degree-p cell, in the order of the facet parameter.
    fn side_nodes(f: &Facet, p: usize) -> impl Iterator<Item = usize> {
        let ln = f.local_nodes(p);
        (0..=p).map(move |j| ln[j])
    }

    /// Use the continuous steady slip velocity ([`super::steady_slip`]) when the facets allow
    /// it (returns whether it is on). The element dof lists change: rebuild the assembler.
    pub fn enable_steady_slip(&mut self, mesh: &Mesh) -> bool {
        if self.steady_slip.is_none() {
            self.steady_slip = SteadySlip::new(mesh, &self.facets);
        }
        self.steady_slip.is_some()
    }

    /// Dof lists of the contact elements (full numbering): facet node dofs (with the steady
    /// slip: the facet's extended node list, [`SteadySlip::nodes`]), then the road height
    /// under load control.
    pub fn element_dofs(&self, mesh: &Mesh, dofs: &DofMap) -> (Vec<u32>, Vec<usize>) {
        let mut list = Vec::new();
        let mut off = vec![0];
        for (e, f) in self.facets.iter().enumerate() {
            let c = f.cell as usize;
            let p = mesh.degree[c] as usize;
            let nodes = mesh.cell_nodes(c);
            if let Some(s) = &self.steady_slip {
                for &n in s.nodes(e) {
                    list.push(2 * n);
                    list.push(2 * n + 1);
                }
            } else {
                for a in Self::side_nodes(f, p) {
                    list.push(2 * nodes[a]);
                    list.push(2 * nodes[a] + 1);
                }
            }
            if self.load.is_some() && dofs.n_global > 0 {
                list.push(dofs.global(0) as u32);
            }
            off.push(list.len());
        }
        (list, off)
    }

    /// Current road height: the global unknown under load control, else `self.h`.
    pub fn road_height(&self, dofs: &DofMap, x: &[f64]) -> f64 {
        if self.load.is_some() && dofs.n_global > 0 {
            x[dofs.global(0)]
        } else {
            self.h
        }
    }

    /// Facets integrated during the last assembly.
    pub fn visited_facets(&self) -> usize {
        self.visited.load(Ordering::Relaxed)
    }
    pub fn reset_visited(&self) {
        self.visited.store(0, Ordering::Relaxed);
    }

    /// Reference position, reference length weight and angle at facet point `q`.
    #[allow(clippy::too_many_arguments)]
    fn facet_point(
        &self,
        mesh: &Mesh,
        f: &Facet,
        q: usize,
        n: &[f64; 3],
        dn: &[f64; 3],
        p: usize,
    ) -> FacetPoint {
        let c = f.cell as usize;
        let (xi, eta) = f.ref_point(self.pts[q]);
        let (x, t) = if let Some((x, jac)) = mesh.geometry[c].polar_map(xi, eta) {
            let k = f.tangent_column();
            (x, Vec2::new(jac[(0, k)], jac[(1, k)]))
        } else {
            let nodes = mesh.cell_nodes(c);
            let (mut x, mut t) = (Vec2::zeros(), Vec2::zeros());
            for (j, a) in Self::side_nodes(f, p).enumerate() {
                let xa = mesh.nodes[nodes[a] as usize];
                x += xa * n[j];
                t += xa * dn[j];
            }
            (x, t)
        };
        // dθ/dη of the reference point: (X1 X2' − X2 X1') / |X|².
        let dtheta = (x[0] * t[1] - x[1] * t[0]) / x.norm_squared();
        let inv = if dtheta != 0.0 { 1.0 / dtheta } else { 0.0 };
        FacetPoint {
            x,
            ds0: t.norm() * self.wts[q],
            theta: x[1].atan2(x[0]),
            dx_dtheta: t * inv,
            dn_dtheta: dn.map(|d| d * inv),
        }
    }

    /// Whether the friction law is the steady mode's elastic-slip law, which the contact
    /// element takes from [`Self::elastic`] rather than pointwise.
    pub fn is_elastic_slip(&self) -> bool {
        matches!(self.friction, Friction::CoulombElastic(l) if l.mu != 0.0)
    }

    /// Before a steady assembly at state `x`: march the elastic-slip law
    /// ([`super::steady_elastic`]) and keep the result for the kernel (no effect for other
    /// laws). `scale` is the factor the assembly applies to the contact residual.
    pub fn prepare_steady(
        &mut self,
        mesh: &Mesh,
        dofs: &DofMap,
        x: &[f64],
        omega: f64,
        scale: f64,
    ) {
        self.elastic = self.elastic_march(mesh, dofs, x, omega).map(|mut m| {
            m.scale = scale;
            m
        });
    }

    /// The elastic-slip march at state `x` and angular speed `omega` (`None` unless the law is
    /// [`super::laws::CoulombElastic`] with μ > 0): every facet point in flow order from a point
    /// out of contact, the return mapping of [`super::steady_elastic`].
    pub fn elastic_march(
        &self,
        mesh: &Mesh,
        dofs: &DofMap,
        x: &[f64],
        omega: f64,
    ) -> Option<ElasticMarch> {
        let Friction::CoulombElastic(law) = self.friction else {
            return None;
        };
        if law.mu == 0.0 {
            return None;
        }
        struct Pt {
            theta: f64,
            chi1: f64,
            tn: f64,
            dtn_du2: [f64; 3],
            dtn_dh: f64,
            nv: [f64; 3],
            ds: f64,
            nodes: [u32; 3],
            nn: usize,
        }
        let kin = SlipKinematics::Steady { omega };
        let h = self.road_height(dofs, x);
        let h_dof = (self.load.is_some() && dofs.n_global > 0).then(|| dofs.global(0) as u32);
        let damping = self.normal.has_damping();
        let nq = self.pts.len();
        let mut pts = Vec::with_capacity(self.facets.len() * nq);
        for f in &self.facets {
            let c = f.cell as usize;
            let p = mesh.degree[c] as usize;
            let nn = p + 1;
            let cn = mesh.cell_nodes(c);
            let side = f.local_nodes(p);
            let touch = self.can_touch(mesh, f, x, h);
            let mut nodes = [0u32; 3];
            for j in 0..nn {
                nodes[j] = cn[side[j]];
            }
            for q in 0..nq {
                let (nv, dv) = lagrange_1d(p, self.pts[q]);
                let fp = self.facet_point(mesh, f, q, &nv, &dv, p);
                let (u, vel) = self.point_motion(cn, &side, nn, &nv, &fp, x, &kin);
                let xc = fp.x + u;
                let delta = -h - xc[1];
                let mut pt = Pt {
                    theta: fp.theta,
                    chi1: xc[0],
                    tn: 0.0,
                    dtn_du2: [0.0; 3],
                    dtn_dh: 0.0,
                    nv,
                    ds: fp.ds0,
                    nodes,
                    nn,
                };
                if touch && delta > 0.0 {
                    let nval = self.normal.eval(delta, if damping { -vel[1] } else { 0.0 });
                    let cv = Self::velocity_coefficients(&nv, &fp, &kin, 0.0);
                    let d_rate = if damping { nval.d_rate } else { 0.0 };
                    pt.tn = nval.t;
                    for b in 0..nn {
                        pt.dtn_du2[b] = -nval.d_delta * nv[b] - d_rate * cv[b];
                    }
                    pt.dtn_dh = -nval.d_delta;
                }
                pts.push(pt);
            }
        }
        let n = pts.len();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| pts[a].theta.total_cmp(&pts[b].theta));
        if omega < 0.0 {
            order.reverse();
        }
        let start = order.iter().position(|&i| pts[i].tn <= 0.0).unwrap_or(0);
        let mut m = ElasticMarch {
            points: vec![
                MarchPoint {
                    t: 0.0,
                    state: PointState::Out,
                };
                n
            ],
            n_q: nq,
            anchors: Vec::new(),
            stick: Vec::new(),
            scale: 1.0,
        };
        let two_pi = 2.0 * std::f64::consts::PI;
        let v_per_omega = if omega != 0.0 { self.v0 / omega } else { 0.0 };
        let (k, mu) = (law.k_t, law.mu);
        // Running unwrapped angle, the current anchor (index, A_s).
        let (mut theta_u, mut prev_theta) = (0.0, pts[order[start]].theta);
        let mut anchor: Option<(u32, f64)> = None;
        let anchor_gradient = |pt: &Pt, slip: Option<f64>| {
            let mut g = AnchorGradient::default();
            for j in 0..pt.nn {
                g.push(2 * pt.nodes[j], k * pt.nv[j]);
                if let Some(sign) = slip {
                    g.push(2 * pt.nodes[j] + 1, sign * mu * pt.dtn_du2[j]);
                }
            }
            if let (Some(sign), Some(hd)) = (slip, h_dof) {
                g.push(hd, sign * mu * pt.dtn_dh);
            }
            g
        };
        for step in 0..n {
            let i = order[(start + step) % n];
            let pt = &pts[i];
            let mut d = pt.theta - prev_theta;
            d -= two_pi * (d / two_pi).round();
            theta_u += d;
            prev_theta = pt.theta;
            if pt.tn <= 0.0 {
                anchor = None;
                continue;
            }
            let g_i = pt.chi1 - v_per_omega * theta_u;
            let (t, state) = match anchor {
                None => {
                    m.anchors.push(anchor_gradient(pt, None));
                    anchor = Some(((m.anchors.len() - 1) as u32, k * g_i));
                    (0.0, PointState::Entry)
                }
                Some((a, big_a)) => {
                    let trial = big_a - k * g_i;
                    let bound = mu * pt.tn;
                    if trial.abs() <= bound {
                        let mut rows = [(0u32, 0.0); 3];
                        for (j, row) in rows.iter_mut().enumerate().take(pt.nn) {
                            *row = (2 * pt.nodes[j], -pt.nv[j] * pt.ds);
                        }
                        m.stick.push(StickRows {
                            anchor: a,
                            n: pt.nn,
                            rows,
                        });
                        (trial, PointState::Stick { anchor: a })
                    } else {
                        let sign = trial.signum();
                        let t = sign * bound;
                        m.anchors.push(anchor_gradient(pt, Some(sign)));
                        anchor = Some(((m.anchors.len() - 1) as u32, t + k * g_i));
                        (t, PointState::Slip { sign })
                    }
                }
            };
            m.points[i] = MarchPoint { t, state };
        }
        Some(m)
    }

    /// Whether a facet can touch the road (see module docs).
    fn can_touch(&self, mesh: &Mesh, f: &Facet, x: &[f64], h: f64) -> bool {
        let c = f.cell as usize;
        let p = mesh.degree[c] as usize;
        let nodes = mesh.cell_nodes(c);
        let pos = |a: usize| {
            let n = nodes[a] as usize;
            mesh.nodes[n] + Vec2::new(x[2 * n], x[2 * n + 1])
        };
        let ln = f.local_nodes(p);
        let first = pos(ln[0]);
        let last = pos(ln[p]);
        let margin = 0.1 * (last - first).norm();
        Self::side_nodes(f, p).any(|a| pos(a)[1] < -h + margin)
    }

    /// Displacement and velocity at facet point `q` of cell `c` (the velocity as
    /// [`SlipKinematics`] defines it).
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn point_motion(
        &self,
        nodes: &[u32],
        side: &[usize; 3],
        nn: usize,
        nv: &[f64; 3],
        fp: &FacetPoint,
        x: &[f64],
        kin: &SlipKinematics,
    ) -> (Vec2, Vec2) {
        let mut u = Vec2::zeros();
        for j in 0..nn {
            let n = nodes[side[j]] as usize;
            u += Vec2::new(x[2 * n], x[2 * n + 1]) * nv[j];
        }
        let vel = match *kin {
            SlipKinematics::Static { x_prev, dtau } => {
                let mut a = Vec2::zeros();
                for j in 0..nn {
                    let n = nodes[side[j]] as usize;
                    a += Vec2::new(x_prev[2 * n], x_prev[2 * n + 1]) * nv[j];
                }
                (u - a) / dtau.max(f64::MIN_POSITIVE)
            }
            SlipKinematics::Dynamic { v, .. } => {
                let mut a = Vec2::zeros();
                for j in 0..nn {
                    let n = nodes[side[j]] as usize;
                    a += Vec2::new(v[2 * n], v[2 * n + 1]) * nv[j];
                }
                a
            }
            SlipKinematics::Steady { omega } => {
                // ω ∂θχ = ω (dX/dη + du/dη) / (dθ/dη).
                let mut du = Vec2::zeros();
                for j in 0..nn {
                    let n = nodes[side[j]] as usize;
                    du += Vec2::new(x[2 * n], x[2 * n + 1]) * fp.dn_dtheta[j];
                }
                (fp.dx_dtheta + du) * omega
            }
        };
        (u, vel)
    }

    /// The steady slip stencil of facet `e`, when the steady kinematics use it.
    #[inline]
    fn nodal_slip(&self, kin: &SlipKinematics) -> Option<&SteadySlip> {
        match kin {
            SlipKinematics::Steady { .. } => self.steady_slip.as_ref(),
            _ => None,
        }
    }

    /// Steady slip w = ω (∂θX1 + Σ_j N_j (∂θu1)_j) − v0 at a facet point from the nodal
    /// derivatives ([`super::steady_slip`]); `cw[b]` = ∂w/∂u_{b,1} over the facet's extended
    /// node list.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn nodal_slip_w(
        &self,
        s: &SteadySlip,
        e: usize,
        nn: usize,
        nv: &[f64; 3],
        fp: &FacetPoint,
        x: &[f64],
        kin: &SlipKinematics,
        cw: &mut [f64; MAX_EXT],
    ) -> f64 {
        let omega = match *kin {
            SlipKinematics::Steady { omega } => omega,
            _ => 0.0,
        };
        let d = s.facet_derivatives(e, nn, x);
        let mut du = 0.0;
        for j in 0..nn {
            du += nv[j] * d[j];
            for &(i, w) in &s.stencil[e][j] {
                cw[i as usize] += omega * nv[j] * w;
            }
        }
        omega * (fp.dx_dtheta[0] + du) - self.v0
    }

    /// ∂v/∂u_b (per facet node b, same for both components): kv N_b (static, dynamic) or
    /// ω ∂θN_b (steady).
    #[inline]
    fn velocity_coefficients(
        nv: &[f64; 3],
        fp: &FacetPoint,
        kin: &SlipKinematics,
        kv: f64,
    ) -> [f64; 3] {
        match *kin {
            SlipKinematics::Steady { omega } => fp.dn_dtheta.map(|d| omega * d),
            _ => nv.map(|n| kv * n),
        }
    }

    /// Contact element kernel for facet `e`: fills the local residual/tangent in the order of
    /// [`Self::element_dofs`]. `x`: current full state; `kin`: how the velocities are
    /// obtained (the last converged load step, the velocity field or ω ∂θχ).
    #[allow(clippy::too_many_arguments, clippy::needless_range_loop)]
    pub fn kernel(
        &self,
        mesh: &Mesh,
        dofs: &DofMap,
        x: &[f64],
        kin: &SlipKinematics,
        e: usize,
        loc: &mut LocalSystem,
        with_k: bool,
    ) {
        let f = self.facets[e];
        let c = f.cell as usize;
        let p = mesh.degree[c] as usize;
        let h = self.road_height(dofs, x);
        let has_h = self.load.is_some() && dofs.n_global > 0;
        let nn = p + 1;
        let slip = self.nodal_slip(kin);
        // Nodes of the element: the facet's, or its extended list with the steady slip.
        let ne = self.steady_slip.as_ref().map_or(nn, |s| s.nodes(e).len());
        let ih = 2 * ne; // local index of H
        if has_h && e == 0 {
            // R_H = P − ∫ t_n ds0: the load enters once, through the first contact element.
            loc.r[ih] += self.load.unwrap_or(0.0);
        }
        if !self.can_touch(mesh, &f, x, h) {
            return;
        }
        self.visited.fetch_add(1, Ordering::Relaxed);
        let nodes = mesh.cell_nodes(c);
        let side = f.local_nodes(p);
        let nd = loc.nd;
        let friction = self.friction.is_active();
        // The elastic-slip law acts through the steady march only (the scene accepts it in
        // the steady mode alone); elsewhere it contributes nothing.
        let elastic_law = self.is_elastic_slip();
        let elastic = match kin {
            SlipKinematics::Steady { .. } if elastic_law => self.elastic.as_ref(),
            _ => None,
        };
        let (elastic_mu, elastic_k) = match self.friction {
            Friction::CoulombElastic(l) => (l.mu, l.k_t),
            _ => (0.0, 0.0),
        };
        let (kx, kv, dynamic) = kin.factors();
        let damping = dynamic && self.normal.has_damping();
        for q in 0..self.pts.len() {
            let (nv, dv) = lagrange_1d(p, self.pts[q]);
            let fp = self.facet_point(mesh, &f, q, &nv, &dv, p);
            let (u, vel) = self.point_motion(nodes, &side, nn, &nv, &fp, x, kin);
            let xc = fp.x + u;
            let delta = -h - xc[1];
            if delta <= 0.0 {
                continue;
            }
            let rate = if damping { -vel[1] } else { 0.0 };
            let nval = self.normal.eval(delta, rate);
            if nval.t <= 0.0 && nval.d_delta == 0.0 {
                continue;
            }
            let ds = fp.ds0;
            // Derivatives with respect to the unknowns (δ = −H − x2, δ̇ = −v2): with
            // ∂x/∂u_b = kx N_b and ∂v/∂u_b = cv_b ([`Self::velocity_coefficients`]),
            // ∂t_n/∂u_{b,2} = −d_delta kx N_b − d_rate cv_b; ∂/∂H has the kx part only.
            let cv = Self::velocity_coefficients(&nv, &fp, kin, kv);
            let d_rate = if damping { nval.d_rate } else { 0.0 };
            let mut dtn_du2 = [0.0; 3];
            for b in 0..nn {
                dtn_du2[b] = -nval.d_delta * kx * nv[b] - d_rate * cv[b];
            }
            let dtn_dh = -nval.d_delta * kx;
            let (mut tt, mut dtt_du1, mut dtt_du2, mut dtt_dh) =
                (0.0, [0.0; MAX_EXT], [0.0; 3], 0.0);
            if let (Some(m), true) = (elastic, friction) {
                // Elastic slip: the marched traction; its own facet's part of the tangent
                // (the anchor's is applied matrix-free, [`ElasticMarch::apply_correction`]).
                let mp = m.point(e, q);
                tt = mp.t;
                match mp.state {
                    PointState::Stick { .. } => {
                        for b in 0..nn {
                            dtt_du1[b] = -elastic_k * nv[b];
                        }
                    }
                    PointState::Slip { sign } => {
                        let mu = elastic_mu;
                        for b in 0..nn {
                            dtt_du2[b] = sign * mu * dtn_du2[b];
                        }
                        dtt_dh = sign * mu * dtn_dh;
                    }
                    PointState::Out | PointState::Entry => {}
                }
            } else if friction && !elastic_law {
                // ∂w/∂u_{b,1}: the facet-wise cv_b, or ω Σ_j N_j W_jb (nodal derivatives).
                let mut cw = [0.0; MAX_EXT];
                let w = match slip {
                    Some(s) => self.nodal_slip_w(s, e, nn, &nv, &fp, x, kin, &mut cw),
                    None => {
                        cw[..nn].copy_from_slice(&cv[..nn]);
                        vel[0] - self.v0
                    }
                };
                let fv = self.friction.eval(w, nval.t, delta);
                tt = fv.t;
                for b in 0..ne {
                    dtt_du1[b] = fv.d_w * cw[b];
                }
                for b in 0..nn {
                    dtt_du2[b] = fv.d_tn * dtn_du2[b] - fv.d_delta * kx * nv[b];
                }
                dtt_dh = fv.d_tn * dtn_dh - fv.d_delta * kx;
            }
            for a in 0..nn {
                loc.r[2 * a] -= nv[a] * tt * ds;
                loc.r[2 * a + 1] -= nv[a] * nval.t * ds;
            }
            if has_h {
                loc.r[ih] -= nval.t * ds;
            }
            if !with_k {
                continue;
            }
            for a in 0..nn {
                let na = nv[a] * ds;
                for (b, d) in dtt_du1.iter().enumerate().take(ne) {
                    loc.k[(2 * a) * nd + 2 * b] -= na * d;
                }
                for b in 0..nn {
                    loc.k[(2 * a) * nd + 2 * b + 1] -= na * dtt_du2[b];
                    loc.k[(2 * a + 1) * nd + 2 * b + 1] -= na * dtn_du2[b];
                }
                if has_h {
                    loc.k[(2 * a) * nd + ih] -= na * dtt_dh;
                    loc.k[(2 * a + 1) * nd + ih] -= na * dtn_dh;
                    loc.k[ih * nd + 2 * a + 1] -= dtn_du2[a] * ds;
                }
            }
            if has_h {
                loc.k[ih * nd + ih] -= dtn_dh * ds;
            }
        }
    }

    /// Gershgorin row sums of the boundary matrix ∫Γc N_a N_b ds0 over the contact facets, per
    /// mesh node (0 off the contact boundary): an upper bound on the eigenvalues of the contact
    /// penalty (× ∂t_n/∂δ) and damping (× ∂t_n/∂δ̇) matrices, for stable-step estimates.
    pub fn boundary_row_sums(&self, mesh: &Mesh) -> Vec<f64> {
        let mut out = vec![0.0; mesh.n_nodes()];
        for f in &self.facets {
            let c = f.cell as usize;
            let p = mesh.degree[c] as usize;
            let nodes = mesh.cell_nodes(c);
            let side = f.local_nodes(p);
            let mut m = [[0.0f64; 3]; 3];
            for q in 0..self.pts.len() {
                let (nv, dv) = lagrange_1d(p, self.pts[q]);
                let fp = self.facet_point(mesh, f, q, &nv, &dv, p);
                for a in 0..=p {
                    for b in 0..=p {
                        m[a][b] += nv[a] * nv[b] * fp.ds0;
                    }
                }
            }
            for a in 0..=p {
                out[nodes[side[a]] as usize] += m[a][..=p].iter().map(|v| v.abs()).sum::<f64>();
            }
        }
        out
    }

    /// Traction samples at every facet quadrature point (contact or not); `kin` as in
    /// [`Self::kernel`].
    pub fn samples(
        &self,
        mesh: &Mesh,
        dofs: &DofMap,
        x: &[f64],
        kin: &SlipKinematics,
    ) -> Vec<ContactSample> {
        let h = self.road_height(dofs, x);
        let (_, _, dynamic) = kin.factors();
        let damping = dynamic && self.normal.has_damping();
        let march = match *kin {
            SlipKinematics::Steady { omega } => self.elastic_march(mesh, dofs, x, omega),
            _ => None,
        };
        let mut out = Vec::new();
        for (e, f) in self.facets.iter().enumerate() {
            let c = f.cell as usize;
            let p = mesh.degree[c] as usize;
            let nodes = mesh.cell_nodes(c);
            let side = f.local_nodes(p);
            let slip = self.nodal_slip(kin);
            for q in 0..self.pts.len() {
                let (nv, dv) = lagrange_1d(p, self.pts[q]);
                let fp = self.facet_point(mesh, f, q, &nv, &dv, p);
                let (u, vel) = self.point_motion(nodes, &side, p + 1, &nv, &fp, x, kin);
                let xc = fp.x + u;
                let delta = -h - xc[1];
                let w = match slip {
                    Some(s) => {
                        let mut cw = [0.0; MAX_EXT];
                        self.nodal_slip_w(s, e, p + 1, &nv, &fp, x, kin, &mut cw)
                    }
                    None => vel[0] - self.v0,
                };
                let (t_n, t_t) = if delta > 0.0 {
                    let nv = self.normal.eval(delta, if damping { -vel[1] } else { 0.0 });
                    let tt = if let Some(m) = &march {
                        m.point(e, q).t
                    } else if self.friction.is_active() && !self.is_elastic_slip() {
                        self.friction.eval(w, nv.t, delta).t
                    } else {
                        0.0
                    };
                    (nv.t, tt)
                } else {
                    (0.0, 0.0)
                };
                out.push(ContactSample {
                    theta: fp.theta,
                    x1: xc[0],
                    x2: xc[1],
                    delta: delta.max(0.0),
                    t_n,
                    t_t,
                    w,
                    ds0: fp.ds0,
                });
            }
        }
        out
    }

    /// Resultant force and moment of the contact tractions on the body, patch extent, peak
    /// pressure and the pressure's second moment.
    pub fn totals(samples: &[ContactSample]) -> ContactTotals {
        let mut t = ContactTotals {
            x_min: f64::NAN,
            x_max: f64::NAN,
            ..Default::default()
        };
        let (mut p0, mut p1) = (0.0, 0.0);
        for s in samples {
            t.force_x += s.t_t * s.ds0;
            t.force_y += s.t_n * s.ds0;
            t.moment += (s.x1 * s.t_n - s.x2 * s.t_t) * s.ds0;
            if s.t_n > 0.0 {
                t.x_min = if t.x_min.is_nan() {
                    s.x1
                } else {
                    t.x_min.min(s.x1)
                };
                t.x_max = if t.x_max.is_nan() {
                    s.x1
                } else {
                    t.x_max.max(s.x1)
                };
                t.max_pressure = t.max_pressure.max(s.t_n);
                p0 += s.t_n * s.ds0;
                p1 += s.t_n * s.ds0 * s.x1;
            }
        }
        if p0 > 0.0 {
            t.centroid = p1 / p0;
            t.pressure_second_moment = samples
                .iter()
                .filter(|s| s.t_n > 0.0)
                .map(|s| s.t_n * s.ds0 * (s.x1 - t.centroid).powi(2))
                .sum::<f64>()
                / p0;
        }
        t
    }
}
