//! Prints how long the pre-integrated tables take to build at their default 256x256 size (all
//! cores), for the book and reports: `cargo run -p skinkit-render --example lut_timing --profile test`.

use std::time::Instant;

use skinkit_render::skin::lut::{DiffuseLut, DiffuseLutSpec};
use skinkit_render::skin::profile::{Domain, Normalisation};
use skinkit_render::skin::shadow::{ShadowLut, ShadowLutSpec};

fn main() {
    for normalisation in [Normalisation::TwoD, Normalisation::OneD] {
        for domain in [Domain::Full, Domain::Half] {
            let spec = DiffuseLutSpec { normalisation, domain, ..DiffuseLutSpec::default() };
            let started = Instant::now();
            let lut = DiffuseLut::build(&spec).expect("default spec is valid");
            let seconds = started.elapsed().as_secs_f64();
            println!(
                "diffuse 256x256 {} {}: {seconds:.4} s ({} texels)",
                normalisation.name(),
                domain.name(),
                lut.texels.len()
            );
        }
    }
    let started = Instant::now();
    let lut = ShadowLut::build(&ShadowLutSpec::default()).expect("default spec is valid");
    println!("shadow 256x256: {:.4} s ({} texels)", started.elapsed().as_secs_f64(), lut.texels.len());
}
