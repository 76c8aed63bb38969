//! Comparing a height map with the exact heights it should have (synthetic heightfields): the
//! error measure of the accuracy stage and the tests.

use skinkit_maps::{Grid, NormalMap, ScalarMap, Vec3};

/// The normals of a height map (the round trip of integration): central differences, one-sided
/// at the borders of a map that does not wrap; `texel` is the texel's size in the heights' unit.
pub fn normals_of(heights: &ScalarMap, texel: f32, wraps: bool) -> NormalMap {
    let (w, h) = heights.size();
    let at = |x: isize, y: isize| {
        if wraps { *heights.get_wrapped(x, y) } else { *heights.get_clamped(x, y) }
    };
    let grid = Grid::from_fn(w, h, |x, y| {
        let (x, y) = (x as isize, y as isize);
        // Texels between the two samples: 2 inside, 1 at a clamped border.
        let span =
            |lo: isize, hi: isize, n: usize| if wraps { 2.0 } else { (hi.min(n as isize - 1) - lo.max(0)) as f32 };
        let dx = (at(x + 1, y) - at(x - 1, y)) / (span(x - 1, x + 1, w).max(1.0) * texel);
        let drow = (at(x, y + 1) - at(x, y - 1)) / (span(y - 1, y + 1, h).max(1.0) * texel);
        Vec3::new(-dx, drow, 1.0).normalize()
    });
    NormalMap::from_grid(grid)
}

/// RMS of `ours - exact` over the valid texels after removing the mean (and the best plane with
/// `plane`), as a share of the exact heights' RMS after the same removal.
pub fn error_share(ours: &ScalarMap, exact: &ScalarMap, valid: Option<&[bool]>, plane: bool) -> f64 {
    let w = ours.width();
    let pick: Vec<usize> = (0..ours.len()).filter(|&i| valid.is_none_or(|v| v[i])).collect();
    let xy = |i: usize| ((i % w) as f64, (i / w) as f64);
    let detrend = |v: &dyn Fn(usize) -> f64| -> Vec<f64> {
        let fit = fit_plane(&pick, &xy, v, plane);
        pick.iter().map(|&i| v(i) - fit(i)).collect()
    };
    let diff = detrend(&|i| (ours.as_slice()[i] - exact.as_slice()[i]) as f64);
    let base = detrend(&|i| exact.as_slice()[i] as f64);
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    rms(&diff) / rms(&base)
}

/// The least-squares plane (or constant) through `v` over `pick`, as a function of the texel.
fn fit_plane<'a>(
    pick: &[usize],
    xy: &'a dyn Fn(usize) -> (f64, f64),
    v: &dyn Fn(usize) -> f64,
    plane: bool,
) -> Box<dyn Fn(usize) -> f64 + 'a> {
    let n = pick.len() as f64;
    let mean = |f: &dyn Fn(usize) -> f64| pick.iter().map(|&i| f(i)).sum::<f64>() / n;
    let (mx, my, mv) = (mean(&|i| xy(i).0), mean(&|i| xy(i).1), mean(v));
    if !plane {
        return Box::new(move |_| mv);
    }
    let s = |f: &dyn Fn(usize) -> f64| pick.iter().map(|&i| f(i)).sum::<f64>();
    let sxx = s(&|i| (xy(i).0 - mx).powi(2));
    let syy = s(&|i| (xy(i).1 - my).powi(2));
    let sxy = s(&|i| (xy(i).0 - mx) * (xy(i).1 - my));
    let sxv = s(&|i| (xy(i).0 - mx) * (v(i) - mv));
    let syv = s(&|i| (xy(i).1 - my) * (v(i) - mv));
    let det = sxx * syy - sxy * sxy;
    let a = (sxv * syy - syv * sxy) / det;
    let b = (syv * sxx - sxv * sxy) / det;
    Box::new(move |i| mv + a * (xy(i).0 - mx) + b * (xy(i).1 - my))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A map that differs from the truth by a plane scores 0 with `plane` and not without; one
    /// that differs by noise of a tenth of the truth's RMS scores about 0.1.
    #[test]
    fn planes_and_means_are_removed_as_asked() {
        let truth = Grid::from_fn(20, 10, |x, y| ((x * 7 + y * 3) % 5) as f32 - 2.0);
        let tilted = Grid::from_fn(20, 10, |x, y| truth.get(x, y) + 0.3 * x as f32 - 0.2 * y as f32 + 4.0);
        assert!(error_share(&tilted, &truth, None, true) < 1e-5);
        assert!(error_share(&tilted, &truth, None, false) > 0.5);
        let rms = (truth.as_slice().iter().map(|v| (v * v) as f64).sum::<f64>() / 200.0).sqrt() as f32;
        let noisy =
            Grid::from_fn(20, 10, |x, y| truth.get(x, y) + if (x + y) % 2 == 0 { 0.1 * rms } else { -0.1 * rms });
        let e = error_share(&noisy, &truth, None, false);
        assert!((e - 0.1).abs() < 0.01, "{e}");
        let valid: Vec<bool> = (0..200).map(|i| i % 3 != 0).collect();
        assert!(error_share(&tilted, &truth, Some(&valid), true) < 1e-5);
    }

    /// A plane's normals come back exact, with the signs of skinkit's frame (rows grow downward,
    /// y up), inside and at the borders.
    #[test]
    fn normals_of_a_plane() {
        let plane = Grid::from_fn(6, 5, |x, y| 0.5 * x as f32 - 0.25 * y as f32);
        let expected = Vec3::new(-0.5, -0.25, 1.0).normalize();
        for n in normals_of(&plane, 1.0, false).as_slice() {
            assert!((*n - expected).length() < 1e-6, "{n} against {expected}");
        }
    }
}
