//! Steady rolling: the internal variables along a closed ring of quadrature points.
//!
//! In steady rolling at angular speed ω the history of a material point is the spatial history
//! along its reference circle (θ = Θ + ω t). Both viscoelastic models of
//! [`super::viscoelastic`] have internal variables obeying a linear ODE with constant
//! coefficients, `Ẋ + X/τ = f(E, Ė)`, which along a ring becomes
//!
//! ```text
//! ω ∂θX + X/τ = f(E, ω ∂θE),          X(θ + 2π) = X(θ)
//! ```
//!
//! (convolution: `X = Q`, `f = g ω ∂θE`; multiplicative: `X = E_v`, `f = E/τ`). With `E`
//! linear in θ between consecutive points `θ_k → θ_{k+1}` (spacing `Δθ_k`, time `Δt_k = Δθ_k/ω`)
//! the step of the exponential integrator is exact, so the ring is the cyclic affine recurrence
//!
//! ```text
//! X_{k+1} = a_k X_k + c_k(E_k, E_{k+1}),      k = 0 … m−1 (indices mod m),   a_k = exp(−Δt_k/τ)
//! ```
//!
//! whose periodic solution is exact (no start-up, no truncation of the memory):
//! `X_0 = (1 − A)⁻¹ Σ_k (Π_{j>k} a_j) c_k`, `A = Π a_k < 1`, then the forward sweep. Its cost is
//! two sweeps, O(m), and it never forms the dense ring operator: the map `c ↦ X` is
//! `K = (lower semiseparable) + A/(1 − A) · p qᵀ` with `p_i = Π_{j<i} a_j`,
//! `q_k = 1/Π_{j≤k} a_j`, applied by the same sweeps ([`periodic_affine`]) and its transpose by
//! the backward sweeps ([`periodic_affine_transpose`]). In a global Newton tangent the ring
//! coupling keeps its sparsity when the recurrence itself is kept as equations (bidiagonal
//! plus one wrap-around entry per ring) instead of eliminating `X` (which would couple every
//! point to the whole ring upstream).

use super::viscoelastic::{exp_weights, ViscoModel, Viscoelastic};

/// The periodic solution of `x_{k+1} = a_k x_k + c_k` (indices mod m), written into `x`.
/// `a_k ∈ [0, 1)`. Two O(m) sweeps; no product of the `a_k` is formed that could underflow
/// harmlessly or not (the wrap-around factor A only enters through `1 − A`).
pub fn periodic_affine(a: &[f64], c: &[f64], x: &mut [f64]) {
    let m = a.len();
    // Sweep from zero: y_m = Σ_k (Π_{j>k} a_j) c_k, and A = Π a_k.
    let mut y = 0.0;
    let mut big_a = 1.0;
    for k in 0..m {
        y = a[k] * y + c[k];
        big_a *= a[k];
    }
    let mut xk = y / (1.0 - big_a);
    for k in 0..m {
        x[k] = xk;
        xk = a[k] * xk + c[k];
    }
}

/// Flow-order index `j` of a ring of `m` points: counter-clockwise for ω ≥ 0, clockwise
/// otherwise. Returns (point position, spacing index from this point to the next in flow).
#[inline]
pub fn flow(j: usize, m: usize, forward: bool) -> (usize, usize) {
    if forward {
        (j, j)
    } else {
        // Position m−1−j; the next in flow is m−2−j (mod m), spacing dθ[m−2−j] (mod m).
        (m - 1 - j, (2 * m - 2 - j) % m)
    }
}

/// Scratch of [`sweep_ring`] (grown as needed).
#[derive(Clone, Debug, Default)]
pub struct RingScratch {
    a: Vec<f64>,
    phi: Vec<f64>,
    c: Vec<f64>,
    x: Vec<f64>,
}

/// The periodic solution `X = L_i e` of the exact step recurrence along one closed ring of
/// points `pts` (counter-clockwise; `dtheta[k]` the angle from point k to k + 1, the last one
/// wrapping to point 0) at angular speed `omega` (the flow runs clockwise for ω < 0), for each
/// Prony term i of `ve` and each of the `n_comp` components of the per-point values
/// `e(point, component)`, handed to `out(point, term, component, X)` (`point` the entry of
/// `pts`).
#[allow(clippy::too_many_arguments)]
pub fn sweep_ring(
    pts: &[u32],
    dtheta: &[f64],
    ve: &Viscoelastic,
    omega: f64,
    n_comp: usize,
    e: impl Fn(usize, usize) -> f64,
    out: &mut impl FnMut(usize, usize, usize, f64),
    s: &mut RingScratch,
) {
    let forward = omega >= 0.0;
    let w = omega.abs();
    let m = pts.len();
    for v in [&mut s.a, &mut s.phi, &mut s.c, &mut s.x] {
        v.resize(m, 0.0);
    }
    for (i, &(g, tau)) in ve.prony().iter().enumerate() {
        for j in 0..m {
            let (_, k) = flow(j, m, forward);
            let (a, phi) = exp_weights(dtheta[k] / (w * tau));
            s.a[j] = a;
            s.phi[j] = phi;
        }
        for comp in 0..n_comp {
            for j in 0..m {
                let (k0, _) = flow(j, m, forward);
                let (k1, _) = flow((j + 1) % m, m, forward);
                let (e0, e1) = (e(pts[k0] as usize, comp), e(pts[k1] as usize, comp));
                let (a, phi) = (s.a[j], s.phi[j]);
                s.c[j] = match ve.model {
                    ViscoModel::Convolution => g * phi * (e1 - e0),
                    ViscoModel::Multiplicative => (phi - a) * e0 + (1.0 - phi) * e1,
                };
            }
            periodic_affine(&s.a, &s.c, &mut s.x);
            for j in 0..m {
                let (k, _) = flow(j, m, forward);
                out(pts[k] as usize, i, comp, s.x[j]);
            }
        }
    }
}

/// `Kᵀ r` for the linear map `K: c ↦ x` of [`periodic_affine`]: the periodic solution of the
/// adjoint recurrence `z_k = a_{k+1} z_{k+1} + r_{k+1}` (indices mod m), so that
/// `Σ_k r_k x_k = Σ_k z_k c_k` for every `c`.
pub fn periodic_affine_transpose(a: &[f64], r: &[f64], z: &mut [f64]) {
    let m = a.len();
    // m backward steps from z_{m−1} = 0 around the ring back to z_{m−1}.
    let mut y = 0.0;
    let mut big_a = 1.0;
    for j in (0..m).rev() {
        // a_{k+1}, r_{k+1} for k = m−2, …, 0 and then k = m−1 (wrapping to j = 0).
        y = a[j] * y + r[j];
        big_a *= a[j];
    }
    let mut zk = y / (1.0 - big_a);
    z[m - 1] = zk;
    for k in (0..m.saturating_sub(1)).rev() {
        zk = a[k + 1] * zk + r[k + 1];
        z[k] = zk;
    }
}

impl Viscoelastic {
    /// Steady states along one closed ring: `e[k]` the Green strain `[E11, E22, E12]` at the
    /// `m` points of the ring (counter-clockwise), `dtheta[k]` the angle from point k to point
    /// k + 1 (the last one wraps to point 0), spinning at `omega > 0`. Writes the full state of
    /// each point (`n_state` values, the layout of [`super::viscoelastic`]) into `states`
    /// (`m · n_state`): the periodic solution of the exact step recurrence. The overstress at a
    /// point is then [`Viscoelastic::overstress`] with `Δt = 0` from its state.
    pub fn ring_states(&self, omega: f64, dtheta: &[f64], e: &[[f64; 3]], states: &mut [f64]) {
        let m = e.len();
        let ns = self.n_state();
        let mut a = vec![0.0; m];
        let mut c = vec![0.0; m];
        let mut x = vec![0.0; m];
        for k in 0..m {
            states[k * ns..k * ns + 3].copy_from_slice(&e[k]);
        }
        for (i, &(g, tau)) in self.prony().iter().enumerate() {
            let weights: Vec<(f64, f64)> = dtheta
                .iter()
                .map(|d| exp_weights(d / (omega * tau)))
                .collect();
            for k in 0..m {
                a[k] = weights[k].0;
            }
            for comp in 0..3 {
                for k in 0..m {
                    let (ak, phi) = weights[k];
                    let (e0, e1) = (e[k][comp], e[(k + 1) % m][comp]);
                    c[k] = match self.model {
                        ViscoModel::Convolution => g * phi * (e1 - e0),
                        ViscoModel::Multiplicative => (phi - ak) * e0 + (1.0 - phi) * e1,
                    };
                }
                periodic_affine(&a, &c, &mut x);
                for k in 0..m {
                    states[k * ns + 3 + 3 * i + comp] = x[k];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::fd_check::SplitMix;
    use crate::math::Mat2;

    fn random_ring(m: usize, rng: &mut SplitMix) -> (Vec<f64>, Vec<f64>) {
        let a: Vec<f64> = (0..m).map(|_| 0.3 + 0.69 * rng.next()).collect();
        let c: Vec<f64> = (0..m).map(|_| 2.0 * rng.next() - 1.0).collect();
        (a, c)
    }

    #[test]
    #[allow(clippy::needless_range_loop)] // dense matrix indexed as in the formulas
    fn periodic_solution_satisfies_the_recurrence_and_its_transpose_is_the_adjoint() {
        let mut rng = SplitMix(5);
        for m in [1, 2, 7, 64] {
            let (a, c) = random_ring(m, &mut rng);
            let mut x = vec![0.0; m];
            periodic_affine(&a, &c, &mut x);
            for k in 0..m {
                let r = x[(k + 1) % m] - a[k] * x[k] - c[k];
                assert!(r.abs() < 1e-13, "m = {m}, k = {k}: {r}");
            }
            // Dense K column by column, then Kᵀ r against the transpose sweep.
            let mut kmat = vec![vec![0.0; m]; m];
            let mut e = vec![0.0; m];
            for j in 0..m {
                e.fill(0.0);
                e[j] = 1.0;
                periodic_affine(&a, &e, &mut x);
                for i in 0..m {
                    kmat[i][j] = x[i];
                }
            }
            let r: Vec<f64> = (0..m).map(|_| rng.next() - 0.5).collect();
            let mut z = vec![0.0; m];
            periodic_affine_transpose(&a, &r, &mut z);
            for j in 0..m {
                let kt: f64 = (0..m).map(|i| kmat[i][j] * r[i]).sum();
                assert!(
                    (kt - z[j]).abs() < 1e-12,
                    "m = {m}, j = {j}: {kt} vs {}",
                    z[j]
                );
            }
            // The semiseparable form: K_ik = (P_i/P_{k+1}) ([i > k] + A/(1 − A)).
            if m <= 7 {
                let p = |i: usize| a[..i].iter().product::<f64>();
                let big_a = p(m);
                for i in 0..m {
                    for k in 0..m {
                        let v = p(i) / p(k + 1)
                            * (if i > k { 1.0 } else { 0.0 } + big_a / (1.0 - big_a));
                        assert!((v - kmat[i][k]).abs() < 1e-12, "({i}, {k})");
                    }
                }
            }
        }
    }

    /// Sinusoidal strain along the ring, E12(θ) = ε sin θ: the periodic (steady-state) solution
    /// of ω Q' + Q/τ = g ω E' is Q = g ε ωτ (ωτ sin θ + cos θ)/(1 + (ωτ)²) (convolution). The
    /// ring integration converges to it at second order in the point spacing, and a transient
    /// run of the step integrator around the ring for many revolutions converges to the same
    /// periodic states.
    #[test]
    fn ring_states_match_the_harmonic_steady_state_and_the_long_time_limit() {
        let (g, tau, omega, eps) = (0.8, 0.05, 20.0, 1e-3);
        let ve = Viscoelastic::new(ViscoModel::Convolution, 2.0, &[(g, tau)]).unwrap();
        let wt = omega * tau;
        let exact = |th: f64| g * eps * wt * (wt * th.sin() + th.cos()) / (1.0 + wt * wt);
        let mut errs = Vec::new();
        for m in [32, 64, 128] {
            let dth = 2.0 * std::f64::consts::PI / m as f64;
            let e: Vec<[f64; 3]> = (0..m)
                .map(|k| [0.0, 0.0, eps * (k as f64 * dth).sin()])
                .collect();
            let mut st = vec![0.0; m * ve.n_state()];
            ve.ring_states(omega, &vec![dth; m], &e, &mut st);
            let err = (0..m)
                .map(|k| (st[k * 6 + 5] - exact(k as f64 * dth)).abs())
                .fold(0.0, f64::max)
                / (g * eps);
            errs.push(err);
            if m == 64 {
                // Long-time limit of the step integrator (the transient history at one point).
                let n = ve.n_state();
                let (mut s, mut s1) = (vec![0.0; n], vec![0.0; n]);
                for step in 0..40 * m {
                    let k = (step + 1) % m;
                    let h = Mat2::new(0.0, 2.0 * e[k][2], 0.0, 0.0);
                    // ∇u with Green strain ≈ E (small strain: E12 = H12/2 + O(ε²)).
                    ve.overstress(&h, &s, dth / omega, &mut s1, false);
                    s.copy_from_slice(&s1);
                    s[0] = e[k][0];
                    s[1] = e[k][1];
                    s[2] = e[k][2];
                }
                // After 40 revolutions (decay e^{-40·2π/(ωτ)}), the state at point 0.
                let d = (s[5] - st[5]).abs() / (g * eps);
                assert!(d < 1e-12, "transient limit differs by {d}");
            }
        }
        let orders: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        println!("ring vs harmonic steady state: errors {errs:?}, orders {orders:.2?}");
        assert!(orders.iter().all(|p| (p - 2.0).abs() < 0.2), "{orders:?}");
        assert!(errs[2] < 1e-3);
    }

    #[test]
    fn multiplicative_ring_is_periodic_with_the_exact_step() {
        // The ring states are fixed points of the step integrator around the ring: stepping
        // from point k's state with the strain path to point k+1 gives point k+1's state.
        let ve =
            Viscoelastic::new(ViscoModel::Multiplicative, 3.0, &[(0.6, 0.01), (0.4, 0.2)]).unwrap();
        let m = 48;
        let omega = 15.0;
        let mut rng = SplitMix(8);
        let dth: Vec<f64> = (0..m).map(|_| 0.5 + rng.next()).collect();
        let total: f64 = dth.iter().sum();
        let dth: Vec<f64> = dth
            .iter()
            .map(|d| d * 2.0 * std::f64::consts::PI / total)
            .collect();
        // Admissible strains from symmetric stretches U = I + H (H symmetric, small).
        let hs: Vec<Mat2> = (0..m)
            .map(|k| {
                let t = k as f64 * 2.0 * std::f64::consts::PI / m as f64;
                Mat2::new(
                    0.2 * t.sin(),
                    0.1 * t.cos(),
                    0.1 * t.cos(),
                    -0.15 * (2.0 * t).sin(),
                )
            })
            .collect();
        let e: Vec<[f64; 3]> = hs
            .iter()
            .map(|h| {
                let g = super::super::viscoelastic::green_strain(h);
                [g[(0, 0)], g[(1, 1)], g[(0, 1)]]
            })
            .collect();
        let n = ve.n_state();
        let mut st = vec![0.0; m * n];
        ve.ring_states(omega, &dth, &e, &mut st);
        let mut new = vec![0.0; n];
        for k in 0..m {
            let k1 = (k + 1) % m;
            ve.overstress(
                &hs[k1],
                &st[k * n..(k + 1) * n],
                dth[k] / omega,
                &mut new,
                false,
            );
            for (a, b) in new.iter().zip(&st[k1 * n..(k1 + 1) * n]) {
                assert!((a - b).abs() < 1e-13, "point {k1}: {a} vs {b}");
            }
        }
    }
}
