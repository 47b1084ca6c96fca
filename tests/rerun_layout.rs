//! The Rerun recording as an engineer opens it: `run.rrd` (and an `.rrd` converted from
//! `run.mcap`) carries a default layout (a blueprint store, activated) with a head-on body view,
//! one time-series view for the hub forces and torque together, one for Newton, one for the
//! energies and bar charts of the contact tractions against x1, named with the scene's units;
//! the body is visible at sim_time 0 (the reference configuration); the contact bar charts have
//! widths that tile the patch (not 1-length-unit bars); the body view is magnified by
//! `[output] displacement_scale`; a killed run's `.rrd` is repaired by `tread replay --to`.

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

#[test]
fn run_rrd_has_the_default_layout_units_initial_state_and_tiled_bars() {
    let dir = TestDir::new("rerun_layout", "run");
    let out = run(&dir, &[]);
    let rrd = out.join("run.rrd");
    let s = read_stores(&rrd);

    // The layout: a blueprint store, activated and the default.
    assert_eq!(s.activation, vec![(true, true)]);
    assert!(s.blueprint_entities.iter().any(|e| e == "/viewport"));
    for (class, n) in [("3D", 1), ("TimeSeries", 4), ("BarChart", 2)] {
        let got = s.blueprint_text.matches(&format!("\"{class}\"")).count();
        assert_eq!(got, n, "{class} views");
    }
    for name in [
        "Body head-on [mm], colour τ = max in-plane shear [N/mm²], u ×10",
        "Hub force F_x, F_y [N/mm] and torque M [N·mm/mm] against load factor λ on sim_time",
        "Newton iterations and relative residual",
        "Energies (strain, kinetic, total) [N·mm/mm]",
        "Contact pressure t_n [N/mm²] against x1 [mm]",
        "Contact shear t_T [N/mm²] against x1 [mm]",
    ] {
        assert!(s.blueprint_text.contains(name), "no view named {name:?}");
    }
    for q in [
        "/hub/**",
        "/newton/**",
        "/energy/**",
        "/contact/pressure",
        "/body/**",
    ] {
        assert!(s.blueprint_text.contains(q), "no view shows {q}");
    }
    assert!(s.blueprint_text.contains("EyeControls3D"));

    // Series named with units.
    let names = |e: &str| s.text[e].clone();
    assert!(names("/hub/force_x").contains("F_x [N/mm]"));
    assert!(names("/hub/torque").contains("M [N·mm/mm]"));

    // The body at sim_time 0: the reference configuration, before step 0.
    let r = read_rrd(&rrd);
    let mesh = &r["/body/mesh"];
    assert_eq!(
        mesh.times[0],
        (-1, 0),
        "first body/mesh row: no step, sim_time 0"
    );
    let (h, rows) = read_csv(&out.join("history.csv"));
    let steps = rows.len();
    assert_eq!(mesh.times.len(), steps + 1);
    assert!(r.contains_key("/body/colour_scale"));
    assert!(r.contains_key("/contact/curves/pressure"));

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
    let _ = h;

    // Bar charts: widths tile the patch (sum = extent + half of each end spacing), far below
    // the default 1 length unit each.
    let widths_id = rerun::archetypes::BarChart::descriptor_widths().component;
    let absc_id = rerun::archetypes::BarChart::descriptor_abscissa().component;
    let last = s.chunks["/contact/pressure"].last().unwrap();
    assert!(
        last.components().get_array(widths_id).is_some(),
        "no widths"
    );
    let w: Vec<f32> = last.iter_slices::<f32>(widths_id).last().unwrap().to_vec();
    assert!(w.len() >= 3, "{w:?}");
    assert!(w.iter().all(|&x| x > 0.0 && x < 0.2), "{w:?}");
    let _ = absc_id;
    let cx = column(&h, &rows, "patch_x_min");
    let cy = column(&h, &rows, "patch_x_max");
    let extent = cy[steps - 1] - cx[steps - 1];
    let total: f64 = w.iter().map(|x| f64::from(*x)).sum();
    assert!(
        total >= extent && total <= extent * 1.5 + 0.1,
        "bars span {total}, patch {extent}"
    );
}

#[test]
fn replayed_mcap_has_the_layout_and_contact_bars() {
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
        "/tread/contact_curves/pressure",
    ] {
        assert!(s.blueprint_text.contains(q), "no view shows {q}");
    }
    assert!(s
        .blueprint_text
        .contains("Contact pressure t_n [N/mm²] against x1 [mm]"));
    assert!(s.chunks.contains_key("/tread/contact_curves/pressure"));
    assert!(s.chunks.contains_key("/tread/newton/log10_residual"));
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
