//! Charts the project draws itself (plotters): speed against accuracy, log-log.
//!
//! One function, [`draw`], takes named series of `(x, y)` points and writes a PNG and/or an SVG.
//! Files are written atomically (a temporary file in the same folder, then a rename).
//!
//! Series are told apart by colour (a qualitative palette, [`PALETTE`]) and by line style
//! ([`Dash`]); the legend stands to the right of the plot, never over the curves. A chart may
//! mark a floor: a horizontal line below which its values cannot go (e.g. the noise of the
//! reference the errors were measured against).

mod axes;

use std::ops::Range;
use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::combinators::LogCoord;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

/// One curve: a label for the legend and its points in drawing order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Index in [`PALETTE`] (modulo its length); `None`: the series' own index.
    pub colour: Option<usize>,
    pub dash: Dash,
}

/// A line style.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Dash {
    #[default]
    Solid,
    /// Long dashes.
    Dashed,
    /// Short dashes.
    Dotted,
}

/// A horizontal line marking a value the curves cannot go below, with its legend label.
#[derive(Debug, Clone, PartialEq)]
pub struct Floor {
    pub value: f64,
    pub label: String,
}

/// Titles and axis kinds.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ChartSpec {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub floor: Option<Floor>,
}

/// Pixel size of PNG charts (SVGs use the same units), the legend column included.
pub const SIZE: (u32, u32) = (1120, 640);
/// Width of the legend column right of the plot.
const LEGEND_WIDTH: u32 = 230;

/// A qualitative palette (Tableau 10, its yellow darkened to read on white): neighbours
/// differ in hue, none is pale.
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(0x4e, 0x79, 0xa7),
    RGBColor(0xf2, 0x8e, 0x2b),
    RGBColor(0xe1, 0x57, 0x59),
    RGBColor(0x59, 0xa1, 0x4f),
    RGBColor(0x76, 0xb7, 0xb2),
    RGBColor(0xb0, 0x7a, 0xa1),
    RGBColor(0x9c, 0x75, 0x5f),
    RGBColor(0xb8, 0x98, 0x1c),
    RGBColor(0xff, 0x6f, 0x91),
    RGBColor(0x55, 0x55, 0x55),
];

fn colour_of(i: usize, s: &Series) -> RGBColor {
    PALETTE[s.colour.unwrap_or(i) % PALETTE.len()]
}

/// Draws `series` to `path`; the format follows the extension (`.png` or `.svg`).
pub fn draw(spec: &ChartSpec, series: &[Series], path: &Path) -> Result<(), String> {
    write(path, SIZE, &One { spec, series })
}

/// Draws several charts on one page, `cols` side by side, each [`SIZE`] (e.g. an overview of
/// charts that are also written one per file). The format follows the extension.
pub fn draw_panels(
    panels: &[(ChartSpec, Vec<Series>)],
    cols: usize,
    path: &Path,
) -> Result<(), String> {
    if panels.is_empty() {
        return Err(format!("chart `{}`: no chart to draw", path.display()));
    }
    let cols = cols.clamp(1, panels.len());
    let rows = panels.len().div_ceil(cols);
    let size = (SIZE.0 * cols as u32, SIZE.1 * rows as u32);
    write(path, size, &Panels { panels, rows, cols })
}

/// Something drawn onto a drawing area of either backend.
trait Paint {
    fn paint<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static;
}

struct One<'a> {
    spec: &'a ChartSpec,
    series: &'a [Series],
}

impl Paint for One<'_> {
    fn paint<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        plot(root, self.spec, self.series)
    }
}

struct Panels<'a> {
    panels: &'a [(ChartSpec, Vec<Series>)],
    rows: usize,
    cols: usize,
}

impl Paint for Panels<'_> {
    fn paint<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let areas = root.split_evenly((self.rows, self.cols));
        for (area, (spec, series)) in areas.iter().zip(self.panels) {
            plot(area, spec, series)?;
        }
        Ok(())
    }
}

/// Paints a PNG or SVG (by `path`'s extension) of `size` pixels and writes it atomically.
fn write(path: &Path, size: (u32, u32), what: &impl Paint) -> Result<(), String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if ext != "png" && ext != "svg" {
        return Err(format!(
            "chart `{}`: use a .png or .svg file name",
            path.display()
        ));
    }
    crate::atomic_file::write_atomic(path, |tmp, _| {
        let result = if ext == "png" {
            (|| {
                // plotters draws into an RGB buffer; the `image` crate the renderer already uses
                // encodes it (plotters' own encoder would build a second, older `image`).
                let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
                {
                    let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
                    what.paint(&root)
                        .and_then(|_| root.present().map_err(|e| e.to_string()))?;
                }
                image::RgbImage::from_raw(size.0, size.1, rgb)
                    .ok_or_else(|| "chart buffer has the wrong size".to_string())
                    .and_then(|img| {
                        img.save_with_format(tmp, image::ImageFormat::Png)
                            .map_err(|e| e.to_string())
                    })
            })()
        } else {
            let root = SVGBackend::new(tmp, size).into_drawing_area();
            what.paint(&root)
                .and_then(|_| root.present().map_err(|e| e.to_string()))
        };
        result.map_err(|e| format!("cannot draw chart `{}`: {e}", path.display()))
    })
}

/// An axis over `[lo, hi]`, log or linear, with the ticks of [`axes::log_ticks`] or
/// [`axes::linear_ticks`]. One type for both kinds: plotters' chart code is generic over the
/// axis types, and a type per kind would compile all of it once for each of the four pairs.
struct Axis {
    scale: Scale,
    bold: Vec<f64>,
    light: Vec<f64>,
}

enum Scale {
    Log(LogCoord<f64>),
    Linear(RangedCoordf64),
}

fn axis((lo, hi): (f64, f64), log: bool) -> Axis {
    let ((bold, light), scale) = if log {
        (
            axes::log_ticks(lo, hi),
            Scale::Log((lo..hi).log_scale().into()),
        )
    } else {
        (axes::linear_ticks(lo, hi), Scale::Linear((lo..hi).into()))
    };
    Axis { scale, bold, light }
}

impl Ranged for Axis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        match &self.scale {
            Scale::Log(c) => c.map(value, limit),
            Scale::Linear(c) => c.map(value, limit),
        }
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        match &self.scale {
            Scale::Log(c) => c.range(),
            Scale::Linear(c) => c.range(),
        }
    }

    fn axis_pixel_range(&self, limit: (i32, i32)) -> Range<i32> {
        match &self.scale {
            Scale::Log(c) => c.axis_pixel_range(limit),
            Scale::Linear(c) => c.axis_pixel_range(limit),
        }
    }
}

fn plot<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    spec: &ChartSpec,
    series: &[Series],
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    // The title spans the plot and the legend column.
    let below = root.titled(&spec.title, ("sans-serif", 20)).map_err(err)?;
    let width = below.dim_in_pixel().0;
    let (area, legend) = below.split_horizontally(width.saturating_sub(LEGEND_WIDTH));
    let floor = spec
        .floor
        .as_ref()
        .filter(|f| f.value.is_finite() && (!spec.log_y || f.value > 0.0));
    let xs = axes::range(
        series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
        spec.log_x,
    )?;
    let ys = axes::range(
        series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .chain(floor.map(|f| f.value)),
        spec.log_y,
    )?;
    let mut builder = ChartBuilder::on(&area);
    builder
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(80);
    let mut chart = builder
        .build_cartesian_2d(axis(xs, spec.log_x), axis(ys, spec.log_y))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(&spec.x_label)
        .y_desc(&spec.y_label)
        .x_label_formatter(&|v| axes::tick(*v))
        .y_label_formatter(&|v| axes::tick(*v))
        .draw()
        .map_err(err)?;
    if let Some(f) = floor {
        let line = vec![(xs.0, f.value), (xs.1, f.value)];
        chart
            .draw_series(DashedLineSeries::new(
                line,
                6,
                6,
                FLOOR_COLOUR.stroke_width(2),
            ))
            .map_err(err)?;
    }
    for (i, s) in series.iter().enumerate() {
        let color = colour_of(i, s);
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|(x, y)| {
                x.is_finite()
                    && y.is_finite()
                    && (!spec.log_x || *x > 0.0)
                    && (!spec.log_y || *y > 0.0)
            })
            .collect();
        let style = color.stroke_width(2);
        match dash_pattern(s.dash) {
            None => chart
                .draw_series(LineSeries::new(pts.clone(), style))
                .map(|_| ()),
            Some((on, off)) => chart
                .draw_series(DashedLineSeries::new(pts.clone(), on, off, style))
                .map(|_| ()),
        }
        .map_err(err)?;
        chart
            .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))
            .map_err(err)?;
    }
    draw_legend(&legend, series, floor).map_err(err)
}

/// The colour of the floor line.
const FLOOR_COLOUR: RGBColor = RGBColor(0x88, 0x88, 0x88);

/// Dash and gap lengths in pixels (`None`: a solid line).
fn dash_pattern(dash: Dash) -> Option<(u32, u32)> {
    match dash {
        Dash::Solid => None,
        Dash::Dashed => Some((10, 5)),
        Dash::Dotted => Some((3, 4)),
    }
}

/// The legend column: a sample of each line (its colour, style and marker) and its label.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    series: &[Series],
    floor: Option<&Floor>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let row = 22;
    let top = 24;
    let font = ("sans-serif", 15).into_font();
    let mut entries: Vec<(String, RGBColor, Dash, bool)> = series
        .iter()
        .enumerate()
        .map(|(i, s)| (s.label.clone(), colour_of(i, s), s.dash, true))
        .collect();
    if let Some(f) = floor {
        entries.push((f.label.clone(), FLOOR_COLOUR, Dash::Dashed, false));
    }
    for (k, (label, color, dash, marker)) in entries.into_iter().enumerate() {
        let y = top + row * k as i32;
        let (x0, x1) = (8, 44);
        let style = color.stroke_width(2);
        match dash_pattern(dash) {
            None => area.draw(&PathElement::new(vec![(x0, y), (x1, y)], style))?,
            Some((on, off)) => {
                let mut x = x0;
                while x < x1 {
                    let end = (x + on as i32).min(x1);
                    area.draw(&PathElement::new(vec![(x, y), (end, y)], style))?;
                    x = end + off as i32;
                }
            }
        }
        if marker {
            area.draw(&Circle::new(((x0 + x1) / 2, y), 3, color.filled()))?;
        }
        area.draw(&Text::new(
            label,
            (x1 + 8, y - 8),
            font.clone().color(&BLACK),
        ))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> ChartSpec {
        ChartSpec {
            title: "error against time".into(),
            x_label: "seconds".into(),
            y_label: "RMSE".into(),
            log_x: true,
            log_y: true,
            floor: None,
        }
    }

    fn series() -> Vec<Series> {
        vec![
            Series {
                label: "a".into(),
                points: vec![(0.1, 1.0), (1.0, 0.3), (10.0, 0.1)],
                ..Series::default()
            },
            Series {
                label: "b".into(),
                points: vec![(0.2, 0.5), (2.0, 0.4), (f64::NAN, 0.2)],
                dash: Dash::Dashed,
                ..Series::default()
            },
        ]
    }

    #[test]
    fn draws_png_and_svg_and_leaves_no_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("c.png");
        let svg = dir.path().join("c.svg");
        draw(&spec(), &series(), &png).unwrap();
        draw(&spec(), &series(), &svg).unwrap();
        let img = image::open(&png).unwrap();
        assert_eq!((img.width(), img.height()), SIZE);
        // Something other than the white background was drawn.
        let rgb = img.to_rgb8();
        let inked = rgb.pixels().filter(|p| p.0 != [255, 255, 255]).count();
        assert!(inked > 1000, "{inked} non-white pixels");
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.contains("<svg") && text.contains("RMSE"));
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
    }

    #[test]
    fn draws_panels_on_one_page() {
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("p.png");
        let panels = vec![(spec(), series()); 3];
        draw_panels(&panels, 2, &png).unwrap();
        let img = image::open(&png).unwrap();
        assert_eq!((img.width(), img.height()), (2 * SIZE.0, 2 * SIZE.1));
        // The empty fourth panel stays white; the third is drawn.
        let rgb = img.to_rgb8();
        let inked = |x0: u32, y0: u32| {
            (0..SIZE.1)
                .flat_map(|y| (0..SIZE.0).map(move |x| (x, y)))
                .filter(|&(x, y)| rgb.get_pixel(x0 + x, y0 + y).0 != [255, 255, 255])
                .count()
        };
        assert!(inked(0, SIZE.1) > 1000);
        assert_eq!(inked(SIZE.0, SIZE.1), 0);
        assert!(draw_panels(&[], 2, &png).is_err());
    }

    /// Subnormal, huge and equal values on log axes, and values near ±f64::MAX on linear
    /// ones, are drawn (plotters' own tick search never ended on some of these).
    #[test]
    fn extreme_values_are_drawn() {
        let dir = tempfile::tempdir().unwrap();
        let one = |points: Vec<(f64, f64)>| {
            vec![Series {
                label: "x".into(),
                points,
                ..Series::default()
            }]
        };
        let cases = [
            (true, vec![(5e-324, 5e-324), (1e-310, 1.0)]),
            (true, vec![(1e-300, 1e-300), (1e300, f64::MAX)]),
            (true, vec![(5e-324, 2.0), (f64::MAX, 2.0)]),
            (true, vec![(7.0, 7.0)]),
            (false, vec![(-f64::MAX, 0.0), (f64::MAX, 5e-324)]),
            (false, vec![(1.0, 1.0)]),
        ];
        for (i, (log, points)) in cases.into_iter().enumerate() {
            let spec = ChartSpec {
                log_x: log,
                log_y: log,
                ..spec()
            };
            let path = dir.path().join(format!("{i}.svg"));
            draw(&spec, &one(points.clone()), &path).unwrap_or_else(|e| panic!("{points:?}: {e}"));
            assert!(std::fs::metadata(&path).unwrap().len() > 0);
        }
    }

    #[test]
    fn nothing_drawable_is_an_error_not_a_panic() {
        let dir = tempfile::tempdir().unwrap();
        let bad = vec![Series {
            label: "neg".into(),
            points: vec![(-1.0, -1.0), (f64::INFINITY, 0.0)],
            ..Series::default()
        }];
        assert!(draw(&spec(), &bad, &dir.path().join("x.png")).is_err());
        assert!(draw(&spec(), &series(), &dir.path().join("x.gif")).is_err());
        assert!(draw(&spec(), &[], &dir.path().join("x.svg")).is_err());
    }
}
