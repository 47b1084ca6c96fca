//! The adaptive model problems of [`crate::adapt`] run from a scene
//! ([`crate::io::scene::model_problem`]): `tread run scenarios/model_problems/<kind>.toml`.
//!
//! Each kind calls its algorithm once, observes every step or adaptive pass, and writes into
//! the output folder
//!
//! | file | sink | content |
//! |---|---|---|
//! | `summary.json` | always | the envelope of every run (`scene`, `mode` = `"model_problem"`, `dofs`, `converged`, `version`, `newton_iterations`, `wall_time_s`, `error`), `kind`, the resolved `problem` keys, `results` (the final errors against the exact or published reference solution, the estimate and its effectivity) |
//! | `steps.csv` | `csv` | one row per time step (heat, burgers, Taylor–Green), adaptive pass (lshape, Kovasznay, every attempt of a Taylor–Green step) or mesh recalculation (cavity) |
//! | `solution.vtu` | `vtu` | the final mesh, every cell split into sub-quads with the solution as point fields, and the cell fields `error_indicator`, `error` (where the exact solution is known), `degree`, `level` |
//! | `error_mesh.png` | `png` | the final mesh, every cell shaded by log10 of its error indicator |
//! | `solution.png` | `png` | the final solution shaded, with contour lines (the stream function of the cavity at the contour values of Ghia et al.) |
//! | `run.rrd` | `rerun` | the Rerun recording ([`crate::io::record::quad_rrd`]), one frame per row of `steps.csv` |
//!
//! What each kind solves and measures:
//! * `cavity`: lid-driven cavity, Q2/Q1 Taylor–Hood, Newton by continuation 100 → 400 → 1000
//!   up to `reynolds`, then `recalculations` moving-mesh relocations
//!   ([`crate::adapt::moving_mesh`]). Error: the largest deviation of u(0.5, y) and v(x, 0.5)
//!   from the tables of Ghia et al. (Re = 100, 400) or Botella & Peyret (Re = 1000), and the
//!   error of ψ_min (Re = 1000). Indicator: the normalised velocity gradient ê_K of the
//!   monitor.
//! * `heat`, `burgers`: Crank–Nicolson with the two-grid adaptive h-method
//!   ([`crate::adapt::two_grid`]); error ‖u − u_h‖ against the closed-form solution (rotating
//!   Gaussian hill, Cole–Hopf), indicator η_K = ‖u_f − u_h‖_K.
//! * `p_navier_stokes`: the p-method ([`crate::adapt::p_navier_stokes`]) on Kovasznay flow
//!   (steady) or the Taylor–Green vortex (transient); error ‖u − u_p‖ against the exact flow,
//!   indicator η_K = ‖u_{p+r} − u_p‖_K.
//! * `lshape`: −Δu = 0 on the L-shape, u = r^{2/3} sin(2θ/3), the loop solve → estimate → mark
//!   → refine → transfer ([`crate::adapt::driver`]); energy error |u − u_h|₁ and its observed
//!   rate in the number of equations.
//!
//! A failed solve still writes `summary.json` (`converged = false`, `error`) and the rows of
//! `steps.csv` reached, and returns [`AppError::Failed`] (exit status 1).
//!
//! **Interrupts.** Ctrl-C (SIGTERM, SIGHUP: [`crate::io::record::interrupted`]) stops a run at
//! the next step boundary: after the time step (heat, burgers, Taylor–Green), the adaptive pass
//! (lshape, Kovasznay), the Newton solve of the Reynolds continuation or the mesh recalculation
//! (cavity) in progress. Every output is then written for the last state computed (its
//! `results` against the reference at that state: the time reached, the Reynolds number
//! reached), `summary.json` says `converged = false`, `"error": "interrupted"` and
//! `interrupted_at` (the time, the pass or the Reynolds number reached), and the run returns
//! [`AppError::Interrupted`] (exit status 130). Pictures and the
//! recording that cannot be written are warnings, listed in `incomplete_outputs`.

use crate::adapt::burgers::{Burgers, ColeHopf};
use crate::adapt::cavity_reference;
use crate::adapt::convection::{ConvectionDiffusion, RotatingHill};
use crate::adapt::driver::{self as adapt_loop, loglog_slope, AdaptOptions, Marking};
use crate::adapt::moving_mesh::{cell_monitor, moving_mesh_cavity_until, MonitorParams};
use crate::adapt::navier_stokes::{
    bilinear, psi_min, stream_function, CavityLid, NsSolution, TaylorHood,
};
use crate::adapt::p_navier_stokes::{
    adapt_steady_until, degree_histogram, exact_error, run_transient_observed, Field, PAdaptParams,
    PMarking, SteadyProblem, SweepReport, TimeParams, TransientProblem,
};
use crate::adapt::poisson::{energy_error_sq, lshape_energy_sq, LShape};
use crate::adapt::quadtree::Quadtree;
use crate::adapt::space::Space;
use crate::adapt::two_grid::{self, error_sq, Kernel, TransientOptions};
use crate::driver::results::{
    CavityResults, LShapeResults, ModeSummary, ModelProblemSummary, ModelResults, PnsResults,
    RunOutcome, RunStats, Summary, TwoGridResults,
};
use crate::element::hierarchical::Basis1d;
use crate::io::output::{ensure_dir, write_csv, write_json, OutputError};
use crate::io::record::interrupted;
use crate::io::record::quad::{self, PointField, QuadCells, Shading};
use crate::io::scene::model_problem::{
    CavityMesh, CavitySpec, Flow, LEstimator, LRefinement, LShapeSpec, Lid, ModelScene, PnsSpec,
    Problem, TwoGridSpec,
};
use crate::io::scene::Sink;
use crate::setup::{AppError, RunOptions};
use std::cell::Cell;
use std::f64::consts::PI;
use std::ops::ControlFlow;
use std::path::Path;
use std::time::Instant;

/// `steps.csv`: header and rows.
struct Table {
    header: Vec<&'static str>,
    rows: Vec<Vec<f64>>,
}

/// What a kind's run returns.
struct Done {
    dofs: usize,
    newton_iterations: usize,
    results: ModelResults,
    headline: String,
    /// Where an interrupt stopped the run (time, pass or Reynolds number; see the module
    /// docs); `None` when it ran to its end.
    interrupted_at: Option<f64>,
}

/// The final mesh and solution as the pictures and the VTU see them.
struct Picture<'a> {
    title: String,
    cells: QuadCells<'a>,
    /// Sub-quads per cell side of the VTU.
    sub: &'a dyn Fn(usize) -> usize,
    point_fields: Vec<PointField<'a>>,
    cell_fields: Vec<(&'static str, Vec<f64>)>,
    indicator: &'a [f64],
    indicator_label: &'static str,
    shade: &'a dyn Fn(usize, f64, f64) -> f64,
    shade_label: String,
    levels: &'a [f64],
    edges: bool,
}

/// The sinks of a run: which files, the recording, the warnings met.
struct Outputs<'a> {
    dir: &'a Path,
    scene: &'a ModelScene,
    #[cfg(feature = "rerun")]
    rrd: Option<crate::io::record::quad_rrd::QuadRecording>,
    /// (sink, path, message) of outputs not written.
    incomplete: Vec<(String, String, String)>,
}

/// One frame of the recording.
#[cfg_attr(not(feature = "rerun"), allow(dead_code))]
struct Frame<'a> {
    index: usize,
    time: Option<f64>,
    cells: &'a QuadCells<'a>,
    sub: &'a dyn Fn(usize) -> usize,
    value: &'a dyn Fn(usize, f64, f64) -> f64,
    indicators: &'a [f64],
    scalars: &'a [(&'a str, f64)],
}

impl<'a> Outputs<'a> {
    fn open(scene: &'a ModelScene, dir: &'a Path) -> Self {
        #[cfg_attr(not(feature = "rerun"), allow(unused_mut))]
        let mut o = Outputs {
            dir,
            scene,
            #[cfg(feature = "rerun")]
            rrd: None,
            incomplete: Vec::new(),
        };
        if scene.has(Sink::Rerun) {
            #[cfg(feature = "rerun")]
            {
                let path = dir.join("run.rrd");
                let name = format!("{} ({})", scene.name, scene.problem.kind());
                let doc = format!(
                    "# {name}\n\ntread {}: model problem `{}`. `solution`: the solution \
                     (viridis, frame minimum to maximum); `error`: the cells beside it by log10 of \
                     their error indicator. Timeline `step`: the rows of `steps.csv`.\n\n```toml\n{}\n```\n",
                    env!("CARGO_PKG_VERSION"),
                    scene.problem.kind(),
                    scene.to_toml_string()
                );
                match crate::io::record::quad_rrd::QuadRecording::create(&path, &name, &doc) {
                    Ok(r) => o.rrd = Some(r),
                    Err(e) => o.warn("rerun", &path, &e),
                }
            }
            #[cfg(not(feature = "rerun"))]
            eprintln!(
                "tread: warning: output sink \"rerun\" skipped: this build has no `rerun` feature"
            );
        }
        o
    }

    fn warn(&mut self, sink: &str, path: &Path, msg: &str) {
        eprintln!(
            "tread: warning: {sink}: cannot write {}: {msg}",
            path.display()
        );
        self.incomplete
            .push((sink.into(), path.display().to_string(), msg.into()));
    }

    /// Whether frames are recorded (so that a kind builds them only then).
    fn recording(&self) -> bool {
        #[cfg(feature = "rerun")]
        {
            self.rrd.is_some()
        }
        #[cfg(not(feature = "rerun"))]
        {
            false
        }
    }

    #[cfg_attr(not(feature = "rerun"), allow(unused_variables))]
    fn frame(&mut self, f: &Frame) {
        #[cfg(feature = "rerun")]
        if let Some(r) = self.rrd.as_mut() {
            r.frame(&crate::io::record::quad_rrd::QuadFrame {
                index: f.index as i64,
                time: f.time,
                cells: f.cells,
                sub: f.sub,
                value: f.value,
                indicators: f.indicators,
                scalars: f.scalars,
            });
        }
    }

    fn finish_recording(&mut self) {
        #[cfg(feature = "rerun")]
        if let Some(r) = self.rrd.take() {
            if let Err(e) = r.finish() {
                let p = self.dir.join("run.rrd");
                self.warn("rerun", &p, &e);
            }
        }
    }

    /// The VTU and the two pictures of the final state.
    fn picture(&mut self, p: &Picture) -> Result<(), OutputError> {
        if self.scene.has(Sink::Vtu) {
            let cf: Vec<(&str, &[f64])> = p
                .cell_fields
                .iter()
                .map(|(n, v)| (*n, v.as_slice()))
                .collect();
            quad::write_vtu(
                &self.dir.join("solution.vtu"),
                &p.cells,
                p.sub,
                &p.point_fields,
                &cf,
            )?;
        }
        if self.scene.has(Sink::Png) {
            let path = self.dir.join("error_mesh.png");
            let title = format!("{}: error level", p.title);
            if let Err(e) = quad::mesh_png(&path, &title, &p.cells, p.indicator, p.indicator_label)
            {
                self.warn("png", &path, &e);
            }
            let path = self.dir.join("solution.png");
            let n = p.cells.n_cells;
            let sub = |k: usize| ((p.sub)(k) * 2).clamp(2, if n > 2000 { 2 } else { 8 });
            let shading = Shading {
                eval: p.shade,
                sub: &sub,
                levels: p.levels,
            };
            if let Err(e) =
                quad::solution_png(&path, &p.title, &p.cells, &shading, p.edges, &p.shade_label)
            {
                self.warn("png", &path, &e);
            }
        }
        Ok(())
    }
}

/// Run a model-problem scene and write its outputs into `opts.out_dir` (see the module docs).
pub fn run(scene: &ModelScene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    let t0 = Instant::now();
    let dir = opts.out_dir.as_path();
    ensure_dir(dir)?;
    let mut out = Outputs::open(scene, dir);
    let mut table = Table {
        header: Vec::new(),
        rows: Vec::new(),
    };
    let r = match &scene.problem {
        Problem::Cavity(s) => cavity(s, &mut out, &mut table),
        Problem::Heat(s) => {
            let kernel = ConvectionDiffusion {
                hill: RotatingHill {
                    kappa: s.kappa,
                    sigma2: s.sigma2,
                    centre: s.centre,
                },
                supg: s.supg,
            };
            let tree = two_grid::square([-1.0, -1.0], 2.0, s.time.levels, s.time.degree);
            transient(&kernel, &tree, &s.time, "heat", &mut out, &mut table)
        }
        Problem::Burgers(s) => {
            let kernel = Burgers {
                exact: ColeHopf {
                    nu: s.nu,
                    ..ColeHopf::default()
                },
            };
            let tree = two_grid::square([0.0, 0.0], 1.0, s.time.levels, s.time.degree);
            transient(&kernel, &tree, &s.time, "burgers", &mut out, &mut table)
        }
        Problem::PNavierStokes(s) => p_navier_stokes(s, &mut out, &mut table),
        Problem::LShape(s) => lshape(s, &mut out, &mut table),
    };
    out.finish_recording();
    let wall = t0.elapsed().as_secs_f64();
    let interrupted_at = r.as_ref().ok().and_then(|d| d.interrupted_at);
    let (converged, error) = match &r {
        Ok(_) if interrupted_at.is_some() => (false, Some("interrupted".to_string())),
        Ok(_) => (true, None),
        Err(Failed::Output(e)) => (false, Some(e.to_string())),
        Err(Failed::Solve(f)) => (false, Some(f.message.clone())),
    };
    let (dofs, newton, results, headline) = match &r {
        Ok(d) => (
            d.dofs,
            d.newton_iterations,
            Some(d.results.clone()),
            vec![d.headline.clone()],
        ),
        Err(Failed::Solve(f)) => (f.dofs, f.newton_iterations, None, Vec::new()),
        Err(Failed::Output(_)) => (0, 0, None, Vec::new()),
    };
    let problem = scene
        .to_toml_string()
        .parse::<toml::Table>()
        .ok()
        .and_then(|t| t.get("problem").cloned())
        .and_then(|p| serde_json::to_value(p).ok())
        .unwrap_or_default();
    let typed = Summary::new(
        &scene.name,
        "model_problem",
        dofs,
        converged,
        ModeSummary::ModelProblem(Box::new(ModelProblemSummary {
            kind: scene.problem.kind().to_string(),
            run: RunStats {
                newton_iterations: newton,
                wall_time_s: wall,
                error: error.clone(),
            },
            problem,
            results,
            steps: table.rows.len(),
            interrupted_at,
        })),
    );
    if scene.has(Sink::Csv) && !table.header.is_empty() {
        write_csv(
            &dir.join("steps.csv"),
            &table.header,
            table.rows.iter().cloned(),
        )?;
    }
    let mut summary = typed.to_json();
    if !out.incomplete.is_empty() {
        if let Some(m) = summary.as_object_mut() {
            let list: Vec<serde_json::Value> = out
                .incomplete
                .iter()
                .map(|(s, p, e)| serde_json::json!({"sink": s, "path": p, "error": e}))
                .collect();
            m.insert("incomplete_outputs".into(), serde_json::Value::Array(list));
        }
    }
    write_json(&dir.join("summary.json"), &summary)?;
    match r {
        Ok(_) if interrupted_at.is_some() => Err(AppError::Interrupted(dir.to_path_buf())),
        Ok(_) => Ok(RunOutcome {
            summary,
            typed,
            field: None,
            history: None,
            contact: Vec::new(),
            out_dir: dir.to_path_buf(),
            converged,
            headline,
        }),
        Err(Failed::Output(e)) => Err(e.into()),
        Err(Failed::Solve(f)) => Err(AppError::Failed(f.message, dir.to_path_buf())),
    }
}

/// Why a kind stopped.
enum Failed {
    Solve(Failure),
    Output(OutputError),
}

struct Failure {
    message: String,
    dofs: usize,
    newton_iterations: usize,
}

impl From<OutputError> for Failed {
    fn from(e: OutputError) -> Self {
        Failed::Output(e)
    }
}

fn solve_failed(e: impl std::fmt::Display, dofs: usize, newton_iterations: usize) -> Failed {
    Failed::Solve(Failure {
        message: e.to_string(),
        dofs,
        newton_iterations,
    })
}

/// Sub-quads per side for a cell of degree p (the VTU and the recording).
fn sub_of(p: usize) -> usize {
    p.clamp(1, 8)
}

/// The cells of a quadtree's leaves as [`QuadCells`] maps.
fn tree_map<'a>(
    tree: &'a Quadtree,
    leaves: &'a [u32],
) -> impl Fn(usize, f64, f64) -> [f64; 2] + 'a {
    move |k, xi, eta| tree.map_point(leaves[k], xi, eta)
}

fn level_field(tree: &Quadtree, leaves: &[u32]) -> Vec<f64> {
    leaves
        .iter()
        .map(|&c| f64::from(tree.cells[c as usize].level))
        .collect()
}

// ---------------------------------------------------------------------------------------------
// cavity

fn cavity(s: &CavitySpec, out: &mut Outputs, table: &mut Table) -> Result<Done, Failed> {
    let lid = match s.lid {
        Lid::Standard => CavityLid::Discontinuous,
        Lid::Regularised => CavityLid::Regularised,
    };
    let ladder: Vec<f64> = [100.0, 400.0, 1000.0]
        .into_iter()
        .filter(|&re| re <= s.reynolds)
        .collect();
    let params = MonitorParams {
        alpha: s.alpha,
        beta: s.beta,
        gamma: s.gamma,
        ..MonitorParams::default()
    };
    let recalcs = if s.mesh == CavityMesh::Moving {
        s.recalculations
    } else {
        0
    };
    // The reference tables of a Reynolds number (an interrupted continuation ends below the
    // scene's).
    let reference_at = |re: f64| match lid {
        CavityLid::Discontinuous => cavity_reference::table(re),
        CavityLid::Regularised => None,
    };
    table.header = vec![
        "recalculation",
        "equations",
        "min_det_j",
        "relocation_step",
        "newton_iterations",
        "psi_min",
        "psi_min_x",
        "psi_min_y",
        "centreline_u_error",
        "centreline_v_error",
        "psi_min_error",
    ];
    let mut newton = 0;
    let mut n_eq = 0;
    let mut first: Option<(f64, f64)> = None;
    let mut pass_error: Option<String> = None;
    let mut moved = 0;
    let run = moving_mesh_cavity_until(
        s.levels,
        lid,
        &ladder,
        &params,
        recalcs,
        s.tolerance,
        &interrupted,
        &mut |r, th, x| {
            moved = r.index;
            let reference = reference_at(r.reynolds);
            newton += r.newton_iterations;
            n_eq = th.n_eq();
            let sol = NsSolution { th, x: x.to_vec() };
            let (space, psi) = match stream_function(&sol) {
                Ok(v) => v,
                Err(e) => {
                    pass_error.get_or_insert(e.to_string());
                    return;
                }
            };
            let (at, pm) = psi_min(th, &space, &psi);
            let (eu, ev) = reference.map_or((f64::NAN, f64::NAN), |t| {
                t.deviations(&|p| sol.velocity(p).ok().map(|v| v.0))
            });
            let pe = reference
                .and_then(|t| t.psi_min)
                .map_or(f64::NAN, |r| (pm - r).abs());
            if first.is_none() {
                first = Some((eu.max(ev), pe));
            }
            table.rows.push(vec![
                r.index as f64,
                th.n_eq() as f64,
                r.min_det_j,
                r.step,
                r.newton_iterations as f64,
                pm,
                at[0],
                at[1],
                eu,
                ev,
                pe,
            ]);
            if out.recording() {
                let map = |k: usize, a: f64, b: f64| bilinear(&th.corners[k], a, b).0;
                let cells = QuadCells {
                    n_cells: th.corners.len(),
                    map: &map,
                };
                let value = |k: usize, a: f64, b: f64| space.eval(&th.tree, &psi, k, 0, a, b).0;
                let ind = gradient_indicator(th, x);
                let scalars = [
                    ("psi_min", pm),
                    ("centreline_u_error", eu),
                    ("centreline_v_error", ev),
                    ("min_det_j", r.min_det_j),
                ];
                out.frame(&Frame {
                    index: r.index,
                    time: None,
                    cells: &cells,
                    sub: &|_| 4,
                    value: &value,
                    indicators: &ind,
                    scalars: &scalars,
                });
            }
        },
    );
    let run = run.map_err(|e| solve_failed(e, n_eq, newton))?;
    if let Some(e) = pass_error {
        return Err(solve_failed(e, n_eq, newton));
    }
    let (th, x, reynolds) = (run.th, run.x, run.reynolds);
    let interrupted_at = run.stopped.then_some(reynolds);
    let reference = reference_at(reynolds);
    let recalcs = moved;
    let sol = NsSolution { th: &th, x };
    let (space, psi) = stream_function(&sol).map_err(|e| solve_failed(e, n_eq, newton))?;
    let (at, pm) = psi_min(&th, &space, &psi);
    let (eu, ev) = match reference {
        Some(t) => {
            let (a, b) = t.deviations(&|p| sol.velocity(p).ok().map(|v| v.0));
            (Some(a), Some(b))
        }
        None => (None, None),
    };
    let psi_err = reference.and_then(|t| t.psi_min).map(|r| (pm - r).abs());
    let ind = gradient_indicator(&th, &sol.x);
    let monitor = cell_monitor(&th, &sol.x, &params);
    let min_det = th.min_det_j();
    let map = |k: usize, a: f64, b: f64| bilinear(&th.corners[k], a, b).0;
    let nc = th.corners.len();
    let x = &sol.x;
    let vel = |k: usize, a: f64, b: f64, o: &mut [f64]| {
        o[0] = th.eval_velocity(x, k, 0, a, b).0;
        o[1] = th.eval_velocity(x, k, 1, a, b).0;
    };
    let pres = |k: usize, a: f64, b: f64, o: &mut [f64]| o[0] = th.eval_pressure(x, k, a, b);
    let psi_at = |k: usize, a: f64, b: f64| space.eval(&th.tree, &psi, k, 0, a, b).0;
    let psi_f = |k: usize, a: f64, b: f64, o: &mut [f64]| o[0] = psi_at(k, a, b);
    let title = format!(
        "cavity Re = {}, {} × {} cells{}",
        reynolds,
        1 << s.levels,
        1 << s.levels,
        if recalcs > 0 {
            format!(", moved {recalcs} times")
        } else {
            String::new()
        }
    );
    let levels = cavity_reference::GHIA_PSI_LEVELS;
    out.picture(&Picture {
        title,
        cells: QuadCells {
            n_cells: nc,
            map: &map,
        },
        sub: &|_| 2,
        point_fields: vec![
            PointField {
                name: "velocity",
                n_comp: 2,
                eval: &vel,
            },
            PointField {
                name: "pressure",
                n_comp: 1,
                eval: &pres,
            },
            PointField {
                name: "stream_function",
                n_comp: 1,
                eval: &psi_f,
            },
        ],
        cell_fields: vec![
            ("error_indicator", ind.clone()),
            ("monitor", monitor),
            ("degree", vec![2.0; nc]),
            ("level", vec![f64::from(s.levels); nc]),
        ],
        indicator: &ind,
        indicator_label: "|grad u|_K / max",
        shade: &psi_at,
        shade_label: "stream function".into(),
        levels: &levels,
        edges: recalcs > 0,
    })?;
    let (u0, p0) = first.unwrap_or((f64::NAN, f64::NAN));
    let finite = |v: f64| v.is_finite().then_some(v);
    let res = CavityResults {
        reynolds,
        equations: th.n_eq(),
        cells: nc,
        recalculations: recalcs,
        min_det_j: min_det,
        psi_min: pm,
        psi_min_at: at,
        reference: reference.map(|t| t.source.to_string()),
        centreline_u_error: eu,
        centreline_v_error: ev,
        centreline_error: eu.zip(ev).map(|(a, b)| a.max(b)),
        psi_min_error: psi_err,
        uniform_centreline_error: finite(u0),
        uniform_psi_min_error: finite(p0),
    };
    let mut headline = format!(
        "cavity Re = {}: {} equations, psi_min = {pm:.6} at ({:.4}, {:.4})",
        reynolds,
        th.n_eq(),
        at[0],
        at[1]
    );
    if let (Some(t), Some(e)) = (reference, res.centreline_error) {
        headline.push_str(&format!(
            "; largest centreline deviation from {} {e:.3e}",
            t.source
        ));
        if let Some(pe) = psi_err {
            headline.push_str(&format!(", |psi_min - ref| {pe:.3e}"));
        }
        if recalcs > 0 {
            headline.push_str(&format!(" (uniform mesh: {u0:.3e}, {p0:.3e})"));
        }
    }
    Ok(Done {
        dofs: th.n_eq(),
        newton_iterations: newton,
        results: ModelResults::Cavity(res),
        headline,
        interrupted_at,
    })
}

/// ê_K = |∇u|_K / max_K |∇u|_K at the cell centres (the indicator of the moving-mesh monitor).
fn gradient_indicator(th: &TaylorHood, x: &[f64]) -> Vec<f64> {
    let unit = MonitorParams {
        alpha: 1.0,
        beta: 1.0,
        gamma: 0.0,
        ..MonitorParams::default()
    };
    cell_monitor(th, x, &unit)
        .into_iter()
        .map(|m| m - 1.0)
        .collect()
}

// ---------------------------------------------------------------------------------------------
// heat, burgers

fn transient(
    kernel: &dyn Kernel,
    tree0: &Quadtree,
    s: &TwoGridSpec,
    name: &str,
    out: &mut Outputs,
    table: &mut Table,
) -> Result<Done, Failed> {
    let mut o = TransientOptions::new(s.degree, s.dt, s.steps);
    o.adaptive = s.adaptive;
    o.estimate = !s.adaptive;
    o.marking = Marking::Dorfler(s.dorfler);
    o.coarsen_fraction = s.coarsen;
    o.min_level = s.min_level;
    o.max_level = s.max_level;
    o.initial_sweeps = s.initial_sweeps;
    table.header = vec![
        "step",
        "t",
        "equations",
        "cells",
        "l2_error",
        "h1_error",
        "estimate",
        "effectivity",
        "newton_iterations",
    ];
    let nc = kernel.n_comp();
    let mut last: Option<(Quadtree, Vec<f64>, Vec<f64>, f64)> = None;
    let mut newton = 0;
    let mut n_eq = 0;
    let steps = s.steps;
    let mut stopped = false;
    let run = two_grid::run_observed(kernel, tree0, 0.0, &o, &mut |v| {
        let r = v.record;
        let index = table.rows.len();
        newton += r.newton_iterations;
        n_eq = r.n_eq;
        table.rows.push(vec![
            index as f64,
            r.t,
            r.n_eq as f64,
            r.n_cells as f64,
            r.l2_error,
            r.h1_error,
            r.estimate,
            r.estimate / r.l2_error,
            r.newton_iterations as f64,
        ]);
        let ind: Vec<f64> = v.indicators.map_or_else(Vec::new, <[f64]>::to_vec);
        if out.recording() {
            let map = tree_map(v.tree, &v.space.leaves);
            let cells = QuadCells {
                n_cells: v.space.leaves.len(),
                map: &map,
            };
            let value = |k: usize, a: f64, b: f64| comp_value(v.tree, v.space, v.x, nc, k, a, b);
            let scalars = [
                ("equations", r.n_eq as f64),
                ("l2_error", r.l2_error),
                ("estimate", r.estimate),
            ];
            out.frame(&Frame {
                index,
                time: Some(r.t),
                cells: &cells,
                sub: &|k| sub_of(v.space.degree[k]),
                value: &value,
                indicators: &ind,
                scalars: &scalars,
            });
        }
        stopped = index + 1 < steps && interrupted();
        if index + 1 == steps || stopped {
            last = Some((v.tree.clone(), v.x.to_vec(), ind, r.t));
        }
        if stopped {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    let run = run.map_err(|e| solve_failed(e, n_eq, newton))?;
    let Some((tree, x, ind, t)) = last else {
        return Err(solve_failed("no time step was taken", n_eq, newton));
    };
    let space = two_grid::space_at(&tree, kernel, t).map_err(|e| solve_failed(e, n_eq, newton))?;
    let (l2, _) = error_sq(&tree, &space, &x, kernel, t);
    let err: Vec<f64> = l2.iter().map(|e| e.sqrt()).collect();
    let last_rec = run
        .last()
        .cloned()
        .ok_or_else(|| solve_failed("no step", n_eq, newton))?;
    let leaves = &space.leaves;
    let map = tree_map(&tree, leaves);
    let n = leaves.len();
    let sol = |k: usize, a: f64, b: f64, o: &mut [f64]| {
        for (c, v) in o.iter_mut().enumerate().take(nc) {
            *v = space.eval(&tree, &x, k, c, a, b).0;
        }
    };
    let exact = |k: usize, a: f64, b: f64, o: &mut [f64]| {
        let p = tree.map_point(leaves[k], a, b);
        for (c, v) in o.iter_mut().enumerate().take(nc) {
            *v = kernel.exact(p, t, c).0;
        }
    };
    let shade = |k: usize, a: f64, b: f64| comp_value(&tree, &space, &x, nc, k, a, b);
    let degree: Vec<f64> = space.degree.iter().map(|&p| p as f64).collect();
    let indicator = if ind.is_empty() {
        vec![f64::NAN; n]
    } else {
        ind
    };
    out.picture(&Picture {
        title: format!("{name}, t = {t:.4}, {} cells", n),
        cells: QuadCells {
            n_cells: n,
            map: &map,
        },
        sub: &|k| sub_of(space.degree[k]),
        point_fields: vec![
            PointField {
                name: "u",
                n_comp: nc,
                eval: &sol,
            },
            PointField {
                name: "u_exact",
                n_comp: nc,
                eval: &exact,
            },
        ],
        cell_fields: vec![
            ("error_indicator", indicator.clone()),
            ("error", err),
            ("degree", degree),
            ("level", level_field(&tree, leaves)),
        ],
        indicator: &indicator,
        indicator_label: "two-grid eta_K",
        shade: &shade,
        shade_label: if nc == 1 { "u".into() } else { "|u|".into() },
        levels: &[],
        edges: false,
    })?;
    let res = TwoGridResults {
        t,
        equations: last_rec.n_eq,
        max_equations: run.max_eq(),
        cells: last_rec.n_cells,
        l2_error: last_rec.l2_error,
        h1_error: last_rec.h1_error,
        estimate: last_rec.estimate,
        effectivity: last_rec.estimate / last_rec.l2_error,
    };
    let headline = format!(
        "{name}: t = {t:.4}, {} equations (at most {}), L2 error {:.3e}, two-grid estimate {:.3e} (effectivity {:.3})",
        res.equations, res.max_equations, res.l2_error, res.estimate, res.effectivity
    );
    Ok(Done {
        dofs: res.equations,
        newton_iterations: newton,
        results: ModelResults::TwoGrid(res),
        headline,
        interrupted_at: stopped.then_some(t),
    })
}

/// u (one component) or |u| (two) of a Lagrange solution in leaf `k`.
fn comp_value(
    tree: &Quadtree,
    space: &Space,
    x: &[f64],
    nc: usize,
    k: usize,
    a: f64,
    b: f64,
) -> f64 {
    if nc == 1 {
        space.eval(tree, x, k, 0, a, b).0
    } else {
        (0..nc)
            .map(|c| space.eval(tree, x, k, c, a, b).0.powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

// ---------------------------------------------------------------------------------------------
// p_navier_stokes

/// The exact velocity and its gradient at a point (of the final time).
type ExactAt = dyn Fn([f64; 2]) -> ([f64; 2], [[f64; 2]; 2]);

/// Kovasznay flow at Reynolds number `re`: u = 1 − e^{λx} cos 2πy, v = λ/(2π) e^{λx} sin 2πy,
/// λ = Re/2 − (Re²/4 + 4π²)^{1/2}.
fn kovasznay(re: f64, x: [f64; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
    let l = re / 2.0 - (re * re / 4.0 + 4.0 * PI * PI).sqrt();
    let e = (l * x[0]).exp();
    let (s, c) = (2.0 * PI * x[1]).sin_cos();
    (
        [1.0 - e * c, l / (2.0 * PI) * e * s],
        [
            [-l * e * c, 2.0 * PI * e * s],
            [l * l / (2.0 * PI) * e * s, l * e * c],
        ],
    )
}

/// The Taylor–Green vortex shifted off the mesh lines: u = (cos kX sin kY, −sin kX cos kY)
/// e^{−2νk²t}, X = x + 0.1, Y = y + 0.2, k = 2π.
fn taylor_green(nu: f64, x: [f64; 2], t: f64) -> ([f64; 2], [[f64; 2]; 2]) {
    let k = 2.0 * PI;
    let a = (-2.0 * nu * k * k * t).exp();
    let (sx, cx) = (k * (x[0] + 0.1)).sin_cos();
    let (sy, cy) = (k * (x[1] + 0.2)).sin_cos();
    (
        [a * cx * sy, -a * sx * cy],
        [
            [-a * k * sx * sy, a * k * cx * cy],
            [-a * k * cx * cy, a * k * sx * sy],
        ],
    )
}

/// Unit square split once, the lower-left quadrant twice more (25 cells).
fn graded_unit_square() -> Quadtree {
    let mut t = Quadtree::new([0.0, 0.0], 1.0, &[(0, 0)], 2);
    let l = t.leaves();
    t.refine(&l);
    for _ in 0..2 {
        let m: Vec<u32> = t
            .leaves()
            .into_iter()
            .filter(|&c| {
                let [x, y] = t.corner(c);
                x < 0.49 && y < 0.49
            })
            .collect();
        t.refine(&m);
    }
    t
}

fn pns_row(r: &SweepReport, index: usize) -> Vec<f64> {
    let e = r.effectivity.as_ref();
    vec![
        index as f64,
        r.t,
        r.sweep as f64,
        if r.accepted { 1.0 } else { 0.0 },
        r.n_eq as f64,
        r.n_eq_enriched as f64,
        r.estimate,
        e.map_or(f64::NAN, |e| e.error),
        e.map_or(f64::NAN, |e| e.global),
        r.worst_ratio,
        r.degrees.iter().copied().min().unwrap_or(0) as f64,
        r.degrees.iter().copied().max().unwrap_or(0) as f64,
        r.newton_iterations as f64,
    ]
}

fn p_navier_stokes(s: &PnsSpec, out: &mut Outputs, table: &mut Table) -> Result<Done, Failed> {
    table.header = vec![
        "solve",
        "t",
        "attempt",
        "accepted",
        "equations",
        "equations_enriched",
        "estimate",
        "l2_error",
        "effectivity",
        "worst_ratio",
        "min_degree",
        "max_degree",
        "newton_iterations",
    ];
    let params = PAdaptParams {
        tol: s.tolerance,
        enrich: s.enrich,
        marking: PMarking::Tolerance,
        max_degree: s.max_degree,
        max_sweeps: s.max_sweeps,
    };
    let zero = |_: [f64; 2], _: f64| [0.0, 0.0];
    let stopped = Cell::new(false);
    let (reports, fin, t, exact_at): (Vec<SweepReport>, (Field, Vec<f64>), f64, Box<ExactAt>) =
        match s.flow {
            Flow::Kovasznay => {
                let re = s.reynolds.unwrap_or(40.0);
                let coarse: Vec<(i64, i64)> =
                    (0..4).flat_map(|j| (0..3).map(move |i| (i, j))).collect();
                let tree = Quadtree::new([-0.5, -0.5], 0.5, &coarse, 2);
                let n = tree.leaves().len();
                let g = |x: [f64; 2], c: usize| kovasznay(re, x).0[c];
                let ex = |x: [f64; 2]| kovasznay(re, x);
                let problem = SteadyProblem {
                    nu: 1.0 / re,
                    g: &g,
                    f: &zero,
                    exact: Some(&ex),
                };
                // Polled only while another sweep is due.
                let stop = || {
                    stopped.set(interrupted());
                    stopped.get()
                };
                let (reps, est) =
                    adapt_steady_until(&tree, &vec![s.degree; n], &problem, &params, &stop)
                        .map_err(|e| solve_failed(e, 0, 0))?;
                for r in &reps {
                    let i = table.rows.len();
                    table.rows.push(pns_row(r, i));
                }
                (
                    reps,
                    (est.coarse, est.indicators),
                    0.0,
                    Box::new(move |x| kovasznay(re, x)),
                )
            }
            Flow::TaylorGreen => {
                let nu = s.nu.unwrap_or(0.01);
                let tree = graded_unit_square();
                let n = tree.leaves().len();
                let g = |x: [f64; 2], t: f64, c: usize| taylor_green(nu, x, t).0[c];
                let u0 = |x: [f64; 2]| taylor_green(nu, x, 0.0).0;
                let ex = |x: [f64; 2], t: f64| taylor_green(nu, x, t);
                let problem = TransientProblem {
                    nu,
                    g: &g,
                    f: &zero,
                    u0: &u0,
                    exact: Some(&ex),
                };
                let time = TimeParams {
                    dt: s.dt.unwrap_or(0.02),
                    n_steps: s.steps.unwrap_or(5),
                    theta: 0.5,
                };
                let mut last: Option<(Field, Vec<f64>, f64)> = None;
                let mut step = 0;
                let reps = run_transient_observed(
                    &tree,
                    &vec![s.degree; n],
                    &problem,
                    &time,
                    &params,
                    &mut |r, new, _fine, eta| {
                        if out.recording() {
                            pns_frame(out, step, Some(r.t), new, eta, r);
                        }
                        step += 1;
                        last = Some((new.clone(), eta.to_vec(), r.t));
                        if step < time.n_steps && interrupted() {
                            stopped.set(true);
                            ControlFlow::Break(())
                        } else {
                            ControlFlow::Continue(())
                        }
                    },
                )
                .map_err(|e| solve_failed(e, 0, 0))?;
                for r in &reps {
                    let i = table.rows.len();
                    table.rows.push(pns_row(r, i));
                }
                let (field, eta, t_reached) =
                    last.ok_or_else(|| solve_failed("no time step was taken", 0, 0))?;
                let fin = (field, eta);
                let t = if stopped.get() {
                    t_reached
                } else {
                    time.dt * time.n_steps as f64
                };
                (reps, fin, t, Box::new(move |x| taylor_green(nu, x, t)))
            }
        };
    let newton: usize = reports.iter().map(|r| r.newton_iterations).sum();
    let last = reports
        .iter()
        .rev()
        .find(|r| r.accepted)
        .or(reports.last())
        .cloned()
        .ok_or_else(|| solve_failed("no solve", 0, newton))?;
    let (field, eta) = fin;
    if s.flow == Flow::Kovasznay && out.recording() {
        pns_frame(
            out,
            reports.len().saturating_sub(1),
            None,
            &field,
            &eta,
            &last,
        );
    }
    let th = field.th.clone();
    let err = exact_error(&field, &*exact_at);
    let n = th.n_cells();
    let map = |k: usize, a: f64, b: f64| th.point(k, a, b);
    let xv = &field.x;
    let vel = |k: usize, a: f64, b: f64, o: &mut [f64]| {
        let u = th.velocity(xv, k, a, b).0;
        o[0] = u[0];
        o[1] = u[1];
    };
    let exact_f = |k: usize, a: f64, b: f64, o: &mut [f64]| {
        let u = exact_at(th.point(k, a, b)).0;
        o[0] = u[0];
        o[1] = u[1];
    };
    let pres = |k: usize, a: f64, b: f64, o: &mut [f64]| o[0] = th.pressure(xv, k, a, b);
    let speed = |k: usize, a: f64, b: f64| {
        let u = th.velocity(xv, k, a, b).0;
        u[0].hypot(u[1])
    };
    let degrees = th.degrees().to_vec();
    let leaves = th.vel.leaves.clone();
    out.picture(&Picture {
        title: format!(
            "p-method, {}{}",
            s.flow,
            if t > 0.0 {
                format!(", t = {t:.3}")
            } else {
                String::new()
            }
        ),
        cells: QuadCells {
            n_cells: n,
            map: &map,
        },
        sub: &|k| sub_of(degrees[k]),
        point_fields: vec![
            PointField {
                name: "velocity",
                n_comp: 2,
                eval: &vel,
            },
            PointField {
                name: "velocity_exact",
                n_comp: 2,
                eval: &exact_f,
            },
            PointField {
                name: "pressure",
                n_comp: 1,
                eval: &pres,
            },
        ],
        cell_fields: vec![
            ("error_indicator", eta.clone()),
            ("error", err.l2.clone()),
            ("degree", degrees.iter().map(|&p| p as f64).collect()),
            ("level", level_field(&th.tree, &leaves)),
        ],
        indicator: &eta,
        indicator_label: "eta_K = |u_(p+r) - u_p|_K",
        shade: &speed,
        shade_label: "|u|".into(),
        levels: &[],
        edges: true,
    })?;
    let l2 = err.l2_total();
    let estimate = eta.iter().map(|e| e * e).sum::<f64>().sqrt();
    let res = PnsResults {
        flow: s.flow.to_string(),
        t,
        equations: last.n_eq,
        equations_enriched: last.n_eq_enriched,
        estimate,
        l2_error: l2,
        effectivity: estimate / l2,
        tolerance: s.tolerance,
        worst_ratio: last.worst_ratio,
        accepted: last.accepted && last.worst_ratio <= 1.0,
        solves: reports.len(),
        degrees: degree_histogram(&degrees)
            .into_iter()
            .map(|(p, c)| [p, c])
            .collect(),
    };
    let headline = format!(
        "p-method ({}): {} equations, degrees {}, L2 velocity error {:.3e}, estimate {:.3e} (effectivity {:.3}), tolerance {:.1e} {}",
        s.flow,
        res.equations,
        res.degrees
            .iter()
            .map(|[p, c]| format!("{p}:{c}"))
            .collect::<Vec<_>>()
            .join(" "),
        l2,
        estimate,
        res.effectivity,
        s.tolerance,
        if res.accepted { "met" } else { "not met" }
    );
    Ok(Done {
        dofs: res.equations,
        newton_iterations: newton,
        results: ModelResults::PNavierStokes(res),
        headline,
        interrupted_at: stopped.get().then(|| {
            if s.flow == Flow::Kovasznay {
                reports.len().saturating_sub(1) as f64
            } else {
                t
            }
        }),
    })
}

fn pns_frame(
    out: &mut Outputs,
    index: usize,
    time: Option<f64>,
    f: &Field,
    eta: &[f64],
    r: &SweepReport,
) {
    let th = &f.th;
    let map = |k: usize, a: f64, b: f64| th.point(k, a, b);
    let cells = QuadCells {
        n_cells: th.n_cells(),
        map: &map,
    };
    let value = |k: usize, a: f64, b: f64| {
        let u = th.velocity(&f.x, k, a, b).0;
        u[0].hypot(u[1])
    };
    let scalars = [
        ("equations", r.n_eq as f64),
        ("estimate", r.estimate),
        (
            "l2_error",
            r.effectivity.as_ref().map_or(f64::NAN, |e| e.error),
        ),
    ];
    out.frame(&Frame {
        index,
        time,
        cells: &cells,
        sub: &|k| sub_of(th.degrees()[k]),
        value: &value,
        indicators: eta,
        scalars: &scalars,
    });
}

// ---------------------------------------------------------------------------------------------
// lshape

fn lshape(s: &LShapeSpec, out: &mut Outputs, table: &mut Table) -> Result<Done, Failed> {
    let mut o = AdaptOptions::h(s.degree);
    o.initial_levels = s.initial_levels;
    o.marking = Marking::Dorfler(s.dorfler);
    o.max_dofs = s.max_dofs;
    o.max_steps = s.max_steps;
    o.uniform = s.uniform;
    o.estimator = match s.estimator {
        LEstimator::Explicit => adapt_loop::EstimatorKind::Explicit,
        LEstimator::Equilibrated => adapt_loop::EstimatorKind::Equilibrated,
        LEstimator::Recovery => adapt_loop::EstimatorKind::Recovery,
        LEstimator::Interpolation => adapt_loop::EstimatorKind::Interpolation,
    };
    match s.refinement {
        LRefinement::H => {}
        LRefinement::P | LRefinement::Hp => {
            o.basis = Basis1d::Hierarchical;
            o.max_degree = s.max_degree;
            o.strategy = if s.refinement == LRefinement::P {
                adapt_loop::Strategy::P
            } else {
                adapt_loop::Strategy::Hp
            };
        }
    }
    table.header = vec![
        "step",
        "equations",
        "cells",
        "max_level",
        "max_degree",
        "energy_error",
        "relative_error",
        "estimate",
        "effectivity",
        "t_solve",
        "t_estimate",
    ];
    let u_norm = lshape_energy_sq().sqrt();
    let mut last: Option<(Quadtree, Vec<f64>, Vec<f64>)> = None;
    let mut n_eq = 0;
    let mut stopped = false;
    let recs = adapt_loop::run_observed(
        Quadtree::l_shape(0, s.degree),
        &LShape,
        u_norm,
        &o,
        &mut |v| {
            let r = v.record;
            n_eq = r.n_eq;
            table.rows.push(vec![
                r.step as f64,
                r.n_eq as f64,
                r.n_cells as f64,
                f64::from(r.max_level),
                r.max_degree as f64,
                r.error,
                r.rel_error,
                r.estimate,
                r.estimate / r.error,
                r.t_solve,
                r.t_estimate,
            ]);
            if out.recording() {
                let map = tree_map(v.tree, &v.space.leaves);
                let cells = QuadCells {
                    n_cells: v.space.leaves.len(),
                    map: &map,
                };
                let value = |k: usize, a: f64, b: f64| v.space.eval(v.tree, v.x, k, 0, a, b).0;
                let scalars = [
                    ("equations", r.n_eq as f64),
                    ("energy_error", r.error),
                    ("estimate", r.estimate),
                ];
                out.frame(&Frame {
                    index: r.step,
                    time: None,
                    cells: &cells,
                    sub: &|k| sub_of(v.space.degree[k]),
                    value: &value,
                    indicators: &v.estimate.indicators,
                    scalars: &scalars,
                });
            }
            last = Some((v.tree.clone(), v.x.to_vec(), v.estimate.indicators.clone()));
            stopped = !v.last && interrupted();
            if stopped {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        },
    )
    .map_err(|e| solve_failed(e, n_eq, 0))?;
    let (tree, x, ind) = last.ok_or_else(|| solve_failed("no mesh was solved", n_eq, 0))?;
    let fin = recs
        .last()
        .cloned()
        .ok_or_else(|| solve_failed("no mesh was solved", n_eq, 0))?;
    let g = |p: [f64; 2], _c: usize| crate::adapt::poisson::Exact::u(&LShape, p);
    let space = Space::new(&tree, o.basis, 1, Some(&g)).map_err(|e| solve_failed(e, n_eq, 0))?;
    let err: Vec<f64> = energy_error_sq(&space, &tree, &x, &LShape)
        .iter()
        .map(|e| e.sqrt())
        .collect();
    let leaves = &space.leaves;
    let map = tree_map(&tree, leaves);
    let n = leaves.len();
    let sol =
        |k: usize, a: f64, b: f64, out: &mut [f64]| out[0] = space.eval(&tree, &x, k, 0, a, b).0;
    let exact = |k: usize, a: f64, b: f64, out: &mut [f64]| {
        out[0] = crate::adapt::poisson::Exact::u(&LShape, tree.map_point(leaves[k], a, b));
    };
    let shade = |k: usize, a: f64, b: f64| space.eval(&tree, &x, k, 0, a, b).0;
    let degree: Vec<f64> = space.degree.iter().map(|&p| p as f64).collect();
    out.picture(&Picture {
        title: format!(
            "L-shape, {} refinement, {} equations",
            s.refinement, fin.n_eq
        ),
        cells: QuadCells {
            n_cells: n,
            map: &map,
        },
        sub: &|k| sub_of(space.degree[k]),
        point_fields: vec![
            PointField {
                name: "u",
                n_comp: 1,
                eval: &sol,
            },
            PointField {
                name: "u_exact",
                n_comp: 1,
                eval: &exact,
            },
        ],
        cell_fields: vec![
            ("error_indicator", ind.clone()),
            ("error", err),
            ("degree", degree),
            ("level", level_field(&tree, leaves)),
        ],
        indicator: &ind,
        indicator_label: "eta_K",
        shade: &shade,
        shade_label: "u".into(),
        levels: &[],
        edges: n <= 4096,
    })?;
    let pts: Vec<(f64, f64)> = recs
        .iter()
        .filter(|r| r.n_eq >= 400)
        .map(|r| (r.n_eq as f64, r.error))
        .collect();
    let rate = (pts.len() >= 3).then(|| loglog_slope(&pts));
    let res = LShapeResults {
        equations: fin.n_eq,
        cells: fin.n_cells,
        max_level: fin.max_level,
        max_degree: fin.max_degree,
        energy_error: fin.error,
        relative_error: fin.rel_error,
        estimate: fin.estimate,
        effectivity: fin.estimate / fin.error,
        rate,
    };
    let headline = format!(
        "L-shape ({} refinement, {} estimator): {} meshes, {} equations, energy error {:.3e} ({:.3e} relative), estimate {:.3e} (effectivity {:.3}){}",
        s.refinement,
        s.estimator,
        recs.len(),
        res.equations,
        res.energy_error,
        res.relative_error,
        res.estimate,
        res.effectivity,
        rate.map(|r| format!(", rate {r:.3} in the number of equations"))
            .unwrap_or_default()
    );
    Ok(Done {
        dofs: res.equations,
        newton_iterations: 0,
        results: ModelResults::LShape(res),
        headline,
        interrupted_at: stopped.then_some(fin.step as f64),
    })
}
