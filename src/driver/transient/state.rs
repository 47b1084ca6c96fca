//! The state of the transient model at one instant.

/// Time, and the full vectors (displacement dofs, cell-owned pressures, global unknowns such as
/// the road height or the hub angle, in [`crate::assembly::DofMap`] order) of the unknowns, their
/// rates and their second rates.
///
/// A time step goes from the committed state ([`super::Transient::state`]) to a new one
/// ([`super::Transient::next`]): the integrator fills `next` (its Newton iterate is the model's
/// `sys.x`), and only once the step is accepted does `next` become the committed state, with
/// the quadrature-point history stored in the model ([`crate::physics::SolidModel::history`])
/// advanced in the same commit. A rejected step leaves the committed state and the history
/// untouched. The rigid-road contact has no history of its own in the transient mode (its
/// friction depends on the slip rate only).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct State {
    /// Time.
    pub t: f64,
    /// Unknowns (full vector).
    pub u: Vec<f64>,
    /// Their rates (velocities; zero for the quasi-static road height).
    pub v: Vec<f64>,
    /// Their second rates (accelerations).
    pub a: Vec<f64>,
}

impl State {
    /// At rest at time `t` in configuration `u`.
    pub fn at_rest(t: f64, u: Vec<f64>) -> Self {
        let n = u.len();
        Self {
            t,
            u,
            v: vec![0.0; n],
            a: vec![0.0; n],
        }
    }

    /// Number of entries of each full vector.
    pub fn len(&self) -> usize {
        self.u.len()
    }

    /// Whether the vectors are empty.
    pub fn is_empty(&self) -> bool {
        self.u.is_empty()
    }

    /// Append one unknown (a global unknown added after construction) at rest with value `u`.
    pub fn push(&mut self, u: f64) {
        self.u.push(u);
        self.v.push(0.0);
        self.a.push(0.0);
    }
}
