//! The static squat holds: q̈ ≈ 0, the spheres carry body weight, and 0.2 s
//! of forward simulation with its excitations moves the pelvis < 1 mm, in
//! both backends.

use crate::common::FixedExcitation;
use leap::integrator::{Dopri5, Dopri5Options};
use leap::laws::OpenSimLaws;
use leap::model::Model;
use leap::ode::{Excitation, SimbodyStateEquation, StateEquation};
use leap::path::PathSmoothing;
use leap::simbody::SimbodyIntegrator;
use leap::squat::static_squat;
use std::sync::Arc;

fn pelvis_shift(eq: &StateEquation, x0: &[f64], x1: &[f64]) -> f64 {
    let m = &eq.model;
    let tx = eq.system.q_of_model_coordinate[m.coordinate_index("pelvis_tx").unwrap()];
    let ty = eq.system.q_of_model_coordinate[m.coordinate_index("pelvis_ty").unwrap()];
    ((x1[tx] - x0[tx]).powi(2) + (x1[ty] - x0[ty]).powi(2)).sqrt()
}

#[test]
fn static_squat_holds_in_both_backends() {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    let eq = StateEquation::new(&model, true, PathSmoothing::Smooth { delta: 0.02 }).unwrap();
    let laws = OpenSimLaws::new(&model).unwrap();
    let sq = static_squat(&eq, &laws, &model.poses["squat"]).unwrap();
    assert!(sq.max_abs_qdd <= 1e-6, "q̈ = {}", sq.max_abs_qdd);
    assert!(
        (sq.vertical_grf_bw - 1.0).abs() < 1e-6,
        "GRF {} BW",
        sq.vertical_grf_bw
    );
    assert!(sq.excitation.iter().all(|&a| (0.01..=1.0).contains(&a)));
    // Fibres in equilibrium and activations steady: the muscle states do not move.
    let mut w = eq.workspace::<f64>();
    let mut dx = vec![0.0; eq.nx()];
    eq.rhs(&laws, &mut w, &sq.x, &sq.excitation, &mut dx)
        .unwrap();
    let n = eq.nq();
    assert!(
        dx[2 * n..].iter().all(|v| v.abs() < 1e-8),
        "muscle state rates {:?}",
        &dx[2 * n..]
    );

    // Rust-native, Dormand-Prince at 1e-6.
    let mut sys = FixedExcitation {
        eq: &eq,
        laws: &laws,
        ws: eq.workspace(),
        u: sq.excitation.clone(),
    };
    let mut ig = Dopri5::new(
        &mut sys,
        0.0,
        &sq.x,
        Dopri5Options {
            accuracy: 1e-6,
            ..Default::default()
        },
    )
    .unwrap();
    while ig.t() < 0.2 {
        ig.step(&mut sys, 0.2).unwrap();
    }
    let shift = pelvis_shift(&eq, &sq.x, ig.x());
    eprintln!(
        "static squat: max |q̈| {:.2e}, Rust-native pelvis shift after 0.2 s {shift:.3e} m",
        sq.max_abs_qdd
    );
    assert!(shift < 1e-3, "Rust-native: pelvis moved {shift} m in 0.2 s");

    // Simbody, RungeKuttaMerson at OpenSim's default accuracy 1e-5.
    let eqa = Arc::new(eq.clone());
    let mut sb = SimbodyStateEquation::new(eqa.clone(), Arc::new(laws.clone())).unwrap();
    sb.set_excitation(Excitation::Constant(sq.excitation.clone()));
    sb.set_state(0.0, &sq.x).unwrap();
    sb.simbody.set_applied_forces(&vec![0.0; n], &[]).unwrap();
    sb.simbody
        .integrate(SimbodyIntegrator::RungeKuttaMerson, 1e-5, 0.2)
        .unwrap();
    let mut x1 = vec![0.0; eq.nx()];
    sb.state(&mut x1).unwrap();
    let shift = pelvis_shift(&eq, &sq.x, &x1);
    eprintln!("Simbody pelvis shift after 0.2 s {shift:.3e} m");
    assert!(shift < 1e-3, "Simbody: pelvis moved {shift} m in 0.2 s");
}

/// A squat that cannot stand is named by the file and the pose it came
/// from: the feet lifted off the ground (every contact sphere raised by
/// 0.5 m, the standing pose lowered with them) leave no pelvis height and ankle angle that balance the body; a
/// pose not among the model's is called "the given pose".
#[test]
fn a_squat_that_cannot_stand_names_file_and_pose() {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap();
    for s in v["forces"]["contact"]["spheres"].as_array_mut().unwrap() {
        let y = s["location"][1].as_f64().unwrap();
        s["location"][1] = (y + 0.5).into();
    }
    // The standing pose follows the feet (the state equation checks it).
    let ty = v["poses"]["standing"]["pelvis_ty"].as_f64().unwrap();
    v["poses"]["standing"]["pelvis_ty"] = (ty - 0.5).into();
    let model = Model::from_json_str(&v.to_string(), "raised.json").unwrap();
    let eq = StateEquation::new(&model, true, PathSmoothing::Smooth { delta: 0.02 }).unwrap();
    let laws = OpenSimLaws::new(&model).unwrap();
    let e = static_squat(&eq, &laws, &model.poses["squat"])
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("raised.json: poses.squat: static squat: "),
        "{e}"
    );
    let mut other = model.poses["squat"].clone();
    other[0] += 1e-3;
    let e = static_squat(&eq, &laws, &other).unwrap_err().to_string();
    assert!(
        e.starts_with("raised.json: the given pose: static squat: "),
        "{e}"
    );
}
