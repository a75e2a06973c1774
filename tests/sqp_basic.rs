//! The SQP on small problems written here (the published test set is in
//! tests/sqp_testset.rs).

use leap::nlp::{AdNlp, AdProblem};
use leap::scalar::Scalar;
use leap::sqp::{solve, HessianMode, SqpSettings, SqpStatus};

/// HS071 (Hock & Schittkowski 1981, problem 71): f* = 17.0140173.
struct Hs071;
impl AdProblem for Hs071 {
    fn name(&self) -> String {
        "hs071".into()
    }
    fn num_variables(&self) -> usize {
        4
    }
    fn num_constraints(&self) -> usize {
        2
    }
    fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l.fill(1.0);
        u.fill(5.0);
    }
    fn constraint_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l[0] = 25.0;
        u[0] = f64::INFINITY;
        l[1] = 40.0;
        u[1] = 40.0;
    }
    fn initial_point(&self, x: &mut [f64]) {
        x.copy_from_slice(&[1.0, 5.0, 5.0, 1.0]);
    }
    fn eval<D: Scalar>(&self, x: &[D], c: &mut [D]) -> D {
        c[0] = x[0] * x[1] * x[2] * x[3];
        c[1] = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3];
        x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2]
    }
}

/// Rosenbrock, unconstrained: f* = 0 at (1, 1).
struct Rosenbrock;
impl AdProblem for Rosenbrock {
    fn name(&self) -> String {
        "rosenbrock".into()
    }
    fn num_variables(&self) -> usize {
        2
    }
    fn num_constraints(&self) -> usize {
        0
    }
    fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l.fill(f64::NEG_INFINITY);
        u.fill(f64::INFINITY);
    }
    fn constraint_bounds(&self, _l: &mut [f64], _u: &mut [f64]) {}
    fn initial_point(&self, x: &mut [f64]) {
        x.copy_from_slice(&[-1.2, 1.0]);
    }
    fn eval<D: Scalar>(&self, x: &[D], _c: &mut [D]) -> D {
        let a = x[1] - x[0] * x[0];
        let b = D::from(1.0) - x[0];
        a * a * 100.0 + b * b
    }
}

fn run<P: AdProblem>(p: P, mode: HessianMode) -> leap::sqp::SqpResult {
    let mut nlp = AdNlp::new(p);
    let settings = SqpSettings { hessian: Some(mode), verbose: std::env::var("LEAP_SQP_VERBOSE").is_ok(), ..Default::default() };
    solve(&mut nlp, &settings)
}

#[test]
fn hs071_both_hessians() {
    for mode in [HessianMode::ExactConvexified, HessianMode::PartitionedBfgs] {
        let r = run(Hs071, mode);
        assert_eq!(r.status, SqpStatus::Solved, "{mode:?}: {}", r.message);
        assert!((r.objective - 17.0140173).abs() < 1e-6 * 17.0, "{mode:?}: {}", r.objective);
    }
}

#[test]
fn rosenbrock_both_hessians() {
    for mode in [HessianMode::ExactConvexified, HessianMode::PartitionedBfgs] {
        let r = run(Rosenbrock, mode);
        assert_eq!(r.status, SqpStatus::Solved, "{mode:?}: {}", r.message);
        assert!(r.objective.abs() < 1e-10, "{mode:?}: {}", r.objective);
        assert!((r.x[0] - 1.0).abs() < 1e-5 && (r.x[1] - 1.0).abs() < 1e-5);
    }
}
