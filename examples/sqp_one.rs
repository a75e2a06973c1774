//! Solve one test-set problem with the iteration log: `cargo run --release --example sqp_one -- hs015 [exact|bfgs] [tol]`.
use leap::nlp::AdNlp;
use leap::sqp::{solve, SqpSettings};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let p = leap::testset::by_name(&args[1]).expect("unknown problem");
    let mode = args
        .get(2)
        .map_or(leap::sqp::HessianMode::PartitionedBfgs, |s| {
            s.parse().expect("mode: exact or bfgs")
        });
    let tol = args.get(3).map(|s| s.parse().expect("tol")).unwrap_or(1e-6);
    let r = solve(
        &mut AdNlp::new(p),
        &SqpSettings {
            hessian: mode,
            verbose: true,
            optim_convergence_tolerance: tol,
            ..Default::default()
        },
    );
    println!(
        "{:?} f {} viol {} its {}: {}\nx {:?}",
        r.status, r.objective, r.constraint_violation, r.iterations, r.message, r.x
    );
}
