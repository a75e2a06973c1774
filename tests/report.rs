//! `leap report`: the panels follow Moco's sections with the model's
//! counts, the drawn lines carry the files' values (a file in degrees and
//! one in radians overlay), and bad input is refused naming the file.

use crate::common::refused;
use assert_cmd::Command;
use leap::io::StoTable;
use leap::model::Model;
use leap::ode::StateEquation;
use leap::report::{panels, ReportFile, Section};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

fn model() -> Model {
    Model::from_file(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/models/jumper.json"
    )))
    .unwrap()
}

/// The full system's angular columns, as `leap report` reads files.
fn angular(m: &Model) -> HashSet<String> {
    let (_, eq) = StateEquation::opensim(m, false).unwrap();
    leap::io::angular_columns(&eq)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("leap_report_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A table with every state and excitation column of the model (both
/// legs, OpenSim names), three rows.
fn solution_like(m: &Model) -> StoTable {
    let (_, eq) = StateEquation::opensim(m, false).unwrap();
    let labels: Vec<String> = eq
        .model_state_columns()
        .into_iter()
        .map(|(l, _)| l)
        .chain(
            m.muscles
                .iter()
                .map(|mu| format!("/forceset/{}", mu.spec.name)),
        )
        .collect();
    let rows = (0..3)
        .map(|k| labels.iter().map(|_| 0.1 * k as f64).collect())
        .collect();
    table(labels, vec![0.0, 0.1, 0.2], rows)
}

/// A table of `labels` over `time` with `rows`.
fn table(labels: Vec<String>, time: Vec<f64>, rows: Vec<Vec<f64>>) -> StoTable {
    StoTable {
        labels,
        time,
        rows,
        ..Default::default()
    }
}

fn file(name: &str, table: StoTable) -> ReportFile {
    ReportFile {
        name: name.into(),
        table,
    }
}

#[test]
fn panels_follow_mocos_sections_with_the_models_counts() {
    let m = model();
    let ang = angular(&m);
    let files = [file("s.sto", solution_like(&m))];
    let (nc, nm) = (m.coordinates.len(), m.muscles.len());
    let count =
        |ps: &[leap::report::Panel], s: Section| ps.iter().filter(|p| p.section == s).count();
    let all = panels(&files, false, &ang);
    for (s, n) in [
        (Section::CoordinateValues, nc),
        (Section::CoordinateSpeeds, nc),
        (Section::Activations, nm),
        (Section::FiberLengths, nm),
        (Section::Excitations, nm),
        (Section::Other, 0),
    ] {
        assert_eq!(count(&all, s), n, "{s:?}");
    }
    // Sections in Moco's order.
    assert!(all.windows(2).all(|w| w[0].section <= w[1].section));
    // Bilateral: a left coordinate or muscle joins its right partner's
    // panel; the pelvis and the lumbar joint have no partner.
    let sided = m
        .coordinates
        .iter()
        .filter(|c| c.name.ends_with("_l"))
        .count();
    let both = panels(&files, true, &ang);
    assert_eq!(count(&both, Section::CoordinateValues), nc - sided);
    assert_eq!(count(&both, Section::Activations), nm / 2);
    let hip = both
        .iter()
        .find(|p| p.section == Section::CoordinateValues && p.title == "hip_flexion_r")
        .unwrap();
    assert_eq!(hip.series.len(), 2);
    assert_eq!(hip.series.iter().filter(|s| s.left).count(), 1);
    assert_eq!(hip.y_label, "angle (rad)");
    let tx = both.iter().find(|p| p.title == "pelvis_tx").unwrap();
    assert_eq!(tx.y_label, "position (m)");
    // A ground force file's columns (leap's names, and OpenSim's).
    let grf = table(
        [
            "ground_force_r_vy",
            "ground_force_px",
            "ground_torque_z",
            "other",
        ]
        .map(String::from)
        .to_vec(),
        vec![0.0, 0.1],
        vec![vec![0.0; 4]; 2],
    );
    let ps = panels(&[file("g.mot", grf)], true, &ang);
    let units: Vec<&str> = ps.iter().map(|p| p.y_label.as_str()).collect();
    assert_eq!(units, ["force (N)", "point (m)", "torque (N·m)", ""]);
    assert!(ps.iter().all(|p| p.section == Section::Other));
}

/// Every `<polyline ... stroke-width="W" points="..."/>` of an SVG with
/// stroke width `width`: its points.
fn polylines(svg: &str, width: &str) -> Vec<Vec<(f64, f64)>> {
    svg.lines()
        .filter(|l| l.starts_with("<polyline") && l.contains(&format!("stroke-width=\"{width}\"")))
        .map(|l| {
            let pts = l
                .split("points=\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap();
            pts.split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect()
        })
        .collect()
}

#[test]
fn the_lines_carry_the_values_and_degrees_overlay_radians() {
    let m = model();
    let ang = angular(&m);
    let dir = tmp("lines");
    // A ramp and a sine of the hip angle, in radians in the trajectory and
    // in degrees in the reference.
    let hip = "/jointset/hip_r/hip_flexion_r/value";
    let n = 41;
    let time: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
    let table = |degrees: bool| {
        let rows = time
            .iter()
            .map(|&s| {
                let a = (10.0 * s).sin();
                vec![if degrees { a.to_degrees() } else { a }, 2.0 * s + 1.0]
            })
            .collect();
        let mut t = table(vec![hip.into(), "ramp".into()], time.clone(), rows);
        if degrees {
            t.metadata.insert("inDegrees".into(), "yes".into());
        }
        t
    };
    let (main, reference) = (dir.join("main.sto"), dir.join("deg.sto"));
    table(false).write_sto(&main).unwrap();
    table(true).write_sto(&reference).unwrap();
    let (svg, ps, warnings) =
        leap::report::report(&main, std::slice::from_ref(&reference), false, &ang).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(ps.len(), 2);
    assert_eq!(ps[0].section, Section::CoordinateValues);
    assert_eq!(ps[1].section, Section::Other);
    // Lines of the trajectory (2 px, a legend sample first) and of the
    // reference (4 px, likewise).
    let (ours, refs) = (polylines(&svg, "2"), polylines(&svg, "4"));
    assert_eq!(ours.len(), 3, "legend sample and two panels");
    assert_eq!(refs.len(), 3);
    for (a, b) in ours[1..].iter().zip(&refs[1..]) {
        assert_eq!(a.len(), n);
        // The same values, to the pixel: the file in degrees was read in
        // radians.
        assert_eq!(a, b);
    }
    // The ramp is straight and rises (SVG y grows downwards): each point
    // within the pixel rounding of it and of the two ends (1.5 px).
    let ramp = &ours[2];
    let (p0, p1) = (ramp[0], ramp[n - 1]);
    for &(x, y) in ramp {
        let on_line = p0.1 + (p1.1 - p0.1) * (x - p0.0) / (p1.0 - p0.0);
        assert!(
            (y - on_line).abs() <= 1.5,
            "{x},{y} off the line by {}",
            y - on_line
        );
    }
    assert!(p1.1 < p0.1 && p1.0 > p0.0);
    // Every point of the sine sits where an affine map of its value puts
    // it (the map from the values' extremes), to the pixel rounding.
    let hip_line = &ours[1];
    let value = |k: usize| (10.0 * time[k]).sin();
    let (lo, hi) = (0..n).fold((0, 0), |(lo, hi), k| {
        (
            if value(k) < value(lo) { k } else { lo },
            if value(k) > value(hi) { k } else { hi },
        )
    });
    let (y_lo, y_hi) = (hip_line[lo].1, hip_line[hi].1);
    assert!(y_hi < y_lo, "larger values higher up");
    for (k, &(_, y)) in hip_line.iter().enumerate() {
        let want = y_lo + (y_hi - y_lo) * (value(k) - value(lo)) / (value(hi) - value(lo));
        assert!((y - want).abs() <= 1.5, "point {k}: {y} against {want}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn leap_report_writes_beside_the_trajectory_and_refuses_bad_input() {
    let m = model();
    let dir = tmp("cli");
    let traj = dir.join("jump_solution.sto");
    solution_like(&m).write_sto(&traj).unwrap();
    let other = table(
        vec!["unrelated".into()],
        vec![0.0, 1.0],
        vec![vec![0.0], vec![1.0]],
    );
    let unrelated = dir.join("unrelated.sto");
    other.write_sto(&unrelated).unwrap();
    let o = Command::cargo_bin("leap")
        .unwrap()
        .arg("report")
        .arg(&traj)
        .arg("--ref-files")
        .arg(&unrelated)
        .arg("--json")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("unrelated.sto: no column in common"), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let svg = dir.join("jump_solution_report.svg");
    assert_eq!(v["output"], svg.display().to_string());
    assert!(std::fs::read_to_string(&svg).unwrap().starts_with("<svg"));
    assert_eq!(v["sections"][0]["section"], "coordinate values");
    assert_eq!(v["sections"].as_array().unwrap().len(), 5);
    // Bad input: a missing file, a file with only time, a row of NaN.
    let only_time = dir.join("time.sto");
    std::fs::write(&only_time, "endheader\ntime\n0\n1\n").unwrap();
    let nan = dir.join("nan.sto");
    std::fs::write(&nan, "endheader\ntime\tx\n0\t1\n1\tNaN\n").unwrap();
    for (args, what) in [
        (vec![dir.join("none.sto")], "none.sto".to_string()),
        (
            vec![only_time.clone()],
            format!("{}: no column but time to plot", only_time.display()),
        ),
        (vec![nan.clone()], format!("{}", nan.display())),
        (
            vec![traj.clone(), "--ref-files".into(), nan.clone()],
            format!("{}", nan.display()),
        ),
    ] {
        let err = refused(
            Command::cargo_bin("leap")
                .unwrap()
                .arg("report")
                .args(&args),
            "report",
        );
        assert!(err.contains(&what), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
