//! MCAP sink: `run.mcap`, every channel **protobuf** with its schema (a `FileDescriptorSet`)
//! embedded, so the file is self-describing.
//!
//! Why protobuf: both Foxglove and the Rerun viewer decode protobuf channels from the embedded
//! descriptors (Rerun keeps JSON channels only as raw bytes). Where a Foxglove well-known schema
//! fits, it is used, because both viewers then *display* it: `foxglove.PointCloud` (Rerun maps it
//! to `Points3D`, Foxglove's 3D panel colours it by any field) and `foxglove.Log` (Rerun:
//! `TextLog`). The full deformed mesh goes out as `foxglove.SceneUpdate` (triangles with
//! per-vertex colours and the boundary/road lines), which Foxglove's 3D panel draws; Rerun 0.36
//! does not map scene primitives (it shows the struct), so for Rerun the `.rrd` sink carries the
//! mesh. Scalar data uses small flat messages (derived with `foxglove::Encode`, package and
//! message name `treadxxx.TreadXxx`) whose numeric fields both viewers plot as time series.
//!
//! | topic | schema | when | content |
//! |---|---|---|---|
//! | `/tread/step` | `treadstep.TreadStep` | every accepted step | index, time, dt, Newton iterations, residual, is_final |
//! | `/tread/newton` | `treadnewton.TreadNewton` | every Newton iteration | step, time, iteration, residual (max), residual_rel[], increment_norm, alpha |
//! | `/tread/rejected` | `treadrejected.TreadRejected` | rejected step | index, time, dt, reason |
//! | `/tread/nodes` | `foxglove.PointCloud` | recorded steps | deformed nodes: x, y, z (f32), `max_shear_stress`, `u1`, `u2` (f32), red/green/blue/alpha (u8, the stress colour map) |
//! | `/tread/mesh` | `foxglove.SceneUpdate` | recorded steps | entity `body`: triangles of the deformed mesh coloured by stress, lines: boundary loops and the road |
//! | `/tread/contact` | `foxglove.PointCloud` | recorded steps with contact | facet points: x, y, z, `t_n`, `t_t`, `penetration`, `slip_velocity`, `theta` (f32) + colour by t_n |
//! | `/tread/contact_patch` | `treadcontact.TreadContact` | recorded steps with contact | arrays along the boundary: theta, x1, x2, t_n, t_t, penetration, slip_velocity, ds0 |
//! | `/tread/hub` | `treadhub.TreadHub` | recorded steps | force_x, force_y, torque |
//! | `/tread/energy` | `treadenergy.TreadEnergy` | recorded steps | strain, kinetic, total |
//! | `/tread/series/<name>` | `treadscalar.TreadScalar` | recorded steps | one channel per named series of the view (`StepView::series`) |
//! | `/tread/continuation` | `treadbranchpoint.TreadBranchPoint` | continuation points | parameter, arc length, det sign, kind, measures |
//! | `/tread/steady` | `treadsteady.TreadSteady` | steady state | time, change, named results |
//! | `/tread/log` | `foxglove.Log` | run start/end, rejections, interrupts | text |
//!
//! Every message's `log_time` = `publish_time` = the step's time in nanoseconds from 0 (the load
//! factor λ counts as seconds in load stepping). Metadata records: `scene` (name, mode, the
//! resolved scene TOML), `build` (tread version, cargo features) and, at the end, `summary`
//! (summary.json, converged, error).
//!
//! Chunks are zstd-compressed, at most 256 KiB, and the current chunk is closed after every
//! recorded step, so a killed process leaves a file readable up to its last recorded step (read
//! it with a streaming reader, e.g. `mcap::MessageStream`, which reports the truncation after the
//! last complete message). Non-finite numbers are written as 0 (absent for optional fields).

use super::{
    boundary_loops, colormap, display_triangles, or_zero, ContinuationPoint, NewtonIteration,
    RecordError, Recorder, RejectedStep, RunEnd, RunMeta, SteadyReached, StepInfo, StepView,
};
use foxglove::messages as fm;
use foxglove::Encode;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

/// Largest chunk before it is closed (it is also closed after every recorded step).
pub const CHUNK_SIZE: u64 = 256 * 1024;

/// One accepted step.
#[derive(Encode, Debug, Clone)]
pub struct TreadStep {
    pub index: u64,
    pub time: f64,
    pub dt: f64,
    pub newton_iterations: u64,
    pub residual: f64,
    pub is_final: bool,
}

/// One Newton iteration.
#[derive(Encode, Debug, Clone)]
pub struct TreadNewton {
    pub step: u64,
    pub time: f64,
    pub iteration: u64,
    /// Largest relative residual over the fields.
    pub residual: f64,
    /// Relative residual per field (u, p, H, …).
    pub residual_rel: Vec<f64>,
    pub increment_norm: f64,
    pub alpha: f64,
}

/// A rejected step.
#[derive(Encode, Debug, Clone)]
pub struct TreadRejected {
    pub index: u64,
    pub time: f64,
    pub dt: f64,
    pub reason: String,
}

/// Contact tractions along the outer boundary (arrays indexed by facet point).
#[derive(Encode, Debug, Clone, Default)]
pub struct TreadContact {
    pub step: u64,
    pub time: f64,
    pub theta: Vec<f64>,
    pub x1: Vec<f64>,
    pub x2: Vec<f64>,
    pub t_n: Vec<f64>,
    pub t_t: Vec<f64>,
    pub penetration: Vec<f64>,
    pub slip_velocity: Vec<f64>,
    pub ds0: Vec<f64>,
}

/// Hub force and torque on the body.
#[derive(Encode, Debug, Clone)]
pub struct TreadHub {
    pub step: u64,
    pub time: f64,
    pub force_x: f64,
    pub force_y: f64,
    pub torque: f64,
}

/// Energies.
#[derive(Encode, Debug, Clone)]
pub struct TreadEnergy {
    pub step: u64,
    pub time: f64,
    pub strain: f64,
    pub kinetic: f64,
    pub total: f64,
}

/// One value of a named series (the channel names it).
#[derive(Encode, Debug, Clone)]
pub struct TreadScalar {
    pub step: u64,
    pub time: f64,
    pub value: f64,
}

/// A continuation point.
#[derive(Encode, Debug, Clone)]
pub struct TreadBranchPoint {
    pub index: u64,
    pub parameter_name: String,
    pub parameter: f64,
    pub arc_length: f64,
    pub newton_iterations: u64,
    pub det_sign: i64,
    pub kind: String,
    pub measure_names: Vec<String>,
    pub measure_values: Vec<f64>,
}

/// A steady state.
#[derive(Encode, Debug, Clone)]
pub struct TreadSteady {
    pub time: f64,
    pub change: f64,
    pub names: Vec<String>,
    pub values: Vec<f64>,
}

/// Nanoseconds from 0 of a time in seconds (clamped at 0).
pub fn time_ns(t: f64) -> u64 {
    if t.is_finite() && t > 0.0 {
        (t * 1e9).round() as u64
    } else {
        0
    }
}

pub struct McapSink {
    path: PathBuf,
    writer: Option<mcap::Writer<BufWriter<File>>>,
    channels: BTreeMap<String, u16>,
    sequence: u32,
    error: Option<RecordError>,
    triangles: Vec<[u32; 3]>,
    loops: Vec<Vec<u32>>,
    buf: Vec<u8>,
    ro: f64,
    /// Accepted steps so far and the time of the last one (the end-of-run log is stamped with
    /// it, not with 0).
    steps: u64,
    last_time: f64,
}

impl McapSink {
    /// Writes `dir/run.mcap`.
    pub fn new(dir: &Path) -> Self {
        Self::with_path(dir.join("run.mcap"))
    }

    pub fn with_path(path: PathBuf) -> Self {
        Self {
            path,
            writer: None,
            channels: BTreeMap::new(),
            sequence: 0,
            error: None,
            triangles: Vec::new(),
            loops: Vec::new(),
            buf: Vec::new(),
            ro: 1.0,
            steps: 0,
            last_time: 0.0,
        }
    }

    fn fail(&mut self, e: impl std::fmt::Display) {
        if self.error.is_none() {
            self.error = Some(RecordError::new("mcap", &self.path, e));
        }
        // Stop writing (dropping the writer tries to finish the file; errors are ignored):
        // whatever was written stays readable up to its last chunk.
        self.writer = None;
    }

    pub(super) fn open(&mut self) -> Result<(), String> {
        let f = File::create(&self.path).map_err(|e| e.to_string())?;
        let opts = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .chunk_size(Some(CHUNK_SIZE))
            .profile("")
            .library(format!("tread {}", env!("CARGO_PKG_VERSION")));
        let w = opts.create(BufWriter::new(f)).map_err(|e| e.to_string())?;
        self.writer = Some(w);
        Ok(())
    }

    /// Channel id of `topic` with schema of `T` (registered on first use).
    fn channel<T: Encode>(&mut self, topic: &str) -> Option<u16> {
        if let Some(id) = self.channels.get(topic) {
            return Some(*id);
        }
        let w = self.writer.as_mut()?;
        let schema = T::get_schema()?;
        let r = w
            .add_schema(&schema.name, &schema.encoding, &schema.data)
            .and_then(|sid| {
                w.add_channel(sid, topic, &T::get_message_encoding(), &BTreeMap::new())
            });
        match r {
            Ok(id) => {
                self.channels.insert(topic.to_string(), id);
                Some(id)
            }
            Err(e) => {
                self.fail(e);
                None
            }
        }
    }

    pub(super) fn write<T: Encode>(&mut self, topic: &str, time: f64, msg: &T) {
        if self.error.is_some() || self.writer.is_none() {
            return;
        }
        let Some(ch) = self.channel::<T>(topic) else {
            return;
        };
        self.buf.clear();
        if let Err(e) = msg.encode(&mut self.buf) {
            self.fail(e);
            return;
        }
        self.sequence = self.sequence.wrapping_add(1);
        let t = time_ns(time);
        let header = mcap::records::MessageHeader {
            channel_id: ch,
            sequence: self.sequence,
            log_time: t,
            publish_time: t,
        };
        let r = match self.writer.as_mut() {
            Some(w) => w.write_to_known_channel(&header, &self.buf),
            None => return,
        };
        if let Err(e) = r {
            self.fail(e);
        }
    }

    pub(super) fn close_chunk(&mut self) {
        let r = match self.writer.as_mut() {
            Some(w) => w.flush(),
            None => return,
        };
        if let Err(e) = r {
            self.fail(e);
        }
    }

    pub(super) fn metadata(&mut self, name: &str, pairs: &[(&str, &str)]) {
        let r = match self.writer.as_mut() {
            Some(w) => w.write_metadata(&mcap::records::Metadata {
                name: name.to_string(),
                metadata: pairs
                    .iter()
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect(),
            }),
            None => return,
        };
        if let Err(e) = r {
            self.fail(e);
        }
    }

    fn log_text(&mut self, time: f64, level: fm::log::Level, text: &str) {
        let msg = fm::Log {
            timestamp: Some(timestamp(time)),
            level: level as i32,
            message: text.to_string(),
            name: "tread".to_string(),
            file: String::new(),
            line: 0,
        };
        self.write("/tread/log", time, &msg);
    }

    /// The channels of a view under `prefix` (`/tread` for steps, `/tread/steady` for the
    /// steady state, so that it never appears as a step).
    fn write_view(&mut self, prefix: &str, info: &StepInfo, v: &StepView) {
        let time = info.time;
        if let Some(mesh) = v.mesh {
            let nn = mesh.n_nodes();
            let measures: Vec<f64> = (0..v.stress.len()).map(|n| v.stress_measure(n)).collect();
            let smax = measures.iter().copied().fold(0.0, f64::max);
            let colour = |n: usize| {
                let m = measures.get(n).copied().unwrap_or(0.0);
                colormap(if smax > 0.0 { m / smax } else { 0.0 })
            };
            let pos = |n: usize| {
                let u = v.u(n);
                [mesh.nodes[n][0] + u[0], mesh.nodes[n][1] + u[1]]
            };
            // Point cloud of the deformed nodes.
            let fields = [
                ("x", 0, F32),
                ("y", 4, F32),
                ("z", 8, F32),
                ("max_shear_stress", 12, F32),
                ("u1", 16, F32),
                ("u2", 20, F32),
                ("red", 24, U8),
                ("green", 25, U8),
                ("blue", 26, U8),
                ("alpha", 27, U8),
            ];
            let mut data = Vec::with_capacity(28 * nn);
            for n in 0..nn {
                let p = pos(n);
                let u = v.u(n);
                let m = measures.get(n).copied().unwrap_or(0.0);
                for f in [p[0], p[1], 0.0, m, u[0], u[1]] {
                    data.extend_from_slice(&(or_zero(f) as f32).to_le_bytes());
                }
                let c = colour(n);
                data.extend_from_slice(&[c[0], c[1], c[2], 255]);
            }
            let cloud = point_cloud(time, &fields, 28, data);
            self.write(&format!("{prefix}/nodes"), time, &cloud);

            // Scene update: the deformed mesh, its boundary and the road.
            let p3 = |n: usize| {
                let p = pos(n);
                fm::Point3 {
                    x: or_zero(p[0]),
                    y: or_zero(p[1]),
                    z: 0.0,
                }
            };
            let rgba = |c: [u8; 3]| fm::Color {
                r: f64::from(c[0]) / 255.0,
                g: f64::from(c[1]) / 255.0,
                b: f64::from(c[2]) / 255.0,
                a: 1.0,
            };
            let tri = fm::TriangleListPrimitive {
                pose: Some(identity_pose()),
                points: (0..nn).map(p3).collect(),
                color: None,
                colors: (0..nn).map(|n| rgba(colour(n))).collect(),
                indices: self.triangles.iter().flatten().copied().collect(),
            };
            let mut lines: Vec<fm::LinePrimitive> = self
                .loops
                .iter()
                .map(|l| line(l.iter().map(|&n| p3(n as usize)).collect(), [0.1, 0.1, 0.1]))
                .collect();
            if let Some(h) = v.road_height {
                let w = 1.5 * self.ro;
                lines.push(line(
                    vec![
                        fm::Point3 {
                            x: -w,
                            y: -h,
                            z: 0.0,
                        },
                        fm::Point3 {
                            x: w,
                            y: -h,
                            z: 0.0,
                        },
                    ],
                    [0.5, 0.3, 0.1],
                ));
            }
            let update = fm::SceneUpdate {
                deletions: Vec::new(),
                entities: vec![fm::SceneEntity {
                    timestamp: Some(timestamp(time)),
                    frame_id: "hub".to_string(),
                    id: "body".to_string(),
                    lifetime: None,
                    frame_locked: false,
                    metadata: Vec::new(),
                    arrows: Vec::new(),
                    cubes: Vec::new(),
                    spheres: Vec::new(),
                    cylinders: Vec::new(),
                    lines,
                    triangles: vec![tri],
                    texts: Vec::new(),
                    models: Vec::new(),
                }],
            };
            self.write(&format!("{prefix}/mesh"), time, &update);
        }
        if !v.contact.is_empty() {
            let pmax = v.contact.iter().map(|s| s.t_n).fold(0.0, f64::max);
            let fields = [
                ("x", 0, F32),
                ("y", 4, F32),
                ("z", 8, F32),
                ("t_n", 12, F32),
                ("t_t", 16, F32),
                ("penetration", 20, F32),
                ("slip_velocity", 24, F32),
                ("theta", 28, F32),
                ("red", 32, U8),
                ("green", 33, U8),
                ("blue", 34, U8),
                ("alpha", 35, U8),
            ];
            let mut data = Vec::with_capacity(36 * v.contact.len());
            let mut patch = TreadContact {
                step: info.index,
                time,
                ..Default::default()
            };
            for s in v.contact {
                for f in [s.x1, s.x2, 0.0, s.t_n, s.t_t, s.delta, s.w, s.theta] {
                    data.extend_from_slice(&(or_zero(f) as f32).to_le_bytes());
                }
                let c = colormap(if pmax > 0.0 { s.t_n / pmax } else { 0.0 });
                data.extend_from_slice(&[c[0], c[1], c[2], 255]);
                patch.theta.push(or_zero(s.theta));
                patch.x1.push(or_zero(s.x1));
                patch.x2.push(or_zero(s.x2));
                patch.t_n.push(or_zero(s.t_n));
                patch.t_t.push(or_zero(s.t_t));
                patch.penetration.push(or_zero(s.delta));
                patch.slip_velocity.push(or_zero(s.w));
                patch.ds0.push(or_zero(s.ds0));
            }
            let cloud = point_cloud(time, &fields, 36, data);
            self.write(&format!("{prefix}/contact"), time, &cloud);
            self.write(&format!("{prefix}/contact_patch"), time, &patch);
        }
        if let Some(h) = v.hub {
            let msg = TreadHub {
                step: info.index,
                time,
                force_x: or_zero(h.force[0]),
                force_y: or_zero(h.force[1]),
                torque: or_zero(h.torque),
            };
            self.write(&format!("{prefix}/hub"), time, &msg);
        }
        if let Some(e) = v.energy {
            let msg = TreadEnergy {
                step: info.index,
                time,
                strain: or_zero(e.strain),
                kinetic: or_zero(e.kinetic),
                total: or_zero(e.total()),
            };
            self.write(&format!("{prefix}/energy"), time, &msg);
        }
        for (name, value) in v.series(info) {
            if !value.is_finite() {
                continue;
            }
            let msg = TreadScalar {
                step: info.index,
                time,
                value,
            };
            self.write(&format!("{prefix}/series/{name}"), time, &msg);
        }
    }
}

pub(super) const F32: i32 = fm::packed_element_field::NumericType::Float32 as i32;
pub(super) const U8: i32 = fm::packed_element_field::NumericType::Uint8 as i32;

pub(super) fn timestamp(t: f64) -> fm::Timestamp {
    let ns = time_ns(t);
    fm::Timestamp::new(
        u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX),
        (ns % 1_000_000_000) as u32,
    )
}

pub(super) fn identity_pose() -> fm::Pose {
    fm::Pose {
        position: Some(fm::Vector3 {
            x: 0.0,
            y: 0.0,
            z: 0.0,
        }),
        orientation: Some(fm::Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }),
    }
}

pub(super) fn point_cloud(
    time: f64,
    fields: &[(&str, u32, i32)],
    stride: u32,
    data: Vec<u8>,
) -> fm::PointCloud {
    fm::PointCloud {
        timestamp: Some(timestamp(time)),
        frame_id: "hub".to_string(),
        pose: Some(identity_pose()),
        point_stride: stride,
        fields: fields
            .iter()
            .map(|(name, offset, ty)| fm::PackedElementField {
                name: (*name).to_string(),
                offset: *offset,
                r#type: *ty,
            })
            .collect(),
        data: data.into(),
    }
}

fn line(points: Vec<fm::Point3>, rgb: [f64; 3]) -> fm::LinePrimitive {
    fm::LinePrimitive {
        r#type: fm::line_primitive::Type::LineStrip as i32,
        pose: Some(identity_pose()),
        thickness: 2.0,
        scale_invariant: true,
        points,
        color: Some(fm::Color {
            r: rgb[0],
            g: rgb[1],
            b: rgb[2],
            a: 1.0,
        }),
        colors: Vec::new(),
        indices: Vec::new(),
    }
}

impl McapSink {
    /// Finish the file (summary and footer): the first error of the whole file, if any.
    pub(super) fn finish_file(&mut self) -> Result<(), RecordError> {
        if let Some(mut w) = self.writer.take() {
            if let Err(e) = w.finish() {
                self.error
                    .get_or_insert(RecordError::new("mcap", &self.path, e));
            }
        }
        self.error.take().map_or(Ok(()), Err)
    }

    /// The first error so far, if any.
    pub(super) fn error(&self) -> Option<&RecordError> {
        self.error.as_ref()
    }
}

impl Recorder for McapSink {
    fn run_started(&mut self, meta: &RunMeta) {
        if let Err(e) = self.open() {
            self.fail(e);
            return;
        }
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
        self.metadata(
            "scene",
            &[
                ("name", meta.scene_name),
                ("mode", meta.mode),
                ("time", meta.time_name),
                ("toml", meta.scene_toml),
            ],
        );
        self.metadata(
            "build",
            &[
                ("tread_version", meta.version),
                ("features", meta.features),
                (
                    "time_unit_note",
                    "log_time = step time in ns (load factor counted as seconds)",
                ),
            ],
        );
        let text = format!(
            "run started: scene {} ({} mode)",
            meta.scene_name, meta.mode
        );
        self.log_text(0.0, fm::log::Level::Info, &text);
    }
    fn wants_view(&self, _info: &StepInfo) -> bool {
        self.writer.is_some()
    }
    fn step(&mut self, info: &StepInfo, view: Option<&StepView>) {
        let msg = TreadStep {
            index: info.index,
            time: or_zero(info.time),
            dt: or_zero(info.dt),
            newton_iterations: info.newton_iterations as u64,
            residual: or_zero(info.residual),
            is_final: info.is_final,
        };
        self.write("/tread/step", info.time, &msg);
        self.steps = info.index + 1;
        if info.time.is_finite() {
            self.last_time = self.last_time.max(info.time);
        }
        if let Some(v) = view {
            self.write_view("/tread", info, v);
            self.close_chunk();
        }
    }
    fn step_rejected(&mut self, s: &RejectedStep) {
        let msg = TreadRejected {
            index: s.index,
            time: or_zero(s.time),
            dt: or_zero(s.dt),
            reason: s.reason.to_string(),
        };
        self.write("/tread/rejected", s.time, &msg);
        let text = format!("step {} to {:.6e} rejected: {}", s.index, s.time, s.reason);
        self.log_text(s.time, fm::log::Level::Warning, &text);
    }
    fn newton_iteration(&mut self, it: &NewtonIteration) {
        let msg = TreadNewton {
            step: it.step,
            time: or_zero(it.time),
            iteration: it.iteration as u64,
            residual: or_zero(it.residual_rel.iter().copied().fold(0.0, f64::max)),
            residual_rel: it.residual_rel.iter().map(|v| or_zero(*v)).collect(),
            increment_norm: or_zero(it.increment_norm),
            alpha: or_zero(it.alpha),
        };
        self.write("/tread/newton", it.time, &msg);
    }
    fn continuation_point(&mut self, p: &ContinuationPoint) {
        let msg = TreadBranchPoint {
            index: p.index,
            parameter_name: p.parameter_name.to_string(),
            parameter: or_zero(p.parameter),
            arc_length: or_zero(p.arc_length),
            newton_iterations: p.newton_iterations as u64,
            det_sign: i64::from(p.det_sign),
            kind: p.kind.as_str().to_string(),
            measure_names: p.measures.iter().map(|(n, _)| (*n).to_string()).collect(),
            measure_values: p.measures.iter().map(|(_, v)| or_zero(*v)).collect(),
        };
        // Branch points are ordered by their index (log_time = index seconds).
        self.write("/tread/continuation", p.index as f64, &msg);
        self.close_chunk();
    }
    fn steady_reached(&mut self, s: &SteadyReached, view: &StepView) {
        let msg = TreadSteady {
            time: or_zero(s.time),
            change: or_zero(s.change),
            names: s.results.iter().map(|(n, _)| (*n).to_string()).collect(),
            values: s.results.iter().map(|(_, v)| or_zero(*v)).collect(),
        };
        self.write("/tread/steady", s.time, &msg);
        // Not a step: its own channels, step = the number of accepted steps before it.
        let info = StepInfo {
            index: self.steps,
            time: s.time,
            dt: 0.0,
            newton_iterations: 0,
            residual: s.change,
            is_final: true,
        };
        self.write_view("/tread/steady", &info, view);
        self.close_chunk();
    }
    fn run_finished(&mut self, end: &RunEnd) -> Vec<RecordError> {
        if self.writer.is_some() {
            let text = match (end.interrupted, end.error) {
                (true, _) => format!("run interrupted after {} steps", end.steps),
                (false, Some(e)) => format!("run failed after {} steps: {e}", end.steps),
                (false, None) => format!("run finished: {} steps", end.steps),
            };
            let level = if end.converged {
                fm::log::Level::Info
            } else {
                fm::log::Level::Error
            };
            self.log_text(self.last_time, level, &text);
            let summary = end
                .summary
                .map(|s| serde_json::to_string(s).unwrap_or_default())
                .unwrap_or_default();
            let converged = end.converged.to_string();
            let steps = end.steps.to_string();
            self.metadata(
                "summary",
                &[
                    ("converged", &converged),
                    (
                        "interrupted",
                        if end.interrupted { "true" } else { "false" },
                    ),
                    ("error", end.error.unwrap_or("")),
                    ("steps", &steps),
                    ("summary_json", &summary),
                ],
            );
        }
        if let Some(mut w) = self.writer.take() {
            if let Err(e) = w.finish() {
                self.error
                    .get_or_insert(RecordError::new("mcap", &self.path, e));
            }
        }
        self.error.take().into_iter().collect()
    }
}
