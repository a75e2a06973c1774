//! `leap analyze` against the laws of mechanics: with the feet in the air
//! the work of the muscles and passive joint torques must equal the change
//! of kinetic plus potential energy (the work-energy theorem), and over a
//! push-off the vertical ground impulse less the weight's must equal the
//! change of COM momentum (Newton's second law), on trajectories integrated
//! by the Rust-native Dormand-Prince with OpenSim's laws.

use crate::common::{assert_push_off_consistent, extensor_bang_bang, FixedExcitation};
use leap::analyze::analyze;
use leap::integrator::{Dopri5, Dopri5Options};
use leap::laws::OpenSimLaws;
use leap::ode::StateEquation;
use leap::path::PathSmoothing;
use leap::simulate::{simulate_rust, standing_com_height};

fn jumper() -> (leap::model::Model, StateEquation, OpenSimLaws, Vec<f64>) {
    let model = leap::model::Model::from_file("models/jumper_gait2392.json").unwrap();
    let eq = StateEquation::new(&model, true, PathSmoothing::Exact).unwrap();
    let laws = OpenSimLaws::new(&model).unwrap();
    let ocp = leap::ocp::JumpOcp::new(&model, Default::default()).unwrap();
    let x0 = ocp.x0().to_vec();
    (model, eq, laws, x0)
}

#[test]
fn muscle_and_passive_work_equal_the_energy_change_in_the_air() {
    let (model, eq, laws, mut x0) = jumper();
    // The squat lifted 0.6 m: 0.15 s of free fall and leg motion stay
    // clear of the ground.
    let ty = model.coordinate_index("pelvis_ty").unwrap();
    x0[eq.system.q_of_model_coordinate[ty]] += 0.6;
    let mut sys = FixedExcitation {
        eq: &eq,
        laws: &laws,
        ws: eq.workspace::<f64>(),
        u: vec![0.6; eq.nm()],
    };
    let opts = Dopri5Options {
        accuracy: 1e-9,
        ..Default::default()
    };
    let mut dp = Dopri5::new(&mut sys, 0.0, &x0, opts).unwrap();
    let (t_end, rows) = (0.15, 3000);
    let (mut time, mut states) = (vec![0.0], vec![x0.clone()]);
    let mut next = 1;
    while next <= rows {
        let t = dp.step(&mut sys, t_end).unwrap();
        while next <= rows && (next as f64) * t_end / rows as f64 <= t + 1e-15 {
            let tk = (next as f64) * t_end / rows as f64;
            let mut x = vec![0.0; eq.nx()];
            dp.dense(tk, &mut x);
            time.push(tk);
            states.push(x);
            next += 1;
        }
    }
    let a = analyze(&eq, &laws, &time, &states, Some((0.0, t_end))).unwrap();
    let b = &a.budget;
    assert!(
        a.peak_vertical_grf_bw == 0.0,
        "the feet touched the ground: {} BW",
        a.peak_vertical_grf_bw
    );
    let scale = b.muscle_work_j.abs() + b.passive_torque_work_j.abs();
    assert!(scale > 1.0, "too little work to test: {b:?}");
    assert!(
        b.contact_work_j.abs() <= 1e-3 * scale,
        "ΔE {} J against muscle {} J + passive {} J",
        b.energy_change_j,
        b.muscle_work_j,
        b.passive_torque_work_j
    );
    // In the air the only vertical force is the weight.
    let want = -model.total_mass() * model.gravity[1].abs() * t_end;
    assert!(
        (a.com_momentum_change_ns - want).abs() <= 1e-6 * want.abs(),
        "{} N·s, free fall {want} N·s",
        a.com_momentum_change_ns
    );
}

#[test]
fn push_off_impulse_equals_the_momentum_change_and_the_jump_matches_the_simulation() {
    let (model, eq, laws, x0) = jumper();
    let squat = model.poses["squat"].clone();
    let exc = extensor_bang_bang(&eq, &squat);
    let standing = standing_com_height(&eq);
    let opts = leap::simulate::SimulateOptions {
        t_max: 1.0,
        integrator: Dopri5Options {
            accuracy: 1e-7,
            max_step: 1e-3,
            ..Default::default()
        },
    };
    let (s, traj) = simulate_rust(&eq, &laws, &exc, &x0, standing, opts).unwrap();
    let a = analyze(&eq, &laws, &traj.time, &traj.states, None).unwrap();
    assert!(a.liftoff, "no lift-off found");
    let lt = s.liftoff_time_s.unwrap();
    assert!(
        (a.budget.end_s - lt).abs() <= 2e-3,
        "lift-off at {} s, the simulation's at {lt} s",
        a.budget.end_s
    );
    assert_push_off_consistent(&a, 2e-3, s.jump_height_m, "simulation");
    // The push-off is driven by the muscles: their net work is most of
    // the energy gained.
    let b = &a.budget;
    assert!(
        b.energy_change_j > 0.0 && b.muscle_work_j > b.energy_change_j * 0.8,
        "{b:?}"
    );
}
