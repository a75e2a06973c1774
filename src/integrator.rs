//! A Rust-native variable-step Runge-Kutta integrator: Dormand-Prince 5(4)
//! with FSAL, step-size control and cubic Hermite dense output for event
//! location (Dormand & Prince, J. Comput. Appl. Math. 6, 1980; Hairer,
//! Nørsett & Wanner, *Solving ODEs I*, §II.4-II.6).

/// An explicit ODE `ẋ = f(t, x)`.
pub trait OdeSystem {
    fn dim(&self) -> usize;
    /// Write `f(t, x)` into `dx`; an error stops the integration.
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), String>;
}

/// Settings of [`Dopri5`]; `accuracy` is the relative and absolute
/// tolerance, as Simbody's `setAccuracy`.
#[derive(Debug, Clone, Copy)]
pub struct Dopri5Options {
    pub accuracy: f64,
    pub min_step: f64,
    pub max_step: f64,
    pub max_steps: usize,
}

impl Default for Dopri5Options {
    fn default() -> Self {
        // OpenSim's AbstractTool defaults (model-equations.md §7.5).
        Dopri5Options {
            accuracy: 1e-5,
            min_step: 1e-8,
            max_step: 1.0,
            max_steps: 20_000,
        }
    }
}

/// Counters of an integration.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct IntegrationStats {
    pub steps: usize,
    pub rejected_steps: usize,
    pub f_evals: usize,
    /// Steps taken at the minimum step size with the error estimate above
    /// the accuracy (counted in `steps`): as Simbody does, a step that
    /// cannot be made smaller is accepted. A jump of the right-hand side (a
    /// knee spline's end, a path point switching) has a local error of
    /// about h·Δf, which no step above the minimum brings below 1e-8.
    pub steps_over_tolerance: usize,
}

/// Why an integration stopped early.
#[derive(Debug, Clone, thiserror::Error)]
pub enum IntegrationError {
    #[error("at t = {t}: the right-hand side failed: {reason}")]
    Rhs { t: f64, reason: String },
    #[error("integrator settings: {0}")]
    Options(String),
    #[error(
        "at t = {t}: more than {max_steps} steps: the model is too stiff to integrate at this accuracy"
    )]
    TooManySteps { t: f64, max_steps: usize },
    #[error("at t = {t}: the state is not finite")]
    NotFinite { t: f64 },
}

/// Dormand–Prince nodes c_s and coefficients a_sj (row 6: the fifth-order
/// weights b_j, the new state being stage 6's point).
pub(crate) const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
pub(crate) const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
/// Fifth-order weights minus the embedded fourth-order ones.
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

/// Dormand-Prince 5(4) stepping one accepted step at a time.
#[derive(Debug, Clone)]
pub struct Dopri5 {
    pub options: Dopri5Options,
    pub stats: IntegrationStats,
    t: f64,
    h: f64,
    /// The length of the last accepted step.
    h_last: f64,
    x: Vec<f64>,
    k: [Vec<f64>; 7],
    xs: Vec<f64>,
    xnew: Vec<f64>,
    /// The last accepted step: t0, x0, f0 (for dense output).
    t_prev: f64,
    x_prev: Vec<f64>,
    f_prev: Vec<f64>,
}

impl Dopri5 {
    /// Start at (t0, x0).
    pub fn new<S: OdeSystem>(
        sys: &mut S,
        t0: f64,
        x0: &[f64],
        options: Dopri5Options,
    ) -> Result<Self, IntegrationError> {
        let o = &options;
        if !(o.accuracy > 0.0 && o.accuracy.is_finite()) {
            return Err(IntegrationError::Options(format!(
                "accuracy must be positive and finite, got {}",
                o.accuracy
            )));
        }
        if !(o.min_step > 0.0 && o.min_step <= o.max_step && o.max_step.is_finite()) {
            return Err(IntegrationError::Options(format!(
                "the steps must satisfy 0 < min_step <= max_step < inf, got {} and {}",
                o.min_step, o.max_step
            )));
        }
        let n = x0.len();
        let mut me = Dopri5 {
            options,
            stats: IntegrationStats::default(),
            t: t0,
            h: 0.0,
            h_last: 0.0,
            x: x0.to_vec(),
            k: std::array::from_fn(|_| vec![0.0; n]),
            xs: vec![0.0; n],
            xnew: vec![0.0; n],
            t_prev: t0,
            x_prev: x0.to_vec(),
            f_prev: vec![0.0; n],
        };
        if x0.iter().any(|v| !v.is_finite()) {
            return Err(IntegrationError::NotFinite { t: t0 });
        }
        sys.rhs(t0, x0, &mut me.k[0])
            .map_err(|reason| IntegrationError::Rhs { t: t0, reason })?;
        me.stats.f_evals += 1;
        me.f_prev.copy_from_slice(&me.k[0]);
        // Initial step (Hairer et al. II.4, simplified).
        let d0 = me.norm_scaled(&me.x, &me.x);
        let d1 = me.norm_scaled(&me.k[0], &me.x);
        let h0 = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        };
        me.h = h0.min(options.max_step).max(options.min_step);
        Ok(me)
    }

    fn norm_scaled(&self, v: &[f64], x: &[f64]) -> f64 {
        let tol = self.options.accuracy;
        let n = v.len().max(1) as f64;
        (v.iter()
            .zip(x)
            .map(|(v, x)| (v / (tol + tol * x.abs())).powi(2))
            .sum::<f64>()
            / n)
            .sqrt()
            * tol
    }

    /// Current time and state.
    pub fn t(&self) -> f64 {
        self.t
    }
    pub fn x(&self) -> &[f64] {
        &self.x
    }
    /// The length h of the last accepted step, as its stages used it (the
    /// time advanced by it may differ in the last bit).
    pub fn last_step(&self) -> f64 {
        self.h_last
    }
    /// The derivative at the current state (FSAL).
    pub fn f(&self) -> &[f64] {
        &self.k[0]
    }

    /// Take one accepted step, not past `t_end`. Returns the new time.
    pub fn step<S: OdeSystem>(&mut self, sys: &mut S, t_end: f64) -> Result<f64, IntegrationError> {
        let n = self.x.len();
        let tol = self.options.accuracy;
        let mut stage_error: Option<(f64, String)> = None;
        loop {
            if self.stats.steps + self.stats.rejected_steps >= self.options.max_steps {
                return Err(IntegrationError::TooManySteps {
                    t: self.t,
                    max_steps: self.options.max_steps,
                });
            }
            let mut h = self.h.min(self.options.max_step);
            let last = self.t + h >= t_end - 1e-14 * t_end.abs().max(1.0);
            if last {
                h = t_end - self.t;
            }
            for s in 1..7 {
                for i in 0..n {
                    let mut acc = self.x[i];
                    for j in 0..s {
                        acc += h * A[s][j] * self.k[j][i];
                    }
                    self.xs[i] = acc;
                }
                if s == 6 {
                    self.xnew.copy_from_slice(&self.xs);
                }
                let (_, tail) = self.k.split_at_mut(s);
                self.stats.f_evals += 1;
                if let Err(reason) = sys.rhs(self.t + C[s] * h, &self.xs, &mut tail[0]) {
                    // A trial state the model rejects (e.g. a fibre out of
                    // range) fails the step, as in Simbody: retry smaller.
                    stage_error = Some((self.t + C[s] * h, reason));
                    break;
                }
            }
            if let Some((t_fail, reason)) = stage_error.take() {
                self.stats.rejected_steps += 1;
                if h <= self.options.min_step {
                    return Err(IntegrationError::Rhs { t: t_fail, reason });
                }
                self.h = (h * 0.25).max(self.options.min_step);
                continue;
            }
            // Error estimate (the 7th stage is f at the new point: FSAL), in
            // the max norm so that one stiff component (a fibre at low
            // activation) cannot hide among the others.
            let mut err: f64 = 0.0;
            for i in 0..n {
                let mut e = 0.0;
                for s in 0..7 {
                    e += E[s] * self.k[s][i];
                }
                let sc = tol + tol * self.x[i].abs().max(self.xnew[i].abs());
                // NaN propagates (f64::max would skip it).
                let ei = (h * e / sc).abs();
                if ei.is_nan() || ei > err {
                    err = ei;
                }
            }
            let finite = err.is_finite()
                && self.xnew.iter().all(|v| v.is_finite())
                && self.k[6].iter().all(|v| v.is_finite());
            let at_minimum = h <= self.options.min_step;
            if finite && (err <= 1.0 || at_minimum) {
                if err > 1.0 {
                    self.stats.steps_over_tolerance += 1;
                }
                self.t_prev = self.t;
                self.x_prev.copy_from_slice(&self.x);
                self.f_prev.copy_from_slice(&self.k[0]);
                self.t = if last { t_end } else { self.t + h };
                self.h_last = h;
                self.x.copy_from_slice(&self.xnew);
                let k6 = self.k[6].clone();
                self.k[0].copy_from_slice(&k6);
                self.stats.steps += 1;
                let fac = if err == 0.0 {
                    5.0
                } else {
                    (0.9 * err.powf(-0.2)).clamp(0.2, 5.0)
                };
                if !last || fac < 1.0 {
                    self.h = (h * fac).max(self.options.min_step);
                }
                return Ok(self.t);
            }
            self.stats.rejected_steps += 1;
            let fac = if finite {
                (0.9 * err.powf(-0.2)).clamp(0.1, 1.0)
            } else {
                0.1
            };
            // Down to the minimum, where the next try is accepted if its
            // state and derivative are finite.
            if h <= self.options.min_step {
                return Err(IntegrationError::NotFinite { t: self.t + h });
            }
            self.h = (h * fac).max(self.options.min_step);
        }
    }

    /// The state at `t` inside the last accepted step (cubic Hermite
    /// interpolation between its ends), written into `out`.
    pub fn dense(&self, t: f64, out: &mut [f64]) {
        let h = self.t - self.t_prev;
        if h <= 0.0 {
            out.copy_from_slice(&self.x);
            return;
        }
        let s = ((t - self.t_prev) / h).clamp(0.0, 1.0);
        let (h00, h10, h01, h11) = (
            2.0 * s * s * s - 3.0 * s * s + 1.0,
            s * s * s - 2.0 * s * s + s,
            -2.0 * s * s * s + 3.0 * s * s,
            s * s * s - s * s,
        );
        for i in 0..out.len() {
            out[i] = h00 * self.x_prev[i]
                + h10 * h * self.f_prev[i]
                + h01 * self.x[i]
                + h11 * h * self.k[0][i];
        }
    }

    /// Start of the last accepted step.
    pub fn t_prev(&self) -> f64 {
        self.t_prev
    }

    /// Restart from a new state (e.g. after a discontinuity), keeping counters.
    pub fn reset<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: f64,
        x: &[f64],
    ) -> Result<(), IntegrationError> {
        self.t = t;
        self.t_prev = t;
        self.x.copy_from_slice(x);
        self.x_prev.copy_from_slice(x);
        sys.rhs(t, x, &mut self.k[0])
            .map_err(|reason| IntegrationError::Rhs { t, reason })?;
        self.stats.f_evals += 1;
        self.f_prev.copy_from_slice(&self.k[0]);
        Ok(())
    }
}
