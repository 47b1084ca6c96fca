//! `[material]` / `[[material]]`: the hyperelastic model and its parameters (stresses in F/L²,
//! density in F·T²/L⁴), and the optional `[material.viscoelastic]` Prony overstress.
//!
//! The section is `model` (a [`MaterialModel`]), the density `rho` and the law's parameters.
//! Which keys a law has, what they mean, their units and bounds are declared by the law itself
//! next to its physics ([`crate::material::MaterialLawSpec`]); this file holds the section as
//! given (so that every problem can be reported with its key), the generic checks that walk
//! those declarations, the incompressibility formulation of the laws that need a pressure
//! field, and the resolution into the physics law [`Material`].

use super::issue::{issue, ordered_values, positive, quoted_list, Issue};
use crate::material::Material;
use crate::params::LawKind;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Hyperelastic model (`[material] model`): the keyword enum of the registered laws.
pub use crate::material::MaterialKind as MaterialModel;

/// `kappa = PERTURBED_KAPPA_FACTOR * (c1 + c2)` (in general: `× G/2`, G the small-strain shear
/// modulus) when the perturbed incompressible formulation is chosen without an explicit `kappa`.
pub const PERTURBED_KAPPA_FACTOR: f64 = 1.0e4;

/// The key of the bulk modulus of the perturbed incompressible formulation.
const PERTURBED_KAPPA: &str = "kappa";

/// One `[[material]]` entry: the material of a mesh region.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionMaterial {
    /// Name of a 2D physical group of the mesh file.
    pub region: String,
    pub material: MaterialSpec,
}

keyword_enum! {
    /// How the incompressibility constraint is imposed (`[material] formulation`).
    #[derive(Default)]
    Formulation, "formulation" {
        #[default]
        /// Exact saddle point (displacement + discontinuous P1 pressure, LU).
        Exact => "exact",
        /// Perturbed Lagrangian with bulk modulus `kappa`, pressure condensed per element.
        Perturbed => "perturbed",
    }
}

/// `[material]` as given: the model, the density, the parameter values by key, and for an
/// incompressible model its formulation. Which parameters are required depends on `model`;
/// after [`Scene::from_toml_str`](super::Scene::from_toml_str) the model-dependent defaults
/// are filled in (`formulation` for an incompressible model, `kappa` for the perturbed
/// formulation), and [`MaterialSpec::params`] gives the physics law.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSpec {
    pub model: MaterialModel,
    /// Density per unit reference volume.
    pub rho: f64,
    /// Parameter values by key: those of some registered law, and `kappa` of the perturbed
    /// formulation (a key of another model than `model` is reported by the checks).
    pub values: BTreeMap<String, f64>,
    /// Incompressibility formulation (incompressible models only).
    pub formulation: Option<Formulation>,
    /// `[material.viscoelastic]`: a viscoelastic overstress on the elastic law (any model).
    pub viscoelastic: Option<ViscoelasticSpec>,
}

/// `[material.viscoelastic]`: `S = ∂W/∂E + S_v` with the Prony kernel
/// `k(s) = Σ g_i exp(−s/τ_i)`; see [`crate::material::viscoelastic`] for both models.
/// Units: `gamma` is a stress (the scene's stress unit), `g` dimensionless, `tau` a time (the
/// scene's time unit). At small strain the overstress adds the shear relaxation modulus
/// `(gamma/2) k(t)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViscoelasticSpec {
    /// `"convolution"` (the linear convolution on the Green strain rate) or `"multiplicative"`
    /// (the thermodynamically consistent finite-strain model).
    pub model: String,
    /// Stress scale γ (stress units), >= 0.
    pub gamma: f64,
    /// Prony terms `[[g_i, tau_i], ...]` (g dimensionless >= 0, tau > 0 in time units), 1 to 8.
    pub prony: Vec<[f64; 2]>,
}

impl ViscoelasticSpec {
    /// The law, or the message explaining what is wrong.
    pub fn build(&self) -> Result<crate::material::Viscoelastic, String> {
        let model = crate::material::ViscoModel::from_name(&self.model).ok_or_else(|| {
            format!(
                "unknown model \"{}\"; expected one of {}",
                self.model,
                quoted_list(crate::material::ViscoModel::NAMES)
            )
        })?;
        let prony: Vec<(f64, f64)> = self.prony.iter().map(|p| (p[0], p[1])).collect();
        crate::material::Viscoelastic::new(model, self.gamma, &prony).map_err(|e| e.to_string())
    }
}

impl MaterialSpec {
    /// A section with `model`, `rho` and the given `(key, value)` pairs.
    pub fn new(model: MaterialModel, rho: f64, values: &[(&str, f64)]) -> Self {
        Self {
            model,
            rho,
            values: values.iter().map(|&(k, v)| (k.to_string(), v)).collect(),
            formulation: None,
            viscoelastic: None,
        }
    }

    /// The value given for `key`.
    pub fn get(&self, key: &str) -> Option<f64> {
        self.values.get(key).copied()
    }

    /// Give `key` the value `value`.
    pub fn set(&mut self, key: &str, value: f64) {
        self.values.insert(key.to_string(), value);
    }

    /// The physics law of `model` from the given values. `None` only if a parameter the model
    /// requires is missing, which cannot happen after validation.
    pub fn params(&self) -> Option<Material> {
        self.model.build_from(|k| self.get(k)).ok()
    }

    /// Small-strain shear modulus G of the law (`mu`, `2 (c1 + c2)`, ...).
    pub fn shear_modulus(&self) -> Option<f64> {
        Some(self.params()?.small_strain_shear_modulus())
    }

    /// Small-strain bulk modulus K; for an incompressible model the perturbed formulation's
    /// `kappa`, `None` for the exact formulation (K = ∞).
    pub fn bulk_modulus(&self) -> Option<f64> {
        if self.is_incompressible() {
            self.perturbed_kappa()
        } else {
            self.params()?.small_strain_bulk_modulus()
        }
    }

    /// Whether the model carries a pressure field (an incompressible law).
    pub fn is_incompressible(&self) -> bool {
        self.model.is_incompressible()
    }

    /// The resolved formulation: `Some` only for an incompressible model (default `exact`).
    pub fn resolved_formulation(&self) -> Option<Formulation> {
        self.is_incompressible()
            .then(|| self.formulation.unwrap_or_default())
    }

    /// The bulk modulus of the perturbed formulation (incompressible models with
    /// `formulation = "perturbed"`): the given `kappa`, or `1e4 · G/2`.
    pub fn perturbed_kappa(&self) -> Option<f64> {
        if self.resolved_formulation() != Some(Formulation::Perturbed) {
            return None;
        }
        match self.get(PERTURBED_KAPPA) {
            Some(k) => Some(k),
            None => Some(PERTURBED_KAPPA_FACTOR * 0.5 * self.shear_modulus()?),
        }
    }

    /// The resolved bulk modulus used by the model, if it has one (a law's `kappa`, or the
    /// perturbed incompressible formulation's).
    pub fn resolved_kappa(&self) -> Option<f64> {
        if self.is_incompressible() {
            self.perturbed_kappa()
        } else {
            self.params()?.param(PERTURBED_KAPPA)
        }
    }

    /// Fill the model-dependent defaults into the optional fields.
    pub(super) fn resolve(&mut self) {
        if let Some(formulation) = self.resolved_formulation() {
            self.formulation = Some(formulation);
            if let Some(kappa) = self.perturbed_kappa() {
                self.set(PERTURBED_KAPPA, kappa);
            }
        }
    }

    /// The keys of `[material]` that belong to `model` (besides `model` itself): `rho`, the
    /// law's parameters, and for an incompressible law `formulation` and `kappa`.
    pub fn keys_of(model: MaterialModel) -> Vec<&'static str> {
        let mut keys = vec!["rho"];
        keys.extend(model.params().iter().map(|p| p.key));
        if model.is_incompressible() {
            keys.push("formulation");
            if !keys.contains(&PERTURBED_KAPPA) {
                keys.push(PERTURBED_KAPPA);
            }
        }
        keys
    }

    /// Every parameter key a `[material]` can hold: those of the registered laws, then the
    /// perturbed formulation's `kappa`.
    pub fn all_value_keys() -> Vec<&'static str> {
        let mut keys = MaterialModel::all_keys();
        if !keys.contains(&PERTURBED_KAPPA) {
            keys.push(PERTURBED_KAPPA);
        }
        keys
    }

    /// The given values: those of the known keys in the order of [`Self::all_value_keys`],
    /// then any others.
    fn ordered(&self) -> Vec<(&str, f64)> {
        ordered_values(&self.values, &Self::all_value_keys())
    }
}

impl Serialize for MaterialSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let given = self.ordered();
        let mut m = s.serialize_map(None)?;
        m.serialize_entry("model", &self.model)?;
        m.serialize_entry("rho", &self.rho)?;
        for (k, v) in given {
            m.serialize_entry(k, &v)?;
        }
        if let Some(f) = &self.formulation {
            m.serialize_entry("formulation", f)?;
        }
        if let Some(ve) = &self.viscoelastic {
            m.serialize_entry("viscoelastic", ve)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for MaterialSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        struct Given {
            model: MaterialModel,
            rho: f64,
            #[serde(default)]
            formulation: Option<Formulation>,
            #[serde(default)]
            viscoelastic: Option<ViscoelasticSpec>,
            #[serde(flatten)]
            values: BTreeMap<String, f64>,
        }
        let g = Given::deserialize(d)?;
        let known = MaterialSpec::all_value_keys();
        if let Some(key) = g.values.keys().find(|k| !known.contains(&k.as_str())) {
            return Err(serde::de::Error::custom(format!("unknown field `{key}`")));
        }
        Ok(MaterialSpec {
            model: g.model,
            rho: g.rho,
            values: g.values,
            formulation: g.formulation,
            viscoelastic: g.viscoelastic,
        })
    }
}

/// The checks of `[material]`, from the law's declared parameters: the viscoelastic
/// overstress, the density, keys of another model, missing parameters, values out of their
/// bounds, the law's own checks between parameters, then the incompressibility formulation.
pub(super) fn validate_material(m: &MaterialSpec, out: &mut Vec<Issue>) {
    if let Some(ve) = &m.viscoelastic {
        if let Err(msg) = ve.build() {
            let key = if crate::material::ViscoModel::from_name(&ve.model).is_none() {
                "model"
            } else if msg.starts_with("gamma") {
                "gamma"
            } else {
                "prony"
            };
            out.push(issue(format!("material.viscoelastic.{key}"), msg));
        }
    }
    let model = m.model;
    if !positive(m.rho) {
        out.push(issue(
            "material.rho",
            format!("density must be > 0, got {}", m.rho),
        ));
    }
    let allowed = MaterialSpec::keys_of(model);
    let mut given: Vec<&str> = m.ordered().into_iter().map(|(k, _)| k).collect();
    if m.formulation.is_some() {
        given.push("formulation");
    }
    for key in given {
        if !allowed.contains(&key) {
            out.push(issue(
                format!("material.{key}"),
                format!(
                    "`{key}` is not a parameter of model \"{model}\" (its keys are model, {})",
                    allowed.join(", ")
                ),
            ));
        }
    }
    for p in model.params() {
        match m.get(p.key) {
            None => {
                let note = if p.note.is_empty() {
                    String::new()
                } else {
                    format!("; {}", p.note)
                };
                out.push(issue(
                    format!("material.{}", p.key),
                    format!("required for model \"{model}\" ({}{note})", p.what),
                ));
            }
            Some(x) if !p.bound.admits(x) => out.push(issue(
                format!("material.{}", p.key),
                format!("{} must be {}, got {x}", p.what, p.bound),
            )),
            Some(_) => {}
        }
    }
    for (key, msg) in model.cross_check(&|k| m.get(k)) {
        out.push(issue(format!("material.{key}"), msg));
    }
    if model.is_incompressible() && !model.params().iter().any(|p| p.key == PERTURBED_KAPPA) {
        match (m.formulation.unwrap_or_default(), m.get(PERTURBED_KAPPA)) {
            (Formulation::Perturbed, Some(k)) if !positive(k) => out.push(issue(
                "material.kappa",
                format!("bulk modulus must be > 0, got {k}"),
            )),
            (Formulation::Exact, Some(_)) => out.push(issue(
                "material.kappa",
                "`kappa` is only used with formulation = \"perturbed\" \
                 (the exact formulation has no bulk modulus)",
            )),
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::scene::tests::*;
    use crate::io::scene::*;

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
            Some(crate::material::MooneyRivlinIncompressible::new(80.0, 20.0).into())
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
            Some(crate::material::NeoHookean::new(200.0, 1800.0).into())
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
            Some(crate::material::MooneyRivlin::new(80.0, 20.0, 2000.0).into())
        );
        assert_eq!(s.material.resolved_kappa(), Some(2000.0));
        assert_eq!(s.material.resolved_formulation(), None);
        assert_eq!(s.material.shear_modulus(), Some(200.0));
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
        assert_eq!(s.material.get("kappa"), Some(1e4 * 100.0));
        assert_eq!(s.material.resolved_kappa(), Some(1e6));
        // Integers are accepted for floats.
        assert_eq!(s.geometry.ri, 1.0);
        assert_eq!(s.motion.omega, 0.0);
        // Explicit kappa wins.
        let s2 = load_with(text, &["material.kappa=5000"]).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s2.material.get("kappa"), Some(5000.0));
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
    fn sub_table_keys_can_be_overridden() {
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
        let set = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let s = Scene::from_toml_str(
            base,
            "v.toml",
            &set(&[
                "material.viscoelastic.gamma=300",
                "material.viscoelastic.model=multiplicative",
                "material.viscoelastic.prony=[[1.0, 0.05]]",
            ]),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let ve = s.material.viscoelastic.clone().expect("parsed");
        assert_eq!(
            (ve.model.as_str(), ve.gamma, ve.prony),
            ("multiplicative", 300.0, vec![[1.0, 0.05]])
        );
        // Every problem at once, each named with its key and `(--set)`.
        let e = Scene::from_toml_str(
            base,
            "v.toml",
            &set(&[
                "material.viscoelastic.colour=1",
                "material.viscoelastic.gamma=big",
                "mesh.n_r.x=1",
                "a.b.c.d=1",
            ]),
        )
        .expect_err("invalid overrides");
        let colour = e
            .find("material.viscoelastic.colour")
            .unwrap_or_else(|| panic!("{e}"));
        assert!(
            colour
                .message
                .contains("keys of [material.viscoelastic] are model, gamma, prony"),
            "{}",
            colour.message
        );
        assert!(e.has_key("material.viscoelastic.gamma"), "{e}");
        let n_r = e.find("mesh.n_r.x").unwrap_or_else(|| panic!("{e}"));
        assert!(
            n_r.message.contains("is a value, not a table"),
            "{}",
            n_r.message
        );
        assert!(e.has_key("a.b.c.d"), "{e}");
        assert!(e.to_string().contains("(--set)"), "{e}");
    }
}
