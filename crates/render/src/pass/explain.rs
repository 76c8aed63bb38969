//! `skinkit render --explain`: a scene's passes for people, each as it describes itself
//! (`Pass::explain`), with what it reads and writes and every GPU resource with its bytes.
//! [`super::build`] computes what the same graph asks for.

use super::graph::PassGraph;
use super::{Context, Described};
use crate::gpu::OutputFormat as TargetFormat;
use crate::load::Loaded;
use crate::scene::Scene;
use crate::shading::Texture;
use crate::skin::tsd;

/// One GPU resource a plan needs.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Resource {
    /// What it is.
    pub name: String,
    /// Format and size, for people.
    pub detail: String,
    /// Bytes on the device.
    pub bytes: u64,
}

/// One pass of a plan.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Pass {
    /// Its name, as the GPU timings print it too.
    pub name: String,
    /// What it does.
    pub what: String,
    /// Names of the resources it reads.
    pub reads: Vec<String>,
    /// Names of the resources it writes.
    pub writes: Vec<String>,
    /// Device bytes of what it writes.
    pub bytes_written: u64,
}

/// The passes and GPU resources a scene needs, in execution order.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Plan {
    /// Passes in order.
    pub passes: Vec<Pass>,
    /// Every resource, once.
    pub resources: Vec<Resource>,
    /// What was asked for and not built, and why.
    pub notes: Vec<String>,
}

impl Plan {
    /// Total device bytes.
    pub fn bytes(&self) -> u64 {
        self.resources.iter().map(|r| r.bytes).sum()
    }
}

/// Bytes of a mip-mapped Rgba16Float texture (8 bytes a texel, a chain of halvings).
fn mipped_bytes(width: u32, height: u32) -> (u64, u32) {
    let (mut w, mut h, mut bytes, mut levels) = (width.max(1), height.max(1), 0u64, 0u32);
    loop {
        bytes += 8 * w as u64 * h as u64;
        levels += 1;
        if w == 1 && h == 1 {
            return (bytes, levels);
        }
        w = (w / 2).max(1);
        h = (h / 2).max(1);
    }
}

/// The plan of `graph` for `scene` drawn at `width x height` into `format`: every pass of the
/// graph's ordered list, what it reads and writes, and every resource with its bytes.
pub fn plan(scene: &Scene, loaded: &Loaded, graph: &PassGraph, width: u32, height: u32, format: TargetFormat) -> Plan {
    let resources = resources(scene, loaded, graph, width, height, format);
    let context = Context { scene, inputs: &loaded.inputs, graph };
    let passes = graph
        .passes
        .0
        .iter()
        .map(|pass| {
            let Described { what, reads, writes } = pass.explain(&context);
            let bytes = resources.iter().filter(|r| writes.contains(&r.name)).map(|r| r.bytes).sum();
            Pass { name: pass.name(), what, reads, writes, bytes_written: bytes }
        })
        .collect();
    Plan { passes, resources, notes: graph.notes.clone() }
}

/// Every GPU resource of `graph`, once.
fn resources(
    scene: &Scene,
    loaded: &Loaded,
    graph: &PassGraph,
    width: u32,
    height: u32,
    format: TargetFormat,
) -> Vec<Resource> {
    let inputs = &loaded.inputs;
    let texture = |name: &str, t: &Texture| {
        let (bytes, levels) = mipped_bytes(t.width, t.height);
        Resource {
            name: name.into(),
            detail: format!("{}x{} Rgba16Float, {levels} mip levels", t.width, t.height),
            bytes,
        }
    };
    let n_vertices = inputs.vertices.len() as u64;
    let mut out = vec![
        resource("vertices", format!("{n_vertices} vertices x 48 B (position, normal, tangent, uv)"), 48 * n_vertices),
        resource("indices", format!("{} triangles, u32", inputs.indices.len() / 3), 4 * inputs.indices.len() as u64),
        resource(
            "uniforms",
            format!("camera, {} lights, {} Lafortune lobes", inputs.lights.len(), inputs.brdf.lobes.len()),
            super::UNIFORM_BYTES,
        ),
        texture("normal map", &inputs.normal_map),
        texture("albedo", &inputs.albedo),
    ];
    out.extend(effect_resources(scene, graph, n_vertices));
    let (target_name, bytes_per_pixel) = match format {
        TargetFormat::Hdr16 => ("Rgba16Float", 8),
        TargetFormat::Hdr32 => ("Rgba32Float", 16),
        TargetFormat::Srgb8 => ("Rgba8UnormSrgb", 4),
    };
    let pixels = width as u64 * height as u64;
    out.push(resource("colour target", format!("{width}x{height} {target_name}"), bytes_per_pixel * pixels));
    out.push(resource("depth", format!("{width}x{height} Depth32Float"), 4 * pixels));
    out
}

fn resource(name: &str, detail: String, bytes: u64) -> Resource {
    Resource { name: name.into(), detail, bytes }
}

/// A table built on the CPU: `w` x `h` Rgba32Float.
fn table(name: &str, w: u32, h: u32, what: &str) -> Resource {
    Resource {
        name: name.into(),
        detail: format!("{w}x{h} Rgba32Float, {what}; built on the CPU, cached by its parameters"),
        bytes: 16 * w as u64 * h as u64,
    }
}

/// The resources the graph's effects add: curvature, tables, the shadow map, the light maps.
fn effect_resources(scene: &Scene, graph: &PassGraph, n_vertices: u64) -> Vec<Resource> {
    let mut out = Vec::new();
    let skin = &scene.skin;
    if graph.vertex_curvature {
        let detail = format!(
            "{n_vertices} vertices x 8 B (1/r in 1/mm from the mesh's mean curvature, mm per UV unit); computed on the CPU"
        );
        out.push(resource("per-vertex curvature", detail, 8 * n_vertices));
    }
    if graph.diffuse_lut {
        let [w, h] = skin.preintegrated.lut_size;
        let what = format!(
            "pre-integrated diffuse D(N.L, 1/r), {} normalisation, {} ring",
            skin.preintegrated.normalisation.name(),
            skin.preintegrated.domain.name()
        );
        out.push(table("diffuse LUT", w, h, &what));
    }
    if graph.zonal_table {
        let n = crate::skin::sh::ZONAL_SAMPLES as u32;
        out.push(table("zonal table", n, 3, "the skin's SH zonal factors A_l(1/r), l = 0, 1, 2"));
    }
    if let Some(shadow) = graph.shadow {
        let (n, key, filter) = (shadow.size as u64, shadow.light, shadow.filter);
        let detail = format!("{n}x{n} Depth32Float, light[{key}], {filter}x{filter} box filter");
        out.push(resource("shadow map", detail, 4 * n * n));
        if graph.features.translucent_shadows {
            let casters = scene.translucent.len();
            let detail = format!("{n}x{n} Rgba16Float: opacity of {casters} translucent caster(s), summed");
            out.push(resource("shadow opacity", detail, 8 * n * n));
        }
    }
    if graph.shadow_lut {
        let n = crate::skin::shadow::SHADOW_LUT_SIDE;
        out.push(table("shadow LUT", n, n, "shadow scattering P_S(s, w), penumbra of a disc of taps"));
    }
    if let Some(tsd) = graph.tsd {
        let n = tsd.size as u64;
        out.push(resource("tsd depth", format!("{n}x{n} Depth32Float in texture space (culling pre-pass)"), 4 * n * n));
        for name in &tsd::LIGHT_MAP_NAMES[..tsd::map_count(tsd.kernel)] {
            out.push(resource(
                name,
                format!("{n}x{n} Rgba16Float: diffuse irradiance, kernel size in alpha"),
                8 * n * n,
            ));
        }
        let detail = format!("{n}x{n} Rg16Float: the blur kernel's widening along u and v");
        out.push(resource(super::tsd::STRETCH, detail, 4 * n * n));
        if let Some(path) = &skin.tsd.kernel_map {
            out.push(resource("kernel map", format!("{} (per-texel blur kernel size)", path.display()), 0));
        }
    }
    out
}
