//! The default layout (Rerun "blueprint") sent with every `.rrd` this program writes: by the
//! `rerun` sink during a run ([`super::rrd`]) and by `tread replay LOG.mcap --to FILE.rrd`.
//!
//! | view | kind | content |
//! |---|---|---|
//! | Body head-on (x1 right, x2 up) | 3D, camera on the +x3 axis looking at the body | deformed mesh coloured by the in-plane max shear stress τ, its colour scale with labelled ends (`body/colour_scale`), boundary, road, contact points and traction arrows, and the contact pressure and shear drawn as curves against x1 below the road |
//! | Hub force and torque | time series | F_x, F_y [F/L] and M [F·L/L] together |
//! | Newton iterations per step | time series | iterations of every step |
//! | Newton residual | time series | log10 of the relative residual of every Newton iteration (dots) |
//! | Energies | time series | strain, kinetic, total [F·L/L] |
//! | Contact pressure / shear against x1 | 2D charts ([`super::rrd_draw`]) | t_n and t_T [F/L²] through the contact points against x1 [L], round ticks on both axes, the x range over the patch |
//! | Other series, Log, Scene | time series, text log, text | everything else (the linear relative residual, the load factor λ of load stepping) |
//!
//! Units in the view names come from `[scene] units` (`"L-F-T"`, see [`super::png::Units`]).
//! The time panel opens on `sim_time` (simulated time), or on `step` for load stepping (a steady
//! or static run, which has no `sim_time`), following the data (a finished run shows its last
//! state).
//!
//! # How the layout is built
//!
//! The Rust SDK of this Rerun version (0.36.3) has a blueprint builder
//! (`rerun::blueprint::Blueprint`), but it cannot set view properties such as the 3D camera
//! (`EyeControls3D`), and it gives views random ids (so a file would differ between two runs of the
//! same scene). This module therefore logs the blueprint archetypes themselves
//! (`ViewportBlueprint`, `ContainerBlueprint`, `ViewBlueprint`, `ViewContents`, and the view
//! properties `EyeControls3D`, `LineGrid3D`, `PlotLegend`) to a blueprint store through the SDK's
//! in-memory stream, exactly as the builder does, with fixed view and container ids, and sends the
//! messages into the recording's own sink with `RecordingStream::send_blueprint` (activated and
//! made the default for the application `tread`). The `.rrd` then holds two stores: the recording
//! and its blueprint. A user who rearranges the views can go back to this layout with the
//! viewer's "Reset to default blueprint".

use super::png::{with_unit, Units};
use rerun::external::re_log_types::{BlueprintActivationCommand, LogMsg};
use rerun::external::re_sdk_types::blueprint::archetypes as bp;
use rerun::external::re_sdk_types::blueprint::components as bpc;
use rerun::external::re_sdk_types::datatypes::{Range1D, Range2D};
use rerun::{RecordingStream, RecordingStreamResult};

/// Entity paths (queries) of the things a layout shows; the run's own `.rrd` and a converted MCAP
/// name them differently.
#[derive(Clone, Debug)]
pub struct LayoutPaths {
    /// Everything drawn in the body view (entity queries, e.g. `/body/**`).
    pub body: Vec<String>,
    pub hub: Vec<String>,
    pub newton_iterations: Vec<String>,
    pub newton_residual: Vec<String>,
    pub energy: Vec<String>,
    /// The entities of the pressure and shear charts (queries ending in `/**`).
    pub pressure: String,
    pub shear: String,
    pub series: Vec<String>,
    pub log: String,
    pub scene: String,
}

impl LayoutPaths {
    /// The entities of the `rerun` sink ([`super::rrd`]).
    pub fn run() -> Self {
        Self {
            body: vec![
                "/body/**".into(),
                "/road/**".into(),
                "/contact/points".into(),
                "/contact/traction".into(),
                "/contact/curves/**".into(),
            ],
            hub: vec!["/hub/**".into()],
            newton_iterations: vec!["/newton/iterations".into()],
            newton_residual: vec!["/newton/log10_residual".into()],
            energy: vec!["/energy/**".into()],
            pressure: "/contact/chart/pressure/**".into(),
            shear: "/contact/chart/shear/**".into(),
            series: vec![
                "/series/**".into(),
                "/branch/**".into(),
                "/newton/residual".into(),
            ],
            log: "/log".into(),
            scene: "/scene".into(),
        }
    }

    /// The entities of an MCAP log converted by `tread replay --to` ([`crate::io::replay`]).
    pub fn replay() -> Self {
        Self {
            body: vec![
                "/tread/mesh/**".into(),
                "/tread/contact".into(),
                "/tread/traction".into(),
                "/tread/colour_scale/**".into(),
                "/tread/contact_curves/**".into(),
            ],
            hub: vec!["/tread/hub/**".into()],
            newton_iterations: vec!["/tread/step/newton_iterations".into()],
            newton_residual: vec!["/tread/newton/log10_residual".into()],
            energy: vec!["/tread/energy/**".into()],
            pressure: "/tread/contact_chart/pressure/**".into(),
            shear: "/tread/contact_chart/shear/**".into(),
            series: vec![
                "/tread/series/**".into(),
                "/tread/continuation/**".into(),
                "/tread/newton/residual".into(),
            ],
            log: "/tread/log".into(),
            scene: "/metadata/**".into(),
        }
    }
}

/// What the layout needs to know of the run.
#[derive(Clone, Debug)]
pub struct LayoutSpec {
    pub units: Units,
    /// Largest radius of the body (for the camera distance); 1 when unknown.
    pub radius: f64,
    /// Displacement magnification of the body view (shown in its name when not 1).
    pub magnification: f64,
    /// `"load_factor"` (load stepping: timeline `step` only) or `"time"` (timelines `sim_time` and
    /// `step`).
    pub time_name: String,
    pub paths: LayoutPaths,
}

/// One view of the layout (what is logged for it).
#[derive(Clone, Debug, PartialEq)]
pub struct ViewSpec {
    /// Fixed id (a UUID text) of the view: `view/<id>` in the blueprint store.
    pub id: String,
    /// Rerun view class: `3D`, `2D`, `TimeSeries`, `TextLog`, `TextDocument`.
    pub class: &'static str,
    pub name: String,
    pub contents: Vec<String>,
}

/// A fixed UUID text for the `k`-th view or container (version-4 layout, so the viewer parses it
/// like its own ids; fixed so that the same run writes the same file).
fn fixed_id(k: u32) -> String {
    let b = fixed_uuid(k);
    let h: String = b.iter().map(|x| format!("{x:02x}")).collect();
    format!(
        "{}-{}-{}-{}-{}",
        &h[0..8],
        &h[8..12],
        &h[12..16],
        &h[16..20],
        &h[20..32]
    )
}

/// The bytes of [`fixed_id`]`(k)`.
fn fixed_uuid(k: u32) -> [u8; 16] {
    (0x7265_a0d0_0000_4000_8000_0000_0000_0000u128 | u128::from(k)).to_be_bytes()
}

/// The views of the layout, in the order they are placed.
pub fn views(spec: &LayoutSpec) -> Vec<ViewSpec> {
    let u = &spec.units;
    let p = &spec.paths;
    let mag = if (spec.magnification - 1.0).abs() > 0.0 {
        format!(", u ×{}", crate::io::output::fmt_num(spec.magnification))
    } else {
        String::new()
    };
    let x_name = match spec.time_name.as_str() {
        "load_factor" => "load step".to_string(),
        _ => format!("time [{}]", u.time),
    };
    let v = |k: u32, class: &'static str, name: String, contents: &[String]| ViewSpec {
        id: fixed_id(k),
        class,
        name,
        contents: contents.to_vec(),
    };
    vec![
        v(
            1,
            "3D",
            format!(
                "Body head-on [{}], colour τ = max in-plane shear [{}]{mag}",
                u.length,
                u.stress()
            ),
            &p.body,
        ),
        v(
            2,
            "TimeSeries",
            format!(
                "Hub force F_x, F_y [{}] and torque M [{}] against {x_name}",
                u.force_per_thickness(),
                u.moment_per_thickness()
            ),
            &p.hub,
        ),
        v(
            3,
            "TimeSeries",
            format!("Newton iterations per step against {x_name}"),
            &p.newton_iterations,
        ),
        v(
            10,
            "TimeSeries",
            format!("Newton residual: log10 of the relative residual of every iteration, against {x_name}"),
            &p.newton_residual,
        ),
        v(
            4,
            "TimeSeries",
            format!(
                "Energies (strain, kinetic, total) [{}] against {x_name}",
                u.moment_per_thickness()
            ),
            &p.energy,
        ),
        v(
            5,
            "2D",
            format!(
                "Contact pressure t_n [{}] against x1 [{}]",
                u.stress(),
                u.length
            ),
            std::slice::from_ref(&p.pressure),
        ),
        v(
            6,
            "2D",
            format!(
                "Contact shear t_T [{}] against x1 [{}]",
                u.stress(),
                u.length
            ),
            std::slice::from_ref(&p.shear),
        ),
        v(
            7,
            "TimeSeries",
            format!("Other series against {x_name} (units in each name)"),
            &p.series,
        ),
        v(8, "TextLog", "Log".into(), std::slice::from_ref(&p.log)),
        v(
            9,
            "TextDocument",
            "Scene".into(),
            std::slice::from_ref(&p.scene),
        ),
    ]
}

/// A solid dark background for the view at `path`: the light labels read on it, and the
/// viridis colours of the body stand out.
fn dark_background(bs: &RecordingStream, path: &str) -> RecordingStreamResult<()> {
    bs.log(
        format!("{path}/Background"),
        &bp::Background::new(bpc::BackgroundKind::SolidColor)
            .with_color(rerun::Color::from_rgb(22, 22, 26)),
    )
}

/// `name [unit]` of a named series for the Rerun legends.
pub fn series_label(units: &Units, name: &str) -> String {
    let pretty = match name {
        "hub_force_x" => "F_x",
        "hub_force_y" => "F_y",
        "hub_torque" => "M",
        "energy_strain" => "strain energy",
        "energy_kinetic" => "kinetic energy",
        "energy_total" => "total energy",
        other => other,
    };
    with_unit(pretty, &units.of_scalar(name))
}

/// The blueprint messages of the layout (a blueprint store of the application `app_id`).
pub fn blueprint_messages(
    app_id: &'static str,
    spec: &LayoutSpec,
) -> RecordingStreamResult<Vec<LogMsg>> {
    let (bs, storage) = rerun::RecordingStreamBuilder::new(app_id)
        .recording_id(format!("{app_id}-default-layout"))
        .send_properties(false)
        .blueprint()
        .memory()?;
    bs.set_log_time_enabled(false);
    bs.set_log_tick_enabled(false);
    // The viewer reads blueprint data on this timeline.
    bs.set_time_sequence("blueprint", 0);
    let views = views(spec);
    for v in &views {
        let path = format!("view/{}", v.id);
        bs.log(
            format!("{path}/ViewContents"),
            &bp::ViewContents::new(
                v.contents
                    .iter()
                    .map(|q| bpc::QueryExpression(q.clone().into())),
            ),
        )?;
        bs.log(
            path.as_str(),
            &bp::ViewBlueprint::new(bpc::ViewClass(v.class.into()))
                .with_display_name(v.name.as_str())
                .with_space_origin("/"),
        )?;
        match v.class {
            "3D" => {
                // Head-on: the camera on the +x3 axis, x2 up, looking a little below and right
                // of the hub (the road and the contact curves are below the body, the colour
                // scale and its labels right of it).
                let r = spec.radius.max(f64::MIN_POSITIVE) as f32;
                let target = [0.35 * r, -0.3 * r, 0.0];
                bs.log(
                    format!("{path}/EyeControls3D"),
                    &bp::EyeControls3D::new()
                        .with_kind(bpc::Eye3DKind::Orbital)
                        .with_position([0.35 * r, -0.3 * r, 3.0 * r])
                        .with_look_target(target)
                        .with_eye_up([0.0, 1.0, 0.0]),
                )?;
                bs.log(
                    format!("{path}/LineGrid3D"),
                    &bp::LineGrid3D::new().with_visible(false),
                )?;
                dark_background(&bs, &path)?;
            }
            "2D" => {
                let (lo, hi) = super::rrd_draw::chart_bounds();
                bs.log(
                    format!("{path}/VisualBounds2D"),
                    &bp::VisualBounds2D::new(Range2D {
                        x_range: Range1D([f64::from(lo[0]), f64::from(hi[0])]),
                        y_range: Range1D([f64::from(lo[1]), f64::from(hi[1])]),
                    }),
                )?;
                dark_background(&bs, &path)?;
            }
            "TimeSeries" => {
                // A single series is named by its view: no legend over the data.
                let single = v.contents.len() == 1 && !v.contents[0].ends_with("**");
                bs.log(
                    format!("{path}/PlotLegend"),
                    &bp::PlotLegend::new().with_visible(!single),
                )?;
            }
            _ => {}
        }
    }
    let id = |k: u32| format!("container/{}", fixed_id(100 + k));
    let view_path = |k: usize| format!("view/{}", views[k].id);
    let container = |kind: bpc::ContainerKind, name: &str, children: Vec<String>| {
        bp::ContainerBlueprint::new(kind)
            .with_display_name(name)
            .with_contents(children.into_iter().map(bpc::IncludedContent::from))
    };
    // Left: the body above the two contact charts; right: the hub loads, the Newton iterations
    // beside the residual, the energies, above the tabs of the rest.
    bs.log(
        id(2),
        &container(
            bpc::ContainerKind::Horizontal,
            "Contact tractions",
            vec![view_path(5), view_path(6)],
        ),
    )?;
    bs.log(
        id(1),
        &container(
            bpc::ContainerKind::Vertical,
            "Body and contact",
            vec![view_path(0), id(2)],
        )
        .with_row_shares([1.8f32, 1.0]),
    )?;
    bs.log(
        id(5),
        &container(
            bpc::ContainerKind::Horizontal,
            "Newton",
            vec![view_path(2), view_path(3)],
        ),
    )?;
    bs.log(
        id(4),
        &container(
            bpc::ContainerKind::Tabs,
            "More",
            vec![view_path(7), view_path(8), view_path(9)],
        ),
    )?;
    bs.log(
        id(3),
        &container(
            bpc::ContainerKind::Vertical,
            "Time series",
            vec![view_path(1), id(5), view_path(4), id(4)],
        ),
    )?;
    bs.log(
        id(0),
        &container(bpc::ContainerKind::Horizontal, "tread", vec![id(1), id(3)])
            .with_col_shares([1.2f32, 1.0]),
    )?;
    // Open on the simulated time (the load step in load stepping), following the data: the
    // final state once the run is over.
    let timeline = if spec.time_name == "load_factor" {
        "step"
    } else {
        "sim_time"
    };
    bs.log(
        "time_panel",
        &bp::TimePanelBlueprint::new()
            .with_timeline(bpc::TimelineName(timeline.into()))
            .with_play_state(bpc::PlayState::Following),
    )?;
    bs.log(
        "viewport",
        &bp::ViewportBlueprint::new()
            .with_root_container(bpc::RootContainer(fixed_uuid(100).into()))
            .with_auto_layout(false)
            .with_auto_views(false),
    )?;
    Ok(storage.take())
}

/// Send the layout into `rec` (see the module docs), active and the default of `app_id`.
pub fn send_layout(
    rec: &RecordingStream,
    app_id: &'static str,
    spec: &LayoutSpec,
) -> RecordingStreamResult<()> {
    let msgs = blueprint_messages(app_id, spec)?;
    let Some(blueprint_id) = msgs.iter().find_map(|m| match m {
        LogMsg::SetStoreInfo(info) => Some(info.info.store_id.clone()),
        _ => None,
    }) else {
        return Ok(());
    };
    rec.send_blueprint(
        msgs,
        BlueprintActivationCommand {
            blueprint_id,
            make_active: true,
            make_default: true,
        },
    );
    Ok(())
}
