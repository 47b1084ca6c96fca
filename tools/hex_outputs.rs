//! Writes the 3D outputs (`hex.pvd` + `hex/*.vtu`, `hex.mcap`, `hex.rrd` with the `rerun`
//! feature) of revolved Hex8 and Hex27 meshes with closed-form fields, for independent readers
//! (tools/check_hex_outputs.py): OUT/hex8 and OUT/hex27, two steps each (time 0 and 1).
//!
//! Fields at a reference point X (s = 0.5 at step 0, 1 at step 1):
//! u = s · 0.01 (X2, 0.5 X1, 0.1 X3); `radius` = sqrt(X1² + X2²) (scalar, length);
//! `cauchy_stress` Voigt [X1, X2, X3, 1, 2, 3] (symmetric tensor, stress); cell field
//! `cell_index2` = 2 c.
//!
//! Usage: cargo run --release --example hex_outputs -- OUT

use std::path::PathBuf;
use tread::io::record::hex_out::{HexOutputOptions, HexOutputs, HexState};
use tread::io::record::vtu::{Encoding, VtuCompression, VtuFormat};
use tread::io::record::vtu3d::Field3D;
use tread::mesh::revolved::{revolved, RevolvedSpec};

fn main() {
    let Some(out) = std::env::args().nth(1).map(PathBuf::from) else {
        eprintln!("usage: hex_outputs OUT");
        std::process::exit(2);
    };
    for (degree, name, compression) in [
        (1, "hex8", VtuCompression::None),
        (2, "hex27", VtuCompression::Zlib),
    ] {
        let spec = RevolvedSpec {
            ri: 1.0,
            ro: 2.0,
            width: 0.6,
            n_r: 2,
            n_z: 2,
            n_theta: 12,
            degree,
            grading_r: 1.0,
            grading_theta: 0.0,
            theta_ratio: 1.0,
            grading_z: 1.0,
            half_width: false,
            crown_radius: Some(1.0),
        };
        let mesh = match revolved(&spec) {
            Ok(m) => m,
            Err(e) => {
                eprintln!("hex_outputs: {e}");
                std::process::exit(1);
            }
        };
        let opts = HexOutputOptions {
            encoding: Encoding {
                format: VtuFormat::Binary,
                compression,
            },
            ..HexOutputOptions::default()
        };
        let dir = out.join(name);
        let run = || -> Result<(), tread::io::record::RecordError> {
            let mut w = HexOutputs::create(&dir, &mesh, opts)?;
            let radius: Vec<f64> = mesh.nodes.iter().map(|x| x.x.hypot(x.y)).collect();
            let sigma: Vec<f64> = mesh
                .nodes
                .iter()
                .flat_map(|x| [x.x, x.y, x.z, 1.0, 2.0, 3.0])
                .collect();
            let cells: Vec<f64> = (0..mesh.n_cells()).map(|c| 2.0 * c as f64).collect();
            for index in 0..2u64 {
                let s = 0.5 * (index + 1) as f64;
                let u: Vec<f64> = mesh
                    .nodes
                    .iter()
                    .flat_map(|x| [s * 0.01 * x.y, s * 0.005 * x.x, s * 0.001 * x.z])
                    .collect();
                let pf = [
                    Field3D::scalar("radius", &radius, "in"),
                    Field3D::sym_tensor("cauchy_stress", &sigma, "psi"),
                ];
                let cf = [Field3D::scalar("cell_index2", &cells, "")];
                w.write_step(
                    &mesh,
                    &HexState {
                        index,
                        time: index as f64,
                        u: &u,
                        point_fields: &pf,
                        cell_fields: &cf,
                    },
                )?;
            }
            w.finish()
        };
        if let Err(e) = run() {
            eprintln!("hex_outputs: {e}");
            std::process::exit(1);
        }
        println!(
            "hex_outputs: {} ({} nodes, {} cells)",
            dir.display(),
            mesh.n_nodes(),
            mesh.n_cells()
        );
    }
}
