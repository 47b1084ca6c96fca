//! Scene files: the TOML description of one run.
//!
//! A scene describes a plane-strain hollow cylinder `ri <= |X| <= ro` bonded to a rigid hub at
//! `|X| = ri`, its mesh, its material, what to compute and how to solve it. Units are whatever the
//! scene uses consistently (the paper's case: inch, psi, lbf·s²/in⁴, rad/s); `[scene] units` only
//! records which. Forces are per unit thickness.
//!
//! The schema, key by key (kind, default, unit, meaning), is the table in `schema.rs`;
//! `docs/reference.md` is generated from it (`tread schema --markdown`), and `tread schema` prints
//! it as a JSON Schema for editors. One file per section holds its serde struct, keyword enums
//! and range checks (`geometry.rs` for `[scene]` and `[geometry]`, `mesh.rs`, `material.rs`,
//! `motion.rs`, `contact.rs` for `[road]` and `[contact]`, `friction.rs`, `stick_slip.rs`,
//! `time.rs`, `steady.rs` for `[continuation]`, `solver.rs`, `output.rs`, `analysis.rs`);
//! `load.rs` applies overrides and the schema pass, `spans.rs` locates keys, `errors.rs` holds
//! the error types and `issue.rs` the unlocated problems that the section checks report. The
//! files import one way: sections from `issue.rs` and earlier sections, `schema.rs` from the
//! sections, `load.rs` from `schema.rs`, and this file from all of them.
//! In short:
//!
//! ```toml
//! [scene]     name, description = "", units = "in-lbf-s"
//! [geometry]  ri, ro
//! [mesh]      n_r = 4, n_theta = 32, order = 2, grading_r = 1.0, grading_theta = 0.0
//!             | file = "tyre.msh", hub = "hub", contact = "contact"   (a Gmsh .msh 4.1 mesh)
//! [material]  model (a registered law), rho, and the law's parameters (e.g. neo_hookean: mu,
//!             lambda); an incompressible law also formulation = "exact" | "perturbed", kappa.
//!             `docs/reference.md` and `tread check` list every law with its keys
//! [material.viscoelastic]  model = "convolution" | "multiplicative", gamma, prony = [[g, tau], ...]
//!             (optional: a Prony-series overstress on the elastic law; `gamma` in stress
//!             units, `g` dimensionless, `tau` in time units; see `material::viscoelastic`)
//! [[material]] region = "<2D physical group of mesh.file>", then the keys of [material]
//!             (one per region; instead of a single [material])
//! [analysis]  mode = "spinning" | "static" | "stick_slip" | "transient"
//! [motion]    omega, ramp = 0                                 (spinning, transient)
//!             control = "speed" | "torque", hub_inertia, torque = 0   (transient)
//!             control = "speed" | "torque" | "free_rolling" | "creep", torque, creep (steady)
//! [road]      disp | load, v0 = 0, ramp = 0, v0_ramp = motion.ramp   (static, transient)
//! [contact]   c_n, m_n = 1, b_n = 0, l_n = 0, quadrature = "lobatto", points = 4
//!                                                             (static, transient)
//! [friction]  law = "none" or a registered law, and its parameters (e.g. coulomb_tanh: mu,
//!             eps; every law with its keys in `docs/reference.md`)  (static, stick_slip, transient)
//! [stick_slip] mass, stiffness, normal_force, belt_speed, t_end, rtol = 1e-8, atol = 1e-10,
//!             x0 = 0, v0, output_interval                     (stick_slip)
//! [time]      integrator = "generalized_alpha" | "central_difference" | "bdf" | "sdirk",
//!             rho_inf = 0.8, dt, dt_min = dt·1e-4, dt_max = dt·10, t_end, adaptive = true,
//!             error_tol = 1e-4, steady_tol = 1e-4, stop_at_steady = true,
//!             mass = "consistent" | "lumped", max_steps = 200000  (transient)
//! [solver]    tolerance = 1e-10, max_iterations = 25, load_steps = 4, max_cutbacks = 10,
//!             linear = "auto", threads = 0, line_search = true
//! [output]    sinks = ["summary", "csv", "vtu", "png"], every = 1, vtu_format = "binary" | "ascii",
//!             vtu_compression = "none" | "zlib" (binary only),
//!             displacement_scale = 1 (magnification of the body in the Rerun view)
//!             (sinks from "summary", "csv", "vtu", "mcap", "rerun", "png")
//! ```
//!
//! # Loading
//!
//! [`Scene::from_toml_str`] parses the text, applies `--set section.key=value` (or `section.table.key=value`) overrides, fills the
//! defaults, resolves model-dependent defaults (the incompressible formulation and, for the
//! perturbed Lagrangian, `kappa = 1e4 G/2`, i.e. `1e4 (c1 + c2)` for Mooney–Rivlin; `time.mass = "lumped"` for the
//! `central_difference` integrator) and validates. It collects **all** problems it can
//! find (unknown sections and keys, wrong types, missing required keys, out-of-range values, keys
//! that do not belong to the chosen material model) and returns them together as [`SceneErrors`],
//! each naming the dotted key (`geometry.ri`) and the line of the original file where the key (or,
//! for a missing key, its section header) is written. A value that came from an override is reported
//! as `(--set)` instead of a line. Only a TOML syntax error stops early (nothing else can be checked
//! then); it carries toml's own line.
//!
//! Pipeline: (1) `toml` parses the original text into a table (syntax errors, with toml's span);
//! (2) overrides are applied to that table; (3) a schema pass checks every section and key
//! (known? right type? required ones present?), collecting every problem and dropping the
//! offending entries; (4) each section is deserialized with serde (`deny_unknown_fields`
//! everywhere, so the typed structs are strict on their own too, e.g. for
//! `toml::from_str::<Scene>`); (5) the typed sections are validated (ranges and cross-key rules).
//! Line numbers come from the byte spans that the `toml` parser gives for every key of the
//! original text (`spans`), so a key that was *not* overridden always reports its line in the
//! file.
//!
//! Which sections a mode uses: `spinning` uses `[motion]`; `static` requires `[road]` and
//! `[contact]` and may have `[friction]`; `stick_slip` requires `[stick_slip]` and a `[friction]`
//! law of `coulomb_tanh`, `coulomb_linear` or `rate_dependent`; `transient` requires `[time]` and
//! `motion.omega`, and may have `[road]` with `[contact]` (both or neither; without them the
//! cylinder spins up in time without contact) and, only with contact, `[friction]`. A section (or a
//! non-zero `motion.omega`, `motion.ramp`, `road.v0`, `road.ramp`, `road.v0_ramp`, `contact.b_n`,
//! or a friction law other than `none`) that the mode does not use is an error rather than being
//! silently ignored. `[geometry]` and `[material]` are required in every mode; a `stick_slip`
//! scene carries nominal values that the mode does not use. A `transient` scene that stops at the
//! steady state (`time.stop_at_steady`) needs a mesh uniform in θ (`mesh.grading_theta = 0`): the
//! steady-state extraction re-indexes nodes by whole nodal angle steps.
//!
//! # Time (transient mode)
//!
//! Time starts at `t = 0` with the cylinder at rest, undeformed, and the road (if any) at first
//! touch (`H = Ro`). The hub angular speed, the road penetration (or load) and the road speed are
//! brought in by C² ramps `f(t) = S(t / ramp)` with the quintic smoothstep
//! `S(s) = 6s⁵ − 15s⁴ + 10s³` on `[0, 1]` (`S = 0` before, `1` after; `S′ = S″ = 0` at both
//! ends; a zero ramp applies the full value at once): `ω(t) = omega·S(t / motion.ramp)`,
//! `DISP(t) = disp·S(t / road.ramp)` (or the load), `v0(t) = v0·S(t / road.v0_ramp)`. See
//! [`smoothstep`], [`Motion::omega_at`], [`Motion::angle_at`], [`RoadSpec::ramp_factor`] and
//! [`RoadSpec::v0_at`]. The run stops at `time.t_end`, after `time.max_steps` steps, or, with
//! `time.stop_at_steady`, once rolling is steady: the referential field, the hub forces and the
//! torque change by less than `steady_tol` (relative) over one node passage. In `transient`,
//! `[solver]` drives the Newton iterations of each implicit time step (`tolerance`,
//! `max_iterations`, `linear`, `threads`, `line_search`); a step whose Newton iteration fails is
//! retried with half the step, at most `max_cutbacks` times and not below `time.dt_min`;
//! `load_steps` is not used (the ramps apply the loads in time).
//!
//! # Contact and friction conventions
//!
//! The road is the line `x2 = −H`; penetration `δ = (−H − x2)_+`; normal traction (per unit
//! *reference* length of the outer boundary) `t_n = c_n δ^m_n + b_n δ^l_n δ̇`, `δ̇ = −ẋ2`, clamped
//! at `t_n >= 0`, pushing the body in +x2. Slip velocity of the body against the road
//! `w = ẋ1 − v0`; tangential traction `t_T = −μ(|w|) t_n φ_ε(w)` with `φ_ε(w) = tanh(w/ε)` or
//! `clamp(w/ε, −1, 1)`. In a static analysis there is no time: `w = dx1/dτ` in the pseudo-time
//! `τ ∈ [0, 1]` of the load stepping, so `eps` (and `v_s`) are then slip *lengths* over the whole
//! loading.
//!
//! [`Scene::to_toml_string`] writes the resolved scene (every default filled), which parses back
//! to the same [`Scene`]; `tread check` prints it. Optional keys whose defaults follow other keys
//! (`time.dt_min`, `time.dt_max`, `road.v0_ramp`, `stick_slip.v0`, `stick_slip.output_interval`)
//! stay unset when not given; methods give the values (`resolved_*`, `initial_velocity`).

use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::path::Path;

use issue::{issue, issue_near, table_has, Issue};
pub(crate) use schema::cell;
pub use schema::{json_schema, markdown_reference};
use spans::Locator;

// ---------------------------------------------------------------------------------------------
// Keyword enums
// ---------------------------------------------------------------------------------------------

macro_rules! keyword_enum {
    (
        $(#[$meta:meta])*
        $name:ident, $what:literal {
            $( $(#[$vmeta:meta])* $variant:ident => $text:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, ::serde::Serialize, ::serde::Deserialize)]
        #[serde(rename_all = "snake_case")]
        pub enum $name {
            $( $(#[$vmeta])* $variant ),+
        }

        impl $name {
            /// Every variant, in declaration order.
            pub const ALL: &'static [$name] = &[$($name::$variant),+];
            /// The spelling of every variant in a scene file, in declaration order.
            pub const NAMES: &'static [&'static str] = &[$($text),+];

            /// The spelling of this variant in a scene file.
            pub fn as_str(self) -> &'static str {
                match self {
                    $($name::$variant => $text),+
                }
            }
        }

        impl ::std::fmt::Display for $name {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.as_str())
            }
        }

        impl ::std::str::FromStr for $name {
            type Err = String;

            fn from_str(s: &str) -> Result<Self, String> {
                match s.trim() {
                    $($text => Ok($name::$variant),)+
                    other => Err(format!(
                        "unknown {} \"{}\"; expected one of {}",
                        $what,
                        other,
                        $crate::io::scene::issue::quoted_list(Self::NAMES)
                    )),
                }
            }
        }
    };
}

mod analysis;
mod contact;
mod errors;
mod friction;
mod geometry;
mod issue;
mod load;
mod material;
mod mesh;
pub mod model_problem;
mod motion;
mod output;
mod schema;
mod solver;
mod spans;
mod steady;
mod stick_slip;
mod time;

pub use analysis::*;
pub use contact::*;
pub use errors::*;
pub use friction::*;
pub use geometry::*;
use load::*;
pub use material::*;
pub use mesh::*;
pub use motion::*;
pub use output::*;
pub use solver::*;
pub use steady::*;
pub use stick_slip::*;
pub use time::*;

/// One scene file, resolved: every default filled.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    pub scene: SceneInfo,
    pub geometry: Geometry,
    #[serde(default)]
    pub mesh: MeshSpec,
    pub material: MaterialSpec,
    pub analysis: Analysis,
    #[serde(default)]
    pub motion: Motion,
    /// `[road]`: required for `static`; optional for `transient` (with `[contact]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub road: Option<RoadSpec>,
    /// `[contact]`: required for `static`; optional for `transient` (with `[road]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactSpec>,
    /// `[friction]`: law `none` when absent.
    #[serde(default)]
    pub friction: FrictionSpec,
    /// `[stick_slip]`: required for `stick_slip`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stick_slip: Option<StickSlipSpec>,
    /// `[time]`: required for `transient`, allowed (unused) in `steady`, forbidden otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time: Option<TimeSpec>,
    /// `[continuation]`: optional, `steady` only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub continuation: Option<ContinuationSpec>,
    #[serde(default)]
    pub solver: SolverSpec,
    #[serde(default)]
    pub output: OutputSpec,
    /// `[[material]]`: one material per mesh region (a 2D physical group of `mesh.file`), in the
    /// file's order. Empty for a scene with a single `[material]`; otherwise `material` holds the
    /// first region's material (for scales such as the shear wave speed).
    #[serde(skip)]
    pub regions: Vec<RegionMaterial>,
}

impl Scene {
    /// Parse, apply `--set key=value` overrides (dotted keys like `"mesh.n_r=8"`; the value is
    /// parsed as a TOML value, falling back to a bare string; for string-valued keys the raw text
    /// is taken as the string unless it is a quoted TOML string), fill defaults, validate.
    /// Collects all errors, not just the first.
    pub fn from_toml_str(
        text: &str,
        source_name: &str,
        overrides: &[String],
    ) -> Result<Scene, SceneErrors> {
        let locator = Locator::new(text);
        let mut ctx = Ctx {
            source_name,
            locator: &locator,
            overridden: BTreeSet::new(),
            issues: Vec::new(),
            region_elements: Vec::new(),
        };

        let mut doc: toml::Table = match text.parse::<toml::Table>() {
            Ok(t) => t,
            Err(e) => {
                let line = e
                    .span()
                    .map(|s| spans::LineIndex::new(text).line_of(s.start));
                let key = line
                    .and_then(|l| {
                        locator
                            .key_at_line(l)
                            .or_else(|| spans::key_written_at(text, l))
                    })
                    .unwrap_or_default();
                return Err(SceneErrors(vec![SceneError {
                    key,
                    line,
                    message: format!("TOML syntax error: {}", e.message().trim_end()),
                    source_name: source_name.to_string(),
                }]));
            }
        };

        ctx.apply_overrides(&mut doc, overrides);
        // `[[material]]`: the first entry goes through the `[material]` path (its errors name
        // `material.<key>`), the others are checked here (`material[<region>].<key>`).
        let region_tables = ctx.take_region_materials(&mut doc);
        let clean = ctx.check_schema(&doc);

        let info: Option<SceneInfo> = ctx.required_section(&clean, "scene");
        let geometry: Option<Geometry> = ctx.required_section(&clean, "geometry");
        let mesh: Option<MeshSpec> = ctx.optional_section(&clean, "mesh");
        let material: Option<MaterialSpec> = ctx.required_section(&clean, "material");
        let analysis: Option<Analysis> = ctx.required_section(&clean, "analysis");
        let motion: Option<Motion> = ctx.optional_section(&clean, "motion");
        let road: Option<Option<RoadSpec>> = ctx.present_section(&clean, "road");
        let contact: Option<Option<ContactSpec>> = ctx.present_section(&clean, "contact");
        let friction: Option<FrictionSpec> = ctx.optional_section(&clean, "friction");
        let stick_slip: Option<Option<StickSlipSpec>> = ctx.present_section(&clean, "stick_slip");
        let time: Option<Option<TimeSpec>> = ctx.present_section(&clean, "time");
        let continuation: Option<Option<ContinuationSpec>> =
            ctx.present_section(&clean, "continuation");
        let solver: Option<SolverSpec> = ctx.optional_section(&clean, "solver");
        let output: Option<OutputSpec> = ctx.optional_section(&clean, "output");

        let mut out = Vec::new();
        let mut regions = ctx.region_materials(&region_tables, &mut out);
        if let Some(m) = &mesh {
            validate_mesh_file(m, &region_tables, &doc, &mut out);
        }
        if let Some(s) = &info {
            validate_info(s, &mut out);
        }
        if let Some(g) = &geometry {
            validate_geometry(g, &mut out);
        }
        if let Some(m) = &mesh {
            validate_mesh(m, &mut out);
        }
        if let Some(m) = &material {
            validate_material(m, &mut out);
        }
        let mode = analysis.as_ref().map(|a| a.mode);
        if let Some(m) = &motion {
            let omega_given = table_has(&doc, "motion", "omega");
            let omega_bad = !table_has(&clean, "motion", "omega") && omega_given;
            if !omega_bad {
                validate_motion(mode, m, omega_given, &mut out);
            }
            validate_motion_ramp(mode, m, &mut out);
            let integrator = match &time {
                Some(Some(t)) => Some(t.integrator),
                _ => None,
            };
            // An unknown or ill-typed `control` was dropped (and reported): the other keys
            // cannot be checked against it.
            let control_bad =
                table_has(&doc, "motion", "control") && !table_has(&clean, "motion", "control");
            if !control_bad {
                validate_motion_control(mode, m, integrator, &mut out);
            }
        }
        if let Some(Some(r)) = &road {
            validate_road(r, mode, geometry.as_ref(), &mut out);
        }
        if let Some(Some(c)) = &contact {
            validate_contact(c, mode, &mut out);
        }
        // An unknown or ill-typed `law` was dropped (and reported): the remaining keys cannot
        // be checked against a law, and the mode cannot be checked against it.
        let law_bad = table_has(&doc, "friction", "law") && !table_has(&clean, "friction", "law");
        let friction_law = match (&friction, law_bad) {
            (Some(f), false) => {
                validate_friction(f, &mut out);
                Some(f.law)
            }
            _ => None,
        };
        if let Some(Some(s)) = &stick_slip {
            validate_stick_slip(s, &mut out);
        }
        // An explicitly written `mass` (valid or not) counts as given.
        let time_mass_given = table_has(&doc, "time", "mass");
        if let Some(Some(t)) = &time {
            validate_time(t, time_mass_given, mode == Some(Mode::Steady), &mut out);
        }
        if let Some(Some(c)) = &continuation {
            validate_continuation(
                c,
                mode,
                road.as_ref().and_then(|r| r.as_ref()),
                motion.as_ref().map(|m| m.control),
                &mut out,
            );
        }
        if let Some(mode) = mode {
            let used = SectionsGiven {
                road: doc.contains_key("road"),
                contact: doc.contains_key("contact"),
                stick_slip: doc.contains_key("stick_slip"),
                time: doc.contains_key("time"),
                continuation: doc.contains_key("continuation"),
                friction_law,
            };
            validate_mode_sections(mode, &used, &mut out);
        }
        if let (Some(m), Some(Some(t))) = (&mesh, &time) {
            if m.file.is_none() {
                validate_steady_extraction(mode, m, t, &mut out);
            }
        }
        if let Some(s) = &solver {
            validate_solver(s, &mut out);
        }
        if let Some(o) = &output {
            validate_output(o, &mut out);
        }
        if let Some(m) = &mesh {
            let cx = Dimension3DContext {
                mode,
                has_regions: !region_tables.is_empty(),
                doc: Some(&doc),
                lobatto_points: lobatto_points(contact.as_ref().and_then(|c| c.as_ref())),
            };
            validate_dimension(m, &cx, &mut out);
            if m.is_3d() && table_has(&doc, "output", "sinks") {
                if let Some(o) = &output {
                    validate_output_3d(o, &mut out);
                }
            }
        }
        // A key already reported by the schema pass (unknown or ill-typed) is not reported again
        // (e.g. as "required" because its ill-typed value was dropped).
        let reported: BTreeSet<String> = ctx.issues.iter().map(|i| i.key.clone()).collect();
        ctx.issues
            .extend(out.into_iter().filter(|i| !reported.contains(&i.key)));

        if !ctx.issues.is_empty() {
            return Err(ctx.into_errors());
        }
        let (
            Some(scene),
            Some(geometry),
            Some(mesh),
            Some(mut material),
            Some(analysis),
            Some(motion),
            Some(road),
            Some(contact),
            Some(friction),
            Some(stick_slip),
            Some(mut time),
            Some(continuation),
            Some(solver),
            Some(output),
        ) = (
            info,
            geometry,
            mesh,
            material,
            analysis,
            motion,
            road,
            contact,
            friction,
            stick_slip,
            time,
            continuation,
            solver,
            output,
        )
        else {
            // Unreachable in practice: every `None` above records an issue.
            return Err(SceneErrors(vec![SceneError {
                key: String::new(),
                line: None,
                message: "scene is incomplete".to_string(),
                source_name: source_name.to_string(),
            }]));
        };
        material.resolve();
        if let (Some(first), Some((name, _))) = (regions.first_mut(), region_tables.first()) {
            // The first region's material is `material` itself.
            *first = RegionMaterial {
                region: name.clone(),
                material: material.clone(),
            };
        }
        if let Some(t) = time.as_mut() {
            if !time_mass_given {
                t.mass = t.effective_mass();
            }
        }
        Ok(Scene {
            scene,
            geometry,
            mesh,
            material,
            analysis,
            motion,
            road,
            contact,
            friction,
            stick_slip,
            time,
            continuation,
            solver,
            output,
            regions,
        })
    }

    /// Read a scene file and load it with [`Scene::from_toml_str`]; the path names the source.
    pub fn from_path(path: &Path, overrides: &[String]) -> Result<Scene, SceneErrors> {
        let name = path.display().to_string();
        match std::fs::read_to_string(path) {
            Ok(text) => Scene::from_toml_str(&text, &name, overrides).map(|mut s| {
                s.resolve_paths(path);
                s
            }),
            Err(e) => Err(SceneErrors(vec![SceneError {
                key: String::new(),
                line: None,
                message: format!("cannot read scene file: {e}"),
                source_name: name,
            }])),
        }
    }

    /// Make a relative `mesh.file` relative to the scene file at `scene_path` (as read from disk).
    pub fn resolve_paths(&mut self, scene_path: &Path) {
        if let (Some(f), Some(dir)) = (&self.mesh.file, scene_path.parent()) {
            if Path::new(f).is_relative() && !dir.as_os_str().is_empty() {
                self.mesh.file = Some(dir.join(f).display().to_string());
            }
        }
    }

    /// Validate a scene built in code (ranges, model keys). Errors carry no line numbers; the
    /// source is named `<scene>`.
    pub fn validate(&self) -> Result<(), SceneErrors> {
        let mut out = Vec::new();
        validate_info(&self.scene, &mut out);
        validate_geometry(&self.geometry, &mut out);
        validate_mesh(&self.mesh, &mut out);
        validate_dimension(
            &self.mesh,
            &Dimension3DContext {
                mode: Some(self.analysis.mode),
                has_regions: !self.regions.is_empty(),
                doc: None,
                lobatto_points: lobatto_points(self.contact.as_ref()),
            },
            &mut out,
        );
        validate_material(&self.material, &mut out);
        let mode = Some(self.analysis.mode);
        validate_motion(mode, &self.motion, true, &mut out);
        validate_motion_ramp(mode, &self.motion, &mut out);
        validate_motion_control(
            mode,
            &self.motion,
            self.time.as_ref().map(|t| t.integrator),
            &mut out,
        );
        if let Some(r) = &self.road {
            validate_road(r, mode, Some(&self.geometry), &mut out);
        }
        if let Some(c) = &self.contact {
            validate_contact(c, mode, &mut out);
        }
        validate_friction(&self.friction, &mut out);
        if let Some(s) = &self.stick_slip {
            validate_stick_slip(s, &mut out);
        }
        if let Some(t) = &self.time {
            validate_time(t, true, mode == Some(Mode::Steady), &mut out);
            validate_steady_extraction(mode, &self.mesh, t, &mut out);
        }
        if let Some(c) = &self.continuation {
            validate_continuation(
                c,
                mode,
                self.road.as_ref(),
                Some(self.motion.control),
                &mut out,
            );
        }
        let used = SectionsGiven {
            road: self.road.is_some(),
            contact: self.contact.is_some(),
            stick_slip: self.stick_slip.is_some(),
            time: self.time.is_some(),
            continuation: self.continuation.is_some(),
            friction_law: Some(self.friction.law),
        };
        validate_mode_sections(self.analysis.mode, &used, &mut out);
        validate_solver(&self.solver, &mut out);
        validate_output(&self.output, &mut out);
        if out.is_empty() {
            Ok(())
        } else {
            Err(SceneErrors(
                out.into_iter()
                    .map(|i| SceneError {
                        key: i.key,
                        line: None,
                        message: i.message,
                        source_name: "<scene>".to_string(),
                    })
                    .collect(),
            ))
        }
    }

    /// The resolved scene (defaults filled) as TOML, for `tread check`. Parses back to `self`.
    pub fn to_toml_string(&self) -> String {
        if !self.regions.is_empty() {
            return self.to_toml_string_regions();
        }
        if self.mesh.file.is_some() {
            let mut scene = self.clone();
            // Not written: the loader refuses them next to `mesh.file` (their defaults stand).
            scene.mesh = MeshSpec {
                file: self.mesh.file.clone(),
                hub: self.mesh.hub.clone(),
                contact: self.mesh.contact.clone(),
                dimension: self.mesh.dimension,
                ..MeshSpec::default()
            };
            return match toml::Table::try_from(&scene)
                .map(|t| toml::to_string_pretty(&self.drop_unused(t)))
            {
                Ok(Ok(s)) => s,
                Ok(Err(e)) | Err(e) => format!("# cannot write scene as TOML: {e}\n"),
            };
        }
        match toml::to_string_pretty(self) {
            Ok(s) => s,
            // Only possible for non-finite floats in a scene built in code.
            Err(e) => format!("# cannot write scene as TOML: {e}\n"),
        }
    }

    /// The resolved table without the keys the loader refuses in this scene: the generated
    /// annulus's `[mesh]` keys when the mesh comes from `mesh.file`.
    fn drop_unused(&self, mut t: toml::Table) -> toml::Table {
        if self.mesh.file.is_some() {
            if let Some(toml::Value::Table(m)) = t.get_mut("mesh") {
                for key in MeshSpec::GENERATOR_KEYS {
                    m.remove(*key);
                }
            }
        }
        t
    }

    /// [`Self::to_toml_string`] with every key's unit and meaning (from the scene schema) as a
    /// trailing comment: the listing of `tread check`. Parses back to `self` as well.
    pub fn to_annotated_toml_string(&self) -> String {
        schema::annotate(&self.to_toml_string())
    }

    /// [`Self::to_toml_string`] of a scene with `[[material]]` regions.
    fn to_toml_string_regions(&self) -> String {
        let table = toml::Table::try_from(self).and_then(|mut t| {
            let mut arr = Vec::new();
            for r in &self.regions {
                let mut m = toml::Table::try_from(&r.material)?;
                m.insert("region".into(), toml::Value::String(r.region.clone()));
                arr.push(toml::Value::Table(m));
            }
            t.insert("material".into(), toml::Value::Array(arr));
            Ok(self.drop_unused(t))
        });
        match table.map(|t| toml::to_string_pretty(&t)) {
            Ok(Ok(s)) => s,
            Ok(Err(e)) => format!("# cannot write scene as TOML: {e}\n"),
            Err(e) => format!("# cannot write scene as TOML: {e}\n"),
        }
    }

    /// The shear wave speed `sqrt(G / rho)` of the material, if defined.
    pub fn shear_wave_speed(&self) -> Option<f64> {
        let g = self.material.shear_modulus()?;
        let rho = self.material.rho;
        (g > 0.0 && rho > 0.0).then(|| (g / rho).sqrt())
    }
}

/// Which mode-dependent sections a scene has; `friction_law` is `None` when it cannot be
/// checked (an invalid `law` already reported).
struct SectionsGiven {
    road: bool,
    contact: bool,
    stick_slip: bool,
    time: bool,
    continuation: bool,
    friction_law: Option<FrictionLawName>,
}

/// `"a", "b" or "c"`.
/// `contact.points` when `contact.quadrature` is Lobatto.
fn lobatto_points(c: Option<&ContactSpec>) -> Option<usize> {
    c.filter(|c| c.quadrature == ContactQuadrature::Lobatto)
        .map(|c| c.points)
}

/// The sinks a three-dimensional run writes: all of them (`png`: the footprint maps of the
/// contact patch).
fn validate_output_3d(_o: &OutputSpec, _out: &mut Vec<Issue>) {}

fn or_list(names: &[&str]) -> String {
    let quoted: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
    match quoted.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        Some((last, _)) => last.clone(),
        None => String::new(),
    }
}

fn validate_mode_sections(mode: Mode, given: &SectionsGiven, out: &mut Vec<Issue>) {
    const ROAD_MODES: &str = "\"static\" and \"transient\"";
    let unused = |section: &str, used_by: &str, out: &mut Vec<Issue>| {
        out.push(issue(
            section,
            format!(
                "section [{section}] is not used by analysis mode \"{mode}\" (only by \
                 {used_by}); remove it"
            ),
        ));
    };
    let missing = |section: &str, needs: &str, out: &mut Vec<Issue>| {
        out.push(issue_near(
            section,
            format!(
                "required section [{section}] is missing: analysis mode \"{mode}\" needs it \
                 ({needs})"
            ),
            "analysis.mode",
        ));
    };
    // A law whose argument only the steady mode supplies (the elastic slip).
    if let Some(law) = given.friction_law.filter(|l| l.steady_only()) {
        if !matches!(mode, Mode::Steady | Mode::Spinning | Mode::StickSlip) {
            out.push(issue_near(
                "friction.law",
                format!(
                    "friction law \"{law}\" marches the elastic slip along the streamlines of \
                     steady rolling and is available in analysis mode \"steady\" only, not \
                     \"{mode}\"; use coulomb_tanh or coulomb_linear (a slip-velocity law)"
                ),
                "analysis.mode",
            ));
        }
    }
    let no_contact_friction = |law: FrictionLawName, what: &str, out: &mut Vec<Issue>| {
        out.push(issue(
            "friction.law",
            format!(
                "analysis mode \"{mode}\" {what}, hence no friction: law must be \"none\" (or \
                 omit [friction]), got \"{law}\""
            ),
        ));
    };
    if given.continuation && mode != Mode::Steady {
        unused("continuation", "\"steady\"", out);
    }
    if given.time && !matches!(mode, Mode::Transient | Mode::Steady) {
        let note = if mode == Mode::StickSlip {
            "; the oscillator's t_end and tolerances are in [stick_slip]"
        } else {
            ""
        };
        unused("time", &format!("\"transient\"{note}"), out);
    }
    match mode {
        Mode::Spinning => {
            if given.road {
                unused("road", ROAD_MODES, out);
            }
            if given.contact {
                unused("contact", ROAD_MODES, out);
            }
            if given.stick_slip {
                unused("stick_slip", "\"stick_slip\"", out);
            }
            if let Some(law) = given.friction_law.filter(|l| *l != FrictionLawName::None) {
                no_contact_friction(law, "has no road contact", out);
            }
        }
        Mode::Static => {
            if !given.road {
                missing("road", "disp or load", out);
            }
            if !given.contact {
                missing("contact", "c_n", out);
            }
            if given.stick_slip {
                unused("stick_slip", "\"stick_slip\"", out);
            }
        }
        Mode::StickSlip => {
            if given.road {
                unused("road", ROAD_MODES, out);
            }
            if given.contact {
                unused("contact", ROAD_MODES, out);
            }
            if !given.stick_slip {
                missing(
                    "stick_slip",
                    "mass, stiffness, normal_force, belt_speed, t_end",
                    out,
                );
            }
            match given.friction_law {
                Some(law) if !stick_slip_law(law) => out.push(issue_near(
                    "friction.law",
                    format!(
                        "analysis mode \"stick_slip\" needs a friction law {} in [friction], got \
                         \"{law}\"{}",
                        or_list(&stick_slip_laws()),
                        if law.needs_penetration() {
                            format!(" ({law} needs a penetration, which this mode does not have)")
                        } else {
                            String::new()
                        }
                    ),
                    "analysis.mode",
                )),
                _ => {}
            }
        }
        Mode::Transient | Mode::Steady => {
            if !given.time && mode == Mode::Transient {
                missing("time", "dt, t_end", out);
            }
            if given.stick_slip {
                unused("stick_slip", "\"stick_slip\"", out);
            }
            // Road contact needs both the road and the contact law; neither = no contact.
            match (given.road, given.contact) {
                (true, false) => out.push(issue_near(
                    "contact",
                    format!(
                        "analysis mode \"{mode}\" has [road] but no [contact]: give both \
                         (rolling on the road) or neither (spinning up without contact); \
                         [contact] needs c_n"
                    ),
                    "road",
                )),
                (false, true) => out.push(issue_near(
                    "road",
                    format!(
                        "analysis mode \"{mode}\" has [contact] but no [road]: give both \
                         (rolling on the road) or neither (spinning up without contact); [road] \
                         needs disp or load"
                    ),
                    "contact",
                )),
                _ => {}
            }
            if !given.road && !given.contact {
                if let Some(law) = given.friction_law.filter(|l| *l != FrictionLawName::None) {
                    no_contact_friction(
                        law,
                        "without [road] and [contact] has no road contact",
                        out,
                    );
                }
            }
        }
    }
}

#[cfg(test)]
mod tests;

/// The 1-based line of a dotted key (`mesh.file`) in a scene's text, or of its nearest enclosing
/// section when the key itself is not written there; `None` when neither is.
pub fn key_line(text: &str, dotted: &str) -> Option<usize> {
    spans::Locator::new(text).locate(dotted)
}
