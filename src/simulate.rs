//! Forward simulation of a jump: integrate ẋ = f(x, u(t)) from a start
//! state, detect lift-off (no vertical ground force), follow the flight to
//! the centre-of-mass apex, and report what the paper reports.

use crate::integrator::{Dopri5, Dopri5Options, IntegrationError, OdeSystem};
use crate::io::StoTable;
use crate::ode::{ForceLaws, StateEquation, StateWorkspace};
use crate::study::StudyError;
use serde::Serialize;
use std::path::Path;

/// Excitations as a function of time.
pub trait ExcitationSource {
    fn at(&self, t: f64, u: &mut [f64]);
}

impl ExcitationSource for crate::io::Controls {
    fn at(&self, t: f64, u: &mut [f64]) {
        crate::io::Controls::at(self, t, u)
    }
}

/// The bang-bang pattern: each muscle fully on (1) inside its interval,
/// otherwise at `off_level` (the minimum excitation).
#[derive(Debug, Clone, Serialize)]
pub struct BangBang {
    /// Per muscle: `Some((t_on, t_off))` or `None` (always off).
    pub intervals: Vec<Option<(f64, f64)>>,
    pub off_level: f64,
}

impl ExcitationSource for BangBang {
    fn at(&self, t: f64, u: &mut [f64]) {
        for (o, iv) in u.iter_mut().zip(&self.intervals) {
            *o = match iv {
                Some((a, b)) if t >= *a && t < *b => 1.0,
                _ => self.off_level,
            };
        }
    }
}

/// Net sagittal action of each carried muscle at a pose: positive when its
/// moment arms, weighted by sign, extend the trunk, hip and knee and
/// plantarflex the ankle (OpenSim signs: lumbar extension +, hip flexion +,
/// knee angle + toward extension, ankle angle + dorsiflexion).
pub fn extensor_moments(eq: &StateEquation, pose: &[f64]) -> Vec<f64> {
    use crate::multibody::{GeneralizedForces, ModelView};
    let sys = &eq.system;
    let mut ws = eq.multibody.workspace::<f64>();
    let q = sys.q_from_model(pose);
    eq.multibody.set_state(&mut ws, &q, &vec![0.0; q.len()]);
    let sign_of = |name: &str| -> f64 {
        if name.starts_with("lumbar_extension") || name.starts_with("knee_angle") {
            1.0
        } else if name.starts_with("hip_flexion") || name.starts_with("ankle_angle") {
            -1.0
        } else {
            0.0
        }
    };
    eq.muscles
        .iter()
        .map(|&mi| {
            let mut tau = vec![0.0; q.len()];
            {
                let view = ModelView {
                    mb: &eq.multibody,
                    ws: &ws,
                    q_of: &sys.q_of_model_coordinate,
                };
                let mut sink = GeneralizedForces {
                    mb: &eq.multibody,
                    ws: &ws,
                    q_of: &sys.q_of_model_coordinate,
                    tau: &mut tau,
                };
                eq.model.muscles[mi]
                    .path
                    .calc(&view, eq.smoothing, Some((1.0, &mut sink)));
            }
            let f0 = eq.model.muscles[mi].spec.max_isometric_force;
            sys.coordinates
                .iter()
                .enumerate()
                .map(|(k, &c)| sign_of(&eq.model.coordinates[c].name) * tau[k] * f0)
                .sum()
        })
        .collect()
}

/// Results of a forward jump.
#[derive(Debug, Clone, Serialize)]
pub struct JumpSummary {
    /// Apex COM height minus standing COM height (m).
    pub jump_height_m: f64,
    pub liftoff_time_s: Option<f64>,
    /// Vertical COM velocity at lift-off (m/s).
    pub liftoff_com_velocity_mps: Option<f64>,
    /// COM height at lift-off (m).
    pub liftoff_com_height_m: Option<f64>,
    /// Peak total vertical ground force / body weight.
    pub peak_vertical_grf_bw: f64,
    /// Apex COM height (m) and the standing COM height it is measured from.
    pub apex_com_height_m: f64,
    pub standing_com_height_m: f64,
    pub final_time_s: f64,
    pub steps: usize,
    pub rejected_steps: usize,
    /// Dormand–Prince: steps accepted at the minimum step size with the
    /// error above the accuracy ([`crate::integrator::IntegrationStats`]);
    /// Simbody does the same but does not count them (None).
    pub steps_over_tolerance: Option<usize>,
    pub f_evals: usize,
    pub wall_time_s: f64,
    pub integrator: String,
    pub accuracy: f64,
}

impl JumpSummary {
    /// The speed (m/s, positive) at which the centre of mass moved down
    /// when the feet left the ground, if it did: a fall, not a jump
    /// (muscles too weak, or switched off early), whatever the height
    /// after.
    pub fn falling_at_liftoff(&self) -> Option<f64> {
        self.liftoff_com_velocity_mps
            .filter(|&vy| vy < 0.0)
            .map(|vy| -vy)
    }
}

/// A recorded trajectory: times, states, controls and ground forces.
#[derive(Debug, Clone, Default)]
pub struct Trajectory {
    pub time: Vec<f64>,
    pub states: Vec<Vec<f64>>,
    pub controls: Vec<Vec<f64>>,
    /// Per time: right and left foot force (ground on foot, N) and centre of
    /// pressure on the ground (m): [Fx, Fy, Fz, px, py, pz] × 2.
    pub grf: Vec<[f64; 12]>,
}

/// A simulation stopped early: the cause, where, and what was computed.
#[derive(Debug, thiserror::Error)]
#[error("integration stopped: {cause} (the last state reached at t = {t} s)")]
pub struct SimulationFailure {
    /// The time of the last state reached (the failing step's start).
    pub t: f64,
    pub state: Vec<f64>,
    pub cause: String,
    pub trajectory: Trajectory,
}

struct Rhs<'a, L: ForceLaws<f64>, E: ExcitationSource> {
    eq: &'a StateEquation,
    laws: &'a L,
    exc: &'a E,
    ws: StateWorkspace<f64>,
    u: Vec<f64>,
}

impl<L: ForceLaws<f64>, E: ExcitationSource> OdeSystem for Rhs<'_, L, E> {
    fn dim(&self) -> usize {
        self.eq.nx()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), String> {
        self.exc.at(t, &mut self.u);
        // OpenSim 4: Thelen's min_control is its minimum activation.
        for v in self.u.iter_mut() {
            *v = v.clamp(crate::laws::MIN_ACTIVATION, 1.0);
        }
        self.eq
            .rhs(self.laws, &mut self.ws, x, &self.u, dx)
            .map_err(|e| e.to_string())
    }
}

/// Ground forces per foot from the workspace of the last evaluation of
/// `eq.rhs` at state `x`: [Fx, Fy, Fz, px, py, pz] for the right then the
/// left foot (ground on foot, N; centre of pressure on the ground, m).
pub fn grf_of(eq: &StateEquation, ws: &StateWorkspace<f64>, x: &[f64]) -> [f64; 12] {
    let mut out = [0.0; 12];
    let Some(contact) = &eq.model.contact else {
        return out;
    };
    let n = eq.nq();
    let mut mbw = eq.multibody.workspace::<f64>();
    eq.multibody.set_state(&mut mbw, &x[..n], &x[n..2 * n]);
    let mut moment = [[0.0f64; 2]; 2]; // Σ x·Fy, Σ z·Fy per side
    for (k, sp) in contact.spheres.iter().enumerate() {
        let f = ws.sphere_force[k];
        let side = if eq.model.bodies[sp.body].name.ends_with("_l") {
            1
        } else {
            0
        };
        let p = eq
            .multibody
            .model_point_position(&mbw, sp.body, sp.location);
        for d in 0..3 {
            out[6 * side + d] += f[d];
        }
        moment[side][0] += p[0] * f[1];
        moment[side][1] += p[2] * f[1];
    }
    for side in 0..2 {
        let fy = out[6 * side + 1];
        if fy > 0.0 {
            out[6 * side + 3] = moment[side][0] / fy;
            out[6 * side + 5] = moment[side][1] / fy;
        }
    }
    out
}

/// COM position and velocity at state x.
fn com_at(eq: &StateEquation, x: &[f64]) -> ([f64; 3], [f64; 3]) {
    let n = eq.nq();
    let mut w = eq.multibody.workspace::<f64>();
    eq.multibody.set_state(&mut w, &x[..n], &x[n..2 * n]);
    (eq.multibody.com_position(&w), eq.multibody.com_velocity(&w))
}

/// Lift-off time, COM velocity and height, and the apex: the highest COM
/// seen, or the ballistic rise from lift-off (closed form in flight).
fn liftoff_and_apex(
    eq: &StateEquation,
    liftoff: &Option<(f64, Vec<f64>)>,
    seen: f64,
) -> (Option<f64>, Option<f64>, Option<f64>, f64) {
    let Some((t, xl)) = liftoff else {
        return (None, None, None, seen);
    };
    let (c, v) = com_at(eq, xl);
    let g = eq.model.gravity[1].abs();
    let rise = v[1].max(0.0) * v[1].max(0.0) / (2.0 * g);
    (Some(*t), Some(v[1]), Some(c[1]), seen.max(c[1] + rise))
}

/// Options of a Rust-native forward simulation.
#[derive(Debug, Clone, Copy)]
pub struct SimulateOptions {
    pub integrator: Dopri5Options,
    /// Stop here if the jump has not reached its apex (s).
    pub t_max: f64,
}

impl Default for SimulateOptions {
    fn default() -> Self {
        SimulateOptions {
            integrator: Dopri5Options::default(),
            t_max: 2.0,
        }
    }
}

/// Integrate a jump with the Rust-native Dormand-Prince 5(4) from `x0`.
pub fn simulate_rust<L: ForceLaws<f64>, E: ExcitationSource>(
    eq: &StateEquation,
    laws: &L,
    exc: &E,
    x0: &[f64],
    standing_com_height: f64,
    opts: SimulateOptions,
) -> Result<(JumpSummary, Trajectory), Box<SimulationFailure>> {
    let start = std::time::Instant::now();
    let nm = eq.nm();
    let mut sys = Rhs {
        eq,
        laws,
        exc,
        ws: eq.workspace(),
        u: vec![0.0; nm],
    };
    let mut traj = Trajectory::default();
    let fail = |t: f64, x: &[f64], cause: String, traj: Trajectory| {
        Box::new(SimulationFailure {
            t,
            state: x.to_vec(),
            cause,
            trajectory: traj,
        })
    };
    let mut ig = match Dopri5::new(&mut sys, 0.0, x0, opts.integrator) {
        Ok(ig) => ig,
        Err(e) => return Err(fail(0.0, x0, e.to_string(), traj)),
    };
    let weight = eq.model.total_mass() * (eq.model.gravity[1].abs());
    let record = |traj: &mut Trajectory,
                  sys: &mut Rhs<'_, L, E>,
                  t: f64,
                  x: &[f64]|
     -> Result<f64, String> {
        let mut dx = vec![0.0; x.len()];
        sys.rhs(t, x, &mut dx)?;
        let g = grf_of(sys.eq, &sys.ws, x);
        traj.time.push(t);
        traj.states.push(x.to_vec());
        traj.controls.push(sys.u.clone());
        traj.grf.push(g);
        Ok(g[1] + g[7])
    };
    let mut peak_fy = match record(&mut traj, &mut sys, 0.0, x0) {
        Ok(f) => f,
        Err(e) => return Err(fail(0.0, x0, e, traj)),
    };
    let mut in_contact = peak_fy > 0.0;
    let mut liftoff: Option<(f64, Vec<f64>)> = None;
    let com = |x: &[f64]| com_at(eq, x);
    let mut apex = f64::NEG_INFINITY;
    loop {
        let t = match ig.step(&mut sys, opts.t_max) {
            Ok(t) => t,
            Err(e) => {
                let (t, x) = (ig.t(), ig.x().to_vec());
                let cause = match e {
                    IntegrationError::Rhs { reason, .. } => reason,
                    other => other.to_string(),
                };
                return Err(fail(t, &x, cause, traj));
            }
        };
        let x = ig.x().to_vec();
        let fy = match record(&mut traj, &mut sys, t, &x) {
            Ok(f) => f,
            Err(e) => return Err(fail(t, &x, e, traj)),
        };
        peak_fy = peak_fy.max(fy);
        if fy > 0.0 {
            in_contact = true;
        }
        if in_contact && liftoff.is_none() && fy <= 0.0 {
            // Bisect on the dense output for the last instant with contact.
            let (mut a, mut b) = (ig.t_prev(), t);
            let mut xm = vec![0.0; x.len()];
            let mut dx = vec![0.0; x.len()];
            for _ in 0..40 {
                let m = 0.5 * (a + b);
                ig.dense(m, &mut xm);
                if sys.rhs(m, &xm, &mut dx).is_err() {
                    break;
                }
                let g = grf_of(eq, &sys.ws, &xm);
                if g[1] + g[7] > 0.0 {
                    a = m;
                } else {
                    b = m;
                }
            }
            ig.dense(b, &mut xm);
            liftoff = Some((b, xm));
        }
        let (c, v) = com(&x);
        if liftoff.is_some() {
            apex = apex.max(c[1]);
            if v[1] <= 0.0 || fy > 0.0 {
                break;
            }
        }
        if t >= opts.t_max {
            apex = apex.max(c[1]);
            break;
        }
    }
    let (lt, lv, lh, apex) = liftoff_and_apex(eq, &liftoff, apex);
    let summary = JumpSummary {
        jump_height_m: apex - standing_com_height,
        liftoff_time_s: lt,
        liftoff_com_velocity_mps: lv,
        liftoff_com_height_m: lh,
        peak_vertical_grf_bw: peak_fy / weight,
        apex_com_height_m: apex,
        standing_com_height_m: standing_com_height,
        final_time_s: ig.t(),
        steps: ig.stats.steps,
        rejected_steps: ig.stats.rejected_steps,
        steps_over_tolerance: Some(ig.stats.steps_over_tolerance),
        f_evals: ig.stats.f_evals,
        wall_time_s: start.elapsed().as_secs_f64(),
        integrator: "Dormand-Prince 5(4) (Rust-native)".into(),
        accuracy: opts.integrator.accuracy,
    };
    Ok((summary, traj))
}

/// The files [`write_trajectory`] writes for `name`: states, controls,
/// ground forces.
pub fn trajectory_files(name: &str) -> [String; 3] {
    ["_states.sto", "_controls.sto", "_grf.mot"].map(|s| format!("{name}{s}"))
}

/// Write states and controls (.sto, OpenSim 4 names, every state and
/// excitation of the whole model: both legs, see
/// [`StateEquation::model_state_columns`]) and ground reaction forces
/// (.mot) of a trajectory into `dir` with file prefix `name`.
pub fn write_trajectory(
    eq: &StateEquation,
    traj: &Trajectory,
    dir: &Path,
    name: &str,
) -> Result<Vec<std::path::PathBuf>, crate::io::StoError> {
    let mut states = StoTable {
        name: None,
        ..Default::default()
    };
    states.metadata.insert("inDegrees".into(), "no".into());
    (states.labels, states.rows) = model_columns(&eq.model_state_columns(), &traj.states);
    states.time = traj.time.clone();
    let mut controls = StoTable::default();
    controls.metadata.insert("inDegrees".into(), "no".into());
    (controls.labels, controls.rows) = model_columns(&eq.model_control_columns(), &traj.controls);
    controls.time = traj.time.clone();
    let grf = grf_table(&format!("{name}_grf"), &traj.time, &traj.grf);
    let paths = trajectory_files(name).map(|f| dir.join(f));
    states.write_sto(&paths[0])?;
    controls.write_sto(&paths[1])?;
    grf.write_mot(&paths[2])?;
    Ok(paths.to_vec())
}

/// The labels and rows of a table of the whole model's `columns` (as
/// [`StateEquation::model_state_columns`] gives them) from the system's
/// `rows` (NaN where a row is too short).
pub fn model_columns(
    columns: &[(String, usize)],
    rows: &[Vec<f64>],
) -> (Vec<String>, Vec<Vec<f64>>) {
    let labels = columns.iter().map(|(l, _)| l.clone()).collect();
    let rows = rows
        .iter()
        .map(|r| {
            columns
                .iter()
                .map(|&(_, k)| r.get(k).copied().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    (labels, rows)
}

/// Ground reaction forces per foot as an OpenSim ExternalLoads table
/// (`ground_force_{r,l}_{vx,vy,vz,px,py,pz}`), rows as [`grf_of`] returns.
pub fn grf_table(name: &str, time: &[f64], grf: &[[f64; 12]]) -> StoTable {
    let mut t = StoTable {
        name: Some(name.to_string()),
        ..Default::default()
    };
    for side in ["r", "l"] {
        for l in ["vx", "vy", "vz", "px", "py", "pz"] {
            t.labels.push(format!("ground_force_{side}_{l}"));
        }
    }
    t.time = time.to_vec();
    t.rows = grf.iter().map(|g| g.to_vec()).collect();
    t
}

/// Integrate a jump with one of Simbody's integrators (the Simbody backend
/// of the state equation), recording every `report_interval` seconds.
/// Lift-off is located to within the report interval by bisection on a
/// re-integration from the last report before it.
#[allow(clippy::too_many_arguments)]
pub fn simulate_simbody<E: ExcitationSource + Clone + Send + 'static>(
    eq: &std::sync::Arc<StateEquation>,
    laws: &std::sync::Arc<crate::laws::OpenSimLaws>,
    exc: &E,
    x0: &[f64],
    standing_com_height: f64,
    integrator: crate::simbody::SimbodyIntegrator,
    accuracy: f64,
    t_max: f64,
    report_interval: f64,
) -> Result<(JumpSummary, Trajectory), Box<SimulationFailure>> {
    use crate::ode::{Excitation, SimbodyStateEquation};
    let start = std::time::Instant::now();
    let n = eq.nq();
    let nm = eq.nm();
    let mut traj = Trajectory::default();
    let fail = |t: f64, x: &[f64], cause: String, traj: Trajectory| {
        Box::new(SimulationFailure {
            t,
            state: x.to_vec(),
            cause,
            trajectory: traj,
        })
    };
    let mut sb = match SimbodyStateEquation::new(eq.clone(), laws.clone()) {
        Ok(s) => s,
        Err(e) => return Err(fail(0.0, x0, e.to_string(), traj)),
    };
    let e2 = exc.clone();
    sb.set_excitation(Excitation::OfTime(Box::new(move |t, u| {
        e2.at(t, u);
        for v in u.iter_mut() {
            *v = v.clamp(crate::laws::MIN_ACTIVATION, 1.0);
        }
    })));
    // Ground forces at a state, from the Rust-native evaluation of the same
    // equation (checked against Simbody by `leap crosscheck`).
    let mut ws = eq.workspace::<f64>();
    let mut u = vec![0.0; nm];
    let mut dx = vec![0.0; eq.nx()];
    let mut grf_at = |t: f64, x: &[f64], u: &mut Vec<f64>| -> Result<[f64; 12], String> {
        exc.at(t, u);
        for v in u.iter_mut() {
            *v = v.clamp(crate::laws::MIN_ACTIVATION, 1.0);
        }
        eq.rhs(&**laws, &mut ws, x, u, &mut dx)
            .map_err(|e| e.to_string())?;
        Ok(grf_of(eq, &ws, x))
    };
    // Simbody aborts the process on an accuracy ≥ 1; a tiny one or a tiny
    // report interval never ends.
    let checked = check_integrator_accuracy(
        accuracy,
        &IntegratorChoice::Simbody(integrator),
        Some(t_max),
    )
    .map_err(|r| format!("accuracy: {r}"))
    .and_then(|()| {
        check_report_interval(report_interval, t_max).map_err(|r| format!("report_interval: {r}"))
    });
    if let Err(cause) = checked {
        return Err(fail(0.0, x0, cause, traj));
    }
    let step_cap = match integrator {
        crate::simbody::SimbodyIntegrator::ExplicitEuler => 0,
        _ => MAX_INTEGRATOR_STEPS,
    };
    let start_at = |sb: &mut SimbodyStateEquation, t: f64, x: &[f64]| -> Result<(), String> {
        sb.set_state(t, x).map_err(|e| e.to_string())?;
        sb.simbody
            .set_applied_forces(&vec![0.0; n], &[])
            .map_err(|e| e.to_string())?;
        sb.simbody
            .integration_start(integrator, accuracy, 1e-8, 1.0, step_cap)
            .map_err(|e| e.to_string())
    };
    if let Err(e) = start_at(&mut sb, 0.0, x0) {
        return Err(fail(0.0, x0, e, traj));
    }
    let weight = eq.model.total_mass() * eq.model.gravity[1].abs();
    let mut x = x0.to_vec();
    let mut t = 0.0;
    let g0 = match grf_at(0.0, &x, &mut u) {
        Ok(g) => g,
        Err(e) => return Err(fail(0.0, &x, e, traj)),
    };
    traj.time.push(0.0);
    traj.states.push(x.clone());
    traj.controls.push(u.clone());
    traj.grf.push(g0);
    let mut peak_fy = g0[1] + g0[7];
    let mut in_contact = peak_fy > 0.0;
    let mut liftoff: Option<(f64, Vec<f64>)> = None;
    let mut stats = crate::simbody::IntegratorStats::default();
    let mut extra = crate::simbody::IntegratorStats::default();
    let com = |x: &[f64]| com_at(eq, x);
    let mut apex = f64::NEG_INFINITY;
    while t < t_max {
        let t_next = (t + report_interval).min(t_max);
        let x_prev = x.clone();
        let t_prev = t;
        match sb.simbody.integration_step_to(t_next) {
            Ok(s) => stats = s,
            Err(e) => return Err(fail(t, &x, e.to_string(), traj)),
        }
        t = match sb.state(&mut x) {
            Ok(t) => t,
            Err(e) => return Err(fail(t, &x, e.to_string(), traj)),
        };
        let g = match grf_at(t, &x, &mut u) {
            Ok(g) => g,
            Err(e) => return Err(fail(t, &x, e, traj)),
        };
        traj.time.push(t);
        traj.states.push(x.clone());
        traj.controls.push(u.clone());
        traj.grf.push(g);
        let fy = g[1] + g[7];
        peak_fy = peak_fy.max(fy);
        if fy > 0.0 {
            in_contact = true;
        }
        if in_contact && liftoff.is_none() && fy <= 0.0 {
            // Bisection by re-integrating from the last report.
            let (mut a, mut b) = (t_prev, t);
            let mut xb = x.clone();
            let mut xm = x.clone();
            for _ in 0..20 {
                let m = 0.5 * (a + b);
                if start_at(&mut sb, t_prev, &x_prev).is_err() {
                    break;
                }
                match sb.simbody.integration_step_to(m) {
                    Ok(s) => {
                        extra.steps_taken += s.steps_taken;
                        extra.steps_attempted += s.steps_attempted;
                        extra.realizations += s.realizations;
                    }
                    Err(_) => break,
                }
                if sb.state(&mut xm).is_err() {
                    break;
                }
                match grf_at(m, &xm, &mut u) {
                    Ok(gm) if gm[1] + gm[7] > 0.0 => a = m,
                    Ok(_) => {
                        b = m;
                        xb.copy_from_slice(&xm);
                    }
                    Err(_) => break,
                }
            }
            liftoff = Some((b, xb));
            // Continue from the reported state.
            let _ = extra.final_time;
            if let Err(e) = start_at(&mut sb, t, &x) {
                return Err(fail(t, &x, e, traj));
            }
            extra.steps_taken += stats.steps_taken;
            extra.steps_attempted += stats.steps_attempted;
            extra.realizations += stats.realizations;
            extra.error_test_failures += stats.error_test_failures;
            stats = crate::simbody::IntegratorStats::default();
        }
        let (c, v) = com(&x);
        if liftoff.is_some() {
            apex = apex.max(c[1]);
            if v[1] <= 0.0 || fy > 0.0 {
                break;
            }
        }
        if t >= t_max {
            apex = apex.max(c[1]);
        }
    }
    let (lt, lv, lh, apex) = liftoff_and_apex(eq, &liftoff, apex);
    let steps = (stats.steps_taken + extra.steps_taken) as usize;
    let attempted = (stats.steps_attempted + extra.steps_attempted) as usize;
    let summary = JumpSummary {
        jump_height_m: apex - standing_com_height,
        liftoff_time_s: lt,
        liftoff_com_velocity_mps: lv,
        liftoff_com_height_m: lh,
        peak_vertical_grf_bw: peak_fy / weight,
        apex_com_height_m: apex,
        standing_com_height_m: standing_com_height,
        final_time_s: t,
        steps,
        rejected_steps: attempted.saturating_sub(steps),
        steps_over_tolerance: None,
        f_evals: (stats.realizations + extra.realizations) as usize,
        wall_time_s: start.elapsed().as_secs_f64(),
        integrator: format!("{integrator:?} (Simbody)"),
        accuracy,
    };
    Ok((summary, traj))
}

/// The smallest relative accuracy leap passes to an error-controlled
/// integrator: below it the error control works on rounding error and the
/// steps shrink without end (1e-300 never finished; 1e-12 takes the
/// RungeKuttaMerson jump 28 000 steps, 9 s).
pub const MIN_ACCURACY: f64 = 1e-12;
/// Steps an error-controlled Simbody integration may attempt (from its
/// start, and again from lift-off), so that a model too stiff for the
/// accuracy (a contact transition velocity of 1e-6 m/s ran for minutes)
/// ends with an error instead of running on (14 s for that model): five
/// times OpenSim's `maximum_number_of_integrator_steps` (20 000), since at
/// [`MIN_ACCURACY`] RungeKuttaMerson needs 28 000 for the jump and
/// RungeKuttaFeldberg 16 000 (RungeKutta3 has its own floor,
/// [`MIN_ACCURACY_RK3`]). ExplicitEuler's fixed steps are bounded by
/// [`MAX_FIXED_STEPS`] instead.
pub const MAX_INTEGRATOR_STEPS: i32 = 100_000;
/// The smallest fixed step of ExplicitEuler (s): about 70 µs a step on the
/// jumper, so a million steps to a second of motion take over a minute.
pub const MIN_FIXED_STEP: f64 = 1e-6;
/// The largest fixed step of ExplicitEuler (s): the bang-bang jump is
/// 25.7 cm at 1e-5 and 1e-4 s, fails at 0.344 s with 2e-4 s and lands at
/// −13.8 cm with 5e-4 s and more (`leap simulate --integrator ExplicitEuler
/// --accuracy A`, 2026-12-06): the contact and the tendons are stiffer than
/// that.
pub const MAX_FIXED_STEP: f64 = 1e-4;
/// The most steps of ExplicitEuler's fixed step to `t_max`.
pub const MAX_FIXED_STEPS: f64 = 1e6;
/// The most rows a Simbody simulation reports (`t_max / report_interval`):
/// each costs about half a millisecond and a kilobyte of output (the
/// default 1e-3 s reports 1000 rows a second).
pub const MAX_REPORTED_ROWS: f64 = 1e5;
/// The latest end of a forward simulation (s).
pub const MAX_T_MAX: f64 = 10.0;
/// The finest relative accuracy of the third-order RungeKutta3.
pub const MIN_ACCURACY_RK3: f64 = 1e-10;
/// The finest relative accuracy of CPodes on the jumper: the bang-bang
/// jump integrates at 1e-5 to 1e-7 (1,408 to 2,884 steps), and from 1e-8 to
/// 1e-12 CPodes' error test fails repeatedly near t = 0.35 s, its step
/// down to 2e-9 s (`leap simulate --integrator CPodes --accuracy A`,
/// 2026-12-07).
pub const MIN_ACCURACY_CPODES: f64 = 1e-7;
/// The coarsest relative accuracy: at 1e-1 the bang-bang jump came out at
/// 16.1 cm against 23.5 cm at 1e-2 to 1e-4 (an earlier model's; today's
/// jumps 25.7 cm at 1e-2 to 1e-4).
pub const MAX_ACCURACY: f64 = 1e-2;
/// The longest report interval (s): the peak ground force is read at the
/// reports (bang-bang jump: 2.533 BW at 1 ms, 2.529 at 10 ms, 2.25 at
/// 100 ms, and at 300 ms the 1.0 BW of the squat), and a landing inside the
/// interval after lift-off would hide the flight.
pub const MAX_REPORT_INTERVAL: f64 = 1e-2;

/// Why `accuracy` is unusable for `integrator`, if it is: a relative error
/// tolerance in [[`MIN_ACCURACY`], [`MAX_ACCURACY`]] (Simbody asserts
/// accuracy < 1 and aborts the process otherwise), or for ExplicitEuler a fixed step of at
/// least [`MIN_FIXED_STEP`] s, at most [`MAX_FIXED_STEP`] s and, where the end time `t_max` is known, at
/// most [`MAX_FIXED_STEPS`] steps to it.
pub fn check_integrator_accuracy(
    accuracy: f64,
    integrator: &IntegratorChoice,
    t_max: Option<f64>,
) -> Result<(), String> {
    if !(accuracy.is_finite() && accuracy > 0.0) {
        return Err(format!(
            "must be positive, got {}",
            crate::io::readable(accuracy)
        ));
    }
    if let IntegratorChoice::Simbody(crate::simbody::SimbodyIntegrator::ExplicitEuler) = integrator
    {
        if accuracy < MIN_FIXED_STEP {
            return Err(format!(
                "ExplicitEuler's fixed step must be at least {MIN_FIXED_STEP:e} s, got {}: a million steps to each second of motion already take over a minute",
                crate::io::readable(accuracy)
            ));
        }
        if accuracy > MAX_FIXED_STEP {
            return Err(format!(
                "ExplicitEuler's fixed step must be at most {MAX_FIXED_STEP:e} s, got {}: the contact and the tendons are stiffer (with a step of 2e-4 s the bang-bang jump fails at 0.344 s, with 5e-4 s it lands at -13.8 cm)",
                crate::io::readable(accuracy)
            ));
        }
        if let Some(t_max) = t_max.filter(|t| t / accuracy > MAX_FIXED_STEPS) {
            return Err(format!(
                "ExplicitEuler's fixed step of {accuracy:e} s takes {:.1e} steps to t_max = {t_max} s; at most {MAX_FIXED_STEPS:e}",
                t_max / accuracy
            ));
        }
        return Ok(());
    }
    // Integrators with a floor of their own: (name, floor, why).
    use crate::simbody::SimbodyIntegrator as S;
    let own_floor = match integrator {
        IntegratorChoice::Simbody(S::RungeKutta3) => Some((
            "RungeKutta3",
            MIN_ACCURACY_RK3,
            format!("a third-order method, at 1e-12 it needs more than {MAX_INTEGRATOR_STEPS} steps to lift-off (at 1e-10 about 68,000 to the apex)"),
        )),
        IntegratorChoice::Simbody(S::CPodes) => Some((
            "CPodes",
            MIN_ACCURACY_CPODES,
            format!("on leap's jumper (models/jumper.json) its error test fails repeatedly from 1e-8 on, near t = 0.35 s of the bang-bang jump with steps down to 2e-9 s; RungeKuttaMerson (OpenSim's default) takes accuracies to {MIN_ACCURACY:e}"),
        )),
        _ => None,
    };
    if let Some((name, floor, why)) = own_floor.filter(|(_, f, _)| accuracy < *f) {
        return Err(format!(
            "{name} needs at least {floor:e}, got {}: {why}",
            crate::io::readable(accuracy)
        ));
    }
    if !(MIN_ACCURACY..=MAX_ACCURACY).contains(&accuracy) {
        return Err(format!(
            "must be a relative error tolerance in [{MIN_ACCURACY:e}, {MAX_ACCURACY:e}], got {}: below {MIN_ACCURACY:e} the error control works on rounding error and the steps shrink without end; above {MAX_ACCURACY:e} the jump is off by centimetres (bang-bang at 1e-1, on an earlier model: 16.1 cm instead of 23.5)",
            crate::io::readable(accuracy)
        ));
    }
    Ok(())
}

/// Why `report_interval` is too long or reports too many rows to `t_max`,
/// if it does.
fn check_report_interval(report_interval: f64, t_max: f64) -> Result<(), String> {
    if !(report_interval.is_finite() && report_interval > 0.0) {
        return Err(format!(
            "must be positive, got {}",
            crate::io::readable(report_interval)
        ));
    }
    if report_interval > MAX_REPORT_INTERVAL {
        return Err(format!(
            "at most {MAX_REPORT_INTERVAL} s, got {}: the peak ground force is read at the reports, and a landing within one report of lift-off would hide the flight",
            crate::io::readable(report_interval)
        ));
    }
    let rows = t_max / report_interval;
    if rows > MAX_REPORTED_ROWS {
        return Err(format!(
            "{report_interval:e} s over t_max = {t_max} s would report {rows:.1e} rows; at most {MAX_REPORTED_ROWS:e} (report_interval ≥ t_max / {MAX_REPORTED_ROWS:e})"
        ));
    }
    Ok(())
}

/// Whole-body COM height of the model standing (its `standing` pose, or
/// the coordinates' defaults).
pub fn standing_com_height(eq: &StateEquation) -> f64 {
    let pose = eq.model.poses.get("standing").cloned().unwrap_or_else(|| {
        eq.model
            .coordinates
            .iter()
            .map(|c| c.default_value)
            .collect()
    });
    let mut w = eq.multibody.workspace::<f64>();
    let q = eq.system.q_from_model(&pose);
    eq.multibody.set_state(&mut w, &q, &vec![0.0; q.len()]);
    eq.multibody.com_position(&w)[1]
}

/// A forward-simulation study (JSON). Paths written in it are relative to
/// the study file; those it omits take `leap solve`'s defaults
/// ([`crate::study::default_model`],
/// [`crate::study::DEFAULT_OUTPUT_DIRECTORY`] in the working directory).
#[derive(Debug, Clone, serde::Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SimulateStudy {
    #[serde(default)]
    pub model: Option<String>,
    /// `RungeKuttaMerson` (default, as OpenSim), `RungeKuttaFeldberg`,
    /// `RungeKutta3`, `CPodes`, `ExplicitEuler` (Simbody) or `DormandPrince`
    /// (Rust-native).
    #[serde(default = "default_integrator")]
    pub integrator: String,
    /// Integrator accuracy in [1e-12, 1e-2] (for ExplicitEuler: the fixed
    /// step, s, from 1e-6 to 1e-4 and at most 1e6 steps to `t_max`).
    #[serde(default = "default_accuracy")]
    pub accuracy: f64,
    /// Stop here if the apex is not reached (s).
    #[serde(default = "default_t_max")]
    pub t_max: f64,
    /// Results directory.
    #[serde(default)]
    pub out: Option<String>,
    /// Excitations from an OpenSim controls or Moco solution file; else the
    /// bang-bang pattern.
    #[serde(default)]
    pub controls: Option<String>,
    #[serde(default)]
    pub bang_bang: Option<BangBangSpec>,
    /// Report interval of the Simbody integrators (s), at least
    /// `t_max / 1e5` ([`MAX_REPORTED_ROWS`]) and at most 10 ms
    /// ([`MAX_REPORT_INTERVAL`]).
    #[serde(default = "default_report")]
    pub report_interval: f64,
}

/// The bang-bang pattern: muscles in `on` (default: the extensors at the
/// squat) are fully on between `on_time` (≥ 0) and `off_time` (after it),
/// the others off.
#[derive(Debug, Clone, serde::Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BangBangSpec {
    #[serde(default)]
    pub on: Option<Vec<String>>,
    #[serde(default)]
    pub on_time: f64,
    #[serde(default = "default_off")]
    pub off_time: f64,
}

fn default_integrator() -> String {
    "RungeKuttaMerson".into()
}
fn default_accuracy() -> f64 {
    1e-5
}
fn default_t_max() -> f64 {
    1.0
}
fn default_report() -> f64 {
    1e-3
}
fn default_off() -> f64 {
    f64::INFINITY
}

impl crate::study::StudyKind for SimulateStudy {
    const KIND: &'static str = "simulate";
    fn fields() -> serde_json::Value {
        serde_json::from_str::<SimulateStudy>(r#"{"bang_bang": {}}"#)
            .ok()
            .and_then(|s| serde_json::to_value(s).ok())
            .unwrap_or_default()
    }
}

impl SimulateStudy {
    /// Read a study file: one JSON object, unknown fields refused. Values
    /// are checked by [`SimulateStudy::check`] once command-line options
    /// have overridden them.
    pub fn from_file(path: &Path) -> Result<Self, StudyError> {
        let study: Self = crate::study::read_study(path)?;
        study.one_source_of_excitations(&path.display().to_string())
    }

    /// Parse study JSON; `origin` names it in errors.
    pub fn from_json_str(text: &str, origin: &str) -> Result<Self, StudyError> {
        let study: Self = crate::study::parse_study(text, origin)?;
        study.one_source_of_excitations(origin)
    }

    /// One source of excitations per file (`--controls` on the command line
    /// still replaces the file's bang-bang pattern).
    fn one_source_of_excitations(self, origin: &str) -> Result<Self, StudyError> {
        if self.controls.is_some() && self.bang_bang.is_some() {
            return Err(StudyError::Field {
                origin: origin.into(),
                field: "bang_bang".into(),
                reason: "given together with 'controls': the excitations come from one of them"
                    .into(),
            });
        }
        Ok(self)
    }

    /// Check every value and return the integrator; `origin` names the
    /// study file (or "command line") in errors.
    pub fn check(&self, origin: &str) -> Result<IntegratorChoice, StudyError> {
        let err = |field: &str, reason: String| StudyError::Field {
            origin: origin.into(),
            field: field.into(),
            reason,
        };
        let choice = parse_integrator(&self.integrator).map_err(|r| err("integrator", r))?;
        for (field, path, what) in [
            ("model", &self.model, "a model file"),
            ("controls", &self.controls, "a controls file"),
            ("out", &self.out, "a directory"),
        ] {
            if path.as_deref().is_some_and(|p| p.trim().is_empty()) {
                return Err(err(field, format!("empty: name {what}")));
            }
            if let Some(why) = path.as_deref().and_then(crate::io::path_text_problem) {
                return Err(err(field, why));
            }
        }
        if !(self.t_max.is_finite() && self.t_max > 0.0 && self.t_max <= MAX_T_MAX) {
            return Err(err(
                "t_max",
                format!(
                    "must be a time in (0, {MAX_T_MAX}] s (a jump lifts off and reaches its apex within about a second), got {}",
                    crate::io::readable(self.t_max)
                ),
            ));
        }
        check_integrator_accuracy(self.accuracy, &choice, Some(self.t_max))
            .map_err(|r| err("accuracy", r))?;
        check_report_interval(self.report_interval, self.t_max)
            .map_err(|r| err("report_interval", r))?;
        if let Some(bb) = &self.bang_bang {
            if !(bb.on_time.is_finite() && bb.on_time >= 0.0) {
                return Err(err(
                    "bang_bang.on_time",
                    format!(
                        "must be a time ≥ 0 s (the simulation starts at 0), got {}",
                        bb.on_time
                    ),
                ));
            }
            if bb.on_time >= self.t_max {
                return Err(err(
                    "bang_bang.on_time",
                    format!(
                        "{} s is not before t_max = {} s: no muscle would switch on",
                        crate::io::readable(bb.on_time),
                        crate::io::readable(self.t_max)
                    ),
                ));
            }
            if bb.on.as_ref().is_some_and(|on| on.is_empty()) {
                return Err(err(
                    "bang_bang.on",
                    "is empty: no muscle would switch on (name the muscles to switch on, or leave 'on' out for the extensors at the squat)".into(),
                ));
            }
            if bb.off_time.is_nan() || bb.off_time <= bb.on_time {
                return Err(err(
                    "bang_bang.off_time",
                    format!(
                        "must be after on_time ({} s), got {}",
                        bb.on_time, bb.off_time
                    ),
                ));
            }
        }
        Ok(choice)
    }
}

impl Default for SimulateStudy {
    fn default() -> Self {
        SimulateStudy {
            model: None,
            integrator: default_integrator(),
            accuracy: default_accuracy(),
            t_max: default_t_max(),
            out: None,
            controls: None,
            bang_bang: None,
            report_interval: default_report(),
        }
    }
}

/// Which integrator a name means.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IntegratorChoice {
    Simbody(crate::simbody::SimbodyIntegrator),
    DormandPrince,
}

/// Parse an integrator name (OpenSim's names).
pub fn parse_integrator(name: &str) -> Result<IntegratorChoice, String> {
    use crate::simbody::SimbodyIntegrator as S;
    Ok(match name {
        "RungeKuttaMerson" => IntegratorChoice::Simbody(S::RungeKuttaMerson),
        "RungeKuttaFeldberg" => IntegratorChoice::Simbody(S::RungeKuttaFeldberg),
        "RungeKutta3" => IntegratorChoice::Simbody(S::RungeKutta3),
        "CPodes" => IntegratorChoice::Simbody(S::CPodes),
        "ExplicitEuler" => IntegratorChoice::Simbody(S::ExplicitEuler),
        "DormandPrince" | "DormandPrince54" => IntegratorChoice::DormandPrince,
        other => {
            return Err(format!(
                "unknown integrator '{other}': use RungeKuttaMerson, RungeKuttaFeldberg, RungeKutta3, CPodes, ExplicitEuler or DormandPrince"
            ))
        }
    })
}

/// Excitations of a study: a controls file or the bang-bang pattern.
#[derive(Clone)]
pub enum StudyExcitation {
    Controls(crate::io::Controls),
    BangBang(BangBang),
}

impl ExcitationSource for StudyExcitation {
    fn at(&self, t: f64, u: &mut [f64]) {
        match self {
            StudyExcitation::Controls(c) => c.at(t, u),
            StudyExcitation::BangBang(b) => b.at(t, u),
        }
    }
}
