//! Steady incompressible Navier–Stokes with Taylor–Hood Q2/Q1 on quadtrees: the exact Jacobian
//! against finite differences on a mesh with hanging nodes, manufactured-solution rates on
//! uniform and locally refined meshes, and the lid-driven cavity against published tables.

use std::f64::consts::PI;
use tread::adapt::moving_mesh::{moving_mesh_cavity, MonitorParams, VertexGrid};
use tread::adapt::navier_stokes::{
    cavity, errors, psi_min, solve_newton, stream_function, unit_square, CavityLid, NsSolution,
    TaylorHood,
};
use tread::adapt::quadtree::Quadtree;

/// A mesh with hanging nodes: uniform `levels`, then the leaves in the lower-left quadrant
/// refined once more.
fn locally_refined(levels: u32) -> Quadtree {
    let mut t = unit_square(levels);
    let marked: Vec<u32> = t
        .leaves()
        .into_iter()
        .filter(|&c| {
            let [x, y] = t.corner(c);
            x < 0.5 - 1e-12 && y < 0.5 - 1e-12
        })
        .collect();
    t.refine(&marked);
    assert!(t.is_balanced());
    t
}

// Manufactured solution: ψ = sin(πx) sin(πy), u = ∂ψ/∂y, v = −∂ψ/∂x (divergence-free),
// p = cos(πx) cos(πy) (zero mean). Δu = −2π² u; (u·∇)u = π³ (sin πx cos πx, sin πy cos πy).
fn mms_u(x: [f64; 2]) -> [f64; 2] {
    let (sx, cx, sy, cy) = (
        (PI * x[0]).sin(),
        (PI * x[0]).cos(),
        (PI * x[1]).sin(),
        (PI * x[1]).cos(),
    );
    [PI * sx * cy, -PI * cx * sy]
}
fn mms_grad(x: [f64; 2]) -> [[f64; 2]; 2] {
    let (sx, cx, sy, cy) = (
        (PI * x[0]).sin(),
        (PI * x[0]).cos(),
        (PI * x[1]).sin(),
        (PI * x[1]).cos(),
    );
    let p2 = PI * PI;
    [[p2 * cx * cy, -p2 * sx * sy], [p2 * sx * sy, -p2 * cx * cy]]
}
fn mms_p(x: [f64; 2]) -> f64 {
    (PI * x[0]).cos() * (PI * x[1]).cos()
}
fn mms_f(nu: f64) -> impl Fn([f64; 2]) -> [f64; 2] {
    move |x| {
        let u = mms_u(x);
        let (sx, cx, sy, cy) = (
            (PI * x[0]).sin(),
            (PI * x[0]).cos(),
            (PI * x[1]).sin(),
            (PI * x[1]).cos(),
        );
        let p3 = PI * PI * PI;
        [
            nu * 2.0 * PI * PI * u[0] + p3 * sx * cx - PI * sx * cy,
            nu * 2.0 * PI * PI * u[1] + p3 * sy * cy - PI * cx * sy,
        ]
    }
}

#[test]
fn jacobian_matches_finite_differences_with_hanging_nodes() {
    let t = locally_refined(1);
    let th = TaylorHood::new(&t, &|x, c| mms_u(x)[c]).unwrap();
    assert!(th.vel.n_hanging > 0 && th.pres.n_hanging > 0);
    let nu = 0.05;
    let f = mms_f(nu);
    // A state away from the solution: deterministic pseudo-random equation values.
    let n = th.n_eq();
    let y: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7371).sin() * 1.3).collect();
    let mut jac = vec![0.0; th.pattern.nnz()];
    let _ = th.residual(&y, nu, &f, Some(&mut jac));
    let pat = &th.pattern;
    let eps = 1e-6;
    let mut max_err: f64 = 0.0;
    let mut max_entry: f64 = 0.0;
    for j in 0..n {
        let mut yp = y.clone();
        let mut ym = y.clone();
        yp[j] += eps;
        ym[j] -= eps;
        let rp = th.residual(&yp, nu, &f, None);
        let rm = th.residual(&ym, nu, &f, None);
        let mut col = vec![0.0; n];
        for k in pat.col_ptr[j]..pat.col_ptr[j + 1] {
            col[pat.row_idx[k]] = jac[k];
        }
        for i in 0..n {
            let fd = (rp[i] - rm[i]) / (2.0 * eps);
            max_err = max_err.max((fd - col[i]).abs());
            max_entry = max_entry.max(col[i].abs());
        }
    }
    assert!(max_entry > 0.1);
    assert!(
        max_err < 1e-7 * max_entry,
        "FD mismatch {max_err:e} (max entry {max_entry:e})"
    );
}

fn mms_solve(t: &Quadtree, nu: f64) -> (usize, f64, [f64; 3]) {
    let th = TaylorHood::new(t, &|x, c| mms_u(x)[c]).unwrap();
    let mut y = vec![0.0; th.n_eq()];
    let f = mms_f(nu);
    let st = solve_newton(&th, &mut y, nu, &f, 1e-11, 20).unwrap();
    assert!(st.iterations <= 8, "{:?}", st.residuals);
    let sol = NsSolution {
        th: &th,
        x: th.distribute(&y),
    };
    let e = errors(&sol, &mms_u, &mms_grad, &mms_p);
    let hmax = t.leaves().iter().map(|&c| t.h(c)).fold(0.0, f64::max);
    (th.n_eq(), hmax, [e.u_l2, e.u_h1, e.p_l2])
}

fn check_rates(meshes: &[Quadtree], label: &str) {
    let nu = 0.1;
    let r: Vec<_> = meshes.iter().map(|t| mms_solve(t, nu)).collect();
    for w in r.windows(2) {
        let (_, h0, e0) = w[0];
        let (n1, h1, e1) = w[1];
        let rate = |k: usize| (e0[k] / e1[k]).ln() / (h0 / h1).ln();
        let (ru, rg, rp) = (rate(0), rate(1), rate(2));
        println!(
            "{label}: n_eq {n1} h {h1:.4} errors {:.3e} {:.3e} {:.3e} rates u {ru:.2} H1 {rg:.2} p {rp:.2}",
            e1[0], e1[1], e1[2]
        );
        assert!(ru > 2.8, "{label}: velocity L2 rate {ru}");
        assert!(rg > 1.9, "{label}: velocity H1 rate {rg}");
        assert!(rp > 1.9, "{label}: pressure L2 rate {rp}");
    }
}

#[test]
fn manufactured_solution_rates_uniform() {
    check_rates(&[unit_square(2), unit_square(3), unit_square(4)], "uniform");
}

#[test]
fn manufactured_solution_rates_locally_refined() {
    check_rates(
        &[locally_refined(2), locally_refined(3), locally_refined(4)],
        "local",
    );
}

use tread::adapt::cavity_reference::{
    GHIA_U100, GHIA_U400, GHIA_V100, GHIA_V400, GHIA_V400_MISPRINT, GHIA_X, GHIA_Y,
};
include!("common/botella_peyret.rs");
const BP_PSI_AT: [f64; 2] = [0.5308, 0.5652];

/// Largest deviation of u(0.5, y) and v(x, 0.5) from the tabulated stations (`skip_v`: indices of
/// v stations left out).
fn centreline_errors(
    sol: &NsSolution,
    ys: &[f64],
    us: &[f64],
    xs: &[f64],
    vs: &[f64],
    skip_v: &[usize],
) -> (f64, f64, usize, usize) {
    let (mut eu, mut ev, mut iu, mut iv) = (0.0f64, 0.0f64, 0, 0);
    for (i, (&y, &u)) in ys.iter().zip(us).enumerate() {
        let e = (sol.velocity([0.5, y]).unwrap().0[0] - u).abs();
        if e > eu {
            eu = e;
            iu = i;
        }
    }
    for (i, (&x, &v)) in xs.iter().zip(vs).enumerate() {
        if skip_v.contains(&i) {
            continue;
        }
        let e = (sol.velocity([x, 0.5]).unwrap().0[1] - v).abs();
        if e > ev {
            ev = e;
            iv = i;
        }
    }
    (eu, ev, iu, iv)
}

#[test]
fn driven_cavity_against_ghia_and_botella_peyret() {
    // 64 × 64 uniform Q2/Q1 (36 482 equations), continuation 100 → 400 → 1000.
    let t = unit_square(6);
    let run = cavity(&t, CavityLid::Discontinuous, &[100.0, 400.0, 1000.0], 1e-10).unwrap();
    let th = &run.th;
    for s in &run.stats {
        assert!(
            s.iterations <= 10,
            "Newton at nu = {}: {:?}",
            s.nu,
            s.residuals
        );
    }
    let sol = |k: usize| NsSolution {
        th,
        x: th.distribute(&run.states[k].1),
    };
    // Re = 100 against Ghia et al. Tables I and II.
    let s100 = sol(0);
    let (eu, ev, _, _) = centreline_errors(&s100, &GHIA_Y, &GHIA_U100, &GHIA_X, &GHIA_V100, &[]);
    println!("Re 100: max |u - Ghia| {eu:.3e}, max |v - Ghia| {ev:.3e}");
    assert!(eu < 1e-2 && ev < 1e-2);
    // Re = 400 against Ghia et al., the misprinted station left out.
    let s400 = sol(1);
    let (eu, ev, _, _) = centreline_errors(
        &s400,
        &GHIA_Y,
        &GHIA_U400,
        &GHIA_X,
        &GHIA_V400,
        &[GHIA_V400_MISPRINT],
    );
    println!("Re 400: max |u - Ghia| {eu:.3e}, max |v - Ghia| {ev:.3e} (x = 0.9063 left out)");
    assert!(eu < 2e-2 && ev < 2e-2);
    // Measured: the computed v there is about −0.39, 0.15 away from the printed value.
    let v_mis = s400.velocity([GHIA_X[GHIA_V400_MISPRINT], 0.5]).unwrap().0[1];
    println!(
        "Re 400: v(0.9063, 0.5) = {v_mis:.5} (Ghia prints {})",
        GHIA_V400[GHIA_V400_MISPRINT]
    );
    assert!((v_mis - GHIA_V400[GHIA_V400_MISPRINT]).abs() > 0.1);
    // Re = 1000 against Botella & Peyret.
    let s1000 = sol(2);
    let (space, psi) = stream_function(&s1000).unwrap();
    let (at, pm) = psi_min(th, &space, &psi);
    let rel = (pm - BP_PSI_MIN).abs() / BP_PSI_MIN.abs();
    let (eu, ev, _, _) = centreline_errors(&s1000, &BP_Y, &BP_U, &BP_X, &BP_V, &[]);
    println!(
        "Re 1000: psi_min {pm:.7} at ({:.4}, {:.4}), relative error {rel:.3e}; max |u - BP| {eu:.3e}, max |v - BP| {ev:.3e}",
        at[0], at[1]
    );
    assert!(rel < 1e-3);
    assert!((at[0] - BP_PSI_AT[0]).abs() < 2e-3 && (at[1] - BP_PSI_AT[1]).abs() < 2e-3);
    assert!(eu < 5e-3 && ev < 5e-3);
}

/// Regularised lid U = 16 x² (1 − x)²: in the Stokes limit (Re = 0.01) the flow is symmetric
/// under x ↦ 1 − x (the mesh is symmetric too), so the primary vortex centre lies on x = 0.5,
/// and the lid trace reproduces the lid velocity (no published reference is used here).
#[test]
fn driven_cavity_regularised_lid() {
    let t = unit_square(5);
    let run = cavity(&t, CavityLid::Regularised, &[0.01], 1e-12).unwrap();
    let th = &run.th;
    let s = NsSolution {
        th,
        x: th.distribute(&run.states[0].1),
    };
    let (space, psi) = stream_function(&s).unwrap();
    let (at, pm) = psi_min(th, &space, &psi);
    println!(
        "regularised lid, Re 0.01: psi_min {pm:.7} at ({:.5}, {:.5})",
        at[0], at[1]
    );
    assert!((at[0] - 0.5).abs() < 1e-4, "vortex centre at x = {}", at[0]);
    assert!(pm < 0.0);
    // The lid profile is of degree 4, outside the Q2 trace space: its boundary projection on
    // h = 1/32 is accurate to O(h³).
    let (u, _) = s.velocity([0.3, 1.0]).unwrap();
    let ul = 16.0 * 0.09 * 0.49;
    assert!((u[0] - ul).abs() < 1e-4, "lid u {} vs {ul}", u[0]);
}

#[test]
fn bad_input_is_an_error() {
    let t = unit_square(1);
    let th = TaylorHood::new(&t, &|x, c| CavityLid::Discontinuous.g(x, c)).unwrap();
    let mut y = vec![0.0; th.n_eq()];
    let zero = |_: [f64; 2]| [0.0, 0.0];
    for nu in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = solve_newton(&th, &mut y, nu, &zero, 1e-10, 5).unwrap_err();
        assert!(e.to_string().contains("viscosity"), "{e}");
    }
    let sol = NsSolution {
        th: &th,
        x: th.distribute(&y),
    };
    let e = sol.velocity([1.5, 0.5]).unwrap_err();
    assert!(e.to_string().contains("outside"), "{e}");
    // Newton that cannot converge in the allowed iterations says so.
    let e = solve_newton(&th, &mut y, 1e-3, &zero, 1e-300, 1).unwrap_err();
    assert!(e.to_string().contains("did not converge"), "{e}");
}

/// Re = 1000 on a locally refined mesh: 32 × 32 uniform, then three more levels in the cells
/// at the two top corners (hanging nodes in both fields), 9 140 equations. The corner
/// singularity dominates the error of ψ_min: the graded mesh reaches Botella & Peyret's value
/// to 1.2e-4 (measured) against 6.3e-3 on the uniform 32 × 32 mesh; the centreline profiles
/// stay limited by the bulk resolution (measured 4.0e-3 in u, 5.1e-3 in v, so the bound on
/// them is the measured level, not the 5e-3 target, which the 64 × 64 test meets).
#[test]
fn driven_cavity_graded_towards_lid_corners() {
    let mut t = unit_square(5);
    for _ in 0..3 {
        let marked: Vec<u32> = t
            .leaves()
            .into_iter()
            .filter(|&c| {
                let [x, y] = t.corner(c);
                let h = t.h(c);
                y + h > 1.0 - 1e-12 && (x < 1e-12 || x + h > 1.0 - 1e-12)
            })
            .collect();
        t.refine(&marked);
    }
    let run = cavity(&t, CavityLid::Discontinuous, &[100.0, 400.0, 1000.0], 1e-10).unwrap();
    let th = &run.th;
    assert!(th.vel.n_hanging > 0 && th.pres.n_hanging > 0);
    let s = NsSolution {
        th,
        x: th.distribute(&run.states[2].1),
    };
    let (space, psi) = stream_function(&s).unwrap();
    let (at, pm) = psi_min(th, &space, &psi);
    let rel = (pm - BP_PSI_MIN).abs() / BP_PSI_MIN.abs();
    let (eu, ev, _, _) = centreline_errors(&s, &BP_Y, &BP_U, &BP_X, &BP_V, &[]);
    println!(
        "graded, n_eq {}: psi_min {pm:.7} at ({:.4}, {:.4}), rel {rel:.3e}; u {eu:.3e} v {ev:.3e}",
        th.n_eq(),
        at[0],
        at[1]
    );
    assert!(rel < 1e-3);
    assert!(eu < 6e-3 && ev < 6e-3);
}

/// The Taylor–Hood pair on `levels` with the interior vertices displaced by a smooth field
/// (boundary vertices fixed): every cell becomes a general convex quadrilateral.
fn distorted(levels: u32) -> TaylorHood {
    let t = unit_square(levels);
    let mut th = TaylorHood::new(&t, &|x, c| mms_u(x)[c]).unwrap();
    let mut g = VertexGrid::new(&th).unwrap();
    let n = g.n;
    let h = 1.0 / n as f64;
    for j in 1..n {
        for i in 1..n {
            let p = &mut g.x[i + (n + 1) * j];
            let (x, y) = (p[0], p[1]);
            // Amplitude 0.2 h on the coarsest mesh, alternating with the vertex parity so the
            // cells stay distorted under refinement.
            let s = if (i + j) % 2 == 0 { 1.0 } else { -1.0 };
            p[0] += 0.2 * h * s * (PI * y).sin();
            p[1] += 0.15 * h * s * (PI * x).sin();
        }
    }
    th.set_corners(g.corners()).unwrap();
    assert!(th.min_det_j() > 0.0);
    th
}

#[test]
fn manufactured_solution_rates_distorted_cells() {
    let nu = 0.1;
    let f = mms_f(nu);
    let mut prev: Option<[f64; 3]> = None;
    for levels in 2..=4 {
        let th = distorted(levels);
        let mut y = vec![0.0; th.n_eq()];
        let st = solve_newton(&th, &mut y, nu, &f, 1e-11, 20).unwrap();
        assert!(st.iterations <= 8, "{:?}", st.residuals);
        let sol = NsSolution {
            th: &th,
            x: th.distribute(&y),
        };
        let e = errors(&sol, &mms_u, &mms_grad, &mms_p);
        let e = [e.u_l2, e.u_h1, e.p_l2];
        if let Some(e0) = prev {
            let r: Vec<f64> = (0..3).map(|k| (e0[k] / e[k]).log2()).collect();
            println!(
                "distorted level {levels}: errors {:.3e} {:.3e} {:.3e} rates {r:.2?}",
                e[0], e[1], e[2]
            );
            assert!(r[0] > 2.8 && r[1] > 1.9 && r[2] > 1.9, "rates {r:?}");
        }
        prev = Some(e);
    }
}

#[test]
fn relocation_with_constant_monitor_is_a_no_op() {
    let t = unit_square(3);
    let th = TaylorHood::new(&t, &|x, c| CavityLid::Discontinuous.g(x, c)).unwrap();
    let mut g = VertexGrid::new(&th).unwrap();
    let x0 = g.x.clone();
    let step = g
        .relocate(&|_| 3.0, 3.0, &MonitorParams::default())
        .unwrap();
    assert_eq!(step, 1.0);
    let d =
        g.x.iter()
            .zip(&x0)
            .map(|(a, b)| (a[0] - b[0]).abs().max((a[1] - b[1]).abs()))
            .fold(0.0, f64::max);
    assert!(d < 1e-14, "uniform mesh moved by {d:e}");
    // A mesh with hanging nodes is refused.
    let th = TaylorHood::new(&locally_refined(1), &|x, c| {
        CavityLid::Discontinuous.g(x, c)
    })
    .unwrap();
    assert!(VertexGrid::new(&th).is_err());
}

/// Re = 1000 (continuation 100 → 400 → 1000) on 16 × 16 cells: the fixed uniform mesh against
/// the same cells moved 8 times (α = 4, β = 4, γ = 0), both against Botella & Peyret's
/// centreline tables and ψ_min. Same cells, same dofs (2 210 equations). Measured: centreline
/// error 7.7e-2 → 3.1e-2, absolute ψ_min error 7.9e-3 → 4.3e-3. (At Re = 100 against Ghia et al. the
/// uniform 16 × 16 mesh already agrees to 8.6e-3, the level of the table's own accuracy, and
/// the moved mesh does not measurably differ, so that comparison is not asserted.)
#[test]
fn moving_mesh_cavity_re1000_beats_the_uniform_mesh() {
    let params = MonitorParams::default();
    let mut rows = Vec::new();
    moving_mesh_cavity(
        4,
        CavityLid::Discontinuous,
        &[100.0, 400.0, 1000.0],
        &params,
        8,
        1e-10,
        &mut |r, th, x| {
            assert!(r.min_det_j > 0.0, "recalculation {}: det J {}", r.index, r.min_det_j);
            let sol = NsSolution { th, x: x.to_vec() };
            let (eu, ev, _, _) =
                centreline_errors(&sol, &BP_Y, &BP_U, &BP_X, &BP_V, &[]);
            let (space, psi) = stream_function(&sol).unwrap();
            let (_, pm) = psi_min(th, &space, &psi);
            println!(
                "recalc {} n_eq {} min det J {:.3e} step {} newton {} psi_min {pm:.6} u {eu:.3e} v {ev:.3e}",
                r.index, th.n_eq(), r.min_det_j, r.step, r.newton_iterations
            );
            rows.push((eu.max(ev), (pm - BP_PSI_MIN).abs()));
        },
    )
    .unwrap();
    let (e0, p0) = rows[0];
    let (e8, p8) = rows[8];
    assert!(e8 < 0.7 * e0, "centreline error {e8:e} vs uniform {e0:e}");
    assert!(p8 < p0, "psi_min error {p8:e} vs uniform {p0:e}");
}
