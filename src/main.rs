//! The `leap` command line.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use leap::study::SIMULATE_FILE_PREFIX;
use std::path::PathBuf;
use std::process::ExitCode;

/// Standard output closed or full (`leap solve | head`, `> /dev/full`): an
/// error to report, not a panic, with exit code 3 (1 and 2 say how a solve
/// or simulation ended). Results files are written before the summary is
/// printed.
#[derive(Debug, thiserror::Error)]
#[error("writing to standard output: {0}")]
struct StdoutError(std::io::Error);

/// `println!` that returns a [`StdoutError`] instead of panicking.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*).map_err(StdoutError)?
    }};
}

/// `print!` that returns a [`StdoutError`] instead of panicking.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*).map_err(StdoutError)?
    }};
}

#[derive(Parser)]
#[command(
    name = "leap",
    version,
    about = "Predict human movement by optimal control (OpenSim-compatible models)."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Compare the Rust-native dynamics with Simbody at random states.
    Crosscheck {
        #[command(flatten)]
        model: ModelFile,
        /// Number of random states (default 100).
        #[arg(long, allow_negative_numbers = true, value_parser = whole_count)]
        samples: Option<usize>,
        /// Seed of the random states.
        #[arg(long, default_value_t = 1, allow_negative_numbers = true, value_parser = whole_seed)]
        seed: u64,
        /// Instead: the collocation Jacobian of the jump, exact Rust-native
        /// (dual numbers) against Simbody's central differences, at the
        /// bang-bang guess and --samples perturbed points (default 2 here).
        #[arg(long)]
        jacobian: bool,
        /// With --jacobian: mesh intervals (default 28).
        #[arg(long, allow_negative_numbers = true)]
        num_mesh_intervals: Option<i64>,
        /// With --jacobian: midpoint-euler (default), trapezoidal,
        /// hermite-simpson or backward-euler.
        #[arg(long)]
        scheme: Option<String>,
        /// With --jacobian: implicit (midpoint-euler's default) or explicit.
        #[arg(long)]
        fiber_dynamics: Option<String>,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Forward simulation of the jump from the static squat (OpenSim's
    /// ForwardTool): excitations from a controls file or the bang-bang pattern.
    Simulate {
        /// Study file (JSON); command-line options override it.
        #[arg(long)]
        study: Option<PathBuf>,
        /// Model file (JSON; default: the study's, else models/jumper.json in
        /// the working directory, else leap's own).
        #[arg(long)]
        model: Option<PathBuf>,
        /// OpenSim controls (.sto) or Moco solution with /forceset/<muscle> columns.
        #[arg(long)]
        controls: Option<PathBuf>,
        /// RungeKuttaMerson (default), RungeKuttaFeldberg, RungeKutta3, CPodes,
        /// ExplicitEuler (Simbody) or DormandPrince (Rust-native).
        #[arg(long)]
        integrator: Option<String>,
        /// Integrator accuracy (ExplicitEuler: fixed step in s). Default 1e-5.
        #[arg(long, allow_hyphen_values = true)]
        accuracy: Option<f64>,
        /// Stop time if the apex is not reached (s; default 1).
        #[arg(long, allow_hyphen_values = true)]
        t_max: Option<f64>,
        /// Results directory (default results/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Solve the maximum-height jump (Porsa, Lin & Pandy 2016) by direct
    /// collocation (or direct shooting) and SQP from a study file (or the built-in study, the
    /// paper's problem); write the solution, ground forces and iteration
    /// history, print the paper's Table 2 row and check the optimal
    /// excitations by forward simulation.
    #[command(after_help = "Examples:
  leap solve
  leap solve models/jump_collocation.json --out results/jump28
  leap solve --num-mesh-intervals 8 --max-iterations 50 --json
  leap solve --guess results/jump_solution.sto --scheme trapezoidal")]
    Solve {
        /// Study file (JSON); command-line options override it.
        study: Option<PathBuf>,
        /// Results directory (default: the study's output_directory, results/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Model file (JSON), in place of the study's model (default:
        /// models/jumper.json in the working directory, else leap's own).
        #[arg(long)]
        model: Option<PathBuf>,
        /// collocation (default) or shooting (the paper's direct shooting:
        /// excitations at the nodes, Dormand–Prince 5(4), forward
        /// sensitivities, about 1 s per iteration; the study's
        /// shooting.derivatives "central-difference" is the paper's, about
        /// 23 s per iteration).
        #[arg(long)]
        method: Option<String>,
        /// Uniform mesh intervals (≥ 2; default 28).
        #[arg(long, allow_negative_numbers = true)]
        num_mesh_intervals: Option<i64>,
        /// SQP iteration limit.
        #[arg(long, allow_negative_numbers = true)]
        max_iterations: Option<i64>,
        /// "bang-bang" (integrated on the mesh), "bang-bang-resampled" or a
        /// .sto file with every state and control column (the control
        /// columns alone with --integrate-guess or method shooting).
        #[arg(long)]
        guess: Option<String>,
        /// Integrate the guess file's excitations on the mesh from the
        /// squat (t_f the file's), as the bang-bang guess is, instead of
        /// resampling its states: a guess from another mesh then meets the
        /// defects from the start (a guess file, collocation only).
        #[arg(long)]
        integrate_guess: bool,
        /// midpoint-euler (default), trapezoidal, hermite-simpson or
        /// backward-euler (the last three with explicit fibre dynamics).
        #[arg(long)]
        scheme: Option<String>,
        /// implicit (default: the muscle-tendon force balance at the
        /// interval's fibre velocity; midpoint-euler only) or explicit
        /// (fibre velocity from the inverted force-velocity curve, the
        /// paper's form).
        #[arg(long)]
        fiber_dynamics: Option<String>,
        /// exact (default: exact element Hessians, negative eigenvalues
        /// clipped), exact-block-diagonal, exact-inertia-corrected (exact
        /// element Hessians unmodified, the interior-point QP solver's
        /// inertia correction) or bfgs.
        #[arg(long)]
        hessian: Option<String>,
        /// rust-native (default: leap's dynamics, exact Jacobian from dual
        /// numbers) or simbody (Simbody's multibody system with the same
        /// force laws, Jacobian by coloured central differences: the
        /// cross-check path; collocation only).
        #[arg(long)]
        backend: Option<String>,
        /// Skip the forward simulation of the optimal excitations.
        #[arg(long)]
        no_forward_check: bool,
        /// Write each SQP iteration's QP (and each plain QP taken as
        /// infeasible) as clarabel JSON into OUT/qps/, a few MB each, for
        /// examples/qp_replay, examples/ipm_bench and
        /// scripts/qp_negative_curvature.py.
        #[arg(long)]
        dump_qps: bool,
        /// Print one JSON object (no progress output).
        #[arg(long)]
        json: bool,
        /// No progress output or iteration log.
        #[arg(long)]
        quiet: bool,
        /// The SQP's iteration log on stderr even when it is not a terminal.
        #[arg(long, conflicts_with = "quiet")]
        verbose: bool,
    },
    /// ẋ = f(x, u) and its parts (muscle, contact and joint quantities) at
    /// given states, like OpenSim's Analyze tool. Input: JSON
    /// ({"state": {name: value}, "excitation": {"/forceset/<m>": value}} or
    /// {"x": [...], "u": [...]}, or an array of these) or CSV (a header of
    /// state and control names, one row per evaluation).
    Eval {
        #[command(flatten)]
        model: ModelFile,
        /// The states and excitations: JSON (.json) or CSV (.csv); `leap
        /// squat` prints a ready-made one.
        #[arg(long)]
        input: PathBuf,
        /// The full 10-coordinate system instead of the symmetric one.
        #[arg(long)]
        full: bool,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// What drives and limits a jump: per muscle over the push-off its peak
    /// activation, time at full activation, peak force and shortening speed
    /// against its maximum, and work; the energy budget of the push-off.
    /// From a states file (`_solution.sto`, or the forward check's finer
    /// `_forward_states.sto`).
    Analyze {
        /// States over time (OpenSim .sto with the model's state names).
        states: PathBuf,
        #[command(flatten)]
        model: ModelFile,
        /// Analyse from START to END (s) instead of the push-off.
        #[arg(long, num_args = 2, value_names = ["START", "END"], allow_hyphen_values = true)]
        window: Option<Vec<f64>>,
        /// The full 10-coordinate system instead of the symmetric one.
        #[arg(long)]
        full: bool,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Plot a trajectory file (a solution, states, controls or ground
    /// forces) against time as Moco's report does: sections of coordinate
    /// values, speeds, activations, fibre lengths and excitations, then
    /// any other column, reference files drawn beneath; one SVG page.
    Report {
        /// The trajectory (.sto or .mot).
        trajectory: PathBuf,
        /// Files drawn beneath the trajectory, thicker (the forward
        /// check's states, measured data): their columns of the same names.
        #[arg(long = "ref-files", num_args = 1..)]
        ref_files: Vec<PathBuf>,
        /// A right and a left column in one panel, the left dashed.
        #[arg(long)]
        bilateral: bool,
        /// The SVG file (default: <trajectory stem>_report.svg beside the
        /// trajectory).
        #[arg(long)]
        output: Option<PathBuf>,
        /// The model whose rotational coordinates a file in degrees holds
        /// in degrees (default as every command's).
        #[command(flatten)]
        model: ModelFile,
        /// Print JSON (the file written, its panels by section, warnings).
        #[arg(long)]
        json: bool,
    },
    /// Print the state and control names `leap eval` expects, and the static
    /// squat as a ready-made input.
    Squat {
        #[command(flatten)]
        model: ModelFile,
        /// Both legs' states and excitations (the full system, for `leap
        /// eval --full`) instead of the symmetric system's right leg.
        #[arg(long)]
        full: bool,
    },
    /// The length jumps of the exact muscle paths where conditional path
    /// points switch (what the optimizer's smoothed paths, blended over
    /// 0.02 rad, remove), other coordinates at a pose of the model.
    Paths {
        #[command(flatten)]
        model: ModelFile,
        /// Pose of the other coordinates (a pose name of the model file).
        #[arg(long, default_value = "squat")]
        pose: String,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Benchmarks that print tables (medians of repeated batches).
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
}

#[derive(Subcommand)]
enum BenchCommand {
    /// Time per q̈ evaluation of a skeleton, Rust-native against Simbody.
    Dynamics {
        #[command(flatten)]
        model: ModelFile,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Time per ẋ = f(x, u) evaluation, Rust-native against Simbody.
    StateEquation {
        #[command(flatten)]
        model: ModelFile,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// The SQP on the Hock–Schittkowski test set per Hessian mode: problems
    /// at the published optimum, iterations, median wall time and its split.
    Sqp {
        /// Runs of the whole set per mode (the median is reported).
        #[arg(long, default_value_t = 5, allow_negative_numbers = true, value_parser = bench_repeats)]
        repeats: usize,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// SQP iterations on the 29-node jump collocation problem from the
    /// bang-bang guess: time per iteration split into derivatives, Hessian,
    /// QP and line search.
    SqpJump {
        #[command(flatten)]
        model: ModelFile,
        #[arg(long, default_value_t = 3, allow_negative_numbers = true, value_parser = bench_iterations)]
        iterations: usize,
        /// "exact" (the jump's default) or "bfgs".
        #[arg(long, default_value = "exact")]
        hessian: String,
        /// Turn off clarabel's equilibration of the QPs.
        #[arg(long)]
        no_equilibrate: bool,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Collocation against shooting: the first SQP iterations of each on
    /// the 29-node jump, time per iteration split into derivatives, Hessian,
    /// QP and line search, against the paper's CPU time per iteration.
    Methods {
        #[command(flatten)]
        model: ModelFile,
        /// SQP iterations per method (a shooting iteration takes about 1 s
        /// with forward sensitivities, 23 s with central differences).
        #[arg(long, default_value_t = 3, allow_negative_numbers = true, value_parser = bench_iterations)]
        iterations: usize,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// A whole `leap solve` of a study (default: the built-in jump study),
    /// without the forward check: status, iterations, wall time and its
    /// split into derivatives, Hessian, QP, line search and other.
    Solve {
        /// Study file (as `leap solve`).
        study: Option<PathBuf>,
        /// Model file (JSON), in place of the study's model (as `leap
        /// solve --model`).
        #[arg(long)]
        model: Option<PathBuf>,
        /// Solves per mesh (the medians over all runs are reported).
        #[arg(long, default_value_t = 1, allow_negative_numbers = true, value_parser = bench_repeats)]
        repeats: usize,
        /// Hessian mode (as `leap solve --hessian`; default: the study's).
        #[arg(long)]
        hessian: Option<String>,
        /// Mesh intervals to sweep, comma-separated (e.g. 24,26,28,30;
        /// default: the study's mesh). The SQP's path changes with the
        /// last bit of its input: compare solver changes on the medians of
        /// a sweep, not on one solve.
        #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
        num_mesh_intervals: Vec<i64>,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// One forward jump per integrator and accuracy: steps, rejected steps,
    /// f evaluations, wall time.
    Integrators {
        #[command(flatten)]
        model: ModelFile,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
    },
}

/// The `--model` option of every command but `simulate` (whose study may
/// name one).
#[derive(clap::Args)]
struct ModelFile {
    /// Model file (JSON; default: models/jumper.json in the working
    /// directory, else leap's own, as `leap solve` finds it).
    #[arg(long)]
    model: Option<PathBuf>,
}

impl ModelFile {
    /// The file given, or the default model.
    fn path(self) -> PathBuf {
        model_file(self.model)
    }
}

/// `model`, or the default model: `models/jumper.json` in the working
/// directory, else leap's own (as `leap solve` and `leap simulate` find
/// it); a read error names the path.
fn model_file(model: Option<PathBuf>) -> PathBuf {
    model
        .or_else(leap::study::default_model)
        .unwrap_or_else(|| PathBuf::from(leap::study::DEFAULT_MODEL))
}

/// A model's OpenSim laws and the state equation of its symmetric (or
/// full) system with OpenSim's exact muscle paths.
fn opensim_system(
    model: &std::path::Path,
    full: bool,
) -> anyhow::Result<(leap::laws::OpenSimLaws, leap::ode::StateEquation)> {
    let m = leap::model::Model::from_file(model)?;
    Ok(leap::ode::StateEquation::opensim(&m, !full)?)
}

/// A symmetric command's refusal of a file whose legs differ, with the
/// hint that `--full` reads both.
fn full_hint(e: impl Into<anyhow::Error>, full: bool) -> anyhow::Error {
    let e = e.into();
    let text = format!("{e:#}");
    if !full && text.contains(leap::io::COPY_MISMATCH_REASON) {
        anyhow::anyhow!("{text}; or give --full to read both legs, on the full system")
    } else {
        e
    }
}

fn main() -> ExitCode {
    // Built for x86-64-v3 (.cargo/config.toml): refuse a CPU without it
    // rather than die on an illegal instruction.
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    if !(std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")) {
        leap::errln!(
            "error: this build of leap needs a CPU with AVX2 and FMA (x86-64-v3, .cargo/config.toml); \
             rebuild with RUSTFLAGS=\"-C target-cpu=x86-64\" for this one"
        );
        return ExitCode::from(2);
    }
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) if e.is::<StdoutError>() => {
            leap::errln!("error: {}", leap::io::bounded_message(&format!("{e:#}")));
            ExitCode::from(3)
        }
        Err(e) => {
            leap::errln!("error: {}", leap::io::bounded_message(&format!("{e:#}")));
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Command::Crosscheck {
            model,
            samples,
            seed,
            jacobian,
            num_mesh_intervals,
            scheme,
            fiber_dynamics,
            json,
        } => {
            let model = model.path();
            if !jacobian {
                for (given, option) in [
                    (num_mesh_intervals.is_some(), "--num-mesh-intervals"),
                    (scheme.is_some(), "--scheme"),
                    (fiber_dynamics.is_some(), "--fiber-dynamics"),
                ] {
                    if given {
                        anyhow::bail!("{option}: applies to --jacobian only");
                    }
                }
            }
            let samples = samples.unwrap_or(if jacobian { 2 } else { 100 });
            if samples == 0 {
                anyhow::bail!("--samples must be at least 1");
            }
            let limit = if jacobian { 100 } else { 1_000_000 };
            if samples > limit {
                anyhow::bail!(
                    "--samples: at most {limit}, got {samples}{}",
                    if jacobian {
                        " (each perturbed point costs two collocation Jacobians)"
                    } else {
                        " (about a millisecond each: a million take a quarter of an hour)"
                    }
                );
            }
            let m = leap::model::Model::from_file(&model)?;
            if jacobian {
                let options = jacobian_options(num_mesh_intervals, scheme, fiber_dynamics)?;
                let report =
                    leap::crosscheck::jacobian(&m, options, samples, seed).map_err(|e| {
                        // The model is named once: by the error where it
                        // names it (a model's field), else here.
                        let (text, file) = (e.to_string(), model.display().to_string());
                        if text.starts_with(&format!("{file}: ")) {
                            anyhow::anyhow!("Jacobian cross-check: {text}")
                        } else {
                            anyhow::anyhow!("Jacobian cross-check of {file}: {text}")
                        }
                    })?;
                if json {
                    outln!("{}", serde_json::to_string_pretty(&report)?);
                } else {
                    outln!("{}", report.table());
                }
                return Ok(if report.passed {
                    ExitCode::SUCCESS
                } else {
                    ExitCode::from(1)
                });
            }
            let report = leap::crosscheck::run(&m, samples, seed)
                .with_context(|| format!("cross-check of {}", model.display()))?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                outln!("{}", report.table());
            }
            Ok(if report.passed {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(1)
            })
        }
        Command::Simulate {
            study,
            model,
            controls,
            integrator,
            accuracy,
            t_max,
            out,
            json,
        } => simulate(
            study, model, controls, integrator, accuracy, t_max, out, json,
        ),
        Command::Solve {
            study,
            out,
            model,
            method,
            num_mesh_intervals,
            max_iterations,
            guess,
            integrate_guess,
            scheme,
            fiber_dynamics,
            hessian,
            backend,
            no_forward_check,
            dump_qps,
            json,
            quiet,
            verbose,
        } => {
            let overrides = leap::study::Overrides {
                output_directory: out,
                method,
                num_mesh_intervals,
                max_iterations,
                guess,
                integrate_guess,
                scheme,
                fiber_dynamics,
                hessian,
                backend,
                no_forward_check,
                dump_qps,
            };
            solve(study, model, overrides, json, quiet, verbose)
        }
        Command::Analyze {
            states,
            model,
            window,
            full,
            json,
        } => {
            let model = model.path();
            let (laws, eq) = opensim_system(&model, full)?;
            let (time, xs) =
                leap::analyze::read_states(&eq, &states).map_err(|e| full_hint(e, full))?;
            let window = match window.as_deref() {
                Some(&[a, b]) if !a.is_finite() || !b.is_finite() => anyhow::bail!(
                    "command line: --window: START and END must be finite times (s), got {} and {}",
                    leap::io::readable(a),
                    leap::io::readable(b)
                ),
                Some(&[a, b]) if a < b => Some((a, b)),
                Some(&[a, b]) => anyhow::bail!(
                    "command line: --window: START must be below END, got {} and {}",
                    leap::io::readable(a),
                    leap::io::readable(b)
                ),
                Some(w) => anyhow::bail!("command line: --window: takes START and END, got {w:?}"),
                None => None,
            };
            let a = leap::analyze::analyze(&eq, &laws, &time, &xs, window)
                .with_context(|| format!("{}", states.display()))?;
            if json {
                let mut v = serde_json::to_value(&a)?;
                v["newton_mismatch"] = serde_json::json!(a.newton_mismatch());
                outln!("{}", serde_json::to_string_pretty(&v)?);
            } else {
                out!("{}", a.to_text());
            }
            for w in &a.warnings {
                leap::errln!("warning: {}: {w}", states.display());
            }
            if let Some(w) = a.newton_warning() {
                leap::errln!("{w}");
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Eval {
            model,
            input,
            full,
            json,
        } => {
            let model = model.path();
            let (laws, eq) = opensim_system(&model, full)?;
            let inputs = leap::eval::read_inputs(&eq, &input).map_err(|e| {
                // A symmetric system's input (`leap squat`'s) given with
                // --full misses the left leg's names (by name, as CSV
                // columns) or values (as arrays).
                if full && e.lacks_values {
                    anyhow::anyhow!("{e}; with --full an input holds both legs' states and excitations (`leap squat --full` prints one)")
                } else {
                    full_hint(e, full)
                }
            })?;
            let mut reports = Vec::with_capacity(inputs.len());
            for (k, (x, u)) in inputs.iter().enumerate() {
                let r = leap::eval::evaluate(&eq, &laws, x, u)
                    .with_context(|| format!("{}: evaluation {k}", input.display()))?;
                for w in &r.warnings {
                    leap::errln!("warning: {}: evaluation {k}: {w}", input.display());
                }
                reports.push(r);
            }
            if json {
                let v = if reports.len() == 1 {
                    serde_json::to_value(&reports[0])?
                } else {
                    serde_json::to_value(&reports)?
                };
                outln!("{}", serde_json::to_string_pretty(&v)?);
            } else {
                for (k, r) in reports.iter().enumerate() {
                    outln!("evaluation {k}");
                    let mut t = comfy_table::Table::new();
                    t.set_header([
                        "muscle",
                        "L_MT (m)",
                        "v_MT (m/s)",
                        "l_M (m)",
                        "v_M (m/s)",
                        "pennation (rad)",
                        "tendon force (N)",
                        "moment arms (m)",
                    ]);
                    for (name, mr) in &r.muscles {
                        let arms: Vec<String> = mr
                            .moment_arms
                            .iter()
                            .map(|(c, v)| format!("{c} {v:+.4}"))
                            .collect();
                        t.add_row([
                            name.clone(),
                            format!("{:.5}", mr.length),
                            format!("{:+.4}", mr.lengthening_speed),
                            format!("{:.5}", mr.fiber_length),
                            format!("{:+.4}", mr.fiber_velocity),
                            format!("{:.4}", mr.pennation_angle),
                            format!("{:.2}", mr.tendon_force),
                            arms.join(", "),
                        ]);
                    }
                    outln!("{t}");
                    let acc: Vec<String> = r
                        .accelerations
                        .iter()
                        .map(|(c, v)| format!("{c} {v:+.4e}"))
                        .collect();
                    outln!("q̈: {}", acc.join(", "));
                    let lig: Vec<String> = r
                        .ligament_torques
                        .iter()
                        .map(|(c, v)| format!("{c} {v:+.3}"))
                        .collect();
                    outln!("passive torques (N·m): {}", lig.join(", "));
                    let fy: f64 = r.contact_forces.values().map(|f| f[1]).sum();
                    outln!("total vertical contact force: {fy:.2} N");
                }
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Paths { model, pose, json } => {
            let model = model.path();
            let m = leap::model::Model::from_file(&model)?;
            let eq = leap::ode::StateEquation::new(&m, true, leap::path::PathSmoothing::Exact)?;
            let q = m.poses.get(&pose).cloned().ok_or_else(|| {
                let have = if m.poses.is_empty() {
                    "the model has no poses".to_string()
                } else {
                    format!(
                        "have: {}",
                        m.poses.keys().cloned().collect::<Vec<_>>().join(", ")
                    )
                };
                anyhow::anyhow!("{}: poses: no pose '{pose}' ({have})", model.display())
            })?;
            let jumps = leap::eval::switch_jumps(&eq, &q);
            if jumps.is_empty() && !json {
                outln!(
                    "{}: no muscle path has a conditional point that switches within its coordinate's range: no length jump to smooth",
                    model.display()
                );
                return Ok(ExitCode::SUCCESS);
            }
            let largest = jumps.iter().map(|j| j.jump_m.abs()).fold(0.0, f64::max);
            if json {
                outln!(
                    "{}",
                    serde_json::to_string_pretty(
                        &serde_json::json!({"pose": pose, "largest_jump_m": largest, "switches": jumps})
                    )?
                );
            } else {
                let mut t = comfy_table::Table::new();
                t.set_header([
                    "muscle",
                    "point",
                    "coordinate",
                    "switch at (rad)",
                    "length jump (mm)",
                ]);
                for j in &jumps {
                    t.add_row([
                        j.muscle.clone(),
                        format!("P{}", j.point),
                        j.coordinate.clone(),
                        format!("{:.6}", j.at),
                        format!("{:+.4}", 1e3 * j.jump_m),
                    ]);
                }
                outln!("conditional path points of the exact (OpenSim) paths, other coordinates at the '{pose}' pose\n{t}\nlargest length jump, which the optimizer's smoothed paths remove: {:.4} mm", 1e3 * largest);
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Report {
            trajectory,
            ref_files,
            bilateral,
            output,
            model,
            json,
        } => {
            let model = model.path();
            let m = leap::model::Model::from_file(&model)?;
            let (_, eq) = leap::ode::StateEquation::opensim(&m, false)?;
            let columns = leap::io::ModelColumns::of(&eq);
            // Read first, so that a missing trajectory is named as such.
            let (text, panels, warnings) =
                leap::report::report(&trajectory, &ref_files, bilateral, &columns)?;
            let output = output.unwrap_or_else(|| leap::report::default_output(&trajectory));
            leap::report::check_output(&output, &trajectory, &ref_files)?;
            leap::io::write_output(&output, text)
                .map_err(|e| anyhow::anyhow!("--output: {}: {e}", output.display()))?;
            for w in &warnings {
                leap::errln!("warning: {w}");
            }
            if json {
                // Sections in the report's order, each with its panels.
                let sections: Vec<serde_json::Value> = leap::report::sections(&panels)
                    .into_iter()
                    .map(|(section, ps)| {
                        let titles: Vec<&str> = ps.iter().map(|p| p.title.as_str()).collect();
                        serde_json::json!({"section": section.title(), "panels": titles})
                    })
                    .collect();
                outln!(
                    "{}",
                    serde_json::to_string_pretty(&serde_json::json!({
                        "output": output.display().to_string(),
                        "panels": panels.len(),
                        "sections": sections,
                        "warnings": warnings,
                    }))?
                );
            } else {
                outln!("{} panels written to {}", panels.len(), output.display());
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Squat { model, full } => {
            let model = model.path();
            let m = leap::model::Model::from_file(&model)?;
            let (laws, eq) = leap::ode::StateEquation::opensim(&m, !full)?;
            let pose = m.squat_pose()?;
            let sq = leap::squat::static_squat(&eq, &laws, &pose)?;
            let state: serde_json::Map<String, serde_json::Value> = eq
                .state_names()
                .into_iter()
                .zip(sq.x.iter())
                .map(|(n, v)| (n, serde_json::json!(v)))
                .collect();
            let exc: serde_json::Map<String, serde_json::Value> = eq
                .control_names()
                .into_iter()
                .zip(sq.excitation.iter())
                .map(|(n, v)| (n, serde_json::json!(v)))
                .collect();
            let v = serde_json::json!({"state": state, "excitation": exc, "max_abs_qdd": sq.max_abs_qdd, "vertical_grf_bw": sq.vertical_grf_bw, "qp_iterations": sq.qp_iterations});
            outln!("{}", serde_json::to_string_pretty(&v)?);
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which: BenchCommand::StateEquation { model, json },
        } => {
            let model = model.path();
            let m = leap::model::Model::from_file(&model)?;
            let report = leap::bench::state_equation(&m)?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                outln!("{}", report.table());
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which: BenchCommand::Integrators { model, json },
        } => {
            let model = model.path();
            let m = leap::model::Model::from_file(&model)?;
            let cases = [
                ("RungeKuttaMerson", 1e-3),
                ("RungeKuttaMerson", 1e-5),
                ("RungeKuttaFeldberg", 1e-3),
                ("RungeKuttaFeldberg", 1e-5),
                ("RungeKutta3", 1e-5),
                ("CPodes", 1e-5),
                ("ExplicitEuler", 2e-5),
                ("DormandPrince", 1e-3),
                ("DormandPrince", 1e-5),
                ("DormandPrince", 1e-7),
            ];
            let rows = leap::bench::integrators(&m, &cases).map_err(|e| anyhow::anyhow!(e))?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&rows)?);
            } else {
                outln!("{}", leap::bench::integrator_table(&rows));
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which: BenchCommand::Sqp { repeats, json },
        } => {
            let rows = leap::bench::sqp_test_set(repeats);
            if json {
                outln!("{}", serde_json::to_string_pretty(&rows)?);
            } else {
                outln!("{}", leap::bench::sqp_table(&rows));
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which:
                BenchCommand::SqpJump {
                    model,
                    iterations,
                    hessian,
                    no_equilibrate,
                    json,
                },
        } => {
            let model = model.path();
            let m = leap::model::Model::from_file(&model)?;
            let mode: leap::sqp::HessianMode = hessian
                .parse()
                .map_err(|e: String| anyhow::anyhow!("--hessian: {e}"))?;
            let report = leap::bench::sqp_jump(&m, iterations, mode, !no_equilibrate)
                .map_err(|e| anyhow::anyhow!(e))?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                outln!("{}", report.table());
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which:
                BenchCommand::Methods {
                    model,
                    iterations,
                    json,
                },
        } => {
            let model = model.path();
            let m = leap::model::Model::from_file(&model)?;
            let report = leap::bench::methods(&m, iterations).map_err(|e| anyhow::anyhow!(e))?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                outln!("{}", report.table());
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which:
                BenchCommand::Solve {
                    study,
                    model,
                    repeats,
                    hessian,
                    num_mesh_intervals,
                    json,
                },
        } => {
            let config =
                leap::study::SolveConfig::load_with_model(study.as_deref(), model.as_deref())?;
            let name = study.map_or("built-in jump study".into(), |p| p.display().to_string());
            let report = leap::bench::solve(
                &config,
                &name,
                repeats,
                hessian.as_deref(),
                &num_mesh_intervals,
            )
            .map_err(|e| anyhow::anyhow!(e))?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                outln!("{}", report.table());
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which: BenchCommand::Dynamics { model, json },
        } => {
            let model = model.path();
            let m = leap::model::Model::from_file(&model)?;
            let report = leap::bench::dynamics(&m)?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&report)?);
            } else {
                outln!("{}", report.table());
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}

/// A count of runs: a whole number ≥ 1.
fn at_least_one(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        Ok(_) => Err("must be at least 1".into()),
        Err(_) => Err(format!("expected a whole number ≥ 1, got '{s}'")),
    }
}

/// A count given on the command line (`--samples`): a whole number ≥ 0,
/// its range checked where it is used.
fn whole_count(s: &str) -> Result<usize, String> {
    s.parse::<usize>()
        .map_err(|_| format!("expected a whole number ≥ 0, got '{s}'"))
}

/// `--seed`: a whole number in [0, 2⁶⁴).
fn whole_seed(s: &str) -> Result<u64, String> {
    s.parse::<u64>()
        .map_err(|_| format!("expected a whole number in [0, 2^64), got '{s}'"))
}

/// The most runs a benchmark repeats (`--repeats`): a median needs a few;
/// a thousand default solves take about six hours.
const MAX_BENCH_REPEATS: usize = 1000;
/// The most SQP iterations a benchmark times (`--iterations`): a shooting
/// iteration takes about a second, 23 s with central differences.
const MAX_BENCH_ITERATIONS: usize = 10_000;

fn bench_repeats(s: &str) -> Result<usize, String> {
    at_most(at_least_one(s)?, MAX_BENCH_REPEATS)
}

fn bench_iterations(s: &str) -> Result<usize, String> {
    at_most(at_least_one(s)?, MAX_BENCH_ITERATIONS)
}

fn at_most(n: usize, limit: usize) -> Result<usize, String> {
    if n > limit {
        Err(format!("at most {limit}, got {n}"))
    } else {
        Ok(n)
    }
}

/// Ctrl-C while `leap <command>` writes its results: the first press is
/// absorbed with a word, so that this run's first files do not stand beside
/// an earlier run's others; a further one removes the file under way and
/// quits.
fn ctrl_c_while_writing(command: &str, warned: &std::sync::atomic::AtomicBool) {
    if !warned.swap(true, std::sync::atomic::Ordering::SeqCst) {
        leap::errln!("leap {command}: interrupted while writing the results: finishing them (Ctrl-C again to quit at once, leaving them incomplete)");
        return;
    }
    leap::io::remove_pending_outputs();
    std::process::exit(130);
}

#[allow(clippy::too_many_arguments)]
fn simulate(
    study: Option<PathBuf>,
    model: Option<PathBuf>,
    controls: Option<PathBuf>,
    integrator: Option<String>,
    accuracy: Option<f64>,
    t_max: Option<f64>,
    out: Option<PathBuf>,
    json: bool,
) -> Result<ExitCode> {
    use leap::simulate::*;
    use std::sync::Arc;
    // Study file first (paths relative to it), then command-line overrides.
    let (mut st, base) = match &study {
        Some(p) => (
            SimulateStudy::from_file(p)?,
            p.parent().map(|d| d.to_path_buf()).unwrap_or_default(),
        ),
        None => (SimulateStudy::default(), PathBuf::new()),
    };
    let rel = |s: &str| -> PathBuf {
        if study.is_some() {
            base.join(s)
        } else {
            PathBuf::from(s)
        }
    };
    // A file the study names (relative to it) is checked as the study's
    // field, as `leap solve`'s study checks its model and guess.
    let study_file = |field: &str, name: &Option<String>, what: &str| -> Result<Option<PathBuf>> {
        let Some(p) = name.as_deref().map(rel) else {
            return Ok(None);
        };
        // An empty name, or one holding a control character, is refused as
        // such by the study's check (before anything is read).
        if name
            .as_deref()
            .is_some_and(|n| n.trim().is_empty() || leap::io::path_text_problem(n).is_some())
        {
            return Ok(Some(p));
        }
        if let (Some(s), Some(why)) = (&study, leap::io::input_file_problem(&p)) {
            anyhow::bail!("{}: {field}: {what} '{}' {why}", s.display(), p.display());
        }
        Ok(Some(p))
    };
    // What the study omits is relative to the working directory.
    let model_path = model_file(match model {
        Some(m) => Some(m),
        None => study_file("model", &st.model, "model file")?,
    });
    let controls_path = match controls {
        Some(c) => Some(c),
        None => study_file("controls", &st.controls, "controls file")?,
    };
    let out_dir = out
        .or_else(|| st.out.as_deref().map(rel))
        .unwrap_or_else(|| PathBuf::from(leap::study::DEFAULT_OUTPUT_DIRECTORY));
    let origin = study
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| "command line".into());
    let where_ = format!("{origin}: ");
    // The study's own values are checked as the file gives them, so that
    // a bad value on the command line is not blamed on the file.
    let overridden = integrator.is_some() || accuracy.is_some() || t_max.is_some();
    if overridden && study.is_some() {
        st.check(&origin)?;
    }
    let integrator_given = integrator.is_some();
    if let Some(i) = integrator {
        st.integrator = i;
    }
    if let Some(a) = accuracy {
        st.accuracy = a;
    }
    if let Some(t) = t_max {
        st.t_max = t;
    }
    // A field the command line set is the command line's: its option. With
    // a study whose own values passed, any error is the options' doing:
    // named as theirs, with the study's field they clash with.
    let options: Vec<&str> = [
        ("integrator", integrator_given),
        ("accuracy", accuracy.is_some()),
        ("t_max", t_max.is_some()),
    ]
    .into_iter()
    .filter_map(|(f, g)| g.then_some(f))
    .collect();
    let flag = |f: &str| format!("--{}", f.replace('_', "-"));
    let choice = st.check(&origin).map_err(|e| match e {
        leap::study::StudyError::Field { field, reason, .. }
            if options.contains(&field.as_str()) =>
        {
            leap::study::StudyError::Field {
                origin: "command line".into(),
                field: flag(&field),
                reason,
            }
        }
        leap::study::StudyError::Field { field, reason, .. }
            if study.is_some() && !options.is_empty() =>
        {
            leap::study::StudyError::Field {
                origin: "command line".into(),
                field: options
                    .iter()
                    .map(|f| flag(f))
                    .collect::<Vec<_>>()
                    .join(", "),
                reason: format!("with {origin}'s {field}: {reason}"),
            }
        }
        e => e,
    })?;
    let mut files = leap::simulate::trajectory_files(SIMULATE_FILE_PREFIX).to_vec();
    files.push(format!("{SIMULATE_FILE_PREFIX}_summary.json"));
    leap::solve::check_result_files(&out_dir, &files)
        .map_err(|e| anyhow::anyhow!("{}: {e}", out_dir.display()))?;
    // An input among the result files would be overwritten by them.
    let inputs = [
        (
            "the controls file (controls, --controls)",
            controls_path.as_deref(),
        ),
        ("the model (model, --model)", Some(model_path.as_path())),
        ("the study file", study.as_deref()),
    ];
    let inputs = inputs.into_iter().filter_map(|(w, p)| p.map(|p| (w, p)));
    let instead = "another results directory (out, --out)";
    if let Some((input, reason)) = leap::io::input_among_results(inputs, &out_dir, &files, instead)
    {
        anyhow::bail!("{}: {reason}", input.display());
    }
    if controls_path.is_some() && st.bang_bang.is_some() {
        leap::errln!(
            "note: {origin}: bang_bang is not used: the excitations come from the controls file (--controls)"
        );
    }
    let m = leap::model::Model::from_file(&model_path)?;
    let (laws, eq) = leap::ode::StateEquation::opensim(&m, true)?;
    let pose = m.squat_pose()?;
    let squat = leap::squat::static_squat(&eq, &laws, &pose)?;
    let names: Vec<&str> = eq
        .muscles
        .iter()
        .map(|&k| m.muscles[k].spec.name.as_str())
        .collect();
    let mut unread = Vec::new();
    let exc = match &controls_path {
        Some(p) => {
            let t = leap::io::StoTable::read(p)?;
            let c = leap::io::Controls::from_table(&t, p, &names)?;
            // A misspelt muscle's column would be lost without a word.
            let all: Vec<&str> = m.muscles.iter().map(|x| x.spec.name.as_str()).collect();
            unread = leap::io::unread_excitation_columns(&t, &all);
            if !unread.is_empty() {
                let more = match unread.len() {
                    n if n > 10 => format!(" and {} more", n - 10),
                    _ => String::new(),
                };
                leap::errln!(
                    "warning: {}: {} column(s) name no muscle of the model and are not read: {}{more}",
                    p.display(),
                    unread.len(),
                    unread[..unread.len().min(10)].join(", ")
                );
            }
            c.check_run(p, st.t_max)?;
            StudyExcitation::Controls(c)
        }
        None => {
            let bb = st.bang_bang.clone().unwrap_or(BangBangSpec {
                on: None,
                on_time: 0.0,
                off_time: f64::INFINITY,
            });
            let on: Vec<bool> = match &bb.on {
                Some(list) => {
                    for (i, n) in list.iter().enumerate() {
                        if !names.contains(&n.as_str()) {
                            anyhow::bail!("{where_}bang_bang.on: unknown muscle '{n}' (the symmetric model's muscles are {})", names.join(", "));
                        }
                        if let Some(j) = list[..i].iter().position(|m| m == n) {
                            anyhow::bail!("{where_}bang_bang.on[{i}]: muscle '{n}' named twice (also bang_bang.on[{j}]): a muscle is on or off");
                        }
                    }
                    names.iter().map(|n| list.iter().any(|l| l == n)).collect()
                }
                None => extensor_moments(&eq, &pose)
                    .iter()
                    .map(|&e| e > 0.0)
                    .collect(),
            };
            StudyExcitation::BangBang(BangBang {
                intervals: on
                    .iter()
                    .map(|&o| {
                        if o {
                            Some((bb.on_time, bb.off_time))
                        } else {
                            None
                        }
                    })
                    .collect(),
                off_level: leap::laws::MIN_ACTIVATION,
            })
        }
    };
    let standing = standing_com_height(&eq);
    let result = match choice {
        IntegratorChoice::DormandPrince => {
            let opts = SimulateOptions {
                integrator: leap::integrator::Dopri5Options {
                    accuracy: st.accuracy,
                    ..Default::default()
                },
                t_max: st.t_max,
            };
            simulate_rust(&eq, &laws, &exc, &squat.x, standing, opts)
        }
        IntegratorChoice::Simbody(which) => simulate_simbody(
            &Arc::new(eq.clone()),
            &Arc::new(laws.clone()),
            &exc,
            &squat.x,
            standing,
            which,
            st.accuracy,
            st.t_max,
            st.report_interval,
        ),
    };
    leap::solve::create_results_dir(&out_dir)
        .map_err(|e| anyhow::anyhow!("{}: {e}", out_dir.display()))?;
    // Until here Ctrl-C quits with nothing written. While the files are
    // written, one press is absorbed with a word, so that this run's first
    // files do not stand beside an earlier run's others; a further press
    // quits.
    let warned = std::sync::atomic::AtomicBool::new(false);
    let _ = ctrlc::set_handler(move || ctrl_c_while_writing("simulate", &warned));
    let controls_range = match &exc {
        StudyExcitation::Controls(c) => c.time.first().zip(c.time.last()).map(|(a, b)| (*a, *b)),
        StudyExcitation::BangBang(_) => None,
    };
    match result {
        Ok((summary, traj)) => {
            let files = write_trajectory(&eq, &traj, &out_dir, SIMULATE_FILE_PREFIX)?;
            let mut v = serde_json::to_value(&summary)?;
            // Without a lift-off there is no jump: the JSON says so as the
            // text does ("-"), and keeps the COM's change apart.
            if summary.liftoff_time_s.is_none() {
                v["jump_height_m"] = serde_json::Value::Null;
                v["final_com_height_change_m"] = serde_json::json!(summary.jump_height_m);
            }
            // A fall gives no jump: say so, as for no lift-off.
            let falling = summary.falling_at_liftoff();
            v["liftoff_while_falling"] = serde_json::json!(falling.is_some());
            if let Some(v_down) = falling {
                leap::errln!(
                    "warning: the feet left the ground with the centre of mass moving down at {v_down:.3} m/s: a fall, not a jump (the jump height is the apex after lift-off against the standing height)"
                );
            }
            if let Some((a, b)) = controls_range {
                v["controls_time_range"] = serde_json::json!([a, b]);
                v["unread_controls_columns"] = serde_json::json!(unread);
                // A controls file that stops well before lift-off (a
                // solution's ends at its t_f, at about lift-off) leaves the
                // jump to its held last row: say so. Without a lift-off the
                // warning below speaks.
                if let Some(push_off) = summary.liftoff_time_s {
                    if a > 0.0 || b < 0.9 * push_off {
                        leap::errln!(
                            "warning: the controls file covers {a:.3}–{b:.3} s of a push-off to {push_off:.3} s: outside that range its first and last rows are held"
                        );
                    }
                }
                // Times in milliseconds stretch a push-off a thousandfold:
                // the file spans more than any run, and the push-off ends
                // before its second row.
                // Without a lift-off, such a file's push-off was read a
                // thousandfold slowed: the same hint.
                if let StudyExcitation::Controls(c) = &exc {
                    let (end, what) = match summary.liftoff_time_s {
                        Some(t) => (t, "the push-off ended (lift-off)"),
                        None => (st.t_max, "the run ended (t_max)"),
                    };
                    let long = c.time.len() > 1 && c.time[0] <= 0.0 && b - a > MAX_T_MAX;
                    if long && c.time[1] >= end {
                        leap::errln!(
                            "warning: {what} at {end:.3} s, before the controls file's second row (t = {} s; the file spans {}–{} s, longer than any jump): it read only the line between the first two rows; OpenSim's files are in seconds (times in milliseconds need dividing by 1000)",
                            leap::io::readable(c.time[1]),
                            leap::io::readable(a),
                            leap::io::readable(b)
                        );
                    } else if long && summary.liftoff_time_s.is_none() {
                        leap::errln!(
                            "warning: no lift-off before t_max = {} s, and the controls file spans {}–{} s, longer than any jump: OpenSim's files are in seconds (times in milliseconds need dividing by 1000)",
                            leap::io::readable(st.t_max),
                            leap::io::readable(a),
                            leap::io::readable(b)
                        );
                    }
                }
            }
            let summary_file = out_dir.join(format!("{SIMULATE_FILE_PREFIX}_summary.json"));
            v["files"] = serde_json::json!(files
                .iter()
                .chain(std::iter::once(&summary_file))
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>());
            v["static_squat_max_abs_qdd"] = serde_json::json!(squat.max_abs_qdd);
            leap::io::write_output(&summary_file, serde_json::to_string_pretty(&v)?)
                .with_context(|| summary_file.display().to_string())?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&v)?);
            } else {
                let f = |o: Option<f64>, scale: f64, unit: &str| {
                    o.map(|v| format!("{:.3} {unit}", v * scale))
                        .unwrap_or_else(|| "-".into())
                };
                outln!(
                    "forward jump ({}, accuracy {:e}) from the static squat",
                    summary.integrator,
                    summary.accuracy
                );
                match summary.liftoff_time_s {
                    Some(_) => outln!(
                        "  jump height            {:.1} cm",
                        100.0 * summary.jump_height_m
                    ),
                    None => {
                        outln!("  jump height            - (no lift-off before t_max)");
                        leap::errln!(
                            "warning: the feet did not leave the ground before t_max = {} s: no jump; the COM ended {:.1} cm from its standing height",
                            st.t_max,
                            100.0 * summary.jump_height_m
                        );
                    }
                }
                outln!(
                    "  lift-off time          {}",
                    f(summary.liftoff_time_s, 1.0, "s")
                );
                outln!(
                    "  lift-off COM velocity  {}",
                    f(summary.liftoff_com_velocity_mps, 1.0, "m/s")
                );
                outln!(
                    "  peak vertical GRF      {:.2} BW",
                    summary.peak_vertical_grf_bw
                );
                outln!(
                    "  steps {} (rejected {}), f evaluations {}, wall {:.3} s",
                    summary.steps,
                    summary.rejected_steps,
                    summary.f_evals,
                    summary.wall_time_s
                );
                outln!("  results in {}", out_dir.display());
            }
            Ok(ExitCode::SUCCESS)
        }
        Err(failure) => {
            let files = write_trajectory(&eq, &failure.trajectory, &out_dir, SIMULATE_FILE_PREFIX)?;
            let names = eq.state_names();
            let state: serde_json::Map<String, serde_json::Value> = names
                .iter()
                .zip(&failure.state)
                .map(|(n, v)| (n.clone(), serde_json::json!(v)))
                .collect();
            let summary_file = out_dir.join(format!("{SIMULATE_FILE_PREFIX}_summary.json"));
            let v = serde_json::json!({"status": "failed", "time": failure.t, "cause": failure.cause, "state": state,
                "files": files.iter().chain(std::iter::once(&summary_file)).map(|p| p.display().to_string()).collect::<Vec<_>>()});
            leap::io::write_output(&summary_file, serde_json::to_string_pretty(&v)?)
                .with_context(|| summary_file.display().to_string())?;
            if json {
                outln!("{}", serde_json::to_string_pretty(&v)?);
            }
            leap::errln!("error: integration stopped: {} (the last state reached at t = {} s; it and the partial results written to {})", failure.cause, failure.t, out_dir.display());
            Ok(ExitCode::from(1))
        }
    }
}

fn solve(
    study: Option<PathBuf>,
    model: Option<PathBuf>,
    overrides: leap::study::Overrides,
    json: bool,
    quiet: bool,
    force_log: bool,
) -> Result<ExitCode> {
    use std::io::IsTerminal;
    use std::sync::atomic::{AtomicBool, Ordering};
    // Ctrl-C stops the SQP at its next iteration and writes the results of
    // its last iterate (status user_requested_stop); a second one exits.
    // Once the results are being written (a few seconds, with the forward
    // check), one more Ctrl-C is needed: quitting then leaves this run's
    // first files beside an earlier run's others.
    let interrupt = std::sync::Arc::new(AtomicBool::new(false));
    let writing = std::sync::Arc::new(AtomicBool::new(false));
    let (flag, writes, warned) = (interrupt.clone(), writing.clone(), AtomicBool::new(false));
    let handler = ctrlc::set_handler(move || {
        let again = flag.swap(true, Ordering::Relaxed);
        if writes.load(Ordering::SeqCst) {
            return ctrl_c_while_writing("solve", &warned);
        }
        if again {
            std::process::exit(130);
        }
        leap::errln!("leap solve: interrupted: stopping at the next iteration and writing the results (Ctrl-C again to quit at once)");
    });
    let mut config = leap::study::SolveConfig::load_with_model(study.as_deref(), model.as_deref())?;
    config.apply(&overrides)?;
    if handler.is_ok() {
        config.settings.interrupt = Some(interrupt);
        config.writing = Some(writing);
    }
    let chatty = !json && !quiet;
    let verbose = force_log || (chatty && std::io::stderr().is_terminal());
    let mut progress = |line: &str| {
        if chatty {
            leap::errln!("leap solve: {line}");
        }
    };
    let report = leap::solve::run(&config, verbose, &mut progress)?;
    if json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else if !quiet {
        out!("{}", report.table());
        outln!("  results in {}", config.output_directory.display());
        // The command that plots them, the forward check beneath.
        let named = |suffix: &str| {
            report
                .output_files
                .iter()
                .find(|f| f.ends_with(suffix))
                .cloned()
        };
        // Quoted for a shell where a path holds a space or a quote.
        let arg = |p: String| {
            if p.contains(|c: char| c.is_whitespace() || c == '\'' || c == '"') {
                format!("'{}'", p.replace('\'', r"'\''"))
            } else {
                p
            }
        };
        if let Some(solution) = named("_solution.sto") {
            // The forward check's states only when it ran through (a failed
            // one writes what it reached, down to its first row).
            let ran = report
                .forward_check
                .as_ref()
                .is_some_and(|f| f.summary.is_some());
            let forward = named("_forward_states.sto")
                .filter(|_| ran)
                .map(|f| format!(" --ref-files {}", arg(f)))
                .unwrap_or_default();
            outln!("  plots: leap report {}{forward}", arg(solution));
        }
    }
    Ok(if report.success {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// `leap crosscheck --jacobian`'s transcription: the built-in study's, with
/// the options given.
fn jacobian_options(
    num_mesh_intervals: Option<i64>,
    scheme: Option<String>,
    fiber_dynamics: Option<String>,
) -> anyhow::Result<leap::transcription::TranscriptionOptions> {
    let mut t = leap::transcription::TranscriptionOptions::default();
    if let Some(n) = num_mesh_intervals {
        t.num_mesh_intervals = leap::study::check_mesh_intervals(n)
            .map_err(|r| anyhow::anyhow!("--num-mesh-intervals: {r}"))?;
    }
    if let Some(s) = &scheme {
        t.scheme = leap::study::parse_scheme(s).map_err(|r| anyhow::anyhow!("--scheme: {r}"))?;
    }
    t.fiber_dynamics = match &fiber_dynamics {
        Some(f) => leap::study::parse_fiber_dynamics(f)
            .map_err(|r| anyhow::anyhow!("--fiber-dynamics: {r}"))?,
        None => leap::study::default_fiber_dynamics(t.scheme),
    };
    leap::study::check_fiber_dynamics(&t).map_err(|r| anyhow::anyhow!("--fiber-dynamics: {r}"))?;
    Ok(t)
}
