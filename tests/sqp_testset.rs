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
/// starting point, with the reason and the published runs from the same
/// start, those that end where leap does and those that do not
/// (Schittkowski's own test frame with NLPQLP 4.04: PROB.FOR, TEST.DAT and
/// RESULT.DAT, vendored in github.com/jkitchin/ripopt at commit 3f2125c,
/// benchmarks/hs; IPOPT's runs on the same Fortran problems there). The
/// note of each landing lists them. `None` = both Hessian modes.
///
/// Checked: moving the projected start inside the bounds by IPOPT's
/// bound_push (0.01) does not change hs002 (exact), hs016, hs020 or hs055.
const KNOWN_FAILURES: &[(&str, Option<HessianMode>, &str)] = &[
    ("hs002", Some(HessianMode::ExactConvexified), "nonconvex: ends at the other local minimum f = 4.9412 (-1.2210, 1.5), as IPOPT does from the book's x0 (ripopt's native IPOPT run, benchmarks/hs/hs_ipopt_native_results.json at jkitchin/ripopt 3f2125c: 4.9412293 in 10 iterations; the CasADi test suite's hs002.py expects it too); NLPQLP, a BFGS SQP, reaches 0.050426 (Schittkowski's test frame, TEST.DAT in the same directory), as leap's BFGS mode does"),
    ("hs013", None, "degenerate, not reachable to 1e-6 with these QP solvers: along x2 = 0, x1 = 1 + ε violates by ε³ with f = 1 - 2ε + ε², and the feasible side has f ≈ 1 + 2ε, so f within 1e-6 needs |ε| ≤ 5e-7, where the KKT-like multipliers are 2/(3ε²) ≈ 2.7e12 and the linearised row's d1 coefficient 3ε² ≤ 7.5e-13 must resolve a change of ε³ ≤ 1.25e-19. The QP solvers accept row residuals of about 1e-10·(1 + ‖b‖) ≥ 1.1e-9 (b holds the step bound 10), so below ε ≈ (1.1e-9)^(1/3) ≈ 1e-3 the QP no longer determines d1 (exact + IPM, iteration 18 at ε = 4.5e-4: d1 = 10, the bound, instead of ≤ 1.5e-4, the row violated by 6.1e-6 and accepted as almost solved). The runs stop at that scale (2026-12-04, LEAP_ONLY=hs013 LEAP_ALL=1): exact + IPM 'acceptable' after 52 iterations at f = 0.99287 (violation 4.5e-8), BFGS + IPM 'solved' after 36 at f = 0.99627 (violation 6.5e-9), exact + clarabel and BFGS + clarabel at the 3,000-iteration limit, returning iterations 35 (f = 0.86594, violation 3.3e-4) and 24 (f = 0.99896, violation 1.4e-10). An earlier exact + IPM run cycled at x1 = 1.0074 until its line search failed after 1573 iterations (its feasibility QP, which keeps ½dᵀBd with B11 ≈ 500 against the row gradient 1.6e-4, reduced the violation 4e-7 by 5e-11, below the absolute 1e-9 of the old stationarity test, and called it infeasible). Published runs do not reach 1e-6 either: NLPQLP 1.0000017 (rel. err 1.7e-6, Schittkowski's TEST.DAT, jkitchin/ripopt 3f2125c benchmarks/hs), IPOPT 0.99458 at (1.0027, 0) (github.com/jkitchin/ripopt/issues/19)"),
    ("hs016", None, "the book's x0 = (−2, 1) violates x1 ≥ −0.5; its projection (−0.5, 1) lies next to the local minimum f = 23.1447 at (−0.5, 1/√2) (bound and x1 + x2² ≥ 0 active, positive multipliers), where the SQP ends, also from IPOPT's pushed start (−0.495, 0.99). Schittkowski's own test frame ends there with NLPQLP (23.144661, listed under 'Local solution: TP 16' in RESULT.DAT; jkitchin/ripopt 3f2125c benchmarks/hs); IPOPT, an interior-point method, reaches 0.25 from the same x0 (hs_ipopt_native_results.json there)"),
    ("hs020", None, "nonconvex: from the book's x0 = (−2, 1) (the SIF's; projected to (−0.5, 1)) ends at the local minimum f = 40.199 (−0.5, √3/2); the SIF's SOLTN is 40.199 and the CasADi test suite (hs020.py: 'starts closer to local minimum') expects IPOPT there. Schittkowski's later Fortran version (PROB.FOR, TP20) starts at (0.1, 1), from which NLPQLP (38.198730, TEST.DAT) and IPOPT (38.19873) reach f*, and so does leap in all four modes (checked with solve_from)"),
    ("hs055", None, "rank-deficient: the feasible set is the segment x(t), t ∈ [0, 1]; the point of it nearest x0 (ℓ1 and ℓ2, SNOPT's proximal-point start) is t = 1, the local minimum f = 20/3, where the SQP ends; the SIF's SOLTN is 6.6666667, and NLPQLP ends there too (6.6666667, listed under 'Local solution: TP 55' in Schittkowski's RESULT.DAT, jkitchin/ripopt 3f2125c benchmarks/hs)"),
];

fn known_failure(name: &str, mode: HessianMode) -> bool {
    KNOWN_FAILURES
        .iter()
        .any(|&(n, m, _)| n == name && m.is_none_or(|m| m == mode))
}

fn run_all(mode: HessianMode, qp_solver: QpSolver) {
    run_all_with(mode, qp_solver, |s| s);
}

/// [`run_all`] with settings changed by `adjust`.
fn run_all_with(mode: HessianMode, qp_solver: QpSolver, adjust: fn(SqpSettings) -> SqpSettings) {
    let mut failures = Vec::new();
    let mut iterations = 0;
    let mut fallbacks = 0;
    let mut fallback_names = Vec::new();
    let mut stalls: Vec<(&str, usize)> = Vec::new();
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
        let st = adjust(SqpSettings {
            qp_solver,
            ..settings(mode)
        });
        let r = solve(&mut AdNlp::new(p), &st);
        iterations += r.iterations;
        // Leap's interior-point solver may hand clarabel only QPs that
        // clarabel then finds infeasible.
        let handed = r.qp_fallbacks - r.qp_fallbacks_infeasible;
        if !known_failure(name, mode) && handed > 0 {
            fallbacks += handed;
            fallback_names.push(name);
        }
        if r.qp_stalls_taken_infeasible > 0 {
            stalls.push((name, r.qp_stalls_taken_infeasible));
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
        "{mode:?}, {qp_solver:?}: {solved} of {} problems, {iterations} iterations, {fallbacks} feasible QPs handed to clarabel, stalled plain QPs taken as infeasible {stalls:?}",
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

/// The filter line search's opt-in filter reset and second-order
/// correction of every rejected full step (off by default) keep every
/// problem at its published optimum, in both Hessian modes.
#[test]
fn hock_schittkowski_with_filter_resets_and_every_correction() {
    for mode in [HessianMode::ExactConvexified, HessianMode::PartitionedBfgs] {
        run_all_with(mode, QpSolver::InteriorPoint, |s| SqpSettings {
            max_filter_resets: 5,
            second_order_correction_every_rejected_step: true,
            ..s
        });
    }
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

/// Both Hessian modes, with either QP solver. With the convexified exact
/// Hessian a direction without curvature is held by the eigenvalue floor
/// until the step bound grows past its initial value and the floor falls
/// with it; a floor that did not would cap the step at ‖g‖/floor and let
/// the objective fall only linearly, never reaching −1e20.
#[test]
fn unbounded_problems_are_reported() {
    for mode in [HessianMode::ExactConvexified, HessianMode::PartitionedBfgs] {
        for qp_solver in [QpSolver::InteriorPoint, QpSolver::Clarabel] {
            for p in unbounded_problems() {
                let name = p.name;
                let st = SqpSettings {
                    qp_solver,
                    ..settings(mode)
                };
                let r = solve(&mut AdNlp::new(p), &st);
                assert_eq!(
                    r.status,
                    SqpStatus::Unbounded,
                    "{name} {mode:?} {qp_solver:?}: {} ({} iterations)",
                    r.message,
                    r.iterations
                );
            }
        }
    }
}

/// With `qp_dump_every`, the plain QP the SQP takes as infeasible is
/// written beside each iteration's QP: clarabel, reading the file back,
/// must find it primal infeasible, and the elastic QP the SQP went on with
/// must solve.
#[test]
fn plain_qps_taken_as_infeasible_are_written() {
    use clarabel::solver::SolverStatus;
    let dir = std::env::temp_dir().join(format!("leap_qp_dump_{}", std::process::id()));
    let p = infeasible_problems()
        .into_iter()
        .find(|p| p.name == "infeasible_linear")
        .expect("infeasible_linear is in the test set");
    for qp_solver in [QpSolver::Clarabel, QpSolver::InteriorPoint] {
        let _ = std::fs::remove_dir_all(&dir);
        let st = SqpSettings {
            qp_solver,
            qp_dump_dir: Some(dir.clone()),
            qp_dump_every: true,
            ..settings(HessianMode::PartitionedBfgs)
        };
        let r = solve(&mut AdNlp::new(p.clone()), &st);
        assert_eq!(
            r.status,
            SqpStatus::Infeasible,
            "{qp_solver:?}: {}",
            r.message
        );
        let status = |name: &str| crate::common::clarabel_status(&dir.join(name));
        assert_eq!(
            status("qp_iter0_plain_infeasible.json"),
            SolverStatus::PrimalInfeasible,
            "{qp_solver:?}"
        );
        assert_eq!(
            status("qp_iter0_qp.json"),
            SolverStatus::Solved,
            "{qp_solver:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
