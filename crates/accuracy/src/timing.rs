//! Wall-clock timing of a choice: the median of a few runs.

use std::time::Instant;

/// Runs `f` `runs` times (at least once) and returns its last result and the median seconds.
pub fn median_of<T>(runs: usize, mut f: impl FnMut() -> T) -> (T, f64) {
    let mut seconds = Vec::with_capacity(runs.max(1));
    let mut last = None;
    for _ in 0..runs.max(1) {
        let start = Instant::now();
        last = Some(f());
        seconds.push(start.elapsed().as_secs_f64());
    }
    (last.expect("at least one run"), median(seconds))
}

/// The median of `values` (the mean of the middle two for an even count; 0 when empty).
pub fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let m = values.len() / 2;
    if values.len() % 2 == 1 { values[m] } else { 0.5 * (values[m - 1] + values[m]) }
}

/// A duration that a plot's log axis can show: at least a nanosecond.
pub fn positive(seconds: f64) -> f64 {
    if seconds.is_finite() { seconds.max(1e-9) } else { 1e-9 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(Vec::new()), 0.0);
    }

    #[test]
    fn times_are_positive() {
        let (value, seconds) = median_of(3, || 7);
        assert_eq!(value, 7);
        assert!(positive(seconds) > 0.0);
        assert_eq!(positive(f64::NAN), 1e-9);
    }
}
