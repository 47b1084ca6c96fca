//! Critical speeds of the steady operator against an independent 1D Fourier-mode reference.

mod common;
#[path = "common/tempdir.rs"]
mod tempdir;

use common::fourier_modes::{FourierModes, MooneyRivlinRef};
use tread::driver::critical::{self, CriticalOptions};
use tread::io::Scene;

const RI: f64 = 1.0;
const RO: f64 = 2.0;
const RHO: f64 = 0.027;
const C1: f64 = 80.0;
const C2: f64 = 20.0;
const KAPPA: f64 = 20000.0;

fn spinning_scene(n_r: usize, n_theta: usize, grading_r: f64) -> Scene {
    spinning_scene_with(n_r, n_theta, grading_r, "")
}

fn spinning_scene_with(n_r: usize, n_theta: usize, grading_r: f64, extra: &str) -> Scene {
    let mode = if extra.is_empty() {
        "spinning"
    } else {
        "steady"
    };
    let text = format!(
        r#"
[scene]
name = "critical_test"
[geometry]
ri = {RI}
ro = {RO}
[mesh]
n_r = {n_r}
n_theta = {n_theta}
order = 2
grading_r = {grading_r}
[material]
model = "mooney_rivlin"
c1 = {C1}
c2 = {C2}
kappa = {KAPPA}
rho = {RHO}
[analysis]
mode = "{mode}"
[motion]
omega = 1.0
[solver]
tolerance = 1e-10
{extra}
"#
    );
    Scene::from_toml_str(&text, "test", &[]).expect("valid test scene")
}

fn reference(n_el: usize, p: usize) -> FourierModes {
    FourierModes {
        ri: RI,
        ro: RO,
        rho: RHO,
        mat: MooneyRivlinRef {
            c1: C1,
            c2: C2,
            kappa: KAPPA,
        },
        n_el,
        p,
    }
}

/// The 1D reference itself: converged in its own discretisation, ω_c(n) decreasing in n
/// toward the Rayleigh-wave estimate 0.955 √(G/ρ) / Ro (a surface wave of the body).
#[test]
fn fourier_reference_converges_and_falls_toward_the_surface_wave_limit() {
    let (coarse, fine) = (reference(8, 4), reference(16, 6));
    let mut prev = f64::INFINITY;
    for n in [4, 8, 16, 32, 64] {
        let a = coarse
            .crossing(n, 30.0, 90.0, 12)
            .unwrap()
            .expect("crossing");
        let b = fine.crossing(n, 30.0, 90.0, 12).unwrap().expect("crossing");
        assert!((a - b).abs() < 1e-4 * b, "n = {n}: {a} vs {b}");
        assert!(
            b < prev,
            "omega_c({n}) = {b} is not below the previous {prev}"
        );
        prev = b;
    }
    let g = 2.0 * (C1 + C2);
    let w_r = 0.955 * (g / RHO).sqrt() / RO;
    // ω_c(64) = 42.398 rad/s, still 3 % above the half-space value and falling.
    assert!(
        prev > w_r && prev < 1.05 * w_r,
        "omega_c(64) = {prev}, Rayleigh {w_r}"
    );
}

/// The crossing speeds of the FE steady operator (Fourier/Bloch reduction of the full sparse
/// tangent about the finite spun state) against the 1D reference, on a fine mesh, and the
/// full-operator check at the lowest crossing.
#[test]
fn fe_crossing_speeds_match_the_fourier_mode_reference() {
    let opts = CriticalOptions {
        n_max: None,
        omega_max: Some(75.0),
        samples: 24,
        ..Default::default()
    };
    let rep = critical::run(&spinning_scene(8, 64, 1.0), &opts).expect("critical run");
    let fine = reference(16, 6);
    for n in [4, 8, 12] {
        let fe = rep
            .crossings
            .iter()
            .find(|c| c.n == n)
            .map(|c| c.omega)
            .expect("FE crossing");
        let r = fine
            .crossing(n, 30.0, 90.0, 12)
            .unwrap()
            .expect("1D crossing");
        let err = (fe - r) / r;
        println!(
            "n = {n}: FE {fe:.5} rad/s, 1D {r:.5} rad/s, error {:.3} %",
            100.0 * err
        );
        assert!(err.abs() < 5e-3, "n = {n}: FE {fe} vs 1D {r}");
    }
    assert!(rep.hermitian_defect < 1e-10, "{}", rep.hermitian_defect);
    // The discrete minimum sits at the largest wave number the mesh resolves.
    let (w, n) = (rep.omega_crit.unwrap(), rep.n_star.unwrap());
    assert_eq!(n, rep.n_resolved);
    let chk = rep.full_operator.as_ref().expect("full-operator check");
    assert_eq!(chk.negative_below, Some(0));
    assert!(chk.negative_above.unwrap_or(0) >= 1);
    assert!(chk.sigma_ratio < 1e-4, "sigma ratio {}", chk.sigma_ratio);
    assert_eq!(chk.null_mode_n, n);
    println!("FE 8x64: omega_crit = {w:.5} rad/s, n* = {n}");
}

/// Arc-length continuation in ω of the steady spinning cylinder (no road) runs through the
/// critical speed of a small mesh and reports the crossing where it is.
#[test]
fn continuation_passes_the_critical_speed_of_a_small_mesh() {
    let crit = critical::run(&spinning_scene(2, 16, 1.0), &CriticalOptions::default())
        .expect("critical run");
    let wc = crit.omega_crit.expect("a critical speed");
    let target = 1.3 * wc;
    let extra = format!(
        "[continuation]\nparameter = \"omega\"\ntarget = {target}\nds = 0.2\nds_max = 4.0\nmax_steps = 300"
    );
    let mut scene = spinning_scene_with(2, 16, 1.0, &extra);
    scene.motion.omega = 10.0;
    let dir = tempdir::TestDir::new("critical", "continuation");
    let out = tread::app::run(
        &scene,
        &tread::app::RunOptions {
            out_dir: dir.path().to_path_buf(),
            verbose: false,
            quiet: true,
        },
    )
    .expect("continuation run");
    let res = &out.summary["results"];
    let branch = res["branch"].as_array().expect("branch");
    let last = branch.last().unwrap()["omega"].as_f64().unwrap();
    assert!(
        last >= target * 0.999,
        "the branch ends at {last}, target {target}"
    );
    // The inertia of K jumps between the two branch points around ω_crit.
    let k = branch
        .iter()
        .position(|p| p["omega"].as_f64().unwrap() > wc)
        .expect("a point above the critical speed");
    let (a, b) = (&branch[k - 1], &branch[k]);
    assert_eq!(a["negative_eigenvalues"].as_f64(), Some(0.0));
    assert!(b["negative_eigenvalues"].as_f64().unwrap() >= 1.0);
    let special = res["special_points"].as_array().expect("special points");
    let hit = special.iter().any(|s| {
        let l = s["lambda"].as_f64().unwrap();
        s["detected_by"] == "negative_eigenvalues"
            && l >= a["omega"].as_f64().unwrap()
            && l <= b["omega"].as_f64().unwrap()
    });
    assert!(hit, "no crossing reported near {wc}: {special:?}");
}

/// A rolling search whose steady branch ends before the search end says where and why it
/// ended and how the smallest singular value went, and never claims the range it did not
/// cover (the undamped frictionless scene: Newton fails just past the critical speed).
#[test]
fn rolling_search_states_where_and_why_the_branch_ended() {
    let scene = Scene::from_toml_str(
        include_str!("../scenarios/oden_steady_sweep.toml"),
        "critical_rolling",
        &[
            "contact.b_n=0".into(),
            "time.strain_rate_damping=0".into(),
            "mesh.n_theta=32".into(),
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let r = critical::run(
        &scene,
        &CriticalOptions {
            n_max: None,
            n_min: None,
            omega_max: None,
            samples: 12,
            no_contact: false,
            verbose: false,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let h = critical::headline(&r);
    println!("{h}");
    assert_eq!(r.kind, "rolling");
    let last = r.sweep.last().unwrap().omega;
    if r.end_reason == "newton_failed" {
        assert!(r.omega_covered < r.omega_max, "{h}");
        assert_eq!(r.omega_covered, last);
        assert!(h.contains("the steady branch ended at"), "{h}");
        assert!(!h.contains(&format!("below {:.4}", r.omega_max)), "{h}");
    } else {
        assert_eq!(r.end_reason, "target_reached");
        assert!(h.contains("followed to the end of the search"), "{h}");
    }
    assert!(h.contains("smallest singular value of the tangent"), "{h}");
    let v = serde_json::to_value(&r).unwrap();
    assert!(v["end_reason"].is_string() && v["omega_covered"].is_number());
}

/// The headline of a report whose branch ended early (the README's undamped example on
/// 3 × 64 cells: σ_min from 2.2 at 10 rad/s to 0.036 at 46.68 rad/s, search end 65.75 rad/s).
#[test]
fn headline_of_an_early_branch_end_names_it_and_the_singular_value_trend() {
    let row = |omega: f64, sigma_min: f64| critical::SweepRow {
        omega,
        sigma_min,
        n_dominant: 30,
        negative_eigenvalues: None,
        hub_force_x: 0.0,
        hub_force_y: -100.0,
    };
    let r = critical::CriticalReport {
        omega_crit: None,
        n_star: None,
        crossings: vec![],
        kind: "rolling",
        density: RHO,
        shear_modulus: 200.0,
        omega_rayleigh_estimate: 41.1,
        omega_max: 65.7547,
        n_resolved: 64,
        not_crossed: vec![],
        unresolved_crossings: vec![],
        full_operator: None,
        sweep: vec![row(10.0, 2.2), row(30.0, 1.1), row(46.68, 0.036)],
        branch_end: Some("Newton did not converge at 46.69 rad/s".into()),
        end_reason: "newton_failed",
        omega_covered: 46.68,
        hermitian_defect: 0.0,
        wall_time_s: 1.0,
    };
    let h = critical::headline(&r);
    assert!(!h.contains("below 65.7547"), "{h}");
    assert!(h.contains("between 10.0000 and 46.6800 rad/s"), "{h}");
    assert!(
        h.contains("ended at 46.6800 rad/s, short of the 65.7547 rad/s searched"),
        "{h}"
    );
    assert!(
        h.contains("2.20 at 10.0000 rad/s, 0.0360 at 46.6800 rad/s"),
        "{h}"
    );
}
