pub mod fourier_modes;
pub mod reference;

use tread::io::Scene;

/// A spinning-annulus scene (Ri = 1, Ro = 2, ρ = 0.027, ω = 1 rad/s) with the given
/// `[material]` keys (without `rho`) and `[mesh]` keys, one key per line.
#[allow(dead_code)]
pub fn spinning_scene(material: &str, mesh: &str) -> Scene {
    let text = format!(
        r#"
[scene]
name = "test"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
{mesh}
[material]
{material}
rho = 0.027
[analysis]
mode = "spinning"
[motion]
omega = 1.0
"#
    );
    Scene::from_toml_str(&text, "test", &[]).expect("valid test scene")
}
