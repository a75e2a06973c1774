//! Local errors of a solution's mesh intervals: `cargo run --release
//! --example mesh_error_probe -- SOLUTION.sto [MODEL]`.
use leap::io::StoTable;
use std::path::Path;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let sol = args.next().ok_or("solution file")?;
    let model_path = args.next().unwrap_or("models/jumper.json".into());
    let model = leap::model::Model::from_file(Path::new(&model_path))?;
    let ocp = leap::ocp::JumpOcp::new(&model, Default::default())?;
    let t = StoTable::read(Path::new(&sol))?;
    let names = ocp.eq.state_names();
    let cnames = ocp.eq.control_names();
    let col = |n: &String| t.column(n).ok_or(format!("no column {n}"));
    let sc: Vec<Vec<f64>> = names.iter().map(col).collect::<Result<_, _>>()?;
    let cc: Vec<Vec<f64>> = cnames.iter().map(col).collect::<Result<_, _>>()?;
    let mesh = leap::transcription::MeshTrajectory {
        time: t.time.clone(),
        states: (0..t.time.len())
            .map(|k| sc.iter().map(|c| c[k]).collect())
            .collect(),
        controls: (0..t.time.len())
            .map(|k| cc.iter().map(|c| c[k]).collect())
            .collect(),
    };
    let (olaws, oeq) = leap::ode::StateEquation::opensim(&model, true)?;
    let acc: f64 = std::env::var("ACC")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1e-8);
    let a = leap::mesh_error::mesh_error(&ocp.eq, &ocp.laws, &mesh, acc)?;
    let mut ws = oeq.workspace();
    let b = leap::mesh_error::local_errors(
        |x, u, dx| {
            // OpenSim's forward simulation clamps the excitations.
            let u: Vec<f64> = u
                .iter()
                .map(|v| v.clamp(leap::laws::MIN_ACTIVATION, 1.0))
                .collect();
            oeq.rhs(&olaws, &mut ws, x, &u, dx)
                .map_err(|e| e.to_string())
        },
        &mesh,
        acc,
        &|j| names[j].clone(),
    )?;
    println!("interval t0 t1 | optimizer's dynamics: rel err, state | OpenSim's: rel err, state");
    for (x, y) in a.intervals.iter().zip(&b.intervals) {
        println!(
            "{:3} {:.4} {:.4} | {:.3e} {:40} | {:.3e} {}",
            x.interval,
            x.t_start,
            x.t_end,
            x.relative_error.unwrap_or(f64::NAN),
            x.state,
            y.relative_error.unwrap_or(f64::NAN),
            y.state
        );
    }
    Ok(())
}
