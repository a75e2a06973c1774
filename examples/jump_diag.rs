//! Diagnose the SQP on the jump: `cargo run --release --example jump_diag -- N ITERATIONS`
//! runs the collocation with N mesh intervals, prints the largest multipliers,
//! then (unless NOFD is set) checks the Jacobian at the last iterate by central
//! differences, naming the worst entries. `HESSIAN=exact` uses the exact
//! convexified element Hessians instead of the default model, `DELTA0=v`
//! sets the initial step bound, `EIGFLOOR=v` the relative eigenvalue floor of
//! the exact Hessians, `VGROWTH=v` the filter's local violation limit,
//! `QPDUMP=DIR` writes failing QPs there, `TRRATIO=0` turns the
//! trust-region ratio test off, `MODEL=F` solves with another model file.
use leap::nlp::Nlp;
use std::sync::Arc;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(28);
    let iterations: usize = args.next().map(|s| s.parse()).transpose()?.unwrap_or(8);
    let model_path = std::env::var("MODEL").unwrap_or("models/jumper.json".into());
    let model = leap::model::Model::from_file(std::path::Path::new(&model_path))?;
    let ocp = Arc::new(leap::ocp::JumpOcp::new(&model, Default::default())?);
    let opts = leap::transcription::TranscriptionOptions {
        num_mesh_intervals: n,
        ..Default::default()
    };
    let mut tr = leap::transcription::Transcription::new(ocp.clone(), opts)?;
    let (guess, _) = tr.bang_bang_guess()?;
    let settings = leap::sqp::SqpSettings {
        max_iterations: iterations,
        verbose: true,
        scale_variables_using_bounds: std::env::var("NOSCALE").is_err(),
        hessian: if std::env::var("HESSIAN").as_deref() == Ok("exact") {
            leap::sqp::HessianMode::ExactConvexified
        } else {
            leap::sqp::SqpSettings::default().hessian
        },
        ..Default::default()
    };
    let settings = leap::sqp::SqpSettings {
        qp_dump_dir: std::env::var_os("QPDUMP").map(Into::into),
        initial_step_bound: std::env::var("DELTA0")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(settings.initial_step_bound),
        hessian: if std::env::var("HESSIAN").as_deref() == Ok("exact") {
            leap::sqp::HessianMode::ExactConvexified
        } else {
            settings.hessian
        },
        eigenvalue_floor: std::env::var("EIGFLOOR")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(settings.eigenvalue_floor),
        trust_region_ratio: std::env::var("TRRATIO").map_or(true, |v| v != "0"),
        max_violation_growth: std::env::var("VGROWTH")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(settings.max_violation_growth),
        ..settings
    };
    let r = leap::sqp::solve_from(&mut tr, &guess, &settings);
    println!(
        "{:?} after {} iterations: {}",
        r.status, r.iterations, r.message
    );
    let x = r.x.clone();
    let mut li: Vec<usize> = (0..r.lambda.len()).collect();
    li.sort_by(|&a, &b| r.lambda[b].abs().partial_cmp(&r.lambda[a].abs()).unwrap());
    for &i in li.iter().take(12) {
        println!("lambda {:.3e} {}", r.lambda[i], tr.constraint_name(i));
    }
    let mut zi: Vec<usize> = (0..r.zeta.len()).collect();
    zi.sort_by(|&a, &b| r.zeta[b].abs().partial_cmp(&r.zeta[a].abs()).unwrap());
    for &i in zi.iter().take(8) {
        println!("zeta {:.3e} {}", r.zeta[i], tr.variable_name(i));
    }
    if std::env::var("NOFD").is_ok() {
        return Ok(());
    }
    let (nv, m) = (tr.num_variables(), tr.num_constraints());
    let pat = tr.jacobian_structure();
    let mut jv = vec![0.0; pat.len()];
    tr.jacobian_values(&x, &mut jv)?;
    let mut dense = std::collections::HashMap::new();
    for (k, &(i, j)) in pat.iter().enumerate() {
        dense.insert((i, j), jv[k]);
    }
    let mut worst: Vec<(f64, usize, usize, f64, f64)> = Vec::new();
    let mut cp = vec![0.0; m];
    let mut cm = vec![0.0; m];
    for j in 0..nv {
        let h = 1e-7 * x[j].abs().max(1.0);
        let mut xp = x.clone();
        xp[j] += h;
        tr.constraints(&xp, &mut cp)?;
        let mut xm = x.clone();
        xm[j] -= h;
        tr.constraints(&xm, &mut cm)?;
        for i in 0..m {
            let fd = (cp[i] - cm[i]) / (2.0 * h);
            let an = dense.get(&(i, j)).copied().unwrap_or(0.0);
            let err = (fd - an).abs() / fd.abs().max(1.0);
            if err > 1e-4 {
                worst.push((err, i, j, an, fd));
            }
        }
    }
    worst.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
    println!("{} entries with relative error > 1e-4", worst.len());
    for w in worst.iter().take(30) {
        println!(
            "{:.2e}  {} / {}: analytic {:.6e} fd {:.6e}",
            w.0,
            tr.constraint_name(w.1),
            tr.variable_name(w.2),
            w.3,
            w.4
        );
    }
    Ok(())
}
