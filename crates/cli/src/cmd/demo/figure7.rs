//! The demo's figure 7 (Haro et al. 2001, section 6, figure 7): the sample head's face without
//! and with the grown map, side by side, under the same light and camera, with a label per panel.
//!
//! # Framing
//! The camera looks from a little to the subject's left (216 mm away, 24 degrees) at the right brow,
//! eye and temple and the nose, 92 mm across 1024 pixels (0.09 mm a pixel at the point between
//! eye and nose): a texel of the demo's 2048 x 1024 face map (0.22 mm on the sample head's face,
//! median) is two to three pixels, so the map's pores and the temple's furrows are a few pixels
//! wide. A whole head at this scale would need panels about 2500 pixels tall.
//!
//! # Light
//! The default skin lobes (pbrt-v1's skin set; see
//! `skinkit_render::brdf` and the test `skin_lobes_reflect_like_the_skin_surface`) are weak
//! where light and view are both near the normal (their albedo is about a 1.4-index surface's
//! Fresnel reflectance there, 2-3 %) and strong toward grazing, as skin is (Marschner et al.
//! 1999). So the sheen comes from a rim light above and behind the subject's right, which meets
//! the temple, the brow and the side of the nose obliquely where the camera also sees them
//! obliquely; a warm key from the subject's left front and a dim cool fill from below the camera
//! draw the rest of the face. Section 6 of the paper notes that highlights look more real with fine
//! detail under them.
//!
//! # Measured
//! The skin panel is also drawn to linear EXR with the lobes and without (`lobes = []`), and the
//! same for the smooth head; [`skinkit_render::highlight::specular_share`] says how much of the
//! highlight pixels the lobes make, and how much local contrast the bumps give the sheen (the
//! demo report's `renders.figure7`).

use skinkit_maps::format::ImageFormat;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::Serialize;
use skinkit_maps::Samples;
use skinkit_maps::io::{self, Limits};
use skinkit_render::highlight::{SpecularShare, specular_share};
use skinkit_render::renderer::Renderer;

use super::figures::{grid, write_text};
use crate::output::Output;
use crate::render_job::{Job, RenderReport, render};

/// Side of each figure-7 panel, pixels.
pub const PANEL: usize = 1024;

/// The camera and lights of figure 7 (and of `samples/scenes/head.toml`, which repeats them).
const LIGHTS_AND_CAMERA: &str = r#"# Rim: above and behind the subject's right, grazing the temple, the brow and the nose (the sheen).
[[light]]
kind = "directional"
direction = [-0.45, 0.77, -0.45]
intensity = 6.0

# Key: warm, from the subject's left front.
[[light]]
kind = "directional"
direction = [0.85, 0.45, 0.25]
colour = [1.0, 0.93, 0.85]
intensity = 2.0

# Fill: cool and dim, from below the camera on the subject's right (into the eye socket).
[[light]]
kind = "directional"
direction = [-0.3, -0.1, 0.95]
colour = [0.85, 0.9, 1.0]
intensity = 0.3

# The right brow, eye and the nose, seen from a little to the subject's left: 216 mm from the
# point between them, 24 degrees across 1024 pixels (92 mm, 0.09 mm a pixel there).
[[camera]]
position = [26.2, 15.0, 229.5]
target = [-22.0, -6.0, 20.0]
fov_deg = 24.0
"#;

/// Figure 7 and what its specular lobes contribute.
#[derive(Serialize)]
pub struct Figure7 {
    pub image: String,
    /// The lobes' share of the skin panel's highlights.
    pub skin: SpecularShare,
    /// The same for the smooth head (no fine-scale structure).
    pub smooth: SpecularShare,
}

/// The face scene: the sample head with `normal_map` (a path relative to the scene) or smooth,
/// with the default skin lobes or none.
pub fn face_scene(normal_map: Option<&str>, lobes: bool) -> String {
    let map = normal_map
        .map_or(String::new(), |p| format!("\n[normal_map]\npath = \"{p}\"\ngreen = \"up\"\nframes = \"paper\"\n"));
    let brdf =
        if lobes { "" } else { "\n# The diffuse term alone, to measure what the lobes add.\n[brdf]\nlobes = []\n" };
    format!(
        r#"# Written by `skinkit demo`: the sample head's face (figure 7 of Haro et al. 2001){}{}.
mesh = "head.obj"
mm_per_unit = 1.0
specular = "pixel"
{map}{brdf}
{LIGHTS_AND_CAMERA}
[output]
size = [{PANEL}, {PANEL}]
"#,
        if normal_map.is_some() { ", with the grown face map" } else { ", without fine-scale structure" },
        if lobes { "" } else { ", diffuse only" },
    )
}

/// Renders figure 7 of `map` (an absolute path with forward slashes) into `dir`, which already
/// holds `head.obj`; every render's report is pushed to `renders`.
pub fn figure7(
    map: &str,
    dir: &Path,
    renderer: &Renderer,
    out: &Output,
    renders: &mut Vec<RenderReport>,
) -> Result<Figure7> {
    let mut scenes = Scenes { dir, renderer, out, renders };
    let smooth = scenes.draw("head-smooth", face_scene(None, true), ImageFormat::Png)?;
    let skin = scenes.draw("head-skin", face_scene(Some(map), true), ImageFormat::Png)?;
    let skin_share = scenes.share("head-skin", Some(map))?;
    let smooth_share = scenes.share("head-smooth", None)?;
    let image = dir.join("figure7.png");
    let panels = [(smooth, "without fine-scale structure".to_owned()), (skin, "with the grown map".to_owned())];
    grid(&panels, 2, &image)?;
    Ok(Figure7 { image: image.display().to_string(), skin: skin_share, smooth: smooth_share })
}

/// Writes scenes into a folder and renders them on one device.
struct Scenes<'a> {
    dir: &'a Path,
    renderer: &'a Renderer,
    out: &'a Output,
    renders: &'a mut Vec<RenderReport>,
}

impl Scenes<'_> {
    /// Writes `name.toml` and renders it to `name.ext`.
    fn draw(&mut self, name: &str, text: String, format: ImageFormat) -> Result<PathBuf> {
        let scene = self.dir.join(format!("{name}.toml"));
        write_text(&scene, &text)?;
        let image = self.dir.join(format!("{name}.{}", format.extension()));
        let job = Job { scene, out: Some(image.clone()), size: None, frames: None, reference: None };
        self.renders.push(render(&job, self.renderer, self.out)?);
        Ok(image)
    }

    /// The face with `map` drawn to EXR with and without the lobes, and the lobes' share.
    fn share(&mut self, name: &str, map: Option<&str>) -> Result<SpecularShare> {
        let with = self.draw(name, face_scene(map, true), ImageFormat::Exr)?;
        let without = self.draw(&format!("{name}-diffuse"), face_scene(map, false), ImageFormat::Exr)?;
        let ((a, width), (b, _)) = (linear(&with)?, linear(&without)?);
        specular_share(&a, &b, width)
            .with_context(|| format!("comparing {} with {}", with.display(), without.display()))
    }
}

/// The linear RGB samples of an EXR render and its width.
fn linear(path: &Path) -> Result<(Vec<f32>, usize)> {
    let photo = io::read_photo(path, &Limits::default())?;
    match photo.samples() {
        Samples::F32(s) => Ok((s.clone(), photo.width())),
        _ => bail!("{}: expected a float render", path.display()),
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use skinkit_render::scene::Scene;

    use super::*;

    fn samples() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/scenes")
    }

    /// `samples/scenes/head.toml` and `head-smooth.toml` promise figure 7's light and camera.
    #[test]
    fn sample_scenes_repeat_the_figure() {
        let figure = Scene::parse(&face_scene(Some("map.png"), true), &samples().join("figure.toml")).unwrap();
        for name in ["head.toml", "head-smooth.toml"] {
            let sample = Scene::load(&samples().join(name)).unwrap();
            assert_eq!(sample.lights, figure.lights, "{name}");
            assert_eq!(sample.cameras, figure.cameras, "{name}");
            assert_eq!(sample.brdf, figure.brdf, "{name}");
        }
    }

    #[test]
    fn the_diffuse_scene_differs_only_by_its_lobes() {
        let origin = samples().join("figure.toml");
        let with = Scene::parse(&face_scene(Some("map.png"), true), &origin).unwrap();
        let without = Scene::parse(&face_scene(Some("map.png"), false), &origin).unwrap();
        assert_eq!(with.brdf.lobes.len(), 3);
        assert!(without.brdf.lobes.is_empty());
        assert_eq!(with.brdf.diffuse, without.brdf.diffuse);
        assert_eq!((with.lights, with.cameras, with.normal_map), (without.lights, without.cameras, without.normal_map));
    }
}
