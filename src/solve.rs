//! `leap solve`: the jump problem of Porsa, Lin & Pandy (2016) from a study
//! ([`crate::study`]) through direct collocation ([`crate::transcription`])
//! or direct shooting ([`crate::shooting`]) and the SQP ([`crate::sqp`]) to
//! files OpenSim and Moco users can open, the paper's Table 2 row, and a
//! forward check of the optimal excitations.
//!
//! With method "shooting" the solution holds the node states of the
//! integration, and `<name>_grf.mot` the ground forces at every integrator
//! step; the peak force and lift-off are taken over those steps.
//!
//! Outputs (into the study's `output_directory` and nowhere else), with
//! `<name>` the study's name (default `jump`):
//! - `<name>_solution.sto`: states and excitations at the mesh nodes (node
//!   0, the fixed squat, included) under Moco's names and with a
//!   `MocoSolution` header (`num_iterations`, `objective`,
//!   `solver_duration`, `status`, `success`, ...);
//! - `<name>_grf.mot`: ground reaction forces per foot at the nodes
//!   (OpenSim's ExternalLoads columns);
//! - `<name>_history.csv`: one row per SQP iteration;
//! - `<name>_forward_states.sto`, `_controls.sto`, `_grf.mot`: the forward
//!   check integrated by Simbody;
//! - `<name>_summary.json`: the [`SolveReport`].
//!
//! Jump height = J − Y_C,standing with J = Y_C(t_f) + Ẏ_C(t_f)²/(2g) the
//! apex of the centre of mass leaving the ground at t_f (eq. 3); the ground
//! contact time is t_f.

use crate::io::{Controls, StoError, StoTable};
use crate::model::{Model, ModelError};
use crate::nlp::Nlp;
use crate::ocp::{JumpOcp, OcpError, OcpOptions, FIBER_CLAMP_BAND};
use crate::shooting::{NodeValues, Shooting, ShootingDerivatives, ShootingOptions};
use crate::simulate::{
    grf_of, grf_table, simulate_rust, simulate_simbody, write_trajectory, JumpSummary,
    SimulateOptions,
};
use crate::sqp::{HessianMode, SqpResult, SqpStatus};
use crate::study::{
    backend_name, fiber_dynamics_name, scheme_name, ForwardCheck, GuessChoice, Method,
    ProblemSettings, SolveConfig,
};
use crate::transcription::{GuessProjection, MeshTrajectory, Transcription, TranscriptionError};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Stop time of the forward check after the predicted lift-off (s): the
/// flight to the apex of a 0.4 m jump takes under 0.3 s.
const FORWARD_FLIGHT_TIME: f64 = 1.0;

/// How closely the forward check must reproduce the predicted jump height
/// (1 cm, the tolerance of Porsa et al.'s comparison that the issue asks for).
pub const FORWARD_CHECK_TOLERANCE_M: f64 = 0.01;

/// The offset of [`ForwardCheckReport::excitation_sensitivity`]: 0.1% of
/// the full excitation. The default jump's forward jump moves by less than
/// a millimetre (about linearly: excitations at their bounds make the
/// change first-order); the long push-off of the problem without the
/// paper's rule moves by 20 cm.
pub const EXCITATION_OFFSET: f64 = 0.001;

/// The accuracy at which [`SolveReport::mesh_error`] integrates each mesh
/// interval: far below the local errors of a collocation mesh (1e-3 and up
/// on the jump's meshes), and at shooting's own 1e-8.
pub const MESH_ERROR_ACCURACY: f64 = 1e-8;

/// A solve could not be set up or its results not written. How the
/// optimizer ended is not an error: it is [`SolveReport::status`].
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Ocp(#[from] OcpError),
    #[error(transparent)]
    Transcription(#[from] TranscriptionError),
    #[error(transparent)]
    Sto(#[from] StoError),
    #[error("{file}: {reason}")]
    Guess { file: PathBuf, reason: String },
    /// The solve's last iterate could not be evaluated for the report.
    #[error("the solution: {0}")]
    Solution(String),
    #[error("{file}: {error}")]
    Io {
        file: PathBuf,
        error: std::io::Error,
    },
    /// A result file could not be written after others of this run were.
    #[error("{error} (this run's result files written before it: {written}; an earlier run's result files removed, so that none is read as this run's: {removed})")]
    Partial {
        error: Box<SolveError>,
        written: String,
        removed: String,
    },
    /// A study setting the model cannot take.
    #[error("{origin}: {field}: {reason}")]
    Setting {
        origin: String,
        field: String,
        reason: String,
    },
}

/// A failure of the built-in bang-bang guess (the model too stiff to
/// integrate, a jump that does not lift off) is the model's: named by its
/// file, as a guess file's failures are by theirs.
fn of_model(model: &Model, e: impl std::fmt::Display) -> SolveError {
    SolveError::Guess {
        file: model.file.clone(),
        reason: e.to_string(),
    }
}

/// The bang-bang guess's integration failed: for a DeGrooteFregly2016Muscle
/// model, say why it fails and what works instead.
fn bang_bang_failure(
    model: &Model,
    method: Method,
    integration_failed: bool,
    e: impl std::fmt::Display,
) -> SolveError {
    if !integration_failed
        || model.muscle_model != crate::model::MuscleModel::DeGrooteFregly2016Muscle
    {
        return of_model(model, e);
    }
    let instead = match method {
        Method::Collocation => "collocation states them as implicit force balances and solves from a guess file (--guess FILE: a solution of the same model with Thelen2003Muscle, say)",
        Method::Shooting => "direct shooting integrates them at every evaluation; solve by collocation from a guess file instead (--method collocation --guess FILE: a solution of the same model with Thelen2003Muscle, say)",
    };
    of_model(
        model,
        format!("{e}: DeGrooteFregly2016Muscle's explicit fibre dynamics are too stiff to integrate through the jump (a tendon below its slack length pushes, and the inverted force-velocity curve grows exponentially; OpenSim 4.6's own explicit integration of this model stops too); {instead}"),
    )
}

/// Create the results directory `dir` (and its parents), with an error
/// that says what stands in the way (the OS's own, "File exists", does not
/// say that a regular file has the directory's name).
pub fn create_results_dir(dir: &Path) -> Result<(), std::io::Error> {
    check_results_dir(dir)?;
    std::fs::create_dir_all(dir).map_err(|e| {
        std::io::Error::new(
            e.kind(),
            format!("cannot create the results directory: {e}"),
        )
    })
}

/// Whether a file stands where the results directory `dir` should be (an
/// error saying so), without creating anything.
pub fn check_results_dir(dir: &Path) -> Result<(), std::io::Error> {
    if dir.exists() && !dir.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            "cannot create the results directory: a file of that name exists",
        ));
    }
    Ok(())
}

/// The files a solve named `name` writes into its results directory.
pub fn result_files(name: &str) -> Vec<String> {
    let mut files: Vec<String> = ["_solution.sto", "_grf.mot", "_history.csv", "_summary.json"]
        .iter()
        .map(|s| format!("{name}{s}"))
        .collect();
    files.extend(crate::simulate::trajectory_files(&format!(
        "{name}_forward"
    )));
    files
}

/// Remove the result files of a solve named `name` in `dir` that this run
/// did not write (`written`): an earlier run's forward check beside a
/// solution without one would be read as this solution's. Returns the
/// files removed.
fn remove_stale_results(
    dir: &Path,
    name: &str,
    written: &[PathBuf],
) -> Result<Vec<String>, SolveError> {
    let mut removed = Vec::new();
    for f in result_files(name) {
        let p = dir.join(&f);
        if written.contains(&p) || !p.is_file() {
            continue;
        }
        std::fs::remove_file(&p).map_err(|e| {
            io_error(
                &p,
                e,
                "cannot remove this result file of an earlier run, which this run did not write",
            )
        })?;
        removed.push(p.display().to_string());
    }
    Ok(removed)
}

/// The reports `leap report` writes by default
/// ([`crate::report::default_output`]) of a solve's tables (its `.sto` and
/// `.mot` [`result_files`]) that lie in `dir`: drawn of an earlier run,
/// since this run has just written or removed its results.
fn earlier_reports(dir: &Path, name: &str) -> Vec<String> {
    result_files(name)
        .iter()
        .filter(|f| f.ends_with(".sto") || f.ends_with(".mot"))
        .map(|f| crate::report::default_output(&dir.join(f)))
        .filter(|p| p.is_file())
        .map(|p| p.display().to_string())
        .collect()
}

/// An I/O error on `file`, `what` failed, with the OS's reason.
fn io_error(file: &Path, e: std::io::Error, what: &str) -> SolveError {
    SolveError::Io {
        file: file.into(),
        error: std::io::Error::new(e.kind(), format!("{what}: {e}")),
    }
}

/// Remove the QPs an earlier run dumped into `dir` (`qp_iter*.json`), so
/// that the directory holds this run's only. Returns how many.
fn remove_stale_qp_dumps(dir: &Path) -> Result<usize, SolveError> {
    let entries = match std::fs::read_dir(dir) {
        Ok(e) => e,
        // No directory yet: nothing of an earlier run to remove.
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(0),
        Err(e) => {
            return Err(io_error(
                dir,
                e,
                "--dump-qps: cannot read the QP directory to remove an earlier run's QPs",
            ))
        }
    };
    let mut n = 0;
    for e in entries.flatten() {
        let p = e.path();
        let is_dump = p
            .file_name()
            .and_then(|f| f.to_str())
            .is_some_and(|f| f.starts_with("qp_iter") && f.ends_with(".json"));
        if is_dump && p.is_file() {
            std::fs::remove_file(&p).map_err(|e| {
                io_error(&p, e, "--dump-qps: cannot remove this QP of an earlier run")
            })?;
            n += 1;
        }
    }
    Ok(n)
}

/// With `--dump-qps`, remove an earlier run's QPs before the SQP dumps
/// this run's, and say so.
fn clear_qp_dumps(
    settings: &crate::sqp::SqpSettings,
    progress: &mut dyn FnMut(&str),
) -> Result<(), SolveError> {
    if let Some(q) = &settings.qp_dump_dir {
        let n = remove_stale_qp_dumps(q)?;
        if n > 0 {
            progress(&format!(
                "--dump-qps: removed {n} QPs of an earlier run from {}",
                q.display()
            ));
        }
    }
    Ok(())
}

/// Whether a directory stands where one of `files` should be written in
/// `dir` (an error naming it), found before anything is computed: a result
/// file that cannot be written had lost the summary after a whole solve.
pub fn check_result_files(dir: &Path, files: &[String]) -> Result<(), std::io::Error> {
    check_results_dir(dir)?;
    check_writable(dir)?;
    match files.iter().map(|f| dir.join(f)).find(|p| p.is_dir()) {
        Some(p) => Err(std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            format!(
                "cannot write the result file {}: a directory of that name exists",
                p.display()
            ),
        )),
        None => Ok(()),
    }
}

/// Whether files can be created in `dir`, or, where it does not exist yet,
/// in its nearest existing ancestor (where it will be created): a probe
/// file is created and removed. A read-only results directory had lost a
/// whole solve, refused only when its first result was written.
fn check_writable(dir: &Path) -> Result<(), std::io::Error> {
    let mut at = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    while !at.exists() {
        match at.parent() {
            Some(p) if !p.as_os_str().is_empty() => at = p,
            _ => {
                at = Path::new(".");
                break;
            }
        }
    }
    if !at.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            format!(
                "cannot create the results directory: {} is a file",
                at.display()
            ),
        ));
    }
    let probe = at.join(format!(".leap-write-probe-{}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        // A probe of the same name left by an earlier process of this id,
        // or another thread's: the directory takes files.
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
        Err(e) => Err(std::io::Error::new(
            e.kind(),
            if at == dir {
                format!("cannot write into the results directory: {e}")
            } else {
                format!(
                    "cannot create the results directory in {}: {e}",
                    at.display()
                )
            },
        )),
    }
}

/// The forward check: the optimal excitations (linear between the nodes,
/// held after t_f) integrated from the squat.
#[derive(Debug, Clone, Serialize)]
pub struct ForwardCheckReport {
    pub integrator: String,
    pub accuracy: f64,
    /// Simbody's jump (None if the integration failed).
    pub summary: Option<JumpSummary>,
    /// The Rust-native Dormand–Prince 5(4) jump at accuracy 1e-6.
    pub rust_summary: Option<JumpSummary>,
    /// How much the forward jump depends on the excitations: the same
    /// Dormand–Prince jump with every excitation raised and lowered by
    /// [`EXCITATION_OFFSET`] (the simulation clamps them to [0.01, 1], as
    /// OpenSim does, so excitations at either end do not move one way). At
    /// a squat jump's optimum both land within a millimetre of
    /// `rust_summary` (both a little lower); an open-loop movement that
    /// needs feedback (a long push-off balancing the body) lands far from
    /// it, and then small differences between the forward check's model and
    /// the optimizer's decide what the forward check shows.
    pub excitation_sensitivity: Option<ExcitationSensitivity>,
    /// The Dormand–Prince jump (1e-6) under the optimizer's own dynamics
    /// (its smoothed activation switch, fibre clamp and paths) instead of
    /// OpenSim's: its difference from the predicted height is the mesh's
    /// discretisation error, its difference from `rust_summary` the
    /// smoothing's.
    pub optimizer_dynamics_jump_height_m: Option<f64>,
    /// [`crate::analyze`] on Simbody's trajectory: what drove and limited
    /// its push-off (`leap analyze <name>_forward_states.sto` prints it).
    pub push_off: Option<crate::analyze::JumpAnalysis>,
    /// Why an integration failed.
    pub errors: Vec<String>,
}

/// [`ForwardCheckReport::excitation_sensitivity`].
#[derive(Debug, Clone, Serialize)]
pub struct ExcitationSensitivity {
    /// The offset added to every excitation.
    pub offset: f64,
    /// The forward jump heights (m) with the excitations raised and
    /// lowered (None where that integration failed).
    pub jump_height_raised_m: Option<f64>,
    pub jump_height_lowered_m: Option<f64>,
    /// The larger of the two changes from the unperturbed jump (m).
    pub largest_change_m: Option<f64>,
}

/// A shooting solve's derivative settings and evaluation counts.
#[derive(Debug, Clone, Serialize)]
pub struct ShootingSummary {
    /// "central-difference" or "forward-sensitivity".
    pub derivatives: &'static str,
    pub integrator_accuracy: f64,
    /// The central-difference step (None with forward sensitivities).
    pub finite_difference_step: Option<f64>,
    pub counters: crate::shooting::ShootingCounters,
}

/// What `leap solve` reports (the `--json` object and `<name>_summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct SolveReport {
    /// "collocation" or "shooting".
    pub method: Method,
    /// How the SQP ended (snake_case [`SqpStatus`]).
    pub status: SqpStatus,
    /// The same as IPOPT's return status, as Moco writes it.
    pub moco_status: &'static str,
    pub success: bool,
    pub message: String,
    pub iterations: usize,
    /// Wall time of the SQP (s) and per iteration.
    pub wall_time_s: f64,
    pub wall_time_per_iteration_s: f64,
    /// −J at the solution (m).
    pub objective: f64,
    pub jump_height_m: f64,
    pub apex_com_height_m: f64,
    pub standing_com_height_m: f64,
    /// Lift-off (s): where the vertical ground force at the points where
    /// the dynamics hold (interval midpoints for midpoint Euler, nodes
    /// otherwise) last falls through the lift-off row's level (1% of body
    /// weight), interpolated linearly; t_f if it is still above at t_f.
    pub ground_contact_time_s: f64,
    /// t_f (s), at or after lift-off (J is constant in flight).
    pub final_time_s: f64,
    /// Whether the lift-off row holds (F_y(t_f)/(m g) at most its level,
    /// within the paper's 1e-3). When false the body is still on the ground
    /// at t_f (a solve stopped early), and the ground contact time and the
    /// lift-off quantities are t_f's.
    pub lifted_off: bool,
    /// Ẏ_C (m/s) and Y_C (m) at lift-off, interpolated between the nodes.
    pub liftoff_com_velocity_mps: f64,
    pub liftoff_com_height_m: f64,
    /// Peak total vertical ground force / body weight where the dynamics
    /// are enforced: at the interval midpoints (mean states and
    /// excitations) for midpoint Euler, at the nodes for the other schemes.
    /// Midpoint Euler leaves node states free to alternate about the
    /// midpoints (a foot in and out of contact from node to node), so its
    /// node forces need not be any force the dynamics saw.
    pub peak_vertical_grf_bw: f64,
    /// The same over the nodes (the `_grf.mot` rows).
    pub peak_vertical_grf_nodes_bw: f64,
    /// Largest violation of the constraints (defects, no countermovement,
    /// lift-off) in their units.
    pub max_constraint_violation: f64,
    /// Scaled dual infeasibility at the returned iterate (IPOPT's inf_du,
    /// as the history records it for that iterate): at an optimum at most
    /// `optim_convergence_tolerance`. The paper's rule stops where the
    /// objective no longer moves, which need not be an optimum (the
    /// default jump stops at 2.2e-3).
    pub dual_infeasibility: f64,
    /// The forward check's jump height (Simbody), its difference from the
    /// predicted one (forward − predicted), and the Rust-native one.
    pub forward_jump_height_m: Option<f64>,
    pub forward_check_difference_m: Option<f64>,
    /// Whether the forward check reproduces the predicted height within
    /// [`FORWARD_CHECK_TOLERANCE_M`]. When not, the predicted jump does not
    /// hold for the model: the solve stopped early, or it converged on the
    /// discretisation error of a coarse mesh over a long push-off (the
    /// default jump from a slow push-off guess "solved" at 35.5 cm and
    /// jumped 18.9 cm forward).
    pub forward_check_agrees: Option<bool>,
    /// Whether the forward check's feet left the ground with the centre of
    /// mass moving down: a fall, not a jump (as `leap simulate`'s
    /// `liftoff_while_falling`). None without a forward check that ran.
    pub forward_liftoff_while_falling: Option<bool>,
    pub forward_jump_height_rust_m: Option<f64>,
    pub forward_check: Option<ForwardCheckReport>,
    /// How well the mesh resolves the solution (collocation, with the
    /// forward check): each interval integrated from its first node with
    /// the optimizer's own dynamics (Dormand–Prince at
    /// [`MESH_ERROR_ACCURACY`]) against the next node, per interval the
    /// largest state error relative to 1 + the state's largest magnitude,
    /// with that state's absolute error ([`crate::mesh_error`]). Where it is
    /// large the mesh is too coarse for the movement. None for shooting,
    /// without the forward check, or if the check could not run
    /// (`mesh_error_failure` says why).
    pub mesh_error: Option<crate::mesh_error::MeshError>,
    pub mesh_error_failure: Option<String>,
    /// The initial guess and, for bang-bang, its jump height (m).
    pub guess: String,
    pub guess_jump_height_m: Option<f64>,
    /// For the bang-bang guess: how its integration on the mesh went.
    pub guess_mesh_integration: Option<crate::transcription::MeshIntegration>,
    pub num_mesh_intervals: usize,
    pub scheme: &'static str,
    /// "explicit" or "implicit" ([`crate::transcription::FiberDynamics`]).
    pub fiber_dynamics: &'static str,
    /// Where collocation's points were evaluated: "rust-native" or
    /// "simbody" ([`crate::transcription::Backend`]).
    pub backend: &'static str,
    /// The SQP's Hessian mode (`hessian_mode` in the JSON).
    #[serde(rename = "hessian_mode")]
    pub hessian: HessianMode,
    /// The Hessian as a study names it ("exact", "exact-block-diagonal",
    /// "exact-inertia-corrected", "bfgs"; `--hessian`): `hessian` in the
    /// JSON, as in the study file.
    #[serde(rename = "hessian")]
    pub hessian_option: &'static str,
    /// The problem solved (the study's `problem`): bounds on t_f (s), the
    /// number of eq. 4's rows, and whether the rows Ẏ_C ≥ 0 at every node
    /// were imposed.
    pub time_final_bounds: [f64; 2],
    pub no_countermovement_nodes: usize,
    pub no_com_descent: bool,
    /// b of the optimizer's activation switch (the study's
    /// `problem.activation_dynamics_smoothing`).
    pub activation_dynamics_smoothing: Option<f64>,
    pub variables: usize,
    pub constraints: usize,
    pub time_split: crate::sqp::TimeSplit,
    /// QPs that leap's interior-point solver handed to clarabel, and how
    /// many of them clarabel found infeasible.
    pub qp_fallbacks: usize,
    pub qp_fallbacks_infeasible: usize,
    /// Wall time clarabel spent on them (part of the QP time).
    pub qp_fallback_seconds: f64,
    /// Plain QPs taken as infeasible where the interior-point solver's
    /// primal residual stalled (no clarabel certificate asked for; the
    /// elastic QP followed, or a second-order correction was dropped).
    pub qp_stalls_taken_infeasible: usize,
    /// The filter line search's opt-in heuristics as the study set them
    /// (its `line_search`) and the filter resets made.
    pub line_search: LineSearchReport,
    /// The inertia correction's τ over the solve's QPs (None where no QP
    /// needed one, as in every mode but `exact-inertia-corrected`).
    pub hessian_shift: Option<crate::sqp::HessianShiftSummary>,
    pub study: Option<String>,
    /// Settings of the study that the method does not use (a collocation
    /// study solved with `--method shooting`).
    pub ignored_study_settings: Vec<String>,
    /// Settings of the study that a command-line option changed with it
    /// ([`crate::study::SolveConfig::switched`]), in words.
    pub switched_study_settings: Vec<String>,
    /// Method "shooting": its derivatives and the work they took.
    pub shooting: Option<ShootingSummary>,
    pub model: String,
    pub output_files: Vec<String>,
    /// Result files of this study's name that an earlier run left in the
    /// results directory and this run did not write (the forward check's,
    /// with the check off), removed so that none is read as this run's.
    pub removed_stale_files: Vec<String>,
    /// Reports that `leap report` drew of an earlier run's results in the
    /// results directory (`<name>_solution_report.svg`, ...): kept (they are
    /// the user's), said to be of an earlier run.
    pub earlier_reports: Vec<String>,
    /// Columns of the guess file that look like excitations but name no
    /// muscle of the model (a misspelt muscle): not read.
    pub unread_guess_columns: Vec<String>,
    /// States of the guess file outside the problem's bounds, projected
    /// into them before the solve (a file in degrees read as radians, a
    /// solution of a model with other ranges).
    pub guess_projected_states: Vec<GuessProjection>,
}

/// The SQP settings of a study's `line_search` ([`crate::study::LineSearchSpec`])
/// and how many filter resets the solve made.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct LineSearchReport {
    pub max_filter_resets: usize,
    pub filter_reset_trigger: usize,
    pub second_order_correction_every_rejected_step: bool,
    pub filter_resets: usize,
}

impl LineSearchReport {
    /// The settings of `s`, with the resets a solve made.
    pub fn new(s: &crate::sqp::SqpSettings, filter_resets: usize) -> Self {
        LineSearchReport {
            max_filter_resets: s.max_filter_resets,
            filter_reset_trigger: s.filter_reset_trigger,
            second_order_correction_every_rejected_step: s
                .second_order_correction_every_rejected_step,
            filter_resets,
        }
    }
}

/// IPOPT's return status for an SQP status (what Moco writes as `status`).
pub fn moco_status(s: SqpStatus) -> &'static str {
    match s {
        SqpStatus::Solved => "Solve_Succeeded",
        SqpStatus::Acceptable => "Solved_To_Acceptable_Level",
        SqpStatus::IterationLimit => "Maximum_Iterations_Exceeded",
        SqpStatus::Infeasible => "Infeasible_Problem_Detected",
        SqpStatus::Unbounded => "Diverging_Iterates",
        SqpStatus::RestorationFailed => "Restoration_Failed",
        SqpStatus::LineSearchFailed => "Error_In_Step_Computation",
        SqpStatus::NumericalError => "Error_In_Step_Computation",
        SqpStatus::EvaluationError => "Invalid_Number_Detected",
        SqpStatus::InvalidProblem => "Invalid_Problem_Definition",
        SqpStatus::UserRequestedStop => "User_Requested_Stop",
    }
}

/// The jump problem's options for a collocation: the paper constrains 7
/// intervals against countermovement (eq. 4), a coarser mesh all it has;
/// schemes that evaluate the dynamics at the nodes get Thelen's fibre clamp
/// spread over a band.
pub fn collocation_ocp_options(t: &crate::transcription::TranscriptionOptions) -> OcpOptions {
    collocation_problem_options(t, &ProblemSettings::default())
}

/// [`collocation_ocp_options`] for a study's `problem` settings.
pub fn collocation_problem_options(
    t: &crate::transcription::TranscriptionOptions,
    problem: &ProblemSettings,
) -> OcpOptions {
    OcpOptions {
        fiber_clamp_smoothing: t
            .scheme
            .evaluates_dynamics_at_nodes()
            .then_some(FIBER_CLAMP_BAND),
        ..problem.ocp_options(t.num_mesh_intervals)
    }
}

/// Refuse a run that would overwrite or remove one of its own inputs (the
/// guess, the model or the study file) among its result files: the
/// solution of a previous run given as the guess in the same results
/// directory, or its forward check's controls, which a run without the
/// check removes as stale.
fn check_inputs_are_not_results(config: &SolveConfig) -> Result<(), SolveError> {
    let guess = match &config.guess {
        crate::study::GuessChoice::File(f) => Some(("the guess (guess, --guess)", f.as_path())),
        _ => None,
    };
    let inputs = guess
        .into_iter()
        .chain([("the model (model, --model)", config.model.as_path())])
        .chain(
            config
                .study_file
                .iter()
                .map(|f| ("the study file", f.as_path())),
        );
    let files = result_files(&config.name);
    let instead = "another results directory (output_directory, --out) or name";
    match crate::io::input_among_results(inputs, &config.output_directory, &files, instead) {
        Some((input, reason)) => Err(SolveError::Io {
            file: input.into(),
            error: std::io::Error::new(std::io::ErrorKind::AlreadyExists, reason),
        }),
        None => Ok(()),
    }
}

/// Run a study: build the problem, solve it, write the outputs, check the
/// solution forward. `verbose` prints the SQP's iteration log to standard
/// error; `progress` receives one line per stage.
pub fn run(
    config: &SolveConfig,
    verbose: bool,
    progress: &mut dyn FnMut(&str),
) -> Result<SolveReport, SolveError> {
    let dir = &config.output_directory;
    // A file where the results directory should be is found before the
    // squat and the guess are computed, not after.
    check_result_files(dir, &result_files(&config.name)).map_err(|e| SolveError::Io {
        file: dir.clone(),
        error: std::io::Error::new(e.kind(), format!("output_directory (--out): {e}")),
    })?;
    check_inputs_are_not_results(config)?;
    if let Some(q) = config
        .settings
        .qp_dump_dir
        .as_ref()
        .filter(|q| q.exists() && !q.is_dir())
    {
        return Err(SolveError::Io {
            file: q.clone(),
            error: std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                "--dump-qps: cannot create the QP directory: a file of that name exists",
            ),
        });
    }
    progress(&format!("model {}", config.model.display()));
    let model = Model::from_file(&config.model)?;
    // The setting blends Thelen's switch for the optimizer; De Groote's
    // smooth switch is the model's own (its forward check integrates it).
    if model.muscle_model == crate::model::MuscleModel::DeGrooteFregly2016Muscle
        && config.problem.activation_dynamics_smoothing.is_some()
    {
        return Err(SolveError::Setting {
            origin: config
                .study_file
                .as_ref()
                .map_or_else(|| "built-in study".into(), |p| p.display().to_string()),
            field: "problem.activation_dynamics_smoothing".into(),
            reason: format!(
                "smooths Thelen2003Muscle's activation switch for the optimizer; the muscles of {} are DeGrooteFregly2016Muscle, whose smooth switch is the model's own",
                config.model.display()
            ),
        });
    }
    if config.method == Method::Shooting {
        return run_shooting(config, &model, verbose, progress);
    }
    let big_n = config.transcription.num_mesh_intervals;
    let options = collocation_problem_options(&config.transcription, &config.problem);
    progress("static squat and jump problem");
    let ocp = Arc::new(JumpOcp::new(&model, options)?);
    progress(&format!(
        "collocation: {} mesh intervals, {}, {} fibre dynamics, {} points",
        big_n,
        scheme_name(config.transcription.scheme),
        fiber_dynamics_name(config.transcription.fiber_dynamics),
        backend_name(config.transcription.backend)
    ));
    for line in &config.switched {
        progress(line);
    }
    let mut tr = Transcription::new(ocp.clone(), config.transcription)?;
    let mut mesh_integration = None;
    let mut unread_guess = Vec::new();
    let mut guess_projected = Vec::new();
    let (guess, guess_name, guess_jump) = match &config.guess {
        GuessChoice::BangBang => {
            progress("initial guess: the bang-bang jump, integrated on the mesh");
            let (mut v, s) = tr.bang_bang_guess().map_err(|e| {
                let failed = matches!(e, TranscriptionError::Simulation(_));
                bang_bang_failure(&model, Method::Collocation, failed, e)
            })?;
            let m = integrate_guess_on_mesh(&mut tr, &mut v, progress).map_err(|e| {
                of_model(
                    &model,
                    format!("the bang-bang guess integrated on the mesh: {e}"),
                )
            })?;
            mesh_integration = Some(m);
            (v, "bang-bang".to_string(), Some(s.jump_height_m))
        }
        GuessChoice::BangBangResampled => {
            progress("initial guess: the bang-bang jump, resampled onto the mesh");
            let (v, s) = tr.bang_bang_guess().map_err(|e| {
                let failed = matches!(e, TranscriptionError::Simulation(_));
                bang_bang_failure(&model, Method::Collocation, failed, e)
            })?;
            (v, "bang-bang-resampled".to_string(), Some(s.jump_height_m))
        }
        GuessChoice::File(p) if config.integrate_guess => {
            progress(&format!(
                "initial guess: {}, its excitations integrated on the mesh",
                p.display()
            ));
            let FileGuess { mut v, unread, .. } = guess_from_file_with(&tr, p, false)?;
            say_guess_warnings(progress, p, &unread, &[]);
            unread_guess = unread;
            let m = integrate_guess_on_mesh(&mut tr, &mut v, progress).map_err(|e| {
                SolveError::Guess {
                    file: p.clone(),
                    reason: format!("its excitations integrated on the mesh: {e}"),
                }
            })?;
            mesh_integration = Some(m);
            (v, p.display().to_string(), None)
        }
        GuessChoice::File(p) => {
            progress(&format!("initial guess: {}", p.display()));
            let FileGuess {
                v,
                unread,
                projected,
            } = guess_from_file_with(&tr, p, true)?;
            say_guess_warnings(progress, p, &unread, &projected);
            unread_guess = unread;
            guess_projected = projected;
            (v, p.display().to_string(), None)
        }
    };
    // The results directory only once the problem is set up.
    create_results_dir(dir).map_err(|error| SolveError::Io {
        file: dir.clone(),
        error,
    })?;
    let mut settings = config.settings.clone();
    settings.verbose = verbose;
    let hessian = match settings.hessian {
        HessianMode::ExactConvexified => "exact element Hessians",
        HessianMode::PartitionedBfgs => "partitioned BFGS",
    };
    progress(&format!(
        "SQP: {} variables, {} constraints, at most {} iterations, {hessian}",
        tr.num_variables(),
        tr.num_constraints(),
        settings.max_iterations
    ));
    clear_qp_dumps(&settings, progress)?;
    let result = crate::sqp::solve_from(&mut tr, &guess, &settings);
    let mut report = evaluate(&mut tr, &result);
    report.guess = guess_name;
    report.guess_jump_height_m = guess_jump;
    report.guess_mesh_integration = mesh_integration;
    report.unread_guess_columns = unread_guess;
    report.guess_projected_states = guess_projected;
    report.switched_study_settings = config.switched.clone();
    report.study = config.study_file.as_ref().map(|p| p.display().to_string());
    report.model = config.model.display().to_string();
    report.hessian_option = crate::study::hessian_option_name(&config.settings);
    report.line_search = LineSearchReport::new(&config.settings, result.filter_resets);

    // Outputs.
    let mesh = tr.unpack(&result.x);
    let grf: Vec<[f64; 12]> = node_grf(&ocp, &mesh);
    finish(
        config,
        &ocp,
        &mesh,
        &result,
        report,
        (&mesh.time, &grf),
        progress,
    )
}

/// A guess's excitations integrated on the mesh, its states replaced
/// ([`Transcription::integrate_on_mesh`]); one progress line on how it went.
fn integrate_guess_on_mesh(
    tr: &mut Transcription,
    v: &mut [f64],
    progress: &mut dyn FnMut(&str),
) -> Result<crate::transcription::MeshIntegration, String> {
    let started = std::time::Instant::now();
    let m = tr.integrate_on_mesh(v).map_err(|e| e.to_string())?;
    let mut left = Vec::new();
    if m.at_bound > 0 {
        left.push(format!("{} stopped with a state at its bound", m.at_bound));
    }
    if m.stopped_short > 0 {
        left.push(format!(
            "{} stopped short inside the bounds",
            m.stopped_short
        ));
    }
    if let Some(u) = &m.first_unsolved {
        let first = if m.at_bound + m.stopped_short > 1 {
            "the first: "
        } else {
            ""
        };
        let why = match &u.held {
            Some(h) => format!(
                ", {} held at its {} bound",
                h.name,
                if h.lower { "lower" } else { "upper" }
            ),
            None => String::new(),
        };
        left.push(format!("{first}interval {}{why}", u.interval));
    }
    let left = if left.is_empty() {
        String::new()
    } else {
        format!(" ({})", left.join("; "))
    };
    progress(&format!(
        "initial guess: {} of {} intervals integrated to {:.0e}{left} in {:.2} s; largest defect left {:.2e} (interval {}, {})",
        m.converged,
        m.intervals,
        crate::transcription::MESH_NEWTON_TOL,
        started.elapsed().as_secs_f64(),
        m.worst_defect,
        m.worst_interval,
        m.worst_state_name
    ));
    Ok(m)
}

/// [`run`] for method "shooting" ([`crate::shooting`]).
fn run_shooting(
    config: &SolveConfig,
    model: &Model,
    verbose: bool,
    progress: &mut dyn FnMut(&str),
) -> Result<SolveReport, SolveError> {
    let dir = &config.output_directory;
    let big_n = config.transcription.num_mesh_intervals;
    let options = config.problem.ocp_options(big_n);
    progress("static squat and jump problem");
    let ocp = Arc::new(JumpOcp::new(model, options)?);
    let opts = ShootingOptions {
        num_intervals: big_n,
        ..config.shooting
    };
    let derivatives = match opts.derivatives {
        ShootingDerivatives::CentralDifference => {
            format!(
                "central differences of step {:e}",
                opts.finite_difference_step
            )
        }
        ShootingDerivatives::ForwardSensitivity => "forward sensitivities".to_string(),
    };
    progress(&format!(
        "direct shooting: {big_n} control intervals, Dormand–Prince 5(4) at accuracy {:e}, {derivatives} on {} threads",
        opts.accuracy, opts.threads
    ));
    let mut sh = Shooting::new(ocp.clone(), opts)?;
    if !config.ignored.is_empty() {
        progress(&format!(
            "method shooting ignores the study's {}",
            config.ignored.join(", ")
        ));
    }
    let mut unread_guess = Vec::new();
    let (guess, guess_name, guess_jump) = match &config.guess {
        GuessChoice::BangBang | GuessChoice::BangBangResampled => {
            progress("initial guess: the bang-bang excitations at the nodes");
            let (v, s) = sh.bang_bang_guess().map_err(|e| {
                let failed = matches!(e, OcpError::Simulation(_));
                bang_bang_failure(model, Method::Shooting, failed, e)
            })?;
            (v, "bang-bang".to_string(), Some(s.jump_height_m))
        }
        GuessChoice::File(p) => {
            progress(&format!(
                "initial guess: the excitations of {}",
                p.display()
            ));
            let (v, unread) = shooting_guess_from_file(&sh, p)?;
            say_guess_warnings(progress, p, &unread, &[]);
            unread_guess = unread;
            (v, p.display().to_string(), None)
        }
    };
    create_results_dir(dir).map_err(|error| SolveError::Io {
        file: dir.clone(),
        error,
    })?;
    let mut settings = crate::shooting::sqp_settings(&config.settings);
    settings.verbose = verbose;
    progress(&format!(
        "SQP: {} variables, {} constraints ({} Jacobian entries), at most {} iterations, BFGS",
        sh.num_variables(),
        sh.num_constraints(),
        sh.jacobian_structure().len(),
        settings.max_iterations
    ));
    clear_qp_dumps(&settings, progress)?;
    let result = crate::sqp::solve_from(&mut sh, &guess, &settings);
    let violation = match crate::nlp::constraint_violations(&mut sh, &result.x) {
        Ok(v) => v.into_iter().fold(0.0, f64::max),
        Err(_) => f64::NAN,
    };
    let (nodes, traj) = sh
        .trajectory(&result.x)
        .map_err(|e| SolveError::Solution(format!("the last iterate does not integrate: {e}")))?;
    let tf = sh.final_time(&result.x);
    let h = tf / big_n as f64;
    let nu = ocp.nu();
    let controls = sh.node_controls(&result.x);
    let mesh = MeshTrajectory {
        time: (0..=big_n).map(|k| k as f64 * h).collect(),
        states: nodes.states.clone(),
        controls: controls.chunks(nu).map(<[f64]>::to_vec).collect(),
    };
    let mut report = shooting_report(&ocp, &sh, &result, &nodes, &traj, violation);
    report.guess = guess_name;
    report.unread_guess_columns = unread_guess;
    report.guess_jump_height_m = guess_jump;
    report.study = config.study_file.as_ref().map(|p| p.display().to_string());
    report.model = config.model.display().to_string();
    report.hessian_option = crate::study::hessian_option_name(&config.settings);
    report.line_search = LineSearchReport::new(&config.settings, result.filter_resets);
    report.ignored_study_settings = config.ignored.clone();
    let o = sh.options();
    report.shooting = Some(ShootingSummary {
        derivatives: o.derivatives.name(),
        integrator_accuracy: o.accuracy,
        finite_difference_step: (o.derivatives == ShootingDerivatives::CentralDifference)
            .then_some(o.finite_difference_step),
        counters: sh.counters,
    });
    let grf = (traj.time.as_slice(), traj.grf.as_slice());
    finish(config, &ocp, &mesh, &result, report, grf, progress)
}

/// The output files of either method: the solution at the nodes, the
/// ground forces `grf` (times and forces), the iteration history, the
/// forward check and the summary.
///
/// A write that fails part-way (a full disk) would leave this run's first
/// files beside an earlier run's others, read as one solve: the earlier
/// run's result files (those older than this run's writing) are removed
/// too, and the error lists what this run wrote and what was removed.
fn finish(
    config: &SolveConfig,
    ocp: &Arc<JumpOcp>,
    mesh: &MeshTrajectory,
    result: &SqpResult,
    report: SolveReport,
    grf: (&[f64], &[[f64; 12]]),
    progress: &mut dyn FnMut(&str),
) -> Result<SolveReport, SolveError> {
    if let Some(w) = &config.writing {
        w.store(true, std::sync::atomic::Ordering::SeqCst);
    }
    let (dir, name) = (&config.output_directory, &config.name);
    // Each result file as it was: every write replaces its file by a new
    // one (`io::write_output_with`), so a file this run wrote is another.
    let identity = |f: &str| {
        dir.join(f)
            .metadata()
            .ok()
            .filter(|m| m.is_file())
            .map(|m| (m.modified().ok(), file_id(&m)))
    };
    let before: Vec<(String, _)> = result_files(name)
        .into_iter()
        .map(|f| {
            let id = identity(&f);
            (f, id)
        })
        .collect();
    let error = match write_results(config, ocp, mesh, result, report, grf, progress) {
        Ok(report) => return Ok(report),
        Err(e) => e,
    };
    let (mut written, mut removed) = (Vec::new(), Vec::new());
    for (f, was) in before {
        match identity(&f) {
            // Removed as stale before the write that failed.
            None if was.is_some() => removed.push(f),
            None => {}
            Some(now) if Some(now) != was => written.push(f),
            Some(_) if std::fs::remove_file(dir.join(&f)).is_ok() => removed.push(f),
            Some(_) => {}
        }
    }
    if written.is_empty() {
        return Err(error);
    }
    let list = |v: &[String]| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.join(", ")
        }
    };
    Err(SolveError::Partial {
        error: Box::new(error),
        written: list(&written),
        removed: list(&removed),
    })
}

/// A file's identity on its file system (its inode on Unix).
fn file_id(m: &std::fs::Metadata) -> u64 {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        m.ino()
    }
    #[cfg(not(unix))]
    {
        m.len()
    }
}

/// [`finish`]'s writing.
fn write_results(
    config: &SolveConfig,
    ocp: &Arc<JumpOcp>,
    mesh: &MeshTrajectory,
    result: &SqpResult,
    mut report: SolveReport,
    grf: (&[f64], &[[f64; 12]]),
    progress: &mut dyn FnMut(&str),
) -> Result<SolveReport, SolveError> {
    let (dir, name) = (&config.output_directory, &config.name);
    let mut files = Vec::new();
    let p = dir.join(format!("{name}_solution.sto"));
    solution_table(ocp, mesh, result, &report).write_sto(&p)?;
    files.push(p);
    let p = dir.join(format!("{name}_grf.mot"));
    grf_table(&format!("{name}_grf"), grf.0, grf.1).write_mot(&p)?;
    files.push(p);
    let p = dir.join(format!("{name}_history.csv"));
    result
        .write_history_csv(&p)
        .map_err(|error| SolveError::Io {
            file: p.clone(),
            error,
        })?;
    files.push(p);
    // Shooting's nodes are its own integrator's: only a collocation mesh
    // has a local error to measure.
    if config.method == Method::Collocation && config.forward_check.is_some() {
        let excitations = crate::mesh_error::Excitations::of(config.transcription.scheme);
        match crate::mesh_error::mesh_error(
            &ocp.eq,
            &ocp.laws,
            mesh,
            excitations,
            MESH_ERROR_ACCURACY,
        ) {
            Ok(m) => report.mesh_error = Some(m),
            Err(e) => report.mesh_error_failure = Some(e),
        }
    }
    if let Some(fc) = config.forward_check {
        progress("forward check: the optimal excitations integrated from the squat");
        let (check, fw_files) = forward_check(ocp, mesh, fc, dir, name)?;
        files.extend(fw_files);
        // Without a lift-off the forward run did not jump: no height to
        // compare with the prediction (its COM change is not one).
        let jumped = |s: &crate::simulate::JumpSummary| {
            s.liftoff_time_s.is_some().then_some(s.jump_height_m)
        };
        report.forward_jump_height_m = check.summary.as_ref().and_then(jumped);
        report.forward_jump_height_rust_m = check.rust_summary.as_ref().and_then(jumped);
        report.forward_check_difference_m = report
            .forward_jump_height_m
            .map(|h| h - report.jump_height_m);
        report.forward_check_agrees = report
            .forward_check_difference_m
            .map(|d| d.abs() <= FORWARD_CHECK_TOLERANCE_M);
        report.forward_liftoff_while_falling = check
            .summary
            .as_ref()
            .map(|s| s.falling_at_liftoff().is_some());
        report.forward_check = Some(check);
    }
    let p = dir.join(format!("{name}_summary.json"));
    files.push(p.clone());
    report.removed_stale_files = remove_stale_results(dir, name, &files)?;
    report.earlier_reports = earlier_reports(dir, name);
    report.output_files = files.iter().map(|f| f.display().to_string()).collect();
    let text = serde_json::to_string_pretty(&report).unwrap_or_default();
    crate::io::write_output(&p, text).map_err(|error| SolveError::Io { file: p, error })?;
    Ok(report)
}

/// A shooting guess from a controls or solution file: its excitations
/// sampled at the nodes, t_f its last time (within the final time's
/// bounds).
fn shooting_guess_from_file(
    sh: &Shooting,
    path: &Path,
) -> Result<(Vec<f64>, Vec<String>), SolveError> {
    let eq = &sh.ocp.eq;
    let muscles: Vec<&str> = eq
        .muscles
        .iter()
        .map(|&m| eq.model.muscles[m].spec.name.as_str())
        .collect();
    let t = StoTable::read(path)?;
    let controls = Controls::from_table(&t, path, &muscles)?;
    let tf = guess_final_time(path, &controls.time, sh.ocp.options.final_time_bounds)?;
    let v = sh
        .point_from_source(&controls, tf)
        .map_err(|e| SolveError::Guess {
            file: path.into(),
            reason: e.to_string(),
        })?;
    Ok((v, unread_guess_columns(&eq.model, &t)))
}

/// The report of a shooting solve, from its last iterate integrated with
/// every step recorded: the peak ground force and lift-off over the steps,
/// not only the nodes.
fn shooting_report(
    ocp: &JumpOcp,
    sh: &Shooting,
    r: &SqpResult,
    nodes: &NodeValues,
    traj: &crate::simulate::Trajectory,
    violation: f64,
) -> SolveReport {
    let tf = sh.final_time(&r.x);
    let force: Vec<f64> = traj
        .grf
        .iter()
        .map(|g| (g[1] + g[7]) / ocp.body_weight)
        .collect();
    let max = |v: &[f64]| v.iter().copied().fold(f64::NAN, f64::max);
    let level = ocp.options.liftoff.fraction();
    let mut ws = ocp.eq.multibody.workspace::<f64>();
    let mut com = |x: &[f64]| ocp.jump_objective(&mut ws, x);
    let last = nodes.states.len().saturating_sub(1);
    let at_tf = (
        tf,
        nodes.com_height.get(last).copied().unwrap_or(f64::NAN),
        nodes.com_velocity.get(last).copied().unwrap_or(f64::NAN),
    );
    let (t_liftoff, y, ydot) = match force.iter().rposition(|&f| f > level) {
        Some(i) if i + 1 < force.len() => {
            let (t0, t1) = (traj.time[i], traj.time[i + 1]);
            let w = (force[i] - level) / (force[i] - force[i + 1]);
            let (a, b) = (com(&traj.states[i]), com(&traj.states[i + 1]));
            (
                t0 + (t1 - t0) * w,
                a.0 + w * (b.0 - a.0),
                a.1 + w * (b.1 - a.1),
            )
        }
        _ => at_tf,
    };
    let lifted_off = lift_off_row_holds(ocp, nodes.vertical_force_bw.last().copied());
    report_at(
        r,
        ocp,
        SolutionQuantities {
            method: Method::Shooting,
            apex: nodes.objective,
            final_time: tf,
            liftoff: (t_liftoff, y, ydot),
            lifted_off,
            peak_grf: (max(&force), max(&nodes.vertical_force_bw)),
            violation,
            mesh: (sh.num_intervals(), "direct shooting", "explicit"),
            backend: "rust-native",
            size: (sh.num_variables(), sh.num_constraints()),
        },
    )
}

/// The report's solution quantities at the SQP's last iterate.
fn evaluate(tr: &mut Transcription, r: &SqpResult) -> SolveReport {
    let ocp = tr.ocp.clone();
    let x = &r.x;
    let tf = tr.final_time(x);
    let mesh = tr.unpack(x);
    let forces_of = |m: &MeshTrajectory| -> Vec<f64> {
        node_grf(&ocp, m)
            .iter()
            .map(|g| (g[1] + g[7]) / ocp.body_weight)
            .collect()
    };
    let max = |v: &[f64]| v.iter().copied().fold(f64::NAN, f64::max);
    let node_forces = forces_of(&mesh);
    let peak_nodes = max(&node_forces);
    // The dynamics hold at the interval midpoints for midpoint Euler (mean
    // state and excitation), at the nodes otherwise.
    let points = if !tr.options().scheme.evaluates_dynamics_at_nodes() {
        let mean = |a: &[Vec<f64>]| -> Vec<Vec<f64>> {
            a.windows(2)
                .map(|w| w[0].iter().zip(&w[1]).map(|(p, q)| 0.5 * (p + q)).collect())
                .collect()
        };
        MeshTrajectory {
            time: mesh.time.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect(),
            states: mean(&mesh.states),
            controls: mean(&mesh.controls),
        }
    } else {
        mesh.clone()
    };
    let forces = forces_of(&points);
    let peak = max(&forces);
    // Lift-off: J is constant in flight, so t_f may lie after it (the
    // lift-off row only bounds the force at t_f). The ground contact ends
    // where the vertical force at the points where the dynamics hold last
    // falls through the lift-off row's level, interpolated linearly; the
    // lift-off COM height and velocity are taken there.
    let level = ocp.options.liftoff.fraction();
    let t_liftoff = match forces.iter().rposition(|&f| f > level) {
        Some(i) if i + 1 < forces.len() => {
            let (t0, t1) = (points.time[i], points.time[i + 1]);
            let (f0, f1) = (forces[i], forces[i + 1]);
            t0 + (t1 - t0) * (f0 - level) / (f0 - f1)
        }
        _ => tf,
    };
    let lifted_off = lift_off_row_holds(&ocp, node_forces.last().copied());
    // Y_C, Ẏ_C and J at every node; J at the last is the objective.
    let mut ws = ocp.eq.multibody.workspace::<f64>();
    let com: Vec<(f64, f64, f64)> = mesh
        .states
        .iter()
        .map(|x| ocp.jump_objective(&mut ws, x))
        .collect();
    let (y_f, ydot_f, j) = com
        .last()
        .copied()
        .unwrap_or((f64::NAN, f64::NAN, f64::NAN));
    let (y, ydot) = match mesh.time.iter().position(|&t| t >= t_liftoff) {
        Some(k) if k > 0 => {
            let (t0, t1) = (mesh.time[k - 1], mesh.time[k]);
            let w = ((t_liftoff - t0) / (t1 - t0)).clamp(0.0, 1.0);
            let lerp = |a: f64, b: f64| a + w * (b - a);
            (lerp(com[k - 1].0, com[k].0), lerp(com[k - 1].1, com[k].1))
        }
        _ => (y_f, ydot_f),
    };
    let violation = match crate::nlp::constraint_violations(tr, x) {
        Ok(v) => v.into_iter().fold(0.0, f64::max),
        Err(_) => f64::NAN,
    };
    report_at(
        r,
        &ocp,
        SolutionQuantities {
            method: Method::Collocation,
            apex: j,
            final_time: tf,
            liftoff: (t_liftoff, y, ydot),
            lifted_off,
            peak_grf: (peak, peak_nodes),
            violation,
            mesh: (
                tr.num_intervals(),
                scheme_name(tr.options().scheme),
                fiber_dynamics_name(tr.options().fiber_dynamics),
            ),
            backend: backend_name(tr.options().backend),
            size: (tr.num_variables(), tr.num_constraints()),
        },
    )
}

/// The paper's constraint tolerance: its solutions meet every constraint
/// to 1e-3 (Porsa et al. 2016).
pub const PAPER_CONSTRAINT_TOLERANCE: f64 = 1e-3;

/// Whether the lift-off row F_y(t_f)/(m g) ≤ level holds within the
/// paper's constraint tolerance (1e-3) for the vertical force at t_f.
fn lift_off_row_holds(ocp: &JumpOcp, force_at_tf: Option<f64>) -> bool {
    force_at_tf.is_some_and(|f| f <= ocp.liftoff_bounds().1 + PAPER_CONSTRAINT_TOLERANCE)
}

/// What either method's solution gives its report.
struct SolutionQuantities {
    method: Method,
    /// J at t_f (m).
    apex: f64,
    final_time: f64,
    /// Lift-off time, Y_C and Ẏ_C there (t_f's without lift-off).
    liftoff: (f64, f64, f64),
    lifted_off: bool,
    /// Peak vertical ground force / body weight, and over the nodes.
    peak_grf: (f64, f64),
    violation: f64,
    /// Intervals, scheme, fibre dynamics.
    mesh: (usize, &'static str, &'static str),
    /// Where the points were evaluated ("rust-native", "simbody").
    backend: &'static str,
    /// Variables, constraints.
    size: (usize, usize),
}

/// The report of a solve ending at `r` (no forward check, guess or files
/// yet).
fn report_at(r: &SqpResult, ocp: &JumpOcp, q: SolutionQuantities) -> SolveReport {
    let j = q.apex;
    SolveReport {
        method: q.method,
        status: r.status,
        moco_status: moco_status(r.status),
        success: r.status.success(),
        message: r.message.clone(),
        iterations: r.iterations,
        wall_time_s: r.time.total_s,
        wall_time_per_iteration_s: r.time.total_s / r.iterations.max(1) as f64,
        objective: -j,
        jump_height_m: j - ocp.standing_com_height,
        apex_com_height_m: j,
        standing_com_height_m: ocp.standing_com_height,
        ground_contact_time_s: q.liftoff.0,
        final_time_s: q.final_time,
        lifted_off: q.lifted_off,
        liftoff_com_velocity_mps: q.liftoff.2,
        liftoff_com_height_m: q.liftoff.1,
        peak_vertical_grf_bw: q.peak_grf.0,
        peak_vertical_grf_nodes_bw: q.peak_grf.1,
        max_constraint_violation: q.violation,
        dual_infeasibility: r.dual_infeasibility,
        forward_jump_height_m: None,
        forward_check_difference_m: None,
        forward_liftoff_while_falling: None,
        forward_check_agrees: None,
        forward_jump_height_rust_m: None,
        forward_check: None,
        mesh_error: None,
        mesh_error_failure: None,
        guess: String::new(),
        guess_jump_height_m: None,
        guess_mesh_integration: None,
        num_mesh_intervals: q.mesh.0,
        scheme: q.mesh.1,
        fiber_dynamics: q.mesh.2,
        backend: q.backend,
        hessian: r.hessian,
        hessian_option: "",
        time_final_bounds: ocp.options.final_time_bounds,
        no_countermovement_nodes: ocp.options.no_countermovement_nodes,
        no_com_descent: ocp.options.no_com_descent,
        activation_dynamics_smoothing: ocp.options.activation_smoothing,
        variables: q.size.0,
        constraints: q.size.1,
        time_split: r.time,
        qp_fallbacks: r.qp_fallbacks,
        qp_fallbacks_infeasible: r.qp_fallbacks_infeasible,
        qp_fallback_seconds: r.qp_fallback_seconds,
        qp_stalls_taken_infeasible: r.qp_stalls_taken_infeasible,
        // Set by the run, which has the settings.
        line_search: LineSearchReport::default(),
        hessian_shift: crate::sqp::HessianShiftSummary::of(&r.history),
        study: None,
        ignored_study_settings: Vec::new(),
        switched_study_settings: Vec::new(),
        shooting: None,
        model: String::new(),
        output_files: Vec::new(),
        removed_stale_files: Vec::new(),
        earlier_reports: Vec::new(),
        unread_guess_columns: Vec::new(),
        guess_projected_states: Vec::new(),
    }
}

/// Ground reaction forces per foot at each node, from the contact alone.
pub fn node_grf(ocp: &JumpOcp, mesh: &MeshTrajectory) -> Vec<[f64; 12]> {
    let mut ws = ocp.eq.workspace::<f64>();
    // The contact forces alone: a node whose muscles have no explicit fibre
    // velocity (a DeGroote muscle of implicit fibre dynamics at a = 0) still
    // has its ground forces.
    mesh.states
        .iter()
        .map(|x| match ocp.eq.contact_forces(&ocp.laws, &mut ws, x) {
            Ok(()) => grf_of(&ocp.eq, &ws, x),
            Err(_) => [f64::NAN; 12],
        })
        .collect()
}

/// The solution as a Moco solution table: time, states, then excitations,
/// with `MocoSolution`'s metadata; every state and excitation of the whole
/// model, both legs ([`crate::ode::StateEquation::model_state_columns`]),
/// so that Moco reads it on the model file.
pub fn solution_table(
    ocp: &JumpOcp,
    mesh: &MeshTrajectory,
    r: &SqpResult,
    report: &SolveReport,
) -> StoTable {
    let mut t = StoTable::default();
    let md = &mut t.metadata;
    md.insert("inDegrees".into(), "no".into());
    let state_columns = ocp.eq.model_state_columns();
    let control_columns = ocp.eq.model_control_columns();
    md.insert("num_states".into(), state_columns.len().to_string());
    md.insert("num_controls".into(), control_columns.len().to_string());
    for k in [
        "num_multipliers",
        "num_derivatives",
        "num_parameters",
        "num_slacks",
    ] {
        md.insert(k.into(), "0".into());
    }
    md.insert("num_iterations".into(), r.iterations.to_string());
    md.insert("objective".into(), format!("{}", report.objective));
    md.insert("solver_duration".into(), format!("{:.6}", r.time.total_s));
    md.insert("status".into(), moco_status(r.status).into());
    md.insert("success".into(), r.status.success().to_string());
    let (mut labels, states) = crate::simulate::model_columns(&state_columns, &mesh.states);
    let (control_labels, controls) =
        crate::simulate::model_columns(&control_columns, &mesh.controls);
    labels.extend(control_labels);
    t.labels = labels;
    t.time = mesh.time.clone();
    t.rows = states
        .into_iter()
        .zip(controls)
        .map(|(mut x, u)| {
            x.extend(u);
            x
        })
        .collect();
    t
}

/// A guess from a `.sto` with every state and excitation column (a
/// previous solution), from t = 0, resampled onto the mesh with t_f its
/// last time, which must lie within the final time's bounds. Angles in
/// degrees (`inDegrees=yes`) are converted to radians; time must be finite
/// and strictly increasing over at least 2 rows, every value used finite,
/// activations in [0, 1] and fibre lengths positive.
pub fn guess_from_file(tr: &Transcription, path: &Path) -> Result<Vec<f64>, SolveError> {
    guess_from_file_with(tr, path, true).map(|g| g.v)
}

/// The guess of a file's excitations alone (a solution, or a controls file
/// as `leap simulate` reads it), every node's states the squat's, for
/// [`Transcription::integrate_on_mesh`] to replace; t_f its last time.
pub fn guess_from_excitations_file(
    tr: &Transcription,
    path: &Path,
) -> Result<Vec<f64>, SolveError> {
    guess_from_file_with(tr, path, false).map(|g| g.v)
}

/// A guess read from a file.
struct FileGuess {
    v: Vec<f64>,
    /// The file's excitation-like columns that name no muscle of the model
    /// (not read; [`crate::io::unread_excitation_columns`]).
    unread: Vec<String>,
    /// The states that lay outside their bounds (projected into them).
    projected: Vec<GuessProjection>,
}

/// The guess of a file, with its states or without.
fn guess_from_file_with(
    tr: &Transcription,
    path: &Path,
    with_states: bool,
) -> Result<FileGuess, SolveError> {
    // Without states, the file's state columns are not read; they are
    // checked only to be finite (`Controls::from_table`).
    let t = if with_states {
        crate::io::read_states(&tr.ocp.eq, path)?
    } else {
        let t = StoTable::read(path)?;
        t.check_time(path, 2)?;
        t
    };
    let bad = |reason: String| SolveError::Guess {
        file: path.into(),
        reason,
    };
    let tf = guess_final_time(path, &t.time, tr.ocp.options.final_time_bounds)?;
    let eq = &tr.ocp.eq;
    let missing = "missing (a guess needs every state and control column; with integrate_guess (--integrate-guess) the control columns alone)";
    let states = if with_states {
        t.finite_columns(path, &eq.state_names(), missing)?
    } else {
        vec![tr.ocp.x0().to_vec(); t.time.len()]
    };
    // Excitations as a controls file reads them (finite, in [0, 1]).
    let muscles: Vec<&str> = eq
        .muscles
        .iter()
        .map(|&m| eq.model.muscles[m].spec.name.as_str())
        .collect();
    let controls = Controls::from_table(&t, path, &muscles)?.values;
    let (v, projected) = tr
        .guess_from_trajectory(&t.time, &states, &controls, tf)
        .map_err(|e| bad(e.to_string()))?;
    Ok(FileGuess {
        v,
        unread: unread_guess_columns(&eq.model, &t),
        projected,
    })
}

/// A guess file's t_f, its last time: the file must start at 0 (the
/// squat) and end within the final time's `bounds`.
fn guess_final_time(path: &Path, time: &[f64], bounds: [f64; 2]) -> Result<f64, SolveError> {
    let bad = |reason: String| SolveError::Guess {
        file: path.into(),
        reason,
    };
    let (Some(&t0), Some(&tf)) = (time.first(), time.last()) else {
        return Err(bad("time: no rows".into()));
    };
    if t0.abs() > 1e-9 {
        return Err(bad(format!(
            "time: starts at {} s; a guess must start at 0 (the squat)",
            crate::io::readable(t0)
        )));
    }
    let [t_min, t_max] = bounds;
    if !(t_min..=t_max).contains(&tf) {
        return Err(bad(format!(
            "time: ends at {} s, outside the final time's bounds [{t_min}, {t_max}] s (the study's problem.time_final_bounds; the guess's last time is its t_f)",
            crate::io::readable(tf)
        )));
    }
    Ok(tf)
}

/// The warnings on a guess file: its columns read by nothing, its states
/// projected into their bounds. Said as soon as the guess is read (in the
/// progress lines, before the SQP) and again in the summary.
fn guess_warnings(guess: &str, unread: &[String], projected: &[GuessProjection]) -> Vec<String> {
    let mut w = Vec::new();
    if !unread.is_empty() {
        w.push(format!(
            "warning: {guess}: {} column(s) name no muscle of the model and are not read: {}",
            unread.len(),
            unread.join(", ")
        ));
    }
    for p in projected {
        w.push(format!("warning: {guess}: {p}; projected into the bounds"));
    }
    w
}

/// [`guess_warnings`] of guess file `p` as progress lines.
fn say_guess_warnings(
    progress: &mut dyn FnMut(&str),
    p: &Path,
    unread: &[String],
    projected: &[GuessProjection],
) {
    for w in guess_warnings(&p.display().to_string(), unread, projected) {
        progress(&w);
    }
}

/// The columns of a guess file that look like excitations but name no
/// muscle of the model (either leg): a misspelt muscle, read by nothing.
fn unread_guess_columns(model: &Model, t: &StoTable) -> Vec<String> {
    let all: Vec<&str> = model.muscles.iter().map(|m| m.spec.name.as_str()).collect();
    crate::io::unread_excitation_columns(t, &all)
}

/// Integrate the node excitations (linear between nodes, held after t_f)
/// from the squat with Simbody and with the Rust-native integrator; write
/// Simbody's trajectory as `<name>_forward_*`.
fn forward_check(
    ocp: &Arc<JumpOcp>,
    mesh: &MeshTrajectory,
    fc: ForwardCheck,
    dir: &Path,
    name: &str,
) -> Result<(ForwardCheckReport, Vec<PathBuf>), SolveError> {
    let mut report = ForwardCheckReport {
        integrator: format!("{:?}", fc.integrator),
        accuracy: fc.accuracy,
        summary: None,
        rust_summary: None,
        excitation_sensitivity: None,
        optimizer_dynamics_jump_height_m: None,
        push_off: None,
        errors: Vec::new(),
    };
    let tf = mesh.time.last().copied().unwrap_or(f64::NAN);
    if !(tf.is_finite() && tf > 0.0) || mesh.time.windows(2).any(|w| w[1] <= w[0]) {
        report
            .errors
            .push(format!("no forward check: final time {tf} s"));
        return Ok((report, Vec::new()));
    }
    let controls = Controls {
        time: mesh.time.clone(),
        values: mesh.controls.clone(),
    };
    let t_max = tf + FORWARD_FLIGHT_TIME;
    // The forward check integrates the model as OpenSim does, as `leap
    // simulate` does: not the optimizer's smoothed activation switch, fibre
    // clamp and conditional path points (the smoothed paths had put the
    // default solve's forward jump 0.16 mm lower).
    let (laws, eq) = match crate::ode::StateEquation::opensim(&ocp.eq.model, true) {
        Ok((laws, eq)) => (Arc::new(laws), Arc::new(eq)),
        Err(e) => {
            report.errors.push(format!("no forward check: {e}"));
            return Ok((report, Vec::new()));
        }
    };
    let simbody = simulate_simbody(
        &eq,
        &laws,
        &controls,
        ocp.x0(),
        ocp.standing_com_height,
        fc.integrator,
        fc.accuracy,
        t_max,
        1e-3,
    );
    let prefix = format!("{name}_forward");
    let files = match simbody {
        Ok((summary, traj)) => {
            report.summary = Some(summary);
            match crate::analyze::analyze(&eq, &laws, &traj.time, &traj.states, None) {
                Ok(a) => report.push_off = Some(a),
                Err(e) => report.errors.push(format!("push-off analysis: {e}")),
            }
            write_trajectory(&ocp.eq, &traj, dir, &prefix)?
        }
        Err(f) => {
            report
                .errors
                .push(format!("{:?} (Simbody): {f}", fc.integrator));
            write_trajectory(&ocp.eq, &f.trajectory, dir, &prefix)?
        }
    };
    let opts = SimulateOptions {
        integrator: crate::integrator::Dopri5Options {
            accuracy: 1e-6,
            ..Default::default()
        },
        t_max,
    };
    let rust_jump = |controls: &Controls| {
        simulate_rust(
            &eq,
            laws.as_ref(),
            controls,
            ocp.x0(),
            ocp.standing_com_height,
            opts,
        )
        .map(|(summary, _)| summary)
    };
    match simulate_rust(
        &ocp.eq,
        &ocp.laws,
        &controls,
        ocp.x0(),
        ocp.standing_com_height,
        opts,
    ) {
        Ok((s, _)) => report.optimizer_dynamics_jump_height_m = Some(s.jump_height_m),
        Err(f) => report.errors.push(format!(
            "Dormand-Prince (Rust), the optimizer's dynamics: {f}"
        )),
    }
    match rust_jump(&controls) {
        Ok(summary) => report.rust_summary = Some(summary),
        Err(f) => report.errors.push(format!("Dormand-Prince (Rust): {f}")),
    }
    let mut perturbed = |sign: f64| {
        let mut c = controls.clone();
        for v in c.values.iter_mut().flatten() {
            *v = (*v + sign * EXCITATION_OFFSET).clamp(0.0, 1.0);
        }
        match rust_jump(&c) {
            Ok(s) => Some(s.jump_height_m),
            Err(f) => {
                report.errors.push(format!(
                    "Dormand-Prince (Rust), excitations {:+}: {f}",
                    sign * EXCITATION_OFFSET
                ));
                None
            }
        }
    };
    let (raised, lowered) = (perturbed(1.0), perturbed(-1.0));
    let nominal = report.rust_summary.as_ref().map(|s| s.jump_height_m);
    let largest_change_m = match (nominal, raised, lowered) {
        (Some(h), Some(a), Some(b)) => Some((a - h).abs().max((b - h).abs())),
        _ => None,
    };
    report.excitation_sensitivity = Some(ExcitationSensitivity {
        offset: EXCITATION_OFFSET,
        jump_height_raised_m: raised,
        jump_height_lowered_m: lowered,
        largest_change_m,
    });
    Ok((report, files))
}

/// The table of `rows` under `header`, one row each (the paper's Table 2
/// layout), or, on a terminal too narrow for that, transposed: one line
/// per column of `header`, one column per row.
fn table_fitting_terminal(header: &[&str], rows: &[Vec<String>]) -> String {
    table_fitting(header, rows, comfy_table::Table::new().width())
}

/// [`table_fitting_terminal`] for a terminal `width` columns wide (None:
/// not a terminal).
fn table_fitting(header: &[&str], rows: &[Vec<String>], width: Option<u16>) -> String {
    let mut t = comfy_table::Table::new();
    t.set_header(header.to_vec());
    for r in rows {
        t.add_row(r.clone());
    }
    let text = t.to_string();
    let widest = text.lines().map(|l| l.chars().count()).max().unwrap_or(0);
    match width {
        Some(w) if widest > usize::from(w) => transposed(header, rows).to_string(),
        _ => text,
    }
}

/// `rows` under `header` as columns: `header[0]` and the rows' first cells
/// head the columns, each further header cell leads a line.
fn transposed(header: &[&str], rows: &[Vec<String>]) -> comfy_table::Table {
    let mut t = comfy_table::Table::new();
    let mut top = vec![header[0].to_string()];
    top.extend(rows.iter().map(|r| r[0].clone()));
    t.set_header(top);
    for (i, name) in header.iter().enumerate().skip(1) {
        let mut line = vec![name.to_string()];
        line.extend(rows.iter().map(|r| r[i].clone()));
        t.add_row(line);
    }
    t
}

impl SolveReport {
    /// The paper's Table 2 row and the forward check, for a terminal.
    pub fn table(&self) -> String {
        let header = [
            "",
            "iterations",
            "time (s)",
            "time / iteration (s)",
            "jump height (cm)",
            "ground contact time (s)",
            "lift-off COM velocity (m/s)",
            "peak vertical GRF (BW)",
            "max constraint violation",
        ];
        let leap = vec![
            "leap".to_string(),
            self.iterations.to_string(),
            format!("{:.2}", self.wall_time_s),
            format!("{:.3}", self.wall_time_per_iteration_s),
            format!("{:.2}", 100.0 * self.jump_height_m),
            format!("{:.3}", self.ground_contact_time_s),
            format!("{:.3}", self.liftoff_com_velocity_mps),
            format!("{:.2}", self.peak_vertical_grf_bw),
            format!("{:.2e}", self.max_constraint_violation),
        ];
        // Porsa et al. (2016): the cost of their solve by the same method
        // (MATLAB fmincon, 29 nodes), the predicted jump over their solves,
        // and the measured jumps (mean and range).
        let (iterations, time, per_iteration) = match self.method {
            Method::Collocation => ("702", "12240 (3.4 h CPU)", "17.4"),
            Method::Shooting => ("602", "3045600 (846 h CPU)", "5059"),
        };
        let paper = [
            "Porsa et al. 2016",
            iterations,
            time,
            per_iteration,
            "≈ 36.0",
            "0.28–0.31",
            "2.2",
            "3.0–3.1",
            "≤ 1e-3",
        ];
        let experiment = [
            "experiment",
            "",
            "",
            "",
            "36.9 (33–41)",
            "0.25–0.39",
            "2.0–2.5",
            "2.5–3.0",
            "",
        ];
        let rows = [
            leap,
            paper.map(String::from).to_vec(),
            experiment.map(String::from).to_vec(),
        ];
        let t = table_fitting_terminal(&header, &rows);
        let mut s = format!(
            "jump solve ({} mesh intervals, {}, {} fibre dynamics, {} Hessian{}): {} ({}){}\n{t}\n",
            self.num_mesh_intervals,
            self.scheme,
            self.fiber_dynamics,
            self.hessian_option,
            if self.backend == "rust-native" {
                String::new()
            } else {
                format!(", {} backend", self.backend)
            },
            self.status.name(),
            self.moco_status,
            if self.message.is_empty() {
                String::new()
            } else {
                format!(": {}", self.message)
            }
        );
        let paper = crate::study::ProblemSettings::default().ocp_options(self.num_mesh_intervals);
        if self.time_final_bounds != paper.final_time_bounds
            || self.no_countermovement_nodes != paper.no_countermovement_nodes
            || self.no_com_descent != paper.no_com_descent
            || self.activation_dynamics_smoothing != paper.activation_smoothing
        {
            s.push_str(&format!(
                "  problem (the study's): t_f in [{}, {}] s, {} no-countermovement rows (eq. 4), {}{}\n",
                self.time_final_bounds[0],
                self.time_final_bounds[1],
                self.no_countermovement_nodes,
                if self.no_com_descent {
                    "centre of mass never descending at the nodes"
                } else {
                    "no bound on the centre of mass's descent"
                },
                match self.activation_dynamics_smoothing {
                    Some(b) => format!(", activation switch smoothed with b = {b}"),
                    None => ", OpenSim's activation switch".into(),
                }
            ));
        }
        s.push_str(&format!("  leap's times are wall times of the SQP; the paper's are its {} solve's CPU time (MATLAB fmincon) and its predictions over its solves; the experiment's (Porsa et al. 2016) mean (range)\n", match self.method {
            Method::Collocation => "collocation",
            Method::Shooting => "shooting",
        }));
        if self.method == Method::Shooting {
            s.push_str(&format!(
                "  peak vertical GRF over every integrator step; at the nodes {:.2} BW\n",
                self.peak_vertical_grf_nodes_bw
            ));
        } else if self.peak_vertical_grf_nodes_bw != self.peak_vertical_grf_bw {
            s.push_str(&format!(
                "  peak vertical GRF at the interval midpoints, where the dynamics hold; at the nodes {:.2} BW\n",
                self.peak_vertical_grf_nodes_bw
            ));
        }
        let t = &self.time_split;
        s.push_str(&format!(
            "  time split: derivatives {:.2} s, Hessian {:.2} s, QP {:.2} s, line search {:.2} s, other {:.2} s\n",
            t.derivatives_s, t.hessian_s, t.qp_s, t.line_search_s, t.other_s
        ));
        if self.qp_fallbacks > 0 {
            s.push_str(&format!(
                "  {} QPs handed by leap's interior-point solver to clarabel ({} of them infeasible), {:.1} s of the QP time\n",
                self.qp_fallbacks, self.qp_fallbacks_infeasible, self.qp_fallback_seconds
            ));
        }
        if self.qp_stalls_taken_infeasible > 0 {
            s.push_str(&format!(
                "  {} plain QPs taken as infeasible where the interior-point solver stalled (the SQP went on with the elastic QP, or without a second-order correction)\n",
                self.qp_stalls_taken_infeasible
            ));
        }
        let ls = &self.line_search;
        if ls.max_filter_resets > 0 || ls.second_order_correction_every_rejected_step {
            s.push_str(&format!(
                "  line search: {} of at most {} filter resets (trigger {}), second-order correction of every rejected full step {}\n",
                ls.filter_resets,
                ls.max_filter_resets,
                ls.filter_reset_trigger,
                if ls.second_order_correction_every_rejected_step { "on" } else { "off" }
            ));
        }
        if let Some(h) = &self.hessian_shift {
            s.push_str(&format!(
                "  inertia correction: τ > 0 in {} of {} QPs, median {:.2e}, largest {:.2e} (τ I on the equilibrated QP, whose entries are at most about 1: a τ near 1 or above outweighs much of the exact curvature)\n",
                h.shifted, h.qps, h.median, h.max
            ));
        }
        if self.max_constraint_violation.is_nan() {
            s.push_str("  warning: the constraints could not be evaluated at the returned iterate (its violation is null in the JSON): its jump height, contact time, lift-off velocity and forces are not to be believed\n");
        } else if self.max_constraint_violation > PAPER_CONSTRAINT_TOLERANCE {
            s.push_str(&format!(
                "  warning: the returned iterate violates a constraint by {:.2e}, above the paper's {PAPER_CONSTRAINT_TOLERANCE:e} (the history CSV's `max_violation_constraint` names each iteration's most violated one): its jump height, contact time, lift-off velocity and forces are not to be believed\n",
                self.max_constraint_violation,
            ));
        }
        if !self.lifted_off {
            s.push_str(&format!(
                "  warning: the body is still on the ground at t_f = {:.3} s (the lift-off row is violated); the ground contact time and the lift-off velocity are t_f's, not a lift-off's\n",
                self.final_time_s,
            ));
        }
        if let Some(fc) = &self.forward_check {
            match (&fc.summary, self.forward_check_difference_m) {
                (Some(sm), Some(d)) => {
                    s.push_str(&format!(
                        "  forward check ({}, accuracy {:e}): jump height {:.2} cm ({:+.2} cm from the prediction), lift-off at {}\n",
                        fc.integrator,
                        fc.accuracy,
                        100.0 * sm.jump_height_m,
                        100.0 * d,
                        sm.liftoff_time_s
                            .map(|t| format!("{t:.3} s"))
                            .unwrap_or_else(|| "— (no lift-off)".into())
                    ));
                    // As `leap simulate` warns.
                    if let Some(v_down) = sm.falling_at_liftoff() {
                        s.push_str(&format!(
                            "  warning: in the forward check the feet left the ground with the centre of mass moving down at {v_down:.3} m/s: a fall, not a jump\n"
                        ));
                    }
                    if self.forward_check_agrees == Some(false) {
                        s.push_str(&format!(
                            "  warning: the forward check misses the prediction by more than {:.0} cm: the predicted jump does not hold for the model (a solve stopped early, or on a converged one the discretisation error of {:.1} ms intervals, which the optimizer exploits over a long push-off); do not read the predicted height as the model's\n",
                            100.0 * FORWARD_CHECK_TOLERANCE_M,
                            1e3 * self.final_time_s / self.num_mesh_intervals as f64
                        ));
                    }
                }
                _ => s.push_str("  forward check (Simbody): failed\n"),
            }
            if let Some(r) = &fc.rust_summary {
                s.push_str(&format!(
                    "  forward check (Dormand-Prince, Rust): jump height {:.2} cm\n",
                    100.0 * r.jump_height_m
                ));
                if let Some(h) = fc.optimizer_dynamics_jump_height_m {
                    s.push_str(&format!(
                        "  forward check under the optimizer's own (smoothed) dynamics: {:.2} cm, so {:+.2} cm of the difference is the mesh's, {:+.2} cm the smoothing's\n",
                        100.0 * h,
                        100.0 * (h - self.jump_height_m),
                        100.0 * (r.jump_height_m - h)
                    ));
                }
                if let Some(e) = &fc.excitation_sensitivity {
                    let cm = |h: Option<f64>| {
                        h.map_or("failed".to_string(), |h| {
                            format!("{:+.2} cm", 100.0 * (h - r.jump_height_m))
                        })
                    };
                    s.push_str(&format!(
                        "  open-loop sensitivity: every excitation {:+} changes that forward jump by {}, {:+} by {}{}\n",
                        e.offset,
                        cm(e.jump_height_raised_m),
                        -e.offset,
                        cm(e.jump_height_lowered_m),
                        if e.largest_change_m.is_some_and(|d| d > FORWARD_CHECK_TOLERANCE_M) {
                            format!(
                                "; warning: {}% of excitation moves the jump by more than {:.0} cm: the movement is highly sensitive open loop (as a long push-off that balances the body), and its predicted height is no robust prediction",
                                100.0 * e.offset,
                                100.0 * FORWARD_CHECK_TOLERANCE_M
                            )
                        } else {
                            String::new()
                        }
                    ));
                }
            }
            if let Some(a) = &fc.push_off {
                let fastest = a
                    .muscles
                    .iter()
                    .filter(|m| !m.peak_shortening_ratio.is_nan())
                    .max_by(|x, y| x.peak_shortening_ratio.total_cmp(&y.peak_shortening_ratio));
                let full = a
                    .muscles
                    .iter()
                    .filter(|m| m.saturated_fraction >= 0.4)
                    .count();
                s.push_str(&format!(
                    "  push-off (forward check): muscles {:+.0} J, body {:+.0} J; {} of {} muscles at activation ≥ 0.95 for 40% of it or more{}; `leap analyze {} --model {}` for the table\n",
                    a.budget.muscle_work_j,
                    a.budget.energy_change_j,
                    full,
                    a.muscles.len(),
                    fastest
                        .map(|m| format!(
                            "; fastest fibres {} at {:.2} of v_max",
                            m.name, m.peak_shortening_ratio
                        ))
                        .unwrap_or_default(),
                    self.output_files
                        .iter()
                        .find(|f| f.ends_with("_forward_states.sto"))
                        .map_or("<out>/<name>_forward_states.sto", |f| f.as_str()),
                    self.model
                ));
            }
            for e in &fc.errors {
                s.push_str(&format!("  forward check: {e}\n"));
            }
        }
        if let Some(m) = &self.mesh_error {
            let worst = m.worst_interval.and_then(|k| m.intervals.get(k - 1));
            let failed = m.intervals.iter().filter(|i| i.failure.is_some()).count();
            if let (Some(w), Some(median)) = (worst, m.median_relative_error) {
                s.push_str(&format!(
                    "  mesh error (each interval integrated from its first node, Dormand–Prince at {:e}; relative to 1 + the state's largest magnitude): median {:.1e}, largest {:.1e} in interval {} ({:.3}–{:.3} s, {} off by {:.2e} in its units){}; a finer mesh lowers it\n",
                    m.accuracy,
                    median,
                    w.relative_error.unwrap_or(f64::NAN),
                    w.interval,
                    w.t_start,
                    w.t_end,
                    w.state,
                    w.absolute_error.unwrap_or(f64::NAN),
                    if failed > 0 {
                        format!("; {failed} intervals failed to integrate")
                    } else {
                        String::new()
                    }
                ));
            } else if failed > 0 {
                s.push_str(&format!(
                    "  mesh error: all {failed} intervals failed to integrate\n"
                ));
            }
        }
        if let Some(e) = &self.mesh_error_failure {
            s.push_str(&format!("  mesh error: {e}\n"));
        }
        if let Some(g) = self.guess_jump_height_m {
            s.push_str(&format!(
                "  initial guess {}: jump height {:.2} cm\n",
                self.guess,
                100.0 * g
            ));
        }
        for w in &self.switched_study_settings {
            s.push_str(&format!("  note: {w}\n"));
        }
        for w in guess_warnings(
            &self.guess,
            &self.unread_guess_columns,
            &self.guess_projected_states,
        ) {
            s.push_str(&format!("  {w}\n"));
        }
        if !self.removed_stale_files.is_empty() {
            s.push_str(&format!(
                "  removed result files of an earlier run that this run did not write: {}\n",
                self.removed_stale_files.join(", ")
            ));
        }
        if !self.earlier_reports.is_empty() {
            s.push_str(&format!(
                "  warning: report(s) drawn of an earlier run, not of these results: {} (`leap report` of this run's table redraws one)\n",
                self.earlier_reports.join(", ")
            ));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The transposed table holds cell (i, j) of the row table at (j, i).
    #[test]
    fn transposed_table_swaps_rows_and_columns() {
        let header = ["", "a", "b"];
        let rows = vec![
            vec!["x".to_string(), "1".into(), "2".into()],
            vec!["y".to_string(), "3".into(), "".into()],
        ];
        let t = transposed(&header, &rows);
        let cells =
            |r: &comfy_table::Row| -> Vec<String> { r.cell_iter().map(|c| c.content()).collect() };
        assert_eq!(cells(t.header().unwrap()), ["", "x", "y"]);
        assert_eq!(cells(t.row(0).unwrap()), ["a", "1", "3"]);
        assert_eq!(cells(t.row(1).unwrap()), ["b", "2", ""]);
        assert!(t.row(2).is_none());
        // Off a terminal, or on a wide one, the row layout stays; on a
        // narrow one the table is transposed.
        let row_layout = |text: &str| text.lines().any(|l| l.contains(" x ") && l.contains(" 2 "));
        for width in [None, Some(200)] {
            assert!(
                row_layout(&table_fitting(&header, &rows, width)),
                "{width:?}"
            );
        }
        let narrow = table_fitting(&header, &rows, Some(10));
        assert!(!row_layout(&narrow), "{narrow}");
        assert!(
            narrow
                .lines()
                .any(|l| l.contains(" a ") && l.contains(" 3 ")),
            "{narrow}"
        );
    }
}
