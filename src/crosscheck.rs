//! Cross-check of the Rust-native dynamics against Simbody.
//!
//! At random states inside the coordinate ranges, with random generalized
//! forces and random forces at every station, both backends compute the mass
//! matrix, bias forces, accelerations, whole-body centre of mass position,
//! velocity and acceleration, and station positions and velocities. Each
//! quantity's error is normwise relative, `‖rust − simbody‖∞ / ‖simbody‖∞`,
//! maximised over the samples. For a model with symmetry pairs the symmetric
//! system is also checked against the full one with equal left and right
//! states (`M_s = Bᵀ M B`, `b_s = Bᵀ b`, `q̈ = B q̈_s`, same COM and stations),
//! in both backends.

use crate::model::{Model, ModelError, SystemSpec};
use crate::multibody::{Multibody, SingularMassMatrix};
use crate::simbody::{SimbodyError, SimbodyModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::collections::BTreeMap;

/// The largest error the cross-check accepts for the multibody quantities.
pub const TOLERANCE: f64 = 1e-10;
/// The largest error it accepts for the state equation ẋ = f(x, u).
pub const STATE_EQUATION_TOLERANCE: f64 = 1e-9;

/// A cross-check could not run.
#[derive(Debug, thiserror::Error)]
pub enum CrosscheckError {
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Simbody(#[from] SimbodyError),
    #[error(transparent)]
    Singular(#[from] SingularMassMatrix),
    #[error(transparent)]
    Ode(#[from] crate::ode::OdeError),
    #[error(transparent)]
    Laws(#[from] crate::laws::UnsupportedLaw),
}

/// Largest normwise relative errors, per comparison and quantity.
#[derive(Debug, Clone, Serialize)]
pub struct CrosscheckReport {
    pub model: String,
    pub samples: usize,
    pub seed: u64,
    pub tolerance: f64,
    pub max_rel_error: f64,
    /// Largest normwise relative error of ẋ = f(x, u) (Rust-native laws and
    /// kinematics against the same laws inside Simbody), if the model has
    /// force elements.
    pub state_equation_max_rel_error: Option<f64>,
    pub state_equation_tolerance: f64,
    pub passed: bool,
    /// comparison → quantity → max relative error
    pub comparisons: BTreeMap<String, BTreeMap<String, f64>>,
}

fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    let mut num: f64 = 0.0;
    let mut den: f64 = 0.0;
    for (x, y) in a.iter().zip(b) {
        num = num.max((x - y).abs());
        den = den.max(y.abs());
    }
    if !num.is_finite() || !den.is_finite() {
        return f64::INFINITY;
    }
    if den == 0.0 {
        num
    } else {
        num / den
    }
}

/// Everything one backend reports at one sample.
#[derive(Debug, Clone, Default)]
struct Sample {
    mass_matrix: Vec<f64>,
    bias: Vec<f64>,
    qdd: Vec<f64>,
    com_position: Vec<f64>,
    com_velocity: Vec<f64>,
    com_acceleration: Vec<f64>,
    station_position: Vec<f64>,
    station_velocity: Vec<f64>,
}

impl Sample {
    fn quantities(&self) -> [(&'static str, &Vec<f64>); 8] {
        [
            ("mass_matrix", &self.mass_matrix),
            ("bias", &self.bias),
            ("qdd", &self.qdd),
            ("com_position", &self.com_position),
            ("com_velocity", &self.com_velocity),
            ("com_acceleration", &self.com_acceleration),
            ("station_position", &self.station_position),
            ("station_velocity", &self.station_velocity),
        ]
    }
}

/// Inputs of one sample: q, q̇, generalized forces, one force per station.
#[derive(Debug, Clone)]
struct Inputs {
    q: Vec<f64>,
    u: Vec<f64>,
    tau: Vec<f64>,
    station_forces: Vec<[f64; 3]>,
}

fn eval_rust(model: &Model, mb: &Multibody, x: &Inputs) -> Result<Sample, SingularMassMatrix> {
    let n = mb.nq();
    let mut ws = mb.workspace::<f64>();
    mb.set_state(&mut ws, &x.q, &x.u);
    let mut tau = x.tau.clone();
    let mut s = Sample::default();
    for (st, f) in model.stations.iter().zip(&x.station_forces) {
        let (b, p) = mb.body_point(st.body, st.location);
        mb.add_point_force(&ws, b, p, *f, &mut tau);
        s.station_position.extend(mb.point_position(&ws, b, p));
        s.station_velocity.extend(mb.point_velocity(&ws, b, p));
    }
    let mut qdd = vec![0.0; n];
    mb.forward_dynamics(&mut ws, &tau, &mut qdd)?;
    s.mass_matrix = mb.mass_matrix(&ws).to_vec();
    s.bias = mb.bias(&ws).to_vec();
    s.com_position = mb.com_position(&ws).to_vec();
    s.com_velocity = mb.com_velocity(&ws).to_vec();
    s.com_acceleration = mb.com_acceleration(&ws, &qdd).to_vec();
    s.qdd = qdd;
    Ok(s)
}

fn eval_simbody(model: &Model, sb: &mut SimbodyModel, x: &Inputs) -> Result<Sample, SimbodyError> {
    let n = sb.nq();
    sb.set_state(0.0, &x.q, &x.u)?;
    let forces: Vec<(usize, [f64; 3], [f64; 3])> = model
        .stations
        .iter()
        .zip(&x.station_forces)
        .map(|(st, f)| (st.body, st.location, *f))
        .collect();
    sb.set_applied_forces(&x.tau, &forces)?;
    let mut s = Sample {
        mass_matrix: vec![0.0; n * n],
        bias: vec![0.0; n],
        qdd: vec![0.0; n],
        ..Default::default()
    };
    sb.mass_matrix(&mut s.mass_matrix)?;
    sb.bias(&mut s.bias)?;
    sb.accelerations(&mut s.qdd)?;
    s.com_position = sb.com_position()?.to_vec();
    s.com_velocity = sb.com_velocity()?.to_vec();
    s.com_acceleration = sb.com_acceleration()?.to_vec();
    for st in &model.stations {
        s.station_position
            .extend(sb.station_position(st.body, st.location)?);
        s.station_velocity
            .extend(sb.station_velocity(st.body, st.location)?);
    }
    Ok(s)
}

/// Project a full-system sample onto the symmetric system: `Bᵀ M B`, `Bᵀ b`,
/// and q̈ restricted to the independent coordinates.
fn project(full: &Sample, full_sys: &SystemSpec, sym_sys: &SystemSpec) -> Sample {
    let nf = full_sys.nq();
    let ns = sym_sys.nq();
    // B[i][k] = 1 when full coordinate i follows symmetric coordinate k.
    let map: Vec<usize> = full_sys
        .coordinates
        .iter()
        .map(|&c| sym_sys.q_of_model_coordinate[c])
        .collect();
    let mut m = vec![0.0; ns * ns];
    let mut b = vec![0.0; ns];
    for i in 0..nf {
        b[map[i]] += full.bias[i];
        for j in 0..nf {
            m[map[i] * ns + map[j]] += full.mass_matrix[i * nf + j];
        }
    }
    let qdd = sym_sys
        .coordinates
        .iter()
        .map(|&c| full.qdd[full_sys.q_of_model_coordinate[c]])
        .collect();
    Sample {
        mass_matrix: m,
        bias: b,
        qdd,
        ..full.clone()
    }
}

fn record(table: &mut BTreeMap<String, f64>, a: &Sample, b: &Sample) {
    for ((name, x), (_, y)) in a.quantities().iter().zip(b.quantities().iter()) {
        let e = rel_err(x, y);
        let entry = table.entry(name.to_string()).or_insert(0.0);
        if e > *entry || e.is_nan() {
            *entry = e;
        }
    }
}

fn random_inputs(rng: &mut ChaCha8Rng, model: &Model, sys: &SystemSpec) -> Inputs {
    let model_q: Vec<f64> = model
        .coordinates
        .iter()
        .map(|c| {
            // Translations of the base: keep the model near the origin.
            let [lo, hi] = c.range;
            let (lo, hi) = if hi - lo > 4.0 { (-1.0, 1.0) } else { (lo, hi) };
            rng.random_range(lo..=hi)
        })
        .collect();
    let model_u: Vec<f64> = model
        .coordinates
        .iter()
        .map(|_| rng.random_range(-5.0..=5.0))
        .collect();
    let model_tau: Vec<f64> = model
        .coordinates
        .iter()
        .map(|_| rng.random_range(-100.0..=100.0))
        .collect();
    let station_forces = model
        .stations
        .iter()
        .map(|_| {
            [
                rng.random_range(-500.0..=500.0),
                rng.random_range(-500.0..=1500.0),
                rng.random_range(-100.0..=100.0),
            ]
        })
        .collect();
    Inputs {
        q: sys.q_from_model(&model_q),
        u: sys.q_from_model(&model_u),
        tau: sys.q_from_model(&model_tau),
        station_forces,
    }
}

/// Run the cross-check on `samples` random states drawn with `seed`.
pub fn run(model: &Model, samples: usize, seed: u64) -> Result<CrosscheckReport, CrosscheckError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let full = model.system(false)?;
    let mb_full = Multibody::new(model, &full);
    let mut sb_full = SimbodyModel::new(model, &full)?;
    let sym = if model.symmetry.is_empty() {
        None
    } else {
        Some(model.system(true)?)
    };
    let mut sym_backends = match &sym {
        Some(s) => Some((Multibody::new(model, s), SimbodyModel::new(model, s)?)),
        None => None,
    };
    let mut comparisons: BTreeMap<String, BTreeMap<String, f64>> = BTreeMap::new();
    for _ in 0..samples {
        let x = random_inputs(&mut rng, model, &full);
        let r = eval_rust(model, &mb_full, &x)?;
        let s = eval_simbody(model, &mut sb_full, &x)?;
        record(
            comparisons
                .entry("rust_vs_simbody_full".into())
                .or_default(),
            &r,
            &s,
        );
        if let (Some(sym), Some((mb_sym, sb_sym))) = (&sym, sym_backends.as_mut()) {
            // A symmetric state: left coordinates copy their right partners;
            // generalized forces likewise, so the full solution stays symmetric.
            let xs = random_inputs(&mut rng, model, sym);
            let model_q = sym.model_from_q(&xs.q);
            let model_u = sym.model_from_q(&xs.u);
            let model_tau = sym.model_from_q(&xs.tau);
            let xf = Inputs {
                q: full.q_from_model(&model_q),
                u: full.q_from_model(&model_u),
                tau: full.q_from_model(&model_tau),
                station_forces: mirror_station_forces(model, &xs.station_forces),
            };
            // The symmetric system carries both legs' forces: sum of generalized forces.
            let xs = Inputs {
                station_forces: xf.station_forces.clone(),
                tau: sym_tau(&full, sym, &xf.tau),
                ..xs
            };
            let rs = eval_rust(model, mb_sym, &xs)?;
            let ss = eval_simbody(model, sb_sym, &xs)?;
            record(
                comparisons
                    .entry("rust_vs_simbody_symmetric".into())
                    .or_default(),
                &rs,
                &ss,
            );
            let rf = eval_rust(model, &mb_full, &xf)?;
            let sf = eval_simbody(model, &mut sb_full, &xf)?;
            record(
                comparisons
                    .entry("symmetric_vs_full_rust".into())
                    .or_default(),
                &rs,
                &project(&rf, &full, sym),
            );
            record(
                comparisons
                    .entry("symmetric_vs_full_simbody".into())
                    .or_default(),
                &ss,
                &project(&sf, &full, sym),
            );
        }
    }
    let max_rel_error = comparisons
        .values()
        .flat_map(|t| t.values())
        .fold(
            0.0f64,
            |a, &b| if b.is_nan() { f64::INFINITY } else { a.max(b) },
        );
    let state_equation_max_rel_error =
        if model.muscles.is_empty() && model.contact.is_none() && model.ligaments.is_empty() {
            None
        } else {
            let mut worst: f64 = 0.0;
            let mut table = BTreeMap::new();
            for symmetric in [true, false] {
                if symmetric && model.symmetry.is_empty() {
                    continue;
                }
                let e = state_equation_error(model, symmetric, samples, &mut rng)?;
                table.insert(
                    if symmetric {
                        "symmetric".to_string()
                    } else {
                        "full".to_string()
                    },
                    e,
                );
                worst = worst.max(if e.is_nan() { f64::INFINITY } else { e });
            }
            comparisons.insert("state_equation_rust_vs_simbody".into(), table);
            Some(worst)
        };
    let passed = max_rel_error <= TOLERANCE
        && state_equation_max_rel_error.is_none_or(|e| e <= STATE_EQUATION_TOLERANCE);
    Ok(CrosscheckReport {
        model: model.file.display().to_string(),
        samples,
        seed,
        tolerance: TOLERANCE,
        max_rel_error,
        state_equation_max_rel_error,
        state_equation_tolerance: STATE_EQUATION_TOLERANCE,
        passed,
        comparisons,
    })
}

/// Largest normwise relative error of ẋ = f(x, u) between the Rust-native
/// state equation and the same equation inside Simbody, at random states
/// near the model's squat (so that the feet touch the ground) with random
/// speeds, fibre lengths, activations and excitations.
fn state_equation_error(
    model: &Model,
    symmetric: bool,
    samples: usize,
    rng: &mut ChaCha8Rng,
) -> Result<f64, CrosscheckError> {
    use crate::ode::{SimbodyStateEquation, StateEquation};
    use std::sync::Arc;
    let eq = Arc::new(StateEquation::new(
        model,
        symmetric,
        crate::path::PathSmoothing::Smooth { delta: 0.02 },
    )?);
    let laws = Arc::new(crate::laws::OpenSimLaws::new(model)?);
    let mut sb = SimbodyStateEquation::new(eq.clone(), laws.clone())?;
    let (n, nm, nx) = (eq.nq(), eq.nm(), eq.nx());
    let pose = model
        .poses
        .get("squat")
        .cloned()
        .unwrap_or_else(|| model.coordinates.iter().map(|c| c.default_value).collect());
    let q0 = eq.system.q_from_model(&pose);
    let ty = model
        .coordinate_index("pelvis_ty")
        .map(|c| eq.system.q_of_model_coordinate[c]);
    let mut ws = eq.workspace::<f64>();
    let mut worst: f64 = 0.0;
    for _ in 0..samples {
        let mut x = vec![0.0; nx];
        for i in 0..n {
            x[i] = q0[i] + rng.random_range(-0.05..=0.05);
            x[n + i] = rng.random_range(-2.0..=2.0);
        }
        if let Some(ty) = ty {
            x[ty] += rng.random_range(-0.03..=0.0);
        }
        // Fibre lengths within ±0.5 % of muscle-tendon equilibrium at the
        // state's activation, so that every law sees a physical tendon.
        let lmt = eq.path_lengths(&x[..n]);
        for k in 0..nm {
            let a = rng.random_range(0.01..=1.0);
            let lm = laws.muscles[eq.muscles[k]].equilibrium_fiber_length(a, lmt[k]);
            x[2 * n + k] = lm * rng.random_range(0.995..=1.005);
            x[2 * n + nm + k] = a;
        }
        let u: Vec<f64> = (0..nm).map(|_| rng.random_range(0.01..=1.0)).collect();
        let (mut fr, mut fs) = (vec![0.0; nx], vec![0.0; nx]);
        eq.rhs(&*laws, &mut ws, &x, &u, &mut fr)?;
        sb.rhs(&x, &u, &mut fs)?;
        worst = worst.max(rel_err(&fr, &fs));
    }
    Ok(worst)
}

/// Station forces on the left side equal to those on the right partner
/// station (matched by name, `_r` ↔ `_l`, z mirrored), so both legs stay
/// mirror images.
fn mirror_station_forces(model: &Model, forces: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let mut out = forces.to_vec();
    for (i, st) in model.stations.iter().enumerate() {
        if let Some(stem) = st.name.strip_suffix("_l") {
            let right = format!("{stem}_r");
            if let Some(j) = model.stations.iter().position(|s| s.name == right) {
                let f = forces[j];
                out[i] = [f[0], f[1], -f[2]];
            }
        }
    }
    out
}

/// Generalized forces of the symmetric system for full-system forces `tau`
/// (`Bᵀ τ`).
fn sym_tau(full: &SystemSpec, sym: &SystemSpec, tau: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; sym.nq()];
    for (i, &c) in full.coordinates.iter().enumerate() {
        out[sym.q_of_model_coordinate[c]] += tau[i];
    }
    out
}

impl CrosscheckReport {
    /// A table a person can read.
    pub fn table(&self) -> String {
        let mut t = comfy_table::Table::new();
        let cols: Vec<&String> = self
            .comparisons
            .keys()
            .filter(|k| k.as_str() != "state_equation_rust_vs_simbody")
            .collect();
        let mut header = vec!["quantity".to_string()];
        header.extend(cols.iter().map(|s| s.to_string()));
        t.set_header(header);
        let names = [
            "mass_matrix",
            "bias",
            "qdd",
            "com_position",
            "com_velocity",
            "com_acceleration",
            "station_position",
            "station_velocity",
        ];
        for q in names {
            if cols.iter().all(|c| !self.comparisons[*c].contains_key(q)) {
                continue;
            }
            let mut row = vec![q.to_string()];
            for c in &cols {
                row.push(
                    self.comparisons[*c]
                        .get(q)
                        .map(|e| format!("{e:.2e}"))
                        .unwrap_or_else(|| "-".into()),
                );
            }
            t.add_row(row);
        }
        let fline = match (
            self.state_equation_max_rel_error,
            self.comparisons.get("state_equation_rust_vs_simbody"),
        ) {
            (Some(e), Some(tab)) => {
                format!(
                "\nstate equation ẋ = f(x, u), Rust-native against Simbody: {} (tolerance {:.0e})",
                tab.iter().map(|(k, v)| format!("{k} {v:.2e}")).collect::<Vec<_>>().join(", "),
                self.state_equation_tolerance
            ) + if e.is_nan() { " NaN" } else { "" }
            }
            _ => String::new(),
        };
        format!(
            "{t}{fline}\nmodel {}: {} samples (seed {}), largest relative error {:.2e}, tolerance {:.0e}: {}",
            self.model,
            self.samples,
            self.seed,
            self.max_rel_error,
            self.tolerance,
            if self.passed { "PASS" } else { "FAIL" }
        )
    }
}

/// The largest difference between the Rust-native and Simbody collocation
/// Jacobians the cross-check accepts away from kinks, relative to the
/// largest entry of the row (the bound `tests/transcription.rs` sets the
/// exact Jacobian against Rust-native finite differences).
pub const JACOBIAN_TOLERANCE: f64 = 1e-6;
/// The largest entry Simbody's differences may find outside the pattern,
/// relative to the row's largest (the transcription tests' bound on
/// Rust-native differences outside it).
pub const PATTERN_TOLERANCE: f64 = 1e-7;

/// Relative step of the one-sided differences that tell a jump in a
/// derivative (a kink) from a wrong derivative (the transcription tests'
/// step for the same check).
pub const KINK_ONE_SIDED_STEP: f64 = 1e-8;

/// Per row of a sparse Jacobian, its largest |entry| (at least 1).
fn row_scale(structure: &[(usize, usize)], values: &[f64], rows: usize) -> Vec<f64> {
    let mut scale = vec![1.0f64; rows];
    for (&(i, _), v) in structure.iter().zip(values) {
        scale[i] = scale[i].max(v.abs());
    }
    scale
}

/// Whether `d` exceeds `bound`, NaN counting as exceeding.
fn exceeds(d: f64, bound: f64) -> bool {
    d.is_nan() || d > bound
}

/// One point of [`jacobian`]: the rows and the Jacobian at a variable
/// vector, Rust-native against Simbody.
#[derive(Debug, Clone, Serialize)]
pub struct JacobianPoint {
    /// "bang-bang guess" or "perturbed guess <k>".
    pub point: String,
    /// Whether the point is held to [`JACOBIAN_TOLERANCE`]: not the guess,
    /// whose muscles at a = u = a_min sit on the activation switch, where
    /// the one-sided derivatives differ.
    pub checked: bool,
    /// max |c_rust − c_simbody| / max(1, |c_rust|), and its row.
    pub rows: f64,
    pub rows_at: String,
    /// max |J_rust − J_simbody| / max(1, the row's largest |J_rust|), and
    /// its entry; entries beyond [`JACOBIAN_TOLERANCE`].
    pub jacobian: f64,
    pub jacobian_at: String,
    pub entries_beyond: usize,
    /// Of those, entries at a kink, of one of two kinds; a wrong
    /// derivative is neither.
    /// - A jump in the second derivative (Thelen's tendon and
    ///   force–velocity curves are piecewise, their pieces meeting with
    ///   equal slopes): differenced again with a tenth and a hundredth of
    ///   the step, the entry's difference from the exact one shrinks at
    ///   least threefold each time (first order: tenfold), or falls within
    ///   the tolerance.
    /// - A jump in the derivative itself (a clamp, a tendon at its slack
    ///   length; the schemes that evaluate the dynamics at the nodes meet
    ///   them): one-sided differences of step [`KINK_ONE_SIDED_STEP`] differ
    ///   by more than 1e-3 of the row's largest entry and the exact entry is
    ///   one of them within 1e-4 (the bounds of the transcription tests'
    ///   kink check).
    pub entries_at_kinks: usize,
    /// The largest difference among the other entries beyond the tolerance
    /// (zero if none). The point passes with none, and with at most one
    /// entry in a thousand at kinks.
    pub unexplained: f64,
}

/// [`jacobian`]'s report.
#[derive(Debug, Clone, Serialize)]
pub struct JacobianReport {
    pub model: String,
    pub num_mesh_intervals: usize,
    pub scheme: &'static str,
    pub fiber_dynamics: &'static str,
    pub entries: usize,
    pub points: Vec<JacobianPoint>,
    /// Simbody's differences over every column, not coloured, at the first
    /// perturbed point: the largest entry outside the Rust-native pattern
    /// relative to its row's largest, and where.
    pub outside_pattern: f64,
    pub outside_pattern_at: String,
    pub tolerance: f64,
    pub pattern_tolerance: f64,
    pub passed: bool,
}

/// The collocation Jacobian of the jump on `model`, Rust-native (exact, by
/// dual numbers) against Simbody (central differences through Simbody's
/// multibody system, [`crate::transcription::Backend::Simbody`]), at the
/// bang-bang guess and at `perturbed` points near it: each variable moved
/// by up to 1e-3 of its range (at most 2), kept inside its bounds with a
/// margin, so that no activation equals its excitation.
pub fn jacobian(
    model: &Model,
    options: crate::transcription::TranscriptionOptions,
    perturbed: usize,
    seed: u64,
) -> Result<JacobianReport, String> {
    use crate::nlp::Nlp;
    use crate::transcription::{Backend, StatePattern, Transcription, TranscriptionOptions};
    if perturbed == 0 {
        return Err("at least one perturbed point is needed (the guess sits on kinks)".into());
    }
    let ocp = std::sync::Arc::new(
        crate::ocp::JumpOcp::new(model, crate::solve::collocation_ocp_options(&options))
            .map_err(|e| e.to_string())?,
    );
    let pattern = StatePattern::detect_for(
        &ocp,
        options.fiber_dynamics,
        options.pattern_samples,
        options.pattern_seed,
    )
    .map_err(|e| e.to_string())?;
    let build = |backend: Backend, pattern: StatePattern, compress_columns: bool| {
        let options = TranscriptionOptions {
            backend,
            compress_columns,
            ..options
        };
        Transcription::with_pattern(ocp.clone(), options, pattern).map_err(|e| e.to_string())
    };
    let mut rust = build(
        Backend::RustNative,
        pattern.clone(),
        options.compress_columns,
    )?;
    let mut sb = build(Backend::Simbody, pattern.clone(), options.compress_columns)?;
    let (mut guess, _) = rust.bang_bang_guess().map_err(|e| e.to_string())?;
    rust.integrate_on_mesh(&mut guess)
        .map_err(|e| e.to_string())?;
    let (n, m) = (rust.num_variables(), rust.num_constraints());
    let (mut lo, mut hi) = (vec![0.0; n], vec![0.0; n]);
    rust.variable_bounds(&mut lo, &mut hi);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut points = vec![("bang-bang guess".to_string(), guess.clone())];
    for k in 1..=perturbed {
        let x = (0..n)
            .map(|i| {
                let width = (hi[i] - lo[i]).min(2.0);
                // Distinct margins keep clipped values apart (an activation
                // equal to its excitation sits on the activation switch).
                let margin = (1e-4 + 1e-3 * (i % 7) as f64) * width;
                let v = guess[i] + 1e-3 * width * rng.random_range(-1.0..1.0);
                v.clamp(lo[i] + margin, hi[i] - margin)
            })
            .collect();
        points.push((format!("perturbed guess {k}"), x));
    }
    let structure = rust.jacobian_structure();
    let nnz = structure.len();
    let mut reports = Vec::new();
    let (mut cr, mut cs) = (vec![0.0; m], vec![0.0; m]);
    let (mut jr, mut js) = (vec![0.0; nnz], vec![0.0; nnz]);
    for (k, (point, x)) in points.iter().enumerate() {
        let err = |e: crate::nlp::EvalError| format!("{point}: {e}");
        rust.constraints(x, &mut cr).map_err(err)?;
        sb.constraints(x, &mut cs).map_err(err)?;
        rust.jacobian_values(x, &mut jr).map_err(err)?;
        sb.jacobian_values(x, &mut js).map_err(err)?;
        let (mut rows, mut rows_row) = (0.0f64, 0);
        for (i, (a, b)) in cr.iter().zip(&cs).enumerate() {
            let e = (a - b).abs() / a.abs().max(1.0);
            if exceeds(e, rows) {
                (rows, rows_row) = (e, i);
            }
        }
        let scale = row_scale(&structure, &jr, m);
        let (mut worst, mut at, mut beyond) = (0.0f64, String::new(), Vec::new());
        for (e, &(i, j)) in structure.iter().enumerate() {
            let d = (jr[e] - js[e]).abs() / scale[i];
            if exceeds(d, JACOBIAN_TOLERANCE) {
                beyond.push((e, d));
            }
            if exceeds(d, worst) {
                worst = d;
                at = format!(
                    "∂{}/∂{}: {} (Rust-native) against {} (Simbody), row scale {}",
                    rust.constraint_name(i),
                    rust.variable_name(j),
                    jr[e],
                    js[e],
                    scale[i]
                );
            }
        }
        let (mut kinks, mut unexplained) = (0, 0.0f64);
        if k > 0 && !beyond.is_empty() {
            use crate::transcription::{Differences, FD_STEP};
            let mut with = |d: Differences| -> Result<Vec<f64>, String> {
                sb.set_differences(d).map_err(|e| e.to_string())?;
                let mut values = vec![0.0; nnz];
                let r = sb.jacobian_values(x, &mut values).map_err(err);
                sb.set_differences(Differences::Central { step: FD_STEP })
                    .map_err(|e| e.to_string())?;
                r.map(|_| values)
            };
            let fine = with(Differences::Central {
                step: FD_STEP / 10.0,
            })?;
            let finer = with(Differences::Central {
                step: FD_STEP / 100.0,
            })?;
            let step = KINK_ONE_SIDED_STEP;
            let forward = with(Differences::Forward { step })?;
            let backward = with(Differences::Backward { step })?;
            for &(e, d) in &beyond {
                let s = scale[structure[e].0];
                let off = |v: f64| (jr[e] - v).abs() / s;
                // Converging on the exact entry as the step shrinks tenfold,
                // twice: a wrong entry stops converging at its error.
                let (d1, d2) = (off(fine[e]), off(finer[e]));
                let smooth_kink = d1 <= d / 3.0 && d2 <= (d1 / 3.0).max(JACOBIAN_TOLERANCE);
                let (f, b) = (forward[e], backward[e]);
                let jump = (f - b).abs() / s > 1e-3 && off(f).min(off(b)) <= 1e-4;
                if !d.is_nan() && (smooth_kink || jump) {
                    kinks += 1;
                } else {
                    // A NaN difference is unexplained too.
                    unexplained = if d.is_nan() {
                        f64::INFINITY
                    } else {
                        unexplained.max(d)
                    };
                }
            }
        }
        reports.push(JacobianPoint {
            point: point.clone(),
            checked: k > 0,
            rows,
            rows_at: rust.constraint_name(rows_row),
            jacobian: worst,
            jacobian_at: at,
            entries_beyond: beyond.len(),
            entries_at_kinks: kinks,
            unexplained,
        });
    }
    // Every column differenced apart: what lies outside the pattern.
    let (mut outside, mut outside_at) = (0.0f64, String::new());
    if let Some((_, x)) = points.get(1) {
        let dense = StatePattern {
            rows: vec![(0..pattern.nx + pattern.nu).collect(); pattern.rows.len()],
            ..pattern.clone()
        };
        let mut all = build(Backend::Simbody, dense, false)?;
        let all_structure = all.jacobian_structure();
        let mut jd = vec![0.0; all_structure.len()];
        all.jacobian_values(x, &mut jd)
            .map_err(|e| format!("every column apart: {e}"))?;
        let inside: std::collections::HashSet<(usize, usize)> = structure.iter().copied().collect();
        let scale = row_scale(&all_structure, &jd, m);
        for (&(i, j), v) in all_structure.iter().zip(&jd) {
            let r = v.abs() / scale[i];
            if !inside.contains(&(i, j)) && exceeds(r, outside) {
                outside = r;
                outside_at = format!(
                    "∂{}/∂{} = {v}",
                    all.constraint_name(i),
                    all.variable_name(j)
                );
            }
        }
    }
    // Kinks are rare: at most one entry in a thousand (the transcription
    // tests' allowance).
    let passed = reports.iter().all(|p| {
        p.rows <= STATE_EQUATION_TOLERANCE
            && (!p.checked || (p.unexplained == 0.0 && p.entries_at_kinks <= nnz / 1000))
    }) && outside <= PATTERN_TOLERANCE;
    Ok(JacobianReport {
        model: model.file.display().to_string(),
        num_mesh_intervals: options.num_mesh_intervals,
        scheme: crate::study::scheme_name(options.scheme),
        fiber_dynamics: crate::study::fiber_dynamics_name(options.fiber_dynamics),
        entries: nnz,
        points: reports,
        outside_pattern: outside,
        outside_pattern_at: outside_at,
        tolerance: JACOBIAN_TOLERANCE,
        pattern_tolerance: PATTERN_TOLERANCE,
        passed,
    })
}

impl JacobianReport {
    /// Lines a person can read.
    pub fn table(&self) -> String {
        let mut t = comfy_table::Table::new();
        t.set_header(vec![
            "point",
            "rows",
            "Jacobian",
            &format!("entries beyond {:.0e}", self.tolerance),
            "of them at kinks",
            "largest Jacobian difference",
        ]);
        for p in &self.points {
            t.add_row(vec![
                format!(
                    "{}{}",
                    p.point,
                    if p.checked {
                        ""
                    } else {
                        " (not held: on the activation switch)"
                    }
                ),
                format!("{:.2e}", p.rows),
                format!("{:.2e}", p.jacobian),
                p.entries_beyond.to_string(),
                if p.checked {
                    p.entries_at_kinks.to_string()
                } else {
                    "-".into()
                },
                p.jacobian_at.clone(),
            ]);
        }
        format!(
            "collocation Jacobian of the jump, Rust-native (dual numbers) against Simbody (central differences): model {}, {} mesh intervals, {}, {} fibre dynamics, {} entries\n{t}\noutside the pattern (every column differenced through Simbody): largest {:.2e} (tolerance {:.0e}){}\nrows within {:.0e}, Jacobians within {:.0e} of each row's largest entry but at kinks: {}",
            self.model,
            self.num_mesh_intervals,
            self.scheme,
            self.fiber_dynamics,
            self.entries,
            self.outside_pattern,
            self.pattern_tolerance,
            if self.outside_pattern_at.is_empty() { String::new() } else { format!(", {}", self.outside_pattern_at) },
            STATE_EQUATION_TOLERANCE,
            self.tolerance,
            if self.passed { "PASS" } else { "FAIL" }
        )
    }
}
