//! leap: predicting human movement by optimal control.
//!
//! Data flows one way: [`model`] (files and validation) → [`multibody`]
//! (Rust-native dynamics) and [`simbody`] (the Simbody bridge) → [`path`]
//! and the force laws ([`laws`]) → the state equation ([`ode`]) → forward
//! simulation ([`simulate`], [`squat`]) → the jump problem ([`ocp`]), its
//! transcription ([`transcription`]) and solver ([`sqp`]), run from a study
//! ([`study`], [`solve`]) → output ([`io`]).

// Index loops mirror the equations they implement.
#![allow(clippy::needless_range_loop, clippy::large_enum_variant)]

/// `eprintln!` that carries on when standard error is closed or full
/// (`leap paths 2>&1 | head -1`, `2>/dev/full`): a warning or a log line
/// that cannot be shown is no reason to panic (`eprintln!` does).
#[macro_export]
macro_rules! errln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr().lock(), $($arg)*);
    }};
}

pub mod analyze;
pub mod bench;
pub mod crosscheck;
pub mod eval;
pub mod hyperdual;
pub mod integrator;
pub mod io;
pub mod laws;
pub mod mesh_error;
pub mod model;
pub mod multibody;
pub mod nlp;
pub mod ocp;
pub mod ode;
pub mod path;
pub mod report;
pub mod scalar;
pub mod shooting;
pub mod simbody;
pub mod simulate;
pub mod solve;
pub mod spline;
pub mod sqp;
pub mod squat;
pub mod study;
pub mod testset;
pub mod transcription;
