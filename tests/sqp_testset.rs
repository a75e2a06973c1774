//! The SQP on the published test set of src/testset.rs: every
//! Hock–Schittkowski problem must reach the book's optimal value within
//! 1e-6 relative with status solved, in both Hessian modes; infeasible and
//! unbounded problems must be reported as such.

use leap::nlp::AdNlp;
use leap::sqp::{solve, HessianMode, QpSolver, SqpSettings, SqpStatus};
use leap::testset::{hock_schittkowski, infeasible_problems, unbounded_problems};

fn settings(mode: HessianMode) -> SqpSettings {
    SqpSettings {
        hessian: mode,
        verbose: std::env::var("LEAP_SQP_VERBOSE").is_ok(),
        ..Default::default()
    }
}

/// Problems the SQP does not solve to the book's optimum from the book's
/// starting point, with the reason and the evidence that a good solver
/// ends there too; the note of each landing lists them. `None` = both
/// Hessian modes.
///
/// Checked: moving the projected start inside the bounds by IPOPT's
/// bound_push (0.01) does not change hs002 (exact), hs016, hs020 or hs055.
const KNOWN_FAILURES: &[(&str, Option<HessianMode>, &str)] = &[
    ("hs002", Some(HessianMode::ExactConvexified), "nonconvex: ends at the other local minimum f = 4.9412 (-1.2210, 1.5); the CasADi test suite (test/python/hock_schittkowski/hs002.py) expects IPOPT to end there from the book's x0"),
    ("hs013", None, "degenerate: no KKT multipliers exist at x* (MFCQ fails), the SQP converges linearly with diverging multipliers; since the dual scaling s_d is capped it is no longer called solved at f = 1.00007 and ends at the iteration limit. IPOPT reports 'optimal' at f = 0.9946, x = (1.003, 0) (github.com/jkitchin/ripopt/issues/19; OPTI's fmin 0.9945785)"),
    ("hs016", None, "the book's x0 = (−2, 1) violates x1 ≥ −0.5; its projection (−0.5, 1) lies next to the local minimum f = 23.1447 at (−0.5, 1/√2) (bound and x1 + x2² ≥ 0 active, positive multipliers), where the SQP ends, also from (−0.49, 1), where IPOPT's bound_push would start; no published run found"),
    ("hs020", None, "nonconvex: ends at the local minimum f = 40.199 (−0.5, √3/2); the CasADi test suite (hs020.py: 'starts closer to local minimum') expects IPOPT there, and the SIF's SOLTN is 40.199"),
    ("hs055", None, "rank-deficient: the feasible set is the segment x(t), t ∈ [0, 1]; the point of it nearest x0 (ℓ1 and ℓ2, SNOPT's proximal-point start) is t = 1, the local minimum f = 20/3, where the SQP ends; the SIF's SOLTN is 6.6666667"),
];

fn known_failure(name: &str, mode: HessianMode) -> bool {
    KNOWN_FAILURES
        .iter()
        .any(|&(n, m, _)| n == name && m.is_none_or(|m| m == mode))
}

fn run_all(mode: HessianMode, qp_solver: QpSolver) {
    let mut failures = Vec::new();
    let mut iterations = 0;
    let mut fallbacks = 0;
    let mut fallback_names = Vec::new();
    let mut solved = 0;
    let problems = hock_schittkowski();
    for p in problems.iter().cloned() {
        let (name, f_star) = (p.name, p.reference_optimum());
        if known_failure(name, mode) && std::env::var("LEAP_ALL").is_err() {
            continue;
        }
        // LEAP_ONLY=hs013,hs016 runs only these (with LEAP_SQP_VERBOSE, to
        // read their iteration logs).
        if let Ok(only) = std::env::var("LEAP_ONLY") {
            if !only.split(',').any(|n| n == name) {
                continue;
            }
        }
        solved += 1;
        let st = SqpSettings {
            qp_solver,
            ..settings(mode)
        };
        let r = solve(&mut AdNlp::new(p), &st);
        iterations += r.iterations;
        // Leap's interior-point solver may hand clarabel only QPs that
        // clarabel then finds infeasible.
        let handed = r.qp_fallbacks - r.qp_fallbacks_infeasible;
        if !known_failure(name, mode) && handed > 0 {
            fallbacks += handed;
            fallback_names.push(name);
        }
        let err = (r.objective - f_star).abs() / f_star.abs().max(1.0);
        if r.status != SqpStatus::Solved
            || err.is_nan()
            || err > 1e-6
            || r.constraint_violation > 1e-6
        {
            failures.push(format!("{name}: {:?} f {} (f* {f_star}, rel err {err:.1e}) viol {:.1e} after {} iterations: {}", r.status, r.objective, r.constraint_violation, r.iterations, r.message));
        }
    }
    eprintln!(
        "{mode:?}, {qp_solver:?}: {solved} of {} problems, {iterations} iterations, {fallbacks} feasible QPs handed to clarabel",
        problems.len()
    );
    assert!(solved >= 25 || std::env::var("LEAP_ONLY").is_ok());
    // Leap's interior-point solver must solve every feasible QP of the
    // test set itself (clarabel is only its fallback).
    assert!(
        qp_solver == QpSolver::Clarabel || fallbacks == 0,
        "{fallbacks} feasible QPs handed to clarabel, in {fallback_names:?}"
    );
    assert!(
        failures.is_empty(),
        "{mode:?}: {} of {} failed:\n{}",
        failures.len(),
        problems.len(),
        failures.join("\n")
    );
}

#[test]
fn hock_schittkowski_exact_hessian() {
    run_all(HessianMode::ExactConvexified, QpSolver::InteriorPoint);
}

#[test]
fn hock_schittkowski_partitioned_bfgs() {
    run_all(HessianMode::PartitionedBfgs, QpSolver::InteriorPoint);
}

/// The same with clarabel alone solving the QPs.
#[test]
fn hock_schittkowski_exact_hessian_clarabel() {
    run_all(HessianMode::ExactConvexified, QpSolver::Clarabel);
}

#[test]
fn hock_schittkowski_partitioned_bfgs_clarabel() {
    run_all(HessianMode::PartitionedBfgs, QpSolver::Clarabel);
}

#[test]
fn infeasible_problems_are_reported() {
    for mode in [HessianMode::ExactConvexified, HessianMode::PartitionedBfgs] {
        for p in infeasible_problems() {
            let name = p.name;
            let r = solve(&mut AdNlp::new(p), &settings(mode));
            assert_eq!(
                r.status,
                SqpStatus::Infeasible,
                "{name} {mode:?}: {} ({} iterations)",
                r.message,
                r.iterations
            );
            assert!(r.constraint_violation > 1e-3, "{name}");
        }
    }
}

/// Known failure: with the convexified exact Hessian the eigenvalue floor
/// caps the step along a direction without curvature at ‖g‖/δ, so the
/// objective falls only linearly and never reaches −1e20; only the
/// partitioned BFGS mode reports unboundedness so far.
#[test]
fn unbounded_problems_are_reported() {
    let mode = HessianMode::PartitionedBfgs;
    for p in unbounded_problems() {
        let name = p.name;
        let r = solve(&mut AdNlp::new(p), &settings(mode));
        assert_eq!(
            r.status,
            SqpStatus::Unbounded,
            "{name} {mode:?}: {} ({} iterations)",
            r.message,
            r.iterations
        );
    }
}
