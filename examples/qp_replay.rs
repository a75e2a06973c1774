//! Re-solve a QP that the SQP wrote with `qp_dump_dir` (clarabel JSON):
//! `cargo run --release --example qp_replay -- qp_iter12_failed.json [key=value ...]`
//! where the optional settings override clarabel's (e.g. `tol_feas=1e-6`,
//! `equilibrate_enable=false`, `direct_solve_method=faer`); with `TIMERS=1`
//! clarabel's internal timers are printed too; with `IPM=1` leap's own
//! interior-point solver (`leap::sqp::ipm`) solves it too, for comparison.
#[path = "common/qp_json.rs"]
mod qp_json;
use clarabel::solver::*;
use qp_json::csc;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .ok_or("usage: qp_replay FILE.json [key=value ...]")?;
    let text = std::fs::read_to_string(&path)?;
    let mut json: serde_json::Value = serde_json::from_str(&text)?;
    for kv in args {
        let (k, v) = kv.split_once('=').ok_or("settings are key=value")?;
        let value: serde_json::Value =
            serde_json::from_str(v).unwrap_or(serde_json::Value::String(v.into()));
        json["settings"][k] = value;
    }
    if std::env::var_os("IPM").is_some() {
        ipm(&json)?;
    }
    let tmp = std::env::temp_dir().join(format!("qp_replay_{}.json", std::process::id()));
    std::fs::write(&tmp, serde_json::to_string(&json)?)?;
    let mut f = std::fs::File::open(&tmp)?;
    let mut s = DefaultSolver::<f64>::load_from_file(&mut f, None)?;
    std::fs::remove_file(&tmp).ok();
    s.solve();
    let ls = &s.info.linsolver;
    println!(
        "{}: KKT non-zeros {}, factor non-zeros {}",
        ls.name, ls.nnzA, ls.nnzL
    );
    println!(
        "{:?}: {} iterations, {:.3} s, objective {:e}, r_prim {:.1e}, r_dual {:.1e}",
        s.solution.status,
        s.solution.iterations,
        s.solution.solve_time,
        s.solution.obj_val,
        s.solution.r_prim,
        s.solution.r_dual
    );
    if std::env::var_os("TIMERS").is_some() {
        if let Some(t) = &s.timers {
            t.print();
        }
    }
    Ok(())
}

/// Solve the QP with leap's interior-point method and print the outcome.
fn ipm(json: &serde_json::Value) -> Result<(), Box<dyn std::error::Error>> {
    let (p, a) = (csc(&json["P"])?, csc(&json["A"])?);
    let q: Vec<f64> = serde_json::from_value(json["q"].clone())?;
    let b: Vec<f64> = serde_json::from_value(json["b"].clone())?;
    let num_eq = json["cones"][0]["ZeroConeT"].as_u64().unwrap_or(0) as usize;
    let t = std::time::Instant::now();
    let mut s = leap::sqp::ipm::Ipm::new(&p, &a, num_eq)?;
    let setup = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let status = s.solve(&p, &a, &q, &b, 1e-10);
    let solve = t.elapsed().as_secs_f64();
    let (kkt, factor) = s.size();
    let mut px = vec![0.0; q.len()];
    leap::sqp::ipm::Ipm::p_mul(&p, &s.x, &mut px);
    let obj: f64 = s.x.iter().zip(&px).map(|(x, y)| 0.5 * x * y).sum::<f64>()
        + s.x.iter().zip(&q).map(|(x, y)| x * y).sum::<f64>();
    println!(
        "leap ipm: KKT non-zeros {kkt}, factor values {factor}; {status:?}: {} iterations, setup {setup:.3} s, solve {solve:.3} s, objective {obj:e}",
        s.iterations
    );
    Ok(())
}
