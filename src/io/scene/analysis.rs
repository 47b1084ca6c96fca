//! `[analysis]`: what to compute.

use serde::{Deserialize, Serialize};

keyword_enum! {
    /// What to compute (`[analysis] mode`).
    Mode, "analysis mode" {
        /// Steady spinning about the hub at `[motion] omega`, no contact: the centrifugal load
        /// `ρ ω² X` is ramped in `load_steps` steps of ω².
        Spinning => "spinning",
        /// Quasi-static indentation of the (non-spinning) cylinder onto the road (`[road]`,
        /// `[contact]`, optional `[friction]`), by load stepping in a pseudo-time τ ∈ [0, 1].
        Static => "static",
        /// The classical one-degree-of-freedom stick-slip oscillator (a mass on a spring, pressed
        /// onto a moving belt): `[stick_slip]` and `[friction]`; no finite elements.
        StickSlip => "stick_slip",
        /// The dynamic Lagrangian model (material mesh rotating with the body) integrated in time
        /// (`[time]`) until rolling is steady: the hub spins up to `[motion] omega`; with `[road]`
        /// and `[contact]` (optional, both or neither) the road rises and moves at `v0`, and
        /// `[friction]` may act. Without them: a cylinder spinning up in time, no contact.
        Transient => "transient",
        /// Steady rolling solved directly in the θ-referential (Eulerian/ALE) description: the
        /// same scene as `transient` (`[road]` and `[contact]` optional, both or neither; the
        /// ramps and `[time]` are ignored), at `[motion] omega` and `road.v0`, optionally
        /// followed by arc-length continuation (`[continuation]`).
        Steady => "steady",
    }
}

/// `[analysis]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Analysis {
    pub mode: Mode,
}
