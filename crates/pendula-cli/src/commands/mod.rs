//! The study commands, one file each.
//!
//! # How they are built
//!
//! The study commands live one per file in `crates/pendula-cli/src/commands/`.
//! `crates/pendula-cli/src/commands/report.rs` runs them through the same dispatcher as the command
//! line (`dispatch` in `crates/pendula-cli/src/main.rs`), each with its outputs in the report's
//! folder, and builds its sentences and tables from their JSON summaries, so the text cannot
//! disagree with the numbers; its `GALLERY` list is the README gallery's manifest (`report
//! --gallery DIR` regenerates it, a test compares it with the README's captions). `compare` gives
//! every method the same cost (evaluations per simulated second; implicit methods' steps calibrated
//! by pilot runs), runs the methods in parallel, and extrapolates a crossover beyond the run from
//! RK4's fitted drift.

pub mod animate;
pub mod compare;
pub mod fractal;
pub mod merge;
pub mod plot;
pub mod report;
pub mod resume;
pub mod serve;
pub mod sweep;
