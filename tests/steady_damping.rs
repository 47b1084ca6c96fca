//! The steady mode's strain-rate damping on any mesh, with its two Newton matrices: the
//! matrix-free coupling (the cells' own sparsity, GMRES) and the assembled one (extended
//! elements, direct LU).
//!
//! - Both give the exact tangent of the same residual: checked against central differences,
//!   on a ring mesh (five-point ring differences) and on the same mesh with its ring structure
//!   removed (cell-average derivatives, the path of imported meshes).
//! - Both converge to the same steady state.
//! - The damping's residual on a prescribed smooth state converges to the closed-form power
//!   at fourth order with either nodal derivative (`tools/steady_damping_power.py`).
//! - A Gmsh mesh refined at the footprint (no rings) solves the damped frictional scene, and
//!   its hub force agrees with the structured mesh's.

#[path = "common/fixtures.rs"]
mod fixtures;

use tread::assembly::CONSTRAINED;
use tread::driver::steady::SteadyRolling;
use tread::driver::steady_run::{build_steady, solve_steady};
use tread::io::Scene;
use tread::model::SteadyDampingTangent;
use tread::physics::ThetaDerivativeSource;
use tread::solver::NonlinearSystem;

const ODEN: &str = include_str!("../scenarios/oden_hollow_cylinder.toml");
const FOOTPRINT: &str = include_str!("../scenarios/steady_footprint_refined.toml");

fn scene(text: &str, name: &str, set: &[&str]) -> Scene {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(text, name, &set).unwrap_or_else(|e| panic!("{e}"))
}

/// max |K − K_fd| / max |K| with K the exact tangent (assembled matrix plus the matrix-free
/// part), and max |matrix-free part| / max |K|.
fn fd_errors(st: &mut SteadyRolling) -> (f64, f64) {
    let (a, k) = matrix_and_tangent(st);
    let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let corr = max_diff(&a, &k);
    let err = fixtures::fd_max_error(st, 1e-7, |i, j| k[i][j]);
    (err / kmax, corr / kmax)
}

/// (assembled matrix, exact tangent = matrix + matrix-free part), dense, at the current state.
fn matrix_and_tangent(st: &mut SteadyRolling) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    assert!(st.evaluate(true));
    let a = st.sys.asm.to_dense();
    let mut k = a.clone();
    if st.has_tangent_correction() {
        let n = st.n_eq();
        let (mut e, mut col) = (vec![0.0; n], vec![0.0; n]);
        for j in 0..n {
            e.fill(0.0);
            e[j] = 1.0;
            col.fill(0.0);
            st.tangent_correction(&e, &mut col);
            for i in 0..n {
                k[i][j] += col[i];
            }
        }
    }
    (a, k)
}

fn max_diff(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()))
}

/// A smooth, non-symmetric displacement on the free nodes (hanging nodes follow their masters)
/// and the road raised into contact: a state to check tangents at.
fn pressed_by_hand(mut st: SteadyRolling) -> SteadyRolling {
    let mesh = st.sys.model.mesh.clone();
    for nd in 0..mesh.n_nodes() {
        let x = mesh.nodes[nd];
        if st.sys.dofs.eq[2 * nd] < CONSTRAINED {
            let (r, th) = (x.norm(), x[1].atan2(x[0]));
            st.sys.x[2 * nd] += 0.02 * (r - 1.0) * (th.sin() + 0.5 * (2.0 * th).cos());
            st.sys.x[2 * nd + 1] += 0.03 * (r - 1.0) * (0.3 + th.cos() * th.cos()) + 0.01;
        }
    }
    st.sys.dofs.apply_constraints(&mut st.sys.x);
    if let Some(c) = st.sys.contact.as_mut() {
        c.h = 1.97;
    }
    st
}

/// A small damped frictional steady system pressed into the road by hand (no solve): a
/// smooth, non-symmetric state with contact.
fn tiny(rings: bool) -> SteadyRolling {
    let sc = scene(
        ODEN,
        "tiny",
        &[
            "analysis.mode=\"steady\"",
            "mesh.n_r=1",
            "mesh.n_theta=8",
            "time.strain_rate_damping=3.0",
            "motion.omega=20",
            "road.v0=39",
        ],
    );
    let mut model = tread::app::build_model(&sc).unwrap_or_else(|e| panic!("{e}"));
    model.strain_rate_damping = 3.0;
    if !rings {
        model.mesh.rings = None;
    }
    let contact = tread::setup::build_contact(&sc, &model).unwrap_or_else(|e| panic!("{e}"));
    let sys = tread::model::SolidSystem::with_contact(model, contact);
    pressed_by_hand(SteadyRolling::new(sys, 20.0, 2.0))
}

/// Block 0 (the cells) has an empty core: its matrices are assembled in the coupling block.
fn cells_in_coupling(st: &SteadyRolling) -> bool {
    st.sys.asm.blocks[0]
        .core
        .as_ref()
        .is_some_and(|c| c.iter().all(|&k| k == 0))
}

#[test]
fn damped_steady_tangent_is_exact_in_both_modes_with_and_without_rings() {
    for rings in [true, false] {
        let mut st = tiny(rings);
        let src = st
            .sys
            .steady_visc
            .as_ref()
            .expect("damping on")
            .nodal
            .source;
        assert_eq!(
            src,
            if rings {
                ThetaDerivativeSource::Rings
            } else {
                ThetaDerivativeSource::CellAverage
            }
        );
        assert_eq!(
            st.sys.steady_damping_tangent(),
            Some(SteadyDampingTangent::MatrixFree)
        );
        let (err_mf, corr) = fd_errors(&mut st);
        assert!(st.sys.asm.blocks[0].core.is_none());
        st.sys
            .set_steady_damping_tangent(SteadyDampingTangent::Assembled);
        assert!(!st.has_tangent_correction());
        // The coupling block holds the cells' matrices: block 0 keeps their residuals only.
        assert!(cells_in_coupling(&st));
        let (err_as, none) = fd_errors(&mut st);
        println!(
            "rings {rings} ({src:?}): FD error matrix-free {err_mf:.2e} (matrix-free part {corr:.2e} of max |K|), assembled {err_as:.2e}"
        );
        assert!(err_mf < 1e-6 && err_as < 1e-6, "{err_mf:e} {err_as:e}");
        // The coupling beyond the cells is a visible part of the tangent.
        assert!(corr > 1e-3, "{corr:e}");
        assert_eq!(none, 0.0);
        // Banded: three-point ring differences in the matrix, the rest matrix-free (rings
        // only; without them the system stays as it is).
        st.sys
            .set_steady_damping_tangent(SteadyDampingTangent::Banded);
        if rings {
            assert_eq!(
                st.sys.steady_damping_tangent(),
                Some(SteadyDampingTangent::Banded)
            );
            assert!(st.has_tangent_correction());
            let (err_b, corr_b) = fd_errors(&mut st);
            println!("banded: FD error {err_b:.2e} (matrix-free part {corr_b:.2e})");
            assert!(err_b < 1e-6, "{err_b:e}");
            // Its matrix-free part is smaller than the cells-only split's.
            assert!(corr_b > 0.0 && corr_b < corr, "{corr_b:e} vs {corr:e}");
        } else {
            assert_eq!(
                st.sys.steady_damping_tangent(),
                Some(SteadyDampingTangent::Assembled)
            );
        }
        assert!(cells_in_coupling(&st));
        // Back to matrix-free: the same sparsity as without damping again, the cells' matrices
        // in block 0.
        let nnz_as = st.sys.asm.nnz();
        st.sys
            .set_steady_damping_tangent(SteadyDampingTangent::MatrixFree);
        assert!(st.sys.asm.nnz() < nnz_as);
        assert!(st.sys.asm.blocks[0].core.is_none());
    }
}

/// The system of [`tiny`] on the exact polar annulus with the cells below the axis refined
/// once and one of their children once more: hanging nodes on the contact boundary and
/// inside, no rings.
fn tiny_refined() -> SteadyRolling {
    let sc = scene(
        ODEN,
        "tiny",
        &[
            "analysis.mode=\"steady\"",
            "mesh.n_r=1",
            "mesh.n_theta=8",
            "time.strain_rate_damping=3.0",
            "motion.omega=20",
            "road.v0=39",
        ],
    );
    let mesh = fixtures::refined_below_hub(&sc);
    let (material, pressure) = tread::setup::build_material(&sc).unwrap_or_else(|e| panic!("{e}"));
    let mut model = tread::physics::SolidModel::new(mesh, material, sc.material.rho, pressure);
    model.strain_rate_damping = 3.0;
    let contact = tread::setup::build_contact(&sc, &model).unwrap_or_else(|e| panic!("{e}"));
    let sys = tread::model::SolidSystem::with_contact(model, contact);
    pressed_by_hand(SteadyRolling::new(sys, 20.0, 2.0))
}

#[test]
fn damped_frictional_steady_tangent_is_exact_with_hanging_nodes() {
    let mut st = tiny_refined();
    assert!(st.sys.dofs.has_constraints());
    let (err_mf, corr) = fd_errors(&mut st);
    st.sys
        .set_steady_damping_tangent(SteadyDampingTangent::Assembled);
    assert!(cells_in_coupling(&st));
    let (err_as, _) = fd_errors(&mut st);
    println!(
        "hanging nodes: FD error matrix-free {err_mf:.2e} (matrix-free part {corr:.2e}), assembled {err_as:.2e}"
    );
    assert!(err_mf < 1e-6 && err_as < 1e-6, "{err_mf:e} {err_as:e}");
    assert!(corr > 1e-3, "{corr:e}");
}

fn hub_force(st: &SteadyRolling) -> (f64, f64) {
    let (f, _) = st.sys.hub_reaction();
    (f[0], f[1])
}

/// The two Newton matrices converge to the same steady state of the damped frictional
/// default scene (the residual is the same; only the path differs).
#[test]
fn matrix_free_and_assembled_reach_the_same_state() {
    let sc = scene(
        ODEN,
        "modes",
        &["analysis.mode=\"steady\"", "mesh.n_theta=48", "mesh.n_r=2"],
    );
    let mut out = Vec::new();
    for mode in [
        SteadyDampingTangent::MatrixFree,
        SteadyDampingTangent::Assembled,
        SteadyDampingTangent::Banded,
    ] {
        let mut st = build_steady(&sc).unwrap_or_else(|e| panic!("{e}"));
        st.sys.set_steady_damping_tangent(mode);
        let mut rep = Default::default();
        let r =
            solve_steady(&sc, &mut st, false, &mut rep, &mut ()).unwrap_or_else(|e| panic!("{e}"));
        assert!(r.damping_fallback.is_none() && r.recovery.is_none());
        assert_eq!(st.sys.steady_damping_tangent(), Some(mode));
        out.push((hub_force(&st), st.sys.x.clone()));
    }
    let (a, xa) = &out[0];
    for (b, xb) in &out[1..] {
        let du = xa
            .iter()
            .zip(xb)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        println!("hub force matrix-free {a:?}, other {b:?}; max |du| = {du:.2e}");
        assert!((a.0 - b.0).abs() < 1e-6 * a.1.abs() && (a.1 - b.1).abs() < 1e-6 * a.1.abs());
        assert!(du < 1e-7, "{du:e}");
    }
}

/// `[solver] damping_cell_weight` changes the assembled part of the matrix-free damping
/// tangent (GMRES's preconditioner) and nothing else: at one state the exact tangent is the
/// same for every weight (to the single precision in which ∂r/∂v is stored), and the steady
/// solves reach the same state. Out-of-range weights
/// are refused by name.
#[test]
fn damping_cell_weight_changes_only_the_preconditioner() {
    let base = [
        "analysis.mode=\"steady\"",
        "mesh.n_theta=48",
        "mesh.n_r=2",
        "solver.damping_tangent=\"matrix_free\"",
    ];
    let mut runs = Vec::new();
    for w in ["1.0", "0.4"] {
        let key = format!("solver.damping_cell_weight={w}");
        let sc = scene(ODEN, "weight", &[&base[..], &[key.as_str()]].concat());
        let mut st = build_steady(&sc).unwrap_or_else(|e| panic!("{e}"));
        let mut rep = Default::default();
        let r =
            solve_steady(&sc, &mut st, false, &mut rep, &mut ()).unwrap_or_else(|e| panic!("{e}"));
        assert!(r.damping_fallback.is_none() && r.recovery.is_none());
        assert_eq!(
            st.sys.steady_damping_tangent(),
            Some(SteadyDampingTangent::MatrixFree)
        );
        runs.push(st);
    }
    let (f1, f4) = (hub_force(&runs[0]), hub_force(&runs[1]));
    let du = runs[0]
        .sys
        .x
        .iter()
        .zip(&runs[1].sys.x)
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    println!("hub force with weight 1 {f1:?}, 0.4 {f4:?}; max |du| = {du:.2e}");
    assert!((f1.0 - f4.0).abs() < 1e-6 * f1.1.abs() && (f1.1 - f4.1).abs() < 1e-6 * f1.1.abs());
    assert!(du < 1e-7, "{du:e}");
    // The same state in both systems.
    let x = runs[0].sys.x.clone();
    runs[1].sys.x.copy_from_slice(&x);
    let (a1, k1) = matrix_and_tangent(&mut runs[0]);
    let (a4, k4) = matrix_and_tangent(&mut runs[1]);
    let kmax = k1.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let (da, dk) = (max_diff(&a1, &a4) / kmax, max_diff(&k1, &k4) / kmax);
    println!("relative to max |K|: assembled parts differ by {da:.2e}, exact tangents by {dk:.2e}");
    assert!(da > 1e-3, "the weight did not reach the matrix: {da:e}");
    // The matrix-free part applies ∂r/∂v stored in single precision, the assembled part
    // takes it in double precision: the exact tangents agree to single precision.
    assert!(dk < 1e-8, "{dk:e}");
    for bad in ["0.0", "1.5", "-0.2"] {
        let e = Scene::from_toml_str(
            ODEN,
            "weight",
            &[format!("solver.damping_cell_weight={bad}")],
        )
        .expect_err("refused");
        assert!(e.to_string().contains("solver.damping_cell_weight"), "{e}");
    }
}

/// Damping on an imported mesh without rings (Gmsh, refined at the footprint): the nodal
/// velocities come from cell averages. It solves, and its hub force differs from the
/// structured ring mesh's no more than the two meshes already differ without damping.
#[test]
fn damped_steady_solve_on_a_gmsh_mesh_without_rings() {
    let dir = format!("{}/scenarios", env!("CARGO_MANIFEST_DIR"));
    let text = FOOTPRINT.replace(
        "file = \"footprint_refined.msh\"",
        &format!("file = \"{dir}/footprint_refined.msh\""),
    );
    let text = format!("{text}\n[time]\ndt = 1e-3\nt_end = 1.0\nstrain_rate_damping = 1.0\n");
    let sc = scene(&text, "gmsh_damped", &[]);
    let mut st = build_steady(&sc).unwrap_or_else(|e| panic!("{e}"));
    assert!(st.sys.model.mesh.rings.is_none());
    assert_eq!(
        st.sys
            .steady_visc
            .as_ref()
            .expect("damping on")
            .nodal
            .source,
        ThetaDerivativeSource::CellAverage
    );
    assert!(st.damping_fallback.is_none());
    // `banded` needs node rings: this mesh gets the matrix-free tangent, and says why.
    let banded = build_steady(&scene(
        &text,
        "gmsh_banded",
        &["solver.damping_tangent=\"banded\""],
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        banded.sys.steady_damping_tangent(),
        Some(SteadyDampingTangent::MatrixFree)
    );
    let why = banded.damping_fallback.as_deref().unwrap_or("");
    assert!(why.contains("banded") && why.contains("rings"), "{why}");
    let mut rep = Default::default();
    solve_steady(&sc, &mut st, false, &mut rep, &mut ()).unwrap_or_else(|e| panic!("{e}"));
    let g = hub_force(&st);

    // The same scene on the generated ring mesh, fine in θ (Q2, 3 × 192).
    let (i, j) = (
        FOOTPRINT.find("\n[mesh]").unwrap(),
        FOOTPRINT.find("\n[material]").unwrap(),
    );
    let ring_text = format!(
        "{}\n[mesh]\nn_r = 3\nn_theta = 192\norder = 2\n{}",
        &FOOTPRINT[..i],
        &FOOTPRINT[j..]
    );
    let ring_text =
        format!("{ring_text}\n[time]\ndt = 1e-3\nt_end = 1.0\nstrain_rate_damping = 1.0\n");
    let sr = scene(&ring_text, "ring_damped", &[]);
    let mut sr_st = build_steady(&sr).unwrap_or_else(|e| panic!("{e}"));
    assert!(sr_st.sys.model.mesh.rings.is_some());
    solve_steady(&sr, &mut sr_st, false, &mut Default::default(), &mut ())
        .unwrap_or_else(|e| panic!("{e}"));
    let r = hub_force(&sr_st);
    // Without damping, for scale: the damping must change the answer visibly.
    let sc0 = scene(&text, "gmsh_undamped", &["time.strain_rate_damping=0"]);
    let mut st0 = build_steady(&sc0).unwrap_or_else(|e| panic!("{e}"));
    solve_steady(&sc0, &mut st0, false, &mut Default::default(), &mut ())
        .unwrap_or_else(|e| panic!("{e}"));
    let u = hub_force(&st0);
    let sr0 = scene(&ring_text, "ring_undamped", &["time.strain_rate_damping=0"]);
    let mut sr0_st = build_steady(&sr0).unwrap_or_else(|e| panic!("{e}"));
    solve_steady(&sr0, &mut sr0_st, false, &mut Default::default(), &mut ())
        .unwrap_or_else(|e| panic!("{e}"));
    let r0 = hub_force(&sr0_st);
    println!("hub force: gmsh damped {g:?}, ring damped {r:?}, gmsh undamped {u:?}, ring undamped {r0:?}");
    let dist = |p: (f64, f64), q: (f64, f64)| ((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt();
    let effect = dist(g, u);
    assert!(effect > 1e-3 * r.1.abs(), "damping effect {effect:e}");
    // The two meshes differ (resolution away from the footprint) by about 3 % of the load
    // without damping; the damping, computed from cell averages on one and ring differences
    // on the other, adds no discrepancy of its own beyond a fraction of its effect.
    let (d_damped, d_undamped) = (dist(g, r), dist(u, r0));
    assert!(
        d_damped <= d_undamped + 0.5 * effect,
        "gmsh vs ring: damped {d_damped:e}, undamped {d_undamped:e}, damping effect {effect:e}"
    );
}

/// The same damped, frictionless scene on the same meshes with the nodal velocities from
/// ring differences and from cell averages (the ring structure removed): the hub load and
/// the hub torque agree. Frictionless and without normal damping, the hub torque is the
/// strain-rate damping's rolling resistance alone.
#[test]
fn ring_and_cell_average_velocities_converge_together() {
    let mut diffs = Vec::new();
    for n_theta in [48usize, 96, 192] {
        let sc = scene(
            ODEN,
            "sources",
            &[
                "analysis.mode=\"steady\"",
                "mesh.n_r=2",
                &format!("mesh.n_theta={n_theta}"),
                "friction.mu=0",
                "contact.b_n=0",
                "time.strain_rate_damping=2.0",
            ],
        );
        let mut f = Vec::new();
        for rings in [true, false] {
            let mut model = tread::app::build_model(&sc).unwrap_or_else(|e| panic!("{e}"));
            model.strain_rate_damping = 2.0;
            if !rings {
                model.mesh.rings = None;
            }
            let c = tread::setup::build_contact(&sc, &model).unwrap_or_else(|e| panic!("{e}"));
            let sys = tread::model::SolidSystem::with_contact(model, c);
            let mut st = SteadyRolling::new(sys, sc.motion.omega, sc.geometry.ro);
            st.plan = tread::setup::solve_plan(&sc, &st.sys);
            solve_steady(&sc, &mut st, false, &mut Default::default(), &mut ())
                .unwrap_or_else(|e| panic!("{e}"));
            let (force, torque) = st.sys.hub_reaction();
            f.push((torque, force[1]));
        }
        let (a, b) = (f[0], f[1]);
        let d = ((a.0 - b.0).abs() / a.0.abs(), (a.1 - b.1).abs() / a.1.abs());
        println!("n_theta {n_theta}: rings {a:?}, cell average {b:?}; relative differences torque {:.2e}, Fy {:.2e}", d.0, d.1);
        // Rolling resistance from the damping: a visible torque (lever arm ~ Ro).
        assert!(a.0.abs() > 1e-3 * a.1.abs() * sc.geometry.ro, "{a:?}");
        diffs.push(d);
    }
    // The two sources agree to 0.15 % in the damping torque and the load on every mesh. (The
    // load difference converges under θ-refinement, 4.5e-4 → 1e-7; the torque difference
    // stays near 7e-4 while the torque itself still moves by 1.5 % between these meshes.)
    for (k, d) in diffs.iter().enumerate() {
        assert!(d.0 < 1.5e-3 && d.1 < 1.5e-3, "mesh {k}: {diffs:?}");
    }
}

/// `[solver] damping_tangent` selects the Newton matrix; `auto` (the default) starts
/// matrix-free on small meshes (banded from `BANDED_MIN_EQUATIONS` on), and without damping
/// there is none to choose.
#[test]
fn damping_tangent_scene_key() {
    let base = ["analysis.mode=\"steady\"", "mesh.n_theta=16", "mesh.n_r=1"];
    for (value, want) in [
        (None, Some(SteadyDampingTangent::MatrixFree)),
        (Some("auto"), Some(SteadyDampingTangent::MatrixFree)),
        (Some("matrix_free"), Some(SteadyDampingTangent::MatrixFree)),
        (Some("assembled"), Some(SteadyDampingTangent::Assembled)),
        (Some("banded"), Some(SteadyDampingTangent::Banded)),
    ] {
        let mut set: Vec<String> = base.iter().map(|s| s.to_string()).collect();
        if let Some(v) = value {
            set.push(format!("solver.damping_tangent=\"{v}\""));
        }
        let set: Vec<&str> = set.iter().map(|s| s.as_str()).collect();
        let st = build_steady(&scene(ODEN, "key", &set)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(st.sys.steady_damping_tangent(), want, "{value:?}");
    }
    let st = build_steady(&scene(
        ODEN,
        "key",
        &[&base[..], &["time.strain_rate_damping=0"]].concat(),
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(st.sys.steady_damping_tangent(), None);
    let e = Scene::from_toml_str(
        ODEN,
        "key",
        &["solver.damping_tangent=\"sparse\"".to_string()],
    )
    .expect_err("refused");
    assert!(e.to_string().contains("damping_tangent"), "{e}");
}

/// The steady damping's residual at a prescribed smooth state, tested with a smooth field w
/// (both vanishing on the hub): r_d(u) · w → ∫ η Ė : δE[w] dA, Ė = sym(Fᵀ ∇v),
/// v = ω (t + ∂θu), whose closed-form value `tools/steady_damping_power.py` computes
/// (sympy; Gauss–Legendre in r, trapezoidal in θ). Both nodal θ-derivatives converge at fourth
/// order on isoparametric Q2 meshes (measured 3.99–4.02): the ring differences and the cell
/// average of imported meshes.
#[test]
fn damping_residual_converges_to_the_closed_form_power() {
    use tread::assembly::FIXED;
    const P_EXACT: f64 = -4.741743874616523;
    let omega = 10.0;
    for rings in [true, false] {
        let mut errors = Vec::new();
        for (n_r, n_theta) in [(4, 32), (8, 64), (16, 128)] {
            let mut model = fixtures::neo_hookean_annulus(n_r, n_theta);
            if !rings {
                model.mesh.rings = None;
            }
            model.strain_rate_damping = 1.0;
            let mut sys = tread::model::SolidSystem::new(model, "hub");
            sys.steady_omega = Some(omega);
            assert!(sys.enable_steady_viscosity());
            let source = sys.steady_visc.as_ref().map(|sv| sv.nodal.source);
            let expected = if rings {
                ThetaDerivativeSource::Rings
            } else {
                ThetaDerivativeSource::CellAverage
            };
            assert_eq!(source, Some(expected));
            let n_nodes = sys.model.mesh.n_nodes();
            let mut w = vec![0.0; sys.x.len()];
            for n in 0..n_nodes {
                let x = sys.model.mesh.nodes[n];
                let (r, th) = (x.norm(), x[1].atan2(x[0]));
                sys.x[2 * n] = 0.05 * (r - 1.0) * (2.0 * th + 0.3).cos();
                sys.x[2 * n + 1] = 0.04 * (r - 1.0).powi(2) * (3.0 * th).sin();
                w[2 * n] = (r - 1.0) * th.sin();
                w[2 * n + 1] = (r - 1.0) * (2.0 * th).cos();
            }
            assert!(sys.evaluate(false));
            let damped = sys.residual().to_vec();
            sys.model.strain_rate_damping = 0.0;
            assert!(sys.evaluate(false));
            let undamped = sys.residual().to_vec();
            let mut p = 0.0;
            for (d, wd) in w.iter().enumerate().take(2 * n_nodes) {
                let e = sys.dofs.eq[d];
                if e != FIXED {
                    p += (damped[e as usize] - undamped[e as usize]) * wd;
                }
            }
            let err = (p - P_EXACT).abs() / P_EXACT.abs();
            println!("rings {rings}, {n_r} x {n_theta}: P = {p:.12}, relative error {err:.3e}");
            errors.push(err);
        }
        for k in 1..errors.len() {
            let rate = (errors[k - 1] / errors[k]).log2();
            assert!(
                rate > 3.5,
                "rings {rings}: errors {errors:?}, rate {rate:.2}"
            );
        }
        assert!(errors[2] < 1e-6, "rings {rings}: errors {errors:?}");
    }
}
