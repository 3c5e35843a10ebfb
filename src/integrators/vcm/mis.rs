//! The multiple-importance weights of vertex connection and merging, computed from three
//! quantities every subpath carries (Georgiev et al. 2012, "Light transport simulation with
//! vertex connection and merging", and its technical report's recursive form): `vcm`, `vc` and
//! `vm`. Each is a sum, over the techniques that would have sampled the subpath's vertices
//! from the other end, of the ratio of that technique's density to this one's, divided by
//! what the next step of the path (not known yet) contributes. With them a weight needs only
//! the vertex at each end of the connection or merge: no path is revisited.
//!
//! A merge's density relative to a connection's, `eta = pi r^2 N`, depends on the radius, and
//! the radius is each camera path's own (its pixel's footprint where it first meets a
//! non-specular surface): the quantities are carried in parts ([`Parts`]) that every weight
//! evaluates with the radius of the camera path at hand.
//!
//! Densities enter through `mis` (the power heuristic: squared). The same functions serve both
//! the renderer and the test that checks their weights against every technique's density
//! computed by brute force.

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
}

impl Factors {
    pub(super) fn new(radius: f64, light_paths: f64, use_vc: bool, use_vm: bool) -> Self {
        let eta = std::f64::consts::PI * radius * radius * light_paths;
        Self {
            vm_weight: if use_vm { mis(eta) } else { 0.0 },
            vc_weight: if use_vc { mis(1.0 / eta) } else { 0.0 },
            light_paths,
        }
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
///   factors without E.
///
/// So a light path's stored vertex holds its parts, and each connection, merge or light-traced
/// splat evaluates them with the E of the camera path it meets (for a splat, the camera path
/// that would end at the light vertex: the radius at the vertex's distance from the lens). The
/// techniques of one whole path then all see one radius, the camera end's, and the weights
/// are exactly the power heuristic's for that radius (`mis/tests.rs` checks it with a
/// different radius per camera path): a radius per camera path keeps them exact. Without
/// merging E is 0 (and without connections `1 / E` is 0), as in the recursion itself.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Parts {
    pub(super) vcm: f64,
    pub(super) vc: [f64; 2],
    pub(super) vm: [f64; 2],
}

impl Parts {
    /// At the camera: `light_paths` the light paths' count, `pdf_camera` the camera's
    /// solid-angle density of the first direction.
    pub(super) fn camera(light_paths: f64, pdf_camera: f64) -> Self {
        Self {
            vcm: mis(light_paths / pdf_camera),
            vc: [0.0; 2],
            vm: [0.0; 2],
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
    }

    /// Scattering at a non-specular vertex into a direction of cosine `cos_out`, sampled with
    /// solid-angle density `pdf_dir`; `pdf_rev` is the density of the reverse choice.
    pub(super) fn scatter(&mut self, cos_out: f64, pdf_dir: f64, pdf_rev: f64) {
        let (k, p) = (mis(cos_out / pdf_dir), mis(pdf_rev));
        *self = Self {
            vcm: mis(1.0 / pdf_dir),
            vc: [k * (self.vc[0] * p + self.vcm), k * (self.vc[1] * p + 1.0)],
            vm: [k * (self.vm[0] * p + 1.0), k * (self.vm[1] * p + self.vcm)],
        };
    }

    /// Scattering by a delta lobe: no technique can connect or merge at this vertex, and the
    /// forward and reverse densities are the same.
    pub(super) fn scatter_specular(&mut self, cos_out: f64) {
        let c = mis(cos_out);
        self.vcm = 0.0;
        self.vc = self.vc.map(|x| x * c);
        self.vm = self.vm.map(|x| x * c);
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
/// the vertex and at the light (1 for a delta light and the environment).
#[allow(clippy::too_many_arguments)]
pub(super) fn direct(
    f: &Factors,
    cam: &Quantities,
    bsdf_pdf: f64,
    bsdf_rev: f64,
    direct_pdf_w: f64,
    emission_pdf_w: f64,
    cos_to_light: f64,
    cos_at_light: f64,
) -> f64 {
    let w_light = mis(bsdf_pdf / direct_pdf_w);
    let w_camera = mis(emission_pdf_w * cos_to_light / (direct_pdf_w * cos_at_light))
        * (f.vm_weight + cam.vcm + cam.vc * mis(bsdf_rev));
    1.0 / (w_light + 1.0 + w_camera)
}

/// A connection between a camera vertex and a light vertex: `cam_pdf_a` the camera BSDF's
/// density of the light vertex per area, `light_pdf_a` the light BSDF's of the camera vertex;
/// `cam_rev`, `light_rev` each BSDF's solid-angle density of its own subpath's previous
/// direction given the connection.
pub(super) fn connect(
    f: &Factors,
    cam: &Quantities,
    light: &Quantities,
    cam_pdf_a: f64,
    light_pdf_a: f64,
    cam_rev: f64,
    light_rev: f64,
) -> f64 {
    let w_light = mis(cam_pdf_a) * (f.vm_weight + light.vcm + light.vc * mis(light_rev));
    let w_camera = mis(light_pdf_a) * (f.vm_weight + cam.vcm + cam.vc * mis(cam_rev));
    1.0 / (w_light + 1.0 + w_camera)
}

/// A light vertex connected to the camera: `camera_pdf_a` the camera's density of the vertex
/// per area, `light_rev` the vertex BSDF's density of its previous direction given the
/// direction toward the camera.
pub(super) fn to_camera(f: &Factors, light: &Quantities, camera_pdf_a: f64, light_rev: f64) -> f64 {
    let w_light =
        mis(camera_pdf_a / f.light_paths) * (f.vm_weight + light.vcm + light.vc * mis(light_rev));
    1.0 / (w_light + 1.0)
}

/// A light vertex merged at a camera vertex: `cam_pdf` the camera BSDF's density of the light
/// vertex's incoming direction, `cam_rev` that of the camera path's previous direction given it.
pub(super) fn merge(
    f: &Factors,
    cam: &Quantities,
    light: &Quantities,
    cam_pdf: f64,
    cam_rev: f64,
) -> f64 {
    let w_light = light.vcm * f.vc_weight + light.vm * mis(cam_pdf);
    let w_camera = cam.vcm * f.vc_weight + cam.vm * mis(cam_rev);
    1.0 / (w_light + 1.0 + w_camera)
}

#[cfg(test)]
mod tests;
