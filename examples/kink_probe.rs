//! Kinks and curvature near a solution:
//! `cargo run --release --example kink_probe -- STUDY SOLUTION.sto [H]`
//! reads a solution of the study's transcription (a `_solution.sto`) and,
//! for every variable off its bounds, steps H times the variable's bound
//! range (clamped to [1e-3, 1e3]; H default 1e-7) each way. It names the constraint entries whose
//! forward and backward slopes differ by more than 1% (a constraint that
//! bends within the step: a kink, or curvature on that scale; ROWS=text
//! prints only the constraints whose names contain it) and the smooth
//! entries whose exact Jacobian differs from the central difference.
use leap::nlp::Nlp;
use std::sync::Arc;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(study), Some(solution)) = (args.first(), args.get(1)) else {
        return Err("usage: kink_probe STUDY SOLUTION.sto [H]".into());
    };
    let c = leap::study::SolveConfig::load_with_model(Some(std::path::Path::new(study)), None)?;
    let hrel: f64 = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(1e-7);
    if !(hrel > 0.0 && hrel < 1.0) {
        return Err(
            format!("H = {hrel}: a step between 0 and 1 (of each variable's bound range)").into(),
        );
    }
    let model = leap::model::Model::from_file(&c.model)?;
    let options = leap::solve::collocation_problem_options(&c.transcription, &c.problem);
    let ocp = Arc::new(leap::ocp::JumpOcp::new(&model, options)?);
    let mut tr = leap::transcription::Transcription::new(ocp, c.transcription)?;
    let x = leap::solve::guess_from_file(&tr, std::path::Path::new(solution))?;
    let (n, m) = (tr.num_variables(), tr.num_constraints());
    let (mut xl, mut xu) = (vec![0.0; n], vec![0.0; n]);
    tr.variable_bounds(&mut xl, &mut xu);
    let mut c0 = vec![0.0; m];
    tr.constraints(&x, &mut c0)?;
    let (mut cp, mut cm) = (vec![0.0; m], vec![0.0; m]);
    let mut found: Vec<(f64, usize, usize, f64, f64)> = Vec::new();
    let pat = tr.jacobian_structure();
    let mut jv = vec![0.0; pat.len()];
    tr.jacobian_values(&x, &mut jv)?;
    let dense: std::collections::HashMap<(usize, usize), f64> =
        pat.iter().zip(&jv).map(|(&ij, &v)| (ij, v)).collect();
    let mut wrong: Vec<(f64, usize, usize, f64, f64)> = Vec::new();
    for j in 0..n {
        let h = hrel * (xu[j] - xl[j]).clamp(1e-3, 1e3);
        // A variable on its bound: the other side is outside the problem.
        if x[j] - h <= xl[j] || x[j] + h >= xu[j] {
            continue;
        }
        let mut xp = x.clone();
        xp[j] += h;
        let mut xm = x.clone();
        xm[j] -= h;
        if tr.constraints(&xp, &mut cp).is_err() || tr.constraints(&xm, &mut cm).is_err() {
            continue;
        }
        for i in 0..m {
            let (fw, bw) = ((cp[i] - c0[i]) / h, (c0[i] - cm[i]) / h);
            let jump = (fw - bw).abs() / fw.abs().max(bw.abs()).max(1e-3);
            let central = 0.5 * (fw + bw);
            let an = dense.get(&(i, j)).copied().unwrap_or(0.0);
            let err = (an - central).abs() / central.abs().max(1.0);
            if err > 1e-4 && jump < 1e-3 {
                wrong.push((err, i, j, an, central));
            }
            if jump > 1e-2 {
                found.push((jump, i, j, fw, bw));
            }
        }
    }
    let rows = std::env::var("ROWS").unwrap_or_default();
    print_largest(
        &tr,
        found,
        "entries whose one-sided slopes differ by more than 1%",
        ("forward", "backward"),
        |i| tr.constraint_name(i).contains(&rows),
        40,
    );
    print_largest(
        &tr,
        wrong,
        "smooth entries whose Jacobian value differs from the central difference by more than 1e-4",
        ("analytic", "central"),
        |_| true,
        20,
    );
    Ok(())
}

/// The entries (size, row, column, value, value) of `list`, largest first:
/// their count, then at most `limit` of the rows `keep` keeps.
fn print_largest(
    tr: &leap::transcription::Transcription,
    mut list: Vec<(f64, usize, usize, f64, f64)>,
    what: &str,
    (first, second): (&str, &str),
    keep: impl Fn(usize) -> bool,
    limit: usize,
) {
    list.sort_by(|a, b| b.0.total_cmp(&a.0));
    println!("{} {what}", list.len());
    for (size, i, j, a, b) in list.into_iter().filter(|e| keep(e.1)).take(limit) {
        println!(
            "{size:.2e}  {} / {}: {first} {a:.6e} {second} {b:.6e}",
            tr.constraint_name(i),
            tr.variable_name(j)
        );
    }
}
