//! The demo's report page, `DIR/index.html`: per stage, the inputs and outputs as pictures beside
//! the stage's time and accuracy table, and the machine it ran on. One file of HTML and CSS (no
//! script, no network); its pictures sit beside it, in the demo's own folders or in `page/`
//! (8-bit previews drawn here: normal maps as relief under a raking light, photos stretched to
//! be seen, heights lit from their own normals and in false colour with a scale bar), all linked by relative paths, so the folder can be moved or zipped as a whole.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use skinkit_accuracy::{Stage, markdown};
use skinkit_capture::session::Session;
use skinkit_maps::{Grid, NormalEncoding, io, preview};

use super::DemoReport;

/// Longest side of a preview on the page, pixels.
const PREVIEW_SIDE: usize = 1024;
/// Size of the face map's detail at one texel a pixel.
const DETAIL: (usize, usize) = (1024, 512);
/// Longest side of a photo thumbnail.
const THUMB_SIDE: usize = 160;

/// Writes `out/index.html` (and its previews in `out/page/`) for `report`, whose outputs are in
/// `out`; the photos are read from the molds in `samples`. Returns the page's path.
///
/// # Errors
/// When an output of the demo cannot be read or a preview or the page cannot be written.
pub fn write(out: &Path, samples: &Path, report: &DemoReport) -> Result<PathBuf> {
    let previews = out.join("page");
    std::fs::create_dir_all(&previews).with_context(|| format!("cannot create {}", previews.display()))?;
    let mut html = String::new();
    head(&mut html, report);
    showcase(&mut html, out, report);
    contents(&mut html, report);
    capture(&mut html, out, samples, report)?;
    synthesis(&mut html, out, report)?;
    face(&mut html, out, report)?;
    renders(&mut html, out, report);
    html += "</main></body></html>\n";
    let page = out.join("index.html");
    crate::pipeline::write_text(&page, "the demo page", &html)?;
    Ok(page)
}

/// `text` with the five characters HTML gives meaning to escaped.
fn esc(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;").replace('\'', "&#39;")
}

/// `path` relative to `out`, with forward slashes (for `src` and `href`).
fn rel(out: &Path, path: &Path) -> String {
    let path = path.strip_prefix(out).unwrap_or(path);
    path.components().map(|c| c.as_os_str().to_string_lossy()).collect::<Vec<_>>().join("/")
}

/// A picture with its caption.
pub(super) fn figure(html: &mut String, src: &str, caption: &str, class: &str) {
    let _ = write!(
        html,
        "<figure class=\"{class}\"><a href=\"{s}\"><img src=\"{s}\" alt=\"{c}\"></a><figcaption>{c}</figcaption></figure>",
        s = esc(src),
        c = esc(caption)
    );
}

/// A table: header cells, then rows of cells (already formatted).
fn table(html: &mut String, header: &[&str], rows: &[Vec<String>]) {
    html.push_str("<table><thead><tr>");
    for h in header {
        let _ = write!(html, "<th>{}</th>", esc(h));
    }
    html.push_str("</tr></thead><tbody>");
    for row in rows {
        html.push_str("<tr>");
        for cell in row {
            let _ = write!(html, "<td>{}</td>", esc(cell));
        }
        html.push_str("</tr>");
    }
    html.push_str("</tbody></table>\n");
}

/// A stage's heading and its time.
fn stage(html: &mut String, id: &str, title: &str, seconds: Option<f64>, what: &str) {
    let time = seconds.map_or(String::new(), |s| format!(" <span class=\"time\">{s:.1} s</span>"));
    let _ = writeln!(html, "<section id=\"{id}\"><h2>{}{time}</h2><p>{}</p>", esc(title), esc(what));
}

const STYLE: &str = "body{font:15px/1.45 system-ui,sans-serif;margin:0;background:#f6f5f3;color:#222}\
main{max-width:1400px;margin:auto;padding:1em 2em}h1{margin-bottom:.2em}\
h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}.time{color:#777;font-weight:normal;font-size:.8em}\
.bar .scale{display:flex;gap:.4em}.bar .ramp{width:18px;height:200px;border:1px solid #999}\
.bar .labels{display:flex;flex-direction:column;justify-content:space-between;font-size:.8em;height:200px}\
table{border-collapse:collapse;margin:.8em 0}th,td{padding:.2em .7em;border-bottom:1px solid #ddd;text-align:right}\
th:first-child,td:first-child{text-align:left}.row{display:flex;flex-wrap:wrap;gap:.6em;align-items:flex-start}\
figure{margin:0}figure img{display:block;max-width:100%;image-rendering:auto;border:1px solid #bbb}\
figcaption{font-size:.85em;color:#555;max-width:32em}.thumb img{width:96px}.map img{width:256px}\
.wide img{width:100%}.native img{width:auto;max-width:100%}.machine{color:#555}\
nav ol{columns:2;max-width:40em}details{margin:.4em 0 1em}summary{cursor:pointer;color:#345}.why{color:#553}";

fn head(html: &mut String, report: &DemoReport) {
    let s = &report.seconds;
    let _ = writeln!(
        html,
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>skinkit demo</title>\
         <style>{STYLE}</style></head><body><main><h1>skinkit demo</h1>\
         <p class=\"machine\">skinkit {} on {}; {:.1} s in all.</p>\
         <p>Photos of four sample molds, each under eight lights, are solved for their normals and \
         albedo; each normal map is grown to a larger one; one grown map per face region is \
         stitched into a face map; the face map is rendered on a head.</p>",
        esc(report.machine.skinkit),
        esc(&report.machine.summary()),
        s.total
    );
}

/// The page opens with the face: figure 7, the grown skin without and with the map, and what
/// the map does to the sheen.
fn showcase(html: &mut String, out: &Path, report: &DemoReport) {
    let Some(r) = &report.renders else { return };
    let (skin, smooth) = (&r.figure7.skin, &r.figure7.smooth);
    stage(
        html,
        "showcase",
        "The grown skin",
        None,
        &format!(
            "The sample head's brow, eye and nose at 0.09 mm a pixel, without (left) and with (right) the face \
             map grown from the four molds below (the paper's figure 7). Over the brightest {:.0} % of the skin's \
             pixels the specular lobes make {:.0} % of the light, and the map raises the sheen's local contrast \
             from {:.3} to {:.3}.",
            skinkit_render::highlight::HIGHLIGHT_FRACTION * 100.0,
            skin.mean * 100.0,
            smooth.local_contrast,
            skin.local_contrast
        ),
    );
    let p = rel(out, Path::new(&r.figure7.image));
    figure(html, &p, "Figure 7: the head without (left) and with (right) the face map", "wide");
    html.push_str("</section>\n");
}

/// The table of contents: the sections the page has.
fn contents(html: &mut String, report: &DemoReport) {
    let mut entries = vec![("capture", "Capture"), ("synthesis", "Synthesis"), ("face", "Face map")];
    if report.renders.is_some() {
        entries.insert(0, ("showcase", "The grown skin"));
        entries.push(("renders", "Renders"));
    }
    html.push_str("<nav><h2>Contents</h2><ol>");
    for (id, title) in entries {
        let _ = write!(html, "<li><a href=\"#{id}\">{}</a></li>", esc(title));
    }
    html.push_str("</ol></nav>\n");
}

/// Photos, maps and errors of every mold.
fn capture(html: &mut String, out: &Path, samples: &Path, report: &DemoReport) -> Result<()> {
    stage(
        html,
        "capture",
        "Capture",
        Some(report.seconds.capture),
        "Per mold: its eight photos, then the robust solver's normal map drawn as relief under a raking \
         light and as stored (16-bit PNG), its albedo and its confidence. The table gives each solver's \
         angular error against the mold's ground truth.",
    );
    let rows: Vec<Vec<String>> = report
        .molds
        .iter()
        .map(|m| {
            vec![
                m.region.clone(),
                m.solver.clone(),
                format!("{:.3}", m.mean_error_deg),
                format!("{:.3}", m.rms_error_deg),
                format!("{:.3}", m.p95_error_deg),
                m.invalid_pixels.to_string(),
                format!("{:.2}", m.solve_seconds * 1e3),
            ]
        })
        .collect();
    table(html, &["mold", "solver", "mean deg", "rms deg", "p95 deg", "invalid", "solve ms"], &rows);
    let mut regions: Vec<&str> = report.molds.iter().map(|m| m.region.as_str()).collect();
    regions.dedup();
    for region in regions {
        let _ = write!(html, "<h3>{}</h3><div class=\"row\">", esc(region));
        let session = Session::from_dir(&samples.join(region))?;
        for (i, photo) in session.photos.iter().enumerate() {
            let src = photo_thumbnail(out, photo, &format!("{region}-photo-{}.png", i + 1))?;
            figure(html, &src, &format!("light {}", i + 1), "thumb");
        }
        html.push_str("</div><div class=\"row\">");
        let dir = out.join("capture").join(region).join("robust");
        let shaded = shaded_normals(out, &dir.join("normal.png"), &format!("capture-{region}.png"))?;
        figure(html, &shaded, "normals, as relief", "map");
        for (name, caption) in
            [("normal.png", "normals, as stored"), ("albedo.png", "albedo"), ("confidence.png", "confidence")]
        {
            figure(html, &rel(out, &dir.join(name)), caption, "map");
        }
        super::height::figures(html, out, &dir.join("height.exr"), &format!("capture-{region}"), true, false)?;
        html.push_str("</div>\n");
    }
    accuracy(html, report, &[Stage::Capture, Stage::Detrend, Stage::Height]);
    html.push_str("</section>\n");
    Ok(())
}

/// Every grown map beside its exemplar, with the growth's quality measures.
fn synthesis(html: &mut String, out: &Path, report: &DemoReport) -> Result<()> {
    stage(
        html,
        "synthesis",
        "Synthesis",
        Some(report.seconds.synthesis),
        "Each mold's captured normal map (left) grown to a larger map (right), both drawn as relief at \
         one texel a pixel (shrunk only where the page is narrower). Slope W1: distance between the slope distributions of the grown map and its \
         exemplar; spectrum: distance between their power spectra; largest: texels of the largest \
         piece copied verbatim.",
    );
    let rows: Vec<Vec<String>> = report
        .growths
        .iter()
        .map(|g| {
            vec![
                g.region.clone(),
                format!("{}x{}", g.width, g.height),
                format!("{:.2}", g.seconds),
                g.quality.slope_distance.map_or("-".into(), |d| format!("{d:.4}")),
                format!("{:.3}", g.quality.spectrum_distance),
                g.quality.largest_block.to_string(),
            ]
        })
        .collect();
    table(html, &["grown", "size", "seconds", "slope W1", "spectrum", "largest"], &rows);
    for g in &report.growths {
        let exemplar = out.join("capture").join(&g.region).join("robust").join("normal.png");
        let _ = write!(html, "<h3>{}</h3><div class=\"row\">", esc(&g.region));
        let src = shaded_normals(out, &exemplar, &format!("exemplar-{}.png", g.region))?;
        figure(html, &src, "exemplar (captured)", "native");
        let grown = out.join("synth").join(&g.region).join("normal.png");
        let src = shaded_normals(out, &grown, &format!("grown-{}.png", g.region))?;
        figure(html, &src, &format!("grown to {}x{} in {:.1} s", g.width, g.height, g.seconds), "native");
        let height = out.join("synth").join(&g.region).join("height.exr");
        super::height::figures(html, out, &height, &format!("grown-{}", g.region), true, true)?;
        html.push_str("</div>\n");
    }
    accuracy(html, report, &[Stage::Synthesis]);
    html.push_str("</section>\n");
    Ok(())
}

/// The stitched face map with its region boundaries, the regions and the seam measures.
fn face(html: &mut String, out: &Path, report: &DemoReport) -> Result<()> {
    let Some(f) = &report.face else { return Ok(()) };
    stage(
        html,
        "face",
        "Face map",
        Some(f.seconds.total),
        "One synthesis per face region, joined by multiresolution splines along random curves. The map \
         is drawn as relief, region boundaries in red. Seams: gradient ratio across a boundary against \
         inside the regions (1 is invisible) and the mean angle between the normals either side.",
    );
    let dir = out.join("face");
    let (whole, detail) = face_preview(out, &dir.join("normal.png"), &dir.join("labels.png"))?;
    figure(html, &whole, &format!("{}x{} face map, {} regions", f.width, f.height, f.regions.len()), "wide");
    figure(html, &detail, "its centre at one texel a pixel", "native");
    html.push_str("<div class=\"row\">");
    super::height::figures(html, out, &dir.join("height.exr"), "face", true, false)?;
    html.push_str("</div>");
    let rows: Vec<Vec<String>> = f
        .regions
        .iter()
        .map(|r| {
            vec![
                r.name.clone(),
                r.texels.to_string(),
                format!("{}x{}", r.exemplar_size.0, r.exemplar_size.1),
                format!("{:.2}", r.synthesis_seconds),
            ]
        })
        .collect();
    table(html, &["region", "texels", "exemplar", "synthesis s"], &rows);
    let s = &f.seams.summary;
    let ratio = |r: Option<f64>| r.map_or("-".into(), |r| format!("{r:.2}"));
    table(
        html,
        &["seams", "mean gradient ratio", "max gradient ratio", "mean jump deg", "max jump deg"],
        &[vec![
            format!("{} boundaries, {} spline levels", s.boundaries, f.levels),
            ratio(s.mean_gradient_ratio),
            ratio(s.max_gradient_ratio),
            format!("{:.2}", s.mean_jump_degrees),
            format!("{:.2}", s.max_jump_degrees),
        ]],
    );
    if let Some(h) = &f.height_map {
        round_trip_table(html, &h.round_trip);
    }
    accuracy(html, report, &[Stage::Stitching]);
    html.push_str("</section>\n");
    Ok(())
}

/// How the face height's own normals agree with the face's normal map, and where they part.
fn round_trip_table(html: &mut String, a: &skinkit_height::round_trip::Agreement) {
    let row = |name: &str, s: &skinkit_maps::normal::AngularStats| {
        vec![
            name.to_owned(),
            s.count.to_string(),
            format!("{:.2}", s.median),
            format!("{:.2}", s.p95),
            format!("{:.1}", s.max),
        ]
    };
    let mut rows = vec![row("every texel", &a.all)];
    if let Some(seams) = &a.seams {
        rows.push(row("on region seams", &seams.on_seams));
        rows.push(row("off seams", &seams.off_seams));
    }
    table(html, &["the height's normals against the map (deg)", "texels", "median", "p95", "max"], &rows);
}

/// The figures and every render, each with its caption, and the skin methods' errors.
fn renders(html: &mut String, out: &Path, report: &DemoReport) {
    let Some(r) = &report.renders else { return };
    let adapter = r.renders.first().map_or("", |j| j.adapter.as_str());
    stage(
        html,
        "renders",
        "Renders",
        report.seconds.renders,
        &format!("The face map on the sample head, drawn by the bundled renderer on {adapter}."),
    );
    let p = |s: &str| rel(out, Path::new(s));
    figure(html, &p(&r.figure8), "Figure 8: a patch of the face map under four light directions", "wide");
    figure(html, &p(&r.skin.image), "Skin scattering methods against the texture-space reference", "wide");
    if let Some(t) = &r.height_round_trip {
        let caption = format!(
            "Figure 7's close-up lit from the face's normal map (left) and from its height's own normals (right): FLIP {:.3}",
            t.flip_height_vs_map
        );
        figure(html, &p(&t.image), &caption, "wide");
    }
    let rows: Vec<Vec<String>> = r
        .skin
        .methods
        .iter()
        .map(|m| vec![m.method.clone(), format!("{:.4}", m.flip_mean), format!("{:.3}", m.render_seconds)])
        .collect();
    table(html, &["skin method", "FLIP against the reference", "render s"], &rows);
    html.push_str("<h3>Every render</h3><div class=\"row\">");
    for job in &r.renders {
        for image in job.images.iter().filter(|i| i.path.ends_with(".png")) {
            let scene = Path::new(&job.scene).file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned());
            let caption = format!("{scene}: {}x{}, {:.2} s", job.width, job.height, image.render_seconds);
            figure(html, &p(&image.path), &caption, "map");
        }
    }
    html.push_str("</div>");
    accuracy(html, report, &[Stage::Rendering]);
    html.push_str("</section>\n");
}

/// The quick accuracy run's block for each of `stages` (nothing without the run): its plot, the
/// default's row, a line where another choice scores better and why the default stays, and the
/// full table one click away.
fn accuracy(html: &mut String, report: &DemoReport, stages: &[Stage]) {
    let Some(run) = &report.accuracy else { return };
    for stage in run.stages.iter().filter(|s| stages.contains(&s.stage)) {
        let _ = write!(html, "<h3>Accuracy against time: {}</h3>", esc(stage.stage.name()));
        if let Some(reason) = &stage.skipped {
            let _ = write!(html, "<p>Not measured: {}.</p>", esc(reason));
            continue;
        }
        let caption =
            format!("{} against {} (quick run, {:.1} s)", stage.error_metric, stage.cost_axis, stage.wall_seconds);
        figure(html, &format!("accuracy/{}", markdown::plot_name(stage)), &caption, "native");
        let header = ["series", "choice", stage.error_metric.as_str(), stage.cost_axis.as_str()];
        let row = |c: &skinkit_accuracy::Choice| {
            vec![c.series.clone(), c.label.clone(), format!("{:.4}", c.error()), format!("{:.4}", c.cost)]
        };
        let defaults: Vec<Vec<String>> = stage.choices.iter().filter(|c| c.is_default()).map(row).collect();
        if !defaults.is_empty() {
            table(html, &header, &defaults);
        }
        for (winner, default) in stage.defaults_beaten() {
            let why = stage.stage.why_default_kept().unwrap_or("this quick run measures it on small inputs");
            let _ = write!(
                html,
                "<p class=\"why\">{} scores {:.4} against the default's {:.4}; the default stays: {}.</p>",
                esc(&format!("{}: {}", winner.series, winner.label)),
                winner.error(),
                default.error(),
                esc(why)
            );
        }
        let _ = write!(
            html,
            "<details><summary>Every choice ({}), and the setup</summary><p>{}</p>",
            stage.choices.len(),
            esc(&stage.setup)
        );
        let rows: Vec<Vec<String>> = stage.choices.iter().map(row).collect();
        table(html, &header, &rows);
        html.push_str("</details>\n");
    }
}

fn photo_thumbnail(out: &Path, photo: &Path, name: &str) -> Result<String> {
    let read = io::read_photo(photo, &Default::default()).context("cannot read a photo")?;
    let luminance = Grid::from_vec(read.width(), read.height(), read.luminance())?;
    save(out, &preview::shrink(&preview::gray(&luminance), THUMB_SIDE), name)
}

/// A normal map drawn as relief in `page/name`; returns its link.
fn shaded_normals(out: &Path, map: &Path, name: &str) -> Result<String> {
    let normals =
        io::read_normal_map(map, NormalEncoding::default(), &Default::default()).context("cannot read a normal map")?;
    save(out, &preview::shrink(&preview::shade_normals(&normals, preview::raking_light()), PREVIEW_SIDE), name)
}

/// The face map as relief with its regions' boundaries (where the label picture's colour
/// changes) in red: whole, shrunk to fit the page, and its centre at one texel a pixel (shrinking
/// averages the fine relief away). Boundaries are drawn after shrinking, so the lines stay one
/// pixel wide and pure. Returns both links.
fn face_preview(out: &Path, normal: &Path, labels: &Path) -> Result<(String, String)> {
    let normals = io::read_normal_map(normal, NormalEncoding::default(), &Default::default())
        .context("cannot read the face's normal map")?;
    let (w, h) = normals.size();
    let shaded = preview::shade_normals(&normals, preview::raking_light());
    let (cw, ch) = (w.min(DETAIL.0), h.min(DETAIL.1));
    let (x0, y0) = ((w - cw) / 2, (h - ch) / 2);
    let mut detail = shaded.crop(x0, y0, cw, ch)?;
    let factor = w.max(h).div_ceil(PREVIEW_SIDE).max(1);
    let mut picture = preview::shrink(&shaded, PREVIEW_SIDE);
    let read = io::read_photo(labels, &Default::default()).context("cannot read the face's label map")?;
    if (read.width(), read.height()) == (w, h) {
        let channels = read.channels().count();
        let label = |x: usize, y: usize| -> [u32; 3] {
            let i = channels * (y * w + x);
            std::array::from_fn(|c| read.samples().get(i + c.min(channels - 1)) as u32)
        };
        let (sw, sh) = picture.size();
        let labels = Grid::from_fn(sw, sh, |x, y| label((x * factor).min(w - 1), (y * factor).min(h - 1)));
        preview::outline(&mut picture, &labels, [230, 30, 30]);
        let labels = Grid::from_fn(cw, ch, |x, y| label(x0 + x, y0 + y));
        preview::outline(&mut detail, &labels, [230, 30, 30]);
    }
    Ok((save(out, &picture, "face.png")?, save(out, &detail, "face-detail.png")?))
}

pub(super) fn save(out: &Path, picture: &preview::Picture, name: &str) -> Result<String> {
    let path = out.join("page").join(name);
    preview::write_png(&path, picture).context("cannot write a picture of the demo page")?;
    Ok(rel(out, &path))
}
