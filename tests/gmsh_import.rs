//! Meshes read from Gmsh files: a Gmsh-made structured annulus gives the generator's results to
//! round-off (static indentation, spinning), and a two-material cylinder read from Gmsh matches
//! an independent axisymmetric reference (radial shooting through both layers).

use tread::app::build_system;
use tread::driver::indentation::solve_indentation;
use tread::driver::spinning::{results, solve_spinning};
use tread::io::Scene;
use tread::math::Vec2;
use tread::model::system::Loading;
use tread::model::SolidSystem;
use tread::solver::stepping::{StepOptions, StepReport};
use tread::solver::{LinearKind, NewtonOptions};

fn data(name: &str) -> String {
    format!("{}/tests/gmsh_data/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn scenario_mesh(name: &str) -> String {
    format!("{}/scenarios/{name}", env!("CARGO_MANIFEST_DIR"))
}

fn load(text: &str) -> Scene {
    Scene::from_toml_str(text, "test", &[]).unwrap_or_else(|e| panic!("{e}"))
}

const STATIC: &str = r#"
[scene]
name = "t"
[geometry]
ri = 1.0
ro = 2.0
[material]
model = "mooney_rivlin"
c1 = 80.0
c2 = 20.0
kappa = 2000.0
rho = 0.027
[analysis]
mode = "static"
[road]
disp = 0.1
[contact]
c_n = 2.0e5
quadrature = "gauss"
points = 4
"#;

const SPIN: &str = r#"
[scene]
name = "t"
[geometry]
ri = 1.0
ro = 2.0
[material]
model = "neo_hookean"
mu = 200.0
lambda = 1800.0
rho = 0.027
[analysis]
mode = "spinning"
[motion]
omega = 60.0
"#;

fn newton() -> (NewtonOptions, StepOptions) {
    (
        NewtonOptions {
            tol: 1e-12,
            max_iterations: 30,
            ..Default::default()
        },
        StepOptions {
            initial_steps: 4,
            max_cutbacks: 8,
            verbose: false,
        },
    )
}

fn solve_static(scene: &Scene) -> SolidSystem {
    let mut sys = build_system(scene).unwrap_or_else(|e| panic!("{e}"));
    sys.loading = Loading::Indent {
        h_touch: scene.geometry.ro,
        disp: 0.1,
    };
    let (n, s) = newton();
    let mut rep = StepReport::default();
    solve_indentation(&mut sys, LinearKind::Cholesky, n, &s, &mut rep, &mut ())
        .expect("indentation converges");
    sys
}

fn solve_spin(scene: &Scene) -> SolidSystem {
    let mut sys = build_system(scene).unwrap_or_else(|e| panic!("{e}"));
    let (n, s) = newton();
    let mut rep = StepReport::default();
    solve_spinning(
        &mut sys,
        scene.motion.omega,
        LinearKind::Cholesky,
        n,
        &s,
        &mut rep,
        &mut (),
    )
    .expect("spinning converges");
    sys
}

/// For every node of `a`, the node of `b` at the same reference position (within `tol`).
fn match_nodes(a: &SolidSystem, b: &SolidSystem, tol: f64) -> Vec<usize> {
    let (ma, mb) = (&a.model.mesh, &b.model.mesh);
    assert_eq!(ma.n_nodes(), mb.n_nodes(), "node counts");
    assert_eq!(ma.n_cells(), mb.n_cells(), "cell counts");
    ma.nodes
        .iter()
        .enumerate()
        .map(|(i, x)| {
            let (j, d) = mb
                .nodes
                .iter()
                .enumerate()
                .map(|(j, y)| (j, (x - y).norm()))
                .fold((0, f64::INFINITY), |m, v| if v.1 < m.1 { v } else { m });
            assert!(d <= tol, "node {i} at {x:?}: nearest Gmsh node {d:e} away");
            j
        })
        .collect()
}

fn disp(sys: &SolidSystem, n: usize) -> Vec2 {
    Vec2::new(sys.x[2 * n], sys.x[2 * n + 1])
}

/// Largest nodal displacement difference over the largest displacement.
fn field_difference(a: &SolidSystem, b: &SolidSystem, map: &[usize]) -> f64 {
    let mut dmax: f64 = 0.0;
    let mut umax: f64 = 0.0;
    for (i, &j) in map.iter().enumerate() {
        dmax = dmax.max((disp(a, i) - disp(b, j)).norm());
        umax = umax.max(disp(a, i).norm());
    }
    assert!(umax > 1e-3, "the load must deform the body ({umax})");
    dmax / umax
}

#[test]
fn gmsh_q2_annulus_matches_generator_static_indentation() {
    let generated = solve_static(&load(&format!(
        "{STATIC}[mesh]\nn_r = 2\nn_theta = 16\norder = 2\n"
    )));
    for file in ["annulus_q2.msh", "annulus_q2_binary.msh"] {
        let scene = load(&format!("{STATIC}[mesh]\nfile = \"{}\"\n", data(file)));
        let sys = solve_static(&scene);
        assert!(sys.model.mesh.rings.is_none());
        let map = match_nodes(&generated, &sys, 1e-14);
        // The hub node sets are the same nodes.
        let mut hub_a: Vec<usize> = generated
            .model
            .mesh
            .node_set("hub")
            .iter()
            .map(|&n| map[n as usize])
            .collect();
        let mut hub_b: Vec<usize> = sys
            .model
            .mesh
            .node_set("hub")
            .iter()
            .map(|&n| n as usize)
            .collect();
        hub_a.sort();
        hub_b.sort();
        assert_eq!(hub_a, hub_b, "{file}: hub nodes");
        let d = field_difference(&generated, &sys, &map);
        assert!(d < 1e-12, "{file}: displacement difference {d:e}");
        let (fa, ma) = generated.hub_reaction();
        let (fb, mb) = sys.hub_reaction();
        assert!(
            (fa - fb).norm() < 1e-11 * fa.norm(),
            "{file}: hub force {fa:?} vs {fb:?}"
        );
        assert!(
            (ma - mb).abs() < 1e-11 * fa.norm() * 2.0,
            "{file}: torque {ma} vs {mb}"
        );
        assert!(fa[1] < -10.0, "the road pushes: {fa:?}");
    }
}

#[test]
fn gmsh_q1_annulus_matches_generator_spinning() {
    let generated = solve_spin(&load(&format!(
        "{SPIN}[mesh]\nn_r = 2\nn_theta = 16\norder = 1\n"
    )));
    let sys = solve_spin(&load(&format!(
        "{SPIN}[mesh]\nfile = \"{}\"\n",
        data("annulus_q1.msh")
    )));
    let map = match_nodes(&generated, &sys, 1e-14);
    let d = field_difference(&generated, &sys, &map);
    assert!(d < 1e-12, "displacement difference {d:e}");
    let (ra, rb) = (results(&generated), results(&sys));
    for (name, a, b) in [
        ("u_r_outer", ra.u_r_outer, rb.u_r_outer),
        ("sigma_r_inner", ra.sigma_r_inner, rb.sigma_r_inner),
        (
            "sigma_theta_inner",
            ra.sigma_theta_inner,
            rb.sigma_theta_inner,
        ),
        (
            "sigma_theta_outer",
            ra.sigma_theta_outer,
            rb.sigma_theta_outer,
        ),
    ] {
        assert!(a.abs() > 0.0, "{name} = 0");
        assert!((a - b).abs() <= 1e-11 * a.abs(), "{name}: {a} vs {b}");
    }
}

// ---------------------------------------------------------------------------------------------
// Two-layer spinning annulus: an independent axisymmetric reference.
// ---------------------------------------------------------------------------------------------

/// Plane-strain compressible neo-Hookean principal first Piola–Kirchhoff stresses
/// W = μ/2 (l1² + l2² − 2) − μ ln J + λ/2 (ln J)², J = l1 l2:
/// P_R = μ (l1 − 1/l1) + λ ln J / l1, P_T = μ (l2 − 1/l2) + λ ln J / l2.
fn nh_stresses(mu: f64, lambda: f64, l1: f64, l2: f64) -> (f64, f64, f64) {
    let lj = (l1 * l2).ln();
    let pr = mu * (l1 - 1.0 / l1) + lambda * lj / l1;
    let pt = mu * (l2 - 1.0 / l2) + lambda * lj / l2;
    let dpr = mu * (1.0 + 1.0 / (l1 * l1)) + lambda * (1.0 - lj) / (l1 * l1);
    (pr, pt, dpr)
}

struct Layer {
    mu: f64,
    lambda: f64,
    rho: f64,
}

/// Shooting on the radial equilibrium dP_R/dR + (P_R − P_T)/R + ρ ω² r = 0 with state (u, P_R)
/// (both continuous across the layer interface `rm`), u(ri) = 0, unknown P_R(ri) found by the
/// secant method so that P_R(ro) = 0. RK4 with `n` steps per layer. Returns u(R) at the step
/// points of both layers.
fn two_layer_reference(
    ri: f64,
    rm: f64,
    ro: f64,
    inner: &Layer,
    outer: &Layer,
    omega: f64,
    n: usize,
) -> Vec<(f64, f64)> {
    let layer_at = |r: f64| if r < rm { inner } else { outer };
    // u' from P_R at (R, u): solve P_R(l1, l2) = p for l1 by Newton.
    let rhs = |rr: f64, u: f64, p: f64, lay: &Layer| -> (f64, f64) {
        let l2 = 1.0 + u / rr;
        let mut l1 = 1.0;
        for _ in 0..60 {
            let (pr, _, dpr) = nh_stresses(lay.mu, lay.lambda, l1, l2);
            let d = (pr - p) / dpr;
            l1 -= d;
            if d.abs() < 1e-15 {
                break;
            }
        }
        let (_, pt, _) = nh_stresses(lay.mu, lay.lambda, l1, l2);
        let du = l1 - 1.0;
        let dp = -(p - pt) / rr - lay.rho * omega * omega * (rr + u);
        (du, dp)
    };
    let shoot = |p0: f64, table: Option<&mut Vec<(f64, f64)>>| -> f64 {
        let mut tab = table;
        let (mut u, mut p) = (0.0, p0);
        for (a, b) in [(ri, rm), (rm, ro)] {
            let lay = layer_at(0.5 * (a + b));
            let h = (b - a) / n as f64;
            for k in 0..n {
                let r = a + h * k as f64;
                if let Some(t) = tab.as_deref_mut() {
                    t.push((r, u));
                }
                let k1 = rhs(r, u, p, lay);
                let k2 = rhs(r + 0.5 * h, u + 0.5 * h * k1.0, p + 0.5 * h * k1.1, lay);
                let k3 = rhs(r + 0.5 * h, u + 0.5 * h * k2.0, p + 0.5 * h * k2.1, lay);
                let k4 = rhs(r + h, u + h * k3.0, p + h * k3.1, lay);
                u += h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
                p += h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
            }
        }
        if let Some(t) = tab {
            t.push((ro, u));
        }
        p
    };
    let (mut a, mut b) = (0.0, 1.0);
    let (mut fa, mut fb) = (shoot(a, None), shoot(b, None));
    for _ in 0..60 {
        let c = b - fb * (b - a) / (fb - fa);
        a = b;
        fa = fb;
        b = c;
        fb = shoot(b, None);
        if fb.abs() < 1e-13 {
            break;
        }
    }
    assert!(
        fb.abs() < 1e-10,
        "shooting did not converge: P_R(ro) = {fb}"
    );
    let mut table = Vec::new();
    shoot(b, Some(&mut table));
    table
}

/// Linear interpolation in a fine table.
fn interp(t: &[(f64, f64)], r: f64) -> f64 {
    let k = t.partition_point(|(x, _)| *x < r).clamp(1, t.len() - 1);
    let ((x0, y0), (x1, y1)) = (t[k - 1], t[k]);
    if x1 == x0 {
        return y0;
    }
    y0 + (y1 - y0) * (r - x0) / (x1 - x0)
}

#[test]
fn two_material_cylinder_matches_two_layer_radial_shooting() {
    let (ri, rm, ro) = (0.5, 1.6, 2.0);
    let omega = 60.0;
    let core = Layer {
        mu: 2000.0,
        lambda: 8000.0,
        rho: 0.05,
    };
    let tread = Layer {
        mu: 200.0,
        lambda: 1800.0,
        rho: 0.027,
    };
    let text = format!(
        r#"
[scene]
name = "two_layer"
[geometry]
ri = {ri}
ro = {ro}
[mesh]
file = "{}"
[[material]]
region = "core"
model = "neo_hookean"
mu = {}
lambda = {}
rho = {}
[[material]]
region = "tread"
model = "neo_hookean"
mu = {}
lambda = {}
rho = {}
[analysis]
mode = "spinning"
[motion]
omega = {omega}
"#,
        scenario_mesh("two_layer.msh"),
        core.mu,
        core.lambda,
        core.rho,
        tread.mu,
        tread.lambda,
        tread.rho
    );
    let scene = load(&text);
    assert_eq!(scene.regions.len(), 2);
    let sys = solve_spin(&scene);
    let mesh = &sys.model.mesh;
    assert_eq!(mesh.region_names, vec!["core", "tread"]);
    assert!(mesh.regions.contains(&0) && mesh.regions.contains(&1));
    let reference = two_layer_reference(ri, rm, ro, &core, &tread, omega, 4000);
    // The same body made of the tread rubber only: the layering must matter far more than the
    // discretisation error, or this test could not tell the materials apart.
    let homogeneous = two_layer_reference(ri, rm, ro, &tread, &tread, omega, 4000);
    let u_ref_max = reference.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    let (mut err, mut sep, mut tang): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for (n, x) in mesh.nodes.iter().enumerate() {
        let r = x.norm();
        let er = x / r;
        let u = disp(&sys, n);
        let ur = u.dot(&er);
        err = err.max((ur - interp(&reference, r)).abs());
        sep = sep.max((interp(&homogeneous, r) - interp(&reference, r)).abs());
        tang = tang.max((u - er * ur).norm());
    }
    let (err, sep, tang) = (err / u_ref_max, sep / u_ref_max, tang / u_ref_max);
    eprintln!("two-layer: max |u_r − ref| / max u = {err:.3e}, homogeneous vs layered {sep:.3e}, tangential {tang:.3e}");
    assert!(err < 5e-3, "radial displacement error {err:e}");
    assert!(sep > 50.0 * err, "layering effect {sep:e} vs error {err:e}");
    assert!(
        tang < 5e-3,
        "an axisymmetric problem: tangential displacement {tang:e}"
    );
    // The outer-surface mean radial displacement from the facet set.
    let res = results(&sys);
    let u_ro = interp(&reference, ro);
    assert!(
        (res.u_r_outer - u_ro).abs() < 5e-3 * u_ro.abs(),
        "u_r(outer) {} vs {}",
        res.u_r_outer,
        u_ro
    );
}
