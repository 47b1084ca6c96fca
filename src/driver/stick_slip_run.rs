//! Driver of the `stick_slip` mode: the spring–mass block on a moving belt (paper §4) from the
//! scene's `[stick_slip]` and `[friction]` sections; writes summary.json with the measured period
//! and slip amplitude, and the closed-form static/kinetic cycle for comparison when the law is
//! rate dependent.
//!
//! Recording: diffsol integrates the whole interval first; then every output sample is sent to
//! the recorder as a step (time = t, no mesh, scalars `x`, `v`, `friction_force`, `slipping`),
//! so `history.csv` (CSV sink), `run.mcap`, `run.rrd` and `series.png` carry the time history.
//! An interrupt stops the replay at a sample.

use super::envelope::{RunClock, RunEnvelope};
use crate::contact::stick_slip::{
    closed_form_cycle, simulate, supported_law_list, Phase, StickSlipSpec,
};
use crate::contact::Friction;
use crate::driver::results::RunOutcome;
use crate::driver::results::{
    ModeSummary, RunStats, StickSlipResults, StickSlipSummary, Summary, Terms,
};
use crate::io::output::ensure_dir;
use crate::io::record::{self, Recorder, StepInfo, StepView};
use crate::io::scene::{stick_slip_law, Scene};
use crate::setup::{AppError, RunOptions};
use std::time::Instant;

pub fn run(scene: &Scene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    let t0 = Instant::now();
    ensure_dir(&opts.out_dir)?;
    let Some(ss) = &scene.stick_slip else {
        return Err(AppError::Unsupported(
            "mode \"stick_slip\" needs the [stick_slip] section".into(),
        ));
    };
    let friction = match scene.friction.params() {
        Some(f) if stick_slip_law(f.kind()) => f,
        _ => {
            return Err(AppError::Unsupported(format!(
                "friction.law: stick_slip needs {}",
                supported_law_list()
            )))
        }
    };
    // The closed-form static/kinetic cycle exists for the rate-dependent law.
    let static_kinetic = match friction {
        Friction::RateDependent(l) => Some((l.mu_s, l.mu_k)),
        _ => None,
    };
    let spec = StickSlipSpec {
        mass: ss.mass,
        stiffness: ss.stiffness,
        normal_force: ss.normal_force,
        belt_speed: ss.belt_speed,
        t_end: ss.t_end,
        rtol: ss.rtol,
        atol: ss.atol,
        friction,
        x0: ss.x0,
        v0: ss.v0.unwrap_or(ss.belt_speed),
        output_interval: ss.output_interval.unwrap_or(ss.t_end / 2000.0),
        stick_threshold: StickSlipSpec::suggested_stick_threshold(&friction, ss.belt_speed),
    };
    let clock = RunClock {
        mesh: None,
        time_name: "time",
        time_end: ss.t_end,
    };
    let mut env = RunEnvelope::open(scene, opts, clock, Vec::new())?;
    let recorders = &mut env.recorders;
    let res = simulate(&spec);
    let mut interrupted = false;
    let mut steps = 0u64;
    if let Ok(r) = &res {
        let n = r.samples.len();
        for (i, smp) in r.samples.iter().enumerate() {
            if record::interrupted() {
                interrupted = true;
                break;
            }
            let info = StepInfo {
                index: i as u64,
                time: smp.t,
                dt: if i > 0 {
                    smp.t - r.samples[i - 1].t
                } else {
                    0.0
                },
                newton_iterations: 0,
                residual: 0.0,
                is_final: i + 1 == n,
            };
            let scalars = [
                ("x", smp.x),
                ("v", smp.v),
                ("friction_force", smp.friction_force),
                ("slipping", f64::from(u8::from(smp.phase == Phase::Slip))),
            ];
            let view = StepView {
                mesh: None,
                x: &[],
                stress: &[],
                sigma_33: &[],
                stress_recovered: &[],
                error_indicator: &[],
                pressure: &[],
                contact: &[],
                hub: None,
                energy: None,
                road_height: None,
                omega: 0.0,
                scalars: &scalars,
            };
            let wants = recorders.wants_view(&info);
            recorders.step(&info, wants.then_some(&view));
            steps += 1;
        }
    }
    let wall = t0.elapsed().as_secs_f64();
    let (converged, error) = match (&res, interrupted) {
        (_, true) => (false, Some("interrupted".to_string())),
        (Ok(_), false) => (true, None),
        (Err(e), false) => (false, Some(e.to_string())),
    };
    let closed = static_kinetic.map(|(mu_s, mu_k)| {
        closed_form_cycle(
            ss.mass,
            ss.stiffness,
            ss.normal_force,
            ss.belt_speed,
            mu_s,
            mu_k,
        )
    });
    let mut headline = Vec::new();
    let results = match &res {
        Ok(r) => {
            let opt = |v: Option<f64>| {
                v.map_or(
                    "not measured (fewer than two cycles)".to_string(),
                    crate::io::output::fmt_num,
                )
            };
            headline.push(format!(
                "period = {} s, slip amplitude = {}, {} steps",
                opt(r.period),
                opt(r.amplitude),
                r.stats.steps
            ));
            let closed = closed.as_ref().and_then(|c| c.as_ref().ok());
            Some(StickSlipResults {
                period: r.period,
                amplitude: r.amplitude,
                x_min: r.x_min,
                x_max: r.x_max,
                stick_time: r.stick_time,
                slip_time: r.slip_time,
                cycles: r.stick_to_slip.len(),
                solver_stats: r.stats,
                period_rel_error: closed.zip(r.period).map(|(c, p)| (p - c.period) / c.period),
                amplitude_rel_error: closed
                    .zip(r.amplitude)
                    .map(|(c, a)| (a - c.amplitude) / c.amplitude),
                closed_form: closed.copied(),
            })
        }
        Err(_) => None,
    };
    let typed = Summary::new(
        &scene.scene.name,
        scene.analysis.mode.to_string(),
        2,
        converged,
        ModeSummary::StickSlip(StickSlipSummary {
            run: RunStats {
                newton_iterations: res.as_ref().map(|r| r.stats.newton_iterations).unwrap_or(0),
                wall_time_s: wall,
                error: error.clone(),
            },
            results,
            // One mass on a belt: friction and inertia, nothing else (no mesh, no contact
            // facets).
            terms: Terms {
                friction: true,
                normal_damping: false,
                inertia: true,
                history: false,
                pressure: false,
                contact_facets_per_iteration: 0.0,
            },
        }),
    );
    let summary = env.finish(&typed, steps, wall, error.as_deref(), interrupted)?;
    if interrupted {
        return Err(AppError::Interrupted(opts.out_dir.clone()));
    }
    match res {
        Ok(_) => Ok(RunOutcome {
            summary,
            typed,
            field: None,
            history: None,
            contact: Vec::new(),
            out_dir: opts.out_dir.clone(),
            converged,
            headline,
        }),
        Err(e) => Err(AppError::Failed(
            format!("stick-slip integration failed: {e}"),
            opts.out_dir.clone(),
        )),
    }
}
