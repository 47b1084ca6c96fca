//! Rerun sink: `run.rrd` for the Rerun viewer (`rerun run.rrd`). Behind the default cargo
//! feature `rerun`.
//!
//! Timelines: `step` (sequence: the accepted-step index) and, for a time-stepping run, `sim_time`
//! (duration: simulated seconds). A load-stepping run (`RunMeta::time_name` = `load_factor`:
//! static, spinning, steady) has `step` only, and λ is the series `series/load_factor` (Rerun has
//! no float timeline; λ as a duration would read "+990 ms"). On an ω-continuation branch also
//! `omega` (duration: the hub speed in rad/s counted as seconds), so the deformed body and its
//! stresses can be scrubbed by speed; the wall-clock `log_time`/`log_tick` timelines are off, so
//! a file depends only on the run. The recording is named `<scene> (<mode> mode)`. Entities:
//!
//! | entity | archetype | content |
//! |---|---|---|
//! | `scene` | TextDocument (static) | the resolved scene TOML and the build |
//! | `body/mesh` | Mesh3D | the deformed mesh (z = 0), vertex colours = in-plane max shear stress (viridis, 0 … frame max); the reference configuration (u = 0, the initial state of every mode) at `sim_time` 0, or at `step` −1 in load stepping |
//! | `body/colour_scale` | Mesh3D + Points3D labels (`body/colour_scale/labels`) | the colour scale of the mesh beside the body: viridis from 0 (bottom) to the frame's maximum τ (top), labelled with values and unit in light text right of the bar ([`rrd_draw::colour_scale`]) |
//! | `body/boundary` | LineStrips3D | inner and outer boundary loops |
//! | `road` | LineStrips3D | the road line x2 = −H (magnified with the body, see below) |
//! | `contact/points` | Points3D | facet points of the outer boundary in contact, coloured by t_n |
//! | `contact/traction` | Arrows3D | traction vectors (t_T, t_n) at those points (scaled to 0.2 Ro at the peak) |
//! | `contact/chart/pressure/*`, `contact/chart/shear/*` | LineStrips2D, Points2D | charts of t_n and t_T against x1 for 2D views: frame, grid at round ticks over the patch, tick labels, the curve and a marker per contact point ([`rrd_draw::contact_chart`]) |
//! | `contact/curves/pressure`, `contact/curves/shear`, `contact/curves/axis`, `contact/curves/labels` | LineStrips3D, Points3D labels | t_n and t_T drawn as curves against x1 below the road and the body (one scale for both, peak = 0.3 Ro; the labels give the peak values and the x1 range) |
//! | `hub/force_x`, `hub/force_y`, `hub/torque` | Scalars | hub loads |
//! | `energy/strain`, `energy/kinetic`, `energy/total` | Scalars | energies |
//! | `series/<name>` | Scalars | the other series of the view (contact resultants, patch, stress max, model scalars) |
//! | `newton/iterations` | Scalars | Newton iterations of every step |
//! | `newton/residual`, `newton/log10_residual` | Scalars (drawn as dots) | every Newton iteration (max over fields of ‖R_f‖/‖R_f⁰‖, and its log10), also on the `newton_iteration` timeline |
//! | `series/load_factor` | Scalars | λ of every step (load stepping) |
//! | `branch/<name>` | Scalars | continuation points on the `branch_point` timeline; `branch/table` TextDocument at the end |
//! | `steady/mesh`, `steady/results` | Mesh3D, TextDocument | the steady state |
//! | `log` | TextLog | run start and end, rejected steps, interrupts |
//!
//! Every series is named with its unit (`F_x [lbf/in]`) from `[scene] units`. The recording
//! carries a default layout ([`super::rrd_layout`]): a head-on view of the body and separate
//! views for the hub loads, the Newton iterations, the Newton residuals, the energies and the
//! contact tractions. In load stepping every series has a marker at each step (a plain steady
//! solve has a single step).
//!
//! # Displacement magnification
//!
//! `[output] displacement_scale = k` (default 1) draws the body (mesh, boundary, colour-scale
//! position, contact points and traction arrows) at x = x_rigid + k (x − x_rigid), so that a
//! 0.1 in penetration on a 2 in radius can be seen (k = 10 or 20). x_rigid is the reference
//! position X turned by the hub angle φ when the model has one (the `phi` scalar of a transient
//! run: x_rigid = R(φ) X, so only the deformation is magnified, not the rotation), else X. Only
//! this view is magnified: every number (series, contact curves and bar charts, all other files)
//! is the computed one; the body view's name says `u ×k`. A contact point's X is taken on the
//! outer circle of radius Ro at its reference angle θ, and the road is drawn at
//! x2 = −Ro + k (Ro − H) (the undeformed bottom moved k times the penetration), so the magnified
//! body still meets it.

use super::png::Units;
use super::rrd_draw;
use super::rrd_layout::{self, series_label, LayoutPaths, LayoutSpec};
use super::{
    boundary_loops, colormap, display_triangles, ContinuationPoint, NewtonIteration, RecordError,
    Recorder, RejectedStep, RunEnd, RunMeta, SteadyReached, StepInfo, StepView,
};
use rerun::RecordingStream;
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

pub struct RrdSink {
    path: PathBuf,
    rec: Option<RecordingStream>,
    file: Option<RrdFile>,
    error: Option<RecordError>,
    triangles: Vec<[u32; 3]>,
    loops: Vec<Vec<u32>>,
    ro: f64,
    styled: BTreeSet<String>,
    newton_counter: i64,
    branch: Vec<String>,
    branch_header: Option<String>,
    units: Units,
    /// Lowest x2 of the body as last displayed (the contact curves are drawn below it).
    bottom: f64,
    /// Displacement magnification of the body view (`[output] displacement_scale`).
    magnification: f64,
    /// Load stepping (`RunMeta::time_name` = `load_factor`): the steps are on the `step`
    /// sequence only, λ is the series `series/load_factor`.
    load_stepping: bool,
}

/// An `.rrd` file encoded on the thread that logs (the recording stream's), not by the SDK's
/// file writer: a write error (a full disk) is kept and every later message dropped, so that a
/// run or a conversion never waits on a writer that stopped. [`RrdFile::finish`] writes the
/// footer and says whether the file is complete.
#[derive(Clone)]
pub struct RrdFile(std::sync::Arc<std::sync::Mutex<RrdFileState>>);

type RrdEncoder = rerun::external::re_log_encoding::Encoder<std::io::BufWriter<std::fs::File>>;

pub struct RrdFileState {
    enc: Option<RrdEncoder>,
    error: Option<String>,
}

impl RrdFileState {
    /// Stop writing after `e`: the encoder is taken apart without its drop (which would try to
    /// write the footer again).
    fn fail(&mut self, e: String) {
        if let Some(enc) = self.enc.take() {
            let _ = enc.into_inner();
        }
        self.error.get_or_insert(e);
    }
}

impl RrdFile {
    /// Create (truncate) `path` and write the stream header.
    pub fn create(path: &Path) -> Result<Self, String> {
        use rerun::external::re_build_info::CrateVersion;
        use rerun::external::re_log_encoding::EncodingOptions;
        let f = std::fs::File::create(path).map_err(|e| e.to_string())?;
        let enc = RrdEncoder::new_eager(
            CrateVersion::LOCAL,
            EncodingOptions::PROTOBUF_COMPRESSED,
            std::io::BufWriter::new(f),
        )
        .map_err(|e| e.to_string())?;
        Ok(Self(std::sync::Arc::new(std::sync::Mutex::new(
            RrdFileState {
                enc: Some(enc),
                error: None,
            },
        ))))
    }

    fn state(&self) -> std::sync::MutexGuard<'_, RrdFileState> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Write the footer, flush and sync: `Err` with the first write error when the file is not
    /// complete. Messages sent afterwards are dropped.
    pub fn finish(&self) -> Result<(), String> {
        let mut st = self.state();
        if let Some(mut enc) = st.enc.take() {
            let done = enc
                .finish()
                .map_err(|e| e.to_string())
                .and_then(|()| enc.into_inner().map_err(|e| e.to_string()))
                .and_then(|w| w.into_inner().map_err(|e| e.error().to_string()))
                .and_then(|f| f.sync_all().map_err(|e| e.to_string()));
            if let Err(e) = done {
                st.error.get_or_insert(e);
            }
        }
        match &st.error {
            Some(e) => Err(e.clone()),
            None => Ok(()),
        }
    }
}

impl rerun::sink::LogSink for RrdFile {
    fn send(&self, msg: rerun::log::LogMsg) {
        let mut st = self.state();
        let r = st.enc.as_mut().map(|enc| enc.append(&msg));
        if let Some(Err(e)) = r {
            st.fail(e.to_string());
        }
    }

    fn flush_blocking(
        &self,
        _timeout: std::time::Duration,
    ) -> Result<(), rerun::sink::SinkFlushError> {
        let mut st = self.state();
        let r = st.enc.as_mut().map(|enc| enc.flush_blocking());
        if let Some(Err(e)) = r {
            st.fail(e.to_string());
        }
        match &st.error {
            Some(e) => Err(rerun::sink::SinkFlushError::failed(e.clone())),
            None => Ok(()),
        }
    }
}

/// A recording stream from `builder` writing into `path` through an [`RrdFile`].
pub fn file_recording(
    builder: rerun::RecordingStreamBuilder,
    path: &Path,
) -> Result<(RecordingStream, RrdFile), String> {
    let file = RrdFile::create(path)?;
    let rec = builder.buffered().map_err(|e| e.to_string())?;
    rec.set_sink(Box::new(file.clone()));
    Ok((rec, file))
}

/// `[output] displacement_scale` of a resolved scene TOML (1 when absent or not a finite
/// positive number).
pub fn displacement_scale(scene_toml: &str) -> f64 {
    scene_toml
        .parse::<toml::Table>()
        .ok()
        .and_then(|t| {
            let v = t.get("output")?.get("displacement_scale")?;
            v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
        })
        .filter(|k| k.is_finite() && *k > 0.0)
        .unwrap_or(1.0)
}

/// `[scene] units` of a resolved scene TOML (the default units when absent).
pub fn scene_units(scene_toml: &str) -> Units {
    scene_toml
        .parse::<toml::Table>()
        .ok()
        .and_then(|t| t.get("scene")?.get("units")?.as_str().map(Units::parse))
        .unwrap_or_default()
}

/// x_rigid + k (x − x_rigid): the displayed position (module docs, displacement magnification).
fn magnify(k: f64, rigid: [f64; 2], x: [f64; 2]) -> [f32; 3] {
    [
        super::or_zero(rigid[0] + k * (x[0] - rigid[0])) as f32,
        super::or_zero(rigid[1] + k * (x[1] - rigid[1])) as f32,
        0.0,
    ]
}

/// R(φ) X.
fn rotate(phi: f64, p: [f64; 2]) -> [f64; 2] {
    let (s, c) = phi.sin_cos();
    [c * p[0] - s * p[1], s * p[0] + c * p[1]]
}

/// Entity path of a named series.
pub fn series_entity(name: &str) -> String {
    if let Some(r) = name.strip_prefix("hub_") {
        format!("hub/{r}")
    } else if let Some(r) = name.strip_prefix("energy_") {
        format!("energy/{r}")
    } else {
        format!("series/{name}")
    }
}

impl RrdSink {
    /// Writes `dir/run.rrd`.
    pub fn new(dir: &Path) -> Self {
        Self::with_path(dir.join("run.rrd"))
    }

    pub fn with_path(path: PathBuf) -> Self {
        Self {
            path,
            rec: None,
            file: None,
            error: None,
            triangles: Vec::new(),
            loops: Vec::new(),
            ro: 1.0,
            styled: BTreeSet::new(),
            newton_counter: 0,
            branch: Vec::new(),
            branch_header: None,
            units: Units::default(),
            bottom: f64::INFINITY,
            magnification: 1.0,
            load_stepping: false,
        }
    }

    fn check(&mut self, r: Result<(), rerun::RecordingStreamError>) {
        if let Err(e) = r {
            if self.error.is_none() {
                self.error = Some(RecordError::new("rerun", &self.path, e));
            }
        }
    }

    fn scalar(&mut self, entity: &str, name: &str, value: f64) {
        let Some(rec) = self.rec.clone() else { return };
        if !value.is_finite() {
            return;
        }
        if self.styled.insert(entity.to_string()) {
            let r = if entity.starts_with("newton/") && entity.ends_with("residual") {
                // One value per Newton iteration, several per step: dots, not a line through
                // every iteration of every step.
                rec.log_static(
                    entity,
                    &rerun::SeriesPoints::new()
                        .with_names([name])
                        .with_marker_sizes([1.5]),
                )
            } else if self.load_stepping {
                // Few load steps (a plain steady solve has one): a marker at each, so a single
                // step is seen.
                rec.log_static(entity, &rerun::SeriesLines::new().with_names([name]))
                    .and_then(|()| {
                        rec.log_static(
                            entity,
                            &rerun::SeriesPoints::new()
                                .with_names([name])
                                .with_marker_sizes([3.0]),
                        )
                    })
            } else {
                rec.log_static(entity, &rerun::SeriesLines::new().with_names([name]))
            };
            self.check(r);
        }
        let r = rec.log(entity, &rerun::Scalars::single(value));
        self.check(r);
    }

    fn text(&mut self, level: &str, text: &str) {
        let Some(rec) = self.rec.clone() else { return };
        let r = rec.log(
            "log",
            &rerun::TextLog::new(text).with_level(rerun::TextLogLevel::from(level)),
        );
        self.check(r);
    }

    /// Log the mesh of `entity` at the nodal positions `pos` (display coordinates) with stress
    /// measures `m` (empty: no stress, uniform colour), and its colour scale.
    fn log_mesh(&mut self, entity: &str, pos: &[[f32; 3]], m: &[f64]) {
        let Some(rec) = self.rec.clone() else { return };
        let mmax = m
            .iter()
            .copied()
            .filter(|x| x.is_finite())
            .fold(0.0, f64::max);
        let colors: Vec<rerun::Color> = (0..pos.len())
            .map(|n| {
                let t = m
                    .get(n)
                    .map_or(0.0, |x| if mmax > 0.0 { x / mmax } else { 0.0 });
                let c = colormap(t);
                rerun::Color::from_rgb(c[0], c[1], c[2])
            })
            .collect();
        let r = rec.log(
            format!("{entity}/mesh"),
            &rerun::Mesh3D::new(pos.to_vec())
                .with_triangle_indices(self.triangles.iter().copied())
                .with_vertex_colors(colors),
        );
        self.check(r);
        let strips: Vec<Vec<[f32; 3]>> = self
            .loops
            .iter()
            .map(|l| {
                l.iter()
                    .filter_map(|&n| pos.get(n as usize).copied())
                    .collect()
            })
            .collect();
        if !strips.is_empty() {
            let r = rec.log(
                format!("{entity}/boundary"),
                &rerun::LineStrips3D::new(strips).with_colors([rerun::Color::from_rgb(30, 30, 30)]),
            );
            self.check(r);
        }
        self.colour_scale(entity, mmax);
    }

    /// The colour scale of the mesh colours ([`rrd_draw::colour_scale`]).
    fn colour_scale(&mut self, entity: &str, max: f64) {
        let Some(rec) = self.rec.clone() else { return };
        let r = rrd_draw::colour_scale(&rec, entity, self.ro, max, &self.units);
        self.check(r);
    }

    /// The hub angle φ of a view (its `phi` scalar), 0 when it has none.
    fn hub_angle(v: &StepView) -> f64 {
        v.scalars
            .iter()
            .find(|(n, _)| *n == "phi")
            .map_or(0.0, |(_, p)| if p.is_finite() { *p } else { 0.0 })
    }

    fn mesh(&mut self, entity: &str, v: &StepView) {
        let (Some(_), Some(mesh)) = (self.rec.as_ref(), v.mesh) else {
            return;
        };
        let nn = mesh.n_nodes();
        let phi = Self::hub_angle(v);
        let k = self.magnification;
        let pos: Vec<[f32; 3]> = (0..nn)
            .map(|n| {
                let u = v.u(n);
                let xr = [mesh.nodes[n][0], mesh.nodes[n][1]];
                magnify(k, rotate(phi, xr), [xr[0] + u[0], xr[1] + u[1]])
            })
            .collect();
        let m: Vec<f64> = (0..v.stress.len()).map(|n| v.stress_measure(n)).collect();
        self.bottom = pos
            .iter()
            .map(|p| f64::from(p[1]))
            .fold(f64::INFINITY, f64::min);
        self.log_mesh(entity, &pos, &m);
    }

    /// Contact pressure and shear as curves against x1 below the road (in the body view) and as
    /// charts against x1 ([`rrd_draw::contact_charts`]).
    fn contact_curves(&mut self, patch: &[&crate::contact::ContactSample], road: Option<f64>) {
        let Some(rec) = self.rec.clone() else { return };
        let pts = rrd_draw::sorted_patch(patch.iter().map(|s| (s.x1, s.t_n, s.t_t)));
        let r = rrd_draw::contact_charts(
            &rec,
            "contact/chart/pressure",
            "contact/chart/shear",
            &pts,
            &self.units,
        );
        self.check(r);
        // Curves: baseline 0.1 Ro below the road and the body.
        let base = (-road.unwrap_or(self.ro)).min(self.bottom) - 0.1 * self.ro;
        let r = rrd_draw::contact_curves(&rec, "contact/curves", &pts, base, self.ro, &self.units);
        self.check(r);
    }

    fn write_view(&mut self, info: &StepInfo, v: &StepView) {
        let Some(rec) = self.rec.clone() else { return };
        self.mesh("body", v);
        // The road as displayed: magnified like the body about the undeformed bottom x2 = −Ro
        // (so a magnified penetration still meets it), at x2 = −H when k = 1.
        let road = v
            .road_height
            .map(|h| self.ro - self.magnification * (self.ro - h));
        if let Some(h) = road {
            let w = (1.5 * self.ro) as f32;
            let h = h as f32;
            let r = rec.log(
                "road",
                &rerun::LineStrips3D::new([[[-w, -h, 0.0], [w, -h, 0.0]]])
                    .with_colors([rerun::Color::from_rgb(140, 80, 30)]),
            );
            self.check(r);
        }
        let patch: Vec<_> = v
            .contact
            .iter()
            .filter(|s| s.t_n > 0.0 && s.x1.is_finite() && s.x2.is_finite())
            .collect();
        if !v.contact.is_empty() {
            let pmax = patch.iter().map(|s| s.t_n).fold(0.0, f64::max);
            let (k, phi, ro) = (self.magnification, Self::hub_angle(v), self.ro);
            let points: Vec<[f32; 3]> = patch
                .iter()
                .map(|s| {
                    let xr = rotate(phi, [ro * s.theta.cos(), ro * s.theta.sin()]);
                    magnify(k, xr, [s.x1, s.x2])
                })
                .collect();
            let colors: Vec<rerun::Color> = patch
                .iter()
                .map(|s| {
                    let c = colormap(if pmax > 0.0 { s.t_n / pmax } else { 0.0 });
                    rerun::Color::from_rgb(c[0], c[1], c[2])
                })
                .collect();
            let r = rec.log(
                "contact/points",
                &rerun::Points3D::new(points.clone()).with_colors(colors),
            );
            self.check(r);
            let t: Vec<(f64, f64)> = patch.iter().map(|s| (s.t_n, s.t_t)).collect();
            let r = rrd_draw::traction_arrows(&rec, "contact/traction", &points, &t, self.ro);
            self.check(r);
            self.contact_curves(&patch, road);
        }
        for (name, value) in v.series(info) {
            if name == "newton_iterations" {
                continue; // logged for every step in `step`
            }
            let label = series_label(&self.units, name);
            self.scalar(&series_entity(name), &label, value);
        }
    }

    /// The step's times: `step`, and `sim_time` (simulated seconds) unless load stepping.
    fn set_step_time(&self, index: u64, time: f64) {
        if let Some(rec) = &self.rec {
            rec.set_time_sequence("step", index as i64);
            if !self.load_stepping {
                rec.set_duration_secs("sim_time", super::or_zero(time));
            }
        }
    }
}

impl Recorder for RrdSink {
    fn run_started(&mut self, meta: &RunMeta) {
        // Named by scene and mode: the transient and steady recordings of one `tread compare`
        // are told apart in the viewer's recording list.
        let name = format!("{} ({} mode)", meta.scene_name, meta.mode);
        let builder = rerun::RecordingStreamBuilder::new("tread")
            .recording_name(name.as_str())
            .send_properties(false);
        let rec = match file_recording(builder, &self.path) {
            Ok((rec, file)) => {
                self.file = Some(file);
                rec
            }
            Err(e) => {
                self.error = Some(RecordError::new("rerun", &self.path, e));
                return;
            }
        };
        rec.set_log_time_enabled(false);
        rec.set_log_tick_enabled(false);
        // `send_properties(false)` (no wall-clock start time: reproducible files) drops the
        // builder's name too, so the name is sent on its own.
        let _ = rec.send_recording_name(name.as_str());
        self.rec = Some(rec.clone());
        self.units = scene_units(meta.scene_toml);
        self.magnification = displacement_scale(meta.scene_toml);
        self.load_stepping = meta.time_name == "load_factor";
        if let Some(mesh) = meta.mesh {
            self.triangles = display_triangles(mesh);
            self.loops = boundary_loops(mesh);
            self.ro = mesh
                .nodes
                .iter()
                .map(|p| p.norm())
                .fold(0.0, f64::max)
                .max(f64::MIN_POSITIVE);
        }
        let doc = format!(
            "# {} ({} mode)\n\ntread {} (features: {}); {}.\n\n```toml\n{}\n```\n",
            meta.scene_name,
            meta.mode,
            meta.version,
            if meta.features.is_empty() {
                "none"
            } else {
                meta.features
            },
            if self.load_stepping {
                "timeline `step`: the load step (the reference configuration at step −1); the \
                 load factor λ is the series `series/load_factor`"
            } else {
                "timelines `step` and `sim_time` (the simulated time)"
            },
            meta.scene_toml
        );
        let r = rec.log_static(
            "scene",
            &rerun::TextDocument::new(doc).with_media_type(rerun::MediaType::markdown()),
        );
        self.check(r);
        let spec = LayoutSpec {
            units: self.units.clone(),
            radius: self.ro,
            magnification: self.magnification,
            time_name: meta.time_name.to_string(),
            paths: LayoutPaths::run(),
        };
        let r = rrd_layout::send_layout(&rec, "tread", &spec);
        self.check(r);
        // The initial state, the reference configuration (u = 0, without stress): at sim_time 0
        // before the first step (so no `step` index), or at step −1 in load stepping.
        if self.load_stepping {
            rec.set_time_sequence("step", -1);
        } else {
            rec.disable_timeline("step");
            rec.set_duration_secs("sim_time", 0.0);
        }
        if let Some(mesh) = meta.mesh {
            let pos: Vec<[f32; 3]> = mesh
                .nodes
                .iter()
                .map(|p| [p[0] as f32, p[1] as f32, 0.0])
                .collect();
            self.log_mesh("body", &pos, &[]);
        }
        self.set_step_time(0, 0.0);
        self.text(
            "INFO",
            &format!("run started: {} ({} mode)", meta.scene_name, meta.mode),
        );
    }
    fn wants_view(&self, _info: &StepInfo) -> bool {
        self.rec.is_some()
    }
    fn step(&mut self, info: &StepInfo, view: Option<&StepView>) {
        if self.rec.is_none() {
            return;
        }
        self.set_step_time(info.index, info.time);
        self.scalar(
            "newton/iterations",
            "Newton iterations per step [iterations]",
            info.newton_iterations as f64,
        );
        if self.load_stepping {
            self.scalar("series/load_factor", "load factor λ [1]", info.time);
        }
        if let Some(v) = view {
            self.write_view(info, v);
        }
    }
    fn step_rejected(&mut self, s: &RejectedStep) {
        if self.rec.is_none() {
            return;
        }
        self.set_step_time(s.index, s.time);
        self.text(
            "WARN",
            &format!("step {} to {:.6e} rejected: {}", s.index, s.time, s.reason),
        );
    }
    fn newton_iteration(&mut self, it: &NewtonIteration) {
        let Some(rec) = self.rec.clone() else { return };
        self.set_step_time(it.step, it.time);
        rec.set_time_sequence("newton_iteration", self.newton_counter);
        self.newton_counter += 1;
        let res = it.residual_rel.iter().copied().fold(0.0, f64::max);
        self.scalar("newton/residual", "relative residual [1]", res);
        if res > 0.0 {
            self.scalar(
                "newton/log10_residual",
                "log10 relative residual [1]",
                res.log10(),
            );
        }
        rec.disable_timeline("newton_iteration");
    }
    fn continuation_point(&mut self, p: &ContinuationPoint) {
        let Some(rec) = self.rec.clone() else { return };
        if p.parameter_name == "omega" {
            // Kept set: the step that follows (the body at this point) is logged on it too.
            rec.set_duration_secs("omega", super::or_zero(p.parameter));
        }
        rec.set_time_sequence("branch_point", p.index as i64);
        self.scalar(
            &format!("branch/{}", p.parameter_name),
            p.parameter_name,
            p.parameter,
        );
        self.scalar("branch/arc_length", "arc length", p.arc_length);
        self.scalar("branch/det_sign", "sign of det K", f64::from(p.det_sign));
        for (n, v) in p.measures {
            self.scalar(&format!("branch/{n}"), n, *v);
        }
        rec.disable_timeline("branch_point");
        if self.branch_header.is_none() {
            let mut h = format!(
                "| point | {} | arc length | det sign | kind |",
                p.parameter_name
            );
            for (n, _) in p.measures {
                let _ = write!(h, " {n} |");
            }
            self.branch_header = Some(h);
        }
        let mut row = format!(
            "| {} | {:.6e} | {:.6e} | {} | {} |",
            p.index,
            p.parameter,
            p.arc_length,
            p.det_sign,
            p.kind.as_str()
        );
        for (_, v) in p.measures {
            let _ = write!(row, " {v:.6e} |");
        }
        self.branch.push(row);
    }
    fn steady_reached(&mut self, s: &SteadyReached, view: &StepView) {
        let Some(rec) = self.rec.clone() else { return };
        if !self.load_stepping {
            rec.set_duration_secs("sim_time", super::or_zero(s.time));
        }
        self.mesh("steady", view);
        let mut doc = format!(
            "# Steady state\n\ntime {:.6e}, change {:.3e}\n\n| result | value |\n|---|---|\n",
            s.time, s.change
        );
        for (n, v) in s.results {
            let _ = writeln!(doc, "| {n} | {v:.9e} |");
        }
        let r = rec.log(
            "steady/results",
            &rerun::TextDocument::new(doc).with_media_type(rerun::MediaType::markdown()),
        );
        self.check(r);
    }
    fn run_finished(&mut self, end: &RunEnd) -> Vec<RecordError> {
        if let Some(rec) = self.rec.clone() {
            if let (Some(h), false) = (&self.branch_header, self.branch.is_empty()) {
                let ncol = h.matches('|').count() - 1;
                let mut doc = format!("# Branch\n\n{h}\n|{}\n", "---|".repeat(ncol));
                for r in &self.branch {
                    doc.push_str(r);
                    doc.push('\n');
                }
                let r = rec.log_static(
                    "branch/table",
                    &rerun::TextDocument::new(doc).with_media_type(rerun::MediaType::markdown()),
                );
                self.check(r);
            }
            let text = match (end.interrupted, end.error) {
                (true, _) => format!("run interrupted after {} steps", end.steps),
                (false, Some(e)) => format!("run failed after {} steps: {e}", end.steps),
                (false, None) => format!("run finished: {} steps", end.steps),
            };
            self.text(if end.converged { "INFO" } else { "ERROR" }, &text);
            if let Err(e) = rec.flush_blocking() {
                self.error
                    .get_or_insert(RecordError::new("rerun", &self.path, e));
            }
        }
        self.rec = None;
        if let Some(file) = self.file.take() {
            if let Err(e) = file.finish() {
                self.error
                    .get_or_insert(RecordError::new("rerun", &self.path, e));
            }
        }
        self.error.take().into_iter().collect()
    }
}
