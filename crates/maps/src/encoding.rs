//! How normals are stored in integer images: `[-1, 1]` mapped linearly to `[0, 255]` (Haro et al.
//! section 3) or `[0, 65535]`, with the y axis green-up (OpenGL, glTF, skinkit's default) or
//! green-down (DirectX, Unreal).
//!
//! An all-zero pixel is skinkit's marker for an invalid texel: it would decode to `(-1, -1, -1)`,
//! which is not a unit vector, so nothing valid is lost by reserving it.

use glam::Vec3;

/// Which way the green channel points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum GreenAxis {
    /// Green grows with +y (OpenGL, glTF, Blender).
    #[default]
    Up,
    /// Green grows with -y (DirectX, Unreal, 3ds Max).
    Down,
}

impl std::str::FromStr for GreenAxis {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "up" | "opengl" | "gl" => Ok(GreenAxis::Up),
            "down" | "directx" | "dx" => Ok(GreenAxis::Down),
            other => Err(format!("unknown green axis `{other}` (expected `up` or `down`)")),
        }
    }
}

/// The integer encoding of a normal map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct NormalEncoding {
    pub green: GreenAxis,
}

/// Decoded vectors shorter than this are taken as invalid texels rather than renormalised.
const MIN_DECODED_LENGTH: f32 = 0.5;

impl NormalEncoding {
    /// The y sign applied when going between memory and the file.
    fn y_sign(self) -> f32 {
        match self.green {
            GreenAxis::Up => 1.0,
            GreenAxis::Down => -1.0,
        }
    }

    /// Encodes `n` as three integers in `0..=max` (255 or 65535). Invalid texels give `[0, 0, 0]`.
    pub fn encode(self, n: Vec3, max: u32) -> [u32; 3] {
        if !is_valid_normal(n) {
            return [0; 3];
        }
        let scale = max as f32;
        let q = |c: f32| ((c.clamp(-1.0, 1.0) * 0.5 + 0.5) * scale + 0.5) as u32;
        let q = [q(n.x), q(n.y * self.y_sign()), q(n.z)];
        // A valid normal that happens to round to the invalid marker (only (-1,-1,-1)-ish ones,
        // which are not unit) cannot occur; keep the guard for safety anyway.
        if q == [0; 3] { [0, 0, 1] } else { q }
    }

    /// Decodes three integers in `0..=max` to a unit vector, or `Vec3::ZERO` for the invalid marker
    /// and for codes too far from the unit sphere to be normals.
    pub fn decode(self, c: [u32; 3], max: u32) -> Vec3 {
        if c == [0; 3] {
            return Vec3::ZERO;
        }
        let s = 2.0 / max as f32;
        let v = Vec3::new(c[0] as f32 * s - 1.0, (c[1] as f32 * s - 1.0) * self.y_sign(), c[2] as f32 * s - 1.0);
        if v.length() < MIN_DECODED_LENGTH { Vec3::ZERO } else { normalize_or_invalid(v) }
    }

    /// Maps a float triple read from a file (EXR) to memory, flipping y for green-down files.
    pub fn decode_float(self, v: [f32; 3]) -> Vec3 {
        let v = Vec3::new(v[0], v[1] * self.y_sign(), v[2]);
        // A vector already of unit length to float precision (every map skinkit writes) is kept
        // as it is: normalising it again can move its last bit, and a map read back must give the
        // same results, bit for bit, as the map in memory did (a batch's face from its captures).
        if v.is_finite() && (v.length_squared() - 1.0).abs() <= 4.0 * f32::EPSILON {
            return v;
        }
        normalize_or_invalid(v)
    }

    /// Maps a normal to the float triple stored in a file (EXR).
    pub fn encode_float(self, n: Vec3) -> [f32; 3] {
        if !is_valid_normal(n) {
            return [0.0; 3];
        }
        [n.x, n.y * self.y_sign(), n.z]
    }
}

/// Normalises `v`, or returns `Vec3::ZERO` when it is non-finite or (nearly) zero.
pub fn normalize_or_invalid(v: Vec3) -> Vec3 {
    let len = v.length();
    if len.is_finite() && len > 1e-12 { v / len } else { Vec3::ZERO }
}

/// True for a finite, non-zero vector (a texel that holds a normal).
pub fn is_valid_normal(n: Vec3) -> bool {
    n.is_finite() && n != Vec3::ZERO
}

/// sRGB electro-optical transfer: encoded `[0, 1]` to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// Linear to sRGB-encoded `[0, 1]`.
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.0031308 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_encoding_maps_axes_to_channels() {
        let e = NormalEncoding::default();
        assert_eq!(e.encode(Vec3::Z, 255), [128, 128, 255]);
        assert_eq!(e.encode(Vec3::X, 255), [255, 128, 128]);
        assert_eq!(e.encode(-Vec3::Y, 65535), [32768, 0, 32768]);
    }

    #[test]
    fn green_down_flips_y_only() {
        let up = NormalEncoding { green: GreenAxis::Up };
        let down = NormalEncoding { green: GreenAxis::Down };
        let n = Vec3::new(0.3, 0.4, 0.866).normalize();
        let cu = up.encode(n, 65535);
        let cd = down.encode(n, 65535);
        assert_eq!(cu[0], cd[0]);
        assert_eq!(cu[2], cd[2]);
        assert_eq!(cu[1] + cd[1], 65535);
        assert!((down.decode(cd, 65535) - n).length() < 1e-4);
    }

    #[test]
    fn round_trip_error_is_quantisation_bounded() {
        let e = NormalEncoding::default();
        for i in 0..500 {
            let t = i as f32 * 0.37;
            let n = Vec3::new(t.sin() * 0.7, (t * 1.3).cos() * 0.6, 0.5 + 0.5 * (t * 0.7).sin().abs()).normalize();
            let a8 = crate::normal::angle_degrees(e.decode(e.encode(n, 255), 255), n);
            let a16 = crate::normal::angle_degrees(e.decode(e.encode(n, 65535), 65535), n);
            assert!(a8 < 0.5, "8-bit error {a8}");
            assert!(a16 < 0.002, "16-bit error {a16}");
        }
    }

    #[test]
    fn invalid_marker_round_trips() {
        let e = NormalEncoding::default();
        assert_eq!(e.encode(Vec3::ZERO, 255), [0; 3]);
        assert_eq!(e.encode(Vec3::NAN, 255), [0; 3]);
        assert_eq!(e.decode([0; 3], 255), Vec3::ZERO);
        assert_eq!(e.decode_float([f32::NAN, 0.0, 1.0]), Vec3::ZERO);
    }

    #[test]
    fn srgb_round_trip() {
        for i in 0..=255 {
            let c = i as f32 / 255.0;
            assert!((linear_to_srgb(srgb_to_linear(c)) - c).abs() < 1e-5);
        }
    }
}
