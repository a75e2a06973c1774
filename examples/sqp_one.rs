//! Solve one test-set problem with the iteration log: `cargo run --release --example sqp_one -- hs015 [exact|bfgs|inertia] [tol]`
//! ("inertia": exact Hessian with the interior-point solver's inertia
//! correction, unscaled variables, as `tests/sqp_inertia.rs`).
use leap::nlp::AdNlp;
use leap::sqp::{solve, SqpSettings};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let p = leap::testset::by_name(&args[1]).expect("unknown problem");
    let inertia = args.get(2).is_some_and(|s| s == "inertia");
    let mode = match args.get(2) {
        Some(_) if inertia => leap::sqp::HessianMode::ExactConvexified,
        Some(s) => s.parse().expect("mode: exact, bfgs or inertia"),
        None => leap::sqp::HessianMode::PartitionedBfgs,
    };
    let tol = args.get(3).map(|s| s.parse().expect("tol")).unwrap_or(1e-6);
    let r = solve(
        &mut AdNlp::new(p),
        &SqpSettings {
            hessian: mode,
            verbose: true,
            optim_convergence_tolerance: tol,
            ..if inertia {
                SqpSettings {
                    convexification: leap::sqp::Convexification::InertiaCorrection,
                    qp_solver: leap::sqp::QpSolver::InteriorPoint,
                    scale_variables_using_bounds: false,
                    ..Default::default()
                }
            } else {
                Default::default()
            }
        },
    );
    println!(
        "{:?} f {} viol {} its {}: {}\nx {:?}",
        r.status, r.objective, r.constraint_violation, r.iterations, r.message, r.x
    );
}
