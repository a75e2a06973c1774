//! The QP subproblem of one SQP iteration, in clarabel's form
//!
//! ```text
//!   minimise ½ dᵀ B d + gᵀ d  [+ ρ Σ (p_i + n_i)]
//!   subject to  c_L − c ≤ J d [+ p − n] ≤ c_U − c,
//!               max(x_L − x, −Δ) ≤ d ≤ min(x_U − x, Δ),   p, n ≥ 0,
//! ```
//!
//! (the bracketed elastic slacks only in elastic mode), written as
//! `A z + s = b, s ∈ {0}^{m_eq} × R₊^{m_in}`. The pattern of P (upper
//! triangle of the union of the element blocks, plus the diagonal) and of A
//! is fixed when the QP is built; each iteration only refills values and
//! calls clarabel's in-place updates (presolve off, structural zeros kept),
//! so the solver object is created once per solve.

use super::ipm::{Ipm, IpmStatus, KktOrdering};
use crate::nlp::{Element, INFINITE_BOUND};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT,
    SolverStatus, SupportedConeT, ZeroConeT,
};
use std::path::Path;

/// What a row of A stands for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Row {
    /// J_i d (+ p − n) = c_L − c.
    Equality(usize),
    /// −J_i d (− p + n) ≤ c − c_L.
    Lower(usize),
    /// J_i d (+ p − n) ≤ c_U − c.
    Upper(usize),
    /// d_j = 0 (fixed variable).
    Fixed(usize),
    /// −d_j ≤ min(x_j − x_L, Δ).
    VarLower(usize),
    /// d_j ≤ min(x_U − x_j, Δ).
    VarUpper(usize),
    /// −(slack column k) ≤ 0.
    Slack(usize),
}

/// A QP solve's outcome.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum QpOutcome {
    Solved,
    Infeasible,
    Failed(SolverStatus),
}

/// The fixed-pattern QP of an SQP solve.
pub(crate) struct Qp {
    pub n: usize,
    /// Number of QP variables (n, or n + 2 m_c in elastic mode).
    pub nz: usize,
    pub rows: Vec<Row>,
    num_eq: usize,
    p: CscMatrix<f64>,
    /// For element e, the P entry of each local (a, b), a ≤ b, row-major
    /// over the upper triangle.
    p_elem: Vec<Vec<usize>>,
    a: CscMatrix<f64>,
    /// For Jacobian entry k, the A entries it fills and their signs.
    a_jac: Vec<[(usize, f64); 2]>,
    pub q: Vec<f64>,
    pub b: Vec<f64>,
    /// Whether a bound row's right-hand side is the variable bound (not Δ).
    b_is_bound: Vec<bool>,
    solver: Option<DefaultSolver<f64>>,
    settings: DefaultSettings<f64>,
    tolerance: f64,
    /// Solution: d (length n), multipliers of the constraints (λ, length m)
    /// and of the bounds (ζ, length n), slacks p − n per constraint.
    pub d: Vec<f64>,
    pub lambda: Vec<f64>,
    pub zeta: Vec<f64>,
    pub slack_sum: f64,
    pub iterations: u32,
    /// Leap's interior-point solver ([`Ipm`]), tried first when set; the
    /// clarabel solver remains the fallback where it fails.
    use_ipm: bool,
    /// P may be indefinite: the interior-point solver adds τ I until the
    /// QP is convex on its equality constraints ([`Ipm::inertia_correction`]);
    /// a fallback to clarabel gets P with the last τ on its diagonal.
    inertia_correction: bool,
    /// ½ dᵀ (τ-part) d of the last answer: the curvature the correction
    /// added to the QP's model along its step.
    pub shift_curvature: f64,
    ipm: Option<Ipm>,
    /// QPs the interior-point solver handed to clarabel, and how many of
    /// them clarabel found infeasible.
    pub fallbacks: usize,
    pub fallbacks_infeasible: usize,
    /// Wall time clarabel spent on those QPs.
    pub fallback_seconds: f64,
    /// Plain QPs whose primal residual stalled in the interior-point
    /// solver, taken as infeasible without asking clarabel.
    pub stalls_taken_infeasible: usize,
    /// Whether this is the elastic QP (slack columns), which always has a
    /// solution.
    elastic: bool,
    /// The interior-point solver starts from its last answer
    /// ([`Ipm::warm_start`]).
    warm_start: bool,
}

/// Sparse matrix from entries (row, col), returning the nz index of each.
fn csc(nrows: usize, ncols: usize, entries: &[(usize, usize)]) -> (CscMatrix<f64>, Vec<usize>) {
    let mut order: Vec<usize> = (0..entries.len()).collect();
    order.sort_by_key(|&k| (entries[k].1, entries[k].0));
    let mut colptr = vec![0usize; ncols + 1];
    let mut rowval = Vec::with_capacity(entries.len());
    let mut index = vec![0usize; entries.len()];
    for (nz, &k) in order.iter().enumerate() {
        let (r, c) = entries[k];
        colptr[c + 1] += 1;
        rowval.push(r);
        index[k] = nz;
    }
    for c in 0..ncols {
        colptr[c + 1] += colptr[c];
    }
    let nzval = vec![0.0; entries.len()];
    (CscMatrix::new(nrows, ncols, colptr, rowval, nzval), index)
}

impl Qp {
    /// Lay out the QP of a problem with these bounds, Jacobian pattern and
    /// elements.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        x_lower: &[f64],
        x_upper: &[f64],
        c_lower: &[f64],
        c_upper: &[f64],
        jac: &[(usize, usize)],
        elements: &[Element],
        elastic: bool,
        tolerance: f64,
        equilibrate: bool,
        use_ipm: bool,
        inertia_correction: bool,
    ) -> Qp {
        let (n, m) = (x_lower.len(), c_lower.len());
        let finite = |v: f64| v.abs() < INFINITE_BOUND;
        // Rows: equalities first (clarabel's zero cone), then inequalities.
        let mut rows = Vec::new();
        for i in 0..m {
            if c_lower[i] == c_upper[i] {
                rows.push(Row::Equality(i));
            }
        }
        for j in 0..n {
            if x_lower[j] == x_upper[j] {
                rows.push(Row::Fixed(j));
            }
        }
        let num_eq = rows.len();
        let mut slack_of = vec![None; m];
        let mut nz = n;
        for i in 0..m {
            let active = c_lower[i] == c_upper[i] || finite(c_lower[i]) || finite(c_upper[i]);
            if elastic && active {
                slack_of[i] = Some(nz);
                nz += 2;
            }
            if c_lower[i] != c_upper[i] {
                if finite(c_lower[i]) {
                    rows.push(Row::Lower(i));
                }
                if finite(c_upper[i]) {
                    rows.push(Row::Upper(i));
                }
            }
        }
        for j in 0..n {
            if x_lower[j] != x_upper[j] {
                rows.push(Row::VarLower(j));
                rows.push(Row::VarUpper(j));
            }
        }
        for k in n..nz {
            rows.push(Row::Slack(k));
        }
        // Where each constraint's rows are.
        let mut rows_of: Vec<Vec<(usize, f64)>> = vec![Vec::new(); m];
        let mut entries = Vec::new();
        let mut fixed_entries = Vec::new(); // (entry index, value)
        for (r, row) in rows.iter().enumerate() {
            match *row {
                Row::Equality(i) | Row::Upper(i) => rows_of[i].push((r, 1.0)),
                Row::Lower(i) => rows_of[i].push((r, -1.0)),
                Row::Fixed(j) | Row::VarUpper(j) => {
                    fixed_entries.push((entries.len(), 1.0));
                    entries.push((r, j));
                }
                Row::VarLower(j) => {
                    fixed_entries.push((entries.len(), -1.0));
                    entries.push((r, j));
                }
                Row::Slack(k) => {
                    fixed_entries.push((entries.len(), -1.0));
                    entries.push((r, k));
                }
            }
        }
        let mut a_jac_entry = Vec::with_capacity(jac.len());
        for &(i, j) in jac {
            let mut slots = [(usize::MAX, 0.0); 2];
            for (s, &(r, sign)) in rows_of[i].iter().enumerate() {
                slots[s] = (entries.len(), sign);
                entries.push((r, j));
            }
            a_jac_entry.push(slots);
        }
        for i in 0..m {
            if let Some(k) = slack_of[i] {
                for &(r, sign) in &rows_of[i] {
                    fixed_entries.push((entries.len(), sign));
                    entries.push((r, k));
                    fixed_entries.push((entries.len(), -sign));
                    entries.push((r, k + 1));
                }
            }
        }
        let (mut a, index) = csc(rows.len(), nz, &entries);
        for &(e, v) in &fixed_entries {
            a.nzval[index[e]] = v;
        }
        let a_jac = a_jac_entry
            .iter()
            .map(|slots| {
                slots.map(|(e, s)| {
                    if e == usize::MAX {
                        (usize::MAX, 0.0)
                    } else {
                        (index[e], s)
                    }
                })
            })
            .collect();
        // P: every diagonal entry (a variable outside all elements keeps one,
        // zero), then each element's upper triangle (merged).
        let mut p_entries: Vec<(usize, usize)> = (0..n).map(|j| (j, j)).collect();
        let mut lookup = std::collections::HashMap::new();
        for j in 0..n {
            lookup.insert((j, j), j);
        }
        let mut p_elem = Vec::with_capacity(elements.len());
        for el in elements {
            let k = el.variables.len();
            let block = el.block_ids();
            let mut map = Vec::with_capacity(k * (k + 1) / 2);
            for a_ in 0..k {
                for b_ in a_..k {
                    if block[a_] != block[b_] {
                        // Outside the element's blocks: no P entry.
                        map.push(usize::MAX);
                        continue;
                    }
                    let key = (el.variables[a_], el.variables[b_]);
                    let next = p_entries.len();
                    let e = *lookup.entry(key).or_insert_with(|| {
                        p_entries.push(key);
                        next
                    });
                    map.push(e);
                }
            }
            p_elem.push(map);
        }
        let (p, pindex) = csc(nz, nz, &p_entries);
        let p_elem = p_elem
            .into_iter()
            .map(|map| {
                map.into_iter()
                    .map(|e| if e == usize::MAX { e } else { pindex[e] })
                    .collect()
            })
            .collect();
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .max_threads(1)
            .presolve_enable(false)
            .input_sparse_dropzeros(false)
            .direct_solve_method("qdldl".into())
            // Clarabel's Ruiz equilibration is computed once, from the first
            // iterate, and kept through the in-place updates.
            .equilibrate_enable(equilibrate)
            // Clarabel's default static regularisation (1e-8) perturbs the
            // equality rows of the equilibrated KKT system enough that the
            // primal residual of the jump's QPs stalls near 1e-7: 120-200
            // interior-point iterations. At 1e-11 the same QPs take 22-30
            // (`examples/qp_replay` on the dumped QPs).
            .static_regularization_constant(1e-11)
            .tol_gap_abs(tolerance)
            .tol_gap_rel(tolerance)
            .tol_feas(tolerance)
            .tol_ktratio(tolerance.sqrt().min(1e-6))
            .max_iter(200)
            .build()
            .expect("valid clarabel settings");
        let nrows = rows.len();
        Qp {
            n,
            nz,
            rows,
            num_eq,
            p,
            p_elem,
            a,
            a_jac,
            q: vec![0.0; nz],
            b: vec![0.0; nrows],
            b_is_bound: vec![true; nrows],
            solver: None,
            settings,
            tolerance,
            d: vec![0.0; n],
            lambda: vec![0.0; m],
            zeta: vec![0.0; n],
            slack_sum: 0.0,
            iterations: 0,
            use_ipm,
            inertia_correction,
            shift_curvature: 0.0,
            ipm: None,
            fallbacks: 0,
            fallbacks_infeasible: 0,
            fallback_seconds: 0.0,
            stalls_taken_infeasible: 0,
            elastic,
            warm_start: false,
        }
    }

    /// Whether the interior-point solver starts each QP from the last
    /// one's answer ([`Ipm::warm_start`]; off by default).
    pub fn set_warm_start(&mut self, on: bool) {
        self.warm_start = on;
        if let Some(ipm) = &mut self.ipm {
            ipm.warm_start = on;
        }
    }

    /// Variables, rows, non-zeros of P (upper triangle) and of A.
    pub fn size(&self) -> (usize, usize, usize, usize) {
        (
            self.nz,
            self.rows.len(),
            self.p.nzval.len(),
            self.a.nzval.len(),
        )
    }

    /// Fill P from the element matrices (row-major k×k, both triangles).
    pub fn set_hessian(&mut self, blocks: &[Vec<f64>], elements: &[Element]) {
        self.p.nzval.iter_mut().for_each(|v| *v = 0.0);
        for (e, el) in elements.iter().enumerate() {
            let k = el.variables.len();
            let mut t = 0;
            for a in 0..k {
                for b in a..k {
                    if let Some(v) = self.p.nzval.get_mut(self.p_elem[e][t]) {
                        *v += blocks[e][a * k + b];
                    }
                    t += 1;
                }
            }
        }
    }

    /// Fill A's Jacobian entries.
    pub fn set_jacobian(&mut self, values: &[f64]) {
        for (k, slots) in self.a_jac.iter().enumerate() {
            for &(nz, sign) in slots {
                if nz != usize::MAX {
                    self.a.nzval[nz] = sign * values[k];
                }
            }
        }
    }

    /// Fill q and b: gradient `g`, constraint values `c` (or their
    /// second-order-correction substitute), bounds, step bound `delta`,
    /// elastic penalty `rho`.
    #[allow(clippy::too_many_arguments)]
    pub fn set_vectors(
        &mut self,
        g: &[f64],
        c: &[f64],
        x: &[f64],
        x_lower: &[f64],
        x_upper: &[f64],
        c_lower: &[f64],
        c_upper: &[f64],
        delta: f64,
        rho: f64,
    ) {
        self.q[..self.n].copy_from_slice(g);
        for v in &mut self.q[self.n..] {
            *v = rho;
        }
        for (r, row) in self.rows.iter().enumerate() {
            self.b[r] = match *row {
                Row::Equality(i) => c_lower[i] - c[i],
                Row::Lower(i) => c[i] - c_lower[i],
                Row::Upper(i) => c_upper[i] - c[i],
                Row::Fixed(_) | Row::Slack(_) => 0.0,
                Row::VarLower(j) => (x[j] - x_lower[j]).min(delta).max(0.0),
                Row::VarUpper(j) => (x_upper[j] - x[j]).min(delta).max(0.0),
            };
            self.b_is_bound[r] = match *row {
                Row::VarLower(j) => x[j] - x_lower[j] <= delta,
                Row::VarUpper(j) => x_upper[j] - x[j] <= delta,
                _ => true,
            };
        }
    }

    /// Solve with the current values (creating the solver on first use).
    pub fn solve(&mut self) -> Result<QpOutcome, String> {
        if self.use_ipm {
            if let Some(outcome) = self.solve_ipm()? {
                return Ok(outcome);
            }
        }
        let reused = self.solver.is_some();
        let mut outcome = self.solve_clarabel()?;
        if reused && matches!(outcome, QpOutcome::Failed(_)) {
            // The equilibration kept from the first QP can be far off for
            // this one (exact Hessians change by orders of magnitude between
            // iterations): a fresh solver equilibrates this QP itself.
            let first = self.iterations;
            self.solver = None;
            outcome = self.solve_clarabel()?;
            self.iterations += first;
        }
        Ok(outcome)
    }

    /// Leap's interior-point solver on the current values: its outcome,
    /// or None where clarabel is to solve the QP.
    fn solve_ipm(&mut self) -> Result<Option<QpOutcome>, String> {
        if self.ipm.is_none() {
            // The inertia correction pivots without interchanges: in
            // nested-dissection order its solves lost their footing (all
            // four meshes of the jump ended in numerical errors), so it
            // keeps AMD's.
            let ordering = if self.inertia_correction {
                KktOrdering::Amd
            } else {
                KktOrdering::SmallerFactor
            };
            // A constraint bounded on both sides has two rows, the lower
            // one its upper one negated: one KKT row stands for both.
            let twins: Vec<(usize, usize)> = self
                .rows
                .windows(2)
                .enumerate()
                .filter_map(|(r, w)| match (w[0], w[1]) {
                    (Row::Lower(i), Row::Upper(k)) if i == k => Some((r, r + 1)),
                    _ => None,
                })
                .collect();
            let mut ipm = Ipm::with_twins(&self.p, &self.a, self.num_eq, ordering, &twins)?;
            ipm.inertia_correction = self.inertia_correction;
            ipm.warm_start = self.warm_start;
            self.ipm = Some(ipm);
        }
        let ipm = self.ipm.as_mut().expect("created above");
        let status = ipm.solve(&self.p, &self.a, &self.q, &self.b, self.tolerance);
        self.iterations = ipm.iterations;
        match status {
            IpmStatus::Solved => {
                self.shift_curvature = ipm.shift_curvature;
                let ipm = self.ipm.take().expect("created above");
                self.extract(&ipm.x, &ipm.z, &ipm.s);
                self.ipm = Some(ipm);
                Ok(Some(QpOutcome::Solved))
            }
            IpmStatus::PrimalInfeasible => Ok(Some(QpOutcome::Infeasible)),
            // A plain QP whose primal residual stalls is taken as
            // infeasible, and the SQP turns to its elastic QP, which always
            // has a solution; an elastic QP that stalls goes to clarabel.
            IpmStatus::Stalled if !self.elastic => {
                self.stalls_taken_infeasible += 1;
                Ok(Some(QpOutcome::Infeasible))
            }
            IpmStatus::Stalled | IpmStatus::Failed => {
                self.fallbacks += 1;
                Ok(None)
            }
        }
    }

    /// Clarabel on the current values (creating its solver on first use).
    fn solve_clarabel(&mut self) -> Result<QpOutcome, String> {
        // With the inertia correction, clarabel gets P + the interior
        // point's last τ on the diagonal (P alone may be indefinite).
        let shift: Option<Vec<f64>> = if self.inertia_correction {
            self.ipm.as_ref().map(|i| i.shift_diag.clone())
        } else {
            None
        };
        let p_shifted = shift.as_ref().map(|sd| {
            let mut p = self.p.clone();
            for (j, t) in sd.iter().enumerate() {
                for k in p.colptr[j]..p.colptr[j + 1] {
                    if p.rowval[k] == j {
                        p.nzval[k] += t;
                    }
                }
            }
            p
        });
        let started = std::time::Instant::now();
        let p = p_shifted.as_ref().unwrap_or(&self.p);
        match &mut self.solver {
            Some(s) => {
                s.update_P(&p.nzval).map_err(|e| e.to_string())?;
                s.update_A(&self.a.nzval).map_err(|e| e.to_string())?;
                s.update_q(&self.q).map_err(|e| e.to_string())?;
                s.update_b(&self.b).map_err(|e| e.to_string())?;
            }
            None => {
                let cones: Vec<SupportedConeT<f64>> = vec![
                    ZeroConeT(self.num_eq),
                    NonnegativeConeT(self.rows.len() - self.num_eq),
                ];
                let s =
                    DefaultSolver::new(p, &self.q, &self.a, &self.b, &cones, self.settings.clone())
                        .map_err(|e| e.to_string())?;
                self.solver = Some(s);
            }
        }
        let s = self.solver.as_mut().expect("created above");
        s.solve();
        if self.use_ipm {
            self.fallback_seconds += started.elapsed().as_secs_f64();
        }
        self.iterations = s.solution.iterations;
        let status = s.solution.status;
        match status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {}
            SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
                if self.use_ipm {
                    self.fallbacks_infeasible += 1;
                }
                return Ok(QpOutcome::Infeasible);
            }
            other => return Ok(QpOutcome::Failed(other)),
        }
        let s = self.solver.take().expect("created above");
        self.extract(&s.solution.x, &s.solution.z, &s.solution.s);
        self.shift_curvature = shift.map_or(0.0, |sd| {
            0.5 * sd
                .iter()
                .zip(&s.solution.x)
                .map(|(t, x)| t * x * x)
                .sum::<f64>()
        });
        self.solver = Some(s);
        Ok(QpOutcome::Solved)
    }

    /// τ of the last answer's inertia correction, on the equilibrated QP
    /// (whose entries are at most about 1; a clarabel fallback gets the
    /// same τ on P's diagonal): 0 without the interior-point solver, without
    /// the correction, or where P needed none.
    pub fn hessian_shift(&self) -> f64 {
        self.ipm.as_ref().map_or(0.0, Ipm::shift)
    }

    /// Read the step, multipliers and slack sum from a solution in
    /// clarabel's form (x, row duals z, row slacks s).
    fn extract(&mut self, x: &[f64], z: &[f64], sl: &[f64]) {
        self.d.copy_from_slice(&x[..self.n]);
        // An interior-point solution stops just inside active bounds; put
        // the step exactly on a bound whose multiplier dominates its slack
        // (strict complementarity), as an active-set QP would.
        for (r, row) in self.rows.iter().enumerate() {
            let active = z[r] > 1e3 * sl[r].max(0.0) && sl[r] < 1e-7 * (1.0 + self.b[r].abs());
            match *row {
                Row::VarUpper(j) if active => self.d[j] = self.b[r],
                Row::VarLower(j) if active => self.d[j] = -self.b[r],
                _ => {}
            }
        }
        self.lambda.iter_mut().for_each(|v| *v = 0.0);
        self.zeta.iter_mut().for_each(|v| *v = 0.0);
        for (r, row) in self.rows.iter().enumerate() {
            match *row {
                Row::Equality(i) | Row::Upper(i) => self.lambda[i] += z[r],
                Row::Lower(i) => self.lambda[i] -= z[r],
                // Rows at the step bound Δ rather than at a variable bound
                // carry trust-region multipliers, not bound multipliers.
                Row::Fixed(j) => self.zeta[j] += z[r],
                Row::VarUpper(j) if self.b_is_bound[r] => self.zeta[j] += z[r],
                Row::VarLower(j) if self.b_is_bound[r] => self.zeta[j] -= z[r],
                Row::VarUpper(_) | Row::VarLower(_) => {}
                Row::Slack(_) => {}
            }
        }
        self.slack_sum = x[self.n..].iter().map(|v| v.max(0.0)).sum();
    }

    /// Write the QP with its current values as clarabel JSON.
    pub fn dump(&self, path: &Path) -> Result<(), String> {
        use clarabel::solver::SolverJSONReadWrite;
        let cones: Vec<SupportedConeT<f64>> = vec![
            ZeroConeT(self.num_eq),
            NonnegativeConeT(self.rows.len() - self.num_eq),
        ];
        let s = DefaultSolver::new(
            &self.p,
            &self.q,
            &self.a,
            &self.b,
            &cones,
            self.settings.clone(),
        )
        .map_err(|e| e.to_string())?;
        crate::io::write_output_with(path, |f| s.save_to_file(f))
            .map_err(|e| format!("{}: {e}", path.display()))
    }
}
