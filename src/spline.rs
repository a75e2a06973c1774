//! OpenSim's `SimmSpline`: the Forsythe–Malcolm–Moler interpolating cubic.
//!
//! OpenSim's knee translations and moving path points are `SimmSpline`s of a
//! coordinate. Its end conditions are not "natural": the third derivative at
//! each end equals the third divided difference of the four end knots
//! (Forsythe, Malcolm & Moler, *Computer Methods for Mathematical
//! Computations*, 1977, routine `SPLINE`). With three knots the end third
//! derivatives are zero; with two the spline is the straight line through them.
//! Outside `[x₀, x_{n−1}]` it extrapolates linearly with the end slope.
//!
//! On `[x_k, x_{k+1}]`, with `dx = x − x_k`:
//! `y(x) = y_k + dx·(b_k + dx·(c_k + dx·d_k))`.

use crate::scalar::{c, Scalar};
use serde::{Deserialize, Serialize};

/// Knots of a spline as they appear in a model file (`x` strictly increasing).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SplineData {
    pub x: Vec<f64>,
    pub y: Vec<f64>,
}

/// Why a set of knots cannot make a spline.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SplineError {
    #[error("x and y have different lengths ({nx} and {ny})")]
    LengthMismatch { nx: usize, ny: usize },
    #[error("at least 2 knots are needed, got {0}")]
    TooFewKnots(usize),
    #[error("knots are not strictly increasing: x[{index}] = {} does not exceed x[{prev}] = {}", crate::io::readable(*value), crate::io::readable(*prev_value), prev = index - 1)]
    NotIncreasing {
        index: usize,
        value: f64,
        prev_value: f64,
    },
    #[error("knot {index} is not finite")]
    NotFinite { index: usize },
    #[error("the knots x[{prev}] = {}, x[{index}] = {} rise by {rise:e} over {run:e}, a slope of {slope:e} (at most {MAX_SECANT_SLOPE:e}): a location moving that fast with its coordinate (m per rad) is a slip of digits", crate::io::readable(*prev_x), crate::io::readable(*x), prev = index - 1, slope = rise / run)]
    TooSteep {
        index: usize,
        prev_x: f64,
        x: f64,
        rise: f64,
        run: f64,
    },
}

/// The steepest secant between neighbouring knots. leap's splines give a
/// location (m) as a function of a coordinate (the knee's translations and
/// moving path points, of an angle in rad): gait2392's reach 0.08 m/rad.
/// Knots far steeper (a knot moved to 1e-12 rad of its neighbour) make a
/// joint or path that flies apart with a tiny rotation, and would be met
/// only later as a singular mass matrix or a failed squat.
pub const MAX_SECANT_SLOPE: f64 = 100.0;

/// A `SimmSpline` with its coefficients computed once.
#[derive(Debug, Clone, PartialEq)]
pub struct SimmSpline {
    x: Vec<f64>,
    y: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
    d: Vec<f64>,
}

impl SimmSpline {
    /// Fit the spline through the knots, validating them first.
    pub fn new(data: &SplineData) -> Result<Self, SplineError> {
        let (x, y) = (&data.x, &data.y);
        if x.len() != y.len() {
            return Err(SplineError::LengthMismatch {
                nx: x.len(),
                ny: y.len(),
            });
        }
        let n = x.len();
        if n < 2 {
            return Err(SplineError::TooFewKnots(n));
        }
        for i in 0..n {
            if !x[i].is_finite() || !y[i].is_finite() {
                return Err(SplineError::NotFinite { index: i });
            }
            if i > 0 && x[i] <= x[i - 1] {
                return Err(SplineError::NotIncreasing {
                    index: i,
                    value: x[i],
                    prev_value: x[i - 1],
                });
            }
        }
        for i in 1..n {
            let (rise, run) = (y[i] - y[i - 1], x[i] - x[i - 1]);
            if !rise.is_finite() || rise.abs() > MAX_SECANT_SLOPE * run {
                return Err(SplineError::TooSteep {
                    index: i,
                    prev_x: x[i - 1],
                    x: x[i],
                    rise,
                    run,
                });
            }
        }
        let (b, c, d) = fmm_coefficients(x, y);
        Ok(Self {
            x: x.clone(),
            y: y.clone(),
            b,
            c,
            d,
        })
    }

    /// The knots' abscissae.
    pub fn knots_x(&self) -> &[f64] {
        &self.x
    }

    /// The knots' ordinates.
    pub fn knots_y(&self) -> &[f64] {
        &self.y
    }

    /// The knots and coefficients as one block `[x, y, b, c, d]` (5n values),
    /// the form the Simbody facade takes.
    pub fn coefficient_blocks(&self) -> Vec<f64> {
        let mut out = Vec::with_capacity(5 * self.x.len());
        for v in [&self.x, &self.y, &self.b, &self.c, &self.d] {
            out.extend_from_slice(v);
        }
        out
    }

    /// Index `k` of the interval holding `x` (clamped to the end intervals).
    #[inline]
    fn interval(&self, x: f64) -> usize {
        let n = self.x.len();
        if n == 2 || x <= self.x[1] {
            return 0;
        }
        if x >= self.x[n - 2] {
            return n - 2;
        }
        // Binary search: x[lo] <= x < x[hi].
        let (mut lo, mut hi) = (1usize, n - 2);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if x < self.x[mid] {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        lo
    }

    /// Value, first and second derivative at `x`.
    #[inline]
    pub fn eval<S: Scalar>(&self, x: S) -> (S, S, S) {
        let n = self.x.len();
        let xv = x.re();
        if xv < self.x[0] {
            let dx = x - self.x[0];
            return (dx * self.b[0] + self.y[0], c(self.b[0]), S::zero());
        }
        if xv > self.x[n - 1] {
            let dx = x - self.x[n - 1];
            return (
                dx * self.b[n - 1] + self.y[n - 1],
                c(self.b[n - 1]),
                S::zero(),
            );
        }
        let k = self.interval(xv);
        let dx = x - self.x[k];
        let (bk, ck, dk) = (self.b[k], self.c[k], self.d[k]);
        let value = dx * (dx * (dx * dk + ck) + bk) + self.y[k];
        let slope = dx * (dx * (3.0 * dk) + 2.0 * ck) + bk;
        let curvature = dx * (6.0 * dk) + 2.0 * ck;
        (value, slope, curvature)
    }

    /// Value at `x`.
    #[inline]
    pub fn value<S: Scalar>(&self, x: S) -> S {
        self.eval(x).0
    }
}

/// Forsythe–Malcolm–Moler `SPLINE`: coefficients `b, c, d` for every knot.
fn fmm_coefficients(x: &[f64], y: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = x.len();
    let mut b = vec![0.0; n];
    let mut c = vec![0.0; n];
    let mut d = vec![0.0; n];
    if n == 2 {
        let slope = (y[1] - y[0]) / (x[1] - x[0]);
        b[0] = slope;
        b[1] = slope;
        return (b, c, d);
    }
    let nm1 = n - 1;
    // Tridiagonal system: d holds the off-diagonal (interval widths),
    // b the diagonal, c the right-hand side (second divided differences).
    d[0] = x[1] - x[0];
    c[1] = (y[1] - y[0]) / d[0];
    for i in 1..nm1 {
        d[i] = x[i + 1] - x[i];
        b[i] = 2.0 * (d[i - 1] + d[i]);
        c[i + 1] = (y[i + 1] - y[i]) / d[i];
        c[i] = c[i + 1] - c[i];
    }
    // End conditions: third derivatives match third divided differences.
    b[0] = -d[0];
    b[nm1] = -d[n - 2];
    c[0] = 0.0;
    c[nm1] = 0.0;
    if n > 3 {
        c[0] = c[2] / (x[3] - x[1]) - c[1] / (x[2] - x[0]);
        c[nm1] = c[n - 2] / (x[nm1] - x[n - 3]) - c[n - 3] / (x[n - 2] - x[n - 4]);
        c[0] = c[0] * d[0] * d[0] / (x[3] - x[0]);
        c[nm1] = -c[nm1] * d[n - 2] * d[n - 2] / (x[nm1] - x[n - 4]);
    }
    // Forward elimination.
    for i in 1..n {
        let t = d[i - 1] / b[i - 1];
        b[i] -= t * d[i - 1];
        c[i] -= t * c[i - 1];
    }
    // Back substitution.
    c[nm1] /= b[nm1];
    for i in (0..nm1).rev() {
        c[i] = (c[i] - d[i] * c[i + 1]) / b[i];
    }
    // Polynomial coefficients.
    b[nm1] = (y[nm1] - y[n - 2]) / d[n - 2] + d[n - 2] * (c[n - 2] + 2.0 * c[nm1]);
    for i in 0..nm1 {
        b[i] = (y[i + 1] - y[i]) / d[i] - d[i] * (c[i + 1] + 2.0 * c[i]);
        d[i] = (c[i + 1] - c[i]) / d[i];
        c[i] *= 3.0;
    }
    c[nm1] *= 3.0;
    d[nm1] = d[n - 2];
    (b, c, d)
}

#[cfg(test)]
#[allow(clippy::approx_constant)] // knot values copied from gait2392
mod tests {
    use super::*;

    fn knee_ty() -> SimmSpline {
        SimmSpline::new(&SplineData {
            x: vec![
                -2.0944, -1.22173, -0.523599, -0.349066, -0.174533, 0.159149, 2.0944,
            ],
            y: vec![
                -0.4226, -0.4082, -0.399, -0.3976, -0.3966, -0.395264, -0.396,
            ],
        })
        .unwrap()
    }

    /// A secant of 100 per unit passes, one a hair steeper (or a knot moved
    /// to 1e-12 of its neighbour) is refused naming the knots.
    #[test]
    fn knots_steeper_than_the_limit_are_refused() {
        let ok = SimmSpline::new(&SplineData {
            x: vec![0.0, 0.01, 1.0],
            y: vec![0.0, 1.0, 1.0],
        });
        assert!(ok.is_ok(), "{ok:?}");
        for x1 in [0.0099, 1e-12] {
            let e = SimmSpline::new(&SplineData {
                x: vec![0.0, x1, 1.0],
                y: vec![0.0, 1.0, 1.0],
            })
            .unwrap_err();
            assert!(matches!(e, SplineError::TooSteep { index: 1, .. }), "{e}");
            assert!(e.to_string().contains("x[0] = 0, x[1] = "), "{e}");
        }
    }

    #[test]
    fn interpolates_knots_and_is_c2() {
        let s = knee_ty();
        for (i, (&x, &y)) in s.x.iter().zip(&s.y).enumerate() {
            assert!((s.value(x) - y).abs() < 1e-15, "knot {i}");
        }
        for &xk in &s.x[1..s.x.len() - 1] {
            let (_, d1l, d2l) = s.eval(xk - 1e-12);
            let (_, d1r, d2r) = s.eval(xk + 1e-12);
            assert!((d1l - d1r).abs() < 1e-9 && (d2l - d2r).abs() < 1e-8);
        }
    }

    #[test]
    fn reproduces_cubics_exactly() {
        // FMM end conditions are exact for cubic data (third divided differences).
        let f = |x: f64| 0.3 - 1.2 * x + 0.7 * x * x - 0.25 * x * x * x;
        let x: Vec<f64> = vec![-1.0, -0.3, 0.2, 0.9, 1.4, 2.5];
        let s = SimmSpline::new(&SplineData {
            x: x.clone(),
            y: x.iter().map(|&v| f(v)).collect(),
        })
        .unwrap();
        for i in 0..50 {
            let t = -1.0 + 3.5 * i as f64 / 49.0;
            assert!((s.value(t) - f(t)).abs() < 1e-12, "t = {t}");
        }
    }
}
