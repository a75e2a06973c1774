//! `leap analyze`: what drives and what limits a jump, from its states over
//! time (a solution's `_solution.sto` or, at finer resolution, its forward
//! check's `_forward_states.sto`).
//!
//! Over the push-off (t = 0 to lift-off, where the vertical ground force
//! falls below 1% of body weight) each muscle-tendon unit is reported with
//! its peak activation, the share of the push-off it spends at activation
//! ≥ 0.95 (saturated: more force needs more strength, not more drive), its
//! peak tendon force over its maximum isometric force, its peak fibre
//! shortening speed over its maximum (v_max · l_opt; near 1 the
//! force-velocity curve leaves it no force), and its work
//! W = ∫ F_T · (−dL_MT/dt) dt, positive and net, counted for both sides
//! where the symmetric system applies one muscle's tension twice.
//!
//! The energy budget of the window: the change of the system's kinetic plus
//! gravitational potential energy equals the work of the muscles, of the
//! passive joint torques and of the ground contact; the contact's share is
//! what the first leaves after the other two (with the integration error of
//! the trapezoidal rule on the file's rows).

use crate::io::StoError;
use crate::laws::OpenSimLaws;
use crate::ode::{ForceLaws, MuscleRates, StateEquation};
use serde::Serialize;
use std::path::Path;

/// Activation at or above which a muscle counts as saturated.
pub const SATURATED_ACTIVATION: f64 = 0.95;

/// Peak shortening speed over v_max · l_opt beyond which `leap analyze`
/// warns that the states do not fit the model: the force–velocity curve
/// ends at v_max (the default jump's vasti reach 1.00, Thelen's linear
/// extension below zero force), and a DeGroote solution read with the
/// default Thelen model gave 7.3.
pub const IMPOSSIBLE_SHORTENING_RATIO: f64 = 1.5;

/// One muscle-tendon unit over the window.
#[derive(Debug, Clone, Serialize)]
pub struct MuscleWork {
    pub name: String,
    pub max_isometric_force_n: f64,
    pub peak_activation: f64,
    /// Share of the window with activation ≥ [`SATURATED_ACTIVATION`].
    pub saturated_fraction: f64,
    /// Peak tendon force / maximum isometric force.
    pub peak_force_ratio: f64,
    /// Peak fibre shortening speed / (v_max · l_opt), over the rows where
    /// the muscle has a fibre velocity; NaN (null in JSON) where none has.
    pub peak_shortening_ratio: f64,
    /// ∫ max(0, P) dt and ∫ P dt with P = F_T · (−dL_MT/dt), both sides (J).
    pub positive_work_j: f64,
    pub net_work_j: f64,
}

/// Work and energy over the window (J).
#[derive(Debug, Clone, Serialize)]
pub struct EnergyBudget {
    pub start_s: f64,
    pub end_s: f64,
    /// Kinetic plus gravitational potential energy, end minus start.
    pub energy_change_j: f64,
    pub muscle_work_j: f64,
    pub passive_torque_work_j: f64,
    /// What the energy change leaves after the muscles and passive
    /// torques: the ground contact's work plus the integration error.
    pub contact_work_j: f64,
}

/// The relative difference between impulse and momentum change above which
/// the analysis warns: a forward simulation's states agree to 1e-4 and a
/// 28-interval solution's nodes to about 6% (their ground force integrated
/// by the trapezoid over 11 ms).
pub const NEWTON_MISMATCH_WARNING: f64 = 0.25;

/// The analysis of a jump's push-off (or of a given window).
#[derive(Debug, Clone, Serialize)]
pub struct JumpAnalysis {
    /// Whether the feet left the ground inside the file (else the window
    /// runs to its end). Not looked for in a given window.
    pub liftoff: bool,
    /// Whether the window was given (`--window`), not the push-off found.
    pub window_given: bool,
    /// Whether each muscle's row stands for both legs' (the symmetric
    /// system), not for one muscle (`--full`).
    pub both_sides: bool,
    pub budget: EnergyBudget,
    /// ∫ (F_y − m g) dt over the window and m · ΔẎ_C: equal by Newton's
    /// second law (N·s).
    pub vertical_impulse_ns: f64,
    pub com_momentum_change_ns: f64,
    /// COM height above standing and vertical velocity at the window's end,
    /// and the jump height they give (height + Ẏ²/2g).
    pub end_com_height_above_standing_m: f64,
    pub end_com_vertical_velocity_mps: f64,
    pub jump_height_m: f64,
    pub body_weight_n: f64,
    pub peak_vertical_grf_bw: f64,
    /// By net work, largest first.
    pub muscles: Vec<MuscleWork>,
    /// What makes the file's states doubtful, each at its first row:
    /// coordinates outside their ranges in the model file, fibres outside
    /// the optimizer's bounds, fibre speeds beyond the model's muscles or
    /// overflowing, a contact sphere sunk past its centre.
    pub warnings: Vec<String>,
}

/// The states of `eq` over time from an OpenSim storage file: its columns
/// named as [`StateEquation::state_names`] (other columns are ignored), in
/// radians whatever the header's `inDegrees` (see [`crate::io::read_states`]);
/// at least 2 rows, time strictly increasing, every value finite.
pub fn read_states(eq: &StateEquation, path: &Path) -> Result<(Vec<f64>, Vec<Vec<f64>>), StoError> {
    let table = crate::io::read_states(eq, path)?;
    // Not one state column (ground forces, controls, pre-4.0 names).
    let columns = eq.model_state_columns();
    if !columns.iter().any(|(l, _)| table.labels.contains(l)) {
        let old = crate::io::pre_4_state_names(eq);
        let renamed = table
            .labels
            .iter()
            .find_map(|l| {
                old.get(l)
                    .map(|path| format!("; its '{l}' is the pre-4.0 name of '{path}'"))
            })
            .unwrap_or_default();
        return Err(StoError::Column {
            file: path.into(),
            column: table.labels.first().cloned().unwrap_or_else(|| "time".into()),
            reason: format!("no column of the file names a state of the model by its OpenSim 4 path (/jointset/<joint>/<coordinate>/value, /forceset/<muscle>/fiber_length, …): `leap analyze` reads a states file, a solve's `_solution.sto` or a simulation's `_forward_states.sto`{renamed}"),
        });
    }
    let missing = if eq.system.symmetric {
        "missing (a states file of this model's symmetric system is needed; `--full` for the full one)"
    } else {
        "missing (a states file of this model's full system, both legs, is needed; without `--full` for the symmetric one)"
    };
    let states = table.finite_columns(path, &eq.state_names(), missing)?;
    Ok((table.time, states))
}

/// [`analyze`] could not evaluate the states, or found no rows to analyse.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    #[error(transparent)]
    Ode(#[from] crate::ode::OdeError),
    /// The state equation failed at the row of this time.
    #[error("row at t = {t} s: {e}", t = crate::io::readable(*.0), e = .1)]
    AtRow(f64, crate::ode::OdeError),
    #[error("no rows between {} s and {} s", crate::io::readable(*.0), crate::io::readable(*.1))]
    EmptyWindow(f64, f64),
    #[error("one row between {} s and {} s (t = {} s): a window needs two rows or more to integrate over", crate::io::readable(*.0), crate::io::readable(*.1), crate::io::readable(*.2))]
    OneRow(f64, f64, f64),
    /// A row whose states give a non-finite quantity; the third field
    /// names its coordinates outside their ranges
    /// ([`crate::eval::outside_range_hint`]).
    #[error("row at t = {t} s: its states give a non-finite {what}{why}", t = crate::io::readable(*.0), what = .1, why = if .2.is_empty() { ": a state of that row lies far outside what the model can do" } else { .2.as_str() })]
    NotFinite(f64, &'static str, String),
    /// A row whose centre of mass lies or moves vertically beyond
    /// [`MAX_COM_MAGNITUDE`] (a height of 1e300 m is finite, and no jump).
    #[error("row at t = {t} s: its states put the {what} at {v}, beyond ±{MAX_COM_MAGNITUDE} (m, m/s): no movement of the model{why}", t = crate::io::readable(*.0), what = .1, v = crate::io::readable(*.2), why = if .3.is_empty() { "" } else { .3.as_str() })]
    FarOutside(f64, &'static str, f64, String),
}

/// The largest centre-of-mass height (m) or vertical speed (m/s) a row
/// may give.
pub const MAX_COM_MAGNITUDE: f64 = 1e3;

/// The contact sphere sunk deepest into the ground at the state in `ws`
/// (as [`StateEquation::rhs`] left it), if it is sunk beyond its radius
/// (its centre below the surface): its name and depth (m). Under a jump's
/// forces the spheres sink millimetres: one of the default model's 32 mm
/// spheres needs about 1.8 kN, 2.5 body weights on that sphere alone, to
/// sink to its centre.
fn sunk_sphere(eq: &StateEquation, ws: &crate::ode::StateWorkspace<f64>) -> Option<(String, f64)> {
    let contact = eq.model.contact.as_ref()?;
    let (k, bottom) = crate::ode::lowest_sphere(&eq.multibody, &ws.mb, contact)?;
    let sp = &contact.spheres[k];
    (-bottom > sp.radius).then(|| (sp.name.clone(), -bottom))
}

/// The warning for a state whose deepest contact sphere is sunk past its
/// centre ([`sunk_sphere`]), if one is.
pub(crate) fn sunk_sphere_warning(
    eq: &StateEquation,
    ws: &crate::ode::StateWorkspace<f64>,
) -> Option<String> {
    let (name, depth) = sunk_sphere(eq, ws)?;
    Some(format!(
        "contact sphere '{name}' lies {:.1} mm deep in the ground, its centre below the surface (a jump's spheres sink millimetres): the ground force there is not one a foot meets (pelvis_ty in another model's convention?)",
        1e3 * depth
    ))
}

/// OpenSim's laws as the analysis reads a row: a DeGrooteFregly2016Muscle
/// whose explicit fibre velocity overflows there gets NaN for it, where
/// [`OpenSimLaws`] refuses the whole row. De Groote's inverted force–velocity curve (a sinh) overflows where
/// the force balance asks the force–velocity multiplier for more than about
/// 230, a tendon force far beyond the fibre's activation and length, as at
/// a collocation solution's nodes, whose force balances midpoint Euler
/// enforces at the interval midpoints only. What the analysis integrates
/// (tendon forces, path speeds, ground and passive forces) needs no fibre
/// velocity. Thelen's non-finite velocities (a fibre whose passive force
/// overflows) are refused as before.
struct RowLaws<'a>(&'a OpenSimLaws);

impl ForceLaws<f64> for RowLaws<'_> {
    fn muscle(
        &self,
        m: usize,
        a: f64,
        lm: f64,
        lmt: f64,
        vmt: f64,
        u: f64,
    ) -> Result<MuscleRates<f64>, String> {
        let r = self.0.raw_muscle_rates(m, a, lm, lmt, vmt, u);
        let degroote = matches!(
            self.0.muscles.get(m),
            Some(crate::laws::MuscleLaw::DeGroote(_))
        );
        if degroote && r.tendon_force.is_finite() && !r.fiber_velocity.is_finite() {
            return Ok(MuscleRates {
                fiber_velocity: f64::NAN,
                ..r
            });
        }
        crate::laws::finite_rates(r, a, lm, lmt)
    }
    fn sphere(&self, k: usize, p: [f64; 3], v: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        self.0.sphere(k, p, v)
    }
    fn ligament(&self, l: usize, q: f64, qd: f64) -> f64 {
        self.0.ligament(l, q, qd)
    }
}

/// Per row: what the analysis integrates.
struct Sample {
    t: f64,
    activation: Vec<f64>,
    tendon_force: Vec<f64>,
    /// −dL_MT/dt (shortening positive).
    shortening_speed: Vec<f64>,
    /// NaN where the muscle has none ([`RowLaws`]).
    fiber_velocity: Vec<f64>,
    fiber_length: Vec<f64>,
    passive_power: f64,
    vertical_grf: f64,
    energy: f64,
    com_height: f64,
    com_vertical_velocity: f64,
}

fn sample(
    eq: &StateEquation,
    laws: &RowLaws,
    ws: &mut crate::ode::StateWorkspace<f64>,
    t: f64,
    x: &[f64],
) -> Result<Sample, AnalysisError> {
    let (n, nm) = (eq.nq(), eq.nm());
    // Excitation = activation: only the activation rate depends on it,
    // which the analysis does not use.
    let u: Vec<f64> = x[2 * n + nm..].to_vec();
    let mut xdot = vec![0.0; eq.nx()];
    eq.rhs(laws, ws, x, &u, &mut xdot)
        .map_err(|e| AnalysisError::AtRow(t, e))?;
    let passive_power = eq
        .model
        .ligaments
        .iter()
        .zip(&ws.ligament_torque)
        .map(|(l, tq)| tq * x[n + eq.system.q_of_model_coordinate[l.coordinate]])
        .sum();
    let com = eq.multibody.com_position(&ws.mb);
    let vcom = eq.multibody.com_velocity(&ws.mb);
    let energy = eq.multibody.energy(&ws.mb);
    let vertical_grf: f64 = ws.sphere_force.iter().map(|f| f[1]).sum();
    // Finite states far outside the model's reach (a speed of 1e300)
    // overflow here: refused, not reported as an infinite jump.
    let power: f64 = ws
        .tendon_force
        .iter()
        .zip(&ws.mtu_speed)
        .map(|(f, v)| f * v)
        .sum();
    for (value, what) in [
        (energy, "kinetic plus potential energy"),
        (com[1], "centre-of-mass height"),
        (vcom[1], "centre-of-mass velocity"),
        (vertical_grf, "ground force"),
        (passive_power, "passive joint torque power"),
        (power, "muscle power"),
    ] {
        if !value.is_finite() {
            return Err(AnalysisError::NotFinite(
                t,
                what,
                crate::eval::outside_range_hint(
                    eq,
                    x,
                    "a file in degrees without `inDegrees=yes` in its header?",
                ),
            ));
        }
    }
    for (value, what) in [
        (com[1], "centre-of-mass height"),
        (vcom[1], "centre-of-mass vertical velocity"),
    ] {
        if value.abs() > MAX_COM_MAGNITUDE {
            return Err(AnalysisError::FarOutside(
                t,
                what,
                value,
                crate::eval::outside_range_hint(
                    eq,
                    x,
                    "a file in degrees without `inDegrees=yes` in its header?",
                ),
            ));
        }
    }
    Ok(Sample {
        t,
        activation: u,
        tendon_force: ws.tendon_force.clone(),
        shortening_speed: ws.mtu_speed.iter().map(|v| -v).collect(),
        fiber_velocity: xdot[2 * n..2 * n + nm].to_vec(),
        fiber_length: x[2 * n..2 * n + nm].to_vec(),
        passive_power,
        vertical_grf,
        energy,
        com_height: com[1],
        com_vertical_velocity: vcom[1],
    })
}

/// Analyse the states `states` at times `time` over `window` (start, end),
/// or over the push-off: from the first row to lift-off.
pub fn analyze(
    eq: &StateEquation,
    laws: &crate::laws::OpenSimLaws,
    time: &[f64],
    states: &[Vec<f64>],
    window: Option<(f64, f64)>,
) -> Result<JumpAnalysis, AnalysisError> {
    let nm = eq.nm();
    let mut ws = eq.workspace::<f64>();
    let weight = eq.model.total_mass() * eq.model.gravity[1].abs();
    // Lift-off where the vertical ground force falls below the jump
    // problem's lift-off level (1% of body weight), as the solve reports it.
    let level = crate::ocp::LiftOff::default().fraction() * weight;
    let (t0, t1) = window.unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
    let mut samples = Vec::new();
    let mut liftoff = false;
    let mut in_contact = false;
    let mut warnings = Vec::new();
    let mut warned = vec![false; eq.nq()];
    let mut warned_fibre = vec![false; eq.nm()];
    let mut warned_sunk = false;
    let row_laws = RowLaws(laws);
    // A window's ends hold the rows a hair beyond them: report times
    // summed step by step (0.2000000000000001) are the rows meant.
    let slack = |t: f64| 1e-9 * (1.0 + t.abs());
    for (t, x) in time.iter().zip(states) {
        if *t < t0 - slack(t0) {
            continue;
        }
        if *t > t1 + slack(t1) {
            break;
        }
        for (k, w) in crate::eval::coordinates_outside_range(eq, x) {
            if !std::mem::replace(&mut warned[k], true) {
                warnings.push(format!(
                    "at t = {} s, its first row outside: {w}",
                    crate::io::readable(*t)
                ));
            }
        }
        for (k, w) in crate::eval::unusual_fibre_lengths(eq, laws, x, false) {
            if !std::mem::replace(&mut warned_fibre[k], true) {
                warnings.push(format!(
                    "at t = {} s, its first such row: {w}",
                    crate::io::readable(*t)
                ));
            }
        }
        let s = sample(eq, &row_laws, &mut ws, *t, x)?;
        if !warned_sunk {
            if let Some(w) = sunk_sphere_warning(eq, &ws) {
                warned_sunk = true;
                warnings.push(format!(
                    "at t = {} s, its first such row: {w}",
                    crate::io::readable(*t),
                ));
            }
        }
        let fy = s.vertical_grf;
        samples.push(s);
        if window.is_none() {
            if fy >= level {
                in_contact = true;
            } else if in_contact {
                liftoff = true;
                break;
            }
        }
    }
    let (first, last) = match (samples.first(), samples.last()) {
        (Some(f), _) if samples.len() == 1 => return Err(AnalysisError::OneRow(t0, t1, f.t)),
        (Some(f), Some(l)) => (f, l),
        _ => return Err(AnalysisError::EmptyWindow(t0, t1)),
    };
    let trapezoid = |f: &dyn Fn(&Sample) -> f64| -> f64 {
        samples
            .windows(2)
            .map(|w| 0.5 * (w[1].t - w[0].t) * (f(&w[0]) + f(&w[1])))
            .sum()
    };
    let duration = last.t - first.t;
    let mut muscles = Vec::with_capacity(nm);
    // Per carried muscle, the peak row-to-row shortening speed over
    // v_max · l_opt; the muscles with rows without a fibre velocity.
    let mut row_to_row = Vec::with_capacity(nm);
    let mut without = Vec::new();
    let mut muscle_work = 0.0;
    for (k, &mi) in eq.muscles.iter().enumerate() {
        let spec = &eq.model.muscles[mi].spec;
        let twice = eq.multiplicity[k];
        let power = |s: &Sample| twice * s.tendon_force[k] * s.shortening_speed[k];
        let net = trapezoid(&power);
        let positive = trapezoid(&|s: &Sample| power(s).max(0.0));
        // Time at saturation: the trapezoidal rule on the indicator.
        let saturated =
            trapezoid(&|s: &Sample| f64::from(u8::from(s.activation[k] >= SATURATED_ACTIVATION)));
        let vmax = spec.max_contraction_velocity * spec.optimal_fiber_length;
        let peak = |f: &dyn Fn(&Sample) -> f64| samples.iter().map(f).fold(f64::MIN, f64::max);
        // Over the rows with a fibre velocity; NaN if none has one.
        let peak_shortening = samples
            .iter()
            .map(|s| -s.fiber_velocity[k])
            .filter(|v| !v.is_nan())
            .fold(f64::NAN, f64::max);
        // How fast the file's fibre length changes from row to row (a
        // collocation solution's nodes obey the fibre dynamics only between
        // them); + 0.0: no "-0.00" for a fibre at rest.
        let between = samples
            .windows(2)
            .map(|w| -(w[1].fiber_length[k] - w[0].fiber_length[k]) / (w[1].t - w[0].t))
            .fold(f64::MIN, f64::max);
        row_to_row.push(between / vmax + 0.0);
        let mut rows_without = samples.iter().filter(|s| s.fiber_velocity[k].is_nan());
        if let Some(first) = rows_without.next() {
            without.push(format!(
                "{} at {} (the first at t = {} s)",
                spec.name,
                match rows_without.count() + 1 {
                    1 => "1 row".to_string(),
                    n => format!("{n} rows"),
                },
                crate::io::readable(first.t)
            ));
        }
        muscle_work += net;
        muscles.push(MuscleWork {
            name: spec.name.clone(),
            max_isometric_force_n: spec.max_isometric_force,
            peak_activation: peak(&|s| s.activation[k]),
            saturated_fraction: if duration > 0.0 {
                saturated / duration
            } else {
                0.0
            },
            peak_force_ratio: peak(&|s| s.tendon_force[k]) / spec.max_isometric_force,
            peak_shortening_ratio: peak_shortening / vmax,
            positive_work_j: positive,
            net_work_j: net,
        });
    }
    // A Hill muscle's fibre cannot shorten much faster than v_max: states
    // whose fibre lengths do are another muscle law's or model's.
    // Beside each, how fast its fibre length changes from row to row.
    let mut too_fast: Vec<(&MuscleWork, f64)> = muscles
        .iter()
        .zip(row_to_row)
        .filter(|(m, _)| m.peak_shortening_ratio > IMPOSSIBLE_SHORTENING_RATIO)
        .collect();
    too_fast.sort_by(|a, b| {
        b.0.peak_shortening_ratio
            .total_cmp(&a.0.peak_shortening_ratio)
    });
    if !too_fast.is_empty() {
        let list: Vec<String> = too_fast
            .iter()
            .map(|(m, between)| {
                format!(
                    "{} {:.2} ({between:.2} from row to row)",
                    m.name, m.peak_shortening_ratio
                )
            })
            .collect();
        warnings.push(format!(
            "by the model's force–velocity law, fibres shorten faster than muscles can, in times their maximum contraction velocity: {}; the file's states do not obey this model's fibre dynamics (written with another model or muscle_model? give it with --model; a collocation solution's nodes obey them only between nodes)",
            list.join(", ")
        ));
    }
    if !without.is_empty() {
        warnings.push(format!(
            "the fibre velocity overflows for {}: De Groote's inverted force–velocity curve overflows where the tendon force lies far beyond what the row's activation and fibre length can hold (a collocation solution's nodes, whose force balances midpoint Euler enforces at the interval midpoints only, may hold such states); the peak fibre speeds leave those rows out, the work and forces do not need them",
            without.join(", ")
        ));
    }
    muscles.sort_by(|a, b| b.net_work_j.total_cmp(&a.net_work_j));
    let passive = trapezoid(&|s| s.passive_power);
    let energy_change = last.energy - first.energy;
    let g = eq.model.gravity[1].abs();
    let standing = crate::simulate::standing_com_height(eq);
    let v = last.com_vertical_velocity;
    Ok(JumpAnalysis {
        liftoff,
        window_given: window.is_some(),
        both_sides: eq.system.symmetric,
        budget: EnergyBudget {
            start_s: first.t,
            end_s: last.t,
            energy_change_j: energy_change,
            muscle_work_j: muscle_work,
            passive_torque_work_j: passive,
            contact_work_j: energy_change - muscle_work - passive,
        },
        vertical_impulse_ns: trapezoid(&|s| s.vertical_grf - weight),
        com_momentum_change_ns: eq.model.total_mass()
            * (last.com_vertical_velocity - first.com_vertical_velocity),
        end_com_height_above_standing_m: last.com_height - standing,
        end_com_vertical_velocity_mps: v,
        jump_height_m: last.com_height - standing + v.max(0.0) * v.max(0.0) / (2.0 * g),
        body_weight_n: weight,
        peak_vertical_grf_bw: samples
            .iter()
            .map(|s| s.vertical_grf)
            .fold(f64::MIN, f64::max)
            / weight,
        muscles,
        warnings,
    })
}

impl JumpAnalysis {
    /// |impulse − momentum change| / max(|impulse|, |momentum change|,
    /// 1 N·s): 0 for a file that obeys Newton's second law (a window over
    /// the standing squat, both near 0, stays near 0).
    pub fn newton_mismatch(&self) -> f64 {
        let (a, b) = (self.vertical_impulse_ns, self.com_momentum_change_ns);
        (a - b).abs() / a.abs().max(b.abs()).max(1.0)
    }

    /// The warning `leap analyze` gives when the file breaks Newton's
    /// second law by more than [`NEWTON_MISMATCH_WARNING`].
    pub fn newton_warning(&self) -> Option<String> {
        let r = self.newton_mismatch();
        (r > NEWTON_MISMATCH_WARNING).then(|| {
            format!(
                "warning: the impulse and the momentum change differ by {:.0}% (Newton's second law equates them): the file's speeds are not its positions' rates, or its rows lie too far apart to integrate the ground force; read this analysis with care",
                100.0 * r
            )
        })
    }

    /// The report as text: the muscle table and the energy budget.
    pub fn to_text(&self) -> String {
        let b = &self.budget;
        let mut s = format!(
            "{} from {:.3} s to {:.3} s: {} {:.2} cm (COM {:+.2} cm from standing, rising at {:.3} m/s), peak vertical ground force {:.2} BW\n",
            if self.window_given {
                "given window"
            } else if self.liftoff {
                "push-off"
            } else {
                "window (no lift-off in the file)"
            },
            b.start_s,
            b.end_s,
            if self.liftoff {
                "jump height"
            } else {
                "apex if it flew from its end"
            },
            100.0 * self.jump_height_m,
            100.0 * self.end_com_height_above_standing_m,
            self.end_com_vertical_velocity_mps,
            self.peak_vertical_grf_bw
        );
        s.push_str(&format!(
            "{:<14} {:>8} {:>7} {:>10} {:>8} {:>9} {:>10} {:>9} {:>7}\n",
            "muscle", "F0 (N)", "peak a", "a≥0.95 %", "F/F0", "v/vmax", "W+ (J)", "W (J)", "W %"
        ));
        let total = self.budget.muscle_work_j;
        for m in &self.muscles {
            s.push_str(&format!(
                "{:<14} {:>8.0} {:>7.2} {:>10.0} {:>8.2} {:>9} {:>10.1} {:>9.1} {:>7.1}\n",
                m.name,
                m.max_isometric_force_n,
                m.peak_activation,
                100.0 * m.saturated_fraction,
                m.peak_force_ratio,
                // "-": no row had a fibre velocity.
                if m.peak_shortening_ratio.is_nan() {
                    "-".to_string()
                } else {
                    format!("{:.2}", m.peak_shortening_ratio)
                },
                m.positive_work_j,
                m.net_work_j,
                if total != 0.0 {
                    100.0 * m.net_work_j / total
                } else {
                    0.0
                }
            ));
        }
        s.push_str(&format!(
            "energy budget (J): kinetic + potential energy {:+.1} = muscles {:+.1} + passive joint torques {:+.1} + ground contact {:+.1}\n",
            b.energy_change_j, b.muscle_work_j, b.passive_torque_work_j, b.contact_work_j
        ));
        s.push_str(&format!(
            "vertical impulse ∫(Fy − mg) dt {:.2} N·s, COM momentum change {:.2} N·s\n",
            self.vertical_impulse_ns, self.com_momentum_change_ns
        ));
        s.push_str(if self.both_sides {
            "work of the muscles on both sides; "
        } else {
            "work of each muscle; "
        });
        s.push_str("W+ positive work; a≥0.95 % the share of the window at activation ≥ 0.95; v/vmax the peak fibre shortening speed over v_max·l_opt (-: no row had a fibre velocity)\n");
        s
    }
}
