//! `leap analyze` against the laws of mechanics: with the feet in the air
//! the work of the muscles and passive joint torques must equal the change
//! of kinetic plus potential energy (the work-energy theorem), and over a
//! push-off the vertical ground impulse less the weight's must equal the
//! change of COM momentum (Newton's second law), on trajectories integrated
//! by the Rust-native Dormand-Prince with OpenSim's laws.

use crate::common::{assert_push_off_consistent, extensor_bang_bang, FixedExcitation};
use leap::analyze::analyze;
use leap::integrator::{Dopri5, Dopri5Options};
use leap::laws::OpenSimLaws;
use leap::ode::StateEquation;
use leap::path::PathSmoothing;
use leap::simulate::{simulate_rust, standing_com_height};

fn jumper() -> (leap::model::Model, StateEquation, OpenSimLaws, Vec<f64>) {
    let model = leap::model::Model::from_file("models/jumper_gait2392.json").unwrap();
    let eq = StateEquation::new(&model, true, PathSmoothing::Exact).unwrap();
    let laws = OpenSimLaws::new(&model).unwrap();
    let ocp = leap::ocp::JumpOcp::new(&model, Default::default()).unwrap();
    let x0 = ocp.x0().to_vec();
    (model, eq, laws, x0)
}

#[test]
fn muscle_and_passive_work_equal_the_energy_change_in_the_air() {
    let (model, eq, laws, mut x0) = jumper();
    // The squat lifted 0.6 m: 0.15 s of free fall and leg motion stay
    // clear of the ground.
    let ty = model.coordinate_index("pelvis_ty").unwrap();
    x0[eq.system.q_of_model_coordinate[ty]] += 0.6;
    let mut sys = FixedExcitation {
        eq: &eq,
        laws: &laws,
        ws: eq.workspace::<f64>(),
        u: vec![0.6; eq.nm()],
    };
    let opts = Dopri5Options {
        accuracy: 1e-9,
        ..Default::default()
    };
    let mut dp = Dopri5::new(&mut sys, 0.0, &x0, opts).unwrap();
    let (t_end, rows) = (0.15, 3000);
    let (mut time, mut states) = (vec![0.0], vec![x0.clone()]);
    let mut next = 1;
    while next <= rows {
        let t = dp.step(&mut sys, t_end).unwrap();
        while next <= rows && (next as f64) * t_end / rows as f64 <= t + 1e-15 {
            let tk = (next as f64) * t_end / rows as f64;
            let mut x = vec![0.0; eq.nx()];
            dp.dense(tk, &mut x);
            time.push(tk);
            states.push(x);
            next += 1;
        }
    }
    let a = analyze(&eq, &laws, &time, &states, Some((0.0, t_end))).unwrap();
    let b = &a.budget;
    assert!(
        a.peak_vertical_grf_bw == 0.0,
        "the feet touched the ground: {} BW",
        a.peak_vertical_grf_bw
    );
    let scale = b.muscle_work_j.abs() + b.passive_torque_work_j.abs();
    assert!(scale > 1.0, "too little work to test: {b:?}");
    assert!(
        b.contact_work_j.abs() <= 1e-3 * scale,
        "ΔE {} J against muscle {} J + passive {} J",
        b.energy_change_j,
        b.muscle_work_j,
        b.passive_torque_work_j
    );
    // In the air the only vertical force is the weight.
    let want = -model.total_mass() * model.gravity[1].abs() * t_end;
    assert!(
        (a.com_momentum_change_ns - want).abs() <= 1e-6 * want.abs(),
        "{} N·s, free fall {want} N·s",
        a.com_momentum_change_ns
    );
}

#[test]
fn push_off_impulse_equals_the_momentum_change_and_the_jump_matches_the_simulation() {
    let (model, eq, laws, x0) = jumper();
    let squat = model.poses["squat"].clone();
    let exc = extensor_bang_bang(&eq, &squat);
    let standing = standing_com_height(&eq);
    let opts = leap::simulate::SimulateOptions {
        t_max: 1.0,
        integrator: Dopri5Options {
            accuracy: 1e-7,
            max_step: 1e-3,
            ..Default::default()
        },
    };
    let (s, traj) = simulate_rust(&eq, &laws, &exc, &x0, standing, opts).unwrap();
    let a = analyze(&eq, &laws, &traj.time, &traj.states, None).unwrap();
    assert!(a.liftoff, "no lift-off found");
    let lt = s.liftoff_time_s.unwrap();
    assert!(
        (a.budget.end_s - lt).abs() <= 2e-3,
        "lift-off at {} s, the simulation's at {lt} s",
        a.budget.end_s
    );
    assert_push_off_consistent(&a, 2e-3, s.jump_height_m, "simulation");
    // The model's own states: every fibre within its force–velocity curve.
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
    assert!(
        a.to_text().starts_with("push-off from 0.000 s"),
        "{}",
        a.to_text()
    );
    // A window given inside the push-off is named as given, and its height
    // is the apex a flight from its end would reach, not the jump's.
    let w = analyze(&eq, &laws, &traj.time, &traj.states, Some((0.1, 0.2))).unwrap();
    assert!(w.window_given && !w.liftoff);
    let text = w.to_text();
    assert!(
        text.starts_with("given window from 0.1") && text.contains("apex if it flew from its end"),
        "{text}"
    );
    // The push-off is driven by the muscles: their net work is most of
    // the energy gained.
    let b = &a.budget;
    assert!(
        b.energy_change_j > 0.0 && b.muscle_work_j > b.energy_change_j * 0.8,
        "{b:?}"
    );
}

/// `read_states` names the file once, then the column and row, for every
/// way a states file can be broken.
#[test]
fn broken_states_files_name_file_column_and_row_once() {
    let (_, eq, _, x0) = jumper();
    let dir = std::env::temp_dir().join(format!("leap-analyze-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = leap::io::StoTable {
        labels: eq.state_names(),
        time: vec![0.0, 0.01, 0.02],
        rows: vec![x0.clone(); 3],
        ..Default::default()
    };
    let ty = "/jointset/ground_pelvis/pelvis_ty/value";
    let k = good.labels.iter().position(|l| l == ty).unwrap();
    let mut nan = good.clone();
    nan.rows[1][k] = f64::NAN;
    let mut inf = good.clone();
    inf.time[2] = f64::INFINITY;
    // An infinite angle is refused by its column, not taken for degrees.
    let knee = "/jointset/knee_r/knee_angle_r/value";
    let kk = good.labels.iter().position(|l| l == knee).unwrap();
    let mut inf_angle = good.clone();
    inf_angle.rows[1][kk] = f64::INFINITY;
    let mut back = good.clone();
    back.time[2] = 0.005;
    let mut one = good.clone();
    one.time.truncate(1);
    one.rows.truncate(1);
    let mut missing = good.clone();
    missing.labels[k] = "pelvis_ty".into();
    // Ground forces: no state column at all.
    let forces = leap::io::StoTable {
        labels: vec!["ground_force_r_vx".into(), "ground_force_r_vy".into()],
        time: vec![0.0, 0.01, 0.02],
        rows: vec![vec![0.0, 700.0]; 3],
        ..Default::default()
    };
    // States under their pre-4.0 names.
    let pre_4 = leap::io::StoTable {
        labels: vec!["knee_angle_r".into(), "knee_angle_r_u".into()],
        ..forces.clone()
    };
    let mut bad_header = good.clone();
    bad_header
        .metadata
        .insert("inDegrees".into(), "radians".into());
    for (name, table, want) in [
        ("nan", nan, format!("column '{ty}': row 2 (t = 0.01): NaN is not a finite number")),
        ("inf", inf, "column 'time': row 3: inf is not finite".into()),
        (
            "inf_angle",
            inf_angle,
            format!("column '{knee}': row 2 (t = 0.01): inf is not a finite number"),
        ),
        (
            "back",
            back,
            "column 'time': not strictly increasing: row 3 has t = 0.005 after t = 0.01".into(),
        ),
        ("one", one, "1 data row; at least 2 are needed".into()),
        (
            "missing",
            missing,
            format!("column '{ty}': missing (a states file of this model's symmetric system is needed; `--full` for the full one)"),
        ),
        (
            "forces",
            forces,
            "column 'ground_force_r_vx': no column of the file names a state of the model by its OpenSim 4 path (/jointset/<joint>/<coordinate>/value, /forceset/<muscle>/fiber_length, …): `leap analyze` reads a states file, a solve's `_solution.sto` or a simulation's `_forward_states.sto`".into(),
        ),
        (
            "pre_4",
            pre_4,
            "column 'knee_angle_r': no column of the file names a state of the model by its OpenSim 4 path (/jointset/<joint>/<coordinate>/value, /forceset/<muscle>/fiber_length, …): `leap analyze` reads a states file, a solve's `_solution.sto` or a simulation's `_forward_states.sto`; its 'knee_angle_r' is the pre-4.0 name of '/jointset/knee_r/knee_angle_r/value'".into(),
        ),
        (
            "bad_header",
            bad_header,
            "header 'inDegrees': 'radians' is neither 'yes' nor 'no'".into(),
        ),
    ] {
        let p = dir.join(format!("{name}.sto"));
        table.write_sto(&p).unwrap();
        let e = leap::analyze::read_states(&eq, &p).unwrap_err().to_string();
        assert_eq!(e, format!("{}: {want}", p.display()), "{name}");
    }
    // A parse error names the file once (it was "X: (file): X: line ...").
    let p = dir.join("no_end.sto");
    std::fs::write(&p, "states\ntime\tx\n").unwrap();
    let e = leap::analyze::read_states(&eq, &p).unwrap_err().to_string();
    assert_eq!(e, format!("{}: line 2: no 'endheader' line", p.display()));
    // A leap model (JSON) given as a table is named as such.
    let e = leap::analyze::read_states(&eq, std::path::Path::new("models/jumper.json"))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("models/jumper.json: line 1: a JSON file (a leap model or study?)"),
        "{e}"
    );
    // So is an OpenSim model (XML), and a table separated by commas.
    let e = leap::analyze::read_states(&eq, std::path::Path::new("models/jumper.osim"))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(
            "models/jumper.osim: line 1: an XML file (an OpenSim .osim model or setup file?)"
        ),
        "{e}"
    );
    let p = dir.join("commas.sto");
    std::fs::write(&p, "states\nendheader\ntime,x\n0,1\n").unwrap();
    let e = leap::analyze::read_states(&eq, &p).unwrap_err().to_string();
    assert!(
        e.ends_with("got 'time,x' (columns separated by commas: a storage table's are separated by tabs, as OpenSim writes them)"),
        "{e}"
    );
    // A good file in radians: the file's values as they are.
    let p = dir.join("good.sto");
    good.write_sto(&p).unwrap();
    let (time, xs) = leap::analyze::read_states(&eq, &p).unwrap();
    let raw = leap::io::StoTable::read(&p).unwrap();
    assert_eq!(time, good.time);
    assert_eq!(xs, raw.rows);
    // `t` written as `name`, and read_states' refusal of it.
    let refusal = |t: &leap::io::StoTable, name: &str| {
        let p = dir.join(name);
        t.write_sto(&p).unwrap();
        let e = leap::analyze::read_states(&eq, &p).unwrap_err().to_string();
        (p, e)
    };
    // The same file headed inDegrees=yes: its angles, the squat's in
    // radians, would be divided by 57; refused, naming the header.
    let mut wrong = good.clone();
    wrong.metadata.insert("inDegrees".into(), "yes".into());
    let (p, e) = refusal(&wrong, "wrong.sto");
    assert!(
        e.starts_with(&format!(
            "{}: header 'inDegrees': the header says yes, but every joint angle lies within ±π",
            p.display()
        )) && e.ends_with("Write inDegrees=no"),
        "{e}"
    );
    // `leap report` refuses it too (it had drawn every angle 57 times too
    // small).
    let columns = leap::io::ModelColumns::of(&eq);
    let e = leap::report::ReportFile::read(&p, &columns)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("header 'inDegrees': the header says yes, but every joint angle lies within ±π"),
        "{e}"
    );
    // Its angles and angular speeds in degrees, as the header says: read
    // back in radians.
    let angular = leap::io::angular_columns(&eq);
    let mut degrees = wrong.clone();
    for (k, label) in degrees.labels.clone().iter().enumerate() {
        if angular.contains(label) {
            for row in &mut degrees.rows {
                row[k] = row[k].to_degrees();
            }
        }
    }
    let p = dir.join("degrees.sto");
    degrees.write_sto(&p).unwrap();
    let (_, xs) = leap::analyze::read_states(&eq, &p).unwrap();
    assert!(leap::report::ReportFile::read(&p, &columns).is_ok());
    for (row, want) in xs.iter().zip(&good.rows) {
        for (a, b) in row.iter().zip(want) {
            assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{a} against {b}");
        }
    }
    // And headed in radians: the squat's knee at some −80 "rad", beyond a
    // whole turn.
    for header in [Some("no"), None] {
        let mut wrong = degrees.clone();
        match header {
            Some(h) => wrong.metadata.insert("inDegrees".into(), h.into()),
            None => wrong.metadata.remove("inDegrees"),
        };
        let (p, e) = refusal(&wrong, "degrees_headed_radians.sto");
        assert!(
            e.starts_with(&format!(
                "{}: header 'inDegrees': the header says no (or has no inDegrees, which means radians), but '",
                p.display()
            )) && e.ends_with("beyond a whole turn (±2π) and its range: a file in degrees? Write inDegrees=yes"),
            "{header:?}: {e}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// States a file can hold but no motion of the model reaches: a coordinate
/// outside its range is warned of (its first row, as `leap eval` words it);
/// a speed so large that the energy overflows is refused naming the row,
/// not reported as an infinite jump; a window holding one row is refused,
/// not integrated over nothing.
#[test]
fn absurd_states_are_warned_of_or_refused_and_one_row_windows_refused() {
    let (_, eq, laws, x0) = jumper();
    let names = eq.state_names();
    let col = |name: &str| names.iter().position(|l| l == name).unwrap();
    let time = vec![0.0, 0.01, 0.02];
    let mut knee = vec![x0.clone(); 3];
    let k = col("/jointset/knee_r/knee_angle_r/value");
    knee[1][k] = 5.0;
    knee[2][k] = 4.0;
    let a = analyze(&eq, &laws, &time, &knee, None).unwrap();
    assert_eq!(
        a.warnings,
        vec!["at t = 0.01 s, its first row outside: /jointset/knee_r/knee_angle_r/value = 5 rad lies outside its range [-2.0944, 0.174533] rad".to_string()],
    );
    let fine = analyze(&eq, &laws, &time, &vec![x0.clone(); 3], None).unwrap();
    assert!(fine.warnings.is_empty(), "{:?}", fine.warnings);
    // A fibre stretched to 1.8 l_opt (within the optimizer's bounds) over
    // a slack tendon: its passive force exceeds the tendon's, so the
    // force–velocity curve is read below zero, far beyond v_max. States
    // of another muscle model read with this one look so (a DeGroote
    // solution's soleus read with Thelen's: 7.3 v_max).
    let vas = eq
        .muscles
        .iter()
        .position(|&m| eq.model.muscles[m].spec.name == "vas_int_r")
        .unwrap();
    let spec = &eq.model.muscles[eq.muscles[vas]].spec;
    let mut stretched = vec![x0.clone(); 3];
    for x in &mut stretched {
        x[col("/forceset/vas_int_r/fiber_length")] = 1.8 * spec.optimal_fiber_length;
    }
    let a = analyze(&eq, &laws, &time, &stretched, None).unwrap();
    let m = a.muscles.iter().find(|m| m.name == "vas_int_r").unwrap();
    assert!(
        m.peak_shortening_ratio > leap::analyze::IMPOSSIBLE_SHORTENING_RATIO,
        "{}",
        m.peak_shortening_ratio
    );
    assert_eq!(a.warnings.len(), 1, "{:?}", a.warnings);
    assert!(
        a.warnings[0].starts_with(&format!(
            "by the model's force–velocity law, fibres shorten faster than muscles can, in times their maximum contraction velocity: vas_int_r {:.2} (0.00 from row to row);",
            m.peak_shortening_ratio
        )),
        "{:?}",
        a.warnings
    );
    let mut fast = vec![x0.clone(); 3];
    fast[1][col("/jointset/ground_pelvis/pelvis_ty/speed")] = 1e300;
    let e = analyze(&eq, &laws, &time, &fast, None)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "row at t = 0.01 s: its states give a non-finite kinetic plus potential energy: a state of that row lies far outside what the model can do"
    );
    // Finite, but no jump: the pelvis a million kilometres up.
    let mut high = vec![x0.clone(); 3];
    high[1][col("/jointset/ground_pelvis/pelvis_ty/value")] = 1e9;
    let e = analyze(&eq, &laws, &time, &high, None)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("row at t = 0.01 s: its states put the centre-of-mass height at ")
            && e.contains("beyond ±1000 (m, m/s)")
            && e.contains("pelvis_ty"),
        "{e}"
    );
    let e = analyze(
        &eq,
        &laws,
        &time,
        &vec![x0.clone(); 3],
        Some((0.005, 0.015)),
    )
    .unwrap_err()
    .to_string();
    assert_eq!(
        e,
        "one row between 0.005 s and 0.015 s (t = 0.01 s): a window needs two rows or more to integrate over"
    );
}

/// A DeGrooteFregly2016Muscle state whose fibre velocity overflows (the
/// tendon force far beyond what the fibre's activation and length hold; the
/// inverted force–velocity curve, a sinh, overflows), as a collocation
/// solution's last node can hold: midpoint Euler enforces the force
/// balance at the interval midpoints only. The state equation refuses such
/// a row; the analysis reads it, warns of it, and leaves it out of that
/// muscle's peak fibre speed alone. The model lists its muscles in reverse
/// (the left leg's first), so that the model's and the system's muscle
/// indices differ.
#[test]
fn a_row_without_a_fibre_velocity_is_warned_of_not_refused() {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap();
    v["forces"]["muscles"].as_array_mut().unwrap().reverse();
    v["forces"]["muscle_model"] = "DeGrooteFregly2016Muscle".into();
    let model = leap::model::Model::from_json_str(&v.to_string(), "dg.json").unwrap();
    let eq = StateEquation::new(&model, true, PathSmoothing::Exact).unwrap();
    assert!(eq.muscles.iter().enumerate().any(|(k, &mi)| k != mi));
    let laws = OpenSimLaws::new(&model).unwrap();
    let ocp = leap::ocp::JumpOcp::new(&model, Default::default()).unwrap();
    let x0 = ocp.x0().to_vec();
    let names = eq.state_names();
    let col = names
        .iter()
        .position(|l| l == "/forceset/soleus_r/fiber_length")
        .unwrap();
    let spec = &model
        .muscles
        .iter()
        .find(|m| m.spec.name == "soleus_r")
        .unwrap()
        .spec;
    let time = vec![0.0, 0.01, 0.02];
    let mut rows = vec![x0.clone(); 3];
    // The fibre just above its shortest (where it stands at its
    // pennation's right angle; the DeGroote solution's soleus reached
    // 1.001 times it) stretches the tendon far beyond what it can hold at
    // the squat's activation.
    rows[1][col] = 1.02 * spec.optimal_fiber_length * spec.pennation_angle_at_optimal.sin();
    let mut ws = eq.workspace::<f64>();
    let mut xdot = vec![0.0; eq.nx()];
    let u = rows[1][eq.nx() - eq.nm()..].to_vec();
    let refused = eq
        .rhs(&laws, &mut ws, &rows[1], &u, &mut xdot)
        .unwrap_err()
        .to_string();
    assert!(refused.contains("soleus_r"), "{refused}");
    let a = analyze(&eq, &laws, &time, &rows, None).unwrap();
    assert_eq!(a.warnings.len(), 1, "{:?}", a.warnings);
    assert!(
        a.warnings[0].starts_with(
            "the fibre velocity overflows for soleus_r at 1 row (the first at t = 0.01 s):"
        ),
        "{:?}",
        a.warnings
    );
    let sol = a.muscles.iter().find(|m| m.name == "soleus_r").unwrap();
    // Its peak speed from the squat's rows, where the fibres rest; its
    // force from all three.
    assert!(
        sol.peak_shortening_ratio.abs() < 1e-3,
        "{}",
        sol.peak_shortening_ratio
    );
    let rest = analyze(&eq, &laws, &time, &vec![x0.clone(); 3], None).unwrap();
    let sol_rest = rest.muscles.iter().find(|m| m.name == "soleus_r").unwrap();
    assert!(
        sol.peak_force_ratio.is_finite() && sol.peak_force_ratio > sol_rest.peak_force_ratio,
        "{} against {} at rest",
        sol.peak_force_ratio,
        sol_rest.peak_force_ratio
    );
    // With no row's fibre velocity, the peak is NaN (null in JSON, "-" in
    // the table).
    let all = vec![rows[1].clone(); 3];
    let b = analyze(&eq, &laws, &time, &all, None).unwrap();
    let sol_none = b.muscles.iter().find(|m| m.name == "soleus_r").unwrap();
    assert!(sol_none.peak_shortening_ratio.is_nan());
    let line = b
        .to_text()
        .lines()
        .find(|l| l.starts_with("soleus_r "))
        .unwrap()
        .to_string();
    assert_eq!(line.split_whitespace().nth(5), Some("-"), "{line}");
    // Every other muscle's figures are the resting rows' own.
    for (m, r) in a.muscles.iter().zip(&rest.muscles) {
        if m.name != "soleus_r" {
            assert_eq!(m.name, r.name);
            assert_eq!(
                m.peak_shortening_ratio, r.peak_shortening_ratio,
                "{}",
                m.name
            );
            assert_eq!(m.peak_force_ratio, r.peak_force_ratio, "{}", m.name);
        }
    }
}

/// States with the body a metre underground (pelvis_ty in another model's
/// convention) are warned of at their first row, naming the deepest
/// contact sphere and its depth: 1 m plus what it sinks at the squat. The
/// analysis had reported thousands of body weights with only the impulse
/// warning.
#[test]
fn a_body_underground_is_warned_of() {
    let (_, eq, laws, x0) = jumper();
    let names = eq.state_names();
    let ty = names
        .iter()
        .position(|l| l == "/jointset/ground_pelvis/pelvis_ty/value")
        .unwrap();
    let time = vec![0.0, 0.01, 0.02];
    let mut rows = vec![x0.clone(); 3];
    rows[1][ty] -= 1.0;
    rows[2][ty] -= 1.0;
    let a = analyze(&eq, &laws, &time, &rows, Some((0.0, 0.02))).unwrap();
    assert_eq!(a.warnings.len(), 1, "{:?}", a.warnings);
    let w = &a.warnings[0];
    let prefix = "at t = 0.01 s, its first such row: contact sphere '";
    assert!(w.starts_with(prefix), "{w}");
    let (name, rest) = w[prefix.len()..].split_once("' lies ").unwrap();
    let depth_mm: f64 = rest.split_once(" mm deep").unwrap().0.parse().unwrap();
    // The same sphere's depth at the squat, from the model's geometry.
    let model = &eq.model;
    let sp = model
        .contact
        .as_ref()
        .unwrap()
        .spheres
        .iter()
        .find(|s| s.name == name)
        .unwrap();
    let mut ws = eq.workspace::<f64>();
    eq.contact_forces(&laws, &mut ws, &x0).unwrap();
    let view = leap::multibody::ModelView {
        mb: &eq.multibody,
        ws: &ws.mb,
        q_of: &eq.system.q_of_model_coordinate,
    };
    use leap::path::BodyKinematics;
    let at_squat = sp.radius - view.position(sp.body, sp.location)[1];
    // To the printed 0.1 mm.
    assert!(
        (depth_mm - 1e3 * (1.0 + at_squat)).abs() <= 0.05 + 1e-9,
        "{depth_mm} mm against 1 m + {at_squat} m"
    );
    let fine = analyze(&eq, &laws, &time, &vec![x0.clone(); 3], None).unwrap();
    assert!(fine.warnings.is_empty(), "{:?}", fine.warnings);
}
