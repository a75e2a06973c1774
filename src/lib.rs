//! leap: predicting human movement by optimal control.
//!
//! Data flows one way: [`model`] (files and validation) → [`multibody`]
//! (Rust-native dynamics) and [`simbody`] (the Simbody bridge) → [`path`]
//! and the force laws ([`laws`]) → the state equation ([`ode`]) → forward
//! simulation ([`simulate`], [`squat`]) → output ([`io`]).

// Index loops mirror the equations they implement.
#![allow(clippy::needless_range_loop, clippy::large_enum_variant)]

pub mod scalar;
pub mod spline;
pub mod path;
pub mod model;
pub mod multibody;
pub mod simbody;
pub mod crosscheck;
pub mod bench;
pub mod io;
pub mod integrator;
pub mod ode;
pub mod laws;
pub mod simulate;
pub mod squat;
pub mod eval;
pub mod nlp;
pub mod sqp;
pub mod testset;
pub mod ocp;
pub mod transcription;
