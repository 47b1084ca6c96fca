//! The standing-wave measures of the steady branch (`wave_amplitude`, `wave_number` of
//! `branch.csv`) on displacement fields with a known pattern: a pure wave of number n on the
//! outer surface, the same under a large low-order (ovalisation) component and a contact
//! flattening at the bottom, and none at all (zero amplitude).

#[path = "common/fixtures.rs"]
mod fixtures;
use fixtures::*;

use std::f64::consts::{FRAC_PI_2, PI};
use tread::driver::steady_run::{wave_amplitude, wave_number};
use tread::model::SolidSystem;

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

/// The lightly damped branch of `scenarios/oden_figs_9_13.toml` (3 × 64) has a limit point near
/// 49.8 rad/s: followed with small arc-length steps, the path turns back there, reports the
/// limit point, and past it the standing wave (n = 5) grows while ω falls (the sheet of large
/// waves). Measured: limit point at 49.766 rad/s, step 44; amplitude 0.0128 in at 48.9 rad/s on
/// the way up, 0.034 in at 48.0 rad/s on the way back.
#[test]
fn damped_branch_folds_back_onto_a_sheet_of_large_waves() {
    use fixtures::tempdir::TestDir;
    let text = scene_text("scenarios/oden_figs_9_13.toml");
    let set: Vec<String> = [
        "continuation.ds_max=0.02",
        "continuation.max_steps=80",
        "continuation.on_limit=follow",
        "output.sinks=[\"summary\"]",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let scene = tread::io::Scene::from_toml_str(&text, "oden_figs_9_13", &set)
        .unwrap_or_else(|e| panic!("{e}"));
    let out = TestDir::new("waves", "fold");
    let o = tread::app::run(
        &scene,
        &tread::app::RunOptions {
            out_dir: out.to_path_buf(),
            verbose: false,
            quiet: true,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let r = &o.summary["results"];
    let limit = r["special_points"]
        .as_array()
        .and_then(|a| a.iter().find(|p| p["kind"] == "limit_point"))
        .unwrap_or_else(|| panic!("no limit point: {}", r["special_points"]));
    let w_fold = limit["lambda"].as_f64().unwrap();
    let branch = r["branch"].as_array().unwrap();
    let num = |p: &serde_json::Value, k: &str| p[k].as_f64().unwrap();
    let top = branch
        .iter()
        .map(|p| num(p, "omega"))
        .fold(f64::NEG_INFINITY, f64::max);
    eprintln!(
        "limit point at {w_fold:.4} rad/s, highest ω {top:.4}, last point ω {:.3} amplitude {:.4}",
        num(branch.last().unwrap(), "omega"),
        num(branch.last().unwrap(), "wave_amplitude")
    );
    assert!((49.0..50.5).contains(&w_fold), "{w_fold}");
    assert!(top < 50.5, "the path went through: {top}");
    // Past the fold: lower speed, larger wave, same wave number.
    let last = branch.last().unwrap();
    let i_top = branch.iter().position(|p| num(p, "omega") == top).unwrap();
    let up = branch[..i_top]
        .iter()
        .rfind(|p| num(p, "omega") <= num(last, "omega"))
        .unwrap();
    assert!(num(last, "omega") < w_fold - 0.5, "{last}");
    assert!(
        num(last, "wave_amplitude") > 2.0 * num(up, "wave_amplitude"),
        "up: {up}, back: {last}"
    );
    assert_eq!(num(last, "wave_number"), 5.0, "{last}");
}

/// Runs `scene` with the `--set` overrides `set`; returns the summary.
fn run_scene(scene: &str, name: &str, set: &[&str]) -> serde_json::Value {
    use fixtures::tempdir::TestDir;
    let text = scene_text(scene);
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let scene =
        tread::io::Scene::from_toml_str(&text, "scene", &set).unwrap_or_else(|e| panic!("{e}"));
    let out = TestDir::new("waves", name);
    tread::app::run(
        &scene,
        &tread::app::RunOptions {
            out_dir: out.to_path_buf(),
            verbose: false,
            quiet: true,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"))
    .summary
}

/// The same damped branch with the same small steps and `on_limit = "jump"`: at the limit point
/// (49.77 rad/s) a direct solve about 1 rad/s beyond lands on the upper sheet (smaller wave,
/// same n = 5), and the path goes on from there to the target, ω increasing, with no second
/// limit point. The landing point and the last point are checked against separate direct
/// solves at their speeds (the upper sheet, found without the continuation), and against the
/// branch before the fold. Measured: jump 49.766 → 50.806 rad/s; at the landing F_y −83.904,
/// amplitude 0.01303 in, against 0.01640 in at the limit point.
#[test]
fn damped_branch_jumps_past_its_limit_point_onto_the_upper_sheet() {
    let r = run_scene(
        "scenarios/oden_figs_9_13.toml",
        "jump",
        &[
            "continuation.ds_max=0.02",
            "continuation.on_limit=jump",
            "output.sinks=[\"summary\"]",
        ],
    );
    let r = &r["results"];
    let cont = &r["continuation"];
    assert!(
        cont["stop_reason"].as_str().unwrap().contains("target"),
        "{cont}"
    );
    let jumps = cont["jumps"].as_array().unwrap();
    assert_eq!(jumps.len(), 1, "{cont}");
    let (step, limit, landed) = (
        jumps[0]["step"].as_u64().unwrap() as usize,
        jumps[0]["limit"].as_f64().unwrap(),
        jumps[0]["landed"].as_f64().unwrap(),
    );
    eprintln!("jump at step {step}: {limit:.4} -> {landed:.4} rad/s");
    assert!((49.0..50.5).contains(&limit), "{limit}");
    // ds_max = 0.02 of |62 - 10| per jump distance: 1.04 rad/s (or 2×, 4× on a retry).
    assert!(landed > limit && landed < limit + 4.2, "{landed}");
    let branch = r["branch"].as_array().unwrap();
    let num = |p: &serde_json::Value, k: &str| p[k].as_f64().unwrap();
    let i = branch
        .iter()
        .position(|p| p["step"].as_u64() == Some(step as u64))
        .unwrap();
    assert_eq!(branch[i]["kind"], "jump", "{}", branch[i]);
    assert_eq!(branch[i - 1]["kind"], "limit_point", "{}", branch[i - 1]);
    let specials = r["special_points"].as_array().unwrap();
    assert_eq!(specials.len(), 1, "{specials:?}");
    assert!(
        branch[i..]
            .windows(2)
            .all(|w| num(&w[1], "omega") > num(&w[0], "omega")),
        "omega not increasing after the jump"
    );
    let last = branch.last().unwrap();
    assert!(num(last, "omega") >= 62.0, "{last}");
    // The landing point: the upper sheet (a smaller wave than at the fold), n = 5.
    assert!(
        num(&branch[i], "wave_amplitude") < 0.9 * num(&branch[i - 1], "wave_amplitude"),
        "{} vs {}",
        branch[i],
        branch[i - 1]
    );
    assert_eq!(num(&branch[i], "wave_number"), 5.0);
    // Separate direct solves at the landing and the last speed agree with the branch.
    for p in [&branch[i], last] {
        let w = num(p, "omega");
        let v0 = num(p, "v0");
        let d = run_scene(
            "scenarios/oden_figs_9_13.toml",
            &format!("direct_{}", w.round()),
            &[
                &format!("motion.omega={w}"),
                &format!("road.v0={v0}"),
                "continuation.target=1000",
                "continuation.max_steps=1",
                "output.sinks=[\"summary\"]",
            ],
        );
        let first = &d["results"]["branch"][0];
        for k in ["hub_force_x", "hub_force_y", "hub_torque"] {
            let (a, b) = (num(first, k), num(p, k));
            assert!(
                (a - b).abs() < 1e-6 * b.abs().max(1.0),
                "{k} at {w}: direct {a}, branch {b}"
            );
        }
    }
}

/// Above the critical speed (46.7 rad/s on this mesh), the transient mode of the lightly damped
/// `oden_figs_9_13` scene (3 × 64) rolls into the same standing-wave state as the steady mode's
/// direct solve, at 55 and 60 rad/s (1.18 and 1.29 times critical): hub forces within 2 % of
/// |F| (measured: F_x 1.24 % and 1.61 %, F_y 0.10 % and 0.24 %), the referential field within
/// 5 % (2.4 %, 3.1 %), the wave amplitude on the outer surface within 5 % (2.2 %, 2.6 %) with
/// the same wave number. About 35 s per speed.
#[test]
fn transient_above_the_critical_speed_matches_the_damped_steady_branch() {
    use fixtures::tempdir::TestDir;
    use tread::app::RunOptions;
    use tread::driver::compare::read_csv;
    let text = scene_text("scenarios/oden_figs_9_13.toml");
    for omega in [55.0, 60.0] {
        let set: Vec<String> = vec![
            format!("motion.omega={omega}"),
            format!("road.v0={}", 1.9666667 * omega),
            "output.sinks=[\"summary\",\"csv\"]".into(),
        ];
        let sc = tread::io::Scene::from_toml_str(&text, "above_critical", &set)
            .unwrap_or_else(|e| panic!("{e}"));
        let dir = TestDir::new("wave_measures", &format!("compare-{omega}"));
        let out = tread::driver::compare::run(
            &sc,
            &RunOptions {
                out_dir: dir.to_path_buf(),
                verbose: false,
                quiet: true,
            },
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let c = &out.summary["results"]["compare"];
        let g = |k: &str| c[k].as_f64().unwrap_or_else(|| panic!("{k}: {c}"));
        assert_eq!(c["transient_steady"], true, "{c}");
        // The wave measures of both referential fields.
        let measure = |sub: &str| {
            let (head, rows) = read_csv(&dir.join(sub).join("steady_field.csv")).unwrap();
            let col = |k: &str| head.iter().position(|h| h == k).unwrap();
            let (c1, c2) = (col("u1"), col("u2"));
            let mut sys = tread::app::build_system(&sc).unwrap();
            assert_eq!(rows.len(), sys.model.mesh.n_nodes());
            for (n, r) in rows.iter().enumerate() {
                sys.x[2 * n] = r[c1];
                sys.x[2 * n + 1] = r[c2];
            }
            (wave_amplitude(&sys), wave_number(&sys))
        };
        let (at, nt) = measure("transient");
        let (as_, ns) = measure("steady");
        let da = (at - as_).abs() / as_;
        eprintln!(
            "omega {omega}: F_x diff {:.3e}, F_y diff {:.3e}, field {:.3e}; wave amplitude {at:.4e} / {as_:.4e} ({da:.2e}), n {nt} / {ns}",
            g("hub_force_x_rel_diff"),
            g("hub_force_y_rel_diff"),
            g("field_rel_l2")
        );
        assert!(g("hub_force_x_rel_diff") < 0.02 && g("hub_force_y_rel_diff") < 0.02);
        assert!(g("field_rel_l2") < 0.05);
        assert!(
            as_ > 5e-3,
            "no standing wave in the steady field: {as_:.3e}"
        );
        assert!(da < 0.05, "wave amplitude {at:.4e} vs {as_:.4e}");
        assert_eq!(nt, ns);
    }
}
