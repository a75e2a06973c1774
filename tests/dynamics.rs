//! The Rust-native multibody against closed forms, energy conservation and
//! finite differences.

use leap::model::Model;
use leap::multibody::Multibody;
use leap::scalar::{Dual64, DualStruct};
use leap::simbody::{SimbodyIntegrator, SimbodyModel};

const G: f64 = 9.80665;

/// Closed-form equations of motion of the planar double pendulum of
/// models/double_pendulum.json (absolute angle q1, relative angle q2; links
/// hang along −y; Spong, Hutchinson & Vidyasagar, *Robot Modeling and
/// Control*, §7.3): returns (M, C q̇ − g).
fn double_pendulum_closed_form(q: [f64; 2], u: [f64; 2]) -> ([f64; 4], [f64; 2]) {
    let (m1, a1, i1) = (1.3, 0.4, 0.06);
    let (m2, a2, i2) = (0.7, 0.25, 0.02);
    let l1 = 0.9;
    let c2 = q[1].cos();
    let m11 = i1 + m1 * a1 * a1 + i2 + m2 * (l1 * l1 + a2 * a2 + 2.0 * l1 * a2 * c2);
    let m12 = i2 + m2 * (a2 * a2 + l1 * a2 * c2);
    let m22 = i2 + m2 * a2 * a2;
    let h = m2 * l1 * a2 * q[1].sin();
    let (t1, t12) = (q[0].sin(), (q[0] + q[1]).sin());
    let dv1 = m1 * G * a1 * t1 + m2 * G * (l1 * t1 + a2 * t12);
    let dv2 = m2 * G * a2 * t12;
    let b1 = -h * (2.0 * u[0] * u[1] + u[1] * u[1]) + dv1;
    let b2 = h * u[0] * u[0] + dv2;
    ([m11, m12, m12, m22], [b1, b2])
}

#[test]
fn double_pendulum_matches_closed_form() {
    let m = Model::from_file("models/double_pendulum.json").unwrap();
    let sys = m.system(false).unwrap();
    let mb = Multibody::new(&m, &sys);
    let mut ws = mb.workspace::<f64>();
    for k in 0..25 {
        let t = k as f64;
        let q = [2.9 * (0.7 * t).sin(), 3.0 * (1.3 * t + 0.4).cos()];
        let u = [4.0 * (0.3 * t).cos(), -3.0 * (0.9 * t).sin()];
        let tau = [5.0 * (t * 0.5).sin(), -2.0];
        mb.set_state(&mut ws, &q, &u);
        let (mm, b) = double_pendulum_closed_form(q, u);
        let scale_m = mm.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        for (x, y) in mb.mass_matrix(&ws).iter().zip(&mm) {
            assert!((x - y).abs() <= 1e-13 * scale_m, "M: {x} vs {y}");
        }
        let scale_b = b.iter().fold(1.0f64, |a, x| a.max(x.abs()));
        for (x, y) in mb.bias(&ws).iter().zip(&b) {
            assert!((x - y).abs() <= 1e-13 * scale_b, "b: {x} vs {y}");
        }
        // q̈ = M⁻¹(τ − b) by Cramer's rule.
        let det = mm[0] * mm[3] - mm[1] * mm[2];
        let r = [tau[0] - b[0], tau[1] - b[1]];
        let qdd_ref = [
            (mm[3] * r[0] - mm[1] * r[1]) / det,
            (mm[0] * r[1] - mm[2] * r[0]) / det,
        ];
        let mut qdd = [0.0; 2];
        mb.forward_dynamics(&mut ws, &tau, &mut qdd).unwrap();
        for (x, y) in qdd.iter().zip(&qdd_ref) {
            assert!((x - y).abs() <= 1e-11 * (1.0 + y.abs()), "qdd: {x} vs {y}");
        }
    }
}

/// Classical fixed-step RK4 on the Rust-native dynamics (no applied forces).
fn rk4_energy_drift(
    model: &Model,
    symmetric: bool,
    q0: Vec<f64>,
    u0: Vec<f64>,
    h: f64,
    steps: usize,
) -> (f64, f64) {
    let sys = model.system(symmetric).unwrap();
    let mb = Multibody::new(model, &sys);
    let n = mb.nq();
    let mut ws = mb.workspace::<f64>();
    let zero = vec![0.0; n];
    let mut f = |q: &[f64], u: &[f64]| -> Vec<f64> {
        let mut qdd = vec![0.0; n];
        mb.set_state(&mut ws, q, u);
        mb.forward_dynamics(&mut ws, &zero, &mut qdd).unwrap();
        qdd
    };
    let (mut q, mut u) = (q0, u0);
    let energy = |q: &[f64], u: &[f64]| {
        let mut w = mb.workspace::<f64>();
        mb.set_state(&mut w, q, u);
        mb.energy(&w)
    };
    let e0 = energy(&q, &u);
    let axpy = |x: &[f64], a: f64, y: &[f64]| -> Vec<f64> {
        x.iter().zip(y).map(|(x, y)| x + a * y).collect()
    };
    let mut max_drift: f64 = 0.0;
    for _ in 0..steps {
        let k1q = u.clone();
        let k1u = f(&q, &u);
        let k2q = axpy(&u, h / 2.0, &k1u);
        let k2u = f(&axpy(&q, h / 2.0, &k1q), &k2q);
        let k3q = axpy(&u, h / 2.0, &k2u);
        let k3u = f(&axpy(&q, h / 2.0, &k2q), &k3q);
        let k4q = axpy(&u, h, &k3u);
        let k4u = f(&axpy(&q, h, &k3q), &k4q);
        for i in 0..n {
            q[i] += h / 6.0 * (k1q[i] + 2.0 * k2q[i] + 2.0 * k3q[i] + k4q[i]);
            u[i] += h / 6.0 * (k1u[i] + 2.0 * k2u[i] + 2.0 * k3u[i] + k4u[i]);
        }
        max_drift = max_drift.max((energy(&q, &u) - e0).abs());
    }
    (e0, max_drift)
}

#[test]
fn passive_simulation_conserves_energy_rust_native() {
    let m = Model::from_file("models/double_pendulum.json").unwrap();
    let (e0, drift) = rk4_energy_drift(&m, false, vec![1.2, -0.7], vec![0.0, 2.0], 1e-3, 2000);
    // Scale: the pendulum's energy swing |E| ~ 10 J; RK4 at h = 1 ms keeps drift tiny.
    assert!(
        drift < 1e-8 * e0.abs().max(1.0),
        "double pendulum drift {drift} J (E0 {e0})"
    );
    let j = Model::from_file("models/jumper_gait2392.json").unwrap();
    let sys = j.system(true).unwrap();
    let q0 = sys.q_from_model(&j.poses["squat"]);
    let u0: Vec<f64> = (0..7).map(|i| 0.5 * (i as f64 - 3.0)).collect();
    let (e0, drift) = rk4_energy_drift(&j, true, q0, u0, 2e-4, 2500);
    assert!(
        drift < 1e-8 * e0.abs(),
        "jumper (free flight) drift {drift} J (E0 {e0})"
    );
}

#[test]
fn passive_simulation_conserves_energy_simbody() {
    let m = Model::from_file("models/jumper_gait2392.json").unwrap();
    let sys = m.system(true).unwrap();
    let mut sb = SimbodyModel::new(&m, &sys).unwrap();
    let q0 = sys.q_from_model(&m.poses["squat"]);
    let u0: Vec<f64> = (0..7).map(|i| 0.5 * (i as f64 - 3.0)).collect();
    sb.set_state(0.0, &q0, &u0).unwrap();
    sb.set_applied_forces(&[0.0; 7], &[]).unwrap();
    let e0 = sb.energy().unwrap();
    let stats = sb
        .integrate(SimbodyIntegrator::RungeKuttaMerson, 1e-9, 0.5)
        .unwrap();
    assert!((stats.final_time - 0.5).abs() < 1e-12);
    let e1 = sb.energy().unwrap();
    assert!(
        (e1 - e0).abs() < 1e-6 * e0.abs(),
        "Simbody drift {} J of {e0} J",
        e1 - e0
    );
    // The Rust-native energy at Simbody's final state is Simbody's energy.
    let (mut q, mut u) = (vec![0.0; 7], vec![0.0; 7]);
    sb.state(&mut q, &mut u).unwrap();
    let mb = Multibody::new(&m, &sys);
    let mut ws = mb.workspace::<f64>();
    mb.set_state(&mut ws, &q, &u);
    assert!((mb.energy(&ws) - e1).abs() < 1e-10 * e1.abs());
}

/// Forward-mode dual numbers through the whole q̈ computation agree with
/// central finite differences, for every q and q̇ direction.
#[test]
fn dual_number_derivatives_match_central_differences() {
    let m = Model::from_file("models/jumper_gait2392.json").unwrap();
    let sys = m.system(true).unwrap();
    let mb = Multibody::new(&m, &sys);
    let n = mb.nq();
    let q0 = sys.q_from_model(&m.poses["squat"]);
    let u0: Vec<f64> = (0..n).map(|i| 0.3 * (i as f64 + 1.0).sin()).collect();
    let tau0: Vec<f64> = (0..n).map(|i| 20.0 * (i as f64).cos()).collect();
    let heel = m
        .stations
        .iter()
        .find(|s| s.name == "sole_heel_lat_r")
        .unwrap();
    let (hb, hp) = mb.body_point(heel.body, heel.location);
    let qdd_f64 = |q: &[f64], u: &[f64]| -> Vec<f64> {
        let mut ws = mb.workspace::<f64>();
        mb.set_state(&mut ws, q, u);
        let mut tau = tau0.clone();
        mb.add_point_force(&ws, hb, hp, [30.0, 600.0, 0.0], &mut tau);
        let mut qdd = vec![0.0; n];
        mb.forward_dynamics(&mut ws, &tau, &mut qdd).unwrap();
        qdd
    };
    let mut ws = mb.workspace::<Dual64>();
    for dir in 0..2 * n {
        let q: Vec<Dual64> = q0
            .iter()
            .enumerate()
            .map(|(i, &x)| {
                if dir == i {
                    Dual64::from_re(x).derivative()
                } else {
                    Dual64::from_re(x)
                }
            })
            .collect();
        let u: Vec<Dual64> = u0
            .iter()
            .enumerate()
            .map(|(i, &x)| {
                if dir == n + i {
                    Dual64::from_re(x).derivative()
                } else {
                    Dual64::from_re(x)
                }
            })
            .collect();
        mb.set_state(&mut ws, &q, &u);
        let mut tau: Vec<Dual64> = tau0.iter().map(|&t| Dual64::from_re(t)).collect();
        mb.add_point_force(
            &ws,
            hb,
            hp,
            [
                Dual64::from_re(30.0),
                Dual64::from_re(600.0),
                Dual64::from_re(0.0),
            ],
            &mut tau,
        );
        let mut qdd = vec![Dual64::from_re(0.0); n];
        mb.forward_dynamics(&mut ws, &tau, &mut qdd).unwrap();
        let h = 1e-6;
        let (mut qp, mut qm, mut up, mut um) = (q0.clone(), q0.clone(), u0.clone(), u0.clone());
        if dir < n {
            qp[dir] += h;
            qm[dir] -= h;
        } else {
            up[dir - n] += h;
            um[dir - n] -= h;
        }
        let (fp, fm) = (qdd_f64(&qp, &up), qdd_f64(&qm, &um));
        for k in 0..n {
            let fd = (fp[k] - fm[k]) / (2.0 * h);
            let ad = qdd[k].eps;
            assert!(
                (fd - ad).abs() <= 1e-6 * (1.0 + ad.abs()),
                "d qdd[{k}] / d x[{dir}]: dual {ad} vs central difference {fd}"
            );
        }
        // The COM acceleration's derivative too.
        let acom = mb.com_acceleration(&ws, &qdd);
        assert!(acom[1].re().is_finite() && acom[1].eps.is_finite());
    }
}
