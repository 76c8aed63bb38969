//! A face: every region of a placed [`Layout`] grown from its exemplar and stitched
//! ([`Face::build`]), the report that describes it ([`FaceReport`]), and its folder of files
//! ([`files`]). Exemplars come from the layout's sources: normal maps are read here, capture
//! sessions are captured by the caller's function (capture is another crate's work), each
//! session folder once ([`ExemplarCache`]).

pub mod files;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;
use skinkit_maps::io::{self, Limits};
use skinkit_maps::{NormalEncoding, NormalMap};
use skinkit_synth::SynthConfig;

use crate::compose::{ComposeSeconds, RegionReport};
use crate::curve::CurveParams;
use crate::layout::{ExemplarSource, Layout};
use crate::seam::SeamReport;
use crate::{ComposeOptions, Composed, Error, Result, compose};

/// How a face is grown and stitched (what `skinkit stitch` and `skinkit face` take as flags).
#[derive(Clone, Debug)]
pub struct FaceOptions {
    /// Seed of the curves and of every region's synthesis.
    pub seed: u64,
    /// Spline levels (`None`: from the narrowest region, at most 6).
    pub levels: Option<usize>,
    /// Largest displacement of the boundary curves in texels (`None`: 64 at 4096 wide, scaled
    /// with the map; 0: straight boundaries).
    pub curve_amplitude: Option<f64>,
    /// Blend across boundaries with the spline (`false`: hard boundaries).
    pub blend: bool,
    /// Band width of the seam metric, texels.
    pub seam_band: usize,
    /// Grow the regions with the scanline start instead of the upsampled one.
    pub scanline: bool,
    /// Working-memory limit of the whole build, bytes.
    pub memory_limit: u64,
}

impl Default for FaceOptions {
    fn default() -> Self {
        FaceOptions {
            seed: 0,
            levels: None,
            curve_amplitude: None,
            blend: true,
            seam_band: 4,
            scanline: false,
            memory_limit: SynthConfig::default().memory_limit,
        }
    }
}

/// Captured sessions by (canonical) folder, so a mold used by several regions, or already
/// captured by the caller, is captured once.
pub type ExemplarCache = BTreeMap<PathBuf, NormalMap>;

/// Captures a session folder into its normal map (the caller's capture, with its options); the
/// second argument names the region that asked for it.
pub type Capture<'a> = dyn FnMut(&Path, &str) -> std::result::Result<NormalMap, BoxError> + 'a;

/// Any error a caller's capture returns, kept as the cause of [`Error::Exemplar`].
pub type BoxError = Box<dyn std::error::Error + Send + Sync>;

/// A stitched face in memory, with what its report needs.
pub struct Face {
    pub layout: Layout,
    /// Each region's exemplar, in the layout's order.
    pub exemplars: Vec<NormalMap>,
    pub composed: Composed,
    /// The curve amplitude used, texels.
    pub amplitude: f64,
    pub options: FaceOptions,
    /// Reading and capturing the exemplars.
    pub seconds_exemplars: f64,
}

impl Face {
    /// Grows and stitches `layout` (already sized and, on a mesh, placed on its surface): the
    /// map's memory is checked before any exemplar is read or captured; `progress` is told as
    /// [`crate::compose::compose`] tells it.
    pub fn build(
        layout: Layout,
        options: &FaceOptions,
        cache: &mut ExemplarCache,
        capture: &mut Capture,
        progress: &dyn skinkit_maps::progress::Progress,
    ) -> Result<Face> {
        layout.check_placed()?;
        let amplitude = options.curve_amplitude.unwrap_or_else(|| ComposeOptions::default_amplitude(layout.width));
        let synth = if options.scanline { SynthConfig::scanline(0, 0) } else { SynthConfig::default() };
        let compose_options = ComposeOptions {
            curve: CurveParams::new(amplitude, options.seed),
            levels: options.levels,
            blend: options.blend,
            synth: SynthConfig { memory_limit: options.memory_limit, ..synth },
            seed: options.seed,
            seam_band: options.seam_band,
        };
        crate::compose::check_memory(&layout, &compose_options)?;
        let t = Instant::now();
        let exemplars = exemplars(&layout, cache, capture)?;
        let seconds_exemplars = t.elapsed().as_secs_f64();
        // Each region's synthesis takes as many pyramid levels as its exemplar allows; the report
        // keeps what each region's synthesis adjusted (`regions[].warnings`).
        let composed = compose(&layout, &exemplars, &compose_options, progress)?;
        Ok(Face { layout, exemplars, composed, amplitude, options: options.clone(), seconds_exemplars })
    }

    /// The report of this face, whose normal map is `out`; `write` and `total` are the seconds
    /// the files and the whole run took (the height files' figures are the caller's to add).
    pub fn report(&self, out: &Path, write: f64, total: f64) -> FaceReport {
        let c = &self.composed;
        let layout = &self.layout;
        FaceReport {
            layout: layout.origin.display().to_string(),
            out: out.display().to_string(),
            width: layout.width,
            height: layout.height,
            mm_per_texel: layout.mm_per_texel,
            levels: c.levels,
            curve_amplitude: self.amplitude,
            blend: self.options.blend,
            start: if self.options.scanline { "scanline" } else { "upsampled" }.to_owned(),
            seed: self.options.seed,
            regions: c.regions.clone(),
            udim_tiles: layout.atlas.as_ref().filter(|a| !a.is_single_1001()).map(|a| a.tiles.clone()),
            regions_at_once: c.regions_at_once,
            seams: c.seams.clone(),
            seconds: FaceSeconds {
                exemplars: self.seconds_exemplars,
                compose: c.seconds.clone(),
                write,
                height: 0.0,
                total,
            },
            height_map: None,
            peak_memory_mib: None,
        }
    }
}

/// Each region's exemplar: a normal map read from disk, or a session captured (once per folder).
fn exemplars(layout: &Layout, cache: &mut ExemplarCache, capture: &mut Capture) -> Result<Vec<NormalMap>> {
    let fail = |region: &str, what: String, source: BoxError| Error::Exemplar {
        origin: layout.origin.clone(),
        region: region.to_owned(),
        what,
        source,
    };
    let mut maps = Vec::with_capacity(layout.regions.len());
    for region in &layout.regions {
        let map = match &region.exemplar {
            ExemplarSource::NormalMap(path) => io::read_normal_map(path, NormalEncoding::default(), &Limits::default())
                .map_err(|e| fail(&region.name, "cannot read its exemplar".into(), e.into()))?,
            ExemplarSource::Session(dir) => {
                let key = dir.canonicalize().unwrap_or_else(|_| dir.clone());
                if let Some(map) = cache.get(&key) {
                    map.clone()
                } else {
                    let map = capture(dir, &region.name)
                        .map_err(|e| fail(&region.name, format!("cannot capture {}", dir.display()), e))?;
                    cache.insert(key, map.clone());
                    map
                }
            }
        };
        maps.push(map);
    }
    Ok(maps)
}

/// Seconds per stage of a face.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FaceSeconds {
    /// Reading exemplar maps and capturing sessions.
    pub exemplars: f64,
    #[serde(flatten)]
    pub compose: ComposeSeconds,
    pub write: f64,
    /// Integrating the face's height and writing its files (beside the normal maps' writing).
    pub height: f64,
    pub total: f64,
}

/// What `stitch --report`, `--json` and a face folder's report.json hold.
#[derive(Clone, Debug, Serialize)]
pub struct FaceReport {
    pub layout: String,
    pub out: String,
    pub width: usize,
    pub height: usize,
    pub mm_per_texel: f64,
    pub levels: usize,
    pub curve_amplitude: f64,
    pub blend: bool,
    /// How the regions were grown: `upsampled` (the default) or `scanline`.
    pub start: String,
    pub seed: u64,
    pub regions: Vec<RegionReport>,
    /// On a mesh over several UDIM tiles: their numbers (one `normal.<tile>.png` each; `width x
    /// height` and the height files are then the tiles' atlas, side by side, higher v on top).
    pub udim_tiles: Option<Vec<u32>>,
    /// Regions grown at once: all, or 1 when their estimates do not fit the memory limit together.
    pub regions_at_once: usize,
    pub seams: SeamReport,
    pub seconds: FaceSeconds,
    /// The face's height in mm (height.exr, height.png, cavity.png, bands.exr).
    pub height_map: Option<files::FaceHeight>,
    /// The process's peak resident memory, where the platform tells it.
    pub peak_memory_mib: Option<f64>,
}
