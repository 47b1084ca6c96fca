//! The verdict of `tread compare`: every quantity with its unit, relative difference and
//! tolerance, one line saying whether the steady solution is validated against the transient,
//! and exit status 4 when it is not.

#[path = "common/tempdir.rs"]
mod tempdir;

use tempdir::TestDir;
use tread::driver::compare::{
    comparison_table, judge, CompareInputs, CompareTolerances, NOT_VALIDATED_EXIT,
};
use tread::io::record::png::Units;

fn inputs() -> CompareInputs {
    CompareInputs {
        hub_force_x: (22.1079, 22.0986),
        hub_force_y: (-95.8105, -95.8242),
        hub_torque: (50.8334, 50.7481),
        contact_x_min: (-0.583527, -0.583382),
        contact_x_max: (0.460739, 0.460812),
        max_pressure: (122.176, 122.306),
        field_rel_l2: 9.46e-4,
        ro: 2.0,
        surface_spacing: 2.0 * std::f64::consts::PI * 2.0 / 256.0,
        transient_steady: true,
        steady_tol: Some(1e-4),
    }
}

#[test]
fn close_modes_are_validated_with_units_and_plain_numbers() {
    let units = Units::parse("in-lbf-s");
    let (qs, ok, verdict) = judge(&inputs(), &CompareTolerances::default(), &units);
    assert!(ok, "{verdict}");
    assert!(
        verdict.starts_with("steady solution validated against the transient"),
        "{verdict}"
    );
    assert_eq!(qs.len(), 7);
    let table = comparison_table(&qs).join("\n");
    for want in [
        "hub_force_x [lbf/in]",
        "22.1079",
        "hub_torque [lbf·in/in]",
        "max_pressure [lbf/in²]",
        "|F_steady|",
        "|hub_torque_steady|",
        "1 %",
    ] {
        assert!(table.contains(want), "missing {want}:\n{table}");
    }
    // Plain numbers, no exponents such as 2.210795e1.
    assert!(!table.contains("e1 ") && !table.contains("e0"), "{table}");
    assert!(!table.contains("wall"), "{table}");
    // The relative torque difference is relative to the torque itself.
    let t = qs.iter().find(|q| q.name == "hub_torque").unwrap();
    assert!((t.rel_diff - 0.0853 / 50.7481).abs() < 1e-6, "{t:?}");
}

#[test]
fn a_torque_five_percent_off_is_not_validated() {
    let units = Units::parse("in-lbf-s");
    let mut inp = inputs();
    inp.hub_torque = (4.536, 4.31626);
    inp.steady_tol = Some(1e-3);
    let (qs, ok, verdict) = judge(&inp, &CompareTolerances::default(), &units);
    assert!(!ok);
    assert!(
        verdict.starts_with("not validated: hub_torque differs by 5.09 %"),
        "{verdict}"
    );
    assert!(verdict.contains("tolerance 2 %"), "{verdict}");
    assert!(verdict.contains("time.steady_tol"), "{verdict}");
    assert_eq!(qs.iter().filter(|q| !q.within).count(), 1);
}

#[test]
fn a_torque_near_zero_is_relative_to_the_load_moment() {
    let units = Units::parse("in-lbf-s");
    let mut inp = inputs();
    inp.hub_torque = (2e-3, 1e-3);
    let (qs, ok, verdict) = judge(&inp, &CompareTolerances::default(), &units);
    let t = qs.iter().find(|q| q.name == "hub_torque").unwrap();
    assert_eq!(t.relative_to, "|F_steady| Ro");
    let fmag = 22.0986f64.hypot(95.8242);
    assert!((t.scale - 2.0 * fmag).abs() < 1e-9, "{t:?}");
    assert!(ok, "{verdict}");
}

#[test]
fn a_transient_run_not_steady_is_not_validated() {
    let mut inp = inputs();
    inp.transient_steady = false;
    let (_, ok, verdict) = judge(&inp, &CompareTolerances::default(), &Units::default());
    assert!(!ok);
    assert!(
        verdict.contains("did not reach its steady state"),
        "{verdict}"
    );
}

/// The command: a tolerance no run meets gives the verdict line, exit status 4, and the same
/// verdict in summary.json and compare.csv (read with a CSV reader).
#[test]
fn compare_exits_with_status_4_when_not_validated() {
    let dir = TestDir::new("compare-verdict", "strict");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_tread"))
        .args(["--threads", "1", "compare"])
        .arg(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scenarios/rolling_frictionless.toml"
        ))
        .args([
            "--set",
            "mesh.n_theta=32",
            "--set",
            "output.sinks=[\"summary\",\"csv\"]",
            "--force-tol",
            "1e-12",
            "--out",
        ])
        .arg(&*dir)
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(NOT_VALIDATED_EXIT as i32),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("not validated: hub_force_x differs by"),
        "{stdout}"
    );
    assert!(stdout.contains("hub_force_y [lbf/in]"), "{stdout}");
    assert!(stdout.contains("wall time: transient"), "{stdout}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let c = &s["results"]["compare"];
    assert_eq!(c["validated"].as_bool(), Some(false), "{c}");
    assert!(c["verdict"].as_str().unwrap().starts_with("not validated"));
    let qs = c["quantities"].as_array().unwrap();
    assert_eq!(qs.len(), 7);
    assert_eq!(qs[0]["tolerance"].as_f64(), Some(1e-12));
    assert_eq!(qs[1]["unit"].as_str(), Some("lbf/in"));
    let mut r = csv::Reader::from_path(dir.join("compare.csv")).unwrap();
    let h: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(
        h,
        tread::driver::compare::COMPARE_CSV_COLUMNS.map(String::from)
    );
    let rows: Vec<csv::StringRecord> = r.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 7);
    assert_eq!(&rows[0][8], "false");
    assert!(rows.iter().all(|r| &r[0] != "wall_time_s"));
}
