//! The three-dimensional solid on revolved hexahedral meshes: its global tangent against finite
//! differences of the residual, the plane-strain limit against the 2D program, spinning against
//! the independent radial solution, and a manufactured solution with observed rates.

mod common;

use common::reference::neo_hookean_radial;
use tread::app::build_system;
use tread::driver::spinning::solve_spinning;
use tread::driver::spinning3d::solve_spinning_3d;
use tread::material::{Hyperelastic, Material, MaterialKind};
use tread::math::Mat3;
use tread::mesh::revolved::{revolved, RevolvedSpec};
use tread::model::{Coefficients, Solid3D, Solid3DSystem};
use tread::physics::PressureMode;
use tread::solver::observe::NoObserver;
use tread::solver::stepping::{solve_load_steps, StepOptions, StepReport};
use tread::solver::{LinearKind, Newton, NewtonOptions, NonlinearSystem};

const RI: f64 = 1.0;
const RO: f64 = 2.0;
const RHO: f64 = 0.027;

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

fn newton_opts() -> NewtonOptions {
    NewtonOptions {
        tol: 1e-11,
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

fn tangent_check(material: Material, pressure: PressureMode, degree: usize) -> f64 {
    let mesh = revolved(&spec(1, 1, 6, degree, 0.4)).expect("mesh");
    let fx = fixed(&mesh, false);
    let mut sys = Solid3DSystem::new(Solid3D::new(mesh, material, RHO, pressure), &fx);
    sys.coefficients = Coefficients {
        omega2: 900.0,
        ..Default::default()
    };
    let n = sys.n_eq();
    let dx: Vec<f64> = (0..n).map(|k| 0.03 * noise(k)).collect();
    sys.update(1.0, &dx);
    assert!(sys.evaluate(true));
    let dense = sys.asm.to_dense();
    let mut worst: f64 = 0.0;
    let scale = dense.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let h = 1e-6;
    let mut e = vec![0.0; n];
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
    worst
}

#[test]
fn global_tangent_matches_finite_differences() {
    let mri = MaterialKind::MooneyRivlinIncompressible.build(&[80.0, 20.0]);
    let cases = [
        ("neo-Hookean Hex8", neo_hookean(), PressureMode::None, 1),
        ("neo-Hookean Hex27", neo_hookean(), PressureMode::None, 2),
        (
            "Mooney-Rivlin incompressible, exact, Hex27",
            mri,
            PressureMode::Exact { p0: 0.0 },
            2,
        ),
        (
            "Mooney-Rivlin incompressible, perturbed, Hex27",
            mri,
            PressureMode::Perturbed {
                kappa: 2.0e4,
                p0: 0.0,
            },
            2,
        ),
    ];
    for (name, m, p, deg) in cases {
        let err = tangent_check(m, p, deg);
        eprintln!("{name}: worst |K − K_fd| / max|K| = {err:.2e}");
        assert!(err < 1e-6, "{name}: tangent error {err:.3e}");
    }
}

/// The 2D spinning solution on the annulus with the same radial and angular breaks.
fn spin_2d(n_r: usize, n_theta: usize, omega: f64) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
    let sc = common::spinning_scene(
        "model = \"neo_hookean\"\nmu = 200.0\nlambda = 1800.0",
        &format!("n_r = {n_r}\nn_theta = {n_theta}\norder = 2"),
    );
    let mut sys = build_system(&sc).expect("2D system");
    let mut rep = StepReport::default();
    solve_spinning(
        &mut sys,
        omega,
        LinearKind::Cholesky,
        newton_opts(),
        &steps(4),
        &mut rep,
        &mut (),
    )
    .expect("2D spinning converges");
    let nodes = sys.model.mesh.nodes.iter().map(|x| [x[0], x[1]]).collect();
    let u = (0..sys.model.mesh.n_nodes())
        .map(|n| [sys.x[2 * n], sys.x[2 * n + 1]])
        .collect();
    (nodes, u)
}

fn spin_3d(s: &RevolvedSpec, omega: f64) -> Solid3DSystem {
    let mut mesh = revolved(s).expect("mesh");
    // Isoparametric cells, as the plane-strain program builds them.
    mesh.make_isoparametric();
    let fx = fixed(&mesh, true);
    let mut sys = Solid3DSystem::new(
        Solid3D::new(mesh, neo_hookean(), RHO, PressureMode::None),
        &fx,
    );
    let mut rep = StepReport::default();
    solve_spinning_3d(
        &mut sys,
        omega,
        LinearKind::Cholesky,
        newton_opts(),
        &steps(4),
        &mut rep,
        &mut NoObserver,
    )
    .expect("3D spinning converges");
    sys
}

#[test]
fn plane_strain_slab_reproduces_the_2d_spinning_field() {
    let omega = 60.0;
    let (n_r, n_theta) = (3, 24);
    let (nodes2, u2) = spin_2d(n_r, n_theta, omega);
    let sys = spin_3d(&spec(n_r, 2, n_theta, 2, 0.3), omega);
    let key = |x: f64, y: f64| ((x * 1e9).round() as i64, (y * 1e9).round() as i64);
    let index: std::collections::HashMap<_, _> = nodes2
        .iter()
        .enumerate()
        .map(|(i, x)| (key(x[0], x[1]), i))
        .collect();
    let umax = u2.iter().map(|u| u[0].hypot(u[1])).fold(0.0f64, f64::max);
    let mut worst: f64 = 0.0;
    for (n, x) in sys.solid.mesh.nodes.iter().enumerate() {
        let i = *index
            .get(&key(x[0], x[1]))
            .expect("every 3D node lies over a 2D node");
        let u = sys.node_displacement(n);
        worst = worst
            .max((u[0] - u2[i][0]).abs())
            .max((u[1] - u2[i][1]).abs())
            .max(u[2].abs());
    }
    eprintln!(
        "plane-strain slab: max |u_3D − u_2D| / max|u| = {:.2e}",
        worst / umax
    );
    assert!(
        worst / umax < 1e-8,
        "slab differs from 2D: {:.3e}",
        worst / umax
    );
}

#[test]
fn spinning_slab_converges_to_the_radial_solution() {
    let omega = 104.443315253851; // 5 % radial growth of the outer surface
    let refsol = neo_hookean_radial(RI, RO, 1800.0, 200.0, RHO, omega).expect("reference");
    let u_ref = refsol.u(RO);
    for degree in [1, 2] {
        let mut errs = Vec::new();
        for n_r in [2, 4, 8] {
            let sys = spin_3d(&spec(n_r, 1, 8 * n_r, degree, 0.2), omega);
            let outer = sys.solid.mesh.node_set("outer");
            // The mean radial displacement of the outer nodes (every node on a circle of
            // nodes counts once; the θ-interpolation error averages out as in the 2D ring mean).
            let mut ur = 0.0;
            for &n in outer {
                let x = sys.solid.mesh.nodes[n as usize];
                let u = sys.node_displacement(n as usize);
                ur += (u[0] * x[0] + u[1] * x[1]) / x[0].hypot(x[1]);
            }
            let e = (ur / outer.len() as f64 - u_ref).abs() / u_ref;
            eprintln!("degree {degree}, n_r = {n_r}: |mean u_r(Ro) − ref| / ref = {e:.3e}");
            errs.push(e);
        }
        let rate = (errs[1] / errs[2]).log2();
        eprintln!("degree {degree}: observed rate of u_r(Ro) {rate:.2}");
        assert!(
            errs[2] < errs[1] && errs[1] < errs[0],
            "no convergence: {errs:?}"
        );
        // Displacements converge at h^{p+1} (polar maps: no geometry error).
        assert!(
            rate > degree as f64 + 0.7,
            "rate {rate:.2} below {}",
            degree + 1
        );
    }
}

/// u*(X): a smooth 3D field (all components, all coordinates).
fn u_star(x: [f64; 3]) -> [f64; 3] {
    let a = 0.02;
    [
        a * (x[0] * x[1]).sin() + a * x[2] * x[2],
        a * (0.5 * x[0] + x[2]).cos() * x[1],
        a * (x[0] + x[1] + 2.0 * x[2]).sin(),
    ]
}

fn grad_star(x: [f64; 3]) -> Mat3 {
    let h = 1e-5;
    let mut g = Mat3::zeros();
    for j in 0..3 {
        let (mut p, mut m) = (x, x);
        p[j] += h;
        m[j] -= h;
        let (up, um) = (u_star(p), u_star(m));
        for i in 0..3 {
            g[(i, j)] = (up[i] - um[i]) / (2.0 * h);
        }
    }
    g
}

#[test]
fn manufactured_solution_converges_at_optimal_rates() {
    let mat = neo_hookean();
    // b = −Div P(∇u*), by central differences of P along each coordinate.
    let body = move |x: [f64; 3]| -> [f64; 3] {
        let h = 1e-4;
        let mut b = [0.0; 3];
        for j in 0..3 {
            let (mut p, mut m) = (x, x);
            p[j] += h;
            m[j] -= h;
            let pp = <Material as Hyperelastic<Mat3>>::stress(&mat, &grad_star(p));
            let pm = <Material as Hyperelastic<Mat3>>::stress(&mat, &grad_star(m));
            for i in 0..3 {
                b[i] -= (pp[(i, j)] - pm[(i, j)]) / (2.0 * h);
            }
        }
        b
    };
    for degree in [1, 2] {
        let mut rows = Vec::new();
        for level in 0..3 {
            let n = 1 << level;
            let mesh = revolved(&spec(n, n, 12 * n, degree, 0.5)).expect("mesh");
            // Dirichlet data u* on the whole boundary.
            let mut fx = vec![false; 3 * mesh.n_nodes()];
            for set in ["hub", "outer", "side_neg", "side_pos"] {
                for &k in mesh.node_set(set) {
                    fx[3 * k as usize..3 * k as usize + 3].fill(true);
                }
            }
            let mut solid = Solid3D::new(mesh, neo_hookean(), RHO, PressureMode::None);
            solid.body_force = Some(Box::new(body));
            let mut sys = Solid3DSystem::new(solid, &fx);
            for (k, x) in sys.solid.mesh.nodes.iter().enumerate() {
                if fx[3 * k] {
                    let u = u_star([x[0], x[1], x[2]]);
                    sys.x[3 * k..3 * k + 3].copy_from_slice(&u);
                }
            }
            sys.set_target(Coefficients {
                body_load: 1.0,
                ..Default::default()
            });
            sys.set_reference_force(1.0);
            let mut newton =
                Newton::new(&sys, LinearKind::Cholesky, newton_opts()).expect("analysis");
            let mut rep = StepReport::default();
            solve_load_steps(&mut sys, &mut newton, &steps(1), &mut rep, &mut NoObserver)
                .expect("MMS solve converges");
            let (l2, h1) = errors(&sys);
            eprintln!(
                "degree {degree}, level {level}: {} dofs, L2 {l2:.3e}, H1 {h1:.3e}",
                sys.n_eq()
            );
            rows.push((l2, h1));
        }
        let rl2 = (rows[1].0 / rows[2].0).log2();
        let rh1 = (rows[1].1 / rows[2].1).log2();
        eprintln!("degree {degree}: observed rates L2 {rl2:.2}, H1 {rh1:.2}");
        let p = degree as f64;
        assert!(rl2 > p + 1.0 - 0.3, "L2 rate {rl2:.2} (degree {degree})");
        assert!(rh1 > p - 0.3, "H1 rate {rh1:.2} (degree {degree})");
    }
}

/// L2 and H1-seminorm errors against u*, with a 4-point Gauss rule per direction.
fn errors(sys: &Solid3DSystem) -> (f64, f64) {
    let (pts, ws) = tread::element::gauss_1d(4);
    let (mut l2, mut h1) = (0.0, 0.0);
    for c in 0..sys.solid.mesh.n_cells() {
        for (k, wk) in pts.iter().zip(&ws) {
            for (j, wj) in pts.iter().zip(&ws) {
                for (i, wi) in pts.iter().zip(&ws) {
                    let xi = [*i, *j, *k];
                    let (_, jac) = sys.solid.mesh.map(c, xi);
                    let w = wi * wj * wk * jac.determinant();
                    let pv = sys
                        .solid
                        .point_values(c, &sys.dofs, &sys.x, xi)
                        .expect("admissible");
                    let x = [pv.x[0], pv.x[1], pv.x[2]];
                    let us = u_star(x);
                    let gs = grad_star(x);
                    for a in 0..3 {
                        l2 += (pv.u[a] - us[a]).powi(2) * w;
                        for b in 0..3 {
                            h1 += (pv.grad_u[(a, b)] - gs[(a, b)]).powi(2) * w;
                        }
                    }
                }
            }
        }
    }
    (l2.sqrt(), h1.sqrt())
}

#[test]
fn plane_strain_slab_reproduces_the_2d_indentation() {
    use tread::contact::facet3d::ContactSurface3D;
    use tread::contact::{ContactModel, FacetRule, Friction, NormalCompliance};
    use tread::driver::indentation::{results, solve_indentation};
    use tread::mesh::{annulus, AnnulusSpec};
    use tread::model::system::Loading;
    use tread::model::SolidSystem;
    use tread::physics::SolidModel;
    let (n_r, n_theta, grading_theta, disp, c_n, width) = (3, 32, 0.6, 0.05, 2.0e4, 0.25);
    let normal = NormalCompliance::new(c_n, 1.0, 0.0, 0.0);
    // 2D: the exact polar cells of the annulus, frictionless, displacement control.
    let mesh2 = annulus(&AnnulusSpec {
        ri: RI,
        ro: RO,
        n_r,
        n_theta,
        degree: 2,
        grading_r: 1.0,
        grading_theta,
    });
    let model = SolidModel::new(mesh2, neo_hookean(), 1.0, PressureMode::None);
    let cm = ContactModel::new(
        &model.mesh,
        RO,
        0.0,
        normal,
        Friction::None,
        FacetRule::Gauss(4),
        None,
    );
    let mut s2 = SolidSystem::with_contact(model, cm);
    s2.loading = Loading::Indent { h_touch: RO, disp };
    let mut rep = StepReport::default();
    solve_indentation(
        &mut s2,
        LinearKind::Cholesky,
        newton_opts(),
        &steps(4),
        &mut rep,
        &mut (),
    )
    .expect("2D indentation converges");
    let r2 = results(&s2, RO);
    // 3D: the slab with u3 = 0 on its faces, on the same (r, θ) mesh with the exact cylindrical
    // cells.
    let mut s = spec(n_r, 2, n_theta, 2, width);
    s.grading_theta = grading_theta;
    let mesh = revolved(&s).expect("mesh");
    let fx = fixed(&mesh, true);
    let surface = ContactSurface3D::new(
        mesh.facet_set("outer").to_vec(),
        RO,
        nalgebra::Vector2::zeros(),
        normal,
        Friction::None,
        FacetRule::Gauss(4),
    )
    .expect("contact surface");
    let mut s3 = Solid3DSystem::new(
        Solid3D::new(mesh, neo_hookean(), 1.0, PressureMode::None),
        &fx,
    )
    .with_contact(surface, RO, disp)
    .expect("contact on the mesh");
    s3.set_reference_force(200.0 * disp * width);
    let mut newton = Newton::new(&s3, LinearKind::Cholesky, newton_opts()).expect("analysis");
    let mut rep3 = StepReport::default();
    solve_load_steps(&mut s3, &mut newton, &steps(4), &mut rep3, &mut NoObserver)
        .expect("3D indentation converges");
    s3.evaluate(false);
    let f3 = s3.contact.as_ref().expect("contact").totals.force;
    let (fy2, fy3) = (r2.contact_force_y, f3[1] / width);
    eprintln!(
        "contact force per width: 2D {fy2:.12e}, 3D {fy3:.12e}; 3D lateral {:.2e}",
        f3[2]
    );
    assert!(
        (fy3 - fy2).abs() <= 1e-8 * fy2.abs(),
        "contact force per width {fy3} vs 2D {fy2}"
    );
    assert!(f3[2].abs() <= 1e-10 * fy2.abs() * width);
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
        "indentation slab: max |u_3D − u_2D| / max|u| = {:.2e}",
        worst / umax
    );
    assert!(
        worst / umax < 1e-8,
        "slab field differs from 2D: {:.3e}",
        worst / umax
    );
}
