//! End-to-end tests of `skinkit demo`: one run of the demo on the bundled samples (shared by the
//! tests here), its report, its outputs and its report page, opened in headless Chromium.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The demo's output folder and its `--json` report, run once for every test of this file.
fn demo() -> (&'static Path, &'static serde_json::Value) {
    static DEMO: OnceLock<(tempfile::TempDir, serde_json::Value)> = OnceLock::new();
    let (dir, report) = DEMO.get_or_init(|| {
        let tmp = tempfile::tempdir().unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_skinkit"))
            .args(["demo", "--json", "--out", tmp.path().to_str().unwrap()])
            .output()
            .expect("skinkit runs");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (tmp, serde_json::from_slice(&o.stdout).unwrap())
    });
    (dir.path(), report)
}

#[test]
fn demo_reports_every_mold_with_both_solvers() {
    let (tmp, report) = demo();
    let molds = report["molds"].as_array().unwrap();
    assert_eq!(molds.len(), 8);
    for m in molds {
        assert!(m["mean_error_deg"].as_f64().unwrap().is_finite());
    }
    assert!(tmp.join("demo-report.json").is_file());
    // Each mold's robust map grown to the default 1024x1024, albedo and coordinates beside it.
    let growths = report["growths"].as_array().unwrap();
    assert_eq!(growths.len(), 4);
    for g in growths {
        let region = g["region"].as_str().unwrap();
        assert_eq!((g["width"].as_u64(), g["height"].as_u64()), (Some(1024), Some(1024)), "{region}");
        let slope = g["quality"]["slope_distance"].as_f64().unwrap();
        assert!(slope.is_finite() && slope < 0.1, "{region}: slope distance {slope}");
        let dir = tmp.join("synth").join(region);
        for name in ["normal.png", "albedo.png", "coords.png"] {
            assert!(dir.join(name).is_file(), "{region}/{name} missing");
        }
        let normals =
            skinkit_maps::io::read_normal_map(&dir.join("normal.png"), Default::default(), &Default::default())
                .unwrap();
        assert_eq!(normals.size(), (1024, 1024));
    }
    // The sample face, stitched at 2048x1024 from the seven regions of samples/face/layout.toml.
    let face = &report["face"];
    assert_eq!((face["width"].as_u64(), face["height"].as_u64()), (Some(2048), Some(1024)));
    assert_eq!(face["regions"].as_array().unwrap().len(), 7);
    assert!(face["seams"]["summary"]["mean_jump_degrees"].as_f64().unwrap().is_finite());
    for name in ["normal.png", "normal.exr", "labels.png", "report.json"] {
        assert!(tmp.join("face").join(name).is_file(), "face/{name} missing");
    }
    // Figures 7 (the face without and with the face map) and 8 (a patch under four lights),
    // rendered on the test machine's adapter (lavapipe in CI: scripts/test installs it).
    let renders = &report["renders"];
    // Figure 7: two PNG panels and four EXRs (skin and smooth, lobes on and off); figure 8: four
    // patches; the skin figure: six methods.
    // With the height's round trip: figure 7 lit from the height's normals and from the
    // differenced map.
    assert_eq!(renders["renders"].as_array().unwrap().len(), 18, "{renders}");
    let read = |name: &str| {
        let p = skinkit_maps::io::read_photo(&tmp.join("render").join(name), &Default::default()).unwrap();
        let skinkit_maps::Samples::U8(v) = p.samples() else { panic!("{name} is not 8-bit") };
        (p.width(), p.height(), v.clone())
    };
    let (w7, h7, fig7) = read("figure7.png");
    assert_eq!((w7, h7), (2 * 1024, 1024));
    let (w8, h8, _) = read("figure8.png");
    assert_eq!((w8, h8), (2 * 768, 2 * 768));
    // The right panel (with fine-scale structure) is not the left one.
    let differ = (0..h7)
        .flat_map(|y| (0..1024).map(move |x| (x, y)))
        .filter(|&(x, y)| fig7[3 * (y * w7 + x)] != fig7[3 * (y * w7 + x + 1024)])
        .count();
    assert!(differ > 1024 * 1024 / 20, "figure 7's panels differ in only {differ} pixels");
    // Issue 13: the lobes make much of figure 7's highlights, and the grown map raises the
    // sheen's local contrast. Issue 41 asks, over the brightest 5 % of the skin's pixels, for
    // the lobes to make at least a quarter and the grown map to at least double the contrast.
    // Measured on the MakeHuman head, framed on brow, eye and nose under a rim, a key and a
    // fill: 37 %, contrast 0.131 against 0.047 (2.8x).
    let (skin, smooth) = (&renders["figure7"]["skin"], &renders["figure7"]["smooth"]);
    let share = skin["mean"].as_f64().unwrap();
    assert!(share >= 0.25, "the lobes make only {share} of figure 7's highlights");
    let (c_skin, c_smooth) = (skin["local_contrast"].as_f64().unwrap(), smooth["local_contrast"].as_f64().unwrap());
    assert!(c_skin >= 2.0 * c_smooth, "sheen contrast {c_skin} with the map, {c_smooth} without");
    assert!(tmp.join("render").join("head-skin.toml").is_file());
    let (ws, hs, _) = read("figure-skin.png");
    assert_eq!((ws, hs), (3 * 768, 2 * 768));
    skin_figure_ranks_the_methods(renders);
    height_round_trip(face, renders);
}

/// The skin figure: six methods in a 3 x 2 grid, each with its FLIP mean against the reference
/// (the last panel, 0 against itself). Framed on the nose's shadow across the cheek, where
/// scattering shows (issue 41): the best skin method is within half of Lambert's error.
/// Measured: Lambert 0.050, blog fit 0.055, own fit and LUT 0.035, TSD 0.024.
fn skin_figure_ranks_the_methods(renders: &serde_json::Value) {
    let methods = renders["skin"]["methods"].as_array().unwrap();
    let names: Vec<&str> = methods.iter().map(|m| m["method"].as_str().unwrap()).collect();
    assert_eq!(names, ["lambert", "blog-fit", "own-fit", "lut-256", "tsd-1x1024", "reference-1024"]);
    let flip = |m: &serde_json::Value| m["flip_mean"].as_f64().unwrap();
    for m in methods {
        let last = m["method"] == "reference-1024";
        assert!(if last { flip(m) == 0.0 } else { flip(m) > 0.0 && flip(m) < 0.2 }, "{m}");
    }
    let lambert = flip(&methods[0]);
    let best = methods[1..5].iter().map(flip).fold(f64::INFINITY, f64::min);
    assert!(best <= 0.5 * lambert, "best skin method FLIP {best}, Lambert {lambert}");
}

/// Issue 40: the face's height keeps what its normal map shows. Measured on the demo's face:
/// texels 0.23 deg median, 7.1 max; figure 7 lit from the height's normals FLIP 0.020 against the
/// normal map, 0.018 of it the differencing's own filter, 0.009 against the differenced map.
fn height_round_trip(face: &serde_json::Value, renders: &serde_json::Value) {
    let texels = &face["height_map"]["round_trip"];
    let median = texels["all"]["median"].as_f64().unwrap();
    assert!(median < 0.5, "the height's normals are {median} deg from the map's (median)");
    let on = texels["seams"]["on_seams"]["count"].as_u64().unwrap();
    assert!(on > 0, "no texel on a region seam: {texels}");
    let t = &renders["height_round_trip"];
    let flip = |k: &str| t[k].as_f64().unwrap();
    assert!(flip("flip_height_vs_map") > 0.0 && flip("flip_height_vs_map") < 0.05, "{t}");
    assert!(flip("flip_height_vs_differenced_map") < flip("flip_height_vs_map"), "{t}");
}

/// `node` and the page checker's packages (`tools/page-check`, installed with npm when missing),
/// and the system's Chromium; `None` with the reason when one of them cannot be had here.
fn page_checker() -> Result<PathBuf, String> {
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/page-check");
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    if !Path::new(&chromium).is_file() {
        return Err(format!("no Chromium at {chromium} (Debian: apt-get install chromium; scripts/test installs it)"));
    }
    let runs = |program: &str, args: &[&str]| {
        Command::new(program).args(args).current_dir(&tools).output().is_ok_and(|o| o.status.success())
    };
    if !runs("node", &["--version"]) {
        return Err("no node (Debian: apt-get install nodejs npm)".into());
    }
    if !tools.join("node_modules/playwright-core").is_dir()
        && !runs("npm", &["ci", "--no-audit", "--no-fund", "--silent"])
    {
        return Err(format!("npm ci failed in {}", tools.display()));
    }
    Ok(tools.join("check-page.mjs"))
}

#[test]
fn demo_page_loads_every_image_without_console_errors_in_headless_chromium() {
    let (dir, report) = demo();
    let page = dir.join("index.html");
    assert_eq!(report["page"].as_str(), Some(page.to_str().unwrap()));
    let html = std::fs::read_to_string(&page).unwrap();
    // Self-contained: no script, nothing fetched from elsewhere, every picture beside the page.
    assert!(!html.contains("<script") && !html.contains("http://") && !html.contains("https://"));
    for stage in ["id=\"capture\"", "id=\"synthesis\"", "id=\"face\"", "id=\"renders\""] {
        assert!(html.contains(stage), "the page has no {stage} section");
    }
    // Each stage's plot from the quick accuracy run, and its numbers in the report.
    for stage in ["capture", "detrend", "height", "synthesis", "stitching", "rendering"] {
        let plot = format!("accuracy/accuracy-{stage}.png");
        assert!(html.contains(&plot) && dir.join(&plot).is_file(), "no {plot}");
    }
    let stages = report["accuracy"]["stages"].as_array().unwrap();
    assert_eq!(stages.len(), 6);
    assert!(stages.iter().all(|s| s["skipped"].is_null() && !s["choices"].as_array().unwrap().is_empty()));
    let checker = match page_checker() {
        Ok(c) => c,
        Err(why) => {
            eprintln!("skipped: the report page was not opened in a browser: {why}");
            return;
        }
    };
    let screenshot = dir.join("page-screenshot.png");
    let o = Command::new("node").arg(&checker).arg(&page).arg(&screenshot).output().expect("node runs");
    assert!(o.status.success(), "check-page.mjs failed: {}", String::from_utf8_lossy(&o.stderr));
    let seen: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(seen["title"], "skinkit demo");
    for list in ["console_errors", "page_errors", "failed_requests"] {
        assert_eq!(seen[list].as_array().map(Vec::len), Some(0), "{list}: {}", seen[list]);
    }
    let images = seen["images"].as_array().unwrap();
    // Per mold: 8 photos and 4 maps, exemplar and grown; the face; 3 figures and the renders.
    assert!(images.len() >= 4 * (8 + 4 + 2) + 1 + 3, "only {} images", images.len());
    for image in images {
        assert!(image["complete"] == true && image["natural_width"].as_u64() > Some(0), "did not load: {image}");
    }
    let shot = skinkit_maps::io::read_photo(&screenshot, &Default::default()).unwrap();
    assert!(shot.width() >= 1280 && shot.height() > 2000, "{}x{}", shot.width(), shot.height());
    // Kept beside the test's outputs for a person to look at when it fails.
    let kept = Path::new(env!("CARGO_TARGET_TMPDIR")).join("demo-page.png");
    std::fs::copy(&screenshot, &kept).unwrap();
    eprintln!("screenshot of the report page: {}", kept.display());
}

/// Issue 42, D14: a demo of a samples folder without sample molds fails, naming the folder,
/// rather than writing empty tables and an empty report page with exit 0.
#[test]
fn d14_demo_of_an_empty_samples_folder_fails() {
    let tmp = tempfile::tempdir().unwrap();
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let out = tmp.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_skinkit"))
        .args(["demo", "--samples", empty.to_str().unwrap(), "--no-render", "--no-accuracy", "--out"])
        .arg(&out)
        .output()
        .expect("skinkit runs");
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("empty: no sample molds in this folder"), "{e}");
}
