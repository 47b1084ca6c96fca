//! Output files a user of ParaView, Abaqus-style status files and plots expects, read back:
//! binary VTU with the full stress tensor (σ33 of plane strain), the pressure and cell data;
//! the increment status file `run.sta`; plot units, tick labels and panels; `--mode` errors;
//! the replay viewer's bind address and the recording name.
//!
//! `TREAD_BIN` runs the same checks against another build of the program.

mod logread;
#[path = "common/tempdir.rs"]
mod tempdir;

use logread::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use tempdir::TestDir;
use tread::io::record::png::{self, AxisLayout, Scale, Units};
use tread::io::record::vtu::{vtu_bytes, VtuFormat};
use tread::io::record::StepView;
use tread::material::{
    Hyperelastic, Material, MooneyRivlin, MooneyRivlinIncompressible, NeoHookean,
};
use tread::math::Mat2;
use tread::mesh::{annulus, AnnulusSpec};

fn tread() -> Command {
    let bin = std::env::var("TREAD_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_tread").into());
    let mut c = Command::new(bin);
    c.env("RAYON_NUM_THREADS", "1");
    c
}

fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
}

fn run(scene: &Path, out: &Path, set: &[&str]) -> Output {
    let mut c = tread();
    c.args(["-q", "run"]).arg(scene).arg("--out").arg(out);
    for s in set {
        c.args(["--set", s]);
    }
    let o = c.output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "panic: {err}");
    o
}

fn run_ok(scene: &Path, out: &Path, set: &[&str]) -> Output {
    let o = run(scene, out, set);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    o
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().map(|x| x.abs()).fold(0.0, f64::max)
}

// ---------------------------------------------------------------------------------------------
// VTU
// ---------------------------------------------------------------------------------------------

/// Run a spinning scene into `out` with the given VTU encoding; the last listed `.vtu`.
fn spinning_vtu(d: &TestDir, scene_file: &str, tag: &str, format: &str) -> (PathBuf, Vtu) {
    let out = d.join(tag);
    let fmt = format!("output.vtu_format=\"{format}\"");
    run_ok(
        &scene(scene_file),
        &out,
        &[
            "mesh.n_r=2",
            "mesh.n_theta=16",
            r#"output.sinks=["summary","csv","vtu"]"#,
            &fmt,
        ],
    );
    let pvd = parse_pvd(&out.join("fields.pvd"));
    let last = out.join(&pvd.last().expect("a step").1);
    let v = parse_vtu(&last);
    (last, v)
}

#[test]
fn vtu_is_binary_by_default_and_equals_the_ascii_encoding() {
    let d = TestDir::new("outputs_more", "vtu_binary");
    let (bin_path, bin) = spinning_vtu(&d, "spinning_incompressible.toml", "bin", "binary");
    let (asc_path, asc) = spinning_vtu(&d, "spinning_incompressible.toml", "asc", "ascii");
    let raw = std::fs::read(&bin_path).unwrap();
    let head = String::from_utf8_lossy(&raw[..raw.len().min(4000)]).to_string();
    assert!(head.contains("header_type=\"UInt64\""), "{head}");
    assert!(head.contains("<AppendedData encoding=\"raw\">"), "{head}");
    assert!(head.contains("format=\"appended\""));
    let text = std::fs::read_to_string(&asc_path).unwrap();
    assert!(!text.contains("AppendedData") && text.contains("format=\"ascii\""));
    // Smaller, and the same numbers bit for bit (ASCII writes round-trip text).
    assert!(raw.len() < text.len(), "{} vs {}", raw.len(), text.len());
    assert_eq!((bin.n_points, bin.n_cells), (asc.n_points, asc.n_cells));
    assert_eq!(bin.points, asc.points);
    assert_eq!(bin.time, asc.time);
    assert_eq!(
        bin.arrays.keys().collect::<Vec<_>>(),
        asc.arrays.keys().collect::<Vec<_>>()
    );
    for (name, a) in &bin.arrays {
        let b = &asc.arrays[name];
        assert_eq!(a.len(), b.len(), "{name}");
        for (x, y) in a.iter().zip(b) {
            assert!(x == y || (x.is_nan() && y.is_nan()), "{name}: {x} vs {y}");
        }
    }
}

#[test]
fn vtu_holds_the_full_stress_tensor_pressure_and_cell_data() {
    let d = TestDir::new("outputs_more", "vtu_tensor");
    // Incompressible Mooney–Rivlin (exact Q2/P1): a pressure field; at small strain ν = 1/2,
    // so σ33 = (σ11 + σ22)/2 up to O(strain) relative terms.
    let (_, v) = spinning_vtu(&d, "spinning_incompressible.toml", "inc", "binary");
    let n = v.n_points;
    for name in [
        "cauchy_stress",
        "sigma_11",
        "sigma_22",
        "sigma_12",
        "sigma_33",
        "pressure",
        "pressure_field",
        "cell_id",
        "region",
    ] {
        assert!(
            v.arrays.contains_key(name),
            "no {name}: {:?}",
            v.arrays.keys()
        );
    }
    let t = &v.arrays["cauchy_stress"];
    assert_eq!(t.len(), 9 * n);
    let (s11, s22, s12, s33) = (
        &v.arrays["sigma_11"],
        &v.arrays["sigma_22"],
        &v.arrays["sigma_12"],
        &v.arrays["sigma_33"],
    );
    for k in 0..n {
        let row = &t[9 * k..9 * k + 9];
        assert_eq!(
            row,
            [s11[k], s12[k], 0.0, s12[k], s22[k], 0.0, 0.0, 0.0, s33[k]]
        );
    }
    let smax = max_abs(s11).max(max_abs(s22));
    assert!(smax > 0.0);
    assert!(
        max_abs(s33) > 0.05 * smax,
        "σ33 is not zero in plane strain"
    );
    for k in 0..n {
        let mean = 0.5 * (s11[k] + s22[k]);
        assert!(
            (s33[k] - mean).abs() <= 0.05 * smax,
            "node {k}: σ33 = {}, (σ11 + σ22)/2 = {mean}",
            s33[k]
        );
    }
    // The hydrostatic pressure is −tr σ/3; the mixed formulation's unknown is finite too.
    for k in 0..n {
        let p = -(s11[k] + s22[k] + s33[k]) / 3.0;
        assert!((v.arrays["pressure"][k] - p).abs() <= 1e-12 * smax);
    }
    assert!(v.arrays["pressure_field"].iter().all(|p| p.is_finite()));
    let ids = &v.arrays["cell_id"];
    assert_eq!(ids, &(0..v.n_cells).map(|c| c as f64).collect::<Vec<_>>());
    assert!(v.arrays["region"].iter().all(|&r| r == 0.0));

    // Compressible neo-Hookean: no pressure unknown; σ33 = ν (σ11 + σ22) at small strain.
    let (_, v) = spinning_vtu(&d, "spinning_neo_hookean.toml", "nh", "binary");
    assert!(!v.arrays.contains_key("pressure_field"));
    assert!(v.arrays.contains_key("pressure"));
    let text = std::fs::read_to_string(scene("spinning_neo_hookean.toml")).unwrap();
    let get = |k: &str| -> f64 {
        let l = text
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{k} ")))
            .unwrap_or_else(|| panic!("no {k}"));
        l.split('=')
            .nth(1)
            .unwrap()
            .split('#')
            .next()
            .unwrap()
            .trim()
            .parse()
            .unwrap()
    };
    let (mu, lambda) = (get("mu"), get("lambda"));
    let nu = lambda / (2.0 * (lambda + mu));
    let (s11, s22, s33) = (
        &v.arrays["sigma_11"],
        &v.arrays["sigma_22"],
        &v.arrays["sigma_33"],
    );
    let smax = max_abs(s11).max(max_abs(s22));
    assert!(max_abs(s33) > 0.05 * smax);
    for k in 0..v.n_points {
        let lin = nu * (s11[k] + s22[k]);
        assert!(
            (s33[k] - lin).abs() <= 0.05 * smax,
            "node {k}: σ33 = {}, ν(σ11 + σ22) = {lin}",
            s33[k]
        );
    }
}

#[test]
fn vtu_keeps_nan_as_nan() {
    let mesh = annulus(&AnnulusSpec {
        ri: 1.0,
        ro: 2.0,
        n_r: 1,
        n_theta: 8,
        degree: 2,
        grading_r: 1.0,
        grading_theta: 0.0,
    });
    let nn = mesh.n_nodes();
    let x = vec![0.0; 2 * nn];
    let mut stress = vec![[1.0, 2.0, 3.0]; nn];
    stress[3] = [f64::NAN; 3];
    let mut s33 = vec![0.5; nn];
    s33[3] = f64::NAN;
    let view = StepView {
        mesh: Some(&mesh),
        x: &x,
        stress: &stress,
        sigma_33: &s33,
        stress_recovered: &[],
        error_indicator: &[],
        pressure: &[],
        contact: &[],
        hub: None,
        energy: None,
        road_height: None,
        omega: 0.0,
        scalars: &[],
    };
    let d = TestDir::new("outputs_more", "vtu_nan");
    for (f, name) in [(VtuFormat::Binary, "b.vtu"), (VtuFormat::Ascii, "a.vtu")] {
        let p = d.join(name);
        std::fs::write(&p, vtu_bytes(&mesh, &view, 0.5, f)).unwrap();
        let v = parse_vtu(&p);
        assert_eq!(v.time, 0.5);
        for a in ["sigma_11", "sigma_33"] {
            assert!(v.arrays[a][3].is_nan(), "{name} {a}: {}", v.arrays[a][3]);
            assert!(v.arrays[a][2].is_finite());
        }
        assert!(v.arrays["cauchy_stress"][9 * 3 + 8].is_nan());
    }
}

/// σ33 of each law against a finite difference of its energy written in 3D (F33 = s):
/// I1 = F:F + s², I2 = J2² + (F:F) s², J = J2 s; σ33 = ∂W/∂s / J at s = 1.
#[test]
fn sigma_33_matches_the_three_dimensional_energy() {
    fn inv(h: &Mat2, s: f64) -> (f64, f64, f64) {
        let f = Mat2::identity() + h;
        let ff = f.norm_squared();
        let j2 = f.determinant();
        (ff + s * s, j2 * j2 + ff * s * s, j2 * s)
    }
    let (c1, c2, kappa, mu, lambda) = (80.0, 20.0, 5000.0, 150.0, 900.0);
    let nh = |h: &Mat2, s: f64| {
        let (i1, _, j) = inv(h, s);
        0.5 * mu * (i1 - 3.0) - mu * j.ln() + 0.5 * lambda * j.ln().powi(2)
    };
    let mr = |h: &Mat2, s: f64| {
        let (i1, i2, j) = inv(h, s);
        c1 * (j.powf(-2.0 / 3.0) * i1 - 3.0)
            + c2 * (j.powf(-4.0 / 3.0) * i2 - 3.0)
            + 0.5 * kappa * (j - 1.0).powi(2)
    };
    let inc = |h: &Mat2, s: f64| {
        let (i1, i2, _) = inv(h, s);
        c1 * (i1 - 3.0) + c2 * (i2 - 3.0)
    };
    type Energy<'a> = &'a dyn Fn(&Mat2, f64) -> f64;
    let laws: [(Material, Energy); 3] = [
        (NeoHookean::new(mu, lambda).into(), &nh),
        (MooneyRivlin::new(c1, c2, kappa).into(), &mr),
        (MooneyRivlinIncompressible::new(c1, c2).into(), &inc),
    ];
    let grads = [
        Mat2::new(0.1, 0.05, -0.03, -0.08),
        Mat2::new(-0.2, 0.3, 0.1, 0.25),
        Mat2::new(0.01, 0.0, 0.0, 0.01),
    ];
    for (law, w) in &laws {
        for h in &grads {
            let e = 1e-6;
            let j = (Mat2::identity() + h).determinant();
            let fd = (w(h, 1.0 + e) - w(h, 1.0 - e)) / (2.0 * e) / j;
            let got = law.cauchy_33(h);
            assert!(
                (got - fd).abs() <= 1e-6 * fd.abs().max(c1),
                "{law:?} at {h}: σ33 = {got}, FD = {fd}"
            );
            // The in-plane stress of the same 3D energy matches the law's (same energy).
            let p = law.stress(h);
            assert!(p.iter().all(|v| v.is_finite()));
        }
    }
    // Neo-Hookean closed form: σ33 = λ ln J / J.
    let h = Mat2::new(0.1, 0.05, -0.03, -0.08);
    let j: f64 = (Mat2::identity() + h).determinant();
    let got = NeoHookean::new(mu, lambda).cauchy_33(&h);
    assert!((got - lambda * j.ln() / j).abs() < 1e-12 * lambda);
}

// ---------------------------------------------------------------------------------------------
// run.sta
// ---------------------------------------------------------------------------------------------

/// One data line of a `run.sta`: (step, status, time, dt, newton, residual; 0 and NaN for
/// `-`, unknown figures).
type StaRow = (u64, String, f64, f64, usize, f64);

/// Comment lines and data lines of a `run.sta`.
fn read_sta(path: &Path) -> (Vec<String>, Vec<StaRow>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut comments = Vec::new();
    let mut rows = Vec::new();
    for l in text.lines() {
        if l.starts_with('#') {
            comments.push(l.to_string());
            continue;
        }
        let data = l.split('#').next().unwrap();
        let w: Vec<&str> = data.split_whitespace().collect();
        assert_eq!(w.len(), 10, "line {l:?}");
        rows.push((
            w[0].parse().unwrap(),
            w[2].to_string(),
            w[3].parse().unwrap(),
            w[4].parse().unwrap(),
            match w[5] {
                "-" => 0,
                n => n
                    .parse()
                    .unwrap_or_else(|e| panic!("newton {n:?} ({e}) in {l:?}")),
            },
            match w[6] {
                "-" => f64::NAN,
                r => r
                    .parse()
                    .unwrap_or_else(|e| panic!("residual {r:?} ({e}) in {l:?}")),
            },
        ));
        assert!(
            !data.contains("NaN") && !data.contains("inf"),
            "no non-finite number in {l:?}"
        );
    }
    (comments, rows)
}

fn accepted_match_history(out: &Path) -> Vec<(u64, String, f64, f64, usize, f64)> {
    let (comments, rows) = read_sta(&out.join("run.sta"));
    assert!(comments[0].contains("increment status"), "{comments:?}");
    assert!(
        comments
            .iter()
            .any(|c| c.contains("step") && c.contains("newton_total")),
        "{comments:?}"
    );
    assert!(
        comments.last().unwrap().contains("completed"),
        "{comments:?}"
    );
    let (h, hist) = read_csv(&out.join("history.csv"));
    let times = column(&h, &hist, "time");
    let acc: Vec<_> = rows.iter().filter(|r| r.1 == "accepted").collect();
    assert_eq!(acc.len(), times.len(), "one accepted line per history row");
    for (k, (r, t)) in acc.iter().zip(&times).enumerate() {
        assert_eq!(r.0, k as u64);
        assert_eq!(r.2, *t, "step {k}");
    }
    rows
}

#[test]
fn run_sta_lists_load_steps_with_newton_counts() {
    let d = TestDir::new("outputs_more", "sta_static");
    let out = d.join("out");
    run_ok(
        &scene("indentation_friction.toml"),
        &out,
        &[
            "mesh.n_r=2",
            "mesh.n_theta=32",
            r#"output.sinks=["summary","csv"]"#,
        ],
    );
    let rows = accepted_match_history(&out);
    for r in rows.iter().filter(|r| r.1 == "accepted") {
        assert!(r.4 >= 1, "Newton iterations {r:?}");
        assert!(r.5.is_finite() && r.5 < 1e-6, "residual {r:?}");
        assert!(r.3 > 0.0, "dt {r:?}");
    }
    let last = rows.last().unwrap();
    assert_eq!(last.2, 1.0, "the load factor ends at 1");
}

#[test]
fn run_sta_lists_continuation_points() {
    let d = TestDir::new("outputs_more", "sta_cont");
    let out = d.join("out");
    run_ok(
        &scene("oden_steady_sweep.toml"),
        &out,
        &[
            "mesh.n_r=2",
            "mesh.n_theta=32",
            "continuation.max_steps=4",
            r#"output.sinks=["summary","csv"]"#,
        ],
    );
    accepted_match_history(&out);
}

#[test]
fn run_sta_lists_time_steps_and_rejections_and_verbose_shows_step_headers() {
    let d = TestDir::new("outputs_more", "sta_transient");
    let out = d.join("out");
    let o = tread()
        .args(["run", "-v"])
        .arg(scene("free_rolling.toml"))
        .arg("--out")
        .arg(&out)
        .args([
            "--set",
            r#"output.sinks=["summary","csv"]"#,
            "--set",
            "time.t_end=0.002",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let rows = accepted_match_history(&out);
    let s = summary(&out);
    let rejected = rows.iter().filter(|r| r.1 == "cutback").count() as u64;
    assert_eq!(
        Some(rejected),
        s["results"]["rejected_steps"].as_u64(),
        "{s}"
    );
    // -v: a step header above each Newton table.
    let first_header = err.find("step 0: t = ").unwrap_or_else(|| panic!("{err}"));
    let first_table = err.find("iter").unwrap_or_else(|| panic!("{err}"));
    assert!(first_header < first_table, "{err}");
    let headers = err.matches("  step ").count();
    assert!(
        headers >= rows.len(),
        "{headers} headers for {} lines",
        rows.len()
    );
}

#[test]
fn run_sta_cutback_lines_carry_the_attempts_newton_figures() {
    // The free-rolling scene's time-step controller rejects its fifth step (local error above
    // 4 × error_tol): the rejected attempt converged, so its line carries its Newton
    // iterations and final residual, and the run total counts them.
    let d = TestDir::new("outputs_more", "sta_cutback");
    let out = d.join("out");
    run_ok(
        &scene("free_rolling.toml"),
        &out,
        &[r#"output.sinks=["summary","csv"]"#, "time.t_end=0.03"],
    );
    let (_, rows) = read_sta(&out.join("run.sta"));
    let text = std::fs::read_to_string(out.join("run.sta")).unwrap();
    let cut: Vec<_> = rows.iter().filter(|r| r.1 == "cutback").collect();
    assert!(!cut.is_empty(), "a rejected step expected:\n{text}");
    for r in &cut {
        assert!(r.4 >= 1, "Newton iterations of the attempt: {r:?}\n{text}");
        assert!(
            r.5.is_finite() && r.5 < 1e-6,
            "converged residual: {r:?}\n{text}"
        );
    }
    let newton_sum: usize = rows.iter().map(|r| r.4).sum();
    let total: usize = text
        .lines()
        .rfind(|l| !l.starts_with('#'))
        .and_then(|l| l.split_whitespace().nth(9))
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("newton_total of the last line:\n{text}"));
    assert_eq!(
        total, newton_sum,
        "newton_total counts every attempt:\n{text}"
    );
}

// ---------------------------------------------------------------------------------------------
// Plots
// ---------------------------------------------------------------------------------------------

#[test]
fn plot_ticks_are_plain_numbers() {
    let a = AxisLayout::new(Scale::Linear, [0.0, 100.0].into_iter());
    let labels: Vec<String> = a.major.iter().map(|v| a.plain_label(*v)).collect();
    assert!(labels.contains(&"60".to_string()), "{labels:?}");
    assert!(labels.iter().all(|l| !l.contains('e')), "{labels:?}");
    let a = AxisLayout::new(Scale::Linear, [-98.5, -98.3].into_iter());
    let labels: Vec<String> = a.major.iter().map(|v| a.plain_label(*v)).collect();
    assert!(
        labels
            .iter()
            .all(|l| !l.contains('e') && l.starts_with("-98.")),
        "{labels:?}"
    );
    // Distinct ticks keep distinct labels.
    let mut u = labels.clone();
    u.dedup();
    assert_eq!(u.len(), labels.len(), "{labels:?}");
    let a = AxisLayout::new(Scale::Linear, [0.0, 2.5e-7].into_iter());
    let labels: Vec<String> = a.major.iter().map(|v| a.plain_label(*v)).collect();
    assert!(labels.iter().any(|l| l.contains("e-7")), "{labels:?}");
}

#[test]
fn plot_units_come_from_the_scene() {
    let u = Units::parse("in-lbf-s");
    assert_eq!(u.stress(), "lbf/in²");
    assert_eq!(u.force_per_thickness(), "lbf/in");
    assert_eq!(u.of_scalar("v"), "in/s");
    assert_eq!(u.of_scalar("friction_force"), "lbf");
    let u = Units::parse("m-N-s");
    assert_eq!(u.of_scalar("x"), "m");
    assert_eq!(png::with_unit("time", &u.time), "time [s]");
}

/// (width, height) from a PNG header.
fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[1..4], b"PNG");
    let w = u32::from_be_bytes(b[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(b[20..24].try_into().unwrap());
    (w, h)
}

#[test]
fn stick_slip_series_are_drawn_in_one_panel_per_quantity() {
    let d = TestDir::new("outputs_more", "stick_slip_png");
    let out = d.join("out");
    run_ok(
        &scene("stick_slip.toml"),
        &out,
        &[
            "stick_slip.t_end=2.0",
            r#"output.sinks=["summary","csv","png"]"#,
        ],
    );
    // Four quantities (x, v, friction force, slip flag), four panels: taller than one chart.
    let (w, h) = png_size(&out.join("series.png"));
    assert_eq!(w, 900);
    assert!(h >= 4 * 200, "series.png is {w}×{h}");
}

#[test]
fn round_off_resultants_are_drawn_as_zero() {
    let s = [(0.0, 1e-14), (1.0, -3e-14)];
    let (name, v) = png::clamp_round_off("F_x", &s, 1e3);
    assert!(name.contains("round-off"), "{name}");
    assert!(v.iter().all(|p| p.1 == 0.0));
    let (name, v) = png::clamp_round_off("F_x", &s, 1e-6);
    assert_eq!(name, "F_x");
    assert_eq!(v, s);
}

// ---------------------------------------------------------------------------------------------
// --mode
// ---------------------------------------------------------------------------------------------

#[test]
fn mode_switch_errors_name_the_mode_flag() {
    let d = TestDir::new("outputs_more", "mode");
    let out = d.join("out");
    let o = tread()
        .args(["-q", "run"])
        .arg(scene("free_rolling.toml"))
        .args(["--mode", "spinning", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    if !o.status.success() {
        assert!(!err.contains("(--set)"), "{err}");
        assert!(err.contains("--mode"), "{err}");
    }
    // A rolling scene run as spinning: the road, contact, friction, time and the spin-up ramp
    // are left out (and said so), and it runs.
    let o = tread()
        .args(["-q", "run"])
        .arg(scene("oden_hollow_cylinder.toml"))
        .args([
            "--mode",
            "spinning",
            "--set",
            "mesh.n_theta=16",
            "--set",
            "mesh.n_r=1",
            "--set",
            "output.sinks=summary",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    for s in [
        "left out",
        "[road]",
        "[contact]",
        "[friction]",
        "[time]",
        "motion.ramp",
    ] {
        assert!(err.contains(s), "{s}: {err}");
    }
    let sum: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(sum["mode"], "spinning", "{sum}");
    assert_eq!(sum["converged"], true, "{sum}");
    // A real --set error is still labelled (--set).
    let o = tread()
        .args(["-q", "run"])
        .arg(scene("free_rolling.toml"))
        .args(["--mode", "transient", "--set", "mesh.n_r=-1", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("(--set)"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// replay
// ---------------------------------------------------------------------------------------------

/// A stand-in viewer that writes its arguments to `$ARGS_FILE`.
fn fake_viewer(d: &TestDir) -> (PathBuf, PathBuf) {
    let bin = d.join("fake-rerun");
    let args = d.join("args.txt");
    std::fs::write(&bin, "#!/bin/sh\nprintf '%s\\n' \"$@\" > \"$ARGS_FILE\"\n").unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&bin, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    (bin, args)
}

#[cfg(unix)]
#[test]
fn replay_viewer_listens_on_loopback_unless_asked() {
    let d = TestDir::new("outputs_more", "replay_bind");
    let (bin, args) = fake_viewer(&d);
    let rrd = d.join("run.rrd");
    std::fs::write(&rrd, b"not read by the fake viewer").unwrap();
    for (extra, want) in [(None, "127.0.0.1"), (Some("0.0.0.0"), "0.0.0.0")] {
        let mut c = tread();
        c.env("TREAD_RERUN_BIN", &bin).env("ARGS_FILE", &args);
        c.arg("replay").arg(&rrd);
        if let Some(b) = extra {
            c.args(["--bind", b]);
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let a = std::fs::read_to_string(&args).unwrap();
        let a: Vec<&str> = a.lines().collect();
        let k = a
            .iter()
            .position(|x| *x == "--bind")
            .expect("--bind passed");
        assert_eq!(a[k + 1], want, "{a:?}");
    }
}

#[test]
fn mcap_log_names_the_scene_for_the_recording() {
    let d = TestDir::new("outputs_more", "replay_name");
    let out = d.join("out");
    run_ok(
        &scene("spinning_neo_hookean.toml"),
        &out,
        &[
            "mesh.n_r=2",
            "mesh.n_theta=16",
            r#"output.sinks=["summary","mcap"]"#,
        ],
    );
    let bytes = std::fs::read(out.join("run.mcap")).unwrap();
    assert_eq!(
        tread::io::replay::mcap_scene_name(&bytes).as_deref(),
        Some("spinning_neo_hookean")
    );
}

#[test]
fn contact_surface_series_carries_pressure_shear_and_slip() {
    let d = TestDir::new("outputs_more", "contact_series");
    let out = d.join("out");
    run_ok(
        &scene("indentation_friction.toml"),
        &out,
        &[
            "mesh.n_r=2",
            "mesh.n_theta=32",
            r#"output.sinks=["summary","csv","vtu"]"#,
        ],
    );
    let fields = parse_pvd(&out.join("fields.pvd"));
    let contact = parse_pvd(&out.join("contact.pvd"));
    assert_eq!(
        fields.iter().map(|f| f.0).collect::<Vec<_>>(),
        contact.iter().map(|f| f.0).collect::<Vec<_>>(),
        "one contact surface per recorded step, same times"
    );
    let v = parse_vtu(&out.join(&contact.last().unwrap().1));
    assert_eq!(v.n_cells, v.n_points, "one segment per point (closed)");
    for a in ["theta", "penetration", "t_n", "t_t", "slip_velocity", "ds0"] {
        assert_eq!(v.arrays[a].len(), v.n_points, "{a}");
    }
    // Segments k → k + 1, the last back to the first point.
    let conn = &v.arrays["connectivity"];
    assert_eq!(conn.len(), 2 * v.n_points);
    for (k, seg) in conn.chunks(2).enumerate() {
        assert_eq!(seg, [k as f64, ((k + 1) % v.n_points) as f64]);
    }
    assert!(v.arrays["types"].iter().all(|&t| t == 3.0));
    // The same tractions as contact.csv (end of the run).
    let (h, rows) = read_csv(&out.join("contact.csv"));
    let max = |x: &[f64]| x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let tn_csv = column(&h, &rows, "t_n");
    assert_eq!(rows.len(), v.n_points);
    assert_eq!(max(&v.arrays["t_n"]), max(&tn_csv));
    assert!(max(&v.arrays["t_n"]) > 0.0);
    assert!(max_abs(&v.arrays["t_t"]) > 0.0, "friction acts");
    let theta = &v.arrays["theta"];
    assert!(theta.windows(2).all(|w| w[1] >= w[0]), "ordered by θ");
}
