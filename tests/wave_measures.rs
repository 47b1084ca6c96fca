//! The standing-wave measures of the steady branch (`wave_amplitude`, `wave_number` of
//! `branch.csv`) on displacement fields with a known pattern: a pure wave of number n on the
//! outer surface, the same under a large low-order (ovalisation) component and a contact
//! flattening at the bottom, and none at all (zero amplitude).

#[path = "common/fixtures.rs"]
mod fixtures;
use fixtures::*;

use std::f64::consts::{FRAC_PI_2, PI};
use tread::driver::steady_run::{wave_amplitude, wave_number};
use tread::driver::SolidSystem;

/// A system on the 3 × `n_theta` annulus whose radial displacement is `f(θ) · (r − 1)` (zero
/// at the hub, `f` at the outer surface).
fn with_radial(n_theta: usize, f: impl Fn(f64) -> f64) -> SolidSystem {
    let mut sys = SolidSystem::new(neo_hookean_annulus(3, n_theta), "hub");
    for (n, x) in sys.model.mesh.nodes.clone().iter().enumerate() {
        let (r, th) = (x.norm(), x[1].atan2(x[0]));
        let ur = f(th) * (r - 1.0);
        sys.x[2 * n] = ur * x[0] / r;
        sys.x[2 * n + 1] = ur * x[1] / r;
    }
    sys
}

#[test]
fn wave_number_and_amplitude_of_known_patterns() {
    for (n_theta, n) in [(64, 5), (64, 12), (128, 17), (128, 30)] {
        let amp = 2e-3;
        // The wave alone.
        let sys = with_radial(n_theta, |th| amp * (n as f64 * th + 0.4).cos());
        assert_eq!(wave_number(&sys), n as f64, "pure wave n = {n}");
        let a = wave_amplitude(&sys);
        assert!((a - amp).abs() < 0.05 * amp, "amplitude {a} of {amp}");
        // Under an ovalisation ten times larger and a flattening at the bottom (θ = −π/2).
        let sys = with_radial(n_theta, |th| {
            let d = (th + FRAC_PI_2).rem_euclid(2.0 * PI);
            let d = d.min(2.0 * PI - d);
            let flat = if d < 0.3 { -0.1 * (1.0 - d / 0.3) } else { 0.0 };
            amp * (n as f64 * th + 0.4).cos() + 10.0 * amp * (2.0 * th).cos() + flat
        });
        assert_eq!(wave_number(&sys), n as f64, "n = {n} under ovalisation");
    }
    // No displacement, no amplitude.
    let sys = with_radial(64, |_| 0.0);
    assert_eq!(wave_amplitude(&sys), 0.0);
}
