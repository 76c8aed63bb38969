//! A table the CPU computes and the passes sample (LUTs, zonal factors), as it is uploaded.

/// An RGB float table for the GPU, with the affine map from its parameter to a texture coordinate.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Row-major RGB, row 0 at the top.
    pub texels: Vec<[f32; 3]>,
    /// `coordinate = parameter * scale + offset` for the table's second axis (v for LUTs indexed
    /// by N.L or s along u; u for the zonal table).
    pub scale: f32,
    /// See `scale`.
    pub offset: f32,
}

impl Table {
    /// The affine map putting `lo` on the centre of the first texel and `hi` on the last of `n`.
    pub(crate) fn centred_map(lo: f32, hi: f32, n: u32) -> (f32, f32) {
        if n <= 1 || hi <= lo {
            return (0.0, 0.5);
        }
        let n = n as f32;
        let scale = (n - 1.0) / (n * (hi - lo));
        (scale, 0.5 / n - lo * scale)
    }
}
