//! zlib-compressed binary VTU (`[output] vtu_compression = "zlib"`): every appended array,
//! decompressed block by block with the VTK header read independently here, equals the raw
//! binary array of the uncompressed file, byte for byte; arrays longer than one 32 KiB block are
//! split as VTK does; a scene asking for compression with the ascii format is refused.

#[path = "common/tempdir.rs"]
mod tempdir;

use std::collections::BTreeMap;
use std::io::Read;
use tread::io::record::vtu::{vtu_bytes, Encoding, VtuCompression, VtuFormat, ZLIB_BLOCK};
use tread::io::record::StepView;
use tread::mesh::annulus::{annulus, AnnulusSpec};

fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

/// (name or `Points`, offset) of every appended array, and the appended block.
fn appended(file: &[u8]) -> (Vec<(String, usize)>, Vec<u8>) {
    let marker = b"<AppendedData encoding=\"raw\">\n_";
    let at = file
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("appended block")
        + marker.len();
    let head = String::from_utf8_lossy(&file[..at]).into_owned();
    let mut arrays = Vec::new();
    for tag in head.split("<DataArray ").skip(1) {
        let tag = &tag[..tag.find('>').unwrap()];
        let Some(o) = tag.find("offset=\"") else {
            continue; // the inline TimeValue
        };
        let o = &tag[o + 8..];
        let offset: usize = o[..o.find('"').unwrap()].parse().unwrap();
        let name = tag
            .find("Name=\"")
            .map(|n| {
                let n = &tag[n + 6..];
                n[..n.find('"').unwrap()].to_string()
            })
            .unwrap_or_else(|| "Points".into());
        arrays.push((name, offset));
    }
    (arrays, file[at..].to_vec())
}

fn raw_arrays(file: &[u8]) -> BTreeMap<String, Vec<u8>> {
    let (arrays, blob) = appended(file);
    arrays
        .into_iter()
        .map(|(n, o)| {
            let len = u64_at(&blob, o) as usize;
            (n, blob[o + 8..o + 8 + len].to_vec())
        })
        .collect()
}

/// Decompressed arrays and the number of blocks of each.
fn zlib_arrays(file: &[u8]) -> BTreeMap<String, (Vec<u8>, usize)> {
    let (arrays, blob) = appended(file);
    arrays
        .into_iter()
        .map(|(n, o)| {
            let nb = u64_at(&blob, o) as usize;
            let bs = u64_at(&blob, o + 8) as usize;
            let last = u64_at(&blob, o + 16) as usize;
            assert_eq!(bs, ZLIB_BLOCK);
            let mut p = o + 24 + 8 * nb;
            let mut out = Vec::new();
            for k in 0..nb {
                let c = u64_at(&blob, o + 24 + 8 * k) as usize;
                let mut d = Vec::new();
                flate2::read::ZlibDecoder::new(&blob[p..p + c])
                    .read_to_end(&mut d)
                    .unwrap();
                // Every block but the last is full; the last is `last` bytes (0: full).
                let want = if k + 1 == nb && last != 0 { last } else { bs };
                assert_eq!(d.len(), want, "{n}: block {k}");
                out.extend_from_slice(&d);
                p += c;
            }
            (n, (out, nb))
        })
        .collect()
}

#[test]
fn zlib_vtu_decompresses_to_the_raw_arrays() {
    // 2 × 200 Q2 cells: 2000 nodes, so Points (48 KB) needs two blocks.
    let mesh = annulus(&AnnulusSpec {
        ri: 1.0,
        ro: 2.0,
        n_r: 2,
        n_theta: 200,
        degree: 2,
        grading_r: 1.0,
        grading_theta: 0.0,
    });
    let nn = mesh.n_nodes();
    assert!(24 * nn > ZLIB_BLOCK);
    let x: Vec<f64> = (0..2 * nn).map(|k| 1e-3 * (k as f64).sin()).collect();
    let stress: Vec<[f64; 3]> = (0..nn)
        .map(|n| [n as f64, -(n as f64), 0.5 * n as f64])
        .collect();
    let mut s33 = vec![0.25; nn];
    s33[7] = f64::NAN;
    let view = StepView {
        mesh: Some(&mesh),
        x: &x,
        stress: &stress,
        sigma_33: &s33,
        stress_recovered: &[],
        error_indicator: &[],
        pressure: &[],
        contact: &[],
        hub: None,
        energy: None,
        road_height: None,
        omega: 0.0,
        scalars: &[],
    };
    let raw = vtu_bytes(&mesh, &view, 0.5, VtuFormat::Binary);
    let z = vtu_bytes(
        &mesh,
        &view,
        0.5,
        Encoding {
            format: VtuFormat::Binary,
            compression: VtuCompression::Zlib,
        },
    );
    let zs = String::from_utf8_lossy(&z[..200]).into_owned();
    assert!(zs.contains("compressor=\"vtkZLibDataCompressor\""), "{zs}");
    assert!(!String::from_utf8_lossy(&raw[..200]).contains("compressor"));
    assert!(z.len() < raw.len(), "{} vs {}", z.len(), raw.len());
    let r = raw_arrays(&raw);
    let d = zlib_arrays(&z);
    assert_eq!(r.keys().collect::<Vec<_>>(), d.keys().collect::<Vec<_>>());
    for (name, bytes) in &r {
        let (dz, nb) = &d[name];
        assert_eq!(dz, bytes, "{name}");
        assert_eq!(*nb, bytes.len().div_ceil(ZLIB_BLOCK), "{name}");
    }
    assert!(d["Points"].1 >= 2);
    // NaN survives compression.
    let s = &d["sigma_33"].0;
    assert!(f64::from_le_bytes(s[56..64].try_into().unwrap()).is_nan());
}

#[test]
fn zlib_with_ascii_is_refused() {
    let toml = r#"
[scene]
name = "z"
[geometry]
ri = 1.0
ro = 2.0
[mesh]
n_r = 1
n_theta = 8
[material]
model = "neo_hookean"
mu = 1.0
lambda = 1.0
rho = 1.0
[analysis]
mode = "spinning"
[motion]
omega = 1.0
[output]
vtu_format = "ascii"
vtu_compression = "zlib"
"#;
    let e = tread::io::Scene::from_toml_str(toml, "z.toml", &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("output.vtu_compression"), "{e}");
    let ok = toml.replace("vtu_format = \"ascii\"", "vtu_format = \"binary\"");
    let s = tread::io::Scene::from_toml_str(&ok, "z.toml", &[]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.output.vtu_compression, VtuCompression::Zlib);
}
