//! Unit tests of scene loading: parsing, defaults, overrides, every error with its key and line.

use super::*;

const INCOMPRESSIBLE: &str = include_str!("../../../scenarios/spinning_incompressible.toml");
const NEO_HOOKEAN: &str = include_str!("../../../scenarios/spinning_neo_hookean.toml");
const MOONEY_RIVLIN: &str = include_str!("../../../scenarios/spinning_mooney_rivlin.toml");
const FRICTIONLESS: &str = include_str!("../../../scenarios/indentation_frictionless.toml");
const FRICTION: &str = include_str!("../../../scenarios/indentation_friction.toml");
const LOAD_CONTROL: &str = include_str!("../../../scenarios/indentation_load_control.toml");
const STICK_SLIP: &str = include_str!("../../../scenarios/stick_slip.toml");
const ODEN: &str = include_str!("../../../scenarios/oden_hollow_cylinder.toml");
const ROLLING_FRICTIONLESS: &str = include_str!("../../../scenarios/rolling_frictionless.toml");
const FREE_ROLLING: &str = include_str!("../../../scenarios/free_rolling.toml");
const STEADY_SWEEP: &str = include_str!("../../../scenarios/oden_steady_sweep.toml");
const BRAKING: &str = include_str!("../../../scenarios/braking.toml");

const MINIMAL: &str = r#"
[scene]
name = "minimal"

[geometry]
ri = 1.0
ro = 2.0

[material]
model = "neo_hookean"
rho = 0.027
mu = 200.0
lambda = 1800.0

[analysis]
mode = "spinning"

[motion]
omega = 20.0
"#;

fn load(text: &str) -> Result<Scene, SceneErrors> {
    Scene::from_toml_str(text, "test.toml", &[])
}

fn load_with(text: &str, overrides: &[&str]) -> Result<Scene, SceneErrors> {
    let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(text, "test.toml", &ov)
}

fn errors(text: &str) -> SceneErrors {
    match load(text) {
        Ok(s) => panic!("expected errors, got {s:?}"),
        Err(e) => e,
    }
}

fn errors_with(text: &str, overrides: &[&str]) -> SceneErrors {
    match load_with(text, overrides) {
        Ok(s) => panic!("expected errors, got {s:?}"),
        Err(e) => e,
    }
}

/// 1-based line of the first line of `text` that starts with `prefix` (after whitespace).
fn line_of(text: &str, prefix: &str) -> usize {
    text.lines()
        .position(|l| l.trim_start().starts_with(prefix))
        .map(|i| i + 1)
        .unwrap_or_else(|| panic!("no line starts with {prefix:?}"))
}

fn replace_line(text: &str, prefix: &str, new: &str) -> String {
    let mut found = false;
    let out: Vec<String> = text
        .lines()
        .map(|l| {
            if !found && l.trim_start().starts_with(prefix) {
                found = true;
                new.to_string()
            } else {
                l.to_string()
            }
        })
        .collect();
    assert!(found, "no line starts with {prefix:?}");
    out.join("\n") + "\n"
}

#[test]
fn incompressible_scene_parses() {
    let s = load(INCOMPRESSIBLE).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.scene.name, "spinning_incompressible");
    assert_eq!(s.scene.units, "in-lbf-s");
    assert_eq!(s.geometry.ri, 1.0);
    assert_eq!(s.geometry.ro, 2.0);
    assert_eq!(s.mesh.n_r, 4);
    assert_eq!(s.mesh.n_theta, 48);
    assert_eq!(s.mesh.order, 2);
    assert_eq!(s.material.model, MaterialModel::MooneyRivlinIncompressible);
    assert_eq!(s.material.rho, 0.027);
    assert_eq!(
        s.material.params(),
        Some(MaterialParams::MooneyRivlinIncompressible {
            c1: 80.0,
            c2: 20.0,
            formulation: Formulation::Exact,
            kappa: None
        })
    );
    assert_eq!(s.material.formulation, Some(Formulation::Exact));
    assert_eq!(s.material.shear_modulus(), Some(200.0));
    assert_eq!(s.material.bulk_modulus(), None);
    assert!(s.material.is_incompressible());
    assert_eq!(s.analysis.mode, Mode::Spinning);
    assert_eq!(s.motion.omega, 20.0);
    // The density is chosen so that c_R / Ro is about the paper's top speed, 395 rpm.
    let c_r = 0.955 * s.shear_wave_speed().unwrap_or(0.0);
    let rpm = c_r / s.geometry.ro * 60.0 / (2.0 * std::f64::consts::PI);
    assert!((rpm - 395.0).abs() < 10.0, "critical spin {rpm} rpm");
}

#[test]
fn neo_hookean_scene_parses() {
    let s = load(NEO_HOOKEAN).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.scene.name, "spinning_neo_hookean");
    assert_eq!(
        s.material.params(),
        Some(MaterialParams::NeoHookean {
            mu: 200.0,
            lambda: 1800.0
        })
    );
    assert_eq!(s.material.rho, 0.027);
    assert_eq!(s.motion.omega, 20.0);
    assert_eq!((s.geometry.ri, s.geometry.ro), (1.0, 2.0));
    assert!(!s.material.is_incompressible());
    let k = s.material.bulk_modulus().unwrap_or(0.0);
    assert!((k - (1800.0 + 400.0 / 3.0)).abs() < 1e-9);
}

#[test]
fn mooney_rivlin_scene_parses() {
    let s = load(MOONEY_RIVLIN).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.scene.name, "spinning_mooney_rivlin");
    assert_eq!(
        s.material.params(),
        Some(MaterialParams::MooneyRivlin {
            c1: 80.0,
            c2: 20.0,
            kappa: 2000.0
        })
    );
    assert_eq!(s.material.resolved_kappa(), Some(2000.0));
    assert_eq!(s.material.resolved_formulation(), None);
    assert_eq!(s.material.shear_modulus(), Some(200.0));
}

#[test]
fn defaults_are_filled() {
    let s = load(MINIMAL).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.scene.description, "");
    assert_eq!(s.scene.units, DEFAULT_UNITS);
    assert_eq!(s.mesh, MeshSpec::default());
    assert_eq!(s.mesh.n_r, 4);
    assert_eq!(s.mesh.n_theta, 32);
    assert_eq!(s.mesh.order, 2);
    assert_eq!(s.mesh.grading_r, 1.0);
    assert_eq!(s.mesh.grading_theta, 0.0);
    assert_eq!(s.solver.tolerance, 1e-10);
    assert_eq!(s.solver.max_iterations, 25);
    assert_eq!(s.solver.load_steps, 4);
    assert_eq!(s.solver.max_cutbacks, 10);
    assert_eq!(s.solver.linear, LinearChoice::Auto);
    assert_eq!(s.solver.threads, 0);
    assert!(s.solver.line_search);
    assert_eq!(s.output.sinks, DEFAULT_SINKS);
    assert_eq!(s.output.every, 1);
    assert_eq!(s.material.formulation, None);
    assert_eq!(s.material.kappa, None);
    assert!(s.validate().is_ok());
}

#[test]
fn partial_sections_fill_remaining_defaults() {
    let text = format!("{MINIMAL}\n[mesh]\nn_r = 6\n\n[solver]\nlinear = \"lu\"\n");
    let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.mesh.n_r, 6);
    assert_eq!(s.mesh.n_theta, 32);
    assert_eq!(s.solver.linear, LinearChoice::Lu);
    assert_eq!(s.solver.max_iterations, 25);
}

#[test]
fn perturbed_kappa_default_is_resolved() {
    let text = r#"
[scene]
name = "p"
[geometry]
ri = 1
ro = 2
[material]
model = "mooney_rivlin_incompressible"
rho = 0.027
c1 = 80
c2 = 20
formulation = "perturbed"
[analysis]
mode = "spinning"
[motion]
omega = 0
"#;
    let s = load(text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.material.formulation, Some(Formulation::Perturbed));
    assert_eq!(s.material.kappa, Some(1e4 * 100.0));
    assert_eq!(s.material.resolved_kappa(), Some(1e6));
    // Integers are accepted for floats.
    assert_eq!(s.geometry.ri, 1.0);
    assert_eq!(s.motion.omega, 0.0);
    // Explicit kappa wins.
    let s2 = load_with(text, &["material.kappa=5000"]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s2.material.kappa, Some(5000.0));
}

#[test]
fn unknown_key_rejected_with_name_and_line() {
    let text = replace_line(MINIMAL, "lambda", "lambda = 1800.0\nlamda = 3.0  # typo");
    let e = errors(&text);
    let err = e.find("material.lamda").unwrap_or_else(|| panic!("{e}"));
    assert_eq!(err.line, Some(line_of(&text, "lamda")));
    assert!(err.message.contains("unknown key"), "{}", err.message);
    let shown = err.to_string();
    assert!(
        shown.starts_with(&format!(
            "test.toml:{}: key `material.lamda`",
            err.line.unwrap_or(0)
        )),
        "{shown}"
    );
    assert_eq!(e.0.len(), 1, "{e}");
}

#[test]
fn steady_sweep_scene_and_continuation_rules() {
    let s = load(STEADY_SWEEP).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.analysis.mode, Mode::Steady);
    let c = s.continuation.clone().unwrap_or_default();
    assert_eq!(c.parameter, ContinuationParameter::Omega);
    assert_eq!(c.target, 60.0);
    // [continuation] only in steady mode, with the line of its header.
    let e = errors_with(STEADY_SWEEP, &["analysis.mode=\"transient\""]);
    let err = e.find("continuation").unwrap_or_else(|| panic!("{e}"));
    assert!(err.message.contains("not used"), "{e}");
    // load continuation needs load control.
    let e = errors_with(STEADY_SWEEP, &["continuation.parameter=\"load\""]);
    assert_only(&e, "continuation.parameter", None);
    // ds_max < ds.
    let e = errors_with(STEADY_SWEEP, &["continuation.ds_max=0.001"]);
    assert_only(&e, "continuation.ds_max", None);
    // A transient scene runs in steady mode with --mode steady ([time] allowed).
    let t = load_with(ODEN, &["analysis.mode=\"steady\""]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(t.analysis.mode, Mode::Steady);
}

#[test]
fn unknown_section_rejected() {
    let text = format!("{MINIMAL}\n[adaptivity]\ntarget = 0.1\n");
    let e = errors(&text);
    let err = e.find("adaptivity").unwrap_or_else(|| panic!("{e}"));
    assert_eq!(err.line, Some(line_of(&text, "[adaptivity]")));
    assert!(err.message.contains("unknown section"));
}

#[test]
fn wrong_type_rejected_naming_key() {
    let text = replace_line(MINIMAL, "ro =", "ro = \"two\"  # oops");
    let e = errors(&text);
    let err = e.find("geometry.ro").unwrap_or_else(|| panic!("{e}"));
    assert_eq!(err.line, Some(line_of(&text, "ro =")));
    assert!(err.message.contains("expected a number"), "{}", err.message);
    assert!(err.message.contains("\"two\""), "{}", err.message);

    let text = format!("{MINIMAL}\n[mesh]\nn_r = 2.5\norder = -1\n");
    let e = errors(&text);
    assert_eq!(
        e.find("mesh.n_r").and_then(|x| x.line),
        Some(line_of(&text, "n_r"))
    );
    assert_eq!(
        e.find("mesh.order").and_then(|x| x.line),
        Some(line_of(&text, "order"))
    );

    let text = replace_line(MINIMAL, "model", "model = \"ogden\"");
    let e = errors(&text);
    let err = e.find("material.model").unwrap_or_else(|| panic!("{e}"));
    assert!(err.message.contains("neo_hookean"), "{}", err.message);
    assert_eq!(err.line, Some(line_of(&text, "model")));
}

#[test]
fn non_finite_float_rejected() {
    let text = replace_line(MINIMAL, "omega", "omega = nan");
    let e = errors(&text);
    assert!(e.has_key("motion.omega"), "{e}");
}

#[test]
fn ri_not_less_than_ro_rejected_with_line() {
    let text = replace_line(MINIMAL, "ri =", "ri = 2.5   # larger than ro");
    let e = errors(&text);
    assert_eq!(e.0.len(), 1, "{e}");
    let err = &e.0[0];
    assert_eq!(err.key, "geometry.ro");
    assert_eq!(err.line, Some(line_of(&text, "ro =")));
    assert!(err.message.contains("greater than"), "{}", err.message);

    let text = replace_line(MINIMAL, "ri =", "ri = -1.0");
    let e = errors(&text);
    let err = e.find("geometry.ri").unwrap_or_else(|| panic!("{e}"));
    assert_eq!(err.line, Some(line_of(&text, "ri =")));
}

#[test]
fn non_positive_moduli_and_density_rejected() {
    let text = replace_line(MINIMAL, "mu =", "mu = 0.0");
    let text = replace_line(&text, "rho =", "rho = -0.027");
    let e = errors(&text);
    assert_eq!(e.0.len(), 2, "{e}");
    assert_eq!(
        e.find("material.mu").and_then(|x| x.line),
        Some(line_of(&text, "mu ="))
    );
    assert_eq!(
        e.find("material.rho").and_then(|x| x.line),
        Some(line_of(&text, "rho ="))
    );
    // Sorted by line.
    assert!(e.0[0].line < e.0[1].line);

    let e = errors(&replace_line(MOONEY_RIVLIN, "c2 ", "c2 = -1.0"));
    assert!(e.has_key("material.c2"), "{e}");
    let e = errors(&replace_line(MOONEY_RIVLIN, "kappa", "kappa = 0"));
    assert!(e.has_key("material.kappa"), "{e}");
    // c2 = 0 is fine.
    assert!(load(&replace_line(MOONEY_RIVLIN, "c2 ", "c2 = 0.0")).is_ok());
}

#[test]
fn n_theta_too_small_or_odd_rejected() {
    let e = errors(&format!("{MINIMAL}\n[mesh]\nn_theta = 6\n"));
    let err = e.find("mesh.n_theta").unwrap_or_else(|| panic!("{e}"));
    assert!(err.message.contains(">= 8"), "{}", err.message);
    let text = format!("{MINIMAL}\n[mesh]\nn_theta = 33\n");
    let e = errors(&text);
    let err = e.find("mesh.n_theta").unwrap_or_else(|| panic!("{e}"));
    assert!(err.message.contains("even"), "{}", err.message);
    assert_eq!(err.line, Some(line_of(&text, "n_theta")));
}

#[test]
fn other_mesh_and_solver_ranges_rejected() {
    let text = format!(
        "{MINIMAL}\n[mesh]\nn_r = 0\norder = 3\ngrading_r = 0\ngrading_theta = 1.0\n\
             [solver]\ntolerance = 1.0\nmax_iterations = 0\nload_steps = 0\n"
    );
    let e = errors(&text);
    for key in [
        "mesh.n_r",
        "mesh.order",
        "mesh.grading_r",
        "mesh.grading_theta",
        "solver.tolerance",
        "solver.max_iterations",
        "solver.load_steps",
    ] {
        assert!(e.has_key(key), "missing {key} in\n{e}");
    }
    assert_eq!(e.0.len(), 7, "{e}");
}

#[test]
fn scene_name_must_be_a_directory_name() {
    let e = errors(&replace_line(MINIMAL, "name", "name = \"my scene/1\""));
    assert!(e.has_key("scene.name"), "{e}");
    let e = errors(&replace_line(MINIMAL, "name", "name = \"\""));
    assert!(e.has_key("scene.name"), "{e}");
}

#[test]
fn key_not_belonging_to_model_rejected() {
    // lambda with mooney_rivlin
    let text = replace_line(MOONEY_RIVLIN, "kappa", "kappa = 2000.0\nlambda = 1800.0");
    let e = errors(&text);
    assert_eq!(e.0.len(), 1, "{e}");
    let err = &e.0[0];
    assert_eq!(err.key, "material.lambda");
    assert_eq!(err.line, Some(line_of(&text, "lambda")));
    assert!(err.message.contains("not a parameter"), "{}", err.message);
    // kappa with the exact incompressible formulation
    let text = replace_line(INCOMPRESSIBLE, "c2 ", "c2 = 20.0\nkappa = 1e5");
    let e = errors(&text);
    assert!(e.has_key("material.kappa"), "{e}");
    // formulation with neo_hookean
    let e = errors(&replace_line(
        MINIMAL,
        "mu =",
        "mu = 200\nformulation = \"exact\"",
    ));
    assert!(e.has_key("material.formulation"), "{e}");
}

#[test]
fn missing_required_keys_reported() {
    // Missing model parameter: line of the [material] header.
    let text = MINIMAL.replace("lambda = 1800.0\n", "");
    let e = errors(&text);
    let err = e.find("material.lambda").unwrap_or_else(|| panic!("{e}"));
    assert_eq!(err.line, Some(line_of(&text, "[material]")));
    assert!(err.message.contains("required"));
    // Missing schema-required key.
    let text = MINIMAL.replace("ro = 2.0\n", "");
    let e = errors(&text);
    let err = e.find("geometry.ro").unwrap_or_else(|| panic!("{e}"));
    assert_eq!(err.line, Some(line_of(&text, "[geometry]")));
    // Missing omega for spinning.
    let text = MINIMAL.replace("omega = 20.0\n", "");
    let e = errors(&text);
    assert!(e.has_key("motion.omega"), "{e}");
    // Missing section.
    let text = MINIMAL.replace("[analysis]\nmode = \"spinning\"\n", "");
    let e = errors(&text);
    let err = e.find("analysis").unwrap_or_else(|| panic!("{e}"));
    assert_eq!(err.line, None);
    assert!(err.message.contains("missing"));
}

#[test]
fn multiple_errors_reported_together() {
    let text = r#"
[scene]
name = "many"
[geometry]
ri = 3.0          # >= ro
ro = 2.0
[mesh]
n_theta = 7
bogus = 1
[material]
model = "mooney_rivlin"
rho = 0.0
c1 = 80
c2 = 20
kappa = 2000
mu = 3
[analysis]
mode = "spinning"
[motion]
omega = -1.0
[solver]
linear = "qr"
"#;
    let e = errors(text);
    for key in [
        "geometry.ro",
        "mesh.n_theta",
        "mesh.bogus",
        "material.rho",
        "material.mu",
        "motion.omega",
        "solver.linear",
    ] {
        let err = e
            .find(key)
            .unwrap_or_else(|| panic!("missing {key} in\n{e}"));
        assert!(err.line.is_some(), "{err}");
    }
    assert_eq!(e.0.len(), 7, "{e}");
    let shown = e.to_string();
    assert_eq!(shown.lines().count(), 7, "{shown}");
    // Ordered by line.
    let lines: Vec<usize> = e.0.iter().filter_map(|x| x.line).collect();
    let mut sorted = lines.clone();
    sorted.sort_unstable();
    assert_eq!(lines, sorted);
}

#[test]
fn ill_typed_required_key_reported_once() {
    let text = replace_line(MOONEY_RIVLIN, "c2 ", "c2 = \"20\"");
    let e = errors(&text);
    assert_eq!(e.0.len(), 1, "{e}");
    assert_eq!(e.0[0].key, "material.c2");
    assert!(e.0[0].message.contains("expected a number"), "{e}");
}

#[test]
fn type_and_range_errors_in_different_sections_together() {
    let text = replace_line(MINIMAL, "ri =", "ri = \"one\"");
    let text = replace_line(&text, "mu =", "mu = -5");
    let e = errors(&text);
    assert!(e.has_key("geometry.ri"), "{e}");
    assert!(e.has_key("material.mu"), "{e}");
}

#[test]
fn overrides_apply() {
    let s = load_with(
        INCOMPRESSIBLE,
        &[
            "mesh.n_r=8",
            " motion.omega = 30.5 ",
            "solver.linear=lu",
            "output.sinks=csv,mcap",
            "output.every=5",
            "scene.name=run2024",
            "scene.description=\"quoted text\"",
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.mesh.n_r, 8);
    assert_eq!(s.motion.omega, 30.5);
    assert_eq!(s.solver.linear, LinearChoice::Lu);
    assert_eq!(s.output.sinks, [Sink::Csv, Sink::Mcap]);
    assert_eq!(s.output.every, 5);
    assert_eq!(s.scene.name, "run2024");
    assert_eq!(s.scene.description, "quoted text");
    let s = load_with(MINIMAL, &["output.sinks=[\"rerun\"]"]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.output.sinks, [Sink::Rerun]);
    let s = load_with(MINIMAL, &["output.sinks=[]"]).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.output.sinks.is_empty());
    // A string-valued key takes an unquoted number literally.
    let s = load_with(MINIMAL, &["scene.name=2024"]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.scene.name, "2024");
    // An override can create a section absent from the file.
    let s = load_with(MINIMAL, &["solver.threads=3"]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.solver.threads, 3);
    // Switching the model by override.
    let s = load_with(
        MOONEY_RIVLIN,
        &[
            "material.model=mooney_rivlin_incompressible",
            "material.formulation=perturbed",
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        s.material.resolved_formulation(),
        Some(Formulation::Perturbed)
    );
    assert_eq!(s.material.kappa, Some(2000.0));
}

#[test]
fn override_of_unknown_key_rejected() {
    let e = errors_with(MINIMAL, &["mesh.nr=8"]);
    assert_eq!(e.0.len(), 1, "{e}");
    let err = &e.0[0];
    assert_eq!(err.key, "mesh.nr");
    assert_eq!(err.line, None);
    assert!(err.is_override());
    assert!(err.message.contains("mesh.nr=8"), "{}", err.message);
    assert!(err.to_string().contains("(--set)"), "{err}");

    let e = errors_with(MINIMAL, &["adaptivity.target=0.1"]);
    assert_only(&e, "adaptivity.target", None);
    assert!(e.0[0].message.contains("unknown section"), "{e}");
    let e = errors_with(MINIMAL, &["time.dtt=0.1"]);
    assert_only(&e, "time.dtt", None);
    assert!(e.0[0].message.contains("keys of [time]"), "{e}");
    let e = errors_with(MINIMAL, &["n_r=8"]);
    assert!(e.0[0].is_override(), "{e}");
    let e = errors_with(MINIMAL, &["mesh.n_r"]);
    assert_eq!(e.0[0].key, "mesh.n_r");
    assert!(e.0[0].message.contains("malformed"), "{e}");
}

#[test]
fn override_errors_show_set_instead_of_line() {
    let e = errors_with(INCOMPRESSIBLE, &["mesh.n_theta=7", "mesh.n_r=abc"]);
    assert_eq!(e.0.len(), 2, "{e}");
    for err in &e.0 {
        assert_eq!(err.line, None);
        assert!(err.is_override());
        assert!(
            err.to_string()
                .starts_with(&format!("test.toml:(--set): key `{}`", err.key)),
            "{err}"
        );
    }
    assert!(e
        .find("mesh.n_r")
        .is_some_and(|x| x.message.contains("\"abc\"")));
    // A non-overridden key keeps its line from the file while another key is overridden.
    let text = replace_line(INCOMPRESSIBLE, "rho", "rho = -1.0");
    let e = errors_with(&text, &["geometry.ro=0.5"]);
    let rho = e.find("material.rho").unwrap_or_else(|| panic!("{e}"));
    assert_eq!(rho.line, Some(line_of(&text, "rho")));
    assert!(!rho.is_override());
    let ro = e.find("geometry.ro").unwrap_or_else(|| panic!("{e}"));
    assert!(ro.is_override(), "{ro}");
    assert!(ro.to_string().contains("(--set)"));
}

#[test]
fn syntax_error_has_line() {
    let text = replace_line(MINIMAL, "ro =", "ro = ");
    let e = errors(&text);
    assert_eq!(e.0.len(), 1, "{e}");
    assert_eq!(e.0[0].line, Some(line_of(&text, "ro =")));
    let text = format!("{MINIMAL}[geometry]\nri = 1.0\n");
    let e = errors(&text);
    assert_eq!(e.0.len(), 1, "{e}");
    assert!(e.0[0].line.is_some());
    assert!(e.0[0].message.contains("duplicate"), "{e}");
}

#[test]
fn round_trip_through_to_toml_string() {
    for text in [
        INCOMPRESSIBLE,
        NEO_HOOKEAN,
        MOONEY_RIVLIN,
        MINIMAL,
        FRICTIONLESS,
        FRICTION,
        LOAD_CONTROL,
        STICK_SLIP,
        ODEN,
        ROLLING_FRICTIONLESS,
        FREE_ROLLING,
        BRAKING,
        STEADY_SWEEP,
    ] {
        let s = load(text).unwrap_or_else(|e| panic!("{e}"));
        let out = s.to_toml_string();
        let back =
            Scene::from_toml_str(&out, "roundtrip", &[]).unwrap_or_else(|e| panic!("{e}\n{out}"));
        assert_eq!(back, s, "{out}");
        // Strict serde on its own, too.
        let direct: Scene = toml::from_str(&out).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(direct, s);
        assert!(
            out.contains("[solver]") && out.contains("tolerance"),
            "{out}"
        );
    }
    let s = load_with(
        INCOMPRESSIBLE,
        &[
            "material.formulation=perturbed",
            "scene.description=a \"quoted\" # thing",
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let out = s.to_toml_string();
    assert!(out.contains("kappa"), "{out}");
    let back = load(&out).unwrap_or_else(|e| panic!("{e}\n{out}"));
    assert_eq!(back, s);
}

#[test]
fn output_sinks_are_checked() {
    let text = format!("{MINIMAL}\n[output]\nsinks = [\"csv\", \"hdf5\"]\nevery = 0\n");
    let e = load(&text).err().unwrap_or_else(|| panic!("accepted"));
    let sinks = e.find("output.sinks").unwrap_or_else(|| panic!("{e}"));
    assert!(
        sinks.message.contains("hdf5") && sinks.line.is_some(),
        "{e}"
    );
    assert!(e.has_key("output.every"), "{e}");
    let text = format!("{MINIMAL}\n[output]\nsinks = [\"csv\", \"csv\"]\n");
    let e = load(&text).err().unwrap_or_else(|| panic!("accepted"));
    assert!(
        e.find("output.sinks")
            .is_some_and(|x| x.message.contains("twice")),
        "{e}"
    );
    let e = errors_with(MINIMAL, &["output.sinks=csv,nope"]);
    assert!(
        e.find("output.sinks")
            .is_some_and(|x| x.message.contains("nope")),
        "{e}"
    );
    // Round trip of a non-default list.
    let s = load_with(MINIMAL, &["output.sinks=mcap,rerun", "output.every=3"])
        .unwrap_or_else(|e| panic!("{e}"));
    let back = load(&s.to_toml_string()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(back, s);
}

#[test]
fn serde_itself_rejects_unknown_fields() {
    let text = format!("{MINIMAL}\n[output]\nevery = 2\npng = true\n");
    let r: Result<Scene, _> = toml::from_str(&text);
    let e = r.err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("png"), "{e}");
}

#[test]
fn keyword_enums_match_serde_names() {
    fn check<T: Serialize + FromStr + fmt::Display + Copy + PartialEq + fmt::Debug>(
        all: &[T],
        names: &[&str],
    ) {
        assert_eq!(all.len(), names.len());
        for (v, n) in all.iter().zip(names) {
            assert_eq!(serde_json::to_string(v).ok(), Some(format!("\"{n}\"")));
            assert_eq!(v.to_string(), *n);
            assert_eq!(n.parse::<T>().ok(), Some(*v));
        }
    }
    check(Mode::ALL, Mode::NAMES);
    check(MaterialModel::ALL, MaterialModel::NAMES);
    check(Formulation::ALL, Formulation::NAMES);
    check(LinearChoice::ALL, LinearChoice::NAMES);
    check(ContactQuadrature::ALL, ContactQuadrature::NAMES);
    check(FrictionLawName::ALL, FrictionLawName::NAMES);
    check(Sink::ALL, Sink::NAMES);
    assert_eq!("spinning".parse::<Mode>(), Ok(Mode::Spinning));
    assert_eq!("static".parse::<Mode>(), Ok(Mode::Static));
    assert_eq!("stick_slip".parse::<Mode>(), Ok(Mode::StickSlip));
    assert_eq!("transient".parse::<Mode>(), Ok(Mode::Transient));
    assert_eq!("steady".parse::<Mode>(), Ok(Mode::Steady));
    check(ContinuationParameter::ALL, ContinuationParameter::NAMES);
    let err = "dynamic".parse::<Mode>().err().unwrap_or_default();
    assert!(
        err.contains("\"spinning\", \"static\", \"stick_slip\", \"transient\", \"steady\""),
        "{err}"
    );
    check(IntegratorName::ALL, IntegratorName::NAMES);
    check(MassKind::ALL, MassKind::NAMES);
    assert_eq!(IntegratorName::default(), IntegratorName::GeneralizedAlpha);
    assert_eq!(MassKind::default(), MassKind::Consistent);
    assert_eq!(
        IntegratorName::NAMES,
        &["generalized_alpha", "central_difference", "bdf", "sdirk"]
    );
    assert_eq!(FrictionLawName::default(), FrictionLawName::None);
    assert_eq!(ContactQuadrature::default(), ContactQuadrature::Lobatto);
}

#[test]
fn schema_matches_serde_structs() {
    fn keys<T: Serialize>(v: &T) -> Vec<String> {
        match serde_json::to_value(v) {
            Ok(serde_json::Value::Object(m)) => m.keys().cloned().collect(),
            _ => Vec::new(),
        }
    }
    let full_material = MaterialSpec {
        model: MaterialModel::NeoHookean,
        rho: 1.0,
        mu: Some(1.0),
        lambda: Some(1.0),
        c1: Some(1.0),
        c2: Some(1.0),
        kappa: Some(1.0),
        formulation: Some(Formulation::Exact),
        viscoelastic: Some(ViscoelasticSpec {
            model: "convolution".into(),
            gamma: 1.0,
            prony: vec![[1.0, 1.0]],
        }),
    };
    let info = SceneInfo {
        name: "a".into(),
        description: String::new(),
        units: String::new(),
    };
    let cases: Vec<(&str, Vec<String>)> = vec![
        ("scene", keys(&info)),
        ("geometry", keys(&Geometry { ri: 1.0, ro: 2.0 })),
        (
            "mesh",
            keys(&MeshSpec {
                file: Some("m.msh".into()),
                hub: Some("hub".into()),
                contact: Some("contact".into()),
                ..MeshSpec::default()
            }),
        ),
        ("material", keys(&full_material)),
        (
            "analysis",
            keys(&Analysis {
                mode: Mode::Spinning,
            }),
        ),
        ("motion", keys(&Motion::default())),
        ("road", keys(&full_road())),
        ("contact", keys(&full_contact())),
        ("friction", keys(&full_friction())),
        ("stick_slip", keys(&full_stick_slip())),
        ("time", keys(&full_time())),
        ("continuation", keys(&ContinuationSpec::default())),
        ("solver", keys(&SolverSpec::default())),
        ("output", keys(&OutputSpec::default())),
    ];
    assert_eq!(cases.len(), SCHEMA.len());
    for (name, mut serde_keys) in cases {
        let sec = section_schema(name).unwrap_or_else(|| panic!("{name}"));
        let mut schema_keys: Vec<String> = sec.fields.iter().map(|f| f.key.to_string()).collect();
        serde_keys.sort();
        schema_keys.sort();
        assert_eq!(serde_keys, schema_keys, "section {name}");
    }
}

#[test]
fn locator_handles_comments_quotes_dotted_and_multiline() {
    let text = r#"# header comment [geometry]
title = """
[geometry]
ri = 99
"""
arr = [
  [1, 2],
  { ri = 3 },
]
[ "geometry" ]   # spaced, quoted header
"ri" = 1.0 # comment with ro = 5
ro = "a # not a comment" # real comment
mesh.n_r = 4
[material]
'rho'=1
"#;
    let loc = Locator::new(text);
    assert_eq!(loc.locate("geometry"), Some(10));
    assert_eq!(loc.locate("geometry.ri"), Some(11));
    assert_eq!(loc.locate("geometry.ro"), Some(12));
    assert_eq!(loc.locate("geometry.mesh.n_r"), Some(13));
    assert_eq!(loc.locate("material.rho"), Some(15));
    assert_eq!(loc.locate("material.mu"), Some(14)); // missing: section header
    assert_eq!(loc.locate("solver.tolerance"), None);
    assert_eq!(loc.locate("arr"), Some(6));
    assert_eq!(loc.key_at_line(12).as_deref(), Some("geometry.ro"));

    // Top-level dotted keys define their section implicitly.
    let loc = Locator::new("geometry.ri = 1\ngeometry.ro = 2\n");
    assert_eq!(loc.locate("geometry.ro"), Some(2));
    assert_eq!(loc.locate("geometry.x"), Some(1));
}

#[test]
fn dotted_keys_in_file_get_lines() {
    let text = MINIMAL.replace("[motion]\nomega = 20.0\n", "motion.omega = -3.0\n");
    // Dotted top-level key after [analysis] means analysis.motion.omega: unknown key.
    let e = errors(&text);
    let err = e.find("analysis.motion").unwrap_or_else(|| panic!("{e}"));
    assert_eq!(err.line, Some(line_of(&text, "motion.omega")));
}

#[test]
fn no_panic_on_garbage() {
    let inputs = [
            "",
            "[",
            "[[scene]]\nname = 1",
            "scene = 3",
            "[scene]\nname = []\n[geometry]\nri = {}\nro = 1979-05-27T07:32:00Z",
            "\u{feff}[scene]\nname = \"é\"",
            "[mesh]\nn_r = -9223372036854775808\nn_theta = 9223372036854775807",
            "[material]\nmodel = 3\n[analysis]\nmode = \"static\"",
            "a = \"\"\"\nunterminated",
            "time = 3\n[analysis]\nmode = \"transient\"",
            "[analysis]\nmode = \"transient\"\n[time]\ndt = []\nt_end = {}\nmax_steps = -1\nmass = 1",
            "[analysis]\nmode = \"transient\"\n[motion]\nramp = \"x\"\n[road]\nramp = -1e308\nv0_ramp = nan",
        ];
    for text in inputs {
        let r = Scene::from_toml_str(text, "x", &["=".into(), "..=".into(), "a.b.c=1".into()]);
        let e = r.err().unwrap_or_else(|| panic!("accepted {text:?}"));
        assert!(!e.0.is_empty());
        let _ = e.to_string();
    }
    let e = errors("");
    for sec in ["scene", "geometry", "material", "analysis"] {
        assert!(e.has_key(sec), "{e}");
    }
}

// --- contact, friction, road, stick-slip ---------------------------------------------

fn full_road() -> RoadSpec {
    RoadSpec {
        disp: Some(0.1),
        load: Some(1.0),
        v0: 0.0,
        ramp: 0.0,
        v0_ramp: Some(0.0),
    }
}

fn full_contact() -> ContactSpec {
    ContactSpec {
        c_n: 1.0,
        m_n: 1.0,
        b_n: 0.0,
        l_n: 0.0,
        quadrature: ContactQuadrature::Gauss,
        points: 4,
        clamp: ClampKind::Smooth,
        clamp_width: Some(10.0),
    }
}

fn full_friction() -> FrictionSpec {
    FrictionSpec {
        law: FrictionLawName::None,
        mu: Some(1.0),
        eps: Some(1.0),
        mu_s: Some(1.0),
        mu_k: Some(1.0),
        v_s: Some(1.0),
        c_t: Some(1.0),
        m_t: Some(1.0),
    }
}

fn full_stick_slip() -> StickSlipSpec {
    StickSlipSpec {
        mass: 1.0,
        stiffness: 1.0,
        normal_force: 1.0,
        belt_speed: 1.0,
        t_end: 1.0,
        rtol: 1e-8,
        atol: 1e-10,
        x0: 0.0,
        v0: Some(0.0),
        output_interval: Some(0.1),
    }
}

fn full_time() -> TimeSpec {
    TimeSpec {
        dt_min: Some(1e-6),
        dt_max: Some(1e-2),
        ..TimeSpec::new(1e-3, 1.0)
    }
}

/// Remove the section starting at the line `header` up to (not including) the next header.
fn remove_section(text: &str, header: &str) -> String {
    let mut out = Vec::new();
    let mut skipping = false;
    let mut found = false;
    for l in text.lines() {
        let t = l.trim_start();
        if t.starts_with('[') {
            skipping = t.starts_with(header);
            found |= skipping;
        }
        if !skipping {
            out.push(l);
        }
    }
    assert!(found, "no section {header}");
    out.join("\n") + "\n"
}

/// The single error of `e`, which must name `key`, on `line`.
fn assert_only(e: &SceneErrors, key: &str, line: Option<usize>) {
    assert_eq!(e.0.len(), 1, "{e}");
    assert_eq!(e.0[0].key, key, "{e}");
    assert_eq!(e.0[0].line, line, "{e}");
}

#[test]
fn indentation_scenes_parse() {
    let s = load(FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.scene.name, "indentation_frictionless");
    assert_eq!(s.analysis.mode, Mode::Static);
    assert_eq!((s.geometry.ri, s.geometry.ro), (1.0, 2.0));
    assert_eq!((s.mesh.n_r, s.mesh.n_theta, s.mesh.order), (6, 96, 2));
    assert_eq!(s.mesh.grading_theta, 0.6);
    assert_eq!(
        s.material.params(),
        Some(MaterialParams::MooneyRivlin {
            c1: 80.0,
            c2: 20.0,
            kappa: 2000.0
        })
    );
    assert_eq!(s.material.rho, 0.027);
    assert_eq!(s.motion.omega, 0.0);
    assert_eq!(
        s.road,
        Some(RoadSpec {
            disp: Some(0.1),
            load: None,
            v0: 0.0,
            ramp: 0.0,
            v0_ramp: None
        })
    );
    assert_eq!(
        s.contact,
        Some(ContactSpec {
            c_n: 2.0e5,
            m_n: 1.0,
            b_n: 0.0,
            l_n: 0.0,
            quadrature: ContactQuadrature::Lobatto,
            points: 4,
            clamp: ClampKind::Hard,
            clamp_width: None
        })
    );
    // c_n = 1000 G / (Ro − Ri).
    let g = s.material.shear_modulus().unwrap_or(0.0);
    let c_n = s.contact.as_ref().map_or(0.0, |c| c.c_n);
    assert!((c_n - 1000.0 * g / (s.geometry.ro - s.geometry.ri)).abs() < 1e-6);
    assert_eq!(s.friction, FrictionSpec::default());
    assert_eq!(s.friction.params(), Some(FrictionParams::None));
    assert!(!s.friction.is_active());
    assert_eq!(s.stick_slip, None);
    assert_eq!(s.solver.load_steps, 5);
    assert!(s.validate().is_ok());

    let f = load(FRICTION).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(f.scene.name, "indentation_friction");
    assert_eq!(
        f.friction.params(),
        Some(FrictionParams::CoulombTanh { mu: 0.3, eps: 0.01 })
    );
    assert!(f.friction.is_active());
    // Same scene otherwise.
    assert_eq!(
        (&f.road, &f.contact, &f.mesh),
        (&s.road, &s.contact, &s.mesh)
    );
    assert_eq!(f.material, s.material);
}

#[test]
fn load_control_scene_parses() {
    let s = load(LOAD_CONTROL).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.scene.name, "indentation_load_control");
    assert_eq!(s.analysis.mode, Mode::Static);
    assert_eq!(
        s.road,
        Some(RoadSpec {
            disp: None,
            load: Some(300.0),
            v0: 0.0,
            ramp: 0.0,
            v0_ramp: None
        })
    );
    let base = load(FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.contact, base.contact);
    assert_eq!(s.friction, base.friction);
    assert_eq!(s.mesh, base.mesh);
    assert_eq!(s.solver, base.solver);
}

#[test]
fn stick_slip_scene_parses() {
    let s = load(STICK_SLIP).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.scene.name, "stick_slip");
    assert_eq!(s.scene.units, "m-N-s");
    assert_eq!(s.analysis.mode, Mode::StickSlip);
    assert_eq!(s.road, None);
    assert_eq!(s.contact, None);
    let ss = s
        .stick_slip
        .clone()
        .unwrap_or_else(|| panic!("no [stick_slip]"));
    assert_eq!(
        (
            ss.mass,
            ss.stiffness,
            ss.normal_force,
            ss.belt_speed,
            ss.t_end
        ),
        (1.0, 100.0, 10.0, 0.1, 20.0)
    );
    assert_eq!((ss.rtol, ss.atol, ss.x0), (1e-8, 1e-10, 0.0));
    assert_eq!((ss.v0, ss.output_interval), (None, None));
    assert_eq!(ss.initial_velocity(), 0.1);
    assert!((ss.resolved_output_interval() - 0.01).abs() < 1e-15);
    assert_eq!(
        s.friction.params(),
        Some(FrictionParams::RateDependent {
            mu_s: 0.6,
            mu_k: 0.4,
            v_s: 1e-4,
            eps: 1e-7
        })
    );
    assert!(s.friction.is_active());
    assert!(s.validate().is_ok());
    // Defaults of an explicit minimal [stick_slip].
    let text = STICK_SLIP
        .lines()
        .filter(|l| {
            let t = l.trim_start();
            !["rtol", "atol", "x0"].iter().any(|k| t.starts_with(k))
        })
        .collect::<Vec<_>>()
        .join("\n");
    let d = load(&text).unwrap_or_else(|e| panic!("{e}"));
    let dss = d.stick_slip.unwrap_or_else(|| panic!("no [stick_slip]"));
    assert_eq!(dss.rtol, DEFAULT_STICK_SLIP_RTOL);
    assert_eq!(dss.atol, DEFAULT_STICK_SLIP_ATOL);
    assert_eq!(dss.x0, 0.0);
}

#[test]
fn contact_defaults_are_filled() {
    let text = remove_section(FRICTIONLESS, "[contact]") + "[contact]\nc_n = 1e4\n";
    let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        s.contact,
        Some(ContactSpec {
            c_n: 1e4,
            m_n: DEFAULT_M_N,
            b_n: 0.0,
            l_n: 0.0,
            quadrature: ContactQuadrature::Lobatto,
            points: DEFAULT_CONTACT_POINTS,
            clamp: ClampKind::Hard,
            clamp_width: None
        })
    );
    // No [friction] at all: law none.
    let text = remove_section(FRICTION, "[friction]");
    let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.friction.law, FrictionLawName::None);
    assert!(!s.friction.is_active());
}

#[test]
fn friction_params_and_is_active() {
    let mut f = FrictionSpec {
        law: FrictionLawName::CoulombLinear,
        mu: Some(0.0),
        eps: Some(1e-3),
        ..FrictionSpec::default()
    };
    assert_eq!(
        f.params(),
        Some(FrictionParams::CoulombLinear { mu: 0.0, eps: 1e-3 })
    );
    assert!(!f.is_active(), "zero coefficient");
    f.mu = Some(0.2);
    assert!(f.is_active());
    f.eps = None;
    assert_eq!(f.params(), None);
    assert!(!f.is_active(), "incomplete");
    let om = FrictionSpec {
        law: FrictionLawName::OdenMartins,
        c_t: Some(5.0),
        m_t: Some(1.5),
        eps: Some(1e-3),
        ..FrictionSpec::default()
    };
    assert_eq!(
        om.params(),
        Some(FrictionParams::OdenMartins {
            c_t: 5.0,
            m_t: 1.5,
            eps: 1e-3
        })
    );
    assert!(om.is_active());
    let rd = FrictionSpec {
        law: FrictionLawName::RateDependent,
        mu_s: Some(0.0),
        mu_k: Some(0.0),
        v_s: Some(1.0),
        eps: Some(1e-3),
        ..FrictionSpec::default()
    };
    assert!(!rd.is_active());
    assert_eq!(FrictionSpec::keys_of(FrictionLawName::None), &[] as &[&str]);
    assert_eq!(
        FrictionSpec::keys_of(FrictionLawName::RateDependent),
        &["mu_s", "mu_k", "v_s", "eps"]
    );
}

#[test]
fn non_positive_c_n_rejected_with_line() {
    for bad in ["c_n = 0.0", "c_n = -2.0e5"] {
        let text = replace_line(FRICTIONLESS, "c_n", bad);
        let e = errors(&text);
        assert_only(&e, "contact.c_n", Some(line_of(&text, "c_n")));
        assert!(e.0[0].message.contains("> 0"), "{e}");
    }
}

#[test]
fn contact_exponents_damping_and_points_rejected() {
    let text = replace_line(FRICTIONLESS, "m_n", "m_n = 0.5");
    let e = errors(&text);
    assert_only(&e, "contact.m_n", Some(line_of(&text, "m_n")));
    assert!(e.0[0].message.contains(">= 1"), "{e}");

    let text = replace_line(FRICTIONLESS, "b_n", "b_n = -1.0");
    let text = replace_line(&text, "l_n", "l_n = -0.5");
    let text = replace_line(&text, "points", "points = 7");
    let e = errors(&text);
    assert_eq!(e.0.len(), 3, "{e}");
    for key in ["b_n", "l_n", "points"] {
        let err = e
            .find(&format!("contact.{key}"))
            .unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, key)), "{err}");
    }
    let e = errors(&replace_line(FRICTIONLESS, "points", "points = 1"));
    assert!(e.has_key("contact.points"), "{e}");
    for ok in ["points = 2", "points = 6"] {
        assert!(
            load(&replace_line(FRICTIONLESS, "points", ok)).is_ok(),
            "{ok}"
        );
    }
    assert!(load(&replace_line(FRICTIONLESS, "m_n", "m_n = 1.5")).is_ok());
}

#[test]
fn contact_clamp_keys_are_validated() {
    // Default: the hard clamp, no width.
    let sc = load(FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
    let c = sc.contact.as_ref().unwrap_or_else(|| panic!("no contact"));
    assert_eq!((c.clamp, c.clamp_width), (ClampKind::Hard, None));
    // Smooth with and without a width.
    let text = replace_line(FRICTIONLESS, "points", "points = 4\nclamp = \"smooth\"");
    let sc = load(&text).unwrap_or_else(|e| panic!("{e}"));
    let c = sc.contact.as_ref().unwrap_or_else(|| panic!("no contact"));
    assert_eq!((c.clamp, c.clamp_width), (ClampKind::Smooth, None));
    let sc = load_with(&text, &["contact.clamp_width=25"]).unwrap_or_else(|e| panic!("{e}"));
    let c = sc.contact.as_ref().unwrap_or_else(|| panic!("no contact"));
    assert_eq!(c.clamp_width, Some(25.0));
    // A misspelt clamp names the key and the allowed values.
    let bad = replace_line(FRICTIONLESS, "points", "points = 4\nclamp = \"soft\"");
    let e = errors(&bad);
    assert_only(&e, "contact.clamp", Some(line_of(&bad, "clamp")));
    assert!(
        e.0[0].message.contains("\"hard\"") && e.0[0].message.contains("\"smooth\""),
        "{e}"
    );
    // A width must be positive and is only allowed with the smooth clamp.
    for w in ["0", "-3"] {
        let e = errors_with(&text, &[&format!("contact.clamp_width={w}")]);
        assert!(e.has_key("contact.clamp_width"), "{e}");
        assert!(e.0[0].message.contains("> 0"), "{e}");
    }
    let e = errors_with(FRICTIONLESS, &["contact.clamp_width=5"]);
    assert!(e.has_key("contact.clamp_width"), "{e}");
    assert!(e.0[0].message.contains("smooth"), "{e}");
    // The printed scene keeps the choice (round trip).
    let sc = load_with(&text, &["contact.clamp_width=25"]).unwrap_or_else(|e| panic!("{e}"));
    let back = load(&sc.to_toml_string()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(back.contact, sc.contact);
}

#[test]
fn negative_mu_and_non_positive_eps_rejected() {
    let text = replace_line(FRICTION, "mu =", "mu = -0.1");
    let e = errors(&text);
    assert_only(&e, "friction.mu", Some(line_of(&text, "mu =")));
    assert!(e.0[0].message.contains(">= 0"), "{e}");
    assert!(load(&replace_line(FRICTION, "mu =", "mu = 0.0")).is_ok());

    for bad in ["eps = 0.0", "eps = -0.01"] {
        let text = replace_line(FRICTION, "eps", bad);
        let e = errors(&text);
        assert_only(&e, "friction.eps", Some(line_of(&text, "eps")));
        assert!(e.0[0].message.contains("> 0"), "{e}");
    }
    let text = replace_line(STICK_SLIP, "eps", "eps = 0");
    let e = errors(&text);
    assert_only(&e, "friction.eps", Some(line_of(&text, "eps")));
    let text = replace_line(STICK_SLIP, "mu_s", "mu_s = -0.6");
    let e = errors(&text);
    assert_only(&e, "friction.mu_s", Some(line_of(&text, "mu_s")));
    let text = replace_line(STICK_SLIP, "v_s", "v_s = 0.0");
    let e = errors(&text);
    assert_only(&e, "friction.v_s", Some(line_of(&text, "v_s")));
}

#[test]
fn kinetic_above_static_rejected() {
    let text = replace_line(STICK_SLIP, "mu_k", "mu_k = 0.7");
    let e = errors(&text);
    assert_only(&e, "friction.mu_k", Some(line_of(&text, "mu_k")));
    assert!(e.0[0].message.contains("must not exceed"), "{e}");
    assert!(load(&replace_line(STICK_SLIP, "mu_k", "mu_k = 0.6")).is_ok());
}

#[test]
fn oden_martins_keys_checked() {
    let text = FRICTIONLESS.replace(
        "law = \"none\"",
        "law = \"oden_martins\"\nc_t = 6.0e4\nm_t = 0.5\neps = 0.01",
    );
    let e = errors(&text);
    assert_only(&e, "friction.m_t", Some(line_of(&text, "m_t")));
    let s = load(&replace_line(&text, "m_t", "m_t = 1.0")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        s.friction.params(),
        Some(FrictionParams::OdenMartins {
            c_t: 6.0e4,
            m_t: 1.0,
            eps: 0.01
        })
    );
    // Missing keys of the law: reported at the [friction] header.
    let text = FRICTIONLESS.replace("law = \"none\"", "law = \"oden_martins\"");
    let e = errors(&text);
    assert_eq!(e.0.len(), 3, "{e}");
    for key in ["friction.c_t", "friction.m_t", "friction.eps"] {
        let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, "[friction]")));
        assert!(err.message.contains("required for friction law"), "{err}");
    }
}

#[test]
fn both_or_neither_disp_and_load_rejected() {
    let text = replace_line(FRICTIONLESS, "disp", "disp = 0.1\nload = 300.0");
    let e = errors(&text);
    assert_only(&e, "road.disp", Some(line_of(&text, "disp")));
    assert!(e.0[0].message.contains("not both"), "{e}");

    let text = FRICTIONLESS
        .lines()
        .filter(|l| !l.starts_with("disp"))
        .collect::<Vec<_>>()
        .join("\n");
    let e = errors(&text);
    assert_only(&e, "road.disp", Some(line_of(&text, "[road]")));
    assert!(e.0[0].message.contains("required"), "{e}");

    let text = replace_line(LOAD_CONTROL, "load =", "load = 0.0");
    let e = errors(&text);
    assert_only(&e, "road.load", Some(line_of(&text, "load =")));
    let text = replace_line(FRICTIONLESS, "disp", "disp = -0.1");
    let e = errors(&text);
    assert_only(&e, "road.disp", Some(line_of(&text, "disp")));
    // Penetration at least the wall thickness.
    let text = replace_line(FRICTIONLESS, "disp", "disp = 1.0");
    let e = errors(&text);
    assert_only(&e, "road.disp", Some(line_of(&text, "disp")));
    assert!(e.0[0].message.contains("wall thickness"), "{e}");
    assert!(load(&replace_line(FRICTIONLESS, "disp", "disp = 0")).is_ok());
}

#[test]
fn static_without_road_or_contact_rejected() {
    let text = remove_section(FRICTIONLESS, "[road]");
    let e = errors(&text);
    assert_only(&e, "road", Some(line_of(&text, "mode =")));
    assert!(e.0[0].message.contains("\"static\""), "{e}");
    assert!(e.0[0].message.contains("missing"), "{e}");

    let text = remove_section(&text, "[contact]");
    let e = errors(&text);
    assert_eq!(e.0.len(), 2, "{e}");
    for key in ["road", "contact"] {
        let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, "mode =")));
    }
    // Switching a spinning scene to static by override: the mode is the anchor, so (--set).
    let e = errors_with(MINIMAL, &["analysis.mode=static", "motion.omega=0"]);
    assert_eq!(e.0.len(), 2, "{e}");
    assert!(
        e.0.iter().all(|x| x.is_override() && x.line.is_none()),
        "{e}"
    );
}

#[test]
fn friction_key_of_another_law_rejected() {
    let text = replace_line(FRICTION, "eps", "eps = 0.01\nmu_s = 0.5");
    let e = errors(&text);
    assert_only(&e, "friction.mu_s", Some(line_of(&text, "mu_s")));
    assert!(e.0[0].message.contains("not a parameter"), "{e}");
    assert!(e.0[0].message.contains("coulomb_tanh"), "{e}");
    assert!(e.0[0].message.contains("law, mu, eps"), "{e}");

    let text = replace_line(STICK_SLIP, "v_s", "v_s = 0.01\nmu = 0.5");
    let e = errors(&text);
    assert_only(&e, "friction.mu", Some(line_of(&text, "mu = 0.5")));

    let text = FRICTIONLESS.replace("law = \"none\"", "law = \"none\"\nmu = 0.3");
    let e = errors(&text);
    assert_only(&e, "friction.mu", Some(line_of(&text, "mu =")));
    assert!(e.0[0].message.contains("takes no other key"), "{e}");
}

#[test]
fn invalid_friction_law_reported_once() {
    // The keys of an unknown law are not checked against the default law.
    let text = replace_line(FRICTION, "law", "law = \"coulomb\"");
    let e = errors(&text);
    assert_only(&e, "friction.law", Some(line_of(&text, "law")));
    assert!(e.0[0].message.contains("coulomb_tanh"), "{e}");
    let text = replace_line(STICK_SLIP, "law", "law = 3");
    let e = errors(&text);
    assert_only(&e, "friction.law", Some(line_of(&text, "law")));
}

#[test]
fn stick_slip_without_section_or_law_rejected() {
    let text = remove_section(STICK_SLIP, "[stick_slip]");
    let e = errors(&text);
    assert_only(&e, "stick_slip", Some(line_of(&text, "mode =")));
    assert!(e.0[0].message.contains("missing"), "{e}");

    let text = remove_section(STICK_SLIP, "[friction]");
    let e = errors(&text);
    assert_only(&e, "friction.law", Some(line_of(&text, "mode =")));
    assert!(e.0[0].message.contains("\"none\""), "{e}");

    let text = STICK_SLIP.replace(
        "law = \"rate_dependent\"",
        "law = \"oden_martins\"\nc_t = 1\nm_t = 1",
    );
    let text = text
        .lines()
        .filter(|l| !["mu_s", "mu_k", "v_s"].iter().any(|k| l.starts_with(k)))
        .collect::<Vec<_>>()
        .join("\n");
    let e = errors(&text);
    assert_only(&e, "friction.law", Some(line_of(&text, "law")));
    assert!(e.0[0].message.contains("penetration"), "{e}");

    // Coulomb laws are fine.
    let text = STICK_SLIP
        .lines()
        .filter(|l| !["mu_s", "mu_k", "v_s"].iter().any(|k| l.starts_with(k)))
        .collect::<Vec<_>>()
        .join("\n");
    let s = load_with(&text, &["friction.law=coulomb_linear", "friction.mu=0.5"])
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        s.friction.params(),
        Some(FrictionParams::CoulombLinear { mu: 0.5, eps: 1e-7 })
    );
}

#[test]
fn stick_slip_ranges_and_required_keys() {
    let text = replace_line(STICK_SLIP, "mass", "mass = 0.0");
    let text = replace_line(&text, "belt_speed", "belt_speed = -0.1");
    let text = replace_line(&text, "rtol", "rtol = 0");
    let e = errors(&text);
    assert_eq!(e.0.len(), 3, "{e}");
    for key in ["mass", "belt_speed", "rtol"] {
        let err = e
            .find(&format!("stick_slip.{key}"))
            .unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, key)));
    }
    let e = errors(&STICK_SLIP.replace("t_end = 20.0", ""));
    let err = e.find("stick_slip.t_end").unwrap_or_else(|| panic!("{e}"));
    assert!(err.message.contains("required key is missing"), "{err}");
    assert_eq!(e.0.len(), 1, "{e}");
    let e = errors_with(STICK_SLIP, &["stick_slip.output_interval=30"]);
    assert_only(&e, "stick_slip.output_interval", None);
    assert!(e.0[0].is_override());
    let s = load_with(
        STICK_SLIP,
        &["stick_slip.output_interval=0.05", "stick_slip.v0=0"],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let ss = s.stick_slip.unwrap_or_else(|| panic!("no [stick_slip]"));
    assert_eq!(ss.resolved_output_interval(), 0.05);
    assert_eq!(ss.initial_velocity(), 0.0);
}

#[test]
fn sections_not_used_by_the_mode_rejected() {
    // [road] and [contact] in a spinning scene.
    let text = format!("{MINIMAL}\n[road]\ndisp = 0.1\n\n[contact]\nc_n = 1e5\n");
    let e = errors(&text);
    assert_eq!(e.0.len(), 2, "{e}");
    assert_eq!(
        e.find("road").and_then(|x| x.line),
        Some(line_of(&text, "[road]"))
    );
    assert_eq!(
        e.find("contact").and_then(|x| x.line),
        Some(line_of(&text, "[contact]"))
    );
    assert!(e.0[0].message.contains("not used"), "{e}");
    // An override creating [road] in a spinning scene: (--set).
    let e = errors_with(MINIMAL, &["road.disp=0.1"]);
    assert_only(&e, "road", None);
    assert!(e.0[0].is_override(), "{e}");
    // Friction in a spinning scene.
    let text = format!("{MINIMAL}\n[friction]\nlaw = \"coulomb_tanh\"\nmu = 0.3\neps = 0.1\n");
    let e = errors(&text);
    assert_only(&e, "friction.law", Some(line_of(&text, "law")));
    assert!(load(&format!("{MINIMAL}\n[friction]\nlaw = \"none\"\n")).is_ok());
    // [stick_slip] in a static scene; [road] in a stick-slip scene.
    let text = format!(
        "{FRICTIONLESS}\n[stick_slip]\nmass = 1\nstiffness = 1\nnormal_force = 1\n\
             belt_speed = 1\nt_end = 1\n"
    );
    let e = errors(&text);
    assert_only(&e, "stick_slip", Some(line_of(&text, "[stick_slip]")));
    let text = format!("{STICK_SLIP}\n[road]\nload = 1.0\n");
    let e = errors(&text);
    assert_only(&e, "road", Some(line_of(&text, "[road]")));
}

#[test]
fn static_rejects_spin_road_speed_and_damping() {
    let text = format!("{FRICTIONLESS}\n[motion]\nomega = 20.0\n");
    let e = errors(&text);
    assert_only(&e, "motion.omega", Some(line_of(&text, "omega")));
    let text = replace_line(FRICTIONLESS, "v0", "v0 = 1.0");
    let e = errors(&text);
    assert_only(&e, "road.v0", Some(line_of(&text, "v0")));
    let text = replace_line(FRICTIONLESS, "b_n", "b_n = 5.0");
    let e = errors(&text);
    assert_only(&e, "contact.b_n", Some(line_of(&text, "b_n")));
    let e = errors_with(STICK_SLIP, &["motion.omega=1"]);
    assert_only(&e, "motion.omega", None);
}

#[test]
fn missing_c_n_reported_once() {
    let text = FRICTIONLESS
        .lines()
        .filter(|l| !l.starts_with("c_n"))
        .collect::<Vec<_>>()
        .join("\n");
    let e = errors(&text);
    assert_only(&e, "contact.c_n", Some(line_of(&text, "[contact]")));
    assert!(e.0[0].message.contains("required key is missing"), "{e}");
    let e = errors(&replace_line(FRICTIONLESS, "c_n", "c_n = \"big\""));
    assert_eq!(e.0.len(), 1, "{e}");
    assert!(e.0[0].message.contains("expected a number"), "{e}");
}

#[test]
fn overrides_of_new_keys() {
    let s = load_with(FRICTION, &["friction.mu=0.5"]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        s.friction.params(),
        Some(FrictionParams::CoulombTanh { mu: 0.5, eps: 0.01 })
    );
    let s = load_with(
        FRICTIONLESS,
        &[
            "friction.law=coulomb_linear",
            "friction.mu=0.2",
            "friction.eps=1e-3",
            "contact.quadrature=lobatto",
            "contact.points=3",
            "contact.m_n=2",
            "road.disp=0.05",
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        s.friction.params(),
        Some(FrictionParams::CoulombLinear { mu: 0.2, eps: 1e-3 })
    );
    let c = s.contact.unwrap_or_else(|| panic!("no contact"));
    assert_eq!(
        (c.quadrature, c.points, c.m_n),
        (ContactQuadrature::Lobatto, 3, 2.0)
    );
    assert_eq!(s.road.and_then(|r| r.disp), Some(0.05));
    let s = load_with(LOAD_CONTROL, &["road.load=250"]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.road.and_then(|r| r.load), Some(250.0));
    let s = load_with(STICK_SLIP, &["stick_slip.t_end=5", "friction.mu_k=0.3"])
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.stick_slip.map(|x| x.t_end), Some(5.0));
    assert_eq!(s.friction.mu_k, Some(0.3));

    // Bad override values: (--set) and the key.
    let e = errors_with(FRICTION, &["friction.mu=-1"]);
    assert_only(&e, "friction.mu", None);
    assert!(e.0[0].is_override());
    assert!(
        e.0[0]
            .to_string()
            .starts_with("test.toml:(--set): key `friction.mu`"),
        "{e}"
    );
    let e = errors_with(FRICTIONLESS, &["contact.quadrature=simpson"]);
    assert_only(&e, "contact.quadrature", None);
    assert!(e.0[0].message.contains("\"lobatto\""), "{e}");
    // Adding `load` by override to a disp scene: the clash is reported at `disp`'s line.
    let e = errors_with(FRICTIONLESS, &["road.load=300"]);
    assert_only(&e, "road.disp", Some(line_of(FRICTIONLESS, "disp")));
    // Unknown keys of the new sections.
    let e = errors_with(FRICTION, &["friction.muu=0.5"]);
    assert_only(&e, "friction.muu", None);
    assert!(e.0[0].message.contains("mu_s"), "{e}");
}

#[test]
fn unknown_keys_in_new_sections_rejected() {
    let text = replace_line(FRICTIONLESS, "c_n", "c_n = 2e5\npenalty = 1e5");
    let e = errors(&text);
    assert_only(&e, "contact.penalty", Some(line_of(&text, "penalty")));
    let text = replace_line(STICK_SLIP, "mass", "mass = 1.0\ndamping = 0.1");
    let e = errors(&text);
    assert_only(&e, "stick_slip.damping", Some(line_of(&text, "damping")));
    let text = replace_line(FRICTIONLESS, "disp", "disp = 0.1\nspeed = 2");
    let e = errors(&text);
    assert_only(&e, "road.speed", Some(line_of(&text, "speed")));
    assert!(e.0[0].message.contains("v0_ramp"), "{e}");
}

#[test]
fn round_trip_of_optional_new_keys() {
    let cases: [(&str, &[&str]); 3] = [
        (
            STICK_SLIP,
            &["stick_slip.v0=0.05", "stick_slip.output_interval=0.02"],
        ),
        (
            FRICTIONLESS,
            &[
                "friction.law=oden_martins",
                "friction.c_t=6e4",
                "friction.m_t=1",
                "friction.eps=0.01",
                "contact.quadrature=lobatto",
            ],
        ),
        (LOAD_CONTROL, &["contact.l_n=1.5"]),
    ];
    for (text, ov) in cases {
        let s = load_with(text, ov).unwrap_or_else(|e| panic!("{e}"));
        let out = s.to_toml_string();
        let back = load(&out).unwrap_or_else(|e| panic!("{e}\n{out}"));
        assert_eq!(back, s, "{out}");
        let direct: Scene = toml::from_str(&out).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(direct, s);
    }
    // Absent optional sections are not written; [friction] always is.
    let out = load(MINIMAL)
        .unwrap_or_else(|e| panic!("{e}"))
        .to_toml_string();
    assert!(
        !out.contains("[road]") && !out.contains("[contact]"),
        "{out}"
    );
    assert!(!out.contains("[stick_slip]"), "{out}");
    assert!(out.contains("[friction]\nlaw = \"none\""), "{out}");
}

#[test]
fn schema_required_flags_match_serde() {
    fn check<T: Serialize + DeserializeOwned + fmt::Debug>(name: &str, full: &T) {
        let sec = section_schema(name).unwrap_or_else(|| panic!("{name}"));
        let table = match toml::Value::try_from(full) {
            Ok(toml::Value::Table(t)) => t,
            other => panic!("{name}: {other:?}"),
        };
        for f in sec.fields {
            assert!(table.contains_key(f.key), "{name}.{} not serialized", f.key);
            let mut t = table.clone();
            t.remove(f.key);
            let r = toml::Value::Table(t).try_into::<T>();
            assert_eq!(r.is_err(), f.required, "{name}.{}: {r:?}", f.key);
        }
    }
    check(
        "scene",
        &SceneInfo {
            name: "a".into(),
            description: "d".into(),
            units: "u".into(),
        },
    );
    check("geometry", &Geometry { ri: 1.0, ro: 2.0 });
    check(
        "mesh",
        &MeshSpec {
            file: Some("m.msh".into()),
            hub: Some("hub".into()),
            contact: Some("contact".into()),
            ..MeshSpec::default()
        },
    );
    check(
        "material",
        &MaterialSpec {
            model: MaterialModel::NeoHookean,
            rho: 1.0,
            mu: Some(1.0),
            lambda: Some(1.0),
            c1: Some(1.0),
            c2: Some(1.0),
            kappa: Some(1.0),
            formulation: Some(Formulation::Exact),
            viscoelastic: Some(ViscoelasticSpec {
                model: "multiplicative".into(),
                gamma: 2.0,
                prony: vec![[0.5, 0.1], [0.5, 1.0]],
            }),
        },
    );
    check("analysis", &Analysis { mode: Mode::Static });
    check("motion", &Motion::default());
    check("road", &full_road());
    check("contact", &full_contact());
    check("friction", &full_friction());
    check("stick_slip", &full_stick_slip());
    check("time", &full_time());
    check("solver", &SolverSpec::default());
    check("output", &OutputSpec::default());
}

#[test]
fn validate_checks_new_sections_of_scenes_built_in_code() {
    let mut s = load(FRICTION).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.validate().is_ok());
    s.friction.mu = Some(-0.3);
    if let Some(c) = s.contact.as_mut() {
        c.c_n = 0.0;
    }
    s.stick_slip = Some(full_stick_slip());
    let e = s.validate().err().unwrap_or_else(|| panic!("accepted"));
    assert_eq!(e.0.len(), 3, "{e}");
    for key in ["friction.mu", "contact.c_n", "stick_slip"] {
        let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, None);
        assert_eq!(err.source_name, "<scene>");
    }
    s.stick_slip = None;
    s.road = None;
    let e = s.validate().err().unwrap_or_else(|| panic!("accepted"));
    assert!(e.has_key("road"), "{e}");
}

// --- transient mode, [time], ramps ------------------------------------------------------

/// MINIMAL as a transient scene without contact: only the required keys of [time].
fn minimal_transient() -> String {
    MINIMAL.replace("mode = \"spinning\"", "mode = \"transient\"")
        + "\n[time]\ndt = 1e-3\nt_end = 0.5\n"
}

#[test]
fn oden_scene_parses() {
    let s = load(ODEN).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.scene.name, "oden_hollow_cylinder");
    assert_eq!(s.analysis.mode, Mode::Transient);
    assert_eq!((s.geometry.ri, s.geometry.ro), (1.0, 2.0));
    assert_eq!(
        (
            s.mesh.n_r,
            s.mesh.n_theta,
            s.mesh.order,
            s.mesh.grading_theta
        ),
        (3, 64, 2, 0.0)
    );
    assert_eq!(
        s.material.params(),
        Some(MaterialParams::MooneyRivlin {
            c1: 80.0,
            c2: 20.0,
            kappa: 20000.0
        })
    );
    // Nearly incompressible: κ / G = 100.
    let g = s.material.shear_modulus().unwrap_or(0.0);
    assert_eq!(s.material.bulk_modulus().unwrap_or(0.0) / g, 100.0);
    // Critical spin c_R / Ro ≈ 395 rpm, the paper's top speed.
    let c_r = 0.955 * s.shear_wave_speed().unwrap_or(0.0);
    let rpm = c_r / s.geometry.ro * 60.0 / (2.0 * std::f64::consts::PI);
    assert!((rpm - 395.0).abs() < 10.0, "critical spin {rpm} rpm");
    assert_eq!(
        s.motion,
        Motion {
            omega: 10.0,
            ramp: 0.05,
            ..Motion::default()
        }
    );
    let road = s.road.clone().unwrap_or_else(|| panic!("no [road]"));
    assert_eq!((road.disp, road.load, road.ramp), (Some(0.1), None, 0.05));
    assert_eq!(road.v0_ramp, None);
    assert_eq!(road.resolved_v0_ramp(&s.motion), 0.05);
    // Free-rolling-like road speed: v0 = ω (Ro − DISP/3).
    let r_eff = s.geometry.ro - 0.1 / 3.0;
    assert!(
        (road.v0 - s.motion.omega * r_eff).abs() < 1e-5,
        "{}",
        road.v0
    );
    assert_eq!(
        s.contact,
        Some(ContactSpec {
            c_n: 2.0e4,
            m_n: 1.0,
            b_n: 1000.0,
            l_n: 1.0,
            quadrature: ContactQuadrature::Lobatto,
            points: 4,
            clamp: ClampKind::Hard,
            clamp_width: None
        })
    );
    assert_eq!(
        s.friction.params(),
        Some(FrictionParams::CoulombTanh { mu: 0.3, eps: 0.5 })
    );
    let t = s.time.clone().unwrap_or_else(|| panic!("no [time]"));
    assert_eq!(
        t,
        TimeSpec {
            integrator: IntegratorName::GeneralizedAlpha,
            rho_inf: 0.8,
            dt: 2.0e-4,
            dt_min: None,
            dt_max: None,
            t_end: 2.0,
            adaptive: true,
            error_tol: 1e-3,
            steady_tol: 1e-3,
            stop_at_steady: true,
            mass: MassKind::Consistent,
            max_steps: 200_000,
            strain_rate_damping: 1.0,
        }
    );
    assert!((t.resolved_dt_min() - 2.0e-8).abs() < 1e-20);
    assert!((t.resolved_dt_max() - 2.0e-3).abs() < 1e-15);
    assert_eq!(t.effective_mass(), MassKind::Consistent);
    assert!(!t.is_explicit());
    assert_eq!((s.solver.load_steps, s.solver.tolerance), (1, 1e-8));
    assert_eq!(s.stick_slip, None);
    assert!(s.validate().is_ok());

    // The frictionless scene is the same scene without friction.
    let f = load(ROLLING_FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(f.scene.name, "rolling_frictionless");
    assert_eq!(f.friction, FrictionSpec::default());
    assert!(!f.friction.is_active());
    assert_eq!(
        (&f.geometry, &f.mesh, &f.material, &f.analysis),
        (&s.geometry, &s.mesh, &s.material, &s.analysis)
    );
    assert_eq!(
        (&f.motion, &f.road, &f.contact),
        (&s.motion, &s.road, &s.contact)
    );
    assert_eq!(
        (&f.time, &f.solver, &f.output),
        (&s.time, &s.solver, &s.output)
    );
    assert!(f.validate().is_ok());
}

#[test]
fn torque_control_scenes_parse() {
    let f = load(FREE_ROLLING).unwrap_or_else(|e| panic!("{e}"));
    let b = load(BRAKING).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        (f.scene.name.as_str(), b.scene.name.as_str()),
        ("free_rolling", "braking")
    );
    for s in [&f, &b] {
        assert_eq!(s.analysis.mode, Mode::Transient);
        assert_eq!(s.motion.control, Control::Torque);
        assert_eq!(s.motion.hub_inertia, 0.5);
        assert_eq!(s.motion.omega, 2.0);
        assert_eq!((s.mesh.n_r, s.mesh.n_theta), (2, 32));
        let road = s.road.as_ref().unwrap_or_else(|| panic!("no road"));
        assert_eq!((road.disp, road.v0_ramp), (Some(0.1), Some(0.0)));
        assert!(s.friction.is_active());
        assert!(s.validate().is_ok());
    }
    assert_eq!((f.motion.torque, f.motion.ramp), (0.0, 0.0));
    assert_eq!((b.motion.torque, b.motion.ramp), (-10.0, 0.2));
    // The two scenes differ only in the torque, its ramp and the naming.
    assert_eq!(
        (
            &f.geometry,
            &f.mesh,
            &f.material,
            &f.road,
            &f.contact,
            &f.friction,
            &f.time
        ),
        (
            &b.geometry,
            &b.mesh,
            &b.material,
            &b.road,
            &b.contact,
            &b.friction,
            &b.time
        )
    );
    // Defaults: speed control, no inertia, no torque.
    let s = load(ODEN).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        (s.motion.control, s.motion.hub_inertia, s.motion.torque),
        (Control::Speed, 0.0, 0.0)
    );
}

#[test]
fn torque_control_keys_are_validated() {
    // Torque control without an inertia (or a negative one): reported on the key.
    let e = errors_with(FREE_ROLLING, &["motion.hub_inertia=0"]);
    assert_only(&e, "motion.hub_inertia", None);
    let e = errors_with(FREE_ROLLING, &["motion.hub_inertia=-1"]);
    assert_only(&e, "motion.hub_inertia", None);
    // Torque and inertia are only for torque control; lines of the file.
    let text = BRAKING.replace("control = \"torque\"", "control = \"speed\"");
    let e = errors(&text);
    assert_eq!(e.0.len(), 2, "{e}");
    assert_eq!(
        e.find("motion.torque").and_then(|x| x.line),
        Some(line_of(&text, "torque = -10.0"))
    );
    assert_eq!(
        e.find("motion.hub_inertia").and_then(|x| x.line),
        Some(line_of(&text, "hub_inertia ="))
    );
    // Only generalized-α, only transient.
    let e = errors_with(
        FREE_ROLLING,
        &["time.integrator=central_difference", "time.mass=lumped"],
    );
    assert_only(
        &e,
        "motion.control",
        Some(line_of(FREE_ROLLING, "control = \"torque\"")),
    );
    assert!(e.0[0].message.contains("generalized_alpha"), "{e}");
    let e = errors_with(MINIMAL, &["motion.control=torque", "motion.hub_inertia=1"]);
    assert!(e.has_key("motion.control"), "{e}");
    // Unknown keyword, wrong type, non-finite torque.
    let e = errors_with(FREE_ROLLING, &["motion.control=brake"]);
    assert_only(&e, "motion.control", None);
    assert!(e.0[0].message.contains("speed"), "{e}");
    let text = FREE_ROLLING.replace("torque = 0.0 ", "torque = \"none\" ");
    let e = errors(&text);
    assert_only(
        &e,
        "motion.torque",
        Some(line_of(&text, "torque = \"none\"")),
    );
    let e = errors_with(BRAKING, &["motion.torque=nan"]);
    assert_only(&e, "motion.torque", None);
}

#[test]
fn time_defaults_are_filled() {
    let s = load(&minimal_transient()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.analysis.mode, Mode::Transient);
    // A spinning cylinder in time: no road, no contact.
    assert_eq!((&s.road, &s.contact), (&None, &None));
    assert_eq!(s.motion.ramp, 0.0);
    let t = s.time.unwrap_or_else(|| panic!("no [time]"));
    assert_eq!(t, TimeSpec::new(1e-3, 0.5));
    assert_eq!(t.integrator, IntegratorName::GeneralizedAlpha);
    assert_eq!(t.rho_inf, DEFAULT_RHO_INF);
    assert_eq!(t.rho_inf, 0.8);
    assert_eq!((t.dt_min, t.dt_max), (None, None));
    assert_eq!(t.resolved_dt_min(), 1e-3 * DT_MIN_FACTOR);
    assert_eq!(t.resolved_dt_max(), 1e-3 * DT_MAX_FACTOR);
    assert!(t.adaptive && t.stop_at_steady);
    assert_eq!((t.error_tol, t.steady_tol), (1e-4, 1e-4));
    assert_eq!(t.mass, MassKind::Consistent);
    assert_eq!(t.max_steps, 200_000);
    assert_eq!(t.max_steps, DEFAULT_MAX_STEPS);

    // Road defaults in transient: no ramps, v0_ramp follows motion.ramp.
    let text = remove_section(&remove_section(ODEN, "[road]"), "[time]")
        + "[road]\ndisp = 0.05\nv0 = 3.0\n[time]\ndt = 1e-3\nt_end = 1\n";
    let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
    let road = s.road.unwrap_or_else(|| panic!("no [road]"));
    assert_eq!((road.ramp, road.v0_ramp), (0.0, None));
    assert_eq!(road.resolved_v0_ramp(&s.motion), s.motion.ramp);
    assert_eq!(road.resolved_v0_ramp(&s.motion), 0.05);
}

#[test]
fn time_ranges_rejected_with_key_and_line() {
    let cases: [(&str, &str, &str, &str); 14] = [
        ("dt =", "dt = 0.0", "time.dt", "> 0"),
        ("dt =", "dt = -2e-4", "time.dt", "> 0"),
        ("t_end", "t_end = 0", "time.t_end", "> 0"),
        ("t_end", "t_end = -1.0", "time.t_end", "> 0"),
        ("dt =", "dt = 3.0", "time.dt", "must not exceed t_end"),
        ("rho_inf", "rho_inf = -0.1", "time.rho_inf", "[0, 1]"),
        ("rho_inf", "rho_inf = 1.01", "time.rho_inf", "[0, 1]"),
        (
            "dt =",
            "dt = 2e-4\ndt_min = 3e-4",
            "time.dt_min",
            "must not exceed dt",
        ),
        ("dt =", "dt = 2e-4\ndt_min = 0", "time.dt_min", "> 0"),
        ("dt =", "dt = 2e-4\ndt_max = 1e-4", "time.dt_max", ">= dt"),
        ("error_tol", "error_tol = 0.0", "time.error_tol", "> 0"),
        ("steady_tol", "steady_tol = 0", "time.steady_tol", "> 0"),
        ("steady_tol", "steady_tol = -1e-3", "time.steady_tol", "> 0"),
        ("max_steps", "max_steps = 0", "time.max_steps", ">= 1"),
    ];
    for (prefix, new, key, what) in cases {
        let text = replace_line(ODEN, prefix, new);
        let e = errors(&text);
        let field = key.trim_start_matches("time.");
        assert_only(&e, key, Some(line_of(&text, &format!("{field} ="))));
        assert!(e.0[0].message.contains(what), "{new}: {e}");
        assert!(
            e.0[0].to_string().starts_with(&format!(
                "test.toml:{}: key `{key}`",
                line_of(&text, &format!("{field} ="))
            )),
            "{e}"
        );
    }
    // Boundary values are accepted.
    for ok in [
        ("rho_inf", "rho_inf = 0"),
        ("rho_inf", "rho_inf = 1.0"),
        ("dt =", "dt = 2e-4\ndt_min = 2e-4\ndt_max = 2e-4"),
        ("dt =", "dt = 2.0"),
    ] {
        let text = replace_line(ODEN, ok.0, ok.1);
        assert!(load(&text).is_ok(), "{}", ok.1);
    }
    // Several problems of [time] at once, each on its own line.
    let text = replace_line(ODEN, "rho_inf", "rho_inf = 2");
    let text = replace_line(&text, "t_end", "t_end = 0");
    let text = replace_line(&text, "error_tol", "error_tol = -1");
    let e = errors(&text);
    assert_eq!(e.0.len(), 3, "{e}");
    for key in ["rho_inf", "t_end", "error_tol"] {
        let err = e
            .find(&format!("time.{key}"))
            .unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, key)));
    }
    // Missing required keys: at the [time] header.
    let text = ODEN
        .lines()
        .filter(|l| !l.starts_with("dt =") && !l.starts_with("t_end"))
        .collect::<Vec<_>>()
        .join("\n");
    let e = errors(&text);
    assert_eq!(e.0.len(), 2, "{e}");
    for key in ["time.dt", "time.t_end"] {
        let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
        assert_eq!(err.line, Some(line_of(&text, "[time]")));
        assert!(err.message.contains("required key is missing"), "{err}");
    }
    // Wrong types and unknown values.
    let text = replace_line(ODEN, "integrator", "integrator = \"newmark\"");
    let e = errors(&text);
    assert_only(&e, "time.integrator", Some(line_of(&text, "integrator")));
    assert!(e.0[0].message.contains("\"generalized_alpha\""), "{e}");
    let text = replace_line(ODEN, "adaptive", "adaptive = 1");
    let e = errors(&text);
    assert_only(&e, "time.adaptive", Some(line_of(&text, "adaptive")));
    let text = replace_line(ODEN, "max_steps", "max_steps = 1.5");
    let e = errors(&text);
    assert_only(&e, "time.max_steps", Some(line_of(&text, "max_steps")));
    let text = replace_line(ODEN, "dt =", "dt = 2e-4\ndt_step = 1");
    let e = errors(&text);
    assert_only(&e, "time.dt_step", Some(line_of(&text, "dt_step")));
    assert!(e.0[0].message.contains("steady_tol"), "{e}");
}

#[test]
fn central_difference_uses_lumped_mass() {
    // Explicit consistent mass with central difference: named at its line.
    let text = replace_line(ODEN, "integrator", "integrator = \"central_difference\"");
    let e = errors(&text);
    assert_only(&e, "time.mass", Some(line_of(&text, "mass =")));
    assert!(e.0[0].message.contains("lumped"), "{e}");
    // Omitted: resolved to lumped (and written so by to_toml_string).
    let text = text
        .lines()
        .filter(|l| !l.starts_with("mass ="))
        .collect::<Vec<_>>()
        .join("\n");
    let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
    let t = s.time.clone().unwrap_or_else(|| panic!("no [time]"));
    assert_eq!(t.integrator, IntegratorName::CentralDifference);
    assert_eq!(
        (t.mass, t.effective_mass()),
        (MassKind::Lumped, MassKind::Lumped)
    );
    assert!(t.is_explicit());
    let out = s.to_toml_string();
    assert!(out.contains("mass = \"lumped\""), "{out}");
    assert_eq!(load(&out).unwrap_or_else(|e| panic!("{e}\n{out}")), s);
    // Explicit lumped is fine; an override back to consistent is reported as (--set).
    assert!(load(&replace_line(
        &text,
        "integrator",
        "integrator = \"central_difference\"\nmass = \"lumped\""
    ))
    .is_ok());
    let e = errors_with(&text, &["time.mass=consistent"]);
    assert_only(&e, "time.mass", None);
    assert!(e.0[0].is_override(), "{e}");
    // An unknown mass is reported once, not also as "consistent".
    let e = errors_with(&text, &["time.mass=diagonal"]);
    assert_only(&e, "time.mass", None);
    assert!(e.0[0].message.contains("\"lumped\""), "{e}");
    // Other integrators keep the consistent default.
    let s = load_with(ODEN, &["time.integrator=bdf"]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.time.map(|t| t.mass), Some(MassKind::Consistent));
    let s = load_with(ODEN, &["time.integrator=sdirk", "time.mass=lumped"])
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        s.time.map(|t| (t.integrator, t.mass)),
        Some((IntegratorName::Sdirk, MassKind::Lumped))
    );
}

#[test]
fn time_section_only_in_transient() {
    let time = "\n[time]\ndt = 1e-3\nt_end = 1.0\n";
    for base in [MINIMAL, FRICTIONLESS, STICK_SLIP] {
        let text = format!("{base}{time}");
        let e = errors(&text);
        assert_only(&e, "time", Some(line_of(&text, "[time]")));
        assert!(e.0[0].message.contains("not used"), "{e}");
        assert!(e.0[0].message.contains("\"transient\""), "{e}");
    }
    // Created by an override: (--set).
    let e = errors_with(MINIMAL, &["time.dt=1e-3", "time.t_end=1"]);
    assert_only(&e, "time", None);
    assert!(e.0[0].is_override(), "{e}");
    // Required in transient: at the line of `mode`.
    let text = remove_section(ODEN, "[time]");
    let e = errors(&text);
    assert_only(&e, "time", Some(line_of(&text, "mode =")));
    assert!(e.0[0].message.contains("missing"), "{e}");
    assert!(e.0[0].message.contains("dt, t_end"), "{e}");
    // [stick_slip] in a transient scene.
    let text = format!(
        "{ODEN}\n[stick_slip]\nmass = 1\nstiffness = 1\nnormal_force = 1\nbelt_speed = 1\n\
             t_end = 1\n"
    );
    let e = errors(&text);
    assert_only(&e, "stick_slip", Some(line_of(&text, "[stick_slip]")));
}

#[test]
fn transient_requires_omega() {
    let text = ODEN
        .lines()
        .filter(|l| !l.starts_with("omega"))
        .collect::<Vec<_>>()
        .join("\n");
    let e = errors(&text);
    assert_only(&e, "motion.omega", Some(line_of(&text, "[motion]")));
    assert!(e.0[0].message.contains("\"transient\""), "{e}");
    // No [motion] at all: at the line of `mode`.
    let text = remove_section(&minimal_transient(), "[motion]");
    let e = errors(&text);
    assert_only(&e, "motion.omega", Some(line_of(&text, "mode =")));
    let e = errors(&remove_section(MINIMAL, "[motion]"));
    assert_only(&e, "motion.omega", Some(line_of(MINIMAL, "mode =")));
    // omega = 0 is allowed (a road moving under a non-spinning cylinder).
    assert!(load(&replace_line(ODEN, "omega", "omega = 0")).is_ok());
    let e = errors(&replace_line(ODEN, "omega", "omega = -10"));
    assert!(e.has_key("motion.omega"), "{e}");
}

#[test]
fn transient_allows_road_speed_damping_and_spin() {
    // Static still rejects them (see static_rejects_spin_road_speed_and_damping); in
    // transient they are the point.
    let s = load_with(
        ODEN,
        &[
            "road.v0=-5",
            "contact.b_n=0",
            "motion.omega=40",
            "contact.l_n=1",
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.road.as_ref().map(|r| r.v0), Some(-5.0));
    assert_eq!(s.motion.omega, 40.0);
    assert_eq!(s.contact.as_ref().map(|c| (c.b_n, c.l_n)), Some((0.0, 1.0)));
    // Load control in transient.
    let s = load_with(
        &ODEN.replace("disp = 0.1", "load = 300.0"),
        &["road.ramp=0.1"],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let road = s.road.unwrap_or_else(|| panic!("no [road]"));
    assert_eq!((road.disp, road.load, road.ramp), (None, Some(300.0), 0.1));
}

#[test]
fn ramps_only_in_transient() {
    // motion.ramp in spinning (file) and static (override).
    let text = replace_line(MINIMAL, "omega", "omega = 20.0\nramp = 0.1");
    let e = errors(&text);
    assert_only(&e, "motion.ramp", Some(line_of(&text, "ramp")));
    assert!(e.0[0].message.contains("\"spinning\""), "{e}");
    let e = errors_with(FRICTIONLESS, &["motion.ramp=0.1"]);
    assert_only(&e, "motion.ramp", None);
    assert!(e.0[0].is_override(), "{e}");
    let e = errors_with(STICK_SLIP, &["motion.ramp=1"]);
    assert_only(&e, "motion.ramp", None);
    // road.ramp and road.v0_ramp in static.
    let text = replace_line(FRICTIONLESS, "disp", "disp = 0.1\nramp = 0.05");
    let e = errors(&text);
    assert_only(&e, "road.ramp", Some(line_of(&text, "ramp")));
    assert!(e.0[0].message.contains("static"), "{e}");
    let text = replace_line(FRICTIONLESS, "v0", "v0 = 0.0\nv0_ramp = 0.05");
    let e = errors(&text);
    assert_only(&e, "road.v0_ramp", Some(line_of(&text, "v0_ramp")));
    // Zero ramps are fine anywhere.
    let text = replace_line(FRICTIONLESS, "v0", "v0 = 0.0\nv0_ramp = 0\nramp = 0.0");
    assert!(load(&text).is_ok());
    assert!(load(&replace_line(MINIMAL, "omega", "omega = 20.0\nramp = 0")).is_ok());
    // Negative or non-finite ramps in transient.
    let text = replace_line(ODEN, "ramp = 0.05", "ramp = -0.05");
    let e = errors(&text);
    assert_only(&e, "motion.ramp", Some(line_of(&text, "ramp = -0.05")));
    assert!(e.0[0].message.contains(">= 0"), "{e}");
    let e = errors_with(ODEN, &["road.ramp=-1", "road.v0_ramp=-2"]);
    assert_eq!(e.0.len(), 2, "{e}");
    assert!(e.has_key("road.ramp") && e.has_key("road.v0_ramp"), "{e}");
    assert!(e.0.iter().all(|x| x.is_override()), "{e}");
    let e = errors_with(ODEN, &["motion.ramp=inf"]);
    assert_only(&e, "motion.ramp", None);
    // v0_ramp given: it wins over motion.ramp.
    let s = load_with(ODEN, &["road.v0_ramp=0.2"]).unwrap_or_else(|e| panic!("{e}"));
    let road = s.road.clone().unwrap_or_else(|| panic!("no [road]"));
    assert_eq!(road.v0_ramp, Some(0.2));
    assert_eq!(road.resolved_v0_ramp(&s.motion), 0.2);
}

#[test]
fn transient_road_contact_and_friction_rules() {
    // Neither [road] nor [contact]: a spinning cylinder in time (frictionless).
    let text = remove_section(&remove_section(ROLLING_FRICTIONLESS, "[road]"), "[contact]");
    let s = load(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((s.road, s.contact), (None, None));
    // ... but friction needs contact.
    let text = remove_section(&remove_section(ODEN, "[road]"), "[contact]");
    let e = errors(&text);
    assert_only(&e, "friction.law", Some(line_of(&text, "law")));
    assert!(e.0[0].message.contains("\"transient\""), "{e}");
    assert!(e.0[0].message.contains("\"coulomb_tanh\""), "{e}");
    // One without the other: named, at the header of the one given.
    let text = remove_section(ODEN, "[contact]");
    let e = errors(&text);
    assert_only(&e, "contact", Some(line_of(&text, "[road]")));
    assert!(e.0[0].message.contains("both"), "{e}");
    let text = remove_section(ODEN, "[road]");
    let e = errors(&text);
    assert_only(&e, "road", Some(line_of(&text, "[contact]")));
    assert!(e.0[0].message.contains("both"), "{e}");
    // Every friction law is allowed with contact.
    let s = load_with(
        ROLLING_FRICTIONLESS,
        &[
            "friction.law=oden_martins",
            "friction.c_t=6e3",
            "friction.m_t=1",
            "friction.eps=0.5",
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(s.friction.is_active());
}

#[test]
fn graded_mesh_rejected_when_stopping_at_steady() {
    let text = replace_line(ODEN, "grading_theta", "grading_theta = 0.5");
    let e = errors(&text);
    assert_only(
        &e,
        "mesh.grading_theta",
        Some(line_of(&text, "grading_theta")),
    );
    assert!(e.0[0].message.contains("uniform in θ"), "{e}");
    // Without stopping at the steady state a graded mesh is allowed.
    let text = replace_line(&text, "stop_at_steady", "stop_at_steady = false");
    assert!(load(&text).is_ok());
    // An out-of-range grading is reported once.
    let e = errors(&replace_line(ODEN, "grading_theta", "grading_theta = 1.0"));
    assert_eq!(e.0.len(), 1, "{e}");
    // Static scenes keep their graded meshes.
    assert!(load(FRICTIONLESS).is_ok());
}

#[test]
fn overrides_of_time_keys() {
    let s = load_with(ODEN, &["time.dt=1e-4"]).unwrap_or_else(|e| panic!("{e}"));
    let t = s.time.clone().unwrap_or_else(|| panic!("no [time]"));
    assert_eq!(t.dt, 1e-4);
    assert!((t.resolved_dt_min() - 1e-8).abs() < 1e-20);
    assert!((t.resolved_dt_max() - 1e-3).abs() < 1e-15);
    let s = load_with(
        ODEN,
        &[
            "time.integrator=central_difference",
            "time.mass=lumped",
            "time.adaptive=false",
            "time.stop_at_steady=false",
            "time.t_end=0.5",
            "time.rho_inf=1",
            "time.dt_min=1e-6",
            "time.dt_max=1e-3",
            "time.error_tol=1e-5",
            "time.steady_tol=1e-5",
            "time.max_steps=10",
            "motion.ramp=0.1",
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let t = s.time.clone().unwrap_or_else(|| panic!("no [time]"));
    assert_eq!(
        t,
        TimeSpec {
            integrator: IntegratorName::CentralDifference,
            rho_inf: 1.0,
            dt: 2e-4,
            dt_min: Some(1e-6),
            dt_max: Some(1e-3),
            t_end: 0.5,
            adaptive: false,
            error_tol: 1e-5,
            steady_tol: 1e-5,
            stop_at_steady: false,
            mass: MassKind::Lumped,
            max_steps: 10,
            strain_rate_damping: 1.0,
        }
    );
    // road.v0_ramp follows the overridden motion.ramp.
    assert_eq!(
        s.road.as_ref().map(|r| r.resolved_v0_ramp(&s.motion)),
        Some(0.1)
    );
    // Bad override values: (--set) and the key.
    let e = errors_with(ODEN, &["time.dt=-1e-4"]);
    assert_only(&e, "time.dt", None);
    assert!(e.0[0].is_override());
    assert!(
        e.0[0]
            .to_string()
            .starts_with("test.toml:(--set): key `time.dt`"),
        "{e}"
    );
    let e = errors_with(ODEN, &["time.dt=5"]);
    assert_only(&e, "time.dt", None);
    assert!(e.0[0].message.contains("t_end"), "{e}");
    // dt overridden below an explicit dt_min in the file: dt_min keeps its line.
    let text = replace_line(ODEN, "dt =", "dt = 2e-4\ndt_min = 1e-5");
    let e = errors_with(&text, &["time.dt=1e-6"]);
    assert_only(&e, "time.dt_min", Some(line_of(&text, "dt_min")));
    let e = errors_with(ODEN, &["time.integrator=euler"]);
    assert_only(&e, "time.integrator", None);
    assert!(e.0[0].message.contains("\"sdirk\""), "{e}");
    // Switching a spinning scene to transient by override.
    let s = load_with(
        MINIMAL,
        &["analysis.mode=transient", "time.dt=1e-3", "time.t_end=1"],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.time.map(|t| (t.dt, t.t_end)), Some((1e-3, 1.0)));
    let e = errors_with(MINIMAL, &["analysis.mode=transient"]);
    assert_only(&e, "time", None);
    assert!(e.0[0].is_override(), "{e}");
}

#[test]
fn round_trip_of_transient_keys() {
    let cases: [(&str, &[&str]); 3] = [
        (
            ODEN,
            &[
                "time.dt_min=1e-7",
                "time.dt_max=1e-3",
                "road.v0_ramp=0.2",
                "time.integrator=bdf",
            ],
        ),
        (
            ROLLING_FRICTIONLESS,
            &["time.integrator=central_difference", "time.mass=lumped"],
        ),
        (
            &ODEN.replace("disp = 0.1", "load = 300.0"),
            &["time.rho_inf=0"],
        ),
    ];
    for (text, ov) in cases {
        let s = load_with(text, ov).unwrap_or_else(|e| panic!("{e}"));
        let out = s.to_toml_string();
        let back = load(&out).unwrap_or_else(|e| panic!("{e}\n{out}"));
        assert_eq!(back, s, "{out}");
        let direct: Scene = toml::from_str(&out).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(direct, s);
        assert!(out.contains("[time]") && out.contains("ramp = "), "{out}");
    }
    let s = load(&minimal_transient()).unwrap_or_else(|e| panic!("{e}"));
    let out = s.to_toml_string();
    assert!(
        out.contains("[time]\nintegrator = \"generalized_alpha\""),
        "{out}"
    );
    assert!(!out.contains("dt_min") && !out.contains("[road]"), "{out}");
    assert_eq!(load(&out).unwrap_or_else(|e| panic!("{e}\n{out}")), s);
    // Scenes of the other modes write no [time].
    let out = load(FRICTIONLESS)
        .unwrap_or_else(|e| panic!("{e}"))
        .to_toml_string();
    assert!(!out.contains("[time]"), "{out}");
}

#[test]
fn validate_checks_transient_scenes_built_in_code() {
    let mut s = load(ODEN).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.validate().is_ok());
    if let Some(t) = s.time.as_mut() {
        t.dt = -1.0;
        t.integrator = IntegratorName::CentralDifference;
        t.mass = MassKind::Consistent;
    }
    s.motion.ramp = -1.0;
    let e = s.validate().err().unwrap_or_else(|| panic!("accepted"));
    assert_eq!(e.0.len(), 3, "{e}");
    for key in ["time.dt", "time.mass", "motion.ramp"] {
        let err = e.find(key).unwrap_or_else(|| panic!("{e}"));
        assert_eq!((err.line, err.source_name.as_str()), (None, "<scene>"));
    }
    s.time = None;
    s.motion.ramp = 0.0;
    let e = s.validate().err().unwrap_or_else(|| panic!("accepted"));
    assert!(e.has_key("time"), "{e}");
    // [time] in a static scene built in code.
    let mut st = load(FRICTIONLESS).unwrap_or_else(|e| panic!("{e}"));
    st.time = Some(TimeSpec::new(1e-3, 1.0));
    let e = st.validate().err().unwrap_or_else(|| panic!("accepted"));
    assert!(e.has_key("time"), "{e}");
}

#[test]
fn smoothstep_ramps() {
    assert_eq!((smoothstep(-1.0), smoothstep(0.0)), (0.0, 0.0));
    assert_eq!((smoothstep(1.0), smoothstep(2.0)), (1.0, 1.0));
    assert!((smoothstep(0.5) - 0.5).abs() < 1e-15);
    // Symmetric, monotone, C²: derivative and integral consistent with S.
    let h = 1e-6;
    for i in 1..100 {
        let x = i as f64 / 100.0;
        assert!((smoothstep(x) + smoothstep(1.0 - x) - 1.0).abs() < 1e-14);
        assert!(smoothstep(x) >= smoothstep(x - 0.01));
        let d = (smoothstep(x + h) - smoothstep(x - h)) / (2.0 * h);
        assert!((d - smoothstep_derivative(x)).abs() < 1e-6, "{x}");
        let q = (smoothstep_integral(x + h) - smoothstep_integral(x - h)) / (2.0 * h);
        assert!((q - smoothstep(x)).abs() < 1e-6, "{x}");
    }
    assert_eq!(smoothstep_derivative(0.0), 0.0);
    assert_eq!(smoothstep_derivative(1.0), 0.0);
    assert!((smoothstep_integral(1.0) - 0.5).abs() < 1e-15);
    assert!((smoothstep_integral(3.0) - 2.5).abs() < 1e-15);

    let m = Motion {
        omega: 10.0,
        ramp: 0.05,
        ..Motion::default()
    };
    assert_eq!((m.omega_at(-1.0), m.omega_at(0.0)), (0.0, 0.0));
    assert!((m.omega_at(0.025) - 5.0).abs() < 1e-12);
    assert_eq!(m.omega_at(0.05), 10.0);
    assert_eq!(m.omega_at(1.0), 10.0);
    assert!((m.angle_at(1.0) - 10.0 * (1.0 - 0.025)).abs() < 1e-12);
    assert!((m.angle_at(0.05) - 10.0 * 0.025).abs() < 1e-12);
    assert_eq!(m.angle_at(-1.0), 0.0);
    assert!((m.omega_dot_at(0.025) - 10.0 * 1.875 / 0.05).abs() < 1e-9);
    assert_eq!(m.omega_dot_at(0.06), 0.0);
    // A zero ramp: full speed at once.
    let step = Motion {
        omega: 10.0,
        ramp: 0.0,
        ..Motion::default()
    };
    assert_eq!((step.omega_at(0.0), step.omega_at(0.3)), (10.0, 10.0));
    assert!((step.angle_at(0.3) - 3.0).abs() < 1e-12);
    assert_eq!(step.omega_dot_at(0.0), 0.0);

    let road = RoadSpec {
        disp: Some(0.1),
        load: None,
        v0: 20.0,
        ramp: 0.1,
        v0_ramp: None,
    };
    assert!((road.ramp_factor(0.05) - 0.5).abs() < 1e-12);
    assert_eq!(road.ramp_factor(0.2), 1.0);
    assert!((road.ramp_factor_rate(0.05) - 1.875 / 0.1).abs() < 1e-9);
    assert!((road.v0_at(0.025, &m) - 10.0).abs() < 1e-12);
    assert_eq!(road.v0_at(0.05, &m), 20.0);
    let late = RoadSpec {
        v0_ramp: Some(0.5),
        ..road
    };
    assert!((late.v0_at(0.25, &m) - 10.0).abs() < 1e-12);
}

#[test]
fn viscoelastic_subtable_is_parsed_and_checked() {
    let base = r#"
[scene]
name = "v"
[geometry]
ri = 1.0
ro = 2.0
[material]
model = "neo_hookean"
mu = 200.0
lambda = 1800.0
rho = 0.027
[material.viscoelastic]
model = "convolution"
gamma = 200.0
prony = [[0.7, 0.01], [0.3, 1]]
[analysis]
mode = "transient"
[motion]
omega = 10.0
[time]
dt = 1e-3
t_end = 0.1
"#;
    let s = Scene::from_toml_str(base, "v.toml", &[]).unwrap_or_else(|e| panic!("{e}"));
    let ve = s.material.viscoelastic.clone().expect("parsed");
    assert_eq!(ve.prony, vec![[0.7, 0.01], [0.3, 1.0]]);
    let law = ve.build().expect("valid");
    assert_eq!(law.model, crate::material::ViscoModel::Convolution);
    assert_eq!(law.prony(), &[(0.7, 0.01), (0.3, 1.0)]);
    // Every problem at once, each with its key and line.
    let bad = base
        .replace("model = \"convolution\"", "model = \"maxwell\"\ncolour = 1")
        .replace("gamma = 200.0", "gamma = \"big\"")
        .replace(
            "prony = [[0.7, 0.01], [0.3, 1]]",
            "prony = [[0.7], [0.3, 1]]",
        );
    let e = Scene::from_toml_str(&bad, "v.toml", &[]).expect_err("invalid");
    for key in [
        "material.viscoelastic.model",
        "material.viscoelastic.colour",
        "material.viscoelastic.gamma",
        "material.viscoelastic.prony",
    ] {
        assert!(e.has_key(key), "{key} not reported: {e}");
    }
    let text = e.to_string();
    assert!(
        text.contains("maxwell") && text.contains("\"multiplicative\""),
        "{text}"
    );
    // Values checked by the law: a non-positive relaxation time, a negative gamma.
    let bad = base.replace("[0.3, 1]]", "[0.3, 0.0]]");
    let e = Scene::from_toml_str(&bad, "v.toml", &[]).expect_err("tau = 0");
    let err = e
        .find("material.viscoelastic.prony")
        .unwrap_or_else(|| panic!("{e}"));
    assert!(err.message.contains("tau > 0"), "{}", err.message);
    assert_eq!(err.line, Some(15));
    let bad = base.replace("gamma = 200.0", "gamma = -1.0");
    let e = Scene::from_toml_str(&bad, "v.toml", &[]).expect_err("gamma < 0");
    assert!(e.has_key("material.viscoelastic.gamma"), "{e}");
    // Missing keys.
    let bad = base.replace("gamma = 200.0\n", "");
    let e = Scene::from_toml_str(&bad, "v.toml", &[]).expect_err("missing");
    assert!(e.has_key("material.viscoelastic.gamma"), "{e}");
}

#[test]
fn annotated_listing_round_trips_and_names_units() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).expect("scenarios/") {
        let path = entry.expect("entry").path();
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") || text.contains("[sweep]") {
            continue;
        }
        let s = Scene::from_path(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
        let out = s.to_annotated_toml_string();
        // (A scene with `mesh.file` does not parse back: the listing writes the generator's
        // keys too, which a file mesh refuses; the plain listing does the same.)
        if s.mesh.file.is_none() {
            let back = Scene::from_toml_str(&out, "annotated", &[])
                .unwrap_or_else(|e| panic!("{e}\n{out}"));
            assert_eq!(back, s, "{out}");
        }
        // Every one-line `key = value` carries its comment.
        for line in out.lines() {
            let t = line.trim();
            if t.contains(" = ") && !t.ends_with('[') && !t.starts_with('"') {
                assert!(
                    t.contains("  # "),
                    "{}: no annotation on `{t}`",
                    path.display()
                );
            }
        }
        n += 1;
    }
    assert!(n >= 20);
    let s = load(MINIMAL).unwrap_or_else(|e| panic!("{e}"));
    let out = s.to_annotated_toml_string();
    assert!(out.contains("ri = 1.0  # [L] inner (hub) radius"), "{out}");
    assert!(out.contains("rho = 0.027  # [F·T²/L⁴]"), "{out}");
}
