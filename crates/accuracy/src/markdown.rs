//! `accuracy.md`: how the run was made, then per stage its setup, a table of every choice (knobs,
//! metrics, seconds) and its plot.

use std::fmt::Write;

use crate::choice::{Report, StageReport};

/// The file name of a stage's plot.
pub fn plot_name(stage: &StageReport) -> String {
    format!("accuracy-{}.png", stage.stage.name())
}

/// The whole report as markdown.
pub fn render(report: &Report) -> String {
    let mode = if report.quick { "quick" } else { "full" };
    let timing = if report.runs == 1 {
        "one run per choice (quick mode: times are indicative)".to_owned()
    } else {
        format!("the median of {} runs per choice", report.runs)
    };
    let mut s = format!(
        "# Accuracy against time\n\n`skinkit accuracy` ({mode} mode), seed {}, {} worker threads, \
         {:.1} s in all. Times are wall clock, {timing}; rendering times are GPU frame times \
         (timestamps summed over the passes) over the base pass's. Every error is measured \
         against an exact or ground-truth form; the same seed gives the same numbers, times apart.\n",
        report.seed, report.threads, report.wall_seconds
    );
    for stage in &report.stages {
        s.push('\n');
        s.push_str(&stage_section(stage));
    }
    s
}

/// One stage's section: heading, setup, table and plot.
pub fn stage_section(stage: &StageReport) -> String {
    let mut s = format!("## {}\n\n", stage.stage.name());
    if let Some(reason) = &stage.skipped {
        let _ = writeln!(s, "Skipped: {reason}\n");
        return s;
    }
    let _ = writeln!(s, "{}. {:.1} s for the stage.\n", stage.setup, stage.wall_seconds);
    s.push_str(&table(stage));
    let _ = writeln!(
        s,
        "\n![{}: {} against {}]({})",
        stage.stage.name(),
        stage.error_metric,
        stage.cost_axis,
        plot_name(stage)
    );
    s
}

/// The stage's table: one row per choice.
pub fn table(stage: &StageReport) -> String {
    let Some(first) = stage.choices.first() else { return "No choices were measured.\n".into() };
    let knob_names: Vec<&str> = first.knobs.iter().map(|(k, _)| k.as_str()).collect();
    let metric_names: Vec<&str> = first.metrics.iter().map(|m| m.name.as_str()).collect();
    let cost = if stage.cost_axis == "seconds" { None } else { Some(stage.cost_axis.as_str()) };
    let mut head = vec!["choice"];
    head.extend(&knob_names);
    head.extend(&metric_names);
    head.push("seconds");
    head.extend(cost);
    let mut s = format!("| {} |\n|{}\n", head.join(" | "), " --- |".repeat(head.len()));
    for c in &stage.choices {
        let mut cells = vec![format!("{}: {}", c.series, c.label)];
        cells.extend(
            knob_names.iter().map(|k| c.knobs.iter().find(|(n, _)| n == k).map_or("-".into(), |(_, v)| v.clone())),
        );
        cells.extend(metric_names.iter().map(|m| c.metric(m).map_or("-".into(), number)));
        cells.push(number(c.seconds));
        if cost.is_some() {
            cells.push(format!("{:.2}", c.cost));
        }
        let _ = writeln!(s, "| {} |", cells.join(" | "));
    }
    s
}

/// Four significant digits, plain for everyday magnitudes.
fn number(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&a) {
        let decimals = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choice::{Choice, Stage, knobs, metrics};

    #[test]
    fn numbers_keep_four_digits() {
        assert_eq!(number(0.0), "0");
        assert_eq!(number(1.23456), "1.235");
        assert_eq!(number(0.0123456), "0.01235");
        assert_eq!(number(123.456), "123.5");
        assert_eq!(number(2e-6), "2.000e-6");
    }

    #[test]
    fn a_table_has_a_row_per_choice() {
        let mut stage = StageReport::new(Stage::Capture, "setup".into(), "err", "seconds");
        for k in [3, 8] {
            stage.choices.push(Choice::timed(
                "robust",
                &k.to_string(),
                knobs(&[("lights", k.to_string())]),
                metrics(&[("err", 1.0 / k as f64)]),
                0.01,
                1,
            ));
        }
        let t = table(&stage);
        assert_eq!(t.lines().count(), 4, "{t}");
        assert!(t.contains("| robust: 8 | 8 | 0.1250 | 0.01000 |"), "{t}");
    }
}
