//! Gmsh `.msh` 4.1 import of hexahedral meshes (ASCII and binary) into a [`HexMesh`], with the
//! machinery and error style of the 2D reader [`super::gmsh`] (header check, `$PhysicalNames`,
//! node tags read from the file, errors naming the file).
//!
//! What is taken from the file:
//! * **cells**: the 3D elements, 8-node (Gmsh type 5) or 27-node (type 12) hexahedra, all of one
//!   kind. Gmsh numbers a hexahedron's nodes corners first (bottom face ζ = −1 counter-clockwise,
//!   then the top face), then the 12 edge nodes, the 6 face centres and the body centre; the
//!   cells here use the tensor order of [`crate::element::hex`] (node `i + m j + m² k`), so the
//!   nodes are permuted by [`GMSH_HEX8`] / [`GMSH_HEX27`] (tensor node a ↦ Gmsh node). Both
//!   tables are the match of the reference coordinates Gmsh reports for types 5 and 12
//!   (`gmsh.model.mesh.getElementProperties`) with the tensor nodes' ones. A cell with
//!   det(dX/dξ) ≤ 0 at a quadrature point is reported as inverted.
//! * **regions**: the 3D physical groups ([`GmshGroups::regions`]; empty: one region `"all"`).
//! * **named boundaries**: the 2D physical groups named by `hub` and `contact`: each of their
//!   quadrilaterals (type 3 or 10) must be a face of a cell. They become the facet sets `hub` and
//!   `outer` (cell, local face) and the node sets of all their faces' nodes.
//! * Nodes that no cell uses are dropped; the others keep the file's order. Coordinates are the
//!   reference position (X1, X2, X3) in the frame of [`super::hex_mesh`].
//!
//! Geometry: every cell is isoparametric ([`HexGeometry::Isoparametric`]).

use super::gmsh::{
    check_header, describe_parse_error, entity_physical_tags, node_tags, physical_group_tag,
    physical_names, GmshGroups, MeshError,
};
use super::hex_mesh::{HexFacet, HexGeometry, HexMesh};
use crate::element::hex::{face_nodes, Hex27, Hex8, QuadRule3D};
use mshio::mshfile::ElementType;
use nalgebra::Vector3;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

/// Tensor-order local node a ↦ Gmsh's local node of an 8-node hexahedron.
pub const GMSH_HEX8: [usize; 8] = [0, 1, 3, 2, 4, 5, 7, 6];
/// Tensor-order local node a ↦ Gmsh's local node of a 27-node hexahedron.
pub const GMSH_HEX27: [usize; 27] = [
    0, 8, 1, 9, 20, 11, 3, 13, 2, 10, 21, 12, 22, 26, 23, 15, 24, 14, 4, 16, 5, 17, 25, 18, 7, 19,
    6,
];

/// Read a hexahedral `.msh` 4.1 file (ASCII or binary) of at most
/// [`super::gmsh::MAX_MESH_BYTES`].
pub fn read_msh_hex(path: &Path, groups: &GmshGroups) -> Result<HexMesh, MeshError> {
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let bytes = super::gmsh::read_bounded(&abs, super::gmsh::MAX_MESH_BYTES)?;
    parse_msh_hex(&bytes, &abs.display().to_string(), groups)
}

/// Parse the bytes of a hexahedral `.msh` 4.1 file; `file` names it in errors.
pub fn parse_msh_hex(bytes: &[u8], file: &str, groups: &GmshGroups) -> Result<HexMesh, MeshError> {
    let err = |message: String| MeshError {
        file: file.to_string(),
        message,
    };
    check_header(bytes).map_err(&err)?;
    let names = physical_names(bytes).map_err(&err)?;
    let msh = mshio::parse_msh_bytes(bytes).map_err(|e| err(describe_parse_error(bytes, &e)))?;
    let tags = node_tags(bytes).map_err(&err)?;
    let data = &msh.data;
    let (Some(nodes), Some(elements)) = (&data.nodes, &data.elements) else {
        return Err(err(
            "no $Nodes or no $Elements section (is the file complete?)".into(),
        ));
    };
    let entity_groups = entity_physical_tags(data);
    let group_tag = |dim: i32, name: &str| physical_group_tag(&names, dim, name);
    if tags.len() != nodes.node_blocks.len() {
        return Err(err(format!(
            "$Nodes: {} node blocks parsed but {} read with their tags",
            nodes.node_blocks.len(),
            tags.len()
        )));
    }
    let mut node_index: HashMap<u64, usize> = HashMap::new();
    let mut coords: Vec<Vector3<f64>> = Vec::new();
    for (block, block_tags) in nodes.node_blocks.iter().zip(&tags) {
        if block_tags.len() != block.nodes.len() {
            return Err(err(format!(
                "$Nodes: a block of entity {} has {} tags for {} nodes",
                block.entity_tag,
                block_tags.len(),
                block.nodes.len()
            )));
        }
        for (n, &tag) in block.nodes.iter().zip(block_tags) {
            if !(n.x.is_finite() && n.y.is_finite() && n.z.is_finite()) {
                return Err(err(format!("node {tag} has a non-finite coordinate")));
            }
            if node_index.insert(tag, coords.len()).is_some() {
                return Err(err(format!(
                    "node tag {tag} is given to more than one node"
                )));
            }
            coords.push(Vector3::new(n.x, n.y, n.z));
        }
    }
    let lookup = |tag: u64, el: u64| -> Result<usize, String> {
        node_index.get(&tag).copied().ok_or_else(|| {
            format!("element {el} refers to node {tag}, which the file does not define")
        })
    };
    let mut degree: Option<usize> = None;
    let mut cells_file: Vec<Vec<usize>> = Vec::new();
    let mut cell_entity: Vec<i32> = Vec::new();
    let mut cell_tag: Vec<u64> = Vec::new();
    let mut quads: Vec<(i32, u64, [usize; 4])> = Vec::new(); // (entity, tag, corners)
    for block in &elements.element_blocks {
        match block.entity_dim {
            3 => {
                let (p, perm): (usize, &[usize]) = match block.element_type {
                    ElementType::Hex8 => (1, &GMSH_HEX8),
                    ElementType::Hex27 => (2, &GMSH_HEX27),
                    other => {
                        return Err(err(format!(
                            "unsupported element type {other:?} (Gmsh type {}) in volume {}: \
                             only 8-node (type 5) and 27-node (type 12) hexahedra are supported \
                             (mesh the volume transfinite and recombined, and for order 2 set \
                             Mesh.SecondOrderIncomplete = 0)",
                            other as u8, block.entity_tag
                        )))
                    }
                };
                match degree {
                    None => degree = Some(p),
                    Some(q) if q != p => {
                        return Err(err(format!(
                            "the mesh mixes 8-node and 27-node hexahedra (volume {}); use one \
                             order",
                            block.entity_tag
                        )))
                    }
                    _ => {}
                }
                for el in &block.elements {
                    if el.nodes.len() != perm.len() {
                        return Err(err(format!(
                            "element {} has {} nodes, expected {}",
                            el.element_tag,
                            el.nodes.len(),
                            perm.len()
                        )));
                    }
                    let mut v = Vec::with_capacity(perm.len());
                    for &g in perm {
                        v.push(lookup(el.nodes[g], el.element_tag).map_err(&err)?);
                    }
                    cells_file.push(v);
                    cell_entity.push(block.entity_tag);
                    cell_tag.push(el.element_tag);
                }
            }
            2 => match block.element_type {
                ElementType::Qua4 | ElementType::Qua9 => {
                    for el in &block.elements {
                        if el.nodes.len() < 4 {
                            return Err(err(format!(
                                "quadrilateral {} has fewer than 4 nodes",
                                el.element_tag
                            )));
                        }
                        let mut c = [0; 4];
                        for (slot, &t) in c.iter_mut().zip(&el.nodes[..4]) {
                            *slot = lookup(t, el.element_tag).map_err(&err)?;
                        }
                        quads.push((block.entity_tag, el.element_tag, c));
                    }
                }
                other => {
                    return Err(err(format!(
                        "unsupported surface element type {other:?} (Gmsh type {}) on surface \
                         {}: boundary faces must be 4- or 9-node quadrilaterals (types 3, 10)",
                        other as u8, block.entity_tag
                    )))
                }
            },
            _ => {}
        }
    }
    let Some(p) = degree else {
        return Err(err(
            "no 3D elements (hexahedra) in the file; with physical groups defined, Gmsh saves \
             only the elements of physical groups: put the volumes in a 3D physical group"
                .into(),
        ));
    };
    let n_cells = cells_file.len();
    let mut regions = vec![0u16; n_cells];
    let region_names = if groups.regions.is_empty() {
        vec!["all".to_string()]
    } else {
        let mut rt = Vec::new();
        for r in &groups.regions {
            rt.push(group_tag(3, r).map_err(&err)?);
        }
        for c in 0..n_cells {
            let phys = entity_groups
                .get(&(3, cell_entity[c]))
                .map(Vec::as_slice)
                .unwrap_or(&[]);
            let Some(k) = rt.iter().position(|t| phys.contains(t)) else {
                return Err(err(format!(
                    "element {} (volume {}) belongs to none of the material regions [{}]",
                    cell_tag[c],
                    cell_entity[c],
                    groups.regions.join(", ")
                )));
            };
            regions[c] = k as u16;
        }
        groups.regions.clone()
    };
    let mut new_index = vec![u32::MAX; coords.len()];
    let mut nodes_out = Vec::new();
    for cn in &cells_file {
        for &n in cn {
            new_index[n] = 0;
        }
    }
    for (i, slot) in new_index.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = nodes_out.len() as u32;
            nodes_out.push(coords[i]);
        }
    }
    let mut conn = Vec::with_capacity(n_cells * (p + 1).pow(3));
    let mut offsets = vec![0];
    for cn in &cells_file {
        conn.extend(cn.iter().map(|&n| new_index[n]));
        offsets.push(conn.len());
    }
    let mut mesh = HexMesh {
        nodes: nodes_out,
        conn,
        offsets,
        degree: vec![p as u8; n_cells],
        geometry: vec![HexGeometry::Isoparametric; n_cells],
        node_sets: BTreeMap::new(),
        facet_sets: BTreeMap::new(),
        rings: None,
        regions,
        region_names,
    };
    let rule = QuadRule3D::gauss_3d(p + 1);
    for (c, &tag) in cell_tag.iter().enumerate() {
        let bad = rule.points.iter().any(|x| {
            let d = mesh.map(c, *x).1.determinant();
            d <= 0.0 || d.is_nan()
        });
        if bad {
            return Err(err(format!(
                "element {} is inverted or degenerate: det(dX/dξ) <= 0 inside it",
                tag
            )));
        }
    }
    // Named boundaries: each cell face by its sorted corner nodes.
    let faces: Vec<Vec<usize>> = (0..6)
        .map(|f| {
            if p == 1 {
                face_nodes::<Hex8>(f)
            } else {
                face_nodes::<Hex27>(f)
            }
        })
        .collect();
    let m = p + 1;
    let corners = [0, p, p * m, p * m + p];
    let mut by_corners: HashMap<[u32; 4], HexFacet> = HashMap::new();
    for c in 0..n_cells {
        let cn = mesh.cell_nodes(c);
        for (f, fnodes) in faces.iter().enumerate() {
            let mut key = corners.map(|k| cn[fnodes[k]]);
            key.sort_unstable();
            by_corners.insert(
                key,
                HexFacet {
                    cell: c as u32,
                    face: f as u8,
                },
            );
        }
    }
    for (scene_key, set) in [("hub", &groups.hub), ("contact", &groups.contact)] {
        let tag =
            group_tag(2, set).map_err(|m| err(format!("{m} (named by [mesh] {scene_key})")))?;
        let mut facets = Vec::new();
        let mut seen = BTreeSet::new();
        for (entity, el_tag, q) in &quads {
            if !entity_groups
                .get(&(2, *entity))
                .is_some_and(|g| g.contains(&tag))
            {
                continue;
            }
            let mut key = q.map(|n| new_index[n]);
            key.sort_unstable();
            let Some(f) = by_corners.get(&key) else {
                return Err(err(format!(
                    "quadrilateral {el_tag} of physical group \"{set}\" is not a face of any \
                     hexahedron"
                )));
            };
            if seen.insert((f.cell, f.face)) {
                facets.push(*f);
            }
        }
        if facets.is_empty() {
            return Err(err(format!(
                "physical group \"{set}\" (named by [mesh] {scene_key}) has no quadrilaterals"
            )));
        }
        let mut ns: BTreeSet<u32> = BTreeSet::new();
        for f in &facets {
            let cn = mesh.cell_nodes(f.cell as usize);
            ns.extend(faces[f.face as usize].iter().map(|&a| cn[a]));
        }
        let name = if scene_key == "hub" { "hub" } else { "outer" };
        mesh.node_sets
            .insert(name.to_string(), ns.into_iter().collect());
        mesh.facet_sets.insert(name.to_string(), facets);
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::hex::{surface_map, FacetPoints, FacetRule3D, Lagrange3D};

    fn data(name: &str) -> String {
        format!("{}/tests/gmsh_data/{name}", env!("CARGO_MANIFEST_DIR"))
    }

    fn groups(regions: &[&str]) -> GmshGroups {
        GmshGroups {
            hub: "hub".into(),
            contact: "outer".into(),
            regions: regions.iter().map(|s| s.to_string()).collect(),
        }
    }

    fn volume(m: &HexMesh) -> f64 {
        let rule = QuadRule3D::gauss_3d(4);
        (0..m.n_cells())
            .map(|c| {
                rule.points
                    .iter()
                    .zip(&rule.weights)
                    .map(|(x, w)| w * m.map(c, *x).1.determinant())
                    .sum::<f64>()
            })
            .sum()
    }

    /// Facet area of a named set.
    fn area(m: &HexMesh, set: &str) -> f64 {
        let mut a = 0.0;
        for f in m.facet_set(set) {
            let fr = FacetRule3D::new(f.face as usize, 4, FacetPoints::Gauss);
            for (x, w) in fr.points.iter().zip(&fr.weights) {
                a += w * surface_map(&m.map(f.cell as usize, *x).1, f.face as usize).0;
            }
        }
        a
    }

    #[test]
    fn permutations_match_gmsh_reference_points() {
        // Gmsh's reference coordinates of the hexahedron nodes (types 5 and 12, as reported by
        // getElementProperties): corners, edges, face centres, centre.
        let gmsh27: [[i8; 3]; 27] = [
            [-1, -1, -1],
            [1, -1, -1],
            [1, 1, -1],
            [-1, 1, -1],
            [-1, -1, 1],
            [1, -1, 1],
            [1, 1, 1],
            [-1, 1, 1],
            [0, -1, -1],
            [-1, 0, -1],
            [-1, -1, 0],
            [1, 0, -1],
            [1, -1, 0],
            [0, 1, -1],
            [1, 1, 0],
            [-1, 1, 0],
            [0, -1, 1],
            [-1, 0, 1],
            [1, 0, 1],
            [0, 1, 1],
            [0, 0, -1],
            [0, -1, 0],
            [-1, 0, 0],
            [1, 0, 0],
            [0, 1, 0],
            [0, 0, 1],
            [0, 0, 0],
        ];
        for a in 0..27 {
            let r = Hex27::node_ref(a);
            assert_eq!(r, gmsh27[GMSH_HEX27[a]].map(f64::from), "node {a}");
        }
        for a in 0..8 {
            assert_eq!(
                Hex8::node_ref(a),
                gmsh27[GMSH_HEX8[a]].map(f64::from),
                "node {a}"
            );
        }
    }

    #[test]
    fn annular_segments_read_back() {
        // Quarter annulus 1 ≤ r ≤ 2 of width 0.5, 3 × 4 × 2 cells, nodes on the circles.
        let (ri, ro, w, nt) = (1.0f64, 2.0f64, 0.5, 4.0);
        let dt = std::f64::consts::FRAC_PI_2 / nt;
        // Hex8: straight chords, exact volume W · (n_θ/2) sin Δθ (ro² − ri²).
        let m8 = read_msh_hex(Path::new(&data("annular_hex8.msh")), &groups(&["body"])).unwrap();
        assert_eq!((m8.n_cells(), m8.n_nodes()), (24, 4 * 5 * 3));
        let v8 = w * 0.5 * nt * dt.sin() * (ro * ro - ri * ri);
        assert!(
            (volume(&m8) - v8).abs() < 1e-13 * v8,
            "{} vs {v8}",
            volume(&m8)
        );
        // Hex27: quadratic arcs; the volume approaches the exact one, π/4 (ro² − ri²) W.
        let m27 = read_msh_hex(Path::new(&data("annular_hex27.msh")), &groups(&[])).unwrap();
        assert_eq!(m27.n_nodes(), 7 * 9 * 5);
        let exact = std::f64::consts::FRAC_PI_4 * (ro * ro - ri * ri) * w;
        let e27 = (volume(&m27) - exact).abs() / exact;
        let e8 = (v8 - exact).abs() / exact;
        // Measured: the quadratic arc error is far below the chord error (ratio < 1e-2).
        assert!(e27 < 1e-2 * e8 && e27 < 1e-4, "e27 {e27:e}, e8 {e8:e}");
        for m in [&m8, &m27] {
            assert_eq!(
                m.region_names,
                if m.n_nodes() == 60 {
                    vec!["body"]
                } else {
                    vec!["all"]
                }
            );
            assert_eq!(m.facet_set("hub").len(), 8);
            assert_eq!(m.facet_set("outer").len(), 8);
            for &n in m.node_set("hub") {
                assert!((m.nodes[n as usize].xy().norm() - ri).abs() < 1e-12);
            }
            for &n in m.node_set("outer") {
                assert!((m.nodes[n as usize].xy().norm() - ro).abs() < 1e-12);
            }
            // Outward normals of the outer faces point radially outwards.
            for f in m.facet_set("outer") {
                let (x, j) = m.map(f.cell as usize, [1.0, 0.1, -0.3]);
                let (da, n) = surface_map(&j, f.face as usize);
                assert!(da > 0.0 && n.dot(&Vector3::new(x[0], x[1], 0.0).normalize()) > 0.99);
            }
        }
        // Hub area: the quarter cylinder r = 1 of width W (quadratic arcs: close, not exact).
        let a = area(&m27, "hub");
        let exact_a = std::f64::consts::FRAC_PI_2 * ri * w;
        assert!((a - exact_a).abs() < 1e-4 * exact_a, "{a} vs {exact_a}");
    }

    #[test]
    fn binary_box_hex27() {
        let m = read_msh_hex(Path::new(&data("box_hex27_bin.msh")), &groups(&["body"])).unwrap();
        assert_eq!(m.n_cells(), 8);
        assert!((volume(&m) - 1.0).abs() < 1e-14);
        assert!((area(&m, "hub") - 0.5).abs() < 1e-14);
        assert!((area(&m, "outer") - 0.5).abs() < 1e-14);
        for &n in m.node_set("outer") {
            assert_eq!(m.nodes[n as usize][0], 2.0);
        }
    }

    #[test]
    fn clear_errors() {
        let bytes = std::fs::read(data("annular_hex8.msh")).unwrap();
        let cut = &bytes[..bytes.len() * 2 / 3];
        let e = parse_msh_hex(cut, "cut.msh", &groups(&[])).unwrap_err();
        assert!(e.to_string().starts_with("mesh file cut.msh: "), "{e}");
        let e = read_msh_hex(Path::new(&data("tet_box.msh")), &groups(&[])).unwrap_err();
        assert!(
            e.message.contains("unsupported element type") && e.message.contains("type 4"),
            "{e}"
        );
        let e = read_msh_hex(
            Path::new(&data("annular_hex8.msh")),
            &GmshGroups {
                hub: "axle".into(),
                ..groups(&[])
            },
        )
        .unwrap_err();
        assert!(
            e.message.contains("no 2D physical group named \"axle\""),
            "{e}"
        );
        let e =
            read_msh_hex(Path::new(&data("annular_hex8.msh")), &groups(&["rubber"])).unwrap_err();
        assert!(e.message.contains("\"rubber\""), "{e}");
    }
}
