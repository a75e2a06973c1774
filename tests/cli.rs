//! The `leap` command line: cross-check JSON output and clear errors.

use assert_cmd::Command;

#[test]
fn crosscheck_json_reports_error_and_samples() {
    let out = Command::cargo_bin("leap")
        .unwrap()
        .args([
            "crosscheck",
            "--model",
            "models/jumper.json",
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
