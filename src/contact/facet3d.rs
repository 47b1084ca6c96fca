//! Three-dimensional contact of the quadrilateral facets of a hexahedral mesh with the rigid
//! road plane x2 = −H (n·x = −H with camber).
//!
//! # Frame, sign conventions and units
//!
//! The frame is the 3D frame of the revolved meshes: x1 along the road, x2 up, x3 along the
//! axle; the road is the plane x2 = −H (H > 0 the road height below the axle) and moves in its
//! own plane with the velocity V = (V1, V3) (hub frame; components along e1 and e3). A point of
//! the facet at the reference position X has the current position x = X + u and the material
//! velocity v. The formulas below are written for the uncambered road; with a camber γ
//! ([`ContactSurface3D::set_camber`], [`RoadFrame`]) the road's frame (e1, n, e3) replaces
//! (x1, x2, x3) in them: δ = −H − n·x, δ̇ = −n·v, w = (e1·v − V1, e3·v − V3),
//! T = t1 e1 + t_n n + t3 e3, and the tangent's x2 column becomes the rank-one −(∂T/∂δ) nᵀ.
//! At every facet quadrature point
//!
//! ```text
//! δ = −H − x2                       penetration (> 0 in contact)
//! δ̇ = −v2                           its rate
//! w = (v1 − V1, v3 − V3)            slip velocity of the body relative to the road (in (e1, e3))
//! t_n = t_n(δ, δ̇) ≥ 0               normal compliance (super::laws::NormalCompliance)
//! t_T = (t1, t3) = t_T(w, t_n, δ)   isotropic friction (super::laws_vec::eval_vec)
//! ```
//!
//! The traction on the body is T = t1 e1 + t_n e2 + t3 e3 per unit **reference** area dA0 of
//! the facet (as the 2D element integrates per unit reference length ds0): t_n pushes the body
//! up, t_T opposes the slip (t_T·w ≤ 0). The residual follows the convention R = internal −
//! external, the contact traction being external:
//!
//! ```text
//! R_{3a+i} −= ∫_facet N_a T_i dA0,
//! ```
//!
//! with the cell-local dof order 3·a + i (a a local node of the hexahedron in the
//! [`crate::element::hex`] order, i the component). Units: lengths L (of the mesh), tractions
//! F/L², c_n in F/L^{2+m_n}, b_n in F·T/L^{3+l_n}, velocities L/T (in a static analysis: L per
//! unit pseudo-time, see below), the resultant force F and the moment F·L.
//!
//! # Velocities and the tangent
//!
//! As in 2D ([`super::facet::SlipKinematics`]) the kinematics ([`Kinematics3D`]) say where the
//! velocity comes from and how it moves with the unknown U:
//!
//! * `Static { u_prev, dtau }`: v = (u − u_prev)/Δτ in the pseudo-time of the load stepping
//!   (so ε of the friction law is a slip length over the whole loading); δu = δU, δv = δU/Δτ;
//!   no normal damping (δ̇ is not a physical rate).
//! * `Dynamic { v, kx, kv }`: the velocity field of the time integrator; δu = kx δU and
//!   δv = kv δU (generalized-α: kx = 1 − α_f, kv = (1 − α_f) γ/(β Δt)); damping active.
//!
//! * `Steady { omega }`: steady rolling in the θ-referential description, v = ω ∂θχ, the
//!   θ-derivative taken along the facet as the plane program's steady contact element does:
//!   along the direction d = α a + β b of the facet's tangent plane (a, b the reference
//!   tangents of its two parameters) along which the polar angle advances by 1 and x3 stays,
//!   so v = ω (d + Σ_b (∂_d N_b) u_b) with ∂_d N_b = α ∂N_b/∂ξ_a + β ∂N_b/∂ξ_b. On an exact
//!   cylindrical facet d = t = e3 × X = (−X2, X1, 0); on an isoparametric one d is the
//!   interpolated surface's, and a plane-strain slab reproduces the plane program's
//!   dx/dθ = (dX/dη)/(dθ/dη). δv = ω Σ_b (∂_d N_b) δU_b (facet nodes only); damping active.
//!   The slip w is the 3D form of the plane program's w = ω ∂θχ1 − v0, facet-wise (the plane
//!   program's steady mode takes the friction slip from nodal θ-differences along the
//!   contact boundary by default, see [`super::steady_slip`]).
//!
//! With the derivatives of the laws, ∂T/∂U_b = N_b D with the 3 × 3 matrix (rows and columns
//! in the component order 1, 2, 3; d_w the 2 × 2 ∂t_T/∂w in the (1, 3) components)
//!
//! ```text
//! g = −(∂t_n/∂δ kx + ∂t_n/∂δ̇ kv)
//! D = | kv d_w11   ∂t1/∂t_n g − ∂t1/∂δ kx   kv d_w13 |
//!     | 0          g                         0        |
//!     | kv d_w31   ∂t3/∂t_n g − ∂t3/∂δ kx   kv d_w33 |
//! ```
//!
//! and the local tangent K_{3a+i, 3b+j} = −∫ N_a N_b D_ij dA0. In the kernel D is kept as
//! its two parts, ∂T/∂x (the column of x2) and ∂T/∂v, so that each takes its own weight: kx N_b
//! for the position, kv N_b (nodal velocities) or ω ∇N_b · t (steady) for the velocity. Frictionless and undamped it is
//! symmetric: the residual is then the gradient of Φ = ∫ c_n δ^{m+1}/(m+1) dA0.
//!
//! # The road height as an unknown (load control)
//!
//! [`ContactSurface3D::facet_kernel_height`] appends H after the cell's dofs: its row is the
//! facet's part −∫ t_n dA0 of the equation λ · load − ∫ t_n dA0 = 0 (the load added once by the
//! caller), with ∂δ/∂H = −1, so that ∂T/∂H = (∂t1/∂t_n ∂t_n/∂H − ∂t1/∂δ, −∂t_n/∂δ,
//! ∂t3/∂t_n ∂t_n/∂H − ∂t3/∂δ) and ∂R_H/∂U_b = −∫ N_b ∂t_n/∂u_b2 dA0; H moves no velocity.
//!
//! # Facets, rule and margin
//!
//! A facet is a [`HexFacet`] (cell, face) of a [`HexMesh`]; the reference surface, its area
//! element dA0 (from [`surface_map`]) and position come from the cell's exact map where it
//! has one (cylindrical, crowned), else from the isoparametric interpolation of its nodes. The
//! facet rule is the tensor Gauss (1–6 points per direction) or Gauss–Lobatto (2–4) rule
//! ([`FacetRule3D`]). A facet is skipped when all its nodes are higher than the road by more
//! than 10 % of the longer diagonal of its corners (the rule of the 2D element).

use super::facet::FacetRule;
use super::laws::{Friction, LawError, NormalCompliance};
use super::laws_vec::eval_vec;
use super::steady_slip3d::{SteadySlip3D, MAX_EXTRA, MAX_FACET_NODES};
use crate::element::hex::{
    face_axis, face_free_axes, surface_map, FacetPoints, FacetRule3D, Hex27, Hex8, Lagrange3D,
};
use crate::mesh::hex_mesh::{HexFacet, HexMesh};
use crate::physics::ring_derivative::WIDTH;
use nalgebra::{Matrix3, Vector2, Vector3};

/// Largest number of dofs of a cell (Hex27).
pub const MAX_CELL_DOFS: usize = 81;

/// Most nodes of a contact element: a Hex27 cell and the stencil nodes of the steady nodal
/// slip outside it ([`super::steady_slip3d`]).
pub const MAX_ELEMENT_NODES: usize = 27 + MAX_EXTRA;

/// Most dofs of a contact element (its nodes' and the road height under load control).
pub const MAX_ELEMENT_DOFS: usize = 3 * MAX_ELEMENT_NODES + 1;

/// Nodal-slip weights of one facet ([`SteadySlip3D::stencil`]).
type Stencil = [[(u8, f64); WIDTH]; MAX_FACET_NODES];

/// Error in the set-up or the input of a 3D contact surface.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Contact3DError {
    #[error(transparent)]
    Law(#[from] LawError),
    #[error(
        "facet rule {0:?} is not available on hexahedral facets (Gauss: 1-6 points, Lobatto: 2-4)"
    )]
    Rule(FacetRule),
    #[error("friction law `{0}` is the steady mode's elastic-slip law; the 3D contact surface has no steady kinematics")]
    SteadyOnlyFriction(&'static str),
    #[error("facet {index}: face {face} is not a face of a hexahedron (0..6)")]
    BadFace { index: usize, face: u8 },
    #[error("facet {index}: cell {cell} is not in the mesh ({n_cells} cells)")]
    BadCell {
        index: usize,
        cell: u32,
        n_cells: usize,
    },
    #[error("facet {index}: cell {cell} has degree {degree}; hexahedra of degree 1 or 2 only")]
    BadDegree { index: usize, cell: u32, degree: u8 },
    #[error("vector `{name}` has {got} entries, the mesh needs {want} (3 per node)")]
    Length {
        name: &'static str,
        got: usize,
        want: usize,
    },
    #[error("road height H = {0} and road velocity must be finite")]
    NonFinite(f64),
}

/// Where the velocity at the contact points comes from (full vectors, 3 per node).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kinematics3D<'a> {
    /// Static analysis: v = (u − u_prev)/Δτ (load-stepping pseudo-time), no normal damping.
    Static { u_prev: &'a [f64], dtau: f64 },
    /// Dynamic analysis: `v` is the velocity field; a unit change of the unknown moves the
    /// positions by `kx` and the velocities by `kv`. Normal damping active.
    Dynamic { v: &'a [f64], kx: f64, kv: f64 },
    /// Steady rolling in the θ-referential description (ω in rad/s about +x3): the unknown is
    /// the motion χ = X + u of the material point at the referential position X, and the
    /// velocity is v = ω ∂θχ, the θ-derivative taken along the facet (module docs; t =
    /// e3 × X = (−X2, X1, 0) on exact cylindrical facets). Normal damping active.
    Steady { omega: f64 },
}

impl Kinematics3D<'_> {
    /// (kx, kv, damping active); in the steady kinematics kv = ω (δv = ω ∇δu t).
    pub fn factors(&self) -> (f64, f64, bool) {
        match *self {
            Kinematics3D::Static { dtau, .. } => (1.0, 1.0 / dtau.max(f64::MIN_POSITIVE), false),
            Kinematics3D::Dynamic { kx, kv, .. } => (kx, kv, true),
            Kinematics3D::Steady { omega } => (1.0, omega, true),
        }
    }
}

/// Cell-local motion of one facet's cell: displacements and velocities (3·a + i order, 3N
/// entries) and the factors of [`Kinematics3D::factors`].
#[derive(Clone, Copy, Debug)]
pub struct CellMotion<'a> {
    pub u: &'a [f64],
    pub v: &'a [f64],
    pub kx: f64,
    pub kv: f64,
    pub damping: bool,
}

/// Resultants and statistics of the contact on the body (accumulated over facets).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ContactTotals3D {
    /// ∫ T dA0: force of the road on the body (F1 longitudinal, F2 vertical, F3 lateral).
    pub force: [f64; 3],
    /// ∫ x × T dA0: moment about the hub centre (the origin).
    pub moment: [f64; 3],
    /// Reference area of the quadrature points with t_n > 0 (Σ dA0).
    pub contact_area: f64,
    /// Largest penetration δ and pressure t_n at a quadrature point.
    pub max_penetration: f64,
    pub max_pressure: f64,
    /// Quadrature points with t_n > 0, and facets integrated (not skipped by the margin).
    pub points_in_contact: usize,
    pub facets_integrated: usize,
}

impl ContactTotals3D {
    /// Add the totals of another set of facets.
    pub fn add(&mut self, o: &ContactTotals3D) {
        for i in 0..3 {
            self.force[i] += o.force[i];
            self.moment[i] += o.moment[i];
        }
        self.contact_area += o.contact_area;
        self.max_penetration = self.max_penetration.max(o.max_penetration);
        self.max_pressure = self.max_pressure.max(o.max_pressure);
        self.points_in_contact += o.points_in_contact;
        self.facets_integrated += o.facets_integrated;
    }
}

/// Contact state at one facet quadrature point (for outputs).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ContactSample3D {
    pub cell: u32,
    pub face: u8,
    /// Current position.
    pub x1: f64,
    pub x2: f64,
    pub x3: f64,
    /// Penetration (δ)_+.
    pub delta: f64,
    /// Contact pressure t_n.
    pub p: f64,
    /// Tangential traction on the body (e1, e3 components).
    pub t1: f64,
    pub t3: f64,
    /// Slip velocity w = (v1 − V1, v3 − V3).
    pub w1: f64,
    pub w3: f64,
    /// In contact with friction and |w| below the regularisation ε (the regularised stick
    /// zone); false without friction.
    pub stick: bool,
    /// Reference area weight of the point (dA0).
    pub da0: f64,
}

/// The contact surface: facets, road, laws and facet rule.
#[derive(Clone, Debug)]
pub struct ContactSurface3D {
    /// Road height H: the road is the plane x2 = −H.
    pub h: f64,
    /// Road velocity (V1, V3) in its plane.
    pub v_road: Vector2<f64>,
    pub normal: NormalCompliance,
    pub friction: Friction,
    pub rule: FacetRule,
    pub facets: Vec<HexFacet>,
    /// The facet rule on each of the six faces.
    rules: Vec<FacetRule3D>,
    /// Steady kinematics: the friction slip from nodal θ-derivatives along the node rings
    /// ([`super::steady_slip3d`]); set by [`Self::enable_steady_slip`].
    steady_slip: Option<SteadySlip3D>,
    /// The road's frame in the wheel's (camber, [`Self::set_camber`]).
    frame: RoadFrame,
}

/// The road's frame in the wheel frame: `n` its upward unit normal, `e1` and `e3` its
/// in-plane directions (longitudinal, lateral). Without camber (e1, n, e3) = (x1, x2, x3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoadFrame {
    pub e1: Vector3<f64>,
    pub n: Vector3<f64>,
    pub e3: Vector3<f64>,
}

impl RoadFrame {
    /// The frame of a wheel cambered by `gamma` (radians): the wheel plane tilted by γ about
    /// the rolling direction x1 relative to the road, so that in the wheel frame the road is
    /// turned by −γ about x1: n = (0, cos γ, −sin γ), e3 = (0, sin γ, cos γ), e1 = x1. γ > 0
    /// lowers the wheel's +x3 side toward the road: the wheel leans toward +e3 (its top is at
    /// +R sin γ along e3 from its bottom).
    pub fn cambered(gamma: f64) -> Self {
        let (s, c) = gamma.sin_cos();
        Self {
            e1: Vector3::x(),
            n: Vector3::new(0.0, c, -s),
            e3: Vector3::new(0.0, s, c),
        }
    }

    /// Components of a wheel-frame vector in the road frame (along e1, n, e3).
    pub fn components(&self, v: [f64; 3]) -> [f64; 3] {
        let v = Vector3::from(v);
        [self.e1.dot(&v), self.n.dot(&v), self.e3.dot(&v)]
    }
}

/// One facet quadrature point: shape values, reference and current position, velocity, and
/// how the velocity moves with the cell's nodal displacements: δv = Σ_b `sv[b]` δu_b over the
/// cell nodes `cols` (the facet's nodes).
struct Point<'a> {
    n: &'a [f64],
    x: Vector3<f64>,
    vel: Vector3<f64>,
    da0: f64,
    sv: &'a [f64],
    cols: &'a [usize],
    /// The velocity of the friction slip and its sensitivity δv_w = Σ_m `sw[m]` δu_m over
    /// the element's local nodes `wcols`: `vel`, `sv`, `cols` except with the steady nodal
    /// slip.
    vw: Vector3<f64>,
    sw: &'a [f64],
    wcols: &'a [usize],
}

/// Where the velocity of a facet point comes from inside the kernel.
#[derive(Clone, Copy, Debug)]
enum PointVelocity<'a> {
    /// Interpolated from the cell's nodal velocities; δx = kx N δU, δv = kv N δU.
    Nodal {
        v: &'a [f64],
        kx: f64,
        kv: f64,
        damping: bool,
    },
    /// Steady rolling: v = ω ∂θχ, ∂θ along the facet (module docs); with `stencil` the
    /// friction slip's ∂θu from nodal derivatives ([`super::steady_slip3d`]).
    Steady {
        omega: f64,
        stencil: Option<&'a Stencil>,
    },
}

impl PointVelocity<'_> {
    /// (kx, damping active).
    fn kx_damping(&self) -> (f64, bool) {
        match *self {
            PointVelocity::Nodal { kx, damping, .. } => (kx, damping),
            PointVelocity::Steady { .. } => (1.0, true),
        }
    }
}

impl ContactSurface3D {
    /// A contact surface on `facets`. Checks the laws, the rule and the face numbers.
    pub fn new(
        facets: Vec<HexFacet>,
        h: f64,
        v_road: Vector2<f64>,
        normal: NormalCompliance,
        friction: Friction,
        rule: FacetRule,
    ) -> Result<Self, Contact3DError> {
        normal.validate()?;
        friction.validate()?;
        if friction.kind().steady_only() && friction.is_active() {
            return Err(Contact3DError::SteadyOnlyFriction(friction.name()));
        }
        if !h.is_finite() || !v_road.iter().all(|v| v.is_finite()) {
            return Err(Contact3DError::NonFinite(h));
        }
        let (q, kind) = match rule {
            FacetRule::Gauss(q) if (1..=6).contains(&q) => (q, FacetPoints::Gauss),
            FacetRule::Lobatto(q) if (2..=4).contains(&q) => (q, FacetPoints::GaussLobatto),
            _ => return Err(Contact3DError::Rule(rule)),
        };
        if let Some((index, f)) = facets.iter().enumerate().find(|(_, f)| f.face >= 6) {
            return Err(Contact3DError::BadFace {
                index,
                face: f.face,
            });
        }
        Ok(Self {
            h,
            v_road,
            normal,
            friction,
            rule,
            facets,
            rules: (0..6).map(|f| FacetRule3D::new(f, q, kind)).collect(),
            steady_slip: None,
            frame: RoadFrame::cambered(0.0),
        })
    }

    /// Camber the wheel by `gamma` (radians, |γ| < π/2) relative to the road
    /// ([`RoadFrame::cambered`]): the road becomes the plane n·x = −H, its velocity (V1, V3)
    /// is along (e1, e3), the slip is w = (e1·v − V1, e3·v − V3), δ = −H − n·x, δ̇ = −n·v.
    pub fn set_camber(&mut self, gamma: f64) -> Result<(), Contact3DError> {
        if !(gamma.is_finite() && gamma.abs() < std::f64::consts::FRAC_PI_2) {
            return Err(Contact3DError::NonFinite(gamma));
        }
        self.frame = RoadFrame::cambered(gamma);
        Ok(())
    }

    /// The road's frame ([`Self::set_camber`]).
    pub fn frame(&self) -> RoadFrame {
        self.frame
    }

    /// The road height of first touch in the road's frame: the largest −n·X over the nodes
    /// of the facets' cells.
    pub fn first_touch(&self, mesh: &HexMesh) -> f64 {
        let n = self.frame.n;
        self.facets
            .iter()
            .flat_map(|f| mesh.cell_nodes(f.cell as usize))
            .map(|&a| -n.dot(&mesh.nodes[a as usize]))
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// Take the steady friction slip from nodal θ-derivatives along the node rings of the
    /// facets ([`super::steady_slip3d`]); each facet's element then extends over the stencil
    /// nodes outside its cell ([`Self::extra_nodes`]). `false` (and the facet-wise derivative
    /// kept) when the facets do not form rings of at least five nodes. Only the steady
    /// kinematics use it.
    pub fn enable_steady_slip(&mut self, mesh: &HexMesh) -> bool {
        if self.steady_slip.is_none() {
            self.steady_slip = SteadySlip3D::new(mesh, &self.facets);
        }
        self.steady_slip.is_some()
    }

    /// Back to the facet-wise derivative of the steady friction slip.
    pub fn disable_steady_slip(&mut self) {
        self.steady_slip = None;
    }

    /// Whether the steady friction slip is taken from nodal derivatives.
    pub fn has_steady_slip(&self) -> bool {
        self.steady_slip.is_some()
    }

    /// The nodes of facet `e`'s element beyond its cell's (the nodal slip's stencil nodes;
    /// empty without it). The element's dofs are the cell's, then these nodes', 3 per node.
    pub fn extra_nodes(&self, e: usize) -> &[u32] {
        self.steady_slip.as_ref().map_or(&[], |s| s.extra(e))
    }

    /// Check that every facet's cell exists in `mesh` with degree 1 or 2, and the lengths of
    /// the full vectors.
    pub fn check(
        &self,
        mesh: &HexMesh,
        vectors: &[(&'static str, &[f64])],
    ) -> Result<(), Contact3DError> {
        for (index, f) in self.facets.iter().enumerate() {
            let c = f.cell as usize;
            if c >= mesh.n_cells() {
                return Err(Contact3DError::BadCell {
                    index,
                    cell: f.cell,
                    n_cells: mesh.n_cells(),
                });
            }
            if !matches!(mesh.degree[c], 1 | 2) {
                return Err(Contact3DError::BadDegree {
                    index,
                    cell: f.cell,
                    degree: mesh.degree[c],
                });
            }
        }
        let want = 3 * mesh.n_nodes();
        for &(name, v) in vectors {
            if v.len() != want {
                return Err(Contact3DError::Length {
                    name,
                    got: v.len(),
                    want,
                });
            }
        }
        Ok(())
    }

    /// Whether a facet of the cell with local motion `u` can reach the road (margin rule of
    /// the module docs).
    fn can_touch<E: Lagrange3D>(&self, mesh: &HexMesh, facet: HexFacet, u: &[f64]) -> bool {
        let nodes = mesh.cell_nodes(facet.cell as usize);
        let (fn_, nf) = face_nodes_fixed::<E>(facet.face as usize);
        let pos = |a: usize| {
            let n = nodes[a] as usize;
            mesh.nodes[n] + Vector3::new(u[3 * a], u[3 * a + 1], u[3 * a + 2])
        };
        let m = E::P + 1;
        // Corners in the face's tensor order: (0, 0), (p, 0), (0, p), (p, p).
        let c = [fn_[0], fn_[m - 1], fn_[m * (m - 1)], fn_[m * m - 1]];
        let chord = (pos(c[3]) - pos(c[0]))
            .norm()
            .max((pos(c[2]) - pos(c[1])).norm());
        let margin = 0.1 * chord;
        fn_[..nf]
            .iter()
            .any(|&a| self.frame.n.dot(&pos(a)) < -self.h + margin)
    }

    /// Visit the quadrature points of a facet with the cell-local displacement `u` and the
    /// velocity source `vel`.
    fn for_points<E: Lagrange3D>(
        &self,
        mesh: &HexMesh,
        facet: HexFacet,
        u: &[f64],
        vel: &PointVelocity,
        mut f: impl FnMut(&Point),
    ) {
        let c = facet.cell as usize;
        let face = facet.face as usize;
        let rule = &self.rules[face];
        let nodes = mesh.cell_nodes(c);
        let (fn_, nf) = face_nodes_fixed::<E>(face);
        let mut n = [0.0; 27];
        let mut dn = [[0.0; 3]; 27];
        let mut sv = [0.0; 27];
        let mut sw = [0.0; MAX_ELEMENT_NODES];
        let mut wcols = [0usize; MAX_ELEMENT_NODES];
        let mut nw = 0;
        if let PointVelocity::Steady {
            stencil: Some(st), ..
        } = *vel
        {
            // The element's nodes the nodal slip reaches (the same at every point).
            let mut seen = [false; MAX_ELEMENT_NODES];
            for row in &st[..nf] {
                for &(m, _) in row {
                    if !seen[m as usize] {
                        seen[m as usize] = true;
                        wcols[nw] = m as usize;
                        nw += 1;
                    }
                }
            }
        }
        for (xi, &wq) in rule.points.iter().zip(&rule.weights) {
            E::eval(*xi, &mut n[..E::N], &mut dn[..E::N]);
            let (xref, jac) = match mesh.geometry[c].exact_map(*xi) {
                Some(m) => m,
                None => {
                    let mut p = Vector3::zeros();
                    let mut j = Matrix3::zeros();
                    for a in 0..E::N {
                        let xa = mesh.nodes[nodes[a] as usize];
                        p += xa * n[a];
                        for k in 0..3 {
                            for i in 0..3 {
                                j[(i, k)] += xa[i] * dn[a][k];
                            }
                        }
                    }
                    (p, j)
                }
            };
            let (da, _) = surface_map(&jac, face);
            let mut x = xref;
            for &a in &fn_[..nf] {
                for i in 0..3 {
                    x[i] += n[a] * u[3 * a + i];
                }
            }
            let mut v = Vector3::zeros();
            let mut vw = None;
            let cols: &[usize] = match *vel {
                PointVelocity::Nodal { v: vn, kv, .. } => {
                    for &a in &fn_[..nf] {
                        for i in 0..3 {
                            v[i] += n[a] * vn[3 * a + i];
                        }
                        sv[a] = kv * n[a];
                    }
                    &fn_[..nf]
                }
                PointVelocity::Steady { omega, stencil } => {
                    // ∂θ along the facet: the direction d = α a + β b of the facet's tangent
                    // plane (a, b its parameter tangents) along which θ advances by 1 and x3
                    // stays, d = t = e3 × X on an exact cylindrical facet.
                    let [p, q] = face_free_axes(face);
                    let (ta, tb) = (jac.column(p), jac.column(q));
                    let r2 = xref[0] * xref[0] + xref[1] * xref[1];
                    let rate =
                        |w: &nalgebra::MatrixView3x1<f64>| (xref[0] * w[1] - xref[1] * w[0]) / r2;
                    let (ga, gb) = (rate(&ta), rate(&tb));
                    let det = ga * tb[2] - gb * ta[2];
                    let scale = ta.norm() * tb.norm() / r2.sqrt().max(f64::MIN_POSITIVE);
                    let (al, be) = if r2 > 0.0 && det.abs() > 1e-12 * scale {
                        (tb[2] / det, -ta[2] / det)
                    } else {
                        (0.0, 0.0)
                    };
                    let d = ta * al + tb * be;
                    v = d;
                    for &b in &fn_[..nf] {
                        let gt = al * dn[b][p] + be * dn[b][q];
                        for i in 0..3 {
                            v[i] += u[3 * b + i] * gt;
                        }
                        sv[b] = omega * gt;
                    }
                    v *= omega;
                    if let Some(st) = stencil {
                        // v_w = ω (d + Σ_j N_j (∂θu)_j), (∂θu)_j = Σ_k W_jk u_k.
                        let mut w = d;
                        for &m in &wcols[..nw] {
                            sw[m] = 0.0;
                        }
                        for (j, row) in st[..nf].iter().enumerate() {
                            let nj = n[fn_[j]];
                            for &(m, wk) in row {
                                let m = m as usize;
                                for i in 0..3 {
                                    w[i] += nj * wk * u[3 * m + i];
                                }
                                sw[m] += omega * nj * wk;
                            }
                        }
                        vw = Some(w * omega);
                    }
                    &fn_[..nf]
                }
            };
            let (vw, sw, wcols): (Vector3<f64>, &[f64], &[usize]) = match vw {
                Some(w) => (w, &sw[..], &wcols[..nw]),
                None => (v, &sv[..E::N], cols),
            };
            f(&Point {
                n: &n[..E::N],
                x,
                vel: v,
                da0: da * wq,
                sv: &sv[..E::N],
                cols,
                vw,
                sw,
                wcols,
            });
        }
    }

    /// The facet kernel: local residual `r` (3N entries) and, with `k`, the local tangent
    /// (row-major (3N)², `k[row·3N + col]`) of facet `facet` in the dofs of its cell, N the
    /// cell's node count; both buffers are overwritten (zeroed first). `m` is the cell-local
    /// motion. Adds the facet's resultants to `totals`. Returns false (with zero `r` and `k`)
    /// when the facet is skipped by the margin rule.
    ///
    /// The cell must have degree 1 or 2 ([`Self::check`]); `r`, `k`, `m.u`, `m.v` must hold at
    /// least 3N, (3N)², 3N, 3N entries.
    pub fn facet_kernel(
        &self,
        mesh: &HexMesh,
        facet: HexFacet,
        m: &CellMotion,
        r: &mut [f64],
        k: Option<&mut [f64]>,
        totals: &mut ContactTotals3D,
    ) -> bool {
        let vel = PointVelocity::Nodal {
            v: m.v,
            kx: m.kx,
            kv: m.kv,
            damping: m.damping,
        };
        self.kernel(mesh, facet, m.u, &vel, 0, r, k, false, totals)
    }

    /// [`Self::facet_kernel`] with the road height H as one more unknown after the cell's 3N
    /// dofs (load control): `r` has 3N + 1 entries, `k` (3N + 1)² (row-major, stride 3N + 1).
    /// Row 3N is −∫ t_n dA0 (the facet's part of the road-height equation
    /// λ·load − ∫ t_n dA0 = 0, whose load term the caller adds once); column 3N holds
    /// ∂R/∂H, with ∂δ/∂H = −1 (δ = −H − x2; H moves no velocity).
    pub fn facet_kernel_height(
        &self,
        mesh: &HexMesh,
        facet: HexFacet,
        m: &CellMotion,
        r: &mut [f64],
        k: Option<&mut [f64]>,
        totals: &mut ContactTotals3D,
    ) -> bool {
        let vel = PointVelocity::Nodal {
            v: m.v,
            kx: m.kx,
            kv: m.kv,
            damping: m.damping,
        };
        self.kernel(mesh, facet, m.u, &vel, 0, r, k, true, totals)
    }

    /// The facet kernel of steady rolling ([`Kinematics3D::Steady`]) of facet `e`: as
    /// [`Self::facet_kernel`] (with `with_h`: [`Self::facet_kernel_height`]) with the velocity
    /// v = ω ∂θχ of the element-local displacement `u`, the θ-derivative taken along the facet
    /// (module docs), the friction slip's from nodal derivatives when enabled
    /// ([`Self::enable_steady_slip`]). The element's local nodes are the cell's N, then the
    /// [`Self::extra_nodes`] of the facet (M of them): `u` holds 3(N + M) entries, `r` 3(N + M)
    /// (+ 1 with H), `k` the square of that, row-major.
    #[allow(clippy::too_many_arguments)]
    pub fn facet_kernel_steady(
        &self,
        mesh: &HexMesh,
        e: usize,
        u: &[f64],
        omega: f64,
        with_h: bool,
        r: &mut [f64],
        k: Option<&mut [f64]>,
        totals: &mut ContactTotals3D,
    ) -> bool {
        let vel = PointVelocity::Steady {
            omega,
            stencil: self.steady_slip.as_ref().map(|s| s.stencil(e)),
        };
        let n_extra = self.extra_nodes(e).len();
        self.kernel(mesh, self.facets[e], u, &vel, n_extra, r, k, with_h, totals)
    }

    #[allow(clippy::too_many_arguments)]
    fn kernel(
        &self,
        mesh: &HexMesh,
        facet: HexFacet,
        u: &[f64],
        vel: &PointVelocity,
        n_extra: usize,
        r: &mut [f64],
        k: Option<&mut [f64]>,
        with_h: bool,
        totals: &mut ContactTotals3D,
    ) -> bool {
        if mesh.degree[facet.cell as usize] == 1 {
            self.kernel_impl::<Hex8>(mesh, facet, u, vel, n_extra, r, k, with_h, totals)
        } else {
            self.kernel_impl::<Hex27>(mesh, facet, u, vel, n_extra, r, k, with_h, totals)
        }
    }

    #[allow(clippy::needless_range_loop, clippy::too_many_arguments)] // D[i][j], N_a N_b: indices as in the formulas
    fn kernel_impl<E: Lagrange3D>(
        &self,
        mesh: &HexMesh,
        facet: HexFacet,
        u: &[f64],
        vel: &PointVelocity,
        n_extra: usize,
        r: &mut [f64],
        mut k: Option<&mut [f64]>,
        with_h: bool,
        totals: &mut ContactTotals3D,
    ) -> bool {
        // Local size: the element's 3(N + M) dofs, then H under load control (index `ih`).
        let ih = 3 * (E::N + n_extra);
        let nd = ih + usize::from(with_h);
        r[..nd].fill(0.0);
        if let Some(k) = k.as_deref_mut() {
            k[..nd * nd].fill(0.0);
        }
        if !self.can_touch::<E>(mesh, facet, u) {
            return false;
        }
        totals.facets_integrated += 1;
        let (fn_, nf) = face_nodes_fixed::<E>(facet.face as usize);
        let friction = self.friction.is_active();
        let (kx, damping) = vel.kx_damping();
        let damping = damping && self.normal.has_damping();
        let RoadFrame { e1, n: nr, e3 } = self.frame;
        self.for_points::<E>(mesh, facet, u, vel, |pt| {
            let delta = -self.h - nr.dot(&pt.x);
            if delta <= 0.0 {
                return;
            }
            let rate = if damping { -nr.dot(&pt.vel) } else { 0.0 };
            let nv = self.normal.eval(delta, rate);
            if nv.t <= 0.0 && nv.d_delta == 0.0 {
                return;
            }
            let d_rate = if damping { nv.d_rate } else { 0.0 };
            // The traction in the road frame, τ = (τ1, τn, τ3) on (e1, n, e3), and its
            // derivatives in δ (g_δ), δ̇ (g_r) and the slip w (d_w); T = e1 τ1 + n τn + e3 τ3.
            let mut tau = Vector3::new(0.0, nv.t, 0.0);
            let mut g_d = Vector3::new(0.0, nv.d_delta, 0.0);
            let mut g_r = Vector3::new(0.0, d_rate, 0.0);
            let mut dw = Matrix3::zeros();
            if friction {
                let w = Vector2::new(
                    e1.dot(&pt.vw) - self.v_road[0],
                    e3.dot(&pt.vw) - self.v_road[1],
                );
                let fv = eval_vec(&self.friction, w, nv.t, delta);
                tau[0] = fv.t[0];
                tau[2] = fv.t[1];
                g_d[0] = fv.d_tn[0] * nv.d_delta + fv.d_delta[0];
                g_d[2] = fv.d_tn[1] * nv.d_delta + fv.d_delta[1];
                g_r[0] = fv.d_tn[0] * d_rate;
                g_r[2] = fv.d_tn[1] * d_rate;
                // ∂T/∂v through w = (e1·v − V1, e3·v − V3).
                let c0 = e1 * fv.d_w[(0, 0)] + e3 * fv.d_w[(1, 0)];
                let c1 = e1 * fv.d_w[(0, 1)] + e3 * fv.d_w[(1, 1)];
                dw = c0 * e1.transpose() + c1 * e3.transpose();
            }
            let global = |t: &Vector3<f64>| e1 * t[0] + nr * t[1] + e3 * t[2];
            let tr = global(&tau);
            // δ = −H − n·x, δ̇ = −n·v: ∂T/∂x = −(Q g_δ) nᵀ, ∂T/∂v (rate) = −(Q g_r) nᵀ,
            // ∂T/∂H = −Q g_δ.
            let q_d = global(&g_d);
            let dx = -q_d * nr.transpose();
            let dr = -global(&g_r) * nr.transpose();
            let da = pt.da0;
            for &a in &fn_[..nf] {
                for i in 0..3 {
                    r[3 * a + i] -= pt.n[a] * tr[i] * da;
                }
            }
            if with_h {
                r[ih] -= nv.t * da;
            }
            if nv.t > 0.0 {
                let f = tr * da;
                let mo = pt.x.cross(&f);
                for i in 0..3 {
                    totals.force[i] += f[i];
                    totals.moment[i] += mo[i];
                }
                totals.contact_area += da;
                totals.points_in_contact += 1;
                totals.max_penetration = totals.max_penetration.max(delta);
                totals.max_pressure = totals.max_pressure.max(nv.t);
            }
            if let Some(k) = k.as_deref_mut() {
                // ∂T_i/∂u_bj = ∂T_i/∂x_j kx N_b + (∂T/∂v, rate)_ij sv_b + (∂T/∂v, slip)_ij sw_b.
                for &a in &fn_[..nf] {
                    let na = pt.n[a] * da;
                    for &b in pt.cols {
                        let (cx, cv) = (na * kx * pt.n[b], na * pt.sv[b]);
                        for i in 0..3 {
                            let row = (3 * a + i) * nd + 3 * b;
                            for j in 0..3 {
                                k[row + j] -= cx * dx[(i, j)] + cv * dr[(i, j)];
                            }
                        }
                    }
                    if friction {
                        for &b in pt.wcols {
                            let cw = na * pt.sw[b];
                            for i in 0..3 {
                                let row = (3 * a + i) * nd + 3 * b;
                                for j in 0..3 {
                                    k[row + j] -= cw * dw[(i, j)];
                                }
                            }
                        }
                    }
                }
                if with_h {
                    // Column H of the displacement rows (∂δ/∂H = −1, H moves no velocity);
                    // row H: −∫ ∂t_n/∂U, −∫ ∂t_n/∂H (t_n does not depend on the slip).
                    for &a in &fn_[..nf] {
                        let na = pt.n[a] * da;
                        for i in 0..3 {
                            k[(3 * a + i) * nd + ih] += na * q_d[i];
                        }
                    }
                    for &b in pt.cols {
                        let (cx, cv) = (da * kx * pt.n[b], da * pt.sv[b]);
                        for j in 0..3 {
                            k[ih * nd + 3 * b + j] += (cx * nv.d_delta + cv * d_rate) * nr[j];
                        }
                    }
                    k[ih * nd + ih] += nv.d_delta * da;
                }
            }
        });
        true
    }

    /// Gather the cell-local displacement and velocity of cell `c` (3N entries each).
    fn gather(
        mesh: &HexMesh,
        c: usize,
        u: &[f64],
        kin: &Kinematics3D,
        ul: &mut [f64],
        vl: &mut [f64],
    ) {
        for (a, &n) in mesh.cell_nodes(c).iter().enumerate() {
            let n = n as usize;
            for i in 0..3 {
                ul[3 * a + i] = u[3 * n + i];
                vl[3 * a + i] = match *kin {
                    Kinematics3D::Static { u_prev, dtau } => {
                        (u[3 * n + i] - u_prev[3 * n + i]) / dtau.max(f64::MIN_POSITIVE)
                    }
                    Kinematics3D::Dynamic { v, .. } => v[3 * n + i],
                    Kinematics3D::Steady { .. } => 0.0,
                };
            }
        }
    }

    fn kin_vectors<'a>(u: &'a [f64], kin: &Kinematics3D<'a>) -> [(&'static str, &'a [f64]); 2] {
        match *kin {
            Kinematics3D::Static { u_prev, .. } => [("u", u), ("u_prev", u_prev)],
            Kinematics3D::Dynamic { v, .. } => [("u", u), ("v", v)],
            Kinematics3D::Steady { .. } => [("u", u), ("u", u)],
        }
    }

    /// Gather the element-local displacement of facet `e` (its cell's nodes, then its
    /// [`Self::extra_nodes`]) from the full `u` into `ul`; returns the element's dof count.
    fn gather_element(&self, mesh: &HexMesh, e: usize, u: &[f64], ul: &mut [f64]) -> usize {
        let c = self.facets[e].cell as usize;
        let mut k = 0;
        for &n in mesh.cell_nodes(c).iter().chain(self.extra_nodes(e)) {
            let n = n as usize;
            ul[k..k + 3].copy_from_slice(&u[3 * n..3 * n + 3]);
            k += 3;
        }
        k
    }

    /// Loop the facets at the full displacement `u` (3 per node): call
    /// `sink(cell, extra, r, k)` with each integrated facet's local residual and (with
    /// `with_k`) tangent in the dofs of its element (3·a + i, row-major): the cell's nodes,
    /// then the nodes `extra` ([`Self::extra_nodes`]: the steady nodal slip's, otherwise
    /// none), for a global assembler to scatter; return the totals.
    pub fn for_each_facet(
        &self,
        mesh: &HexMesh,
        u: &[f64],
        kin: &Kinematics3D,
        with_k: bool,
        mut sink: impl FnMut(usize, &[u32], &[f64], Option<&[f64]>),
    ) -> Result<ContactTotals3D, Contact3DError> {
        self.check(mesh, &Self::kin_vectors(u, kin))?;
        let (kx, kv, damping) = kin.factors();
        let mut totals = ContactTotals3D::default();
        let (mut ul, mut vl) = ([0.0; MAX_ELEMENT_DOFS], [0.0; MAX_CELL_DOFS]);
        let mut r = [0.0; MAX_ELEMENT_DOFS];
        let mut k = if with_k {
            vec![0.0; MAX_ELEMENT_DOFS * MAX_ELEMENT_DOFS]
        } else {
            Vec::new()
        };
        for (e, &f) in self.facets.iter().enumerate() {
            let c = f.cell as usize;
            let (integrated, nd) = match *kin {
                Kinematics3D::Steady { omega } => {
                    let nd = self.gather_element(mesh, e, u, &mut ul);
                    let kb = with_k.then_some(&mut k[..nd * nd]);
                    let ok = self.facet_kernel_steady(
                        mesh,
                        e,
                        &ul,
                        omega,
                        false,
                        &mut r,
                        kb,
                        &mut totals,
                    );
                    (ok, nd)
                }
                _ => {
                    let nd = 3 * mesh.cell_nodes(c).len();
                    Self::gather(mesh, c, u, kin, &mut ul, &mut vl);
                    let m = CellMotion {
                        u: &ul[..nd],
                        v: &vl[..nd],
                        kx,
                        kv,
                        damping,
                    };
                    let kb = with_k.then_some(&mut k[..nd * nd]);
                    (self.facet_kernel(mesh, f, &m, &mut r, kb, &mut totals), nd)
                }
            };
            if integrated {
                let extra = match *kin {
                    Kinematics3D::Steady { .. } => self.extra_nodes(e),
                    _ => &[],
                };
                sink(c, extra, &r[..nd], with_k.then_some(&k[..nd * nd]));
            }
        }
        Ok(totals)
    }

    /// Per mesh node a, Σ over the facets' quadrature points of |N_a| Σ_b |N_b| dA0 (0 off
    /// the contact surface): an upper bound on the row sums |∫ N_a N_b dA0| of the surface
    /// mass, hence (× ∂t_n/∂δ, ∂t_n/∂δ̇) on the eigenvalues of the contact penalty and
    /// damping matrices, for stable-step estimates.
    pub fn boundary_row_sums(&self, mesh: &HexMesh) -> Vec<f64> {
        let mut out = vec![0.0; mesh.n_nodes()];
        let ul = [0.0; MAX_ELEMENT_DOFS];
        let vl = [0.0; MAX_CELL_DOFS];
        for &f in &self.facets {
            let c = f.cell as usize;
            let nodes = mesh.cell_nodes(c);
            let nd = 3 * nodes.len();
            let vel = PointVelocity::Nodal {
                v: &vl[..nd],
                kx: 1.0,
                kv: 0.0,
                damping: false,
            };
            let mut visit = |pt: &Point| {
                let s: f64 = pt.n.iter().map(|v| v.abs()).sum();
                for (a, na) in pt.n.iter().enumerate() {
                    out[nodes[a] as usize] += na.abs() * s * pt.da0;
                }
            };
            if mesh.degree[c] == 1 {
                self.for_points::<Hex8>(mesh, f, &ul, &vel, &mut visit);
            } else {
                self.for_points::<Hex27>(mesh, f, &ul, &vel, &mut visit);
            }
        }
        out
    }

    /// The contact state at every quadrature point of every facet (contact or not) at the full
    /// displacement `u`, for outputs of the pressure and traction over the patch.
    pub fn samples(
        &self,
        mesh: &HexMesh,
        u: &[f64],
        kin: &Kinematics3D,
    ) -> Result<Vec<ContactSample3D>, Contact3DError> {
        self.check(mesh, &Self::kin_vectors(u, kin))?;
        let (_, _, damping) = kin.factors();
        let damping = damping && self.normal.has_damping();
        let friction = self.friction.is_active();
        let eps = self.friction.eps().unwrap_or(0.0);
        let mut out = Vec::new();
        let (mut ul, mut vl) = ([0.0; MAX_ELEMENT_DOFS], [0.0; MAX_CELL_DOFS]);
        for (e, &f) in self.facets.iter().enumerate() {
            let c = f.cell as usize;
            let RoadFrame { e1, n: nr, e3 } = self.frame;
            let mut visit = |pt: &Point| {
                let delta = -self.h - nr.dot(&pt.x);
                let w = Vector2::new(
                    e1.dot(&pt.vw) - self.v_road[0],
                    e3.dot(&pt.vw) - self.v_road[1],
                );
                let nv = self
                    .normal
                    .eval(delta, if damping { -nr.dot(&pt.vel) } else { 0.0 });
                let t = if friction && nv.t > 0.0 {
                    eval_vec(&self.friction, w, nv.t, delta).t
                } else {
                    Vector2::zeros()
                };
                out.push(ContactSample3D {
                    cell: f.cell,
                    face: f.face,
                    x1: pt.x[0],
                    x2: pt.x[1],
                    x3: pt.x[2],
                    delta: delta.max(0.0),
                    p: nv.t,
                    t1: t[0],
                    t3: t[1],
                    w1: w[0],
                    w3: w[1],
                    stick: friction && nv.t > 0.0 && w.norm() < eps,
                    da0: pt.da0,
                });
            };
            let nd = 3 * mesh.cell_nodes(c).len();
            let vel = match *kin {
                Kinematics3D::Steady { omega } => {
                    self.gather_element(mesh, e, u, &mut ul);
                    PointVelocity::Steady {
                        omega,
                        stencil: self.steady_slip.as_ref().map(|s| s.stencil(e)),
                    }
                }
                _ => {
                    Self::gather(mesh, c, u, kin, &mut ul, &mut vl);
                    PointVelocity::Nodal {
                        v: &vl[..nd],
                        kx: 1.0,
                        kv: 1.0,
                        damping,
                    }
                }
            };
            if mesh.degree[c] == 1 {
                self.for_points::<Hex8>(mesh, f, &ul, &vel, &mut visit);
            } else {
                self.for_points::<Hex27>(mesh, f, &ul, &vel, &mut visit);
            }
        }
        Ok(out)
    }
}

/// Local nodes of face `f` of `E` in the face's tensor order (as
/// [`crate::element::hex::face_nodes`], without allocating) and their count.
fn face_nodes_fixed<E: Lagrange3D>(f: usize) -> ([usize; 9], usize) {
    let m = E::P + 1;
    let (k, s) = face_axis(f);
    let fixed = if s < 0.0 { 0 } else { E::P };
    let [u, v] = face_free_axes(f);
    let mut out = [0usize; 9];
    for iv in 0..m {
        for iu in 0..m {
            let mut idx = [0usize; 3];
            idx[k] = fixed;
            idx[u] = iu;
            idx[v] = iv;
            out[iu + m * iv] = idx[0] + m * (idx[1] + m * idx[2]);
        }
    }
    (out, m * m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hex::face_nodes;

    #[test]
    fn fixed_face_nodes_match_the_element_module() {
        for f in 0..6 {
            let (a, n) = face_nodes_fixed::<Hex8>(f);
            assert_eq!(&a[..n], face_nodes::<Hex8>(f).as_slice());
            let (a, n) = face_nodes_fixed::<Hex27>(f);
            assert_eq!(&a[..n], face_nodes::<Hex27>(f).as_slice());
        }
    }
}
