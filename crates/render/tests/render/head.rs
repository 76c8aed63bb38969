//! The sample head (`samples/head/head.obj`, issue 41): size and units, closedness and winding,
//! its UV layout for a face map (no flipped or zero-area face triangle, texel density in a stated
//! range), the sample layout's points on it, tangent frames, OBJ round trip.

use std::collections::HashMap;
use std::path::Path;

use glam::{Vec2, Vec3};
use skinkit_render::frames::{FrameMethod, tangents};
use skinkit_render::head::{SAMPLE_HEAD_OBJ, sample_head, write_obj};
use skinkit_render::mesh::Mesh;

/// The demo's face map (`skinkit demo` stitches the sample layout at 2048 x 1024).
const MAP: Vec2 = Vec2::new(2048.0, 1024.0);

fn key(p: Vec3) -> [u32; 3] {
    p.to_array().map(f32::to_bits)
}

/// One OBJ group of the sample head (`skin`, `pockets` or `eyes`) as a mesh of its own.
fn group(name: &str) -> Mesh {
    let mut current = "";
    let mut text = String::new();
    for line in SAMPLE_HEAD_OBJ.lines() {
        if let Some(g) = line.strip_prefix("g ") {
            current = g.trim();
        } else if !line.starts_with("f ") || current == name {
            text.push_str(line);
            text.push('\n');
        }
    }
    Mesh::parse_obj(&mut text.as_bytes(), name).unwrap().mesh
}

/// The front of the face: from above the brows to under the chin, between the cheekbones, in
/// front of the ears (mm, the head's frame: origin between the eyes, +z out of the face).
fn on_face(p: Vec3) -> bool {
    p.z > -5.0 && (-110.0..70.0).contains(&p.y) && p.x.abs() < 65.0
}

/// A triangle's centre, twice its signed UV area in texels of [`MAP`] (negative when it is
/// counter-clockwise on the surface, since v runs down the image) and the millimetres of
/// surface per texel (the square root of its area ratio).
fn uv_triangle(mesh: &Mesh, t: usize) -> (Vec3, f32, f32) {
    let [a, b, c] = mesh.triangle(t);
    let p = [a, b, c].map(|k| mesh.positions[k]);
    let uv = [a, b, c].map(|k| mesh.uvs[k] * MAP);
    let signed = (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]);
    let area = (p[1] - p[0]).cross(p[2] - p[0]).length();
    ((p[0] + p[1] + p[2]) / 3.0, signed, (area / signed.abs()).sqrt())
}

fn percentile(sorted: &[f32], q: f32) -> f32 {
    sorted[((sorted.len() - 1) as f32 * q).round() as usize]
}

#[test]
fn head_is_valid_and_in_millimetres() {
    let head = sample_head();
    head.validate().unwrap();
    assert!((15_000..25_000).contains(&head.positions.len()), "{} vertices", head.positions.len());
    assert!(head.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-3));
    assert!(SAMPLE_HEAD_OBJ.lines().next().unwrap().contains("MakeHuman base mesh hm08 (CC0 1.0)"));
    // Crown to the neck's cut, 1 unit = 1 mm: a head (about 230 mm crown to chin) and some neck.
    let (min, max) = group("skin").bounds();
    let size = max - min;
    assert!((200.0..=280.0).contains(&size.y), "height {size}");
    assert!((150.0..=200.0).contains(&size.x) && (180.0..=230.0).contains(&size.z), "{size}");
}

#[test]
fn head_is_closed_with_consistent_winding() {
    // Weld by exact position (seam copies share a `v` line), then every directed edge must appear
    // once and its reverse once: no boundary edge, the neck is closed.
    let head = sample_head();
    let mut ids = HashMap::new();
    let weld: Vec<usize> = head
        .positions
        .iter()
        .map(|&p| {
            let next = ids.len();
            *ids.entry(key(p)).or_insert(next)
        })
        .collect();
    let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
    for t in 0..head.triangle_count() {
        let [a, b, c] = head.triangle(t).map(|i| weld[i]);
        assert!(a != b && b != c && a != c, "triangle {t} is degenerate");
        for e in [(a, b), (b, c), (c, a)] {
            *edges.entry(e).or_default() += 1;
        }
    }
    for (&(a, b), &count) in &edges {
        assert_eq!(count, 1, "edge {a}-{b} used {count} times in one direction");
        assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no opposite: the surface is open");
    }
    // Three spheres (V - E + F = 2 each): the skin with its pockets, and two eyeballs.
    let (v, e, f) = (ids.len() as i64, edges.len() as i64 / 2, head.triangle_count() as i64);
    assert_eq!(v - e + f, 6);
}

#[test]
fn skin_faces_point_outward() {
    let skin = group("skin");
    let centroid = skin.positions.iter().sum::<Vec3>() / skin.positions.len() as f32;
    let outward = (0..skin.triangle_count())
        .filter(|&t| {
            let p = skin.triangle(t).map(|i| skin.positions[i]);
            (p[1] - p[0]).cross(p[2] - p[0]).dot((p[0] + p[1] + p[2]) / 3.0 - centroid) > 0.0
        })
        .count();
    // The ears' backs, the nostrils' rims and the eyelids' folds face inward here and there.
    let fraction = outward as f32 / skin.triangle_count() as f32;
    assert!(fraction > 0.95, "{fraction}");
}

/// The face's UV layout: one island with no flipped or zero-area triangle, the pockets (relaxed
/// into discs inside the lips, lids and nostrils) off the map one width to the right, so they
/// take no texel from the skin; and a texel of the demo's 2048 x 1024 map covering 0.2 mm of skin
/// in the middle of the face (median 0.22 when measured), 98 % of the face's triangles between
/// 0.08 and 0.75 mm (the nose's underside, the eyelids' creases and the jaw's sides meet the
/// projection's rays obliquely: 0.087 and 0.69 measured at the 1st and 99th percentiles).
#[test]
fn face_uv_layout_is_one_unfolded_island_of_bounded_density() {
    for (name, island) in [("skin", 0.2..0.8), ("pockets", 1.2..1.8)] {
        let mesh = group(name);
        for t in 0..mesh.triangle_count() {
            let (centre, signed, _) = uv_triangle(&mesh, t);
            if on_face(centre) {
                assert!(signed < -1e-4, "{name} triangle {t} at {centre} is flipped or has no UV area ({signed})");
                let uv = mesh.uvs[mesh.triangle(t)[0]];
                assert!(island.contains(&uv.x) && (0.05..0.95).contains(&uv.y), "{name} {t} at {uv}: off the island");
            }
        }
    }
    let eyes = group("eyes");
    assert!(eyes.uvs.iter().all(|t| t.x > 1.0), "the eyeballs' UVs are on the map");
    let skin = group("skin");
    let mut mm: Vec<f32> =
        (0..skin.triangle_count()).map(|t| uv_triangle(&skin, t)).filter(|t| on_face(t.0)).map(|t| t.2).collect();
    mm.sort_by(f32::total_cmp);
    let (p1, median, p99) = (percentile(&mm, 0.01), percentile(&mm, 0.5), percentile(&mm, 0.99));
    assert!(mm.len() > 10_000, "{} face triangles", mm.len());
    assert!((0.18..=0.26).contains(&median), "median {median} mm a texel");
    assert!(p1 >= 0.08 && p99 <= 0.75, "1st and 99th percentiles {p1} and {p99} mm a texel");
}

/// The surface point at `uv` on `mesh`, by barycentric lookup in its UV triangles.
fn at_uv(mesh: &Mesh, uv: Vec2) -> Option<Vec3> {
    (0..mesh.triangle_count()).find_map(|t| {
        let [a, b, c] = mesh.triangle(t);
        let (ta, tb, tc) = (mesh.uvs[a], mesh.uvs[b], mesh.uvs[c]);
        let d = (tb - ta).perp_dot(tc - ta);
        let (s, r) = ((uv - ta).perp_dot(tc - ta) / d, (tb - ta).perp_dot(uv - ta) / d);
        (s >= 0.0 && r >= 0.0 && s + r <= 1.0 && d.abs() > 0.0).then(|| {
            mesh.positions[a]
                + s * (mesh.positions[b] - mesh.positions[a])
                + r * (mesh.positions[c] - mesh.positions[a])
        })
    })
}

/// `samples/face/layout.toml`'s points land on the features they name.
#[test]
fn layout_points_land_on_their_features() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/face/layout.toml");
    let layout: toml::Table = std::fs::read_to_string(path).unwrap().parse().unwrap();
    let skin = group("skin");
    let mut found = HashMap::new();
    for region in layout["region"].as_array().unwrap() {
        let name = region["name"].as_str().unwrap().to_owned();
        let point = region["points"][0].as_array().unwrap();
        let uv = Vec2::new(point[0].as_float().unwrap() as f32, point[1].as_float().unwrap() as f32);
        found.insert(name.clone(), at_uv(&skin, uv).unwrap_or_else(|| panic!("{name} at {uv} is on no skin")));
    }
    let p = |n: &str| found[n];
    // Forehead above the brows (y = 0 is the eyes' level), in the middle.
    assert!(p("forehead").y > 35.0 && p("forehead").x.abs() < 5.0, "{}", p("forehead"));
    // Temples: beside the forehead, above the eyes, toward the sides; the subject's right is -x.
    assert!(p("temple-right").x < -40.0 && p("temple-left").x > 40.0);
    assert!(p("temple-right").y > 10.0 && p("temple-left").y > 10.0);
    // The nose: the middle, forward of the cheeks, below the eyes.
    assert!(p("nose").x.abs() < 5.0 && p("nose").z > p("cheek-right").z + 15.0 && p("nose").y < -15.0);
    // Cheeks below the eyes, either side of the nose; the chin at the bottom.
    assert!(p("cheek-right").x < -25.0 && p("cheek-left").x > 25.0 && p("cheek-right").y < -25.0);
    assert!(p("chin").y < -85.0 && p("chin").x.abs() < 5.0, "{}", p("chin"));
}

#[test]
fn skin_frames_are_finite_and_unmirrored_on_the_face() {
    let skin = group("skin");
    for method in [FrameMethod::Paper, FrameMethod::MikkTSpace] {
        let t = tangents(&skin, method);
        assert!(t.iter().all(|t| t.is_finite() && (t.truncate().length() - 1.0).abs() < 1e-3), "{method:?}");
        let mirrored = skin.positions.iter().zip(&t).filter(|(p, t)| on_face(**p) && t.w != 1.0).count();
        assert_eq!(mirrored, 0, "{method:?}");
    }
}

fn corners(mesh: &Mesh) -> Vec<[f32; 8]> {
    mesh.indices
        .iter()
        .map(|&i| {
            let (p, n, t) = (mesh.positions[i as usize], mesh.normals[i as usize], mesh.uvs[i as usize]);
            [p.x, p.y, p.z, n.x, n.y, n.z, t.x, t.y]
        })
        .collect()
}

#[test]
fn obj_round_trip_through_the_loader() {
    let head = sample_head();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("head.obj");
    write_obj(&head, &path).unwrap();
    let loaded = Mesh::load(&path).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    // The loader may renumber vertices; compare triangle corners. Positions and normals are
    // written in round-trip notation; v goes through 1 - (1 - v).
    let (a, b) = (corners(&head), corners(&loaded.mesh));
    assert_eq!(a.len(), b.len());
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        let err = x.iter().zip(y).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max);
        assert!(err < 1e-6, "corner {k}: {x:?} vs {y:?}");
    }
    assert_eq!(loaded.mesh.positions.len(), head.positions.len());
}
