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

/// The columns with only `angular` known (no pre-4.0 names).
fn cols(angular: &HashSet<String>) -> leap::io::ModelColumns {
    leap::io::ModelColumns {
        angular: angular.clone(),
        ..Default::default()
    }
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
        .find(|p| p.section == Section::CoordinateValues && p.title == "hip_flexion")
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
        leap::report::report(&main, std::slice::from_ref(&reference), false, &cols(&ang)).unwrap();
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
    // The trajectory as its own reference, and a trajectory of no column of
    // the model (the double pendulum's): drawn, with a warning.
    let o = Command::cargo_bin("leap")
        .unwrap()
        .arg("report")
        .arg(&traj)
        .arg("--ref-files")
        .arg(&traj)
        .arg("--output")
        .arg(dir.join("self.svg"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && err.contains("the reference is the trajectory itself"),
        "{err}"
    );
    let o = Command::cargo_bin("leap")
        .unwrap()
        .arg("report")
        .arg(&traj)
        .args(["--model", "models/double_pendulum.json", "--output"])
        .arg(dir.join("other_model.svg"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success()
            && err.contains("no column names a coordinate, muscle or excitation of the model"),
        "{err}"
    );
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

/// An activation panel of one series of `values` over `time`.
fn panel_of(time: Vec<f64>, values: Vec<f64>) -> leap::report::Panel {
    leap::report::Panel {
        section: Section::Activations,
        title: "x".into(),
        y_label: String::new(),
        series: vec![leap::report::Series {
            file: 0,
            left: false,
            time,
            values,
        }],
    }
}

#[test]
fn y_ranges_hold_fractions_to_0_1_and_refuse_overflowing_spans() {
    use leap::report::panel_ranges;
    let t = vec![0.0, 2.0];
    // Moco's rule: activations, excitations and normalized tendon forces
    // in [0, 1] get the axis [0, 1].
    assert_eq!(
        panel_ranges(&panel_of(t.clone(), vec![0.2, 0.7])).unwrap(),
        ((0.0, 2.0), (0.0, 1.0))
    );
    // Not quantities with units that happen to lie in it (a fibre length
    // in metres, a centre of pressure): their own range, widened by 5%.
    for section in [Section::FiberLengths, Section::Other] {
        let p = leap::report::Panel {
            section,
            ..panel_of(t.clone(), vec![0.08, 0.12])
        };
        let (_, (lo, hi)) = panel_ranges(&p).unwrap();
        assert!(
            (lo - 0.078).abs() < 1e-12 && (hi - 0.122).abs() < 1e-12,
            "{section:?}: {lo} {hi}"
        );
    }
    // Otherwise the range widened by 5% of its size on each side.
    let (_, (lo, hi)) = panel_ranges(&panel_of(t.clone(), vec![-1.0, 3.0])).unwrap();
    assert!(
        (lo + 1.2).abs() < 1e-12 && (hi - 3.2).abs() < 1e-12,
        "{lo} {hi}"
    );
    // A constant gets a span; NaN (a Moco parameter's rows) is left out.
    let (_, (lo, hi)) = panel_ranges(&panel_of(t.clone(), vec![5.0, f64::NAN])).unwrap();
    assert!(lo < 5.0 && hi > 5.0);
    // Spans beyond a double are refused: plotters does not finish on them.
    for (time, values) in [
        (t.clone(), vec![0.0, 1.75e308]),
        (t.clone(), vec![-1e308, 1e308]),
        (vec![-1.7e308, 1.7e308], vec![0.0, 2.0]),
    ] {
        let e = panel_ranges(&panel_of(time, values)).unwrap_err();
        assert!(e.contains("overflows a double"), "{e}");
    }
}

#[test]
fn left_columns_are_dashed_references_cut_and_parameters_left_out() {
    let ang = HashSet::new();
    let dir = tmp("styles");
    let main = dir.join("bil.sto");
    std::fs::write(
        &main,
        "num_states=0\nnum_controls=2\nnum_parameters=1\nendheader\n\
         time\ta_r\ta_l\tmass\n0\t0.1\t0.2\t70\n1\t0.5\t0.6\tNaN\n",
    )
    .unwrap();
    let width2 = |svg: &str| polylines(svg, "2").len();
    let (plain, ps, _) = leap::report::report(&main, &[], false, &cols(&ang)).unwrap();
    // The parameter column (its value, then NaN) is no panel.
    assert_eq!(
        ps.iter().map(|p| p.title.as_str()).collect::<Vec<_>>(),
        ["a_r", "a_l"]
    );
    assert_eq!(width2(&plain), 3, "legend sample and two solid lines");
    let (both, ps, _) = leap::report::report(&main, &[], true, &cols(&ang)).unwrap();
    assert_eq!(ps.len(), 1);
    assert_eq!(ps[0].title, "a", "both sides: no side in the name");
    assert!(width2(&both) > 5, "the left line drawn in dashes");
    // A reference reaching past the trajectory is cut to its time span.
    let longer = dir.join("longer.sto");
    std::fs::write(&longer, "endheader\ntime\ta_r\n-1\t0\n0.5\t0.3\n3\t0.9\n").unwrap();
    let (_, ps, _) = leap::report::report(&main, &[longer], false, &cols(&ang)).unwrap();
    let reference = ps[0].series.iter().find(|s| s.file == 1).unwrap();
    assert_eq!(reference.time, [0.5]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A long file is drawn with a few points per pixel column, its extremes
/// kept: a one-row spike among 50,000 rows reaches the same pixel as in a
/// three-row file of the same ranges.
#[test]
fn long_files_are_thinned_keeping_their_extremes() {
    let ang = HashSet::new();
    let dir = tmp("thin");
    let n = 50_000;
    let spike = 31_337;
    let time: Vec<f64> = (0..n).map(|k| k as f64 / (n - 1) as f64).collect();
    let values: Vec<f64> = (0..n).map(|k| if k == spike { 1.0 } else { 0.0 }).collect();
    let long = dir.join("long.sto");
    table(
        vec!["x".into()],
        time.clone(),
        values.iter().map(|&v| vec![v]).collect(),
    )
    .write_sto(&long)
    .unwrap();
    let short = dir.join("short.sto");
    table(
        vec!["x".into()],
        vec![0.0, time[spike], 1.0],
        vec![vec![0.0], vec![1.0], vec![0.0]],
    )
    .write_sto(&short)
    .unwrap();
    let line = |f: &Path| {
        let (svg, _, _) = leap::report::report(f, &[], false, &cols(&ang)).unwrap();
        polylines(&svg, "2").remove(1)
    };
    let (long_line, short_line) = (line(&long), line(&short));
    assert!(long_line.len() < 4 * 330, "{} points", long_line.len());
    let top = |l: &[(f64, f64)]| l.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let bottom = |l: &[(f64, f64)]| l.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(top(&long_line), top(&short_line));
    assert_eq!(bottom(&long_line), bottom(&short_line));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_output_may_not_be_an_input_nor_in_a_missing_directory() {
    let dir = tmp("output");
    let traj = dir.join("a.sto");
    table(vec!["x".into()], vec![0.0, 1.0], vec![vec![0.0], vec![1.0]])
        .write_sto(&traj)
        .unwrap();
    let before = std::fs::read_to_string(&traj).unwrap();
    for (output, what) in [
        (traj.clone(), "the report would overwrite it"),
        (dir.join("no_dir/r.svg"), "does not exist"),
        (dir.join("r.png"), "name the file .svg"),
        (
            dir.clone(),
            "--output is a directory; name the .svg file to write (such as",
        ),
    ] {
        let err = refused(
            Command::cargo_bin("leap")
                .unwrap()
                .arg("report")
                .arg(&traj)
                .arg("--output")
                .arg(&output),
            "report --output",
        );
        assert!(err.contains(what), "{err}");
    }
    assert_eq!(std::fs::read_to_string(&traj).unwrap(), before);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The text of every `<text>` element of an SVG, trimmed.
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = &t[t.find('>')? + 1..];
            Some(body[..body.find("</text>")?].trim().to_string())
        })
        .collect()
}

#[test]
fn tick_labels_read_zero_without_a_sign() {
    let ang = HashSet::new();
    let dir = tmp("ticks");
    // Ranges whose tick at zero plotters computes as a tiny negative
    // number (-0.7..0.2 and -0.12..0.08 printed "-0.0"), and some that
    // never did.
    for (k, (a, b)) in [
        (-0.7, 0.2),
        (-0.12, 0.08),
        (-1.0, 1.0),
        (-0.3, 0.3),
        (-10.0, 10.0),
    ]
    .into_iter()
    .enumerate()
    {
        let time: Vec<f64> = (0..50).map(|i| i as f64 / 49.0).collect();
        let rows = time
            .iter()
            .map(|&t| vec![a + (b - a) * (0.5 - 0.5 * (std::f64::consts::PI * t).cos())])
            .collect();
        let path = dir.join(format!("r{k}.sto"));
        table(vec!["x".into()], time, rows)
            .write_sto(&path)
            .unwrap();
        let (svg, _, _) = leap::report::report(&path, &[], false, &cols(&ang)).unwrap();
        let ticks: Vec<f64> = texts(&svg)
            .iter()
            .filter_map(|t| t.parse::<f64>().ok())
            .collect();
        // The y ticks and the time ticks 0.0, 0.5, 1.0 at least; zero
        // among the y ticks of every range here.
        assert!(ticks.len() >= 6, "[{a}, {b}]: ticks {ticks:?}");
        let zeros: Vec<String> = texts(&svg)
            .into_iter()
            .filter(|t| t.parse::<f64>() == Ok(0.0))
            .collect();
        assert!(zeros.len() >= 2, "[{a}, {b}]: zeros {zeros:?}");
        assert!(
            zeros.iter().all(|t| !t.starts_with('-')),
            "[{a}, {b}]: a zero tick with a sign: {zeros:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tick_labels_tell_close_ticks_apart_and_round_ones_plainly() {
    let ang = HashSet::new();
    let dir = tmp("tick_digits");
    // A span of 1e-6 about -0.4352 (plotters' own text printed one label
    // five times), and one of 1,000 N (it printed "800.0").
    // Spans that are rounding (1e-14 at 0.7, 1e-10 at 100, 1e-19 at
    // 3e-18) are drawn as constants: the same label three times, or 36
    // characters, before.
    for (k, (a, b, plain)) in [
        (-0.4352005, -0.4351995, false),
        (0.0, 1000.0, true),
        (0.7, 0.70000000000001, false),
        (100.0, 100.0000000001, false),
        (-3.3e-18, -3.2e-18, false),
    ]
    .into_iter()
    .enumerate()
    {
        let time = vec![0.0, 0.5, 1.0];
        let rows = vec![vec![a], vec![0.5 * (a + b)], vec![b]];
        let path = dir.join(format!("d{k}.sto"));
        table(vec!["x".into()], time, rows)
            .write_sto(&path)
            .unwrap();
        let (svg, _, _) = leap::report::report(&path, &[], false, &cols(&ang)).unwrap();
        // The y ticks: plotters anchors their texts at the end.
        let y: Vec<String> = svg
            .split("<text")
            .filter(|t| t.contains("text-anchor=\"end\""))
            .filter_map(|t| {
                let body = &t[t.find('>')? + 1..];
                Some(body[..body.find("</text>")?].trim().to_string())
            })
            .collect();
        let values: Vec<f64> = y.iter().map(|t| t.parse().unwrap()).collect();
        assert!(values.len() >= 2, "[{a}, {b}]: {y:?}");
        let mut distinct = y.clone();
        distinct.sort();
        distinct.dedup();
        assert_eq!(distinct.len(), y.len(), "[{a}, {b}]: a label twice: {y:?}");
        // Each label within half a step of a tick's value: the ticks are
        // evenly spaced, so neighbouring labels differ by the same step.
        let steps: Vec<f64> = values.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
        assert!(
            steps
                .iter()
                .all(|s| (s - steps[0]).abs() <= 1e-9 * (1.0 + steps[0])),
            "[{a}, {b}]: uneven labels {y:?}"
        );
        if plain {
            assert!(y.iter().all(|t| !t.contains('.')), "{y:?}");
        }
        assert!(y.iter().all(|t| t.len() <= 16), "[{a}, {b}]: {y:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// OpenSim's inverse kinematics writes coordinates by their pre-4.0
/// names (`hip_flexion_r`, in degrees): such a file overlays a solution's
/// `/jointset/.../value` columns, converted to radians, as Moco's
/// `TabOpUseAbsoluteStateNames` reads it; a reference outside the
/// trajectory's time span is warned of.
#[test]
fn an_ik_file_overlays_by_its_pre_4_names_and_a_reference_elsewhere_in_time_is_warned_of() {
    let m = model();
    let (_, eq) = StateEquation::opensim(&m, false).unwrap();
    let columns = leap::io::ModelColumns::of(&eq);
    let dir = tmp("ik");
    let time: Vec<f64> = (0..21).map(|k| k as f64 * 0.01).collect();
    let hip = |t: f64| 1.2 - 3.0 * t * t;
    let tx = |t: f64| 0.1 * t;
    let solution = table(
        vec![
            "/jointset/hip_r/hip_flexion_r/value".into(),
            "/jointset/ground_pelvis/pelvis_tx/value".into(),
            "/forceset/soleus_r/activation".into(),
            "/forceset/soleus_r".into(),
        ],
        time.clone(),
        time.iter()
            .map(|&t| vec![hip(t), tx(t), t, 1.0 - t])
            .collect(),
    );
    let mut ik = table(
        vec![
            "hip_flexion_r".into(),
            "pelvis_tx".into(),
            "soleus_r.activation".into(),
            "soleus_r.excitation".into(),
        ],
        time.clone(),
        time.iter()
            .map(|&t| vec![hip(t).to_degrees(), tx(t), t, 1.0 - t])
            .collect(),
    );
    ik.metadata.insert("inDegrees".into(), "yes".into());
    let (main, reference) = (dir.join("solution.sto"), dir.join("ik.mot"));
    solution.write_sto(&main).unwrap();
    ik.write_sto(&reference).unwrap();
    let (svg, ps, warnings) =
        leap::report::report(&main, std::slice::from_ref(&reference), false, &columns).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    for p in &ps {
        assert_eq!(p.series.len(), 2, "{}: the IK column joins it", p.title);
    }
    assert_eq!(ps[0].section, Section::CoordinateValues);
    // The same points, to the pixel: names mapped, degrees converted
    // (the hip), metres kept (pelvis_tx).
    let (ours, refs) = (polylines(&svg, "2"), polylines(&svg, "4"));
    assert_eq!(ours.len(), 5, "legend sample and four panels");
    assert_eq!(ours[1..], refs[1..]);
    // The reading itself: the renamed columns, the hip in radians.
    let f = leap::report::ReportFile::read(&reference, &columns).unwrap();
    assert_eq!(f.table.labels[0], "/jointset/hip_r/hip_flexion_r/value");
    assert_eq!(f.table.labels[2], "/forceset/soleus_r/activation");
    assert_eq!(f.table.labels[3], "/forceset/soleus_r");
    assert!((f.table.rows[20][0] - hip(0.2)).abs() < 1e-12);
    assert!((f.table.rows[20][1] - tx(0.2)).abs() < 1e-15);
    // A reference a second later than the solution: warned of, not drawn.
    let mut later = ik.clone();
    later.time.iter_mut().for_each(|t| *t += 1.0);
    let later_path = dir.join("later.mot");
    later.write_sto(&later_path).unwrap();
    let (_, ps, warnings) =
        leap::report::report(&main, std::slice::from_ref(&later_path), false, &columns).unwrap();
    assert!(
        warnings.len() == 1 && warnings[0].contains("0 of its rows"),
        "{warnings:?}"
    );
    assert!(ps
        .iter()
        .all(|p| p.series.iter().all(|s| s.file == 0 || s.time.is_empty())));
    let _ = std::fs::remove_dir_all(&dir);
}
