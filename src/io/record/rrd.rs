//! Rerun sink: `run.rrd` for the Rerun viewer (`rerun run.rrd`). Behind the default cargo
//! feature `rerun`.
//!
//! Timelines: `step` (sequence: the accepted-step index) and `sim_time` (duration: simulated
//! seconds, or the load factor λ counted as seconds in load stepping; on a continuation branch
//! the continuation parameter); on an ω-continuation branch also `omega` (duration: the hub
//! speed in rad/s counted as seconds), so the deformed body and its stresses can be scrubbed by
//! speed; the wall-clock
//! `log_time`/`log_tick` timelines are off, so a file depends only on the run. Entities:
//!
//! | entity | archetype | content |
//! |---|---|---|
//! | `scene` | TextDocument (static) | the resolved scene TOML and the build |
//! | `body/mesh` | Mesh3D | the deformed mesh (z = 0), vertex colours = in-plane max shear stress (viridis, 0 … frame max); the reference configuration (u = 0, the initial state of every mode) at `sim_time` 0 |
//! | `body/colour_scale` | Mesh3D + Points3D labels (`body/colour_scale/labels`) | the colour scale of the mesh beside the body: viridis from 0 (bottom) to the frame's maximum τ (top), labelled with values and unit |
//! | `body/boundary` | LineStrips3D | inner and outer boundary loops |
//! | `road` | LineStrips3D | the road line x2 = −H (magnified with the body, see below) |
//! | `contact/points` | Points3D | facet points of the outer boundary in contact, coloured by t_n |
//! | `contact/traction` | Arrows3D | traction vectors (t_T, t_n) at those points (scaled to 0.2 Ro at the peak) |
//! | `contact/pressure`, `contact/shear` | BarChart | t_n and t_T at the contact points (abscissa x1; each bar as wide as its point's share of the patch: half the distance to each neighbour) |
//! | `contact/curves/pressure`, `contact/curves/shear`, `contact/curves/axis`, `contact/curves/labels` | LineStrips3D, Points3D labels | t_n and t_T drawn as curves against x1 below the road and the body (one scale for both, peak = 0.3 Ro; the labels give the peak values and the x1 range) |
//! | `hub/force_x`, `hub/force_y`, `hub/torque` | Scalars | hub loads |
//! | `energy/strain`, `energy/kinetic`, `energy/total` | Scalars | energies |
//! | `series/<name>` | Scalars | the other series of the view (contact resultants, patch, stress max, model scalars) |
//! | `newton/iterations` | Scalars | Newton iterations of every step |
//! | `newton/residual`, `newton/log10_residual` | Scalars | every Newton iteration (max over fields of ‖R_f‖/‖R_f⁰‖, and its log10), also on the `newton_iteration` timeline |
//! | `branch/<name>` | Scalars | continuation points on the `branch_point` timeline; `branch/table` TextDocument at the end |
//! | `steady/mesh`, `steady/results` | Mesh3D, TextDocument | the steady state |
//! | `log` | TextLog | run start and end, rejected steps, interrupts |
//!
//! Every series is named with its unit (`F_x [lbf/in]`) from `[scene] units`. The recording
//! carries a default layout ([`super::rrd_layout`]): a head-on view of the body and separate
//! views for the hub loads, the Newton iterations, the energies and the contact tractions.
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

/// Widths of bars centred at the sorted abscissae `x`: half the distance to each neighbour
/// (the outer bars extend as far outwards as inwards), so the bars tile the patch. A point that
/// shares its abscissa with its only neighbour takes the width of the next bar, so no bar is
/// invisible.
pub fn bar_widths(x: &[f64]) -> Vec<f64> {
    let mut w = raw_bar_widths(x);
    for i in 0..w.len() {
        if w[i] <= 0.0 {
            let near = (1..w.len())
                .flat_map(|d| [i.checked_sub(d), Some(i + d)])
                .flatten()
                .filter_map(|j| w.get(j).copied())
                .find(|v| *v > 0.0);
            w[i] = near.unwrap_or(0.0);
        }
    }
    w
}

fn raw_bar_widths(x: &[f64]) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| {
            let left = if i > 0 { x[i] - x[i - 1] } else { f64::NAN };
            let right = if i + 1 < n { x[i + 1] - x[i] } else { f64::NAN };
            match (left.is_finite(), right.is_finite()) {
                (true, true) => 0.5 * (left + right),
                (true, false) => left,
                (false, true) => right,
                (false, false) => 0.0,
            }
        })
        .collect()
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
            let r = rec.log_static(entity, &rerun::SeriesLines::new().with_names([name]));
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

    /// The colour scale of the mesh colours: a vertical bar right of the body (x1 from 1.15 Ro to
    /// 1.25 Ro, x2 from −0.6 Ro to Ro) in the same piecewise-linear viridis as the mesh (its five
    /// stops are the bar's vertices, so the GPU's linear interpolation reproduces the map
    /// exactly), labelled 0 below and the maximum τ of the frame above.
    fn colour_scale(&mut self, entity: &str, max: f64) {
        let Some(rec) = self.rec.clone() else { return };
        let ro = self.ro as f32;
        let (x0, x1) = (1.15 * ro, 1.25 * ro);
        let y = |t: f32| -0.6 * ro + 1.6 * ro * t;
        let mut pos = Vec::with_capacity(10);
        let mut colors = Vec::with_capacity(10);
        for k in 0..5 {
            let t = k as f32 / 4.0;
            let c = colormap(f64::from(t));
            for x in [x0, x1] {
                pos.push([x, y(t), 0.0]);
                colors.push(rerun::Color::from_rgb(c[0], c[1], c[2]));
            }
        }
        let tris: Vec<[u32; 3]> = (0..4u32)
            .flat_map(|k| {
                let a = 2 * k;
                [[a, a + 1, a + 3], [a, a + 3, a + 2]]
            })
            .collect();
        let r = rec.log(
            format!("{entity}/colour_scale"),
            &rerun::Mesh3D::new(pos)
                .with_triangle_indices(tris)
                .with_vertex_colors(colors),
        );
        self.check(r);
        let unit = self.units.stress();
        let fmt =
            |v: f64| crate::io::output::fmt_num(if v.abs() > 0.0 { round_sig(v, 4) } else { 0.0 });
        let labels = [
            format!("τ = 0 {unit}"),
            format!("τ max = {} {unit}", fmt(max)),
        ];
        let xc = 0.5 * (x0 + x1);
        let r = rec.log(
            format!("{entity}/colour_scale/labels"),
            // Labels are drawn centred on their point: below and above the bar.
            &rerun::Points3D::new([[xc, y(0.0) - 0.08 * ro, 0.0], [xc, y(1.0) + 0.08 * ro, 0.0]])
                .with_radii([0.005 * ro])
                .with_colors([rerun::Color::from_rgb(30, 30, 30)])
                .with_labels(labels)
                .with_show_labels(true),
        );
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
    /// bar charts with their true widths.
    fn contact_curves(&mut self, patch: &[&crate::contact::ContactSample], road: Option<f64>) {
        let Some(rec) = self.rec.clone() else { return };
        let mut pts: Vec<(f64, f64, f64)> = patch
            .iter()
            .map(|s| (s.x1, s.t_n, super::or_zero(s.t_t)))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let x1: Vec<f64> = pts.iter().map(|p| p.0).collect();
        let tn: Vec<f64> = pts.iter().map(|p| p.1).collect();
        let tt: Vec<f64> = pts.iter().map(|p| p.2).collect();
        let w: Vec<f32> = bar_widths(&x1).into_iter().map(|w| w as f32).collect();
        let pressure_colour = rerun::Color::from_rgb(200, 60, 40);
        let shear_colour = rerun::Color::from_rgb(40, 90, 200);
        let r = rec.log(
            "contact/pressure",
            &rerun::BarChart::new(tn.clone())
                .with_abscissa(x1.clone())
                .with_widths(w.clone())
                .with_color(pressure_colour),
        );
        self.check(r);
        let r = rec.log(
            "contact/shear",
            &rerun::BarChart::new(tt.clone())
                .with_abscissa(x1.clone())
                .with_widths(w)
                .with_color(shear_colour),
        );
        self.check(r);
        // Curves: baseline 0.1 Ro below the road and the body, one scale for both (peak |t| =
        // 0.3 Ro).
        let ro = self.ro;
        let base = (-road.unwrap_or(ro)).min(self.bottom) - 0.1 * ro;
        let peak = tn
            .iter()
            .chain(&tt)
            .map(|t| t.abs())
            .filter(|t| t.is_finite())
            .fold(0.0, f64::max);
        let scale = if peak > 0.0 { 0.3 * ro / peak } else { 0.0 };
        let curve = |t: &[f64]| -> Vec<[f32; 3]> {
            x1.iter()
                .zip(t)
                .map(|(x, t)| [*x as f32, (base - scale * t) as f32, 0.0])
                .collect()
        };
        let unit = self.units.stress();
        let (pmax, tabs) = (
            tn.iter().copied().fold(0.0, f64::max),
            tt.iter().map(|t| t.abs()).fold(0.0, f64::max),
        );
        let r = rec.log(
            "contact/curves/pressure",
            &rerun::LineStrips3D::new([curve(&tn)]).with_colors([pressure_colour]),
        );
        self.check(r);
        let r = rec.log(
            "contact/curves/shear",
            &rerun::LineStrips3D::new([curve(&tt)]).with_colors([shear_colour]),
        );
        self.check(r);
        let (Some(&a), Some(&b)) = (x1.first(), x1.last()) else {
            return;
        };
        let r = rec.log(
            "contact/curves/axis",
            &rerun::LineStrips3D::new([[
                [a as f32, base as f32, 0.0],
                [b as f32, base as f32, 0.0],
            ]])
            .with_colors([rerun::Color::from_rgb(90, 90, 90)]),
        );
        self.check(r);
        // Labels apart from each other: t_n under its peak, t_T right of the patch, the axis
        // left of it (labels are drawn centred on their point).
        let fmt = |v: f64| crate::io::output::fmt_num(round_sig(v, 4));
        let kmax = (0..tn.len())
            .max_by(|&i, &j| tn[i].total_cmp(&tn[j]))
            .unwrap_or(0);
        let r = rec.log(
            "contact/curves/labels",
            &rerun::Points3D::new([
                [
                    x1[kmax] as f32,
                    (base - scale * tn[kmax] - 0.08 * ro) as f32,
                    0.0,
                ],
                [(b + 0.45 * ro) as f32, base as f32, 0.0],
                [(a - 0.45 * ro) as f32, base as f32, 0.0],
            ])
            .with_radii([0.004 * ro as f32])
            .with_colors([
                pressure_colour,
                shear_colour,
                rerun::Color::from_rgb(90, 90, 90),
            ])
            .with_labels([
                format!("t_n against x1, max {} {unit}", fmt(pmax)),
                format!("t_T, max |t_T| {} {unit}", fmt(tabs)),
                format!("x1 {} … {} {}", fmt(a), fmt(b), self.units.length),
            ])
            .with_show_labels(true),
        );
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
            let tmax = patch.iter().map(|s| s.t_n.hypot(s.t_t)).fold(0.0, f64::max);
            let scale = if tmax > 0.0 {
                0.2 * self.ro / tmax
            } else {
                0.0
            };
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
            let vectors: Vec<[f32; 3]> = patch
                .iter()
                .map(|s| [(s.t_t * scale) as f32, (s.t_n * scale) as f32, 0.0])
                .collect();
            let r = rec.log(
                "contact/traction",
                &rerun::Arrows3D::from_vectors(vectors).with_origins(points),
            );
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

    fn set_step_time(&self, index: u64, time: f64) {
        if let Some(rec) = &self.rec {
            rec.set_time_sequence("step", index as i64);
            rec.set_duration_secs("sim_time", super::or_zero(time));
        }
    }
}

impl Recorder for RrdSink {
    fn run_started(&mut self, meta: &RunMeta) {
        // Named by scene and mode: the transient and steady recordings of one `tread compare`
        // are told apart in the viewer's recording list.
        let name = format!("{} ({} mode)", meta.scene_name, meta.mode);
        let r = rerun::RecordingStreamBuilder::new("tread")
            .recording_name(name.as_str())
            .send_properties(false)
            .save(&self.path);
        let rec = match r {
            Ok(rec) => rec,
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
            "# {} ({} mode)\n\ntread {} (features: {}); `sim_time` is the {}.\n\n```toml\n{}\n```\n",
            meta.scene_name,
            meta.mode,
            meta.version,
            if meta.features.is_empty() { "none" } else { meta.features },
            if meta.time_name == "load_factor" {
                "load factor λ (counted as seconds)"
            } else {
                "simulated time"
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
        // The initial state at sim_time 0 (before the first step, so no `step` index): the
        // reference configuration, u = 0, without stress.
        rec.disable_timeline("step");
        rec.set_duration_secs("sim_time", 0.0);
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
        rec.set_duration_secs("sim_time", super::or_zero(s.time));
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
        // Dropping the last handle closes the file sink.
        self.rec = None;
        self.error.take().into_iter().collect()
    }
}

/// `v` rounded to `digits` significant digits (for labels).
fn round_sig(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return 0.0;
    }
    let e = v.abs().log10().floor() as i32;
    let f = 10f64.powi(digits - 1 - e);
    (v * f).round() / f
}
