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

fn study_error(json: &str) -> String {
    let st = leap::simulate::SimulateStudy::from_json_str(json, "sim.json").unwrap();
    st.check("sim.json").unwrap_err().to_string()
}

/// Settings that would abort (Simbody asserts accuracy < 1), never end or
/// make no sense are refused naming the study and the field.
#[test]
fn simulate_study_values_are_checked() {
    for (json, want) in [
        (r#"{"accuracy": 1}"#, "sim.json: accuracy: must be a relative error tolerance in [1e-12, 1e-2], got 1"),
        (r#"{"accuracy": 10}"#, "sim.json: accuracy: must be a relative error tolerance in [1e-12, 1e-2], got 10"),
        (r#"{"accuracy": 1e-300}"#, "sim.json: accuracy: must be a relative error tolerance in [1e-12, 1e-2]"),
        (r#"{"accuracy": 0}"#, "sim.json: accuracy: must be positive, got 0"),
        (r#"{"integrator": "DormandPrince", "accuracy": 2}"#, "sim.json: accuracy: must be a relative error tolerance"),
        (r#"{"integrator": "ExplicitEuler", "accuracy": 1e-12}"#, "sim.json: accuracy: ExplicitEuler's fixed step must be at least 1e-6 s"),
        (r#"{"integrator": "ExplicitEuler", "accuracy": 1.01e-4}"#, "sim.json: accuracy: ExplicitEuler's fixed step must be at most 1e-4 s, got 0.000101"),
        (r#"{"integrator": "ExplicitEuler", "accuracy": 100}"#, "sim.json: accuracy: ExplicitEuler's fixed step must be at most 1e-4 s, got 100"),
        (r#"{"integrator": "ExplicitEuler", "accuracy": 2e-6, "t_max": 10}"#, "sim.json: accuracy: ExplicitEuler's fixed step of 2e-6 s takes 5.0e6 steps to t_max = 10 s; at most 1e6"),
        (r#"{"report_interval": 1e-9}"#, "sim.json: report_interval: 1e-9 s over t_max = 1 s would report 1.0e9 rows; at most 1e5"),
        (r#"{"report_interval": 0}"#, "sim.json: report_interval: must be positive, got 0"),
        (r#"{"t_max": -1}"#, "sim.json: t_max: must be a time in (0, 10] s (a jump lifts off and reaches its apex within about a second), got -1"),
        (r#"{"t_max": 1e300}"#, "sim.json: t_max: must be a time in (0, 10] s"),
        (r#"{"integrator": "Verlet"}"#, "sim.json: integrator: unknown integrator 'Verlet'"),
        (r#"{"bang_bang": {"on_time": 0.3, "off_time": 0.1}}"#, "sim.json: bang_bang.off_time: must be after on_time (0.3 s), got 0.1"),
        (r#"{"bang_bang": {"on_time": 0.2, "off_time": 0.2}}"#, "sim.json: bang_bang.off_time: must be after on_time"),
        (r#"{"bang_bang": {"on_time": -0.1, "off_time": 0.3}}"#, "sim.json: bang_bang.on_time: must be a time ≥ 0 s"),
        (r#"{"bang_bang": {"on": []}}"#, "sim.json: bang_bang.on: is empty: no muscle would switch on"),
        // Empty paths: "out" had written into the study's own directory,
        // "model" and "controls" had named that directory, not the field.
        (r#"{"out": ""}"#, "sim.json: out: empty: name a directory"),
        (r#"{"model": " "}"#, "sim.json: model: empty: name a model file"),
        (r#"{"controls": ""}"#, "sim.json: controls: empty: name a controls file"),
    ] {
        let e = study_error(json);
        assert!(e.starts_with(want), "{json}: {e}");
    }
    let ok = leap::simulate::SimulateStudy::from_json_str(
        r#"{"integrator": "ExplicitEuler", "accuracy": 1e-4, "bang_bang": {"on_time": 0, "off_time": 0.3}}"#,
        "sim.json",
    )
    .unwrap();
    assert!(matches!(
        ok.check("sim.json").unwrap(),
        leap::simulate::IntegratorChoice::Simbody(leap::simbody::SimbodyIntegrator::ExplicitEuler)
    ));
}

#[test]
fn a_simulate_study_is_one_json_object() {
    for (text, reason) in [
        (
            r#"{"t_max": 1} garbage"#,
            "trailing characters at line 1 column 14",
        ),
        (
            r#"{"t_max": 1}{"t_max": 2}"#,
            "trailing characters at line 1 column 13",
        ),
        ("[]", "expected a JSON object, got an array"),
        (
            r#"["m.json", "RungeKutta3"]"#,
            "expected a JSON object, got an array",
        ),
    ] {
        let e = match leap::simulate::SimulateStudy::from_json_str(text, "sim.json") {
            Ok(_) => panic!("{text} was accepted"),
            Err(e) => e.to_string(),
        };
        assert_eq!(e, format!("sim.json: (document): {reason}"), "{text}");
    }
}

/// Called directly, the Simbody simulation refuses an accuracy Simbody
/// would abort on, and a report interval that would never end, as a
/// failure at t = 0 instead.
#[test]
fn simbody_simulation_refuses_what_would_abort_or_hang() {
    use std::sync::Arc;
    let model = leap::model::Model::from_file("models/jumper_reduced.json").unwrap();
    let laws = Arc::new(leap::laws::OpenSimLaws::new(&model).unwrap());
    let eq = Arc::new(StateEquation::new(&model, true, PathSmoothing::Exact).unwrap());
    let exc = BangBang {
        intervals: vec![None; eq.nm()],
        off_level: 0.01,
    };
    let x0 = vec![0.0; eq.nx()];
    let run = |accuracy: f64, report_interval: f64| {
        leap::simulate::simulate_simbody(
            &eq,
            &laws,
            &exc,
            &x0,
            1.0,
            leap::simbody::SimbodyIntegrator::RungeKuttaMerson,
            accuracy,
            1.0,
            report_interval,
        )
        .map(|_| ())
        .unwrap_err()
    };
    let f = run(1.0, 1e-3);
    assert_eq!(f.t, 0.0);
    assert!(
        f.cause
            .starts_with("accuracy: must be a relative error tolerance in [1e-12, 1e-2]"),
        "{}",
        f.cause
    );
    let f = run(1e-5, 1e-9);
    assert!(
        f.cause
            .starts_with("report_interval: 1e-9 s over t_max = 1 s"),
        "{}",
        f.cause
    );
}
