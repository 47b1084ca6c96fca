//! `[material]` / `[[material]]`: the hyperelastic model and its parameters (stresses in F/L²,
//! density in F·T²/L⁴), and the optional `[material.viscoelastic]` Prony overstress.

use super::*;

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
