//! The sample head: size, closedness and winding, UV layout, OBJ round trip.

use std::collections::HashMap;

use glam::Vec3;
use skinkit_render::frames::{FrameMethod, tangents};
use skinkit_render::head::{HEAD_COLUMNS, HEAD_ROWS, sample_head, write_obj};
use skinkit_render::mesh::Mesh;

fn key(p: Vec3) -> [u32; 3] {
    p.to_array().map(f32::to_bits)
}

#[test]
fn head_is_low_poly_and_valid() {
    let head = sample_head();
    head.validate().unwrap();
    let expected = 2 * HEAD_COLUMNS + (HEAD_ROWS - 1) * (HEAD_COLUMNS + 1);
    assert_eq!(head.positions.len(), expected);
    assert!(head.positions.len() < 15_000, "{}", head.positions.len());
    assert!(head.uvs.iter().all(|t| (0.0..=1.0).contains(&t.x) && (0.0..=1.0).contains(&t.y)));
    assert!(head.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
    // About 200 mm tall (1 unit = 1 mm), narrower than deep.
    let (min, max) = head.bounds();
    let size = max - min;
    assert!((200.0..=230.0).contains(&size.y), "{size}");
    assert!(size.x < size.z && size.x > 120.0, "{size}");
}

#[test]
fn head_is_closed_with_consistent_winding() {
    // Weld by exact position (seam and pole copies share positions bit for bit), then every
    // directed edge must appear once and its reverse once.
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
    // Euler characteristic of a sphere: V - E + F = 2.
    let (v, e, f) = (ids.len() as i64, edges.len() as i64 / 2, head.triangle_count() as i64);
    assert_eq!(v - e + f, 2);
}

#[test]
fn head_faces_point_outward() {
    let head = sample_head();
    let centroid = head.positions.iter().sum::<Vec3>() / head.positions.len() as f32;
    let mut outward = 0;
    for t in 0..head.triangle_count() {
        let p = head.triangle(t).map(|i| head.positions[i]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let mid = (p[0] + p[1] + p[2]) / 3.0;
        outward += usize::from(n.dot(mid - centroid) > 0.0);
    }
    let fraction = outward as f32 / head.triangle_count() as f32;
    assert!(fraction > 0.99, "{fraction}");
    // Vertex normals agree.
    let agree = head.positions.iter().zip(&head.normals).filter(|(p, n)| n.dot(**p - centroid) > 0.0).count();
    assert!(agree as f32 > 0.99 * head.positions.len() as f32);
}

#[test]
fn face_sits_where_the_sample_layout_expects_it() {
    let head = sample_head();
    // The nose tip is the most forward point: at u = 0.5, v near the layout's 0.47.
    let tip = (0..head.positions.len()).max_by(|&a, &b| head.positions[a].z.total_cmp(&head.positions[b].z)).unwrap();
    let uv = head.uvs[tip];
    assert!((uv.x - 0.5).abs() < 0.01 && (0.42..=0.52).contains(&uv.y), "nose tip at {uv}");
    // Facing +z with the subject's right (the camera's left, -x) on the left of the map.
    let at = |u: f32, v: f32| {
        let k = (0..head.uvs.len())
            .min_by(|&a, &b| {
                head.uvs[a].distance(glam::Vec2::new(u, v)).total_cmp(&head.uvs[b].distance(glam::Vec2::new(u, v)))
            })
            .unwrap();
        head.positions[k]
    };
    assert!(at(0.27, 0.6).x < -30.0 && at(0.73, 0.6).x > 30.0);
    assert!(at(0.5, 0.14).y > at(0.5, 0.47).y && at(0.5, 0.47).y > at(0.5, 0.85).y);
    assert!(at(0.5, 0.47).z > 80.0 && at(0.0, 0.5).z < -80.0);
    // Ears at u = 0.1 and 0.9: the sides.
    assert!(at(0.1, 0.45).x < -60.0 && at(0.9, 0.45).x > 60.0);
}

#[test]
fn head_frames_are_finite_and_unmirrored_on_the_face() {
    let head = sample_head();
    for method in [FrameMethod::Paper, FrameMethod::MikkTSpace] {
        let t = tangents(&head, method);
        assert!(t.iter().all(|t| t.is_finite() && (t.truncate().length() - 1.0).abs() < 1e-4));
        let face: Vec<_> = head
            .uvs
            .iter()
            .zip(&t)
            .filter(|(uv, _)| (0.2..0.8).contains(&uv.x) && (0.1..0.9).contains(&uv.y))
            .collect();
        assert!(face.iter().all(|(_, t)| t.w == 1.0), "{method:?}");
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
