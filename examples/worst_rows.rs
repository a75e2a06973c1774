//! The constraint rows a solution violates most, by name, and its final
//! time: `cargo run --release --example worst_rows -- results/jump_solution.sto`
//! (29-node midpoint collocation of the built-in jump, `models/jumper.json`).
use leap::nlp::Nlp;
use std::sync::Arc;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: worst_rows SOLUTION.sto")?;
    // MODEL=models/jumper_jmp_strength.json for another model.
    let model_path = std::env::var("MODEL").unwrap_or_else(|_| "models/jumper.json".into());
    let model = leap::model::Model::from_file(std::path::Path::new(&model_path))?;
    let ocp = Arc::new(leap::ocp::JumpOcp::new(&model, Default::default())?);
    let mut tr = leap::transcription::Transcription::new(ocp, Default::default())?;
    let x = leap::solve::guess_from_file(&tr, std::path::Path::new(&path))?;
    let mut v: Vec<(f64, usize)> = leap::nlp::constraint_violations(&mut tr, &x)?
        .into_iter()
        .zip(0..)
        .collect();
    v.sort_by(|a, b| b.0.total_cmp(&a.0));
    for &(val, i) in v.iter().take(15) {
        println!("{val:.3e} {}", tr.constraint_name(i));
    }
    println!("tf {}", tr.final_time(&x));
    Ok(())
}
