//! A sparse SQP method whose QP subproblems clarabel solves.
//!
//! Each iteration linearises the constraints and models the Lagrangian with
//! a positive semidefinite, partially separable Hessian B (one block per
//! [`Element`] of the problem), solves the QP of [`qp`] for a step d and
//! multipliers, and takes a step along d that decreases the ℓ₁ merit
//! function φ(x; ν) = f(x) + ν ‖viol c(x)‖₁ (Nocedal & Wright 2006,
//! Algorithm 18.3; Han 1977; Powell 1978), by default through IPOPT's
//! filter ([`LineSearch::Filter`]), with a second-order correction when the
//! full step is rejected while the constraints got worse (Maratos effect).
//!
//! * Hessian: [`HessianMode::ExactConvexified`] takes each element's exact
//!   Lagrangian Hessian and replaces its eigenvalues μ by max(μ, δ)
//!   ([`Convexification`]);
//!   [`HessianMode::PartitionedBfgs`] keeps one damped BFGS matrix per
//!   element (Griewank & Toint 1982; Powell's damping keeps it positive
//!   definite).
//! * Feasibility: when the linearised constraints are inconsistent, the QP
//!   is re-solved in elastic mode (ℓ₁-penalised slacks p, n ≥ 0 on every
//!   constraint row, as SNOPT does), so every iteration gets a step. A
//!   point where the elastic QP cannot reduce the linearised infeasibility
//!   even without the objective is a stationary point of the infeasibility:
//!   status [`SqpStatus::Infeasible`].
//! * Step bound: |d_j| ≤ Δ (enlarged ×4 whenever a full step reaches it),
//!   so every QP is bounded; an objective below `unbounded_objective` at a
//!   feasible point, or a QP that fails at a huge Δ while the objective
//!   keeps falling at feasible points, gives [`SqpStatus::Unbounded`].
//!   Once Δ grows past its initial value the eigenvalue floor of the exact
//!   Hessian falls in proportion, so Δ, not the floor, holds a step along a
//!   direction without curvature.
//! * Termination, with Moco's setting names: primal infeasibility (largest
//!   constraint violation in the problem's units, IPOPT's `constr_viol_tol`,
//!   which Moco sets to it) ≤ `optim_constraint_tolerance` and scaled dual
//!   infeasibility and complementarity (IPOPT's scaling, s_max = 100, with
//!   the divisor s_d capped at 1e4 so diverging multipliers cannot hide
//!   a residual) ≤
//!   `optim_convergence_tolerance`; or, with `paper_criterion`, the change
//!   of the objective below 1e-6 with constraints within 1e-3 (Porsa et al.
//!   2016) over a step neither the line search nor the step bound cut
//!   short, at a scaled dual infeasibility of at most
//!   `paper_criterion_dual_infeasibility`.

mod helper;
pub mod ipm;
mod ldlt;
pub mod qp;

use crate::nlp::{check_elements, Element, EvalError, Nlp, INFINITE_BOUND};
use nalgebra::{DMatrix, SymmetricEigen};
use qp::{Qp, QpOutcome};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// How the QP's Hessian is built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HessianMode {
    /// Exact element Hessians with eigenvalues μ → max(μ, δ)
    /// ([`Convexification`]).
    ExactConvexified,
    /// One damped BFGS matrix per element.
    PartitionedBfgs,
}

/// How [`HessianMode::ExactConvexified`] makes an element's Hessian
/// positive definite, eigenvalue by eigenvalue.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Convexification {
    /// μ → max(μ, δ): negative curvature is dropped, the step along it is
    /// left to the step bound Δ (a box trust region). Default: on the
    /// jump and the test set it takes far fewer iterations (`leap bench
    /// sqp`; the landing notes).
    Clip,
    /// μ → max(|μ|, δ) (modified Newton, Gill & Murray): negative
    /// curvature becomes positive curvature of the same size, which keeps
    /// steps short where the Lagrangian bends down.
    Absolute,
    /// No eigenvalue modification: the element Hessians as they are, and
    /// the interior-point QP solver adds τ I to the whole QP Hessian until
    /// it is positive definite on the null space of the equality rows and
    /// of the rows active at its last answer (IPOPT's inertia correction,
    /// Wächter & Biegler 2006, with the previous active set as the
    /// prediction); τ rises further within a solve where the KKT matrix's
    /// inertia turns wrong. The QP model keeps the true curvature along
    /// the constraints. Needs [`QpSolver::InteriorPoint`]. Measured, not
    /// the jump's default (the README gives the numbers); on the test set
    /// with the library's scaling it solves hs106 in 7 iterations, the
    /// clip in 38.
    InertiaCorrection,
}

/// Which solver solves the QP subproblems.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum QpSolver {
    /// Clarabel alone (default).
    Clarabel,
    /// Leap's interior-point method ([`ipm`]): single-entry rows (bounds)
    /// folded into the KKT diagonal, faer's supernodal LDLᵀ with the
    /// ordering kept for the whole solve; clarabel solves any QP it fails
    /// on. Without equilibration it reached the default jump's solution
    /// (28.31 cm, 357 iterations) in 202 s instead of clarabel's 535 s
    /// but led the reduced jump to a poor local optimum (12.3 cm). With
    /// Ruiz equilibration of every QP: reduced jump 28.90 cm in 172
    /// iterations, 32.9 s (clarabel 28.45 cm, 150, 43.0 s); default jump
    /// solved at a higher optimum, 30.53 cm, but after 816 iterations,
    /// 377 s (`leap bench solve`, partly sharing the cores). Not the
    /// default until its paths are understood.
    InteriorPoint,
}

/// How a step is accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LineSearch {
    /// Backtracking on the ℓ1 merit function f + ν‖c‖₁.
    L1Merit,
    /// Backtracking with IPOPT's filter (Wächter & Biegler 2006): a trial
    /// point is accepted when it reduces the violation or the objective
    /// enough and no earlier point dominates it; near feasibility an
    /// Armijo decrease of f alone. Optionally the filter is emptied when
    /// its entries keep refusing steps ([`SqpSettings::max_filter_resets`]).
    /// Falls back to the merit search when no trial is acceptable and in
    /// elastic mode.
    Filter,
}

impl std::str::FromStr for HessianMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "exact" | "exact_convexified" => Ok(HessianMode::ExactConvexified),
            "bfgs" | "partitioned_bfgs" => Ok(HessianMode::PartitionedBfgs),
            _ => Err(format!(
                "unknown Hessian mode '{s}' (expected 'exact' or 'bfgs')"
            )),
        }
    }
}

/// Settings of [`solve`]; names follow Moco where it has one.
#[derive(Debug, Clone)]
pub struct SqpSettings {
    /// Scaled dual infeasibility and complementarity tolerance.
    pub optim_convergence_tolerance: f64,
    /// Largest constraint violation allowed at a solution, in the
    /// problem's units (IPOPT's `constr_viol_tol`, which Moco sets to it).
    pub optim_constraint_tolerance: f64,
    pub max_iterations: usize,
    /// Default: partitioned BFGS, chosen by `leap bench sqp`: it solves
    /// more of the test set at the published optimum, in less time.
    pub hessian: HessianMode,
    /// Eigenvalue modification of the exact element Hessians.
    pub convexification: Convexification,
    /// Smallest eigenvalue kept, relative to the element's largest |μ|
    /// (and at least this absolute), while the step bound is at most its
    /// initial value; times Δ₀/Δ beyond.
    pub eigenvalue_floor: f64,
    /// With the exact Hessian: where an element declares blocks
    /// ([`Element::blocks`]), keep only the curvature inside each block and
    /// convexify each block by itself. An approximation (the dropped
    /// couplings are real curvature) that keeps the QP's KKT factor
    /// sparse.
    pub block_diagonal_elements: bool,
    /// Stop when |Δf| < 1e-6 (1 + |f|) with the constraints within 1e-3,
    /// the criterion of Porsa et al. (2016), both in the problem's units
    /// (not the solver's scaling), where Δf is the change over a whole step
    /// (α = 1 inside the step bound: a step the line search or the step
    /// bound cut short proves nothing), and,
    /// besides the paper, the scaled dual infeasibility at most
    /// `paper_criterion_dual_infeasibility`.
    pub paper_criterion: bool,
    /// The paper's criterion holds only where the scaled dual
    /// infeasibility is at most this (default 1): a small step whose
    /// multipliers do not balance the gradient is no optimum. Without it
    /// the jump's 14- and 20-interval meshes stopped at 6.2 and 23.0 cm
    /// with dual infeasibilities of 1.4e4 and 6.6e4 (multipliers up to
    /// 1e13 the iterations before); the solves that reached an optimum
    /// (28 and 26 intervals, both Hessian modes) stopped at 1e-3 to 5e-2.
    pub paper_criterion_dual_infeasibility: f64,
    /// At the iteration limit, return the iterate of lowest objective
    /// among those with violation (largest row, in the problem's units) at
    /// most this, when the last iterate is worse or violates more (default
    /// 1e-3, the paper's constraint tolerance; 0 returns the last
    /// iterate, as IPOPT does). The last iterate of a solve that creeps
    /// along the constraints can be far off them (the jump: 0.36 after
    /// 600 iterations, where iteration 563 had 3e-4).
    pub best_iterate_violation: f64,
    /// "Acceptable" levels (IPOPT's acceptable_tol): met for
    /// `acceptable_iterations` consecutive iterations, or when no further
    /// progress is possible, the solve ends as [`SqpStatus::Acceptable`].
    pub acceptable_convergence_tolerance: f64,
    /// In the problem's units, as `optim_constraint_tolerance`.
    pub acceptable_constraint_tolerance: f64,
    pub acceptable_iterations: usize,
    /// Initial step bound Δ (times max(1, ‖x₀‖∞)).
    pub initial_step_bound: f64,
    /// An objective below this at a feasible point means unbounded.
    pub unbounded_objective: f64,
    /// Relative accuracy of the QP solves.
    pub qp_tolerance: f64,
    /// Clarabel's Ruiz equilibration of each QP (computed from the first
    /// QP and kept through the in-place updates).
    pub qp_equilibrate: bool,
    /// Leap's interior-point QP solver starts each QP from the last one's
    /// multipliers (slacks from the new bounds), and from its cold start
    /// again where that does not solve; not with the inertia correction.
    /// Default on: the default jump took 25% fewer interior-point
    /// iterations on its consecutive QPs (docs/implicit-fibre-dynamics.md, "Speed").
    pub qp_warm_start: bool,
    /// Which solver solves the QPs first ([`QpSolver`]; default clarabel,
    /// see there).
    pub qp_solver: QpSolver,
    /// Second-order correction of a rejected full step that raised the
    /// violation (outside elastic mode).
    pub second_order_correction: bool,
    /// In the filter line search, a second-order correction of every
    /// rejected full step, not only of one that raised the violation (the
    /// default, IPOPT's trigger). A step the filter's entries refuse
    /// although it lowered the violation can still carry a curvature
    /// residual the correction removes: on `models/jump_gait2392.json`
    /// full steps that halved the violation left 2e-4 on activation defects
    /// (the switch's tanh at b = 200), their linearisation 1e-11. See
    /// [`SqpSettings::max_filter_resets`] for what it does with the reset.
    pub second_order_correction_every_rejected_step: bool,
    /// Print the iteration log to standard error.
    pub verbose: bool,
    /// Directory where a failing QP is written (clarabel JSON).
    pub qp_dump_dir: Option<PathBuf>,
    /// Also write every iteration's QP there (`qp_iter<k>_qp.json`, the
    /// elastic one where the plain QP was infeasible), and each plain QP
    /// found or taken as infeasible (`qp_iter<k>_plain_infeasible.json`),
    /// for profiling the QP solver and checking its verdicts.
    pub qp_dump_every: bool,
    /// Gradient-based scaling of the objective and constraints at the
    /// starting point (IPOPT's default); the dual infeasibility and
    /// complementarity tolerances apply to the scaled problem, the
    /// constraint tolerances to the problem's units (as IPOPT's).
    pub nlp_scaling: bool,
    /// Solve in variables scaled by the widths of their bounds
    /// ([`crate::nlp::ScaledVariables`]; Moco's name). Results are
    /// returned in the problem's own variables. Default on: on hs106
    /// (x from 10 to 1e4) the unscaled exact-Hessian SQP zigzagged
    /// against the step bound, converged linearly and stopped as
    /// acceptable after 216 iterations at a violation of 2.2e-7; scaled,
    /// it is solved in 38 (with the constraint tolerance in the problem's
    /// units; 197 and 37 before), and the whole test set took fewer iterations
    /// in every mode but one (PartitionedBfgs with clarabel, 3860 → 3866,
    /// all in hs013's iteration limit). The jump sets it itself.
    pub scale_variables_using_bounds: bool,
    /// Step acceptance (default: the filter, see `leap bench sqp`).
    pub line_search: LineSearch,
    /// The filter rejects a trial point whose violation exceeds this
    /// multiple of the current one (or of θ_min), besides IPOPT's θ_max
    /// (default 100, measured on the jump with `jump_diag`, VGROWTH).
    pub max_violation_growth: f64,
    /// A filter reset after IPOPT's heuristic, with its option names
    /// (IPOPT's defaults are 5 and 5; leap's `max_filter_resets` default is
    /// 0, off, see below): when in `filter_reset_trigger`
    /// successive filter line searches the last trial rejected was
    /// dominated by a filter entry, the filter is emptied before the next
    /// one, at most `max_filter_resets` times per solve. An entry left by an
    /// iterate that came unusually close to the constraints at a low
    /// objective blocks every step that trades a little objective for a
    /// lot of feasibility, which is what a Newton step near the optimum
    /// does: on `models/jump_gait2392.json` (28 intervals) the full step
    /// that reduced the violation 44% at a cost of 8e-6 in J was refused 17
    /// times in a row, the line search took steps of 1e-5 instead, and the
    /// solve cycled until its iteration limit.
    ///
    /// It counts more than IPOPT does: a dominated trial counts even when
    /// it also fails the sufficient-decrease test against the current
    /// iterate (IPOPT counts only trials that pass that test), and a line
    /// search that accepts nothing (and falls back to the merit search)
    /// counts by its last trial too (IPOPT leaves the count alone). With
    /// IPOPT's count (and its reset on acceptance, which keeps the new
    /// entry) `jump_gait2392.json` still reached its 3,000-iteration limit
    /// (2026-12-07, 28.04 cm); with this one and
    /// `second_order_correction_every_rejected_step` it solves in 377
    /// iterations, with either alone it cycles. Off by default: with both
    /// on, the reduced jump by Hermite–Simpson (a CI test) reached its
    /// 1,000-iteration limit instead of solving, and with
    /// `--hessian exact-inertia-corrected` the default study's 26-interval
    /// mesh ended "infeasible" (the other shipped studies and the
    /// Hock–Schittkowski set kept or improved their results; docs/sqp.md).
    /// A study turns both on with its `line_search`
    /// ([`crate::study::LineSearchSpec`]), as `models/jump_gait2392.json`
    /// does.
    pub max_filter_resets: usize,
    /// See [`SqpSettings::max_filter_resets`].
    pub filter_reset_trigger: usize,
    /// Shrink the step bound Δ to half the step when a full plain-QP step
    /// achieved less than a quarter of the ℓ1-merit reduction its QP
    /// model predicted (the trust-region ratio test of Fletcher's Sℓ1QP);
    /// such a step does not grow Δ even when it reached it. Without the
    /// test Δ moves only with the line search,
    /// and full steps that the filter accepts can cycle: on the jump,
    /// consecutive steps of equal size and opposite sign (cos = −0.99)
    /// for hundreds of iterations.
    pub trust_region_ratio: bool,
    /// With `verbose`: for each rejected full step, the objective and
    /// violation changes and the constraints that grew most.
    pub verbose_line_search: bool,
    /// Stop as [`SqpStatus::RestorationFailed`] when the last
    /// `stall_iterations` iterations made no progress: the violation (the
    /// largest row violation with the rows scaled as the solver scales them,
    /// by at most 1: at most the log's `inf_pr`, on the jump about a tenth
    /// of it) stayed above `stall_violation` and never fell 10%
    /// below its value at the window's start, while the objective moved
    /// less than 1e-3·(1 + |f|). 0 turns the test off. Default 50: the
    /// full jump with Hermite–Simpson stalls in elastic mode at a scaled
    /// violation of 3.7e-3 (falling 2% in 40 iterations, objective range 8.6e-5) and
    /// would otherwise run 3,000 iterations; no window of the solves that
    /// converge (the jump with every scheme and study of the README) met
    /// the violation part of the test alone.
    pub stall_iterations: usize,
    /// The violation above which [`SqpSettings::stall_iterations`] counts
    /// (default 1e-3, the paper's constraint tolerance).
    pub stall_violation: f64,
    /// BFGS's first scaling of the identity: false (default) Shanno and
    /// Phua's yᵀy/sᵀy, the largest curvature the first step saw; true
    /// Oren and Luenberger's sᵀy/sᵀs, the curvature along the step, never
    /// larger.
    pub bfgs_scaling_along_step: bool,
    /// When set (by `leap solve` on Ctrl-C), the solve stops at the next
    /// iteration with status [`SqpStatus::UserRequestedStop`] and returns
    /// its iterate, as at the iteration limit.
    pub interrupt: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

impl Default for SqpSettings {
    fn default() -> Self {
        SqpSettings {
            optim_convergence_tolerance: 1e-6,
            optim_constraint_tolerance: 1e-8,
            max_iterations: 3000,
            hessian: HessianMode::PartitionedBfgs,
            convexification: Convexification::Clip,
            eigenvalue_floor: 1e-8,
            block_diagonal_elements: false,
            paper_criterion: false,
            paper_criterion_dual_infeasibility: 1.0,
            best_iterate_violation: 1e-3,
            acceptable_convergence_tolerance: 1e-5,
            acceptable_constraint_tolerance: 1e-6,
            acceptable_iterations: 15,
            initial_step_bound: 10.0,
            unbounded_objective: -1e20,
            qp_tolerance: 1e-10,
            qp_equilibrate: true,
            qp_warm_start: true,
            qp_solver: QpSolver::Clarabel,
            second_order_correction: true,
            second_order_correction_every_rejected_step: false,
            verbose: false,
            qp_dump_dir: None,
            qp_dump_every: false,
            nlp_scaling: true,
            scale_variables_using_bounds: true,
            verbose_line_search: false,
            line_search: LineSearch::Filter,
            max_violation_growth: 100.0,
            max_filter_resets: 0,
            filter_reset_trigger: 5,
            trust_region_ratio: true,
            stall_iterations: 50,
            stall_violation: 1e-3,
            bfgs_scaling_along_step: false,
            interrupt: None,
        }
    }
}

/// How a solve ended (serialized by [`SqpStatus::name`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SqpStatus {
    /// Converged to the requested tolerances.
    Solved,
    /// Converged to the acceptable tolerances only.
    Acceptable,
    IterationLimit,
    /// A (local) minimiser of the constraint violation that violates the
    /// constraints: the problem is (locally) infeasible.
    Infeasible,
    /// The objective decreased without bound at feasible points.
    Unbounded,
    /// No step decreased the merit function at an infeasible point.
    RestorationFailed,
    /// No step decreased the merit function at a feasible point that is
    /// not a solution.
    LineSearchFailed,
    /// The QP solver failed, or evaluations are not finite at the start.
    NumericalError,
    /// The problem's evaluation returned an error.
    EvaluationError,
    /// The problem is malformed (bounds, elements, dimensions).
    InvalidProblem,
    /// Stopped on request ([`SqpSettings::interrupt`]).
    UserRequestedStop,
}

impl Serialize for SqpStatus {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl SqpStatus {
    /// The snake_case name the JSON and the tables give ("solved",
    /// "iteration_limit").
    pub fn name(self) -> &'static str {
        match self {
            SqpStatus::Solved => "solved",
            SqpStatus::Acceptable => "acceptable",
            SqpStatus::IterationLimit => "iteration_limit",
            SqpStatus::Infeasible => "infeasible",
            SqpStatus::Unbounded => "unbounded",
            SqpStatus::RestorationFailed => "restoration_failed",
            SqpStatus::LineSearchFailed => "line_search_failed",
            SqpStatus::NumericalError => "numerical_error",
            SqpStatus::EvaluationError => "evaluation_error",
            SqpStatus::InvalidProblem => "invalid_problem",
            SqpStatus::UserRequestedStop => "user_requested_stop",
        }
    }

    /// Solved or acceptable.
    pub fn success(self) -> bool {
        matches!(self, SqpStatus::Solved | SqpStatus::Acceptable)
    }
}

/// One iteration, as logged.
#[derive(Debug, Clone, Serialize, Default)]
pub struct IterationRecord {
    pub iter: usize,
    /// The objective in the problem's units.
    pub objective: f64,
    /// Largest constraint violation in the problem's units.
    pub inf_pr: f64,
    /// Scaled dual infeasibility ‖∇f + Jᵀλ + ζ‖∞ / s_d.
    pub inf_du: f64,
    /// Scaled complementarity.
    pub complementarity: f64,
    /// ∞-norm of the step taken (scaled variables): α‖d‖∞, or after a
    /// second-order correction the distance to the point it reached.
    pub step_norm: f64,
    /// The step bound Δ of the QP (|d_j| ≤ Δ).
    pub step_bound: f64,
    /// Actual over predicted ℓ1-merit reduction of a full step (NaN when
    /// not measured: shortened or corrected steps, or the test is off).
    pub model_ratio: f64,
    /// The line search's step length (0 when it failed: no step taken).
    pub alpha: f64,
    pub ls_trials: usize,
    pub qp_iterations: u32,
    /// "ok", "elastic", "soc", "failed".
    pub qp_mode: String,
    pub penalty: f64,
    pub merit: f64,
    pub hessian_skips: usize,
    /// τ of the QP's inertia correction (leap's interior-point solver with
    /// [`Convexification::InertiaCorrection`]): the multiple of I added to
    /// the Hessian of the equilibrated QP, whose entries are at most about
    /// 1, until it is convex on the QP's constraints; 0 where none was
    /// needed or in the other modes. IPOPT logs its counterpart as lg(rg).
    /// A τ near 1 or above outweighs much of the exact curvature.
    pub hessian_shift: f64,
    pub derivatives_s: f64,
    pub qp_s: f64,
    pub line_search_s: f64,
    pub hessian_s: f64,
    pub time_s: f64,
    /// The constraint row violated most at this iterate (in the problem's
    /// units; empty when none is violated), to see which part of the
    /// problem holds the solve back.
    pub max_violation_constraint: String,
    /// The row whose multiplier estimate |λ_i| is largest (the QP's
    /// multipliers of the previous step, in the problem's units), and that
    /// |λ_i|: the merit penalty follows the largest one, so this names
    /// the row that drives it (empty and 0 before the first QP).
    pub max_multiplier_constraint: String,
    pub max_multiplier: f64,
}

/// Where the time of a solve went (seconds).
#[derive(Debug, Clone, Copy, Serialize, Default)]
pub struct TimeSplit {
    pub derivatives_s: f64,
    pub hessian_s: f64,
    pub qp_s: f64,
    pub line_search_s: f64,
    pub other_s: f64,
    pub total_s: f64,
}

/// The outcome of [`solve`]: status, last iterate and history.
#[derive(Debug, Clone, Serialize)]
pub struct SqpResult {
    pub status: SqpStatus,
    pub message: String,
    pub x: Vec<f64>,
    /// Constraint multipliers λ (L = f + λᵀc; positive at an active upper
    /// bound).
    pub lambda: Vec<f64>,
    /// Bound multipliers ζ.
    pub zeta: Vec<f64>,
    pub objective: f64,
    pub constraint_violation: f64,
    pub dual_infeasibility: f64,
    pub iterations: usize,
    pub qp_iterations: u64,
    /// QPs that leap's interior-point solver could not solve and handed
    /// to clarabel ([`QpSolver::InteriorPoint`]).
    pub qp_fallbacks: usize,
    /// Of those, the ones clarabel found infeasible (the interior-point
    /// solver hands over a QP whose primal residual stops falling).
    pub qp_fallbacks_infeasible: usize,
    /// Wall time clarabel spent on those QPs (part of the QP time).
    pub qp_fallback_seconds: f64,
    /// Plain QPs that the interior-point solver took as infeasible because
    /// its primal residual stalled (the SQP went on with the elastic QP,
    /// or dropped that second-order correction).
    pub qp_stalls_taken_infeasible: usize,
    /// Filter resets made ([`SqpSettings::max_filter_resets`]).
    pub filter_resets: usize,
    pub hessian: HessianMode,
    pub time: TimeSplit,
    pub history: Vec<IterationRecord>,
}

impl SqpResult {
    /// Write the iteration history as CSV.
    pub fn write_history_csv(&self, path: &std::path::Path) -> std::io::Result<()> {
        write_history_csv(&self.history, path)
    }
}

/// The median of `v` (NaN when empty).
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let k = v.len();
    if k == 0 {
        f64::NAN
    } else if k % 2 == 1 {
        v[k / 2]
    } else {
        0.5 * (v[k / 2 - 1] + v[k / 2])
    }
}

/// How much the inertia correction damped a solve's QPs: over the
/// iterations whose QP was solved, how many needed τ > 0, their median
/// and largest τ (see [`IterationRecord::hessian_shift`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HessianShiftSummary {
    pub qps: usize,
    pub shifted: usize,
    pub median: f64,
    pub max: f64,
}

impl HessianShiftSummary {
    /// None where no QP needed a shift.
    pub fn of(history: &[IterationRecord]) -> Option<HessianShiftSummary> {
        let solved: Vec<f64> = history
            .iter()
            .filter(|r| !r.qp_mode.is_empty() && r.qp_mode != "failed")
            .map(|r| r.hessian_shift)
            .collect();
        let shifted: Vec<f64> = solved.iter().copied().filter(|&t| t > 0.0).collect();
        (!shifted.is_empty()).then(|| HessianShiftSummary {
            qps: solved.len(),
            shifted: shifted.len(),
            max: shifted.iter().fold(0.0f64, |a, &b| a.max(b)),
            median: median(shifted),
        })
    }
}

/// IPOPT's lg(rg) column: log10 of the Hessian regularisation, "-" where
/// there was none.
fn lg_rg(shift: f64) -> String {
    if shift > 0.0 {
        format!("{:.1}", shift.log10())
    } else {
        "-".into()
    }
}

/// Write iteration records as CSV (one header line, one row each), whole
/// or not at all ([`crate::io::write_output_with`]).
pub fn write_history_csv(
    history: &[IterationRecord],
    path: &std::path::Path,
) -> std::io::Result<()> {
    crate::io::write_output_with(path, |file| {
        let mut f = std::io::BufWriter::new(file);
        history_csv(history, &mut f)?;
        std::io::Write::flush(&mut f)
    })
}

fn history_csv(history: &[IterationRecord], f: &mut impl std::io::Write) -> std::io::Result<()> {
    writeln!(f, "iter,objective,inf_pr,inf_du,complementarity,step_norm,step_bound,model_ratio,alpha,ls_trials,qp_iterations,qp_mode,penalty,merit,hessian_skips,hessian_shift,derivatives_s,qp_s,line_search_s,hessian_s,time_s,max_violation_constraint,max_multiplier_constraint,max_multiplier")?;
    // RFC 4180: a name holding a comma or quote is quoted, quotes doubled.
    let field = |name: &str| {
        if name.contains([',', '"', '\n']) {
            format!("\"{}\"", name.replace('"', "\"\""))
        } else {
            name.to_string()
        }
    };
    for r in history {
        writeln!(
            f,
            "{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{},{:e},{:e},{},{:e},{:e},{:e},{:e},{:e},{:e},{},{},{:e}",
            r.iter,
            r.objective,
            r.inf_pr,
            r.inf_du,
            r.complementarity,
            r.step_norm,
            r.step_bound,
            r.model_ratio,
            r.alpha,
            r.ls_trials,
            r.qp_iterations,
            r.qp_mode,
            r.penalty,
            r.merit,
            r.hessian_skips,
            r.hessian_shift,
            r.derivatives_s,
            r.qp_s,
            r.line_search_s,
            r.hessian_s,
            r.time_s,
            field(&r.max_violation_constraint),
            field(&r.max_multiplier_constraint),
            r.max_multiplier
        )?;
    }
    Ok(())
}

/// The problem's data fixed for a solve.
struct Problem {
    n: usize,
    m: usize,
    xl: Vec<f64>,
    xu: Vec<f64>,
    cl: Vec<f64>,
    cu: Vec<f64>,
    jac: Vec<(usize, usize)>,
    elements: Vec<Element>,
    /// Element of each constraint row.
    owner: Vec<usize>,
    objective_element: Option<usize>,
    /// Factors back to the problem's units of each constraint row and of
    /// the objective (1 unless the solver scaled the problem).
    row_unscale: Vec<f64>,
    objective_unscale: f64,
}

/// The index and value of the largest positive value (None when none is
/// positive; NaN values are passed over).
fn largest_positive(values: impl Iterator<Item = f64>) -> Option<(usize, f64)> {
    values
        .enumerate()
        .filter(|&(_, v)| v > 0.0)
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

impl Problem {
    fn read<N: Nlp + ?Sized>(nlp: &N) -> Result<Problem, String> {
        let (n, m) = (nlp.num_variables(), nlp.num_constraints());
        let (mut xl, mut xu) = (vec![0.0; n], vec![0.0; n]);
        nlp.variable_bounds(&mut xl, &mut xu);
        let (mut cl, mut cu) = (vec![0.0; m], vec![0.0; m]);
        nlp.constraint_bounds(&mut cl, &mut cu);
        for j in 0..n {
            if xl[j].is_nan()
                || xu[j].is_nan()
                || xl[j] > xu[j]
                || xl[j] >= INFINITE_BOUND
                || xu[j] <= -INFINITE_BOUND
            {
                return Err(format!(
                    "variable {}: bounds [{}, {}] are not a non-empty interval",
                    nlp.variable_name(j),
                    xl[j],
                    xu[j]
                ));
            }
        }
        for i in 0..m {
            if cl[i].is_nan()
                || cu[i].is_nan()
                || cl[i] > cu[i]
                || cl[i] >= INFINITE_BOUND
                || cu[i] <= -INFINITE_BOUND
            {
                return Err(format!(
                    "constraint {}: bounds [{}, {}] are not a non-empty interval",
                    nlp.constraint_name(i),
                    cl[i],
                    cu[i]
                ));
            }
        }
        let jac = nlp.jacobian_structure();
        let mut seen = std::collections::HashSet::with_capacity(jac.len());
        for &(i, j) in &jac {
            if i >= m || j >= n {
                return Err(format!("Jacobian entry ({i}, {j}) is outside {m}×{n}"));
            }
            if !seen.insert((i, j)) {
                return Err(format!("Jacobian entry ({i}, {j}) is listed twice"));
            }
        }
        let elements = nlp.elements();
        check_elements(&elements, n, m)?;
        let mut owner = vec![0; m];
        for (e, el) in elements.iter().enumerate() {
            for &i in &el.constraints {
                owner[i] = e;
            }
        }
        for &(i, j) in &jac {
            if elements[owner[i]].variables.binary_search(&j).is_err() {
                return Err(format!(
                    "Jacobian entry ({}, {}) lies outside the variables of element {}",
                    nlp.constraint_name(i),
                    nlp.variable_name(j),
                    owner[i]
                ));
            }
        }
        let objective_element = elements.iter().position(|e| e.objective);
        Ok(Problem {
            n,
            m,
            xl,
            xu,
            cl,
            cu,
            jac,
            elements,
            owner,
            objective_element,
            row_unscale: vec![1.0; m],
            objective_unscale: 1.0,
        })
    }

    /// How far c_i lies outside [c_l, c_u] (0 inside).
    fn row_violation(&self, c: &[f64], i: usize) -> f64 {
        (self.cl[i] - c[i]).max(c[i] - self.cu[i]).max(0.0)
    }

    /// out += s·J d, with J's values `jv`.
    fn add_jacobian_times(&self, jv: &[f64], d: &[f64], s: f64, out: &mut [f64]) {
        for (k, &(i, j)) in self.jac.iter().enumerate() {
            out[i] += s * jv[k] * d[j];
        }
    }

    /// The row violated most in the problem's units, with its violation
    /// (None when every row holds).
    fn max_violation_row(&self, c: &[f64]) -> Option<(usize, f64)> {
        largest_positive((0..self.m).map(|i| self.row_violation(c, i) * self.row_unscale[i]))
    }

    /// The row with the largest multiplier in the problem's units
    /// (λ_i · s_i / s_f for the scaled row i), with |λ_i| (None when all
    /// are zero).
    fn max_multiplier_row(&self, lambda: &[f64]) -> Option<(usize, f64)> {
        largest_positive(
            (0..self.m).map(|i| (lambda[i] * self.objective_unscale / self.row_unscale[i]).abs()),
        )
    }

    fn violation(&self, c: &[f64]) -> (f64, f64) {
        let (mut l1, mut inf) = (0.0f64, 0.0f64);
        for i in 0..self.m {
            let v = self.row_violation(c, i);
            l1 += v;
            inf = inf.max(v);
        }
        (l1, inf)
    }
}

/// ½ dᵀBd of the QP's Hessian model, from its element blocks.
fn model_curvature(elements: &[Element], blocks: &[Vec<f64>], d: &[f64]) -> f64 {
    let mut sum = 0.0;
    for (el, b) in elements.iter().zip(blocks) {
        let k = el.variables.len();
        for (a, &ja) in el.variables.iter().enumerate() {
            let row = &b[a * k..(a + 1) * k];
            let bd: f64 = row
                .iter()
                .zip(&el.variables)
                .map(|(v, &jb)| v * d[jb])
                .sum();
            sum += d[ja] * bd;
        }
    }
    0.5 * sum
}

/// Why the solve has stalled ([`SqpSettings::stall_iterations`]), from
/// the (violation, objective) of every iterate so far.
fn stalled(progress: &[(f64, f64)], window: usize, violation: f64) -> Option<String> {
    let n = progress.len();
    if window == 0 || n <= window {
        return None;
    }
    let w = &progress[n - 1 - window..];
    let (v0, f_last) = (w[0].0, w[window].1);
    let v_min = w.iter().fold(f64::INFINITY, |a, &(v, _)| a.min(v));
    let (f_min, f_max) = w
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(_, f)| {
            (lo.min(f), hi.max(f))
        });
    let stuck =
        v_min > violation && v_min > 0.9 * v0 && f_max - f_min <= 1e-3 * (1.0 + f_last.abs());
    stuck.then(|| {
        format!(
            "no progress in {window} iterations: the violation stayed above {violation:e} and fell only from {v0:e} to {v_min:e}, the objective moved {:e}",
            f_max - f_min
        )
    })
}

/// The iterate kept for [`SqpSettings::best_iterate_violation`].
struct BestIterate {
    iter: usize,
    inf_du: f64,
    /// Largest violation in the problem's units.
    inf_units: f64,
    x: Vec<f64>,
    f: f64,
    c: Vec<f64>,
    lambda: Vec<f64>,
    zeta: Vec<f64>,
}

/// The iterate's evaluations.
struct Point {
    x: Vec<f64>,
    f: f64,
    c: Vec<f64>,
    g: Vec<f64>,
    jv: Vec<f64>,
}

fn eval_fc<N: Nlp + ?Sized>(nlp: &mut N, x: &[f64], c: &mut [f64]) -> Result<f64, EvalError> {
    let f = nlp.objective(x)?;
    nlp.constraints(x, c)?;
    if !f.is_finite() {
        return Err(EvalError::new("objective", format!("not finite ({f})")));
    }
    if let Some(i) = c.iter().position(|v| !v.is_finite()) {
        return Err(EvalError::new(
            "constraints",
            format!("{}: not finite ({})", nlp.constraint_name(i), c[i]),
        ));
    }
    Ok(f)
}

fn eval_derivatives<N: Nlp + ?Sized>(nlp: &mut N, p: &mut Point) -> Result<(), EvalError> {
    nlp.gradient(&p.x, &mut p.g)?;
    nlp.jacobian_values(&p.x, &mut p.jv)?;
    if let Some(j) = p.g.iter().position(|v| !v.is_finite()) {
        return Err(EvalError::new(
            "gradient",
            format!("{}: not finite", nlp.variable_name(j)),
        ));
    }
    if p.jv.iter().any(|v| !v.is_finite()) {
        return Err(EvalError::new("jacobian", "an entry is not finite"));
    }
    Ok(())
}

/// Gradients of every element's part of the Lagrangian, σ∇f (objective
/// element) + Σ_{i∈e} λ_i ∇c_i, over the element's variables: O(nnz + Σk).
fn all_element_gradients(
    pb: &Problem,
    g: &[f64],
    jv: &[f64],
    lambda: &[f64],
    out: &mut [Vec<f64>],
) {
    for (e, el) in pb.elements.iter().enumerate() {
        out[e].iter_mut().for_each(|v| *v = 0.0);
        if pb.objective_element == Some(e) {
            for (a, &j) in el.variables.iter().enumerate() {
                out[e][a] = g[j];
            }
        }
    }
    for (k, &(i, j)) in pb.jac.iter().enumerate() {
        let e = pb.owner[i];
        if let Ok(a) = pb.elements[e].variables.binary_search(&j) {
            out[e][a] += lambda[i] * jv[k];
        }
    }
}

/// Replace the eigenvalues μ of a symmetric k×k matrix by max(μ, δ_s)
/// (clip) or max(|μ|, δ_s) (absolute), with δ_s = δ·max(1, max|μ|); leave
/// it as it is for the inertia correction (the QP solver convexifies).
fn convexify(h: &mut [f64], k: usize, delta: f64, how: Convexification) {
    if k == 0 || how == Convexification::InertiaCorrection {
        return;
    }
    let m = DMatrix::from_row_slice(k, k, h);
    let m = (&m + m.transpose()) * 0.5;
    let eig = SymmetricEigen::new(m);
    let scale = eig
        .eigenvalues
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs()))
        .max(1.0);
    let floor = delta * scale;
    let vals = match how {
        Convexification::Clip => eig.eigenvalues.map(|v| v.max(floor)),
        Convexification::Absolute => eig.eigenvalues.map(|v| v.abs().max(floor)),
        Convexification::InertiaCorrection => eig.eigenvalues.clone(),
    };
    let r = &eig.eigenvectors * DMatrix::from_diagonal(&vals) * eig.eigenvectors.transpose();
    for a in 0..k {
        for b in 0..k {
            h[a * k + b] = r[(a, b)];
        }
    }
}

/// [`convexify`] each diagonal block of a k×k matrix (`blocks`: a
/// partition of 0..k) by itself and zero the entries between blocks.
fn convexify_blocks(
    h: &mut [f64],
    k: usize,
    blocks: &[Vec<usize>],
    delta: f64,
    how: Convexification,
) {
    let mut sub = Vec::new();
    let mut out = vec![0.0; k * k];
    for members in blocks {
        let kb = members.len();
        sub.clear();
        for &a in members {
            sub.extend(members.iter().map(|&b| h[a * k + b]));
        }
        convexify(&mut sub, kb, delta, how);
        for (i, &a) in members.iter().enumerate() {
            for (j, &b) in members.iter().enumerate() {
                out[a * k + b] = sub[i * kb + j];
            }
        }
    }
    h.copy_from_slice(&out);
}

/// One thread's share of [`convexify_elements`]: elements and their blocks.
type Part<'a> = Vec<(&'a Element, &'a mut Vec<f64>)>;

/// [`convexify`] (or [`convexify_blocks`]) every element's block, on as
/// many threads as the machine has where the eigenvalue work is large
/// (on the jump: 28 blocks of 86 × 86, about 20 ms per SQP iteration on
/// one thread); the elements go to the threads in turn.
fn convexify_elements(
    elements: &[Element],
    blocks: &mut [Vec<f64>],
    floor: f64,
    how: Convexification,
) {
    let one = |el: &Element, b: &mut Vec<f64>| {
        let k = el.variables.len();
        if el.blocks.is_empty() {
            convexify(b, k, floor, how);
        } else {
            convexify_blocks(b, k, &el.blocks, floor, how);
        }
    };
    let work: usize = elements.iter().map(|el| el.variables.len().pow(3)).sum();
    let threads = if work < 1_000_000 {
        1
    } else {
        std::thread::available_parallelism()
            .map_or(1, |n| n.get())
            .min(elements.len())
    };
    if threads <= 1 {
        for (el, b) in elements.iter().zip(blocks.iter_mut()) {
            one(el, b);
        }
        return;
    }
    let mut parts: Vec<Vec<(&Element, &mut Vec<f64>)>> = (0..threads).map(|_| Vec::new()).collect();
    for (e, pair) in elements.iter().zip(blocks.iter_mut()).enumerate() {
        parts[e % threads].push(pair);
    }
    // Each part in a slot that its thread takes: a part whose thread the
    // system refuses (a process limit) stays there for this thread.
    let slots: Vec<std::sync::Mutex<Part>> = parts.into_iter().map(std::sync::Mutex::new).collect();
    let run = |slot: &std::sync::Mutex<Part>| {
        let part = match slot.lock() {
            Ok(mut g) => std::mem::take(&mut *g),
            Err(p) => std::mem::take(&mut *p.into_inner()),
        };
        for (el, b) in part {
            one(el, b);
        }
    };
    std::thread::scope(|s| {
        for slot in slots.iter().skip(1) {
            // Refused: left in its slot, run below.
            let _ = std::thread::Builder::new().spawn_scoped(s, move || run(slot));
        }
        for slot in &slots {
            run(slot);
        }
    });
}

/// Damped BFGS update of B (k×k row-major) with step s and gradient
/// change y (Powell 1978). Returns false when skipped.
fn bfgs_update(
    b: &mut [f64],
    s: &[f64],
    y: &[f64],
    first: &mut bool,
    floor: f64,
    along_step: bool,
) -> bool {
    let k = s.len();
    let ss: f64 = s.iter().map(|v| v * v).sum();
    if ss < 1e-300 {
        return false;
    }
    let sy: f64 = s.iter().zip(y).map(|(a, b)| a * b).sum();
    if *first {
        // Scale the initial identity to the curvature seen (Shanno & Phua).
        // The lower limit is the exact mode's eigenvalue floor (it was
        // 1e-6): on a plateau such as hs025's start the curvature is tiny,
        // and a larger limit caps the steps at ‖g‖/limit.
        let yy: f64 = y.iter().map(|v| v * v).sum();
        if sy > 1e-12 * ss.sqrt() * yy.sqrt() && sy > 0.0 {
            let gamma = if along_step { sy / ss } else { yy / sy }.clamp(floor, 1e6);
            for a in 0..k {
                for c in 0..k {
                    b[a * k + c] = if a == c { gamma } else { 0.0 };
                }
            }
            *first = false;
        }
    }
    let mut bs = vec![0.0; k];
    for a in 0..k {
        bs[a] = (0..k).map(|c| b[a * k + c] * s[c]).sum();
    }
    let sbs: f64 = s.iter().zip(&bs).map(|(a, b)| a * b).sum();
    if sbs <= 1e-300 {
        return false;
    }
    let theta = if sy >= 0.2 * sbs {
        1.0
    } else {
        0.8 * sbs / (sbs - sy)
    };
    let r: Vec<f64> = (0..k)
        .map(|a| theta * y[a] + (1.0 - theta) * bs[a])
        .collect();
    let sr: f64 = s.iter().zip(&r).map(|(a, b)| a * b).sum();
    if sr <= 1e-300 {
        return false;
    }
    // A step too short to measure curvature (an element whose variables
    // barely moved while round-off changed its gradient) would add a
    // curvature rᵀr/sᵀr of 1e20 and more: skip it. Curvature above 1e10 has
    // no meaning in a scaled problem.
    let rr: f64 = r.iter().map(|v| v * v).sum();
    if rr / sr > 1e10 {
        return false;
    }
    for a in 0..k {
        for c in 0..k {
            b[a * k + c] += r[a] * r[c] / sr - bs[a] * bs[c] / sbs;
        }
    }
    true
}

/// The failure message of a QP outcome, if it failed.
fn qp_failure(outcome: &Result<QpOutcome, String>) -> Option<String> {
    match outcome {
        Ok(QpOutcome::Solved) => None,
        Ok(other) => Some(format!("{other:?}")),
        Err(e) => Some(e.clone()),
    }
}

/// max |v_i| (0 for an empty slice).
pub(crate) fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |a, x| a.max(x.abs()))
}

struct Measures {
    inf_du: f64,
    compl: f64,
}

/// Largest divisor of the dual infeasibility and complementarity: they are
/// scaled by the mean multiplier size only up to 1e4 · s_max = 1e6.
const S_D_LIMIT: f64 = 1e4;

/// Scaled dual infeasibility and complementarity at p with (λ, ζ).
fn measures(pb: &Problem, p: &Point, lambda: &[f64], zeta: &[f64]) -> Measures {
    let mut r = p.g.clone();
    for (k, &(i, j)) in pb.jac.iter().enumerate() {
        r[j] += lambda[i] * p.jv[k];
    }
    for j in 0..pb.n {
        r[j] += zeta[j];
    }
    let s_max = 100.0;
    let sum: f64 = lambda.iter().chain(zeta.iter()).map(|v| v.abs()).sum();
    // IPOPT's s_d grows without limit with the multipliers. Where no KKT
    // multipliers exist (MFCQ fails, hs013) they diverge along the
    // iterates, and an unlimited s_d divides a dual residual that stays
    // O(1) down to any tolerance: a point 7e-5 from x* passed as solved.
    // Multipliers beyond s_max · S_D_LIMIT no longer loosen the test.
    let s_d = ((sum / ((pb.n + pb.m).max(1) as f64)).max(s_max) / s_max).min(S_D_LIMIT);
    let mut compl = 0.0f64;
    for i in 0..pb.m {
        if pb.cl[i] == pb.cu[i] {
            continue;
        }
        let l = lambda[i];
        let slack = if l > 0.0 {
            pb.cu[i] - p.c[i]
        } else {
            p.c[i] - pb.cl[i]
        };
        if slack.is_finite() {
            compl = compl.max((l * slack).abs());
        }
    }
    for j in 0..pb.n {
        if pb.xl[j] == pb.xu[j] {
            continue;
        }
        let z = zeta[j];
        let slack = if z > 0.0 {
            pb.xu[j] - p.x[j]
        } else {
            p.x[j] - pb.xl[j]
        };
        if slack.is_finite() && slack.abs() < INFINITE_BOUND {
            compl = compl.max((z * slack).abs());
        }
    }
    Measures {
        inf_du: norm_inf(&r) / s_d,
        compl: compl / s_d,
    }
}

/// Solve `nlp` from its initial point.
pub fn solve<N: Nlp + ?Sized>(nlp: &mut N, settings: &SqpSettings) -> SqpResult {
    let mut x0 = vec![0.0; nlp.num_variables()];
    nlp.initial_point(&mut x0);
    solve_from(nlp, &x0, settings)
}

/// Solve `nlp` from `x0` (projected into the variable bounds).
pub fn solve_from<N: Nlp + ?Sized>(nlp: &mut N, x0: &[f64], settings: &SqpSettings) -> SqpResult {
    if settings.scale_variables_using_bounds && x0.len() == nlp.num_variables() {
        let mut scaled = crate::nlp::ScaledVariables::from_bounds(nlp);
        let xs = scaled.scale_point(x0);
        let mut r = solve_unscaled(&mut scaled, &xs, settings);
        r.x = scaled.unscale(&r.x);
        for (z, d) in r.zeta.iter_mut().zip(&scaled.scale) {
            *z /= d;
        }
        return r;
    }
    solve_unscaled(nlp, x0, settings)
}

fn solve_unscaled<N: Nlp + ?Sized>(nlp: &mut N, x0: &[f64], settings: &SqpSettings) -> SqpResult {
    let start = Instant::now();
    let hessian = settings.hessian;
    let mut result = SqpResult {
        status: SqpStatus::InvalidProblem,
        message: String::new(),
        x: x0.to_vec(),
        lambda: vec![0.0; nlp.num_constraints()],
        zeta: vec![0.0; nlp.num_variables()],
        objective: f64::NAN,
        constraint_violation: f64::NAN,
        dual_infeasibility: f64::NAN,
        iterations: 0,
        qp_iterations: 0,
        qp_fallbacks: 0,
        qp_fallbacks_infeasible: 0,
        qp_fallback_seconds: 0.0,
        qp_stalls_taken_infeasible: 0,
        filter_resets: 0,
        hessian,
        time: TimeSplit::default(),
        history: Vec::new(),
    };
    let pb = match Problem::read(nlp) {
        Ok(pb) => pb,
        Err(e) => {
            result.message = e;
            return result;
        }
    };
    if x0.len() != pb.n {
        result.message = format!(
            "initial point has {} entries, the problem {} variables",
            x0.len(),
            pb.n
        );
        return result;
    }
    if hessian == HessianMode::ExactConvexified && !nlp.has_hessian() {
        result.message = "exact Hessian requested but the problem provides none".into();
        return result;
    }
    if hessian == HessianMode::ExactConvexified
        && settings.convexification == Convexification::InertiaCorrection
        && settings.qp_solver != QpSolver::InteriorPoint
    {
        result.message =
            "the inertia correction needs the interior-point QP solver (qp_solver interior-point)"
                .into();
        return result;
    }
    if !settings.nlp_scaling {
        let mut solver = Solver::new(pb, hessian, settings);
        solver.run(nlp, x0, &mut result, start, 0.0);
        return result;
    }
    let x0p: Vec<f64> = x0
        .iter()
        .enumerate()
        .map(|(j, &v)| v.clamp(pb.xl[j], pb.xu[j]))
        .collect();
    // The scaling's derivatives at the start are counted in the first
    // iteration's (a shooting problem's central-difference Jacobian takes
    // tens of seconds).
    let t = Instant::now();
    let mut scaled = GradientScaled::new(
        nlp,
        &x0p,
        pb.jac.clone(),
        settings.optim_convergence_tolerance,
    );
    let scaling_s = t.elapsed().as_secs_f64();
    let pb = match Problem::read(&scaled) {
        Ok(mut pb) => {
            pb.row_unscale = scaled.sc.iter().map(|s| 1.0 / s).collect();
            pb.objective_unscale = 1.0 / scaled.sf;
            pb
        }
        Err(e) => {
            result.message = e;
            return result;
        }
    };
    let mut solver = Solver::new(pb, hessian, settings);
    solver.run(&mut scaled, x0, &mut result, start, scaling_s);
    // Back to the problem's units (the log's objective and inf_pr are in
    // them already, its dual infeasibility scaled, as IPOPT's are).
    let (sf, sc) = (scaled.sf, scaled.sc.clone());
    result.objective /= sf;
    for (l, s) in result.lambda.iter_mut().zip(&sc) {
        *l *= s / sf;
    }
    for z in result.zeta.iter_mut() {
        *z /= sf;
    }
    if let Ok(v) = crate::nlp::constraint_violations(nlp, &result.x) {
        result.constraint_violation = v.into_iter().fold(0.0, f64::max);
    }
    result
}

/// IPOPT's gradient-based scaling (`nlp_scaling_method gradient-based`,
/// `nlp_scaling_max_gradient` 100): the objective and each constraint row
/// are multiplied by min(1, 100/‖∇‖∞) taken at the starting point, so no
/// gradient exceeds 100 there. A flat start (objective gradient below the
/// stationarity tolerance) has its objective scaled up instead, by
/// min(100, 1/‖∇f‖∞).
struct GradientScaled<'a, N: Nlp + ?Sized> {
    inner: &'a mut N,
    sf: f64,
    sc: Vec<f64>,
    jac_rows: Vec<usize>,
    lambda: Vec<f64>,
}

impl<'a, N: Nlp + ?Sized> GradientScaled<'a, N> {
    /// `flat_tolerance`: the stationarity tolerance; an objective gradient
    /// below it at x0 is scaled up.
    fn new(inner: &'a mut N, x0: &[f64], jac: Vec<(usize, usize)>, flat_tolerance: f64) -> Self {
        let (n, m) = (inner.num_variables(), inner.num_constraints());
        let factor = |max: f64| {
            if max.is_finite() && max > 100.0 {
                (100.0 / max).max(1e-8)
            } else {
                1.0
            }
        };
        let mut g = vec![0.0; n];
        let sf = if inner.gradient(x0, &mut g).is_ok() {
            let g_max = norm_inf(&g);
            if g_max > 0.0 && g_max < flat_tolerance {
                // A flat start: the objective's gradient at x0 already
                // passes the stationarity test, which then cannot tell the
                // start from a minimiser (hs025 begins on a plateau with
                // ‖∇f‖ = 2e-8 and stops there). Scale the objective up, as
                // IPOPT's nlp_scaling_obj_target_gradient does, by at most
                // the factor 100 that gradient-based scaling takes off
                // steep problems, so x0 is no longer stationary in the
                // scaled problem.
                (1.0 / g_max).min(100.0)
            } else {
                factor(g_max)
            }
        } else {
            1.0
        };
        let mut jv = vec![0.0; jac.len()];
        let mut row_max = vec![0.0f64; m];
        if inner.jacobian_values(x0, &mut jv).is_ok() {
            for (k, &(i, _)) in jac.iter().enumerate() {
                row_max[i] = row_max[i].max(jv[k].abs());
            }
        }
        let sc = row_max.into_iter().map(factor).collect();
        GradientScaled {
            inner,
            sf,
            sc,
            jac_rows: jac.into_iter().map(|(i, _)| i).collect(),
            lambda: vec![0.0; m],
        }
    }
}

impl<N: Nlp + ?Sized> Nlp for GradientScaled<'_, N> {
    fn num_variables(&self) -> usize {
        self.inner.num_variables()
    }
    fn num_constraints(&self) -> usize {
        self.inner.num_constraints()
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        self.inner.variable_bounds(lower, upper)
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        self.inner.constraint_bounds(lower, upper);
        for i in 0..lower.len() {
            lower[i] *= self.sc[i];
            upper[i] *= self.sc[i];
        }
    }
    fn initial_point(&self, x: &mut [f64]) {
        self.inner.initial_point(x)
    }
    fn objective(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        Ok(self.inner.objective(x)? * self.sf)
    }
    fn gradient(&mut self, x: &[f64], g: &mut [f64]) -> Result<(), EvalError> {
        self.inner.gradient(x, g)?;
        g.iter_mut().for_each(|v| *v *= self.sf);
        Ok(())
    }
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        self.inner.constraints(x, c)?;
        c.iter_mut().zip(&self.sc).for_each(|(v, s)| *v *= s);
        Ok(())
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        self.inner.jacobian_structure()
    }
    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        self.inner.jacobian_values(x, values)?;
        for (v, &i) in values.iter_mut().zip(&self.jac_rows) {
            *v *= self.sc[i];
        }
        Ok(())
    }
    fn elements(&self) -> Vec<Element> {
        self.inner.elements()
    }
    fn has_hessian(&self) -> bool {
        self.inner.has_hessian()
    }
    fn element_hessian(
        &mut self,
        x: &[f64],
        e: usize,
        sigma: f64,
        lambda: &[f64],
        h: &mut [f64],
    ) -> Result<(), EvalError> {
        for i in 0..lambda.len() {
            self.lambda[i] = lambda[i] * self.sc[i];
        }
        self.inner
            .element_hessian(x, e, sigma * self.sf, &self.lambda, h)
    }
    fn element_hessians(
        &mut self,
        x: &[f64],
        sigma: f64,
        lambda: &[f64],
        blocks: &mut [Vec<f64>],
    ) -> Result<(), EvalError> {
        for i in 0..lambda.len() {
            self.lambda[i] = lambda[i] * self.sc[i];
        }
        self.inner
            .element_hessians(x, sigma * self.sf, &self.lambda, blocks)
    }
    fn variable_name(&self, i: usize) -> String {
        self.inner.variable_name(i)
    }
    fn constraint_name(&self, i: usize) -> String {
        self.inner.constraint_name(i)
    }
}

struct Solver<'s> {
    pb: Problem,
    mode: HessianMode,
    settings: &'s SqpSettings,
    /// Element Hessian blocks (row-major).
    blocks: Vec<Vec<f64>>,
    bfgs_first: Vec<bool>,
    qp: Option<Qp>,
    qp_elastic: Option<Qp>,
}

impl<'s> Solver<'s> {
    /// Every BFGS block back to the identity, rescaled at its next update.
    fn reset_bfgs(&mut self) {
        for (b, first) in self.blocks.iter_mut().zip(&mut self.bfgs_first) {
            let k = (b.len() as f64).sqrt().round() as usize;
            b.iter_mut().for_each(|v| *v = 0.0);
            for a in 0..k {
                b[a * k + a] = 1.0;
            }
            *first = true;
        }
    }

    fn new(mut pb: Problem, mode: HessianMode, settings: &'s SqpSettings) -> Self {
        if !(mode == HessianMode::ExactConvexified && settings.block_diagonal_elements) {
            for el in &mut pb.elements {
                el.blocks.clear();
            }
        }
        let blocks: Vec<Vec<f64>> = pb
            .elements
            .iter()
            .map(|el| {
                let k = el.variables.len();
                let mut b = vec![0.0; k * k];
                for a in 0..k {
                    b[a * k + a] = 1.0;
                }
                b
            })
            .collect();
        let bfgs_first = vec![true; pb.elements.len()];
        Solver {
            pb,
            mode,
            settings,
            blocks,
            bfgs_first,
            qp: None,
            qp_elastic: None,
        }
    }

    fn dump(&self, elastic: bool, iter: usize, what: &str) -> String {
        let Some(dir) = &self.settings.qp_dump_dir else {
            return String::new();
        };
        let qp = if elastic { &self.qp_elastic } else { &self.qp };
        let Some(qp) = qp else { return String::new() };
        if let Err(e) = std::fs::create_dir_all(dir) {
            return format!(" (QP not written: {}: {e})", dir.display());
        }
        let path = dir.join(format!("qp_iter{iter}_{what}.json"));
        match qp.dump(&path) {
            Ok(()) => format!(" (QP written to {})", path.display()),
            Err(e) => format!(" (QP not written: {e})"),
        }
    }

    /// Set the QP's vectors and matrices and solve; `c` stands for the
    /// constraint values (the second-order correction passes others).
    #[allow(clippy::too_many_arguments)]
    /// The second-order correction of a rejected full step d (Nocedal &
    /// Wright §18.3): the QP re-solved with c_soc = c(x + d) − J d, so its
    /// rows read J d̂ + c(x + d) − J d within bounds. Returns the corrected
    /// point with f and c there (None when the QP or the evaluation failed)
    /// and the QP's time.
    #[allow(clippy::type_complexity)]
    fn second_order_correction<N: Nlp + ?Sized>(
        &mut self,
        nlp: &mut N,
        p: &Point,
        d: &[f64],
        c_full: &[f64],
        delta: f64,
        rho: f64,
    ) -> (Option<(Vec<f64>, f64, Vec<f64>)>, f64) {
        let mut c_soc = c_full.to_vec();
        self.pb.add_jacobian_times(&p.jv, d, -1.0, &mut c_soc);
        let t = Instant::now();
        let soc = self.solve_qp(false, p, &c_soc, None, delta, rho, false);
        let dq = t.elapsed().as_secs_f64();
        let Ok(QpOutcome::Solved) = soc else {
            return (None, dq);
        };
        let q = self.qp.as_ref().expect("solved");
        let x: Vec<f64> = (0..self.pb.n)
            .map(|j| (p.x[j] + q.d[j]).clamp(self.pb.xl[j], self.pb.xu[j]))
            .collect();
        let mut c = vec![0.0; self.pb.m];
        match eval_fc(nlp, &x, &mut c) {
            Ok(f) => (Some((x, f, c)), dq),
            Err(_) => (None, dq),
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn solve_qp(
        &mut self,
        elastic: bool,
        p: &Point,
        c: &[f64],
        g_override: Option<&[f64]>,
        delta: f64,
        rho: f64,
        refresh_matrices: bool,
    ) -> Result<QpOutcome, String> {
        let Solver {
            pb,
            blocks,
            qp,
            qp_elastic,
            settings,
            ..
        } = self;
        let slot = if elastic { qp_elastic } else { qp };
        let qp = slot.get_or_insert_with(|| {
            let mut qp = Qp::new(
                &pb.xl,
                &pb.xu,
                &pb.cl,
                &pb.cu,
                &pb.jac,
                &pb.elements,
                elastic,
                settings.qp_tolerance,
                settings.qp_equilibrate,
                settings.qp_solver == QpSolver::InteriorPoint,
                settings.hessian == HessianMode::ExactConvexified
                    && settings.convexification == Convexification::InertiaCorrection,
            );
            qp.set_warm_start(settings.qp_warm_start);
            if settings.verbose {
                let (nv, rows, nnz_p, nnz_a) = qp.size();
                crate::errln!(
                    "{} QP: {nv} variables, {rows} rows, nnz(P) {nnz_p}, nnz(A) {nnz_a}",
                    if elastic { "elastic" } else { "plain" }
                );
            }
            qp
        });
        if refresh_matrices {
            qp.set_hessian(blocks, &pb.elements);
            qp.set_jacobian(&p.jv);
        }
        qp.set_vectors(
            g_override.unwrap_or(&p.g),
            c,
            &p.x,
            &pb.xl,
            &pb.xu,
            &pb.cl,
            &pb.cu,
            delta,
            rho,
        );
        qp.solve()
    }

    fn update_hessian<N: Nlp + ?Sized>(
        &mut self,
        nlp: &mut N,
        p: &Point,
        lambda: &[f64],
        prev: Option<(&Point, &[Vec<f64>])>,
        skips: &mut usize,
        floor: f64,
    ) -> Result<(), EvalError> {
        match self.mode {
            HessianMode::ExactConvexified => {
                nlp.element_hessians(&p.x, 1.0, lambda, &mut self.blocks)?;
                for (e, b) in self.blocks.iter().enumerate() {
                    if b.iter().any(|v| !v.is_finite()) {
                        return Err(EvalError::new(
                            "hessian",
                            format!("element {e}: an entry is not finite"),
                        ));
                    }
                }
                convexify_elements(
                    &self.pb.elements,
                    &mut self.blocks,
                    floor,
                    self.settings.convexification,
                );
            }
            HessianMode::PartitionedBfgs => {
                let Some((old, old_grads)) = prev else {
                    return Ok(());
                };
                let mut new_grads: Vec<Vec<f64>> = self
                    .pb
                    .elements
                    .iter()
                    .map(|el| vec![0.0; el.variables.len()])
                    .collect();
                all_element_gradients(&self.pb, &p.g, &p.jv, lambda, &mut new_grads);
                for (e, el) in self.pb.elements.iter().enumerate() {
                    let s: Vec<f64> = el.variables.iter().map(|&j| p.x[j] - old.x[j]).collect();
                    let y: Vec<f64> = new_grads[e]
                        .iter()
                        .zip(&old_grads[e])
                        .map(|(a, b)| a - b)
                        .collect();
                    if !bfgs_update(
                        &mut self.blocks[e],
                        &s,
                        &y,
                        &mut self.bfgs_first[e],
                        self.settings.eigenvalue_floor,
                        self.settings.bfgs_scaling_along_step,
                    ) {
                        *skips += 1;
                    }
                }
            }
        }
        Ok(())
    }

    fn run<N: Nlp + ?Sized>(
        &mut self,
        nlp: &mut N,
        x0: &[f64],
        result: &mut SqpResult,
        start: Instant,
        scaling_s: f64,
    ) {
        let (n, m) = (self.pb.n, self.pb.m);
        let st = self.settings;
        let mut x: Vec<f64> = x0
            .iter()
            .enumerate()
            .map(|(j, &v)| v.clamp(self.pb.xl[j], self.pb.xu[j]))
            .collect();
        if x.iter().any(|v| !v.is_finite()) {
            result.status = SqpStatus::InvalidProblem;
            result.message = "the initial point is not finite".into();
            return;
        }
        let mut p = Point {
            x: std::mem::take(&mut x),
            f: 0.0,
            c: vec![0.0; m],
            g: vec![0.0; n],
            jv: vec![0.0; self.pb.jac.len()],
        };
        let mut time = TimeSplit {
            derivatives_s: scaling_s,
            ..Default::default()
        };
        let t = Instant::now();
        match eval_fc(nlp, &p.x, &mut p.c) {
            Ok(f) => p.f = f,
            Err(e) => {
                result.status = SqpStatus::EvaluationError;
                result.message = format!("at the initial point: {e}");
                result.x = p.x;
                return;
            }
        }
        time.line_search_s += t.elapsed().as_secs_f64();
        let f_first = p.f;
        let mut lambda = vec![0.0; m];
        let mut zeta = vec![0.0; n];
        let mut nu = 0.0f64; // merit penalty
        let mut rho; // elastic weight, set at every iteration
        let scale_x = norm_inf(&p.x).max(1.0);
        let delta_0 = st.initial_step_bound * scale_x;
        let mut delta = delta_0;
        let mut prev: Option<(Point, Vec<Vec<f64>>)> = None;
        let mut acceptable_count = 0usize;
        let mut best: Option<BestIterate> = None;
        // (violation, objective) of the iterates, for the stall test.
        let mut progress: Vec<(f64, f64)> = Vec::new();
        // Filter (θ, f) pairs and the violation limits θ_max, θ_min, set at
        // the first iteration from θ₀ as IPOPT does.
        let mut filter: Vec<(f64, f64)> = Vec::new();
        let (mut theta_max, mut theta_min) = (f64::NAN, f64::NAN);
        // The filter reset heuristic: successive line searches whose last
        // rejected trial a filter entry rejected, and the resets so far.
        let (mut filter_rejections, mut filter_resets) = (0usize, 0usize);
        let mut last_f = f64::NAN;
        // Whether the step to the current iterate was taken whole (α = 1).
        let mut last_full_step = false;
        let mut skips = 0usize;
        // QP failures retried at a smaller step bound, and the last step's
        // norm.
        let mut qp_retries = 0usize;
        let mut last_step = f64::INFINITY;
        let finish = |result: &mut SqpResult,
                      status: SqpStatus,
                      msg: String,
                      p: &Point,
                      lambda: &[f64],
                      zeta: &[f64],
                      time: &mut TimeSplit,
                      pb: &Problem| {
            result.status = status;
            result.message = msg;
            result.x = p.x.clone();
            result.lambda = lambda.to_vec();
            result.zeta = zeta.to_vec();
            result.objective = p.f;
            result.constraint_violation = pb.violation(&p.c).1;
            time.total_s = start.elapsed().as_secs_f64();
            time.other_s = (time.total_s
                - time.derivatives_s
                - time.hessian_s
                - time.qp_s
                - time.line_search_s)
                .max(0.0);
            result.time = *time;
        };
        for iter in 0..=st.max_iterations {
            let mut rec = IterationRecord {
                iter,
                step_bound: delta,
                model_ratio: f64::NAN,
                ..Default::default()
            };
            // Derivatives at the iterate.
            let t = Instant::now();
            if let Err(e) = eval_derivatives(nlp, &mut p) {
                let dt = t.elapsed().as_secs_f64();
                time.derivatives_s += dt;
                // Not measured at this iterate (the last value is the
                // previous iterate's).
                result.dual_infeasibility = f64::NAN;
                finish(
                    result,
                    SqpStatus::EvaluationError,
                    e.to_string(),
                    &p,
                    &lambda,
                    &zeta,
                    &mut time,
                    &self.pb,
                );
                return;
            }
            let dt = t.elapsed().as_secs_f64();
            time.derivatives_s += dt;
            // The first iteration's record holds the scaling's too.
            rec.derivatives_s = if iter == 0 { dt + scaling_s } else { dt };
            // Optimality at (x, λ, ζ).
            let (viol1, inf_pr) = self.pb.violation(&p.c);
            // The largest violation in the problem's units and its row.
            let worst_row = self.pb.max_violation_row(&p.c);
            if let Some((i, _)) = worst_row {
                rec.max_violation_constraint = nlp.constraint_name(i);
            }
            if let Some((i, v)) = self.pb.max_multiplier_row(&lambda) {
                rec.max_multiplier_constraint = nlp.constraint_name(i);
                rec.max_multiplier = v;
            }
            let ms = measures(&self.pb, &p, &lambda, &zeta);
            // The constraints and the objective in the problem's units, as
            // IPOPT logs them (its `inf_pr` and `objective` are unscaled,
            // its `inf_du` scaled).
            let inf_units = worst_row.map_or(0.0, |(_, v)| v);
            let f_units = p.f * self.pb.objective_unscale;
            rec.objective = f_units;
            rec.inf_pr = inf_units;
            rec.inf_du = ms.inf_du;
            rec.complementarity = ms.compl;
            result.dual_infeasibility = ms.inf_du;
            result.iterations = iter;
            // Moco's optim_constraint_tolerance is IPOPT's constr_viol_tol:
            // the largest violation in the problem's units. (IPOPT also
            // asks the scaled violation to be within `tol`: the rows' scale
            // factors are at most 1, so it is within the constraint
            // tolerance, and so within `tol` too when, as by default, the
            // constraint tolerance is the smaller.)
            let solved = iter > 0
                && inf_units <= st.optim_constraint_tolerance
                && ms.inf_du <= st.optim_convergence_tolerance
                && ms.compl <= st.optim_convergence_tolerance;
            // The paper's criterion and the best iterate judge the
            // constraints and the objective in the problem's units too.
            // Only a change over a whole step counts: a step the line
            // search or the step bound cut short changes the objective
            // little wherever it is (the reduced jump with a smoother
            // activation switch was called solved after α = 0.03, at a
            // 2 cm fall; the 20-interval jump on a step the ratio test had
            // cut to half the step before, 2.8e-3 m below the J it reaches
            // when such steps do not count).
            let paper = st.paper_criterion
                && iter > 0
                && last_full_step
                && inf_units <= 1e-3
                && ms.inf_du <= st.paper_criterion_dual_infeasibility
                && (f_units - last_f).abs() < 1e-6 * (1.0 + f_units.abs());
            let acceptable = iter > 0
                && inf_units <= st.acceptable_constraint_tolerance
                && ms.inf_du <= st.acceptable_convergence_tolerance
                && ms.compl <= st.acceptable_convergence_tolerance;
            acceptable_count = if acceptable { acceptable_count + 1 } else { 0 };
            if st.best_iterate_violation > 0.0
                && inf_units <= st.best_iterate_violation
                && best.as_ref().is_none_or(|b: &BestIterate| p.f < b.f)
            {
                best = Some(BestIterate {
                    iter,
                    inf_units,
                    inf_du: ms.inf_du,
                    x: p.x.clone(),
                    f: p.f,
                    c: p.c.clone(),
                    lambda: lambda.clone(),
                    zeta: zeta.clone(),
                });
            }
            last_f = f_units;
            if solved || paper {
                self.log(&rec, start, result);
                let msg = if solved {
                    "optimal solution found"
                } else {
                    "objective change below 1e-6 with constraints within 1e-3 (Porsa et al. 2016)"
                };
                finish(
                    result,
                    SqpStatus::Solved,
                    msg.into(),
                    &p,
                    &lambda,
                    &zeta,
                    &mut time,
                    &self.pb,
                );
                return;
            }
            if acceptable_count >= st.acceptable_iterations.max(1) {
                self.log(&rec, start, result);
                finish(
                    result,
                    SqpStatus::Acceptable,
                    format!("acceptable level met for {acceptable_count} consecutive iterations"),
                    &p,
                    &lambda,
                    &zeta,
                    &mut time,
                    &self.pb,
                );
                return;
            }
            if inf_pr <= st.optim_constraint_tolerance * norm_inf(&p.x).max(1.0)
                && p.f < st.unbounded_objective
            {
                self.log(&rec, start, result);
                finish(
                    result,
                    SqpStatus::Unbounded,
                    format!(
                        "objective {f_units:e} (scaled {:e}, below {:e}) at a feasible point",
                        p.f, st.unbounded_objective
                    ),
                    &p,
                    &lambda,
                    &zeta,
                    &mut time,
                    &self.pb,
                );
                return;
            }
            // The stall test reads the solver's scaled violation and
            // objective, the units its thresholds were chosen in.
            progress.push((inf_pr, p.f));
            let stall = stalled(&progress, st.stall_iterations, st.stall_violation);
            let interrupted = st
                .interrupt
                .as_ref()
                .is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed));
            if iter == st.max_iterations || stall.is_some() || interrupted {
                self.log(&rec, start, result);
                let (status, mut msg) = match stall {
                    Some(why) if iter < st.max_iterations => (SqpStatus::RestorationFailed, why),
                    _ if interrupted && iter < st.max_iterations => (
                        SqpStatus::UserRequestedStop,
                        format!("stopped on request after {iter} iterations"),
                    ),
                    _ => (
                        SqpStatus::IterationLimit,
                        format!("{} iterations", st.max_iterations),
                    ),
                };
                if let Some(b) = best.filter(|b| b.iter != iter) {
                    if inf_units > st.best_iterate_violation || b.f < p.f {
                        msg += &format!(
                            "; returned iteration {} (objective {:e}, largest violation {:e}) instead of the last (objective {:e}, violation {:e})",
                            b.iter,
                            b.f * self.pb.objective_unscale,
                            b.inf_units,
                            f_units,
                            inf_units
                        );
                        result.dual_infeasibility = b.inf_du;
                        p.x = b.x;
                        p.f = b.f;
                        p.c = b.c;
                        lambda = b.lambda;
                        zeta = b.zeta;
                    }
                }
                finish(result, status, msg, &p, &lambda, &zeta, &mut time, &self.pb);
                return;
            }
            // Hessian model.
            let t = Instant::now();
            let old_grads = prev.as_ref().map(|(o, g)| (o, g.as_slice()));
            // The eigenvalue floor falls as the step bound grows past its
            // initial value: a direction without curvature is then held by
            // the step bound, as in a trust-region method, and not at
            // ‖g‖/floor, so iterates that run down an unbounded objective
            // grow geometrically and reach `unbounded_objective`.
            let floor = st.eigenvalue_floor * (delta_0 / delta).min(1.0);
            if let Err(e) = self.update_hessian(nlp, &p, &lambda, old_grads, &mut skips, floor) {
                time.hessian_s += t.elapsed().as_secs_f64();
                finish(
                    result,
                    SqpStatus::EvaluationError,
                    e.to_string(),
                    &p,
                    &lambda,
                    &zeta,
                    &mut time,
                    &self.pb,
                );
                return;
            }
            rec.hessian_s = t.elapsed().as_secs_f64();
            time.hessian_s += rec.hessian_s;
            rec.hessian_skips = skips;
            // QP: plain, then elastic when inconsistent.
            let t = Instant::now();
            // Elastic weight: from this iteration's gradient and the merit
            // penalty, raised below only for this iteration when the slacks
            // take up more than they must. A weight carried over from early,
            // badly infeasible iterations (1e8 and more) would put entries
            // of that size into later elastic QPs and break them.
            rho = (10.0 * (1.0 + norm_inf(&p.g))).max(nu);
            let mut elastic = false;
            let mut outcome = self.solve_qp(false, &p, &p.c, None, delta, rho, true);
            let mut qp_its = self.qp.as_ref().map_or(0, |q| q.iterations);
            if matches!(
                outcome,
                Ok(QpOutcome::Infeasible) | Ok(QpOutcome::Failed(_))
            ) {
                if matches!(outcome, Ok(QpOutcome::Failed(_))) {
                    self.dump(false, iter, "plain_failed");
                } else if st.qp_dump_every {
                    // The plain QP found (or, where the interior-point
                    // solver stalled, taken as) infeasible: replayable with
                    // clarabel to check that verdict (`examples/qp_replay`).
                    self.dump(false, iter, "plain_infeasible");
                }
                elastic = true;
                outcome = self.solve_qp(true, &p, &p.c, None, delta, rho, true);
                qp_its += self.qp_elastic.as_ref().map_or(0, |q| q.iterations);
            }
            rec.qp_s = t.elapsed().as_secs_f64();
            time.qp_s += rec.qp_s;
            rec.qp_mode = if elastic {
                "elastic".into()
            } else {
                "ok".into()
            };
            if st.qp_dump_every {
                self.dump(elastic, iter, "qp");
            }
            if let Some(msg) = qp_failure(&outcome) {
                // A QP that fails at a huge step bound after the objective
                // kept falling at feasible points: diverging iterates.
                let diverging = delta >= 1e6 * scale_x
                    && inf_pr <= st.optim_constraint_tolerance * norm_inf(&p.x).max(1.0)
                    && p.f < f_first - 1e6 * (1.0 + f_first.abs()) * f64::EPSILON.sqrt();
                if diverging {
                    rec.qp_mode = "failed".into();
                    rec.qp_iterations = qp_its;
                    self.log(&rec, start, result);
                    finish(result, SqpStatus::Unbounded, format!("diverging iterates: f = {f_units:e} falling at feasible points, step bound {delta:e}, QP {msg}"), &p, &lambda, &zeta, &mut time, &self.pb);
                    return;
                }
                let dump = self.dump(elastic, iter, "failed");
                rec.qp_mode = "failed".into();
                rec.qp_iterations = qp_its;
                self.log(&rec, start, result);
                // A smaller step bound makes the QP better conditioned (the
                // box rows bind); retry from the same point, whose Hessian
                // update is already done.
                if qp_retries < 4 && delta > 1e-6 * scale_x {
                    qp_retries += 1;
                    // From the second retry on, the quasi-Newton blocks
                    // start afresh (SNOPT resets its BFGS when the QP
                    // fails): their conditioning may be what failed.
                    if qp_retries >= 2 && self.mode == HessianMode::PartitionedBfgs {
                        self.reset_bfgs();
                    }
                    delta = (delta.min(10.0 * last_step) / 4.0).max(1e-6 * scale_x);
                    prev = None;
                    // The retry starts from the same point: Δf = 0 there
                    // says nothing of convergence.
                    last_full_step = false;
                    continue;
                }
                finish(
                    result,
                    SqpStatus::NumericalError,
                    format!("QP subproblem at iteration {iter}: {msg}{dump}"),
                    &p,
                    &lambda,
                    &zeta,
                    &mut time,
                    &self.pb,
                );
                return;
            }
            // Elastic mode: the slacks must take up only what the
            // linearisation cannot satisfy. Compare with the least
            // linearised violation (objective dropped); equal and no
            // reduction means a stationary point of the infeasibility;
            // otherwise raise ρ until the step reduces the violation
            // by a fair share of what is possible (SNOPT's elastic
            // weight rule).
            // The first elastic QP has already taken a fair share when it
            // removes a tenth of the violation itself: what is possible is
            // at most the whole violation, so neither the feasibility QP
            // nor a higher ρ can change the verdict (and the step is not
            // stationary). On the jump this skips two of the three extra QPs
            // of every elastic iteration.
            let fair_share_taken = || {
                let slack = self.qp_elastic.as_ref().map_or(viol1, |q| q.slack_sum);
                viol1 - slack >= 0.1 * viol1
            };
            if elastic && viol1 > st.optim_constraint_tolerance && !fair_share_taken() {
                let t = Instant::now();
                let zero = vec![0.0; n];
                let feas = self.solve_qp(true, &p, &p.c, Some(&zero), delta, 1.0, false);
                let least = match feas {
                    Ok(QpOutcome::Solved) => {
                        self.qp_elastic.as_ref().map_or(viol1, |q| q.slack_sum)
                    }
                    // No verdict without a solved feasibility QP.
                    _ => f64::NAN,
                };
                let possible = viol1 - least;
                // Relative to the violation itself: against max(viol, 1)
                // a small violation passed as stationary whenever the QP
                // reduced it by less than 1e-9 absolute (hs013 at x =
                // (1.0074, 0): 5e-11 of a violation of 4e-7, a feasible
                // problem called infeasible after 1573 iterations).
                if possible <= 1e-9 * viol1 {
                    time.qp_s += t.elapsed().as_secs_f64();
                    self.log(&rec, start, result);
                    finish(result, SqpStatus::Infeasible, format!("converged to a point of locally minimal constraint violation {inf_units:e} (largest row)"), &p, &lambda, &zeta, &mut time, &self.pb);
                    return;
                }
                if possible.is_finite() {
                    let mut tries = 0;
                    loop {
                        let outcome = self.solve_qp(true, &p, &p.c, None, delta, rho, false);
                        qp_its += self.qp_elastic.as_ref().map_or(0, |q| q.iterations);
                        if let Some(msg) = qp_failure(&outcome) {
                            time.qp_s += t.elapsed().as_secs_f64();
                            let dump = self.dump(true, iter, "failed");
                            self.log(&rec, start, result);
                            finish(
                                result,
                                SqpStatus::NumericalError,
                                format!("elastic QP subproblem at iteration {iter}: {msg}{dump}"),
                                &p,
                                &lambda,
                                &zeta,
                                &mut time,
                                &self.pb,
                            );
                            return;
                        }
                        let got = viol1 - self.qp_elastic.as_ref().map_or(viol1, |q| q.slack_sum);
                        tries += 1;
                        if got >= 0.1 * possible || tries >= 8 {
                            break;
                        }
                        rho *= 10.0;
                    }
                }
                let dt = t.elapsed().as_secs_f64();
                time.qp_s += dt;
                rec.qp_s += dt;
            }
            rec.qp_iterations = qp_its;
            result.qp_iterations += qp_its as u64;
            result.qp_fallbacks = self.qp.as_ref().map_or(0, |q| q.fallbacks)
                + self.qp_elastic.as_ref().map_or(0, |q| q.fallbacks);
            result.qp_fallbacks_infeasible = self.qp.as_ref().map_or(0, |q| q.fallbacks_infeasible)
                + self
                    .qp_elastic
                    .as_ref()
                    .map_or(0, |q| q.fallbacks_infeasible);
            result.qp_fallback_seconds = self.qp.as_ref().map_or(0.0, |q| q.fallback_seconds)
                + self.qp_elastic.as_ref().map_or(0.0, |q| q.fallback_seconds);
            result.qp_stalls_taken_infeasible =
                self.qp.as_ref().map_or(0, |q| q.stalls_taken_infeasible);
            let qp = if elastic {
                self.qp_elastic.as_ref()
            } else {
                self.qp.as_ref()
            }
            .expect("solved above");
            let d = qp.d.clone();
            let shift_curvature = qp.shift_curvature;
            rec.hessian_shift = qp.hessian_shift();
            let (lam_qp, zeta_qp) = (qp.lambda.clone(), qp.zeta.clone());
            let slack_sum = if elastic { qp.slack_sum } else { 0.0 };
            // Merit penalty ν ≥ ‖λ‖∞ with a margin; lowered again when the
            // multipliers fall well below it, so one bad iterate does not
            // freeze the merit function on feasibility.
            //
            // In elastic mode the multipliers of the linearised constraints
            // are the elastic weight ρ wherever a slack is active, and ρ is
            // at least ν: a margin on them would raise ν by 1.65 at every
            // elastic iteration, and ρ with it (the reduced jump at 24
            // intervals: 3e3 to 2e10 in 20 iterations, until the QPs
            // failed). The elastic step is a descent direction of the ℓ1
            // merit function with weight ρ itself (Fletcher's Sℓ1QP), so ν
            // only rises to ‖λ‖∞ there.
            let lam_max = norm_inf(&lam_qp);
            let needed = if elastic {
                lam_max
            } else {
                1.1 * lam_max + 1e-6
            };
            if nu < needed {
                nu = if elastic {
                    needed
                } else {
                    (1.5 * needed).max(1.5 * nu)
                };
            } else if nu > 10.0 * needed {
                nu = (nu / 10.0).max(1.5 * needed);
            }
            let gd: f64 = p.g.iter().zip(&d).map(|(a, b)| a * b).sum();
            let mut dphi = gd - nu * (viol1 - slack_sum);
            if dphi > 0.0 {
                // The QP step is not a descent direction of φ (only with
                // very inexact QPs); use a small multiple as Armijo slope.
                dphi = -1e-12 * (1.0 + p.f.abs());
            }
            let phi0 = p.f + nu * viol1;
            rec.penalty = nu;
            // Line search on φ with backtracking and one second-order
            // correction.
            let t = Instant::now();
            let mut alpha = 1.0;
            let mut trials = 0;
            let mut accepted: Option<(Vec<f64>, f64, Vec<f64>)> = None;
            let mut trial_c = vec![0.0; m];
            let mut trial_x = vec![0.0; n];
            let mut soc_tried = false;
            let dnorm = norm_inf(&d);
            let bound_hit = dnorm >= 0.999 * delta;
            let mut soc_used = false;
            let mut soc_qp_s = 0.0;
            let mut filter_accepted = false;
            if st.line_search == LineSearch::Filter && !elastic {
                if theta_max.is_nan() {
                    theta_max = 1e4 * viol1.max(1.0);
                    theta_min = 1e-4 * viol1.max(1.0);
                }
                let theta0 = viol1;
                // Ok(f-type) when the trial (θ, f) at step a is acceptable;
                // Err(true) when a filter entry dominates it (whatever the
                // test against the current iterate would say, see
                // `max_filter_resets`), Err(false) when a violation limit
                // or that test rejects it.
                let acceptable_trial = |th: f64, f: f64, a: f64, filter: &[(f64, f64)]| {
                    // Besides IPOPT's global θ_max, a local limit: a step
                    // that multiplies the violation by more than
                    // `max_violation_growth` left the region where the
                    // linearisation holds (stiff tendon and contact
                    // defects); backtracking shortens it and the step bound
                    // follows (a trust region on the constraints' curvature,
                    // as filter-SQP shrinks its trust region on rejected
                    // steps, Fletcher & Leyffer 2002). On the jump, 100
                    // beat both 10 (stuck near J = 1.248) and no limit
                    // (violation up to 10, then stalled in elastic mode).
                    if th.partial_cmp(&theta_max) != Some(std::cmp::Ordering::Less)
                        || th > st.max_violation_growth * theta0.max(theta_min)
                    {
                        return Err(false);
                    }
                    if filter.iter().any(|&(tj, fj)| th >= tj && f >= fj) {
                        return Err(true);
                    }
                    let switching = gd < 0.0 && a * (-gd).powf(2.3) > theta0.powf(1.1);
                    if theta0 <= theta_min && switching {
                        (f <= p.f + 1e-4 * a * gd + 10.0 * f64::EPSILON * p.f.abs())
                            .then_some(true)
                            .ok_or(false)
                    } else {
                        (th <= (1.0 - 1e-5) * theta0 || f <= p.f - 1e-8 * theta0)
                            .then_some(false)
                            .ok_or(false)
                    }
                };
                // IPOPT's filter reset ([`SqpSettings::max_filter_resets`]).
                if st.filter_reset_trigger > 0
                    && filter_rejections >= st.filter_reset_trigger
                    && filter_resets < st.max_filter_resets
                {
                    filter.clear();
                    filter_resets += 1;
                    result.filter_resets = filter_resets;
                    filter_rejections = 0;
                    if st.verbose_line_search {
                        crate::errln!(
                            "  filter reset ({filter_resets} of {})",
                            st.max_filter_resets
                        );
                    }
                }
                // Whether the last trial rejected was rejected by the filter.
                let mut by_filter = false;
                let mut a = 1.0;
                while a >= 1e-8 {
                    trials += 1;
                    for j in 0..n {
                        trial_x[j] = (p.x[j] + a * d[j]).clamp(self.pb.xl[j], self.pb.xu[j]);
                    }
                    if let Ok(f) = eval_fc(nlp, &trial_x, &mut trial_c) {
                        let (th, _) = self.pb.violation(&trial_c);
                        let verdict = acceptable_trial(th, f, a, &filter);
                        if a == 1.0 && verdict.is_err() && st.verbose_line_search {
                            self.log_rejected_step(nlp, &p, &d, (f, &trial_c), nu, delta);
                        }
                        if let Err(b) = verdict {
                            by_filter = b;
                        }
                        if let Ok(f_type) = verdict {
                            if !f_type {
                                filter.push(((1.0 - 1e-5) * theta0, p.f - 1e-8 * theta0));
                            }
                            accepted = Some((trial_x.clone(), f, trial_c.clone()));
                            filter_accepted = true;
                            alpha = a;
                            break;
                        }
                        if a == 1.0
                            && st.second_order_correction
                            && (th >= theta0 || st.second_order_correction_every_rejected_step)
                        {
                            soc_tried = true;
                            let (soc, dq) =
                                self.second_order_correction(nlp, &p, &d, &trial_c, delta, rho);
                            time.qp_s += dq;
                            rec.qp_s += dq;
                            soc_qp_s += dq;
                            if let Some((soc_x, f2, soc_c)) = soc {
                                let (th2, _) = self.pb.violation(&soc_c);
                                let verdict = acceptable_trial(th2, f2, 1.0, &filter);
                                if let Err(b) = verdict {
                                    by_filter = b;
                                }
                                if let Ok(f_type) = verdict {
                                    if !f_type {
                                        filter.push(((1.0 - 1e-5) * theta0, p.f - 1e-8 * theta0));
                                    }
                                    accepted = Some((soc_x, f2, soc_c));
                                    filter_accepted = true;
                                    soc_used = true;
                                    alpha = 1.0;
                                    break;
                                }
                            }
                        }
                    } else {
                        by_filter = false;
                    }
                    a *= 0.5;
                }
                filter_rejections = if by_filter { filter_rejections + 1 } else { 0 };
            }
            while !filter_accepted && alpha > 1e-12 {
                trials += 1;
                for j in 0..n {
                    trial_x[j] = (p.x[j] + alpha * d[j]).clamp(self.pb.xl[j], self.pb.xu[j]);
                }
                // Not finite at the trial point: shorten the step.
                if let Ok(f) = eval_fc(nlp, &trial_x, &mut trial_c) {
                    let (v1, _) = self.pb.violation(&trial_c);
                    let phi = f + nu * v1;
                    // Armijo with IPOPT's round-off allowance 10 ε |φ|.
                    if phi <= phi0 + 1e-4 * alpha * dphi + 10.0 * f64::EPSILON * phi0.abs() {
                        accepted = Some((trial_x.clone(), f, trial_c.clone()));
                        break;
                    }
                    // (The filter search logged its own full step.)
                    let filter_ran = st.line_search == LineSearch::Filter && !elastic;
                    if alpha == 1.0 && st.verbose_line_search && !filter_ran {
                        self.log_rejected_step(nlp, &p, &d, (f, &trial_c), nu, delta);
                    }
                    // Second-order correction (Nocedal & Wright §18.3)
                    // when the full step made the constraints worse.
                    if alpha == 1.0
                        && st.second_order_correction
                        && !soc_tried
                        && v1 > viol1
                        && !elastic
                    {
                        soc_tried = true;
                        let (soc, dq) =
                            self.second_order_correction(nlp, &p, &d, &trial_c, delta, rho);
                        time.qp_s += dq;
                        rec.qp_s += dq;
                        soc_qp_s += dq;
                        if let Some((soc_x, f2, soc_c)) = soc {
                            let (v2, _) = self.pb.violation(&soc_c);
                            if f2 + nu * v2 <= phi0 + 1e-4 * dphi {
                                accepted = Some((soc_x, f2, soc_c));
                                soc_used = true;
                                break;
                            }
                        }
                    }
                }
                alpha *= 0.5;
            }
            rec.line_search_s = t.elapsed().as_secs_f64() - soc_qp_s;
            time.line_search_s += rec.line_search_s;
            rec.ls_trials = trials;
            // The step taken: α·d, or after a second-order correction the
            // correction QP's (the point it reached, not d); none when the
            // line search failed.
            let taken = match &accepted {
                Some((x, _, _)) if soc_used => x
                    .iter()
                    .zip(&p.x)
                    .fold(0.0f64, |m, (a, b)| m.max((a - b).abs())),
                Some(_) => dnorm * alpha,
                None => 0.0,
            };
            rec.step_norm = taken;
            // (A QP failure's retry bounds its step by this.)
            last_step = taken.max(1e-12 * scale_x);
            rec.alpha = if accepted.is_some() { alpha } else { 0.0 };
            // A full step that the step bound cut short proves no more
            // than one the line search cut: the QP's own step was longer.
            last_full_step = alpha == 1.0 && accepted.is_some() && taken < 0.999 * delta;
            rec.merit = phi0;
            if soc_used {
                rec.qp_mode = "soc".into();
            }
            let Some((xn, fn_, cn)) = accepted else {
                self.log(&rec, start, result);
                // No decrease possible along d.
                let (status, msg) = if dnorm <= 1e-12 * scale_x
                    && inf_units <= st.acceptable_constraint_tolerance
                {
                    (
                        SqpStatus::Acceptable,
                        "step below 1e-12 at a feasible point".to_string(),
                    )
                } else if acceptable {
                    (
                        SqpStatus::Acceptable,
                        "no further progress; acceptable level met".to_string(),
                    )
                } else if inf_units > st.optim_constraint_tolerance {
                    (
                        SqpStatus::RestorationFailed,
                        format!(
                            "line search failed at an infeasible point (violation {inf_units:e})"
                        ),
                    )
                } else {
                    (
                        SqpStatus::LineSearchFailed,
                        "line search failed at a feasible point".to_string(),
                    )
                };
                finish(result, status, msg, &p, &lambda, &zeta, &mut time, &self.pb);
                return;
            };
            // Ratio of the actual to the predicted reduction of the ℓ1
            // merit φ = f + ν‖c‖₁ over the full step; the model is the
            // QP's: gᵀd + ½dᵀBd and the linearised constraints c + Jd.
            let ratio = if st.trust_region_ratio && alpha == 1.0 && !soc_used && !elastic {
                let mut lin = p.c.clone();
                self.pb.add_jacobian_times(&p.jv, &d, 1.0, &mut lin);
                let (lin1, _) = self.pb.violation(&lin);
                let curv = model_curvature(&self.pb.elements, &self.blocks, &d) + shift_curvature;
                let pred = -(gd + curv) + nu * (viol1 - lin1);
                let (v_new, _) = self.pb.violation(&cn);
                let ared = phi0 - (fn_ + nu * v_new);
                (pred > 1e-12 * (1.0 + phi0.abs())).then(|| ared / pred)
            } else {
                None
            };
            rec.model_ratio = ratio.unwrap_or(f64::NAN);
            self.log(&rec, start, result);
            // The step bound acts as a box trust region: it grows when a
            // full step reached it, shrinks to half a full step that the
            // model predicted badly (ratio below 1/4) and to twice the
            // accepted step when the line search had to cut the step short.
            qp_retries = 0;
            if alpha == 1.0 {
                match ratio {
                    Some(r) if r < 0.25 => {
                        delta = (0.5 * dnorm).max(1e-6 * scale_x).min(delta);
                    }
                    _ => {
                        if bound_hit {
                            delta *= 4.0;
                        }
                    }
                }
            } else {
                delta = (2.0 * alpha * dnorm).max(1e-3 * scale_x).min(delta);
            }
            // Multipliers: the QP's (a short step does not make the QP's
            // estimate worse, and blending slows the dual convergence).
            lambda.copy_from_slice(&lam_qp);
            zeta.copy_from_slice(&zeta_qp);
            // Element gradients at the old point with the new λ, for BFGS.
            // (None after an elastic step: no update from it, see below.)
            let grads = if self.mode == HessianMode::PartitionedBfgs && !elastic {
                let mut g: Vec<Vec<f64>> = self
                    .pb
                    .elements
                    .iter()
                    .map(|el| vec![0.0; el.variables.len()])
                    .collect();
                all_element_gradients(&self.pb, &p.g, &p.jv, &lambda, &mut g);
                g
            } else {
                Vec::new()
            };
            let old = std::mem::replace(
                &mut p,
                Point {
                    x: xn,
                    f: fn_,
                    c: cn,
                    g: vec![0.0; n],
                    jv: vec![0.0; self.pb.jac.len()],
                },
            );
            // No quasi-Newton update from an elastic step: its QP
            // multipliers are the elastic weight ρ on every row whose slack
            // is active, not estimates of the NLP's multipliers, and the
            // update would build the curvature of ρ·c into B (hs061's first
            // elastic steps: λ = (340, −247) against (−0.89, −1.74) at the
            // solution, B₂₂ = 1660 from −4λ₁, which held x₂ on the wrong
            // branch of 3x₁ − 2x₂² = 7 and ended at the local minimum
            // −81.919; without these updates the path reaches −143.646).
            prev = if elastic { None } else { Some((old, grads)) };
        }
    }

    /// With `verbose_line_search`: a rejected full step d to a trial
    /// point (its objective and constraints): its objective and
    /// violation changes, the rows whose violation grew most, and the rows
    /// most violated at the trial beside their linearised values c + J d,
    /// which tell the constraints' curvature from a QP that left them
    /// violated.
    fn log_rejected_step<N: Nlp + ?Sized>(
        &self,
        nlp: &N,
        p: &Point,
        d: &[f64],
        (f, trial_c): (f64, &[f64]),
        nu: f64,
        delta: f64,
    ) {
        let gd: f64 = p.g.iter().zip(d).map(|(a, b)| a * b).sum();
        let (v0, _) = self.pb.violation(&p.c);
        let (v1, _) = self.pb.violation(trial_c);
        crate::errln!("  rejected full step: Δf {:.3e} (gᵀd {:.3e}), ν·Δviol {:.3e} (viol {:.3e} → {:.3e}), |d| {:.3e}, Δ {:.3e}", f - p.f, gd, nu * (v1 - v0), v0, v1, norm_inf(d), delta);
        let viol = |c: &[f64], i: usize| self.pb.row_violation(c, i);
        let mut lin = p.c.clone();
        self.pb.add_jacobian_times(&p.jv, d, 1.0, &mut lin);
        let largest = |key: &dyn Fn(usize) -> f64| {
            let mut rows: Vec<(f64, usize)> = (0..trial_c.len()).map(|i| (key(i), i)).collect();
            rows.sort_by(|a, b| b.0.total_cmp(&a.0));
            rows.truncate(6);
            rows
        };
        for (dv, i) in largest(&|i| viol(trial_c, i) - viol(&p.c, i)) {
            crate::errln!("    {:.3e} {}", dv, nlp.constraint_name(i));
        }
        let (lin1, _) = self.pb.violation(&lin);
        crate::errln!("    linearised violation {lin1:.3e}; most violated at the trial:");
        for (v, i) in largest(&|i| viol(trial_c, i)) {
            crate::errln!(
                "    {:.3e} (now {:.3e}, linearised {:.3e}) {}",
                v,
                viol(&p.c, i),
                viol(&lin, i),
                nlp.constraint_name(i)
            );
        }
    }

    fn log(&self, rec: &IterationRecord, start: Instant, result: &mut SqpResult) {
        let mut rec = rec.clone();
        rec.time_s = start.elapsed().as_secs_f64();
        if self.settings.verbose {
            if rec.iter.is_multiple_of(10) {
                crate::errln!("iter    objective    inf_pr   inf_du    compl    ||d||  delta  ratio    alpha  ls  qp_it  qp_mode   lg(rg)  penalty  time_s");
            }
            crate::errln!(
                "{:4} {:14.7e} {:8.2e} {:8.2e} {:8.2e} {:8.2e} {:6.0e} {:6.2} {:8.2e} {:3} {:6} {:8} {:>6} {:8.2e} {:7.2}",
                rec.iter, rec.objective, rec.inf_pr, rec.inf_du, rec.complementarity, rec.step_norm, rec.step_bound, rec.model_ratio, rec.alpha, rec.ls_trials, rec.qp_iterations, rec.qp_mode, lg_rg(rec.hessian_shift), rec.penalty, rec.time_s
            );
        }
        result.history.push(rec);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stall test reads the last `window` + 1 iterates: it fires only
    /// when the violation stayed above the limit, fell less than 10% and
    /// the objective moved less than 1e-3·(1 + |f|); each change below
    /// breaks exactly one of those.
    #[test]
    fn stall_needs_every_part_of_the_test() {
        // Violation 1 falling 0.1% per iteration, objective flat.
        let flat: Vec<(f64, f64)> = (0..11).map(|k| (1.0 - 1e-3 * k as f64, 2.0)).collect();
        assert!(stalled(&flat, 10, 1e-3).is_some());
        // Too short for the window, or the test off.
        assert!(stalled(&flat[..10], 10, 1e-3).is_none());
        assert!(stalled(&flat, 0, 1e-3).is_none());
        // The violation falls 10% by the window's end.
        let mut falling = flat.clone();
        falling[10].0 = 0.9 * falling[0].0 - 1e-12;
        assert!(stalled(&falling, 10, 1e-3).is_none());
        // Only iterates inside the window count: progress before it does not.
        let mut older = vec![(10.0, 5.0)];
        older.extend_from_slice(&flat);
        assert!(stalled(&older, 10, 1e-3).is_some());
        // The objective moves 1e-3·(1 + |f|) and a little more.
        let mut moving = flat.clone();
        moving[5].1 = 2.0 - 3e-3 - 1e-12;
        assert!(stalled(&moving, 10, 1e-3).is_none());
        moving[5].1 = 2.0 - 3e-3 + 1e-12;
        assert!(stalled(&moving, 10, 1e-3).is_some());
        // The same history 1000 times closer to feasibility: at most the
        // limit 1e-3, above 1e-4.
        let near: Vec<(f64, f64)> = flat.iter().map(|&(v, f)| (1e-3 * v, f)).collect();
        assert!(stalled(&near, 10, 1e-3).is_none());
        assert!(stalled(&near, 10, 1e-4).is_some());
    }

    /// The first BFGS update scales the identity by Shanno–Phua's yᵀy/sᵀy
    /// or, along the step, by Oren–Luenberger's sᵀy/sᵀs: a direction
    /// orthogonal to s and y keeps that curvature, and the secant equation
    /// B s = y holds (an undamped update: sᵀy ≥ 0.2 sᵀBs).
    #[test]
    fn first_bfgs_update_scales_the_identity_as_chosen() {
        let s = [1.0, 0.0, 0.0];
        let y = [2.0, 1.0, 0.0];
        let (ss, sy, yy) = (1.0, 2.0, 5.0);
        for (along, gamma) in [(false, yy / sy), (true, sy / ss)] {
            let mut b = vec![0.0; 9];
            for i in 0..3 {
                b[i * 3 + i] = 1.0;
            }
            let mut first = true;
            assert!(bfgs_update(&mut b, &s, &y, &mut first, 1e-8, along));
            assert!(!first);
            // e_3 is orthogonal to s and y.
            assert!(
                (b[8] - gamma).abs() < 1e-12,
                "{along}: {} against {gamma}",
                b[8]
            );
            for r in 0..3 {
                let bs: f64 = (0..3).map(|c| b[r * 3 + c] * s[c]).sum();
                assert!((bs - y[r]).abs() < 1e-12, "{along}: (Bs)_{r} = {bs}");
            }
        }
    }

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(Vec::new()).is_nan());
    }

    /// Only iterations with a solved QP count; the median and the largest
    /// are over those with τ > 0.
    #[test]
    fn hessian_shift_summary_counts_the_shifted_qps() {
        let rec = |mode: &str, t: f64| IterationRecord {
            qp_mode: mode.into(),
            hessian_shift: t,
            ..Default::default()
        };
        let h = [
            rec("ok", 0.0),
            rec("ok", 0.5),
            rec("elastic", 0.1),
            rec("soc", 2.0),
            rec("failed", 9.0),
            rec("", 7.0),
        ];
        let s = HessianShiftSummary::of(&h).expect("three shifted QPs");
        assert_eq!((s.qps, s.shifted, s.median, s.max), (4, 3, 0.5, 2.0));
        assert_eq!(HessianShiftSummary::of(&h[..1]), None);
    }

    /// Each block convexified alone (as `convexify` of the submatrix), the
    /// entries between blocks zero, the whole positive definite.
    #[test]
    fn convexify_blocks_is_block_diagonal_and_positive_definite() {
        let k = 6;
        let mut h = vec![0.0; k * k];
        for a in 0..k {
            for b in 0..=a {
                // An indefinite symmetric matrix, fully coupled.
                let v = ((a * 7 + b * 3) as f64).sin() * 2.0 + if a == b { 0.5 } else { 0.0 };
                h[a * k + b] = v;
                h[b * k + a] = v;
            }
        }
        let blocks = vec![vec![0, 3], vec![1, 2, 5], vec![4]];
        let mut out = h.clone();
        convexify_blocks(&mut out, k, &blocks, 1e-4, Convexification::Clip);
        let id = Element {
            variables: (0..k).collect(),
            constraints: vec![],
            objective: true,
            blocks: blocks.clone(),
        }
        .block_ids();
        for a in 0..k {
            for b in 0..k {
                if id[a] != id[b] {
                    assert_eq!(out[a * k + b], 0.0);
                }
            }
        }
        for members in &blocks {
            let kb = members.len();
            let mut sub: Vec<f64> = members
                .iter()
                .flat_map(|&a| members.iter().map(move |&b| (a, b)))
                .map(|(a, b)| h[a * k + b])
                .collect();
            convexify(&mut sub, kb, 1e-4, Convexification::Clip);
            for (i, &a) in members.iter().enumerate() {
                for (j, &b) in members.iter().enumerate() {
                    assert_eq!(out[a * k + b], sub[i * kb + j]);
                }
            }
        }
        let eig = SymmetricEigen::new(DMatrix::from_row_slice(k, k, &out));
        let min = eig.eigenvalues.iter().fold(f64::INFINITY, |a, &v| a.min(v));
        assert!(min > 0.0, "smallest eigenvalue {min}");
        let eig0 = SymmetricEigen::new(DMatrix::from_row_slice(k, k, &h));
        assert!(eig0.eigenvalues.iter().any(|&v| v < 0.0));
    }
}
