// Hertz contact of a body with principal curvature radii R' and R'' pressed onto a rigid plane
// (Johnson, Contact Mechanics, 1985, §4.2 and §3.5), independent of the library (std only).
// Include with `include!("common/hertz.rs")`.
//
// With A = 1/(2R_max), B = 1/(2R_min) (A ≤ B), the pressure p = p0 sqrt(1 − x²/a² − y²/b²) on
// the ellipse of semi-axes a ≥ b (a along the direction of the larger radius), e² = 1 − b²/a²,
// and E* = E/(1 − ν²) for a rigid counter-body:
//
//   B/A = ((a²/b²) E(e) − K(e)) / (K(e) − E(e))          (solved for e²)
//   a³  = 3 P (K − E) / (2 π A E* e²),  b = a sqrt(1 − e²)
//   p0  = 3 P / (2 π a b),  δ = p0 b K(e) / E*
//
// K, E are the complete elliptic integrals of modulus e (parameter m = e²), computed by the
// arithmetic-geometric mean. Circular limit (e → 0): a = (3 P R / (4 E*))^{1/3}, δ = a²/R.

/// Complete elliptic integrals K(m), E(m) of parameter m = e² ∈ [0, 1) by the AGM:
/// K = π / (2 AGM(1, sqrt(1 − m))), E = K (1 − Σ_n 2^{n−1} c_n²) with c_0² = m.
#[allow(dead_code)]
pub fn ellip_ke(m: f64) -> (f64, f64) {
    let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
    let mut sum = 0.5 * m; // 2^{-1} c_0²
    let mut pow = 0.5;
    for _ in 0..60 {
        let c = 0.5 * (a - b);
        let an = 0.5 * (a + b);
        b = (a * b).sqrt();
        a = an;
        pow *= 2.0;
        sum += pow * c * c;
        if c.abs() <= 1e-17 * a {
            break;
        }
    }
    let k = std::f64::consts::PI / (2.0 * a);
    (k, k * (1.0 - sum))
}

/// (K − E)/m, with its series π/4 (1 + 3m/8 + 15m²/64) where m is small (no cancellation).
#[allow(dead_code)]
fn k_minus_e_over_m(m: f64) -> f64 {
    if m < 1e-5 {
        std::f64::consts::FRAC_PI_4 * (1.0 + 3.0 * m / 8.0 + 15.0 * m * m / 64.0)
    } else {
        let (k, e) = ellip_ke(m);
        (k - e) / m
    }
}

/// The Hertz ellipse: semi-axes a ≥ b, peak pressure, approach, e².
#[allow(dead_code)]
#[derive(Clone, Copy, Debug)]
pub struct HertzEllipse {
    pub a: f64,
    pub b: f64,
    pub p0: f64,
    pub delta: f64,
    pub e2: f64,
}

/// Hertz contact of radii `r1`, `r2` (> 0) on a rigid plane under the load `p` with the
/// contact modulus `e_star`.
#[allow(dead_code)]
pub fn hertz_ellipse(r1: f64, r2: f64, e_star: f64, p: f64) -> HertzEllipse {
    let (ca, cb) = (0.5 / r1.max(r2), 0.5 / r1.min(r2));
    let ratio = cb / ca;
    // g(m) = ((E/(1 − m) − K)/(K − E)) increases from 1 (m = 0) to ∞ (m → 1): bisection.
    let g = |m: f64| {
        let (k, e) = ellip_ke(m);
        let km = k_minus_e_over_m(m);
        (e / (1.0 - m) - k) / (m * km)
    };
    let m = if ratio <= 1.0 {
        0.0
    } else {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            let gm = if mid < 1e-5 {
                // Series of g near 0: 1 + 3m/4 (B/A − 1 ≈ 3m/4 for the near-circle).
                1.0 + 0.75 * mid
            } else {
                g(mid)
            };
            if gm < ratio {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    let km = k_minus_e_over_m(m);
    let (k, _) = ellip_ke(m);
    let a = (3.0 * p * km / (2.0 * std::f64::consts::PI * ca * e_star)).cbrt();
    let b = a * (1.0 - m).sqrt();
    let p0 = 3.0 * p / (2.0 * std::f64::consts::PI * a * b);
    HertzEllipse {
        a,
        b,
        p0,
        delta: p0 * b * k / e_star,
        e2: m,
    }
}
