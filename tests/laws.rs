//! OpenSim's force laws against OpenSim 4.6's own numbers
//! (model-equations.md §8, tests/data/thelen_opensim46.json) and against
//! their closed forms.

use leap::laws::{passive_torque, sphere_ground_force, Thelen};
use leap::model::{ContactLaw, ContactSpec, LigamentSpec, MuscleSpec};

fn muscle(phi0: f64, p: &serde_json::Value) -> MuscleSpec {
    MuscleSpec {
        name: "m".into(),
        max_isometric_force: 1000.0,
        optimal_fiber_length: 0.1,
        tendon_slack_length: 0.2,
        pennation_angle_at_optimal: phi0,
        max_contraction_velocity: 10.0,
        activation_time_constant: p["activation_time_constant"].as_f64().unwrap(),
        deactivation_time_constant: p["deactivation_time_constant"].as_f64().unwrap(),
        FmaxTendonStrain: p["FmaxTendonStrain"].as_f64().unwrap(),
        FmaxMuscleStrain: 0.6,
        KshapeActive: p["KshapeActive"].as_f64().unwrap(),
        KshapePassive: p["KshapePassive"].as_f64().unwrap(),
        Af: p["Af"].as_f64().unwrap(),
        Flen: p["Flen"].as_f64().unwrap(),
        path: vec![],
    }
}

/// Relative error with an absolute floor (the tables carry 10 significant
/// digits; zero entries are exact zeros in OpenSim).
fn close(a: f64, b: f64, floor: f64) -> bool {
    (a - b).abs() <= 2e-9 * b.abs().max(floor)
}

/// OpenSim 4.6's Thelen2003Muscle tables (model-equations.md §8).
fn thelen_tables() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string("tests/data/thelen_opensim46.json").unwrap())
        .unwrap()
}

/// The rows of table `key` of one parameter set, as numbers.
fn rows_of(d: &serde_json::Value, key: &str) -> Vec<Vec<f64>> {
    d[key]
        .as_array()
        .unwrap()
        .iter()
        .map(|row| {
            row.as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect()
        })
        .collect()
}

#[test]
fn thelen_matches_opensim_46_tables() {
    let data = thelen_tables();
    for set in ["defaults", "legacy"] {
        let d = &data[set];
        for r in rows_of(d, "rows") {
            let th = Thelen::new(&muscle(r[0], &d["params"]));
            let info = th.calc(r[4], r[3], r[1], r[2], r[5]);
            let ctx = format!("{set} {r:?}");
            assert!(
                close(info.tendon_force, r[6], 1e-6),
                "F_T {} ({ctx})",
                info.tendon_force
            );
            assert!(
                close(info.fiber_velocity, r[7], 1e-6),
                "v_M {} ({ctx})",
                info.fiber_velocity
            );
            assert!(
                close(info.force_velocity_multiplier, r[8], 1e-6),
                "f_v {} ({ctx})",
                info.force_velocity_multiplier
            );
            assert!(
                close(info.pennation_angle, r[9], 1e-6),
                "phi {} ({ctx})",
                info.pennation_angle
            );
            assert!(
                close(info.activation_rate, r[10], 1e-6),
                "da/dt {} ({ctx})",
                info.activation_rate
            );
        }
        for r in rows_of(d, "equilibrium") {
            let th = Thelen::new(&muscle(r[0], &d["params"]));
            let lm = th.equilibrium_fiber_length(r[2], r[1]);
            // OpenSim's equilibrium solver stops at a force residual of
            // 1e-8·F0, so its l_M is good to about 1e-9 m (§2.7).
            assert!(
                (lm - r[3]).abs() < 2e-9,
                "{set} equilibrium l_M {lm} vs {} ({r:?})",
                r[3]
            );
            let info = th.calc(r[2], lm, r[1], 0.0, r[2]);
            assert!(
                (info.tendon_force - r[4]).abs() < 1e-5 * r[4].max(1.0),
                "{set} equilibrium F_T {} vs {}",
                info.tendon_force,
                r[4]
            );
            assert!(
                info.fiber_velocity.abs() < 1e-9,
                "equilibrium fibre velocity {}",
                info.fiber_velocity
            );
        }
    }
}

/// The implicit fibre dynamics hold where OpenSim's explicit ones do: at
/// every row of the OpenSim 4.6 tables (both parameter sets, shortening,
/// lengthening and slack tendons), the force balance at OpenSim's own
/// fibre velocity is zero, and Thelen's forward force-velocity curve gives
/// back OpenSim's f_v.
#[test]
fn thelen_force_balance_vanishes_at_opensim_fibre_velocity() {
    let data = thelen_tables();
    let mut rows = 0;
    for set in ["defaults", "legacy"] {
        let d = &data[set];
        for r in rows_of(d, "rows") {
            let th = Thelen::new(&muscle(r[0], &d["params"]));
            let (lmt, lm, a) = (r[1], r[3], r[4]);
            let info = th.calc(a, lm, lmt, r[2], r[5]);
            if info.fiber_clamped {
                continue;
            }
            rows += 1;
            let vn = r[7] / (th.vmax * th.lopt);
            // OpenSim's table carries 10 digits of v_M; the balance's
            // slope in v is at most ~10 F0 per unit of v_n here.
            let res = th.force_balance(a, lm, lmt, vn);
            assert!(res.abs() < 1e-7, "{set} {r:?}: residual {res}");
            let fv = th.fv(a.clamp(0.01, 1.0), vn);
            assert!(close(fv, r[8], 1e-3), "{set} {r:?}: f_v {fv} vs {}", r[8]);
        }
    }
    assert!(rows > 10, "only {rows} unclamped rows");
}

/// f_v is the inverse of the explicit velocity in all four regions (slack
/// tendon, shortening, lengthening, beyond the knee), and continuous with a
/// continuous slope where the regions meet except at v = 0, where Thelen's
/// curve itself has a kink.
#[test]
fn thelen_forward_force_velocity_inverts_the_explicit_one() {
    let p = serde_json::json!({"activation_time_constant": 0.01, "deactivation_time_constant": 0.04,
        "FmaxTendonStrain": 0.033, "KshapeActive": 0.5, "KshapePassive": 4.0, "Af": 0.3, "Flen": 1.8});
    let th = Thelen::new(&muscle(0.2, &p));
    let (lo, vm) = (th.lopt, th.vmax);
    let mut regions = [0usize; 4];
    for &a in &[0.01, 0.05, 0.3, 1.0] {
        let k = 0.25 + 0.75 * a;
        for i in 0..=400 {
            // Tendon lengths from slack to far beyond isometric.
            let lmt = 0.25 + 0.1 * i as f64 / 400.0;
            let r = th.rates(a, lo, lmt, a);
            let vn = r.fiber_velocity / (vm * lo);
            let region = if vn <= -k {
                0
            } else if vn <= 0.0 {
                1
            } else if th.fv(a, vn) < 0.95 * 1.8 {
                2
            } else {
                3
            };
            regions[region] += 1;
            let res = th.force_balance(a, lo, lmt, vn);
            assert!(res.abs() < 1e-12, "a {a} l_MT {lmt}: residual {res}");
        }
        // Value and slope continuity at v = −k and at the knee.
        let cc = (2.0 + 2.0 / 0.3) / 0.8;
        let knee_v = k * (0.95 * 1.8 - 1.0) / ((1.8 - 0.95 * 1.8) * cc);
        for v0 in [-k, knee_v] {
            let e = 1e-7;
            let (fm, f0, fp) = (th.fv(a, v0 - e), th.fv(a, v0), th.fv(a, v0 + e));
            assert!((fp - fm).abs() < 1e-5, "f_v jumps at {v0}");
            let (sl, sr) = ((f0 - fm) / e, (fp - f0) / e);
            assert!(
                (sl - sr).abs() < 1e-4 * sl.abs(),
                "slope {sl} vs {sr} at {v0}"
            );
        }
    }
    assert!(
        regions.iter().all(|&n| n > 0),
        "regions covered {regions:?}"
    );
}

/// Hunt-Crossley in closed form: f = (4/3)·√R·(E/2^{3/2})·δ^{3/2}·(1 + 1.5 c v_n),
/// friction μ·f·min(v_s/v_t, 1) with μ_s = μ_d (model-equations.md §4.2).
#[test]
fn hunt_crossley_closed_form() {
    let spec = ContactSpec {
        law: ContactLaw::HuntCrossleyForce,
        stiffness: 1e7,
        dissipation: 0.5,
        static_friction: 0.8,
        dynamic_friction: 0.8,
        viscous_friction: 0.0,
        transition_velocity: 0.01,
        hertz_smoothing: None,
        hunt_crossley_smoothing: None,
        derivative_smoothing: None,
        spheres: vec![],
    };
    let r = 0.05;
    for (depth, vy, vx) in [(0.001, 0.0, 0.0), (0.002, -0.3, 0.005), (0.004, 0.2, -0.5)] {
        let p = [0.3, r - depth, 0.1];
        let (f, at) = sphere_ground_force(&spec, r, p, [vx, vy, 0.0]);
        let fh = 4.0 / 3.0 * r.sqrt() * (1e7 / 2f64.powf(1.5)) * depth.powf(1.5);
        let fy = fh * (1.0 + 1.5 * 0.5 * (-vy));
        assert!((f[1] - fy).abs() < 1e-10 * fy, "{} vs {fy}", f[1]);
        let fx = -(vx.signum()) * 0.8 * fy * (vx.abs() / 0.01).min(1.0);
        assert!((f[0] - fx).abs() < 1e-10 * fy, "{} vs {fx}", f[0]);
        assert!(
            (at[1] - (-depth / 2.0)).abs() < 1e-15,
            "contact point mid-overlap"
        );
    }
    // Out of contact, or separating fast enough: no force.
    assert_eq!(
        sphere_ground_force(&spec, r, [0.0, r + 1e-6, 0.0], [0.0, 0.0, 0.0]).0,
        [0.0; 3]
    );
    assert_eq!(
        sphere_ground_force(&spec, r, [0.0, r - 1e-3, 0.0], [0.0, 3.0, 0.0]).0[1],
        0.0
    );
}

/// The Anderson & Pandy form, and OpenSim 4.6's ExpressionBasedCoordinateForce
/// for the hip-flexion entry (model-equations.md §8.6).
#[test]
fn passive_torque_is_the_anderson_pandy_exponential() {
    let hip = LigamentSpec {
        coordinate: "hip_flexion_r".into(),
        k1: -2.44,
        k2: 5.05,
        k3: 1.51,
        k4: -21.88,
        theta1: -0.6981,
        theta2: 1.81,
        damping: 0.1,
    };
    for (q, qd, want) in [
        (-0.8, 0.0, 14.03678414),
        (-0.5, 1.0, -0.08022579784),
        (0.0, 0.0, -0.0002612991696),
        (1.0, -2.0, 0.1591766869),
        (1.9, 0.5, -3.893940604),
    ] {
        let t: f64 = passive_torque(&hip, q, qd);
        assert!(
            (t - want).abs() <= 1e-9 * want.abs().max(1e-3),
            "hip q={q}: {t} vs {want}"
        );
    }
    let l = LigamentSpec {
        coordinate: "knee_angle_r".into(),
        k1: -6.09,
        k2: 33.94,
        k3: 11.03,
        k4: -11.33,
        theta1: -2.4,
        theta2: 0.13,
        damping: 0.1,
    };
    // Sign check of model-data.md §9: at q = 0.13 the first term is −6.09 N·m.
    let t: f64 = passive_torque(&l, 0.13, 0.0);
    assert!((t - (-6.09 + 11.03 * (-11.33f64 * (0.13 + 2.4)).exp())).abs() < 1e-12);
    let t2: f64 = passive_torque(&l, -1.0, 2.0);
    let want =
        -6.09 * (33.94f64 * (-1.0 - 0.13)).exp() + 11.03 * (-11.33f64 * (-1.0 + 2.4)).exp() - 0.2;
    assert!((t2 - want).abs() < 1e-12);
}

/// model-equations.md §8.4: OpenSim 4.6's HuntCrossleyForce and
/// SmoothSphereHalfSpaceForce on a spinning, sliding sphere.
#[test]
fn contact_laws_match_opensim_46_tables() {
    let data: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string("tests/data/contact_opensim46.json").unwrap(),
    )
    .unwrap();
    let r = 0.05;
    let mut checked = 0;
    for case in data["cases"].as_array().unwrap() {
        let law = if case["law"] == "HuntCrossleyForce" {
            ContactLaw::HuntCrossleyForce
        } else {
            ContactLaw::SmoothSphereHalfSpaceForce
        };
        let g = |k: &str| case[k].as_f64().unwrap();
        let spec = ContactSpec {
            law,
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
        for row in case["rows"].as_array().unwrap() {
            let v: Vec<f64> = row
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            let (depth, vy, vx, w) = (v[0], v[1], v[2], v[3]);
            let p = [0.0, r - depth, 0.0];
            // Velocity of the sphere's material point at the mid-overlap contact point.
            let arm = r - depth / 2.0;
            let vc = [vx + w * arm, vy, 0.0];
            let (f, _) = sphere_ground_force(&spec, r, p, vc);
            let scale = v[4].abs().max(1e-9);
            assert!(
                (f[1] - v[4]).abs() <= 1e-8 * scale,
                "{:?} F_y {} vs {} ({v:?})",
                case["law"],
                f[1],
                v[4]
            );
            assert!(
                (f[0] - v[5]).abs() <= 1e-8 * scale,
                "{:?} F_x {} vs {} ({v:?})",
                case["law"],
                f[0],
                v[5]
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 24);
}

/// The smoothed activation switch (OcpOptions::activation_smoothing): with a
/// very sharp blend it is OpenSim's law wherever u ≠ a; at moderate
/// sharpness its derivative is continuous across u = a (dual number against
/// central differences), where OpenSim's own law has a kink.
#[test]
fn smoothed_activation_switch() {
    use leap::scalar::Dual64;
    let p = serde_json::json!({"activation_time_constant": 0.01, "deactivation_time_constant": 0.04,
        "FmaxTendonStrain": 0.033, "KshapeActive": 0.5, "KshapePassive": 4.0, "Af": 0.3, "Flen": 1.8});
    let opensim = Thelen::new(&muscle(0.1, &p));
    let mut sharp = opensim.clone();
    sharp.activation_smoothing = Some(1e6);
    for &(a, u) in &[
        (0.2f64, 0.9f64),
        (0.9, 0.2),
        (0.5, 0.51),
        (0.5, 0.49),
        (0.01, 1.0),
        (1.0, 0.01),
    ] {
        let (r0, r1): (f64, f64) = (opensim.activation_rate(a, u), sharp.activation_rate(a, u));
        assert!(
            (r0 - r1).abs() <= 1e-12 * r0.abs(),
            "a {a} u {u}: {r0} vs {r1}"
        );
    }
    let mut smooth = opensim.clone();
    smooth.activation_smoothing = Some(10.0);
    let h = 1e-6;
    for &a in &[0.01f64, 0.3, 0.8] {
        let d = smooth.activation_rate(Dual64::from(a), Dual64::new(a, 1.0));
        let fd: f64 =
            (smooth.activation_rate(a, a + h) - smooth.activation_rate(a, a - h)) / (2.0 * h);
        assert!(
            (d.eps - fd).abs() <= 1e-6 * fd.abs(),
            "∂/∂u at u = a = {a}: {} vs {fd}",
            d.eps
        );
        // OpenSim's law: the one-sided slopes differ by the time constants.
        let right: f64 = (opensim.activation_rate(a, a + h) - opensim.activation_rate(a, a)) / h;
        let left: f64 = (opensim.activation_rate(a, a) - opensim.activation_rate(a, a - h)) / h;
        assert!(
            (right - left).abs() > 0.1 * right.abs(),
            "a {a}: kink {right} vs {left}"
        );
        // The smoothed slope lies between them.
        assert!(d.eps > left.min(right) && d.eps < left.max(right));
    }
}

/// Thelen's fibre clamp spread over a band above the fibre-length floor:
/// the model's own velocity above the band, a shortening fibre stopped at
/// the floor (as OpenSim's clamp stops it at l_min), and a velocity whose
/// derivative in the fibre length is continuous (checked against central
/// differences, and the one-sided slopes at the band's top).
#[test]
fn smoothed_fibre_clamp() {
    use leap::laws::FiberClampSmoothing;
    use leap::scalar::Dual64;
    let p = serde_json::json!({"activation_time_constant": 0.01, "deactivation_time_constant": 0.04,
        "FmaxTendonStrain": 0.033, "KshapeActive": 0.5, "KshapePassive": 4.0, "Af": 0.3, "Flen": 1.8});
    let opensim = Thelen::new(&muscle(0.3, &p));
    let lmin = opensim.min_fiber_length;
    let (floor, width) = (1.001 * lmin, 0.02 * lmin);
    let mut smooth = opensim.clone();
    smooth.fiber_clamp_smoothing = Some(FiberClampSmoothing { floor, width });
    let (a, u) = (0.8, 0.8);
    // Muscle-tendon lengths with the tendon slack at the floor (0.19 m:
    // the fibre alone is longer than the path minus the slack length) and
    // with it stretched (0.21 m).
    let v = |t: &Thelen, lm: f64, lmt: f64| -> f64 { t.rates(a, lm, lmt, u).fiber_velocity };
    let dv = |t: &Thelen, lm: f64, lmt: f64| -> f64 {
        t.rates(
            Dual64::from(a),
            Dual64::new(lm, 1.0),
            Dual64::from(lmt),
            Dual64::from(u),
        )
        .fiber_velocity
        .eps
    };
    let slack = 0.19 + 0.0;
    let vmax = 10.0 * 0.1;
    // Above the band the velocity is the model's, bit for bit.
    for lm in [floor + 1.0001 * width, 0.06, 0.1, 0.14] {
        for lmt in [slack, 0.21, 0.25] {
            assert_eq!(
                v(&smooth, lm, lmt),
                v(&opensim, lm, lmt),
                "lm {lm} lmt {lmt}"
            );
        }
    }
    // At the floor with the tendon slack the model's fibre shortens at
    // about v_max·(0.25 + 0.75 a); the smoothed one stops.
    let v_model = v(&opensim, floor, slack);
    assert!(v_model < -0.5 * vmax, "model velocity {v_model}");
    let v_floor = v(&smooth, floor, slack);
    assert!(
        v_floor >= 0.0 && v_floor <= 1e-4 * v_model.abs(),
        "at the floor: {v_floor} (model {v_model})"
    );
    // A lengthening fibre in the band keeps its velocity (to the blend).
    let v_len = v(&opensim, floor + 0.5 * width, 0.25);
    assert!(v_len > 0.1 * vmax, "lengthening {v_len}");
    assert!((v(&smooth, floor + 0.5 * width, 0.25) - v_len).abs() <= 1e-3 * v_len);
    // Derivatives in the fibre length across the band (dual numbers against
    // central differences), and C¹ at the band's top.
    let h = 1e-9;
    for r in [0.05, 0.3, 0.5, 0.7, 0.95] {
        let lm = floor + r * width;
        for lmt in [slack, 0.205] {
            let fd = (v(&smooth, lm + h, lmt) - v(&smooth, lm - h, lmt)) / (2.0 * h);
            let d = dv(&smooth, lm, lmt);
            assert!(
                (d - fd).abs() <= 1e-5 * fd.abs().max(1.0),
                "r {r} lmt {lmt}: {d} vs {fd}"
            );
        }
    }
    // C¹ at both ends of the band: the one-sided slopes agree to a
    // millionth of the ramp's own slope |v|/width.
    let h = 1e-8;
    for edge in [floor, floor + width] {
        let right = (v(&smooth, edge + h, slack) - v(&smooth, edge, slack)) / h;
        let left = (v(&smooth, edge, slack) - v(&smooth, edge - h, slack)) / h;
        assert!(
            (right - left).abs() <= 1e-6 * v_model.abs() / width,
            "slopes at {edge}: {left} vs {right}"
        );
    }
    // ... where the ramp itself is steep: at mid-band the velocity falls
    // with the length at 15/8 |v|/width (the ramp's slope there).
    let mid = dv(&smooth, floor + 0.5 * width, slack);
    assert!(
        (mid + 1.875 * v_model.abs() / width).abs() <= 0.05 * mid.abs(),
        "mid-band slope {mid}"
    );
}
