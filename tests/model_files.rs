//! Model files: the jumper loads, SimmSpline reproduces model-data.md's knee
//! check values, and every broken file gives an error naming file and field.

use leap::model::{Model, ModelError};
use leap::path::PathSmoothing;
use leap::spline::{SimmSpline, SplineData};

#[test]
fn jumper_loads_with_gait2392_masses_and_credits() {
    let m = Model::from_file("models/jumper_gait2392.json").unwrap();
    // 12 gait2392 bodies (8 segments with the foot as talus+calcn+toes).
    assert_eq!(m.bodies.len(), 12);
    // gait2392 total mass, model-data.md §2 item 5: 75.1646 kg.
    assert!((m.total_mass() - 75.1646).abs() < 1e-9);
    assert!(m
        .credits
        .iter()
        .any(|c| c.contains("gait2392") && c.contains("CC BY 3.0")));
    assert_eq!(m.system(false).unwrap().nq(), 10);
    let sym = m.system(true).unwrap();
    assert_eq!(sym.nq(), 7);
    let names: Vec<&str> = sym
        .coordinates
        .iter()
        .map(|&c| m.coordinates[c].name.as_str())
        .collect();
    assert_eq!(
        names,
        [
            "pelvis_tilt",
            "pelvis_tx",
            "pelvis_ty",
            "hip_flexion_r",
            "knee_angle_r",
            "ankle_angle_r",
            "lumbar_extension"
        ]
    );
    assert_eq!(m.stations.len(), 16);
}

/// Leap's default model is the gait2392 jumper (the model of the OpenSim
/// reference data) with the OpenSim Jumper's maximum isometric forces of
/// model-data.md §7.2 (DynamicJumperModel.osim) and nothing else changed:
/// soleus 4000 and tib_post 3600 N; and each group of gait2392 muscles that
/// one Jumper muscle stands for (as gait10dof18musc's lumped muscles: the
/// Jumper has no semimem, semiten, lat_gas or ext_dig) scaled together to
/// that muscle's force: vasti 5000 N (vas_int), hamstrings 2700 N
/// (bifemlh), gastrocnemii 2500 N (med_gas), dorsiflexors 3000 N (tib_ant).
/// Its OpenSim export carries the same forces.
#[test]
fn default_model_is_gait2392_with_the_jumpers_forces() {
    let read = |p: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
    };
    let (mut default, gait2392) = (
        read("models/jumper.json"),
        read("models/jumper_gait2392.json"),
    );
    let groups: [(&[&str], f64); 6] = [
        (&["soleus"], 4000.0),
        (&["tib_post"], 3600.0),
        (&["vas_med", "vas_int", "vas_lat"], 5000.0),
        (&["bifemlh", "semimem", "semiten"], 2700.0),
        (&["med_gas", "lat_gas"], 2500.0),
        (&["tib_ant", "ext_dig"], 3000.0),
    ];
    let muscles = |v: &serde_json::Value| v["forces"]["muscles"].as_array().unwrap().clone();
    let force = |m: &serde_json::Value| m["max_isometric_force"].as_f64().unwrap();
    let (ours, theirs) = (muscles(&default), muscles(&gait2392));
    assert_eq!(ours.len(), 48);
    for side in ["r", "l"] {
        let get = |list: &[serde_json::Value], name: &str| {
            list.iter()
                .find(|m| m["name"] == format!("{name}_{side}"))
                .unwrap()
                .clone()
        };
        for (group, total) in groups {
            let sum: f64 = group.iter().map(|v| force(&get(&ours, v))).sum();
            assert!((sum - total).abs() < 1e-9, "{group:?}_{side}: {sum} N");
            let ratio = force(&get(&ours, group[0])) / force(&get(&theirs, group[0]));
            for v in group {
                let r = force(&get(&ours, v)) / force(&get(&theirs, v));
                assert!((r - ratio).abs() < 1e-12, "{v}_{side} scaled by {r}");
            }
        }
    }
    // Everything else is gait2392's: put the groups' forces back and
    // compare the whole model.
    let in_groups = |name: &str| {
        groups.iter().any(|(g, _)| {
            g.iter()
                .any(|m| name == format!("{m}_r") || name == format!("{m}_l"))
        })
    };
    for (m, g) in default["forces"]["muscles"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .zip(&theirs)
    {
        if in_groups(m["name"].as_str().unwrap()) {
            m["max_isometric_force"] = g["max_isometric_force"].clone();
        }
    }
    default["name"] = gait2392["name"].clone();
    default["credits"] = gait2392["credits"].clone();
    assert_eq!(default, gait2392);
    // The OpenSim export: each muscle's max_isometric_force as in the JSON.
    let osim = std::fs::read_to_string("models/jumper.osim").unwrap();
    for m in &ours {
        let name = m["name"].as_str().unwrap();
        let at = osim
            .find(&format!("Muscle name=\"{name}\""))
            .unwrap_or_else(|| panic!("{name} not in models/jumper.osim"));
        let tag = "<max_isometric_force>";
        let start = at + osim[at..].find(tag).unwrap() + tag.len();
        let end = start + osim[start..].find('<').unwrap();
        let f: f64 = osim[start..end].parse().unwrap();
        assert!(
            (f - force(m)).abs() <= 1e-9 * f,
            "{name}: {f} N in the .osim"
        );
    }
}

/// model-data.md §6: at knee_angle = −1.3962634 the FMM SimmSpline gives
/// tx = 0.00410999 and ty = −0.41105525 (and the OpenSim Jumper file stores
/// tib_ty_r = −0.41105524), quoted to 8 decimals.
#[test]
fn knee_splines_match_model_data_check_values() {
    let m = Model::from_file("models/jumper_gait2392.json").unwrap();
    let knee = m.joints.iter().find(|j| j.name == "knee_r").unwrap();
    let leap::model::JointKind::TranslatingHinge {
        translation_x,
        translation_y,
        ..
    } = &knee.kind
    else {
        panic!("knee_r is not a translating hinge")
    };
    let q = -1.3962634;
    let tx: f64 = translation_x.value(q);
    let ty: f64 = translation_y.value(q);
    assert!((tx - 0.00410999).abs() < 5e-9, "tx = {tx}");
    assert!((ty - -0.41105525).abs() < 5e-9, "ty = {ty}");
}

#[test]
fn spline_extrapolates_linearly_with_end_slope() {
    let s = SimmSpline::new(&SplineData {
        x: vec![0.0, 1.0, 2.0, 3.0, 4.0],
        y: vec![0.0, 1.0, 0.0, 2.0, 1.0],
    })
    .unwrap();
    let (_, slope_hi, _) = s.eval(4.0 - 1e-13);
    let (v, d1, d2) = s.eval(5.5f64);
    assert!((v - (1.0 + 1.5 * slope_hi)).abs() < 1e-9);
    assert!((d1 - slope_hi).abs() < 1e-9 && d2 == 0.0);
}

fn broken(name: &str) -> ModelError {
    let path = format!("tests/data/broken/{name}.json");
    match Model::from_file(&path) {
        Ok(_) => panic!("{path} was accepted"),
        Err(e) => {
            let msg = e.to_string();
            assert!(
                msg.starts_with(&path),
                "error does not name the file: {msg}"
            );
            e
        }
    }
}

#[test]
fn broken_model_files_name_file_field_and_reason() {
    let cases: &[(&str, &str, &str)] = &[
        ("negative_mass", "bodies[0].mass", "positive"),
        ("unknown_body", "joints[1].parent", "unknown body 'linkX'"),
        ("broken_json", "", "EOF while parsing"),
        (
            "unknown_field",
            "bodies[1].colour",
            "unknown field `colour`",
        ),
        (
            "inertia_not_pd",
            "bodies[1].inertia",
            "not positive definite",
        ),
        (
            "default_outside_range",
            "coordinates[1].default_value",
            "outside the range",
        ),
        (
            "unknown_coordinate",
            "joints[0].coordinate",
            "unknown coordinate 'q9'",
        ),
        ("duplicate_body", "bodies[2].name", "defined twice"),
        ("kinematic_loop", "bodies[0]", "kinematic loop"),
        (
            "unknown_station_body",
            "stations[0].body",
            "unknown body 'hand'",
        ),
        (
            "unknown_joint_type",
            "joints[0].type",
            "unknown variant `ball`",
        ),
        ("range_reversed", "coordinates[0].range", "min < max"),
        (
            "spline_not_increasing",
            "joints[2].translation_y",
            "not strictly increasing",
        ),
        (
            "asymmetric_hip",
            "joints[6].location_in_parent",
            "symmetry partner 'hip_r'",
        ),
        (
            "pose_outside_range",
            "poses.squat.knee_angle_r",
            "outside the range",
        ),
    ];
    for (name, field, reason) in cases {
        let e = broken(name);
        if !field.is_empty() {
            assert_eq!(e.field(), *field, "{name}: {e}");
        }
        assert!(e.to_string().contains(reason), "{name}: {e}");
    }
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let e = Model::from_file("models/no_such_model.json").unwrap_err();
    assert!(matches!(e, ModelError::Io { .. }));
    assert!(e.to_string().contains("models/no_such_model.json"));
}

/// The default model as JSON, to break one thing at a time.
fn jumper_json() -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap()
}

/// The error of a model built from `v` (named "m.json"), checked to name
/// the file.
fn refused(v: &serde_json::Value) -> ModelError {
    let e = Model::from_json_str(&v.to_string(), "m.json").unwrap_err();
    assert!(e.to_string().starts_with("m.json: "), "{e}");
    e
}

fn muscle_index(v: &serde_json::Value, name: &str) -> usize {
    v["forces"]["muscles"]
        .as_array()
        .unwrap()
        .iter()
        .position(|m| m["name"] == name)
        .unwrap()
}

/// serde reads the first value and fills a struct from an array by
/// position; a model file is exactly one object.
#[test]
fn a_model_file_is_one_json_object() {
    let text = std::fs::read_to_string("models/jumper.json").unwrap();
    for (doc, reason) in [
        (format!("{text}\n\n{{}}"), "trailing characters at line"),
        (format!("{text} xyz"), "trailing characters at line"),
        ("[]".to_string(), "expected a JSON object, got an array"),
        (
            r#"["jump", [], [0, -9.8, 0]]"#.to_string(),
            "expected a JSON object, got an array",
        ),
    ] {
        let e = Model::from_json_str(&doc, "m.json").unwrap_err();
        assert!(matches!(e, ModelError::Parse { .. }), "{e}");
        assert_eq!(e.field(), "(document)", "{e}");
        assert!(
            e.to_string()
                .starts_with(&format!("m.json: (document): {reason}")),
            "{e}"
        );
    }
    // A byte-order mark before the object is no content.
    let m = Model::from_json_str(&format!("\u{feff}{text}"), "m.json");
    assert!(m.is_ok(), "{:?}", m.err());
    // Inside the object too, no struct is read from an array by position,
    // which serde would accept, filling the fields in order: a body as
    // [name, mass, mass_center, inertia].
    let v = jumper_json();
    let mut w = v.clone();
    let b = w["bodies"][1].clone();
    w["bodies"][1] = serde_json::json!([b["name"], b["mass"], b["mass_center"], b["inertia"]]);
    let e = Model::from_json_str(&w.to_string(), "m.json").unwrap_err();
    assert_eq!(e.field(), "bodies[1]", "{e}");
    assert!(
        e.to_string()
            .contains("expected an object with named fields, got an array"),
        "{e}"
    );
    // A joint (a tagged enum), a path point and the contact as arrays of
    // their values (in serde_json's key order) are refused at or in them.
    for (place, field) in [
        ("/joints/2", "joints[2]"),
        ("/forces/muscles/10/path/2", "forces.muscles[10].path[2]"),
        ("/forces/contact", "forces.contact"),
    ] {
        let mut w = v.clone();
        let obj = w.pointer(place).unwrap().as_object().unwrap().clone();
        *w.pointer_mut(place).unwrap() = obj.into_iter().map(|(_, x)| x).collect();
        let e = Model::from_json_str(&w.to_string(), "m.json").unwrap_err();
        assert!(e.field().starts_with(field), "{e}");
    }
}

/// A key given twice in one object is refused where serde would keep the
/// last one without a word (a map: a pose's coordinate), naming the object
/// and the key.
#[test]
fn a_key_given_twice_is_refused() {
    let text = std::fs::read_to_string("models/jumper.json").unwrap();
    let v = jumper_json();
    let tilt = v["poses"]["squat"]["pelvis_tilt"].to_string();
    let at = text.find("\"pelvis_tilt\":").unwrap();
    // The squat pose's pelvis_tilt, given again (0.9) before the first.
    let (first, _) = text.split_at(at);
    assert!(first.contains("\"squat\""), "the squat pose comes first");
    let twice = format!("{first}\"pelvis_tilt\": 0.9, {}", &text[at..]);
    let e = Model::from_json_str(&twice, "m.json").unwrap_err();
    assert_eq!(e.field(), "poses.squat", "{e}");
    assert!(
        e.to_string().contains("key 'pelvis_tilt' given twice"),
        "{e} ({tilt})"
    );
    assert_eq!(
        leap::model::duplicate_key(r#"{"a": [{"b": 1, "c": {"d": 1, "d": 2}}], "e": 1}"#),
        Some(("a[0].c".to_string(), "d".to_string()))
    );
    assert_eq!(
        leap::model::duplicate_key(r#"{"a": 1, "b": {"a": 1}, "a": 2}"#),
        Some(("(document)".to_string(), "a".to_string()))
    );
    assert_eq!(
        leap::model::duplicate_key(r#"{"a": {"a": [1, {"a": 1}]}}"#),
        None
    );
}

/// A left path point that follows a coordinate without a pair in
/// `symmetry` (the knee pair left out) is refused with that reason and
/// the pair to add; a right point that follows a left coordinate is
/// refused as such.
#[test]
fn a_missing_symmetry_pair_is_named_as_missing() {
    // A right point on the left knee (and its mirror on the right one).
    let mut v = jumper_json();
    let (r, l) = (
        muscle_index(&v, "rect_fem_r"),
        muscle_index(&v, "rect_fem_l"),
    );
    assert_eq!(
        v["forces"]["muscles"][r]["path"][1]["coordinate"],
        "knee_angle_r"
    );
    v["forces"]["muscles"][r]["path"][1]["coordinate"] = "knee_angle_l".into();
    v["forces"]["muscles"][l]["path"][1]["coordinate"] = "knee_angle_r".into();
    let e = refused(&v);
    assert_eq!(e.field(), format!("forces.muscles[{l}].path[1].coordinate"));
    assert!(
        e.to_string().contains("the right point follows the left coordinate 'knee_angle_l' (the partner of 'knee_angle_r')"),
        "{e}"
    );
    let mut v = jumper_json();
    let pairs = v["symmetry"].as_array_mut().unwrap();
    pairs.retain(|p| p[0] != "knee_angle_r");
    let e = refused(&v);
    assert!(
        e.to_string().contains("coordinate 'knee_angle_l' where the right point's 'knee_angle_r' has no partner in `symmetry`, so both points would follow 'knee_angle_r' (if 'knee_angle_l' mirrors it, add [\"knee_angle_r\", \"knee_angle_l\"] to `symmetry`)"),
        "{e}"
    );
}

/// Joints and path points are objects tagged by `type`: a field is
/// checked against the type (taken, not taken) and an error inside one
/// names the field's own path.
#[test]
fn joint_and_path_point_fields_are_checked_against_their_type() {
    let v = jumper_json();
    let joint = |t: &str| {
        v["joints"]
            .as_array()
            .unwrap()
            .iter()
            .position(|j| j["type"] == t)
            .unwrap()
    };
    let (pin, knee) = (joint("pin"), joint("translating_hinge"));
    let l = muscle_index(&v, "rect_fem_r");
    let point = |t: &str| {
        v["forces"]["muscles"][l]["path"]
            .as_array()
            .unwrap()
            .iter()
            .position(|p| p["type"] == t)
            .unwrap()
    };
    let (fixed, moving) = (point("fixed"), point("moving"));
    let pp = format!("/forces/muscles/{l}/path");
    type Change = Box<dyn Fn(&mut serde_json::Value)>;
    let set = |at: String, key: &'static str, x: serde_json::Value| -> Change {
        Box::new(move |w| {
            w.pointer_mut(&at).unwrap()[key] = x.clone();
        })
    };
    let drop = |at: String, key: &'static str| -> Change {
        Box::new(move |w| {
            w.pointer_mut(&at)
                .unwrap()
                .as_object_mut()
                .unwrap()
                .remove(key);
        })
    };
    let cases: Vec<(Change, String, &str)> = vec![
        (
            set(format!("/joints/{pin}"), "coordinates", serde_json::json!(["a", "b", "c"])),
            format!("joints[{pin}]"),
            "unknown field `coordinates`: a pin joint has fields `type`, `name`, `parent`, `child`, `location_in_parent`, `coordinate`",
        ),
        // A field no joint type has: the error lists the pin joint's
        // fields, not every type's.
        (
            set(format!("/joints/{pin}"), "orientaton", serde_json::json!([0.0, 0.0, 0.0])),
            format!("joints[{pin}].orientaton"),
            "unknown field `orientaton`: a pin joint has fields `type`, `name`, `parent`, `child`, `location_in_parent`, `coordinate` at line",
        ),
        (
            set(format!("{pp}/{moving}"), "locaton", serde_json::json!([0.0, 0.0, 0.0])),
            format!("forces.muscles[{l}].path[{moving}].locaton"),
            "unknown field `locaton`: a moving path point has fields `type`, `body`, `coordinate`, `x_location`, `y_location`, `z_location` at line",
        ),
        (
            drop(format!("/joints/{knee}"), "translation_x"),
            format!("joints[{knee}]"),
            "missing field `translation_x`: a translating_hinge joint",
        ),
        (
            set(format!("/joints/{knee}"), "coordinate", serde_json::Value::Null),
            format!("joints[{knee}].coordinate"),
            "invalid type: null, expected a string",
        ),
        (
            set(format!("/joints/{knee}"), "translation_y", serde_json::json!({"x": [0.0, "1"], "y": [0.0, 1.0]})),
            format!("joints[{knee}].translation_y.x[1]"),
            "invalid type: string \"1\", expected f64",
        ),
        (
            set(format!("{pp}/{fixed}"), "range", serde_json::json!([0.0, 1.0])),
            format!("forces.muscles[{l}].path[{fixed}]"),
            "unknown field `range`: a fixed path point has fields `type`, `body`, `location`",
        ),
        (
            drop(format!("{pp}/{moving}"), "z_location"),
            format!("forces.muscles[{l}].path[{moving}]"),
            "missing field `z_location`: a moving path point",
        ),
        (
            set(format!("{pp}/{moving}"), "body", serde_json::json!(3)),
            format!("forces.muscles[{l}].path[{moving}].body"),
            "expected a string",
        ),
        (
            set(format!("{pp}/{moving}"), "type", serde_json::json!("sliding")),
            format!("forces.muscles[{l}].path[{moving}].type"),
            "unknown variant `sliding`, expected one of `fixed`, `conditional`, `moving`",
        ),
    ];
    for (change, field, reason) in cases {
        let mut w = v.clone();
        change(&mut w);
        let e = refused(&w);
        assert_eq!(e.field(), field, "{e}");
        assert!(e.to_string().contains(reason), "{e}");
    }
    // A type is a string: not null, and not serde's map form of an enum
    // (`{"pin": null}`), which serde's own enums take.
    for (at, field) in [
        (format!("/joints/{pin}"), format!("joints[{pin}].type")),
        (
            format!("{pp}/{fixed}"),
            format!("forces.muscles[{l}].path[{fixed}].type"),
        ),
    ] {
        let name = v.pointer(&at).unwrap()["type"].clone();
        for (bad, kind) in [
            (serde_json::Value::Null, "null"),
            (serde_json::json!({ name.as_str().unwrap(): null }), "map"),
        ] {
            let mut w = v.clone();
            w.pointer_mut(&at).unwrap()["type"] = bad;
            let e = refused(&w);
            assert_eq!(e.field(), field, "{e}");
            assert!(
                e.to_string()
                    .contains(&format!("invalid type: {kind}, expected a string")),
                "{e}"
            );
        }
    }
    // Written back, a model reads as itself.
    let file: leap::model::ModelFile = serde_json::from_value(v.clone()).unwrap();
    let back = serde_json::to_value(&file).unwrap();
    assert_eq!(back["joints"], v["joints"]);
    assert_eq!(
        back["forces"]["muscles"][l]["path"],
        v["forces"]["muscles"][l]["path"]
    );
}

/// A body welded to ground (a platform, a force plate) had passed the
/// checks and panicked in every command that built the multibody system.
#[test]
fn a_weld_to_ground_is_refused_naming_the_joint() {
    let mut v = jumper_json();
    v["bodies"].as_array_mut().unwrap().push(serde_json::json!({
        "name": "platform", "mass": 10.0, "mass_center": [0.0, 0.0, 0.0],
        "inertia": [0.1, 0.1, 0.1, 0.0, 0.0, 0.0]
    }));
    let joints = v["joints"].as_array_mut().unwrap();
    joints.push(serde_json::json!({
        "type": "weld", "name": "ground_platform", "parent": "ground",
        "child": "platform", "location_in_parent": [0.0, 0.0, 0.0]
    }));
    let j = joints.len() - 1;
    let e = refused(&v).to_string();
    assert!(
        e.contains(&format!("joints[{j}].parent")) && e.contains("weld"),
        "{e}"
    );
    // The same body welded to the pelvis is a model leap takes, and builds.
    v["joints"][j]["parent"] = "pelvis".into();
    let m = Model::from_json_str(&v.to_string(), "m.json").unwrap();
    leap::multibody::Multibody::new(&m, &m.system(false).unwrap());
}

/// A DeGrooteFregly2016Muscle model that gives Thelen2003Muscle's shape
/// constants other than their defaults is refused, naming the muscle's
/// field: the values would be read and have no effect (De Groote's curves
/// are fixed). With the defaults (as models/jumper.json gives them) or
/// with Thelen's muscles the same file loads; the tendon and passive
/// strains carry over and change De Groote's curves.
#[test]
fn thelen_shape_constants_are_refused_on_degroote_muscles() {
    let mut v = jumper_json();
    v["forces"]["muscle_model"] = "DeGrooteFregly2016Muscle".into();
    Model::from_json_str(&v.to_string(), "m.json").unwrap();
    let (k, l) = (muscle_index(&v, "soleus_r"), muscle_index(&v, "soleus_l"));
    for (field, value) in [
        ("KshapeActive", 0.6),
        ("KshapePassive", 5.0),
        ("Af", 0.25),
        ("Flen", 1.4),
    ] {
        let mut w = v.clone();
        // Both legs: the symmetric system needs mirror images.
        w["forces"]["muscles"][k][field] = value.into();
        w["forces"]["muscles"][l][field] = value.into();
        let e = refused(&w).to_string();
        assert!(
            e.contains(&format!("forces.muscles[{k}].{field}"))
                && e.contains(
                    "is a Thelen2003Muscle constant with no effect on DeGrooteFregly2016Muscle"
                ),
            "{e}"
        );
        w["forces"]["muscle_model"] = "Thelen2003Muscle".into();
        Model::from_json_str(&w.to_string(), "m.json").unwrap();
    }
    // The strains reach De Groote's tendon and passive curves.
    let mut w = v.clone();
    for i in [k, l] {
        w["forces"]["muscles"][i]["FmaxTendonStrain"] = 0.049.into();
        w["forces"]["muscles"][i]["FmaxMuscleStrain"] = 0.7.into();
    }
    let m = Model::from_json_str(&w.to_string(), "m.json").unwrap();
    let base = Model::from_json_str(&v.to_string(), "m.json").unwrap();
    let soleus = |m: &Model| {
        let spec = &m
            .muscles
            .iter()
            .find(|x| x.spec.name == "soleus_r")
            .unwrap()
            .spec;
        leap::laws::DeGroote::new(spec)
    };
    // By their definitions: the tendon force at 1 + FmaxTendonStrain and
    // the passive force at 1 + FmaxMuscleStrain are F0.
    let (b, c) = (soleus(&base), soleus(&m));
    for (value, at) in [
        (b.ft(1.033_f64), "ft(1.033), default"),
        (c.ft(1.049_f64), "ft(1.049), 0.049"),
        (b.fpe(1.6_f64), "fpe(1.6), default"),
        (c.fpe(1.7_f64), "fpe(1.7), 0.7"),
    ] {
        assert!((value - 1.0).abs() < 1e-12, "{at}: {value}");
    }
    assert!(c.ft(1.033_f64) < 0.9 && c.fpe(1.6_f64) < 0.9);
}

/// `leap eval` reports contact forces per sphere name.
#[test]
fn contact_spheres_need_distinct_names_and_at_least_one() {
    let mut v = jumper_json();
    v["forces"]["contact"]["spheres"][1]["name"] =
        v["forces"]["contact"]["spheres"][0]["name"].clone();
    let e = refused(&v);
    assert_eq!(e.field(), "forces.contact.spheres[1].name");
    assert!(
        e.to_string()
            .contains("sphere 'heel_lat_r' is defined twice"),
        "{e}"
    );
    v["forces"]["contact"]["spheres"] = serde_json::json!([]);
    let e = refused(&v);
    assert_eq!(e.field(), "forces.contact.spheres");
    assert!(e.to_string().contains("no contact spheres"), "{e}");
}

/// The symmetric system moves both legs as one: a left foot whose spheres
/// are gone, raised or moved (each a model of one-footed contact, which
/// would roll the body) is refused by the symmetric system, naming the
/// sphere and the body it lacks a partner on; the full system takes such a
/// model. A sphere's z does not act in the plane (moved along z it still
/// mirrors), and a sphere on a midline body (the pelvis) needs no partner.
#[test]
fn the_symmetric_system_needs_mirrored_contact_spheres() {
    let build = |v: &serde_json::Value, symmetric: bool| {
        let m = Model::from_json_str(&v.to_string(), "m.json").unwrap();
        leap::ode::StateEquation::new(&m, symmetric, PathSmoothing::Smooth { delta: 0.02 })
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    let v = jumper_json();
    build(&v, true).unwrap();
    let spheres = v["forces"]["contact"]["spheres"]
        .as_array()
        .unwrap()
        .clone();
    let left = |s: &serde_json::Value| s["name"].as_str().unwrap().ends_with("_l");
    // Only the right foot's spheres.
    let mut w = v.clone();
    w["forces"]["contact"]["spheres"] =
        serde_json::json!(spheres.iter().filter(|s| !left(s)).collect::<Vec<_>>());
    let e = build(&w, true).unwrap_err();
    assert!(
        e.contains("forces.contact.spheres[0]: sphere 'heel_lat_r' of the right leg (on 'calcn_r', radius 0.032 m) has no mirror image")
            && e.contains("the other leg has no spheres"),
        "{e}"
    );
    build(&w, false).unwrap();
    let i = spheres.iter().position(|s| s["name"] == "meta1_l").unwrap();
    // One left sphere moved by 1 mm in x or y, or with another radius:
    // refused, naming the pair (meta1_r, the first checked, and meta1_l
    // 1 mm off).
    for (field, k) in [("location", 0), ("location", 1), ("radius", 3)] {
        let mut w = v.clone();
        let s = &mut w["forces"]["contact"]["spheres"][i];
        if field == "radius" {
            s[field] = (s[field].as_f64().unwrap() + 1e-3).into();
        } else {
            s[field][k] = (s[field][k].as_f64().unwrap() + 1e-3).into();
        }
        let e = build(&w, true).unwrap_err();
        assert!(e.contains("has no mirror image"), "{field} {k}: {e}");
        if field == "location" {
            assert!(
                e.contains("sphere 'meta1_r' of the right leg")
                    && e.contains("'meta1_l' (radius 0.032 m), lies 1.0 mm away in the plane"),
                "{e}"
            );
        }
    }
    // A left sphere removed whose partner's twin on the same foot differs
    // only in z (heel_med_r and heel_lat_r share x and y): one to one, the
    // right foot's two have one partner.
    let mut w = v.clone();
    w["forces"]["contact"]["spheres"] = serde_json::json!(spheres
        .iter()
        .filter(|s| s["name"] != "heel_med_l")
        .collect::<Vec<_>>());
    let at = |name: &str| {
        let s = spheres.iter().find(|s| s["name"] == name).unwrap();
        (s["location"][0].as_f64(), s["location"][1].as_f64())
    };
    assert_eq!(at("heel_med_r"), at("heel_lat_r"), "the jumper's heels");
    let e = build(&w, true).unwrap_err();
    assert!(
        e.contains("has 2 sphere(s) of its radius at its x and y on its leg and 1 on the left leg"),
        "{e}"
    );
    build(&w, false).unwrap();
    // Moved along z: it still mirrors.
    let mut w = v.clone();
    let z = w["forces"]["contact"]["spheres"][i]["location"][2]
        .as_f64()
        .unwrap();
    w["forces"]["contact"]["spheres"][i]["location"][2] = (z + 0.05).into();
    build(&w, true).unwrap();
    // A sphere on the pelvis, a midline body: no partner needed.
    let mut w = v.clone();
    let mut extra = spheres[0].clone();
    extra["name"] = "pelvis_sphere".into();
    extra["body"] = "pelvis".into();
    extra["location"] = serde_json::json!([0.0, 0.5, 0.0]);
    w["forces"]["contact"]["spheres"]
        .as_array_mut()
        .unwrap()
        .push(extra);
    build(&w, true).unwrap();
}

/// Refused at load instead of as "the feet do not touch the ground" from
/// the static squat.
#[test]
fn jump_models_need_gravity_down_muscles_and_contact() {
    for g in [[0.0, 0.0, 0.0], [0.0, 9.81, 0.0], [-9.81, 0.0, 0.0]] {
        let mut v = jumper_json();
        v["gravity"] = serde_json::json!(g);
        let e = refused(&v);
        assert_eq!(e.field(), "gravity");
        assert!(e.to_string().contains("must point down (−y)"), "{e}");
    }
    // Three components, no more.
    let mut v = jumper_json();
    v["gravity"] = serde_json::json!([0.0, -9.81, 0.0, 1.0]);
    let e = refused(&v);
    assert_eq!(e.field(), "gravity");
    assert!(
        e.to_string()
            .contains("more elements than this field takes"),
        "{e}"
    );
    // Its magnitude within [1, 100] m/s² (the Moon's 1.62 passes).
    for (g, ok) in [
        (1.62, true),
        (1.0, true),
        (100.0, true),
        (0.99, false),
        (5e-324, false),
        (100.5, false),
        (1e308, false),
    ] {
        let mut v = jumper_json();
        v["gravity"] = serde_json::json!([0.0, -g, 0.0]);
        let got = Model::from_json_str(&v.to_string(), "m.json");
        if ok {
            assert!(got.is_ok(), "g = {g}: {:?}", got.err());
        } else {
            let e = got.unwrap_err();
            assert_eq!(e.field(), "gravity");
            assert!(e.to_string().contains("lies outside [1, 100] m/s²"), "{e}");
        }
    }
    let mut v = jumper_json();
    v["forces"]["muscles"] = serde_json::json!([]);
    let e = refused(&v);
    assert_eq!(e.field(), "forces.muscles");
    assert!(e.to_string().contains("no muscles: a jump model"), "{e}");
    let mut v = jumper_json();
    v["forces"].as_object_mut().unwrap().remove("contact");
    let e = refused(&v);
    assert_eq!(e.field(), "forces.contact");
    assert!(e.to_string().contains("needs foot-ground contact"), "{e}");
    // A model without contact may point gravity anywhere.
    let mut p: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string("models/double_pendulum.json").unwrap())
            .unwrap();
    p["gravity"] = serde_json::json!([9.81, 0.0, 0.0]);
    let m = Model::from_json_str(&p.to_string(), "p.json").unwrap();
    assert_eq!(m.gravity, [9.81, 0.0, 0.0]);
}

/// The symmetric system carries each left muscle by its right partner:
/// a sided muscle without its partner is refused naming both.
#[test]
fn sided_muscles_need_their_mirror_partner() {
    let mut v = jumper_json();
    let k = muscle_index(&v, "ext_dig_l");
    v["forces"]["muscles"].as_array_mut().unwrap().remove(k);
    let e = refused(&v);
    assert_eq!(
        e.field(),
        format!("forces.muscles[{}].name", muscle_index(&v, "ext_dig_r"))
    );
    assert!(
        e.to_string()
            .contains("right muscle 'ext_dig_r' has no mirror partner 'ext_dig_l'"),
        "{e}"
    );
    let mut v = jumper_json();
    let k = muscle_index(&v, "ercspn_r");
    v["forces"]["muscles"][k]["name"] = "ercspn".into();
    let e = refused(&v);
    assert_eq!(
        e.field(),
        format!("forces.muscles[{}].name", muscle_index(&v, "ercspn_l"))
    );
    assert!(
        e.to_string().contains(
            "left muscle 'ercspn_l' has no mirror partner 'ercspn_r' ('ercspn' has no side suffix)"
        ),
        "{e}"
    );
    // A midline muscle (no side suffix) is carried once.
    let l = muscle_index(&v, "ercspn_l");
    v["forces"]["muscles"].as_array_mut().unwrap().remove(l);
    let m = Model::from_json_str(&v.to_string(), "m.json").unwrap();
    assert!(m.muscles.iter().any(|m| m.spec.name == "ercspn"));
}

#[test]
fn mirror_muscles_must_have_equal_parameters_and_the_error_names_the_parameter() {
    for (param, value) in [
        ("max_isometric_force", 3e4),
        ("activation_time_constant", 0.02),
    ] {
        let mut v = jumper_json();
        let (l, r) = (muscle_index(&v, "iliacus_l"), muscle_index(&v, "iliacus_r"));
        v["forces"]["muscles"][l][param] = value.into();
        let e = refused(&v);
        assert_eq!(e.field(), format!("forces.muscles[{l}].{param}"));
        assert!(
            e.to_string().contains(&format!(
                "muscle 'iliacus_l' is not the mirror image of 'iliacus_r' (forces.muscles[{r}]): {param} is {value:?} against"
            )),
            "{e}"
        );
    }
}

/// Without coordinate pairs the legs move apart, and the symmetric system
/// the jump is solved on cannot carry a left muscle by its right one.
#[test]
fn a_jump_model_with_paired_muscles_needs_symmetry_pairs() {
    let mut v = jumper_json();
    v["symmetry"] = serde_json::json!([]);
    let e = refused(&v);
    assert_eq!(e.field(), "symmetry");
    assert!(
        e.to_string()
            .contains("no right/left coordinate pairs, but the muscles come in pairs ('ercspn_r', 'ercspn_l')"),
        "{e}"
    );
}

/// Two path points fixed at the same place on the same body make a segment
/// of zero length, whose direction (and so the lengthening speed and the
/// forces) would be 0/0: refused, also across a conditional point that can
/// switch off between them, and the error names the point.
#[test]
fn coincident_path_points_are_refused() {
    let i = 3;
    let v = jumper_json();
    assert_eq!(v["forces"]["muscles"][i]["name"], "iliacus_r");
    assert_eq!(v["forces"]["muscles"][i]["path"][2]["type"], "conditional");
    // Neighbours.
    let mut w = v.clone();
    w["forces"]["muscles"][i]["path"][1]["location"] =
        w["forces"]["muscles"][i]["path"][0]["location"].clone();
    let e = refused(&w);
    assert_eq!(e.field(), format!("forces.muscles[{i}].path[1].location"));
    assert!(
        e.to_string()
            .contains("coincides with path point 0 on the same body"),
        "{e}"
    );
    // Across the conditional point 2, which switches off outside its range.
    let mut w = v.clone();
    w["forces"]["muscles"][i]["path"][3]["body"] = "pelvis".into();
    w["forces"]["muscles"][i]["path"][3]["location"] =
        w["forces"]["muscles"][i]["path"][1]["location"].clone();
    let e = refused(&w);
    assert_eq!(e.field(), format!("forces.muscles[{i}].path[3].location"));
    assert!(
        e.to_string()
            .contains("coincides with path point 1 on the same body"),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("when the conditional points between them are inactive"),
        "{e}"
    );
    // The same location on another body is a different point (moved on
    // both sides, so that the paths stay mirror images).
    let mut w = v.clone();
    let l = muscle_index(&v, "iliacus_l");
    for m in [i, l] {
        w["forces"]["muscles"][m]["path"][3]["location"] =
            w["forces"]["muscles"][m]["path"][1]["location"].clone();
    }
    assert!(Model::from_json_str(&w.to_string(), "m.json").is_ok());
}

/// The symmetric system carries a left muscle by its right partner only if
/// their paths are mirror images, compared point by point when the file is
/// read: a left path point moved by a millimetre, a conditional point's
/// range (which sampled path lengths miss where the poses do not reach
/// it), its coordinate, its kind or a point's body are refused, naming the
/// left point's field.
#[test]
fn mirror_muscles_must_have_mirror_paths_and_the_error_names_the_point() {
    let v = jumper_json();
    let (l, r) = (muscle_index(&v, "iliacus_l"), muscle_index(&v, "iliacus_r"));
    let stem = format!("m.json: forces.muscles[{l}].path");
    let why =
        format!("muscle 'iliacus_l' is not the mirror image of 'iliacus_r' (forces.muscles[{r}])");
    assert_eq!(v["forces"]["muscles"][l]["path"][2]["type"], "conditional");
    let x = v["forces"]["muscles"][l]["path"][4]["location"][0]
        .as_f64()
        .unwrap();
    let cases: [(&str, usize, serde_json::Value, &str); 5] = [
        ("location", 4, serde_json::json!([x + 1e-3, 0.0, 0.0]), "location"),
        ("range", 2, serde_json::json!([-1.0, 1e-300]), "range [-1.0, 1e-300] against"),
        ("coordinate", 2, "knee_angle_l".into(), "coordinate 'knee_angle_l' where the right point's 'hip_flexion_r' has the partner 'hip_flexion_l'"),
        ("body", 4, "femur_r".into(), "body 'femur_r' where the mirror of 'femur_r' is 'femur_l'"),
        ("type", 2, "fixed".into(), "its point is of another kind"),
    ];
    for (field, k, value, reason) in cases {
        let mut w = v.clone();
        if field == "location" {
            let mut loc = w["forces"]["muscles"][l]["path"][k]["location"].clone();
            loc[0] = value[0].clone();
            w["forces"]["muscles"][l]["path"][k]["location"] = loc;
        } else if field == "type" {
            let p = &mut w["forces"]["muscles"][l]["path"][k];
            p["type"] = value;
            let o = p.as_object_mut().unwrap();
            o.remove("coordinate");
            o.remove("range");
        } else {
            w["forces"]["muscles"][l]["path"][k][field] = value;
        }
        let e = refused(&w);
        let at = if field == "type" {
            format!("forces.muscles[{l}].path[{k}]")
        } else {
            format!("forces.muscles[{l}].path[{k}].{field}")
        };
        assert_eq!(e.field(), at, "{e}");
        assert!(e.to_string().starts_with(&stem), "{e}");
        assert!(
            e.to_string().contains(&why) && e.to_string().contains(reason),
            "{field}: {e}"
        );
    }
}

/// Mirror bodies are the children of symmetry partners' joints (and the
/// bodies welded onto them), whatever their names: the jumper with its
/// bodies renamed `femur_right`/`femur_left` loads, its static squat is the
/// jumper's, and a left muscle on the wrong calcaneus (welded to the talus)
/// is still refused, naming the mirror body.
#[test]
fn mirror_bodies_pair_by_joints_not_only_by_names() {
    let v = jumper_json();
    let rename = |n: &str| match (n.strip_suffix("_r"), n.strip_suffix("_l")) {
        (Some(stem), _) => format!("{stem}_right"),
        (_, Some(stem)) => format!("{stem}_left"),
        _ => n.to_string(),
    };
    let mut w = v.clone();
    for b in w["bodies"].as_array_mut().unwrap() {
        b["name"] = rename(b["name"].as_str().unwrap()).into();
    }
    for j in w["joints"].as_array_mut().unwrap() {
        for k in ["parent", "child"] {
            j[k] = rename(j[k].as_str().unwrap()).into();
        }
    }
    for m in w["forces"]["muscles"].as_array_mut().unwrap() {
        for p in m["path"].as_array_mut().unwrap() {
            p["body"] = rename(p["body"].as_str().unwrap()).into();
        }
    }
    for sp in w["forces"]["contact"]["spheres"].as_array_mut().unwrap() {
        sp["body"] = rename(sp["body"].as_str().unwrap()).into();
    }
    for st in w["stations"].as_array_mut().into_iter().flatten() {
        st["body"] = rename(st["body"].as_str().unwrap()).into();
    }
    let squat = |v: &serde_json::Value| {
        let m = Model::from_json_str(&v.to_string(), "m.json").unwrap();
        let (laws, eq) = leap::ode::StateEquation::opensim(&m, true).unwrap();
        leap::squat::static_squat(&eq, &laws, &m.squat_pose().unwrap())
            .unwrap()
            .x
    };
    assert_eq!(squat(&w), squat(&v));
    let l = muscle_index(&w, "med_gas_l");
    let k = w["forces"]["muscles"][l]["path"]
        .as_array()
        .unwrap()
        .iter()
        .position(|p| p["body"] == "calcn_left")
        .unwrap();
    w["forces"]["muscles"][l]["path"][k]["body"] = "calcn_right".into();
    let e = refused(&w);
    assert_eq!(e.field(), format!("forces.muscles[{l}].path[{k}].body"));
    assert!(
        e.to_string()
            .contains("body 'calcn_right' where the mirror of 'calcn_right' is 'calcn_left'"),
        "{e}"
    );
}

/// What OpenSim refuses or what the symmetric jump would drop unseen.
#[test]
fn flen_paths_of_conditional_points_duplicate_passive_torques_and_asymmetric_poses_are_refused() {
    let v = jumper_json();
    // OpenSim's Thelen2003Muscle: Flen > 1 and 0.95 > 1/Flen.
    let partner = muscle_index(&v, "glut_max1_l");
    assert_eq!(v["forces"]["muscles"][5]["name"], "glut_max1_r");
    for (flen, ok) in [(1.0, false), (1.05, false), (1.06, true), (1.4, true)] {
        let mut w = v.clone();
        w["forces"]["muscles"][5]["Flen"] = flen.into();
        w["forces"]["muscles"][partner]["Flen"] = flen.into();
        match Model::from_json_str(&w.to_string(), "m.json") {
            Ok(_) => assert!(ok, "Flen {flen} accepted"),
            Err(e) => {
                assert!(!ok, "Flen {flen}: {e}");
                assert_eq!(e.field(), "forces.muscles[5].Flen");
            }
        }
    }
    // A path whose points are all conditional can vanish.
    let i = muscle_index(&v, "iliacus_r");
    let mut w = v.clone();
    let cond = w["forces"]["muscles"][i]["path"][2].clone();
    assert_eq!(cond["type"], "conditional");
    let mut second = cond.clone();
    second["location"][1] = (cond["location"][1].as_f64().unwrap() - 0.05).into();
    w["forces"]["muscles"][i]["path"] = serde_json::json!([cond, second]);
    let e = refused(&w);
    assert_eq!(e.field(), format!("forces.muscles[{i}].path"));
    assert!(e.to_string().contains("always active"), "{e}");
    // One passive torque per coordinate (the .osim names it by it).
    let mut w = v.clone();
    let first = w["forces"]["ligaments"][0].clone();
    let n = w["forces"]["ligaments"].as_array().unwrap().len();
    w["forces"]["ligaments"].as_array_mut().unwrap().push(first);
    let e = refused(&w);
    assert_eq!(e.field(), format!("forces.ligaments[{n}].coordinate"));
    assert!(e.to_string().contains("forces.ligaments[0]"), "{e}");
    // A pose whose left side differs from the right.
    let mut w = v.clone();
    let r = w["poses"]["squat"]["knee_angle_r"].as_f64().unwrap();
    w["poses"]["squat"]["knee_angle_l"] = (r + 0.1).into();
    let e = refused(&w);
    assert_eq!(e.field(), "poses.squat.knee_angle_l");
    assert!(e.to_string().contains("knee_angle_r"), "{e}");
    // Equal sides stay accepted.
    let mut w = v.clone();
    w["poses"]["squat"]["knee_angle_l"] = r.into();
    assert!(Model::from_json_str(&w.to_string(), "m.json").is_ok());
}

/// A rigid body's central inertia is positive definite, each product is at
/// most half the third moment (Simbody's `Inertia` check) and its
/// principal moments satisfy the triangle inequality; and the inertia about
/// the body's origin, which Simbody and leap's multibody take, is finite.
/// Each is refused at load, naming the field, rather than as a Simbody
/// exception or a mass matrix of NaN at the squat.
#[test]
fn body_inertias_must_be_physical_and_finite_about_the_origin() {
    let torso = |v: &serde_json::Value| {
        v["bodies"]
            .as_array()
            .unwrap()
            .iter()
            .position(|b| b["name"] == "torso")
            .unwrap()
    };
    // Positive definite and within the diagonal triangle inequality, but
    // |2 Iyz| = 2 > Ixx = 1.4745.
    let mut v = jumper_json();
    let t = torso(&v);
    v["bodies"][t]["inertia"] = serde_json::json!([1.4745, 0.7555, 1.4314, 0.0, 0.0, -1.0]);
    let e = refused(&v);
    assert_eq!(e.field(), format!("bodies[{t}].inertia"));
    assert!(
        e.to_string().contains("product of inertia too large"),
        "{e}"
    );
    // Moments 1, 1, 1 and products 0.5 pass both, but the principal moments
    // are 2, 0.5 and 0.5 (the eigenvalues of I + 0.5·(11ᵀ − I)).
    v["bodies"][t]["inertia"] = serde_json::json!([1.0, 1.0, 1.0, 0.5, 0.5, 0.5]);
    let e = refused(&v);
    assert_eq!(e.field(), format!("bodies[{t}].inertia"));
    assert!(
        e.to_string().contains("principal moments")
            && e.to_string().contains("violate the triangle inequality"),
        "{e}"
    );
    // A physical inertia in a rotated frame is accepted: the torso's
    // principal moments turned by 0.3 rad about x.
    let (c, s) = (0.3f64.cos(), 0.3f64.sin());
    let (yy, zz) = (0.7555, 1.4314);
    v["bodies"][t]["inertia"] = serde_json::json!([
        1.4745,
        c * c * yy + s * s * zz,
        s * s * yy + c * c * zz,
        0.0,
        0.0,
        c * s * (yy - zz)
    ]);
    Model::from_json_str(&v.to_string(), "m.json").unwrap();
    // m·|c|² would overflow: the mass centre lies far outside the body.
    let mut v = jumper_json();
    v["bodies"][t]["mass_center"] = serde_json::json!([0.0, 1e300, 0.0]);
    let e = refused(&v);
    assert_eq!(e.field(), format!("bodies[{t}].mass_center"));
    assert!(e.to_string().contains("within ±100 m"), "{e}");
}

/// Names become OpenSim paths and .sto column labels: a muscle named
/// "sol eus/\t_r" had been accepted, and `leap simulate` wrote a states
/// file whose labels the tab split, which `leap analyze` then refused.
#[test]
fn names_that_break_paths_or_column_labels_are_refused() {
    let v = jumper_json();
    let soleus = muscle_index(&v, "soleus_r");
    for (path, name) in [
        (format!("forces.muscles[{soleus}].name"), "sol eus_r"),
        (format!("forces.muscles[{soleus}].name"), "sol\teus_r"),
        (format!("forces.muscles[{soleus}].name"), "soleus/_r"),
        ("bodies[0].name".to_string(), "pel+vis"),
        ("coordinates[0].name".to_string(), ""),
        ("joints[0].name".to_string(), "ground*pelvis"),
        ("stations[0].name".to_string(), "a\\b"),
        ("forces.contact.spheres[0].name".to_string(), "heel\n"),
        ("coordinates[3].name".to_string(), "hip,flexion_r"),
    ] {
        let mut m = v.clone();
        let mut at = &mut m;
        for part in path.split('.') {
            at = match part.split_once('[') {
                Some((key, idx)) => {
                    &mut at[key][idx.trim_end_matches(']').parse::<usize>().unwrap()]
                }
                None => &mut at[part],
            };
        }
        *at = serde_json::json!(name);
        let e = refused(&m);
        assert_eq!(e.field(), path, "{name:?}: {e}");
        let want = if name.is_empty() {
            "empty name".to_string()
        } else {
            "may not hold \\ / * + or ',', whitespace or control characters".to_string()
        };
        assert!(e.to_string().contains(&want), "{name:?}: {e}");
    }
}

/// Locations far beyond a human body and absurd masses are refused with
/// the field named: a mass centre at 1e100 m had reached Simbody, which
/// threw about the inertia's triangle inequality; a joint at 1e150 m and a
/// conditional path point at 1e150 m failed later naming no field (or
/// another muscle); a body of 1e12 kg set the two backends apart.
#[test]
fn far_locations_and_absurd_masses_are_refused_naming_the_field() {
    let v = jumper_json();
    let med_gas = muscle_index(&v, "med_gas_r");
    let far = "within ±100 m of the body's origin in each coordinate";
    for (field, pointer, value, want) in [
        (
            "bodies[1].mass_center",
            "/bodies/1/mass_center",
            serde_json::json!([0.0, 1e100, 0.0]),
            format!("{far}, got [0, 1e100, 0]"),
        ),
        (
            "joints[1].location_in_parent",
            "/joints/1/location_in_parent",
            serde_json::json!([0.0, -150.0, 0.0]),
            far.to_string(),
        ),
        (
            "stations[0].location",
            "/stations/0/location",
            serde_json::json!([1e150, 0.0, 0.0]),
            far.to_string(),
        ),
        (
            "bodies[1].mass",
            "/bodies/1/mass",
            serde_json::json!(1e12),
            "mass must be positive and at most 1e4 kg, got 1e12".to_string(),
        ),
        (
            "bodies[1].inertia",
            "/bodies/1/inertia",
            serde_json::json!([1e30, 1e30, 1e30, 0.0, 0.0, 0.0]),
            "a moment of 1e30 kg·m² gives a body of".to_string(),
        ),
        (
            "forces.contact.spheres[0].location",
            "/forces/contact/spheres/0/location",
            serde_json::json!([0.0, 0.0, f64::MAX]),
            far.to_string(),
        ),
    ] {
        let mut m = v.clone();
        *m.pointer_mut(pointer).unwrap() = value;
        let e = refused(&m);
        assert_eq!(e.field(), field, "{e}");
        assert!(e.to_string().contains(&want), "{field}: {e}");
    }
    // A path point, fixed or moving: the muscle's path names it.
    let mut m = v.clone();
    m["forces"]["muscles"][med_gas]["path"][0]["location"] = serde_json::json!([0.0, 1e150, 0.0]);
    let e = refused(&m);
    assert_eq!(
        e.field(),
        format!("forces.muscles[{med_gas}].path[0].location"),
        "{e}"
    );
    assert!(e.to_string().contains("within ±100 m"), "{e}");
    let rect_fem = muscle_index(&v, "rect_fem_r");
    let mut m = v.clone();
    m["forces"]["muscles"][rect_fem]["path"][2]["y_location"]["y"][1] = serde_json::json!(1e150);
    let e = refused(&m);
    assert_eq!(
        e.field(),
        format!("forces.muscles[{rect_fem}].path[2].y_location"),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("within ±100 m of the body's origin, got 1e150"),
        "{e}"
    );
}

/// The physical parameters of the muscles, the foot contact and the
/// passive joint torques must lie within ranges a decade or more beyond
/// those of the human models leap meets (gait2392's muscles and the
/// Thelen2003Muscle curves of OpenSim's models, Falisse et al.'s contact,
/// Anderson & Pandy's torques): beyond them (a force with extra digits, a
/// length in millimetres, a time constant in milliseconds, a shape factor
/// that turns a curve into a step) the file is refused, naming the
/// parameter, instead of failing later as a squat that does not touch the
/// ground or a non-finite fibre velocity, or loading to jump 78 cm (Af
/// 1e-300 flattens the force-velocity curve). The bounds themselves load
/// (a muscle's on both sides, as mirror partners must be; a signed
/// torque coefficient at either sign).
#[test]
fn parameters_far_outside_human_ranges_are_refused() {
    let v = jumper_json();
    let (r, l) = (muscle_index(&v, "soleus_r"), muscle_index(&v, "soleus_l"));
    // (where, indices to change alike, parameter, lowest, highest, unit,
    // signed)
    let muscles = |p| ("forces/muscles", vec![r, l], p);
    let contact = |p| ("forces/contact", vec![], p);
    let ligament = |p| ("forces/ligaments", vec![2, 3], p);
    let cases = [
        (muscles("max_isometric_force"), 1e-3, 1e5, "N", false),
        (muscles("optimal_fiber_length"), 1e-4, 5.0, "m", false),
        (muscles("tendon_slack_length"), 1e-4, 5.0, "m", false),
        (
            muscles("max_contraction_velocity"),
            0.1,
            100.0,
            "l_opt/s",
            false,
        ),
        (muscles("activation_time_constant"), 1e-4, 10.0, "s", false),
        (
            muscles("deactivation_time_constant"),
            1e-4,
            10.0,
            "s",
            false,
        ),
        (muscles("FmaxTendonStrain"), 1e-3, 1.0, "", false),
        (muscles("FmaxMuscleStrain"), 1e-2, 10.0, "", false),
        (muscles("KshapeActive"), 1e-2, 10.0, "", false),
        (muscles("KshapePassive"), 0.1, 100.0, "", false),
        (muscles("Af"), 1e-2, 10.0, "", false),
        // Flen's lowest is OpenSim's rule, tested with the broken files.
        (muscles("Flen"), 1.0 / 0.95 + 1e-9, 100.0, "", false),
        (contact("stiffness"), 1e4, 1e10, "Pa", false),
        (contact("transition_velocity"), 1e-5, 10.0, "m/s", false),
        (contact("dissipation"), 0.0, 100.0, "s/m", false),
        (contact("viscous_friction"), 0.0, 100.0, "s/m", false),
        (
            ("forces/contact/spheres", vec![3, 11], "radius"),
            1e-3,
            1.0,
            "m",
            false,
        ),
        (ligament("k1"), 0.0, 1e4, "N·m", true),
        (ligament("k2"), 0.0, 1e3, "1/rad", true),
        (ligament("k3"), 0.0, 1e4, "N·m", true),
        (ligament("k4"), 0.0, 1e3, "1/rad", true),
        (
            ligament("theta1"),
            0.0,
            2.0 * std::f64::consts::PI,
            "rad",
            true,
        ),
        (
            ligament("theta2"),
            0.0,
            2.0 * std::f64::consts::PI,
            "rad",
            true,
        ),
        (ligament("damping"), 0.0, 1e3, "N·m·s/rad", false),
    ];
    for ((place, indices, name), lo, hi, unit, signed) in cases {
        let mut values = vec![(lo, true), (hi, true), (hi * 1.01, false)];
        if signed {
            values.extend([(-hi, true), (-hi * 1.01, false)]);
        } else if lo > 0.0 && name != "Flen" {
            values.push((lo * 0.99, false));
        }
        for (value, ok) in values {
            let mut m = v.clone();
            let mut field = place.replace('/', ".");
            if indices.is_empty() {
                *m.pointer_mut(&format!("/{place}/{name}")).unwrap() = serde_json::json!(value);
            }
            for (n, &k) in indices.iter().enumerate() {
                *m.pointer_mut(&format!("/{place}/{k}/{name}")).unwrap() = serde_json::json!(value);
                if n == 0 {
                    field = format!("{field}[{k}]");
                }
            }
            let got = Model::from_json_str(&m.to_string(), "m.json");
            // Inside its range an exponent beyond about 300 may still
            // overflow its term over the knee's range (tested below),
            // named alike.
            let overflows = |e: &ModelError| {
                (name == "k2" || name == "k4")
                    && value.abs() > 300.0
                    && e.field() == format!("{field}.{name}")
                    && e.to_string().contains("overflows at")
            };
            if ok {
                assert!(
                    got.as_ref().err().is_none_or(overflows),
                    "{place} {name} = {value}: {:?}",
                    got.err()
                );
                continue;
            }
            let e = got.unwrap_err();
            assert_eq!(e.field(), format!("{field}.{name}"), "{e}");
            let text = e.to_string();
            let shown = if unit.is_empty() {
                String::new()
            } else {
                format!(" {unit}")
            };
            assert!(text.contains(&format!("{shown}: lies outside [")), "{text}");
        }
    }
    // SmoothSphereHalfSpaceForce's smoothing constants (OpenSim's defaults
    // 300 1/m, 50 s/m, 1e-5 m²): within their ranges under that law, and
    // refused under HuntCrossleyForce, which has none.
    for (name, lo, hi) in [
        ("hertz_smoothing", 10.0, 1e5),
        ("hunt_crossley_smoothing", 1.0, 1e4),
        ("derivative_smoothing", 1e-9, 1e-3),
    ] {
        for (law, value, ok) in [
            ("SmoothSphereHalfSpaceForce", lo, true),
            ("SmoothSphereHalfSpaceForce", hi, true),
            ("SmoothSphereHalfSpaceForce", lo * 0.99, false),
            ("SmoothSphereHalfSpaceForce", hi * 1.01, false),
            ("SmoothSphereHalfSpaceForce", 1e-300, false),
            ("HuntCrossleyForce", lo, false),
        ] {
            let mut m = v.clone();
            m["forces"]["contact"]["law"] = law.into();
            m["forces"]["contact"][name] = value.into();
            let got = Model::from_json_str(&m.to_string(), "m.json");
            if ok {
                assert!(got.is_ok(), "{law} {name} = {value}: {:?}", got.err());
                continue;
            }
            let e = got.unwrap_err();
            assert_eq!(e.field(), format!("forces.contact.{name}"), "{e}");
            let want = if law == "HuntCrossleyForce" {
                "HuntCrossleyForce does not use it"
            } else {
                ": lies outside ["
            };
            assert!(e.to_string().contains(want), "{e}");
        }
    }
    // The knee's passive torque −6.09·exp(k2·(q − 0.13)) with its second
    // derivative (×k2²) is finite over the knee's range [−2.0944, 0.1745]
    // while 6.09·k2²·exp(−k2·2.2244) stays below f64::MAX (ln = 709.78):
    // k2 = −300 gives 680.5, −320 gives 725.2.
    for (k2, ok) in [(-300.0, true), (-320.0, false)] {
        let mut m = v.clone();
        for k in [2, 3] {
            m["forces"]["ligaments"][k]["k2"] = serde_json::json!(k2);
        }
        let got = Model::from_json_str(&m.to_string(), "m.json");
        if ok {
            assert!(got.is_ok(), "k2 = {k2}: {:?}", got.err());
        } else {
            let e = got.unwrap_err();
            assert_eq!(e.field(), "forces.ligaments[2].k2", "{e}");
            assert!(e.to_string().contains("overflows at -2.0944 rad"), "{e}");
        }
    }
    // A term switched off (k1 = 0) does not overflow, whatever its k2.
    let mut m = v.clone();
    for k in [2, 3] {
        m["forces"]["ligaments"][k]["k1"] = serde_json::json!(0.0);
        m["forces"]["ligaments"][k]["k2"] = serde_json::json!(-1e3);
    }
    let got = Model::from_json_str(&m.to_string(), "m.json");
    assert!(got.is_ok(), "{:?}", got.err());
    // ... and its torque is the other term alone, finite at the squat's knee
    // (−1.396 rad), where exp(−1e3·(q − 0.13)) overflows.
    let l = &m["forces"]["ligaments"][2];
    let spec: leap::model::LigamentSpec = serde_json::from_value(l.clone()).unwrap();
    let q = -1.3962634;
    let tau = leap::laws::passive_torque(&spec, q, 0.0);
    let other = 11.03 * (-11.33 * (q + 2.4f64)).exp();
    assert!(
        (tau - other).abs() <= 1e-12 * other.abs(),
        "{tau} against {other}"
    );
    // Friction coefficients up to 10 (dynamic at most static).
    for (stat, dynamic, refused) in [
        (10.0, 10.0, None),
        (10.1, 0.8, Some("static_friction")),
        (10.0, 10.1, Some("dynamic_friction")),
    ] {
        let mut m = v.clone();
        m["forces"]["contact"]["static_friction"] = serde_json::json!(stat);
        m["forces"]["contact"]["dynamic_friction"] = serde_json::json!(dynamic);
        let got = Model::from_json_str(&m.to_string(), "m.json");
        match refused {
            None => assert!(got.is_ok(), "{:?}", got.err()),
            Some(name) => {
                let e = got.unwrap_err();
                assert_eq!(e.field(), format!("forces.contact.{name}"), "{e}");
                assert!(e.to_string().contains(": lies outside [0, 10]"), "{e}");
            }
        }
    }
}

/// A symmetry pair is [right, left] of one coordinate: a reversed pair, a
/// pair of one side or of two coordinates, a coordinate paired twice and
/// partners whose ranges or defaults differ are refused at the pair's own
/// entry (they had been reported at a joint, a later pair or a pose).
#[test]
fn symmetry_pairs_are_checked_at_their_own_entry() {
    let v = jumper_json();
    let pair = |r: &str, l: &str| serde_json::json!([r, l]);
    let cases = [
        (
            pair("hip_flexion_l", "hip_flexion_r"),
            "symmetry[0]",
            "lists the left coordinate first: a pair is [right, left], so write [\"hip_flexion_r\", \"hip_flexion_l\"]",
        ),
        (
            pair("hip_flexion_r", "knee_angle_l"),
            "symmetry[0]",
            "whose names differ in more than the side",
        ),
        (
            pair("hip_flexion_r", "knee_angle_r"),
            "symmetry[0]",
            "pairs two coordinates of one side",
        ),
        (
            pair("hip_flexion_r", "hip_flexion_r"),
            "symmetry[0]",
            "pairs coordinate 'hip_flexion_r' with itself",
        ),
    ];
    // Refused at `field`, for `reason`.
    let refused_at = |m: &serde_json::Value, field: &str, reason: &str| {
        let e = refused(m);
        assert_eq!(e.field(), field, "{e}");
        assert!(e.to_string().contains(reason), "{e}");
    };
    for (p, field, reason) in cases {
        let mut m = v.clone();
        m["symmetry"][0] = p;
        refused_at(&m, field, reason);
    }
    // A coordinate paired twice: the later pair is refused, naming the
    // earlier one.
    let mut m = v.clone();
    m["symmetry"]
        .as_array_mut()
        .unwrap()
        .push(pair("lumbar_extension", "knee_angle_l"));
    refused_at(
        &m,
        "symmetry[3][1]",
        "'knee_angle_l' is already paired by symmetry[1]",
    );
    // Partners with different ranges or defaults.
    let hip_l = v["coordinates"]
        .as_array()
        .unwrap()
        .iter()
        .position(|c| c["name"] == "hip_flexion_l")
        .unwrap();
    for (key, value) in [
        ("range", serde_json::json!([-2.0, 2.0])),
        ("default_value", serde_json::json!(0.1)),
    ] {
        let mut m = v.clone();
        m["coordinates"][hip_l][key] = value;
        refused_at(
            &m,
            "symmetry[0]",
            "mirror partners need one range and one default",
        );
    }
}

/// A spline whose neighbouring knots rise more than 100 m per radian (a
/// knot moved to 1e-12 rad of its neighbour) is refused when the file is
/// read, naming the joint's translation or the moving point's coordinate
/// function, where before it loaded and failed later as a singular mass
/// matrix. gait2392's knee and patella splines reach 0.08 m/rad.
#[test]
fn steep_splines_are_refused_naming_the_function() {
    let v = jumper_json();
    for (joint, f) in [(2, "translation_x"), (7, "translation_y")] {
        let mut m = v.clone();
        let x0 = m["joints"][joint][f]["x"][0].as_f64().unwrap();
        m["joints"][joint][f]["x"][1] = (x0 + 1e-12).into();
        let e = refused(&m);
        assert_eq!(e.field(), format!("joints[{joint}].{f}"), "{e}");
        assert!(e.to_string().contains("a slip of digits"), "{e}");
    }
    let k = muscle_index(&v, "rect_fem_r");
    let l = muscle_index(&v, "rect_fem_l");
    let mut m = v.clone();
    for j in [k, l] {
        let x0 = m["forces"]["muscles"][j]["path"][2]["y_location"]["x"][0]
            .as_f64()
            .unwrap();
        m["forces"]["muscles"][j]["path"][2]["y_location"]["x"][1] = (x0 + 1e-12).into();
    }
    let e = refused(&m);
    assert_eq!(
        e.field(),
        format!("forces.muscles[{k}].path[2].y_location"),
        "{e}"
    );
    assert!(e.to_string().contains("a slip of digits"), "{e}");
}
