//! `tread compare SCENE` of a three-dimensional scene (`mesh.dimension = 3`): the transient
//! mode run to its steady state and the steady mode on the same scene, compared in memory.
//!
//! 1. The transient mode runs into `OUT/transient/` ([`super::run3d::run`] with
//!    `analysis.mode = "transient"`) and extracts the referential field at its last node
//!    passage; its hub loads are the averages over that passage
//!    (`results.transient.hub_loads_passage_mean`).
//! 2. The steady mode (no continuation) solves the same scene into `OUT/steady/`.
//! 3. `OUT/summary.json` gets `results.compare`, `OUT/compare.csv` one row per judged quantity
//!    (the columns of the plane-strain comparison), `OUT/footprint_compare.csv` both modes'
//!    tractions at the tread's facet quadrature points:
//!    * the six hub loads in the road frame; forces relative to |F_steady| (the magnitude of
//!      the steady hub force), moments to |F_steady| Ro (`--force-tol`, `--torque-tol`);
//!    * the referential field: ‖u_t − u_s‖_L2(Ω) / ‖u_s‖_L2(Ω) with the finite-element
//!      interpolation on the referential mesh (the consistent mass matrix of each cell over ρ,
//!      the Gauss rule of the mass: exact for the interpolant);
//!    * the footprint: both fields evaluated by the steady mode's contact at the same facet
//!      quadrature points (the transient's material velocity at its steady state is ω ∂θχ of
//!      its referential field, so its contact pressure and traction are those of the steady
//!      kinematics on that field): `footprint_pressure` = ‖p_t − p_s‖ / ‖p_s‖ and
//!      `footprint_traction` = ‖t_t − t_s‖ / ‖t_s‖ (tangential traction vectors), L2 norms over
//!      the reference tread surface; `max_pressure` (relative to the steady peak), and the
//!      contact areas (reported, not judged);
//!    * wall times, speed-up, whether and when the transient run was steady, the verdict
//!      ([`super::compare::verdict`]).

use super::compare::{comparison_table, percent, plain, verdict, CompareTolerances};
use super::results::{
    Compare3DResults, Compare3DSection, Compare3DSummary, CompareQuantity, HubLoads3D, ModeSummary,
    RunOutcome, Summary,
};
use crate::contact::facet3d::ContactSample3D;
use crate::io::output::{ensure_dir, write_csv, write_json};
use crate::io::record::png::Units;
use crate::io::scene::{Control, Mode, Scene};
use crate::model::Solid3DSystem;
use crate::setup::{build_system_3d, AppError, RunOptions};
use crate::solver::stepping::LoadedSystem;

fn for_mode(scene: &Scene, mode: Mode) -> Scene {
    let mut s = scene.clone();
    s.analysis.mode = mode;
    if mode == Mode::Steady {
        s.continuation = None;
    }
    s
}

/// Relative L2 difference of two nodal fields (3 per node) over the body's reference volume,
/// ‖a − b‖ / ‖b‖, with each cell's consistent mass matrix; also max over nodes of |a − b| and
/// of |b|.
pub fn field_difference_3d(sys: &Solid3DSystem, a: &[f64], b: &[f64]) -> (f64, f64, f64) {
    let mesh = &sys.solid.mesh;
    let (mut num, mut den) = (0.0, 0.0);
    let mut m = Vec::new();
    for c in 0..mesh.n_cells() {
        let nodes = mesh.cell_nodes(c);
        sys.solid.cell_mass(c, &mut m);
        let n = nodes.len();
        for (i, &p) in nodes.iter().enumerate() {
            for (j, &q) in nodes.iter().enumerate() {
                let (p, q) = (p as usize, q as usize);
                let w = m[i * n + j];
                for d in 0..3 {
                    let (ep, eq) = (a[3 * p + d] - b[3 * p + d], a[3 * q + d] - b[3 * q + d]);
                    num += w * ep * eq;
                    den += w * b[3 * p + d] * b[3 * q + d];
                }
            }
        }
    }
    let norm = |v: &[f64], k: usize| {
        (v[3 * k].powi(2) + v[3 * k + 1].powi(2) + v[3 * k + 2].powi(2)).sqrt()
    };
    let diff: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    let n = mesh.n_nodes();
    let max_d = (0..n).map(|k| norm(&diff, k)).fold(0.0f64, f64::max);
    let max_b = (0..n).map(|k| norm(b, k)).fold(0.0f64, f64::max);
    ((num.max(0.0) / den).sqrt(), max_d, max_b)
}

/// The contact samples of the steady system with its displacements set to `u` (3 per node).
fn samples_of(
    sys: &mut Solid3DSystem,
    u: &[f64],
    road_height: Option<f64>,
) -> Result<Vec<ContactSample3D>, AppError> {
    sys.x[..u.len()].copy_from_slice(u);
    // Under load control the road height is the run's own unknown.
    if let (Some(ih), Some(h)) = (sys.contact.as_ref().and_then(|c| c.h_dof), road_height) {
        sys.x[ih] = h;
    }
    sys.contact_samples()
        .map_err(|e| AppError::Unsupported(format!("compare: contact samples: {e}")))
}

/// L2 differences of the footprints `t` and `s` (the same points): pressure and tangential
/// traction, each relative to the steady norm.
fn footprint_difference(t: &[ContactSample3D], s: &[ContactSample3D]) -> (f64, f64) {
    let (mut dp, mut np, mut dt, mut nt) = (0.0, 0.0, 0.0, 0.0);
    for (a, b) in t.iter().zip(s) {
        let w = b.da0;
        dp += w * (a.p - b.p).powi(2);
        np += w * b.p * b.p;
        dt += w * ((a.t1 - b.t1).powi(2) + (a.t3 - b.t3).powi(2));
        nt += w * (b.t1 * b.t1 + b.t3 * b.t3);
    }
    let rel = |d: f64, n: f64| if n > 0.0 { (d / n).sqrt() } else { f64::NAN };
    (rel(dp, np), rel(dt, nt))
}

fn area(s: &[ContactSample3D]) -> f64 {
    s.iter().filter(|p| p.p > 0.0).map(|p| p.da0).sum()
}

fn max_pressure(s: &[ContactSample3D]) -> f64 {
    s.iter().map(|p| p.p).fold(0.0f64, f64::max)
}

/// The names of the six hub loads, in [`HubLoads3D::to_array`] order.
pub const HUB_LOADS: [&str; 6] = HubLoads3D::NAMES;

/// What [`judge_3d`] compares.
#[derive(Clone, Debug)]
pub struct Compare3DInputs {
    /// The six hub loads of both modes (transient, steady).
    pub hub_loads: (HubLoads3D, HubLoads3D),
    /// ‖u_t − u_s‖_L2 / ‖u_s‖_L2.
    pub field_rel_l2: f64,
    /// Footprint pressure and traction L2 differences (relative).
    pub footprint_pressure: f64,
    pub footprint_traction: f64,
    /// Peak pressures (transient, steady).
    pub max_pressure: (f64, f64),
    pub ro: f64,
}

/// Every judged quantity of the 3D comparison with its relative difference and tolerance:
/// forces relative to |F_steady| (`tol.force`), moments to |F_steady| Ro (`tol.torque`), the
/// field (`tol.field`), the footprint pressure and traction (`tol.footprint`) and the peak
/// pressure relative to itself (`tol.pressure`). A non-finite difference is not within.
pub fn judge_3d(
    inp: &Compare3DInputs,
    tol: &CompareTolerances,
    units: &Units,
) -> Vec<CompareQuantity> {
    let (t, s) = (inp.hub_loads.0.to_array(), inp.hub_loads.1.to_array());
    let fmag = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
    let q = |name: &str,
             unit: String,
             t: Option<f64>,
             s: Option<f64>,
             abs: f64,
             rel_to: &str,
             scale: f64,
             tolerance: f64| {
        let rel_diff = abs / scale;
        CompareQuantity {
            name: name.into(),
            unit,
            transient: t,
            steady: s,
            abs_diff: abs,
            rel_diff,
            relative_to: rel_to.into(),
            scale,
            tolerance,
            within: rel_diff.is_finite() && rel_diff <= tolerance,
        }
    };
    let mut out = Vec::new();
    for k in 0..6 {
        let (unit, rel_to, scale, tolerance) = if k < 3 {
            (units.force.clone(), "|F_steady|", fmag, tol.force)
        } else {
            (
                format!("{}·{}", units.force, units.length),
                "|F_steady| Ro",
                fmag * inp.ro,
                tol.torque,
            )
        };
        out.push(q(
            HUB_LOADS[k],
            unit,
            Some(t[k]),
            Some(s[k]),
            (t[k] - s[k]).abs(),
            rel_to,
            scale,
            tolerance,
        ));
    }
    out.push(q(
        "field_l2",
        "1".into(),
        None,
        None,
        inp.field_rel_l2,
        "‖u_steady‖_L2",
        1.0,
        tol.field,
    ));
    out.push(q(
        "footprint_pressure",
        "1".into(),
        None,
        None,
        inp.footprint_pressure,
        "‖p_steady‖_L2(tread)",
        1.0,
        tol.footprint,
    ));
    out.push(q(
        "footprint_traction",
        "1".into(),
        None,
        None,
        inp.footprint_traction,
        "‖t_steady‖_L2(tread)",
        1.0,
        tol.footprint_traction,
    ));
    let (pt, ps) = inp.max_pressure;
    out.push(q(
        "max_pressure",
        units.stress(),
        Some(pt),
        Some(ps),
        (pt - ps).abs(),
        "|max_pressure_steady|",
        ps.abs(),
        tol.pressure,
    ));
    out
}

/// Run the three-dimensional `scene` in both modes, compare and judge them against `tol`
/// (see the module docs).
pub fn run(
    scene: &Scene,
    opts: &RunOptions,
    tol: &CompareTolerances,
) -> Result<RunOutcome, AppError> {
    super::compare::check_time(scene)?;
    // What the 3D transient half does not run (a steady scene may have it).
    if scene.motion.control != Control::Speed {
        return Err(AppError::Unsupported(format!(
            "motion.control: compare runs the three-dimensional transient mode, which runs \
             \"speed\" only (this scene has \"{}\")",
            scene.motion.control
        )));
    }
    ensure_dir(&opts.out_dir)?;
    let mut warnings = Vec::new();
    let tr_opts = RunOptions {
        out_dir: opts.out_dir.join("transient"),
        ..opts.clone()
    };
    let tr_scene = for_mode(scene, Mode::Transient);
    let tr = super::run3d::run(&tr_scene, &tr_opts)?;
    let st_scene = for_mode(scene, Mode::Steady);
    let st_opts = RunOptions {
        out_dir: opts.out_dir.join("steady"),
        ..opts.clone()
    };
    let st = super::run3d::run(&st_scene, &st_opts)?;
    let (Some(tres), Some(sres)) = (tr.typed.solid3d(), st.typed.solid3d()) else {
        return Err(AppError::Unsupported(
            "compare: the transient and steady runs gave no results to compare".into(),
        ));
    };
    let Some(ts) = tres.transient.as_ref() else {
        return Err(AppError::Unsupported(
            "compare: the transient run gave no transient results".into(),
        ));
    };
    if !ts.steady {
        warnings.push(
            "the transient run did not reach its steady state (time.t_end or max_steps first): \
             its last extracted field and passage are compared"
                .to_string(),
        );
    }
    let (Some(u_t), Some(u_s)) = (tr.field.as_deref(), st.field.as_deref()) else {
        return Err(AppError::Unsupported(format!(
            "compare: the transient run ended at t = {:.4e} s before its first node passage, so \
             it extracted no referential field to compare (raise time.t_end, now {} s)",
            ts.final_time,
            scene.time.as_ref().map_or(f64::NAN, |t| t.t_end)
        )));
    };
    let (Some(lt), Some(ls)) = (ts.hub_loads_passage_mean, sres.hub_loads) else {
        return Err(AppError::Unsupported(format!(
            "compare: the transient run saw {} node passages, fewer than the two its mean hub \
             loads need (raise time.t_end)",
            ts.passages
        )));
    };
    // The steady system of the scene evaluates both footprints at the same points.
    let mut sys = build_system_3d(&st_scene)?;
    sys.set_load(1.0);
    let (rel_l2, max_d, max_s) = field_difference_3d(&sys, u_t, u_s);
    let fp_t = samples_of(&mut sys, u_t, tres.road_height)?;
    let fp_s = samples_of(&mut sys, u_s, sres.road_height)?;
    let (fp_p, fp_tr) = footprint_difference(&fp_t, &fp_s);
    let units = Units::parse(&scene.scene.units);
    let quantities = judge_3d(
        &Compare3DInputs {
            hub_loads: (lt, ls),
            field_rel_l2: rel_l2,
            footprint_pressure: fp_p,
            footprint_traction: fp_tr,
            max_pressure: (max_pressure(&fp_t), max_pressure(&fp_s)),
            ro: scene.geometry.ro,
        },
        tol,
        &units,
    );
    let (validated, verdict) = verdict(
        &quantities,
        ts.steady,
        scene.time.as_ref().map(|t| t.steady_tol),
    );
    let wall = |o: &RunOutcome| o.typed.run_stats().map_or(f64::NAN, |r| r.wall_time_s);
    let (wt, ws) = (wall(&tr), wall(&st));
    let compare = Compare3DResults {
        hub_loads_transient: lt,
        hub_loads_steady: ls,
        field_rel_l2: rel_l2,
        field_max_abs: max_d,
        field_rel_max: if max_s > 0.0 { max_d / max_s } else { f64::NAN },
        footprint_pressure_rel_l2: fp_p,
        footprint_traction_rel_l2: fp_tr,
        max_pressure_transient: max_pressure(&fp_t),
        max_pressure_steady: max_pressure(&fp_s),
        contact_area_transient: area(&fp_t),
        contact_area_steady: area(&fp_s),
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
        ModeSummary::Compare3D(Box::new(Compare3DSummary {
            warnings,
            results: Compare3DSection {
                compare: compare.clone(),
            },
            transient_dir: tr_opts.out_dir.display().to_string(),
            steady_dir: st_opts.out_dir.display().to_string(),
        })),
    );
    let summary = typed.to_json();
    write_json(&opts.out_dir.join("summary.json"), &summary)?;
    let c = &compare;
    super::compare::write_compare_csv(&opts.out_dir.join("compare.csv"), &c.quantities)?;
    write_csv(
        &opts.out_dir.join("footprint_compare.csv"),
        &[
            "cell",
            "face",
            "x1",
            "x2",
            "x3",
            "da0",
            "p_transient",
            "p_steady",
            "t1_transient",
            "t1_steady",
            "t3_transient",
            "t3_steady",
        ],
        fp_t.iter().zip(&fp_s).map(|(a, b)| {
            vec![
                b.cell as f64,
                b.face as f64,
                b.x1,
                b.x2,
                b.x3,
                b.da0,
                a.p,
                b.p,
                a.t1,
                b.t1,
                a.t3,
                b.t3,
            ]
        }),
    )?;
    let mut headline = comparison_table(&c.quantities);
    headline.extend([
        c.verdict.clone(),
        format!(
            "transient hub loads: averages over the last node passage ({})",
            match ts.time_to_steady {
                Some(t) if ts.steady => format!("steady after {} {}", plain(t, 4), units.time),
                _ => "not steady".into(),
            },
        ),
        format!(
            "contact area: transient {} {l}², steady {} {l}² ({} apart)",
            plain(c.contact_area_transient, 4),
            plain(c.contact_area_steady, 4),
            percent((c.contact_area_transient - c.contact_area_steady).abs() / c.contact_area_steady),
            l = units.length
        ),
        format!(
            "wall time: transient {} s, steady {} s (speed-up {})",
            plain(wt, 3),
            plain(ws, 3),
            plain(wt / ws, 3)
        ),
        format!(
            "files: {} (summary.json, compare.csv, footprint_compare.csv), transient run in {}, steady run in {}",
            opts.out_dir.display(),
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
