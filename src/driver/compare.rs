//! `tread compare SCENE`: the same scene in both modes.
//!
//! 1. The transient mode (`analysis.mode = "transient"`, the scene's `[time]`) runs until steady
//!    into `OUT/transient/` and extracts the referential field at its last node passage.
//! 2. The steady mode (no continuation) solves the same scene into `OUT/steady/`.
//! 3. `OUT/summary.json` gets `results.compare` and `OUT/compare.csv` one row per quantity:
//!    * hub forces and torque from both; `hub_force_x_rel_diff` and `hub_force_y_rel_diff` are
//!      |F_i(transient) − F_i(steady)| / |F(steady)| (relative to the magnitude of the steady
//!      hub force vector, so that a component near zero, e.g. Fx without friction, is not
//!      divided by itself); `hub_torque_abs_diff` = |T_t − T_s|. The transient loads are
//!      their averages over the last node passage (`transient_loads` = "passage_mean"; the
//!      loads of a steady rolling state oscillate within a passage as nodes enter the patch,
//!      by several per cent of |F| on a coarse mesh), or the last step's when the run had
//!      fewer than two passages (`transient_loads` = "last_step"); the last step's are also
//!      given as `hub_force_x_transient_last_step` etc.;
//!    * the referential displacement fields of both runs (in memory, the numbers of their
//!      `steady_field.csv`): `field_rel_l2` =
//!      ‖u_t − u_s‖_L2(Ω) / ‖u_s‖_L2(Ω) (integrated with the finite-element interpolation on the
//!      referential mesh, 3×3 Gauss points per cell), `field_max_abs` = max over nodes of
//!      |u_t − u_s|, `field_rel_max` = that over max |u_s|;
//!    * contact patch ends and peak pressure from both;
//!    * `wall_time_transient_s`, `wall_time_steady_s`, `speedup` (their ratio), whether the
//!      transient run reached its steady state (`transient_steady`) and when;
//!    * the verdict: `quantities` (every judged quantity with its unit, both values, |Δ|, the
//!      relative difference, what it is relative to and its tolerance, see [`judge`]),
//!      `validated` and `verdict` (one sentence). The steady solution is validated when the
//!      transient run reached its steady state and every quantity is within its tolerance
//!      ([`CompareTolerances`]); otherwise the run still writes every output and `tread`
//!      exits with status [`NOT_VALIDATED_EXIT`].
//!
//!    With the `png` sink, `OUT/contact_compare.png` draws t_n and t_T along x1 from both.

use super::results::{
    CompareQuantity, CompareResults, CompareSection, CompareSummary, ModeSummary, Summary,
};
use super::steady_run;
use crate::assembly::QpHistory;
use crate::contact::ContactSample;
use crate::driver::results::RunOutcome;
use crate::element::QuadRule;
use crate::io::output::{ensure_dir, write_json, write_text_csv};
use crate::io::scene::{Mode, Scene, Sink};
use crate::math::Vec2;
use crate::setup::{build_model, AppError, RunOptions};
use std::path::Path;

/// Exit status of `tread compare` (and of `tread` without arguments) when both runs finished
/// but the steady solution is not validated against the transient.
pub const NOT_VALIDATED_EXIT: u8 = 4;

/// Tolerances of the verdict (see [`judge`] for what each difference is relative to). The
/// defaults are the agreement the two formulations reach on the shipped scenes' meshes once
/// the transient run is steady (tests/compare.rs: hub forces within 0.5 % of |F|, the field
/// within 1 % in relative L2 on 3 × 128 cells; the main job's 8 × 128 mesh: 0.01–0.1 %), with
/// a margin of two for the hub loads: the hub loads of the main job's mesh are within 1 % of
/// their mesh-converged values, so a gap of that size between the modes is a discretisation
/// difference, not a disagreement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompareTolerances {
    /// Hub force components, relative to |F_steady| (default 1e-2).
    pub force: f64,
    /// Hub torque, relative to |T_steady| (or to |F_steady| Ro when the torque is below
    /// [`TORQUE_NEAR_ZERO`] of that; default 2e-2).
    pub torque: f64,
    /// Referential displacement field, ‖u_t − u_s‖_L2 / ‖u_s‖_L2 (default 1e-2).
    pub field: f64,
    /// Contact patch ends: in surface node spacings (a patch end is resolved to one node
    /// spacing; default 1), reported relative to the steady patch length.
    pub contact_spacings: f64,
    /// Peak pressure, relative to the steady peak (a pointwise maximum on the mesh, the
    /// least converged of the quantities; default 5e-2).
    pub pressure: f64,
    /// Three dimensions: the footprint's contact pressure, L2 over the tread relative to the
    /// steady one (default 2e-2).
    pub footprint: f64,
    /// Three dimensions: the footprint's tangential traction, likewise (default 5e-2).
    pub footprint_traction: f64,
}

impl Default for CompareTolerances {
    fn default() -> Self {
        CompareTolerances {
            force: 1e-2,
            torque: 2e-2,
            field: 1e-2,
            contact_spacings: 1.0,
            pressure: 5e-2,
            footprint: 2e-2,
            footprint_traction: 5e-2,
        }
    }
}

/// A hub torque below this fraction of |F_steady| Ro is near zero (e.g. frictionless rolling
/// without damping): its difference is then relative to |F_steady| Ro, not to itself.
pub const TORQUE_NEAR_ZERO: f64 = 1e-3;

/// What [`judge`] compares: both modes' values and the scales.
#[derive(Clone, Debug)]
pub struct CompareInputs {
    /// (transient, steady) of hub force x1, x2, torque, patch ends, peak pressure.
    pub hub_force_x: (f64, f64),
    pub hub_force_y: (f64, f64),
    pub hub_torque: (f64, f64),
    pub contact_x_min: (f64, f64),
    pub contact_x_max: (f64, f64),
    pub max_pressure: (f64, f64),
    /// ‖u_t − u_s‖_L2 / ‖u_s‖_L2.
    pub field_rel_l2: f64,
    /// Outer radius and the spacing of the outer-surface nodes (length).
    pub ro: f64,
    pub surface_spacing: f64,
    pub transient_steady: bool,
    /// `time.steady_tol` of the transient run (named in the verdict when not validated).
    pub steady_tol: Option<f64>,
}

/// Judge the comparison: every quantity with its relative difference and tolerance, whether
/// all are within, and the verdict sentence. Hub force components are relative to |F_steady|
/// (the magnitude of the steady hub force: a component near zero, Fx without friction, is not
/// divided by itself); the torque to |T_steady|, or to |F_steady| Ro when |T_steady| is below
/// [`TORQUE_NEAR_ZERO`] of that; patch ends to the steady patch length (their tolerance is
/// `contact_spacings` surface node spacings); the peak pressure to itself. A non-finite
/// difference is not within its tolerance.
pub fn judge(
    inp: &CompareInputs,
    tol: &CompareTolerances,
    units: &crate::io::record::png::Units,
) -> (Vec<CompareQuantity>, bool, String) {
    let fmag = inp.hub_force_x.1.hypot(inp.hub_force_y.1);
    let load_moment = fmag * inp.ro;
    let q = |name: &str,
             unit: String,
             (t, s): (f64, f64),
             relative_to: String,
             scale: f64,
             tolerance: f64| {
        let abs_diff = (t - s).abs();
        let rel_diff = abs_diff / scale;
        CompareQuantity {
            name: name.into(),
            unit,
            transient: Some(t),
            steady: Some(s),
            abs_diff,
            rel_diff,
            relative_to,
            scale,
            tolerance,
            within: rel_diff.is_finite() && rel_diff <= tolerance,
        }
    };
    let f_unit = units.force_per_thickness();
    let (torque_rel, torque_scale) = if inp.hub_torque.1.abs() >= TORQUE_NEAR_ZERO * load_moment {
        ("|hub_torque_steady|".to_string(), inp.hub_torque.1.abs())
    } else {
        ("|F_steady| Ro".to_string(), load_moment)
    };
    let patch = inp.contact_x_max.1 - inp.contact_x_min.1;
    let contact_tol = tol.contact_spacings * inp.surface_spacing / patch;
    let out = vec![
        q(
            "hub_force_x",
            f_unit.clone(),
            inp.hub_force_x,
            "|F_steady|".into(),
            fmag,
            tol.force,
        ),
        q(
            "hub_force_y",
            f_unit,
            inp.hub_force_y,
            "|F_steady|".into(),
            fmag,
            tol.force,
        ),
        q(
            "hub_torque",
            units.moment_per_thickness(),
            inp.hub_torque,
            torque_rel,
            torque_scale,
            tol.torque,
        ),
        CompareQuantity {
            name: "field_l2".into(),
            unit: "1".into(),
            transient: None,
            steady: None,
            abs_diff: inp.field_rel_l2,
            rel_diff: inp.field_rel_l2,
            relative_to: "‖u_steady‖_L2".into(),
            scale: 1.0,
            tolerance: tol.field,
            within: inp.field_rel_l2.is_finite() && inp.field_rel_l2 <= tol.field,
        },
        q(
            "contact_x_min",
            units.length.clone(),
            inp.contact_x_min,
            "steady patch length".into(),
            patch,
            contact_tol,
        ),
        q(
            "contact_x_max",
            units.length.clone(),
            inp.contact_x_max,
            "steady patch length".into(),
            patch,
            contact_tol,
        ),
        q(
            "max_pressure",
            units.stress(),
            inp.max_pressure,
            "|max_pressure_steady|".into(),
            inp.max_pressure.1.abs(),
            tol.pressure,
        ),
    ];
    let (validated, verdict) = verdict(&out, inp.transient_steady, inp.steady_tol);
    (out, validated, verdict)
}

/// Whether the judged quantities `out` validate the steady solution (all within their
/// tolerances and the transient run steady, `transient_steady`), and the verdict sentence;
/// `steady_tol` is the transient's `time.steady_tol` for the hint.
pub fn verdict(
    out: &[CompareQuantity],
    transient_steady: bool,
    steady_tol: Option<f64>,
) -> (bool, String) {
    let failed: Vec<String> = out
        .iter()
        .filter(|q| !q.within)
        .map(|q| {
            format!(
                "{} differs by {} of {} (tolerance {})",
                q.name,
                percent(q.rel_diff),
                q.relative_to,
                percent(q.tolerance)
            )
        })
        .collect();
    let validated = failed.is_empty() && transient_steady;
    let verdict = if validated {
        let worst = out
            .iter()
            .max_by(|a, b| (a.rel_diff / a.tolerance).total_cmp(&(b.rel_diff / b.tolerance)));
        format!(
            "steady solution validated against the transient: all {} quantities within their tolerances{}",
            out.len(),
            worst.map_or(String::new(), |w| format!(
                " (closest to its tolerance: {} at {} of {}, tolerance {})",
                w.name,
                percent(w.rel_diff),
                w.relative_to,
                percent(w.tolerance)
            ))
        )
    } else {
        let mut why = Vec::new();
        if !transient_steady {
            why.push(
                "the transient run did not reach its steady state (raise time.t_end or lower time.steady_tol)"
                    .to_string(),
            );
        }
        let any_failed = !failed.is_empty();
        why.extend(failed);
        let hint = match steady_tol {
            // A transient run stopped at a loose steady tolerance can still carry a slowly
            // decaying oscillation: the torque is the load it shows in first.
            Some(t) if any_failed && transient_steady => format!(
                " (the transient run stopped once it changed by less than time.steady_tol = {t:e} per node passage; a tighter time.steady_tol, e.g. --set time.steady_tol={:e}, lets it settle further)",
                t / 10.0
            ),
            _ => String::new(),
        };
        format!("not validated: {}{hint}", why.join("; "))
    };
    (validated, verdict)
}

/// A ratio as a percentage with three significant digits: `0.0412 %`, `5.07 %`.
pub fn percent(x: f64) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    let p = plain(100.0 * x, 3);
    // Trailing zeros of a decimal fraction say nothing here (`1 %`, not `1.00 %`).
    let p = if p.contains('.') && !p.contains('e') {
        p.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        p
    };
    format!("{p} %")
}

/// `x` with `sig` significant digits as a plain decimal number (no exponent between 1e-4 and
/// 1e9; outside, `1.23e-7`).
pub fn plain(x: f64, sig: usize) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".into();
    }
    let mag = x.abs().log10().floor() as i32;
    if !(-4..9).contains(&mag) {
        return format!("{:.*e}", sig.saturating_sub(1), x);
    }
    let dec = (sig as i32 - 1 - mag).max(0) as usize;
    format!("{x:.dec$}")
}

/// Read a CSV of numbers written by [`crate::io::output::write_csv`]: header and rows (an
/// empty field, a non-finite value, reads as NaN).
pub fn read_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>), String> {
    let (header, text) = crate::io::output::read_text_csv(path)?;
    let mut rows = Vec::new();
    for (i, r) in text.iter().enumerate() {
        if r.iter().all(|f| f.trim().is_empty()) {
            continue;
        }
        let row: Result<Vec<f64>, _> = r
            .iter()
            .map(|v| match v.trim() {
                "" => Ok(f64::NAN),
                v => v.parse::<f64>(),
            })
            .collect();
        rows.push(row.map_err(|e| format!("{} line {}: {e}", path.display(), i + 2))?);
    }
    Ok((header, rows))
}

/// Field differences on the referential mesh of `scene`: (relative L2, max |Δu|, max |u_s|).
/// `u_t`, `u_s`: displacements, 2 per node in node order (an error when shorter).
pub fn field_difference(
    scene: &Scene,
    u_t: &[f64],
    u_s: &[f64],
) -> Result<(f64, f64, f64), AppError> {
    let sys = crate::model::SolidSystem::new(build_model(scene)?, "hub");
    let n = sys.model.mesh.n_nodes();
    if u_t.len() < 2 * n || u_s.len() < 2 * n {
        return Err(AppError::Unsupported(format!(
            "compare: the referential fields have {} and {} values, the mesh {} nodes",
            u_t.len(),
            u_s.len(),
            n
        )));
    }
    let mut xd = sys.x.clone();
    let mut xs = sys.x.clone();
    for i in 0..2 * n {
        xd[i] = u_t[i] - u_s[i];
        xs[i] = u_s[i];
    }
    let rule = QuadRule::gauss_2d(3);
    let (mut num, mut den) = (0.0, 0.0);
    for c in 0..sys.model.mesh.n_cells() {
        for (pt, w) in rule.points.iter().zip(&rule.weights) {
            let (Some(pd), Some(ps)) = (
                sys.model.point_values(c, &sys.dofs, &xd, pt.0, pt.1),
                sys.model.point_values(c, &sys.dofs, &xs, pt.0, pt.1),
            ) else {
                continue;
            };
            let dv = ps.jac.determinant().abs() * w;
            num += pd.u.norm_squared() * dv;
            den += ps.u.norm_squared() * dv;
        }
    }
    let node = |u: &[f64], k: usize| Vec2::new(u[2 * k], u[2 * k + 1]);
    let max_d = (0..n)
        .map(|k| (node(u_t, k) - node(u_s, k)).norm())
        .fold(0.0, f64::max);
    let max_s = (0..n).map(|k| node(u_s, k).norm()).fold(0.0, f64::max);
    let rel = if den > 0.0 {
        (num / den).sqrt()
    } else {
        f64::NAN
    };
    Ok((rel, max_d, max_s))
}

/// The internal variables of a stateful material from both runs, compared along the rings of
/// quadrature points ([`QpHistory::ring`]) in polar components (rr, θθ, rθ) at each point's
/// position, which are the same in the transient's material reference frame and in the
/// referential frame (the two differ by the rotation φ = kΔθ of the last passage).
#[derive(Clone, Debug, Default)]
pub struct HistoryComparison {
    /// (ring, mean radius, ‖ΔQ‖_L2 / ‖Q_s‖_L2 over the ring, max |ΔQ|, max |Q_s|) per ring.
    pub rings: Vec<[f64; 5]>,
    /// Over the whole body (quadrature weights).
    pub rel_l2: f64,
    pub max_abs: f64,
    pub rel_max: f64,
}

/// Compare the quadrature-point histories `h_t` (transient, re-indexed to the referential
/// cells) and `h_s` (steady) of `scene`'s mesh: every internal-variable tensor (the entries
/// after the stored strain, three per tensor `[a11, a22, a12]`). `None` when the mesh has no
/// rings or the layouts differ.
pub fn history_difference(
    scene: &Scene,
    h_t: &QpHistory,
    h_s: &QpHistory,
) -> Result<Option<HistoryComparison>, AppError> {
    if h_t.n_state != h_s.n_state || h_t.data.len() != h_s.data.len() || h_s.n_state < 6 {
        return Ok(None);
    }
    let model = build_model(&for_mode(scene, Mode::Steady))?;
    let Some(layout) = model.mesh.rings else {
        return Ok(None);
    };
    if h_s.offsets.len() != model.mesh.n_cells() + 1 {
        return Ok(None);
    }
    let q = model.qp_per_direction(0);
    let polar = |a: &[f64], x: Vec2| -> [f64; 3] {
        let r = x.norm().max(f64::MIN_POSITIVE);
        let (c, s) = (x[0] / r, x[1] / r);
        let (a11, a22, a12) = (a[0], a[1], a[2]);
        [
            c * c * a11 + s * s * a22 + 2.0 * c * s * a12,
            s * s * a11 + c * c * a22 - 2.0 * c * s * a12,
            c * s * (a22 - a11) + (c * c - s * s) * a12,
        ]
    };
    let n_tensors = h_s.n_state / 3;
    let mut out = HistoryComparison::default();
    let (mut num, mut den, mut max_s) = (0.0, 0.0, 0.0f64);
    let mut g = [[0.0; 2]; 9];
    for ring in 0..QpHistory::n_rings(&layout, q) {
        let (mut rn, mut rd, mut rmax_d, mut rmax_s, mut radius, mut count) =
            (0.0, 0.0, 0.0f64, 0.0f64, 0.0, 0.0f64);
        for (c, pt) in QpHistory::ring(&layout, q, ring) {
            let Some((x, w)) = model.qp_geometry(c, pt, &mut g) else {
                continue;
            };
            let (a, b) = (h_t.point(c, pt), h_s.point(c, pt));
            for t in 1..n_tensors {
                let (pa, pb) = (
                    polar(&a[3 * t..3 * t + 3], x),
                    polar(&b[3 * t..3 * t + 3], x),
                );
                for i in 0..3 {
                    let (d, v) = (pa[i] - pb[i], pb[i]);
                    // The shear component counts twice in the tensor norm.
                    let m = if i == 2 { 2.0 } else { 1.0 };
                    rn += m * d * d * w;
                    rd += m * v * v * w;
                    rmax_d = rmax_d.max(d.abs());
                    rmax_s = rmax_s.max(v.abs());
                }
            }
            radius += x.norm();
            count += 1.0;
        }
        num += rn;
        den += rd;
        out.max_abs = out.max_abs.max(rmax_d);
        max_s = max_s.max(rmax_s);
        let rel = if rd > 0.0 { (rn / rd).sqrt() } else { f64::NAN };
        out.rings
            .push([ring as f64, radius / count.max(1.0), rel, rmax_d, rmax_s]);
    }
    out.rel_l2 = if den > 0.0 {
        (num / den).sqrt()
    } else {
        f64::NAN
    };
    out.rel_max = if max_s > 0.0 {
        out.max_abs / max_s
    } else {
        f64::NAN
    };
    Ok(Some(out))
}

/// The scene as one of the two compared runs: its mode set, and in the steady mode no
/// continuation (the comparison is at the scene's speed). Its outputs are the scene's: the
/// comparison takes both runs' results in memory.
fn for_mode(scene: &Scene, mode: Mode) -> Scene {
    let mut s = scene.clone();
    s.analysis.mode = mode;
    if mode == Mode::Steady {
        s.continuation = None;
    }
    s
}

/// Mean spacing of the outer-surface nodes of `scene`'s mesh (the nodes within 1e-9 Ro of the
/// outer radius; 2π Ro over their count).
fn surface_spacing(scene: &Scene) -> Result<f64, AppError> {
    let model = build_model(&for_mode(scene, Mode::Steady))?;
    let ro = scene.geometry.ro;
    let n = model
        .mesh
        .nodes
        .iter()
        .filter(|p| (p[0].hypot(p[1]) - ro).abs() <= 1e-9 * ro)
        .count();
    Ok(if n > 0 {
        2.0 * std::f64::consts::PI * ro / n as f64
    } else {
        f64::NAN
    })
}

/// [`run_with_tolerances`] with the default tolerances.
pub fn run(scene: &Scene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    run_with_tolerances(scene, opts, &CompareTolerances::default())
}

/// The transient half of a comparison needs `[time]` with its time steps.
pub fn check_time(scene: &Scene) -> Result<(), AppError> {
    match &scene.time {
        None => Err(AppError::Unsupported(
            "compare runs the transient mode, which needs the [time] section".into(),
        )),
        Some(t) if t.steady_only() => Err(AppError::Unsupported(
            "compare runs the transient mode, which needs time.dt and time.t_end (this \
             steady scene's [time] leaves them out)"
                .into(),
        )),
        Some(_) => Ok(()),
    }
}

/// Run `scene` in both modes, compare and judge them against `tol` (see the module docs).
pub fn run_with_tolerances(
    scene: &Scene,
    opts: &RunOptions,
    tol: &CompareTolerances,
) -> Result<RunOutcome, AppError> {
    ensure_dir(&opts.out_dir)?;
    check_time(scene)?;
    if scene.mesh.dimension == 3 {
        return Err(AppError::Unsupported(
            "mesh.dimension = 3: the three-dimensional comparison is driver::compare3d::run".into(),
        ));
    }
    let mut warnings = steady_run::warnings(scene);
    let tr_scene = for_mode(scene, Mode::Transient);
    let tr_opts = RunOptions {
        out_dir: opts.out_dir.join("transient"),
        ..opts.clone()
    };
    let tr = match super::transient_run::run(&tr_scene, &tr_opts) {
        Ok(o) => o,
        Err(AppError::Solve(e, dir)) => {
            return Err(AppError::Solve(e, dir));
        }
        Err(e) => return Err(e),
    };
    let st_scene = for_mode(scene, Mode::Steady);
    let st_opts = RunOptions {
        out_dir: opts.out_dir.join("steady"),
        ..opts.clone()
    };
    let st = super::steady_run::run(&st_scene, &st_opts)?;
    let (Some(ts), Some(ss)) = (tr.typed.transient(), st.typed.steady()) else {
        return Err(AppError::Unsupported(
            "compare: the transient and steady runs gave no results to compare".into(),
        ));
    };
    if !ts.steady {
        warnings.push(
            "the transient run did not reach its steady state (time.t_end or max_steps first): \
             its last extracted field is compared"
                .into(),
        );
    }
    // Fields on the referential mesh (those of both runs' steady_field.csv).
    let Some(u_t) = tr.field.as_deref() else {
        return Err(AppError::Unsupported(format!(
            "compare: the transient run ended at t = {:.4e} s before its first cell passage, so \
             it extracted no referential field to compare (raise time.t_end, now {} s)",
            ts.final_time,
            scene.time.as_ref().map_or(f64::NAN, |t| t.t_end)
        )));
    };
    let Some(u_s) = st.field.as_deref() else {
        return Err(AppError::Unsupported(
            "compare: the steady run gave no referential field".into(),
        ));
    };
    let (rel_l2, max_d, max_s) = field_difference(scene, u_t, u_s)?;
    // Internal variables along the rings (stateful materials on ring meshes).
    let history = match (&tr.history, &st.history) {
        (Some(ht), Some(hs)) => history_difference(scene, ht, hs)?,
        (None, Some(_)) => {
            warnings.push(
                "the internal variables are not compared: the transient run's last node passage \
                 did not fall on a step end (or the mesh has no rings)"
                    .into(),
            );
            None
        }
        _ => None,
    };
    let nan = f64::NAN;
    let last = (ts.hub_force_x, ts.hub_force_y, ts.hub_torque);
    let mean = (
        ts.hub_force_x_passage_mean.unwrap_or(nan),
        ts.hub_force_y_passage_mean.unwrap_or(nan),
        ts.hub_torque_passage_mean.unwrap_or(nan),
    );
    let have_mean = mean.0.is_finite() && mean.1.is_finite() && mean.2.is_finite();
    let (fxt, fyt, tqt) = if have_mean { mean } else { last };
    let (fxs, fys, tqs) = (ss.hub_force_x, ss.hub_force_y, ss.hub_torque);
    let fmag = fxs.hypot(fys).max(f64::MIN_POSITIVE);
    let wall = |o: &RunOutcome| o.typed.run_stats().map_or(nan, |r| r.wall_time_s);
    let (wt, ws) = (wall(&tr), wall(&st));
    let units = crate::io::record::png::Units::parse(&scene.scene.units);
    let (quantities, validated, verdict) = judge(
        &CompareInputs {
            hub_force_x: (fxt, fxs),
            hub_force_y: (fyt, fys),
            hub_torque: (tqt, tqs),
            contact_x_min: (ts.contact_x_min, ss.contact_x_min),
            contact_x_max: (ts.contact_x_max, ss.contact_x_max),
            max_pressure: (ts.max_pressure, ss.max_pressure),
            field_rel_l2: rel_l2,
            ro: scene.geometry.ro,
            surface_spacing: surface_spacing(scene)?,
            transient_steady: ts.steady,
            steady_tol: scene.time.as_ref().map(|t| t.steady_tol),
        },
        tol,
        &units,
    );
    let compare = CompareResults {
        hub_force_x_transient: fxt,
        hub_force_x_steady: fxs,
        hub_force_y_transient: fyt,
        hub_force_y_steady: fys,
        hub_torque_transient: tqt,
        hub_torque_steady: tqs,
        transient_loads: if have_mean {
            "passage_mean"
        } else {
            "last_step"
        }
        .to_string(),
        hub_force_x_transient_last_step: last.0,
        hub_force_y_transient_last_step: last.1,
        hub_torque_transient_last_step: last.2,
        hub_force_x_rel_diff: (fxt - fxs).abs() / fmag,
        hub_force_y_rel_diff: (fyt - fys).abs() / fmag,
        hub_torque_abs_diff: (tqt - tqs).abs(),
        hub_torque_rel_diff: (tqt - tqs).abs() / (fmag * scene.geometry.ro),
        field_rel_l2: rel_l2,
        field_max_abs: max_d,
        field_rel_max: if max_s > 0.0 { max_d / max_s } else { nan },
        history_rel_l2: history.as_ref().map(|h| h.rel_l2),
        history_rel_max: history.as_ref().map(|h| h.rel_max),
        contact_x_min_transient: ts.contact_x_min,
        contact_x_min_steady: ss.contact_x_min,
        contact_x_max_transient: ts.contact_x_max,
        contact_x_max_steady: ss.contact_x_max,
        max_pressure_transient: ts.max_pressure,
        max_pressure_steady: ss.max_pressure,
        wall_time_transient_s: wt,
        wall_time_steady_s: ws,
        speedup: wt / ws,
        transient_steady: ts.steady,
        transient_time_to_steady: ts.time_to_steady,
        transient_steps: ts.steps,
        quantities,
        validated,
        verdict,
    };
    let converged = tr.converged && st.converged;
    for w in &warnings {
        eprintln!("tread: warning: {w}");
    }
    let typed = Summary::new(
        &scene.scene.name,
        "compare",
        st.typed.dofs,
        converged,
        ModeSummary::Compare(CompareSummary {
            warnings,
            results: CompareSection {
                compare: compare.clone(),
            },
            transient_dir: tr_opts.out_dir.display().to_string(),
            steady_dir: st_opts.out_dir.display().to_string(),
        }),
    );
    let summary = typed.to_json();
    write_json(&opts.out_dir.join("summary.json"), &summary)?;
    let c = &compare;
    write_compare_csv(&opts.out_dir.join("compare.csv"), &c.quantities)?;
    if let Some(h) = &history {
        let ring_rows: Vec<Vec<String>> = h
            .rings
            .iter()
            .map(|r| {
                vec![
                    (r[0] as usize).to_string(),
                    r[1].to_string(),
                    r[2].to_string(),
                    r[3].to_string(),
                    r[4].to_string(),
                ]
            })
            .collect();
        write_text_csv(
            &opts.out_dir.join("history_rings.csv"),
            &["ring", "radius", "rel_l2", "max_abs_diff", "max_abs_steady"],
            ring_rows,
        )?;
    }
    if scene.output.has(Sink::Png) {
        contact_plot(
            &tr.contact,
            &st.contact,
            &opts.out_dir.join("contact_compare.png"),
            &crate::io::record::png::Units::parse(&scene.scene.units),
        );
    }
    let mut headline = comparison_table(&c.quantities);
    headline.extend([
        c.verdict.clone(),
        format!(
            "transient loads: {} ({})",
            if have_mean {
                "averages over the last node passage"
            } else {
                "the last step (fewer than two node passages)"
            },
            match ts.time_to_steady {
                Some(t) if ts.steady => format!("steady after {} {}", plain(t, 4), units.time),
                _ => "not steady".into(),
            },
        ),
        match &history {
            Some(h) => format!(
                "internal variables along the rings (not judged): relative L2 difference {}, largest difference {} of the largest steady value (history_rings.csv)",
                percent(h.rel_l2),
                percent(h.rel_max)
            ),
            None => "internal variables: none compared".into(),
        },
        format!(
            "wall time: transient {} s, steady {} s (speed-up {})",
            plain(wt, 3),
            plain(ws, 3),
            plain(wt / ws, 3)
        ),
        format!(
            "files: {} (summary.json, compare.csv{}), transient run in {}, steady run in {}",
            opts.out_dir.display(),
            if scene.output.has(Sink::Png) {
                ", contact_compare.png"
            } else {
                ""
            },
            tr_opts.out_dir.display(),
            st_opts.out_dir.display()
        ),
    ]);
    Ok(RunOutcome {
        summary,
        typed,
        field: None,
        history: None,
        contact: Vec::new(),
        out_dir: opts.out_dir.clone(),
        converged,
        headline,
    })
}

/// `compare.csv`: one row per judged quantity ([`COMPARE_CSV_COLUMNS`]).
pub fn write_compare_csv(
    path: &Path,
    qs: &[CompareQuantity],
) -> Result<(), crate::io::output::OutputError> {
    let v = |x: Option<f64>| x.map_or(String::new(), |x| x.to_string());
    let rows = qs.iter().map(|q| {
        vec![
            q.name.clone(),
            q.unit.clone(),
            v(q.transient),
            v(q.steady),
            q.abs_diff.to_string(),
            q.rel_diff.to_string(),
            q.relative_to.clone(),
            q.tolerance.to_string(),
            q.within.to_string(),
        ]
    });
    write_text_csv(path, &COMPARE_CSV_COLUMNS, rows)
}

/// Columns of `compare.csv` (one row per [`CompareQuantity`]).
pub const COMPARE_CSV_COLUMNS: [&str; 9] = [
    "quantity",
    "unit",
    "transient",
    "steady",
    "abs_diff",
    "rel_diff",
    "relative_to",
    "tolerance",
    "within",
];

/// The judged quantities as an aligned text table: name with unit, both values and the
/// absolute difference as plain numbers (six significant digits), the relative difference,
/// what it is relative to, the tolerance and `ok` or `FAIL`.
pub fn comparison_table(qs: &[CompareQuantity]) -> Vec<String> {
    let v = |x: Option<f64>| x.map_or("–".to_string(), |x| plain(x, 6));
    let mut rows: Vec<[String; 8]> = vec![[
        "quantity".into(),
        "transient".into(),
        "steady".into(),
        "|difference|".into(),
        "relative".into(),
        "relative to".into(),
        "tolerance".into(),
        "".into(),
    ]];
    for q in qs {
        let name = if q.unit == "1" {
            q.name.clone()
        } else {
            format!("{} [{}]", q.name, q.unit)
        };
        let abs = if q.transient.is_some() {
            plain(q.abs_diff, 3)
        } else {
            "–".into()
        };
        rows.push([
            name,
            v(q.transient),
            v(q.steady),
            abs,
            percent(q.rel_diff),
            q.relative_to.clone(),
            percent(q.tolerance),
            if q.within { "ok" } else { "FAIL" }.into(),
        ]);
    }
    let width = |k: usize| rows.iter().map(|r| r[k].chars().count()).max().unwrap_or(0);
    let w: Vec<usize> = (0..8).map(width).collect();
    let pad = |t: &str, n: usize, right: bool| {
        let fill = " ".repeat(n.saturating_sub(t.chars().count()));
        if right {
            format!("{fill}{t}")
        } else {
            format!("{t}{fill}")
        }
    };
    rows.iter()
        .map(|r| {
            let cells: Vec<String> = (0..8)
                .map(|k| pad(&r[k], w[k], matches!(k, 1..=4 | 6)))
                .collect();
            cells.join("  ").trim_end().to_string()
        })
        .collect()
}

/// Points (x1, value) of one curve.
type Curve = Vec<(f64, f64)>;

/// t_n and t_T along x1 of both modes' final contact tractions (warnings only on failure).
fn contact_plot(
    tr: &[ContactSample],
    st: &[ContactSample],
    out: &Path,
    units: &crate::io::record::png::Units,
) {
    let curves = |samples: &[ContactSample]| -> (Curve, Curve) {
        let mut rows: Vec<&ContactSample> = samples
            .iter()
            .filter(|s| s.t_n > 0.0 && s.x1.is_finite())
            .collect();
        rows.sort_by(|a, b| a.x1.total_cmp(&b.x1));
        (
            rows.iter().map(|s| (s.x1, s.t_n)).collect(),
            rows.iter().map(|s| (s.x1, s.t_t)).collect(),
        )
    };
    let ((tn_t, tt_t), (tn_s, tt_s)) = (curves(tr), curves(st));
    if tn_t.is_empty() || tn_s.is_empty() {
        eprintln!("tread: warning: contact_compare.png: no contact in one of the modes");
        return;
    }
    if let Err(e) = crate::io::record::png::line_chart(
        out,
        "Contact tractions: transient (extracted) vs steady",
        &crate::io::record::png::with_unit("x1", &units.length),
        &crate::io::record::png::with_unit("traction", &units.stress()),
        &[
            ("t_n transient", &tn_t),
            ("t_n steady", &tn_s),
            ("t_T transient", &tt_t),
            ("t_T steady", &tt_s),
        ],
    ) {
        eprintln!("tread: warning: contact_compare.png: {e}");
    }
}
