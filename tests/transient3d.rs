//! Transient (dynamic Lagrangian) rolling of the three-dimensional body
//! ([`tread::driver::transient3d`]): the plane-strain limit (a slab with u3 = 0 on its faces,
//! integrated with the same integrator and steps, reproduces the plane-strain transient's hub
//! loads per unit width and its field at every step, with friction, normal damping and the
//! strain-rate damping) and the Newton tangent of a 3D time step against central differences.

use tread::driver::transient::body3d::contact_samples_3d;
use tread::driver::transient::registry::Integrate;
use tread::solver::integrators::IntegratorName;
#[path = "common/fixtures.rs"]
mod fixtures;

use tread::driver::transient::{integrate, TimeOptions, Transient, TransientReport};
use tread::driver::transient3d::kinematics_3d;
use tread::driver::transient_run::kinematics;
use tread::io::Scene;
use tread::model::{Solid3DSystem, SolidSystem};

/// The rolling scene in plane strain or, with `width`, as a slab with sliding sides: ω ramped
/// to 10 rad/s, pressed in by 0.05 and the road brought to 0.995 ω Ro, tanh friction, normal
/// damping; fixed steps; `extra` appended to the scene text (e.g. a `[material.viscoelastic]`
/// table).
fn scene_with(width: Option<f64>, integrator: &str, dt: f64, t_end: f64, extra: &str) -> Scene {
    let mesh3 = match width {
        Some(w) => format!("dimension = 3\nwidth = {w}\nn_z = 1\nsides = \"sliding\"\n"),
        None => String::new(),
    };
    let mass = if integrator == "central_difference" {
        "lumped"
    } else {
        "consistent"
    };
    let text = format!(
        r#"
[scene]
name = "slab"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
{mesh3}n_r = 2
n_theta = 32
order = 2
[material]
model = "mooney_rivlin"
c1 = 80.0
c2 = 20.0
kappa = 2000.0
rho = 0.027
[analysis]
mode = "transient"
[motion]
omega = 10.0
ramp = 0.1
[road]
disp = 0.05
ramp = 0.1
v0 = 19.9
[contact]
c_n = 2.0e4
b_n = 2.0
quadrature = "gauss"
points = 3
[friction]
law = "coulomb_tanh"
mu = 0.3
eps = 0.5
[time]
integrator = "{integrator}"
rho_inf = 0.8
dt = {dt}
t_end = {t_end}
adaptive = false
stop_at_steady = false
mass = "{mass}"
max_steps = 100000
strain_rate_damping = 0.5
[solver]
tolerance = 1e-11
linear = "lu"
{extra}"#
    );
    Scene::from_toml_str(&text, "slab", &[]).unwrap_or_else(|e| panic!("{e}"))
}

fn time_options(sc: &Scene) -> TimeOptions {
    let ts = sc.time.as_ref().expect("[time]");
    TimeOptions {
        dt: ts.dt,
        dt_min: ts.resolved_dt_min(),
        dt_max: ts.resolved_dt_max(),
        t_end: ts.t_end,
        adaptive: false,
        error_tol: ts.error_tol,
        steady_tol: ts.steady_tol,
        stop_at_steady: false,
        max_steps: ts.max_steps,
        lumped: ts.integrator == IntegratorName::CentralDifference,
        land_on_passages: false,
    }
}

/// Per accepted step: t and the hub loads (F1, F2, M3); the final displacements.
type Run = (Vec<[f64; 4]>, Vec<f64>, TransientReport);

fn run_2d(sc: &Scene) -> Run {
    let ts = sc.time.as_ref().expect("[time]");
    let mut model = tread::setup::build_model(sc).unwrap_or_else(|e| panic!("{e}"));
    model.strain_rate_damping = ts.strain_rate_damping;
    let c = tread::setup::build_contact(sc, &model).unwrap_or_else(|e| panic!("{e}"));
    let sys = SolidSystem::with_contact(model, c);
    let lumped = ts.integrator == IntegratorName::CentralDifference;
    let mut tr = Transient::new(
        sys,
        ts.integrator.scheme(ts.rho_inf),
        kinematics(sc),
        lumped,
    );
    let plan = tread::setup::solve_plan(sc, &tr.sys);
    let mut rows = Vec::new();
    let rep = integrate(
        &mut tr,
        &time_options(sc),
        plan.newton,
        plan.kind,
        |tr, _| {
            let l = tr.hub_loads();
            rows.push([tr.state.t, l[0], l[1], l[5]]);
        },
    )
    .unwrap_or_else(|(e, _)| panic!("2D transient: {e}"));
    (rows, tr.state.u.clone(), rep)
}

fn run_3d(sc: &Scene) -> (Run, Vec<[f64; 3]>) {
    let ts = sc.time.as_ref().expect("[time]");
    let mut sys: Solid3DSystem =
        tread::setup::build_system_3d(sc).unwrap_or_else(|e| panic!("{e}"));
    sys.strain_rate_damping = ts.strain_rate_damping;
    let kind = tread::setup::linear_kind_3d(sc, &sys);
    let (newton, _) = tread::setup::solver_options(sc, false);
    let kin = kinematics_3d(sc, &sys);
    let scheme = ts.integrator.scheme_3d(ts.rho_inf).expect("a 3D scheme");
    let lumped = ts.integrator == IntegratorName::CentralDifference;
    let mut tr = Transient::new(sys, scheme, kin, lumped);
    let mut rows = Vec::new();
    let mut off_plane = Vec::new();
    let rep = integrate(&mut tr, &time_options(sc), newton, kind, |tr, _| {
        let l = tr.hub_loads();
        rows.push([tr.state.t, l[0], l[1], l[5]]);
        off_plane.push([l[2], l[3], l[4]]);
    })
    .unwrap_or_else(|(e, _)| panic!("3D transient: {e}"));
    let n = tr.sys.solid.mesh.n_nodes();
    let mut u = tr.state.u.clone();
    u.truncate(3 * n);
    // Node positions ride along for the comparison.
    let mut out = u;
    out.extend(
        tr.sys
            .solid
            .mesh
            .nodes
            .iter()
            .flat_map(|x| [x[0], x[1], x[2]]),
    );
    ((rows, out, rep), off_plane)
}

fn compare(integrator: &str, dt: f64, t_end: f64) {
    compare_with(integrator, dt, t_end, "");
}

fn compare_with(integrator: &str, dt: f64, t_end: f64, extra: &str) {
    let width = 0.25;
    let (rows2, u2, rep2) = run_2d(&scene_with(None, integrator, dt, t_end, extra));
    let ((rows3, u3, rep3), off) = run_3d(&scene_with(Some(width), integrator, dt, t_end, extra));
    assert_eq!(rep2.steps, rep3.steps, "{integrator}: steps");
    assert!(rep2.steps > 20, "{integrator}: {} steps", rep2.steps);
    let fscale = rows2.iter().map(|r| r[2].abs()).fold(0.0, f64::max);
    assert!(fscale > 1.0, "{integrator}: no contact force ({fscale})");
    let mut worst: f64 = 0.0;
    for (a, b) in rows2.iter().zip(&rows3) {
        assert!(
            (a[0] - b[0]).abs() < 1e-12,
            "{integrator}: times {} vs {}",
            a[0],
            b[0]
        );
        for (i, s) in [(1, 1.0), (2, 1.0), (3, 2.0)] {
            worst = worst.max((b[i] / width - a[i]).abs() / (fscale * s));
        }
    }
    let off_worst = off
        .iter()
        .map(|o| o[0].abs().max(o[1].abs()).max(o[2].abs()))
        .fold(0.0, f64::max);
    eprintln!(
        "{integrator}: {} steps, final 2D (F1, F2, M3) = ({:.10e}, {:.10e}, {:.10e}), 3D per width ({:.10e}, {:.10e}, {:.10e}); worst relative difference {worst:.2e}; |F3|, |M1|, |M2| ≤ {off_worst:.2e}",
        rep2.steps,
        rows2.last().unwrap()[1],
        rows2.last().unwrap()[2],
        rows2.last().unwrap()[3],
        rows3.last().unwrap()[1] / width,
        rows3.last().unwrap()[2] / width,
        rows3.last().unwrap()[3] / width,
    );
    assert!(
        worst < 1e-8,
        "{integrator}: hub loads differ by {worst:.3e}"
    );
    assert!(
        off_worst < 1e-8 * fscale * width,
        "{integrator}: out-of-plane loads {off_worst:.3e}"
    );
    // Field: every 3D node against the 2D node at the same (X1, X2).
    let n3 = u3.len() / 6;
    let (d3, x3) = u3.split_at(3 * n3);
    let model = tread::setup::build_model(&scene_with(None, integrator, dt, t_end, extra))
        .expect("2D model");
    let key = |x: f64, y: f64| ((x * 1e9).round() as i64, (y * 1e9).round() as i64);
    let index: std::collections::HashMap<_, _> = model
        .mesh
        .nodes
        .iter()
        .enumerate()
        .map(|(i, x)| (key(x[0], x[1]), i))
        .collect();
    let umax = (0..model.mesh.n_nodes())
        .map(|n| u2[2 * n].hypot(u2[2 * n + 1]))
        .fold(0.0f64, f64::max);
    let mut field: f64 = 0.0;
    for n in 0..n3 {
        let i = index[&key(x3[3 * n], x3[3 * n + 1])];
        field = field
            .max((d3[3 * n] - u2[2 * i]).abs())
            .max((d3[3 * n + 1] - u2[2 * i + 1]).abs())
            .max(d3[3 * n + 2].abs());
    }
    eprintln!(
        "{integrator}: max |u_3D − u_2D| / max |u| = {:.2e}",
        field / umax
    );
    assert!(
        field / umax < 1e-8,
        "{integrator}: field differs {:.3e}",
        field / umax
    );
}

#[test]
fn plane_strain_slab_rolls_as_the_2d_transient_generalized_alpha() {
    compare("generalized_alpha", 2e-3, 0.15);
}

#[test]
fn plane_strain_slab_rolls_as_the_2d_transient_central_difference() {
    compare("central_difference", 2e-5, 0.05);
}

/// A viscoelastic slab (both models, two Prony terms with relaxation times of the order of the
/// run, γ about a third of the shear modulus): the quadrature-point history of the 3D body
/// gives the plane-strain transient's hub loads and field to 1e-8.
#[test]
fn viscoelastic_slab_rolls_as_the_2d_transient() {
    for model in ["multiplicative", "convolution"] {
        let extra = format!(
            "[material.viscoelastic]\nmodel = \"{model}\"\ngamma = 60.0\nprony = [[0.6, 0.02], [0.4, 0.2]]\n"
        );
        eprintln!("viscoelastic model {model}:");
        compare_with("generalized_alpha", 2e-3, 0.15, &extra);
    }
}

/// The Newton system of a 3D time step (generalized-α, ρ∞ = 0.7) against central differences
/// of its residual: Hex8 and Hex27, free sides, tanh friction at a slip angle of 3° on a
/// road cambered by 2°, normal damping, strain-rate damping η = 2, elastic and with either viscoelastic model (a committed history
/// away from the reference, the step's overstress from it), mid-step state (rigid rotation plus a perturbation, in
/// contact and sliding).
#[test]
fn time_step_tangent_matches_finite_differences_3d() {
    use tread::driver::transient::{Body, GenAlpha, Scheme};
    use tread::solver::NonlinearSystem;
    let models = [None, Some("multiplicative"), Some("convolution")];
    for (order, visco) in [1, 2].into_iter().flat_map(|o| models.map(|m| (o, m))) {
        let visco_table = visco.map_or(String::new(), |m| {
            format!(
                "[material.viscoelastic]\nmodel = \"{m}\"\ngamma = 60.0\nprony = [[0.6, 0.02], [0.4, 0.2]]\n"
            )
        });
        let text = format!(
            r#"
[scene]
name = "tangent"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
dimension = 3
width = 0.5
n_z = 1
n_r = 1
n_theta = 12
order = {order}
[material]
model = "mooney_rivlin"
c1 = 80.0
c2 = 20.0
kappa = 2000.0
rho = 0.027
[analysis]
mode = "transient"
[motion]
omega = 10.0
[road]
disp = 0.05
v0 = 19.0
slip_angle = 3.0
camber = 2.0
[contact]
c_n = 2.0e4
b_n = 5.0
[friction]
law = "coulomb_tanh"
mu = 0.3
eps = 0.5
[time]
dt = 1e-3
t_end = 1.0
{visco_table}"#
        );
        let sc = Scene::from_toml_str(&text, "tangent", &[]).unwrap_or_else(|e| panic!("{e}"));
        let mut sys = tread::setup::build_system_3d(&sc).unwrap_or_else(|e| panic!("{e}"));
        sys.strain_rate_damping = 2.0;
        let mut kin = kinematics_3d(&sc, &sys);
        kin.omega.time = 0.0;
        kin.v0.time = 0.0;
        kin.disp = kin.disp.map(|mut d| {
            d.time = 0.0;
            d
        });
        let mut tr = Transient::new(
            sys,
            Scheme::generalized_alpha(GenAlpha::new(0.7)),
            kin,
            false,
        );
        let h = tr.kin.h_touch - 0.05;
        tr.sys.set_road(Some(h), None, 19.0);
        let n = tr.sys.solid.mesh.n_nodes();
        let omega = 10.0;
        for a in 0..n {
            let x = tr.sys.solid.mesh.nodes[a];
            tr.state.v[3 * a] = -omega * x[1];
            tr.state.v[3 * a + 1] = omega * x[0];
            tr.state.a[3 * a] = -omega * omega * x[0];
            tr.state.a[3 * a + 1] = -omega * omega * x[1];
        }
        tr.dt = 1e-3;
        if visco.is_some() {
            // A committed history away from the reference (a sheared, stretched state), then
            // the overstress over a step from it.
            let mut xh = tr.sys.x.clone();
            for a in 0..n {
                let x = tr.sys.solid.mesh.nodes[a];
                xh[3 * a] = 0.02 * x[1] + 0.01 * x[2];
                xh[3 * a + 1] = -0.015 * x[1];
                xh[3 * a + 2] = 0.01 * x[0];
            }
            let dofs = tr.sys.dofs.clone();
            tr.sys.solid.commit_history(&dofs, &xh, 5e-3);
            tr.sys.set_history_dt(1e-3);
        }
        let (s, c) = (omega * 1e-3).sin_cos();
        for a in 0..n {
            let x = tr.sys.solid.mesh.nodes[a];
            tr.sys.x[3 * a] = c * x[0] - s * x[1] - x[0] + 1e-3 * x[1].sin();
            tr.sys.x[3 * a + 1] = s * x[0] + c * x[1] - x[1] + 1e-3 * x[0].cos();
            tr.sys.x[3 * a + 2] = 1e-3 * (x[0] + x[2]).sin();
        }
        // The hub follows the prescribed rotation (its dofs carry no equation).
        assert!(tr.evaluate(true));
        let v = tr.state.v.clone();
        let samples = contact_samples_3d(&tr.sys, &tr.sys.x, &v).expect("samples");
        let in_contact = samples.iter().filter(|s| s.delta > 0.0).count();
        let sliding = samples.iter().filter(|s| s.delta > 0.0 && !s.stick).count();
        assert!(in_contact > 3, "order {order}: {in_contact} contact points");
        let k = tr.sys.asm.to_dense();
        let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let err = fixtures::fd_max_error(&mut tr, 1e-7, |i, j| k[i][j]) / kmax;
        eprintln!(
            "order {order}, viscoelastic {visco:?}: {} equations, {in_contact} contact points \
             ({sliding} outside the regularised zone), max|K − K_fd|/max|K| = {err:.2e}",
            tr.n_eq()
        );
        assert!(
            err < 1e-6,
            "order {order}, viscoelastic {visco:?}: dynamic tangent differs from FD: {err:.3e}"
        );
    }
}
