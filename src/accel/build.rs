//! Building the BVH: binned SAH splits over the primitives' boxes, recursively, into nodes
//! flattened depth-first (an interior node's first child follows it).
//!
//! Large nodes use every core: the two halves of a split are built with `rayon::join`, each
//! into its own run of nodes, and the runs are joined in depth-first order afterwards; the
//! bounds, bins and items' bin numbers of a very large node are gathered in parallel chunks
//! (the partition itself stays serial and in place: a parallel one that keeps this order
//! copies the items twice and was measured slower). A split depends only
//! on the items (box unions and bin counts do not depend on the order they are merged in), so
//! the tree is the same, node for node, on any number of threads.

use glam::Vec3A;
use rayon::prelude::*;

use crate::geometry::Aabb;

const BINS: usize = 12;
const MAX_LEAF: usize = 4;

/// Sizes (in items) from which the build works in parallel.
#[derive(Debug, Clone, Copy)]
pub(super) struct Parallelism {
    /// A node of at least this many items builds its two halves with `rayon::join`.
    pub join: usize,
    /// A node of at least this many items gathers its bounds and bins in parallel chunks.
    pub binning: usize,
}

impl Parallelism {
    /// A task per subtree of 4096 items or more (about 0.5 ms of work), and parallel bins for
    /// nodes of 64K items or more (the top few levels, which would otherwise run on one core).
    pub const DEFAULT: Self = Self {
        join: 4096,
        binning: 1 << 16,
    };
}

/// Items per chunk of a parallel pass over a node's items.
const CHUNK: usize = 1 << 13;

/// A primitive as the build sees it; the build reorders the items into leaf order.
pub(super) struct Item {
    pub bounds: Aabb,
    pub centroid: Vec3A,
    pub index: usize,
    /// A mesh triangle: leaves test these four at a time (see `split`'s cost).
    pub triangle: bool,
    /// A shape whose intersection costs far more than a box test (a boxed or CSG shape: a
    /// revolve's segment, a patch, a transformed object): a leaf holds at most one (`split`).
    pub heavy: bool,
}

impl Item {
    pub fn new(bounds: Aabb, index: usize) -> Self {
        Self {
            bounds,
            centroid: bounds.centroid(),
            index,
            triangle: false,
            heavy: false,
        }
    }

    /// A mesh triangle's item.
    pub fn triangle(bounds: Aabb, index: usize) -> Self {
        Self {
            triangle: true,
            ..Self::new(bounds, index)
        }
    }
}

/// A node of the built tree.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct BuildNode {
    pub bounds: Aabb,
    /// Leaf: index of its first item. Interior: index of its second child.
    pub offset: u32,
    /// Items in a leaf (at most 8); 0 for an interior node.
    pub count: u32,
    /// Interior: the axis the split ordered the children on.
    pub axis: u8,
}

/// What the build asks, at a coarse grain, to learn whether to stop.
pub(super) type Stop<'s> = &'s (dyn Fn() -> bool + Sync);

/// Builds the tree over `items` (reordered into leaf order). From depth `median_depth` on,
/// nodes split at the object median instead of by SAH.
#[cfg(test)]
pub(super) fn build(items: &mut [Item], median_depth: usize, par: Parallelism) -> Vec<BuildNode> {
    build_until(items, median_depth, par, &|| false).unwrap_or_default()
}

/// [`build`], asking `stop` before each node of [`Parallelism::join`] items or more (a subtree
/// smaller than that takes about half a millisecond): `None` once it said yes.
pub(super) fn build_until(
    items: &mut [Item],
    median_depth: usize,
    par: Parallelism,
    stop: Stop,
) -> Option<Vec<BuildNode>> {
    if items.is_empty() {
        return Some(Vec::new());
    }
    let run = build_run(items, 0, 0, median_depth, par, stop)?;
    let mut nodes = vec![
        BuildNode {
            bounds: Aabb::EMPTY,
            offset: 0,
            count: 0,
            axis: 0,
        };
        run.len()
    ];
    run.write(&mut nodes, 0);
    Some(nodes)
}

/// The nodes of a subtree, in depth-first order, before they are placed in the final array.
enum Run {
    /// Built on one thread; interior offsets count from the subtree's root.
    Nodes(Vec<BuildNode>),
    /// Split with the halves built in parallel.
    Split {
        node: BuildNode,
        first: Box<Run>,
        second: Box<Run>,
        len: usize,
    },
}

impl Run {
    fn len(&self) -> usize {
        match self {
            Run::Nodes(nodes) => nodes.len(),
            Run::Split { len, .. } => *len,
        }
    }

    /// Writes the subtree into `out`, whose first node has index `base` in the final array.
    fn write(self, out: &mut [BuildNode], base: usize) {
        match self {
            Run::Nodes(nodes) => {
                for (slot, mut node) in out.iter_mut().zip(nodes) {
                    if node.count == 0 {
                        node.offset += base as u32;
                    }
                    *slot = node;
                }
            }
            Run::Split {
                mut node,
                first,
                second,
                ..
            } => {
                let n_first = first.len();
                node.offset = (base + 1 + n_first) as u32;
                out[0] = node;
                let (a, b) = out[1..].split_at_mut(n_first);
                rayon::join(
                    || first.write(a, base + 1),
                    || second.write(b, base + 1 + n_first),
                );
            }
        }
    }
}

/// The subtree over `items` (which start at index `start` of all items); `None` when `stop`
/// said so.
fn build_run(
    items: &mut [Item],
    start: usize,
    depth: usize,
    median_depth: usize,
    par: Parallelism,
    stop: Stop,
) -> Option<Run> {
    if items.len() < par.join {
        let mut nodes = Vec::with_capacity(items.len() / 2 + 1);
        build_serial(items, start, depth, median_depth, par, &mut nodes);
        return Some(Run::Nodes(nodes));
    }
    if stop() {
        return None;
    }
    let (node, mid) = split(items, start, depth, median_depth, par);
    let Some(mid) = mid else {
        return Some(Run::Nodes(vec![node]));
    };
    let (a, b) = items.split_at_mut(mid);
    let (first, second) = rayon::join(
        || build_run(a, start, depth + 1, median_depth, par, stop),
        || build_run(b, start + mid, depth + 1, median_depth, par, stop),
    );
    let (first, second) = (first?, second?);
    let len = 1 + first.len() + second.len();
    Some(Run::Split {
        node,
        first: Box::new(first),
        second: Box::new(second),
        len,
    })
}

/// The subtree over `items` on this thread, appended to `nodes`; returns its root's index.
fn build_serial(
    items: &mut [Item],
    start: usize,
    depth: usize,
    median_depth: usize,
    par: Parallelism,
    nodes: &mut Vec<BuildNode>,
) -> usize {
    let idx = nodes.len();
    let (node, mid) = split(items, start, depth, median_depth, par);
    nodes.push(node);
    if let Some(mid) = mid {
        let (a, b) = items.split_at_mut(mid);
        build_serial(a, start, depth + 1, median_depth, par, nodes);
        let second = build_serial(b, start + mid, depth + 1, median_depth, par, nodes);
        nodes[idx].offset = second as u32;
    }
    idx
}

/// The bounds of the items and of their centroids, whether all are mesh triangles and whether
/// two or more are heavy (in the same pass over the items, so in parallel chunks for a large
/// node).
fn bounds_of(items: &[Item], par: Parallelism) -> (Aabb, Aabb, bool, bool) {
    type Acc = (Aabb, Aabb, bool, u8);
    let fold = |(b, c, t, h): Acc, it: &Item| {
        (
            b.union(it.bounds),
            c.with_point(it.centroid),
            t & it.triangle,
            (h + it.heavy as u8).min(2),
        )
    };
    let empty = (Aabb::EMPTY, Aabb::EMPTY, true, 0);
    let (b, c, t, h) = if items.len() < par.binning {
        items.iter().fold(empty, fold)
    } else {
        items
            .par_chunks(CHUNK)
            .map(|chunk| chunk.iter().fold(empty, fold))
            .reduce(
                || empty,
                |x, y| {
                    (
                        x.0.union(y.0),
                        x.1.union(y.1),
                        x.2 & y.2,
                        (x.3 + y.3).min(2),
                    )
                },
            )
    };
    (b, c, t, h >= 2)
}

/// Each item's bin (the items of a large node, in parallel chunks), for the partition.
fn bin_indices(items: &[Item], bin_of: impl Fn(&Item) -> usize + Sync) -> Vec<u8> {
    let mut bins = vec![0u8; items.len()];
    bins.par_chunks_mut(CHUNK)
        .zip(items.par_chunks(CHUNK))
        .for_each(|(out, chunk)| {
            for (b, it) in out.iter_mut().zip(chunk) {
                *b = bin_of(it) as u8;
            }
        });
    bins
}

type Bins = ([Aabb; BINS], [usize; BINS]);

/// The items' boxes and counts per bin.
fn bins_of(items: &[Item], bin_of: impl Fn(&Item) -> usize + Sync, par: Parallelism) -> Bins {
    // Filled in place: a fold that passed the bins by value copied them (480 bytes) at every
    // item, about 4 % of `check`'s time for a scene of 100 000 objects.
    let fill = |chunk: &[Item]| {
        let mut bins: Bins = ([Aabb::EMPTY; BINS], [0; BINS]);
        for it in chunk {
            let b = bin_of(it);
            bins.0[b] = bins.0[b].union(it.bounds);
            bins.1[b] += 1;
        }
        bins
    };
    let empty = ([Aabb::EMPTY; BINS], [0; BINS]);
    if items.len() < par.binning {
        return fill(items);
    }
    items.par_chunks(CHUNK).map(fill).reduce(
        || empty,
        |mut x, y| {
            for i in 0..BINS {
                x.0[i] = x.0[i].union(y.0[i]);
                x.1[i] += y.1[i];
            }
            x
        },
    )
}

/// The node over `items`, and where they are split into its children (`None`: a leaf). The
/// items are reordered so that the first child's come first.
fn split(
    items: &mut [Item],
    start: usize,
    depth: usize,
    median_depth: usize,
    par: Parallelism,
) -> (BuildNode, Option<usize>) {
    let n = items.len();
    let (bounds, cb, packets, heavy) = bounds_of(items, par);
    let mut node = BuildNode {
        bounds,
        offset: start as u32,
        count: n as u32,
        axis: 0,
    };
    // A leaf holds at most one heavy item (above the median split's depth): a leaf tests each
    // of its shapes, where separate leaves let the wide nodes' box tests (eight at once) cull
    // the heavy ones a ray passes by, and let the traversal skip those whose box it enters
    // only beyond the nearest hit found (which helps even where their boxes nearly coincide,
    // as a vase's outer and inner walls).
    let heavy = heavy && depth < median_depth;
    if n <= MAX_LEAF && !heavy {
        return (node, None);
    }
    let ext = cb.diagonal();
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    // A node of mesh triangles only counts its cost in packets of four (the leaf tests them
    // four at a time), so that splits prefer multiples of four and packets fill, and it counts
    // the visit of the extra node a split makes as one packet test, so that a leaf of two
    // packets is kept when splitting saves less than that. Any other node counts items, which
    // leaves trees without meshes as they were.
    let cost = |k: usize| if packets { k.div_ceil(4) } else { k } as f32;
    let visit = if packets { 1.0 } else { 0.0 };
    let lo = cb.min[axis];
    let span = ext[axis];
    let mid = if depth >= median_depth {
        items.select_nth_unstable_by(n / 2, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
        n / 2
    } else if span <= 0.0 || !span.is_finite() {
        n / 2
    } else {
        // Binned SAH.
        let bin_of =
            |it: &Item| (((it.centroid[axis] - lo) / span * BINS as f32) as usize).min(BINS - 1);
        let (bin_b, bin_n) = bins_of(items, bin_of, par);
        let mut best = (f32::INFINITY, 0usize);
        for split in 1..BINS {
            let (lb, ln) = (0..split).fold((Aabb::EMPTY, 0), |(b, c), i| {
                (b.union(bin_b[i]), c + bin_n[i])
            });
            let (rb, rn) = (split..BINS).fold((Aabb::EMPTY, 0), |(b, c), i| {
                (b.union(bin_b[i]), c + bin_n[i])
            });
            if ln == 0 || rn == 0 {
                continue;
            }
            let cost = lb.surface_area() * cost(ln) + rb.surface_area() * cost(rn);
            if cost < best.0 {
                best = (cost, split);
            }
        }
        let leaf_cost = bounds.surface_area() * (cost(n) - visit);
        if best.0 >= leaf_cost * 0.9 && n <= 8 && !heavy || best.0.is_infinite() {
            if best.0.is_infinite() {
                // All centroids in one bin: split in the middle of the ordering.
                items.sort_by(|a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
                n / 2
            } else {
                return (node, None);
            }
        } else {
            let split = best.1;
            // (Lomuto: an item not yet visited is still at its place, so its bin can be
            // computed beforehand, in parallel for a large node.)
            let mut i = 0;
            if n < par.binning {
                for j in 0..n {
                    if bin_of(&items[j]) < split {
                        items.swap(i, j);
                        i += 1;
                    }
                }
            } else {
                let bins = bin_indices(items, bin_of);
                for (j, &b) in bins.iter().enumerate() {
                    if (b as usize) < split {
                        items.swap(i, j);
                        i += 1;
                    }
                }
            }
            i
        }
    };
    node.count = 0;
    node.axis = axis as u8;
    (node, Some(mid.clamp(1, n - 1)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// Boxes of mixed sizes in clusters, with runs of identical boxes (whose centroids all
    /// fall in one bin, or coincide): every kind of split the build makes.
    fn items(rng: &mut Rng, n: usize) -> Vec<Item> {
        let centres: Vec<Vec3A> = (0..20)
            .map(|_| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * 100.0)
            .collect();
        let mut out = Vec::with_capacity(n);
        while out.len() < n {
            let cluster = out.len() % centres.len();
            let c = centres[cluster];
            let p = c + Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * (0.01 + 10.0 * rng.f32());
            let b = Aabb::new(p, p + Vec3A::splat(0.001 + rng.f32()));
            let copies = if rng.f32() < 0.05 { 40 } else { 1 };
            for _ in 0..copies.min(n - out.len()) {
                // Every other cluster is mesh triangles (costed in packets of four).
                out.push(Item {
                    triangle: cluster.is_multiple_of(2),
                    ..Item::new(b, out.len())
                });
            }
        }
        out
    }

    fn copied(items: &[Item]) -> Vec<Item> {
        let copy = |it: &Item| Item {
            triangle: it.triangle,
            heavy: it.heavy,
            ..Item::new(it.bounds, it.index)
        };
        items.iter().map(copy).collect()
    }

    /// The nodes and the leaf order of the items, built on `threads` threads.
    fn built(
        threads: usize,
        items: &[Item],
        median_depth: usize,
        par: Parallelism,
    ) -> (Vec<BuildNode>, Vec<usize>) {
        let mut items = copied(items);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let nodes = pool.install(|| build(&mut items, median_depth, par));
        (nodes, items.iter().map(|it| it.index).collect())
    }

    /// The tree is the one the plain recursion builds, node for node and with the items in the
    /// same order, on 1, 2 and 4 threads; with thresholds low enough that thousands of
    /// subtrees are built as separate tasks and the top nodes bin in parallel chunks, under
    /// SAH splits and under median splits.
    #[test]
    fn the_tree_is_the_same_on_any_number_of_threads() {
        let mut rng = Rng::new(11);
        let all = items(&mut rng, 60_000);
        let par = Parallelism {
            join: 16,
            binning: 2 * CHUNK + 5,
        };
        for median_depth in [usize::MAX, 32, 4] {
            let mut plain = copied(&all);
            let mut nodes = Vec::new();
            let serial = Parallelism {
                join: usize::MAX,
                binning: usize::MAX,
            };
            build_serial(&mut plain, 0, 0, median_depth, serial, &mut nodes);
            let order: Vec<usize> = plain.iter().map(|it| it.index).collect();
            assert!(nodes.len() > 10_000, "{} nodes", nodes.len());
            for threads in [1, 2, 4] {
                let (got, got_order) = built(threads, &all, median_depth, par);
                assert!(
                    got == nodes,
                    "{threads} threads, median from {median_depth}"
                );
                assert!(
                    got_order == order,
                    "{threads} threads, median from {median_depth}"
                );
            }
            // Leaves cover the items once each, in order.
            let mut next = 0;
            for n in nodes.iter().filter(|n| n.count > 0) {
                assert_eq!(n.offset as usize, next);
                next += n.count as usize;
            }
            assert_eq!(next, all.len());
        }
    }

    /// The binned SAH copes with every extent a node's centroids can have: none on
    /// two axes (a row of boxes), a subnormal one, one that overflows to infinity
    /// (coordinates near `f32::MAX`) and none at all (identical boxes). Each tree's leaves
    /// cover the items once, hold at most 8 items, and each node's box holds its items.
    #[test]
    fn binning_copes_with_degenerate_and_extreme_extents() {
        let boxes = |f: &dyn Fn(usize) -> Vec3A| -> Vec<Item> {
            (0..300)
                .map(|i| {
                    let p = f(i);
                    Item::triangle(Aabb::new(p, p), i)
                })
                .collect()
        };
        let cases: [(&str, Vec<Item>); 4] = [
            ("a row", boxes(&|i| Vec3A::new(i as f32, 0.0, 0.0))),
            (
                "subnormal",
                boxes(&|i| Vec3A::new(1e-42 * (i % 7) as f32, 0.0, 1e-40)),
            ),
            (
                "overflowing",
                boxes(&|i| {
                    let s = if i % 2 == 0 { 1.0 } else { -1.0 };
                    Vec3A::new(s * 3e38, (i % 5) as f32, -s * 3e38 * (i % 3) as f32)
                }),
            ),
            ("identical", boxes(&|_| Vec3A::splat(2.5))),
        ];
        for (what, mut items) in cases {
            let nodes = build(&mut items, usize::MAX, Parallelism::DEFAULT);
            let mut seen = vec![false; items.len()];
            let mut next = 0;
            for (k, n) in nodes.iter().enumerate() {
                if n.count > 0 {
                    assert_eq!(n.offset as usize, next, "{what}: leaf {k}");
                    assert!(n.count <= 8, "{what}: leaf {k} holds {}", n.count);
                    for it in &items[next..next + n.count as usize] {
                        assert!(!seen[it.index], "{what}: item {} twice", it.index);
                        seen[it.index] = true;
                        assert_eq!(n.bounds.union(it.bounds), n.bounds, "{what}");
                    }
                    next += n.count as usize;
                }
            }
            assert!(seen.iter().all(|&s| s), "{what}: an item is in no leaf");
        }
    }

    /// Leaf sizes of a tree built over `items`.
    fn leaf_sizes(mut items: Vec<Item>) -> Vec<u32> {
        let nodes = build(&mut items, usize::MAX, Parallelism::DEFAULT);
        nodes
            .iter()
            .filter(|n| n.count > 0)
            .map(|n| n.count)
            .collect()
    }

    /// Four boxes in a row, or four copies of one box, each item heavy or not.
    fn four(apart: bool, heavy: bool) -> Vec<Item> {
        (0..4)
            .map(|i| {
                let x = if apart { 3.0 * i as f32 } else { 0.0 };
                let b = Aabb::new(Vec3A::new(x, 0.0, 0.0), Vec3A::new(x + 1.0, 1.0, 1.0));
                Item {
                    heavy,
                    ..Item::new(b, i)
                }
            })
            .collect()
    }

    /// Heavy items get leaves of their own, apart or on one box (where the traversal may still
    /// skip the farther one); a small node of cheap items stays one leaf.
    #[test]
    fn heavy_items_get_leaves_of_their_own() {
        assert_eq!(leaf_sizes(four(true, true)), [1, 1, 1, 1]);
        assert_eq!(leaf_sizes(four(false, true)), [1, 1, 1, 1]);
        assert_eq!(leaf_sizes(four(true, false)), [4]);
        // One heavy item among cheap ones: one leaf.
        let mut mixed = four(true, false);
        mixed[2].heavy = true;
        assert_eq!(leaf_sizes(mixed), [4]);
    }

    /// A build asks whether to stop about once per subtree of [`Parallelism::join`] items
    /// (so a cancel is seen within about half a millisecond of work per thread), builds the
    /// same tree when nothing stops it, and stops at once (asking few more times) when told.
    #[test]
    fn a_build_asks_at_a_coarse_grain_and_stops_when_told() {
        use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
        let n = 200_000;
        let all = items(&mut Rng::new(5), n);
        let par = Parallelism::DEFAULT;
        let asked = AtomicUsize::new(0);
        let mut a = copied(&all);
        let never = || {
            asked.fetch_add(1, Relaxed);
            false
        };
        let nodes = build_until(&mut a, usize::MAX, par, &never).expect("not stopped");
        assert_eq!(
            (nodes, a.iter().map(|it| it.index).collect()),
            built(1, &all, usize::MAX, par)
        );
        let full = asked.load(Relaxed);
        println!("a build of {n} items asked {full} times");
        assert!(full >= n / par.join && full <= 4 * n / par.join, "{full}");
        let asked = AtomicUsize::new(0);
        let mut b = copied(&all);
        let soon = || asked.fetch_add(1, Relaxed) >= 3;
        assert!(build_until(&mut b, usize::MAX, par, &soon).is_none());
        // Each task in flight asks once more, then gives up.
        let stopped = asked.load(Relaxed);
        assert!(stopped < full / 4, "{stopped} of {full}");
    }
}
