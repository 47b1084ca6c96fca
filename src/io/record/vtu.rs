//! VTU/PVD sink (ParaView): one unstructured-grid file per recorded step,
//! `fields/step_NNNNNN.vtu`, listed with its time in `fields.pvd` (rewritten atomically after
//! every step, so an interrupted run leaves a valid series), and `steady.vtu` for a steady
//! state.
//!
//! Each `.vtu` (VTK XML 1.0) holds the **reference** node positions (z = 0) and, as point data:
//!
//! | array | components | meaning (units of the scene) |
//! |---|---|---|
//! | `displacement` | 3 | u (z = 0): use ParaView's *Warp By Vector* to see the deformed body; length |
//! | `cauchy_stress` | 9 | the full Cauchy stress tensor, row-major 3×3 (σ13 = σ23 = 0); stress |
//! | `max_shear_stress` | 1 | in-plane maximum shear stress (see [`super::stress_measure`]); stress |
//! | `sigma_11`, `sigma_22`, `sigma_12`, `sigma_33` | 1 | the same stresses one by one; stress |
//! | `pressure` | 1 | hydrostatic pressure −(σ11 + σ22 + σ33)/3 (compression positive); stress |
//! | `cauchy_stress_recovered` | 9 | the recovered (smoothed, superconvergent) Cauchy stress, row-major 3×3 like `cauchy_stress`: superconvergent patch recovery of the element stresses at the superconvergent points, continuous across cells (see `crate::physics::recovery`); always finite; stress |
//! | `pressure_field` | 1 | the pressure unknown p of a mixed (incompressible) formulation, σ = σ_law − p I (it includes the law's reference pressure, e.g. 2c1 + 4c2 for Mooney–Rivlin, so it is not the hydrostatic pressure); only when the model has one; stress |
//!
//! σ33 is the plane-strain out-of-plane stress of the constitutive law (F33 = 1), not zero.
//! Nodal stresses are cell values averaged at shared nodes; a node where no cell gives a
//! finite value holds NaN (missing in ParaView), never 0. Cell data: `cell_id` (Int64, 0-based
//! cell index) and `region` (Int32, material region of the cell, 0-based in the order of the
//! scene's materials). Cells are VTK_BIQUADRATIC_QUAD (28) for Q2 and VTK_QUAD (9) for Q1; the
//! field data `TimeValue` is the step's time.
//!
//! With contact, `contact.pvd` lists `contact/step_NNNNNN.vtu`: the contact surface of each
//! recorded step as a closed chain of line segments (VTK_LINE) through the contact sample points at
//! their current positions, with point data `theta`, `penetration`, `t_n`, `t_t`,
//! `slip_velocity`, `ds0` (see [`contact_vtu_bytes`]); ParaView's *Plot Data* draws t_n against
//! x1 from it.
//!
//! Encoding (`[output] vtu_format`): `binary` (default) stores every array as raw
//! little-endian data in one `<AppendedData encoding="raw">` block, each array preceded by its
//! byte count as a UInt64 (`header_type="UInt64"`); `ascii` writes the same arrays as text, each
//! number the shortest text that reads back exactly (`NaN`, `inf` for non-finite values).
//!
//! Compression (`[output] vtu_compression`, binary only): `none` (default) or `zlib`. With
//! `zlib` the file declares `compressor="vtkZLibDataCompressor"` and each appended array is
//! split into blocks of [`ZLIB_BLOCK`] bytes (the last one shorter), each compressed as a zlib
//! stream, after the VTK header of UInt64 numbers: number of blocks, block size, size of the last
//! block when it is partial (0 when full), then the compressed size of every block. ParaView,
//! VTK and meshio read it.

use super::{RecordError, Recorder, RunEnd, SteadyReached, StepInfo, StepView};
pub use crate::io::scene::{VtuCompression, VtuFormat};
use crate::mesh::Mesh;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

pub struct VtuSink {
    dir: PathBuf,
    /// (time, file name relative to `dir`) of every written step.
    written: Vec<(f64, String)>,
    /// The same for the contact surface (`contact.pvd`).
    contact_written: Vec<(f64, String)>,
    error: Option<RecordError>,
    format: VtuFormat,
    compression: VtuCompression,
}

/// Uncompressed size of a zlib block of the appended data (VTK's default).
pub const ZLIB_BLOCK: usize = 32 * 1024;

impl VtuSink {
    /// Writes into `dir` (`fields.pvd`, `fields/`, `steady.vtu`), binary.
    pub fn new(dir: &Path) -> Self {
        Self::with_format(dir, VtuFormat::Binary)
    }

    /// Writes into `dir` in the given encoding.
    pub fn with_format(dir: &Path, format: VtuFormat) -> Self {
        Self {
            dir: dir.to_path_buf(),
            written: Vec::new(),
            contact_written: Vec::new(),
            error: None,
            format,
            compression: VtuCompression::None,
        }
    }

    /// Compress the binary data (no effect on the ascii format).
    pub fn with_compression(mut self, compression: VtuCompression) -> Self {
        self.compression = compression;
        self
    }

    fn encoding(&self) -> Encoding {
        Encoding {
            format: self.format,
            compression: self.compression,
        }
    }

    fn write_step(&mut self, info: &StepInfo, view: &StepView) -> Result<(), RecordError> {
        let Some(mesh) = view.mesh else {
            return Ok(());
        };
        let sub = self.dir.join("fields");
        std::fs::create_dir_all(&sub).map_err(|e| RecordError::new("vtu", &sub, e))?;
        let name = format!("fields/step_{:06}.vtu", info.index);
        let path = self.dir.join(&name);
        write_atomic(
            &path,
            &grid_bytes(&grid(mesh, view), info.time, self.encoding()),
        )?;
        self.written.push((info.time, name));
        let pvd = self.dir.join("fields.pvd");
        write_atomic(&pvd, pvd_text(&self.written).as_bytes())?;
        if let Some(bytes) =
            contact_grid(view.contact).map(|g| grid_bytes(&g, info.time, self.encoding()))
        {
            let sub = self.dir.join("contact");
            std::fs::create_dir_all(&sub).map_err(|e| RecordError::new("vtu", &sub, e))?;
            let name = format!("contact/step_{:06}.vtu", info.index);
            write_atomic(&self.dir.join(&name), &bytes)?;
            self.contact_written.push((info.time, name));
            let pvd = self.dir.join("contact.pvd");
            write_atomic(&pvd, pvd_text(&self.contact_written).as_bytes())?;
        }
        Ok(())
    }
}

/// Write through a temporary file and a rename; a failed write (a full disk) removes the
/// temporary, so that neither a partial file nor the temporary is left.
pub(super) fn write_atomic(path: &Path, text: &[u8]) -> Result<(), RecordError> {
    let tmp = path.with_extension("tmp");
    if let Err(e) = std::fs::write(&tmp, text) {
        let _ = std::fs::remove_file(&tmp);
        return Err(RecordError::new("vtu", &tmp, e));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        RecordError::new("vtu", path, e)
    })
}

/// The VTK cell type and node order of cell `c`.
fn vtk_cell(mesh: &Mesh, c: usize) -> (u8, Vec<u32>) {
    let nodes = mesh.cell_nodes(c);
    let p = mesh.degree[c] as usize;
    let at = |i: usize, j: usize| nodes[i + (p + 1) * j];
    if p == 1 {
        (9, vec![at(0, 0), at(1, 0), at(1, 1), at(0, 1)])
    } else {
        (
            28,
            vec![
                at(0, 0),
                at(2, 0),
                at(2, 2),
                at(0, 2),
                at(1, 0),
                at(2, 1),
                at(1, 2),
                at(0, 1),
                at(1, 1),
            ],
        )
    }
}

/// Round-trip text of a number; NaN stays NaN (ParaView shows it as missing).
fn num(v: f64) -> String {
    crate::io::output::fmt_num(v)
}

/// The values of one data array.
pub(super) enum Values {
    F64(Vec<f64>),
    I64(Vec<i64>),
    I32(Vec<i32>),
    U8(Vec<u8>),
}

impl Values {
    fn type_name(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::I64(_) => "Int64",
            Values::I32(_) => "Int32",
            Values::U8(_) => "UInt8",
        }
    }
    fn n_bytes(&self) -> usize {
        match self {
            Values::F64(v) => 8 * v.len(),
            Values::I64(v) => 8 * v.len(),
            Values::I32(v) => 4 * v.len(),
            Values::U8(v) => v.len(),
        }
    }
    fn push_le(&self, out: &mut Vec<u8>) {
        match self {
            Values::F64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            Values::I64(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            Values::I32(v) => v
                .iter()
                .for_each(|x| out.extend_from_slice(&x.to_le_bytes())),
            Values::U8(v) => out.extend_from_slice(v),
        }
    }
    fn push_text(&self, out: &mut String, per_line: usize) {
        let per_line = per_line.max(1);
        let mut line = |k: usize, t: String| {
            out.push_str(&t);
            out.push(if (k + 1).is_multiple_of(per_line) {
                '\n'
            } else {
                ' '
            });
        };
        match self {
            Values::F64(v) => v.iter().enumerate().for_each(|(k, x)| line(k, num(*x))),
            Values::I64(v) => v
                .iter()
                .enumerate()
                .for_each(|(k, x)| line(k, x.to_string())),
            Values::I32(v) => v
                .iter()
                .enumerate()
                .for_each(|(k, x)| line(k, x.to_string())),
            Values::U8(v) => v
                .iter()
                .enumerate()
                .for_each(|(k, x)| line(k, x.to_string())),
        }
    }
}

/// A named data array with its number of components.
pub(super) struct Array {
    name: std::borrow::Cow<'static, str>,
    components: usize,
    values: Values,
}

impl Array {
    pub(super) fn new(
        name: impl Into<std::borrow::Cow<'static, str>>,
        components: usize,
        values: Values,
    ) -> Self {
        Array {
            name: name.into(),
            components,
            values,
        }
    }
}

/// The arrays of one `.vtu`: points, point data, cell data, cells.
pub(super) struct Grid {
    /// Attributes of `<PointData>` naming the active arrays.
    pub(super) active: String,
    pub(super) n_points: usize,
    pub(super) n_cells: usize,
    pub(super) points: Array,
    pub(super) point_data: Vec<Array>,
    pub(super) cell_data: Vec<Array>,
    pub(super) cells: Vec<Array>,
}

fn grid(mesh: &Mesh, view: &StepView) -> Grid {
    let nn = mesh.n_nodes();
    let nc = mesh.n_cells();
    let points = mesh.nodes.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
    let disp = (0..nn)
        .flat_map(|n| {
            let u = view.u(n);
            [u[0], u[1], 0.0]
        })
        .collect();
    let mut point_data = vec![Array::new("displacement", 3, Values::F64(disp))];
    if view.stress.len() == nn {
        let s33 = |n: usize| view.sigma_33.get(n).copied().unwrap_or(f64::NAN);
        let tensor = (0..nn)
            .flat_map(|n| {
                let [a, b, c] = view.stress[n];
                [a, c, 0.0, c, b, 0.0, 0.0, 0.0, s33(n)]
            })
            .collect();
        point_data.push(Array::new("cauchy_stress", 9, Values::F64(tensor)));
        let col = |f: &dyn Fn(usize) -> f64| Values::F64((0..nn).map(f).collect());
        point_data.push(Array::new(
            "max_shear_stress",
            1,
            col(&|n| view.stress_measure(n)),
        ));
        point_data.push(Array::new("sigma_11", 1, col(&|n| view.stress[n][0])));
        point_data.push(Array::new("sigma_22", 1, col(&|n| view.stress[n][1])));
        point_data.push(Array::new("sigma_12", 1, col(&|n| view.stress[n][2])));
        point_data.push(Array::new("sigma_33", 1, col(&s33)));
        point_data.push(Array::new(
            "pressure",
            1,
            col(&|n| -(view.stress[n][0] + view.stress[n][1] + s33(n)) / 3.0),
        ));
        if view.pressure.len() == nn {
            point_data.push(Array::new("pressure_field", 1, col(&|n| view.pressure[n])));
        }
        if view.stress_recovered.len() == nn {
            let tensor = view
                .stress_recovered
                .iter()
                .flat_map(|&[a, b, c, d]| [a, c, 0.0, c, b, 0.0, 0.0, 0.0, d])
                .collect();
            point_data.push(Array::new(
                "cauchy_stress_recovered",
                9,
                Values::F64(tensor),
            ));
        }
    }
    let mut cell_data = vec![
        Array::new("cell_id", 1, Values::I64((0..nc as i64).collect())),
        Array::new(
            "region",
            1,
            Values::I32(
                (0..nc)
                    .map(|c| mesh.regions.get(c).map_or(0, |&r| i32::from(r)))
                    .collect(),
            ),
        ),
    ];
    if view.error_indicator.len() == nc {
        cell_data.push(Array::new(
            "error_indicator",
            1,
            Values::F64(view.error_indicator.to_vec()),
        ));
    }
    let mut conn = Vec::with_capacity(9 * nc);
    let mut offsets = Vec::with_capacity(nc);
    let mut types = Vec::with_capacity(nc);
    for c in 0..nc {
        let (t, nodes) = vtk_cell(mesh, c);
        conn.extend(nodes.iter().map(|&n| i64::from(n)));
        offsets.push(conn.len() as i64);
        types.push(t);
    }
    Grid {
        active: " Scalars=\"max_shear_stress\" Vectors=\"displacement\" Tensors=\"cauchy_stress\""
            .to_string(),
        n_points: nn,
        n_cells: nc,
        points: Array::new("Points", 3, Values::F64(points)),
        point_data,
        cell_data,
        cells: vec![
            Array::new("connectivity", 1, Values::I64(conn)),
            Array::new("offsets", 1, Values::I64(offsets)),
            Array::new("types", 1, Values::U8(types)),
        ],
    }
}

/// How the arrays of a `.vtu` are written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Encoding {
    pub format: VtuFormat,
    /// Only for the binary format.
    pub compression: VtuCompression,
}

impl From<VtuFormat> for Encoding {
    fn from(format: VtuFormat) -> Self {
        Encoding {
            format,
            compression: VtuCompression::None,
        }
    }
}

/// The bytes of one `.vtu` file in the given encoding (a [`VtuFormat`] or an [`Encoding`]).
pub fn vtu_bytes(mesh: &Mesh, view: &StepView, time: f64, format: impl Into<Encoding>) -> Vec<u8> {
    grid_bytes(&grid(mesh, view), time, format.into())
}

/// The contact surface of a step as a closed chain of line segments through the contact sample points (in
/// the order of their reference angle θ) at their current positions (x1, x2, 0), with point
/// data `theta` (rad), `penetration` (length, > 0 in contact), `t_n` (normal traction on the
/// body, stress units, > 0 in compression), `t_t` (tangential traction, stress units),
/// `slip_velocity` (length/time) and `ds0` (reference length weight, length). `None` without
/// contact samples.
pub fn contact_vtu_bytes(
    samples: &[crate::contact::ContactSample],
    time: f64,
    format: impl Into<Encoding>,
) -> Option<Vec<u8>> {
    contact_grid(samples).map(|g| grid_bytes(&g, time, format.into()))
}

fn contact_grid(samples: &[crate::contact::ContactSample]) -> Option<Grid> {
    if samples.is_empty() {
        return None;
    }
    let mut order: Vec<usize> = (0..samples.len()).collect();
    order.sort_by(|&a, &b| samples[a].theta.total_cmp(&samples[b].theta));
    let pts = order
        .iter()
        .flat_map(|&k| [samples[k].x1, samples[k].x2, 0.0])
        .collect();
    let col = |f: &dyn Fn(&crate::contact::ContactSample) -> f64| {
        Values::F64(order.iter().map(|&k| f(&samples[k])).collect())
    };
    let n = samples.len() as i64;
    // Closed: segment k joins points k and k + 1, the last one back to point 0.
    let conn: Vec<i64> = (0..n).flat_map(|k| [k, (k + 1) % n]).collect();
    let g = Grid {
        active: " Scalars=\"t_n\"".to_string(),
        n_points: samples.len(),
        n_cells: samples.len(),
        points: Array::new("Points", 3, Values::F64(pts)),
        point_data: vec![
            Array::new("theta", 1, col(&|c| c.theta)),
            Array::new("penetration", 1, col(&|c| c.delta)),
            Array::new("t_n", 1, col(&|c| c.t_n)),
            Array::new("t_t", 1, col(&|c| c.t_t)),
            Array::new("slip_velocity", 1, col(&|c| c.w)),
            Array::new("ds0", 1, col(&|c| c.ds0)),
        ],
        cell_data: Vec::new(),
        cells: vec![
            Array::new("connectivity", 1, Values::I64(conn)),
            Array::new("offsets", 1, Values::I64((1..=n).map(|k| 2 * k).collect())),
            // VTK_LINE segments (read by every VTK reader, meshio included).
            Array::new("types", 1, Values::U8(vec![3; samples.len()])),
        ],
    };
    Some(g)
}

/// The appended bytes of one array compressed in zlib blocks (see the module docs), with the
/// UInt64 header.
fn zlib_blocks(raw: &[u8]) -> Vec<u8> {
    use std::io::Write as _;
    let blocks: Vec<Vec<u8>> = raw
        .chunks(ZLIB_BLOCK)
        .map(|b| {
            let mut z = flate2::write::ZlibEncoder::new(
                Vec::with_capacity(b.len() / 2 + 64),
                flate2::Compression::default(),
            );
            // Writing into a Vec cannot fail.
            let _ = z.write_all(b);
            z.finish().unwrap_or_default()
        })
        .collect();
    let mut out =
        Vec::with_capacity(8 * (3 + blocks.len()) + blocks.iter().map(Vec::len).sum::<usize>());
    out.extend_from_slice(&(blocks.len() as u64).to_le_bytes());
    out.extend_from_slice(&(ZLIB_BLOCK as u64).to_le_bytes());
    out.extend_from_slice(&((raw.len() % ZLIB_BLOCK) as u64).to_le_bytes());
    for b in &blocks {
        out.extend_from_slice(&(b.len() as u64).to_le_bytes());
    }
    for b in &blocks {
        out.extend_from_slice(b);
    }
    out
}

pub(super) fn grid_bytes(g: &Grid, time: f64, enc: Encoding) -> Vec<u8> {
    let binary = enc.format == VtuFormat::Binary;
    let zlib = binary && enc.compression == VtuCompression::Zlib;
    let mut s = String::with_capacity(if binary { 4096 } else { 200 * g.n_points });
    let mut blob: Vec<u8> = Vec::new();
    // One array: inline text, or a reference into the appended block.
    let mut array = |s: &mut String, a: &Array| {
        let name = if a.name == "Points" {
            String::new()
        } else {
            format!(" Name=\"{}\"", a.name)
        };
        let head = format!(
            "<DataArray type=\"{}\"{name} NumberOfComponents=\"{}\"",
            a.values.type_name(),
            a.components
        );
        if binary {
            let _ = writeln!(s, "{head} format=\"appended\" offset=\"{}\"/>", blob.len());
            if zlib {
                let mut raw = Vec::with_capacity(a.values.n_bytes());
                a.values.push_le(&mut raw);
                blob.extend_from_slice(&zlib_blocks(&raw));
            } else {
                blob.extend_from_slice(&(a.values.n_bytes() as u64).to_le_bytes());
                a.values.push_le(&mut blob);
            }
        } else {
            let _ = writeln!(s, "{head} format=\"ascii\">");
            a.values.push_text(s, a.components.max(1));
            s.push_str("</DataArray>\n");
        }
    };
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str(if zlib {
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">\n"
    } else {
        "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
    });
    s.push_str("<UnstructuredGrid>\n<FieldData>\n");
    let _ = writeln!(
        s,
        "<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>",
        num(time)
    );
    s.push_str("</FieldData>\n");
    let _ = writeln!(
        s,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        g.n_points, g.n_cells
    );
    s.push_str("<Points>\n");
    array(&mut s, &g.points);
    s.push_str("</Points>\n");
    let _ = writeln!(s, "<PointData{}>", g.active);
    for a in &g.point_data {
        array(&mut s, a);
    }
    s.push_str("</PointData>\n<CellData>\n");
    for a in &g.cell_data {
        array(&mut s, a);
    }
    s.push_str("</CellData>\n<Cells>\n");
    for a in &g.cells {
        array(&mut s, a);
    }
    s.push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n");
    let mut out = s.into_bytes();
    if binary {
        out.extend_from_slice(b"<AppendedData encoding=\"raw\">\n_");
        out.extend_from_slice(&blob);
        out.extend_from_slice(b"\n</AppendedData>\n");
    }
    out.extend_from_slice(b"</VTKFile>\n");
    out
}

/// The text of one `.vtu` file in the ASCII encoding.
pub fn vtu_text(mesh: &Mesh, view: &StepView, time: f64) -> String {
    String::from_utf8_lossy(&vtu_bytes(mesh, view, time, VtuFormat::Ascii)).into_owned()
}

/// The text of the `.pvd` collection.
pub fn pvd_text(entries: &[(f64, String)]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n",
    );
    for (t, f) in entries {
        let _ = writeln!(
            s,
            "<DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{f}\"/>",
            num(*t)
        );
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    s
}

impl Recorder for VtuSink {
    fn wants_view(&self, _info: &StepInfo) -> bool {
        self.error.is_none()
    }
    fn step(&mut self, info: &StepInfo, view: Option<&StepView>) {
        if let (Some(v), None) = (view, &self.error) {
            if let Err(e) = self.write_step(info, v) {
                self.error = Some(e);
            }
        }
    }
    fn steady_reached(&mut self, s: &SteadyReached, view: &StepView) {
        if let (Some(mesh), None) = (view.mesh, &self.error) {
            let path = self.dir.join("steady.vtu");
            let bytes = vtu_bytes(mesh, view, s.time, self.encoding());
            if let Err(e) = write_atomic(&path, &bytes) {
                self.error = Some(e);
            }
        }
    }
    fn run_finished(&mut self, _end: &RunEnd) -> Vec<RecordError> {
        self.error.take().into_iter().collect()
    }
}
