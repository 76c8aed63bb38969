//! The review page of a batch, `OUT/batch-review.html`, beside `batch-report.json`: one row per
//! session, the sessions that need a look first, so that a person finds the bad captures of a
//! batch of hundreds at a glance.
//!
//! One file of HTML and CSS (no script, nothing fetched from elsewhere). Each row shows the
//! session's previews (`batch-review/SESSION/*.png`, [`review`](crate::review); small and
//! `loading="lazy"`, so 500 rows open at once), the numbers that flag a bad capture, its time,
//! and links to its files. Rows are ordered: failed sessions, then by [`badness`] (the worst of
//! the signs, each divided by the level that deserves a look), then by name.

use std::fmt::Write as _;

use percent_encoding::{AsciiSet, NON_ALPHANUMERIC, utf8_percent_encode};

use crate::outcome::SessionOutcome;
use crate::report::BatchReport;
use crate::review::{HeightRange, PREVIEW_SIDE, PREVIEWS, Signs};

/// The page's file name, beside `batch-report.json`.
pub const PAGE: &str = "batch-review.html";

/// Share of unsolved pixels that deserves a look: the capture's own warning level.
pub const INVALID_LOOK: f64 = 0.10;
/// Share of solved pixels that lost a light that deserves a look. On the sample molds (8 lights
/// at 45 degrees) a few percent of the pixels lose a light to cast shadows; a saturated lamp
/// costs most of the map that light.
pub const DROPPED_LOOK: f64 = 0.30;
/// Median residual of the fit that deserves a look: a sample mold fits within about 1 %, a rig
/// that does not match the photos leaves tens of percent.
pub const RESIDUAL_LOOK: f64 = 0.05;

/// Characters kept as they are in a link: the unreserved ones of RFC 3986.
const LINK: &AsciiSet = &NON_ALPHANUMERIC.remove(b'-').remove(b'.').remove(b'_').remove(b'~');

/// How much a session needs a look: the largest of its signs divided by its look level (1 and
/// more deserve a look); 0 when it has no signs.
pub fn badness(signs: &Signs) -> f64 {
    let parts = [
        Some(signs.invalid_share / INVALID_LOOK),
        signs.dropped_share.map(|d| d / DROPPED_LOOK),
        signs.residual.map(|r| r / RESIDUAL_LOOK),
    ];
    parts.into_iter().flatten().filter(|v| v.is_finite()).fold(0.0, f64::max)
}

/// The outcomes in the page's order: failed first, then the worst signs, then by name.
pub fn order(outcomes: &[SessionOutcome]) -> Vec<&SessionOutcome> {
    let score = |o: &SessionOutcome| o.signs.as_ref().map_or(f64::INFINITY, badness);
    let mut rows: Vec<&SessionOutcome> = outcomes.iter().collect();
    rows.sort_by(|a, b| a.ok.cmp(&b.ok).then(score(b).total_cmp(&score(a))).then(a.session.cmp(&b.session)));
    rows
}

/// `text` with the characters HTML gives meaning to escaped.
pub fn esc(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;").replace('\'', "&#39;")
}

/// A relative link to `segments` joined with `/`, each percent-encoded (a session named `a#1`
/// or `50% gain` still links to its folder).
pub fn link(segments: &[&str]) -> String {
    let parts: Vec<String> =
        segments.iter().flat_map(|s| s.split('/')).map(|s| utf8_percent_encode(s, LINK).to_string()).collect();
    esc(&parts.join("/"))
}

/// The page of `report`, its previews in `batch-review/` beside it.
pub fn html(report: &BatchReport) -> String {
    let rows = order(&report.outcomes);
    let mut html = String::with_capacity(2048 + 1024 * rows.len());
    head(&mut html, report, &rows);
    for (i, row) in rows.iter().enumerate() {
        session_row(&mut html, i + 1, row);
    }
    html.push_str("</tbody></table></main></body></html>\n");
    html
}

const STYLE: &str = "body{font:14px system-ui,sans-serif;margin:1em;color:#222}\
table{border-collapse:collapse}th,td{padding:3px 6px;border-bottom:1px solid #ddd;text-align:left;vertical-align:middle}\
td.n{text-align:right;font-variant-numeric:tabular-nums}img{width:96px;height:96px;object-fit:contain;background:#eee;display:block}\
tr.failed{background:#fde2e2}tr.look{background:#fff4d6}td.why{max-width:28em;font-size:12px}a{color:#035}";

fn head(html: &mut String, report: &BatchReport, rows: &[&SessionOutcome]) {
    let look = rows.iter().filter(|o| o.ok && o.signs.as_ref().is_some_and(|s| badness(s) >= 1.0)).count();
    let _ = write!(
        html,
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>skinkit batch review</title>\
         <style>{STYLE}</style></head><body><main><h1>Batch review</h1><p>{} sessions: {} failed, {look} to look at \
         (a sign at or above its level: unsolved {:.0} %, lights dropped {:.0} %, fit residual {:.0} %), {} fine. \
         Failed sessions first, then the worst. Data: <a href=\"batch-report.json\">batch-report.json</a>.</p>",
        report.outcomes.len(),
        report.failed,
        100.0 * INVALID_LOOK,
        100.0 * DROPPED_LOOK,
        100.0 * RESIDUAL_LOOK,
        report.outcomes.len() - report.failed - look,
    );
    html.push_str(
        "<table><thead><tr><th>#</th><th>session</th><th>relief</th><th>albedo</th><th>confidence</th>\
         <th>height</th><th>unsolved</th><th>lights dropped</th><th>fit residual</th><th>rig condition</th><th>height range</th><th>time</th>\
         <th>status</th><th>files</th></tr></thead><tbody>",
    );
}

fn percent(value: Option<f64>) -> String {
    value.map_or_else(|| "–".to_owned(), |v| format!("{:.1} %", 100.0 * v))
}

fn session_row(html: &mut String, rank: usize, o: &SessionOutcome) {
    let badness = o.signs.as_ref().map_or(0.0, badness);
    let class = if !o.ok {
        "failed"
    } else if badness >= 1.0 {
        "look"
    } else {
        "fine"
    };
    let name = esc(&o.session);
    let _ = write!(html, "<tr class=\"{class}\" id=\"{name}\"><td class=\"n\">{rank}</td>");
    let _ = write!(html, "<td><a href=\"{}/\">{name}</a></td>", link(&[&o.session]));
    for preview in PREVIEWS {
        if o.signs.is_some() {
            let src = link(&[crate::review::FOLDER, &o.session, preview]);
            let what = preview.trim_end_matches(".png");
            let _ = write!(
                html,
                "<td><a href=\"{src}\"><img src=\"{src}\" alt=\"{what} of {name}\" loading=\"lazy\" \
                 width=\"{PREVIEW_SIDE}\" height=\"{PREVIEW_SIDE}\"></a></td>"
            );
        } else {
            html.push_str("<td></td>");
        }
    }
    let signs = o.signs.as_ref();
    for cell in [
        percent(signs.map(|s| s.invalid_share)),
        percent(signs.and_then(|s| s.dropped_share)),
        percent(signs.and_then(|s| s.residual)),
        signs.and_then(|s| s.condition_number).map_or_else(|| "–".to_owned(), |c| format!("{c:.2}")),
        signs.and_then(|s| s.height_range.as_ref()).map_or_else(|| "–".to_owned(), HeightRange::text),
        o.seconds.map_or_else(|| "–".to_owned(), |s| format!("{s:.2} s")),
    ] {
        let _ = write!(html, "<td class=\"n\">{}</td>", esc(&cell));
    }
    let status = match (&o.error, o.skipped) {
        (Some(e), _) => format!("failed: {e}"),
        (None, true) => "ok (up to date, skipped)".to_owned(),
        (None, false) if badness >= 1.0 => "look".to_owned(),
        (None, false) => "ok".to_owned(),
    };
    let _ = write!(html, "<td class=\"why\">{}</td><td>", esc(&status));
    if o.signs.is_some() {
        for file in ["normal.png", "albedo.png", "confidence.png", "height.exr", "report.json"] {
            let _ = write!(html, "<a href=\"{}\">{}</a> ", link(&[&o.session, file]), file);
        }
    }
    html.push_str("</td></tr>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outcome(name: &str, ok: bool, invalid: f64, residual: Option<f64>) -> SessionOutcome {
        SessionOutcome {
            session: name.to_owned(),
            ok,
            error: (!ok).then(|| "too few <valid> pixels".to_owned()),
            invalid_pixels: Some(0),
            seconds: Some(1.0),
            skipped: false,
            signs: Some(Signs {
                invalid_share: invalid,
                dropped_share: Some(0.01),
                residual,
                condition_number: Some(1.5),
                height_range: Some(HeightRange { span: 0.0425, unit: "mm".to_owned() }),
            }),
            skipped_files: Vec::new(),
        }
    }

    #[test]
    fn badness_is_the_worst_sign_over_its_level() {
        let signs = Signs {
            invalid_share: 0.05,
            dropped_share: Some(0.6),
            residual: Some(0.01),
            condition_number: None,
            height_range: None,
        };
        assert!((badness(&signs) - 2.0).abs() < 1e-12, "dropped 0.6 / 0.3 is the worst");
        let none = Signs {
            invalid_share: 0.0,
            dropped_share: None,
            residual: None,
            condition_number: None,
            height_range: None,
        };
        assert_eq!(badness(&none), 0.0);
    }

    #[test]
    fn failed_sessions_come_first_then_the_worst() {
        let outcomes = vec![
            outcome("a-fine", true, 0.0, Some(0.01)),
            outcome("b-wrong-rig", true, 0.0, Some(0.4)),
            outcome("c-blank", false, 1.0, None),
            outcome("d-dark-edge", true, 0.2, Some(0.01)),
            SessionOutcome {
                signs: None,
                error: Some("no rig.toml".into()),
                ok: false,
                ..outcome("e-no-rig", false, 0.0, None)
            },
        ];
        let names: Vec<&str> = order(&outcomes).iter().map(|o| o.session.as_str()).collect();
        assert_eq!(names, ["e-no-rig", "c-blank", "b-wrong-rig", "d-dark-edge", "a-fine"]);
    }

    #[test]
    fn names_are_escaped_in_text_and_encoded_in_links() {
        assert_eq!(link(&["a b#1", "relief.png"]), "a%20b%231/relief.png");
        assert_eq!(link(&["ann/brow"]), "ann/brow");
        assert_eq!(link(&["x\"&<"]), "x%22%26%3C");
        let report = BatchReport::new(
            1,
            vec![outcome("<b>&\"mold\"", false, 1.0, None)],
            false,
            &skinkit_maps::limits::MemoryGate::new(1 << 30),
            None,
            Vec::new(),
        );
        let page = html(&report);
        assert!(page.contains("&lt;b&gt;&amp;&quot;mold&quot;") && !page.contains("<b>&"), "{page}");
        assert!(page.contains("too few &lt;valid&gt; pixels"));
        assert!(page.contains("src=\"batch-review/%3Cb%3E%26%22mold%22/relief.png\""), "{page}");
        assert_eq!(page.matches("loading=\"lazy\"").count(), PREVIEWS.len());
        assert!(page.contains("42.5 µm"), "the height range in micrometres: {page}");
        assert!(!page.contains("<script") && !page.contains("http"));
        assert!(page.contains("class=\"failed\""));
    }
}
