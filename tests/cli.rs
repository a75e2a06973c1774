//! The `leap` command line: cross-check JSON output and clear errors.

use crate::common::refused;
use assert_cmd::Command;

#[test]
fn crosscheck_json_reports_error_and_samples() {
    let out = Command::cargo_bin("leap")
        .unwrap()
        .args([
            "crosscheck",
            "--model",
            "models/jumper_gait2392.json",
            "--samples",
            "10",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["samples"].as_u64(), Some(10));
    let e = v["max_rel_error"].as_f64().unwrap();
    assert!(e <= 1e-10, "max_rel_error {e}");
}

/// `leap crosscheck --jacobian` on the default model: exit 0 with the
/// verdict, each point's rows and Jacobian, and what lies outside the
/// pattern (the bounds are the library's, tested in
/// `transcription::simbody_backend_matches_rust_native_rows_and_jacobian`);
/// mesh options without `--jacobian`, and bad ones with it, are refused by
/// name.
#[test]
fn crosscheck_jacobian_reports_each_point() {
    let out = Command::cargo_bin("leap")
        .unwrap()
        .args([
            "crosscheck",
            "--jacobian",
            "--num-mesh-intervals",
            "12",
            "--samples",
            "1",
            "--json",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["passed"].as_bool(), Some(true));
    assert_eq!(v["num_mesh_intervals"].as_u64(), Some(12));
    let points = v["points"].as_array().unwrap();
    assert_eq!(points.len(), 2);
    assert_eq!(points[1]["checked"].as_bool(), Some(true));
    assert!(points[1]["rows"].as_f64().unwrap() <= 1e-9);
    assert!(v["outside_pattern"].as_f64().unwrap() <= 1e-7);
    for (args, what) in [
        (vec!["crosscheck", "--scheme", "trapezoidal"], "--scheme"),
        (
            vec!["crosscheck", "--jacobian", "--scheme", "euler"],
            "--scheme",
        ),
        (
            vec!["crosscheck", "--jacobian", "--num-mesh-intervals", "1"],
            "--num-mesh-intervals",
        ),
        (
            vec!["crosscheck", "--jacobian", "--num-mesh-intervals", "-2"],
            "-2",
        ),
        (
            vec![
                "crosscheck",
                "--jacobian",
                "--scheme",
                "trapezoidal",
                "--fiber-dynamics",
                "implicit",
            ],
            "--fiber-dynamics",
        ),
        (
            vec!["crosscheck", "--jacobian", "--samples", "1000"],
            "--samples",
        ),
    ] {
        let err = refused(
            Command::cargo_bin("leap").unwrap().args(&args),
            &format!("{args:?}"),
        );
        assert!(err.contains(what), "{args:?}: {err}");
    }
}

#[test]
fn bad_model_files_exit_nonzero_naming_file_and_field() {
    for (file, field) in [
        ("tests/data/broken/negative_mass.json", "bodies[0].mass"),
        ("tests/data/broken/unknown_body.json", "joints[1].parent"),
        ("tests/data/broken/broken_json.json", "EOF while parsing"),
    ] {
        let out = Command::cargo_bin("leap")
            .unwrap()
            .args(["crosscheck", "--model", file, "--json"])
            .output()
            .unwrap();
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(file) && err.contains(field), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn zero_samples_is_refused() {
    // Zero, and more than run in a quarter of an hour (1e8 ran for a day).
    for n in ["0", "100000000"] {
        let out = Command::cargo_bin("leap")
            .unwrap()
            .args(["crosscheck", "--samples", n])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&out.stderr).contains("--samples"));
    }
}

/// `leap analyze` on a states file of another system, and on one with a
/// non-finite value: exit 2 (bad input) naming the file and the column.
#[test]
fn analyze_names_the_missing_or_bad_column() {
    let dir = std::env::temp_dir().join(format!("leap-cli-analyze-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = leap::model::Model::from_file("models/jumper_gait2392.json").unwrap();
    let eq = leap::ode::StateEquation::new(&model, true, leap::path::PathSmoothing::Exact).unwrap();
    let ocp = leap::ocp::JumpOcp::new(&model, Default::default()).unwrap();
    let mut table = leap::io::StoTable {
        labels: eq.state_names(),
        time: vec![0.0, 0.01],
        rows: vec![ocp.x0().to_vec(), ocp.x0().to_vec()],
        ..Default::default()
    };
    // Out of the physical range, as `leap eval` refuses it.
    let names = eq.state_names();
    let act = names
        .iter()
        .position(|n| n.ends_with("/activation"))
        .unwrap();
    let fib = names
        .iter()
        .position(|n| n.ends_with("/fiber_length"))
        .unwrap();
    let mut ranges = Vec::new();
    for (k, v, what) in [
        (act, 7.0, "an activation must be in [0, 1], got 7"),
        (fib, -0.1, "a fibre length must be positive, got -0.1 m"),
    ] {
        let mut t = table.clone();
        t.rows[1][k] = v;
        let file = dir.join(format!("range{k}.sto"));
        t.write_sto(&file).unwrap();
        ranges.push((
            file,
            format!("column '{}': row 2 (t = 0.01): {what}", names[k]),
        ));
    }
    table.rows[1][3] = f64::NAN;
    let bad = dir.join("nan.sto");
    table.write_sto(&bad).unwrap();
    table.labels.remove(0);
    for row in &mut table.rows {
        row.remove(0);
    }
    let short = dir.join("short.sto");
    table.write_sto(&short).unwrap();
    for (file, want) in [
        (&bad, format!("column '{}'", eq.state_names()[3])),
        (&short, format!("column '{}'", eq.state_names()[0])),
        (&ranges[0].0, ranges[0].1.clone()),
        (&ranges[1].0, ranges[1].1.clone()),
    ] {
        let out = Command::cargo_bin("leap")
            .unwrap()
            .args(["analyze", file.to_str().unwrap()])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains(file.to_str().unwrap()) && err.contains(&want),
            "{err}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The `leap squat` state as a `leap eval` input, in a fresh directory.
fn squat_input(name: &str) -> (std::path::PathBuf, serde_json::Value) {
    let dir = std::env::temp_dir().join(format!("leap-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let o = Command::cargo_bin("leap")
        .unwrap()
        .arg("squat")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (dir, serde_json::from_slice(&o.stdout).unwrap())
}

/// `leap eval` refuses inputs outside their physical range (OpenSim's
/// muscles take activations and excitations in [0, 1] and positive fibre
/// lengths), both forms of one input, and a file without evaluations,
/// naming the file and the field; exit code 2.
/// A change to an input, by name, and the field its error must name.
type InputCase = (
    &'static str,
    Box<dyn Fn(&mut serde_json::Value)>,
    &'static str,
);

#[test]
fn eval_refuses_inputs_outside_their_physical_range() {
    let (dir, squat) = squat_input("eval-range");
    let cases: Vec<InputCase> = vec![
        (
            "activation",
            Box::new(|s| s["state"]["/forceset/soleus_r/activation"] = 2.0.into()),
            "/forceset/soleus_r/activation",
        ),
        (
            "fibre",
            Box::new(|s| s["state"]["/forceset/soleus_r/fiber_length"] = (-0.1).into()),
            "/forceset/soleus_r/fiber_length",
        ),
        (
            "excitation",
            Box::new(|s| s["excitation"]["/forceset/soleus_r"] = 5.0.into()),
            "/forceset/soleus_r",
        ),
        (
            "both",
            Box::new(|s| s["x"] = serde_json::json!([0.0])),
            "'state'",
        ),
        (
            "empty",
            Box::new(|s| *s = serde_json::json!([])),
            "no evaluations",
        ),
        (
            "far",
            Box::new(|s| s["state"]["/jointset/knee_r/knee_angle_r/value"] = 1e6.into()),
            "at this state",
        ),
        (
            "misspelt",
            Box::new(|s| s["states"] = s["state"].clone()),
            "states: unknown key",
        ),
    ];
    let eval = |name: &str, input: &serde_json::Value| {
        let file = dir.join(format!("{name}.json"));
        std::fs::write(&file, serde_json::to_vec(input).unwrap()).unwrap();
        Command::cargo_bin("leap")
            .unwrap()
            .args(["eval", "--input"])
            .arg(&file)
            .output()
            .unwrap()
    };
    for (name, edit, field) in cases {
        let mut s = squat.clone();
        edit(&mut s);
        let o = eval(name, &s);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains(&format!("{name}.json")) && err.contains(field),
            "{name}: {err}"
        );
    }
    // The squat itself is in range.
    let o = eval("ok", &squat);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // A key given twice (JSON readers keep one of them) is refused.
    let text = serde_json::to_string(&squat).unwrap();
    let twice = text.replacen(
        "\"/forceset/add_long_r\":",
        "\"/forceset/add_long_r\":5,\"/forceset/add_long_r\":",
        1,
    );
    assert_ne!(twice, text);
    let file = dir.join("twice.json");
    std::fs::write(&file, twice).unwrap();
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args(["eval", "--input"])
        .arg(&file)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("twice.json: excitation: key '/forceset/add_long_r' given twice"),
        "{err}"
    );
    // A NaN, as Python's json.dump writes it, is named: JSON has none.
    let nan = text.replacen(
        "\"/forceset/add_long_r\":",
        "\"/forceset/add_long_r\":NaN,\"x\":",
        1,
    );
    assert_ne!(nan, text);
    let file = dir.join("nan.json");
    std::fs::write(&file, nan).unwrap();
    let err = eval_refused(&file, "a NaN literal");
    assert!(
        err.contains("nan.json: line 1") && err.contains("JSON has no NaN or Infinity"),
        "{err}"
    );
    // The symmetric system's input given with --full lacks the left leg.
    let err = refused(
        Command::cargo_bin("leap")
            .unwrap()
            .args(["eval", "--full", "--input"])
            .arg(dir.join("ok.json")),
        "a symmetric input with --full",
    );
    assert!(
        err.contains("ok.json: state: missing '") && err.contains("`leap squat --full` prints one"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `leap eval` evaluates a state OpenSim would evaluate but warns of what
/// makes it unusual: a coordinate outside its range (the knee bent 0.2 rad
/// past the model's limit) and a fibre below its minimum length (held
/// there), on stderr and in the JSON's `warnings`; the squat has none.
#[test]
fn eval_warns_of_coordinates_outside_their_range_and_clamped_fibres() {
    let (dir, squat) = squat_input("eval-warn");
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap();
    let range = model["coordinates"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == "knee_angle_r")
        .unwrap()["range"]
        .clone();
    let lo = range[0].as_f64().unwrap();
    let eval = |name: &str, input: &serde_json::Value| {
        let file = dir.join(format!("{name}.json"));
        std::fs::write(&file, serde_json::to_vec(input).unwrap()).unwrap();
        let o = Command::cargo_bin("leap")
            .unwrap()
            .args(["eval", "--json", "--input"])
            .arg(&file)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (String::from_utf8_lossy(&o.stderr).to_string(), v)
    };
    let (err, v) = eval("squat", &squat);
    assert!(!err.contains("warning"), "{err}");
    assert_eq!(v["warnings"], serde_json::json!([]));
    let mut s = squat.clone();
    s["state"]["/jointset/knee_r/knee_angle_r/value"] = (lo - 0.2).into();
    s["state"]["/forceset/soleus_r/fiber_length"] = 1e-4.into();
    let (err, v) = eval("outside", &s);
    let w = v["warnings"].as_array().unwrap();
    assert_eq!(w.len(), 2, "{w:?}");
    let knee = format!("lies outside its range [{lo}, {}] rad", range[1]);
    for text in [w[0].as_str().unwrap(), &err] {
        assert!(
            text.contains("/jointset/knee_r/knee_angle_r/value") && text.contains(&knee),
            "{text}"
        );
    }
    let fibre = w[1].as_str().unwrap();
    assert!(
        fibre.starts_with("/forceset/soleus_r/fiber_length = 0.0001 m is 0.002 optimal fibre lengths, outside [0.2, 2]")
            && fibre.contains("; and below the minimum fibre length"),
        "{fibre}"
    );
    assert!(
        err.contains(fibre) && err.contains("outside.json: evaluation 0"),
        "{err}"
    );
    // The feet half a metre into the ground (pelvis_ty lowered): meganewtons
    // of contact force, warned of with the deepest sphere.
    let mut s = squat.clone();
    let ty = "/jointset/ground_pelvis/pelvis_ty/value";
    s["state"][ty] = (s["state"][ty].as_f64().unwrap() - 0.5).into();
    let (err, v) = eval("sunk", &s);
    let w: Vec<&str> = v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|w| w.as_str())
        .collect();
    assert!(
        w.iter()
            .any(|w| w.contains("mm deep in the ground, its centre below the surface")),
        "{w:?}"
    );
    assert!(err.contains("mm deep in the ground"), "{err}");
    // A knee at 1e10 rad breaks the mass matrix before any force: the
    // refusal names the coordinate, not the model's masses alone.
    let mut s = squat.clone();
    s["state"]["/jointset/knee_r/knee_angle_r/value"] = 1e10.into();
    let file = dir.join("far_knee.json");
    std::fs::write(&file, serde_json::to_vec(&s).unwrap()).unwrap();
    let err = eval_refused(&file, "a knee at 1e10 rad");
    assert!(
        err.contains("no motion at this state: /jointset/knee_r/knee_angle_r/value = 1e10 rad")
            && err.contains(&knee),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Integrator accuracies Simbody cannot take (it asserts at 1 and above)
/// or that never finish are refused before the simulation, negative ones
/// read as numbers, not flags; exit code 2 naming the field.
#[test]
fn simulate_refuses_accuracies_outside_their_range() {
    for args in [
        &["--accuracy", "1"][..],
        &["--accuracy", "10", "--integrator", "CPodes"],
        &["--accuracy", "-1"],
        &["--accuracy", "1e-300"],
        &["--accuracy", "1e-12", "--integrator", "ExplicitEuler"],
    ] {
        let o = Command::cargo_bin("leap")
            .unwrap()
            .arg("simulate")
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("accuracy:"), "{args:?}: {err}");
    }
}

/// A results directory whose name a regular file holds is named as such
/// (the OS says only "File exists").
/// `leap simulate` and `leap solve` (before its squat and guess) name a
/// file that stands where the results directory should be, and leave it.
#[test]
fn results_directory_taken_by_a_file_is_named() {
    let (dir, _) = squat_input("out-file");
    let file = dir.join("taken");
    std::fs::write(&file, "x").unwrap();
    for (args, want) in [
        (
            &["simulate", "--t-max", "0.05"][..],
            "a file of that name exists",
        ),
        (
            &["solve", "models/jump_reduced.json"],
            "output_directory (--out): cannot create the results directory: a file of that name exists",
        ),
    ] {
        let err = refused(
            Command::cargo_bin("leap")
                .unwrap()
                .args(args)
                .arg("--out")
                .arg(&file),
            &format!("{args:?}"),
        );
        assert!(
            err.contains("taken") && err.contains(want),
            "{args:?}: {err}"
        );
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn zero_repeats_are_refused() {
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args(["bench", "solve", "--repeats", "0"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--repeats") && err.contains("at least 1"),
        "{err}"
    );
}

/// `leap eval --input <file>`, refused: its stderr.
fn eval_refused(file: &std::path::Path, what: &str) -> String {
    refused(
        Command::cargo_bin("leap")
            .unwrap()
            .args(["eval", "--input"])
            .arg(file),
        what,
    )
}

/// A CSV as spreadsheets write it (byte-order mark, quoted labels, a
/// leading time column, which is not read) reads as the same evaluation
/// as the JSON input.
#[test]
fn eval_reads_a_spreadsheet_csv() {
    let (dir, squat) = squat_input("eval-csv");
    let (st, ex) = (
        squat["state"].as_object().unwrap(),
        squat["excitation"].as_object().unwrap(),
    );
    let labels: Vec<String> = st
        .keys()
        .chain(ex.keys())
        .map(|k| format!("\"{k}\""))
        .collect();
    let values: Vec<String> = st
        .values()
        .chain(ex.values())
        .map(|v| format!("{:e}", v.as_f64().unwrap()))
        .collect();
    let csv = dir.join("squat.csv");
    std::fs::write(
        &csv,
        format!(
            "\u{feff}\"time\",{}\n0.5,{}\n",
            labels.join(","),
            values.join(",")
        ),
    )
    .unwrap();
    let json = dir.join("squat.json");
    std::fs::write(&json, serde_json::to_vec(&squat).unwrap()).unwrap();
    let run = |f: &std::path::Path| -> serde_json::Value {
        let o = Command::cargo_bin("leap")
            .unwrap()
            .args(["eval", "--json", "--input"])
            .arg(f)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    assert_eq!(
        run(&csv)["state_derivative"],
        run(&json)["state_derivative"]
    );
    // As in the JSON form, a column named twice or unknown is an error.
    for (name, extra_label, want) in [
        ("dup", labels[0].clone(), "appears twice"),
        ("unknown", "\"foo\"".to_string(), "unknown column 'foo'"),
    ] {
        let bad = dir.join(format!("{name}.csv"));
        std::fs::write(
            &bad,
            format!(
                "{},{extra_label}\n{},0\n",
                labels.join(","),
                values.join(",")
            ),
        )
        .unwrap();
        let err = eval_refused(&bad, name);
        assert!(
            err.contains("header") && err.contains(want),
            "{name}: {err}"
        );
    }
    // A semicolon-separated export, and a pre-4.0 name (OpenSim 3's
    // `soleus_r` for the excitation): refused with what was meant.
    let pre_4: Vec<String> = labels
        .iter()
        .map(|l| l.replace("/forceset/soleus_r\"", "soleus_r\""))
        .collect();
    for (name, text, want) in [
        (
            "semicolons",
            format!("{}\n{}\n", labels.join(";"), values.join(";")),
            "separated by semicolons",
        ),
        (
            "pre-4",
            format!("{}\n{}\n", pre_4.join(","), values.join(",")),
            "'soleus_r' (column",
        ),
    ] {
        let bad = dir.join(format!("{name}.csv"));
        std::fs::write(&bad, text).unwrap();
        let err = eval_refused(&bad, name);
        assert!(err.contains(want), "{name}: {err}");
        if name == "pre-4" {
            assert!(err.contains("'/forceset/soleus_r'"), "{err}");
        }
    }
    // In the JSON form, an excitation put under "state" is named as one.
    let mut misplaced = squat.clone();
    let v = misplaced["excitation"]
        .as_object_mut()
        .unwrap()
        .remove("/forceset/soleus_r")
        .unwrap();
    misplaced["state"]["/forceset/soleus_r"] = v;
    let bad = dir.join("misplaced.json");
    std::fs::write(&bad, misplaced.to_string()).unwrap();
    let err = eval_refused(&bad, "misplaced");
    assert!(
        err.contains("state./forceset/soleus_r: unknown name: '/forceset/soleus_r' is an excitation: it goes under 'excitation'"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_closed_or_full_standard_output_is_an_error_not_a_panic() {
    // `leap ... | head` closes the pipe; /dev/full refuses every write.
    for args in [
        vec!["squat", "--model", "models/jumper_reduced.json"],
        vec![
            "crosscheck",
            "--model",
            "models/jumper_reduced.json",
            "--samples",
            "1",
            "--json",
        ],
    ] {
        let full = std::fs::File::create("/dev/full").unwrap();
        let out = std::process::Command::new(assert_cmd::cargo::cargo_bin("leap"))
            .args(&args)
            .stdout(full)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{args:?}: {err}");
        assert!(
            err.contains("writing to standard output") && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}

/// A closed or full standard error (`2>&1 | head`, `2>/dev/full`) is no
/// reason to panic: the error or warning that cannot be shown is dropped,
/// and the exit code is the run's own (it had been 101, a panic in
/// `eprintln!`).
#[test]
fn a_full_standard_error_keeps_the_runs_exit_code() {
    let dir = std::env::temp_dir().join(format!("leap-cli-stderr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.to_str().unwrap();
    // A run that warns on standard error (no lift-off by t_max), and one
    // whose standard output fails too (its error goes to standard error).
    let warns = ["simulate", "--t-max", "0.05", "--out", out];
    let run = |args: &[&str], stdout_full: bool| {
        let full = || std::fs::File::create("/dev/full").unwrap();
        let mut c = std::process::Command::new(assert_cmd::cargo::cargo_bin("leap"));
        c.args(args).stderr(full());
        if stdout_full {
            c.stdout(full());
        } else {
            c.stdout(std::process::Stdio::null());
        }
        c.status().unwrap().code()
    };
    let normal = Command::cargo_bin("leap")
        .unwrap()
        .args(warns)
        .output()
        .unwrap();
    assert!(
        String::from_utf8_lossy(&normal.stderr).contains("warning"),
        "the run should warn: {}",
        String::from_utf8_lossy(&normal.stderr)
    );
    assert_eq!(run(&warns, false), normal.status.code());
    assert_eq!(run(&warns, true), Some(3));
    assert_eq!(
        run(&["squat", "--model", "models/jumper_reduced.json"], true),
        Some(3)
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `leap analyze` warns when the file breaks Newton's second law (impulse
/// against momentum change): times scaled by 1e3 had printed an impulse
/// a thousand times the momentum change without a word. A simulated jump's
/// states agree.
#[test]
fn analyze_warns_when_impulse_and_momentum_disagree() {
    let dir = std::env::temp_dir().join(format!("leap-cli-newton-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args(["simulate", "--integrator", "DormandPrince", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let states = dir.join("forward_states.sto");
    let mut slow = leap::io::StoTable::read(&states).unwrap();
    for t in &mut slow.time {
        *t *= 1e3;
    }
    let slow_file = dir.join("slow.sto");
    slow.write_sto(&slow_file).unwrap();
    for (file, warned) in [(&states, false), (&slow_file, true)] {
        for json in [false, true] {
            let o = Command::cargo_bin("leap")
                .unwrap()
                .arg("analyze")
                .arg(file)
                .args(json.then_some("--json"))
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(o.status.success(), "{err}");
            assert_eq!(
                err.contains("warning: the impulse and the momentum change differ"),
                warned,
                "{file:?}: {err}"
            );
            if json {
                let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
                let r = v["newton_mismatch"].as_f64().unwrap();
                assert_eq!(r > 0.25, warned, "{r}");
            }
        }
    }
    // A window must be two finite times, the first below the second.
    for (window, want) in [
        (
            ["0", "inf"],
            "command line: --window: START and END must be finite times (s), got 0 and inf",
        ),
        (
            ["1e308", "1e309"],
            "command line: --window: START and END must be finite times (s), got 1e308 and inf",
        ),
        (
            ["0.2", "0.1"],
            "command line: --window: START must be below END, got 0.2 and 0.1",
        ),
    ] {
        let o = Command::cargo_bin("leap")
            .unwrap()
            .arg("analyze")
            .arg(&states)
            .arg("--window")
            .args(window)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(want),
            "{window:?}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `leap eval` reads the left leg's columns of leap's files as checks, as
/// the `.sto` readers do: equal to their right partners' they give the
/// same evaluation; different, or not a number, they are refused, naming
/// the column, its partner and the reason, in both input forms.
#[test]
fn eval_checks_the_left_legs_columns() {
    let (dir, squat) = squat_input("eval-left");
    let (knee_r, knee_l) = (
        "/jointset/knee_r/knee_angle_r/value",
        "/jointset/knee_l/knee_angle_l/value",
    );
    let knee = squat["state"][knee_r].as_f64().unwrap();
    let soleus = squat["excitation"]["/forceset/soleus_r"].clone();
    let with = |k: f64, s: serde_json::Value| {
        let mut v = squat.clone();
        v["state"][knee_l] = k.into();
        v["excitation"]["/forceset/soleus_l"] = s;
        v
    };
    let run = |name: &str, v: &serde_json::Value| {
        let f = dir.join(format!("{name}.json"));
        std::fs::write(&f, serde_json::to_vec(v).unwrap()).unwrap();
        let mut cmd = Command::cargo_bin("leap").unwrap();
        cmd.args(["eval", "--json", "--input"]).arg(f);
        cmd
    };
    let out = |v: &serde_json::Value, name: &str| -> serde_json::Value {
        let o = run(name, v).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    assert_eq!(
        out(&with(knee, soleus.clone()), "same")["state_derivative"],
        out(&squat, "plain")["state_derivative"]
    );
    let err = refused(&mut run("bent", &with(-1.0, soleus.clone())), "bent");
    assert!(
        err.contains(&format!("{knee_l}: -1 differs from {knee_r} ({knee})"))
            && err.contains("its right leg's")
            && err.contains("or give --full to read both legs, on the full system"),
        "{err}"
    );
    let err = refused(&mut run("text", &with(knee, "x".into())), "text");
    assert!(
        err.contains("excitation./forceset/soleus_l: not a finite number"),
        "{err}"
    );
    // The CSV form.
    let (st, ex) = (
        squat["state"].as_object().unwrap(),
        squat["excitation"].as_object().unwrap(),
    );
    let labels: Vec<&str> = st.keys().chain(ex.keys()).map(|k| k.as_str()).collect();
    let values: Vec<String> = st
        .values()
        .chain(ex.values())
        .map(|v| v.as_f64().unwrap().to_string())
        .collect();
    for (left, want) in [
        (knee.to_string(), None),
        (
            "-1".to_string(),
            Some(format!(
                "line 2, column '{knee_l}': -1 differs from {knee_r}"
            )),
        ),
        (
            "abc".to_string(),
            Some(format!("line 2, column '{knee_l}': 'abc' is not a number")),
        ),
    ] {
        let f = dir.join("left.csv");
        std::fs::write(
            &f,
            format!(
                "{},{knee_l}\n{},{left}\n",
                labels.join(","),
                values.join(",")
            ),
        )
        .unwrap();
        let mut cmd = Command::cargo_bin("leap").unwrap();
        cmd.args(["eval", "--json", "--input"]).arg(&f);
        match want {
            None => assert!(cmd.output().unwrap().status.success()),
            Some(w) => {
                let err = refused(&mut cmd, &left);
                assert!(err.contains(&w), "{err}");
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// An error that echoes its input (here an unknown `leap eval` CSV column
/// of 200,000 characters) is bounded for the terminal: the file and the
/// reason kept, the middle left out with its length.
#[test]
fn an_error_echoing_a_huge_input_is_bounded() {
    let (dir, _) = squat_input("eval-huge-label");
    let file = dir.join("huge.csv");
    let label = "x".repeat(200_000);
    std::fs::write(&file, format!("{label}\n0\n")).unwrap();
    let err = eval_refused(&file, "huge label");
    assert!(
        err.chars().count() < leap::io::MAX_MESSAGE_CHARS + 100,
        "{} characters",
        err.chars().count()
    );
    assert!(err.contains(file.to_str().unwrap()), "{err}");
    assert!(err.contains("characters left out]"), "{err}");
    assert!(
        err.trim_end().ends_with(
            "not a state or excitation of this model's system (`leap squat` prints the names)"
        ),
        "{}",
        &err[err.len().saturating_sub(300)..]
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Messages the second fuzzing round found unclear: CSV content in a file
/// not named .csv is read as JSON, and the error says so (a .json file's
/// does not); a model without poses says it has none; `leap bench
/// state-equation` on a model without a squat says so, as the other
/// commands do, not that it misses the jumper's pelvis coordinate.
#[test]
fn unclear_messages_of_the_second_fuzzing_round_say_what_happened() {
    let dir = std::env::temp_dir().join(format!("leap-cli-fuzz2-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let txt = dir.join("input.txt");
    std::fs::write(&txt, "a,b\n1,2\n").unwrap();
    let json = dir.join("input.json");
    std::fs::write(&json, "a,b\n1,2\n").unwrap();
    let err = eval_refused(&txt, "csv as txt");
    assert!(
        err.contains(&format!("{}: line 1, column 1: ", txt.display()))
            && err.contains("(read as JSON: only a file whose name ends in .csv is read as CSV)"),
        "{err}"
    );
    let err = eval_refused(&json, "csv as json");
    assert!(
        err.contains(&format!("{}: line 1, column 1: ", json.display()))
            && !err.contains("read as JSON"),
        "{err}"
    );
    // A storage file (a solution) is pointed to `leap analyze`.
    let err = eval_refused(
        std::path::Path::new("tests/data/controls/jump_optimal.sto"),
        "storage file",
    );
    assert!(
        err.contains("a storage file is not an input of `leap eval`")
            && err.contains("`leap analyze` reads a states .sto"),
        "{err}"
    );
    let err = refused(
        Command::cargo_bin("leap").unwrap().args([
            "paths",
            "--model",
            "models/double_pendulum.json",
        ]),
        "paths",
    );
    assert!(
        err.contains(
            "models/double_pendulum.json: poses: no pose 'squat' (the model has no poses)"
        ),
        "{err}"
    );
    let o = Command::cargo_bin("leap")
        .unwrap()
        .args([
            "bench",
            "state-equation",
            "--model",
            "models/double_pendulum.json",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("the model has no 'squat' pose to start from"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The model file an OpenSim user has at hand is an `.osim`: refused
/// naming it as XML and pointing to leap's JSON models (it had read
/// "expected value at line 1 column 1").
#[test]
fn an_osim_model_is_refused_pointing_to_the_json_models() {
    for args in [
        vec!["squat", "--model", "models/jumper.osim"],
        vec!["simulate", "--model", "models/jumper.osim", "--out"],
        // As a study, too: the likelier slip.
        vec!["solve", "models/jumper.osim", "--out"],
        vec!["simulate", "--study", "models/jumper.osim", "--out"],
    ] {
        let dir = std::env::temp_dir().join(format!("leap-cli-osim-{}", std::process::id()));
        let mut cmd = Command::cargo_bin("leap").unwrap();
        cmd.args(&args);
        if args.last() == Some(&"--out") {
            cmd.arg(&dir);
        }
        let err = refused(&mut cmd, "an .osim model");
        assert!(
            err.contains("jumper.osim")
                && err.contains("an XML file")
                && err.contains("models/jumper.json"),
            "{args:?}: {err}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
    // A storage file (the other kind a solve leaves about) as a study or
    // a model: named as such.
    let dir = std::env::temp_dir().join(format!("leap-cli-sto-model-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let table = dir.join("states.sto");
    std::fs::write(
        &table,
        "states\nversion=1\nnRows=1\nnColumns=2\ninDegrees=no\nendheader\ntime\tx\n0\t1\n",
    )
    .unwrap();
    for args in [vec!["squat", "--model"], vec!["solve"]] {
        let mut cmd = Command::cargo_bin("leap").unwrap();
        cmd.args(&args).arg(&table);
        let err = refused(&mut cmd, "a storage file as a model");
        assert!(
            err.contains("states.sto: (document): an OpenSim storage file"),
            "{args:?}: {err}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `leap paths` of a model whose paths switch nowhere (the jumper with its
/// conditional points made fixed) says so, where it had printed an empty
/// table; the Jacobian cross-check of a model without the squat names the
/// model once, where it had named it twice.
#[test]
fn paths_without_switches_and_crosscheck_name_the_model_once() {
    let dir = std::env::temp_dir().join(format!("leap_cli_nocond_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap();
    let mut made_fixed = 0;
    for mu in m["forces"]["muscles"].as_array_mut().unwrap() {
        for p in mu["path"].as_array_mut().unwrap() {
            if p["type"] == "conditional" {
                let o = p.as_object_mut().unwrap();
                o.remove("coordinate");
                o.remove("range");
                o.insert("type".into(), "fixed".into());
                made_fixed += 1;
            }
        }
    }
    assert!(made_fixed > 0);
    let model = dir.join("no_conditional.json");
    std::fs::write(&model, serde_json::to_vec(&m).unwrap()).unwrap();
    let o = Command::cargo_bin("leap")
        .unwrap()
        .arg("paths")
        .arg("--model")
        .arg(&model)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        text.contains("no muscle path has a conditional point that switches"),
        "{text}"
    );
    let err = refused(
        Command::cargo_bin("leap").unwrap().args([
            "crosscheck",
            "--jacobian",
            "--model",
            "models/double_pendulum.json",
        ]),
        "a Jacobian cross-check without the squat",
    );
    assert_eq!(
        err.matches("models/double_pendulum.json").count(),
        1,
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
