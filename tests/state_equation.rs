//! The state equation's plumbing with simple closed-form laws: the symmetric
//! system equals the full system with mirrored states, dual numbers agree
//! with finite differences, and the layout follows OpenSim's names.

use crate::common::TestLaws;
use leap::model::Model;
use leap::ode::{SimbodyStateEquation, StateEquation};
use leap::path::PathSmoothing;
use leap::scalar::Dual64;
use std::sync::Arc;

fn symmetric_state(eq: &StateEquation, k: usize) -> (Vec<f64>, Vec<f64>) {
    let (n, nm) = (eq.nq(), eq.nm());
    let mut x = vec![0.0; eq.nx()];
    let q0 = eq.system.q_from_model(&eq.model.poses["squat"]);
    for i in 0..n {
        x[i] = q0[i] + 0.003 * ((k + i) as f64).sin();
        x[n + i] = 0.5 * ((2 * k + i) as f64).cos();
    }
    // Lower the pelvis so the feet press into the ground.
    let ty = eq.system.q_of_model_coordinate[eq.model.coordinate_index("pelvis_ty").unwrap()];
    x[ty] -= 0.01;
    for m in 0..nm {
        x[2 * n + m] = 0.1 + 0.01 * m as f64;
        x[2 * n + nm + m] = 0.2 + 0.02 * ((m + k) as f64).sin();
    }
    let u = (0..nm)
        .map(|m| 0.5 + 0.4 * ((m * 3 + k) as f64).cos())
        .collect();
    (x, u)
}

#[test]
fn symmetric_system_equals_full_system_with_mirrored_states() {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    let laws = TestLaws(model.clone());
    let sym = StateEquation::new(&model, true, PathSmoothing::Smooth { delta: 0.02 }).unwrap();
    let full = StateEquation::new(&model, false, PathSmoothing::Smooth { delta: 0.02 }).unwrap();
    assert_eq!((sym.nq(), sym.nm(), sym.nx()), (7, 24, 62));
    assert_eq!((full.nq(), full.nm(), full.nx()), (10, 48, 116));
    let names = sym.state_names();
    assert_eq!(names[3], "/jointset/hip_r/hip_flexion_r/value");
    assert_eq!(names[7 + 4], "/jointset/knee_r/knee_angle_r/speed");
    assert_eq!(names[14], "/forceset/ercspn_r/fiber_length");
    assert_eq!(names[38 + 20], "/forceset/soleus_r/activation");
    for k in 0..4 {
        let (xs, us) = symmetric_state(&sym, k);
        // Full state: every model coordinate from its symmetric driver; left
        // muscles copy their right partners.
        let (ns, nms, nf, nmf) = (sym.nq(), sym.nm(), full.nq(), full.nm());
        let mq = sym.system.model_from_q(&xs[..ns]);
        let mu = sym.system.model_from_q(&xs[ns..2 * ns]);
        let mut xf = vec![0.0; full.nx()];
        xf[..nf].copy_from_slice(&full.system.q_from_model(&mq));
        xf[nf..2 * nf].copy_from_slice(&full.system.q_from_model(&mu));
        let mut uf = vec![0.0; nmf];
        for (j, &mi) in full.muscles.iter().enumerate() {
            let name = &model.muscles[mi].spec.name;
            let right = name
                .strip_suffix("_l")
                .map(|s| format!("{s}_r"))
                .unwrap_or(name.clone());
            let ks = sym
                .muscles
                .iter()
                .position(|&m| model.muscles[m].spec.name == right)
                .unwrap();
            xf[2 * nf + j] = xs[2 * ns + ks];
            xf[2 * nf + nmf + j] = xs[2 * ns + nms + ks];
            uf[j] = us[ks];
        }
        // The whole model's columns the files carry: the symmetric
        // system's give this full state; the full system's are its own
        // names in x's order.
        let full_names = full.state_names();
        let sym_columns = sym.model_state_columns();
        assert_eq!(sym_columns.len(), full.nx());
        for (label, i) in &sym_columns {
            let j = full_names.iter().position(|l| l == label).unwrap();
            assert_eq!(xs[*i], xf[j], "{label}");
        }
        let full_columns = full.model_state_columns();
        assert_eq!(
            full_columns,
            full_names.iter().cloned().zip(0..).collect::<Vec<_>>()
        );
        let full_controls = full.control_names();
        for (label, i) in sym.model_control_columns() {
            let j = full_controls.iter().position(|l| *l == label).unwrap();
            assert_eq!(us[i], uf[j], "{label}");
        }
        assert_eq!(
            full.model_control_columns(),
            full_controls.iter().cloned().zip(0..).collect::<Vec<_>>()
        );
        let mut ds = vec![0.0; sym.nx()];
        let mut df = vec![0.0; full.nx()];
        sym.rhs(&laws, &mut sym.workspace(), &xs, &us, &mut ds)
            .unwrap();
        let mut wf = full.workspace();
        full.rhs(&laws, &mut wf, &xf, &uf, &mut df).unwrap();
        assert!(
            wf.sphere_force.iter().any(|f| f[1] > 0.0),
            "the feet touch the ground"
        );
        // Accelerations of every symmetric coordinate.
        let scale = df[nf..2 * nf].iter().fold(1.0f64, |a, x| a.max(x.abs()));
        for (i, &c) in sym.system.coordinates.iter().enumerate() {
            let a_full = df[nf + full.system.q_of_model_coordinate[c]];
            assert!(
                (ds[ns + i] - a_full).abs() <= 1e-10 * scale,
                "q̈ of {}: {} vs {}",
                model.coordinates[c].name,
                ds[ns + i],
                a_full
            );
        }
        for (ks, &mi) in sym.muscles.iter().enumerate() {
            let j = full.muscles.iter().position(|&m| m == mi).unwrap();
            assert!((ds[2 * ns + ks] - df[2 * nf + j]).abs() < 1e-12);
            assert!((ds[2 * ns + nms + ks] - df[2 * nf + nmf + j]).abs() < 1e-12);
        }
    }
}

/// The whole model's columns of models without mirror partners (the
/// double pendulum: the system's own, no muscles) and of the reduced
/// jumper (10 muscles per side: 60 states): each left column takes its
/// right partner's index.
#[test]
fn model_columns_of_other_models() {
    let pendulum = Model::from_file("models/double_pendulum.json").unwrap();
    let eq = StateEquation::new(&pendulum, true, PathSmoothing::Exact).unwrap();
    assert_eq!(
        eq.model_state_columns(),
        eq.state_names().into_iter().zip(0..).collect::<Vec<_>>()
    );
    assert!(eq.model_control_columns().is_empty());
    let reduced = Model::from_file("models/jumper_reduced.json").unwrap();
    let eq = StateEquation::new(&reduced, true, PathSmoothing::Exact).unwrap();
    assert_eq!(eq.nx(), 2 * 7 + 2 * 10);
    let columns = eq.model_state_columns();
    assert_eq!(columns.len(), 2 * 10 + 2 * 20);
    let index = |l: &str| columns.iter().find(|c| c.0 == l).unwrap().1;
    for (label, i) in &columns {
        if label.contains("_l/") {
            assert_eq!(*i, index(&label.replace("_l/", "_r/")), "{label}");
        }
    }
    let controls = eq.model_control_columns();
    assert_eq!(controls.len(), 20);
    for (label, i) in &controls {
        if let Some(stem) = label.strip_suffix("_l") {
            let right = controls
                .iter()
                .find(|c| c.0 == format!("{stem}_r"))
                .unwrap();
            assert_eq!(*i, right.1, "{label}");
        }
    }
}

/// x as dual numbers with x[dir] seeded.
fn seeded(x: &[f64], dir: usize) -> Vec<Dual64> {
    x.iter()
        .enumerate()
        .map(|(i, &v)| {
            let d = Dual64::from(v);
            if i == dir {
                d.derivative()
            } else {
                d
            }
        })
        .collect()
}

/// The default jumper's symmetric state equation with smoothed path points,
/// and test laws.
fn smooth_symmetric() -> (StateEquation, TestLaws) {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    let eq = StateEquation::new(&model, true, PathSmoothing::Smooth { delta: 0.02 }).unwrap();
    (eq, TestLaws(model))
}

#[test]
fn state_derivative_jacobian_matches_central_differences() {
    let (eq, laws) = smooth_symmetric();
    let (x, u) = symmetric_state(&eq, 1);
    let nx = eq.nx();
    let mut wd = eq.workspace::<Dual64>();
    let mut w = eq.workspace::<f64>();
    let ud: Vec<Dual64> = u.iter().map(|&v| Dual64::from(v)).collect();
    for dir in (0..nx).step_by(5) {
        let xd = seeded(&x, dir);
        let mut fd = vec![Dual64::from(0.0); nx];
        eq.rhs(&laws, &mut wd, &xd, &ud, &mut fd).unwrap();
        let h = 1e-6;
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[dir] += h;
        xm[dir] -= h;
        let (mut fp, mut fm) = (vec![0.0; nx], vec![0.0; nx]);
        eq.rhs(&laws, &mut w, &xp, &u, &mut fp).unwrap();
        eq.rhs(&laws, &mut w, &xm, &u, &mut fm).unwrap();
        for i in 0..nx {
            let cd = (fp[i] - fm[i]) / (2.0 * h);
            assert!(
                (fd[i].eps - cd).abs() <= 1e-5 * (1.0 + cd.abs()),
                "∂f[{i}]/∂x[{dir}]: dual {} vs central {}",
                fd[i].eps,
                cd
            );
        }
    }
}

/// Muscle paths computed once (`path_values`) and given to `rhs` give the
/// state derivative of the walked paths, values and first derivatives;
/// given paths of another (q, q̇) are refused.
#[test]
fn given_paths_reproduce_the_walked_paths() {
    use leap::ode::{GivenPaths, OdeError};
    let (eq, laws) = smooth_symmetric();
    let (x, u) = symmetric_state(&eq, 2);
    let (n, nx) = (eq.nq(), eq.nx());
    let ud: Vec<Dual64> = u.iter().map(|&v| Dual64::from(v)).collect();
    // Seeded along a coordinate, a speed and a fibre length in turn.
    for dir in [2, n + 4, 2 * n + 3] {
        let xd = seeded(&x, dir);
        let mut walked = vec![Dual64::from(0.0); nx];
        let mut w = eq.workspace::<Dual64>();
        eq.rhs(&laws, &mut w, &xd, &ud, &mut walked).unwrap();
        let mut given = GivenPaths::default();
        eq.path_values(&mut w, &xd[..n], &xd[n..2 * n], &mut given)
            .unwrap();
        assert!(given.unit.iter().any(|g| g.re != 0.0));
        w.given_paths = Some(given);
        let mut fast = vec![Dual64::from(0.0); nx];
        eq.rhs(&laws, &mut w, &xd, &ud, &mut fast).unwrap();
        for i in 0..nx {
            for (what, a, b) in [
                ("value", fast[i].re, walked[i].re),
                ("derivative", fast[i].eps, walked[i].eps),
            ] {
                assert!(
                    (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
                    "f[{i}] {what} along x[{dir}]: given paths {a}, walked {b}"
                );
            }
        }
        let mut other = xd.clone();
        other[1] += 1e-9;
        assert!(matches!(
            eq.rhs(&laws, &mut w, &other, &ud, &mut fast),
            Err(OdeError::StaleGivenPaths)
        ));
    }
}

#[test]
fn wrong_lengths_are_errors() {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    let eq = StateEquation::new(&model, true, PathSmoothing::Exact).unwrap();
    let laws = TestLaws(model.clone());
    let mut w = eq.workspace::<f64>();
    let mut xd = vec![0.0; 62];
    assert!(eq
        .rhs(&laws, &mut w, &[0.0; 61], &[0.0; 24], &mut xd)
        .is_err());
    assert!(eq
        .rhs(&laws, &mut w, &[0.0; 62], &[0.0; 23], &mut xd)
        .is_err());
}

#[test]
fn simbody_state_equation_matches_rust_native() {
    let model = Model::from_file("models/jumper_gait2392.json").unwrap();
    for symmetric in [true, false] {
        let eq = Arc::new(
            StateEquation::new(&model, symmetric, PathSmoothing::Smooth { delta: 0.02 }).unwrap(),
        );
        let laws = Arc::new(TestLaws(model.clone()));
        let mut sb = SimbodyStateEquation::new(eq.clone(), laws.clone()).unwrap();
        let mut w = eq.workspace::<f64>();
        let nx = eq.nx();
        let n = eq.nq();
        let mut worst: f64 = 0.0;
        for k in 0..6 {
            let (x, u) = if symmetric {
                symmetric_state(&eq, k)
            } else {
                let mut x = vec![0.0; nx];
                let q0 = eq.system.q_from_model(&model.poses["squat"]);
                for i in 0..n {
                    x[i] = q0[i] + 0.003 * ((k + 3 * i) as f64).sin();
                    x[n + i] = 0.4 * ((k + i) as f64).cos();
                }
                x[eq.system.q_of_model_coordinate[model.coordinate_index("pelvis_ty").unwrap()]] -=
                    0.01;
                for (i, xi) in x.iter_mut().enumerate().skip(2 * n) {
                    *xi = 0.1 + 0.003 * i as f64;
                }
                (x, (0..eq.nm()).map(|m| 0.3 + 0.02 * m as f64).collect())
            };
            let (mut fr, mut fs) = (vec![0.0; nx], vec![0.0; nx]);
            eq.rhs(&*laws, &mut w, &x, &u, &mut fr).unwrap();
            sb.rhs(&x, &u, &mut fs).unwrap();
            let scale = fs.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for i in 0..nx {
                worst = worst.max((fr[i] - fs[i]).abs() / scale);
            }
        }
        assert!(
            worst <= 1e-9,
            "symmetric={symmetric}: worst normwise relative difference {worst:e}"
        );
    }
}

/// The contact forces alone ([`StateEquation::contact_forces`], which the
/// ground forces of a solution's nodes take) are those of the whole state
/// equation: equal where it evaluates, and there where it cannot. A
/// DeGrooteFregly2016Muscle at zero activation under tendon tension has no
/// explicit fibre velocity; a DeGroote solve's last node had written NaN
/// ground forces and been reported still on the ground.
#[test]
fn contact_forces_alone_are_the_state_equations() {
    let model = Model::from_file("models/jumper.json").unwrap();
    let (laws, eq) = StateEquation::opensim(&model, true).unwrap();
    let (x, u) = symmetric_state(&eq, 3);
    let mut ws = eq.workspace::<f64>();
    let mut xdot = vec![0.0; eq.nx()];
    eq.rhs(&laws, &mut ws, &x, &u, &mut xdot).unwrap();
    let full = ws.sphere_force.clone();
    assert!(full.iter().any(|f| f[1] > 0.0), "no sphere in contact");
    let mut alone = eq.workspace::<f64>();
    eq.contact_forces(&laws, &mut alone, &x).unwrap();
    assert_eq!(alone.sphere_force, full);

    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap();
    v["forces"]["muscle_model"] = "DeGrooteFregly2016Muscle".into();
    let dg = Model::from_json_str(&v.to_string(), "jumper_degroote.json").unwrap();
    let (dg_laws, dg_eq) = StateEquation::opensim(&dg, true).unwrap();
    let (n, nm) = (dg_eq.nq(), dg_eq.nm());
    let mut x0 = x.clone();
    for a in &mut x0[2 * n + nm..] {
        *a = 0.0;
    }
    let mut ws = dg_eq.workspace::<f64>();
    let e = dg_eq
        .rhs(&dg_laws, &mut ws, &x0, &vec![0.0; nm], &mut xdot)
        .unwrap_err();
    assert!(e.to_string().contains("fibre velocity"), "{e}");
    let mut alone = dg_eq.workspace::<f64>();
    dg_eq.contact_forces(&dg_laws, &mut alone, &x0).unwrap();
    assert_eq!(alone.sphere_force, full);
}
