//! Texture evaluation cost per shading point, as ratios against a constant color parameter
//! (the cheapest thing a material can read) measured in the same run.
//!
//! `cargo bench --bench textures`

use std::hint::black_box;
use std::path::PathBuf;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DAffine3, DVec3, Vec2, Vec3A};
use sppm_lang::Span;
use sppm_lang::internals::scene::{
    ColorMap, ColorParam, ImageData, Mapping, Pattern, Texture, Wrap,
};
use sppm_lang::internals::textures::{self, EnvironmentMap, TexCoord};

fn points() -> Vec<TexCoord> {
    (0..1024)
        .map(|i| {
            let t = i as f32;
            let p = Vec3A::new(
                (t * 0.618).fract(),
                (t * 0.414).fract(),
                (t * 0.732).fract(),
            ) * 4.0
                - 2.0;
            TexCoord {
                p,
                n: p.normalize_or(Vec3A::Y),
                uv: Vec2::new((t * 0.271).fract(), (t * 0.577).fract()),
            }
        })
        .collect()
}

fn texture(pattern: Pattern, mapping: Mapping) -> Texture {
    Texture {
        pattern,
        mapping,
        transform: DAffine3::from_scale(DVec3::splat(2.0)),
        span: Span::default(),
    }
}

fn image(w: u32, h: u32) -> ImageData {
    ImageData {
        path: PathBuf::from("bench"),
        width: w,
        height: h,
        pixels: (0..w * h)
            .map(|i| [(i % 7) as f32 / 7.0, (i % 11) as f32 / 11.0, 0.5])
            .collect(),
    }
}

fn bench(c: &mut Criterion) {
    let pts = points();
    let map = ColorMap(vec![(0.0, DVec3::ZERO), (0.5, DVec3::X), (1.0, DVec3::ONE)]);
    let img = Arc::new(image(512, 256));
    let cases = [
        (
            "checker_solid",
            texture(
                Pattern::Checker {
                    a: DVec3::X,
                    b: DVec3::Y,
                },
                Mapping::Solid,
            ),
        ),
        (
            "marble_4_octaves",
            texture(
                Pattern::Marble {
                    map: map.clone(),
                    turbulence: 1.0,
                    octaves: 4,
                },
                Mapping::Solid,
            ),
        ),
        (
            "image_bilinear_spherical",
            texture(
                Pattern::Image {
                    image: img.clone(),
                    wrap: Wrap::Repeat,
                    bilinear: true,
                },
                Mapping::Spherical,
            ),
        ),
    ];
    let mut group = c.benchmark_group("texture_eval_1024_points");
    group.bench_function("baseline_const_param", |b| {
        let param = ColorParam::Const(DVec3::new(0.2, 0.4, 0.6));
        b.iter(|| {
            let mut acc = Vec3A::ZERO;
            for p in &pts {
                acc += textures::color_param(black_box(&param), &[], p);
            }
            acc
        })
    });
    for (name, tex) in &cases {
        group.bench_function(*name, |b| {
            b.iter(|| {
                let mut acc = Vec3A::ZERO;
                for p in &pts {
                    acc += textures::evaluate(black_box(tex), p);
                }
                acc
            })
        });
    }
    let env = EnvironmentMap::new(&img, 1.0, DAffine3::IDENTITY);
    group.bench_function("environment_sample", |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for p in &pts {
                if let Some(s) = env.sample(black_box(p.uv)) {
                    acc += s.pdf;
                }
            }
            acc
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
