//! The SQP on small optimal control problems with closed-form optima,
//! transcribed here by trapezoidal collocation with the sparse, partially
//! separable structure of the jump problem (one element per interval, free
//! final time as a shared column):
//!
//! * minimum-effort double integrator: min ∫₀¹ u², ẍ = u, rest to rest
//!   over a unit distance: u*(t) = 6 − 12t, J* = 12;
//! * Bryson–Denham (Bryson & Ho 1975, §3.11): min ½∫₀¹ u², ẍ = u,
//!   x(0) = x(1) = 0, ẋ(0) = −ẋ(1) = 1, x ≤ ℓ = 1/9: J* = 4/(9ℓ) = 4;
//! * brachistochrone with free final time: a bead slides from (0, 0) to
//!   (x_f, y_f) under gravity; the minimum time follows from the cycloid
//!   x = R(φ − sin φ), y = −R(1 − cos φ), T* = φ_f √(R/g).
//!
//! Every test also checks the transcription's Jacobian and Hessian against
//! central finite differences.

use leap::nlp::{check_derivatives, Element, EvalError, Nlp};
use leap::scalar::Scalar;
use leap::sqp::{solve, HessianMode, SqpSettings, SqpStatus};
use num_dual::{Dual64, HyperDual64};

trait Ocp {
    const NX: usize;
    const NU: usize;
    fn dynamics<D: Scalar>(&self, x: &[D], u: &[D], xdot: &mut [D]);
    /// Running cost L(x, u) (integrated by the trapezoidal rule).
    fn running_cost<D: Scalar>(&self, x: &[D], u: &[D]) -> D;
    /// Minimise the final time instead of (in addition to) the integral.
    fn minimum_time(&self) -> bool {
        false
    }
    /// Fixed duration, or bounds of a free one.
    fn duration(&self) -> Result<f64, (f64, f64)>;
    fn state_bounds(&self, i: usize) -> (f64, f64);
    fn control_bounds(&self, _i: usize) -> (f64, f64) {
        (f64::NEG_INFINITY, f64::INFINITY)
    }
    fn initial_state(&self) -> Vec<Option<f64>>;
    fn final_state(&self) -> Vec<Option<f64>>;
    /// Initial guess of node k of N.
    fn guess(&self, k: usize, n: usize, x: &mut [f64], u: &mut [f64]);
}

struct Trapezoid<O: Ocp> {
    ocp: O,
    n: usize,
    free_time: bool,
}

impl<O: Ocp> Trapezoid<O> {
    fn new(ocp: O, intervals: usize) -> Self {
        let free_time = ocp.duration().is_err();
        Trapezoid {
            ocp,
            n: intervals,
            free_time,
        }
    }
    fn nz(&self) -> usize {
        O::NX + O::NU
    }
    fn tf_index(&self) -> usize {
        (self.n + 1) * self.nz()
    }
    fn tf<D: Scalar>(&self, z: &[D]) -> D {
        match self.ocp.duration() {
            Ok(t) => D::from(t),
            Err(_) => z[self.tf_index()],
        }
    }
    /// Variables an interval depends on: its two nodes and tf.
    fn interval_vars(&self, k: usize) -> Vec<usize> {
        let nz = self.nz();
        let mut v: Vec<usize> = (k * nz..(k + 2) * nz).collect();
        if self.free_time {
            v.push(self.tf_index());
        }
        v
    }
    /// Defects of interval k and its cost share, from the interval's
    /// variables `w` (as listed by `interval_vars`).
    fn interval<D: Scalar>(&self, w: &[D], defect: &mut [D]) -> D {
        let (nx, nz) = (O::NX, self.nz());
        let tf = if self.free_time {
            w[2 * nz]
        } else {
            D::from(self.ocp.duration().unwrap_or(0.0))
        };
        let h = tf / self.n as f64;
        let (a, b) = (&w[..nz], &w[nz..2 * nz]);
        let mut fa = vec![D::from(0.0); nx];
        let mut fb = vec![D::from(0.0); nx];
        self.ocp.dynamics(&a[..nx], &a[nx..], &mut fa);
        self.ocp.dynamics(&b[..nx], &b[nx..], &mut fb);
        for i in 0..nx {
            defect[i] = b[i] - a[i] - h * 0.5 * (fa[i] + fb[i]);
        }
        h * 0.5
            * (self.ocp.running_cost(&a[..nx], &a[nx..])
                + self.ocp.running_cost(&b[..nx], &b[nx..]))
    }
    fn gather<D: Scalar>(&self, z: &[f64], vars: &[usize]) -> Vec<D> {
        vars.iter().map(|&j| D::from(z[j])).collect()
    }
}

impl<O: Ocp> Nlp for Trapezoid<O> {
    fn num_variables(&self) -> usize {
        self.tf_index() + usize::from(self.free_time)
    }
    fn num_constraints(&self) -> usize {
        self.n * O::NX
    }
    fn variable_bounds(&self, lo: &mut [f64], hi: &mut [f64]) {
        let (nx, nz) = (O::NX, self.nz());
        let (x0, xf) = (self.ocp.initial_state(), self.ocp.final_state());
        for k in 0..=self.n {
            for i in 0..nx {
                let (l, u) = self.ocp.state_bounds(i);
                let fixed = if k == 0 {
                    x0[i]
                } else if k == self.n {
                    xf[i]
                } else {
                    None
                };
                (lo[k * nz + i], hi[k * nz + i]) = match fixed {
                    Some(v) => (v, v),
                    None => (l, u),
                };
            }
            for i in 0..O::NU {
                (lo[k * nz + nx + i], hi[k * nz + nx + i]) = self.ocp.control_bounds(i);
            }
        }
        if let Err((l, u)) = self.ocp.duration() {
            lo[self.tf_index()] = l;
            hi[self.tf_index()] = u;
        }
    }
    fn constraint_bounds(&self, lo: &mut [f64], hi: &mut [f64]) {
        lo.fill(0.0);
        hi.fill(0.0);
    }
    fn initial_point(&self, z: &mut [f64]) {
        let (nx, nz) = (O::NX, self.nz());
        for k in 0..=self.n {
            let (x, u) = z[k * nz..(k + 1) * nz].split_at_mut(nx);
            self.ocp.guess(k, self.n, x, u);
        }
        if let Err((l, u)) = self.ocp.duration() {
            z[self.tf_index()] = 0.5 * (l + u);
        }
    }
    fn objective(&mut self, z: &[f64]) -> Result<f64, EvalError> {
        let mut d = vec![0.0; O::NX];
        let mut f = if self.ocp.minimum_time() {
            self.tf(z)
        } else {
            0.0
        };
        for k in 0..self.n {
            let w: Vec<f64> = self.gather(z, &self.interval_vars(k));
            f += self.interval(&w, &mut d);
        }
        Ok(f)
    }
    fn gradient(&mut self, z: &[f64], g: &mut [f64]) -> Result<(), EvalError> {
        g.fill(0.0);
        if self.ocp.minimum_time() {
            g[self.tf_index()] = 1.0;
        }
        let mut d = vec![Dual64::from(0.0); O::NX];
        for k in 0..self.n {
            let vars = self.interval_vars(k);
            for (a, &j) in vars.iter().enumerate() {
                let mut w: Vec<Dual64> = self.gather(z, &vars);
                w[a].eps = 1.0;
                g[j] += self.interval(&w, &mut d).eps;
            }
        }
        Ok(())
    }
    fn constraints(&mut self, z: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        for k in 0..self.n {
            let w: Vec<f64> = self.gather(z, &self.interval_vars(k));
            self.interval(&w, &mut c[k * O::NX..(k + 1) * O::NX]);
        }
        Ok(())
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        let mut s = Vec::new();
        for k in 0..self.n {
            for i in 0..O::NX {
                for &j in &self.interval_vars(k) {
                    s.push((k * O::NX + i, j));
                }
            }
        }
        s
    }
    fn jacobian_values(&mut self, z: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        let mut d = vec![Dual64::from(0.0); O::NX];
        let mut t = 0;
        for k in 0..self.n {
            let vars = self.interval_vars(k);
            let nv = vars.len();
            let mut block = vec![0.0; O::NX * nv];
            for a in 0..nv {
                let mut w: Vec<Dual64> = self.gather(z, &vars);
                w[a].eps = 1.0;
                self.interval(&w, &mut d);
                for i in 0..O::NX {
                    block[i * nv + a] = d[i].eps;
                }
            }
            values[t..t + block.len()].copy_from_slice(&block);
            t += block.len();
        }
        Ok(())
    }
    fn elements(&self) -> Vec<Element> {
        let mut els: Vec<Element> = (0..self.n)
            .map(|k| Element {
                variables: self.interval_vars(k),
                constraints: (k * O::NX..(k + 1) * O::NX).collect(),
                objective: false,
                blocks: Vec::new(),
            })
            .collect();
        // The objective: all node variables (the running cost) and tf.
        els.push(Element {
            variables: (0..self.num_variables()).collect(),
            constraints: vec![],
            objective: true,
            blocks: Vec::new(),
        });
        els
    }
    fn has_hessian(&self) -> bool {
        true
    }
    fn element_hessian(
        &mut self,
        z: &[f64],
        e: usize,
        sigma: f64,
        lambda: &[f64],
        h: &mut [f64],
    ) -> Result<(), EvalError> {
        h.fill(0.0);
        let mut d = vec![HyperDual64::from(0.0); O::NX];
        let second = |this: &Self,
                      vars: &[usize],
                      a: usize,
                      b: usize,
                      d: &mut [HyperDual64]|
         -> HyperDual64 {
            let mut w: Vec<HyperDual64> = this.gather(z, vars);
            w[a].eps1 = 1.0;
            w[b].eps2 = 1.0;
            this.interval(&w, d)
        };
        if e < self.n {
            let vars = self.interval_vars(e);
            let nv = vars.len();
            for a in 0..nv {
                for b in a..nv {
                    second(self, &vars, a, b, &mut d);
                    let v: f64 = (0..O::NX)
                        .map(|i| lambda[e * O::NX + i] * d[i].eps1eps2)
                        .sum();
                    h[a * nv + b] = v;
                    h[b * nv + a] = v;
                }
            }
        } else {
            let nvar = self.num_variables();
            for k in 0..self.n {
                let vars = self.interval_vars(k);
                let nv = vars.len();
                for a in 0..nv {
                    for b in a..nv {
                        let v = sigma * second(self, &vars, a, b, &mut d).eps1eps2;
                        h[vars[a] * nvar + vars[b]] += v;
                        if a != b {
                            h[vars[b] * nvar + vars[a]] += v;
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// ẍ = u as x = (position, speed).
fn double_integrator<D: Scalar>(x: &[D], u: &[D], xdot: &mut [D]) {
    xdot[0] = x[1];
    xdot[1] = u[0];
}

struct DoubleIntegrator;
impl Ocp for DoubleIntegrator {
    const NX: usize = 2;
    const NU: usize = 1;
    fn dynamics<D: Scalar>(&self, x: &[D], u: &[D], xdot: &mut [D]) {
        double_integrator(x, u, xdot);
    }
    fn running_cost<D: Scalar>(&self, _x: &[D], u: &[D]) -> D {
        u[0] * u[0]
    }
    fn duration(&self) -> Result<f64, (f64, f64)> {
        Ok(1.0)
    }
    fn state_bounds(&self, _i: usize) -> (f64, f64) {
        (-10.0, 10.0)
    }
    fn initial_state(&self) -> Vec<Option<f64>> {
        vec![Some(0.0), Some(0.0)]
    }
    fn final_state(&self) -> Vec<Option<f64>> {
        vec![Some(1.0), Some(0.0)]
    }
    fn guess(&self, k: usize, n: usize, x: &mut [f64], u: &mut [f64]) {
        x[0] = k as f64 / n as f64;
        x[1] = 1.0;
        u[0] = 0.0;
    }
}

struct BrysonDenham;
const ELL: f64 = 1.0 / 9.0;
impl Ocp for BrysonDenham {
    const NX: usize = 2;
    const NU: usize = 1;
    fn dynamics<D: Scalar>(&self, x: &[D], u: &[D], xdot: &mut [D]) {
        double_integrator(x, u, xdot);
    }
    fn running_cost<D: Scalar>(&self, _x: &[D], u: &[D]) -> D {
        u[0] * u[0] * 0.5
    }
    fn duration(&self) -> Result<f64, (f64, f64)> {
        Ok(1.0)
    }
    fn state_bounds(&self, i: usize) -> (f64, f64) {
        if i == 0 {
            (f64::NEG_INFINITY, ELL)
        } else {
            (-10.0, 10.0)
        }
    }
    fn initial_state(&self) -> Vec<Option<f64>> {
        vec![Some(0.0), Some(1.0)]
    }
    fn final_state(&self) -> Vec<Option<f64>> {
        vec![Some(0.0), Some(-1.0)]
    }
    fn guess(&self, k: usize, n: usize, x: &mut [f64], u: &mut [f64]) {
        let t = k as f64 / n as f64;
        x[0] = 0.0;
        x[1] = 1.0 - 2.0 * t;
        u[0] = -2.0;
    }
}

const G: f64 = 9.81;
struct Brachistochrone {
    xf: f64,
    yf: f64,
}
impl Ocp for Brachistochrone {
    const NX: usize = 3; // x, y, speed
    const NU: usize = 1; // path angle from the downward vertical
    fn dynamics<D: Scalar>(&self, x: &[D], u: &[D], xdot: &mut [D]) {
        xdot[0] = x[2] * u[0].sin();
        xdot[1] = -x[2] * u[0].cos();
        xdot[2] = u[0].cos() * G;
    }
    fn running_cost<D: Scalar>(&self, _x: &[D], _u: &[D]) -> D {
        D::from(0.0)
    }
    fn minimum_time(&self) -> bool {
        true
    }
    fn duration(&self) -> Result<f64, (f64, f64)> {
        Err((0.1, 2.0))
    }
    fn state_bounds(&self, i: usize) -> (f64, f64) {
        if i == 2 {
            (0.0, 20.0)
        } else {
            (-5.0, 5.0)
        }
    }
    fn control_bounds(&self, _i: usize) -> (f64, f64) {
        (0.0, std::f64::consts::PI)
    }
    fn initial_state(&self) -> Vec<Option<f64>> {
        vec![Some(0.0), Some(0.0), Some(0.0)]
    }
    fn final_state(&self) -> Vec<Option<f64>> {
        vec![Some(self.xf), Some(self.yf), None]
    }
    fn guess(&self, k: usize, n: usize, x: &mut [f64], u: &mut [f64]) {
        let s = k as f64 / n as f64;
        x[0] = s * self.xf;
        x[1] = s * self.yf;
        x[2] = (2.0 * G * (-x[1]).max(0.0)).sqrt();
        u[0] = 1.0;
    }
}

/// T* of the brachistochrone to (xf, yf), yf < 0, from the cycloid.
fn brachistochrone_time(xf: f64, yf: f64) -> f64 {
    let ratio = xf / -yf;
    let shape = |phi: f64| (phi - phi.sin()) / (1.0 - phi.cos()) - ratio;
    let (mut lo, mut hi) = (1e-6, 2.0 * std::f64::consts::PI - 1e-6);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if shape(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let phi = 0.5 * (lo + hi);
    let r = -yf / (1.0 - phi.cos());
    phi * (r / G).sqrt()
}

fn settings(mode: HessianMode) -> SqpSettings {
    SqpSettings {
        hessian: mode,
        verbose: std::env::var("LEAP_SQP_VERBOSE").is_ok(),
        ..Default::default()
    }
}

fn derivatives_ok<N: Nlp>(nlp: &mut N) {
    let mut z = vec![0.0; nlp.num_variables()];
    nlp.initial_point(&mut z);
    for (j, v) in z.iter_mut().enumerate() {
        *v += 0.01 * ((j * 7919) % 13) as f64 / 13.0;
    }
    let lambda: Vec<f64> = (0..nlp.num_constraints())
        .map(|i| ((i * 31) % 7) as f64 - 3.0)
        .collect();
    let r = check_derivatives(nlp, &z, &lambda, 1e-6).expect("evaluations");
    assert!(r.gradient < 1e-6, "gradient {r:?}");
    assert!(r.jacobian < 1e-6, "jacobian {r:?}");
    assert!(
        r.jacobian_outside_pattern < 1e-9,
        "jacobian outside its pattern {r:?}"
    );
    assert!(r.hessian.unwrap() < 1e-5, "hessian {r:?}");
}

/// The exact optimum of a linear-quadratic transcription, from its KKT
/// system solved densely (fixed variables as equality rows).
fn lq_optimum<N: Nlp>(nlp: &mut N) -> (Vec<f64>, f64) {
    let (n, m) = (nlp.num_variables(), nlp.num_constraints());
    let zero = vec![0.0; n];
    let mut g0 = vec![0.0; n];
    nlp.gradient(&zero, &mut g0).unwrap();
    let mut c0 = vec![0.0; m];
    nlp.constraints(&zero, &mut c0).unwrap();
    let pattern = nlp.jacobian_structure();
    let mut jv = vec![0.0; pattern.len()];
    nlp.jacobian_values(&zero, &mut jv).unwrap();
    let h = leap::nlp::assemble_hessian(nlp, &zero, 1.0, &vec![0.0; m]).unwrap();
    let (mut xl, mut xu) = (vec![0.0; n], vec![0.0; n]);
    nlp.variable_bounds(&mut xl, &mut xu);
    let fixed: Vec<usize> = (0..n).filter(|&j| xl[j] == xu[j]).collect();
    let k = n + m + fixed.len();
    let mut kkt = nalgebra::DMatrix::<f64>::zeros(k, k);
    let mut rhs = nalgebra::DVector::<f64>::zeros(k);
    for i in 0..n {
        for j in 0..n {
            kkt[(i, j)] = h[i * n + j];
        }
        rhs[i] = -g0[i];
    }
    for (t, &(i, j)) in pattern.iter().enumerate() {
        kkt[(n + i, j)] = jv[t];
        kkt[(j, n + i)] = jv[t];
    }
    for i in 0..m {
        rhs[n + i] = -c0[i];
    }
    for (r, &j) in fixed.iter().enumerate() {
        kkt[(n + m + r, j)] = 1.0;
        kkt[(j, n + m + r)] = 1.0;
        rhs[n + m + r] = xl[j];
    }
    let sol = kkt.lu().solve(&rhs).expect("nonsingular KKT system");
    let x: Vec<f64> = sol.iter().take(n).copied().collect();
    let f = nlp.objective(&x).unwrap();
    (x, f)
}

#[test]
fn double_integrator_minimum_effort() {
    let mut errors = Vec::new();
    for n in [10, 20, 40] {
        let mut nlp = Trapezoid::new(DoubleIntegrator, n);
        derivatives_ok(&mut nlp);
        let (x_ref, f_ref) = lq_optimum(&mut nlp);
        for mode in [HessianMode::ExactConvexified, HessianMode::PartitionedBfgs] {
            let r = solve(&mut nlp, &settings(mode));
            assert_eq!(r.status, SqpStatus::Solved, "N={n} {mode:?}: {}", r.message);
            assert!(r.constraint_violation < 1e-8);
            assert!(
                (r.objective - f_ref).abs() < 1e-9 * f_ref,
                "N={n} {mode:?}: J {} vs KKT {f_ref}",
                r.objective
            );
            let dx =
                r.x.iter()
                    .zip(&x_ref)
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max);
            assert!(dx < 1e-4, "N={n} {mode:?}: |x − x_KKT| = {dx}");
        }
        errors.push((f_ref - 12.0).abs());
    }
    // The discrete optimum converges to J* = 12 at second order.
    assert!(
        errors[0] < 0.5 && errors[1] < errors[0] / 3.5 && errors[2] < errors[1] / 3.5,
        "{errors:?}"
    );
}

#[test]
fn bryson_denham_state_constraint() {
    let mut errors = Vec::new();
    for n in [30, 60, 120] {
        let mut nlp = Trapezoid::new(BrysonDenham, n);
        if n == 30 {
            derivatives_ok(&mut nlp);
        }
        let r = solve(&mut nlp, &settings(HessianMode::ExactConvexified));
        assert_eq!(r.status, SqpStatus::Solved, "N={n}: {}", r.message);
        let xmax = (0..=n)
            .map(|k| r.x[k * 3])
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(xmax <= ELL + 1e-8, "state bound violated: {xmax}");
        // The bound is reached in the middle of the interval.
        assert!(
            xmax > ELL - 1e-8,
            "N={n}: the state bound is never active ({xmax})"
        );
        errors.push((r.objective - 4.0 / (9.0 * ELL)).abs());
    }
    assert!(
        errors[0] < 0.05 && errors[1] < errors[0] / 3.0 && errors[2] < errors[1] / 3.0,
        "{errors:?}"
    );
    let r = solve(
        &mut Trapezoid::new(BrysonDenham, 60),
        &settings(HessianMode::PartitionedBfgs),
    );
    // BFGS reaches the acceptable level only (the state-bound arc makes the
    // multipliers converge slowly).
    assert!(r.status.success(), "BFGS: {:?} {}", r.status, r.message);
    assert!((r.objective - 4.0).abs() < 0.02, "BFGS: {}", r.objective);
}

#[test]
fn brachistochrone_free_final_time() {
    let (xf, yf) = (1.0, -0.65);
    let t_star = brachistochrone_time(xf, yf);
    let mut errors = Vec::new();
    for n in [20, 40] {
        let mut nlp = Trapezoid::new(Brachistochrone { xf, yf }, n);
        derivatives_ok(&mut nlp);
        for mode in [HessianMode::ExactConvexified, HessianMode::PartitionedBfgs] {
            let r = solve(&mut nlp, &settings(mode));
            assert_eq!(r.status, SqpStatus::Solved, "N={n} {mode:?}: {}", r.message);
            let tf = r.x[nlp.tf_index()];
            assert!((r.objective - tf).abs() < 1e-12);
            if mode == HessianMode::ExactConvexified {
                errors.push((tf - t_star).abs() / t_star);
            } else {
                assert!(
                    (tf - t_star).abs() / t_star < 5e-3,
                    "N={n} BFGS: T {tf} vs {t_star}"
                );
            }
        }
    }
    assert!(
        errors[0] < 5e-3 && errors[1] < errors[0] / 2.5,
        "relative errors {errors:?} (T* = {t_star})"
    );
}
