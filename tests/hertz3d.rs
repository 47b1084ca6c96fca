//! Hertz contact of a crowned wheel pressed lightly onto the rigid road (Johnson, Contact
//! Mechanics, 1985, §4.2): the semi-axes a, b of the elliptic contact and the peak pressure p0
//! of the 3D finite-element solution (Hex27, compressible neo-Hookean, frictionless normal
//! compliance, displacement control) against the Hertz solution for the computed load, on a
//! sequence of graded meshes, for the crown radii R_c = Ro (circular contact) and R_c = Ro/2.
//!
//! The reference (tests/common/hertz.rs, std only, checked against scipy in tests/contact3d.rs)
//! takes the two principal radii of relative curvature, Ro along the road x1 and R_c along the
//! axle x3, against a plane, and E* = E/(1 − ν²) of the material's small-strain E, ν (rigid
//! road).
//!
//! What bounds the error against Hertz besides the discretisation:
//! * the wheel is not a half-space: a hub-bonded ring of radius Ro = 1, hub ri = 0.25 and
//!   half-width 0.3 (12 contact radii to the free sides, 30 to the hub);
//!   the far boundaries change the pressure by a relative amount of order (a/L)², L the
//!   distance to them, and a rigid motion of the contact region changes nothing;
//! * the body is a paraboloid only to O((a/R)²) (torus against its osculating paraboloid);
//! * the response is not linear: strains are of order p0/E ≈ 1.7 %; the load is per
//!   reference area and the surface stretches by a comparable relative amount, so p0 (per
//!   reference area) carries an O(p0/E) bias while a, b (moments of the force density) do
//!   not;
//! * the normal compliance adds a penetration t_n/c_n to the gap, a fraction of the Hertz
//!   approach δ_H that the test prints and bounds.
//!
//! Measured quantities: a, b from the second moments of the contact force density
//! ([`semi_axes`]), p0 as the least-squares projection of the computed pressure on the Hertz
//! profile of those semi-axes. The pointwise penalty pressure of the Q2 facets oscillates
//! (largest over the Gauss points and at the corner node under the centre, printed for the
//! record, are off by tens of per cent); the integral measures converge.
//!
//! The wheel is symmetric about its mid-plane x3 = 0: half the width is meshed
//! (`RevolvedSpec::half_width`), with u3 = 0 on the symmetry plane. Meshes are graded
//! geometrically toward the contact in all three directions (`grading_r`, `theta_ratio`,
//! `grading_z`). Print the refinement table with `--nocapture`.

include!("common/hertz.rs");

use nalgebra::Vector2;
use std::time::Instant;
use tread::contact::facet::FacetRule;
use tread::contact::facet3d::{ContactSample3D, ContactSurface3D, Kinematics3D};
use tread::contact::laws::{Friction, NormalCompliance};
use tread::material::MaterialKind;
use tread::mesh::revolved::{revolved, RevolvedSpec};
use tread::model::{Solid3D, Solid3DSystem};
use tread::physics::PressureMode;
use tread::solver::observe::NoObserver;
use tread::solver::stepping::{solve_load_steps, StepOptions, StepReport};
use tread::solver::{LinearKind, Newton, NewtonOptions, NonlinearSystem};

const RI: f64 = 0.25;
const RO: f64 = 1.0;
/// Half-width of the wheel.
const HALF_W: f64 = 0.3;
/// Lamé constants of the small-strain limit: ν = λ/(2(λ + μ)) = 0.3.
const MU: f64 = 1.0;
const LAMBDA: f64 = 1.5;
/// Normal compliance t_n = C_N δ (linear penalty).
const C_N: f64 = 2.0e4;

/// Small-strain Young's modulus and Poisson's ratio of the Lamé constants.
fn young_poisson() -> (f64, f64) {
    let e = MU * (3.0 * LAMBDA + 2.0 * MU) / (LAMBDA + MU);
    (e, LAMBDA / (2.0 * (LAMBDA + MU)))
}

/// A graded mesh: the smallest cells (size `h0`) at the bottom of the mid-plane, growing
/// geometrically by at most `q` per cell in every direction (radially toward the hub,
/// circumferentially toward the top, axially toward the side).
#[derive(Clone, Copy, Debug)]
struct Level {
    h0: f64,
    q: f64,
}

/// Number of cells n and growth factor g ≤ `q` of the geometric sequence of first cell `h0`
/// that covers `len` exactly: h0 (gⁿ − 1)/(g − 1) = len.
fn geometric(len: f64, h0: f64, q: f64) -> (usize, f64) {
    let n = ((1.0 + len * (q - 1.0) / h0).ln() / q.ln()).ceil().max(1.0) as usize;
    let cover = |g: f64| h0 * (0..n).map(|k| g.powi(k as i32)).sum::<f64>() - len;
    let (mut lo, mut hi) = (1.0, q);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if cover(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (n, 0.5 * (lo + hi))
}

fn spec(level: Level, crown: f64) -> RevolvedSpec {
    let Level { h0, q } = level;
    // θ: each half circle (arc π Ro) from the bottom to the top.
    let (m, gt) = geometric(std::f64::consts::PI * RO, h0, q);
    let (n_r, gr) = geometric(RO - RI, h0, q);
    let (n_z, gz) = geometric(HALF_W, h0, q);
    RevolvedSpec {
        ri: RI,
        ro: RO,
        width: 2.0 * HALF_W,
        n_r,
        n_z,
        n_theta: 2 * m,
        degree: 2,
        // The radial cells shrink toward the outer surface.
        grading_r: gr.powi(1 - n_r as i32),
        grading_theta: 0.0,
        theta_ratio: gt.powi(m as i32 - 1),
        grading_z: gz.powi(n_z as i32 - 1),
        half_width: true,
        crown_radius: Some(crown),
    }
}

/// What one solve measured.
#[derive(Clone, Copy, Debug)]
struct Measured {
    /// Total load (both halves).
    load: f64,
    /// Semi-axes along x1 and x3 from the second moments of the pressure.
    a1: f64,
    a3: f64,
    /// Largest pressure at the Gauss points and at the node under the centre.
    p_gauss: f64,
    p_node: f64,
    p_fit: f64,
    max_penetration: f64,
    dofs: usize,
    cells: usize,
    seconds: f64,
    iterations: usize,
}

/// Second moments of the force density: for p = p0 sqrt(1 − x²/a² − y²/b²) on the ellipse,
/// with x = a ρ cos φ, y = b ρ sin φ (dA = a b ρ dρ dφ),
/// ∫p dA = 2π a b p0 ∫₀¹ sqrt(1 − ρ²) ρ dρ = 2π a b p0 / 3 and
/// ∫p x² dA = a³ b p0 ∫ cos²φ dφ ∫₀¹ ρ³ sqrt(1 − ρ²) dρ = π a³ b p0 · 2/15, so
/// ∫p x² / ∫p = a²/5 (and b²/5 for y). The force density t_n dA0 (per reference area times
/// the reference area) at the current positions is the force element p dA whatever the
/// surface stretch. On the half model x3 ≥ 0 the ratio is the same by symmetry; x1 is
/// measured from the centroid of the force.
fn semi_axes(samples: &[ContactSample3D]) -> (f64, f64) {
    let (mut f, mut f1, mut f11, mut f33) = (0.0, 0.0, 0.0, 0.0);
    for s in samples.iter().filter(|s| s.p > 0.0) {
        let w = s.p * s.da0;
        f += w;
        f1 += w * s.x1;
        f11 += w * s.x1 * s.x1;
        f33 += w * s.x3 * s.x3;
    }
    let c1 = f1 / f;
    ((5.0 * (f11 / f - c1 * c1)).sqrt(), (5.0 * f33 / f).sqrt())
}

fn solve(level: Level, crown: f64, disp: f64) -> Measured {
    let t0 = Instant::now();
    let s = spec(level, crown);
    let mesh = revolved(&s).expect("valid mesh");
    let cells = mesh.n_cells();
    let mut fixed = vec![false; 3 * mesh.n_nodes()];
    for &n in mesh.node_set("hub") {
        fixed[3 * n as usize..3 * n as usize + 3].fill(true);
    }
    for &n in mesh.node_set("mid") {
        fixed[3 * n as usize + 2] = true;
    }
    let normal = NormalCompliance::new(C_N, 1.0, 0.0, 0.0);
    let surface = ContactSurface3D::new(
        mesh.facet_set("outer").to_vec(),
        RO,
        Vector2::zeros(),
        normal,
        Friction::None,
        FacetRule::Gauss(3),
    )
    .expect("contact surface");
    let material = MaterialKind::NeoHookean.build(&[MU, LAMBDA]);
    let mut sys = Solid3DSystem::new(
        Solid3D::new(mesh, material, 1.0, PressureMode::None),
        &fixed,
    )
    .with_contact(surface, RO, disp)
    .expect("contact on the mesh");
    let (e, nu) = young_poisson();
    // Force scale: the Hertz load of a circular contact of radius 0.02 Ro.
    sys.set_reference_force(4.0 / 3.0 * e / (1.0 - nu * nu) * 0.02f64.powi(3) * RO * RO);
    let opts = NewtonOptions {
        tol: 1e-6,
        max_iterations: 30,
        ..Default::default()
    };
    let mut newton = Newton::new(&sys, LinearKind::Cholesky, opts).expect("analysis");
    let mut rep = StepReport::default();
    let steps = StepOptions {
        initial_steps: 1,
        max_cutbacks: 6,
        verbose: false,
    };
    solve_load_steps(&mut sys, &mut newton, &steps, &mut rep, &mut NoObserver)
        .expect("indentation converges");
    assert!(sys.evaluate(false), "admissible final state");
    let rc = sys.contact.as_ref().expect("contact");
    let n_u = sys.dofs.n_u;
    let u = &sys.x[..n_u];
    let kin = Kinematics3D::Static {
        u_prev: u,
        dtau: 1.0,
    };
    let samples = rc
        .surface
        .samples(&sys.solid.mesh, u, &kin)
        .expect("samples");
    let (a1, a3) = semi_axes(&samples);
    let p_gauss = samples.iter().map(|s| s.p).fold(0.0, f64::max);
    // The pressure at the node under the centre (θ = −π/2 on the mid-plane, a corner of the
    // mesh): C_N (−H − x2)_+ there.
    let centre = sys
        .solid
        .mesh
        .nodes
        .iter()
        .position(|x| x[0].abs() < 1e-12 && (x[1] + RO).abs() < 1e-12 && x[2] == 0.0)
        .expect("a node under the centre");
    let p_node = C_N * (-rc.surface.h + RO - sys.x[3 * centre + 1]).max(0.0);
    // Least-squares projection of the computed pressure (at the Gauss points, weights dA0) on
    // the Hertz profile p0 φ, φ = sqrt(1 − x1²/a1² − x3²/a3²)_+, of the measured semi-axes:
    // p0 = ∫ p φ / ∫ φ². The pointwise penalty pressure oscillates from one Gauss point to the
    // next in the cells the contact edge crosses (the largest value over the points, printed,
    // overshoots by tens of per cent), which the projection averages.
    let c1 = samples.iter().map(|s| s.p * s.da0 * s.x1).sum::<f64>()
        / samples.iter().map(|s| s.p * s.da0).sum::<f64>();
    let (mut pf, mut ff) = (0.0, 0.0);
    for s in &samples {
        let t = 1.0 - ((s.x1 - c1) / a1).powi(2) - (s.x3 / a3).powi(2);
        if t > 0.0 {
            pf += s.p * t.sqrt() * s.da0;
            ff += t * s.da0;
        }
    }
    let p_fit = pf / ff;
    Measured {
        load: 2.0 * rc.totals.force[1],
        a1,
        a3,
        p_gauss,
        p_node,
        p_fit,
        max_penetration: rc.totals.max_penetration,
        dofs: sys.dofs.n_eq,
        cells,
        seconds: t0.elapsed().as_secs_f64(),
        iterations: rep.total_iterations,
    }
}

#[test]
fn crowned_wheel_contact_is_the_hertz_ellipse() {
    let (e, nu) = young_poisson();
    let e_star = e / (1.0 - nu * nu);
    let levels = [
        Level { h0: 0.01, q: 2.3 },
        Level { h0: 0.005, q: 2.1 },
        Level { h0: 0.003, q: 2.1 },
    ];
    // Road displacement: about 1.5 δ_H of the circular case (the rest is the compliance of
    // the wheel between the hub and the contact region); a/R ≈ 0.025.
    let disp = 6.0e-4;
    for crown in [RO, 0.5 * RO] {
        println!("crown R_c = {crown}, E* = {e_star:.4}, c_n = {C_N:e}, disp = {disp:e}");
        println!(
            "{:>7} {:>5} {:>6} {:>7} {:>10} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>6} {:>4}",
            "h0",
            "q",
            "cells",
            "dofs",
            "P",
            "a/R",
            "err a",
            "err b",
            "p0 gp",
            "p0 node",
            "p0 fit",
            "pen/δH",
            "s",
            "it"
        );
        let mut worst = Vec::new();
        for &level in &levels {
            let m = solve(level, crown, disp);
            let h = hertz_ellipse(RO, crown, e_star, m.load);
            // a lies along the larger radius: x1 (Ro) for R_c ≤ Ro.
            let (ea, eb) = (m.a1 / h.a - 1.0, m.a3 / h.b - 1.0);
            let ep = m.p_fit / h.p0 - 1.0;
            println!(
                "{:>7.4} {:>5.2} {:>6} {:>7} {:>10.4e} {:>8.4} {:>+8.3}% {:>+8.3}% {:>+8.3}% {:>+8.3}% {:>+8.3}% {:>7.3}% {:>6.1} {:>4}",
                level.h0,
                level.q,
                m.cells,
                m.dofs,
                m.load,
                h.a / RO,
                100.0 * ea,
                100.0 * eb,
                100.0 * (m.p_gauss / h.p0 - 1.0),
                100.0 * (m.p_node / h.p0 - 1.0),
                100.0 * ep,
                100.0 * m.max_penetration / h.delta,
                m.seconds,
                m.iterations
            );
            assert!(h.a <= 0.05 * RO, "a/R = {} is not a light load", h.a / RO);
            // The penalty's own penetration is a small part of the Hertz approach.
            let pen = m.max_penetration / h.delta;
            assert!(pen < 0.01, "R_c = {crown}: penetration / δ_H = {pen}");
            worst.push(ea.abs().max(eb.abs()).max(ep.abs()));
            if level.h0 == levels[levels.len() - 1].h0 {
                for (err, what) in [(ea, "a"), (eb, "b"), (ep, "p0")] {
                    assert!(
                        err.abs() < 0.03,
                        "R_c = {crown}, finest mesh: {what} is {:+.2} % off Hertz",
                        100.0 * err
                    );
                }
            }
        }
        // Refinement: the finest mesh's worst error at most half the coarsest's.
        let (coarse, fine) = (worst[0], worst[worst.len() - 1]);
        assert!(
            fine <= 0.5 * coarse,
            "R_c = {crown}: worst error {fine:.3e} on the finest mesh, {coarse:.3e} on the coarsest"
        );
    }
}
