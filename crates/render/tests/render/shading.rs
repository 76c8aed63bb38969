//! The CPU reference of the base shading against independent computations: normal decoding,
//! frames, the fragment step against a rotation built another way, texture sampling, mip chains,
//! tone mapping, and the rasteriser's coverage.

use crate::common::plain_inputs;
use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
use skinkit_render::brdf::Lafortune;
use skinkit_render::shading::{
    Camera, GreenAxis, Light, LightKind, MAX_LIGHTS, RenderInputs, ShadingParams, SpecularMode, Texture, ToneCurve,
    Varyings, Vertex, decode_normal, render_cpu, shade_fragment, shade_vertex, srgb_encode, tangent_frame, tone_map,
};
use std::f32::consts::PI;

fn sun(toward: Vec3, intensity: f32) -> Light {
    Light { kind: LightKind::Directional { toward }, color: Vec3::new(1.0, 0.9, 0.8), intensity }
}

fn params<'a>(
    brdf: &'a Lafortune,
    lights: &'a [Light],
    normal_map: &'a Texture,
    albedo: &'a Texture,
) -> ShadingParams<'a> {
    ShadingParams {
        eye: Vec3::new(0.0, 0.0, 5.0),
        lights,
        brdf,
        normal_map,
        green: GreenAxis::Up,
        albedo,
        specular: SpecularMode::Pixel,
    }
}

fn varyings(view_ts: Vec3, light_ts: Vec3) -> Varyings {
    let mut lights_ts = [Vec3::ZERO; MAX_LIGHTS];
    lights_ts[0] = light_ts;
    Varyings { uv: Vec2::new(0.3, 0.7), view_ts, lights_ts, ..Default::default() }
}

#[test]
fn decoding_flips_green_and_renormalises() {
    let texel = Vec4::new(0.3, 0.4, 0.5, 0.0);
    let up = decode_normal(texel, GreenAxis::Up);
    let down = decode_normal(texel, GreenAxis::Down);
    assert!((up - Vec3::new(0.3, 0.4, 0.5).normalize()).length() < 1e-6);
    assert!((down - Vec3::new(0.3, -0.4, 0.5).normalize()).length() < 1e-6);
    assert_eq!(decode_normal(Vec4::ZERO, GreenAxis::Up), Vec3::Z, "invalid texel");
    assert_eq!(decode_normal(Vec4::splat(f32::NAN), GreenAxis::Up), Vec3::Z);
}

#[test]
fn tangent_frames_are_orthonormal_with_handedness() {
    let n = Vec3::new(0.2, 0.3, 0.9).normalize();
    let (t, b, nn) = tangent_frame(n, Vec4::new(1.0, 0.1, 0.0, 1.0));
    let m = Mat3::from_cols(t, b, nn);
    assert!((m.transpose() * m - Mat3::IDENTITY).abs_diff_eq(Mat3::ZERO, 1e-5));
    assert!(m.determinant() > 0.0);
    let (_, b_mirrored, _) = tangent_frame(n, Vec4::new(1.0, 0.1, 0.0, -1.0));
    assert!((b + b_mirrored).length() < 1e-6, "w = -1 flips the bitangent");
    // Degenerate tangents (zero, parallel to the normal, NaN) still give finite frames.
    for tangent in [Vec4::ZERO, n.extend(1.0), Vec4::splat(f32::NAN)] {
        let (t, b, _) = tangent_frame(n, tangent);
        assert!(t.is_finite() && b.is_finite() && (t.dot(n)).abs() < 1e-5, "{tangent}");
    }
}

#[test]
fn flat_map_fragment_is_brdf_times_cosine() {
    let brdf = Lafortune::skin();
    let lights = [sun(Vec3::new(0.3, -0.2, 0.9), 2.0)];
    let (map, albedo) = (Texture::flat_normals(), Texture::solid([1.0; 4]));
    let p = params(&brdf, &lights, &map, &albedo);
    let l = Vec3::new(0.3, -0.2, 0.9).normalize();
    let v = Vec3::new(-0.5, 0.1, 0.8).normalize();
    let got = shade_fragment(&p, &varyings(v, l));
    let expected = lights[0].color * 2.0 * brdf.eval(l, v) * l.z;
    assert!((got - expected).abs().max_element() < 1e-5, "{got} vs {expected}");
}

#[test]
fn bumped_fragment_matches_an_independent_rotation() {
    // With an isotropic BRDF (the skin set: Cx = Cy) the result depends only on the rotation
    // taking z to the map normal, whichever tangent is chosen: build it as a quaternion.
    let brdf = Lafortune::skin();
    let lights = [sun(Vec3::Z, 1.5)];
    let n = Vec3::new(0.35, -0.25, 0.9).normalize();
    let map = Texture::solid([n.x, n.y, n.z, 0.0]);
    let albedo = Texture::solid([0.8, 0.7, 0.6, 1.0]);
    let p = params(&brdf, &lights, &map, &albedo);
    let to_local = Quat::from_rotation_arc(Vec3::Z, n).inverse();
    for (l, v) in [
        (Vec3::new(0.2, 0.1, 1.0), Vec3::new(-0.4, 0.3, 0.8)),
        (Vec3::new(0.9, 0.0, 0.2), Vec3::new(0.1, -0.2, 1.0)),
        (Vec3::new(-0.5, 0.5, 0.5), Vec3::new(0.5, 0.5, 0.5)),
    ] {
        let (l, v) = (l.normalize(), v.normalize());
        // Interpolated vectors arrive unnormalised: halve them.
        let got = shade_fragment(&p, &varyings(v * 0.5, l * 0.5));
        let (ll, vl) = (to_local * l, to_local * v);
        let mut f = brdf.eval(ll, vl);
        f += brdf.diffuse * (Vec3::new(0.8, 0.7, 0.6) - Vec3::ONE) / PI;
        let expected = lights[0].color * 1.5 * f * ll.z.max(0.0);
        assert!((got - expected).abs().max_element() < 1e-4, "{l} {v}: {got} vs {expected}");
    }
}

#[test]
fn light_behind_the_map_normal_gives_no_light() {
    let brdf = Lafortune::skin();
    let lights = [sun(Vec3::Z, 1.0)];
    let (map, albedo) = (Texture::flat_normals(), Texture::solid([1.0; 4]));
    let p = params(&brdf, &lights, &map, &albedo);
    let got = shade_fragment(&p, &varyings(Vec3::Z, Vec3::new(0.3, 0.0, -0.7)));
    assert_eq!(got, Vec3::ZERO);
}

#[test]
fn vertex_step_takes_light_and_view_into_texture_space() {
    let brdf = Lafortune::skin();
    let lights = [sun(Vec3::new(1.0, 0.0, 0.0), 1.0)];
    let (map, albedo) = (Texture::flat_normals(), Texture::solid([1.0; 4]));
    let mut p = params(&brdf, &lights, &map, &albedo);
    // A vertex facing +x with u along -z: the light along +x is the texture-space normal.
    let vertex =
        Vertex { position: [1.0, 0.0, 0.0], normal: [1.0, 0.0, 0.0], tangent: [0.0, 0.0, -1.0, 1.0], uv: [0.5, 0.5] };
    let out = shade_vertex(&p, Mat4::IDENTITY, &vertex);
    assert!((out.varyings.lights_ts[0] - Vec3::Z).length() < 1e-6);
    // Eye at (0, 0, 5): direction (-1, 0, 5)/|.|; tangent -z, bitangent cross(x, -z) = +y.
    let e = Vec3::new(-1.0, 0.0, 5.0).normalize();
    let expected = Vec3::new(-e.z, e.y, e.x);
    assert!((out.varyings.view_ts - expected).length() < 1e-6, "{}", out.varyings.view_ts);
    assert_eq!(out.varyings.vertex_specular, Vec3::ZERO);
    p.specular = SpecularMode::Vertex;
    let out = shade_vertex(&p, Mat4::IDENTITY, &vertex);
    let lobes = brdf.eval_specular(Vec3::Z, expected);
    assert!((out.varyings.vertex_specular - lights[0].color * lobes).abs().max_element() < 1e-5);
}

#[test]
fn bilinear_sampling_follows_gpu_texel_centres_and_repeats() {
    let t = Texture::from_fn(4, 2, |x, y| [x as f32, y as f32, 0.0, 1.0]);
    let at = |u: f32, v: f32| t.sample(Vec2::new(u, v));
    assert_eq!(at(0.125, 0.25), Vec4::new(0.0, 0.0, 0.0, 1.0), "texel (0, 0) centre");
    assert_eq!(at(0.375, 0.75), Vec4::new(1.0, 1.0, 0.0, 1.0), "texel (1, 1) centre");
    assert!((at(0.25, 0.25).x - 0.5).abs() < 1e-6, "between texels 0 and 1");
    // u = 0 lies halfway between texel 3 (wrapped) and texel 0.
    assert!((at(0.0, 0.25).x - 1.5).abs() < 1e-6);
    assert!((at(1.375, -0.75) - at(0.375, 0.25)).abs().max_element() < 1e-5, "repeat");
    assert!(at(f32::NAN, 0.5).is_finite());
}

#[test]
fn mip_chain_averages_unnormalised_normals() {
    let bumpy = Texture::from_fn(8, 8, |x, y| {
        let s = if (x + y) % 2 == 0 { 0.6 } else { -0.6 };
        [s, 0.0, 0.8, 0.0]
    });
    let chain = bumpy.mip_chain();
    assert_eq!(chain.len(), 4);
    assert_eq!((chain[3].width, chain[3].height), (1, 1));
    // The 2x2 checker of tilted normals averages to a short vector along z: renormalised it is
    // the mean surface, so distant skin shades smoothly instead of sparkling.
    for level in &chain[1..] {
        for t in &level.texels {
            assert!((Vec4::from(*t) - Vec4::new(0.0, 0.0, 0.8, 0.0)).length() < 1e-6, "{t:?}");
        }
    }
    // Odd sizes reuse the edge texels and reach 1x1.
    let odd = Texture::from_fn(5, 3, |x, _| [x as f32, 0.0, 0.0, 0.0]).mip_chain();
    let sizes: Vec<_> = odd.iter().map(|t| (t.width, t.height)).collect();
    assert_eq!(sizes, vec![(5, 3), (2, 1), (1, 1)]);
    assert_eq!(odd[1].texels[1][0], 2.5, "columns 2 and 3");
}

#[test]
fn tone_curves_and_srgb() {
    let c = Vec3::new(0.5, 1.0, 3.0);
    assert_eq!(tone_map(c, 2.0, ToneCurve::None), Vec3::new(1.0, 2.0, 6.0));
    assert_eq!(tone_map(c, 2.0, ToneCurve::Clamp), Vec3::new(1.0, 1.0, 1.0));
    let r = tone_map(c, 1.0, ToneCurve::Reinhard);
    assert!((r - Vec3::new(1.0 / 3.0, 0.5, 0.75)).length() < 1e-6);
    assert_eq!(tone_map(Vec3::splat(-1.0), 1.0, ToneCurve::None), Vec3::ZERO);
    // sRGB: published values of the transfer function.
    assert!((srgb_encode(0.5) - 0.735357).abs() < 1e-5);
    assert!((srgb_encode(0.002) - 0.02584).abs() < 1e-5);
    assert!((srgb_encode(2.0) - 1.0).abs() < 1e-6);
    assert_eq!(srgb_encode(f32::NAN), 0.0);
}

fn head_on_plane(width: u32, height: u32) -> RenderInputs {
    let corner = |x: f32, y: f32| Vertex {
        position: [x, y, 0.0],
        normal: [0.0, 0.0, 1.0],
        tangent: [1.0, 0.0, 0.0, 1.0],
        uv: [(x + 1.0) / 2.0, (1.0 - y) / 2.0],
    };
    plain_inputs(
        (vec![corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)], vec![0, 1, 2, 0, 2, 3]),
        Camera::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 45.0, width as f32 / height as f32),
        vec![sun(Vec3::Z, 2.0)],
        Lafortune::lambert(Vec3::splat(0.6)),
    )
}

#[test]
fn rasteriser_covers_the_projected_square() {
    let (w, h) = (64, 48);
    let scene = head_on_plane(w, h);
    let image = render_cpu(&scene, w, h);
    // Independent projection of the square's half-size: 1 / (4 tan(22.5 deg)) of half the height.
    let half_px = (h as f32 / 2.0) / (4.0 * (22.5f32).to_radians().tan());
    let expected = scene.lights[0].color * 2.0 * 0.6 / PI;
    for y in 0..h {
        for x in 0..w {
            let p = image[(y * w + x) as usize];
            let (dx, dy) = (x as f32 + 0.5 - w as f32 / 2.0, y as f32 + 0.5 - h as f32 / 2.0);
            let inside = dx.abs() < half_px - 0.01 && dy.abs() < half_px - 0.01;
            let outside = dx.abs() > half_px + 0.01 || dy.abs() > half_px + 0.01;
            if inside {
                assert!((Vec3::new(p[0], p[1], p[2]) - expected).abs().max_element() < 1e-5, "({x}, {y}) {p:?}");
            } else if outside {
                assert_eq!(p, [0.0; 4], "({x}, {y})");
            }
        }
    }
}

#[test]
fn rasteriser_row_zero_is_the_top() {
    // Light only the top half of the image: a texture whose top rows are bright.
    let (w, h) = (32, 32);
    let mut scene = head_on_plane(w, h);
    scene.albedo = Texture::from_fn(1, 2, |_, y| if y == 0 { [1.0; 4] } else { [0.0, 0.0, 0.0, 1.0] });
    let image = render_cpu(&scene, w, h);
    let at = |x: u32, y: u32| image[(y * w + x) as usize][0];
    assert!(at(16, 10) > 0.3, "top of the plane (v = 0.25) reads albedo row 0");
    assert!(at(16, 21) < 0.05, "bottom reads row 1");
}

#[test]
fn depth_test_keeps_the_nearest_triangle() {
    let (w, h) = (16, 16);
    let mut scene = head_on_plane(w, h);
    // A second, larger square behind the first, lit the same but with a different albedo row.
    let back: Vec<Vertex> = scene
        .vertices
        .iter()
        .map(|v| Vertex { position: [v.position[0] * 3.0, v.position[1] * 3.0, -1.0], uv: [0.5, 0.75], ..*v })
        .collect();
    scene.albedo = Texture::from_fn(1, 2, |_, y| if y == 0 { [1.0; 4] } else { [0.25, 0.25, 0.25, 1.0] });
    let mut indices: Vec<u32> = vec![4, 5, 6, 4, 6, 7];
    indices.extend(&scene.indices);
    scene.vertices.extend(back);
    scene.indices = indices;
    let image = render_cpu(&scene, w, h);
    let centre = image[(8 * w + 8) as usize][0];
    let corner = image[0][0];
    assert!(centre > 2.0 * corner && corner > 0.0, "centre {centre}, corner {corner}");
}

#[test]
fn normal_maps_upload_their_vectors_and_keep_invalid_zero() {
    let mut map = skinkit_maps::NormalMap::flat(3, 2);
    map.set(1, 0, Vec3::ZERO);
    map.set(2, 1, Vec3::new(0.6, 0.0, 0.8));
    let t = Texture::from_normal_map(&map);
    assert_eq!((t.width, t.height), (3, 2));
    assert_eq!(t.texels[0], [0.0, 0.0, 1.0, 0.0]);
    assert_eq!(t.texels[1], [0.0; 4], "invalid normal stays zero");
    assert_eq!(t.texels[5], [0.6, 0.0, 0.8, 0.0]);
    // f16 storage keeps unit normals within 1e-3.
    let q = t.quantized_f16();
    assert!(q.texels.iter().zip(&t.texels).all(|(a, b)| (0..4).all(|i| (a[i] - b[i]).abs() < 1e-3)));
}
