//! The multiple-importance weights of vertex connection and merging, computed from three
//! quantities every subpath carries (Georgiev et al. 2012, "Light transport simulation with
//! vertex connection and merging", and its technical report's recursive form): `vcm`, `vc` and
//! `vm` (with the final gather a fourth, `last`, below). Each is a sum, over the techniques
//! that would have sampled the subpath's vertices from the other end, of the ratio of that
//! technique's density to this one's, divided by what the next step of the path (not known
//! yet) contributes. With them a weight needs only the vertex at each end of the connection or
//! merge: no path is revisited.
//!
//! **A radius per camera path.** A merge's density relative to a connection's,
//! `eta = pi r^2 N`, depends on the radius, and the radius is each camera path's own (its
//! pixel's footprint where it first meets a non-specular surface). The quantities are carried
//! in parts affine in the merge factor `E = mis(eta)` ([`Parts`]): a light vertex stores its
//! parts, and each connection, merge or light-traced splat evaluates them with the `E` of the
//! camera path it meets (for a splat, the camera path that would end at the light vertex: the
//! radius at the vertex's distance from the lens). The techniques of one whole path then all
//! see one radius, the camera end's, and the weights are exactly the power heuristic's for it.
//!
//! **The final gather.** With final gathering, the merge at a camera path's second vertex
//! after a non-specular first uses a wider radius `R = GATHER_RADIUS_FACTOR r`, `r` that camera
//! path's own radius (as SPPM's gather points): a technique of its own, whose density is that
//! of the merge at the same vertex with `pi R^2 N` in place of `pi r^2 N`, and which takes the
//! place of that merge. In the sums it changes the terms that count the merge at that vertex:
//! in `vc` the merge's density over a connection's, `E`, becomes the gather's factor
//! `E_g = mis(pi R^2 N) = G E`; in `vm` the merge's density over the merge at the next vertex,
//! 1, becomes `G = mis(R^2 / r^2)` (`Factors::gather_weight`, `Factors::gather_ratio`: both
//! per camera path, from its `r`). The camera path knows which of its vertices is its second:
//! its `scatter` there takes `G` in place of 1 in both sums (the parts stay affine in `E`), and
//! the merge factor at that vertex in `direct` and `connect` is `E_g`. A light vertex does not
//! know it ahead: it turns out to be the camera path's second in a connection whose camera
//! part is one vertex (the light end itself: its merge factor in `connect` is that camera
//! path's `E_g`), and its predecessor does when light tracing connects it to the camera or a
//! camera path merges with it at its first vertex. For those each light subpath keeps apart
//! `last`, the coefficient `k` with which its last `scatter` added the merge at the vertex it
//! scattered at: the parts `[0, k]` of `vc` (the term `k E`) and `[k, 0]` of `vm` (the term
//! `k`). [`Parts::gathered`] evaluates the quantities with that term re-weighted by the
//! meeting camera path's gather, `k E_g` and `k G`: affine in `E` like the rest, so the same
//! stored vertex serves camera paths of every radius, gathering or not. The gather merge
//! itself is weighed against the same techniques as the merge with `r` at its vertex, each of
//! whose densities is now over `R^2 / r^2` times as much: its weight is
//! `1 / (1 + (w_light + w_camera) / G)` from that merge's sums.
//!
//! Densities enter through `mis` (the power heuristic: squared). The same functions serve both
//! the renderer and the test that checks their weights against every technique's density
//! computed by brute force (`mis/tests.rs`: camera paths of different radii meeting one light
//! subpath, with and without the final gather).

/// The heuristic: the power heuristic with exponent 2.
#[inline]
pub(super) fn mis(x: f64) -> f64 {
    x * x
}

/// The constants of the weights for one camera path's radius (and the iteration's light
/// paths' count).
#[derive(Debug, Clone, Copy)]
pub(super) struct Factors {
    /// `mis(eta)` with `eta = pi r^2 N` when merging is used, else 0: a merge's density relative
    /// to the connection at the same vertex.
    pub(super) vm_weight: f64,
    /// `mis(1 / eta)` when connections are used, else 0.
    pub(super) vc_weight: f64,
    /// Number of light paths per iteration (one per pixel, or a quarter as many).
    pub(super) light_paths: f64,
    /// `E_g = mis(pi R^2 N)`: the gather merge's density relative to the connection at its
    /// vertex (without the final gather, `vm_weight`).
    pub(super) gather_weight: f64,
    /// `G = mis(R^2 / r^2)`: the gather merge's density over the merge with `r` at the same
    /// vertex (without the final gather, 1).
    pub(super) gather_ratio: f64,
}

impl Factors {
    pub(super) fn new(radius: f64, light_paths: f64, use_vc: bool, use_vm: bool) -> Self {
        let eta = std::f64::consts::PI * radius * radius * light_paths;
        Self {
            vm_weight: if use_vm { mis(eta) } else { 0.0 },
            vc_weight: if use_vc { mis(1.0 / eta) } else { 0.0 },
            light_paths,
            gather_weight: if use_vm { mis(eta) } else { 0.0 },
            gather_ratio: 1.0,
        }
    }

    /// The same with the final gather, of radius `factor` times this one's (nothing changes
    /// without merging).
    pub(super) fn with_gather(self, factor: f64) -> Self {
        if self.vm_weight <= 0.0 {
            return self;
        }
        let ratio = mis(factor * factor);
        Self {
            gather_weight: self.vm_weight * ratio,
            gather_ratio: ratio,
            ..self
        }
    }

    /// The merge factor at a vertex: the final gather's where `gather` (the vertex is the
    /// camera path's second, after a non-specular first), else `vm_weight`.
    pub(super) fn merge_at(&self, gather: bool) -> f64 {
        if gather {
            self.gather_weight
        } else {
            self.vm_weight
        }
    }

    /// The factor to the merge term a `scatter` adds at a vertex, relative to the plain
    /// merge's: `G` at the final gather's vertex, else 1.
    pub(super) fn merge_ratio(&self, gather: bool) -> f64 {
        if gather { self.gather_ratio } else { 1.0 }
    }
}

/// The recursive quantities of a subpath at its last vertex, for the merge factor of the
/// camera path they meet: what every weight below takes ([`Parts::at`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Quantities {
    pub(super) vcm: f64,
    pub(super) vc: f64,
    pub(super) vm: f64,
}

/// The recursive quantities of a subpath in parts, for every merge factor at once: with
/// `E = mis(eta)` ([`Factors::vm_weight`]) and `1 / E` ([`Factors::vc_weight`]),
///
/// ```text
/// vc = vc[0] + E vc[1]        vm = vm[0] + vm[1] / E        (vcm has no E)
/// ```
///
/// By induction over the recursion (`'` the next vertex's, `k = mis(cos_out / pdf_dir)`,
/// `p = mis(pdf_rev)`):
/// - at the light's first vertex `vc = mis(cos_light / emission_pdf_w)`, `vm = vc / E`: the
///   parts `vc = [vc, 0]`, `vm = [0, vc]`; at the camera `vc = vm = 0`;
/// - `vc' = k (vc p + vcm + E)` gives `vc'[0] = k (vc[0] p + vcm)`, `vc'[1] = k (vc[1] p + 1)`;
/// - `vm' = k (vm p + vcm / E + 1)` gives `vm'[0] = k (vm[0] p + 1)`, `vm'[1] = k (vm[1] p +
///   vcm)`;
/// - `vcm' = mis(1 / pdf_dir)` has no E; arriving, and a delta bounce, scale all three by
///   factors without E;
/// - at the camera path's final-gather vertex the merge there counts `G E` in `vc'` and `G`
///   in `vm'` (`G` has no E): `vc'[1] = k (vc[1] p + G)`, `vm'[0] = k (vm[0] p + G)`;
/// - `last' = k`, the merge term just added, kept apart: `[0, k]` in `vc'`, `[k, 0]` in `vm'`
///   (scaled by arriving as the rest; zero after a delta bounce and at the light).
///
/// So a light path's stored vertex holds its parts, and each connection, merge or light-traced
/// splat evaluates them with the E of the camera path it meets ([`Parts::at`], or
/// [`Parts::gathered`] where the vertex before it is that camera path's gather vertex).
/// Without merging E is 0 (and without connections `1 / E` is 0), as in the recursion itself.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Parts {
    pub(super) vcm: f64,
    pub(super) vc: [f64; 2],
    pub(super) vm: [f64; 2],
    /// `k` of the last `scatter` (see above); zero after a light point or a delta bounce.
    pub(super) last: f64,
}

impl Parts {
    /// At the camera: `light_paths` the light paths' count, `pdf_camera` the camera's
    /// solid-angle density of the first direction.
    pub(super) fn camera(light_paths: f64, pdf_camera: f64) -> Self {
        Self {
            vcm: mis(light_paths / pdf_camera),
            vc: [0.0; 2],
            vm: [0.0; 2],
            last: 0.0,
        }
    }

    /// At a light path's first surface: `direct_pdf_a` is the density per area of the light
    /// point for next-event estimation from that surface (for a delta light the choice of the
    /// light alone), `emission_pdf_w` the emission's density (light choice, area, direction),
    /// `cos_light` the cosine at the light (zero for a delta light: no connection reaches it;
    /// 1 for the environment, whose directions are measured without one).
    pub(super) fn light(direct_pdf_a: f64, emission_pdf_w: f64, cos_light: f64) -> Self {
        let vc = mis(cos_light / emission_pdf_w);
        Self {
            vcm: mis(direct_pdf_a / emission_pdf_w),
            vc: [vc, 0.0],
            vm: [0.0, vc],
            last: 0.0,
        }
    }

    /// The quantities for the merge factor of `f`.
    pub(super) fn at(&self, f: &Factors) -> Quantities {
        Quantities {
            vcm: self.vcm,
            vc: self.vc[0] + f.vm_weight * self.vc[1],
            vm: self.vm[0] + f.vc_weight * self.vm[1],
        }
    }

    /// The quantities for `f` when the vertex before this one is the camera path's final
    /// gather vertex (light tracing connects this vertex to the camera, or a camera path
    /// merges with it at its first vertex): the last merge term weighed by `G`, i.e. `E_g` in
    /// `vc`. The same as [`Parts::at`] without the gather.
    pub(super) fn gathered(&self, f: &Factors) -> Quantities {
        let extra = self.last * (f.gather_ratio - 1.0);
        Self {
            vc: [self.vc[0], self.vc[1] + extra],
            vm: [self.vm[0] + extra, self.vm[1]],
            ..*self
        }
        .at(f)
    }

    /// Arriving at a surface after a segment of squared length `dist2` (`None`: the light
    /// point's own distance is already in `light`'s `direct_pdf_a`), at cosine `cos`.
    pub(super) fn arrive(&mut self, dist2: Option<f64>, cos: f64) {
        if let Some(d2) = dist2 {
            self.vcm *= mis(d2);
        }
        let c = mis(cos.abs());
        self.vcm /= c;
        self.vc = self.vc.map(|x| x / c);
        self.vm = self.vm.map(|x| x / c);
        self.last /= c;
    }

    /// Scattering at a non-specular vertex into a direction of cosine `cos_out`, sampled with
    /// solid-angle density `pdf_dir`; `pdf_rev` is the density of the reverse choice.
    /// `merge_ratio` is the merge's factor at this vertex over the plain merge's
    /// ([`Factors::merge_ratio`]): `G` at the camera path's final gather vertex, else 1.
    pub(super) fn scatter(&mut self, cos_out: f64, pdf_dir: f64, pdf_rev: f64, merge_ratio: f64) {
        let (k, p, g) = (mis(cos_out / pdf_dir), mis(pdf_rev), merge_ratio);
        *self = Self {
            vcm: mis(1.0 / pdf_dir),
            vc: [k * (self.vc[0] * p + self.vcm), k * (self.vc[1] * p + g)],
            vm: [k * (self.vm[0] * p + g), k * (self.vm[1] * p + self.vcm)],
            last: k,
        };
    }

    /// Scattering by a delta lobe: no technique can connect or merge at this vertex, and the
    /// forward and reverse densities are the same.
    pub(super) fn scatter_specular(&mut self, cos_out: f64) {
        let c = mis(cos_out);
        self.vcm = 0.0;
        self.vc = self.vc.map(|x| x * c);
        self.vm = self.vm.map(|x| x * c);
        self.last = 0.0;
    }
}

/// The weight of a camera path that hits an area light (or escapes to the environment):
/// `direct_pdf_a` is next-event estimation's density of that light point per area (for the
/// environment per solid angle), `emission_pdf_w` the density of a light path starting there.
pub(super) fn hit_light(cam: &Quantities, direct_pdf_a: f64, emission_pdf_w: f64) -> f64 {
    1.0 / (1.0 + mis(direct_pdf_a) * cam.vcm + mis(emission_pdf_w) * cam.vc)
}

/// Next-event estimation at a camera vertex: `bsdf_pdf` and `bsdf_rev` the camera BSDF's
/// densities toward the light and back (`bsdf_pdf` zero for a delta light), `direct_pdf_w`
/// the light sample's density per solid angle including the light choice (for a delta light
/// the squared distance times the choice), `emission_pdf_w` the density of a light path
/// leaving the light point toward the vertex (light choice, area, direction), the cosines at
/// the vertex and at the light (1 for a delta light and the environment). `gather`: the camera
/// vertex is the camera path's second after a non-specular first.
#[allow(clippy::too_many_arguments)]
pub(super) fn direct(
    f: &Factors,
    cam: &Quantities,
    gather: bool,
    bsdf_pdf: f64,
    bsdf_rev: f64,
    direct_pdf_w: f64,
    emission_pdf_w: f64,
    cos_to_light: f64,
    cos_at_light: f64,
) -> f64 {
    let w_light = mis(bsdf_pdf / direct_pdf_w);
    let w_camera = mis(emission_pdf_w * cos_to_light / (direct_pdf_w * cos_at_light))
        * (f.merge_at(gather) + cam.vcm + cam.vc * mis(bsdf_rev));
    1.0 / (w_light + 1.0 + w_camera)
}

/// A connection between a camera vertex and a light vertex: `cam_pdf_a` the camera BSDF's
/// density of the light vertex per area, `light_pdf_a` the light BSDF's of the camera vertex;
/// `cam_rev`, `light_rev` each BSDF's solid-angle density of its own subpath's previous
/// direction given the connection. `gather` says which end is the camera path's second vertex
/// after a non-specular first, if either: the camera vertex (the camera path's second) or the
/// light vertex (the camera vertex is the camera path's first).
#[allow(clippy::too_many_arguments)]
pub(super) fn connect(
    f: &Factors,
    cam: &Quantities,
    light: &Quantities,
    cam_pdf_a: f64,
    light_pdf_a: f64,
    cam_rev: f64,
    light_rev: f64,
    gather: GatherAt,
) -> f64 {
    let merge_light = f.merge_at(gather == GatherAt::Light);
    let merge_cam = f.merge_at(gather == GatherAt::Camera);
    let w_light = mis(cam_pdf_a) * (merge_light + light.vcm + light.vc * mis(light_rev));
    let w_camera = mis(light_pdf_a) * (merge_cam + cam.vcm + cam.vc * mis(cam_rev));
    1.0 / (w_light + 1.0 + w_camera)
}

/// A light vertex connected to the camera: `light` its quantities [`Parts::gathered`] (the
/// vertex before it is the camera path's second), `camera_pdf_a` the camera's density of the
/// vertex per area, `light_rev` the vertex BSDF's density of its previous direction given the
/// direction toward the camera.
pub(super) fn to_camera(f: &Factors, light: &Quantities, camera_pdf_a: f64, light_rev: f64) -> f64 {
    let w_light =
        mis(camera_pdf_a / f.light_paths) * (f.vm_weight + light.vcm + light.vc * mis(light_rev));
    1.0 / (w_light + 1.0)
}

/// A light vertex merged at a camera vertex: `cam_pdf` the camera BSDF's density of the light
/// vertex's incoming direction, `cam_rev` that of the camera path's previous direction given it.
/// At the camera path's first vertex `light` is [`Parts::gathered`]; `gather`: the camera
/// vertex is the camera path's second after a non-specular first (the final gather's merge,
/// radius R).
pub(super) fn merge(
    f: &Factors,
    cam: &Quantities,
    light: &Quantities,
    cam_pdf: f64,
    cam_rev: f64,
    gather: bool,
) -> f64 {
    let w_light = light.vcm * f.vc_weight + light.vm * mis(cam_pdf);
    let w_camera = cam.vcm * f.vc_weight + cam.vm * mis(cam_rev);
    if gather {
        1.0 / (1.0 + (w_light + w_camera) / f.gather_ratio)
    } else {
        1.0 / (w_light + 1.0 + w_camera)
    }
}

/// Which end of a connection is the camera path's second vertex after a non-specular first
/// (where the final gather merges), if either.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum GatherAt {
    Neither,
    Camera,
    Light,
}

#[cfg(test)]
mod tests;
