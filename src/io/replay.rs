//! `tread replay LOG [--to FILE]`: open a log in the Rerun viewer, or convert an MCAP log to a
//! Rerun `.rrd`.
//!
//! * `LOG.rrd`: runs the Rerun viewer (`rerun LOG.rrd`) and waits for it.
//! * `LOG.mcap`: converts it to a temporary `.rrd` ([`mcap_to_rrd`]) and opens that; with
//!   `--to FILE.rrd` only converts.
//! * `LOG.rrd --to FILE.rrd`: rewrites the recording ([`recover_rrd`]): the way to repair the
//!   `run.rrd` of a killed run, which ends without the footer that `rerun rrd verify` requires
//!   (and possibly inside a message).
//!
//! The viewer is the `rerun` executable on `PATH` (or `$TREAD_RERUN_BIN`); when there is none,
//! [`ReplayError::NoViewer`] says how to install it. The viewer's server listens on the
//! loopback address only (`rerun --bind 127.0.0.1`); `tread replay --bind ADDR` chooses
//! another address (e.g. `0.0.0.0` to accept connections from other machines).
//!
//! A converted recording is named by scene and mode (the `name` and `mode` of the MCAP's `scene`
//! metadata record), as the `.rrd` written during a run is, and carries the same default layout
//! ([`crate::io::record::rrd_layout`], with the MCAP's entity paths and the units of its scene),
//! drawn from what the MCAP carries ([`crate::io::record::rrd_draw`]): the colour scale of the
//! body (`tread/colour_scale`, from the `max_shear_stress` of `/tread/nodes`), the traction
//! arrows (`tread/traction`, from `/tread/contact`), the contact curves below the road
//! (`tread/contact_curves/*`) and the pressure and shear charts (`tread/contact_chart/*`, from
//! `/tread/contact_patch`), series named with their units, and the Newton residual's log10
//! (`tread/newton/log10_residual`). Not there: the displacement magnification and the reference
//! configuration before the first step (the MCAP holds neither).
//!
//! The conversion reads the MCAP with a streaming reader (a truncated file converts up to its
//! last complete chunk), decodes every protobuf message with the schema embedded in the file
//! (prost-reflect) and logs: `foxglove.SceneUpdate` triangles and lines as `Mesh3D` and
//! `LineStrips3D` (so the deformed mesh appears, which the Rerun viewer's own MCAP importer does
//! not map), `foxglove.PointCloud` as `Points3D` (with its red/green/blue fields as colours),
//! `foxglove.Log` as `TextLog`, and every numeric field of any other message as a `Scalars`
//! series at `<topic>/<field>`. Timelines: `step` (the `index` of the latest `/tread/step`
//! message at the same log time, or a message's own `step` field) and, for a time-stepping run,
//! `sim_time` = log_time (ns from 0); a load-stepping run (`time` = `load_factor` in the `scene`
//! record) has `step` only, with λ as the series `tread/series/load_factor`. Metadata records
//! become static text documents under `metadata/<name>`.

use std::path::{Path, PathBuf};
use std::process::Command;

#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    #[error(
        "the Rerun viewer (`rerun`) is not installed or not on PATH.\n\
         Install it with one of:\n  \
         pip install rerun-sdk==0.36.*          # provides the `rerun` command\n  \
         cargo install rerun-cli --version 0.36.3 --locked\n\
         then run `tread replay {0}` again (or `rerun {0}`).\n\
         An .mcap log also opens in Foxglove (https://app.foxglove.dev, or the desktop app): \
         File > Open local file."
    )]
    NoViewer(String),
    #[error("cannot read {0}: {1}")]
    Read(PathBuf, String),
    #[error("cannot write {0}: {1}")]
    Write(PathBuf, String),
    #[error("{0}: unknown log type (expected .rrd or .mcap)")]
    UnknownType(PathBuf),
    #[error("the viewer failed: {0}")]
    Viewer(String),
    #[error("converting MCAP to .rrd needs the `rerun` cargo feature (a default feature)")]
    NoRerunFeature,
}

/// What a conversion read.
#[derive(Debug, Default, Clone)]
pub struct ConvertStats {
    pub messages: u64,
    /// Messages whose schema was not protobuf or could not be decoded.
    pub skipped: u64,
    /// The file ended early (truncated: e.g. a killed run).
    pub truncated: bool,
}

/// The viewer executable: `$TREAD_RERUN_BIN`, else `rerun` found on PATH.
pub fn find_viewer() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("TREAD_RERUN_BIN") {
        let p = PathBuf::from(p);
        return p.is_file().then_some(p);
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(if cfg!(windows) { "rerun.exe" } else { "rerun" }))
        .find(|p| p.is_file())
}

fn kind(log: &Path) -> Option<&'static str> {
    match log.extension().and_then(|e| e.to_str()) {
        Some("rrd") => Some("rrd"),
        Some("mcap") => Some("mcap"),
        _ => None,
    }
}

/// Address the viewer listens on unless the user chooses another: the loopback address.
pub const DEFAULT_BIND: std::net::IpAddr = std::net::IpAddr::V4(std::net::Ipv4Addr::LOCALHOST);

/// Run `tread replay LOG [--to FILE]` with the viewer bound to [`DEFAULT_BIND`].
pub fn replay(log: &Path, to: Option<&Path>) -> Result<String, ReplayError> {
    replay_bound(log, to, DEFAULT_BIND)
}

/// The scene name of an MCAP log (its `scene` metadata record), if it has one.
pub fn mcap_scene_name(bytes: &[u8]) -> Option<String> {
    let reader = mcap::read::LinearReader::new(bytes).ok()?;
    for r in reader {
        match r {
            Ok(mcap::records::Record::Metadata(m)) if m.name == "scene" => {
                return m.metadata.get("name").cloned();
            }
            Ok(_) => {}
            Err(_) => return None,
        }
    }
    None
}

/// Run `tread replay LOG [--to FILE] [--bind ADDR]`; returns a line to print. A viewer started
/// here listens on `bind`.
pub fn replay_bound(
    log: &Path,
    to: Option<&Path>,
    bind: std::net::IpAddr,
) -> Result<String, ReplayError> {
    if !log.is_file() {
        return Err(ReplayError::Read(log.to_path_buf(), "no such file".into()));
    }
    let k = kind(log).ok_or_else(|| ReplayError::UnknownType(log.to_path_buf()))?;
    if k == "mcap" {
        check_mcap(log)?;
    }
    match (k, to) {
        ("mcap", Some(to)) => {
            let st = mcap_to_rrd(log, to)?;
            Ok(format!(
                "converted {} messages{}{} to {}",
                st.messages,
                if st.skipped > 0 {
                    format!(" ({} not decodable, skipped)", st.skipped)
                } else {
                    String::new()
                },
                if st.truncated {
                    " (the MCAP was truncated: converted up to its last complete chunk)"
                } else {
                    ""
                },
                to.display()
            ))
        }
        ("rrd", Some(to)) => {
            let st = recover_rrd(log, to)?;
            Ok(format!(
                "rewrote {} messages of {} to {}{}",
                st.messages,
                log.display(),
                to.display(),
                if st.truncated {
                    " (the .rrd ended inside a message, as after a killed run: kept every complete message, added the footer)"
                } else {
                    ""
                }
            ))
        }
        ("mcap", None) => {
            let viewer =
                find_viewer().ok_or_else(|| ReplayError::NoViewer(log.display().to_string()))?;
            let tmp = std::env::temp_dir().join(format!("tread-replay-{}.rrd", std::process::id()));
            mcap_to_rrd(log, &tmp)?;
            let r = open(&viewer, &tmp, bind);
            let _ = std::fs::remove_file(&tmp);
            r
        }
        _ => {
            let viewer =
                find_viewer().ok_or_else(|| ReplayError::NoViewer(log.display().to_string()))?;
            open(&viewer, log, bind)
        }
    }
}

/// MCAP files start with these 8 bytes.
const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// Refuse what is not an MCAP log with at least one readable message (random bytes, an empty
/// or header-only file), before anything is converted or written.
pub fn check_mcap(log: &Path) -> Result<u64, ReplayError> {
    let bad = |m: &str| ReplayError::Read(log.to_path_buf(), m.to_string());
    let bytes = std::fs::read(log).map_err(|e| bad(&e.to_string()))?;
    if !bytes.starts_with(MCAP_MAGIC) {
        return Err(bad("not an MCAP log (no MCAP magic bytes at the start)"));
    }
    let stream = mcap::MessageStream::new(&bytes).map_err(|e| bad(&e.to_string()))?;
    let mut n = 0u64;
    for m in stream {
        match m {
            Ok(_) => n += 1,
            Err(_) => break,
        }
    }
    if n == 0 {
        return Err(bad("the MCAP log holds no readable message"));
    }
    Ok(n)
}

fn open(viewer: &Path, file: &Path, bind: std::net::IpAddr) -> Result<String, ReplayError> {
    let status = Command::new(viewer)
        .arg("--bind")
        .arg(bind.to_string())
        .arg(file)
        .status()
        .map_err(|e| ReplayError::Viewer(format!("{}: {e}", viewer.display())))?;
    if status.success() {
        Ok(format!("viewer closed ({})", file.display()))
    } else {
        Err(ReplayError::Viewer(format!(
            "{} exited with {status}",
            viewer.display()
        )))
    }
}

/// Rewrite the `.rrd` `src` into `dst`: every message up to the first one that cannot be decoded
/// (the end of a file cut short by a killed run), then the footer (the chunk manifest that
/// `rerun rrd verify` requires and that a killed run never writes). A complete file is copied
/// message by message. Without the `rerun` feature the file is copied byte for byte.
#[cfg(feature = "rerun")]
pub fn recover_rrd(src: &Path, dst: &Path) -> Result<ConvertStats, ReplayError> {
    use rerun::external::re_log_encoding::DecoderApp;
    if same_file(src, dst) {
        return Err(ReplayError::Write(
            dst.to_path_buf(),
            "is the file being read; choose another --to".into(),
        ));
    }
    let f = std::fs::File::open(src)
        .map_err(|e| ReplayError::Read(src.to_path_buf(), e.to_string()))?;
    let mut st = ConvertStats::default();
    let mut msgs = Vec::new();
    for m in DecoderApp::decode_lazy(std::io::BufReader::new(f)) {
        match m {
            Ok(m) => msgs.push(m),
            Err(_) => {
                st.truncated = true;
                break;
            }
        }
    }
    if msgs.is_empty() {
        return Err(ReplayError::Read(
            src.to_path_buf(),
            "not a Rerun recording (no readable message)".into(),
        ));
    }
    st.messages = msgs.len() as u64;
    // Encoded here, on this thread, into a temporary renamed when complete: a write error (a
    // full disk) is returned at once, and leaves neither a partial file nor the temporary.
    let tmp = crate::io::output::tmp_path(dst);
    let written = write_rrd(&tmp, &msgs);
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(ReplayError::Write(dst.to_path_buf(), e));
    }
    std::fs::rename(&tmp, dst).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        ReplayError::Write(dst.to_path_buf(), e.to_string())
    })?;
    Ok(st)
}

/// Encode `msgs` as a complete `.rrd` (stream header, messages, footer) into `path`.
#[cfg(feature = "rerun")]
fn write_rrd(path: &Path, msgs: &[rerun::external::re_log_types::LogMsg]) -> Result<(), String> {
    use rerun::external::re_build_info::CrateVersion;
    use rerun::external::re_log_encoding::{Encoder, EncodingOptions};
    let f = std::fs::File::create(path).map_err(|e| e.to_string())?;
    let mut enc = Encoder::new_eager(
        CrateVersion::LOCAL,
        EncodingOptions::PROTOBUF_COMPRESSED,
        std::io::BufWriter::new(f),
    )
    .map_err(|e| e.to_string())?;
    for m in msgs {
        enc.append(m).map_err(|e| e.to_string())?;
    }
    enc.finish().map_err(|e| e.to_string())?;
    let w = enc.into_inner().map_err(|e| e.to_string())?;
    let f = w.into_inner().map_err(|e| e.error().to_string())?;
    f.sync_all().map_err(|e| e.to_string())
}

/// See the `rerun` build's docs: here the file is copied.
#[cfg(not(feature = "rerun"))]
pub fn recover_rrd(src: &Path, dst: &Path) -> Result<ConvertStats, ReplayError> {
    if same_file(src, dst) {
        return Err(ReplayError::Write(
            dst.to_path_buf(),
            "is the file being read; choose another --to".into(),
        ));
    }
    std::fs::copy(src, dst).map_err(|e| ReplayError::Write(dst.to_path_buf(), e.to_string()))?;
    Ok(ConvertStats::default())
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// Convert an MCAP log to a Rerun `.rrd` (see the module docs).
#[cfg(not(feature = "rerun"))]
pub fn mcap_to_rrd(_mcap: &Path, _rrd: &Path) -> Result<ConvertStats, ReplayError> {
    Err(ReplayError::NoRerunFeature)
}

/// Convert an MCAP log to a Rerun `.rrd` (see the module docs).
#[cfg(feature = "rerun")]
pub fn mcap_to_rrd(mcap_path: &Path, rrd: &Path) -> Result<ConvertStats, ReplayError> {
    convert::run(mcap_path, rrd)
}

#[cfg(feature = "rerun")]
mod convert {
    use super::{ConvertStats, ReplayError};
    use crate::io::record::png::Units;
    use crate::io::record::rrd_draw;
    use crate::io::record::rrd_layout::{self, series_label};
    use prost_reflect::{DescriptorPool, DynamicMessage, MessageDescriptor, Value};
    use std::collections::{BTreeMap, BTreeSet, HashMap};
    use std::path::Path;

    pub fn run(mcap_path: &Path, rrd: &Path) -> Result<ConvertStats, ReplayError> {
        let bytes = std::fs::read(mcap_path)
            .map_err(|e| ReplayError::Read(mcap_path.to_path_buf(), e.to_string()))?;
        // Written into a temporary renamed when complete: a full disk is an error, with neither
        // a partial file nor the temporary left.
        let tmp = crate::io::output::tmp_path(rrd);
        let builder = rerun::RecordingStreamBuilder::new("tread").send_properties(false);
        let (rec, file) = crate::io::record::rrd::file_recording(builder, &tmp)
            .map_err(|e| ReplayError::Write(rrd.to_path_buf(), e))?;
        let failed = |e: String| {
            let _ = std::fs::remove_file(&tmp);
            ReplayError::Write(rrd.to_path_buf(), e)
        };
        rec.set_log_time_enabled(false);
        rec.set_log_tick_enabled(false);
        // Named after the scene (`send_properties(false)` drops a builder's name).
        if let Some(name) = super::mcap_scene_name(&bytes) {
            let name = match mcap_scene_field(&bytes, "mode") {
                Some(m) => format!("{name} ({m} mode)"),
                None => name,
            };
            let _ = rec.send_recording_name(name);
        }
        let scene_toml = mcap_scene_field(&bytes, "toml").unwrap_or_default();
        let radius = scene_toml
            .parse::<toml::Table>()
            .ok()
            .and_then(|t| t.get("geometry")?.get("ro")?.as_float())
            .filter(|r| r.is_finite() && *r > 0.0)
            .unwrap_or(1.0);
        let units = crate::io::record::rrd::scene_units(&scene_toml);
        let load_stepping = mcap_scene_field(&bytes, "time").as_deref() == Some("load_factor");
        let spec = rrd_layout::LayoutSpec {
            units: units.clone(),
            radius,
            magnification: 1.0,
            time_name: if load_stepping { "load_factor" } else { "time" }.into(),
            paths: rrd_layout::LayoutPaths::replay(),
        };
        rrd_layout::send_layout(&rec, "tread", &spec).map_err(|e| failed(e.to_string()))?;
        let mut draw = Drawing {
            units,
            ro: radius,
            bottom: f64::INFINITY,
            road: None,
            styled: BTreeSet::new(),
        };
        let mut st = ConvertStats::default();
        // Metadata records (not part of the message stream).
        if let Ok(reader) = mcap::read::LinearReader::new(&bytes) {
            for r in reader {
                match r {
                    Ok(mcap::records::Record::Metadata(m)) => {
                        let mut doc = format!("# {}\n\n", m.name);
                        for (k, v) in &m.metadata {
                            if v.contains('\n') {
                                doc.push_str(&format!("**{k}**:\n\n```\n{v}\n```\n\n"));
                            } else {
                                doc.push_str(&format!("**{k}**: {v}\n\n"));
                            }
                        }
                        let _ = rec.log_static(
                            format!("metadata/{}", m.name),
                            &rerun::TextDocument::new(doc)
                                .with_media_type(rerun::MediaType::markdown()),
                        );
                    }
                    Ok(_) => {}
                    Err(_) => break,
                }
            }
        }
        let stream = mcap::MessageStream::new(&bytes)
            .map_err(|e| ReplayError::Read(mcap_path.to_path_buf(), e.to_string()))?;
        let mut pools: HashMap<u16, Option<MessageDescriptor>> = HashMap::new();
        let mut step_at: BTreeMap<u64, i64> = BTreeMap::new();
        for m in stream {
            let m = match m {
                Ok(m) => m,
                Err(_) => {
                    st.truncated = true;
                    break;
                }
            };
            let desc = pools
                .entry(m.channel.id)
                .or_insert_with(|| descriptor(&m.channel))
                .clone();
            let Some(desc) = desc else {
                st.skipped += 1;
                continue;
            };
            let Ok(msg) = DynamicMessage::decode(desc.clone(), m.data.as_ref()) else {
                st.skipped += 1;
                continue;
            };
            st.messages += 1;
            let topic = m.channel.topic.trim_start_matches('/').to_string();
            if topic == "tread/step" {
                if let Some(i) = uint_field(&msg, "index") {
                    step_at.insert(m.log_time, i as i64);
                }
            }
            if !load_stepping {
                rec.set_duration_secs("sim_time", m.log_time as f64 * 1e-9);
            }
            let step = uint_field(&msg, "step")
                .map(|s| s as i64)
                .or_else(|| step_at.get(&m.log_time).copied());
            match (step, load_stepping) {
                (Some(s), _) => rec.set_time_sequence("step", s),
                // Before the first step (on no timeline at all it would be static).
                (None, true) => rec.set_time_sequence("step", -1),
                (None, false) => rec.disable_timeline("step"),
            }
            match desc.full_name() {
                "foxglove.SceneUpdate" => scene_update(&rec, &topic, &msg),
                "foxglove.PointCloud" => {
                    let cloud = point_cloud(&rec, &topic, &msg);
                    draw.cloud(&rec, &topic, &cloud);
                }
                "treadcontact.TreadContact" => draw.contact(&rec, &topic, &msg),
                "foxglove.Log" => {
                    if let Some(Value::String(t)) =
                        msg.get_field_by_name("message").map(|v| v.into_owned())
                    {
                        let _ = rec.log(topic.as_str(), &rerun::TextLog::new(t));
                    }
                }
                _ => {
                    if topic == "tread/step" && load_stepping {
                        let lambda = f64_of(&msg, "time");
                        draw.scalar(
                            &rec,
                            "tread/series/load_factor",
                            "load factor λ [1]",
                            lambda,
                        );
                    }
                    for (f, v) in msg.fields() {
                        let name = f.name();
                        if matches!(name, "step" | "time" | "index") {
                            continue;
                        }
                        if let Some(x) = number(v) {
                            let entity = format!("{topic}/{name}");
                            let label = draw.label(&topic, name);
                            draw.scalar(&rec, &entity, &label, x);
                            if topic == "tread/newton" && name == "residual" && x > 0.0 {
                                draw.scalar(
                                    &rec,
                                    "tread/newton/log10_residual",
                                    "log10 relative residual [1]",
                                    x.log10(),
                                );
                            }
                        }
                    }
                }
            }
        }
        let flushed = rec.flush_blocking().map_err(|e| e.to_string());
        drop(rec);
        flushed.map_err(failed)?;
        file.finish().map_err(failed)?;
        std::fs::rename(&tmp, rrd).map_err(|e| failed(e.to_string()))?;
        Ok(st)
    }

    /// A field of the `scene` metadata record of an MCAP log (`toml`: the resolved scene, `mode`,
    /// `time`: `time` or `load_factor`).
    fn mcap_scene_field(bytes: &[u8], field: &str) -> Option<String> {
        let reader = mcap::read::LinearReader::new(bytes).ok()?;
        for r in reader {
            match r {
                Ok(mcap::records::Record::Metadata(m)) if m.name == "scene" => {
                    return m.metadata.get(field).cloned();
                }
                Ok(_) => {}
                Err(_) => return None,
            }
        }
        None
    }

    fn f64_list(m: &DynamicMessage, name: &str) -> Vec<f64> {
        match m.get_field_by_name(name).map(|v| v.into_owned()) {
            Some(Value::List(l)) => l.iter().map(|v| number(v).unwrap_or(f64::NAN)).collect(),
            _ => Vec::new(),
        }
    }

    /// What the drawings of the run's own `.rrd` need, gathered from the messages.
    struct Drawing {
        units: Units,
        ro: f64,
        /// Lowest x2 of the body in the last `/tread/nodes` cloud.
        bottom: f64,
        /// The last road height (`/tread/series/road_height`).
        road: Option<f64>,
        /// Series whose name and style are logged.
        styled: BTreeSet<String>,
    }

    impl Drawing {
        /// `name [unit]` of field `field` of `topic`, as the run's own `.rrd` names it.
        fn label(&self, topic: &str, field: &str) -> String {
            let name = match topic {
                "tread/hub" => format!("hub_{field}"),
                "tread/energy" => format!("energy_{field}"),
                "tread/step" if field == "newton_iterations" => {
                    return "Newton iterations per step [iterations]".into()
                }
                "tread/newton" if field == "residual" => return "relative residual [1]".into(),
                t => match t.strip_prefix("tread/series/") {
                    Some(n) if field == "value" => n.to_string(),
                    _ => field.to_string(),
                },
            };
            series_label(&self.units, &name)
        }

        /// A finite value of a series, named (and for the residuals drawn as dots) the first
        /// time.
        fn scalar(&mut self, rec: &rerun::RecordingStream, entity: &str, name: &str, x: f64) {
            if !x.is_finite() {
                return;
            }
            if self.styled.insert(entity.to_string()) {
                let _ = if entity.starts_with("tread/newton/") && entity.ends_with("residual") {
                    rec.log_static(
                        entity,
                        &rerun::SeriesPoints::new()
                            .with_names([name])
                            .with_marker_sizes([1.5]),
                    )
                } else {
                    rec.log_static(entity, &rerun::SeriesLines::new().with_names([name]))
                };
            }
            let _ = rec.log(entity, &rerun::Scalars::single(x));
            if entity == "tread/series/road_height/value" {
                self.road = Some(x);
            }
        }

        /// The colour scale of `/tread/nodes` and the traction arrows of `/tread/contact`.
        fn cloud(&mut self, rec: &rerun::RecordingStream, topic: &str, c: &Cloud) {
            let col = |n: &str| c.get(n).map(Vec::as_slice).unwrap_or(&[]);
            match topic {
                "tread/nodes" => {
                    self.bottom = col("y").iter().copied().fold(f64::INFINITY, f64::min);
                    let max = col("max_shear_stress")
                        .iter()
                        .copied()
                        .filter(|x| x.is_finite())
                        .fold(0.0, f64::max);
                    let _ = rrd_draw::colour_scale(rec, "tread", self.ro, max, &self.units);
                }
                "tread/contact" => {
                    let (x, y, tn, tt) = (col("x"), col("y"), col("t_n"), col("t_t"));
                    let k: Vec<usize> = (0..x.len().min(y.len()).min(tn.len()).min(tt.len()))
                        .filter(|&k| tn[k] > 0.0)
                        .collect();
                    let origins: Vec<[f32; 3]> =
                        k.iter().map(|&k| [x[k] as f32, y[k] as f32, 0.0]).collect();
                    let t: Vec<(f64, f64)> = k.iter().map(|&k| (tn[k], tt[k])).collect();
                    let _ = rrd_draw::traction_arrows(rec, "tread/traction", &origins, &t, self.ro);
                }
                _ => {}
            }
        }

        /// The contact curves below the road and the pressure and shear charts of a
        /// `/tread/contact_patch` message.
        fn contact(&mut self, rec: &rerun::RecordingStream, topic: &str, msg: &DynamicMessage) {
            if topic != "tread/contact_patch" {
                return;
            }
            let (x1, tn, tt) = (
                f64_list(msg, "x1"),
                f64_list(msg, "t_n"),
                f64_list(msg, "t_t"),
            );
            let n = x1.len().min(tn.len()).min(tt.len());
            let pts = rrd_draw::sorted_patch((0..n).map(|k| (x1[k], tn[k], tt[k])));
            if pts.is_empty() {
                return;
            }
            let _ = rrd_draw::contact_charts(
                rec,
                "tread/contact_chart/pressure",
                "tread/contact_chart/shear",
                &pts,
                &self.units,
            );
            let base = (-self.road.unwrap_or(self.ro)).min(self.bottom) - 0.1 * self.ro;
            let _ = rrd_draw::contact_curves(
                rec,
                "tread/contact_curves",
                &pts,
                base,
                self.ro,
                &self.units,
            );
        }
    }

    fn descriptor(ch: &mcap::Channel) -> Option<MessageDescriptor> {
        let schema = ch.schema.as_ref()?;
        if schema.encoding != "protobuf" || ch.message_encoding != "protobuf" {
            return None;
        }
        let pool = DescriptorPool::decode(schema.data.as_ref()).ok()?;
        pool.get_message_by_name(&schema.name)
    }

    fn number(v: &Value) -> Option<f64> {
        Some(match v {
            Value::F64(x) => *x,
            Value::F32(x) => f64::from(*x),
            Value::I32(x) => f64::from(*x),
            Value::I64(x) => *x as f64,
            Value::U32(x) => f64::from(*x),
            Value::U64(x) => *x as f64,
            Value::Bool(b) => f64::from(u8::from(*b)),
            _ => return None,
        })
    }

    fn uint_field(msg: &DynamicMessage, name: &str) -> Option<u64> {
        match msg.get_field_by_name(name)?.as_ref() {
            Value::U64(x) => Some(*x),
            Value::U32(x) => Some(u64::from(*x)),
            _ => None,
        }
    }

    fn f64_of(m: &DynamicMessage, name: &str) -> f64 {
        m.get_field_by_name(name)
            .and_then(|v| number(&v))
            .unwrap_or(0.0)
    }

    fn messages(m: &DynamicMessage, name: &str) -> Vec<DynamicMessage> {
        match m.get_field_by_name(name).map(|v| v.into_owned()) {
            Some(Value::List(l)) => l
                .into_iter()
                .filter_map(|v| match v {
                    Value::Message(x) => Some(x),
                    _ => None,
                })
                .collect(),
            _ => Vec::new(),
        }
    }

    fn point3(p: &DynamicMessage) -> [f32; 3] {
        [
            f64_of(p, "x") as f32,
            f64_of(p, "y") as f32,
            f64_of(p, "z") as f32,
        ]
    }

    fn color(c: &DynamicMessage) -> rerun::Color {
        let b = |n: &str| (f64_of(c, n) * 255.0).round().clamp(0.0, 255.0) as u8;
        rerun::Color::from_unmultiplied_rgba(b("r"), b("g"), b("b"), b("a"))
    }

    fn scene_update(rec: &rerun::RecordingStream, topic: &str, msg: &DynamicMessage) {
        for e in messages(msg, "entities") {
            let id = match e.get_field_by_name("id").map(|v| v.into_owned()) {
                Some(Value::String(s)) if !s.is_empty() => s,
                _ => "entity".to_string(),
            };
            for (k, t) in messages(&e, "triangles").iter().enumerate() {
                let pts: Vec<[f32; 3]> = messages(t, "points").iter().map(point3).collect();
                let idx: Vec<u32> = match t.get_field_by_name("indices").map(|v| v.into_owned()) {
                    Some(Value::List(l)) => l
                        .iter()
                        .filter_map(|v| match v {
                            Value::U32(x) => Some(*x),
                            _ => None,
                        })
                        .collect(),
                    _ => Vec::new(),
                };
                let tris: Vec<[u32; 3]> = if idx.is_empty() {
                    (0..pts.len() as u32 / 3)
                        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                        .collect()
                } else {
                    idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
                };
                let colors: Vec<rerun::Color> = messages(t, "colors").iter().map(color).collect();
                let mut mesh = rerun::Mesh3D::new(pts).with_triangle_indices(tris);
                if !colors.is_empty() {
                    mesh = mesh.with_vertex_colors(colors);
                }
                let _ = rec.log(format!("{topic}/{id}/triangles/{k}"), &mesh);
            }
            let strips: Vec<Vec<[f32; 3]>> = messages(&e, "lines")
                .iter()
                .map(|l| messages(l, "points").iter().map(point3).collect())
                .collect();
            if !strips.is_empty() {
                let _ = rec.log(
                    format!("{topic}/{id}/lines"),
                    &rerun::LineStrips3D::new(strips),
                );
            }
        }
    }

    /// The fields of a point cloud by name, one value per point.
    type Cloud = HashMap<String, Vec<f64>>;

    /// Log a `foxglove.PointCloud` as `Points3D`; returns its fields.
    fn point_cloud(rec: &rerun::RecordingStream, topic: &str, msg: &DynamicMessage) -> Cloud {
        let stride = f64_of(msg, "point_stride") as usize;
        let data = match msg.get_field_by_name("data").map(|v| v.into_owned()) {
            Some(Value::Bytes(b)) => b,
            _ => return Cloud::new(),
        };
        let mut fields: HashMap<String, (usize, i32)> = HashMap::new();
        for f in messages(msg, "fields") {
            let name = match f.get_field_by_name("name").map(|v| v.into_owned()) {
                Some(Value::String(s)) => s,
                _ => continue,
            };
            let ty = match f.get_field_by_name("type").map(|v| v.into_owned()) {
                Some(Value::EnumNumber(n)) => n,
                _ => 0,
            };
            fields.insert(name, (f64_of(&f, "offset") as usize, ty));
        }
        if stride == 0 {
            return Cloud::new();
        }
        let read = |p: usize, name: &str| -> Option<f64> {
            let (off, ty) = *fields.get(name)?;
            let b = data.get(p * stride + off..)?;
            Some(match ty {
                1 => f64::from(*b.first()?),
                7 => f64::from(f32::from_le_bytes(b.get(..4)?.try_into().ok()?)),
                8 => f64::from_le_bytes(b.get(..8)?.try_into().ok()?),
                _ => return None,
            })
        };
        let n = data.len() / stride;
        let pos: Vec<[f32; 3]> = (0..n)
            .map(|p| {
                [
                    read(p, "x").unwrap_or(0.0) as f32,
                    read(p, "y").unwrap_or(0.0) as f32,
                    read(p, "z").unwrap_or(0.0) as f32,
                ]
            })
            .collect();
        let mut pts = rerun::Points3D::new(pos);
        if fields.contains_key("red") {
            let c: Vec<rerun::Color> = (0..n)
                .map(|p| {
                    let g = |k| read(p, k).unwrap_or(0.0).clamp(0.0, 255.0) as u8;
                    rerun::Color::from_rgb(g("red"), g("green"), g("blue"))
                })
                .collect();
            pts = pts.with_colors(c);
        }
        let _ = rec.log(topic, &pts);
        fields
            .keys()
            .map(|k| {
                let col = (0..n).map(|p| read(p, k).unwrap_or(f64::NAN)).collect();
                (k.clone(), col)
            })
            .collect()
    }
}
