//! The chart's files: the CSV table (also read back by `--from-csv`) and the charts drawn
//! from it (PNG and SVG).
//!
//! The CSV has one row per measurement, `method,iterations,seconds,rmse,rel_mse,window_rmse,
//! window_rel_mse`, after `# scene: NAME` and `# reference: NAME` comment lines; the
//! reference's noise floor, when known, is a row named [`FLOOR_ROW`] (iterations and seconds 0).

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use sppm_lang::internals::chart::{ChartSpec, Floor, Series, draw};

use super::{Errors, Row, rank_of, style_of};

/// The CSV's columns.
const COLUMNS: [&str; 7] = [
    "method",
    "iterations",
    "seconds",
    "rmse",
    "rel_mse",
    "window_rmse",
    "window_rel_mse",
];

/// The CSV row that holds the reference's noise floor.
pub const FLOOR_ROW: &str = "reference-noise";

/// The reference's noise floor on the whole image and the window, when known.
#[derive(Default, Clone, Copy)]
pub struct Floors {
    pub whole: Option<Errors>,
    pub window: Option<Errors>,
}

/// Everything a chart is drawn from.
pub struct Table {
    pub scene: String,
    pub reference: String,
    pub rows: Vec<Row>,
    pub floors: Floors,
    pub has_window: bool,
}

/// Reads a CSV written by [`write_outputs`].
pub fn read_csv(path: &Path) -> Result<Table, String> {
    // As a scene is read: a FIFO would block, /dev/zero would fill the memory.
    let text =
        sppm_lang::internals::files::read_text(path, sppm_lang::internals::files::MAX_SOURCE_BYTES)
            .map_err(|e| e.with_path(path))?;
    let mut table = Table {
        scene: String::new(),
        reference: String::new(),
        rows: Vec::new(),
        floors: Floors::default(),
        has_window: false,
    };
    for (n, line) in text.lines().enumerate().skip(1) {
        if let Some(comment) = line.strip_prefix('#') {
            let comment = comment.trim();
            if let Some(v) = comment.strip_prefix("scene:") {
                table.scene = v.trim().to_string();
            } else if let Some(v) = comment.strip_prefix("reference:") {
                table.reference = v.trim().to_string();
            }
            continue;
        }
        let bad = || format!("{}:{}: not a chart row: `{line}`", path.display(), n + 1);
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 7 {
            return Err(bad());
        }
        let is_floor = f[0] == FLOOR_ROW;
        // A time is positive (the floor row's is 0); an error is 0 or more (0: the images were
        // equal, a point the log-log chart leaves off).
        let num = |col: usize| -> Result<f64, String> {
            let text = f[col].trim();
            let v: f64 = text.parse().map_err(|_| bad())?;
            let time = col == 2 && !is_floor;
            if !v.is_finite() || v < 0.0 || (time && v == 0.0) {
                return Err(format!(
                    "{}:{}: column {} ({}) holds `{text}`, which a chart cannot draw: {} must \
                     be a finite number {}",
                    path.display(),
                    n + 1,
                    col + 1,
                    COLUMNS[col],
                    if time { "a time" } else { "an error" },
                    if time { "above 0" } else { "of 0 or more" },
                ));
            }
            Ok(v)
        };
        let window = if f[5].is_empty() {
            None
        } else {
            table.has_window = true;
            Some(Errors {
                rmse: num(5)?,
                rel_mse: num(6)?,
            })
        };
        let whole = Errors {
            rmse: num(3)?,
            rel_mse: num(4)?,
        };
        let seconds = num(2)?;
        if is_floor {
            table.floors = Floors {
                whole: Some(whole),
                window,
            };
            continue;
        }
        table.rows.push(Row {
            method: f[0].to_string(),
            iterations: f[1].trim().parse().map_err(|_| {
                format!(
                    "{}:{}: column 2 (iterations) holds `{}`, which is not a whole number of 0 \
                     or more",
                    path.display(),
                    n + 1,
                    f[1]
                )
            })?,
            seconds,
            whole,
            window,
        });
    }
    if table.rows.is_empty() {
        return Err(format!("`{}` has no rows", path.display()));
    }
    Ok(table)
}

/// Every file [`write_outputs`] writes for `output`: the CSV, then a PNG and an SVG per chart
/// (the window's charts only when `has_window`).
pub fn output_files(output: &Path, has_window: bool) -> Vec<PathBuf> {
    let suffixes: &[&str] = if has_window {
        &["", "_relmse", "_window", "_window_relmse"]
    } else {
        &["", "_relmse"]
    };
    let mut files = vec![output.with_extension("csv")];
    for suffix in suffixes {
        for ext in ["png", "svg"] {
            files.push(sibling(output, suffix, ext));
        }
    }
    files
}

fn sibling(path: &Path, suffix: &str, ext: &str) -> PathBuf {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("chart");
    path.with_file_name(format!("{stem}{suffix}.{ext}"))
}

fn csv_line(
    csv: &mut String,
    method: &str,
    iterations: u32,
    seconds: f64,
    whole: Errors,
    window: Option<Errors>,
) {
    let (wr, wm) = window.map_or((String::new(), String::new()), |w| {
        (format!("{:.6e}", w.rmse), format!("{:.6e}", w.rel_mse))
    });
    let _ = writeln!(
        csv,
        "{method},{iterations},{seconds:.6e},{:.6e},{:.6e},{wr},{wm}",
        whole.rmse, whole.rel_mse
    );
}

/// Writes the CSV beside `output` and the charts: RMSE and relative MSE, on the whole image
/// and (when measured) the window.
pub fn write_outputs(output: &Path, table: &Table) -> Result<(), String> {
    let mut csv = COLUMNS.join(",") + "\n";
    // Commas would split the comment's field in a spreadsheet; they are not in file names we
    // write, and a name with one still reads back (the comment is one line).
    let _ = writeln!(csv, "# scene: {}", table.scene);
    let _ = writeln!(csv, "# reference: {}", table.reference);
    if let Some(f) = table.floors.whole {
        csv_line(&mut csv, FLOOR_ROW, 0, 0.0, f, table.floors.window);
    }
    for r in &table.rows {
        csv_line(
            &mut csv,
            &r.method,
            r.iterations,
            r.seconds,
            r.whole,
            r.window,
        );
    }
    type Pick = fn(&Errors) -> f64;
    let rmse: Pick = |e| e.rmse;
    let rel: Pick = |e| e.rel_mse;
    let mut charts: Vec<(&str, &str, &str, bool, Pick)> = vec![
        ("", "RMSE (whole image)", "RMSE", false, rmse),
        (
            "_relmse",
            "relative MSE (whole image)",
            "relative MSE",
            false,
            rel,
        ),
    ];
    if table.has_window {
        charts.push(("_window", "RMSE (window)", "RMSE", true, rmse));
        charts.push((
            "_window_relmse",
            "relative MSE (window)",
            "relative MSE",
            true,
            rel,
        ));
    }
    // The methods in the table's order (the integrators, then SPPM's variations), then any
    // others in the order met.
    let mut labels: Vec<&str> = Vec::new();
    for r in &table.rows {
        if !labels.contains(&r.method.as_str()) {
            labels.push(&r.method);
        }
    }
    labels.sort_by_key(|l| rank_of(l));
    // Every chart is planned before any file is written: one that cannot be drawn leaves the
    // CSV and the charts of an earlier run as they were.
    let mut plans = Vec::new();
    for (suffix, title, y_label, in_window, pick) in charts {
        let errors = |r: &Row| if in_window { r.window } else { Some(r.whole) };
        let series: Vec<Series> = labels
            .iter()
            .map(|l| {
                let (colour, dash) = style_of(l).unzip();
                Series {
                    label: (*l).to_string(),
                    points: table
                        .rows
                        .iter()
                        .filter(|r| r.method == *l)
                        .filter_map(|r| errors(r).map(|e| (r.seconds, pick(&e))))
                        .filter(|(t, v)| *t > 0.0 && *v > 0.0)
                        .collect(),
                    colour,
                    dash: dash.unwrap_or_default(),
                }
            })
            .filter(|s| !s.points.is_empty())
            .collect();
        let floor = if in_window {
            table.floors.window
        } else {
            table.floors.whole
        };
        let mut names = Vec::new();
        if !table.scene.is_empty() {
            names.push(table.scene.clone());
        }
        if !table.reference.is_empty() {
            names.push(format!("reference {}", table.reference));
        }
        let spec = ChartSpec {
            title: if names.is_empty() {
                format!("{title} against time")
            } else {
                format!("{title} against time: {}", names.join(", "))
            },
            x_label: "seconds of rendering".into(),
            y_label: y_label.into(),
            log_x: true,
            log_y: true,
            floor: floor.map(|f| Floor {
                value: pick(&f),
                label: "reference noise".into(),
            }),
        };
        let drawable = series
            .iter()
            .flat_map(|s| &s.points)
            .any(|(t, v)| t.is_finite() && v.is_finite());
        if !drawable {
            return Err(format!(
                "no point of the {title} chart can be drawn (no finite value, or none positive \
                 on a log axis); nothing was written"
            ));
        }
        plans.push((suffix, spec, series));
    }
    write_atomic(&output.with_extension("csv"), &csv)?;
    for (suffix, spec, series) in plans {
        for ext in ["png", "svg"] {
            draw(&spec, &series, &sibling(output, suffix, ext))?;
        }
    }
    Ok(())
}

fn write_atomic(path: &Path, text: &str) -> Result<(), String> {
    sppm_lang::internals::atomic_file::write_atomic(path, |_, f| {
        f.write_all(text.as_bytes())
            .map_err(|e| format!("cannot write `{}`: {e}", path.display()))
    })
}
