//! The reference of what a user writes and reads: scene keys (from the scene schema) and every
//! `summary.json` key and CSV column with its unit (the registries below). `tread schema
//! --markdown` prints it; `docs/reference.md` is that output, and a test checks that the committed
//! file equals what the program generates, and that every key and column that runs write is
//! registered here.
//!
//! Units are those of the scene (`[scene] units = "L-F-T"`): L length, F force, T time; forces,
//! torques and energies are per unit thickness (plane strain); `–` marks dimensionless numbers,
//! counts, flags and text. In load stepping the "time" is the load factor λ (dimensionless).

use crate::io::scene::markdown_reference;

/// One documented output key or column.
#[derive(Clone, Copy, Debug)]
pub struct OutputKey {
    /// Dotted key (`results.hub_force_x`; `[]` marks the elements of an array) or column name.
    pub key: &'static str,
    /// Unit in the scene's L-F-T system, `–` when dimensionless or not a number.
    pub unit: &'static str,
    /// Which runs write it (empty: every run that writes the file).
    pub when: &'static str,
    pub doc: &'static str,
}

const fn k(
    key: &'static str,
    unit: &'static str,
    when: &'static str,
    doc: &'static str,
) -> OutputKey {
    OutputKey {
        key,
        unit,
        when,
        doc,
    }
}

const N: &str = "–";
const D3: &str = "mesh.dimension = 3";
const D2: &str = "mesh.dimension = 2";
const TR: &str = "transient";
const SD: &str = "steady";
const TS: &str = "transient, steady";
const CONT: &str = "steady with [continuation]";
const C3: &str = "steady with [continuation], mesh.dimension = 3";
const VCONT: &str = "steady, [material.viscoelastic], continuation in omega";
const SS: &str = "stick_slip";
const CMP: &str = "tread compare";
const CMP3: &str = "tread compare, mesh.dimension = 3";
const TR3: &str = "transient, mesh.dimension = 3";
const SDC: &str = "steady with motion.control other than speed";
const REC: &str = "steady, when the first solve failed";
const EPSC: &str = "steady, friction with ε < 1e-2 v_ref";
const MP: &str = "model problems";
const MPC: &str = "model problem cavity";
const MPT: &str = "model problems heat, burgers";
const MPP: &str = "model problem p_navier_stokes";
const MPL: &str = "model problem lshape";
const MPTPL: &str = "model problems heat, burgers, p_navier_stokes, lshape";
const MPTP: &str = "model problems heat, burgers, p_navier_stokes";
const CST: &str = "steady, solver.coarse_start on a generated annulus with n_r even >= 4, n_theta a multiple of 4 >= 64 (three dimensions: a generated revolved mesh with n_theta a multiple of 4 >= 64)";

/// Every key of `summary.json` (objects are listed with their keys).
pub static SUMMARY_KEYS: &[OutputKey] = &[
    k("scene", N, "", "scene name"),
    k("mode", N, "", "analysis mode that ran (`spinning`, `static`, `stick_slip`, `transient`, `steady`, `compare`; `model_problem` for a scene with `[problem]`)"),
    k("dofs", N, "", "number of unknowns solved for (free displacement dofs + pressure dofs + global unknowns)"),
    k("newton_iterations", N, "", "Newton iterations summed over the run"),
    k("wall_time_s", "s", "", "wall time of the run (set-up, solve, results), seconds"),
    k("converged", N, "", "whether the analysis reached its target"),
    k("error", N, "", "null, or why the solve failed (`interrupted` after Ctrl-C, SIGTERM or SIGHUP)"),
    k("incomplete_outputs", N, "", "outputs a sink could not finish (a full disk, a removed folder); absent when every output is complete"),
    k("incomplete_outputs[].sink", N, "", "the sink (`vtu`, `mcap`, `rerun`, `png`, `csv`, `sta`)"),
    k("incomplete_outputs[].path", N, "", "the file it could not write"),
    k("incomplete_outputs[].error", N, "", "why"),
    k("warnings", N, TS, "list of warnings, e.g. steady rolling not reached by `t_end`"),
    k("version", N, "", "tread version"),
    k("transient_dir", N, CMP, "folder of the transient run's own outputs"),
    k("steady_dir", N, CMP, "folder of the steady run's own outputs"),
    // terms
    k("terms", N, "", "which terms of the model ran"),
    k("terms.friction", N, "", "friction acted (a law other than `none` with a non-zero coefficient)"),
    k("terms.normal_damping", N, "", "contact damping `b_n` acted"),
    k("terms.inertia", N, "", "inertia (or the centrifugal load) was assembled"),
    k("terms.history", N, "", "the material carried history (viscoelastic)"),
    k("terms.pressure", N, "", "a pressure field was solved for (incompressible material)"),
    k("terms.strain_rate_damping", N, TR, "`time.strain_rate_damping` acted"),
    k("terms.damping_tangent", N, SD, "Newton matrix of the steady strain-rate damping: `matrix_free` (the cells' own sparsity, the rest by GMRES), `banded` (three-point ring differences in the matrix, the rest by GMRES) or `assembled` (the whole coupling, direct LU); null without damping"),
    k("terms.damping_tangent_fallback", N, SD, "why the damping tangent differs from the one asked for: the press switched from the matrix-free or banded to the assembled one, or `banded` was asked for on a mesh without node rings (matrix-free then); null: it does not"),
    k("terms.contact_facets_per_iteration", N, "", "mean contact facets integrated per assembly"),
    // mesh
    k("mesh", N, "", "the mesh"),
    k("mesh.n_r", N, "", "radial cells (as in the scene)"),
    k("mesh.n_theta", N, "", "circumferential cells (as in the scene)"),
    k("mesh.order", N, "", "element order"),
    k("mesh.nodes", N, "", "number of nodes"),
    k("mesh.cells", N, "", "number of cells"),
    k("mesh.pressure_dofs", N, "", "pressure unknowns (incompressible material)"),
    k("mesh.n_z", N, D3, "axial cells of the generated wheel (null for a mesh file)"),
    k("mesh.width", "L", D3, "width of the generated wheel (null for a mesh file)"),
    k("mesh.sides", N, D3, "`free` or `sliding` flat faces of the generated wheel (null for a mesh file)"),
    k("mesh.crown_radius", "L", D3, "crown radius of the generated wheel (null: flat, or a mesh file)"),
    k("mesh.contact_facets", N, D3, "facets of the contact surface (0 in the spinning mode)"),
    // solver
    k("solver", N, "", "solver statistics"),
    k("solver.linear", N, "", "sparse solver used (`cholesky` or `lu`)"),
    k("solver.switched_to_lu", N, "", "Cholesky failed and LU took over"),
    k("solver.load_steps", N, "", "accepted load (or time) steps"),
    k("solver.cutbacks", N, "", "step halvings after a failed Newton solve"),
    k("solver.threads", N, "", "worker threads"),
    k("solver.interrupted_at", "T or λ", "interrupted runs", "load factor or time reached when the run was interrupted"),
    k("solver.recovery", N, SD, "null when the first steady solve worked, else how it was recovered"),
    k("solver.recovery.direct_error", N, REC, "why the direct solve failed"),
    k("solver.recovery.strategy", N, REC, "strategy that succeeded (`kappa_homotopy`, `eps_homotopy`, `omega_stepping`, `combined`); null if none did"),
    k("solver.recovery.attempts", N, REC, "one entry per strategy tried"),
    k("solver.recovery.attempts[].strategy", N, REC, "strategy of this attempt"),
    k("solver.recovery.attempts[].succeeded", N, REC, "whether it reached the scene's state"),
    k("solver.recovery.attempts[].error", N, REC, "why it failed (null if it succeeded)"),
    k("solver.recovery.attempts[].press_steps", N, REC, "load steps of the initial press"),
    k("solver.recovery.attempts[].press_cutbacks", N, REC, "cut-backs of the initial press"),
    k("solver.recovery.attempts[].legs", N, REC, "parameter legs walked"),
    k("solver.recovery.attempts[].legs[].parameter", N, REC, "parameter of the leg"),
    k("solver.recovery.attempts[].legs[].from", "as the parameter", REC, "start value"),
    k("solver.recovery.attempts[].legs[].to", "as the parameter", REC, "target value"),
    k("solver.recovery.attempts[].legs[].steps", N, REC, "steps of the leg"),
    k("solver.recovery.attempts[].legs[].cutbacks", N, REC, "cut-backs of the leg"),
    k("solver.recovery.attempts[].legs[].reached", "as the parameter", REC, "value reached"),
    k("solver.eps_continuation", N, SD, "null, or how a steady solve with a small friction regularisation (ε < 1e-2 v_ref, v_ref = max(|v0|, |ω| Ro)) reached it: pressed in at ε_c = 1e-2 v_ref, then ε walked down geometrically to the scene's value (when it fails, the direct press-in follows)"),
    k("solver.eps_continuation.strategy", N, EPSC, "always `eps_homotopy`"),
    k("solver.eps_continuation.succeeded", N, EPSC, "whether it reached the scene's ε"),
    k("solver.eps_continuation.error", N, EPSC, "why it failed (null if it succeeded)"),
    k("solver.eps_continuation.press_steps", N, EPSC, "load steps of the press-in at ε_c"),
    k("solver.eps_continuation.press_cutbacks", N, EPSC, "cut-backs of the press-in at ε_c"),
    k("solver.eps_continuation.legs", N, EPSC, "the ε leg (one entry)"),
    k("solver.eps_continuation.legs[].parameter", N, EPSC, "`eps`"),
    k("solver.eps_continuation.legs[].from", "L/T", EPSC, "ε_c"),
    k("solver.eps_continuation.legs[].to", "L/T", EPSC, "the scene's ε"),
    k("solver.eps_continuation.legs[].spacing", N, EPSC, "`geometric`"),
    k("solver.eps_continuation.legs[].steps", N, EPSC, "steps in ε"),
    k("solver.eps_continuation.legs[].newton_iterations", N, EPSC, "Newton iterations of the ε steps"),
    k("solver.eps_continuation.legs[].cutbacks", N, EPSC, "step halvings in ε"),
    k("solver.eps_continuation.legs[].reached", "L/T", EPSC, "ε reached"),
    k("solver.eps_continuation.newton_iterations", N, EPSC, "Newton iterations (press-in and ε steps)"),
    k("solver.eps_continuation.wall_time_s", "s", EPSC, "wall time of the continuation"),
    k("solver.coarse_start", N, SD, "null, or how the steady solve started from the steady state of the mesh with half the cells in r and θ (nested iteration, `[solver] coarse_start`)"),
    k("solver.coarse_start.meshes", N, CST, "the coarser meshes solved first, coarsest first, as `n_r x n_theta` (three dimensions: `n_r x n_z x n_theta`)"),
    k("solver.coarse_start.coarse_newton_iterations", N, CST, "Newton iterations on the coarser meshes"),
    k("solver.coarse_start.coarse_wall_time_s", "s", CST, "wall time of the coarser meshes' set-up and solves and of the interpolation (not of this mesh's symbolic analysis, made alongside)"),
    k("solver.coarse_start.newton_iterations", N, CST, "Newton iterations on the scene's mesh from the interpolated state"),
    k("solver.coarse_start.succeeded", N, CST, "whether Newton converged from it (if not, the press-in from the undeformed state followed)"),
    k("solver.coarse_start.error", N, CST, "why it did not (null if it did)"),
    k("solver.recovery.newton_iterations", N, REC, "Newton iterations of the recovery"),
    k("solver.recovery.cutbacks", N, REC, "cut-backs of the recovery"),
    k("solver.recovery.wall_time_s", "s", REC, "wall time of the recovery"),
    k("solver.recovery.message", N, REC, "one-line account of the recovery"),
    // results: spinning and static
    k("results", N, "", "the results of the mode"),
    k("results.omega", "rad/T", "spinning, steady", "angular speed reached"),
    k("results.u_r_outer", "L", "spinning, static", "mean radial displacement of the outer surface, (1/L)∮ u·e_R ds"),
    k("results.sigma_r_inner", "F/L²", "spinning, static", "ring average of the Cauchy σ_rr on the hub surface"),
    k("results.sigma_theta_inner", "F/L²", "spinning, static", "ring average of the Cauchy σ_θθ on the hub surface"),
    k("results.sigma_r_outer", "F/L²", "spinning, static", "ring average of σ_rr on the outer surface"),
    k("results.sigma_theta_outer", "F/L²", "spinning, static", "ring average of σ_θθ on the outer surface"),
    k("results.max_displacement", "L", "spinning, static", "largest nodal |u|"),
    k("results.recovered_stress", N, "spinning", "ring averages of the recovered nodal Cauchy stress (superconvergent patch recovery of the element stresses at the 2×2 Gauss points of Q2 cells or the centres of Q1 cells, complete cubic (Q2) or linear (Q1) least-squares fit per vertex patch, boundary nodes from the interior patches), interpolated along the facets: about one order of h more accurate than `results.sigma_*`; the same field is the VTU array `cauchy_stress_recovered`"),
    k("results.recovered_stress.sigma_r_inner", "F/L²", "spinning", "ring average of the recovered σ_rr on the hub surface"),
    k("results.recovered_stress.sigma_theta_inner", "F/L²", "spinning", "ring average of the recovered σ_θθ on the hub surface"),
    k("results.recovered_stress.sigma_r_outer", "F/L²", "spinning", "ring average of the recovered σ_rr on the outer surface (0 for a free surface, up to the discretisation error)"),
    k("results.recovered_stress.sigma_theta_outer", "F/L²", "spinning", "ring average of the recovered σ_θθ on the outer surface"),
    k("results.error_estimate", N, "spinning", "a posteriori estimates of the energy error ‖u − u_h‖_A of the solution, A = ∂P/∂F at the solution (the energy norm of the problem linearised about it)"),
    k("results.error_estimate.recovery", "(F·L/L)^½", "spinning", "Zienkiewicz–Zhu estimate: the recovered displacement gradient against the element's, in the energy norm; asymptotically exact (effectivity 0.99–1.00 on the spinning annulus at 4k–16k DOFs); per cell it is the VTU array `error_indicator`"),
    k("results.error_estimate.explicit_residual", "(F·L/L)^½", "spinning", "explicit residual indicator (element residual Div P + b − ρω²∂θθχ, traction jumps, traction on the free outer surface), its unknown constant taken as 1: an upper indicator, 14–19 times the error on the spinning annulus"),
    k("results.error_estimate.energy_norm", "(F·L/L)^½", "spinning", "energy norm ‖u_h‖_A of the solution"),
    k("results.error_estimate.relative", N, "spinning", "recovery / energy_norm: the relative energy error"),
    k("results.hub_force_x", "F/L", "static, transient, steady", "force of the hub on the body, x1 (from the residual at the hub dofs; transient: last step)"),
    k("results.hub_force_y", "F/L", "static, transient, steady", "force of the hub on the body, x2 (an indented cylinder has < 0)"),
    k("results.hub_torque", "F·L/L", "static, transient, steady", "moment of the hub on the body about its centre, counter-clockwise positive"),
    k("results.contact_x_min", "L", "static, transient, steady", "lower end in x1 of the contact patch (outermost facet points with t_n > 0)"),
    k("results.contact_x_max", "L", "static, transient, steady", "upper end in x1 of the contact patch"),
    k("results.max_pressure", "F/L²", "static, transient, steady", "peak normal traction (per unit reference length)"),
    k("results.contact_force_x", "F/L", "static, transient, steady", "resultant of the contact tractions on the body, x1"),
    k("results.contact_force_y", "F/L", "static, transient, steady", "resultant of the contact tractions on the body, x2"),
    k("results.contact_half_width_moment", "L", "static, transient, steady", "Hertz-type half-width 2√⟨(x1 − x̄)²⟩ of the pressure"),
    k("results.contact_centroid", "L", TS, "x̄: pressure-weighted mean x1 of the patch"),
    k("results.contact_moment", "F·L/L", TS, "moment of the contact tractions about the hub centre"),
    k("results.road_height", "L", "static", "final road height H"),
    k("results.dimension", N, D3, "3"),
    k("results.contact_force", "F", D3, "[F1, F2, F3]: resultant of the contact tractions on the body (along the road, up, along the axle; totals, not per width)"),
    k("results.contact_moment", "F·L", D3, "[M1, M2, M3]: moment of the contact tractions about the hub centre"),
    k("results.load", "F", D3, "the hub load of load control (`road.load`; null under displacement control and when spinning)"),
    k("results.contact_area", "L²", D3, "reference area of the facet quadrature points with t_n > 0"),
    k("results.max_penetration", "L", D3, "largest penetration at a facet quadrature point"),
    k("results.points_in_contact", N, D3, "facet quadrature points with t_n > 0"),
    k("results.u_r_outer_mean", "L", D3, "mean radial displacement of the outer surface nodes, Σ u·e_R / n"),
    k("results.hub_loads", N, D3, "the loads of the road on the body at the hub centre, in the road frame (e1, n, e3) = (x1, x2, x3) without camber (null without contact)"),
    k("results.hub_loads.longitudinal_force", "F", D3, "along the road's e1 (+x1)"),
    k("results.hub_loads.vertical_force", "F", D3, "along the road normal n (up): the wheel load"),
    k("results.hub_loads.lateral_force", "F", D3, "along the road's lateral e3 (+x3 without camber)"),
    k("results.hub_loads.overturning_moment", "F·L", D3, "about e1"),
    k("results.hub_loads.aligning_moment", "F·L", D3, "about the road normal n"),
    k("results.hub_loads.axle_moment", "F·L", D3, "about e3 (the axle without camber; the hub's drive torque is its negative)"),
    k("results.transient", N, TR3, "the time integration of the 3D transient mode"),
    k("results.transient.integrator", N, TR3, "time.integrator"),
    k("results.transient.steps", N, TR3, "accepted time steps"),
    k("results.transient.rejected", N, TR3, "rejected time steps (step-size control, failed Newton solves)"),
    k("results.transient.newton_iterations", N, TR3, "Newton iterations over all steps"),
    k("results.transient.steady", N, TR3, "whether the passage-to-passage changes stayed below time.steady_tol at two consecutive node passages"),
    k("results.transient.time_to_steady", "T", TR3, "time at which rolling became steady (null when not)"),
    k("results.transient.final_time", "T", TR3, "time of the last accepted step"),
    k("results.transient.revolutions", N, TR3, "hub revolutions at the last step"),
    k("results.transient.passages", N, TR3, "node passages (the body turned by one cell angle)"),
    k("results.transient.last_change", N, TR3, "relative changes over the last passage: [field, hub force, hub moment]"),
    k("results.transient.dt_min_used", "T", TR3, "smallest accepted step"),
    k("results.transient.dt_max_used", "T", TR3, "largest accepted step"),
    k("results.transient.hub_loads_passage_mean", N, TR3, "the road's six loads on the body at the hub centre in the road frame, averaged over the last node passage (−the hub's reaction); null before two passages"),
    k("results.transient.hub_loads_passage_mean.longitudinal_force", "F", TR3, "passage mean, along e1"),
    k("results.transient.hub_loads_passage_mean.vertical_force", "F", TR3, "passage mean, along n"),
    k("results.transient.hub_loads_passage_mean.lateral_force", "F", TR3, "passage mean, along e3"),
    k("results.transient.hub_loads_passage_mean.overturning_moment", "F·L", TR3, "passage mean, about e1"),
    k("results.transient.hub_loads_passage_mean.aligning_moment", "F·L", TR3, "passage mean, about n"),
    k("results.transient.hub_loads_passage_mean.axle_moment", "F·L", TR3, "passage mean, about e3"),
    k("results.road_velocity", "L/T", "steady, mesh.dimension = 3", "[V1, V3]: the road velocity in its plane"),
    k("results.slip_angle", "deg", "steady, mesh.dimension = 3", "slip angle α (`road.slip_angle`)"),
    k("results.viscous_dissipation", "F·L/T", "steady, mesh.dimension = 3, multiplicative viscoelastic", "power dissipated by the viscoelastic overstress ∫ D dV; with no other dissipation it equals the hub's axle moment times ω"),
    k("results.penetration", "L", "static, steady", "final penetration DISP = Ro − H"),
    k("results.contact_facets_per_iteration", N, "static", "mean facets integrated per assembly"),
    k("results.contact_facets_total", N, "static", "facets on the outer surface"),
    // transient and steady
    k("results.time_to_steady", "T", TS, "time when steady rolling was declared (null if not; steady: 0)"),
    k("results.steady", N, TS, "whether rolling became steady (steady: converged)"),
    k("results.revolutions", N, TS, "hub revolutions (steady: 0)"),
    k("results.steps", N, TS, "accepted time steps (steady: continuation steps, 0 without [continuation])"),
    k("results.rejected_steps", N, TR, "rejected time steps"),
    k("results.node_passages", N, TR, "cell passages through the bottom"),
    k("results.final_time", "T", TR, "time reached"),
    k("results.dt_min_used", "T", TR, "smallest accepted step"),
    k("results.dt_max_used", "T", TR, "largest accepted step"),
    k("results.integrator", N, TR, "time integrator"),
    k("results.mass", N, TR, "mass matrix (`consistent`, `lumped`)"),
    k("results.viscous_energy", N, TR, "viscoelastic materials only: energy balance of the viscous overstress from the start of time stepping, per unit thickness (its power S_v : Ė is the rate of the energy its internal variables store plus a dissipation ≥ 0)"),
    k("results.viscous_energy.work", "F·L/L", TR, "work of the overstress ∫∫ S_v : Ė dV dt (trapezoidal in time)"),
    k("results.viscous_energy.stored", "F·L/L", TR, "energy stored in the internal variables at the end (Maxwell springs of the convolution model, Σ ψ_i of the multiplicative one)"),
    k("results.viscous_energy.dissipated", "F·L/L", TR, "work − change of the stored energy"),
    k("results.viscous_energy.min_dissipated", "F·L/L", TR, "lowest cumulative dissipation at the end of any step"),
    k("results.viscous_energy.min_dissipated_time", "T", TR, "time of that lowest value"),
    k("results.viscous_energy.work_abs", "F·L/L", TR, "Σ over the steps of |work of the step| (scale of the balance)"),
    k("results.viscous_energy.energy_created", N, TR, "true when the overstress created energy: min_dissipated < −1e-6 work_abs (also a warning)"),
    k("results.omega_steady", "rad/T", TR, "hub angular speed at the end"),
    k("results.rolling_radius", "L", TR, "effective rolling radius v0 / ω"),
    k("results.applied_torque", "F·L/L", TR, "hub torque applied at the end (torque control; else the reaction)"),
    k("results.control", N, TS, "transient: the hub control (`speed`, `torque`); steady: null for `speed`, else what the control did (keys below)"),
    k("results.control.control", N, SDC, "`torque`, `free_rolling` or `creep`"),
    k("results.control.target_torque", "F·L/L", SDC, "target hub torque (0 for free rolling and creep's free-rolling stage); per unit thickness in the plane, a total (F·L) in three dimensions"),
    k("results.control.torque_tolerance", "F·L/L", SDC, "absolute torque tolerance, 1e-7 |F_y| Ro at the press-in state (three dimensions: 1e-7 |F_hub| Ro, a total)"),
    k("results.control.v0_free", "L/T", SDC, "free-rolling road speed (free rolling and creep; else null)"),
    k("results.control.rolling_radius", "L", SDC, "effective rolling radius R_e = v0_free / ω (else null)"),
    k("results.control.creep", N, SDC, "creep ξ = v0 / v0_free − 1 of the final state (else null)"),
    k("results.control.evaluations", N, SDC, "steady solves, one per trial v0"),
    k("results.control.newton_iterations", N, SDC, "their Newton iterations"),
    k("results.control.history", "[L/T, F·L/L]", SDC, "(v0, hub torque) of every trial of the secant iteration"),
    k("results.creep", N, SD, "creep ξ = (v0 − ω R_e) / (ω R_e)"),
    k("results.v0", "L/T", SD, "road speed (three dimensions: of the final state, along the road velocity turned by the slip angle)"),
    k("results.wall_time_first_solution_s", "s", SD, "wall time to the first steady solution"),
    k("results.steady_change_field", N, TR, "relative change of the referential field over the last node passage"),
    k("results.steady_change_force", N, TR, "relative change of the hub force over the last node passage"),
    k("results.steady_change_torque", N, TR, "relative change of the hub torque over the last node passage"),
    k("results.steady_change_omega", N, TR, "relative change of ω over the last node passage"),
    k("results.hub_force_x_passage_mean", "F/L", TS, "hub_force_x averaged over the last node passage (the steady load)"),
    k("results.hub_force_y_passage_mean", "F/L", TS, "hub_force_y averaged over the last node passage"),
    k("results.hub_torque_passage_mean", "F·L/L", TS, "hub_torque averaged over the last node passage"),
    // continuation
    k("results.branch", N, CONT, "the branch, one entry per converged point (the rows of branch.csv)"),
    k("results.rolling_resistance", N, VCONT, "rolling-resistance coefficient along the branch (see the keys below)"),
    k("results.rolling_resistance.definition", N, VCONT, "`C_rr = sign(omega) T / (P Ro), P = -F_y`"),
    k("results.rolling_resistance.omega", "1/T", VCONT, "ω of each branch point with a load"),
    k("results.rolling_resistance.coefficient", N, VCONT, "C_rr at those points (> 0: the hub feeds the dissipation)"),
    k("results.rolling_resistance.peak", N, VCONT, "the interior maximum of C_rr (parabola in log ω through the largest value and its neighbours); null when the branch does not bracket it"),
    k("results.rolling_resistance.peak.omega", "1/T", VCONT, "ω at the peak"),
    k("results.rolling_resistance.peak.coefficient", N, VCONT, "C_rr at the peak"),
    k("results.rolling_resistance.peak.step", N, VCONT, "branch step of the largest sampled C_rr"),
    k("results.branch[].step", N, CONT, "continuation step"),
    k("results.branch[].lambda", "as the parameter", CONT, "parameter value"),
    k("results.branch[].omega", "rad/T", CONT, "angular speed"),
    k("results.branch[].v0", "L/T", CONT, "road speed"),
    k("results.branch[].creep", N, CONT, "creep ξ"),
    k("results.branch[].penetration", "L", CONT, "penetration Ro − H"),
    k("results.branch[].hub_force_x", "F/L", CONT, "hub force, x1"),
    k("results.branch[].hub_force_y", "F/L", CONT, "hub force, x2"),
    k("results.branch[].hub_torque", "F·L/L", CONT, "hub torque"),
    k("results.branch[].slip_angle", "deg", C3, "slip angle α of the point"),
    k("results.branch[].camber", "deg", C3, "camber γ of the point"),
    k("results.branch[].road_height", "L", C3, "road height H of the point"),
    k("results.branch[].longitudinal_force", "F", C3, "hub load of the road on the body along e1 (the hub loads below as in `results.hub_loads`)"),
    k("results.branch[].vertical_force", "F", C3, "along the road normal n"),
    k("results.branch[].lateral_force", "F", C3, "along e3"),
    k("results.branch[].overturning_moment", "F·L", C3, "about e1"),
    k("results.branch[].aligning_moment", "F·L", C3, "about n"),
    k("results.branch[].axle_moment", "F·L", C3, "about e3"),
    k("results.branch[].points_in_contact", N, C3, "facet quadrature points in contact"),
    k("results.branch[].contact_x_min", "L", CONT, "lower end of the contact patch"),
    k("results.branch[].contact_x_max", "L", CONT, "upper end of the contact patch"),
    k("results.branch[].max_pressure", "F/L²", CONT, "peak normal traction"),
    k("results.branch[].wave_amplitude", "L", CONT, "half the peak-to-peak u_r of the outer surface more than 60° from the bottom (standing waves)"),
    k("results.branch[].wave_number", N, CONT, "dominant circumferential wave number n ≥ 4 of u_r on the same arc (Hann-windowed Fourier spectrum, mean removed; up to n_theta / 2, four Q2 nodes per wavelength)"),
    k("results.branch[].det_sign", N, CONT, "sign of the tangent's determinant (symmetric tangent only)"),
    k("results.branch[].negative_eigenvalues", N, CONT, "negative eigenvalues of the tangent (symmetric tangent only)"),
    k("results.branch[].test_function", N, CONT, "smallest-eigenvalue estimate"),
    k("results.branch[].iterations", N, CONT, "corrector iterations"),
    k("results.branch[].kind", N, CONT, "0 start, 1 regular, 2 limit point, 3 bifurcation, 4 first point after a branch switch, 5 first point after a jump past a limit point"),
    k("results.branch[].wall_time_s", "s", CONT, "wall time of the step"),
    k("results.branch[].factor_solve_s", "s", CONT, "time in factorisations and solves"),
    k("results.special_points", N, CONT, "limit and bifurcation points"),
    k("results.special_points[].step", N, CONT, "step after which it was detected"),
    k("results.special_points[].kind", N, CONT, "`limit` or `bifurcation`"),
    k("results.special_points[].lambda", "as the parameter", CONT, "estimated parameter value"),
    k("results.special_points[].detected_by", N, CONT, "what detected it"),
    k("results.continuation", N, CONT, "continuation statistics"),
    k("results.continuation.parameter", N, CONT, "continuation parameter"),
    k("results.continuation.steps", N, CONT, "continuation steps"),
    k("results.continuation.stop_reason", N, CONT, "why the continuation stopped"),
    k("results.continuation.switched_at", N, CONT, "the step after which the path switched branches (`[continuation] switch_branch`), null when it did not"),
    k("results.continuation.jumps", N, CONT, "jumps past limit points (`[continuation] on_limit = \"jump\"`): [{`step` of the first point after the jump, `limit` (the limit point's parameter), `landed` (the parameter of the direct solve)}]"),
    k("results.continuation.failed_jumps", N, CONT, "parameter values of the limit points past which no direct solve converged (the path followed the branch back there)"),
    k("results.continuation.corrector_iterations", N, CONT, "corrector iterations in total"),
    k("results.continuation.cutbacks", N, CONT, "step reductions"),
    k("results.continuation.assemblies", N, CONT, "tangent assemblies"),
    k("results.continuation.factorizations", N, CONT, "factorisations"),
    // stick-slip
    k("results.period", "T", SS, "mean time between stick→slip transitions, the first interval skipped (null with fewer than three)"),
    k("results.amplitude", "L", SS, "slip amplitude x_max − x_min"),
    k("results.x_min", "L", SS, "smallest x of the last cycle"),
    k("results.x_max", "L", SS, "largest x of the last cycle"),
    k("results.stick_time", "T", SS, "duration of the stick phase in the last complete cycle"),
    k("results.slip_time", "T", SS, "duration of the slip phase in the last complete cycle"),
    k("results.cycles", N, SS, "stick→slip transitions"),
    k("results.period_rel_error", N, SS, "relative difference of the period from the closed form"),
    k("results.amplitude_rel_error", N, SS, "relative difference of the amplitude from the closed form"),
    k("results.closed_form", N, SS, "the exact static/kinetic Coulomb cycle (rate-dependent law), else null"),
    k("results.closed_form.period", "T", SS, "period"),
    k("results.closed_form.amplitude", "L", SS, "amplitude"),
    k("results.closed_form.stick_time", "T", SS, "stick time"),
    k("results.closed_form.slip_time", "T", SS, "slip time"),
    k("results.closed_form.x_min", "L", SS, "smallest x"),
    k("results.closed_form.x_max", "L", SS, "largest x"),
    k("results.solver_stats", N, SS, "statistics of the ODE integrator"),
    k("results.solver_stats.steps", N, SS, "steps"),
    k("results.solver_stats.newton_iterations", N, SS, "Newton iterations"),
    k("results.solver_stats.newton_failures", N, SS, "Newton failures"),
    k("results.solver_stats.error_test_failures", N, SS, "error-test failures"),
    k("results.solver_stats.factorizations", N, SS, "factorisations"),
    // compare
    k("results.compare", N, CMP, "transient against steady; the transient loads are the averages over its last node passage"),
    k("results.compare.hub_force_x_transient", "F/L", CMP, "transient hub_force_x"),
    k("results.compare.hub_force_x_steady", "F/L", CMP, "steady hub_force_x"),
    k("results.compare.hub_force_y_transient", "F/L", CMP, "transient hub_force_y"),
    k("results.compare.hub_force_y_steady", "F/L", CMP, "steady hub_force_y"),
    k("results.compare.hub_torque_transient", "F·L/L", CMP, "transient hub_torque"),
    k("results.compare.hub_torque_steady", "F·L/L", CMP, "steady hub_torque"),
    k("results.compare.transient_loads", N, CMP, "`passage_mean` or `last_step`: which transient loads are compared"),
    k("results.compare.hub_force_x_transient_last_step", "F/L", CMP, "transient hub_force_x at the last step"),
    k("results.compare.hub_force_y_transient_last_step", "F/L", CMP, "transient hub_force_y at the last step"),
    k("results.compare.hub_torque_transient_last_step", "F·L/L", CMP, "transient hub_torque at the last step"),
    k("results.compare.hub_force_x_rel_diff", N, CMP, "|Δ hub_force_x| / |F_steady|"),
    k("results.compare.hub_force_y_rel_diff", N, CMP, "|Δ hub_force_y| / |F_steady|"),
    k("results.compare.hub_torque_abs_diff", "F·L/L", CMP, "|Δ hub_torque|"),
    k("results.compare.hub_torque_rel_diff", N, CMP, "|Δ hub_torque| / (|F_steady| Ro)"),
    k("results.compare.field_rel_l2", N, CMP, "relative FE L2 difference of the referential fields"),
    k("results.compare.field_max_abs", "L", CMP, "largest nodal difference of the referential fields"),
    k("results.compare.field_rel_max", N, CMP, "field_max_abs / largest steady nodal |u|"),
    k("results.compare.history_rel_l2", N, CMP, "viscoelastic scenes on ring meshes: ‖Q_t − Q_s‖_L2 / ‖Q_s‖_L2 of the internal variables (every Prony term, polar components at each quadrature point, quadrature weights), the transient's at its last node passage re-indexed to the referential cells; null when not compared (the passage fell between steps, or no rings); per ring in `history_rings.csv`"),
    k("results.compare.history_rel_max", N, CMP, "max |Q_t − Q_s| over the largest steady |Q| component"),
    k("results.compare.contact_x_min_transient", "L", CMP, "transient contact_x_min"),
    k("results.compare.contact_x_min_steady", "L", CMP, "steady contact_x_min"),
    k("results.compare.contact_x_max_transient", "L", CMP, "transient contact_x_max"),
    k("results.compare.contact_x_max_steady", "L", CMP, "steady contact_x_max"),
    k("results.compare.max_pressure_transient", "F/L²", CMP, "transient max_pressure"),
    k("results.compare.max_pressure_steady", "F/L²", CMP, "steady max_pressure"),
    k("results.compare.wall_time_transient_s", "s", CMP, "wall time of the transient run"),
    k("results.compare.wall_time_steady_s", "s", CMP, "wall time of the steady run"),
    k("results.compare.speedup", N, CMP, "wall_time_transient_s / wall_time_steady_s"),
    k("results.compare.transient_steady", N, CMP, "whether the transient reached steady rolling"),
    k("results.compare.transient_time_to_steady", "T", CMP, "the transient's time_to_steady"),
    k("results.compare.transient_steps", N, CMP, "the transient's accepted steps"),
    k("results.compare.hub_loads_transient", N, CMP3, "the transient's six hub loads (road frame), averaged over its last node passage"),
    k("results.compare.hub_loads_transient.longitudinal_force", "F", CMP3, "transient, along e1"),
    k("results.compare.hub_loads_transient.vertical_force", "F", CMP3, "transient, along n"),
    k("results.compare.hub_loads_transient.lateral_force", "F", CMP3, "transient, along e3"),
    k("results.compare.hub_loads_transient.overturning_moment", "F·L", CMP3, "transient, about e1"),
    k("results.compare.hub_loads_transient.aligning_moment", "F·L", CMP3, "transient, about n"),
    k("results.compare.hub_loads_transient.axle_moment", "F·L", CMP3, "transient, about e3"),
    k("results.compare.hub_loads_steady", N, CMP3, "the steady mode's six hub loads (road frame)"),
    k("results.compare.hub_loads_steady.longitudinal_force", "F", CMP3, "steady, along e1"),
    k("results.compare.hub_loads_steady.vertical_force", "F", CMP3, "steady, along n"),
    k("results.compare.hub_loads_steady.lateral_force", "F", CMP3, "steady, along e3"),
    k("results.compare.hub_loads_steady.overturning_moment", "F·L", CMP3, "steady, about e1"),
    k("results.compare.hub_loads_steady.aligning_moment", "F·L", CMP3, "steady, about n"),
    k("results.compare.hub_loads_steady.axle_moment", "F·L", CMP3, "steady, about e3"),
    k("results.compare.footprint_pressure_rel_l2", N, CMP3, "‖p_t − p_s‖ / ‖p_s‖, L2 over the tread, both fields' contact pressure at the steady mode's facet quadrature points"),
    k("results.compare.footprint_traction_rel_l2", N, CMP3, "the same for the tangential traction vector (e1, e3)"),
    k("results.compare.contact_area_transient", "L²", CMP3, "reference area in contact, transient field"),
    k("results.compare.contact_area_steady", "L²", CMP3, "reference area in contact, steady field"),
    k("results.compare.quantities", N, CMP, "the judged quantities, one object each (below); also `compare.csv`"),
    k("results.compare.quantities[].name", N, CMP, "`hub_force_x`, `hub_force_y`, `hub_torque`, `field_l2`, `contact_x_min`, `contact_x_max`, `max_pressure`; in three dimensions the six hub loads (`longitudinal_force` … `axle_moment`), `field_l2`, `footprint_pressure`, `footprint_traction`, `max_pressure`"),
    k("results.compare.quantities[].unit", N, CMP, "unit of the quantity in the scene's system (`[scene] units`, e.g. `lbf/in`); `1` dimensionless"),
    k("results.compare.quantities[].transient", "as the quantity", CMP, "transient value (null for `field_l2`)"),
    k("results.compare.quantities[].steady", "as the quantity", CMP, "steady value (null for `field_l2`)"),
    k("results.compare.quantities[].abs_diff", "as the quantity", CMP, "|transient − steady| (`field_l2`: ‖u_t − u_s‖_L2 / ‖u_s‖_L2)"),
    k("results.compare.quantities[].rel_diff", N, CMP, "abs_diff / scale"),
    k("results.compare.quantities[].relative_to", N, CMP, "what the difference is relative to: `|F_steady|` for the hub force components (a component near zero is not divided by itself), `|hub_torque_steady|` or, for a torque below 1e-3 |F_steady| Ro, `|F_steady| Ro`; `steady patch length` for the patch ends; `|max_pressure_steady|`; `‖u_steady‖_L2`"),
    k("results.compare.quantities[].scale", "as the quantity", CMP, "the value of `relative_to`"),
    k("results.compare.quantities[].tolerance", N, CMP, "largest accepted rel_diff: hub forces 0.01, torque 0.02, field 0.01, peak pressure 0.05 (`tread compare --force-tol`, `--torque-tol`, `--field-tol`, `--pressure-tol`); patch ends one surface node spacing over the patch length (`--contact-tol` spacings)"),
    k("results.compare.quantities[].within", N, CMP, "rel_diff <= tolerance (false for a non-finite difference)"),
    k("results.compare.validated", N, CMP, "every quantity within its tolerance and the transient run steady; `tread compare` (and `tread` without a command) exits with status 4 when false"),
    k("results.compare.verdict", N, CMP, "the sentence printed last: `steady solution validated against the transient: …` or `not validated: …` (what failed)"),
    // model problems (scenes with [problem])
    k("kind", N, MP, "`problem.kind`: `cavity`, `heat`, `burgers`, `p_navier_stokes`, `lshape`"),
    k("problem", N, MP, "the resolved `[problem]` table (every key with its value, defaults filled)"),
    k("steps", N, MP, "rows of `steps.csv`: time steps, adaptive passes (every attempt of a p-adaptive time step) or mesh recalculations"),
    k("interrupted_at", "T, – or –", "interrupted model problems", "where Ctrl-C (SIGTERM, SIGHUP) stopped the run: the time reached (heat, burgers, Taylor–Green), the last adaptive pass (lshape, Kovasznay) or the Reynolds number reached (cavity); absent otherwise"),
    k("results.equations", N, MP, "equations (unknowns) of the final solution"),
    k("results.cells", N, "model problems cavity, heat, burgers, lshape", "cells of the final mesh"),
    k("results.reynolds", N, MPC, "Reynolds number (ν = 1/Re, lid speed 1)"),
    k("results.recalculations", N, MPC, "moving-mesh relocations made (0 on the uniform mesh)"),
    k("results.min_det_j", "L²", MPC, "smallest corner det J of the final cells"),
    k("results.psi_min", "L²/T", MPC, "minimum of the stream function (primary vortex)"),
    k("results.psi_min_at", "L", MPC, "[x, y] where it is reached"),
    k("results.reference", N, MPC, "source of the reference tables (`Ghia et al. (1982)` at Re = 100, 400; `Botella & Peyret (1998)` at Re = 1000); null for the regularised lid"),
    k("results.centreline_u_error", "L/T", MPC, "largest |u(0.5, y) − u_ref| over the tabulated stations (null without a reference)"),
    k("results.centreline_v_error", "L/T", MPC, "largest |v(x, 0.5) − v_ref| over the tabulated stations (Ghia's misprinted Re = 400 station x = 0.9063 left out)"),
    k("results.centreline_error", "L/T", MPC, "the larger of the two"),
    k("results.psi_min_error", "L²/T", MPC, "|ψ_min − ψ_min,ref| (Re = 1000 only)"),
    k("results.uniform_centreline_error", "L/T", MPC, "centreline_error on the starting uniform mesh (recalculation 0)"),
    k("results.uniform_psi_min_error", "L²/T", MPC, "psi_min_error on the starting uniform mesh"),
    k("results.t", "T", MPTP, "time of the final solution (Kovasznay: 0)"),
    k("results.max_equations", N, MPT, "largest number of equations over the steps"),
    k("results.l2_error", "as u", MPTP, "‖u − u_h‖_L² at the final time against the exact solution (p_navier_stokes: the velocity)"),
    k("results.h1_error", "as u / L", MPT, "|u − u_h|_H¹ at the final time"),
    k("results.estimate", "as the error", MPTPL, "the error estimate of the final solution: two-grid ‖u_f − u_h‖ (heat, burgers), enrichment ‖u_{p+r} − u_p‖ (p_navier_stokes), the driving estimator's energy estimate (lshape)"),
    k("results.effectivity", N, MPTPL, "estimate / error"),
    k("results.flow", N, MPP, "`kovasznay` or `taylor_green`"),
    k("results.equations_enriched", N, MPP, "equations of the enriched pair (every degree + `enrich`)"),
    k("results.tolerance", "L·L/T", MPP, "`problem.tolerance` τ on the L² velocity estimate"),
    k("results.worst_ratio", N, MPP, "largest η_K / τ_K, τ_K = τ (|K| / |Ω|)^{1/2} (≤ 1: every cell within its share)"),
    k("results.accepted", N, MPP, "the final solution met the tolerance (no cell left to raise)"),
    k("results.solves", N, MPP, "solves made (Kovasznay: sweeps; Taylor–Green: attempts over all steps)"),
    k("results.degrees", N, MPP, "cells per velocity degree of the final solution, pairs [degree, cells]"),
    k("results.max_level", N, MPL, "finest refinement level of the final mesh"),
    k("results.max_degree", N, MPL, "largest polynomial degree of the final mesh"),
    k("results.energy_error", "as u", MPL, "|u − u_h|₁ against u = r^{2/3} sin(2θ/3)"),
    k("results.relative_error", N, MPL, "energy_error / |u|₁"),
    k("results.rate", N, MPL, "least-squares slope of log energy_error against log equations over the meshes with at least 400 equations (null with fewer than three); optimal −p/2, uniform refinement −1/3"),
];

/// One CSV file and its columns.
#[derive(Clone, Copy, Debug)]
pub struct CsvFile {
    pub name: &'static str,
    pub when: &'static str,
    pub columns: &'static [OutputKey],
}

const HIST: &str = "history.csv";

/// Every CSV file and column. `history.csv` holds `step, time` and the series of the run, each
/// only where it applies.
pub static CSV_FILES: &[CsvFile] = &[
    CsvFile {
        name: HIST,
        when: "sink `csv`; one row per accepted step",
        columns: &[
            k("step", N, "", "index of the accepted step"),
            k(
                "time",
                "T or λ",
                "",
                "t (transient, stick_slip) or the load factor λ (load stepping)",
            ),
            k("newton_iterations", N, "", "Newton iterations of the step"),
            k("t", "T", TR3, "time"),
            k("omega", "1/T", TR3, "hub angular speed"),
            k("hub_force_1", "F", TR3, "force of the hub on the body, x1 (wheel frame)"),
            k("hub_force_2", "F", TR3, "force of the hub on the body, x2"),
            k("hub_force_3", "F", TR3, "force of the hub on the body, x3"),
            k("hub_moment_1", "F·L", TR3, "moment of the hub on the body about the hub centre, x1"),
            k("hub_moment_2", "F·L", TR3, "moment of the hub on the body, x2"),
            k("hub_moment_3", "F·L", TR3, "moment of the hub on the body, x3"),
            k("hub_force_x", "F/L", "", "force of the hub on the body, x1"),
            k("hub_force_y", "F/L", "", "force of the hub on the body, x2"),
            k("hub_torque", "F·L/L", "", "moment of the hub on the body"),
            k("energy_strain", "F·L/L", "", "stored strain energy"),
            k("energy_kinetic", "F·L/L", "", "kinetic energy"),
            k("energy_total", "F·L/L", "", "strain + kinetic energy"),
            k("road_height", "L", "with contact", "road height H"),
            k(
                "contact_force_x",
                "F/L",
                "with contact",
                "resultant contact traction, x1",
            ),
            k(
                "contact_force_y",
                "F/L",
                "with contact",
                "resultant contact traction, x2",
            ),
            k(
                "max_pressure",
                "F/L²",
                "with contact",
                "peak normal traction",
            ),
            k(
                "patch_x_min",
                "L",
                "with contact",
                "lower end of the contact patch",
            ),
            k(
                "patch_x_max",
                "L",
                "with contact",
                "upper end of the contact patch",
            ),
            k(
                "max_shear_stress",
                "F/L²",
                "",
                "largest nodal in-plane maximum shear stress",
            ),
            k("phi", "rad", TR, "hub rotation angle"),
            k("revolutions", N, TR, "hub revolutions"),
            k("x", "L", SS, "position of the mass"),
            k("v", "L/T", SS, "velocity of the mass"),
            k("friction_force", "F", SS, "friction force on the mass"),
            k("slipping", N, SS, "0 = stick, 1 = slip"),
        ],
    },
    CsvFile {
        name: "profile.csv",
        when: "sink `csv`; spinning (generated annulus)",
        columns: &[
            k("r", "L", "", "radius of the radial Gauss point"),
            k("u_r", "L", "", "ring average of the radial displacement"),
            k("sigma_r", "F/L²", "", "ring average of σ_rr"),
            k("sigma_theta", "F/L²", "", "ring average of σ_θθ"),
            k("sigma_r_theta", "F/L²", "", "ring average of σ_rθ"),
        ],
    },
    CsvFile {
        name: "nodes.csv",
        when: "sink `csv`; spinning, static, steady (X3, u3: mesh.dimension = 3)",
        columns: &[
            k("node", N, "", "node index"),
            k("X1", "L", "", "reference position, x1"),
            k("X2", "L", "", "reference position, x2"),
            k("X3", "L", D3, "reference position, x3 (along the axle)"),
            k("u1", "L", "", "displacement, x1"),
            k("u2", "L", "", "displacement, x2"),
            k("u3", "L", D3, "displacement, x3"),
        ],
    },
    CsvFile {
        name: "steps.csv",
        when: "sink `csv`; mesh.dimension = 3; one row per accepted load step",
        columns: &[
            k("step", N, "", "index of the accepted step"),
            k("load_factor", N, "", "load factor λ of the step"),
            k("newton_iterations", N, "", "Newton iterations of the step"),
            k("road_height", "L", "static, steady", "road height H (empty when spinning)"),
            k("contact_force_1", "F", "", "resultant contact traction on the body, x1"),
            k("contact_force_2", "F", "", "resultant contact traction on the body, x2"),
            k("contact_force_3", "F", "", "resultant contact traction on the body, x3"),
            k("contact_moment_1", "F·L", "", "moment of the contact tractions about the hub centre, x1 (overturning)"),
            k("contact_moment_2", "F·L", "", "moment of the contact tractions about the hub centre, x2 (aligning)"),
            k("contact_moment_3", "F·L", "", "moment of the contact tractions about the hub centre, x3 (axle)"),
            k("max_pressure", "F/L²", "", "peak normal traction"),
            k("points_in_contact", N, "", "facet quadrature points with t_n > 0"),
            k("u_r_outer_mean", "L", "", "mean radial displacement of the outer surface nodes"),
        ],
    },
    CsvFile {
        name: "convergence.csv",
        when: "sink `csv`; spinning, static (also in three dimensions)",
        columns: &[
            k("step", N, "", "load step"),
            k("load_factor", N, "", "load factor λ of the step"),
            k("iteration", N, "", "Newton iteration"),
            k(
                "residual_u_rel",
                N,
                "",
                "relative residual of the displacement equations",
            ),
            k(
                "residual_p_rel",
                N,
                "",
                "relative residual of the pressure equations",
            ),
            k(
                "residual_h_rel",
                N,
                "",
                "relative residual of the global equations (road height, hub)",
            ),
            k("increment_norm", N, "", "norm of the Newton increment"),
            k("alpha", N, "", "line-search step length"),
        ],
    },
    CsvFile {
        name: "contact.csv",
        when: "sink `csv`; static, transient, steady (mesh.dimension = 3: static, the columns marked so)",
        columns: &[
            k("cell", N, D3, "cell of the contact facet"),
            k("face", N, D3, "local face of the cell (0..6: ξ = ∓1, η = ∓1, ζ = ∓1)"),
            k(
                "theta",
                "rad",
                D2,
                "reference angle of the facet point (−π/2 = bottom)",
            ),
            k("x1", "L", "", "current position, x1"),
            k("x2", "L", "", "current position, x2"),
            k("x3", "L", D3, "current position, x3"),
            k("penetration", "L", "", "penetration δ"),
            k(
                "t_n",
                "F/L²",
                "",
                "normal traction on the body (per unit reference length and thickness; 3D: per unit reference area)",
            ),
            k("t_t", "F/L²", D2, "tangential traction on the body"),
            k("t_1", "F/L²", D3, "tangential traction on the body, x1"),
            k("t_3", "F/L²", D3, "tangential traction on the body, x3"),
            k(
                "slip_velocity",
                "L/T (static: L)",
                D2,
                "slip velocity w (static: slip per unit pseudo-time)",
            ),
            k("slip_1", "L", D3, "slip per unit pseudo-time of the last load step, x1"),
            k("slip_3", "L", D3, "slip per unit pseudo-time of the last load step, x3"),
            k("stick", N, D3, "1 where |slip| is below the regularisation ε (with friction)"),
            k("dA0", "L²", D3, "reference area weight"),
            k("ds0", "L", D2, "reference length weight"),
        ],
    },
    CsvFile {
        name: "passages.csv",
        when: "sink `csv`; transient",
        columns: &[
            k("t", "T", "", "time of the cell passage"),
            k(
                "change_field",
                N,
                "",
                "relative change of the referential field over the passage",
            ),
            k("change_force", N, "", "relative change of the hub force"),
            k("change_torque", N, "", "relative change of the hub torque"),
            k("hub_force_x", "F/L", "", "hub force, x1"),
            k("hub_force_y", "F/L", "", "hub force, x2"),
            k("hub_torque", "F·L/L", "", "hub torque"),
            k("omega", "rad/T", "", "hub angular speed at the passage"),
            k(
                "change_omega",
                N,
                "",
                "relative change of ω over the passage",
            ),
        ],
    },
    CsvFile {
        name: "steady_field.csv",
        when: "sink `csv`; transient, steady",
        columns: &[
            k("ring", N, "", "ring of referential nodes"),
            k("pos", N, "", "position along the ring"),
            k("X1", "L", "", "referential node, x1"),
            k("X2", "L", "", "referential node, x2"),
            k("u1", "L", "", "u = χ − X, x1"),
            k("u2", "L", "", "u = χ − X, x2"),
        ],
    },
    CsvFile {
        name: "steady_field_3d.csv",
        when: "sink `csv`; transient, mesh.dimension = 3: the referential field of the last node passage",
        columns: &[
            k("node", N, "", "node index"),
            k("X1", "L", "", "referential node, x1"),
            k("X2", "L", "", "referential node, x2"),
            k("X3", "L", "", "referential node, x3"),
            k("u1", "L", "", "u = χ − X, x1"),
            k("u2", "L", "", "u = χ − X, x2"),
            k("u3", "L", "", "u = χ − X, x3"),
        ],
    },
    CsvFile {
        name: "footprint_compare.csv",
        when: "tread compare, mesh.dimension = 3: one row per facet quadrature point of the tread",
        columns: &[
            k("cell", N, "", "cell of the facet"),
            k("face", N, "", "local face of the cell"),
            k("x1", "L", "", "current position of the point (steady field), x1"),
            k("x2", "L", "", "x2"),
            k("x3", "L", "", "x3"),
            k("da0", "L²", "", "reference area weight of the point"),
            k("p_transient", "F/L²", "", "contact pressure of the transient's referential field"),
            k("p_steady", "F/L²", "", "contact pressure of the steady field"),
            k("t1_transient", "F/L²", "", "tangential traction on the body along e1, transient"),
            k("t1_steady", "F/L²", "", "the same, steady"),
            k("t3_transient", "F/L²", "", "tangential traction on the body along e3, transient"),
            k("t3_steady", "F/L²", "", "the same, steady"),
        ],
    },
    CsvFile {
        name: "branch.csv",
        when: "steady with [continuation]; the columns of `results.branch[]` above",
        columns: &[],
    },
    CsvFile {
        name: "history_rings.csv",
        when: "tread compare on a viscoelastic scene with a ring mesh; one row per ring of quadrature points, innermost first",
        columns: &[
            k("ring", N, "", "ring index (radial quadrature-point line)"),
            k("radius", "L", "", "mean reference radius of the ring's points"),
            k("rel_l2", N, "", "‖Q_t − Q_s‖ / ‖Q_s‖ over the ring (polar components, quadrature weights)"),
            k("max_abs_diff", N, "", "max |Q_t − Q_s| over the ring's points and components (the internal variables are strain-like)"),
            k("max_abs_steady", N, "", "max |Q_s| over the ring"),
        ],
    },
    CsvFile {
        name: "compare.csv",
        when: "tread compare; one row per judged quantity (the wall times are in summary.json)",
        columns: &[
            k(
                "quantity",
                N,
                "",
                "name of the compared quantity (a key of `results.compare`)",
            ),
            k("unit", N, "", "unit of the quantity (`results.compare.quantities[].unit`)"),
            k("transient", "as the quantity", "", "transient value (empty for `field_l2`)"),
            k("steady", "as the quantity", "", "steady value (empty for `field_l2`)"),
            k("abs_diff", "as the quantity", "", "|transient − steady|"),
            k("rel_diff", N, "", "abs_diff / the scale named in `relative_to`"),
            k("relative_to", N, "", "what rel_diff is relative to (`results.compare.quantities[].relative_to`)"),
            k("tolerance", N, "", "largest accepted rel_diff"),
            k("within", N, "", "`true` or `false`: rel_diff <= tolerance"),
        ],
    },
    CsvFile {
        name: "steps.csv",
        when: "model problems (sink `csv`): one row per time step (heat, burgers), adaptive pass (lshape; p_navier_stokes: every sweep or attempt of a step) or mesh recalculation (cavity); the columns depend on the kind",
        columns: &[
            k("recalculation", N, MPC, "0: the uniform mesh after the continuation in Re, then one per relocation"),
            k("equations", N, MP, "equations of the solve"),
            k("min_det_j", "L²", MPC, "smallest corner det J of the cells"),
            k("relocation_step", N, MPC, "accepted relocation step λ (1: the full relocation)"),
            k("newton_iterations", N, "model problems cavity, heat, burgers, p_navier_stokes", "Newton iterations of the solve (cavity recalculation 0: of the whole continuation)"),
            k("psi_min", "L²/T", MPC, "minimum of the stream function"),
            k("psi_min_x", "L", MPC, "where, x"),
            k("psi_min_y", "L", MPC, "where, y"),
            k("centreline_u_error", "L/T", MPC, "largest |u(0.5, y) − u_ref| (empty without a reference)"),
            k("centreline_v_error", "L/T", MPC, "largest |v(x, 0.5) − v_ref|"),
            k("psi_min_error", "L²/T", MPC, "|ψ_min − ψ_min,ref| (Re = 1000)"),
            k("step", N, "model problems heat, burgers, lshape", "index of the time step or mesh"),
            k("t", "T", MPTP, "time of the solution (Kovasznay: 0)"),
            k("cells", N, "model problems heat, burgers, lshape", "cells of the mesh"),
            k("l2_error", "as u", MPTP, "‖u − u_h‖_L² against the exact solution"),
            k("h1_error", "as u / L", MPT, "|u − u_h|_H¹"),
            k("estimate", "as the error", MPTPL, "the error estimate (two-grid, enrichment or the driving estimator)"),
            k("effectivity", N, MPTPL, "estimate / error"),
            k("solve", N, MPP, "index of the solve"),
            k("attempt", N, MPP, "attempt within the time step (steady: the sweep)"),
            k("accepted", N, MPP, "1: the solution was accepted (time advanced after it)"),
            k("equations_enriched", N, MPP, "equations of the enriched pair"),
            k("worst_ratio", N, MPP, "largest η_K / τ_K"),
            k("min_degree", N, MPP, "smallest velocity degree"),
            k("max_degree", N, "model problems p_navier_stokes, lshape", "largest (velocity) degree"),
            k("max_level", N, MPL, "finest refinement level"),
            k("energy_error", "as u", MPL, "|u − u_h|₁"),
            k("relative_error", N, MPL, "energy_error / |u|₁"),
            k("t_solve", "s", MPL, "wall time of the solve step"),
            k("t_estimate", "s", MPL, "wall time of the estimate step"),
        ],
    },
];

/// Whether a `summary.json` key (dotted, `[]` for array elements) is in [`SUMMARY_KEYS`].
pub fn summary_key_documented(key: &str) -> bool {
    SUMMARY_KEYS.iter().any(|k| k.key == key)
}

/// Whether a column of a CSV file is in [`CSV_FILES`] (`branch.csv`: the `results.branch[]` keys).
pub fn csv_column_documented(file: &str, column: &str) -> bool {
    if file == "branch.csv" {
        return summary_key_documented(&format!("results.branch[].{column}"));
    }
    CSV_FILES
        .iter()
        .any(|f| f.name == file && f.columns.iter().any(|c| c.key == column))
}

fn rows(keys: &[OutputKey], out: &mut String) {
    out.push_str("| key | unit | written by | meaning |\n|---|---|---|---|\n");
    for k in keys {
        out.push_str(&format!(
            "| `{}` | {} | {} | {} |\n",
            k.key,
            crate::io::scene::cell(k.unit),
            if k.when.is_empty() { "all" } else { k.when },
            crate::io::scene::cell(k.doc)
        ));
    }
}

/// The whole reference in Markdown (`tread schema --markdown`, `docs/reference.md`).
pub fn markdown() -> String {
    let mut out = String::from(
        "# tread reference: scene keys, summary.json keys, CSV columns\n\n\
         Generated by `tread schema --markdown` from the program's own tables; do not edit by \
         hand (a test compares this file with the program's output).\n\n## Scene keys\n\n",
    );
    out.push_str(&markdown_reference());
    out.push_str("\n### Model-problem scenes (`[problem]`)\n\n");
    out.push_str(&crate::io::scene::model_problem::markdown_reference());
    out.push_str(
        "\n## summary.json\n\nUnits as above (L, F, T of the scene; s = seconds of wall time). \
         `[]` marks the elements of an array. Non-finite numbers are written as null.\n\n",
    );
    rows(SUMMARY_KEYS, &mut out);
    out.push_str("\n## CSV files\n\nEmpty fields are non-finite values.\n");
    for f in CSV_FILES {
        out.push_str(&format!("\n### `{}`\n\n{}\n\n", f.name, f.when));
        if !f.columns.is_empty() {
            rows(f.columns, &mut out);
        }
    }
    out.push_str(PNG_FILES);
    out.push_str(EXIT_STATUS);
    out
}

/// Which PNG plots a run writes (`[output] sinks` with `png`).
const PNG_FILES: &str = "\n## PNG plots\n\n\
Every axis carries its unit from `[scene] units`. `contact.png`: t_n and t_T along x1 (sorted \
by x1) at the last recorded state. `hub_forces.png`, `hub_torque.png`, `energy.png`: against \
time (transient) or load factor, written only for two or more distinct recorded times on one \
clock: a steady solve pressed in one load step (the default, `solver.load_steps = 1`) has a \
single state and writes none of them, and a steady run with `[continuation]` writes \
`branch.png` instead (its loads against the continuation parameter). A steady press in \
several load steps plots them against the load factor. A model problem (a scene with \
`[problem]`) writes `error_mesh.png` (its final mesh, every cell shaded by log10 of its error \
indicator over at most six decades) and `solution.png` (the final solution shaded, with contour \
lines; the cavity's stream function at the contour values of Ghia et al.).\n";

/// The exit statuses of `tread`.
const EXIT_STATUS: &str = "\n## Exit status\n\n\
| status | meaning |\n|---|---|\n\
| 0 | success |\n\
| 1 | the solve failed (the outputs hold the last converged state) |\n\
| 2 | invalid scene or arguments, or an unsupported request |\n\
| 3 | an output file or folder could not be written |\n\
| 4 | `tread compare` and `tread` without a command: both modes ran and every output is written, \
but the steady solution is not validated against the transient (`results.compare.validated` \
false: a quantity outside its tolerance, or the transient run did not reach its steady state) |\n\
| 130 | interrupted (Ctrl-C) |\n";
