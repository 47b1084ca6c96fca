//! Local refinement of solid meshes with hanging nodes: the forest reproduces an unrefined
//! mesh, stays one-irregular, constrains every hanging node to its coarse side (exactly for the
//! isoparametric map), passes the patch test of a homogeneous deformation, and the assembled
//! tangent of the constrained system equals finite differences of its residual.

#[path = "common/fixtures.rs"]
mod fixtures;

use tread::material::{Material, MooneyRivlin, NeoHookean};
use tread::math::{Mat2, Vec2};
use tread::mesh::{annulus, AnnulusSpec, Forest, Mesh};
use tread::model::SolidSystem;
use tread::physics::{PressureMode, SolidModel};
use tread::solver::NonlinearSystem;

fn root(order: usize, n_r: usize, n_theta: usize) -> Mesh {
    annulus(&AnnulusSpec {
        ri: 1.0,
        ro: 2.0,
        n_r,
        n_theta,
        degree: order,
        grading_r: 1.3,
        grading_theta: 0.2,
    })
}

/// Refine leaf `first`, then the first child of it that touches an unrefined neighbour, so that
/// the one-irregularity closure has to act.
fn refined(order: usize, iso: bool) -> (Forest, Mesh) {
    let mut m = root(order, 2, 8);
    if iso {
        m.make_isoparametric();
    }
    let mut f = Forest::new(m).unwrap();
    f.refine(&[9]).unwrap();
    let n0 = f.leaves().len();
    // The children of leaf 9 are at its place: 9..13. Refine one of them twice.
    f.refine(&[9]).unwrap();
    let n1 = f.leaves().len();
    assert!(
        n1 > n0 + 3,
        "one-irregularity closure split no neighbour ({n0} -> {n1})"
    );
    f.refine(&[9]).unwrap();
    let (mesh, _) = f.mesh();
    (f, mesh)
}

#[test]
fn unrefined_forest_reproduces_the_mesh() {
    for order in [1, 2] {
        let m = root(order, 3, 12);
        let f = Forest::new(m.clone()).unwrap();
        let (r, origin) = f.mesh();
        assert_eq!(r.n_nodes(), m.n_nodes());
        assert_eq!(r.n_cells(), m.n_cells());
        assert_eq!(origin.len(), r.n_nodes());
        assert!(r.constraints.is_empty());
        for name in ["hub", "outer"] {
            assert_eq!(r.facet_set(name).len(), m.facet_set(name).len(), "{name}");
            assert_eq!(r.node_set(name).len(), m.node_set(name).len(), "{name}");
        }
    }
}

#[test]
fn hanging_nodes_lie_on_their_coarse_sides() {
    for order in [1, 2] {
        let (f, mesh) = refined(order, true);
        assert!(!mesh.constraints.is_empty());
        let constrained: std::collections::HashSet<u32> =
            mesh.constraints.iter().map(|c| c.node).collect();
        for c in &mesh.constraints {
            let sum: f64 = c.masters.iter().map(|m| m.1).sum();
            assert!((sum - 1.0).abs() < 1e-14, "weights sum {sum}");
            assert!(c.masters.iter().all(|m| !constrained.contains(&m.0)));
            let x: Vec2 = c
                .masters
                .iter()
                .fold(Vec2::zeros(), |s, &(m, w)| s + mesh.nodes[m as usize] * w);
            let err = (x - mesh.nodes[c.node as usize]).norm();
            assert!(
                err < 1e-12,
                "Q{order}: hanging node {} off its side by {err:.2e}",
                c.node
            );
        }
        // One-irregular: leaves that share a side differ by at most one level.
        eprintln!(
            "Q{order}: {} leaves, {} nodes, {} hanging nodes, levels up to {}",
            f.leaves().len(),
            mesh.n_nodes(),
            mesh.constraints.len(),
            f.leaves().iter().map(|l| l.level).max().unwrap()
        );
        // The facets of the outer boundary cover its angle once.
        let mut angle = 0.0;
        for fc in mesh.facet_set("outer") {
            let n = mesh.cell_nodes(fc.cell as usize);
            let ln = fc.local_nodes(order);
            let (a, b) = (
                mesh.nodes[n[ln[0]] as usize],
                mesh.nodes[n[ln[order]] as usize],
            );
            let d = (a[0] * b[1] - a[1] * b[0]).atan2(a.dot(&b)).abs();
            angle += d;
        }
        let two_pi = 2.0 * std::f64::consts::PI;
        assert!(
            (angle - two_pi).abs() < 1e-12,
            "outer facets cover {angle} rad"
        );
    }
}

fn system(mesh: Mesh, material: Material) -> SolidSystem {
    let model = SolidModel::new(mesh, material, 0.8, PressureMode::None);
    SolidSystem::new(model, "hub")
}

/// u = H X on every node: the constrained values are the masters' interpolation of it, and the
/// residual vanishes at every equation away from the boundary (the refined cells, the hanging
/// nodes' masters included).
#[test]
fn homogeneous_deformation_passes_the_patch_test() {
    let h = Mat2::new(0.04, -0.02, 0.03, -0.05);
    for order in [1, 2] {
        let (_, mesh) = refined(order, true);
        let mut sys = system(mesh, NeoHookean::new(2.0, 5.0).into());
        let (moved, worst) = fixtures::affine_patch_test(&mut sys, &h);
        assert!(
            moved < 1e-14,
            "constraints moved an affine field by {moved:.2e}"
        );
        eprintln!("Q{order}: interior residual {worst:.2e} of the force scale");
        assert!(worst < 1e-12, "Q{order}: patch test residual {worst:.3e}");
    }
}

#[test]
fn tangent_matches_finite_differences_with_hanging_nodes() {
    for (order, material) in [
        (1, Material::from(NeoHookean::new(2.0, 5.0))),
        (2, MooneyRivlin::new(0.8, 0.2, 20.0).into()),
    ] {
        let (_, mesh) = refined(order, false);
        let mut sys = system(mesh, material);
        fixtures::smooth_loaded_state(&mut sys);
        let n = sys.n_eq();
        let err = fixtures::tangent_fd_error(&mut sys);
        eprintln!("Q{order}: {n} equations, max |K − K_fd| / max |K| = {err:.2e}");
        assert!(err < 1e-7, "Q{order}: tangent error {err:.3e}");
    }
}

/// Every leaf's neighbours are at most one level finer: points just outside each side (at side
/// parameters ±1/4, ±3/4, where only a neighbour two levels finer would have nodes) are located
/// in the leaf mesh and their cell's level is compared.
fn assert_one_irregular(f: &Forest) {
    let (mesh, _) = f.mesh();
    let loc = tread::mesh::locate::PointLocator::new(&mesh);
    let out = 1.0 + 1e-6;
    for l in f.leaves() {
        for s in [-0.75, -0.25, 0.25, 0.75] {
            for (a, b) in [(-out, s), (out, s), (s, -out), (s, out)] {
                let (xi, eta) = l.to_root(a, b);
                let x = f.root_point(l.root as usize, xi, eta);
                if let Some((c, _, _)) = loc.locate(&mesh, x) {
                    let m = f.leaves()[c];
                    assert!(
                        m.level <= l.level + 1,
                        "leaf {l:?} has neighbour {m:?} two levels finer"
                    );
                }
            }
        }
    }
}

/// Coarsening every leaf round after round undoes the refinement back to the root mesh (no
/// hanging nodes left), the forest staying one-irregular after every round; a family whose
/// parent would sit next to leaves two levels finer is not merged.
#[test]
fn coarsening_undoes_refinement_and_keeps_one_irregularity() {
    for order in [1, 2] {
        let (mut f, _) = refined(order, false);
        let root_cells = f.root.n_cells();
        assert_one_irregular(&f);
        // Only the level-1 leaves: the families next to the level-2 and level-3 leaves must stay.
        let level1: Vec<usize> = (0..f.leaves().len())
            .filter(|&k| f.leaves()[k].level == 1)
            .collect();
        let families = level1.len() / 4;
        let merged = f.coarsen(&level1).unwrap();
        assert_one_irregular(&f);
        assert!(
            merged >= 1 && merged < families,
            "merged {merged} of {families} families"
        );
        let deepest = f.leaves().iter().map(|l| l.level).max().unwrap_or(0);
        let mut rounds = 0;
        loop {
            let all: Vec<usize> = (0..f.leaves().len()).collect();
            let merged = f.coarsen(&all).unwrap();
            assert_one_irregular(&f);
            if merged == 0 {
                break;
            }
            rounds += 1;
        }
        // One level per round at most.
        assert!(
            rounds >= usize::from(deepest),
            "{rounds} rounds from level {deepest}"
        );
        assert_eq!(f.leaves().len(), root_cells);
        let (m, _) = f.mesh();
        assert!(m.constraints.is_empty());
        assert_eq!(m.n_cells(), root_cells);
        assert!(f.coarsen(&[root_cells]).is_err());
    }
}
