//! Viscoelastic laws on homogeneous deformations: stress relaxation after a step strain and
//! creep under a constant stress, against closed forms and an independent ODE reference;
//! non-negative dissipation of the multiplicative model along random strain paths.

use tread::material::{
    check_stateful, Constitutive, Material, MooneyRivlinIncompressible, NeoHookean, SplitMix,
    ViscoModel, Viscoelastic, ViscoelasticMaterial,
};
use tread::math::Mat2;

fn green(h: &Mat2) -> Mat2 {
    let f = Mat2::identity() + h;
    (f.transpose() * f - Mat2::identity()) * 0.5
}

const MODELS: [ViscoModel; 2] = [ViscoModel::Convolution, ViscoModel::Multiplicative];

/// Step strain at t = 0 (applied in a step of length 0: the instantaneous response), then held:
/// the overstress relaxes exactly as the closed forms
/// - convolution: S_v(t) = γ Σ g_i exp(−t/τ_i) E;
/// - multiplicative: E_v,i(t) = (1 − exp(−t/τ_i)) E, S_v = Σ μ_i ((I + 2E_v,i)⁻¹ − C⁻¹),
///
/// at finite strain, whatever the (random) step sizes, since the integrator is exact for a
/// strain that is piecewise linear in time.
#[test]
fn relaxation_after_a_step_strain_matches_closed_forms() {
    let prony = [(0.5, 0.1), (0.3, 1.0), (0.2, 10.0)];
    let gamma = 6.0;
    let h = Mat2::new(0.25, 0.4, -0.1, -0.15); // finite strain, rotation included
    let f = Mat2::identity() + h;
    let e = green(&h);
    let c_inv = (f.transpose() * f).try_inverse().unwrap();
    let mut rng = SplitMix(11);
    for model in MODELS {
        let elastic = Material::from(NeoHookean::new(2.0, 5.0));
        let m = ViscoelasticMaterial {
            elastic,
            visco: Viscoelastic::new(model, gamma, &prony).unwrap(),
        };
        let n = m.n_state();
        let (mut s, mut s1) = (vec![0.0; n], vec![0.0; n]);
        let mut t = 0.0;
        let mut worst = 0.0_f64;
        let mut dt = 0.0;
        while t < 30.0 {
            let (p, _) = m.update(&h, &s, dt, &mut s1, false);
            s.copy_from_slice(&s1);
            t += dt;
            let pe = tread::material::Hyperelastic::stress(&elastic, &h);
            let sv = match model {
                ViscoModel::Convolution => {
                    e * (gamma
                        * prony
                            .iter()
                            .map(|(g, tau)| g * (-t / tau).exp())
                            .sum::<f64>())
                }
                ViscoModel::Multiplicative => prony
                    .iter()
                    .map(|(g, tau)| {
                        let ev = e * (1.0 - (-t / tau).exp());
                        let gi = (Mat2::identity() + ev * 2.0).try_inverse().unwrap();
                        (gi - c_inv) * (0.5 * gamma * g)
                    })
                    .sum(),
            };
            let expected = pe + f * sv;
            let err = (p - expected).norm() / (f * sv).norm().max(1e-300);
            // Relative to the overstress itself (which decays by e^{-3} over the run).
            assert!(err < 1e-11, "{model:?} at t = {t}: {p} vs {expected}");
            worst = worst.max(err);
            dt = 0.05 + 0.5 * rng.next();
        }
        // At the end the short terms are gone: only g3 e^{-3} remains (convolution).
        println!("relaxation {model:?}: worst rel err of the overstress {worst:.2e}");
    }
}

/// Creep under a constant shear stress at small strain, for a one-term Prony series (a standard
/// linear solid: closed form) and a two-term one (reference: RK4 on the ODE system of the
/// linear solid, written here). The material's strain is found at each step by a scalar Newton
/// on P12(γ_s) = τ0 with the law's algorithmic tangent; the error decreases as Δt² (the strain
/// path is taken linear over each step), and the observed order is checked.
#[test]
fn creep_under_constant_shear_stress_matches_reference() {
    let g_inf = 1.5;
    let tau0 = 1e-6 * g_inf; // small strain: finite-strain terms are 1e-6 relative
    for model in MODELS {
        for prony in [vec![(1.0, 0.4)], vec![(0.7, 0.2), (0.3, 3.0)]] {
            let gamma = 4.0; // Σ G_i = γ/2 Σ g_i = 2
            let visco = Viscoelastic::new(model, gamma, &prony).unwrap();
            let m = ViscoelasticMaterial {
                elastic: NeoHookean::new(g_inf, 3.0).into(),
                visco,
            };
            let gs: Vec<(f64, f64)> = prony.iter().map(|(g, t)| (0.5 * gamma * g, *t)).collect();
            let t_end = 6.0;
            // Independent reference: q_i' = G_i γ' − q_i/τ_i with G∞ γ + Σ q_i = τ0, i.e.
            // γ' = Σ (q_i/τ_i) / (G∞ + Σ G_i); RK4 with 20000 steps.
            let reference = |t_out: f64| -> f64 {
                let g_tot: f64 = g_inf + gs.iter().map(|g| g.0).sum::<f64>();
                // Instantaneous response: γ(0+) = τ0/(G∞ + ΣG_i), q_i(0+) = G_i γ(0+).
                let g0 = tau0 / g_tot;
                let mut q: Vec<f64> = gs.iter().map(|g| g.0 * g0).collect();
                let rhs = |q: &[f64]| -> Vec<f64> {
                    let gd = q.iter().zip(&gs).map(|(qi, g)| qi / g.1).sum::<f64>() / g_tot;
                    q.iter()
                        .zip(&gs)
                        .map(|(qi, g)| g.0 * gd - qi / g.1)
                        .collect()
                };
                let n = 20000;
                let h = t_out / n as f64;
                for _ in 0..n {
                    let k1 = rhs(&q);
                    let y2: Vec<f64> = q.iter().zip(&k1).map(|(a, b)| a + 0.5 * h * b).collect();
                    let k2 = rhs(&y2);
                    let y3: Vec<f64> = q.iter().zip(&k2).map(|(a, b)| a + 0.5 * h * b).collect();
                    let k3 = rhs(&y3);
                    let y4: Vec<f64> = q.iter().zip(&k3).map(|(a, b)| a + h * b).collect();
                    let k4 = rhs(&y4);
                    for i in 0..q.len() {
                        q[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
                    }
                }
                (tau0 - q.iter().sum::<f64>()) / g_inf
            };
            let closed_form = |t: f64| -> Option<f64> {
                (gs.len() == 1).then(|| {
                    let (g1, tau) = gs[0];
                    let tc = tau * (g_inf + g1) / g_inf;
                    tau0 / g_inf - tau0 * (1.0 / g_inf - 1.0 / (g_inf + g1)) * (-t / tc).exp()
                })
            };
            let r_end = reference(t_end);
            if let Some(cf) = closed_form(t_end) {
                assert!(
                    (r_end - cf).abs() < 1e-12 * cf,
                    "RK4 reference {r_end} vs {cf}"
                );
            }
            let run = |nsteps: usize| -> f64 {
                let dt = t_end / nsteps as f64;
                let n = m.n_state();
                let (mut s, mut s1) = (vec![0.0; n], vec![0.0; n]);
                let mut gam = 0.0;
                // Instantaneous loading (Δt = 0), then constant stress.
                for k in 0..=nsteps {
                    let step = if k == 0 { 0.0 } else { dt };
                    for _ in 0..20 {
                        let h = Mat2::new(0.0, gam, 0.0, 0.0);
                        let (p, a) = m.update(&h, &s, step, &mut s1, true);
                        let r = p[(0, 1)] - tau0;
                        if r.abs() < 1e-15 * tau0 {
                            break;
                        }
                        gam -= r / a[(1, 1)];
                    }
                    let h = Mat2::new(0.0, gam, 0.0, 0.0);
                    m.update(&h, &s, step, &mut s1, false);
                    s.copy_from_slice(&s1);
                }
                gam
            };
            let e1 = (run(60) - r_end).abs() / r_end;
            let e2 = (run(120) - r_end).abs() / r_end;
            let order = (e1 / e2).log2();
            println!(
                "creep {model:?} {} terms: γ(t_end) = {r_end:.6e}, rel err {e1:.2e} (Δt), {e2:.2e} (Δt/2), order {order:.2}",
                prony.len()
            );
            assert!(e2 < 2e-4, "{e2}");
            assert!((order - 2.0).abs() < 0.2, "order {order}");
        }
    }
}

/// The multiplicative model dissipates: along random strain paths (rotations, compression,
/// shear, at finite strain), (1) the dissipation rate D = −∂ψ/∂E_v : Ė_v, with ∂ψ/∂E_v by finite
/// differences of the free energy and Ė_v = (E − E_v)/τ from the evolution law, is ≥ 0 at every
/// point and equals the closed form; (2) the work done on the material minus the change of free
/// energy, accumulated with fine steps (trapezoidal work), never decreases beyond the
/// quadrature error.
#[test]
fn multiplicative_model_dissipation_is_non_negative_along_random_paths() {
    let prony = [(0.6, 0.05), (0.4, 0.7)];
    let visco = Viscoelastic::new(ViscoModel::Multiplicative, 3.0, &prony).unwrap();
    let m = ViscoelasticMaterial {
        elastic: MooneyRivlinIncompressible::new(0.8, 0.2).into(),
        visco,
    };
    let n = m.n_state();
    let mut rng = SplitMix(2024);
    let mut min_rate = f64::INFINITY;
    let mut min_cum = f64::INFINITY;
    for path in 0..20 {
        // Random piecewise-smooth path: sum of sinusoids in each component of ∇u.
        let amp: Vec<f64> = (0..12).map(|_| 0.4 * (2.0 * rng.next() - 1.0)).collect();
        let freq: Vec<f64> = (0..12).map(|_| 0.5 + 6.0 * rng.next()).collect();
        let grad = |t: f64| {
            Mat2::from_fn(|i, j| {
                let k = 2 * i + j;
                amp[k] * (freq[k] * t).sin()
                    + amp[k + 4] * (freq[k + 4] * t).cos() * t.min(1.0)
                    + amp[k + 8] * (1.0 - (-(freq[k + 8]) * t).exp()) * 0.5
            })
        };
        let (mut s, mut s1) = (vec![0.0; n], vec![0.0; n]);
        // Start from a relaxed state at grad(0): E_v = E(0).
        let h0 = grad(0.0);
        let e0 = green(&h0);
        s[0] = e0[(0, 0)];
        s[1] = e0[(1, 1)];
        s[2] = e0[(0, 1)];
        for i in 0..prony.len() {
            s[3 + 3 * i..6 + 3 * i].copy_from_slice(&[e0[(0, 0)], e0[(1, 1)], e0[(0, 1)]]);
        }
        let nsteps = 4000;
        let dt = 2.0 / nsteps as f64;
        let (mut p_old, _) = m.update(&h0, &s, 0.0, &mut s1, false);
        let psi = |h: &Mat2, st: &[f64]| visco.free_energy(h, st).unwrap();
        let mut h_old = h0;
        let mut cum = 0.0;
        for k in 1..=nsteps {
            let h = grad(k as f64 * dt);
            if (Mat2::identity() + h).determinant() < 0.3 {
                break;
            }
            let psi_old = psi(&h_old, &s);
            let (p, _) = m.update(&h, &s, dt, &mut s1, false);
            // Work on the overstress only: the elastic part is conservative.
            let pe_old = tread::material::Hyperelastic::stress(&m.elastic, &h_old);
            let pe = tread::material::Hyperelastic::stress(&m.elastic, &h);
            let work = 0.5
                * ((p - pe) + (p_old - pe_old))
                    .component_mul(&(h - h_old))
                    .sum();
            cum += work - (psi(&h, &s1) - psi_old);
            min_cum = min_cum.min(cum / (k as f64 * dt));
            s.copy_from_slice(&s1);
            p_old = p;
            h_old = h;
            // (1) The rate at the new state, closed form and from ∂ψ/∂E_v.
            let d = visco.dissipation_rate(&h, &s).unwrap();
            let e = green(&h);
            let mut d_fd = 0.0;
            for (i, &(_, tau)) in prony.iter().enumerate() {
                let rate = [
                    (e[(0, 0)] - s[3 + 3 * i]) / tau,
                    (e[(1, 1)] - s[4 + 3 * i]) / tau,
                    (e[(0, 1)] - s[5 + 3 * i]) / tau,
                ];
                for (c, r) in rate.iter().enumerate() {
                    let eps = 1e-6;
                    let (mut sp, mut sm) = (s.clone(), s.clone());
                    sp[3 + 3 * i + c] += eps;
                    sm[3 + 3 * i + c] -= eps;
                    let dpsi = (psi(&h, &sp) - psi(&h, &sm)) / (2.0 * eps);
                    d_fd -= dpsi * r;
                }
            }
            assert!(d >= 0.0, "path {path}, step {k}: D = {d}");
            assert!(
                (d - d_fd).abs() <= 1e-6 * d.abs().max(1e-3),
                "path {path}, step {k}: D = {d}, from ψ: {d_fd}"
            );
            min_rate = min_rate.min(d);
        }
    }
    // The accumulated dissipation per unit time: ≥ 0 up to the O(Δt²) trapezoidal error.
    println!("dissipation: min rate {min_rate:.3e}, min cumulative mean {min_cum:.3e}");
    assert!(min_cum > -1e-6, "{min_cum}");
}

/// The convolution model has no free energy; its tangent with history passes the same stateful
/// FD check as the multiplicative one on an incompressible base law at large strain.
#[test]
fn fd_tangent_with_history_at_large_strain() {
    let mut rng = SplitMix(99);
    for model in MODELS {
        let m = ViscoelasticMaterial {
            elastic: MooneyRivlinIncompressible::new(80.0, 20.0).into(),
            visco: Viscoelastic::new(model, 150.0, &[(0.5, 0.01), (0.5, 0.2)]).unwrap(),
        };
        let n = m.n_state();
        let mut s = vec![0.0; n];
        let mut s1 = vec![0.0; n];
        let mut worst = 0.0_f64;
        for k in 0..50 {
            let h = Mat2::from_fn(|_, _| 0.6 * (2.0 * rng.next() - 1.0));
            if (Mat2::identity() + h).determinant() < 0.4 {
                continue;
            }
            let dt = 0.002 * (1 + k % 7) as f64;
            let r = check_stateful(&m, &h, &s, dt);
            assert!(r.tangent_rel_err < 1e-7 && r.stress_rel_err < 1e-9, "{r:?}");
            worst = worst.max(r.tangent_rel_err);
            m.update(&h, &s, dt, &mut s1, false);
            s.copy_from_slice(&s1);
        }
        println!("{model:?}: worst FD tangent rel err {worst:.2e}");
    }
}
