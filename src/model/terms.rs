//! What a driver supplies to the one assembly of the solid's residual and tangent
//! ([`crate::model::SolidSystem::assemble`]), and the per-cell evaluation that every assembly
//! and every hub-reaction sum shares.
//!
//! Every analysis solves R(x) = 0 with
//!
//! ```text
//! R = s · [ f_int(x, v) − ω² B(x) − f_body + f_contact(x, v) ] + M a
//! ```
//!
//! (per unit thickness, in the scene's force unit). The drivers differ only in what they
//! supply:
//!
//! | driver                 | rates `v`                                | s        | M a            |
//! |------------------------|------------------------------------------|----------|----------------|
//! | static, spinning       | [`Rates::Static`]: (x − x_prev)/Δτ, contact only | 1 | –          |
//! | steady (θ-referential) | [`Rates::Steady`]: ω ∂θχ of the state    | 1        | – (ω² B in f)  |
//! | transient integrators  | [`Rates::Dynamic`]: the velocity field, ∂v/∂x = kv | 1 − α_f etc. | [`Inertia`], ∂a/∂x = c_a |
//!
//! The force-averaged weights of the previous step and the hub-angle row of torque control
//! are the transient driver's own additions on top of this residual.

use crate::assembly::{DofMap, LocalSystem};
use crate::physics::SolidModel;

/// The rates of the motion, as the driver supplies them.
#[derive(Clone, Copy, Debug)]
pub enum Rates<'a> {
    /// Load stepping (static, spinning): no rate-dependent solid forces; friction sees the
    /// pseudo-velocity (x − x_prev)/Δτ of the load step in load-stepping time.
    Static,
    /// Steady rolling at the system's `steady_omega`: the velocity is v = ω ∂θχ of the state,
    /// for the strain-rate damping, the normal damping and the friction slip.
    Steady,
    /// Transient: the forces are evaluated at the configuration `x` with the velocity field
    /// `v` (full vectors, e.g. generalized-α's intermediate values); the unknown moves `x` by
    /// 1 and `v` by `kv` per unit change.
    Dynamic { x: &'a [f64], v: &'a [f64], kv: f64 },
}

/// Inertia M a with the cell mass matrices.
#[derive(Clone, Copy, Debug)]
pub struct Inertia<'a> {
    /// Scalar cell mass matrices ρ0 ∫ N_a N_b dV (n × n row-major per cell, n its node count)
    /// at `offsets[c]..offsets[c + 1]`.
    pub mass: &'a [f64],
    pub offsets: &'a [usize],
    /// Acceleration (full vector) and its derivative with respect to the unknown.
    pub acc: &'a [f64],
    pub ca: f64,
}

/// Called with each cell's finished local system (in the cell's dof order), e.g. to collect
/// the hub-torque projections of torque control. Runs inside the parallel assembly.
pub type CellHook<'a> = &'a (dyn Fn(&SolidModel, usize, &LocalSystem) + Sync);

/// The coefficients of one assembly.
#[derive(Clone, Copy)]
pub struct Terms<'a> {
    pub rates: Rates<'a>,
    /// Factor s on the static forces (internal and contact) and their tangent: 1, or a time
    /// integrator's weight (1 − α_f of force-averaged generalized-α).
    pub force_scale: f64,
    pub inertia: Option<Inertia<'a>>,
    pub cell_hook: Option<CellHook<'a>>,
}

impl Terms<'_> {
    /// Static forces only, at the given rates.
    pub fn forces(rates: Rates<'_>) -> Terms<'_> {
        Terms {
            rates,
            force_scale: 1.0,
            inertia: None,
            cell_hook: None,
        }
    }
}

/// The solid-rate part of one cell's evaluation.
#[derive(Clone, Copy)]
pub(crate) enum CellRate<'a> {
    /// No strain-rate damping (or none active).
    None,
    /// Independent velocity field, ∂v/∂x = kv.
    Dynamic { v: &'a [f64], kv: f64 },
    /// Nodal velocities ω ∂θχ (full vector) of the steady mode, linearised in the tangent with
    /// each cell's own θ-derivative (N × N at `local[local_off[c]..]`, N its nodes).
    Steady {
        vel: &'a [f64],
        omega: f64,
        local: &'a [f64],
        local_off: &'a [usize],
    },
}

/// The per-cell evaluation shared by every assembly and every hub-reaction sum: the solid's
/// forces at the rates, scaled by `force_scale`, plus the inertia rows.
pub(crate) struct CellForces<'a> {
    pub model: &'a SolidModel,
    pub dofs: &'a DofMap,
    pub x: &'a [f64],
    pub rate: CellRate<'a>,
    pub force_scale: f64,
    pub inertia: Option<Inertia<'a>>,
}

impl CellForces<'_> {
    /// Fill `loc` (already cleared to the cell's size) for cell `c`. With `av` (steady rates
    /// only), ∂r_c/∂v_c is written there.
    pub fn eval(&self, c: usize, loc: &mut LocalSystem, with_k: bool, av: Option<&mut [f64; 324]>) {
        let (model, dofs, x) = (self.model, self.dofs, self.x);
        match self.rate {
            CellRate::None => model.cell_system(c, dofs, x, loc, with_k),
            CellRate::Dynamic { v, kv } => {
                model.cell_system_viscous(c, dofs, x, v, kv, loc, with_k)
            }
            CellRate::Steady {
                vel,
                omega,
                local,
                local_off,
            } => {
                let nn = model.mesh.cell_nodes(c).len();
                let d = &local[local_off[c]..local_off[c] + nn * nn];
                model.cell_system_steady_viscous(c, dofs, x, vel, omega, d, loc, with_k, av);
            }
        }
        let nd = loc.nd;
        let fs = self.force_scale;
        if fs != 1.0 {
            loc.r[..nd].iter_mut().for_each(|v| *v *= fs);
            if with_k {
                loc.k[..nd * nd].iter_mut().for_each(|v| *v *= fs);
            }
        }
        let Some(inertia) = &self.inertia else {
            return;
        };
        let cd = dofs.cell(c);
        let m = &inertia.mass[inertia.offsets[c]..inertia.offsets[c + 1]];
        let nn = model.mesh.cell_nodes(c).len();
        for a in 0..nn {
            for b in 0..nn {
                let mab = m[a * nn + b];
                if mab == 0.0 {
                    continue;
                }
                for i in 0..2 {
                    loc.r[2 * a + i] += mab * inertia.acc[cd[2 * b + i] as usize];
                    if with_k {
                        loc.k[(2 * a + i) * nd + 2 * b + i] += inertia.ca * mab;
                    }
                }
            }
        }
    }
}
