//! The Rerun recording as an engineer opens it: `run.rrd` (and an `.rrd` converted from
//! `run.mcap`) carries a default layout (a blueprint store, activated) with a head-on body view,
//! one time-series view for the hub forces and torque together, one for Newton, one for the
//! energies and bar charts of the contact tractions against x1, named with the scene's units;
//! Newton iterations and residuals in separate views; the body is visible before the first step
//! (the reference configuration); a load-stepping run (static, steady) is on the `step`
//! sequence, with no duration timeline; the colour scale's labels are light and beside the bar;
//! the contact charts are drawn against x1 over the patch with round ticks; recordings are named
//! by scene and mode; an `.rrd` converted from MCAP has the colour scale, contact curves, arrows
//! and charts and the units; the body view is magnified by `[output] displacement_scale`; a
//! killed run's `.rrd` is repaired by `tread replay --to`.

#![cfg(feature = "rerun")]

mod logread;
#[path = "common/tempdir.rs"]
mod tempdir;

use logread::*;
use rerun::external::re_log_encoding::DecoderApp;
use rerun::log::{Chunk, LogMsg};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;
use tempdir::TestDir;

fn tread() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tread"))
}

const SCENE: &str = r#"
[scene]
name = "layout_static"
units = "mm-N-s"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
n_r = 2
n_theta = 32
grading_theta = 0.5
[material]
model = "mooney_rivlin"
c1 = 80.0
c2 = 20.0
kappa = 2000.0
rho = 0.027
[analysis]
mode = "static"
[road]
disp = 0.08
[contact]
c_n = 2.0e5
[solver]
load_steps = 2
[output]
sinks = ["summary", "csv", "mcap", "rerun"]
displacement_scale = 10
"#;

/// What a decoded `.rrd` holds, by store kind.
#[derive(Default)]
struct Stores {
    /// Debug text of every blueprint chunk (display names, classes and queries are in it).
    blueprint_text: String,
    blueprint_entities: Vec<String>,
    activation: Vec<(bool, bool)>,
    /// Recording chunks by entity.
    chunks: BTreeMap<String, Vec<Chunk>>,
    /// Debug text of the recording chunks by entity (string values are in it).
    text: BTreeMap<String, String>,
}

fn read_stores(path: &Path) -> Stores {
    let f = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut s = Stores::default();
    for msg in DecoderApp::decode_lazy(std::io::BufReader::new(f)) {
        let msg = msg.unwrap_or_else(|e| panic!("{}: decode: {e}", path.display()));
        match msg {
            LogMsg::BlueprintActivationCommand(c) => {
                s.activation.push((c.make_active, c.make_default));
            }
            LogMsg::ArrowMsg(store, arrow) => {
                let chunk = Chunk::from_arrow_msg(&arrow).expect("chunk");
                let e = chunk.entity_path().to_string();
                if store.is_blueprint() {
                    s.blueprint_text.push_str(&format!("{:?}\n", arrow.batch));
                    s.blueprint_entities.push(e);
                } else {
                    s.text
                        .entry(e.clone())
                        .or_default()
                        .push_str(&format!("{:?}\n", arrow.batch));
                    s.chunks.entry(e).or_default().push(chunk);
                }
            }
            LogMsg::SetStoreInfo(_) => {}
        }
    }
    s
}

fn run(dir: &Path, extra: &[&str]) -> std::path::PathBuf {
    let f = dir.join("scene.toml");
    std::fs::write(&f, SCENE).unwrap();
    let out = dir.join("out");
    let o = tread()
        .args(["-q", "run", f.to_str().unwrap(), "--out"])
        .arg(&out)
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

/// Timelines of every temporal recording chunk.
fn timelines(s: &Stores) -> std::collections::BTreeSet<String> {
    s.chunks
        .values()
        .flatten()
        .filter(|c| !c.is_static())
        .flat_map(|c| {
            c.timelines()
                .keys()
                .map(|t| t.to_string())
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Positions of the Points2D rows of `entity` (the last row).
fn last_points2d(s: &Stores, entity: &str) -> Vec<[f32; 2]> {
    let id = rerun::archetypes::Points2D::descriptor_positions().component;
    let c = s.chunks[entity].last().unwrap();
    c.iter_slices::<[f32; 2]>(id).last().unwrap().to_vec()
}

/// Positions and colours of the Points3D rows of `entity` (the last row).
fn last_points3d(s: &Stores, entity: &str) -> (Vec<[f32; 3]>, Vec<u32>) {
    let pid = rerun::archetypes::Points3D::descriptor_positions().component;
    let cid = rerun::archetypes::Points3D::descriptor_colors().component;
    let c = s.chunks[entity].last().unwrap();
    (
        c.iter_slices::<[f32; 3]>(pid).last().unwrap().to_vec(),
        c.iter_slices::<u32>(cid).last().unwrap().to_vec(),
    )
}

/// The recording's name (its `/__properties` chunk) contains `name`.
fn assert_named(s: &Stores, name: &str) {
    let props: String = s
        .text
        .iter()
        .filter(|(e, _)| e.contains("__properties"))
        .map(|(_, t)| t.as_str())
        .collect();
    assert!(
        props.contains(name),
        "recording not named {name:?}: {props}"
    );
}

#[test]
fn run_rrd_has_the_default_layout_units_initial_state_and_charts() {
    let dir = TestDir::new("rerun_layout", "run");
    let out = run(&dir, &[]);
    let rrd = out.join("run.rrd");
    let s = read_stores(&rrd);

    // The layout: a blueprint store, activated and the default.
    assert_eq!(s.activation, vec![(true, true)]);
    assert!(s.blueprint_entities.iter().any(|e| e == "/viewport"));
    for (class, n) in [("3D", 1), ("TimeSeries", 5), ("2D", 2), ("BarChart", 0)] {
        let got = s.blueprint_text.matches(&format!("\"{class}\"")).count();
        assert_eq!(got, n, "{class} views");
    }
    for name in [
        "Body head-on [mm], colour τ = max in-plane shear [N/mm²], u ×10",
        "Hub force F_x, F_y [N/mm] and torque M [N·mm/mm] against load step",
        "Newton iterations per step against load step",
        "Newton residual: log10 of the relative residual of every iteration",
        "Energies (strain, kinetic, total) [N·mm/mm]",
        "Contact pressure t_n [N/mm²] against x1 [mm]",
        "Contact shear t_T [N/mm²] against x1 [mm]",
    ] {
        assert!(s.blueprint_text.contains(name), "no view named {name:?}");
    }
    for q in [
        "/hub/**",
        "/newton/iterations",
        "/newton/log10_residual",
        "/energy/**",
        "/contact/chart/pressure/**",
        "/body/**",
    ] {
        assert!(s.blueprint_text.contains(q), "no view shows {q}");
    }
    assert!(s.blueprint_text.contains("EyeControls3D"));
    assert!(s.blueprint_text.contains("VisualBounds2D"));

    // Named by scene and mode.
    assert_named(&s, "layout_static (static mode)");

    // Load stepping: the step sequence only, no duration timeline (λ is a series).
    let tl = timelines(&s);
    assert!(tl.contains("step"), "{tl:?}");
    assert!(
        !tl.contains("sim_time"),
        "a load-stepping run on sim_time: {tl:?}"
    );
    let r = read_rrd(&rrd);
    let (h, rows) = read_csv(&out.join("history.csv"));
    let steps = rows.len();
    let lambda = &r["/series/load_factor"];
    assert_eq!(lambda.scalars.len(), steps);
    assert!((lambda.scalars[steps - 1] - 1.0).abs() < 1e-12);
    assert_eq!(
        r["/hub/force_y"]
            .times
            .iter()
            .map(|t| t.0)
            .collect::<Vec<_>>(),
        (0..steps as i64).collect::<Vec<_>>()
    );
    // Few load steps: the series carry markers, so one step is seen too.
    assert!(s.text["/hub/force_y"].contains("SeriesPoints"));

    // Series named with units.
    let names = |e: &str| s.text[e].clone();
    assert!(names("/hub/force_x").contains("F_x [N/mm]"));
    assert!(names("/hub/torque").contains("M [N·mm/mm]"));

    // The body before the first step (step −1): the reference configuration.
    let mesh = &r["/body/mesh"];
    assert_eq!(mesh.times[0].0, -1, "first body/mesh row at step -1");
    assert_eq!(mesh.times.len(), steps + 1);
    assert!(r.contains_key("/contact/curves/pressure"));

    // The colour scale's labels: light text, right of the bar (x1 > 1.25 Ro), not on it.
    let ro = 2.0f32;
    let (lp, lc) = last_points3d(&s, "/body/colour_scale/labels");
    assert_eq!(lp.len(), 2);
    for p in &lp {
        assert!(p[0] > 1.25 * ro + 0.3 * ro, "label at {p:?}");
    }
    for c in &lc {
        let [r, g, b] = [c >> 24, (c >> 16) & 255, (c >> 8) & 255];
        assert!(r.min(g).min(b) >= 200, "label colour {c:08x}");
    }

    // Magnification: the body view shows X + 10 u (the final step).
    let (nh, nrows) = read_csv(&out.join("nodes.csv"));
    let (x1, u1, x2, u2) = (
        column(&nh, &nrows, "X1"),
        column(&nh, &nrows, "u1"),
        column(&nh, &nrows, "X2"),
        column(&nh, &nrows, "u2"),
    );
    let umax = u2.iter().fold(0.0f64, |m, u| m.max(u.abs()));
    assert!(umax > 0.01, "{umax}");
    for n in 0..x1.len() {
        let p = mesh.last_vertices[n];
        assert!(
            (f64::from(p[0]) - (x1[n] + 10.0 * u1[n])).abs() < 1e-4,
            "node {n}"
        );
        assert!(
            (f64::from(p[1]) - (x2[n] + 10.0 * u2[n])).abs() < 1e-4,
            "node {n}"
        );
    }

    // The contact charts: one marker per contact point, spread over most of the frame's width
    // (the x range is the patch, padded to round ticks), inside the frame.
    let (w, hgt) = (
        tread::io::record::rrd_draw::CHART_W,
        tread::io::record::rrd_draw::CHART_H,
    );
    let cx = column(&h, &rows, "patch_x_min");
    let cy = column(&h, &rows, "patch_x_max");
    for e in [
        "/contact/chart/pressure/points",
        "/contact/chart/shear/points",
    ] {
        let p = last_points2d(&s, e);
        assert!(p.len() >= 3, "{e}: {p:?}");
        let xs: Vec<f32> = p.iter().map(|q| q[0]).collect();
        let (a, b) = (xs[0], xs[xs.len() - 1]);
        assert!(xs.windows(2).all(|q| q[0] <= q[1]), "{e}: not along x1");
        assert!(a >= 0.0 && b <= w && b - a >= 0.4 * w, "{e}: {a} … {b}");
        assert!(
            p.iter().all(|q| q[1] <= 1e-6 && q[1] >= -hgt - 1e-6),
            "{e}: {p:?}"
        );
    }
    // The ticks: round values covering the patch, at least three along x1.
    let (x0, step, n) = tread::io::record::rrd_draw::nice_ticks(cx[steps - 1], cy[steps - 1]);
    assert!(n >= 3 && x0 <= cx[steps - 1] && x0 + step * (n - 1) as f64 >= cy[steps - 1]);
    assert!(s.text["/contact/chart/pressure/ticks"].contains("x1 [mm]"));
}

#[test]
fn newton_iterations_and_residuals_are_separate_views() {
    use tread::io::record::rrd_layout::{views, LayoutPaths, LayoutSpec};
    for paths in [LayoutPaths::run(), LayoutPaths::replay()] {
        let spec = LayoutSpec {
            units: Default::default(),
            radius: 1.0,
            magnification: 1.0,
            time_name: "time".into(),
            paths,
        };
        let v = views(&spec);
        let shows = |q: &str| -> Vec<usize> {
            (0..v.len())
                .filter(|&k| v[k].contents.iter().any(|c| c.contains(q)))
                .collect()
        };
        let it = shows("newton_iterations");
        let it = if it.is_empty() {
            shows("newton/iterations")
        } else {
            it
        };
        let res = shows("log10_residual");
        assert_eq!(it.len(), 1, "{v:?}");
        assert_eq!(res.len(), 1, "{v:?}");
        assert_ne!(it, res, "iterations and residuals in one view");
        assert_eq!(v[it[0]].contents.len(), 1, "{:?}", v[it[0]]);
        assert_eq!(v[res[0]].contents.len(), 1, "{:?}", v[res[0]]);
    }
}

#[test]
fn a_steady_recording_is_named_by_mode_and_on_the_step_sequence() {
    let dir = TestDir::new("rerun_layout", "steady");
    let out = dir.join("out");
    let o = tread()
        .args(["-q", "run", "scenarios/rolling_frictionless.toml", "--out"])
        .arg(&out)
        .args([
            "--set",
            "analysis.mode=\"steady\"",
            "--set",
            "mesh.n_theta=32",
            "--set",
            "output.sinks=[\"summary\",\"mcap\",\"rerun\"]",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = read_stores(&out.join("run.rrd"));
    assert_named(&s, "rolling_frictionless (steady mode)");
    let tl = timelines(&s);
    assert!(!tl.contains("sim_time"), "{tl:?}");
    assert!(s.blueprint_text.contains("against load step"));
    let r = read_rrd(&out.join("run.rrd"));
    assert!(!r["/hub/force_y"].scalars.is_empty());
    assert!(r["/hub/force_y"].times.iter().all(|t| t.0 >= 0));
    // The MCAP converted: the same name and timelines.
    let to = dir.join("converted.rrd");
    let o = tread()
        .args(["replay", out.join("run.mcap").to_str().unwrap(), "--to"])
        .arg(&to)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c = read_stores(&to);
    assert_named(&c, "rolling_frictionless (steady mode)");
    let tl = timelines(&c);
    assert!(!tl.contains("sim_time"), "{tl:?}");
}

#[test]
fn replayed_mcap_has_the_layout_colour_scale_curves_arrows_charts_and_units() {
    let dir = TestDir::new("rerun_layout", "replay");
    let out = run(&dir, &[]);
    let to = dir.join("converted.rrd");
    let o = tread()
        .args(["replay", out.join("run.mcap").to_str().unwrap(), "--to"])
        .arg(&to)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = read_stores(&to);
    assert_eq!(s.activation, vec![(true, true)]);
    for q in [
        "/tread/hub/**",
        "/tread/energy/**",
        "/tread/colour_scale/**",
        "/tread/contact_curves/**",
        "/tread/traction",
        "/tread/contact_chart/pressure/**",
    ] {
        assert!(s.blueprint_text.contains(q), "no view shows {q}");
    }
    assert!(s
        .blueprint_text
        .contains("Contact pressure t_n [N/mm²] against x1 [mm]"));
    for e in [
        "/tread/colour_scale",
        "/tread/colour_scale/labels",
        "/tread/contact_curves/pressure",
        "/tread/contact_curves/shear",
        "/tread/traction",
        "/tread/contact_chart/pressure/points",
        "/tread/contact_chart/shear/curve",
        "/tread/newton/log10_residual",
    ] {
        assert!(s.chunks.contains_key(e), "no {e}");
    }
    assert!(s.text["/tread/hub/force_x"].contains("F_x [N/mm]"));
    assert!(s.text["/tread/energy/strain"].contains("strain energy [N·mm/mm]"));
    assert_named(&s, "layout_static (static mode)");
    assert!(!timelines(&s).contains("sim_time"));
    // The charts of the last step match the run's own.
    let run = read_stores(&out.join("run.rrd"));
    assert_eq!(
        last_points2d(&s, "/tread/contact_chart/pressure/points"),
        last_points2d(&run, "/contact/chart/pressure/points")
    );
}

/// Statuses of `rerun rrd verify` on each file, or None without the Rerun CLI.
fn rerun_verify(files: &[&Path]) -> Option<Vec<bool>> {
    let cli = tread::io::replay::find_viewer()?;
    Some(
        files
            .iter()
            .map(|f| {
                Command::new(&cli)
                    .args(["rrd", "verify"])
                    .arg(f)
                    .output()
                    .map(|o| o.status.success())
                    .unwrap_or(false)
            })
            .collect(),
    )
}

#[test]
fn killed_run_rrd_is_repaired_by_replay() {
    let dir = TestDir::new("rerun_layout", "killed");
    let f = dir.join("scene.toml");
    // Many small load steps, so the run is still going when it is killed.
    // A finer mesh and a deeper indentation: most contact Newton solves take 5–6 iterations, so
    // the load increments grow little and the run takes seconds.
    let scene = SCENE
        .replace("load_steps = 2", "load_steps = 80")
        .replace("n_theta = 32", "n_theta = 192")
        .replace("n_r = 2", "n_r = 6")
        .replace("disp = 0.08", "disp = 0.1");
    std::fs::write(&f, scene).unwrap();
    let out = dir.join("out");
    let mut child = tread()
        .args(["-q", "run", f.to_str().unwrap(), "--out"])
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    loop {
        let n = std::fs::read_to_string(out.join("history.csv"))
            .map(|s| s.lines().count().saturating_sub(1))
            .unwrap_or(0);
        if n >= 3 {
            break;
        }
        assert!(child.try_wait().unwrap().is_none(), "the run ended first");
        assert!(t0.elapsed().as_secs() < 300, "timeout");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // Let the recording's writer thread flush (it does so every few hundred ms).
    std::thread::sleep(std::time::Duration::from_millis(600));
    assert!(child.try_wait().unwrap().is_none(), "the run ended first");
    child.kill().unwrap();
    child.wait().unwrap();
    let killed = out.join("run.rrd");
    let repaired = dir.join("repaired.rrd");
    let from_mcap = dir.join("from_mcap.rrd");
    for (src, dst) in [(&killed, &repaired), (&out.join("run.mcap"), &from_mcap)] {
        let o = tread()
            .args(["replay", src.to_str().unwrap(), "--to"])
            .arg(dst)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    // Both read back whole with the layout and steps of the killed run.
    let r = read_rrd(&repaired);
    assert!(r["/hub/force_y"].scalars.len() >= 2);
    assert_eq!(read_stores(&repaired).activation, vec![(true, true)]);
    let m = read_rrd(&from_mcap);
    assert!(m["/tread/hub/force_y"].scalars.len() >= 3);
    match rerun_verify(&[&killed, &repaired, &from_mcap]) {
        Some(ok) => assert_eq!(
            ok,
            [false, true, true],
            "rrd verify of the killed, repaired and converted files"
        ),
        None => eprintln!(
            "SKIPPED: no Rerun CLI (`rerun` on PATH or $TREAD_RERUN_BIN): `rerun rrd verify` not run"
        ),
    }
}
