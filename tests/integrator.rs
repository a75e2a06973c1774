//! The Dormand-Prince 5(4) integrator against closed-form solutions.

use leap::integrator::{Dopri5, Dopri5Options, IntegrationError, OdeSystem};

struct Oscillator;
impl OdeSystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), String> {
        dx[0] = x[1];
        dx[1] = -4.0 * x[0];
        Ok(())
    }
}

fn run(accuracy: f64) -> (f64, Dopri5) {
    let mut sys = Oscillator;
    let opts = Dopri5Options {
        accuracy,
        ..Default::default()
    };
    let mut ig = Dopri5::new(&mut sys, 0.0, &[1.0, 0.0], opts).unwrap();
    while ig.t() < 10.0 {
        ig.step(&mut sys, 10.0).unwrap();
    }
    // x(t) = cos 2t
    let err = (ig.x()[0] - (20.0f64).cos())
        .abs()
        .max((ig.x()[1] + 2.0 * (20.0f64).sin()).abs());
    (err, ig)
}

#[test]
fn oscillator_error_follows_the_accuracy() {
    let (e5, ig5) = run(1e-5);
    let (e9, ig9) = run(1e-9);
    assert!(e5 < 1e-3, "{e5}");
    assert!(e9 < 1e-7, "{e9}");
    assert!(ig9.stats.steps > ig5.stats.steps);
    assert_eq!(ig9.t(), 10.0);
    // FSAL: 6 new evaluations per attempted step, plus the first.
    assert_eq!(
        ig9.stats.f_evals,
        1 + 6 * (ig9.stats.steps + ig9.stats.rejected_steps)
    );
}

#[test]
fn dense_output_is_accurate_inside_a_step() {
    let (_, ig) = run(1e-10);
    let mid = 0.5 * (ig.t_prev() + ig.t());
    let mut x = [0.0; 2];
    ig.dense(mid, &mut x);
    assert!((x[0] - (2.0 * mid).cos()).abs() < 1e-6);
}

struct Failing;
impl OdeSystem for Failing {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, _x: &[f64], dx: &mut [f64]) -> Result<(), String> {
        if t > 0.5 {
            return Err("muscle fibre length went negative".into());
        }
        dx[0] = 1.0;
        Ok(())
    }
}

#[test]
fn rhs_errors_report_time_and_reason() {
    let mut sys = Failing;
    let mut ig = Dopri5::new(&mut sys, 0.0, &[0.0], Dopri5Options::default()).unwrap();
    let e = loop {
        match ig.step(&mut sys, 1.0) {
            Ok(_) => continue,
            Err(e) => break e,
        }
    };
    assert!(matches!(e, IntegrationError::Rhs { t, .. } if t > 0.5));
    assert!(e.to_string().contains("fibre length"));
}

/// ẋ = 1 below x = 1/2 and 10⁴ above: a jump of the right-hand side, as a
/// knee spline's end or a path point switching makes.
struct Jump;
impl OdeSystem for Jump {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), String> {
        dx[0] = if x[0] < 0.5 { 1.0 } else { 1e4 };
        Ok(())
    }
}

/// A jump of the right-hand side whose local error h·Δf stays above the
/// accuracy at the minimum step is crossed by a step of the minimum size,
/// accepted and counted, as Simbody does (x(t) = 1/2 + 10⁴(t − 1/2) after
/// t = 1/2: the crossing costs at most h_min·Δf = 1e-4); with a minimum
/// step small enough to resolve it, no step exceeds the accuracy and the
/// crossing is closer (measured: 1.3e-8 against 1.7e-5).
#[test]
fn a_jump_of_the_rhs_is_crossed_at_the_minimum_step() {
    let run = |min_step: f64| {
        let opts = Dopri5Options {
            accuracy: 1e-10,
            min_step,
            max_steps: 1_000_000,
            ..Default::default()
        };
        let mut ig = Dopri5::new(&mut Jump, 0.0, &[0.0], opts).unwrap();
        while ig.t() < 0.5001 {
            ig.step(&mut Jump, 0.5001).unwrap();
        }
        ((ig.x()[0] - 1.5).abs(), ig.stats)
    };
    let (forced, stats) = run(1e-8);
    assert!(stats.steps_over_tolerance >= 1, "{stats:?}");
    assert!(forced <= 1e-4, "{forced}");
    let (resolved, stats) = run(1e-16);
    assert_eq!(stats.steps_over_tolerance, 0, "{stats:?}");
    assert!(resolved < forced, "{resolved} against {forced}");
}

/// ẋ = 1 until x = 1/2, then NaN: the integration stops with the state not
/// finite, past x = 1/2, and does not take the NaN as a step.
struct GoesNan;
impl OdeSystem for GoesNan {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), String> {
        dx[0] = if x[0] < 0.5 { 1.0 } else { f64::NAN };
        Ok(())
    }
}

#[test]
fn a_nan_derivative_stops_the_integration_and_bad_settings_are_refused() {
    let mut ig = Dopri5::new(&mut GoesNan, 0.0, &[0.0], Dopri5Options::default()).unwrap();
    let e = loop {
        match ig.step(&mut GoesNan, 1.0) {
            Ok(_) => assert!(ig.x()[0].is_finite() && ig.f()[0].is_finite()),
            Err(e) => break e,
        }
    };
    assert!(
        matches!(e, IntegrationError::NotFinite { t } if t >= 0.5),
        "{e}"
    );
    for (min_step, max_step, accuracy) in [
        (1e-3, 1e-4, 1e-5),
        (0.0, 1.0, 1e-5),
        (1e-8, f64::INFINITY, 1e-5),
        (1e-8, 1.0, 0.0),
        (1e-8, 1.0, f64::NAN),
    ] {
        let opts = Dopri5Options {
            min_step,
            max_step,
            accuracy,
            ..Default::default()
        };
        let r = Dopri5::new(&mut Jump, 0.0, &[0.0], opts);
        assert!(
            matches!(r, Err(IntegrationError::Options(_))),
            "{min_step} {max_step} {accuracy}"
        );
    }
}
