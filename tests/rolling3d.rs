//! Steady rolling of the three-dimensional body in the θ-referential description
//! ([`tread::driver::steady3d`]): the global tangent against central differences of the
//! residual (Hex8 and Hex27, displacement and load control, friction with the slip from nodal
//! ring derivatives and facet-wise, normal damping, a slip angle, the strain-rate damping and
//! either viscoelastic model with its ring coupling), the plane-strain limit
//! (a slab with u3 = 0 on its faces reproduces the 2D steady mode, with damping and friction,
//! the strain-rate damping and either viscoelastic model,
//! the friction slip taken the same way in both, also under the free-rolling, creep and
//! torque controls), and the symmetry of the hub loads in the slip angle.

use tread::contact::facet3d::ContactSurface3D;
use tread::contact::laws::CoulombTanh;
use tread::contact::{ContactModel, FacetRule, Friction, NormalCompliance};
use tread::driver::steady3d::{apply_control_3d, solve_steady_3d};
use tread::driver::steady_run;
use tread::io::scene::Control;
use tread::io::Scene;
use tread::material::viscoelastic::ViscoModel;
use tread::material::{Material, MaterialKind, Viscoelastic};
use tread::mesh::revolved::{revolved, RevolvedSpec};
use tread::model::{Solid3D, Solid3DSystem};
use tread::physics::PressureMode;
use tread::solver::observe::NoObserver;
use tread::solver::stepping::{LoadedSystem, StepReport};
use tread::solver::NonlinearSystem;

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

/// A deterministic pseudo-random sequence in [-1, 1].
fn noise(k: usize) -> f64 {
    let x = ((k as f64 + 1.0) * 12.9898).sin() * 43758.5453;
    2.0 * (x - x.floor()) - 1.0
}

/// Worst |K − K_fd| / max |K| of the steady system (ω = 3, road at 0.99 ωRo turned by 3°,
/// damped normal compliance, tanh friction) at a perturbed state with the road 0.08 into the
/// wheel; also the contact points and those in the regularised stick zone (|w| < ε).
fn tangent_check(
    degree: usize,
    load: bool,
    facet_wise: bool,
    camber: f64,
    eta: f64,
    visco: Option<ViscoModel>,
) -> (f64, usize, usize) {
    let mesh = revolved(&spec(1, 1, 8, degree, 0.4)).expect("mesh");
    let mut fx = vec![false; 3 * mesh.n_nodes()];
    for &n in mesh.node_set("hub") {
        fx[3 * n as usize..3 * n as usize + 3].fill(true);
    }
    let omega = 3.0;
    let eps = 0.37;
    let mut s = ContactSurface3D::new(
        mesh.facet_set("outer").to_vec(),
        RO,
        nalgebra::Vector2::zeros(),
        NormalCompliance::new(2.0e3, 1.0, 40.0, 0.0),
        Friction::CoulombTanh(CoulombTanh::new(0.3, eps)),
        FacetRule::Gauss(3),
    )
    .expect("contact surface");
    s.set_camber(camber.to_radians()).expect("camber");
    let mut solid = Solid3D::new(mesh, neo_hookean(), 1.0, PressureMode::None);
    if let Some(model) = visco {
        // γ = 0.3 G, ω τ = 0.3 and 3.
        let ve = Viscoelastic::new(model, 60.0, &[(0.6, 0.1), (0.4, 1.0)]).expect("prony");
        solid.set_viscoelastic(ve);
    }
    let sys = Solid3DSystem::new(solid, &fx);
    let mut sys = if load {
        sys.with_contact_load(s, RO, RO - 0.08, 30.0)
    } else {
        sys.with_contact(s, RO, 0.08)
    }
    .expect("contact on the mesh");
    sys.set_steady_rolling(omega, 0.99 * omega * RO, 3f64.to_radians())
        .expect("steady");
    if facet_wise {
        sys.disable_steady_slip();
    }
    sys.enable_steady_viscosity(eta).expect("ring mesh");
    if visco.is_some() {
        sys.enable_steady_history().expect("rings of points");
    }
    sys.set_load(if load { 0.7 } else { 1.0 });
    let n = sys.n_eq();
    let dx: Vec<f64> = (0..n).map(|k| 0.02 * noise(k)).collect();
    sys.update(1.0, &dx);
    assert!(sys.evaluate(true));
    let samples = sys.contact_samples().expect("samples");
    let in_contact = samples.iter().filter(|p| p.p > 0.0).count();
    let sticking = samples
        .iter()
        .filter(|p| p.p > 0.0 && p.w1.hypot(p.w3) < eps)
        .count();
    let mut dense = sys.asm.to_dense();
    if visco.is_some() {
        // The ring coupling of the history, applied matrix-free, column by column.
        assert!(sys.has_tangent_correction());
        let mut col = vec![0.0; n];
        let mut unit = vec![0.0; n];
        for j in 0..n {
            unit[j] = 1.0;
            col.fill(0.0);
            sys.tangent_correction(&unit, &mut col);
            unit[j] = 0.0;
            for i in 0..n {
                dense[i][j] += col[i];
            }
        }
    }
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
    (worst, in_contact, sticking)
}

#[test]
fn steady_tangent_matches_central_differences() {
    for (name, degree, load, facet_wise) in [
        ("Hex8, displacement control", 1, false, false),
        ("Hex27, displacement control", 2, false, false),
        ("Hex8, load control", 1, true, false),
        ("Hex27, load control", 2, true, false),
        ("Hex27, load control, facet-wise slip", 2, true, true),
        ("Hex8, load control, camber 3°", 1, true, false),
        ("Hex27, displacement control, camber −3°", 2, false, false),
        (
            "Hex8, displacement control, strain-rate damping",
            1,
            false,
            false,
        ),
        ("Hex27, load control, strain-rate damping", 2, true, false),
        (
            "Hex27, displacement control, camber 3°, strain-rate damping",
            2,
            false,
            false,
        ),
        (
            "Hex8, load control, viscoelastic (multiplicative)",
            1,
            true,
            false,
        ),
        (
            "Hex27, displacement control, camber 3°, viscoelastic (multiplicative)",
            2,
            false,
            false,
        ),
        (
            "Hex27, load control, viscoelastic (convolution)",
            2,
            true,
            false,
        ),
    ] {
        let camber = if name.contains("camber 3") {
            3.0
        } else if name.contains("camber −3") {
            -3.0
        } else {
            0.0
        };
        // η ω / G = 0.3: the viscous stresses are of the elastic ones' order.
        let eta = if name.contains("strain-rate") {
            20.0
        } else {
            0.0
        };
        let visco = if name.contains("multiplicative") {
            Some(ViscoModel::Multiplicative)
        } else if name.contains("convolution") {
            Some(ViscoModel::Convolution)
        } else {
            None
        };
        let (err, contact, stick) = tangent_check(degree, load, facet_wise, camber, eta, visco);
        eprintln!(
            "{name}: worst |K − K_fd| / max|K| = {err:.2e}; {contact} contact points, {stick} with |w| < ε"
        );
        assert!(contact >= 4, "{name}: only {contact} contact points");
        assert!(
            stick >= 1 && stick < contact,
            "{name}: {stick} of {contact} in the regularised zone"
        );
        assert!(err < 1e-6, "{name}: tangent error {err:.3e}");
    }
}

/// The plane-strain steady scene (or, with `width`, its slab with sliding sides), rolling at
/// ω = 10 on the road at `v0`, with damping `b_n` and the friction table `friction`.
fn slab_scene(width: Option<f64>, v0: f64, b_n: f64, friction: &str, alpha: f64) -> Scene {
    slab_scene_with(width, v0, b_n, friction, alpha, "")
}

/// [`slab_scene`] with the tables `extra` appended.
fn slab_scene_with(
    width: Option<f64>,
    v0: f64,
    b_n: f64,
    friction: &str,
    alpha: f64,
    extra: &str,
) -> Scene {
    let mesh3 = match width {
        Some(w) => format!("dimension = 3\nwidth = {w}\nn_z = 1\nsides = \"sliding\"\n"),
        None => String::new(),
    };
    let slip = if alpha != 0.0 {
        format!("slip_angle = {alpha}\n")
    } else {
        String::new()
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
n_theta = 48
order = 2
grading_theta = 0.6
[material]
model = "mooney_rivlin"
c1 = 80.0
c2 = 20.0
kappa = 2000.0
rho = 0.027
[analysis]
mode = "steady"
[motion]
omega = 10.0
[road]
disp = 0.05
v0 = {v0}
{slip}[contact]
c_n = 2.0e4
b_n = {b_n}
quadrature = "gauss"
points = 4
[friction]
{friction}
[solver]
tolerance = 1e-11
load_steps = 4
linear = "lu"
{extra}"#
    );
    Scene::from_toml_str(&text, "slab", &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// The 2D steady state of the scene, the friction slip from nodal θ-derivatives (the
/// default) or facet-wise.
fn steady_2d(
    sc: &Scene,
    facet_wise: bool,
) -> (tread::driver::steady::SteadyRolling, ContactModelTotals) {
    let mut st = steady_run::build_steady(sc).unwrap_or_else(|e| panic!("{e}"));
    if facet_wise {
        st.sys.disable_steady_slip();
    }
    let mut rep = StepReport::default();
    steady_run::solve_steady(sc, &mut st, false, &mut rep, &mut ())
        .unwrap_or_else(|e| panic!("2D steady: {}", e.error));
    let t = ContactModel::totals(&st.sys.contact_samples());
    (st, (t.force_x, t.force_y, t.moment))
}

type ContactModelTotals = (f64, f64, f64);

fn steady_3d(sc: &Scene, facet_wise: bool) -> Solid3DSystem {
    let mut s3 = tread::setup::build_system_3d(sc).unwrap_or_else(|e| panic!("{e}"));
    if facet_wise {
        s3.disable_steady_slip();
    }
    let kind = tread::setup::linear_kind_3d(sc, &s3);
    let (newton, step) = tread::setup::solver_options(sc, false);
    let mut rep = StepReport::default();
    solve_steady_3d(&mut s3, kind, newton, &step, &mut rep, &mut NoObserver)
        .unwrap_or_else(|e| panic!("3D steady: {e}"));
    s3
}

#[test]
fn plane_strain_slab_rolls_as_the_2d_steady_mode() {
    let width = 0.25;
    let v0 = 0.995 * 10.0 * RO;
    let tanh = "law = \"coulomb_tanh\"\nmu = 0.3\neps = 0.05";
    // η ω / G = 0.1 with G = 2 (c1 + c2) = 200.
    let visc = "[time]\nstrain_rate_damping = 2.0\n";
    // Two Prony terms with ω τ = 0.2 and 2, γ = 0.3 G.
    let visco = |model: &str| {
        format!(
            "[material.viscoelastic]\nmodel = \"{model}\"\ngamma = 60.0\nprony = [[0.6, 0.02], [0.4, 0.2]]\n"
        )
    };
    for (name, b_n, friction, facet_wise, extra) in [
        ("frictionless, damped", 2.0, "law = \"none\"", false, ""),
        ("tanh friction, damped, nodal slip", 2.0, tanh, false, ""),
        (
            "tanh friction, damped, facet-wise slip",
            2.0,
            tanh,
            true,
            "",
        ),
        (
            "frictionless, strain-rate damping",
            0.0,
            "law = \"none\"",
            false,
            visc,
        ),
        (
            "tanh friction, damped, strain-rate damping",
            2.0,
            tanh,
            false,
            visc,
        ),
        (
            "tanh friction, damped, viscoelastic (multiplicative)",
            2.0,
            tanh,
            false,
            &visco("multiplicative"),
        ),
        (
            "frictionless, viscoelastic (convolution)",
            0.0,
            "law = \"none\"",
            false,
            &visco("convolution"),
        ),
    ] {
        let sc2 = slab_scene_with(None, v0, b_n, friction, 0.0, extra);
        let (st, (fx2, fy2, m2)) = steady_2d(&sc2, facet_wise);
        let sc3 = slab_scene_with(Some(width), v0, b_n, friction, 0.0, extra);
        let s3 = steady_3d(&sc3, facet_wise);
        let t3 = s3.contact.as_ref().expect("contact").totals;
        let (f, m) = (t3.force, t3.moment);
        eprintln!(
            "{name}: 2D (F1, F2, M3) = ({fx2:.12e}, {fy2:.12e}, {m2:.12e}); 3D per width ({:.12e}, {:.12e}, {:.12e}); F3 = {:.2e}, M1 = {:.2e}, M2 = {:.2e}",
            f[0] / width,
            f[1] / width,
            m[2] / width,
            f[2],
            m[0],
            m[1]
        );
        let fscale = fy2.abs();
        for (a, b, what) in [
            (f[0] / width, fx2, "F1"),
            (f[1] / width, fy2, "F2"),
            (m[2] / width, m2, "M3"),
        ] {
            assert!(
                (a - b).abs() <= 1e-8 * fscale * if what == "M3" { RO } else { 1.0 },
                "{name}: {what} 3D {a} vs 2D {b}"
            );
        }
        assert!(f[2].abs() <= 1e-9 * fscale, "{name}: F3 = {}", f[2]);
        let key = |x: f64, y: f64| ((x * 1e9).round() as i64, (y * 1e9).round() as i64);
        let mesh2 = &st.sys.model.mesh;
        let index: std::collections::HashMap<_, _> = mesh2
            .nodes
            .iter()
            .enumerate()
            .map(|(i, x)| (key(x[0], x[1]), i))
            .collect();
        let x2 = &st.sys.x;
        let umax = (0..mesh2.n_nodes())
            .map(|n| x2[2 * n].hypot(x2[2 * n + 1]))
            .fold(0.0f64, f64::max);
        let mut worst: f64 = 0.0;
        for (n, x) in s3.solid.mesh.nodes.iter().enumerate() {
            let i = index[&key(x[0], x[1])];
            let u = s3.node_displacement(n);
            worst = worst
                .max((u[0] - x2[2 * i]).abs())
                .max((u[1] - x2[2 * i + 1]).abs())
                .max(u[2].abs());
        }
        eprintln!("{name}: max |u_3D − u_2D| / max|u| = {:.2e}", worst / umax);
        assert!(
            worst / umax < 1e-8,
            "{name}: field differs {:.3e}",
            worst / umax
        );
    }
}

/// α → −α and γ → −γ mirror the wheel in x3: the lateral force, the overturning and the
/// aligning moments (in the road frame) change sign, the rest stays. A free-sided wheel (no symmetry imposed), friction and
/// damping (l_n = 1: with l_n = 0 the damping term jumps where points enter the patch at the
/// leading edge, and Newton stalls when one enters at the final load).
#[test]
fn slip_angle_and_camber_signs_flip_lateral_force_and_aligning_moment() {
    let scene = cornering_scene;
    for (what, (ap, gp)) in [("slip angle", (2.0, 0.0)), ("camber", (0.0, 2.0))] {
        let plus = steady_3d(&scene(ap, gp), false);
        let minus = steady_3d(&scene(-ap, -gp), false);
        // The hub loads in the road frame (longitudinal, vertical, lateral).
        let loads = |s: &Solid3DSystem| {
            let c = s.contact.as_ref().expect("contact");
            let f = c.surface.frame();
            (f.components(c.totals.force), f.components(c.totals.moment))
        };
        let ((fp, mp), (fm, mm)) = (loads(&plus), loads(&minus));
        eprintln!("{what} +2°: F = {fp:?}, M = {mp:?}\n{what} −2°: F = {fm:?}, M = {mm:?}");
        let fs = fp[1].abs();
        // The lateral force must be clearly non-zero for the symmetry to mean something.
        assert!(fp[2].abs() > 1e-3 * fs, "{what}: no lateral force: {fp:?}");
        let tol = 1e-8 * fs;
        for (a, b) in [(fp[2], fm[2]), (mp[0], mm[0]), (mp[1], mm[1])] {
            assert!((a + b).abs() <= tol * RO, "{what}, odd: {a} vs {b}");
        }
        for (a, b) in [(fp[0], fm[0]), (fp[1], fm[1]), (mp[2], mm[2])] {
            assert!((a - b).abs() <= tol * RO, "{what}, even: {a} vs {b}");
        }
    }
}

/// The rolling controls on the plane-strain slab: free rolling, a given creep and a given
/// torque find the same road speed as the 2D steady mode (the same secant iteration on the
/// same torque, per unit width), and the hub's reaction balances the contact force exactly
/// (the θ-referential inertia has no resultant on closed rings).
#[test]
fn rolling_controls_on_the_slab_match_the_2d_steady_mode() {
    let width = 0.25;
    let v0 = 0.995 * 10.0 * RO;
    let tanh = "law = \"coulomb_tanh\"\nmu = 0.3\neps = 0.05";
    let torque_2d = 1.0;
    for (control, creep, torque) in [
        (Control::FreeRolling, 0.0, 0.0),
        (Control::Creep, -2e-3, 0.0),
        (Control::Torque, 0.0, torque_2d),
    ] {
        let mut sc2 = slab_scene(None, v0, 2.0, tanh, 0.0);
        let mut sc3 = slab_scene(Some(width), v0, 2.0, tanh, 0.0);
        for (sc, t) in [(&mut sc2, torque), (&mut sc3, torque * width)] {
            sc.motion.control = control;
            sc.motion.creep = creep;
            sc.motion.torque = t;
        }
        let (mut st, _) = steady_2d(&sc2, false);
        let rep2 = steady_run::apply_control(&sc2, &mut st, false)
            .unwrap_or_else(|e| panic!("2D {control:?}: {e}"));
        let mut s3 = steady_3d(&sc3, false);
        let kind = tread::setup::linear_kind_3d(&sc3, &s3);
        let (newton, _) = tread::setup::solver_options(&sc3, false);
        let rep3 = apply_control_3d(&sc3, &mut s3, kind, newton)
            .unwrap_or_else(|e| panic!("3D {control:?}: {e}"));
        let (f3, m3) = s3.hub_reaction();
        let (f2, m2) = st.sys.hub_reaction();
        eprintln!(
            "{control:?}: v0 2D {:.12e} 3D {:.12e}; hub torque 2D {:.6e}, 3D per width {:.6e}; \
             F1 2D {:.9e}, 3D per width {:.9e}; evaluations {} / {}",
            st.v0(),
            s3.road_speed(),
            m2,
            m3[2] / width,
            f2[0],
            f3[0] / width,
            rep2.evaluations,
            rep3.evaluations,
        );
        // The torque and free-rolling controls reached their torque.
        if control != Control::Creep {
            assert!(
                (m3[2] - torque * width).abs() <= rep3.torque_tolerance,
                "{control:?}: 3D hub torque {} vs {}",
                m3[2],
                torque * width
            );
            assert!((m2 - torque).abs() <= rep2.torque_tolerance);
        }
        // The road speed of both (the torque tolerance 1e-7 |F| Ro bounds the difference).
        let dv = (s3.road_speed() - st.v0()).abs() / v0;
        assert!(dv < 1e-6, "{control:?}: v0 differs by {dv:.3e} (relative)");
        if control == Control::Creep {
            assert!((rep3.creep - creep).abs() < 1e-12, "creep {}", rep3.creep);
            assert!(
                (rep3.v0_free / rep2.v0_free - 1.0).abs() < 1e-6,
                "v0_free {} vs {}",
                rep3.v0_free,
                rep2.v0_free
            );
            // ξ < 0, the road slower than the free-rolling speed: the tread slides forward
            // (+x1 at the bottom) over the road, the road's friction on it points to −x1
            // (the direction of travel: a driven wheel) and the hub holds it with F1 > 0.
            assert!(f3[0] > 0.0, "hub F1 = {}", f3[0]);
        }
        let fscale = f2[1].abs();
        assert!(
            (f3[0] / width - f2[0]).abs() < 1e-5 * fscale,
            "{control:?}: F1 3D per width {} vs 2D {}",
            f3[0] / width,
            f2[0]
        );
        // The hub balances the contact exactly (no inertia resultant).
        let tc = s3.contact.as_ref().expect("contact").totals.force;
        for i in 0..3 {
            assert!(
                (f3[i] + tc[i]).abs() <= 1e-9 * fscale * width,
                "{control:?}: hub F{} = {} vs contact {}",
                i + 1,
                f3[i],
                tc[i]
            );
        }
    }
}

/// A free-sided Hex8 wheel rolling at ω = 10 on the road at 19.9 in/s turned by the slip angle
/// `alpha` (degrees), with the camber `camber` (degrees), tanh friction and damping.
fn cornering_scene(alpha: f64, camber: f64) -> Scene {
    cornering_scene_at(alpha, camber, 10.0, 0.04)
}

/// [`cornering_scene`] at the angular speed `omega` (the road speed 1.99 ω) and the
/// penetration `disp`.
fn cornering_scene_at(alpha: f64, camber: f64, omega: f64, disp: f64) -> Scene {
    let v0 = 1.99 * omega;
    let text = format!(
        r#"
[scene]
name = "cornering"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
dimension = 3
width = 0.6
n_z = 2
n_r = 2
n_theta = 32
order = 1
grading_theta = 0.6
[material]
model = "neo_hookean"
mu = 200.0
lambda = 1800.0
rho = 0.027
[analysis]
mode = "steady"
[motion]
omega = {omega}
[road]
disp = {disp}
v0 = {v0}
slip_angle = {alpha}
camber = {camber}
[contact]
c_n = 2.0e4
b_n = 2.0
l_n = 1.0
quadrature = "gauss"
points = 3
[friction]
law = "coulomb_tanh"
mu = 0.5
eps = 0.2
[solver]
tolerance = 1e-11
load_steps = 3
linear = "lu"
"#
    );
    Scene::from_toml_str(&text, "cornering", &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// Arc-length continuation in the slip angle, the camber, the angular speed (road speed
/// proportional) and the penetration: every converged point of the path is the steady state of
/// a direct solve at its parameter (the vertical and lateral forces and the aligning moment to
/// the solver tolerance), and the path reaches the target.
#[test]
fn continuation_points_are_steady_states() {
    use tread::driver::steady3d::{follow_path_3d, Path3DParameter};
    use tread::io::scene::{ContinuationParameter, ContinuationSpec};
    for (parameter, target) in [
        (ContinuationParameter::SlipAngle, 3.0),
        (ContinuationParameter::Camber, 3.0),
        (ContinuationParameter::Omega, 13.0),
        (ContinuationParameter::Disp, 0.06),
    ] {
        // The ω and penetration paths at a slip angle of 2°: a lateral force to follow.
        let at = |value: f64| match parameter {
            ContinuationParameter::SlipAngle => cornering_scene(value, 0.0),
            ContinuationParameter::Camber => cornering_scene(0.0, value),
            ContinuationParameter::Omega => cornering_scene_at(2.0, 0.0, value, 0.04),
            _ => cornering_scene_at(2.0, 0.0, 10.0, value),
        };
        let sc = match parameter {
            ContinuationParameter::SlipAngle | ContinuationParameter::Camber => at(0.0),
            ContinuationParameter::Omega => at(10.0),
            _ => at(0.04),
        };
        let mut sys = steady_3d(&sc, false);
        let cs = ContinuationSpec {
            parameter,
            target,
            ds: 0.2,
            ..Default::default()
        };
        let mut points: Vec<(f64, [f64; 3], f64)> = Vec::new();
        let mut on_point =
            |p: &tread::driver::steady3d::SteadyPath3D,
             b: &tread::solver::continuation::BranchPoint| {
                let c = p.sys.contact.as_ref().expect("contact");
                let (f, m) = (
                    c.surface.frame().components(c.totals.force),
                    c.surface.frame().components(c.totals.moment),
                );
                points.push((b.lambda, f, m[1]));
                true
            };
        let path = Path3DParameter::of(parameter, f64::NAN, &sys).expect("parameter");
        let (rep, res) = follow_path_3d(&sc, &cs, path, &mut sys, false, &mut on_point);
        res.unwrap_or_else(|e| panic!("{parameter} continuation: {e}"));
        let rep = rep.expect("report");
        eprintln!(
            "{parameter}: {} points, {} corrector iterations",
            points.len(),
            rep.total_iterations,
        );
        let last = points.last().copied().expect("points");
        let start = points[0].0;
        assert!(
            (last.0 - start) / (target - start) >= 1.0 - 1e-9,
            "{parameter}: target not reached: {}",
            last.0
        );
        assert!(points.len() >= 4);
        let fz = sys.contact.as_ref().expect("contact").totals.force[1].abs();
        // Two points of the path, each against a direct solve from the undeformed state.
        for &(value, f, m2) in [points[2], last].iter() {
            let direct = steady_3d(&at(value), false);
            let c = direct.contact.as_ref().expect("contact");
            let (fd, md) = (
                c.surface.frame().components(c.totals.force),
                c.surface.frame().components(c.totals.moment),
            );
            eprintln!(
                "{parameter} = {value:.6}: path F2 {:.10e} F3 {:.10e} M2 {m2:.10e}; direct F2 {:.10e} F3 {:.10e} M2 {:.10e}",
                f[1], f[2], fd[1], fd[2], md[1]
            );
            assert!(f[2] < 0.0, "{parameter}: lateral force {}", f[2]);
            for (a, b, what) in [(f[1], fd[1], "F2"), (f[2], fd[2], "F3")] {
                assert!((a - b).abs() <= 1e-7 * fz, "{parameter}: {what} {a} vs {b}");
            }
            assert!(
                (m2 - md[1]).abs() <= 1e-7 * fz * RO,
                "{parameter}: M2 {m2} vs {}",
                md[1]
            );
        }
    }
}

/// The nested iteration of the 3D steady mode: from the coarser mesh's steady state
/// (interpolated) Newton reaches the same steady state as the press-in from the undeformed
/// state, in fewer iterations on the scene's mesh.
#[test]
fn nested_iteration_reaches_the_press_in_state() {
    use tread::driver::steady3d::solve_steady_3d_nested;
    let mut sc = cornering_scene(2.0, 0.0);
    sc.mesh.n_theta = 64;
    let solve = |coarse_start: bool| {
        let mut sc = sc.clone();
        sc.solver.coarse_start = coarse_start;
        let mut s3 = tread::setup::build_system_3d(&sc).unwrap_or_else(|e| panic!("{e}"));
        let kind = tread::setup::linear_kind_3d(&sc, &s3);
        let (newton, step) = tread::setup::solver_options(&sc, false);
        let mut rep = StepReport::default();
        let (cs, res) =
            solve_steady_3d_nested(&sc, &mut s3, kind, newton, &step, &mut rep, &mut NoObserver);
        res.unwrap_or_else(|e| panic!("coarse_start = {coarse_start}: {e}"));
        (s3, cs, rep.total_iterations)
    };
    let (nested, cs, it_nested) = solve(true);
    let (direct, none, it_direct) = solve(false);
    assert!(none.is_none());
    let cs = cs.expect("the nested iteration applies at n_theta = 64");
    eprintln!(
        "nested: {:?}, {} Newton iterations on the scene's mesh; press-in: {}",
        cs, it_nested, it_direct
    );
    assert!(cs.succeeded, "{:?}", cs.error);
    assert_eq!(cs.meshes, vec!["1x1x32".to_string()]);
    assert!(it_nested < it_direct);
    let (a, b) = (
        nested.contact.as_ref().expect("contact").totals,
        direct.contact.as_ref().expect("contact").totals,
    );
    let fz = b.force[1].abs();
    for i in 0..3 {
        assert!((a.force[i] - b.force[i]).abs() <= 1e-8 * fz, "F{}", i + 1);
        assert!(
            (a.moment[i] - b.moment[i]).abs() <= 1e-8 * fz * RO,
            "M{}",
            i + 1
        );
    }
    let n = nested.dofs.n_u;
    let du = (0..n)
        .map(|i| (nested.x[i] - direct.x[i]).abs())
        .fold(0.0, f64::max);
    let umax = direct.x[..n].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(du <= 1e-7 * umax, "field differs by {du:e} of {umax:e}");
}

/// A torque beyond what friction transmits (μ |F| Ro) cannot be reached: the torque control
/// says so, with the range of torques its trials reached, instead of failing at a trial.
#[test]
fn unreachable_torque_is_reported() {
    let mut sc = cornering_scene(0.0, 0.0);
    sc.motion.control = Control::Torque;
    sc.motion.torque = 1e3;
    let mut s3 = steady_3d(&sc, false);
    let kind = tread::setup::linear_kind_3d(&sc, &s3);
    let (newton, _) = tread::setup::solver_options(&sc, false);
    let e = apply_control_3d(&sc, &mut s3, kind, newton).expect_err("beyond friction");
    let msg = e.to_string();
    eprintln!("{msg}");
    match e {
        tread::solver::SolveError::TorqueUnreachable { target, t_max, .. } => {
            assert_eq!(target, 1e3);
            // The wheel load is 13 lbf, μ = 0.5, Ro = 2: friction transmits about 13 lbf·in.
            assert!(
                t_max < 20.0 && t_max > 0.0,
                "largest torque reached {t_max}"
            );
        }
        other => panic!("expected TorqueUnreachable, got {other}"),
    }
    assert!(msg.contains("no road speed"), "{msg}");
}
