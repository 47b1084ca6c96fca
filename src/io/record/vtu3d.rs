//! VTU writer for hexahedral meshes ([`HexMesh`]): one VTK XML unstructured grid with the
//! reference node positions, the displacement and the given point and cell fields, in the
//! encodings of the 2D writer ([`super::vtu`]: `binary` raw appended data, optionally zlib
//! blocks, or `ascii`).
//!
//! Cells: VTK_HEXAHEDRON (12) for Hex8, VTK_TRIQUADRATIC_HEXAHEDRON (29) for Hex27. The local
//! node `a = i + m·j + m²·k` of [`crate::element::hex`] is permuted to VTK's order
//! ([`VTK_HEX8`], [`VTK_HEX27`]): corners counter-clockwise on ζ = −1 then on ζ = +1, the edge
//! midpoints of ζ = −1, of ζ = +1, the vertical edges, the face centres ξ = −1, ξ = +1, η = −1,
//! η = +1, ζ = −1, ζ = +1, and the centre (VTK's parametric coordinates (r, s, t) = (ξ, η, ζ)
//! mapped to [0, 1]).
//!
//! Point data: `displacement` (3 components, length) and every [`Field3D`]: scalars (1),
//! vectors (3), tensors written as 9 components row-major 3×3 (a symmetric tensor is given in
//! Voigt order `[11, 22, 33, 23, 13, 12]` and expanded). Cell data: `cell_id` (Int64), `region`
//! (Int32) and the cell fields. The field data `TimeValue` is the time.

use super::vtu::{grid_bytes, Array, Encoding, Grid, Values};
use crate::mesh::hex_mesh::HexMesh;

/// VTK node `k` of a Hex8 cell is local node `VTK_HEX8[k]`.
pub const VTK_HEX8: [usize; 8] = [0, 1, 3, 2, 4, 5, 7, 6];

/// VTK node `k` of a Hex27 cell (VTK_TRIQUADRATIC_HEXAHEDRON) is local node `VTK_HEX27[k]`.
pub const VTK_HEX27: [usize; 27] = [
    0, 2, 8, 6, 18, 20, 26, 24, // corners
    1, 5, 7, 3, // edges of ζ = −1
    19, 23, 25, 21, // edges of ζ = +1
    9, 11, 17, 15, // edges along ζ
    12, 14, 10, 16, 4, 22, // face centres ξ−, ξ+, η−, η+, ζ−, ζ+
    13, // centre
];

/// How the values of a field are laid out (per node or per cell, entity-major).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldKind {
    /// One value.
    Scalar,
    /// Three components (x1, x2, x3).
    Vector,
    /// Symmetric tensor, 6 values in Voigt order `[11, 22, 33, 23, 13, 12]`.
    SymTensor,
    /// Full tensor, 9 values row-major.
    Tensor,
}

impl FieldKind {
    /// Values per entity.
    pub fn components(self) -> usize {
        match self {
            FieldKind::Scalar => 1,
            FieldKind::Vector => 3,
            FieldKind::SymTensor => 6,
            FieldKind::Tensor => 9,
        }
    }
}

/// A named field of a 3D result, per node or per cell.
#[derive(Clone, Copy, Debug)]
pub struct Field3D<'a> {
    /// Array name (letters, digits, `_`, `-`, `.`).
    pub name: &'a str,
    pub kind: FieldKind,
    /// `kind.components()` values per entity, entity-major.
    pub values: &'a [f64],
    /// Unit of the values (shown in viewers), e.g. `"psi"`; may be empty.
    pub unit: &'a str,
}

impl<'a> Field3D<'a> {
    pub fn scalar(name: &'a str, values: &'a [f64], unit: &'a str) -> Self {
        Self {
            name,
            kind: FieldKind::Scalar,
            values,
            unit,
        }
    }
    pub fn vector(name: &'a str, values: &'a [f64], unit: &'a str) -> Self {
        Self {
            name,
            kind: FieldKind::Vector,
            values,
            unit,
        }
    }
    pub fn sym_tensor(name: &'a str, values: &'a [f64], unit: &'a str) -> Self {
        Self {
            name,
            kind: FieldKind::SymTensor,
            values,
            unit,
        }
    }
}

/// Bad input to the 3D writers.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HexOutputError {
    #[error("field `{name}`: {got} values, expected {expected}")]
    FieldLength {
        name: String,
        expected: usize,
        got: usize,
    },
    #[error(
        "field name `{0}` is empty or holds characters other than letters, digits, `_`, `-`, `.`"
    )]
    FieldName(String),
    #[error("cell {cell} has degree {degree}; only 1 (Hex8) and 2 (Hex27) are written")]
    Degree { cell: usize, degree: u8 },
}

/// Check a field's name and length against `n` entities.
pub fn check_field(f: &Field3D, n: usize) -> Result<(), HexOutputError> {
    let ok = !f.name.is_empty()
        && f.name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
    if !ok {
        return Err(HexOutputError::FieldName(f.name.to_string()));
    }
    let expected = n * f.kind.components();
    if f.values.len() != expected {
        return Err(HexOutputError::FieldLength {
            name: f.name.to_string(),
            expected,
            got: f.values.len(),
        });
    }
    Ok(())
}

/// The VTK cell type and node order of cell `c`.
fn vtk_cell(mesh: &HexMesh, c: usize) -> Result<(u8, Vec<i64>), HexOutputError> {
    let nodes = mesh.cell_nodes(c);
    let (t, perm): (u8, &[usize]) = match (mesh.degree[c], nodes.len()) {
        (1, 8) => (12, &VTK_HEX8),
        (2, 27) => (29, &VTK_HEX27),
        (d, _) => return Err(HexOutputError::Degree { cell: c, degree: d }),
    };
    Ok((t, perm.iter().map(|&a| i64::from(nodes[a])).collect()))
}

/// The values of a field as written: tensors as 9 components row-major.
fn vtk_values(f: &Field3D) -> (usize, Vec<f64>) {
    match f.kind {
        FieldKind::SymTensor => (
            9,
            f.values
                .chunks_exact(6)
                .flat_map(|v| [v[0], v[5], v[4], v[5], v[1], v[3], v[4], v[3], v[2]])
                .collect(),
        ),
        k => (k.components(), f.values.to_vec()),
    }
}

/// The bytes of the `.vtu` of a hexahedral mesh with displacement `u` (3 per node,
/// node-major), point fields (per node) and cell fields (per cell), at `time`.
pub fn hex_vtu_bytes(
    mesh: &HexMesh,
    u: &[f64],
    point_fields: &[Field3D],
    cell_fields: &[Field3D],
    time: f64,
    encoding: impl Into<Encoding>,
) -> Result<Vec<u8>, HexOutputError> {
    let nn = mesh.n_nodes();
    let nc = mesh.n_cells();
    check_field(&Field3D::vector("displacement", u, ""), nn)?;
    for f in point_fields {
        check_field(f, nn)?;
    }
    for f in cell_fields {
        check_field(f, nc)?;
    }
    let mut active = String::from(" Vectors=\"displacement\"");
    if let Some(f) = point_fields.iter().find(|f| f.kind == FieldKind::Scalar) {
        active.push_str(&format!(" Scalars=\"{}\"", f.name));
    }
    if let Some(f) = point_fields
        .iter()
        .find(|f| matches!(f.kind, FieldKind::SymTensor | FieldKind::Tensor))
    {
        active.push_str(&format!(" Tensors=\"{}\"", f.name));
    }
    let mut point_data = vec![Array::new("displacement", 3, Values::F64(u.to_vec()))];
    for f in point_fields {
        let (k, v) = vtk_values(f);
        point_data.push(Array::new(f.name.to_string(), k, Values::F64(v)));
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
    for f in cell_fields {
        let (k, v) = vtk_values(f);
        cell_data.push(Array::new(f.name.to_string(), k, Values::F64(v)));
    }
    let mut conn = Vec::with_capacity(mesh.conn.len());
    let mut offsets = Vec::with_capacity(nc);
    let mut types = Vec::with_capacity(nc);
    for c in 0..nc {
        let (t, nodes) = vtk_cell(mesh, c)?;
        conn.extend(nodes);
        offsets.push(conn.len() as i64);
        types.push(t);
    }
    let g = Grid {
        active,
        n_points: nn,
        n_cells: nc,
        points: Array::new(
            "Points",
            3,
            Values::F64(mesh.nodes.iter().flat_map(|p| [p.x, p.y, p.z]).collect()),
        ),
        point_data,
        cell_data,
        cells: vec![
            Array::new("connectivity", 1, Values::I64(conn)),
            Array::new("offsets", 1, Values::I64(offsets)),
            Array::new("types", 1, Values::U8(types)),
        ],
    };
    Ok(grid_bytes(&g, time, encoding.into()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hex::{Hex27, Hex8, Lagrange3D};
    use crate::io::record::vtu::VtuFormat;
    use crate::mesh::revolved::{revolved, RevolvedSpec};

    /// VTK's parametric coordinates (r, s, t) ∈ [0, 1]³ of the nodes of
    /// VTK_TRIQUADRATIC_HEXAHEDRON, in VTK's node order (vtkTriQuadraticHexahedron); the first
    /// 8 are those of VTK_HEXAHEDRON.
    const VTK_PCOORDS_29: [[f64; 3]; 27] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [0.0, 1.0, 1.0],
        [0.5, 0.0, 0.0],
        [1.0, 0.5, 0.0],
        [0.5, 1.0, 0.0],
        [0.0, 0.5, 0.0],
        [0.5, 0.0, 1.0],
        [1.0, 0.5, 1.0],
        [0.5, 1.0, 1.0],
        [0.0, 0.5, 1.0],
        [0.0, 0.0, 0.5],
        [1.0, 0.0, 0.5],
        [1.0, 1.0, 0.5],
        [0.0, 1.0, 0.5],
        [0.0, 0.5, 0.5],
        [1.0, 0.5, 0.5],
        [0.5, 0.0, 0.5],
        [0.5, 1.0, 0.5],
        [0.5, 0.5, 0.0],
        [0.5, 0.5, 1.0],
        [0.5, 0.5, 0.5],
    ];

    #[test]
    fn permutations_match_vtk_parametric_coordinates() {
        let to_ref = |p: [f64; 3]| p.map(|x| 2.0 * x - 1.0);
        for (k, &a) in VTK_HEX27.iter().enumerate() {
            assert_eq!(
                Hex27::node_ref(a),
                to_ref(VTK_PCOORDS_29[k]),
                "Hex27 node {k}"
            );
        }
        for (k, &a) in VTK_HEX8.iter().enumerate() {
            assert_eq!(
                Hex8::node_ref(a),
                to_ref(VTK_PCOORDS_29[k]),
                "Hex8 node {k}"
            );
        }
        let mut s = VTK_HEX27.to_vec();
        s.sort_unstable();
        assert_eq!(s, (0..27).collect::<Vec<_>>());
    }

    /// The text between `<tag` … `>` and `</DataArray>` of the array named `name`.
    fn ascii_array(text: &str, name: &str) -> (String, Vec<f64>) {
        let key = format!("Name=\"{name}\"");
        let at = text.find(&key).unwrap();
        let start = text[..at].rfind("<DataArray").unwrap();
        let head_end = start + text[start..].find('>').unwrap();
        let end = head_end + text[head_end..].find("</DataArray>").unwrap();
        let head = text[start..head_end].to_string();
        let vals = text[head_end + 1..end]
            .split_whitespace()
            .map(|t| t.parse::<f64>().unwrap())
            .collect();
        (head, vals)
    }

    #[test]
    fn hex_vtu_ascii_parses_back() {
        for p in [1usize, 2] {
            let m = revolved(&RevolvedSpec {
                ri: 1.0,
                ro: 2.0,
                width: 0.5,
                n_r: 1,
                n_z: 2,
                n_theta: 6,
                degree: p,
                grading_r: 1.0,
                grading_theta: 0.0,
                theta_ratio: 1.0,
                grading_z: 1.0,
                half_width: false,
                crown_radius: None,
            })
            .unwrap();
            let nn = m.n_nodes();
            let u: Vec<f64> = m
                .nodes
                .iter()
                .flat_map(|x| [0.01 * x.y, 0.0, 0.0])
                .collect();
            let vm: Vec<f64> = m.nodes.iter().map(|x| x.norm()).collect();
            let sig: Vec<f64> = (0..nn)
                .flat_map(|n| [1.0, 2.0, 3.0, 4.0, 5.0, 6.0].map(|v| v * n as f64))
                .collect();
            let fields = [
                Field3D::scalar("von_mises", &vm, "psi"),
                Field3D::sym_tensor("cauchy_stress", &sig, "psi"),
            ];
            let cf: Vec<f64> = (0..m.n_cells()).map(|c| c as f64 * 0.5).collect();
            let cells = [Field3D::scalar("cell_value", &cf, "")];
            let b = hex_vtu_bytes(&m, &u, &fields, &cells, 0.25, VtuFormat::Ascii).unwrap();
            let t = String::from_utf8(b).unwrap();
            assert!(!t.contains("NaN"));
            assert!(t.contains(&format!(
                "<Piece NumberOfPoints=\"{nn}\" NumberOfCells=\"{}\">",
                m.n_cells()
            )));
            let (_, types) = ascii_array(&t, "types");
            let ty = if p == 1 { 12.0 } else { 29.0 };
            assert_eq!(types, vec![ty; m.n_cells()]);
            let (_, offs) = ascii_array(&t, "offsets");
            let npc = (p + 1).pow(3) as f64;
            assert_eq!(offs.last().copied(), Some(npc * m.n_cells() as f64));
            let (_, conn) = ascii_array(&t, "connectivity");
            assert!(conn.iter().all(|&c| c >= 0.0 && c < nn as f64));
            let (head, s) = ascii_array(&t, "cauchy_stress");
            assert!(head.contains("NumberOfComponents=\"9\""));
            // Node 1: Voigt [1, 2, 3, 4, 5, 6] → [[1, 6, 5], [6, 2, 4], [5, 4, 3]].
            assert_eq!(&s[9..18], &[1.0, 6.0, 5.0, 6.0, 2.0, 4.0, 5.0, 4.0, 3.0]);
            let (_, v) = ascii_array(&t, "von_mises");
            let (lo, hi) = v
                .iter()
                .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
            assert!((lo - 1.0).abs() < 1e-12 && hi <= (4.0f64 + 0.0625).sqrt() + 1e-12);
            let (_, c) = ascii_array(&t, "cell_value");
            assert_eq!(c, cf);
            let (head, d) = ascii_array(&t, "displacement");
            assert!(head.contains("NumberOfComponents=\"3\""));
            assert_eq!(d, u);
            // Binary and zlib are accepted and differ from the text.
            let z = hex_vtu_bytes(
                &m,
                &u,
                &fields,
                &cells,
                0.25,
                Encoding {
                    format: VtuFormat::Binary,
                    compression: crate::io::record::vtu::VtuCompression::Zlib,
                },
            )
            .unwrap();
            assert!(String::from_utf8_lossy(&z).contains("vtkZLibDataCompressor"));
        }
    }

    #[test]
    fn bad_fields_are_reported() {
        let m = revolved(&RevolvedSpec {
            ri: 1.0,
            ro: 2.0,
            width: 0.5,
            n_r: 1,
            n_z: 1,
            n_theta: 4,
            degree: 1,
            grading_r: 1.0,
            grading_theta: 0.0,
            theta_ratio: 1.0,
            grading_z: 1.0,
            half_width: false,
            crown_radius: None,
        })
        .unwrap();
        let u = vec![0.0; 3 * m.n_nodes()];
        let short = vec![0.0; 2];
        let r = hex_vtu_bytes(
            &m,
            &u,
            &[Field3D::scalar("a", &short, "")],
            &[],
            0.0,
            VtuFormat::Ascii,
        );
        assert!(matches!(r, Err(HexOutputError::FieldLength { .. })));
        let ok = vec![0.0; m.n_nodes()];
        let r = hex_vtu_bytes(
            &m,
            &u,
            &[Field3D::scalar("a\"b", &ok, "")],
            &[],
            0.0,
            VtuFormat::Ascii,
        );
        assert!(matches!(r, Err(HexOutputError::FieldName(_))));
    }
}
