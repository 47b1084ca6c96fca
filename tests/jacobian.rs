//! The assembled global tangent equals central finite differences of the assembled residual on
//! a tiny mesh, for every material and pressure treatment, with spin (ω ≠ 0) and a body force;
//! serial and parallel assembly agree; Newton converges quadratically.

use tread::assembly::FIXED;
use tread::material::{Material, MooneyRivlin, MooneyRivlinIncompressible, NeoHookean};
use tread::math::Vec2;
use tread::mesh::{annulus, AnnulusSpec};
use tread::model::SolidSystem;
use tread::physics::{PressureMode, SolidModel};
use tread::solver::NonlinearSystem;

fn tiny(order: usize, material: Material, pressure: PressureMode) -> SolidSystem {
    let mesh = annulus(&AnnulusSpec {
        ri: 1.0,
        ro: 2.0,
        n_r: 2,
        n_theta: 8,
        degree: order,
        grading_r: 1.5,
        grading_theta: 0.3,
    });
    let mut model = SolidModel::new(mesh, material, 0.8, pressure);
    model.omega2 = 3.0;
    model.body_force = Some(Box::new(|x: Vec2| {
        Vec2::new(0.3 * x[1], -0.2 * x[0] * x[0])
    }));
    let mut sys = SolidSystem::new(model, "hub");
    // A smooth, non-trivial admissible state (|∇u| ~ 0.1) and perturbed pressures.
    for n in 0..sys.model.mesh.n_nodes() {
        let x = sys.model.mesh.nodes[n];
        if sys.dofs.eq[2 * n] != FIXED {
            sys.x[2 * n] += 0.05 * (x[0] * 1.3).sin() + 0.02 * x[1];
            sys.x[2 * n + 1] += 0.04 * (x[1] * 0.9).cos() * x[0];
        }
    }
    for d in sys.dofs.n_u..sys.dofs.n_full() {
        sys.x[d] += 3.0 * ((d as f64) * 0.37).sin();
    }
    sys
}

fn residual(sys: &mut SolidSystem) -> Vec<f64> {
    assert!(sys.evaluate(false));
    sys.residual().to_vec()
}

/// max |K − K_fd| / max |K|.
fn fd_error(sys: &mut SolidSystem) -> f64 {
    assert!(sys.evaluate(true));
    let k = sys.asm.to_dense();
    let n = sys.n_eq();
    let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut err = 0.0f64;
    let mut e = vec![0.0; n];
    for j in 0..n {
        let h = 1e-6;
        e.fill(0.0);
        e[j] = h;
        sys.update(1.0, &e);
        let rp = residual(sys);
        sys.update(-2.0, &e);
        let rm = residual(sys);
        sys.update(1.0, &e);
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            err = err.max((fd - k[i][j]).abs());
        }
    }
    err / kmax
}

#[test]
fn tangent_matches_finite_differences() {
    let cases: Vec<(&str, usize, Material, PressureMode)> = vec![
        (
            "neo-Hookean Q2",
            2,
            NeoHookean::new(2.0, 5.0).into(),
            PressureMode::None,
        ),
        (
            "neo-Hookean Q1",
            1,
            NeoHookean::new(2.0, 5.0).into(),
            PressureMode::None,
        ),
        (
            "Mooney-Rivlin Q2",
            2,
            MooneyRivlin::new(0.8, 0.2, 10.0).into(),
            PressureMode::None,
        ),
        (
            "incompressible exact Q2/P1",
            2,
            MooneyRivlinIncompressible::new(0.8, 0.2).into(),
            PressureMode::Exact { p0: 2.4 },
        ),
        (
            "incompressible perturbed Q2/P1",
            2,
            MooneyRivlinIncompressible::new(0.8, 0.2).into(),
            PressureMode::Perturbed {
                kappa: 50.0,
                p0: 2.4,
            },
        ),
    ];
    for (name, order, mat, pm) in cases {
        let mut sys = tiny(order, mat, pm);
        let err = fd_error(&mut sys);
        eprintln!(
            "{name}: n_eq = {}, max|K − K_fd|/max|K| = {err:.2e}",
            sys.n_eq()
        );
        assert!(
            err < 1e-7,
            "{name}: tangent differs from FD of the residual by {err:.3e}"
        );
    }
}

#[test]
fn serial_and_parallel_assembly_agree() {
    // Two meshes large enough for the parallel schedules: ring-ordered cells cut into
    // contiguous chunks (n_r = 8), and a single ring where chunks wrap around and the cells are
    // coloured instead (n_r = 1).
    for (n_r, n_theta, chunked) in [(8usize, 40usize, true), (1, 300, false)] {
        let mesh = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r,
            n_theta,
            degree: 2,
            grading_r: 1.0,
            grading_theta: 0.0,
        });
        let mut model = SolidModel::new(
            mesh,
            MooneyRivlinIncompressible::new(0.8, 0.2).into(),
            0.8,
            PressureMode::Exact { p0: 2.4 },
        );
        model.omega2 = 2.0;
        let mut sys = SolidSystem::new(model, "hub");
        for (d, v) in sys.x.iter_mut().enumerate() {
            *v += 1e-4 * ((d as f64) * 0.7).sin();
        }
        assert_eq!(sys.asm.n_chunks() > 0, chunked, "schedule for n_r = {n_r}");
        assert_eq!(sys.asm.n_colors() > 0, !chunked);
        sys.asm.parallel = false;
        assert!(sys.evaluate(true));
        let (r1, k1) = (sys.residual().to_vec(), sys.matrix_values().to_vec());
        sys.asm.parallel = true;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        pool.install(|| assert!(sys.evaluate(true)));
        let (r2, k2) = (sys.residual().to_vec(), sys.matrix_values().to_vec());
        let sr = r1.iter().map(|a| a.abs()).fold(0.0, f64::max);
        let sk = k1.iter().map(|a| a.abs()).fold(0.0, f64::max);
        let dr = r1
            .iter()
            .zip(&r2)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let dk = k1
            .iter()
            .zip(&k2)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "n_r = {n_r}: chunks {}, colours {}: |Δr| = {dr:.2e}, |ΔK| = {dk:.2e}",
            sys.asm.n_chunks(),
            sys.asm.n_colors()
        );
        assert!(
            dr <= 1e-13 * sr && dk <= 1e-13 * sk,
            "serial/parallel differ: {dr:.2e} {dk:.2e}"
        );
    }
}

#[test]
fn tangent_is_symmetric_without_friction() {
    let mut sys = tiny(2, NeoHookean::new(2.0, 5.0).into(), PressureMode::None);
    assert!(sys.evaluate(true));
    let k = sys.asm.to_dense();
    let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for (i, ki) in k.iter().enumerate() {
        for (j, kj) in k.iter().enumerate() {
            assert!((ki[j] - kj[i]).abs() <= 1e-12 * kmax);
        }
    }
}

mod contact {
    use super::*;
    use tread::contact::laws::{CoulombLinear, CoulombTanh, OdenMartins, RateDependent};
    use tread::contact::{ContactModel, FacetRule, Friction, NormalCompliance};
    use tread::solver::stepping::LoadedSystem;

    /// A small mesh pushed into the road so that several facets are in contact, with a
    /// history state (x_prev) different from x so that friction slips.
    fn contact_system(
        friction: Friction,
        load: Option<f64>,
        m_n: f64,
        rule: FacetRule,
    ) -> SolidSystem {
        let mesh = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 2,
            n_theta: 16,
            degree: 2,
            grading_r: 1.0,
            grading_theta: 0.5,
        });
        let model = SolidModel::new(
            mesh,
            NeoHookean::new(2.0, 5.0).into(),
            0.8,
            PressureMode::None,
        );
        let normal = NormalCompliance::new(300.0, m_n, 0.0, 0.0);
        let cm = ContactModel::new(&model.mesh, 1.9, 0.0, normal, friction, rule, load);
        let mut sys = SolidSystem::with_contact(model, cm);
        for n in 0..sys.model.mesh.n_nodes() {
            let x = sys.model.mesh.nodes[n];
            if sys.dofs.eq[2 * n] != FIXED {
                sys.x[2 * n] = 0.02 * x[0] + 0.01 * x[1];
                sys.x[2 * n + 1] = 0.03 * (x[0] * 0.5).sin() + 0.02 * (x[1] + 1.0);
                sys.x_prev[2 * n] = sys.x[2 * n] - 0.004 * x[0];
            }
        }
        sys.set_load_step_length(0.5);
        sys
    }

    #[test]
    fn contact_tangent_matches_finite_differences() {
        let cases: Vec<(&str, Friction, Option<f64>, f64, FacetRule)> = vec![
            (
                "frictionless, m_n = 1, Gauss",
                Friction::None,
                None,
                1.0,
                FacetRule::Gauss(4),
            ),
            (
                "frictionless, m_n = 2, Lobatto",
                Friction::None,
                None,
                2.0,
                FacetRule::Lobatto(4),
            ),
            (
                "Coulomb tanh",
                Friction::CoulombTanh(CoulombTanh::new(0.3, 0.01)),
                None,
                1.0,
                FacetRule::Gauss(4),
            ),
            (
                "Coulomb linear",
                Friction::CoulombLinear(CoulombLinear::new(0.3, 0.5)),
                None,
                1.5,
                FacetRule::Gauss(3),
            ),
            (
                "rate dependent",
                Friction::RateDependent(RateDependent::new(0.5, 0.3, 0.01, 0.02)),
                None,
                1.0,
                FacetRule::Gauss(4),
            ),
            (
                "Oden-Martins",
                Friction::OdenMartins(OdenMartins::new(5.0, 1.5, 0.02)),
                None,
                1.0,
                FacetRule::Gauss(4),
            ),
            (
                "load control, frictionless",
                Friction::None,
                Some(3.0),
                1.0,
                FacetRule::Gauss(4),
            ),
            (
                "load control, Coulomb tanh",
                Friction::CoulombTanh(CoulombTanh::new(0.3, 0.01)),
                Some(3.0),
                1.0,
                FacetRule::Gauss(4),
            ),
        ];
        for (name, fr, load, m_n, rule) in cases {
            let mut sys = contact_system(fr, load, m_n, rule);
            assert!(sys.evaluate(false));
            let visited = sys.contact.as_ref().unwrap().visited_facets();
            let in_contact = sys.contact_samples().iter().filter(|s| s.t_n > 0.0).count();
            assert!(in_contact >= 4, "{name}: only {in_contact} contact points");
            let err = fd_error(&mut sys);
            eprintln!("{name}: {visited} facets visited, {in_contact} points in contact, max|K − K_fd|/max|K| = {err:.2e}");
            assert!(
                err < 1e-6,
                "{name}: contact tangent differs from FD by {err:.3e}"
            );
        }
    }

    #[test]
    fn load_control_equation_balances_hub_load() {
        // At a converged load-control state the contact force equals the hub load and the hub
        // reaction balances it.
        let mut sys = contact_system(Friction::None, Some(3.0), 1.0, FacetRule::Gauss(4));
        sys.x.iter_mut().take(sys.dofs.n_u).for_each(|v| *v = 0.0);
        sys.loading = tread::model::system::Loading::Load { load: 3.0 };
        sys.set_reference_force(3.0);
        let mut newton =
            tread::solver::Newton::new(&sys, tread::solver::LinearKind::Lu, Default::default())
                .unwrap();
        sys.set_load(1.0);
        newton.solve(&mut sys).expect("load control converges");
        let tot = ContactModel::totals(&sys.contact_samples());
        let (f, m) = sys.hub_reaction();
        eprintln!(
            "contact force ({:.6e}, {:.6e}), hub reaction ({:.6e}, {:.6e}), moment {m:.3e}",
            tot.force_x, tot.force_y, f[0], f[1]
        );
        assert!(
            (tot.force_y - 3.0).abs() < 1e-8,
            "contact force {} ≠ load",
            tot.force_y
        );
        assert!(
            (f[1] + 3.0).abs() < 1e-7 && f[0].abs() < 1e-7,
            "hub reaction {f:?}"
        );
    }
}

/// The steady mode's elastic-slip friction ([`tread::contact::steady_elastic`]): the assembled
/// tangent plus its matrix-free anchor coupling equals central finite differences of the
/// residual, at a state with points in entry, stick and slip, with and without load control,
/// Gauss and Lobatto points, Q1 and Q2.
#[test]
fn steady_elastic_slip_tangent_matches_finite_differences() {
    use tread::contact::laws::CoulombElastic;
    use tread::contact::steady_elastic::PointState;
    use tread::contact::{ContactModel, FacetRule, Friction, NormalCompliance};
    use tread::driver::steady::SteadyRolling;

    for (order, rule, load, k_t) in [
        (2, FacetRule::Gauss(4), None, 2.0e3),
        (2, FacetRule::Lobatto(4), Some(3.0), 2.0e3),
        (1, FacetRule::Gauss(3), Some(3.0), 5.0e2),
    ] {
        let mesh = annulus(&AnnulusSpec {
            ri: 1.0,
            ro: 2.0,
            n_r: 2,
            n_theta: 24,
            degree: order,
            grading_r: 1.0,
            grading_theta: 0.6,
        });
        let model = SolidModel::new(
            mesh,
            NeoHookean::new(2.0, 5.0).into(),
            0.01,
            PressureMode::None,
        );
        let contact = ContactModel::new(
            &model.mesh,
            1.9,
            1.99,
            NormalCompliance::new(300.0, 1.0, 0.0, 0.0),
            Friction::CoulombElastic(CoulombElastic::new(0.3, k_t)),
            rule,
            load,
        );
        let mut st = SteadyRolling::new(SolidSystem::with_contact(model, contact), 1.0, 2.0);
        // A smooth state pressed into the road, with a tangential shear that makes the
        // material stick at entry and slip behind.
        for nd in 0..st.sys.model.mesh.n_nodes() {
            let x = st.sys.model.mesh.nodes[nd];
            if st.sys.dofs.eq[2 * nd] != FIXED {
                let r = x.norm();
                st.sys.x[2 * nd] = 0.004 * (r - 1.0) * (3.0 * x[0]).sin() + 0.001 * x[1];
                st.sys.x[2 * nd + 1] = 0.02 * (r - 1.0) * (1.0 + 0.3 * x[0]);
            }
        }
        if load.is_some() {
            let dofs = &st.sys.dofs;
            let g = dofs.global(0);
            st.sys.x[g] = 1.93;
        }
        assert!(st.evaluate(true));
        let m = st
            .sys
            .contact
            .as_ref()
            .unwrap()
            .elastic
            .clone()
            .expect("march");
        let count =
            |f: &dyn Fn(&PointState) -> bool| m.points.iter().filter(|p| f(&p.state)).count();
        let (stick, slip) = (
            count(&|s| matches!(s, PointState::Stick { .. })),
            count(&|s| matches!(s, PointState::Slip { .. })),
        );
        let k = st.sys.asm.to_dense();
        let n = st.n_eq();
        let kmax = k.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut col = vec![0.0; n];
        let mut e = vec![0.0; n];
        let mut err = 0.0f64;
        let h = 1e-7;
        for j in 0..n {
            e.fill(0.0);
            e[j] = 1.0;
            col.fill(0.0);
            st.tangent_correction(&e, &mut col);
            e[j] = h;
            st.update(1.0, &e);
            assert!(st.evaluate(false));
            let rp = st.residual().to_vec();
            st.update(-2.0, &e);
            assert!(st.evaluate(false));
            let rm = st.residual().to_vec();
            st.update(1.0, &e);
            for i in 0..n {
                let fd = (rp[i] - rm[i]) / (2.0 * h);
                err = err.max((fd - k[i][j] - col[i]).abs());
            }
        }
        assert!(st.evaluate(true));
        let err = err / kmax;
        eprintln!(
            "Q{order} {rule:?} load {load:?}: {stick} stick, {slip} slip points, {} anchors; \
             max|K − K_fd|/max|K| = {err:.2e}",
            m.anchors.len()
        );
        assert!(stick >= 4 && slip >= 2, "{stick} stick, {slip} slip points");
        assert!(
            err < 1e-5,
            "elastic-slip tangent differs from FD by {err:.3e}"
        );
    }
}
