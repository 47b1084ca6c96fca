//! Static indentation: the road raised into the cylinder (displacement control, H = Ro − λ·DISP)
//! or the cylinder pressed onto the road by a hub load (load control, H unknown), by load
//! stepping in λ with cut-back. No inertia (ω = 0).
//!
//! Results: the force and moment the hub exerts on the body (`hub_force_x`, `hub_force_y`,
//! `hub_torque`; an indented cylinder has hub_force_y < 0: the hub pushes it down), the contact
//! patch extent in x1 (`contact_x_min`, `contact_x_max`: the outermost facet quadrature points
//! with t_n > 0), the peak normal traction (`max_pressure`, per unit reference length), the
//! final road height and penetration DISP = Ro − H.

use crate::contact::ContactModel;
use crate::io::record::Recorder;
use crate::model::system::{Loading, SolidSystem};
use crate::solver::stepping::{solve_load_steps, StepOptions, StepReport};
use crate::solver::{LinearKind, Newton, NewtonOptions, SolveError};

#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct IndentationResults {
    pub hub_force_x: f64,
    pub hub_force_y: f64,
    pub hub_torque: f64,
    pub contact_x_min: f64,
    pub contact_x_max: f64,
    pub max_pressure: f64,
    /// Resultant of the contact tractions on the body (x, y).
    pub contact_force_x: f64,
    pub contact_force_y: f64,
    /// Hertz-type half-width from the pressure's second moment: a = 2 √⟨(x1 − x̄)²⟩.
    pub contact_half_width_moment: f64,
    pub road_height: f64,
    pub penetration: f64,
    /// Mean number of contact facets integrated per assembly.
    pub contact_facets_per_iteration: f64,
    pub contact_facets_total: usize,
}

/// Solve the static indentation to λ = 1. `ro`: outer radius (for the road position).
pub fn solve_indentation(
    sys: &mut SolidSystem,
    kind: LinearKind,
    newton_opts: NewtonOptions,
    step_opts: &StepOptions,
    report: &mut StepReport,
    rec: &mut dyn Recorder,
) -> Result<(), SolveError> {
    // Floor of the convergence reference: the hub load, or the penalty/body force scale for
    // displacement control (h_touch = Ro).
    let ro = match sys.loading {
        Loading::Indent { h_touch, .. } => h_touch,
        _ => 0.0,
    };
    sys.set_reference_force(sys.contact_force_scale(ro));
    let mut newton = Newton::new(sys, kind, newton_opts)?;
    solve_load_steps(sys, &mut newton, step_opts, report, rec)
}

pub fn results(sys: &SolidSystem, ro: f64) -> IndentationResults {
    let samples = sys.contact_samples();
    let t = ContactModel::totals(&samples);
    let (f, m) = sys.hub_reaction();
    let h = sys.road_height().unwrap_or(f64::NAN);
    IndentationResults {
        hub_force_x: f[0],
        hub_force_y: f[1],
        hub_torque: m,
        contact_x_min: t.x_min,
        contact_x_max: t.x_max,
        max_pressure: t.max_pressure,
        contact_force_x: t.force_x,
        contact_force_y: t.force_y,
        contact_half_width_moment: 2.0 * t.pressure_second_moment.sqrt(),
        road_height: h,
        penetration: ro - h,
        contact_facets_per_iteration: sys.mean_facets_per_assembly(),
        contact_facets_total: sys.contact.as_ref().map_or(0, |c| c.facets.len()),
    }
}
