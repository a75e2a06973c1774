//! Rust force elements inside Simbody: muscle-path forces applied through the
//! callback equal the Rust-native ones, auxiliary states integrate, and Rust
//! errors and panics come back as errors with their message.

use leap::model::Model;
use leap::multibody::{GeneralizedForces, ModelView, Multibody};
use leap::path::PathSmoothing;
use leap::simbody::{
    simbody_q_order, ForceBuffer, SimbodyIntegrator, SimbodyKinematics, SimbodyModel,
};

#[test]
fn path_forces_through_the_callback_match_rust_native() {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    for symmetric in [false, true] {
        let sys = model.system(symmetric).unwrap();
        let perm = simbody_q_order(&sys);
        let q_index: Vec<usize> = sys.q_of_model_coordinate.iter().map(|&k| perm[k]).collect();
        let mobod: Vec<i32> = sys.system_body_of.iter().map(|&s| s as i32 + 1).collect();
        let tensions: Vec<f64> = (0..model.muscles.len())
            .map(|i| 100.0 + 37.0 * i as f64)
            .collect();
        let m2 = model.clone();
        let (t2, q2, mb2) = (tensions.clone(), q_index.clone(), mobod.clone());
        let mut buf = ForceBuffer::default();
        let f: Box<leap::simbody::ForceFn> = Box::new(move |ctx, _t, q, u, _z, _zdot| {
            buf.clear();
            {
                let kin = SimbodyKinematics {
                    ctx,
                    mobod: &mb2,
                    q_index: &q2,
                    q,
                    u,
                    error: Default::default(),
                };
                for (m, t) in m2.muscles.iter().zip(&t2) {
                    m.path.calc(
                        &kin,
                        PathSmoothing::Smooth { delta: 0.02 },
                        Some((*t, &mut buf)),
                    );
                }
                if let Some(e) = kin.error.into_inner() {
                    return Err(e);
                }
            }
            buf.flush(ctx, &mb2, &q2)
        });
        let mut sb = SimbodyModel::with_force(&model, &sys, Some((f, 0))).unwrap();
        let mb = Multibody::new(&model, &sys);
        let mut ws = mb.workspace::<f64>();
        let n = sys.nq();
        for k in 0..5 {
            let mut mq = model.poses["squat"].clone();
            for (i, v) in mq.iter_mut().enumerate() {
                *v += 0.1 * ((k * 7 + i) as f64).sin();
            }
            let q = sys.q_from_model(&mq);
            let u: Vec<f64> = (0..n).map(|i| ((k + i) as f64).cos()).collect();
            sb.set_state(0.0, &q, &u).unwrap();
            sb.set_applied_forces(&vec![0.0; n], &[]).unwrap();
            let mut qdd_s = vec![0.0; n];
            sb.accelerations(&mut qdd_s).unwrap();
            mb.set_state(&mut ws, &q, &u);
            let mut tau = vec![0.0; n];
            {
                let view = ModelView {
                    mb: &mb,
                    ws: &ws,
                    q_of: &sys.q_of_model_coordinate,
                };
                let mut sink = GeneralizedForces {
                    mb: &mb,
                    ws: &ws,
                    q_of: &sys.q_of_model_coordinate,
                    tau: &mut tau,
                };
                for (m, t) in model.muscles.iter().zip(&tensions) {
                    m.path.calc(
                        &view,
                        PathSmoothing::Smooth { delta: 0.02 },
                        Some((*t, &mut sink)),
                    );
                }
            }
            let mut qdd_r = vec![0.0; n];
            mb.forward_dynamics(&mut ws, &tau, &mut qdd_r).unwrap();
            let scale = qdd_s.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            for (a, b) in qdd_r.iter().zip(&qdd_s) {
                assert!(
                    (a - b).abs() <= 1e-10 * scale,
                    "symmetric={symmetric}: {a} vs {b}"
                );
            }
        }
        assert!(sb.force_calls() >= 5);
    }
}

#[test]
fn auxiliary_states_integrate_with_the_multibody_state() {
    // z' = −z/τ on 3 states: z(t) = z0·exp(−t/τ).
    let model = Model::from_file("models/double_pendulum.json").unwrap();
    let sys = model.system(false).unwrap();
    let f: Box<leap::simbody::ForceFn> = Box::new(|_ctx, _t, _q, _u, z, zdot| {
        for (d, v) in zdot.iter_mut().zip(z) {
            *d = -v / 0.04;
        }
        Ok(())
    });
    let mut sb = SimbodyModel::with_force(&model, &sys, Some((f, 3))).unwrap();
    sb.set_state(0.0, &[0.5, 0.0], &[0.0, 0.0]).unwrap();
    sb.set_z(&[1.0, 0.5, -2.0]).unwrap();
    sb.set_applied_forces(&[0.0, 0.0], &[]).unwrap();
    let mut zd = [0.0; 3];
    sb.zdot(&mut zd).unwrap();
    assert!((zd[0] + 25.0).abs() < 1e-12);
    sb.integrate(SimbodyIntegrator::RungeKuttaMerson, 1e-10, 0.1)
        .unwrap();
    let mut z = [0.0; 3];
    sb.z(&mut z).unwrap();
    let decay = (-0.1f64 / 0.04).exp();
    for (got, z0) in z.iter().zip([1.0, 0.5, -2.0]) {
        assert!((got - z0 * decay).abs() < 1e-8, "{got} vs {}", z0 * decay);
    }
}

#[test]
fn callback_errors_and_panics_become_errors() {
    let model = Model::from_file("models/double_pendulum.json").unwrap();
    let sys = model.system(false).unwrap();
    let f: Box<leap::simbody::ForceFn> = Box::new(|_ctx, t, _q, _u, _z, _zdot| {
        if t > 0.05 {
            return Err("contact model diverged".into());
        }
        Ok(())
    });
    let mut sb = SimbodyModel::with_force(&model, &sys, Some((f, 0))).unwrap();
    sb.set_state(0.0, &[0.5, 0.0], &[0.0, 0.0]).unwrap();
    sb.set_applied_forces(&[0.0, 0.0], &[]).unwrap();
    let e = sb
        .integrate(SimbodyIntegrator::RungeKuttaMerson, 1e-6, 0.2)
        .unwrap_err()
        .to_string();
    // Said once, with the time of the failing call. Here Simbody's own
    // reason is that its step collapsed at 0.05 s after the force element's
    // failures: both are given.
    assert_eq!(e.matches("contact model diverged").count(), 1, "{e}");
    assert!(e.contains("Unable to advance time past 0.05"), "{e}");
    let t: f64 = e
        .split_once("forces in this call, at t = ")
        .and_then(|(_, r)| r.split(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no time in {e}"));
    assert!((0.05..0.2).contains(&t), "{e}");
    // The model stays usable.
    sb.set_state(0.0, &[0.5, 0.0], &[0.0, 0.0]).unwrap();
    let mut qdd = [0.0; 2];
    sb.accelerations(&mut qdd).unwrap();

    let g: Box<leap::simbody::ForceFn> =
        Box::new(|_ctx, _t, _q, _u, _z, _zdot| panic!("index out of bounds in a muscle"));
    let mut sb = SimbodyModel::with_force(&model, &sys, Some((g, 0))).unwrap();
    sb.set_state(0.0, &[0.5, 0.0], &[0.0, 0.0]).unwrap();
    let e = sb.accelerations(&mut qdd).unwrap_err().to_string();
    assert!(
        e.contains("panic in Rust force element") && e.contains("index out of bounds in a muscle"),
        "{e}"
    );
}

#[test]
fn a_persistent_integration_stops_at_its_step_cap_with_an_error() {
    // A stiff decay z' = −z/τ, τ = 1e-6 s, at accuracy 1e-8 needs far more
    // than 50 steps to 0.1 s: the integration must stop there, with an
    // error, and stay usable; without a cap it runs to the end.
    let model = Model::from_file("models/double_pendulum.json").unwrap();
    let sys = model.system(false).unwrap();
    let f: Box<leap::simbody::ForceFn> = Box::new(|_ctx, _t, _q, _u, z, zdot| {
        zdot[0] = -z[0] / 1e-6;
        Ok(())
    });
    let mut sb = SimbodyModel::with_force(&model, &sys, Some((f, 1))).unwrap();
    for cap in [50, 0] {
        sb.set_state(0.0, &[0.5, 0.0], &[0.0, 0.0]).unwrap();
        sb.set_z(&[1.0]).unwrap();
        sb.set_applied_forces(&[0.0, 0.0], &[]).unwrap();
        sb.integration_start(SimbodyIntegrator::RungeKuttaMerson, 1e-8, 1e-12, 1.0, cap)
            .unwrap();
        let (mut steps, mut failed_at) = (0, None);
        for k in 1..=10 {
            match sb.integration_step_to(0.01 * k as f64) {
                Ok(s) => steps = s.steps_attempted,
                Err(e) => {
                    failed_at = Some((k, e.to_string()));
                    break;
                }
            }
        }
        if cap > 0 {
            // The cap is reached within the first report interval.
            let (k, e) = failed_at.expect("the capped integration went on");
            assert_eq!(k, 1, "{e}");
            assert!(e.contains("step limit of 50 integrator steps"), "{e}");
        } else {
            assert!(failed_at.is_none(), "{failed_at:?}");
            assert!(steps > 50, "{steps}");
        }
    }
}

/// An accuracy of 1 or more, which Simbody's error-controlled integrators
/// assert against (aborting the process), is an error of the bridge; for
/// explicit Euler, which takes it as its fixed step, it is a step.
#[test]
fn an_accuracy_of_one_or_more_is_an_error_not_an_abort() {
    let model = Model::from_file("models/double_pendulum.json").unwrap();
    let sys = model.system(false).unwrap();
    let mut sb = SimbodyModel::with_force(&model, &sys, None).unwrap();
    sb.set_state(0.0, &[0.5, 0.0], &[0.0, 0.0]).unwrap();
    sb.set_applied_forces(&[0.0, 0.0], &[]).unwrap();
    for accuracy in [1.0, 2.5, f64::INFINITY, 0.0, f64::NAN] {
        let e = sb
            .integration_start(SimbodyIntegrator::RungeKuttaMerson, accuracy, 1e-12, 1.0, 0)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("integrator: accuracy must be"),
            "{accuracy}: {e}"
        );
    }
    sb.integration_start(SimbodyIntegrator::ExplicitEuler, 1.5, 1e-12, 1.0, 0)
        .unwrap();
}
