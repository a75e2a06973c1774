//! Muscle paths of the jumper against model-data.md's length and moment-arm
//! check table, moment arms against finite differences of the length, and
//! the smooth switching option.
// 0.785398 below is where gait2392's conditional path points switch, as the
// model file writes it, not π/4.
#![allow(clippy::approx_constant)]

use leap::model::Model;
use leap::multibody::{GeneralizedForces, ModelView, Multibody};
use leap::path::PathSmoothing;
use leap::scalar::Dual64;

fn eval(
    model: &Model,
    model_q: &[f64],
    muscle: usize,
    smoothing: PathSmoothing,
) -> (f64, Vec<f64>) {
    let sys = model.system(false).unwrap();
    let mb = Multibody::new(model, &sys);
    let mut ws = mb.workspace::<f64>();
    let q = sys.q_from_model(model_q);
    mb.set_state(&mut ws, &q, &vec![0.0; q.len()]);
    let mut tau = vec![0.0; q.len()];
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
    let v = model.muscles[muscle]
        .path
        .calc(&view, smoothing, Some((1.0, &mut sink)));
    // Moment arms r = generalized force of a unit tension, per model coordinate.
    (v.length, sys.model_from_q(&tau))
}

#[test]
fn lengths_and_moment_arms_match_the_check_table() {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    let data: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string("tests/data/path_check_values.json").unwrap(),
    )
    .unwrap();
    let mut checked = 0;
    for (pose_name, pose) in data["poses"].as_object().unwrap() {
        let mut q: Vec<f64> = model.coordinates.iter().map(|c| c.default_value).collect();
        for (c, v) in pose.as_object().unwrap() {
            q[model.coordinate_index(c).unwrap()] = v.as_f64().unwrap();
        }
        for (name, rows) in data["muscles"].as_object().unwrap() {
            let m = model
                .muscles
                .iter()
                .position(|m| m.spec.name == *name)
                .unwrap();
            let (len, r) = eval(&model, &q, m, PathSmoothing::Exact);
            let row = &rows[pose_name];
            // Values are quoted to 4 decimals: half a unit of the last digit.
            let tol = 0.5e-4 + 1e-9;
            assert!(
                (len - row["length"].as_f64().unwrap()).abs() <= tol,
                "{name} {pose_name} length {len} vs {}",
                row["length"]
            );
            for (coord, key) in [
                ("hip_flexion_r", "hip"),
                ("knee_angle_r", "knee"),
                ("ankle_angle_r", "ankle"),
                ("lumbar_extension", "lumbar"),
            ] {
                let want = row[key].as_f64().unwrap();
                let got = r[model.coordinate_index(coord).unwrap()];
                assert!(
                    (got - want).abs() <= tol,
                    "{name} {pose_name} r_{key} = {got} vs {want}"
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 2 * 24 * 4);
}

/// r = −∂L/∂q: the applied-tension moment arms equal dual-number derivatives
/// of the length and central differences, in both switching modes.
#[test]
fn moment_arms_are_minus_length_derivatives() {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    let sys = model.system(false).unwrap();
    let mb = Multibody::new(&model, &sys);
    let mut qm: Vec<f64> = model.poses["squat"].clone();
    // Near the rect_fem and vas_int switches, inside the smooth blend.
    qm[model.coordinate_index("knee_angle_r").unwrap()] = -1.43;
    for smoothing in [PathSmoothing::Exact, PathSmoothing::Smooth { delta: 0.02 }] {
        for (mi, m) in model
            .muscles
            .iter()
            .enumerate()
            .filter(|(_, m)| m.spec.name.ends_with("_r"))
        {
            let (_, r) = eval(&model, &qm, mi, smoothing);
            let q = sys.q_from_model(&qm);
            for k in 0..q.len() {
                let mut ws = mb.workspace::<Dual64>();
                let qd: Vec<Dual64> = q
                    .iter()
                    .enumerate()
                    .map(|(i, &x)| {
                        if i == k {
                            Dual64::from_re(x).derivative()
                        } else {
                            Dual64::from_re(x)
                        }
                    })
                    .collect();
                mb.set_state(&mut ws, &qd, &vec![Dual64::from_re(0.0); q.len()]);
                let view = ModelView {
                    mb: &mb,
                    ws: &ws,
                    q_of: &sys.q_of_model_coordinate,
                };
                let v = m
                    .path
                    .calc::<_, _, GeneralizedForces<Dual64>>(&view, smoothing, None);
                let c = sys.coordinates[k];
                let dl = v.length.eps;
                assert!(
                    (r[c] + dl).abs() < 1e-12,
                    "{} d/d{}: r {} vs -dL/dq {}",
                    m.spec.name,
                    model.coordinates[c].name,
                    r[c],
                    -dl
                );
            }
        }
    }
}

/// The lengthening speed is dL/dt = Σ ∂L/∂q q̇.
#[test]
fn lengthening_speed_is_the_time_derivative_of_length() {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    let sys = model.system(true).unwrap();
    let mb = Multibody::new(&model, &sys);
    let q0 = sys.q_from_model(&model.poses["squat"]);
    let u: Vec<f64> = (0..q0.len()).map(|i| 0.7 * (i as f64 - 2.5)).collect();
    let smoothing = PathSmoothing::Smooth { delta: 0.02 };
    let length_at = |t: f64| -> Vec<f64> {
        let q: Vec<f64> = q0.iter().zip(&u).map(|(q, u)| q + t * u).collect();
        let mut ws = mb.workspace::<f64>();
        mb.set_state(&mut ws, &q, &u);
        let view = ModelView {
            mb: &mb,
            ws: &ws,
            q_of: &sys.q_of_model_coordinate,
        };
        model
            .muscles
            .iter()
            .map(|m| {
                m.path
                    .calc::<_, _, GeneralizedForces<f64>>(&view, smoothing, None)
                    .length
            })
            .collect()
    };
    let mut ws = mb.workspace::<f64>();
    mb.set_state(&mut ws, &q0, &u);
    let view = ModelView {
        mb: &mb,
        ws: &ws,
        q_of: &sys.q_of_model_coordinate,
    };
    let h = 1e-6;
    let (lp, lm) = (length_at(h), length_at(-h));
    for (i, m) in model.muscles.iter().enumerate() {
        let v = m
            .path
            .calc::<_, _, GeneralizedForces<f64>>(&view, smoothing, None);
        let fd = (lp[i] - lm[i]) / (2.0 * h);
        assert!(
            (v.lengthening_speed - fd).abs() < 1e-7,
            "{}: {} vs {}",
            m.spec.name,
            v.lengthening_speed,
            fd
        );
    }
}

/// The length jumps of the exact paths at conditional-point switches, with
/// the other coordinates at 0, against model-data.md §10's list (computed
/// independently by the reference author, quoted to 0.01 mm or better).
#[test]
fn switch_jumps_match_model_data() {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    let eq = leap::ode::StateEquation::new(&model, true, PathSmoothing::Exact).unwrap();
    let mut pose: Vec<f64> = vec![0.0; model.coordinates.len()];
    pose[model.coordinate_index("pelvis_ty").unwrap()] = 0.94387;
    let jumps = leap::eval::switch_jumps(&eq, &pose);
    let find = |m: &str, at: f64| {
        jumps
            .iter()
            .find(|j| j.muscle == m && (j.at - at).abs() < 1e-9)
            .unwrap()
            .jump_m
            .abs()
            * 1e3
    };
    for (m, at, mm, tol) in [
        ("iliacus_r", 0.785398, 0.56, 0.005),
        ("psoas_r", 0.785398, 0.011, 0.0005),
        ("med_gas_r", -0.785398, 0.36, 0.005),
        ("lat_gas_r", -0.785398, 0.03, 0.005),
        ("vas_med_r", -1.78006, 0.023, 0.0005),
        ("iliacus_r", -1.5708, 22.7, 0.05),
        ("med_gas_r", 0.174533, 6.7, 0.05),
    ] {
        let got = find(m, at);
        assert!((got - mm).abs() <= tol, "{m} at {at}: {got} mm vs {mm} mm");
    }
    // Each switch names its conditional path point as the model's .osim
    // does (gait2392's names).
    let osim = std::fs::read_to_string("models/jumper_gait2392.osim").unwrap();
    for j in &jumps {
        assert!(
            osim.contains(&format!("<ConditionalPathPoint name=\"{}\">", j.path_point)),
            "{j:?}"
        );
    }
    // The smooth option has no jump: its length is continuous across a switch.
    let sys = model.system(true).unwrap();
    let mb = Multibody::new(&model, &sys);
    let ili = model
        .muscles
        .iter()
        .position(|m| m.spec.name == "iliacus_r")
        .unwrap();
    let length = |hip: f64, sm: PathSmoothing| {
        let mut q = pose.clone();
        q[model.coordinate_index("hip_flexion_r").unwrap()] = hip;
        let mut ws = mb.workspace::<f64>();
        mb.set_state(&mut ws, &sys.q_from_model(&q), &[0.0; 7]);
        let view = ModelView {
            mb: &mb,
            ws: &ws,
            q_of: &sys.q_of_model_coordinate,
        };
        model.muscles[ili]
            .path
            .calc::<f64, _, GeneralizedForces<f64>>(&view, sm, None)
            .length
    };
    let sm = PathSmoothing::Smooth { delta: 0.02 };
    let d_exact = (length(0.785398 + 1e-9, PathSmoothing::Exact)
        - length(0.785398 - 1e-9, PathSmoothing::Exact))
    .abs();
    let d_smooth = (length(0.785398 + 1e-9, sm) - length(0.785398 - 1e-9, sm)).abs();
    assert!(
        d_exact > 5e-4 && d_smooth < 1e-9,
        "exact jump {d_exact}, smooth {d_smooth}"
    );
}
