//! Outputs read back by independent readers: every sink's file (CSV, VTU/PVD, MCAP, Rerun
//! `.rrd`, PNG) after a static indentation run and after a synthetic time-stepping driver (a
//! rigid rotation of the mesh) with decimation; an MCAP left unfinished (as by a killed process)
//! and truncated files stay readable up to their last complete chunk.

mod logread;
#[path = "common/tempdir.rs"]
mod tempdir;

use logread::*;
use std::path::Path;
use tempdir::TestDir;
use tread::app::{self, RunOptions};
use tread::driver::frame::SolidFrame;
use tread::io::record::mcap::McapSink;
use tread::io::record::{
    self, ContinuationPoint, PointKind, Recorder, Recorders, RunEnd, RunMeta, SteadyReached,
    StepInfo,
};
use tread::io::Scene;

fn tmpdir(name: &str) -> TestDir {
    TestDir::new("logs", name)
}

const STATIC: &str = r#"
[scene]
name = "logs_static"
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
load_steps = 3
[output]
sinks = ["summary", "csv", "vtu", "mcap", "rerun", "png"]
"#;

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn static_run_every_output_reads_back() {
    let dir = tmpdir("static");
    let scene = Scene::from_toml_str(STATIC, "static", &[]).unwrap_or_else(|e| panic!("{e}"));
    let o = app::run(
        &scene,
        &RunOptions {
            out_dir: dir.to_path_buf(),
            verbose: false,
            quiet: true,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(o.converged);
    let s = summary(&dir);
    let steps = s["solver"]["load_steps"].as_u64().unwrap() as usize;
    let fy = s["results"]["hub_force_y"].as_f64().unwrap();
    let torque = s["results"]["hub_torque"].as_f64().unwrap();
    assert!(steps >= 3 && fy < 0.0, "{s}");
    let mesh = &app::build_system(&scene).unwrap().model.mesh;
    let n_nodes = mesh.n_nodes();

    // history.csv: one row per load step, time = λ, the final hub force = the summary's.
    let (h, rows) = read_csv(&dir.join("history.csv"));
    assert_eq!(rows.len(), steps);
    let t = column(&h, &rows, "time");
    assert_eq!(
        column(&h, &rows, "step"),
        (0..steps).map(|i| i as f64).collect::<Vec<_>>()
    );
    assert!(t.windows(2).all(|w| w[1] > w[0]) && (t[steps - 1] - 1.0).abs() < 1e-15);
    let hfy = column(&h, &rows, "hub_force_y");
    assert!(
        (hfy[steps - 1] - fy).abs() <= 1e-9 * fy.abs(),
        "{} vs {fy}",
        hfy[steps - 1]
    );
    // Load stepping from first touch: the hub force grows monotonically in magnitude.
    assert!(hfy.windows(2).all(|w| w[1] < w[0]), "{hfy:?}");
    let es = column(&h, &rows, "energy_strain");
    assert!(es.iter().all(|e| *e > 0.0));

    // VTU/PVD: one data set per step with its λ; the last file's displacement = nodes.csv.
    let pvd = parse_pvd(&dir.join("fields.pvd"));
    assert_eq!(pvd.len(), steps);
    for (k, (ts, _)) in pvd.iter().enumerate() {
        assert!((ts - t[k]).abs() <= 1e-9, "{ts} vs {}", t[k]);
    }
    let last = parse_vtu(&dir.join(&pvd[steps - 1].1));
    assert_eq!(last.n_points, n_nodes);
    assert_eq!(last.n_cells, mesh.n_cells());
    assert_eq!(last.points.len(), 3 * n_nodes);
    assert_eq!(last.arrays["types"], vec![28.0; mesh.n_cells()]);
    assert_eq!(last.arrays["connectivity"].len(), 9 * mesh.n_cells());
    assert!((last.time - 1.0).abs() < 1e-12);
    let (nh, nodes) = read_csv(&dir.join("nodes.csv"));
    let u1 = column(&nh, &nodes, "u1");
    let u2 = column(&nh, &nodes, "u2");
    let disp = &last.arrays["displacement"];
    for n in 0..n_nodes {
        assert!((disp[3 * n] - u1[n]).abs() <= 1e-9 * (1.0 + u1[n].abs()));
        assert!((disp[3 * n + 1] - u2[n]).abs() <= 1e-9 * (1.0 + u2[n].abs()));
    }
    assert_eq!(last.arrays["max_shear_stress"].len(), n_nodes);

    // MCAP: counts per topic, log times = λ in ns, values = the other outputs.
    let m = read_mcap(&dir.join("run.mcap"));
    assert!(!m.truncated, "a finished MCAP reads to its end");
    for topic in [
        "/tread/step",
        "/tread/nodes",
        "/tread/mesh",
        "/tread/hub",
        "/tread/energy",
    ] {
        assert_eq!(m.count(topic), steps, "{topic}");
    }
    assert_eq!(m.count("/tread/contact"), steps);
    assert_eq!(m.count("/tread/series/hub_force_y"), steps);
    let (_, conv) = read_csv(&dir.join("convergence.csv"));
    assert_eq!(m.count("/tread/newton"), conv.len());
    for (k, st) in m.topic("/tread/step").iter().enumerate() {
        assert_eq!(st.schema, "treadstep.TreadStep");
        assert_eq!(f64_field(&st.msg, "index"), k as f64);
        assert!((f64_field(&st.msg, "time") - t[k]).abs() < 1e-12);
        assert_eq!(st.log_time, (t[k] * 1e9).round() as u64);
    }
    let hub = m.topic("/tread/hub");
    let last_hub = &hub[steps - 1].msg;
    assert!((f64_field(last_hub, "force_y") - fy).abs() <= 1e-9 * fy.abs());
    assert!((f64_field(last_hub, "torque") - torque).abs() <= 1e-9 * (1.0 + torque.abs()));
    // The point cloud of the last step: deformed node positions X + u (f32).
    let cloud = &m.topic("/tread/nodes")[steps - 1].msg;
    assert_eq!(m.topic("/tread/nodes")[0].schema, "foxglove.PointCloud");
    let stride = f64_field(cloud, "point_stride") as usize;
    let data = bytes_field(cloud, "data");
    assert_eq!(data.len(), stride * n_nodes);
    let (x1, x2) = (column(&nh, &nodes, "X1"), column(&nh, &nodes, "X2"));
    for n in 0..n_nodes {
        let f = |o: usize| {
            f32::from_le_bytes(data[n * stride + o..n * stride + o + 4].try_into().unwrap())
        };
        assert!((f64::from(f(0)) - (x1[n] + u1[n])).abs() < 1e-5);
        assert!((f64::from(f(4)) - (x2[n] + u2[n])).abs() < 1e-5);
    }
    // Contact arrays along the boundary: the resultant of t_n ds0 balances the hub force.
    let patch = &m.topic("/tread/contact_patch")[steps - 1].msg;
    let tn = list_f64(patch, "t_n");
    let ds0 = list_f64(patch, "ds0");
    let fc: f64 = tn.iter().zip(&ds0).map(|(a, b)| a * b).sum();
    assert!(
        (fc + fy).abs() <= 1e-6 * fy.abs(),
        "contact {fc} vs hub {fy}"
    );
    assert_eq!(m.metadata["scene"]["name"], "logs_static");
    assert!(m.metadata["scene"]["toml"].contains("[contact]"));
    assert_eq!(
        m.metadata["build"]["tread_version"],
        env!("CARGO_PKG_VERSION")
    );
    assert_eq!(m.metadata["summary"]["converged"], "true");
    assert!(m.count("/tread/log") >= 2);

    // Rerun: the rerun crate's decoder.
    #[cfg(feature = "rerun")]
    {
        let r = read_rrd(&dir.join("run.rrd"));
        let fyr = &r["/hub/force_y"];
        assert_eq!(fyr.scalars.len(), steps);
        assert!((fyr.scalars[steps - 1] - fy).abs() <= 1e-9 * fy.abs());
        let st: Vec<i64> = fyr.times.iter().map(|x| x.0).collect();
        assert_eq!(st, (0..steps as i64).collect::<Vec<_>>());
        // Load stepping: no `sim_time` (read back as −1); λ is a series.
        assert!(fyr.times.iter().all(|x| x.1 == -1), "{:?}", fyr.times);
        let lambda = &r["/series/load_factor"].scalars;
        assert_eq!(lambda.len(), steps);
        assert!((lambda[steps - 1] - 1.0).abs() < 1e-12);
        let mesh_r = &r["/body/mesh"];
        // Every step, and the reference configuration at step −1 first.
        assert_eq!(mesh_r.mesh_vertices, vec![n_nodes; steps + 1]);
        assert_eq!(mesh_r.times[0], (-1, -1));
        assert_eq!(mesh_r.times[1], (0, -1));
        for n in 0..n_nodes {
            let p = mesh_r.last_vertices[n];
            assert!((f64::from(p[0]) - (x1[n] + u1[n])).abs() < 1e-5);
        }
        assert_eq!(r["/newton/iterations"].scalars.len(), steps);
        assert_eq!(r["/newton/residual"].scalars.len(), conv.len());
        assert!(r["/scene"].static_rows >= 1);
        assert!(r.contains_key("/contact/chart/pressure/curve") && r.contains_key("/road"));
    }

    // PNG plots exist and are PNG images of the drawn size.
    for p in [
        "hub_forces.png",
        "hub_torque.png",
        "energy.png",
        "contact.png",
    ] {
        assert_eq!(png_size(&dir.join(p)), (900, 560), "{p}");
    }
}

/// Build the spinning system of a small scene and drive it as a time-stepping driver would: a
/// rigid rotation u = (Q(ωt) − I) X, one step per dt, events to `rec`.
fn rigid_rotation_run(dir: &Path, sinks: &str, every: usize, steps: u64) -> (Scene, f64) {
    let text = format!(
        r#"
[scene]
name = "logs_rotation"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
n_r = 2
n_theta = 16
[material]
model = "neo_hookean"
mu = 200.0
lambda = 1800.0
rho = 0.027
[analysis]
mode = "spinning"
[motion]
omega = 20.0
[output]
sinks = {sinks}
every = {every}
"#
    );
    let scene = Scene::from_toml_str(&text, "rotation", &[]).unwrap_or_else(|e| panic!("{e}"));
    let mut sys = app::build_system(&scene).unwrap();
    let omega = scene.motion.omega;
    sys.model.omega2 = omega * omega;
    let (mut rec, _) = app::build_recorders(&scene, dir, true);
    let toml = scene.to_toml_string();
    let dt = 0.002;
    rec.run_started(&RunMeta {
        scene_name: "logs_rotation",
        mode: "rigid_rotation",
        scene_toml: &toml,
        version: env!("CARGO_PKG_VERSION"),
        features: record::build_features(),
        mesh: Some(&sys.model.mesh),
        time_name: "time",
        time_end: dt * steps as f64,
        revolution_period: Some(2.0 * std::f64::consts::PI / omega),
    });
    for k in 0..steps {
        let t = dt * (k + 1) as f64;
        let (s, c) = (omega * t).sin_cos();
        for (n, p) in sys.model.mesh.nodes.iter().enumerate() {
            sys.x[2 * n] = c * p[0] - s * p[1] - p[0];
            sys.x[2 * n + 1] = s * p[0] + c * p[1] - p[1];
        }
        let info = StepInfo {
            index: k,
            time: t,
            dt,
            newton_iterations: 1,
            residual: 0.0,
            is_final: k + 1 == steps,
        };
        let frame = rec
            .wants_view(&info)
            .then(|| SolidFrame::capture(&sys, rec.wants_fields(&info)));
        let scalars = [("angle", omega * t)];
        rec.step(
            &info,
            frame.as_ref().map(|f| f.view(&sys, &scalars)).as_ref(),
        );
    }
    // Then, as a steady/continuation driver would: five branch points and a steady state.
    for i in 0..5u64 {
        let measures = [("u_r_outer", 0.01 * i as f64), ("hub_torque", -(i as f64))];
        rec.continuation_point(&ContinuationPoint {
            index: i,
            parameter_name: "omega",
            parameter: 10.0 + i as f64,
            arc_length: i as f64,
            newton_iterations: 3,
            det_sign: if i < 3 { 1 } else { -1 },
            kind: if i == 3 {
                PointKind::LimitPoint
            } else {
                PointKind::Regular
            },
            measures: &measures,
        });
    }
    let frame = SolidFrame::capture(&sys, true);
    rec.steady_reached(
        &SteadyReached {
            time: dt * steps as f64,
            change: 1e-9,
            results: &[("hub_force_y", -5.0)],
        },
        &frame.view(&sys, &[]),
    );
    let errs = rec.run_finished(&RunEnd {
        converged: true,
        interrupted: false,
        error: None,
        steps,
        wall_time_s: 0.0,
        summary: None,
    });
    assert!(errs.is_empty(), "{errs:?}");
    (scene, dt)
}

#[test]
fn synthetic_time_stepping_with_decimation_reads_back() {
    let dir = tmpdir("rotation");
    let steps = 20u64;
    let every = 3usize;
    let (scene, dt) = rigid_rotation_run(
        &dir,
        r#"["csv", "vtu", "mcap", "rerun", "png"]"#,
        every,
        steps,
    );
    let recorded: Vec<u64> = (0..steps)
        .filter(|k| k % every as u64 == 0 || *k + 1 == steps)
        .collect();
    assert_eq!(recorded.len(), 8); // 0, 3, …, 18 and the final 19
    let sys = app::build_system(&scene).unwrap();
    let mesh = &sys.model.mesh;
    let omega = scene.motion.omega;
    let (ri, ro, rho) = (1.0f64, 2.0f64, 0.027);
    // A rigid rotation: no strain energy; kinetic ½ ρ ω² ∫|X|² dA = ρ ω² π (ro⁴ − ri⁴)/4. The
    // Q2 interpolation of the rotation and the isoparametric cells (the default geometry) are
    // not exact on this coarse mesh: O(h³) errors, ~1e-4 relative here.
    let ke = rho * omega * omega * std::f64::consts::PI * (ro.powi(4) - ri.powi(4)) / 4.0;

    // history.csv has every step (scalars are not decimated; `every` thins the fields).
    let (h, rows) = read_csv(&dir.join("history.csv"));
    let all: Vec<u64> = (0..steps).collect();
    assert_eq!(
        column(&h, &rows, "step"),
        all.iter().map(|k| *k as f64).collect::<Vec<_>>()
    );
    for (r, k) in column(&h, &rows, "time").iter().zip(&all) {
        assert!((r - dt * (*k + 1) as f64).abs() < 1e-15);
    }
    for e in column(&h, &rows, "energy_kinetic") {
        assert!((e - ke).abs() <= 5e-4 * ke, "{e} vs {ke}");
    }
    for e in column(&h, &rows, "energy_strain") {
        // Relative to the elastic energy scale μ·A (A = π (ro² − ri²)).
        let scale = 200.0 * std::f64::consts::PI * (ro * ro - ri * ri);
        assert!(
            e.abs() <= 1e-4 * scale,
            "strain energy of a rigid rotation: {e}"
        );
    }
    for tau in column(&h, &rows, "max_shear_stress") {
        assert!(tau.abs() < 1e-2 * 200.0, "{tau}"); // vs the shear modulus μ = 200
    }
    eprintln!(
        "rigid rotation: kinetic {:?} (exact {ke}), strain {:?}, max shear {:?}",
        column(&h, &rows, "energy_kinetic").last(),
        column(&h, &rows, "energy_strain").last(),
        column(&h, &rows, "max_shear_stress").last()
    );

    let pvd = parse_pvd(&dir.join("fields.pvd"));
    assert_eq!(pvd.len(), recorded.len());
    let v = parse_vtu(&dir.join(&pvd.last().unwrap().1));
    let ang = omega * dt * steps as f64;
    for (n, p) in mesh.nodes.iter().enumerate() {
        let u = [
            v.arrays["displacement"][3 * n],
            v.arrays["displacement"][3 * n + 1],
        ];
        assert!((p[0] + u[0] - (ang.cos() * p[0] - ang.sin() * p[1])).abs() < 1e-9);
        assert!((p[1] + u[1] - (ang.sin() * p[0] + ang.cos() * p[1])).abs() < 1e-9);
    }

    let m = read_mcap(&dir.join("run.mcap"));
    assert_eq!(m.count("/tread/step"), steps as usize, "every step's info");
    // Decimated views; the steady state's field on its own channels at the end.
    assert_eq!(m.count("/tread/nodes"), recorded.len(), "decimated views");
    assert_eq!(m.count("/tread/steady/nodes"), 1, "steady field");
    assert_eq!(m.count("/tread/series/angle"), recorded.len());
    let lt: Vec<u64> = m
        .topic("/tread/nodes")
        .iter()
        .take(recorded.len())
        .map(|x| x.log_time)
        .collect();
    let want: Vec<u64> = recorded
        .iter()
        .map(|k| (dt * (*k + 1) as f64 * 1e9).round() as u64)
        .collect();
    assert_eq!(lt, want);
    for (x, k) in m.topic("/tread/series/angle").iter().zip(&recorded) {
        assert!((f64_field(&x.msg, "value") - omega * dt * (*k + 1) as f64).abs() < 1e-12);
    }

    // Branch points and the steady state.
    let bp = m.topic("/tread/continuation");
    assert_eq!(bp.len(), 5);
    for (i, p) in bp.iter().enumerate() {
        assert_eq!(f64_field(&p.msg, "parameter"), 10.0 + i as f64);
        assert_eq!(
            list_f64(&p.msg, "measure_values"),
            vec![0.01 * i as f64, -(i as f64)]
        );
        assert_eq!(
            f64_field(&p.msg, "det_sign"),
            if i < 3 { 1.0 } else { -1.0 }
        );
    }
    let sd = m.topic("/tread/steady");
    assert_eq!(sd.len(), 1);
    assert_eq!(list_f64(&sd[0].msg, "values"), vec![-5.0]);
    let st = parse_vtu(&dir.join("steady.vtu"));
    assert_eq!(st.n_points, mesh.n_nodes());
    assert_eq!(png_size(&dir.join("branch.png")), (900, 560));

    #[cfg(feature = "rerun")]
    {
        let r = read_rrd(&dir.join("run.rrd"));
        let mut om = r["/branch/omega"].scalars.clone();
        om.sort_by(f64::total_cmp);
        assert_eq!(om, vec![10.0, 11.0, 12.0, 13.0, 14.0]);
        assert_eq!(r["/branch/hub_torque"].scalars.len(), 5);
        assert!(r["/branch/table"].static_rows >= 1);
        assert_eq!(r["/steady/mesh"].mesh_vertices, vec![mesh.n_nodes()]);
        assert_eq!(r["/body/mesh"].mesh_vertices.len(), recorded.len() + 1);
        let k = &r["/energy/kinetic"];
        assert_eq!(
            k.times.iter().map(|x| x.0 as u64).collect::<Vec<_>>(),
            recorded
        );
        assert!(k.scalars.iter().all(|e| (e - ke).abs() <= 5e-4 * ke));
        assert_eq!(r["/newton/iterations"].scalars.len(), steps as usize);
        let sim: Vec<i64> = k.times.iter().map(|x| x.1).collect();
        assert_eq!(sim.iter().map(|x| *x as u64).collect::<Vec<_>>(), want);
    }
    for p in ["series.png", "branch.png"] {
        assert!(png_size(&dir.join(p)).0 > 0, "{p}");
    }
    // Time steps and continuation points in one run: the histories would mix two clocks, so
    // they are not drawn (branch.png has the loads against the parameter).
    for p in ["energy.png", "hub_forces.png", "hub_torque.png"] {
        assert!(!dir.join(p).exists(), "{p} drawn over two clocks");
    }
}

#[test]
fn unfinished_and_truncated_mcap_read_up_to_the_last_chunk() {
    // An MCAP sink that is never finished nor dropped: as after SIGKILL.
    let dir = tmpdir("killed");
    let path = dir.join("run.mcap");
    let scene = Scene::from_toml_str(STATIC, "static", &[]).unwrap();
    let sys = app::build_system(&scene).unwrap();
    let mut sink = McapSink::with_path(path.clone());
    let toml = scene.to_toml_string();
    sink.run_started(&RunMeta {
        scene_name: "killed",
        mode: "static",
        scene_toml: &toml,
        version: env!("CARGO_PKG_VERSION"),
        features: "",
        mesh: Some(&sys.model.mesh),
        time_name: "time",
        time_end: 1.0,
        revolution_period: None,
    });
    let frame = SolidFrame::capture(&sys, true);
    let n = 12u64;
    for k in 0..n {
        let info = StepInfo {
            index: k,
            time: 0.1 * (k + 1) as f64,
            dt: 0.1,
            newton_iterations: 2,
            residual: 1e-12,
            is_final: false,
        };
        sink.step(&info, Some(&frame.view(&sys, &[])));
    }
    std::mem::forget(sink); // no finish, no drop: the file ends after the last closed chunk
    let full = read_mcap(&path);
    assert!(full.truncated, "no summary and no end magic");
    let steps: Vec<f64> = full
        .topic("/tread/step")
        .iter()
        .map(|m| f64_field(&m.msg, "index"))
        .collect();
    assert_eq!(steps, (0..n).map(|k| k as f64).collect::<Vec<_>>());
    assert_eq!(full.count("/tread/nodes"), n as usize);
    assert_eq!(full.metadata["scene"]["name"], "killed");

    // Cut the file anywhere: the reader returns a consistent prefix (whole steps only, in
    // order), never garbage.
    let bytes = std::fs::read(&path).unwrap();
    let cut_path = dir.join("cut.mcap");
    let mut previous = 0;
    for frac in [0.2, 0.35, 0.5, 0.65, 0.8, 0.95] {
        let cut = (bytes.len() as f64 * frac) as usize;
        std::fs::write(&cut_path, &bytes[..cut]).unwrap();
        let m = read_mcap(&cut_path);
        let idx: Vec<f64> = m
            .topic("/tread/step")
            .iter()
            .map(|x| f64_field(&x.msg, "index"))
            .collect();
        assert_eq!(idx, (0..idx.len()).map(|k| k as f64).collect::<Vec<_>>());
        // A step's view is in the same chunk as its info: no step without its nodes.
        assert_eq!(m.count("/tread/nodes"), idx.len(), "cut at {frac}");
        assert!(idx.len() >= previous && idx.len() < n as usize);
        previous = idx.len();
    }
    assert!(previous > 0);
}

#[test]
fn no_sink_fan_out_asks_for_no_view() {
    let r = Recorders::new();
    let info = StepInfo {
        index: 0,
        time: 1.0,
        dt: 1.0,
        newton_iterations: 1,
        residual: 0.0,
        is_final: true,
    };
    assert!(!r.wants_view(&info));
    // Progress alone (the quiet flag off) never asks for views either.
    let mut p = Recorders::new();
    p.push(Box::new(record::progress::Progress::new()), 1);
    assert!(!p.wants_view(&info));
}
