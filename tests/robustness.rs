//! Bad model files, made systematically: every value of the default model
//! changed to one it must not take (zero, negative, 1e300, the wrong type,
//! null), every key removed, every array shortened and given a duplicate:
//! about 16,000 files. Each is taken as far as the jump problem's first
//! evaluation, ẋ = f(x, u) at the static squat, through both backends. No
//! mutant may panic; a refused one must name the file and a field of it
//! (`<file>: <field>: <reason>`); an accepted one must give finite rates on
//! which the Rust-native and Simbody backends agree.
//!
//! `LEAP_MUTANT_SHOW=1` prints every mutant's outcome.

use leap::model::Model;
use leap::ocp::{JumpOcp, OcpOptions};
use serde_json::Value;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// One change to the model file: where, and what it became.
struct Mutant {
    place: String,
    what: String,
    text: String,
}

/// Every value of `v` with its place (`.forces.muscles[3].path[1]`),
/// objects and arrays as well as numbers, strings and booleans.
fn values(v: &Value, place: String, out: &mut Vec<(String, Value)>) {
    out.push((place.clone(), v.clone()));
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                values(x, format!("{place}.{k}"), out);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                values(x, format!("{place}[{i}]"), out);
            }
        }
        _ => {}
    }
}

/// The JSON pointer (RFC 6901, serde_json's `Value::pointer`) of a place
/// as `values` writes it (`.forces.muscles[3].path`) or an error names it
/// (`symmetry[2][1]`): `/forces/muscles/3/path`. The model's keys hold no
/// `/` or `~`.
fn pointer(place: &str) -> String {
    place
        .trim_start_matches('.')
        .split(['.', '['])
        .filter(|s| !s.is_empty())
        .map(|s| format!("/{}", s.trim_end_matches(']')))
        .collect()
}

/// The value at `place` (as `values` writes it) of `root`.
fn at<'a>(root: &'a mut Value, place: &str) -> &'a mut Value {
    root.pointer_mut(&pointer(place)).unwrap()
}

/// Each value of the model changed in each way it must not be: a number
/// to zero, its negative (−1 for zero) and 1e300 (finite, but no length,
/// mass or stiffness of a body), or a string; a string emptied, unknown or
/// a number; a boolean flipped; anything null; each key of an object
/// removed; an array without its first element, and with it twice.
fn mutants(model: &Value) -> Vec<Mutant> {
    let mut list = Vec::new();
    let mut all = Vec::new();
    values(model, String::new(), &mut all);
    let mut push = |place: &str, what: String, m: Value| {
        list.push(Mutant {
            place: place.to_string(),
            what,
            text: m.to_string(),
        })
    };
    for (place, v) in &all {
        let replacements: Vec<(&str, Value)> = match v {
            Value::Number(n) => {
                let x = n.as_f64().unwrap();
                vec![
                    ("0", Value::from(0.0)),
                    ("negated", Value::from(if x == 0.0 { -1.0 } else { -x })),
                    ("1e300", Value::from(1e300)),
                    ("a string", Value::from("1")),
                ]
            }
            Value::String(_) => vec![
                ("empty", Value::from("")),
                ("unknown", Value::from("no_such_thing")),
                ("a number", Value::from(1.0)),
            ],
            Value::Bool(b) => vec![("flipped", Value::from(!b))],
            Value::Object(o) => {
                for k in o.keys() {
                    let mut m = model.clone();
                    at(&mut m, place).as_object_mut().unwrap().remove(k);
                    push(place, format!("without '{k}'"), m);
                }
                vec![]
            }
            Value::Array(a) => {
                if let Some(first) = a.first() {
                    let mut m = model.clone();
                    at(&mut m, place).as_array_mut().unwrap().remove(0);
                    push(place, "without its first element".into(), m);
                    let mut m = model.clone();
                    at(&mut m, place)
                        .as_array_mut()
                        .unwrap()
                        .insert(0, first.clone());
                    push(place, "with its first element twice".into(), m);
                }
                vec![]
            }
            Value::Null => vec![],
        };
        for (what, nv) in replacements.into_iter().chain([("null", Value::Null)]) {
            if place.is_empty() {
                continue; // the whole document: `a_model_file_is_one_json_object`
            }
            let mut m = model.clone();
            *at(&mut m, place) = nv;
            push(place, what.to_string(), m);
        }
    }
    list
}

/// What became of one mutant.
enum Outcome {
    /// Refused, at load or later (the static squat, the state equation,
    /// Simbody): the message.
    Refused(String),
    /// Evaluated by both backends: the largest difference of ẋ, relative
    /// to max(1, |ẋ|).
    Evaluated(f64),
}

/// Whether `path` (`forces.muscles[17].path`, `symmetry[2][1]`,
/// `(document)`) names a value of `doc`.
fn resolves(doc: &Value, path: &str) -> bool {
    path == "(document)" || doc.pointer(&pointer(path)).is_some()
}

/// The field path an error names after the file (`<file>: <path>: why`):
/// names, indices and `(document)`.
fn named_field<'a>(message: &'a str, file: &str) -> Option<&'a str> {
    let rest = message.strip_prefix(file)?.strip_prefix(": ")?;
    let path = &rest[..rest.find(": ")?];
    let ok = !path.is_empty()
        && path
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_.[]()".contains(c));
    ok.then_some(path)
}

fn take(text: &str) -> Result<Outcome, String> {
    let model = match Model::from_json_str(text, "mutant.json") {
        Ok(m) => m,
        Err(e) => return Ok(Outcome::Refused(e.to_string())),
    };
    let ocp = match JumpOcp::new(&model, OcpOptions::default()) {
        Ok(o) => o,
        Err(e) => return Ok(Outcome::Refused(e.to_string())),
    };
    let (x, u) = (ocp.x0().to_vec(), ocp.u0().to_vec());
    let mut rust = vec![0.0f64; x.len()];
    let mut ws = ocp.eq.workspace::<f64>();
    let (ydd, fy) = match ocp.state_rates(&mut ws, &x, &u, &mut rust) {
        Ok(v) => v,
        Err(e) => return Ok(Outcome::Refused(e.to_string())),
    };
    if !(rust.iter().all(|v| v.is_finite()) && ydd.is_finite() && fy.is_finite()) {
        return Err(format!(
            "Rust-native rates not finite: ẋ {rust:?}, Ÿ_C {ydd}, F_y {fy}"
        ));
    }
    let mut sb = match ocp.simbody_rates() {
        Ok(s) => s,
        Err(e) => return Ok(Outcome::Refused(e.to_string())),
    };
    let mut simbody = vec![0.0f64; x.len()];
    match sb.eval(&x, &u, &mut simbody) {
        Ok(_) => {}
        Err(e) => return Ok(Outcome::Refused(e)),
    }
    if !simbody.iter().all(|v| v.is_finite()) {
        return Err(format!("Simbody rates not finite: {simbody:?}"));
    }
    let diff = rust
        .iter()
        .zip(&simbody)
        .map(|(a, b)| (a - b).abs() / a.abs().max(1.0))
        .fold(0.0, f64::max);
    Ok(Outcome::Evaluated(diff))
}

#[test]
fn every_mutated_field_is_refused_by_name_or_evaluates_finitely() {
    let model: Value =
        serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap();
    let all = mutants(&model);
    let mut failures = Vec::new();
    let (mut refused, mut evaluated) = (0, 0);
    let mut worst = (0.0, String::new());
    let t = std::time::Instant::now();
    for m in &all {
        match catch_unwind(AssertUnwindSafe(|| take(&m.text))) {
            Err(p) => {
                let msg = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                failures.push(format!("{} {}: panicked: {msg}", m.place, m.what));
            }
            Ok(Err(e)) => failures.push(format!("{} {}: {e}", m.place, m.what)),
            Ok(Ok(Outcome::Refused(e))) => {
                refused += 1;
                if std::env::var("LEAP_MUTANT_SHOW").is_ok() {
                    eprintln!("REFUSED {} {}: {e}", m.place, m.what);
                }
                // The error names the file and a field of it: the one
                // changed, or one it made wrong (a reference to a renamed
                // body, a pose outside a changed range, a mirror partner,
                // the squat that no longer stands).
                let doc: Value = serde_json::from_str(&m.text).unwrap();
                // A field removed is named as missing: it, or the object
                // that misses it.
                let removed = m
                    .what
                    .strip_prefix("without '")
                    .map(|k| format!("{}.{}", m.place, k.trim_end_matches('\'')));
                let names_removed = |f: &str| {
                    removed.as_deref().is_some_and(|r| {
                        let r = r.trim_start_matches('.');
                        r.starts_with(f) || f.starts_with(r)
                    })
                };
                match named_field(&e, "mutant.json") {
                    Some(f) if resolves(&doc, f) || names_removed(f) => {
                        // A value of the wrong type is named exactly, also
                        // inside joints and path points (tagged objects,
                        // where serde's own enums lose the path).
                        let type_error =
                            e.contains("invalid type") || e.contains("expected a whole number");
                        if type_error && f != m.place.trim_start_matches('.') {
                            failures.push(format!(
                                "{} {}: type error named at {f}: {e}",
                                m.place, m.what
                            ));
                        }
                    }
                    _ => failures.push(format!(
                        "{} {}: error without the file and a field of it: {e}",
                        m.place, m.what
                    )),
                }
            }
            Ok(Ok(Outcome::Evaluated(d))) => {
                evaluated += 1;
                if std::env::var("LEAP_MUTANT_SHOW").is_ok() {
                    eprintln!("EVALUATED {} {}: {d:.1e}", m.place, m.what);
                }
                if d > worst.0 {
                    worst = (d, format!("{} {}", m.place, m.what));
                }
            }
        }
    }
    eprintln!(
        "{} mutants: {refused} refused, {evaluated} evaluated, {} failures, {:.1} s",
        all.len(),
        failures.len(),
        t.elapsed().as_secs_f64()
    );
    eprintln!(
        "largest difference of the backends' rates: {:.1e} ({})",
        worst.0, worst.1
    );
    for f in &failures {
        eprintln!("{f}");
    }
    assert!(failures.is_empty());
    // Both backends compute the same laws; they differ in the multibody
    // dynamics (leap's recursive one against Simbody's), which the changed
    // masses, inertias, joint and contact locations exercise.
    assert!(
        worst.0 <= 1e-8,
        "rates differ by {:.1e} at {}",
        worst.0,
        worst.1
    );
    // The mutants reach every stage: most are refused, some evaluated.
    assert!(
        refused > 10_000 && evaluated > 500,
        "{refused} refused, {evaluated} evaluated"
    );
}

/// The study files likewise: every value, key and array of the built-in
/// study written out (`models/jump_collocation.json`) and of the shooting
/// study changed, each mutant read and resolved as `leap solve` does. A
/// removed or null field takes its default; a refused mutant names the
/// study file and a field of it.
#[test]
fn every_mutated_study_field_is_refused_by_name_or_resolves() {
    use leap::study::SolveStudy as Study;
    let mut failures = Vec::new();
    let (mut refused, mut resolved) = (0, 0);
    for file in ["models/jump_collocation.json", "models/jump_shooting.json"] {
        let study: Value = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        for m in mutants(&study) {
            let outcome = catch_unwind(AssertUnwindSafe(|| {
                Study::from_json_str(&m.text, file)
                    .and_then(|s| s.resolve(Some(std::path::Path::new(file))))
            }));
            match outcome {
                Err(_) => failures.push(format!("{file} {} {}: panicked", m.place, m.what)),
                Ok(Err(e)) => {
                    refused += 1;
                    let e = e.to_string();
                    if std::env::var("LEAP_MUTANT_SHOW").is_ok() {
                        eprintln!("REFUSED {} {}: {e}", m.place, m.what);
                    }
                    let doc: Value = serde_json::from_str(&m.text).unwrap();
                    match named_field(&e, file) {
                        Some(f)
                            if resolves(&doc, f)
                                || f.starts_with(m.place.trim_start_matches('.')) => {}
                        _ => failures.push(format!(
                            "{file} {} {}: error without the file and a field of it: {e}",
                            m.place, m.what
                        )),
                    }
                }
                Ok(Ok(_)) => {
                    resolved += 1;
                    if std::env::var("LEAP_MUTANT_SHOW").is_ok() {
                        eprintln!("RESOLVED {} {}", m.place, m.what);
                    }
                }
            }
        }
    }
    eprintln!(
        "studies: {refused} refused, {resolved} resolved, {} failures",
        failures.len()
    );
    for f in &failures {
        eprintln!("{f}");
    }
    assert!(failures.is_empty());
    assert!(
        refused > 50 && resolved > 50,
        "{refused} refused, {resolved} resolved"
    );
}

/// A path point far outside its body is named by the muscle's index in
/// the file and the point's in its path, when the model is read: vas_med_r's
/// fourth point (path[3], its second conditional one, inactive at the
/// default values and the squat) moved to 1e300 m, and soleus_r's first
/// point, fixed. (Until the model file bounded locations, the state
/// equation's path-length check named them as lengths of inf m.)
#[test]
fn a_path_without_a_finite_length_is_named_with_its_point() {
    let base: Value =
        serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap();
    let index = |name: &str| {
        base["forces"]["muscles"]
            .as_array()
            .unwrap()
            .iter()
            .position(|m| m["name"] == name)
            .unwrap()
    };
    for (muscle, point) in [("vas_med_r", 3), ("soleus_r", 0)] {
        let k = index(muscle);
        let mut v = base.clone();
        v["forces"]["muscles"][k]["path"][point]["location"][0] = 1e300.into();
        let e = Model::from_json_str(&v.to_string(), "m.json").unwrap_err();
        assert_eq!(
            e.field(),
            format!("forces.muscles[{k}].path[{point}].location"),
            "{e}"
        );
        assert!(e.to_string().contains("within ±100 m"), "{e}");
    }
}

/// A jump model's standing pose must put its feet on the ground, since the
/// jump height is measured from the centre of mass there: the pelvis raised
/// or lowered by 10 cm moves every sphere by exactly that (a translation),
/// and the refusal names `poses.standing` with the distance; without a
/// standing pose the coordinates' default values are checked, named
/// `poses`. Each shipped jump model stands within a millimetre.
#[test]
fn a_standing_pose_off_the_ground_is_refused_naming_it() {
    let base: Value =
        serde_json::from_str(&std::fs::read_to_string("models/jumper.json").unwrap()).unwrap();
    let ty = base["poses"]["standing"]["pelvis_ty"].as_f64().unwrap();
    for (shift, words) in [(0.1, "100.0 mm above"), (-0.1, "100.0 mm into")] {
        let mut v = base.clone();
        v["poses"]["standing"]["pelvis_ty"] = (ty + shift).into();
        let model = Model::from_json_str(&v.to_string(), "m.json").unwrap();
        let e = JumpOcp::new(&model, OcpOptions::default()).err().unwrap();
        let e = e.to_string();
        assert!(e.starts_with("m.json: poses.standing: "), "{e}");
        assert!(e.contains(words), "{e}");
    }
    let mut v = base.clone();
    v["poses"].as_object_mut().unwrap().remove("standing");
    let coords = v["coordinates"].as_array_mut().unwrap();
    let k = coords
        .iter()
        .position(|c| c["name"] == "pelvis_ty")
        .unwrap();
    coords[k]["default_value"] = (ty + 0.1).into();
    let model = Model::from_json_str(&v.to_string(), "m.json").unwrap();
    let e = JumpOcp::new(&model, OcpOptions::default())
        .err()
        .unwrap()
        .to_string();
    assert!(e.starts_with("m.json: poses: "), "{e}");
    assert!(
        e.contains("default values") && e.contains("100.0 mm above"),
        "{e}"
    );
    // SmoothSphereHalfSpaceForce pushes before touching, so its spheres
    // rest above the ground: not checked.
    let mut v = base.clone();
    v["forces"]["contact"]["law"] = "SmoothSphereHalfSpaceForce".into();
    v["poses"]["standing"]["pelvis_ty"] = (ty + 0.1).into();
    let model = Model::from_json_str(&v.to_string(), "m.json").unwrap();
    JumpOcp::new(&model, OcpOptions::default()).unwrap();
    for file in [
        "models/jumper.json",
        "models/jumper_gait2392.json",
        "models/jumper_jmp_strength.json",
        "models/jumper_reduced.json",
    ] {
        let model = Model::from_file(file).unwrap();
        JumpOcp::new(&model, OcpOptions::default()).unwrap();
    }
}
