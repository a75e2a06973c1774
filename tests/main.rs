//! Every integration test in one binary: one build and link (with the
//! release profile's LTO) instead of one per file, which took most of the
//! CI run. Run one file's tests with a filter, e.g.
//! `cargo test --release --test integration transcription::`.

mod analyze;
mod cli;
mod cli_simulate;
mod cli_solve;
mod common;
mod dynamics;
mod integrator;
mod io;
mod jump_solve;
mod laws;
mod laws_opensim;
mod model_files;
mod no_alloc;
mod opensim_files;
mod opensim_forward;
mod paths;
mod paths_opensim;
mod report;
mod robustness;
mod shooting;
mod simbody_bridge;
mod simbody_callback;
mod simulate;
mod sqp_basic;
mod sqp_inertia;
mod sqp_ocp;
mod sqp_testset;
mod squat;
mod state_equation;
mod transcription;
