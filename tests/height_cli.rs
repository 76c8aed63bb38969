//! End-to-end tests of the height outputs: `capture`'s height.exr in mm, `skinkit height` and its
//! deliverables (16-bit PNG at midlevel 0.5, cavity, bands), `synth --height` tiling, the PNG
//! colour chunks, and refusals. A module of `tests/cli.rs` (one test binary).

use std::path::Path;

use crate::support::{mold, s, skinkit, stderr};

/// The one channel `name` of an EXR file, its size and its header's text attributes.
fn read_exr_channel(path: &Path, name: &str) -> (usize, usize, Vec<f32>, Vec<(String, String)>) {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .unwrap();
    let layer = &image.layer_data[0];
    let size = layer.size;
    let channel = layer.channel_data.list.iter().find(|c| c.name == *name).expect("the channel");
    let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
    let attributes = layer
        .attributes
        .other
        .iter()
        .filter_map(|(k, v)| match v {
            exr::meta::attribute::AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    (size.width(), size.height(), values, attributes)
}

/// The value of `key` in the `skinkit` attribute's `key=value; ...` list (or a PNG's tEXt key).
fn attribute(attributes: &[(String, String)], key: &str) -> String {
    let (_, text) = attributes
        .iter()
        .find(|(k, _)| k == "skinkit")
        .unwrap_or_else(|| panic!("no skinkit attribute in {attributes:?}"));
    let key = key.trim_start_matches("skinkit.");
    text.split("; ")
        .find_map(|kv| kv.strip_prefix(&format!("{key}=")))
        .unwrap_or_else(|| panic!("{key} in {text}"))
        .to_string()
}

/// A PNG's 16-bit grey samples, its gAMA (if any) and its tEXt entries.
fn read_png16(path: &Path) -> (Vec<u16>, Option<f32>, Vec<(String, String)>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let samples = buf[..info.buffer_size()].chunks_exact(2).map(|b| u16::from_be_bytes([b[0], b[1]])).collect();
    let meta = reader.info();
    let gamma = meta.gama_chunk.or(meta.source_gamma).map(|g| g.into_value());
    let text = meta.uncompressed_latin1_text.iter().map(|t| (t.keyword.clone(), t.text.clone())).collect();
    (samples, gamma, text)
}

/// A capture whose rig gives the pixel size (the sample molds': 0.02 mm) writes height.exr in mm; its slopes give back the
/// capture's normals (the round trip), within a degree on average.
#[test]
fn capture_writes_height_in_mm_whose_normals_match_the_capture() {
    let tmp = tempfile::tempdir().unwrap();
    // The sample rigs give mm_per_pixel = 0.02.
    let rig = mold("forehead").join("rig.toml");
    let out = tmp.path().join("cap");
    let o = skinkit(&["capture", "--rig", s(&rig), "--photos-from", s(&mold("forehead")), "--out", s(&out), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["height_map"]["unit"], "mm", "{report}");
    let (w, h, heights, attrs) = read_exr_channel(&out.join("height.exr"), "Y");
    assert_eq!(
        (attribute(&attrs, "skinkit.unit"), attribute(&attrs, "skinkit.mm_per_texel")),
        ("mm".to_string(), "0.019999999552965164".to_string())
    );
    let normals = skinkit_maps::io::read_normal_map(
        &out.join("normal.exr"),
        skinkit_maps::NormalEncoding::default(),
        &skinkit_maps::Limits::default(),
    )
    .unwrap();
    // Central differences of the height step over two edges, each of which the integrator fits
    // to the mean slope of its two texels: so they are compared with the slopes filtered the same
    // way, [1, 2, 1] / 4 along each axis (the raw slopes differ more at pores two texels wide).
    let slope = |x: usize, y: usize| {
        let n = normals.get(x, y);
        (-n.x / n.z, n.y / n.z)
    };
    let (mut sum, mut n) = (0f64, 0usize);
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let dx = (heights[y * w + x + 1] - heights[y * w + x - 1]) / (2.0 * 0.02);
            let drow = (heights[(y + 1) * w + x] - heights[(y - 1) * w + x]) / (2.0 * 0.02);
            let sx = (slope(x - 1, y).0 + 2.0 * slope(x, y).0 + slope(x + 1, y).0) / 4.0;
            let sy = (slope(x, y - 1).1 + 2.0 * slope(x, y).1 + slope(x, y + 1).1) / 4.0;
            let from_height = glam::Vec3::new(-dx, drow, 1.0).normalize();
            let from_map = glam::Vec3::new(-sx, sy, 1.0).normalize();
            sum += from_height.dot(from_map).clamp(-1.0, 1.0).acos().to_degrees() as f64;
            n += 1;
        }
    }
    let mean = sum / n as f64;
    assert!(mean < 1.5, "normals of the height are {mean:.2} degrees from the capture's on average");
}

/// `skinkit height` writes the float EXR, the 16-bit PNG whose `(value - 0.5) * scale` is the
/// height, the cavity map and bands that sum to the height; every file says what it is.
#[test]
fn height_command_writes_the_deliverables_artists_load() {
    let tmp = tempfile::tempdir().unwrap();
    let d = |f: &str| tmp.path().join(f);
    let map = mold("cheek").join("truth.png");
    let o = skinkit(&[
        "height",
        s(&map),
        "--out",
        s(&d("h.exr")),
        "--png",
        s(&d("h.png")),
        "--cavity",
        s(&d("c.png")),
        "--bands",
        s(&d("b.exr")),
        "--mm-per-texel",
        "0.05",
        "--json",
        "--zip",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let scale = report["png"]["scale"].as_f64().unwrap();
    let (_, _, heights, attrs) = read_exr_channel(&d("h.exr"), "Y");
    assert_eq!(attribute(&attrs, "skinkit.integrator"), "neumann-dct");
    let (png, gamma, text) = read_png16(&d("h.png"));
    assert_eq!(gamma, Some(1.0), "a height PNG says it is linear");
    assert!(text.iter().any(|(k, v)| k == "skinkit.scale" && v.parse::<f64>().unwrap() == scale), "{text:?}");
    for (&v, &hh) in png.iter().zip(&heights) {
        let back = (v as f64 / 65535.0 - 0.5) * scale;
        assert!((back - hh as f64).abs() <= scale / 65535.0, "{back} against {hh}");
    }
    let bands: Vec<Vec<f32>> = ["R", "G", "B"].iter().map(|c| read_exr_channel(&d("b.exr"), c).2).collect();
    for i in 0..heights.len() {
        let sum = bands[0][i] + bands[1][i] + bands[2][i];
        assert!((sum - heights[i]).abs() < 1e-6, "bands sum {sum} against {}", heights[i]);
    }
    let (cavity, _, _) = read_png16(&d("c.png"));
    let mean = cavity.iter().map(|&v| v as f64 / 65535.0).sum::<f64>() / cavity.len() as f64;
    assert!((mean - 0.5).abs() < 0.05, "cavity mean {mean}");
}

/// A grown map's height tiles: the step across the wrap seam is no larger than the steps inside.
#[test]
fn synth_height_tiles() {
    let tmp = tempfile::tempdir().unwrap();
    let (out, height) = (tmp.path().join("g.png"), tmp.path().join("g.exr"));
    let exemplar = mold("cheek").join("truth.png");
    let args = ["synth", s(&exemplar), "--out", s(&out), "--size", "96x64", "--height", s(&height), "--quiet"];
    let o = skinkit(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let (w, h, v, attrs) = read_exr_channel(&height, "Y");
    assert_eq!(attribute(&attrs, "skinkit.unit"), "texel");
    let rms_step = |x0: usize, x1: usize| {
        ((0..h).map(|y| (v[y * w + x1] - v[y * w + x0]).powi(2) as f64).sum::<f64>() / h as f64).sqrt()
    };
    let mut interior: Vec<f64> = (0..w - 1).map(|x| rms_step(x, x + 1)).collect();
    interior.sort_by(f64::total_cmp);
    let seam = rms_step(w - 1, 0);
    assert!(seam <= interior[interior.len() - 1], "seam {seam} over every interior step {interior:?}");
}

/// Linear 16-bit PNGs (albedo) say so in a gAMA chunk; 8-bit pictures carry an sRGB chunk.
#[test]
fn pngs_say_their_colour_encoding() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cap");
    let rig = mold("nose").join("rig.toml");
    let o = skinkit(&["capture", "--rig", s(&rig), "--photos-from", s(&mold("nose")), "--out", s(&out), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, gamma, _) = read_png16(&out.join("albedo.png"));
    assert_eq!(gamma, Some(1.0), "albedo.png is linear and says so");
}

/// A normal map with no usable texel is refused, naming the file; a wrong extension is a usage
/// error before any work.
#[test]
fn height_refuses_maps_without_a_usable_normal() {
    let tmp = tempfile::tempdir().unwrap();
    let map = tmp.path().join("blank.png");
    skinkit_maps::io::write_png(&map, 4, 4, skinkit_maps::io::PngLayout::Rgb16, &[0; 48]).unwrap();
    let out = tmp.path().join("h.exr");
    let o = skinkit(&["height", s(&map), "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("blank.png") && stderr(&o).contains("usable normal"), "{}", stderr(&o));
    assert!(!out.exists());
    let o = skinkit(&["height", s(&map), "--out", s(&tmp.path().join("h.tif"))]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}
