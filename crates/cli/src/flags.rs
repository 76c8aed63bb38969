//! Value parsers for flags whose range is known before the run, so every bad flag value is a
//! usage error (clap prints it with the flag's name and exits 2) rather than a failed run
//! (exit 1) found after parsing. The ranges are the libraries' own (`SynthConfig::validate`,
//! `spline::MAX_LEVELS`, `skinkit_maps::limits`), named here, not copied.

use skinkit_maps::limits;

/// A parser of integers in `lo..=hi`.
pub fn usize_in(lo: usize, hi: usize) -> impl Fn(&str) -> Result<usize, String> + Clone + Send + Sync + 'static {
    move |text: &str| match text.trim().parse::<usize>() {
        Ok(n) if (lo..=hi).contains(&n) => Ok(n),
        _ if hi == usize::MAX => Err(format!("`{text}` is not a whole number of at least {lo}")),
        _ => Err(format!("`{text}` is not a whole number from {lo} to {hi}")),
    }
}

/// A parser of odd integers in `lo..=hi` (window sides).
pub fn odd_in(lo: usize, hi: usize) -> impl Fn(&str) -> Result<usize, String> + Clone + Send + Sync + 'static {
    move |text: &str| match text.trim().parse::<usize>() {
        Ok(n) if (lo..=hi).contains(&n) && n % 2 == 1 => Ok(n),
        _ => Err(format!("`{text}` is not an odd number from {lo} to {hi}")),
    }
}

/// A parser of finite numbers in `lo..=hi` (`what` says what they are in the message), for f32
/// and f64 flags alike.
pub fn number_in<T>(
    lo: T,
    hi: T,
    what: &'static str,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: std::str::FromStr + Into<f64> + PartialOrd + Copy + std::fmt::Display + Send + Sync + 'static,
{
    move |text: &str| match text.trim().parse::<T>() {
        Ok(v) if v.into().is_finite() && (lo..=hi).contains(&v) => Ok(v),
        _ => Err(format!("`{text}` is not {what} from {lo} to {hi}")),
    }
}

/// A share in `(0, 1]`: a fraction of something that must keep part of it.
pub fn share(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(v) if v > 0.0 && v <= 1.0 => Ok(v),
        _ => Err(format!("`{text}` is not a share above 0 and at most 1")),
    }
}

/// A physical texel or pixel size in millimetres: above 0, at most a metre.
pub fn positive_mm(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1e3 => Ok(v),
        _ => Err(format!("`{text}` is not a size in millimetres (above 0, at most 1000)")),
    }
}

/// A shadow table's penumbra width in millimetres: from 0 to
/// [`skinkit_render::skin::shadow::MAX_PENUMBRA_MM`] (issue 42, D14).
pub fn penumbra_mm(text: &str) -> Result<f32, String> {
    let max = skinkit_render::skin::shadow::MAX_PENUMBRA_MM;
    match text.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && (0.0..=max).contains(&v) => Ok(v),
        _ => Err(format!("`{text}` is not a penumbra width in millimetres (0 to {max})")),
    }
}

/// A face map size `WxH` of at most [`limits::MAX_MAP_TEXELS`] texels.
/// `WIDTHxHEIGHT` with positive integers (`x` or `X`).
pub fn parse_size(text: &str) -> Result<(usize, usize), String> {
    let bad = || format!("`{text}` is not a size: expected WIDTHxHEIGHT with positive integers, e.g. 512x512");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let side = |s: &str| s.trim().parse::<usize>().ok().filter(|&v| v > 0);
    match (side(w), side(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(bad()),
    }
}

pub fn map_size(text: &str) -> Result<(usize, usize), String> {
    size_within(text, limits::MAX_MAP_TEXELS, "a face map may be", "texels, 32768x32768")
}

/// An image size `WxH` of at most [`limits::MAX_IMAGE_PIXELS`] pixels (a grown map, a render).
pub fn image_size(text: &str) -> Result<(usize, usize), String> {
    size_within(text, limits::MAX_IMAGE_PIXELS, "an image may be", "pixels, 16384x16384")
}

/// A `WxH` size whose area is at most `max` (no overflow), else a message naming `what` and `unit`.
fn size_within(text: &str, max: u64, what: &str, unit: &str) -> Result<(usize, usize), String> {
    let (w, h) = parse_size(text)?;
    match (w as u64).checked_mul(h as u64) {
        Some(n) if n <= max => Ok((w, h)),
        _ => Err(format!("`{text}` is larger than {what} ({max} {unit})")),
    }
}

/// A parser of square sides `n` from `lo` with `n * n` at most `max_texels`.
pub fn square_side(
    lo: usize,
    max_texels: u64,
) -> impl Fn(&str) -> Result<usize, String> + Clone + Send + Sync + 'static {
    move |text: &str| match text.trim().parse::<usize>() {
        Ok(n) if n >= lo && (n as u64).checked_mul(n as u64).is_some_and(|t| t <= max_texels) => Ok(n),
        _ => Err(format!("`{text}` is not a side from {lo} whose square is at most {max_texels} texels")),
    }
}

/// A parser of `WxH` sizes of at most `max` per side.
pub fn size_at_most(max: usize) -> impl Fn(&str) -> Result<(usize, usize), String> + Clone + Send + Sync + 'static {
    move |text: &str| {
        let (w, h) = parse_size(text)?;
        if w > max || h > max {
            return Err(format!("`{text}` is larger than {max}x{max}"));
        }
        Ok((w, h))
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn sizes_parse_and_bad_ones_explain_the_format() {
        assert_eq!(parse_size("512x256"), Ok((512, 256)));
        assert_eq!(parse_size("7X3"), Ok((7, 3)));
        for bad in ["512", "0x4", "ax4", "4x", "-1x3", "4x4x4"] {
            let e = parse_size(bad).unwrap_err();
            assert!(e.contains(bad) && e.contains("WIDTHxHEIGHT"), "{bad}: {e}");
        }
    }

    use super::*;

    #[test]
    fn ranges_accept_their_ends_and_refuse_beyond() {
        let p = usize_in(1, 64);
        assert_eq!((p("1"), p("64")), (Ok(1), Ok(64)));
        for bad in ["0", "65", "-1", "x", ""] {
            assert!(p(bad).unwrap_err().contains("from 1 to 64"), "{bad}");
        }
        assert!(usize_in(1, usize::MAX)("0").unwrap_err().contains("at least 1"));
        let o = odd_in(3, 31);
        assert_eq!((o("3"), o("31")), (Ok(3), Ok(31)));
        assert!(o("4").is_err() && o("1").is_err() && o("33").is_err());
        let w = number_in::<f32>(0.0, 10.0, "a weight");
        assert!(w("-0.5").is_err() && w("NaN").is_err() && w("inf").is_err() && w("10.5").is_err());
        assert_eq!((w("0"), w("10")), (Ok(0.0), Ok(10.0)));
        assert!(number_in::<f64>(0.0, 1.0, "x")("1e30").unwrap_err().contains("from 0 to 1"));
        assert!(share("0").is_err() && share("1.01").is_err() && share("nan").is_err());
        assert_eq!(share("1"), Ok(1.0));
        assert_eq!(map_size("32768x32768"), Ok((32768, 32768)));
        assert!(map_size("32768x32769").unwrap_err().contains("larger than a face map"));
        assert!(map_size("18446744073709551615x3").is_err(), "no overflow");
        assert_eq!(image_size("16384x16384"), Ok((16384, 16384)));
        assert!(image_size("16385x16384").unwrap_err().contains("larger than an image"));
        let side = square_side(8, 100);
        assert_eq!((side("8"), side("10")), (Ok(8), Ok(10)));
        assert!(side("7").is_err() && side("11").is_err() && side("18446744073709551615").is_err());
        let lut = size_at_most(4096);
        assert_eq!(lut("4096x1"), Ok((4096, 1)));
        assert!(lut("4097x1").unwrap_err().contains("larger than 4096x4096") && lut("0x3").is_err());
    }
}

/// `--green`: the green channel convention of normal maps read and written (`down` for DirectX
/// and Unreal bakes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Green {
    #[default]
    Up,
    Down,
}

impl Green {
    pub fn encoding(self) -> skinkit_maps::NormalEncoding {
        let green = match self {
            Green::Up => skinkit_maps::GreenAxis::Up,
            Green::Down => skinkit_maps::GreenAxis::Down,
        };
        skinkit_maps::NormalEncoding { green }
    }
}

/// `--transfer`: how 8- and 16-bit values relate to light.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum TransferArg {
    #[default]
    Linear,
    Srgb,
}

impl From<TransferArg> for skinkit_maps::Transfer {
    fn from(t: TransferArg) -> Self {
        match t {
            TransferArg::Linear => skinkit_maps::Transfer::Linear,
            TransferArg::Srgb => skinkit_maps::Transfer::Srgb,
        }
    }
}

/// `--raw`: how camera RAW photos become RGB.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum RawArg {
    /// Each 2x2 Bayer cell binned into one pixel (no interpolation).
    #[default]
    Half,
    /// Demosaiced to the sensor's size.
    Full,
}

impl From<RawArg> for skinkit_maps::raw::RawMode {
    fn from(r: RawArg) -> Self {
        match r {
            RawArg::Half => skinkit_maps::raw::RawMode::Half,
            RawArg::Full => skinkit_maps::raw::RawMode::Full,
        }
    }
}

/// `--kind`: what a map holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum MapKind {
    /// Unit normals.
    #[default]
    Normal,
    /// Linear colour.
    Color,
}

impl MapKind {
    /// `normal` or `color`, as reports name it.
    pub fn name(self) -> &'static str {
        match self {
            MapKind::Normal => "normal",
            MapKind::Color => "color",
        }
    }
}
