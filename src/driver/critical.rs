//! Critical speeds of the steady (θ-referential) operator: where standing waves can appear.
//!
//! # The operator
//!
//! The steady residual R(χ; ω) (see [`super::steady`]) has the tangent
//!
//! ```text
//! K(ω) = K_el(χ_ω) − ω² B,      B(δ, η) = ∫Ω0 ρ0 ∂θδ · ∂θη dV,
//! ```
//!
//! (plus the contact and friction tangents in a rolling scene), with χ_ω the *finite* steady
//! state at ω (spun, and pressed when the scene has a road). A null vector of K(ω) is a
//! pattern that is stationary in the lab (hub) frame while the material flows through it: a
//! standing wave. ω is in rad/s; forces per unit thickness.
//!
//! # Spinning cylinder without contact (Fourier / Bloch reduction)
//!
//! The structured annulus ([`crate::mesh::annulus`], uniform in θ) is invariant under the
//! rotation by one cell, and so is K(ω) about the axisymmetric spun state. K therefore
//! block-diagonalises by circumferential wave number n: for the node classes α = (ring,
//! position inside a cell column, polar component) the Bloch vectors
//!
//! ```text
//! e_α(n): u(node) = e^{i n φ_node} (e_r or e_θ at the node),   φ = θ + π/2,
//! ```
//!
//! span invariant subspaces, and the reduced Hermitian matrix
//!
//! ```text
//! K_n[α, β] = e^{−i n φ_a} e_c'(a)ᵀ Σ_b K[a, b] e_d'(b) e^{i n φ_b}
//! ```
//!
//! (a the representative node of class α in the first cell column, b over the row's
//! neighbours) is read from the rows of one cell column. The crossing speed ω_c(n) of wave
//! number n is the smallest ω where the smallest eigenvalue of K_n(ω) reaches zero (located on a
//! grid of ω, then by the Illinois variant of regula falsi with a fresh base state per
//! evaluation). A real mode of wave number n is a (cos, sin) pair: it makes two eigenvalues of
//! K cross zero together. The mesh resolves n ≤ n_theta / 2 (four Q2 nodes per wavelength).
//! The strain-rate damping is left out of this operator (it is not part of K(ω) about a rigid
//! spin's velocity field only through its tangent, which is not Hermitian).
//!
//! **Full-operator check.** At the lowest crossing ω*, the full sparse K is factorized: the
//! number of negative eigenvalues (LBLᵀ inertia) just below and above ω*, the smallest singular
//! value by inverse iteration (relative to its value at 0.9 ω*), and the dominant Fourier
//! component of the radial displacement of the outer ring in the inverse-iteration vector are
//! reported ([`FullOperatorCheck`]).
//!
//! # Rolling (pressed) scene
//!
//! The steady branch is followed in ω from the scene's speed (the press as in `tread run`,
//! then Newton at each speed with the previous solution as start, v0/ω fixed). At each speed
//! the smallest singular value σ_min of K is computed by inverse iteration on KᵀK (one LU of K
//! and one of Kᵀ). Local minima of σ_min are refined by golden-section search; a minimum is a
//! singular point when σ_min there is below 1e-3 of its value at the start (a real test
//! function: the LU pivot sign is not used). Each is reported with the dominant Fourier
//! component of its (right) singular vector on the outer ring, and the symmetric-case inertia
//! when the tangent is symmetric. Where Newton stops converging, the sweep ends and says so.

use super::steady::SteadyRolling;
use super::steady_run::{build_steady, solve_steady};
use crate::assembly::CONSTRAINED;
use crate::io::Scene;
use crate::setup::AppError;
use crate::solver::linear::SparseSolver;
use crate::solver::stepping::StepReport;
use crate::solver::{LinearKind, Newton, NewtonOptions, NonlinearSystem, SolveError};
use nalgebra::{DMatrix, SymmetricEigen};
use std::f64::consts::{FRAC_PI_2, PI};

/// Options of [`run`].
#[derive(Clone, Debug)]
pub struct CriticalOptions {
    /// Largest wave number (default: all the mesh resolves, n_theta / 2).
    pub n_max: Option<usize>,
    /// Smallest wave number of the spinning search (default 1).
    pub n_min: Option<usize>,
    /// Upper end of the ω search (default: 2 × the Rayleigh estimate 0.955 √(G/ρ) / Ro, or
    /// 1.6 × it for a rolling scene).
    pub omega_max: Option<f64>,
    /// Grid intervals in ω (spinning) or speeds visited (rolling).
    pub samples: usize,
    /// Treat the scene without its road (spinning cylinder).
    pub no_contact: bool,
    pub verbose: bool,
}

impl Default for CriticalOptions {
    fn default() -> Self {
        Self {
            n_max: None,
            n_min: None,
            omega_max: None,
            samples: 48,
            no_contact: false,
            verbose: false,
        }
    }
}

/// Crossing speed of one wave number.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Crossing {
    pub n: usize,
    /// rad/s.
    pub omega: f64,
}

/// The full sparse operator at the lowest crossing (spinning case).
#[derive(Clone, Debug, serde::Serialize)]
pub struct FullOperatorCheck {
    pub omega: f64,
    /// Negative eigenvalues of K at ω (1 − 1e-3) and ω (1 + 1e-3) (LBLᵀ inertia).
    pub negative_below: Option<usize>,
    pub negative_above: Option<usize>,
    /// Smallest singular value of K at ω and at 0.9 ω (inverse iteration), and their ratio.
    pub sigma_min: f64,
    pub sigma_min_at_0_9: f64,
    pub sigma_ratio: f64,
    /// Dominant Fourier component of u_r on the outer ring of the inverse-iteration vector.
    pub null_mode_n: usize,
}

/// A singular point found along a rolling branch.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SingularPoint {
    pub omega: f64,
    /// Dominant Fourier component (wave number) of u_r on the outer ring of the null vector.
    pub n: usize,
    /// σ_min / σ_min at the first speed of the sweep.
    pub sigma_rel: f64,
}

/// One speed of the rolling sweep.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SweepRow {
    pub omega: f64,
    pub sigma_min: f64,
    pub n_dominant: usize,
    pub negative_eigenvalues: Option<usize>,
    pub hub_force_x: f64,
    pub hub_force_y: f64,
}

/// What `tread critical` found.
#[derive(Clone, Debug, serde::Serialize)]
pub struct CriticalReport {
    /// Lowest singular speed found (rad/s); `None` when none below `omega_max`.
    pub omega_crit: Option<f64>,
    /// Wave number of its null mode.
    pub n_star: Option<usize>,
    pub crossings: Vec<Crossing>,
    /// "spinning" (Fourier reduction) or "rolling" (sweep along the steady branch).
    pub kind: &'static str,
    pub density: f64,
    pub shear_modulus: f64,
    /// 0.955 √(G/ρ) / Ro (rad/s): the incompressible half-space Rayleigh estimate.
    pub omega_rayleigh_estimate: f64,
    pub omega_max: f64,
    /// Largest wave number the mesh resolves (n_theta / 2).
    pub n_resolved: usize,
    /// Wave numbers without a crossing below `omega_max`.
    pub not_crossed: Vec<usize>,
    /// Spinning: crossings of the patterns the mesh does not resolve (wave number
    /// n_theta − n > n_theta / 2, alternating between corner and mid-side node columns),
    /// found in the Bloch blocks n ≤ n_theta / 2. The discrete operator is singular there too.
    pub unresolved_crossings: Vec<Crossing>,
    pub full_operator: Option<FullOperatorCheck>,
    pub sweep: Vec<SweepRow>,
    /// Rolling: where the branch could not be continued (Newton failure), if it stopped.
    pub branch_end: Option<String>,
    /// Why the search ended: `target_reached` (the search end `omega_max` was covered; the
    /// spinning search always covers it) or `newton_failed` (rolling: Newton failed at the next
    /// speed even after the speed step was halved nine times, to 1/512 of the sampling step).
    pub end_reason: &'static str,
    /// Highest speed the search covered (rad/s): `omega_max`, or the last converged speed
    /// of the rolling branch.
    pub omega_covered: f64,
    /// Largest |K_n − K_nᴴ| / max |K_n| met (Hermitian check of the reduction).
    pub hermitian_defect: f64,
    pub wall_time_s: f64,
}

/// Node ring structure of a uniform annulus mesh, checked.
#[derive(Clone, Copy, Debug)]
struct Rings {
    rings: usize,
    per_ring: usize,
    deg: usize,
    n_theta: usize,
}

fn rings_of(st: &SteadyRolling) -> Result<Rings, AppError> {
    let mesh = &st.sys.model.mesh;
    let rl = mesh.rings.ok_or_else(|| {
        AppError::Unsupported("critical: needs the structured annulus mesh".into())
    })?;
    // Uniform in θ: node pos of every ring at −π/2 + 2π pos / per_ring.
    let dphi = 2.0 * PI / rl.per_ring as f64;
    for pos in 0..rl.per_ring {
        let x = mesh.nodes[(rl.rings - 1) * rl.per_ring + pos];
        let th = x[1].atan2(x[0]);
        let want = -FRAC_PI_2 + pos as f64 * dphi;
        let d = (th - want + PI).rem_euclid(2.0 * PI) - PI;
        if d.abs() > 1e-9 {
            return Err(AppError::Unsupported(
                "critical: mesh.grading_theta must be 0 (the Fourier reduction needs a mesh uniform in θ)"
                    .into(),
            ));
        }
    }
    Ok(Rings {
        rings: rl.rings,
        per_ring: rl.per_ring,
        deg: rl.per_ring / rl.n_theta,
        n_theta: rl.n_theta,
    })
}

/// Rows of K belonging to the first cell column (nodes with pos < deg, rings ≥ 1), in
/// Cartesian components: row index ((ring − 1) deg + pos) · 2 + comp → [(full dof, value)].
fn sector_rows(st: &SteadyRolling, rg: &Rings) -> Vec<Vec<(usize, f64)>> {
    let dofs = &st.sys.dofs;
    let m = (rg.rings - 1) * rg.deg * 2;
    let mut slot = vec![usize::MAX; st.sys.n_eq()];
    let mut full_of_eq = vec![0usize; st.sys.n_eq()];
    for (full, &e) in dofs.eq.iter().enumerate() {
        if e >= CONSTRAINED {
            continue;
        }
        full_of_eq[e as usize] = full;
        if full >= dofs.n_u {
            continue;
        }
        let (node, comp) = (full / 2, full % 2);
        let (ring, pos) = (node / rg.per_ring, node % rg.per_ring);
        if ring >= 1 && pos < rg.deg {
            slot[e as usize] = ((ring - 1) * rg.deg + pos) * 2 + comp;
        }
    }
    let mut rows = vec![Vec::new(); m];
    let (cp, ri) = st.sys.pattern();
    let vals = st.sys.matrix_values();
    for j in 0..st.sys.n_eq() {
        for p in cp[j]..cp[j + 1] {
            let s = slot[ri[p]];
            if s != usize::MAX {
                rows[s].push((full_of_eq[j], vals[p]));
            }
        }
    }
    rows
}

/// Real embedding [[Re, −Im], [Im, Re]] of the Bloch matrix K_n, symmetrised, and the
/// relative Hermitian defect.
fn bloch_matrix(rows: &[Vec<(usize, f64)>], rg: &Rings, n: usize) -> (DMatrix<f64>, f64) {
    let m = rows.len();
    let dphi = 2.0 * PI / rg.per_ring as f64;
    let mut re = DMatrix::<f64>::zeros(m, m);
    let mut im = DMatrix::<f64>::zeros(m, m);
    let nf = n as f64;
    for (row, entries) in rows.iter().enumerate() {
        let cls_a = row / 2;
        let c = row % 2;
        let pa = cls_a % rg.deg;
        let phi_a = pa as f64 * dphi;
        let th_a = phi_a - FRAC_PI_2;
        // Polar unit vectors at a: e_r = (cos, sin), e_θ = (−sin, cos); component c of each.
        let (sa, ca) = th_a.sin_cos();
        let ra = [[ca, -sa], [sa, ca]]; // ra[c][c'] = (e_c')_c
        for &(full, v) in entries {
            let (node, d) = (full / 2, full % 2);
            let (ring, pos) = (node / rg.per_ring, node % rg.per_ring);
            if ring == 0 {
                continue;
            }
            let phi_b = pos as f64 * dphi;
            let th_b = phi_b - FRAC_PI_2;
            let (sb, cb) = th_b.sin_cos();
            let rb = [[cb, -sb], [sb, cb]];
            let cls_b = (ring - 1) * rg.deg + pos % rg.deg;
            let (sp, cph) = (nf * (phi_b - phi_a)).sin_cos();
            for (cp, &ra_c) in ra[c].iter().enumerate() {
                for (dp, &rb_d) in rb[d].iter().enumerate() {
                    let w = ra_c * v * rb_d;
                    if w == 0.0 {
                        continue;
                    }
                    let (i, j) = (cls_a * 2 + cp, cls_b * 2 + dp);
                    re[(i, j)] += w * cph;
                    im[(i, j)] += w * sp;
                }
            }
        }
    }
    let scale = re.amax().max(im.amax()).max(f64::MIN_POSITIVE);
    let defect = (&re - re.transpose())
        .amax()
        .max((&im + im.transpose()).amax())
        / scale;
    let mut h = DMatrix::<f64>::zeros(2 * m, 2 * m);
    for i in 0..m {
        for j in 0..m {
            let r = 0.5 * (re[(i, j)] + re[(j, i)]);
            let s = 0.5 * (im[(i, j)] - im[(j, i)]);
            h[(i, j)] = r;
            h[(i + m, j + m)] = r;
            h[(i + m, j)] = s;
            h[(i, j + m)] = -s;
        }
    }
    (h, defect)
}

/// Smallest eigenvalues of K_n (divided by the largest |eigenvalue|, scale-free) over the
/// eigenvectors dominated by wave number n and over those dominated by its alias n_theta − n
/// (Q2: the Bloch block n also holds the pattern that alternates between the corner and
/// mid-side node columns, wave number n_theta − n; +∞ when there is none), and the Hermitian
/// defect.
fn bloch_lambda_min(rows: &[Vec<(usize, f64)>], rg: &Rings, n: usize) -> (f64, f64, f64) {
    let (h, defect) = bloch_matrix(rows, rg, n);
    let m = rows.len();
    let eig = SymmetricEigen::new(h);
    let lmax = eig
        .eigenvalues
        .iter()
        .map(|v| v.abs())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let nyquist = 2 * n == rg.n_theta;
    let (mut own, mut alias) = (f64::INFINITY, f64::INFINITY);
    for (j, &lam) in eig.eigenvalues.iter().enumerate() {
        let v = eig.eigenvectors.column(j);
        let is_alias = if rg.deg == 2 && !nyquist {
            // Classes ((ring − 1) deg + parity) · 2 + comp; complex amplitude v[c] + i v[c + m].
            let (mut wn, mut wa) = (0.0, 0.0);
            for base in (0..m).step_by(4) {
                for comp in 0..2 {
                    let (e, o) = (base + comp, base + 2 + comp);
                    let (er, ei, or, oi) = (v[e], v[e + m], v[o], v[o + m]);
                    wn += (er + or).powi(2) + (ei + oi).powi(2);
                    wa += (er - or).powi(2) + (ei - oi).powi(2);
                }
            }
            wa > wn
        } else {
            false
        };
        let l = lam / lmax;
        if is_alias {
            alias = alias.min(l);
        } else {
            own = own.min(l);
        }
    }
    (own, alias, defect)
}

/// First sign change of `f` along the grid, refined by the Illinois method with a fresh base
/// state per evaluation; `eval(ω)` returns f(ω).
fn refine_crossing(
    omegas: &[f64],
    fk: &[f64],
    mut eval: impl FnMut(f64, usize) -> Result<f64, AppError>,
) -> Result<Option<f64>, AppError> {
    let Some(k) = fk.iter().position(|&f| f <= 0.0) else {
        return Ok(None);
    };
    if k == 0 {
        return Ok(Some(omegas[0]));
    }
    let (mut a, mut fa) = (omegas[k - 1], fk[k - 1]);
    let (mut b, mut fb) = (omegas[k], fk[k]);
    let mut side = 0i32;
    for _ in 0..40 {
        if (b - a).abs() <= 1e-7 * b {
            break;
        }
        let c = (a * fb - b * fa) / (fb - fa);
        let c = if c > a && c < b { c } else { 0.5 * (a + b) };
        let fc = eval(c, k - 1)?;
        if fc > 0.0 {
            a = c;
            fa = fc;
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        } else {
            b = c;
            fb = fc;
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        }
        if fc.abs() < 1e-13 {
            break;
        }
    }
    Ok(Some(if fa.abs() < fb.abs() { a } else { b }))
}

/// Solve the steady state at ω from the current state (v0 = (v0/ω) ω); tangent assembled on
/// return.
fn solve_at(st: &mut SteadyRolling, newton: &mut Newton, omega: f64) -> Result<(), SolveError> {
    let v0 = st.v0_per_omega * omega;
    st.set_omega(omega, v0);
    newton.solve(st)?;
    if !st.evaluate(true) {
        return Err(SolveError::InadmissibleStart);
    }
    Ok(())
}

/// Dominant Fourier component (n ≥ 1) of the radial component of `v` (equation numbering) on
/// the outer ring.
fn dominant_wave_number(st: &SteadyRolling, v: &[f64]) -> usize {
    let mesh = &st.sys.model.mesh;
    let Some(rl) = mesh.rings else { return 0 };
    let dofs = &st.sys.dofs;
    let last = rl.rings - 1;
    let ur: Vec<f64> = (0..rl.per_ring)
        .map(|pos| {
            let node = last * rl.per_ring + pos;
            let x = mesh.nodes[node];
            let get = |d: usize| match dofs.eq[d] {
                e if e >= CONSTRAINED => 0.0,
                e => v[e as usize],
            };
            (get(2 * node) * x[0] + get(2 * node + 1) * x[1]) / x.norm()
        })
        .collect();
    let np = ur.len();
    let (mut best, mut bn) = (-1.0, 0);
    for n in 1..=np / 2 {
        let (mut c, mut s) = (0.0, 0.0);
        for (k, u) in ur.iter().enumerate() {
            let a = 2.0 * PI * (n * k) as f64 / np as f64;
            c += u * a.cos();
            s += u * a.sin();
        }
        let amp = c * c + s * s;
        if amp > best {
            best = amp;
            bn = n;
        }
    }
    bn
}

/// Transpose of a CSC pattern: (col_ptr, row_idx, map) with valuesᵀ[k] = values[map[k]].
fn transpose_pattern(n: usize, cp: &[usize], ri: &[usize]) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let mut cnt = vec![0usize; n + 1];
    for &r in ri {
        cnt[r + 1] += 1;
    }
    for i in 0..n {
        cnt[i + 1] += cnt[i];
    }
    let mut next = cnt.clone();
    let mut rt = vec![0usize; ri.len()];
    let mut map = vec![0usize; ri.len()];
    for j in 0..n {
        let col = cp[j]..cp[j + 1];
        for (p, &r) in col.clone().zip(&ri[col]) {
            let k = next[r];
            next[r] += 1;
            rt[k] = j;
            map[k] = p;
        }
    }
    (cnt, rt, map)
}

/// Smallest singular value of the assembled tangent by inverse iteration on (KᵀK)⁻¹ (LU of K
/// and of Kᵀ), the right singular vector, and the inertia when K is symmetric.
struct SingularProbe {
    lu: SparseSolver,
    lut: SparseSolver,
    tmap: Vec<usize>,
    vt: Vec<f64>,
    v: Vec<f64>,
}

impl SingularProbe {
    fn new(st: &SteadyRolling) -> Result<Self, AppError> {
        let n = st.sys.n_eq();
        let (cp, ri) = st.sys.pattern();
        let err = |e: crate::solver::linear::LinearError| {
            AppError::Unsupported(format!("critical: linear solver: {e}"))
        };
        let mut lu = SparseSolver::new(n, cp, ri, LinearKind::Lu).map_err(err)?;
        lu.set_track_determinant(true);
        let (ct, rt, tmap) = transpose_pattern(n, cp, ri);
        let mut lut = SparseSolver::new(n, &ct, &rt, LinearKind::Lu).map_err(err)?;
        lut.set_track_determinant(false);
        // Deterministic start with content in every wave number.
        let v: Vec<f64> = (0..n)
            .map(|i| ((i as f64 * 0.618_033_988_75).fract() - 0.5) + 0.1)
            .collect();
        Ok(Self {
            lu,
            lut,
            vt: vec![0.0; tmap.len()],
            tmap,
            v,
        })
    }

    /// (σ_min, negative eigenvalue count if known). `iters` inverse iterations.
    fn probe(&mut self, st: &SteadyRolling, iters: usize) -> Result<(f64, Option<usize>), String> {
        let vals = st.sys.matrix_values();
        self.lu.factorize(vals).map_err(|e| e.to_string())?;
        for (k, &p) in self.tmap.iter().enumerate() {
            self.vt[k] = vals[p];
        }
        self.lut.factorize(&self.vt).map_err(|e| e.to_string())?;
        let neg = self.lu.negative_eigenvalues();
        let mut sigma = f64::NAN;
        let nrm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let n0 = nrm(&self.v).max(f64::MIN_POSITIVE);
        self.v.iter_mut().for_each(|x| *x /= n0);
        for _ in 0..iters {
            // w = K⁻¹ K⁻ᵀ v
            let mut w = self.v.clone();
            self.lut.solve_in_place(&mut w).map_err(|e| e.to_string())?;
            self.lu.solve_in_place(&mut w).map_err(|e| e.to_string())?;
            let nw = nrm(&w);
            if !nw.is_finite() || nw == 0.0 {
                return Ok((0.0, neg));
            }
            sigma = (1.0 / nw).sqrt();
            self.v = w.into_iter().map(|x| x / nw).collect();
        }
        Ok((sigma, neg))
    }
}

/// Newton for the sweeps in ω, from the run's plan (`st.plan`, built once from the scene):
/// its tolerance and line search, at least 25 iterations, and always the sparse LU in double
/// precision, whose determinant's sign the sweeps read (the plan may hold a Cholesky or
/// single-precision factors).
fn newton_for(st: &SteadyRolling, verbose: bool) -> Result<Newton, AppError> {
    let plan = st.plan.verbose(verbose);
    let opts = NewtonOptions {
        max_iterations: plan.newton.max_iterations.max(25),
        mixed_precision: false,
        single_precision_preconditioner: false,
        ..plan.newton
    };
    Newton::new(st, LinearKind::Lu, opts)
        .map_err(|e| AppError::Unsupported(format!("critical: {e}")))
}

fn solve_err(e: SolveError, what: String) -> AppError {
    AppError::Unsupported(format!("critical: {what}: {e}"))
}

/// Check the options a user gives (`tread critical` flags) before any work: a clear error
/// naming the flag instead of a search over an empty or non-finite range.
fn check_options(opts: &CriticalOptions) -> Result<(), AppError> {
    let bad = |m: String| Err(AppError::Unsupported(format!("critical: {m}")));
    if let Some(w) = opts.omega_max {
        if !w.is_finite() || w <= 0.0 {
            return bad(format!(
                "--omega-max must be a finite speed > 0 (rad/s), got {w}"
            ));
        }
    }
    if opts.n_max == Some(0) {
        return bad("--n-max must be at least 1 (wave numbers start at 1)".into());
    }
    if let (Some(lo), Some(hi)) = (opts.n_min, opts.n_max) {
        if lo > hi {
            return bad(format!(
                "--n-min {lo} exceeds --n-max {hi}: no wave number to search"
            ));
        }
    }
    Ok(())
}

/// Locate the critical speeds of a scene (see the module docs).
pub fn run(scene: &Scene, opts: &CriticalOptions) -> Result<CriticalReport, AppError> {
    check_options(opts)?;
    let t0 = std::time::Instant::now();
    let mut scene = scene.clone();
    if opts.no_contact {
        scene.road = None;
        scene.contact = None;
    }
    let spinning = scene.road.is_none() || scene.contact.is_none();
    let mut st = build_steady(&scene)?;
    let g = st.sys.model.material.small_strain_shear_modulus();
    let rho = st.sys.model.rho;
    let ro = scene.geometry.ro;
    if !(rho > 0.0 && g > 0.0) {
        return Err(AppError::Unsupported(
            "critical: material.rho and the shear modulus must be positive".into(),
        ));
    }
    let omega_r = 0.955 * (g / rho).sqrt() / ro;
    let rg = rings_of(&st)?;
    let n_resolved = rg.n_theta / 2;
    let mut report = CriticalReport {
        omega_crit: None,
        n_star: None,
        crossings: Vec::new(),
        kind: if spinning { "spinning" } else { "rolling" },
        density: rho,
        shear_modulus: g,
        omega_rayleigh_estimate: omega_r,
        omega_max: 0.0,
        n_resolved,
        not_crossed: Vec::new(),
        unresolved_crossings: Vec::new(),
        full_operator: None,
        sweep: Vec::new(),
        branch_end: None,
        end_reason: "target_reached",
        omega_covered: f64::NAN,
        hermitian_defect: 0.0,
        wall_time_s: 0.0,
    };
    if spinning {
        spinning_critical(opts, &mut st, rg, &mut report)?;
        report.omega_covered = report.omega_max;
    } else {
        rolling_critical(&scene, opts, &mut st, &mut report)?;
    }
    report.wall_time_s = t0.elapsed().as_secs_f64();
    Ok(report)
}

fn spinning_critical(
    opts: &CriticalOptions,
    st: &mut SteadyRolling,
    rg: Rings,
    report: &mut CriticalReport,
) -> Result<(), AppError> {
    if st.sys.dofs.n_eq
        != st
            .sys
            .dofs
            .eq
            .iter()
            .take(st.sys.dofs.n_u)
            .filter(|&&e| e < CONSTRAINED)
            .count()
    {
        return Err(AppError::Unsupported(
            "critical: the Fourier reduction needs a displacement-only model (material.model = \"mooney_rivlin\" or \"neo_hookean\", or formulation = \"perturbed\")".into(),
        ));
    }
    // The conservative operator: no strain-rate damping.
    st.sys.model.strain_rate_damping = 0.0;
    st.sys.steady_visc = None;
    let omega_max = opts
        .omega_max
        .unwrap_or(2.0 * report.omega_rayleigh_estimate);
    report.omega_max = omega_max;
    let n_max = opts
        .n_max
        .unwrap_or(report.n_resolved)
        .min(report.n_resolved);
    if let Some(lo) = opts.n_min.filter(|&lo| lo > n_max) {
        return Err(AppError::Unsupported(format!(
            "critical: --n-min {lo} exceeds the largest wave number searched, {n_max} (the mesh \
             resolves n <= n_theta / 2 = {})",
            report.n_resolved
        )));
    }
    let samples = opts.samples.max(4);
    // Reference force for Newton: the centrifugal load at omega_max on the undeformed body.
    st.set_omega(omega_max, 0.0);
    let f = st.sys.residual_norm().max(f64::MIN_POSITIVE);
    st.sys.set_reference_force(f);
    let mut newton = newton_for(st, opts.verbose)?;
    let dw = omega_max / samples as f64;
    let mut states: Vec<Vec<f64>> = Vec::new();
    let mut omegas = Vec::new();
    let mut fvals: Vec<Vec<(f64, f64)>> = Vec::new();
    for k in 1..=samples {
        let w = dw * k as f64;
        solve_at(st, &mut newton, w)
            .map_err(|e| solve_err(e, format!("spun state at {w} rad/s")))?;
        let rows = sector_rows(st, &rg);
        let mut fv = vec![(f64::INFINITY, f64::INFINITY); n_max + 1];
        for (n, f) in fv
            .iter_mut()
            .enumerate()
            .skip(opts.n_min.unwrap_or(1).max(1))
        {
            let (own, alias, d) = bloch_lambda_min(&rows, &rg, n);
            *f = (own, alias);
            report.hermitian_defect = report.hermitian_defect.max(d);
        }
        if opts.verbose {
            let m = fv[1..]
                .iter()
                .map(|f| f.0.min(f.1))
                .fold(f64::INFINITY, f64::min);
            eprintln!("critical: omega = {w:.4}: smallest scaled eigenvalue over n = {m:.3e}");
        }
        let mut x = Vec::new();
        st.save_state(&mut x);
        states.push(x);
        omegas.push(w);
        fvals.push(fv);
    }
    // Refine each wave number's first crossing (and its alias's).
    let n_min = opts.n_min.unwrap_or(1).max(1);
    for n in n_min..=n_max {
        for alias in [false, true] {
            let fk: Vec<f64> = fvals
                .iter()
                .map(|f| if alias { f[n].1 } else { f[n].0 })
                .collect();
            let mut eval = |w: f64, k: usize| -> Result<f64, AppError> {
                st.restore_state(&states[k]);
                solve_at(st, &mut newton, w)
                    .map_err(|e| solve_err(e, format!("spun state at {w} rad/s")))?;
                let rows = sector_rows(st, &rg);
                let (own, al, _) = bloch_lambda_min(&rows, &rg, n);
                Ok(if alias { al } else { own })
            };
            match (refine_crossing(&omegas, &fk, &mut eval)?, alias) {
                (Some(w), false) => report.crossings.push(Crossing { n, omega: w }),
                (Some(w), true) => report.unresolved_crossings.push(Crossing {
                    n: rg.n_theta - n,
                    omega: w,
                }),
                (None, false) => report.not_crossed.push(n),
                (None, true) => {}
            }
        }
    }
    report.unresolved_crossings.sort_by_key(|c| c.n);
    let lowest = report
        .crossings
        .iter()
        .chain(&report.unresolved_crossings)
        .min_by(|a, b| a.omega.total_cmp(&b.omega));
    if let Some(c) = lowest {
        report.omega_crit = Some(c.omega);
        report.n_star = Some(c.n);
    }
    // Full-operator check at ω*.
    if let Some(ws) = report.omega_crit {
        let k0 = omegas.iter().rposition(|&w| w < ws).unwrap_or(0);
        let start = states[k0].clone();
        let mut probe = SingularProbe::new(st)?;
        let mut at = |w: f64, iters: usize| -> Result<(f64, Option<usize>), AppError> {
            st.restore_state(&start);
            solve_at(st, &mut newton, w)
                .map_err(|e| solve_err(e, format!("spun state at {w} rad/s")))?;
            probe
                .probe(st, iters)
                .map_err(|e| AppError::Unsupported(format!("critical: {e}")))
        };
        let (s09, _) = at(0.9 * ws, 30)?;
        let (_, below) = at(ws * (1.0 - 1e-3), 1)?;
        let (_, above) = at(ws * (1.0 + 1e-3), 1)?;
        let (s0, _) = at(ws, 30)?;
        let null_n = dominant_wave_number(st, &probe.v);
        report.full_operator = Some(FullOperatorCheck {
            omega: ws,
            negative_below: below,
            negative_above: above,
            sigma_min: s0,
            sigma_min_at_0_9: s09,
            sigma_ratio: s0 / s09,
            null_mode_n: null_n,
        });
    }
    Ok(())
}

fn rolling_critical(
    scene: &Scene,
    opts: &CriticalOptions,
    st: &mut SteadyRolling,
    report: &mut CriticalReport,
) -> Result<(), AppError> {
    let omega_max = opts
        .omega_max
        .unwrap_or(1.6 * report.omega_rayleigh_estimate);
    report.omega_max = omega_max;
    let mut rec = ();
    let mut steps = StepReport::default();
    solve_steady(scene, st, opts.verbose, &mut steps, &mut rec)
        .map_err(|f| solve_err(f.error, "steady state at the scene's speed".into()))?;
    let mut newton = newton_for(st, opts.verbose)?;
    let mut probe = SingularProbe::new(st)?;
    let w0 = st.omega();
    let samples = opts.samples.max(4);
    let dw = (omega_max - w0) / samples as f64;
    // Also refuses a NaN end (a NaN comparison is false).
    if dw.is_nan() || dw <= 0.0 {
        return Err(AppError::Unsupported(format!(
            "critical: the search end {omega_max} rad/s must exceed the scene's motion.omega = {w0}"
        )));
    }
    let mut states: Vec<Vec<f64>> = Vec::new();
    let mut sig: Vec<f64> = Vec::new();
    let mut om: Vec<f64> = Vec::new();
    // March in ω; where Newton fails, halve the step from the last converged speed (down to
    // dw / 512) to approach the end of the branch, and double it again after two successes.
    let (mut w, mut step, mut ok_run) = (w0, dw, 0usize);
    while w <= omega_max * (1.0 + 1e-12) {
        if let Err(e) = solve_at(st, &mut newton, w) {
            let Some(x) = states.last() else {
                return Err(solve_err(e, format!("steady state at {w} rad/s")));
            };
            st.restore_state(x);
            let wl = *om.last().unwrap_or(&w0);
            if step > dw / 512.0 {
                step *= 0.5;
                ok_run = 0;
                w = wl + step;
                continue;
            }
            report.branch_end = Some(format!(
                "Newton did not converge at {w:.6} rad/s ({e}) with the speed step halved to {step:.3e} rad/s; the steady branch ends between {wl:.6} and {w:.6} rad/s"
            ));
            report.end_reason = "newton_failed";
            break;
        }
        let (s, neg) = probe
            .probe(st, 30)
            .map_err(|e| AppError::Unsupported(format!("critical: {e}")))?;
        let (f, _) = st.sys.hub_reaction();
        report.sweep.push(SweepRow {
            omega: w,
            sigma_min: s,
            n_dominant: dominant_wave_number(st, &probe.v),
            negative_eigenvalues: neg,
            hub_force_x: f[0],
            hub_force_y: f[1],
        });
        if opts.verbose {
            eprintln!("critical: omega = {w:.4}: sigma_min = {s:.4e}, neg = {neg:?}");
        }
        let mut x = Vec::new();
        st.save_state(&mut x);
        states.push(x);
        sig.push(s);
        om.push(w);
        ok_run += 1;
        if ok_run >= 2 && step < dw {
            step = (2.0 * step).min(dw);
            ok_run = 0;
        }
        w += step;
    }
    report.omega_covered = if report.end_reason == "target_reached" {
        omega_max
    } else {
        om.last().copied().unwrap_or(w0)
    };
    let s_ref = sig.first().copied().unwrap_or(f64::NAN);
    // Symmetric tangent (no friction, no damping): a change of the inertia between two
    // speeds brackets a crossing; located by bisection on the negative-eigenvalue count.
    for k in 1..sig.len() {
        let (Some(na), Some(nb)) = (
            report.sweep[k - 1].negative_eigenvalues,
            report.sweep[k].negative_eigenvalues,
        ) else {
            continue;
        };
        if na == nb {
            continue;
        }
        let (mut a, mut b) = (om[k - 1], om[k]);
        let mut n_upper = report.sweep[k].n_dominant;
        for _ in 0..14 {
            let c = 0.5 * (a + b);
            st.restore_state(&states[k - 1]);
            if solve_at(st, &mut newton, c).is_err() {
                break;
            }
            let Ok((_, nc)) = probe.probe(st, 30) else {
                break;
            };
            if nc == Some(na) {
                a = c;
            } else {
                b = c;
                n_upper = dominant_wave_number(st, &probe.v);
            }
        }
        report.crossings.push(Crossing {
            n: n_upper,
            omega: 0.5 * (a + b),
        });
    }

    // Local minima of σ_min (interior, or a sign change of the inertia) refined by
    // golden-section search.
    for k in 1..sig.len().saturating_sub(1) {
        let inertia_jump = match (
            report.sweep[k - 1].negative_eigenvalues,
            report.sweep[k + 1].negative_eigenvalues,
        ) {
            (Some(a), Some(b)) => a != b,
            _ => false,
        };
        if !(sig[k] <= sig[k - 1] && sig[k] <= sig[k + 1]) || inertia_jump {
            continue;
        }
        let (mut a, mut b) = (om[k - 1], om[k + 1]);
        let start = states[k - 1].clone();
        let gr = 0.5 * (5f64.sqrt() - 1.0);
        let mut eval = |w: f64, st: &mut SteadyRolling, probe: &mut SingularProbe| -> Option<f64> {
            st.restore_state(&start);
            solve_at(st, &mut newton, w).ok()?;
            probe.probe(st, 12).ok().map(|r| r.0)
        };
        let (mut c, mut d) = (b - gr * (b - a), a + gr * (b - a));
        let (Some(mut fc), Some(mut fd)) = (eval(c, st, &mut probe), eval(d, st, &mut probe))
        else {
            continue;
        };
        for _ in 0..30 {
            if fc < fd {
                b = d;
                d = c;
                fd = fc;
                c = b - gr * (b - a);
                match eval(c, st, &mut probe) {
                    Some(v) => fc = v,
                    None => break,
                }
            } else {
                a = c;
                c = d;
                fc = fd;
                d = a + gr * (b - a);
                match eval(d, st, &mut probe) {
                    Some(v) => fd = v,
                    None => break,
                }
            }
            if (b - a) < 1e-7 * b {
                break;
            }
        }
        let w = 0.5 * (a + b);
        let Some(s) = eval(w, st, &mut probe) else {
            continue;
        };
        let rel = s / s_ref;
        if rel < 1e-3 {
            report.crossings.push(Crossing {
                n: dominant_wave_number(st, &probe.v),
                omega: w,
            });
        }
    }
    if let Some(x) = states.last() {
        st.restore_state(x);
    }
    report.crossings.sort_by(|a, b| a.omega.total_cmp(&b.omega));
    if let Some(c) = report.crossings.first() {
        report.omega_crit = Some(c.omega);
        report.n_star = Some(c.n);
    }
    Ok(())
}

/// Write `dir/critical.json` (and `dir/crossings.csv`, `dir/sweep.csv`).
pub fn write(report: &CriticalReport, dir: &std::path::Path) -> Result<(), AppError> {
    use crate::io::output::{ensure_dir, write_csv, write_json};
    ensure_dir(dir)?;
    let v = serde_json::to_value(report).map_err(|e| {
        AppError::Unsupported(format!("critical: cannot serialise the report: {e}"))
    })?;
    write_json(&dir.join("critical.json"), &v)?;
    write_csv(
        &dir.join("crossings.csv"),
        &["n", "omega"],
        report.crossings.iter().map(|c| vec![c.n as f64, c.omega]),
    )?;
    if !report.sweep.is_empty() {
        write_csv(
            &dir.join("sweep.csv"),
            &[
                "omega",
                "sigma_min",
                "n_dominant",
                "negative_eigenvalues",
                "hub_force_x",
                "hub_force_y",
            ],
            report.sweep.iter().map(|r| {
                vec![
                    r.omega,
                    r.sigma_min,
                    r.n_dominant as f64,
                    r.negative_eigenvalues.map_or(-1.0, |v| v as f64),
                    r.hub_force_x,
                    r.hub_force_y,
                ]
            }),
        )?;
    }
    Ok(())
}

/// One-line summary for the terminal.
pub fn headline(r: &CriticalReport) -> String {
    let found = match (r.omega_crit, r.n_star) {
        (Some(w), Some(n)) => Some(format!(
            "critical speed ({}): {w:.6} rad/s ({:.2} rpm), wave number n* = {n}; {} crossings, Rayleigh estimate {:.4} rad/s",
            r.kind,
            w * 30.0 / PI,
            r.crossings.len(),
            r.omega_rayleigh_estimate
        )),
        _ => None,
    };
    if r.kind != "rolling" {
        return found.unwrap_or_else(|| {
            format!(
                "no singular point below {:.4} rad/s ({})",
                r.omega_max, r.kind
            )
        });
    }
    let (Some(first), Some(last)) = (r.sweep.first(), r.sweep.last()) else {
        return found.unwrap_or_else(|| "no speed of the rolling branch converged".into());
    };
    let covered = r.omega_covered;
    let search = match found {
        Some(f) => f,
        None => format!(
            "no singular point found between {:.4} and {:.4} rad/s (rolling)",
            first.omega, covered
        ),
    };
    let end = if r.end_reason == "newton_failed" {
        format!(
            "the steady branch ended at {:.4} rad/s, short of the {:.4} rad/s searched: Newton did not converge at the next speed even with the speed step halved to 1/512 of the sampling step",
            covered, r.omega_max
        )
    } else {
        format!(
            "the branch was followed to the end of the search, {:.4} rad/s",
            r.omega_max
        )
    };
    let low = r
        .sweep
        .iter()
        .min_by(|a, b| a.sigma_min.total_cmp(&b.sigma_min))
        .unwrap_or(last);
    let trend = format!(
        "smallest singular value of the tangent {} at {:.4} rad/s, {} at {:.4} rad/s{}",
        sig3(first.sigma_min),
        first.omega,
        sig3(last.sigma_min),
        last.omega,
        if low.omega != last.omega && low.omega != first.omega {
            format!(
                " (lowest {} at {:.4} rad/s)",
                sig3(low.sigma_min),
                low.omega
            )
        } else {
            String::new()
        }
    );
    let falling = last.sigma_min < 0.1 * first.sigma_min && r.end_reason == "newton_failed";
    format!(
        "{search}; {end}; {trend}{}",
        if falling {
            ": it fell by a factor of more than 10 toward the end of the branch, where the tangent is close to singular"
        } else {
            ""
        }
    )
}

/// Three significant digits.
fn sig3(x: f64) -> String {
    if x.is_finite() && x != 0.0 && (1e-3..1e5).contains(&x.abs()) {
        let dec = (2 - x.abs().log10().floor() as i32).max(0) as usize;
        format!("{x:.dec$}")
    } else {
        format!("{x:.2e}")
    }
}
