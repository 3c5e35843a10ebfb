//! The collapse's plan: which interior nodes of the binary tree become 8-wide nodes, chosen
//! so that the wide nodes' summed surface area is the least any collapse of that tree can
//! have.
//!
//! A wide node is made from an interior binary node by opening some of the interior nodes
//! below it, so that their children take their place, until it has at most eight children;
//! the binary leaves stay as they are. Whatever is opened, each binary leaf ends in exactly
//! one slot, so the leaves' tests do not depend on the collapse; what does is the wide nodes
//! a ray visits, and under the SAH's assumption (a ray enters a box with a probability in
//! proportion to its surface area) their expected number is the wide nodes' summed area over
//! the root's. The greedy collapse (open the child of largest area until eight) used 4.4 of a
//! node's eight slots on average on a mesh of 10^6 triangles, the plan 6.0 (with a third fewer
//! nodes; docs/measurements.md). The plan is the minimum by dynamic programming over the
//! binary tree (as in Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal on GPUs
//! Through Compressed Wide BVHs", HPG 2017, with the leaves fixed): for each interior node `n`
//! and `j` slots, `cost(n, j)` is the least summed area of the wide nodes in `n`'s subtree
//! when that subtree takes at most `j` slots of its parent:
//!
//! - `cost(n, 1) = area(n) + split(n, 8)` (`n` a wide node of its own);
//! - `cost(n, j) = min(cost(n, j - 1), split(n, j))` for `j` from 2 (`n` opened);
//! - `split(n, j)`: the least `cost(first, k) + cost(second, j - k)`, `k` from 1 to `j - 1`;
//!
//! a leaf costs 0 in any number of slots. Ties keep the fewer slots and the smaller `k`. A NaN
//! area (a flat box spanning more than `f32`'s range on another axis) counts as infinite; an
//! infinite cost never wins a comparison against a finite one, and every choice stays in its
//! range whatever the costs, so such boxes leave a valid plan. Each node's choices depend only on
//! its subtree, so the plan is the same on any number of threads.

use super::{BinaryNode, WIDTH};

/// An interior node's choices: at `[0]`, the slots of a wide node made from it that its first
/// child's subtree takes (the second's take the rest); at `[j - 1]`, for `j` from 2 to
/// [`WIDTH`], how its subtree is opened into `j` slots of its parent: 0 when it is best in
/// `j - 1` slots, else the slots its first child's subtree takes. (A leaf's entry is unused.)
pub(super) type Choice = [u8; WIDTH];

/// Each binary node's [`Choice`], by node index. Subtrees of `parallel_from` nodes or more
/// have their two halves planned with `rayon::join`.
pub(super) fn plan(nodes: &[BinaryNode], parallel_from: usize) -> Vec<Choice> {
    let mut plan = vec![[0; WIDTH]; nodes.len()];
    if !nodes.is_empty() {
        subtree(nodes, &mut plan, 0, 0, nodes.len(), parallel_from);
    }
    plan
}

/// The costs of node `n`'s subtree in 1 to [`WIDTH`] slots; fills the choices of the nodes
/// `n..end` (its subtree), held in `plan` from index `base` on.
fn subtree(
    nodes: &[BinaryNode],
    plan: &mut [Choice],
    base: usize,
    n: usize,
    end: usize,
    parallel_from: usize,
) -> [f32; WIDTH] {
    if nodes[n].count > 0 {
        return [0.0; WIDTH];
    }
    // Flattened depth-first: the first child follows its parent, and its subtree ends where
    // the second child's begins.
    let (first, second) = (n + 1, nodes[n].offset as usize);
    let (a, b) = if end - n >= parallel_from {
        let (left, right) = plan[first - base..].split_at_mut(second - first);
        rayon::join(
            || subtree(nodes, left, first, first, second, parallel_from),
            || subtree(nodes, right, second, second, end, parallel_from),
        )
    } else {
        (
            subtree(nodes, plan, base, first, second, parallel_from),
            subtree(nodes, plan, base, second, end, parallel_from),
        )
    };
    let area = nodes[n].bounds.surface_area();
    let area = if area.is_nan() { f32::INFINITY } else { area };
    let (cost, choice) = combine(area, &a, &b);
    plan[n - base] = choice;
    cost
}

/// A node's costs and choices from its area and its children's costs.
fn combine(area: f32, a: &[f32; WIDTH], b: &[f32; WIDTH]) -> ([f32; WIDTH], Choice) {
    // split[j]: the least cost of the two children's subtrees in j slots, and the first's share.
    let mut split = [(f32::INFINITY, 1u8); WIDTH + 1];
    for (j, s) in split.iter_mut().enumerate().skip(2) {
        *s = (a[0] + b[j - 2], 1);
        for k in 2..j {
            let c = a[k - 1] + b[j - k - 1];
            if c < s.0 {
                *s = (c, k as u8);
            }
        }
    }
    let mut cost = [0.0; WIDTH];
    let mut choice = [0; WIDTH];
    cost[0] = area + split[WIDTH].0;
    choice[0] = split[WIDTH].1;
    for j in 2..=WIDTH {
        if split[j].0 < cost[j - 2] {
            cost[j - 1] = split[j].0;
            choice[j - 1] = split[j].1;
        } else {
            cost[j - 1] = cost[j - 2];
        }
    }
    (cost, choice)
}

/// Appends to `kids` the slots of node `c`'s subtree given `slots` of them (at least one): `c`
/// itself, or what it is opened into.
pub(super) fn open(
    nodes: &[BinaryNode],
    plan: &[Choice],
    c: usize,
    slots: usize,
    kids: &mut arrayvec::ArrayVec<usize, WIDTH>,
) {
    let mut j = slots;
    if nodes[c].count == 0 {
        while j > 1 && plan[c][j - 1] == 0 {
            j -= 1;
        }
    }
    if nodes[c].count > 0 || j <= 1 {
        kids.push(c);
        return;
    }
    // (A choice is from 1 to j - 1 by construction; clamped so that a wrong one could not
    // give more than `slots` kids.)
    let k = usize::from(plan[c][j - 1]).clamp(1, j - 1);
    open(nodes, plan, c + 1, k, kids);
    open(nodes, plan, nodes[c].offset as usize, j - k, kids);
}
