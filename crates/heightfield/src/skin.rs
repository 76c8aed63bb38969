//! [`Heightfield`]: a rasterised skin surface, heights in millimetres and exact normals, and
//! [`generate`], which builds one from [`SkinParams`].
//!
//! Texel `(col, row)` samples the analytic surface at its centre, `x = (col - (W-1)/2) * s`,
//! `y = ((H-1)/2 - row) * s` (origin at the field's centre, y up while rows grow down), and its
//! normal is `normalize(-dh/dx, -dh/dy, 1)` of the exact gradient there.

use glam::{DVec2, Vec3};
use rayon::prelude::*;
use skinkit_maps::{Grid, NormalMap, ScalarMap};

use crate::params::{SkinParams, texel_to_mm};
use crate::surface::{HeightSample, Surface};
use crate::{Error, Result};

/// A rasterised heightfield with analytic normals.
#[derive(Clone, Debug)]
pub struct Heightfield {
    /// The parameters it was generated from; `None` for fields built by [`Heightfield::from_fn`].
    pub params: Option<SkinParams>,
    /// Texel pitch in millimetres.
    pub mm_per_texel: f64,
    /// Heights in millimetres above the mean plane.
    pub heights: ScalarMap,
    /// Unit normals from the exact gradient.
    pub normals: NormalMap,
}

/// Generates the heightfield of `params`; rows are evaluated in parallel and the result does not
/// depend on the thread count.
///
/// # Errors
/// When `params` fails [`SkinParams::validate`].
pub fn generate(params: &SkinParams) -> Result<Heightfield> {
    let surface = Surface::new(params)?;
    Ok(rasterise(&surface))
}

impl SkinParams {
    /// Same as [`generate`].
    ///
    /// # Errors
    /// When the parameters fail [`SkinParams::validate`].
    pub fn generate(&self) -> Result<Heightfield> {
        generate(self)
    }

    /// The analytic surface of these parameters, for point evaluation.
    ///
    /// # Errors
    /// When the parameters fail [`SkinParams::validate`].
    pub fn surface(&self) -> Result<Surface> {
        Surface::new(self)
    }
}

/// Samples `surface` at every texel centre of its parameters' grid.
pub fn rasterise(surface: &Surface) -> Heightfield {
    let p = surface.params();
    let (w, h) = (p.width, p.height);
    let columns = column_tables(surface);
    let table = surface.waves().table_len();
    let mut heights = vec![0f32; w * h];
    let mut normals = vec![Vec3::ZERO; w * h];
    heights.par_chunks_mut(w).zip(normals.par_chunks_mut(w)).enumerate().for_each(|(row, (hs, ns))| {
        let y = texel_to_mm(w, h, p.mm_per_texel, 0, row).1;
        let row_table = surface.waves().row_table(y);
        for col in 0..w {
            let x = texel_to_mm(w, h, p.mm_per_texel, col, row).0;
            let column = &columns[col * table..(col + 1) * table];
            let s = surface.eval_tabulated(DVec2::new(x, y), column, &row_table);
            hs[col] = s.height as f32;
            ns[col] = s.normal().as_vec3();
        }
    });
    build(Some(p.clone()), p.mm_per_texel, w, h, heights, normals)
}

/// The noise's per-column tables, one after another.
fn column_tables(surface: &Surface) -> Vec<f64> {
    let p = surface.params();
    let mut table = Vec::with_capacity(p.width * surface.waves().table_len());
    for col in 0..p.width {
        surface.waves().column_table(p.texel_to_mm(col, 0).0, &mut table);
    }
    table
}

fn build(
    params: Option<SkinParams>,
    mm_per_texel: f64,
    w: usize,
    h: usize,
    heights: Vec<f32>,
    normals: Vec<Vec3>,
) -> Heightfield {
    let heights = Grid::from_vec(w, h, heights).expect("one height per texel");
    let normals = NormalMap::from_unit_grid(Grid::from_vec(w, h, normals).expect("one normal per texel"))
        .expect("normals of a finite gradient are unit vectors");
    Heightfield { params, mm_per_texel, heights, normals }
}

impl Heightfield {
    /// A field sampled from any height function `f(x_mm, y_mm)` with its exact gradient, on the same
    /// texel grid as generated fields (origin at the centre, y up). Non-finite samples become height
    /// 0 with an invalid normal.
    ///
    /// # Errors
    /// When the size or pitch is invalid (as for [`SkinParams::validate`]).
    pub fn from_fn(
        width: usize,
        height: usize,
        mm_per_texel: f64,
        f: impl Fn(f64, f64) -> HeightSample + Sync,
    ) -> Result<Self> {
        SkinParams::flat(width, height, mm_per_texel, 0).validate()?;
        let samples = Grid::from_fn(width, height, |col, row| {
            let (x, y) = texel_to_mm(width, height, mm_per_texel, col, row);
            f(x, y)
        });
        let mut heights = Vec::with_capacity(samples.len());
        let mut normals = Vec::with_capacity(samples.len());
        for s in samples.as_slice() {
            let ok = s.height.is_finite() && s.gradient.is_finite();
            heights.push(if ok { s.height as f32 } else { 0.0 });
            normals.push(if ok { s.normal().as_vec3() } else { Vec3::ZERO });
        }
        Ok(build(None, mm_per_texel, width, height, heights, normals))
    }

    pub fn width(&self) -> usize {
        self.heights.width()
    }
    pub fn height(&self) -> usize {
        self.heights.height()
    }

    /// Position in millimetres of the centre of texel `(col, row)` (origin at the centre, y up).
    pub fn texel_to_mm(&self, col: usize, row: usize) -> (f64, f64) {
        texel_to_mm(self.width(), self.height(), self.mm_per_texel, col, row)
    }

    /// Checks that heights and normals agree in size and the pitch is usable.
    pub(crate) fn check(&self) -> Result<()> {
        if self.heights.size() != self.normals.size() {
            let (hw, hh) = self.heights.size();
            let (nw, nh) = self.normals.size();
            return Err(Error::invalid("heightfield", format!("heights are {hw}x{hh} but normals {nw}x{nh}")));
        }
        if !(self.mm_per_texel.is_finite() && self.mm_per_texel > 0.0) {
            return Err(Error::invalid("heightfield.mm_per_texel", format!("{} is not positive", self.mm_per_texel)));
        }
        Ok(())
    }
}
