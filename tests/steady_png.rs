//! PNG plots of a steady run: the contact tractions are drawn along x1 in order (not as a
//! closed loop back to the first point), and a plain steady solve, a single state, writes no
//! history plots (hub_forces.png, hub_torque.png, energy.png would be single dots).

#[path = "common/tempdir.rs"]
mod tempdir;

use tempdir::TestDir;
use tread::app::RunOptions;
use tread::contact::ContactSample;
use tread::io::record::png::contact_curves;
use tread::io::Scene;

fn sample(x1: f64, t_n: f64) -> ContactSample {
    ContactSample {
        theta: 0.0,
        x1,
        x2: -1.9,
        delta: 0.0,
        t_n,
        t_t: 0.1 * t_n,
        w: 0.0,
        ds0: 0.01,
    }
}

#[test]
fn contact_curves_are_sorted_along_x1() {
    // Facet order around the body starts inside the patch and wraps round to its start.
    let s: Vec<ContactSample> = [0.1, 0.3, 0.5, -0.5, -0.3, -0.1]
        .iter()
        .map(|&x| sample(x, 1.0 - x * x))
        .collect();
    let (tn, tt) = contact_curves(s.iter());
    assert_eq!(tn.len(), 6);
    for c in [&tn, &tt] {
        assert!(c.windows(2).all(|w| w[0].0 <= w[1].0), "{c:?}");
    }
    assert_eq!(tn[0].0, -0.5);
}

#[test]
fn a_plain_steady_solve_writes_contact_png_and_no_history_plots() {
    let scene = Scene::from_toml_str(
        include_str!("../scenarios/rolling_frictionless.toml"),
        "steady_png",
        &[
            "analysis.mode=\"steady\"".into(),
            "mesh.n_theta=32".into(),
            "output.sinks=[\"summary\",\"png\"]".into(),
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let dir = TestDir::new("steady-png", "plain");
    tread::app::run(
        &scene,
        &RunOptions {
            out_dir: dir.to_path_buf(),
            verbose: false,
            quiet: true,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(dir.join("contact.png").exists());
    for f in ["hub_forces.png", "hub_torque.png", "energy.png"] {
        assert!(!dir.join(f).exists(), "{f} of a single steady state");
    }
}

#[test]
fn a_steady_press_in_several_load_steps_plots_its_history() {
    let scene = Scene::from_toml_str(
        include_str!("../scenarios/rolling_frictionless.toml"),
        "steady_png_steps",
        &[
            "analysis.mode=\"steady\"".into(),
            "mesh.n_theta=32".into(),
            "solver.load_steps=3".into(),
            "output.sinks=[\"summary\",\"png\"]".into(),
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let dir = TestDir::new("steady-png", "steps");
    tread::app::run(
        &scene,
        &RunOptions {
            out_dir: dir.to_path_buf(),
            verbose: false,
            quiet: true,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(dir.join("hub_forces.png").exists());
}
