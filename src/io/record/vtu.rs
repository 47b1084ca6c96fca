//! VTU/PVD sink (ParaView): one unstructured-grid file per recorded step,
//! `fields/step_NNNNNN.vtu`, listed with its time in `fields.pvd` (rewritten atomically after
//! every step, so an interrupted run leaves a valid series), and `steady.vtu` for a steady
//! state.
//!
//! Each `.vtu` (ASCII, VTK XML 1.0) holds the **reference** node positions (z = 0) and, as point
//! data, `displacement` (3 components, z = 0: use ParaView's *Warp By Vector* to see the deformed
//! body), `max_shear_stress` (the stress measure, see [`super::stress_measure`]) and the nodal
//! Cauchy stresses `sigma_11`, `sigma_22`, `sigma_12`; cells are VTK_BIQUADRATIC_QUAD (28) for
//! Q2 and VTK_QUAD (9) for Q1; the field data `TimeValue` is the step's time. Numbers are
//! written as the shortest text that reads back exactly; non-finite values as `NaN`/`inf`.

use super::{RecordError, Recorder, RunEnd, SteadyReached, StepInfo, StepView};
use crate::mesh::Mesh;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

pub struct VtuSink {
    dir: PathBuf,
    /// (time, file name relative to `dir`) of every written step.
    written: Vec<(f64, String)>,
    error: Option<RecordError>,
}

impl VtuSink {
    /// Writes into `dir` (`fields.pvd`, `fields/`, `steady.vtu`).
    pub fn new(dir: &Path) -> Self {
        Self {
            dir: dir.to_path_buf(),
            written: Vec::new(),
            error: None,
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
        write_atomic(&path, &vtu_text(mesh, view, info.time))?;
        self.written.push((info.time, name));
        let pvd = self.dir.join("fields.pvd");
        write_atomic(&pvd, &pvd_text(&self.written))
    }
}

fn write_atomic(path: &Path, text: &str) -> Result<(), RecordError> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text).map_err(|e| RecordError::new("vtu", &tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| RecordError::new("vtu", path, e))
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

/// The text of one `.vtu` file.
pub fn vtu_text(mesh: &Mesh, view: &StepView, time: f64) -> String {
    let nn = mesh.n_nodes();
    let nc = mesh.n_cells();
    let mut s = String::with_capacity(200 * nn);
    s.push_str("<?xml version=\"1.0\"?>\n");
    s.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n");
    s.push_str("<UnstructuredGrid>\n<FieldData>\n");
    let _ = writeln!(
        s,
        "<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>",
        num(time)
    );
    s.push_str("</FieldData>\n");
    let _ = writeln!(s, "<Piece NumberOfPoints=\"{nn}\" NumberOfCells=\"{nc}\">");
    s.push_str(
        "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n",
    );
    for p in &mesh.nodes {
        let _ = writeln!(s, "{} {} 0", num(p[0]), num(p[1]));
    }
    s.push_str("</DataArray>\n</Points>\n");
    s.push_str("<PointData Scalars=\"max_shear_stress\" Vectors=\"displacement\">\n");
    s.push_str("<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for n in 0..nn {
        let u = view.u(n);
        let _ = writeln!(s, "{} {} 0", num(u[0]), num(u[1]));
    }
    s.push_str("</DataArray>\n");
    if view.stress.len() == nn {
        let arrays: [(&str, &dyn Fn(usize) -> f64); 4] = [
            ("max_shear_stress", &|n| view.stress_measure(n)),
            ("sigma_11", &|n| view.stress[n][0]),
            ("sigma_22", &|n| view.stress[n][1]),
            ("sigma_12", &|n| view.stress[n][2]),
        ];
        for (name, f) in arrays {
            let _ = writeln!(
                s,
                "<DataArray type=\"Float64\" Name=\"{name}\" format=\"ascii\">"
            );
            for n in 0..nn {
                let _ = writeln!(s, "{}", num(f(n)));
            }
            s.push_str("</DataArray>\n");
        }
    }
    s.push_str("</PointData>\n<Cells>\n");
    let mut offsets = Vec::with_capacity(nc);
    let mut types = Vec::with_capacity(nc);
    s.push_str("<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    let mut off = 0usize;
    for c in 0..nc {
        let (t, nodes) = vtk_cell(mesh, c);
        let line: Vec<String> = nodes.iter().map(|n| n.to_string()).collect();
        let _ = writeln!(s, "{}", line.join(" "));
        off += nodes.len();
        offsets.push(off);
        types.push(t);
    }
    s.push_str("</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for o in offsets {
        let _ = writeln!(s, "{o}");
    }
    s.push_str("</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for t in types {
        let _ = writeln!(s, "{t}");
    }
    s.push_str("</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    s
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
            if let Err(e) = write_atomic(&path, &vtu_text(mesh, view, s.time)) {
                self.error = Some(e);
            }
        }
    }
    fn run_finished(&mut self, _end: &RunEnd) -> Vec<RecordError> {
        self.error.take().into_iter().collect()
    }
}
