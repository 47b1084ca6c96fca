//! `[output]`: output sinks, decimation, the VTU encoding and compression, and the Rerun
//! view's displacement magnification.

use super::issue::{issue, Issue};
use serde::{Deserialize, Serialize};

keyword_enum! {
    /// Encoding of the `.vtu` files (`[output] vtu_format`).
    #[derive(Default)]
    VtuFormat, "VTU format" {
        #[default]
        /// Raw little-endian binary in an appended block (`header_type="UInt64"`).
        Binary => "binary",
        /// Text (larger and slower; readable in an editor).
        Ascii => "ascii",
    }
}

keyword_enum! {
    /// Compression of the binary `.vtu` data (`[output] vtu_compression`).
    #[derive(Default)]
    VtuCompression, "VTU compression" {
        #[default]
        /// Raw bytes.
        None => "none",
        /// zlib (deflate) blocks of 32 KiB (`compressor="vtkZLibDataCompressor"`).
        Zlib => "zlib",
    }
}

keyword_enum! {
    /// An output sink (`[output] sinks`); see `src/io/record/mod.rs` and docs/outputs.md.
    Sink, "output sink" {
        /// `summary.json` (always written, also when not listed).
        Summary => "summary",
        /// CSV tables: `history.csv` (time histories) and the end-of-run tables.
        Csv => "csv",
        /// ParaView: `fields.pvd` + `fields/step_*.vtu` (and `steady.vtu`).
        Vtu => "vtu",
        /// `run.mcap` (protobuf channels readable by Foxglove and the Rerun viewer).
        Mcap => "mcap",
        /// `run.rrd` for the Rerun viewer (needs the default `rerun` cargo feature).
        Rerun => "rerun",
        /// PNG plots (hub forces, energy, contact distributions, branch diagrams).
        Png => "png",
    }
}

/// `[output]`: which sinks record the run and how often.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSpec {
    /// Output sinks; `summary.json` is written whether listed or not.
    pub sinks: Vec<Sink>,
    /// Decimation: steps between recorded frames (>= 1); the final step is always recorded.
    pub every: usize,
    /// Encoding of the `.vtu` files: `binary` (default) or `ascii`.
    pub vtu_format: VtuFormat,
    /// Displacement magnification of the body in the Rerun recording's view (> 0; default 1).
    pub displacement_scale: f64,
    /// Compression of the binary `.vtu` data: `none` (default) or `zlib`.
    pub vtu_compression: VtuCompression,
    /// Speeds (rad/s) at which the steady continuation in ω draws the deformed shape with
    /// stress contours (`shape_omega_<ω>.png`, `shape_montage.png`); empty: none.
    pub snapshot_omegas: Vec<f64>,
}

/// Most speeds `[output] snapshot_omegas` may list.
pub const MAX_SNAPSHOTS: usize = 12;

/// Default of `[output] sinks`: the light-weight outputs (MCAP and Rerun logs are opt-in).
pub const DEFAULT_SINKS: &[Sink] = &[Sink::Summary, Sink::Csv, Sink::Vtu, Sink::Png];

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            sinks: DEFAULT_SINKS.to_vec(),
            every: 1,
            vtu_format: VtuFormat::Binary,
            displacement_scale: 1.0,
            vtu_compression: VtuCompression::None,
            snapshot_omegas: Vec::new(),
        }
    }
}

impl OutputSpec {
    /// Whether `sink` is listed.
    pub fn has(&self, sink: Sink) -> bool {
        self.sinks.contains(&sink)
    }
}

pub(super) fn validate_output(s: &OutputSpec, out: &mut Vec<Issue>) {
    if s.every < 1 {
        out.push(issue("output.every", "must be >= 1, got 0"));
    }
    if !(s.displacement_scale.is_finite() && s.displacement_scale > 0.0) {
        out.push(issue(
            "output.displacement_scale",
            format!("must be a finite number > 0, got {}", s.displacement_scale),
        ));
    }
    if s.vtu_compression != VtuCompression::None && s.vtu_format == VtuFormat::Ascii {
        out.push(issue(
            "output.vtu_compression",
            "applies to vtu_format = \"binary\" only (the ascii format is not compressed)",
        ));
    }
    if s.snapshot_omegas.len() > MAX_SNAPSHOTS {
        out.push(issue(
            "output.snapshot_omegas",
            format!(
                "lists {} speeds; at most {MAX_SNAPSHOTS} are drawn",
                s.snapshot_omegas.len()
            ),
        ));
    }
    if let Some(w) = s.snapshot_omegas.iter().find(|w| !w.is_finite()) {
        out.push(issue(
            "output.snapshot_omegas",
            format!("must be finite numbers (rad/s), got {w}"),
        ));
    }
    for (i, k) in s.sinks.iter().enumerate() {
        if s.sinks[..i].contains(k) {
            out.push(issue("output.sinks", format!("\"{k}\" is listed twice")));
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::io::scene::tests::*;

    #[test]
    fn output_sinks_are_checked() {
        let text = format!("{MINIMAL}\n[output]\nsinks = [\"csv\", \"hdf5\"]\nevery = 0\n");
        let e = load(&text).err().unwrap_or_else(|| panic!("accepted"));
        let sinks = e.find("output.sinks").unwrap_or_else(|| panic!("{e}"));
        assert!(
            sinks.message.contains("hdf5") && sinks.line.is_some(),
            "{e}"
        );
        assert!(e.has_key("output.every"), "{e}");
        let text = format!("{MINIMAL}\n[output]\nsinks = [\"csv\", \"csv\"]\n");
        let e = load(&text).err().unwrap_or_else(|| panic!("accepted"));
        assert!(
            e.find("output.sinks")
                .is_some_and(|x| x.message.contains("twice")),
            "{e}"
        );
        let e = errors_with(MINIMAL, &["output.sinks=csv,nope"]);
        assert!(
            e.find("output.sinks")
                .is_some_and(|x| x.message.contains("nope")),
            "{e}"
        );
        // Round trip of a non-default list.
        let s = load_with(MINIMAL, &["output.sinks=mcap,rerun", "output.every=3"])
            .unwrap_or_else(|e| panic!("{e}"));
        let back = load(&s.to_toml_string()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(back, s);
    }
}
