//! What several of these test modules share: the WGSL validator they check shaders with, and
//! render inputs with the plainest material (flat normals, white albedo, no tone curve).

use skinkit_render::brdf::Lafortune;
use skinkit_render::shading::{Camera, GreenAxis, Light, RenderInputs, SpecularMode, Texture, ToneCurve, Vertex};

/// Parses and validates a WGSL module with naga (every flag, default capabilities); the error
/// is naga's, with the source lines it points at.
pub fn validate(source: &str) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
        .validate(&module)
        .map_err(|e| e.emit_to_string(source))?;
    Ok(module)
}

/// A mesh seen by `camera` under `lights`, shaded by `brdf` with flat normals and a white albedo,
/// linear (no tone curve), on a black background.
pub fn plain_inputs(
    mesh: (Vec<Vertex>, Vec<u32>),
    camera: Camera,
    lights: Vec<Light>,
    brdf: Lafortune,
) -> RenderInputs {
    RenderInputs {
        vertices: mesh.0,
        indices: mesh.1,
        camera,
        lights,
        brdf,
        normal_map: Texture::flat_normals(),
        green: GreenAxis::Up,
        albedo: Texture::solid([1.0; 4]),
        specular: SpecularMode::Pixel,
        exposure: 1.0,
        tone: ToneCurve::None,
        background: [0.0; 4],
    }
}
