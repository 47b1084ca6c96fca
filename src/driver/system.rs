//! [`SolidSystem`]: a [`SolidModel`] with its dofs, assembler and state, exposed to Newton as a
//! [`NonlinearSystem`]. The hub node set is bonded to the rigid hub (u = 0 there); the load
//! factor λ scales ω² (steady spinning) so that ω is reached by load stepping.

use crate::assembly::{Assembler, DofMap};
use crate::physics::SolidModel;
use crate::solver::stepping::LoadedSystem;
use crate::solver::NonlinearSystem;

pub struct SolidSystem {
    pub model: SolidModel,
    pub dofs: DofMap,
    pub asm: Assembler,
    /// Full state vector (displacements, then cell pressures).
    pub x: Vec<f64>,
    /// Target ω² reached at λ = 1.
    pub omega2_target: f64,
    ref_norms: Vec<f64>,
}

impl SolidSystem {
    /// Fix the nodes of `fixed_set` (both components, value 0 unless changed in `x`).
    pub fn new(model: SolidModel, fixed_set: &str) -> Self {
        let fixed: Vec<u32> = model.mesh.node_set(fixed_set).to_vec();
        Self::with_fixed_nodes(model, &fixed)
    }

    /// Fix both displacement components of the given nodes (values taken from `x`, initially 0).
    pub fn with_fixed_nodes(model: SolidModel, fixed: &[u32]) -> Self {
        let fixed = fixed.to_vec();
        let dofs = DofMap::new(&model.mesh, model.dofs_per_cell(), &fixed);
        let asm = Assembler::new(&model.mesh, &dofs);
        let x = model.initial_state(&dofs);
        // Pressure residuals are volumes (∫ (J − 1) q dV): their floor is the volume scale.
        let area = domain_area(&model);
        Self {
            model,
            dofs,
            asm,
            x,
            omega2_target: 0.0,
            ref_norms: vec![0.0, 1e-3 * area],
        }
    }

    /// Number of equations (free dofs).
    pub fn n_dofs(&self) -> usize {
        self.dofs.n_eq
    }

    /// Set the reference norm of the displacement residual (e.g. the norm of the full load).
    pub fn set_reference_force(&mut self, f: f64) {
        self.ref_norms[0] = f;
    }

    /// Norm of the residual at the current state (assembles the residual only).
    pub fn residual_norm(&mut self) -> f64 {
        self.model
            .assemble(&mut self.asm, &self.dofs, &self.x, false);
        self.asm.residual.iter().map(|r| r * r).sum::<f64>().sqrt()
    }
}

/// Area of the reference domain (quadrature of det J).
pub fn domain_area(model: &SolidModel) -> f64 {
    let rule = crate::element::QuadRule::gauss_2d(3);
    let mut a = 0.0;
    for c in 0..model.mesh.n_cells() {
        for (pt, w) in rule.points.iter().zip(&rule.weights) {
            if let Some(pv) = model.point_values_geometry(c, pt.0, pt.1) {
                a += pv.determinant() * w;
            }
        }
    }
    a
}

impl NonlinearSystem for SolidSystem {
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
    fn pattern(&self) -> (&[usize], &[usize]) {
        (&self.asm.col_ptr, &self.asm.row_idx)
    }
    fn evaluate(&mut self, with_matrix: bool) -> bool {
        let ok = self
            .model
            .assemble(&mut self.asm, &self.dofs, &self.x, with_matrix);
        ok && self.asm.residual.iter().all(|r| r.is_finite())
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

impl LoadedSystem for SolidSystem {
    fn set_load(&mut self, lambda: f64) {
        self.model.omega2 = lambda * self.omega2_target;
    }
}
