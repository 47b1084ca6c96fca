//! Static indentation of the three-dimensional body under load control (the road height H a
//! global unknown with λ · load − ∫ t_n dA0 = 0): the global tangent against central
//! differences of the residual (Hex8 and Hex27, frictionless and with sliding friction), load
//! control against displacement control (the same force gives the same field), and the
//! plane-strain slab under load control against the 2D load-control indentation run here.

use tread::contact::facet3d::ContactSurface3D;
use tread::contact::laws::CoulombTanh;
use tread::contact::{FacetRule, Friction, NormalCompliance};
use tread::driver::indentation::{results as results_2d, solve_indentation};
use tread::driver::indentation3d::solve_indentation_3d;
use tread::io::Scene;
use tread::material::{Material, MaterialKind};
use tread::mesh::revolved::{revolved, RevolvedSpec};
use tread::model::{Solid3D, Solid3DSystem};
use tread::physics::PressureMode;
use tread::solver::observe::NoObserver;
use tread::solver::stepping::{LoadedSystem, StepOptions, StepReport};
use tread::solver::{LinearKind, NewtonOptions, NonlinearSystem};

const RI: f64 = 1.0;
const RO: f64 = 2.0;

fn spec(n_r: usize, n_z: usize, n_theta: usize, degree: usize, width: f64) -> RevolvedSpec {
    RevolvedSpec {
        ri: RI,
        ro: RO,
        width,
        n_r,
        n_z,
        n_theta,
        degree,
        grading_r: 1.0,
        grading_theta: 0.0,
        theta_ratio: 1.0,
        grading_z: 1.0,
        half_width: false,
        crown_radius: None,
    }
}

fn neo_hookean() -> Material {
    MaterialKind::NeoHookean.build(&[200.0, 1800.0])
}

/// Hub fixed in every component; with `slab`, u3 = 0 on both flat faces.
fn fixed(mesh: &tread::mesh::hex_mesh::HexMesh, slab: bool) -> Vec<bool> {
    let mut f = vec![false; 3 * mesh.n_nodes()];
    for &n in mesh.node_set("hub") {
        f[3 * n as usize..3 * n as usize + 3].fill(true);
    }
    if slab {
        for set in ["side_neg", "side_pos"] {
            for &n in mesh.node_set(set) {
                f[3 * n as usize + 2] = true;
            }
        }
    }
    f
}

fn surface(
    mesh: &tread::mesh::hex_mesh::HexMesh,
    c_n: f64,
    friction: Friction,
) -> ContactSurface3D {
    ContactSurface3D::new(
        mesh.facet_set("outer").to_vec(),
        RO,
        nalgebra::Vector2::zeros(),
        NormalCompliance::new(c_n, 1.0, 0.0, 0.0),
        friction,
        FacetRule::Gauss(3),
    )
    .expect("contact surface")
}

fn newton_opts() -> NewtonOptions {
    NewtonOptions {
        tol: 1e-12,
        max_iterations: 30,
        ..Default::default()
    }
}

fn steps(n: usize) -> StepOptions {
    StepOptions {
        initial_steps: n,
        max_cutbacks: 8,
        verbose: false,
    }
}

/// A deterministic pseudo-random sequence in [-1, 1].
fn noise(k: usize) -> f64 {
    let x = ((k as f64 + 1.0) * 12.9898).sin() * 43758.5453;
    2.0 * (x - x.floor()) - 1.0
}

/// Worst |K − K_fd| / max |K| of the load-control system at a perturbed state with the road
/// pressed 0.08 into the wheel; also the number of contact points and of those that slip
/// (|w| > ε, ε of the friction law; 0 without friction).
fn tangent_check(degree: usize, friction: Friction) -> (f64, usize, usize) {
    let mesh = revolved(&spec(1, 1, 8, degree, 0.4)).expect("mesh");
    let fx = fixed(&mesh, false);
    let s = surface(&mesh, 2.0e3, friction);
    let mut sys = Solid3DSystem::new(
        Solid3D::new(mesh, neo_hookean(), 1.0, PressureMode::None),
        &fx,
    )
    .with_contact_load(s, RO, RO - 0.08, 30.0)
    .expect("contact on the mesh");
    // λ = 0.7 of the load, the slip measured over a step of length 0.7 from the undeformed
    // state: the perturbation below moves the facet nodes by up to 0.03, |w| up to 0.04.
    sys.set_load(0.7);
    let n = sys.n_eq();
    let dx: Vec<f64> = (0..n).map(|k| 0.03 * noise(k)).collect();
    sys.update(1.0, &dx);
    assert!(sys.evaluate(true));
    let samples = sys.contact_samples().expect("samples");
    let eps = friction.eps().unwrap_or(f64::INFINITY);
    let in_contact = samples.iter().filter(|p| p.p > 0.0).count();
    let slipping = samples
        .iter()
        .filter(|p| p.p > 0.0 && p.w1.hypot(p.w3) > eps)
        .count();
    let dense = sys.asm.to_dense();
    let scale = dense.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let h = 1e-6;
    let mut e = vec![0.0; n];
    let mut worst: f64 = 0.0;
    for j in 0..n {
        e[j] = 1.0;
        sys.update(h, &e);
        assert!(sys.evaluate(false));
        let rp = sys.residual().to_vec();
        sys.update(-2.0 * h, &e);
        assert!(sys.evaluate(false));
        let rm = sys.residual().to_vec();
        sys.update(h, &e);
        e[j] = 0.0;
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            worst = worst.max((fd - dense[i][j]).abs() / scale);
        }
    }
    // The road-height row and column are in the matrix (not only zeros).
    let ih = n - 1;
    assert!(dense[ih][ih].abs() > 0.0 && dense[ih].iter().filter(|v| **v != 0.0).count() > 1);
    (worst, in_contact, slipping)
}

#[test]
fn load_control_tangent_matches_central_differences() {
    let tanh = Friction::CoulombTanh(CoulombTanh::new(0.3, 0.01));
    for (name, degree, friction) in [
        ("Hex8 frictionless", 1, Friction::None),
        ("Hex27 frictionless", 2, Friction::None),
        ("Hex8 Coulomb tanh", 1, tanh),
        ("Hex27 Coulomb tanh", 2, tanh),
    ] {
        let (err, contact, slip) = tangent_check(degree, friction);
        eprintln!(
            "{name}: worst |K − K_fd| / max|K| = {err:.2e}; {contact} contact points, {slip} slipping (|w| > ε)"
        );
        assert!(contact >= 4, "{name}: only {contact} contact points");
        if friction.is_active() {
            assert!(
                slip >= contact / 2,
                "{name}: {slip} of {contact} points slip"
            );
        }
        assert!(err < 1e-6, "{name}: tangent error {err:.3e}");
    }
}

/// Solve a wheel (free sides) pressed onto the road: load control with `load`, or
/// displacement control with `disp`.
fn pressed(load: Option<f64>, disp: f64) -> Solid3DSystem {
    let mesh = revolved(&spec(2, 2, 24, 2, 0.3)).expect("mesh");
    let fx = fixed(&mesh, false);
    let s = surface(&mesh, 2.0e4, Friction::None);
    let sys = Solid3DSystem::new(
        Solid3D::new(mesh, neo_hookean(), 1.0, PressureMode::None),
        &fx,
    );
    let mut sys = match load {
        Some(p) => sys.with_contact_load(s, RO, RO * (1.0 - 1e-3), p),
        None => sys.with_contact(s, RO, disp),
    }
    .expect("contact on the mesh");
    let mut rep = StepReport::default();
    solve_indentation_3d(
        &mut sys,
        LinearKind::Cholesky,
        newton_opts(),
        &steps(4),
        &mut rep,
        &mut NoObserver,
    )
    .expect("indentation converges");
    sys
}

#[test]
fn load_control_and_displacement_control_agree() {
    let load = 6.0;
    let sl = pressed(Some(load), 0.0);
    let h = sl.road_height().expect("road height");
    let fl = sl.contact.as_ref().expect("contact").totals.force;
    assert!(
        (fl[1] - load).abs() <= 1e-9 * load,
        "load control: contact force {} for load {load}",
        fl[1]
    );
    // Displacement control to the road height load control found.
    let sd = pressed(None, RO - h);
    let fd = sd.contact.as_ref().expect("contact").totals.force;
    let n_u = sl.dofs.n_u;
    let umax = sl.x[..n_u].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let du = sl.x[..n_u]
        .iter()
        .zip(&sd.x[..n_u])
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    eprintln!(
        "H = {h:.12}: contact force load control {:.12e}, displacement control {:.12e}; max |Δu| / max |u| = {:.2e}",
        fl[1],
        fd[1],
        du / umax
    );
    assert!(
        (fd[1] - load).abs() <= 1e-8 * load,
        "displacement control force {} vs load {load}",
        fd[1]
    );
    assert!(du / umax < 1e-8, "fields differ: {:.3e}", du / umax);
}

/// The scene of the plane-strain load-control indentation (or, with `three_d`, its slab of
/// width `width` with sliding sides and the load times the width).
fn slab_scene(three_d: Option<f64>, load_per_width: f64) -> Scene {
    let (mesh3, load) = match three_d {
        Some(w) => (
            format!("dimension = 3\nwidth = {w}\nn_z = 1\nsides = \"sliding\"\n"),
            load_per_width * w,
        ),
        None => (String::new(), load_per_width),
    };
    let text = format!(
        r#"
[scene]
name = "slab"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
{mesh3}n_r = 3
n_theta = 32
order = 2
grading_theta = 0.6
[material]
model = "mooney_rivlin"
c1 = 80.0
c2 = 20.0
kappa = 2000.0
rho = 0.027
[analysis]
mode = "static"
[road]
load = {load}
[contact]
c_n = 2.0e4
quadrature = "gauss"
points = 4
[friction]
law = "none"
[solver]
tolerance = 1e-12
load_steps = 4
"#
    );
    Scene::from_toml_str(&text, "slab", &[]).expect("valid scene")
}

#[test]
fn sliding_slab_under_load_control_equals_the_2d_indentation() {
    let (p, width) = (80.0, 0.25);
    // 2D: the plane-strain program from its scene.
    let sc2 = slab_scene(None, p);
    let mut s2 = tread::app::build_system(&sc2).expect("2D system");
    s2.loading = tread::setup::scene_loading(&sc2);
    let kind = tread::setup::linear_kind(&sc2, &s2);
    let (newton, step) = tread::setup::solver_options(&sc2, false);
    let mut rep = StepReport::default();
    solve_indentation(&mut s2, kind, newton, &step, &mut rep, &mut ()).expect("2D converges");
    let r2 = results_2d(&s2, RO);
    // 3D: the slab from its scene (the same (r, θ) mesh, isoparametric cells both).
    let sc3 = slab_scene(Some(width), p);
    let mut s3 = tread::setup::build_system_3d(&sc3).expect("3D system");
    let kind = tread::setup::linear_kind_3d(&sc3, &s3);
    let (newton, step) = tread::setup::solver_options(&sc3, false);
    let mut rep3 = StepReport::default();
    solve_indentation_3d(&mut s3, kind, newton, &step, &mut rep3, &mut NoObserver)
        .expect("3D converges");
    let f3 = s3.contact.as_ref().expect("contact").totals.force;
    let h3 = s3.road_height().expect("road height");
    let (fy2, fy3) = (r2.contact_force_y, f3[1] / width);
    eprintln!(
        "load control: road height 2D {:.14}, 3D {h3:.14}; contact force per width 2D {fy2:.12e}, 3D {fy3:.12e}",
        r2.road_height
    );
    assert!((fy2 - p).abs() <= 1e-9 * p, "2D force {fy2} vs load {p}");
    assert!(
        (fy3 - fy2).abs() <= 1e-8 * fy2.abs(),
        "3D {fy3} vs 2D {fy2}"
    );
    let pen = RO - r2.road_height;
    assert!(
        (h3 - r2.road_height).abs() <= 1e-8 * pen,
        "road height 3D {h3} vs 2D {}",
        r2.road_height
    );
    let key = |x: f64, y: f64| ((x * 1e9).round() as i64, (y * 1e9).round() as i64);
    let index: std::collections::HashMap<_, _> = s2
        .model
        .mesh
        .nodes
        .iter()
        .enumerate()
        .map(|(i, x)| (key(x[0], x[1]), i))
        .collect();
    let umax = (0..s2.model.mesh.n_nodes())
        .map(|n| s2.x[2 * n].hypot(s2.x[2 * n + 1]))
        .fold(0.0f64, f64::max);
    let mut worst: f64 = 0.0;
    for (n, x) in s3.solid.mesh.nodes.iter().enumerate() {
        let i = index[&key(x[0], x[1])];
        let u = s3.node_displacement(n);
        worst = worst
            .max((u[0] - s2.x[2 * i]).abs())
            .max((u[1] - s2.x[2 * i + 1]).abs())
            .max(u[2].abs());
    }
    eprintln!(
        "load-control slab: max |u_3D − u_2D| / max|u| = {:.2e}",
        worst / umax
    );
    assert!(
        worst / umax < 1e-8,
        "slab field differs: {:.3e}",
        worst / umax
    );
}
