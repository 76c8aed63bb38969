//! The fixed exemplar set of the synthesis suite: the sample molds' captured normal maps, the
//! heightfield presets, the texture photos (as colour and as height fields turned into normals)
//! and a made-here image of a few ink blots on plain paper. Every exemplar is 128x128.

use std::path::{Path, PathBuf};

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skinkit_capture::solve::{self, PhotoStack, SolveConfig};
use skinkit_capture::{Rig, detrend};
use skinkit_heightfield::SkinParams;
use skinkit_maps::io::{self, Limits};
use skinkit_maps::{ColorMap, Grid, NormalMap, Transfer};

/// Exemplar side.
pub const SIDE: usize = 128;
/// Detrend block of the captured maps (the paper's 50 x 50, as `skinkit capture`).
const DETREND_BLOCK: usize = 50;
/// Height of a photo's luminance 0 to 1 in texels, for its normal map (a step from black to white
/// across one texel is a slope of this).
const PHOTO_RELIEF: f32 = 4.0;

/// What an exemplar holds.
#[derive(Clone)]
pub enum Texels {
    Normal(NormalMap),
    Color(ColorMap),
}

impl Texels {
    pub fn grid(&self) -> &Grid<Vec3> {
        match self {
            Texels::Normal(n) => n.grid(),
            Texels::Color(c) => c,
        }
    }
}

/// One exemplar of the suite.
#[derive(Clone)]
pub struct Exemplar {
    pub name: String,
    pub texels: Texels,
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The texture photos' folder (`brick-128.png`, `grass-128.png`, `gravel-128.png`; CC0 photos kept
/// out of the repository), named by `SYNTH_SUITE_TEXTURES`.
fn textures() -> Option<PathBuf> {
    let dir = PathBuf::from(std::env::var_os("SYNTH_SUITE_TEXTURES")?);
    dir.is_dir().then_some(dir)
}

/// A heightfield preset's constructor (width, height, seed).
type Preset = fn(usize, usize, u64) -> SkinParams;

/// Every exemplar of the suite (photos only when their folder exists; the report says so).
pub fn all() -> Vec<Exemplar> {
    let mut set = Vec::new();
    for region in ["forehead", "nose", "cheek", "forehead-edge"] {
        set.push(Exemplar { name: format!("captured {region}"), texels: Texels::Normal(captured(region)) });
    }
    let presets: [(&str, Preset); 4] = [
        ("forehead", SkinParams::forehead),
        ("nose", SkinParams::nose),
        ("cheek", SkinParams::cheek),
        ("forehead edge", SkinParams::forehead_edge),
    ];
    for (name, preset) in presets {
        let normals = preset(SIDE, SIDE, 1).generate().expect("preset generates").normals;
        set.push(Exemplar { name: format!("heightfield {name}"), texels: Texels::Normal(normals) });
    }
    match textures() {
        Some(dir) => {
            for name in ["brick", "grass", "gravel"] {
                let color = read_srgb(&dir.join(format!("{name}-128.png")));
                let normals = luminance_normals(&color);
                set.push(Exemplar { name: format!("{name} photo, colour"), texels: Texels::Color(color) });
                set.push(Exemplar { name: format!("{name} photo as height"), texels: Texels::Normal(normals) });
            }
        }
        None => eprintln!("suite: SYNTH_SUITE_TEXTURES names no folder; the photo exemplars are skipped"),
    }
    set.push(Exemplar { name: "ink blots on paper".into(), texels: Texels::Color(ink_blots(SIDE, 7)) });
    set
}

/// A sample mold's captured normals (distant-light solve, then the 50 x 50 detrend), its top-left
/// 128x128 corner.
fn captured(region: &str) -> NormalMap {
    let dir = repo().join("samples/molds").join(region);
    let rig = Rig::load(&dir.join("rig.toml")).expect("sample rig loads");
    let names: Vec<String> = (1..=8).map(|i| format!("{i:02}.png")).collect();
    let photos = names
        .iter()
        .map(|n| {
            io::read_photo(&dir.join(n), &Limits::default()).expect("sample photo").with_transfer(Transfer::Linear)
        })
        .collect();
    let stack = PhotoStack::new(photos, names).expect("sample stack");
    let mut solution = solve::solve(&stack, &rig, &SolveConfig::default(), &solve::NoProgress).expect("solves");
    detrend::detrend(&mut solution.normals, DETREND_BLOCK);
    let n = &solution.normals;
    NormalMap::from_unit_grid(Grid::from_fn(SIDE, SIDE, |x, y| n.get(x, y))).expect("unit or zero")
}

/// An 8-bit image's RGB as `[0, 1]` sRGB codes (what the peer sees).
fn read_srgb(path: &Path) -> ColorMap {
    let image = texture_synthesis::image::open(path).expect("texture photo decodes").to_rgb8();
    let (w, h) = image.dimensions();
    Grid::from_fn(w as usize, h as usize, |x, y| {
        let p = image.get_pixel(x as u32, y as u32).0;
        Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) / 255.0
    })
}

/// The normals of a height field `PHOTO_RELIEF * luminance` (central differences, clamped edges).
pub fn luminance_normals(color: &ColorMap) -> NormalMap {
    let (w, h) = color.size();
    let height = |x: isize, y: isize| {
        let c = *color.get(x.clamp(0, w as isize - 1) as usize, y.clamp(0, h as isize - 1) as usize);
        PHOTO_RELIEF * c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
    };
    let grid = Grid::from_fn(w, h, |x, y| {
        let (x, y) = (x as isize, y as isize);
        // Rows run down the image; the map's y is up, so dh/dy changes sign.
        let sx = 0.5 * (height(x + 1, y) - height(x - 1, y));
        let sy = -0.5 * (height(x, y + 1) - height(x, y - 1));
        Vec3::new(-sx, -sy, 1.0).normalize()
    });
    NormalMap::from_unit_grid(grid).expect("unit normals")
}

/// A few dark blots on plain paper: most of the image is one near-constant colour, the case where
/// a synthesis that regresses to the most common window returns a blank map.
pub fn ink_blots(side: usize, seed: u64) -> ColorMap {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let paper = Vec3::new(0.93, 0.91, 0.86);
    let ink = Vec3::new(0.08, 0.10, 0.22);
    // Each blot: a few overlapping discs around a centre.
    let blots: Vec<Vec<(f32, f32, f32)>> = (0..6)
        .map(|_| {
            let (cx, cy) = (rng.random_range(0.0..side as f32), rng.random_range(0.0..side as f32));
            (0..4)
                .map(|_| {
                    let r = rng.random_range(2.0..7.0f32);
                    (cx + rng.random_range(-6.0..6.0f32), cy + rng.random_range(-6.0..6.0f32), r)
                })
                .collect()
        })
        .collect();
    let grain: Vec<f32> = (0..side * side).map(|_| rng.random_range(-0.015..0.015f32)).collect();
    Grid::from_fn(side, side, |x, y| {
        let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
        let inside = blots
            .iter()
            .flatten()
            .map(|&(cx, cy, r)| (r - ((px - cx).powi(2) + (py - cy).powi(2)).sqrt()).clamp(0.0, 1.0))
            .fold(0.0f32, f32::max);
        paper.lerp(ink, inside) + Vec3::splat(grain[y * side + x])
    })
}
