//! `tread-bench-sweep`: cost of `tread sweep` itself.
//!
//! 1. **Plan**: `tread sweep plan` of a 1000-run spec (10 × 10 × 10 over the creep-force
//!    scene): the wall time of the whole command (parse, every run's scene loaded and
//!    validated, the table printed), and of [`tread::sweep::plan::check`] in process.
//! 2. **Overhead of the local backend per run**: N runs of a scene taking about `--seconds`
//!    each, once as bare `tread run` processes one after the other, once as `tread sweep run
//!    -j 1` (plan + queued marks + one run-one supervisor per run + status files + collect).
//!    Overhead per run = (T_sweep − T_bare) / N, also as a fraction of the bare time, in wall
//!    time and in CPU time (user + system of every process, from getrusage: robust against
//!    other load on a shared machine). The two are alternated `--repeat` times; medians of the
//!    per-round figures are reported, and each round.
//!    A second pass with tiny runs (≈ 20 ms) shows the absolute cost per run.
//!
//! Everything with `--threads 1`. Usage:
//! `tread-bench-sweep [--runs N] [--repeat R] [--out DIR] [--smoke]`.

#[path = "common.rs"]
mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

fn tread_exe() -> PathBuf {
    // The tools are built next to `tread`.
    let me = std::env::current_exe().expect("current_exe");
    me.with_file_name("tread")
}

/// User + system CPU time of the waited-for children (and their waited-for descendants), s.
fn children_cpu() -> f64 {
    // SAFETY: getrusage fills the struct it is given.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe {
        libc::getrusage(libc::RUSAGE_CHILDREN, &mut u);
    }
    let tv = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    tv(u.ru_utime) + tv(u.ru_stime)
}

/// Run a command; (wall time, CPU time of it and its descendants).
fn run(cmd: &mut Command) -> (f64, f64) {
    let c0 = children_cpu();
    let t0 = Instant::now();
    let o = cmd.output().expect("spawn");
    let dt = (t0.elapsed().as_secs_f64(), children_cpu() - c0);
    if !o.status.success() {
        panic!(
            "{:?} failed: {}\n{}",
            cmd,
            o.status,
            String::from_utf8_lossy(&o.stderr)
        );
    }
    dt
}

const SPIN: &str = r#"
[scene]
name = "bench"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
n_r = 2
n_theta = 8
[material]
model = "neo_hookean"
mu = 200.0
lambda = 1800.0
rho = 0.027
[analysis]
mode = "spinning"
[motion]
omega = 20.0
[output]
sinks = ["summary"]
"#;

/// Per round: (bare wall, sweep wall, bare CPU, sweep CPU).
type Round = (f64, f64, f64, f64);

/// Bare runs vs the local backend for `n` runs with the given extra overrides, `repeat` rounds.
fn overhead(dir: &Path, exe: &Path, n: usize, fixed: &[(&str, &str)], repeat: usize) -> Vec<Round> {
    std::fs::write(dir.join("spin.toml"), SPIN).unwrap();
    let omegas: Vec<String> = (0..n).map(|i| format!("{:.1}", 10.0 + i as f64)).collect();
    let mut spec = format!(
        "[sweep]\nname = \"bench\"\nscene = \"spin.toml\"\n[[axis]]\nkey = \"motion.omega\"\nvalues = [{}]\n",
        omegas.join(", ")
    );
    if !fixed.is_empty() {
        let items: Vec<String> = fixed
            .iter()
            .map(|(k, v)| format!("{{ key = \"{k}\", values = [{v}] }}"))
            .collect();
        spec += &format!("[[axis]]\nzip = [{}]\n", items.join(", "));
    }
    spec += "[outputs]\nsinks = [\"summary\"]\n";
    let spec_path = dir.join("bench.toml");
    std::fs::write(&spec_path, spec).unwrap();
    let mut rounds = Vec::new();
    for r in 0..repeat {
        let bare_dir = dir.join(format!("bare{r}"));
        let mut t = (0.0, 0.0);
        for (i, w) in omegas.iter().enumerate() {
            let mut c = Command::new(exe);
            c.args(["--threads", "1", "-q", "run"])
                .arg(dir.join("spin.toml"))
                .arg("--out")
                .arg(bare_dir.join(i.to_string()))
                .args(["--set", &format!("motion.omega={w}")]);
            for (k, v) in fixed {
                c.args(["--set", &format!("{k}={v}")]);
            }
            c.args(["--set", "output.sinks=[\"summary\"]"]);
            let (w, cpu) = run(&mut c);
            t.0 += w;
            t.1 += cpu;
        }
        let root = dir.join(format!("sweep{r}"));
        let mut c = Command::new(exe);
        c.args(["--threads", "1", "-q", "sweep", "run"])
            .arg(&spec_path)
            .args(["-j", "1", "--out"])
            .arg(&root);
        let (w, cpu) = run(&mut c);
        rounds.push((t.0, w, t.1, cpu));
        let _ = std::fs::remove_dir_all(&bare_dir);
        let _ = std::fs::remove_dir_all(&root);
    }
    rounds
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let get = |k: &str| {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let smoke = args.iter().any(|a| a == "--smoke");
    let n: usize = get("--runs")
        .and_then(|s| s.parse().ok())
        .unwrap_or(if smoke { 2 } else { 8 });
    let repeat: usize = get("--repeat")
        .and_then(|s| s.parse().ok())
        .unwrap_or(if smoke { 1 } else { 3 });
    let out = PathBuf::from(get("--out").unwrap_or_else(|| "target/bench_sweep".into()));
    std::fs::create_dir_all(&out).unwrap();
    let exe = tread_exe();
    assert!(exe.exists(), "{} not built", exe.display());

    // 1. Plan of 1000 runs.
    let scen = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/creep_force.toml");
    let spec = format!(
        "[sweep]\nname = \"plan1000\"\nscene = \"{}\"\n[[axis]]\nkey = \"friction.mu\"\nlinear = {{ start = 0.1, stop = 1.0, num = 10 }}\n[[axis]]\nkey = \"road.v0\"\nlinear = {{ start = 3.0, stop = 5.7, num = 10 }}\n[[axis]]\nkey = \"road.disp\"\ngeometric = {{ start = 0.01, stop = 0.2, num = 10 }}\n",
        scen.display()
    );
    let spec_path = out.join("plan1000.toml");
    std::fs::write(&spec_path, spec).unwrap();
    let mut cli = Vec::new();
    for _ in 0..3 {
        let mut c = Command::new(&exe);
        c.args(["--threads", "1", "sweep", "plan"]).arg(&spec_path);
        cli.push(run(&mut c).0);
    }
    let s = tread::sweep::Spec::load(&spec_path).unwrap();
    let t0 = Instant::now();
    tread::sweep::plan::check(&s).unwrap();
    let inproc = t0.elapsed().as_secs_f64();
    println!(
        "plan: {} runs: `tread --threads 1 sweep plan` {:.3} s (median of 3), plan::check in process {:.3} s ({} rayon threads)",
        s.n_runs(),
        common::median(cli),
        inproc,
        rayon::current_num_threads()
    );

    // 2. Overhead per run.
    let cases: Vec<(&str, Vec<(&str, &str)>)> = if smoke {
        vec![("tiny", vec![])]
    } else {
        vec![
            (
                "long",
                vec![
                    ("mesh.n_r", "8"),
                    ("mesh.n_theta", "192"),
                    ("solver.load_steps", "20"),
                ],
            ),
            ("tiny", vec![]),
        ]
    };
    for (name, fixed) in cases {
        let dir = out.join(name);
        std::fs::create_dir_all(&dir).unwrap();
        let rounds = overhead(&dir, &exe, n, &fixed, repeat);
        let nf = n as f64;
        let med = |f: &dyn Fn(&Round) -> f64| common::median(rounds.iter().map(f).collect());
        let per_bare = med(&|r| r.0 / nf);
        let over_wall = med(&|r| (r.1 - r.0) / nf);
        let over_wall_rel = med(&|r| (r.1 - r.0) / r.0);
        let over_cpu = med(&|r| (r.3 - r.2) / nf);
        let over_cpu_rel = med(&|r| (r.3 - r.2) / r.2);
        println!(
            "overhead ({name} runs: {n} runs, {per_bare:.3} s wall per bare run; medians over {repeat} rounds): wall {:.1} ms/run = {:.2} %, CPU {:.1} ms/run = {:.2} %",
            over_wall * 1e3,
            100.0 * over_wall_rel,
            over_cpu * 1e3,
            100.0 * over_cpu_rel
        );
        for (k, r) in rounds.iter().enumerate() {
            println!(
                "  round {k}: bare {:.3} s wall / {:.3} s CPU, sweep -j 1 {:.3} s wall / {:.3} s CPU",
                r.0, r.2, r.1, r.3
            );
        }
    }
}
