//! Why a BVH build gave no BVH.

/// Why a build gave no BVH.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unbuilt {
    /// The build's `stop` said yes.
    Stopped,
    /// The tree has more nodes than its child references can name (see
    /// [`super::wide::fits`]: over a billion triangles).
    TooLarge,
}

impl std::fmt::Display for Unbuilt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Unbuilt::Stopped => "the build was stopped",
            Unbuilt::TooLarge => {
                "too many primitives for one BVH: its nodes would pass the 16 GiB its child \
                 references can address"
            }
        })
    }
}
