//! The energy account of the viscous overstress over a viscoelastic transient run.

use serde::Serialize;

/// Energy of the viscous overstress over a viscoelastic transient run, per unit thickness in
/// the scene's energy unit, counted from the start of time stepping. The overstress power
/// `S_v : Ė` is the rate of the energy its internal variables store plus a dissipation, which
/// every physical model keeps non-negative (for the convolution model: its Prony terms are
/// Maxwell elements in the Green strain; for the multiplicative model: its dissipation
/// inequality). A negative cumulative dissipation means the overstress created energy.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ViscousEnergy {
    /// Work of the overstress `∫∫ S_v : Ė dV dt` (trapezoidal in time).
    pub work: f64,
    /// Energy stored in the internal variables at the end.
    pub stored: f64,
    /// Dissipated energy: work − (stored at the end − stored at the start).
    pub dissipated: f64,
    /// Lowest cumulative dissipation at the end of any step, and the time it was reached.
    pub min_dissipated: f64,
    pub min_dissipated_time: f64,
    /// Sum over the steps of |work of the step|: the scale of the balance.
    pub work_abs: f64,
    /// Whether the overstress created energy: `min_dissipated < −ENERGY_CREATED_TOL · work_abs`
    /// (the trapezoidal work is second-order accurate, and its leading dissipation error is
    /// itself non-negative).
    pub energy_created: bool,
    /// Stored energy at the start of the account.
    #[serde(skip)]
    stored0: f64,
}

/// Relative tolerance of [`ViscousEnergy::energy_created`].
pub const ENERGY_CREATED_TOL: f64 = 1e-6;

impl ViscousEnergy {
    /// An account starting with `stored` in the internal variables at time `t`.
    pub fn start(stored: f64, t: f64) -> Self {
        Self {
            work: 0.0,
            stored,
            dissipated: 0.0,
            min_dissipated: 0.0,
            min_dissipated_time: t,
            work_abs: 0.0,
            energy_created: false,
            stored0: stored,
        }
    }

    /// Add one committed step ending at time `t` with the overstress work `work` and the stored
    /// energy `stored` at its end.
    pub fn add(&mut self, work: f64, stored: f64, t: f64) {
        self.work += work;
        self.work_abs += work.abs();
        self.stored = stored;
        self.dissipated = self.work - (stored - self.stored0);
        if self.dissipated < self.min_dissipated {
            self.min_dissipated = self.dissipated;
            self.min_dissipated_time = t;
        }
        self.energy_created = self.min_dissipated < -ENERGY_CREATED_TOL * self.work_abs;
    }
}
