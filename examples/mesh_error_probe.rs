//! How far a solution's forward check is the mesh's and how far the
//! model's: `cargo run --release --example mesh_error_probe -- SOLUTION.sto
//! [MODEL]` integrates the solution's excitations from the squat under the
//! optimizer's dynamics and under OpenSim's (the forward check's), and each
//! mesh interval from its first node under both.
use leap::io::StoTable;
use std::path::Path;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let sol = args.next().ok_or("solution file")?;
    let model_path = args.next().unwrap_or("models/jumper.json".into());
    let model = leap::model::Model::from_file(Path::new(&model_path))?;
    // ACTIVATION_SMOOTHING=none: OpenSim's activation switch in the
    // optimizer's dynamics too (the paths stay smoothed).
    let activation_smoothing = match std::env::var("ACTIVATION_SMOOTHING").as_deref() {
        Ok("none") => None,
        Ok(b) => Some(b.parse()?),
        Err(_) => leap::ocp::OcpOptions::default().activation_smoothing,
    };
    let ocp = leap::ocp::JumpOcp::new(
        &model,
        leap::ocp::OcpOptions {
            activation_smoothing,
            ..Default::default()
        },
    )?;
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
    let a = leap::mesh_error::mesh_error(
        &ocp.eq,
        &ocp.laws,
        &mesh,
        leap::mesh_error::Excitations::Linear,
        acc,
    )?;
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
        leap::mesh_error::Excitations::Linear,
        acc,
        &|j| names[j].clone(),
    )?;
    // The whole jump from the squat under each dynamics (Dormand–Prince at
    // 1e-8): does the forward check's model differ from the optimizer's?
    let muscles: Vec<&str> = ocp
        .eq
        .muscles
        .iter()
        .map(|&m| ocp.eq.model.muscles[m].spec.name.as_str())
        .collect();
    let controls = leap::io::Controls::from_file(Path::new(&sol), &muscles)?;
    let opts = leap::simulate::SimulateOptions {
        integrator: leap::integrator::Dopri5Options {
            accuracy: 1e-8,
            ..Default::default()
        },
        t_max: t.time.last().copied().unwrap_or(1.0) + 1.0,
    };
    let h = |r: Result<(leap::simulate::JumpSummary, _), _>| match r {
        Ok((s, _)) => format!("{:.2} cm", 100.0 * s.jump_height_m),
        Err(e) => format!("failed: {e}"),
    };
    let (x0, standing) = (ocp.x0(), ocp.standing_com_height);
    println!(
        "forward jump (Dormand–Prince 1e-8): optimizer's dynamics {}, OpenSim's {}",
        h(leap::simulate::simulate_rust(
            &ocp.eq, &ocp.laws, &controls, x0, standing, opts
        )),
        h(leap::simulate::simulate_rust(
            &oeq, &olaws, &controls, x0, standing, opts
        ))
    );
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
