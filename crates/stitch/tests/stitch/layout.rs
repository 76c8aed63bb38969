//! Face layouts: parsing, path resolution, every refusal naming the file and field, and the
//! sample layout.

use std::path::{Path, PathBuf};

use skinkit_stitch::Error;
use skinkit_stitch::layout::{self, ExemplarSource, Layout};
use skinkit_stitch::partition::{Partition, SeedPoint};

const ORIGIN: &str = "faces/test.toml";

fn parse(text: &str) -> Result<Layout, Error> {
    Layout::parse(text, Path::new(ORIGIN))
}

/// The error message of a layout that must fail; it always names the file.
fn error(text: &str) -> String {
    let msg = parse(text).unwrap_err().to_string();
    assert!(msg.starts_with(ORIGIN), "message does not name the file: {msg}");
    msg
}

const REGION: &str = r#"
[[region]]
name = "cheek"
exemplar = "cheek.png"
exemplar_mm_per_texel = 0.02
points = [[0.3, 0.6]]
"#;

#[test]
fn parses_a_layout_with_defaults_resolved_paths_and_both_point_kinds() {
    let text = r#"
mm_per_texel = 0.05
coverage = "charts.png"

[[region]]
name = "forehead"
session = "../molds/forehead"
exemplar_mm_per_texel = 0.02
points = [[0.5, 0.0], [1.0, 1.0]]
seed = 11

[[region]]
name = "nose"
exemplar = "/abs/nose.png"
exemplar_mm_per_texel = 0.025
pixels = [[2048, 1000], [0, 2047]]
"#;
    let l = parse(text).unwrap();
    assert_eq!((l.width, l.height), (4096, 2048));
    assert_eq!(l.mm_per_texel, 0.05);
    assert_eq!(l.coverage, Some(PathBuf::from("faces/charts.png")));
    assert_eq!(l.regions.len(), 2);
    let (f, n) = (&l.regions[0], &l.regions[1]);
    assert_eq!(f.exemplar, ExemplarSource::Session(PathBuf::from("faces/../molds/forehead")));
    assert_eq!(n.exemplar, ExemplarSource::NormalMap(PathBuf::from("/abs/nose.png")));
    assert_eq!((f.seed, n.seed), (Some(11), None));
    assert_eq!(n.exemplar_mm_per_texel, 0.025);
    // UV (0.5, 0) is the top row; (1, 1) clamps to the last texel; pixels stay where they are.
    let seeds = l.seed_points();
    let expected = [(0, 2048, 0), (0, 4095, 2047), (1, 2048, 1000), (1, 0, 2047)];
    assert_eq!(seeds, expected.map(|(region, x, y)| SeedPoint { region, x, y }).to_vec());
}

#[test]
fn uv_and_texel_conversions_invert() {
    for (w, h) in [(4096, 2048), (7, 3), (1, 1)] {
        for y in 0..h.min(50) as u32 {
            for x in 0..w.min(50) as u32 {
                assert_eq!(layout::uv_to_texel(layout::texel_to_uv(x, y, w, h), w, h), [x, y]);
            }
        }
    }
    assert_eq!(layout::uv_to_texel([0.999_999, 0.5], 10, 4), [9, 2]);
}

#[test]
fn with_size_keeps_the_face_and_rescales_the_map() {
    let l = parse(&format!("size = [1000, 500]\nmm_per_texel = 0.1\n{REGION}\n[[region]]\nname = \"nose\"\nexemplar = \"n.png\"\nexemplar_mm_per_texel = 0.02\npixels = [[500, 250]]\n")).unwrap();
    let half = l.with_size(500, 250).unwrap();
    assert_eq!((half.width, half.height), (500, 250));
    assert!((half.mm_per_texel - 0.2).abs() < 1e-12);
    let seeds = half.seed_points();
    assert_eq!((seeds[0].x, seeds[0].y), (150, 150));
    assert_eq!((seeds[1].x, seeds[1].y), (250, 125));
    // Points apart at 1000x500 can meet on a tiny map.
    let msg = l.with_size(1, 1).unwrap_err().to_string();
    assert!(msg.contains("region `cheek` point 1 and region `nose` point 1 fall on the same texel"), "{msg}");
}

#[test]
fn a_missing_scale_is_named_not_a_parse_error() {
    // Issue 41: not "TOML parse error at line 1, column 1"; refused once it is clear no mesh
    // (from the layout or `face --mesh`) will measure it.
    let l = parse(&format!("size = [64, 32]\n{REGION}")).unwrap();
    let msg = l.check_placed().unwrap_err().to_string();
    assert!(
        msg.contains("mm_per_texel: missing: the physical size of one map texel") && !msg.contains("line 1"),
        "{msg}"
    );
}

#[test]
fn refusals_name_the_file_and_the_field() {
    let cases: Vec<(String, &str)> = vec![
        ("mm_per_texel = 0.05\n".into(), "region: the layout has no [[region]] entries"),
        (
            format!("mm_per_texel = 0.05\nsize = [0, 2048]\n{REGION}"),
            "size: 0x2048 must have positive width and height",
        ),
        (format!("mm_per_texel = 0.05\nsize = [-4, 2]\n{REGION}"), "size: -4x2"),
        (format!("mm_per_texel = 0.05\nsize = [100000, 100000]\n{REGION}"), "exceeds the limit"),
        (format!("mm_per_texel = 0.0\n{REGION}"), "mm_per_texel: 0 must be a finite number > 0"),
        (format!("mm_per_texel = -1.0\n{REGION}"), "mm_per_texel: -1"),
        (format!("mm_per_texel = nan\n{REGION}"), "mm_per_texel: NaN"),
        (
            format!(
                "mm_per_texel = 0.05\n{}",
                REGION.replace("exemplar_mm_per_texel = 0.02", "exemplar_mm_per_texel = 0")
            ),
            "region `cheek`: exemplar_mm_per_texel: 0 must be",
        ),
        (format!("mm_per_texel = 0.05\n{REGION}{REGION}"), "region.name: regions 1 and 2 are both named `cheek`"),
        (
            format!("mm_per_texel = 0.05\n{}", REGION.replace("[[0.3, 0.6]]", "[[0.3, 1.2]]")),
            "region `cheek`: points: point 1 (0.3, 1.2) lies outside the map",
        ),
        (
            format!("mm_per_texel = 0.05\n{}", REGION.replace("points = [[0.3, 0.6]]", "pixels = [[4096, 3]]")),
            "region `cheek`: pixels: pixel 1 (4096, 3) lies outside the 4096x2048 map",
        ),
        (
            format!("mm_per_texel = 0.05\n{}", REGION.replace("points = [[0.3, 0.6]]", "points = []")),
            "region `cheek`: points: no seed points",
        ),
        (
            format!("mm_per_texel = 0.05\n{}", REGION.replace("exemplar = \"cheek.png\"", "")),
            "region `cheek`: exemplar: missing",
        ),
        (
            format!(
                "mm_per_texel = 0.05\n{}",
                REGION.replace("exemplar = \"cheek.png\"", "exemplar = \"a.png\"\nsession = \"s\"")
            ),
            "not both",
        ),
        (
            format!("mm_per_texel = 0.05\n{}", REGION.replace("name = \"cheek\"", "name = \" \"")),
            "region `region 1`: name: must not be empty",
        ),
        (format!("mm_per_texel = 0.05\nscale = 2\n{REGION}"), "unknown field `scale`"),
        (
            format!("mm_per_texel = 0.05\n{}", REGION.replace("seed", "sed")).replace("points", "pointz"),
            "unknown field `pointz`",
        ),
        ("mm_per_texel = \n".into(), "line 1"),
    ];
    for (text, expected) in cases {
        let msg = error(&text);
        assert!(msg.contains(expected), "expected `{expected}` in `{msg}`");
    }
}

#[test]
fn two_points_on_one_texel_are_refused_naming_both_regions() {
    let text = format!(
        "mm_per_texel = 0.05\n{REGION}\n[[region]]\nname = \"nose\"\nexemplar = \"n.png\"\nexemplar_mm_per_texel = 0.02\npoints = [[0.5, 0.5], [0.30001, 0.60001]]\n"
    );
    let msg = error(&text);
    assert!(
        msg.contains(
            "region `cheek` point 1 and region `nose` point 2 fall on the same texel (1228, 1228) of the 4096x2048 map"
        ),
        "{msg}"
    );
    assert!(matches!(parse(&text), Err(Error::CoincidentPoints { .. })));
    // Within one region too, and a UV point on the same texel as a pixel point.
    let same = REGION.replace("points = [[0.3, 0.6]]", "points = [[0.3, 0.6]]\npixels = [[1228, 1228]]");
    assert!(
        error(&format!("mm_per_texel = 0.05\n{same}")).contains("region `cheek` point 1 and region `cheek` point 2")
    );
}

#[test]
fn a_missing_exemplar_is_an_error_at_load_naming_the_region_and_path() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("molds")).unwrap();
    std::fs::write(dir.path().join("nose.png"), b"not checked here").unwrap();
    let write = |body: &str| {
        let path = dir.path().join("face.toml");
        std::fs::write(&path, format!("mm_per_texel = 0.05\n{body}")).unwrap();
        path
    };
    let ok = write(
        "[[region]]\nname = \"nose\"\nexemplar = \"nose.png\"\nexemplar_mm_per_texel = 0.02\npoints = [[0.5, 0.5]]\n\
         [[region]]\nname = \"brow\"\nsession = \"molds\"\nexemplar_mm_per_texel = 0.02\npoints = [[0.5, 0.1]]\n",
    );
    let layout = Layout::load(&ok).unwrap();
    assert_eq!(layout.regions[1].exemplar, ExemplarSource::Session(dir.path().join("molds")));

    let missing = write(
        "[[region]]\nname = \"cheek\"\nexemplar = \"cheek.png\"\nexemplar_mm_per_texel = 0.02\npoints = [[0.5, 0.5]]\n",
    );
    let msg = Layout::load(&missing).unwrap_err().to_string();
    assert!(msg.contains("region `cheek`: exemplar normal map") && msg.contains("cheek.png does not exist"), "{msg}");
    assert!(msg.contains("face.toml"), "{msg}");
    // Parsing alone does not touch the file system.
    assert!(Layout::parse(&std::fs::read_to_string(&missing).unwrap(), &missing).is_ok());

    // A session must be a folder, not a file.
    let file_session = write(
        "[[region]]\nname = \"nose\"\nsession = \"nose.png\"\nexemplar_mm_per_texel = 0.02\npoints = [[0.5, 0.5]]\n",
    );
    assert!(Layout::load(&file_session).unwrap_err().to_string().contains("region `nose`: capture session folder"));

    let no_file = dir.path().join("absent.toml");
    assert!(Layout::load(&no_file).unwrap_err().to_string().contains("absent.toml"));
}

#[test]
fn the_coverage_mask_must_match_the_map() {
    let dir = tempfile::tempdir().unwrap();
    let mask = dir.path().join("mask.png");
    // 4x2, white on the left half.
    let samples = [255u16, 255, 0, 0, 255, 255, 0, 0];
    skinkit_maps::io::write_png(&mask, 4, 2, skinkit_maps::io::PngLayout::Gray8, &samples).unwrap();
    let origin = dir.path().join("face.toml");
    let text = |size: &str| format!("size = {size}\nmm_per_texel = 0.05\ncoverage = \"mask.png\"\n{REGION}");
    let layout = Layout::parse(&text("[4, 2]"), &origin).unwrap();
    let coverage = layout.load_coverage().unwrap().unwrap();
    assert_eq!(coverage.as_slice(), &[true, true, false, false, true, true, false, false]);
    let wrong = Layout::parse(&text("[8, 2]"), &origin).unwrap();
    let msg = wrong.load_coverage().unwrap_err().to_string();
    assert!(msg.contains("coverage") && msg.contains("is 4x2 but the map is 8x2"), "{msg}");
}

#[test]
fn the_sample_face_layout_loads_and_partitions() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/face/layout.toml");
    let layout = Layout::load(&path).unwrap();
    assert_eq!((layout.width, layout.height), (4096, 2048));
    assert_eq!(layout.regions.len(), 7);
    let seeds = layout.seed_points();
    assert_eq!(seeds.len(), 7, "the paper's 7 points");
    for r in &layout.regions {
        let ExemplarSource::Session(dir) = &r.exemplar else { panic!("{} is not a session", r.name) };
        assert!(dir.join("rig.toml").is_file(), "{}", dir.display());
        assert_eq!(r.exemplar_mm_per_texel, 0.02);
    }
    // Every region gets a sizeable share of a small version of the map.
    let small = layout.with_size(512, 256).unwrap();
    let p = Partition::nearest(512, 256, 7, &small.seed_points()).unwrap();
    for (r, area) in p.areas().iter().enumerate() {
        assert!(area.texels > 512 * 256 / 30, "region {} has {} texels", layout.regions[r].name, area.texels);
    }
}

/// Issue 42: a layout of thousands of tiny regions ran for hours (each region is grown on its
/// own); more than `MAX_REGIONS` is refused at load, naming the file, the field and the limit.
#[test]
fn probe2_too_many_regions_are_refused_at_load() {
    let region = |i: usize| {
        format!(
            "[[region]]\nname = \"r{i}\"\nexemplar = \"e.png\"\nexemplar_mm_per_texel = 0.02\npoints = [[{}, {}]]\n",
            (i % 64) as f64 / 64.0 + 0.005,
            (i / 64) as f64 / 64.0 + 0.005
        )
    };
    let many: String = (0..=layout::MAX_REGIONS).map(region).collect();
    let msg = error(&format!("mm_per_texel = 0.05\n{many}"));
    assert!(
        msg.contains("region")
            && msg.contains(&format!("{} regions: at most {}", layout::MAX_REGIONS + 1, layout::MAX_REGIONS)),
        "{msg}"
    );
    let enough: String = (0..layout::MAX_REGIONS).map(region).collect();
    assert!(parse(&format!("mm_per_texel = 0.05\n{enough}")).is_ok());
}
