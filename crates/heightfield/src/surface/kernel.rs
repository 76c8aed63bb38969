//! The compact smooth kernel shared by pores and furrows.

/// `(1 - q)^3` for `q < 1`, else 0, with its derivative in `q`. Used with `q = r^2 / R^2`, the
/// profile and its first two derivatives in `r` vanish at `r = R`, so summed features stay C2 and
/// the analytic gradient is exact everywhere.
#[inline]
pub(crate) fn bump(q: f64) -> (f64, f64) {
    if q >= 1.0 {
        return (0.0, 0.0);
    }
    let a = 1.0 - q;
    (a * a * a, -3.0 * a * a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivative_matches_differences_and_edge_is_flat() {
        for q in [0.0, 0.2, 0.5, 0.9] {
            let e = 1e-6;
            let fd = (bump(q + e).0 - bump(q - e).0) / (2.0 * e);
            assert!((bump(q).1 - fd).abs() < 1e-8, "q={q}");
        }
        assert_eq!(bump(1.0), (0.0, 0.0));
        let below = bump(1.0 - 1e-4);
        assert!(below.0 < 1e-11 && below.1.abs() < 1e-7);
    }
}
