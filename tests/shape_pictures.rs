//! Deformed-shape pictures of the steady continuation in ω (`[output] snapshot_omegas`): a
//! tiny version of `scenarios/oden_figs_9_13.toml` (coarse mesh, a few steps) writes one PNG
//! per requested speed and a montage, valid PNGs of the expected size whose pictures differ
//! between speeds; the branch plot is written too; bad lists are refused naming the key. The
//! rasteriser: which pixels a triangle covers, colour interpolation, the colour bar's ends.

#[path = "common/tempdir.rs"]
mod tempdir;

use std::path::Path;
use tempdir::TestDir;
use tread::app::RunOptions;
use tread::io::record::colormap;
use tread::io::record::shape::{omega_tag, von_mises, Raster};
use tread::io::Scene;

const FIGS: &str = include_str!("../scenarios/oden_figs_9_13.toml");

fn scene(set: &[&str]) -> Result<Scene, String> {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    Scene::from_toml_str(FIGS, "figs", &set).map_err(|e| e.to_string())
}

/// Width, height and RGB pixels of a PNG file (8-bit RGB or RGBA).
fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    let (w, h) = (be(16), be(20));
    let dec = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut r = dec
        .read_info()
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut buf = vec![0; r.output_buffer_size()];
    let info = r
        .next_frame(&mut buf)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!((info.width, info.height), (w, h));
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let ch = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        c => panic!("{}: colour type {c:?}", path.display()),
    };
    let rgb = buf[..info.buffer_size()]
        .chunks(ch)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    (w, h, rgb)
}

#[test]
fn shape_pictures_at_the_requested_speeds() {
    let dir = TestDir::new("shape", "tiny");
    let sc = scene(&[
        "mesh.n_r=2",
        "mesh.n_theta=24",
        "continuation.target=40",
        "continuation.ds=0.2",
        "continuation.ds_max=0.4",
        "continuation.max_steps=8",
        "output.sinks=summary,csv,png",
        "output.snapshot_omegas=10,25,40",
        "output.displacement_scale=2",
    ])
    .unwrap_or_else(|e| panic!("{e}"));
    let opts = RunOptions {
        out_dir: dir.to_path_buf(),
        verbose: false,
        quiet: true,
    };
    let out = tread::app::run(&sc, &opts).unwrap_or_else(|e| panic!("{e}"));
    let branch = out.summary["results"]["branch"]
        .as_array()
        .unwrap_or_else(|| panic!("no branch: {}", out.summary));
    assert!(branch.len() >= 3, "{}", out.summary);
    let singles: Vec<_> = ["10", "25", "40"]
        .iter()
        .map(|w| decode(&dir.join(format!("shape_omega_{w}.png"))))
        .collect();
    for (w, h, rgb) in &singles {
        assert_eq!((*w, *h), (780 + 150, 680), "single picture size");
        // The body is drawn: many pixels are neither white nor grey.
        let coloured = rgb
            .chunks(3)
            .filter(|p| !(p[0] == p[1] && p[1] == p[2]))
            .count();
        assert!(coloured > 20_000, "{coloured} coloured pixels");
    }
    // Pictures of different speeds differ (shape, stress and title).
    assert_ne!(singles[0].2, singles[1].2);
    assert_ne!(singles[1].2, singles[2].2);
    let (w, h, _) = decode(&dir.join("shape_montage.png"));
    assert_eq!((w, h), (3 * 360 + 150, 46 + 380), "montage size");
    // The branch plot: one panel per quantity.
    let (_, bh, _) = decode(&dir.join("branch.png"));
    assert!(bh >= 560, "{bh}");
}

#[test]
fn bad_snapshot_lists_are_refused_naming_the_key() {
    for bad in [
        "output.snapshot_omegas=10,fast",
        "output.snapshot_omegas=[10, \"x\"]",
        "output.snapshot_omegas=[1,2,3,4,5,6,7,8,9,10,11,12,13]",
        "output.snapshot_omegas=nan",
    ] {
        let e = scene(&[bad])
            .err()
            .unwrap_or_else(|| panic!("accepted {bad}"));
        assert!(e.contains("output.snapshot_omegas"), "{bad}: {e}");
    }
    let ok = scene(&["output.snapshot_omegas=[5, 20.5]"]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(ok.output.snapshot_omegas, [5.0, 20.5]);
    let one = scene(&["output.snapshot_omegas=30"]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(one.output.snapshot_omegas, [30.0]);
}

#[test]
fn a_triangle_covers_the_pixels_whose_centres_are_inside() {
    let mut r = Raster::new(10, 10, [255, 255, 255]);
    // Right triangle with legs along the top and left edges of a 6 × 6 square.
    r.fill_triangle([[0.0, 0.0], [6.0, 0.0], [0.0, 6.0]], [1.0; 3], 0.0, 1.0);
    let top = colormap(1.0);
    for y in 0..10 {
        for x in 0..10 {
            let inside = (x as f64 + 0.5) + (y as f64 + 0.5) <= 6.0;
            let want = if inside { top } else { [255, 255, 255] };
            assert_eq!(r.pixel(x, y), Some(want), "pixel ({x}, {y})");
        }
    }
    // Either orientation draws the same; degenerate and non-finite triangles draw nothing.
    let mut s = Raster::new(10, 10, [255, 255, 255]);
    s.fill_triangle([[0.0, 0.0], [0.0, 6.0], [6.0, 0.0]], [1.0; 3], 0.0, 1.0);
    assert_eq!(r, s);
    let blank = Raster::new(10, 10, [255, 255, 255]);
    let mut d = blank.clone();
    d.fill_triangle([[0.0, 0.0], [5.0, 5.0], [9.0, 9.0]], [1.0; 3], 0.0, 1.0);
    d.fill_triangle(
        [[0.0, f64::NAN], [5.0, 0.0], [0.0, 5.0]],
        [1.0; 3],
        0.0,
        1.0,
    );
    assert_eq!(d, blank);
    // Off-image parts are clipped.
    let mut c = blank.clone();
    c.fill_triangle(
        [[-50.0, -50.0], [60.0, -50.0], [-50.0, 60.0]],
        [0.0; 3],
        0.0,
        1.0,
    );
    assert_eq!(c.pixel(0, 0), Some(colormap(0.0)));
    assert_eq!(c.pixel(9, 9), Some([255, 255, 255]));
}

#[test]
fn colours_are_interpolated_and_the_bar_maps_min_and_max_to_its_ends() {
    let mut r = Raster::new(100, 4, [255, 255, 255]);
    // Value = x / 100 along a long thin pair of triangles: colour of lo at the left end,
    // of hi at the right end.
    r.fill_triangle(
        [[0.0, 0.0], [100.0, 0.0], [100.0, 4.0]],
        [0.0, 100.0, 100.0],
        0.0,
        100.0,
    );
    r.fill_triangle(
        [[0.0, 0.0], [100.0, 4.0], [0.0, 4.0]],
        [0.0, 100.0, 0.0],
        0.0,
        100.0,
    );
    assert_eq!(r.pixel(0, 2), Some(colormap(0.005)));
    assert_eq!(r.pixel(99, 2), Some(colormap(0.995)));
    assert_eq!(r.pixel(50, 2), Some(colormap(0.505)));
    let mut b = Raster::new(5, 50, [255, 255, 255]);
    b.colour_bar(1, 0, 3, 50);
    assert_eq!(b.pixel(2, 0), Some(colormap(1.0)));
    assert_eq!(b.pixel(2, 49), Some(colormap(0.0)));
    assert_eq!(b.pixel(0, 10), Some([255, 255, 255]));
    assert_eq!(b.pixel(4, 10), Some([255, 255, 255]));
}

#[test]
fn von_mises_of_simple_states() {
    // Uniaxial σ11 = s: s; pure shear σ12 = t: √3 t; hydrostatic: 0.
    assert!((von_mises([2.0, 0.0, 0.0], 0.0) - 2.0).abs() < 1e-14);
    assert!((von_mises([0.0, 0.0, 1.0], 0.0) - 3f64.sqrt()).abs() < 1e-14);
    assert!(von_mises([-5.0, -5.0, 0.0], -5.0).abs() < 1e-14);
    assert_eq!(omega_tag(10.0), "10");
    assert_eq!(omega_tag(45.25), "45.25");
    assert_eq!(omega_tag(-3.5), "m3.5");
}
