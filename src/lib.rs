//! # tread
//!
//! Finite-element simulation of rolling contact of a hyperelastic hollow cylinder in plane
//! strain: a rigid hub, a rubber annulus, a rigid road. See `README.md` for the user's view; the
//! formulation is stated in each module's docs, the conventions here (spatial frame with the hub centre
//! at the origin, x1 right, x2 up, counter-clockwise spin ω > 0; forces per unit thickness;
//! units as the scene declares them).
//!
//! Layout: [`math`] aliases, [`mesh`] structured annulus and mesh data, [`element`] shape
//! functions and quadrature, [`material`] hyperelastic laws, [`assembly`] dofs / pattern /
//! parallel assembler, [`physics`] element kernels, [`solver`] Newton, load stepping and sparse
//! direct solvers, [`driver`] analyses, [`io`] scenes and outputs, [`setup`] scene → model,
//! options and sinks, [`app`] the `tread` program (dispatch on the analysis mode),
//! [`sweep`] parameter sweeps over many runs (local process pool or Slurm job array).
//!
//! # Using the library
//!
//! A run goes scene → mode → results: [`io::scene::Scene::from_toml_str`] reads and validates a
//! scene (every problem at once, each naming its key and line), [`app::run`] runs its analysis
//! mode and writes the outputs of its `[output] sinks`, and the returned [`app::RunOutcome`]
//! holds the typed summary, the JSON of `summary.json` and, for the rolling modes, the
//! referential field.
//!
//! Spin the paper's hollow cylinder (neo-Hookean, hub rim fixed, outer surface free) and read
//! the ring-averaged stresses: the radial stress vanishes at the free surface.
//!
//! ```
//! use tread::app::{self, RunOptions};
//! use tread::io::scene::Scene;
//!
//! let text = r#"
//! [scene]
//! name = "doc_spin"
//! [geometry]
//! ri = 1.0
//! ro = 2.0
//! [mesh]
//! n_r = 4
//! n_theta = 48
//! [material]
//! model = "neo_hookean"
//! mu = 200.0
//! lambda = 1800.0
//! rho = 0.027
//! [analysis]
//! mode = "spinning"
//! [motion]
//! omega = 20.0
//! [output]
//! sinks = ["summary"]
//! "#;
//! let scene = Scene::from_toml_str(text, "doc_spin.toml", &[]).expect("a valid scene");
//! let out_dir = std::env::temp_dir().join(format!("tread-doc-spin-{}", std::process::id()));
//! let opts = RunOptions { out_dir: out_dir.clone(), verbose: false, quiet: true };
//! let outcome = app::run(&scene, &opts).expect("the run");
//! assert!(outcome.converged);
//! let r = &outcome.summary["results"];
//! let (s_in, s_out) = (r["sigma_r_inner"].as_f64().unwrap(), r["sigma_r_outer"].as_f64().unwrap());
//! assert!(s_out.abs() < 0.01 * s_in.abs(), "free surface: {s_out} vs {s_in}");
//! assert!(out_dir.join("summary.json").is_file());
//! std::fs::remove_dir_all(&out_dir).ok();
//! ```
//!
//! A shipped scene with `--set`-style overrides, solved in the steady θ-referential mode: the
//! road's contact force balances the hub force.
//!
//! ```
//! use tread::app::{self, RunOptions};
//! use tread::io::scene::Scene;
//!
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/creep_force.toml");
//! let text = std::fs::read_to_string(path).unwrap();
//! let set = ["mesh.n_r=2", "mesh.n_theta=64", "output.sinks=[\"summary\"]"].map(String::from);
//! let mut scene = Scene::from_toml_str(&text, path, &set).expect("a valid scene");
//! scene.resolve_paths(std::path::Path::new(path));
//! let out_dir = std::env::temp_dir().join(format!("tread-doc-steady-{}", std::process::id()));
//! let opts = RunOptions { out_dir: out_dir.clone(), verbose: false, quiet: true };
//! let outcome = app::run(&scene, &opts).expect("the steady solve");
//! let r = &outcome.summary["results"];
//! let (hub, road) = (r["hub_force_y"].as_f64().unwrap(), r["contact_force_y"].as_f64().unwrap());
//! assert!((hub + road).abs() < 1e-6 * road.abs(), "hub {hub}, road {road}");
//! // The referential displacement field: two components per node.
//! assert_eq!(outcome.field.as_ref().map(|f| f.len() % 2), Some(0));
//! std::fs::remove_dir_all(&out_dir).ok();
//! ```

pub mod adapt;
pub mod app;
pub mod assembly;
pub mod contact;
pub mod driver;
pub mod element;
pub mod io;
pub mod material;
pub mod math;
pub mod mesh;
pub mod model;
pub mod params;
pub mod physics;
pub mod setup;
pub mod solver;
pub mod sweep;
