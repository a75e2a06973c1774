//! The nonlinear program the optimizer sees, apart from any solver (as
//! Drake's `MathematicalProgram`):
//!
//! ```text
//!   minimise f(x)   subject to   x_L ≤ x ≤ x_U,   c_L ≤ c(x) ≤ c_U
//! ```
//!
//! with equalities where `c_L = c_U` and infinite bounds (±∞, or beyond
//! ±1e19 as in IPOPT) where a side is absent. The Jacobian ∂c/∂x is sparse
//! with a pattern fixed for the whole solve. The Lagrangian is
//! L(x, λ) = σ f(x) + Σ λ_i c_i(x) (σ the objective factor).
//!
//! The problem also states its partially separable structure as
//! [`Element`]s (Griewank & Toint 1982): each constraint row belongs to
//! exactly one element, the objective to at most one, and the Hessian of an
//! element's part of the Lagrangian is supported on the element's
//! variables. Elements may share variables (a collocation defect couples two
//! neighbouring nodes). The optimizer builds its Hessian model per element
//! (a convexified exact element Hessian or a damped BFGS matrix), so the sum
//! is positive semidefinite and has the sparsity of the problem.

use crate::scalar::Scalar;
use num_dual::{Dual64, HyperDual64};

/// Bounds at or beyond this magnitude count as infinite (IPOPT's
/// `nlp_lower_bound_inf`/`nlp_upper_bound_inf`).
pub const INFINITE_BOUND: f64 = 1e19;

/// An evaluation of the problem failed at a point.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{what}: {reason}")]
pub struct EvalError {
    /// Which evaluation: "objective", "constraints", "jacobian", ...
    pub what: String,
    pub reason: String,
}

impl EvalError {
    pub fn new(what: impl Into<String>, reason: impl Into<String>) -> Self {
        EvalError {
            what: what.into(),
            reason: reason.into(),
        }
    }
}

/// A group of variables and the parts of the problem that act on them.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    /// Variable indices, increasing.
    pub variables: Vec<usize>,
    /// Constraint rows whose Hessians are supported on `variables`.
    pub constraints: Vec<usize>,
    /// Whether the objective's Hessian belongs to this element.
    pub objective: bool,
    /// Optional partition of the element's variables (local indices into
    /// `variables`) for a block-diagonal Hessian approximation
    /// ([`crate::sqp::SqpSettings::block_diagonal_elements`]): the QP then
    /// keeps only the curvature inside each block. Empty: one block.
    pub blocks: Vec<Vec<usize>>,
}

/// A nonlinear program with a sparse Jacobian of fixed pattern.
///
/// Evaluations take `&mut self` so an implementation can keep workspaces
/// and caches; they return an [`EvalError`] instead of panicking.
pub trait Nlp {
    /// Number of variables n.
    fn num_variables(&self) -> usize;
    /// Number of constraint rows m.
    fn num_constraints(&self) -> usize;
    /// Variable bounds (length n each).
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]);
    /// Constraint bounds (length m each); equal for equalities.
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]);
    /// The initial guess (length n).
    fn initial_point(&self, x: &mut [f64]);
    /// f(x).
    fn objective(&mut self, x: &[f64]) -> Result<f64, EvalError>;
    /// ∇f(x) into `g` (length n).
    fn gradient(&mut self, x: &[f64], g: &mut [f64]) -> Result<(), EvalError>;
    /// c(x) into `c` (length m).
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError>;
    /// The Jacobian's pattern as (row, column) pairs, without duplicates;
    /// fixed for the whole solve. Structural zeros are allowed.
    fn jacobian_structure(&self) -> Vec<(usize, usize)>;
    /// Jacobian values in the order of [`Nlp::jacobian_structure`].
    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), EvalError>;
    /// The partially separable structure. Default: one element holding
    /// every variable, every constraint and the objective.
    fn elements(&self) -> Vec<Element> {
        Element::whole(self.num_variables(), self.num_constraints())
    }
    /// Whether [`Nlp::element_hessian`] is implemented.
    fn has_hessian(&self) -> bool {
        false
    }
    /// The dense Hessian of element `e`'s part of the Lagrangian,
    /// σ f (if the element holds the objective) + Σ_{i ∈ element} λ_i c_i,
    /// over the element's variables, row-major k×k (k = number of element
    /// variables; both triangles). `lambda` has length m.
    fn element_hessian(
        &mut self,
        _x: &[f64],
        _e: usize,
        _sigma: f64,
        _lambda: &[f64],
        _h: &mut [f64],
    ) -> Result<(), EvalError> {
        Err(EvalError::new(
            "hessian",
            "this problem provides no Hessian",
        ))
    }
    /// Every element's Hessian at one point, `blocks[e]` as
    /// [`Nlp::element_hessian`]'s `h`. The default calls it element by
    /// element; a problem whose elements share work at x (the
    /// transcription's point derivatives) or a wrapper that transforms x or
    /// λ (scaling) overrides it to do that work once per point instead of
    /// once per element, which is O(n) each: O(n²) in all on fine meshes.
    fn element_hessians(
        &mut self,
        x: &[f64],
        sigma: f64,
        lambda: &[f64],
        blocks: &mut [Vec<f64>],
    ) -> Result<(), EvalError> {
        for (e, h) in blocks.iter_mut().enumerate() {
            self.element_hessian(x, e, sigma, lambda, h)?;
        }
        Ok(())
    }
    /// A name for variable `i` in messages.
    fn variable_name(&self, i: usize) -> String {
        format!("x[{i}]")
    }
    /// A name for constraint row `i` in messages.
    fn constraint_name(&self, i: usize) -> String {
        format!("c[{i}]")
    }
}

impl Element {
    /// One element with everything.
    pub fn whole(n: usize, m: usize) -> Vec<Element> {
        vec![Element {
            variables: (0..n).collect(),
            constraints: (0..m).collect(),
            objective: true,
            blocks: Vec::new(),
        }]
    }

    /// The block of each local variable (all 0 without blocks).
    pub fn block_ids(&self) -> Vec<usize> {
        let mut id = vec![0; self.variables.len()];
        for (b, members) in self.blocks.iter().enumerate() {
            for &a in members {
                if let Some(slot) = id.get_mut(a) {
                    *slot = b;
                }
            }
        }
        id
    }
}

/// Each constraint row's violation at x: how far c_i(x) lies outside
/// [c_l, c_u] (0 inside).
pub fn constraint_violations<N: Nlp + ?Sized>(
    nlp: &mut N,
    x: &[f64],
) -> Result<Vec<f64>, EvalError> {
    let m = nlp.num_constraints();
    let mut c = vec![0.0; m];
    nlp.constraints(x, &mut c)?;
    let (mut cl, mut cu) = (vec![0.0; m], vec![0.0; m]);
    nlp.constraint_bounds(&mut cl, &mut cu);
    Ok((0..m)
        .map(|i| (cl[i] - c[i]).max(c[i] - cu[i]).max(0.0))
        .collect())
}

/// Check that `elements` partition the constraint rows, hold the objective
/// at most once and list valid, increasing variables.
pub fn check_elements(elements: &[Element], n: usize, m: usize) -> Result<(), String> {
    let mut owner = vec![usize::MAX; m];
    let mut objective = None;
    for (e, el) in elements.iter().enumerate() {
        if el.variables.windows(2).any(|w| w[0] >= w[1]) {
            return Err(format!(
                "element {e}: variables are not strictly increasing"
            ));
        }
        if let Some(&v) = el.variables.iter().find(|&&v| v >= n) {
            return Err(format!("element {e}: variable {v} out of range (n = {n})"));
        }
        if !el.blocks.is_empty() {
            let k = el.variables.len();
            let mut seen = vec![false; k];
            for &a in el.blocks.iter().flatten() {
                if a >= k {
                    return Err(format!(
                        "element {e}: block member {a} out of range ({k} variables)"
                    ));
                }
                if std::mem::replace(&mut seen[a], true) {
                    return Err(format!("element {e}: variable {a} is in two blocks"));
                }
            }
            if let Some(a) = seen.iter().position(|&s| !s) {
                return Err(format!("element {e}: variable {a} is in no block"));
            }
        }
        for &i in &el.constraints {
            if i >= m {
                return Err(format!(
                    "element {e}: constraint {i} out of range (m = {m})"
                ));
            }
            if owner[i] != usize::MAX {
                return Err(format!(
                    "constraint {i} belongs to elements {} and {e}",
                    owner[i]
                ));
            }
            owner[i] = e;
        }
        if el.objective {
            if let Some(o) = objective {
                return Err(format!("the objective belongs to elements {o} and {e}"));
            }
            objective = Some(e);
        }
    }
    if let Some(i) = owner.iter().position(|&o| o == usize::MAX) {
        return Err(format!("constraint {i} belongs to no element"));
    }
    Ok(())
}

/// A small problem written once, generic over the scalar type, from which
/// [`AdNlp`] derives exact gradients, Jacobians and Hessians with forward
/// dual numbers. For test problems and prototypes (dense derivatives).
pub trait AdProblem {
    fn name(&self) -> String;
    fn num_variables(&self) -> usize;
    fn num_constraints(&self) -> usize;
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]);
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]);
    fn initial_point(&self, x: &mut [f64]);
    /// Returns f(x) and writes c(x).
    fn eval<D: Scalar>(&self, x: &[D], c: &mut [D]) -> D;
}

/// [`Nlp`] over an [`AdProblem`], dense derivatives by dual numbers.
pub struct AdNlp<P: AdProblem> {
    pub problem: P,
    n: usize,
    m: usize,
    blocks: Vec<Vec<usize>>,
}

impl<P: AdProblem> AdNlp<P> {
    pub fn new(problem: P) -> Self {
        let (n, m) = (problem.num_variables(), problem.num_constraints());
        AdNlp {
            problem,
            n,
            m,
            blocks: Vec::new(),
        }
    }

    /// Declare blocks of the one element ([`Element::blocks`]).
    pub fn with_blocks(mut self, blocks: Vec<Vec<usize>>) -> Self {
        self.blocks = blocks;
        self
    }
}

fn finite_check(what: &str, v: &[f64]) -> Result<(), EvalError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(EvalError::new(what, format!("entry {i} is {}", v[i]))),
        None => Ok(()),
    }
}

impl<P: AdProblem> Nlp for AdNlp<P> {
    fn num_variables(&self) -> usize {
        self.n
    }
    fn elements(&self) -> Vec<Element> {
        let mut e = Element::whole(self.n, self.m);
        e[0].blocks = self.blocks.clone();
        e
    }
    fn num_constraints(&self) -> usize {
        self.m
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        self.problem.variable_bounds(lower, upper)
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        self.problem.constraint_bounds(lower, upper)
    }
    fn initial_point(&self, x: &mut [f64]) {
        self.problem.initial_point(x)
    }
    fn objective(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        let mut c = vec![0.0; self.m];
        let f = self.problem.eval(x, &mut c);
        finite_check("objective", &[f])?;
        Ok(f)
    }
    fn gradient(&mut self, x: &[f64], g: &mut [f64]) -> Result<(), EvalError> {
        let mut c = vec![Dual64::from(0.0); self.m];
        for j in 0..self.n {
            let xd: Vec<Dual64> = x
                .iter()
                .enumerate()
                .map(|(k, &v)| Dual64::new(v, if k == j { 1.0 } else { 0.0 }))
                .collect();
            g[j] = self.problem.eval(&xd, &mut c).eps;
        }
        finite_check("gradient", g)
    }
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        self.problem.eval(x, c);
        finite_check("constraints", c)
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        (0..self.m)
            .flat_map(|i| (0..self.n).map(move |j| (i, j)))
            .collect()
    }
    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        let mut c = vec![Dual64::from(0.0); self.m];
        for j in 0..self.n {
            let xd: Vec<Dual64> = x
                .iter()
                .enumerate()
                .map(|(k, &v)| Dual64::new(v, if k == j { 1.0 } else { 0.0 }))
                .collect();
            self.problem.eval(&xd, &mut c);
            for i in 0..self.m {
                values[i * self.n + j] = c[i].eps;
            }
        }
        finite_check("jacobian", values)
    }
    fn has_hessian(&self) -> bool {
        true
    }
    fn element_hessian(
        &mut self,
        x: &[f64],
        _e: usize,
        sigma: f64,
        lambda: &[f64],
        h: &mut [f64],
    ) -> Result<(), EvalError> {
        let n = self.n;
        let mut c = vec![HyperDual64::from(0.0); self.m];
        for j in 0..n {
            for k in j..n {
                let xd: Vec<HyperDual64> = x
                    .iter()
                    .enumerate()
                    .map(|(i, &v)| {
                        HyperDual64::new(
                            v,
                            if i == j { 1.0 } else { 0.0 },
                            if i == k { 1.0 } else { 0.0 },
                            0.0,
                        )
                    })
                    .collect();
                let f = self.problem.eval(&xd, &mut c);
                let mut v = sigma * f.eps1eps2;
                for i in 0..self.m {
                    v += lambda[i] * c[i].eps1eps2;
                }
                h[j * n + k] = v;
                h[k * n + j] = v;
            }
        }
        finite_check("hessian", h)
    }
}

/// The largest discrepancies of an NLP's derivatives against central
/// finite differences at one point.
#[derive(Debug, Clone, Default)]
pub struct DerivativeCheck {
    /// max |analytic − fd| / max(1, |fd|) over the gradient.
    pub gradient: f64,
    /// The same over the Jacobian's pattern, and the largest finite
    /// difference found outside the declared pattern.
    pub jacobian: f64,
    pub jacobian_outside_pattern: f64,
    /// The same over the Lagrangian Hessian (None without a Hessian).
    pub hessian: Option<f64>,
}

/// Compare the derivatives of `nlp` at `x` with central differences of
/// step `h` (relative to max(1, |x_j|)); the Hessian with multipliers
/// `lambda` against differences of the Lagrangian gradient.
pub fn check_derivatives<N: Nlp + ?Sized>(
    nlp: &mut N,
    x: &[f64],
    lambda: &[f64],
    h: f64,
) -> Result<DerivativeCheck, EvalError> {
    let (n, m) = (nlp.num_variables(), nlp.num_constraints());
    let pattern = nlp.jacobian_structure();
    let mut g = vec![0.0; n];
    nlp.gradient(x, &mut g)?;
    let mut jv = vec![0.0; pattern.len()];
    nlp.jacobian_values(x, &mut jv)?;
    let mut jac = vec![0.0; m * n];
    let mut in_pattern = vec![false; m * n];
    for (k, &(i, j)) in pattern.iter().enumerate() {
        jac[i * n + j] += jv[k];
        in_pattern[i * n + j] = true;
    }
    let mut report = DerivativeCheck::default();
    let mut xp = x.to_vec();
    let (mut cp, mut cm) = (vec![0.0; m], vec![0.0; m]);
    // Lagrangian gradient ∇f + Jᵀλ, for the Hessian check.
    let lag_grad = |nlp: &mut N, x: &[f64]| -> Result<Vec<f64>, EvalError> {
        let mut g = vec![0.0; n];
        nlp.gradient(x, &mut g)?;
        let mut jv = vec![0.0; pattern.len()];
        nlp.jacobian_values(x, &mut jv)?;
        for (k, &(i, j)) in pattern.iter().enumerate() {
            g[j] += lambda[i] * jv[k];
        }
        Ok(g)
    };
    let hess = if nlp.has_hessian() {
        Some(assemble_hessian(nlp, x, 1.0, lambda)?)
    } else {
        None
    };
    let mut hess_err: f64 = 0.0;
    for j in 0..n {
        let step = h * x[j].abs().max(1.0);
        xp[j] = x[j] + step;
        let fp = nlp.objective(&xp)?;
        nlp.constraints(&xp, &mut cp)?;
        let gp = if hess.is_some() {
            Some(lag_grad(nlp, &xp)?)
        } else {
            None
        };
        xp[j] = x[j] - step;
        let fm = nlp.objective(&xp)?;
        nlp.constraints(&xp, &mut cm)?;
        let gm = if hess.is_some() {
            Some(lag_grad(nlp, &xp)?)
        } else {
            None
        };
        xp[j] = x[j];
        let fd = (fp - fm) / (2.0 * step);
        report.gradient = report.gradient.max((g[j] - fd).abs() / fd.abs().max(1.0));
        for i in 0..m {
            let fd = (cp[i] - cm[i]) / (2.0 * step);
            if in_pattern[i * n + j] {
                report.jacobian = report
                    .jacobian
                    .max((jac[i * n + j] - fd).abs() / fd.abs().max(1.0));
            } else {
                report.jacobian_outside_pattern = report.jacobian_outside_pattern.max(fd.abs());
            }
        }
        if let (Some(hm), Some(gp), Some(gm)) = (&hess, gp, gm) {
            for i in 0..n {
                let fd = (gp[i] - gm[i]) / (2.0 * step);
                hess_err = hess_err.max((hm[i * n + j] - fd).abs() / fd.abs().max(1.0));
            }
        }
    }
    report.hessian = hess.map(|_| hess_err);
    Ok(report)
}

/// The dense n×n Lagrangian Hessian summed from the element Hessians.
pub fn assemble_hessian<N: Nlp + ?Sized>(
    nlp: &mut N,
    x: &[f64],
    sigma: f64,
    lambda: &[f64],
) -> Result<Vec<f64>, EvalError> {
    let n = nlp.num_variables();
    let mut out = vec![0.0; n * n];
    for (e, el) in nlp.elements().iter().enumerate() {
        let k = el.variables.len();
        let mut he = vec![0.0; k * k];
        nlp.element_hessian(x, e, sigma, lambda, &mut he)?;
        for a in 0..k {
            for b in 0..k {
                out[el.variables[a] * n + el.variables[b]] += he[a * k + b];
            }
        }
    }
    Ok(out)
}

/// `nlp` in scaled variables x̃ = x / D (Moco's
/// `scale_variables_using_bounds`): D_j is the width of variable j's bounds
/// where both are finite and differ, else 1. The optimizer sees O(1)
/// variables whatever their units (fibre lengths of centimetres next to
/// speeds of tens of rad/s), so an identity Hessian model and a box step
/// bound mean the same in every direction.
pub struct ScaledVariables<'a, N: Nlp + ?Sized> {
    inner: &'a mut N,
    /// D (length n).
    pub scale: Vec<f64>,
    x: Vec<f64>,
    jac_cols: Vec<usize>,
    element_variables: Vec<Vec<usize>>,
}

impl<'a, N: Nlp + ?Sized> ScaledVariables<'a, N> {
    /// Scales from `inner`'s variable bounds.
    pub fn from_bounds(inner: &'a mut N) -> Self {
        let n = inner.num_variables();
        let (mut lo, mut hi) = (vec![0.0; n], vec![0.0; n]);
        inner.variable_bounds(&mut lo, &mut hi);
        let scale = lo
            .iter()
            .zip(&hi)
            .map(|(&l, &u)| {
                let w = u - l;
                if l.abs() < INFINITE_BOUND && u.abs() < INFINITE_BOUND && w > 0.0 && w.is_finite()
                {
                    w
                } else {
                    1.0
                }
            })
            .collect();
        let jac_cols = inner.jacobian_structure().iter().map(|&(_, j)| j).collect();
        let element_variables = inner.elements().into_iter().map(|e| e.variables).collect();
        ScaledVariables {
            inner,
            scale,
            x: vec![0.0; n],
            jac_cols,
            element_variables,
        }
    }
    /// x = D x̃.
    pub fn unscale(&self, xs: &[f64]) -> Vec<f64> {
        xs.iter().zip(&self.scale).map(|(v, d)| v * d).collect()
    }
    /// x̃ = x / D.
    pub fn scale_point(&self, x: &[f64]) -> Vec<f64> {
        x.iter().zip(&self.scale).map(|(v, d)| v / d).collect()
    }
    /// An element's Hessian in x scaled to x̃: D_e H D_e.
    fn scale_block(&self, e: usize, h: &mut [f64]) {
        let vars = &self.element_variables[e];
        let k = vars.len();
        for a in 0..k {
            for b in 0..k {
                h[a * k + b] *= self.scale[vars[a]] * self.scale[vars[b]];
            }
        }
    }
    /// `f` of the inner problem at x = D x̃ (kept in a reused buffer).
    fn at<R>(&mut self, xs: &[f64], f: impl FnOnce(&mut N, &[f64]) -> R) -> R {
        for ((o, v), d) in self.x.iter_mut().zip(xs).zip(&self.scale) {
            *o = v * d;
        }
        f(self.inner, &self.x)
    }
}

impl<N: Nlp + ?Sized> Nlp for ScaledVariables<'_, N> {
    fn num_variables(&self) -> usize {
        self.inner.num_variables()
    }
    fn num_constraints(&self) -> usize {
        self.inner.num_constraints()
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        self.inner.variable_bounds(lower, upper);
        for j in 0..self.scale.len() {
            if lower[j].abs() < INFINITE_BOUND {
                lower[j] /= self.scale[j];
            }
            if upper[j].abs() < INFINITE_BOUND {
                upper[j] /= self.scale[j];
            }
        }
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        self.inner.constraint_bounds(lower, upper);
    }
    fn initial_point(&self, x: &mut [f64]) {
        self.inner.initial_point(x);
        for (v, d) in x.iter_mut().zip(&self.scale) {
            *v /= d;
        }
    }
    fn objective(&mut self, xs: &[f64]) -> Result<f64, EvalError> {
        self.at(xs, |n, x| n.objective(x))
    }
    fn gradient(&mut self, xs: &[f64], g: &mut [f64]) -> Result<(), EvalError> {
        self.at(xs, |n, x| n.gradient(x, g))?;
        for (v, d) in g.iter_mut().zip(&self.scale) {
            *v *= d;
        }
        Ok(())
    }
    fn constraints(&mut self, xs: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        self.at(xs, |n, x| n.constraints(x, c))
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        self.inner.jacobian_structure()
    }
    fn jacobian_values(&mut self, xs: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        self.at(xs, |n, x| n.jacobian_values(x, values))?;
        for (v, &j) in values.iter_mut().zip(&self.jac_cols) {
            *v *= self.scale[j];
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
        xs: &[f64],
        e: usize,
        sigma: f64,
        lambda: &[f64],
        h: &mut [f64],
    ) -> Result<(), EvalError> {
        self.at(xs, |n, x| n.element_hessian(x, e, sigma, lambda, h))?;
        self.scale_block(e, h);
        Ok(())
    }
    fn element_hessians(
        &mut self,
        xs: &[f64],
        sigma: f64,
        lambda: &[f64],
        blocks: &mut [Vec<f64>],
    ) -> Result<(), EvalError> {
        self.at(xs, |n, x| n.element_hessians(x, sigma, lambda, blocks))?;
        for (e, h) in blocks.iter_mut().enumerate() {
            self.scale_block(e, h);
        }
        Ok(())
    }
    fn variable_name(&self, i: usize) -> String {
        self.inner.variable_name(i)
    }
    fn constraint_name(&self, i: usize) -> String {
        self.inner.constraint_name(i)
    }
}
