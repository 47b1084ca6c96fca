//! Independent readers of the output files for the tests: the mcap crate's streaming reader
//! with prost-reflect decoding through the schema embedded in the file, the rerun crate's .rrd
//! decoder, a quick-xml parse of VTU/PVD, a plain CSV split and the PNG header.
#![allow(dead_code)]

use prost_reflect::{DescriptorPool, DynamicMessage, MessageDescriptor, Value};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

pub struct McapMessage {
    pub topic: String,
    pub schema: String,
    pub log_time: u64,
    pub msg: DynamicMessage,
}

pub struct Mcap {
    pub messages: Vec<McapMessage>,
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// The stream ended with an error (a truncated file).
    pub truncated: bool,
}

impl Mcap {
    pub fn topic(&self, t: &str) -> Vec<&McapMessage> {
        self.messages.iter().filter(|m| m.topic == t).collect()
    }
    pub fn count(&self, t: &str) -> usize {
        self.messages.iter().filter(|m| m.topic == t).count()
    }
}

pub fn f64_field(m: &DynamicMessage, name: &str) -> f64 {
    match m.get_field_by_name(name).map(|v| v.into_owned()) {
        Some(Value::F64(x)) => x,
        Some(Value::F32(x)) => f64::from(x),
        Some(Value::U64(x)) => x as f64,
        Some(Value::U32(x)) => f64::from(x),
        Some(Value::I64(x)) => x as f64,
        Some(Value::I32(x)) => f64::from(x),
        Some(Value::Bool(b)) => f64::from(u8::from(b)),
        other => panic!("field {name}: {other:?}"),
    }
}

pub fn list_f64(m: &DynamicMessage, name: &str) -> Vec<f64> {
    match m.get_field_by_name(name).map(|v| v.into_owned()) {
        Some(Value::List(l)) => l
            .into_iter()
            .map(|v| match v {
                Value::F64(x) => x,
                other => panic!("{name}: {other:?}"),
            })
            .collect(),
        other => panic!("field {name}: {other:?}"),
    }
}

pub fn bytes_field(m: &DynamicMessage, name: &str) -> Vec<u8> {
    match m.get_field_by_name(name).map(|v| v.into_owned()) {
        Some(Value::Bytes(b)) => b.to_vec(),
        other => panic!("field {name}: {other:?}"),
    }
}

/// Read every message (decoded with its embedded protobuf schema) and the metadata records.
/// With a truncated file, the messages before the damage are returned and `truncated` is set.
pub fn read_mcap(path: &Path) -> Mcap {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut metadata = BTreeMap::new();
    let reader = mcap::read::LinearReader::new_with_options(
        &bytes,
        mcap::read::Options::IgnoreEndMagic.into(),
    )
    .expect("mcap magic");
    for r in reader {
        match r {
            Ok(mcap::records::Record::Metadata(m)) => {
                metadata.insert(m.name.clone(), m.metadata.clone());
            }
            Ok(_) => {}
            Err(_) => break,
        }
    }
    let mut messages = Vec::new();
    let mut truncated = false;
    let mut descs: HashMap<u16, MessageDescriptor> = HashMap::new();
    for m in mcap::MessageStream::new(&bytes).expect("mcap stream") {
        let m = match m {
            Ok(m) => m,
            Err(_) => {
                truncated = true;
                break;
            }
        };
        let schema = m
            .channel
            .schema
            .as_ref()
            .expect("every channel has a schema");
        assert_eq!(schema.encoding, "protobuf", "{}", m.channel.topic);
        assert_eq!(m.channel.message_encoding, "protobuf");
        let desc = descs
            .entry(m.channel.id)
            .or_insert_with(|| {
                DescriptorPool::decode(schema.data.as_ref())
                    .expect("schema is a FileDescriptorSet")
                    .get_message_by_name(&schema.name)
                    .unwrap_or_else(|| panic!("schema names its message: {}", schema.name))
            })
            .clone();
        let msg = DynamicMessage::decode(desc, m.data.as_ref())
            .unwrap_or_else(|e| panic!("{}: {e}", m.channel.topic));
        messages.push(McapMessage {
            topic: m.channel.topic.clone(),
            schema: schema.name.clone(),
            log_time: m.log_time,
            msg,
        });
    }
    Mcap {
        messages,
        metadata,
        truncated,
    }
}

/// `(header, rows)` of a CSV file (empty fields as NaN).
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(
        !text.contains("NaN") && !text.contains("inf"),
        "{}",
        path.display()
    );
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .filter(|l| !l.is_empty())
        .map(|l| {
            l.split(',')
                .map(|c| {
                    if c.is_empty() {
                        f64::NAN
                    } else {
                        c.parse().unwrap()
                    }
                })
                .collect::<Vec<f64>>()
        })
        .collect();
    (header, rows)
}

pub fn column(header: &[String], rows: &[Vec<f64>], name: &str) -> Vec<f64> {
    let k = header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"));
    rows.iter().map(|r| r[k]).collect()
}

/// A parsed `.vtu`.
#[derive(Debug, Default)]
pub struct Vtu {
    pub n_points: usize,
    pub n_cells: usize,
    pub time: f64,
    pub points: Vec<f64>,
    /// Point-data and cell arrays by name (flattened).
    pub arrays: BTreeMap<String, Vec<f64>>,
}

/// Parse a `.vtu` written as ASCII or as raw appended binary (`header_type="UInt64"`).
pub fn parse_vtu(path: &Path) -> Vtu {
    use quick_xml::events::Event;
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let marker = b"<AppendedData encoding=\"raw\">";
    let (xml, blob): (String, &[u8]) = match bytes.windows(marker.len()).position(|w| w == marker) {
        Some(k) => {
            let us = k + bytes[k..]
                .iter()
                .position(|&b| b == b'_')
                .expect("'_' after AppendedData");
            let head = String::from_utf8(bytes[..k].to_vec()).expect("utf8 XML header");
            (head + "</VTKFile>", &bytes[us + 1..])
        }
        None => (String::from_utf8(bytes.clone()).expect("utf8"), &[]),
    };
    let decode = |ty: &str, offset: usize| -> Vec<f64> {
        let n = u64::from_le_bytes(blob[offset..offset + 8].try_into().unwrap()) as usize;
        let d = &blob[offset + 8..offset + 8 + n];
        match ty {
            "Float64" => d
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                .collect(),
            "Int64" => d
                .chunks_exact(8)
                .map(|c| i64::from_le_bytes(c.try_into().unwrap()) as f64)
                .collect(),
            "Int32" => d
                .chunks_exact(4)
                .map(|c| i32::from_le_bytes(c.try_into().unwrap()) as f64)
                .collect(),
            "UInt8" => d.iter().map(|&b| f64::from(b)).collect(),
            other => panic!("unknown VTK type {other}"),
        }
    };
    let mut r = quick_xml::Reader::from_str(&xml);
    let mut v = Vtu::default();
    let mut current: Option<String> = None;
    let mut in_points = false;
    let store = |v: &mut Vtu, name: &str, vals: Vec<f64>| {
        if name == "Points" {
            v.points.extend(vals);
        } else if name == "TimeValue" {
            v.time = vals[0];
        } else {
            v.arrays.entry(name.to_string()).or_default().extend(vals);
        }
    };
    loop {
        match r.read_event().expect("well-formed XML") {
            ev @ (Event::Start(_) | Event::Empty(_)) => {
                let empty = matches!(ev, Event::Empty(_));
                let (Event::Start(e) | Event::Empty(e)) = ev else {
                    unreachable!()
                };
                let attr = |k: &str| {
                    e.attributes()
                        .flatten()
                        .find(|a| a.key.as_ref() == k.as_bytes())
                        .map(|a| String::from_utf8_lossy(&a.value).to_string())
                };
                match e.name().as_ref() {
                    b"Piece" => {
                        v.n_points = attr("NumberOfPoints").unwrap().parse().unwrap();
                        v.n_cells = attr("NumberOfCells").unwrap().parse().unwrap();
                    }
                    b"Points" => in_points = true,
                    b"DataArray" => {
                        let name = attr("Name").unwrap_or_else(|| {
                            if in_points {
                                "Points".into()
                            } else {
                                "?".into()
                            }
                        });
                        if attr("format").as_deref() == Some("appended") {
                            let off: usize = attr("offset").unwrap().parse().unwrap();
                            let vals = decode(&attr("type").unwrap(), off);
                            store(&mut v, &name, vals);
                        } else if !empty {
                            current = Some(name);
                        }
                    }
                    _ => {}
                }
            }
            Event::End(e) => {
                if e.name().as_ref() == b"Points" {
                    in_points = false;
                }
                if e.name().as_ref() == b"DataArray" {
                    current = None;
                }
            }
            Event::Text(t) => {
                if let Some(name) = &current {
                    let s = t.decode().expect("utf8").to_string();
                    let vals: Vec<f64> = s
                        .split_whitespace()
                        .map(|w| w.parse::<f64>().expect("number"))
                        .collect();
                    store(&mut v, name, vals);
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    v
}

/// `(timestep, file)` of every data set of a `.pvd`.
pub fn parse_pvd(path: &Path) -> Vec<(f64, String)> {
    use quick_xml::events::Event;
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut r = quick_xml::Reader::from_str(&text);
    let mut out = Vec::new();
    loop {
        match r.read_event().expect("well-formed XML") {
            Event::Empty(e) | Event::Start(e) if e.name().as_ref() == b"DataSet" => {
                let get = |k: &str| {
                    e.attributes()
                        .flatten()
                        .find(|a| a.key.as_ref() == k.as_bytes())
                        .map(|a| String::from_utf8_lossy(&a.value).to_string())
                        .unwrap()
                };
                out.push((get("timestep").parse().unwrap(), get("file")));
            }
            Event::Eof => break,
            _ => {}
        }
    }
    out
}

/// Width and height of a PNG (from its IHDR chunk), after checking the signature.
pub fn png_size(path: &Path) -> (u32, u32) {
    let b = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    assert_eq!(&b[12..16], b"IHDR");
    (
        u32::from_be_bytes(b[16..20].try_into().unwrap()),
        u32::from_be_bytes(b[20..24].try_into().unwrap()),
    )
}

/// What one entity of an `.rrd` holds, rows sorted by the `step` timeline.
#[cfg(feature = "rerun")]
#[derive(Debug, Default, Clone)]
pub struct RrdEntity {
    /// (step, sim_time in ns) of each temporal row.
    pub times: Vec<(i64, i64)>,
    /// Scalars values, in step order.
    pub scalars: Vec<f64>,
    /// Vertex count of each Mesh3D row, in step order.
    pub mesh_vertices: Vec<usize>,
    /// First vertex positions of the last Mesh3D row.
    pub last_vertices: Vec<[f32; 3]>,
    pub static_rows: usize,
}

/// One temporal row of an entity: step, sim_time, its scalar and its mesh vertices.
#[cfg(feature = "rerun")]
type RrdRow = (i64, i64, Option<f64>, Option<Vec<[f32; 3]>>);

/// Decode an `.rrd` with the rerun crate's decoder; entities by path (e.g. `/hub/force_y`).
#[cfg(feature = "rerun")]
pub fn read_rrd(path: &Path) -> BTreeMap<String, RrdEntity> {
    use rerun::external::re_log_encoding::DecoderApp;
    use rerun::log::{Chunk, LogMsg};
    let f = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut rows: BTreeMap<String, Vec<RrdRow>> = BTreeMap::new();
    let mut statics: BTreeMap<String, usize> = BTreeMap::new();
    let scalars_id = rerun::archetypes::Scalars::descriptor_scalars().component;
    let verts_id = rerun::archetypes::Mesh3D::descriptor_vertex_positions().component;
    for msg in DecoderApp::decode_lazy(std::io::BufReader::new(f)) {
        let msg = msg.unwrap_or_else(|e| panic!("{}: decode: {e}", path.display()));
        let LogMsg::ArrowMsg(_, arrow) = msg else {
            continue;
        };
        let chunk = Chunk::from_arrow_msg(&arrow).expect("chunk");
        let entity = chunk.entity_path().to_string();
        if chunk.is_static() {
            *statics.entry(entity).or_default() += chunk.num_rows();
            continue;
        }
        let steps: Vec<i64> = chunk
            .timelines()
            .get(&rerun::TimelineName::from("step"))
            .map(|c| c.times_raw().to_vec())
            .unwrap_or_else(|| vec![-1; chunk.num_rows()]);
        let sim: Vec<i64> = chunk
            .timelines()
            .get(&rerun::TimelineName::from("sim_time"))
            .map(|c| c.times_raw().to_vec())
            .unwrap_or_else(|| vec![-1; chunk.num_rows()]);
        let s: Vec<Option<f64>> = if chunk.components().get_array(scalars_id).is_some() {
            chunk
                .iter_slices::<f64>(scalars_id)
                .map(|x| x.first().copied())
                .collect()
        } else {
            vec![None; chunk.num_rows()]
        };
        let v: Vec<Option<Vec<[f32; 3]>>> = if chunk.components().get_array(verts_id).is_some() {
            chunk
                .iter_slices::<[f32; 3]>(verts_id)
                .map(|x| Some(x.to_vec()))
                .collect()
        } else {
            vec![None; chunk.num_rows()]
        };
        let e = rows.entry(entity).or_default();
        for i in 0..chunk.num_rows() {
            e.push((
                steps[i],
                sim[i],
                s.get(i).copied().flatten(),
                v.get(i).cloned().flatten(),
            ));
        }
    }
    let mut out: BTreeMap<String, RrdEntity> = BTreeMap::new();
    for (k, n) in statics {
        out.entry(k).or_default().static_rows = n;
    }
    for (k, mut r) in rows {
        r.sort_by_key(|x| (x.0, x.1));
        let e = out.entry(k).or_default();
        for (st, t, s, v) in r {
            e.times.push((st, t));
            if let Some(s) = s {
                e.scalars.push(s);
            }
            if let Some(v) = v {
                e.mesh_vertices.push(v.len());
                e.last_vertices = v;
            }
        }
    }
    out
}
