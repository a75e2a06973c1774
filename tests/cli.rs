//! The `leap` command line: cross-check JSON output and clear errors.

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
    let out = Command::cargo_bin("leap")
        .unwrap()
        .args(["crosscheck", "--samples", "0"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--samples"));
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
