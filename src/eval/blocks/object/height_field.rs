//! `height_field { png "h.png" | exr "h.exr" | function W, H { f(x, y) } [smooth]
//! [water_level w] }` as POV-Ray writes it: the image read (or the function sampled) into a grid
//! of heights here, its memory counted against the load's limit before it is allocated.

use std::sync::Arc;

use rayon::prelude::*;

use super::ObjectBuilder;
use crate::diag::{Error, SourceResult, short_number, size_text};
use crate::eval::Evaluator;
use crate::eval::value::Value;
use crate::scene::height_field::{grid_bytes, height_grid_from_image};
use crate::scene::{HeightField, HeightGrid, MAX_HEIGHT_FIELD_SIDE, ShapeDecl};

const EXAMPLE: &str = "height_field { png \"terrain.png\" smooth }";

impl ObjectBuilder {
    pub(super) fn height_field(&self, ev: &mut Evaluator) -> SourceResult<ShapeDecl> {
        let grid = match (&self.hf_file, self.values.as_slice()) {
            (Some((path, span)), []) => {
                ev.dependencies.push(path.clone());
                let bytes = ev
                    .options
                    .world
                    .read(path, crate::files::MAX_ASSET_BYTES)
                    .map_err(|e| {
                        vec![
                            Error::new(format!("cannot open image `{}`: {e}", path.display()))
                                .label("cannot load this image")
                                .help(ev.path_help(*span))
                                .at(*span),
                        ]
                    })?;
                let room = ev.memory_left();
                height_grid_from_image(&bytes, path, room).map_err(|e| {
                    vec![
                        Error::new(e.message)
                            .label("cannot use this image")
                            .help(e.help.unwrap_or_else(|| {
                                "give a PNG (8 or 16 bits, grey or colour), JPEG or EXR image"
                                    .into()
                            }))
                            .at(*span),
                    ]
                })?
            }
            (None, [(Value::Function(f), span)]) => {
                let Some((w, h, gspan)) = f.grid else {
                    return Err(vec![
                        Error::new("a height field's function needs the grid it is sampled on")
                            .label("no grid")
                            .help(
                                "write the grid's sides after `function`, as in POV-Ray: \
                                   `function 256, 256 { 0.5 + 0.3 * sin(6 * x) * cos(6 * y) }`",
                            )
                            .at(*span),
                    ]);
                };
                let side = |v: f64| v.is_finite() && v.fract() == 0.0 && v >= 2.0;
                if !(side(w) && side(h)) {
                    return Err(vec![
                        Error::new(format!(
                            "the grid {} x {} is not two whole numbers of at least 2",
                            short_number(w),
                            short_number(h)
                        ))
                        .label("the grid's sides")
                        .help("e.g. `function 256, 256 { ... }`")
                        .at(gspan),
                    ]);
                }
                let max = f64::from(MAX_HEIGHT_FIELD_SIDE);
                if w > max || h > max {
                    return Err(vec![
                        Error::new(format!(
                            "the grid {} x {} is larger than {MAX_HEIGHT_FIELD_SIDE} samples a \
                             side",
                            short_number(w),
                            short_number(h)
                        ))
                        .label("too many samples")
                        .help(format!(
                            "a height field has at most {MAX_HEIGHT_FIELD_SIDE} samples a side"
                        ))
                        .at(gspan),
                    ]);
                }
                let (nx, nz) = (w as u32, h as u32);
                let need = grid_bytes(nx, nz);
                if need > ev.memory_left() {
                    return Err(vec![
                        Error::new(format!(
                            "a grid of {nx} x {nz} heights needs {}, more than the {} left of \
                             the load's memory limit of {}",
                            size_text(need),
                            size_text(ev.memory_left()),
                            size_text(ev.memory_limit())
                        ))
                        .label("too many samples")
                        .help(
                            "use a coarser grid, or raise the limit with `--memory-limit` \
                             (e.g. `--memory-limit 8G`)",
                        )
                        .at(gspan),
                    ]);
                }
                if f.params.len() > 3 {
                    return Err(vec![
                        Error::new(format!(
                            "a height field's function takes x and y, this one takes {} \
                             parameters",
                            f.params.len()
                        ))
                        .label("too many parameters")
                        .help("e.g. `function 64, 64 { x * y }` (x and y run over [0, 1])")
                        .at(*span),
                    ]);
                }
                let code = f.code.clone();
                let n = f.params.len();
                let mut heights = vec![0.0f32; nx as usize * nz as usize];
                heights
                    .par_chunks_mut(nx as usize)
                    .enumerate()
                    .for_each(|(j, row)| {
                        let y = j as f64 / f64::from(nz - 1);
                        for (i, v) in row.iter_mut().enumerate() {
                            let x = i as f64 / f64::from(nx - 1);
                            *v = code.eval(&[x, y, 0.0][..n]).clamp(0.0, 1.0) as f32;
                        }
                    });
                if let Some(k) = heights.iter().position(|h| h.is_nan()) {
                    let (i, j) = (k % nx as usize, k / nx as usize);
                    return Err(vec![
                        Error::new(format!(
                            "the height field's function is NaN at x = {}, y = {}",
                            short_number(i as f64 / f64::from(nx - 1)),
                            short_number(j as f64 / f64::from(nz - 1))
                        ))
                        .label("not a number here")
                        .help("a height is a number in [0, 1]; guard a division or a root")
                        .at(*span),
                    ]);
                }
                HeightGrid { nx, nz, heights }
            }
            _ => {
                return Err(vec![
                    Error::new("a height field takes one image or one function")
                        .label("here")
                        .help(format!(
                            "e.g. `{EXAMPLE}`, or `height_field {{ function 64, 64 {{ x * y }} }}`"
                        ))
                        .at(self.span),
                ]);
            }
        };
        ev.held.height_fields += grid_bytes(grid.nx, grid.nz);
        let water = self.water.map_or(0.0, |w| w.0);
        let top = grid.heights.iter().fold(0.0f32, |m, &h| m.max(h));
        if f64::from(top) <= water {
            let at = self.water.map_or(self.span, |w| w.1);
            return Err(vec![
                Error::new(format!(
                    "the height field lies at or below its water level {} everywhere (its \
                     highest sample is {})",
                    short_number(water),
                    short_number(f64::from(top))
                ))
                .label("nothing above the water")
                .help(
                    "a height field is the solid between the water level and its heights: \
                       lower the level, or check the image (all black?)",
                )
                .at(at),
            ]);
        }
        Ok(ShapeDecl::HeightField(HeightField {
            grid: Arc::new(grid),
            water,
            smooth: self.smooth,
        }))
    }
}
