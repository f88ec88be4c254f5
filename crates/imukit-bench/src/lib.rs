//! Criterion benchmarks of imukit's kernels, in `benches/` (`cargo bench -p imukit-bench`). A crate
//! of their own: as imukit's dev-dependency, criterion (regex, serde, clap, …) was compiled by every
//! `cargo test`.
