//! Benchmarks that print tables: medians over repeated batches, measured in
//! one run so ratios compare like with like.

use crate::model::Model;
use crate::multibody::Multibody;
use crate::simbody::SimbodyModel;
use crate::sqp::median;
use serde::Serialize;
use std::hint::black_box;
use std::time::Instant;

/// One timed row.
#[derive(Debug, Clone, Serialize)]
pub struct BenchRow {
    pub system: String,
    pub backend: String,
    pub what: String,
    /// The evaluation's size: nq for q̈, nx for ẋ = f(x, u)
    /// ([`DynamicsReport::size_name`]).
    pub size: usize,
    pub median_ns: f64,
    pub min_ns: f64,
    pub max_ns: f64,
    pub batches: usize,
    pub calls_per_batch: usize,
}

/// The dynamics benchmark's results.
#[derive(Debug, Clone, Serialize)]
pub struct DynamicsReport {
    /// What is evaluated, and the name of its size ("nq", "nx").
    pub evaluation: &'static str,
    pub size_name: &'static str,
    pub model: String,
    pub rows: Vec<BenchRow>,
    /// Simbody median / Rust-native median, per system.
    pub speedup: Vec<(String, f64)>,
}

/// Median, min and max nanoseconds per call over `batches` batches.
pub fn time_per_call(batches: usize, calls: usize, mut f: impl FnMut(usize)) -> (f64, f64, f64) {
    // Warm up.
    for i in 0..calls.min(1000) {
        f(i);
    }
    let mut per_call: Vec<f64> = (0..batches)
        .map(|_| {
            let t0 = Instant::now();
            for i in 0..calls {
                f(i);
            }
            t0.elapsed().as_nanos() as f64 / calls as f64
        })
        .collect();
    per_call.sort_by(|a, b| a.total_cmp(b));
    (
        per_call[per_call.len() / 2],
        per_call[0],
        per_call[per_call.len() - 1],
    )
}

/// Time per q̈ evaluation (set q and q̇, apply generalized forces, solve for
/// q̈) of the model's full and symmetric systems, Rust-native against Simbody.
pub fn dynamics(model: &Model) -> Result<DynamicsReport, crate::crosscheck::CrosscheckError> {
    let mut rows = Vec::new();
    let mut speedup = Vec::new();
    let mut systems = vec![("full", model.system(false)?)];
    if !model.symmetry.is_empty() {
        systems.push(("symmetric", model.system(true)?));
    }
    let pose = model
        .poses
        .get("squat")
        .cloned()
        .unwrap_or_else(|| model.coordinates.iter().map(|c| c.default_value).collect());
    for (label, sys) in systems {
        let n = sys.nq();
        let q0 = sys.q_from_model(&pose);
        // A small set of distinct states, cycled, so no cache short-cuts a call.
        let states: Vec<(Vec<f64>, Vec<f64>)> = (0..16)
            .map(|k| {
                let s = 0.01 * k as f64;
                (
                    q0.iter()
                        .enumerate()
                        .map(|(i, q)| q + s * ((i + 1) as f64).sin())
                        .collect(),
                    (0..n).map(|i| s * (i as f64 - 2.0)).collect(),
                )
            })
            .collect();
        let tau: Vec<f64> = (0..n).map(|i| 10.0 * (i as f64).cos()).collect();

        let mb = Multibody::new(model, &sys);
        let mut ws = mb.workspace::<f64>();
        let mut qdd = vec![0.0; n];
        let mut failed = false;
        let (med_r, min_r, max_r) = time_per_call(31, 20_000, |i| {
            let (q, u) = &states[i % states.len()];
            mb.set_state(&mut ws, q, u);
            failed |= mb
                .forward_dynamics(&mut ws, black_box(&tau), &mut qdd)
                .is_err();
            black_box(&qdd);
        });
        if failed {
            return Err(crate::multibody::SingularMassMatrix {
                pivot: 0,
                value: f64::NAN,
            }
            .into());
        }
        rows.push(BenchRow {
            system: label.into(),
            backend: "rust-native".into(),
            what: "set q, q̇; q̈ = M⁻¹(τ − b)".into(),
            size: n,
            median_ns: med_r,
            min_ns: min_r,
            max_ns: max_r,
            batches: 31,
            calls_per_batch: 20_000,
        });

        let mut sb = SimbodyModel::new(model, &sys)?;
        sb.set_state(0.0, &states[0].0, &states[0].1)?;
        sb.set_applied_forces(&tau, &[])?;
        let mut err = None;
        let (med_s, min_s, max_s) = time_per_call(15, 2_000, |i| {
            let (q, u) = &states[i % states.len()];
            if let Err(e) = sb
                .set_state(0.0, q, u)
                .and_then(|_| sb.accelerations(&mut qdd))
            {
                err = Some(e);
            }
            black_box(&qdd);
        });
        if let Some(e) = err {
            return Err(e.into());
        }
        rows.push(BenchRow {
            system: label.into(),
            backend: "simbody".into(),
            what: "set q, q̇; realize(Acceleration)".into(),
            size: n,
            median_ns: med_s,
            min_ns: min_s,
            max_ns: max_s,
            batches: 15,
            calls_per_batch: 2_000,
        });
        speedup.push((label.to_string(), med_s / med_r));
    }
    Ok(DynamicsReport {
        evaluation: "q̈",
        size_name: "nq",
        model: model.file.display().to_string(),
        rows,
        speedup,
    })
}

impl DynamicsReport {
    /// A table a person can read.
    pub fn table(&self) -> String {
        let mut t = comfy_table::Table::new();
        t.set_header([
            "system",
            self.size_name,
            "backend",
            "evaluation",
            "median ns/call",
            "min",
            "max",
            "batches × calls",
        ]);
        for r in &self.rows {
            t.add_row([
                r.system.clone(),
                r.size.to_string(),
                r.backend.clone(),
                r.what.clone(),
                format!("{:.0}", r.median_ns),
                format!("{:.0}", r.min_ns),
                format!("{:.0}", r.max_ns),
                format!("{} × {}", r.batches, r.calls_per_batch),
            ]);
        }
        let ratios: Vec<String> = self
            .speedup
            .iter()
            .map(|(s, r)| format!("{s}: Rust-native {r:.1}× faster than Simbody"))
            .collect();
        format!(
            "{} evaluation, {}\n{t}\n{}",
            self.evaluation,
            self.model,
            ratios.join("\n")
        )
    }
}

/// Time per evaluation of ẋ = f(x, u) of the symmetric jumper at states
/// along a squat: Rust-native (f64, and with one dual direction) against the
/// Simbody backend.
pub fn state_equation(model: &Model) -> Result<DynamicsReport, crate::crosscheck::CrosscheckError> {
    use crate::ode::{SimbodyStateEquation, StateEquation};
    use crate::scalar::Dual64;
    use std::sync::Arc;
    let eq = Arc::new(StateEquation::new(
        model,
        true,
        crate::path::PathSmoothing::Smooth { delta: 0.02 },
    )?);
    let laws = Arc::new(crate::laws::OpenSimLaws::new(model)?);
    // The states are perturbations of the static squat: a jump model's.
    let pose = model.squat_pose().map_err(|e| {
        crate::crosscheck::CrosscheckError::Simbody(crate::simbody::SimbodyError::Input(
            e.to_string(),
        ))
    })?;
    let sq = crate::squat::static_squat(&eq, &laws, &pose).map_err(|e| {
        crate::crosscheck::CrosscheckError::Simbody(crate::simbody::SimbodyError::Input(
            e.to_string(),
        ))
    })?;
    let (n, nx) = (eq.nq(), eq.nx());
    let states: Vec<Vec<f64>> = (0..16)
        .map(|k| {
            let mut x = sq.x.clone();
            for i in 0..n {
                x[n + i] = 0.05 * k as f64 * ((i + 1) as f64).sin();
            }
            x
        })
        .collect();
    let u = sq.excitation.clone();
    let mut rows = Vec::new();
    let mut ws = eq.workspace::<f64>();
    let mut xd = vec![0.0; nx];
    let mut bad = false;
    let (m, lo, hi) = time_per_call(21, 5_000, |i| {
        bad |= eq
            .rhs(&*laws, &mut ws, &states[i % 16], &u, &mut xd)
            .is_err();
        black_box(&xd);
    });
    let row =
        |backend: &str, what: &str, (m, lo, hi): (f64, f64, f64), b: usize, c: usize| BenchRow {
            system: "symmetric jumper".into(),
            backend: backend.into(),
            what: what.into(),
            size: nx,
            median_ns: m,
            min_ns: lo,
            max_ns: hi,
            batches: b,
            calls_per_batch: c,
        };
    rows.push(row(
        "rust-native",
        "ẋ = f(x, u), f64",
        (m, lo, hi),
        21,
        5_000,
    ));
    let mut wsd = eq.workspace::<Dual64>();
    let ud: Vec<Dual64> = u.iter().map(|&v| Dual64::from(v)).collect();
    let sd: Vec<Vec<Dual64>> = states
        .iter()
        .map(|x| {
            x.iter()
                .enumerate()
                .map(|(i, &v)| {
                    if i == 3 {
                        Dual64::from(v).derivative()
                    } else {
                        Dual64::from(v)
                    }
                })
                .collect()
        })
        .collect();
    let mut xdd = vec![Dual64::from(0.0); nx];
    let t_dual = time_per_call(11, 2_000, |i| {
        bad |= eq
            .rhs(&*laws, &mut wsd, &sd[i % 16], &ud, &mut xdd)
            .is_err();
        black_box(&xdd);
    });
    rows.push(row(
        "rust-native",
        "ẋ and one directional derivative (Dual64)",
        t_dual,
        11,
        2_000,
    ));
    let mut sb = SimbodyStateEquation::new(eq.clone(), laws.clone())?;
    let mut err = None;
    let t_sb = time_per_call(7, 300, |i| {
        if let Err(e) = sb.rhs(&states[i % 16], &u, &mut xd) {
            err = Some(e);
        }
        black_box(&xd);
    });
    if let Some(e) = err {
        return Err(e.into());
    }
    if bad {
        return Err(crate::crosscheck::CrosscheckError::Simbody(
            crate::simbody::SimbodyError::Input("f(x, u) failed during the benchmark".into()),
        ));
    }
    rows.push(row(
        "simbody",
        "ẋ = f(x, u) (forces in a Simbody force element)",
        t_sb,
        7,
        300,
    ));
    let speedup = vec![("f(x, u)".to_string(), t_sb.0 / m)];
    Ok(DynamicsReport {
        evaluation: "ẋ = f(x, u)",
        size_name: "nx",
        model: model.file.display().to_string(),
        rows,
        speedup,
    })
}

/// One forward jump per integrator and accuracy from the static squat with
/// the default bang-bang excitations.
#[derive(Debug, Clone, Serialize)]
pub struct IntegratorRow {
    pub integrator: String,
    pub accuracy: f64,
    pub steps: usize,
    pub rejected_steps: usize,
    pub f_evals: usize,
    pub wall_time_s: f64,
    pub jump_height_m: f64,
    pub liftoff_time_s: Option<f64>,
}

/// Forward jumps with every integrator (a table).
pub fn integrators(model: &Model, cases: &[(&str, f64)]) -> Result<Vec<IntegratorRow>, String> {
    use crate::simulate::*;
    use std::sync::Arc;
    let (laws, eq) = crate::ode::StateEquation::opensim(model, true).map_err(|e| e.to_string())?;
    let pose = model.squat_pose().map_err(|e| e.to_string())?;
    let sq = crate::squat::static_squat(&eq, &laws, &pose).map_err(|e| e.to_string())?;
    let ext = extensor_moments(&eq, &pose);
    let exc = StudyExcitation::BangBang(BangBang {
        intervals: ext
            .iter()
            .map(|&e| {
                if e > 0.0 {
                    Some((0.0, f64::INFINITY))
                } else {
                    None
                }
            })
            .collect(),
        off_level: crate::laws::MIN_ACTIVATION,
    });
    let standing = standing_com_height(&eq);
    let (eqa, lawsa) = (Arc::new(eq.clone()), Arc::new(laws.clone()));
    let mut rows = Vec::new();
    for &(name, acc) in cases {
        let r = match parse_integrator(name)? {
            IntegratorChoice::DormandPrince => simulate_rust(
                &eq,
                &laws,
                &exc,
                &sq.x,
                standing,
                SimulateOptions {
                    integrator: crate::integrator::Dopri5Options {
                        accuracy: acc,
                        max_steps: 200_000,
                        ..Default::default()
                    },
                    t_max: 1.0,
                },
            ),
            IntegratorChoice::Simbody(w) => {
                simulate_simbody(&eqa, &lawsa, &exc, &sq.x, standing, w, acc, 1.0, 1e-3)
            }
        };
        let (s, _) = r.map_err(|e| format!("{name} at {acc:e}: {e}"))?;
        rows.push(IntegratorRow {
            integrator: s.integrator.clone(),
            accuracy: acc,
            steps: s.steps,
            rejected_steps: s.rejected_steps,
            f_evals: s.f_evals,
            wall_time_s: s.wall_time_s,
            jump_height_m: s.jump_height_m,
            liftoff_time_s: s.liftoff_time_s,
        });
    }
    Ok(rows)
}

/// The integrator table as text.
pub fn integrator_table(rows: &[IntegratorRow]) -> String {
    let mut t = comfy_table::Table::new();
    t.set_header([
        "integrator",
        "accuracy",
        "steps",
        "rejected",
        "f evaluations",
        "wall time (s)",
        "jump height (cm)",
        "lift-off (s)",
    ]);
    for r in rows {
        t.add_row([
            r.integrator.clone(),
            format!("{:e}", r.accuracy),
            r.steps.to_string(),
            r.rejected_steps.to_string(),
            r.f_evals.to_string(),
            format!("{:.3}", r.wall_time_s),
            format!("{:.2}", 100.0 * r.jump_height_m),
            r.liftoff_time_s
                .map(|t| format!("{t:.4}"))
                .unwrap_or("-".into()),
        ]);
    }
    format!("forward jump from the static squat, default bang-bang excitations\n{t}")
}

/// One Hessian mode on the whole Hock–Schittkowski test set.
#[derive(Debug, Clone, Serialize)]
pub struct SqpTestSetRow {
    pub hessian: crate::sqp::HessianMode,
    pub line_search: crate::sqp::LineSearch,
    pub problems: usize,
    /// Status solved with the book's f* within 1e-6 relative.
    pub at_published_optimum: usize,
    pub solved_or_acceptable: usize,
    pub iterations: usize,
    pub qp_iterations: u64,
    /// Median over `repeats` runs of the whole set (s).
    pub wall_time_s: f64,
    pub derivatives_s: f64,
    pub hessian_s: f64,
    pub qp_s: f64,
    pub line_search_s: f64,
    pub other_s: f64,
}

/// Solve the whole Hock–Schittkowski set once per Hessian mode, `repeats`
/// times, and report the median wall time with the time split of the
/// median run.
pub fn sqp_test_set(repeats: usize) -> Vec<SqpTestSetRow> {
    use crate::sqp::{solve, HessianMode, LineSearch, SqpSettings};
    let mut rows = Vec::new();
    for (mode, line_search) in [
        (HessianMode::ExactConvexified, LineSearch::Filter),
        (HessianMode::PartitionedBfgs, LineSearch::Filter),
        (HessianMode::ExactConvexified, LineSearch::L1Merit),
        (HessianMode::PartitionedBfgs, LineSearch::L1Merit),
    ] {
        let settings = SqpSettings {
            hessian: mode,
            line_search,
            ..Default::default()
        };
        let mut runs = Vec::new();
        for _ in 0..repeats.max(1) {
            let mut row = SqpTestSetRow {
                hessian: mode,
                line_search,
                problems: 0,
                at_published_optimum: 0,
                solved_or_acceptable: 0,
                iterations: 0,
                qp_iterations: 0,
                wall_time_s: 0.0,
                derivatives_s: 0.0,
                hessian_s: 0.0,
                qp_s: 0.0,
                line_search_s: 0.0,
                other_s: 0.0,
            };
            let t = Instant::now();
            for p in crate::testset::hock_schittkowski() {
                let f_star = p.reference_optimum();
                let r = solve(&mut crate::nlp::AdNlp::new(p), &settings);
                row.problems += 1;
                row.iterations += r.iterations;
                row.qp_iterations += r.qp_iterations;
                row.solved_or_acceptable += usize::from(r.status.success());
                if r.status == crate::sqp::SqpStatus::Solved
                    && (r.objective - f_star).abs() <= 1e-6 * f_star.abs().max(1.0)
                {
                    row.at_published_optimum += 1;
                }
                row.derivatives_s += r.time.derivatives_s;
                row.hessian_s += r.time.hessian_s;
                row.qp_s += r.time.qp_s;
                row.line_search_s += r.time.line_search_s;
                row.other_s += r.time.other_s;
            }
            row.wall_time_s = t.elapsed().as_secs_f64();
            runs.push(row);
        }
        runs.sort_by(|a, b| a.wall_time_s.total_cmp(&b.wall_time_s));
        rows.push(runs.swap_remove(runs.len() / 2));
    }
    rows
}

/// The test-set rows as a table.
pub fn sqp_table(rows: &[SqpTestSetRow]) -> String {
    let mut t = comfy_table::Table::new();
    t.set_header(vec![
        "Hessian",
        "line search",
        "problems",
        "at reference f* (solved)",
        "solved/acceptable",
        "iterations",
        "QP iterations",
        "wall s (median)",
        "derivatives s",
        "Hessian s",
        "QP s",
        "line search s",
        "other s",
    ]);
    for r in rows {
        t.add_row(vec![
            format!("{:?}", r.hessian),
            format!("{:?}", r.line_search),
            r.problems.to_string(),
            r.at_published_optimum.to_string(),
            r.solved_or_acceptable.to_string(),
            r.iterations.to_string(),
            r.qp_iterations.to_string(),
            format!("{:.3}", r.wall_time_s),
            format!("{:.3}", r.derivatives_s),
            format!("{:.3}", r.hessian_s),
            format!("{:.3}", r.qp_s),
            format!("{:.3}", r.line_search_s),
            format!("{:.3}", r.other_s),
        ]);
    }
    t.to_string()
}

/// One SQP iteration on the 29-node jump collocation problem (2,409
/// variables, 1,736 dynamics rows), from the bang-bang guess.
#[derive(Debug, Clone, Serialize)]
pub struct SqpJumpRow {
    pub iter: usize,
    pub derivatives_ms: f64,
    pub hessian_ms: f64,
    pub qp_ms: f64,
    pub qp_iterations: u32,
    pub qp_mode: String,
    pub line_search_ms: f64,
    pub objective: f64,
    pub inf_pr: f64,
}

/// The problem's size and the first `iterations` SQP iterations on it.
#[derive(Debug, Clone, Serialize)]
pub struct SqpJumpReport {
    pub variables: usize,
    pub constraints: usize,
    pub jacobian_nnz: usize,
    pub hessian: crate::sqp::HessianMode,
    pub qp_equilibrate: bool,
    /// The built-in study's choices that the iterations ran with.
    pub fiber_dynamics: crate::transcription::FiberDynamics,
    pub qp_solver: crate::sqp::QpSolver,
    pub rows: Vec<SqpJumpRow>,
}

/// Run `iterations` SQP iterations on the jump transcription of `model`,
/// with the built-in study's transcription and solver settings (those of
/// `leap solve`: implicit fibre dynamics, the interior-point QP solver)
/// and the Hessian mode and QP equilibration given.
pub fn sqp_jump(
    model: &Model,
    iterations: usize,
    hessian: crate::sqp::HessianMode,
    qp_equilibrate: bool,
) -> Result<SqpJumpReport, String> {
    use crate::nlp::Nlp;
    let config = crate::study::SolveConfig::builtin().map_err(|e| e.to_string())?;
    let ocp = std::sync::Arc::new(
        crate::ocp::JumpOcp::new(model, Default::default()).map_err(|e| e.to_string())?,
    );
    let fiber_dynamics = config.transcription.fiber_dynamics;
    let mut tr = crate::transcription::Transcription::new(ocp, config.transcription)
        .map_err(|e| e.to_string())?;
    let (mut guess, _) = tr.bang_bang_guess().map_err(|e| e.to_string())?;
    if config.guess == crate::study::GuessChoice::BangBang {
        tr.integrate_on_mesh(&mut guess)
            .map_err(|e| e.to_string())?;
    }
    let settings = crate::sqp::SqpSettings {
        hessian,
        max_iterations: iterations,
        qp_equilibrate,
        ..config.settings
    };
    let r = crate::sqp::solve_from(&mut tr, &guess, &settings);
    let rows = r
        .history
        .iter()
        .filter(|h| h.qp_iterations > 0)
        .map(|h| SqpJumpRow {
            iter: h.iter,
            derivatives_ms: 1e3 * h.derivatives_s,
            hessian_ms: 1e3 * h.hessian_s,
            qp_ms: 1e3 * h.qp_s,
            qp_iterations: h.qp_iterations,
            qp_mode: h.qp_mode.clone(),
            line_search_ms: 1e3 * h.line_search_s,
            objective: h.objective,
            inf_pr: h.inf_pr,
        })
        .collect();
    Ok(SqpJumpReport {
        variables: tr.num_variables(),
        constraints: tr.num_constraints(),
        jacobian_nnz: tr.jacobian_nnz(),
        hessian,
        qp_equilibrate,
        fiber_dynamics,
        qp_solver: settings.qp_solver,
        rows,
    })
}

impl SqpJumpReport {
    pub fn table(&self) -> String {
        let mut t = comfy_table::Table::new();
        t.set_header(vec![
            "iter",
            "derivatives ms",
            "Hessian ms",
            "QP ms",
            "QP iterations",
            "QP mode",
            "line search ms",
            "objective",
            "inf_pr",
        ]);
        for r in &self.rows {
            t.add_row(vec![
                r.iter.to_string(),
                format!("{:.1}", r.derivatives_ms),
                format!("{:.1}", r.hessian_ms),
                format!("{:.0}", r.qp_ms),
                r.qp_iterations.to_string(),
                r.qp_mode.clone(),
                format!("{:.2}", r.line_search_ms),
                format!("{:.6}", r.objective),
                format!("{:.2e}", r.inf_pr),
            ]);
        }
        format!(
            "jump collocation: {} variables, {} constraints, nnz(J) {}, {} fibre dynamics, Hessian {:?}, QP solver {:?}, QP equilibration {}\n{t}",
            self.variables,
            self.constraints,
            self.jacobian_nnz,
            crate::study::fiber_dynamics_name(self.fiber_dynamics),
            self.hessian,
            self.qp_solver,
            self.qp_equilibrate
        )
    }
}

/// One whole `leap solve` (without the forward check), per repeat.
#[derive(Debug, Clone, Serialize)]
pub struct SolveBenchRun {
    pub num_mesh_intervals: usize,
    pub status: crate::sqp::SqpStatus,
    pub iterations: usize,
    pub wall_time_s: f64,
    pub split: crate::sqp::TimeSplit,
    pub jump_height_m: f64,
    /// QPs handed from leap's interior-point solver to clarabel, and
    /// clarabel's wall time on them (part of the QP time).
    pub qp_fallbacks: usize,
    pub qp_fallback_seconds: f64,
}

/// The whole solve of a study: iterations, wall time and its split
/// (derivatives, Hessian, QP, line search, other), per repeat and the
/// median.
#[derive(Debug, Clone, Serialize)]
pub struct SolveBenchReport {
    pub study: String,
    pub variables: usize,
    pub constraints: usize,
    /// The SQP's Hessian mode (`hessian_mode` in the JSON, as in `leap
    /// solve`'s).
    #[serde(rename = "hessian_mode")]
    pub hessian: crate::sqp::HessianMode,
    /// The Hessian as a study names it ([`crate::study::hessian_option_name`]):
    /// `hessian` in the JSON.
    #[serde(rename = "hessian")]
    pub hessian_option: &'static str,
    pub runs: Vec<SolveBenchRun>,
    pub median_wall_time_s: f64,
    /// Medians over all runs of the iteration count and of the wall time
    /// per iteration: the SQP's path changes with the last bit of its
    /// input, so one solve says little about a change to the solver and a
    /// sweep over meshes says more.
    pub median_iterations: f64,
    pub median_time_per_iteration_s: f64,
}

/// Solve `config` `repeats` times (output into a temporary directory,
/// removed after; no forward check), with the Hessian mode `hessian` when
/// given, at each mesh of `meshes` (the study's own when empty).
pub fn solve(
    config: &crate::study::SolveConfig,
    study: &str,
    repeats: usize,
    hessian: Option<&str>,
    meshes: &[i64],
) -> Result<SolveBenchReport, String> {
    let out = std::env::temp_dir().join(format!("leap_bench_solve_{}", std::process::id()));
    let mut configs = Vec::new();
    let mesh_list: Vec<Option<i64>> = if meshes.is_empty() {
        vec![None]
    } else {
        meshes.iter().map(|&n| Some(n)).collect()
    };
    // Every mesh is checked before the first solve starts.
    for n in mesh_list {
        let mut config = config.clone();
        config
            .apply(&crate::study::Overrides {
                output_directory: Some(out.clone()),
                no_forward_check: true,
                hessian: hessian.map(str::to_string),
                num_mesh_intervals: n,
                ..Default::default()
            })
            .map_err(|e| e.to_string())?;
        configs.push(config);
    }
    let mut runs = Vec::new();
    let (mut variables, mut constraints) = (0, 0);
    for config in &configs {
        for _ in 0..repeats.max(1) {
            let r = crate::solve::run(config, false, &mut |_| {}).map_err(|e| {
                // No scratch results left behind by a failed solve.
                let _ = std::fs::remove_dir_all(&out);
                e.to_string()
            })?;
            (variables, constraints) = (r.variables, r.constraints);
            runs.push(SolveBenchRun {
                num_mesh_intervals: config.transcription.num_mesh_intervals,
                status: r.status,
                iterations: r.iterations,
                wall_time_s: r.wall_time_s,
                split: r.time_split,
                jump_height_m: r.jump_height_m,
                qp_fallbacks: r.qp_fallbacks,
                qp_fallback_seconds: r.qp_fallback_seconds,
            });
        }
    }
    let _ = std::fs::remove_dir_all(&out);
    Ok(SolveBenchReport {
        study: study.into(),
        variables,
        constraints,
        hessian: configs[0].settings.hessian,
        hessian_option: crate::study::hessian_option_name(&configs[0].settings),
        median_wall_time_s: median(runs.iter().map(|r| r.wall_time_s).collect()),
        median_iterations: median(runs.iter().map(|r| r.iterations as f64).collect()),
        median_time_per_iteration_s: median(
            runs.iter()
                .map(|r| r.wall_time_s / r.iterations.max(1) as f64)
                .collect(),
        ),
        runs,
    })
}

impl SolveBenchReport {
    pub fn table(&self) -> String {
        let mut t = comfy_table::Table::new();
        t.set_header(vec![
            "run",
            "mesh intervals",
            "status",
            "iterations",
            "wall time (s)",
            "per iteration (s)",
            "derivatives (s)",
            "Hessian (s)",
            "QP (s)",
            "line search (s)",
            "other (s)",
            "QP fallbacks (clarabel s)",
            "jump height (cm)",
        ]);
        for (k, r) in self.runs.iter().enumerate() {
            let s = &r.split;
            t.add_row(vec![
                (k + 1).to_string(),
                r.num_mesh_intervals.to_string(),
                r.status.name().to_string(),
                r.iterations.to_string(),
                format!("{:.1}", r.wall_time_s),
                format!("{:.3}", r.wall_time_s / r.iterations.max(1) as f64),
                format!("{:.1}", s.derivatives_s),
                format!("{:.1}", s.hessian_s),
                format!("{:.1}", s.qp_s),
                format!("{:.2}", s.line_search_s),
                format!("{:.2}", s.other_s),
                format!("{} ({:.1})", r.qp_fallbacks, r.qp_fallback_seconds),
                format!("{:.2}", 100.0 * r.jump_height_m),
            ]);
        }
        format!(
            "{} ({} Hessian): {} variables, {} constraints (last run); medians over {} runs: wall time {:.1} s, {} iterations, {:.3} s per iteration\n{t}",
            self.study,
            self.hessian_option,
            self.variables,
            self.constraints,
            self.runs.len(),
            self.median_wall_time_s,
            self.median_iterations,
            self.median_time_per_iteration_s
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bad mesh or Hessian anywhere in a sweep is an error naming the
    /// option and the value. (Were the meshes checked lazily, the first
    /// case would solve the 28-interval jump for minutes before failing:
    /// the test would still pass, slowly.)
    #[test]
    fn solve_sweep_checks_every_mesh_before_solving() {
        let config = crate::study::SolveConfig::builtin().expect("built-in study");
        let e = solve(&config, "built-in", 1, None, &[28, 1]).unwrap_err();
        assert!(
            e.contains("--num-mesh-intervals") && e.contains("got 1"),
            "{e}"
        );
        let e = solve(&config, "built-in", 1, Some("newton"), &[]).unwrap_err();
        assert!(e.contains("--hessian") && e.contains("'newton'"), "{e}");
    }
}

/// The cost of one SQP iteration by method on the 29-node jump.
#[derive(Debug, Clone, Serialize)]
pub struct MethodRow {
    pub method: &'static str,
    pub variables: usize,
    pub constraints: usize,
    pub jacobian_nnz: usize,
    /// Iterations timed (those that solved a QP).
    pub iterations: usize,
    /// Medians per iteration (s).
    pub derivatives_s: f64,
    pub hessian_s: f64,
    pub qp_s: f64,
    pub line_search_s: f64,
    pub iteration_s: f64,
    /// Porsa et al. (2016): CPU time per iteration of their solve (s).
    pub paper_iteration_s: f64,
}

/// [`methods`]: both rows and the shooting integrations' cost.
#[derive(Debug, Clone, Serialize)]
pub struct MethodsReport {
    pub rows: Vec<MethodRow>,
    /// One integration of the push-off from the squat (median, s), and its
    /// right-hand-side evaluations.
    pub shooting_integration_s: f64,
    pub shooting_integration_f_evals: usize,
    /// One shooting Jacobian (at the bang-bang guess) with each kind of
    /// derivatives.
    pub shooting_jacobians: Vec<ShootingJacobianCost>,
    /// The study's shooting settings (the derivatives: both, as above).
    pub shooting: crate::shooting::ShootingOptions,
    /// One collocation Jacobian (at the bang-bang guess) with each backend.
    pub collocation_jacobians: Vec<CollocationJacobianCost>,
}

/// One collocation Jacobian with one backend
/// ([`crate::transcription::Backend`]).
#[derive(Debug, Clone, serde::Serialize)]
pub struct CollocationJacobianCost {
    pub backend: &'static str,
    /// Points where the state equation is evaluated, and evaluations of it
    /// per point (dual passes of `lanes` directions; Simbody: the value and
    /// four differences per colour).
    pub points: usize,
    pub evaluations_per_point: usize,
    /// Median wall time over 5 Jacobians (s).
    pub seconds: f64,
}

/// The work of one shooting Jacobian.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ShootingJacobianCost {
    pub derivatives: &'static str,
    /// Central differences: integrations, each from its column's node.
    pub integrations: usize,
    /// Forward sensitivities: integrator steps replayed, and point
    /// Jacobians ∂f/∂(x, u) (one per stage and per node).
    pub steps_replayed: usize,
    pub point_jacobians: usize,
    /// Right-hand-side evaluations (f64) and wall time.
    pub f_evals: usize,
    pub seconds: f64,
}

/// Porsa et al. (2016), Table 2: collocation 702 iterations in 3.4 h of
/// CPU, shooting 602 iterations in 846 h.
pub const PAPER_COLLOCATION_S_PER_ITERATION: f64 = 3.4 * 3600.0 / 702.0;
pub const PAPER_SHOOTING_S_PER_ITERATION: f64 = 846.0 * 3600.0 / 602.0;

fn method_row(
    method: &'static str,
    size: (usize, usize, usize),
    history: &[crate::sqp::IterationRecord],
    paper_iteration_s: f64,
) -> MethodRow {
    let timed: Vec<&crate::sqp::IterationRecord> =
        history.iter().filter(|h| h.qp_iterations > 0).collect();
    let m = |f: &dyn Fn(&crate::sqp::IterationRecord) -> f64| {
        median(timed.iter().map(|h| f(h)).collect())
    };
    MethodRow {
        method,
        variables: size.0,
        constraints: size.1,
        jacobian_nnz: size.2,
        iterations: timed.len(),
        derivatives_s: m(&|h| h.derivatives_s),
        hessian_s: m(&|h| h.hessian_s),
        qp_s: m(&|h| h.qp_s),
        line_search_s: m(&|h| h.line_search_s),
        iteration_s: m(&|h| h.derivatives_s + h.hessian_s + h.qp_s + h.line_search_s),
        paper_iteration_s,
    }
}

/// The first `iterations` SQP iterations of each method on the built-in
/// study's jump from the bang-bang guess (collocation: the study's
/// transcription, exact Hessians; shooting: Dormand–Prince at the default
/// accuracy, BFGS, once with central differences and once with forward
/// sensitivities), per iteration against the paper's CPU time per
/// iteration.
pub fn methods(model: &Model, iterations: usize) -> Result<MethodsReport, String> {
    use crate::nlp::Nlp;
    let config = crate::study::SolveConfig::builtin().map_err(|e| e.to_string())?;
    let settings = crate::sqp::SqpSettings {
        max_iterations: iterations,
        ..config.settings.clone()
    };
    // Collocation, as `leap solve` sets it up.
    let ocp = std::sync::Arc::new(
        crate::ocp::JumpOcp::new(model, Default::default()).map_err(|e| e.to_string())?,
    );
    let mut tr = crate::transcription::Transcription::new(ocp.clone(), config.transcription)
        .map_err(|e| e.to_string())?;
    let (mut guess, _) = tr.bang_bang_guess().map_err(|e| e.to_string())?;
    tr.integrate_on_mesh(&mut guess)
        .map_err(|e| e.to_string())?;
    let mut collocation_jacobians = Vec::new();
    for backend in [
        crate::transcription::Backend::RustNative,
        crate::transcription::Backend::Simbody,
    ] {
        let mut t = crate::transcription::Transcription::with_pattern(
            ocp.clone(),
            crate::transcription::TranscriptionOptions {
                backend,
                ..config.transcription
            },
            tr.pattern().clone(),
        )
        .map_err(|e| e.to_string())?;
        let mut values = vec![0.0; t.jacobian_nnz()];
        let mut times = Vec::new();
        for _ in 0..5 {
            let started = std::time::Instant::now();
            t.jacobian_values(&guess, &mut values)
                .map_err(|e| e.to_string())?;
            times.push(started.elapsed().as_secs_f64());
        }
        let stats = t.jacobian_stats();
        collocation_jacobians.push(CollocationJacobianCost {
            backend: crate::study::backend_name(backend),
            points: t.num_points(),
            evaluations_per_point: match backend {
                crate::transcription::Backend::RustNative => stats.passes,
                crate::transcription::Backend::Simbody => 1 + 4 * stats.colors,
            },
            seconds: median(times),
        });
    }
    let r = crate::sqp::solve_from(&mut tr, &guess, &settings);
    let collocation = method_row(
        "collocation",
        (tr.num_variables(), tr.num_constraints(), tr.jacobian_nnz()),
        &r.history,
        PAPER_COLLOCATION_S_PER_ITERATION,
    );
    // Shooting, with each kind of derivatives.
    let mut rows = vec![collocation];
    let mut jacobians = Vec::new();
    let mut integration = (f64::NAN, 0);
    for derivatives in [
        crate::shooting::ShootingDerivatives::CentralDifference,
        crate::shooting::ShootingDerivatives::ForwardSensitivity,
    ] {
        let options = crate::shooting::ShootingOptions {
            num_intervals: config.transcription.num_mesh_intervals,
            derivatives,
            ..config.shooting
        };
        let mut sh =
            crate::shooting::Shooting::new(ocp.clone(), options).map_err(|e| e.to_string())?;
        let (v, _) = sh.bang_bang_guess().map_err(|e| e.to_string())?;
        if integration.1 == 0 {
            let mut times = Vec::new();
            for k in 0..5 {
                let mut p = v.clone();
                let last = p.len() - 1;
                p[last] += 1e-9 * k as f64;
                let before = sh.counters.f_evals;
                let t = std::time::Instant::now();
                sh.evaluate(&p).map_err(|e| e.to_string())?;
                times.push(t.elapsed().as_secs_f64());
                integration.1 = sh.counters.f_evals - before;
            }
            integration.0 = median(times);
        }
        sh.evaluate(&v).map_err(|e| e.to_string())?;
        let before = sh.counters;
        let mut g = vec![0.0; sh.num_variables()];
        sh.gradient(&v, &mut g).map_err(|e| e.to_string())?;
        let c = sh.counters;
        jacobians.push(ShootingJacobianCost {
            derivatives: derivatives.name(),
            integrations: c.difference_simulations - before.difference_simulations,
            steps_replayed: c.sensitivity_steps - before.sensitivity_steps,
            point_jacobians: c.point_jacobians - before.point_jacobians,
            f_evals: c.f_evals - before.f_evals,
            seconds: c.jacobian_seconds - before.jacobian_seconds,
        });
        // A fresh problem for the SQP: `sh` holds the derivatives at `v`
        // just measured, which its first iteration would reuse uncounted.
        let mut sh =
            crate::shooting::Shooting::new(ocp.clone(), options).map_err(|e| e.to_string())?;
        let settings = crate::shooting::sqp_settings(&settings);
        let size = (
            sh.num_variables(),
            sh.num_constraints(),
            sh.jacobian_structure().len(),
        );
        let r = crate::sqp::solve_from(&mut sh, &v, &settings);
        let label = match derivatives {
            crate::shooting::ShootingDerivatives::CentralDifference => {
                "shooting, central-difference"
            }
            crate::shooting::ShootingDerivatives::ForwardSensitivity => {
                "shooting, forward-sensitivity"
            }
        };
        rows.push(method_row(
            label,
            size,
            &r.history,
            PAPER_SHOOTING_S_PER_ITERATION,
        ));
    }
    Ok(MethodsReport {
        rows,
        shooting_integration_s: integration.0,
        shooting_integration_f_evals: integration.1,
        shooting_jacobians: jacobians,
        shooting: crate::shooting::ShootingOptions {
            num_intervals: config.transcription.num_mesh_intervals,
            ..config.shooting
        },
        collocation_jacobians,
    })
}

impl MethodsReport {
    pub fn table(&self) -> String {
        let mut t = comfy_table::Table::new();
        t.set_header(vec![
            "method",
            "variables",
            "constraints",
            "nnz(J)",
            "iterations timed",
            "derivatives (s)",
            "Hessian (s)",
            "QP (s)",
            "line search (s)",
            "iteration (s)",
            "paper's iteration (s CPU)",
            "paper / leap",
        ]);
        for r in &self.rows {
            t.add_row(vec![
                r.method.to_string(),
                r.variables.to_string(),
                r.constraints.to_string(),
                r.jacobian_nnz.to_string(),
                r.iterations.to_string(),
                format!("{:.3}", r.derivatives_s),
                format!("{:.3}", r.hessian_s),
                format!("{:.3}", r.qp_s),
                format!("{:.3}", r.line_search_s),
                format!("{:.3}", r.iteration_s),
                format!("{:.1}", r.paper_iteration_s),
                format!("{:.0}", r.paper_iteration_s / r.iteration_s),
            ]);
        }
        let ratio = |r: &MethodRow| r.iteration_s / self.rows[0].iteration_s;
        let mut text = format!(
            "the 29-node jump, per SQP iteration (medians over the first iterations from the bang-bang guess; wall time on this machine against the paper's CPU time, Porsa et al. 2016 Table 2)\n{t}\n  shooting: one push-off integration {:.3} s ({} f evaluations, Dormand–Prince at {:e}); Jacobians on {} threads\n",
            self.shooting_integration_s,
            self.shooting_integration_f_evals,
            self.shooting.accuracy,
            self.shooting.threads,
        );
        for j in &self.collocation_jacobians {
            text += &format!(
                "  one collocation Jacobian through {}: {:.4} s, {} points × {}\n",
                j.backend,
                j.seconds,
                j.points,
                if j.backend == "simbody" {
                    format!("{} Simbody evaluations (the value, central differences of two steps per colour)", j.evaluations_per_point)
                } else {
                    format!("{} coloured dual passes", j.evaluations_per_point)
                }
            );
        }
        for j in &self.shooting_jacobians {
            let work = if j.integrations > 0 {
                format!(
                    "{} integrations from each column's node, step {:e}",
                    j.integrations, self.shooting.finite_difference_step
                )
            } else {
                format!(
                    "{} steps replayed, {} point Jacobians",
                    j.steps_replayed, j.point_jacobians
                )
            };
            text += &format!(
                "  one {} Jacobian: {:.2} s, {work}, {} f evaluations\n",
                j.derivatives, j.seconds, j.f_evals
            );
        }
        for r in self.rows.iter().skip(1) {
            text += &format!(
                "  an iteration of {} costs {:.1} collocation iterations (the paper's shooting: {:.0})\n",
                r.method,
                ratio(r),
                PAPER_SHOOTING_S_PER_ITERATION / PAPER_COLLOCATION_S_PER_ITERATION
            );
        }
        text
    }
}
