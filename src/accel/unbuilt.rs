//! Why a BVH build gave no BVH.

/// Why a build gave no BVH.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unbuilt {
    /// The build's `stop` said yes.
    Stopped,
    /// More primitives than one BVH numbers (more than [`MAX_PRIMITIVES`]), or more nodes
    /// than its child references can name.
    TooLarge,
}

/// The most primitives (shapes and mesh triangles) one BVH takes, 2^29: the build numbers its
/// primitives, binary nodes and triangle packets in `u32`s (a leaf's packet reference in 29
/// bits), which all hold their counts below this. A tree this large would take about 40 GB.
pub const MAX_PRIMITIVES: usize = 1 << 29;

/// Whether `shapes` shapes and meshes of the given triangle counts are more primitives than
/// one BVH takes ([`MAX_PRIMITIVES`]).
pub(super) fn too_many(shapes: usize, triangles: impl IntoIterator<Item = usize>) -> bool {
    triangles.into_iter().fold(shapes, usize::saturating_add) > MAX_PRIMITIVES
}

impl std::fmt::Display for Unbuilt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Unbuilt::Stopped => "the build was stopped",
            Unbuilt::TooLarge => {
                "too many primitives for one BVH: at most 2^29 (536 870 912) shapes and \
                 triangles, in nodes its child references can address (16 GiB)"
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{MAX_PRIMITIVES, too_many};

    /// The count is shapes plus every mesh's triangles, without overflow, against the limit.
    #[test]
    fn the_primitive_limit_counts_shapes_and_triangles() {
        assert!(!too_many(0, []));
        assert!(!too_many(MAX_PRIMITIVES, []));
        assert!(!too_many(1, [MAX_PRIMITIVES - 3, 2]));
        assert!(too_many(1, [MAX_PRIMITIVES - 3, 3]));
        assert!(too_many(0, [usize::MAX, usize::MAX]));
        assert!(too_many(usize::MAX, [1]));
    }
}
