//! `[material]` / `[[material]]`: the hyperelastic model and its parameters (stresses in F/L²,
//! density in F·T²/L⁴), and the optional `[material.viscoelastic]` Prony overstress.

use super::issue::{issue, positive, quoted_list, Issue};
use serde::{Deserialize, Serialize};

/// `kappa = PERTURBED_KAPPA_FACTOR * (c1 + c2)` when the perturbed incompressible formulation is
/// chosen without an explicit `kappa`.
pub const PERTURBED_KAPPA_FACTOR: f64 = 1.0e4;

/// One `[[material]]` entry: the material of a mesh region.
#[derive(Clone, Debug, PartialEq)]
pub struct RegionMaterial {
    /// Name of a 2D physical group of the mesh file.
    pub region: String,
    pub material: MaterialSpec,
}

keyword_enum! {
    /// Hyperelastic model (`[material] model`).
    MaterialModel, "material model" {
        /// Compressible neo-Hookean with Lamé constants `mu`, `lambda`.
        NeoHookean => "neo_hookean",
        /// Compressible Mooney–Rivlin `c1 (Ī1 − 3) + c2 (Ī2 − 3) + U(J)` with bulk modulus `kappa`.
        MooneyRivlin => "mooney_rivlin",
        /// Incompressible Mooney–Rivlin `c1 (I1 − 3) + c2 (I2 − 3)`, J = 1 by a Q2/P1 pressure.
        MooneyRivlinIncompressible => "mooney_rivlin_incompressible",
    }
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

/// `[material]`. Which of the optional parameters are required depends on `model`; after
/// [`Scene::from_toml_str`] the model-dependent defaults are filled in (`formulation` for the
/// incompressible model, `kappa` for the perturbed formulation), and [`MaterialSpec::params`]
/// gives the resolved parameters as one enum.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    pub model: MaterialModel,
    /// Density per unit reference volume.
    pub rho: f64,
    /// Lamé shear modulus (neo_hookean).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu: Option<f64>,
    /// Lamé first parameter (neo_hookean).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lambda: Option<f64>,
    /// Mooney–Rivlin C1 (mooney_rivlin, mooney_rivlin_incompressible).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c1: Option<f64>,
    /// Mooney–Rivlin C2 (mooney_rivlin, mooney_rivlin_incompressible).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c2: Option<f64>,
    /// Bulk modulus (mooney_rivlin; mooney_rivlin_incompressible with the perturbed formulation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kappa: Option<f64>,
    /// Incompressibility formulation (mooney_rivlin_incompressible only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub formulation: Option<Formulation>,
    /// `[material.viscoelastic]`: a viscoelastic overstress on the elastic law (any model).
    #[serde(default, skip_serializing_if = "Option::is_none")]
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

/// Resolved material parameters, one variant per model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaterialParams {
    NeoHookean {
        mu: f64,
        lambda: f64,
    },
    MooneyRivlin {
        c1: f64,
        c2: f64,
        kappa: f64,
    },
    MooneyRivlinIncompressible {
        c1: f64,
        c2: f64,
        formulation: Formulation,
        /// `Some` for the perturbed formulation, `None` for the exact one.
        kappa: Option<f64>,
    },
}

impl MaterialSpec {
    /// The resolved parameters of the chosen model, with model-dependent defaults applied
    /// (formulation `exact`; `kappa = 1e4 (c1 + c2)` for `perturbed`). `None` only if a
    /// parameter the model requires is missing, which cannot happen after validation.
    pub fn params(&self) -> Option<MaterialParams> {
        match self.model {
            MaterialModel::NeoHookean => Some(MaterialParams::NeoHookean {
                mu: self.mu?,
                lambda: self.lambda?,
            }),
            MaterialModel::MooneyRivlin => Some(MaterialParams::MooneyRivlin {
                c1: self.c1?,
                c2: self.c2?,
                kappa: self.kappa?,
            }),
            MaterialModel::MooneyRivlinIncompressible => {
                let c1 = self.c1?;
                let c2 = self.c2?;
                let formulation = self.formulation.unwrap_or_default();
                let kappa = match formulation {
                    Formulation::Exact => None,
                    Formulation::Perturbed => {
                        Some(self.kappa.unwrap_or(PERTURBED_KAPPA_FACTOR * (c1 + c2)))
                    }
                };
                Some(MaterialParams::MooneyRivlinIncompressible {
                    c1,
                    c2,
                    formulation,
                    kappa,
                })
            }
        }
    }

    /// Small-strain shear modulus G: `mu`, or `2 (c1 + c2)` for Mooney–Rivlin.
    pub fn shear_modulus(&self) -> Option<f64> {
        match self.params()? {
            MaterialParams::NeoHookean { mu, .. } => Some(mu),
            MaterialParams::MooneyRivlin { c1, c2, .. }
            | MaterialParams::MooneyRivlinIncompressible { c1, c2, .. } => Some(2.0 * (c1 + c2)),
        }
    }

    /// Small-strain bulk modulus K: `lambda + 2 mu / 3`, `kappa`; `None` for the exactly
    /// incompressible formulation (K = ∞).
    pub fn bulk_modulus(&self) -> Option<f64> {
        match self.params()? {
            MaterialParams::NeoHookean { mu, lambda } => Some(lambda + 2.0 * mu / 3.0),
            MaterialParams::MooneyRivlin { kappa, .. } => Some(kappa),
            MaterialParams::MooneyRivlinIncompressible { kappa, .. } => kappa,
        }
    }

    /// Whether the model carries a pressure field (incompressible Mooney–Rivlin).
    pub fn is_incompressible(&self) -> bool {
        self.model == MaterialModel::MooneyRivlinIncompressible
    }

    /// The resolved formulation: `Some` only for the incompressible model.
    pub fn resolved_formulation(&self) -> Option<Formulation> {
        match self.params()? {
            MaterialParams::MooneyRivlinIncompressible { formulation, .. } => Some(formulation),
            _ => None,
        }
    }

    /// The resolved bulk modulus used by the model, if it has one (`mooney_rivlin`, or the
    /// perturbed incompressible formulation).
    pub fn resolved_kappa(&self) -> Option<f64> {
        match self.params()? {
            MaterialParams::NeoHookean { .. } => None,
            MaterialParams::MooneyRivlin { kappa, .. } => Some(kappa),
            MaterialParams::MooneyRivlinIncompressible { kappa, .. } => kappa,
        }
    }

    /// Fill the model-dependent defaults into the optional fields.
    pub(super) fn resolve(&mut self) {
        if let Some(MaterialParams::MooneyRivlinIncompressible {
            formulation, kappa, ..
        }) = self.params()
        {
            self.formulation = Some(formulation);
            self.kappa = kappa;
        }
    }

    /// The keys of `[material]` that belong to `model` (besides `model` itself).
    pub fn keys_of(model: MaterialModel) -> &'static [&'static str] {
        match model {
            MaterialModel::NeoHookean => &["rho", "mu", "lambda"],
            MaterialModel::MooneyRivlin => &["rho", "c1", "c2", "kappa"],
            MaterialModel::MooneyRivlinIncompressible => {
                &["rho", "c1", "c2", "formulation", "kappa"]
            }
        }
    }
}

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
    let given: [(&str, bool); 6] = [
        ("mu", m.mu.is_some()),
        ("lambda", m.lambda.is_some()),
        ("c1", m.c1.is_some()),
        ("c2", m.c2.is_some()),
        ("kappa", m.kappa.is_some()),
        ("formulation", m.formulation.is_some()),
    ];
    let allowed = MaterialSpec::keys_of(model);
    for (key, present) in given {
        if present && !allowed.contains(&key) {
            out.push(issue(
                format!("material.{key}"),
                format!(
                    "`{key}` is not a parameter of model \"{model}\" (its keys are model, {})",
                    allowed.join(", ")
                ),
            ));
        }
    }
    let need_positive = |key: &str, v: Option<f64>, what: &str, out: &mut Vec<Issue>| match v {
        None => out.push(issue(
            format!("material.{key}"),
            format!("required for model \"{model}\" ({what})"),
        )),
        Some(x) if !positive(x) => out.push(issue(
            format!("material.{key}"),
            format!("{what} must be > 0, got {x}"),
        )),
        Some(_) => {}
    };
    match model {
        MaterialModel::NeoHookean => {
            need_positive("mu", m.mu, "Lamé shear modulus", out);
            need_positive("lambda", m.lambda, "Lamé first parameter", out);
        }
        MaterialModel::MooneyRivlin | MaterialModel::MooneyRivlinIncompressible => {
            need_positive("c1", m.c1, "Mooney–Rivlin C1", out);
            match m.c2 {
                None => out.push(issue(
                    "material.c2",
                    format!("required for model \"{model}\" (Mooney–Rivlin C2; may be 0)"),
                )),
                Some(x) if !(x.is_finite() && x >= 0.0) => out.push(issue(
                    "material.c2",
                    format!("Mooney–Rivlin C2 must be >= 0, got {x}"),
                )),
                Some(_) => {}
            }
            if model == MaterialModel::MooneyRivlin {
                need_positive("kappa", m.kappa, "bulk modulus", out);
            } else {
                match m.formulation.unwrap_or_default() {
                    Formulation::Perturbed => {
                        if let Some(k) = m.kappa {
                            if !positive(k) {
                                out.push(issue(
                                    "material.kappa",
                                    format!("bulk modulus must be > 0, got {k}"),
                                ));
                            }
                        }
                    }
                    Formulation::Exact => {
                        if m.kappa.is_some() {
                            out.push(issue(
                                "material.kappa",
                                "`kappa` is only used with formulation = \"perturbed\" \
                                 (the exact formulation has no bulk modulus)",
                            ));
                        }
                    }
                }
            }
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
}
