//! `leap simulate`, `leap eval` and `leap squat` from the command line:
//! outputs, JSON fields, and clear errors for bad input.

use crate::common::refused;
use assert_cmd::Command;
use leap::study::SIMULATE_FILE_PREFIX;

fn leap() -> Command {
    Command::cargo_bin("leap").unwrap()
}

/// `leap simulate --study STUDY --out OUT`.
fn simulate_study(study: &std::path::Path, out: &std::path::Path) -> Command {
    let mut cmd = leap();
    cmd.args(["simulate", "--study"])
        .arg(study)
        .arg("--out")
        .arg(out);
    cmd
}

/// `leap simulate --t-max 0.2 --out <out>` (the default study's first
/// 0.2 s), which must succeed.
fn simulate_push_off(out: &std::path::Path) {
    let o = leap()
        .args(["simulate", "--t-max", "0.2", "--out"])
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("leap-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn bang_bang_jump_leaves_the_ground_and_writes_opensim_files() {
    let out = tmp("sim");
    let o = leap()
        .args([
            "simulate",
            "--integrator",
            "DormandPrince",
            "--json",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for key in [
        "jump_height_m",
        "liftoff_time_s",
        "liftoff_com_velocity_mps",
        "peak_vertical_grf_bw",
        "steps",
        "rejected_steps",
        "wall_time_s",
    ] {
        assert!(
            v.get(key).is_some_and(|x| x.is_number()),
            "missing {key}: {v}"
        );
    }
    assert!(v["jump_height_m"].as_f64().unwrap() > 0.05);
    assert!(v["liftoff_com_velocity_mps"].as_f64().unwrap() > 0.5);
    let names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    for f in [
        "forward_states.sto",
        "forward_controls.sto",
        "forward_grf.mot",
        "forward_summary.json",
    ] {
        assert!(names.contains(&f.to_string()), "{f} not in {names:?}");
    }
    assert_eq!(names.len(), 4, "nothing else is written: {names:?}");
    // The JSON names every file written, the summary among them.
    let mut listed: Vec<String> = v["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let p = std::path::PathBuf::from(f.as_str().unwrap());
            p.file_name().unwrap().to_string_lossy().into_owned()
        })
        .collect();
    let mut written = names.clone();
    listed.sort();
    written.sort();
    assert_eq!(listed, written);
    // The controls it wrote drive the same jump when read back.
    let out2 = tmp("sim2");
    let o2 = leap()
        .args([
            "simulate",
            "--integrator",
            "DormandPrince",
            "--json",
            "--controls",
        ])
        .arg(out.join("forward_controls.sto"))
        .arg("--out")
        .arg(&out2)
        .output()
        .unwrap();
    assert!(
        o2.status.success(),
        "{}",
        String::from_utf8_lossy(&o2.stderr)
    );
    let v2: serde_json::Value = serde_json::from_slice(&o2.stdout).unwrap();
    let (h1, h2) = (
        v["jump_height_m"].as_f64().unwrap(),
        v2["jump_height_m"].as_f64().unwrap(),
    );
    assert!((h1 - h2).abs() < 5e-3, "{h1} vs {h2}");
    std::fs::remove_dir_all(&out).ok();
    std::fs::remove_dir_all(&out2).ok();
}

#[test]
fn bad_simulate_input_gets_clear_errors() {
    let out = tmp("bad");
    let cases: [(&[&str], &str); 6] = [
        (&["--integrator", "Verlet"], "unknown integrator 'Verlet'"),
        (
            &[
                "--controls",
                "tests/data/controls/jumper_missing_soleus.sto",
            ],
            "missing: no excitation column for muscle 'soleus_r'",
        ),
        (
            &["--controls", "tests/data/controls/jumper_nan.sto"],
            "row 2 (t = 0.1): excitation NaN",
        ),
        (
            &["--controls", "tests/data/controls/jumper_time_order.sto"],
            "not strictly increasing",
        ),
        (&["--accuracy=-1"], "accuracy: must be positive"),
        // The left soleus's own column, not its right partner's values.
        (
            &["--controls", "tests/data/controls/jumper_asymmetric.sto"],
            "jumper_asymmetric.sto: columns '/forceset/soleus_l' and '/forceset/soleus_r' differ at row 1 (t = 0): 0.5 and 0.01061888305456504;",
        ),
    ];
    for (args, want) in cases {
        let o = leap()
            .arg("simulate")
            .args(args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    let study = out.join("study.json");
    std::fs::write(
        &study,
        r#"{"integrator": "RungeKuttaMerson", "acuracy": 1e-5}"#,
    )
    .unwrap();
    let o = leap()
        .args(["simulate", "--study"])
        .arg(&study)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("study.json") && err.contains("acuracy"),
        "{err}"
    );
    // A path holding a control character, escaped in the message.
    for field in ["model", "controls", "out"] {
        std::fs::write(&study, format!(r#"{{"{field}": "m\n.json"}}"#)).unwrap();
        let err = refused(
            leap().args(["simulate", "--study"]).arg(&study),
            "a control character",
        );
        assert!(
            err.contains(&format!(
                r#"study.json: {field}: holds the control character U+000A at character 2 of "m\n.json"; remove it"#
            )) && !err.contains("m\n"),
            "{err}"
        );
    }
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn eval_reports_the_static_squat_at_rest() {
    let out = tmp("eval");
    let o = leap().arg("squat").output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let squat = out.join("squat.json");
    std::fs::write(&squat, &o.stdout).unwrap();
    let o = leap()
        .args(["eval", "--json", "--input"])
        .arg(&squat)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for (c, a) in v["accelerations"].as_object().unwrap() {
        assert!(a.as_f64().unwrap().abs() <= 1e-6, "{c}: {a}");
    }
    let soleus = &v["muscles"]["soleus_r"];
    assert!(soleus["tendon_force"].as_f64().unwrap() > 0.0);
    assert!(
        soleus["moment_arms"]["ankle_angle_r"].as_f64().unwrap() < 0.0,
        "soleus plantarflexes"
    );
    // A missing state is named.
    let mut s: serde_json::Value = serde_json::from_slice(&std::fs::read(&squat).unwrap()).unwrap();
    s["state"]
        .as_object_mut()
        .unwrap()
        .remove("/forceset/soleus_r/activation");
    std::fs::write(&squat, serde_json::to_vec(&s).unwrap()).unwrap();
    let o = leap()
        .args(["eval", "--input"])
        .arg(&squat)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("squat.json")
            && err.contains("/forceset/soleus_r/activation"),
        "{err}"
    );
    std::fs::remove_dir_all(&out).ok();
}

/// Simbody asserts accuracy < 1 and aborts the process; a tiny accuracy,
/// fixed step or report interval never ends: all are refused as bad input.
#[test]
fn accuracies_that_would_abort_or_hang_are_refused() {
    let out = tmp("accuracy");
    for (args, want) in [
        (vec!["--accuracy", "1"], "accuracy: "),
        (vec!["--accuracy", "0.1"], "accuracy: "),
        (
            vec!["--integrator", "RungeKutta3", "--accuracy", "1e-11"],
            "RungeKutta3 needs at least 1e-10",
        ),
        (vec!["--accuracy", "10"], "accuracy: "),
        (
            vec!["--integrator", "CPodes", "--accuracy", "10"],
            "accuracy: ",
        ),
        (vec!["--accuracy", "1e-300"], "accuracy: "),
        (
            vec!["--integrator", "CPodes", "--accuracy", "1e-8"],
            "CPodes needs at least 1e-7",
        ),
        (
            vec!["--integrator", "ExplicitEuler", "--accuracy", "1e-12"],
            "fixed step",
        ),
    ] {
        let o = leap()
            .arg("simulate")
            .args(&args)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
        let own_floor = args.contains(&"1e-8") || args.contains(&"1e-11");
        if !args.contains(&"ExplicitEuler") && !own_floor {
            assert!(err.contains("[1e-12, 1e-2]"), "{args:?}: {err}");
        }
        assert!(!err.contains("Assertion"), "{args:?}: {err}");
    }
    std::fs::remove_dir_all(&out).ok();
}

/// A controls file among the run's own result files would be overwritten
/// by them: refused, and kept.
#[test]
fn controls_among_the_runs_result_files_are_refused_and_kept() {
    let out = tmp("controls-are-result");
    let controls = out.join(format!("{SIMULATE_FILE_PREFIX}_controls.sto"));
    std::fs::copy("tests/data/controls/jumper_missing_soleus.sto", &controls).unwrap();
    let before = std::fs::read(&controls).unwrap();
    let o = leap()
        .args(["simulate", "--controls"])
        .arg(&controls)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("the controls file (controls, --controls) is one of this run's result files"),
        "{err}"
    );
    assert_eq!(std::fs::read(&controls).unwrap(), before);
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn nonsense_simulate_study_settings_name_the_field() {
    let out = tmp("bad-study");
    let model = std::env::current_dir().unwrap().join("models/jumper.json");
    for (json, field, reason) in [
        (
            r#"{"bang_bang": {"on_time": 0.3, "off_time": 0.1}}"#,
            "bang_bang.off_time",
            "must be after on_time",
        ),
        (
            r#"{"bang_bang": {"on_time": -0.2, "off_time": 0.3}}"#,
            "bang_bang.on_time",
            "≥ 0",
        ),
        (r#"{"report_interval": 1e-9}"#, "report_interval", "rows"),
        (
            r#"{"report_interval": 0.05}"#,
            "report_interval",
            "at most 0.01 s",
        ),
        (r#"{"accuracy": 1}"#, "accuracy", "[1e-12, 1e-2]"),
        (
            r#"{"controls": "nope.sto"}"#,
            "controls",
            "nope.sto' not found",
        ),
        (
            r#"{"controls": " "}"#,
            "controls",
            "empty: name a controls file",
        ),
        (
            r#"{"t_max": 0.5, "bang_bang": {"on_time": 0.5, "off_time": 0.6}}"#,
            "bang_bang.on_time",
            "0.5 s is not before t_max = 0.5 s: no muscle would switch on",
        ),
        (
            r#"{"controls": "tests/data/controls/jump_optimal.sto", "bang_bang": {"on_time": 0, "off_time": 0.3}}"#,
            "bang_bang",
            "given together with 'controls'",
        ),
    ] {
        let mut v: serde_json::Value = serde_json::from_str(json).unwrap();
        v["model"] = model.display().to_string().into();
        let study = out.join("study.json");
        std::fs::write(&study, v.to_string()).unwrap();
        let err = refused(&mut simulate_study(&study, &out.join("results")), json);
        assert!(
            err.contains(&format!("{}: {field}: ", study.display())) && err.contains(reason),
            "{json}: {err}"
        );
    }
    // A bad value on the command line is the command line's, not the
    // (good) study's.
    let study = out.join("study.json");
    std::fs::write(
        &study,
        serde_json::json!({"model": model, "accuracy": 1e-5, "t_max": 1.0}).to_string(),
    )
    .unwrap();
    for (option, value, reason) in [
        ("--accuracy", "NaN", "must be positive, got NaN"),
        ("--t-max", "0", "must be a time in (0, 10] s"),
        ("--integrator", "Foo", "unknown integrator 'Foo'"),
    ] {
        let err = refused(
            simulate_study(&study, &out.join("results")).args([option, value]),
            option,
        );
        assert!(
            err.contains(&format!("command line: {option}: {reason}")),
            "{option}: {err}"
        );
    }
    // An option that clashes with a (good) study field is named, with it.
    std::fs::write(
        &study,
        serde_json::json!({"model": model, "t_max": 1.0, "bang_bang": {"on_time": 0.5, "off_time": 0.6}}).to_string(),
    )
    .unwrap();
    let err = refused(
        simulate_study(&study, &out.join("results")).args(["--t-max", "0.4"]),
        "clash",
    );
    assert!(
        err.contains(&format!(
            "command line: --t-max: with {}'s bang_bang.on_time: 0.5 s is not before t_max = 0.4 s",
            study.display()
        )),
        "{err}"
    );
    std::fs::remove_dir_all(&out).ok();
}

/// Model errors reach the command line naming file and field (here one that
/// `leap eval`'s per-sphere report would otherwise have lost).
#[test]
fn a_model_with_duplicate_sphere_names_is_refused() {
    let out = tmp("dup-sphere");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap();
    v["forces"]["contact"]["spheres"][9]["name"] = "heel_lat_l".into();
    let model = out.join("m.json");
    std::fs::write(&model, v.to_string()).unwrap();
    let err = refused(leap().args(["squat", "--model"]).arg(&model), "squat");
    assert!(
        err.contains(&format!(
            "{}: forces.contact.spheres[9].name: sphere 'heel_lat_l' is defined twice",
            model.display()
        )),
        "{err}"
    );
    std::fs::remove_dir_all(&out).ok();
}

/// Results replace what a results directory held, links included: a
/// symbolic link where `forward_states.sto` goes is replaced by the file, and
/// the file it pointed to, outside the directory, is left as it was.
#[cfg(unix)]
#[test]
fn results_replace_links_and_never_write_through_them() {
    let out = tmp("links");
    let outside = tmp("links-outside").join("precious.txt");
    std::fs::write(&outside, "not leap's").unwrap();
    for name in ["forward_states.sto", "forward_summary.json"] {
        let link = out.join(name);
        let _ = std::fs::remove_file(&link);
        std::os::unix::fs::symlink(&outside, &link).unwrap();
    }
    let o = leap()
        .args(["simulate", "--integrator", "DormandPrince", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read_to_string(&outside).unwrap(), "not leap's");
    for name in ["forward_states.sto", "forward_summary.json"] {
        let meta = std::fs::symlink_metadata(out.join(name)).unwrap();
        assert!(meta.file_type().is_file(), "{name} is still a link");
    }
    let states = std::fs::read_to_string(out.join("forward_states.sto")).unwrap();
    assert!(states.contains("endheader"), "{states}");
    let _ = std::fs::remove_dir_all(&out);
    let _ = std::fs::remove_dir_all(outside.parent().unwrap());
}

/// A simulate study that names no model uses the default model relative
/// to the working directory, as `leap solve`'s study does, not relative to
/// the study file; a model it names is relative to the study file.
#[test]
fn a_study_without_a_model_uses_the_working_directorys_default() {
    let dir = tmp("study-defaults");
    let study = dir.join("empty.json");
    std::fs::write(&study, r#"{"integrator": "DormandPrince"}"#).unwrap();
    let o = simulate_study(&study, &dir.join("out")).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::write(&study, r#"{"model": "jumper.json"}"#).unwrap();
    let err = refused(&mut simulate_study(&study, &dir.join("out")), "named model");
    assert!(
        err.contains(&dir.join("jumper.json").display().to_string()),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A controls file that stops long before the push-off ends is used with
/// its last row held, and `leap simulate` says so (a file of the first
/// 0.02 s had "jumped" −8.6 cm without a word); the JSON gives the file's
/// time range. A solution's excitations, which end at its t_f, about at
/// lift-off, raise no warning.
#[test]
fn a_controls_file_that_stops_early_is_warned_of() {
    use leap::io::StoTable;
    let out = tmp("short_controls");
    let full = std::path::Path::new("tests/data/controls/jump_optimal.sto");
    let mut t = StoTable::read(full).unwrap();
    let keep = t.time.iter().take_while(|&&x| x <= 0.05).count();
    t.time.truncate(keep);
    t.rows.truncate(keep);
    let short = out.join("short.sto");
    t.write_sto(&short).unwrap();
    let last = *t.time.last().unwrap();
    for (file, warned) in [(short.as_path(), true), (full, false)] {
        let o = leap()
            .args([
                "simulate",
                "--json",
                "--integrator",
                "DormandPrince",
                "--controls",
            ])
            .arg(file)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{err}");
        assert_eq!(
            err.contains("warning: the controls file covers"),
            warned,
            "{file:?}: {err}"
        );
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let range = v["controls_time_range"].as_array().unwrap();
        assert_eq!(range[0].as_f64(), Some(0.0));
        if warned {
            assert_eq!(range[1].as_f64(), Some(last));
            assert!(err.contains(&format!("covers 0.000–{last:.3} s")), "{err}");
        }
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// A controls file in milliseconds stretches the push-off a thousandfold:
/// the run ends before its second row, and `leap simulate` warns of it,
/// naming the unit (a file in seconds with a long tail is not warned of).
/// A file that starts at or after t_max, or ends at or before 0, gives the
/// run one of its rows only, and is refused naming the file and its time
/// column.
#[test]
fn controls_in_milliseconds_are_warned_of_and_late_ones_refused() {
    use leap::io::StoTable;
    let out = tmp("ms_controls");
    let full = std::path::Path::new("tests/data/controls/jump_optimal.sto");
    let t = StoTable::read(full).unwrap();
    let mut ms = t.clone();
    ms.time.iter_mut().for_each(|x| *x *= 1000.0);
    let ms_file = out.join("ms.sto");
    ms.write_sto(&ms_file).unwrap();
    let mut late = t.clone();
    late.time.iter_mut().for_each(|x| *x += 0.5);
    let late_file = out.join("late.sto");
    late.write_sto(&late_file).unwrap();
    let run = |file: &std::path::Path| {
        leap()
            .args([
                "simulate",
                "--integrator",
                "DormandPrince",
                "--t-max",
                "0.5",
                "--controls",
            ])
            .arg(file)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap()
    };
    let o = run(&ms_file);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    // As written (16 significant digits) and read back.
    let ms = StoTable::read(&ms_file).unwrap();
    let (second, last) = (
        leap::io::readable(ms.time[1]),
        leap::io::readable(*ms.time.last().unwrap()),
    );
    assert!(
        err.contains(&format!(
            "before the controls file's second row (t = {second} s; the file spans 0–{last} s, longer than any jump)"
        )) && err.contains("milliseconds"),
        "{err}"
    );
    // Rows dense enough in milliseconds that the run ends after the
    // second: no lift-off, and the same hint.
    let mut dense = ms.clone();
    dense.time.clear();
    dense.rows.clear();
    for k in 0..ms.time.len() - 1 {
        for j in 0..100 {
            dense
                .time
                .push(ms.time[k] + (ms.time[k + 1] - ms.time[k]) * j as f64 / 100.0);
            dense.rows.push(ms.rows[k].clone());
        }
    }
    dense.time.push(*ms.time.last().unwrap());
    dense.rows.push(ms.rows.last().unwrap().clone());
    let dense_file = out.join("ms_dense.sto");
    dense.write_sto(&dense_file).unwrap();
    let o = run(&dense_file);
    let err = String::from_utf8_lossy(&o.stderr);
    let dense = StoTable::read(&dense_file).unwrap();
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains(&format!(
            "warning: no lift-off before t_max = 0.5 s, and the controls file spans 0–{} s, longer than any jump",
            leap::io::readable(*dense.time.last().unwrap())
        )) && err.contains("milliseconds"),
        "{err}"
    );
    // The solution's own file raises no such warning, nor does it with a
    // long tail in seconds (its last row held to 3.5 s).
    let mut tail = t.clone();
    tail.time.push(3.5);
    tail.rows.push(t.rows.last().unwrap().clone());
    let tail_file = out.join("tail.sto");
    tail.write_sto(&tail_file).unwrap();
    // Nor does a ramp of two rows in seconds, whose second row lies after
    // lift-off.
    let ramp_file = out.join("ramp.sto");
    std::fs::write(
        &ramp_file,
        std::fs::read_to_string(full)
            .unwrap()
            .lines()
            .take_while(|l| *l != "endheader")
            .chain(["endheader".to_string().as_str()])
            .map(|l| format!("{l}\n"))
            .collect::<String>()
            + &format!("time\t{}\n", t.labels.join("\t"))
            + &format!("0\t{}\n", vec!["0.01"; t.labels.len()].join("\t"))
            + &format!("0.5\t{}\n", vec!["1"; t.labels.len()].join("\t")),
    )
    .unwrap();
    for file in [full, tail_file.as_path(), ramp_file.as_path()] {
        let o = run(file);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            o.status.success() && !err.contains("controls file"),
            "{err}"
        );
        // (The ramp does not lift off by t_max, which is warned of.)
        assert_eq!(err.contains("warning"), file == ramp_file, "{err}");
    }
    // Without a lift-off the JSON gives no jump height, as the text gives
    // "-", and the COM's change apart.
    let o = leap()
        .args([
            "simulate",
            "--integrator",
            "DormandPrince",
            "--t-max",
            "0.5",
            "--json",
            "--controls",
        ])
        .arg(&ramp_file)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(
        v["liftoff_time_s"].is_null() && v["jump_height_m"].is_null(),
        "{v}"
    );
    // The COM's change is the written states' last row's, as `leap
    // analyze` computes it from the file over the whole run.
    let change = v["final_com_height_change_m"].as_f64().unwrap();
    let a = leap()
        .arg("analyze")
        .arg(out.join("forward_states.sto"))
        .args(["--window", "0", "0.5", "--json"])
        .output()
        .unwrap();
    let a: serde_json::Value = serde_json::from_slice(&a.stdout).unwrap();
    let end = a["end_com_height_above_standing_m"].as_f64().unwrap();
    assert!(change < -0.01, "the ramp sinks: {change}");
    assert!((change - end).abs() < 1e-9, "{change} against {end}");
    // Files the run would read one row of: one starting at t_max, one
    // ending before 0.
    let mut early = t.clone();
    let end = *t.time.last().unwrap();
    early.time.iter_mut().for_each(|x| *x += -0.25 - end);
    *early.time.last_mut().unwrap() = -0.25;
    let early_file = out.join("early.sto");
    early.write_sto(&early_file).unwrap();
    for (file, reason) in [
        (
            &late_file,
            "starts at 0.5 s, not before the simulation's end t_max = 0.5 s",
        ),
        (
            &early_file,
            "ends at -0.25 s, not after the simulation's start at 0 s",
        ),
    ] {
        let o = run(file);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains(&format!("{}: column 'time': {reason}", file.display())),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

/// Every command with a `--model` finds the default model as `leap solve`
/// does: `models/jumper.json` in the working directory, else leap's own.
/// Run from a directory without it, `leap squat` prints the jumper's squat
/// and `leap analyze` reads a states file with it; a named model that is
/// not there is an error naming it.
#[test]
fn commands_find_the_default_model_outside_the_source_tree() {
    let dir = tmp("default-model");
    let run = |args: &[&str]| {
        let o = leap().current_dir(&dir).args(args).output().unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        o
    };
    let v: serde_json::Value = serde_json::from_slice(&run(&["squat"]).stdout).unwrap();
    assert!(
        v["state"]["/forceset/soleus_r/activation"].is_number(),
        "{v}"
    );
    let here = std::env::current_dir().unwrap();
    run(&["simulate", "--out", "out"]);
    run(&["analyze", "out/forward_states.sto", "--json"]);
    let err = refused(
        leap()
            .current_dir(&dir)
            .args(["squat", "--model", "models/jumper.json"]),
        "a named model that is not there",
    );
    assert!(
        err.contains("models/jumper.json") && err.contains("cannot read"),
        "{err}"
    );
    assert!(!dir.join("models").exists() && here.join("models/jumper.json").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A controls column that names no muscle of the model (here a misspelt
/// soleus) is not read, and `leap simulate` says so, on stderr and in the
/// JSON; a state column beside it (as in a solution) and the left leg's
/// columns of leap's own files are not counted. The jump is the one of the
/// file without the column.
#[test]
fn controls_columns_that_name_no_muscle_are_warned_of() {
    let out = tmp("misspelt_controls");
    let run = |file: &str| {
        let o = leap()
            .args(["simulate", "--json", "--controls", file, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(o.status.success(), "{err}");
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (v, err)
    };
    let (v, err) = run("tests/data/controls/jumper_misspelt.sto");
    assert!(
        err.contains("warning: tests/data/controls/jumper_misspelt.sto: 1 column(s) name no muscle of the model and are not read: /forceset/solues_r"),
        "{err}"
    );
    assert_eq!(
        v["unread_controls_columns"],
        serde_json::json!(["/forceset/solues_r"])
    );
    let (plain, err) = run("tests/data/controls/jump_optimal.sto");
    assert!(!err.contains("not read"), "{err}");
    assert_eq!(v["jump_height_m"], plain["jump_height_m"]);
    // leap's own controls file, both legs (copied: as the run's own result
    // file it is refused, see below).
    let own = out.join("own_controls.sto");
    std::fs::copy(out.join("forward_controls.sto"), &own).unwrap();
    let (v, err) = run(own.to_str().unwrap());
    assert!(!err.contains("not read"), "{err}");
    assert_eq!(v["unread_controls_columns"], serde_json::json!([]));
    let _ = std::fs::remove_dir_all(&out);
}

/// A bang-bang pattern names muscles of the model, each once: an unknown
/// one and a repeated one are refused naming the entry, before anything
/// is written.
#[test]
fn bang_bang_muscles_are_known_and_named_once() {
    let dir = tmp("bang_bang_names");
    for (on, want) in [
        (
            r#"["soleus_r", "solues_r"]"#,
            "bang_bang.on: unknown muscle 'solues_r'",
        ),
        (
            r#"["soleus_r", "vas_int_r", "soleus_r"]"#,
            "bang_bang.on[2]: muscle 'soleus_r' named twice (also bang_bang.on[0])",
        ),
    ] {
        let study = dir.join("study.json");
        std::fs::write(&study, format!(r#"{{"bang_bang": {{"on": {on}}}}}"#)).unwrap();
        let out = dir.join("out");
        let o = simulate_study(&study, &out).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains(want), "{err}");
        assert!(!out.join("forward_states.sto").exists());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A lift-off with the centre of mass moving down is a fall: the vasti and
/// soleus alone unload the feet while the body drops, and the "jump" was
/// reported as −17 cm without a word.
#[test]
fn a_lift_off_while_falling_is_warned_of() {
    let dir = tmp("falling");
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/models/jumper.json");
    let study = dir.join("two_muscles.json");
    std::fs::write(
        &study,
        format!(
            r#"{{"model": "{model}", "bang_bang": {{"on": ["vas_int_r", "soleus_r"], "on_time": 0.0, "off_time": 0.3}}}}"#
        ),
    )
    .unwrap();
    let o = simulate_study(&study, &dir.join("out"))
        .arg("--json")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let vy = v["liftoff_com_velocity_mps"].as_f64().unwrap();
    assert!(vy < 0.0, "the body falls at lift-off: {vy}");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("a fall, not a jump"), "{err}");
    assert_eq!(v["liftoff_while_falling"], true, "{v}");
    // The default extensors jump: no such warning.
    let study = dir.join("extensors.json");
    // The README's example: Feldberg's steps overshoot an activation of 1
    // by about 1e-4, which `leap analyze` and guesses had refused.
    std::fs::write(
        &study,
        format!(
            r#"{{"model": "{model}", "integrator": "RungeKuttaFeldberg", "bang_bang": {{"on_time": 0.0, "off_time": 0.3}}}}"#
        ),
    )
    .unwrap();
    let o = simulate_study(&study, &dir.join("out"))
        .arg("--json")
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(!String::from_utf8_lossy(&o.stderr).contains("a fall"));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["liftoff_while_falling"], false, "{v}");
    let o = leap()
        .arg("analyze")
        .arg(dir.join("out/forward_states.sto"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_dir_all(&dir).ok();
}

/// `leap analyze` of a states file with a fibre far outside what muscles
/// do (vas_int at 1e-4 m, 0.001 optimal fibre lengths, in one row; its
/// tendon then takes the muscle's length) warns, naming the column and the
/// time, where it had reported the row's forces without a word; the file
/// as simulated does not warn. Times beyond a day are refused (a span that
/// overflows a double had printed NaN and exited 0).
#[test]
fn analyze_warns_of_fibres_outside_the_optimizers_bounds() {
    let out = tmp("fibre_warning");
    simulate_push_off(&out);
    let states = out.join("forward_states.sto");
    let o = leap().arg("analyze").arg(&states).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && !err.contains("fiber_length"), "{err}");
    let mut t = leap::io::StoTable::read(&states).unwrap();
    let row = t.rows.len() / 3;
    // vas_int's fibre (both legs' columns, which must agree) in one row.
    let vas_int = |t: &mut leap::io::StoTable, v: f64| {
        for side in ["r", "l"] {
            let label = format!("/forceset/vas_int_{side}/fiber_length");
            let k = t.labels.iter().position(|l| *l == label).unwrap();
            t.rows[row][k] = v;
        }
    };
    vas_int(&mut t, 1e-4);
    let file = out.join("short_fibre.sto");
    t.write_sto(&file).unwrap();
    let o = leap().arg("analyze").arg(&file).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains(&format!(
            "at t = {} s, its first such row: /forceset/vas_int_r/fiber_length = 0.0001 m is",
            leap::io::readable(t.time[row])
        )) && err.contains("outside [0.2, 2]"),
        "{err}"
    );
    // A fibre of 100 m gives no finite fibre velocity: the error names
    // the row's time as well as the muscle.
    vas_int(&mut t, 100.0);
    t.write_sto(&file).unwrap();
    let o = leap().arg("analyze").arg(&file).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains(&format!(
                "row at t = {} s: muscle 'vas_int_r'",
                leap::io::readable(t.time[row])
            )),
        "{err}"
    );
    let mut t = leap::io::StoTable::read(&states).unwrap();
    let n = t.time.len();
    t.time[0] = -1.7e308;
    t.time[n - 1] = 1.7e308;
    t.write_sto(&file).unwrap();
    let o = leap().arg("analyze").arg(&file).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("column 'time': row 1: t = -1.7e308 s lies beyond a day (±86400 s)"),
        "{err}"
    );
    // A last row at 1e300 s, a typo: refused, where the analysis had
    // printed a 1e300 s window and its work in 300 digits.
    let mut t = leap::io::StoTable::read(&states).unwrap();
    t.time[n - 1] = 1e300;
    t.write_sto(&file).unwrap();
    for command in ["analyze", "report"] {
        let o = leap().arg(command).arg(&file).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{command}: {err}");
        assert!(
            err.contains(&format!("row {n}: t = 1e300 s lies beyond a day")),
            "{command}: {err}"
        );
    }
    std::fs::remove_dir_all(&out).ok();
}

/// A states file in degrees without `inDegrees=yes` (a slip when writing
/// one by hand), which gave non-finite forces: the refusal names the
/// header, the farthest angle and the likely cause, where it had named no
/// column.
#[test]
fn states_in_degrees_without_the_header_key_are_refused_naming_the_cause() {
    let out = tmp("degrees_unsaid");
    simulate_push_off(&out);
    let m =
        leap::model::Model::from_file(concat!(env!("CARGO_MANIFEST_DIR"), "/models/jumper.json"))
            .unwrap();
    let (_, eq) = leap::ode::StateEquation::opensim(&m, false).unwrap();
    let angular = leap::io::angular_columns(&eq);
    let mut t = leap::io::StoTable::read(&out.join("forward_states.sto")).unwrap();
    // Degrees written, the header left saying nothing (radians).
    for (k, label) in t.labels.iter().enumerate() {
        if angular.contains(label) {
            t.rows.iter_mut().for_each(|r| r[k] = r[k].to_degrees());
        }
    }
    t.metadata.remove("inDegrees");
    let file = out.join("degrees.sto");
    t.write_sto(&file).unwrap();
    let o = leap().arg("analyze").arg(&file).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("header 'inDegrees'")
            && err.contains("'/jointset/knee_r/knee_angle_r/value' reaches -79.9")
            && err.contains("a file in degrees? Write inDegrees=yes"),
        "{err}"
    );
    // The same file with the key read in radians: analysed.
    t.metadata.insert("inDegrees".into(), "yes".into());
    t.write_sto(&file).unwrap();
    let o = leap().arg("analyze").arg(&file).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // `leap eval` input has no header: its hint says it reads radians.
    let squat = leap().args(["squat"]).output().unwrap();
    let mut input: serde_json::Value = serde_json::from_slice(&squat.stdout).unwrap();
    let (_, sym) = leap::ode::StateEquation::opensim(&m, true).unwrap();
    let sym_angular = leap::io::angular_columns(&sym);
    for (name, v) in input["state"].as_object_mut().unwrap() {
        if sym_angular.contains(name) {
            *v = serde_json::json!(v.as_f64().unwrap().to_degrees());
        }
    }
    let eval_in = out.join("eval_degrees.json");
    std::fs::write(&eval_in, input.to_string()).unwrap();
    let o = leap()
        .arg("eval")
        .arg("--input")
        .arg(&eval_in)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("outside its range") && err.contains("leap eval reads coordinates in radians"),
        "{err}"
    );
    // A window ends on the row of its end time, written a hair later
    // (report times summed step by step: 0.1500000000000001).
    let states = out.join("forward_states.sto");
    let o = leap()
        .arg("analyze")
        .arg(&states)
        .args(["--window", "0.05", "0.15", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let end = a["budget"]["end_s"].as_f64().unwrap();
    assert!((end - 0.15).abs() < 1e-12, "the window ended at {end}");
    // The symmetric analysis's rows stand for both legs; --full's for one
    // muscle each.
    for (full, says) in [
        (false, "work of the muscles on both sides"),
        (true, "work of each muscle"),
    ] {
        let mut c = leap();
        c.arg("analyze").arg(&states);
        if full {
            c.arg("--full");
        }
        let o = c.output().unwrap();
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success() && text.contains(says), "{full}: {text}");
    }
    std::fs::remove_dir_all(&out).ok();
}

/// A muscle law that fails inside Simbody's step (a DeGroote muscle whose
/// inverted force–velocity curve overflows at the minimum activation;
/// README, "The model") is reported once, with its time and reason, not
/// inside SimTK's exception text.
#[test]
fn a_force_element_failure_in_a_step_is_said_once() {
    let dir = tmp("degroote-step");
    let mut model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap();
    model["forces"]["muscle_model"] = "DeGrooteFregly2016Muscle".into();
    let file = dir.join("degroote.json");
    std::fs::write(&file, model.to_string()).unwrap();
    let o = leap()
        .args(["simulate", "--t-max", "0.01", "--model"])
        .arg(&file)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("integration stopped: Simbody: the muscle, contact and ligament forces (leap's force element) failed at t = 0.000")
            && err.matches("non-finite fibre velocity").count() == 1
            && !err.contains("SimTK Exception"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
