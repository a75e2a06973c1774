//! Write the QPs of the first SQP iterations on the jump collocation
//! problem as clarabel JSON (exact element Hessians with the jump's
//! eigenvalue floor 1e-4, as `leap solve`), for profiling the QP solver:
//! `cargo run --release --example sqp_jump_dump -- DIR [ITERATIONS]`;
//! with `INERTIA=1` the QPs of `--hessian exact-inertia-corrected` instead
//! (element Hessians unmodified, for leap's interior-point solver); `MESH`
//! sets the number of mesh intervals (default 28). Besides each
//! iteration's QP (`qp_iter<k>_qp.json`) it writes the plain QPs the SQP
//! took as infeasible (`qp_iter<k>_plain_infeasible.json`).
use std::sync::Arc;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = args.next().ok_or("usage: sqp_jump_dump DIR [ITERATIONS]")?;
    let iterations: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(1);
    let model = leap::model::Model::from_file(std::path::Path::new("models/jumper.json"))?;
    let ocp = Arc::new(leap::ocp::JumpOcp::new(&model, Default::default())?);
    let mesh: usize = match std::env::var("MESH") {
        Ok(s) => s.parse().map_err(|e| format!("MESH={s}: {e}"))?,
        Err(_) => 28,
    };
    let mut tr = leap::transcription::Transcription::new(
        ocp,
        leap::transcription::TranscriptionOptions {
            num_mesh_intervals: mesh,
            ..Default::default()
        },
    )?;
    let (guess, _) = tr.bang_bang_guess()?;
    let settings = leap::sqp::SqpSettings {
        max_iterations: iterations,
        qp_dump_dir: Some(dir.into()),
        qp_dump_every: true,
        hessian: leap::sqp::HessianMode::ExactConvexified,
        eigenvalue_floor: 1e-4,
        ..Default::default()
    };
    let settings = if std::env::var_os("INERTIA").is_some() {
        leap::sqp::SqpSettings {
            convexification: leap::sqp::Convexification::InertiaCorrection,
            qp_solver: leap::sqp::QpSolver::InteriorPoint,
            ..settings
        }
    } else {
        settings
    };
    let r = leap::sqp::solve_from(&mut tr, &guess, &settings);
    println!("{:?} after {} iterations", r.status, r.iterations);
    Ok(())
}
