//! What the interactive viewer draws, without a window: a scene's pass graph with some of its
//! effects switched off and the base pass's ingredients toggled, rendered offscreen. The viewer
//! (`crate::viewer`, cargo feature `viewer`) shows these frames; the tests draw them headless,
//! so the path a user sees is the path that is tested.

use crate::effect::Effect;
use crate::gpu::{Gpu, GpuError, PreparedScene, Rendered, Target};
use crate::graph::PassGraph;
use crate::load::{LoadError, Loaded};
use crate::scene::Scene;
use crate::shading::{Camera, Light, SpecularMode, Texture};
use crate::skin::setup;

/// What went wrong drawing a frame.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FrameError {
    /// The renderer failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// A table or map of an effect could not be built.
    #[error(transparent)]
    Load(#[from] LoadError),
}

/// The switches of one frame.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Toggles {
    /// The fine-scale normal map (off: the mesh's own normals).
    pub normal_map: bool,
    /// The Lafortune lobes (off: diffuse only).
    pub specular: bool,
    /// Lobes per vertex instead of per pixel.
    pub vertex_specular: bool,
    /// Effects of the scene switched off, in [`Effect::ALL`] order.
    pub off: Vec<Effect>,
}

impl Toggles {
    /// Everything the scene asks for, on.
    pub fn all_on(scene: &Scene) -> Toggles {
        Toggles {
            normal_map: true,
            specular: true,
            vertex_specular: scene.specular == SpecularMode::Vertex,
            off: Vec::new(),
        }
    }

    /// Switches `effect` off, or back on.
    pub fn flip(&mut self, effect: Effect) {
        match self.off.iter().position(|&e| e == effect) {
            Some(i) => {
                self.off.remove(i);
            }
            None => {
                self.off.push(effect);
                self.off.sort();
            }
        }
    }
}

/// A scene loaded once, its frames prepared once per set of toggles (pipelines and tables stay
/// cached in the [`Gpu`] across them).
pub struct ViewSession {
    scene: Scene,
    loaded: Loaded,
    prepared: Vec<(Toggles, PreparedScene)>,
}

impl ViewSession {
    /// A session on `scene` and its loaded inputs.
    pub fn new(scene: Scene, loaded: Loaded) -> ViewSession {
        ViewSession { scene, loaded, prepared: Vec::new() }
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The effects the scene lists (what the viewer's number keys toggle).
    pub fn effects(&self) -> &[Effect] {
        &self.scene.effects
    }

    /// The scene's first light, as loaded.
    pub fn first_light(&self) -> Option<Light> {
        self.loaded.inputs.lights.first().copied()
    }

    /// Draws one frame with `toggles` from `camera`, the first light replaced by `light`, into
    /// `target`, and reads it back.
    ///
    /// # Errors
    /// A table that cannot be built, or a renderer error.
    pub fn frame(
        &mut self,
        gpu: &Gpu,
        toggles: &Toggles,
        camera: &Camera,
        light: Option<Light>,
        target: &Target,
    ) -> Result<Rendered, FrameError> {
        if !self.prepared.iter().any(|(t, _)| t == toggles) {
            let prepared = self.prepare(gpu, toggles)?;
            self.prepared.push((toggles.clone(), prepared));
        }
        let (_, prepared) = self.prepared.iter_mut().find(|(t, _)| t == toggles).expect("prepared above");
        prepared.set_camera(camera);
        if let Some(light) = light {
            prepared.set_light(0, &light);
        }
        gpu.draw(prepared, target)?;
        Ok(gpu.read(target)?)
    }

    /// The graph of the scene with `toggles.off` removed, built and uploaded.
    fn prepare(&self, gpu: &Gpu, toggles: &Toggles) -> Result<PreparedScene, FrameError> {
        let mut scene = self.scene.clone();
        scene.effects.retain(|e| !toggles.off.contains(e));
        let mut loaded = self.loaded.clone();
        if !toggles.normal_map {
            loaded.inputs.normal_map = Texture::flat_normals();
        }
        if !toggles.specular {
            loaded.inputs.brdf.lobes.clear();
        }
        loaded.inputs.specular = if toggles.vertex_specular { SpecularMode::Vertex } else { SpecularMode::Pixel };
        let graph = PassGraph::build(&scene);
        let skin = setup::build(&scene, &loaded, &graph)?;
        Ok(gpu.prepare_with(&loaded.inputs, &skin)?)
    }
}
