//! A whole capture through `skinkit_capture::session` alone (no CLI): synthetic photos of a
//! rendered skin heightfield written as a session folder, read back by `Session::from_dir`,
//! captured, and compared with the heightfield's exact normals.

use glam::Vec3;
use skinkit_capture::Rig;
use skinkit_capture::session::{self, CaptureOptions, Session, Stage};
use skinkit_capture::solve::Method;
use skinkit_heightfield::{self as hf, SkinParams};
use skinkit_maps::io::{self, PngLayout};
use skinkit_maps::progress::Step;
use skinkit_maps::{NormalEncoding, Samples};

/// Renders a cheek mold of `size` pixels under the paper's turntable into `dir` (photos 01-08,
/// rig.toml, truth.png), lit and quantised as the sample molds are.
fn write_session(dir: &std::path::Path, size: usize, noise_sigma: f32) -> Rig {
    let rig = Rig::turntable(8, 45.0, 1.0).unwrap();
    let field = hf::generate(&SkinParams::cheek(size, size, 17)).unwrap();
    let lights: Vec<hf::RenderLight> = rig
        .lights()
        .iter()
        .map(|l| hf::RenderLight { direction: l.direction(), intensity: l.intensity(), position: l.position() })
        .collect();
    let config = hf::RenderConfig {
        albedo: hf::Albedo::Constant(Vec3::splat(0.8)),
        shadows: true,
        specular: None,
        ambient: Vec3::ZERO,
        noise_sigma,
        exposure: 1.0,
        channels: skinkit_maps::Channels::Gray,
        format: hf::Quantise::U16,
        seed: 5,
    };
    let photos = hf::render(&field, &lights, &config).unwrap();
    for (i, photo) in photos.iter().enumerate() {
        let Samples::U16(samples) = photo.samples() else { panic!("the renderer wrote 16-bit samples") };
        let path = dir.join(format!("{:02}.png", i + 1));
        io::write_png(&path, photo.width(), photo.height(), PngLayout::Gray16, samples).unwrap();
    }
    io::write_normal_map(&dir.join("truth.png"), &field.normals, NormalEncoding::default(), 16).unwrap();
    rig.save(&dir.join("rig.toml")).unwrap();
    rig
}

#[test]
fn a_session_folder_is_captured_by_the_library_alone() {
    let dir = tempfile::tempdir().unwrap();
    write_session(dir.path(), 96, 0.0);
    let files = Session::from_dir(dir.path()).unwrap();
    assert_eq!(files.photos.len(), 8, "truth.png is not a photo");
    assert_eq!(files.truth.as_deref(), Some(dir.path().join("truth.png").as_path()));
    let stages = std::sync::Mutex::new(Vec::new());
    for method in [Method::Robust, Method::LeastSquares] {
        let mut options = CaptureOptions::default();
        options.solve.method = method;
        stages.lock().unwrap().clear();
        let record = |step: Step<'_>| {
            if let Step::Start { name, .. } = step {
                stages.lock().unwrap().push(name.to_owned());
            }
        };
        let captured = session::capture(&files, &options, &record).unwrap();
        let stages = stages.lock().unwrap().clone();
        let names = [Stage::Decode, Stage::Solve, Stage::Detrend, Stage::Statistics, Stage::Height].map(Stage::name);
        assert_eq!(stages, names);
        let r = &captured.report;
        assert_eq!((r.width, r.height, r.light_count), (96, 96, 8));
        assert_eq!(r.solver, if method == Method::Robust { "robust" } else { "leastsquares" });
        assert_eq!(r.valid_pixels + r.invalid_pixels, 96 * 96);
        let e = r.error_vs_truth_degrees.expect("the session has a truth map");
        println!("{method:?}: error vs truth mean {:.3} deg, p95 {:.3}", e.mean, e.p95);
        // Noise-free 16-bit photos with cast shadows: robust drops the shadowed readings, least
        // squares is biased in the furrows.
        let bound = if method == Method::Robust { 0.5 } else { 3.0 };
        assert!(e.mean < bound, "{method:?}: mean error {} deg", e.mean);
        let truth =
            io::read_normal_map(files.truth.as_deref().unwrap(), NormalEncoding::default(), &Default::default());
        let again = session::compare_with_truth(&captured.solution.normals, truth.unwrap(), options.detrend_block);
        assert_eq!(again.unwrap(), e, "compare_with_truth is the report's comparison");
    }
}

#[test]
fn session_errors_name_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let e = Session::from_dir(dir.path()).map_err(|e| skinkit_maps::error::one_line(&e)).unwrap_err();
    assert!(e.contains("no rig.toml"), "{e}");
    write_session(dir.path(), 16, 0.002);
    std::fs::remove_file(dir.path().join("08.png")).unwrap();
    let files = Session::from_dir(dir.path()).unwrap();
    let e = session::capture(&files, &CaptureOptions::default(), &skinkit_maps::progress::NoProgress)
        .map_err(|e| skinkit_maps::error::one_line(&e))
        .unwrap_err();
    assert!(e.contains("8 lights") && e.contains("7 photos") && e.contains("rig.toml"), "{e}");
    std::fs::write(dir.path().join("08.png"), b"not a png").unwrap();
    let files = Session::from_dir(dir.path()).unwrap();
    let e = session::capture(&files, &CaptureOptions::default(), &skinkit_maps::progress::NoProgress)
        .map_err(|e| skinkit_maps::error::one_line(&e))
        .unwrap_err();
    // The photo's place in the rig, then its file, each once.
    assert!(e.starts_with("photo 8: ") && e.matches("08.png").count() == 1, "{e}");
}

/// Issue 15, D11: a rig's conditioning and its ambient frame are reported against the rig file.
#[test]
fn d11_rig_errors_name_the_rig_file() {
    let dir = tempfile::tempdir().unwrap();
    write_session(dir.path(), 16, 0.0);
    let rig_path = dir.path().join("rig.toml");
    let capture = |rig_text: &str| {
        std::fs::write(&rig_path, rig_text).unwrap();
        let files = Session::from_dir(dir.path()).unwrap();
        session::capture(&files, &CaptureOptions::default(), &skinkit_maps::progress::NoProgress)
            .map_err(|e| skinkit_maps::error::one_line(&e))
            .unwrap_err()
    };
    let rig_name = rig_path.display().to_string();
    // Eight lights within +-0.015 of the y = 0 plane: rank 3, but a condition number over 50.
    let nearly_coplanar: String = (0..8)
        .map(|i| {
            let x = (i as f32 - 3.5) / 4.0;
            let y = if i % 2 == 0 { 0.015 } else { -0.015 };
            format!("[[light]]\ndirection = [{x}, {y}, 1.0]\n")
        })
        .collect();
    let e = capture(&nearly_coplanar);
    assert!(e.starts_with(&format!("{rig_name}: ")) && e.contains("condition number"), "{e}");
    assert_eq!(e.matches(&rig_name).count(), 1, "{e}");
    // A rig whose ambient frame is missing: the rig file and its field, then the missing file.
    let good = Rig::turntable(8, 45.0, 1.0).unwrap().to_toml_string();
    let e = capture(&format!("ambient = \"nope.png\"\n{good}"));
    let want = format!("{rig_name}: field `ambient` (the ambient frame): ");
    assert!(e.starts_with(&want) && e.contains("nope.png") && !e.contains("photo"), "{e}");
    assert_eq!(e.matches("nope.png").count(), 1, "{e}");
}
