//! A study solved with SQP settings taken from the environment, for
//! experiments on the globalisation (`leap solve`'s run, the settings set
//! directly, without the checks of its command-line options):
//! `cargo run --release --example study_probe -- STUDY OUT` (no forward
//! check) with any of LS=merit|filter, VGROWTH=v (max_violation_growth),
//! TRRATIO=0, SOC=0, SOCALL=1 (second_order_correction_every_rejected_step),
//! RESETS=n (max_filter_resets), MAXIT=n, STALL=n,
//! HESSIAN=exact|bfgs (no inertia correction), QP=clarabel|interior-point,
//! N=mesh intervals, SCHEME and FIBER (`--scheme`, `--fiber-dynamics`),
//! VERBOSE=1 (the iteration log), VLS=1 (each rejected full step).
use leap::sqp::{HessianMode, LineSearch, QpSolver};
use std::str::FromStr;

/// The environment variable `key`, if set, parsed into `field`.
fn parse<T: FromStr>(key: &str, field: &mut T) -> Result<(), String>
where
    T::Err: std::fmt::Display,
{
    if let Ok(v) = std::env::var(key) {
        *field = v.parse().map_err(|e| format!("{key}={v}: {e}"))?;
    }
    Ok(())
}

/// The environment variable `key`, if set: on unless "0".
fn switch(key: &str, field: &mut bool) {
    if let Ok(v) = std::env::var(key) {
        *field = v != "0";
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [study, out] = args.as_slice() else {
        return Err("usage: study_probe STUDY OUT".into());
    };
    let mut c = leap::study::SolveConfig::load_with_model(Some(std::path::Path::new(study)), None)?;
    c.apply(&leap::study::Overrides {
        scheme: std::env::var("SCHEME").ok(),
        fiber_dynamics: std::env::var("FIBER").ok(),
        ..Default::default()
    })?;
    c.output_directory = out.into();
    c.forward_check = None;
    let env = |k: &str| std::env::var(k).ok();
    let s = &mut c.settings;
    if let Some(v) = env("LS") {
        s.line_search = match v.as_str() {
            "merit" => LineSearch::L1Merit,
            "filter" => LineSearch::Filter,
            _ => return Err(format!("LS={v}: merit or filter").into()),
        };
    }
    parse("VGROWTH", &mut s.max_violation_growth)?;
    switch("TRRATIO", &mut s.trust_region_ratio);
    switch("SOC", &mut s.second_order_correction);
    switch("SOCALL", &mut s.second_order_correction_every_rejected_step);
    parse("RESETS", &mut s.max_filter_resets)?;
    parse("MAXIT", &mut s.max_iterations)?;
    parse("STALL", &mut s.stall_iterations)?;
    if let Some(v) = env("HESSIAN") {
        s.hessian = HessianMode::from_str(&v)?;
    }
    if let Some(v) = env("QP") {
        s.qp_solver = match v.as_str() {
            "clarabel" => QpSolver::Clarabel,
            "interior-point" => QpSolver::InteriorPoint,
            _ => return Err(format!("QP={v}: clarabel or interior-point").into()),
        };
    }
    parse("N", &mut c.transcription.num_mesh_intervals)?;
    s.verbose = false;
    switch("VERBOSE", &mut s.verbose);
    switch("VLS", &mut s.verbose_line_search);
    let verbose = s.verbose;
    let r = leap::solve::run(&c, verbose, &mut |_| {})?;
    println!(
        "{} after {} iterations, {:.1} s: J {:.8}, jump {:.4} cm, violation {:.2e}: {}",
        r.moco_status,
        r.iterations,
        r.wall_time_s,
        r.objective,
        r.jump_height_m * 100.0,
        r.max_constraint_violation,
        r.message
    );
    Ok(())
}
