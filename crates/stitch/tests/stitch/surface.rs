//! A face map on the user's own mesh (issue 41): 3-D seed points land on their UVs, and each
//! region is grown at the scale its triangles' surface area against their UV area gives.

use std::path::Path;

use skinkit_heightfield::SkinParams;
use skinkit_stitch::curve::CurveParams;
use skinkit_stitch::layout::Layout;
use skinkit_stitch::surface::Surface;
use skinkit_stitch::{ComposeOptions, compose};
use skinkit_synth::SynthConfig;

/// A 2 x 1 plane (mesh units of 1 cm) in two quads split at x = 1: the left quad on u in
/// [0, 0.25], the right one on u in [0.25, 1], so the right has three times the texels per mm².
fn plane() -> Surface {
    let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0]];
    let uv = |x: f32, y: f32| [if x <= 1.0 { 0.25 * x } else { 0.25 + 0.75 * (x - 1.0) }, 1.0 - y];
    let uvs: Vec<[f32; 2]> = p.iter().map(|q: &[f32; 3]| uv(q[0], q[1])).collect();
    // The last triangle has zero UV area (and zero surface area): it must count for nothing.
    Surface::new("plane.obj", &p, &uvs, &[0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2, 3, 3, 3], 10.0).unwrap()
}

const LAYOUT: &str = r#"
size = [64, 32]
mesh = "plane.obj"
mm_per_unit = 10.0
[[region]]
name = "a"
exemplar = "a.png"
exemplar_mm_per_texel = 0.3
positions = [[0.5, 0.5, 1.0]]
[[region]]
name = "b"
exemplar = "b.png"
exemplar_mm_per_texel = 0.3
points = [[0.375, 0.5]]
"#;

#[test]
fn regions_on_a_mesh_are_grown_at_their_measured_scale() {
    let layout = Layout::parse(LAYOUT, Path::new("/virtual/layout.toml")).unwrap();
    assert_eq!(layout.mesh.as_deref(), Some(Path::new("/virtual/plane.obj")));
    // Not placed: the 3-D point has no UV yet.
    let ex = || vec![SkinParams::forehead(64, 64, 1).generate().unwrap().normals; 2];
    let options = ComposeOptions {
        curve: CurveParams::new(0.0, 1),
        synth: SynthConfig { levels: 2, ..SynthConfig::default() },
        ..ComposeOptions::default()
    };
    let e = compose(&layout, &ex(), &options, &skinkit_maps::progress::NoProgress).unwrap_err().to_string();
    assert!(e.contains("region `a`: positions") && e.contains("mesh"), "{e}");

    let placed = layout.on_surface(plane()).unwrap();
    // (0.5, 0.5) on the left quad: u = 0.125, v = 1 - 0.5.
    let [u, v] = placed.regions[0].points[0];
    assert!((u - 0.125).abs() < 1e-9 && (v - 0.5).abs() < 1e-9, "{u} {v}");
    // The whole mesh: 200 mm² on 64 x 32 texels.
    assert!((placed.mm_per_texel - (200.0f64 / 2048.0).sqrt()).abs() < 1e-9, "{}", placed.mm_per_texel);

    let c = compose(&placed, &ex(), &options, &skinkit_maps::progress::NoProgress).unwrap();
    // Straight boundary at u = 0.25: the left quad is region a's, the right quad region b's.
    let expected = [(100.0f64 / 512.0).sqrt(), (100.0f64 / 1536.0).sqrt()];
    for (r, want) in c.regions.iter().zip(expected) {
        let scale = r.mesh_scale.expect("measured on the mesh");
        assert!((r.mm_per_texel - want).abs() < 1e-9, "{}: {} against {want}", r.name, r.mm_per_texel);
        assert!((scale.area_mm2 - 100.0).abs() < 1e-6 && scale.triangles == 2, "{scale:?}");
        // The 64-texel exemplar at 0.3 mm is resampled to the region's own scale.
        let side = (64.0 * 0.3 / want).round() as usize;
        assert_eq!(r.exemplar_size, (side, side), "{}", r.name);
    }
    assert!(c.normals.grid().as_slice().iter().all(|n| n.is_finite() && (n.length() - 1.0).abs() < 1e-4));
}

#[test]
fn a_point_off_the_map_and_a_missing_scale_are_named() {
    let unplaced =
        LAYOUT.replace("mesh = \"plane.obj\"\n", "").replace("positions = [[0.5, 0.5, 1.0]]", "points = [[0.1, 0.5]]");
    let unplaced = Layout::parse(&unplaced, Path::new("/v/l.toml")).unwrap();
    let e = unplaced.check_placed().unwrap_err();
    assert!(e.to_string().contains("mm_per_texel: missing"), "{e}");
    let layout = Layout::parse(LAYOUT, Path::new("/v/l.toml")).unwrap();
    let mut off = plane();
    off.uvs.iter_mut().for_each(|uv| uv[0] += 20.0);
    let e = layout.on_surface(off).unwrap_err().to_string();
    assert!(e.contains("plane.obj") && e.contains("1001 to 1999"), "{e}");
}

/// A 4 x 1 strip over UDIM tiles 1001 to 1004: quad k on u in [k, k + 1].
fn strip() -> Surface {
    let mut p = Vec::new();
    let mut uvs = Vec::new();
    let mut indices = Vec::new();
    for k in 0..4u32 {
        let x = k as f32;
        let base = p.len() as u32;
        for (dx, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            p.push([x + dx, y, 0.0]);
            uvs.push([x + dx, 1.0 - y]);
        }
        indices.extend([0, 1, 2, 0, 2, 3].map(|i| base + i));
    }
    Surface::new("strip.obj", &p, &uvs, &indices, 5.0).unwrap()
}

#[test]
fn udim_tiles_are_one_continuous_map() {
    let text = LAYOUT.replace("size = [64, 32]", "size = [32, 32]").replace("[[0.5, 0.5, 1.0]]", "[[0.5, 0.5, 0.0]]");
    let text = text.replace("points = [[0.375, 0.5]]", "positions = [[3.5, 0.5, 0.0]]");
    let placed = Layout::parse(&text, Path::new("/v/l.toml")).unwrap().on_surface(strip()).unwrap();
    let atlas = placed.atlas.clone().unwrap();
    assert_eq!(atlas.tiles, vec![1001, 1002, 1003, 1004]);
    assert_eq!((placed.width, placed.height), (128, 32));
    // Each tile: 5 x 5 mm on 32 x 32 texels.
    assert!((placed.mm_per_texel - 5.0 / 32.0).abs() < 1e-9, "{}", placed.mm_per_texel);
    let ex = vec![SkinParams::forehead(64, 64, 1).generate().unwrap().normals; 2];
    let options =
        ComposeOptions { synth: SynthConfig { levels: 2, ..SynthConfig::default() }, ..ComposeOptions::default() };
    let c = compose(&placed, &ex, &options, &skinkit_maps::progress::NoProgress).unwrap();
    let tiles = atlas.split(c.normals.grid()).unwrap();
    assert_eq!(tiles.iter().map(|t| t.0).collect::<Vec<_>>(), atlas.tiles);
    // Across a tile boundary neighbouring texels differ as much as neighbours within a tile.
    let angle = |a: glam::Vec3, b: glam::Vec3| a.angle_between(b) as f64;
    let column_step = |a: &skinkit_maps::Grid<glam::Vec3>, xa: usize, b: &skinkit_maps::Grid<glam::Vec3>, xb: usize| {
        (0..32).map(|y| angle(*a.get(xa, y), *b.get(xb, y))).sum::<f64>() / 32.0
    };
    let inside: f64 = tiles
        .iter()
        .flat_map(|(_, t)| (0..31).map(move |x| (t, x)))
        .map(|(t, x)| column_step(t, x, t, x + 1))
        .sum::<f64>()
        / (4.0 * 31.0);
    for k in 0..3 {
        let across = column_step(&tiles[k].1, 31, &tiles[k + 1].1, 0);
        assert!(
            across < 1.5 * inside,
            "tiles {} | {}: {across} rad across against {inside} inside",
            tiles[k].0,
            tiles[k + 1].0
        );
    }
}
