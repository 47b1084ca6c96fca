//! `tread run` on three-dimensional scenes (`mesh.dimension = 3`), small versions of the shipped
//! scenes through `--set`: the load reached equals the requested load, the spinning slab's mean
//! radial displacement matches the independent radial solution, the output files exist and
//! parse; bad 3D inputs exit non-zero naming the key; `tread adapt` refuses 3D scenes;
//! `tread check` accepts them.

mod common;
mod logread;
#[path = "common/tempdir.rs"]
mod tempdir;

use common::reference::neo_hookean_radial;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use tempdir::TestDir;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn scene(name: &str) -> PathBuf {
    root().join("scenarios").join(name)
}

fn tread(args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_tread"))
        .args(args)
        .output()
        .expect("run tread");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    out
}

/// `tread run scene --out dir --quiet --set …`; the summary on success.
fn run(scene: &Path, dir: &Path, set: &[&str]) -> Value {
    let mut args = vec![
        "run",
        scene.to_str().expect("path"),
        "--out",
        dir.to_str().expect("path"),
        "--quiet",
    ];
    for s in set {
        args.push("--set");
        args.push(s);
    }
    let out = tread(&args);
    assert!(
        out.status.success(),
        "tread run failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("summary.json parses")
}

fn f(v: &Value, path: &str) -> f64 {
    let mut x = v;
    for k in path.split('.') {
        x = match k.parse::<usize>() {
            Ok(i) => &x[i],
            Err(_) => &x[k],
        };
    }
    x.as_f64()
        .unwrap_or_else(|| panic!("{path} is not a number: {x}"))
}

fn csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .expect("header")
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|v| {
                    if v.is_empty() {
                        f64::NAN
                    } else {
                        v.parse().expect("number")
                    }
                })
                .collect::<Vec<f64>>()
        })
        .collect();
    (header, rows)
}

/// Every key of a summary (dotted, `[]` for array elements) is in the output reference.
fn assert_documented(v: &Value, prefix: &str) {
    if let Value::Object(m) = v {
        for (k, x) in m {
            let key = if prefix.is_empty() {
                k.clone()
            } else {
                format!("{prefix}.{k}")
            };
            assert!(
                tread::io::reference::summary_key_documented(&key),
                "summary key {key} is not in docs/reference.md"
            );
            assert_documented(x, &key);
        }
    }
}

/// The field files of a run: the `.pvd` lists every `.vtu`, which exist as VTK XML; the MCAP
/// file has its magic bytes at both ends.
fn assert_field_files(dir: &Path, steps: usize) {
    let pvd = std::fs::read_to_string(dir.join("hex.pvd")).expect("hex.pvd");
    let files: Vec<&str> = pvd
        .split("file=\"")
        .skip(1)
        .filter_map(|s| s.split('"').next())
        .collect();
    assert_eq!(files.len(), steps, "{pvd}");
    for name in files {
        let bytes = std::fs::read(dir.join(name)).expect("vtu file");
        let head = String::from_utf8_lossy(&bytes[..bytes.len().min(400)]).to_string();
        assert!(
            head.contains("<VTKFile") && head.contains("UnstructuredGrid"),
            "{name}: {head}"
        );
    }
    let mcap = std::fs::read(dir.join("hex.mcap")).expect("hex.mcap");
    let magic = b"\x89MCAP0\r\n";
    assert!(
        mcap.starts_with(magic) && mcap.ends_with(magic),
        "hex.mcap magic"
    );
}

#[test]
fn load_controlled_indentation_reaches_the_requested_load() {
    let d = TestDir::new("cli3d", "indentation");
    let load = 20.0;
    let load_set = format!("road.load={load}");
    let s = run(
        &scene("indentation_3d.toml"),
        &d,
        &[
            "mesh.n_r=2",
            "mesh.n_theta=24",
            "mesh.crown_radius=1.0",
            &load_set,
            "solver.load_steps=2",
        ],
    );
    assert_eq!(s["converged"], Value::Bool(true), "{s}");
    assert_eq!(s["mode"], "static");
    assert_documented(&s, "");
    let r = &s["results"];
    // The reference: the requested load, and the road height the penetration is measured from.
    let fy = f(r, "contact_force.1");
    eprintln!(
        "crowned wheel, load {load}: contact force ({:.3e}, {fy:.12e}, {:.3e}), H = {}, {} points in contact",
        f(r, "contact_force.0"),
        f(r, "contact_force.2"),
        f(r, "road_height"),
        r["points_in_contact"]
    );
    assert!(
        (fy - load).abs() <= 1e-8 * load,
        "contact force {fy} vs load {load}"
    );
    assert_eq!(f(r, "load"), load);
    assert!((f(r, "penetration") - (2.0 - f(r, "road_height"))).abs() < 1e-14);
    assert!(f(r, "penetration") > 0.0 && f(r, "max_pressure") > 0.0);
    // A crowned wheel symmetric about x3 = 0 and about the vertical: no lateral or
    // longitudinal force beyond round-off.
    assert!(f(r, "contact_force.0").abs() <= 1e-9 * load);
    assert!(f(r, "contact_force.2").abs() <= 1e-9 * load);
    assert_eq!(s["mesh"]["crown_radius"], 1.0);
    let n_eq = s["dofs"].as_u64().expect("dofs") as usize;
    assert!(n_eq > 0);
    // steps.csv: one row per accepted step, the last one at λ = 1 with the load.
    let (h, rows) = csv(&d.join("steps.csv"));
    assert_eq!(h[..2], ["step", "load_factor"]);
    for c in &h {
        assert!(
            tread::io::reference::csv_column_documented("steps.csv", c),
            "steps.csv column {c}"
        );
    }
    let steps = s["solver"]["load_steps"].as_u64().expect("steps") as usize;
    assert_eq!(rows.len(), steps);
    let last = rows.last().expect("a step");
    assert_eq!(last[1], 1.0);
    assert!((last[5] - load).abs() <= 1e-8 * load);
    // nodes.csv: every node with its reference position and displacement.
    let (h, rows) = csv(&d.join("nodes.csv"));
    assert_eq!(h, ["node", "X1", "X2", "X3", "u1", "u2", "u3"]);
    for c in &h {
        assert!(tread::io::reference::csv_column_documented("nodes.csv", c));
    }
    assert_eq!(
        rows.len() as u64,
        s["mesh"]["nodes"].as_u64().expect("nodes")
    );
    let ur_max = rows
        .iter()
        .map(|r| (r[4] * r[4] + r[5] * r[5] + r[6] * r[6]).sqrt())
        .fold(0.0, f64::max);
    assert!((ur_max - f(r, "max_displacement")).abs() <= 1e-12 * ur_max);
    assert_field_files(&d, steps);
}

/// `contact.csv` of a frictional 3D indentation: the tractions at the facet points sum to the
/// summary's contact force, obey the Coulomb bound |t_T| ≤ μ t_n pointwise, and the friction
/// they carry is that of the last load step (not the zero slip of the committed state).
#[test]
fn contact_table_of_a_frictional_indentation() {
    let d = TestDir::new("cli3d", "contact_table");
    let mu = 0.5;
    let text = std::fs::read_to_string(scene("indentation_3d.toml"))
        .expect("scene")
        .replace("load = 50.0", "disp = 0.03")
        .replace(
            "law = \"none\"",
            &format!("law = \"coulomb_tanh\"\nmu = {mu}\neps = 0.001"),
        );
    let f_scene = d.join("friction_3d.toml");
    std::fs::write(&f_scene, text).expect("write scene");
    let s = run(
        &f_scene,
        &d.join("out"),
        &[
            "mesh.n_r=2",
            "mesh.n_theta=24",
            "output.sinks=[\"summary\",\"csv\"]",
        ],
    );
    assert_eq!(s["converged"], Value::Bool(true), "{s}");
    let r = &s["results"];
    let (h, rows) = csv(&d.join("out/contact.csv"));
    let col = |k: &str| {
        h.iter()
            .position(|c| c == k)
            .unwrap_or_else(|| panic!("{k}: {h:?}"))
    };
    let (tn, t1, t3, da) = (col("t_n"), col("t_1"), col("t_3"), col("dA0"));
    let sum = |c: usize| rows.iter().map(|q| q[c] * q[da]).sum::<f64>();
    let (f1, f2, f3) = (
        f(r, "contact_force.0"),
        f(r, "contact_force.1"),
        f(r, "contact_force.2"),
    );
    eprintln!(
        "contact.csv: sum t_n dA0 = {:.12e} (summary F2 {f2:.12e}), sum t_1 dA0 = {:.3e}, sum t_3 dA0 = {:.3e}",
        sum(tn),
        sum(t1),
        sum(t3)
    );
    assert!(
        (sum(tn) - f2).abs() <= 1e-9 * f2.abs(),
        "{} vs {f2}",
        sum(tn)
    );
    assert!((sum(t1) - f1).abs() <= 1e-9 * f2.abs());
    assert!((sum(t3) - f3).abs() <= 1e-9 * f2.abs());
    let p_max = rows.iter().map(|q| q[tn]).fold(0.0, f64::max);
    let mut t_max: f64 = 0.0;
    for q in &rows {
        let tt = q[t1].hypot(q[t3]);
        assert!(tt <= mu * q[tn] * (1.0 + 1e-12) + 1e-12 * p_max, "{q:?}");
        t_max = t_max.max(tt);
    }
    // The wheel's tread spreads under the load: friction resists it.
    eprintln!("max |t_T| = {t_max:.4e}, max t_n = {p_max:.4e}");
    assert!(
        t_max > 1e-2 * mu * p_max,
        "no friction traction in contact.csv: {t_max:e}"
    );
}

#[test]
fn friction_indentation_under_displacement_control() {
    let d = TestDir::new("cli3d", "friction");
    // The shipped scene with the load replaced by a penetration and Coulomb friction.
    let text = std::fs::read_to_string(scene("indentation_3d.toml"))
        .expect("scene")
        .replace("load = 50.0", "disp = 0.03")
        .replace(
            "law = \"none\"",
            "law = \"coulomb_tanh\"\nmu = 0.5\neps = 0.001",
        );
    let f_scene = d.join("friction_3d.toml");
    std::fs::write(&f_scene, text).expect("write scene");
    let s = run(
        &f_scene,
        &d.join("out"),
        &[
            "mesh.n_r=2",
            "mesh.n_theta=24",
            "output.sinks=[\"summary\"]",
        ],
    );
    assert_eq!(s["converged"], Value::Bool(true), "{s}");
    let r = &s["results"];
    assert_eq!(s["solver"]["linear"], "lu");
    // The reference: the prescribed penetration.
    assert!((f(r, "penetration") - 0.03).abs() < 1e-14, "{r}");
    assert!(r["load"].is_null());
    let fy = f(r, "contact_force.1");
    eprintln!(
        "friction, DISP = 0.03: contact force ({:.3e}, {fy:.6e}, {:.3e})",
        f(r, "contact_force.0"),
        f(r, "contact_force.2")
    );
    assert!(fy > 0.0);
    // Symmetric about the vertical and about x3 = 0: the friction forces cancel.
    assert!(f(r, "contact_force.0").abs() <= 1e-8 * fy);
    assert!(f(r, "contact_force.2").abs() <= 1e-8 * fy);
    assert!(
        !d.join("out/steps.csv").exists(),
        "csv written without the sink"
    );
    assert!(
        !d.join("out/hex.pvd").exists(),
        "vtu written without the sink"
    );
}

#[test]
fn spinning_slab_matches_the_radial_solution() {
    let d = TestDir::new("cli3d", "spinning");
    let omega = 60.0;
    let omega_set = format!("motion.omega={omega}");
    let s = run(
        &scene("spinning_3d.toml"),
        &d,
        &["mesh.n_r=3", "mesh.n_theta=24", &omega_set],
    );
    assert_eq!(s["converged"], Value::Bool(true), "{s}");
    assert_eq!(s["mode"], "spinning");
    assert_documented(&s, "");
    let r = &s["results"];
    assert_eq!(f(r, "omega"), omega);
    // The independent 1D radial solution of the spinning neo-Hookean annulus (plane strain:
    // the sliding slab), the scene's material.
    let refsol = neo_hookean_radial(1.0, 2.0, 1800.0, 200.0, 0.027, omega).expect("reference");
    let u_ref = refsol.u(2.0);
    let ur = f(r, "u_r_outer_mean");
    let e = (ur - u_ref).abs() / u_ref;
    eprintln!("spinning slab at {omega} rad/s: mean u_r(Ro) {ur:.10e}, radial solution {u_ref:.10e}, relative error {e:.2e}");
    // The discretisation error of Hex27 on 3 × 24 cells (h³ convergence is measured in
    // tests/solid3d.rs): this bound is a measured value with a margin, not a target.
    assert!(e < 1e-4, "relative error {e:.3e}");
    // The sliding faces keep u3 = 0 (the mid-layer of Hex27 nodes up to round-off).
    let (_, rows) = csv(&d.join("nodes.csv"));
    let umax = f(r, "max_displacement");
    assert!(rows.iter().all(|r| r[6].abs() <= 1e-12 * umax));
    assert!(rows
        .iter()
        .filter(|r| r[3].abs() > 0.0)
        .all(|r| r[6] == 0.0));
    assert!(r["road_height"].is_null());
    assert_field_files(
        &d,
        s["solver"]["load_steps"].as_u64().expect("steps") as usize,
    );
}

fn bad(name: &str, set: &[&str], key: &str) {
    let d = TestDir::new("cli3d", name);
    let mut args = vec![
        "run",
        "scenarios/indentation_3d.toml",
        "--out",
        d.to_str().expect("path"),
        "--quiet",
    ];
    for s in set {
        args.push("--set");
        args.push(s);
    }
    let out = Command::new(env!("CARGO_BIN_EXE_tread"))
        .current_dir(root())
        .args(&args)
        .output()
        .expect("run tread");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{name}: panic: {stderr}");
    assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
    assert!(
        stderr.contains(key),
        "{name}: key {key} not named in: {stderr}"
    );
    assert!(!d.join("summary.json").exists(), "{name}: ran anyway");
}

#[test]
fn bad_three_dimensional_inputs_name_the_key() {
    let transient = [
        "analysis.mode=\"transient\"",
        "time.dt=1e-3",
        "time.t_end=0.1",
    ];
    let with = |extra: &'static str| {
        let mut v = transient.to_vec();
        v.push(extra);
        v
    };
    bad(
        "transient_torque",
        &with("motion.control=\"torque\""),
        "motion.control",
    );
    bad(
        "transient_bdf",
        &with("time.integrator=\"bdf\""),
        "time.integrator",
    );
    bad("mode", &["analysis.mode=\"stick_slip\""], "analysis.mode");
    bad("slip_static", &["road.slip_angle=2.0"], "road.slip_angle");
    bad("camber_range", &["road.camber=95.0"], "road.camber");
    bad(
        "steady_creep_range",
        &[
            "analysis.mode=\"steady\"",
            "motion.omega=1.0",
            "road.v0=1.9",
            "motion.control=\"creep\"",
            "motion.creep=-1.0",
        ],
        "motion.creep",
    );
    bad("dimension", &["mesh.dimension=4"], "mesh.dimension");
    bad("width", &["mesh.width=-1.0"], "mesh.width");
    bad("crown", &["mesh.crown_radius=0.1"], "mesh.crown_radius");
    bad(
        "crown_sliding",
        &["mesh.crown_radius=1.0", "mesh.sides=\"sliding\""],
        "mesh.sides",
    );
    bad("sides", &["mesh.sides=\"glued\""], "mesh.sides");
    bad("n_z", &["mesh.n_z=0"], "mesh.n_z");
    bad("theta_ratio", &["mesh.theta_ratio=0.0"], "mesh.theta_ratio");
    bad("grading_z", &["mesh.grading_z=-2.0"], "mesh.grading_z");
    bad(
        "lobatto",
        &["contact.quadrature=\"lobatto\"", "contact.points=6"],
        "contact.points",
    );
    bad(
        "file",
        &["mesh.file=\"missing.msh\"", "mesh.n_r=2"],
        "mesh.n_r",
    );
    // Keys of the three-dimensional wheel in a plane-strain scene.
    let d = TestDir::new("cli3d", "two_d");
    let out = Command::new(env!("CARGO_BIN_EXE_tread"))
        .current_dir(root())
        .args([
            "run",
            "scenarios/indentation_load_control.toml",
            "--out",
            d.to_str().expect("path"),
            "--set",
            "mesh.width=0.5",
        ])
        .output()
        .expect("run tread");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("mesh.width") && stderr.contains("dimension = 3"),
        "{stderr}"
    );
}

#[test]
fn missing_hexahedral_mesh_file_is_named() {
    let d = TestDir::new("cli3d", "mesh_file");
    let text = std::fs::read_to_string(scene("spinning_3d.toml"))
        .expect("scene")
        .lines()
        .filter(|l| {
            ![
                "width",
                "n_z",
                "sides",
                "n_r",
                "n_theta",
                "order",
                "grading_r",
                "grading_theta",
            ]
            .iter()
            .any(|k| l.starts_with(&format!("{k} ")))
        })
        .collect::<Vec<_>>()
        .join("\n")
        .replace("dimension = 3", "dimension = 3\nfile = \"nowhere.msh\"");
    let f_scene = d.join("file_3d.toml");
    std::fs::write(&f_scene, text).expect("write");
    let out = tread(&["check", f_scene.to_str().expect("path")]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("mesh.file") && stderr.contains("nowhere.msh"),
        "{stderr}"
    );
}

#[test]
fn adapt_refuses_and_check_accepts_three_dimensional_scenes() {
    let d = TestDir::new("cli3d", "adapt");
    for name in ["indentation_3d.toml", "spinning_3d.toml"] {
        let sc = scene(name);
        let out = tread(&[
            "adapt",
            sc.to_str().expect("path"),
            "--out",
            d.to_str().expect("path"),
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
        assert!(
            stderr.contains("mesh.dimension = 3") && stderr.contains("tread adapt"),
            "{name}: {stderr}"
        );
        let out = tread(&["check", sc.to_str().expect("path")]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            stdout.contains("valid") && stdout.contains("dimension = 3"),
            "{stdout}"
        );
        // The listing loads back to the same scene.
        let listing: String = stdout
            .lines()
            .filter(|l| !l.starts_with("# "))
            .collect::<Vec<_>>()
            .join("\n");
        let back = tread::io::Scene::from_toml_str(&listing, "listing", &[])
            .unwrap_or_else(|e| panic!("{name}: listing does not load: {e}\n{listing}"));
        let mut orig = tread::io::Scene::from_path(&sc, &[]).expect("scene");
        orig.mesh.file = back.mesh.file.clone();
        assert_eq!(back, orig, "{name}");
    }
}

#[test]
fn spinning_runs_on_a_hexahedral_gmsh_file() {
    use tread::driver::spinning3d::solve_spinning_3d;
    use tread::mesh::gmsh::GmshGroups;
    use tread::model::{Solid3D, Solid3DSystem};
    use tread::solver::observe::NoObserver;
    use tread::solver::stepping::{StepOptions, StepReport};
    use tread::solver::{LinearKind, NewtonOptions};
    let d = TestDir::new("cli3d", "gmsh");
    // The whole annulus 1 ≤ r ≤ 2, width 0.5, of 8-node hexahedra (4 patches of 3 × 4 cells,
    // 2 across the width; tools/gmsh_hex_meshes.py), free flat faces.
    let msh = root().join("tests/gmsh_data/ring_hex8.msh");
    let text = gmsh_spinning_scene(&msh);
    let f_scene = d.join("gmsh_3d.toml");
    std::fs::write(&f_scene, text).expect("write");
    let s = run(&f_scene, &d.join("out"), &[]);
    assert_eq!(s["converged"], Value::Bool(true), "{s}");
    assert_eq!(s["mesh"]["nodes"], 192);
    assert_eq!(s["mesh"]["cells"], 96);
    assert!(s["mesh"]["n_r"].is_null() && s["mesh"]["width"].is_null());
    // The library on the same file: hub fixed in every component, the scene's material,
    // speed and solver settings.
    let groups = GmshGroups {
        hub: "hub".into(),
        contact: "outer".into(),
        regions: Vec::new(),
    };
    let mesh = tread::mesh::gmsh3d::read_msh_hex(&msh, &groups).expect("mesh");
    let mut fixed = vec![false; 3 * mesh.n_nodes()];
    for &n in mesh.node_set("hub") {
        fixed[3 * n as usize..3 * n as usize + 3].fill(true);
    }
    let material = tread::material::MaterialKind::NeoHookean.build(&[200.0, 1800.0]);
    let solid = Solid3D::new(mesh, material, 0.027, tread::physics::PressureMode::None);
    let mut sys = Solid3DSystem::new(solid, &fixed);
    let opts = NewtonOptions {
        tol: 1e-10,
        max_iterations: 25,
        ..Default::default()
    };
    let steps = StepOptions {
        initial_steps: 4,
        max_cutbacks: 10,
        verbose: false,
    };
    let mut rep = StepReport::default();
    solve_spinning_3d(
        &mut sys,
        20.0,
        LinearKind::Cholesky,
        opts,
        &steps,
        &mut rep,
        &mut NoObserver,
    )
    .expect("library solve");
    let (_, rows) = csv(&d.join("out/nodes.csv"));
    assert_eq!(rows.len(), 192);
    let umax = f(&s["results"], "max_displacement");
    let mut worst: f64 = 0.0;
    for r in &rows {
        let u = sys.node_displacement(r[0] as usize);
        for i in 0..3 {
            worst = worst.max((r[4 + i] - u[i]).abs());
        }
    }
    eprintln!(
        "mesh file: max |u_run − u_library| / max |u| = {:.2e}",
        worst / umax
    );
    assert!(worst <= 1e-9 * umax, "{worst:e}");
    // Spun all the way round, the rim moves outwards.
    let mesh = &sys.solid.mesh;
    let rim = mesh.node_set("outer");
    let mean_ur = rim
        .iter()
        .map(|&n| {
            let (x, u) = (mesh.nodes[n as usize], sys.node_displacement(n as usize));
            (x[0] * u[0] + x[1] * u[1]) / x[0].hypot(x[1])
        })
        .sum::<f64>()
        / rim.len() as f64;
    assert!(
        mean_ur > 0.0,
        "mean radial displacement of the rim {mean_ur:e}"
    );
    assert_field_files(
        &d.join("out"),
        s["solver"]["load_steps"].as_u64().expect("steps") as usize,
    );
}

/// The spinning scene on the hexahedral Gmsh file `msh` (groups `hub` and `outer`).
fn gmsh_spinning_scene(msh: &Path) -> String {
    std::fs::read_to_string(scene("spinning_3d.toml"))
        .expect("scene")
        .lines()
        .filter(|l| {
            ![
                "width",
                "n_z",
                "sides",
                "n_r",
                "n_theta",
                "order",
                "grading_r",
                "grading_theta",
            ]
            .iter()
            .any(|k| l.starts_with(&format!("{k} ")))
        })
        .collect::<Vec<_>>()
        .join("\n")
        .replace(
            "dimension = 3",
            &format!(
                "dimension = 3\nfile = \"{}\"\nhub = \"hub\"\ncontact = \"outer\"",
                msh.display()
            ),
        )
}

/// A sector (the quarter annulus of tests/gmsh_data/annular_hex27.msh) is refused by the
/// spinning mode: its θ-referential inertia would miss the terms on the cut faces.
#[test]
fn spinning_refuses_a_mesh_that_does_not_close_around_the_axle() {
    let d = TestDir::new("cli3d", "gmsh_sector");
    let msh = root().join("tests/gmsh_data/annular_hex27.msh");
    let f_scene = d.join("sector.toml");
    std::fs::write(&f_scene, gmsh_spinning_scene(&msh)).expect("write");
    let out = tread(&[
        "run",
        f_scene.to_str().expect("path"),
        "--out",
        d.join("out").to_str().expect("path"),
        "--quiet",
    ]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("mesh.file") && stderr.contains("does not close around the axle"),
        "{stderr}"
    );
}

/// The steady cornering scene on a small mesh: the hub loads in summary.json are the sums of
/// the contact table (the load-control equation holds the wheel load), the lateral force at a
/// positive slip angle is negative (the documented convention), and the `png` sink writes the
/// three footprint maps.
#[test]
fn steady_cornering_writes_hub_loads_and_footprints() {
    let d = TestDir::new("cli3d", "cornering");
    let s = run(
        &scene("cornering_3d.toml"),
        &d.join("out"),
        &[
            "mesh.n_theta=32",
            "mesh.order=1",
            "solver.load_steps=4",
            "output.sinks=[\"summary\", \"csv\", \"png\"]",
        ],
    );
    assert_documented(&s, "");
    let load = 50.0;
    let vertical = f(&s, "results.hub_loads.vertical_force");
    let lateral = f(&s, "results.hub_loads.lateral_force");
    assert!(
        (vertical - load).abs() <= 1e-8 * load,
        "vertical {vertical}"
    );
    assert!(lateral < -1e-3 * load, "lateral force {lateral} at α = +2°");
    assert_eq!(f(&s, "results.slip_angle"), 2.0);
    let (h, rows) = csv(&d.join("out").join("contact.csv"));
    let col = |name: &str| h.iter().position(|c| c == name).expect(name);
    let (tn, t3, da) = (col("t_n"), col("t_3"), col("dA0"));
    let fz: f64 = rows.iter().map(|r| r[tn] * r[da]).sum();
    let fy: f64 = rows.iter().map(|r| r[t3] * r[da]).sum();
    assert!((fz - vertical).abs() <= 1e-9 * load, "Σ t_n dA0 = {fz}");
    assert!((fy - lateral).abs() <= 1e-9 * load, "Σ t_3 dA0 = {fy}");
    for file in [
        "footprint_pressure.png",
        "footprint_traction.png",
        "footprint_stick_slip.png",
    ] {
        let bytes = std::fs::read(d.join("out").join(file)).expect(file);
        assert!(
            bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
            "{file} is not a PNG"
        );
    }
}

/// The Rerun recording of a steady run with contact carries the contact patch at every
/// recorded step: the points coloured by pressure, the traction arrows, the stick points and
/// the legend, on the same frames as the body (builds with the `rerun` feature; without it the
/// sink is skipped).
#[test]
fn steady_rerun_recording_has_the_footprint() {
    let d = TestDir::new("cli3d", "footprint_rrd");
    let out = d.join("out");
    let s = run(
        &scene("cornering_3d.toml"),
        &out,
        &[
            "mesh.n_theta=32",
            "mesh.order=1",
            "solver.load_steps=4",
            "output.sinks=[\"summary\", \"rerun\"]",
        ],
    );
    assert!(f(&s, "results.hub_loads.lateral_force") < 0.0);
    #[cfg(feature = "rerun")]
    {
        let r = logread::read_rrd(&out.join("hex.rrd"));
        let frames = &r["/body/mesh"].times;
        assert!(!frames.is_empty());
        for e in [
            "/footprint/pressure",
            "/footprint/traction",
            "/footprint/stick",
            "/footprint/legend",
        ] {
            assert_eq!(&r[e].times, frames, "{e}");
        }
    }
    #[cfg(not(feature = "rerun"))]
    assert!(!out.join("hex.rrd").exists());
}

/// `tread compare` on a 3D steady scene with a control the 3D transient does not run: exit 2,
/// the key named, nothing compared.
#[test]
fn compare_refuses_what_the_3d_transient_does_not_run() {
    let d = TestDir::new("cli3d", "compare_control");
    let sc = scene("transient_cornering_3d.toml");
    let out_dir = d.join("out");
    let out = tread(&[
        "compare",
        sc.to_str().expect("path"),
        "--set",
        "analysis.mode=\"steady\"",
        "--set",
        "motion.control=\"free_rolling\"",
        "--out",
        out_dir.to_str().expect("path"),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("motion.control") && stderr.contains("free_rolling"),
        "{stderr}"
    );
    assert!(!out_dir.join("compare.csv").exists());
}
