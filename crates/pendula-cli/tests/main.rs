//! The CLI's tests: one test binary (one link, one run), a module per subject, the helpers
//! they share in `util`. Most run the real `pendula` binary (`CARGO_BIN_EXE_pendula`) in a
//! temporary directory.
//!
//! - `cli`: `simulate`, `list`, `plot`, `serve`, completions and man pages, and every
//!   invalid input with its message, exit code, and no file left behind;
//! - `study`, `chaos`, `sweep`: the study commands, the chaos commands, sweeps and shards;
//! - `defaults`: the study commands on their defaults, for every catalogued system;
//! - `docs`: the examples of README.md and docs/GUIDE.md, run as printed;
//! - `outputs`, `resume`, `full_disk`: interrupts, checkpoints and full disks, on real
//!   processes and devices;
//! - `battery`: the hardening battery, hostile requests to every command;
//! - `fuzz`: the fuzz harness, generated and hostile input to every reader of user input, in
//!   process, through the library target (`pendula_cli`).

mod battery;
mod chaos;
mod cli;
mod defaults;
mod docs;
mod full_disk;
mod fuzz;
mod outputs;
mod resume;
mod study;
mod sweep;
mod util;
