//! Derivatives of the shooting transcription at the bang-bang guess (or,
//! with RAMP=1, at excitations rising from 0.2 to 0.8 over the nodes):
//! central differences under several integrator accuracies and steps, then
//! forward sensitivities at several accuracies. `cargo run --release
//! --example shooting_probe -- N [MODEL]` prints each pass's time and its
//! gradient's and Jacobian's distance from the reference: central
//! differences at accuracy 1e-12 and step 1e-5, or with
//! REFERENCE=sensitivity the sensitivities at 1e-12. QUICK=1 runs only the
//! default quotients and the sensitivities; WORST=1 names the eight
//! largest differences of each pass.
use leap::nlp::Nlp;
use std::sync::Arc;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(8, |s| s.parse().unwrap_or(8));
    let file = args.get(2).map_or("models/jumper.json", |s| s.as_str());
    let model = match leap::model::Model::from_file(std::path::Path::new(file)) {
        Ok(m) => m,
        Err(e) => return eprintln!("{e}"),
    };
    let opts = leap::ocp::OcpOptions {
        no_countermovement_nodes: 7.min(n),
        ..Default::default()
    };
    let ocp = Arc::new(leap::ocp::JumpOcp::new(&model, opts).expect("jump problem"));
    use leap::shooting::ShootingDerivatives::{CentralDifference, ForwardSensitivity};
    let mut settings = vec![
        (1e-12, 1e-5, CentralDifference),
        (1e-12, 1e-4, CentralDifference),
        (1e-8, 1e-3, CentralDifference),
        (1e-8, 1e-4, CentralDifference),
        (1e-10, 1e-4, CentralDifference),
        (1e-6, 0.0, ForwardSensitivity),
        (1e-8, 0.0, ForwardSensitivity),
        (1e-10, 0.0, ForwardSensitivity),
        (1e-12, 0.0, ForwardSensitivity),
    ];
    // REFERENCE=sensitivity: distances from the sensitivities at 1e-12.
    if std::env::var("REFERENCE").as_deref() == Ok("sensitivity") {
        settings.rotate_right(1);
    }
    // QUICK=1: only the default quotients and the sensitivities.
    if std::env::var_os("QUICK").is_some() {
        settings.retain(|&(a, d, _)| d == 0.0 || (a == 1e-8 && d == 1e-3));
    }
    let mut reference: Option<(Vec<f64>, Vec<f64>)> = None;
    for (acc, delta, derivatives) in settings {
        let mut sh = leap::shooting::Shooting::new(
            ocp.clone(),
            leap::shooting::ShootingOptions {
                num_intervals: n,
                accuracy: acc,
                finite_difference_step: if delta > 0.0 { delta } else { 1e-3 },
                derivatives,
                ..Default::default()
            },
        )
        .expect("shooting");
        let (mut v, _) = sh.bang_bang_guess().expect("guess");
        // RAMP=1: excitations rising from 0.2 to 0.8 over the nodes, an
        // interior point away from the activation switch and clamp.
        if std::env::var_os("RAMP").is_some() {
            let nu = ocp.nu();
            for k in 0..n {
                for i in 0..nu {
                    v[k * nu + i] = 0.2 + 0.6 * k as f64 / (n - 1).max(1) as f64;
                }
            }
        }
        let t = std::time::Instant::now();
        let mut g = vec![0.0; v.len()];
        sh.gradient(&v, &mut g).expect("gradient");
        let mut jac = vec![0.0; sh.jacobian_structure().len()];
        sh.jacobian_values(&v, &mut jac).expect("jacobian");
        let secs = t.elapsed().as_secs_f64();
        let (gr, jr) = reference.get_or_insert_with(|| (g.clone(), jac.clone()));
        let rel = |a: &[f64], b: &[f64]| {
            let d = a
                .iter()
                .zip(b.iter())
                .map(|(x, y)| (x - y).powi(2))
                .sum::<f64>()
                .sqrt();
            d / b.iter().map(|y| y * y).sum::<f64>().sqrt()
        };
        let jmax = jac
            .iter()
            .zip(jr.iter())
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        if std::env::var_os("WORST").is_some() {
            let st = sh.jacobian_structure();
            let mut idx: Vec<usize> = (0..jac.len()).collect();
            idx.sort_by(|&a, &b| (jac[b] - jr[b]).abs().total_cmp(&(jac[a] - jr[a]).abs()));
            for &e in idx.iter().take(8) {
                let (r, c) = st[e];
                println!(
                    "  {} / {}: {:.6e} against {:.6e}",
                    sh.constraint_name(r),
                    sh.variable_name(c),
                    jac[e],
                    jr[e]
                );
            }
        }
        println!(
            "{derivatives:?} accuracy {acc:e} step {delta:e}: pass {secs:.2} s, f evals {}, gradient rel. error {:.2e}, Jacobian rel. error {:.2e}, largest entry error {:.2e}",
            sh.counters.f_evals,
            rel(&g, gr),
            rel(&jac, jr),
            jmax
        );
    }
}
