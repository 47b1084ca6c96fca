//! Adaptive steady rolling (`tread adapt` on a `mode = "steady"` scene): the paper's damped,
//! frictional hollow cylinder, solved on meshes refined where the recovery estimator puts the
//! error (at the contact patch, since the steady mesh does not turn with the body).
//!
//! Against a uniform 12 × 256 reference computed here: after five refinements (about 5.6k
//! equations) the hub forces and torque are within 0.3 %, several times closer than the
//! uniform 6 × 128 mesh with more equations; the transferred steady state makes every later
//! mesh a few Newton iterations; the finest cells lie between the hub and the contact patch.

use std::path::Path;
use std::process::Command;
use tread::driver::adaptive::{run, AdaptOptions};
use tread::driver::steady_run::{build_steady, solve_steady};
use tread::io::Scene;
use tread::solver::stepping::StepReport;

const ODEN: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");

fn scene(sets: &[&str]) -> Scene {
    let mut all = vec!["analysis.mode=\"steady\"".to_string()];
    all.extend(sets.iter().map(|s| s.to_string()));
    Scene::from_toml_str(ODEN, "oden_hollow_cylinder", &all).unwrap_or_else(|e| panic!("{e}"))
}

/// Hub force x, y and torque of the steady state on the uniform n_r × n_theta mesh, with its
/// number of equations.
fn uniform(n_r: usize, n_theta: usize) -> ([f64; 3], usize) {
    let s = scene(&[
        &format!("mesh.n_r={n_r}"),
        &format!("mesh.n_theta={n_theta}"),
    ]);
    let mut st = build_steady(&s).unwrap_or_else(|e| panic!("{e}"));
    solve_steady(&s, &mut st, false, &mut StepReport::default(), &mut ())
        .unwrap_or_else(|e| panic!("{n_r} x {n_theta}: {e}"));
    let (f, m) = st.sys.hub_reaction();
    ([f[0], f[1], m], st.sys.n_dofs())
}

fn rel(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|k| ((a[k] - b[k]) / b[k]).abs())
}

#[test]
fn adaptive_steady_rolling_beats_uniform_refinement() {
    let (reference, n_ref) = uniform(12, 256);
    let (coarse_uniform, n_uniform) = uniform(6, 128);
    let s = scene(&[]);
    let opts = AdaptOptions {
        steps: 5,
        fraction: 0.5,
        ..Default::default()
    };
    let mut finest_at_patch = true;
    let res = run(&s, &opts, Path::new("unused"), |sys, st, ind| {
        assert_eq!(ind.len(), st.cells);
        // Where the finest cells are: between the hub and the contact patch (below the hub,
        // y < −Ri, within the patch's half-width ≈ √(2 Ro DISP) ≈ 0.63 of the axis).
        let mesh = &sys.model.mesh;
        let area = |c: usize| -> f64 {
            let n = mesh.cell_nodes(c);
            let p: Vec<_> = [0, 2, 8, 6]
                .iter()
                .map(|&a| mesh.nodes[n[a] as usize])
                .collect();
            0.5 * (0..4)
                .map(|k| {
                    let (a, b) = (p[k], p[(k + 1) % 4]);
                    a[0] * b[1] - a[1] * b[0]
                })
                .sum::<f64>()
                .abs()
        };
        if st.step > 0 {
            let amin = (0..mesh.n_cells()).map(area).fold(f64::INFINITY, f64::min);
            for c in (0..mesh.n_cells()).filter(|&c| area(c) < 1.01 * amin) {
                let x = mesh.nodes[mesh.cell_nodes(c)[4] as usize];
                if !(x[1] < -1.0 && x[0].abs() < 0.7) {
                    eprintln!("mesh {}: finest cell {c} at {x:?}", st.step);
                    finest_at_patch = false;
                }
            }
        }
        eprintln!(
            "{}: {} cells, {} equations, {} hanging, F = ({:.6}, {:.6}), T = {:.6}, {} Newton",
            st.step,
            st.cells,
            st.dofs,
            st.hanging_nodes,
            st.hub_force_x,
            st.hub_force_y,
            st.hub_torque,
            st.newton_iterations
        );
    });
    let (sys, steps) = res.unwrap_or_else(|e| panic!("{e}"));
    let last = steps.last().unwrap();
    let adaptive = [last.hub_force_x, last.hub_force_y, last.hub_torque];
    let (e_ad, e_un) = (rel(adaptive, reference), rel(coarse_uniform, reference));
    eprintln!(
        "reference 12 x 256 ({n_ref} eq) {reference:?}; adaptive ({} eq) errors {:?}; \
         uniform 6 x 128 ({n_uniform} eq) errors {:?}",
        last.dofs,
        e_ad.map(|e| format!("{e:.2e}")),
        e_un.map(|e| format!("{e:.2e}"))
    );
    assert_eq!(steps.len(), 6);
    assert!(last.hanging_nodes > 0 && sys.dofs.has_constraints());
    assert!(last.dofs < n_uniform, "{} vs {n_uniform}", last.dofs);
    for (k, e) in e_ad.iter().enumerate() {
        assert!(*e < 3e-3, "component {k}: adaptive error {e:.3e}");
    }
    // Force x and torque (the rolling resistance): several times closer than the uniform mesh
    // with more equations.
    for k in [0, 2] {
        assert!(
            e_ad[k] < e_un[k] / 3.0,
            "component {k}: adaptive {:.3e} vs uniform {:.3e}",
            e_ad[k],
            e_un[k]
        );
    }
    // Every later mesh starts from the transferred steady state.
    for st in &steps[1..] {
        assert!(
            st.newton_iterations <= 6,
            "mesh {}: {} Newton iterations",
            st.step,
            st.newton_iterations
        );
    }
    assert!(
        finest_at_patch,
        "the finest cells are not between the hub and the contact patch"
    );
}

#[test]
fn tread_adapt_runs_a_steady_scene_and_refuses_what_it_cannot_transfer() {
    let dir = std::env::temp_dir().join(format!("tread_adapt_steady_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let bin = env!("CARGO_BIN_EXE_tread");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let out = Command::new(bin)
        .arg("adapt")
        .arg(scenes.join("oden_hollow_cylinder.toml"))
        .args(["--set", "analysis.mode=steady", "--steps", "2", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("adaptive steady rolling: 3 meshes"));
    let csv = std::fs::read_to_string(dir.join("adapt.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].contains(",hub_torque,"), "{}", lines[0]);
    assert_eq!(lines.len(), 4, "{csv}");
    for l in &lines[1..] {
        assert!(
            l.split(',')
                .all(|v| v.parse::<f64>().is_ok_and(f64::is_finite)),
            "{l}"
        );
    }
    // A transient scene and a mesh file: exit 2 with the reason.
    for (file, why) in [
        ("free_rolling.toml", "\"steady\""),
        ("steady_footprint_refined.toml", "generated annulus"),
    ] {
        let mut cmd = Command::new(bin);
        cmd.args(["-q", "adapt"]).arg(scenes.join(file));
        let out = cmd.arg("--out").arg(dir.join("x")).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{file}: {err}");
        assert!(err.contains(why), "{file}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

const VISCO: &str = include_str!("../scenarios/viscoelastic_rolling.toml");

/// Hub load −F_y and torque of the viscoelastic scene's steady state on the uniform mesh with
/// the exact ring integration of the history, with its number of equations.
fn visco_uniform(n_r: usize, n_theta: usize) -> (f64, f64, usize) {
    let s = Scene::from_toml_str(
        VISCO,
        "viscoelastic_rolling",
        &[
            "analysis.mode=\"steady\"".to_string(),
            format!("mesh.n_r={n_r}"),
            format!("mesh.n_theta={n_theta}"),
            "solver.steady_history=\"rings\"".to_string(),
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut st = build_steady(&s).unwrap_or_else(|e| panic!("{e}"));
    solve_steady(&s, &mut st, false, &mut StepReport::default(), &mut ())
        .unwrap_or_else(|e| panic!("{n_r} x {n_theta}: {e}"));
    let (f, m) = st.sys.hub_reaction();
    (-f[1], m, st.sys.n_dofs())
}

/// Adaptive steady rolling of a viscoelastic cylinder: the internal variables are a function
/// of the steady state, integrated along the streamlines by the upwind scheme on every
/// (hanging-node) mesh, so nothing is transferred but the displacement. After eight
/// refinements (about 6.7k equations) the hub load and the rolling-resistance torque are
/// within 0.1 % and 0.3 % of the exact-ring solution on 32 × 512 (131k equations), closer than
/// the uniform 8 × 128 ring mesh with more equations.
#[test]
fn adaptive_viscoelastic_steady_rolling() {
    let (p_ref, t_ref, n_ref) = visco_uniform(32, 512);
    let (p_un, t_un, n_un) = visco_uniform(8, 128);
    let s = Scene::from_toml_str(
        VISCO,
        "viscoelastic_rolling",
        &["analysis.mode=\"steady\"".into()],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let opts = AdaptOptions {
        steps: 8,
        ..Default::default()
    };
    let (sys, steps) =
        run(&s, &opts, Path::new("unused"), |_, _, _| {}).unwrap_or_else(|e| panic!("{e}"));
    let last = steps.last().unwrap();
    let (p, t) = (-last.hub_force_y, last.hub_torque);
    let (ep, et) = ((p - p_ref).abs() / p_ref, (t - t_ref).abs() / t_ref);
    let (ep_un, et_un) = ((p_un - p_ref).abs() / p_ref, (t_un - t_ref).abs() / t_ref);
    eprintln!(
        "reference 32 x 512 rings ({n_ref} eq): P = {p_ref:.4}, T = {t_ref:.5}; adaptive ({} eq, {} hanging): \
         P = {p:.4} ({ep:.2e}), T = {t:.5} ({et:.2e}); uniform 8 x 128 ({n_un} eq): ({ep_un:.2e}, {et_un:.2e})",
        last.dofs, last.hanging_nodes
    );
    assert!(sys.model.viscoelastic.is_some() && last.hanging_nodes > 0);
    assert!(last.dofs < n_un, "{} vs {n_un}", last.dofs);
    assert!(ep < 1e-3 && et < 3e-3, "{ep:e} {et:e}");
    assert!(
        ep < ep_un && et < et_un,
        "adaptive ({ep:e}, {et:e}) vs uniform ({ep_un:e}, {et_un:e})"
    );
    for st in &steps[1..] {
        assert!(
            st.newton_iterations <= 6,
            "mesh {}: {} Newton iterations",
            st.step,
            st.newton_iterations
        );
    }
}

/// The moving mesh on the rolling footprint (`tread adapt --refine r`): the cell boundaries of
/// the scene's 4 × 64 annulus moved toward the large indicators (α = 4, β = 4, γ = 0), same
/// cells and equations: every moved mesh stays valid (boundaries in order), the cells shrink
/// at the contact patch, and after four relocations the hub loads are closer to the uniform
/// 12 × 256 reference than on the uniform mesh it started from (measured: the vertical force
/// 1.40e-2 → 1.01e-2, the torque 4.39e-2 → 3.83e-2; the target is only "lower").
#[test]
fn moving_mesh_lowers_the_error_of_the_footprint_mesh() {
    use tread::driver::adaptive::Refinement;
    let (reference, _) = uniform(12, 256);
    let s = scene(&["mesh.n_r=4", "mesh.n_theta=64"]);
    let opts = AdaptOptions {
        steps: 4,
        refinement: Refinement::R,
        ..Default::default()
    };
    let mut smallest_at_patch = Vec::new();
    let res = run(&s, &opts, Path::new("unused"), |sys, st, _| {
        let mesh = &sys.model.mesh;
        // The angular size of each column of cells (outer layer), and where the smallest is.
        let outer = mesh.facet_set("outer");
        let (mut dmin, mut at) = (f64::INFINITY, 0.0);
        for f in outer {
            let n = mesh.cell_nodes(f.cell as usize);
            let (a, b) = (mesh.nodes[n[2] as usize], mesh.nodes[n[8] as usize]);
            let mut d = b[1].atan2(b[0]) - a[1].atan2(a[0]);
            if d <= 0.0 {
                d += std::f64::consts::TAU;
            }
            assert!(d > 0.0 && d < 1.0, "mesh {}: column of {d} rad", st.step);
            if d < dmin {
                dmin = d;
                at = mesh.nodes[n[5] as usize][1].atan2(mesh.nodes[n[5] as usize][0]);
            }
        }
        smallest_at_patch.push((at + std::f64::consts::FRAC_PI_2).abs() < 0.4);
        eprintln!(
            "{}: {} equations, F = ({:.6}, {:.6}), T = {:.6}, smallest column {dmin:.4} rad at θ = {at:.3}, estimate {:.4e}",
            st.step, st.dofs, st.hub_force_x, st.hub_force_y, st.hub_torque, st.estimate
        );
    });
    let (_, steps) = res.unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(steps.len(), 5);
    assert!(steps.iter().all(|s| s.dofs == steps[0].dofs));
    let loads =
        |s: &tread::driver::adaptive::AdaptStep| [s.hub_force_x, s.hub_force_y, s.hub_torque];
    let (e0, e4) = (
        rel(loads(&steps[0]), reference),
        rel(loads(&steps[4]), reference),
    );
    eprintln!(
        "uniform 4 x 64 errors {:?}; moved errors {:?}",
        e0.map(|e| format!("{e:.2e}")),
        e4.map(|e| format!("{e:.2e}"))
    );
    assert!(
        smallest_at_patch[1..].iter().all(|&b| b),
        "{smallest_at_patch:?}"
    );
    // The vertical load and the torque (the damped rolling's resistance), the loads the mesh
    // resolves least.
    for k in [1, 2] {
        assert!(
            e4[k] < e0[k],
            "component {k}: moved {:.3e} vs uniform {:.3e}",
            e4[k],
            e0[k]
        );
    }
}
