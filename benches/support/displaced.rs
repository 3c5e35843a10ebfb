//! The scale benchmark's mesh and rays, shared with the instruction-count workloads
//! (`benches/scale.rs`, `benches/instructions.rs`): a displaced sphere, camera rays that it
//! fills and diffuse bounces from their hits.

use glam::Vec3A;
use sppm_lang::internals::accel::Bvh;
use sppm_lang::internals::geometry::Ray;
use sppm_lang::internals::shapes::mesh::TriangleMesh;

/// A mesh as two buffers: vertices and three vertex indices per triangle.
pub struct Mesh {
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

/// A UV sphere of about `n` triangles with smooth bumps of a tenth of its radius.
pub fn displaced_sphere(n: usize) -> Mesh {
    let rings = ((n as f64 / 4.0).sqrt().round() as u32).max(4);
    let segments = (n as u32 / (2 * rings)).max(4);
    let mut vertices = Vec::with_capacity(((rings + 1) * segments) as usize);
    for i in 0..=rings {
        let th = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segments {
            let ph = std::f64::consts::TAU * j as f64 / segments as f64;
            let r = 1.0
                + 0.06 * (7.0 * th).sin() * (5.0 * ph).cos()
                + 0.03 * (23.0 * th + 1.0).sin() * (17.0 * ph).sin();
            vertices.push([
                (r * th.sin() * ph.cos()) as f32,
                (r * th.cos()) as f32,
                (r * th.sin() * ph.sin()) as f32,
            ]);
        }
    }
    let idx = |i: u32, j: u32| i * segments + j % segments;
    let mut triangles = Vec::with_capacity(n);
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (idx(i, j), idx(i, j + 1), idx(i + 1, j), idx(i + 1, j + 1));
            if i > 0 {
                triangles.push([a, b, c]);
            }
            if i + 1 < rings {
                triangles.push([b, d, c]);
            }
        }
    }
    Mesh {
        vertices,
        triangles,
    }
}

/// The mesh as the renderer stores it: a shared vertex buffer and three indices per triangle.
pub fn triangle_mesh(mesh: &Mesh) -> TriangleMesh {
    TriangleMesh::from_buffers(mesh.vertices.clone(), &mesh.triangles)
}

pub fn mesh_bvh(mesh: TriangleMesh) -> Bvh {
    Bvh::with_meshes(Vec::new(), vec![(mesh, 0)]).expect("a BVH of bench size")
}

/// `side` x `side` camera rays from a pinhole at distance 2.4 whose view the mesh fills.
pub fn camera_rays(side: u32) -> Vec<Ray> {
    let eye = Vec3A::new(0.0, 0.3, -2.4);
    let forward = (-eye).normalize();
    let right = Vec3A::Y.cross(forward).normalize();
    let up = forward.cross(right);
    let half = (25f32.to_radians()).tan();
    let n = side;
    (0..n * n)
        .map(|k| {
            let (x, y) = (k % n, k / n);
            let sx = (2.0 * (x as f32 + 0.5) / n as f32 - 1.0) * half;
            let sy = (1.0 - 2.0 * (y as f32 + 0.5) / n as f32) * half;
            Ray::new(eye, (forward + sx * right + sy * up).normalize())
        })
        .collect()
}

/// `count` diffuse bounces: from each camera hit (cycled), a cosine-distributed direction about the
/// side of the surface the camera saw.
pub fn bounce_rays(bvh: &Bvh, camera: &[Ray], count: usize) -> Vec<Ray> {
    let hits: Vec<(Vec3A, Vec3A)> = camera
        .iter()
        .filter_map(|r| {
            let (h, _) = bvh.intersect(r, 0.0, f32::INFINITY)?;
            let n = if h.n.dot(r.d) < 0.0 { h.n } else { -h.n };
            Some((h.p, n))
        })
        .collect();
    assert!(!hits.is_empty(), "the camera sees the mesh");
    let mut rnd = uniform_floats(0x2545f4914f6cdd1d);
    (0..count)
        .map(|k| {
            let (p, n) = hits[k % hits.len()];
            let (u1, u2) = (rnd(), rnd());
            let (r, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
            let t = if n.x.abs() > 0.9 { Vec3A::Y } else { Vec3A::X };
            let (a, b) = (t.cross(n).normalize(), n.cross(t.cross(n).normalize()));
            let d = a * r * phi.cos() + b * r * phi.sin() + n * (1.0 - u1).max(0.0).sqrt();
            Ray::new(p + n * 1e-4, d.normalize())
        })
        .collect()
}

/// Floats uniform in [0, 1) from a xorshift64 generator seeded with `seed` (not zero): the
/// benches' fixed, dependency-free random numbers.
pub fn uniform_floats(seed: u64) -> impl FnMut() -> f32 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    }
}
