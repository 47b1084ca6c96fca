//! Adaptive static indentation and adaptive steady rolling: solve → estimate → mark → refine →
//! transfer, on a locally refined annulus with hanging nodes ([`crate::mesh::refine`]).
//!
//! 1. **Solve** on the current mesh.
//!    * Static indentation (`analysis.mode = "static"`): by load stepping on the first mesh,
//!      then by Newton at the full load from the transferred state (load stepping from scratch
//!      if that fails). With friction the solution depends on the load path, so every mesh is
//!      solved by load stepping from the undeformed state.
//!    * Steady rolling (`analysis.mode = "steady"`): the θ-referential problem on the spatial
//!      mesh, which does not turn with the body, so the refinement stays where the contact
//!      patch is. The first mesh is solved like `tread run` solves it (press-in, recovery
//!      strategies, the scene's rolling control); every later one by Newton at the full load
//!      from the transferred steady state (which, unlike a static frictional state, does not
//!      depend on a load path), then the rolling control; from scratch if that fails.
//! 2. **Estimate** the energy error cell by cell ([`SolidEstimator`]): the Zienkiewicz–Zhu
//!    recovery estimator by default, the interpolation estimator with recovered derivatives,
//!    or the explicit residual with the contact traction as boundary data
//!    ([`crate::physics::estimate`]).
//! 3. **Mark** by Dörfler's bulk criterion: the fewest cells whose squared indicators make up
//!    the fraction θ of the total ([`crate::adapt::marking`], shared with the model problems).
//! 4. **Refine** the marked cells into four, keeping the mesh one-irregular; with a coarsening
//!    fraction c > 0, also **coarsen**: a family of four sibling cells, none of them marked,
//!    merges back into its parent when the parent's predicted indicator is small,
//!    η_P² ≈ 2^{2p} Σ_children η_K² < c η² / N (the energy error of degree p scales like h^p;
//!    N cells), and the parent keeps the mesh one-irregular. The scene's mesh is never
//!    coarsened.
//! 5. **Transfer** the displacement to the new mesh by evaluating the old solution at the new
//!    nodes (exact for the nodes of unrefined cells and for the children's nodes that the
//!    parent interpolates).
//!
//! The root mesh is the scene's structured annulus with the exact polar cell map, so every
//! refined cell lies exactly on the circles and the adaptive meshes converge to the true
//! geometry. A viscoelastic material needs no transfer in steady rolling: its internal
//! variables are a function of the steady state, integrated along the streamlines by the
//! upwind scheme on the refined (non-ring) meshes (`physics::streamline_upwind`). Static
//! indentation refuses viscoelastic materials (no relaxed limit there).

use super::indentation::{self, IndentationResults};
use super::steady::SteadyRolling;
use super::steady_run;
use crate::adapt::marking::{coarsening_limit, CellEstimate, CellEstimator, Marking};
use crate::adapt::moving_mesh::MonitorParams;
use crate::io::output::{ensure_dir, write_json, OutputError};
use crate::io::record::vtu::vtu_bytes;
use crate::io::scene::VtuFormat;
use crate::io::scene::{Mode, Scene, SteadyHistoryChoice};
use crate::mesh::locate::vector_at;
use crate::mesh::{annulus, Forest, Mesh};
use crate::model::system::SolidSystem;
use crate::physics::estimate::SolidContext;
use crate::physics::SolidModel;
use crate::physics::{equilibrated, estimate};
use crate::setup::{build_contact, build_material, AppError};
use crate::solver::stepping::{LoadedSystem, StepReport};
use crate::solver::{Newton, NonlinearSystem, SolveError};
use std::path::Path;
use std::time::Instant;

/// The estimator that drives the marking.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SolidEstimator {
    /// Zienkiewicz–Zhu recovery ([`estimate::recovery`]).
    Recovery,
    /// Interpolation error with recovered derivatives ([`estimate::interpolation`]).
    Interpolation,
    /// Explicit residual with the contact traction on the contact facets
    /// ([`estimate::explicit_residual_with`]; its constant taken as 1, so its global value is
    /// an indicator, not an estimate of the error's size).
    Explicit,
    /// Equilibrated residual with local Neumann problems ([`equilibrated::equilibrated`]; an
    /// upper bound of the energy error of the static solid).
    Equilibrated,
}

impl SolidEstimator {
    pub fn keyword(self) -> &'static str {
        match self {
            Self::Recovery => "recovery",
            Self::Interpolation => "interpolation",
            Self::Explicit => "explicit",
            Self::Equilibrated => "equilibrated",
        }
    }
}

impl SolidEstimator {
    /// Whether the estimator takes the contact tractions as boundary data.
    pub fn uses_applied_tractions(self) -> bool {
        matches!(self, Self::Explicit | Self::Equilibrated)
    }
}

/// The chosen estimator, itself an estimator of the solid.
impl CellEstimator<SolidContext<'_>> for SolidEstimator {
    type Error = std::convert::Infallible;
    fn name(&self) -> &'static str {
        self.keyword()
    }
    fn estimate(&self, ctx: &SolidContext) -> Result<CellEstimate, Self::Error> {
        match self {
            Self::Recovery => estimate::Recovery.estimate(ctx),
            Self::Interpolation => estimate::Interpolation.estimate(ctx),
            Self::Explicit => estimate::ExplicitResidual.estimate(ctx),
            Self::Equilibrated => equilibrated::Equilibrated.estimate(ctx),
        }
    }
}

impl std::str::FromStr for SolidEstimator {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        parse_keyword(
            "estimator",
            &[
                Self::Recovery,
                Self::Interpolation,
                Self::Explicit,
                Self::Equilibrated,
            ],
            Self::keyword,
            s,
        )
    }
}

/// The option of `all` whose keyword is `s`, or an error naming `what` and the keywords.
fn parse_keyword<T: Copy>(
    what: &str,
    all: &[T],
    keyword: fn(T) -> &'static str,
    s: &str,
) -> Result<T, String> {
    if let Some(&v) = all.iter().find(|&&v| keyword(v) == s) {
        return Ok(v);
    }
    let names: Vec<String> = all.iter().map(|&v| format!("\"{}\"", keyword(v))).collect();
    let (last, rest) = names
        .split_last()
        .map_or(("", &[][..]), |(l, r)| (l.as_str(), r));
    Err(format!(
        "unknown {what} `{s}` (expected {} or {last})",
        rest.join(", ")
    ))
}

/// How marked cells are refined (`tread adapt --refine`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Refinement {
    /// Split into four (quadtree, hanging nodes).
    #[default]
    H,
    /// Raise the degree from 1 to 2 (the solid's elements are Lagrange Q1 and Q2; transitions
    /// between degrees are constrained to the lower degree's trace, the minimum rule). Cells
    /// already of degree 2 are left: the loop stops when no marked cell can be raised.
    P,
    /// Raise marked cells of degree 1 to 2, split marked cells of degree 2.
    Hp,
    /// Move the annulus's cell boundaries toward the large indicators (moving mesh: same
    /// cells and unknowns, [`super::relocation`]); no marking.
    R,
}

impl Refinement {
    pub fn keyword(self) -> &'static str {
        match self {
            Self::H => "h",
            Self::P => "p",
            Self::Hp => "hp",
            Self::R => "r",
        }
    }
}

impl std::str::FromStr for Refinement {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        parse_keyword(
            "refinement",
            &[Self::H, Self::P, Self::Hp, Self::R],
            Self::keyword,
            s,
        )
    }
}

/// Options of the adaptive loop.
#[derive(Clone, Debug)]
pub struct AdaptOptions {
    /// The estimator that drives the marking.
    pub estimator: SolidEstimator,
    /// Refinement steps after the first solve.
    pub steps: usize,
    /// Dörfler fraction θ ∈ (0, 1]: marked cells carry θ of the squared estimate.
    pub fraction: f64,
    /// Stop before a mesh would exceed this many equations.
    pub max_dofs: usize,
    /// Stop once the relative estimate η / ‖u_h‖_A is below this.
    pub tolerance: f64,
    /// Coarsening fraction c ≥ 0: a family of four unmarked sibling cells merges when its
    /// predicted parent indicator 2^{2p} Σ η_K² is below c · η² / N (N cells, degree p);
    /// 0 = no coarsening.
    pub coarsen: f64,
    /// Uniform refinements of the scene's mesh before the first solve (which the coarsening
    /// may then undo where the error is small).
    pub uniform: usize,
    /// How marked cells are refined: h, p (degree 1 → 2) or hp; or r, the cell boundaries
    /// moved instead.
    pub refinement: Refinement,
    /// The monitor of `Refinement::R` (α, β, γ of [`super::relocation`]).
    pub monitor: MonitorParams,
}

impl Default for AdaptOptions {
    fn default() -> Self {
        Self {
            estimator: SolidEstimator::Recovery,
            steps: 8,
            fraction: 0.5,
            max_dofs: 200_000,
            tolerance: 0.0,
            coarsen: 0.0,
            uniform: 0,
            refinement: Refinement::H,
            monitor: MonitorParams::default(),
        }
    }
}

/// One mesh of the adaptive sequence.
#[derive(Clone, Debug, serde::Serialize)]
pub struct AdaptStep {
    pub step: usize,
    pub cells: usize,
    pub dofs: usize,
    pub hanging_nodes: usize,
    pub max_level: u8,
    /// Cells of degree 2 (the rest are of degree 1).
    pub degree2_cells: usize,
    /// Families of four cells merged into their parent after the previous mesh (0 on the
    /// first).
    pub coarsened: usize,
    /// Recovery estimate η and its ratio to the energy norm of the solution.
    pub estimate: f64,
    pub relative_estimate: f64,
    pub hub_force_x: f64,
    pub hub_force_y: f64,
    /// Hub torque (the driving torque of steady rolling).
    pub hub_torque: f64,
    /// Penetration DISP = Ro − H (the unknown of load control).
    pub penetration: f64,
    pub newton_iterations: usize,
    /// Wall time of this step's solve and estimate, and since the start (s).
    pub wall_step_s: f64,
    pub wall_total_s: f64,
}

/// The scene's annulus with the exact polar map (no `make_isoparametric`).
pub fn polar_root(scene: &Scene) -> Result<Mesh, AppError> {
    if scene.mesh.file.is_some() {
        return Err(AppError::Unsupported(
            "tread adapt refines the generated annulus ([mesh] n_r, n_theta), not a mesh file"
                .into(),
        ));
    }
    Ok(annulus(&crate::setup::annulus_spec(scene)))
}

/// The scene's static indentation system on `mesh`.
pub fn indentation_system(scene: &Scene, mesh: Mesh) -> Result<SolidSystem, AppError> {
    if scene.material.viscoelastic.is_some() {
        return Err(AppError::Unsupported(
            "adaptive indentation: viscoelastic materials have no static limit here".into(),
        ));
    }
    let (material, pressure) = build_material(scene)?;
    let model = SolidModel::new(mesh, material, scene.material.rho, pressure);
    let contact = build_contact(scene, &model)?;
    let mut sys = SolidSystem::with_contact(model, contact);
    sys.loading = crate::setup::scene_loading(scene);
    Ok(sys)
}

/// Solve `sys` to the full load: from its current state by Newton when `warm`, else (or if
/// that fails) by load stepping from `cold` (the undeformed state of the system as built;
/// `None`: the current state is that). Returns the Newton iterations.
pub fn solve_static(
    scene: &Scene,
    sys: &mut SolidSystem,
    warm: bool,
    cold: Option<&[f64]>,
    out_dir: &Path,
) -> Result<usize, AppError> {
    let plan = crate::setup::solve_plan(scene, sys);
    let (kind, newton_opts, step_opts) = (plan.kind, plan.newton, plan.steps);
    if warm {
        sys.set_load(1.0);
        let ro = scene.geometry.ro;
        sys.set_reference_force(sys.contact_force_scale(ro));
        let warm_run = Newton::new(sys, kind, newton_opts.clone()).and_then(|mut n| n.solve(sys));
        match warm_run {
            Ok(rep) => return Ok(rep.iterations),
            Err(_) => {
                if let Some(c) = cold {
                    sys.x.copy_from_slice(c);
                }
                sys.set_load(0.0);
            }
        }
    }
    let mut report = StepReport::default();
    indentation::solve_indentation(sys, kind, newton_opts, &step_opts, &mut report, &mut ())
        .map_err(|e| AppError::Solve(e, out_dir.to_path_buf()))?;
    Ok(report.total_iterations)
}

/// The system an adaptive run solves on each mesh.
enum Problem {
    Static(Box<SolidSystem>),
    Steady(Box<SteadyRolling>),
}

impl Problem {
    /// The scene's problem on `mesh`.
    fn build(scene: &Scene, mesh: Mesh) -> Result<Self, AppError> {
        match scene.analysis.mode {
            Mode::Steady => {
                if scene.road.is_none() || scene.contact.is_none() {
                    return Err(AppError::Unsupported(
                        "tread adapt: steady rolling needs [road] and [contact]".into(),
                    ));
                }
                let (material, pressure) = build_material(scene)?;
                let mut model = SolidModel::new(mesh, material, scene.material.rho, pressure);
                // A viscoelastic history is a function of the steady state (integrated along
                // the streamlines at every evaluation): nothing to transfer between meshes.
                // One discretisation of it on every mesh of the loop: the upwind scheme, unless
                // the scene asks for the rings (which the refined meshes do not have).
                crate::setup::attach_viscoelastic(scene, &mut model)?;
                let mut scene = scene.clone();
                if scene.solver.steady_history == SteadyHistoryChoice::Auto {
                    scene.solver.steady_history = SteadyHistoryChoice::Upwind;
                }
                Ok(Self::Steady(Box::new(steady_run::steady_on(
                    &scene, model,
                )?)))
            }
            _ => Ok(Self::Static(Box::new(indentation_system(scene, mesh)?))),
        }
    }

    fn sys(&self) -> &SolidSystem {
        match self {
            Self::Static(s) => s.as_ref(),
            Self::Steady(st) => &st.sys,
        }
    }

    fn sys_mut(&mut self) -> &mut SolidSystem {
        match self {
            Self::Static(s) => s.as_mut(),
            Self::Steady(st) => &mut st.sys,
        }
    }

    /// Whether the next mesh starts from the transferred state at the full load. Friction makes
    /// the static solution depend on the load path (the stick anchors are committed load step
    /// by load step): such a scene is solved by load stepping on every mesh. A steady state
    /// has no path.
    fn warm_starts(&self) -> bool {
        match self {
            Self::Static(sys) => !sys.contact.as_ref().is_some_and(|c| c.friction.is_active()),
            Self::Steady(_) => true,
        }
    }

    fn into_sys(self) -> SolidSystem {
        match self {
            Self::Static(s) => *s,
            Self::Steady(st) => st.sys,
        }
    }

    /// Solve on the current mesh (see the module docs); `warm`: start from the current,
    /// transferred state; `cold`: the state as built, to fall back to. Returns the Newton
    /// iterations.
    fn solve(
        &mut self,
        scene: &Scene,
        warm: bool,
        cold: &[f64],
        out_dir: &Path,
    ) -> Result<usize, AppError> {
        match self {
            Self::Static(sys) => solve_static(scene, sys, warm, Some(cold), out_dir),
            Self::Steady(st) => solve_rolling(scene, st, warm, cold, out_dir),
        }
    }
}

/// Solve the current mesh ([`Problem::solve`]); `None` when an interrupt (Ctrl-C) stopped the
/// solve after at least one mesh was solved (`done`): the loop then ends with those meshes. An
/// interrupt on the first mesh is the error [`AppError::Interrupted`].
fn solve_unless_interrupted(
    problem: &mut Problem,
    scene: &Scene,
    warm: bool,
    cold: &[f64],
    out_dir: &Path,
    done: &[AdaptStep],
) -> Result<Option<usize>, AppError> {
    match problem.solve(scene, warm, cold, out_dir) {
        Ok(n) => Ok(Some(n)),
        Err(AppError::Solve(SolveError::Interrupted { .. }, dir)) if done.is_empty() => {
            Err(AppError::Interrupted(dir))
        }
        Err(AppError::Solve(SolveError::Interrupted { .. }, _)) => Ok(None),
        Err(e) => Err(e),
    }
}

/// Steady rolling on one mesh of the adaptive sequence: Newton at the full load from the
/// current state when `warm` (else, or if that fails, the whole steady solve from `cold`), then
/// the scene's rolling control.
fn solve_rolling(
    scene: &Scene,
    st: &mut SteadyRolling,
    warm: bool,
    cold: &[f64],
    out_dir: &Path,
) -> Result<usize, AppError> {
    let fail = |e: SolveError| AppError::Solve(e, out_dir.to_path_buf());
    let mut report = StepReport::default();
    let mut solved = false;
    let mut recovery_iterations = 0;
    if warm {
        match steady_run::press_once(scene, st, false, &mut report, &mut ()) {
            Ok(()) => solved = true,
            Err(e @ SolveError::Interrupted { .. }) => return Err(fail(e)),
            Err(_) => st.sys.restore_state(cold),
        }
    }
    if !solved {
        recovery_iterations = steady_run::solve_steady(scene, st, false, &mut report, &mut ())
            .map_err(|f| fail(f.error))?
            .recovery_iterations();
    }
    let control = steady_run::apply_control(scene, st, false).map_err(fail)?;
    Ok(report.total_iterations + control.newton_iterations + recovery_iterations)
}

/// Run the adaptive loop on the scene (static indentation or steady rolling). `on_step` sees
/// every solved mesh with its indicators; `out_dir` is where the caller writes (named in
/// errors).
///
/// An interrupt (Ctrl-C: [`crate::io::record::interrupted`]) ends the loop at the next mesh
/// boundary: after the mesh being estimated, or, when it comes during a solve after the first
/// mesh, with the meshes solved before it (the returned system then holds the state
/// transferred to the unsolved mesh). The steps returned are the solved meshes; the caller
/// tells an interrupted run by `interrupted()`. An interrupt during the first mesh's solve is
/// the error [`AppError::Interrupted`] (exit status 130).
pub fn run(
    scene: &Scene,
    opts: &AdaptOptions,
    out_dir: &Path,
    mut on_step: impl FnMut(&SolidSystem, &AdaptStep, &[f64]),
) -> Result<(SolidSystem, Vec<AdaptStep>), AppError> {
    if !(opts.coarsen.is_finite() && opts.coarsen >= 0.0) {
        return Err(AppError::Unsupported(format!(
            "tread adapt: the coarsening fraction must be >= 0, got {}",
            opts.coarsen
        )));
    }
    if !(opts.fraction > 0.0 && opts.fraction <= 1.0) {
        return Err(AppError::Unsupported(format!(
            "tread adapt: the Dörfler fraction must be in (0, 1], got {}",
            opts.fraction
        )));
    }
    if !matches!(scene.analysis.mode, Mode::Static | Mode::Steady) {
        return Err(AppError::Unsupported(format!(
            "tread adapt needs analysis.mode = \"static\" (indentation) or \"steady\" \
             (steady rolling); the scene's is \"{}\"",
            scene.analysis.mode
        )));
    }
    if opts.refinement == Refinement::R {
        return run_relocation(scene, opts, out_dir, on_step);
    }
    let t0 = Instant::now();
    let mut forest = Forest::new(polar_root(scene)?)
        .map_err(|e| AppError::Unsupported(format!("tread adapt: {e}")))?;
    if opts.refinement != Refinement::H {
        let r = opts.refinement.keyword();
        if scene.mesh.order != 1 {
            return Err(AppError::Unsupported(format!(
                "tread adapt --refine {r} raises cells from degree 1 to 2: start from mesh.order = 1 (the scene has {})",
                scene.mesh.order
            )));
        }
        if !matches!(
            crate::setup::build_material(scene)?.1,
            crate::physics::PressureMode::None
        ) {
            return Err(AppError::Unsupported(format!(
                "tread adapt --refine {r}: an incompressible material needs Q2 displacements (with P1 pressures) in every cell; use --refine h with mesh.order = 2"
            )));
        }
    }
    // The uniform refinements must not outgrow --max-dofs (2 p² equations per cell, roughly).
    let degree = forest.root.degree.first().copied().unwrap_or(1) as usize;
    let cells = 4usize
        .checked_pow(u32::try_from(opts.uniform).unwrap_or(u32::MAX))
        .and_then(|f| f.checked_mul(forest.leaves().len()));
    let estimate = cells.and_then(|c| c.checked_mul(2 * degree * degree));
    if estimate.is_none_or(|e| e > opts.max_dofs) {
        return Err(AppError::Unsupported(format!(
            "tread adapt: {} uniform refinements of the {}-cell mesh give about {} equations, more than the limit of {} (--max-dofs)",
            opts.uniform,
            forest.leaves().len(),
            estimate.map_or("too many".to_string(), |e| e.to_string()),
            opts.max_dofs
        )));
    }
    for _ in 0..opts.uniform {
        let all: Vec<usize> = (0..forest.leaves().len()).collect();
        forest
            .refine(&all)
            .map_err(|e| AppError::Unsupported(format!("tread adapt: {e}")))?;
    }
    let (mut mesh, _) = forest.mesh();
    let mut problem = Problem::build(scene, mesh.clone())?;
    let mut steps = Vec::new();
    let mut warm = false;
    let mut cold = problem.sys().x.clone();
    let mut coarsened = 0;
    for step in 0..=opts.steps {
        let ts = Instant::now();
        let Some(iterations) =
            solve_unless_interrupted(&mut problem, scene, warm, &cold, out_dir, &steps)?
        else {
            break;
        };
        let sys = problem.sys();
        let rec = AdaptStep {
            hanging_nodes: mesh.constraints.len(),
            max_level: forest.leaves().iter().map(|l| l.level).max().unwrap_or(0),
            degree2_cells: forest.degrees().iter().filter(|&&d| d == 2).count(),
            coarsened,
            ..AdaptStep::of(step, mesh.n_cells(), iterations)
        };
        let (est, done) = rec.record(scene, opts, sys, (ts, t0), &mut on_step, &mut steps);
        if done {
            break;
        }
        // Mark (Dörfler) and refine.
        let marked = est.mark(Marking::Dorfler(opts.fraction));
        // Coarsening candidates, by leaf (indices change with the refinement): the children of
        // the families whose predicted parent indicator is small.
        let small = if opts.coarsen > 0.0 {
            let degree = forest.degrees().iter().copied().max().unwrap_or(1);
            let growth = f64::from(1u32 << (2 * u32::from(degree)));
            let limit = coarsening_limit(&est.indicators, opts.coarsen);
            coarsening_candidates(forest.leaves(), &est.indicators, &marked, growth, limit)
        } else {
            Default::default()
        };
        let old_forest = forest.clone();
        let adapt_err = |e| AppError::Unsupported(format!("tread adapt: {e}"));
        // p: raise degree-1 cells; h: split; hp: raise the degree-1 cells, split the others.
        // Raising keeps the leaf indices, so the split uses the same ones.
        let (raise, split): (Vec<usize>, Vec<usize>) = match opts.refinement {
            // (`R` runs its own loop, `run_relocation`.)
            Refinement::H | Refinement::R => (Vec::new(), marked.clone()),
            Refinement::P => (marked.clone(), Vec::new()),
            Refinement::Hp => marked.iter().partition(|&&k| forest.degrees()[k] == 1),
        };
        let raised = forest.raise_degree(&raise).map_err(adapt_err)?;
        let split_count = forest.refine(&split).map_err(adapt_err)?;
        if raised + split_count == 0 {
            // p-refinement with every marked cell already of degree 2: nothing left to do.
            break;
        }
        coarsened = 0;
        if !small.is_empty() {
            let merge: Vec<usize> = (0..forest.leaves().len())
                .filter(|&k| small.contains(&forest.leaves()[k]))
                .collect();
            coarsened = forest.coarsen(&merge).map_err(adapt_err)?;
        }
        let (new_mesh, origin) = forest.mesh();
        let mut next_problem = Problem::build(scene, new_mesh.clone())?;
        if next_problem.sys().n_dofs() > opts.max_dofs {
            break;
        }
        // Transfer: the displacements, and the global unknowns (the road height under load
        // control).
        let at = origin.iter().map(|&(root, xi, eta)| {
            old_forest
                .locate(root, xi, eta)
                .map(|(leaf, (a, b))| (leaf, a, b))
        });
        cold = transfer(sys, &mesh, next_problem.sys_mut(), at);
        problem = next_problem;
        mesh = new_mesh;
        warm = problem.warm_starts();
    }
    Ok((problem.into_sys(), steps))
}

/// The moving-mesh loop (`--refine r`, [`super::relocation`]): solve on the scene's annulus
/// (the exact polar map), estimate, move the cell boundaries, transfer the solution, solve
/// again, `opts.steps` times; every mesh is one [`AdaptStep`] with the same cells and unknowns.
fn run_relocation(
    scene: &Scene,
    opts: &AdaptOptions,
    out_dir: &Path,
    mut on_step: impl FnMut(&SolidSystem, &AdaptStep, &[f64]),
) -> Result<(SolidSystem, Vec<AdaptStep>), AppError> {
    let m = opts.monitor;
    m.check()
        .map_err(|e| AppError::Unsupported(format!("tread adapt --refine r: {e}")))?;
    if opts.uniform > 0 || opts.coarsen > 0.0 {
        return Err(AppError::Unsupported(
            "tread adapt --refine r moves the scene's cells: --uniform and --coarsen do not apply"
                .into(),
        ));
    }
    let t0 = Instant::now();
    let mut mesh = polar_root(scene)?;
    let spec = crate::setup::annulus_spec(scene);
    let (mut rb, mut tb) = (
        crate::mesh::annulus::radial_breaks(&spec),
        crate::mesh::annulus::angular_breaks(&spec),
    );
    let mut problem = Problem::build(scene, mesh.clone())?;
    let mut cold = problem.sys().x.clone();
    let mut warm = false;
    let mut steps = Vec::new();
    for step in 0..=opts.steps {
        let ts = Instant::now();
        let Some(iterations) =
            solve_unless_interrupted(&mut problem, scene, warm, &cold, out_dir, &steps)?
        else {
            break;
        };
        let sys = problem.sys();
        let rec = AdaptStep {
            degree2_cells: mesh.degree.iter().filter(|&&d| d == 2).count(),
            ..AdaptStep::of(step, mesh.n_cells(), iterations)
        };
        let (est, done) = rec.record(scene, opts, sys, (ts, t0), &mut on_step, &mut steps);
        if done {
            break;
        }
        let sq: Vec<f64> = est.indicators.iter().map(|e| e * e).collect();
        let (rb1, tb1, new_mesh) = super::relocation::relocate(&spec, &rb, &tb, &sq, &m);
        let mut next_problem = Problem::build(scene, new_mesh.clone())?;
        // Transfer: the old displacement field at the new nodes (located in the old cells),
        // and the global unknowns.
        let found = crate::mesh::locate::locate_points(&mesh, &new_mesh.nodes);
        cold = transfer(
            sys,
            &mesh,
            next_problem.sys_mut(),
            found.into_iter().map(Some),
        );
        problem = next_problem;
        mesh = new_mesh;
        (rb, tb) = (rb1, tb1);
        warm = problem.warm_starts();
    }
    Ok((problem.into_sys(), steps))
}

/// Transfer the solved `old` (on `old_mesh`) to the newly built `next`: its global unknowns
/// (the road height under load control), and at each new node the old displacement at the
/// node's place `at[node]` (old cell and reference point; `None` keeps the built value); the
/// constraints of hanging nodes are then applied. Returns `next`'s state as built (the cold
/// start to fall back to).
fn transfer(
    old: &SolidSystem,
    old_mesh: &Mesh,
    next: &mut SolidSystem,
    at: impl Iterator<Item = Option<(usize, f64, f64)>>,
) -> Vec<f64> {
    let cold = next.x.clone();
    let mut x = next.x.clone();
    for k in 0..next.dofs.n_global.min(old.dofs.n_global) {
        x[next.dofs.global(k)] = old.x[old.dofs.global(k)];
    }
    for (node, place) in at.enumerate() {
        if let Some((c, xi, eta)) = place {
            let u = vector_at(old_mesh, &old.x, c, xi, eta);
            x[2 * node] = u[0];
            x[2 * node + 1] = u[1];
        }
    }
    next.dofs.apply_constraints(&mut x);
    next.restore_state(&x);
    cold
}

impl AdaptStep {
    /// The row of mesh `step` with `cells` cells solved in `iterations` Newton iterations; the
    /// mesh's other counts, the estimate, the loads and the times zero until filled in.
    fn of(step: usize, cells: usize, iterations: usize) -> Self {
        Self {
            step,
            cells,
            dofs: 0,
            hanging_nodes: 0,
            max_level: 0,
            degree2_cells: 0,
            coarsened: 0,
            estimate: 0.0,
            relative_estimate: 0.0,
            hub_force_x: 0.0,
            hub_force_y: 0.0,
            hub_torque: 0.0,
            penetration: 0.0,
            newton_iterations: iterations,
            wall_step_s: 0.0,
            wall_total_s: 0.0,
        }
    }

    /// The row of a solved mesh, finished: the estimate ([`Self::estimate_on`]), the wall
    /// times since `ts` (this mesh) and `t0` (the run), `on_step`, and the row pushed to
    /// `steps`. Returns the estimate and whether the loop ends here (the last step, the
    /// tolerance reached, or an interrupt).
    fn record(
        mut self,
        scene: &Scene,
        opts: &AdaptOptions,
        sys: &SolidSystem,
        (ts, t0): (Instant, Instant),
        on_step: &mut impl FnMut(&SolidSystem, &AdaptStep, &[f64]),
        steps: &mut Vec<AdaptStep>,
    ) -> (CellEstimate, bool) {
        let est = self.estimate_on(scene, opts, sys);
        self.wall_step_s = ts.elapsed().as_secs_f64();
        self.wall_total_s = t0.elapsed().as_secs_f64();
        on_step(sys, &self, &est.indicators);
        let done = self.step == opts.steps
            || self.relative_estimate < opts.tolerance
            || crate::io::record::interrupted();
        steps.push(self);
        (est, done)
    }

    /// Estimate the error of the solved `sys` with `opts.estimator` (the contact tractions
    /// are the boundary data of the residual estimators only) and fill in the row's
    /// equations, estimate and loads; returns the estimate.
    fn estimate_on(
        &mut self,
        scene: &Scene,
        opts: &AdaptOptions,
        sys: &SolidSystem,
    ) -> CellEstimate {
        let applied = opts
            .estimator
            .uses_applied_tractions()
            .then(|| sys.contact_tractions())
            .flatten();
        let ctx = SolidContext {
            model: &sys.model,
            dofs: &sys.dofs,
            x: &sys.x,
            free: &[],
            applied: applied.as_ref(),
        };
        let Ok(est) = opts.estimator.estimate(&ctx);
        let norm = estimate::energy_norm(&sys.model, &sys.dofs, &sys.x);
        let r: IndentationResults = indentation::results(sys, scene.geometry.ro);
        self.dofs = sys.n_dofs();
        self.estimate = est.global;
        self.relative_estimate = if norm > 0.0 { est.global / norm } else { 0.0 };
        self.hub_force_x = r.hub_force_x;
        self.hub_force_y = r.hub_force_y;
        self.hub_torque = r.hub_torque;
        self.penetration = r.penetration;
        est
    }
}

/// The leaves of the families (four sibling leaves, none in `marked`) whose predicted parent
/// indicator `growth · Σ η_K²` is below `limit`.
fn coarsening_candidates(
    leaves: &[crate::mesh::refine::Leaf],
    indicators: &[f64],
    marked: &[usize],
    growth: f64,
    limit: f64,
) -> std::collections::HashSet<crate::mesh::refine::Leaf> {
    use std::collections::HashMap;
    // Per parent: children that are leaves, whether one of them is marked, Σ η_K².
    let mut family: HashMap<crate::mesh::refine::Leaf, (usize, bool, f64)> = HashMap::new();
    let mut is_marked = vec![false; leaves.len()];
    for &k in marked {
        is_marked[k] = true;
    }
    for (k, l) in leaves.iter().enumerate() {
        if let Some(p) = l.parent() {
            let e = family.entry(p).or_default();
            e.0 += 1;
            e.1 |= is_marked[k];
            e.2 += indicators[k] * indicators[k];
        }
    }
    leaves
        .iter()
        .filter(|l| {
            l.parent()
                .and_then(|p| family.get(&p))
                .is_some_and(|&(n, any_marked, sum)| n == 4 && !any_marked && growth * sum < limit)
        })
        .copied()
        .collect()
}

/// Write `DIR/adapt.csv` (one row per mesh), `DIR/adapt.json` (options and steps) and, through
/// `on_step` of [`run`], `DIR/adapt_<step>.vtu` (the mesh, displacement, stresses and the
/// `error_indicator` per cell).
pub fn write(dir: &Path, opts: &AdaptOptions, steps: &[AdaptStep]) -> Result<(), OutputError> {
    ensure_dir(dir)?;
    let header = [
        "step",
        "cells",
        "dofs",
        "hanging_nodes",
        "max_level",
        "degree2_cells",
        "coarsened",
        "estimate",
        "relative_estimate",
        "hub_force_x",
        "hub_force_y",
        "hub_torque",
        "penetration",
        "newton_iterations",
        "wall_step_s",
        "wall_total_s",
    ];
    let rows = steps.iter().map(|s| {
        vec![
            s.step.to_string(),
            s.cells.to_string(),
            s.dofs.to_string(),
            s.hanging_nodes.to_string(),
            s.max_level.to_string(),
            s.degree2_cells.to_string(),
            s.coarsened.to_string(),
            format!("{:.10e}", s.estimate),
            format!("{:.10e}", s.relative_estimate),
            format!("{:.12e}", s.hub_force_x),
            format!("{:.12e}", s.hub_force_y),
            format!("{:.12e}", s.hub_torque),
            format!("{:.12e}", s.penetration),
            s.newton_iterations.to_string(),
            format!("{:.6}", s.wall_step_s),
            format!("{:.6}", s.wall_total_s),
        ]
    });
    crate::io::output::write_text_csv(&dir.join("adapt.csv"), &header, rows)?;
    let json = serde_json::json!({
        "options": {
            "steps": opts.steps,
            "fraction": opts.fraction,
            "max_dofs": opts.max_dofs,
            "tolerance": opts.tolerance,
            "coarsen": opts.coarsen,
            "uniform": opts.uniform,
            "estimator": opts.estimator.keyword(),
            "refinement": opts.refinement.keyword(),
            "marking": "doerfler",
        },
        "steps": steps,
        // Stopped by Ctrl-C: `steps` are the meshes solved before it.
        "interrupted": crate::io::record::interrupted(),
    });
    write_json(&dir.join("adapt.json"), &json)
}

/// The VTU of one solved mesh, with the cells' error indicators.
pub fn write_vtu(dir: &Path, step: usize, sys: &SolidSystem) -> Result<(), OutputError> {
    let frame = super::frame::SolidFrame::capture(sys, true);
    let view = frame.view(sys, &[]);
    let path = dir.join(format!("adapt_{step:03}.vtu"));
    std::fs::write(
        &path,
        vtu_bytes(&sys.model.mesh, &view, step as f64, VtuFormat::Binary),
    )
    .map_err(|source| OutputError { path, source })
}

/// One line on the last mesh (`what`: "adaptive indentation", "adaptive steady rolling").
pub fn headline(what: &str, steps: &[AdaptStep]) -> String {
    match steps.last() {
        Some(s) => format!(
            "{what}: {} meshes, last {} cells, {} equations ({} hanging nodes, level {}), estimate {:.3e} ({:.3e} relative), hub force = ({:.6e}, {:.6e}), torque {:.6e}",
            steps.len(),
            s.cells,
            s.dofs,
            s.hanging_nodes,
            s.max_level,
            s.estimate,
            s.relative_estimate,
            s.hub_force_x,
            s.hub_force_y,
            s.hub_torque
        ),
        None => format!("{what}: no mesh solved"),
    }
}
