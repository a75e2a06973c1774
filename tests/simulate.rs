//! The forward-simulation pipeline (integration, lift-off, apex, output
//! files) with simple closed-form laws; the OpenSim laws have their own tests.

use crate::common::TestLaws;
use leap::io::StoTable;
use leap::ode::StateEquation;
use leap::path::PathSmoothing;
use leap::simulate::{
    extensor_moments, simulate_rust, write_trajectory, BangBang, SimulateOptions,
};

#[test]
fn bang_bang_jump_leaves_the_ground_and_reaches_its_apex() {
    let model = leap::model::Model::from_file("models/jumper_gait2392.json").unwrap();
    let eq = StateEquation::new(&model, true, PathSmoothing::Smooth { delta: 0.02 }).unwrap();
    let laws = TestLaws(model.clone());
    let squat = model.poses["squat"].clone();
    let ext = extensor_moments(&eq, &squat);
    let names: Vec<&str> = eq
        .muscles
        .iter()
        .map(|&m| model.muscles[m].spec.name.as_str())
        .collect();
    // Anatomy check of the classification at the squat.
    for (name, want) in [
        ("vas_int_r", true),
        ("soleus_r", true),
        ("glut_max2_r", true),
        ("tib_ant_r", false),
        ("iliacus_r", false),
    ] {
        let k = names.iter().position(|n| *n == name).unwrap();
        assert_eq!(ext[k] > 0.0, want, "{name}: {}", ext[k]);
    }
    let exc = BangBang {
        intervals: ext
            .iter()
            .map(|&e| if e > 0.0 { Some((0.0, 10.0)) } else { None })
            .collect(),
        off_level: 0.01,
    };
    let (n, nm) = (eq.nq(), eq.nm());
    let mut x0 = vec![0.0; eq.nx()];
    x0[..n].copy_from_slice(&eq.system.q_from_model(&squat));
    x0[eq.system.q_of_model_coordinate[model.coordinate_index("pelvis_ty").unwrap()]] -= 0.002;
    for m in 0..nm {
        x0[2 * n + m] = 0.1;
        x0[2 * n + nm + m] = 0.01;
    }
    let standing = {
        let mut w = eq.multibody.workspace::<f64>();
        let q = eq.system.q_from_model(&model.poses["standing"]);
        eq.multibody.set_state(&mut w, &q, &vec![0.0; n]);
        eq.multibody.com_position(&w)[1]
    };
    let opts = SimulateOptions {
        t_max: 1.5,
        ..Default::default()
    };
    let (s, traj) = simulate_rust(&eq, &laws, &exc, &x0, standing, opts).unwrap();
    let lt = s.liftoff_time_s.expect("lifts off");
    assert!(s.liftoff_com_velocity_mps.unwrap() > 0.0);
    // After lift-off no ground force; before, some.
    for (t, g) in traj.time.iter().zip(&traj.grf) {
        if *t > lt + 1e-9 {
            assert!(g[1] + g[7] <= 0.0, "ground force in flight at t = {t}");
        }
    }
    // The apex is the ballistic rise from lift-off.
    let g = 9.80665;
    let v = s.liftoff_com_velocity_mps.unwrap();
    let ballistic = s.liftoff_com_height_m.unwrap() + v * v / (2.0 * g);
    assert!(
        (s.apex_com_height_m - ballistic).abs() < 2e-3,
        "{} vs {}",
        s.apex_com_height_m,
        ballistic
    );
    assert!(s.steps > 10 && s.f_evals >= 6 * s.steps);
    // Files load back with OpenSim's names.
    let dir = std::env::temp_dir().join(format!("leap-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let paths = write_trajectory(&eq, &traj, &dir, "jump").unwrap();
    let states = StoTable::read(&paths[0]).unwrap();
    assert!(states
        .labels
        .contains(&"/jointset/hip_r/hip_flexion_r/value".to_string()));
    assert!(states
        .labels
        .contains(&"/forceset/soleus_r/activation".to_string()));
    let grf = StoTable::read(&paths[2]).unwrap();
    assert_eq!(grf.labels[1], "ground_force_r_vy");
    assert_eq!(grf.time.len(), traj.time.len());
    std::fs::remove_dir_all(&dir).ok();
}
