//! Adaptive work–precision benchmark on the L-shape (−Δu = 0, u = r^{2/3} sin(2θ/3)): relative
//! energy error ‖∇(u − u_h)‖ / |u|₁ against equations and against wall time for h-adaptive Q1
//! and Q2 (Jacobi-CG from the transferred solution, "the fast h-method", and sparse Cholesky),
//! uniform p (hierarchical, fixed mesh) and hp.
//!
//! ```text
//! cargo run --release --no-default-features --bin tread-bench-adapt -- [--out DIR]
//!     [--venv PYTHON_VENV] [--smoke]
//! ```
//!
//! Writes `DIR/adapt.csv` (one row per adaptive step), `DIR/adapt_dofs.png` (error vs
//! equations) and `DIR/adapt_time.png` (error vs cumulative wall time), and a Markdown table on
//! stdout: the time to reach 1e-3 (Q1) and 1e-5 (Q2, hp). Wall time is that of the adaptive
//! algorithm (solve, estimate, mark, refine, transfer); the exact-error evaluation is excluded.
//! The code is serial.
//!
//! With `--venv`, `tools/peer_adapt_skfem.py` is run with that venv's python: the same problem
//! with scikit-fem (adaptive P1 and P2 triangles, its residual estimator, the same Dörfler
//! fraction θ = `--fraction`, 0.5 by default), and its error per DOF and time per adaptive step
//! are compared in the same table.
//! Default `DIR = out/bench_adapt`.

use plotters::prelude::*;
use std::path::{Path, PathBuf};
use tread::adapt::driver::{
    run, AdaptOptions, EstimatorKind, Marking, Solver, StepRecord, Strategy,
};
use tread::adapt::poisson::{lshape_energy_sq, LShape};
use tread::adapt::quadtree::Quadtree;
use tread::element::hierarchical::Basis1d;
use tread::io::record::png::{register_font, AxisLayout, Scale};

struct Series {
    name: String,
    steps: Vec<(usize, f64, f64, f64)>, // (n, rel error, cumulative time, time of the step)
}

fn case(name: &str, opts: AdaptOptions) -> Result<Series, String> {
    let unorm = lshape_energy_sq().sqrt();
    let recs: Vec<StepRecord> = run(Quadtree::l_shape(0, opts.degree), &LShape, unorm, &opts)
        .map_err(|e| format!("{name}: {e}"))?;
    let mut prev = 0.0;
    let steps = recs
        .iter()
        .map(|r| {
            let dt = r.t_total - prev;
            prev = r.t_total;
            (r.n_eq, r.rel_error, r.t_total, dt)
        })
        .collect();
    Ok(Series {
        name: name.to_string(),
        steps,
    })
}

fn time_to(s: &Series, target: f64) -> Option<(f64, usize)> {
    s.steps.iter().find(|r| r.1 <= target).map(|r| (r.2, r.0))
}

fn plot(path: &Path, series: &[Series], by_time: bool) -> Result<(), String> {
    register_font()?;
    let data: Vec<(String, Vec<(f64, f64)>)> = series
        .iter()
        .map(|s| {
            let pts = s
                .steps
                .iter()
                .filter(|r| r.1 > 0.0 && (!by_time || r.2 > 0.0))
                .map(|r| {
                    let x = if by_time { r.2 } else { r.0 as f64 };
                    (x.log10(), r.1.log10())
                })
                .collect();
            (s.name.clone(), pts)
        })
        .collect();
    let all = || data.iter().flat_map(|(_, p)| p.iter());
    let xa = AxisLayout::new(Scale::Log10, all().map(|p| p.0));
    let ya = AxisLayout::new(Scale::Log10, all().map(|p| p.1));
    let e = |x: &dyn std::fmt::Display| format!("{}: {x}", path.display());
    let root = BitMapBackend::new(path, (960, 640)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let title = if by_time {
        "L-shape: relative energy error vs wall time"
    } else {
        "L-shape: relative energy error vs equations"
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(48)
        .y_label_area_size(80)
        .build_cartesian_2d(xa.clone(), ya.clone())
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc(if by_time {
            "cumulative wall time [s]"
        } else {
            "equations N"
        })
        .y_desc("‖∇(u − u_h)‖ / |u|₁")
        .x_label_formatter(&|v| xa.label(*v, false))
        .y_label_formatter(&|v| ya.label(*v, false))
        .draw()
        .map_err(|x| e(&x))?;
    let colors = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(255, 127, 14),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
    ];
    for (i, (name, p)) in data.iter().enumerate() {
        let c = colors[i % colors.len()];
        let style = c.stroke_width(2);
        chart
            .draw_series(LineSeries::new(p.iter().copied(), style))
            .map_err(|x| e(&x))?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 22, y)], style));
        chart
            .draw_series(p.iter().map(|q| Circle::new(*q, 3, c.filled())))
            .map_err(|x| e(&x))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))
}

fn peer(venv: &Path, out: &Path, smoke: bool, fraction: f64) -> Result<Vec<Series>, String> {
    let py = venv.join("bin").join("python");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/peer_adapt_skfem.py");
    let json = out.join("peer_skfem.json");
    let mut cmd = std::process::Command::new(&py);
    cmd.arg(&script)
        .arg("--out")
        .arg(&json)
        .arg("--fraction")
        .arg(fraction.to_string());
    if smoke {
        cmd.arg("--smoke");
    }
    let st = cmd
        .status()
        .map_err(|e| format!("cannot run {}: {e}", py.display()))?;
    if !st.success() {
        return Err(format!(
            "{} {} failed: {st}",
            py.display(),
            script.display()
        ));
    }
    let text = std::fs::read_to_string(&json).map_err(|e| format!("{}: {e}", json.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", json.display()))?;
    let mut out = Vec::new();
    for s in v.as_array().ok_or("peer output is not a list")? {
        let name = s["name"].as_str().unwrap_or("peer").to_string();
        let mut steps = Vec::new();
        let mut cum = 0.0;
        for r in s["steps"].as_array().ok_or("peer series without steps")? {
            let n = r["n"].as_u64().unwrap_or(0) as usize;
            let err = r["rel_error"].as_f64().unwrap_or(f64::NAN);
            let dt = r["time"].as_f64().unwrap_or(f64::NAN);
            cum += dt;
            steps.push((n, err, cum, dt));
        }
        out.push(Series { name, steps });
    }
    Ok(out)
}

fn main() {
    if let Err(e) = real_main() {
        eprintln!("tread-bench-adapt: {e}");
        std::process::exit(1);
    }
}

fn real_main() -> Result<(), String> {
    let mut out = PathBuf::from("out/bench_adapt");
    let mut venv: Option<PathBuf> = None;
    let mut smoke = false;
    let mut fraction = 0.5;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out = PathBuf::from(args.next().ok_or("--out needs a directory")?),
            "--venv" => venv = Some(PathBuf::from(args.next().ok_or("--venv needs a path")?)),
            "--smoke" => smoke = true,
            "--fraction" => {
                fraction = args
                    .next()
                    .and_then(|v| v.parse::<f64>().ok())
                    .filter(|f| *f > 0.0 && *f <= 1.0)
                    .ok_or("--fraction needs a number in (0, 1]")?
            }
            other => {
                return Err(format!(
                    "unknown argument `{other}` (use --out, --venv, --smoke, --fraction)"
                ))
            }
        }
    }
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let (t1, t2) = if smoke { (3e-2, 3e-3) } else { (1e-3, 1e-5) };
    let cap = if smoke { 20_000 } else { 2_000_000 };
    let mut series = Vec::new();
    let h = |p: u8, solver: Solver, target: f64| {
        let mut o = AdaptOptions::h(p);
        o.solver = solver;
        o.target_rel_error = target;
        o.max_dofs = cap;
        o.max_steps = 200;
        o.marking = Marking::Dorfler(fraction);
        o
    };
    series.push(case("h Q1, Jacobi-CG", h(1, Solver::Cg { tol: 1e-6 }, t1))?);
    series.push(case("h Q1, Cholesky", h(1, Solver::Direct, t1))?);
    series.push(case("h Q2, Jacobi-CG", h(2, Solver::Cg { tol: 1e-8 }, t2))?);
    series.push(case("h Q2, Cholesky", h(2, Solver::Direct, t2))?);
    let mut p = AdaptOptions::h(1);
    p.basis = Basis1d::Hierarchical;
    p.strategy = Strategy::P;
    p.uniform = true;
    p.initial_levels = 2;
    p.max_degree = 8;
    p.max_steps = 8;
    series.push(case("p (uniform, 48 cells)", p)?);
    let mut hp = AdaptOptions::h(3);
    hp.basis = Basis1d::Hierarchical;
    hp.strategy = Strategy::Hp;
    hp.hp_decay = 0.3;
    hp.max_degree = 8;
    hp.estimator = EstimatorKind::Equilibrated;
    hp.target_rel_error = t2;
    hp.max_dofs = if smoke { 3000 } else { 40_000 };
    hp.max_steps = 200;
    series.push(case("hp (equilibrated)", hp)?);
    if let Some(v) = &venv {
        match peer(v, &out, smoke, fraction) {
            Ok(s) => series.extend(s),
            Err(e) => eprintln!("peer comparison skipped: {e}"),
        }
    }
    // CSV (the series names contain commas: the csv crate quotes them).
    let rows = series.iter().flat_map(|s| {
        s.steps.iter().enumerate().map(|(i, r)| {
            vec![
                s.name.clone(),
                i.to_string(),
                r.0.to_string(),
                format!("{:.6e}", r.1),
                format!("{:.6}", r.2),
                format!("{:.6}", r.3),
            ]
        })
    });
    let csv_path = out.join("adapt.csv");
    tread::io::output::write_text_csv(
        &csv_path,
        &[
            "series",
            "step",
            "n",
            "rel_error",
            "cumulative_time_s",
            "step_time_s",
        ],
        rows,
    )
    .map_err(|e| e.to_string())?;
    plot(&out.join("adapt_dofs.png"), &series, false)?;
    plot(&out.join("adapt_time.png"), &series, true)?;
    println!("| series | steps | final N | final rel. error | total time [s] | time to {t1:.0e} | time to {t2:.0e} | mean time per step [s] |");
    println!("|---|---|---|---|---|---|---|---|");
    for s in &series {
        let last = s.steps.last().copied().unwrap_or((0, f64::NAN, 0.0, 0.0));
        let f = |t: Option<(f64, usize)>| {
            t.map_or("—".to_string(), |(t, n)| format!("{t:.3} s (N = {n})"))
        };
        println!(
            "| {} | {} | {} | {:.3e} | {:.3} | {} | {} | {:.4} |",
            s.name,
            s.steps.len(),
            last.0,
            last.1,
            last.2,
            f(time_to(s, t1)),
            f(time_to(s, t2)),
            last.2 / s.steps.len().max(1) as f64
        );
    }
    // Error per DOF at matched sizes against the peer (same order).
    for (ours, theirs) in [
        ("h Q1, Cholesky", "scikit-fem P1"),
        ("h Q2, Cholesky", "scikit-fem P2"),
    ] {
        let (Some(a), Some(b)) = (
            series.iter().find(|s| s.name == ours),
            series.iter().find(|s| s.name.starts_with(theirs)),
        ) else {
            continue;
        };
        // Errors of both at the largest N both reached (log-interpolated along each).
        let (Some(&(na, _, ta, _)), Some(&(nb, _, tb, _))) = (a.steps.last(), b.steps.last())
        else {
            continue;
        };
        let n = na.min(nb);
        let (ea, eb) = (interp_at(a, n as f64), interp_at(b, n as f64));
        let per_step_a = ta / a.steps.len() as f64;
        let per_step_b = tb / b.steps.len() as f64;
        println!(
            "peer ratio {ours} vs {theirs}: error at N = {n}: {ea:.3e} vs {eb:.3e} (ratio {:.2}); mean time per adaptive step {per_step_a:.4} s vs {per_step_b:.4} s (ratio {:.2})",
            ea / eb,
            per_step_a / per_step_b
        );
    }
    println!(
        "wrote {}, adapt_dofs.png, adapt_time.png",
        csv_path.display()
    );
    Ok(())
}

/// Relative error of series `s` at `n` equations (log–log interpolation between steps).
fn interp_at(s: &Series, n: f64) -> f64 {
    let pts = &s.steps;
    if let Some(&(nl, el, _, _)) = pts.last().filter(|p| p.0 as f64 == n) {
        let _ = nl;
        return el;
    }
    for w in pts.windows(2) {
        let (n0, e0) = (w[0].0 as f64, w[0].1);
        let (n1, e1) = (w[1].0 as f64, w[1].1);
        if n0 <= n && n <= n1 && n1 > n0 {
            let t = (n.ln() - n0.ln()) / (n1.ln() - n0.ln());
            return (e0.ln() + t * (e1.ln() - e0.ln())).exp();
        }
    }
    f64::NAN
}
