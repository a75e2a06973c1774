//! Time leap's interior-point QP solver on QPs the SQP wrote
//! (`sqp_jump_dump`, clarabel JSON): for each file, the median of
//! `REPEATS` (default 3) solves, its iterations and objective.
//! `cargo run --release --example ipm_bench -- DIR/*.json` (with
//! `INERTIA=1` the solver's inertia correction is on, as in
//! `--hessian exact-inertia-corrected`; `TOL` sets its tolerance, default
//! 1e-10 as the SQP's; `ORDERING=amd` orders the KKT matrix by AMD alone
//! instead of the smaller factor of AMD and nested dissection; `CHAIN=1`
//! solves the files in the order given with one solver, each QP
//! warm-started from the last, as the SQP does: consecutive QPs of one
//! solve, with REPEATS=1; `TWINS=0` keeps a range's two rows apart in the
//! KKT system instead of merging them, as the SQP does).
#[path = "common/qp_json.rs"]
mod qp_json;
use leap::sqp::ipm::{Ipm, KktOrdering};
use qp_json::csc;

/// The range rows' pairs, as the SQP names them (none with `TWINS=0`).
fn twins(a: &clarabel::algebra::CscMatrix<f64>, num_eq: usize) -> Vec<(usize, usize)> {
    if std::env::var("TWINS").as_deref() == Ok("0") {
        Vec::new()
    } else {
        Ipm::detect_twins(a, num_eq)
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let repeats: usize = std::env::var("REPEATS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let inertia = std::env::var_os("INERTIA").is_some();
    let ordering = match std::env::var("ORDERING").as_deref() {
        Ok("amd") => KktOrdering::Amd,
        _ => KktOrdering::SmallerFactor,
    };
    let tol: f64 = std::env::var("TOL")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1e-10);
    let (mut total, mut total_it) = (0.0, 0);
    let mut factor_size = None;
    let mut chain: Option<Ipm> = None;
    for path in std::env::args().skip(1) {
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path)?)?;
        let (p, a) = (csc(&json["P"])?, csc(&json["A"])?);
        let q: Vec<f64> = serde_json::from_value(json["q"].clone())?;
        let b: Vec<f64> = serde_json::from_value(json["b"].clone())?;
        let num_eq = json["cones"][0]["ZeroConeT"].as_u64().unwrap_or(0) as usize;
        let mut times = Vec::new();
        let (mut status, mut iterations, mut obj) = (None, 0, 0.0);
        for _ in 0..repeats.max(1) {
            let mut fresh;
            let s: &mut Ipm = if std::env::var_os("CHAIN").is_some() {
                if chain.is_none() {
                    chain = Some(Ipm::with_twins(
                        &p,
                        &a,
                        num_eq,
                        ordering,
                        &twins(&a, num_eq),
                    )?);
                }
                chain.as_mut().unwrap()
            } else {
                fresh = Ipm::with_twins(&p, &a, num_eq, ordering, &twins(&a, num_eq))?;
                &mut fresh
            };
            s.inertia_correction = inertia;
            s.warm_start = std::env::var_os("CHAIN").is_some();
            let t = std::time::Instant::now();
            status = Some(s.solve(&p, &a, &q, &b, tol));
            times.push(t.elapsed().as_secs_f64());
            iterations = s.iterations;
            factor_size = Some(s.size());
            let mut px = vec![0.0; q.len()];
            Ipm::p_mul(&p, &s.x, &mut px);
            obj = s.x.iter().zip(&px).map(|(x, y)| 0.5 * x * y).sum::<f64>()
                + s.x.iter().zip(&q).map(|(x, y)| x * y).sum::<f64>();
        }
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        total += median;
        total_it += iterations;
        println!(
            "{path}: {status:?}, {iterations} iterations, {:.1} ms ({:.2} ms/iteration), objective {obj:.10e}",
            1e3 * median,
            1e3 * median / iterations.max(1) as f64
        );
    }
    if let Some((kkt, factor)) = factor_size {
        println!("KKT matrix {kkt} entries (upper triangle), factor {factor}");
    }
    println!("total {:.1} ms, {total_it} iterations", 1e3 * total);
    Ok(())
}
