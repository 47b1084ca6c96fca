//! The three-dimensional solid as a nonlinear system for the solvers: the state, the dof map,
//! the assembler and the coefficients of the analysis, with load stepping in ω² (spinning) or
//! in the body-force factor.
//!
//! The residual is that of [`super::kernel`] summed over the cells (assembled in parallel by
//! [`Assembler::add_block_large`]); the coefficients at load factor λ are λ times the target's
//! ([`Solid3DSystem::set_target`]), so a spinning solve steps ω² from 0 as the plane-strain one
//! does.

use super::kernel::{Coefficients, Inadmissible};
use super::solid3d::Solid3D;
use crate::assembly::{Assembler, DofMap, CONSTRAINED};
use crate::contact::facet3d::{CellMotion, Contact3DError, ContactSurface3D, ContactTotals3D};
use crate::solver::stepping::LoadedSystem;
use crate::solver::NonlinearSystem;
use std::sync::atomic::{AtomicBool, Ordering};

/// The 3D solid, its state and what the analysis supplies.
pub struct Solid3DSystem {
    pub solid: Solid3D,
    pub dofs: DofMap,
    pub asm: Assembler,
    /// Full state: displacements, cell pressures, global unknowns.
    pub x: Vec<f64>,
    /// Coefficients of the current evaluation.
    pub coefficients: Coefficients,
    /// Coefficients at load factor 1.
    target: Coefficients,
    ref_norms: Vec<f64>,
    /// Why the last evaluation failed, if it did.
    inadmissible: Option<Inadmissible>,
    /// Contact with the road (block 1 of the assembler: the cells of the contact facets).
    pub contact: Option<RoadContact3D>,
}

/// The road under displacement control: H = `h_touch` − λ · `disp`, and the state of the
/// load-stepping pseudo-time the friction slip is measured in.
pub struct RoadContact3D {
    pub surface: ContactSurface3D,
    pub h_touch: f64,
    pub disp: f64,
    /// Full state at the start of the step and the step's pseudo-time length.
    x_prev: Vec<f64>,
    lambda_prev: f64,
    dtau: f64,
    /// Resultants of the last evaluation.
    pub totals: ContactTotals3D,
}

impl Solid3DSystem {
    /// The system with displacement component i of node n fixed where `fixed_u[3n + i]`.
    pub fn new(solid: Solid3D, fixed_u: &[bool]) -> Self {
        let dofs = solid.dof_map(fixed_u, 0);
        let asm = Assembler::with_blocks(
            &dofs,
            vec![(dofs.cell_dofs.clone(), dofs.cell_offsets.clone())],
        );
        let mut x = vec![0.0; dofs.n_full()];
        if let crate::physics::PressureMode::Exact { p0 } = solid.pressure {
            let per = solid.dofs_per_cell();
            for c in 0..solid.mesh.n_cells() {
                x[dofs.n_u + per * c] = p0;
            }
        }
        // Pressure residuals are volumes: their floor is a fraction of the body's volume.
        let volume = Self::volume(&solid);
        Self {
            solid,
            dofs,
            asm,
            x,
            coefficients: Coefficients::default(),
            target: Coefficients::default(),
            ref_norms: vec![0.0, 1e-3 * volume],
            inadmissible: None,
            contact: None,
        }
    }

    /// Add contact with the road on `surface` under displacement control (road height
    /// H = h_touch − λ · disp), after checking the surface against the mesh.
    pub fn with_contact(
        mut self,
        mut surface: ContactSurface3D,
        h_touch: f64,
        disp: f64,
    ) -> Result<Self, Contact3DError> {
        let n_u = self.dofs.n_u;
        surface.check(&self.solid.mesh, &[("u", &self.x[..n_u])])?;
        surface.h = h_touch;
        let mesh = &self.solid.mesh;
        let (mut d, mut o) = (Vec::new(), vec![0]);
        for f in &surface.facets {
            let c = f.cell as usize;
            let nd = 3 * mesh.cell_nodes(c).len();
            d.extend_from_slice(&self.dofs.cell(c)[..nd]);
            o.push(d.len());
        }
        self.asm = Assembler::with_blocks(
            &self.dofs,
            vec![
                (self.dofs.cell_dofs.clone(), self.dofs.cell_offsets.clone()),
                (d, o),
            ],
        );
        self.contact = Some(RoadContact3D {
            surface,
            h_touch,
            disp,
            x_prev: self.x.clone(),
            lambda_prev: 0.0,
            dtau: 1.0,
            totals: ContactTotals3D::default(),
        });
        Ok(self)
    }

    fn volume(solid: &Solid3D) -> f64 {
        let mut v = 0.0;
        let (pts, ws) = crate::element::gauss_1d(2);
        for c in 0..solid.mesh.n_cells() {
            for (k, wk) in pts.iter().zip(&ws) {
                for (j, wj) in pts.iter().zip(&ws) {
                    for (i, wi) in pts.iter().zip(&ws) {
                        let (_, jac) = solid.mesh.map(c, [*i, *j, *k]);
                        v += jac.determinant() * wi * wj * wk;
                    }
                }
            }
        }
        v
    }

    /// The coefficients reached at load factor 1 ([`LoadedSystem::set_load`] scales them).
    pub fn set_target(&mut self, target: Coefficients) {
        self.target = target;
    }

    /// The floor of the displacement residual's convergence reference: a physical force scale
    /// of the problem (e.g. the centrifugal force ρ ω² Ro V).
    pub fn set_reference_force(&mut self, f: f64) {
        self.ref_norms[0] = f;
    }

    /// Why the last evaluation failed, if it did.
    pub fn inadmissible(&self) -> Option<Inadmissible> {
        self.inadmissible
    }

    /// Residual and tangent at the current state into the assembler; `false` if a cell was
    /// inadmissible.
    pub fn assemble(&mut self, with_matrix: bool) -> bool {
        let bad = AtomicBool::new(false);
        let why = std::sync::Mutex::new(None);
        let (solid, dofs, x, co) = (&self.solid, &self.dofs, &self.x, self.coefficients);
        self.asm.zero(with_matrix);
        self.asm.add_block_large(0, dofs, with_matrix, |c, r, k| {
            if let Err(e) = solid.cell(c, dofs, x, &co, r, k) {
                bad.store(true, Ordering::Relaxed);
                if let Ok(mut w) = why.lock() {
                    *w = Some(e);
                }
                r.fill(0.0);
                k.fill(0.0);
            }
        });
        self.inadmissible = why.into_inner().ok().flatten();
        if let Some(rc) = self.contact.as_mut() {
            let mesh = &solid.mesh;
            let totals = std::sync::Mutex::new(ContactTotals3D::default());
            let (surface, x_prev, dtau) = (&rc.surface, &rc.x_prev, rc.dtau);
            self.asm.add_block_large(1, dofs, with_matrix, |e, r, k| {
                let f = surface.facets[e];
                let cd = dofs.cell(f.cell as usize);
                let nd = r.len();
                let (mut ul, mut vl) = ([0.0; 81], [0.0; 81]);
                for i in 0..nd {
                    let g = cd[i] as usize;
                    ul[i] = x[g];
                    vl[i] = (x[g] - x_prev[g]) / dtau;
                }
                let m = CellMotion {
                    u: &ul[..nd],
                    v: &vl[..nd],
                    kx: 1.0,
                    kv: 1.0 / dtau,
                    damping: false,
                };
                let mut t = ContactTotals3D::default();
                let kb = if k.is_empty() { None } else { Some(k) };
                surface.facet_kernel(mesh, f, &m, r, kb, &mut t);
                if let Ok(mut all) = totals.lock() {
                    all.add(&t);
                }
            });
            rc.totals = totals.into_inner().unwrap_or_default();
        }
        !bad.load(Ordering::Relaxed)
    }

    /// The displacement of node `n`.
    pub fn node_displacement(&self, n: usize) -> [f64; 3] {
        [self.x[3 * n], self.x[3 * n + 1], self.x[3 * n + 2]]
    }
}

impl NonlinearSystem for Solid3DSystem {
    fn n_eq(&self) -> usize {
        self.dofs.n_eq
    }
    fn fields(&self) -> &[u8] {
        &self.dofs.field
    }
    fn field_names(&self) -> &'static [&'static str] {
        &["u", "p"]
    }
    fn reference_norms(&self) -> Vec<f64> {
        self.ref_norms.clone()
    }
    fn force_scale(&self) -> &[f64] {
        &self.asm.scale
    }
    fn state_magnitudes(&self, out: &mut Vec<f64>) {
        out.clear();
        out.resize(self.dofs.n_eq, 0.0);
        let n_u = self.dofs.n_u;
        for (d, &e) in self.dofs.eq.iter().enumerate() {
            if e >= CONSTRAINED {
                continue;
            }
            out[e as usize] = if d < n_u {
                let n = d / 3;
                (self.solid.mesh.nodes[n] + nalgebra::Vector3::from(self.node_displacement(n)))
                    .norm()
            } else {
                self.x[d].abs()
            };
        }
    }
    fn pattern(&self) -> (&[usize], &[usize]) {
        (&self.asm.col_ptr, &self.asm.row_idx)
    }
    fn evaluate(&mut self, with_matrix: bool) -> bool {
        self.assemble(with_matrix)
    }
    fn residual(&self) -> &[f64] {
        &self.asm.residual
    }
    fn matrix_values(&self) -> &[f64] {
        &self.asm.values
    }
    fn update(&mut self, alpha: f64, dx: &[f64]) {
        self.dofs.add_free(alpha, dx, &mut self.x);
    }
    fn save_state(&self, buf: &mut Vec<f64>) {
        buf.clear();
        buf.extend_from_slice(&self.x);
    }
    fn restore_state(&mut self, buf: &[f64]) {
        self.x.copy_from_slice(buf);
    }
}

impl LoadedSystem for Solid3DSystem {
    fn set_load(&mut self, lambda: f64) {
        self.coefficients = Coefficients {
            omega2: lambda * self.target.omega2,
            body_load: lambda * self.target.body_load,
        };
        if let Some(rc) = self.contact.as_mut() {
            rc.surface.h = rc.h_touch - lambda * rc.disp;
            rc.dtau = (lambda - rc.lambda_prev).max(f64::MIN_POSITIVE);
        }
    }
    fn commit(&mut self) {
        if let Some(rc) = self.contact.as_mut() {
            rc.x_prev.copy_from_slice(&self.x);
            rc.lambda_prev += rc.dtau;
        }
    }
}
