//! The bundled renderer (Haro et al. 2001, section 5, on today's hardware): scenes, meshes,
//! texture-space frames, the Lafortune skin BRDF with its CPU reference, and the wgpu passes.
//!
//! The front door is [`renderer`]: a [`renderer::Renderer`] prepares a scene once (loaded,
//! planned, set up, memory-checked and uploaded) and draws its frames in memory; callers outside
//! this crate wire nothing else of the sequence (issue 38).
//!
//! Geometry side: [`scene`] (TOML scenes), [`mesh`] (OBJ and glTF loading), [`frames`] (the
//! paper's per-vertex texture-space frames and MikkTSpace), [`head`] (the sample head).
//! Shading side: [`brdf`] (Lafortune), [`shading`] (the CPU reference of the shaders), [`gpu`]
//! (device, resources, pipelines, readback, timing) and [`pass`] (one module per pass of the
//! graph, each with its WGSL); [`export`] writes a scene's skin as glTF 2.0 and [`gltf_maps`]
//! reads a glTF material's textures back as maps; [`load`] turns a scene into what the passes draw and plans the
//! passes and resources it needs; [`highlight`] measures how much of a render's highlights the
//! specular lobes make.

pub mod brdf;
pub mod compare;
pub mod effect;
pub mod export;
pub mod frames;
pub mod gltf_maps;
pub mod gpu;
pub mod head;
pub mod highlight;
pub mod label;
pub mod load;
pub mod mesh;
pub mod pass;
pub mod renderer;
pub mod scene;
pub mod shading;
pub mod skin;
pub mod view;
#[cfg(feature = "viewer")]
pub mod viewer;
