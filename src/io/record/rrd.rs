//! Rerun sink: `run.rrd` for the Rerun viewer (`rerun run.rrd`). Behind the default cargo
//! feature `rerun`.
//!
//! Timelines: `step` (sequence: the accepted-step index) and `sim_time` (duration: simulated
//! seconds, or the load factor λ counted as seconds in load stepping); the wall-clock
//! `log_time`/`log_tick` timelines are off, so a file depends only on the run. Entities:
//!
//! | entity | archetype | content |
//! |---|---|---|
//! | `scene` | TextDocument (static) | the resolved scene TOML and the build |
//! | `body/mesh` | Mesh3D | the deformed mesh (z = 0), vertex colours = in-plane max shear stress (viridis, 0 … frame max) |
//! | `body/boundary` | LineStrips3D | inner and outer boundary loops |
//! | `road` | LineStrips3D | the road line x2 = −H |
//! | `contact/points` | Points3D | facet points of the outer boundary in contact, coloured by t_n |
//! | `contact/traction` | Arrows3D | traction vectors (t_T, t_n) at those points (scaled to 0.2 Ro at the peak) |
//! | `contact/pressure`, `contact/shear` | BarChart | t_n and t_T along the patch (abscissa x1) |
//! | `hub/force_x`, `hub/force_y`, `hub/torque` | Scalars | hub loads |
//! | `energy/strain`, `energy/kinetic`, `energy/total` | Scalars | energies |
//! | `series/<name>` | Scalars | the other series of the view (contact resultants, patch, stress max, model scalars) |
//! | `newton/iterations` | Scalars | Newton iterations of every step |
//! | `newton/residual` | Scalars | every Newton iteration, also on the `newton_iteration` timeline |
//! | `branch/<name>` | Scalars | continuation points on the `branch_point` timeline; `branch/table` TextDocument at the end |
//! | `steady/mesh`, `steady/results` | Mesh3D, TextDocument | the steady state |
//! | `log` | TextLog | run start and end, rejected steps, interrupts |

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

    fn mesh(&mut self, entity: &str, v: &StepView) {
        let (Some(rec), Some(mesh)) = (self.rec.clone(), v.mesh) else {
            return;
        };
        let nn = mesh.n_nodes();
        let pos: Vec<[f32; 3]> = (0..nn)
            .map(|n| {
                let u = v.u(n);
                [
                    super::or_zero(mesh.nodes[n][0] + u[0]) as f32,
                    super::or_zero(mesh.nodes[n][1] + u[1]) as f32,
                    0.0,
                ]
            })
            .collect();
        let m: Vec<f64> = (0..v.stress.len()).map(|n| v.stress_measure(n)).collect();
        let mmax = m.iter().copied().fold(0.0, f64::max);
        let colors: Vec<rerun::Color> = (0..nn)
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
            &rerun::Mesh3D::new(pos.clone())
                .with_triangle_indices(self.triangles.iter().copied())
                .with_vertex_colors(colors),
        );
        self.check(r);
        let strips: Vec<Vec<[f32; 3]>> = self
            .loops
            .iter()
            .map(|l| l.iter().map(|&n| pos[n as usize]).collect())
            .collect();
        if !strips.is_empty() {
            let r = rec.log(
                format!("{entity}/boundary"),
                &rerun::LineStrips3D::new(strips).with_colors([rerun::Color::from_rgb(30, 30, 30)]),
            );
            self.check(r);
        }
    }

    fn write_view(&mut self, info: &StepInfo, v: &StepView) {
        let Some(rec) = self.rec.clone() else { return };
        self.mesh("body", v);
        if let Some(h) = v.road_height {
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
            let points: Vec<[f32; 3]> = patch
                .iter()
                .map(|s| [s.x1 as f32, s.x2 as f32, 0.0])
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
            let x1: Vec<f64> = patch.iter().map(|s| s.x1).collect();
            let tn: Vec<f64> = patch.iter().map(|s| s.t_n).collect();
            let tt: Vec<f64> = patch.iter().map(|s| super::or_zero(s.t_t)).collect();
            let r = rec.log(
                "contact/pressure",
                &rerun::BarChart::new(tn).with_abscissa(x1.clone()),
            );
            self.check(r);
            let r = rec.log("contact/shear", &rerun::BarChart::new(tt).with_abscissa(x1));
            self.check(r);
        }
        for (name, value) in v.series(info) {
            if name == "newton_iterations" {
                continue; // logged for every step in `step`
            }
            self.scalar(&series_entity(name), name, value);
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
        let r = rerun::RecordingStreamBuilder::new("tread")
            .recording_name(meta.scene_name)
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
        let _ = rec.send_recording_name(meta.scene_name);
        self.rec = Some(rec.clone());
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
            "Newton iterations",
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
        self.scalar("newton/residual", "relative residual", res);
        rec.disable_timeline("newton_iteration");
    }
    fn continuation_point(&mut self, p: &ContinuationPoint) {
        let Some(rec) = self.rec.clone() else { return };
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
