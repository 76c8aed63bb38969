//! Rigs from public photometric-stereo light files.
//!
//! * DiLiGenT (Shi et al., the benchmark in docs/references.md): `light_directions.txt` holds one
//!   `x y z` per line and `light_intensities.txt` one `r g b` per line, photo order. DiLiGenT's
//!   frame is x right, y up, z toward the camera (loaders of the benchmark document it so and
//!   flip y and z when they convert to image coordinates), which is skinkit's frame: directions
//!   are taken as they are.
//! * UW/Seitz `lights.txt` (the `psmImages` course data): a count line, then one `x y z` per
//!   line. The course notes say the lights were balanced to the same brightness, so every
//!   intensity is 1. Which way the file's y axis points is not stated in any source found (the
//!   course skeletons compute it from chrome-sphere highlights in image coordinates, and both
//!   conventions appear in student code); skinkit *assumes* x right, y up, z toward the camera,
//!   like DiLiGenT. If normals from such a rig come out mirrored top to bottom (bumps read as
//!   pits under light from above), call [`crate::Rig::flip_y`] on the imported rig.
//!
//! Readers come in pairs: `diligent(dir)` / `uw_lights(path)` open files and call
//! `parse_diligent` / `parse_uw_lights`, which take any reader and a name for messages. Errors
//! name the file and the 1-based line.

use std::io::Read;
use std::path::Path;

use glam::Vec3;

use crate::rig::{Light, Rig};
use crate::{Error, Result};

/// DiLiGenT light direction file name.
pub const DILIGENT_DIRECTIONS: &str = "light_directions.txt";
/// DiLiGenT light intensity file name.
pub const DILIGENT_INTENSITIES: &str = "light_intensities.txt";

/// Reads a DiLiGenT object folder's `light_directions.txt` and `light_intensities.txt`.
///
/// # Errors
/// [`Error::Io`] when a file cannot be read; [`Error::BadFile`] as [`parse_diligent`].
pub fn diligent(dir: &Path) -> Result<Rig> {
    let dirs_path = dir.join(DILIGENT_DIRECTIONS);
    let ints_path = dir.join(DILIGENT_INTENSITIES);
    let dirs = open(&dirs_path)?;
    let ints = open(&ints_path)?;
    parse_diligent(dirs, &dirs_path.display().to_string(), ints, &ints_path.display().to_string())
}

/// Parses DiLiGenT direction and intensity text; the names appear in messages.
///
/// # Errors
/// [`Error::BadFile`] naming file and line for a malformed line, a zero or downward direction, a
/// non-positive intensity; naming the intensity file when the counts differ.
pub fn parse_diligent(
    directions: impl Read,
    directions_name: &str,
    intensities: impl Read,
    intensities_name: &str,
) -> Result<Rig> {
    let dirs = read_triples(directions, directions_name)?;
    let ints = read_triples(intensities, intensities_name)?;
    if dirs.len() != ints.len() {
        return Err(Error::BadFile {
            location: intensities_name.to_owned(),
            reason: format!("{} intensities but {directions_name} has {} directions", ints.len(), dirs.len()),
        });
    }
    let lights = dirs
        .iter()
        .zip(&ints)
        .map(|(d, e)| {
            Light::new(d.value, e.value, None).map_err(|reason| {
                let (name, line) = if reason.starts_with("intensity") {
                    (intensities_name, e.line)
                } else {
                    (directions_name, d.line)
                };
                Error::BadFile { location: format!("{name}: line {line}"), reason }
            })
        })
        .collect::<Result<Vec<_>>>()?;
    named(lights, directions_name, "DiLiGenT")
}

/// Reads a UW/Seitz `lights.txt` (count line, then one direction per line; unit intensities).
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::BadFile`] as [`parse_uw_lights`].
pub fn uw_lights(path: &Path) -> Result<Rig> {
    parse_uw_lights(open(path)?, &path.display().to_string())
}

/// Parses UW/Seitz `lights.txt` text; `name` appears in messages.
///
/// # Errors
/// [`Error::BadFile`] naming `name` and the line for a bad count, a malformed or zero direction,
/// or a count that does not match the number of direction lines.
pub fn parse_uw_lights(reader: impl Read, name: &str) -> Result<Rig> {
    let text = read_text(reader, name)?;
    let mut lines = numbered_lines(&text);
    let (count_line, count_text) =
        lines.next().ok_or_else(|| bad(name, "empty file: expected a light count".into()))?;
    let count: usize = count_text
        .parse()
        .map_err(|_| bad(&format!("{name}: line {count_line}"), format!("`{count_text}` is not a light count")))?;
    let dirs = lines.map(|(line, t)| parse_triple(t, name, line)).collect::<Result<Vec<_>>>()?;
    if dirs.len() != count {
        return Err(bad(
            name,
            format!("declares {count} lights on line {count_line} but has {} direction lines", dirs.len()),
        ));
    }
    let lights = dirs
        .iter()
        .map(|d| {
            Light::new(d.value, Vec3::ONE, None).map_err(|reason| bad(&format!("{name}: line {}", d.line), reason))
        })
        .collect::<Result<Vec<_>>>()?;
    named(lights, name, "UW/Seitz lights.txt")
}

/// A parsed `a b c` line and its 1-based line number.
struct Triple {
    value: Vec3,
    line: usize,
}

/// A light file, through the input gate ([`skinkit_maps::input`]).
fn open(path: &Path) -> Result<std::fs::File> {
    Ok(skinkit_maps::input::open(path, skinkit_maps::input::Kind::LightFile).map_err(skinkit_maps::Error::from)?)
}

/// The reader's text, at most the input gate's limit for a light file (a file that grew past it
/// after the gate looked is refused, not read without end).
fn read_text(reader: impl Read, name: &str) -> Result<String> {
    let limit = skinkit_maps::input::Kind::LightFile.limit();
    let mut text = String::new();
    reader.take(limit + 1).read_to_string(&mut text).map_err(|e| bad(name, format!("cannot read: {e}")))?;
    if text.len() as u64 > limit {
        return Err(bad(name, format!("longer than a light file may be ({} MiB)", limit >> 20)));
    }
    Ok(text)
}

/// Non-blank lines, trimmed, with 1-based line numbers.
fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines().enumerate().map(|(i, l)| (i + 1, l.trim())).filter(|(_, l)| !l.is_empty())
}

fn read_triples(reader: impl Read, name: &str) -> Result<Vec<Triple>> {
    let text = read_text(reader, name)?;
    numbered_lines(&text).map(|(line, t)| parse_triple(t, name, line)).collect()
}

/// Three whitespace- (or comma-) separated finite numbers.
fn parse_triple(text: &str, name: &str, line: usize) -> Result<Triple> {
    let location = || format!("{name}: line {line}");
    let fields: Vec<&str> = text.split(|c: char| c.is_whitespace() || c == ',').filter(|s| !s.is_empty()).collect();
    if fields.len() != 3 {
        return Err(bad(&location(), format!("expected 3 numbers, found {} in `{text}`", fields.len())));
    }
    let mut v = [0f32; 3];
    for (slot, f) in v.iter_mut().zip(&fields) {
        *slot = f
            .parse::<f32>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad(&location(), format!("`{f}` is not a finite number")))?;
    }
    Ok(Triple { value: Vec3::from_array(v), line })
}

fn named(lights: Vec<Light>, origin: &str, format: &str) -> Result<Rig> {
    Ok(Rig::new(lights, origin)?.with_description(format!("imported from {origin} ({format})")))
}

fn bad(location: &str, reason: String) -> Error {
    Error::BadFile { location: location.to_owned(), reason }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triple_accepts_commas_and_spaces() {
        let t = parse_triple("0.1, -0.2   0.97", "f", 3).unwrap();
        assert_eq!(t.value, Vec3::new(0.1, -0.2, 0.97));
        assert_eq!(t.line, 3);
    }
}
