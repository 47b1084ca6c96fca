use tread::driver::SolidSystem;
use tread::material::{Material, NeoHookean};
use tread::mesh::{annulus, AnnulusSpec};
use tread::physics::{PressureMode, SolidModel};
use tread::solver::{LinearKind, Newton, NewtonOptions, NonlinearSystem, SparseSolver};
fn main() {
    let mesh = annulus(&AnnulusSpec { ri: 1.0, ro: 2.0, n_r: 8, n_theta: 64, degree: 2, grading_r: 1.0, grading_theta: 0.0 });
    let mat = Material::NeoHookean(NeoHookean::new(1.0, 2.0));
    let mut model = SolidModel::new(mesh, mat, 1.0, PressureMode::None);
    model.body_force = Some(Box::new(|x| tread::math::Vec2::new(0.1 * x[1], 0.05)));
    let mut fixed: Vec<u32> = model.mesh.node_set("hub").to_vec();
    fixed.extend_from_slice(model.mesh.node_set("outer"));
    let mut sys = SolidSystem::with_fixed_nodes(model, &fixed);
    for n in 0..sys.model.mesh.n_nodes() { let x = sys.model.mesh.nodes[n]; sys.x[2*n] = 0.1 * x[0].sin(); sys.x[2*n+1] = 0.05 * x[1]; }
    sys.evaluate(true);
    let (cp, ri) = sys.pattern();
    for kind in [LinearKind::Cholesky, LinearKind::Lu] {
        let mut s = SparseSolver::new(sys.n_eq(), cp, ri, kind).unwrap();
        s.factorize(sys.matrix_values()).unwrap();
        let mut x: Vec<f64> = sys.residual().to_vec();
        s.solve_in_place(&mut x).unwrap();
        let mut y = vec![0.0; x.len()];
        sys.asm.matvec(&x, &mut y);
        let err: f64 = y.iter().zip(sys.residual()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        println!("{kind:?}: |K x - r| = {err:.3e}");
    }
    let mut n = Newton::new(&sys, LinearKind::Cholesky, NewtonOptions { verbose: true, ..Default::default() }).unwrap();
    sys.set_reference_force(1e-3);
    println!("{:?}", n.solve(&mut sys).map(|r| r.iterations));
}
