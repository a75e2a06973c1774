//! Direct shooting of the jump problem ([`crate::ocp::JumpOcp`]), the
//! paper's first method (Porsa, Lin & Pandy 2016, "direct shooting"):
//! the excitations at the nodes are the variables, and every evaluation
//! integrates the state equation forward from the static squat with a
//! variable-step Runge–Kutta integrator. Derivatives are forward
//! sensitivities of the integrator's steps (default) or the paper's central
//! differences ([`ShootingDerivatives`]).
//!
//! **Mesh.** N uniform intervals on [0, t_f] (the paper's 29 nodes: N = 28),
//! nodes t_k = k·h, h = t_f/N. The excitations are linear between the
//! nodes; node 0's are the squat's, fixed.
//!
//! **Variables** (n = N·n_u + 1 = 673 for the paper's problem):
//! `[u_1, u_2, …, u_N, t_f]`.
//!
//! **Integration.** The Rust-native Dormand–Prince 5(4)
//! ([`crate::integrator::Dopri5`]) on the optimizer's state equation (the
//! same smoothed activation switch and paths as collocation), restarted at
//! every node (the excitations have a kink there).
//!
//! **Derivatives.** Forward sensitivities: per interval (on
//! [`ShootingOptions::threads`] threads) the nominal accepted steps are
//! replayed with the point Jacobian ∂f/∂(x, u) at every stage, giving
//! ∂x_k/∂(x_{k−1}, u_{k−1}, u_k, t_f) in normalised time (the steps scale
//! with t_f); these are chained from node to node. Central differences: a
//! restart makes the trajectory up to node k−1 independent of u_k, bit for
//! bit, so a difference quotient in u_k integrates only from node k−1 on:
//! the Jacobian costs about n_u·(N + 1) + 2 whole integrations (698 on the
//! paper's mesh), not 2·(N·n_u + 1), its columns on the threads.
//!
//! **Constraints** (rows in this order):
//! - no countermovement (eq. 4): Ÿ_C(t_j) − Ÿ_C(t_{j+1}) ≤ 0, j = 0..n_cm−1;
//! - lift-off: F_y(t_f)/(m g) ≤ ε ([`crate::ocp::LiftOff`]);
//! - no descent ([`crate::ocp::OcpOptions::no_com_descent`]): Ẏ_C(t_k) ≥ 0,
//!   k = 1..N;
//! - state bounds (eq. 6) at the nodes k = 1..N: coordinates, speeds and
//!   fibre lengths, and the activations of muscles whose excitations may
//!   fall below the activation bound (DeGrooteFregly2016Muscle: u_min = 0).
//!   Thelen muscles' activations need no rows: with u in [0.01, 1] their
//!   activation dynamics (a first-order lag toward u with a positive time
//!   constant) keep a between the extremes of u and its start, inside
//!   [0.01, 1].
//!
//! **Objective**: −J = −(Y_C(t_f) + Ẏ_C(t_f)²/(2g)) (eq. 3).
//!
//! No Hessian: the SQP uses damped BFGS on the one dense element.

use crate::integrator::{Dopri5, Dopri5Options, OdeSystem};
use crate::integrator::{A as DP_A, C as DP_C};
use crate::nlp::{EvalError, Nlp};
use crate::ocp::{JumpOcp, OcpError};
use crate::ode::StateWorkspace;
use crate::scalar::Dual64;
use crate::simulate::{grf_of, ExcitationSource, Trajectory};
use crate::transcription::{jump_objective_gradient, PointJacobian, StatePattern};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

/// Settings of the shooting transcription.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShootingOptions {
    /// Control intervals N (N + 1 nodes; the paper's 29 nodes: 28).
    pub num_intervals: usize,
    /// Dormand–Prince accuracy (relative and absolute, as Simbody's).
    pub accuracy: f64,
    /// Central-difference step: δ in each excitation, δ·t_f in t_f. The
    /// quotient's error is about the integration error over δ plus δ²
    /// times the third derivative. On the reduced jump at an interior point
    /// (`RAMP=1 cargo run --release --example shooting_probe -- 4
    /// models/jumper_reduced.json`), against accuracy 1e-12 and step 1e-5,
    /// the Jacobian's relative error was 7.4e-5 at (1e-8, 1e-3), 3.3e-4
    /// at (1e-8, 1e-4), 6.9e-5 at (1e-10, 1e-4) for twice the time. Where
    /// a muscle rests at the activation floor (u = a = 0.01, OpenSim's clamp
    /// of a in the force) the quotient averages the one-sided derivatives.
    pub finite_difference_step: f64,
    /// How the gradient and the Jacobian are computed.
    pub derivatives: ShootingDerivatives,
    /// Threads for the difference quotients or the sensitivities.
    pub threads: usize,
}

/// The derivatives of a shooting solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShootingDerivatives {
    /// Central differences of whole integrations (the paper's): two
    /// integrations per variable, each from its column's first node.
    CentralDifference,
    /// Forward sensitivities of the integrator's own steps (internal
    /// numerical differentiation, Bock 1981): the nominal steps replayed
    /// with the exact point Jacobian ∂f/∂(x, u) at every stage (dual
    /// numbers), chained from node to node. Exact for the discrete
    /// solution whose steps the error control chose.
    ForwardSensitivity,
}

impl ShootingDerivatives {
    /// The study file's name.
    pub fn name(self) -> &'static str {
        match self {
            ShootingDerivatives::CentralDifference => "central-difference",
            ShootingDerivatives::ForwardSensitivity => "forward-sensitivity",
        }
    }
}

impl Default for ShootingOptions {
    fn default() -> Self {
        ShootingOptions {
            num_intervals: 28,
            accuracy: 1e-8,
            finite_difference_step: 1e-3,
            derivatives: ShootingDerivatives::ForwardSensitivity,
            threads: 2,
        }
    }
}

/// What a row constrains.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Row {
    /// Ÿ_C(t_j) − Ÿ_C(t_{j+1}).
    NoCountermovement(usize),
    /// F_y(t_N)/(m g).
    LiftOff,
    /// Ẏ_C(t_k).
    NoDescent(usize),
    /// State i at node k.
    Bound(usize, usize),
}

impl Row {
    /// The last node the row reads.
    fn last_node(self, big_n: usize) -> usize {
        match self {
            Row::NoCountermovement(j) => j + 1,
            Row::LiftOff => big_n,
            Row::NoDescent(k) | Row::Bound(k, _) => k,
        }
    }
}

/// Per node: the state, Ÿ_C, F_y/(m g), Ẏ_C and Y_C.
#[derive(Debug, Clone, Default)]
pub struct NodeValues {
    /// From the run's first node on.
    pub states: Vec<Vec<f64>>,
    pub com_acceleration: Vec<f64>,
    pub vertical_force_bw: Vec<f64>,
    pub com_velocity: Vec<f64>,
    pub com_height: Vec<f64>,
    /// J = Y_C + Ẏ_C²/(2g) at the last node.
    pub objective: f64,
    pub f_evals: usize,
}

/// Node-quantity layout of a column of difference quotients: the state,
/// then Ÿ_C, F_y/(m g), Ẏ_C.
const EXTRA: usize = 3;

/// The central differences of one variable: of the node quantities from
/// node `first` on (layout: the state, Ÿ_C, F_y/(m g), Ẏ_C per node) and
/// of J.
struct ColumnQuotients {
    column: usize,
    first: usize,
    nodes: Vec<f64>,
    objective: f64,
    f_evals: usize,
}

/// Interval k's sensitivities and node k's point derivatives.
struct IntervalSensitivity {
    k: usize,
    /// ∂x_k/∂(x_{k−1}, u_{k−1}, u_k, t_f), n_x × (n_x + 2 n_u + 1) row-major.
    sens: Vec<f64>,
    /// ∂Ÿ_C/∂(x_k, u_k) and ∂(F_y/(m g))/∂(x_k, u_k).
    ydd: Vec<f64>,
    fy: Vec<f64>,
    /// ∂Ẏ_C/∂(q, q̇)_k.
    yd: Vec<f64>,
    /// ∂J/∂(q, q̇)_N at node N (zero elsewhere).
    j: Vec<f64>,
    f_evals: usize,
    point_jacobians: usize,
    steps: usize,
}

/// Counters of the work done by evaluations.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct ShootingCounters {
    /// Integrations from the squat (nominal evaluations).
    pub simulations: usize,
    /// Difference-quotient integrations (each from its column's first node).
    pub difference_simulations: usize,
    /// Right-hand-side evaluations over all integrations.
    pub f_evals: usize,
    /// Point Jacobians ∂f/∂(x, u) of the sensitivities (one per stage of
    /// every replayed step, one per node).
    pub point_jacobians: usize,
    /// Integrator steps replayed by the sensitivities.
    pub sensitivity_steps: usize,
    /// Jacobian evaluations (central-difference or sensitivity passes).
    pub jacobians: usize,
    /// Wall time of the passes (s).
    pub jacobian_seconds: f64,
}

/// The jump problem transcribed by direct shooting.
pub struct Shooting {
    pub ocp: Arc<JumpOcp>,
    options: ShootingOptions,
    rows: Vec<Row>,
    structure: Vec<(usize, usize)>,
    guess: Vec<f64>,
    nominal: Option<(Vec<f64>, NodeValues)>,
    /// The pattern of ∂f/∂(x, u) (forward sensitivities only).
    pattern: Option<StatePattern>,
    derivatives: Option<(Vec<f64>, Vec<f64>, Vec<f64>)>,
    pub counters: ShootingCounters,
}

/// Called after each accepted step of an interval with the system, the
/// step's start (t, x) and the integrator at its end.
type OnStep<'s> = dyn FnMut(&mut IntervalRhs, f64, &[f64], &Dopri5) + 's;

/// ẋ = f(x, u(t)) with u linear on the current interval.
struct IntervalRhs<'a, 'w> {
    ocp: &'a JumpOcp,
    ws: &'w mut StateWorkspace<f64>,
    u: Vec<f64>,
    ua: &'a [f64],
    ub: &'a [f64],
    ta: f64,
    h: f64,
}

impl OdeSystem for IntervalRhs<'_, '_> {
    fn dim(&self) -> usize {
        self.ocp.nx()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), String> {
        let w = ((t - self.ta) / self.h).clamp(0.0, 1.0);
        for ((u, a), b) in self.u.iter_mut().zip(self.ua).zip(self.ub) {
            *u = a + w * (b - a);
        }
        self.ocp
            .state_rates(self.ws, x, &self.u, dx)
            .map(|_| ())
            .map_err(|e| e.to_string())
    }
}

impl Shooting {
    pub fn new(ocp: Arc<JumpOcp>, options: ShootingOptions) -> Result<Self, OcpError> {
        let big_n = options.num_intervals;
        let bad = |s: String| Err(OcpError::Invalid(s));
        if big_n < 1 {
            return bad("shooting: num_mesh_intervals must be at least 1".into());
        }
        if !(options.accuracy.is_finite() && options.accuracy > 0.0 && options.accuracy < 1.0) {
            return bad(format!(
                "shooting: integrator_accuracy must lie in (0, 1), got {}",
                options.accuracy
            ));
        }
        let d = options.finite_difference_step;
        if !(d.is_finite() && d > 0.0 && d < 0.1) {
            return bad(format!(
                "shooting: finite_difference_step must lie in (0, 0.1), got {d}"
            ));
        }
        if options.threads == 0 {
            return bad("shooting: threads must be at least 1".into());
        }
        let n_cm = ocp.options.no_countermovement_nodes;
        if n_cm > big_n {
            return bad(format!(
                "{n_cm} no-countermovement rows need at least {n_cm} intervals, got num_mesh_intervals = {big_n}"
            ));
        }
        let (nq, nm) = (ocp.nq(), ocp.nm());
        let mut bounded: Vec<usize> = (0..2 * nq + nm).collect();
        bounded.extend(
            (0..nm)
                .filter(|&k| ocp.control_lower[k] < ocp.state_lower[2 * nq + nm + k])
                .map(|k| 2 * nq + nm + k),
        );
        let mut rows: Vec<Row> = (0..n_cm).map(Row::NoCountermovement).collect();
        rows.push(Row::LiftOff);
        if ocp.options.no_com_descent {
            rows.extend((1..=big_n).map(Row::NoDescent));
        }
        for k in 1..=big_n {
            rows.extend(bounded.iter().map(|&i| Row::Bound(k, i)));
        }
        let pattern = match options.derivatives {
            ShootingDerivatives::CentralDifference => None,
            ShootingDerivatives::ForwardSensitivity => {
                let d = crate::transcription::TranscriptionOptions::default();
                Some(
                    StatePattern::detect(&ocp, d.pattern_samples, d.pattern_seed).map_err(
                        |e| {
                            OcpError::Invalid(format!(
                                "shooting: forward sensitivities: {e} (derivatives 'central-difference' need no pattern)"
                            ))
                        },
                    )?,
                )
            }
        };
        let nu = ocp.nu();
        let tf_col = big_n * nu;
        let mut structure = Vec::new();
        for (r, row) in rows.iter().enumerate() {
            let last = row.last_node(big_n);
            structure.extend((0..last * nu).map(|c| (r, c)));
            structure.push((r, tf_col));
        }
        let mut me = Shooting {
            ocp,
            options,
            rows,
            structure,
            guess: Vec::new(),
            nominal: None,
            pattern,
            derivatives: None,
            counters: ShootingCounters::default(),
        };
        // Until a guess is set: the squat's excitations held, t_f mid-range.
        let [t0, t1] = me.ocp.options.final_time_bounds;
        let mut g = Vec::with_capacity(tf_col + 1);
        for _ in 0..big_n {
            g.extend_from_slice(me.ocp.u0());
        }
        g.push(0.5 * (t0 + t1));
        me.guess = g;
        Ok(me)
    }

    pub fn options(&self) -> &ShootingOptions {
        &self.options
    }
    pub fn num_intervals(&self) -> usize {
        self.options.num_intervals
    }
    /// t_f of a point (NaN if `v` is too short).
    pub fn final_time(&self, v: &[f64]) -> f64 {
        v.get(self.options.num_intervals * self.ocp.nu())
            .copied()
            .unwrap_or(f64::NAN)
    }

    /// The point from node excitations u_1..u_N (each clamped into its
    /// bounds) and t_f.
    pub fn point_from(&self, controls: &[Vec<f64>], tf: f64) -> Result<Vec<f64>, EvalError> {
        let big_n = self.options.num_intervals;
        if controls.len() != big_n {
            return Err(EvalError::new(
                "guess",
                format!("{} node excitations for {big_n} intervals", controls.len()),
            ));
        }
        let [t0, t1] = self.ocp.options.final_time_bounds;
        let mut v = Vec::with_capacity(big_n * self.ocp.nu() + 1);
        for u in controls {
            if u.len() != self.ocp.nu() {
                return Err(EvalError::new(
                    "guess",
                    format!("{} excitations, the model has {}", u.len(), self.ocp.nu()),
                ));
            }
            v.extend(
                u.iter()
                    .enumerate()
                    .map(|(i, &x)| x.clamp(self.ocp.control_lower[i], self.ocp.control_upper[i])),
            );
        }
        v.push(tf.clamp(t0, t1));
        Ok(v)
    }

    /// Excitations sampled at the nodes of [0, t_f] from a source.
    pub fn point_from_source(
        &self,
        src: &dyn ExcitationSource,
        tf: f64,
    ) -> Result<Vec<f64>, EvalError> {
        let big_n = self.options.num_intervals;
        let h = tf / big_n as f64;
        let controls: Vec<Vec<f64>> = (1..=big_n)
            .map(|k| {
                let mut u = vec![0.0; self.ocp.nu()];
                src.at(k as f64 * h, &mut u);
                u
            })
            .collect();
        self.point_from(&controls, tf)
    }

    /// The initial guess the SQP starts from ([`Nlp::initial_point`]).
    pub fn set_guess(&mut self, v: Vec<f64>) {
        self.guess = v;
    }

    /// The bang-bang jump's excitations at the nodes, t_f its lift-off time
    /// (the paper's second guess, as collocation's), and its summary.
    pub fn bang_bang_guess(&self) -> Result<(Vec<f64>, crate::simulate::JumpSummary), OcpError> {
        let (summary, _) = self
            .ocp
            .simulate_bang_bang(1e-6)
            .map_err(|f| OcpError::Simulation(f.to_string()))?;
        let tf = summary.liftoff_time_s.ok_or_else(|| {
            OcpError::Invalid(format!(
                "the bang-bang jump does not lift off within {} s",
                summary.final_time_s
            ))
        })?;
        let v = self
            .point_from_source(&self.ocp.bang_bang(), tf)
            .map_err(|e| OcpError::Invalid(e.to_string()))?;
        Ok((v, summary))
    }

    /// Node excitations of a point, node 0 (the squat's) first (only the
    /// nodes `v` holds if it is too short).
    pub fn node_controls(&self, v: &[f64]) -> Vec<f64> {
        let nu = self.ocp.nu();
        let n = (self.options.num_intervals * nu).min(v.len());
        let mut c = Vec::with_capacity(n + nu);
        c.extend_from_slice(self.ocp.u0());
        c.extend_from_slice(&v[..n]);
        c
    }

    fn check_point(&self, v: &[f64]) -> Result<(), EvalError> {
        if v.len() != self.num_variables() {
            return Err(EvalError::new(
                "point",
                format!("{} values for {} variables", v.len(), self.num_variables()),
            ));
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(EvalError::new(
                "point",
                format!("{} is not finite ({})", self.variable_name(i), v[i]),
            ));
        }
        let tf = self.final_time(v);
        if tf <= 0.0 {
            return Err(EvalError::new(
                "point",
                format!("t_f = {tf} s is not positive"),
            ));
        }
        Ok(())
    }

    /// Dormand–Prince settings of an integration over [0, tf].
    fn dopri_options(&self, tf: f64) -> Dopri5Options {
        Dopri5Options {
            accuracy: self.options.accuracy,
            min_step: 1e-10 * tf.max(1e-3),
            max_step: tf / self.options.num_intervals as f64,
            max_steps: 200_000,
        }
    }

    /// Interval k (1..N) of [0, tf]: its start, its end and h = tf/N.
    fn interval_span(&self, k: usize, tf: f64) -> (f64, f64, f64) {
        let big_n = self.options.num_intervals;
        let h = tf / big_n as f64;
        let tb = if k == big_n { tf } else { k as f64 * h };
        ((k - 1) as f64 * h, tb, h)
    }

    /// Integrate interval k (1..N) from `x` (node k−1's state) with the
    /// node excitations `controls` (node 0 first) over [0, tf]: node k's
    /// state and the right-hand-side evaluations. After every accepted
    /// step `on_step` receives the system, the step's start (t, x) and the
    /// integrator (at the step's end).
    fn integrate_interval(
        &self,
        ws: &mut StateWorkspace<f64>,
        controls: &[f64],
        tf: f64,
        k: usize,
        x: &[f64],
        on_step: &mut OnStep,
    ) -> Result<(Vec<f64>, usize), EvalError> {
        let ocp = &*self.ocp;
        let nu = ocp.nu();
        let (ta, tb, h) = self.interval_span(k, tf);
        let mut sys = IntervalRhs {
            ocp,
            ws,
            u: vec![0.0; nu],
            ua: &controls[(k - 1) * nu..k * nu],
            ub: &controls[k * nu..(k + 1) * nu],
            ta,
            h,
        };
        let fail = |e: crate::integrator::IntegrationError| {
            EvalError::new("simulation", format!("interval {k}: {e}"))
        };
        let mut ig = Dopri5::new(&mut sys, ta, x, self.dopri_options(tf)).map_err(fail)?;
        let mut start = x.to_vec();
        while ig.t() < tb {
            let t0 = ig.t();
            start.copy_from_slice(ig.x());
            ig.step(&mut sys, tb).map_err(fail)?;
            on_step(&mut sys, t0, &start, &ig);
        }
        Ok((ig.x().to_vec(), ig.stats.f_evals))
    }

    /// Integrate from node `first` (state `x_first`) to node N with the
    /// node excitations `controls` (node 0 first) over [0, tf]; the node
    /// quantities from node `first` on. `record` receives every accepted
    /// step (time, state, excitations, ground forces).
    fn integrate(
        &self,
        ws: &mut StateWorkspace<f64>,
        controls: &[f64],
        tf: f64,
        first: usize,
        x_first: &[f64],
        mut record: Option<&mut Trajectory>,
    ) -> Result<NodeValues, EvalError> {
        let ocp = &*self.ocp;
        let (nx, nu) = (ocp.nx(), ocp.nu());
        let big_n = self.options.num_intervals;
        let h = tf / big_n as f64;
        let mut out = NodeValues::default();
        let mut xdot = vec![0.0; nx];
        let mut node = |out: &mut NodeValues,
                        ws: &mut StateWorkspace<f64>,
                        k: usize,
                        x: &[f64]|
         -> Result<(), EvalError> {
            let u = &controls[k * nu..(k + 1) * nu];
            let (ydd, fy) = ocp.state_rates(ws, x, u, &mut xdot).map_err(|e| {
                EvalError::new(
                    "simulation",
                    format!("node {k} (t = {} s): {e}", k as f64 * h),
                )
            })?;
            let (y, yd, j) = ocp.jump_objective(&mut ws.mb, x);
            out.states.push(x.to_vec());
            out.com_acceleration.push(ydd);
            out.vertical_force_bw.push(fy);
            out.com_velocity.push(yd);
            out.com_height.push(y);
            out.objective = j;
            Ok(())
        };
        node(&mut out, ws, first, x_first)?;
        let mut x = x_first.to_vec();
        for k in first + 1..=big_n {
            let mut on_step = |sys: &mut IntervalRhs, _: f64, _: &[f64], ig: &Dopri5| {
                if let Some(tr) = record.as_deref_mut() {
                    let (t, xs) = (ig.t(), ig.x().to_vec());
                    let mut d = vec![0.0; nx];
                    if sys.rhs(t, &xs, &mut d).is_ok() {
                        let g = grf_of(&ocp.eq, sys.ws, &xs);
                        tr.time.push(t);
                        tr.states.push(xs);
                        tr.controls.push(sys.u.clone());
                        tr.grf.push(g);
                    }
                }
            };
            let (xk, f_evals) = self.integrate_interval(ws, controls, tf, k, &x, &mut on_step)?;
            out.f_evals += f_evals;
            x = xk;
            node(&mut out, ws, k, &x)?;
        }
        Ok(out)
    }

    /// The nominal integration at `v` (cached).
    pub fn evaluate(&mut self, v: &[f64]) -> Result<&NodeValues, EvalError> {
        let cached = matches!(&self.nominal, Some((p, _)) if p.as_slice() == v);
        if !cached {
            self.nominal = None;
            self.check_point(v)?;
            let mut ws = self.ocp.eq.workspace();
            let controls = self.node_controls(v);
            let r = self.integrate(
                &mut ws,
                &controls,
                self.final_time(v),
                0,
                &self.ocp.squat.x.clone(),
                None,
            )?;
            self.counters.simulations += 1;
            self.counters.f_evals += r.f_evals;
            self.nominal = Some((v.to_vec(), r));
        }
        match &self.nominal {
            Some((_, r)) => Ok(r),
            None => Err(EvalError::new("simulation", "no integration at this point")),
        }
    }

    /// The integration at `v` with every accepted step recorded.
    pub fn trajectory(&self, v: &[f64]) -> Result<(NodeValues, Trajectory), EvalError> {
        self.check_point(v)?;
        let mut ws = self.ocp.eq.workspace();
        let mut tr = Trajectory::default();
        let controls = self.node_controls(v);
        let x0 = self.ocp.squat.x.clone();
        // The start, as `leap simulate` records it.
        let mut d = vec![0.0; self.ocp.nx()];
        if self
            .ocp
            .state_rates(&mut ws, &x0, self.ocp.u0(), &mut d)
            .is_ok()
        {
            tr.time.push(0.0);
            tr.states.push(x0.clone());
            tr.controls.push(self.ocp.u0().to_vec());
            tr.grf.push(grf_of(&self.ocp.eq, &ws, &x0));
        }
        let r = self.integrate(
            &mut ws,
            &controls,
            self.final_time(v),
            0,
            &x0,
            Some(&mut tr),
        )?;
        Ok((r, tr))
    }

    /// The derivatives at `v` (cached; central differences or forward
    /// sensitivities): the gradient of −J and the Jacobian's values.
    fn derivatives_at(&mut self, v: &[f64]) -> Result<(&[f64], &[f64]), EvalError> {
        let cached = matches!(&self.derivatives, Some((p, _, _)) if p.as_slice() == v);
        if !cached {
            self.derivatives = None;
            match self.options.derivatives {
                ShootingDerivatives::CentralDifference => self.compute_quotients(v)?,
                ShootingDerivatives::ForwardSensitivity => self.compute_sensitivities(v)?,
            }
        }
        match &self.derivatives {
            Some((_, g, j)) => Ok((g, j)),
            None => Err(EvalError::new("jacobian", "no derivatives at this point")),
        }
    }

    /// Central differences of every node quantity and J in every variable.
    fn compute_quotients(&mut self, v: &[f64]) -> Result<(), EvalError> {
        let started = std::time::Instant::now();
        self.evaluate(v)?;
        let Some((_, nominal)) = &self.nominal else {
            return Err(EvalError::new("jacobian", "no integration at this point"));
        };
        let (nx, nu) = (self.ocp.nx(), self.ocp.nu());
        let big_n = self.options.num_intervals;
        let n = self.num_variables();
        let tf = self.final_time(v);
        let delta = self.options.finite_difference_step;
        let controls = self.node_controls(v);
        let per_node = nx + EXTRA;
        let me = &*self;
        // Column c: the quotients of the node quantities from its first
        // node, and of J.
        let column =
            |ws: &mut StateWorkspace<f64>, c: usize| -> Result<ColumnQuotients, EvalError> {
                let (first, d) = if c < big_n * nu {
                    (c / nu, delta)
                } else {
                    (0, delta * tf)
                };
                let mut run = |sign: f64| {
                    let mut ctl = controls.clone();
                    let mut t = tf;
                    if c < big_n * nu {
                        ctl[nu + c] += sign * d;
                    } else {
                        t += sign * d;
                    }
                    me.integrate(ws, &ctl, t, first, &nominal.states[first], None)
                };
                let (p, m) = (run(1.0)?, run(-1.0)?);
                let mut q = Vec::with_capacity((big_n + 1 - first) * per_node);
                let s = 0.5 / d;
                for k in 0..p.states.len() {
                    q.extend(
                        p.states[k]
                            .iter()
                            .zip(&m.states[k])
                            .map(|(a, b)| (a - b) * s),
                    );
                    q.push((p.com_acceleration[k] - m.com_acceleration[k]) * s);
                    q.push((p.vertical_force_bw[k] - m.vertical_force_bw[k]) * s);
                    q.push((p.com_velocity[k] - m.com_velocity[k]) * s);
                }
                Ok(ColumnQuotients {
                    column: c,
                    first,
                    nodes: q,
                    objective: (p.objective - m.objective) * s,
                    f_evals: p.f_evals + m.f_evals,
                })
            };
        let done = run_tasks(
            self.options.threads,
            0..n,
            "difference-quotient",
            || Ok(me.ocp.eq.workspace()),
            column,
        )?;
        let mut columns: Vec<(usize, Vec<f64>)> = vec![(0, Vec::new()); n];
        let mut grad = vec![0.0; n];
        let mut f_evals = 0;
        let mut sims = 0;
        for q in done {
            columns[q.column] = (q.first, q.nodes);
            grad[q.column] = -q.objective;
            f_evals += q.f_evals;
            sims += 2;
        }
        let value = |c: usize, k: usize, what: usize| -> f64 {
            let (first, q) = &columns[c];
            if k < *first {
                0.0
            } else {
                q[(k - first) * per_node + what]
            }
        };
        self.counters.difference_simulations += sims;
        self.counters.f_evals += f_evals;
        self.store_derivatives(v, grad, started, |row, c| match row {
            Row::NoCountermovement(j) => value(c, j, nx) - value(c, j + 1, nx),
            Row::LiftOff => value(c, big_n, nx + 1),
            Row::NoDescent(k) => value(c, k, nx + 2),
            Row::Bound(k, i) => value(c, k, i),
        })
    }

    /// The Jacobian's values (`entry(row, column)` over the structure),
    /// checked finite with the gradient, counted and cached at `v`.
    fn store_derivatives(
        &mut self,
        v: &[f64],
        grad: Vec<f64>,
        started: std::time::Instant,
        entry: impl Fn(Row, usize) -> f64,
    ) -> Result<(), EvalError> {
        let jac: Vec<f64> = self
            .structure
            .iter()
            .map(|&(r, c)| entry(self.rows[r], c))
            .collect();
        self.check_derivatives(&grad, &jac)?;
        self.counters.jacobians += 1;
        self.counters.jacobian_seconds += started.elapsed().as_secs_f64();
        self.derivatives = Some((v.to_vec(), grad, jac));
        Ok(())
    }

    /// Interval k's sensitivities (the nominal steps from node k−1's state
    /// `x_start` replayed with the point Jacobian at every stage) and node
    /// k's point derivatives (at its state `x_end`).
    #[allow(clippy::too_many_arguments)]
    fn interval_sensitivity(
        &self,
        pj: &mut PointJacobian,
        entries: &[(usize, usize)],
        ws: &mut StateWorkspace<f64>,
        objective_ws: (&mut crate::multibody::Workspace<Dual64>, &mut [Dual64]),
        controls: &[f64],
        tf: f64,
        k: usize,
        x_start: &[f64],
        x_end: &[f64],
    ) -> Result<IntervalSensitivity, EvalError> {
        let ocp = &*self.ocp;
        let (nx, nu, nq) = (ocp.nx(), ocp.nu(), ocp.nq());
        let m = nx + 2 * nu + 1;
        let tcol = m - 1;
        // The accepted steps (t, h) and their start states, back to back.
        let mut steps: Vec<(f64, f64)> = Vec::new();
        let mut starts: Vec<f64> = Vec::new();
        let (_, f_evals) =
            self.integrate_interval(ws, controls, tf, k, x_start, &mut |_, t0, x0, ig| {
                steps.push((t0, ig.last_step()));
                starts.extend_from_slice(x0);
            })?;
        let (ta, _, hk) = self.interval_span(k, tf);
        let (ua, ub) = (
            &controls[(k - 1) * nu..k * nu],
            &controls[k * nu..(k + 1) * nu],
        );
        let fail = |what: String, e: String| EvalError::new("jacobian", format!("{what}: {e}"));
        // ∂x/∂(x_{k−1}, u_{k−1}, u_k, t_f), n_x × m row-major.
        let mut sens = vec![0.0; nx * m];
        for i in 0..nx {
            sens[i * m + i] = 1.0;
        }
        let mut kv = vec![vec![0.0; nx]; 6];
        let mut dk = vec![vec![0.0; nx * m]; 6];
        let (mut xs, mut dxs) = (vec![0.0; nx], vec![0.0; nx * m]);
        let mut us = vec![0.0; nu];
        let mut g = vec![0.0; nx + 2];
        let mut jac = vec![0.0; entries.len()];
        let mut point_jacobians = 0;
        for (&(t0, h), x0) in steps.iter().zip(starts.chunks_exact(nx)) {
            for st in 0..7 {
                // Stage st's point x0 + h Σ a_sj K_j and its derivative;
                // the step is h = (t_f/N)·Δτ, so ∂h/∂t_f = h/t_f.
                xs.copy_from_slice(x0);
                dxs.copy_from_slice(&sens);
                for (j, (kj, dkj)) in kv.iter().zip(&dk).enumerate().take(st) {
                    let ha = h * DP_A[st][j];
                    if ha == 0.0 {
                        continue;
                    }
                    for (d, e) in dxs.iter_mut().zip(dkj) {
                        *d += ha * e;
                    }
                    for i in 0..nx {
                        xs[i] += ha * kj[i];
                        dxs[i * m + tcol] += ha / tf * kj[i];
                    }
                }
                if st == 6 {
                    break;
                }
                // The excitations are linear in τ = t/t_f on the interval.
                let w = ((t0 + DP_C[st] * h - ta) / hk).clamp(0.0, 1.0);
                for i in 0..nu {
                    us[i] = ua[i] + w * (ub[i] - ua[i]);
                }
                pj.eval(ocp, &xs, &us, &mut g, &mut jac)
                    .map_err(|e| fail(format!("interval {k} at t = {} s", t0 + DP_C[st] * h), e))?;
                point_jacobians += 1;
                kv[st].copy_from_slice(&g[..nx]);
                let d = &mut dk[st];
                d.fill(0.0);
                for (&(r, c), &v) in entries.iter().zip(&jac) {
                    if r >= nx {
                        break;
                    }
                    if v == 0.0 {
                        continue;
                    }
                    let row = &mut d[r * m..(r + 1) * m];
                    if c < nx {
                        for (a, b) in row.iter_mut().zip(&dxs[c * m..(c + 1) * m]) {
                            *a += v * b;
                        }
                    } else {
                        // Column c is excitation c − n_x: its weights
                        // (1 − w) on u_{k−1}, w on u_k.
                        row[c] += v * (1.0 - w);
                        row[c + nu] += v * w;
                    }
                }
            }
            std::mem::swap(&mut sens, &mut dxs);
        }
        // Node k: ∂(Ÿ_C, F_y/(m g))/∂(x_k, u_k), ∂Ẏ_C/∂x_k, ∂J/∂x_k.
        pj.eval(
            ocp,
            x_end,
            &controls[k * nu..(k + 1) * nu],
            &mut g,
            &mut jac,
        )
        .map_err(|e| fail(format!("node {k}"), e))?;
        point_jacobians += 1;
        let mut ydd = vec![0.0; nx + nu];
        let mut fy = vec![0.0; nx + nu];
        for (&(r, c), &v) in entries.iter().zip(&jac) {
            if r == nx {
                ydd[c] = v;
            } else if r == nx + 1 {
                fy[c] = v;
            }
        }
        let (ows, oxd) = objective_ws;
        let mut yd = vec![0.0; 2 * nq];
        jump_objective_gradient(ocp, (&mut *ows, &mut *oxd), &x_end[..2 * nq], 1, &mut yd);
        let mut j = vec![0.0; 2 * nq];
        if k == self.options.num_intervals {
            jump_objective_gradient(ocp, (ows, oxd), &x_end[..2 * nq], 2, &mut j);
        }
        Ok(IntervalSensitivity {
            k,
            sens,
            ydd,
            fy,
            yd,
            j,
            f_evals,
            point_jacobians,
            steps: steps.len(),
        })
    }

    /// Forward sensitivities of every node quantity and J in every
    /// variable: per interval (on the threads) ∂x_k/∂(x_{k−1}, u_{k−1},
    /// u_k, t_f), then chained from node to node.
    fn compute_sensitivities(&mut self, v: &[f64]) -> Result<(), EvalError> {
        let started = std::time::Instant::now();
        self.evaluate(v)?;
        let Some((_, nominal)) = &self.nominal else {
            return Err(EvalError::new("jacobian", "no integration at this point"));
        };
        let Some(pattern) = &self.pattern else {
            return Err(EvalError::new(
                "jacobian",
                "forward sensitivities need the pattern of ∂f/∂(x, u)",
            ));
        };
        let ocp = &*self.ocp;
        let (nx, nu, nq) = (ocp.nx(), ocp.nu(), ocp.nq());
        let m = nx + 2 * nu + 1;
        let big_n = self.options.num_intervals;
        let n = self.num_variables();
        let tf = self.final_time(v);
        let controls = self.node_controls(v);
        let me = &*self;
        let init = || -> Result<_, EvalError> {
            let pj = PointJacobian::new(ocp, pattern)
                .map_err(|e| EvalError::new("jacobian", e.to_string()))?;
            let entries = pj.entries().to_vec();
            Ok((
                pj,
                entries,
                ocp.eq.workspace(),
                ocp.eq.multibody.workspace::<Dual64>(),
                vec![Dual64::from(0.0); 2 * nq],
            ))
        };
        let done = run_tasks(
            self.options.threads,
            1..big_n + 1,
            "sensitivity",
            init,
            |(pj, entries, ws, ows, oxd), k| {
                me.interval_sensitivity(
                    pj,
                    entries,
                    ws,
                    (ows, oxd),
                    &controls,
                    tf,
                    k,
                    &nominal.states[k - 1],
                    &nominal.states[k],
                )
            },
        )?;
        let mut per: Vec<Option<IntervalSensitivity>> = (0..=big_n).map(|_| None).collect();
        let (mut f_evals, mut pjs, mut steps) = (0, 0, 0);
        for s in done {
            f_evals += s.f_evals;
            pjs += s.point_jacobians;
            steps += s.steps;
            let k = s.k;
            per[k] = Some(s);
        }
        // Chain: G_k = ∂x_k/∂v (n_x × n row-major) = A_k G_{k−1} + the
        // columns of u_{k−1}, u_k and t_f; G_0 = 0 (the squat is fixed).
        // Per node the rows of Ÿ_C, F_y/(m g) and Ẏ_C over v.
        let mut g_nodes: Vec<Vec<f64>> = vec![vec![0.0; nx * n]];
        let mut d_ydd = vec![vec![0.0; n]];
        let mut d_fy = vec![vec![0.0; n]];
        let mut d_yd = vec![vec![0.0; n]];
        let mut grad = vec![0.0; n];
        for k in 1..=big_n {
            let Some(s) = per[k].as_ref() else {
                return Err(EvalError::new(
                    "jacobian",
                    format!("interval {k} has no sensitivities"),
                ));
            };
            let prev = &g_nodes[k - 1];
            let used = (k - 1) * nu;
            let mut gk = vec![0.0; nx * n];
            for i in 0..nx {
                let srow = &s.sens[i * m..(i + 1) * m];
                let row = &mut gk[i * n..(i + 1) * n];
                for (l, &a) in srow[..nx].iter().enumerate() {
                    if a == 0.0 {
                        continue;
                    }
                    let src = &prev[l * n..(l + 1) * n];
                    for (r, p) in row[..used].iter_mut().zip(&src[..used]) {
                        *r += a * p;
                    }
                    row[n - 1] += a * src[n - 1];
                }
                if k >= 2 {
                    for c in 0..nu {
                        row[(k - 2) * nu + c] += srow[nx + c];
                    }
                }
                for c in 0..nu {
                    row[(k - 1) * nu + c] += srow[nx + nu + c];
                }
                row[n - 1] += srow[m - 1];
            }
            // ∂(node output)/∂v = ∂/∂x_k · G_k (+ ∂/∂u_k on u_k's columns).
            let through = |dx: &[f64], du: Option<&[f64]>| {
                let mut out = vec![0.0; n];
                for (l, &a) in dx.iter().enumerate() {
                    if a == 0.0 {
                        continue;
                    }
                    for (o, p) in out.iter_mut().zip(&gk[l * n..(l + 1) * n]) {
                        *o += a * p;
                    }
                }
                if let Some(du) = du {
                    for (c, &a) in du.iter().enumerate() {
                        out[(k - 1) * nu + c] += a;
                    }
                }
                out
            };
            d_ydd.push(through(&s.ydd[..nx], Some(&s.ydd[nx..])));
            d_fy.push(through(&s.fy[..nx], Some(&s.fy[nx..])));
            d_yd.push(through(&s.yd, None));
            if k == big_n {
                for (gi, d) in grad.iter_mut().zip(through(&s.j, None)) {
                    *gi = -d;
                }
            }
            g_nodes.push(gk);
        }
        self.counters.f_evals += f_evals;
        self.counters.point_jacobians += pjs;
        self.counters.sensitivity_steps += steps;
        self.store_derivatives(v, grad, started, |row, c| match row {
            Row::NoCountermovement(j) => d_ydd[j][c] - d_ydd[j + 1][c],
            Row::LiftOff => d_fy[big_n][c],
            Row::NoDescent(k) => d_yd[k][c],
            Row::Bound(k, i) => g_nodes[k][i * n + c],
        })
    }

    /// An error naming the first derivative that is not finite.
    fn check_derivatives(&self, grad: &[f64], jac: &[f64]) -> Result<(), EvalError> {
        if let Some(i) = grad.iter().position(|x| !x.is_finite()) {
            return Err(EvalError::new(
                "gradient",
                format!("∂J/∂({}) is not finite", self.variable_name(i)),
            ));
        }
        if let Some(i) = jac.iter().position(|x| !x.is_finite()) {
            let (r, c) = self.structure[i];
            return Err(EvalError::new(
                "jacobian",
                format!(
                    "∂({})/∂({}) is not finite",
                    self.constraint_name(r),
                    self.variable_name(c)
                ),
            ));
        }
        Ok(())
    }

    /// Row `row`'s value from the node quantities of a whole integration.
    fn row_value(&self, nv: &NodeValues, row: Row) -> f64 {
        match row {
            Row::NoCountermovement(j) => nv.com_acceleration[j] - nv.com_acceleration[j + 1],
            Row::LiftOff => nv.vertical_force_bw[self.options.num_intervals],
            Row::NoDescent(k) => nv.com_velocity[k],
            Row::Bound(k, i) => nv.states[k][i],
        }
    }
}

impl Nlp for Shooting {
    fn num_variables(&self) -> usize {
        self.options.num_intervals * self.ocp.nu() + 1
    }
    fn num_constraints(&self) -> usize {
        self.rows.len()
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        let nu = self.ocp.nu();
        for k in 0..self.options.num_intervals {
            lower[k * nu..(k + 1) * nu].copy_from_slice(&self.ocp.control_lower);
            upper[k * nu..(k + 1) * nu].copy_from_slice(&self.ocp.control_upper);
        }
        let [t0, t1] = self.ocp.options.final_time_bounds;
        let n = self.num_variables();
        lower[n - 1] = t0;
        upper[n - 1] = t1;
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        let (lo_l, lo_u) = self.ocp.liftoff_bounds();
        for (r, row) in self.rows.iter().enumerate() {
            (lower[r], upper[r]) = match *row {
                Row::NoCountermovement(_) => (f64::NEG_INFINITY, 0.0),
                Row::LiftOff => (lo_l, lo_u),
                Row::NoDescent(_) => (0.0, f64::INFINITY),
                Row::Bound(_, i) => (self.ocp.state_lower[i], self.ocp.state_upper[i]),
            };
        }
    }
    fn initial_point(&self, x: &mut [f64]) {
        x.copy_from_slice(&self.guess);
    }
    fn objective(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        Ok(-self.evaluate(x)?.objective)
    }
    fn gradient(&mut self, x: &[f64], g: &mut [f64]) -> Result<(), EvalError> {
        g.copy_from_slice(self.derivatives_at(x)?.0);
        Ok(())
    }
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        self.evaluate(x)?;
        let Some((_, nv)) = &self.nominal else {
            return Err(EvalError::new(
                "constraints",
                "no integration at this point",
            ));
        };
        for (r, &row) in self.rows.iter().enumerate() {
            c[r] = self.row_value(nv, row);
        }
        Ok(())
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        self.structure.clone()
    }
    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        values.copy_from_slice(self.derivatives_at(x)?.1);
        Ok(())
    }
    fn variable_name(&self, i: usize) -> String {
        let nu = self.ocp.nu();
        if i >= self.options.num_intervals * nu {
            return "t_f".into();
        }
        let names = self.ocp.eq.control_names();
        format!("node {} {}", i / nu + 1, names[i % nu])
    }
    fn constraint_name(&self, i: usize) -> String {
        match self.rows.get(i) {
            Some(Row::NoCountermovement(j)) => {
                format!("no countermovement: Ÿ_C(node {j}) ≤ Ÿ_C(node {})", j + 1)
            }
            Some(Row::LiftOff) => "lift-off: F_y(t_f)/(m g)".into(),
            Some(Row::NoDescent(k)) => format!("no descent: Ẏ_C(node {k}) ≥ 0"),
            Some(Row::Bound(k, i)) => {
                format!("bound of {} at node {k}", self.ocp.eq.state_names()[*i])
            }
            None => format!("c[{i}]"),
        }
    }
}

/// Tasks `tasks` on up to `threads` scoped threads, each thread with its
/// own state from `init`: every task's result (in no particular order), or
/// the first error; a failing task stops the other threads at their next
/// task. `what` names the tasks in the error of a thread that panicked.
fn run_tasks<S, T: Send>(
    threads: usize,
    tasks: std::ops::Range<usize>,
    what: &str,
    init: impl Fn() -> Result<S, EvalError> + Sync,
    task: impl Fn(&mut S, usize) -> Result<T, EvalError> + Sync,
) -> Result<Vec<T>, EvalError> {
    let next = AtomicUsize::new(tasks.start);
    let failed = AtomicBool::new(false);
    let work = || -> Result<Vec<T>, EvalError> {
        let mut state = init()?;
        let mut done = Vec::new();
        loop {
            let i = next.fetch_add(1, Ordering::Relaxed);
            if i >= tasks.end || failed.load(Ordering::Relaxed) {
                return Ok(done);
            }
            match task(&mut state, i) {
                Ok(r) => done.push(r),
                Err(e) => {
                    failed.store(true, Ordering::Relaxed);
                    return Err(e);
                }
            }
        }
    };
    let threads = threads.min(tasks.len()).max(1);
    let results: Vec<Result<Vec<T>, EvalError>> = std::thread::scope(|scope| {
        // A thread the system refuses (a process limit) leaves its tasks
        // to the others, and to this thread if none started.
        let handles: Vec<_> = (0..threads)
            .filter_map(|_| std::thread::Builder::new().spawn_scoped(scope, work).ok())
            .collect();
        let mut results: Vec<_> = handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err(EvalError::new(
                        "jacobian",
                        format!("a {what} thread panicked"),
                    ))
                })
            })
            .collect();
        if results.is_empty() {
            results.push(work());
        }
        results
    });
    let mut all = Vec::new();
    for r in results {
        all.extend(r?);
    }
    Ok(all)
}

/// The SQP settings of a shooting solve from a study's: damped BFGS (the
/// derivatives are first derivatives only), its first curvature
/// taken along the first step (Oren–Luenberger), not the largest seen
/// (Shanno–Phua). On the full jump from the bang-bang guess with central
/// differences, Shanno–Phua's steps stayed near 1e-3 (the actual reduction twice the predicted) and
/// the paper's rule stopped the solve at 25.6 cm after 45 iterations;
/// Oren–Luenberger's steps were 0.05–0.1 and passed that point by
/// iteration 9 (docs/shooting.md).
pub fn sqp_settings(base: &crate::sqp::SqpSettings) -> crate::sqp::SqpSettings {
    crate::sqp::SqpSettings {
        hessian: crate::sqp::HessianMode::PartitionedBfgs,
        bfgs_scaling_along_step: true,
        ..base.clone()
    }
}
