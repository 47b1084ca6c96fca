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
//! Node tags: mshio keeps a tag → index map only when the file's node tags are not contiguous;
//! for contiguous tags it assumes that the blocks list the tags in increasing order (as Gmsh
//! writes them).

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

/// Read a `.msh` 4.1 file (ASCII or binary).
pub fn read_msh(path: &Path, groups: &GmshGroups) -> Result<Mesh, MeshError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| MeshError {
        file: file.clone(),
        message: format!("cannot read: {e}"),
    })?;
    parse_msh(&bytes, &file, groups)
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
    let data = &msh.data;
    let (Some(nodes), Some(elements)) = (&data.nodes, &data.elements) else {
        return Err(err(
            "no $Nodes or no $Elements section (is the file complete?)".into(),
        ));
    };
    // Physical tags of every (dim, entity).
    let mut entity_groups: HashMap<(i32, i32), Vec<i32>> = HashMap::new();
    if let Some(ent) = &data.entities {
        for c in &ent.curves {
            entity_groups.insert((1, c.tag), c.physical_tags.clone());
        }
        for s in &ent.surfaces {
            entity_groups.insert((2, s.tag), s.physical_tags.clone());
        }
    }
    let group_tag = |dim: i32, name: &str| -> Result<i32, String> {
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
                    "no {}D physical group named \"{name}\"; the file's {}D physical groups are [{}]",
                    dim,
                    dim,
                    have.join(", ")
                )
            })
    };

    // Node coordinates by tag.
    let mut node_index: HashMap<u64, usize> = HashMap::new();
    let mut coords: Vec<Vec2> = Vec::new();
    let mut next_tag = nodes.min_node_tag;
    for block in &nodes.node_blocks {
        let base = coords.len();
        for n in &block.nodes {
            if !(n.x.is_finite() && n.y.is_finite() && n.z.is_finite()) {
                return Err(err(format!(
                    "node {} has a non-finite coordinate",
                    coords.len() + 1
                )));
            }
            if n.z.abs() > 1e-9 * (n.x.abs() + n.y.abs()).max(1.0) {
                return Err(err(format!(
                    "node at ({}, {}, {}) is not in the plane z = 0 (a 2D mesh in x, y is needed)",
                    n.x, n.y, n.z
                )));
            }
            coords.push(Vec2::new(n.x, n.y));
        }
        match &block.node_tags {
            Some(map) => {
                for (&tag, &i) in map {
                    node_index.insert(tag, base + i);
                }
            }
            None => {
                for i in 0..block.nodes.len() {
                    node_index.insert(next_tag, base + i);
                    next_tag += 1;
                }
            }
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

/// The header must say version 4.1 (mshio's own message for other versions is less precise).
fn check_header(bytes: &[u8]) -> Result<(), String> {
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
fn physical_names(bytes: &[u8]) -> Result<Vec<(i32, i32, String)>, String> {
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
    let mut out = Vec::with_capacity(count);
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

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// A one-line description of a parse error: the sections being parsed, what went wrong and
/// where (byte offset, and the line for ASCII content).
fn describe_parse_error(bytes: &[u8], e: &mshio::MshParserError<&[u8]>) -> String {
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

    #[test]
    fn header_checks() {
        assert!(check_header(b"hello").is_err());
        let e = check_header(b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n").unwrap_err();
        assert!(e.contains("2.2") && e.contains("4.1"), "{e}");
        assert!(check_header(b"$MeshFormat\n4.1 0 8\n").is_ok());
    }
}
