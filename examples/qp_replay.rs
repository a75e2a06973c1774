//! Re-solve a QP that the SQP wrote with `qp_dump_dir` (clarabel JSON):
//! `cargo run --release --example qp_replay -- qp_iter12_failed.json [key=value ...]`
//! where the optional settings override clarabel's (e.g. `tol_feas=1e-6`,
//! `equilibrate_enable=false`, `direct_solve_method=faer`); with `TIMERS=1`
//! clarabel's internal timers are printed too.
use clarabel::solver::*;
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
