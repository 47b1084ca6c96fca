//! Gmsh `.msh` 4.1 import (ASCII and binary; parsed by the `mshio` crate, the
//! `$PhysicalNames` section read here).
//!
//! What is taken from the file:
//! * **cells**: the 2D elements, 4-node (Gmsh type 3) or 9-node (type 10) quadrilaterals, all of
//!   one kind. Gmsh numbers a quadrilateral's nodes corners first (counter-clockwise), then the
//!   mid-side nodes (side 0–1, 1–2, 2–3, 3–0), then the centre; the cells here use the
//!   tensor-product order of [`crate::element`] (node `i + (p + 1) j`, i along ξ, j along η), so
//!   the nodes are permuted by [`GMSH_Q1`] / [`GMSH_Q2`]. A cell whose corners run clockwise
//!   (surface normal along −x3) gets ξ and η swapped so that det(dX/dξ) > 0; a cell with
//!   det(dX/dξ) ≤ 0 at a quadrature point after that is reported as inverted.
//! * **regions**: the 2D physical groups. With one material every cell is used (one region
//!   `"all"`); with a material per region every cell must belong to one of the named groups.
//! * **named boundaries**: the 1D physical groups named by the scene (`[mesh] hub`, `[mesh]
//!   contact`): each of their line elements (type 1 or 8) must be a side of a cell. They become
//!   the facet and node sets `hub` (bonded to the rigid hub) and `outer` (contact with the road).
//!   The node sets hold every node of the cells' sides (mid-side nodes included).
//! * Nodes that no cell uses (geometry points, …) are dropped; the others keep the file's order.
//!   Coordinates x, y are the reference position X1, X2 (z must be 0).
//!
//! Geometry: every cell is isoparametric ([`CellGeometry::Isoparametric`]): 9-node cells follow
//! curved boundaries as well as the file's mid-side nodes do.
//!
//! Node tags: every node is identified by the tag the file gives it, in whatever order the blocks
//! list them (a file that lists its nodes in another order is the same mesh). The tags are read
//! here from the `$Nodes` section (`node_tags`), not taken from mshio, which keeps them only when
//! they are not contiguous. A tag given twice is an error.
//!
//! Every count, size and tag in the file is checked against what follows it before anything is
//! allocated for it: a malformed count gives an error naming the section, never an abort.

use super::{CellGeometry, Facet, Mesh};
use crate::element::{Lagrange2D, ShapeTable, Q1, Q2};
use crate::math::{Mat2, Vec2};
use mshio::mshfile::ElementType;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

/// Tensor-order local node a ↦ Gmsh's local node of a 4-node quadrilateral.
pub const GMSH_Q1: [usize; 4] = [0, 1, 3, 2];
/// Tensor-order local node a ↦ Gmsh's local node of a 9-node quadrilateral.
pub const GMSH_Q2: [usize; 9] = [0, 4, 1, 7, 8, 5, 3, 6, 2];

/// A problem with a mesh file, naming the file and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("mesh file {file}: {message}")]
pub struct MeshError {
    pub file: String,
    pub message: String,
}

/// Which physical groups of the file the model uses.
#[derive(Clone, Debug, Default)]
pub struct GmshGroups {
    /// 1D group bonded to the hub.
    pub hub: String,
    /// 1D group where contact with the road can happen.
    pub contact: String,
    /// 2D groups, one per material, in the order of the scene's materials. Empty: one material,
    /// every cell in region 0.
    pub regions: Vec<String>,
}

/// The largest mesh file read, in bytes (1 GiB: a 3D hexahedral mesh of several million nodes in
/// ASCII). Larger files, and endless ones such as `/dev/zero`, are refused before they fill memory.
pub const MAX_MESH_BYTES: u64 = 1 << 30;

/// Read a `.msh` 4.1 file (ASCII or binary) of at most [`MAX_MESH_BYTES`]. Errors name the file
/// by its absolute path (what a relative `mesh.file` resolved to).
pub fn read_msh(path: &Path, groups: &GmshGroups) -> Result<Mesh, MeshError> {
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let bytes = read_bounded(&abs, MAX_MESH_BYTES)?;
    parse_msh(&bytes, &abs.display().to_string(), groups)
}

/// The bytes of a file of at most `limit` bytes; a directory, an unreadable or a larger file is
/// an error naming the path.
pub fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>, MeshError> {
    use std::io::Read;
    let err = |message: String| MeshError {
        file: path.display().to_string(),
        message,
    };
    let f = std::fs::File::open(path).map_err(|e| err(format!("cannot read: {e}")))?;
    let meta = f.metadata().map_err(|e| err(format!("cannot read: {e}")))?;
    if meta.is_dir() {
        return Err(err("is a directory, not a mesh file".into()));
    }
    if meta.len() > limit {
        return Err(err(format!(
            "is {} bytes, more than the {limit} bytes a mesh file may have",
            meta.len()
        )));
    }
    let mut bytes = Vec::new();
    f.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| err(format!("cannot read: {e}")))?;
    if bytes.len() as u64 > limit {
        return Err(err(format!(
            "holds more than the {limit} bytes a mesh file may have (is it a device or a \
             stream?)"
        )));
    }
    Ok(bytes)
}

/// Parse the bytes of a `.msh` 4.1 file; `file` names it in errors.
pub fn parse_msh(bytes: &[u8], file: &str, groups: &GmshGroups) -> Result<Mesh, MeshError> {
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

    // Node coordinates by tag.
    if tags.len() != nodes.node_blocks.len() {
        return Err(err(format!(
            "$Nodes: {} node blocks parsed but {} read with their tags",
            nodes.node_blocks.len(),
            tags.len()
        )));
    }
    let mut node_index: HashMap<u64, usize> = HashMap::new();
    let mut coords: Vec<Vec2> = Vec::new();
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
            if n.z.abs() > 1e-9 * (n.x.abs() + n.y.abs()).max(1.0) {
                return Err(err(format!(
                    "node {tag} at ({}, {}, {}) is not in the plane z = 0 (a 2D mesh in x, y is \
                     needed)",
                    n.x, n.y, n.z
                )));
            }
            if node_index.insert(tag, coords.len()).is_some() {
                return Err(err(format!(
                    "node tag {tag} is given to more than one node"
                )));
            }
            coords.push(Vec2::new(n.x, n.y));
        }
    }

    // Cells.
    let mut degree: Option<usize> = None;
    let mut cell_nodes_file: Vec<Vec<usize>> = Vec::new(); // tensor order, file node indices
    let mut cell_entity: Vec<i32> = Vec::new();
    let mut cell_tag: Vec<u64> = Vec::new();
    let mut lines: Vec<(i32, u64, [usize; 2])> = Vec::new(); // (entity, tag, corner nodes)
    let lookup = |tag: u64, el: u64| -> Result<usize, String> {
        node_index.get(&tag).copied().ok_or_else(|| {
            format!("element {el} refers to node {tag}, which the file does not define")
        })
    };
    // The $Elements header's claims, against its blocks.
    let n_elements: u64 = elements
        .element_blocks
        .iter()
        .map(|b| b.elements.len() as u64)
        .sum();
    if n_elements != elements.num_elements {
        return Err(err(format!(
            "$Elements announces {} elements, its blocks hold {n_elements}",
            elements.num_elements
        )));
    }
    let tags = || {
        elements
            .element_blocks
            .iter()
            .flat_map(|b| b.elements.iter().map(|e| e.element_tag))
    };
    if let (Some(lo), Some(hi)) = (tags().min(), tags().max()) {
        if (lo, hi) != (elements.min_element_tag, elements.max_element_tag) {
            return Err(err(format!(
                "$Elements announces element tags {} to {}, its blocks hold tags {lo} to {hi}",
                elements.min_element_tag, elements.max_element_tag
            )));
        }
    }
    for block in &elements.element_blocks {
        match block.entity_dim {
            2 => {
                let (p, perm): (usize, &[usize]) = match block.element_type {
                    ElementType::Qua4 => (1, &GMSH_Q1),
                    ElementType::Qua9 => (2, &GMSH_Q2),
                    other => {
                        return Err(err(format!(
                            "unsupported element type {other:?} (Gmsh type {}) in surface {}: \
                             only 4-node (type 3) and 9-node (type 10) quadrilaterals are \
                             supported (recombine the mesh into quadrilaterals, and for order 2 \
                             set Mesh.SecondOrderIncomplete = 0)",
                            other as u8, block.entity_tag
                        )))
                    }
                };
                match degree {
                    None => degree = Some(p),
                    Some(q) if q != p => {
                        return Err(err(format!(
                            "the mesh mixes 4-node and 9-node quadrilaterals (surface {}); use one order",
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
                    cell_nodes_file.push(v);
                    cell_entity.push(block.entity_tag);
                    cell_tag.push(el.element_tag);
                }
            }
            1 => match block.element_type {
                ElementType::Lin2 | ElementType::Lin3 => {
                    for el in &block.elements {
                        if el.nodes.len() < 2 {
                            return Err(err(format!(
                                "line element {} has fewer than 2 nodes",
                                el.element_tag
                            )));
                        }
                        let a = lookup(el.nodes[0], el.element_tag).map_err(&err)?;
                        let b = lookup(el.nodes[1], el.element_tag).map_err(&err)?;
                        lines.push((block.entity_tag, el.element_tag, [a, b]));
                    }
                }
                other => {
                    return Err(err(format!(
                        "unsupported line element type {other:?} (Gmsh type {}) on curve {}: \
                         boundary lines must have 2 or 3 nodes (types 1, 8)",
                        other as u8, block.entity_tag
                    )))
                }
            },
            0 => {}
            d => {
                return Err(err(format!(
                    "{d}D elements found (entity {}): a 2D mesh is needed",
                    block.entity_tag
                )))
            }
        }
    }
    let Some(p) = degree else {
        return Err(err(
            "no 2D elements (quadrilaterals) in the file; with physical groups defined, Gmsh \
             saves only the elements of physical groups: put the surfaces in a 2D physical group"
                .into(),
        ));
    };

    // Regions.
    let n_cells = cell_nodes_file.len();
    let mut regions = vec![0u16; n_cells];
    let region_names = if groups.regions.is_empty() {
        vec!["all".to_string()]
    } else {
        let mut tags = Vec::new();
        for r in &groups.regions {
            tags.push(group_tag(2, r).map_err(&err)?);
        }
        for c in 0..n_cells {
            let phys = entity_groups
                .get(&(2, cell_entity[c]))
                .map(Vec::as_slice)
                .unwrap_or(&[]);
            let Some(k) = tags.iter().position(|t| phys.contains(t)) else {
                let mine: Vec<String> = phys
                    .iter()
                    .filter_map(|t| names.iter().find(|(d, tt, _)| *d == 2 && tt == t))
                    .map(|(_, _, n)| format!("\"{n}\""))
                    .collect();
                return Err(err(format!(
                    "element {} (surface {}) belongs to none of the material regions [{}]; \
                     its 2D physical groups are [{}]",
                    cell_tag[c],
                    cell_entity[c],
                    groups
                        .regions
                        .iter()
                        .map(|r| format!("\"{r}\""))
                        .collect::<Vec<_>>()
                        .join(", "),
                    mine.join(", ")
                )));
            };
            regions[c] = k as u16;
        }
        groups.regions.clone()
    };

    // Compact the node numbering to the nodes used by cells (file order kept).
    let mut new_index = vec![u32::MAX; coords.len()];
    let mut nodes_out = Vec::new();
    for cn in &cell_nodes_file {
        for &n in cn {
            if new_index[n] == u32::MAX {
                new_index[n] = 0;
            }
        }
    }
    for (i, slot) in new_index.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = nodes_out.len() as u32;
            nodes_out.push(coords[i]);
        }
    }
    let npc = (p + 1) * (p + 1);
    let mut conn = Vec::with_capacity(n_cells * npc);
    let mut offsets = Vec::with_capacity(n_cells + 1);
    offsets.push(0);
    for (c, cn) in cell_nodes_file.iter().enumerate() {
        let mut local: Vec<u32> = cn.iter().map(|&n| new_index[n]).collect();
        // Orientation: signed area of the corner polygon.
        let corner = |a: usize| nodes_out[local[a] as usize];
        let (x0, x1, x2, x3) = (corner(0), corner(p), corner(npc - 1), corner(npc - 1 - p));
        let area2 = (x2 - x0).perp(&(x3 - x1));
        if area2 < 0.0 {
            // Swap ξ and η: a = i + m j ↦ j + m i.
            let m = p + 1;
            let old = local.clone();
            for j in 0..m {
                for i in 0..m {
                    local[i + m * j] = old[j + m * i];
                }
            }
        }
        if area2 == 0.0 || !area2.is_finite() {
            return Err(err(format!(
                "element {} is degenerate (zero area)",
                cell_tag[c]
            )));
        }
        conn.extend_from_slice(&local);
        offsets.push(conn.len());
    }
    let mut mesh = Mesh {
        nodes: nodes_out,
        conn,
        offsets,
        degree: vec![p as u8; n_cells],
        geometry: vec![CellGeometry::Isoparametric; n_cells],
        node_sets: BTreeMap::new(),
        facet_sets: BTreeMap::new(),
        rings: None,
        regions,
        region_names,
        constraints: Vec::new(),
    };
    if let Some(c) = first_inverted_cell(&mesh) {
        return Err(err(format!(
            "element {} is inverted or degenerate: det(dX/dξ) <= 0 inside it",
            cell_tag[c]
        )));
    }

    // Named boundaries: map each cell side (sorted corner pair) to its facet.
    let mut sides: HashMap<(u32, u32), Facet> = HashMap::new();
    for c in 0..n_cells {
        let cn = mesh.cell_nodes(c);
        for side in 0..4u8 {
            let f = Facet {
                cell: c as u32,
                side,
            };
            let ln = f.local_nodes(p);
            let (a, b) = (cn[ln[0]], cn[ln[p]]);
            sides.insert((a.min(b), a.max(b)), f);
        }
    }
    for (scene_key, set) in [("hub", &groups.hub), ("contact", &groups.contact)] {
        let tag =
            group_tag(1, set).map_err(|m| err(format!("{m} (named by [mesh] {scene_key})")))?;
        let mut facets = Vec::new();
        let mut seen = BTreeSet::new();
        for (entity, el_tag, [a, b]) in &lines {
            let in_group = entity_groups
                .get(&(1, *entity))
                .is_some_and(|g| g.contains(&tag));
            if !in_group {
                continue;
            }
            let (a, b) = (new_index[*a], new_index[*b]);
            let Some(f) = sides.get(&(a.min(b), a.max(b))) else {
                return Err(err(format!(
                    "line element {el_tag} of physical group \"{set}\" is not a side of any \
                     quadrilateral"
                )));
            };
            if seen.insert((f.cell, f.side)) {
                facets.push(*f);
            }
        }
        if facets.is_empty() {
            return Err(err(format!(
                "physical group \"{set}\" (named by [mesh] {scene_key}) has no line elements"
            )));
        }
        let mut nodes: BTreeSet<u32> = BTreeSet::new();
        for f in &facets {
            let cn = mesh.cell_nodes(f.cell as usize);
            for &a in &f.local_nodes(p)[..=p] {
                nodes.insert(cn[a]);
            }
        }
        let name = if scene_key == "hub" { "hub" } else { "outer" };
        mesh.node_sets
            .insert(name.to_string(), nodes.into_iter().collect());
        mesh.facet_sets.insert(name.to_string(), facets);
    }
    Ok(mesh)
}

/// First cell with det(dX/dξ) ≤ 0 at a point of a 4 × 4 Gauss rule or at a corner.
pub fn first_inverted_cell(mesh: &Mesh) -> Option<usize> {
    let (g, _) = crate::element::gauss_1d(4);
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for &a in &g {
        for &b in &g {
            pts.push((a, b));
        }
    }
    pts.extend([(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]);
    let n = pts.len();
    let t1 = ShapeTable::<4>::new::<Q1>(pts.clone(), vec![1.0; n]);
    let t2 = ShapeTable::<9>::new::<Q2>(pts, vec![1.0; n]);
    (0..mesh.n_cells()).find(|&c| {
        let cn = mesh.cell_nodes(c);
        let det = |k: usize| -> f64 {
            let mut j = Mat2::zeros();
            let mut add = |a: usize, d: [f64; 2]| {
                let p = mesh.nodes[cn[a] as usize];
                j[(0, 0)] += p[0] * d[0];
                j[(0, 1)] += p[0] * d[1];
                j[(1, 0)] += p[1] * d[0];
                j[(1, 1)] += p[1] * d[1];
            };
            if mesh.degree[c] == 1 {
                (0..Q1::N).for_each(|a| add(a, t1.dn[k][a]));
            } else {
                (0..Q2::N).for_each(|a| add(a, t2.dn[k][a]));
            }
            j.determinant()
        };
        (0..n).any(|k| {
            let d = det(k);
            d <= 0.0 || d.is_nan()
        })
    })
}

/// Physical tags of every (dim, entity) of a parsed file, for curves, surfaces and volumes.
pub(super) fn entity_physical_tags(
    data: &mshio::MshData<u64, i32, f64>,
) -> HashMap<(i32, i32), Vec<i32>> {
    let mut groups = HashMap::new();
    if let Some(ent) = &data.entities {
        for c in &ent.curves {
            groups.insert((1, c.tag), c.physical_tags.clone());
        }
        for s in &ent.surfaces {
            groups.insert((2, s.tag), s.physical_tags.clone());
        }
        for v in &ent.volumes {
            groups.insert((3, v.tag), v.physical_tags.clone());
        }
    }
    groups
}

/// The tag of the `dim`-dimensional physical group `name` among the file's `names`
/// (`(dim, tag, name)`), or a message listing the groups the file has in that dimension.
pub(super) fn physical_group_tag(
    names: &[(i32, i32, String)],
    dim: i32,
    name: &str,
) -> Result<i32, String> {
    names
        .iter()
        .find(|(d, _, n)| *d == dim && n == name)
        .map(|(_, t, _)| *t)
        .ok_or_else(|| {
            let have: Vec<String> = names
                .iter()
                .filter(|(d, _, _)| *d == dim)
                .map(|(_, _, n)| format!("\"{n}\""))
                .collect();
            format!(
                "no {dim}D physical group named \"{name}\"; the file's {dim}D physical groups are [{}]",
                have.join(", ")
            )
        })
}

/// The header must say version 4.1 (mshio's own message for other versions is less precise).
pub(super) fn check_header(bytes: &[u8]) -> Result<(), String> {
    let head = &bytes[..bytes.len().min(256)];
    let text = String::from_utf8_lossy(head);
    let mut lines = text.lines();
    if lines.next().map(str::trim) != Some("$MeshFormat") {
        return Err("not a Gmsh .msh file (it does not start with $MeshFormat)".into());
    }
    let Some(fmt) = lines.next() else {
        return Err("truncated file: the $MeshFormat section is incomplete".into());
    };
    let mut it = fmt.split_whitespace();
    let version = it.next().unwrap_or("");
    if version != "4.1" {
        return Err(format!(
            "unsupported .msh format version \"{version}\": version 4.1 is needed (Gmsh: \
             -format msh41, or Mesh.MshFileVersion = 4.1)"
        ));
    }
    Ok(())
}

/// `$PhysicalNames`: (dimension, tag, name) of every physical group (ASCII in both the ASCII and
/// the binary format). No section: no groups.
pub(super) fn physical_names(bytes: &[u8]) -> Result<Vec<(i32, i32, String)>, String> {
    let start_tag = b"$PhysicalNames";
    let Some(start) = find(bytes, start_tag) else {
        return Ok(Vec::new());
    };
    let rest = &bytes[start + start_tag.len()..];
    let Some(end) = find(rest, b"$EndPhysicalNames") else {
        return Err("truncated file: $PhysicalNames has no $EndPhysicalNames".into());
    };
    let text = String::from_utf8_lossy(&rest[..end]);
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let count: usize = lines
        .next()
        .and_then(|l| l.parse().ok())
        .ok_or("malformed $PhysicalNames section: no count")?;
    // The count is a claim checked against the lines that follow, not a size to allocate.
    let mut out = Vec::new();
    for line in lines {
        let mut parts = line.splitn(3, char::is_whitespace);
        let dim = parts.next().and_then(|s| s.parse::<i32>().ok());
        let tag = parts.next().and_then(|s| s.parse::<i32>().ok());
        let name = parts.next().map(|s| s.trim().trim_matches('"').to_string());
        match (dim, tag, name) {
            (Some(d), Some(t), Some(n)) => out.push((d, t, n)),
            _ => return Err(format!("malformed $PhysicalNames line: {line}")),
        }
    }
    if out.len() != count {
        return Err(format!(
            "malformed $PhysicalNames section: {} names announced, {} found",
            count,
            out.len()
        ));
    }
    Ok(out)
}

/// The node tags of every block of `$Nodes`, in file order (ASCII or binary, 4- or 8-byte
/// `size_t`, either byte order). Called after mshio has parsed the file, so the layout is known to
/// be well formed; each count is still bounded by the bytes that remain before it is used.
pub(super) fn node_tags(bytes: &[u8]) -> Result<Vec<Vec<u64>>, String> {
    let (binary, size_t, little) = mesh_format(bytes)?;
    let Some(start) = find(bytes, b"\n$Nodes") else {
        return Err("no $Nodes section".into());
    };
    let mut rest = &bytes[start + b"\n$Nodes".len()..];
    // Skip the end of the `$Nodes` line.
    match rest.iter().position(|&b| b == b'\n') {
        Some(k) => rest = &rest[k + 1..],
        None => return Err("truncated file: $Nodes is incomplete".into()),
    }
    let mut reader = Reader {
        rest,
        binary,
        size_t,
        little,
    };
    let n_blocks = reader.size("number of node blocks")?;
    let n_nodes = reader.size("number of nodes")?;
    let min_tag = reader.size("minimum node tag")?;
    let max_tag = reader.size("maximum node tag")?;
    let mut blocks = Vec::new();
    let mut total = 0u64;
    for b in 0..n_blocks {
        let what = |s: &str| format!("{s} of node block {} of {n_blocks}", b + 1);
        let _dim = reader.int(&what("entity dimension"))?;
        let _entity = reader.int(&what("entity tag"))?;
        let parametric = reader.int(&what("parametric flag"))?;
        if parametric != 0 {
            return Err(format!(
                "{} is not supported",
                what("parametric node coordinates")
            ));
        }
        let n = reader.size(&what("number of nodes"))?;
        // Each node takes at least one tag and three coordinates: a count larger than the bytes
        // left cannot be true.
        let per_node = if binary { size_t + 24 } else { 8 };
        if n.saturating_mul(per_node as u64) > reader.rest.len() as u64 {
            return Err(format!(
                "{} = {n} is more than the rest of the file can hold",
                what("number of nodes")
            ));
        }
        let mut block = Vec::with_capacity(n as usize);
        for _ in 0..n {
            let tag = reader.size(&what("node tag"))?;
            if tag == 0 {
                return Err(format!("{}: node tag 0 is not allowed", what("node tags")));
            }
            block.push(tag);
        }
        reader.skip_coords(n, &what("node coordinates"))?;
        total += n;
        blocks.push(block);
    }
    if total != n_nodes {
        return Err(format!(
            "$Nodes announces {n_nodes} nodes, its blocks hold {total}"
        ));
    }
    let all = || blocks.iter().flatten().copied();
    let (lo, hi) = (
        all().min().unwrap_or(min_tag),
        all().max().unwrap_or(max_tag),
    );
    if (lo, hi) != (min_tag, max_tag) && total > 0 {
        return Err(format!(
            "$Nodes announces node tags {min_tag} to {max_tag}, its blocks hold tags {lo} to {hi}"
        ));
    }
    Ok(blocks)
}

/// (binary, size of `size_t`, little-endian) from `$MeshFormat`.
fn mesh_format(bytes: &[u8]) -> Result<(bool, usize, bool), String> {
    let start = find(bytes, b"$MeshFormat").ok_or("no $MeshFormat section")?;
    let after = &bytes[start + b"$MeshFormat".len()..];
    let line_start = after
        .iter()
        .position(|&b| b == b'\n')
        .ok_or("truncated $MeshFormat")?
        + 1;
    let line_len = after[line_start..]
        .iter()
        .position(|&b| b == b'\n')
        .ok_or("truncated $MeshFormat")?;
    let line = String::from_utf8_lossy(&after[line_start..line_start + line_len]).to_string();
    let mut it = line.split_whitespace();
    let _version = it.next();
    let file_type = it.next().unwrap_or("");
    let data_size = it.next().unwrap_or("");
    let binary = match file_type {
        "0" => false,
        "1" => true,
        other => {
            return Err(format!(
                "$MeshFormat: file type \"{other}\" is neither 0 nor 1"
            ))
        }
    };
    let size_t = match data_size {
        "4" => 4,
        "8" => 8,
        other => {
            return Err(format!(
                "$MeshFormat: data size \"{other}\" is neither 4 nor 8"
            ))
        }
    };
    let mut little = true;
    if binary {
        let one = after
            .get(line_start + line_len + 1..line_start + line_len + 5)
            .ok_or("truncated $MeshFormat")?;
        little = match one {
            [1, 0, 0, 0] => true,
            [0, 0, 0, 1] => false,
            _ => {
                return Err(
                    "$MeshFormat: the binary integer 1 that gives the byte order is missing".into(),
                )
            }
        };
    }
    Ok((binary, size_t, little))
}

/// Reads the numbers of a section, ASCII or binary.
struct Reader<'a> {
    rest: &'a [u8],
    binary: bool,
    size_t: usize,
    little: bool,
}

impl Reader<'_> {
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8], String> {
        if self.rest.len() < n {
            return Err(format!("truncated file: {what} is cut off"));
        }
        let (head, tail) = self.rest.split_at(n);
        self.rest = tail;
        Ok(head)
    }

    fn token(&mut self, what: &str) -> Result<String, String> {
        let skip = self
            .rest
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .ok_or_else(|| format!("truncated file: {what} is missing"))?;
        self.rest = &self.rest[skip..];
        let len = self
            .rest
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(self.rest.len());
        let tok = String::from_utf8_lossy(&self.rest[..len]).to_string();
        self.rest = &self.rest[len..];
        Ok(tok)
    }

    fn unsigned(&mut self, n: usize, what: &str) -> Result<u64, String> {
        let little = self.little;
        let b = self.take(n, what)?;
        let mut v = 0u64;
        for k in 0..n {
            let byte = if little { b[n - 1 - k] } else { b[k] };
            v = (v << 8) | u64::from(byte);
        }
        Ok(v)
    }

    fn size(&mut self, what: &str) -> Result<u64, String> {
        if self.binary {
            self.unsigned(self.size_t, what)
        } else {
            let t = self.token(what)?;
            t.parse()
                .map_err(|_| format!("{what} \"{t}\" is not a non-negative integer"))
        }
    }

    fn int(&mut self, what: &str) -> Result<i64, String> {
        if self.binary {
            Ok(i64::from(self.unsigned(4, what)? as u32 as i32))
        } else {
            let t = self.token(what)?;
            t.parse()
                .map_err(|_| format!("{what} \"{t}\" is not an integer"))
        }
    }

    fn skip_coords(&mut self, n: u64, what: &str) -> Result<(), String> {
        if self.binary {
            let len = n
                .checked_mul(24)
                .filter(|&l| l <= self.rest.len() as u64)
                .ok_or_else(|| format!("truncated file: {what} are cut off"))?;
            self.take(len as usize, what)?;
        } else {
            for _ in 0..n.saturating_mul(3) {
                self.token(what)?;
            }
        }
        Ok(())
    }
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// A one-line description of a parse error: the sections being parsed, what went wrong and
/// where (byte offset, and the line for ASCII content).
pub(super) fn describe_parse_error(bytes: &[u8], e: &mshio::MshParserError<&[u8]>) -> String {
    let bt = e.filtered_backtrace();
    let mut ctx: Vec<String> = bt
        .iter()
        .skip(1)
        .rev()
        .map(|(_, k)| k.context().map_or_else(|| k.to_string(), str::to_string))
        .collect();
    ctx.dedup();
    let (what, offset) = match bt.first() {
        Some((rest, k)) => (k.to_string(), bytes.len().saturating_sub(rest.len())),
        None => ("unknown error".to_string(), bytes.len()),
    };
    let truncated = offset >= bytes.len().saturating_sub(1)
        || bt.iter().any(|(rest, _)| rest.is_empty())
        || !bytes.ends_with(b"\n") && !ends_with_section(bytes);
    let line = bytes[..offset.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1;
    let mut msg = format!(
        "malformed .msh file at byte {offset} (line {line}): {what}{}",
        if ctx.is_empty() {
            String::new()
        } else {
            format!(" (in {})", ctx.join(" > "))
        }
    );
    if truncated {
        msg.push_str("; the file looks truncated");
    }
    msg
}

fn ends_with_section(bytes: &[u8]) -> bool {
    let tail = &bytes[bytes.len().saturating_sub(32)..];
    String::from_utf8_lossy(tail)
        .trim_end()
        .ends_with("$EndElements")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::Lagrange2D;

    /// The permutation puts Gmsh's nodes at the tensor-order reference points: Gmsh's Qua9
    /// reference nodes are corners (−1,−1), (1,−1), (1,1), (−1,1), mid-sides (0,−1), (1,0),
    /// (0,1), (−1,0), centre (0,0).
    #[test]
    fn permutations_match_reference_points() {
        let gmsh9 = [
            (-1.0, -1.0),
            (1.0, -1.0),
            (1.0, 1.0),
            (-1.0, 1.0),
            (0.0, -1.0),
            (1.0, 0.0),
            (0.0, 1.0),
            (-1.0, 0.0),
            (0.0, 0.0),
        ];
        for (a, &g) in GMSH_Q2.iter().enumerate() {
            assert_eq!(Q2::node_ref(a), gmsh9[g], "Q2 node {a}");
        }
        for (a, &g) in GMSH_Q1.iter().enumerate() {
            assert_eq!(Q1::node_ref(a), gmsh9[g], "Q1 node {a}");
        }
    }

    /// The text of a shipped mesh.
    fn shipped(name: &str) -> String {
        std::fs::read_to_string(format!("{}/scenarios/{name}", env!("CARGO_MANIFEST_DIR")))
            .expect("shipped mesh")
    }

    fn groups() -> GmshGroups {
        GmshGroups {
            hub: "hub".into(),
            contact: "contact".into(),
            regions: Vec::new(),
        }
    }

    /// Line range of the `$Nodes` section's content (after the `$Nodes` line, before
    /// `$EndNodes`) and the node blocks in it: (header line, tag lines, coordinate lines).
    fn node_blocks(
        lines: &[String],
    ) -> Vec<(usize, std::ops::Range<usize>, std::ops::Range<usize>)> {
        let start = lines.iter().position(|l| l == "$Nodes").expect("$Nodes") + 1;
        let n_blocks: usize = lines[start]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let mut at = start + 1;
        let mut out = Vec::new();
        for _ in 0..n_blocks {
            let n: usize = lines[at]
                .split_whitespace()
                .nth(3)
                .unwrap()
                .parse()
                .unwrap();
            out.push((at, at + 1..at + 1 + n, at + 1 + n..at + 1 + 2 * n));
            at += 1 + 2 * n;
        }
        out
    }

    fn lines_of(text: &str) -> Vec<String> {
        text.lines().map(str::to_string).collect()
    }

    fn parse(lines: &[String]) -> Result<Mesh, MeshError> {
        parse_msh((lines.join("\n") + "\n").as_bytes(), "test.msh", &groups())
    }

    /// Cells as sorted lists of their node coordinates (bit patterns), sorted: equal for two
    /// meshes with the same cells whatever the node numbering.
    fn cell_geometry(m: &Mesh) -> Vec<Vec<(u64, u64)>> {
        let mut cells: Vec<Vec<(u64, u64)>> = (0..m.n_cells())
            .map(|c| {
                let mut v: Vec<(u64, u64)> = m
                    .cell_nodes(c)
                    .iter()
                    .map(|&n| {
                        let p = m.nodes[n as usize];
                        (p[0].to_bits(), p[1].to_bits())
                    })
                    .collect();
                v.sort_unstable();
                v
            })
            .collect();
        cells.sort();
        cells
    }

    /// A `$Nodes` block listed in another order (each tag with its own coordinates) is the same
    /// mesh; so is a file whose tags are not contiguous.
    #[test]
    fn node_order_and_tag_gaps_do_not_change_the_mesh() {
        let lines = lines_of(&shipped("footprint_refined.msh"));
        let reference = parse(&lines).expect("shipped mesh");
        // Reverse the largest block's nodes, keeping each tag with its coordinates.
        let blocks = node_blocks(&lines);
        let (_, tags, coords) = blocks.iter().max_by_key(|b| b.1.len()).unwrap().clone();
        assert!(tags.len() > 100, "{}", tags.len());
        let mut permuted = lines.clone();
        let t: Vec<String> = lines[tags.clone()].iter().rev().cloned().collect();
        let x: Vec<String> = lines[coords.clone()].iter().rev().cloned().collect();
        permuted.splice(tags, t);
        permuted.splice(coords, x);
        let m = parse(&permuted).expect("the same mesh in another node order");
        assert_eq!(m.n_cells(), reference.n_cells());
        assert_eq!(cell_geometry(&m), cell_geometry(&reference));
        assert_eq!(m.facet_sets, {
            // Facets keep their cells (the cell order is the file's element order).
            reference.facet_sets.clone()
        });

        // Tags with gaps: every tag t becomes 3 t + 5, in $Nodes and in $Elements.
        let mut gaps = lines.clone();
        let node_start = gaps.iter().position(|l| l == "$Nodes").unwrap() + 1;
        let mut head: Vec<u64> = gaps[node_start]
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect();
        head[2] = 3 * head[2] + 5;
        head[3] = 3 * head[3] + 5;
        gaps[node_start] = head
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(" ");
        for (_, tags, _) in node_blocks(&lines) {
            for i in tags {
                let t: u64 = gaps[i].trim().parse().unwrap();
                gaps[i] = (3 * t + 5).to_string();
            }
        }
        let el_start = gaps.iter().position(|l| l == "$Elements").unwrap() + 1;
        let n_el_blocks: usize = gaps[el_start]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let mut at = el_start + 1;
        for _ in 0..n_el_blocks {
            let n: usize = gaps[at].split_whitespace().nth(3).unwrap().parse().unwrap();
            for line in &mut gaps[at + 1..at + 1 + n] {
                let mut v: Vec<u64> = line
                    .split_whitespace()
                    .map(|v| v.parse().unwrap())
                    .collect();
                for t in &mut v[1..] {
                    *t = 3 * *t + 5;
                }
                *line = v.iter().map(u64::to_string).collect::<Vec<_>>().join(" ");
            }
            at += 1 + n;
        }
        let m = parse(&gaps).expect("non-contiguous tags");
        assert_eq!(cell_geometry(&m), cell_geometry(&reference));
    }

    /// Two tags exchanged between nodes at different places: the elements now join the wrong
    /// nodes (a tangled mesh), which is refused, not read as the original.
    #[test]
    fn swapped_node_tags_give_the_tangled_mesh_and_are_refused() {
        let lines = lines_of(&shipped("footprint_refined.msh"));
        let blocks = node_blocks(&lines);
        let (_, tags, _) = blocks.iter().max_by_key(|b| b.1.len()).unwrap().clone();
        let (a, b) = (tags.start + 3, tags.start + tags.len() / 2);
        let mut swapped = lines.clone();
        swapped.swap(a, b);
        let e = parse(&swapped).expect_err("a tangled mesh");
        assert!(
            e.message.contains("inverted") || e.message.contains("degenerate"),
            "{e}"
        );
        // A tag given twice is named.
        let mut twice = lines.clone();
        twice[b] = twice[a].clone();
        let e = parse(&twice).expect_err("a duplicated tag");
        assert!(e.message.contains("more than one node"), "{e}");
    }

    /// Counts read from the file are checked against what follows them before anything is
    /// allocated: a huge count is an error, not an abort.
    #[test]
    fn huge_counts_are_errors() {
        let lines = lines_of(&shipped("two_layer.msh"));
        let names = lines.iter().position(|l| l == "$PhysicalNames").unwrap() + 1;
        let nodes = lines.iter().position(|l| l == "$Nodes").unwrap() + 1;
        let elements = lines.iter().position(|l| l == "$Elements").unwrap() + 1;
        let block = nodes + 1;
        let entities = lines.iter().position(|l| l == "$Entities").unwrap() + 1;
        let huge = [
            "100000000000",
            "4611686018427387904",
            "18446744073709551616",
            "-1",
        ];
        for count in huge {
            for (line, field) in [
                (names, 0),
                (entities, 0),
                (entities, 1),
                (entities, 2),
                (nodes, 0),
                (nodes, 1),
                (nodes, 3),
                (block, 3),
                (elements, 0),
                (elements, 1),
                (elements + 1, 3),
            ] {
                let mut bad = lines.clone();
                let mut f: Vec<String> = bad[line].split_whitespace().map(str::to_string).collect();
                f[field] = count.to_string();
                bad[line] = f.join(" ");
                let Err(e) = parse(&bad) else {
                    panic!("count {count} at line {} field {field} accepted", line + 1);
                };
                assert!(!e.message.is_empty());
            }
        }
    }

    #[test]
    fn bounded_reader_refuses_endless_and_large_files() {
        let e = read_bounded(Path::new("/dev/zero"), 1 << 20).expect_err("/dev/zero");
        assert!(e.message.contains("more than"), "{e}");
        let e = read_bounded(Path::new("/"), 1 << 20).expect_err("a directory");
        assert!(e.message.contains("directory"), "{e}");
    }

    #[test]
    fn header_checks() {
        assert!(check_header(b"hello").is_err());
        let e = check_header(b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n").unwrap_err();
        assert!(e.contains("2.2") && e.contains("4.1"), "{e}");
        assert!(check_header(b"$MeshFormat\n4.1 0 8\n").is_ok());
    }
}
