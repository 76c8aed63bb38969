//! Times generation of a 4096x4096 field and rendering of 8 lights at 1024x1024 with shadows, and
//! writes a few 8-bit previews to the directory given as the first argument (if any).
//!
//! `cargo run --release -p skinkit-heightfield --example timing -- /tmp/previews`

use std::path::PathBuf;
use std::time::Instant;

use glam::Vec3;
use skinkit_heightfield::SkinParams;
use skinkit_heightfield::render::{RenderConfig, RenderLight, Specular, render};
use skinkit_maps::io::{PngLayout, write_png};
use skinkit_maps::{Channels, Photo, Samples};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).map(PathBuf::from);
    let threads = rayon::current_num_threads();

    let start = Instant::now();
    let big = SkinParams::cheek(4096, 4096, 1).generate()?;
    println!("generate cheek 4096x4096: {:.2} s ({threads} threads)", start.elapsed().as_secs_f64());
    drop(big);

    let start = Instant::now();
    let big = SkinParams::nose(4096, 4096, 1).generate()?;
    println!("generate nose 4096x4096: {:.2} s", start.elapsed().as_secs_f64());
    drop(big);

    let lights = RenderLight::ring(8, 45.0, Vec3::ONE);
    let config = RenderConfig {
        shadows: true,
        specular: Some(Specular { strength: 0.05, shininess: 30.0 }),
        noise_sigma: 0.005,
        format: skinkit_heightfield::render::Quantise::U16,
        seed: 3,
        ..RenderConfig::default()
    };
    for (name, params) in [
        ("forehead", SkinParams::forehead(1024, 1024, 2)),
        ("forehead_edge", SkinParams::forehead_edge(1024, 1024, 2)),
        ("nose", SkinParams::nose(1024, 1024, 2)),
        ("cheek", SkinParams::cheek(1024, 1024, 2)),
    ] {
        let field = params.generate()?;
        let start = Instant::now();
        let photos = render(&field, &lights, &config)?;
        println!("render {name} 8 lights 1024x1024 with shadows: {:.2} s", start.elapsed().as_secs_f64());
        if let Some(dir) = &out {
            std::fs::create_dir_all(dir)?;
            write_preview(&dir.join(format!("{name}_light0.png")), &photos[0])?;
            write_preview(&dir.join(format!("{name}_light2.png")), &photos[2])?;
        }
    }
    Ok(())
}

/// An 8-bit grey PNG of a 16-bit grey photo.
fn write_preview(path: &std::path::Path, photo: &Photo) -> Result<(), Box<dyn std::error::Error>> {
    let Samples::U16(v) = photo.samples() else { return Err("expected 16-bit samples".into()) };
    assert_eq!(photo.channels(), Channels::Gray);
    let bytes: Vec<u16> = v.iter().map(|&s| s >> 8).collect();
    write_png(path, photo.width(), photo.height(), PngLayout::Gray8, &bytes)?;
    Ok(())
}
