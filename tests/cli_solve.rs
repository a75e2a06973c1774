//! `leap solve`: bad study files are refused naming the file, the field and
//! the reason; a small solve writes its files into `--out` only, and they
//! parse back with the right columns. Convergence of the full problem is
//! not asserted here (a small mesh and a few iterations keep this fast).

use assert_cmd::Command;
use leap::io::StoTable;
use std::path::{Path, PathBuf};

/// A fresh, empty directory under the system's temporary directory.
fn fresh_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("leap_cli_solve_{}_{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn bad_study_files_name_file_field_and_reason() {
    let out = fresh_dir("bad");
    for (file, field, reason) in [
        (
            "unknown_method.json",
            "method",
            "unknown method 'pseudospectral'",
        ),
        (
            "shooting_scheme.json",
            "mesh.scheme",
            "applies to method 'collocation'",
        ),
        ("shooting_hessian.json", "hessian", "no exact Hessian"),
        (
            "shooting_accuracy.json",
            "shooting.integrator_accuracy",
            "got 0.5",
        ),
        (
            "shooting_step.json",
            "shooting.finite_difference_step",
            "applies to derivatives 'central-difference' only",
        ),
        (
            "negative_intervals.json",
            "mesh.num_mesh_intervals",
            "got -3",
        ),
        ("zero_intervals.json", "mesh.num_mesh_intervals", "got 0"),
        ("missing_model.json", "model", "not found"),
        (
            "unknown_field.json",
            "mesh.num_mesh_interval",
            "unknown field",
        ),
        (
            "wrong_type.json",
            "tolerances.max_iterations",
            "invalid type",
        ),
        ("unknown_scheme.json", "mesh.scheme", "hermite-simpson"),
        ("broken_json.json", "(document)", "EOF while parsing"),
    ] {
        let path = format!("tests/data/studies/{file}");
        let o = Command::cargo_bin("leap")
            .unwrap()
            .args(["solve", &path, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{file}: {err}");
        assert!(
            err.contains(&path) && err.contains(field) && err.contains(reason),
            "{file}: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
    }
    // Nothing was written for a refused study.
    assert!(files_in(&out).is_empty(), "{:?}", files_in(&out));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn bad_command_line_values_name_the_option() {
    for (args, what) in [
        (
            vec!["solve", "--num-mesh-intervals", "1"],
            "--num-mesh-intervals",
        ),
        (vec!["solve", "--max-iterations", "0"], "--max-iterations"),
        (vec!["solve", "--scheme", "euler"], "--scheme"),
        (vec!["solve", "--guess", "no_such_guess.sto"], "--guess"),
        (vec!["solve", "--backend", "opensim"], "--backend"),
        (
            vec!["solve", "--method", "shooting", "--backend", "simbody"],
            "--backend",
        ),
        (vec!["solve", "no_such_study.json"], "no_such_study.json"),
        (
            vec!["solve", "--model", "no_such_model.json"],
            "command line: --model: model file 'no_such_model.json' not found",
        ),
        (
            vec!["bench", "solve", "--model", "no_such_model.json"],
            "--model: model file 'no_such_model.json' not found",
        ),
        // A benchmark's runs and iterations are bounded (an unbounded
        // count ran for hours without a word).
        (
            vec!["bench", "solve", "--repeats", "99999999999"],
            "--repeats <REPEATS>': at most 1000, got 99999999999",
        ),
        (
            vec!["bench", "sqp", "--repeats", "1001"],
            "--repeats <REPEATS>': at most 1000, got 1001",
        ),
        (
            vec!["bench", "methods", "--iterations", "10001"],
            "--iterations <ITERATIONS>': at most 10000, got 10001",
        ),
        (
            vec!["bench", "sqp-jump", "--iterations", "0"],
            "--iterations <ITERATIONS>': must be at least 1",
        ),
        // Negative values reach the option's own check, not clap's
        // "unexpected argument '-1'".
        (
            vec!["bench", "sqp", "--repeats", "-1"],
            "--repeats <REPEATS>': expected a whole number ≥ 1, got '-1'",
        ),
        (
            vec!["crosscheck", "--samples", "-1"],
            "--samples <SAMPLES>': expected a whole number ≥ 0, got '-1'",
        ),
        (
            vec!["crosscheck", "--seed", "-1"],
            "--seed <SEED>': expected a whole number in [0, 2^64), got '-1'",
        ),
        (
            vec!["simulate", "--accuracy", "-1e-5"],
            "--accuracy: must be positive, got -1e-5",
        ),
        (
            vec!["simulate", "--t-max", "-1e-3"],
            "--t-max: must be a time in (0, 10] s",
        ),
    ] {
        let err = refused(&args);
        assert!(err.contains(what), "{args:?}: {err}");
    }
}

/// `leap ARGS` from the crate's directory must exit 2 (bad input): its
/// standard error.
fn refused(args: &[&str]) -> String {
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    err
}

/// The keys the `--json` object must have.
const KEYS: [&str; 14] = [
    "status",
    "iterations",
    "wall_time_s",
    "jump_height_m",
    "ground_contact_time_s",
    "liftoff_com_velocity_mps",
    "peak_vertical_grf_bw",
    "peak_vertical_grf_nodes_bw",
    "max_constraint_violation",
    "dual_infeasibility",
    "forward_jump_height_m",
    "forward_check_difference_m",
    "objective",
    "output_files",
];

/// `leap solve` of the 4-interval jump from `cwd` into `out` with `args`,
/// in JSON: it must end solved or stopped (exit 0 or 1).
fn small_solve(cwd: &Path, out: &Path, args: &[&str]) -> (std::process::Output, serde_json::Value) {
    let o = Command::cargo_bin("leap")
        .unwrap()
        .current_dir(cwd)
        .args(["solve", "--num-mesh-intervals", "4", "--json", "--out"])
        .arg(out)
        .args(args)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stdout)));
    (o, v)
}

/// [`small_solve`] from a fresh working directory into a fresh output
/// directory (`<tag>_cwd`, `<tag>_out`): both, and the JSON.
fn small_solve_in_fresh_dirs(tag: &str, args: &[&str]) -> (PathBuf, PathBuf, serde_json::Value) {
    let cwd = fresh_dir(&format!("{tag}_cwd"));
    let out = fresh_dir(&format!("{tag}_out"));
    let (_, v) = small_solve(&cwd, &out, args);
    (cwd, out, v)
}

#[test]
fn small_solve_writes_only_into_out_and_files_parse_back() {
    // Run from an empty working directory: the default model is found next
    // to the crate, and nothing may appear there (no results/).
    let cwd = fresh_dir("cwd");
    let out = fresh_dir("out");
    let (o, v) = small_solve(&cwd, &out, &["--max-iterations", "3"]);
    for k in KEYS {
        assert!(v.get(k).is_some(), "missing key {k} in {v}");
    }
    // Exit code 0 exactly when the SQP succeeded.
    assert_eq!(v["success"].as_bool(), Some(o.status.code() == Some(0)));
    assert!(v["iterations"].as_u64().unwrap() <= 3);
    assert_eq!(v["num_mesh_intervals"].as_u64(), Some(4));
    let tf = v["ground_contact_time_s"].as_f64().unwrap();
    assert!((0.1..=1.0).contains(&tf), "t_f {tf}");
    // The forward check ran (Simbody and the Rust integrator).
    assert!(v["forward_jump_height_m"].as_f64().is_some(), "{v}");
    let d = v["forward_check_difference_m"].as_f64().unwrap();
    let h = v["jump_height_m"].as_f64().unwrap();
    let hf = v["forward_jump_height_m"].as_f64().unwrap();
    assert!((hf - h - d).abs() < 1e-12);
    // Agreement is within 1 cm (a 3-iteration solve may miss it).
    assert_eq!(
        v["forward_check_agrees"].as_bool(),
        Some(d.abs() <= 0.01),
        "{v}"
    );
    // The forward check is `leap simulate` of the solution's excitations:
    // OpenSim's model (tests/opensim_forward.rs), switching path points.
    // Not to the bit (the file's times, t_max and the squat's own solve
    // differ in the last digits, and the steps adapt): within 1e-6 m, where
    // the optimizer's smoothed paths put the default solve's 1.6e-4 m off.
    let sim_out = fresh_dir("forward_as_simulate");
    // `leap simulate --json <args> --controls <file>`: its jump height.
    let simulated = |args: &[&str], controls: &Path| {
        let o = Command::cargo_bin("leap")
            .unwrap()
            .args(["simulate", "--json"])
            .args(args)
            .arg("--controls")
            .arg(controls)
            .arg("--out")
            .arg(&sim_out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        s["jump_height_m"].as_f64().unwrap()
    };
    let hs = simulated(&[], &out.join("jump_solution.sto"));
    assert!(
        (hs - hf).abs() < 1e-6,
        "leap simulate {hs}, forward check {hf}"
    );

    // The open-loop sensitivity is `leap simulate` (Dormand–Prince at
    // 1e-6, as the forward check's second integration) of the solution's
    // excitations raised by the offset, within [0, 1].
    let e = &v["forward_check"]["excitation_sensitivity"];
    let offset = e["offset"].as_f64().unwrap();
    let mut raised = StoTable::read(&out.join("jump_solution.sto")).unwrap();
    let excitation: Vec<bool> = raised
        .labels
        .iter()
        .map(|l| l.starts_with("/forceset/") && l.matches('/').count() == 2)
        .collect();
    // Both legs' columns: 24 muscles per leg.
    assert_eq!(excitation.iter().filter(|&&x| x).count(), 48);
    for row in raised.rows.iter_mut() {
        for (v, _) in row.iter_mut().zip(&excitation).filter(|(_, &x)| x) {
            *v = (*v + offset).clamp(0.0, 1.0);
        }
    }
    let raised_file = sim_out.join("raised.sto");
    raised.write_sto(&raised_file).unwrap();
    let hs = simulated(
        &["--integrator", "DormandPrince", "--accuracy", "1e-6"],
        &raised_file,
    );
    let hr = e["jump_height_raised_m"].as_f64().unwrap();
    assert!((hs - hr).abs() < 1e-6, "leap simulate {hs}, raised {hr}");
    let nominal = v["forward_jump_height_rust_m"].as_f64().unwrap();
    let hl = e["jump_height_lowered_m"].as_f64().unwrap();
    let largest = e["largest_change_m"].as_f64().unwrap();
    assert_eq!(largest, (hr - nominal).abs().max((hl - nominal).abs()));
    assert!(hr != nominal && hl != nominal, "{e}");

    // The mesh error: 4 intervals of about 75 ms are far too coarse for the
    // jump (local errors of percents, the integrator's accuracy 1e-8); the
    // largest is one of the intervals', named by a solution column.
    let m = &v["mesh_error"];
    let intervals = m["intervals"].as_array().unwrap();
    assert_eq!(intervals.len(), 4, "{m}");
    let errors: Vec<f64> = intervals
        .iter()
        .map(|i| i["relative_error"].as_f64().unwrap())
        .collect();
    let worst = m["largest_relative_error"].as_f64().unwrap();
    assert_eq!(errors.iter().copied().fold(0.0, f64::max), worst);
    assert!(worst > 1e-3, "{m}");
    let k = m["worst_interval"].as_u64().unwrap() as usize;
    assert_eq!(errors[k - 1], worst);
    let sol = StoTable::read(&out.join("jump_solution.sto")).unwrap();
    let state = intervals[k - 1]["state"].as_str().unwrap();
    assert!(sol.labels.iter().any(|l| l == state), "{state}");

    assert!(files_in(&cwd).is_empty(), "{:?}", files_in(&cwd));
    let expected = [
        "jump_forward_controls.sto",
        "jump_forward_grf.mot",
        "jump_forward_states.sto",
        "jump_grf.mot",
        "jump_history.csv",
        "jump_solution.sto",
        "jump_summary.json",
    ];
    assert_eq!(files_in(&out), expected);
    let listed: Vec<String> = v["output_files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap().to_string())
        .collect();
    for f in &listed {
        assert!(Path::new(f).starts_with(&out), "{f}");
        assert!(Path::new(f).is_file(), "{f}");
    }
    assert_eq!(listed.len(), expected.len());

    // The solution: N + 1 = 5 nodes, time 0..t_f, Moco names and header.
    let sol = StoTable::read(&out.join("jump_solution.sto")).unwrap();
    assert_eq!(sol.time.len(), 5);
    assert_eq!(sol.time[0], 0.0);
    assert!((sol.time[4] - tf).abs() < 1e-12 * tf.max(1.0));
    // Every state and excitation of the model, both legs: 10 coordinates,
    // 48 muscles.
    assert_eq!(sol.labels.len(), 2 * 10 + 2 * 48 + 48);
    for l in [
        "/jointset/ground_pelvis/pelvis_ty/value",
        "/jointset/knee_r/knee_angle_r/value",
        "/jointset/knee_r/knee_angle_r/speed",
        "/jointset/knee_l/knee_angle_l/value",
        "/forceset/soleus_r/fiber_length",
        "/forceset/soleus_r/activation",
        "/forceset/soleus_l/activation",
        "/forceset/soleus_r",
        "/forceset/soleus_l",
    ] {
        assert!(sol.labels.iter().any(|x| x == l), "no column {l}");
    }
    for k in [
        "num_iterations",
        "objective",
        "solver_duration",
        "status",
        "success",
        "num_states",
        "num_controls",
    ] {
        assert!(sol.metadata.contains_key(k), "no header key {k}");
    }
    assert_eq!(sol.metadata["num_states"], "116");
    assert_eq!(sol.metadata["num_controls"], "48");
    assert_eq!(
        sol.metadata["success"],
        v["success"].as_bool().unwrap().to_string()
    );
    let obj: f64 = sol.metadata["objective"].parse().unwrap();
    assert!((obj - v["objective"].as_f64().unwrap()).abs() < 1e-9);
    // Excitations within [0, 1]; activations within [0.01, 1].
    for c in sol.column("/forceset/soleus_r").unwrap() {
        assert!((0.0..=1.0).contains(&c), "{c}");
    }

    // Ground forces: both feet in ExternalLoads columns at the nodes; the
    // squat (node 0) stands on the ground.
    let grf = StoTable::read(&out.join("jump_grf.mot")).unwrap();
    assert_eq!(grf.time.len(), 5);
    for side in ["r", "l"] {
        for c in ["vx", "vy", "vz", "px", "py", "pz"] {
            let l = format!("ground_force_{side}_{c}");
            assert!(grf.labels.contains(&l), "no column {l}");
        }
    }
    let fy0 =
        grf.column("ground_force_r_vy").unwrap()[0] + grf.column("ground_force_l_vy").unwrap()[0];
    assert!(fy0 > 0.0, "no ground force at the squat: {fy0}");

    // History: a header and one row per iteration (plus the start).
    let hist = std::fs::read_to_string(out.join("jump_history.csv")).unwrap();
    let mut lines = hist.lines();
    let header = lines.next().unwrap();
    assert!(header.starts_with("iter,objective,inf_pr,inf_du"));
    let rows: Vec<&str> = lines.collect();
    assert!(!rows.is_empty());
    // The summary's dual infeasibility is that of a recorded iterate (the
    // last, or the best one at the iteration limit).
    let inf_du = v["dual_infeasibility"].as_f64().unwrap();
    assert!(inf_du.is_finite() && inf_du >= 0.0, "{v}");
    // (Within a few ulps: serde_json's parser need not round-trip.)
    assert!(
        rows.iter().any(|r| {
            let rec: f64 = r.split(',').nth(3).unwrap().parse().unwrap();
            (rec - inf_du).abs() <= 1e-15 * inf_du.abs()
        }),
        "dual infeasibility {inf_du} is no record's"
    );

    // The forward trajectory parses with the states' names.
    let fw = StoTable::read(&out.join("jump_forward_states.sto")).unwrap();
    assert_eq!(fw.labels, sol.labels[..116].to_vec());

    // That solution is a guess for another mesh (resampled).
    let out2 = fresh_dir("out2");
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args([
            "solve",
            "--num-mesh-intervals",
            "6",
            "--max-iterations",
            "1",
            "--no-forward-check",
            "--json",
            "--guess",
        ])
        .arg(out.join("jump_solution.sto"))
        .arg("--out")
        .arg(&out2)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{err}");
    let v2: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v2["num_mesh_intervals"].as_u64(), Some(6));
    assert!(v2["forward_jump_height_m"].is_null());
    assert!(v2["guess"].as_str().unwrap().ends_with("jump_solution.sto"));
    // A solution lies within the problem's bounds: nothing projected.
    assert_eq!(v2["guess_projected_states"], serde_json::json!([]));
    let sol2 = StoTable::read(&out2.join("jump_solution.sto")).unwrap();
    assert_eq!(sol2.time.len(), 7);

    for d in [cwd, out, out2, sim_out] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// Hermite–Simpson runs with the exact element Hessians, the default (before
/// they existed for the scheme, that default stopped the solve before its
/// first iteration with status "invalid_problem").
///
/// On 8 intervals: on the 4 of [`small_solve`] (65 ms steps) the bang-bang
/// guess integrates on none of the intervals and the first line search
/// needs a step below 1e-12 (3.6e-12 before the fibre clamp's band, 9.1e-13
/// with it), which tests the line search's floor, not the Hessians.
#[test]
fn hermite_simpson_solves_with_exact_element_hessians() {
    let out = fresh_dir("hs_out");
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args([
            "solve",
            "--num-mesh-intervals",
            "8",
            "--scheme",
            "hermite-simpson",
            "--max-iterations",
            "2",
            "--no-forward-check",
            "--json",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        matches!(o.status.code(), Some(0 | 1)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["scheme"].as_str(), Some("hermite-simpson"), "{v}");
    // Named as the study names it, the SQP's mode beside it.
    assert_eq!(v["hessian"].as_str(), Some("exact"), "{v}");
    assert_eq!(v["hessian_mode"].as_str(), Some("exact_convexified"), "{v}");
    assert_ne!(v["status"].as_str(), Some("invalid_problem"), "{v}");
    assert!(v["iterations"].as_u64().unwrap() >= 1, "{v}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn study_file_settings_reach_the_solve() {
    // tests/data/studies/small.json: 4 intervals, trapezoidal, 3 iterations,
    // no forward check, name "small".
    let out = fresh_dir("study");
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args(["solve", "tests/data/studies/small.json", "--json", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["scheme"].as_str(), Some("trapezoidal"));
    assert_eq!(v["num_mesh_intervals"].as_u64(), Some(4));
    assert!(v["iterations"].as_u64().unwrap() <= 3);
    assert_eq!(
        files_in(&out),
        [
            "small_grf.mot",
            "small_history.csv",
            "small_solution.sto",
            "small_summary.json"
        ]
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_guess_without_state_columns_is_refused_naming_file_and_column() {
    let out = fresh_dir("guess");
    let guess = "tests/data/controls/jumper_missing_soleus.sto";
    let err = refused(&[
        "solve",
        "--num-mesh-intervals",
        "4",
        "--guess",
        guess,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        err.contains(guess) && err.contains("/jointset/") && err.contains("missing"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// A guess among the run's own result files (a forward check's controls,
/// which a run without the check removes as stale; a solution, which the
/// run overwrites) is refused before anything is written, and kept.
#[test]
fn a_guess_among_the_runs_result_files_is_refused_and_kept() {
    let out = fresh_dir("guess_is_result");
    for (file, extra) in [
        (
            "jump_forward_controls.sto",
            vec!["--integrate-guess", "--no-forward-check"],
        ),
        ("jump_solution.sto", vec![]),
    ] {
        let guess = out.join(file);
        std::fs::copy("tests/data/controls/jumper_missing_soleus.sto", &guess).unwrap();
        let before = std::fs::read(&guess).unwrap();
        let mut args = vec![
            "solve",
            "--max-iterations",
            "1",
            "--guess",
            guess.to_str().unwrap(),
        ];
        args.extend(extra);
        args.extend(["--out", out.to_str().unwrap()]);
        let err = refused(&args);
        assert!(
            err.contains(guess.to_str().unwrap())
                && err.contains("the guess (guess, --guess) is one of this run's result files"),
            "{err}"
        );
        assert_eq!(std::fs::read(&guess).unwrap(), before, "{file}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// A solution in radians whose header says `inDegrees=yes` (its angles
/// would be divided by 57) is refused as a guess, naming the header; the
/// same file in degrees with that header is read.
#[test]
fn a_radians_guess_headed_in_degrees_is_refused() {
    let dir = fresh_dir("radians_headed_degrees");
    solve_json(
        &args(&["--num-mesh-intervals", "4", "--max-iterations", "1"]),
        &dir.join("first"),
    );
    let mut t = leap::io::StoTable::read(&dir.join("first/jump_solution.sto")).unwrap();
    t.metadata.insert("inDegrees".into(), "yes".into());
    let wrong = dir.join("wrong.sto");
    t.write_sto(&wrong).unwrap();
    let err = refused(&[
        "solve",
        "--num-mesh-intervals",
        "4",
        "--max-iterations",
        "1",
        "--guess",
        wrong.to_str().unwrap(),
        "--out",
        dir.join("second").to_str().unwrap(),
    ]);
    assert!(
        err.contains(wrong.to_str().unwrap())
            && err.contains(
                "header 'inDegrees': the header says yes, but every joint angle lies within ±π"
            ),
        "{err}"
    );
    // In degrees, as the header says: a guess like any other.
    let m =
        leap::model::Model::from_file(concat!(env!("CARGO_MANIFEST_DIR"), "/models/jumper.json"))
            .unwrap();
    let (_, eq) = leap::ode::StateEquation::opensim(&m, false).unwrap();
    let angular = leap::io::angular_columns(&eq);
    for (k, label) in t.labels.iter().enumerate() {
        if angular.contains(label) {
            t.rows.iter_mut().for_each(|r| r[k] = r[k].to_degrees());
        }
    }
    let right = dir.join("right.sto");
    t.write_sto(&right).unwrap();
    let v = solve_json(
        &[
            "--num-mesh-intervals".as_ref(),
            "4".as_ref(),
            "--max-iterations".as_ref(),
            "1".as_ref(),
            "--guess".as_ref(),
            right.as_os_str(),
        ],
        &dir.join("third"),
    );
    assert_eq!(v["guess_projected_states"], serde_json::json!([]), "{v}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn example_study_parses() {
    let s = leap::study::SolveStudy::from_file(Path::new("models/jump_collocation.json")).unwrap();
    let c = s
        .resolve(Some(Path::new("models/jump_collocation.json")))
        .unwrap();
    assert_eq!(c.transcription.num_mesh_intervals, 28);
    assert_eq!(c.model, Path::new("models/jumper.json"));
    assert_eq!(c.method, leap::study::Method::Collocation);
    // Written out, the problem section is the built-in study's.
    // (on a coarse mesh too: eq. 4 then covers every interval)
    for n in [4, 28] {
        assert_eq!(
            c.problem.ocp_options(n),
            leap::study::SolveConfig::builtin()
                .unwrap()
                .problem
                .ocp_options(n)
        );
    }
    let p = Path::new("models/jump_shooting.json");
    let c = leap::study::SolveStudy::from_file(p)
        .unwrap()
        .resolve(Some(p))
        .unwrap();
    assert_eq!(c.method, leap::study::Method::Shooting);
    assert_eq!(c.transcription.num_mesh_intervals, 28);
    assert_eq!(c.settings.hessian, leap::sqp::HessianMode::PartitionedBfgs);
    assert_eq!(c.shooting, leap::shooting::ShootingOptions::default());
}

/// `leap bench solve STUDY`: the small study solved twice; each run's time
/// split adds up to no more than its wall time, the iteration count is the
/// study's limit, and nothing is left in the working directory.
#[test]
fn bench_solve_reports_iterations_and_time_split() {
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args([
            "bench",
            "solve",
            "tests/data/studies/small.json",
            "--repeats",
            "2",
            "--json",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let runs = v["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2);
    for r in runs {
        assert_eq!(r["iterations"].as_u64(), Some(3));
        let s = &r["split"];
        let parts: f64 = ["derivatives_s", "hessian_s", "qp_s", "line_search_s"]
            .iter()
            .map(|k| s[k].as_f64().unwrap())
            .sum();
        let wall = r["wall_time_s"].as_f64().unwrap();
        assert!(
            parts > 0.0 && parts <= wall * 1.01 + 1e-3,
            "{parts} of {wall}"
        );
    }
    assert_eq!(v["variables"].as_u64(), Some(4 * 86 + 1));
    assert!(!Path::new("results").join("small_solution.sto").exists());
}

/// `--dump-qps` writes each iteration's QP into OUT/qps/ and nowhere else,
/// as clarabel JSON that clarabel itself reads back and solves.
#[test]
fn dump_qps_writes_each_iteration_qp_into_out() {
    use clarabel::solver::SolverStatus;
    let (cwd, out, v) = small_solve_in_fresh_dirs(
        "dump",
        &["--max-iterations", "2", "--no-forward-check", "--dump-qps"],
    );
    assert!(files_in(&cwd).is_empty(), "{:?}", files_in(&cwd));
    let qps = out.join("qps");
    let dumped = files_in(&qps);
    let its = v["iterations"].as_u64().unwrap() as usize;
    assert!(its >= 1, "{v}");
    for k in 0..its {
        let name = format!("qp_iter{k}_qp.json");
        assert!(dumped.contains(&name), "{name} not in {dumped:?}");
    }
    // The dump keeps the SQP's tolerance (1e-10), where clarabel may stop
    // at its reduced one: a feasible, bounded QP either way.
    let status = crate::common::clarabel_status(&qps.join("qp_iter0_qp.json"));
    assert!(
        matches!(status, SolverStatus::Solved | SolverStatus::AlmostSolved),
        "{status:?}"
    );
    let _ = std::fs::remove_dir_all(&cwd);
    let _ = std::fs::remove_dir_all(&out);
}

/// A solve into a results directory an earlier solve of the same name
/// wrote removes the earlier result files it does not write itself (the
/// forward check's, with the check off; the QPs of iterations it did not
/// reach) and names them: none may be read as this run's. A report `leap
/// report` drew of the earlier run is kept and named as such.
#[test]
fn a_reused_results_directory_keeps_no_stale_result_files() {
    let (cwd, out, _) =
        small_solve_in_fresh_dirs("stale", &["--max-iterations", "2", "--dump-qps"]);
    let forward = [
        "jump_forward_states.sto",
        "jump_forward_controls.sto",
        "jump_forward_grf.mot",
    ];
    let before = files_in(&out);
    for f in forward {
        assert!(before.contains(&f.to_string()), "{f} not in {before:?}");
    }
    assert!(files_in(&out.join("qps")).contains(&"qp_iter1_qp.json".to_string()));
    // A report drawn of the first run's solution.
    let o = Command::cargo_bin("leap")
        .unwrap()
        .arg("report")
        .arg(out.join("jump_solution.sto"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let drawn = out.join("jump_solution_report.svg");
    assert!(drawn.is_file());
    let (_, v) = small_solve(
        &cwd,
        &out,
        &["--max-iterations", "1", "--no-forward-check", "--dump-qps"],
    );
    let after = files_in(&out);
    let removed: Vec<String> = v["removed_stale_files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap().to_string())
        .collect();
    for f in forward {
        assert!(!after.contains(&f.to_string()), "{f} still in {after:?}");
        assert!(
            removed.contains(&out.join(f).display().to_string()),
            "{f} not named in {removed:?}"
        );
    }
    assert_eq!(removed.len(), forward.len(), "{removed:?}");
    // The report is the user's: kept, and said to be of an earlier run.
    assert!(drawn.is_file());
    assert_eq!(
        v["earlier_reports"],
        serde_json::json!([drawn.display().to_string()])
    );
    for f in [
        "jump_solution.sto",
        "jump_grf.mot",
        "jump_history.csv",
        "jump_summary.json",
    ] {
        assert!(after.contains(&f.to_string()), "{f} not in {after:?}");
    }
    // The second solve takes one iteration: iteration 0's QPs only.
    let qps = files_in(&out.join("qps"));
    assert!(
        qps.contains(&"qp_iter0_qp.json".to_string())
            && qps.iter().all(|f| f.starts_with("qp_iter0_")),
        "{qps:?}"
    );
    let _ = std::fs::remove_dir_all(&cwd);
    let _ = std::fs::remove_dir_all(&out);
}

/// A guess file's column that looks like an excitation but names no muscle
/// of the model (a misspelt muscle) is named as not read, in the JSON and
/// the text summary, by both methods (as `leap simulate` warns of it); a
/// shooting guess, like a collocation one, must start at 0 (the squat).
#[test]
fn a_guess_files_unread_columns_are_named_and_shooting_guesses_start_at_zero() {
    let misspelt = "tests/data/controls/jumper_misspelt.sto";
    for (tag, method, extra) in [
        ("unread_colloc", "collocation", vec!["--integrate-guess"]),
        ("unread_shoot", "shooting", vec![]),
    ] {
        let out = fresh_dir(tag);
        let mut a = vec!["--method", method, "--guess", misspelt];
        a.extend(extra);
        a.extend(["--num-mesh-intervals", "2", "--max-iterations", "1"]);
        let v = solve_json(&args(&a), &out);
        assert_eq!(
            v["unread_guess_columns"],
            serde_json::json!(["/forceset/solues_r"]),
            "{method}: {v}"
        );
        let o = Command::cargo_bin("leap")
            .unwrap()
            .arg("solve")
            .args(&a)
            .args(["--no-forward-check", "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(
            text.contains(&format!("warning: {misspelt}: 1 column(s) name no muscle of the model and are not read: /forceset/solues_r")),
            "{method}: {text}"
        );
        // Said as soon as the guess is read too, before the SQP starts.
        let err = String::from_utf8_lossy(&o.stderr);
        let warned = err.find("1 column(s) name no muscle of the model");
        let sqp = err.find("leap solve: SQP:");
        assert!(
            warned.is_some() && sqp.is_some() && warned < sqp,
            "{method}: {err}"
        );
        let _ = std::fs::remove_dir_all(&out);
    }
    let dir = fresh_dir("shifted_guess");
    let shifted = dir.join("shifted.sto");
    let text = std::fs::read_to_string(misspelt).unwrap();
    let (head, body) = text.split_once("endheader\n").unwrap();
    let mut lines = body.lines();
    let mut shifted_text = format!("{head}endheader\n{}\n", lines.next().unwrap());
    for l in lines {
        let (t, rest) = l.split_once('\t').unwrap();
        let t: f64 = t.parse().unwrap();
        shifted_text.push_str(&format!("{}\t{rest}\n", t + 0.1));
    }
    std::fs::write(&shifted, shifted_text).unwrap();
    let err = refused(&[
        "solve",
        "--method",
        "shooting",
        "--guess",
        shifted.to_str().unwrap(),
        "--num-mesh-intervals",
        "2",
    ]);
    assert!(
        err.contains(&format!(
            "{}: time: starts at 0.1 s; a guess must start at 0 (the squat)",
            shifted.display()
        )),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A study file in a fresh directory, with the default model's absolute
/// path in place of `MODEL`.
fn study_file(tag: &str, json: &str) -> PathBuf {
    let model = std::env::current_dir().unwrap().join("models/jumper.json");
    let path = fresh_dir(tag).join("study.json");
    std::fs::write(&path, json.replace("MODEL", &model.display().to_string())).unwrap();
    path
}

/// Refused before the solve: what Simbody would abort on after it, text
/// serde leaves unread, an array it fills by position, and a mesh that
/// would overflow the allocation or run for hours.
#[test]
fn studies_that_would_abort_or_be_misread_are_refused_before_the_solve() {
    for (tag, json, field, reason) in [
        (
            "fc_acc1",
            r#"{"model": "MODEL", "forward_check": {"accuracy": 1}}"#,
            "forward_check.accuracy",
            "must be a relative error tolerance in [1e-12, 1e-2], got 1",
        ),
        (
            "fc_acc_tiny",
            r#"{"model": "MODEL", "forward_check": {"accuracy": 1e-300}}"#,
            "forward_check.accuracy",
            "must be a relative error tolerance in [1e-12, 1e-2], got 1e-300",
        ),
        (
            "trailing",
            r#"{"model": "MODEL"} garbage"#,
            "(document)",
            "trailing characters at line 1 column",
        ),
        (
            "concat",
            "{\"model\": \"MODEL\"}\n{\"mesh\": {\"num_mesh_intervals\": -4}}",
            "(document)",
            "trailing characters at line 2 column 1",
        ),
        (
            "positional",
            r#"["free text", "myname", "MODEL"]"#,
            "(document)",
            "expected a JSON object, got an array",
        ),
        (
            "problem_tf",
            r#"{"model": "MODEL", "problem": {"time_final_bounds": [0.5, 0.2]}}"#,
            "problem.time_final_bounds",
            "need 0.01 ≤ t_min ≤ t_max ≤ 10 (seconds: a push-off lasts tenths of a second), got [0.5, 0.2]",
        ),
        (
            "problem_rows",
            r#"{"model": "MODEL", "mesh": {"num_mesh_intervals": 4}, "problem": {"no_countermovement_nodes": 5}}"#,
            "problem.no_countermovement_nodes",
            "5 rows need 5 mesh intervals, the mesh has 4",
        ),
        (
            "mesh_huge",
            r#"{"model": "MODEL", "mesh": {"num_mesh_intervals": 100000}}"#,
            "mesh.num_mesh_intervals",
            "must be at most 1000, got 100000",
        ),
    ] {
        let study = study_file(tag, json);
        let out = study.parent().unwrap().join("out");
        let err = refused(&[
            "solve",
            study.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            err.contains(&format!("{}: {field}: {reason}", study.display())),
            "{tag}: {err}"
        );
        assert!(!out.exists(), "{tag}: {out:?} was created");
        std::fs::remove_dir_all(study.parent().unwrap()).ok();
    }
}

/// `leap solve ARGS --no-forward-check --json --out OUT`, which must end
/// solved or stopped (exit 0 or 1): its JSON.
fn solve_json(args: &[&std::ffi::OsStr], out: &Path) -> serde_json::Value {
    let o = Command::cargo_bin("leap")
        .unwrap()
        .arg("solve")
        .args(args)
        .args(["--no-forward-check", "--json", "--out"])
        .arg(out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{args:?}: {err}");
    serde_json::from_slice(&o.stdout).unwrap()
}

/// `--model` replaces the study's model: the paper's study on the reduced
/// model is, to the bit, the study that names the reduced model in its
/// file, and not the paper's study on the default model.
#[test]
fn the_model_option_replaces_the_studys_model() {
    let out = fresh_dir("model_option");
    let small = ["--num-mesh-intervals", "4", "--max-iterations", "2"];
    let with = |a: &[&str]| solve_json(&args(&[a, &small[..]].concat()), &out);
    let given = with(&[
        "models/jump_collocation.json",
        "--model",
        "models/jumper_reduced.json",
    ]);
    let named = with(&["models/jump_reduced.json"]);
    let default = with(&["models/jump_collocation.json"]);
    assert_eq!(given["model"], "models/jumper_reduced.json");
    for key in ["variables", "constraints", "objective", "iterations"] {
        assert_eq!(given[key], named[key], "{key}");
    }
    assert_ne!(given["variables"], default["variables"]);
    assert_ne!(given["objective"], default["objective"]);
    let _ = std::fs::remove_dir_all(&out);
}

/// Command-line words as `solve_json` takes them.
fn args<'a>(a: &[&'a str]) -> Vec<&'a std::ffi::OsStr> {
    a.iter()
        .map(|s: &&'a str| std::ffi::OsStr::new(*s))
        .collect()
}

/// The study's `problem` section reaches the problem either method
/// solves: t_f stays within its bounds (the bang-bang guess lifts off at
/// about 0.27 s, above the bound), and eq. 4's rows and the rows Ẏ_C ≥ 0
/// (one per node) come and go with their settings.
#[test]
fn problem_settings_reach_both_methods() {
    let solve = |tag: &str, method: &str, problem: &str| {
        let study = study_file(
            tag,
            &format!(
                r#"{{"model": "MODEL", "mesh": {{"num_mesh_intervals": 4}}, "problem": {problem}}}"#
            ),
        );
        let out = study.parent().unwrap().join("out");
        let v = solve_json(
            &[
                study.as_os_str(),
                "--method".as_ref(),
                method.as_ref(),
                "--max-iterations".as_ref(),
                "2".as_ref(),
            ],
            &out,
        );
        std::fs::remove_dir_all(study.parent().unwrap()).ok();
        v
    };
    for method in ["collocation", "shooting"] {
        let paper = solve(&format!("problem_paper_{method}"), method, "{}");
        assert_eq!(paper["time_final_bounds"], serde_json::json!([0.1, 1.0]));
        assert_eq!(paper["no_countermovement_nodes"].as_u64(), Some(4));
        assert_eq!(paper["no_com_descent"].as_bool(), Some(true));
        let tf = paper["final_time_s"].as_f64().unwrap();
        assert!(tf > 0.2, "{method}: t_f {tf} without the bound");

        let bounded = solve(
            &format!("problem_bounded_{method}"),
            method,
            r#"{"time_final_bounds": [0.1, 0.2], "no_countermovement_nodes": 1, "no_com_descent": false}"#,
        );
        let tf = bounded["final_time_s"].as_f64().unwrap();
        assert!(tf <= 0.2 + 1e-12, "{method}: t_f {tf} above its bound 0.2");
        assert_eq!(bounded["time_final_bounds"], serde_json::json!([0.1, 0.2]));
        assert_eq!(bounded["no_countermovement_nodes"].as_u64(), Some(1));
        assert_eq!(bounded["no_com_descent"].as_bool(), Some(false));
        // 3 fewer rows of eq. 4 and no row Ẏ_C ≥ 0 at the 4 nodes.
        let rows = |v: &serde_json::Value| v["constraints"].as_u64().unwrap();
        assert_eq!(rows(&paper) - rows(&bounded), 3 + 4, "{method}");
        assert_eq!(paper["variables"], bounded["variables"], "{method}");
    }
}

/// A solution of a 4-interval mesh as the guess of a 6-interval one:
/// resampled, its states violate the new mesh's defects most (the largest
/// violation of the first iterate is a defect row); with
/// `--integrate-guess` its excitations are integrated on the new mesh,
/// every interval's defects meet the mesh Newton tolerance (1e-10) or its
/// Newton iteration stops with a state held at its bound (the scheme would
/// take an activation below a_min), and the largest violation lies
/// elsewhere. The same from a controls file.
#[test]
fn integrate_guess_makes_a_coarser_solution_meet_the_defects() {
    let dir = fresh_dir("integrate_guess");
    let coarse = dir.join("coarse");
    solve_json(
        &args(&["--num-mesh-intervals", "4", "--max-iterations", "3"]),
        &coarse,
    );
    let solution = coarse.join("jump_solution.sto");
    let first_row = |guess: &Path, intervals: &str, integrate: bool| {
        let out = dir.join(format!("fine_{integrate}"));
        let _ = std::fs::remove_dir_all(&out);
        let mut a = args(&["--num-mesh-intervals", intervals, "--max-iterations", "1"]);
        a.extend(["--guess".as_ref(), guess.as_os_str()]);
        if integrate {
            a.push("--integrate-guess".as_ref());
        }
        let v = solve_json(&a, &out);
        let history = std::fs::read_to_string(out.join("jump_history.csv")).unwrap();
        let mut lines = history.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let row: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
        let col = header
            .iter()
            .position(|h| *h == "max_violation_constraint")
            .unwrap();
        (v, row[col].clone())
    };
    // The mesh's own rows: the defects and (implicit fibre dynamics) the
    // force balances.
    let mesh_row = |r: &str| r.starts_with("defect") || r.starts_with("force balance");
    let (resampled, worst) = first_row(&solution, "6", false);
    assert!(resampled["guess_mesh_integration"].is_null());
    assert!(mesh_row(&worst), "resampled: {worst}");
    let (integrated, worst) = first_row(&solution, "6", true);
    let m = &integrated["guess_mesh_integration"];
    assert_eq!(m["intervals"].as_u64(), Some(6));
    let (converged, at_bound) = (
        m["converged"].as_u64().unwrap(),
        m["at_bound"].as_u64().unwrap(),
    );
    assert_eq!(converged + at_bound, 6, "{m}");
    // An interval stopped at a bound is left a hair off (b = 200: 1.2e-8,
    // an activation 4e-9 below a_min), the resampled guess by O(1).
    let worst_defect = m["worst_defect"].as_f64().unwrap();
    assert!(
        worst_defect <= if at_bound == 0 { 1e-10 } else { 1e-6 },
        "{m}"
    );
    assert!(!mesh_row(&worst), "integrated: {worst}");
    // Integrated, the excitations alone are read: also a controls file's
    // (the default jump's optimal excitations, as OpenSim reads them),
    // which without --integrate-guess lacks the states.
    let controls = Path::new("tests/data/controls/jump_optimal.sto");
    let (integrated, _) = first_row(controls, "28", true);
    let m = &integrated["guess_mesh_integration"];
    assert_eq!(m["intervals"].as_u64(), Some(28), "{m}");
    let err = refused(&[
        "solve",
        "--guess",
        controls.to_str().unwrap(),
        "--out",
        dir.join("refused").to_str().unwrap(),
    ]);
    assert!(
        err.contains("missing") && err.contains("integrate_guess"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn num_mesh_intervals_beyond_the_maximum_is_refused_without_a_panic() {
    for args in [
        vec!["solve", "--num-mesh-intervals", "9223372036854775807"],
        vec!["solve", "--num-mesh-intervals", "100000"],
        vec![
            "bench",
            "solve",
            "--num-mesh-intervals",
            "28,9223372036854775807",
        ],
    ] {
        let err = refused(&args);
        assert!(
            err.contains("command line: --num-mesh-intervals: must be at most 1000"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// `leap solve --method shooting` on the reduced collocation study (8
/// intervals, 2 iterations): the problem's size, the study's collocation
/// settings listed as ignored, every file in `--out`, and the forward
/// check. A shooting point is an integration of the model, so the Simbody
/// forward check (OpenSim's activation switch and paths, not the
/// optimizer's smoothed ones) must agree within 1 cm after any number of
/// iterations.
#[test]
fn shooting_solve_writes_its_files_and_agrees_with_its_forward_check() {
    let out = fresh_dir("shooting_out");
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args([
            "solve",
            "models/jump_reduced.json",
            "--method",
            "shooting",
            "--num-mesh-intervals",
            "8",
            "--max-iterations",
            "2",
            "--json",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["method"], "shooting", "{v}");
    // 8 nodes × 10 excitations + t_f; 7 no-countermovement rows, lift-off,
    // 8 no-descent rows, 8 × (7 + 7 + 10) state bounds.
    assert_eq!(v["variables"].as_u64(), Some(81));
    assert_eq!(v["constraints"].as_u64(), Some(7 + 1 + 8 + 8 * 24));
    assert_eq!(v["hessian"], "bfgs", "{v}");
    assert_eq!(v["hessian_mode"], "partitioned_bfgs", "{v}");
    assert_eq!(v["shooting"]["derivatives"], "forward-sensitivity", "{v}");
    assert!(
        v["shooting"]["counters"]["point_jacobians"].as_u64() > Some(0),
        "{v}"
    );
    let d = v["forward_check_difference_m"].as_f64().unwrap();
    assert!(d.abs() < 0.01, "forward check {d} m from the prediction");
    // Shooting's nodes are its own integrator's: no mesh error. Its
    // prediction is the optimizer's dynamics integrated (Dormand–Prince at
    // 1e-8), so the forward check under those dynamics (at 1e-6) lands on
    // it (measured 0.06 mm apart), where OpenSim's activation switch moves
    // the forward check by 0.4 mm.
    assert!(v["mesh_error"].is_null(), "{v}");
    let own = v["forward_check"]["optimizer_dynamics_jump_height_m"]
        .as_f64()
        .unwrap();
    let h = v["jump_height_m"].as_f64().unwrap();
    assert!(
        (own - h).abs() < 2e-4,
        "predicted {h}, optimizer's dynamics {own}"
    );
    assert_eq!(
        v["ignored_study_settings"],
        serde_json::json!(["mesh.scheme", "hessian"]),
        "{v}"
    );
    let expected = [
        "jump_reduced_forward_controls.sto",
        "jump_reduced_forward_grf.mot",
        "jump_reduced_forward_states.sto",
        "jump_reduced_grf.mot",
        "jump_reduced_history.csv",
        "jump_reduced_solution.sto",
        "jump_reduced_summary.json",
    ];
    assert_eq!(files_in(&out), expected);
    let sol = StoTable::read(&out.join("jump_reduced_solution.sto")).unwrap();
    assert_eq!(sol.time.len(), 9);
    let tf = v["final_time_s"].as_f64().unwrap();
    assert!((sol.time[8] - tf).abs() < 1e-12);
    let grf = StoTable::read(&out.join("jump_reduced_grf.mot")).unwrap();
    assert!(grf.time.len() > 9, "{} rows", grf.time.len());
    let _ = std::fs::remove_dir_all(&out);
}

/// A solve stopped before the body leaves the ground (the reduced jump by
/// shooting after one iteration: the bang-bang guess still pushes at t_f)
/// says so: `lifted_off` false in the JSON, the ground contact time t_f's,
/// and a warning under the summary table, beside the one that its
/// constraints are violated beyond the paper's 1e-3.
#[test]
fn a_solve_stopped_on_the_ground_says_so() {
    let out = fresh_dir("on_ground");
    let run = |json: bool| {
        let mut c = Command::cargo_bin("leap").unwrap();
        c.args([
            "solve",
            "models/jump_reduced.json",
            "--method",
            "shooting",
            "--num-mesh-intervals",
            "8",
            "--max-iterations",
            "1",
            "--no-forward-check",
            "--out",
        ])
        .arg(&out);
        if json {
            c.arg("--json");
        }
        c.output().unwrap()
    };
    let o = run(true);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["lifted_off"], false, "{v}");
    assert!(
        v["max_constraint_violation"].as_f64().unwrap() > 0.01,
        "{v}"
    );
    assert_eq!(v["ground_contact_time_s"], v["final_time_s"], "{v}");
    let violation = v["max_constraint_violation"].as_f64().unwrap();
    let o = run(false);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("still on the ground at t_f"), "{text}");
    // Its metrics are an infeasible iterate's, which the summary says.
    assert!(
        text.contains(&format!(
            "warning: the returned iterate violates a constraint by {violation:.2e}, above the paper's 1e-3"
        )),
        "{text}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// Ctrl-C: SIGINT to process `pid`.
fn sigint(pid: u32) {
    let sent = std::process::Command::new("kill")
        .args(["-INT", &pid.to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
}

/// Ctrl-C (SIGINT) during `leap solve` stops the SQP at its next iteration
/// and writes the results of its last iterate: status
/// `user_requested_stop` (IPOPT's `User_Requested_Stop` in the solution
/// header), exit code 1, the solution, ground forces, history and summary.
#[test]
fn ctrl_c_stops_a_solve_and_writes_its_results() {
    let out = fresh_dir("interrupted");
    let bin = assert_cmd::cargo::cargo_bin("leap");
    let child = std::process::Command::new(bin)
        .args([
            "solve",
            "models/jump_shooting.json",
            "--max-iterations",
            "1000",
            "--no-forward-check",
            "--json",
            "--out",
        ])
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_secs(3));
    sigint(child.id());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["status"], "user_requested_stop", "{v}");
    assert_eq!(v["moco_status"], "User_Requested_Stop", "{v}");
    assert!(v["iterations"].as_u64().unwrap() < 1000);
    for f in [
        "jump_shooting_solution.sto",
        "jump_shooting_grf.mot",
        "jump_shooting_history.csv",
        "jump_shooting_summary.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let sol = std::fs::read_to_string(out.join("jump_shooting_solution.sto")).unwrap();
    assert!(
        sol.contains("status=User_Requested_Stop"),
        "{}",
        &sol[..400.min(sol.len())]
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// A Ctrl-C that comes while the results are being written (a double tap:
/// the first stopped the SQP) lets them be finished, with a word, instead
/// of quitting with this run's first files beside an earlier run's others.
#[test]
fn a_second_ctrl_c_while_writing_lets_the_results_finish() {
    use std::io::BufRead;
    let out = fresh_dir("interrupted_writing");
    let bin = assert_cmd::cargo::cargo_bin("leap");
    let mut child = std::process::Command::new(bin)
        .args([
            "solve",
            "--num-mesh-intervals",
            "10",
            "--max-iterations",
            "1000",
            "--out",
        ])
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let id = child.id();
    let mut lines = Vec::new();
    for line in std::io::BufReader::new(child.stderr.take().unwrap()).lines() {
        let line = line.unwrap();
        // Once in the SQP, and once in the forward check.
        if line.starts_with("leap solve: SQP:") || line.starts_with("leap solve: forward check:") {
            sigint(id);
        }
        lines.push(line);
    }
    let status = child.wait().unwrap();
    let err = lines.join("\n");
    assert_eq!(status.code(), Some(1), "{err}");
    assert!(
        err.contains("interrupted while writing the results: finishing them"),
        "{err}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("jump_summary.json")).unwrap())
            .unwrap();
    assert_eq!(v["status"], "user_requested_stop", "{v}");
    for f in v["output_files"].as_array().unwrap() {
        assert!(Path::new(f.as_str().unwrap()).is_file(), "{f} missing");
    }
    assert!(v["forward_jump_height_m"].is_number(), "{v}");
    let _ = std::fs::remove_dir_all(&out);
}

/// The default model with DeGrooteFregly2016Muscle muscles, written as
/// `dir/dg.json`.
fn write_degroote_model(dir: &Path) -> PathBuf {
    let mut model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap();
    model["forces"]["muscle_model"] = "DeGrooteFregly2016Muscle".into();
    let p = dir.join("dg.json");
    std::fs::write(&p, model.to_string()).unwrap();
    p
}

/// A forward check that fails (a DeGrooteFregly2016Muscle model, whose
/// explicit fibre dynamics Simbody cannot integrate) writes the states it
/// reached, but the plotting command `leap solve` prints does not offer
/// them as the reference: a failed check's file can hold a single row,
/// which `leap report` refuses.
#[test]
fn a_failed_forward_check_is_not_offered_as_the_plots_reference() {
    let dir = fresh_dir("dg-forward");
    let dg = write_degroote_model(&dir);
    let (_, v) = small_solve(
        &dir,
        &dir.join("guess"),
        &["--no-forward-check", "--max-iterations", "2"],
    );
    let guess = v["output_files"][0].as_str().unwrap().to_string();
    assert!(guess.ends_with("_solution.sto"), "{guess}");
    let out = dir.join("out");
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args([
            "solve",
            "--num-mesh-intervals",
            "6",
            "--max-iterations",
            "1",
        ])
        .args(["--model".as_ref(), dg.as_os_str()])
        .args(["--guess", &guess])
        .args(["--out".as_ref(), out.as_os_str()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{text}");
    assert!(text.contains("forward check (Simbody): failed"), "{text}");
    assert!(out.join("jump_forward_states.sto").is_file());
    let plots = text
        .lines()
        .find(|l| l.contains("plots: leap report"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        plots.contains("jump_solution.sto") && !plots.contains("--ref-files"),
        "{plots}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The forward check is the reader's guard against a predicted jump that
/// does not hold for the model. A solve stopped after one iteration from a
/// guess whose excitations were set to the minimum (its states kept: a
/// jump the muscles cannot make) predicts a jump its forward check misses
/// by far more than 1 cm: the JSON says `forward_check_agrees` false, and
/// the table warns in words.
#[test]
fn a_forward_check_that_misses_is_flagged_and_warned_of() {
    let (v, stdout) = solve_from_excitations("weak", |_| 0.01);
    let d = v["forward_check_difference_m"].as_f64().unwrap();
    assert!(
        d.abs() > 0.01,
        "forward check within 1 cm ({d} m): the case does not test the warning"
    );
    assert_eq!(v["forward_check_agrees"].as_bool(), Some(false), "{v}");
    assert!(
        stdout.contains("warning: the forward check misses the prediction by more than 1 cm"),
        "{stdout}"
    );
    // A body that jumps rises at lift-off: no falling warning here.
    assert!(
        v["forward_check"]["summary"]["liftoff_com_velocity_mps"]
            .as_f64()
            .unwrap()
            > 0.0,
        "{v}"
    );
    assert!(!stdout.contains("a fall, not a jump"), "{stdout}");
    assert_eq!(v["forward_liftoff_while_falling"], false, "{v}");
}

/// As `leap simulate` warns of it, a forward check whose feet leave the
/// ground under a falling body is called a fall: vas_int and soleus
/// alone, fully excited (`leap simulate`'s case; the lift-off velocity is
/// negative in the JSON).
#[test]
fn a_forward_check_that_falls_is_warned_of() {
    let (v, stdout) = solve_from_excitations("falling", |m| {
        if m.starts_with("vas_int") || m.starts_with("soleus") {
            1.0
        } else {
            0.01
        }
    });
    let vy = v["forward_check"]["summary"]["liftoff_com_velocity_mps"]
        .as_f64()
        .unwrap();
    assert!(vy < 0.0, "the case does not fall: lift-off velocity {vy}");
    assert_eq!(v["forward_liftoff_while_falling"], true, "{v}");
    assert!(
        stdout.contains(
            "in the forward check the feet left the ground with the centre of mass moving down"
        ),
        "{stdout}"
    );
}

/// One SQP iteration of the 4-interval solve from a 3-iteration solution
/// whose excitations are replaced by `excitation(muscle)` (its states
/// kept): the summary JSON and the printed table.
fn solve_from_excitations(
    name: &str,
    excitation: impl Fn(&str) -> f64,
) -> (serde_json::Value, String) {
    let (cwd, out, _) =
        small_solve_in_fresh_dirs(&format!("{name}_src"), &["--max-iterations", "3"]);
    let text = std::fs::read_to_string(out.join("jump_solution.sto")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let end = lines.iter().position(|l| l == "endheader").unwrap();
    let labels: Vec<String> = lines[end + 1].split('\t').map(String::from).collect();
    // Excitations are the columns named /forceset/<muscle> alone.
    let excitations: Vec<(usize, &str)> = (0..labels.len())
        .filter_map(|k| {
            labels[k]
                .strip_prefix("/forceset/")
                .filter(|m| !m.contains('/'))
                .map(|m| (k, m))
        })
        .collect();
    // Both legs' columns: 24 muscles per leg.
    assert_eq!(excitations.len(), 48);
    for l in lines
        .iter_mut()
        .skip(end + 2)
        .filter(|l| !l.trim().is_empty())
    {
        let mut f: Vec<String> = l.split('\t').map(String::from).collect();
        for &(k, m) in &excitations {
            f[k] = excitation(m).to_string();
        }
        *l = f.join("\t");
    }
    let guess = out.join(format!("{name}_guess.sto"));
    std::fs::write(&guess, lines.join("\n")).unwrap();
    let out2 = fresh_dir(&format!("{name}_out"));
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args([
            "solve",
            "--num-mesh-intervals",
            "4",
            "--max-iterations",
            "1",
        ])
        .arg("--guess")
        .arg(&guess)
        .arg("--out")
        .arg(&out2)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out2.join("jump_summary.json")).unwrap())
            .unwrap();
    for d in [cwd, out, out2] {
        let _ = std::fs::remove_dir_all(d);
    }
    (v, stdout)
}

/// A result file that cannot be written is found before the solve: a
/// directory where `jump_history.csv` should go had lost the summary and
/// the forward check after the whole solve, and `--dump-qps` with a file
/// named `qps` in `--out` had dumped nothing without a word. `leap
/// simulate` checks its files the same way.
#[test]
fn unwritable_result_files_are_refused_before_the_solve() {
    // `leap <args> --out <fresh dir>` with `block` made in that directory
    // first: exit 2, nothing else written; its stderr.
    let refused = |tag: &str, args: &[&str], block: &dyn Fn(&Path)| {
        let out = fresh_dir(tag);
        block(&out);
        let before = files_in(&out);
        let o = Command::cargo_bin("leap")
            .unwrap()
            .args(args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(files_in(&out), before, "{err}");
        let _ = std::fs::remove_dir_all(&out);
        err
    };
    let solve = ["solve", "--num-mesh-intervals", "4"];
    let err = refused("blocked", &solve, &|d| {
        std::fs::create_dir_all(d.join("jump_history.csv")).unwrap()
    });
    assert!(
        err.contains("cannot write the result file")
            && err.contains("jump_history.csv: a directory of that name exists"),
        "{err}"
    );
    assert!(
        !err.contains("SQP"),
        "refused after the solve started: {err}"
    );
    let err = refused("qps_file", &[&solve[..], &["--dump-qps"]].concat(), &|d| {
        std::fs::write(d.join("qps"), "").unwrap()
    });
    assert!(
        err.contains("--dump-qps: cannot create the QP directory"),
        "{err}"
    );
    let err = refused("simulate_blocked", &["simulate"], &|d| {
        std::fs::create_dir_all(d.join("forward_grf.mot")).unwrap()
    });
    assert!(
        err.contains("forward_grf.mot: a directory of that name exists"),
        "{err}"
    );
    // A results directory that cannot be created (no file can be created
    // in /proc, not even by root): refused before the solve, naming the
    // field; it had been found when the first result was written.
    for args in [&solve[..], &["simulate"]] {
        let out = format!("/proc/leap-results-{}", std::process::id());
        let o = Command::cargo_bin("leap")
            .unwrap()
            .args(args)
            .args(["--out", &out])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains("cannot create the results directory in /proc") && !err.contains("SQP"),
            "{args:?}: {err}"
        );
        if args[0] == "solve" {
            assert!(err.contains("output_directory (--out)"), "{err}");
        }
    }
}

/// A result file that cannot be written after others were (a full disk;
/// here a file-size limit that the forward check's states exceed, with
/// SIGXFSZ ignored so that the write fails instead of the process): the
/// error names what this run wrote, and the earlier run's other result
/// files are removed, so that the directory holds no mix of two solves.
#[cfg(target_os = "linux")]
#[test]
fn a_write_failing_part_way_leaves_no_mix_of_two_solves() {
    let (cwd, out, _) = small_solve_in_fresh_dirs("partial", &["--max-iterations", "2"]);
    let before = files_in(&out);
    assert!(
        before.iter().any(|f| f.contains("forward_states")),
        "{before:?}"
    );
    let solution = std::fs::read_to_string(out.join("jump_solution.sto")).unwrap();
    let forward_size = std::fs::metadata(out.join("jump_forward_states.sto"))
        .unwrap()
        .len();
    // bash's ulimit -f counts kibibytes: below the forward states, above
    // the solution.
    let limit_kib = forward_size / 1024 / 2;
    assert!(limit_kib * 1024 > solution.len() as u64 * 2);
    let o = std::process::Command::new("bash")
        .arg("-c")
        .arg(format!(
            "trap '' XFSZ; ulimit -f {limit_kib}; exec \"$0\" \"$@\""
        ))
        .arg(assert_cmd::cargo::cargo_bin("leap"))
        .args([
            "solve",
            "--num-mesh-intervals",
            "4",
            "--max-iterations",
            "3",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("jump_forward_states.sto: File too large")
            && err.contains("written before it: jump_solution.sto, jump_grf.mot, jump_history.csv")
            && err.contains("jump_summary.json"),
        "{err}"
    );
    let after = files_in(&out);
    assert_eq!(
        after,
        ["jump_grf.mot", "jump_history.csv", "jump_solution.sto"]
            .map(String::from)
            .to_vec(),
        "{err}"
    );
    // This run's solution (3 iterations, not the earlier 2).
    let now = std::fs::read_to_string(out.join("jump_solution.sto")).unwrap();
    assert_ne!(now, solution);
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(&cwd);
}

/// Where the system refuses threads (a process limit, `ulimit -u`), the
/// work of a refused thread runs on the calling one: each method's solve
/// ends as it does with threads (the scoped threads of the Jacobians, the
/// shooting derivatives and the Hessian's convexification had panicked).
/// As root, whom the limit does not bind, the solve runs as `nobody`.
#[cfg(target_os = "linux")]
#[test]
fn a_system_that_refuses_threads_gets_the_same_solve() {
    let root = std::process::Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0");
    use std::os::unix::fs::PermissionsExt;
    let dir = fresh_dir("no_threads");
    std::fs::set_permissions(&dir, PermissionsExt::from_mode(0o777)).unwrap();
    // The binary and the model where `nobody` can read them (the checkout
    // may lie under a private home).
    let (bin, model) = (dir.join("leap"), dir.join("jumper.json"));
    std::fs::copy(assert_cmd::cargo::cargo_bin("leap"), &bin).unwrap();
    std::fs::copy("models/jumper.json", &model).unwrap();
    for f in [&bin, &model] {
        std::fs::set_permissions(f, PermissionsExt::from_mode(0o755)).unwrap();
    }
    // The limit binds where the solves run: a shell there cannot fork.
    // (bash sets the limit; dash, exec'd, does not retry a failed fork.)
    let shell = |limited: bool| {
        let mut c = if limited && root {
            let mut c = std::process::Command::new("setpriv");
            c.args(["--reuid=65534", "--regid=65534", "--clear-groups", "bash"]);
            c
        } else {
            std::process::Command::new("bash")
        };
        c.arg("-c");
        c
    };
    let probe = shell(true)
        .arg("ulimit -u 1; exec sh -c 'true & wait'")
        .output()
        .unwrap();
    assert!(
        !probe.status.success(),
        "ulimit -u 1 does not bind here: {}",
        String::from_utf8_lossy(&probe.stderr)
    );
    for method in ["collocation", "shooting"] {
        let args = [
            "solve",
            "--method",
            method,
            "--num-mesh-intervals",
            "4",
            "--max-iterations",
            "2",
            "--no-forward-check",
            "--json",
            "--out",
        ];
        let run = |limited: bool| {
            let out = dir.join(format!("{method}_{limited}"));
            let limit = if limited { "ulimit -u 1; " } else { "" };
            let o = shell(limited)
                .arg(format!("{limit}exec \"$0\" \"$@\""))
                .arg(&bin)
                .args(args)
                .arg(&out)
                .arg("--model")
                .arg(&model)
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&o.stderr).to_string();
            assert_eq!(
                o.status.code(),
                Some(1),
                "{method}, limited {limited}: {err}"
            );
            let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
            v
        };
        let (free, limited) = (run(false), run(true));
        assert_eq!(limited["status"], "iteration_limit", "{method}: {limited}");
        assert_eq!(limited["objective"], free["objective"], "{method}");
        assert_eq!(
            limited["max_constraint_violation"], free["max_constraint_violation"],
            "{method}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `problem.activation_dynamics_smoothing` blends Thelen2003Muscle's switch
/// for the optimizer; on a DeGrooteFregly2016Muscle model, whose smooth
/// switch is the model's own, it is refused naming the study and the field
/// (it had been reported as applied and changed nothing) whenever the
/// study gives it, even at its default value (the 200 below); without it
/// such a model is read.
#[test]
fn activation_smoothing_is_refused_for_de_groote_muscles() {
    let dir = fresh_dir("dg-smoothing");
    write_degroote_model(&dir);
    let study = dir.join("study.json");
    std::fs::write(
        &study,
        r#"{"model": "dg.json", "problem": {"activation_dynamics_smoothing": 200}}"#,
    )
    .unwrap();
    let err = refused(&["solve", study.to_str().unwrap()]);
    assert!(
        err.contains(&format!(
            "{}: problem.activation_dynamics_smoothing: smooths Thelen2003Muscle's activation switch",
            study.display()
        )) && err.contains("DeGrooteFregly2016Muscle"),
        "{err}"
    );
    // Without the field the model is read and the solve goes on to its
    // guess (where, in leap's fibre-length state, the bang-bang jump's
    // inverted force–velocity curve overflows; README, "The model"): the
    // error says why and names what works, for each method.
    std::fs::write(&study, r#"{"model": "dg.json"}"#).unwrap();
    for (method, instead) in [
        ("collocation", "collocation states them as implicit force balances and solves from a guess file (--guess FILE"),
        ("shooting", "direct shooting integrates them at every evaluation; solve by collocation from a guess file instead (--method collocation --guess FILE"),
    ] {
        let err = refused(&["solve", study.to_str().unwrap(), "--method", method]);
        assert!(
            err.contains("initial guess")
                && !err.contains("activation_dynamics_smoothing")
                && err.contains("DeGrooteFregly2016Muscle's explicit fibre dynamics are too stiff to integrate through the jump")
                && err.contains(instead),
            "{method}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
