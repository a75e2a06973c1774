//! leap's force laws against values OpenSim 4.6 computed with
//! scripts/reference_opensim.py (tests/data/opensim_forces.json): Thelen2003Muscle
//! over a grid for both parameter sets and two pennation angles (and its
//! static equilibrium), both contact laws on a sliding, spinning sphere
//! (force and point of application), and the jumper's passive torques.

use leap::laws::{passive_torque, sphere_ground_force, Thelen};
use leap::model::{ContactLaw, ContactSpec, LigamentSpec, MuscleSpec};

fn data() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string("tests/data/opensim_forces.json").unwrap())
        .unwrap()
}

fn rows(v: &serde_json::Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

/// |a − b| ≤ 1e-8·max(|b|, floor).
fn check(what: &str, a: f64, b: f64, floor: f64) {
    assert!(
        (a - b).abs() <= 1e-8 * b.abs().max(floor),
        "{what}: leap {a} vs OpenSim {b}"
    );
}

#[test]
fn thelen_matches_opensim() {
    let d = data();
    assert!(d["opensim_version"].as_str().unwrap().contains("4.6"));
    let mut n = 0;
    for set in d["thelen"].as_array().unwrap() {
        let p = &set["params"];
        let g = |k: &str| p[k].as_f64().unwrap();
        let spec = MuscleSpec {
            name: "mus".into(),
            max_isometric_force: 1000.0,
            optimal_fiber_length: 0.1,
            tendon_slack_length: 0.2,
            pennation_angle_at_optimal: set["pennation_angle_at_optimal"].as_f64().unwrap(),
            max_contraction_velocity: 10.0,
            activation_time_constant: g("tau_act"),
            deactivation_time_constant: g("tau_deact"),
            FmaxTendonStrain: g("FmaxTendonStrain"),
            FmaxMuscleStrain: 0.6,
            KshapeActive: g("KshapeActive"),
            KshapePassive: g("KshapePassive"),
            Af: g("Af"),
            Flen: g("Flen"),
            path: vec![],
        };
        let th = Thelen::new(&spec);
        for r in rows(&set["rows"]) {
            let info = th.calc(r[3], r[2], r[0], r[1], r[4]);
            let ctx = format!(
                "{} φ0={} {r:?}",
                set["parameters"], spec.pennation_angle_at_optimal
            );
            // Floors: 1 N for forces, 1e-3 m/s for fibre velocities.
            check(&format!("tendon force {ctx}"), info.tendon_force, r[5], 1.0);
            check(
                &format!("fibre velocity {ctx}"),
                info.fiber_velocity,
                r[6],
                1e-3,
            );
            check(
                &format!("f_v {ctx}"),
                info.force_velocity_multiplier,
                r[7],
                1e-3,
            );
            check(
                &format!("pennation {ctx}"),
                info.pennation_angle,
                r[8],
                1e-3,
            );
            check(
                &format!("activation rate {ctx}"),
                info.activation_rate,
                r[9],
                1e-3,
            );
            n += 1;
        }
        for r in rows(&set["equilibrium"]) {
            let lm = th.equilibrium_fiber_length(r[1], r[0]);
            // OpenSim's equilibrium iteration stops at a force residual of
            // 1e-8·F0 (model-equations.md §2.7): its fibre length carries
            // that error divided by the tendon-plus-fibre stiffness.
            assert!(
                (lm - r[2]).abs() < 1e-9,
                "{}: equilibrium l_M {lm} vs {} ({r:?})",
                set["parameters"],
                r[2]
            );
            let ft = th.calc(r[1], lm, r[0], 0.0, r[1]).tendon_force;
            assert!(
                (ft - r[3]).abs() < 1e-5,
                "equilibrium tendon force {ft} vs {}",
                r[3]
            );
        }
    }
    assert_eq!(n, 4 * 5 * 3 * 4 * 3 * 2);
}

#[test]
fn contact_laws_match_opensim() {
    let d = data();
    for set in d["contact"].as_array().unwrap() {
        let g = |k: &str| set[k].as_f64().unwrap();
        let spec = ContactSpec {
            law: if set["law"] == "HuntCrossleyForce" {
                ContactLaw::HuntCrossleyForce
            } else {
                ContactLaw::SmoothSphereHalfSpaceForce
            },
            stiffness: g("stiffness"),
            dissipation: g("dissipation"),
            static_friction: g("static_friction"),
            dynamic_friction: g("dynamic_friction"),
            viscous_friction: g("viscous_friction"),
            transition_velocity: g("transition_velocity"),
            hertz_smoothing: None,
            hunt_crossley_smoothing: None,
            derivative_smoothing: None,
            spheres: vec![],
        };
        let r = g("radius");
        for row in rows(&set["rows"]) {
            let (depth, vy, vx, w) = (row[0], row[1], row[2], row[3]);
            let p = [0.0, r - depth, 0.0];
            let p_contact_y = (p[1] - r) * 0.5;
            let vc = [vx - w * (p_contact_y - p[1]), vy, 0.0];
            let (f, at) = sphere_ground_force(&spec, r, p, vc);
            let ctx = format!("{} {row:?}", set["law"]);
            let scale = row[5].abs().max(1e-6);
            assert!(
                (f[0] - row[4]).abs() <= 1e-8 * scale,
                "F_x {} vs {} ({ctx})",
                f[0],
                row[4]
            );
            assert!(
                (f[1] - row[5]).abs() <= 1e-8 * scale,
                "F_y {} vs {} ({ctx})",
                f[1],
                row[5]
            );
            // Torque about the centre from the point of application.
            let tz = (at[0] - p[0]) * f[1] - (at[1] - p[1]) * f[0];
            assert!(
                (tz - row[6]).abs() <= 1e-8 * (scale * r),
                "torque {} vs {} ({ctx})",
                tz,
                row[6]
            );
        }
    }
}

#[test]
fn passive_torques_match_opensim() {
    let d = data();
    let model = leap::model::Model::from_file("models/jumper_gait2392.json").unwrap();
    for lig in d["ligaments"].as_array().unwrap() {
        let spec: &LigamentSpec = &model
            .ligaments
            .iter()
            .find(|l| l.spec.coordinate == lig["coordinate"].as_str().unwrap())
            .unwrap()
            .spec;
        for r in rows(&lig["rows"]) {
            let t: f64 = passive_torque(spec, r[0], r[1]);
            check(&format!("{} {r:?}", spec.coordinate), t, r[2], 1e-3);
        }
    }
}

/// DeGrooteFregly2016Muscle: at OpenSim's fibre length for its tendon-force
/// state, leap's fibre-length formulation gives OpenSim's fibre velocity,
/// tendon force, pennation and activation rate, and its force balance
/// vanishes at OpenSim's fibre velocity.
#[test]
fn degroote_matches_opensim() {
    use leap::laws::DeGroote;
    let d = data();
    let mut n = 0;
    for set in d["degroote"].as_array().unwrap() {
        let g = |k: &str| set[k].as_f64().unwrap();
        let spec = MuscleSpec {
            name: "mus".into(),
            max_isometric_force: 1000.0,
            optimal_fiber_length: 0.1,
            tendon_slack_length: 0.2,
            pennation_angle_at_optimal: g("pennation_angle_at_optimal"),
            max_contraction_velocity: 10.0,
            activation_time_constant: g("activation_time_constant"),
            deactivation_time_constant: g("deactivation_time_constant"),
            FmaxTendonStrain: g("tendon_strain_at_one_norm_force"),
            FmaxMuscleStrain: 0.6,
            KshapeActive: 0.5,
            KshapePassive: 4.0,
            Af: 0.3,
            Flen: 1.8,
            path: vec![],
        };
        let dg = DeGroote::new(&spec);
        for r in rows(&set["rows"]) {
            let info = dg.calc(r[2], r[4], r[0], r[3]);
            let ctx = format!("φ0={} {r:?}", spec.pennation_angle_at_optimal);
            check(
                &format!("fibre velocity {ctx}"),
                info.fiber_velocity,
                r[5],
                1e-3,
            );
            check(&format!("tendon force {ctx}"), info.tendon_force, r[6], 1.0);
            // The implicit form: the force balance vanishes at OpenSim's
            // fibre velocity (units of F0; OpenSim's v_M carries 10 digits).
            let balance = dg.force_balance(r[2], r[4], r[0], r[5] / (dg.vmax * dg.lopt));
            assert!(balance.abs() < 1e-6, "force balance {balance} ({ctx})");
            check(
                &format!("pennation {ctx}"),
                info.pennation_angle,
                r[7],
                1e-3,
            );
            check(
                &format!("activation rate {ctx}"),
                info.activation_rate,
                r[8],
                1e-3,
            );
            n += 1;
        }
    }
    assert_eq!(n, 2 * 3 * 3 * 3 * 3 * 2);
}

/// model-equations.md §8.3: OpenSim 4.6's DeGroote curve values.
#[test]
fn degroote_curves_match_opensim_tables() {
    use leap::laws::DeGroote;
    let spec = MuscleSpec {
        name: "m".into(),
        max_isometric_force: 1.0,
        optimal_fiber_length: 0.1,
        tendon_slack_length: 0.2,
        pennation_angle_at_optimal: 0.0,
        max_contraction_velocity: 10.0,
        activation_time_constant: 0.015,
        deactivation_time_constant: 0.06,
        FmaxTendonStrain: 0.049,
        FmaxMuscleStrain: 0.6,
        KshapeActive: 0.5,
        KshapePassive: 4.0,
        Af: 0.3,
        Flen: 1.8,
        path: vec![],
    };
    let dg = DeGroote::new(&spec);
    for (l, fal, fpe) in [
        (0.2, 0.00773584584111433, 0.0),
        (0.5, 0.0541121530142743, 0.000565014953778408),
        (1.0, 1.0, 0.0182288238200715),
        (1.5, 0.22614862789744, 0.513374088168605),
        (1.8, 0.0312824712807337, 3.79391495216897),
    ] {
        check(&format!("f_al({l})"), dg.fal(l), fal, 1e-6);
        check(&format!("f_pe({l})"), dg.fpe(l), fpe, 1e-6);
    }
    for (v, fv) in [
        (-1.0, 0.0),
        (-0.5, 0.234036393548804),
        (0.1, 1.20650867126025),
        (1.0, 1.79434296355532),
    ] {
        check(&format!("f_v({v})"), dg.fv(v), fv, 1e-6);
        assert!((dg.fv_inv(fv) - v).abs() < 1e-12);
    }
    for (lt, ft) in [
        (1.01, 0.0882945107353039),
        (1.03, 0.399030766530781),
        (1.049, 1.0),
        (1.06, 1.59418929625228),
    ] {
        check(&format!("f_T({lt})"), dg.ft(lt), ft, 1e-6);
    }
}
