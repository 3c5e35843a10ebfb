//! The Bezier intersectors measured: stress tests against the slow reference intersectors,
//! properties, holes seen through the examples' cameras, and the speed-against-error study end
//! to end. One test binary; run one file's tests with `cargo test -p sppm-measure --test bezier
//! stress::`.

mod bench;
mod holes;
mod props;
mod stress;
