//! Face layouts: which mold grows where on the face map (Haro et al. 2001, section 4.2 and
//! figure 5a: "the regions are defined by a user by selecting a few points (7) on the albedo map").
//!
//! A layout is a TOML file:
//!
//! ```toml
//! size = [4096, 2048]          # output map, width x height (default 4096 x 2048, the paper's)
//! mm_per_texel = 0.05          # physical size of a map texel
//! coverage = "charts.png"      # optional: grey PNG, white where the UV charts hold skin
//!
//! [[region]]
//! name = "forehead"
//! session = "../molds/forehead"      # a capture session folder (photos + rig.toml), or
//! # exemplar = "forehead-normals.png" # an already captured normal map (exactly one of the two)
//! exemplar_mm_per_texel = 0.02
//! points = [[0.5, 0.12]]             # UV in 0..1: u to the right, v = 0 at the TOP row
//! # pixels = [[2048, 245]]           # or texels (column, row), row 0 at the top
//! seed = 11                          # optional synthesis seed of this region
//! ```
//!
//! Coordinates follow the workspace convention (the book, "Formats and conventions"): image row 0
//! at the top, so `v = 0` is the top row. This matches glTF and wgpu UVs; a layout made against
//! an OBJ/OpenGL unwrap (v up) must use `1 - v`. A UV point goes to the texel containing it,
//! `(floor(u * width), floor(v * height))`, clamped so `u = 1` or `v = 1` is the last texel.
//! Pixel points are stored as the UV of their texel's centre, so [`Layout::with_size`] moves them
//! with the map.
//!
//! On the user's own mesh (issue 41), the layout names it and its scale, and `mm_per_texel` is
//! measured per region from the mesh instead ([`crate::surface`]); seed points may then also be
//! 3-D points on the mesh, in mesh units as picked in Blender:
//!
//! ```toml
//! mesh = "head.obj"                  # or .glb/.gltf; `skinkit face --mesh` overrides it
//! mm_per_unit = 10.0                 # mesh units are centimetres
//!
//! [[region]]
//! name = "cheek"
//! exemplar = "cheek.png"
//! exemplar_mm_per_texel = 0.02
//! positions = [[4.1, 2.3, 8.0]]      # nearest surface point, through its triangle's UVs
//! ```
//!
//! Relative paths are resolved against the layout file's folder. Parsing checks everything that
//! needs no file system (sizes, scales, names, points); [`Layout::check_exemplars`] checks that
//! the named exemplars exist, and [`Layout::load`] does both.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Deserialize;
use skinkit_maps::io::{Limits, read_scalar_map};
use skinkit_maps::{Grid, limits};

use crate::partition::SeedPoint;
use crate::surface::Surface;
use crate::udim::Atlas;
use crate::{Error, Result};

/// The paper's map size.
pub const DEFAULT_SIZE: [usize; 2] = [4096, 2048];
/// Largest accepted `width * height` of a face map (a 32768 x 32768 map;
/// [`limits::MAX_MAP_TEXELS`]).
pub const MAX_TEXELS: usize = limits::MAX_MAP_TEXELS as usize;

/// Most regions a layout may have. Each region is grown over its own box (about a second each
/// on a small map), so a few thousand would run for hours; a face has about ten.
pub const MAX_REGIONS: usize = 256;

/// What a layout without `mm_per_texel` is told.
const MISSING_MM_PER_TEXEL: &str = "missing: the physical size of one map texel, in millimetres (pores are \
     grown at this scale); or name the mesh the map goes on (`mesh` and `mm_per_unit`, or `skinkit face \
     --mesh`) to measure it per region";

/// Where a region's exemplar comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ExemplarSource {
    /// A captured normal map (`exemplar = "..."`).
    NormalMap(PathBuf),
    /// A capture session folder to run first (`session = "..."`).
    Session(PathBuf),
}

impl ExemplarSource {
    /// The path, whichever kind.
    pub fn path(&self) -> &Path {
        match self {
            ExemplarSource::NormalMap(p) | ExemplarSource::Session(p) => p,
        }
    }
}

/// One region of the face: a mold and the points it grows from.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    /// Unique name.
    pub name: String,
    /// The exemplar (resolved path).
    pub exemplar: ExemplarSource,
    /// Physical size of an exemplar texel; exemplars are resampled to the map's scale.
    pub exemplar_mm_per_texel: f64,
    /// Seed points as UV, `v = 0` at the top row (pixel points converted to their texel centre;
    /// 3-D points appended by [`Layout::on_surface`]).
    pub points: Vec<[f64; 2]>,
    /// Seed points on the mesh, in mesh units, not yet mapped to UV.
    pub positions: Vec<[f64; 3]>,
    /// Synthesis seed of the region, if the layout fixes one.
    pub seed: Option<u64>,
}

/// A validated face layout.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// The file it came from (for messages).
    pub origin: PathBuf,
    pub width: usize,
    pub height: usize,
    /// Physical size of a map texel: the layout's, or on a mesh the whole mesh's area ratio (0
    /// until [`Layout::on_surface`] measures it; each region's own is measured in `compose`).
    pub mm_per_texel: f64,
    /// Optional coverage mask (resolved path).
    pub coverage: Option<PathBuf>,
    pub regions: Vec<Region>,
    /// The user's mesh (resolved path), if the layout names one.
    pub mesh: Option<PathBuf>,
    /// Millimetres per mesh unit, if the layout gives it.
    pub mm_per_unit: Option<f64>,
    /// The mesh the map is laid out on, once [`Layout::on_surface`] placed it.
    pub surface: Option<Arc<Surface>>,
    /// The mesh's UDIM tiles: the map is their atlas (`width x height` is then the atlas's size).
    pub atlas: Option<Atlas>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLayout {
    size: Option<[i64; 2]>,
    /// Optional here so that its absence is named as such (serde's "missing field" points at
    /// line 1, column 1, issue 41).
    mm_per_texel: Option<f64>,
    coverage: Option<PathBuf>,
    mesh: Option<PathBuf>,
    mm_per_unit: Option<f64>,
    #[serde(default)]
    region: Vec<RawRegion>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRegion {
    name: String,
    exemplar: Option<PathBuf>,
    session: Option<PathBuf>,
    exemplar_mm_per_texel: f64,
    #[serde(default)]
    points: Vec<[f64; 2]>,
    #[serde(default)]
    pixels: Vec<[i64; 2]>,
    #[serde(default)]
    positions: Vec<[f64; 3]>,
    seed: Option<u64>,
}

impl Layout {
    /// Reads, validates and checks the exemplars of a layout file.
    ///
    /// # Errors
    /// When the file cannot be read, [`Layout::parse`] fails or [`Layout::check_exemplars`] fails.
    pub fn load(path: &Path) -> Result<Layout> {
        let text = skinkit_maps::input::read_to_string(path, skinkit_maps::input::Kind::Toml)
            .map_err(skinkit_maps::Error::from)?;
        let layout = Layout::parse(&text, path)?;
        layout.check_exemplars()?;
        Ok(layout)
    }

    /// Parses and validates a layout; `origin` is the file's path, used in messages and to resolve
    /// relative paths (against its folder).
    ///
    /// # Errors
    /// [`Error::Toml`] for bad TOML or unknown keys; [`Error::Layout`] for a zero or too large
    /// size, non-positive scales, no regions, empty or duplicate names, a region with no points
    /// or with both/neither of `exemplar` and `session`, a point outside the map;
    /// [`Error::CoincidentPoints`] for two points on one texel.
    pub fn parse(text: &str, origin: &Path) -> Result<Layout> {
        let raw: RawLayout =
            toml::from_str(text).map_err(|e| Error::Toml { origin: origin.to_owned(), message: e.to_string() })?;
        let ctx = Ctx { origin, base: origin.parent().unwrap_or(Path::new("")) };
        let [width, height] = ctx.size(raw.size)?;
        // On a mesh the scale is measured, so `mm_per_texel` may be left out (0 until then; the
        // mesh may come from `skinkit face --mesh`, so its absence is refused by `check_placed`).
        let mm_per_texel = match raw.mm_per_texel {
            Some(mm) => ctx.positive("mm_per_texel", mm).map(|()| mm)?,
            None => 0.0,
        };
        if let Some(mm) = raw.mm_per_unit {
            ctx.positive("mm_per_unit", mm)?;
        }
        if raw.region.is_empty() {
            return Err(ctx.err("region", "the layout has no [[region]] entries".into()));
        }
        let regions = raw
            .region
            .into_iter()
            .enumerate()
            .map(|(i, r)| ctx.region(i, r, width, height))
            .collect::<Result<Vec<_>>>()?;
        let layout = Layout {
            origin: origin.to_owned(),
            width,
            height,
            mm_per_texel,
            coverage: raw.coverage.map(|p| ctx.base.join(p)),
            regions,
            mesh: raw.mesh.map(|p| ctx.base.join(p)),
            mm_per_unit: raw.mm_per_unit,
            surface: None,
            atlas: None,
        };
        if layout.regions.len() > MAX_REGIONS {
            return Err(ctx.err(
                "region",
                format!("{} regions: at most {MAX_REGIONS} (each is grown on its own)", layout.regions.len()),
            ));
        }
        layout.check_names()?;
        layout.check_coincident()?;
        let points: usize = layout.regions.iter().map(|r| r.points.len()).sum();
        if points > usize::from(u16::MAX) {
            return Err(ctx.err("region", format!("{points} seed points: at most {} (labels are 16-bit)", u16::MAX)));
        }
        Ok(layout)
    }

    /// Checks that every region's exemplar exists: a file for `exemplar`, a folder for `session`
    /// (and the coverage mask, if any, is a file).
    ///
    /// # Errors
    /// [`Error::MissingExemplar`] naming the region and the path.
    pub fn check_exemplars(&self) -> Result<()> {
        for r in &self.regions {
            let (ok, what) = match &r.exemplar {
                ExemplarSource::NormalMap(p) => (p.is_file(), "exemplar normal map"),
                ExemplarSource::Session(p) => (p.is_dir(), "capture session folder"),
            };
            if !ok {
                return Err(self.missing(&r.name, what, r.exemplar.path()));
            }
        }
        match &self.coverage {
            Some(p) if !p.is_file() => Err(self.missing("(coverage)", "coverage mask", p)),
            _ => Ok(()),
        }
    }

    fn missing(&self, region: &str, what: &'static str, path: &Path) -> Error {
        Error::MissingExemplar { origin: self.origin.clone(), region: region.into(), what, path: path.to_owned() }
    }

    /// The same layout for a `width x height` map (`--size`): points keep their UV position and
    /// `mm_per_texel` is scaled by `old width / new width`, so the map still covers the same face.
    ///
    /// # Errors
    /// [`Error::Layout`] for a zero or too large size; [`Error::CoincidentPoints`] when points
    /// that were apart fall on one texel at the new size.
    pub fn with_size(&self, width: usize, height: usize) -> Result<Layout> {
        let ctx = Ctx { origin: &self.origin, base: Path::new("") };
        let [width, height] = ctx.size(Some([width as i64, height as i64]))?;
        let layout = Layout {
            width,
            height,
            mm_per_texel: self.mm_per_texel * self.width as f64 / width as f64,
            ..self.clone()
        };
        layout.check_coincident()?;
        Ok(layout)
    }

    /// The layout on `surface`: every region's 3-D `positions` mapped to the UV of their nearest
    /// surface point and added to its points, and `mm_per_texel` set to the whole mesh's area
    /// ratio (each region's own is measured in [`crate::compose()`]).
    ///
    /// # Errors
    /// When the mesh's UVs span several UDIM tiles ([`crate::udim`]), the map becomes their atlas:
    /// `width x height` are then the atlas's, the layout's size one tile's, and UV `points` address
    /// tile 1001.
    ///
    /// # Errors
    /// [`Error::Layout`] for a position with no nearest UV or an atlas over the size limit;
    /// UVs outside tiles 1001 to 1999; [`Error::CoincidentPoints`] as in [`Layout::parse`].
    pub fn on_surface(&self, mut surface: Surface) -> Result<Layout> {
        let mut layout = self.clone();
        let atlas = Atlas::new(&surface.origin, &surface.uv_centroids(), self.width, self.height)?;
        if !atlas.is_single_1001() {
            // Several tiles (or another one): the map becomes their atlas, UVs follow.
            let [width, height] = Ctx { origin: &self.origin, base: Path::new("") }
                .size(Some([atlas.size().0 as i64, atlas.size().1 as i64]))
                .map_err(|e| {
                    self.err("mesh", format!("{} UDIM tiles of {}x{}: {e}", atlas.tiles.len(), self.width, self.height))
                })?;
            (layout.width, layout.height) = (width, height);
            surface.uvs.iter_mut().for_each(|uv| *uv = atlas.to_atlas(*uv));
            layout.regions.iter_mut().flat_map(|r| r.points.iter_mut()).for_each(|uv| *uv = atlas.to_atlas(*uv));
        }
        for r in &mut layout.regions {
            for (i, &p) in r.positions.iter().enumerate() {
                let uv = surface.nearest_uv(p).filter(|uv| uv.iter().all(|t| (0.0..=1.0).contains(t)));
                let Some(uv) = uv else {
                    let message = format!("position {} {p:?} has no point of the mesh with a UV", i + 1);
                    return Err(self.err(&format!("region `{}`: positions", r.name), message));
                };
                r.points.push(uv);
            }
            r.positions.clear();
        }
        // One label for the whole map: every triangle counts; on a 1x1 map a texel is the UV square.
        let Some(all) = surface.region_scales(&Grid::filled(1, 1, 0u16), 1)[0] else {
            return Err(self.err("mesh", "the mesh has no surface area on its UVs: no scale can be measured".into()));
        };
        layout.mm_per_texel = all.mm_per_texel / ((layout.width * layout.height) as f64).sqrt();
        layout.surface = Some(Arc::new(surface));
        layout.atlas = Some(atlas);
        layout.check_coincident()?;
        Ok(layout)
    }

    fn err(&self, field: &str, message: String) -> Error {
        Error::Layout { origin: self.origin.clone(), field: field.into(), message }
    }

    /// Refuses 3-D points that no mesh placed ([`Layout::on_surface`]), and a layout with neither
    /// `mm_per_texel` nor a mesh to measure it on.
    ///
    /// # Errors
    /// [`Error::Layout`] naming the region or `mm_per_texel`.
    pub fn check_placed(&self) -> Result<()> {
        if let Some(r) = self.regions.iter().find(|r| !r.positions.is_empty()) {
            let message =
                "3-D points need the mesh they lie on: give `mesh` and `mm_per_unit`, or `skinkit face --mesh`";
            let field = format!("region `{}`: positions", r.name);
            return Err(Error::Layout { origin: self.origin.clone(), field, message: message.into() });
        }
        if self.surface.is_none() && self.mm_per_texel <= 0.0 {
            let (origin, message) = (self.origin.clone(), MISSING_MM_PER_TEXEL.into());
            return Err(Error::Layout { origin, field: "mm_per_texel".into(), message });
        }
        Ok(())
    }

    /// The seed points as texels, in layout order (region by region, point by point).
    pub fn seed_points(&self) -> Vec<SeedPoint> {
        self.regions
            .iter()
            .enumerate()
            .flat_map(|(region, r)| r.points.iter().map(move |&uv| (region, uv)))
            .map(|(region, uv)| {
                let [x, y] = uv_to_texel(uv, self.width, self.height);
                SeedPoint { region, x, y }
            })
            .collect()
    }

    /// Reads the coverage mask (if any): true where the grey value is above one half.
    ///
    /// # Errors
    /// When the image cannot be read or is not `width x height`.
    /// The size is compared from the file's header, before anything is decoded (a small PNG can
    /// claim 32768 x 32768 pixels).
    /// The files a face from this layout reads: the layout itself, its coverage mask and its
    /// normal-map exemplars (a session exemplar is a folder, captured first; its files are the
    /// capture's inputs).
    pub fn input_files(&self) -> Vec<PathBuf> {
        let exemplars = self.regions.iter().filter_map(|r| match &r.exemplar {
            ExemplarSource::NormalMap(p) => Some(p.clone()),
            ExemplarSource::Session(_) => None,
        });
        let mut files: Vec<PathBuf> = std::iter::once(self.origin.clone())
            .chain(self.coverage.clone())
            .chain(self.mesh.clone())
            .chain(exemplars)
            .collect();
        files.sort();
        files.dedup();
        files
    }

    pub fn load_coverage(&self) -> Result<Option<Grid<bool>>> {
        let Some(path) = &self.coverage else { return Ok(None) };
        let header = limits::image_header(path, MAX_TEXELS as u64)?;
        if (header.width, header.height) != (self.width as u64, self.height as u64) {
            return Err(Error::Layout {
                origin: self.origin.clone(),
                field: "coverage".into(),
                message: format!(
                    "{} is {}x{} but the map is {}x{}",
                    path.display(),
                    header.width,
                    header.height,
                    self.width,
                    self.height
                ),
            });
        }
        let map = read_scalar_map(path, &Limits { max_pixels: MAX_TEXELS as u64 })?;
        Ok(Some(map.map(|&v| v > 0.5)))
    }

    fn check_names(&self) -> Result<()> {
        let mut seen = HashMap::new();
        for (i, r) in self.regions.iter().enumerate() {
            if let Some(first) = seen.insert(r.name.as_str(), i) {
                let message = format!("regions {} and {} are both named `{}`", first + 1, i + 1, r.name);
                return Err(Error::Layout { origin: self.origin.clone(), field: "region.name".into(), message });
            }
        }
        Ok(())
    }

    /// Refuses two points on one texel (of the same region or of two).
    fn check_coincident(&self) -> Result<()> {
        let mut seen: HashMap<[u32; 2], (usize, usize)> = HashMap::new();
        for (ri, r) in self.regions.iter().enumerate() {
            for (pi, &uv) in r.points.iter().enumerate() {
                let texel = uv_to_texel(uv, self.width, self.height);
                if let Some((rj, pj)) = seen.insert(texel, (ri, pi)) {
                    return Err(Error::CoincidentPoints {
                        origin: self.origin.clone(),
                        first: self.regions[rj].name.clone(),
                        first_point: pj + 1,
                        second: r.name.clone(),
                        second_point: pi + 1,
                        x: texel[0],
                        y: texel[1],
                        width: self.width,
                        height: self.height,
                    });
                }
            }
        }
        Ok(())
    }
}

/// The texel containing UV point `uv` (`v = 0` at the top), clamped to the map.
pub fn uv_to_texel(uv: [f64; 2], width: usize, height: usize) -> [u32; 2] {
    let texel = |t: f64, n: usize| ((t * n as f64).floor().max(0.0) as usize).min(n - 1) as u32;
    [texel(uv[0], width), texel(uv[1], height)]
}

/// The UV of texel `(x, y)`'s centre.
pub fn texel_to_uv(x: u32, y: u32, width: usize, height: usize) -> [f64; 2] {
    [(f64::from(x) + 0.5) / width as f64, (f64::from(y) + 0.5) / height as f64]
}

/// Validation context: the file and the folder relative paths start from.
struct Ctx<'a> {
    origin: &'a Path,
    base: &'a Path,
}

impl Ctx<'_> {
    fn err(&self, field: &str, message: String) -> Error {
        Error::Layout { origin: self.origin.to_owned(), field: field.into(), message }
    }

    fn size(&self, size: Option<[i64; 2]>) -> Result<[usize; 2]> {
        let [w, h] = size.unwrap_or(DEFAULT_SIZE.map(|s| s as i64));
        if w <= 0 || h <= 0 {
            return Err(self.err("size", format!("{w}x{h} must have positive width and height")));
        }
        let (w, h) = (w as usize, h as usize);
        if w.saturating_mul(h) > MAX_TEXELS {
            return Err(self.err("size", format!("{w}x{h} exceeds the limit of {MAX_TEXELS} texels")));
        }
        Ok([w, h])
    }

    fn positive(&self, field: &str, value: f64) -> Result<()> {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(self.err(field, format!("{value} must be a finite number > 0 (millimetres)")))
        }
    }

    fn region(&self, index: usize, raw: RawRegion, width: usize, height: usize) -> Result<Region> {
        let label = if raw.name.trim().is_empty() { format!("region {}", index + 1) } else { raw.name.clone() };
        let field = |key: &str| format!("region `{label}`: {key}");
        if raw.name.trim().is_empty() {
            return Err(self.err(&field("name"), "must not be empty".into()));
        }
        // The name becomes the file name of the region's exemplar in a face folder.
        skinkit_maps::names::check(&raw.name).map_err(|e| self.err(&field("name"), e.to_string()))?;
        self.positive(&field("exemplar_mm_per_texel"), raw.exemplar_mm_per_texel)?;
        let exemplar = match (raw.exemplar, raw.session) {
            (Some(p), None) => ExemplarSource::NormalMap(self.base.join(p)),
            (None, Some(p)) => ExemplarSource::Session(self.base.join(p)),
            (Some(_), Some(_)) => {
                return Err(self.err(&field("exemplar"), "give `exemplar` or `session`, not both".into()));
            }
            (None, None) => {
                return Err(self.err(
                    &field("exemplar"),
                    "missing: give `exemplar` (a normal map) or `session` (a capture folder)".into(),
                ));
            }
        };
        let mut points = Vec::new();
        for (i, &[u, v]) in raw.points.iter().enumerate() {
            if !(u.is_finite() && v.is_finite() && (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)) {
                return Err(self.err(
                    &field("points"),
                    format!("point {} ({u}, {v}) lies outside the map: UV must be in 0..1", i + 1),
                ));
            }
            points.push([u, v]);
        }
        for (i, &[x, y]) in raw.pixels.iter().enumerate() {
            if x < 0 || y < 0 || x as usize >= width || y as usize >= height {
                let message = format!("pixel {} ({x}, {y}) lies outside the {width}x{height} map", i + 1);
                return Err(self.err(&field("pixels"), message));
            }
            points.push(texel_to_uv(x as u32, y as u32, width, height));
        }
        if let Some(i) = raw.positions.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
            return Err(self.err(&field("positions"), format!("position {} is not finite", i + 1)));
        }
        if points.is_empty() && raw.positions.is_empty() {
            let message = "no seed points: give `points` (UV), `pixels` or `positions` (3-D, on a mesh)";
            return Err(self.err(&field("points"), message.into()));
        }
        Ok(Region {
            name: raw.name,
            exemplar,
            exemplar_mm_per_texel: raw.exemplar_mm_per_texel,
            points,
            positions: raw.positions,
            seed: raw.seed,
        })
    }
}
