//! Light rigs: per light a direction, an intensity and optionally a near-light position.
//!
//! (Skeleton: the data types; parsing, validation and conditioning are filled in by the rig work.)

use glam::Vec3;

/// One light of a rig, in the camera frame (x right, y up, +z toward the camera).
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// Unit vector from the surface toward the light.
    pub direction: Vec3,
    /// Linear intensity per RGB channel (a scalar intensity is splatted to all three).
    pub intensity: Vec3,
    /// Position of a near point light in millimetres, origin at the centre of the photographed
    /// field, when known.
    pub position: Option<Vec3>,
}

/// A light rig: the lights in photo order, plus optional metadata.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Rig {
    pub name: Option<String>,
    pub description: Option<String>,
    pub lights: Vec<Light>,
    /// An ambient frame (all lights off), relative to the rig file's folder, to subtract.
    pub ambient: Option<std::path::PathBuf>,
    /// Size of a photo pixel on the mold, in millimetres, when known.
    pub mm_per_pixel: Option<f32>,
}
