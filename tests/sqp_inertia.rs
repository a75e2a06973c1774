//! The exact Hessian without eigenvalue modification, made convex on the
//! constraints by the interior-point QP solver's inertia correction
//! ([`Convexification::InertiaCorrection`]), on the published test set:
//! every Hock–Schittkowski problem that the convexified exact Hessian
//! solves must be solved to the book's optimum within 1e-6 relative here
//! too, and the setting must be refused with clarabel as the QP solver.

use leap::nlp::AdNlp;
use leap::sqp::{solve, Convexification, HessianMode, QpSolver, SqpSettings, SqpStatus};
use leap::testset::hock_schittkowski;

/// Problems that the eigenvalue clip solves and the inertia correction
/// does not, with what happens (both flagged as having local minima in
/// src/testset.rs): the unmodified Hessian lets the SQP stop at other
/// KKT points of these nonconvex problems.
/// (hs033 was one with the variables unscaled: it ended 'acceptable' after
/// 252 iterations at x = (2.0025, 0, 2.0025), f = 2.0, on the cone
/// x3² = x1² + x2²; with the bounds' scaling it is solved in 49.)
const KNOWN_DIFFERENCES: &[(&str, &str)] = &[(
    "hs044",
    "nonconvex bilinear objective: ends at the KKT point x = (0, 0.5, 3, 2), f = −3 (f* = −15)",
)];

fn settings() -> SqpSettings {
    SqpSettings {
        hessian: HessianMode::ExactConvexified,
        convexification: Convexification::InertiaCorrection,
        qp_solver: QpSolver::InteriorPoint,
        verbose: std::env::var("LEAP_SQP_VERBOSE").is_ok(),
        ..Default::default()
    }
}

#[test]
fn hock_schittkowski_with_inertia_correction() {
    let mut failures = Vec::new();
    let mut report = Vec::new();
    let (mut its_ic, mut its_clip) = (0, 0);
    for p in hock_schittkowski() {
        let (name, f_star) = (p.name, p.reference_optimum());
        let err = |f: f64| (f - f_star).abs() / f_star.abs().max(1.0);
        // The reference run: the default convexification (eigenvalue clip).
        let clip = SqpSettings {
            convexification: Convexification::Clip,
            ..settings()
        };
        let r0 = solve(&mut AdNlp::new(p.clone()), &clip);
        let r = solve(&mut AdNlp::new(p), &settings());
        let ok = |r: &leap::sqp::SqpResult| {
            r.status == SqpStatus::Solved
                && err(r.objective) <= 1e-6
                && r.constraint_violation <= 1e-6
        };
        its_ic += r.iterations;
        its_clip += r0.iterations;
        report.push(format!("{name}: {} / {}", r.iterations, r0.iterations));
        if name == "hs106" {
            // Badly scaled (x up to 1e4). Until the solved test read the
            // violation in the problem's units (Moco's and IPOPT's
            // meaning of the constraint tolerance), the inertia correction
            // with the bounds' scaling called hs106 solved after 6
            // iterations at a violation of 2.1e-4, which `ok` refuses.
            assert!(
                ok(&r),
                "hs106: {:?} f {} (f* {f_star}) viol {:.1e} after {} iterations: {}",
                r.status,
                r.objective,
                r.constraint_violation,
                r.iterations,
                r.message
            );
        }
        let known = KNOWN_DIFFERENCES.iter().any(|&(n, _)| n == name);
        if known && ok(&r) {
            failures.push(format!(
                "{name} is listed as a known difference but is solved: remove it"
            ));
        }
        if ok(&r0) && !ok(&r) && !known {
            failures.push(format!(
                "{name}: {:?} f {} (f* {f_star}) viol {:.1e} after {} iterations: {} at x = {:?}",
                r.status, r.objective, r.constraint_violation, r.iterations, r.message, r.x
            ));
        }
    }
    eprintln!(
        "iterations, inertia correction / clip: {its_ic} / {its_clip}\n{}",
        report.join(", ")
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn inertia_correction_needs_the_interior_point_solver() {
    let p = hock_schittkowski().into_iter().next().expect("hs001");
    let st = SqpSettings {
        qp_solver: QpSolver::Clarabel,
        ..settings()
    };
    let r = solve(&mut AdNlp::new(p), &st);
    assert_eq!(r.status, SqpStatus::InvalidProblem);
    assert!(r.message.contains("interior-point"), "{}", r.message);
}

/// The history reports the inertia correction's τ (`hessian_shift`, the
/// CSV column of that name): 0 at every iteration of hs035, whose
/// objective Hessian [[4, 2, 2], [2, 4, 0], [2, 0, 2]] is positive definite
/// and whose constraints are linear, and positive at the first iteration
/// of hs044, whose bilinear objective has Hessian eigenvalues ±2 and whose
/// first QP counts no inequality row as active (every direction must then
/// be convex).
#[test]
fn history_reports_the_inertia_correction() {
    let by_name = |n: &str| leap::testset::by_name(n).expect("in the test set");
    let convex = solve(&mut AdNlp::new(by_name("hs035")), &settings());
    assert_eq!(convex.status, SqpStatus::Solved, "{}", convex.message);
    assert!(!convex.history.is_empty());
    for r in &convex.history {
        assert_eq!(r.hessian_shift, 0.0, "hs035 iteration {}", r.iter);
    }
    let indefinite = solve(&mut AdNlp::new(by_name("hs044")), &settings());
    let first = indefinite.history.first().expect("one iteration at least");
    assert!(
        first.hessian_shift > 0.0,
        "hs044: τ {}",
        first.hessian_shift
    );
    // The CSV carries it under its name.
    let dir = std::env::temp_dir().join(format!("leap_sqp_shift_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("history.csv");
    indefinite.write_history_csv(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header
        .iter()
        .position(|&h| h == "hessian_shift")
        .expect("a hessian_shift column");
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(row[col].parse::<f64>().unwrap(), first.hessian_shift);
    std::fs::remove_dir_all(&dir).ok();
}
