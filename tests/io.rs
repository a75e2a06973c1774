//! Storage files: round trips, OpenSim 3 and Moco control files, states
//! in degrees (OpenSim's `inDegrees=yes`), and clear errors for broken
//! controls, states and guesses.

use leap::io::{Controls, StoError, StoTable};
use leap::ode::StateEquation;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// A fresh directory for one test's files.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("leap-io-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn jumper_ocp() -> &'static Arc<leap::ocp::JumpOcp> {
    static OCP: OnceLock<Arc<leap::ocp::JumpOcp>> = OnceLock::new();
    OCP.get_or_init(|| {
        let model = leap::model::Model::from_file("models/jumper.json").unwrap();
        Arc::new(leap::ocp::JumpOcp::new(&model, Default::default()).unwrap())
    })
}

/// States and excitations of `eq` in SI units and radians: the squat `x0`
/// moved a little in each of 4 rows 0.05 s apart, in the columns leap
/// writes (every state and excitation of the model, both legs).
fn states_table(eq: &StateEquation, x0: &[f64]) -> StoTable {
    let system = system_states_table(eq, x0);
    let (ns, nu) = (eq.model_state_columns(), eq.model_control_columns());
    let split: Vec<(Vec<f64>, Vec<f64>)> = system
        .rows
        .iter()
        .map(|r| (r[..eq.nx()].to_vec(), r[eq.nx()..].to_vec()))
        .collect();
    let (mut labels, mut rows) =
        leap::simulate::model_columns(&ns, &split.iter().map(|s| s.0.clone()).collect::<Vec<_>>());
    let (cl, cr) =
        leap::simulate::model_columns(&nu, &split.iter().map(|s| s.1.clone()).collect::<Vec<_>>());
    labels.extend(cl);
    for (r, c) in rows.iter_mut().zip(cr) {
        r.extend(c);
    }
    StoTable {
        labels,
        rows,
        ..system
    }
}

/// As [`states_table`] with the system's columns alone (the right leg).
fn system_states_table(eq: &StateEquation, x0: &[f64]) -> StoTable {
    let mut t = StoTable::default();
    t.metadata.insert("inDegrees".into(), "no".into());
    t.labels = eq.state_names();
    t.labels.extend(eq.control_names());
    // Rows that differ in the coordinates and speeds; the muscle states
    // stay at x0's, inside their physical range.
    let nqu = 2 * eq.nq();
    for r in 0..4 {
        t.time.push(0.05 * r as f64);
        let mut row: Vec<f64> = x0
            .iter()
            .enumerate()
            .map(|(i, v)| {
                let d = if i < nqu {
                    0.01 * (r as f64) * ((i % 7) as f64 - 3.0) / 3.0
                } else {
                    0.0
                };
                v + d
            })
            .collect();
        row.extend(std::iter::repeat_n(0.3 + 0.1 * r as f64, eq.nm()));
        t.rows.push(row);
    }
    t
}

/// OpenSim's convention, from the model file rather than from leap: the
/// values and speeds of every coordinate but the planar joint's
/// translations (`pelvis_tx`, `pelvis_ty`) are angles.
fn is_angle(label: &str) -> bool {
    let parts: Vec<&str> = label.split('/').collect();
    matches!(parts.as_slice(), ["", "jointset", _, coord, "value" | "speed"]
        if !matches!(*coord, "pelvis_tx" | "pelvis_ty"))
}

/// `t` with its angles in degrees (deg/s) and `inDegrees=<flag>`.
fn in_degrees(t: &StoTable, flag: &str) -> StoTable {
    let mut d = t.clone();
    d.metadata.insert("inDegrees".into(), flag.into());
    for (k, label) in t.labels.iter().enumerate() {
        if is_angle(label) {
            for row in &mut d.rows {
                row[k] *= 180.0 / std::f64::consts::PI;
            }
        }
    }
    d
}

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
    // Two spellings of one muscle's column (Moco's and OpenSim 3's): one
    // would be lost, whichever comes first.
    for (a, b) in [
        ("/forceset/soleus_r", "soleus_r"),
        ("soleus_r.excitation", "/forceset/soleus_r"),
    ] {
        let text =
            format!("endheader\ntime\t{a}\tvas_int_r\t{b}\n0\t0.5\t0.5\t1\n0.1\t0.5\t0.5\t1\n");
        let t = StoTable::parse(&text, Path::new("two.sto")).unwrap();
        let e =
            Controls::from_table(&t, Path::new("two.sto"), &["soleus_r", "vas_int_r"]).unwrap_err();
        // Named in the order of the spellings: Moco's first.
        let other = if a == "/forceset/soleus_r" { b } else { a };
        let msg = e.to_string();
        assert!(
            msg.contains(&format!("two.sto: column '{other}': holds the excitation of muscle 'soleus_r', as column '/forceset/soleus_r' does")),
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

#[test]
fn states_in_degrees_are_read_in_radians_and_only_angles_are_converted() {
    let ocp = jumper_ocp();
    let eq = &ocp.eq;
    let dir = scratch("degrees");
    let rad = states_table(eq, ocp.x0());
    let (p_rad, p_deg) = (dir.join("rad.sto"), dir.join("deg.mot"));
    rad.write_sto(&p_rad).unwrap();
    // "Yes": the header's value is case-insensitive.
    in_degrees(&rad, "Yes").write_mot(&p_deg).unwrap();
    let a = leap::io::read_states(eq, &p_rad).unwrap();
    let b = leap::io::read_states(eq, &p_deg).unwrap();
    assert_eq!(a.labels, b.labels);
    assert_eq!(a.time, b.time);
    let (mut angles, mut others) = (0, 0);
    for (k, label) in a.labels.iter().enumerate() {
        for (ra, rb) in a.rows.iter().zip(&b.rows) {
            if is_angle(label) {
                // Printed with 16 digits in degrees, converted back.
                assert!(
                    (ra[k] - rb[k]).abs() <= 1e-14 * ra[k].abs().max(1e-3),
                    "{label}: {} rad, from degrees {}",
                    ra[k],
                    rb[k]
                );
                angles += 1;
            } else {
                assert_eq!(ra[k], rb[k], "{label} is not an angle");
                others += 1;
            }
        }
    }
    // 8 of the model's 10 coordinates are angles (pelvis tilt, both hips,
    // knees and ankles, lumbar): value and speed in 4 rows. The left leg's
    // are converted too, or they would differ from their right partners.
    assert_eq!(angles, 4 * 2 * 8, "angle cells");
    assert!(others > 0);
    // The file's degrees really are degrees: the knee of the squat.
    let knee = rad
        .labels
        .iter()
        .position(|l| l == "/jointset/knee_r/knee_angle_r/value")
        .unwrap();
    let raw = StoTable::read(&p_deg).unwrap();
    assert!((raw.rows[0][knee] - rad.rows[0][knee].to_degrees()).abs() < 1e-12);
    // analyze reads the same states.
    let (time, xs) = leap::analyze::read_states(eq, &p_deg).unwrap();
    assert_eq!(time, a.time);
    let xa = leap::analyze::read_states(eq, &p_rad).unwrap().1;
    for (x, y) in xs.iter().flatten().zip(xa.iter().flatten()) {
        assert!((x - y).abs() <= 1e-14 * y.abs().max(1e-3), "{x} vs {y}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_guess_in_degrees_equals_the_guess_in_radians_and_bad_guesses_are_refused() {
    use leap::transcription::{Transcription, TranscriptionOptions};
    let ocp = jumper_ocp();
    let tr = Transcription::new(
        ocp.clone(),
        TranscriptionOptions {
            num_mesh_intervals: 8,
            ..Default::default()
        },
    )
    .unwrap();
    let dir = scratch("guess");
    let rad = states_table(&ocp.eq, ocp.x0());
    let (p_rad, p_deg) = (dir.join("rad.sto"), dir.join("deg.sto"));
    rad.write_sto(&p_rad).unwrap();
    in_degrees(&rad, "yes").write_sto(&p_deg).unwrap();
    let a = leap::solve::guess_from_file(&tr, &p_rad).unwrap();
    let b = leap::solve::guess_from_file(&tr, &p_deg).unwrap();
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 1e-14 * x.abs().max(1e-3), "{x} vs {y}");
    }
    // A NaN, a single row, an infinite or a repeated time.
    let mut nan = rad.clone();
    nan.rows[2][3] = f64::NAN;
    let mut one = rad.clone();
    one.time.truncate(1);
    one.rows.truncate(1);
    let mut inf = rad.clone();
    inf.time[3] = f64::INFINITY;
    let mut repeated = rad.clone();
    repeated.time[2] = repeated.time[1];
    let hip = "/jointset/hip_r/hip_flexion_r/value";
    assert_eq!(rad.labels[3], hip);
    // An excitation outside [0, 1].
    let mut strong = rad.clone();
    let soleus = "/forceset/soleus_r";
    let k = rad.labels.iter().position(|l| l == soleus).unwrap();
    strong.rows[2][k] = 5.0;
    // An activation outside [0, 1]; a last time (the guess's t_f) beyond
    // the final time's bounds.
    let mut active = rad.clone();
    let act = "/forceset/soleus_r/activation";
    let ka = rad.labels.iter().position(|l| l == act).unwrap();
    active.rows[2][ka] = 7.0;
    let mut long = rad.clone();
    long.time = vec![0.0, 5.0, 10.0, 15.0];
    let tf = 15;
    // A left leg's column that is not its right partner's copy, a state's
    // and an excitation's: the symmetric model cannot carry it.
    let column = |l: &str| rad.labels.iter().position(|x| x == l).unwrap();
    let (knee_l, knee_r) = (
        "/jointset/knee_l/knee_angle_l/value",
        "/jointset/knee_r/knee_angle_r/value",
    );
    let mut bent = rad.clone();
    bent.rows[2][column(knee_r)] = -1.375;
    bent.rows[2][column(knee_l)] = -1.25;
    let mut uneven = rad.clone();
    uneven.rows[1][column("/forceset/soleus_l")] = 0.9;
    let sr = uneven.rows[1][k];
    for (name, table, want) in [
        (
            "active",
            active,
            format!("column '{act}': row 3 (t = 0.1): an activation must be in [0, 1], got 7"),
        ),
        (
            "long",
            long,
            format!("time: ends at {tf} s, outside the final time's bounds [0.1, 1] s (the study's problem.time_final_bounds; the guess's last time is its t_f)"),
        ),
        (
            "nan",
            nan,
            format!("column '{hip}': row 3 (t = 0.1): NaN is not a finite number"),
        ),
        ("one", one, "1 data row; at least 2 are needed".to_string()),
        (
            "strong",
            strong,
            format!("column '{soleus}': row 3 (t = 0.1): excitation 5 is not a number in [0, 1]"),
        ),
        (
            "inf",
            inf,
            "column 'time': row 4: inf is not finite".to_string(),
        ),
        (
            "bent",
            bent,
            format!("columns '{knee_l}' and '{knee_r}' differ at row 3 (t = 0.1): -1.25 and -1.375; the symmetric model gives both legs one value, its right leg's: give both columns the same values, or leave out the left leg's columns"),
        ),
        (
            "uneven",
            uneven,
            format!("columns '/forceset/soleus_l' and '{soleus}' differ at row 2 (t = 0.05): 0.9 and {sr}; the symmetric model gives both legs one value, its right leg's: give both columns the same values, or leave out the left leg's columns"),
        ),
        (
            "repeated",
            repeated,
            "column 'time': not strictly increasing: row 3 has t = 0.05 after t = 0.05".to_string(),
        ),
    ] {
        let p = dir.join(format!("{name}.sto"));
        table.write_sto(&p).unwrap();
        let e = leap::solve::guess_from_file(&tr, &p)
            .unwrap_err()
            .to_string();
        assert_eq!(e, format!("{}: {want}", p.display()), "{name}");
        // Integrated on the mesh (integrate_guess), only the excitations
        // and times are read: the activation of 7 is no error there. A NaN
        // is, in any column.
        let e = leap::solve::guess_from_excitations_file(&tr, &p).map_err(|e| e.to_string());
        match name {
            "active" | "bent" => assert!(e.is_ok(), "{name}: {e:?}"),
            _ => assert_eq!(e.unwrap_err(), format!("{}: {want}", p.display()), "{name}"),
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_missing_or_binary_file_is_named_once_with_one_reason() {
    let e = StoTable::read(Path::new("no_such_dir/none.sto"))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("no_such_dir/none.sto: "), "{e}");
    // The OS error is the message, not also a `source` that `{:#}` repeats.
    let any = anyhow::Error::new(StoTable::read(Path::new("none.sto")).unwrap_err());
    let full = format!("{any:#}");
    assert_eq!(full.matches("os error").count(), 1, "{full}");
    let dir = scratch("binary");
    let p = dir.join("bin.sto");
    std::fs::write(&p, b"name\nendheader\ntime\tx\n0\t\xff\x00\n").unwrap();
    let e = StoTable::read(&p).unwrap_err().to_string();
    assert_eq!(
        e,
        format!("{}: line 4: not UTF-8 text (a binary file?)", p.display())
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn controls_refuse_an_infinite_time_and_take_one_row() {
    let dir = scratch("controls");
    let mut t = StoTable {
        labels: vec!["/forceset/soleus_r".into()],
        time: vec![0.0],
        rows: vec![vec![0.5]],
        ..Default::default()
    };
    let p = dir.join("one.sto");
    t.write_sto(&p).unwrap();
    let c = Controls::from_file(&p, &["soleus_r"]).unwrap();
    let mut u = [0.0];
    c.at(1.0, &mut u);
    assert_eq!(u, [0.5]);
    let refusal = |t: &StoTable| {
        t.write_sto(&p).unwrap();
        let e = Controls::from_file(&p, &["soleus_r"]).unwrap_err();
        e.to_string()
    };
    t.time.push(f64::INFINITY);
    t.rows.push(vec![0.5]);
    assert_eq!(
        refusal(&t),
        format!("{}: column 'time': row 2: inf is not finite", p.display())
    );
    // No row at all: one is needed.
    t.time.clear();
    t.rows.clear();
    assert_eq!(
        refusal(&t),
        format!("{}: 0 data rows; at least 1 is needed", p.display())
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn directories_and_devices_are_refused_as_input_files() {
    // /dev/zero would fill the memory; a directory is not "not found".
    let sto = leap::io::StoTable::read(Path::new("/dev/zero"))
        .unwrap_err()
        .to_string();
    assert!(sto.contains("/dev/zero") && sto.contains("device"), "{sto}");
    let model = leap::model::Model::from_file("/dev/zero")
        .unwrap_err()
        .to_string();
    assert!(
        model.contains("/dev/zero") && model.contains("device"),
        "{model}"
    );
    let dir = leap::model::Model::from_file("models")
        .unwrap_err()
        .to_string();
    assert!(dir.contains("models") && dir.contains("directory"), "{dir}");
    let study = leap::study::read_study::<leap::study::SolveStudy>(Path::new("tests"))
        .unwrap_err()
        .to_string();
    assert!(study.contains("directory"), "{study}");
    // A pipe is read (up to the limit): process substitution works.
    let fifo = scratch("fifo").join("controls.sto");
    let _ = std::fs::remove_file(&fifo);
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            std::fs::write(&fifo, "endheader\ntime\ta\n0\t1\n0.1\t2\n").unwrap()
        })
    };
    let t = StoTable::read(&fifo).unwrap();
    writer.join().unwrap();
    assert_eq!((t.labels.len(), t.time.len()), (1, 2));
    let _ = std::fs::remove_dir_all(fifo.parent().unwrap());
}

/// An output file is written whole or not at all: a write that fails
/// midway, or panics, leaves the previous file as it was and no partial
/// file beside it; one that succeeds replaces it, with its permissions.
#[test]
fn output_files_are_written_whole_or_not_at_all() {
    let dir = scratch("write_output");
    let path = dir.join("jump_summary.json");
    leap::io::write_output(&path, "old").unwrap();
    let failed = leap::io::write_output_with(&path, |f| {
        std::io::Write::write_all(f, b"half of the new")?;
        Err(std::io::Error::other("disk full"))
    });
    assert_eq!(failed.unwrap_err().to_string(), "disk full");
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("jump_summary.json")]);
    // A panic while writing leaves no partial file either.
    let panicked = std::panic::catch_unwind(|| {
        leap::io::write_output_with(&path, |_| panic!("a bug in the writer"))
    });
    assert!(panicked.is_err());
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("jump_summary.json")]);
    // The replacement keeps the replaced file's permissions.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).unwrap();
    }
    leap::io::write_output(&path, "new").unwrap();
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(&path).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o600);
    }
    // A name near the file system's 255-byte limit still fits.
    let long = dir.join(format!("{}.sto", "x".repeat(250)));
    leap::io::write_output(&long, "long").unwrap();
    assert_eq!(std::fs::read_to_string(&long).unwrap(), "long");
    // A directory in the way is an error naming it, and stays a directory.
    std::fs::create_dir_all(dir.join("sub.sto")).unwrap();
    let e = leap::io::write_output(&dir.join("sub.sto"), "x").unwrap_err();
    assert!(
        e.to_string()
            .contains("sub.sto: is a directory, not a file"),
        "{e}"
    );
    assert!(dir.join("sub.sto").is_dir());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A header key given twice with different values is refused, naming both
/// lines: `inDegrees=no` then `inDegrees=yes` had let the last one win and
/// `leap analyze` read radians as degrees (a −22 cm "jump"). The same value
/// twice is harmless.
#[test]
fn a_header_key_given_twice_with_different_values_is_refused() {
    let p = Path::new("twice.sto");
    let body = "endheader\ntime\tq\n0\t0.1\n0.1\t0.2\n";
    let e = StoTable::parse(&format!("states\ninDegrees=no\ninDegrees=yes\n{body}"), p)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "twice.sto: line 3: header key 'inDegrees' given twice: 'no' on line 2, 'yes' here"
    );
    let t = StoTable::parse(
        &format!("states\ninDegrees=yes\ninDegrees = yes\n{body}"),
        p,
    )
    .unwrap();
    assert_eq!(t.metadata["inDegrees"], "yes");
    assert_eq!(t.rows.len(), 2);
}

/// `nRows` and `nColumns`, as `write_mot` writes them (time is a column),
/// are checked against the file: a file cut at a line boundary had read as
/// complete.
#[test]
fn header_row_and_column_counts_that_disagree_with_the_file_are_refused() {
    let p = Path::new("counts.mot");
    let body = "endheader\ntime\ta\tb\n0\t1\t2\n0.1\t3\t4\n";
    let t = StoTable::parse(&format!("m\nversion=1\nnRows=2\nnColumns=3\n{body}"), p).unwrap();
    assert_eq!((t.labels.len(), t.time.len()), (2, 2));
    assert!(!t.metadata.contains_key("nRows") && !t.metadata.contains_key("nColumns"));
    for (header, want) in [
        (
            "nRows=3\nnColumns=3",
            "counts.mot: header 'nRows': declares 3 data rows, the file has 2",
        ),
        (
            "nRows=2\nnColumns=2",
            "counts.mot: header 'nColumns': declares 2 columns (time included), the file has 3",
        ),
        (
            "nRows=two",
            "counts.mot: header 'nRows': 'two' is not a count",
        ),
    ] {
        let e = StoTable::parse(&format!("m\nversion=1\n{header}\n{body}"), p)
            .unwrap_err()
            .to_string();
        assert_eq!(e, want, "{header}");
        // Without a version the counts hold as in version 1; from version
        // 2 on OpenSim's reader ignores them (its tables write them back
        // unchanged after a trim), and so does leap's.
        let e = StoTable::parse(&format!("m\n{header}\n{body}"), p)
            .unwrap_err()
            .to_string();
        assert_eq!(e, want, "{header}");
        let t = StoTable::parse(&format!("m\nversion=3\n{header}\n{body}"), p).unwrap();
        assert_eq!((t.labels.len(), t.time.len()), (2, 2), "{header}");
    }
    // A file leap wrote, cut after its third data row.
    let dir = scratch("counts");
    let full = dir.join("full.mot");
    let t = StoTable {
        name: Some("grf".into()),
        labels: vec!["a".into()],
        time: vec![0.0, 0.1, 0.2, 0.3, 0.4],
        rows: vec![vec![1.0]; 5],
        ..Default::default()
    };
    t.write_mot(&full).unwrap();
    assert_eq!(StoTable::read(&full).unwrap().time.len(), 5);
    let text = std::fs::read_to_string(&full).unwrap();
    let cut = dir.join("cut.mot");
    let keep = text.find("0.3\t").unwrap();
    std::fs::write(&cut, &text[..keep]).unwrap();
    let e = StoTable::read(&cut).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "{}: header 'nRows': declares 5 data rows, the file has 3",
            cut.display()
        )
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A tab at the end of every line, the label line's and the data lines',
/// makes no column: the label line kept an empty last label and every row
/// was one value short. An empty label between two others is refused.
#[test]
fn a_trailing_tab_makes_no_column_and_an_empty_label_inside_is_refused() {
    let p = Path::new("tabs.sto");
    let want = StoTable::parse("endheader\ntime\ta\tb\n0\t1\t2\n0.1\t3\t4\n", p).unwrap();
    for text in [
        "endheader\ntime\ta\tb\t\n0\t1\t2\t\n0.1\t3\t4\t\n",
        "endheader\r\ntime\ta\tb\t\r\n0\t1\t2\t\r\n0.1\t3\t4\t\r\n",
        // On the label line alone.
        "endheader\ntime\ta\tb\t\n0\t1\t2\n0.1\t3\t4\n",
    ] {
        assert_eq!(StoTable::parse(text, p).unwrap(), want, "{text:?}");
    }
    let e = StoTable::parse("endheader\ntime\t\tb\n0\t1\t2\n", p)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "tabs.sto: line 2: column 2 has no label (time is column 1)"
    );
}

/// Old Mac OS line ends, a carriage return alone, end lines as a newline
/// does: such a file was one line without 'endheader'.
#[test]
fn carriage_return_line_ends_are_read() {
    let p = Path::new("cr.sto");
    let lf = "states\ninDegrees=no\nendheader\ntime\ta\n0\t1\n0.1\t2\n";
    let want = StoTable::parse(lf, p).unwrap();
    assert_eq!(StoTable::parse(&lf.replace('\n', "\r"), p).unwrap(), want);
    // Mixed with LF and CRLF (files pasted together), a blank line kept.
    let mixed = "states\r\ninDegrees=no\rendheader\ntime\ta\r\r0\t1\n0.1\t2";
    assert_eq!(StoTable::parse(mixed, p).unwrap(), want);
    // Lines are counted by them.
    let e = StoTable::parse("endheader\rtime\ta\r0\t1\r0.1\tabc\r", p)
        .unwrap_err()
        .to_string();
    assert_eq!(e, "cr.sto: line 4: column 'a': 'abc' is not a number");
    let dir = scratch("cr");
    let f = dir.join("bin.sto");
    std::fs::write(&f, b"name\rendheader\rtime\tx\r0\t\xff\r").unwrap();
    let e = StoTable::read(&f).unwrap_err().to_string();
    assert_eq!(
        e,
        format!("{}: line 4: not UTF-8 text (a binary file?)", f.display())
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A number too large for a double is named as written, not as the
/// infinity it parses to.
#[test]
fn a_number_that_overflows_is_named_as_written() {
    let p = Path::new("big.sto");
    for (text, want) in [
        (
            "endheader\ntime\ta\n0\t1\n1e400\t2\n",
            "big.sto: line 4: column 'time': '1e400' is not a finite number (it overflows)",
        ),
        (
            "endheader\ntime\ta\n0\t-1.5E+999\n",
            "big.sto: line 3: column 'a': '-1.5E+999' is not a finite number (it overflows)",
        ),
    ] {
        let e = StoTable::parse(text, p).unwrap_err().to_string();
        assert_eq!(e, want);
    }
    // The largest double is a number; Inf, written as such, is read (and
    // refused by the readers that use the table).
    let t = StoTable::parse(
        "endheader\ntime\ta\n0\t1.7976931348623157e308\n0.1\tInf\n",
        p,
    )
    .unwrap();
    assert_eq!(t.rows, [[f64::MAX], [f64::INFINITY]]);
}

/// A value that is not finite is refused in any column, not only in the
/// columns a command reads: `leap analyze` read a NaN excitation, `leap
/// simulate --controls` a NaN state.
#[test]
fn a_non_finite_value_in_a_column_not_read_is_refused() {
    let ocp = jumper_ocp();
    let eq = &ocp.eq;
    let dir = scratch("non_finite");
    let rad = states_table(eq, ocp.x0());
    let column = |l: &str| rad.labels.iter().position(|x| x == l).unwrap();
    let (soleus, hip) = ("/forceset/soleus_r", "/jointset/hip_r/hip_flexion_r/value");
    let muscles: Vec<&str> = eq
        .muscles
        .iter()
        .map(|&m| eq.model.muscles[m].spec.name.as_str())
        .collect();
    // States: an excitation (and an extra column) nobody reads.
    let mut t = rad.clone();
    t.rows[1][column(soleus)] = f64::NAN;
    let p = dir.join("exc_nan.sto");
    t.write_sto(&p).unwrap();
    let want = format!(
        "{}: column '{soleus}': row 2 (t = 0.05): NaN is not a finite number",
        p.display()
    );
    let e = leap::analyze::read_states(eq, &p).unwrap_err().to_string();
    assert_eq!(e, want);
    let mut t = rad.clone();
    t.labels.push("/extra".into());
    for (r, row) in t.rows.iter_mut().enumerate() {
        row.push(if r == 2 { f64::NEG_INFINITY } else { 0.0 });
    }
    t.write_sto(&p).unwrap();
    let e = leap::analyze::read_states(eq, &p).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "{}: column '/extra': row 3 (t = 0.1): -inf is not a finite number",
            p.display()
        )
    );
    // Controls: a state column nobody reads.
    let mut t = rad.clone();
    t.rows[2][column(hip)] = f64::NAN;
    t.write_sto(&p).unwrap();
    let e = Controls::from_file(&p, &muscles).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "{}: column '{hip}': row 3 (t = 0.1): NaN is not a finite number",
            p.display()
        )
    );
    // An excitation that is read keeps its own reason.
    let e = Controls::from_file(Path::new("tests/data/controls/jumper_nan.sto"), &muscles)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("row 2 (t = 0.1): excitation NaN is not a number in [0, 1]"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// With `inDegrees=yes`, a left column that differs from its right
/// partner is shown with the file's own values, in degrees, and said to
/// be: they had been shown converted to radians, without a word.
#[test]
fn a_left_right_mismatch_in_degrees_shows_the_files_values() {
    let ocp = jumper_ocp();
    let eq = &ocp.eq;
    let dir = scratch("mismatch_degrees");
    let mut deg = in_degrees(&states_table(eq, ocp.x0()), "yes");
    let (knee_l, knee_r) = (
        "/jointset/knee_l/knee_angle_l/value",
        "/jointset/knee_r/knee_angle_r/value",
    );
    let column = |l: &str| deg.labels.iter().position(|x| x == l).unwrap();
    let (kl, kr) = (column(knee_l), column(knee_r));
    deg.rows[2][kr] = -80.0;
    deg.rows[2][kl] = -70.0;
    let p = dir.join("deg.sto");
    deg.write_sto(&p).unwrap();
    let e = leap::io::read_states(eq, &p).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "{}: columns '{knee_l}' and '{knee_r}' differ at row 3 (t = 0.1): -70 and -80 (the file's values, in degrees); the symmetric model gives both legs one value, its right leg's: give both columns the same values, or leave out the left leg's columns",
            p.display()
        )
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A left column that differs from its right partner is named with it,
/// neither as the culprit: the right one may be the absurd one.
#[test]
fn a_left_right_mismatch_names_both_columns_alike() {
    let ocp = jumper_ocp();
    let eq = &ocp.eq;
    let dir = scratch("mismatch");
    let mut t = states_table(eq, ocp.x0());
    let (left, right) = (
        "/forceset/soleus_l/fiber_length",
        "/forceset/soleus_r/fiber_length",
    );
    let k = t.labels.iter().position(|x| x == right).unwrap();
    t.rows[1][k] = 1e6;
    let p = dir.join("huge.sto");
    t.write_sto(&p).unwrap();
    // The left value as the file gives it.
    let kl = t.labels.iter().position(|x| x == left).unwrap();
    let fibre = StoTable::read(&p).unwrap().rows[1][kl];
    let e = leap::io::read_states(eq, &p).unwrap_err().to_string();
    assert_eq!(
        e,
        format!(
            "{}: columns '{left}' and '{right}' differ at row 2 (t = 0.05): {fibre} and 1e6; the symmetric model gives both legs one value, its right leg's: give both columns the same values, or leave out the left leg's columns",
            p.display()
        )
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A Moco solution with parameters holds each parameter's value in the
/// first row and NaN in the later ones (`MocoTrajectory::convertToTable`):
/// such a column is read past, while the same NaNs without
/// `num_parameters` in the header, or a NaN in a parameter column's first
/// row, are refused.
#[test]
fn moco_parameter_columns_with_nan_after_the_first_row_are_accepted() {
    let p = Path::new("params.sto");
    let body =
        "endheader\ntime\ta\t/bodyset/torso/mass_param\n0\t1\t70\n0.1\t2\tNaN\n0.2\t3\tNaN\n";
    let t = StoTable::parse(&format!("num_parameters=1\n{body}"), p).unwrap();
    t.check_finite(p).unwrap();
    let t = StoTable::parse(body, p).unwrap();
    let e = t.check_finite(p).unwrap_err().to_string();
    assert_eq!(
        e,
        "params.sto: column '/bodyset/torso/mass_param': row 2 (t = 0.1): NaN is not a finite number"
    );
    let first_nan = body.replace("\t70\n", "\tNaN\n");
    let t = StoTable::parse(&format!("num_parameters=1\n{first_nan}"), p).unwrap();
    assert!(t.check_finite(p).is_err());
}

/// A process that quits part-way through writing its results (a repeated
/// Ctrl-C, whose `exit` runs no destructor) can remove the new files of the
/// writes under way (`remove_pending_outputs`, which removes what
/// `pending_outputs` lists): the list holds a write's new file while it is
/// written, and forgets it when the write ends, whether it failed or not.
/// (Removing is not tried here: other tests write in parallel.)
#[test]
fn pending_output_files_are_listed_while_written() {
    use std::io::Write;
    let dir = scratch("pending");
    let target = dir.join("states.sto");
    let mine = || -> Vec<std::path::PathBuf> {
        leap::io::pending_outputs()
            .into_iter()
            .filter(|p| p.parent() == Some(dir.as_path()))
            .collect()
    };
    for fail in [true, false] {
        let r = leap::io::write_output_with(&target, |f| {
            f.write_all(b"part-way")?;
            let listed = mine();
            assert_eq!(listed.len(), 1, "{listed:?}");
            assert!(listed[0].is_file(), "{listed:?}");
            assert_ne!(listed[0], target);
            if fail {
                Err(std::io::Error::other("quit"))
            } else {
                Ok(())
            }
        });
        assert_eq!(r.is_err(), fail);
        assert!(mine().is_empty(), "{:?}", mine());
    }
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "part-way");
    let _ = std::fs::remove_dir_all(&dir);
}
