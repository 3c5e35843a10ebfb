//! Charts the project draws itself (plotters): speed against accuracy, log-log.
//!
//! One function, [`draw`], takes named series of `(x, y)` points and writes a PNG and/or an SVG.
//! Files are written atomically (a temporary file in the same folder, then a rename).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

/// One curve: a label for the legend and its points in drawing order.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// Titles and axis kinds.
#[derive(Debug, Clone, PartialEq)]
pub struct ChartSpec {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
}

/// Pixel size of PNG charts (SVGs use the same units).
pub const SIZE: (u32, u32) = (960, 640);

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
            let root = BitMapBackend::new(tmp, size).into_drawing_area();
            what.paint(&root)
                .and_then(|_| root.present().map_err(|e| e.to_string()))
        } else {
            let root = SVGBackend::new(tmp, size).into_drawing_area();
            what.paint(&root)
                .and_then(|_| root.present().map_err(|e| e.to_string()))
        };
        result.map_err(|e| format!("cannot draw chart `{}`: {e}", path.display()))
    })
}

/// Axis range covering the finite points (positive ones only on a log axis), padded.
fn range(values: impl Iterator<Item = f64>, log: bool) -> Result<(f64, f64), String> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && (!log || *v > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return Err(
            "no point can be drawn (no finite value, or none positive on a log axis)".into(),
        );
    }
    Ok(if log {
        let (lo, hi) = if hi / lo < 1.0001 {
            (lo / 2.0, hi * 2.0)
        } else {
            (lo, hi)
        };
        (lo / 1.25, hi * 1.25)
    } else {
        let pad = ((hi - lo) * 0.05).max(hi.abs() * 1e-3).max(1e-12);
        (lo - pad, hi + pad)
    })
}

/// A tick label with at most three significant digits and no float noise.
fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-3..=5).contains(&mag) {
        return format!("{v:.2e}");
    }
    let decimals = (2 - mag).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Tick values of a log axis over `[lo, hi]`: labelled ones (1, 2, 5 times a power of ten, or
/// every integer multiple when fewer than four of those fall inside) and grid-only ones (every
/// integer multiple). plotters' own log ticks leave a range that does not span a whole decade,
/// or the part below its first power of ten, without labels.
fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let mut all = Vec::new();
    let mut decade = 10f64.powf(lo.log10().floor());
    while decade <= hi && all.len() < 1000 {
        for m in 1..=9 {
            let v = m as f64 * decade;
            if v >= lo && v <= hi {
                all.push((m, v));
            }
        }
        decade *= 10.0;
    }
    let nice: Vec<f64> = all
        .iter()
        .filter(|(m, _)| matches!(m, 1 | 2 | 5))
        .map(|&(_, v)| v)
        .collect();
    let every: Vec<f64> = all.iter().map(|&(_, v)| v).collect();
    let labelled = if nice.len() >= 4 { nice } else { every.clone() };
    (labelled, every)
}

fn log_axis(
    (lo, hi): (f64, f64),
) -> plotters::coord::combinators::WithKeyPoints<plotters::coord::combinators::LogCoord<f64>> {
    let (bold, light) = log_ticks(lo, hi);
    (lo..hi)
        .log_scale()
        .with_key_points(bold)
        .with_light_points(light)
}

/// The corner of the plot the legend covers: the one with the fewest points within 45% of the
/// axes' span (on the drawn scale) of it, the upper right on a tie.
fn legend_corner(
    series: &[Series],
    xs: (f64, f64),
    ys: (f64, f64),
    spec: &ChartSpec,
) -> SeriesLabelPosition {
    let frac = |v: f64, (lo, hi): (f64, f64), log: bool| {
        if log {
            (v.ln() - lo.ln()) / (hi.ln() - lo.ln())
        } else {
            (v - lo) / (hi - lo)
        }
    };
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| &s.points)
        .map(|&(x, y)| (frac(x, xs, spec.log_x), frac(y, ys, spec.log_y)))
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    let near = |right: bool, upper: bool| {
        pts.iter()
            .filter(|&&(x, y)| {
                (if right { x > 0.55 } else { x < 0.45 })
                    && (if upper { y > 0.55 } else { y < 0.45 })
            })
            .count()
    };
    [
        (SeriesLabelPosition::UpperRight, near(true, true)),
        (SeriesLabelPosition::UpperLeft, near(false, true)),
        (SeriesLabelPosition::LowerLeft, near(false, false)),
        (SeriesLabelPosition::LowerRight, near(true, false)),
    ]
    .into_iter()
    .min_by_key(|c| c.1)
    .map_or(SeriesLabelPosition::UpperRight, |c| c.0)
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
    let xs = range(
        series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
        spec.log_x,
    )?;
    let ys = range(
        series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
        spec.log_y,
    )?;
    let mut builder = ChartBuilder::on(root);
    builder
        .caption(&spec.title, ("sans-serif", 24))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(80);
    // The four axis kinds are four coordinate types in plotters.
    macro_rules! body {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(&spec.x_label)
                .y_desc(&spec.y_label)
                .x_label_formatter(&|v| tick(*v))
                .y_label_formatter(&|v| tick(*v))
                .draw()
                .map_err(err)?;
            for (i, s) in series.iter().enumerate() {
                let color = Palette99::pick(i).mix(0.9);
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
                chart
                    .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                    .map_err(err)?
                    .label(s.label.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                    });
                chart
                    .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                    .map_err(err)?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(legend_corner(series, xs, ys, spec))
                .draw()
                .map_err(err)?;
        }};
    }
    match (spec.log_x, spec.log_y) {
        (true, true) => body!(
            builder
                .build_cartesian_2d(log_axis(xs), log_axis(ys))
                .map_err(err)?
        ),
        (true, false) => body!(
            builder
                .build_cartesian_2d(log_axis(xs), ys.0..ys.1)
                .map_err(err)?
        ),
        (false, true) => body!(
            builder
                .build_cartesian_2d(xs.0..xs.1, log_axis(ys))
                .map_err(err)?
        ),
        (false, false) => body!(
            builder
                .build_cartesian_2d(xs.0..xs.1, ys.0..ys.1)
                .map_err(err)?
        ),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_label_ranges_that_miss_a_power_of_ten() {
        let (bold, light) = log_ticks(0.0165, 0.44);
        let want = [0.02, 0.05, 0.1, 0.2];
        assert_eq!(bold.len(), want.len(), "{bold:?}");
        assert!(bold.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-12));
        assert_eq!(light.len(), 8 + 4, "0.02..0.09 and 0.1..0.4: {light:?}");
        // Less than a decade: every integer multiple is labelled.
        let (bold, _) = log_ticks(0.25, 0.9);
        assert_eq!(bold.len(), 7);
        assert!((bold[0] - 0.3).abs() < 1e-12 && (bold[6] - 0.9).abs() < 1e-12);
    }

    fn spec() -> ChartSpec {
        ChartSpec {
            title: "error against time".into(),
            x_label: "seconds".into(),
            y_label: "RMSE".into(),
            log_x: true,
            log_y: true,
        }
    }

    fn series() -> Vec<Series> {
        vec![
            Series {
                label: "a".into(),
                points: vec![(0.1, 1.0), (1.0, 0.3), (10.0, 0.1)],
            },
            Series {
                label: "b".into(),
                points: vec![(0.2, 0.5), (2.0, 0.4), (f64::NAN, 0.2)],
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

    #[test]
    fn legend_goes_to_the_emptiest_corner() {
        let at = |pts: Vec<(f64, f64)>| {
            let series = [Series {
                label: "a".into(),
                points: pts,
            }];
            let corner = legend_corner(&series, (1.0, 1000.0), (1.0, 1000.0), &spec());
            format!("{corner:?}")
        };
        // A curve falling from the upper left to the lower right leaves the other two corners
        // free; the upper right is taken first.
        assert_eq!(
            at(vec![(1.5, 900.0), (30.0, 30.0), (900.0, 1.5)]),
            "UpperRight"
        );
        // Points in the upper right (on the log scale) move the legend.
        assert_eq!(
            at(vec![
                (100.0, 100.0),
                (500.0, 900.0),
                (900.0, 500.0),
                (1.5, 1.5)
            ]),
            "UpperLeft"
        );
    }

    #[test]
    fn tick_labels_have_no_float_noise() {
        assert_eq!(tick(0.30000000000000004), "0.3");
        assert_eq!(tick(0.1 + 0.2), "0.3");
        assert_eq!(tick(12.5), "12.5");
        assert_eq!(tick(1234.0), "1234");
        assert_eq!(tick(0.000123), "1.23e-4");
        assert_eq!(tick(2.0), "2");
    }

    #[test]
    fn nothing_drawable_is_an_error_not_a_panic() {
        let dir = tempfile::tempdir().unwrap();
        let bad = vec![Series {
            label: "neg".into(),
            points: vec![(-1.0, -1.0), (f64::INFINITY, 0.0)],
        }];
        assert!(draw(&spec(), &bad, &dir.path().join("x.png")).is_err());
        assert!(draw(&spec(), &series(), &dir.path().join("x.gif")).is_err());
        assert!(draw(&spec(), &[], &dir.path().join("x.svg")).is_err());
    }
}
