//! Friction laws with a two-dimensional tangential slip vector (the 3D contact surface).
//!
//! In 3D the road is the plane x2 = −H and its tangent plane is spanned by x1 (rolling
//! direction) and x3 (the axle). The slip velocity of the body relative to the road is the
//! vector w = (w1, w3) = (ẋ1 − v0, ẋ3), and the tangential traction on the body (per unit
//! reference area) is the isotropic extension of a scalar law of [`super::laws`]:
//!
//! t_T(w) = t(s) ŵ,   s = |w|,  ŵ = w / s,
//!
//! where t(s) = [`FrictionLaw::eval`]`(s, t_n, δ).t` ≤ 0 is the scalar traction at slip speed s
//! (so t_T = −μ(|w|) t_n φ_ε(|w|) ŵ opposes the slip: t_T·w ≤ 0). Its derivatives are
//!
//! ∂t_T/∂w = t'(s) ŵŵᵀ + (t(s)/s)(I − ŵŵᵀ),   ∂t_T/∂t_n = (∂t/∂t_n)(s) ŵ,   ∂t_T/∂δ = (∂t/∂δ)(s) ŵ,
//!
//! with the limit t'(0) I at w = 0 (every scalar law is odd and C¹ at 0, so t(s)/s → t'(0)).
//! Below the slip speed [`S_TINY`] the secant t(s)/s is replaced by t'(s), which differs from
//! it by O(s²) for the smooth laws and not at all for the linear one; no division by a vanishing
//! s occurs. Units are those of the scalar laws, with traction per unit reference area.

use super::laws::{FrictionLaw, FrictionValue};
use nalgebra::{Matrix2, Vector2};

/// Slip speed below which the secant t(s)/s is replaced by the tangent t'(s) (velocity units;
/// far below every admissible regularisation ε of the scalar laws).
pub const S_TINY: f64 = 1e-100;

/// Value of a vector friction law and its derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionValueVec {
    /// Tangential traction on the body t_T = (t1, t3).
    pub t: Vector2<f64>,
    /// ∂t_T/∂w (symmetric 2×2).
    pub d_w: Matrix2<f64>,
    /// ∂t_T/∂t_n.
    pub d_tn: Vector2<f64>,
    /// ∂t_T/∂δ (non-zero only for compliance-type laws).
    pub d_delta: Vector2<f64>,
}

/// Isotropic vector friction built from any scalar law: traction and derivatives at the slip
/// vector `w`, normal traction `t_n` and penetration `delta`.
pub fn eval_vec<L: FrictionLaw + ?Sized>(
    law: &L,
    w: Vector2<f64>,
    t_n: f64,
    delta: f64,
) -> FrictionValueVec {
    let s = w.norm();
    if s.is_nan() {
        // A non-finite slip is not hidden: every output is NaN.
        let nan = Vector2::repeat(f64::NAN);
        return FrictionValueVec {
            t: nan,
            d_w: Matrix2::repeat(f64::NAN),
            d_tn: nan,
            d_delta: nan,
        };
    }
    if s == 0.0 {
        let v: FrictionValue = law.eval(0.0, t_n, delta);
        return FrictionValueVec {
            t: Vector2::zeros(),
            d_w: Matrix2::identity() * v.d_w,
            d_tn: Vector2::zeros(),
            d_delta: Vector2::zeros(),
        };
    }
    let v = law.eval(s, t_n, delta);
    let e = w / s;
    let secant = if s < S_TINY { v.d_w } else { v.t / s };
    let ee = e * e.transpose();
    FrictionValueVec {
        t: e * v.t,
        d_w: ee * v.d_w + (Matrix2::identity() - ee) * secant,
        d_tn: e * v.d_tn,
        d_delta: e * v.d_delta,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::laws::{CoulombLinear, CoulombTanh, Friction, OdenMartins, RateDependent};

    /// Deterministic uniform numbers in [0, 1) (64-bit LCG, top 53 bits).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    const EPS: f64 = 0.05;

    fn laws() -> Vec<(&'static str, Friction)> {
        vec![
            ("tanh", Friction::CoulombTanh(CoulombTanh::new(0.7, EPS))),
            (
                "linear",
                Friction::CoulombLinear(CoulombLinear::new(0.7, EPS)),
            ),
            (
                "rate",
                Friction::RateDependent(RateDependent::new(0.9, 0.5, 0.3, EPS)),
            ),
            (
                "oden",
                Friction::OdenMartins(OdenMartins::new(40.0, 1.5, EPS)),
            ),
        ]
    }

    fn close(tag: &str, a: f64, b: f64, rel: f64, abs: f64) {
        assert!(
            (a - b).abs() <= rel * a.abs().max(b.abs()) + abs,
            "{tag}: {a} vs {b} (diff {:e})",
            (a - b).abs()
        );
    }

    /// Random slip vectors: radii spread over several decades including tiny ones near w = 0.
    fn points(rng: &mut Lcg, n: usize) -> Vec<(Vector2<f64>, f64, f64)> {
        (0..n)
            .map(|k| {
                let th = 2.0 * std::f64::consts::PI * rng.next();
                let s = match k % 4 {
                    0 => EPS * 1e-3 * rng.next(),
                    1 => EPS * 0.9 * rng.next(),
                    2 => EPS * (1.1 + 3.0 * rng.next()),
                    _ => EPS * 20.0 * rng.next(),
                };
                let tn = 0.1 + 3.0 * rng.next();
                let delta = 0.01 + 0.2 * rng.next();
                (Vector2::new(s * th.cos(), s * th.sin()), tn, delta)
            })
            .collect()
    }

    #[test]
    fn derivatives_match_central_differences_for_every_law() {
        let mut rng = Lcg(12345);
        let pts = points(&mut rng, 400);
        for (name, law) in laws() {
            let mut checked = 0;
            for &(w, tn, delta) in &pts {
                let s = w.norm();
                // Step in w: small against ε and against the distance to the linear law's kink.
                let h = 1e-6 * EPS;
                if name == "linear" && (s - EPS).abs() < 1e3 * h {
                    continue;
                }
                let v = eval_vec(&law, w, tn, delta);
                for j in 0..2 {
                    let mut dw = Vector2::zeros();
                    dw[j] = h;
                    let tp = eval_vec(&law, w + dw, tn, delta).t;
                    let tm = eval_vec(&law, w - dw, tn, delta).t;
                    let fd = (tp - tm) / (2.0 * h);
                    let scale = v.d_w.abs().max();
                    for i in 0..2 {
                        close(
                            &format!("{name} d_w[{i}{j}] at w={w:?}"),
                            v.d_w[(i, j)],
                            fd[i],
                            1e-5,
                            1e-6 * scale,
                        );
                    }
                }
                let ht = 1e-6;
                let fdt = (eval_vec(&law, w, tn + ht, delta).t
                    - eval_vec(&law, w, tn - ht, delta).t)
                    / (2.0 * ht);
                let fdd = (eval_vec(&law, w, tn, delta + ht).t
                    - eval_vec(&law, w, tn, delta - ht).t)
                    / (2.0 * ht);
                for i in 0..2 {
                    close(&format!("{name} d_tn[{i}]"), v.d_tn[i], fdt[i], 1e-6, 1e-9);
                    close(
                        &format!("{name} d_delta[{i}]"),
                        v.d_delta[i],
                        fdd[i],
                        1e-6,
                        1e-9,
                    );
                }
                checked += 1;
            }
            assert!(checked > 350, "{name}: only {checked} points checked");
        }
    }

    #[test]
    fn zero_slip_limit_is_isotropic_tangent() {
        for (name, law) in laws() {
            let v0 = eval_vec(&law, Vector2::zeros(), 1.3, 0.1);
            let d0 = law.eval(0.0, 1.3, 0.1).d_w;
            assert!(d0 < 0.0, "{name}");
            assert_eq!(v0.t, Vector2::zeros());
            close(name, v0.d_w[(0, 0)], d0, 1e-15, 0.0);
            close(name, v0.d_w[(1, 1)], d0, 1e-15, 0.0);
            assert_eq!(v0.d_w[(0, 1)], 0.0);
            // Continuity of the tangent as w → 0, including below S_TINY.
            for &s in &[1e-9 * EPS, 1e-200] {
                let v = eval_vec(&law, Vector2::new(0.6 * s, -0.8 * s), 1.3, 0.1);
                assert!(v.d_w.iter().all(|x| x.is_finite()), "{name}");
                assert!(
                    (v.d_w - v0.d_w).abs().max() <= 1e-9 * d0.abs(),
                    "{name} s={s}"
                );
            }
        }
    }

    #[test]
    fn reduces_to_scalar_law_along_an_axis() {
        for (name, law) in laws() {
            for &w in &[-3.0 * EPS, -0.4 * EPS, 1e-4 * EPS, 0.3 * EPS, 2.5 * EPS] {
                let sc = law.eval(w, 1.7, 0.08);
                for axis in 0..2 {
                    let mut wv = Vector2::zeros();
                    wv[axis] = w;
                    let v = eval_vec(&law, wv, 1.7, 0.08);
                    close(name, v.t[axis], sc.t, 1e-14, 1e-300);
                    assert!(v.t[1 - axis].abs() == 0.0);
                    close(name, v.d_w[(axis, axis)], sc.d_w, 1e-13, 0.0);
                    close(name, v.d_tn[axis], sc.d_tn, 1e-14, 0.0);
                    close(name, v.d_delta[axis], sc.d_delta, 1e-14, 0.0);
                    // Transverse stiffness is the secant t(|w|)/|w|.
                    close(name, v.d_w[(1 - axis, 1 - axis)], sc.t / w, 1e-13, 0.0);
                }
            }
        }
    }

    #[test]
    fn isotropy_and_dissipation() {
        let mut rng = Lcg(777);
        let pts = points(&mut rng, 200);
        for (name, law) in laws() {
            for &(w, tn, delta) in &pts {
                let a = 2.0 * std::f64::consts::PI * rng.next();
                let r = Matrix2::new(a.cos(), -a.sin(), a.sin(), a.cos());
                let v = eval_vec(&law, w, tn, delta);
                let vr = eval_vec(&law, r * w, tn, delta);
                let scale = v.t.norm() + 1e-300;
                assert!((vr.t - r * v.t).norm() <= 1e-13 * scale, "{name} rotate t");
                let dr = r * v.d_w * r.transpose();
                assert!(
                    (vr.d_w - dr).abs().max() <= 1e-12 * v.d_w.abs().max(),
                    "{name} rotate d_w"
                );
                assert!(v.t.dot(&w) <= 0.0, "{name} dissipation");
                // The traction is parallel to −w.
                assert!((v.t.x * w.y - v.t.y * w.x).abs() <= 1e-14 * scale * w.norm());
            }
        }
    }

    #[test]
    fn non_finite_slip_is_not_hidden() {
        for (name, law) in laws() {
            let v = eval_vec(&law, Vector2::new(f64::NAN, 0.0), 1.0, 0.1);
            assert!(v.t.iter().chain(v.d_w.iter()).all(|x| x.is_nan()), "{name}");
        }
    }

    #[test]
    fn frictionless_is_zero() {
        let v = eval_vec(&Friction::None, Vector2::new(0.3, -0.2), 1.0, 0.1);
        assert_eq!(v.t, Vector2::zeros());
        assert_eq!(v.d_w, Matrix2::zeros());
    }
}
