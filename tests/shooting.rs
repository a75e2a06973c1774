//! Direct shooting ([`leap::shooting`]), the paper's first method, on the
//! reduced model (10 muscles per side): its integration against one
//! continuous integration, its rows against collocation's at the same
//! nodes, its central-difference Jacobian against difference quotients of
//! whole integrations, its central differences and its forward
//! sensitivities against accurate central differences, and the study
//! settings that go with it. `tests/cli_solve.rs` runs a reduced solve
//! through `leap solve`.

use leap::integrator::{Dopri5, Dopri5Options, OdeSystem};
use leap::nlp::Nlp;
use leap::ocp::{JumpOcp, OcpOptions};
use leap::ode::StateWorkspace;
use leap::shooting::{Shooting, ShootingOptions};
use std::path::Path;
use std::sync::Arc;

fn reduced_ocp(intervals: usize) -> Arc<JumpOcp> {
    let model = leap::model::Model::from_file(Path::new("models/jumper_reduced.json")).unwrap();
    let options = OcpOptions {
        no_countermovement_nodes: 7.min(intervals),
        ..Default::default()
    };
    Arc::new(JumpOcp::new(&model, options).unwrap())
}

fn shooting(ocp: &Arc<JumpOcp>, options: ShootingOptions) -> (Shooting, Vec<f64>) {
    let sh = Shooting::new(ocp.clone(), options).unwrap();
    let (v, _) = sh.bang_bang_guess().unwrap();
    (sh, v)
}

/// ẋ = f(x, u(t)) with u from node excitations, for one integration over
/// the whole push-off (no restarts).
struct Continuous<'a> {
    ocp: &'a JumpOcp,
    controls: leap::io::Controls,
    ws: StateWorkspace<f64>,
    u: Vec<f64>,
}

impl OdeSystem for Continuous<'_> {
    fn dim(&self) -> usize {
        self.ocp.nx()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), String> {
        self.controls.at(t, &mut self.u);
        self.ocp
            .state_rates(&mut self.ws, x, &self.u, dx)
            .map(|_| ())
            .map_err(|e| e.to_string())
    }
}

/// The node states of a shooting evaluation (one Dormand–Prince run per
/// interval, restarted at every node) are those of a single integration
/// across all nodes, both at accuracy 1e-11, and J is the apex of the
/// last state's centre of mass.
#[test]
fn shooting_integration_matches_one_continuous_integration() {
    let big_n = 6;
    let ocp = reduced_ocp(big_n);
    let options = ShootingOptions {
        num_intervals: big_n,
        accuracy: 1e-11,
        ..Default::default()
    };
    let (mut sh, v) = shooting(&ocp, options);
    let nodes = sh.evaluate(&v).unwrap().clone();
    let tf = sh.final_time(&v);
    let nu = ocp.nu();
    let controls = leap::io::Controls {
        time: (0..=big_n).map(|k| k as f64 * tf / big_n as f64).collect(),
        values: sh
            .node_controls(&v)
            .chunks(nu)
            .map(<[f64]>::to_vec)
            .collect(),
    };
    let mut sys = Continuous {
        ocp: &ocp,
        controls,
        ws: ocp.eq.workspace(),
        u: vec![0.0; nu],
    };
    let opts = Dopri5Options {
        accuracy: 1e-11,
        ..Default::default()
    };
    let mut ig = Dopri5::new(&mut sys, 0.0, ocp.x0(), opts).unwrap();
    let mut worst: f64 = 0.0;
    for k in 1..=big_n {
        let tk = if k == big_n {
            tf
        } else {
            k as f64 * tf / big_n as f64
        };
        while ig.t() < tk {
            ig.step(&mut sys, tk).unwrap();
        }
        for (a, b) in ig.x().iter().zip(&nodes.states[k]) {
            worst = worst.max((a - b).abs() / (1.0 + b.abs()));
        }
    }
    eprintln!("largest difference of a node state: {worst:.2e}");
    assert!(worst < 1e-7, "node states differ by {worst:.2e}");
    let mut mb = ocp.eq.multibody.workspace::<f64>();
    let (_, _, j) = ocp.jump_objective(&mut mb, ig.x());
    assert!(
        (j - nodes.objective).abs() < 1e-8,
        "J {j} against the shooting's {}",
        nodes.objective
    );
    assert_eq!(sh.objective(&v).unwrap(), -nodes.objective);
}

/// The central-difference Jacobian integrates each excitation's quotient
/// only from the node before it; it equals the quotients of whole
/// integrations from the squat (the restarts make the trajectory before
/// that node the same to the bit), and every entry outside its pattern is
/// zero.
#[test]
fn shooting_jacobian_equals_difference_quotients_of_whole_integrations() {
    let big_n = 4;
    let ocp = reduced_ocp(big_n);
    let options = ShootingOptions {
        num_intervals: big_n,
        derivatives: leap::shooting::ShootingDerivatives::CentralDifference,
        ..Default::default()
    };
    let (mut sh, v) = shooting(&ocp, options);
    let (n, m) = (sh.num_variables(), sh.num_constraints());
    let structure = sh.jacobian_structure();
    let mut jac = vec![0.0; structure.len()];
    sh.jacobian_values(&v, &mut jac).unwrap();
    let mut grad = vec![0.0; n];
    sh.gradient(&v, &mut grad).unwrap();
    let mut dense = vec![vec![0.0; n]; m];
    for (&(r, c), &x) in structure.iter().zip(&jac) {
        dense[r][c] = x;
    }
    let tf = sh.final_time(&v);
    let delta = options.finite_difference_step;
    let (mut cp, mut cm) = (vec![0.0; m], vec![0.0; m]);
    let mut worst: f64 = 0.0;
    for c in 0..n {
        let d = if c == n - 1 { delta * tf } else { delta };
        let (mut vp, mut vm) = (v.clone(), v.clone());
        vp[c] += d;
        vm[c] -= d;
        let fp = sh.objective(&vp).unwrap();
        sh.constraints(&vp, &mut cp).unwrap();
        let fm = sh.objective(&vm).unwrap();
        sh.constraints(&vm, &mut cm).unwrap();
        let s = 0.5 / d;
        let g = (fp - fm) * s;
        worst = worst.max((g - grad[c]).abs() / (1.0 + g.abs()));
        for r in 0..m {
            let q = (cp[r] - cm[r]) * s;
            let e = (q - dense[r][c]).abs() / (1.0 + q.abs());
            assert!(
                e < 1e-9,
                "∂({})/∂({}): whole integrations {q}, the Jacobian {}",
                sh.constraint_name(r),
                sh.variable_name(c),
                dense[r][c]
            );
            worst = worst.max(e);
        }
    }
    eprintln!("largest difference: {worst:.2e}");
    assert!(worst < 1e-9);
    assert_eq!(sh.counters.jacobians, 1);
}

/// The gradient and the Jacobian's values at an interior point:
/// excitations rising from 0.2 to 0.8 over the nodes, t_f the bang-bang
/// guess's.
fn derivatives_at_a_ramp(
    ocp: &Arc<JumpOcp>,
    options: ShootingOptions,
) -> (Vec<f64>, Vec<f64>, Shooting) {
    let big_n = options.num_intervals;
    let (mut sh, mut v) = shooting(ocp, options);
    let nu = ocp.nu();
    for k in 0..big_n {
        let u = 0.2 + 0.6 * k as f64 / (big_n - 1) as f64;
        v[k * nu..(k + 1) * nu].fill(u);
    }
    let mut g = vec![0.0; sh.num_variables()];
    sh.gradient(&v, &mut g).unwrap();
    let mut j = vec![0.0; sh.jacobian_structure().len()];
    sh.jacobian_values(&v, &mut j).unwrap();
    (g, j, sh)
}

/// Central differences at their default settings (accuracy 1e-8, step
/// 1e-3) against accurate ones (accuracy 1e-12, step 1e-5) at a point inside
/// the bounds, excitations rising from 0.2 to 0.8 over the nodes: the
/// gradient and the Jacobian within 1e-3 of the latter's size (measured
/// 9e-6 and 7e-5). At a point where muscles rest at the activation floor
/// (the bang-bang guess: u = a = 0.01, where OpenSim clamps a in the force)
/// the quotients average the one-sided derivatives, whatever the step.
#[test]
fn central_difference_quotients_are_accurate() {
    let big_n = 4;
    let ocp = reduced_ocp(big_n);
    let quotients = |accuracy: f64, step: f64| {
        let options = ShootingOptions {
            num_intervals: big_n,
            accuracy,
            finite_difference_step: step,
            derivatives: leap::shooting::ShootingDerivatives::CentralDifference,
            ..Default::default()
        };
        let (g, j, _) = derivatives_at_a_ramp(&ocp, options);
        (g, j)
    };
    let (g, j) = quotients(1e-8, 1e-3);
    let (g_ref, j_ref) = quotients(1e-12, 1e-5);
    let rel = |a: &[f64], b: &[f64]| {
        let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
        let s: f64 = b.iter().map(|y| y * y).sum();
        (d / s).sqrt()
    };
    let (eg, ej) = (rel(&g, &g_ref), rel(&j, &j_ref));
    eprintln!("gradient relative error {eg:.2e}, Jacobian {ej:.2e}");
    assert!(
        eg < 1e-3 && ej < 1e-3,
        "gradient {eg:.2e}, Jacobian {ej:.2e}"
    );
}

/// Forward sensitivities (the integrator's steps replayed with the point
/// Jacobian at every stage, chained over the nodes) against accurate
/// central differences (accuracy 1e-12, step 1e-5) at the interior point
/// of `central_difference_quotients_are_accurate`: at accuracy
/// 1e-10 the gradient and the Jacobian within 1e-3 of the latter's size
/// (measured 2e-5 and 8e-5), and every column within 1e-2 of its own
/// size (measured 4e-4, an excitation at node 3), so that no variable's
/// derivatives (an excitation's weight on either side of its node, t_f
/// through the step lengths) can be wrong unseen. At the default accuracy
/// 1e-8 the Jacobian's error is larger (7.8e-4 here; `RAMP=1 cargo run
/// --release --example shooting_probe -- 4 models/jumper_reduced.json`):
/// the replayed steps are the state's, chosen for its error alone.
#[test]
fn forward_sensitivities_match_accurate_difference_quotients() {
    use leap::shooting::ShootingDerivatives;
    let big_n = 4;
    let ocp = reduced_ocp(big_n);
    let derivatives = |accuracy: f64, derivatives: ShootingDerivatives, step: f64, threads| {
        let options = ShootingOptions {
            num_intervals: big_n,
            accuracy,
            finite_difference_step: step,
            derivatives,
            threads,
        };
        derivatives_at_a_ramp(&ocp, options)
    };
    let (g, j, sh) = derivatives(1e-10, ShootingDerivatives::ForwardSensitivity, 1e-3, 2);
    // The intervals are independent: one thread gives the same bits.
    let (g1, j1, _) = derivatives(1e-10, ShootingDerivatives::ForwardSensitivity, 1e-3, 1);
    assert!(g1 == g && j1 == j);
    assert_eq!(sh.counters.jacobians, 1);
    assert_eq!(sh.counters.difference_simulations, 0);
    // Six stages per replayed step, and one point per node 1..N.
    assert_eq!(
        sh.counters.point_jacobians,
        6 * sh.counters.sensitivity_steps + big_n
    );
    let (g_ref, j_ref, _) = derivatives(1e-12, ShootingDerivatives::CentralDifference, 1e-5, 2);
    let rel = |a: &[f64], b: &[f64]| {
        let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
        let s: f64 = b.iter().map(|y| y * y).sum();
        (d / s).sqrt()
    };
    let (eg, ej) = (rel(&g, &g_ref), rel(&j, &j_ref));
    let structure = sh.jacobian_structure();
    let mut worst = (0.0, 0);
    for c in 0..sh.num_variables() {
        let (a, b): (Vec<f64>, Vec<f64>) = structure
            .iter()
            .zip(j.iter().zip(&j_ref))
            .filter(|((_, cc), _)| *cc == c)
            .map(|(_, (&a, &b))| (a, b))
            .chain([(g[c], g_ref[c])])
            .unzip();
        let e = rel(&a, &b);
        if e > worst.0 {
            worst = (e, c);
        }
    }
    eprintln!(
        "gradient relative error {eg:.2e}, Jacobian {ej:.2e}, worst column {} {:.2e}",
        sh.variable_name(worst.1),
        worst.0
    );
    assert!(
        eg < 1e-3 && ej < 1e-3,
        "gradient {eg:.2e}, Jacobian {ej:.2e}"
    );
    assert!(
        worst.0 < 1e-2,
        "column {}: {:.2e}",
        sh.variable_name(worst.1),
        worst.0
    );
}

/// Shooting settings that cannot work are refused, naming the setting.
#[test]
fn bad_shooting_settings_are_refused() {
    let ocp = reduced_ocp(4);
    for (options, field) in [
        (
            ShootingOptions {
                num_intervals: 4,
                accuracy: 0.0,
                ..Default::default()
            },
            "integrator_accuracy",
        ),
        (
            ShootingOptions {
                num_intervals: 4,
                finite_difference_step: f64::NAN,
                ..Default::default()
            },
            "finite_difference_step",
        ),
        (
            ShootingOptions {
                num_intervals: 4,
                threads: 0,
                ..Default::default()
            },
            "threads",
        ),
    ] {
        let e = Shooting::new(ocp.clone(), options)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains(field), "{e}");
    }
    // A point with a non-finite value is an error, not a panic.
    let (mut sh, mut v) = shooting(
        &ocp,
        ShootingOptions {
            num_intervals: 4,
            ..Default::default()
        },
    );
    v[3] = f64::NAN;
    let e = sh.objective(&v).unwrap_err().to_string();
    assert!(e.contains("not finite"), "{e}");
}

/// Both methods solve the same problem: at the node states of a shooting
/// integration and its node excitations, collocation's no-countermovement,
/// lift-off and no-descent rows and its objective equal shooting's (the
/// same quantities at the same nodes).
#[test]
fn shooting_rows_are_collocations_rows_at_the_same_nodes() {
    use leap::transcription::{FiberDynamics, Scheme, Transcription, TranscriptionOptions};
    let big_n = 8;
    let ocp = reduced_ocp(big_n);
    let (mut sh, v) = shooting(
        &ocp,
        ShootingOptions {
            num_intervals: big_n,
            ..Default::default()
        },
    );
    let nodes = sh.evaluate(&v).unwrap().clone();
    let tf = sh.final_time(&v);
    let nu = ocp.nu();
    let time: Vec<f64> = (0..=big_n).map(|k| k as f64 * tf / big_n as f64).collect();
    let controls: Vec<Vec<f64>> = sh
        .node_controls(&v)
        .chunks(nu)
        .map(<[f64]>::to_vec)
        .collect();
    let mut tr = Transcription::new(
        ocp.clone(),
        TranscriptionOptions {
            num_mesh_intervals: big_n,
            scheme: Scheme::MidpointEuler,
            fiber_dynamics: FiberDynamics::Explicit,
            ..Default::default()
        },
    )
    .unwrap();
    let (x, _) = tr
        .guess_from_trajectory(&time, &nodes.states, &controls, tf)
        .unwrap();
    let mut c_tr = vec![0.0; tr.num_constraints()];
    tr.constraints(&x, &mut c_tr).unwrap();
    let mut c_sh = vec![0.0; sh.num_constraints()];
    sh.constraints(&v, &mut c_sh).unwrap();
    let rows: Vec<usize> = tr
        .no_countermovement_rows()
        .chain([tr.liftoff_row()])
        .chain(tr.no_descent_rows())
        .collect();
    assert_eq!(rows.len(), 7 + 1 + big_n);
    for (i, &r) in rows.iter().enumerate() {
        let (a, b) = (c_tr[r], c_sh[i]);
        assert!(
            (a - b).abs() <= 1e-9 * (1.0 + a.abs()),
            "{}: collocation {a}, shooting {b}",
            sh.constraint_name(i)
        );
    }
    let (jt, js) = (tr.objective(&x).unwrap(), sh.objective(&v).unwrap());
    assert!((jt - js).abs() <= 1e-12, "{jt} against {js}");
}

/// Study settings with method "shooting": a collocation setting in a
/// shooting study is refused naming it; `--method shooting` on a
/// collocation study lists the study's collocation settings as ignored and
/// takes BFGS; `--method collocation` on a shooting study takes the exact
/// Hessian back; the resampled guess is collocation's.
#[test]
fn shooting_study_settings_combine_as_documented() {
    use leap::sqp::HessianMode;
    use leap::study::{Method, Overrides, SolveStudy};
    let parse = |text: &str| SolveStudy::from_json_str(text, "s.json").unwrap();
    let refused = |text: &str| parse(text).resolve(None).unwrap_err().to_string();
    let e = refused(r#"{"method": "shooting", "guess": "bang-bang-resampled"}"#);
    assert!(e.contains("guess") && e.contains("collocation"), "{e}");
    let e = refused(r#"{"method": "shooting", "hessian_eigenvalue_floor": 1e-3}"#);
    assert!(e.contains("hessian_eigenvalue_floor"), "{e}");
    let e = refused(r#"{"shooting": {"finite_difference_step": 1e-4}}"#);
    assert!(e.contains("shooting") && e.contains("'collocation'"), "{e}");
    let e = refused(r#"{"method": "shooting", "shooting": {"derivatives": "adjoint"}}"#);
    assert!(
        e.contains("shooting.derivatives") && e.contains("forward-sensitivity"),
        "{e}"
    );
    let e = refused(
        r#"{"method": "shooting", "shooting": {"derivatives": "forward-sensitivity", "finite_difference_step": 1e-4}}"#,
    );
    assert!(
        e.contains("shooting.finite_difference_step") && e.contains("'central-difference' only"),
        "{e}"
    );
    let c = parse(r#"{"method": "shooting", "shooting": {"derivatives": "forward-sensitivity"}}"#)
        .resolve(None)
        .unwrap();
    assert_eq!(
        c.shooting.derivatives,
        leap::shooting::ShootingDerivatives::ForwardSensitivity
    );

    let mut c = parse(r#"{"mesh": {"scheme": "trapezoidal"}, "hessian": "exact"}"#)
        .resolve(None)
        .unwrap();
    c.apply(&Overrides {
        method: Some("shooting".into()),
        ..Default::default()
    })
    .unwrap();
    assert_eq!(c.method, Method::Shooting);
    assert_eq!(c.settings.hessian, HessianMode::PartitionedBfgs);
    assert_eq!(c.ignored, ["mesh.scheme", "hessian"]);

    let mut c = parse(r#"{"method": "shooting"}"#).resolve(None).unwrap();
    assert_eq!(c.settings.hessian, HessianMode::PartitionedBfgs);
    c.apply(&Overrides {
        method: Some("collocation".into()),
        ..Default::default()
    })
    .unwrap();
    assert_eq!(c.settings.hessian, HessianMode::ExactConvexified);

    let mut c = parse(r#"{"method": "shooting"}"#).resolve(None).unwrap();
    let e = c
        .apply(&Overrides {
            guess: Some("bang-bang-resampled".into()),
            ..Default::default()
        })
        .unwrap_err()
        .to_string();
    assert!(e.contains("--guess"), "{e}");
}
