//! What a BVH leaf holds, packed after the build: its mesh triangles four to a packet, its
//! quads four to a packet (when it has two or more), and its other shapes one by one.

use glam::Vec3A;
use rayon::prelude::*;

use crate::geometry::Ray;

use super::build::Item;
use super::triangles::{Meshes, PairTest, TrianglePacket};
use crate::shapes::primitive::{AnyShape, LazyHit};
use crate::shapes::quad::{Quad, QuadPacket};

#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Leaf {
    /// First of its shapes in the BVH's shape list (its quads first when it has packets).
    pub shapes: u32,
    /// First of its quad packets.
    pub packet: u32,
    /// First of its triangle packets.
    pub tri_packet: u32,
    /// Shapes in the shape list.
    pub count: u8,
    /// How many of its shapes (the first ones) are quads tested in packets.
    pub quads: u8,
    /// Triangle packets.
    pub tris: u8,
}

/// A leaf reference with this bit set names a leaf of mesh triangles only by its packets
/// directly, without a [`Leaf`] record: bits 0..29 hold its first packet, bit 29 is set when it
/// has two. Otherwise a leaf reference is the leaf's index in the leaf list.
pub(super) const PACKETS: u32 = 1 << 30;
const TWO_PACKETS: u32 = 1 << 29;

/// The index of the first triangle packet of a leaf referenced by its packets ([`PACKETS`]),
/// and whether it has a second.
#[inline(always)]
fn packet_span(leaf: u32) -> (usize, bool) {
    ((leaf & (TWO_PACKETS - 1)) as usize, leaf & TWO_PACKETS != 0)
}

/// The packed contents of all leaves.
#[derive(Default)]
pub(super) struct Leaves {
    pub leaves: Vec<Leaf>,
    pub shapes: Vec<AnyShape>,
    pub ids: Vec<u32>,
    /// Each leaf's quads, four to a packet (the same quads are also in `shapes`).
    pub packets: Vec<QuadPacket>,
    pub tri_packets: Vec<TrianglePacket>,
}

/// The closest hit found so far in a traversal.
pub(super) struct Closest {
    /// The shape hit (its index in the shape list; `usize::MAX`: none, or a triangle).
    pub shape: usize,
    /// The mesh triangle hit (its global number; `u32::MAX`: none, or a shape).
    pub triangle: u32,
    /// The mesh triangle hit's barycentric coordinates (of its second and third vertex).
    pub bary: [f32; 2],
    /// The hit of a boxed shape or CSG tree (full, with its CSG part, or deferred); `None`
    /// for an analytic shape (only its `t` is known).
    pub boxed: Option<LazyHit>,
    /// The reference of the last leaf referenced by its packets ([`PACKETS`]) in which a
    /// triangle was recorded (0: none), kept only by the traversal that asks for it
    /// ([`Leaves::closest`]'s `KEEP_LEAF`). Written with the hit and never cleared, so it may
    /// name a leaf of an earlier, farther hit: [`Leaves::packet_normal`] checks that the leaf
    /// holds the triangle.
    pub leaf: u32,
}

impl Closest {
    pub(super) const NONE: Self = Self {
        shape: usize::MAX,
        triangle: u32::MAX,
        bary: [0.0; 2],
        boxed: None,
        leaf: 0,
    };
}

impl Leaves {
    /// Packs the leaves whose items are `ranges` of `items` (first item, count; in the build's
    /// order, where a shape item's index is its slot in `slots` and a triangle's is `nb` plus
    /// its global number). Returns each leaf's reference. The triangle packets are made in
    /// parallel, in leaf order; the shapes are moved serially.
    pub(super) fn pack(
        &mut self,
        items: &[Item],
        ranges: &[(u32, u16)],
        nb: usize,
        slots: &mut [Option<(AnyShape, u32)>],
        meshes: &Meshes,
    ) -> Vec<u32> {
        let leaf_items = |&(first, count): &(u32, u16)| &items[first as usize..][..count as usize];
        let triangles = |leaf: &[Item]| {
            leaf.iter()
                .filter_map(|it| it.index.checked_sub(nb))
                .map(|g| {
                    let (mesh, k, _) = meshes.locate(g as u32);
                    (mesh.vertices(k), g as u32)
                })
                .collect::<Vec<_>>()
        };
        let counts: Vec<usize> = ranges
            .par_iter()
            .map(|r| {
                leaf_items(r)
                    .iter()
                    .filter(|it| it.index >= nb)
                    .count()
                    .div_ceil(4)
            })
            .collect();
        let start = self.tri_packets.len();
        self.tri_packets
            .par_extend(ranges.par_iter().flat_map_iter(|r| {
                let tris = triangles(leaf_items(r));
                tris.chunks(4).map(TrianglePacket::new).collect::<Vec<_>>()
            }));
        let mut packet = start;
        ranges
            .iter()
            .zip(counts)
            .map(|(r, tris)| {
                let shapes = leaf_items(r).iter().filter(|it| it.index < nb);
                let leaf = self.push(shapes.map(|it| it.index), packet, tris, slots);
                packet += tris;
                leaf
            })
            .collect()
    }

    /// Appends a leaf of the shapes in `slots` at `shapes` and `tris` triangle packets from
    /// `tri_packet` on; returns its reference (below `1 << 31`).
    fn push(
        &mut self,
        shapes: impl Iterator<Item = usize>,
        tri_packet: usize,
        tris: usize,
        slots: &mut [Option<(AnyShape, u32)>],
    ) -> u32 {
        let mut shapes: Vec<(AnyShape, u32)> = shapes.filter_map(|i| slots[i].take()).collect();
        if shapes.is_empty() && (1..=2).contains(&tris) && tri_packet < TWO_PACKETS as usize {
            return PACKETS | tri_packet as u32 | if tris == 2 { TWO_PACKETS } else { 0 };
        }
        let mut leaf = Leaf {
            shapes: self.shapes.len() as u32,
            packet: self.packets.len() as u32,
            tri_packet: tri_packet as u32,
            tris: tris as u8,
            ..Leaf::default()
        };
        // Leaves with two quads or more list them first and test them four at a time.
        let is_quad = |s: &(AnyShape, u32)| matches!(s.0, AnyShape::Quad(_));
        let quads = shapes.iter().filter(|s| is_quad(s)).count();
        if quads >= 2 {
            shapes.sort_by_key(|s| !is_quad(s));
            leaf.quads = quads as u8;
            let qs: Vec<Quad> = shapes[..quads]
                .iter()
                .filter_map(|s| match &s.0 {
                    AnyShape::Quad(q) => Some(*q),
                    _ => None,
                })
                .collect();
            self.packets.extend(qs.chunks(4).map(QuadPacket::new));
        }
        leaf.count = shapes.len() as u8;
        for (s, id) in shapes {
            self.shapes.push(s);
            self.ids.push(id);
        }
        self.leaves.push(leaf);
        (self.leaves.len() - 1) as u32
    }

    pub(super) fn shrink_to_fit(&mut self) {
        self.leaves.shrink_to_fit();
        self.shapes.shrink_to_fit();
        self.ids.shrink_to_fit();
        self.packets.shrink_to_fit();
        self.tri_packets.shrink_to_fit();
    }

    /// The quad packets of a leaf.
    #[inline]
    pub(super) fn quad_packets(&self, leaf: &Leaf) -> &[QuadPacket] {
        let n = (leaf.quads as usize).div_ceil(4);
        &self.packets[leaf.packet as usize..][..n]
    }

    /// The triangle packets of a leaf.
    #[inline]
    pub(super) fn triangle_packets(&self, leaf: &Leaf) -> &[TrianglePacket] {
        &self.tri_packets[leaf.tri_packet as usize..][..leaf.tris as usize]
    }

    /// The triangle packets of a leaf referenced by its packets ([`PACKETS`]): one, or two
    /// (`Err`).
    /// (Read without a bounds check: the checks were two compares and branches per leaf.)
    #[inline(always)]
    fn direct_packets(&self, leaf: u32) -> Result<&TrianglePacket, &[TrianglePacket; 2]> {
        let (first, two) = packet_span(leaf);
        debug_assert!(first + 1 + usize::from(two) <= self.tri_packets.len());
        // SAFETY: the traversals pass only leaf references read from the nodes, and a
        // reference with `PACKETS` set is made only by `Leaves::push`, after `pack` appended
        // the leaf's packets (one, or two with `TWO_PACKETS`) from `first` on; the packets
        // are not changed after the build.
        unsafe {
            let p = self.tri_packets.as_ptr().add(first);
            if two {
                Err(&*p.cast::<[TrianglePacket; 2]>())
            } else {
                Ok(&*p)
            }
        }
    }

    /// The unnormalised geometric normal of triangle `g` (its number over all meshes) from
    /// the packets of leaf reference `leaf` (a [`Closest::leaf`]), if that leaf is referenced
    /// by its packets and holds the triangle: the bits of [`TriangleMesh::geometric_normal`]
    /// (see [`TrianglePacket::geometric_normal_at`]), read from packets the traversal has just
    /// tested rather than from the mesh's buffers.
    ///
    /// [`TriangleMesh::geometric_normal`]: crate::shapes::mesh::TriangleMesh::geometric_normal
    #[inline(always)]
    pub(super) fn packet_normal(&self, leaf: u32, g: u32) -> Option<Vec3A> {
        if leaf & PACKETS == 0 {
            return None;
        }
        let (first, two) = packet_span(leaf);
        // (Checked reads: once a query, and `leaf` may be any value.)
        let packets = self.tri_packets.get(first..=first + usize::from(two))?;
        // The lanes holding `g` over the leaf's one or two packets (bits 4..8: the second),
        // and the packet of the first of them, picked by index rather than a branch (a hit's
        // packet and lane are as good as random).
        let (a, b) = (&packets[0], &packets[packets.len() - 1]);
        let mask = a.lanes_of(g) | ((b.lanes_of(g) << 4) & if two { 0xf0 } else { 0 });
        if mask == 0 {
            return None;
        }
        let lane = mask.trailing_zeros() as usize;
        Some(packets.get(lane >> 2)?.geometric_normal_at(lane))
    }

    /// Tests the leaf referenced by `leaf` for a hit closer than `t_max`, recording it in `c` and `t_max`
    /// (and with `KEEP_LEAF`, a triangle's leaf in [`Closest::leaf`]).
    /// `leaf` is a reference read from this BVH's nodes (see [`Leaves::direct_packets`]).
    /// `lanes` is `ray` as `test` set it up for the triangle packets, once per query.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn closest<P: PairTest, const KEEP_LEAF: bool>(
        &self,
        test: P,
        lanes: &P::Lanes,
        leaf: u32,
        ray: &Ray,
        t_min: f32,
        t_max: &mut f32,
        c: &mut Closest,
    ) {
        if leaf & PACKETS != 0 {
            let hit = match self.direct_packets(leaf) {
                Ok(packet) => test.packet_hit_t(lanes, packet, ray, t_min, *t_max),
                Err(pair) => test.pair_hit_t(lanes, pair, ray, t_min, *t_max),
            };
            if let Some((g, t, b)) = hit {
                *t_max = t;
                c.triangle = g;
                c.bary = b;
                c.shape = usize::MAX;
                if KEEP_LEAF {
                    c.leaf = leaf;
                }
            }
            return;
        }
        let leaf = &self.leaves[leaf as usize];
        if leaf.tris != 0 || leaf.quads != 0 {
            self.closest_packets_in_record(leaf, ray, t_min, t_max, c);
        }
        let rest = leaf.shapes as usize + leaf.quads as usize;
        let end = leaf.shapes as usize + leaf.count as usize;
        for (k, s) in self.shapes[rest..end].iter().enumerate() {
            match s.analytic_t(ray, t_min, *t_max) {
                Ok(Some(t)) => {
                    *t_max = t;
                    c.shape = rest + k;
                    c.triangle = u32::MAX;
                    c.boxed = None;
                }
                Ok(None) => {}
                Err(()) => {
                    if let Some(h) = s.boxed_hit(ray, t_min, *t_max) {
                        *t_max = h.t();
                        c.shape = rest + k;
                        c.triangle = u32::MAX;
                        c.boxed = Some(h);
                    }
                }
            }
        }
    }

    /// The packets of a leaf with a [`Leaf`] record (its triangle packets, then its quad
    /// packets) for [`Leaves::closest`], out of line: inlined, their set-up (the quad
    /// packets' broadcasts of the ray among it) was hoisted into every query of the
    /// traversal, for leaves that a tree of mesh triangles alone never has. (The leaf's other
    /// shapes stay inline: out of line, a call per leaf cost a tree of spheres 3 % more
    /// instructions, see docs/measurements.md.)
    #[inline(never)]
    fn closest_packets_in_record(
        &self,
        leaf: &Leaf,
        ray: &Ray,
        t_min: f32,
        t_max: &mut f32,
        c: &mut Closest,
    ) {
        for packet in self.triangle_packets(leaf) {
            if let Some((g, t, b)) = packet.hit_t(ray, t_min, *t_max) {
                *t_max = t;
                c.triangle = g;
                c.bary = b;
                c.shape = usize::MAX;
            }
        }
        let start = leaf.shapes as usize;
        for (p, packet) in self.quad_packets(leaf).iter().enumerate() {
            if let Some((lane, t)) = packet.hit_t(ray, t_min, *t_max) {
                *t_max = t;
                c.shape = start + 4 * p + lane;
                c.triangle = u32::MAX;
                c.boxed = None;
            }
        }
    }

    /// Whether anything in the leaf referenced by `leaf` is hit with `t_min < t < t_max`.
    /// `leaf` is a reference read from this BVH's nodes (see [`Leaves::direct_packets`]);
    /// `lanes` is `ray` as `test` set it up for the triangle packets, once per query.
    #[inline(always)]
    pub(super) fn occluded<P: PairTest>(
        &self,
        test: P,
        lanes: &P::Lanes,
        leaf: u32,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        if leaf & PACKETS != 0 {
            return match self.direct_packets(leaf) {
                Ok(packet) => test.packet_occluded(lanes, packet, ray, t_min, t_max),
                Err(pair) => test.pair_occluded(lanes, pair, ray, t_min, t_max),
            };
        }
        use crate::shapes::Shape;
        let leaf = &self.leaves[leaf as usize];
        if (leaf.tris != 0 || leaf.quads != 0)
            && self.occluded_packets_in_record(leaf, ray, t_min, t_max)
        {
            return true;
        }
        let start = leaf.shapes as usize + leaf.quads as usize;
        let end = leaf.shapes as usize + leaf.count as usize;
        self.shapes[start..end]
            .iter()
            .any(|s| s.occluded(ray, t_min, t_max))
    }

    /// The packets of a leaf with a [`Leaf`] record for [`Leaves::occluded`], out of line as
    /// [`Leaves::closest_packets_in_record`].
    #[inline(never)]
    fn occluded_packets_in_record(&self, leaf: &Leaf, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.triangle_packets(leaf)
            .iter()
            .any(|p| p.occluded(ray, t_min, t_max))
            || self
                .quad_packets(leaf)
                .iter()
                .any(|p| p.occluded(ray, t_min, t_max))
    }

    pub(super) fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.leaves.capacity() * size_of::<Leaf>()
            + self.shapes.capacity() * size_of::<AnyShape>()
            + self.ids.capacity() * size_of::<u32>()
            + self.packets.capacity() * size_of::<QuadPacket>()
            + self.tri_packets.capacity() * size_of::<TrianglePacket>()
    }
}
