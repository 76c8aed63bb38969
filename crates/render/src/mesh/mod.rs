//! Triangle meshes for the renderer: OBJ (via `tobj`) and glTF 2.0 (via `gltf`) loading into one
//! indexed layout with a position, a normal and a texture coordinate per vertex.
//!
//! Haro et al. 2001 (section 5) render a low-poly face mesh whose texture coordinates address the
//! grown normal map, so a mesh without UVs cannot be rendered with fine-scale structure: loading
//! one is an error naming the file. A mesh without normals gets area-weighted vertex normals,
//! with a note in [`LoadedMesh::warnings`]; its vertices are welded first ([`weld`]: a glTF
//! without indices or normals, split per face corner, would otherwise shade faceted), and
//! vertices at one position share one normal, across UV seams too.
//!
//! # UV convention
//! skinkit puts `v = 0` at the TOP row of an image (as glTF and wgpu textures do; maps are stored
//! row 0 first). OBJ files follow OpenGL, with `v = 0` at the BOTTOM, so the OBJ loader stores
//! `1 - v`; glTF coordinates are taken as they are. [`crate::head::write_obj`] flips back on
//! writing, so an OBJ round trip is the identity.
//!
//! # Hard cases
//! - non-finite positions, normals or UVs: an error naming the vertex index;
//! - indices out of range or a count that is not a multiple of 3: an error;
//! - zero-area triangles are kept (they draw nothing) and contribute nothing to computed normals
//!   or to [`crate::frames`];
//! - loaded normals that are zero or non-finite are replaced by computed ones, with a warning;
//! - a vertex that no triangle with area touches gets the normal +z (deterministic, finite).

pub(crate) mod source;
pub mod weld;

use std::io::BufRead;
use std::path::{Path, PathBuf};

use glam::{Mat3, Mat4, Vec2, Vec3};

/// The deepest node hierarchy a glTF file may have (real scenes nest a few tens of levels).
const MAX_GLTF_DEPTH: usize = 256;

/// Errors from loading or validating a mesh. Every message names the file (or `mesh` for a mesh
/// built in memory).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeshError {
    /// The file could not be read.
    #[error("{file}")]
    Io {
        file: String,
        #[source]
        error: std::io::Error,
    },
    /// The input gate refused the file or could not read it ([`skinkit_maps::input`]).
    #[error(transparent)]
    Input(#[from] skinkit_maps::input::InputError),
    /// The extension names no supported format.
    #[error("{file}: unsupported mesh format (expected .obj, .gltf or .glb)")]
    UnsupportedFormat { file: String },
    /// The OBJ parser refused the file.
    #[error("{file}: not a readable OBJ file: {reason}")]
    Obj { file: String, reason: String },
    /// The glTF parser refused the file or its buffers.
    #[error("{file}: not a readable glTF file: {reason}")]
    Gltf { file: String, reason: String },
    /// No triangles at all.
    #[error("{file}: the mesh has no triangles")]
    Empty { file: String },
    /// Texture coordinates are missing: the texture-space maps cannot be applied.
    #[error(
        "{file}: {part} has no texture coordinates (uv); skinkit needs them to apply the \
         texture-space normal and albedo maps"
    )]
    NoUvs { file: String, part: String },
    /// A non-finite attribute value.
    #[error("{file}: vertex {index} has a non-finite {field} ({value})")]
    NonFinite { file: String, index: usize, field: &'static str, value: String },
    /// An index that names no vertex.
    #[error("{file}: triangle {triangle} uses vertex {index} but the mesh has {count} vertices")]
    IndexOutOfRange { file: String, triangle: usize, index: u32, count: usize },
    /// An OBJ line the loader refuses, named by its line number in the file.
    #[error("{file}: line {line}: {reason}")]
    ObjLine { file: String, line: usize, reason: String },
    /// Attribute arrays or the index count do not fit together.
    #[error("{file}: {field}: {reason}")]
    Layout { file: String, field: &'static str, reason: String },
}

/// Result alias for mesh loading.
pub type Result<T, E = MeshError> = std::result::Result<T, E>;

/// An indexed triangle mesh with one attribute set per vertex (vertices are split at UV seams as
/// the loaders give them). Units are the file's units; the scene says how long one unit is.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, `v = 0` at the top of the image.
    pub uvs: Vec<Vec2>,
    /// Three indices per triangle, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
}

/// A loaded mesh and what the loader had to repair or ignore.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedMesh {
    /// The mesh, validated.
    pub mesh: Mesh,
    /// Notes for the user (computed normals, skipped primitives).
    pub warnings: Vec<String>,
}

impl Mesh {
    /// Loads an OBJ, glTF or GLB file, chosen by extension (case-insensitive).
    ///
    /// # Errors
    /// Unreadable or malformed files, missing UVs, non-finite values, bad indices.
    pub fn load(path: &Path) -> Result<LoadedMesh> {
        let file = path.display().to_string();
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        let bytes = skinkit_maps::input::read(path, skinkit_maps::input::Kind::Mesh)?;
        match ext.as_deref() {
            Some("obj") => Self::parse_obj(&mut bytes.as_slice(), &file),
            Some("gltf") | Some("glb") => Self::parse_gltf(&bytes, path.parent(), &file),
            _ => Err(MeshError::UnsupportedFormat { file }),
        }
    }

    /// Parses OBJ text (all objects merged, polygons triangulated, `v` flipped to top-origin).
    /// Material libraries are not read. `origin` names the source in messages.
    ///
    /// # Errors
    /// As [`Mesh::load`].
    pub fn parse_obj(reader: &mut impl BufRead, origin: &str) -> Result<LoadedMesh> {
        let mut bytes = Vec::new();
        reader.read_to_end(&mut bytes).map_err(|error| MeshError::Io { file: origin.to_owned(), error })?;
        // Source lines are checked first: the parser below re-indexes and forgets them.
        source::check_obj(&String::from_utf8_lossy(&bytes), origin)?;
        let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
        let (models, _materials) =
            tobj::load_obj_buf(&mut bytes.as_slice(), &options, |_| Err(tobj::LoadError::OpenFileFailed))
                .map_err(|e| MeshError::Obj { file: origin.to_owned(), reason: e.to_string() })?;
        let mut builder = Builder::new(origin);
        for model in &models {
            builder.add_obj_model(model)?;
        }
        builder.finish()
    }

    /// Parses glTF JSON or GLB bytes: every triangle primitive of every mesh in the default scene
    /// (or the first scene), with node transforms applied. External buffers are resolved against
    /// `base` (the file's folder).
    ///
    /// # Errors
    /// As [`Mesh::load`].
    pub fn parse_gltf(bytes: &[u8], base: Option<&Path>, origin: &str) -> Result<LoadedMesh> {
        let refused = |reason: String| MeshError::Gltf { file: origin.to_owned(), reason };
        let gltf::Gltf { document, blob } = source::parse_gltf(bytes).map_err(refused)?;
        let base = base.map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."));
        let buffers = source::load_gltf_buffers(&document, &base, blob).map_err(refused)?;
        let scene = document
            .default_scene()
            .or_else(|| document.scenes().next())
            .ok_or_else(|| MeshError::Gltf { file: origin.to_owned(), reason: "the file has no scene".into() })?;
        let mut builder = Builder::new(origin);
        // glTF's nodes form trees; a node reached twice (a cycle, or a child of two parents) would
        // recurse without end or multiply its meshes, so it is refused.
        let mut visited = vec![false; document.nodes().len()];
        for node in scene.nodes() {
            builder.add_gltf_node(&node, Mat4::IDENTITY, &buffers, &mut visited, 0)?;
        }
        builder.finish()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The three vertex indices of triangle `t`.
    pub fn triangle(&self, t: usize) -> [usize; 3] {
        let i = &self.indices[3 * t..3 * t + 3];
        [i[0] as usize, i[1] as usize, i[2] as usize]
    }

    /// Axis-aligned bounds `(min, max)`; `(0, 0)` for a mesh without vertices.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        if self.positions.is_empty() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        let min = self.positions.iter().fold(Vec3::splat(f32::INFINITY), |a, &p| a.min(p));
        let max = self.positions.iter().fold(Vec3::splat(f32::NEG_INFINITY), |a, &p| a.max(p));
        (min, max)
    }

    /// Checks the layout, finiteness and indices of a mesh built in memory.
    ///
    /// # Errors
    /// The first problem found, named as in the loaders with `mesh` as the file.
    pub fn validate(&self) -> Result<()> {
        self.check("mesh")
    }

    /// Area-weighted vertex normals: each triangle adds its un-normalised face normal (twice its
    /// area) to its three vertices, so zero-area triangles add nothing. Vertices with no area
    /// around them get +z.
    pub fn area_weighted_normals(&self) -> Vec<Vec3> {
        let mut sums = vec![Vec3::ZERO; self.positions.len()];
        for t in 0..self.triangle_count() {
            let [a, b, c] = self.triangle(t);
            let n = (self.positions[b] - self.positions[a]).cross(self.positions[c] - self.positions[a]);
            for v in [a, b, c] {
                sums[v] += n;
            }
        }
        sums.into_iter().map(|n| n.try_normalize().unwrap_or(Vec3::Z)).collect()
    }

    fn check(&self, file: &str) -> Result<()> {
        let n = self.positions.len();
        let layout = |field, reason: String| MeshError::Layout { file: file.to_owned(), field, reason };
        if self.normals.len() != n {
            return Err(layout("normals", format!("{} normals for {n} positions", self.normals.len())));
        }
        if self.uvs.len() != n {
            return Err(layout("uvs", format!("{} uvs for {n} positions", self.uvs.len())));
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(layout("indices", format!("{} indices is not a multiple of 3", self.indices.len())));
        }
        if self.indices.is_empty() {
            return Err(MeshError::Empty { file: file.to_owned() });
        }
        check_finite(file, "position", self.positions.iter().map(|p| p.to_array().to_vec()))?;
        check_finite(file, "normal", self.normals.iter().map(|p| p.to_array().to_vec()))?;
        check_finite(file, "uv", self.uvs.iter().map(|p| p.to_array().to_vec()))?;
        self.check_indices(file)
    }

    fn check_indices(&self, file: &str) -> Result<()> {
        let count = self.positions.len();
        match self.indices.iter().position(|&i| i as usize >= count) {
            Some(k) => Err(MeshError::IndexOutOfRange {
                file: file.to_owned(),
                triangle: k / 3,
                index: self.indices[k],
                count,
            }),
            None => Ok(()),
        }
    }
}

fn check_finite(file: &str, field: &'static str, values: impl Iterator<Item = Vec<f32>>) -> Result<()> {
    for (index, v) in values.enumerate() {
        if v.iter().any(|x| !x.is_finite()) {
            let value = format!("{v:?}");
            return Err(MeshError::NonFinite { file: file.to_owned(), index, field, value });
        }
    }
    Ok(())
}

/// Accumulates parts (OBJ models, glTF primitives) into one mesh, tracking which vertices came
/// without normals.
struct Builder {
    file: String,
    mesh: Mesh,
    /// Per vertex: the normal came from the file.
    has_normal: Vec<bool>,
    warnings: Vec<String>,
}

impl Builder {
    fn new(file: &str) -> Self {
        Builder { file: file.to_owned(), mesh: Mesh::default(), has_normal: Vec::new(), warnings: Vec::new() }
    }

    fn add_obj_model(&mut self, model: &tobj::Model) -> Result<()> {
        let m = &model.mesh;
        let n = m.positions.len() / 3;
        let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        if m.texcoords.len() != 2 * n {
            return Err(self.no_uvs(format!("object `{}`", model.name)));
        }
        // OBJ puts v = 0 at the bottom of the image; skinkit at the top.
        let uvs = m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], 1.0 - t[1])).collect();
        let normals = (m.normals.len() == 3 * n)
            .then(|| m.normals.chunks_exact(3).map(|v| Vec3::new(v[0], v[1], v[2])).collect());
        self.add_part(Part { positions, normals, uvs, indices: m.indices.clone() }, &model.name)
    }

    /// Adds `node`'s meshes and, recursively, its children's (at most [`MAX_GLTF_DEPTH`] deep, so
    /// a hostile chain cannot overflow the stack).
    fn add_gltf_node(
        &mut self,
        node: &gltf::Node,
        parent: Mat4,
        buffers: &[gltf::buffer::Data],
        visited: &mut [bool],
        depth: usize,
    ) -> Result<()> {
        let refuse = |reason: String| Err(MeshError::Gltf { file: self.file.clone(), reason });
        if std::mem::replace(&mut visited[node.index()], true) {
            return refuse(format!("node {} is reached twice: a scene's nodes must form a tree", node.index()));
        }
        if depth >= MAX_GLTF_DEPTH {
            return refuse(format!("node {} is nested deeper than {MAX_GLTF_DEPTH} levels", node.index()));
        }
        let transform = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                self.add_gltf_primitive(&mesh, &primitive, transform, buffers)?;
            }
        }
        for child in node.children() {
            self.add_gltf_node(&child, transform, buffers, visited, depth + 1)?;
        }
        Ok(())
    }

    fn add_gltf_primitive(
        &mut self,
        mesh: &gltf::Mesh,
        primitive: &gltf::Primitive,
        transform: Mat4,
        buffers: &[gltf::buffer::Data],
    ) -> Result<()> {
        let name = format!("mesh {} primitive {}", mesh.index(), primitive.index());
        if primitive.mode() != gltf::mesh::Mode::Triangles {
            self.warnings.push(format!("{}: {name} is not a triangle list: skipped", self.file));
            return Ok(());
        }
        source::check_gltf_primitive(primitive, buffers, &name)
            .map_err(|reason| MeshError::Gltf { file: self.file.clone(), reason })?;
        let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| d.0.as_slice()));
        let positions: Vec<Vec3> = match reader.read_positions() {
            Some(p) => p.map(|p| transform.transform_point3(Vec3::from(p))).collect(),
            None => return Err(self.layout("POSITION", format!("{name} has no positions"))),
        };
        let uvs: Vec<Vec2> = match reader.read_tex_coords(0) {
            Some(t) => t.into_f32().map(Vec2::from).collect(),
            None => return Err(self.no_uvs(name)),
        };
        let normal_matrix = Mat3::from_mat4(transform).inverse().transpose();
        let normals =
            reader.read_normals().map(|n| n.map(|n| (normal_matrix * Vec3::from(n)).normalize_or_zero()).collect());
        let mut indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None => (0..positions.len() as u32).collect(),
        };
        // A mirroring transform turns counter-clockwise triangles clockwise: restore the winding.
        if transform.determinant() < 0.0 {
            indices.chunks_exact_mut(3).for_each(|t| t.swap(1, 2));
        }
        self.add_part(Part { positions, normals, uvs, indices }, &name)
    }

    fn add_part(&mut self, part: Part, name: &str) -> Result<()> {
        let n = part.positions.len();
        if part.uvs.len() != n {
            return Err(self.layout("uvs", format!("{name} has {} uvs for {n} positions", part.uvs.len())));
        }
        if let Some(k) = part.indices.iter().position(|&i| i as usize >= n) {
            let (file, triangle, index) = (self.file.clone(), k / 3, part.indices[k]);
            return Err(MeshError::IndexOutOfRange { file, triangle, index, count: n });
        }
        let base = self.mesh.positions.len() as u32;
        let normals = part.normals.filter(|v| v.len() == n);
        self.has_normal.extend(std::iter::repeat_n(normals.is_some(), n));
        if normals.is_none() {
            self.warnings.push(format!("{}: {name} has no normals: computed area-weighted vertex normals", self.file));
        }
        self.mesh.normals.extend(normals.unwrap_or_else(|| vec![Vec3::ZERO; n]));
        self.mesh.positions.extend(part.positions);
        self.mesh.uvs.extend(part.uvs);
        self.mesh.indices.extend(part.indices.iter().map(|&i| i + base));
        Ok(())
    }

    fn finish(mut self) -> Result<LoadedMesh> {
        if self.mesh.indices.is_empty() {
            return Err(MeshError::Empty { file: self.file });
        }
        check_finite(&self.file, "position", self.mesh.positions.iter().map(|p| p.to_array().to_vec()))?;
        self.weld_split_vertices();
        self.repair_normals();
        self.mesh.check(&self.file)?;
        Ok(LoadedMesh { mesh: self.mesh, warnings: self.warnings })
    }

    /// Merges the vertices without a normal from the file that share a position and a UV
    /// ([`Mesh::weld`]); vertices with the file's normals are left as the file has them.
    fn weld_split_vertices(&mut self) {
        let mergeable: Vec<bool> = self.has_normal.iter().map(|&h| !h).collect();
        if mergeable.contains(&true) {
            let old = self.mesh.weld(&mergeable);
            self.has_normal = old.iter().map(|&o| self.has_normal[o]).collect();
        }
    }

    /// Fills in missing normals (smooth over equal positions, [`Mesh::smooth_normals`]) and
    /// replaces zero or non-finite ones (loaded normals are renormalised).
    fn repair_normals(&mut self) {
        let computed = self.mesh.smooth_normals();
        let mut repaired = 0usize;
        for (i, n) in self.mesh.normals.iter_mut().enumerate() {
            match n.try_normalize() {
                Some(unit) if self.has_normal[i] => *n = unit,
                _ => {
                    repaired += usize::from(self.has_normal[i]);
                    *n = computed[i];
                }
            }
        }
        if repaired > 0 {
            self.warnings
                .push(format!("{}: {repaired} zero or non-finite normals replaced by computed ones", self.file));
        }
    }

    fn no_uvs(&self, part: String) -> MeshError {
        MeshError::NoUvs { file: self.file.clone(), part }
    }

    fn layout(&self, field: &'static str, reason: String) -> MeshError {
        MeshError::Layout { file: self.file.clone(), field, reason }
    }
}

/// One OBJ model or glTF primitive before merging.
struct Part {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Vec<Vec2>,
    indices: Vec<u32>,
}
