//! Adaptive static indentation against structured meshes: hub-force error against equations
//! and wall time.
//!
//! ```text
//! cargo run --release --no-default-features --bin tread-bench-adapt-indentation -- \
//!     [--scene scenarios/indentation_frictionless.toml] [--root 2x32] [--steps 12]
//!     [--fraction 0.5] [--structured 2x32,4x64,8x128,16x256] [--gradings 0,0.6,0.8]
//!     [--reference-levels 3] [--out DIR] [--smoke]
//! ```
//!
//! 1. **Structured meshes.** The hub force F_y of the scene on structured meshes (exact polar
//!    cell map) of every grading in `--gradings`, on the mesh sequence `--structured` (each mesh
//!    twice as fine as the previous in both directions), with the Richardson extrapolation of
//!    the finest three of each grading.
//! 2. **Adaptive.** From the `--root` mesh (uniform, no grading), `--steps` steps of solve →
//!    ZZ estimate → Dörfler marking (`--fraction`) → refine → transfer.
//! 3. **Reference.** The extrapolation of the adaptive sequence's last three meshes in the
//!    number of equations N (F = F∞ + C N^−r, r observed), printed next to the structured
//!    extrapolations and finest values (their distance from it is the reference's check).
//! 4. A Markdown table on stdout and `DIR/adapt_indentation.csv`: equations, relative F_y
//!    error, wall time (structured: the solve; adaptive: the whole loop up to that mesh), and
//!    the fewest equations and least time at which each method reaches 1e-3, 1e-4 and 1e-5.
//!
//! Wall times are single runs (the machine is noisy); run with RAYON_NUM_THREADS=1 for
//! serial numbers.

use std::path::PathBuf;
use std::time::Instant;
use tread::driver::adaptive::{indentation_system, polar_root, run, solve_static, AdaptOptions};
use tread::driver::indentation;
use tread::io::Scene;

struct Row {
    method: String,
    dofs: usize,
    fy: f64,
    time: f64,
}

fn arg(args: &[String], key: &str) -> Option<String> {
    args.iter()
        .position(|a| a == key)
        .and_then(|i| args.get(i + 1).cloned())
}

fn parse_mesh(s: &str) -> Result<(usize, usize), String> {
    let (a, b) = s
        .split_once('x')
        .ok_or_else(|| format!("mesh `{s}`: expected N_RxN_THETA"))?;
    Ok((
        a.parse().map_err(|e| format!("mesh `{s}`: {e}"))?,
        b.parse().map_err(|e| format!("mesh `{s}`: {e}"))?,
    ))
}

fn scene_with(text: &str, name: &str, sets: &[String]) -> Result<Scene, String> {
    Scene::from_toml_str(text, name, sets).map_err(|e| e.to_string())
}

fn main() {
    if let Err(e) = real_main() {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

fn real_main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let smoke = args.iter().any(|a| a == "--smoke");
    let scene_path =
        arg(&args, "--scene").unwrap_or_else(|| "scenarios/indentation_frictionless.toml".into());
    let text = std::fs::read_to_string(&scene_path).map_err(|e| format!("{scene_path}: {e}"))?;
    let root = arg(&args, "--root").unwrap_or_else(|| "2x32".into());
    let steps: usize = arg(&args, "--steps")
        .map_or(Ok(if smoke { 2 } else { 12 }), |s| s.parse())
        .map_err(|e| format!("--steps: {e}"))?;
    let fraction: f64 = arg(&args, "--fraction")
        .map_or(Ok(0.5), |s| s.parse())
        .map_err(|e| format!("--fraction: {e}"))?;
    let structured = arg(&args, "--structured").unwrap_or_else(|| {
        if smoke {
            "2x32,4x64".into()
        } else {
            "2x32,4x64,8x128,16x256".into()
        }
    });
    let gradings = arg(&args, "--gradings").unwrap_or_else(|| {
        if smoke {
            "0.6".into()
        } else {
            "0,0.6,0.8".into()
        }
    });
    let out =
        PathBuf::from(arg(&args, "--out").unwrap_or_else(|| "out/bench_adapt_indentation".into()));
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;

    let mut rows: Vec<Row> = Vec::new();
    // 1. Structured meshes.
    let mut extrapolations: Vec<(String, f64, f64, f64)> = Vec::new(); // (grading, F∞, order, finest)
    for g in gradings.split(',') {
        let g: f64 = g.trim().parse().map_err(|e| format!("--gradings: {e}"))?;
        let mut fy = Vec::new();
        for m in structured.split(',') {
            let (nr, nt) = parse_mesh(m.trim())?;
            let sets = vec![
                format!("mesh.n_r={nr}"),
                format!("mesh.n_theta={nt}"),
                format!("mesh.grading_theta={g}"),
                "mesh.grading_r=1".to_string(),
            ];
            let scene = scene_with(&text, &scene_path, &sets)?;
            let t = Instant::now();
            let mut sys =
                indentation_system(&scene, polar_root(&scene).map_err(|e| e.to_string())?)
                    .map_err(|e| e.to_string())?;
            solve_static(&scene, &mut sys, false, None, &out).map_err(|e| e.to_string())?;
            let time = t.elapsed().as_secs_f64();
            let r = indentation::results(&sys, scene.geometry.ro);
            eprintln!(
                "structured g={g} {m}: {} eqs, F_y = {:.12e}, {time:.2} s",
                sys.n_dofs(),
                r.hub_force_y
            );
            fy.push(r.hub_force_y);
            rows.push(Row {
                method: format!("structured, grading {g}"),
                dofs: sys.n_dofs(),
                fy: r.hub_force_y,
                time,
            });
        }
        if fy.len() >= 3 {
            let n = fy.len();
            let (f1, f2, f3) = (fy[n - 3], fy[n - 2], fy[n - 1]);
            let ratio = (f2 - f1) / (f3 - f2);
            let order = ratio.abs().log2();
            let fref = f3 + (f3 - f2) / (ratio - 1.0);
            eprintln!(
                "  grading {g}: observed order {order:.2} in h, extrapolated F_y = {fref:.12e}"
            );
            extrapolations.push((format!("grading {g}"), fref, order, f3));
        }
    }
    // 2. Adaptive.
    let (nr, nt) = parse_mesh(&root)?;
    let sets = vec![
        format!("mesh.n_r={nr}"),
        format!("mesh.n_theta={nt}"),
        "mesh.grading_theta=0".to_string(),
        "mesh.grading_r=1".to_string(),
    ];
    let scene = scene_with(&text, &scene_path, &sets)?;
    let opts = AdaptOptions {
        steps,
        fraction,
        ..Default::default()
    };
    let (_, steps) = run(&scene, &opts, &out, |_, s, _| {
        eprintln!(
            "adaptive step {}: {} cells, {} eqs, {} hanging, level {}, eta_rel {:.3e}, F_y = {:.12e}, {:.2} s",
            s.step, s.cells, s.dofs, s.hanging_nodes, s.max_level, s.relative_estimate, s.hub_force_y, s.wall_step_s
        );
    })
    .map_err(|e| e.to_string())?;
    for s in &steps {
        rows.push(Row {
            method: format!("adaptive Q{} from {root}, θ = {fraction}", scene.mesh.order),
            dofs: s.dofs,
            fy: s.hub_force_y,
            time: s.wall_total_s,
        });
    }
    // 3. Reference: extrapolation of the adaptive sequence in N.
    let n = steps.len();
    if n < 3 {
        return Err("the reference needs at least three adaptive meshes (--steps >= 2)".into());
    }
    let (a, b, c) = (&steps[n - 3], &steps[n - 2], &steps[n - 1]);
    let (d1, d2) = (b.hub_force_y - a.hub_force_y, c.hub_force_y - b.hub_force_y);
    let q = d1 / d2;
    let fref = if q > 1.0 {
        c.hub_force_y + d2 / (q - 1.0)
    } else {
        c.hub_force_y
    };
    let rate = (q.abs().ln()) / ((c.dofs as f64 / b.dofs as f64).ln());
    println!(
        "reference F_y = {fref:.12e}: extrapolation of the last three adaptive meshes ({}, {}, {} equations; observed rate r = {rate:.2})",
        a.dofs, b.dofs, c.dofs
    );
    for (name, f, order, finest) in &extrapolations {
        println!(
            "  structured {name}: Richardson {f:.12e} (order {order:.2} in h), {:.2e} from the reference; finest mesh {:.2e} from it",
            (f - fref).abs() / fref.abs(),
            (finest - fref).abs() / fref.abs()
        );
    }
    println!();

    // 3. Table.
    let mut csv_rows = Vec::new();
    println!("| method | equations | F_y | relative error | wall time (s) |");
    println!("|---|---|---|---|---|");
    for r in &rows {
        let e = (r.fy - fref).abs() / fref.abs();
        println!(
            "| {} | {} | {:.10e} | {e:.2e} | {:.3} |",
            r.method, r.dofs, r.fy, r.time
        );
        csv_rows.push(vec![
            r.method.to_string(),
            r.dofs.to_string(),
            format!("{:.15e}", r.fy),
            format!("{e:.6e}"),
            format!("{:.6}", r.time),
        ]);
    }
    tread::io::output::write_text_csv(
        &out.join("adapt_indentation.csv"),
        &["method", "dofs", "hub_force_y", "rel_error", "wall_s"],
        csv_rows,
    )
    .map_err(|e| e.to_string())?;
    println!();
    for target in [1e-3, 1e-4, 1e-5] {
        let mut methods: Vec<&str> = rows.iter().map(|r| r.method.as_str()).collect();
        methods.dedup();
        for m in methods {
            let hit = rows
                .iter()
                .filter(|r| r.method == m && (r.fy - fref).abs() / fref.abs() <= target)
                .min_by_key(|r| r.dofs);
            match hit {
                Some(r) => println!("{target:.0e}: {m}: {} equations, {:.3} s", r.dofs, r.time),
                None => println!("{target:.0e}: {m}: not reached"),
            }
        }
    }
    Ok(())
}
