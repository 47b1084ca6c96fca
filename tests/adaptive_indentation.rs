//! Adaptive static indentation (solve → ZZ estimate → Dörfler marking → refinement with
//! hanging nodes → transfer) on the paper's cylinder pressed 0.1 in into a frictionless road.

use std::path::Path;
use std::process::Command;
use tread::driver::adaptive::{indentation_system, polar_root, run, solve_static, AdaptOptions};
use tread::driver::indentation;
use tread::io::Scene;

fn scene(sets: &[&str]) -> Scene {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/indentation_frictionless.toml"),
    )
    .unwrap();
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(&text, "indentation_frictionless", &sets).unwrap()
}

/// Equilibrium with hanging nodes (hub force = −contact force), the estimator's optimal rate
/// N^−1 for Q2, and a hub force that converges faster in the number of equations than on the
/// uniformly refined structured mesh.
#[test]
fn adaptive_indentation_converges_at_the_optimal_rate() {
    let s = scene(&["mesh.n_r=2", "mesh.n_theta=32", "mesh.grading_theta=0"]);
    let opts = AdaptOptions {
        steps: 14,
        fraction: 0.5,
        ..Default::default()
    };
    let mut equilibrium = 0.0f64;
    let (_, steps) = run(&s, &opts, Path::new("unused"), |sys, st, ind| {
        let r = indentation::results(sys, 2.0);
        let e =
            (r.hub_force_y + r.contact_force_y).abs() + (r.hub_force_x + r.contact_force_x).abs();
        equilibrium = equilibrium.max(e / r.contact_force_y.abs());
        assert_eq!(ind.len(), st.cells);
        eprintln!(
            "{:2}: {:5} cells {:6} eqs {:4} hanging level {} eta_rel {:.3e} F_y {:.10e}",
            st.step,
            st.cells,
            st.dofs,
            st.hanging_nodes,
            st.max_level,
            st.relative_estimate,
            st.hub_force_y
        );
    })
    .unwrap();
    assert_eq!(steps.len(), 15);
    assert!(
        equilibrium < 1e-10,
        "hub force + contact force = {equilibrium:.2e} relative"
    );
    assert!(steps.iter().skip(1).all(|s| s.hanging_nodes > 0));
    // Estimator rate over the last six meshes: Q2 adaptive, η ∝ N^−1 (measured 0.99).
    let (a, b) = (&steps[8], &steps[14]);
    let rate = -(b.estimate / a.estimate).ln() / (b.dofs as f64 / a.dofs as f64).ln();
    eprintln!("estimator rate in N over steps 8..14: {rate:.3}");
    assert!((rate - 1.0).abs() < 0.15, "estimator rate {rate:.3}");
    // Hub force: the adaptive mesh nearest 8k equations against the finest adaptive one, and
    // the uniform 8 × 128 mesh (8,192 equations) against the same.
    let fine = steps[14].hub_force_y;
    let near = steps
        .iter()
        .min_by_key(|s| (s.dofs as i64 - 8192).abs())
        .unwrap();
    let adaptive_err = (near.hub_force_y - fine).abs() / fine.abs();
    let u = scene(&["mesh.n_r=8", "mesh.n_theta=128", "mesh.grading_theta=0"]);
    let mut sys = indentation_system(&u, polar_root(&u).unwrap()).unwrap();
    solve_static(&u, &mut sys, false, None, Path::new("unused")).unwrap();
    let uniform = indentation::results(&sys, 2.0).hub_force_y;
    let uniform_err = (uniform - fine).abs() / fine.abs();
    eprintln!(
        "against the finest adaptive mesh ({} eqs): adaptive {} eqs {adaptive_err:.2e}, uniform {} eqs {uniform_err:.2e}",
        steps[14].dofs,
        near.dofs,
        sys.n_dofs()
    );
    assert!(
        adaptive_err < 5e-5,
        "adaptive hub force error {adaptive_err:.2e}"
    );
    assert!(near.dofs <= sys.n_dofs() + 1000);
    assert!(
        uniform_err > 2.0 * adaptive_err,
        "uniform {uniform_err:.2e} vs adaptive {adaptive_err:.2e}"
    );
}

/// The interpolation estimator drives the loop as well: its estimate also falls like N^−1
/// (measured 0.996 over steps 6–12) and the hub force at ≈ 18k equations is within 1e-5 of the
/// recovery-driven sequence's finest value.
#[test]
fn interpolation_estimator_drives_the_loop_at_the_optimal_rate() {
    use tread::driver::adaptive::SolidEstimator;
    let s = scene(&["mesh.n_r=2", "mesh.n_theta=32", "mesh.grading_theta=0"]);
    let opts = AdaptOptions {
        estimator: SolidEstimator::Interpolation,
        steps: 12,
        ..Default::default()
    };
    let (_, steps) = run(&s, &opts, Path::new("unused"), |_, _, _| {}).unwrap();
    let (a, b) = (&steps[6], &steps[12]);
    let rate = -(b.estimate / a.estimate).ln() / (b.dofs as f64 / a.dofs as f64).ln();
    // The finest mesh of the recovery-driven test (34,592 equations).
    let fine = -85.978564335;
    let err = (b.hub_force_y - fine).abs() / fine.abs();
    eprintln!(
        "interpolation-driven: rate {rate:.3}, {} equations, F_y {:.10e} ({err:.2e})",
        b.dofs, b.hub_force_y
    );
    assert!((rate - 1.0).abs() < 0.15, "rate {rate:.3}");
    assert!(err < 1e-5, "hub force {err:.2e}");
}

/// The explicit residual estimator, with the contact traction as the boundary data of the
/// contact facets, drives the loop too: its indicator falls at the optimal rate N^−1, the hub
/// force reaches the same value, and its ratio to the ZZ estimate of the same states stays
/// bounded (an efficient and reliable indicator up to its constant).
#[test]
fn explicit_estimator_with_contact_tractions_drives_the_loop() {
    use tread::driver::adaptive::SolidEstimator;
    use tread::physics::estimate::recovery;
    let s = scene(&["mesh.n_r=2", "mesh.n_theta=32", "mesh.grading_theta=0"]);
    let opts = AdaptOptions {
        estimator: SolidEstimator::Explicit,
        steps: 12,
        ..Default::default()
    };
    let mut ratio = Vec::new();
    let (_, steps) = run(&s, &opts, Path::new("unused"), |sys, st, _| {
        let zz = recovery(&sys.model, &sys.dofs, &sys.x).global;
        ratio.push(st.estimate / zz);
        eprintln!(
            "{:2}: {:6} eqs explicit {:.4e} ZZ {zz:.4e} ratio {:.3} F_y {:.10e}",
            st.step,
            st.dofs,
            st.estimate,
            st.estimate / zz,
            st.hub_force_y
        );
    })
    .unwrap();
    let (a, b) = (&steps[6], &steps[12]);
    let rate = -(b.estimate / a.estimate).ln() / (b.dofs as f64 / a.dofs as f64).ln();
    let fine = -85.978564335;
    let err = (b.hub_force_y - fine).abs() / fine.abs();
    let (lo, hi) = ratio[4..]
        .iter()
        .fold((f64::MAX, 0.0f64), |(l, h), &r| (l.min(r), h.max(r)));
    eprintln!(
        "explicit-driven: rate {rate:.3}, hub force {err:.2e}, explicit / ZZ in [{lo:.3}, {hi:.3}]"
    );
    assert!((rate - 1.0).abs() < 0.15, "rate {rate:.3}");
    assert!(err < 1e-5, "hub force {err:.2e}");
    assert!(
        lo > 1.0 && hi / lo < 1.5,
        "explicit / ZZ in [{lo:.3}, {hi:.3}]"
    );
}

/// Load control (the road height is a global unknown): the transfer carries it over, so every
/// refined mesh converges from the transferred state in a few Newton iterations, with the hub
/// load as prescribed and the penetration settling (measured 0.222725 → 0.222791 in over four
/// refinements, 3–4 iterations each).
#[test]
fn load_control_carries_the_road_height_across_meshes() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/indentation_load_control.toml"),
    )
    .unwrap();
    let s = Scene::from_toml_str(&text, "indentation_load_control", &[]).unwrap();
    let opts = AdaptOptions {
        steps: 3,
        ..Default::default()
    };
    let (_, steps) = run(&s, &opts, Path::new("unused"), |_, _, _| {}).unwrap();
    assert_eq!(steps.len(), 4);
    for st in &steps[1..] {
        eprintln!(
            "{}: {} eqs, {} iterations, DISP {:.9e}",
            st.step, st.dofs, st.newton_iterations, st.penetration
        );
        assert!(
            st.newton_iterations <= 8,
            "{} iterations",
            st.newton_iterations
        );
        assert!((st.hub_force_y + 300.0).abs() < 1e-6);
        assert!((st.penetration - steps[0].penetration).abs() < 1e-3 * steps[0].penetration);
    }
}

/// With friction the static solution depends on the load path: every adaptive mesh is solved
/// by load stepping from the undeformed state, so its hub force equals that of an independent
/// load-stepped solve on the same mesh (a warm start at the full load gave 0.13 % more).
#[test]
fn frictional_adaptive_meshes_follow_the_load_path() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/indentation_friction.toml"),
    )
    .unwrap();
    let sets: Vec<String> = ["mesh.n_r=2", "mesh.n_theta=32", "mesh.grading_theta=0"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let s = Scene::from_toml_str(&text, "indentation_friction", &sets).unwrap();
    let opts = AdaptOptions {
        steps: 2,
        ..Default::default()
    };
    let mut last = None;
    let (_, steps) = run(&s, &opts, Path::new("unused"), |sys, st, _| {
        last = Some((sys.model.mesh.clone(), st.hub_force_x, st.hub_force_y));
    })
    .unwrap();
    assert_eq!(steps.len(), 3);
    let (mesh, fx, fy) = last.unwrap();
    assert!(!mesh.constraints.is_empty());
    let mut sys = indentation_system(&s, mesh).unwrap();
    solve_static(&s, &mut sys, false, None, Path::new("unused")).unwrap();
    let r = indentation::results(&sys, 2.0);
    let d = (r.hub_force_x - fx).hypot(r.hub_force_y - fy) / fy.abs();
    eprintln!(
        "adaptive ({fx:.9e}, {fy:.9e}) vs load-stepped ({:.9e}, {:.9e}): {d:.2e}",
        r.hub_force_x, r.hub_force_y
    );
    assert!(d < 1e-8, "{d:.3e}");
}

#[test]
fn tread_adapt_writes_its_table_and_meshes_and_rejects_other_modes() {
    let dir = std::env::temp_dir().join(format!("tread_adapt_cli_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let bin = env!("CARGO_BIN_EXE_tread");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let out = Command::new(bin)
        .args(["-q", "adapt"])
        .arg(scenes.join("indentation_frictionless.toml"))
        .args([
            "--steps",
            "2",
            "--set",
            "mesh.n_r=2",
            "--set",
            "mesh.n_theta=32",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("adapt.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].starts_with("step,cells,dofs,hanging_nodes"));
    assert_eq!(lines.len(), 4, "{csv}");
    for l in &lines[1..] {
        assert!(
            l.split(',')
                .all(|v| v.parse::<f64>().is_ok_and(f64::is_finite)),
            "{l}"
        );
    }
    for k in 0..3 {
        let vtu = std::fs::read(dir.join(format!("adapt_{k:03}.vtu"))).unwrap();
        assert!(String::from_utf8_lossy(&vtu).contains("Name=\"error_indicator\""));
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("adapt.json")).unwrap()).unwrap();
    assert_eq!(json["steps"].as_array().unwrap().len(), 3);
    // Not a static scene: exit 2 with the reason.
    let out = Command::new(bin)
        .args(["-q", "adapt"])
        .arg(scenes.join("spinning_neo_hookean.toml"))
        .arg("--out")
        .arg(dir.join("x"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("analysis.mode = \"static\""));
    let out = Command::new(bin)
        .args(["-q", "adapt"])
        .arg(scenes.join("indentation_frictionless.toml"))
        .args(["--fraction", "0", "--out"])
        .arg(dir.join("y"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("Dörfler fraction"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Coarsening: with a Dörfler fraction of 0.95 the loop refines almost every cell; with a
/// coarsening fraction of 0.1 the families whose indicators have become small merge back. The
/// coarsened sequence ends with fewer equations and a smaller estimate × equations (the Q2
/// optimum makes that constant), its hub force stays as close to the reference, and the merged
/// mesh's transferred state is a good start (few Newton iterations).
#[test]
fn coarsening_sheds_cells_whose_error_is_small() {
    let s = scene(&["mesh.n_r=2", "mesh.n_theta=32", "mesh.grading_theta=0"]);
    let runs: Vec<_> = [0.0, 0.5]
        .iter()
        .map(|&coarsen| {
            let opts = AdaptOptions {
                steps: 4,
                fraction: 0.5,
                uniform: 2,
                coarsen,
                ..Default::default()
            };
            let (_, steps) = run(&s, &opts, Path::new("unused"), |_, st, _| {
                eprintln!(
                    "c = {coarsen}: {:2}: {:5} cells {:6} eqs merged {:3} eta {:.3e} F_y {:.10e} newton {}",
                    st.step, st.cells, st.dofs, st.coarsened, st.estimate, st.hub_force_y, st.newton_iterations
                );
            })
            .unwrap();
            steps
        })
        .collect();
    let (plain, coarse) = (runs[0].last().unwrap(), runs[1].last().unwrap());
    let merged: usize = runs[1].iter().map(|s| s.coarsened).sum();
    assert!(merged > 0, "nothing coarsened");
    assert!(runs[0].iter().all(|s| s.coarsened == 0));
    assert!(
        coarse.dofs < plain.dofs,
        "{} vs {} equations",
        coarse.dofs,
        plain.dofs
    );
    let work = |s: &tread::driver::adaptive::AdaptStep| s.estimate * s.dofs as f64;
    assert!(
        work(coarse) < work(plain),
        "eta N {:.3e} vs {:.3e}",
        work(coarse),
        work(plain)
    );
    // Reference hub force: the adaptive extrapolation of the benchmark (-85.978511).
    let reference = -85.978511;
    let err =
        |s: &tread::driver::adaptive::AdaptStep| ((s.hub_force_y - reference) / reference).abs();
    assert!(
        err(coarse) < 3.0 * err(plain).max(1e-6),
        "{:.2e} vs {:.2e}",
        err(coarse),
        err(plain)
    );
    assert!(runs[1].iter().skip(1).all(|s| s.newton_iterations <= 6));
}

/// Uniform refinements that would outgrow `max_dofs` are refused before any mesh is built
/// (12 refinements of the scene's 576 cells would be some 7.7e10 equations).
#[test]
fn too_many_uniform_refinements_are_refused_up_front() {
    let s = scene(&[]);
    let opts = AdaptOptions {
        uniform: 12,
        ..Default::default()
    };
    let e = run(&s, &opts, Path::new("unused"), |_, _, _| {})
        .err()
        .expect("refused")
        .to_string();
    assert!(
        e.contains("uniform refinements") && e.contains("--max-dofs"),
        "{e}"
    );
    let opts = AdaptOptions {
        uniform: 40,
        ..Default::default()
    };
    let e = run(&s, &opts, Path::new("unused"), |_, _, _| {})
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("too many"), "{e}");
}

/// hp-refinement from Q1 (marked Q1 cells raised to Q2, marked Q2 cells split): against the
/// finest mesh of the h-adaptive Q2 loop, the hub force on the hp mesh nearest 8k equations is
/// more than five times closer than the h-adaptive Q1 loop's at four times the equations, and the
/// estimate falls like N^−1 once the cells are Q2. p alone stops when every marked cell is Q2.
/// A Q2 start or an incompressible material is refused. Measured: hp 5.7e-5 at 8,636
/// equations, h-Q1 4.9e-4 at 33,728; hp estimate rate 1.07 (steps 8–13).
#[test]
fn hp_refinement_from_q1_beats_h_refinement() {
    use tread::driver::adaptive::Refinement;
    let q1 = scene(&["mesh.order=1"]);
    let loop_of = |s: &Scene, refinement, steps, max_dofs| {
        let opts = AdaptOptions {
            steps,
            refinement,
            max_dofs,
            ..Default::default()
        };
        run(s, &opts, Path::new("unused"), |_, _, _| {}).unwrap().1
    };
    let reference = loop_of(&scene(&[]), Refinement::H, 12, 60_000)
        .last()
        .unwrap()
        .hub_force_y;
    let hp = loop_of(&q1, Refinement::Hp, 13, 60_000);
    let h1 = loop_of(&q1, Refinement::H, 14, 60_000);
    let err = |f: f64| (f - reference).abs() / reference.abs();
    for s in &hp {
        eprintln!(
            "hp {:2}: {:6} eqs {:5} Q2 cells of {:5}, eta_rel {:.3e}, error {:.2e}",
            s.step,
            s.dofs,
            s.degree2_cells,
            s.cells,
            s.relative_estimate,
            err(s.hub_force_y)
        );
    }
    let near = |steps: &[tread::driver::adaptive::AdaptStep], n: i64| {
        steps
            .iter()
            .min_by_key(|s| (s.dofs as i64 - n).abs())
            .unwrap()
            .clone()
    };
    let (a, b) = (near(&hp, 8000), near(&h1, 32000));
    eprintln!(
        "hp {} eqs: {:.2e}; h-Q1 {} eqs: {:.2e}",
        a.dofs,
        err(a.hub_force_y),
        b.dofs,
        err(b.hub_force_y)
    );
    assert!(b.dofs > 3 * a.dofs);
    assert!(err(a.hub_force_y) < 1e-4);
    assert!(err(a.hub_force_y) * 5.0 < err(b.hub_force_y));
    assert!(hp.last().unwrap().degree2_cells > 0 && hp.last().unwrap().max_level > 0);
    let (s0, s1) = (&hp[8], hp.last().unwrap());
    let rate = -(s1.estimate / s0.estimate).ln() / (s1.dofs as f64 / s0.dofs as f64).ln();
    eprintln!("hp estimate rate over steps 8..: {rate:.3}");
    assert!((rate - 1.0).abs() < 0.15, "rate {rate}");
    // p only: stops once the marked cells are all Q2, on the root cells.
    let p = loop_of(&q1, Refinement::P, 20, 60_000);
    assert!(p.len() < 21, "{} meshes", p.len());
    assert!(p.iter().all(|s| s.max_level == 0 && s.cells == p[0].cells));
    assert!(p.last().unwrap().degree2_cells > 0);
    // Refused starts.
    let opts = AdaptOptions {
        refinement: Refinement::Hp,
        ..Default::default()
    };
    let e = run(&scene(&[]), &opts, Path::new("unused"), |_, _, _| {})
        .err()
        .expect("a Q2 start is refused")
        .to_string();
    assert!(e.contains("mesh.order = 1"), "{e}");
}
