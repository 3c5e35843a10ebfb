//! `sppm_measure::bezier` end to end on a small ray set: the measurement, its CSV and its charts.
//! (The full run is `cargo run --release -p sppm-measure -- bezier`; its numbers are in docs/measurements.md.)

use sppm_lang::internals::chart::SIZE;
use sppm_measure::bezier::{Method, Options, Row, Surface, charts, csv, run, write_outputs};

fn small() -> Options {
    Options {
        rays: 150,
        repeats: 1,
        seed: 7,
        lathe_newton: vec![(4, 16)],
        patch_newton: vec![(9, 16)],
        lathe_grids: vec![(2, 8), (8, 32), (32, 128)],
        patch_grids: vec![(4, 4), (16, 16), (64, 64)],
    }
}

fn all_row(rows: &[Row], surface: Surface, method: Method) -> &Row {
    rows.iter()
        .find(|r| r.surface == surface && r.method == method && r.kind == "all")
        .unwrap_or_else(|| panic!("no row for {surface:?} {method:?}"))
}

#[test]
fn measures_every_method_against_the_reference_and_writes_csv_and_charts() {
    let opts = small();
    let rows = run(&opts, &|_| {}).unwrap();

    for (surface, kinds, newton, grids) in [
        (Surface::Revolve, 3, opts.lathe_newton[0], &opts.lathe_grids),
        (Surface::Patch, 2, opts.patch_newton[0], &opts.patch_grids),
    ] {
        let name = surface.name();
        let robust = all_row(&rows, surface, Method::Robust);
        assert_eq!(robust.rays, kinds * opts.rays);
        assert!(
            robust.ref_hits * 4 >= robust.rays,
            "{name}: rays must mostly hit"
        );
        assert!(robust.ambiguous * 100 <= robust.rays, "{name}: {robust:?}");
        // The robust method agrees with the reference, up to the f32 t of the renderer.
        assert_eq!(
            (robust.misses, robust.false_hits),
            (0, 0),
            "{name}: {robust:?}"
        );
        assert!(robust.t_err_max < 1e-6, "{name}: {robust:?}");
        assert_eq!(robust.time_vs_robust, 1.0);
        assert!(robust.ns_per_ray > 0.0 && robust.ns_per_ray.is_finite());
        let (starts, iterations) = newton;
        let nt = all_row(&rows, surface, Method::Newton { starts, iterations });
        assert_eq!(nt.rays, robust.rays);
        assert_eq!(nt.ref_hits, robust.ref_hits, "same rays, same reference");
        // A finer mesh has more triangles and follows the surface more closely.
        let meshes: Vec<&Row> = grids
            .iter()
            .map(|&(r, c)| all_row(&rows, surface, Method::Mesh { rows: r, cols: c }))
            .collect();
        for pair in meshes.windows(2) {
            let (coarse, fine) = (pair[0], pair[1]);
            assert!(fine.triangles > 10 * coarse.triangles, "{name}");
            assert!(
                fine.t_err_median < coarse.t_err_median / 4.0,
                "{name}: fine {fine:?}\ncoarse {coarse:?}"
            );
        }
        let (coarse, fine) = (meshes[0], meshes[meshes.len() - 1]);
        assert!(
            fine.misses + fine.false_hits < coarse.misses + coarse.false_hits,
            "{name}: fine {fine:?}\ncoarse {coarse:?}"
        );
        // The coarse mesh visibly misses or invents hits (grazing rays see its facets).
        assert!(coarse.misses + coarse.false_hits > 0, "{name}: {coarse:?}");
        // Per-kind rows add up to the `all` row.
        let parts: Vec<&Row> = rows
            .iter()
            .filter(|r| r.surface == surface && r.method == Method::Robust && r.kind != "all")
            .collect();
        assert_eq!(parts.len(), kinds);
        assert_eq!(
            parts.iter().map(|r| r.ref_hits).sum::<usize>(),
            robust.ref_hits
        );
    }

    // One CSV line per method and ray kind (plus `all`), after the header.
    let text = csv(&rows);
    let methods = |newton: usize, grids: usize| 1 + newton + grids;
    let want = methods(opts.lathe_newton.len(), opts.lathe_grids.len()) * (3 + 1)
        + methods(opts.patch_newton.len(), opts.patch_grids.len()) * (2 + 1);
    assert_eq!(text.lines().count(), 1 + want, "{text}");
    let columns = text.lines().next().unwrap().split(',').count();
    assert!(text.lines().all(|l| l.split(',').count() == columns));
    assert_eq!(
        text.lines()
            .filter(|l| l.starts_with("revolve,robust,all,"))
            .count(),
        1
    );

    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b.png");
    let written = write_outputs(&rows, &out).unwrap();
    // CSV, 6 charts in 2 formats, the overview in 2 formats; nothing else (no temporary file).
    assert_eq!(written.len(), 1 + 12 + 2);
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names.len(), written.len(), "{names:?}");
    for n in [
        "b.csv",
        "b.png",
        "b.svg",
        "b_revolve_wrong.png",
        "b_revolve_terr.svg",
        "b_revolve_far.png",
        "b_patch_wrong.svg",
        "b_patch_terr.png",
    ] {
        assert!(names.iter().any(|x| x == n), "{n} missing: {names:?}");
    }
    assert_eq!(
        std::fs::read_to_string(dir.path().join("b.csv")).unwrap(),
        text
    );
    // The images decode; the overview holds the six charts, a surface per row.
    for p in written
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
    {
        let img = image::open(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let (w, h) = (img.width(), img.height());
        if p.ends_with("b.png") {
            assert_eq!((w, h), (3 * SIZE.0, 2 * SIZE.1));
        } else {
            assert_eq!((w, h), SIZE);
        }
    }
    for p in written
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "svg"))
    {
        let svg = std::fs::read_to_string(p).unwrap();
        assert!(svg.trim_start().starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(
            svg.contains("robust") && svg.contains("mesh, "),
            "{}",
            p.display()
        );
    }
}

#[test]
fn charts_draw_one_series_per_method_and_say_where_zero_goes() {
    let rows = run(&small(), &|_| {}).unwrap();
    let charts = charts(&rows);
    let suffixes: Vec<&str> = charts.iter().map(|c| c.suffix.as_str()).collect();
    assert_eq!(
        suffixes,
        [
            "_revolve_wrong",
            "_revolve_far",
            "_revolve_terr",
            "_patch_wrong",
            "_patch_far",
            "_patch_terr"
        ]
    );
    for c in &charts {
        let labels: Vec<&str> = c.series.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(
            labels.len(),
            3,
            "robust, one Newton start count, meshes: {labels:?}"
        );
        assert!(labels[1].starts_with("newton, "), "{labels:?}");
        assert_eq!(c.series[2].points.len(), 3, "one point per mesh");
        assert!(c.spec.log_x && c.spec.log_y);
        assert!(
            c.series
                .iter()
                .flat_map(|s| &s.points)
                .all(|&(x, y)| x > 0.0 && y > 0.0),
            "{c:?}"
        );
    }
    // The robust method makes no wrong answer: its point sits at the floor, and says so.
    let robust = &charts[0].series[0];
    assert!(
        robust.label.starts_with("robust; 0 drawn at "),
        "{}",
        robust.label
    );
    assert!(charts[0].spec.y_label.contains("0 drawn at"));
}
