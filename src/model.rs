//! Model files: the skeleton of a planar musculoskeletal model, read from JSON
//! and validated once.
//!
//! A model file describes bodies, joints, coordinates and named stations the
//! way OpenSim does (both legs, every segment; SI units, radians, OpenSim's
//! frame conventions: x anterior, y superior, z to the right). Every error
//! names the file, the JSON path of the offending field and the reason.
//!
//! The engine does not use the file's joints directly: [`Model::system`]
//! turns them into a [`SystemSpec`], the list of mobilized bodies that both
//! backends (Simbody and the Rust-native [`crate::multibody`]) build. With
//! `symmetric = true` each left-side coordinate follows its right-side partner
//! and the left leg's bodies are welded onto the right leg's (they overlap in
//! the sagittal plane, offset along z only), which gives the paper's
//! 7-coordinate system.

use crate::spline::{SimmSpline, SplineData};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// Standard gravity (m/s²), as Simbody and OpenSim use it.
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// A model file as written (serde's view; see [`Model`] for the validated form).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    pub name: String,
    /// Where the data come from and under which licence.
    #[serde(default)]
    pub credits: Vec<String>,
    /// Gravity in ground (m/s²); with foot-ground contact it must point
    /// down, `[0, -g, 0]`.
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    pub bodies: Vec<BodySpec>,
    pub joints: Vec<JointSpec>,
    pub coordinates: Vec<CoordinateSpec>,
    #[serde(default)]
    pub stations: Vec<StationSpec>,
    /// Right/left coordinate pairs that the symmetric system couples. With
    /// pairs, every muscle named `<stem>_r` needs its `<stem>_l` with equal
    /// parameters (the symmetric system carries both by the right one).
    #[serde(default)]
    pub symmetry: Vec<[String; 2]>,
    /// Named poses: coordinate values (rad or m); missing coordinates take
    /// their `default_value`. A `squat` pose makes the model a jump model
    /// (`leap squat`, `solve` and `simulate` start from it): it then needs
    /// muscles and foot-ground contact.
    #[serde(default)]
    pub poses: BTreeMap<String, BTreeMap<String, f64>>,
    /// Muscles, passive joint torques and foot-ground contact.
    #[serde(default)]
    pub forces: ForcesSpec,
}

/// The force elements of a model file.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForcesSpec {
    /// Muscle law for every muscle: `Thelen2003Muscle` (default) or
    /// `DeGrooteFregly2016Muscle`.
    #[serde(default)]
    pub muscle_model: MuscleModel,
    #[serde(default)]
    pub muscles: Vec<MuscleSpec>,
    #[serde(default)]
    pub ligaments: Vec<LigamentSpec>,
    #[serde(default)]
    pub contact: Option<ContactSpec>,
}

/// The muscle law.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum MuscleModel {
    #[default]
    Thelen2003Muscle,
    DeGrooteFregly2016Muscle,
}

/// A Hill-type muscle-tendon unit with OpenSim's property names and units
/// (N, m, s, rad; `max_contraction_velocity` in optimal fibre lengths per
/// second). Thelen 2003 curve constants keep OpenSim's capitalisation.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
pub struct MuscleSpec {
    pub name: String,
    pub max_isometric_force: f64,
    pub optimal_fiber_length: f64,
    pub tendon_slack_length: f64,
    pub pennation_angle_at_optimal: f64,
    #[serde(default = "d_vmax")]
    pub max_contraction_velocity: f64,
    #[serde(default = "d_tau_act")]
    pub activation_time_constant: f64,
    #[serde(default = "d_tau_deact")]
    pub deactivation_time_constant: f64,
    #[serde(default = "d_tendon_strain")]
    pub FmaxTendonStrain: f64,
    #[serde(default = "d_muscle_strain")]
    pub FmaxMuscleStrain: f64,
    #[serde(default = "d_kshape_active")]
    pub KshapeActive: f64,
    #[serde(default = "d_kshape_passive")]
    pub KshapePassive: f64,
    #[serde(default = "d_af")]
    pub Af: f64,
    #[serde(default = "d_flen")]
    pub Flen: f64,
    pub path: Vec<crate::path::PathPointSpec>,
}

// The legacy OpenSim 3.x values every gait2392 muscle carries (model-data.md §7.2).
fn d_vmax() -> f64 {
    10.0
}
fn d_tau_act() -> f64 {
    0.01
}
fn d_tau_deact() -> f64 {
    0.04
}
fn d_tendon_strain() -> f64 {
    0.033
}
fn d_muscle_strain() -> f64 {
    0.6
}
fn d_kshape_active() -> f64 {
    0.5
}
fn d_kshape_passive() -> f64 {
    4.0
}
fn d_af() -> f64 {
    0.3
}
fn d_flen() -> f64 {
    1.8
}

/// A passive joint torque on one coordinate, the Anderson & Pandy (1999)
/// exponential form with linear damping (model-equations.md §5.3):
/// `T = k1·exp(k2·(q − θ2)) + k3·exp(k4·(q − θ1)) − damping·q̇` (N·m).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LigamentSpec {
    pub coordinate: String,
    pub k1: f64,
    pub k2: f64,
    pub k3: f64,
    pub k4: f64,
    pub theta1: f64,
    pub theta2: f64,
    pub damping: f64,
}

/// The contact law between spheres and the ground half-space (normal +y).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ContactLaw {
    /// OpenSim `HuntCrossleyForce` (Simbody's Hertz + Hunt-Crossley with
    /// Stribeck-like friction).
    HuntCrossleyForce,
    /// OpenSim `SmoothSphereHalfSpaceForce` (smooth approximation).
    SmoothSphereHalfSpaceForce,
}

/// Foot-ground contact: one law and parameter set for every sphere.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    pub law: ContactLaw,
    /// Stiffness E (Pa = N/m²) of both surfaces.
    pub stiffness: f64,
    /// Hunt-Crossley dissipation c (s/m).
    pub dissipation: f64,
    pub static_friction: f64,
    pub dynamic_friction: f64,
    /// Viscous friction coefficient (s/m).
    pub viscous_friction: f64,
    /// Transition velocity (m/s).
    pub transition_velocity: f64,
    /// Smoothing constants of the smooth law (OpenSim defaults when absent).
    #[serde(default)]
    pub hertz_smoothing: Option<f64>,
    #[serde(default)]
    pub hunt_crossley_smoothing: Option<f64>,
    #[serde(default)]
    pub derivative_smoothing: Option<f64>,
    /// At least one, with distinct names.
    pub spheres: Vec<SphereSpec>,
}

/// A contact sphere fixed on a body.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    pub name: String,
    pub body: String,
    /// Centre in the body frame (m).
    pub location: [f64; 3],
    /// Radius (m).
    pub radius: f64,
}

fn default_gravity() -> [f64; 3] {
    [0.0, -STANDARD_GRAVITY, 0.0]
}

/// A rigid body: mass (kg), centre of mass in the body frame (m) and the
/// inertia about the centre of mass in body axes (kg·m²), in OpenSim's order
/// `[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    pub name: String,
    pub mass: f64,
    pub mass_center: [f64; 3],
    pub inertia: [f64; 6],
}

/// A joint between a parent body (or `ground`) and a child body. The child
/// frame's origin sits at `location_in_parent` (plus the joint's
/// translations) in the parent frame; frames carry no fixed rotation.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", try_from = "JointFields")]
pub enum JointSpec {
    /// Planar base: rotation about z, then translation along ground x and y.
    /// `coordinates` = [rotation, x translation, y translation].
    Planar {
        name: String,
        parent: String,
        child: String,
        location_in_parent: [f64; 3],
        coordinates: [String; 3],
    },
    /// Hinge about z.
    Pin {
        name: String,
        parent: String,
        child: String,
        location_in_parent: [f64; 3],
        coordinate: String,
    },
    /// Hinge about z whose child origin translates along the parent's x and y
    /// as `SimmSpline` functions of the hinge angle (OpenSim's knee
    /// CustomJoint: translation1, translation2).
    TranslatingHinge {
        name: String,
        parent: String,
        child: String,
        location_in_parent: [f64; 3],
        coordinate: String,
        translation_x: SplineData,
        translation_y: SplineData,
    },
    /// No relative motion (OpenSim WeldJoint, or a locked joint at 0).
    Weld {
        name: String,
        parent: String,
        child: String,
        location_in_parent: [f64; 3],
    },
}

/// A joint as a file gives it: the fields of every joint type, each read
/// with its own JSON path (serde's internally tagged enums lose the path of
/// an error inside a variant), then checked against the joint's `type`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JointFields {
    #[serde(rename = "type")]
    kind: JointType,
    name: String,
    parent: String,
    child: String,
    location_in_parent: [f64; 3],
    #[serde(default, deserialize_with = "crate::model::present")]
    coordinates: Option<[String; 3]>,
    #[serde(default, deserialize_with = "crate::model::present")]
    coordinate: Option<String>,
    #[serde(default, deserialize_with = "crate::model::present")]
    translation_x: Option<SplineData>,
    #[serde(default, deserialize_with = "crate::model::present")]
    translation_y: Option<SplineData>,
}

/// Read from a string only: serde's enums also take `{"planar": null}`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(try_from = "String")]
enum JointType {
    Planar,
    Pin,
    TranslatingHinge,
    Weld,
}

const JOINT_TYPES: [(&str, JointType); 4] = [
    ("planar", JointType::Planar),
    ("pin", JointType::Pin),
    ("translating_hinge", JointType::TranslatingHinge),
    ("weld", JointType::Weld),
];

impl TryFrom<String> for JointType {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        variant_named(&s, &JOINT_TYPES)
    }
}

/// The fields every joint has.
const JOINT_COMMON_FIELDS: [&str; 5] = ["type", "name", "parent", "child", "location_in_parent"];

impl JointType {
    /// The fields a joint of this type has besides the common ones.
    fn fields(self) -> &'static [&'static str] {
        match self {
            JointType::Planar => &["coordinates"],
            JointType::Pin => &["coordinate"],
            JointType::TranslatingHinge => &["coordinate", "translation_x", "translation_y"],
            JointType::Weld => &[],
        }
    }
}

impl TryFrom<JointFields> for JointSpec {
    type Error = String;
    fn try_from(j: JointFields) -> Result<Self, String> {
        let kind = variant_name(j.kind, &JOINT_TYPES);
        crate::model::variant_fields(
            &format!("a {kind} joint"),
            &JOINT_COMMON_FIELDS,
            j.kind.fields(),
            &[
                ("coordinates", j.coordinates.is_some()),
                ("coordinate", j.coordinate.is_some()),
                ("translation_x", j.translation_x.is_some()),
                ("translation_y", j.translation_y.is_some()),
            ],
        )?;
        let (name, parent, child, location_in_parent) =
            (j.name, j.parent, j.child, j.location_in_parent);
        // `variant_fields` has checked that each field taken is given.
        let missing = || format!("a {kind} joint misses a field");
        Ok(match j.kind {
            JointType::Planar => JointSpec::Planar {
                name,
                parent,
                child,
                location_in_parent,
                coordinates: j.coordinates.ok_or_else(missing)?,
            },
            JointType::Pin => JointSpec::Pin {
                name,
                parent,
                child,
                location_in_parent,
                coordinate: j.coordinate.ok_or_else(missing)?,
            },
            JointType::TranslatingHinge => JointSpec::TranslatingHinge {
                name,
                parent,
                child,
                location_in_parent,
                coordinate: j.coordinate.ok_or_else(missing)?,
                translation_x: j.translation_x.ok_or_else(missing)?,
                translation_y: j.translation_y.ok_or_else(missing)?,
            },
            JointType::Weld => JointSpec::Weld {
                name,
                parent,
                child,
                location_in_parent,
            },
        })
    }
}

impl JointSpec {
    fn common(&self) -> (&str, &str, &str, &[f64; 3]) {
        match self {
            JointSpec::Planar {
                name,
                parent,
                child,
                location_in_parent,
                ..
            }
            | JointSpec::Pin {
                name,
                parent,
                child,
                location_in_parent,
                ..
            }
            | JointSpec::TranslatingHinge {
                name,
                parent,
                child,
                location_in_parent,
                ..
            }
            | JointSpec::Weld {
                name,
                parent,
                child,
                location_in_parent,
            } => (name, parent, child, location_in_parent),
        }
    }
}

/// A generalized coordinate: `range` = [min, max] and `default_value`, in rad
/// for rotations and m for translations.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoordinateSpec {
    pub name: String,
    pub range: [f64; 2],
    #[serde(default)]
    pub default_value: f64,
}

/// A named point fixed on a body (m, body frame).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StationSpec {
    pub name: String,
    pub body: String,
    pub location: [f64; 3],
}

/// A model file could not be used. `path` is the JSON path of the field.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error("{file}: cannot read: {error}")]
    Io {
        file: PathBuf,
        error: std::io::Error,
    },
    #[error("{file}: {path}: {reason}")]
    Parse {
        file: PathBuf,
        path: String,
        reason: String,
    },
    #[error("{file}: {path}: {reason}")]
    Invalid {
        file: PathBuf,
        path: String,
        reason: String,
    },
}

impl ModelError {
    /// The JSON path of the field at fault (empty for I/O errors).
    pub fn field(&self) -> &str {
        match self {
            ModelError::Io { .. } => "",
            ModelError::Parse { path, .. } | ModelError::Invalid { path, .. } => path,
        }
    }
}

/// A validated body.
#[derive(Debug, Clone)]
pub struct Body {
    pub name: String,
    pub mass: f64,
    pub mass_center: [f64; 3],
    pub inertia: [f64; 6],
}

/// What a validated joint does.
#[derive(Debug, Clone)]
pub enum JointKind {
    Planar {
        coordinates: [usize; 3],
    },
    Pin {
        coordinate: usize,
    },
    TranslatingHinge {
        coordinate: usize,
        translation_x: SimmSpline,
        translation_y: SimmSpline,
    },
    Weld,
}

/// A validated joint; `parent == None` is ground.
#[derive(Debug, Clone)]
pub struct Joint {
    pub name: String,
    pub parent: Option<usize>,
    pub child: usize,
    pub location_in_parent: [f64; 3],
    pub kind: JointKind,
}

/// A validated coordinate.
#[derive(Debug, Clone)]
pub struct Coordinate {
    pub name: String,
    pub range: [f64; 2],
    pub default_value: f64,
}

/// A validated station.
#[derive(Debug, Clone)]
pub struct Station {
    pub name: String,
    pub body: usize,
    pub location: [f64; 3],
}

/// A validated model: the immutable description every backend builds from.
#[derive(Debug, Clone)]
pub struct Model {
    pub file: PathBuf,
    pub name: String,
    pub credits: Vec<String>,
    pub gravity: [f64; 3],
    pub bodies: Vec<Body>,
    pub joints: Vec<Joint>,
    pub coordinates: Vec<Coordinate>,
    pub stations: Vec<Station>,
    /// (right, left) coordinate index pairs.
    pub symmetry: Vec<(usize, usize)>,
    pub poses: BTreeMap<String, Vec<f64>>,
    pub muscle_model: MuscleModel,
    pub muscles: Vec<Muscle>,
    pub ligaments: Vec<Ligament>,
    pub contact: Option<Contact>,
}

/// A validated muscle: its parameters as written and its path.
#[derive(Debug, Clone)]
pub struct Muscle {
    pub spec: MuscleSpec,
    pub path: crate::path::GeometryPath,
}

/// A validated passive joint torque.
#[derive(Debug, Clone)]
pub struct Ligament {
    pub coordinate: usize,
    pub spec: LigamentSpec,
}

/// A validated contact sphere.
#[derive(Debug, Clone)]
pub struct Sphere {
    pub name: String,
    pub body: usize,
    pub location: [f64; 3],
    pub radius: f64,
}

/// Validated foot-ground contact.
#[derive(Debug, Clone)]
pub struct Contact {
    pub spec: ContactSpec,
    pub spheres: Vec<Sphere>,
}

/// Why a JSON file could not be read into a settings struct: the JSON
/// path of the field ("(document)" for the whole file) and the reason.
#[derive(Debug, Clone, PartialEq)]
pub struct JsonError {
    pub path: String,
    pub reason: String,
}

/// Parse `text` as exactly one JSON object into `T` (a model, `leap solve`
/// or `leap simulate` study file). Besides serde's errors (with the JSON
/// path of the field), refuse what serde would accept: a top-level array,
/// which fills a struct's fields by position, and anything after the
/// object (a second object, stray text), which serde leaves unread.
pub fn parse_json_object<T: serde::de::DeserializeOwned + Serialize>(
    text: &str,
) -> Result<T, JsonError> {
    // A byte-order mark, as some Windows editors write, is no content.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let document = |reason: String| JsonError {
        path: "(document)".into(),
        reason,
    };
    match text.trim_start().chars().next() {
        Some('{') => {}
        None => return Err(document("empty; expected a JSON object".into())),
        // An OpenSim model or setup file (.osim, XML) is the file a user
        // has at hand.
        Some('<') => {
            return Err(document(
                "an XML file (an OpenSim .osim model or setup file?): leap reads its own JSON files, such as models/jumper.json and the studies models/jump_*.json (models/jumper.osim is written from models/jumper.json, for OpenSim)".into(),
            ))
        }
        // A states, controls or ground forces table, the other files a
        // solve leaves beside the study.
        Some(_) if text.lines().take(1000).any(|l| l.trim() == "endheader") => {
            return Err(document(
                "an OpenSim storage file (.sto or .mot: a table of states, controls or forces), not a model or study: leap reads its own JSON files, such as models/jumper.json and the studies models/jump_*.json".into(),
            ))
        }
        Some(_) => {
            // Say what the document is when it is JSON, else where it is not.
            let reason = match serde_json::from_str::<serde_json::Value>(text) {
                Ok(v) => format!("expected a JSON object, got {}", json_kind(&v)),
                Err(e) => format!("expected a JSON object: {}", json_error_text(text, &e)),
            };
            return Err(document(reason));
        }
    }
    // serde keeps the last key of a map (a pose's coordinate) without a
    // word; a struct's field given twice is refused here too, as a key.
    if let Some((path, key)) = duplicate_key(text) {
        return Err(JsonError {
            path,
            reason: format!("key '{key}' given twice; a key may appear once in an object"),
        });
    }
    let mut de = serde_json::Deserializer::from_str(text);
    let value = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        let whole = path == "." || path == "?";
        // serde_json says "trailing characters" of an array longer than a
        // fixed-size field ([x, y, z]) takes.
        let reason = if !whole && inner.to_string().starts_with("trailing characters") {
            format!(
                "more elements than this field takes, at line {} column {}",
                inner.line(),
                inner.column()
            )
        } else if inner.to_string().starts_with("duplicate field") {
            // Each key is given once (`duplicate_key`): this is a field
            // given under two of its names (an alias), which serde names by
            // its own name only.
            let text = inner.to_string();
            let (what, at) = text.split_at(text.rfind(" at line ").unwrap_or(text.len()));
            format!("{what}, under two of its names; give it once{at}")
        } else {
            // serde names the Rust type a section deserializes into
            // ("expected struct MeshSpec"), which the user never wrote.
            // Only where a value of another type stands for a section
            // ("invalid type: null, expected struct MeshSpec at line 1").
            let msg = json_error_text(text, &inner);
            if let Some(reason) = whole_number_reason(&msg) {
                reason
            } else {
                match msg.split_once("expected struct ") {
                    Some((before, after)) if msg.starts_with("invalid type") => {
                        match after.split_once(' ') {
                            Some((_, rest)) => format!("{before}expected a JSON object {rest}"),
                            None => format!("{before}expected a JSON object"),
                        }
                    }
                    _ => msg,
                }
            }
        };
        JsonError {
            path: if whole { "(document)".into() } else { path },
            reason,
        }
    })?;
    de.end().map_err(|e| document(e.to_string()))?;
    // serde fills a struct's fields by position from an array too
    // (`"mesh": [28, "trapezoidal"]`): where the parsed value is an object
    // and the text held an array, refuse it.
    if let (Ok(given), Ok(parsed)) = (
        serde_json::from_str::<serde_json::Value>(text),
        serde_json::to_value(&value),
    ) {
        if let Some(path) = array_for_object(&given, &parsed, String::new()) {
            return Err(JsonError {
                path,
                reason: "expected an object with named fields, got an array (fields are not read by position)".into(),
            });
        }
    }
    Ok(value)
}

/// The first key given twice in one object of the JSON document `text`:
/// (the JSON path of the object, as serde_path_to_error writes it, or
/// `(document)`; the key). serde_json keeps the last of them in a map (a
/// pose, an evaluation's states) without a word. None also when `text` is
/// not JSON (its parser says why).
pub fn duplicate_key(text: &str) -> Option<(String, String)> {
    use serde::de::{DeserializeSeed, MapAccess, SeqAccess, Visitor};
    use std::cell::RefCell;
    struct Walk<'a> {
        path: String,
        found: &'a RefCell<Option<(String, String)>>,
    }
    impl Walk<'_> {
        fn at(&self, path: String) -> Self {
            Walk {
                path,
                found: self.found,
            }
        }
    }
    impl<'de> DeserializeSeed<'de> for Walk<'_> {
        type Value = ();
        fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
            d.deserialize_any(self)
        }
    }
    impl<'de> Visitor<'de> for Walk<'_> {
        type Value = ();
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("any JSON value")
        }
        fn visit_bool<E>(self, _: bool) -> Result<(), E> {
            Ok(())
        }
        fn visit_i64<E>(self, _: i64) -> Result<(), E> {
            Ok(())
        }
        fn visit_u64<E>(self, _: u64) -> Result<(), E> {
            Ok(())
        }
        fn visit_f64<E>(self, _: f64) -> Result<(), E> {
            Ok(())
        }
        fn visit_str<E>(self, _: &str) -> Result<(), E> {
            Ok(())
        }
        fn visit_unit<E>(self) -> Result<(), E> {
            Ok(())
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
            let mut i = 0;
            while seq
                .next_element_seed(self.at(format!("{}[{i}]", self.path)))?
                .is_some()
            {
                i += 1;
            }
            Ok(())
        }
        fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
            let mut seen = std::collections::HashSet::new();
            while let Some(key) = map.next_key::<String>()? {
                let path = if self.path.is_empty() {
                    key.clone()
                } else {
                    format!("{}.{key}", self.path)
                };
                if !seen.insert(key.clone()) {
                    let at = if self.path.is_empty() {
                        "(document)".to_string()
                    } else {
                        self.path.clone()
                    };
                    *self.found.borrow_mut() = Some((at, key));
                    return Err(serde::de::Error::custom("duplicate key"));
                }
                map.next_value_seed(self.at(path))?;
            }
            Ok(())
        }
    }
    let found = RefCell::new(None);
    let mut de = serde_json::Deserializer::from_str(text);
    let _ = Walk {
        path: String::new(),
        found: &found,
    }
    .deserialize(&mut de);
    found.into_inner()
}

/// The variant of a `type` tag named `s`, from the (name, variant) table
/// of its enum, with serde's message for an unknown one.
pub(crate) fn variant_named<T: Copy>(s: &str, variants: &[(&str, T)]) -> Result<T, String> {
    variants
        .iter()
        .find(|(n, _)| *n == s)
        .map(|&(_, v)| v)
        .ok_or_else(|| {
            let names: Vec<String> = variants.iter().map(|(n, _)| format!("`{n}`")).collect();
            format!(
                "unknown variant `{s}`, expected one of {}",
                names.join(", ")
            )
        })
}

/// The name of `variant` in its enum's (name, variant) table.
pub(crate) fn variant_name<T: PartialEq>(
    variant: T,
    variants: &[(&'static str, T)],
) -> &'static str {
    variants
        .iter()
        .find(|(_, v)| *v == variant)
        .map_or("?", |(n, _)| n)
}

/// Read an optional field that, when given, must hold a value: `null` is
/// a type error at the field, not an absent field.
pub(crate) fn present<'de, D, T>(d: D) -> Result<Option<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    T::deserialize(d).map(Some)
}

/// Check the optional fields of a tagged object (`given`: name, present)
/// against those its type `takes`: each taken must be present, no other
/// may be. `what` names the type ("a pin joint"); `common` lists the fields
/// every type has, for the message.
pub(crate) fn variant_fields(
    what: &str,
    common: &[&str],
    takes: &[&str],
    given: &[(&str, bool)],
) -> Result<(), String> {
    let all = || {
        common
            .iter()
            .chain(takes)
            .map(|f| format!("`{f}`"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for &(field, present) in given {
        let taken = takes.contains(&field);
        if present && !taken {
            return Err(format!(
                "unknown field `{field}`: {what} has fields {}",
                all()
            ));
        }
        if !present && taken {
            return Err(format!(
                "missing field `{field}`: {what} has fields {}",
                all()
            ));
        }
    }
    Ok(())
}

/// serde's error for a field that no type of joint or path point has
/// lists the fields of every type; this is the error for the element's
/// own type (from its `type` in `text`), as [`variant_fields`] gives it
/// for a field of another type: "unknown field `orientaton`: a pin joint
/// has fields ...". None where `reason` is no such error.
fn unknown_field_of_type(text: &str, path: &str, reason: &str) -> Option<String> {
    let field = reason.strip_prefix("unknown field `")?.split('`').next()?;
    let at = reason.rfind(" at line ").map_or("", |k| &reason[k..]);
    let parent = path.strip_suffix(field)?.strip_suffix('.')?;
    let document: serde_json::Value = serde_json::from_str(text).ok()?;
    let kind = json_at(&document, parent)?.get("type")?.as_str()?;
    let last = parent.rsplit('.').next()?;
    let (what, common, takes): (String, &[&str], &[&str]) =
        if last.starts_with("joints[") && !parent.contains('.') {
            let t = variant_named(kind, &JOINT_TYPES).ok()?;
            (format!("a {kind} joint"), &JOINT_COMMON_FIELDS, t.fields())
        } else if last.starts_with("path[") {
            let (common, takes) = crate::path::path_point_fields(kind)?;
            (format!("a {kind} path point"), common, takes)
        } else {
            return None;
        };
    variant_fields(&what, common, takes, &[(field, true)])
        .err()
        .map(|m| format!("{m}{at}"))
}

/// The value at a JSON path as serde_path_to_error writes it
/// (`forces.muscles[3].path[1]`).
fn json_at<'a>(document: &'a serde_json::Value, path: &str) -> Option<&'a serde_json::Value> {
    let mut v = document;
    for segment in path.split('.') {
        let mut parts = segment.split('[');
        let name = parts.next()?;
        if !name.is_empty() {
            v = v.get(name)?;
        }
        for index in parts {
            v = v.get(index.strip_suffix(']')?.parse::<usize>().ok()?)?;
        }
    }
    Some(v)
}

/// The JSON path (`forces.muscles[3].path[1]`) of the first place where
/// `given` holds an array and `parsed` (the same document read and written
/// back) an object.
fn array_for_object(
    given: &serde_json::Value,
    parsed: &serde_json::Value,
    at: String,
) -> Option<String> {
    use serde_json::Value::{Array, Object};
    match (given, parsed) {
        (Array(_), Object(_)) => Some(if at.is_empty() {
            "(document)".into()
        } else {
            at
        }),
        (Object(g), Object(p)) => g.iter().find_map(|(k, gv)| {
            let pv = p.get(k)?;
            let at = if at.is_empty() {
                k.clone()
            } else {
                format!("{at}.{k}")
            };
            array_for_object(gv, pv, at)
        }),
        (Array(g), Array(p)) => g
            .iter()
            .zip(p)
            .enumerate()
            .find_map(|(i, (gv, pv))| array_for_object(gv, pv, format!("{at}[{i}]"))),
        _ => None,
    }
}

/// serde_json's error `e` in reading `text`, with a word where the text at
/// the error is a NaN or an infinity, which JSON does not have (Python's
/// `json.dump` writes them).
pub fn json_error_text(text: &str, e: &serde_json::Error) -> String {
    if e.is_syntax() && non_finite_literal_at(text, e.line(), e.column()) {
        format!("{e}: JSON has no NaN or Infinity; write a finite number")
    } else {
        e.to_string()
    }
}

/// Whether a `NaN`, `Infinity` or `inf` literal (any case, with or without
/// a sign), a whole word, starts at `line`, `column` (1-based, as
/// serde_json counts bytes) of `text`, or one byte before (where
/// serde_json points past a sign).
fn non_finite_literal_at(text: &str, line: usize, column: usize) -> bool {
    let Some(l) = text.lines().nth(line.saturating_sub(1)) else {
        return false;
    };
    let b = l.as_bytes();
    let word = |c: u8| c.is_ascii_alphanumeric() || c == b'_' || c == b'"' || c == b'.';
    let at = column.saturating_sub(1);
    (at.saturating_sub(1)..=at).any(|k| {
        if k > 0 && b.get(k - 1).is_some_and(|&c| word(c)) {
            return false;
        }
        let mut start = k;
        if matches!(b.get(start), Some(b'-' | b'+')) {
            start += 1;
        }
        ["infinity", "nan", "inf"].iter().any(|w| {
            let end = start + w.len();
            b.get(start..end)
                .is_some_and(|t| t.eq_ignore_ascii_case(w.as_bytes()))
                && !b.get(end).is_some_and(|&c| word(c))
        })
    })
}

/// serde's word for a number where a field takes a whole number ("invalid
/// type: floating point `2.5`, expected i64"; "invalid value: integer
/// `18446744073709551615`, expected i64"), which names a Rust type the user
/// never wrote, in the user's words; None for any other reason.
fn whole_number_reason(reason: &str) -> Option<String> {
    let (integer, rest) = if let Some(r) = reason.strip_prefix("invalid type: floating point `") {
        (false, r)
    } else if let Some(r) = reason.strip_prefix("invalid value: integer `") {
        (true, r)
    } else {
        return None;
    };
    let (value, rest) = rest.split_once("`, expected ")?;
    let (ty, at) = rest.split_at(rest.find(' ').unwrap_or(rest.len()));
    let (min, max): (i128, i128) = match ty {
        "i8" => (i8::MIN.into(), i8::MAX.into()),
        "i16" => (i16::MIN.into(), i16::MAX.into()),
        "i32" => (i32::MIN.into(), i32::MAX.into()),
        "i64" | "isize" => (i64::MIN.into(), i64::MAX.into()),
        "u8" => (0, u8::MAX.into()),
        "u16" => (0, u16::MAX.into()),
        "u32" => (0, u32::MAX.into()),
        "u64" | "usize" => (0, u64::MAX.into()),
        _ => return None,
    };
    let expected = if min == 0 {
        "a whole number ≥ 0"
    } else {
        "a whole number"
    };
    // The value as a whole number (a float's saturates), and whether it
    // has a fraction.
    let (whole, fraction) = if integer {
        (value.parse::<i128>().ok()?, false)
    } else {
        let v = value.parse::<f64>().ok()?;
        (v as i128, v.fract() != 0.0)
    };
    let why = if whole > max {
        ", too large"
    } else if whole < min && min < 0 {
        ", too small"
    } else if whole < min || fraction {
        ""
    } else {
        // 28.0 or 1e3 for 28 or 1000.
        return Some(format!(
            "expected {expected} written without a decimal point or exponent ({whole}), got {value}{at}"
        ));
    };
    Some(format!("expected {expected}, got {value}{why}{at}"))
}

fn json_kind(v: &serde_json::Value) -> &'static str {
    match v {
        serde_json::Value::Null => "null",
        serde_json::Value::Bool(_) => "a boolean",
        serde_json::Value::Number(_) => "a number",
        serde_json::Value::String(_) => "a string",
        serde_json::Value::Array(_) => "an array",
        serde_json::Value::Object(_) => "an object",
    }
}

/// Why a component's name cannot be used, if it cannot: it becomes a part
/// of OpenSim paths (`/forceset/<muscle>/activation`) and of column labels,
/// so it may not hold `\\ / * +` (OpenSim's `ComponentPath` refuses them),
/// whitespace or control characters (which split a .sto file's
/// tab-separated labels), nor ',' (which splits the labels of `leap eval`'s
/// CSV input and of OpenSim's CSV exports).
fn name_problem(name: &str) -> Option<String> {
    if name.is_empty() {
        return Some("empty name".into());
    }
    let shown: String = name.chars().take(80).collect();
    name.chars()
        .find(|c| {
            matches!(c, '\\' | '/' | '*' | '+' | ',') || c.is_whitespace() || c.is_control()
        })
        .map(|c| {
            format!(
                "'{shown}' holds {c:?}: a name becomes part of OpenSim paths and of column labels (.sto, CSV), so it may not hold \\ / * + or ',', whitespace or control characters"
            )
        })
}

fn finite3(v: &[f64; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// The largest body-frame coordinate of a location (m). A human model's
/// points lie within a couple of metres of their body's origin; far beyond
/// it the inertia about the origin, m·|c|², swamps the body's own in
/// Simbody's arithmetic (a mass centre at 1e100 m reached Simbody and was
/// refused there as an inertia breaking the triangle inequality).
pub const MAX_LOCATION_M: f64 = 100.0;

/// The heaviest body (kg): a segment of a human model weighs tens of
/// kilograms (a body of 1e12 kg set the Rust-native and Simbody dynamics
/// apart in their last digits).
pub const MAX_BODY_MASS_KG: f64 = 1e4;

/// Why coordinates `r` and `l` cannot be a symmetry pair [right, left], if
/// they cannot: the symmetric system gives the left coordinate the right
/// one's value, so the two need one range and one default, and names with
/// side suffixes (`hip_flexion_r`) must name one coordinate of each side,
/// the right first.
fn pair_problem(r: &str, l: &str, cr: &Coordinate, cl: &Coordinate) -> Option<String> {
    fn side(n: &str) -> Option<(&str, char)> {
        n.strip_suffix("_r")
            .map(|s| (s, 'r'))
            .or_else(|| n.strip_suffix("_l").map(|s| (s, 'l')))
    }
    if let (Some((sr, ar)), Some((sl, al))) = (side(r), side(l)) {
        if (ar, al) == ('l', 'r') && sr == sl {
            return Some(format!(
                "lists the left coordinate first: a pair is [right, left], so write [\"{l}\", \"{r}\"]"
            ));
        }
        if ar == al {
            return Some(format!(
                "pairs two coordinates of one side ('{r}' and '{l}'): a pair is [right, left]"
            ));
        }
        if sr != sl {
            return Some(format!(
                "pairs '{r}' with '{l}', whose names differ in more than the side: a pair is one coordinate's right and left (['{sr}_r', '{sr}_l'])"
            ));
        }
    }
    if cr.range != cl.range || cr.default_value != cl.default_value {
        return Some(format!(
            "'{r}' (range {:?}, default {}) and '{l}' (range {:?}, default {}) differ: the symmetric system gives both one value, so mirror partners need one range and one default (give '{l}' those of '{r}', which the system carries)",
            cr.range, cr.default_value, cl.range, cl.default_value
        ));
    }
    None
}

/// Why a location (m, body frame) cannot be used, if it cannot.
pub(crate) fn location_problem(v: &[f64; 3]) -> Option<String> {
    (!v.iter().all(|x| x.is_finite() && x.abs() <= MAX_LOCATION_M)).then(|| {
        format!(
            "must be finite and within ±{MAX_LOCATION_M} m of the body's origin in each coordinate, got [{}]",
            v.iter().map(|&x| crate::io::readable(x)).collect::<Vec<_>>().join(", ")
        )
    })
}

impl Model {
    /// Read and validate a model file.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self, ModelError> {
        let path = path.as_ref();
        let text = crate::io::read_input_text(path).map_err(|error| ModelError::Io {
            file: path.into(),
            error,
        })?;
        Self::from_json_str(&text, path)
    }

    /// Parse and validate JSON text; `file` names it in errors.
    pub fn from_json_str(text: &str, file: impl AsRef<Path>) -> Result<Self, ModelError> {
        let file = file.as_ref().to_path_buf();
        let spec: ModelFile = parse_json_object(text).map_err(|e| {
            let reason = unknown_field_of_type(text, &e.path, &e.reason).unwrap_or(e.reason);
            // A study given as the model: say so at its first unknown field.
            let reason = crate::study::with_kind_hint(text, "model", reason);
            ModelError::Parse {
                file: file.clone(),
                reason,
                path: e.path,
            }
        })?;
        Self::from_spec(spec, file)
    }

    /// Validate a deserialized model file.
    pub fn from_spec(spec: ModelFile, file: PathBuf) -> Result<Self, ModelError> {
        let err = |path: String, reason: String| ModelError::Invalid {
            file: file.clone(),
            path,
            reason,
        };

        if !finite3(&spec.gravity) {
            return Err(err("gravity".into(), "must be finite".into()));
        }
        // Bodies.
        let mut body_index = HashMap::new();
        let mut bodies = Vec::with_capacity(spec.bodies.len());
        for (i, b) in spec.bodies.iter().enumerate() {
            let p = |f: &str| format!("bodies[{i}].{f}");
            if let Some(r) = name_problem(&b.name) {
                return Err(err(p("name"), r));
            }
            if b.name == "ground" {
                return Err(err(
                    p("name"),
                    format!("'{}' is not a valid body name", b.name),
                ));
            }
            if body_index.insert(b.name.clone(), i).is_some() {
                return Err(err(
                    p("name"),
                    format!("body '{}' is defined twice", b.name),
                ));
            }
            if !(b.mass.is_finite() && b.mass > 0.0 && b.mass <= MAX_BODY_MASS_KG) {
                return Err(err(
                    p("mass"),
                    format!(
                        "mass must be positive and at most {MAX_BODY_MASS_KG:e} kg, got {}",
                        crate::io::readable(b.mass)
                    ),
                ));
            }
            if let Some(r) = location_problem(&b.mass_center) {
                return Err(err(p("mass_center"), r));
            }
            if let Some(reason) =
                inertia_problem(&b.inertia).or_else(|| inertia_size_problem(&b.inertia, b.mass))
            {
                return Err(err(p("inertia"), reason));
            }
            // Simbody and leap's multibody take the inertia about the body's
            // origin, I + m·(|c|²·1 − c·cᵀ): bounded by the bounds on m and
            // c above (m·|c|² ≤ 3e8 kg·m²).
            bodies.push(Body {
                name: b.name.clone(),
                mass: b.mass,
                mass_center: b.mass_center,
                inertia: b.inertia,
            });
        }
        // Coordinates.
        let mut coord_index = HashMap::new();
        let mut coordinates = Vec::with_capacity(spec.coordinates.len());
        for (i, c) in spec.coordinates.iter().enumerate() {
            let p = |f: &str| format!("coordinates[{i}].{f}");
            if let Some(r) = name_problem(&c.name) {
                return Err(err(p("name"), r));
            }
            if coord_index.insert(c.name.clone(), i).is_some() {
                return Err(err(
                    p("name"),
                    format!("coordinate '{}' is defined twice", c.name),
                ));
            }
            let [lo, hi] = c.range;
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(err(
                    p("range"),
                    format!(
                        "range must be finite with min < max, got [{}, {}]",
                        crate::io::readable(lo),
                        crate::io::readable(hi)
                    ),
                ));
            }
            if !(c.default_value.is_finite() && lo <= c.default_value && c.default_value <= hi) {
                return Err(err(
                    p("default_value"),
                    format!(
                        "default_value {} is outside the range [{}, {}]",
                        crate::io::readable(c.default_value),
                        crate::io::readable(lo),
                        crate::io::readable(hi)
                    ),
                ));
            }
            coordinates.push(Coordinate {
                name: c.name.clone(),
                range: c.range,
                default_value: c.default_value,
            });
        }
        // Joints.
        let mut coord_used: Vec<Option<usize>> = vec![None; coordinates.len()];
        let mut child_of: Vec<Option<usize>> = vec![None; bodies.len()];
        let mut joints = Vec::with_capacity(spec.joints.len());
        let mut joint_names = HashMap::new();
        for (j, js) in spec.joints.iter().enumerate() {
            let (name, parent, child, loc) = js.common();
            let p = |f: &str| format!("joints[{j}].{f}");
            if let Some(r) = name_problem(name) {
                return Err(err(p("name"), r));
            }
            if joint_names.insert(name.to_string(), j).is_some() {
                return Err(err(p("name"), format!("joint '{name}' is defined twice")));
            }
            let parent_idx = if parent == "ground" {
                None
            } else {
                Some(
                    *body_index
                        .get(parent)
                        .ok_or_else(|| err(p("parent"), format!("unknown body '{parent}'")))?,
                )
            };
            let child_idx = *body_index
                .get(child)
                .ok_or_else(|| err(p("child"), format!("unknown body '{child}'")))?;
            if parent_idx == Some(child_idx) {
                return Err(err(
                    p("child"),
                    format!("body '{child}' cannot be its own parent"),
                ));
            }
            if let Some(other) = child_of[child_idx] {
                return Err(err(
                    p("child"),
                    format!(
                        "body '{child}' is already the child of joint '{}'",
                        spec.joints[other].common().0
                    ),
                ));
            }
            child_of[child_idx] = Some(j);
            if let Some(r) = location_problem(loc) {
                return Err(err(p("location_in_parent"), r));
            }
            let mut use_coord = |field: String, cname: &str| -> Result<usize, ModelError> {
                let ci = *coord_index
                    .get(cname)
                    .ok_or_else(|| err(field.clone(), format!("unknown coordinate '{cname}'")))?;
                if let Some(other) = coord_used[ci] {
                    return Err(err(
                        field,
                        format!(
                            "coordinate '{cname}' is already used by joint '{}'",
                            spec.joints[other].common().0
                        ),
                    ));
                }
                coord_used[ci] = Some(j);
                Ok(ci)
            };
            let kind = match js {
                JointSpec::Planar {
                    coordinates: cs, ..
                } => {
                    if parent_idx.is_some() {
                        return Err(err(
                            p("parent"),
                            "a planar joint must have ground as its parent".into(),
                        ));
                    }
                    let mut idx = [0; 3];
                    for (k, cname) in cs.iter().enumerate() {
                        idx[k] = use_coord(p(&format!("coordinates[{k}]")), cname)?;
                    }
                    JointKind::Planar { coordinates: idx }
                }
                JointSpec::Pin { coordinate, .. } => JointKind::Pin {
                    coordinate: use_coord(p("coordinate"), coordinate)?,
                },
                JointSpec::TranslatingHinge {
                    coordinate,
                    translation_x,
                    translation_y,
                    ..
                } => {
                    let coordinate = use_coord(p("coordinate"), coordinate)?;
                    let tx = SimmSpline::new(translation_x)
                        .map_err(|e| err(p("translation_x"), e.to_string()))?;
                    let ty = SimmSpline::new(translation_y)
                        .map_err(|e| err(p("translation_y"), e.to_string()))?;
                    JointKind::TranslatingHinge {
                        coordinate,
                        translation_x: tx,
                        translation_y: ty,
                    }
                }
                JointSpec::Weld { .. } => {
                    if parent_idx.is_none() {
                        return Err(err(
                            p("parent"),
                            "a weld joint must have a body as its parent, not ground: leap's multibody systems have no fixed bodies (leave a fixed platform or force plate out of the model; its ground contact is the half-space's)".into(),
                        ));
                    }
                    JointKind::Weld
                }
            };
            joints.push(Joint {
                name: name.to_string(),
                parent: parent_idx,
                child: child_idx,
                location_in_parent: *loc,
                kind,
            });
        }
        for (i, used) in coord_used.iter().enumerate() {
            if used.is_none() {
                return Err(err(
                    format!("coordinates[{i}]"),
                    format!(
                        "coordinate '{}' is not used by any joint",
                        coordinates[i].name
                    ),
                ));
            }
        }
        for (i, c) in child_of.iter().enumerate() {
            if c.is_none() {
                return Err(err(
                    format!("bodies[{i}]"),
                    format!("body '{}' is not the child of any joint", bodies[i].name),
                ));
            }
        }
        // Every body must reach ground (no cycles).
        for start in 0..bodies.len() {
            let mut b = start;
            let mut steps = 0;
            while let Some(parent) = joints[child_of[b].unwrap_or(0)].parent {
                b = parent;
                steps += 1;
                if steps > bodies.len() {
                    return Err(err(
                        format!("bodies[{start}]"),
                        format!(
                            "body '{}' is in a kinematic loop that never reaches ground",
                            bodies[start].name
                        ),
                    ));
                }
            }
        }
        // Stations.
        let mut stations = Vec::with_capacity(spec.stations.len());
        let mut station_names = HashMap::new();
        for (i, s) in spec.stations.iter().enumerate() {
            let p = |f: &str| format!("stations[{i}].{f}");
            if let Some(r) = name_problem(&s.name) {
                return Err(err(p("name"), r));
            }
            if station_names.insert(s.name.clone(), i).is_some() {
                return Err(err(
                    p("name"),
                    format!("station '{}' is defined twice", s.name),
                ));
            }
            let body = *body_index
                .get(&s.body)
                .ok_or_else(|| err(p("body"), format!("unknown body '{}'", s.body)))?;
            if let Some(r) = location_problem(&s.location) {
                return Err(err(p("location"), r));
            }
            stations.push(Station {
                name: s.name.clone(),
                body,
                location: s.location,
            });
        }
        // Symmetry pairs.
        let mut symmetry = Vec::new();
        let mut in_pair: Vec<Option<usize>> = vec![None; coordinates.len()];
        for (i, [r, l]) in spec.symmetry.iter().enumerate() {
            let ri = *coord_index.get(r).ok_or_else(|| {
                err(
                    format!("symmetry[{i}][0]"),
                    format!("unknown coordinate '{r}'"),
                )
            })?;
            let li = *coord_index.get(l).ok_or_else(|| {
                err(
                    format!("symmetry[{i}][1]"),
                    format!("unknown coordinate '{l}'"),
                )
            })?;
            if ri == li {
                return Err(err(
                    format!("symmetry[{i}]"),
                    format!("pairs coordinate '{r}' with itself"),
                ));
            }
            for (k, c, ci) in [(0, r, ri), (1, l, li)] {
                if let Some(j) = in_pair[ci] {
                    return Err(err(
                        format!("symmetry[{i}][{k}]"),
                        format!("coordinate '{c}' is already paired by symmetry[{j}]: each coordinate has at most one partner"),
                    ));
                }
            }
            if let Some(reason) = pair_problem(r, l, &coordinates[ri], &coordinates[li]) {
                return Err(err(format!("symmetry[{i}]"), reason));
            }
            in_pair[ri] = Some(i);
            in_pair[li] = Some(i);
            symmetry.push((ri, li));
        }
        // Poses.
        let mut poses = BTreeMap::new();
        for (pname, values) in &spec.poses {
            let mut q: Vec<f64> = coordinates.iter().map(|c| c.default_value).collect();
            for (cname, &v) in values {
                let path = format!("poses.{pname}.{cname}");
                let ci = *coord_index
                    .get(cname)
                    .ok_or_else(|| err(path.clone(), format!("unknown coordinate '{cname}'")))?;
                let [lo, hi] = coordinates[ci].range;
                if !(v.is_finite() && lo <= v && v <= hi) {
                    return Err(err(
                        path,
                        format!(
                            "value {} is outside the range [{}, {}]",
                            crate::io::readable(v),
                            crate::io::readable(lo),
                            crate::io::readable(hi)
                        ),
                    ));
                }
                q[ci] = v;
            }
            // The symmetric system stands both legs on the right one's
            // values: a left value that differs would be dropped unseen.
            for (i, [r, l]) in spec.symmetry.iter().enumerate() {
                if let (Some(&vr), Some(&vl)) = (values.get(r), values.get(l)) {
                    if vr != vl {
                        return Err(err(
                            format!("poses.{pname}.{l}"),
                            format!("{vl} differs from its symmetry partner {r} ({vr}, symmetry[{i}]): the symmetric system gives both sides one value"),
                        ));
                    }
                }
            }
            poses.insert(pname.clone(), q);
        }
        // Force elements.
        let body_of = |n: &str| body_index.get(n).copied();
        let coord_of = |n: &str| coord_index.get(n).copied();
        let mut muscles = Vec::with_capacity(spec.forces.muscles.len());
        let mut muscle_names = HashMap::new();
        for (i, m) in spec.forces.muscles.iter().enumerate() {
            let p = |f: &str| format!("forces.muscles[{i}].{f}");
            if let Some(r) = name_problem(&m.name) {
                return Err(err(p("name"), r));
            }
            if muscle_names.insert(m.name.clone(), i).is_some() {
                return Err(err(
                    p("name"),
                    format!("muscle '{}' is defined twice", m.name),
                ));
            }
            // OpenSim's Thelen2003Muscle refuses Flen ≤ 1 (the
            // lengthening force-velocity curve's asymptote) and a linear
            // extrapolation threshold (0.95) not above 1/Flen. DeGroote's
            // muscle has no Flen. (A non-finite Flen is refused below.)
            if spec.forces.muscle_model == MuscleModel::Thelen2003Muscle
                && m.Flen <= 1.0 / crate::laws::FV_THRESHOLD
            {
                return Err(err(
                    p("Flen"),
                    format!(
                        "must be greater than 1/{} = {:.4} (OpenSim's Thelen2003Muscle: Flen > 1 and fv_linear_extrap_threshold > 1/Flen), got {}",
                        crate::laws::FV_THRESHOLD,
                        1.0 / crate::laws::FV_THRESHOLD,
                        crate::io::readable(m.Flen)
                    ),
                ));
            }
            // DeGroote's curves are fixed: Thelen's shape constants would
            // be read and then have no effect. FmaxTendonStrain and
            // FmaxMuscleStrain carry over (its tendon_strain_at_one_norm_force
            // and passive_fiber_strain_at_one_norm_force).
            if spec.forces.muscle_model == MuscleModel::DeGrooteFregly2016Muscle {
                for (name, v, default) in [
                    ("KshapeActive", m.KshapeActive, d_kshape_active()),
                    ("KshapePassive", m.KshapePassive, d_kshape_passive()),
                    ("Af", m.Af, d_af()),
                    ("Flen", m.Flen, d_flen()),
                ] {
                    if v != default {
                        return Err(err(
                            p(name),
                            format!(
                                "{name} ({}) is a Thelen2003Muscle constant with no effect on DeGrooteFregly2016Muscle, whose curves are fixed (FmaxTendonStrain and FmaxMuscleStrain carry over): remove it or give Thelen's default, {}",
                                crate::io::readable(v),
                                crate::io::readable(default)
                            ),
                        ));
                    }
                }
            }
            // Every parameter but the pennation angle has a range, which
            // refuses what is not finite and positive.
            for (name, v) in m.parameters() {
                if let Some(r) = MUSCLE_PARAMETER_RANGES.problem(name, v) {
                    return Err(err(p(name), r));
                }
            }
            let phi = m.pennation_angle_at_optimal;
            if !(phi.is_finite() && (0.0..std::f64::consts::FRAC_PI_2).contains(&phi)) {
                return Err(err(
                    p("pennation_angle_at_optimal"),
                    format!("must be in [0, π/2) rad, got {}", crate::io::readable(phi)),
                ));
            }
            let path = crate::path::GeometryPath::new(&m.path, body_of, coord_of).map_err(
                |(k, f, reason)| {
                    err(
                        if f.is_empty() {
                            p("path")
                        } else {
                            format!("forces.muscles[{i}].path[{k}].{f}")
                        },
                        reason,
                    )
                },
            )?;
            if path.num_conditional() > 8 {
                return Err(err(
                    p("path"),
                    "at most 8 conditional path points per muscle".into(),
                ));
            }
            muscles.push(Muscle {
                spec: m.clone(),
                path,
            });
        }
        let mut ligaments = Vec::new();
        for (i, l) in spec.forces.ligaments.iter().enumerate() {
            let p = |f: &str| format!("forces.ligaments[{i}].{f}");
            let c = coord_of(&l.coordinate).ok_or_else(|| {
                err(
                    p("coordinate"),
                    format!("unknown coordinate '{}'", l.coordinate),
                )
            })?;
            // The ranges refuse what is not finite, and a negative damping.
            for (name, v) in [
                ("k1", l.k1),
                ("k2", l.k2),
                ("k3", l.k3),
                ("k4", l.k4),
                ("theta1", l.theta1),
                ("theta2", l.theta2),
                ("damping", l.damping),
            ] {
                if let Some(r) = LIGAMENT_PARAMETER_RANGES.problem(name, v) {
                    return Err(err(p(name), r));
                }
            }
            // Each exponential term, with its first and second derivatives
            // (the collocation's Hessian), finite over the coordinate's
            // range: a term is monotonic, so its ends bound it. A term
            // switched off (k = 0) is zero (`laws::passive_torque`).
            for (k, kexp, theta, field) in
                [(l.k1, l.k2, l.theta2, "k2"), (l.k3, l.k4, l.theta1, "k4")]
            {
                if k == 0.0 {
                    continue;
                }
                for q in coordinates[c].range {
                    let term = k * (kexp * (q - theta)).exp();
                    if !(term * kexp.abs().max(1.0).powi(2)).is_finite() {
                        return Err(err(
                            p(field),
                            format!(
                                "the passive torque's term {} · exp({} · (q − {})) overflows at {} rad, an end of '{}''s range: it must stay finite over the range",
                                crate::io::readable(k),
                                crate::io::readable(kexp),
                                crate::io::readable(theta),
                                crate::io::readable(q),
                                l.coordinate
                            ),
                        ));
                    }
                }
            }
            if let Some(j) = ligaments.iter().position(|g: &Ligament| g.coordinate == c) {
                return Err(err(
                    p("coordinate"),
                    format!("coordinate '{}' already has a passive torque (forces.ligaments[{j}]): one per coordinate (OpenSim's export names it passive_{})", l.coordinate, l.coordinate),
                ));
            }
            ligaments.push(Ligament {
                coordinate: c,
                spec: l.clone(),
            });
        }
        let contact = match &spec.forces.contact {
            None => None,
            Some(cs) => {
                let p = |f: &str| format!("forces.contact.{f}");
                // The ranges hold the signs too (stiffness and transition
                // velocity positive, the others non-negative) and refuse
                // what is not finite.
                for (name, v) in [
                    ("stiffness", cs.stiffness),
                    ("dissipation", cs.dissipation),
                    ("static_friction", cs.static_friction),
                    ("dynamic_friction", cs.dynamic_friction),
                    ("viscous_friction", cs.viscous_friction),
                    ("transition_velocity", cs.transition_velocity),
                ] {
                    if let Some(r) = CONTACT_PARAMETER_RANGES.problem(name, v) {
                        return Err(err(p(name), r));
                    }
                }
                if cs.dynamic_friction > cs.static_friction {
                    return Err(err(
                        p("dynamic_friction"),
                        "dynamic_friction must not exceed static_friction".into(),
                    ));
                }
                for (name, v) in [
                    ("hertz_smoothing", cs.hertz_smoothing),
                    ("hunt_crossley_smoothing", cs.hunt_crossley_smoothing),
                    ("derivative_smoothing", cs.derivative_smoothing),
                ] {
                    let Some(v) = v else { continue };
                    if cs.law == ContactLaw::HuntCrossleyForce {
                        return Err(err(
                            p(name),
                            format!("{name} is a constant of SmoothSphereHalfSpaceForce; HuntCrossleyForce does not use it (leave it out, or set `law` to SmoothSphereHalfSpaceForce)"),
                        ));
                    }
                    if let Some(r) = CONTACT_PARAMETER_RANGES.problem(name, v) {
                        return Err(err(p(name), r));
                    }
                }
                if cs.spheres.is_empty() {
                    return Err(err(
                        p("spheres"),
                        "no contact spheres: give at least one per foot, or leave out `contact`"
                            .into(),
                    ));
                }
                let mut spheres = Vec::new();
                let mut sphere_names = HashMap::new();
                for (i, sp) in cs.spheres.iter().enumerate() {
                    let q = |f: &str| format!("forces.contact.spheres[{i}].{f}");
                    // Spheres are reported by name (`leap eval`).
                    if let Some(r) = name_problem(&sp.name) {
                        return Err(err(q("name"), r));
                    }
                    if let Some(first) = sphere_names.insert(sp.name.clone(), i) {
                        return Err(err(
                            q("name"),
                            format!(
                                "sphere '{}' is defined twice (also spheres[{first}])",
                                sp.name
                            ),
                        ));
                    }
                    let body = body_of(&sp.body)
                        .ok_or_else(|| err(q("body"), format!("unknown body '{}'", sp.body)))?;
                    if let Some(r) = location_problem(&sp.location) {
                        return Err(err(q("location"), r));
                    }
                    if let Some(r) = CONTACT_PARAMETER_RANGES.problem("radius", sp.radius) {
                        return Err(err(q("radius"), r));
                    }
                    spheres.push(Sphere {
                        name: sp.name.clone(),
                        body,
                        location: sp.location,
                        radius: sp.radius,
                    });
                }
                Some(Contact {
                    spec: cs.clone(),
                    spheres,
                })
            }
        };
        if contact.is_some() {
            check_gravity_down(&spec.gravity).map_err(|r| err("gravity".into(), r))?;
        }
        if !symmetry.is_empty() {
            check_muscle_pairs(&spec.forces.muscles, &spec.symmetry, &spec.joints)
                .map_err(|(path, r)| err(path, r))?;
        }
        let model = Model {
            muscle_model: spec.forces.muscle_model,
            muscles,
            ligaments,
            contact,
            file: file.clone(),
            name: spec.name,
            credits: spec.credits,
            gravity: spec.gravity,
            bodies,
            joints,
            coordinates,
            stations,
            symmetry,
            poses,
        };
        if !model.symmetry.is_empty() {
            model.system(true)?; // reports asymmetric geometry at load time
        }
        if model.poses.contains_key("squat") {
            // A jump model: `leap squat`, `solve` and `simulate` start from
            // the static squat, which stands on the spheres by the muscles.
            if model.muscles.is_empty() {
                return Err(err(
                    "forces.muscles".into(),
                    "no muscles: a jump model (one with a 'squat' pose) needs muscles to hold the squat and push off".into(),
                ));
            }
            if model.contact.is_none() {
                return Err(err(
                    "forces.contact".into(),
                    "missing: a jump model (one with a 'squat' pose) needs foot-ground contact spheres to stand on".into(),
                ));
            }
            // The jump is solved on the symmetric system, which pairs
            // <stem>_r with <stem>_l: without coordinate pairs their legs move
            // apart and no pair can be a mirror image.
            if model.symmetry.is_empty() {
                let paired = model.muscles.iter().find_map(|m| {
                    let left = format!("{}_l", m.spec.name.strip_suffix("_r")?);
                    model
                        .muscles
                        .iter()
                        .any(|o| o.spec.name == left)
                        .then(|| (m.spec.name.clone(), left))
                });
                if let Some((right, left)) = paired {
                    return Err(err(
                        "symmetry".into(),
                        format!("no right/left coordinate pairs, but the muscles come in pairs ('{right}', '{left}'): a jump model is solved on the symmetric system, which needs the pairs (e.g. [\"hip_flexion_r\", \"hip_flexion_l\"])"),
                    ));
                }
            }
        }
        Ok(model)
    }

    /// The `squat` pose a jump starts from (model coordinate values), or an
    /// error naming the file and `poses`.
    pub fn squat_pose(&self) -> Result<Vec<f64>, ModelError> {
        self.poses
            .get("squat")
            .cloned()
            .ok_or_else(|| ModelError::Invalid {
                file: self.file.clone(),
                path: "poses".into(),
                reason: "the model has no 'squat' pose to start from".into(),
            })
    }

    /// Index of the named coordinate.
    pub fn coordinate_index(&self, name: &str) -> Option<usize> {
        self.coordinates.iter().position(|c| c.name == name)
    }

    /// Index of the named body.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// Total mass (kg).
    pub fn total_mass(&self) -> f64 {
        self.bodies.iter().map(|b| b.mass).sum()
    }

    /// The mobilized-body system both backends build. With `symmetric`, the
    /// left coordinate of each symmetry pair follows its right partner.
    pub fn system(&self, symmetric: bool) -> Result<SystemSpec, ModelError> {
        SystemSpec::build(self, symmetric)
    }
}

/// A range a physical parameter must lie in: (name, lowest, highest, unit;
/// "" for a ratio). Each is generous, a decade or more beyond the values of
/// the human models leap meets, so that it refuses only what would
/// otherwise fail later under another name (a squat that does not touch
/// the ground, a non-finite fibre velocity) or load and mislead: a force in
/// the wrong unit or with extra digits, a length in millimetres, a shape
/// factor whose curve becomes a step or a constant.
type ParameterRange = (&'static str, f64, f64, &'static str);

/// The ranges of one kind of force element's parameters, and what they
/// are wider than (for the message).
struct ParameterRanges {
    wider_than: &'static str,
    ranges: &'static [ParameterRange],
}

/// The muscles' ranges, around gait2392's human muscles (forces 100–8,000
/// N, fibres 0.02–0.5 m, tendons 0.01–0.5 m, v_max 10 l_opt/s, time
/// constants 0.01–0.06 s) and the Thelen2003Muscle curves of every OpenSim
/// model in leap's references (FmaxTendonStrain 0.033, FmaxMuscleStrain
/// 0.6, KshapeActive 0.5, KshapePassive 4, Af 0.3, Flen 1.8; Thelen 2003:
/// 0.04–0.05, 0.5–0.6, 0.45, 4–5, 0.25, 1.4). Flen's lowest is OpenSim's
/// own rule, checked first.
const MUSCLE_PARAMETER_RANGES: ParameterRanges = ParameterRanges {
    wider_than: "any human muscle's",
    ranges: &[
        ("max_isometric_force", 1e-3, 1e5, "N"),
        ("optimal_fiber_length", 1e-4, 5.0, "m"),
        ("tendon_slack_length", 1e-4, 5.0, "m"),
        ("max_contraction_velocity", 0.1, 100.0, "l_opt/s"),
        ("activation_time_constant", 1e-4, 10.0, "s"),
        ("deactivation_time_constant", 1e-4, 10.0, "s"),
        ("FmaxTendonStrain", 1e-3, 1.0, ""),
        ("FmaxMuscleStrain", 1e-2, 10.0, ""),
        ("KshapeActive", 1e-2, 10.0, ""),
        ("KshapePassive", 0.1, 100.0, ""),
        ("Af", 1e-2, 10.0, ""),
        ("Flen", 1.0, 100.0, ""),
    ],
};

/// The foot contact's ranges, around the parameters of the contact models
/// in leap's references (Falisse et al. and Moco's 2D gait: stiffness
/// 3.1–3.8e6 Pa, dissipation 2 s/m, friction 0.8, viscous friction 0.5
/// s/m, transition velocity 0.1–0.2 m/s, radii 0.015–0.035 m; OpenSim's
/// `HuntCrossleyForce` defaults a transition velocity of 0.001 m/s).
const CONTACT_PARAMETER_RANGES: ParameterRanges = ParameterRanges {
    wider_than: "any foot contact model's",
    ranges: &[
        ("stiffness", 1e4, 1e10, "Pa"),
        ("dissipation", 0.0, 100.0, "s/m"),
        ("static_friction", 0.0, 10.0, ""),
        ("dynamic_friction", 0.0, 10.0, ""),
        ("viscous_friction", 0.0, 100.0, "s/m"),
        ("transition_velocity", 1e-5, 10.0, "m/s"),
        ("radius", 1e-3, 1.0, "m"),
        // SmoothSphereHalfSpaceForce's constants (OpenSim's defaults 300
        // 1/m, 50 s/m, 1e-5 m² for constant_contact_force): a smoothing
        // near zero halves every force (tanh(0) = 0), one of 1e-2 m² adds
        // 10 cm to the depth.
        ("hertz_smoothing", 10.0, 1e5, "1/m"),
        ("hunt_crossley_smoothing", 1.0, 1e4, "s/m"),
        ("derivative_smoothing", 1e-9, 1e-3, "m²"),
    ],
};

/// The passive joint torques' ranges (k1·exp(k2·(q − θ2)) +
/// k3·exp(k4·(q − θ1)) − damping·q̇), around the coefficients of the models
/// leap meets (Anderson & Pandy's at the hip, knee, ankle and lumbar joints:
/// |k1|, |k3| ≤ 11 N·m, |k2|, |k4| ≤ 38 1/rad, angles within ±2.4 rad,
/// damping 0.1 N·m·s/rad; Falisse et al.'s subtalar and mtp joints: |k1|
/// up to 60 N·m, |k4| up to 70 1/rad).
const LIGAMENT_PARAMETER_RANGES: ParameterRanges = ParameterRanges {
    wider_than: "any joint's passive torque",
    ranges: &[
        ("k1", -1e4, 1e4, "N·m"),
        ("k2", -1e3, 1e3, "1/rad"),
        ("k3", -1e4, 1e4, "N·m"),
        ("k4", -1e3, 1e3, "1/rad"),
        (
            "theta1",
            -2.0 * std::f64::consts::PI,
            2.0 * std::f64::consts::PI,
            "rad",
        ),
        (
            "theta2",
            -2.0 * std::f64::consts::PI,
            2.0 * std::f64::consts::PI,
            "rad",
        ),
        ("damping", 0.0, 1e3, "N·m·s/rad"),
    ],
};

impl ParameterRanges {
    /// Why parameter `name` = `v` is refused, if it is. A parameter
    /// without a range passes.
    fn problem(&self, name: &str, v: f64) -> Option<String> {
        let &(_, lo, hi, unit) = self.ranges.iter().find(|r| r.0 == name)?;
        if v.is_finite() && (lo..=hi).contains(&v) {
            return None;
        }
        // Bounds as written (2π to 4 decimals).
        let r = |x: f64| {
            let s = crate::io::readable(x);
            if s.len() > 10 {
                format!("{x:.4}")
            } else {
                s
            }
        };
        let unit = if unit.is_empty() {
            String::new()
        } else {
            format!(" {unit}")
        };
        Some(format!(
            "{}{unit}: lies outside [{}, {}]{unit}, a range far wider than {} (a slip of units or digits?)",
            crate::io::readable(v),
            r(lo),
            r(hi),
            self.wider_than
        ))
    }
}

impl MuscleSpec {
    /// The muscle's parameters by their model-file names.
    pub(crate) fn parameters(&self) -> [(&'static str, f64); 13] {
        [
            ("max_isometric_force", self.max_isometric_force),
            ("optimal_fiber_length", self.optimal_fiber_length),
            ("tendon_slack_length", self.tendon_slack_length),
            (
                "pennation_angle_at_optimal",
                self.pennation_angle_at_optimal,
            ),
            ("max_contraction_velocity", self.max_contraction_velocity),
            ("activation_time_constant", self.activation_time_constant),
            (
                "deactivation_time_constant",
                self.deactivation_time_constant,
            ),
            ("FmaxTendonStrain", self.FmaxTendonStrain),
            ("FmaxMuscleStrain", self.FmaxMuscleStrain),
            ("KshapeActive", self.KshapeActive),
            ("KshapePassive", self.KshapePassive),
            ("Af", self.Af),
            ("Flen", self.Flen),
        ]
    }
}

/// The magnitude of gravity a contact model may have (m/s²).
const GRAVITY_RANGE: (f64, f64) = (1.0, 100.0);

/// Gravity of a model standing on the ground, whose half-space has the
/// normal +y: `[0, -g, 0]` with g in [`GRAVITY_RANGE`]. (A model without
/// contact, a pendulum say, may point it anywhere.)
fn check_gravity_down(g: &[f64; 3]) -> Result<(), String> {
    if !(g[1] < 0.0 && g[0] == 0.0 && g[2] == 0.0) {
        return Err(format!(
            "must point down (−y), [0, -g, 0] with g > 0, got [{}, {}, {}]: the ground's normal is +y, and the squat and the jump need the model's weight on it",
            crate::io::readable(g[0]),
            crate::io::readable(g[1]),
            crate::io::readable(g[2])
        ));
    }
    if !(GRAVITY_RANGE.0..=GRAVITY_RANGE.1).contains(&-g[1]) {
        return Err(format!(
            "g = {} m/s² lies outside [{}, {}] m/s², far beyond where a person stands (the Moon's 1.62, the Earth's 9.81; a slip of units or digits?)",
            crate::io::readable(-g[1]),
            GRAVITY_RANGE.0,
            GRAVITY_RANGE.1
        ));
    }
    Ok(())
}

/// With a `symmetry` section the symmetric system carries each left muscle
/// (`<stem>_l`) by its right partner (`<stem>_r`), doubling its force: every
/// sided muscle needs its partner, with equal parameters. (A muscle without
/// a side suffix is a midline muscle, carried once.) Partners' paths must
/// be mirror images, point by point ([`path_mirror_problem`]). Returns the
/// JSON path and the reason.
fn check_muscle_pairs(
    muscles: &[MuscleSpec],
    symmetry: &[[String; 2]],
    joints: &[JointSpec],
) -> Result<(), (String, String)> {
    let index = |name: &str| muscles.iter().position(|m| m.name == name);
    for (i, m) in muscles.iter().enumerate() {
        let (stem, own, other) = if let Some(stem) = m.name.strip_suffix("_r") {
            (stem, "right", "_l")
        } else if let Some(stem) = m.name.strip_suffix("_l") {
            (stem, "left", "_r")
        } else {
            continue;
        };
        let partner = format!("{stem}{other}");
        let Some(j) = index(&partner) else {
            let hint = if index(stem).is_some() {
                format!(" ('{stem}' has no side suffix)")
            } else {
                String::new()
            };
            return Err((
                format!("forces.muscles[{i}].name"),
                format!(
                    "{own} muscle '{}' has no mirror partner '{partner}'{hint}: the symmetric system carries each left muscle by its right partner, so with a `symmetry` section every muscle named *_r needs its *_l and the other way round",
                    m.name
                ),
            ));
        };
        if own == "left" {
            continue; // compared from its right partner
        }
        let l = &muscles[j];
        if let Some((field, why)) = path_mirror_problem(&m.path, &l.path, symmetry, joints) {
            return Err((
                format!("forces.muscles[{j}].path{field}"),
                format!(
                    "muscle '{}' is not the mirror image of '{}' (forces.muscles[{i}]): {why}; the symmetric system carries both by the right one",
                    l.name, m.name
                ),
            ));
        }
        for ((name, vr), (_, vl)) in m.parameters().into_iter().zip(l.parameters()) {
            if vr != vl {
                return Err((
                    format!("forces.muscles[{j}].{name}"),
                    format!(
                        "muscle '{}' is not the mirror image of '{}' (forces.muscles[{i}]): {name} is {vl:?} against {vr:?}; the symmetric system carries both by the right one",
                        l.name, m.name
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Where and why a left muscle's path `left` is not the mirror image of
/// its right partner's `right`, if it is not: the same kinds of points in
/// the same order, on mirrored bodies (the children of symmetry partners'
/// joints and the bodies welded onto them, else by name: `<stem>_r` ↔
/// `<stem>_l`, a midline body itself), at mirrored locations (z negated), switched or moved by
/// symmetry partners over the same ranges and splines. The symmetric
/// system evaluates only the right path; sampled path lengths
/// (`StateEquation::new`) cannot see a conditional point whose range
/// differs only away from the samples. Returns (the JSON path below
/// `path`, the reason).
fn path_mirror_problem(
    right: &[crate::path::PathPointSpec],
    left: &[crate::path::PathPointSpec],
    symmetry: &[[String; 2]],
    joints: &[JointSpec],
) -> Option<(String, String)> {
    use crate::path::PathPointSpec as P;
    if right.len() != left.len() {
        return Some((
            String::new(),
            format!("{} path points against {}", left.len(), right.len()),
        ));
    }
    // Bodies moved by symmetry partners are partners (whatever their
    // names); the others pair by OpenSim's names, `<stem>_r` ↔ `<stem>_l`,
    // a midline body with itself.
    let child_of = |c: &str| {
        joints.iter().find_map(|j| match j {
            JointSpec::Pin {
                coordinate, child, ..
            }
            | JointSpec::TranslatingHinge {
                coordinate, child, ..
            } if coordinate == c => Some(child.as_str()),
            _ => None,
        })
    };
    let mut by_joints: Vec<(&str, &str)> = symmetry
        .iter()
        .filter_map(|[r, l]| Some((child_of(r)?, child_of(l)?)))
        .collect();
    // A body welded onto one of a pair (calcn on talus) pairs with the
    // body welded onto the other, where each is the only one.
    let welded_onto = |p: &str| {
        let mut w = joints.iter().filter_map(|j| match j {
            JointSpec::Weld { parent, child, .. } if parent == p => Some(child.as_str()),
            _ => None,
        });
        match (w.next(), w.next()) {
            (Some(c), None) => Some(c),
            _ => None,
        }
    };
    let mut k = 0;
    while k < by_joints.len() {
        let (r, l) = by_joints[k];
        if let (Some(a), Some(b)) = (welded_onto(r), welded_onto(l)) {
            if !by_joints.iter().any(|&(x, y)| x == a || y == b) {
                by_joints.push((a, b));
            }
        }
        k += 1;
    }
    let mirror_body = |b: &str| {
        if let Some(&(r, l)) = by_joints.iter().find(|(r, l)| *r == b || *l == b) {
            return if r == b { l.to_string() } else { r.to_string() };
        }
        match (b.strip_suffix("_r"), b.strip_suffix("_l")) {
            (Some(stem), _) => format!("{stem}_l"),
            (_, Some(stem)) => format!("{stem}_r"),
            _ => b.to_string(),
        }
    };
    let partner = |c: &str| {
        symmetry
            .iter()
            .find(|[r, _]| r == c)
            .map_or(c.to_string(), |[_, l]| l.clone())
    };
    // Why a left point's coordinate `cb` is not the partner of the right
    // one's `ca`: a midline coordinate (no pair in `symmetry`) drives both.
    let coordinate_problem = |ca: &str, cb: &str| -> String {
        if symmetry.iter().any(|[r, _]| r == ca) {
            format!(
                "coordinate '{cb}' where the right point's '{ca}' has the partner '{}'",
                partner(ca)
            )
        } else if let Some([r, _]) = symmetry.iter().find(|[_, l]| l == ca) {
            format!(
                "coordinate '{cb}' where the right point follows the left coordinate '{ca}' (the partner of '{r}'): a right muscle's points follow right or midline coordinates"
            )
        } else {
            format!(
                "coordinate '{cb}' where the right point's '{ca}' has no partner in `symmetry`, so both points would follow '{ca}' (if '{cb}' mirrors it, add [\"{ca}\", \"{cb}\"] to `symmetry`)"
            )
        }
    };
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0);
    let same_knots =
        |a: &[f64], b: &[f64]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| close(*x, *y));
    let mirrored =
        |a: &[f64; 3], b: &[f64; 3]| close(a[0], b[0]) && close(a[1], b[1]) && close(a[2], -b[2]);
    for (k, (r, l)) in right.iter().zip(left).enumerate() {
        let at = |f: &str| format!("[{k}].{f}");
        let (rb, lb) = match (r, l) {
            (P::Fixed { body: rb, .. }, P::Fixed { body: lb, .. })
            | (P::Conditional { body: rb, .. }, P::Conditional { body: lb, .. })
            | (P::Moving { body: rb, .. }, P::Moving { body: lb, .. }) => (rb, lb),
            _ => return Some((
                format!("[{k}]"),
                "its point is of another kind (fixed, conditional or moving) than the right one's"
                    .into(),
            )),
        };
        if *lb != mirror_body(rb) {
            return Some((
                at("body"),
                format!(
                    "body '{lb}' where the mirror of '{rb}' is '{}'",
                    mirror_body(rb)
                ),
            ));
        }
        match (r, l) {
            (P::Fixed { location: a, .. }, P::Fixed { location: b, .. }) if !mirrored(a, b) => {
                return Some((
                    at("location"),
                    format!("location {b:?} is not {a:?} with z negated"),
                ));
            }
            (
                P::Conditional {
                    location: a,
                    coordinate: ca,
                    range: ra,
                    ..
                },
                P::Conditional {
                    location: b,
                    coordinate: cb,
                    range: rb,
                    ..
                },
            ) => {
                if !mirrored(a, b) {
                    return Some((
                        at("location"),
                        format!("location {b:?} is not {a:?} with z negated"),
                    ));
                }
                if *cb != partner(ca) {
                    return Some((at("coordinate"), coordinate_problem(ca, cb)));
                }
                if ra != rb {
                    return Some((at("range"), format!("range {rb:?} against {ra:?}")));
                }
            }
            (
                P::Moving {
                    coordinate: ca,
                    x_location: xa,
                    y_location: ya,
                    z_location: za,
                    ..
                },
                P::Moving {
                    coordinate: cb,
                    x_location: xb,
                    y_location: yb,
                    z_location: zb,
                    ..
                },
            ) => {
                if *cb != partner(ca) {
                    return Some((at("coordinate"), coordinate_problem(ca, cb)));
                }
                let zb_mirrored: Vec<f64> = zb.y.iter().map(|v| -v).collect();
                for (f, same) in [
                    (
                        "x_location",
                        same_knots(&xa.x, &xb.x) && same_knots(&xa.y, &xb.y),
                    ),
                    (
                        "y_location",
                        same_knots(&ya.x, &yb.x) && same_knots(&ya.y, &yb.y),
                    ),
                    (
                        "z_location",
                        same_knots(&za.x, &zb.x) && same_knots(&za.y, &zb_mirrored),
                    ),
                ] {
                    if !same {
                        return Some((
                            at(f),
                            format!("{f} is not the right point's spline (z negated)"),
                        ));
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// Why an inertia `[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]` (about the mass centre,
/// in the body frame) is not physical, if it is not. A rigid body's inertia
/// is positive definite and its principal moments satisfy the triangle
/// inequality; in any frame its moments then satisfy it too and each
/// product is at most half the third moment (|2·Iyz| ≤ Ixx, ...), the
/// conditions Simbody's `Inertia` checks.
fn inertia_problem(i: &[f64; 6]) -> Option<String> {
    if i.iter().any(|v| !v.is_finite()) {
        return Some("inertia must be finite".into());
    }
    let [xx, yy, zz, xy, xz, yz] = *i;
    // Positive definite (Sylvester's criterion).
    let d1 = xx;
    let d2 = xx * yy - xy * xy;
    let d3 = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
    if !(d1 > 0.0 && d2 > 0.0 && d3 > 0.0) {
        return Some(format!("inertia {i:?} is not positive definite"));
    }
    let tol = 1e-12 * (xx + yy + zz);
    if xx + yy + tol < zz || yy + zz + tol < xx || xx + zz + tol < yy {
        return Some(format!(
            "inertia {i:?} violates the triangle inequality (Ixx + Iyy >= Izz, ...)"
        ));
    }
    if (2.0 * yz).abs() > xx + tol || (2.0 * xz).abs() > yy + tol || (2.0 * xy).abs() > zz + tol {
        return Some(format!(
            "inertia {i:?} has a product of inertia too large to be physical (|2 Iyz| <= Ixx, |2 Ixz| <= Iyy, |2 Ixy| <= Izz)"
        ));
    }
    let m = nalgebra::Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz);
    let p = m.symmetric_eigenvalues();
    let (a, b, c) = (p[0], p[1], p[2]);
    if a + b + tol < c || b + c + tol < a || a + c + tol < b {
        return Some(format!(
            "inertia {i:?} has principal moments {:?} that violate the triangle inequality: no rigid body has them",
            [a, b, c]
        ));
    }
    None
}

/// Why a physical inertia (about the mass centre) is too large for a body
/// of `mass` kg, if it is: a body whose mass lies within ±[`MAX_LOCATION_M`]
/// of its origin in each coordinate has its mass within 2√3·MAX_LOCATION_M
/// of its mass centre, so no moment above mass·(2√3·MAX_LOCATION_M)² (a
/// moment of 1e30 kg·m² had loaded, and swamped the dynamics' arithmetic).
fn inertia_size_problem(i: &[f64; 6], mass: f64) -> Option<String> {
    let k_max = 2.0 * 3f64.sqrt() * MAX_LOCATION_M;
    let largest = i[0].max(i[1]).max(i[2]);
    (largest > mass * k_max * k_max).then(|| {
        format!(
            "a moment of {} kg·m² gives a body of {} kg a radius of gyration of {} m; a body whose mass lies within ±{MAX_LOCATION_M} m of its origin has at most {k_max:.0} m",
            crate::io::readable(largest),
            crate::io::readable(mass),
            crate::io::readable((largest / mass).sqrt())
        )
    })
}

/// How a mobilized body moves relative to its parent in a [`SystemSpec`].
#[derive(Debug, Clone)]
pub enum Mobilizer {
    /// q = [rotation about z, x, y] (indices into the system's q).
    Planar { q: [usize; 3] },
    /// Rotation about z by q.
    Pin { q: usize },
    /// Rotation about z by q, origin at `location + (tx(q), ty(q), 0)`.
    TranslatingHinge {
        q: usize,
        translation_x: SimmSpline,
        translation_y: SimmSpline,
    },
    /// Rigidly attached.
    Weld,
}

/// One body of the system: the model's body `body`, attached to system body
/// `parent` (`None` = ground) at `location` in the parent frame.
#[derive(Debug, Clone)]
pub struct SystemBody {
    pub body: usize,
    pub parent: Option<usize>,
    pub location: [f64; 3],
    pub mobilizer: Mobilizer,
}

/// The multibody system built from a model: bodies in topological order
/// (parents first), and the generalized coordinates q.
#[derive(Debug, Clone)]
pub struct SystemSpec {
    pub symmetric: bool,
    pub bodies: Vec<SystemBody>,
    /// The model coordinate behind each system coordinate, in the model's order.
    pub coordinates: Vec<usize>,
    /// For each model coordinate, the system coordinate that drives it.
    pub q_of_model_coordinate: Vec<usize>,
    /// For each model body, its index in `bodies`.
    pub system_body_of: Vec<usize>,
    /// For each model body of the left leg that the symmetric system welds
    /// onto its right partner, that partner (model body index): the two
    /// frames differ by a shift along z alone.
    pub mirror_of: Vec<Option<usize>>,
}

impl SystemSpec {
    fn build(model: &Model, symmetric: bool) -> Result<Self, ModelError> {
        let err = |path: String, reason: String| ModelError::Invalid {
            file: model.file.clone(),
            path,
            reason,
        };
        let nc = model.coordinates.len();
        // Which coordinates follow another.
        let mut follows: Vec<Option<usize>> = vec![None; nc];
        if symmetric {
            for &(r, l) in &model.symmetry {
                follows[l] = Some(r);
            }
        }
        let mut coordinates = Vec::new();
        let mut q_of: Vec<usize> = vec![usize::MAX; nc];
        for c in 0..nc {
            if follows[c].is_none() {
                q_of[c] = coordinates.len();
                coordinates.push(c);
            }
        }
        for c in 0..nc {
            if let Some(r) = follows[c] {
                q_of[c] = q_of[r];
            }
        }
        let joint_of_coord = |c: usize| -> usize {
            model
                .joints
                .iter()
                .position(|j| match &j.kind {
                    JointKind::Planar { coordinates } => coordinates.contains(&c),
                    JointKind::Pin { coordinate }
                    | JointKind::TranslatingHinge { coordinate, .. } => *coordinate == c,
                    JointKind::Weld => false,
                })
                .unwrap_or(usize::MAX)
        };
        let nb = model.bodies.len();
        let mut sys_of: Vec<usize> = vec![usize::MAX; nb];
        // z offset of a body welded onto its mirror partner.
        let mut mirror_of: Vec<Option<(usize, f64)>> = vec![None; nb];
        let mut bodies: Vec<SystemBody> = Vec::with_capacity(nb);
        let mut done = vec![false; model.joints.len()];
        loop {
            let mut progressed = false;
            for (j, joint) in model.joints.iter().enumerate() {
                if done[j] {
                    continue;
                }
                let parent_sys = match joint.parent {
                    None => None,
                    Some(p) if sys_of[p] != usize::MAX => Some(sys_of[p]),
                    Some(_) => continue,
                };
                let jpath = format!("joints[{j}]");
                let follow = match &joint.kind {
                    JointKind::Pin { coordinate }
                    | JointKind::TranslatingHinge { coordinate, .. } => follows[*coordinate],
                    JointKind::Planar { coordinates } => {
                        if coordinates.iter().any(|c| follows[*c].is_some()) {
                            return Err(err(
                                jpath,
                                "a planar joint's coordinates cannot follow symmetry partners"
                                    .into(),
                            ));
                        }
                        None
                    }
                    JointKind::Weld => None,
                };
                let sb = if let Some(rc) = follow {
                    // Left joint: weld the child onto the right partner's child.
                    let pj = joint_of_coord(rc);
                    let partner = &model.joints[pj];
                    if sys_of[partner.child] == usize::MAX {
                        continue;
                    }
                    let same_kind = match (&joint.kind, &partner.kind) {
                        (JointKind::Pin { .. }, JointKind::Pin { .. }) => true,
                        (
                            JointKind::TranslatingHinge {
                                translation_x: ax,
                                translation_y: ay,
                                ..
                            },
                            JointKind::TranslatingHinge {
                                translation_x: bx,
                                translation_y: by,
                                ..
                            },
                        ) => ax == bx && ay == by,
                        _ => false,
                    };
                    if !same_kind {
                        return Err(err(jpath, format!("joint '{}' and its symmetry partner '{}' differ in type or translation splines", joint.name, partner.name)));
                    }
                    // The parents must coincide or be mirror partners.
                    let parent_dz = match (joint.parent, partner.parent) {
                        (a, b) if a == b => 0.0,
                        (Some(a), Some(b)) => match mirror_of[a] {
                            Some((m, dz)) if m == b => dz,
                            _ => return Err(err(jpath, format!("the parents of joint '{}' and its symmetry partner '{}' are not mirror images", joint.name, partner.name))),
                        },
                        _ => return Err(err(jpath, format!("the parents of joint '{}' and its symmetry partner '{}' are not mirror images", joint.name, partner.name))),
                    };
                    let (a, b) = (joint.location_in_parent, partner.location_in_parent);
                    if (a[0] - b[0]).abs() > 1e-12 || (a[1] - b[1]).abs() > 1e-12 {
                        return Err(err(format!("{jpath}.location_in_parent"), format!("x and y must equal those of the symmetry partner '{}' ({:?} vs {:?})", partner.name, a, b)));
                    }
                    let dz = parent_dz + a[2] - b[2];
                    mirror_of[joint.child] = Some((partner.child, dz));
                    SystemBody {
                        body: joint.child,
                        parent: Some(sys_of[partner.child]),
                        location: [0.0, 0.0, dz],
                        mobilizer: Mobilizer::Weld,
                    }
                } else {
                    let mobilizer = match &joint.kind {
                        JointKind::Planar { coordinates: c } => Mobilizer::Planar {
                            q: [q_of[c[0]], q_of[c[1]], q_of[c[2]]],
                        },
                        JointKind::Pin { coordinate } => Mobilizer::Pin {
                            q: q_of[*coordinate],
                        },
                        JointKind::TranslatingHinge {
                            coordinate,
                            translation_x,
                            translation_y,
                        } => Mobilizer::TranslatingHinge {
                            q: q_of[*coordinate],
                            translation_x: translation_x.clone(),
                            translation_y: translation_y.clone(),
                        },
                        JointKind::Weld => Mobilizer::Weld,
                    };
                    SystemBody {
                        body: joint.child,
                        parent: parent_sys,
                        location: joint.location_in_parent,
                        mobilizer,
                    }
                };
                sys_of[joint.child] = bodies.len();
                bodies.push(sb);
                done[j] = true;
                progressed = true;
            }
            if done.iter().all(|&d| d) {
                break;
            }
            if !progressed {
                let j = done.iter().position(|&d| !d).unwrap_or(0);
                return Err(err(format!("joints[{j}]"), format!("joint '{}' cannot be placed in the symmetric system (its symmetry partner is not reachable)", model.joints[j].name)));
            }
        }
        Ok(SystemSpec {
            symmetric,
            bodies,
            coordinates,
            q_of_model_coordinate: q_of,
            system_body_of: sys_of,
            mirror_of: mirror_of.iter().map(|m| m.map(|(b, _)| b)).collect(),
        })
    }

    /// Number of generalized coordinates.
    pub fn nq(&self) -> usize {
        self.coordinates.len()
    }

    /// The system's q for a full model-coordinate vector (right side wins).
    pub fn q_from_model(&self, model_q: &[f64]) -> Vec<f64> {
        self.coordinates.iter().map(|&c| model_q[c]).collect()
    }

    /// Expand a system vector (q or u) to all model coordinates.
    pub fn model_from_q(&self, q: &[f64]) -> Vec<f64> {
        self.q_of_model_coordinate.iter().map(|&k| q[k]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The muscle loop refuses a non-positive or non-finite parameter only
    /// through its range: every parameter but the pennation angle (checked
    /// on its own, in [0, π/2)) must have one, above zero.
    #[test]
    fn every_muscle_parameter_but_the_pennation_has_a_positive_range() {
        let model = Model::from_file("models/jumper.json").unwrap();
        for (name, _) in model.muscles[0].spec.parameters() {
            let range = MUSCLE_PARAMETER_RANGES.ranges.iter().find(|r| r.0 == name);
            if name == "pennation_angle_at_optimal" {
                assert!(range.is_none());
                continue;
            }
            let &(_, lo, hi, _) = range.unwrap_or_else(|| panic!("{name} has no range"));
            assert!(
                lo > 0.0 && lo < hi && hi.is_finite(),
                "{name}: [{lo}, {hi}]"
            );
            for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
                assert!(
                    MUSCLE_PARAMETER_RANGES.problem(name, bad).is_some(),
                    "{name} = {bad}"
                );
            }
        }
    }
}
