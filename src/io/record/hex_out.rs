//! Outputs of three-dimensional results on hexahedral meshes ([`HexMesh`]): one entry point,
//! [`HexOutputs`] (or [`write_hex_outputs`] for a single state), writing into a directory
//!
//! | file | content |
//! |---|---|
//! | `hex.pvd`, `hex/step_NNNNNN.vtu` | ParaView: reference nodes, `displacement`, the point and cell fields ([`super::vtu3d`]); the `.pvd` lists every step with its time and is rewritten (through a temporary file and a rename) after each |
//! | `hex.mcap` | MCAP, protobuf channels: `/tread/hex/nodes` (`foxglove.PointCloud`: deformed surface nodes x, y, z, the colour field, u1, u2, u3 as f32 and red/green/blue/alpha) and `/tread/hex/mesh` (`foxglove.SceneUpdate`, entity `body`: one `TriangleListPrimitive`, the triangulated boundary at the deformed positions with per-vertex colours); metadata `hex` (units, colour field and its range, counts) |
//! | `hex.rrd` | Rerun (cargo feature `rerun`): `body/mesh` (Mesh3D: the triangulated boundary at the deformed positions, vertex colours from the colour field), `body/colour_scale` (Mesh3D bar) with labels (`body/colour_scale/labels`: field name, 0 and maximum with unit), `scene` (TextDocument: units, displacement scale, colour field); with contact (`HexOutputs::write_footprint`) `footprint/pressure` (Points3D at the contact points, viridis by the contact pressure, radius half the point's √dA0), `footprint/traction` (Arrows3D: the tangential traction on the body, the longest 2 √dA0 long), `footprint/stick` (Points3D: the stick zone, white), `footprint/legend` (TextDocument: the ranges and units); timelines `step` and `sim_time` |
//!
//! The viewer surface is the boundary of the body ([`HexMesh::boundary_faces`]) triangulated
//! through all face nodes ([`HexMesh::surface_triangulation`]: 2 triangles per Hex8 face, 8
//! per Hex27 face). Vertices are drawn at X + k u with `k = displacement_scale` (default 1;
//! MCAP and Rerun only: the VTU holds X and u apart). The colour of a vertex is the project's
//! viridis map ([`super::colormap`]) of v / v_max, v the value of the colour field
//! ([`HexOutputOptions::colour_by`], default the first scalar point field; without one |u|),
//! v_max its largest finite value in the step (negative values take the colour of 0).
//! Non-finite values are drawn as 0 (the VTU keeps them as NaN).
//!
//! ```no_run
//! # use tread::io::record::hex_out::*;
//! # use tread::io::record::vtu3d::Field3D;
//! # fn f(mesh: &tread::mesh::hex_mesh::HexMesh, u: &[f64], vm: &[f64]) -> Result<(), tread::io::record::RecordError> {
//! let mut out = HexOutputs::create(std::path::Path::new("out"), mesh, HexOutputOptions::default())?;
//! let fields = [Field3D::scalar("von_mises", vm, "psi")];
//! out.write_step(mesh, &HexState { index: 0, time: 0.0, u, point_fields: &fields, cell_fields: &[] })?;
//! out.finish()
//! # }
//! ```

use super::mcap::{identity_pose, point_cloud, timestamp, McapSink, F32, U8};
use super::png::Units;
use super::vtu::{pvd_text, write_atomic, Encoding, VtuFormat};
use super::vtu3d::{check_field, hex_vtu_bytes, Field3D, FieldKind};
use super::{colormap, or_zero, RecordError};
use crate::mesh::hex_mesh::{HexMesh, SurfaceTriangulation};
use foxglove::messages as fm;
use std::path::{Path, PathBuf};

/// Which files [`HexOutputs`] writes, and how.
#[derive(Clone, Debug)]
pub struct HexOutputOptions {
    pub vtu: bool,
    pub mcap: bool,
    /// `hex.rrd`; ignored in builds without the `rerun` feature.
    pub rerun: bool,
    pub encoding: Encoding,
    /// Units of the scene (length in the Rerun scene text; field units come with the fields).
    pub units: Units,
    /// Displacement magnification k of the viewer surfaces (MCAP, Rerun).
    pub displacement_scale: f64,
    /// Name of the point field that colours the viewer surfaces (a scalar field); `None`: the
    /// first scalar point field, else |u|.
    pub colour_by: Option<String>,
}

impl Default for HexOutputOptions {
    fn default() -> Self {
        Self {
            vtu: true,
            mcap: true,
            rerun: true,
            encoding: VtuFormat::Binary.into(),
            units: Units::default(),
            displacement_scale: 1.0,
            colour_by: None,
        }
    }
}

/// One state of a 3D result.
#[derive(Clone, Copy, Debug)]
pub struct HexState<'a> {
    /// Step index (file names, `step` timeline).
    pub index: u64,
    pub time: f64,
    /// Displacement, 3 per node, node-major.
    pub u: &'a [f64],
    pub point_fields: &'a [Field3D<'a>],
    pub cell_fields: &'a [Field3D<'a>],
}

/// The contact patch of one state, for the Rerun recording (`footprint/…`, see the module
/// docs).
#[derive(Clone, Copy, Debug)]
pub struct FootprintState<'a> {
    /// Step index and time of the state (the same as its [`HexState`]'s).
    pub index: u64,
    pub time: f64,
    pub samples: &'a [crate::contact::facet3d::ContactSample3D],
    /// The road's in-plane directions (e1, e3) in the wheel frame: the tangential traction on
    /// the body is t1 e1 + t3 e3.
    pub e1: [f64; 3],
    pub e3: [f64; 3],
}

/// The writers of a 3D run (see the module docs).
pub struct HexOutputs {
    dir: PathBuf,
    opts: HexOutputOptions,
    surface: SurfaceTriangulation,
    written: Vec<(f64, String)>,
    mcap: Option<McapSink>,
    #[cfg(feature = "rerun")]
    rrd: Option<(rerun::RecordingStream, super::rrd::RrdFile)>,
    /// Largest distance of a node from the origin (places the colour scale).
    radius: f64,
}

/// The colour values of a state (see the module docs), its name and unit.
fn colour_values(opts: &HexOutputOptions, s: &HexState, nn: usize) -> (String, String, Vec<f64>) {
    let pick = s.point_fields.iter().find(|f| {
        f.kind == FieldKind::Scalar && opts.colour_by.as_deref().is_none_or(|n| n == f.name)
    });
    match pick {
        Some(f) => (f.name.to_string(), f.unit.to_string(), f.values.to_vec()),
        None => (
            "|u|".to_string(),
            opts.units.length.clone(),
            (0..nn)
                .map(|n| {
                    let v = s.u.get(3 * n..3 * n + 3).unwrap_or(&[0.0; 3]);
                    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
                })
                .collect(),
        ),
    }
}

impl HexOutputs {
    /// Prepare the writers into `dir` (created) for `mesh`.
    pub fn create(dir: &Path, mesh: &HexMesh, opts: HexOutputOptions) -> Result<Self, RecordError> {
        std::fs::create_dir_all(dir).map_err(|e| RecordError::new("hex", dir, e))?;
        let surface = mesh.surface_triangulation(&mesh.boundary_faces());
        let mcap = if opts.mcap {
            let mut m = McapSink::with_path(dir.join("hex.mcap"));
            m.open()
                .map_err(|e| RecordError::new("mcap", dir.join("hex.mcap"), e))?;
            Some(m)
        } else {
            None
        };
        #[cfg(feature = "rerun")]
        let rrd = if opts.rerun {
            let path = dir.join("hex.rrd");
            let builder = rerun::RecordingStreamBuilder::new("tread")
                .recording_name("tread 3D")
                .send_properties(false);
            let (rec, file) = super::rrd::file_recording(builder, &path)
                .map_err(|e| RecordError::new("rerun", &path, e))?;
            rec.set_log_time_enabled(false);
            rec.set_log_tick_enabled(false);
            let _ = rec.send_recording_name("tread 3D");
            Some((rec, file))
        } else {
            None
        };
        let radius = mesh
            .nodes
            .iter()
            .map(|p| p.norm())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        Ok(Self {
            dir: dir.to_path_buf(),
            opts,
            surface,
            written: Vec::new(),
            mcap,
            #[cfg(feature = "rerun")]
            rrd,
            radius,
        })
    }

    /// Whether [`Self::write_footprint`] records anything (a Rerun recording is open).
    pub fn logs_footprint(&self) -> bool {
        #[cfg(feature = "rerun")]
        let open = self.rrd.is_some();
        #[cfg(not(feature = "rerun"))]
        let open = false;
        open
    }

    /// Log the contact patch of a state (written by [`Self::write_step`] before) to the
    /// Rerun recording; nothing without it (sink `rerun` off, or a build without the
    /// feature).
    pub fn write_footprint(&mut self, f: &FootprintState) -> Result<(), RecordError> {
        #[cfg(feature = "rerun")]
        if let Some((rec, _)) = &self.rrd {
            self::rrd3d::log_footprint(rec, f, &self.opts.units)
                .map_err(|e| RecordError::new("rerun", self.dir.join("hex.rrd"), e))?;
        }
        #[cfg(not(feature = "rerun"))]
        let _ = f;
        Ok(())
    }

    /// Write one state to every file.
    pub fn write_step(&mut self, mesh: &HexMesh, s: &HexState) -> Result<(), RecordError> {
        let nn = mesh.n_nodes();
        let bad = |e: super::vtu3d::HexOutputError| RecordError::new("hex", &self.dir, e);
        check_field(&Field3D::vector("displacement", s.u, ""), nn).map_err(bad)?;
        for f in s.point_fields {
            check_field(f, nn).map_err(bad)?;
        }
        if self.opts.vtu {
            let bytes = hex_vtu_bytes(
                mesh,
                s.u,
                s.point_fields,
                s.cell_fields,
                s.time,
                self.opts.encoding,
            )
            .map_err(bad)?;
            let sub = self.dir.join("hex");
            std::fs::create_dir_all(&sub).map_err(|e| RecordError::new("vtu", &sub, e))?;
            let name = format!("hex/step_{:06}.vtu", s.index);
            write_atomic(&self.dir.join(&name), &bytes)?;
            self.written.push((s.time, name));
            write_atomic(
                &self.dir.join("hex.pvd"),
                pvd_text(&self.written).as_bytes(),
            )?;
        }
        let (cname, cunit, cval) = colour_values(&self.opts, s, nn);
        let vmax = cval
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        let k = if self.opts.displacement_scale.is_finite() {
            self.opts.displacement_scale
        } else {
            1.0
        };
        let sv = &self.surface.vertices;
        let pos: Vec<[f64; 3]> = sv
            .iter()
            .map(|&n| {
                let n = n as usize;
                let x = mesh.nodes[n];
                let u = s.u.get(3 * n..3 * n + 3).unwrap_or(&[0.0; 3]);
                [
                    or_zero(x.x + k * u[0]),
                    or_zero(x.y + k * u[1]),
                    or_zero(x.z + k * u[2]),
                ]
            })
            .collect();
        let value: Vec<f64> = sv
            .iter()
            .map(|&n| or_zero(cval.get(n as usize).copied().unwrap_or(0.0)))
            .collect();
        let colours: Vec<[u8; 3]> = value
            .iter()
            .map(|&v| colormap(if vmax > 0.0 { v / vmax } else { 0.0 }))
            .collect();
        if let Some(m) = self.mcap.as_mut() {
            write_mcap(m, s, &self.surface, &pos, &value, &colours, sv);
            let counts = format!(
                "{} nodes, {} cells, {} surface vertices, {} triangles",
                nn,
                mesh.n_cells(),
                sv.len(),
                self.surface.triangles.len()
            );
            m.metadata(
                "hex",
                &[
                    ("step", &s.index.to_string()),
                    ("length_unit", &self.opts.units.length),
                    ("colour_field", &cname),
                    ("colour_unit", &cunit),
                    ("colour_min", "0"),
                    ("colour_max", &vmax.to_string()),
                    ("displacement_scale", &k.to_string()),
                    ("counts", &counts),
                ],
            );
            m.close_chunk();
            if let Some(e) = m.error() {
                return Err(e.clone());
            }
        }
        #[cfg(feature = "rerun")]
        if let Some((rec, _)) = &self.rrd {
            self::rrd3d::log(
                rec,
                s,
                &self.surface,
                &pos,
                &colours,
                (&cname, &cunit, vmax),
                (&self.opts.units, k, self.radius),
            )
            .map_err(|e| RecordError::new("rerun", self.dir.join("hex.rrd"), e))?;
        }
        #[cfg(not(feature = "rerun"))]
        let _ = self.radius;
        Ok(())
    }

    /// Finish the files (MCAP summary and footer, `.rrd` footer).
    pub fn finish(mut self) -> Result<(), RecordError> {
        if let Some(mut m) = self.mcap.take() {
            m.finish_file()?;
        }
        #[cfg(feature = "rerun")]
        if let Some((rec, file)) = self.rrd.take() {
            let path = self.dir.join("hex.rrd");
            let flushed = rec.flush_blocking();
            drop(rec);
            let finished = file.finish();
            flushed.map_err(|e| RecordError::new("rerun", &path, e))?;
            finished.map_err(|e| RecordError::new("rerun", &path, e))?;
        }
        Ok(())
    }
}

/// Write a single state (step 0) with `opts` into `dir` (see the module docs).
pub fn write_hex_outputs(
    dir: &Path,
    mesh: &HexMesh,
    state: &HexState,
    opts: HexOutputOptions,
) -> Result<(), RecordError> {
    let mut out = HexOutputs::create(dir, mesh, opts)?;
    out.write_step(mesh, state)?;
    out.finish()
}

fn write_mcap(
    m: &mut McapSink,
    s: &HexState,
    surface: &SurfaceTriangulation,
    pos: &[[f64; 3]],
    value: &[f64],
    colours: &[[u8; 3]],
    vertices: &[u32],
) {
    let fields = [
        ("x", 0, F32),
        ("y", 4, F32),
        ("z", 8, F32),
        ("value", 12, F32),
        ("u1", 16, F32),
        ("u2", 20, F32),
        ("u3", 24, F32),
        ("red", 28, U8),
        ("green", 29, U8),
        ("blue", 30, U8),
        ("alpha", 31, U8),
    ];
    let mut data = Vec::with_capacity(32 * pos.len());
    for (i, p) in pos.iter().enumerate() {
        let n = vertices[i] as usize;
        let u = s.u.get(3 * n..3 * n + 3).unwrap_or(&[0.0; 3]);
        for f in [p[0], p[1], p[2], value[i], u[0], u[1], u[2]] {
            data.extend_from_slice(&(or_zero(f) as f32).to_le_bytes());
        }
        let c = colours[i];
        data.extend_from_slice(&[c[0], c[1], c[2], 255]);
    }
    m.write(
        "/tread/hex/nodes",
        s.time,
        &point_cloud(s.time, &fields, 32, data),
    );
    let tri = fm::TriangleListPrimitive {
        pose: Some(identity_pose()),
        points: pos
            .iter()
            .map(|p| fm::Point3 {
                x: p[0],
                y: p[1],
                z: p[2],
            })
            .collect(),
        color: None,
        colors: colours
            .iter()
            .map(|c| fm::Color {
                r: f64::from(c[0]) / 255.0,
                g: f64::from(c[1]) / 255.0,
                b: f64::from(c[2]) / 255.0,
                a: 1.0,
            })
            .collect(),
        indices: surface.triangles.iter().flatten().copied().collect(),
    };
    let update = fm::SceneUpdate {
        deletions: Vec::new(),
        entities: vec![fm::SceneEntity {
            timestamp: Some(timestamp(s.time)),
            frame_id: "hub".to_string(),
            id: "body".to_string(),
            lifetime: None,
            frame_locked: false,
            metadata: Vec::new(),
            arrows: Vec::new(),
            cubes: Vec::new(),
            spheres: Vec::new(),
            cylinders: Vec::new(),
            lines: Vec::new(),
            triangles: vec![tri],
            texts: Vec::new(),
            models: Vec::new(),
        }],
    };
    m.write("/tread/hex/mesh", s.time, &update);
}

#[cfg(feature = "rerun")]
mod rrd3d {
    use super::*;

    /// Log the surface, its colour scale and the scene text of one state.
    pub(super) fn log(
        rec: &rerun::RecordingStream,
        s: &HexState,
        surface: &SurfaceTriangulation,
        pos: &[[f64; 3]],
        colours: &[[u8; 3]],
        (name, unit, vmax): (&str, &str, f64),
        (units, k, radius): (&Units, f64, f64),
    ) -> Result<(), rerun::RecordingStreamError> {
        rec.set_time_sequence("step", s.index as i64);
        rec.set_duration_secs("sim_time", or_zero(s.time));
        let p32: Vec<[f32; 3]> = pos.iter().map(|p| p.map(|x| x as f32)).collect();
        rec.log(
            "body/mesh",
            &rerun::Mesh3D::new(p32)
                .with_triangle_indices(surface.triangles.iter().copied())
                .with_vertex_colors(
                    colours
                        .iter()
                        .map(|c| rerun::Color::from_rgb(c[0], c[1], c[2])),
                ),
        )?;
        // Colour bar beside the body (x1 from 1.15 R to 1.25 R, x2 from −0.6 R to R, x3 = 0),
        // the map's five stops as vertices, as in the 2D view.
        let r = radius as f32;
        let (x0, x1) = (1.15 * r, 1.25 * r);
        let y = |t: f32| -0.6 * r + 1.6 * r * t;
        let mut bar = Vec::with_capacity(10);
        let mut bar_c = Vec::with_capacity(10);
        for i in 0..5 {
            let t = i as f32 / 4.0;
            let c = colormap(f64::from(t));
            for x in [x0, x1] {
                bar.push([x, y(t), 0.0]);
                bar_c.push(rerun::Color::from_rgb(c[0], c[1], c[2]));
            }
        }
        let tris: Vec<[u32; 3]> = (0..4u32)
            .flat_map(|i| {
                let a = 2 * i;
                [[a, a + 1, a + 3], [a, a + 3, a + 2]]
            })
            .collect();
        rec.log(
            "body/colour_scale",
            &rerun::Mesh3D::new(bar)
                .with_triangle_indices(tris)
                .with_vertex_colors(bar_c),
        )?;
        let u = if unit.is_empty() {
            String::new()
        } else {
            format!(" {unit}")
        };
        let xl = x1 + 0.42 * r;
        rec.log(
            "body/colour_scale/labels",
            &rerun::Points3D::new([[xl, y(0.0), 0.0], [xl, y(1.0), 0.0]])
                .with_radii([rerun::Radius::new_ui_points(0.5)])
                .with_labels([format!("{name} 0{u}"), format!("{name} max {vmax:.4e}{u}")])
                .with_show_labels(true),
        )?;
        let doc = format!(
            "# tread 3D\n\nLengths in {}; surface drawn at X + {k} u; colours: {name}{} from 0 to \
             {vmax:.6e} (viridis).\n",
            units.length,
            if unit.is_empty() {
                String::new()
            } else {
                format!(" [{unit}]")
            },
        );
        rec.log(
            "scene",
            &rerun::TextDocument::new(doc).with_media_type(rerun::MediaType::markdown()),
        )
    }

    /// Log the contact patch: the points in contact coloured by pressure, the tangential
    /// tractions as arrows, the stick points, and a legend with the ranges and units.
    pub(super) fn log_footprint(
        rec: &rerun::RecordingStream,
        f: &FootprintState,
        units: &Units,
    ) -> Result<(), rerun::RecordingStreamError> {
        rec.set_time_sequence("step", f.index as i64);
        rec.set_duration_secs("sim_time", or_zero(f.time));
        let pts: Vec<_> = f
            .samples
            .iter()
            .filter(|s| s.p > 0.0 && s.p.is_finite())
            .collect();
        let pmax = pts.iter().map(|s| s.p).fold(0.0, f64::max);
        let pos: Vec<[f32; 3]> = pts
            .iter()
            .map(|s| [s.x1, s.x2, s.x3].map(|v| or_zero(v) as f32))
            .collect();
        let size = |s: &&crate::contact::facet3d::ContactSample3D| s.da0.max(0.0).sqrt();
        rec.log(
            "footprint/pressure",
            &rerun::Points3D::new(pos.clone())
                .with_colors(pts.iter().map(|s| {
                    let c = colormap(if pmax > 0.0 { s.p / pmax } else { 0.0 });
                    rerun::Color::from_rgb(c[0], c[1], c[2])
                }))
                .with_radii(
                    pts.iter()
                        .map(|s| rerun::Radius::new_scene_units(0.5 * size(s) as f32)),
                ),
        )?;
        let tmax = pts
            .iter()
            .map(|s| or_zero(s.t1.hypot(s.t3)))
            .fold(0.0, f64::max);
        let mean = pts.iter().map(size).sum::<f64>() / pts.len().max(1) as f64;
        let scale = if tmax > 0.0 { 2.0 * mean / tmax } else { 0.0 };
        let vectors: Vec<[f32; 3]> = pts
            .iter()
            .map(|s| {
                let (t1, t3) = (or_zero(s.t1), or_zero(s.t3));
                [0, 1, 2].map(|i| (scale * (t1 * f.e1[i] + t3 * f.e3[i])) as f32)
            })
            .collect();
        rec.log(
            "footprint/traction",
            &rerun::Arrows3D::from_vectors(vectors).with_origins(pos.clone()),
        )?;
        let stick: Vec<[f32; 3]> = pts
            .iter()
            .zip(&pos)
            .filter(|(s, _)| s.stick)
            .map(|(_, p)| *p)
            .collect();
        rec.log(
            "footprint/stick",
            &rerun::Points3D::new(stick)
                .with_colors([rerun::Color::from_rgb(255, 255, 255)])
                .with_radii([rerun::Radius::new_scene_units((0.2 * mean) as f32)]),
        )?;
        let su = units.stress();
        let doc = format!(
            "# Contact patch\n\n`footprint/pressure`: the {} points in contact, coloured by the \
             contact pressure from 0 to {pmax:.6e} {su} (viridis). `footprint/traction`: the \
             tangential traction of the road on the body, the longest arrow ({tmax:.6e} {su}) \
             drawn {:.3e} {} long. `footprint/stick`: the points of the stick zone (|w| below \
             the regularisation ε), white.\n",
            pts.len(),
            2.0 * mean,
            units.length
        );
        rec.log(
            "footprint/legend",
            &rerun::TextDocument::new(doc).with_media_type(rerun::MediaType::markdown()),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::revolved::{revolved, RevolvedSpec};

    #[test]
    fn writes_every_file_and_reads_the_mcap_back() {
        let m = revolved(&RevolvedSpec {
            ri: 1.0,
            ro: 2.0,
            width: 0.5,
            n_r: 1,
            n_z: 2,
            n_theta: 8,
            degree: 2,
            grading_r: 1.0,
            grading_theta: 0.0,
            theta_ratio: 1.0,
            grading_z: 1.0,
            half_width: false,
            crown_radius: None,
        })
        .unwrap();
        let dir = std::env::temp_dir().join(format!("tread-hex-out-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let u: Vec<f64> = m
            .nodes
            .iter()
            .flat_map(|x| [0.0, -0.01 * x.x, 0.0])
            .collect();
        let vm: Vec<f64> = m.nodes.iter().map(|x| x.z.abs()).collect();
        let fields = [Field3D::scalar("von_mises", &vm, "psi")];
        let mut out = HexOutputs::create(&dir, &m, HexOutputOptions::default()).unwrap();
        for index in 0..2 {
            out.write_step(
                &m,
                &HexState {
                    index,
                    time: index as f64,
                    u: &u,
                    point_fields: &fields,
                    cell_fields: &[],
                },
            )
            .unwrap();
        }
        out.finish().unwrap();
        assert!(dir.join("hex/step_000001.vtu").is_file());
        let pvd = std::fs::read_to_string(dir.join("hex.pvd")).unwrap();
        assert_eq!(pvd.matches("<DataSet").count(), 2);
        let bytes = std::fs::read(dir.join("hex.mcap")).unwrap();
        let mut topics = std::collections::BTreeMap::new();
        for msg in mcap::MessageStream::new(&bytes).unwrap() {
            let msg = msg.unwrap();
            *topics.entry(msg.channel.topic.clone()).or_insert(0) += 1;
        }
        assert_eq!(topics.get("/tread/hex/nodes"), Some(&2));
        assert_eq!(topics.get("/tread/hex/mesh"), Some(&2));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
