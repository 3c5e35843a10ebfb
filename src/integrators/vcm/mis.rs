//! The multiple-importance weights of vertex connection and merging, computed from three
//! quantities every subpath carries (Georgiev et al. 2012, "Light transport simulation with
//! vertex connection and merging", and its technical report's recursive form): `vcm`, `vc` and
//! `vm`. Each is a sum, over the techniques that would have sampled the subpath's vertices
//! from the other end, of the ratio of that technique's density to this one's, divided by
//! what the next step of the path (not known yet) contributes. With them a weight needs only
//! the vertex at each end of the connection or merge: no path is revisited.
//!
//! Densities enter through `mis` (the power heuristic: squared). The same functions serve both
//! the renderer and the test that checks their weights against every technique's density
//! computed by brute force.
//!
//! **The final gather.** With final gathering, the merge at a camera path's second vertex
//! after a non-specular first uses a wider radius `R` (`GATHER_RADIUS_FACTOR` times `r`, as
//! SPPM's gather points): a technique of its own, whose density is that of the merge at the
//! same vertex with `pi R^2 N` in place of `pi r^2 N`, and which takes the place of that merge.
//! In the sums it changes the terms that count the merge at that vertex: in `vc` the merge's
//! density over a connection's, `vm_weight = mis(pi r^2 N)`, becomes
//! `gather_weight = mis(pi R^2 N)`; in `vm` the merge's density over the merge at the next
//! vertex, 1, becomes `gather_ratio = mis(R^2 / r^2)`. The camera path knows which of its
//! vertices is its second: its `scatter` there, and the merge factor at that vertex in `direct`
//! and `connect`, take the gather's terms. A light vertex does not know it ahead: it turns out
//! to be the camera path's second in a connection whose camera part is one vertex (the light
//! end itself: its merge factor in `connect`), and its predecessor does when light tracing
//! connects it to the camera or a camera path merges with it at its first vertex. For those
//! each subpath keeps apart `last`, the coefficient with which its last `scatter` added the
//! merge at the vertex it scattered at (times `vm_weight` in `vc`, times 1 in `vm`), and
//! [`Quantities::gathered`] re-evaluates that term with the gather's factors. The gather merge
//! itself is weighed against the same techniques as the merge with `r` at its vertex, each of
//! whose densities is now over `R^2 / r^2` times as much: its weight is
//! `1 / (1 + (w_light + w_camera) / gather_ratio)` from that merge's sums. `vcm::mis::tests`
//! checks it all against brute force.

/// The heuristic: the power heuristic with exponent 2.
#[inline]
pub(super) fn mis(x: f64) -> f64 {
    x * x
}

/// Per-iteration constants of the weights.
#[derive(Debug, Clone, Copy)]
pub(super) struct Factors {
    /// `mis(eta)` with `eta = pi r^2 N` when merging is used, else 0: a merge's density relative
    /// to the connection at the same vertex.
    pub(super) vm_weight: f64,
    /// `mis(1 / eta)` when connections are used, else 0.
    pub(super) vc_weight: f64,
    /// Number of light paths per iteration (one per pixel, or a quarter as many).
    pub(super) light_paths: f64,
    /// Whether the final gather's merge is used ([`Factors::with_gather`]).
    pub(super) gather: bool,
    /// `mis(pi R^2 N)`: the gather merge's density relative to the connection at its vertex
    /// (without the final gather, `vm_weight`).
    pub(super) gather_weight: f64,
    /// `mis(R^2 / r^2)`: the gather merge's density over the merge with `r` at the same vertex
    /// (without the final gather, 1).
    pub(super) gather_ratio: f64,
}

impl Factors {
    pub(super) fn new(radius: f64, light_paths: f64, use_vc: bool, use_vm: bool) -> Self {
        let eta = std::f64::consts::PI * radius * radius * light_paths;
        Self {
            vm_weight: if use_vm { mis(eta) } else { 0.0 },
            vc_weight: if use_vc { mis(1.0 / eta) } else { 0.0 },
            light_paths,
            gather: false,
            gather_weight: if use_vm { mis(eta) } else { 0.0 },
            gather_ratio: 1.0,
        }
    }

    /// The same with the final gather, of radius `factor` times the merges' (nothing changes
    /// without merging).
    pub(super) fn with_gather(self, factor: f64) -> Self {
        if self.vm_weight <= 0.0 {
            return self;
        }
        let ratio = mis(factor * factor);
        Self {
            gather: true,
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
}

/// The recursive quantities of a subpath at its last vertex.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Quantities {
    pub(super) vcm: f64,
    pub(super) vc: f64,
    pub(super) vm: f64,
    /// The coefficient with which the last `scatter` added the merge at its vertex (the one
    /// before this), to `vc` times that merge's factor and to `vm` times its ratio to a merge
    /// with `r`; zero after a light point or a delta bounce (no merge there).
    pub(super) last: f64,
}

impl Quantities {
    /// At the camera: `pdf_camera` is the camera's solid-angle density of the first direction.
    pub(super) fn camera(f: &Factors, pdf_camera: f64) -> Self {
        Self {
            vcm: mis(f.light_paths / pdf_camera),
            vc: 0.0,
            vm: 0.0,
            last: 0.0,
        }
    }

    /// At a light path's first surface: `direct_pdf_a` is the density per area of the light
    /// point for next-event estimation from that surface (for a delta light the choice of the
    /// light alone), `emission_pdf_w` the emission's density (light choice, area, direction),
    /// `cos_light` the cosine at the light (zero for a delta light: no connection reaches it;
    /// 1 for the environment, whose directions are measured without one).
    pub(super) fn light(
        f: &Factors,
        direct_pdf_a: f64,
        emission_pdf_w: f64,
        cos_light: f64,
    ) -> Self {
        let vc = mis(cos_light / emission_pdf_w);
        Self {
            vcm: mis(direct_pdf_a / emission_pdf_w),
            vc,
            vm: vc * f.vc_weight,
            last: 0.0,
        }
    }

    /// Arriving at a surface after a segment of squared length `dist2` (`None`: the light
    /// point's own distance is already in `light`'s `direct_pdf_a`), at cosine `cos`.
    pub(super) fn arrive(&mut self, dist2: Option<f64>, cos: f64) {
        if let Some(d2) = dist2 {
            self.vcm *= mis(d2);
        }
        let c = mis(cos.abs());
        self.vcm /= c;
        self.vc /= c;
        self.vm /= c;
        self.last /= c;
    }

    /// Scattering at a non-specular vertex into a direction of cosine `cos_out`, sampled with
    /// solid-angle density `pdf_dir`; `pdf_rev` is the density of the reverse choice. `gather`:
    /// the vertex is the camera path's second after a non-specular first (its merge is the
    /// final gather's).
    pub(super) fn scatter(
        &mut self,
        f: &Factors,
        cos_out: f64,
        pdf_dir: f64,
        pdf_rev: f64,
        gather: bool,
    ) {
        let k = mis(cos_out / pdf_dir);
        let ratio = if gather { f.gather_ratio } else { 1.0 };
        let vc = k * (self.vc * mis(pdf_rev) + self.vcm + f.merge_at(gather));
        let vm = k * (self.vm * mis(pdf_rev) + self.vcm * f.vc_weight + ratio);
        *self = Self {
            vcm: mis(1.0 / pdf_dir),
            vc,
            vm,
            last: k,
        };
    }

    /// Scattering by a delta lobe: no technique can connect or merge at this vertex, and the
    /// forward and reverse densities are the same.
    pub(super) fn scatter_specular(&mut self, cos_out: f64) {
        self.vcm = 0.0;
        self.vc *= mis(cos_out);
        self.vm *= mis(cos_out);
        self.last = 0.0;
    }

    /// A light vertex's quantities when the vertex before it is the camera path's second
    /// (light tracing connects this vertex to the camera, or a camera path merges with it at
    /// its first vertex): the merge there is the final gather's. Unchanged without it.
    pub(super) fn gathered(&self, f: &Factors) -> Self {
        if !f.gather {
            return *self;
        }
        Self {
            vc: self.vc + self.last * (f.gather_weight - f.vm_weight),
            vm: self.vm + self.last * (f.gather_ratio - 1.0),
            ..*self
        }
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

/// A light vertex connected to the camera: `light` its quantities [`Quantities::gathered`] (the
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
/// At the camera path's first vertex `light` is [`Quantities::gathered`]; `gather`: the camera
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
