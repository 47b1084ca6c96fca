//! What the recovery of a failed steady solve did ([`super::steady_recovery`]): the strategies,
//! the parameters their homotopy legs walk, and the [`Recovery`] report the steady driver keeps
//! (`summary.json`: `solver.recovery`). Data only, so that the steady state
//! ([`super::steady::SteadyRolling`]) can hold a report without depending on the algorithm.
//!
//! Units are the scene's: ω in rad/s, κ and G as the material's moduli, ε as a velocity;
//! wall times in seconds.

/// A parameter a homotopy walks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HomotopyParameter {
    /// Angular speed ω, with the road speed v0 = (v0/ω)_scene · ω.
    Omega,
    /// Bulk modulus κ (compressible Mooney–Rivlin) or penalty κ (perturbed incompressible).
    Kappa,
    /// Friction regularisation velocity ε.
    Eps,
}

impl std::fmt::Display for HomotopyParameter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            HomotopyParameter::Omega => "omega",
            HomotopyParameter::Kappa => "kappa",
            HomotopyParameter::Eps => "eps",
        })
    }
}

/// How a leg spaces its values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Spacing {
    /// value = from + s (to − from).
    Linear,
    /// value = from (to / from)^s (both > 0).
    Geometric,
}

/// A recovery strategy (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Strategy {
    KappaHomotopy,
    EpsHomotopy,
    OmegaStepping,
    Combined,
}

impl std::fmt::Display for Strategy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Strategy::KappaHomotopy => "kappa_homotopy",
            Strategy::EpsHomotopy => "eps_homotopy",
            Strategy::OmegaStepping => "omega_stepping",
            Strategy::Combined => "combined",
        })
    }
}

/// What one leg did.
#[derive(Clone, Debug, serde::Serialize)]
pub struct LegReport {
    pub parameter: HomotopyParameter,
    pub spacing: Spacing,
    pub from: f64,
    pub to: f64,
    /// Converged steps.
    pub steps: usize,
    /// Halvings of Δs (failed steps, secant retries not counted).
    pub cutbacks: usize,
    pub newton_iterations: usize,
    /// Last converged value (= `to` when the leg succeeded).
    pub reached: f64,
}

/// One attempt of a strategy.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Attempt {
    pub strategy: Strategy,
    pub succeeded: bool,
    /// Why it failed.
    pub error: Option<String>,
    /// Converged load steps and cut-backs of the press at the benign values.
    pub press_steps: usize,
    pub press_cutbacks: usize,
    pub legs: Vec<LegReport>,
    pub newton_iterations: usize,
    pub wall_time_s: f64,
}

impl Attempt {
    /// Converged steps (press and legs).
    pub fn steps(&self) -> usize {
        self.press_steps + self.legs.iter().map(|l| l.steps).sum::<usize>()
    }
    /// Cut-backs (press and legs).
    pub fn cutbacks(&self) -> usize {
        self.press_cutbacks + self.legs.iter().map(|l| l.cutbacks).sum::<usize>()
    }
}

/// How the steady solve started from the steady state of a coarser mesh (`summary.json`:
/// `solver.coarse_start`; `[solver] coarse_start`).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct CoarseStart {
    /// The coarser meshes solved first, coarsest first, as `n_r x n_theta`.
    pub meshes: Vec<String>,
    /// Newton iterations on the coarser meshes (all of them).
    pub coarse_newton_iterations: usize,
    /// Wall time of the coarser meshes' set-up and solves and of the interpolation (not of
    /// this mesh's symbolic analysis, which runs alongside the coarse solve when the thread
    /// pool has a second worker, and after it otherwise; with a second worker `tread run`
    /// also builds this mesh's system while the coarser ones are solved).
    pub coarse_wall_time_s: f64,
    /// Newton iterations on this mesh from the interpolated state.
    pub newton_iterations: usize,
    /// Whether Newton converged from the interpolated state (if not, the press-in from the
    /// undeformed state followed).
    pub succeeded: bool,
    /// Why it did not.
    pub error: Option<String>,
}

/// What the recovery did (`summary.json`: `solver.recovery`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Recovery {
    /// The failure of the direct solve that started the recovery.
    pub direct_error: String,
    /// The strategy that succeeded (`None`: every attempt failed).
    pub strategy: Option<Strategy>,
    /// Every strategy tried, in order.
    pub attempts: Vec<Attempt>,
    /// Newton iterations over all attempts.
    pub newton_iterations: usize,
    /// Cut-backs over all attempts.
    pub cutbacks: usize,
    pub wall_time_s: f64,
    /// One line for a person (printed to stderr by the driver).
    pub message: String,
}

impl Recovery {
    pub fn succeeded(&self) -> bool {
        self.strategy.is_some()
    }

    pub(super) fn describe(&self) -> String {
        let Some(ok) = self.attempts.iter().find(|a| a.succeeded) else {
            let tried: Vec<String> = self
                .attempts
                .iter()
                .map(|a| {
                    format!(
                        "{} ({})",
                        a.strategy,
                        a.error.as_deref().unwrap_or("no error recorded")
                    )
                })
                .collect();
            return if tried.is_empty() {
                format!(
                    "the steady solve failed ({}) and no recovery strategy applies",
                    self.direct_error
                )
            } else {
                format!(
                    "the steady solve failed ({}); recovery failed too: {}",
                    self.direct_error,
                    tried.join("; ")
                )
            };
        };
        let legs: Vec<String> = ok
            .legs
            .iter()
            .map(|l| {
                format!(
                    "{} from {:.6e} to {:.6e} in {} steps ({} cut-backs)",
                    l.parameter, l.from, l.to, l.steps, l.cutbacks
                )
            })
            .collect();
        let before: Vec<String> = self
            .attempts
            .iter()
            .filter(|a| !a.succeeded)
            .map(|a| a.strategy.to_string())
            .collect();
        format!(
            "the direct steady solve failed ({}); recovered by {}: pressed in at the benign \
             values in {} load steps, then {}{}; {} Newton iterations in {:.2} s",
            self.direct_error,
            ok.strategy,
            ok.press_steps,
            legs.join(", then "),
            if before.is_empty() {
                String::new()
            } else {
                format!(" (tried first, failed: {})", before.join(", "))
            },
            self.newton_iterations,
            self.wall_time_s
        )
    }
}

/// What the first steady solve did besides the press (`summary.json`: `solver.recovery`,
/// `solver.eps_continuation`, `solver.coarse_start`, `terms.damping_tangent_fallback`), returned
/// by the solve whether it succeeded or not.
#[derive(Clone, Debug, Default)]
pub struct SolveReports {
    /// The recovery strategies tried after the press failed.
    pub recovery: Option<Recovery>,
    /// The continuation down to the scene's small friction regularisation.
    pub eps_continuation: Option<Attempt>,
    /// The nested iteration's start from a coarser mesh.
    pub coarse_start: Option<CoarseStart>,
    /// Why the damping tangent differs from the one asked for (set when the system was built,
    /// or when the fast tangent's press failed and the assembled one was used).
    pub damping_fallback: Option<String>,
}

impl SolveReports {
    /// Newton iterations of the recovery (outside the press's own report).
    pub fn recovery_iterations(&self) -> usize {
        self.recovery.as_ref().map_or(0, |r| r.newton_iterations)
    }

    /// Converged steps of the path that found the solution, when a recovery or the ε
    /// continuation found it (`None`: the press did).
    pub fn solution_steps(&self) -> Option<usize> {
        self.recovery
            .as_ref()
            .and_then(|r| r.attempts.iter().find(|a| a.succeeded))
            .or(self.eps_continuation.as_ref().filter(|a| a.succeeded))
            .map(Attempt::steps)
    }
}

/// A failed steady solve: why, and what it tried.
#[derive(Debug)]
pub struct SteadyFailure {
    pub error: crate::solver::SolveError,
    pub reports: Box<SolveReports>,
}

impl std::fmt::Display for SteadyFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.error.fmt(f)
    }
}

impl std::error::Error for SteadyFailure {}
