//! pendula-io: what pendula reads from its users and writes for them, written once for every
//! front end (the CLI, the Python package, the browser lab). It has no command-line parser
//! and no Python binding: the front ends map their own spelling onto these functions.
//!
//! - [`value`]: the value syntax — numbers as typed (NaN, infinities and numbers beyond
//!   f64's range refused), angles as `120deg`, `pi`, `-0.5pi`, `2*pi` (radians), grid axes
//!   `NAME=LO:HI:N`, counts — with errors that name the value and what is allowed.
//! - [`npy`]: NumPy `.npy` arrays of little-endian float64, whole or streamed row by row,
//!   with the length and CRC-32 of what was written, and the check of what a file's header
//!   claims before it is read.
//! - [`shard`]: the descriptions written beside a sharded run's `.npy` files (FILE.npy.json)
//!   and the checks that the shards handed to a merge are all of one run, each once, intact.
//! - [`scenario`]: scenario files (TOML), read by the CLI and written by the lab.
//! - [`checkpoint`]: checkpoint files (header line with a CRC-32, then JSON) and the exact
//!   encodings of the state they hold; [`chunks`]: the values files of grids computed a
//!   chunk at a time with a checkpoint.
//!
//! Units are SI and angles radians, as in the library ([`pendula`]).
//!
//! ```
//! use pendula_io::value::parse_value;
//! let info = pendula::model::find("double").unwrap();
//! let theta1 = info.quantity("theta1").unwrap();
//! assert_eq!(parse_value("theta1", "-0.5pi", Some(theta1)).unwrap(), -std::f64::consts::FRAC_PI_2);
//! assert!(parse_value("m1", "2deg", Some(info.quantity("m1").unwrap())).is_err());
//! ```

pub mod checkpoint;
pub mod chunks;
pub mod npy;
pub mod scenario;
pub mod shard;
pub mod value;

/// Why a value or a file was refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A value that cannot be used: the message names it and what is allowed.
    #[error("{0}")]
    Invalid(String),
    /// The library refused it (an unknown system or quantity name, in its words).
    #[error(transparent)]
    Library(#[from] pendula::Error),
}

/// The result of this crate's functions.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// An [`Error::Invalid`] from a format string.
macro_rules! invalid {
    ($($arg:tt)*) => { $crate::Error::Invalid(format!($($arg)*)) };
}
pub(crate) use invalid;

/// `context: error: its causes`, each cause skipped that only repeats the end of the text
/// before it.
pub(crate) fn caused(context: String, e: &dyn std::error::Error) -> Error {
    let mut text = context;
    let mut cause = Some(e);
    while let Some(c) = cause {
        let t = c.to_string();
        if !text.ends_with(&t) {
            text.push_str(": ");
            text.push_str(&t);
        }
        cause = c.source();
    }
    Error::Invalid(text)
}
