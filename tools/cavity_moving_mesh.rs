//! Moving-mesh (r-) adaptivity on the lid-driven cavity: the uniform 2^L × 2^L mesh, then N
//! node relocations with re-solves (see `tread::adapt::moving_mesh`), one table row per
//! recalculation (min det J, relocation step, Newton iterations, ψ_min and its error, the
//! largest centreline deviation from Botella & Peyret at Re = 1000), and the final mesh as a PNG.
//!
//! `cargo run --release --no-default-features --example cavity_moving_mesh -- [L] [N] [alpha]
//! [beta] [gamma] [out.png]` (defaults 4 8 4 4 0 cavity_moving_mesh.png), Re ladder 100 → 400 →
//! 1000.

use plotters::prelude::*;
use tread::adapt::moving_mesh::{moving_mesh_cavity, MonitorParams};
use tread::adapt::navier_stokes::{psi_min, stream_function, CavityLid, NsSolution};

include!("../tests/common/botella_peyret.rs");

fn arg<T: std::str::FromStr>(args: &[String], i: usize, default: T) -> Result<T, String> {
    match args.get(i) {
        None => Ok(default),
        Some(s) => s
            .parse()
            .map_err(|_| format!("argument {}: cannot parse `{s}`", i + 1)),
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let levels: u32 = arg(&args, 0, 4)?;
    if levels > 7 {
        return Err("level must be at most 7".into());
    }
    let n: usize = arg(&args, 1, 8)?;
    let params = MonitorParams {
        alpha: arg(&args, 2, 4.0)?,
        beta: arg(&args, 3, 4.0)?,
        gamma: arg(&args, 4, 0.0)?,
        ..MonitorParams::default()
    };
    let out: String = arg(&args, 5, "cavity_moving_mesh.png".to_string())?;
    println!("recalc n_eq  min_detJ   step   newton psi_min     rel_err   max|du|   max|dv|");
    let mut err = None;
    let (th, _) = moving_mesh_cavity(
        levels,
        CavityLid::Discontinuous,
        &[100.0, 400.0, 1000.0],
        &params,
        n,
        1e-10,
        &mut |r, th, x| {
            let sol = NsSolution { th, x: x.to_vec() };
            let dev = |ys: &[f64], vs: &[f64], k: usize, pt: &dyn Fn(f64) -> [f64; 2]| {
                ys.iter().zip(vs).try_fold(0.0f64, |m, (&s, &v)| {
                    sol.velocity(pt(s)).map(|u| m.max((u.0[k] - v).abs()))
                })
            };
            let du = dev(&BP_Y, &BP_U, 0, &|y| [0.5, y]);
            let dv = dev(&BP_X, &BP_V, 1, &|x| [x, 0.5]);
            let sf = stream_function(&sol);
            match (du, dv, sf) {
                (Ok(du), Ok(dv), Ok((space, psi))) => {
                    let (_, pm) = psi_min(th, &space, &psi);
                    println!(
                        "{:6} {:5} {:.3e} {:6.4} {:6}  {pm:.7} {:.3e} {du:.3e} {dv:.3e}",
                        r.index,
                        th.n_eq(),
                        r.min_det_j,
                        r.step,
                        r.newton_iterations,
                        (pm - BP_PSI_MIN).abs() / BP_PSI_MIN.abs()
                    );
                }
                (Err(e), _, _) | (_, Err(e), _) | (_, _, Err(e)) => err = Some(e.to_string()),
            }
        },
    )
    .map_err(|e| e.to_string())?;
    if let Some(e) = err {
        return Err(e);
    }
    // The final mesh.
    let px = 800u32;
    let root = BitMapBackend::new(&out, (px, px)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let s = |p: [f64; 2]| -> (i32, i32) {
        let m = 20.0;
        let w = px as f64 - 2.0 * m;
        ((m + w * p[0]) as i32, (m + w * (1.0 - p[1])) as i32)
    };
    for c in &th.corners {
        for (a, b) in [(0, 1), (1, 3), (3, 2), (2, 0)] {
            root.draw(&PathElement::new(vec![s(c[a]), s(c[b])], BLACK))
                .map_err(|e| e.to_string())?;
        }
    }
    root.present().map_err(|e| e.to_string())?;
    println!("mesh written to {out}");
    Ok(())
}

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            std::process::ExitCode::FAILURE
        }
    }
}
