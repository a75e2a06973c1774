//! Published nonlinear-programming test problems with known solutions, for
//! testing optimizers against the [`AdProblem`] interface.
//!
//! # Contents
//!
//! * [`hock_schittkowski`]: 67 problems of W. Hock and K. Schittkowski,
//!   *Test Examples for Nonlinear Programming Codes*, Lecture Notes in
//!   Economics and Mathematical Systems 187, Springer, Berlin 1981 (the
//!   "HS" collection), each with its number, bounds, the book's starting
//!   point x⁰, the book's optimal value f* and, where the book gives one,
//!   its optimal point x*.
//! * [`infeasible_problems`] and [`unbounded_problems`]: small problems
//!   constructed here whose status (no feasible point; objective unbounded
//!   below on the feasible set) is known by inspection.
//!
//! # Conventions
//!
//! The problems are stated as `x_L ≤ x ≤ x_U`, `c_L ≤ c(x) ≤ c_U` (see
//! [`crate::nlp`]); absent sides are ±∞, equalities have `c_L = c_U`. The
//! book's inequalities g(x) ≥ 0 and equalities h(x) = 0 are kept as rows
//! of `c`, in the book's order and mostly in the book's form (a constant
//! is sometimes moved into the bound); the variable bounds are bounds.
//! Objectives are the book's (not the ½-scaled least-squares forms some
//! libraries use). HS118 writes each of the book's 12 pairs of one-sided
//! rows as one two-sided row (m = 17 instead of 29).
//!
//! # Sources
//!
//! The book itself was not at hand; every definition and value was
//! transcribed from public implementations of it and cross-checked between
//! at least two of them, and every x*/f* pair is checked against itself in
//! the unit tests below (f(x*) = f*, x* feasible):
//!
//! * the CUTEst SIF files `HSnn.SIF` (A. R. Conn, Ph. Toint and others; as
//!   distributed with S2MPJ, github.com/GrattonToint/S2MPJ, `sif/`), whose
//!   `*LO SOLTN` lines give f*;
//! * JuliaSmoothOptimizers/OptimizationProblems.jl, `src/ADNLPProblems/hsNN.jl`
//!   (definitions and starting points; several objectives there are scaled
//!   by ½, which the book does not do);
//! * the CasADi test suite, `test/python/hock_schittkowski/hsNNN.py`
//!   (converted from the APMonitor models; `f_opt`, `x_opt`);
//! * TOMLAB's `chs_prob.m` (K. Holmström; `x_opt`, `f_opt` with comments on
//!   the book's errata), the OPTI toolbox's `nlp_HS.m` (J. Currie) and
//!   roboptim-shared-tests `schittkowski/problem_NN.cc` (`x`, `fx`, and
//!   f(x⁰) as `f0`, which confirms x⁰ and the objective).
//!
//! Where these disagree, the value given by the majority and consistent
//! with the other data (feasibility of x*, f(x*) = f*) was taken, and the
//! disagreement is recorded in the problem's `notes`. Closed forms given by
//! the book (√3, 9 − 2.875√7, fractions, ...) are evaluated in f64; decimal
//! values are copied with all published digits. When the published x* is
//! rounded, `x_star_precision` gives its relative precision and the data
//! check widens its tolerances by the first-order effect of that rounding.

use crate::nlp::AdProblem;
use crate::scalar::Scalar;
use std::f64::consts::{PI, SQRT_2};

const INF: f64 = f64::INFINITY;

/// What is known about a problem's solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// A minimum with value `f_star` (at `x_star` when given) is published.
    Optimal,
    /// No point satisfies the bounds and constraints.
    Infeasible,
    /// The objective is unbounded below on the feasible set.
    Unbounded,
}

/// Properties an optimizer test may want to select or skip problems by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Feature {
    /// The problem is not a convex program (nonconvex objective, nonlinear
    /// equality, or a feasible set that is not convex).
    Nonconvex,
    /// A constraint qualification fails at x* (see the notes: LICQ only,
    /// or also MFCQ so that no KKT multipliers exist).
    Degenerate,
    /// The equality constraints are linearly dependent (redundant).
    RankDeficient,
    /// Other local minima exist; a local method from x⁰ may stop at one.
    LocalMinima,
    /// The minimizer is not unique (a set or several isolated points).
    NonuniqueMinimizer,
    /// A feasible point with a lower objective than the published f* is
    /// known: the book's value is a local, not the global, minimum.
    NotGlobal,
}

/// Which evaluation routine a problem uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Id {
    Hs(u32),
    Infeasible(u32),
    Unbounded(u32),
}

/// A test problem with its published solution, usable through
/// [`crate::nlp::AdNlp`].
#[derive(Debug, Clone)]
pub struct HsProblem {
    /// "hs071", "infeasible_linear", ...
    pub name: &'static str,
    /// The number in Hock & Schittkowski (None for the constructed ones).
    pub number: Option<u32>,
    pub n: usize,
    pub m: usize,
    pub x_lower: Vec<f64>,
    pub x_upper: Vec<f64>,
    pub c_lower: Vec<f64>,
    pub c_upper: Vec<f64>,
    /// The book's starting point (it may violate bounds or constraints).
    pub x0: Vec<f64>,
    pub status: Status,
    /// The published optimal value (NaN unless `status` is Optimal).
    pub f_star: f64,
    /// The published optimal point, if the book gives one.
    pub x_star: Option<Vec<f64>>,
    /// Relative precision of the published `x_star` (0 when it is exact or
    /// a closed form, about 10⁻⁶ for seven significant digits).
    pub x_star_precision: f64,
    pub features: &'static [Feature],
    /// Where the data were taken from, beyond the module-level sources.
    pub source: &'static str,
    /// Errata, disagreements between sources, other minima, difficulty.
    pub notes: &'static str,
    id: Id,
}

impl HsProblem {
    fn new(name: &'static str, id: Id, x0: Vec<f64>) -> Self {
        let n = x0.len();
        let number = match id {
            Id::Hs(k) => Some(k),
            _ => None,
        };
        HsProblem {
            name,
            number,
            n,
            m: 0,
            x_lower: vec![-INF; n],
            x_upper: vec![INF; n],
            c_lower: Vec::new(),
            c_upper: Vec::new(),
            x0,
            status: Status::Optimal,
            f_star: f64::NAN,
            x_star: None,
            x_star_precision: 0.0,
            features: &[],
            source: "",
            notes: "",
            id,
        }
    }

    fn hs(number: u32, name: &'static str, x0: Vec<f64>) -> Self {
        Self::new(name, Id::Hs(number), x0)
    }

    fn lower(mut self, l: Vec<f64>) -> Self {
        assert_eq!(l.len(), self.n, "{}: lower bounds", self.name);
        self.x_lower = l;
        self
    }

    fn upper(mut self, u: Vec<f64>) -> Self {
        assert_eq!(u.len(), self.n, "{}: upper bounds", self.name);
        self.x_upper = u;
        self
    }

    /// Append a constraint row `lo ≤ c_i(x) ≤ hi`.
    fn row(mut self, lo: f64, hi: f64) -> Self {
        self.c_lower.push(lo);
        self.c_upper.push(hi);
        self.m += 1;
        self
    }

    /// Append `k` rows c_i(x) ≥ 0.
    fn ge0(mut self, k: usize) -> Self {
        for _ in 0..k {
            self = self.row(0.0, INF);
        }
        self
    }

    /// Append `k` rows c_i(x) = 0.
    fn eq0(mut self, k: usize) -> Self {
        for _ in 0..k {
            self = self.row(0.0, 0.0);
        }
        self
    }

    fn optimum(mut self, f_star: f64, x_star: Option<Vec<f64>>, precision: f64) -> Self {
        if let Some(x) = &x_star {
            assert_eq!(x.len(), self.n, "{}: x*", self.name);
        }
        self.status = Status::Optimal;
        self.f_star = f_star;
        self.x_star = x_star;
        self.x_star_precision = precision;
        self
    }

    fn status(mut self, status: Status) -> Self {
        self.status = status;
        self
    }

    fn features(mut self, features: &'static [Feature]) -> Self {
        self.features = features;
        self
    }

    fn source(mut self, source: &'static str) -> Self {
        self.source = source;
        self
    }

    fn notes(mut self, notes: &'static str) -> Self {
        self.notes = notes;
        self
    }

    /// Whether the problem has `feature`.
    /// The value a solver is judged against: the book's f*, except where a
    /// better feasible point has been published since. hs106 is problem
    /// g10 of the CEC 2006 constrained set (Liang et al. 2006, same
    /// constants), best known f = 7049.24802052867 (the book: 7049.330923).
    pub fn reference_optimum(&self) -> f64 {
        match self.name {
            "hs106" => 7049.24802052867,
            _ => self.f_star,
        }
    }

    pub fn has(&self, feature: Feature) -> bool {
        self.features.contains(&feature)
    }

    /// Whether some constraint row is an equality.
    pub fn has_equalities(&self) -> bool {
        self.c_lower.iter().zip(&self.c_upper).any(|(l, u)| l == u)
    }

    /// Whether some constraint row is an inequality (one- or two-sided).
    pub fn has_inequalities(&self) -> bool {
        self.c_lower.iter().zip(&self.c_upper).any(|(l, u)| l != u)
    }

    /// Whether some variable has a finite bound.
    pub fn has_bounds(&self) -> bool {
        self.x_lower
            .iter()
            .chain(&self.x_upper)
            .any(|b| b.is_finite())
    }
}

impl AdProblem for HsProblem {
    fn name(&self) -> String {
        self.name.to_string()
    }
    fn num_variables(&self) -> usize {
        self.n
    }
    fn num_constraints(&self) -> usize {
        self.m
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&self.x_lower);
        upper.copy_from_slice(&self.x_upper);
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&self.c_lower);
        upper.copy_from_slice(&self.c_upper);
    }
    fn initial_point(&self, x: &mut [f64]) {
        x.copy_from_slice(&self.x0);
    }
    fn eval<D: Scalar>(&self, x: &[D], c: &mut [D]) -> D {
        match self.id {
            Id::Hs(k) => eval_hs(k, x, c),
            Id::Infeasible(k) => eval_infeasible(k, x, c),
            Id::Unbounded(k) => eval_unbounded(k, x, c),
        }
    }
}

use Feature::*;

/// The Hock–Schittkowski problems, in the book's order.
pub fn hock_schittkowski() -> Vec<HsProblem> {
    let s3 = 3f64.sqrt();
    let s7 = 7f64.sqrt();
    vec![
        // ---- unconstrained / bound constrained ----
        HsProblem::hs(1, "hs001", vec![-2.0, 1.0])
            .lower(vec![-INF, -1.5])
            .optimum(0.0, Some(vec![1.0, 1.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS1, OptimizationProblems.jl hs1, roboptim problem_1 (f(x0) = 909)")
            .notes("Rosenbrock's banana with the inactive bound x2 >= -1.5."),
        HsProblem::hs(2, "hs002", vec![-2.0, 1.0])
            .lower(vec![-INF, 1.5])
            .optimum(0.0504261879, Some(hs002_x_star()), 0.0)
            .features(&[Nonconvex, LocalMinima])
            .source("SIF HS2 (lists both 0.050426 and 4.941229), CasADi hs002, OPTI nlp_HS, roboptim problem_2")
            .notes(
                "Rosenbrock with the active bound x2 >= 1.5. The book's x1* = 2a cos(arccos(1/b)/3), \
                 a = (598/1200)^(1/2), b = 400 a^3 (= 1.224370749). A local minimum f = 4.9412294 at \
                 (-1.2210, 1.5) attracts local methods started from x0.",
            ),
        HsProblem::hs(3, "hs003", vec![10.0, 1.0])
            .lower(vec![-INF, 0.0])
            .optimum(0.0, Some(vec![0.0, 0.0]), 0.0)
            .source("SIF HS3, OptimizationProblems.jl hs3, roboptim problem_3 (f(x0) = 1.00081)")
            .notes("Convex but badly scaled: the quadratic term has weight 1e-5."),
        HsProblem::hs(4, "hs004", vec![1.125, 0.125])
            .lower(vec![1.0, 0.0])
            .optimum(8.0 / 3.0, Some(vec![1.0, 0.0]), 0.0)
            .source("SIF HS4 (2.66666), CasADi hs004, roboptim problem_4 (f(x0) = 3.323568)")
            .notes("Solution at the vertex of the bounds."),
        HsProblem::hs(5, "hs005", vec![0.0, 0.0])
            .lower(vec![-1.5, -3.0])
            .upper(vec![4.0, 3.0])
            .optimum(-s3 / 2.0 - PI / 3.0, Some(vec![0.5 - PI / 3.0, -0.5 - PI / 3.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS5 (-1.9132229), CasADi hs005, roboptim problem_5")
            .notes("f* = -sqrt(3)/2 - pi/3, interior minimum (bounds inactive)."),
        HsProblem::hs(25, "hs025", vec![100.0, 12.5, 3.0])
            .lower(vec![0.1, 0.0, 0.0])
            .upper(vec![100.0, 25.6, 5.0])
            .optimum(0.0, Some(vec![50.0, 25.0, 1.5]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS25, OptimizationProblems.jl hs25, CasADi hs025, roboptim problem_25 (f(x0) = 32.835)")
            .notes(
                "Zero-residual data fit with 99 exponential residuals f_i = -i/100 + \
                 exp(-(u_i - x2)^x3 / x1), u_i = 25 + (-50 ln(i/100))^(2/3); nearly flat far from x*.",
            ),
        HsProblem::hs(38, "hs038", vec![-3.0, -1.0, -3.0, -1.0])
            .lower(vec![-10.0; 4])
            .upper(vec![10.0; 4])
            .optimum(0.0, Some(vec![1.0; 4]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS38, OptimizationProblems.jl hs38 (f(x0) = 19192), roboptim problem_38")
            .notes("Colville's (Wood's) function with inactive bounds."),
        HsProblem::hs(45, "hs045", vec![2.0; 5])
            .lower(vec![0.0; 5])
            .upper(vec![1.0, 2.0, 3.0, 4.0, 5.0])
            .optimum(1.0, Some(vec![1.0, 2.0, 3.0, 4.0, 5.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS45, OptimizationProblems.jl hs45, roboptim problem_45 (f(x0) = 26/15)")
            .notes("All five upper bounds active at x*. CasADi's hs045 has x0 = 0 (not the book's 2)."),
        // ---- equality constrained ----
        HsProblem::hs(6, "hs006", vec![-1.2, 1.0])
            .eq0(1)
            .optimum(0.0, Some(vec![1.0, 1.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS6, CasADi hs006, roboptim problem_6 (f(x0) = 4.84)")
            .notes("OptimizationProblems.jl scales the objective by 1/2; the book does not."),
        HsProblem::hs(7, "hs007", vec![2.0, 2.0])
            .eq0(1)
            .optimum(-s3, Some(vec![0.0, s3]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS7 (-1.73205), CasADi hs007, roboptim problem_7 (f(x0) = ln 5 - 2)"),
        HsProblem::hs(8, "hs008", vec![2.0, 1.0])
            .eq0(2)
            .optimum(-1.0, Some(hs008_x_star()), 0.0)
            .features(&[Nonconvex, NonuniqueMinimizer])
            .source("SIF HS8, CasADi hs008, TOMLAB chs_prob (four solutions), OPTI nlp_HS")
            .notes(
                "Constant objective: a system of two equations. Four solutions (+-a, +-9/a), \
                 (+-b, +-9/b), a,b = sqrt((25 +- sqrt(301))/2); x* is (a, 9/a).",
            ),
        HsProblem::hs(9, "hs009", vec![0.0, 0.0])
            .eq0(1)
            .optimum(-0.5, Some(vec![-3.0, -4.0]), 0.0)
            .features(&[Nonconvex, NonuniqueMinimizer, LocalMinima])
            .source("SIF HS9, CasADi hs009, roboptim problem_9 (k = 0)")
            .notes("Minimizers (12k - 3, 16k - 4) for every integer k; x* is k = 0."),
        HsProblem::hs(26, "hs026", vec![-2.6, 2.0, 2.0])
            .eq0(1)
            .optimum(0.0, Some(vec![1.0, 1.0, 1.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS26, OptimizationProblems.jl hs26, roboptim problem_26 (f(x0) = 21.16)")
            .notes(
                "The Hessian is singular at x* (quartic term); roboptim notes a second stationary \
                 point (a, a, a).",
            ),
        HsProblem::hs(27, "hs027", vec![2.0, 2.0, 2.0])
            .row(-1.0, -1.0)
            .optimum(0.04, Some(vec![-1.0, 1.0, 0.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS27, CasADi hs027, OptimizationProblems.jl hs27, roboptim problem_27 (f(x0) = 4.01)"),
        HsProblem::hs(28, "hs028", vec![-4.0, 1.0, 1.0])
            .row(1.0, 1.0)
            .optimum(0.0, Some(vec![0.5, -0.5, 0.5]), 0.0)
            .source("SIF HS28, CasADi hs028, roboptim problem_28 (f(x0) = 13)")
            .notes("Convex quadratic with one linear equality; the objective is only positive semidefinite."),
        HsProblem::hs(39, "hs039", vec![2.0; 4])
            .eq0(2)
            .optimum(-1.0, Some(vec![1.0, 1.0, 0.0, 0.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS39, CasADi hs039, roboptim problem_39 (f(x0) = -2)"),
        HsProblem::hs(40, "hs040", vec![0.8; 4])
            .eq0(3)
            .optimum(
                -0.25,
                Some(vec![2f64.powf(-1.0 / 3.0), 2f64.powf(-0.5), 2f64.powf(-11.0 / 12.0), 2f64.powf(-0.25)]),
                0.0,
            )
            .features(&[Nonconvex, NonuniqueMinimizer])
            .source("SIF HS40, roboptim problem_40 (f(x0) = -0.4096), TOMLAB chs_prob")
            .notes(
                "x* = (2^(-1/3), 2^(-1/2), 2^(-11/12), 2^(-1/4)); flipping the signs of x3 and x4 \
                 gives another minimizer. CasADi's x_opt has 2^(+1/2) for x2 (a typo).",
            ),
        HsProblem::hs(41, "hs041", vec![2.0; 4])
            .lower(vec![0.0; 4])
            .upper(vec![1.0, 1.0, 1.0, 2.0])
            .eq0(1)
            .optimum(52.0 / 27.0, Some(vec![2.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 2.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS41 (1.925925), OptimizationProblems.jl hs41, roboptim problem_41 (f(x0) = -6)")
            .notes("x0 violates the bounds."),
        HsProblem::hs(42, "hs042", vec![1.0; 4])
            .eq0(2)
            .optimum(28.0 - 10.0 * SQRT_2, Some(vec![2.0, 2.0, 0.6 * SQRT_2, 0.8 * SQRT_2]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS42 (13.857864), roboptim problem_42 (f(x0) = 14), OPTI nlp_HS")
            .notes("TOMLAB records the book's misprint 6 sqrt(2) for x3* = 0.6 sqrt(2)."),
        HsProblem::hs(46, "hs046", vec![0.5 * SQRT_2, 1.75, 0.5, 2.0, 2.0])
            .eq0(2)
            .optimum(0.0, Some(vec![1.0; 5]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS46, OptimizationProblems.jl hs46, CasADi hs046")
            .notes("Degenerate minimum: the objective's Hessian is singular at x* (quartic and sixth powers)."),
        HsProblem::hs(47, "hs047", vec![2.0, SQRT_2, -1.0, 2.0 - SQRT_2, 0.5])
            .eq0(3)
            .optimum(0.0, Some(vec![1.0; 5]), 0.0)
            .features(&[Nonconvex, NotGlobal, LocalMinima])
            .source("SIF HS47, OptimizationProblems.jl hs47 (f(x0) = 20.7380774886), roboptim problem_47")
            .notes(
                "The book's f* = 0 at (1,...,1) is a local minimum only: TOMLAB (glcCluster) found the \
                 feasible point (0.67700461670128, 0.726089640962586, 1.215491109042481, 1.75132899519799, \
                 1.477094801614824) with f = -0.0267141826940 (checked in the tests). OPTI's x0 has the \
                 misprint -2 sqrt(2) for 2 - sqrt(2).",
            ),
        HsProblem::hs(48, "hs048", vec![3.0, 5.0, -3.0, 2.0, -2.0])
            .row(5.0, 5.0)
            .row(-3.0, -3.0)
            .optimum(0.0, Some(vec![1.0; 5]), 0.0)
            .source("SIF HS48, CasADi hs048, roboptim problem_48 (f(x0) = 84)")
            .notes("Convex quadratic, linear equalities."),
        HsProblem::hs(49, "hs049", vec![10.0, 7.0, 2.0, -3.0, 0.8])
            .row(7.0, 7.0)
            .row(6.0, 6.0)
            .optimum(0.0, Some(vec![1.0; 5]), 0.0)
            .source("SIF HS49, CasADi hs049, roboptim problem_49 (f(x0) = 266.000064)")
            .notes("Convex, linear equalities; singular Hessian at x* (quartic and sixth powers): slow convergence."),
        HsProblem::hs(50, "hs050", vec![35.0, -31.0, 11.0, 5.0, -5.0])
            .row(6.0, 6.0)
            .row(6.0, 6.0)
            .row(6.0, 6.0)
            .optimum(0.0, Some(vec![1.0; 5]), 0.0)
            .source("SIF HS50, CasADi hs050, OptimizationProblems.jl hs50 (f(x0) = 7516)")
            .notes("Convex, linear equalities. roboptim's f0 = 6256 disagrees with f(x0) = 7516."),
        HsProblem::hs(51, "hs051", vec![2.5, 0.5, 2.0, -1.0, 0.5])
            .row(4.0, 4.0)
            .eq0(2)
            .optimum(0.0, Some(vec![1.0; 5]), 0.0)
            .source("SIF HS51, CasADi hs051, roboptim problem_51 (f(x0) = 8.5)")
            .notes("Convex quadratic, linear equalities; x0 is feasible."),
        HsProblem::hs(52, "hs052", vec![2.0; 5])
            .eq0(3)
            .optimum(
                1859.0 / 349.0,
                Some(vec![-33.0 / 349.0, 11.0 / 349.0, 180.0 / 349.0, -158.0 / 349.0, 11.0 / 349.0]),
                0.0,
            )
            .source("CasADi hs052, roboptim problem_52 (f(x0) = 42), TOMLAB; SIF HS52 has 5.326643")
            .notes("Convex quadratic, linear equalities. f* = 1859/349 = 5.3266476; the SIF's SOLTN 5.326643 is off in the 6th digit."),
        HsProblem::hs(53, "hs053", vec![2.0; 5])
            .lower(vec![-10.0; 5])
            .upper(vec![10.0; 5])
            .eq0(3)
            .optimum(
                176.0 / 43.0,
                Some(vec![-33.0 / 43.0, 11.0 / 43.0, 27.0 / 43.0, -5.0 / 43.0, 11.0 / 43.0]),
                0.0,
            )
            .source("SIF HS53 (4.09302318), CasADi hs053, roboptim problem_53 (f(x0) = 6)")
            .notes("Convex quadratic, linear equalities and inactive bounds."),
        HsProblem::hs(55, "hs055", vec![1.0, 2.0, 0.0, 0.0, 0.0, 2.0])
            .lower(vec![0.0; 6])
            .upper(vec![1.0, INF, INF, 1.0, INF, INF])
            .row(6.0, 6.0)
            .row(3.0, 3.0)
            .row(2.0, 2.0)
            .row(1.0, 1.0)
            .row(2.0, 2.0)
            .row(2.0, 2.0)
            .optimum(19.0 / 3.0, Some(vec![0.0, 4.0 / 3.0, 5.0 / 3.0, 1.0, 2.0 / 3.0, 1.0 / 3.0]), 0.0)
            .features(&[Nonconvex, RankDeficient, Degenerate, LocalMinima])
            .source("OptimizationProblems.jl hs55, CasADi hs055, TOMLAB, roboptim problem_55 (f(x0) = 6); SIF HS55 has 6.66666666")
            .notes(
                "Six linear equalities of rank five: rows 2 + 3 equal rows 4 + 5 + 6 (both sum all x_i = 5), \
                 so LICQ fails everywhere. The feasible set is the segment x = (t, (t + 4)/3, (5 - 4t)/3, \
                 1 - t, (2 - t)/3, (1 + 4t)/3), 0 <= t <= 1, on which f = t/3 + 16/3 + exp(t - t^2): \
                 the book's minimum 19/3 at t = 0 and a local minimum 20/3 at t = 1, which is the SIF's \
                 SOLTN 6.66666666. x0 is infeasible. CasADi changed the bound on x3 (\"revised, not \
                 original\"), not used here.",
            ),
        HsProblem::hs(56, "hs056", hs056_x0())
            .eq0(4)
            .optimum(-3.456, Some(hs056_x_star()), 0.0)
            .features(&[Nonconvex, NonuniqueMinimizer])
            .source("SIF HS56 (-3.456), OptimizationProblems.jl hs56, TOMLAB, roboptim problem_56")
            .notes(
                "x0 = (1, 1, 1, a, a, a, b), a = asin(sqrt(1/4.2)), b = asin(sqrt(5/7.2)); the SIF notes \
                 a misplaced decimal point in the book's printed x0. x* = (2.4, 1.2, 1.2, asin(sqrt(4/7)), \
                 asin(sqrt(2/7)), asin(sqrt(2/7)), pi/2); the angles are determined only up to sign and \
                 multiples of pi. CasADi adds bounds x >= 0, not in the book.",
            ),
        HsProblem::hs(60, "hs060", vec![2.0; 3])
            .lower(vec![-10.0; 3])
            .upper(vec![10.0; 3])
            .row(4.0 + 3.0 * SQRT_2, 4.0 + 3.0 * SQRT_2)
            .optimum(0.03256820025, Some(vec![1.104859024, 1.196674194, 1.535262257]), 1e-8)
            .features(&[Nonconvex])
            .source("CasADi hs060, TOMLAB, roboptim problem_60 (f(x0) = 1); SIF HS60 (0.0325682)"),
        HsProblem::hs(61, "hs061", vec![0.0; 3])
            .row(7.0, 7.0)
            .row(11.0, 11.0)
            .optimum(-143.6461422, Some(vec![5.326770157, -2.118998639, 3.210464239]), 1e-8)
            .features(&[Nonconvex])
            .source("SIF HS61 (-143.646142), CasADi hs061, TOMLAB, roboptim problem_61 (f(x0) = 0)"),
        HsProblem::hs(77, "hs077", vec![2.0; 5])
            .row(2.0 * SQRT_2, 2.0 * SQRT_2)
            .row(8.0 + SQRT_2, 8.0 + SQRT_2)
            .optimum(0.24150513, Some(vec![1.166172, 1.182111, 1.380257, 1.506036, 0.6109203]), 1e-6)
            .features(&[Nonconvex])
            .source("SIF HS77 (0.24150513), TOMLAB, CasADi hs077 (rounded x*)")
            .notes("x* published with 7 digits."),
        HsProblem::hs(78, "hs078", vec![-2.0, 1.5, 2.0, -1.0, -1.0])
            .row(10.0, 10.0)
            .row(0.0, 0.0)
            .row(-1.0, -1.0)
            .optimum(-2.91970041, Some(vec![-1.717142, 1.595708, 1.827248, -0.7636429, -0.7636435]), 1e-6)
            .features(&[Nonconvex])
            .source("SIF HS78 (-2.91970041), TOMLAB, roboptim problem_78 (f(x0) = -6), CasADi hs078")
            .notes(
                "x* published with 7 digits (the same point, differently rounded, is HS80's x*: \
                 (-1.717143, 1.595709, 1.827247, -0.7636413, -0.7636450)). TOMLAB's x5 = -7636435 \
                 lost its decimal point.",
            ),
        HsProblem::hs(79, "hs079", vec![2.0; 5])
            .row(2.0 + 3.0 * SQRT_2, 2.0 + 3.0 * SQRT_2)
            .row(-2.0 + 2.0 * SQRT_2, -2.0 + 2.0 * SQRT_2)
            .row(2.0, 2.0)
            .optimum(0.0787768209, Some(vec![1.191127, 1.362603, 1.472818, 1.635017, 1.679081]), 1e-6)
            .features(&[Nonconvex])
            .source("SIF HS79 (0.0787768), TOMLAB, roboptim problem_79 (f(x0) = 1), CasADi hs079")
            .notes("x* published with 7 digits."),
        // ---- inequality constrained (some with equalities too) ----
        HsProblem::hs(10, "hs010", vec![-10.0, 10.0])
            .ge0(1)
            .optimum(-1.0, Some(vec![0.0, 1.0]), 0.0)
            .source("SIF HS10, CasADi hs010, roboptim problem_10 (f(x0) = -20)")
            .notes("Linear objective over a convex quadratic region (the constraint function is concave)."),
        HsProblem::hs(11, "hs011", vec![4.9, 0.1])
            .ge0(1)
            .optimum(-8.498464223, Some(hs011_x_star()), 0.0)
            .source("SIF HS11 (-8.49846), CasADi hs011, TOMLAB, OPTI nlp_HS, roboptim problem_11 (f(x0) = -24.98)")
            .notes(
                "The book's x* = ((a - 1/a)/sqrt 6, (a^2 - 2 + 1/a^2)/6) needs a = (7.5 sqrt 6 + \
                 sqrt 338.5)^(1/3); TOMLAB, CasADi and OPTI drop the cube root and then report the \
                 formula as wrong. With it, x* = (1.2347728926, 1.5246640931) as TOMLAB's numerical \
                 solution.",
            ),
        HsProblem::hs(12, "hs012", vec![0.0, 0.0])
            .ge0(1)
            .optimum(-30.0, Some(vec![2.0, 3.0]), 0.0)
            .source("SIF HS12, CasADi hs012, roboptim problem_12 (f(x0) = 0)")
            .notes("Convex."),
        HsProblem::hs(13, "hs013", vec![-2.0, -2.0])
            .lower(vec![0.0, 0.0])
            .ge0(1)
            .optimum(1.0, Some(vec![1.0, 0.0]), 0.0)
            .features(&[Nonconvex, Degenerate])
            .source("SIF HS13, CasADi hs013, roboptim problem_13 (f(x0) = 20), TOMLAB")
            .notes(
                "Kuhn & Tucker's example: at x* = (1, 0) the active gradients of (1 - x1)^3 - x2 >= 0 \
                 and x2 >= 0 are (0, -1) and (0, 1), so LICQ and MFCQ fail and no KKT multipliers \
                 exist; methods that need multipliers converge slowly or not at all. x0 violates \
                 the bounds. (OPTI's fmin = 0.9945785 is not the book's value.)",
            ),
        HsProblem::hs(14, "hs014", vec![2.0, 2.0])
            .row(-1.0, -1.0)
            .ge0(1)
            .optimum(9.0 - 2.875 * s7, Some(vec![0.5 * (s7 - 1.0), 0.25 * (s7 + 1.0)]), 0.0)
            .source("CasADi hs014, TOMLAB, OPTI nlp_HS, roboptim problem_14; SIF HS14 has 1.42322464")
            .notes(
                "Convex. f* = 9 - 2.875 sqrt 7 = 1.3934650 = f(x*); the SIF's SOLTN 1.42322464 disagrees. \
                 Rows: x1 - 2x2 = -1, 1 - x1^2/4 - x2^2 >= 0. CasADi adds bounds x >= 0, not in the book.",
            ),
        HsProblem::hs(15, "hs015", vec![-2.0, 1.0])
            .upper(vec![0.5, INF])
            .ge0(2)
            .optimum(306.5, Some(vec![0.5, 2.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS15, CasADi hs015, roboptim problem_15 (f(x0) = 909)"),
        HsProblem::hs(16, "hs016", vec![-2.0, 1.0])
            .lower(vec![-0.5, -INF])
            .upper(vec![0.5, 1.0])
            .ge0(2)
            .optimum(0.25, Some(vec![0.5, 0.25]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS16, OptimizationProblems.jl hs16, CasADi hs016, TOMLAB, roboptim problem_16")
            .notes("x0 violates the bound x1 >= -0.5 (one transcription has x1 >= -2; the SIF and four others have -0.5)."),
        HsProblem::hs(17, "hs017", vec![-2.0, 1.0])
            .lower(vec![-0.5, -INF])
            .upper(vec![0.5, 1.0])
            .ge0(2)
            .optimum(1.0, Some(vec![0.0, 0.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS17, OptimizationProblems.jl hs17, CasADi hs017, roboptim problem_17")
            .notes("x0 violates the bound x1 >= -0.5."),
        HsProblem::hs(18, "hs018", vec![2.0, 2.0])
            .lower(vec![2.0, 0.0])
            .upper(vec![50.0, 50.0])
            .ge0(2)
            .optimum(5.0, Some(vec![250f64.sqrt(), 2.5f64.sqrt()]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS18, CasADi hs018, roboptim problem_18 (f(x0) = 4.04)"),
        HsProblem::hs(19, "hs019", vec![20.1, 5.84])
            .lower(vec![13.0, 0.0])
            .upper(vec![100.0, 100.0])
            .ge0(2)
            .optimum(-6961.81381, Some(vec![14.095, 0.84296079]), 1e-8)
            .features(&[Nonconvex])
            .source("SIF HS19, CasADi hs019, ROL HS_019, roboptim problem_19 (f(x0) = -1808.858296)")
            .notes(
                "Both constraints active; exactly x1 = 14.095, x2 = 5 - sqrt(17.280975). The same problem \
                 is CEC 2006 g06 (-6961.81387558). x0 is infeasible.",
            ),
        HsProblem::hs(20, "hs020", vec![-2.0, 1.0])
            .lower(vec![-0.5, -INF])
            .upper(vec![0.5, INF])
            .ge0(3)
            .optimum(81.5 - 25.0 * s3, Some(vec![0.5, 0.5 * s3]), 0.0)
            .features(&[Nonconvex, LocalMinima])
            .source("CasADi hs020 (comment), TOMLAB, OPTI nlp_HS; SIF HS20 has 40.199")
            .notes(
                "The book's f* = 81.5 - 25 sqrt 3 = 38.19873 at (0.5, sqrt(3)/2). The SIF's SOLTN 40.199 \
                 is the local minimum (-0.5, sqrt(3)/2), which local methods from x0 tend to find. \
                 roboptim's x2* = 5 sqrt 3 is a misprint.",
            ),
        HsProblem::hs(21, "hs021", vec![-1.0, -1.0])
            .lower(vec![2.0, -50.0])
            .upper(vec![50.0, 50.0])
            .row(10.0, INF)
            .optimum(-99.96, Some(vec![2.0, 0.0]), 0.0)
            .source("SIF HS21, OptimizationProblems.jl hs21, roboptim problem_21 (f(x0) = -98.99)")
            .notes("Convex QP; x0 violates the bound x1 >= 2. CasADi's x0 = (-1, 1) is not the book's."),
        HsProblem::hs(22, "hs022", vec![2.0, 2.0])
            .ge0(2)
            .optimum(1.0, Some(vec![1.0, 1.0]), 0.0)
            .source("SIF HS22, CasADi hs022, roboptim problem_22 (f(x0) = 1)")
            .notes("Convex."),
        HsProblem::hs(23, "hs023", vec![3.0, 1.0])
            .lower(vec![-50.0, -50.0])
            .upper(vec![50.0, 50.0])
            .ge0(5)
            .optimum(2.0, Some(vec![1.0, 1.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS23, CasADi hs023, roboptim problem_23 (f(x0) = 10)"),
        HsProblem::hs(24, "hs024", vec![1.0, 0.5])
            .lower(vec![0.0, 0.0])
            .ge0(3)
            .optimum(-1.0, Some(vec![3.0, s3]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS24, CasADi hs024, roboptim problem_24 (f(x0) = -0.013364589564574673)")
            .notes("Nonconvex objective over a triangle (linear constraints)."),
        HsProblem::hs(29, "hs029", vec![1.0; 3])
            .ge0(1)
            .optimum(-16.0 * SQRT_2, Some(vec![4.0, 2.0 * SQRT_2, 2.0]), 0.0)
            .features(&[Nonconvex, NonuniqueMinimizer])
            .source("SIF HS29 (-22.6274169), CasADi hs029, roboptim problem_29")
            .notes("Four minimizers (+-4, +-2 sqrt 2, +-2) with an even number of minus signs."),
        HsProblem::hs(30, "hs030", vec![1.0; 3])
            .lower(vec![1.0, -10.0, -10.0])
            .upper(vec![10.0; 3])
            .ge0(1)
            .optimum(1.0, Some(vec![1.0, 0.0, 0.0]), 0.0)
            .features(&[Nonconvex, Degenerate])
            .source("SIF HS30, CasADi hs030, roboptim problem_30 (f(x0) = 3)")
            .notes(
                "At x* the constraint x1^2 + x2^2 >= 1 and the bound x1 >= 1 are both active with \
                 parallel gradients: LICQ fails (MFCQ holds; multipliers are not unique).",
            ),
        HsProblem::hs(31, "hs031", vec![1.0; 3])
            .lower(vec![-10.0, 1.0, -10.0])
            .upper(vec![10.0, 10.0, 1.0])
            .ge0(1)
            .optimum(6.0, Some(vec![1.0 / s3, s3, 0.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS31, CasADi hs031, roboptim problem_31 (f(x0) = 19)"),
        HsProblem::hs(32, "hs032", vec![0.1, 0.7, 0.2])
            .lower(vec![0.0; 3])
            .ge0(1)
            .eq0(1)
            .optimum(1.0, Some(vec![0.0, 0.0, 1.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS32, OptimizationProblems.jl hs32, CasADi hs032, roboptim problem_32 (f(x0) = 7.2)")
            .notes("One nonlinear inequality and one linear equality."),
        HsProblem::hs(33, "hs033", vec![0.0, 0.0, 3.0])
            .lower(vec![0.0; 3])
            .upper(vec![INF, INF, 5.0])
            .ge0(2)
            .optimum(SQRT_2 - 6.0, Some(vec![0.0, SQRT_2, SQRT_2]), 0.0)
            .features(&[Nonconvex, LocalMinima])
            .source("CasADi hs033, TOMLAB, OPTI nlp_HS, roboptim problem_33 (f(x0) = -3); SIF HS33 has -4.0")
            .notes("f* = sqrt 2 - 6 = -4.5857864. The SIF's SOLTN -4.0 is f at the feasible point (0, 0, 2), not the minimum."),
        HsProblem::hs(34, "hs034", vec![0.0, 1.05, 2.9])
            .lower(vec![0.0; 3])
            .upper(vec![100.0, 100.0, 10.0])
            .ge0(2)
            .optimum(
                -(10f64.ln().ln()),
                Some(vec![10f64.ln().ln(), 10f64.ln(), 10.0]),
                0.0,
            )
            .source("SIF HS34 (-0.83403245), CasADi hs034, roboptim problem_34")
            .notes("Convex (linear objective, concave constraint functions); exp overflows far outside the box."),
        HsProblem::hs(35, "hs035", vec![0.5; 3])
            .lower(vec![0.0; 3])
            .ge0(1)
            .optimum(1.0 / 9.0, Some(vec![4.0 / 3.0, 7.0 / 9.0, 4.0 / 9.0]), 0.0)
            .source("SIF HS35, CasADi hs035, roboptim problem_35 (f(x0) = 2.25)")
            .notes("Beale's convex QP with one linear inequality."),
        HsProblem::hs(36, "hs036", vec![10.0; 3])
            .lower(vec![0.0; 3])
            .upper(vec![20.0, 11.0, 42.0])
            .ge0(1)
            .optimum(-3300.0, Some(vec![20.0, 11.0, 15.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS36, OptimizationProblems.jl hs36, CasADi hs036 (roboptim swaps the x* of 36 and 37)"),
        HsProblem::hs(37, "hs037", vec![10.0; 3])
            .lower(vec![0.0; 3])
            .upper(vec![42.0; 3])
            .ge0(2)
            .optimum(-3456.0, Some(vec![24.0, 12.0, 12.0]), 0.0)
            .features(&[Nonconvex])
            .source("SIF HS37, OptimizationProblems.jl hs37, CasADi hs037"),
        HsProblem::hs(43, "hs043", vec![0.0; 4])
            .ge0(3)
            .optimum(-44.0, Some(vec![0.0, 1.0, 2.0, -1.0]), 0.0)
            .source("SIF HS43, CasADi hs043, roboptim problem_43 (f(x0) = 0)")
            .notes("Rosen-Suzuki; convex."),
        HsProblem::hs(44, "hs044", vec![0.0; 4])
            .lower(vec![0.0; 4])
            .ge0(6)
            .optimum(-15.0, Some(vec![0.0, 3.0, 0.0, 4.0]), 0.0)
            .features(&[Nonconvex, LocalMinima])
            .source("SIF HS44 (lists -13 and -15), CasADi hs044, roboptim problem_44")
            .notes("Indefinite bilinear objective, linear constraints; a local minimum f = -13 at (3, 0, 4, 0)."),
        HsProblem::hs(65, "hs065", vec![-5.0, 5.0, 0.0])
            .lower(vec![-4.5, -4.5, -5.0])
            .upper(vec![4.5, 4.5, 5.0])
            .ge0(1)
            .optimum(0.9535288567, Some(vec![3.650461821, 3.650461821, 4.6204170507]), 1e-8)
            .source("SIF HS65, CasADi hs065, roboptim problem_65 (f(x0) = 1225/9), TOMLAB")
            .notes(
                "Convex. x0 violates the bounds. roboptim and TOMLAB give x2* = 3.65046168, a truncation \
                 of x1* (the problem is symmetric in x1, x2).",
            ),
        HsProblem::hs(71, "hs071", vec![1.0, 5.0, 5.0, 1.0])
            .lower(vec![1.0; 4])
            .upper(vec![5.0; 4])
            .row(25.0, INF)
            .row(40.0, 40.0)
            .optimum(17.0140173, Some(vec![1.0, 4.7429994, 3.8211503, 1.3794082]), 1e-7)
            .features(&[Nonconvex])
            .source("SIF HS71 (17.0140173), TOMLAB, pyOpt/Ipopt examples; roboptim has 4.742994 (misprint)")
            .notes("The Ipopt tutorial problem. CasADi's hs071 leaves x0[0] = 0 (a conversion slip)."),
        HsProblem::hs(76, "hs076", vec![0.5; 4])
            .lower(vec![0.0; 4])
            .ge0(3)
            .optimum(-4.681818181, Some(vec![0.2727273, 2.090909, -0.26e-10, 0.5454545]), 1e-6)
            .source("CasADi hs076, roboptim problem_76 (f(x0) = -1.25), nlpql tests")
            .notes("Convex QP with linear inequalities; x* = (3/11, 23/11, 0, 6/11) to 7 digits."),
        HsProblem::hs(100, "hs100", vec![1.0, 2.0, 0.0, 4.0, 0.0, 1.0, 1.0])
            .ge0(4)
            .optimum(
                680.6300573,
                Some(vec![2.330499, 1.951372, -0.4775414, 4.365726, -0.6244870, 1.038131, 1.594227]),
                1e-6,
            )
            .features(&[Nonconvex])
            .source("SIF HS100 (680.6300573), TOMLAB, CasADi hs100; = CEC 2006 g09 (680.630057374402)"),
        HsProblem::hs(106, "hs106", vec![5000.0, 5000.0, 5000.0, 200.0, 350.0, 150.0, 225.0, 425.0])
            .lower(vec![100.0, 1000.0, 1000.0, 10.0, 10.0, 10.0, 10.0, 10.0])
            .upper(vec![10000.0, 10000.0, 10000.0, 1000.0, 1000.0, 1000.0, 1000.0, 1000.0])
            .ge0(6)
            .optimum(
                7049.330923,
                Some(vec![579.3167, 1359.943, 5110.071, 182.0174, 295.5985, 217.9799, 286.4162, 395.5979]),
                1e-6,
            )
            .features(&[Nonconvex, NotGlobal])
            .source("SIF HS106 (7049.330923), TOMLAB, OptimizationProblems.jl hs106, filterSD hs106d.f")
            .notes(
                "Heat exchanger design, badly scaled (constraint terms ~1e6). The book's point is not \
                 quite optimal: CEC 2006 g10 (the same problem) has 7049.24802052867 at (579.306685, \
                 1359.970678, 5109.970657, 182.017700, 295.601174, 217.982300, 286.416526, 395.601174) \
                 (pymoo), which is feasible (checked in the tests). CasADi uses 833.3325 and 83333.33 \
                 instead of the book's 833.33252 and 83333.333.",
            ),
        HsProblem::hs(113, "hs113", vec![2.0, 3.0, 5.0, 5.0, 1.0, 2.0, 7.0, 3.0, 6.0, 10.0])
            .ge0(8)
            .optimum(
                24.3062091,
                Some(vec![
                    2.171996, 2.363683, 8.773926, 5.095984, 0.9906548, 1.430574, 1.321644, 9.828726, 8.280092,
                    8.375927,
                ]),
                1e-6,
            )
            .source("SIF HS113 (24.3062091), CasADi hs113, DEFT-FUNNEL; = CEC 2006 g07 (24.30620906818)")
            .notes(
                "Convex (convex quadratic objective, concave constraint functions). TOMLAB has the \
                 misprints x10* = 8.37527 and f* = 24.30622091.",
            ),
        HsProblem::hs(118, "hs118", vec![20.0, 55.0, 15.0, 20.0, 60.0, 20.0, 20.0, 60.0, 20.0, 20.0, 60.0, 20.0, 20.0, 60.0, 20.0])
            .lower(vec![8.0, 43.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
            .upper(vec![21.0, 57.0, 16.0, 90.0, 120.0, 60.0, 90.0, 120.0, 60.0, 90.0, 120.0, 60.0, 90.0, 120.0, 60.0])
            .hs118_rows()
            .optimum(
                664.82045,
                Some(vec![8.0, 49.0, 3.0, 1.0, 56.0, 0.0, 1.0, 63.0, 6.0, 3.0, 70.0, 12.0, 5.0, 77.0, 18.0]),
                0.0,
            )
            .source("SIF HS118 (664.82045), CasADi hs118")
            .notes(
                "Convex QP (separable convex quadratic, 29 linear inequalities). The book's 24 one-sided \
                 ramp rows are written as 12 two-sided rows: -7 <= x_{3k+1} - x_{3k-2} <= 6, \
                 -7 <= x_{3k+2} - x_{3k-1} <= 7, -7 <= x_{3k+3} - x_{3k} <= 6 (k = 1..4), then the five \
                 demand rows; m = 17. OptimizationProblems.jl swaps the upper limits 6 and 7 of the \
                 second and third kind, which makes x* infeasible; the SIF and CasADi agree with x*.",
            ),
    ]
}

impl HsProblem {
    fn hs118_rows(mut self) -> Self {
        for _k in 1..=4 {
            self = self.row(-7.0, 6.0).row(-7.0, 7.0).row(-7.0, 6.0);
        }
        for d in [60.0, 50.0, 70.0, 85.0, 100.0] {
            self = self.row(d, INF);
        }
        self
    }
}

fn hs002_x_star() -> Vec<f64> {
    let a = (598.0f64 / 1200.0).sqrt();
    let b = 400.0 * a.powi(3);
    vec![2.0 * a * ((1.0 / b).acos() / 3.0).cos(), 1.5]
}

fn hs008_x_star() -> Vec<f64> {
    let a = ((25.0 + 301f64.sqrt()) / 2.0).sqrt();
    vec![a, 9.0 / a]
}

fn hs011_x_star() -> Vec<f64> {
    let a = (7.5 * 6f64.sqrt() + 338.5f64.sqrt()).cbrt();
    vec![
        (a - 1.0 / a) / 6f64.sqrt(),
        (a * a - 2.0 + 1.0 / (a * a)) / 6.0,
    ]
}

fn hs056_x0() -> Vec<f64> {
    let a = (1.0f64 / 4.2).sqrt().asin();
    let b = (5.0f64 / 7.2).sqrt().asin();
    vec![1.0, 1.0, 1.0, a, a, a, b]
}

fn hs056_x_star() -> Vec<f64> {
    let p = (4.0f64 / 7.0).sqrt().asin();
    let q = (2.0f64 / 7.0).sqrt().asin();
    vec![2.4, 1.2, 1.2, p, q, q, PI / 2.0]
}

/// Problems without a feasible point.
pub fn infeasible_problems() -> Vec<HsProblem> {
    vec![
        HsProblem::new("infeasible_linear", Id::Infeasible(1), vec![0.5, 0.5])
            .lower(vec![0.0, 0.0])
            .upper(vec![1.0, 1.0])
            .row(3.0, INF)
            .status(Status::Infeasible)
            .source("constructed")
            .notes("min x1 + x2 s.t. x1 + x2 >= 3, 0 <= x <= 1: the box allows x1 + x2 <= 2."),
        HsProblem::new("infeasible_nonlinear", Id::Infeasible(2), vec![0.0, 0.0])
            .row(-INF, 1.0)
            .row(3.0, INF)
            .status(Status::Infeasible)
            .features(&[Nonconvex])
            .source("constructed")
            .notes(
                "min (x1 - 2)^2 + (x2 - 2)^2 s.t. x1^2 + x2^2 <= 1, x1 + x2 >= 3: on the unit disc \
                 x1 + x2 <= sqrt 2. The least-violation point is (1/sqrt 2, 1/sqrt 2).",
            ),
        HsProblem::new("infeasible_equality", Id::Infeasible(3), vec![1.0, 1.0])
            .row(-1.0, -1.0)
            .status(Status::Infeasible)
            .features(&[Nonconvex])
            .source("constructed")
            .notes(
                "min x1 + x2 s.t. x1^2 + x2^2 = -1. The violation |c| is least (= 1) at x = 0, where \
                 the constraint gradient vanishes: a stationary point of the infeasibility.",
            ),
        HsProblem::new("infeasible_inconsistent_linear", Id::Infeasible(4), vec![0.0, 0.0, 0.0])
            .row(1.0, 1.0)
            .row(2.0, 2.0)
            .status(Status::Infeasible)
            .features(&[RankDeficient])
            .source("constructed")
            .notes(
                "min x1^2 + x2^2 + x3^2 s.t. x1 + x2 + x3 = 1 and x1 + x2 + x3 = 2: parallel, \
                 inconsistent linear equalities (rank-deficient Jacobian).",
            ),
        HsProblem::new("infeasible_asymptotic", Id::Infeasible(5), vec![0.0, 1.0])
            .row(-1.0, -1.0)
            .status(Status::Infeasible)
            .source("constructed")
            .notes(
                "min x2^2 s.t. exp(-x1) = -1. The violation 1 + exp(-x1) falls towards 1 as                  x1 grows and never reaches it: no stationary point of the infeasibility.",
            ),
    ]
}

/// Problems whose objective is unbounded below on the feasible set.
pub fn unbounded_problems() -> Vec<HsProblem> {
    vec![
        HsProblem::new("unbounded_linear", Id::Unbounded(1), vec![1.0, 2.0])
            .lower(vec![0.0, 0.0])
            .row(0.0, 0.0)
            .status(Status::Unbounded)
            .source("constructed")
            .notes("min -x1 - x2 s.t. x1 - x2 = 0, x >= 0: the ray x1 = x2 -> infinity."),
        HsProblem::new("unbounded_free_variable", Id::Unbounded(2), vec![0.0, 1.0])
            .status(Status::Unbounded)
            .source("constructed")
            .notes("min x1 + x2^2 without constraints: x1 -> -infinity (the Hessian is singular)."),
        HsProblem::new("unbounded_nonlinear", Id::Unbounded(3), vec![1.0, 1.0])
            .lower(vec![0.0, 0.0])
            .row(1.0, INF)
            .status(Status::Unbounded)
            .features(&[Nonconvex])
            .source("constructed")
            .notes("min -x1 s.t. x1 x2 >= 1, x >= 0: x = (t, 1/t), t -> infinity."),
    ]
}

/// Every problem: the HS problems, then the infeasible and unbounded ones.
pub fn all_problems() -> Vec<HsProblem> {
    let mut v = hock_schittkowski();
    v.extend(infeasible_problems());
    v.extend(unbounded_problems());
    v
}

/// The problem with the given name.
pub fn by_name(name: &str) -> Option<HsProblem> {
    all_problems().into_iter().find(|p| p.name == name)
}

// ---------------------------------------------------------------------------
// Evaluation. Variables are renamed x1.. to follow the book's formulas.

#[inline]
fn k<D: Scalar>(v: f64) -> D {
    D::from(v)
}

#[inline]
fn sq<D: Scalar>(v: D) -> D {
    v * v
}

fn eval_hs<D: Scalar>(number: u32, x: &[D], c: &mut [D]) -> D {
    match number {
        1 | 2 => rosenbrock(x[0], x[1]),
        3 => x[1] + sq(x[1] - x[0]) * 1e-5,
        4 => (x[0] + 1.0).powi(3) / 3.0 + x[1],
        5 => (x[0] + x[1]).sin() + sq(x[0] - x[1]) - x[0] * 1.5 + x[1] * 2.5 + 1.0,
        6 => hs006(x, c),
        7 => hs007(x, c),
        8 => hs008(x, c),
        9 => hs009(x, c),
        10 => hs010(x, c),
        11 => hs011(x, c),
        12 => hs012(x, c),
        13 => hs013(x, c),
        14 => hs014(x, c),
        15 => hs015(x, c),
        16 => hs016(x, c),
        17 => hs017(x, c),
        18 => hs018(x, c),
        19 => hs019(x, c),
        20 => hs020(x, c),
        21 => hs021(x, c),
        22 => hs022(x, c),
        23 => hs023(x, c),
        24 => hs024(x, c),
        25 => hs025(x),
        26 => hs026(x, c),
        27 => hs027(x, c),
        28 => hs028(x, c),
        29 => hs029(x, c),
        30 => hs030(x, c),
        31 => hs031(x, c),
        32 => hs032(x, c),
        33 => hs033(x, c),
        34 => hs034(x, c),
        35 => hs035(x, c),
        36 => hs036(x, c),
        37 => hs037(x, c),
        38 => hs038(x),
        39 => hs039(x, c),
        40 => hs040(x, c),
        41 => hs041(x, c),
        42 => hs042(x, c),
        43 => hs043(x, c),
        44 => hs044(x, c),
        45 => -(x[0] * x[1] * x[2] * x[3] * x[4]) / 120.0 + 2.0,
        46 => hs046(x, c),
        47 => hs047(x, c),
        48 => hs048(x, c),
        49 => hs049(x, c),
        50 => hs050(x, c),
        51 => hs051(x, c),
        52 => hs052(x, c),
        53 => hs053(x, c),
        55 => hs055(x, c),
        56 => hs056(x, c),
        60 => hs060(x, c),
        61 => hs061(x, c),
        65 => hs065(x, c),
        71 => hs071(x, c),
        76 => hs076(x, c),
        77 => hs077(x, c),
        78 => hs078(x, c),
        79 => hs079(x, c),
        100 => hs100(x, c),
        106 => hs106(x, c),
        113 => hs113(x, c),
        118 => hs118(x, c),
        _ => unreachable!("no Hock-Schittkowski problem {number} in this set"),
    }
}

fn rosenbrock<D: Scalar>(x1: D, x2: D) -> D {
    sq(x2 - sq(x1)) * 100.0 + sq(k::<D>(1.0) - x1)
}

fn hs006<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = (x2 - sq(x1)) * 10.0;
    sq(k::<D>(1.0) - x1)
}

fn hs007<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = sq(sq(x1) + 1.0) + sq(x2) - 4.0;
    (sq(x1) + 1.0).ln() - x2
}

fn hs008<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = sq(x1) + sq(x2) - 25.0;
    c[1] = x1 * x2 - 9.0;
    k(-1.0)
}

fn hs009<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = x1 * 4.0 - x2 * 3.0;
    (x1 * (PI / 12.0)).sin() * (x2 * (PI / 16.0)).cos()
}

fn hs010<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = -sq(x1) * 3.0 + x1 * x2 * 2.0 - sq(x2) + 1.0;
    x1 - x2
}

fn hs011<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = -sq(x1) + x2;
    sq(x1 - 5.0) + sq(x2) - 25.0
}

fn hs012<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = -sq(x1) * 4.0 - sq(x2) + 25.0;
    sq(x1) * 0.5 + sq(x2) - x1 * x2 - x1 * 7.0 - x2 * 7.0
}

fn hs013<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = (k::<D>(1.0) - x1).powi(3) - x2;
    sq(x1 - 2.0) + sq(x2)
}

fn hs014<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = x1 - x2 * 2.0;
    c[1] = -sq(x1) / 4.0 - sq(x2) + 1.0;
    sq(x1 - 2.0) + sq(x2 - 1.0)
}

fn hs015<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = x1 * x2 - 1.0;
    c[1] = x1 + sq(x2);
    rosenbrock(x1, x2)
}

fn hs016<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = x1 + sq(x2);
    c[1] = sq(x1) + x2;
    rosenbrock(x1, x2)
}

fn hs017<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = sq(x2) - x1;
    c[1] = sq(x1) - x2;
    rosenbrock(x1, x2)
}

fn hs018<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = x1 * x2 - 25.0;
    c[1] = sq(x1) + sq(x2) - 25.0;
    sq(x1) * 0.01 + sq(x2)
}

fn hs019<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = sq(x1 - 5.0) + sq(x2 - 5.0) - 100.0;
    c[1] = -sq(x2 - 5.0) - sq(x1 - 6.0) + 82.81;
    (x1 - 10.0).powi(3) + (x2 - 20.0).powi(3)
}

fn hs020<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = x1 + sq(x2);
    c[1] = sq(x1) + x2;
    c[2] = sq(x1) + sq(x2) - 1.0;
    rosenbrock(x1, x2)
}

fn hs021<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = x1 * 10.0 - x2;
    sq(x1) * 0.01 + sq(x2) - 100.0
}

fn hs022<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = -x1 - x2 + 2.0;
    c[1] = -sq(x1) + x2;
    sq(x1 - 2.0) + sq(x2 - 1.0)
}

fn hs023<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    c[0] = x1 + x2 - 1.0;
    c[1] = sq(x1) + sq(x2) - 1.0;
    c[2] = sq(x1) * 9.0 + sq(x2) - 9.0;
    c[3] = sq(x1) - x2;
    c[4] = sq(x2) - x1;
    sq(x1) + sq(x2)
}

fn hs024<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2) = (x[0], x[1]);
    let s3 = 3f64.sqrt();
    c[0] = x1 / s3 - x2;
    c[1] = x1 + x2 * s3;
    c[2] = -x1 - x2 * s3 + 6.0;
    (sq(x1 - 3.0) - 9.0) * x2.powi(3) / (27.0 * s3)
}

fn hs025<D: Scalar>(x: &[D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    let mut f = k::<D>(0.0);
    for i in 1..=99 {
        let t = i as f64 / 100.0;
        let u = 25.0 + (-50.0 * t.ln()).powf(2.0 / 3.0);
        // (u - x2)^x3 with a variable exponent.
        let p = (x3 * (-x2 + u).ln()).exp();
        f += sq((-p / x1).exp() - t);
    }
    f
}

fn hs026<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = (sq(x2) + 1.0) * x1 + x3.powi(4) - 3.0;
    sq(x1 - x2) + (x2 - x3).powi(4)
}

fn hs027<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = x1 + sq(x3);
    sq(x1 - 1.0) * 0.01 + sq(x2 - sq(x1))
}

fn hs028<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = x1 + x2 * 2.0 + x3 * 3.0;
    sq(x1 + x2) + sq(x2 + x3)
}

fn hs029<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = -sq(x1) - sq(x2) * 2.0 - sq(x3) * 4.0 + 48.0;
    -(x1 * x2 * x3)
}

fn hs030<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = sq(x1) + sq(x2) - 1.0;
    sq(x1) + sq(x2) + sq(x3)
}

fn hs031<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = x1 * x2 - 1.0;
    sq(x1) * 9.0 + sq(x2) + sq(x3) * 9.0
}

fn hs032<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = x2 * 6.0 + x3 * 4.0 - x1.powi(3) - 3.0;
    c[1] = -x1 - x2 - x3 + 1.0;
    sq(x1 + x2 * 3.0 + x3) + sq(x1 - x2) * 4.0
}

fn hs033<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = sq(x3) - sq(x2) - sq(x1);
    c[1] = sq(x1) + sq(x2) + sq(x3) - 4.0;
    (x1 - 1.0) * (x1 - 2.0) * (x1 - 3.0) + x3
}

fn hs034<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = x2 - x1.exp();
    c[1] = x3 - x2.exp();
    -x1
}

fn hs035<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = -x1 - x2 - x3 * 2.0 + 3.0;
    -x1 * 8.0 - x2 * 6.0 - x3 * 4.0
        + sq(x1) * 2.0
        + sq(x2) * 2.0
        + sq(x3)
        + x1 * x2 * 2.0
        + x1 * x3 * 2.0
        + 9.0
}

fn hs036<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = -x1 - x2 * 2.0 - x3 * 2.0 + 72.0;
    -(x1 * x2 * x3)
}

fn hs037<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = -x1 - x2 * 2.0 - x3 * 2.0 + 72.0;
    c[1] = x1 + x2 * 2.0 + x3 * 2.0;
    -(x1 * x2 * x3)
}

fn hs038<D: Scalar>(x: &[D]) -> D {
    let (x1, x2, x3, x4) = (x[0], x[1], x[2], x[3]);
    sq(x2 - sq(x1)) * 100.0
        + sq(k::<D>(1.0) - x1)
        + sq(x4 - sq(x3)) * 90.0
        + sq(k::<D>(1.0) - x3)
        + (sq(x2 - 1.0) + sq(x4 - 1.0)) * 10.1
        + (x2 - 1.0) * (x4 - 1.0) * 19.8
}

fn hs039<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4) = (x[0], x[1], x[2], x[3]);
    c[0] = x2 - x1.powi(3) - sq(x3);
    c[1] = sq(x1) - x2 - sq(x4);
    -x1
}

fn hs040<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4) = (x[0], x[1], x[2], x[3]);
    c[0] = x1.powi(3) + sq(x2) - 1.0;
    c[1] = sq(x1) * x4 - x3;
    c[2] = sq(x4) - x2;
    -(x1 * x2 * x3 * x4)
}

fn hs041<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4) = (x[0], x[1], x[2], x[3]);
    c[0] = x1 + x2 * 2.0 + x3 * 2.0 - x4;
    -(x1 * x2 * x3) + 2.0
}

fn hs042<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4) = (x[0], x[1], x[2], x[3]);
    c[0] = x1 - 2.0;
    c[1] = sq(x3) + sq(x4) - 2.0;
    sq(x1 - 1.0) + sq(x2 - 2.0) + sq(x3 - 3.0) + sq(x4 - 4.0)
}

fn hs043<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4) = (x[0], x[1], x[2], x[3]);
    c[0] = -sq(x1) - sq(x2) - sq(x3) - sq(x4) - x1 + x2 - x3 + x4 + 8.0;
    c[1] = -sq(x1) - sq(x2) * 2.0 - sq(x3) - sq(x4) * 2.0 + x1 + x4 + 10.0;
    c[2] = -sq(x1) * 2.0 - sq(x2) - sq(x3) - x1 * 2.0 + x2 + x4 + 5.0;
    sq(x1) + sq(x2) + sq(x3) * 2.0 + sq(x4) - x1 * 5.0 - x2 * 5.0 - x3 * 21.0 + x4 * 7.0
}

fn hs044<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4) = (x[0], x[1], x[2], x[3]);
    c[0] = -x1 - x2 * 2.0 + 8.0;
    c[1] = -x1 * 4.0 - x2 + 12.0;
    c[2] = -x1 * 3.0 - x2 * 4.0 + 12.0;
    c[3] = -x3 * 2.0 - x4 + 8.0;
    c[4] = -x3 - x4 * 2.0 + 8.0;
    c[5] = -x3 - x4 + 5.0;
    x1 - x2 - x3 - x1 * x3 + x1 * x4 + x2 * x3 - x2 * x4
}

fn hs046<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5) = (x[0], x[1], x[2], x[3], x[4]);
    c[0] = sq(x1) * x4 + (x4 - x5).sin() - 1.0;
    c[1] = x2 + x3.powi(4) * sq(x4) - 2.0;
    sq(x1 - x2) + sq(x3 - 1.0) + (x4 - 1.0).powi(4) + (x5 - 1.0).powi(6)
}

fn hs047<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5) = (x[0], x[1], x[2], x[3], x[4]);
    c[0] = x1 + sq(x2) + x3.powi(3) - 3.0;
    c[1] = x2 - sq(x3) + x4 - 1.0;
    c[2] = x1 * x5 - 1.0;
    sq(x1 - x2) + (x2 - x3).powi(3) + (x3 - x4).powi(4) + (x4 - x5).powi(4)
}

fn hs048<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5) = (x[0], x[1], x[2], x[3], x[4]);
    c[0] = x1 + x2 + x3 + x4 + x5;
    c[1] = x3 - (x4 + x5) * 2.0;
    sq(x1 - 1.0) + sq(x2 - x3) + sq(x4 - x5)
}

fn hs049<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5) = (x[0], x[1], x[2], x[3], x[4]);
    c[0] = x1 + x2 + x3 + x4 * 4.0;
    c[1] = x3 + x5 * 5.0;
    sq(x1 - x2) + sq(x3 - 1.0) + (x4 - 1.0).powi(4) + (x5 - 1.0).powi(6)
}

fn hs050<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5) = (x[0], x[1], x[2], x[3], x[4]);
    c[0] = x1 + x2 * 2.0 + x3 * 3.0;
    c[1] = x2 + x3 * 2.0 + x4 * 3.0;
    c[2] = x3 + x4 * 2.0 + x5 * 3.0;
    sq(x1 - x2) + sq(x2 - x3) + (x3 - x4).powi(4) + sq(x4 - x5)
}

/// The objective of HS51 and HS53.
fn hs051_objective<D: Scalar>(x: &[D]) -> D {
    let (x1, x2, x3, x4, x5) = (x[0], x[1], x[2], x[3], x[4]);
    sq(x1 - x2) + sq(x2 + x3 - 2.0) + sq(x4 - 1.0) + sq(x5 - 1.0)
}

/// The constraints of HS52 and HS53 (HS51's are the same but the first
/// has right-hand side 4, here in the bounds).
fn hs052_constraints<D: Scalar>(x: &[D], c: &mut [D]) {
    let (x1, x2, x3, x4, x5) = (x[0], x[1], x[2], x[3], x[4]);
    c[0] = x1 + x2 * 3.0;
    c[1] = x3 + x4 - x5 * 2.0;
    c[2] = x2 - x5;
}

fn hs051<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    hs052_constraints(x, c);
    hs051_objective(x)
}

fn hs052<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5) = (x[0], x[1], x[2], x[3], x[4]);
    hs052_constraints(x, c);
    sq(x1 * 4.0 - x2) + sq(x2 + x3 - 2.0) + sq(x4 - 1.0) + sq(x5 - 1.0)
}

fn hs053<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    hs052_constraints(x, c);
    hs051_objective(x)
}

fn hs055<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5, x6) = (x[0], x[1], x[2], x[3], x[4], x[5]);
    c[0] = x1 + x2 * 2.0 + x5 * 5.0;
    c[1] = x1 + x2 + x3;
    c[2] = x4 + x5 + x6;
    c[3] = x1 + x4;
    c[4] = x2 + x5;
    c[5] = x3 + x6;
    x1 + x2 * 2.0 + x5 * 4.0 + (x1 * x4).exp()
}

fn hs056<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = x1 - sq(x[3].sin()) * 4.2;
    c[1] = x2 - sq(x[4].sin()) * 4.2;
    c[2] = x3 - sq(x[5].sin()) * 4.2;
    c[3] = x1 + x2 * 2.0 + x3 * 2.0 - sq(x[6].sin()) * 7.2;
    -(x1 * x2 * x3)
}

fn hs060<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = x1 * (sq(x2) + 1.0) + x3.powi(4);
    sq(x1 - 1.0) + sq(x1 - x2) + (x2 - x3).powi(4)
}

fn hs061<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = x1 * 3.0 - sq(x2) * 2.0;
    c[1] = x1 * 4.0 - sq(x3);
    sq(x1) * 4.0 + sq(x2) * 2.0 + sq(x3) * 2.0 - x1 * 33.0 + x2 * 16.0 - x3 * 24.0
}

fn hs065<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3) = (x[0], x[1], x[2]);
    c[0] = -sq(x1) - sq(x2) - sq(x3) + 48.0;
    sq(x1 - x2) + sq(x1 + x2 - 10.0) / 9.0 + sq(x3 - 5.0)
}

fn hs071<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4) = (x[0], x[1], x[2], x[3]);
    c[0] = x1 * x2 * x3 * x4;
    c[1] = sq(x1) + sq(x2) + sq(x3) + sq(x4);
    x1 * x4 * (x1 + x2 + x3) + x3
}

fn hs076<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4) = (x[0], x[1], x[2], x[3]);
    c[0] = -x1 - x2 * 2.0 - x3 - x4 + 5.0;
    c[1] = -x1 * 3.0 - x2 - x3 * 2.0 + x4 + 4.0;
    c[2] = x2 + x3 * 4.0 - 1.5;
    sq(x1) + sq(x2) * 0.5 + sq(x3) + sq(x4) * 0.5 - x1 * x3 + x3 * x4 - x1 - x2 * 3.0 + x3 - x4
}

fn hs077<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5) = (x[0], x[1], x[2], x[3], x[4]);
    c[0] = sq(x1) * x4 + (x4 - x5).sin();
    c[1] = x2 + x3.powi(4) * sq(x4);
    sq(x1 - 1.0) + sq(x1 - x2) + sq(x3 - 1.0) + (x4 - 1.0).powi(4) + (x5 - 1.0).powi(6)
}

fn hs078<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5) = (x[0], x[1], x[2], x[3], x[4]);
    c[0] = sq(x1) + sq(x2) + sq(x3) + sq(x4) + sq(x5);
    c[1] = x2 * x3 - x4 * x5 * 5.0;
    c[2] = x1.powi(3) + x2.powi(3);
    x1 * x2 * x3 * x4 * x5
}

fn hs079<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5) = (x[0], x[1], x[2], x[3], x[4]);
    c[0] = x1 + sq(x2) + x3.powi(3);
    c[1] = x2 - sq(x3) + x4;
    c[2] = x1 * x5;
    sq(x1 - 1.0) + sq(x1 - x2) + sq(x2 - x3) + (x3 - x4).powi(4) + (x4 - x5).powi(4)
}

fn hs100<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5, x6, x7) = (x[0], x[1], x[2], x[3], x[4], x[5], x[6]);
    c[0] = -sq(x1) * 2.0 - x2.powi(4) * 3.0 - x3 - sq(x4) * 4.0 - x5 * 5.0 + 127.0;
    c[1] = -x1 * 7.0 - x2 * 3.0 - sq(x3) * 10.0 - x4 + x5 + 282.0;
    c[2] = -x1 * 23.0 - sq(x2) - sq(x6) * 6.0 + x7 * 8.0 + 196.0;
    c[3] = -sq(x1) * 4.0 - sq(x2) + x1 * x2 * 3.0 - sq(x3) * 2.0 - x6 * 5.0 + x7 * 11.0;
    sq(x1 - 10.0)
        + sq(x2 - 12.0) * 5.0
        + x3.powi(4)
        + sq(x4 - 11.0) * 3.0
        + x5.powi(6) * 10.0
        + sq(x6) * 7.0
        + x7.powi(4)
        - x6 * x7 * 4.0
        - x6 * 10.0
        - x7 * 8.0
}

fn hs106<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5, x6, x7, x8) = (x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7]);
    c[0] = -(x4 + x6) * 0.0025 + 1.0;
    c[1] = -(x5 + x7 - x4) * 0.0025 + 1.0;
    c[2] = -(x8 - x5) * 0.01 + 1.0;
    c[3] = x1 * x6 - x4 * 833.33252 - x1 * 100.0 + 83333.333;
    c[4] = x2 * x7 - x5 * 1250.0 - x2 * x4 + x4 * 1250.0;
    c[5] = x3 * x8 - x3 * x5 + x5 * 2500.0 - 1250000.0;
    x1 + x2 + x3
}

fn hs113<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    let (x1, x2, x3, x4, x5, x6, x7, x8, x9, x10) =
        (x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], x[8], x[9]);
    c[0] = -x1 * 4.0 - x2 * 5.0 + x7 * 3.0 - x8 * 9.0 + 105.0;
    c[1] = -x1 * 10.0 + x2 * 8.0 + x7 * 17.0 - x8 * 2.0;
    c[2] = x1 * 8.0 - x2 * 2.0 - x9 * 5.0 + x10 * 2.0 + 12.0;
    c[3] = -sq(x1 - 2.0) * 3.0 - sq(x2 - 3.0) * 4.0 - sq(x3) * 2.0 + x4 * 7.0 + 120.0;
    c[4] = -sq(x1) * 5.0 - x2 * 8.0 - sq(x3 - 6.0) + x4 * 2.0 + 40.0;
    c[5] = -sq(x1 - 8.0) * 0.5 - sq(x2 - 4.0) * 2.0 - sq(x5) * 3.0 + x6 + 30.0;
    c[6] = -sq(x1) - sq(x2 - 2.0) * 2.0 + x1 * x2 * 2.0 - x5 * 14.0 + x6 * 6.0;
    c[7] = x1 * 3.0 - x2 * 6.0 - sq(x9 - 8.0) * 12.0 + x10 * 7.0;
    sq(x1) + sq(x2) + x1 * x2 - x1 * 14.0 - x2 * 16.0
        + sq(x3 - 10.0)
        + sq(x4 - 5.0) * 4.0
        + sq(x5 - 3.0)
        + sq(x6 - 1.0) * 2.0
        + sq(x7) * 5.0
        + sq(x8 - 11.0) * 7.0
        + sq(x9 - 10.0) * 2.0
        + sq(x10 - 7.0)
        + 45.0
}

fn hs118<D: Scalar>(x: &[D], c: &mut [D]) -> D {
    // Rows per k = 1..4: x_{3k+1} - x_{3k-2}, x_{3k+2} - x_{3k-1},
    // x_{3k+3} - x_{3k} (0-based: x[3k] - x[3k-3], ...).
    for kk in 1..=4 {
        let r = 3 * (kk - 1);
        c[r] = x[3 * kk] - x[3 * kk - 3];
        c[r + 1] = x[3 * kk + 1] - x[3 * kk - 2];
        c[r + 2] = x[3 * kk + 2] - x[3 * kk - 1];
    }
    for j in 0..5 {
        c[12 + j] = x[3 * j] + x[3 * j + 1] + x[3 * j + 2];
    }
    let mut f = k::<D>(0.0);
    for j in 0..5 {
        let (a, b, d) = (x[3 * j], x[3 * j + 1], x[3 * j + 2]);
        f += a * 2.3 + sq(a) * 0.0001 + b * 1.7 + sq(b) * 0.0001 + d * 2.2 + sq(d) * 0.00015;
    }
    f
}

fn eval_infeasible<D: Scalar>(number: u32, x: &[D], c: &mut [D]) -> D {
    match number {
        1 => {
            c[0] = x[0] + x[1];
            x[0] + x[1]
        }
        2 => {
            c[0] = sq(x[0]) + sq(x[1]);
            c[1] = x[0] + x[1];
            sq(x[0] - 2.0) + sq(x[1] - 2.0)
        }
        3 => {
            c[0] = sq(x[0]) + sq(x[1]);
            x[0] + x[1]
        }
        4 => {
            c[0] = x[0] + x[1] + x[2];
            c[1] = x[0] + x[1] + x[2];
            sq(x[0]) + sq(x[1]) + sq(x[2])
        }
        5 => {
            c[0] = (-x[0]).exp();
            sq(x[1])
        }
        _ => unreachable!("no infeasible problem {number}"),
    }
}

fn eval_unbounded<D: Scalar>(number: u32, x: &[D], c: &mut [D]) -> D {
    match number {
        1 => {
            c[0] = x[0] - x[1];
            -x[0] - x[1]
        }
        2 => x[0] + sq(x[1]),
        3 => {
            c[0] = x[0] * x[1];
            -x[0]
        }
        _ => unreachable!("no unbounded problem {number}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nlp::{check_derivatives, AdNlp, Nlp};
    use std::collections::HashSet;

    /// f and c at a point, in f64.
    fn evaluate(p: &HsProblem, x: &[f64]) -> (f64, Vec<f64>) {
        let mut c = vec![f64::NAN; p.m];
        let f = p.eval(x, &mut c);
        (f, c)
    }

    /// The largest bound or constraint violation at `x`, each scaled by
    /// its tolerance `tol_x(j)` / `tol_c(i)`; feasible within tolerance
    /// when at most 1.
    fn scaled_violation(
        p: &HsProblem,
        x: &[f64],
        tol_x: impl Fn(usize) -> f64,
        tol_c: impl Fn(usize) -> f64,
    ) -> (f64, String) {
        let (_, c) = evaluate(p, x);
        let mut worst = (0.0, String::from("none"));
        let mut see = |v: f64, tol: f64, what: String| {
            if v / tol > worst.0 {
                worst = (
                    v / tol,
                    format!("{what}: violation {v:e}, tolerance {tol:e}"),
                );
            }
        };
        for j in 0..p.n {
            let v = (p.x_lower[j] - x[j]).max(x[j] - p.x_upper[j]).max(0.0);
            see(v, tol_x(j), format!("bound on x[{j}] = {}", x[j]));
        }
        for i in 0..p.m {
            let v = (p.c_lower[i] - c[i]).max(c[i] - p.c_upper[i]).max(0.0);
            see(
                v,
                tol_c(i),
                format!(
                    "row {i}: c = {}, [{}, {}]",
                    c[i], p.c_lower[i], p.c_upper[i]
                ),
            );
        }
        worst
    }

    fn feasible(p: &HsProblem, x: &[f64], tol: f64) -> bool {
        scaled_violation(p, x, |_| tol, |_| tol).0 <= 1.0
    }

    #[test]
    fn problem_data_is_consistent() {
        let all = all_problems();
        let mut names = HashSet::new();
        for p in &all {
            assert!(names.insert(p.name), "duplicate name {}", p.name);
            assert_eq!(p.x0.len(), p.n, "{}: x0", p.name);
            assert_eq!(p.x_lower.len(), p.n, "{}: x_lower", p.name);
            assert_eq!(p.x_upper.len(), p.n, "{}: x_upper", p.name);
            assert_eq!(p.c_lower.len(), p.m, "{}: c_lower", p.name);
            assert_eq!(p.c_upper.len(), p.m, "{}: c_upper", p.name);
            for j in 0..p.n {
                assert!(p.x_lower[j] <= p.x_upper[j], "{}: bounds of x[{j}]", p.name);
                assert!(
                    p.x_lower[j] < INF && p.x_upper[j] > -INF,
                    "{}: infinite bound of x[{j}] on the wrong side",
                    p.name
                );
            }
            for i in 0..p.m {
                assert!(
                    p.c_lower[i] <= p.c_upper[i],
                    "{}: bounds of row {i}",
                    p.name
                );
                assert!(
                    p.c_lower[i] < INF && p.c_upper[i] > -INF,
                    "{}: row {i} bounded on the wrong side",
                    p.name
                );
            }
            // Every row is written, f and c are finite at x0.
            let (f, c) = evaluate(p, &p.x0);
            assert!(f.is_finite(), "{}: f(x0) = {f}", p.name);
            assert!(c.iter().all(|v| v.is_finite()), "{}: c(x0) = {c:?}", p.name);
            match p.status {
                Status::Optimal => assert!(p.f_star.is_finite(), "{}: f*", p.name),
                Status::Infeasible | Status::Unbounded => {
                    assert!(
                        p.f_star.is_nan() && p.x_star.is_none(),
                        "{}: no optimum expected",
                        p.name
                    )
                }
            }
            if let Some(x) = &p.x_star {
                assert_eq!(x.len(), p.n, "{}: x*", p.name);
            }
            assert!(
                p.x_star_precision >= 0.0 && p.x_star_precision < 1e-5,
                "{}: x* precision",
                p.name
            );
            assert!(!p.source.is_empty(), "{}: source", p.name);
            // The AdProblem accessors agree with the fields.
            let nlp = AdNlp::new(p.clone());
            assert_eq!(
                (nlp.num_variables(), nlp.num_constraints()),
                (p.n, p.m),
                "{}",
                p.name
            );
            let (mut l, mut u) = (vec![0.0; p.n], vec![0.0; p.n]);
            nlp.variable_bounds(&mut l, &mut u);
            assert_eq!((&l, &u), (&p.x_lower, &p.x_upper), "{}", p.name);
            let (mut l, mut u) = (vec![0.0; p.m], vec![0.0; p.m]);
            nlp.constraint_bounds(&mut l, &mut u);
            assert_eq!((&l, &u), (&p.c_lower, &p.c_upper), "{}", p.name);
            let mut x0 = vec![0.0; p.n];
            nlp.initial_point(&mut x0);
            assert_eq!(x0, p.x0, "{}", p.name);
        }
        for p in hock_schittkowski() {
            let k = p.number.expect("HS number");
            assert_eq!(p.name, format!("hs{k:03}"));
            assert_eq!(p.status, Status::Optimal);
        }
        assert!(infeasible_problems()
            .iter()
            .all(|p| p.status == Status::Infeasible && p.number.is_none()));
        assert!(unbounded_problems()
            .iter()
            .all(|p| p.status == Status::Unbounded && p.number.is_none()));
        assert_eq!(by_name("hs071").and_then(|p| p.number), Some(71));
    }

    #[test]
    fn the_set_covers_the_problem_classes() {
        let hs = hock_schittkowski();
        assert!(hs.len() >= 32, "{} problems", hs.len());
        let count = |pred: &dyn Fn(&HsProblem) -> bool| hs.iter().filter(|p| pred(p)).count();
        assert!(
            count(&|p| p.m == 0) >= 5,
            "bound constrained / unconstrained"
        );
        assert!(
            count(&|p| p.has_equalities() && !p.has_inequalities()) >= 20,
            "equality constrained"
        );
        assert!(
            count(&|p| p.has_inequalities()) >= 25,
            "inequality constrained"
        );
        assert!(
            count(&|p| p.has_equalities() && p.has_inequalities()) >= 3,
            "mixed"
        );
        assert!(count(&|p| p.has(Feature::Nonconvex)) >= 20, "nonconvex");
        assert!(count(&|p| p.has(Feature::Degenerate)) >= 2, "degenerate");
        assert!(
            count(&|p| p.has(Feature::RankDeficient)) >= 1,
            "rank deficient"
        );
        assert!(by_name("hs013").unwrap().has(Feature::Degenerate));
        assert!(infeasible_problems().len() >= 2);
        assert!(unbounded_problems().len() >= 2);
    }

    /// f(x*) = f* and x* is feasible, within 1e-6 widened by the
    /// first-order effect of rounding x* to its published precision.
    #[test]
    fn published_solutions_are_consistent() {
        let mut checked = 0;
        let mut failures = Vec::new();
        for p in hock_schittkowski() {
            let Some(x) = p.x_star.clone() else { continue };
            let prec = p.x_star_precision;
            let mut nlp = AdNlp::new(p.clone());
            let mut g = vec![0.0; p.n];
            nlp.gradient(&x, &mut g).unwrap();
            let mut jac = vec![0.0; p.m * p.n];
            nlp.jacobian_values(&x, &mut jac).unwrap();
            let sensitivity =
                |row: &[f64]| -> f64 { row.iter().zip(&x).map(|(a, b)| (a * b).abs()).sum() };

            let (f, _) = evaluate(&p, &x);
            let base = if p.f_star == 0.0 {
                1e-6
            } else {
                1e-6 * p.f_star.abs()
            };
            let tol_f = base + prec * sensitivity(&g);
            if (f - p.f_star).abs() > tol_f {
                failures.push(format!(
                    "{}: f(x*) = {f:.12}, f* = {:.12}, difference {:e} > {tol_f:e}",
                    p.name,
                    p.f_star,
                    f - p.f_star
                ));
            }
            let (worst, what) = scaled_violation(
                &p,
                &x,
                |j| 1e-6 + prec * x[j].abs(),
                |i| 1e-6 + prec * sensitivity(&jac[i * p.n..(i + 1) * p.n]),
            );
            if worst > 1.0 {
                failures.push(format!("{}: x* infeasible, {what}", p.name));
            }
            checked += 1;
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
        assert!(checked >= 60, "only {checked} published points checked");
    }

    /// Exact and closed-form solutions satisfy everything to rounding
    /// error, and their f* (closed forms or 9-10 published digits) agree
    /// to 1e-9.
    #[test]
    fn exact_solutions_are_consistent_to_rounding() {
        let mut failures = Vec::new();
        for p in hock_schittkowski() {
            let Some(x) = &p.x_star else { continue };
            if p.x_star_precision > 0.0 {
                continue;
            }
            let (worst, what) = scaled_violation(&p, x, |_| 1e-9, |_| 1e-9);
            if worst > 1.0 {
                failures.push(format!("{}: {what}", p.name));
            }
            let (f, _) = evaluate(&p, x);
            if (f - p.f_star).abs() > 1e-9 * p.f_star.abs().max(1.0) {
                failures.push(format!(
                    "{}: f(x*) = {f:.15}, f* = {:.15}",
                    p.name, p.f_star
                ));
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }

    /// Points better than the published optimum, as recorded in the notes.
    #[test]
    fn known_points_below_the_published_optimum() {
        let hs047 = by_name("hs047").unwrap();
        let x = [
            0.67700461670128,
            0.726089640962586,
            1.215491109042481,
            1.75132899519799,
            1.477094801614824,
        ];
        assert!(feasible(&hs047, &x, 1e-10));
        let (f, _) = evaluate(&hs047, &x);
        assert!((f - -0.0267141826940).abs() < 1e-10, "hs047: f = {f}");
        assert!(f < hs047.f_star);

        // CEC 2006 g10 (pymoo), the same problem as HS106.
        let hs106 = by_name("hs106").unwrap();
        let x = [
            579.3066850179796,
            1359.970678079356,
            5109.970657431333,
            182.01769963061534,
            295.6011737027468,
            217.98230036938463,
            286.4165259278685,
            395.6011737027467,
        ];
        assert!(
            feasible(&hs106, &x, 1e-6),
            "{}",
            scaled_violation(&hs106, &x, |_| 1e-6, |_| 1e-6).1
        );
        let (f, _) = evaluate(&hs106, &x);
        assert!((f - 7049.24802052867).abs() < 1e-8, "hs106: f = {f}");
        assert!(f < hs106.f_star - 0.08);
    }

    /// Gradient, Jacobian and Lagrangian Hessian of the dual-number
    /// wrapper against central differences (h = 1e-6) at x0 and x*.
    #[test]
    fn derivatives_match_finite_differences() {
        let mut failures = Vec::new();
        for p in all_problems() {
            let lambda: Vec<f64> = (0..p.m).map(|i| 1.0 - 0.3 * i as f64).collect();
            let mut points = vec![("x0", p.x0.clone())];
            if let Some(x) = &p.x_star {
                points.push(("x*", x.clone()));
            }
            let name = p.name;
            let mut nlp = AdNlp::new(p);
            for (which, x) in points {
                let r = check_derivatives(&mut nlp, &x, &lambda, 1e-6)
                    .unwrap_or_else(|e| panic!("{name} at {which}: {e}"));
                let hessian = r.hessian.expect("AdNlp has a Hessian");
                if r.gradient >= 1e-5
                    || r.jacobian >= 1e-5
                    || r.jacobian_outside_pattern != 0.0
                    || hessian >= 1e-5
                {
                    failures.push(format!("{name} at {which}: {r:?}"));
                }
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }

    /// A small deterministic generator for sample points.
    struct Lcg(u64);
    impl Lcg {
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
        }
    }

    #[test]
    fn infeasible_problems_have_no_feasible_sample() {
        let mut rng = Lcg(12345);
        for p in infeasible_problems() {
            for _ in 0..20_000 {
                let x: Vec<f64> = (0..p.n)
                    .map(|j| rng.uniform(p.x_lower[j].max(-10.0), p.x_upper[j].min(10.0)))
                    .collect();
                assert!(!feasible(&p, &x, 1e-3), "{}: feasible sample {x:?}", p.name);
            }
            assert!(!feasible(&p, &p.x0, 1e-3), "{}: x0 feasible", p.name);
        }
        // The certificates in the notes.
        let lin = by_name("infeasible_linear").unwrap();
        assert_eq!(evaluate(&lin, &lin.x_upper).1[0], 2.0);
        let eq = by_name("infeasible_equality").unwrap();
        assert_eq!(evaluate(&eq, &[0.0, 0.0]).1[0], 0.0);
    }

    #[test]
    fn unbounded_problems_have_descending_feasible_rays() {
        let t = (1u64 << 20) as f64;
        let rays: [(&str, Vec<f64>); 3] = [
            ("unbounded_linear", vec![t, t]),
            ("unbounded_free_variable", vec![-t, 0.0]),
            ("unbounded_nonlinear", vec![t, 1.0 / t]),
        ];
        for (name, x) in rays {
            let p = by_name(name).unwrap();
            assert!(feasible(&p, &x, 0.0), "{name}: ray point infeasible");
            let (f, _) = evaluate(&p, &x);
            assert!(f <= -t, "{name}: f = {f}");
        }
        assert_eq!(unbounded_problems().len(), 3);
    }
}
