//! Storage files: round trips, OpenSim 3 and Moco control files, and clear
//! errors for broken controls.

use leap::io::{Controls, StoError, StoTable};
use std::path::Path;

#[test]
fn sto_round_trip_keeps_values_to_the_last_bit() {
    let dir = std::env::temp_dir().join(format!("leap-io-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut t = StoTable::default();
    t.metadata.insert("inDegrees".into(), "no".into());
    t.labels = vec![
        "/jointset/hip_r/hip_flexion_r/value".into(),
        "/forceset/soleus_r/activation".into(),
    ];
    t.time = vec![0.0, 0.1, 0.2];
    t.rows = vec![
        vec![1.0 / 3.0, 0.05],
        vec![-2.5e-9, 0.999999999999],
        vec![std::f64::consts::PI, 1.0],
    ];
    let p = dir.join("x.sto");
    t.write_sto(&p).unwrap();
    let r = StoTable::read(&p).unwrap();
    assert_eq!(r.labels, t.labels);
    assert_eq!(r.metadata.get("inDegrees").map(String::as_str), Some("no"));
    for (a, b) in r.rows.iter().flatten().zip(t.rows.iter().flatten()) {
        assert_eq!(a, b);
    }
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.contains("DataType=double\nversion=3\n") && text.contains("endheader\ntime\t"));
    t.name = Some("grf".into());
    t.write_mot(&dir.join("x.mot")).unwrap();
    let m = StoTable::read(&dir.join("x.mot")).unwrap();
    assert_eq!(m.name.as_deref(), Some("grf"));
    assert_eq!(m.time, t.time);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn opensim3_controls_are_read_and_interpolated() {
    let c = Controls::from_file(
        Path::new("tests/data/controls/ok_v1.sto"),
        &["vas_int_r", "soleus_r"],
    )
    .unwrap();
    let mut u = [0.0; 2];
    c.at(0.05, &mut u);
    assert!((u[0] - 0.4).abs() < 1e-15 && (u[1] - 0.3).abs() < 1e-15);
    c.at(1.0, &mut u);
    assert_eq!(u, [0.0, 1.0]);
}

#[test]
fn broken_controls_name_file_column_and_reason() {
    let cases = [
        ("missing_muscle", "/forceset/vas_int_r", "missing"),
        ("nan", "/forceset/soleus_r", "row 2"),
        ("time_order", "time", "not strictly increasing"),
    ];
    for (file, column, reason) in cases {
        let path = format!("tests/data/controls/{file}.sto");
        let e = Controls::from_file(Path::new(&path), &["soleus_r", "vas_int_r"]).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, StoError::Column { .. }), "{msg}");
        assert!(
            msg.contains(&path) && msg.contains(column) && msg.contains(reason),
            "{msg}"
        );
    }
    let e = StoTable::parse("a=b\ntime\tx\n0\t1\n", Path::new("no_end.sto")).unwrap_err();
    assert!(e.to_string().contains("endheader"));
    let e = StoTable::parse("endheader\nt\tx\n0\t1\n", Path::new("bad.sto")).unwrap_err();
    assert!(e.to_string().contains("'time'"));
    let e = StoTable::parse("endheader\ntime\tx\n0\tabc\n", Path::new("bad.sto")).unwrap_err();
    assert!(e.to_string().contains("line 3") && e.to_string().contains("'abc'"));
}
