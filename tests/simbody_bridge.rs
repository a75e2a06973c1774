//! The Simbody bridge: C++ and Simbody exceptions become `Err`, bad input is
//! refused before it reaches Simbody, and the Rust-native dynamics agree with
//! Simbody to 1e-10 (the cross-check).

use leap::crosscheck;
use leap::model::Model;
use leap::simbody::{SimbodyError, SimbodyModel};

fn pendulum() -> (Model, SimbodyModel) {
    let m = Model::from_file("models/double_pendulum.json").unwrap();
    let sys = m.system(false).unwrap();
    let sb = SimbodyModel::new(&m, &sys).unwrap();
    (m, sb)
}

#[test]
fn exceptions_become_errors_and_the_model_stays_usable() {
    let (_, mut sb) = pendulum();
    for kind in 0..3 {
        let e = sb.throw_for_test(kind).unwrap_err();
        let SimbodyError::Simbody(msg) = &e else {
            panic!("{e:?}")
        };
        match kind {
            0 => assert!(msg.contains("stage"), "{msg}"),
            1 => assert!(msg.contains("thrown on purpose"), "{msg}"),
            _ => assert!(msg.contains("std::runtime_error"), "{msg}"),
        }
    }
    sb.set_state(0.0, &[0.3, -0.2], &[0.0, 0.0]).unwrap();
    let mut qdd = [0.0; 2];
    sb.set_applied_forces(&[0.0, 0.0], &[]).unwrap();
    sb.accelerations(&mut qdd).unwrap();
    assert!(qdd.iter().all(|a| a.is_finite()));
}

#[test]
fn wrong_lengths_and_bodies_are_refused() {
    let (_, mut sb) = pendulum();
    assert!(matches!(
        sb.set_state(0.0, &[0.1], &[0.0, 0.0]),
        Err(SimbodyError::Input(_))
    ));
    let mut m = vec![0.0; 3];
    assert!(sb.mass_matrix(&mut m).is_err());
    assert!(sb.station_position(7, [0.0; 3]).is_err());
    assert!(sb
        .set_applied_forces(&[0.0, 0.0], &[(9, [0.0; 3], [1.0, 0.0, 0.0])])
        .is_err());
}

#[test]
fn rust_native_dynamics_match_simbody_on_the_jumper() {
    let m = Model::from_file("models/jumper_gait2392.json").unwrap();
    let report = crosscheck::run(&m, 40, 7).unwrap();
    assert_eq!(
        report.comparisons.len(),
        5,
        "full, symmetric, symmetric-vs-full and state-equation comparisons"
    );
    assert!(
        report.max_rel_error <= crosscheck::TOLERANCE,
        "{}",
        report.table()
    );
    // ẋ = f(x, u) with muscles, contact and passive torques: Rust-native
    // against the same laws evaluated from Simbody's kinematics in Simbody.
    let f_err = report
        .state_equation_max_rel_error
        .expect("the jumper has force elements");
    assert!(
        f_err <= crosscheck::STATE_EQUATION_TOLERANCE,
        "{}",
        report.table()
    );
}

#[test]
fn rust_native_dynamics_match_simbody_on_the_double_pendulum() {
    let m = Model::from_file("models/double_pendulum.json").unwrap();
    let report = crosscheck::run(&m, 40, 3).unwrap();
    assert!(
        report.max_rel_error <= crosscheck::TOLERANCE,
        "{}",
        report.table()
    );
}

#[test]
fn simbody_total_mass_equals_the_model_file() {
    let m = Model::from_file("models/jumper_gait2392.json").unwrap();
    for symmetric in [false, true] {
        let sys = m.system(symmetric).unwrap();
        let mut sb = SimbodyModel::new(&m, &sys).unwrap();
        assert!((sb.total_mass().unwrap() - m.total_mass()).abs() < 1e-12);
    }
}
