//! The whole forward model against OpenSim 4.6: the excitations of leap's
//! default solve integrated from the static squat by `leap simulate` and by
//! OpenSim's own Manager on `models/jumper.osim` (both legs, OpenSim's
//! Thelen2003Muscle, HuntCrossleyForce, CustomJoint knee and passive
//! torques; `scripts/opensim_forward_jump.py`, data in
//! `tests/data/opensim_forward_jump.json`).
//!
//! Both sides integrate to a relative accuracy of 1e-8 (RungeKuttaMerson in
//! OpenSim and Simbody); leap's Dormand–Prince runs at 1e-9, since at 1e-8
//! its own error at lift-off is 1.2e-6 rad in the knee (measured against its
//! runs at 1e-9 and 1e-10, which agree with OpenSim to 3e-7), above the
//! bound below, which is for the model, not for an integrator's error. At
//! `leap simulate`'s default 1e-5 the integrator's own error is some 3e-5 m
//! in the jump height, the same in Simbody and OpenSim, and would hide model
//! differences of that size. The bounds are a hundred times the accuracy on
//! quantities of order one (coordinates in rad and m, heights in m,
//! velocities in m/s). Lift-off (the vertical ground force gone) is located
//! by bisection on both sides; 1e-7 s of it moves the lift-off velocity by
//! g·1e-7 s = 1e-6 m/s. The vertical ground force is the stiffest output: at
//! its peak the contact's stiffness is about 370 body weights per metre of
//! the feet's depth (OpenSim, pelvis_ty moved by 1e-7 m at that pose), 4e-4
//! BW for the bound on positions, plus the damping's share; its bound is 1e-3
//! BW. The peak is sampled at leap's reports (Dormand–Prince: each step) and
//! OpenSim's milliseconds, which also stays inside 1e-3 BW.

use assert_cmd::Command;
use leap::io::StoTable;
use serde_json::Value;

const TOL: f64 = 1e-6;
const TOL_GRF: f64 = 1e-3;
const TOL_LIFTOFF: f64 = 1e-7;

fn golden() -> Value {
    let text = std::fs::read_to_string("tests/data/opensim_forward_jump.json").unwrap();
    serde_json::from_str(&text).unwrap()
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number: {}", v[key]))
}

fn simulate(integrator: &str, name: &str) -> (Value, StoTable, StoTable) {
    let out = std::env::temp_dir().join(format!(
        "leap-opensim-forward-{}-{name}",
        std::process::id()
    ));
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args([
            "simulate",
            "--controls",
            "tests/data/controls/jump_optimal.sto",
            "--integrator",
            integrator,
            "--accuracy",
            if integrator == "DormandPrince" {
                "1e-9"
            } else {
                "1e-8"
            },
            "--json",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: Value = serde_json::from_slice(&o.stdout).unwrap();
    let states = StoTable::read(&out.join("forward_states.sto")).unwrap();
    let grf = StoTable::read(&out.join("forward_grf.mot")).unwrap();
    let _ = std::fs::remove_dir_all(&out);
    (summary, states, grf)
}

/// Column `k` of leap's table at time t: the row itself where leap reported
/// at t (Simbody reports every millisecond, OpenSim's sampling interval);
/// between Dormand–Prince's steps (about 0.1–0.3 ms) cubic Hermite with the
/// derivative column `dk` where there is one (coordinates and their speeds),
/// linear otherwise (the ground force, whose interpolation error stays well
/// inside its bound).
fn at(t: &StoTable, k: usize, dk: Option<usize>, time: f64) -> f64 {
    let i = t.time.partition_point(|&s| s <= time + 1e-12);
    assert!(i > 0, "t = {time} before leap's output");
    if (t.time[i - 1] - time).abs() < 1e-12 {
        return t.rows[i - 1][k];
    }
    assert!(i < t.time.len(), "t = {time} after leap's output");
    let (t0, t1) = (t.time[i - 1], t.time[i]);
    let (y0, y1) = (t.rows[i - 1][k], t.rows[i][k]);
    let (h, s) = (t1 - t0, (time - t0) / (t1 - t0));
    match dk {
        Some(dk) => {
            let (d0, d1) = (t.rows[i - 1][dk] * h, t.rows[i][dk] * h);
            let (s2, s3) = (s * s, s * s * s);
            (2.0 * s3 - 3.0 * s2 + 1.0) * y0
                + (s3 - 2.0 * s2 + s) * d0
                + (-2.0 * s3 + 3.0 * s2) * y1
                + (s3 - s2) * d1
        }
        None => y0 + s * (y1 - y0),
    }
}

fn agrees_with_opensim(integrator: &str) {
    let g = golden();
    assert!(g["opensim_version"]
        .as_str()
        .unwrap()
        .starts_with("version 4.6"));
    assert_eq!(g["controls"], "tests/data/controls/jump_optimal.sto");
    let (s, states, grf) = simulate(integrator, integrator);
    // The reference holds for leap's squat as it was when the data were made.
    let row0 = &states.rows[0];
    for (label, v) in g["initial_state"].as_object().unwrap() {
        let k = states
            .labels
            .iter()
            .position(|l| l == label)
            .unwrap_or_else(|| panic!("{label} missing from leap's states"));
        let want = v.as_f64().unwrap();
        assert!(
            (row0[k] - want).abs() <= 1e-9 * (1.0 + want.abs()),
            "initial {label}: leap {} OpenSim run {want}: regenerate with scripts/opensim_forward_jump.py",
            row0[k]
        );
    }
    // The squat is at rest in OpenSim too, with OpenSim's muscle equilibrium.
    assert!(num(&g, "squat_max_abs_qdd") < 1e-6);
    assert!((num(&g, "squat_vertical_grf_bw") - 1.0).abs() < 1e-6);
    assert!(
        num(
            &g,
            "squat_max_fibre_length_difference_to_opensim_equilibrium_m"
        ) < 1e-8
    );

    let weight = num(&g, "body_weight_n");
    let col = |t: &StoTable, l: &str| t.labels.iter().position(|x| x == l).unwrap();
    let (fy_r, fy_l) = (
        col(&grf, "ground_force_r_vy"),
        col(&grf, "ground_force_l_vy"),
    );
    let mut worst_q: (f64, String, f64) = (0.0, String::new(), 0.0);
    let mut worst_f = (0.0, 0.0);
    let samples = g["samples"].as_array().unwrap();
    assert!(samples.len() > 250, "{} samples", samples.len());
    for sample in samples {
        let t = num(sample, "time");
        for (coord, v) in sample["q"].as_object().unwrap() {
            let find = |what: &str| {
                states
                    .labels
                    .iter()
                    .position(|l| l.ends_with(&format!("/{coord}/{what}")))
                    .unwrap_or_else(|| panic!("{coord}/{what} missing"))
            };
            let q = at(&states, find("value"), Some(find("speed")), t);
            let d = (q - v.as_f64().unwrap()).abs();
            if d > worst_q.0 {
                worst_q = (d, coord.clone(), t);
            }
        }
        let fy = at(&grf, fy_r, None, t) + at(&grf, fy_l, None, t);
        let d = (fy / weight - num(sample, "grf_y_bw")).abs();
        if d > worst_f.0 {
            worst_f = (d, t);
        }
    }
    eprintln!(
        "{integrator} against OpenSim 4.6: coordinates within {:.2e} ({} at {} s), vertical GRF within {:.2e} BW (at {} s)",
        worst_q.0, worst_q.1, worst_q.2, worst_f.0, worst_f.1
    );
    assert!(worst_q.0 < TOL, "{worst_q:?}");
    assert!(worst_f.0 < TOL_GRF, "{worst_f:?}");

    for (key, tol) in [
        ("standing_com_height_m", 1e-12),
        ("liftoff_time_s", TOL_LIFTOFF),
        ("liftoff_com_height_m", TOL),
        ("liftoff_com_velocity_mps", TOL),
        ("jump_height_m", TOL),
        ("peak_vertical_grf_bw", TOL_GRF),
    ] {
        let (leap, opensim) = (num(&s, key), num(&g, key));
        eprintln!("  {key}: leap {leap:.9} OpenSim {opensim:.9}");
        assert!(
            (leap - opensim).abs() < tol,
            "{key}: leap {leap} OpenSim {opensim} (tolerance {tol})"
        );
    }
}

#[test]
fn optimal_jump_by_simbody_agrees_with_opensim() {
    agrees_with_opensim("RungeKuttaMerson");
}

#[test]
fn optimal_jump_by_dormand_prince_agrees_with_opensim() {
    agrees_with_opensim("DormandPrince");
}
