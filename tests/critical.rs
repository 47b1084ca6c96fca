//! Critical speeds of the steady operator against an independent 1D Fourier-mode reference.

mod common;

use common::fourier_modes::{FourierModes, MooneyRivlinRef};
use tread::driver::critical::{self, CriticalOptions};
use tread::io::Scene;

const RI: f64 = 1.0;
const RO: f64 = 2.0;
const RHO: f64 = 0.027;
const C1: f64 = 80.0;
const C2: f64 = 20.0;
const KAPPA: f64 = 20000.0;

fn spinning_scene(n_r: usize, n_theta: usize, grading_r: f64) -> Scene {
    let text = format!(
        r#"
[scene]
name = "critical_test"
[geometry]
ri = {RI}
ro = {RO}
[mesh]
n_r = {n_r}
n_theta = {n_theta}
order = 2
grading_r = {grading_r}
[material]
model = "mooney_rivlin"
c1 = {C1}
c2 = {C2}
kappa = {KAPPA}
rho = {RHO}
[analysis]
mode = "spinning"
[motion]
omega = 1.0
[solver]
tolerance = 1e-10
"#
    );
    Scene::from_toml_str(&text, "test", &[]).expect("valid test scene")
}

fn reference(n_el: usize, p: usize) -> FourierModes {
    FourierModes {
        ri: RI,
        ro: RO,
        rho: RHO,
        mat: MooneyRivlinRef {
            c1: C1,
            c2: C2,
            kappa: KAPPA,
        },
        n_el,
        p,
    }
}

#[test]
#[ignore]
fn explore() {
    let r = reference(12, 4);
    for n in [1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64] {
        let w = r.crossing(n, 90.0, 30).unwrap();
        println!("1D n={n}: {w:?}");
    }
}
