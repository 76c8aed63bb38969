//! The sample head for `skinkit samples` and the demo: `samples/head/head.obj`, derived from the
//! MakeHuman base mesh hm08 (CC0 1.0) by `scripts/make_head.py` and built into the library, so
//! the demo and `skinkit samples --head` need no file at run time. Haro et al. 2001 render a
//! low-poly face mesh carrying the grown normal map (section 5, figure 7); this head plays its
//! part for the sample face map.
//!
//! # Geometry
//! Head and neck of hm08's skin, closed under the neck, subdivided once (Catmull-Clark) with
//! smooth vertex normals; in millimetres ([`HEAD_MM_PER_UNIT`] = 1), +y up, the face looking
//! along +z, the origin between the eyes' centres. Three OBJ groups: `skin` (the outer surface),
//! `pockets` (hm08's eye sockets, mouth and nostrils: inside the head, out of sight) and `eyes`
//! (an eyeball in each socket, just inside the lids).
//!
//! # UV unwrap
//! A spherical projection about a point behind the nose, `v = 0` at the crown (the top of the
//! image), the seam at the back of the head (`u = 0 = 1`; faces across it reach a little past
//! `u = 1`). Ear to ear takes `u` in `[0.1, 0.9]`, hairline to chin most of `v`, so the face is
//! one island in the middle of the map with the subject's right on the left, where
//! `samples/face/layout.toml` puts its regions. The pockets, which fold over in the projection,
//! are relaxed (each an averaged disc inside its rim) and, with the eyeballs (each a disc about
//! its front pole), moved one map width to the right (`u + 1`): a repeating sampler reads the
//! same texels, and texture-space passes, which draw into the map, leave them out.
//! `crates/render/tests/render/head.rs` measures the layout: no flipped or zero-area face
//! triangle, the face's texel density in a stated range.

use std::io::Write;
use std::path::Path;

use crate::mesh::Mesh;

/// Millimetres per unit of the sample head.
pub const HEAD_MM_PER_UNIT: f32 = 1.0;

/// The OBJ text of `samples/head/head.obj`.
pub const SAMPLE_HEAD_OBJ: &str = include_str!("../../../samples/head/head.obj");

/// The sample head, all groups merged (what a scene naming `head.obj` renders).
pub fn sample_head() -> Mesh {
    Mesh::parse_obj(&mut SAMPLE_HEAD_OBJ.as_bytes(), "samples/head/head.obj")
        .expect("the sample head built into the library is a valid OBJ (tested)")
        .mesh
}

/// Writes the sample head's OBJ text (with its groups) to `path`, atomically.
///
/// # Errors
/// When the file cannot be written.
pub fn write_sample_head(path: &Path) -> skinkit_maps::Result<()> {
    skinkit_maps::io::write_atomic(path, |w| {
        w.write_all(SAMPLE_HEAD_OBJ.as_bytes())
            .map_err(|error| skinkit_maps::Error::Io { path: path.to_owned(), error })
    })
}

/// Writes `mesh` as an OBJ file (positions, `vt` with `v` flipped back to OBJ's bottom origin,
/// normals, `f a/a/a`), atomically. Numbers use Rust's shortest round-trip formatting.
///
/// # Errors
/// When the file cannot be written.
pub fn write_obj(mesh: &Mesh, path: &Path) -> skinkit_maps::Result<()> {
    skinkit_maps::io::write_atomic(path, |w| {
        obj_text(mesh, w).map_err(|error| skinkit_maps::Error::Io { path: path.to_owned(), error })
    })
}

/// Writes `mesh` as OBJ text to `w` (see [`write_obj`]).
///
/// # Errors
/// When `w` fails.
pub(crate) fn obj_text(mesh: &Mesh, w: &mut impl Write) -> std::io::Result<()> {
    writeln!(w, "# written by skinkit: {} mm per unit", HEAD_MM_PER_UNIT)?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for t in &mesh.uvs {
        writeln!(w, "vt {} {}", t.x, 1.0 - t.y)?;
    }
    for n in &mesh.normals {
        writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
    }
    for tri in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] + 1, tri[1] + 1, tri[2] + 1];
        writeln!(w, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")?;
    }
    Ok(())
}
