//! The bundled renderer (Haro et al. 2001, section 5, on today's hardware): scenes, meshes,
//! texture-space frames, the Lafortune skin BRDF with its CPU reference, and the wgpu passes.
//!
//! The front door is [`renderer`]: a [`renderer::Renderer`] prepares a scene once (loaded,
//! planned, set up, memory-checked and uploaded) and draws its frames in memory; callers outside
//! this crate wire nothing else of the sequence (issue 38).
//!
//! Geometry side: [`scene`] (TOML scenes), [`mesh`] (OBJ and glTF loading), [`frames`] (the
//! paper's per-vertex texture-space frames and MikkTSpace), [`head`] (the sample head).
//! Shading side: [`brdf`] (Lafortune), [`shading`] (the CPU reference of the shaders), [`skin`]
//! (the scattering physics on the CPU), [`compare`] (the skin methods side by side); behind the
//! front door, `load` (a scene's mesh and maps), `pass` (one folder a pass, each with its WGSL,
//! and the pass graph; the book's "Adding an effect") and `gpu` (device, resources, caches,
//! readback, timing, knowing no pass). [`export`] writes a scene's skin as glTF 2.0 and
//! [`gltf_maps`] reads a glTF material's textures back as maps; [`highlight`] measures how much
//! of a render's highlights the specular lobes make.

pub mod brdf;
pub mod compare;
pub mod effect;
pub mod export;
pub mod frames;
pub mod gltf_maps;
// The renderer's layers behind its front door ([`renderer`]): public only so that the crate's own
// integration tests and benchmarks can drive the passes directly (the GPU-against-CPU tests set
// up a pass's inputs by hand); applications go through `renderer` (tests/architecture.rs checks
// that nothing outside this crate names them). Not part of the documented API.
#[doc(hidden)]
pub mod gpu;
pub mod head;
pub mod highlight;
pub mod label;
#[doc(hidden)]
pub mod load;
pub mod mesh;
#[doc(hidden)]
pub mod pass;
pub mod renderer;
pub mod scene;
pub mod shading;
pub mod skin;
pub mod view;
#[cfg(feature = "viewer")]
pub mod viewer;
