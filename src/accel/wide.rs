//! The BVH as traversed: 8-wide nodes collapsed from the binary SAH tree, each holding its
//! children's boxes in SoA form so that one ray tests all eight at once (in one AVX register
//! when the CPU has AVX, else as two halves of four), visiting the hit children nearest first.

use arrayvec::ArrayVec;
use glam::{Vec3A, Vec4};
use rayon::prelude::*;

use super::bvh::Node as BinaryNode;
use crate::geometry::{Aabb, Ray};
use plan::Choice;

mod plan;

/// Children per node.
pub(super) const WIDTH: usize = 8;
/// A child reference with this bit set names a leaf (the rest is its leaf reference, see
/// [`super::leaf::PACKETS`]).
pub(super) const LEAF: u32 = 1 << 31;
/// An unused child slot.
const EMPTY: u32 = u32::MAX;
/// The unit of an interior child reference: the node lies `reference * NODE_UNIT` bytes from
/// the first node, so that the traversal's step to it is one addressing mode (base plus
/// reference times 8), where a node index took a multiply by the node's 224 bytes.
pub(super) const NODE_UNIT: usize = 8;
/// A node's size in [`NODE_UNIT`]s: an interior reference is the node's index times this.
const NODE_STEP: usize = std::mem::size_of::<WideNode>() / NODE_UNIT;
const _: () = assert!(std::mem::size_of::<WideNode>().is_multiple_of(NODE_UNIT));
const _: () = assert!(std::mem::align_of::<WideNode>() >= NODE_UNIT);
/// Far bounds are scaled up by 1 + 2*gamma(3) (pbrt) so that rounding never culls a hit, as
/// in [`Aabb::hit`].
const FAR_SCALE: f32 = 1.000_000_4;

/// Eight children's boxes: their minima on x, y, z, then their maxima on x, y, z, each plane as
/// two halves of four.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C, align(32))]
pub(super) struct WideNode {
    planes: [[Vec4; 2]; 6],
    /// Interior child: its node index times [`NODE_STEP`] (its byte offset over
    /// [`NODE_UNIT`]); leaf: `LEAF | leaf reference`; unused: `EMPTY`.
    pub child: [u32; WIDTH],
}

/// A ray set up for box tests.
pub(super) struct BoxRay {
    o: [f32; 3],
    inv_d: [f32; 3],
    /// Per axis: the byte offset in a [`WideNode`] of the plane (in [`WideNode::planes`])
    /// through which the ray enters the boxes, plane `a` (the minima) or, when the ray runs
    /// toward decreasing coordinates, plane `a + 3` (the maxima); always a plane below 6
    /// times [`PLANE_BYTES`]. (Offsets, not indices: the AVX test adds them to the node's
    /// address as they are, where an index took a shift per plane and node.)
    enter: [usize; 3],
    /// Per axis: the byte offset of the plane through which it leaves them (the other one).
    leave: [usize; 3],
}

/// Bytes of one plane of a [`WideNode`] (eight `f32`s).
const PLANE_BYTES: usize = std::mem::size_of::<[Vec4; 2]>();

impl BoxRay {
    /// Whether the box test can take `ray`: its origin and its direction are finite.
    /// On an axis where the origin is NaN or infinite or the direction infinite (inverse 0) or
    /// NaN, slab distances are NaN (or an infinite origin's, infinite either way) and every
    /// slab distance is NaN and ignored; a ray ignored on all three axes would enter every
    /// box, the unused slots' inverted ones too, and reach a child reference that names
    /// nothing. Such a ray has no meaningful hit: the BVH reports none.
    #[inline(always)]
    pub(super) fn usable(ray: &Ray) -> bool {
        ray.o.is_finite() && ray.d.is_finite()
    }

    #[inline(always)]
    pub(super) fn new(ray: &Ray) -> Self {
        let inv_d: Vec3A = ray.d.recip();
        // Written out per axis: `[0, 1, 2].map(..)` stayed two out-of-line calls in the
        // traversal, paid on every query.
        let (nx, ny, nz) = (
            3 * usize::from(inv_d.x < 0.0),
            3 * usize::from(inv_d.y < 0.0),
            3 * usize::from(inv_d.z < 0.0),
        );
        let p = PLANE_BYTES;
        Self {
            o: ray.o.to_array(),
            inv_d: inv_d.to_array(),
            enter: [nx * p, (1 + ny) * p, (2 + nz) * p],
            leave: [(3 - nx) * p, (4 - ny) * p, (5 - nz) * p],
        }
    }
}

/// A box test: [`Halves`] on any CPU, [`Avx`] where the CPU has AVX.
pub(super) trait BoxTest: Copy {
    /// The children of `node` whose box the ray enters with `t_min <= t <= t_max`
    /// (conservatively, as [`Aabb::hit`]), as a bit mask, and the entry distances. The entry
    /// and exit planes are chosen by the ray's signs; a NaN slab distance (a ray in a slab's
    /// plane, parallel to it) is ignored. Unused slots are never in the mask. Both tests do
    /// the same operations in the same order, so they give the same bits.
    fn hit(self, node: &WideNode, ray: &BoxRay, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]);
}

/// The box test four children at a time (SSE on x86-64).
#[derive(Clone, Copy)]
pub(super) struct Halves;

impl BoxTest for Halves {
    #[inline(always)]
    fn hit(self, node: &WideNode, ray: &BoxRay, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut out = [0.0; WIDTH];
        for h in 0..2 {
            let mut near = Vec4::splat(t_min);
            let mut far = Vec4::splat(t_max);
            for a in 0..3 {
                let (lo, hi) = (
                    node.planes[ray.enter[a] / PLANE_BYTES][h],
                    node.planes[ray.leave[a] / PLANE_BYTES][h],
                );
                let (o, inv_d) = (Vec4::splat(ray.o[a]), Vec4::splat(ray.inv_d[a]));
                // `x.max(acc)` keeps `acc` where `x` is NaN (SSE `maxps` returns its second
                // operand when either is NaN), as `Aabb::hit` does.
                near = ((lo - o) * inv_d).max(near);
                far = ((hi - o) * inv_d).min(far);
            }
            mask |= near.cmple(far * FAR_SCALE).bitmask() << (4 * h);
            out[4 * h..4 * h + 4].copy_from_slice(&near.to_array());
        }
        (mask, out)
    }
}

/// The box test eight children at a time; a value exists only where the CPU has AVX.
#[derive(Clone, Copy)]
pub(super) struct Avx(());

impl Avx {
    /// The AVX box test, if the CPU has AVX.
    #[inline]
    pub(super) fn detect() -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            return Some(Self(()));
        }
        None
    }
}

impl BoxTest for Avx {
    #[inline(always)]
    fn hit(self, node: &WideNode, ray: &BoxRay, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: an `Avx` value is made only after AVX was detected.
            unsafe { hit_avx(node, ray, t_min, t_max) }
        }
        #[cfg(not(target_arch = "x86_64"))]
        Halves.hit(node, ray, t_min, t_max)
    }
}

/// [`BoxTest::hit`] eight children at a time.
///
/// # Safety
///
/// The CPU must have AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
unsafe fn hit_avx(node: &WideNode, ray: &BoxRay, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
    use std::arch::x86_64::*;
    let base = node.planes.as_ptr().cast::<u8>();
    let load = |offset: usize| {
        // SAFETY: `BoxRay` plane offsets are those of planes below 6 (see `BoxRay::new`), and
        // a plane, `[Vec4; 2]`, is eight consecutive `f32`s. (Unchecked: the bounds checks
        // were a compare and branch per plane and node.)
        unsafe { _mm256_loadu_ps(base.add(offset).cast::<f32>()) }
    };
    let mut near = _mm256_set1_ps(t_min);
    let mut far = _mm256_set1_ps(t_max);
    for a in 0..3 {
        let (lo, hi) = (ray.enter[a], ray.leave[a]);
        let (o, inv_d) = (_mm256_set1_ps(ray.o[a]), _mm256_set1_ps(ray.inv_d[a]));
        // `vmaxps` and `vminps` return their second operand on NaN, as `maxps` does.
        near = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(load(lo), o), inv_d), near);
        far = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(load(hi), o), inv_d), far);
    }
    let far = _mm256_mul_ps(far, _mm256_set1_ps(FAR_SCALE));
    // Ordered, non-signalling `<=`: false on NaN, as `cmpleps`.
    let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(near, far)) as u32;
    let mut out = [0.0; WIDTH];
    // SAFETY: `out` holds eight `f32`s.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), near) };
    (mask, out)
}

/// Whether a child entered at `near` may still hold a hit closer than `t_max` (the test of
/// [`BoxTest::hit`] against a shrunk `t_max`).
#[inline(always)]
pub(super) fn still_near(near: f32, t_max: f32) -> bool {
    near <= t_max * FAR_SCALE
}

/// Binary nodes from which the collapse (and its plan) works in parallel.
const PARALLEL_NODES: usize = 1 << 14;
/// Levels of the wide tree whose subtrees are collapsed as parallel tasks (up to 8^2 tasks).
const PARALLEL_LEVELS: usize = 2;

/// Collapses the binary tree (flattened depth-first: an interior node's first child follows
/// it, `offset` names the second; a leaf's `offset` is its leaf reference) into 8-wide nodes,
/// depth-first: each node takes its two children's subtrees opened as the [`plan`] says (the
/// collapse of least summed surface area over the wide nodes), in the binary tree's order.
/// The root is node 0.
///
/// In a large tree the subtrees of the top levels are collapsed in parallel, each into its
/// own run of nodes, and the runs are joined in depth-first order: the nodes are the same on
/// any number of threads.
///
/// The collapse links the nodes by index; the interior references are then turned into
/// offsets ([`NODE_STEP`] per node). `None` when there are more nodes than those offsets can
/// name below the [`LEAF`] bit ([`fits`]).
pub(super) fn collapse(nodes: &[BinaryNode]) -> Option<Vec<WideNode>> {
    if nodes.is_empty() {
        return Some(Vec::new());
    }
    if nodes[0].count > 0 {
        // A single leaf: one node with one child.
        return Some(vec![WideNode::from_children(
            nodes,
            &[0],
            &[LEAF | nodes[0].offset],
        )]);
    }
    let levels = if nodes.len() >= PARALLEL_NODES {
        PARALLEL_LEVELS
    } else {
        0
    };
    let plan = plan::plan(nodes, PARALLEL_NODES);
    let mut out = collapse_run(nodes, &plan, 0, levels);
    if !fits(out.len()) {
        return None;
    }
    // (Serial: a parallel pass took the wall time of a 10^5-triangle build from about 0.02 s
    // to 0.04 s.)
    for n in &mut out {
        for c in &mut n.child {
            if *c & LEAF == 0 {
                // (At most `(LEAF - 1) / NODE_STEP`, as `fits` checked: no overflow.)
                *c *= NODE_STEP as u32;
            }
        }
    }
    out.shrink_to_fit();
    Some(out)
}

/// Whether `count` nodes can all be named by interior references: the last one's offset,
/// `(count - 1) * NODE_STEP`, stays below the [`LEAF`] bit (about 76.7 million nodes, a tree of
/// over a billion triangles).
pub(super) fn fits(count: usize) -> bool {
    count <= (LEAF as usize - 1) / NODE_STEP + 1
}

/// The wide subtree of interior binary node `i` as a run of nodes whose references count from
/// the run's start; `levels` more levels are collapsed in parallel.
fn collapse_run(nodes: &[BinaryNode], plan: &[Choice], i: usize, levels: usize) -> Vec<WideNode> {
    let mut out = Vec::new();
    if levels == 0 {
        collapse_at(nodes, plan, i, &mut out);
        return out;
    }
    let kids = kids_of(nodes, plan, i);
    let runs: Vec<Option<Vec<WideNode>>> = kids
        .par_iter()
        .map(|&k| (nodes[k].count == 0).then(|| collapse_run(nodes, plan, k, levels - 1)))
        .collect();
    out.push(WideNode::from_children(nodes, &[], &[]));
    let mut refs: ArrayVec<u32, WIDTH> = ArrayVec::new();
    for (&k, run) in kids.iter().zip(runs) {
        match run {
            None => refs.push(LEAF | nodes[k].offset),
            Some(run) => {
                let base = out.len() as u32;
                refs.push(base);
                out.extend(run.into_iter().map(|mut n| {
                    // (Leaf and unused references both have the `LEAF` bit: they stay.)
                    for c in &mut n.child {
                        if *c & LEAF == 0 {
                            // (Wrapping only in a tree `collapse` then refuses.)
                            *c = c.wrapping_add(base);
                        }
                    }
                    n
                }));
            }
        }
    }
    out[0] = WideNode::from_children(nodes, &kids, &refs);
    out
}

fn collapse_at(nodes: &[BinaryNode], plan: &[Choice], i: usize, out: &mut Vec<WideNode>) -> u32 {
    let idx = out.len();
    out.push(WideNode::from_children(nodes, &[], &[]));
    let kids = kids_of(nodes, plan, i);
    let refs: ArrayVec<u32, WIDTH> = kids
        .iter()
        .map(|&k| {
            if nodes[k].count > 0 {
                LEAF | nodes[k].offset
            } else {
                collapse_at(nodes, plan, k, out)
            }
        })
        .collect();
    out[idx] = WideNode::from_children(nodes, &kids, &refs);
    idx as u32
}

/// The children of the wide node made from interior binary node `i`: its two children's
/// subtrees opened into eight slots as `plan` says, in the binary tree's order.
fn kids_of(nodes: &[BinaryNode], plan: &[Choice], i: usize) -> ArrayVec<usize, WIDTH> {
    let mut kids = ArrayVec::new();
    // (From 1 to 7 by construction: clamped so that the two shares always make eight.)
    let first = usize::from(plan[i][0]).clamp(1, WIDTH - 1);
    plan::open(nodes, plan, i + 1, first, &mut kids);
    plan::open(
        nodes,
        plan,
        nodes[i].offset as usize,
        WIDTH - first,
        &mut kids,
    );
    kids
}

impl WideNode {
    fn from_children(nodes: &[BinaryNode], kids: &[usize], refs: &[u32]) -> Self {
        // Unused slots get inverted infinite boxes (min +inf, max -inf), which no ray enters:
        // on each axis the entry distance is +inf and the exit distance -inf, whatever the
        // ray's signs, so they never reach the hit mask.
        let mut n = Self {
            planes: [
                [Vec4::INFINITY; 2],
                [Vec4::INFINITY; 2],
                [Vec4::INFINITY; 2],
                [Vec4::NEG_INFINITY; 2],
                [Vec4::NEG_INFINITY; 2],
                [Vec4::NEG_INFINITY; 2],
            ],
            child: [EMPTY; WIDTH],
        };
        for (slot, (&k, &r)) in kids.iter().zip(refs).enumerate() {
            let b: Aabb = nodes[k].bounds;
            for a in 0..3 {
                n.planes[a][slot / 4][slot % 4] = b.min[a];
                n.planes[a + 3][slot / 4][slot % 4] = b.max[a];
            }
            n.child[slot] = r;
        }
        n
    }
}

/// A node of unused boxes with the given child references (for tests of what is done with
/// them).
#[cfg(test)]
impl WideNode {
    pub(super) fn with_children(child: [u32; WIDTH]) -> Self {
        Self {
            planes: [[Vec4::ZERO; 2]; 6],
            child,
        }
    }
}

#[cfg(test)]
mod tests;
