//! Driver of the `stick_slip` mode: the spring–mass block on a moving belt (paper §4) from the
//! scene's `[stick_slip]` and `[friction]` sections; writes `history.csv` and summary.json with
//! the measured period and slip amplitude, and the closed-form static/kinetic cycle for
//! comparison when the law is rate dependent.

use crate::app::{AppError, RunOptions, RunOutcome};
use crate::contact::laws::{CoulombLinear, CoulombTanh, RateDependent};
use crate::contact::stick_slip::{closed_form_cycle, simulate, Phase, StickSlipSpec};
use crate::contact::Friction;
use crate::io::output::{ensure_dir, sanitize, write_csv, write_json};
use crate::io::scene::{FrictionParams, Scene};
use std::time::Instant;

pub fn run(scene: &Scene, opts: &RunOptions) -> Result<RunOutcome, AppError> {
    let t0 = Instant::now();
    ensure_dir(&opts.out_dir)?;
    let Some(ss) = &scene.stick_slip else {
        return Err(AppError::Unsupported(
            "mode \"stick_slip\" needs the [stick_slip] section".into(),
        ));
    };
    let (friction, static_kinetic) = match scene.friction.params() {
        Some(FrictionParams::CoulombTanh { mu, eps }) => {
            (Friction::CoulombTanh(CoulombTanh::new(mu, eps)), None)
        }
        Some(FrictionParams::CoulombLinear { mu, eps }) => {
            (Friction::CoulombLinear(CoulombLinear::new(mu, eps)), None)
        }
        Some(FrictionParams::RateDependent {
            mu_s,
            mu_k,
            v_s,
            eps,
        }) => (
            Friction::RateDependent(RateDependent::new(mu_s, mu_k, v_s, eps)),
            Some((mu_s, mu_k)),
        ),
        _ => {
            return Err(AppError::Unsupported(
                "friction.law: stick_slip needs coulomb_tanh, coulomb_linear or rate_dependent"
                    .into(),
            ))
        }
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
    let res = simulate(&spec);
    let wall = t0.elapsed().as_secs_f64();
    let (converged, error) = match &res {
        Ok(_) => (true, None),
        Err(e) => (false, Some(e.to_string())),
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
            headline.push(format!(
                "period = {:?}, slip amplitude = {:?}, {} steps",
                r.period, r.amplitude, r.stats.steps
            ));
            serde_json::json!({
                "period": r.period,
                "amplitude": r.amplitude,
                "x_min": r.x_min,
                "x_max": r.x_max,
                "stick_time": r.stick_time,
                "slip_time": r.slip_time,
                "cycles": r.stick_to_slip.len(),
                "solver_stats": r.stats,
                "period_rel_error": closed.as_ref().and_then(|c| c.as_ref().ok()).zip(r.period).map(|(c, p)| (p - c.period) / c.period),
                "amplitude_rel_error": closed.as_ref().and_then(|c| c.as_ref().ok()).zip(r.amplitude).map(|(c, a)| (a - c.amplitude) / c.amplitude),
                "closed_form": closed.as_ref().and_then(|c| c.as_ref().ok()).map(|c| serde_json::to_value(c).unwrap_or_default()),
            })
        }
        Err(_) => serde_json::Value::Null,
    };
    let mut summary = serde_json::json!({
        "scene": scene.scene.name,
        "mode": scene.analysis.mode.to_string(),
        "dofs": 2,
        "newton_iterations": res.as_ref().map(|r| r.stats.newton_iterations).unwrap_or(0),
        "wall_time_s": wall,
        "converged": converged,
        "error": error,
        "results": results,
        "version": env!("CARGO_PKG_VERSION"),
    });
    sanitize(&mut summary);
    write_json(&opts.out_dir.join("summary.json"), &summary)?;
    if let Ok(r) = &res {
        write_csv(
            &opts.out_dir.join("history.csv"),
            &["t", "x", "v", "friction_force", "slipping"],
            r.samples.iter().map(|s| {
                vec![
                    s.t,
                    s.x,
                    s.v,
                    s.friction_force,
                    f64::from(u8::from(s.phase == Phase::Slip)),
                ]
            }),
        )?;
    }
    match res {
        Ok(_) => Ok(RunOutcome {
            summary,
            out_dir: opts.out_dir.clone(),
            converged,
            headline,
        }),
        Err(e) => Err(AppError::Unsupported(format!(
            "stick-slip integration failed: {e}"
        ))),
    }
}
