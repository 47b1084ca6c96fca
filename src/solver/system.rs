//! The interface every nonlinear problem gives the solvers: residual, tangent and its
//! pattern, and the optional matrix-free correction of the tangent.

/// A discretised nonlinear problem R(x) = 0 with a fixed sparse tangent pattern.
pub trait NonlinearSystem {
    fn n_eq(&self) -> usize;
    /// Field index of each equation (0 = displacement, 1 = pressure, ...).
    fn fields(&self) -> &[u8];
    fn field_names(&self) -> &'static [&'static str];
    /// Reference norms per field: floors of the convergence reference (see the module docs),
    /// for fields or states whose [`Self::force_scale`] vanishes. They must be physical force
    /// scales of the problem (a load, a weight), never estimates that grow with a penalty.
    fn reference_norms(&self) -> Vec<f64>;
    /// Per-equation force scale at the last evaluation, numbered like [`Self::residual`]:
    /// q_i = Σ_e |r_e,i|, the sum of the magnitudes of the element contributions to equation
    /// i. Empty (the default) when the system has none: the reference is then
    /// [`Self::reference_norms`] alone.
    fn force_scale(&self) -> &[f64] {
        &[]
    }
    /// Magnitudes m_j of the values the unknowns are added to, one per equation (numbering of
    /// [`Self::residual`]): the residual is computed from values of this size, so it is
    /// uncertain by about ε Σ_j |K_ij| m_j (its round-off floor), and a correction below
    /// ε m_j cannot be resolved. For a displacement that is the node's distance from the
    /// origin |X + u|, not |u|: a gap is computed from positions. Leave `out` empty (the
    /// default) for no round-off floor; the increment criterion then uses the saved state.
    fn state_magnitudes(&self, out: &mut Vec<f64>) {
        out.clear();
    }
    /// CSC pattern of the tangent (full, both triangles).
    fn pattern(&self) -> (&[usize], &[usize]);
    /// Evaluate the residual (and tangent values) at the current state. Returns `false` if the
    /// state is inadmissible (e.g. J ≤ 0 at a quadrature point).
    fn evaluate(&mut self, with_matrix: bool) -> bool;
    fn residual(&self) -> &[f64];
    fn matrix_values(&self) -> &[f64];
    /// state ← state + alpha · dx (dx in equation numbering).
    fn update(&mut self, alpha: f64, dx: &[f64]);
    fn save_state(&self, buf: &mut Vec<f64>);
    fn restore_state(&mut self, buf: &[f64]);
    /// Whether the exact tangent has a part that is not in [`Self::matrix_values`] (e.g. the
    /// ring coupling of a steady viscoelastic history), applied matrix-free by
    /// [`Self::tangent_correction`]. Newton then takes the exact step by GMRES preconditioned
    /// with the factorization of the assembled matrix ([`super::krylov`]).
    fn has_tangent_correction(&self) -> bool {
        false
    }
    /// `out += (K_exact − K_assembled) v` at the last evaluation (equation numbering).
    fn tangent_correction(&mut self, _v: &[f64], _out: &mut [f64]) {}
    /// Told when a GMRES solve with [`Self::tangent_correction`] did not reach its tolerance
    /// (the system may then offer another way to form its tangent).
    fn tangent_correction_stalled(&mut self) {}
}

/// The methods of [`NonlinearSystem`] for a wrapper that forwards all of them to its field
/// `$inner` (a system or a mutable reference to one): used inside the wrapper's `impl
/// NonlinearSystem` block, so that a wrapper that changes nothing of the system forwards every
/// method, the optional ones included.
macro_rules! delegate_nonlinear_system {
    ($inner:ident) => {
        fn n_eq(&self) -> usize {
            self.$inner.n_eq()
        }
        fn fields(&self) -> &[u8] {
            self.$inner.fields()
        }
        fn field_names(&self) -> &'static [&'static str] {
            self.$inner.field_names()
        }
        fn reference_norms(&self) -> Vec<f64> {
            self.$inner.reference_norms()
        }
        fn force_scale(&self) -> &[f64] {
            self.$inner.force_scale()
        }
        fn state_magnitudes(&self, out: &mut Vec<f64>) {
            self.$inner.state_magnitudes(out)
        }
        fn pattern(&self) -> (&[usize], &[usize]) {
            self.$inner.pattern()
        }
        fn evaluate(&mut self, with_matrix: bool) -> bool {
            self.$inner.evaluate(with_matrix)
        }
        fn residual(&self) -> &[f64] {
            self.$inner.residual()
        }
        fn matrix_values(&self) -> &[f64] {
            self.$inner.matrix_values()
        }
        fn update(&mut self, alpha: f64, dx: &[f64]) {
            self.$inner.update(alpha, dx)
        }
        fn save_state(&self, buf: &mut Vec<f64>) {
            self.$inner.save_state(buf)
        }
        fn restore_state(&mut self, buf: &[f64]) {
            self.$inner.restore_state(buf)
        }
        fn has_tangent_correction(&self) -> bool {
            self.$inner.has_tangent_correction()
        }
        fn tangent_correction(&mut self, v: &[f64], out: &mut [f64]) {
            self.$inner.tangent_correction(v, out)
        }
        fn tangent_correction_stalled(&mut self) {
            self.$inner.tangent_correction_stalled()
        }
    };
}
pub(crate) use delegate_nonlinear_system;
