//! The sensor: additive Gaussian noise from per-row ChaCha8 streams, clipping at full scale and
//! quantisation.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use skinkit_maps::Samples;

use super::{Quantise, RenderConfig};

pub(super) struct Sensor {
    seed: u64,
    stream: u32,
    sigma: f32,
    format: Quantise,
}

impl Sensor {
    /// The sensor for one photo; `stream` is the light index keying its noise.
    pub(super) fn new(config: &RenderConfig, stream: u32) -> Self {
        Sensor { seed: config.seed, stream, sigma: config.noise_sigma, format: config.format }
    }

    /// Adds noise to one row of interleaved samples, in sample order, from the stream of
    /// `(seed, light, row)`.
    pub(super) fn add_noise(&self, row: usize, samples: &mut [f32]) {
        if self.sigma == 0.0 {
            return;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream((u64::from(self.stream) << 32) | (row as u64 & 0xffff_ffff));
        let normal = Normal::new(0.0f32, self.sigma).expect("sigma is finite and non-negative");
        for v in samples {
            *v += normal.sample(&mut rng);
        }
    }

    /// Clips to `[0, 1]` and stores in the configured sample type (rounding to the nearest code).
    pub(super) fn quantise(&self, values: Vec<f32>) -> Samples {
        match self.format {
            Quantise::Float => Samples::F32(values.into_par_iter().map(clip).collect()),
            Quantise::U8 => Samples::U8(values.into_par_iter().map(|v| (clip(v) * 255.0).round() as u8).collect()),
            Quantise::U16 => Samples::U16(values.into_par_iter().map(|v| (clip(v) * 65535.0).round() as u16).collect()),
        }
    }
}

/// Saturation at full scale; NaN (impossible from validated inputs) would become 0.
#[inline]
fn clip(v: f32) -> f32 {
    if v > 0.0 { v.min(1.0) } else { 0.0 }
}
