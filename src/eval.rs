//! `leap eval`: ẋ = f(x, u) and all its parts at given states, the way
//! OpenSim's Analyze tool reports muscle, contact and joint quantities.
//!
//! Input (JSON): one object or an array of objects, each
//! `{"state": {"<OpenSim state name>": value, ...}, "excitation":
//! {"/forceset/<muscle>": value, ...}}` or `{"x": [...], "u": [...]}` in the
//! order of [`StateEquation::state_names`] and
//! [`StateEquation::control_names`]. Input (CSV): a header of state and
//! control names (an optional `time` column is ignored), one evaluation per
//! row. Missing states or excitations are errors.

use crate::laws::OpenSimLaws;
use crate::multibody::{GeneralizedForces, ModelView};
use crate::ode::StateEquation;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// One muscle's quantities (OpenSim's output names).
#[derive(Debug, Clone, Serialize)]
pub struct MuscleReport {
    pub length: f64,
    pub lengthening_speed: f64,
    /// Moment arm per coordinate (m), r = −∂L/∂q; zero entries omitted.
    pub moment_arms: BTreeMap<String, f64>,
    pub fiber_length: f64,
    pub fiber_velocity: f64,
    pub pennation_angle: f64,
    pub tendon_length: f64,
    pub tendon_force: f64,
    pub active_fiber_force: f64,
    pub passive_fiber_force: f64,
    pub activation_rate: f64,
}

/// Everything at one state.
#[derive(Debug, Clone, Serialize)]
pub struct EvalReport {
    /// ẋ by state name.
    pub state_derivative: BTreeMap<String, f64>,
    /// q̈ by coordinate name.
    pub accelerations: BTreeMap<String, f64>,
    pub muscles: BTreeMap<String, MuscleReport>,
    /// Force on each contact sphere from the ground (N, ground frame).
    pub contact_forces: BTreeMap<String, [f64; 3]>,
    /// Passive joint torques (N·m) by coordinate.
    pub ligament_torques: BTreeMap<String, f64>,
    pub com_position: [f64; 3],
    pub com_velocity: [f64; 3],
    /// What makes this state unusual, though OpenSim evaluates it too: a
    /// coordinate outside its range (where no motion of the model goes,
    /// and a passive torque's exponential may be far beyond its fitted
    /// values), a fibre shorter than its minimum length (held there, as
    /// OpenSim's Thelen muscle holds it).
    pub warnings: Vec<String>,
}

/// Bad `leap eval` input: names the file, the entry and the field.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {place}: {reason}")]
pub struct EvalInputError {
    pub file: String,
    pub place: String,
    pub reason: String,
    /// The input lacks states or excitations the system carries: a missing
    /// column or name, or an array with fewer values than names (as a
    /// symmetric input, `leap squat`'s, given to the full system).
    pub lacks_values: bool,
}

/// Evaluation inputs: one (x, u) pair per evaluation.
pub type Inputs = Vec<(Vec<f64>, Vec<f64>)>;

/// Read evaluations (x, u) from a JSON or CSV file.
pub fn read_inputs(eq: &StateEquation, path: &Path) -> Result<Inputs, EvalInputError> {
    let file = path.display().to_string();
    let err = |place: String, reason: String| EvalInputError {
        file: file.clone(),
        place,
        reason,
        lacks_values: false,
    };
    let lacks = |place: String, reason: String| EvalInputError {
        lacks_values: true,
        ..err(place, reason)
    };
    let text = crate::io::read_input_text(path).map_err(|e| err("(file)".into(), e.to_string()))?;
    // A byte-order mark (spreadsheet exports write one) is not data.
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let states = eq.state_names();
    let controls = eq.control_names();
    // The left leg's columns of leap's files (and of `leap squat --full`'s
    // names on the whole model) are read as checks: each must equal its
    // right partner's, which the symmetric system carries for both.
    let copies = |columns: Vec<(String, usize)>, names: &[String]| -> Vec<(String, usize)> {
        columns
            .into_iter()
            .filter(|(l, i)| *l != names[*i])
            .collect()
    };
    let state_copies = copies(eq.model_state_columns(), &states);
    let control_copies = copies(eq.model_control_columns(), &controls);
    // `given`: the copies an input holds, (label, value), values finite.
    let check_copies =
        |given: &[(String, f64)], x: &[f64], u: &[f64]| -> Result<(), (String, String)> {
            for (label, copy) in given {
                let found = state_copies
                    .iter()
                    .find(|(l, _)| l == label)
                    .map(|(_, i)| (x[*i], &states[*i]))
                    .or_else(|| {
                        control_copies
                            .iter()
                            .find(|(l, _)| l == label)
                            .map(|(_, i)| (u[*i], &controls[*i]))
                    });
                if let Some((original, name)) = found {
                    if let Some(r) = crate::io::copy_mismatch(*copy, original, name) {
                        return Err((label.clone(), r));
                    }
                }
            }
            Ok(())
        };
    let pre_4 = crate::io::pre_4_state_names(eq);
    let angular = crate::io::angular_columns(eq);
    let is_copy = |c: &str, copies: &[(String, usize)]| copies.iter().any(|(l, _)| l == c);
    let known = |c: &str| {
        states.iter().chain(&controls).any(|n| n == c)
            || is_copy(c, &state_copies)
            || is_copy(c, &control_copies)
    };
    let is_csv = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.eq_ignore_ascii_case("csv"))
        .unwrap_or(false);
    let mut out = Vec::new();
    if is_csv {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let (_, header) = lines
            .next()
            .ok_or_else(|| err("line 1".into(), "empty file".into()))?;
        // A spreadsheet in a locale with a decimal comma exports with
        // semicolons; some tools write tabs.
        if !header.contains(',') {
            for (sep, what) in [('\t', "tabs"), (';', "semicolons")] {
                if header.contains(sep) {
                    return Err(err(
                        "header".into(),
                        format!("separated by {what}: leap eval reads CSV separated by commas, with '.' as the decimal point"),
                    ));
                }
            }
        }
        // Labels may be quoted, as spreadsheets write them.
        let cols: Vec<&str> = header
            .split(',')
            .map(|c| c.trim().trim_matches('"'))
            .collect();
        // As in the JSON form: every column is known, and named once.
        if let Some((first, k)) = crate::io::first_repeat(&cols) {
            return Err(err(
                "header".into(),
                format!(
                    "column '{}' appears twice: columns {} and {}",
                    cols[k],
                    first + 1,
                    k + 1
                ),
            ));
        }
        // The documented optional time column (as leap's and OpenSim's
        // tables lead with) is not read.
        for (k, c) in cols.iter().enumerate() {
            if !known(c) && *c != "time" {
                return Err(err(
                    "header".into(),
                    format!(
                        "unknown column '{c}' (column {}): {}",
                        k + 1,
                        unknown_name_reason(c, &pre_4, &angular, None)
                    ),
                ));
            }
        }
        let find = |name: &str| cols.iter().position(|c| *c == name);
        let xi: Vec<usize> = states
            .iter()
            .map(|n| find(n).ok_or_else(|| lacks("header".into(), format!("missing column '{n}'"))))
            .collect::<Result<_, _>>()?;
        let ui: Vec<usize> = controls
            .iter()
            .map(|n| find(n).ok_or_else(|| lacks("header".into(), format!("missing column '{n}'"))))
            .collect::<Result<_, _>>()?;
        // The left leg's columns, read as checks.
        let copy_cols: Vec<usize> = (0..cols.len())
            .filter(|&k| is_copy(cols[k], &state_copies) || is_copy(cols[k], &control_copies))
            .collect();
        for (ln, line) in lines {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            if cells.len() != cols.len() {
                return Err(err(
                    format!("line {}", ln + 1),
                    format!("{} values, expected {}", cells.len(), cols.len()),
                ));
            }
            let parse = |k: usize| -> Result<f64, EvalInputError> {
                let v: f64 = cells[k].parse().map_err(|_| {
                    err(
                        format!("line {}, column '{}'", ln + 1, cols[k]),
                        format!("'{}' is not a number", cells[k]),
                    )
                })?;
                if !v.is_finite() {
                    return Err(err(
                        format!("line {}, column '{}'", ln + 1, cols[k]),
                        "not finite".into(),
                    ));
                }
                Ok(v)
            };
            let x = xi
                .iter()
                .map(|&k| parse(k))
                .collect::<Result<Vec<_>, _>>()?;
            let u = ui
                .iter()
                .map(|&k| parse(k))
                .collect::<Result<Vec<_>, _>>()?;
            check_ranges(&states, &controls, &x, &u).map_err(|(name, reason)| {
                err(format!("line {}, column '{name}'", ln + 1), reason)
            })?;
            let given = copy_cols
                .iter()
                .map(|&k| Ok((cols[k].to_string(), parse(k)?)))
                .collect::<Result<Vec<_>, EvalInputError>>()?;
            check_copies(&given, &x, &u).map_err(|(name, reason)| {
                err(format!("line {}, column '{name}'", ln + 1), reason)
            })?;
            out.push((x, u));
        }
        if out.is_empty() {
            return Err(err(
                "rows".into(),
                "no evaluations: the file has a header but no rows".into(),
            ));
        }
        return Ok(out);
    }
    let ext = |want: &str| {
        path.extension()
            .is_some_and(|x| x.eq_ignore_ascii_case(want))
    };
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| {
        err(
            format!("line {}, column {}", e.line(), e.column()),
            if ext("json") {
                crate::model::json_error_text(text, &e)
            } else if ext("sto") || ext("mot") {
                format!("{e} (read as JSON: a storage file is not an input of `leap eval`, which takes one state as JSON or rows as CSV; `leap analyze` reads a states .sto)")
            } else {
                format!("{e} (read as JSON: only a file whose name ends in .csv is read as CSV)")
            },
        )
    })?;
    if let Some((at, key)) = crate::model::duplicate_key(text) {
        return Err(err(
            at,
            format!("key '{key}' given twice; a key may appear once in an object"),
        ));
    }
    let items: Vec<&serde_json::Value> = match &v {
        serde_json::Value::Array(a) => a.iter().collect(),
        other => vec![other],
    };
    for (i, item) in items.iter().enumerate() {
        let place = |f: &str| {
            if items.len() > 1 {
                format!("[{i}].{f}")
            } else {
                f.to_string()
            }
        };
        if !item.is_object() {
            return Err(err(
                place("(evaluation)"),
                format!("expected an object with 'state' (or 'x') and 'excitation' (or 'u'), got {item}"),
            ));
        }
        // `leap squat` prints its squat's residuals beside the state; they
        // are not read. Any other key is a mistake (a misspelt 'state').
        const SQUAT_KEYS: [&str; 3] = ["max_abs_qdd", "qp_iterations", "vertical_grf_bw"];
        if let Some(k) = item
            .as_object()
            .into_iter()
            .flatten()
            .map(|(k, _)| k)
            .find(|k| {
                !["state", "x", "excitation", "u"].contains(&k.as_str())
                    && !SQUAT_KEYS.contains(&k.as_str())
            })
        {
            return Err(err(
                place(k),
                format!(
                    "unknown key: an evaluation has 'state' (or 'x') and 'excitation' (or 'u'), and may keep {} from `leap squat`, which are not read",
                    SQUAT_KEYS.join(", ")
                ),
            ));
        }
        let mut given = Vec::new();
        let mut vector = |key: &str,
                          named: &str,
                          names: &[String],
                          other_names: &[String],
                          copies: &[(String, usize)]|
         -> Result<Vec<f64>, EvalInputError> {
            if let Some(arr) = item.get(key) {
                if item.get(named).is_some() {
                    return Err(err(
                        place(key),
                        format!("given together with '{named}': give one of them"),
                    ));
                }
                let arr = arr
                    .as_array()
                    .ok_or_else(|| err(place(key), "must be an array of numbers".into()))?;
                if arr.len() != names.len() {
                    let reason = format!("{} values, expected {}", arr.len(), names.len());
                    return Err(if arr.len() < names.len() {
                        lacks(place(key), reason)
                    } else {
                        err(place(key), reason)
                    });
                }
                return arr
                    .iter()
                    .enumerate()
                    .map(|(k, v)| {
                        v.as_f64().filter(|v| v.is_finite()).ok_or_else(|| {
                            err(place(&format!("{key}[{k}]")), "not a finite number".into())
                        })
                    })
                    .collect();
            }
            let obj = item.get(named).and_then(|o| o.as_object()).ok_or_else(|| {
                err(
                    place(named),
                    format!("missing: give '{named}' (by name) or '{key}' (array)"),
                )
            })?;
            for (k, v) in obj {
                if is_copy(k, copies) {
                    let v = v.as_f64().filter(|v| v.is_finite()).ok_or_else(|| {
                        err(place(&format!("{named}.{k}")), "not a finite number".into())
                    })?;
                    given.push((k.clone(), v));
                } else if !names.contains(k) {
                    return Err(err(
                        place(&format!("{named}.{k}")),
                        format!(
                            "unknown name: {}",
                            unknown_name_reason(k, &pre_4, &angular, Some((named, other_names)))
                        ),
                    ));
                }
            }
            names
                .iter()
                .map(|n| {
                    obj.get(n)
                        .ok_or_else(|| lacks(place(named), format!("missing '{n}'")))
                        .and_then(|v| {
                            v.as_f64().filter(|v| v.is_finite()).ok_or_else(|| {
                                err(place(&format!("{named}.{n}")), "not a finite number".into())
                            })
                        })
                })
                .collect()
        };
        let x = vector("x", "state", &states, &controls, &state_copies)?;
        let u = vector("u", "excitation", &controls, &states, &control_copies)?;
        check_ranges(&states, &controls, &x, &u)
            .map_err(|(name, reason)| err(place(&name), reason))?;
        check_copies(&given, &x, &u).map_err(|(name, reason)| err(place(&name), reason))?;
        out.push((x, u));
    }
    if out.is_empty() {
        return Err(err(
            "(file)".into(),
            "no evaluations: an empty array".into(),
        ));
    }
    Ok(out)
}

/// Why `name` is not one of the system's state or control names, with what
/// was probably meant: the OpenSim 4 path of a pre-4.0 name (`soleus_r`,
/// `knee_angle_r_u`, `<muscle>.activation`), in radians where `angular`
/// (the rotational coordinates' columns) holds it; in the JSON form
/// (`other`: the key it was given under, "state" or "excitation", and the
/// other kind's names) a name of the other kind.
fn unknown_name_reason(
    name: &str,
    pre_4: &std::collections::HashMap<String, String>,
    angular: &std::collections::HashSet<String>,
    other: Option<(&str, &[String])>,
) -> String {
    let path = pre_4.get(name).map(String::as_str).unwrap_or(name);
    if let Some((under, _)) = other.filter(|(_, names)| names.iter().any(|n| n == path)) {
        let (what, goes) = if under == "state" {
            ("an excitation", "excitation")
        } else {
            ("a state", "state")
        };
        return format!("'{path}' is {what}: it goes under '{goes}'");
    }
    if path != name {
        let units = if !angular.contains(path) {
            ""
        } else if path.ends_with("/speed") {
            ", in rad/s"
        } else {
            ", in radians"
        };
        return format!(
            "a pre-4.0 name; leap eval reads OpenSim 4's state and control paths: '{path}'{units}"
        );
    }
    "not a state or excitation of this model's system (`leap squat` prints the names)".into()
}

/// The physical range of the inputs: activations (to 1e-6) and excitations
/// in [0, 1], fibre lengths positive. (name, reason) of the first outside it.
fn check_ranges(
    states: &[String],
    controls: &[String],
    x: &[f64],
    u: &[f64],
) -> Result<(), (String, String)> {
    for (name, &v) in states.iter().zip(x) {
        if let Some(reason) = crate::io::muscle_state_out_of_range(name, v) {
            return Err((name.clone(), reason));
        }
    }
    for (name, &v) in controls.iter().zip(u) {
        if !(0.0..=1.0).contains(&v) {
            return Err((
                name.clone(),
                format!(
                    "an excitation must be in [0, 1], got {}",
                    crate::io::readable(v)
                ),
            ));
        }
    }
    Ok(())
}

/// Evaluate ẋ = f(x, u) and its parts.
pub fn evaluate(
    eq: &StateEquation,
    laws: &OpenSimLaws,
    x: &[f64],
    u: &[f64],
) -> Result<EvalReport, crate::ode::OdeError> {
    let (n, nm) = (eq.nq(), eq.nm());
    let mut ws = eq.workspace::<f64>();
    let mut xdot = vec![0.0; eq.nx()];
    const DEGREES: &str = "the input in degrees? leap eval reads coordinates in radians";
    eq.rhs(laws, &mut ws, x, u, &mut xdot)
        .map_err(|e| match e {
            // A coordinate far outside its range (a knee at 1e10 rad) breaks
            // the mass matrix before any force: named, not the masses.
            crate::ode::OdeError::Singular(source) => {
                let why = outside_range_hint(eq, x, DEGREES);
                if why.is_empty() {
                    crate::ode::OdeError::Singular(source)
                } else {
                    crate::ode::OdeError::SingularAt {
                        mass_matrix: source,
                        why,
                    }
                }
            }
            e => e,
        })?;
    let names = eq.state_names();
    if let Some(k) = xdot.iter().position(|v| !v.is_finite()) {
        return Err(crate::ode::OdeError::NotFinite {
            state: names[k].clone(),
            value: xdot[k],
            why: outside_range_hint(eq, x, DEGREES),
        });
    }
    let model = &eq.model;
    let coord_name = |k: usize| model.coordinates[eq.system.coordinates[k]].name.clone();
    let mut warnings: Vec<String> = coordinates_outside_range(eq, x)
        .into_iter()
        .map(|(_, w)| w)
        .collect();
    let mut muscles = BTreeMap::new();
    let mbw = &ws.mb;
    for (k, &mi) in eq.muscles.iter().enumerate() {
        let m = &model.muscles[mi];
        let mut tau = vec![0.0; n];
        {
            let view = ModelView {
                mb: &eq.multibody,
                ws: mbw,
                q_of: &eq.system.q_of_model_coordinate,
            };
            let mut sink = GeneralizedForces {
                mb: &eq.multibody,
                ws: mbw,
                q_of: &eq.system.q_of_model_coordinate,
                tau: &mut tau,
            };
            m.path.calc(&view, eq.smoothing, Some((1.0, &mut sink)));
        }
        let info = laws.muscles[mi].calc(
            x[2 * n + nm + k],
            x[2 * n + k],
            ws.mtu_length[k],
            ws.mtu_speed[k],
            u[k],
        );
        muscles.insert(
            m.spec.name.clone(),
            MuscleReport {
                length: ws.mtu_length[k],
                lengthening_speed: ws.mtu_speed[k],
                moment_arms: (0..n)
                    .filter(|&j| tau[j].abs() > 1e-12)
                    .map(|j| (coord_name(j), tau[j]))
                    .collect(),
                fiber_length: info.fiber_length,
                fiber_velocity: info.fiber_velocity,
                pennation_angle: info.pennation_angle,
                tendon_length: info.tendon_length,
                tendon_force: info.tendon_force,
                active_fiber_force: info.active_fiber_force,
                passive_fiber_force: info.passive_fiber_force,
                activation_rate: info.activation_rate,
            },
        );
    }
    warnings.extend(
        unusual_fibre_lengths(eq, laws, x, true)
            .into_iter()
            .map(|(_, w)| w),
    );
    warnings.extend(crate::analyze::sunk_sphere_warning(eq, &ws));
    let contact_forces = match &model.contact {
        Some(c) => c
            .spheres
            .iter()
            .zip(&ws.sphere_force)
            .map(|(s, f)| (s.name.clone(), *f))
            .collect(),
        None => BTreeMap::new(),
    };
    let ligament_torques = model
        .ligaments
        .iter()
        .zip(&ws.ligament_torque)
        .map(|(l, t)| (model.coordinates[l.coordinate].name.clone(), *t))
        .collect();
    Ok(EvalReport {
        state_derivative: names.iter().cloned().zip(xdot.iter().copied()).collect(),
        accelerations: (0..n).map(|k| (coord_name(k), xdot[n + k])).collect(),
        muscles,
        contact_forces,
        ligament_torques,
        com_position: eq.multibody.com_position(mbw),
        com_velocity: eq.multibody.com_velocity(mbw),
        warnings,
    })
}

/// A length jump of an exact (OpenSim) path where a conditional point
/// switches, which the smooth option removes.
#[derive(Debug, Clone, Serialize)]
pub struct SwitchJump {
    pub muscle: String,
    /// Path point number (1-based, as in OpenSim's P1, P2, ...).
    pub point: usize,
    /// The path point's name in leap's `.osim` files (`scripts/jumper_osim.py`
    /// names them as gait2392 does): `iliacus_r-P3` for point 3.
    pub path_point: String,
    pub coordinate: String,
    /// Coordinate value where the point switches (rad).
    pub at: f64,
    /// L(point on) − L(point off) at the switch (m).
    pub jump_m: f64,
}

/// Every switch of every carried muscle's conditional points inside the
/// coordinate ranges, with the other coordinates at `pose` (model values).
pub fn switch_jumps(eq: &StateEquation, pose: &[f64]) -> Vec<SwitchJump> {
    let model = &eq.model;
    let mut out = Vec::new();
    let mut ws = eq.multibody.workspace::<f64>();
    for &mi in &eq.muscles {
        let m = &model.muscles[mi];
        for (j, (pi, coord, range)) in m.path.conditional_points().into_iter().enumerate() {
            let [lo, hi] = model.coordinates[coord].range;
            for edge in range {
                if edge < lo || edge > hi {
                    continue;
                }
                let mut mq = pose.to_vec();
                mq[coord] = edge;
                let q = eq.system.q_from_model(&mq);
                eq.multibody.set_state(&mut ws, &q, &vec![0.0; q.len()]);
                let view = ModelView {
                    mb: &eq.multibody,
                    ws: &ws,
                    q_of: &eq.system.q_of_model_coordinate,
                };
                let on: f64 = m.path.length_with(&view, j, true);
                let off: f64 = m.path.length_with(&view, j, false);
                out.push(SwitchJump {
                    muscle: m.spec.name.clone(),
                    point: pi + 1,
                    path_point: format!("{}-P{}", m.spec.name, pi + 1),
                    coordinate: model.coordinates[coord].name.clone(),
                    at: edge,
                    jump_m: on - off,
                });
            }
        }
    }
    out
}

/// Why a state `x` may give non-finite forces: ": " and its coordinates
/// outside their ranges ([`coordinates_outside_range`]), with `degrees`
/// (where the input says it is in radians) where every rotational one of
/// them would lie in its range in radians; empty if none is outside.
pub(crate) fn outside_range_hint(eq: &StateEquation, x: &[f64], degrees: &str) -> String {
    let outside = coordinates_outside_range(eq, x);
    if outside.is_empty() {
        return String::new();
    }
    let rotational = crate::io::rotational_coordinates(eq);
    let in_degrees = outside.iter().all(|&(k, _)| {
        let [lo, hi] = eq.model.coordinates[eq.system.coordinates[k]].range;
        rotational.contains(&k) && (lo..=hi).contains(&x[k].to_radians())
    });
    let list: Vec<String> = outside.into_iter().map(|(_, w)| w).collect();
    format!(
        ": {}{}",
        list.join("; "),
        if in_degrees {
            format!(" (in radians it would lie in its range: {degrees})")
        } else {
            String::new()
        }
    )
}

/// The carried muscles of state `x` whose fibre length is unusual: (muscle
/// index in `eq.muscles`, why) of each. Shorter than the Thelen2003Muscle
/// law's minimum length, where the law holds it, as OpenSim's does (the
/// tendon then takes the rest of the muscle's length: a force far beyond
/// F0); or outside [0.2, 2] optimal fibre lengths, the optimizer's
/// `fiber_length_bounds`, far from where force–length curves are measured
/// (an unpennated muscle's minimum length is 0, as in OpenSim). Without
/// `clamp`, the first only where it is the second too (a fast push-off
/// meets a pennated fibre's minimum length: `leap simulate`'s soleus).
pub(crate) fn unusual_fibre_lengths(
    eq: &StateEquation,
    laws: &OpenSimLaws,
    x: &[f64],
    clamp: bool,
) -> Vec<(usize, String)> {
    let n = eq.nq();
    let [lo, hi] = crate::ocp::DEFAULT_FIBER_LENGTH_BOUNDS;
    // (muscle, l_M, l_opt, the law's minimum where below it, outside).
    let found: Vec<(usize, f64, f64, Option<f64>, bool)> = eq
        .muscles
        .iter()
        .enumerate()
        .filter_map(|(k, &mi)| {
            let lm = x[2 * n + k];
            let lopt = eq.model.muscles[mi].spec.optimal_fiber_length;
            let below_min = match &laws.muscles[mi] {
                crate::laws::MuscleLaw::Thelen(t) if lm < t.min_fiber_length => {
                    Some(t.min_fiber_length)
                }
                _ => None,
            };
            let outside = !(lo * lopt..=hi * lopt).contains(&lm);
            ((clamp && below_min.is_some()) || outside).then_some((k, lm, lopt, below_min, outside))
        })
        .collect();
    if found.is_empty() {
        // The usual row (`leap analyze` checks every one): no names built.
        return Vec::new();
    }
    let names = eq.state_names();
    found
        .into_iter()
        .map(|(k, lm, lopt, below_min, outside)| {
            let mut why = format!(
                "{} = {} m is {} optimal fibre lengths",
                names[2 * n + k],
                crate::io::readable(lm),
                crate::io::readable(lm / lopt)
            );
            if outside {
                why += &format!(", outside [{lo}, {hi}] (the optimizer's fiber_length_bounds), far from where force–length curves are measured");
            }
            if let Some(min) = below_min {
                why += &format!(
                    "{}below the minimum fibre length {} m: the law holds the fibre there, as OpenSim's Thelen2003Muscle does, and the tendon takes the rest of the muscle's length",
                    if outside { "; and " } else { ", " },
                    crate::io::readable(min)
                );
            }
            (k, why)
        })
        .collect()
}

/// The coordinates of state `x` outside their ranges in the model file
/// (where no motion of the model goes): (index, "name = value unit lies
/// outside its range [lo, hi] unit") of each.
pub(crate) fn coordinates_outside_range(eq: &StateEquation, x: &[f64]) -> Vec<(usize, String)> {
    let model = &eq.model;
    let outside: Vec<usize> = (0..eq.nq())
        .filter(|&k| {
            let [lo, hi] = model.coordinates[eq.system.coordinates[k]].range;
            !(lo..=hi).contains(&x[k])
        })
        .collect();
    if outside.is_empty() {
        // The usual row (`leap analyze` checks every one): no names built.
        return Vec::new();
    }
    let names = eq.state_names();
    let rotational = crate::io::rotational_coordinates(eq);
    outside
        .into_iter()
        .map(|k| {
            let [lo, hi] = model.coordinates[eq.system.coordinates[k]].range;
            let unit = if rotational.contains(&k) { "rad" } else { "m" };
            (
                k,
                format!(
                    "{} = {} {unit} lies outside its range [{}, {}] {unit}",
                    names[k],
                    crate::io::readable(x[k]),
                    crate::io::readable(lo),
                    crate::io::readable(hi)
                ),
            )
        })
        .collect()
}
