//! Unit tests of scene loading: parsing, defaults, overrides, every error with its key and line.

use super::*;
use crate::contact::laws::{CoulombLinear, CoulombTanh};
use crate::contact::Friction;

pub(super) const INCOMPRESSIBLE: &str =
    include_str!("../../../scenarios/spinning_incompressible.toml");
pub(super) const NEO_HOOKEAN: &str = include_str!("../../../scenarios/spinning_neo_hookean.toml");
pub(super) const MOONEY_RIVLIN: &str =
    include_str!("../../../scenarios/spinning_mooney_rivlin.toml");
pub(super) const FRICTIONLESS: &str =
    include_str!("../../../scenarios/indentation_frictionless.toml");
pub(super) const FRICTION: &str = include_str!("../../../scenarios/indentation_friction.toml");
pub(super) const LOAD_CONTROL: &str =
    include_str!("../../../scenarios/indentation_load_control.toml");
pub(super) const STICK_SLIP: &str = include_str!("../../../scenarios/stick_slip.toml");
pub(super) const ODEN: &str = include_str!("../../../scenarios/oden_hollow_cylinder.toml");
pub(super) const ROLLING_FRICTIONLESS: &str =
    include_str!("../../../scenarios/rolling_frictionless.toml");
pub(super) const FREE_ROLLING: &str = include_str!("../../../scenarios/free_rolling.toml");
pub(super) const STEADY_SWEEP: &str = include_str!("../../../scenarios/oden_steady_sweep.toml");
pub(super) const BRAKING: &str = include_str!("../../../scenarios/braking.toml");

pub(super) const MINIMAL: &str = r#"
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

pub(super) fn load(text: &str) -> Result<Scene, SceneErrors> {
    Scene::from_toml_str(text, "test.toml", &[])
}

pub(super) fn load_with(text: &str, overrides: &[&str]) -> Result<Scene, SceneErrors> {
    let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(text, "test.toml", &ov)
}

pub(super) fn errors(text: &str) -> SceneErrors {
    match load(text) {
        Ok(s) => panic!("expected errors, got {s:?}"),
        Err(e) => e,
    }
}

pub(super) fn errors_with(text: &str, overrides: &[&str]) -> SceneErrors {
    match load_with(text, overrides) {
        Ok(s) => panic!("expected errors, got {s:?}"),
        Err(e) => e,
    }
}

/// 1-based line of the first line of `text` that starts with `prefix` (after whitespace).
pub(super) fn line_of(text: &str, prefix: &str) -> usize {
    text.lines()
        .position(|l| l.trim_start().starts_with(prefix))
        .map(|i| i + 1)
        .unwrap_or_else(|| panic!("no line starts with {prefix:?}"))
}

pub(super) fn replace_line(text: &str, prefix: &str, new: &str) -> String {
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
    assert_eq!(s.material.get("kappa"), None);
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
    assert_eq!(s.material.get("kappa"), Some(2000.0));
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
fn serde_itself_rejects_unknown_fields() {
    let text = format!("{MINIMAL}\n[output]\nevery = 2\npng = true\n");
    let r: Result<Scene, _> = toml::from_str(&text);
    let e = r.err().map(|e| e.to_string()).unwrap_or_default();
    assert!(e.contains("png"), "{e}");
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

pub(super) fn full_road() -> RoadSpec {
    RoadSpec {
        disp: Some(0.1),
        load: Some(1.0),
        v0: 0.0,
        ramp: 0.0,
        v0_ramp: Some(0.0),
        slip_angle: 0.0,
        camber: 0.0,
    }
}

pub(super) fn full_contact() -> ContactSpec {
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

pub(super) fn full_friction() -> FrictionSpec {
    FrictionSpec::new(
        FrictionLawName::None,
        &[
            ("mu", 1.0),
            ("eps", 1.0),
            ("mu_s", 1.0),
            ("mu_k", 1.0),
            ("v_s", 1.0),
            ("c_t", 1.0),
            ("m_t", 1.0),
            ("k_t", 1.0),
        ],
    )
}

pub(super) fn full_stick_slip() -> StickSlipSpec {
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

pub(super) fn full_time() -> TimeSpec {
    TimeSpec {
        dt_min: Some(1e-6),
        dt_max: Some(1e-2),
        ..TimeSpec::new(1e-3, 1.0)
    }
}

/// Remove the section starting at the line `header` up to (not including) the next header.
pub(super) fn remove_section(text: &str, header: &str) -> String {
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
pub(super) fn assert_only(e: &SceneErrors, key: &str, line: Option<usize>) {
    assert_eq!(e.0.len(), 1, "{e}");
    assert_eq!(e.0[0].key, key, "{e}");
    assert_eq!(e.0[0].line, line, "{e}");
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
fn overrides_of_new_keys() {
    let s = load_with(FRICTION, &["friction.mu=0.5"]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        s.friction.params(),
        Some(Friction::CoulombTanh(CoulombTanh::new(0.5, 0.01)))
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
        Some(Friction::CoulombLinear(CoulombLinear::new(0.2, 1e-3)))
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
    assert_eq!(s.friction.get("mu_k"), Some(0.3));

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
fn validate_checks_new_sections_of_scenes_built_in_code() {
    let mut s = load(FRICTION).unwrap_or_else(|e| panic!("{e}"));
    assert!(s.validate().is_ok());
    s.friction.set("mu", -0.3);
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
pub(super) fn minimal_transient() -> String {
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
        Some(crate::material::MooneyRivlin::new(80.0, 20.0, 20000.0).into())
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
        Some(Friction::CoulombTanh(CoulombTanh::new(0.3, 0.5)))
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
