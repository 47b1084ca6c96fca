//! Recovered (SPR) nodal Cauchy stress: exactness on homogeneous deformations and the spinning
//! annulus against its exact axisymmetric solution.

mod common;

use common::reference::{neo_hookean_omega_for_growth, neo_hookean_radial};
use tread::app::build_system;
use tread::driver::frame::nodal_stress_full_at;
use tread::driver::spinning::{results, solve_spinning};
use tread::driver::SolidSystem;
use tread::io::Scene;
use tread::physics::recovery::recover_cauchy;
use tread::solver::stepping::{StepOptions, StepReport};
use tread::solver::{LinearKind, NewtonOptions};

const RI: f64 = 1.0;
const RO: f64 = 2.0;
const RHO: f64 = 0.027;
const NEO: &str = "model = \"neo_hookean\"\nmu = 200.0\nlambda = 1800.0";

fn scene(material: &str, n_r: usize, n_theta: usize, order: usize) -> Scene {
    let text = format!(
        r#"
[scene]
name = "test"
[geometry]
ri = {RI}
ro = {RO}
[mesh]
n_r = {n_r}
n_theta = {n_theta}
order = {order}
[material]
{material}
rho = {RHO}
[analysis]
mode = "spinning"
[motion]
omega = 1.0
"#
    );
    Scene::from_toml_str(&text, "test", &[]).expect("valid test scene")
}

fn solve(sys: &mut SolidSystem, omega: f64) {
    let mut rep = StepReport::default();
    let opts = NewtonOptions {
        tol: 1e-11,
        max_iterations: 30,
        ..Default::default()
    };
    let so = StepOptions {
        initial_steps: 4,
        max_cutbacks: 8,
        verbose: false,
    };
    solve_spinning(sys, omega, LinearKind::Cholesky, opts, &so, &mut rep, &mut ())
        .expect("spinning solve converges");
}

/// σ_r = e_R·σ e_R at reference position X of the stress [σ11, σ22, σ12].
fn sigma_r(x: [f64; 2], s: [f64; 3]) -> f64 {
    let r = x[0].hypot(x[1]);
    let (c, sn) = (x[0] / r, x[1] / r);
    c * c * s[0] + sn * sn * s[1] + 2.0 * c * sn * s[2]
}

/// Spinning annulus: largest relative error of σ_r over the hub nodes, raw (cell values averaged
/// at the nodes) and recovered, the summary's ring average, DOFs.
#[test]
fn spinning_recovered_sigma_r_converges_faster() {
    let omega = neo_hookean_omega_for_growth(RI, RO, 1800.0, 200.0, RHO, 0.05).expect("omega");
    let refsol = neo_hookean_radial(RI, RO, 1800.0, 200.0, RHO, omega).expect("reference");
    let s_ref = refsol.sigma_r(RI);
    let mut rows = Vec::new();
    for n_r in [1usize, 2, 4, 8, 12] {
        let n_t = (8 * n_r).max(8);
        let mut sys = build_system(&scene(NEO, n_r, n_t, 2)).unwrap();
        solve(&mut sys, omega);
        let mesh = &sys.model.mesh;
        let raw = nodal_stress_full_at(&sys, &sys.x).in_plane;
        let rec = recover_cauchy(&sys.model, &sys.dofs, &sys.x);
        let (mut e_raw, mut e_rec) = (0.0f64, 0.0f64);
        for &n in mesh.node_set("hub") {
            let n = n as usize;
            let x = [mesh.nodes[n][0], mesh.nodes[n][1]];
            e_raw = e_raw.max((sigma_r(x, raw[n]) - s_ref).abs() / s_ref.abs());
            let r = rec[n];
            e_rec = e_rec.max((sigma_r(x, [r[0], r[1], r[2]]) - s_ref).abs() / s_ref.abs());
        }
        let samples = tread::physics::recovery::cauchy_samples(&sys.model, &sys.dofs, &sys.x);
        let mut e_gp = 0.0f64;
        for cs in &samples {
            for i in 0..cs.n {
                let x = [cs.x[i][0], cs.x[i][1]];
                let r = x[0].hypot(x[1]);
                let sr = sigma_r(x, [cs.s[i][0], cs.s[i][1], cs.s[i][2]]);
                e_gp = e_gp.max((sr - refsol.sigma_r(r)).abs() / s_ref.abs());
            }
        }
        let mut exact = samples.clone();
        for cs in exact.iter_mut() {
            for i in 0..cs.n {
                let (x, y) = (cs.x[i][0], cs.x[i][1]);
                let r = x.hypot(y);
                let (c, sn) = (x / r, y / r);
                let (a, b) = (refsol.sigma_r(r), refsol.sigma_theta(r));
                cs.s[i] = [a * c * c + b * sn * sn, a * sn * sn + b * c * c, (a - b) * c * sn, 0.0];
            }
        }
        let rex = tread::physics::recovery::recover_nodal(&sys.model.mesh, &exact);
        let mut e_fit = 0.0f64;
        for &n in sys.model.mesh.node_set("hub") {
            let n = n as usize;
            let x = [sys.model.mesh.nodes[n][0], sys.model.mesh.nodes[n][1]];
            let r = rex[n];
            e_fit = e_fit.max((sigma_r(x, [r[0], r[1], r[2]]) - s_ref).abs() / s_ref.abs());
        }
        eprintln!("{n_r}: max Gauss-point σ_r error {e_gp:.3e}, recovery of exact samples {e_fit:.3e}");
        // Hub vertices only and the ring average of the interpolated recovered field.
        let mut e_vert = 0.0f64;
        let (mut len, mut avg) = (0.0, 0.0);
        let (gp, gw) = tread::element::gauss_1d(4);
        for f in mesh.facet_set("hub") {
            let c = f.cell as usize;
            let p = mesh.degree[c] as usize;
            let nodes = mesh.cell_nodes(c);
            let ln = f.local_nodes(p);
            for &k in &[ln[0], ln[p]] {
                let n = nodes[k] as usize;
                let x = [mesh.nodes[n][0], mesh.nodes[n][1]];
                let r = rec[n];
                e_vert = e_vert.max((sigma_r(x, [r[0], r[1], r[2]]) - s_ref).abs() / s_ref.abs());
            }
            for (t, w) in gp.iter().zip(&gw) {
                let (lv, _) = tread::element::lagrange_1d(p, *t);
                let (mut x, mut sr) = ([0.0; 2], [0.0; 3]);
                for i in 0..=p {
                    let n = nodes[ln[i]] as usize;
                    x[0] += lv[i] * mesh.nodes[n][0];
                    x[1] += lv[i] * mesh.nodes[n][1];
                    for j in 0..3 {
                        sr[j] += lv[i] * rec[n][j];
                    }
                }
                len += w;
                avg += w * sigma_r(x, sr);
            }
        }
        eprintln!("{n_r}: recovered σ_r error: hub vertices {e_vert:.3e}, ring average {:.3e}", (avg / len - s_ref).abs() / s_ref.abs());
        let ring = (results(&sys).sigma_r_inner - s_ref).abs() / s_ref.abs();
        rows.push((n_r, n_t, sys.n_dofs(), e_raw, ring, e_rec));
    }
    eprintln!("mesh     DOFs   raw nodal   rate   ring avg    rate   recovered   rate");
    for (i, r) in rows.iter().enumerate() {
        let rate = |f: fn(&(usize, usize, usize, f64, f64, f64)) -> f64| {
            if i == 0 {
                f64::NAN
            } else {
                let p = &rows[i - 1];
                -2.0 * (f(r) / f(p)).ln() / (r.2 as f64 / p.2 as f64).ln()
            }
        };
        eprintln!(
            "{:2}x{:<3} {:6}  {:.3e} {:5.2}  {:.3e} {:5.2}  {:.3e} {:5.2}",
            r.0,
            r.1,
            r.2,
            r.3,
            rate(|r| r.3),
            r.4,
            rate(|r| r.4),
            r.5,
            rate(|r| r.5)
        );
    }
}
