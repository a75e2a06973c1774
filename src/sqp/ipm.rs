//! A primal-dual interior-point QP solver for the SQP's subproblems, on
//! clarabel's problem form
//!
//! ```text
//!   minimise ½ xᵀ P x + qᵀ x   subject to  A x + s = b,
//!   s_r = 0 (the first `num_eq` rows),  s_r ≥ 0 (the others),
//! ```
//!
//! with multipliers z (P x + q + Aᵀ z = 0, z_r ≥ 0 on the inequality
//! rows), so that its solution reads exactly as clarabel's.
//!
//! What it exploits, and clarabel does not:
//! * an inequality row with a single entry (a variable bound, a step bound,
//!   an elastic slack's sign) is eliminated from the KKT system into the
//!   diagonal of P, so the factorised system has the size of the variables
//!   plus the equality and general rows only (the jump's QPs: 7,725 rows,
//!   5,953 variables with the elastic slacks and 1,772 rows, instead of
//!   16,087);
//! * the fill-reducing ordering (the smaller factor of AMD and METIS's
//!   nested dissection, [`KktOrdering`]) and faer's supernodal symbolic
//!   factorisation are computed once per SQP solve, since the pattern is
//!   fixed;
//! * the numeric factorisation and the triangular solves are leap's own
//!   (`sqp::ldlt`), over faer's supernodal layout: plain loops over the
//!   supernodes (most of the jump's are one or two columns wide, where
//!   faer's dense kernels cost more in setup than in arithmetic), faer's
//!   kernels for the wide ones, and the elimination tree's subtrees on two
//!   threads. The jump's QPs 1–30 take 3.0–3.3 s instead of 4.7–4.9 s with
//!   faer's factorisation (`CHAIN=1 examples/ipm_bench`), with the same
//!   interior-point iterations;
//! * the iterative refinement's residuals multiply by the assembled KKT
//!   matrix, one pass over its entries.
//!
//! The method is Mehrotra's predictor-corrector (Mehrotra 1992; Nocedal &
//! Wright 2006, Algorithm 16.4 for QPs), with the starting point of
//! CVXOPT/clarabel (the KKT system with unit slacks, then shifted into the
//! cone), static and dynamic regularisation of the quasi-definite KKT matrix
//! and iterative refinement against the unregularised one. It detects
//! primal infeasibility by a Farkas certificate (Aᵀz ≈ 0, bᵀz < 0,
//! z ≥ 0 on the inequality rows), and reports a primal residual that stops
//! falling as [`IpmStatus::Stalled`] (most likely infeasible). It has no
//! homogeneous embedding: where it fails to converge, the caller falls
//! back to clarabel.
//!
//! With [`Ipm::inertia_correction`] P may be indefinite: the solver adds
//! τ I until the KKT matrix has the inertia of a QP that is convex on its
//! constraints (IPOPT's rule for τ), reading the inertia off the LDLᵀ
//! factor's D.

use super::ldlt::{FactorLayout, SolveScratch};
use super::norm_inf;
use clarabel::algebra::CscMatrix;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::{LdltParams, LdltRegularization};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LdltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side, Spec};

/// The fill-reducing ordering of the KKT matrix, fixed for a solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KktOrdering {
    /// Approximate minimum degree (faer's AMD).
    Amd,
    /// Whichever of AMD and METIS's nested dissection (METIS_NodeND) gives
    /// the smaller factor; the default. On the default jump's KKT system
    /// (7,725 rows, 97,919 entries in its upper triangle) nested
    /// dissection's factor has 323,355 entries against AMD's 553,786, and
    /// the QPs of the jump's first 10 SQP iterations take about 16% less
    /// time with the same interior-point iterations (`ORDERING=amd
    /// examples/ipm_bench` against the default, alternating runs).
    SmallerFactor,
}

/// METIS's nested-dissection ordering (METIS_NodeND) of the symmetric
/// pattern given by its upper triangle (CSC): (fwd, inv) with new i = old
/// fwd[i], or None where METIS fails or the system is too small to gain.
fn nested_dissection(
    dim: usize,
    colptr: &[usize],
    rowind: &[usize],
) -> Option<(Vec<usize>, Vec<usize>)> {
    // METIS's indices are i32: the adjacency lists both triangles.
    if dim < 64 || 2 * rowind.len() >= i32::MAX as usize {
        return None;
    }
    // The adjacency of the graph of the pattern: both triangles, no diagonal.
    let mut degree = vec![0usize; dim];
    for j in 0..dim {
        for &i in &rowind[colptr[j]..colptr[j + 1]] {
            if i != j {
                degree[i] += 1;
                degree[j] += 1;
            }
        }
    }
    let mut xadj = vec![0 as metis_sys::idx_t; dim + 1];
    for v in 0..dim {
        xadj[v + 1] = xadj[v] + degree[v] as metis_sys::idx_t;
    }
    let mut fill: Vec<usize> = xadj[..dim].iter().map(|&x| x as usize).collect();
    let mut adjncy = vec![0 as metis_sys::idx_t; xadj[dim] as usize];
    for j in 0..dim {
        for &i in &rowind[colptr[j]..colptr[j + 1]] {
            if i != j {
                adjncy[fill[i]] = j as metis_sys::idx_t;
                fill[i] += 1;
                adjncy[fill[j]] = i as metis_sys::idx_t;
                fill[j] += 1;
            }
        }
    }
    let mut nvtxs = dim as metis_sys::idx_t;
    let mut options = [0 as metis_sys::idx_t; metis_sys::METIS_NOPTIONS as usize];
    let (mut perm, mut iperm) = (
        vec![0 as metis_sys::idx_t; dim],
        vec![0 as metis_sys::idx_t; dim],
    );
    // SAFETY: METIS reads nvtxs, xadj (nvtxs + 1 entries) and adjncy
    // (xadj[nvtxs] entries, a symmetric graph without self-loops, as built
    // above) and writes nvtxs entries into perm and iperm; options is
    // METIS_NOPTIONS long, and vwgt may be null.
    let status = unsafe {
        metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
        metis_sys::METIS_NodeND(
            &mut nvtxs,
            xadj.as_mut_ptr(),
            adjncy.as_mut_ptr(),
            std::ptr::null_mut(),
            options.as_mut_ptr(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    if status != metis_sys::rstatus_et_METIS_OK {
        return None;
    }
    // METIS: row i of the permuted matrix is row perm[i] of the original.
    let fwd: Vec<usize> = perm.iter().map(|&v| v as usize).collect();
    let inv: Vec<usize> = iperm.iter().map(|&v| v as usize).collect();
    let valid = fwd.iter().all(|&v| v < dim) && (0..dim).all(|i| inv[fwd[i]] == i);
    valid.then_some((fwd, inv))
}

/// How an interior-point solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IpmStatus {
    Solved,
    /// A Farkas certificate of primal infeasibility was found.
    PrimalInfeasible,
    /// The primal residual stopped falling (less than halved in
    /// STALL_WINDOW iterations) far from feasibility: most likely an
    /// infeasible QP whose certificate has not formed yet (on the jump,
    /// clarabel found all 14 such QPs of one solve infeasible, taking
    /// 7-200 iterations, 0.4-9.6 s, to say so).
    Stalled,
    /// Iteration limit, a failed factorisation or stalled steps: not an
    /// answer (the caller falls back to clarabel).
    Failed,
}

/// What a KKT slot is filled from.
#[derive(Clone, Copy)]
enum Slot {
    /// Entry k of P's values.
    P(usize),
    /// Entry k of A's values (a general or equality row).
    A(usize),
}

/// The interior-point solver of one fixed-pattern QP.
pub struct Ipm {
    n: usize,
    m: usize,
    num_eq: usize,
    /// For each row, the A entry index and column of a single-entry
    /// inequality row (eliminated), or None (the row is in the KKT system).
    bound: Vec<Option<(usize, usize)>>,
    /// For each row kept in the KKT system, its row index; a kept row k is
    /// KKT index n + k.
    kept: Vec<usize>,
    /// For each kept row, the inequality row that is its negation (a
    /// constraint's upper and lower bound rows, as the SQP writes them):
    /// that row is not in the KKT system, the kept row stands for both
    /// ([`Ipm::merged_weight`]). usize::MAX where there is none.
    twin: Vec<usize>,
    /// The A entries (kept row's, twin's) of every pair, in order: the
    /// values must stay negated ([`Ipm::twins_hold`]).
    twin_entries: Vec<(usize, usize)>,
    // KKT matrix, upper triangle, CSC.
    colptr: Vec<usize>,
    rowind: Vec<usize>,
    values: Vec<f64>,
    /// Sources of each KKT value (several may add into one slot).
    sources: Vec<(usize, Slot)>,
    /// KKT slot of each diagonal entry.
    diag: Vec<usize>,
    /// Whether `values` and `l_base` hold the P and A of the current
    /// solve (they change from QP to QP, the diagonal from iteration to
    /// iteration).
    assembled: bool,
    /// The diagonal's share of P (the sources of each diagonal slot).
    diag_base: Vec<f64>,
    /// The supernodal factor's values before factorisation, but for the
    /// diagonal: P and A in the factor's layout, zero elsewhere.
    l_base: Vec<f64>,
    signs: Vec<i8>,
    symbolic: SymbolicCholesky<usize>,
    /// The supernodal factor's layout, for [`Ipm::ldlt_solve`] (None when
    /// faer chose the simplicial factorisation).
    layout: Option<FactorLayout>,
    /// Position in the supernodal factor's values of each KKT entry.
    l_slot: Vec<usize>,
    /// The pivot signs in the factor's order.
    factor_signs: Vec<i8>,
    /// Permuted right-hand side of a solve.
    perm_work: Vec<f64>,
    /// Scratch of the triangular solves.
    solve_scratch: SolveScratch,
    /// Scratch of `solve_kkt`: right-hand side, solution, residual, trial.
    kkt_scratch: [Vec<f64>; 4],
    l_values: Vec<f64>,
    work: MemBuffer,
    /// Inertia correction (IPOPT's, Wächter & Biegler 2006 §3.1): P may be
    /// indefinite; τ I is added to it until the KKT matrix has n positive
    /// and (kept rows) negative eigenvalues, i.e. P + τ I is positive
    /// definite on the null space of the equality rows, where the QP is
    /// then convex. The factorisation then runs without the quasi-definite
    /// sign pattern (only tiny pivots are regularised) and its inertia is
    /// read off D (Sylvester's law).
    pub inertia_correction: bool,
    /// τ of the current solve (scaled QP).
    shift: f64,
    /// τ of the last solve that needed one (IPOPT's δ_w memory).
    last_shift: f64,
    /// After a solve: ½ τ ‖x̂‖², the curvature τ I added along the answer
    /// (the SQP's model of the step), and τ on P's diagonal in the
    /// caller's units (τ / D_j², D the equilibration).
    pub shift_curvature: f64,
    pub shift_diag: Vec<f64>,
    /// The inequality rows active at the last answer.
    prev_active: Vec<bool>,
    /// Start each solve from the last one's answer where that one was
    /// solved ([`WARM_START_FLOOR`]); not with the inertia correction.
    pub warm_start: bool,
    last_solved: bool,
    pub iterations: u32,
    pub x: Vec<f64>,
    pub z: Vec<f64>,
    pub s: Vec<f64>,
}

/// Static regularisation of the KKT diagonal, and the iterative
/// refinement that removes it (clarabel's rule: up to 3 steps, each kept
/// only when it cuts the residual of the unregularised system 5-fold,
/// until the residual is within clarabel's default tolerances,
/// REFINE_ABS_TOL + REFINE_TOL·‖rhs‖∞; with 1e-13·(1 + ‖rhs‖∞) instead,
/// 4% more time on the jump's QPs for the same interior-point iterations).
/// Measured on the jump's first 25 QPs (`IPM=1 examples/qp_replay`) and
/// the Hock–Schittkowski set: 1e-11 with one step saves a quarter of the
/// time per iteration, but stalls the dual residual of near-degenerate
/// QPs (hs039, hs046, the jump's first QP) until clarabel takes over.
const STATIC_REG: f64 = 1e-9;
/// Dynamic regularisation of the LDLᵀ pivots: one of the wrong sign for
/// its row, or within ε of zero, becomes ±δ.
const REG_DELTA: f64 = 1e-8;
const REG_EPSILON: f64 = 1e-14;
/// Bounds of the cumulative Ruiz scaling of a variable or row (clarabel's
/// `equilibrate_min_scaling` and `equilibrate_max_scaling`).
const EQUILIBRATION_MIN: f64 = 1e-4;
const EQUILIBRATION_MAX: f64 = 1e4;
const REFINE_STEPS: usize = 3;
const REFINE_TOL: f64 = 1e-13;
const REFINE_ABS_TOL: f64 = 1e-12;
const REFINE_STOP_RATIO: f64 = 5.0;
const MAX_ITER: u32 = 80;
const STALL_WINDOW: u32 = 8;
/// An iterate within this multiple of the tolerance counts as solved
/// where the iteration stalls (clarabel's reduced tolerances are looser:
/// 1e-4 feasibility, 5e-5 gap).
const REDUCED_TOL_FACTOR: f64 = 1e4;
/// Gondzio correctors per iteration, and the step increase they aim at
/// (one corrector: 520 instead of 583 interior-point iterations on the
/// jump's first 25 QPs, at about the same time; whole jump solves took
/// 0.47 s of QP per SQP iteration either way).
const MAX_CORRECTORS: usize = 1;
/// IPOPT's inertia-correction constants (δ_w⁰, δ_w^min, κ_w⁻, κ_w⁺,
/// κ̄_w⁺, δ_w^max), for the scaled QP.
const SHIFT_FIRST: f64 = 1e-4;
const SHIFT_MIN: f64 = 1e-20;
const SHIFT_DECREASE: f64 = 1.0 / 3.0;
const SHIFT_INCREASE: f64 = 8.0;
const SHIFT_INCREASE_FIRST: f64 = 100.0;
const SHIFT_MAX: f64 = 1e40;
/// Row weight s/z of an inactive inequality row in the inertia test
/// (it drops out); an active one gets its inverse (it acts as an equality).
const INACTIVE_WEIGHT: f64 = 1e8;
const GONDZIO_DELTA: f64 = 0.3;
/// The least slack and multiplier of an inequality row in a warm start
/// (scaled QP): on 28 consecutive QPs of the default jump (iterations
/// 12–39, `examples/ipm_bench` with CHAIN=1), 1e-3 to 1e-2 took 354–362
/// interior-point iterations where the cold start took 482; 1e-4 398,
/// 1e-1 418 and 1 465.
const WARM_START_FLOOR: f64 = 1e-2;

/// faer's parallelism: sequential (two threads took 4× longer on the
/// jump's KKT system: its supernodes are small).
fn par() -> Par {
    Par::Seq
}

/// [`twin_rows`]' mark of a twin row (not in the KKT system).
const TWIN: usize = usize::MAX - 1;

/// Each row's entries (column, index in A's values), by column.
fn row_entries(a: &CscMatrix<f64>) -> Vec<Vec<(usize, usize)>> {
    let mut rows = vec![Vec::new(); a.m];
    for j in 0..a.n {
        for k in a.colptr[j]..a.colptr[j + 1] {
            rows[a.rowval[k]].push((j, k));
        }
    }
    rows
}

/// Each row's twin or mark, and the pairs' A entries ([`twin_rows`]).
type TwinRows = (Vec<usize>, Vec<(usize, usize)>);

/// The twin pairs of [`Ipm::with_twins`], checked: for each row its twin
/// (kept rows), [`TWIN`] (twin rows) or usize::MAX, and the A entries
/// (row's, twin's) of every pair. Pairs whose rows are single-entry
/// (eliminated as bounds anyway) are dropped.
fn twin_rows(
    a: &CscMatrix<f64>,
    num_eq: usize,
    bound: &[Option<(usize, usize)>],
    twins: &[(usize, usize)],
) -> Result<TwinRows, String> {
    let mut partner = vec![usize::MAX; a.m];
    let mut entries = Vec::new();
    if twins.is_empty() {
        return Ok((partner, entries));
    }
    let rows = row_entries(a);
    for &(r, t) in twins {
        if r >= a.m || t >= a.m || r == t || r < num_eq || t < num_eq {
            return Err(format!(
                "twin rows ({r}, {t}): not two distinct inequality rows of the {} rows",
                a.m
            ));
        }
        if partner[r] != usize::MAX || partner[t] != usize::MAX {
            return Err(format!("twin rows ({r}, {t}): a row in two pairs"));
        }
        let (x, y) = (&rows[r], &rows[t]);
        if x.len() != y.len() || x.iter().zip(y).any(|(cx, cy)| cx.0 != cy.0) {
            return Err(format!("twin rows ({r}, {t}): different columns"));
        }
        if bound[r].is_some() || bound[t].is_some() {
            continue;
        }
        partner[r] = t;
        partner[t] = TWIN;
        entries.extend(x.iter().zip(y).map(|(cx, cy)| (cx.1, cy.1)));
    }
    Ok((partner, entries))
}

// `!(a > b)` is meant: it is true for NaN as well.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
impl Ipm {
    /// Lay out the KKT system of the QP with these patterns (P: upper
    /// triangle, n×n; A: m×n, the first `num_eq` rows equalities).
    pub fn new(p: &CscMatrix<f64>, a: &CscMatrix<f64>, num_eq: usize) -> Result<Ipm, String> {
        Self::with_ordering(p, a, num_eq, KktOrdering::SmallerFactor)
    }

    /// [`Ipm::new`] with the fill-reducing ordering of the KKT matrix
    /// chosen.
    pub fn with_ordering(
        p: &CscMatrix<f64>,
        a: &CscMatrix<f64>,
        num_eq: usize,
        ordering: KktOrdering,
    ) -> Result<Ipm, String> {
        Self::with_threshold(p, a, num_eq, SupernodalThreshold::AUTO, ordering, &[])
    }

    /// [`Ipm::with_ordering`] for a QP whose rows come in twins: in each
    /// pair (r, t) of inequality rows, row t is row r negated (the upper
    /// and lower bound rows of one constraint, as the SQP writes them).
    /// Only r enters the KKT system, with the weight of both rows
    /// ([`Ipm::merged_weight`]): a shooting QP's system loses half its
    /// constraint rows. The two rows must have the same columns; a solve
    /// whose values are not negated fails ([`IpmStatus::Failed`]).
    pub fn with_twins(
        p: &CscMatrix<f64>,
        a: &CscMatrix<f64>,
        num_eq: usize,
        ordering: KktOrdering,
        twins: &[(usize, usize)],
    ) -> Result<Ipm, String> {
        Self::with_threshold(p, a, num_eq, SupernodalThreshold::AUTO, ordering, twins)
    }

    /// The pairs of neighbouring inequality rows of A that have the same
    /// columns and negated values, as [`Ipm::with_twins`] takes them (for
    /// QPs read from files; the SQP names its pairs).
    pub fn detect_twins(a: &CscMatrix<f64>, num_eq: usize) -> Vec<(usize, usize)> {
        let rows = row_entries(a);
        let mut twins = Vec::new();
        let mut r = num_eq;
        while r + 1 < a.m {
            let (x, y) = (&rows[r], &rows[r + 1]);
            let negated = x.len() > 1
                && x.len() == y.len()
                && x.iter()
                    .zip(y)
                    .all(|(&(cx, kx), &(cy, ky))| cx == cy && a.nzval[kx] == -a.nzval[ky]);
            if negated {
                twins.push((r, r + 1));
                r += 2;
            } else {
                r += 1;
            }
        }
        twins
    }

    /// [`Ipm::new`] with faer's choice between the simplicial and the
    /// supernodal factor set (tests force the supernodal one).
    fn with_threshold(
        p: &CscMatrix<f64>,
        a: &CscMatrix<f64>,
        num_eq: usize,
        threshold: SupernodalThreshold,
        ordering: KktOrdering,
        twins: &[(usize, usize)],
    ) -> Result<Ipm, String> {
        let (n, m) = (p.n, a.m);
        let mut row_count = vec![0usize; m];
        let mut row_entry = vec![(usize::MAX, usize::MAX); m];
        for j in 0..n {
            for k in a.colptr[j]..a.colptr[j + 1] {
                let r = a.rowval[k];
                row_count[r] += 1;
                row_entry[r] = (k, j);
            }
        }
        let bound: Vec<Option<(usize, usize)>> = (0..m)
            .map(|r| (r >= num_eq && row_count[r] == 1).then_some(row_entry[r]))
            .collect();
        let (partner, twin_entries) = twin_rows(a, num_eq, &bound, twins)?;
        let kept: Vec<usize> = (0..m)
            .filter(|&r| bound[r].is_none() && partner[r] != TWIN)
            .collect();
        let twin: Vec<usize> = kept.iter().map(|&r| partner[r]).collect();
        let mut kept_pos = vec![usize::MAX; m];
        for (k, &r) in kept.iter().enumerate() {
            kept_pos[r] = k;
        }
        let dim = n + kept.len();
        // Entries (row, col, source) of the upper triangle.
        let mut entries: Vec<(usize, usize, Option<Slot>)> = Vec::new();
        for j in 0..dim {
            entries.push((j, j, None));
        }
        for j in 0..n {
            for k in p.colptr[j]..p.colptr[j + 1] {
                let i = p.rowval[k];
                if i > j {
                    return Err("P is not upper triangular".into());
                }
                entries.push((i, j, Some(Slot::P(k))));
            }
            for k in a.colptr[j]..a.colptr[j + 1] {
                let r = a.rowval[k];
                if kept_pos[r] != usize::MAX {
                    entries.push((j, n + kept_pos[r], Some(Slot::A(k))));
                }
            }
        }
        entries.sort_by_key(|&(i, j, _)| (j, i));
        let mut colptr = vec![0usize; dim + 1];
        let mut rowind = Vec::with_capacity(entries.len());
        let mut sources = Vec::new();
        let mut diag = vec![0usize; dim];
        let mut last = (usize::MAX, usize::MAX);
        for &(i, j, src) in &entries {
            if (i, j) != last {
                rowind.push(i);
                colptr[j + 1] += 1;
                last = (i, j);
                if i == j {
                    diag[j] = rowind.len() - 1;
                }
            }
            if let Some(s) = src {
                sources.push((rowind.len() - 1, s));
            }
        }
        for j in 0..dim {
            colptr[j + 1] += colptr[j];
        }
        let symb = SymbolicSparseColMatRef::new_checked(dim, dim, &colptr, None, &rowind);
        let symbolic_with = |ordering: SymmetricOrdering<'_, usize>| {
            factorize_symbolic_cholesky(
                symb,
                Side::Upper,
                ordering,
                CholeskySymbolicParams {
                    supernodal_flop_ratio_threshold: threshold,
                    ..Default::default()
                },
            )
            .map_err(|e| format!("symbolic factorisation of the KKT matrix: {e:?}"))
        };
        let mut symbolic = symbolic_with(SymmetricOrdering::Amd)?;
        if ordering == KktOrdering::SmallerFactor {
            if let Some((fwd, inv)) = nested_dissection(dim, &colptr, &rowind) {
                let perm = PermRef::new_checked(&fwd, &inv, dim);
                let nd = symbolic_with(SymmetricOrdering::Custom(perm))?;
                if nd.len_val() < symbolic.len_val() {
                    symbolic = nd;
                }
            }
        }
        let params: Spec<LdltParams, f64> = Default::default();
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_ldlt_scratch::<f64>(par(), params),
            symbolic.solve_in_place_scratch::<f64>(1, par()),
        ]);
        let signs: Vec<i8> = (0..dim).map(|j| if j < n { 1 } else { -1 }).collect();
        let nnz = rowind.len();
        let layout = FactorLayout::of(&symbolic);
        let (mut l_slot, mut factor_signs) = (Vec::new(), Vec::new());
        if let Some(layout) = &layout {
            // new i = old fwd[i]; old i is new inv[i].
            let (fwd, inv): (Vec<usize>, Vec<usize>) = match symbolic.perm() {
                Some(perm) => {
                    let (f, i) = perm.arrays();
                    (f.to_vec(), i.to_vec())
                }
                None => ((0..dim).collect(), (0..dim).collect()),
            };
            for j in 0..dim {
                for &i in &rowind[colptr[j]..colptr[j + 1]] {
                    let (pi, pj) = (inv[i], inv[j]);
                    l_slot.push(
                        layout
                            .position(pi.max(pj), pi.min(pj))
                            .ok_or("the supernodal factor lacks an entry of the KKT matrix")?,
                    );
                }
            }
            factor_signs = fwd.iter().map(|&old| signs[old]).collect();
        }
        Ok(Ipm {
            layout,
            l_slot,
            factor_signs,
            perm_work: vec![0.0; dim],
            solve_scratch: SolveScratch::default(),
            kkt_scratch: Default::default(),
            n,
            m,
            num_eq,
            bound,
            kept,
            twin,
            twin_entries,
            colptr,
            rowind,
            values: vec![0.0; nnz],
            sources,
            diag,
            assembled: false,
            diag_base: vec![0.0; dim],
            l_base: Vec::new(),
            signs,
            l_values: vec![0.0; symbolic.len_val()],
            symbolic,
            work: MemBuffer::new(req),
            inertia_correction: false,
            shift: 0.0,
            last_shift: 0.0,
            shift_curvature: 0.0,
            shift_diag: vec![0.0; n],
            prev_active: Vec::new(),
            warm_start: false,
            last_solved: false,
            iterations: 0,
            x: vec![0.0; n],
            z: vec![0.0; m],
            s: vec![0.0; m],
        })
    }

    /// τ of the last solve: the multiple of I the inertia correction added
    /// to the equilibrated QP's Hessian (0 where P was convex enough).
    pub fn shift(&self) -> f64 {
        self.shift
    }

    /// Non-zeros of the KKT matrix (upper triangle) and of its factor.
    pub fn size(&self) -> (usize, usize) {
        (self.rowind.len(), self.l_values.len())
    }

    /// y += P x for P given by its upper triangle.
    pub fn p_mul(p: &CscMatrix<f64>, x: &[f64], y: &mut [f64]) {
        for j in 0..p.n {
            for k in p.colptr[j]..p.colptr[j + 1] {
                let (i, v) = (p.rowval[k], p.nzval[k]);
                y[i] += v * x[j];
                if i != j {
                    y[j] += v * x[i];
                }
            }
        }
    }

    /// Assemble the reduced KKT matrix for row weights `d` (D_r = s_r/z_r
    /// on inequality rows, 0 on equality rows) and factorise it.
    fn factor(&mut self, p: &CscMatrix<f64>, a: &CscMatrix<f64>, d: &[f64]) -> bool {
        let n = self.n;
        if !self.assembled {
            // P and A into the KKT matrix (and the factor's layout) once
            // per solve: the interior-point iterations change only the
            // diagonal.
            self.values.fill(0.0);
            for &(slot, src) in &self.sources {
                self.values[slot] += match src {
                    Slot::P(k) => p.nzval[k],
                    Slot::A(k) => a.nzval[k],
                };
            }
            for (b, &slot) in self.diag_base.iter_mut().zip(&self.diag) {
                *b = self.values[slot];
            }
            if self.layout.is_some() {
                self.l_base.clear();
                self.l_base.resize(self.l_values.len(), 0.0);
                for (&pos, &v) in self.l_slot.iter().zip(&self.values) {
                    self.l_base[pos] = v;
                }
            }
            self.assembled = true;
        }
        for j in 0..n {
            self.values[self.diag[j]] = self.diag_base[j] + STATIC_REG + self.shift;
        }
        for (r, b) in self.bound.iter().enumerate() {
            if let Some((k, j)) = *b {
                self.values[self.diag[j]] += a.nzval[k] * a.nzval[k] / d[r];
            }
        }
        for k in 0..self.kept.len() {
            self.values[self.diag[n + k]] = -self.merged_weight(k, d) - STATIC_REG;
        }
        if let Some(layout) = &mut self.layout {
            self.l_values.copy_from_slice(&self.l_base);
            for &slot in &self.diag {
                self.l_values[self.l_slot[slot]] = self.values[slot];
            }
            let signs = (!self.inertia_correction).then_some(&self.factor_signs[..]);
            return layout
                .factorise(&mut self.l_values, signs, REG_EPSILON, REG_DELTA)
                .is_ok();
        }
        let dim = self.diag.len();
        let symb = SymbolicSparseColMatRef::new_checked(dim, dim, &self.colptr, None, &self.rowind);
        let mat = SparseColMatRef::new(symb, &self.values);
        let reg = LdltRegularization {
            dynamic_regularization_signs: (!self.inertia_correction).then_some(&self.signs[..]),
            dynamic_regularization_delta: REG_DELTA,
            dynamic_regularization_epsilon: REG_EPSILON,
        };
        self.symbolic
            .factorize_numeric_ldlt(
                &mut self.l_values,
                mat,
                Side::Upper,
                reg,
                par(),
                MemStack::new(&mut self.work),
                Default::default(),
            )
            .is_ok()
    }

    /// The weight of kept row k in the reduced KKT system: its d, or for a
    /// row with a twin t (a_t = −a_r) both rows' slacks eliminated into
    /// one, 1/(1/d_r + 1/d_t). The twin's equation −a_r·dx − d_t·dz_t =
    /// ρ_t and the row's a_r·dx − d_r·dz_r = ρ_r reach the variables only
    /// through dz_r − dz_t ([`Ipm::twin_split`]).
    fn merged_weight(&self, k: usize, d: &[f64]) -> f64 {
        let r = self.kept[k];
        match self.twin[k] {
            usize::MAX => d[r],
            t => d[r] * (d[t] / (d[r] + d[t])),
        }
    }

    /// For kept row k with its twin: (θ_r, θ_t, c) with which the merged
    /// row's right-hand side is θ_r ρ_r − θ_t ρ_t, and the two multipliers'
    /// steps are dz_r = θ_r dz − c (ρ_r + ρ_t), dz_t = −θ_t dz − c (ρ_r +
    /// ρ_t), dz the merged row's (no division by a single vanishing d).
    fn twin_split(&self, k: usize, d: &[f64]) -> (f64, f64, f64) {
        let (dr, dt) = (d[self.kept[k]], d[self.twin[k]]);
        let c = 1.0 / (dr + dt);
        (dt * c, dr * c, c)
    }

    /// Whether every twin row is still its row negated.
    fn twins_hold(&self, a: &CscMatrix<f64>) -> bool {
        self.twin_entries
            .iter()
            .all(|&(k, t)| a.nzval[t] == -a.nzval[k])
    }

    /// Whether the current factor has the inertia (n, kept rows, 0): n
    /// positive pivots of D and one negative per kept row.
    fn inertia_is_right(&self) -> bool {
        let d = |k: usize| self.l_values[k];
        let negative = match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => s.col_ptr()[..s.ncols()]
                .iter()
                .filter(|&&k| d(k) < 0.0)
                .count(),
            SymbolicCholeskyRaw::Supernodal(s) => {
                let (begin, end) = (s.supernode_begin(), s.supernode_end());
                let (vals, rows) = (s.col_ptr_for_val(), s.col_ptr_for_row_idx());
                let mut negative = 0;
                for sn in 0..s.n_supernodes() {
                    let ncols = end[sn] - begin[sn];
                    let nrows = ncols + rows[sn + 1] - rows[sn];
                    negative += (0..ncols)
                        .filter(|&i| d(vals[sn] + i * nrows + i) < 0.0)
                        .count();
                }
                negative
            }
        };
        negative == self.kept.len()
    }

    /// [`Ipm::factor`], with the inertia corrected where asked: raise τ
    /// (IPOPT's rule) until the factor's inertia is right. False when the
    /// factorisation fails, or no τ up to SHIFT_MAX corrects the inertia.
    fn factorise(&mut self, p: &CscMatrix<f64>, a: &CscMatrix<f64>, d: &[f64]) -> bool {
        if !self.inertia_correction {
            return self.factor(p, a, d);
        }
        loop {
            if self.factor(p, a, d) && self.inertia_is_right() {
                return true;
            }
            self.shift = if self.shift == 0.0 {
                if self.last_shift == 0.0 {
                    SHIFT_FIRST
                } else {
                    (SHIFT_DECREASE * self.last_shift).max(SHIFT_MIN)
                }
            } else if self.last_shift == 0.0 {
                SHIFT_INCREASE_FIRST * self.shift
            } else {
                SHIFT_INCREASE * self.shift
            };
            if !(self.shift <= SHIFT_MAX) {
                return false;
            }
        }
    }

    /// Solve [P, Aᵀ; A, −D] [dx; dz] = [rx; rr] with the current factor
    /// (of A and D as given), refining against the unregularised matrix.
    fn solve_kkt(
        &mut self,
        a: &CscMatrix<f64>,
        d: &[f64],
        rx: &[f64],
        rr: &[f64],
        dx: &mut [f64],
        dz: &mut [f64],
    ) {
        let (n, nk) = (self.n, self.kept.len());
        // The vectors of this solve, kept between calls.
        let mut scratch = std::mem::take(&mut self.kkt_scratch);
        let [rhs, sol, res, trial] = &mut scratch;
        for v in [&mut *rhs, &mut *res] {
            v.clear();
            v.resize(n + nk, 0.0);
        }
        // Reduced right-hand side: eliminated rows fold into rx.
        rhs[..n].copy_from_slice(rx);
        for (r, b) in self.bound.iter().enumerate() {
            if let Some((k, j)) = *b {
                rhs[j] += a.nzval[k] * rr[r] / d[r];
            }
        }
        for (k, &r) in self.kept.iter().enumerate() {
            rhs[n + k] = match self.twin[k] {
                usize::MAX => rr[r],
                t => {
                    let (theta_r, theta_t, _) = self.twin_split(k, d);
                    theta_r * rr[r] - theta_t * rr[t]
                }
            };
        }
        sol.clone_from(rhs);
        self.ldlt_solve(sol);
        // Iterative refinement against the true reduced system, while it
        // pays: each step must cut the residual REFINE_STOP_RATIO-fold, or
        // it is undone (clarabel's rule).
        let bound_res = REFINE_ABS_TOL + REFINE_TOL * norm_inf(rhs);
        let residual = |this: &Self, sol: &[f64], res: &mut [f64]| {
            this.kkt_mul(sol, res);
            let mut worst = 0.0f64;
            for (r, h) in res.iter_mut().zip(rhs.iter()) {
                *r = h - *r;
                worst = worst.max(r.abs());
            }
            worst
        };
        let mut worst = residual(self, sol, res);
        for _ in 0..REFINE_STEPS {
            if worst <= bound_res {
                break;
            }
            self.ldlt_solve(res);
            trial.clear();
            trial.extend(sol.iter().zip(res.iter()).map(|(s, r)| s + r));
            let w = residual(self, trial, res);
            if !(w * REFINE_STOP_RATIO <= worst) {
                break;
            }
            std::mem::swap(sol, trial);
            worst = w;
        }
        dx.copy_from_slice(&sol[..n]);
        for r in 0..self.m {
            if let Some((k, j)) = self.bound[r] {
                dz[r] = (a.nzval[k] * dx[j] - rr[r]) / d[r];
            }
        }
        for (k, &r) in self.kept.iter().enumerate() {
            let dzk = sol[n + k];
            match self.twin[k] {
                usize::MAX => dz[r] = dzk,
                t => {
                    let (theta_r, theta_t, c) = self.twin_split(k, d);
                    let both = c * (rr[r] + rr[t]);
                    dz[r] = theta_r * dzk - both;
                    dz[t] = -theta_t * dzk - both;
                }
            }
        }
        self.kkt_scratch = scratch;
    }

    fn ldlt_solve(&mut self, v: &mut [f64]) {
        if let Some(layout) = &mut self.layout {
            match self.symbolic.perm().map(|p| p.arrays().0) {
                Some(fwd) => {
                    for (w, &f) in self.perm_work.iter_mut().zip(fwd) {
                        *w = v[f];
                    }
                    layout.solve(&self.l_values, &mut self.perm_work, &mut self.solve_scratch);
                    for (&w, &f) in self.perm_work.iter().zip(fwd) {
                        v[f] = w;
                    }
                }
                None => layout.solve(&self.l_values, v, &mut self.solve_scratch),
            }
            return;
        }
        let len = v.len();
        let rhs = MatMut::from_column_major_slice_mut(v, len, 1);
        LdltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.work),
        );
    }

    /// out = (reduced KKT matrix of the last factorisation, without its
    /// static regularisation) · v, from the assembled upper triangle: one
    /// pass over its entries, where forming it from P, A and D again
    /// ([`Ipm::reduced_mul`]) took three.
    fn kkt_mul(&self, v: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o = 0.0);
        for (j, &vj) in v.iter().enumerate() {
            let mut acc = 0.0;
            for k in self.colptr[j]..self.colptr[j + 1] {
                let (i, e) = (self.rowind[k], self.values[k]);
                out[i] += e * vj;
                if i != j {
                    acc += e * v[i];
                }
            }
            out[j] += acc;
        }
        let n = self.n;
        for (o, x) in out[..n].iter_mut().zip(&v[..n]) {
            *o -= STATIC_REG * x;
        }
        for (o, x) in out[n..].iter_mut().zip(&v[n..]) {
            *o += STATIC_REG * x;
        }
    }

    /// out = (reduced KKT matrix, unregularised) · v, formed from P, A and
    /// the row weights d (the tests' reference for [`Ipm::kkt_mul`]).
    #[cfg(test)]
    fn reduced_mul(
        &self,
        p: &CscMatrix<f64>,
        a: &CscMatrix<f64>,
        d: &[f64],
        v: &[f64],
        out: &mut [f64],
    ) {
        let n = self.n;
        let mut kept_pos = vec![usize::MAX; self.m];
        for (k, &r) in self.kept.iter().enumerate() {
            kept_pos[r] = k;
        }
        out.iter_mut().for_each(|o| *o = 0.0);
        let (vx, vk) = v.split_at(n);
        {
            let (ox, _) = out.split_at_mut(n);
            Self::p_mul(p, vx, ox);
            for (o, v) in ox.iter_mut().zip(vx) {
                *o += self.shift * v;
            }
        }
        for (r, b) in self.bound.iter().enumerate() {
            if let Some((k, j)) = *b {
                out[j] += a.nzval[k] * a.nzval[k] / d[r] * vx[j];
            }
        }
        for j in 0..n {
            for k in a.colptr[j]..a.colptr[j + 1] {
                let pos = kept_pos[a.rowval[k]];
                if pos != usize::MAX {
                    out[j] += a.nzval[k] * vk[pos];
                    out[n + pos] += a.nzval[k] * vx[j];
                }
            }
        }
        for k in 0..self.kept.len() {
            out[n + k] -= self.merged_weight(k, d) * vk[k];
        }
    }

    /// Largest α ≤ 1 keeping v + α dv ≥ 0 on the inequality rows.
    fn max_step(&self, v: &[f64], dv: &[f64]) -> f64 {
        let mut alpha = 1.0f64;
        for r in self.num_eq..self.m {
            if dv[r] < 0.0 {
                alpha = alpha.min(-v[r] / dv[r]);
            }
        }
        alpha
    }

    /// Solve with these values (P, A with the pattern given to `new`).
    pub fn solve(
        &mut self,
        p: &CscMatrix<f64>,
        a: &CscMatrix<f64>,
        q: &[f64],
        b: &[f64],
        tol: f64,
    ) -> IpmStatus {
        // Ruiz equilibration of [P, Aᵀ; A, 0] (10 passes, cumulative factors
        // within [1e-4, 1e4], as clarabel does, but for every QP): x = D x̂, rows
        // scaled by E; the tolerances apply to the scaled QP. Without it
        // the SQP on the reduced jump took another path in its first
        // iterations and ended at 12.3 cm (418 iterations); with it, 28.9 cm
        // (172 iterations; clarabel: 28.45 cm, 150).
        let (n, m) = (self.n, self.m);
        let (mut dv, mut ev) = (vec![1.0f64; n], vec![1.0f64; m]);
        let (mut ps, mut as_) = (p.clone(), a.clone());
        for _ in 0..10 {
            let (mut cn, mut rn) = (vec![0.0f64; n], vec![0.0f64; m]);
            for j in 0..n {
                for k in ps.colptr[j]..ps.colptr[j + 1] {
                    let (i, v) = (ps.rowval[k], ps.nzval[k].abs());
                    cn[j] = cn[j].max(v);
                    cn[i] = cn[i].max(v);
                }
                for k in as_.colptr[j]..as_.colptr[j + 1] {
                    let (r, v) = (as_.rowval[k], as_.nzval[k].abs());
                    cn[j] = cn[j].max(v);
                    rn[r] = rn[r].max(v);
                }
            }
            // The cumulative factor stays within [1e-4, 1e4]: a row of
            // entries near zero (a constraint whose linearisation vanishes,
            // 1e-29 on the jump with smooth contact) would otherwise be
            // scaled up by 1e4 per pass, its right-hand side with it (to
            // 1e26 in ten passes), and the start would be lost.
            let f = |v: f64, cum: f64| {
                if v > 0.0 {
                    (1.0 / v.sqrt()).clamp(EQUILIBRATION_MIN / cum, EQUILIBRATION_MAX / cum)
                } else {
                    1.0
                }
            };
            let cs: Vec<f64> = cn.iter().zip(&dv).map(|(&v, &c)| f(v, c)).collect();
            let rs: Vec<f64> = rn.iter().zip(&ev).map(|(&v, &c)| f(v, c)).collect();
            for j in 0..n {
                for k in ps.colptr[j]..ps.colptr[j + 1] {
                    ps.nzval[k] *= cs[ps.rowval[k]] * cs[j];
                }
                for k in as_.colptr[j]..as_.colptr[j + 1] {
                    as_.nzval[k] *= rs[as_.rowval[k]] * cs[j];
                }
                dv[j] *= cs[j];
            }
            for r in 0..m {
                ev[r] *= rs[r];
            }
        }
        let qs: Vec<f64> = q.iter().zip(&dv).map(|(q, d)| q * d).collect();
        let bs: Vec<f64> = b.iter().zip(&ev).map(|(b, e)| b * e).collect();
        // A twin row's scale equals its row's (the same magnitudes), so the
        // scaled rows stay negated where the given ones are.
        if !self.twins_hold(&as_) {
            self.iterations = 0;
            return IpmStatus::Failed;
        }
        self.assembled = false;
        self.shift = 0.0;
        if self.inertia_correction {
            // The rows active at the last answer count as active (they
            // will most likely be again): P + τ I must be positive definite
            // on the null space of the equalities and of these rows. Taking
            // every inequality row as inactive instead asked for τ ≈ 0.1
            // (scaled) at every QP of the reduced jump and made the SQP
            // converge linearly (246 iterations against 180).
            let mut w = vec![0.0; m];
            for r in self.num_eq..m {
                w[r] = if self.prev_active.get(r).copied().unwrap_or(false) {
                    1.0 / INACTIVE_WEIGHT
                } else {
                    INACTIVE_WEIGHT
                };
            }
            if !self.factorise(&ps, &as_, &w) {
                self.iterations = 0;
                return IpmStatus::Failed;
            }
        }
        // Warm start from the last answer (an SQP's QPs change little from
        // one iteration to the next); where it does not solve, once more
        // from the cold start.
        let warm: Option<Vec<f64>> =
            (self.warm_start && self.last_solved && !self.inertia_correction && self.z.len() == m)
                .then(|| self.z.iter().zip(&ev).map(|(z, e)| z / e).collect());
        let warm_started = warm.is_some();
        let mut status = self.solve_scaled(&ps, &as_, &qs, &bs, tol, warm);
        if warm_started && status != IpmStatus::Solved {
            let warm_iterations = self.iterations;
            status = self.solve_scaled(&ps, &as_, &qs, &bs, tol, None);
            self.iterations += warm_iterations;
        }
        self.last_solved = status == IpmStatus::Solved;
        if self.shift > 0.0 {
            self.last_shift = self.shift;
        }
        if status == IpmStatus::Solved {
            // Active: the slack below its multiplier (scaled).
            self.prev_active = (0..m)
                .map(|r| r >= self.num_eq && self.s[r] < self.z[r])
                .collect();
        }
        self.shift_curvature = 0.5 * self.shift * self.x.iter().map(|v| v * v).sum::<f64>();
        for j in 0..n {
            self.shift_diag[j] = self.shift / (dv[j] * dv[j]);
            self.x[j] *= dv[j];
        }
        for r in 0..m {
            self.z[r] *= ev[r];
            self.s[r] /= ev[r];
        }
        status
    }

    fn solve_scaled(
        &mut self,
        p: &CscMatrix<f64>,
        a: &CscMatrix<f64>,
        q: &[f64],
        b: &[f64],
        tol: f64,
        warm: Option<Vec<f64>>,
    ) -> IpmStatus {
        let (n, m, ne) = (self.n, self.m, self.num_eq);
        let m_in = (m - ne).max(1) as f64;
        self.iterations = 0;
        let mut d = vec![0.0; m];
        let (mut x, mut s) = (vec![0.0; n], vec![0.0; m]);
        let mut z;
        if let Some(zw) = warm {
            // x = 0 (the step of a new QP), the slacks b − A·0 = b of the
            // inequality rows and the last answer's multipliers, both kept
            // WARM_START_FLOOR from zero.
            z = zw;
            for r in ne..m {
                s[r] = b[r].max(WARM_START_FLOOR);
                z[r] = z[r].max(WARM_START_FLOOR);
            }
        } else {
            // Start: [P, Aᵀ; A, −I_in] [x; z] = [−q; b], then s = −z shifted.
            for r in ne..m {
                d[r] = 1.0;
            }
            if !self.factorise(p, a, &d) {
                return IpmStatus::Failed;
            }
            let mq: Vec<f64> = q.iter().map(|v| -v).collect();
            z = vec![0.0; m];
            self.solve_kkt(a, &d, &mq, b, &mut x, &mut z);
            for r in ne..m {
                s[r] = -z[r];
            }
            let shift = |v: &mut [f64]| {
                let worst = v[ne..].iter().fold(f64::NEG_INFINITY, |w, &x| w.max(-x));
                if worst >= 0.0 {
                    for x in &mut v[ne..] {
                        *x += 1.0 + worst;
                    }
                }
            };
            shift(&mut s);
            shift(&mut z);
        }
        let (norm_q, norm_b) = (norm_inf(q), norm_inf(b));
        let (mut rd, mut rp) = (vec![0.0; n], vec![0.0; m]);
        let (mut ax, mut px, mut atz) = (vec![0.0; m], vec![0.0; n], vec![0.0; n]);
        let (mut dx, mut dz, mut ds) = (vec![0.0; n], vec![0.0; m], vec![0.0; m]);
        let (mut dxa, mut dza, mut dsa) = (vec![0.0; n], vec![0.0; m], vec![0.0; m]);
        let (mut rx, mut rr) = (vec![0.0; n], vec![0.0; m]);
        let (mut dxc, mut dzc, mut dsc, mut cc) =
            (vec![0.0; n], vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        let mut status = IpmStatus::Failed;
        let mut almost = false;
        let mut stalled = false;
        let mut rp_history = Vec::with_capacity(MAX_ITER as usize + 1);
        // LEAP_IPM_VERBOSE=1 prints each iteration (to debug a QP).
        let verbose = std::env::var_os("LEAP_IPM_VERBOSE").is_some();
        for it in 0..=MAX_ITER {
            self.iterations = it;
            // Residuals.
            for (v, xj) in px.iter_mut().zip(&x) {
                *v = self.shift * xj;
            }
            Self::p_mul(p, &x, &mut px);
            ax.iter_mut().for_each(|v| *v = 0.0);
            atz.iter_mut().for_each(|v| *v = 0.0);
            for j in 0..n {
                for k in a.colptr[j]..a.colptr[j + 1] {
                    let r = a.rowval[k];
                    ax[r] += a.nzval[k] * x[j];
                    atz[j] += a.nzval[k] * z[r];
                }
            }
            for j in 0..n {
                rd[j] = px[j] + q[j] + atz[j];
            }
            for r in 0..m {
                rp[r] = ax[r] + s[r] - b[r];
            }
            let gap: f64 = (ne..m).map(|r| s[r] * z[r]).sum();
            let mu = gap / m_in;
            let pobj = 0.5 * x.iter().zip(&px).map(|(a, b)| a * b).sum::<f64>()
                + x.iter().zip(q).map(|(a, b)| a * b).sum::<f64>();
            let scale_p = 1.0 + norm_b.max(norm_inf(&ax)).max(norm_inf(&s));
            let scale_d = 1.0 + norm_q.max(norm_inf(&px)).max(norm_inf(&atz));
            let meets = |tol: f64| {
                norm_inf(&rp) <= tol * scale_p
                    && norm_inf(&rd) <= tol * scale_d
                    && gap <= tol * (1.0 + pobj.abs())
            };
            if meets(tol) {
                status = IpmStatus::Solved;
                break;
            }
            // Where the iteration cannot go on (a failed factorisation, a
            // vanishing step, complementarity far below the tolerance while
            // a residual stalls), an iterate within the reduced tolerance is
            // returned as solved, as clarabel's "almost solved".
            almost = meets(REDUCED_TOL_FACTOR * tol);
            if gap < 1e-4 * tol * (1.0 + pobj.abs()) || !(mu > 0.0) {
                break;
            }
            // A primal residual that no longer falls (less than halved in
            // STALL_WINDOW iterations, where a feasible QP's falls by the
            // product of the steps' (1 − α)) marks an infeasible QP that
            // the Farkas test has not yet caught, or a stalled one: both are
            // clarabel's to decide (on the jump, 8 of 9 such QPs were
            // infeasible, found at the 80-iteration limit before).
            let rp_rel = norm_inf(&rp) / scale_p;
            rp_history.push(rp_rel);
            if it >= STALL_WINDOW
                && rp_rel > REDUCED_TOL_FACTOR * tol
                && rp_rel > 0.5 * rp_history[it as usize - STALL_WINDOW as usize]
            {
                stalled = true;
                break;
            }
            // Farkas: Aᵀz ≈ 0 with bᵀz < 0 (z ≥ 0 on the inequality rows
            // holds throughout).
            let btz: f64 = b.iter().zip(&z).map(|(a, b)| a * b).sum();
            if btz < 0.0 && norm_inf(&atz) <= 1e-8 * -btz && norm_inf(&z) > 1e6 * scale_d {
                status = IpmStatus::PrimalInfeasible;
                break;
            }
            if verbose {
                let (wr, wv) = rp.iter().enumerate().fold((0, 0.0f64), |(a, b), (r, v)| {
                    if v.abs() > b {
                        (r, v.abs())
                    } else {
                        (a, b)
                    }
                });
                crate::errln!(
                    "    largest primal residual: row {wr} ({}) {wv:.2e}, s {:.2e} z {:.2e}",
                    if wr < ne { "equality" } else { "inequality" },
                    s[wr],
                    z[wr]
                );
                crate::errln!(
                    "ipm {it:3} pobj {pobj:+.6e} rp {:.1e} rd {:.1e} gap {gap:.1e} mu {mu:.1e}",
                    norm_inf(&rp) / scale_p,
                    norm_inf(&rd) / scale_d
                );
            }
            if it == MAX_ITER {
                break;
            }
            for r in ne..m {
                d[r] = s[r] / z[r];
            }
            if !self.factorise(p, a, &d) {
                break;
            }
            // Predictor (σ = 0): r_c = s∘z.
            for j in 0..n {
                rx[j] = -rd[j];
            }
            for r in 0..m {
                rr[r] = if r < ne { -rp[r] } else { -rp[r] + s[r] };
            }
            self.solve_kkt(a, &d, &rx, &rr, &mut dxa, &mut dza);
            for r in ne..m {
                dsa[r] = -(s[r] * z[r] + s[r] * dza[r]) / z[r];
            }
            let alpha_a = self.max_step(&s, &dsa).min(self.max_step(&z, &dza));
            let gap_a: f64 = (ne..m)
                .map(|r| (s[r] + alpha_a * dsa[r]) * (z[r] + alpha_a * dza[r]))
                .sum();
            let sigma = (gap_a / gap.max(f64::MIN_POSITIVE)).clamp(0.0, 1.0).powi(3);
            // Corrector: r_c = s∘z + ds_a∘dz_a − σμ.
            for r in ne..m {
                let rc = s[r] * z[r] + dsa[r] * dza[r] - sigma * mu;
                rr[r] = -rp[r] + rc / z[r];
            }
            self.solve_kkt(a, &d, &rx, &rr, &mut dx, &mut dz);
            for r in ne..m {
                let rc = s[r] * z[r] + dsa[r] * dza[r] - sigma * mu;
                ds[r] = -(rc + s[r] * dz[r]) / z[r];
            }
            let mut alpha_max = self.max_step(&s, &ds).min(self.max_step(&z, &dz));
            // Gondzio's multiple centrality correctors (Gondzio 1996;
            // Colombo & Gondzio 2008): aim at a longer step α̃ and pull the
            // products s_r z_r of the trial point there back into
            // [β_min σμ, β_max σμ]. Each costs one solve with the factor
            // already computed (a few percent of a factorisation); kept only
            // when it lengthens the step enough.
            let mut correctors = 0;
            while correctors < MAX_CORRECTORS && alpha_max < 1.0 {
                let target = (alpha_max + GONDZIO_DELTA).min(1.0);
                let smu = (sigma * mu).max(f64::MIN_POSITIVE);
                rx.iter_mut().for_each(|v| *v = 0.0);
                for r in 0..m {
                    rr[r] = 0.0;
                    if r >= ne {
                        let v = (s[r] + target * ds[r]) * (z[r] + target * dz[r]);
                        let c = (v.clamp(0.1 * smu, 10.0 * smu) - v).max(-10.0 * smu);
                        cc[r] = c;
                        rr[r] = -c / z[r];
                    }
                }
                self.solve_kkt(a, &d, &rx, &rr, &mut dxc, &mut dzc);
                for r in ne..m {
                    dsc[r] = ds[r] + (cc[r] - s[r] * dzc[r]) / z[r];
                    dzc[r] += dz[r];
                }
                for r in 0..ne {
                    dzc[r] += dz[r];
                }
                for j in 0..n {
                    dxc[j] += dx[j];
                }
                let alpha_c = self.max_step(&s, &dsc).min(self.max_step(&z, &dzc));
                if alpha_c < alpha_max + 0.1 * GONDZIO_DELTA {
                    break;
                }
                alpha_max = alpha_c;
                std::mem::swap(&mut dx, &mut dxc);
                std::mem::swap(&mut dz, &mut dzc);
                std::mem::swap(&mut ds, &mut dsc);
                correctors += 1;
            }
            let alpha = (0.99 * alpha_max).min(1.0);
            if verbose {
                crate::errln!(
                    "    alpha_aff {alpha_a:.3} sigma {sigma:.2e} alpha {alpha:.3} correctors {correctors}"
                );
            }
            let finite = dx.iter().chain(&dz).chain(&ds[ne..]).all(|v| v.is_finite());
            if !(alpha > 1e-10) || !finite {
                break;
            }
            for j in 0..n {
                x[j] += alpha * dx[j];
            }
            for r in 0..m {
                z[r] += alpha * dz[r];
                if r >= ne {
                    s[r] += alpha * ds[r];
                }
            }
        }
        if status == IpmStatus::Failed && almost {
            status = IpmStatus::Solved;
        } else if status == IpmStatus::Failed && stalled {
            status = IpmStatus::Stalled;
        }
        self.x = x;
        self.z = z;
        self.s = s;
        status
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// min ½(x0² + x1²) − x0 − x1 s.t. x0 + x1 = 1, 0 ≤ x0 ≤ 0.2:
    /// x = (0.2, 0.8), from the KKT conditions by hand.
    #[test]
    fn small_qp_matches_its_kkt_solution() {
        let p = CscMatrix::new(2, 2, vec![0, 1, 2], vec![0, 1], vec![1.0, 1.0]);
        // Rows: x0 + x1 = 1; −x0 ≤ 0; x0 ≤ 0.2; x0 + 2 x1 ≤ 10 (inactive).
        let a = CscMatrix::new(
            4,
            2,
            vec![0, 4, 6],
            vec![0, 1, 2, 3, 0, 3],
            vec![1.0, -1.0, 1.0, 1.0, 1.0, 2.0],
        );
        let mut ipm = Ipm::new(&p, &a, 1).unwrap();
        let st = ipm.solve(&p, &a, &[-1.0, -1.0], &[1.0, 0.0, 0.2, 10.0], 1e-10);
        assert_eq!(st, IpmStatus::Solved);
        assert!((ipm.x[0] - 0.2).abs() < 1e-8 && (ipm.x[1] - 0.8).abs() < 1e-8);
        // Stationarity: x1 − 1 + y = 0 → y = 0.2; x0 − 1 + y + z_ub = 0 →
        // z_ub = 0.6.
        assert!((ipm.z[0] - 0.2).abs() < 1e-7);
        assert!((ipm.z[2] - 0.6).abs() < 1e-7);
        assert!(ipm.z[1].abs() < 1e-7 && ipm.z[3].abs() < 1e-7);
    }

    /// The QP above with an inactive row whose entries nearly vanish
    /// (1e-29·(x0 + x1) ≤ 0.01, as a constraint whose linearisation vanishes
    /// writes it): the same answer. Equilibration bounded per pass only
    /// scaled that row, and its right-hand side, by 1e4 in each of its ten
    /// passes, and the start was lost (clarabel bounds the cumulative
    /// scaling, and so does leap).
    #[test]
    fn vanishing_row_keeps_the_kkt_solution() {
        let p = CscMatrix::new(2, 2, vec![0, 1, 2], vec![0, 1], vec![1.0, 1.0]);
        let a = dense_csc(
            5,
            2,
            &[
                (0, 0, 1.0),
                (0, 1, 1.0),
                (1, 0, -1.0),
                (2, 0, 1.0),
                (3, 0, 1.0),
                (3, 1, 2.0),
                (4, 0, 1e-29),
                (4, 1, 1e-29),
            ],
        );
        let mut ipm = Ipm::new(&p, &a, 1).unwrap();
        let st = ipm.solve(&p, &a, &[-1.0, -1.0], &[1.0, 0.0, 0.2, 10.0, 0.01], 1e-10);
        assert_eq!(st, IpmStatus::Solved);
        assert!((ipm.x[0] - 0.2).abs() < 1e-8 && (ipm.x[1] - 0.8).abs() < 1e-8);
        assert!((ipm.z[0] - 0.2).abs() < 1e-7 && (ipm.z[2] - 0.6).abs() < 1e-7);
        assert!(ipm.z[4].abs() < 1e-7);
    }

    /// P = B Bᵀ (upper triangle) with B random, n × ⌊n/2⌋: positive
    /// semidefinite and singular.
    fn random_singular_psd(rng: &mut rand_chacha::ChaCha8Rng, n: usize) -> CscMatrix<f64> {
        use rand::Rng;
        let k = (n / 2).max(1);
        let bm: Vec<f64> = (0..n * k).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut entries = Vec::new();
        for j in 0..n {
            for i in 0..=j {
                let v: f64 = (0..k).map(|t| bm[i * k + t] * bm[j * k + t]).sum();
                entries.push((i, j, v));
            }
        }
        dense_csc(n, n, &entries)
    }

    /// The objective at `x` within 1e-7 (relative) of clarabel's optimum of
    /// the same QP (the first `ne` rows equalities).
    fn assert_objective_matches_clarabel(
        p: &CscMatrix<f64>,
        a: &CscMatrix<f64>,
        q: &[f64],
        b: &[f64],
        ne: usize,
        x: &[f64],
        case: usize,
    ) {
        use clarabel::solver::{
            DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
            ZeroConeT,
        };
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .presolve_enable(false)
            .build()
            .unwrap();
        let cones = [ZeroConeT(ne), NonnegativeConeT(a.m - ne)];
        let mut cl = DefaultSolver::new(p, q, a, b, &cones, settings).unwrap();
        cl.solve();
        assert_eq!(cl.solution.status, SolverStatus::Solved, "case {case}");
        let obj = |x: &[f64]| {
            let mut px = vec![0.0; p.n];
            Ipm::p_mul(p, x, &mut px);
            (0..p.n)
                .map(|j| 0.5 * x[j] * px[j] + q[j] * x[j])
                .sum::<f64>()
        };
        let (f, f_cl) = (obj(x), obj(&cl.solution.x));
        assert!(
            (f - f_cl).abs() <= 1e-7 * (1.0 + f_cl.abs()),
            "case {case}: objective {f} against clarabel's {f_cl}"
        );
    }

    /// Random feasible convex QPs with equality rows, general inequality
    /// rows and bound rows (single entries), against clarabel's solution
    /// of the same QP.
    #[test]
    fn random_qps_match_clarabel() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for case in 0..20 {
            let n = rng.random_range(3..30);
            let (ne, ng) = (rng.random_range(0..n / 2 + 1), rng.random_range(0..n));
            let p = random_singular_psd(&mut rng, n);
            // Rows: equalities, general inequalities, then x ≥ −1, x ≤ 1.
            let x0: Vec<f64> = (0..n).map(|_| rng.random_range(-0.5..0.5)).collect();
            let mut rows = Vec::new();
            let mut b = Vec::new();
            for r in 0..ne + ng {
                let mut row = Vec::new();
                for j in 0..n {
                    if rng.random_bool(0.4) {
                        row.push((r, j, rng.random_range(-1.0..1.0)));
                    }
                }
                let ax: f64 = row.iter().map(|&(_, j, v)| v * x0[j]).sum();
                b.push(if r < ne {
                    ax
                } else {
                    ax + rng.random_range(0.0..0.3)
                });
                rows.extend(row);
            }
            let m0 = ne + ng;
            for j in 0..n {
                rows.push((m0 + 2 * j, j, -1.0));
                b.push(1.0);
                rows.push((m0 + 2 * j + 1, j, 1.0));
                b.push(1.0);
            }
            let m = m0 + 2 * n;
            let a = dense_csc(m, n, &rows);
            let q: Vec<f64> = (0..n).map(|_| rng.random_range(-3.0..3.0)).collect();
            let mut ipm = Ipm::new(&p, &a, ne).unwrap();
            assert_eq!(
                ipm.solve(&p, &a, &q, &b, 1e-10),
                IpmStatus::Solved,
                "case {case}"
            );
            assert_objective_matches_clarabel(&p, &a, &q, &b, ne, &ipm.x, case);
            // Feasibility and dual sign of leap's own answer.
            for r in 0..m {
                let ax: f64 = rows
                    .iter()
                    .filter(|e| e.0 == r)
                    .map(|e| e.2 * ipm.x[e.1])
                    .sum();
                if r < ne {
                    assert!((ax - b[r]).abs() < 1e-8, "case {case} row {r}");
                } else {
                    assert!(ax <= b[r] + 1e-8 && ipm.z[r] >= 0.0, "case {case} row {r}");
                }
            }
        }
    }

    fn dense_csc(m: usize, n: usize, entries: &[(usize, usize, f64)]) -> CscMatrix<f64> {
        let mut sorted = entries.to_vec();
        sorted.sort_by_key(|e| (e.1, e.0));
        let mut colptr = vec![0usize; n + 1];
        for e in &sorted {
            colptr[e.1 + 1] += 1;
        }
        for j in 0..n {
            colptr[j + 1] += colptr[j];
        }
        CscMatrix::new(
            m,
            n,
            colptr,
            sorted.iter().map(|e| e.0).collect(),
            sorted.iter().map(|e| e.2).collect(),
        )
    }

    /// A stage-structured QP (a transcription's shape: dense 12-variable
    /// stages coupled to their neighbours by the Hessian and by 8 equality
    /// rows each, then the bounds x ≤ 1, folded into the KKT diagonal):
    /// (P, A, equality rows, rows).
    fn stage_qp(seed: u64) -> (CscMatrix<f64>, CscMatrix<f64>, usize, usize) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let (stages, size, links) = (30, 12, 8);
        let n = stages * size;
        let mut pe = Vec::new();
        for s in 0..stages {
            let lo = s * size;
            let hi = ((s + 2) * size).min(n);
            for j in lo..hi {
                for i in lo..=j {
                    let v = if i == j {
                        4.0
                    } else {
                        rng.random_range(-0.3..0.3)
                    };
                    pe.push((i, j, v));
                }
            }
        }
        // Overlapping stage blocks add into one entry: sum duplicates.
        pe.sort_by_key(|e| (e.1, e.0));
        pe.dedup_by(|b, a| {
            let same = (a.0, a.1) == (b.0, b.1);
            if same {
                a.2 += b.2;
            }
            same
        });
        let p = dense_csc(n, n, &pe);
        let mut rows = Vec::new();
        let mut r = 0;
        for s in 0..stages - 1 {
            for _ in 0..links {
                for j in s * size..(s + 2) * size {
                    if rng.random_bool(0.5) {
                        rows.push((r, j, rng.random_range(-1.0..1.0)));
                    }
                }
                r += 1;
            }
        }
        let ne = r;
        for j in 0..n {
            rows.push((r, j, 1.0));
            r += 1;
        }
        let a = dense_csc(r, n, &rows);
        (p, a, ne, r)
    }

    /// Random convex QPs whose general rows are ranges l ≤ a·x ≤ u, written
    /// as the SQP writes them (−a·x ≤ −l, then a·x ≤ u; some ranges
    /// nearly equalities), solved with each pair merged into one KKT row
    /// ([`Ipm::with_twins`]) and as separate rows: the same answer,
    /// multipliers and slacks included; and against clarabel's objective.
    /// A twin whose values stop being negated fails the solve, and twins
    /// with different columns are refused.
    #[test]
    fn twin_rows_solve_as_the_rows_they_stand_for() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
        for case in 0..20 {
            let n = rng.random_range(4..30);
            let (ne, ng) = (rng.random_range(0..n / 3 + 1), rng.random_range(1..2 * n));
            let p = random_singular_psd(&mut rng, n);
            let x0: Vec<f64> = (0..n).map(|_| rng.random_range(-0.5..0.5)).collect();
            let (mut rows, mut b, mut twins) = (Vec::new(), Vec::new(), Vec::new());
            let mut r = 0;
            for g in 0..ne + ng {
                let mut row = Vec::new();
                for j in 0..n {
                    if rng.random_bool(0.5) {
                        row.push((j, rng.random_range(-1.0..1.0)));
                    }
                }
                if row.len() < 2 {
                    row = vec![(0, 1.0), (n - 1, -1.0)];
                }
                let ax: f64 = row.iter().map(|&(j, v)| v * x0[j]).sum();
                if g < ne {
                    rows.extend(row.iter().map(|&(j, v)| (r, j, v)));
                    b.push(ax);
                    r += 1;
                    continue;
                }
                let width = if g % 5 == 0 { 1e-9 } else { 0.3 };
                let lower = ax - rng.random_range(0.0..width);
                let upper = ax + rng.random_range(0.0..width);
                rows.extend(row.iter().map(|&(j, v)| (r, j, -v)));
                b.push(-lower);
                rows.extend(row.iter().map(|&(j, v)| (r + 1, j, v)));
                b.push(upper);
                twins.push((r, r + 1));
                r += 2;
            }
            for j in 0..n {
                rows.push((r, j, -1.0));
                rows.push((r + 1, j, 1.0));
                b.extend([1.0, 1.0]);
                r += 2;
            }
            let m = r;
            let a = dense_csc(m, n, &rows);
            assert_eq!(Ipm::detect_twins(&a, ne), twins, "case {case}");
            let q: Vec<f64> = (0..n).map(|_| rng.random_range(-3.0..3.0)).collect();
            let mut merged =
                Ipm::with_twins(&p, &a, ne, KktOrdering::SmallerFactor, &twins).unwrap();
            let mut separate = Ipm::new(&p, &a, ne).unwrap();
            assert_eq!(merged.kept.len() + twins.len(), separate.kept.len());
            for ipm in [&mut merged, &mut separate] {
                assert_eq!(
                    ipm.solve(&p, &a, &q, &b, 1e-10),
                    IpmStatus::Solved,
                    "case {case}"
                );
            }
            let close = |x: &[f64], y: &[f64], what: &str| {
                let scale = 1.0 + norm_inf(y);
                for (i, (u, v)) in x.iter().zip(y).enumerate() {
                    assert!(
                        (u - v).abs() <= 1e-6 * scale,
                        "case {case}: {what} {i}: merged {u} against separate {v}"
                    );
                }
            };
            close(&merged.x, &separate.x, "x");
            close(&merged.s, &separate.s, "s");
            // A range's multiplier is the difference of its rows' (as the
            // SQP reads it); a nearly equal range leaves each row's own to
            // the interior point's path (s·z ≈ μ on both sides).
            let range = |z: &[f64]| -> Vec<f64> {
                let mut v = z.to_vec();
                for &(r, t) in &twins {
                    (v[r], v[t]) = (z[t] - z[r], 0.0);
                }
                v
            };
            close(&range(&merged.z), &range(&separate.z), "z");
            assert!(merged.z[ne..].iter().all(|&z| z >= 0.0), "case {case}");
            assert_objective_matches_clarabel(&p, &a, &q, &b, ne, &merged.x, case);
            // A twin that is no longer its row negated fails the solve.
            let (t0, _) = twins[0];
            let mut broken = a.clone();
            let e = (0..n)
                .flat_map(|j| broken.colptr[j]..broken.colptr[j + 1])
                .find(|&e| broken.rowval[e] == t0)
                .unwrap();
            broken.nzval[e] *= 1.5;
            assert_eq!(merged.solve(&p, &broken, &q, &b, 1e-10), IpmStatus::Failed);
        }
        // Twins must have the same columns.
        let p = dense_csc(3, 3, &[(0, 0, 1.0), (1, 1, 1.0), (2, 2, 1.0)]);
        let a = dense_csc(
            2,
            3,
            &[(0, 0, 1.0), (0, 1, 1.0), (1, 0, -1.0), (1, 2, -1.0)],
        );
        let e = Ipm::with_twins(&p, &a, 0, KktOrdering::Amd, &[(0, 1)])
            .err()
            .unwrap();
        assert!(e.contains("different columns"), "{e}");
    }

    /// One supernodal solver with twin rows (on two threads), reused for
    /// QPs of the same pattern whose P, A, q and b all change, as the SQP
    /// reuses it: each answer equals a fresh solver's without twins, so the
    /// KKT values assembled once per QP are assembled again for each.
    #[test]
    fn twin_solver_reused_across_qps_matches_fresh_solvers() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(31);
        let (mut p, mut a, ne, m) = shooting_qp(9);
        let twins = Ipm::detect_twins(&a, ne);
        assert!(twins.len() > 20);
        let mut reused = supernodal_ipm(&p, &a, ne, 2);
        assert!(!reused.twin_entries.is_empty());
        let rows = row_entries(&a);
        for round in 0..3 {
            for j in 0..p.n {
                for k in p.colptr[j]..p.colptr[j + 1] {
                    p.nzval[k] = if p.rowval[k] == j {
                        p.n as f64
                    } else {
                        rng.random_range(-0.5..0.5)
                    };
                }
            }
            for entries in &rows {
                for &(_, k) in entries {
                    a.nzval[k] = if entries.len() == 1 {
                        1.0
                    } else {
                        rng.random_range(-1.0..1.0)
                    };
                }
            }
            for &(r, t) in &twins {
                for (&(_, kr), &(_, kt)) in rows[r].iter().zip(&rows[t]) {
                    a.nzval[kt] = -a.nzval[kr];
                }
            }
            let q: Vec<f64> = (0..p.n).map(|_| rng.random_range(-3.0..3.0)).collect();
            // x = 0 is feasible, strictly for the inequalities.
            let b: Vec<f64> = (0..m)
                .map(|r| {
                    if r < ne {
                        0.0
                    } else {
                        rng.random_range(0.05..0.5)
                    }
                })
                .collect();
            let mut fresh = Ipm::new(&p, &a, ne).unwrap();
            for ipm in [&mut reused, &mut fresh] {
                assert_eq!(
                    ipm.solve(&p, &a, &q, &b, 1e-10),
                    IpmStatus::Solved,
                    "round {round}"
                );
            }
            let scale = 1.0 + norm_inf(&fresh.x);
            for (j, (u, v)) in reused.x.iter().zip(&fresh.x).enumerate() {
                assert!(
                    (u - v).abs() <= 1e-6 * scale,
                    "round {round}: x {j}: reused {u} against fresh {v}"
                );
            }
        }
    }

    /// A QP of direct shooting's shape: the excitations of `stages` nodes
    /// and a final time, a dense P (BFGS), and per stage rows on every
    /// variable of its own and earlier stages and the final time (the
    /// states at a node depend on every excitation before it), most of
    /// them twice with opposite signs (range rows, as the SQP writes
    /// them), a few dropping entries at random; the first two rows are
    /// equalities, then the general rows, then the bounds. Its KKT system
    /// has a dense root supernode with one-column constraint rows below,
    /// whose updates the factorisation gathers in batches.
    fn shooting_qp(seed: u64) -> (CscMatrix<f64>, CscMatrix<f64>, usize, usize) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let (stages, size, per_stage) = (8, 6, 9);
        let n = stages * size + 1;
        let mut pe = Vec::new();
        for j in 0..n {
            for i in 0..=j {
                let v = if i == j {
                    n as f64
                } else {
                    rng.random_range(-0.5..0.5)
                };
                pe.push((i, j, v));
            }
        }
        let p = dense_csc(n, n, &pe);
        let mut general: Vec<Vec<(usize, f64)>> = Vec::new();
        for s in 0..stages {
            for _ in 0..per_stage {
                let mut row: Vec<(usize, f64)> = (0..(s + 1) * size)
                    .chain([n - 1])
                    .filter_map(|j| {
                        let v = rng.random_range(-1.0..1.0);
                        rng.random_bool(0.9).then_some((j, v))
                    })
                    .collect();
                if row.is_empty() {
                    row.push((n - 1, 1.0));
                }
                general.push(row);
            }
        }
        let mut rows = Vec::new();
        let mut r = 0;
        for (k, row) in general.iter().enumerate() {
            for &(j, v) in row {
                rows.push((r, j, v));
            }
            r += 1;
            // After the two equalities, most rows come again negated.
            if k >= 2 && k % 4 != 0 {
                for &(j, v) in row {
                    rows.push((r, j, -v));
                }
                r += 1;
            }
        }
        for j in 0..n {
            rows.push((r, j, 1.0));
            r += 1;
        }
        let a = dense_csc(r, n, &rows);
        (p, a, 2, r)
    }

    /// A linear term q in [−q_max, q_max] and the right-hand side b of
    /// [`stage_qp`]: equality rows in [−0.1, 0.1], the bounds x ≤ 1.
    fn stage_vectors(
        rng: &mut rand_chacha::ChaCha8Rng,
        n: usize,
        ne: usize,
        r: usize,
        q_max: f64,
    ) -> (Vec<f64>, Vec<f64>) {
        use rand::Rng;
        let q = (0..n).map(|_| rng.random_range(-q_max..q_max)).collect();
        let b = (0..r)
            .map(|k| {
                if k < ne {
                    rng.random_range(-0.1..0.1)
                } else {
                    1.0
                }
            })
            .collect();
        (q, b)
    }

    /// A solver of the QP with these patterns, its KKT matrix factorised
    /// supernodally on `threads` (1 or 2) threads, whatever its size.
    fn supernodal_ipm(p: &CscMatrix<f64>, a: &CscMatrix<f64>, ne: usize, threads: usize) -> Ipm {
        let mut ipm = Ipm::with_threshold(
            p,
            a,
            ne,
            SupernodalThreshold::FORCE_SUPERNODAL,
            KktOrdering::SmallerFactor,
            &Ipm::detect_twins(a, ne),
        )
        .unwrap();
        let min_work = if threads == 2 { 0.0 } else { f64::INFINITY };
        ipm.layout = FactorLayout::with_parallel_min_work(&ipm.symbolic, min_work);
        assert_eq!(ipm.layout.as_ref().unwrap().parallel(), threads == 2);
        ipm
    }

    /// The loop solve over faer's supernodal layout (one thread and two)
    /// against faer's own solve, on a stage-structured KKT system
    /// ([`stage_qp`]).
    #[test]
    fn supernodal_loop_solve_matches_faer() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
        let (p, a, ne, r) = stage_qp(11);
        for threads in [1, 2] {
            let mut ipm = supernodal_ipm(&p, &a, ne, threads);
            let d: Vec<f64> = (0..r).map(|k| if k < ne { 0.0 } else { 0.5 }).collect();
            assert!(ipm.factor(&p, &a, &d));
            let dim = ipm.diag.len();
            let rhs: Vec<f64> = (0..dim).map(|_| rng.random_range(-1.0..1.0)).collect();
            let mut ours = rhs.clone();
            ipm.ldlt_solve(&mut ours);
            let mut theirs = rhs.clone();
            LdltRef::new(&ipm.symbolic, &ipm.l_values).solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(&mut theirs, dim, 1),
                Par::Seq,
                MemStack::new(&mut ipm.work),
            );
            // The factor holds pivots of −1e-9 (equality rows, static
            // regularisation): both solves lose digits to rounding alike, so
            // they agree to 1e-7 and leave residuals of the same size against
            // the unregularised matrix.
            let scale = norm_inf(&theirs);
            for (k, (x, y)) in ours.iter().zip(&theirs).enumerate() {
                assert!((x - y).abs() <= 1e-7 * scale, "entry {k}: {x} against {y}");
            }
            let residual = |x: &[f64]| {
                let mut kx = vec![0.0; dim];
                ipm.reduced_mul(&p, &a, &d, x, &mut kx);
                kx.iter()
                    .zip(&rhs)
                    .fold(0.0f64, |w, (k, r)| w.max((k - r).abs()))
            };
            // The product from the assembled KKT matrix (the refinement's)
            // against the one formed from P, A and D.
            let (mut from_kkt, mut from_parts) = (vec![0.0; dim], vec![0.0; dim]);
            ipm.kkt_mul(&rhs, &mut from_kkt);
            ipm.reduced_mul(&p, &a, &d, &rhs, &mut from_parts);
            for (k, (x, y)) in from_kkt.iter().zip(&from_parts).enumerate() {
                assert!(
                    (x - y).abs() <= 1e-12 * (1.0 + y.abs()),
                    "row {k}: {x} against {y}"
                );
            }
            let (ro, rt) = (residual(&ours), residual(&theirs));
            assert!(
                ro <= 2.0 * rt + 1e-12,
                "residual {ro:e} against faer's {rt:e}"
            );
        }
    }

    /// The supernodal factorisation (left-looking loops, one thread and
    /// two) against faer's own numeric LDLᵀ of the same matrix and
    /// symbolic factor: the same L and D to rounding, with and without the
    /// sign-driven regularisation (the inertia correction factorises
    /// without signs).
    #[test]
    fn supernodal_factorisation_matches_faer() {
        use crate::sqp::ldlt::{BATCH_MIN_COLUMNS, DENSE_KERNEL_MIN_COLUMNS};
        // faer's dense kernels for every supernode, for the wide ones (the
        // default) and for none; narrow descendants' updates batched into
        // every supernode, into the wide ones (the default) and into none.
        let dense = [1, DENSE_KERNEL_MIN_COLUMNS, usize::MAX];
        let batch = [1, BATCH_MIN_COLUMNS, usize::MAX];
        let cases = [(1, false), (2, false), (2, true)];
        let mut batches = [0usize; 3];
        for (qp, (p, a, ne, r)) in [("stage", stage_qp(5)), ("shooting", shooting_qp(6))] {
            for ((threads, inertia), (dense_min, batch_min)) in cases.into_iter().flat_map(|c| {
                dense
                    .iter()
                    .flat_map(move |&d| batch.map(move |b| (c, (d, b))))
            }) {
                let mut ipm = supernodal_ipm(&p, &a, ne, threads);
                ipm.inertia_correction = inertia;
                let layout = ipm.layout.as_mut().unwrap();
                layout.dense_min = dense_min;
                layout.batch_min = batch_min;
                let d: Vec<f64> = (0..r).map(|k| if k < ne { 0.0 } else { 0.5 }).collect();
                assert!(ipm.factor(&p, &a, &d));
                let ours = ipm.l_values.clone();
                let dim = ipm.diag.len();
                let symb =
                    SymbolicSparseColMatRef::new_checked(dim, dim, &ipm.colptr, None, &ipm.rowind);
                let reg = LdltRegularization {
                    dynamic_regularization_signs: (!inertia).then_some(&ipm.signs[..]),
                    dynamic_regularization_delta: REG_DELTA,
                    dynamic_regularization_epsilon: REG_EPSILON,
                };
                ipm.symbolic
                    .factorize_numeric_ldlt(
                        &mut ipm.l_values,
                        SparseColMatRef::new(symb, &ipm.values),
                        Side::Upper,
                        reg,
                        Par::Seq,
                        MemStack::new(&mut ipm.work),
                        Default::default(),
                    )
                    .unwrap();
                let counts = ipm.layout.as_ref().unwrap().batch_counts();
                for k in 0..3 {
                    batches[k] += counts[k];
                }
                let scale = norm_inf(&ipm.l_values);
                assert!(scale > 1.0);
                for (k, (x, y)) in ours.iter().zip(&ipm.l_values).enumerate() {
                    assert!(
                    (x - y).abs() <= 1e-10 * scale,
                    "{qp} QP, {threads} thread(s), inertia {inertia}, dense from {dense_min}, batched from {batch_min}: value {k}: {x} against faer's {y}"
                );
                }
            }
        }
        // Batches as products, with rows below the target, and by loops.
        assert!(batches.iter().all(|&c| c > 0), "{batches:?}");
    }

    /// The SQP's next QP (the stage QP with its linear term and equality
    /// right-hand side perturbed): warm-started from the last answer, the
    /// solver reaches the cold start's answer, in fewer iterations.
    #[test]
    fn warm_start_reaches_the_cold_answer() {
        use rand::{Rng, SeedableRng};
        let (p, a, ne, r) = stage_qp(7);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
        let (q0, b0) = stage_vectors(&mut rng, p.n, ne, r, 8.0);
        let mut warm = Ipm::new(&p, &a, ne).unwrap();
        warm.warm_start = true;
        assert_eq!(warm.solve(&p, &a, &q0, &b0, 1e-10), IpmStatus::Solved);
        let q1: Vec<f64> = q0
            .iter()
            .map(|v| v + 0.4 * rng.random_range(-1.0..1.0))
            .collect();
        let b1: Vec<f64> = b0
            .iter()
            .enumerate()
            .map(|(k, v)| {
                if k < ne {
                    v + 0.01 * rng.random_range(-1.0..1.0)
                } else {
                    *v
                }
            })
            .collect();
        assert_eq!(warm.solve(&p, &a, &q1, &b1, 1e-10), IpmStatus::Solved);
        let mut cold = Ipm::new(&p, &a, ne).unwrap();
        assert_eq!(cold.solve(&p, &a, &q1, &b1, 1e-10), IpmStatus::Solved);
        let scale = norm_inf(&cold.x);
        for (k, (x, y)) in warm.x.iter().zip(&cold.x).enumerate() {
            assert!((x - y).abs() <= 1e-7 * scale, "x[{k}]: {x} against {y}");
        }
        // Some bounds x ≤ 1 are active, some not.
        assert!(cold.x.iter().any(|&x| x > 1.0 - 1e-6));
        assert!(cold.x.iter().any(|&x| x < 0.9));
        assert!(
            warm.iterations < cold.iterations,
            "warm {} against cold {} iterations",
            warm.iterations,
            cold.iterations
        );
    }

    /// METIS's nested dissection gives a permutation of the stage QP's KKT
    /// system; the solver picks the smaller factor of it and AMD, and both
    /// orderings reach the same answer (the stage QP with a linear term).
    #[test]
    fn nested_dissection_and_amd_solve_alike() {
        use rand::SeedableRng;
        let (p, a, ne, r) = stage_qp(5);
        let amd = Ipm::with_ordering(&p, &a, ne, KktOrdering::Amd).unwrap();
        let (fwd, inv) = nested_dissection(amd.diag.len(), &amd.colptr, &amd.rowind)
            .expect("a nested-dissection ordering");
        let dim = amd.diag.len();
        let mut seen = vec![false; dim];
        for (i, &f) in fwd.iter().enumerate() {
            assert!(!seen[f] && inv[f] == i);
            seen[f] = true;
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
        let (q, b) = stage_vectors(&mut rng, p.n, ne, r, 1.0);
        let mut answers = Vec::new();
        for ordering in [KktOrdering::Amd, KktOrdering::SmallerFactor] {
            let mut ipm = Ipm::with_ordering(&p, &a, ne, ordering).unwrap();
            assert_eq!(ipm.solve(&p, &a, &q, &b, 1e-10), IpmStatus::Solved);
            answers.push((ipm.x.clone(), ipm.size().1));
        }
        let ((x_amd, f_amd), (x_best, f_best)) = (&answers[0], &answers[1]);
        assert!(f_best <= f_amd, "factor {f_best} against AMD's {f_amd}");
        let scale = norm_inf(x_amd);
        for (k, (x, y)) in x_best.iter().zip(x_amd).enumerate() {
            assert!(
                (x - y).abs() <= 1e-7 * (1.0 + scale),
                "x[{k}]: {x} against {y}"
            );
        }
    }

    #[test]
    fn infeasible_qp_is_recognised() {
        // x ≤ −1 and −x ≤ −1 (x ≥ 1): no x.
        let p = CscMatrix::new(1, 1, vec![0, 1], vec![0], vec![1.0]);
        let a = CscMatrix::new(2, 1, vec![0, 2], vec![0, 1], vec![1.0, -1.0]);
        let mut ipm = Ipm::new(&p, &a, 0).unwrap();
        let st = ipm.solve(&p, &a, &[0.0], &[-1.0, -1.0], 1e-10);
        assert_eq!(st, IpmStatus::PrimalInfeasible);
    }

    /// Indefinite P, convex on the equality's null space: min ½(−x0² +
    /// 3 x1²) − x1 s.t. x0 − x1 = 0, −1 ≤ x0 ≤ 10. Along x0 = x1 = t the
    /// objective is t² − t: t = ½, with no shift needed.
    #[test]
    fn inertia_correction_keeps_a_qp_convex_on_its_constraints() {
        let p = CscMatrix::new(2, 2, vec![0, 1, 2], vec![0, 1], vec![-1.0, 3.0]);
        let a = dense_csc(
            3,
            2,
            &[(0, 0, 1.0), (0, 1, -1.0), (1, 0, -1.0), (2, 0, 1.0)],
        );
        let mut ipm = Ipm::new(&p, &a, 1).unwrap();
        ipm.inertia_correction = true;
        let st = ipm.solve(&p, &a, &[0.0, -1.0], &[0.0, 1.0, 10.0], 1e-10);
        assert_eq!(st, IpmStatus::Solved);
        assert_eq!(ipm.shift_curvature, 0.0);
        assert!((ipm.x[0] - 0.5).abs() < 1e-8 && (ipm.x[1] - 0.5).abs() < 1e-8);
    }

    /// Indefinite on the null space: min −½(x0² + x1²) − 0.3 x0 + 0.1 x1
    /// s.t. x0 − x1 = 0, −1 ≤ x0 ≤ 2. The correction must add τ ≥ 1 (the
    /// curvature along (1, 1) is −1 per unit), and the answer must satisfy
    /// the KKT conditions of the shifted QP: along t = x0 = x1 it is
    /// (τ − 1) t² − 0.2 t, minimised at 0.1/(τ − 1), or at the bound t = 2
    /// where τ = 1.
    #[test]
    fn inertia_correction_shifts_an_indefinite_qp() {
        let p = CscMatrix::new(2, 2, vec![0, 1, 2], vec![0, 1], vec![-1.0, -1.0]);
        let a = dense_csc(
            3,
            2,
            &[(0, 0, 1.0), (0, 1, -1.0), (1, 0, -1.0), (2, 0, 1.0)],
        );
        let mut ipm = Ipm::new(&p, &a, 1).unwrap();
        ipm.inertia_correction = true;
        let q = [-0.3, 0.1];
        let b = [0.0, 1.0, 2.0];
        let st = ipm.solve(&p, &a, &q, &b, 1e-10);
        assert_eq!(st, IpmStatus::Solved);
        let tau = ipm.shift_diag[0];
        assert!(tau >= 1.0, "τ = {tau}");
        assert_eq!(ipm.shift_diag[0], ipm.shift_diag[1]);
        // Stationarity of ½xᵀ(P + τI)x + qᵀx with Aᵀz, and x0 = x1.
        let (x, z) = (&ipm.x, &ipm.z);
        let r0 = (tau - 1.0) * x[0] + q[0] + z[0] - z[1] + z[2];
        let r1 = (tau - 1.0) * x[1] + q[1] - z[0];
        assert!(r0.abs() < 1e-7 && r1.abs() < 1e-7, "{r0} {r1}");
        assert!((x[0] - x[1]).abs() < 1e-8);
        let t = if tau > 1.0 + 1e-9 {
            (0.1 / (tau - 1.0)).min(2.0)
        } else {
            2.0
        };
        assert!((x[0] - t).abs() < 1e-7, "x0 = {} against {t}", x[0]);
        let expected = 0.5 * tau * (x[0] * x[0] + x[1] * x[1]);
        assert!((ipm.shift_curvature - expected).abs() < 1e-12);
    }
}
