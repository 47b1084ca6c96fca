//! From a validated [`Scene`] to what a run needs: the model (mesh, material, pressure
//! treatment, contact), the solver options, the recorder's sinks, and the run's error and
//! outcome types shared by every mode. The only translation from scene values to physics
//! values; it runs nothing.
//!
//! Units are the scene's (consistent units, e.g. SI: lengths in m, moduli in Pa, ω in rad/s,
//! forces per unit thickness); no value is rescaled here. Sign conventions are those of the
//! physics modules the values are handed to (road at x2 = −H below the hub centre, ω > 0
//! counter-clockwise).

use crate::contact::facet3d::ContactSurface3D;
use crate::contact::{Clamp, ContactModel, FacetRule, NormalCompliance};
use crate::io::output::OutputError;
use crate::io::record::{self, Recorders};
use crate::io::scene::{
    ClampKind, ContactQuadrature, ContinuationSpec, Formulation, LimitAction, LinearChoice,
    MeshSides, Mode, Scene, Sink, SteadyHistoryChoice, DEFAULT_CLAMP_WIDTH_OVER_G,
};
use crate::material::{Hyperelastic, Material};
use crate::math::Mat2;
use crate::mesh::hex_mesh::HexMesh;
use crate::mesh::revolved::{revolved, RevolvedSpec};
use crate::mesh::{annulus, AnnulusSpec};
use crate::model::system::Loading;
use crate::model::{Solid3D, Solid3DSystem, SolidSystem};
use crate::physics::{PressureMode, SolidModel};
use crate::solver::continuation::ContinuationOptions;
use crate::solver::stepping::StepOptions;
use crate::solver::{LinearKind, NewtonOptions, SolveError, SolvePlan};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum AppError {
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error("the solve failed: {0} (partial results written to {1})")]
    Solve(SolveError, PathBuf),
    #[error("scene: {0}")]
    Unsupported(String),
    #[error("interrupted: the logs up to the last step are written to {0}")]
    Interrupted(PathBuf),
    /// A computation other than a Newton solve failed (e.g. the stick-slip integrator).
    #[error("{0} (partial results written to {1})")]
    Failed(String, PathBuf),
    /// The output folder cannot be used (not writable, locked by another run, …).
    #[error("output folder {0}: {1}")]
    OutDir(PathBuf, String),
    /// The scene would need more memory than allowed.
    #[error("{0}")]
    TooBig(String),
    /// The scene's mesh file (`mesh.file`, resolved path) cannot be read or is not a valid mesh.
    #[error("mesh.file: {0}")]
    MeshFile(crate::mesh::gmsh::MeshError),
}

impl AppError {
    /// Process exit status: 130 interrupted, 1 the computation failed, 2 invalid input (scene,
    /// flags, a model too large for the memory limit), 3 an output file or folder cannot be
    /// written.
    pub fn exit_code(&self) -> u8 {
        match self {
            AppError::Interrupted(_) => 130,
            AppError::Solve(..) | AppError::Failed(..) => 1,
            AppError::Output(_) | AppError::OutDir(..) => 3,
            AppError::Unsupported(_) | AppError::TooBig(_) | AppError::MeshFile(_) => 2,
        }
    }
}

#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    pub out_dir: PathBuf,
    /// Print the Newton convergence table.
    pub verbose: bool,
    /// No progress bar.
    pub quiet: bool,
}

/// The sinks of `[output] sinks` writing into `out_dir` (each with decimation `[output]
/// every`), plus the progress bar unless `quiet`. Returns warnings (a sink not available in
/// this build).
pub fn build_recorders(scene: &Scene, out_dir: &Path, quiet: bool) -> (Recorders, Vec<String>) {
    let mut r = Recorders::new();
    #[cfg_attr(feature = "rerun", allow(unused_mut))]
    let mut warnings = Vec::new();
    let every = scene.output.every;
    for sink in &scene.output.sinks {
        match sink {
            Sink::Summary => {}
            // Scalars at every step: decimating them aliases with the node passages.
            Sink::Csv => r.push(Box::new(record::csv::CsvSink::new(out_dir)), 1),
            Sink::Vtu => r.push(
                Box::new(
                    record::vtu::VtuSink::with_format(out_dir, scene.output.vtu_format)
                        .with_compression(scene.output.vtu_compression),
                ),
                every,
            ),
            Sink::Mcap => r.push(Box::new(record::mcap::McapSink::new(out_dir)), every),
            Sink::Png => r.push(Box::new(record::png::PngSink::new(out_dir)), every),
            #[cfg(feature = "rerun")]
            Sink::Rerun => r.push(Box::new(record::rrd::RrdSink::new(out_dir)), every),
            #[cfg(not(feature = "rerun"))]
            Sink::Rerun => warnings.push(
                "output sink \"rerun\" skipped: this build has no `rerun` feature".to_string(),
            ),
        }
    }
    // The increment status file is always written (one short line per increment).
    r.push(Box::new(record::sta::StaSink::new(out_dir)), 1);
    if !quiet {
        r.push(Box::new(record::progress::Progress::new()), 1);
    }
    (r, warnings)
}

/// Material law and pressure treatment of a scene.
pub fn build_material(scene: &Scene) -> Result<(Material, PressureMode), AppError> {
    build_material_spec(&scene.material)
}

/// Material law and pressure treatment of one `[material]` (or `[[material]]` entry).
pub fn build_material_spec(
    spec: &crate::io::scene::MaterialSpec,
) -> Result<(Material, PressureMode), AppError> {
    let material = spec.params().ok_or_else(|| {
        AppError::Unsupported(
            "material: a parameter required by `material.model` is missing".into(),
        )
    })?;
    if !material.is_incompressible() {
        return Ok((material, PressureMode::None));
    }
    // The unconstrained W is not stress free at F = I; the reference pressure p0 makes it so.
    let p0 = 0.5 * material.stress(&Mat2::zeros()).trace();
    let mode = match (spec.resolved_formulation(), spec.perturbed_kappa()) {
        (Some(Formulation::Perturbed), Some(kappa)) => PressureMode::Perturbed { kappa, p0 },
        _ => PressureMode::Exact { p0 },
    };
    Ok((material, mode))
}

/// Build the solid system (mesh, material, dofs, pattern) of a scene.
pub fn build_system(scene: &Scene) -> Result<SolidSystem, AppError> {
    let model = build_model(scene)?;
    if scene.analysis.mode == Mode::Static {
        let contact = build_contact(scene, &model)?;
        return Ok(SolidSystem::with_contact(model, contact));
    }
    Ok(SolidSystem::new(model, "hub"))
}

/// The road contact of a scene (`[road]`, `[contact]`, `[friction]`).
pub fn build_contact(scene: &Scene, model: &SolidModel) -> Result<ContactModel, AppError> {
    let (Some(road), Some(cs)) = (&scene.road, &scene.contact) else {
        return Err(AppError::Unsupported(format!(
            "mode \"{}\" needs the [road] and [contact] sections",
            scene.analysis.mode
        )));
    };
    let clamp = match cs.clamp {
        ClampKind::Hard => Clamp::Hard,
        ClampKind::Smooth => Clamp::Smooth {
            width: cs.clamp_width.unwrap_or_else(|| {
                DEFAULT_CLAMP_WIDTH_OVER_G * model.material.small_strain_shear_modulus()
            }),
        },
    };
    let (normal, friction, rule) = contact_laws(scene, clamp)?;
    let ro = scene.geometry.ro;
    // Load control starts with a small penetration (1e-3 Ro) so that the road-height equation
    // has a non-zero tangent; displacement control starts at first touch (H = Ro).
    let (h0, load) = match road.load {
        Some(_) => (ro * (1.0 - 1e-3), Some(0.0)),
        None => (ro, None),
    };
    Ok(ContactModel::new(
        &model.mesh,
        h0,
        road.v0,
        normal,
        friction,
        rule,
        load,
    ))
}

/// The normal compliance (with `clamp`), friction law and facet rule of a scene's `[contact]`
/// and `[friction]`.
fn contact_laws(
    scene: &Scene,
    clamp: Clamp,
) -> Result<(NormalCompliance, crate::contact::Friction, FacetRule), AppError> {
    let Some(cs) = &scene.contact else {
        return Err(AppError::Unsupported(format!(
            "mode \"{}\" needs the [road] and [contact] sections",
            scene.analysis.mode
        )));
    };
    let normal = NormalCompliance::new(cs.c_n, cs.m_n, cs.b_n, cs.l_n).with_clamp(clamp);
    let Some(friction) = scene.friction.params() else {
        return Err(AppError::Unsupported(
            "friction: a parameter required by `friction.law` is missing".into(),
        ));
    };
    let rule = match cs.quadrature {
        ContactQuadrature::Gauss => FacetRule::Gauss(cs.points),
        ContactQuadrature::Lobatto => FacetRule::Lobatto(cs.points),
    };
    Ok((normal, friction, rule))
}

/// Mesh, material and solid model of a scene.
pub fn build_model(scene: &Scene) -> Result<SolidModel, AppError> {
    let ms = &scene.mesh;
    let (material, pressure) = build_material(scene)?;
    if !matches!(pressure, PressureMode::None) && ms.order != 2 {
        return Err(AppError::Unsupported(format!(
            "mesh.order = {}: incompressible materials need order = 2 (Q2 displacements with P1 pressures)",
            ms.order
        )));
    }
    if let Some(file) = &ms.file {
        let mut model = build_model_from_file(scene, file, material, pressure)?;
        attach_viscoelastic(scene, &mut model)?;
        return Ok(model);
    }
    let mut mesh = annulus(&annulus_spec(scene));
    // Isoparametric cells: nodes on the exact circles, rigid motions represented exactly
    // (objectivity; see `Mesh::make_isoparametric`).
    mesh.make_isoparametric();
    let mut model = SolidModel::new(mesh, material, scene.material.rho, pressure);
    attach_viscoelastic(scene, &mut model)?;
    Ok(model)
}

/// The generated annulus of the scene's `[geometry]` and `[mesh]`.
pub fn annulus_spec(scene: &Scene) -> AnnulusSpec {
    let ms = &scene.mesh;
    AnnulusSpec {
        ri: scene.geometry.ri,
        ro: scene.geometry.ro,
        n_r: ms.n_r,
        n_theta: ms.n_theta,
        degree: ms.order,
        grading_r: ms.grading_r,
        grading_theta: ms.grading_theta,
    }
}

/// The scene's `[material.viscoelastic]` overstress on `model` (history at every quadrature
/// point), after checking that the mode carries a history.
pub fn attach_viscoelastic(scene: &Scene, model: &mut SolidModel) -> Result<(), AppError> {
    if let Some(vs) = &scene.material.viscoelastic {
        let ve = vs
            .build()
            .map_err(|e| AppError::Unsupported(format!("material.viscoelastic: {e}")))?;
        check_viscoelastic_mode(scene)?;
        model.set_viscoelastic(ve);
    }
    Ok(())
}

/// The modes and integrators that carry a viscoelastic history so far: the transient mode with
/// an integrator that carries it (history committed per accepted step) and the steady mode
/// (internal variables integrated along the streamlines, see `physics::viscoelastic_steady`).
/// The static and spinning modes would need the relaxed limit.
fn check_viscoelastic_mode(scene: &Scene) -> Result<(), AppError> {
    if !matches!(scene.analysis.mode, Mode::Transient | Mode::Steady) {
        return Err(AppError::Unsupported(format!(
            "material.viscoelastic: mode \"{}\" does not support viscoelastic materials yet \
             (use mode = \"transient\" or \"steady\")",
            scene.analysis.mode
        )));
    }
    if let (Some(ts), Mode::Transient) = (&scene.time, scene.analysis.mode) {
        if !ts.integrator.carries_history() {
            return Err(AppError::Unsupported(format!(
                "material.viscoelastic: time.integrator = \"{}\" does not carry a \
                 viscoelastic history; use {}",
                ts.integrator,
                crate::io::scene::IntegratorName::quoted_with(|i| i.carries_history())
            )));
        }
    }
    Ok(())
}

/// The model of a scene whose mesh is a Gmsh file (`[mesh] file`), with a material per region
/// when the scene has `[[material]]`.
fn build_model_from_file(
    scene: &Scene,
    file: &str,
    material: Material,
    pressure: PressureMode,
) -> Result<SolidModel, AppError> {
    use crate::io::scene::{DEFAULT_CONTACT_GROUP, DEFAULT_HUB_GROUP};
    use crate::mesh::gmsh::{read_msh, GmshGroups, MeshError};
    let ms = &scene.mesh;
    let groups = GmshGroups {
        hub: ms.hub.clone().unwrap_or_else(|| DEFAULT_HUB_GROUP.into()),
        contact: ms
            .contact
            .clone()
            .unwrap_or_else(|| DEFAULT_CONTACT_GROUP.into()),
        regions: scene.regions.iter().map(|r| r.region.clone()).collect(),
    };
    let bad = |message: String| {
        AppError::MeshFile(MeshError {
            file: std::path::absolute(file)
                .map_or_else(|_| file.to_string(), |p| p.display().to_string()),
            message,
        })
    };
    let mesh = read_msh(Path::new(file), &groups).map_err(AppError::MeshFile)?;
    if !matches!(pressure, PressureMode::None) && mesh.degree.iter().any(|&p| p != 2) {
        return Err(bad(
            "incompressible materials need 9-node quadrilaterals (Q2 displacements with P1 \
             pressures); the file has 4-node ones"
                .into(),
        ));
    }
    // The road is placed from geometry.ro (first touch at H = ro): the mesh must reach it.
    let ro = mesh.outer_radius();
    let ro_scene = scene.geometry.ro;
    if (ro - ro_scene).abs() > 1e-6 * ro_scene.abs().max(f64::MIN_POSITIVE) {
        return Err(bad(format!(
            "the mesh's outer radius (largest |X| of a node) is {ro}, but geometry.ro = {ro_scene}"
        )));
    }
    let mut model = SolidModel::new(mesh, material, scene.material.rho, pressure);
    if !scene.regions.is_empty() {
        let mut regions = Vec::new();
        for r in &scene.regions {
            let (m, p) = build_material_spec(&r.material)?;
            let p0 = match p {
                PressureMode::Exact { p0 } | PressureMode::Perturbed { p0, .. } => p0,
                PressureMode::None => 0.0,
            };
            regions.push(crate::physics::solid::RegionMaterial {
                material: m,
                rho: r.material.rho,
                p0,
            });
        }
        model.set_region_materials(regions);
    }
    Ok(model)
}

/// Linear solver for a scene's system: Cholesky for symmetric positive problems, LU for the
/// exact incompressible saddle point and whenever friction or damping makes the tangent
/// unsymmetric.
pub fn linear_kind(scene: &Scene, sys: &SolidSystem) -> LinearKind {
    match scene.solver.linear {
        LinearChoice::Cholesky => LinearKind::Cholesky,
        LinearChoice::Lu => LinearKind::Lu,
        LinearChoice::Auto => {
            let friction = sys
                .contact
                .as_ref()
                .is_some_and(|c| c.friction.is_active() || c.normal.has_damping());
            if matches!(sys.model.pressure, PressureMode::Exact { .. }) || friction {
                LinearKind::Lu
            } else {
                LinearKind::Cholesky
            }
        }
    }
}

/// The road of a scene: its load (load control) or its penetration (displacement control), as
/// the load factor's target in static indentation and in the steady press.
pub fn scene_loading(scene: &Scene) -> Loading {
    match scene.road.as_ref().and_then(|r| r.load) {
        Some(load) => Loading::Load { load },
        None => Loading::Indent {
            h_touch: scene.geometry.ro,
            disp: scene.road.as_ref().and_then(|r| r.disp).unwrap_or(0.0),
        },
    }
}

/// The run's solve plan for `sys`: [`linear_kind`] and [`solver_options`] (progress lines
/// off; [`SolvePlan::verbose`] turns them on).
pub fn solve_plan(scene: &Scene, sys: &SolidSystem) -> SolvePlan {
    let (newton, steps) = solver_options(scene, false);
    SolvePlan {
        kind: linear_kind(scene, sys),
        newton,
        steps,
    }
}

/// Newton and load-stepping options from the scene's `[solver]`.
pub fn solver_options(scene: &Scene, verbose: bool) -> (NewtonOptions, StepOptions) {
    let newton_opts = NewtonOptions {
        tol: scene.solver.tolerance,
        max_iterations: scene.solver.max_iterations,
        line_search: scene.solver.line_search,
        verbose,
        mixed_precision: scene.solver.single_precision,
        single_precision_preconditioner: scene.solver.single_precision,
        ..Default::default()
    };
    let step_opts = StepOptions {
        initial_steps: scene.solver.load_steps,
        max_cutbacks: scene.solver.max_cutbacks,
        verbose,
    };
    (newton_opts, step_opts)
}

// ---------------------------------------------------------------------------------------------
// Three dimensions (`mesh.dimension = 3`)
// ---------------------------------------------------------------------------------------------

/// Material law and pressure treatment of a three-dimensional scene: as [`build_material`],
/// with the reference pressure p0 = tr P(F = I) / 3 of the 3 × 3 law (the unconstrained W of
/// an incompressible law is not stress free at F = I; by isotropy it equals the plane-strain
/// program's tr P / 2).
pub fn build_material_3d(scene: &Scene) -> Result<(Material, PressureMode), AppError> {
    let (material, mode) = build_material(scene)?;
    let p0 = <Material as Hyperelastic<crate::math::Mat3>>::stress(
        &material,
        &crate::math::Mat3::zeros(),
    )
    .trace()
        / 3.0;
    let mode = match mode {
        PressureMode::None => PressureMode::None,
        PressureMode::Exact { .. } => PressureMode::Exact { p0 },
        PressureMode::Perturbed { kappa, .. } => PressureMode::Perturbed { kappa, p0 },
    };
    Ok((material, mode))
}

/// The hexahedral mesh of a three-dimensional scene: the annulus of `[geometry]` and `[mesh]`
/// revolved about the axle (`width`, `n_z`, `crown_radius`; isoparametric cells, as the
/// plane-strain program's), or the hexahedra of `mesh.file` (node and facet sets `hub` and
/// `outer` from the groups `mesh.hub` and `mesh.contact`), whose largest distance of a node
/// from the axle must be `geometry.ro` (the road is placed from it).
pub fn build_hex_mesh(scene: &Scene) -> Result<HexMesh, AppError> {
    use crate::io::scene::{DEFAULT_CONTACT_GROUP, DEFAULT_HUB_GROUP};
    use crate::mesh::gmsh::{GmshGroups, MeshError};
    let ms = &scene.mesh;
    let (_, pressure) = build_material_3d(scene)?;
    let incompressible = !matches!(pressure, PressureMode::None);
    if let Some(file) = &ms.file {
        let groups = GmshGroups {
            hub: ms.hub.clone().unwrap_or_else(|| DEFAULT_HUB_GROUP.into()),
            contact: ms
                .contact
                .clone()
                .unwrap_or_else(|| DEFAULT_CONTACT_GROUP.into()),
            regions: Vec::new(),
        };
        let mesh = crate::mesh::gmsh3d::read_msh_hex(Path::new(file), &groups)
            .map_err(AppError::MeshFile)?;
        let bad = |message: String| {
            AppError::MeshFile(MeshError {
                file: std::path::absolute(file)
                    .map_or_else(|_| file.to_string(), |p| p.display().to_string()),
                message,
            })
        };
        if incompressible && mesh.degree.iter().any(|&p| p != 2) {
            return Err(bad(
                "incompressible materials need 27-node hexahedra (Q2 displacements with P1 \
                 pressures); the file has 8-node ones"
                    .into(),
            ));
        }
        let ro = mesh
            .nodes
            .iter()
            .map(|x| x[0].hypot(x[1]))
            .fold(0.0, f64::max);
        let ro_scene = scene.geometry.ro;
        if (ro - ro_scene).abs() > 1e-6 * ro_scene.abs().max(f64::MIN_POSITIVE) {
            return Err(bad(format!(
                "the mesh's outer radius (largest distance of a node from the axle x3) is {ro}, \
                 but geometry.ro = {ro_scene}"
            )));
        }
        return Ok(mesh);
    }
    if incompressible && ms.order != 2 {
        return Err(AppError::Unsupported(format!(
            "mesh.order = {}: incompressible materials need order = 2 (Q2 displacements with P1 pressures)",
            ms.order
        )));
    }
    let spec = RevolvedSpec {
        ri: scene.geometry.ri,
        ro: scene.geometry.ro,
        width: ms.width.unwrap_or(f64::NAN),
        n_r: ms.n_r,
        n_z: ms.resolved_n_z(),
        n_theta: ms.n_theta,
        degree: ms.order,
        grading_r: ms.grading_r,
        grading_theta: ms.grading_theta,
        theta_ratio: ms.theta_ratio.unwrap_or(1.0),
        grading_z: ms.grading_z.unwrap_or(1.0),
        half_width: false,
        crown_radius: ms.crown_radius,
    };
    let mut mesh = revolved(&spec).map_err(|e| {
        let section = if matches!(e.key, "ri" | "ro") {
            "geometry"
        } else {
            "mesh"
        };
        let key = if e.key == "degree" { "order" } else { e.key };
        AppError::Unsupported(format!("{section}.{key} = {}: {}", e.value, e.reason))
    })?;
    mesh.make_isoparametric();
    Ok(mesh)
}

/// The fixed displacement components of a three-dimensional scene's mesh: every component of
/// the hub nodes; with `mesh.sides = "sliding"` u3 on both flat faces too.
pub fn fixed_dofs_3d(scene: &Scene, mesh: &HexMesh) -> Vec<bool> {
    let mut f = vec![false; 3 * mesh.n_nodes()];
    for &n in mesh.node_set("hub") {
        f[3 * n as usize..3 * n as usize + 3].fill(true);
    }
    if scene.mesh.resolved_sides() == MeshSides::Sliding {
        for set in ["side_neg", "side_pos"] {
            for &n in mesh.node_set(set) {
                f[3 * n as usize + 2] = true;
            }
        }
    }
    f
}

/// The road contact of a three-dimensional static scene on the tread facets (`outer`):
/// under load control (`road.load`, a total force) H starts at ro (1 − 10⁻³) as in the
/// plane-strain program, under displacement control at first touch.
pub fn build_contact_3d(scene: &Scene, mesh: &HexMesh) -> Result<ContactSurface3D, AppError> {
    let (Some(road), Some(cs)) = (&scene.road, &scene.contact) else {
        return Err(AppError::Unsupported(format!(
            "mode \"{}\" needs the [road] and [contact] sections",
            scene.analysis.mode
        )));
    };
    let (material, _) = build_material_3d(scene)?;
    let clamp = match cs.clamp {
        ClampKind::Hard => Clamp::Hard,
        ClampKind::Smooth => Clamp::Smooth {
            width: cs.clamp_width.unwrap_or_else(|| {
                DEFAULT_CLAMP_WIDTH_OVER_G * material.small_strain_shear_modulus()
            }),
        },
    };
    let (normal, friction, rule) = contact_laws(scene, clamp)?;
    let facets = mesh.facet_set("outer").to_vec();
    if facets.is_empty() {
        return Err(AppError::Unsupported(
            "mesh: the three-dimensional mesh has no contact facets (mesh.contact)".into(),
        ));
    }
    let mut surface = ContactSurface3D::new(
        facets,
        scene.geometry.ro,
        nalgebra::Vector2::new(road.v0, 0.0),
        normal,
        friction,
        rule,
    )
    .map_err(|e| AppError::Unsupported(format!("contact: {e}")))?;
    surface
        .set_camber(road.camber.to_radians())
        .map_err(|e| AppError::Unsupported(format!("road.camber: {e}")))?;
    Ok(surface)
}

/// The road height H of first touch: `geometry.ro` without camber, else the largest
/// −n·X over the tread facets' nodes (the lowest node relative to the cambered road).
fn first_touch_3d(scene: &Scene, mesh: &HexMesh, surface: &ContactSurface3D) -> f64 {
    let camber = scene.road.as_ref().map_or(0.0, |r| r.camber);
    if camber == 0.0 {
        return scene.geometry.ro;
    }
    surface.first_touch(mesh)
}

/// The three-dimensional solid system of a scene: the solid on [`build_hex_mesh`] with
/// [`fixed_dofs_3d`], and in the static and steady modes the road contact under load control
/// (`road.load`) or displacement control (`road.disp`). The road height of first touch is
/// `geometry.ro`. In the steady mode the body rolls at `motion.omega` on the road moving at
/// `road.v0` turned by `road.slip_angle` ([`Solid3DSystem::set_steady_rolling`]).
pub fn build_system_3d(scene: &Scene) -> Result<Solid3DSystem, AppError> {
    let mesh = build_hex_mesh(scene)?;
    let (material, pressure) = build_material_3d(scene)?;
    let fixed = fixed_dofs_3d(scene, &mesh);
    let steady = scene.analysis.mode == Mode::Steady;
    let contact = match scene.analysis.mode {
        Mode::Static => Some(build_contact_3d(scene, &mesh)?),
        // The road turns the body when there is one; without, the hub spins it freely.
        Mode::Transient => (scene.road.is_some() && scene.contact.is_some())
            .then(|| build_contact_3d(scene, &mesh))
            .transpose()?,
        Mode::Spinning | Mode::Steady => {
            // The θ-referential inertia −ω² ∫ ρ ∂θχ · ∂θη is the centrifugal load only on
            // closed circumferential lines: on a sector its boundary terms on the cut faces
            // are missing.
            if let Some(x) = mesh.circumferential_cut() {
                return Err(AppError::Unsupported(format!(
                    "mesh.file: the mesh does not close around the axle (the boundary face at \
                     ({:.4}, {:.4}, {:.4}) faces the circumferential direction); the spinning \
                     mode needs the body meshed all the way round",
                    x[0], x[1], x[2]
                )));
            }
            steady.then(|| build_contact_3d(scene, &mesh)).transpose()?
        }
        m => {
            return Err(AppError::Unsupported(format!(
                "analysis.mode: mode \"{m}\" does not run in three dimensions yet"
            )))
        }
    };
    let ro = contact
        .as_ref()
        .map_or(scene.geometry.ro, |s| first_touch_3d(scene, &mesh, s));
    let mut solid = Solid3D::new(mesh, material, scene.material.rho, pressure);
    if let Some(vs) = &scene.material.viscoelastic {
        let ve = vs
            .build()
            .map_err(|e| AppError::Unsupported(format!("material.viscoelastic: {e}")))?;
        check_viscoelastic_mode(scene)?;
        if steady && scene.solver.steady_history == SteadyHistoryChoice::Upwind {
            return Err(AppError::Unsupported(
                "solver.steady_history = \"upwind\": not offered with mesh.dimension = 3 (the \
                 three-dimensional steady mode integrates the history along the rings of \
                 quadrature points; use \"auto\" or \"rings\")"
                    .into(),
            ));
        }
        solid.set_viscoelastic(ve);
    }
    let sys = Solid3DSystem::new(solid, &fixed);
    let Some(surface) = contact else {
        return Ok(sys);
    };
    let road = scene.road.as_ref();
    let sys = match road.and_then(|r| r.load) {
        Some(load) => sys.with_contact_load(surface, ro, ro * (1.0 - 1e-3), load),
        None => sys.with_contact(surface, ro, road.and_then(|r| r.disp).unwrap_or(0.0)),
    };
    let mut sys = sys.map_err(|e| AppError::Unsupported(format!("contact: {e}")))?;
    if steady {
        let (v0, alpha) = road.map_or((0.0, 0.0), |r| (r.v0, r.slip_angle.to_radians()));
        sys.set_steady_rolling(scene.motion.omega, v0, alpha)
            .map_err(|e| AppError::Unsupported(format!("motion: {e}")))?;
        let eta = scene.time.as_ref().map_or(0.0, |t| t.strain_rate_damping);
        if eta > 0.0 {
            sys.enable_steady_viscosity(eta)
                .map_err(|e| AppError::Unsupported(format!("time.strain_rate_damping: {e}")))?;
        }
        if sys.solid.viscoelastic.is_some() {
            sys.enable_steady_history()
                .map_err(|e| AppError::Unsupported(format!("material.viscoelastic: {e}")))?;
        }
    }
    if scene.analysis.mode == Mode::Transient {
        // The road starts at rest; the transient driver ramps its speed.
        let alpha = road.map_or(0.0, |r| r.slip_angle.to_radians());
        sys.set_transient(0.0, alpha)
            .map_err(|e| AppError::Unsupported(format!("road.slip_angle: {e}")))?;
    }
    Ok(sys)
}

pub use crate::model::system3d::road_velocity_3d;

/// The arc-length continuation's options of `[continuation]` `cs` from the parameter value
/// `start` and the norm `u_norm` of the start's displacements (the arc-length scales:
/// ‖Δu‖ / u_norm and Δλ / |target − start|), both modes and dimensions alike.
pub fn continuation_options(
    scene: &Scene,
    cs: &ContinuationSpec,
    start: f64,
    u_norm: f64,
    verbose: bool,
) -> ContinuationOptions {
    ContinuationOptions {
        target: cs.target,
        direction: if cs.target >= start { 1.0 } else { -1.0 },
        ds0: cs.ds,
        ds_min: cs.ds * 1e-4,
        ds_max: cs.ds_max,
        x_scale: u_norm.max(1e-12 * scene.geometry.ro),
        lambda_scale: (cs.target - start).abs().max(f64::MIN_POSITIVE),
        max_steps: cs.max_steps,
        max_iterations: scene.solver.max_iterations.min(15),
        desired_iterations: cs.desired_iterations,
        max_cutbacks: scene.solver.max_cutbacks,
        tol: scene.solver.tolerance,
        test_function: true,
        switch_branch: cs.switch_branch,
        stop_at_limit: cs.on_limit == LimitAction::Jump,
        verbose,
    }
}

/// Linear solver of a three-dimensional system: as [`linear_kind`] (LU for the exact
/// incompressible saddle point and with friction).
pub fn linear_kind_3d(scene: &Scene, sys: &Solid3DSystem) -> LinearKind {
    match scene.solver.linear {
        LinearChoice::Cholesky => LinearKind::Cholesky,
        LinearChoice::Lu => LinearKind::Lu,
        LinearChoice::Auto => {
            let friction = sys
                .contact
                .as_ref()
                .is_some_and(|c| c.surface.friction.is_active());
            if matches!(sys.solid.pressure, PressureMode::Exact { .. }) || friction {
                LinearKind::Lu
            } else {
                LinearKind::Cholesky
            }
        }
    }
}
