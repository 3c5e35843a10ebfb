//! Camera subpaths: from the pixel, by BSDF sampling (radiance transport). At each non-specular
//! vertex they add next-event estimation, connections to the vertices of the light path with
//! the pixel's index, and merges with the light vertices within the radius; emission they hit
//! counts with its weight. With light tracing alone a camera path only follows delta bounces
//! to the light or the sky it sees (what light tracing cannot reach).

use glam::Vec3A;

use super::light_path::{LightVertex, VertexSurface};
use super::mis::{self, Factors, GatherAt, Parts};
use super::roulette::connection_roulette;
use super::{Context, bounce, bounce_numbers};
use crate::integrators::common::direct::sample_light;
use crate::integrators::common::footprint;
use crate::integrators::common::{
    attenuate_inside, camera_roulette, medium_after, refraction_scale, transmittance,
};
use crate::lights::AreaLight;
use crate::materials::{Bsdf, TransportMode};
use crate::prepare::{GATHER_RADIUS_FACTOR, InitialRadius, SurfaceHit};
use crate::sampling::Rng;
use crate::textures::luminance;

/// The state of a camera path at its last vertex.
struct State {
    beta: Vec3A,
    len: u32,
    q: Parts,
    /// Every bounce so far specular.
    specular: bool,
    /// The path's length so far while every bounce is specular.
    distance: f64,
    /// The weights' constants for the path's radius, the radius and the merges'
    /// normalisation `1 / (pi r^2 N)`: set at its first non-specular vertex.
    factors: Factors,
    /// 0 until set: at the first vertex whose BSDF is not specular, once, even if that vertex
    /// then samples a delta lobe, so that every technique of the path sees one radius.
    radius: f32,
    vm_normalization: f32,
    medium: Vec3A,
    /// The previous vertex and the light whose surface it lies on, if any (for next-event
    /// estimation's density of a light the path hits).
    prev: Vec3A,
    prev_light: Option<u32>,
    /// The first bounce was non-specular (a lobe other than a delta one).
    first_diffuse: bool,
    /// The product of the bounces' [`refraction_scale`]s: the roulette judges `beta` with
    /// the refractions' `1 / eta^2` undone.
    eta_scale: f32,
}

impl State {
    /// The path's last vertex is its second after a non-specular first, and the final gather
    /// is on: the merge there is the gather's (with 4 times the radius set at the first).
    fn gather_here(&self, ctx: &Context) -> bool {
        ctx.gather && self.len == 2 && self.first_diffuse
    }

    /// The path's last vertex is its first (non-specular: connections and merges happen only
    /// there) and the final gather is on: the vertex a connection or merge leaves it for is
    /// the camera path's second, the gather's (a light vertex, or a light vertex's predecessor).
    fn gather_next(&self, ctx: &Context) -> bool {
        ctx.gather && self.len == 1
    }
}

/// The radiance of one camera path through pixel (x, y); `own` are the vertices of the light
/// path serving the pixel (the pixel's index modulo the light paths' count); `ratio` the
/// pixel's footprint ratio through mirrors and glass (0 until measured).
pub(super) fn radiance(
    ctx: &Context,
    x: u32,
    y: u32,
    own: (&[LightVertex], &[VertexSurface]),
    rng: &mut Rng,
    specular_only: bool,
    ratio: &mut f64,
) -> Radiance {
    let scene = ctx.scene;
    // The stream before the path drew from it: the footprint's neighbour rays retrace it.
    let rng0 = rng.clone();
    let (jitter, lens) = (rng.vec2(), rng.vec2());
    let mut ray = ctx.camera.ray(x, y, jitter, lens);
    let pdf_camera = f64::from(ctx.camera.pdf_dir(ray.d));
    if pdf_camera.is_nan() || pdf_camera <= 0.0 {
        return Radiance::default();
    }
    let mut st = State {
        beta: Vec3A::ONE,
        len: 1,
        q: Parts::camera(ctx.light_paths, pdf_camera),
        specular: true,
        distance: 0.0,
        factors: ctx.factors(ctx.radius.or_fallback(None)),
        radius: 0.0,
        vm_normalization: 0.0,
        medium: Vec3A::ZERO,
        prev: ray.o,
        prev_light: None,
        first_diffuse: false,
        eta_scale: 1.0,
    };
    let mut out = Radiance::default();
    // The first merge's count is the pixel's (`pixel_radius.rs`).
    let mut counted = false;
    loop {
        let Some(sh) = scene.intersect(&ray, f32::INFINITY) else {
            *out.part(st.specular) += st.beta * escaped(ctx, &st, ray.d);
            break;
        };
        attenuate_inside(scene, &sh, &ray, st.medium, &mut st.beta);
        let wo = -ray.d;
        let bsdf = scene.bsdf(&sh);
        let dist = f64::from(sh.hit.t * ray.d.length());
        if st.specular {
            st.distance += dist;
        }
        st.q.arrive(Some(dist * dist), f64::from(wo.dot(bsdf.frame.n).abs()));
        if let Some((li, al)) = scene.area_light(sh.prim) {
            let le = al.le(sh.hit.n, wo);
            if le != Vec3A::ZERO {
                *out.part(st.specular) +=
                    st.beta * le * hit_weight(ctx, &st, (li, al), &sh, wo, dist);
            }
        }
        if ctx.mode.light_trace_only && !bsdf.is_specular() {
            break;
        }
        if st.len >= ctx.max_len {
            break;
        }
        if !bsdf.is_specular() && !specular_only {
            if st.radius == 0.0 {
                out.r0 = set_radius(ctx, &mut st, (x, y), &rng0, ratio);
            }
            let l = &mut out.rest;
            if ctx.mode.use_vc {
                *l += st.beta * direct(ctx, &st, &sh, &bsdf, wo, rng);
                let floor = ctx.connect_floor(ctx.pixel_index(x, y));
                for (v, surface) in own.0.iter().zip(own.1) {
                    if v.len + 1 + st.len > ctx.max_len {
                        continue;
                    }
                    let throughput = st.beta * Vec3A::from(v.beta);
                    let at = Vertices {
                        sh: &sh,
                        bsdf: &bsdf,
                        wo,
                        v,
                        surface,
                    };
                    *l += throughput * connect(ctx, &st, &at, (throughput, floor), rng);
                }
            }
            if ctx.mode.use_vm {
                let (m, found) = merge(ctx, &st, sh.hit.p, &bsdf, wo);
                *l += st.beta * m;
                if !counted && !st.gather_here(ctx) {
                    out.found = found;
                    counted = true;
                }
            }
        }
        if specular_only && !bsdf.samples_delta() {
            // The bounce would sample a lobe that is not a delta one, and the path would end
            // with it: it ends here, its numbers drawn all the same (the pixel's next camera
            // path draws from the same stream).
            bounce_numbers(rng);
            break;
        }
        let mode = TransportMode::Radiance;
        let ratio = st.factors.merge_ratio(st.gather_here(ctx));
        let q = &mut st.q;
        let Some(s) = bounce(ctx, &sh, &bsdf, wo, mode, q, &mut st.medium, rng, ratio) else {
            break;
        };
        if st.len == 1 {
            st.first_diffuse = !s.specular;
        }
        st.specular &= s.specular;
        out.through_delta |= st.specular;
        if specular_only && !st.specular {
            break;
        }
        st.beta *= s.weight;
        st.eta_scale *= refraction_scale(&bsdf, wo, s.wi);
        if !camera_roulette(&mut st.beta, st.eta_scale, st.len, rng) {
            break;
        }
        st.prev = sh.hit.p;
        st.prev_light = scene.prim_light.get(sh.prim as usize).copied();
        ray = scene.spawn_ray(sh.hit.p, sh.hit.n, s.wi);
        st.len += 1;
    }
    out
}

/// Sets the camera path's radius at its first non-specular vertex, `st.distance` along it:
/// SPPM's initial radius (`r_0`) for a pixel whose camera path this is, the pixel's scale
/// (`pixel_radius.rs`) applied. Seen directly it is the straight footprint's, the same rule a
/// light-traced splat's weight uses at its vertex; through mirrors and glass the straight footprint over
/// the path's length times the pixel's `ratio` (`common::footprint`), measured by neighbour
/// rays retraced from `rng0` by the pixel's first camera path that passes a mirror or glass
/// and kept, as SPPM keeps its pixel's radius (for merging only: without it the radius enters
/// no weight). A ratio from an earlier path depends on nothing this path or the light paths
/// sample, so the weights stay exact. Returns `r_0` times the pixel's scale.
fn set_radius(
    ctx: &Context,
    st: &mut State,
    pixel: (u32, u32),
    rng0: &Rng,
    ratio: &mut f64,
) -> f64 {
    let rule = ctx.radius.rule;
    let r0 = match rule {
        InitialRadius::Footprint { .. } if st.len > 1 && ctx.mode.use_vm => {
            if *ratio == 0.0 {
                let (scene, settings, camera) = (ctx.scene, ctx.settings, &ctx.camera);
                let mut rng = rng0.clone();
                let r = footprint::footprint_ratio(scene, camera, settings, pixel, false, &mut rng);
                *ratio = r.unwrap_or(1.0);
            }
            rule.at(st.distance).map(|r| r * *ratio)
        }
        _ => rule.at(st.distance),
    }
    .unwrap_or(ctx.radius.fallback)
        * ctx.pixel_scale(ctx.pixel_index(pixel.0, pixel.1));
    let r = ctx.radius.or_fallback(Some(r0));
    st.factors = ctx.factors(r);
    st.radius = r as f32;
    st.vm_normalization = (1.0 / (std::f64::consts::PI * r * r * ctx.light_paths)) as f32;
    r0
}

/// A camera path's radiance in two parts: what it sees through delta bounces alone (emission
/// and the sky, weight 1: no other technique samples it) and the rest.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Radiance {
    pub(super) specular: Vec3A,
    pub(super) rest: Vec3A,
    /// The path left its first vertex by a delta bounce (a mirror, glass).
    pub(super) through_delta: bool,
    /// The path's initial radius times its pixel's scale (0 if it set none).
    pub(super) r0: f64,
    /// The light vertices its first merge found within its radius (not the final gather's).
    pub(super) found: u32,
}

impl Radiance {
    fn part(&mut self, specular: bool) -> &mut Vec3A {
        if specular {
            &mut self.specular
        } else {
            &mut self.rest
        }
    }
}

/// What a camera path that leaves the scene sees: the backdrop or sky straight on and after
/// delta bounces (weight 1: nothing else samples it), the environment light after a
/// non-specular bounce, weighed against next-event estimation and the light paths that start
/// on the sky.
fn escaped(ctx: &Context, st: &State, d: Vec3A) -> Vec3A {
    let scene = ctx.scene;
    if st.specular {
        return scene.escaped_radiance(d, true);
    }
    if ctx.mode.light_trace_only {
        return Vec3A::ZERO;
    }
    let Some((li, env)) = scene.environment_light() else {
        return Vec3A::ZERO;
    };
    let le = env.le(d);
    if le == Vec3A::ZERO {
        return le;
    }
    let direct_pdf = f64::from(scene.light_distr.pdf(li) * env.pdf_li(d));
    let emission_pdf_w = ctx.emission_pdf_w(li, st.prev, Vec3A::ZERO, -d);
    le * mis::hit_light(&st.q.at(&st.factors), direct_pdf, emission_pdf_w) as f32
}

/// The weight of emission from area light `li` hit at `sh`, `dist` from the previous vertex.
fn hit_weight(
    ctx: &Context,
    st: &State,
    (li, al): (usize, &AreaLight),
    sh: &SurfaceHit,
    wo: Vec3A,
    dist: f64,
) -> f32 {
    // Seen straight on or after delta bounces: no other technique reaches the camera (a light
    // path's point on the light is not stored, and no connection goes through a delta lobe).
    if st.specular {
        return 1.0;
    }
    if ctx.mode.light_trace_only {
        return 0.0;
    }
    let scene = ctx.scene;
    let cos_light = f64::from(sh.hit.n.dot(wo).abs());
    let on_light = st.prev_light == Some(li as u32);
    let pn = f64::from(scene.light_distr.pdf(li));
    let direct_pdf_a =
        pn * f64::from(al.pdf_li_from(st.prev, sh.hit.p, sh.hit.n, on_light)) * cos_light
            / (dist * dist);
    let emission_pdf_w = ctx.emission_pdf_w(li, sh.hit.p, sh.hit.n, wo);
    mis::hit_light(&st.q.at(&st.factors), direct_pdf_a, emission_pdf_w) as f32
}

/// Next-event estimation at a camera vertex, weighted against the camera path hitting the
/// light and every technique that starts on the light.
fn direct(
    ctx: &Context,
    st: &State,
    sh: &SurfaceHit,
    bsdf: &Bsdf,
    wo: Vec3A,
    rng: &mut Rng,
) -> Vec3A {
    let scene = ctx.scene;
    let Some(sl) = sample_light(scene, sh, rng) else {
        return Vec3A::ZERO;
    };
    let (li, ls) = (sl.light, &sl.sample);
    let Some(e) = bsdf.eval(wo, ls.wi, TransportMode::Radiance) else {
        return Vec3A::ZERO;
    };
    let cos_to_light = ls.wi.dot(bsdf.frame.n).abs();
    if cos_to_light == 0.0 {
        return Vec3A::ZERO;
    }
    let pn = f64::from(sl.light_pdf);
    let bsdf_rev = f64::from(e.pdf_rev);
    let (bsdf_pdf, direct_pdf_w, emission_pdf_w, cos_at_light) = if scene.environment == Some(li) {
        // The sky's directions are measured without a cosine at the light.
        (
            f64::from(e.pdf),
            pn * f64::from(ls.pdf),
            ctx.emission_pdf_w(li, sh.hit.p, Vec3A::ZERO, -ls.wi),
            1.0,
        )
    } else if ls.delta {
        let dist2 = f64::from((ls.p - sh.hit.p).length_squared());
        let emission = ctx.emission_pdf_w(li, ls.p, ls.n, -ls.wi);
        (0.0, pn * dist2, emission, 1.0)
    } else {
        (
            f64::from(e.pdf),
            pn * f64::from(ls.pdf),
            ctx.emission_pdf_w(li, ls.p, ls.n, -ls.wi),
            f64::from(ls.n.dot(ls.wi).abs()),
        )
    };
    let w = mis::direct(
        &st.factors,
        &st.q.at(&st.factors),
        st.gather_here(ctx),
        bsdf_pdf,
        bsdf_rev,
        direct_pdf_w,
        emission_pdf_w,
        f64::from(cos_to_light),
        cos_at_light,
    );
    if w.is_nan() || w <= 0.0 || scene.occluded(&sl.shadow_ray, sl.t_max) {
        return Vec3A::ZERO;
    }
    let absorbed = sl.transmittance(scene, sh, wo, st.medium);
    e.f * ls.li * absorbed * (w * f64::from(cos_to_light) / (pn * f64::from(ls.pdf))) as f32
}

/// The two ends of a connection: the camera vertex (`sh`, its BSDF, the direction back along
/// the camera path) and light vertex `v` on `surface`.
struct Vertices<'a> {
    sh: &'a SurfaceHit,
    bsdf: &'a Bsdf,
    wo: Vec3A,
    v: &'a LightVertex,
    surface: &'a VertexSurface,
}

/// Connects a camera vertex to a light vertex (without either path's throughput). `roulette`:
/// both paths' throughput and the pixel's floor (`roulette.rs`): a connection whose weighted
/// contribution falls below the floor plays Russian roulette before its shadow ray.
fn connect(
    ctx: &Context,
    st: &State,
    at: &Vertices,
    (throughput, floor): (Vec3A, f32),
    rng: &mut Rng,
) -> Vec3A {
    let Vertices {
        sh,
        bsdf,
        wo,
        v,
        surface,
    } = *at;
    let scene = ctx.scene;
    let p = sh.hit.p;
    let d = surface.p - p;
    let dist2 = d.length_squared();
    if dist2.is_nan() || dist2 <= 0.0 {
        return Vec3A::ZERO;
    }
    let dist = dist2.sqrt();
    let dir = d / dist;
    let Some(cam) = bsdf.eval(wo, dir, TransportMode::Radiance) else {
        return Vec3A::ZERO;
    };
    let (v_bsdf, v_wo) = (surface.bsdf(), Vec3A::from(v.wo));
    let Some(light) = v_bsdf.eval(v_wo, -dir, TransportMode::Importance) else {
        return Vec3A::ZERO;
    };
    let cos_cam = dir.dot(bsdf.frame.n).abs();
    let cos_light = dir.dot(v_bsdf.frame.n).abs();
    let g = cos_cam * cos_light / dist2;
    let d2 = f64::from(dist2);
    let cam_pdf_a = f64::from(cam.pdf) * f64::from(cos_light) / d2;
    let light_pdf_a = f64::from(light.pdf) * f64::from(cos_cam) / d2;
    // The camera path's second vertex: this one, or the light vertex when this is its first.
    let gather = if st.gather_here(ctx) {
        GatherAt::Camera
    } else if st.gather_next(ctx) {
        GatherAt::Light
    } else {
        GatherAt::Neither
    };
    let w = mis::connect(
        &st.factors,
        &st.q.at(&st.factors),
        &v.q.at(&st.factors),
        cam_pdf_a,
        light_pdf_a,
        f64::from(cam.pdf_rev),
        f64::from(light.pdf_rev),
        gather,
    );
    if !(w > 0.0 && g > 0.0) {
        return Vec3A::ZERO;
    }
    let c = cam.f * light.f * (g * w as f32);
    let Some(scale) = connection_roulette(luminance(throughput * c), floor, rng) else {
        return Vec3A::ZERO;
    };
    let (ray, t_max) = scene.spawn_ray_to(p, sh.hit.n, surface.p, v_bsdf.ng);
    if scene.occluded(&ray, t_max) {
        return Vec3A::ZERO;
    }
    let absorbed = transmittance(medium_after(scene, sh, wo, dir, st.medium), dist);
    c * absorbed * scale
}

/// Merges the light vertices within the radius of camera vertex `p` (without the camera
/// path's throughput): each counts its flux times the camera BSDF over the disk's area and
/// the number of light paths. At the camera path's second vertex after a non-specular first,
/// with the final gather on, the radius is the gather's, `GATHER_RADIUS_FACTOR` times the
/// path's own. Also returns how many light vertices it merged with.
fn merge(ctx: &Context, st: &State, p: Vec3A, bsdf: &Bsdf, wo: Vec3A) -> (Vec3A, u32) {
    let gather = st.gather_here(ctx);
    let (grid, radius, normalization) = if gather {
        let k = GATHER_RADIUS_FACTOR as f32;
        (
            ctx.gather_grid,
            st.radius * k,
            st.vm_normalization / (k * k),
        )
    } else {
        (ctx.grid, st.radius, st.vm_normalization)
    };
    let Some(grid) = grid else {
        return (Vec3A::ZERO, 0);
    };
    // At the camera path's first vertex the light vertex's predecessor is its second.
    let first = st.gather_next(ctx);
    let mut sum = Vec3A::ZERO;
    let mut found = 0u32;
    let cam = st.q.at(&st.factors);
    grid.for_each_within(p, radius, |i| {
        let v = &ctx.vertices[i];
        if v.len + st.len > ctx.max_len {
            return;
        }
        found = found.saturating_add(1);
        let v_wo = Vec3A::from(v.wo);
        let Some(e) = bsdf.eval(wo, v_wo, TransportMode::Radiance) else {
            return;
        };
        let (cam_pdf, cam_rev) = (f64::from(e.pdf), f64::from(e.pdf_rev));
        let light = if first {
            v.q.gathered(&st.factors)
        } else {
            v.q.at(&st.factors)
        };
        let w = mis::merge(&st.factors, &cam, &light, cam_pdf, cam_rev, gather);
        sum += e.f * Vec3A::from(v.beta) * w as f32;
    });
    (sum * normalization, found)
}
