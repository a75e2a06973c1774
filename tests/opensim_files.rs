//! The files leap writes, read by OpenSim 4.6 on `models/jumper.osim`, the
//! model with both legs (`scripts/opensim_reads_leap_files.py`, data in
//! `tests/data/opensim_reads_leap_files.json`). leap integrates the
//! symmetric system, one leg carrying both; its states, controls and
//! solution files must still hold every state and control of the model,
//! or OpenSim and Moco leave the left leg at its default pose (Moco's
//! `StatesTrajectory::createFromStatesTable` refuses such a file unless
//! missing columns are allowed). The script had OpenSim load the files with
//! neither missing nor extra columns allowed and compute, from rows of the
//! states file, the centre of mass and the vertical ground force under each
//! foot; leap must compute the same from its own system state.

use assert_cmd::Command;
use leap::io::StoTable;
use leap::ode::StateEquation;
use serde_json::Value;
use std::collections::BTreeSet;

fn golden() -> Value {
    let text = std::fs::read_to_string("tests/data/opensim_reads_leap_files.json").unwrap();
    serde_json::from_str(&text).unwrap()
}

fn strings(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect()
}

fn names(v: &Value) -> BTreeSet<String> {
    strings(v).into_iter().collect()
}

fn leap(args: &[&str], out: &std::path::Path) -> std::process::Output {
    Command::cargo_bin("leap")
        .unwrap()
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

/// Today's `leap simulate` and `leap solve` files carry exactly the state
/// variables and controls OpenSim lists for the model, and the solution's
/// header splits its columns where Moco reads states and controls.
#[test]
fn leap_files_hold_every_state_and_control_of_the_model() {
    let g = golden();
    let state_variables = names(&g["state_variables"]);
    let controls = names(&g["controls"]);
    assert_eq!(state_variables.len(), 116, "10 coordinates, 48 muscles");
    assert_eq!(controls.len(), 48);
    let out = std::env::temp_dir().join(format!("leap-opensim-files-{}", std::process::id()));

    let sim = out.join("simulate");
    let o = leap(
        &[
            "simulate",
            "--controls",
            "tests/data/controls/jump_optimal.sto",
        ],
        &sim,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let states = StoTable::read(&sim.join("forward_states.sto")).unwrap();
    // The columns in the order OpenSim read them, and as many as its
    // Storage (the GUI's reader) loaded with time.
    assert_eq!(states.labels, strings(&g["states_file_columns"]));
    let storage = |f: &str| g["storage"][f]["columns"].as_u64().unwrap() as usize;
    assert_eq!(
        states.labels.len() + 1,
        storage("simulate/forward_states.sto")
    );
    let labels: BTreeSet<String> = states.labels.iter().cloned().collect();
    assert_eq!(labels.len(), states.labels.len(), "a column twice");
    assert_eq!(labels, state_variables);
    let c = StoTable::read(&sim.join("forward_controls.sto")).unwrap();
    assert_eq!(c.labels, strings(&g["controls_file_columns"]));
    assert_eq!(c.labels.len() + 1, storage("simulate/forward_controls.sto"));
    let grf = StoTable::read(&sim.join("forward_grf.mot")).unwrap();
    assert_eq!(grf.labels.len() + 1, storage("simulate/forward_grf.mot"));
    assert_eq!(c.labels.iter().cloned().collect::<BTreeSet<_>>(), controls);
    assert_eq!(c.labels.len(), controls.len());

    let sol = out.join("solve");
    let o = leap(
        &["solve", "--max-iterations", "1", "--no-forward-check"],
        &sol,
    );
    // 1: the iteration limit, results written.
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let t = StoTable::read(&sol.join("jump_solution.sto")).unwrap();
    assert_eq!(t.labels.len() + 1, storage("solve/jump_solution.sto"));
    let count = |k: &str| t.metadata[k].parse::<usize>().unwrap();
    let (ns, nc) = (count("num_states"), count("num_controls"));
    assert_eq!(ns, g["solution_num_states"].as_u64().unwrap() as usize);
    assert_eq!(nc, g["solution_num_controls"].as_u64().unwrap() as usize);
    assert_eq!(t.labels.len(), ns + nc);
    let first: BTreeSet<String> = t.labels[..ns].iter().cloned().collect();
    let rest: BTreeSet<String> = t.labels[ns..].iter().cloned().collect();
    assert_eq!(first, names(&g["solution_state_names"]));
    assert_eq!(first, state_variables);
    assert_eq!(rest, names(&g["solution_control_names"]));
    assert_eq!(rest, controls);
    let _ = std::fs::remove_dir_all(&out);
}

/// At rows of the states file OpenSim read, with both legs, leap's centre
/// of mass and per-foot vertical ground force from its system state match
/// OpenSim's. The bounds are for two implementations of one model at one
/// state (the forward test's 1e-6 is for whole integrations): positions
/// and velocities to 1e-9 m and m/s, the ground force to 1e-6 BW (at the
/// contact's stiffness, about 370 BW per metre, 1e-9 m of depth is 4e-7
/// BW).
#[test]
fn opensim_reads_both_legs_where_leap_computes_them() {
    let g = golden();
    let model = leap::model::Model::from_file("models/jumper.json").unwrap();
    let (laws, eq) = StateEquation::opensim(&model, true).unwrap();
    let system = eq.state_names();
    let columns = eq.model_state_columns();
    let weight = g["body_weight_n"].as_f64().unwrap();
    let samples = g["samples"].as_array().unwrap();
    assert!(samples.len() >= 5, "{} rows", samples.len());
    let mut ws = eq.workspace::<f64>();
    let u = vec![0.01; eq.nm()];
    let mut dx = vec![0.0; eq.nx()];
    let (mut worst_com, mut worst_grf) = (0.0f64, 0.0f64);
    for s in samples {
        let state = &s["state"];
        let value = |l: &str| {
            state[l]
                .as_f64()
                .unwrap_or_else(|| panic!("t {}: no column {l}", s["time"]))
        };
        let x: Vec<f64> = system.iter().map(|l| value(l)).collect();
        // Every column of the row, the left leg's too, is the value leap's
        // system carries for it.
        for (l, i) in &columns {
            assert_eq!(value(l), x[*i], "t {}: {l}", s["time"]);
        }
        eq.rhs(&laws, &mut ws, &x, &u, &mut dx).unwrap();
        let n = eq.nq();
        let mut mw = eq.multibody.workspace::<f64>();
        eq.multibody.set_state(&mut mw, &x[..n], &x[n..2 * n]);
        let com = eq.multibody.com_position(&mw);
        let vcom = eq.multibody.com_velocity(&mw);
        for k in 0..3 {
            let p = s["com_position"][k].as_f64().unwrap();
            let v = s["com_velocity"][k].as_f64().unwrap();
            worst_com = worst_com.max((com[k] - p).abs()).max((vcom[k] - v).abs());
        }
        let grf = leap::simulate::grf_of(&eq, &ws, &x);
        for (side, fy) in [("r", grf[1]), ("l", grf[7])] {
            let os = s[format!("vertical_grf_{side}_bw")].as_f64().unwrap();
            worst_grf = worst_grf.max((fy / weight - os).abs());
        }
    }
    eprintln!("largest differences: COM {worst_com:.1e}, vertical GRF per foot {worst_grf:.1e} BW");
    assert!(worst_com < 1e-9, "COM differs by {worst_com}");
    assert!(worst_grf < 1e-6, "vertical GRF differs by {worst_grf} BW");
}
