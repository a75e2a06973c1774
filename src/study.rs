//! The study file of `leap solve` (JSON): which model, which method, the
//! mesh, the initial guess, the optimizer's tolerances and where results go.
//! Setting names follow Moco's `MocoDirectCollocationSolver`
//! (`num_mesh_intervals`, `optim_convergence_tolerance`,
//! `optim_constraint_tolerance`, `optim_max_iterations`) where it has one.
//!
//! ```json
//! {
//!   "description": "Porsa, Lin & Pandy (2016): maximum-height squat jump",
//!   "model": "jumper.json",
//!   "method": "collocation",
//!   "mesh": {"num_mesh_intervals": 28, "scheme": "midpoint-euler",
//!            "fiber_dynamics": "implicit"},
//!   "guess": "bang-bang",
//!   "tolerances": {"optim_convergence_tolerance": 1e-6,
//!                  "optim_constraint_tolerance": 1e-8, "max_iterations": 3000},
//!   "hessian": "exact",
//!   "qp_solver": "interior-point",
//!   "output_directory": "../results"
//! }
//! ```
//!
//! Every field is optional; the built-in study (no file) is the paper's
//! problem. Paths written in a study file are relative to the file's
//! directory; the defaults (`models/jumper.json`, `results/`) are relative
//! to the working directory. A bad study is reported with the file, the
//! JSON path of the field and the reason ([`StudyError`]).

use crate::model::parse_json_object;
use crate::simbody::SimbodyIntegrator;
use crate::simulate::{check_integrator_accuracy, parse_integrator, IntegratorChoice};
use crate::sqp::{Convexification, HessianMode, QpSolver, SqpSettings};
use crate::transcription::{Backend, FiberDynamics, Scheme, TranscriptionOptions};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Relative eigenvalue floor of the exact element Hessians in the jump
/// (see [`SolveStudy::resolve`]'s settings).
pub const JUMP_EIGENVALUE_FLOOR: f64 = 1e-4;

/// The same for Hermite–Simpson, whose one element per interval composes
/// the dynamics through the centre state: its largest eigenvalue is set by
/// that stiff composition, and 1e-4 of it lifted every weak direction so
/// far that the full jump crept (26.7 cm after 3,000 iterations); at 1e-6
/// it solved in 580 iterations (32.3 cm), at 1e-7 in 525 (34.1 cm), at 1e-2
/// it stalled in elastic mode (docs/implicit-fibre-dynamics.md, "Speed").
pub const HERMITE_SIMPSON_EIGENVALUE_FLOOR: f64 = 1e-7;

/// The eigenvalue floor a scheme gets unless the study names one.
pub fn default_eigenvalue_floor(scheme: Scheme) -> f64 {
    if scheme == Scheme::HermiteSimpson {
        HERMITE_SIMPSON_EIGENVALUE_FLOOR
    } else {
        JUMP_EIGENVALUE_FLOOR
    }
}

/// Methods a study may name.
pub const METHODS: [&str; 2] = ["collocation", "shooting"];

/// Why a collocation setting is refused with method "shooting".
const COLLOCATION_ONLY: &str = "applies to method 'collocation'; method 'shooting' integrates the state equation (explicit fibre dynamics) with Dormand–Prince 5(4)";

/// Why an exact-Hessian setting is refused with method "shooting".
const NO_EXACT_HESSIAN: &str = "method 'shooting' has no exact Hessian (its central differences and forward sensitivities give first derivatives only); use 'bfgs'";

/// How the jump problem is transcribed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Direct collocation ([`crate::transcription`], the default).
    Collocation,
    /// Direct shooting ([`crate::shooting`]): excitations at the nodes,
    /// forward integration, forward-sensitivity or central-difference
    /// derivatives.
    Shooting,
}

/// Collocation schemes by name (Moco's spelling where it has one).
pub const SCHEMES: [(&str, Scheme); 4] = [
    ("midpoint-euler", Scheme::MidpointEuler),
    ("trapezoidal", Scheme::Trapezoidal),
    ("hermite-simpson", Scheme::HermiteSimpson),
    ("backward-euler", Scheme::BackwardEuler),
];

/// The model when a study names none (relative to the working directory,
/// else to the crate's source directory).
pub const DEFAULT_MODEL: &str = "models/jumper.json";
/// The results directory when a study names none.
pub const DEFAULT_OUTPUT_DIRECTORY: &str = "results";

/// A study could not be read, or one of its settings is unusable.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error("{file}: cannot read the study file: {error}")]
    Io {
        file: PathBuf,
        error: std::io::Error,
    },
    /// `origin` is the study file, or "command line" for an override.
    #[error("{origin}: {field}: {reason}")]
    Field {
        origin: String,
        field: String,
        reason: String,
    },
}

/// The study file as written. Unknown fields are refused.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SolveStudy {
    /// Free text (JSON has no comments).
    #[serde(default)]
    pub description: Option<String>,
    /// Prefix of the output files (default "jump": `jump_solution.sto`, ...).
    #[serde(default)]
    pub name: Option<String>,
    /// Model file (default `models/jumper.json`).
    #[serde(default)]
    pub model: Option<String>,
    /// "collocation" (default) or "shooting" (the paper's direct
    /// shooting: excitations at the mesh nodes, Dormand–Prince 5(4),
    /// forward sensitivities or central differences; see `shooting`).
    #[serde(default)]
    pub method: Option<String>,
    /// Settings of method "shooting".
    #[serde(default)]
    pub shooting: ShootingSpec,
    #[serde(default)]
    pub mesh: MeshSpec,
    /// The jump problem's own settings (bounds on t_f, the
    /// no-countermovement rows), for either method.
    #[serde(default)]
    pub problem: ProblemSpec,
    /// "bang-bang" (default: the bang-bang jump's excitations integrated on
    /// the mesh by the transcription's own scheme, t_f the continuous jump's
    /// lift-off time), "bang-bang-resampled" (the continuous bang-bang jump
    /// resampled onto the mesh, its states violating the defects by the
    /// discretisation error) or a `.sto` file with every state and control
    /// column (a previous solution), resampled onto the mesh with t_f its
    /// last time.
    #[serde(default, alias = "guess_file")]
    pub guess: Option<String>,
    /// With a guess file: integrate its excitations on the mesh from the
    /// squat, t_f its last time (as the bang-bang guess is), instead of
    /// resampling its states (default false). A solution of another mesh
    /// resampled violates the new mesh's defects by the difference of the
    /// discretisations; integrated, it meets them from the start.
    #[serde(default)]
    pub integrate_guess: Option<bool>,
    #[serde(default)]
    pub tolerances: TolerancesSpec,
    /// The filter line search's opt-in heuristics (IPOPT's names), for a
    /// study that needs them.
    #[serde(default)]
    pub line_search: LineSearchSpec,
    /// "exact" (exact element Hessians with negative eigenvalues clipped,
    /// default), "exact-block-diagonal" (the same, block-diagonal over the
    /// transcription's blocks) or "bfgs" (partitioned damped BFGS).
    #[serde(default)]
    pub hessian: Option<String>,
    /// Smallest eigenvalue of an exact element Hessian, relative to the
    /// element's largest (default 1e-4).
    #[serde(default)]
    pub hessian_eigenvalue_floor: Option<f64>,
    /// Where collocation's points are evaluated: "rust-native" (default:
    /// leap's dynamics, the exact Jacobian from dual numbers) or "simbody"
    /// (Simbody's multibody system with the same force laws, the Jacobian
    /// by coloured central differences: the cross-check path;
    /// [`crate::transcription::Backend`]).
    #[serde(default)]
    pub backend: Option<String>,
    /// QP subproblem solver: "interior-point" (default: leap's own, with
    /// clarabel where it fails; faster, see [`QpSolver::InteriorPoint`])
    /// or "clarabel".
    #[serde(default)]
    pub qp_solver: Option<String>,
    /// Results directory (default `results/`).
    #[serde(default, alias = "results_directory")]
    pub output_directory: Option<String>,
    #[serde(default)]
    pub forward_check: ForwardCheckSpec,
}

/// The mesh (Moco's names).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// Uniform mesh intervals, 2 ≤ N ≤ [`MAX_NUM_MESH_INTERVALS`] (default
    /// 28, the paper's 29 nodes).
    /// Signed so that a negative count is reported as such.
    #[serde(default)]
    pub num_mesh_intervals: Option<i64>,
    /// "midpoint-euler" (default, Porsa et al. eq. 7), "trapezoidal",
    /// "hermite-simpson" or "backward-euler".
    #[serde(default, alias = "transcription_scheme")]
    pub scheme: Option<String>,
    /// How the fibre-length rows state the fibre dynamics: "implicit"
    /// (default; the force balance at the interval's fibre velocity,
    /// midpoint-euler only) or "explicit" (the fibre velocity from the
    /// inverted force–velocity curve, the paper's form).
    #[serde(default)]
    pub fiber_dynamics: Option<String>,
}

/// The jump problem's settings ([`crate::ocp::OcpOptions`]); absent
/// fields keep the paper's problem.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ProblemSpec {
    /// Bounds [t_min, t_max] on the final time t_f in seconds (Moco's
    /// `MocoPhase` property `time_final_bounds`; default [0.1, 1.0]; one
    /// value fixes t_f, as in Moco; within [0.01, 10] s). The bang-bang guess's t_f is moved
    /// into them; a guess file must end inside them.
    #[serde(default, alias = "final_time_bounds")]
    pub time_final_bounds: Option<Vec<f64>>,
    /// How many of eq. 4's no-countermovement rows Ÿ_C(t_n) ≤ Ÿ_C(t_{n+1})
    /// to state, from the first node (default 7, the paper's; at most the
    /// number of mesh intervals; 0 states none).
    #[serde(default)]
    pub no_countermovement_nodes: Option<i64>,
    /// Ẏ_C ≥ 0 at every node: the centre of mass never moves down
    /// (default true; false leaves eq. 4 alone, the paper's problem as
    /// printed; [`crate::ocp::OcpOptions::no_com_descent`]).
    #[serde(default)]
    pub no_com_descent: Option<bool>,
    /// b of the optimizer's activation switch ½ + ½·tanh(b·(u − a)), Moco's
    /// `activation_dynamics_smoothing` (default 200, within [1, 1000];
    /// [`crate::ocp::OcpOptions::activation_smoothing`]). The forward check
    /// integrates OpenSim's own switch; a sharper blend narrows the gap.
    #[serde(default)]
    pub activation_dynamics_smoothing: Option<f64>,
}

/// The jump problem's settings, resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProblemSettings {
    pub final_time_bounds: [f64; 2],
    /// None: the paper's 7, or every interval on a coarser mesh.
    pub no_countermovement_nodes: Option<usize>,
    pub no_com_descent: bool,
    /// None: the default, [`crate::ocp::DEFAULT_ACTIVATION_SMOOTHING`]
    /// (Some: the study gave it, which a De Groote model refuses).
    pub activation_dynamics_smoothing: Option<f64>,
}

/// The range of `problem.activation_dynamics_smoothing`: below 1 the blend
/// mixes the activation and deactivation time constants wherever |u − a| <
/// 1; above 1000 it is a step the optimizer's Newton steps meet as a kink.
pub const ACTIVATION_SMOOTHING_RANGE: [f64; 2] = [1.0, 1000.0];

impl Default for ProblemSettings {
    fn default() -> Self {
        let d = crate::ocp::OcpOptions::default();
        ProblemSettings {
            final_time_bounds: d.final_time_bounds,
            no_countermovement_nodes: None,
            no_com_descent: d.no_com_descent,
            activation_dynamics_smoothing: None,
        }
    }
}

impl ProblemSettings {
    /// The problem's options on a mesh of `num_intervals` intervals
    /// (`solve`'s collocation adds its scheme's fibre clamp).
    pub fn ocp_options(&self, num_intervals: usize) -> crate::ocp::OcpOptions {
        let d = crate::ocp::OcpOptions::default();
        crate::ocp::OcpOptions {
            final_time_bounds: self.final_time_bounds,
            no_countermovement_nodes: self
                .no_countermovement_nodes
                .unwrap_or(d.no_countermovement_nodes.min(num_intervals)),
            no_com_descent: self.no_com_descent,
            activation_smoothing: Some(
                self.activation_dynamics_smoothing
                    .unwrap_or(crate::ocp::DEFAULT_ACTIVATION_SMOOTHING),
            ),
            ..d
        }
    }

    /// Whether the rows of eq. 4 fit the mesh; the reason if not.
    fn check_mesh(&self, num_intervals: usize) -> Result<(), String> {
        match self.no_countermovement_nodes {
            Some(n) if n > num_intervals => Err(format!(
                "{n} rows need {n} mesh intervals, the mesh has {num_intervals} (eq. 4 compares the accelerations of consecutive nodes)"
            )),
            _ => Ok(()),
        }
    }
}

/// The shortest final time a study may allow (s): h = t_f/N must stay a
/// time step the contact and muscle dynamics can be integrated over.
const MIN_TIME_FINAL: f64 = 0.01;

/// Final-time bounds as a study file gives them.
fn parse_time_bounds(b: &[f64]) -> Result<[f64; 2], String> {
    let (t0, t1) = match b {
        [t] => (*t, *t),
        [t0, t1] => (*t0, *t1),
        _ => {
            return Err(format!(
                "need [t_min, t_max] in seconds (or one value, a fixed t_f), got {} values",
                b.len()
            ))
        }
    };
    if !(t0 >= MIN_TIME_FINAL && t0 <= t1 && t1 <= crate::simulate::MAX_T_MAX) {
        return Err(format!(
            "need {MIN_TIME_FINAL} ≤ t_min ≤ t_max ≤ {} (seconds: a push-off lasts tenths of a second), got [{}, {}]",
            crate::simulate::MAX_T_MAX,
            crate::io::readable(t0),
            crate::io::readable(t1)
        ));
    }
    Ok([t0, t1])
}

/// Settings of direct shooting.
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ShootingSpec {
    /// Dormand–Prince accuracy (relative and absolute), in [1e-12, 1e-4]
    /// (default 1e-8).
    #[serde(default)]
    pub integrator_accuracy: Option<f64>,
    /// Central-difference step in the excitations (t_f: this times t_f),
    /// in (0, 0.1) (default 1e-3); central differences only.
    #[serde(default)]
    pub finite_difference_step: Option<f64>,
    /// "forward-sensitivity" (default) or "central-difference" (the
    /// paper's) ([`crate::shooting::ShootingDerivatives`]).
    #[serde(default)]
    pub derivatives: Option<String>,
}

/// Stopping rules of the optimizer (Moco's names; −1 means the default,
/// as in Moco).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TolerancesSpec {
    #[serde(default)]
    pub optim_convergence_tolerance: Option<f64>,
    #[serde(default)]
    pub optim_constraint_tolerance: Option<f64>,
    #[serde(default, alias = "optim_max_iterations")]
    pub max_iterations: Option<i64>,
    /// Also stop when |Δf| < 1e-6 (1 + |f|) with the constraints within
    /// 1e-3 (Porsa et al. 2016's criterion, with which the paper counted
    /// its 702 iterations). Default true: the SQP's KKT test
    /// (`optim_convergence_tolerance`) still ends the solve first if met.
    #[serde(default)]
    pub paper_criterion: Option<bool>,
    /// Stop as restoration failed after this many iterations without
    /// progress (`SqpSettings::stall_iterations`: the violation above 1e-3
    /// and falling less than 10%, the objective flat); 0 turns the test
    /// off, −1 keeps the default 50.
    #[serde(default)]
    pub stall_iterations: Option<i64>,
}

/// Heuristics of the SQP's filter line search that leap leaves off by
/// default and a study may turn on ([`SqpSettings::max_filter_resets`],
/// [`SqpSettings::second_order_correction_every_rejected_step`]): together
/// they solve `models/jump_gait2392.json`, whose 28 intervals cycle without
/// them, but the reduced Hermite–Simpson jump stopped at its iteration limit
/// with them (docs/sqp.md).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LineSearchSpec {
    /// Filter resets allowed per solve (IPOPT's `max_filter_resets`;
    /// default 0, none; −1 the default).
    #[serde(default)]
    pub max_filter_resets: Option<i64>,
    /// Successive line searches whose last rejected trial a filter entry
    /// dominated before a reset (IPOPT's `filter_reset_trigger`; default 5,
    /// at least 1; −1 the default).
    #[serde(default)]
    pub filter_reset_trigger: Option<i64>,
    /// A second-order correction for every rejected full step, not only for
    /// one that raised the violation (default false).
    #[serde(default)]
    pub second_order_correction_every_rejected_step: Option<bool>,
}

/// The forward check: the optimal excitations integrated from the squat
/// with a Simbody integrator (OpenSim's names) and with the Rust-native
/// Dormand–Prince 5(4).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ForwardCheckSpec {
    /// Default true.
    #[serde(default)]
    pub enabled: Option<bool>,
    /// Simbody integrator (default "RungeKuttaMerson", OpenSim's default).
    #[serde(default)]
    pub integrator: Option<String>,
    /// Integrator accuracy (default 1e-5, OpenSim's): a relative error
    /// tolerance in [1e-12, 1e-2], or ExplicitEuler's fixed step
    /// ([`crate::simulate::check_integrator_accuracy`]).
    #[serde(default)]
    pub accuracy: Option<f64>,
}

/// Where the initial guess comes from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum GuessChoice {
    /// The bang-bang excitations integrated on the mesh
    /// ([`crate::transcription::Transcription::integrate_on_mesh`]).
    BangBang,
    /// The continuous bang-bang jump resampled onto the mesh.
    BangBangResampled,
    File(PathBuf),
}

/// The guess named in a study file or on the command line: "bang-bang",
/// "bang-bang-resampled", or else a file.
fn parse_guess(g: &str, path: PathBuf) -> Result<GuessChoice, String> {
    match g {
        "bang-bang" => Ok(GuessChoice::BangBang),
        "bang-bang-resampled" => Ok(GuessChoice::BangBangResampled),
        _ => match crate::io::input_file_problem(&path) {
            None => Ok(GuessChoice::File(path)),
            Some(why) => Err(format!(
                "guess file '{}' {why} (use \"bang-bang\", \"bang-bang-resampled\" or a .sto file)",
                path.display()
            )),
        },
    }
}

/// Whether a guess's excitations can be integrated on the mesh on request:
/// only a file's (the bang-bang guess always is, its resampled form never).
fn check_integrate_guess(guess: &GuessChoice) -> Result<(), String> {
    match guess {
        GuessChoice::File(_) => Ok(()),
        GuessChoice::BangBang => Err(
            "applies to a guess file; the guess 'bang-bang' is integrated on the mesh already"
                .into(),
        ),
        GuessChoice::BangBangResampled => Err(
            "applies to a guess file; the guess 'bang-bang-resampled' is the bang-bang jump not integrated on the mesh ('bang-bang' is)"
                .into(),
        ),
    }
}

/// The forward check, resolved.
#[derive(Debug, Clone, Copy)]
pub struct ForwardCheck {
    pub integrator: SimbodyIntegrator,
    pub accuracy: f64,
}

/// A study with defaults filled in, paths resolved and values checked.
#[derive(Debug, Clone)]
pub struct SolveConfig {
    /// The study file it came from (None: the built-in study).
    pub study_file: Option<PathBuf>,
    pub name: String,
    pub model: PathBuf,
    pub method: Method,
    /// The mesh of either method (`num_mesh_intervals`); the scheme and
    /// fibre dynamics are collocation's.
    pub transcription: TranscriptionOptions,
    /// Method "shooting"'s settings (its intervals are the mesh's).
    pub shooting: crate::shooting::ShootingOptions,
    pub guess: GuessChoice,
    /// A guess file's excitations integrated on the mesh
    /// ([`SolveStudy::integrate_guess`]).
    pub integrate_guess: bool,
    /// The jump problem's settings (`problem` in the study).
    pub problem: ProblemSettings,
    pub settings: SqpSettings,
    pub output_directory: PathBuf,
    /// None: skipped.
    pub forward_check: Option<ForwardCheck>,
    /// Whether the study named `hessian_eigenvalue_floor` (else a scheme
    /// given on the command line brings its own default floor).
    pub eigenvalue_floor_given: bool,
    /// Whether the study named `hessian` (else `--method` brings the
    /// method's default: exact for collocation, BFGS for shooting).
    pub hessian_given: bool,
    /// Settings the study names that the method does not use (a
    /// collocation study solved with `--method shooting`); `leap solve`
    /// lists them.
    pub ignored: Vec<String>,
    /// Study settings that a command-line option changed with it (the
    /// study's implicit fibre rows under `--scheme trapezoidal`), in words;
    /// `leap solve` says them.
    pub switched: Vec<String>,
    /// The collocation-only settings the study names (fields), for
    /// `ignored` when `--method shooting` overrides it.
    collocation_named: Vec<&'static str>,
    /// Raised when the solve starts writing its results (set by `leap
    /// solve`, whose Ctrl-C handler then lets them be finished).
    pub writing: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

/// Command-line overrides of a study (`leap solve --...`); paths relative
/// to the working directory.
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    pub output_directory: Option<PathBuf>,
    /// "collocation" or "shooting".
    pub method: Option<String>,
    pub num_mesh_intervals: Option<i64>,
    pub max_iterations: Option<i64>,
    /// "bang-bang" or a file.
    pub guess: Option<String>,
    /// `--integrate-guess`.
    pub integrate_guess: bool,
    pub scheme: Option<String>,
    pub fiber_dynamics: Option<String>,
    pub hessian: Option<String>,
    /// "rust-native" or "simbody".
    pub backend: Option<String>,
    pub no_forward_check: bool,
    /// `--dump-qps`.
    pub dump_qps: bool,
}

/// Read a study file of any kind (`leap solve`'s, `leap simulate`'s): one
/// JSON object, its errors naming the file and the field's JSON path.
pub fn read_study<T: serde::de::DeserializeOwned + Serialize + StudyKind>(
    path: &Path,
) -> Result<T, StudyError> {
    let text = crate::io::read_input_text(path).map_err(|error| StudyError::Io {
        file: path.into(),
        error,
    })?;
    parse_study(&text, &path.display().to_string())
}

/// Parse study JSON (one object); `origin` names it in errors.
pub fn parse_study<T: serde::de::DeserializeOwned + Serialize + StudyKind>(
    text: &str,
    origin: &str,
) -> Result<T, StudyError> {
    parse_json_object(text).map_err(|e| {
        // A file of another kind gets that hint alone: its fields are not
        // misplaced in this one.
        let hinted = with_kind_hint(text, T::KIND, e.reason.clone());
        let reason = match misplaced_field_hint(&T::fields(), &e.path, &e.reason) {
            Some(hint) if hinted == e.reason => format!("{hinted}; {hint}"),
            _ => hinted,
        };
        StudyError::Field {
            origin: origin.into(),
            field: e.path,
            reason,
        }
    })
}

/// The kind of a study file ("solve", "simulate"), for [`parse_study`]'s
/// hint where a file of another kind is given.
pub trait StudyKind {
    const KIND: &'static str;
    /// Every field the study reads, as a JSON object of its nesting (the
    /// values do not matter), for [`misplaced_field_hint`].
    fn fields() -> serde_json::Value;
}

impl StudyKind for SolveStudy {
    const KIND: &'static str = "solve";
    fn fields() -> serde_json::Value {
        let mut v = serde_json::to_value(SolveStudy::default()).unwrap_or_default();
        // The second names (`#[serde(alias)]`), which serialising omits:
        // Moco's top-level `transcription_scheme` is read under `mesh`.
        for (section, alias) in [
            ("", "guess_file"),
            ("", "results_directory"),
            ("mesh", "transcription_scheme"),
            ("tolerances", "optim_max_iterations"),
            ("problem", "final_time_bounds"),
        ] {
            let m = if section.is_empty() {
                v.as_object_mut()
            } else {
                v.get_mut(section).and_then(|s| s.as_object_mut())
            };
            if let Some(m) = m {
                m.insert(alias.into(), serde_json::Value::Null);
            }
        }
        v
    }
}

/// Where an unknown field at `path` (dotted, ending in the field) belongs
/// instead, when the study reads a field of that name elsewhere in
/// `fields` ([`StudyKind::fields`]): a top-level `num_mesh_intervals` is
/// read under `mesh`, a `guess` under `mesh` at the top level.
pub(crate) fn misplaced_field_hint(
    fields: &serde_json::Value,
    path: &str,
    reason: &str,
) -> Option<String> {
    let key = reason.strip_prefix("unknown field `")?.split('`').next()?;
    fn find(v: &serde_json::Value, key: &str, at: &str, out: &mut Vec<String>) {
        if let Some(map) = v.as_object() {
            for (k, child) in map {
                let here = if at.is_empty() {
                    k.clone()
                } else {
                    format!("{at}.{k}")
                };
                if k == key {
                    out.push(here.clone());
                }
                find(child, key, &here, out);
            }
        }
    }
    let mut found = Vec::new();
    find(fields, key, "", &mut found);
    found.retain(|f| f != path);
    let place = |f: &String| match f.rsplit_once('.') {
        Some((parent, _)) => format!("under \"{parent}\" ({f})"),
        None => "at the top level of the study".to_string(),
    };
    (!found.is_empty()).then(|| {
        format!(
            "`{key}` belongs {}",
            found.iter().map(place).collect::<Vec<_>>().join(" or ")
        )
    })
}

/// `reason`, the refusal of `text` read as a file of kind `expected`
/// ("model", "solve", "simulate"), with a hint where it is an unknown field
/// and the file looks like one of another kind.
pub(crate) fn with_kind_hint(text: &str, expected: &str, reason: String) -> String {
    match file_kind(text) {
        Some((kind, hint)) if kind != expected && reason.starts_with("unknown field") => {
            let given_as = if expected == "model" {
                ", not as a model (--model, or a study's \"model\")"
            } else {
                ""
            };
            format!("{reason}; {hint}{given_as}")
        }
        _ => reason,
    }
}

/// What kind of leap file the JSON object `text` looks like, by its
/// top-level keys, when a study refused one of them: a model, a `leap
/// solve` study or a `leap simulate` study (None for neither), with a
/// hint for the user.
fn file_kind(text: &str) -> Option<(&'static str, &'static str)> {
    let v: serde_json::Value = serde_json::from_str(text).ok()?;
    let has = |keys: &[&str]| keys.iter().filter(|k| v.get(**k).is_some()).count();
    let model = has(&[
        "bodies",
        "joints",
        "coordinates",
        "forces",
        "credits",
        "gravity",
    ]);
    let solve = has(&[
        "mesh",
        "tolerances",
        "line_search",
        "method",
        "guess",
        "hessian",
        "shooting",
        "problem",
        "forward_check",
        "qp_solver",
        "description",
    ]);
    let simulate = has(&[
        "t_max",
        "bang_bang",
        "controls",
        "integrator",
        "accuracy",
        "report_interval",
        "out",
    ]);
    if model >= 2 && model > solve.max(simulate) {
        Some(("model", "this looks like a model file (it has bodies, joints, forces), not a study: name it as a study's model or with --model"))
    } else if solve > simulate && solve >= 2 {
        Some(("solve", "this looks like a `leap solve` study file (mesh, tolerances, guess, ...): give it to `leap solve`"))
    } else if simulate > solve && simulate >= 2 {
        Some(("simulate", "this looks like a `leap simulate` study file (t_max, integrator, bang_bang, ...): give it to `leap simulate --study`"))
    } else {
        None
    }
}

impl SolveStudy {
    /// Read a study file (unknown fields and wrong types are errors naming
    /// the JSON path).
    pub fn from_file(path: &Path) -> Result<Self, StudyError> {
        read_study(path)
    }

    /// Parse study JSON (one object); `origin` names it in errors.
    pub fn from_json_str(text: &str, origin: &str) -> Result<Self, StudyError> {
        parse_study(text, origin)
    }

    /// Fill in the defaults, resolve paths against the directory of
    /// `file` (the study's own file, None for the built-in study) and check
    /// every value.
    pub fn resolve(&self, file: Option<&Path>) -> Result<SolveConfig, StudyError> {
        self.resolve_with_model(file, None)
    }

    /// [`Self::resolve`], with the model file named on the command line
    /// (`--model`, relative to the working directory) in place of the
    /// study's `model`.
    pub fn resolve_with_model(
        &self,
        file: Option<&Path>,
        model_override: Option<&Path>,
    ) -> Result<SolveConfig, StudyError> {
        let origin = file
            .map(|p| p.display().to_string())
            .unwrap_or_else(|| "built-in study".into());
        let err = |field: &str, reason: String| StudyError::Field {
            origin: origin.clone(),
            field: field.into(),
            reason,
        };
        let base = file
            .and_then(|p| p.parent())
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let rel = |s: &str| base.join(s);
        for (field, path) in [
            ("model", &self.model),
            ("guess", &self.guess),
            ("output_directory", &self.output_directory),
        ] {
            if let Some(why) = path.as_deref().and_then(crate::io::path_text_problem) {
                return Err(err(field, why));
            }
        }

        let name = self.name.clone().unwrap_or_else(|| "jump".into());
        check_name(&name).map_err(|r| err("name", r))?;

        let method = parse_method(self.method.as_deref().unwrap_or("collocation"))
            .map_err(|r| err("method", r))?;
        if method == Method::Collocation && self.shooting != ShootingSpec::default() {
            return Err(err(
                "shooting",
                "applies to method 'shooting'; this study's method is 'collocation'".into(),
            ));
        }
        let mut shooting = crate::shooting::ShootingOptions::default();
        if let Some(a) = self.shooting.integrator_accuracy {
            if !(a.is_finite() && (1e-12..=1e-4).contains(&a)) {
                return Err(err(
                    "shooting.integrator_accuracy",
                    format!("must lie in [1e-12, 1e-4], got {}: the derivatives' error follows the integration's", crate::io::readable(a)),
                ));
            }
            shooting.accuracy = a;
        }
        if let Some(d) = self.shooting.derivatives.as_deref() {
            shooting.derivatives =
                parse_shooting_derivatives(d).map_err(|r| err("shooting.derivatives", r))?;
        }
        if let Some(d) = self.shooting.finite_difference_step {
            if shooting.derivatives != crate::shooting::ShootingDerivatives::CentralDifference {
                return Err(err(
                    "shooting.finite_difference_step",
                    format!(
                        "applies to derivatives 'central-difference' only, not '{}'{}",
                        shooting.derivatives.name(),
                        if self.shooting.derivatives.is_none() {
                            " (the default); add \"derivatives\": \"central-difference\" for the paper's central differences"
                        } else {
                            ""
                        }
                    ),
                ));
            }
            if !(d.is_finite() && d > 0.0 && d < 0.1) {
                return Err(err(
                    "shooting.finite_difference_step",
                    format!("must lie in (0, 0.1), got {}", crate::io::readable(d)),
                ));
            }
            shooting.finite_difference_step = d;
        }
        let resampled = self.guess.as_deref() == Some("bang-bang-resampled");
        let mut collocation_named = Vec::new();
        for (given, field) in [
            (self.mesh.scheme.is_some(), "mesh.scheme"),
            (self.mesh.fiber_dynamics.is_some(), "mesh.fiber_dynamics"),
            (
                self.backend.as_deref().map(parse_backend) == Some(Ok(Backend::Simbody)),
                "backend",
            ),
            (resampled, "guess"),
            (self.integrate_guess == Some(true), "integrate_guess"),
            (
                self.hessian.as_deref().is_some_and(|h| h != "bfgs"),
                "hessian",
            ),
            (
                self.hessian_eigenvalue_floor.is_some(),
                "hessian_eigenvalue_floor",
            ),
        ] {
            if given {
                if method == Method::Shooting {
                    let reason = if field.starts_with("hessian") {
                        NO_EXACT_HESSIAN
                    } else {
                        COLLOCATION_ONLY
                    };
                    return Err(err(field, reason.into()));
                }
                collocation_named.push(field);
            }
        }

        let model = match (model_override, &self.model) {
            (Some(p), _) => {
                if let Some(why) = crate::io::input_file_problem(p) {
                    return Err(StudyError::Field {
                        origin: "command line".into(),
                        field: "--model".into(),
                        reason: format!("model file '{}' {why}", p.display()),
                    });
                }
                p.to_path_buf()
            }
            (None, Some(m)) => {
                let p = rel(m);
                if let Some(why) = crate::io::input_file_problem(&p) {
                    return Err(err("model", format!("model file '{}' {why}", p.display())));
                }
                p
            }
            (None, None) => default_model()
                .ok_or_else(|| err("model", format!("the default model '{DEFAULT_MODEL}' is found neither in the working directory nor in leap's source tree; name one")))?,
        };

        let mut transcription = TranscriptionOptions::default();
        if let Some(n) = self.mesh.num_mesh_intervals {
            transcription.num_mesh_intervals =
                check_mesh_intervals(n).map_err(|r| err("mesh.num_mesh_intervals", r))?;
        }
        if let Some(s) = &self.mesh.scheme {
            transcription.scheme = parse_scheme(s).map_err(|r| err("mesh.scheme", r))?;
        }
        transcription.fiber_dynamics = default_fiber_dynamics(transcription.scheme);
        if let Some(s) = &self.mesh.fiber_dynamics {
            transcription.fiber_dynamics =
                parse_fiber_dynamics(s).map_err(|r| err("mesh.fiber_dynamics", r))?;
        }
        check_fiber_dynamics(&transcription).map_err(|r| err("mesh.fiber_dynamics", r))?;
        if let Some(b) = &self.backend {
            transcription.backend = parse_backend(b).map_err(|r| err("backend", r))?;
        }

        let guess = match self.guess.as_deref() {
            None => GuessChoice::BangBang,
            Some(g) => parse_guess(g, rel(g)).map_err(|r| err("guess", r))?,
        };
        let integrate_guess = self.integrate_guess.unwrap_or(false);
        if integrate_guess {
            check_integrate_guess(&guess).map_err(|r| err("integrate_guess", r))?;
        }

        let mut problem = ProblemSettings::default();
        let p = &self.problem;
        if let Some(b) = &p.time_final_bounds {
            problem.final_time_bounds =
                parse_time_bounds(b).map_err(|r| err("problem.time_final_bounds", r))?;
        }
        if let Some(n) = p.no_countermovement_nodes {
            problem.no_countermovement_nodes = check_count(n, 0, ", 0 states none")
                .map_err(|r| err("problem.no_countermovement_nodes", r))?;
        }
        problem
            .check_mesh(transcription.num_mesh_intervals)
            .map_err(|r| err("problem.no_countermovement_nodes", r))?;
        if let Some(d) = p.no_com_descent {
            problem.no_com_descent = d;
        }
        if let Some(b) = p.activation_dynamics_smoothing {
            let [lo, hi] = ACTIVATION_SMOOTHING_RANGE;
            if !(b.is_finite() && (lo..=hi).contains(&b)) {
                return Err(err(
                    "problem.activation_dynamics_smoothing",
                    format!(
                        "need {lo} ≤ b ≤ {hi} (the switch ½ + ½·tanh(b·(u − a)); default {}), got {}",
                        crate::ocp::DEFAULT_ACTIVATION_SMOOTHING,
                        crate::io::readable(b)
                    ),
                ));
            }
            problem.activation_dynamics_smoothing = Some(b);
        }

        // The jump's variables range from centimetres (fibre lengths) to
        // tens of rad/s (speeds): the SQP works in variables scaled by
        // their bounds (Moco's scale_variables_using_bounds).
        //
        // Exact element Hessians: from the bang-bang guess they reach the
        // objective that partitioned BFGS reaches in 400 iterations in about
        // 40 (`HESSIAN=exact EIGFLOOR=1e-4 cargo run --release --example
        // jump_diag -- 28 400` against the same without HESSIAN). Their
        // eigenvalue floor is 1e-4 of each element's largest eigenvalue: at
        // the SQP's default 1e-8 the first QPs (λ = 0, so the Hessian is
        // nearly the floor alone) fail in clarabel. Hermite–Simpson takes
        // its own ([`default_eigenvalue_floor`]).
        // Leap's interior-point QP solver by default (clarabel where it
        // fails): with implicit fibre dynamics the 28-interval jump solved
        // in 216 iterations, 113 s, against clarabel's 189, 290 s.
        let mut settings = SqpSettings {
            scale_variables_using_bounds: true,
            hessian: HessianMode::ExactConvexified,
            eigenvalue_floor: default_eigenvalue_floor(transcription.scheme),
            paper_criterion: true,
            qp_solver: QpSolver::InteriorPoint,
            ..Default::default()
        };
        let t = &self.tolerances;
        if let Some(v) = t.optim_convergence_tolerance {
            if let Some(v) =
                check_tolerance(v).map_err(|r| err("tolerances.optim_convergence_tolerance", r))?
            {
                settings.optim_convergence_tolerance = v;
            }
        }
        if let Some(v) = t.optim_constraint_tolerance {
            if let Some(v) =
                check_tolerance(v).map_err(|r| err("tolerances.optim_constraint_tolerance", r))?
            {
                settings.optim_constraint_tolerance = v;
            }
        }
        if let Some(v) = t.max_iterations {
            if let Some(v) =
                check_max_iterations(v).map_err(|r| err("tolerances.max_iterations", r))?
            {
                settings.max_iterations = v;
            }
        }
        if let Some(p) = t.paper_criterion {
            settings.paper_criterion = p;
        }
        if let Some(v) = t.stall_iterations {
            if let Some(v) = check_count(v, 0, ", 0 turns the test off")
                .map_err(|r| err("tolerances.stall_iterations", r))?
            {
                settings.stall_iterations = v;
            }
        }
        let ls = &self.line_search;
        if let Some(v) = ls.max_filter_resets {
            if let Some(v) = check_count(v, 0, ", 0 allows none")
                .map_err(|r| err("line_search.max_filter_resets", r))?
            {
                settings.max_filter_resets = v;
            }
        }
        if let Some(v) = ls.filter_reset_trigger {
            if let Some(v) =
                check_count(v, 1, "").map_err(|r| err("line_search.filter_reset_trigger", r))?
            {
                settings.filter_reset_trigger = v;
            }
        }
        if ls.filter_reset_trigger.is_some_and(|v| v != -1) && settings.max_filter_resets == 0 {
            return Err(err(
                "line_search.filter_reset_trigger",
                "has no effect while max_filter_resets is 0 (the default): allow resets with line_search.max_filter_resets, or remove filter_reset_trigger".into(),
            ));
        }
        if let Some(v) = ls.second_order_correction_every_rejected_step {
            settings.second_order_correction_every_rejected_step = v;
        }
        if method == Method::Shooting {
            settings.hessian = HessianMode::PartitionedBfgs;
        }
        check_method_mesh(method, transcription.num_mesh_intervals)
            .map_err(|r| err("mesh.num_mesh_intervals", r))?;
        if let Some(h) = &self.hessian {
            apply_hessian(&mut settings, h).map_err(|r| err("hessian", r))?;
            check_method_hessian(method, &settings).map_err(|r| err("hessian", r))?;
        }
        if let Some(v) = self.hessian_eigenvalue_floor {
            if !(v.is_finite() && v > 0.0 && v < 1.0) {
                return Err(err(
                    "hessian_eigenvalue_floor",
                    format!(
                        "{} is not a relative floor in (0, 1)",
                        crate::io::readable(v)
                    ),
                ));
            }
            settings.eigenvalue_floor = v;
        }
        if let Some(q) = &self.qp_solver {
            settings.qp_solver = match q.as_str() {
                "interior-point" => QpSolver::InteriorPoint,
                "clarabel" if settings.convexification == Convexification::InertiaCorrection => {
                    return Err(err(
                        "qp_solver",
                        "clarabel needs convex QPs; hessian 'exact-inertia-corrected' needs 'interior-point'".into(),
                    ))
                }
                "clarabel" => QpSolver::Clarabel,
                other => {
                    return Err(err(
                        "qp_solver",
                        format!(
                            "unknown QP solver '{other}' (expected 'interior-point' or 'clarabel')"
                        ),
                    ))
                }
            };
        }

        let output_directory = match &self.output_directory {
            Some(d) if d.is_empty() => {
                return Err(err(
                    "output_directory",
                    "empty: name a directory ('.' for the study file's own)".into(),
                ))
            }
            Some(d) => rel(d),
            None => PathBuf::from(DEFAULT_OUTPUT_DIRECTORY),
        };

        // A disabled check's settings are checked too: a slip in them is
        // found before it is turned on (as with `--no-forward-check`).
        let fc = &self.forward_check;
        let forward_check = {
            let integrator = match fc.integrator.as_deref() {
                None => SimbodyIntegrator::RungeKuttaMerson,
                Some(s) => match parse_integrator(s) {
                    Ok(IntegratorChoice::Simbody(i)) => i,
                    Ok(IntegratorChoice::DormandPrince) => return Err(err(
                        "forward_check.integrator",
                        "the Rust-native Dormand-Prince runs anyway; name a Simbody integrator (RungeKuttaMerson, RungeKuttaFeldberg, RungeKutta3, CPodes, ExplicitEuler)".into(),
                    )),
                    Err(r) => return Err(err("forward_check.integrator", r)),
                },
            };
            let accuracy = fc.accuracy.unwrap_or(1e-5);
            // t_max is t_f + the flight, unknown before the solve.
            check_integrator_accuracy(accuracy, &IntegratorChoice::Simbody(integrator), None)
                .map_err(|r| err("forward_check.accuracy", r))?;
            fc.enabled.unwrap_or(true).then_some(ForwardCheck {
                integrator,
                accuracy,
            })
        };

        Ok(SolveConfig {
            study_file: file.map(Path::to_path_buf),
            name,
            model,
            method,
            transcription,
            shooting,
            guess,
            integrate_guess,
            problem,
            settings,
            output_directory,
            forward_check,
            eigenvalue_floor_given: self.hessian_eigenvalue_floor.is_some(),
            hessian_given: self.hessian.is_some(),
            ignored: Vec::new(),
            switched: Vec::new(),
            collocation_named,
            writing: None,
        })
    }
}

impl SolveConfig {
    /// The built-in study: the paper's problem with the defaults.
    pub fn builtin() -> Result<Self, StudyError> {
        SolveStudy::default().resolve(None)
    }

    /// Read and resolve a study file, or the built-in study.
    pub fn load(file: Option<&Path>) -> Result<Self, StudyError> {
        Self::load_with_model(file, None)
    }

    /// [`Self::load`], with the model file named on the command line
    /// (`--model`) in place of the study's.
    pub fn load_with_model(file: Option<&Path>, model: Option<&Path>) -> Result<Self, StudyError> {
        match file {
            Some(p) => SolveStudy::from_file(p)?.resolve_with_model(Some(p), model),
            None => SolveStudy::default().resolve_with_model(None, model),
        }
    }

    /// Apply command-line overrides; errors name the option.
    pub fn apply(&mut self, o: &Overrides) -> Result<(), StudyError> {
        let err = |field: &str, reason: String| StudyError::Field {
            origin: "command line".into(),
            field: field.into(),
            reason,
        };
        if let Some(d) = &o.output_directory {
            self.output_directory = d.clone();
        }
        if let Some(m) = &o.method {
            let method = parse_method(m).map_err(|r| err("--method", r))?;
            if method != self.method {
                self.method = method;
                if !self.hessian_given && o.hessian.is_none() {
                    self.settings.hessian = match method {
                        Method::Collocation => HessianMode::ExactConvexified,
                        Method::Shooting => HessianMode::PartitionedBfgs,
                    };
                }
                if method == Method::Shooting {
                    // The study's collocation settings: listed, not used.
                    self.ignored = self
                        .collocation_named
                        .iter()
                        .map(|f| f.to_string())
                        .collect();
                    if self.ignored.iter().any(|f| f == "hessian") && o.hessian.is_none() {
                        self.settings.hessian = HessianMode::PartitionedBfgs;
                    }
                    if self.guess == GuessChoice::BangBangResampled {
                        self.guess = GuessChoice::BangBang;
                    }
                    self.integrate_guess = false;
                }
            }
        }
        if self.method == Method::Shooting {
            let resampled = o.guess.as_deref() == Some("bang-bang-resampled");
            for (given, option) in [
                (o.scheme.is_some(), "--scheme"),
                (o.fiber_dynamics.is_some(), "--fiber-dynamics"),
                (
                    o.backend.as_deref().map(parse_backend) == Some(Ok(Backend::Simbody)),
                    "--backend",
                ),
                (resampled, "--guess"),
                (o.integrate_guess, "--integrate-guess"),
            ] {
                if given {
                    return Err(err(option, COLLOCATION_ONLY.into()));
                }
            }
        }
        if let Some(n) = o.num_mesh_intervals {
            self.transcription.num_mesh_intervals =
                check_mesh_intervals(n).map_err(|r| err("--num-mesh-intervals", r))?;
            self.problem
                .check_mesh(self.transcription.num_mesh_intervals)
                .map_err(|r| {
                    err(
                        "--num-mesh-intervals",
                        format!("the study's problem.no_countermovement_nodes: {r}"),
                    )
                })?;
        }
        if let Some(n) = o.max_iterations {
            if let Some(n) = check_max_iterations(n).map_err(|r| err("--max-iterations", r))? {
                self.settings.max_iterations = n;
            }
        }
        if let Some(s) = &o.scheme {
            self.transcription.scheme = parse_scheme(s).map_err(|r| err("--scheme", r))?;
            // Implicit rows exist at midpoints only: another scheme on the
            // command line brings the explicit rows with it.
            if self.transcription.scheme != Scheme::MidpointEuler {
                let named = self.collocation_named.contains(&"mesh.fiber_dynamics");
                if named
                    && o.fiber_dynamics.is_none()
                    && self.transcription.fiber_dynamics == FiberDynamics::Implicit
                {
                    self.switched.push(format!(
                        "the study's mesh.fiber_dynamics \"implicit\" becomes \"explicit\" with --scheme {s} (implicit fibre rows exist with midpoint-euler only; give --fiber-dynamics explicit to choose it and silence this)"
                    ));
                }
                self.transcription.fiber_dynamics = FiberDynamics::Explicit;
            }
            if !self.eigenvalue_floor_given {
                self.settings.eigenvalue_floor =
                    default_eigenvalue_floor(self.transcription.scheme);
            }
        }
        if let Some(s) = &o.fiber_dynamics {
            self.transcription.fiber_dynamics =
                parse_fiber_dynamics(s).map_err(|r| err("--fiber-dynamics", r))?;
        }
        check_fiber_dynamics(&self.transcription).map_err(|r| err("--fiber-dynamics", r))?;
        if let Some(b) = &o.backend {
            self.transcription.backend = parse_backend(b).map_err(|r| err("--backend", r))?;
        }
        if let Some(h) = &o.hessian {
            apply_hessian(&mut self.settings, h).map_err(|r| err("--hessian", r))?;
        }
        check_method_hessian(self.method, &self.settings).map_err(|r| {
            err(
                if o.hessian.is_some() {
                    "--hessian"
                } else {
                    "--method"
                },
                r,
            )
        })?;
        check_method_mesh(self.method, self.transcription.num_mesh_intervals).map_err(|r| {
            err(
                if o.num_mesh_intervals.is_some() {
                    "--num-mesh-intervals"
                } else {
                    "--method"
                },
                r,
            )
        })?;
        if let Some(g) = &o.guess {
            self.guess = parse_guess(g, PathBuf::from(g)).map_err(|r| err("--guess", r))?;
            // A bang-bang guess on the command line replaces the study's
            // file, and with it the file's integrate_guess.
            if !matches!(self.guess, GuessChoice::File(_)) && !o.integrate_guess {
                self.integrate_guess = false;
            }
        }
        if o.integrate_guess {
            self.integrate_guess = true;
        }
        if self.integrate_guess {
            check_integrate_guess(&self.guess).map_err(|r| err("--integrate-guess", r))?;
        }
        if o.no_forward_check {
            self.forward_check = None;
        }
        if o.dump_qps {
            self.settings.qp_dump_dir = Some(self.output_directory.join("qps"));
            self.settings.qp_dump_every = true;
        }
        Ok(())
    }
}

/// The default model: `models/jumper.json` in the working directory, else
/// in the crate's source tree (`leap solve`'s and `leap simulate`'s).
pub fn default_model() -> Option<PathBuf> {
    let here = PathBuf::from(DEFAULT_MODEL);
    if here.is_file() {
        return Some(here);
    }
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join(DEFAULT_MODEL);
    src.is_file().then_some(src)
}

/// The longest study name: its files' names (`<name>_forward_controls.sto`,
/// the longest suffix, 21 bytes) stay far below the 255 bytes of a file
/// name.
const MAX_NAME_LEN: usize = 100;

fn check_name(name: &str) -> Result<(), String> {
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.')
    {
        let shown: String = name.chars().take(MAX_NAME_LEN).collect();
        return Err(format!(
            "'{shown}' must be a non-empty file prefix of letters, digits, '_', '-' or '.'"
        ));
    }
    if name.len() > MAX_NAME_LEN {
        return Err(format!(
            "{} characters; at most {MAX_NAME_LEN} (the prefix of the result files' names)",
            name.len()
        ));
    }
    if name.starts_with('.') {
        return Err(format!(
            "'{name}' starts with '.', which would hide the result files"
        ));
    }
    // `leap simulate` writes forward_*.sto, _grf.mot and _summary.json into
    // the same default directory.
    if name == SIMULATE_FILE_PREFIX {
        return Err(format!(
            "'{name}' names leap simulate's files (forward_grf.mot, forward_summary.json), which the solve would overwrite; choose another name"
        ));
    }
    // A study's forward check writes <name>_forward_grf.mot: the ground
    // forces file of a study named <name>_forward.
    // (A name of "_forward" alone shadows no study: names are not empty.)
    if let Some(other) = name.strip_suffix("_forward").filter(|o| !o.is_empty()) {
        return Err(format!(
            "'{name}' ends in '_forward': its {name}_grf.mot is the forward check's ground forces file of a study named '{other}', which the solves would overwrite and remove in turn; choose another name"
        ));
    }
    Ok(())
}

/// The prefix of `leap simulate`'s result files (`forward_states.sto`,
/// `forward_controls.sto`, `forward_grf.mot`, `forward_summary.json`):
/// apart from `leap solve`'s `jump_*` in the same default directory, whose
/// `jump_grf.mot` and `jump_summary.json` a simulation had overwritten.
pub const SIMULATE_FILE_PREFIX: &str = "forward";

fn parse_method(method: &str) -> Result<Method, String> {
    match method {
        "collocation" => Ok(Method::Collocation),
        "shooting" => Ok(Method::Shooting),
        other => Err(format!(
            "unknown method '{other}' (valid: {})",
            METHODS.join(", ")
        )),
    }
}

/// A study's shooting derivatives by name.
fn parse_shooting_derivatives(name: &str) -> Result<crate::shooting::ShootingDerivatives, String> {
    use crate::shooting::ShootingDerivatives as D;
    [D::CentralDifference, D::ForwardSensitivity]
        .into_iter()
        .find(|d| d.name() == name)
        .ok_or_else(|| {
            format!("unknown derivatives '{name}' (valid: central-difference, forward-sensitivity)")
        })
}

/// The most mesh intervals method "shooting" takes: its sensitivities of
/// every node's state to every control are dense and grow as N² (one
/// iteration of the reduced model: 0.13 GB at 50 intervals, 0.47 GB at 100,
/// 1.8 GB at 200; an allocation of 2 GB failed at 1000), where
/// collocation's Jacobian grows as N.
pub const MAX_SHOOTING_MESH_INTERVALS: usize = 100;

fn check_method_mesh(method: Method, num_intervals: usize) -> Result<(), String> {
    if method == Method::Shooting && num_intervals > MAX_SHOOTING_MESH_INTERVALS {
        return Err(format!(
            "method 'shooting' takes at most {MAX_SHOOTING_MESH_INTERVALS} mesh intervals, got {num_intervals}: its sensitivities of each node's state to every control grow as N² (1.8 GB at 200 intervals); the paper's shooting used 28"
        ));
    }
    Ok(())
}

/// Shooting has first derivatives only (central differences or forward
/// sensitivities): its Hessian is BFGS.
fn check_method_hessian(method: Method, settings: &SqpSettings) -> Result<(), String> {
    if method == Method::Shooting && settings.hessian != HessianMode::PartitionedBfgs {
        return Err(NO_EXACT_HESSIAN.into());
    }
    Ok(())
}

/// The most mesh intervals a study may ask for, far above any use: the
/// studies in the README use 20-40. Every interval adds a node of 86
/// variables (62 states, 24 excitations); a mistyped count of 10⁵ took
/// gigabytes and minutes before the first iteration, and one near 2⁶³
/// overflowed the allocation.
pub const MAX_NUM_MESH_INTERVALS: i64 = 1000;

/// 2 ≤ N ≤ [`MAX_NUM_MESH_INTERVALS`] uniform mesh intervals.
pub fn check_mesh_intervals(n: i64) -> Result<usize, String> {
    if n < 2 {
        return Err(format!("must be an integer ≥ 2, got {n}"));
    }
    if n > MAX_NUM_MESH_INTERVALS {
        return Err(format!(
            "must be at most {MAX_NUM_MESH_INTERVALS}, got {n}: each interval adds 86 variables, and the studies in the README use 20-40 (the paper's 28)"
        ));
    }
    usize::try_from(n).map_err(|_| format!("{n} is too large"))
}

/// A positive tolerance, or −1 for the default (Moco's convention).
fn check_tolerance(v: f64) -> Result<Option<f64>, String> {
    if v == -1.0 {
        Ok(None)
    } else if v.is_finite() && v > 0.0 && v < 1.0 {
        Ok(Some(v))
    } else if v >= 1.0 {
        Err(format!(
            "must be below 1 (or -1 for the default), got {}: at 1 or more the solve ends at iterates far from optimal or feasible (defects of a metre or radian)",
            crate::io::readable(v)
        ))
    } else {
        Err(format!(
            "must be positive (or -1 for the default), got {}",
            crate::io::readable(v)
        ))
    }
}

/// A positive iteration limit, or −1 for the default (Moco's convention).
fn check_max_iterations(n: i64) -> Result<Option<usize>, String> {
    check_count(n, 1, "")
}

/// A count of at least `min` (`what_min` says what `min` means, if
/// anything), or −1 for the default (None).
fn check_count(n: i64, min: i64, what_min: &str) -> Result<Option<usize>, String> {
    match n {
        -1 => Ok(None),
        n if n >= min => usize::try_from(n)
            .map(Some)
            .map_err(|_| format!("{n} is too large")),
        n => Err(format!(
            "must be ≥ {min}{what_min} (or -1 for the default), got {n}"
        )),
    }
}

/// Fibre dynamics by name ("explicit" or "implicit").
pub fn parse_fiber_dynamics(s: &str) -> Result<FiberDynamics, String> {
    match s {
        "explicit" => Ok(FiberDynamics::Explicit),
        "implicit" => Ok(FiberDynamics::Implicit),
        _ => Err(format!(
            "unknown fibre dynamics '{s}' (valid: explicit, implicit)"
        )),
    }
}

/// The fibre dynamics a scheme gets unless the study names them: implicit
/// for midpoint Euler, explicit for the others (implicit rows are stated at
/// the midpoints). Implicit rows have the same variables and solutions as
/// the paper's explicit ones, and on the default study every mesh of 24-30
/// intervals solved (112-829 iterations) where the explicit rows solved two
/// of four (810 and 954 iterations; `leap bench solve --num-mesh-intervals
/// 24,26,28,30`, docs/implicit-fibre-dynamics.md).
pub fn default_fiber_dynamics(scheme: Scheme) -> FiberDynamics {
    if scheme == Scheme::MidpointEuler {
        FiberDynamics::Implicit
    } else {
        FiberDynamics::Explicit
    }
}

/// Implicit fibre dynamics are stated at the midpoints of midpoint Euler.
pub fn check_fiber_dynamics(t: &TranscriptionOptions) -> Result<(), String> {
    if t.fiber_dynamics == FiberDynamics::Implicit && t.scheme != Scheme::MidpointEuler {
        return Err(format!(
            "implicit fibre dynamics need the midpoint-euler scheme, not {}",
            scheme_name(t.scheme)
        ));
    }
    Ok(())
}

/// A points backend by name ("rust-native" or "simbody").
pub fn parse_backend(s: &str) -> Result<Backend, String> {
    match s {
        "rust-native" => Ok(Backend::RustNative),
        "simbody" => Ok(Backend::Simbody),
        _ => Err(format!(
            "unknown backend '{s}' (valid: rust-native, simbody)"
        )),
    }
}

/// The name of a points backend.
pub fn backend_name(b: Backend) -> &'static str {
    match b {
        Backend::RustNative => "rust-native",
        Backend::Simbody => "simbody",
    }
}

/// The name of a fibre dynamics form.
pub fn fiber_dynamics_name(f: FiberDynamics) -> &'static str {
    match f {
        FiberDynamics::Explicit => "explicit",
        FiberDynamics::Implicit => "implicit",
    }
}

/// A scheme by name.
pub fn parse_scheme(s: &str) -> Result<Scheme, String> {
    SCHEMES
        .iter()
        .find(|(n, _)| *n == s)
        .map(|(_, sch)| *sch)
        .ok_or_else(|| {
            format!(
                "unknown scheme '{s}' (valid: {})",
                SCHEMES.map(|(n, _)| n).join(", ")
            )
        })
}

/// The name of a scheme.
pub fn scheme_name(s: Scheme) -> &'static str {
    SCHEMES
        .iter()
        .find(|(_, sch)| *sch == s)
        .map(|(n, _)| *n)
        .unwrap_or("?")
}

/// The Hessian of `settings` as a study names it ([`apply_hessian`]'s
/// inverse): "exact", "exact-block-diagonal", "exact-inertia-corrected" or
/// "bfgs" ("exact-absolute" for the library's mirrored eigenvalues, which
/// no study sets).
pub fn hessian_option_name(settings: &SqpSettings) -> &'static str {
    match (settings.hessian, settings.convexification) {
        (HessianMode::PartitionedBfgs, _) => "bfgs",
        (HessianMode::ExactConvexified, Convexification::InertiaCorrection) => {
            "exact-inertia-corrected"
        }
        (HessianMode::ExactConvexified, _) if settings.block_diagonal_elements => {
            "exact-block-diagonal"
        }
        (HessianMode::ExactConvexified, Convexification::Absolute) => "exact-absolute",
        (HessianMode::ExactConvexified, Convexification::Clip) => "exact",
    }
}

/// A study's Hessian choice: "exact", "exact-block-diagonal" (exact, with
/// the transcription's block-diagonal approximation,
/// [`SqpSettings::block_diagonal_elements`]), "exact-inertia-corrected"
/// (the element Hessians unmodified, [`Convexification::InertiaCorrection`];
/// it brings the interior-point QP solver with it) or "bfgs".
fn apply_hessian(settings: &mut SqpSettings, s: &str) -> Result<(), String> {
    settings.block_diagonal_elements = false;
    settings.convexification = Convexification::Clip;
    settings.trust_region_ratio = true;
    match s {
        "exact-block-diagonal" => {
            settings.hessian = HessianMode::ExactConvexified;
            settings.block_diagonal_elements = true;
        }
        "exact-inertia-corrected" => {
            settings.hessian = HessianMode::ExactConvexified;
            settings.convexification = Convexification::InertiaCorrection;
            settings.qp_solver = QpSolver::InteriorPoint;
            // With the ratio test the reduced jump's step bound collapsed
            // and its elastic QP failed at iteration 49; without it the
            // solve ends (README).
            settings.trust_region_ratio = false;
        }
        _ => {
            settings.hessian = s.parse::<HessianMode>().map_err(|_| {
                format!("unknown Hessian mode '{s}' (expected 'exact', 'exact-block-diagonal', 'exact-inertia-corrected' or 'bfgs')")
            })?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A solve named as `leap simulate`'s files would overwrite them.
    #[test]
    fn a_study_may_not_take_simulates_file_prefix() {
        let (field, reason) = field_error(r#"{"name": "forward"}"#);
        assert_eq!(field, "name");
        assert!(reason.contains("forward_summary.json"), "{reason}");
        assert!(
            SolveStudy::from_json_str(r#"{"name": "forward2"}"#, "s.json")
                .and_then(|s| s.resolve(None))
                .is_ok()
        );
        // Nor one whose result files are another study's forward check:
        // jump_forward_grf.mot.
        let (field, reason) = field_error(r#"{"name": "jump_forward"}"#);
        assert_eq!(field, "name");
        assert!(
            reason.contains("jump_forward_grf.mot") && reason.contains("'jump'"),
            "{reason}"
        );
        // Every pair of names other than these writes disjoint files.
        let names = [
            "jump",
            "jump_forward_states",
            "forward_x",
            "a_forwardb",
            "_forward",
        ];
        for a in names {
            assert!(check_name(a).is_ok(), "{a}");
            for b in names.iter().filter(|&&b| b != a) {
                let (fa, fb) = (crate::solve::result_files(a), crate::solve::result_files(b));
                assert!(fa.iter().all(|f| !fb.contains(f)), "{a} {b}");
            }
            let sim: Vec<String> = crate::simulate::trajectory_files(SIMULATE_FILE_PREFIX)
                .iter()
                .map(|f| f.to_string())
                .chain([format!("{SIMULATE_FILE_PREFIX}_summary.json")])
                .collect();
            assert!(crate::solve::result_files(a)
                .iter()
                .all(|f| !sim.contains(f)));
        }
    }

    fn field_error(json: &str) -> (String, String) {
        let r = SolveStudy::from_json_str(json, "s.json").and_then(|s| s.resolve(None));
        match r {
            Err(StudyError::Field { field, reason, .. }) => (field, reason),
            other => panic!("expected a field error, got {other:?}"),
        }
    }

    /// A field written at the wrong level is refused with where it belongs:
    /// the known fields come from the study's own structure.
    #[test]
    fn a_misplaced_field_is_told_where_it_belongs() {
        for (json, field, hint) in [
            (
                r#"{"num_mesh_intervals": 10}"#,
                "num_mesh_intervals",
                "`num_mesh_intervals` belongs under \"mesh\" (mesh.num_mesh_intervals)",
            ),
            (
                r#"{"max_iterations": 10}"#,
                "max_iterations",
                "`max_iterations` belongs under \"tolerances\" (tolerances.max_iterations)",
            ),
            (
                r#"{"mesh": {"guess": "bang-bang"}}"#,
                "mesh.guess",
                "`guess` belongs at the top level of the study",
            ),
        ] {
            let (f, r) = field_error(json);
            assert_eq!(f, field, "{json}");
            assert!(
                r.starts_with("unknown field") && r.ends_with(hint),
                "{json}: {r}"
            );
        }
        // Moco's top-level name, read under "mesh".
        let (_, r) = field_error(r#"{"transcription_scheme": "trapezoidal"}"#);
        assert!(
            r.ends_with("belongs under \"mesh\" (mesh.transcription_scheme)"),
            "{r}"
        );
        // Every field the hint may point to is one the study reads.
        fn leaves(v: &serde_json::Value, at: &str, out: &mut Vec<String>) {
            match v.as_object() {
                Some(m) => {
                    for (k, c) in m {
                        let here = if at.is_empty() {
                            k.clone()
                        } else {
                            format!("{at}.{k}")
                        };
                        leaves(c, &here, out);
                    }
                }
                None => out.push(at.to_string()),
            }
        }
        let mut all = Vec::new();
        leaves(&SolveStudy::fields(), "", &mut all);
        assert!(all.len() > 20, "{all:?}");
        for path in all {
            let mut json = "null".to_string();
            for k in path.rsplit('.') {
                json = format!("{{\"{k}\": {json}}}");
            }
            if let Err(e) = SolveStudy::from_json_str(&json, "s.json") {
                assert!(!e.to_string().contains("unknown field"), "{path}: {e}");
            }
        }
        // Every name a section reads (serde's "expected one of" list,
        // second names included) is in the hint's fields, and no other.
        let fields = SolveStudy::fields();
        let mut sections = vec![String::new()];
        sections.extend(
            fields
                .as_object()
                .unwrap()
                .iter()
                .filter(|(_, v)| v.is_object())
                .map(|(k, _)| k.clone()),
        );
        for section in sections {
            let json = if section.is_empty() {
                r#"{"zz_unknown": 1}"#.to_string()
            } else {
                format!(r#"{{"{section}": {{"zz_unknown": 1}}}}"#)
            };
            let e = SolveStudy::from_json_str(&json, "s.json")
                .unwrap_err()
                .to_string();
            let list = e
                .split_once("expected one of ")
                .map(|(_, l)| l.split(" at line").next().unwrap_or(l))
                .unwrap_or_else(|| panic!("{section}: {e}"));
            let mut read: Vec<&str> = list.split(", ").map(|n| n.trim_matches('`')).collect();
            let here = if section.is_empty() {
                &fields
            } else {
                &fields[section.as_str()]
            };
            let mut known: Vec<&str> = here
                .as_object()
                .unwrap()
                .keys()
                .map(|k| k.as_str())
                .collect();
            read.sort_unstable();
            known.sort_unstable();
            assert_eq!(read, known, "section {section:?}");
        }
        // A field read nowhere gets no such hint.
        let (_, r) = field_error(r#"{"mesh": {"num_nodes": 29}}"#);
        assert!(!r.contains("belongs"), "{r}");
        // A simulate study's bang-bang timing.
        let e = crate::simulate::SimulateStudy::from_json_str(r#"{"on_time": 0.1}"#, "s.json")
            .unwrap_err()
            .to_string();
        assert!(
            e.ends_with("`on_time` belongs under \"bang_bang\" (bang_bang.on_time)"),
            "{e}"
        );
    }

    /// The error of command-line overrides `o` applied to `c`.
    fn override_error(c: &mut SolveConfig, o: Overrides) -> String {
        c.apply(&o).unwrap_err().to_string()
    }

    /// A study resolved from JSON.
    fn resolved(json: &str) -> SolveConfig {
        SolveStudy::from_json_str(json, "s.json")
            .unwrap()
            .resolve(None)
            .unwrap()
    }

    #[test]
    fn defaults_are_the_papers_problem() {
        let c = SolveStudy::default().resolve(None).unwrap();
        assert_eq!(c.transcription.num_mesh_intervals, 28);
        assert_eq!(c.transcription.scheme, Scheme::MidpointEuler);
        assert_eq!(c.guess, GuessChoice::BangBang);
        assert_eq!(c.name, "jump");
        assert_eq!(c.output_directory, PathBuf::from("results"));
        assert_eq!(c.settings.hessian, HessianMode::ExactConvexified);
        assert_eq!(c.settings.eigenvalue_floor, JUMP_EIGENVALUE_FLOOR);
        assert_eq!(c.transcription.fiber_dynamics, FiberDynamics::Implicit);
        assert_eq!(c.settings.qp_solver, QpSolver::InteriorPoint);
    }

    #[test]
    fn guesses_parse_and_a_missing_file_names_the_field() {
        let guess = |g: &str| {
            SolveStudy::from_json_str(&format!(r#"{{"guess": "{g}"}}"#), "s.json")
                .and_then(|s| s.resolve(None))
                .map(|c| c.guess)
        };
        assert_eq!(guess("bang-bang").unwrap(), GuessChoice::BangBang);
        assert_eq!(
            guess("bang-bang-resampled").unwrap(),
            GuessChoice::BangBangResampled
        );
        let (f, r) = field_error(r#"{"guess": "no_such_solution.sto"}"#);
        assert_eq!(f, "guess");
        assert!(
            r.contains("no_such_solution.sto") && r.contains("bang-bang-resampled"),
            "{r}"
        );
        // A directory or a device is named as such, not as missing.
        let dir = std::env::temp_dir();
        let dir = dir.display().to_string().replace('\\', "/");
        for field in ["guess", "model"] {
            let (f, r) = field_error(&format!(r#"{{"{field}": "{dir}"}}"#));
            assert_eq!(f, field);
            assert!(r.contains("is a directory, not a file"), "{r}");
        }
        #[cfg(unix)]
        {
            let (f, r) = field_error(r#"{"model": "/dev/zero"}"#);
            assert_eq!(f, "model");
            assert!(r.contains("is a device or socket"), "{r}");
        }
    }

    #[test]
    fn bad_values_name_their_field() {
        let (f, r) = field_error(r#"{"mesh": {"num_mesh_intervals": -3}}"#);
        assert_eq!(f, "mesh.num_mesh_intervals");
        assert!(r.contains("-3"), "{r}");
        let (f, _) = field_error(r#"{"mesh": {"num_mesh_intervals": 0}}"#);
        assert_eq!(f, "mesh.num_mesh_intervals");
        let (f, r) = field_error(r#"{"method": "pseudospectral"}"#);
        assert_eq!(f, "method");
        assert!(r.contains("collocation") && r.contains("shooting"), "{r}");
        let (f, r) = field_error(r#"{"mesh": {"scheme": "euler"}}"#);
        assert_eq!(f, "mesh.scheme");
        assert!(r.contains("hermite-simpson"), "{r}");
        let (f, r) = field_error(r#"{"mesh": {"fiber_dynamics": "semi"}}"#);
        assert_eq!(f, "mesh.fiber_dynamics");
        assert!(r.contains("explicit, implicit"), "{r}");
        let (f, r) =
            field_error(r#"{"mesh": {"fiber_dynamics": "implicit", "scheme": "trapezoidal"}}"#);
        assert_eq!(f, "mesh.fiber_dynamics");
        assert!(r.contains("midpoint-euler"), "{r}");
        let (f, r) = field_error(r#"{"tolerances": {"max_iteration": 3}}"#);
        assert_eq!(f, "tolerances.max_iteration");
        assert!(r.contains("max_iteration"), "{r}");
        let (f, _) = field_error(r#"{"tolerances": {"optim_constraint_tolerance": "tight"}}"#);
        assert_eq!(f, "tolerances.optim_constraint_tolerance");
        let (f, _) = field_error(r#"{"tolerances": {"optim_convergence_tolerance": 0}}"#);
        assert_eq!(f, "tolerances.optim_convergence_tolerance");
        let (f, r) = field_error(r#"{"tolerances": {"optim_convergence_tolerance": 1e308}}"#);
        assert_eq!(f, "tolerances.optim_convergence_tolerance");
        assert!(r.contains("below 1") && r.contains("1e308"), "{r}");
        let (f, _) = field_error(r#"{"tolerances": {"optim_constraint_tolerance": 1}}"#);
        assert_eq!(f, "tolerances.optim_constraint_tolerance");
        // Fields by name only: serde would fill a struct from an array.
        let (f, r) = field_error(r#"{"mesh": [8, "trapezoidal", "explicit"]}"#);
        assert_eq!(f, "mesh");
        assert!(r.contains("expected an object with named fields"), "{r}");
        let (f, r) = field_error(r#"{"hessian": "newton"}"#);
        assert_eq!(f, "hessian");
        assert!(r.contains("exact-block-diagonal"), "{r}");
        for (h, block) in [("exact-block-diagonal", true), ("exact", false)] {
            let c = SolveStudy::from_json_str(&format!(r#"{{"hessian": "{h}"}}"#), "s.json")
                .and_then(|s| s.resolve(None))
                .unwrap();
            assert_eq!(c.settings.hessian, HessianMode::ExactConvexified);
            assert_eq!(c.settings.block_diagonal_elements, block);
        }
        for bad in ["0", "-1e-4", "1.5"] {
            let (f, r) = field_error(&format!(r#"{{"hessian_eigenvalue_floor": {bad}}}"#));
            assert_eq!(f, "hessian_eigenvalue_floor");
            assert!(r.contains("(0, 1)"), "{r}");
        }
        let (f, r) = field_error(r#"{"qp_solver": "osqp"}"#);
        assert_eq!(f, "qp_solver");
        assert!(r.contains("'interior-point' or 'clarabel'"), "{r}");
        for (name, want) in [
            ("clarabel", QpSolver::Clarabel),
            ("interior-point", QpSolver::InteriorPoint),
        ] {
            let c = SolveStudy::from_json_str(&format!(r#"{{"qp_solver": "{name}"}}"#), "s.json")
                .and_then(|s| s.resolve(None))
                .unwrap();
            assert_eq!(c.settings.qp_solver, want);
        }
        // The inertia-corrected exact Hessian brings the interior-point
        // solver; clarabel cannot take its indefinite QPs.
        let c = SolveStudy::from_json_str(r#"{"hessian": "exact-inertia-corrected"}"#, "s.json")
            .and_then(|s| s.resolve(None))
            .unwrap();
        assert_eq!(
            c.settings.convexification,
            Convexification::InertiaCorrection
        );
        assert_eq!(c.settings.qp_solver, QpSolver::InteriorPoint);
        let (f, r) =
            field_error(r#"{"hessian": "exact-inertia-corrected", "qp_solver": "clarabel"}"#);
        assert_eq!(f, "qp_solver");
        assert!(r.contains("interior-point"), "{r}");
        let (f, _) = field_error(r#"{"name": "../x"}"#);
        assert_eq!(f, "name");
        // Names whose files cannot be written (a 300-character prefix, past
        // the 255 bytes of a file name, had failed after the solve) or
        // would be hidden are refused before it.
        let long = "n".repeat(300);
        let (f, r) = field_error(&format!(r#"{{"name": "{long}"}}"#));
        assert_eq!(
            (f.as_str(), r.as_str()),
            (
                "name",
                "300 characters; at most 100 (the prefix of the result files' names)"
            )
        );
        assert!(
            SolveStudy::from_json_str(&format!(r#"{{"name": "{}"}}"#, &long[..100]), "s.json")
                .and_then(|s| s.resolve(None))
                .is_ok()
        );
        let (f, r) = field_error(r#"{"name": "."}"#);
        assert_eq!(f, "name");
        assert!(r.contains("hide"), "{r}");
    }

    #[test]
    fn mesh_intervals_have_a_maximum_in_the_file_and_on_the_command_line() {
        for n in ["1001", "100000", "9223372036854775807"] {
            let (f, r) = field_error(&format!(r#"{{"mesh": {{"num_mesh_intervals": {n}}}}}"#));
            assert_eq!(f, "mesh.num_mesh_intervals");
            assert!(r.contains("at most 1000") && r.contains(n), "{r}");
        }
        let mut c = SolveConfig::builtin().unwrap();
        let e = override_error(
            &mut c,
            Overrides {
                num_mesh_intervals: Some(i64::MAX),
                ..Default::default()
            },
        );
        assert!(
            e.starts_with("command line: --num-mesh-intervals: must be at most 1000"),
            "{e}"
        );
        c.apply(&Overrides {
            num_mesh_intervals: Some(MAX_NUM_MESH_INTERVALS),
            ..Default::default()
        })
        .unwrap();
        assert_eq!(c.transcription.num_mesh_intervals, 1000);
    }

    /// Simbody aborts the process on an accuracy ≥ 1 (after the whole
    /// solve); below 1e-12 its steps shrink without end.
    #[test]
    fn forward_check_accuracy_is_a_tolerance_below_one() {
        for a in ["1", "10", "1e-300", "0", "-1e-5"] {
            let (f, r) = field_error(&format!(r#"{{"forward_check": {{"accuracy": {a}}}}}"#));
            assert_eq!(f, "forward_check.accuracy");
            assert!(
                r.contains("[1e-12, 1e-2]") || r.contains("positive"),
                "{a}: {r}"
            );
        }
        let (f, r) =
            field_error(r#"{"forward_check": {"integrator": "ExplicitEuler", "accuracy": 1e-9}}"#);
        assert_eq!(f, "forward_check.accuracy");
        assert!(r.contains("fixed step must be at least 1e-6 s"), "{r}");
        for (integrator, a) in [("RungeKuttaMerson", 1e-12), ("ExplicitEuler", 1e-4)] {
            let json = format!(
                r#"{{"forward_check": {{"integrator": "{integrator}", "accuracy": {a}}}}}"#
            );
            let c = SolveStudy::from_json_str(&json, "s.json")
                .and_then(|s| s.resolve(None))
                .unwrap();
            assert_eq!(c.forward_check.unwrap().accuracy, a);
        }
        // A disabled check's settings are checked as well.
        for (json, field) in [
            (
                r#"{"enabled": false, "accuracy": 5}"#,
                "forward_check.accuracy",
            ),
            (
                r#"{"enabled": false, "integrator": "foo"}"#,
                "forward_check.integrator",
            ),
        ] {
            let (f, _) = field_error(&format!(r#"{{"forward_check": {json}}}"#));
            assert_eq!(f, field, "{json}");
        }
        assert!(resolved(r#"{"forward_check": {"enabled": false}}"#)
            .forward_check
            .is_none());
    }

    /// serde reads the first value and fills a struct from an array by
    /// position; a study is exactly one object.
    #[test]
    fn a_study_is_one_json_object() {
        for (text, reason) in [
            (
                r#"{"name":"jump"} xyz"#,
                "trailing characters at line 1 column 17",
            ),
            (
                "{\"name\": \"a\"}\n{\"name\": \"b\"}",
                "trailing characters at line 2 column 1",
            ),
            ("[]", "expected a JSON object, got an array"),
            (
                r#"["text", "myname", "models/jumper.json"]"#,
                "expected a JSON object, got an array",
            ),
            ("null", "expected a JSON object, got null"),
            ("  ", "empty; expected a JSON object"),
            (
                "<?xml",
                "an XML file (an OpenSim .osim model or setup file?): leap reads its own JSON files, such as models/jumper.json and the studies models/jump_*.json (models/jumper.osim is written from models/jumper.json, for OpenSim)",
            ),
            (
                "x",
                "expected a JSON object: expected value at line 1 column 1",
            ),
        ] {
            let e = SolveStudy::from_json_str(text, "s.json")
                .unwrap_err()
                .to_string();
            assert_eq!(e, format!("s.json: (document): {reason}"), "{text}");
        }
        let s = SolveStudy::from_json_str(" \n{\"name\": \"a\"} \n\t", "s.json").unwrap();
        assert_eq!(s.name.as_deref(), Some("a"));
    }

    #[test]
    fn stall_iterations_zero_turns_the_test_off() {
        let (f, r) = field_error(r#"{"tolerances": {"stall_iterations": -2}}"#);
        assert_eq!(f, "tolerances.stall_iterations");
        assert!(r.contains("-2"), "{r}");
        for (v, want) in [
            (0, 0),
            (-1, SqpSettings::default().stall_iterations),
            (7, 7),
        ] {
            let json = format!(r#"{{"tolerances": {{"stall_iterations": {v}}}}}"#);
            let c = SolveStudy::from_json_str(&json, "s").unwrap();
            assert_eq!(c.resolve(None).unwrap().settings.stall_iterations, want);
        }
    }

    #[test]
    fn line_search_heuristics_are_read_and_checked() {
        let d = SqpSettings::default();
        let c = SolveStudy::from_json_str(
            r#"{"line_search": {"max_filter_resets": 5, "filter_reset_trigger": 3,
                "second_order_correction_every_rejected_step": true}}"#,
            "s",
        )
        .unwrap()
        .resolve(None)
        .unwrap();
        assert_eq!(c.settings.max_filter_resets, 5);
        assert_eq!(c.settings.filter_reset_trigger, 3);
        assert!(c.settings.second_order_correction_every_rejected_step);
        let c = SolveStudy::from_json_str(
            r#"{"line_search": {"max_filter_resets": -1, "filter_reset_trigger": -1}}"#,
            "s",
        )
        .unwrap()
        .resolve(None)
        .unwrap();
        assert_eq!(c.settings.max_filter_resets, d.max_filter_resets);
        assert_eq!(c.settings.filter_reset_trigger, d.filter_reset_trigger);
        assert_eq!(
            c.settings.second_order_correction_every_rejected_step,
            d.second_order_correction_every_rejected_step
        );
        for (json, field, bad) in [
            (
                r#"{"line_search": {"max_filter_resets": -3}}"#,
                "line_search.max_filter_resets",
                "-3",
            ),
            (
                r#"{"line_search": {"max_filter_resets": 1, "filter_reset_trigger": 0}}"#,
                "line_search.filter_reset_trigger",
                "must be ≥ 1 (or -1 for the default), got 0",
            ),
            (
                r#"{"line_search": {"filter_reset_trigger": 3}}"#,
                "line_search.filter_reset_trigger",
                "max_filter_resets is 0",
            ),
        ] {
            let (f, r) = field_error(json);
            assert_eq!(f, field);
            assert!(r.contains(bad), "{r}");
        }
        let e = SolveStudy::from_json_str(r#"{"line_search": {"max_filter_reset": 5}}"#, "s")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("s: line_search.max_filter_reset: unknown field `max_filter_reset`"),
            "{e}"
        );
    }

    #[test]
    fn a_model_or_simulate_study_given_as_a_solve_study_is_named() {
        let model = std::fs::read_to_string("models/jumper.json").unwrap();
        let e = SolveStudy::from_json_str(&model, "m.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("this looks like a model file"), "{e}");
        let sim =
            r#"{"integrator": "RungeKuttaMerson", "t_max": 1.0, "bang_bang": {"on_time": 0.0}}"#;
        let e = SolveStudy::from_json_str(sim, "s.json")
            .unwrap_err()
            .to_string();
        // Its fields are not misplaced in a solve study: that hint alone.
        assert!(
            e.contains("`leap simulate` study file") && !e.contains("belongs"),
            "{e}"
        );
        // A section given as null is a JSON object missing, not a Rust type.
        let e = SolveStudy::from_json_str(r#"{"mesh": null}"#, "s.json")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("mesh: invalid type: null, expected a JSON object at line"),
            "{e}"
        );
        // A solve study's own misspelt field gets no such hint.
        let e = SolveStudy::from_json_str(r#"{"mesh": {}, "tolerance": {}}"#, "s.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("tolerance") && !e.contains("looks like"), "{e}");
        let solve = std::fs::read_to_string("models/jump_collocation.json").unwrap();
        let e = crate::simulate::SimulateStudy::from_json_str(&solve, "s.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("`leap solve` study file"), "{e}");
        // And a study given as the model.
        let e = crate::model::Model::from_json_str(&solve, "s.json")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`leap solve` study file") && e.contains("not as a model"),
            "{e}"
        );
    }

    #[test]
    fn whole_numbers_non_finite_literals_and_control_characters_are_named() {
        for (json, field, want) in [
            (
                r#"{"tolerances": {"max_iterations": 2.5}}"#,
                "tolerances.max_iterations",
                "expected a whole number, got 2.5 at line",
            ),
            (
                r#"{"tolerances": {"max_iterations": 100000000000000000000}}"#,
                "tolerances.max_iterations",
                "expected a whole number, got 1e+20, too large at line",
            ),
            (
                r#"{"tolerances": {"max_iterations": -1e20}}"#,
                "tolerances.max_iterations",
                "expected a whole number, got -1e+20, too small at line",
            ),
            (
                r#"{"tolerances": {"max_iterations": 18446744073709551615}}"#,
                "tolerances.max_iterations",
                "expected a whole number, got 18446744073709551615, too large at line",
            ),
            (
                r#"{"mesh": {"num_mesh_intervals": 28.0}}"#,
                "mesh.num_mesh_intervals",
                "expected a whole number written without a decimal point or exponent (28), got 28.0 at line",
            ),
            (
                r#"{"tolerances": {"optim_convergence_tolerance": NaN}}"#,
                "tolerances.optim_convergence_tolerance",
                "JSON has no NaN or Infinity",
            ),
            (
                r#"{"tolerances": {"max_iterations": 9223372036854775808.0}}"#,
                "tolerances.max_iterations",
                "expected a whole number, got 9.223372036854776e+18, too large at line",
            ),
            (
                r#"{"tolerances": {"optim_convergence_tolerance": -Infinity}}"#,
                "tolerances.optim_convergence_tolerance",
                "JSON has no NaN or Infinity",
            ),
            (
                r#"{"output_directory": "out\u0000x"}"#,
                "output_directory",
                r#"holds the control character U+0000 at character 4 of "out\0x"; remove it"#,
            ),
            (
                r#"{"model": "m\n.json"}"#,
                "model",
                r#"holds the control character U+000A at character 2 of "m\n.json""#,
            ),
        ] {
            let (f, r) = field_error(json);
            assert_eq!(f, field, "{json}");
            assert!(r.contains(want), "{json}: {r}");
            assert!(!r.contains("i64") && !r.contains('\0'), "{json}: {r}");
        }
        // A `leap simulate` study's paths too.
        let e = crate::simulate::SimulateStudy::from_json_str(r#"{"out": "o\u0000x"}"#, "s.json")
            .unwrap()
            .check("s.json")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(r#"s.json: out: holds the control character U+0000 at character 2"#),
            "{e}"
        );
        // No such word where the text only starts like one: a missing
        // comma before a key "info", an unquoted file name.
        for json in [
            r#"{"tolerances": {"max_iterations": 10 "info": 1}}"#,
            r#"{"guess": infile.sto}"#,
        ] {
            let (_, r) = field_error(json);
            assert!(!r.contains("NaN"), "{json}: {r}");
        }
        // Other reasons pass unchanged: a string for a count.
        let (_, r) = field_error(r#"{"tolerances": {"max_iterations": "10"}}"#);
        assert!(r.starts_with("invalid type: string \"10\""), "{r}");
    }

    #[test]
    fn minus_one_means_the_default() {
        let s = SolveStudy::from_json_str(
            r#"{"tolerances": {"optim_max_iterations": -1, "optim_constraint_tolerance": -1}}"#,
            "s",
        )
        .unwrap();
        let c = s.resolve(None).unwrap();
        let d = SqpSettings::default();
        assert_eq!(c.settings.max_iterations, d.max_iterations);
        assert_eq!(
            c.settings.optim_constraint_tolerance,
            d.optim_constraint_tolerance
        );
    }

    /// Hermite–Simpson gets its own eigenvalue floor from a study file and
    /// from `--scheme`, and a floor the study names wins over both.
    #[test]
    fn hermite_simpson_brings_its_eigenvalue_floor() {
        let from = |json: &str| {
            serde_json::from_str::<SolveStudy>(json)
                .unwrap()
                .resolve(None)
                .unwrap()
        };
        let hs = from(r#"{"mesh": {"scheme": "hermite-simpson"}}"#);
        assert_eq!(
            hs.settings.eigenvalue_floor,
            HERMITE_SIMPSON_EIGENVALUE_FLOOR
        );
        let given =
            from(r#"{"mesh": {"scheme": "hermite-simpson"}, "hessian_eigenvalue_floor": 1e-3}"#);
        assert_eq!(given.settings.eigenvalue_floor, 1e-3);
        let scheme = |c: &mut SolveConfig, s: &str| {
            c.apply(&Overrides {
                scheme: Some(s.into()),
                ..Default::default()
            })
            .unwrap()
        };
        let mut c = SolveConfig::builtin().unwrap();
        assert_eq!(c.settings.eigenvalue_floor, JUMP_EIGENVALUE_FLOOR);
        scheme(&mut c, "hermite-simpson");
        assert_eq!(
            c.settings.eigenvalue_floor,
            HERMITE_SIMPSON_EIGENVALUE_FLOOR
        );
        scheme(&mut c, "trapezoidal");
        assert_eq!(c.settings.eigenvalue_floor, JUMP_EIGENVALUE_FLOOR);
        let mut given = from(r#"{"hessian_eigenvalue_floor": 1e-3}"#);
        scheme(&mut given, "hermite-simpson");
        assert_eq!(given.settings.eigenvalue_floor, 1e-3);
    }

    #[test]
    fn overrides_name_the_option() {
        let mut c = SolveConfig::builtin().unwrap();
        let e = override_error(
            &mut c,
            Overrides {
                num_mesh_intervals: Some(1),
                ..Default::default()
            },
        );
        assert!(e.contains("--num-mesh-intervals"), "{e}");
        c.apply(&Overrides {
            num_mesh_intervals: Some(4),
            max_iterations: Some(3),
            scheme: Some("trapezoidal".into()),
            ..Default::default()
        })
        .unwrap();
        assert_eq!(c.transcription.num_mesh_intervals, 4);
        assert_eq!(c.settings.max_iterations, 3);
        assert_eq!(c.transcription.scheme, Scheme::Trapezoidal);
        assert_eq!(c.transcription.fiber_dynamics, FiberDynamics::Explicit);
        // The built-in study names no fibre dynamics: nothing to say.
        assert!(c.switched.is_empty(), "{:?}", c.switched);
        // A study that names implicit rows is told they became explicit;
        // with --fiber-dynamics explicit given, nothing is said.
        let implicit = r#"{"mesh": {"fiber_dynamics": "implicit"}}"#;
        let mut named = resolved(implicit);
        named
            .apply(&Overrides {
                scheme: Some("trapezoidal".into()),
                ..Default::default()
            })
            .unwrap();
        assert_eq!(named.transcription.fiber_dynamics, FiberDynamics::Explicit);
        assert!(
            named.switched.len() == 1
                && named.switched[0].contains("mesh.fiber_dynamics \"implicit\"")
                && named.switched[0].contains("--scheme trapezoidal"),
            "{:?}",
            named.switched
        );
        let mut said = resolved(implicit);
        said.apply(&Overrides {
            scheme: Some("trapezoidal".into()),
            fiber_dynamics: Some("explicit".into()),
            ..Default::default()
        })
        .unwrap();
        assert!(said.switched.is_empty(), "{:?}", said.switched);
        let e = override_error(
            &mut c,
            Overrides {
                scheme: Some("backward-euler".into()),
                fiber_dynamics: Some("implicit".into()),
                ..Default::default()
            },
        );
        assert!(
            e.contains("--fiber-dynamics") && e.contains("midpoint-euler"),
            "{e}"
        );
    }

    /// `backend` in the study and `--backend` on the command line: parsed,
    /// refused by name where unknown, and refused with method shooting
    /// (whose integration is Rust-native), by field or option.
    #[test]
    fn backend_is_collocations_and_errors_name_it() {
        let c = resolved(r#"{"backend": "simbody"}"#);
        assert_eq!(c.transcription.backend, Backend::Simbody);
        assert_eq!(
            SolveConfig::builtin().unwrap().transcription.backend,
            Backend::RustNative
        );
        let (f, r) = field_error(r#"{"backend": "opensim"}"#);
        assert_eq!(f, "backend");
        assert!(
            r.contains("'opensim'") && r.contains("rust-native, simbody"),
            "{r}"
        );
        // An unknown name is reported as such, with either method.
        let (f, r) = field_error(r#"{"method": "shooting", "backend": "opensim"}"#);
        assert_eq!(f, "backend");
        assert!(r.contains("unknown backend 'opensim'"), "{r}");
        let (f, r) = field_error(r#"{"method": "shooting", "backend": "simbody"}"#);
        assert_eq!(f, "backend");
        assert!(r.contains("collocation"), "{r}");
        // Rust-native is shooting's own: no error.
        resolved(r#"{"method": "shooting", "backend": "rust-native"}"#);
        let mut c = SolveConfig::builtin().unwrap();
        let e = override_error(
            &mut c,
            Overrides {
                backend: Some("dual".into()),
                ..Default::default()
            },
        );
        assert!(e.contains("--backend") && e.contains("'dual'"), "{e}");
        let e = override_error(
            &mut c,
            Overrides {
                method: Some("shooting".into()),
                backend: Some("simbody".into()),
                ..Default::default()
            },
        );
        assert!(e.contains("--backend") && e.contains("collocation"), "{e}");
        let mut c = SolveConfig::builtin().unwrap();
        c.apply(&Overrides {
            backend: Some("simbody".into()),
            ..Default::default()
        })
        .unwrap();
        assert_eq!(c.transcription.backend, Backend::Simbody);
        // A collocation study's backend is listed as ignored by --method shooting.
        let mut c = resolved(r#"{"backend": "simbody"}"#);
        c.apply(&Overrides {
            method: Some("shooting".into()),
            ..Default::default()
        })
        .unwrap();
        assert!(c.ignored.iter().any(|f| f == "backend"), "{:?}", c.ignored);
    }

    #[test]
    fn problem_settings_reach_the_ocp_and_bad_ones_name_the_field() {
        // Absent: the paper's problem, as before the section existed.
        let c = SolveConfig::builtin().unwrap();
        assert_eq!(c.problem.ocp_options(28), crate::ocp::OcpOptions::default());
        assert_eq!(c.problem.ocp_options(4).no_countermovement_nodes, 4);
        let c = resolved(
            r#"{"problem": {"time_final_bounds": [0.2, 0.39], "no_countermovement_nodes": 12, "no_com_descent": false}}"#,
        );
        let o = c.problem.ocp_options(28);
        assert_eq!(o.final_time_bounds, [0.2, 0.39]);
        assert_eq!(o.no_countermovement_nodes, 12);
        assert!(!o.no_com_descent);
        assert_eq!(
            o.activation_smoothing,
            Some(crate::ocp::DEFAULT_ACTIVATION_SMOOTHING)
        );
        let c = resolved(r#"{"problem": {"activation_dynamics_smoothing": 123}}"#);
        assert_eq!(c.problem.ocp_options(28).activation_smoothing, Some(123.0));
        // Moco's property name and leap's own both read.
        let c = resolved(r#"{"problem": {"final_time_bounds": [0.3, 0.35]}}"#);
        assert_eq!(c.problem.final_time_bounds, [0.3, 0.35]);
        // Both names at once: the field is named with the reason.
        let (field, reason) = field_error(
            r#"{"problem": {"time_final_bounds": [0.3, 0.35], "final_time_bounds": [0.3, 0.35]}}"#,
        );
        assert_eq!(field, "problem");
        assert!(
            reason.starts_with("duplicate field `time_final_bounds`")
                && reason.contains(", under two of its names; give it once at line 1"),
            "{reason}"
        );
        // One value fixes t_f, as in Moco.
        let c = resolved(r#"{"problem": {"time_final_bounds": [0.3]}}"#);
        assert_eq!(c.problem.final_time_bounds, [0.3, 0.3]);
        for (json, want) in [
            (
                r#"{"problem": {"time_final_bounds": [0.4, 0.2]}}"#,
                "t_min ≤ t_max",
            ),
            (
                r#"{"problem": {"time_final_bounds": [0, 0.5]}}"#,
                "0.01 ≤ t_min ≤ t_max ≤ 10",
            ),
            // Times no push-off takes: refused before the solve, not by it
            // (1e300 s had failed after 20 s as an invalid problem, 100 s
            // "predicted" 62 s of ground contact, 1e-300 s overflowed).
            (
                r#"{"problem": {"time_final_bounds": [1e300]}}"#,
                "got [1e300, 1e300]",
            ),
            (
                r#"{"problem": {"time_final_bounds": [0.2, 100]}}"#,
                "t_max ≤ 10",
            ),
            (
                r#"{"problem": {"time_final_bounds": [1e-300, 0.5]}}"#,
                "0.01 ≤ t_min",
            ),
            (
                r#"{"problem": {"time_final_bounds": [0.3, 0.4, 0.5]}}"#,
                "got 3 values",
            ),
            (r#"{"problem": {"no_countermovement_nodes": -3}}"#, "got -3"),
            (
                r#"{"problem": {"activation_dynamics_smoothing": 1e300}}"#,
                "got 1e300",
            ),
        ] {
            let (f, r) = field_error(json);
            assert!(f.starts_with("problem."), "{json}: {f}");
            assert!(r.contains(want), "{json}: {r}");
        }
        let (f, r) = field_error(r#"{"problem": {"activation_dynamics_smoothing": 0.5}}"#);
        assert_eq!(f, "problem.activation_dynamics_smoothing");
        let want = format!(
            "need 1 ≤ b ≤ 1000 (the switch ½ + ½·tanh(b·(u − a)); default {}), got 0.5",
            crate::ocp::DEFAULT_ACTIVATION_SMOOTHING
        );
        assert!(r.contains(&want), "{r}");
        let (f, r) = field_error(
            r#"{"mesh": {"num_mesh_intervals": 8}, "problem": {"no_countermovement_nodes": 9}}"#,
        );
        assert_eq!(f, "problem.no_countermovement_nodes");
        assert!(r.contains("the mesh has 8"), "{r}");
        let e = SolveStudy::from_json_str(r#"{"problem": {"tf_max": 1}}"#, "s.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("tf_max"), "{e}");
        // A coarser mesh on the command line is checked against the rows.
        let mut c = resolved(r#"{"problem": {"no_countermovement_nodes": 7}}"#);
        let e = override_error(
            &mut c,
            Overrides {
                num_mesh_intervals: Some(6),
                ..Default::default()
            },
        );
        assert!(
            e.contains("--num-mesh-intervals") && e.contains("no_countermovement_nodes"),
            "{e}"
        );
    }

    /// Shooting's dense sensitivities grow as N²: its mesh is bounded
    /// below collocation's, in the study and on the command line.
    #[test]
    fn shooting_takes_at_most_its_own_mesh_limit() {
        let n = MAX_SHOOTING_MESH_INTERVALS + 1;
        let (f, r) = field_error(&format!(
            r#"{{"method": "shooting", "mesh": {{"num_mesh_intervals": {n}}}}}"#
        ));
        assert_eq!(f, "mesh.num_mesh_intervals");
        let limit = format!("at most {MAX_SHOOTING_MESH_INTERVALS} mesh intervals");
        assert!(r.contains(&limit), "{r}");
        resolved(&format!(
            r#"{{"method": "shooting", "mesh": {{"num_mesh_intervals": {}}}}}"#,
            n - 1
        ));
        // Collocation takes it; --method shooting on such a study does not.
        let mut c = resolved(&format!(r#"{{"mesh": {{"num_mesh_intervals": {n}}}}}"#));
        let e = c
            .apply(&Overrides {
                method: Some("shooting".into()),
                ..Default::default()
            })
            .unwrap_err()
            .to_string();
        assert!(e.contains("--method") && e.contains(&limit), "{e}");
    }

    #[test]
    fn integrate_guess_applies_to_guess_files_of_collocation_only() {
        let file = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/controls/jump_optimal.sto"
        );
        let c = resolved(&format!(
            r#"{{"guess": "{file}", "integrate_guess": true}}"#
        ));
        assert!(c.integrate_guess);
        assert!(!resolved(&format!(r#"{{"guess": "{file}"}}"#)).integrate_guess);
        for g in ["bang-bang", "bang-bang-resampled"] {
            let (f, r) = field_error(&format!(r#"{{"guess": "{g}", "integrate_guess": true}}"#));
            assert_eq!(f, "integrate_guess");
            assert!(r.contains("applies to a guess file"), "{r}");
        }
        let (f, r) = field_error(r#"{"method": "shooting", "integrate_guess": true}"#);
        assert_eq!(f, "integrate_guess");
        assert!(r.contains("collocation"), "{r}");
        // On the command line: a file needed, collocation only; a
        // collocation study's setting is listed as ignored by shooting.
        let mut c = SolveConfig::builtin().unwrap();
        let e = override_error(
            &mut c,
            Overrides {
                integrate_guess: true,
                ..Default::default()
            },
        );
        assert!(
            e.contains("--integrate-guess") && e.contains("guess file"),
            "{e}"
        );
        let mut c = SolveConfig::builtin().unwrap();
        let e = override_error(
            &mut c,
            Overrides {
                method: Some("shooting".into()),
                guess: Some(file.into()),
                integrate_guess: true,
                ..Default::default()
            },
        );
        assert!(
            e.contains("--integrate-guess") && e.contains("collocation"),
            "{e}"
        );
        let mut c = resolved(&format!(
            r#"{{"guess": "{file}", "integrate_guess": true}}"#
        ));
        c.apply(&Overrides {
            method: Some("shooting".into()),
            ..Default::default()
        })
        .unwrap();
        assert!(!c.integrate_guess);
        assert!(
            c.ignored.iter().any(|f| f == "integrate_guess"),
            "{:?}",
            c.ignored
        );
        // A bang-bang guess on the command line replaces the study's file
        // and its integration; --integrate-guess with it is refused.
        for g in ["bang-bang", "bang-bang-resampled"] {
            let mut c = resolved(&format!(
                r#"{{"guess": "{file}", "integrate_guess": true}}"#
            ));
            c.apply(&Overrides {
                guess: Some(g.into()),
                ..Default::default()
            })
            .unwrap();
            assert!(!c.integrate_guess, "{g}");
            let e = override_error(
                &mut c,
                Overrides {
                    guess: Some(g.into()),
                    integrate_guess: true,
                    ..Default::default()
                },
            );
            assert!(e.contains("--integrate-guess"), "{g}: {e}");
        }
    }

    /// The Hessian's name in the summary is the study's own: the inverse
    /// of `apply_hessian` for every option, also after another option.
    #[test]
    fn hessian_option_name_inverts_apply_hessian() {
        let options = [
            "exact",
            "exact-block-diagonal",
            "exact-inertia-corrected",
            "bfgs",
        ];
        for before in options {
            for h in options {
                let mut settings = SqpSettings::default();
                apply_hessian(&mut settings, before).unwrap();
                apply_hessian(&mut settings, h).unwrap();
                assert_eq!(hessian_option_name(&settings), h, "{before} then {h}");
            }
        }
        let c = SolveConfig::builtin().unwrap();
        assert_eq!(hessian_option_name(&c.settings), "exact");
        let c = SolveStudy::from_json_str(r#"{"method": "shooting"}"#, "t")
            .unwrap()
            .resolve(None)
            .unwrap();
        assert_eq!(hessian_option_name(&c.settings), "bfgs");
    }
}
