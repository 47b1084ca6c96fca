//! `tread compare` in three dimensions: the transient mode rolled to its steady state and the
//! steady mode on the same mesh agree on a cornering, cambered wheel with friction, damped
//! normal compliance and the strain-rate damping (`scenarios/transient_cornering_3d.toml`:
//! Hex8, 2 × 96 × 2 cells, slip angle 2°, camber 1°). Targets: the six hub loads within 0.5 %
//! (forces of |F_steady|, moments of |F_steady| Ro), the footprint pressure within 2 % (L2
//! over the tread), the referential field within 1 % (relative L2). The remaining
//! differences are those of the two discretizations on one mesh (velocities by time
//! integration of the nodes against ω ∂θχ by ring differences); on 2 × 64 × 2 cells the
//! vertical force differs by 0.57 % and the footprint pressure by 2.8 %, on 2 × 96 × 2 by
//! 0.086 % and 1.6 %. The same targets on a viscoelastic wheel rolling straight
//! (`scenarios/viscoelastic_rolling_3d.toml`: the quadrature-point history of the transient
//! against the ring integration of the steady mode), where the hub's axle moment is the
//! rolling resistance of the hysteresis.

#[path = "common/tempdir.rs"]
mod tempdir;

use tempdir::TestDir;
use tread::app::RunOptions;
use tread::io::Scene;

const SCENE: &str = include_str!("../scenarios/transient_cornering_3d.toml");
const VISCO: &str = include_str!("../scenarios/viscoelastic_rolling_3d.toml");

/// `tread compare` of the scene `text`, asserting the targets of the module docs.
fn compare(text: &str, name: &str) -> tread::driver::results::Compare3DResults {
    let set = ["output.sinks=[\"summary\",\"csv\"]".to_string()];
    let scene = Scene::from_toml_str(text, name, &set).unwrap_or_else(|e| panic!("{e}"));
    let dir = TestDir::new("compare3d", name);
    let out = tread::driver::compare3d::run(
        &scene,
        &RunOptions {
            out_dir: dir.to_path_buf(),
            verbose: false,
            quiet: true,
        },
        &tread::driver::compare::CompareTolerances::default(),
    )
    .unwrap_or_else(|e| panic!("compare: {e}"));
    let c = out.typed.compare_3d().expect("3D comparison").clone();
    for q in &c.quantities {
        println!(
            "{:20} transient {:>12} steady {:>12} rel {:.3e} of {}",
            q.name,
            q.transient.map_or("-".into(), |v| format!("{v:.6}")),
            q.steady.map_or("-".into(), |v| format!("{v:.6}")),
            q.rel_diff,
            q.relative_to
        );
    }
    assert!(c.transient_steady, "transient run not steady");
    assert!(dir.join("compare.csv").exists());
    assert!(dir.join("footprint_compare.csv").exists());
    let hub = tread::driver::results::HubLoads3D::NAMES;
    for q in c
        .quantities
        .iter()
        .filter(|q| hub.contains(&q.name.as_str()))
    {
        assert!(
            q.rel_diff < 5e-3,
            "{} differs by {:.3e} of {}",
            q.name,
            q.rel_diff,
            q.relative_to
        );
    }
    assert!(
        c.footprint_pressure_rel_l2 < 2e-2,
        "footprint pressure differs by {:.3e}",
        c.footprint_pressure_rel_l2
    );
    assert!(
        c.field_rel_l2 < 1e-2,
        "field differs by {:.3e}",
        c.field_rel_l2
    );
    assert!(c.validated, "{}", c.verdict);
    assert!(c.speedup > 1.0);
    c
}

#[test]
fn steady_matches_transient_in_3d_with_slip_angle_and_camber() {
    let c = compare(SCENE, "transient_cornering_3d");
    // The cornering loads are there: a lateral force of a fifth of the load, an overturning
    // moment from the camber.
    let s = c.hub_loads_steady;
    assert!(s.lateral_force.abs() > 0.1 * s.vertical_force.abs());
    assert!(s.overturning_moment.abs() > 0.1 * s.vertical_force.abs());
}

#[test]
fn steady_matches_transient_in_3d_viscoelastic() {
    let c = compare(VISCO, "viscoelastic_rolling_3d");
    // The hysteresis resists the rolling: an axle moment of a few percent of |F| Ro (the
    // road's tangential force balances it).
    let s = c.hub_loads_steady;
    let fr = s.axle_moment.abs() / (s.vertical_force.abs() * 2.0);
    assert!(fr > 0.02, "rolling resistance {fr:.3e}");
}

/// Load control in both modes: the cornering wheel pressed by a given vertical hub load
/// (10 lbf, about three quarters of what its 0.05 in penetration gives) instead of a
/// penetration. The road height is an unknown of each mode (the transient's massless: its
/// equation P(t) − ∫ t_n dA0 = 0 holds at every step). Same targets; the steady vertical force
/// is the load to the Newton tolerance, the transient's passage mean within 0.1 %.
#[test]
fn steady_matches_transient_in_3d_under_load_control() {
    let text: String = SCENE
        .lines()
        .map(|l| {
            if l.starts_with("disp =") {
                "load = 10.0".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    assert!(text.contains("load = 10.0") && !text.contains("\ndisp ="));
    let c = compare(&text, "transient_cornering_3d_load");
    let (t, s) = (c.hub_loads_transient, c.hub_loads_steady);
    assert!(
        (s.vertical_force - 10.0).abs() < 1e-6,
        "{}",
        s.vertical_force
    );
    assert!(
        (t.vertical_force - 10.0).abs() < 1e-2,
        "{}",
        t.vertical_force
    );
    assert!(s.lateral_force.abs() > 0.1 * s.vertical_force.abs());
}
