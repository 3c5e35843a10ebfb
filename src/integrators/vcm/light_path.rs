//! Light subpaths: a light chosen by power (the environment included) emits a path that
//! bounces by BSDF sampling (importance transport, the photon tracer's roulette). Every
//! non-specular vertex (and, for merging, a blend's specular one) is stored for connections
//! and merging, and every non-specular one connected to the camera
//! (light tracing); the splats go to a list the caller adds to the film in path order, so the
//! image does not depend on threads.

use glam::{Vec3, Vec3A};

use super::mis::{self, Parts};
use super::{Context, bounce};
use crate::geometry::Frame;
use crate::geometry::Ray;
use crate::integrators::common::photons::roulette;
use crate::integrators::common::{attenuate_inside, medium_after, transmittance};
use crate::lights::Light;
use crate::materials::{Bsdf, Lobes, TransportMode};
use crate::prepare::SurfaceHit;
use crate::sampling::Rng;

/// A stored non-specular vertex of a light path: what a merge reads of it (the merge grid
/// holds its position). Its surface, which only connections read, is kept apart
/// ([`VertexSurface`]), so that the list the merges read is a third of the size and holds no
/// BSDF.
#[derive(Debug, Clone, Copy)]
pub(super) struct LightVertex {
    /// Unit direction toward the previous vertex (where the light came from).
    pub(super) wo: Vec3,
    /// The flux arriving here, per light path (before this vertex's BSDF).
    pub(super) beta: Vec3,
    /// Segments from the light to here.
    pub(super) len: u32,
    /// The MIS quantities in parts, evaluated with the radius of each camera path it meets.
    pub(super) q: Parts,
}

/// The surface of a stored light vertex, for connections: its position and its BSDF in the
/// compact form [`Bsdf::from_parts`] rebuilds bit for bit (a bump's microsurface as its
/// perturbed normal alone).
#[derive(Debug, Clone, Copy)]
pub(super) struct VertexSurface {
    pub(super) p: Vec3A,
    lobes: Lobes,
    frame: Frame,
    ng: Vec3A,
    bump: Option<Vec3>,
}

impl VertexSurface {
    fn new(p: Vec3A, bsdf: &Bsdf) -> Self {
        Self {
            p,
            lobes: bsdf.lobes,
            frame: bsdf.frame,
            ng: bsdf.ng,
            bump: bsdf.bump_normal().map(Vec3::from),
        }
    }

    /// The vertex's BSDF, as it was when the light path met it.
    pub(super) fn bsdf(&self) -> Bsdf {
        Bsdf::from_parts(self.lobes, self.frame, self.ng, self.bump.map(Vec3A::from))
    }
}

/// Where [`trace`] stores a light path's vertices: each vertex's merge part and its surface,
/// at the same index.
#[derive(Default)]
pub(super) struct Stored {
    pub(super) vertices: Vec<LightVertex>,
    pub(super) surfaces: Vec<VertexSurface>,
}

/// Light tracing's contribution to one pixel.
pub(super) type Splat = (u32, Vec3A);

/// Traces one light path, appending its stored vertices to `stored` and its camera
/// connections to `splats`.
pub(super) fn trace(ctx: &Context, rng: &mut Rng, stored: &mut Stored, splats: &mut Vec<Splat>) {
    let scene = ctx.scene;
    let Some((li, pe)) = ctx.emitters.sample(rng.f32()) else {
        return;
    };
    let light = &scene.lights[li];
    let (u1, u2) = (rng.vec2(), rng.vec2());
    let Some(ps) = light.sample_photon(u1, u2) else {
        return;
    };
    let pn = f64::from(scene.light_distr.pdf(li));
    let mut ray = if ps.n == Vec3A::ZERO {
        Ray::new(ps.p, ps.dir)
    } else {
        scene.spawn_ray(ps.p, ps.n, ps.dir)
    };
    let mut beta = ps.beta / pe;
    let mut q = Parts::default();
    let mut medium = Vec3A::ZERO;
    let mut len = 1u32;
    loop {
        let Some(sh) = scene.intersect(&ray, f32::INFINITY) else {
            return;
        };
        attenuate_inside(scene, &sh, &ray, medium, &mut beta);
        let wo = -ray.d;
        let bsdf = scene.bsdf(&sh);
        let cos_in = f64::from(wo.dot(bsdf.frame.n).abs());
        let dist = f64::from(sh.hit.t * ray.d.length());
        // The segment from the sky has no length: its density is per solid angle.
        let mut dist2 = Some(dist * dist);
        if len == 1 {
            let emission_pdf_w = ctx.emission_pdf_w(li, sh.hit.p, ps.n, ps.dir);
            if emission_pdf_w.is_nan() || emission_pdf_w <= 0.0 {
                return;
            }
            // Next-event estimation's density of the light point seen from this surface (per
            // area; per solid angle for the sky; a delta light's choice alone), and the cosine
            // at the light that a connection to it would use (none for a delta light; the
            // sky's directions are measured without one).
            let (direct_pdf_a, cos_light) = match light {
                Light::Area(al) => {
                    let on_light = scene.prim_light.get(sh.prim as usize) == Some(&(li as u32));
                    let w = f64::from(al.pdf_li_from(sh.hit.p, ps.p, ps.n, on_light));
                    let cos_light = f64::from(ps.n.dot(ps.dir).abs());
                    (pn * w * cos_light / (dist * dist), cos_light)
                }
                Light::Environment(env) => {
                    dist2 = None;
                    (pn * f64::from(env.pdf_li(wo)), 1.0)
                }
                Light::Point(_) | Light::Spot(_) => (pn, 0.0),
            };
            q = Parts::light(direct_pdf_a, emission_pdf_w, cos_light);
        }
        q.arrive(dist2, cos_in);
        let specular = bsdf.is_specular();
        // A blend's specular point stores its vertex for merging all the same (as photon
        // mapping stores its photons there): a camera vertex on a rough point nearby merges with
        // the light arriving at the surface, whichever part the light's own point shows, or the
        // density it estimates lacks the share of the specular part. Connections to such a
        // vertex find no BSDF and add nothing.
        let store = !specular || (ctx.mode.use_vm && scene.blend_stores_photons(&sh));
        if store && (ctx.mode.use_vc || ctx.mode.use_vm) {
            stored.vertices.push(LightVertex {
                wo: wo.into(),
                beta: beta.into(),
                len,
                q,
            });
            stored.surfaces.push(VertexSurface::new(sh.hit.p, &bsdf));
        }
        if !specular && (ctx.mode.use_vc || ctx.mode.light_trace_only) {
            to_camera(ctx, &sh, &bsdf, wo, beta, &q, medium, rng, splats);
        }
        if len + 2 > ctx.max_len {
            return;
        }
        let mode = TransportMode::Importance;
        let Some(s) = bounce(ctx, &sh, &bsdf, wo, mode, &mut q, &mut medium, rng, 1.0) else {
            return;
        };
        if !roulette(&mut beta, s.weight, rng) {
            return;
        }
        ray = scene.spawn_ray(sh.hit.p, sh.hit.n, s.wi);
        len += 1;
    }
}

/// Connects a light vertex to a point of the lens (light tracing).
#[allow(clippy::too_many_arguments)]
fn to_camera(
    ctx: &Context,
    sh: &SurfaceHit,
    bsdf: &Bsdf,
    wo: Vec3A,
    beta: Vec3A,
    q: &Parts,
    medium: Vec3A,
    rng: &mut Rng,
    splats: &mut Vec<Splat>,
) {
    let scene = ctx.scene;
    let Some(cs) = ctx.camera.sample_toward(sh.hit.p, rng.vec2()) else {
        return;
    };
    // The value and the reverse density (toward `wo` from the camera's direction) at once.
    let Some(e) = bsdf.eval(wo, cs.to_camera, TransportMode::Importance) else {
        return;
    };
    let (ray, t_max) = scene.spawn_ray_to(sh.hit.p, sh.hit.n, cs.lens, Vec3A::ZERO);
    if scene.occluded(&ray, t_max) {
        return;
    }
    let cos = cs.to_camera.dot(bsdf.frame.n).abs();
    let dist2 = cs.dist * cs.dist;
    let camera_pdf_a = f64::from(cs.pdf_dir) * f64::from(cos) / f64::from(dist2);
    let w = if ctx.mode.light_trace_only {
        1.0
    } else {
        // The radius of a camera path through the lens point that sees this vertex directly;
        // that camera path's second vertex is this one's predecessor: its merge is the gather's.
        let r = ctx
            .radius
            .at(f64::from(cs.dist), ctx.pixel_scale(cs.pixel as usize));
        let f = ctx.factors(r);
        mis::to_camera(&f, &q.gathered(&f), camera_pdf_a, f64::from(e.pdf_rev))
    };
    let absorbed = transmittance(medium_after(scene, sh, wo, cs.to_camera, medium), cs.dist);
    let c = beta * e.f * absorbed * (w * camera_pdf_a / ctx.light_paths) as f32;
    if c.is_finite() && c.max_element() > 0.0 {
        splats.push((cs.pixel, c));
    }
}

#[cfg(test)]
mod tests {
    use super::{LightVertex, Splat, VertexSurface};
    use crate::prepare::{BPT_VERTEX_BYTES, LT_VERTEX_BYTES, VCM_GRID_BYTES, VCM_VERTEX_BYTES};
    use glam::Vec3A;
    use std::mem::size_of;

    /// The memory budget's figure for a stored light vertex covers what the light pass keeps
    /// of it: the vertex in its path's chunk and again in the iteration's list, its surface
    /// in the chunk, its position, and a grid's entry (index, position, bucket and about two
    /// table slots of `u32`).
    #[test]
    fn the_memory_budget_covers_a_stored_light_vertex() {
        let grid = (4 * size_of::<u32>() + size_of::<Vec3A>()) as u64;
        let splat = size_of::<Splat>() as u64;
        let vertex = 2 * size_of::<LightVertex>() as u64
            + size_of::<VertexSurface>() as u64
            + size_of::<Vec3A>() as u64
            + grid
            + splat;
        assert!(
            grid <= VCM_GRID_BYTES,
            "grid entry {grid} > {VCM_GRID_BYTES}"
        );
        assert!(
            vertex <= VCM_VERTEX_BYTES,
            "light vertex {vertex} > {VCM_VERTEX_BYTES}"
        );
        // Not so generous that the budget stops meaning anything.
        assert!(
            VCM_VERTEX_BYTES <= vertex + vertex / 4,
            "{vertex} vs {VCM_VERTEX_BYTES}"
        );
        // `lt` keeps its splats alone.
        assert!(splat <= LT_VERTEX_BYTES, "{splat} > {LT_VERTEX_BYTES}");
        // `bpt` keeps the chunk's part alone, and its splats.
        let chunk = (size_of::<LightVertex>() + size_of::<VertexSurface>()) as u64 + splat;
        assert!(chunk <= BPT_VERTEX_BYTES, "{chunk} > {BPT_VERTEX_BYTES}");
        assert!(
            BPT_VERTEX_BYTES <= chunk + chunk / 4,
            "{chunk} vs {BPT_VERTEX_BYTES}"
        );
    }

    /// A stored surface gives back the BSDF it was made from, bit for bit, bumped or not: a
    /// connection to it evaluates what the light path's own bounce did.
    #[test]
    fn a_stored_surface_gives_back_its_bsdf() {
        use crate::geometry::Frame;
        use crate::materials::{Bsdf, Lobes};
        let n = Vec3A::new(0.3, -0.2, 0.9).normalize();
        let lobes = Lobes::Glossy {
            albedo: Vec3A::new(0.5, 0.25, 0.125),
            specular: Vec3A::splat(0.04),
            alpha: 0.2,
        };
        let plain = Bsdf::new(lobes, n, Vec3A::X, n);
        let np = Vec3A::new(0.5, 0.1, 0.8).normalize();
        let bumped = Bsdf::bumped(lobes, Frame::from_normal(n), n, np);
        assert!(bumped.bump_normal().is_some());
        for bsdf in [plain, bumped] {
            let back = VertexSurface::new(Vec3A::ONE, &bsdf).bsdf();
            assert_eq!(back, bsdf);
            let (wo, wi) = (Vec3A::new(0.1, 0.2, 0.97).normalize(), n);
            assert_eq!(back.f(wo, wi).to_array(), bsdf.f(wo, wi).to_array());
            assert_eq!(back.pdf(wo, wi).to_bits(), bsdf.pdf(wo, wi).to_bits());
        }
    }
}
