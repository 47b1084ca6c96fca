//! CSV tables shared by the drivers: contact tractions (`contact.csv`), nodal displacements
//! (`nodes.csv`) and the referential field (`steady_field.csv`, the format the transient
//! extraction and the steady mode share: `ring, pos, X1, X2, u1, u2`, u = χ − X at the
//! referential node (X1, X2)).

use crate::contact::ContactSample;
use crate::io::output::{write_csv, OutputError};
use crate::mesh::Mesh;
use std::path::Path;

/// `contact.csv`: one row per facet quadrature point.
pub fn write_contact_csv(path: &Path, samples: &[ContactSample]) -> Result<(), OutputError> {
    write_csv(
        path,
        &[
            "theta",
            "x1",
            "x2",
            "penetration",
            "t_n",
            "t_t",
            "slip_velocity",
            "ds0",
        ],
        samples
            .iter()
            .map(|s| vec![s.theta, s.x1, s.x2, s.delta, s.t_n, s.t_t, s.w, s.ds0]),
    )
}

/// `nodes.csv`: `node, X1, X2, u1, u2` (u: the first 2 · n_nodes entries of `x`).
pub fn write_nodes_csv(path: &Path, mesh: &Mesh, x: &[f64]) -> Result<(), OutputError> {
    write_csv(
        path,
        &["node", "X1", "X2", "u1", "u2"],
        (0..mesh.n_nodes()).map(|n| {
            vec![
                n as f64,
                mesh.nodes[n][0],
                mesh.nodes[n][1],
                x[2 * n],
                x[2 * n + 1],
            ]
        }),
    )
}

/// `steady_field.csv` of a ring-structured mesh (nothing is written without rings).
pub fn write_referential_field_csv(path: &Path, mesh: &Mesh, u: &[f64]) -> Result<(), OutputError> {
    let Some(rl) = mesh.rings else {
        return Ok(());
    };
    write_csv(
        path,
        &["ring", "pos", "X1", "X2", "u1", "u2"],
        (0..mesh.n_nodes()).map(|n| {
            vec![
                (n / rl.per_ring) as f64,
                (n % rl.per_ring) as f64,
                mesh.nodes[n][0],
                mesh.nodes[n][1],
                u[2 * n],
                u[2 * n + 1],
            ]
        }),
    )
}
