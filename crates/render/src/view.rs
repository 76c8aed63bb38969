//! What the interactive viewer draws, without a window: a scene's pass graph with some of its
//! effects switched off and the base pass's ingredients toggled, rendered offscreen through the
//! [`Renderer`]. The viewer (`crate::viewer`, cargo feature `viewer`) shows these frames; the
//! tests draw them headless, so the path a user sees is the path that is tested.

use crate::effect::Effect;
use crate::load::Loaded;
use crate::renderer::{Frame, FrameOptions, Prepared, RenderError, Renderer};
use crate::scene::{Camera, Scene};
use crate::shading::{Light, SpecularMode, Texture};

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
/// cached in the [`Renderer`] across them).
pub struct ViewSession {
    scene: Scene,
    loaded: Loaded,
    options: FrameOptions,
    warnings: Vec<String>,
    prepared: Vec<(Toggles, Prepared)>,
}

impl ViewSession {
    /// A session on `scene` drawn with `options`, loaded (and memory-checked) once by `renderer`.
    ///
    /// # Errors
    /// As [`Renderer::prepare`]'s loading.
    pub fn new(renderer: &Renderer, scene: Scene, options: FrameOptions) -> Result<ViewSession, RenderError> {
        let (loaded, explanation) = renderer.load(&scene, &options)?;
        Ok(ViewSession { scene, loaded, options, warnings: explanation.warnings, prepared: Vec::new() })
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Notes of the loading and the plan, for the user.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The effects the scene lists (what the viewer's number keys toggle).
    pub fn effects(&self) -> &[Effect] {
        &self.scene.effects
    }

    /// The frame size.
    pub fn size(&self) -> (u32, u32) {
        (self.options.width, self.options.height)
    }

    /// Draws the next frames at `width x height` (the window was resized): every prepared set of
    /// toggles gets a new target, memory-checked.
    ///
    /// # Errors
    /// A frame over the memory limit or a size the device refuses.
    pub fn resize(&mut self, renderer: &Renderer, width: u32, height: u32) -> Result<(), RenderError> {
        if (width, height) == self.size() {
            return Ok(());
        }
        self.options.width = width;
        self.options.height = height;
        for (_, prepared) in &mut self.prepared {
            renderer.retarget(&self.scene, prepared, (width, height), self.options.encoding)?;
        }
        Ok(())
    }

    /// The scene's first light, as loaded.
    pub fn first_light(&self) -> Option<Light> {
        self.loaded.inputs.lights.first().copied()
    }

    /// Draws one frame with `toggles` from `camera`, the first light replaced by `light`, and
    /// reads it back.
    ///
    /// # Errors
    /// A table that cannot be built, or a renderer error.
    pub fn frame(
        &mut self,
        renderer: &Renderer,
        toggles: &Toggles,
        camera: &Camera,
        light: Option<Light>,
    ) -> Result<Frame, RenderError> {
        if !self.prepared.iter().any(|(t, _)| t == toggles) {
            let prepared = self.prepare(renderer, toggles)?;
            self.prepared.push((toggles.clone(), prepared));
        }
        let (_, prepared) = self.prepared.iter_mut().find(|(t, _)| t == toggles).expect("prepared above");
        if let Some(light) = light {
            prepared.set_light(0, &light);
        }
        renderer.draw(prepared, camera)
    }

    /// The graph of the scene with `toggles.off` removed, built and uploaded.
    fn prepare(&self, renderer: &Renderer, toggles: &Toggles) -> Result<Prepared, RenderError> {
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
        renderer.prepare_loaded(&scene, loaded, &self.options, Default::default())
    }
}
