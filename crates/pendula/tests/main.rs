//! pendula's integration tests: one binary, one module per concern.
//!
//! Names state their evidence: `ref_*` tests check against an independent reference
//! (closed forms, or mpmath at 30 digits: `reference/mpmath_reference.py`).
//!
//! `reference/mpmath_reference.py` prints every value the tests embed.
//! The `checkpoint` module pauses every method, fixed and adaptive, after many
//! different steps and checks that the continued runs give the same samples, bits and counts.

// Reference values are pasted with the 20 digits mpmath printed, to keep their provenance plain.
#![allow(clippy::excessive_precision)]

mod adaptive;
mod alloc;
mod analysis;
mod architecture;
mod bifurcation;
mod chain;
mod checkpoint;
mod conformance;
mod docs;
mod energy;
mod engine;
mod ensemble;
mod events;
mod exact;
mod forced;
mod formulations;
mod fractal;
mod implicit;
mod kit;
mod lyapunov;
mod messages;
mod observe;
mod poincare;
mod scales;
mod schedule;
mod special;
mod study;
mod support;
mod symplectic;
mod trig;
