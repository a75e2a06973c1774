//! The jumper's muscle paths and knee splines against OpenSim 4.6 itself
//! (tests/data/opensim_paths.json, written by scripts/jumper_osim.py from an
//! .osim export of models/jumper_gait2392.json): lengths, lengthening speeds and
//! moment arms of all 48 paths at 14 poses, and SimmSpline values and
//! derivatives.

use leap::model::{JointKind, Model};
use leap::multibody::{GeneralizedForces, ModelView, Multibody};
use leap::path::PathSmoothing;

fn rel(a: f64, b: f64, floor: f64) -> f64 {
    (a - b).abs() / b.abs().max(floor)
}

#[test]
fn paths_match_opensim() {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    let data: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("tests/data/opensim_paths.json").unwrap())
            .unwrap();
    assert!(data["opensim_version"].as_str().unwrap().contains("4.6"));
    let sys = model.system(false).unwrap();
    let mb = Multibody::new(&model, &sys);
    let mut ws = mb.workspace::<f64>();
    let (mut worst_len, mut worst_speed, mut worst_arm) = (0.0f64, 0.0f64, 0.0f64);
    let mut count = 0;
    for pose in data["poses"].as_array().unwrap() {
        let mut mq = vec![0.0; model.coordinates.len()];
        let mut mu = vec![0.0; model.coordinates.len()];
        for (i, c) in model.coordinates.iter().enumerate() {
            mq[i] = pose["q"][&c.name].as_f64().unwrap();
            mu[i] = pose["u"][&c.name].as_f64().unwrap();
        }
        let (q, u) = (sys.q_from_model(&mq), sys.q_from_model(&mu));
        mb.set_state(&mut ws, &q, &u);
        for m in &model.muscles {
            let want = &pose["muscles"][&m.spec.name];
            let mut tau = vec![0.0; q.len()];
            let v = {
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
                m.path
                    .calc(&view, PathSmoothing::Exact, Some((1.0, &mut sink)))
            };
            worst_len = worst_len.max(rel(v.length, want["length"].as_f64().unwrap(), 1e-3));
            // Speeds and moment arms: relative to 1 m/s and 1 cm where smaller.
            worst_speed = worst_speed.max(rel(
                v.lengthening_speed,
                want["lengthening_speed"].as_f64().unwrap(),
                1.0,
            ));
            let r = sys.model_from_q(&tau);
            for (i, c) in model.coordinates.iter().enumerate() {
                worst_arm = worst_arm.max(rel(
                    r[i],
                    want["moment_arms"][&c.name].as_f64().unwrap(),
                    0.01,
                ));
            }
            count += 1;
        }
    }
    eprintln!("worst relative errors vs OpenSim 4.6: length {worst_len:.2e}, speed {worst_speed:.2e}, moment arm {worst_arm:.2e}");
    assert_eq!(count, 14 * 48);
    assert!(
        worst_len <= 1e-8,
        "length: worst relative error {worst_len:e}"
    );
    assert!(
        worst_speed <= 1e-8,
        "lengthening speed: worst error {worst_speed:e}"
    );
    // OpenSim's MomentArmSolver is exact (unit tension), so the same bound holds.
    assert!(worst_arm <= 1e-8, "moment arm: worst error {worst_arm:e}");
}

#[test]
fn knee_splines_match_opensim_simm_spline() {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    let data: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("tests/data/opensim_paths.json").unwrap())
            .unwrap();
    let knee = model.joints.iter().find(|j| j.name == "knee_r").unwrap();
    let JointKind::TranslatingHinge {
        translation_x,
        translation_y,
        ..
    } = &knee.kind
    else {
        panic!()
    };
    for (key, s) in [
        ("translation_x", translation_x),
        ("translation_y", translation_y),
    ] {
        for row in data["knee_r_splines"][key].as_array().unwrap() {
            let r: Vec<f64> = row
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            let (v, d1, d2) = s.eval(r[0]);
            assert!(
                rel(v, r[1], 1e-3) <= 1e-12,
                "{key}({}) = {v} vs {}",
                r[0],
                r[1]
            );
            assert!(
                rel(d1, r[2], 1e-3) <= 1e-10,
                "{key}'({}) = {d1} vs {}",
                r[0],
                r[2]
            );
            assert!(
                rel(d2, r[3], 1e-3) <= 1e-9,
                "{key}''({}) = {d2} vs {}",
                r[0],
                r[3]
            );
        }
    }
}
