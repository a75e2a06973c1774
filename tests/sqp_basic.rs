//! The SQP on small problems written here (the published test set is in
//! tests/sqp_testset.rs).

use leap::nlp::{AdNlp, AdProblem};
use leap::scalar::Scalar;
use leap::sqp::{solve, HessianMode, SqpSettings, SqpStatus};

/// HS071 from the test set (Hock & Schittkowski 1981, problem 71):
/// f* = 17.0140173.
fn hs071() -> leap::testset::HsProblem {
    leap::testset::by_name("hs071").expect("hs071 is in the test set")
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
    let settings = SqpSettings {
        hessian: mode,
        verbose: std::env::var("LEAP_SQP_VERBOSE").is_ok(),
        ..Default::default()
    };
    solve(&mut nlp, &settings)
}

#[test]
fn hs071_both_hessians() {
    for mode in [HessianMode::ExactConvexified, HessianMode::PartitionedBfgs] {
        let r = run(hs071(), mode);
        assert_eq!(r.status, SqpStatus::Solved, "{mode:?}: {}", r.message);
        assert!(
            (r.objective - 17.0140173).abs() < 1e-6 * 17.0,
            "{mode:?}: {}",
            r.objective
        );
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

#[test]
fn iteration_history_as_csv() {
    let r = run(hs071(), HessianMode::PartitionedBfgs);
    let dir = std::env::temp_dir().join(format!("leap_sqp_history_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("history.csv");
    r.write_history_csv(&path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[0].starts_with("iter,objective,inf_pr,inf_du"));
    assert_eq!(lines.len(), r.history.len() + 1);
    assert_eq!(r.history.len(), r.iterations + 1);
    // The last record is the converged iterate.
    let last: Vec<&str> = lines.last().unwrap().split(',').collect();
    assert!((last[1].parse::<f64>().unwrap() - r.objective).abs() < 1e-12);
    std::fs::remove_dir_all(&dir).ok();
}

/// As IPOPT's log, the history's `objective` and `inf_pr` are in the
/// problem's units, whatever the solver's scaling: the first record, at the
/// start, is the same with IPOPT's gradient-based scaling and without it,
/// on every problem, while the scaled dual infeasibility differs where the
/// scaling acts (asserted to be on some problems). (That a solve called
/// solved is within `optim_constraint_tolerance` in these units, Moco's
/// meaning, `tests/sqp_inertia.rs` checks on hs106.)
#[test]
fn history_is_in_the_problems_units() {
    let mut scaled = Vec::new();
    for p in leap::testset::hock_schittkowski() {
        let name = p.name;
        let with = solve(&mut AdNlp::new(p.clone()), &SqpSettings::default());
        let without = solve(
            &mut AdNlp::new(p),
            &SqpSettings {
                nlp_scaling: false,
                ..Default::default()
            },
        );
        let (a, b) = (&with.history[0], &without.history[0]);
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * x.abs().max(y.abs()).max(1e-300);
        assert!(
            close(a.objective, b.objective),
            "{name}: objective {} against {}",
            a.objective,
            b.objective
        );
        assert!(
            close(a.inf_pr, b.inf_pr),
            "{name}: inf_pr {:e} against {:e}",
            a.inf_pr,
            b.inf_pr
        );
        if !close(a.inf_du, b.inf_du) {
            scaled.push(name);
        }
    }
    assert!(scaled.len() >= 5, "the scaling acts on {scaled:?} only");
}

#[test]
fn bad_problems_get_a_status_not_a_panic() {
    // Inverted bounds.
    struct Inverted;
    impl AdProblem for Inverted {
        fn name(&self) -> String {
            "inverted".into()
        }
        fn num_variables(&self) -> usize {
            1
        }
        fn num_constraints(&self) -> usize {
            0
        }
        fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
            l[0] = 1.0;
            u[0] = 0.0;
        }
        fn constraint_bounds(&self, _l: &mut [f64], _u: &mut [f64]) {}
        fn initial_point(&self, x: &mut [f64]) {
            x[0] = 0.5;
        }
        fn eval<D: Scalar>(&self, x: &[D], _c: &mut [D]) -> D {
            x[0]
        }
    }
    let r = run(Inverted, HessianMode::PartitionedBfgs);
    assert_eq!(r.status, SqpStatus::InvalidProblem);
    assert!(
        r.message.contains("x[0]") && r.message.contains("bounds"),
        "{}",
        r.message
    );
    // NaN at the start.
    struct NanStart;
    impl AdProblem for NanStart {
        fn name(&self) -> String {
            "nan".into()
        }
        fn num_variables(&self) -> usize {
            1
        }
        fn num_constraints(&self) -> usize {
            0
        }
        fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
            l[0] = f64::NEG_INFINITY;
            u[0] = f64::INFINITY;
        }
        fn constraint_bounds(&self, _l: &mut [f64], _u: &mut [f64]) {}
        fn initial_point(&self, x: &mut [f64]) {
            x[0] = -1.0;
        }
        fn eval<D: Scalar>(&self, x: &[D], _c: &mut [D]) -> D {
            x[0].sqrt()
        }
    }
    let r = run(NanStart, HessianMode::PartitionedBfgs);
    assert_eq!(r.status, SqpStatus::EvaluationError, "{}", r.message);
}

/// Variables scaled by their bound widths (Moco's
/// `scale_variables_using_bounds`): the wrapped problem's gradient,
/// Jacobian and Hessian match central differences, and the SQP in scaled
/// variables reaches the published optima, returned in the problem's own
/// variables. hs038 (bounds ±10) and hs071 (bounds [1, 5]) are scaled by 20
/// and 4; hs106 (bounds up to 1e4) is the badly scaled one.
#[test]
fn scaled_variables() {
    use leap::nlp::{check_derivatives, Nlp, ScaledVariables};
    for name in ["hs038", "hs071", "hs106"] {
        let p = leap::testset::by_name(name).unwrap();
        let f_star = p.reference_optimum();
        let mut nlp = AdNlp::new(p);
        let n = nlp.num_variables();
        let mut x0 = vec![0.0; n];
        nlp.initial_point(&mut x0);
        {
            let mut scaled = ScaledVariables::from_bounds(&mut nlp);
            assert!(scaled.scale.iter().any(|&d| d != 1.0), "{name}: no scale");
            let xs = scaled.scale_point(&x0);
            let lambda = vec![0.7; scaled.num_constraints()];
            let chk = check_derivatives(&mut scaled, &xs, &lambda, 1e-6).unwrap();
            assert!(chk.gradient < 1e-6, "{name}: gradient {chk:?}");
            assert!(chk.jacobian < 1e-6, "{name}: jacobian {chk:?}");
            assert!(chk.hessian.unwrap() < 1e-4, "{name}: hessian {chk:?}");
            assert_eq!(scaled.unscale(&xs).len(), n);
        }
        for hessian in [HessianMode::PartitionedBfgs, HessianMode::ExactConvexified] {
            let settings = SqpSettings {
                hessian,
                scale_variables_using_bounds: true,
                ..Default::default()
            };
            let r = leap::sqp::solve_from(&mut nlp, &x0, &settings);
            let err = (r.objective - f_star).abs() / f_star.abs().max(1.0);
            assert!(
                matches!(r.status, SqpStatus::Solved) && err < 1e-6,
                "{name} {hessian:?}: {:?} f {} (f* {f_star}) after {} iterations",
                r.status,
                r.objective,
                r.iterations
            );
            // x is in the problem's own variables: f(x) is the objective.
            let f = nlp.objective(&r.x).unwrap();
            assert!((f - r.objective).abs() <= 1e-9 * f.abs().max(1.0));
        }
    }
}

/// A convex quadratic with one linear equality: the QP model of the ℓ1
/// merit is exact, so the trust-region ratio (actual over predicted
/// reduction) of every full step is 1.
struct ConvexQuadratic;
impl AdProblem for ConvexQuadratic {
    fn name(&self) -> String {
        "convex quadratic".into()
    }
    fn num_variables(&self) -> usize {
        3
    }
    fn num_constraints(&self) -> usize {
        1
    }
    fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l.fill(-100.0);
        u.fill(100.0);
    }
    fn constraint_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l[0] = 1.0;
        u[0] = 1.0;
    }
    fn initial_point(&self, x: &mut [f64]) {
        x.copy_from_slice(&[3.0, -2.0, 0.5]);
    }
    fn eval<D: Scalar>(&self, x: &[D], c: &mut [D]) -> D {
        c[0] = x[0] + x[1] * 2.0 - x[2];
        let a = x[0] - 1.0;
        let b = x[1] + 0.5;
        a * a + b * b * 2.0 + x[2] * x[2] * 3.0 + x[0] * x[1]
    }
}

#[test]
fn trust_region_ratio_is_one_where_the_model_is_exact() {
    let r = run(ConvexQuadratic, HessianMode::ExactConvexified);
    assert_eq!(r.status, SqpStatus::Solved, "{}", r.message);
    let measured: Vec<f64> = r
        .history
        .iter()
        .map(|h| h.model_ratio)
        .filter(|v| !v.is_nan())
        .collect();
    // The first step is full (it lands on the solution) and measured.
    assert!(!measured.is_empty(), "no full step was measured");
    for v in &measured {
        assert!((v - 1.0).abs() < 1e-6, "ratio {v}");
    }
}

/// At the iteration limit the solve returns the iterate of lowest
/// objective among those within `best_iterate_violation` (here checked
/// against the solve's own history, with the solver's scaling off so that
/// its objectives and the result's are the same floating-point numbers).
#[test]
fn iteration_limit_returns_the_best_iterate_within_the_violation_limit() {
    let mut swapped = 0;
    for p in leap::testset::hock_schittkowski() {
        let name = p.name;
        for max_iterations in [2, 4, 6] {
            let settings = SqpSettings {
                max_iterations,
                nlp_scaling: false,
                ..Default::default()
            };
            let r = solve(&mut AdNlp::new(p.clone()), &settings);
            if r.status != SqpStatus::IterationLimit {
                continue;
            }
            let tau = settings.best_iterate_violation;
            let best = r
                .history
                .iter()
                .filter(|h| h.inf_pr <= tau)
                .map(|h| h.objective)
                .fold(f64::INFINITY, f64::min);
            if best.is_finite() {
                assert_eq!(
                    r.objective, best,
                    "{name} after {max_iterations}: {}",
                    r.message
                );
                assert!(r.constraint_violation <= tau, "{name}");
            } else {
                // None within the limit: the last iterate.
                let last = r.history.last().unwrap();
                assert_eq!(r.objective, last.objective, "{name}");
            }
            if r.message.contains("returned iteration") {
                swapped += 1;
            }
        }
    }
    // Some of these short runs end on a worse or infeasible iterate.
    assert!(swapped > 0, "no run returned an earlier iterate");
    // With the problem scaled, the returned earlier iterate is within the
    // limit in the problem's own units. Each constraint is multiplied by
    // 1e3, which gradient-based scaling (IPOPT's, max gradient 100) takes
    // back out: in the solver's scaling a violation is then up to 1e3
    // times smaller than in the problem's units.
    let mut swapped = 0;
    for p in leap::testset::hock_schittkowski() {
        for max_iterations in [2, 4, 6] {
            let settings = SqpSettings {
                max_iterations,
                ..Default::default()
            };
            let mut nlp = AdNlp::new(Amplified(p.clone()));
            let r = solve(&mut nlp, &settings);
            if r.status == SqpStatus::IterationLimit && r.message.contains("returned iteration") {
                swapped += 1;
                let v = leap::nlp::constraint_violations(&mut nlp, &r.x)
                    .unwrap()
                    .into_iter()
                    .fold(0.0, f64::max);
                assert!(
                    v <= settings.best_iterate_violation,
                    "{} after {max_iterations}: violation {v:e}: {}",
                    p.name,
                    r.message
                );
            }
        }
    }
    assert!(swapped > 0, "no scaled run returned an earlier iterate");
}

/// A problem with every constraint (and its bounds) multiplied by 1e3.
struct Amplified(leap::testset::HsProblem);

impl AdProblem for Amplified {
    fn name(&self) -> String {
        self.0.name()
    }
    fn num_variables(&self) -> usize {
        self.0.num_variables()
    }
    fn num_constraints(&self) -> usize {
        self.0.num_constraints()
    }
    fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        self.0.variable_bounds(l, u)
    }
    fn constraint_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        self.0.constraint_bounds(l, u);
        l.iter_mut().chain(u.iter_mut()).for_each(|v| *v *= 1e3);
    }
    fn initial_point(&self, x: &mut [f64]) {
        self.0.initial_point(x)
    }
    fn eval<D: Scalar>(&self, x: &[D], c: &mut [D]) -> D {
        let f = self.0.eval(x, c);
        c.iter_mut().for_each(|v| *v *= 1e3);
        f
    }
}

/// The block-diagonal approximation of the exact Hessian
/// (`block_diagonal_elements`). One block holding every variable is the
/// exact mode itself, iteration for iteration. With every variable a block
/// of its own (a diagonal Hessian) the path changes and convergence may
/// slow to the iteration limit, but a solve that ends "solved" is at the
/// published optimum: the stopping test uses the true derivatives, not the
/// approximation. A partition with a variable missing is refused.
#[test]
fn block_diagonal_hessian_changes_the_path_not_the_solution() {
    let exact = SqpSettings {
        hessian: HessianMode::ExactConvexified,
        max_iterations: 500,
        ..Default::default()
    };
    let blocked = SqpSettings {
        block_diagonal_elements: true,
        ..exact.clone()
    };
    let (mut count, mut solved) = (0, 0);
    for p in leap::testset::hock_schittkowski() {
        let (name, f_star, n) = (p.name, p.reference_optimum(), p.num_variables());
        let plain = solve(&mut AdNlp::new(p.clone()), &exact);
        if plain.status != SqpStatus::Solved
            || (plain.objective - f_star).abs() > 1e-6 * f_star.abs().max(1.0)
        {
            continue;
        }
        count += 1;
        let one = solve(
            &mut AdNlp::new(p.clone()).with_blocks(vec![(0..n).collect()]),
            &blocked,
        );
        assert_eq!(one.iterations, plain.iterations, "{name}");
        assert_eq!(one.objective, plain.objective, "{name}");
        let diag = (0..n).map(|j| vec![j]).collect();
        let r = solve(&mut AdNlp::new(p.clone()).with_blocks(diag), &blocked);
        assert!(r.objective.is_finite(), "{name}: {:?}", r.status);
        if r.status == SqpStatus::Solved {
            solved += 1;
            let err = (r.objective - f_star).abs() / f_star.abs().max(1.0);
            assert!(
                err <= 1e-6,
                "{name}: solved at f {} (f* {f_star})",
                r.objective
            );
            assert!(r.constraint_violation <= 1e-6, "{name}");
        }
    }
    eprintln!("diagonal Hessian: {solved} of {count} solved");
    assert!(count >= 25 && solved > 0);
    let r = solve(
        &mut AdNlp::new(hs071()).with_blocks(vec![vec![0, 1], vec![3]]),
        &blocked,
    );
    assert_eq!(r.status, SqpStatus::InvalidProblem);
    assert!(
        r.message.contains("variable 2 is in no block"),
        "{}",
        r.message
    );
}

/// Two fixed coordinates whose rows the gradient-based scaling treats
/// differently: min 100 x0 + x1² s.t. c0 = 1000 (x0 − 0.001) = 0 (gradient
/// 1000, scaled by 0.1) and c1 = x1 − 0.3 = 0. Closed form: λ0 = −100/1000
/// = −0.1, λ1 = −2·0.3 = −0.6 (L = f + λᵀc). In the problem's units c0 is
/// violated more at x = 0 (1 against 0.3) and c1 has the larger multiplier
/// (0.6 against 0.1); in the scaled units both orders flip (0.1 against
/// 0.3, and 1.0 against 0.6), so the history must convert.
struct ScaledRows;
impl AdProblem for ScaledRows {
    fn name(&self) -> String {
        "scaled_rows".into()
    }
    fn num_variables(&self) -> usize {
        2
    }
    fn num_constraints(&self) -> usize {
        2
    }
    fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l.fill(f64::NEG_INFINITY);
        u.fill(f64::INFINITY);
    }
    fn constraint_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l.fill(0.0);
        u.fill(0.0);
    }
    fn initial_point(&self, x: &mut [f64]) {
        x.fill(0.0);
    }
    fn eval<D: Scalar>(&self, x: &[D], c: &mut [D]) -> D {
        c[0] = (x[0] - D::from(0.001)) * 1000.0;
        c[1] = x[1] - D::from(0.3);
        x[0] * 100.0 + x[1] * x[1]
    }
}

#[test]
fn history_names_the_most_violated_row_and_the_largest_multiplier() {
    for mode in [HessianMode::ExactConvexified, HessianMode::PartitionedBfgs] {
        let r = run(ScaledRows, mode);
        assert_eq!(r.status, SqpStatus::Solved, "{mode:?}: {}", r.message);
        assert!((r.lambda[0] + 0.1).abs() < 1e-8, "{mode:?}: {:?}", r.lambda);
        assert!((r.lambda[1] + 0.6).abs() < 1e-8, "{mode:?}: {:?}", r.lambda);
        let first = &r.history[0];
        assert_eq!(first.max_violation_constraint, "c[0]", "{mode:?}");
        assert_eq!(first.max_multiplier_constraint, "", "{mode:?}");
        assert_eq!(first.max_multiplier, 0.0, "{mode:?}");
        let last = r.history.last().unwrap();
        assert_eq!(last.max_multiplier_constraint, "c[1]", "{mode:?}");
        assert!(
            (last.max_multiplier - 0.6).abs() < 1e-8,
            "{mode:?}: {}",
            last.max_multiplier
        );
        // The CSV carries them as its last three columns.
        let dir =
            std::env::temp_dir().join(format!("leap_sqp_rows_{}_{mode:?}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("history.csv");
        r.write_history_csv(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        assert_eq!(
            &header[header.len() - 3..],
            [
                "max_violation_constraint",
                "max_multiplier_constraint",
                "max_multiplier"
            ]
        );
        let row: Vec<&str> = text.lines().last().unwrap().split(',').collect();
        assert_eq!(row[row.len() - 2], "c[1]");
        assert!((row[row.len() - 1].parse::<f64>().unwrap() - 0.6).abs() < 1e-8);
        std::fs::remove_dir_all(&dir).ok();
    }
}

/// A constraint name holding a comma or a quote stays one CSV field
/// (RFC 4180: quoted, quotes doubled).
#[test]
fn history_csv_quotes_names_with_commas() {
    let rec = leap::sqp::IterationRecord {
        max_violation_constraint: "defect of interval 1, \"q\"".into(),
        max_multiplier_constraint: "c[3]".into(),
        max_multiplier: 2.5,
        ..Default::default()
    };
    let dir = std::env::temp_dir().join(format!("leap_sqp_quote_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("history.csv");
    leap::sqp::write_history_csv(&[rec], &path).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let row = text.lines().nth(1).unwrap();
    assert!(
        row.ends_with(",\"defect of interval 1, \"\"q\"\"\",c[3],2.5e0"),
        "{row}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// The paper's criterion (|Δf| < 1e-6 (1 + |f|) over a full step with the
/// constraints within 1e-3) stops a solve early, but only at an iterate
/// whose scaled dual infeasibility is within
/// `paper_criterion_dual_infeasibility`: with that bound below the
/// convergence tolerance the solve runs to the regular optimality test,
/// iteration for iteration as without the paper's criterion.
#[test]
fn paper_criterion_stops_only_where_the_multipliers_balance_the_gradient() {
    for mode in [HessianMode::ExactConvexified, HessianMode::PartitionedBfgs] {
        let settings = |paper: bool, dual: f64| SqpSettings {
            hessian: mode,
            paper_criterion: paper,
            paper_criterion_dual_infeasibility: dual,
            ..Default::default()
        };
        let plain = solve(&mut AdNlp::new(hs071()), &settings(false, 1.0));
        assert_eq!(
            plain.status,
            SqpStatus::Solved,
            "{mode:?}: {}",
            plain.message
        );
        // Unbounded, the criterion stops hs071 early (exact Hessian: 5
        // iterations against 7; BFGS: 7 against 8) ...
        let early = solve(&mut AdNlp::new(hs071()), &settings(true, f64::INFINITY));
        assert!(
            early.message.contains("Porsa"),
            "{mode:?}: {}",
            early.message
        );
        assert!(early.iterations < plain.iterations, "{mode:?}");
        assert!((early.objective - 17.0140173).abs() < 1e-3 * 17.0);
        // ... bounded, it stops only within the bound ...
        for dual in [1.0, 1e-3] {
            let r = solve(&mut AdNlp::new(hs071()), &settings(true, dual));
            let last = r.history.last().unwrap();
            assert!(r.status.success(), "{mode:?}: {}", r.message);
            assert!(r.iterations <= plain.iterations);
            if r.message.contains("Porsa") {
                assert!(
                    last.inf_du <= dual,
                    "{mode:?}: inf_du {} > {dual}",
                    last.inf_du
                );
                assert!((r.objective - 17.0140173).abs() < 1e-3 * 17.0);
            }
        }
        // ... and bounded below the convergence tolerance it never does.
        let guarded = solve(&mut AdNlp::new(hs071()), &settings(true, 1e-9));
        assert_eq!(guarded.iterations, plain.iterations, "{mode:?}");
        assert_eq!(guarded.message, plain.message, "{mode:?}");
    }
}

/// min −1e-8·x over 0 ≤ x ≤ 1000 from x = 0: a slope so gentle that the
/// first steps, which the step bound holds (Δ = 10, then 40; without
/// curvature the QP's own step is far longer), change f by less than
/// 1e-6 (1 + |f|). The paper's criterion must not read that as
/// convergence: the solve goes on to the bound, x = 1000.
struct GentleSlope;
impl AdProblem for GentleSlope {
    fn name(&self) -> String {
        "gentle slope".into()
    }
    fn num_variables(&self) -> usize {
        1
    }
    fn num_constraints(&self) -> usize {
        0
    }
    fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l[0] = 0.0;
        u[0] = 1000.0;
    }
    fn constraint_bounds(&self, _l: &mut [f64], _u: &mut [f64]) {}
    fn initial_point(&self, x: &mut [f64]) {
        x[0] = 0.0;
    }
    fn eval<D: Scalar>(&self, x: &[D], _c: &mut [D]) -> D {
        x[0] * -1e-8
    }
}

#[test]
fn paper_criterion_ignores_steps_the_step_bound_cut_short() {
    let settings = SqpSettings {
        hessian: HessianMode::ExactConvexified,
        eigenvalue_floor: 1e-14,
        scale_variables_using_bounds: false,
        paper_criterion: true,
        ..Default::default()
    };
    let r = solve(&mut AdNlp::new(GentleSlope), &settings);
    assert!(r.status.success(), "{}", r.message);
    // The first steps reached the bound.
    let first = &r.history[0];
    assert!(
        first.step_norm >= 0.999 * first.step_bound,
        "step {} bound {}",
        first.step_norm,
        first.step_bound
    );
    assert!(
        (r.x[0] - 1000.0).abs() < 1e-3,
        "x = {} ({})",
        r.x[0],
        r.message
    );
}

/// The stall test ends a solve whose violation no longer falls: on
/// `infeasible_asymptotic` (exp(−x1) = −1: the violation 1 + exp(−x1)
/// creeps towards 1 from the second iteration on) a three-iteration window
/// stops it as restoration failed, with the window in the message and
/// before the infeasibility test would have; with the test off it ends as
/// infeasible, as with the default 50.
#[test]
fn stalled_solves_end_as_restoration_failed() {
    let p = leap::testset::by_name("infeasible_asymptotic").expect("in the test set");
    let mut ended = Vec::new();
    for stall_iterations in [0, 3, 50] {
        let settings = SqpSettings {
            hessian: HessianMode::ExactConvexified,
            stall_iterations,
            ..Default::default()
        };
        let r = solve(&mut AdNlp::new(p.clone()), &settings);
        ended.push(r.iterations);
        if stall_iterations == 3 {
            assert_eq!(r.status, SqpStatus::RestorationFailed, "{}", r.message);
            assert!(
                r.message.contains("no progress in 3 iterations"),
                "{}",
                r.message
            );
            // The window: the last four iterates, none 10% below the first.
            let h = &r.history[r.history.len() - 4..];
            assert!(h
                .iter()
                .all(|k| k.inf_pr > 0.9 * h[0].inf_pr && k.inf_pr > 1e-3));
            assert!(
                (r.constraint_violation - 1.0).abs() < 1e-3,
                "{}",
                r.constraint_violation
            );
        } else {
            assert_eq!(
                r.status,
                SqpStatus::Infeasible,
                "{stall_iterations}: {}",
                r.message
            );
        }
    }
    assert!(ended[1] < ended[0], "{ended:?}");
    assert_eq!(ended[0], ended[2]);
}

/// The interrupt flag (Ctrl-C in `leap solve`): unset, the solve is the
/// same to the bit; set, it stops at the next iteration with status
/// user-requested stop and returns that iterate (here the start).
#[test]
fn an_interrupt_stops_the_solve_at_its_next_iteration() {
    use std::sync::atomic::AtomicBool;
    use std::sync::Arc;
    let base = run(hs071(), HessianMode::PartitionedBfgs);
    let flag = Arc::new(AtomicBool::new(false));
    let settings = |flag: &Arc<AtomicBool>| SqpSettings {
        hessian: HessianMode::PartitionedBfgs,
        interrupt: Some(flag.clone()),
        ..Default::default()
    };
    let r = solve(&mut AdNlp::new(hs071()), &settings(&flag));
    assert_eq!(r.status, SqpStatus::Solved);
    assert!(r.x == base.x && r.iterations == base.iterations);
    flag.store(true, std::sync::atomic::Ordering::Relaxed);
    let r = solve(&mut AdNlp::new(hs071()), &settings(&flag));
    assert_eq!(r.status, SqpStatus::UserRequestedStop, "{}", r.message);
    assert_eq!(r.iterations, 0);
    let mut x0 = vec![0.0; r.x.len()];
    leap::nlp::Nlp::initial_point(&AdNlp::new(hs071()), &mut x0);
    assert_eq!(r.x, x0);
    assert!(!r.status.success());
}

/// The Maratos example (Nocedal & Wright 2006, Example 15.4): min
/// 2(x₁² + x₂² − 1) − x₁ on the unit circle, f* = −1 at (1, 0). From a
/// point on the circle the full SQP step leaves it and raises both f and
/// the violation, so the step is rejected and a second-order correction
/// taken.
struct Maratos;
impl AdProblem for Maratos {
    fn name(&self) -> String {
        "maratos".into()
    }
    fn num_variables(&self) -> usize {
        2
    }
    fn num_constraints(&self) -> usize {
        1
    }
    fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l.fill(f64::NEG_INFINITY);
        u.fill(f64::INFINITY);
    }
    fn constraint_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l[0] = 0.0;
        u[0] = 0.0;
    }
    fn initial_point(&self, x: &mut [f64]) {
        let t: f64 = 0.3;
        x.copy_from_slice(&[t.cos(), t.sin()]);
    }
    fn eval<D: Scalar>(&self, x: &[D], c: &mut [D]) -> D {
        let r = x[0] * x[0] + x[1] * x[1] - D::from(1.0);
        c[0] = r;
        r * 2.0 - x[0]
    }
}

/// The history's step norm is the step taken: after a second-order
/// correction the distance between the iterates, not the rejected QP
/// step's length (checked against the iterates of the same solve stopped
/// one iteration apart, in unscaled variables; `best_iterate_violation` 0
/// returns the last iterate even where an earlier one, the start on the
/// circle, was exactly feasible).
#[test]
fn step_norm_after_a_second_order_correction_is_the_step_taken() {
    let settings = |max_iterations| SqpSettings {
        hessian: HessianMode::ExactConvexified,
        max_iterations,
        nlp_scaling: false,
        scale_variables_using_bounds: false,
        best_iterate_violation: 0.0,
        ..Default::default()
    };
    let full = solve(&mut AdNlp::new(Maratos), &settings(100));
    assert_eq!(full.status, SqpStatus::Solved, "{}", full.message);
    assert!((full.objective + 1.0).abs() < 1e-8, "{}", full.objective);
    let soc: Vec<usize> = full
        .history
        .iter()
        .filter(|r| r.qp_mode == "soc")
        .map(|r| r.iter)
        .collect();
    assert!(!soc.is_empty(), "no second-order correction taken");
    // Record k is iterate k and the step from it.
    for &k in &soc {
        let before = solve(&mut AdNlp::new(Maratos), &settings(k)).x;
        let after = solve(&mut AdNlp::new(Maratos), &settings(k + 1)).x;
        let moved = before
            .iter()
            .zip(&after)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let rec = full.history.iter().find(|r| r.iter == k).unwrap();
        assert!(
            (rec.step_norm - moved).abs() <= 1e-12 * moved.max(1.0),
            "iteration {k}: step_norm {} but the iterate moved {moved}",
            rec.step_norm
        );
    }
}

/// min (x − 2)² from x = 0, the objective not finite anywhere but at the
/// start: every trial point of the line search fails.
struct Cliff;
impl AdProblem for Cliff {
    fn name(&self) -> String {
        "cliff".into()
    }
    fn num_variables(&self) -> usize {
        1
    }
    fn num_constraints(&self) -> usize {
        1
    }
    fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l.fill(f64::NEG_INFINITY);
        u.fill(f64::INFINITY);
    }
    fn constraint_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l[0] = -10.0;
        u[0] = 10.0;
    }
    fn initial_point(&self, x: &mut [f64]) {
        x[0] = 0.0;
    }
    fn eval<D: Scalar>(&self, x: &[D], c: &mut [D]) -> D {
        c[0] = x[0];
        let f = (x[0] - D::from(2.0)) * (x[0] - D::from(2.0));
        if x[0].re() == 0.0 {
            f
        } else {
            f * f64::NAN
        }
    }
}

/// A failed line search takes no step: its record's step norm and step
/// length α are 0, and the solve returns the start.
#[test]
fn a_failed_line_search_records_no_step() {
    let settings = SqpSettings {
        hessian: HessianMode::ExactConvexified,
        ..Default::default()
    };
    let r = solve(&mut AdNlp::new(Cliff), &settings);
    assert_eq!(r.status, SqpStatus::LineSearchFailed, "{}", r.message);
    assert_eq!(r.x, vec![0.0]);
    let last = r.history.last().expect("a record of the failed iteration");
    assert!(last.ls_trials > 1, "{last:?}");
    assert_eq!((last.step_norm, last.alpha), (0.0, 0.0), "{last:?}");
}
