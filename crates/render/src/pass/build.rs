//! From a scene's pass graph ([`super::graph::PassGraph`]) to what the GPU draws with
//! ([`super::setup::SkinSetup`]): per-vertex curvature and UV stretch, the diffuse, shadow and
//! zonal tables (built on the CPU, cached in-process by their parameters, so a turntable builds
//! each once), the environment's SH coefficients, the key light's shadow projection and the
//! texture-space diffusion settings. Only what the graph asks for is computed.

use std::collections::HashMap;
use std::path::Path;
use std::sync::{Arc, Mutex, OnceLock};

use glam::Vec3;
use skinkit_maps::io::{self, Limits};

use super::geometry;
use super::graph::{PassGraph, TsdPlan};
use super::setup::{self, ShadowSetup, SkinSetup, TranslucentCaster, TsdSetup};
use crate::gpu::Table;
use crate::load::{LoadError, Loaded};
use crate::scene::Scene;
use crate::shading::Texture;
use crate::skin::lut::{DiffuseLut, DiffuseLutSpec};
use crate::skin::options::{Sky, TsdKernel, Zonal};
use crate::skin::profile::{VARIANCES_MM2, WEIGHTS};
use crate::skin::sh::{self, Sh9, ZonalTable};
use crate::skin::shadow::{ShadowLut, ShadowLutSpec};

/// 1/r range of the diffuse LUT and the zonal table, 1/mm (r >= 1 mm: ears and nostrils).
pub(crate) const INV_R_RANGE: (f32, f32) = (0.0, 1.0);

use crate::skin::sh::ZONAL_SAMPLES;
use crate::skin::shadow::SHADOW_LUT_SIDE;

/// The luminance weights the TSD kernel is matched with (Gosselin et al.'s specular luminance).
const LUMINANCE: [f64; 3] = [0.2125, 0.7154, 0.0721];

/// Builds the skin setup of `scene` for its `graph`.
///
/// # Errors
/// An unreadable environment or kernel map (the error names the field and file), or a table
/// whose parameters are refused.
pub fn setup(scene: &Scene, loaded: &Loaded, graph: &PassGraph) -> Result<SkinSetup, LoadError> {
    let scene_file = scene.file.as_path();
    let inputs = &loaded.inputs;
    let pre = &scene.skin.preintegrated;
    let mut setup = SkinSetup {
        features: graph.features,
        curvature_scale: pre.curvature_scale,
        mm_per_unit: scene.mm_per_unit,
        normal_blur: pre.normal_blur,
        blur_mip: pre.blur_mip,
        effects: scene.effects.clone(),
        ..SkinSetup::default()
    };
    if graph.vertex_curvature {
        setup.vertex_skin = vertex_skin(inputs, scene.mm_per_unit);
    }
    if graph.diffuse_lut {
        let spec = DiffuseLutSpec {
            width: pre.lut_size[0],
            height: pre.lut_size[1],
            normalisation: pre.normalisation,
            domain: pre.domain,
            inv_r_min: INV_R_RANGE.0,
            inv_r_max: INV_R_RANGE.1,
        };
        setup.diffuse_lut = Some(diffuse_table(&spec).map_err(|reason| refused(scene_file, "preintegrated", reason))?);
    }
    if graph.zonal_table {
        let zonal = scene.skin.environment.as_ref().map_or(Zonal::Exact, |e| e.zonal);
        setup.zonal = Some(zonal_table(zonal));
    }
    if let Some(env) = &scene.skin.environment
        && graph.features.sh_ambient
    {
        setup.sh = environment_sh(&env.sky, env.intensity, scene_file)?;
    }
    if let Some(plan) = graph.shadow {
        let options = &scene.skin.shadow;
        let (centre, radius) = geometry::bounding_sphere(&inputs.vertices);
        let (view_proj, texel) = geometry::light_view_proj(&inputs.lights[plan.light], centre, radius, plan.size);
        setup.shadow = Some(ShadowSetup {
            light: plan.light,
            map_size: plan.size,
            filter: plan.filter,
            bias: options.bias,
            disc_radius: match graph.features.shadow_scattering {
                true => 0.5 * options.scatter_width_mm / scene.mm_per_unit,
                false => 0.0,
            },
            view_proj,
            texel,
            new_penumbra: options.new_penumbra,
            translucent: translucent_casters(scene, graph)?,
        });
    }
    if graph.shadow_lut {
        let spec = ShadowLutSpec {
            width: SHADOW_LUT_SIDE,
            height: SHADOW_LUT_SIDE,
            new_penumbra: scene.skin.shadow.new_penumbra,
            ..ShadowLutSpec::default()
        };
        setup.shadow_lut = Some(shadow_table(&spec).map_err(|reason| refused(scene_file, "shadow", reason))?);
    }
    if let Some(plan) = graph.tsd {
        setup.tsd = Some(tsd_setup(scene, plan)?);
    }
    Ok(setup)
}

/// The scene's translucent casters, loaded (only when the graph draws translucent shadows).
fn translucent_casters(scene: &Scene, graph: &PassGraph) -> Result<Vec<TranslucentCaster>, LoadError> {
    if !graph.features.translucent_shadows {
        return Ok(Vec::new());
    }
    scene
        .translucent
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let mesh = crate::mesh::Mesh::load(&t.mesh)
                .map_err(|error| LoadError::Mesh {
                    file: scene.name(),
                    field: format!("translucent[{i}].mesh"),
                    error,
                })?
                .mesh;
            Ok(TranslucentCaster {
                positions: mesh.positions.iter().map(|p| p.to_array()).collect(),
                indices: mesh.indices,
                opacity: t.opacity.to_array(),
            })
        })
        .collect()
}

fn refused(scene_file: &Path, field: &str, reason: String) -> LoadError {
    LoadError::Unsupported { file: scene_file.display().to_string(), field: field.into(), reason }
}

/// Per vertex: |mean curvature| in 1/mm (one smoothing pass) and mm per UV unit.
pub fn vertex_skin(inputs: &crate::shading::RenderInputs, mm_per_unit: f32) -> Vec<[f32; 2]> {
    let positions: Vec<Vec3> = inputs.vertices.iter().map(|v| Vec3::from(v.position)).collect();
    let curvature = crate::skin::curvature::vertex_curvature_smoothed(&positions, &inputs.indices, mm_per_unit, 1);
    let stretch = geometry::uv_stretch(&inputs.vertices, &inputs.indices, mm_per_unit);
    curvature.iter().zip(&stretch).map(|(&k, &s)| [k, s]).collect()
}

type Cache<T> = Mutex<HashMap<String, Arc<T>>>;

fn cached<T>(
    cache: &'static OnceLock<Cache<T>>,
    key: String,
    build: impl FnOnce() -> Result<T, String>,
) -> Result<Arc<T>, String> {
    let map = cache.get_or_init(|| Mutex::new(HashMap::new()));
    if let Some(hit) = map.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return Ok(hit.clone());
    }
    let built = Arc::new(build()?);
    map.lock().unwrap_or_else(|e| e.into_inner()).insert(key, built.clone());
    Ok(built)
}

/// The diffuse LUT of `spec` (built once per parameter set in this process) as a GPU table.
///
/// # Errors
/// The spec's refusal, as text.
pub fn diffuse_table(spec: &DiffuseLutSpec) -> Result<Table, String> {
    static CACHE: OnceLock<Cache<DiffuseLut>> = OnceLock::new();
    let lut = cached(&CACHE, spec.cache_key(), || DiffuseLut::build(spec).map_err(|e| e.to_string()))?;
    let (scale, offset) = Table::centred_map(spec.inv_r_min, spec.inv_r_max, spec.height);
    Ok(Table { width: spec.width, height: spec.height, texels: lut.texels.clone(), scale, offset })
}

/// The shadow-scattering LUT of `spec` (cached) as a GPU table.
///
/// # Errors
/// The spec's refusal, as text.
pub(crate) fn shadow_table(spec: &ShadowLutSpec) -> Result<Table, String> {
    static CACHE: OnceLock<Cache<ShadowLut>> = OnceLock::new();
    let lut = cached(&CACHE, spec.cache_key(), || ShadowLut::build(spec).map_err(|e| e.to_string()))?;
    let (scale, offset) = Table::centred_map(spec.w_min_mm, spec.w_max_mm, spec.height);
    Ok(Table { width: spec.width, height: spec.height, texels: lut.texels.clone(), scale, offset })
}

/// The skin's zonal factors over [`INV_R_RANGE`] (exact projection, cached, or the blog's).
pub(crate) fn zonal_table(zonal: Zonal) -> Table {
    static CACHE: OnceLock<Cache<ZonalTable>> = OnceLock::new();
    let (lo, hi) = INV_R_RANGE;
    let n = ZONAL_SAMPLES;
    let rows: Vec<[[f32; 3]; 3]> = match zonal {
        Zonal::Exact => {
            let table =
                cached(&CACHE, format!("{lo}-{hi}-{n}"), || ZonalTable::build(lo, hi, n).map_err(|e| e.to_string()))
                    .expect("the zonal table's fixed range is valid");
            table.rows.clone()
        }
        Zonal::Blog => (0..n).map(|i| sh::blog_zonal(lo + (hi - lo) * i as f32 / (n - 1) as f32)).collect(),
    };
    let texels = (0..3).flat_map(|l| rows.iter().map(move |row| row[l])).collect();
    let (scale, offset) = Table::centred_map(lo, hi, n as u32);
    Table { width: n as u32, height: 3, texels, scale, offset }
}

/// The environment's radiance SH, scaled by `intensity`.
fn environment_sh(sky: &Sky, intensity: f32, scene_file: &Path) -> Result<[[f32; 3]; 9], LoadError> {
    let scale = |c: Vec3| (c * intensity).to_array();
    let sh = match sky {
        Sky::Constant(c) => Sh9::constant(scale(*c)),
        Sky::Gradient { sky, ground } => Sh9::gradient(scale(*sky), scale(*ground), Vec3::Y),
        Sky::LatLong(path) => {
            let texture = read_linear(path).map_err(|error| map_error(scene_file, "environment.latlong", error))?;
            let texels: Vec<[f32; 3]> =
                texture.texels.iter().map(|t| [t[0] * intensity, t[1] * intensity, t[2] * intensity]).collect();
            Sh9::project_latlong(texture.width as usize, texture.height as usize, &texels)
                .map_err(|e| refused(scene_file, "environment.latlong", e.to_string()))?
        }
    };
    Ok(sh.coeffs)
}

/// [`LoadError::Map`] for the scene file `scene_file` and its `field`.
fn map_error(scene_file: &Path, field: &'static str, error: skinkit_maps::Error) -> LoadError {
    LoadError::Map { file: scene_file.display().to_string(), field, error }
}

/// An image as linear RGB (8-bit as sRGB, 16-bit and float as linear), like an albedo.
fn read_linear(path: &Path) -> skinkit_maps::Result<Texture> {
    crate::load::read_albedo(path, &Limits::default())
}

/// The profile's variance per axis, weighted by luminance over the channels (mm^2).
pub(crate) fn luminance_variance() -> f32 {
    (0..3).map(|c| LUMINANCE[c] * WEIGHTS.iter().zip(VARIANCES_MM2).map(|(w, v)| w[c] * v).sum::<f64>()).sum::<f64>()
        as f32
}

fn tsd_setup(scene: &Scene, plan: TsdPlan) -> Result<TsdSetup, LoadError> {
    let options = &scene.skin.tsd;
    let kernel_map = match &options.kernel_map {
        None => None,
        Some(path) => Some(read_kernel(path).map_err(|error| map_error(&scene.file, "tsd.kernel_map", error))?),
    };
    // The chapter's (a, b) map an artist's kernel value to texels of a 512 map: keep their size on
    // the skin at any resolution. A derived kernel stores its radius over MAX_KERNEL_TEXELS.
    let to_size = plan.size as f32 / 512.0;
    let kernel_scale = match kernel_map {
        Some(_) => [options.kernel_scale[0] * to_size, options.kernel_scale[1] * to_size],
        None => [setup::MAX_KERNEL_TEXELS, 0.0],
    };
    Ok(TsdSetup {
        size: plan.size,
        kernel: options.kernel,
        passes: options.passes,
        kernel_map,
        kernel_scale,
        kernel_mm: match options.kernel {
            TsdKernel::Single => crate::skin::poisson::kernel_mm_for(luminance_variance(), options.passes),
            TsdKernel::Gaussians => crate::skin::tsd::GAUSSIANS_KERNEL_MM,
        },
        curvature_gain: options.curvature_gain,
        backface_bias: options.backface_bias,
        reuse_below_px: options.reuse_below_px,
    })
}

/// A kernel map: its first channel as data (no sRGB decoding), in [0, 1).
fn read_kernel(path: &Path) -> skinkit_maps::Result<Texture> {
    let photo = io::read_photo(path, &Limits::default())?;
    let width = photo.width();
    let stride = match photo.channels() {
        skinkit_maps::Channels::Gray => 1,
        skinkit_maps::Channels::Rgb => 3,
    };
    Ok(Texture::from_fn(width as u32, photo.height() as u32, |x, y| {
        let k = photo.linear(stride * (y as usize * width + x as usize)).clamp(0.0, 0.999);
        [k, k, k, 1.0]
    }))
}
