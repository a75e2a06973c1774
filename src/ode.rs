//! The explicit state equation ẋ = f(x, u, t) of a musculoskeletal model, in
//! OpenSim's formulation: x = (q, q̇, l^M, a) with fibre lengths and
//! activations of every muscle whose states the system carries, u the
//! excitations (Porsa, Lin & Pandy 2016, eqs. 1-2; model-equations.md §2.6).
//!
//! The force laws (muscle, contact, passive joint torque) enter through
//! [`ForceLaws`], so one orchestration serves every law the model file can
//! choose and every scalar type. In the symmetric system each left muscle
//! shares the states of its right partner (it is its mirror image, checked
//! when the equation is built) and its tension is applied by doubling the
//! right one; left contact spheres and ligaments act on the left bodies and
//! coordinates, which follow the right ones exactly.

use crate::model::{Model, ModelError, SystemSpec};
use crate::multibody::{GeneralizedForces, ModelView, Multibody, SingularMassMatrix, Workspace};
use crate::path::{BodyKinematics, ForceSink, PathSmoothing};
use crate::scalar::Scalar;

/// What a muscle law returns for one muscle at one state.
#[derive(Debug, Clone, Copy)]
pub struct MuscleRates<S> {
    /// Tendon force applied along the path (N).
    pub tendon_force: S,
    /// d(fibre length)/dt (m/s).
    pub fiber_velocity: S,
    /// d(activation)/dt (1/s).
    pub activation_rate: S,
}

/// The force laws of a model, by element index into [`Model`]'s lists.
pub trait ForceLaws<S: Scalar> {
    /// Muscle `m` with activation `a`, fibre length `lm`, muscle-tendon
    /// length `lmt` and lengthening speed `vmt`, under excitation `u`.
    fn muscle(&self, m: usize, a: S, lm: S, lmt: S, vmt: S, u: S)
        -> Result<MuscleRates<S>, String>;
    /// Contact sphere `k` with its centre at `p_ground_centre` and the
    /// velocity (ground) of its material point at the contact point: the
    /// force on the sphere and its point of application, in ground.
    fn sphere(
        &self,
        k: usize,
        p_ground_centre: [S; 3],
        v_ground_contact: [S; 3],
    ) -> ([S; 3], [S; 3]);
    /// Passive torque of ligament `l` at coordinate value `q` and speed `qd`.
    fn ligament(&self, l: usize, q: S, qd: S) -> S;
}

/// A state equation could not be built or evaluated.
#[derive(Debug, thiserror::Error)]
pub enum OdeError {
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("{0}")]
    Symmetry(String),
    #[error("muscle '{muscle}': {reason}")]
    Muscle { muscle: String, reason: String },
    #[error(transparent)]
    Singular(#[from] SingularMassMatrix),
    /// [`OdeError::Singular`] at a state with coordinates outside their
    /// ranges, which `why` names ([`crate::eval::outside_range_hint`]): the
    /// likelier cause than the model's masses.
    #[error("no motion at this state{why}; {mass_matrix}")]
    SingularAt {
        mass_matrix: SingularMassMatrix,
        why: String,
    },
    #[error(transparent)]
    Law(#[from] crate::laws::UnsupportedLaw),
    #[error("wrong length of {what}: {got} (expected {want})")]
    Length {
        what: &'static str,
        got: usize,
        want: usize,
    },
    #[error("the workspace's given muscle paths belong to another (q, q̇) or system")]
    StaleGivenPaths,
    /// A derivative that is not finite at the state given; `why` names
    /// the coordinates outside their ranges, if any
    /// ([`crate::eval::outside_range_hint`]).
    #[error("the derivative of '{state}' is {value} at this state{}", if why.is_empty() { " (a coordinate far outside its range?)" } else { why.as_str() })]
    NotFinite {
        state: String,
        value: f64,
        why: String,
    },
    /// A muscle path without a positive finite length at one of the
    /// model's poses.
    #[error(transparent)]
    PathLength(Box<PathLengthError>),
}

/// A muscle path without a positive finite length at one of the model's
/// poses: the file, the muscle (its index in `forces.muscles`), the pose.
#[derive(Debug, thiserror::Error)]
#[error("{file}: forces.muscles[{index}].path: muscle '{muscle}' has length {length:e} m at {pose}: a path needs a positive finite length (a path point or spline value far off?)")]
pub struct PathLengthError {
    pub file: String,
    pub index: usize,
    pub muscle: String,
    pub pose: String,
    pub length: f64,
}

/// The state equation of a model's full or symmetric system.
#[derive(Debug, Clone)]
pub struct StateEquation {
    pub model: Model,
    pub system: SystemSpec,
    pub multibody: Multibody,
    /// Model muscles whose states the system carries.
    pub muscles: Vec<usize>,
    /// How many model muscles each carried muscle stands for (1 or 2).
    pub multiplicity: Vec<f64>,
    /// How conditional path points switch.
    pub smoothing: PathSmoothing,
}

/// Buffers for one evaluation thread.
#[derive(Debug, Clone)]
pub struct StateWorkspace<S: Scalar> {
    pub mb: Workspace<S>,
    tau: Vec<S>,
    qdd: Vec<S>,
    /// Per carried muscle after an evaluation: MTU length, speed, tendon force.
    pub mtu_length: Vec<S>,
    pub mtu_speed: Vec<S>,
    pub tendon_force: Vec<S>,
    /// Per sphere after an evaluation: force on the sphere (ground).
    pub sphere_force: Vec<[S; 3]>,
    /// Per ligament after an evaluation: torque (N·m).
    pub ligament_torque: Vec<S>,
    tau_unit: Vec<S>,
    wrench: Vec<[S; 3]>,
    /// Muscle paths computed elsewhere (see [`GivenPaths`]); `rhs` uses
    /// them instead of walking the paths while this is set.
    pub given_paths: Option<GivenPaths<S>>,
}

/// What `rhs` needs of the carried muscles' paths at one (q, q̇): per
/// muscle its length, lengthening speed and the generalised force of a unit
/// tension (n per muscle, in the order of q). The paths depend on (q, q̇)
/// alone, so where a dual-number evaluation seeds derivatives of other
/// inputs, or derivatives of (q, q̇) only to first order, these can be
/// computed once with a cheaper number type and lifted (the exact
/// Hessian's passes in the transcription).
#[derive(Debug, Clone)]
pub struct GivenPaths<S: Scalar> {
    /// The values of (q, q̇) they belong to: `rhs` refuses others.
    pub at: Vec<f64>,
    pub length: Vec<S>,
    pub speed: Vec<S>,
    pub unit: Vec<S>,
}

impl<S: Scalar> Default for GivenPaths<S> {
    fn default() -> Self {
        GivenPaths {
            at: Vec::new(),
            length: Vec::new(),
            speed: Vec::new(),
            unit: Vec::new(),
        }
    }
}

impl StateEquation {
    /// The model as OpenSim integrates it: its own laws (OpenSim's
    /// activation switch and fibre clamp, no optimizer smoothing) and the
    /// state equation of its symmetric (or full) system with conditional
    /// path points that switch. `leap simulate`, `eval`, `analyze`, `squat`
    /// and `leap solve`'s forward check integrate this; `tests/opensim_forward.rs`
    /// compares it with OpenSim's own forward simulation.
    pub fn opensim(
        model: &Model,
        symmetric: bool,
    ) -> Result<(crate::laws::OpenSimLaws, Self), OdeError> {
        let laws = crate::laws::OpenSimLaws::new(model)?;
        let eq = StateEquation::new(model, symmetric, PathSmoothing::Exact)?;
        Ok((laws, eq))
    }

    /// The state equation of `model`'s symmetric (or full) system.
    pub fn new(model: &Model, symmetric: bool, smoothing: PathSmoothing) -> Result<Self, OdeError> {
        let system = model.system(symmetric)?;
        let multibody = Multibody::new(model, &system);
        if multibody.num_composite_bodies() > 64 {
            return Err(OdeError::Symmetry(format!(
                "{}: more than 64 moving bodies are not supported",
                model.file.display()
            )));
        }
        check_path_lengths(model, &system, &multibody, smoothing)?;
        check_standing_pose(model, &system, &multibody)?;
        if symmetric && !model.symmetry.is_empty() {
            check_contact_mirror(model, &system, &multibody)?;
        }
        let mut muscles = Vec::new();
        let mut multiplicity = Vec::new();
        for (i, m) in model.muscles.iter().enumerate() {
            let name = &m.spec.name;
            if symmetric {
                if let Some(stem) = name.strip_suffix("_l") {
                    if model
                        .muscles
                        .iter()
                        .any(|o| o.spec.name == format!("{stem}_r"))
                    {
                        continue; // carried by its right partner
                    }
                }
                if let Some(stem) = name.strip_suffix("_r") {
                    if let Some(j) = model
                        .muscles
                        .iter()
                        .position(|o| o.spec.name == format!("{stem}_l"))
                    {
                        check_mirror(model, &system, &multibody, i, j)?;
                        muscles.push(i);
                        multiplicity.push(2.0);
                        continue;
                    }
                }
            }
            muscles.push(i);
            multiplicity.push(1.0);
        }
        Ok(StateEquation {
            model: model.clone(),
            system,
            multibody,
            muscles,
            multiplicity,
            smoothing,
        })
    }

    /// Number of generalized coordinates.
    pub fn nq(&self) -> usize {
        self.system.nq()
    }

    /// Number of carried muscles (= excitations).
    pub fn nm(&self) -> usize {
        self.muscles.len()
    }

    /// Number of states: q, q̇, fibre lengths, activations.
    pub fn nx(&self) -> usize {
        2 * self.nq() + 2 * self.nm()
    }

    /// OpenSim's path of model coordinate `c`'s state `what` (`value`,
    /// `speed`): `/jointset/<joint>/<coordinate>/<what>`.
    fn coordinate_path(&self, c: usize, what: &str) -> String {
        let name = &self.model.coordinates[c].name;
        let joint = self.model.joints.iter().find(|j| match &j.kind {
            crate::model::JointKind::Planar { coordinates } => coordinates.contains(&c),
            crate::model::JointKind::Pin { coordinate }
            | crate::model::JointKind::TranslatingHinge { coordinate, .. } => *coordinate == c,
            crate::model::JointKind::Weld => false,
        });
        format!(
            "/jointset/{}/{name}/{what}",
            joint.map(|j| j.name.as_str()).unwrap_or("?")
        )
    }

    /// OpenSim 4 state names, in x's order.
    pub fn state_names(&self) -> Vec<String> {
        let mut out = Vec::with_capacity(self.nx());
        for what in ["value", "speed"] {
            for &c in &self.system.coordinates {
                out.push(self.coordinate_path(c, what));
            }
        }
        for what in ["fiber_length", "activation"] {
            for &m in &self.muscles {
                out.push(format!(
                    "/forceset/{}/{what}",
                    self.model.muscles[m].spec.name
                ));
            }
        }
        out
    }

    /// Control names (Moco: `/forceset/<muscle>`).
    pub fn control_names(&self) -> Vec<String> {
        self.muscles
            .iter()
            .map(|&m| format!("/forceset/{}", self.model.muscles[m].spec.name))
            .collect()
    }

    /// The carried muscle (an index into `muscles`) whose states and
    /// excitation model muscle `i` has: itself, or for a left muscle of
    /// the symmetric system its right partner.
    fn carrier_of_muscle(&self, i: usize) -> Option<usize> {
        if let Some(k) = self.muscles.iter().position(|&m| m == i) {
            return Some(k);
        }
        let right = format!("{}_r", self.model.muscles[i].spec.name.strip_suffix("_l")?);
        self.muscles
            .iter()
            .position(|&m| self.model.muscles[m].spec.name == right)
    }

    /// Every state of the whole model, both legs, as OpenSim names them on
    /// the model file (`models/jumper.osim`), each with the index in x that
    /// holds its value: in the symmetric system a left coordinate or muscle
    /// takes its right partner's. Coordinate values and speeds, then fibre
    /// lengths and activations, each in the model's order; for the full
    /// system these are [`Self::state_names`] in x's order. The files leap
    /// writes carry these columns, so that OpenSim and Moco find every
    /// state of the model in them: the system's columns alone would leave
    /// the left leg at its default pose.
    pub fn model_state_columns(&self) -> Vec<(String, usize)> {
        let (nq, nm) = (self.nq(), self.nm());
        let nc = self.model.coordinates.len();
        let mut out = Vec::new();
        for (what, offset) in [("value", 0), ("speed", nq)] {
            for c in 0..nc {
                let q = self.system.q_of_model_coordinate[c];
                out.push((self.coordinate_path(c, what), offset + q));
            }
        }
        for (what, offset) in [("fiber_length", 2 * nq), ("activation", 2 * nq + nm)] {
            for (i, m) in self.model.muscles.iter().enumerate() {
                if let Some(k) = self.carrier_of_muscle(i) {
                    out.push((format!("/forceset/{}/{what}", m.spec.name), offset + k));
                }
            }
        }
        out
    }

    /// Every excitation of the whole model (Moco: `/forceset/<muscle>`),
    /// both legs, each with the index in u that holds it: in the
    /// symmetric system a left muscle takes its right partner's. For the
    /// full system these are [`Self::control_names`] in u's order.
    pub fn model_control_columns(&self) -> Vec<(String, usize)> {
        self.model
            .muscles
            .iter()
            .enumerate()
            .filter_map(|(i, m)| {
                Some((
                    format!("/forceset/{}", m.spec.name),
                    self.carrier_of_muscle(i)?,
                ))
            })
            .collect()
    }

    /// Buffers for evaluations with scalar type `S`.
    pub fn workspace<S: Scalar>(&self) -> StateWorkspace<S> {
        let n = self.nq();
        let nm = self.nm();
        let z = S::zero();
        let ns = self
            .model
            .contact
            .as_ref()
            .map(|c| c.spheres.len())
            .unwrap_or(0);
        StateWorkspace {
            mb: self.multibody.workspace(),
            tau: vec![z; n],
            qdd: vec![z; n],
            mtu_length: vec![z; nm],
            mtu_speed: vec![z; nm],
            tendon_force: vec![z; nm],
            sphere_force: vec![[z; 3]; ns],
            ligament_torque: vec![z; self.model.ligaments.len()],
            tau_unit: vec![z; n],
            wrench: vec![[z; 3]; self.multibody.num_composite_bodies()],
            given_paths: None,
        }
    }

    /// The carried muscles' path lengths at q (m; at rest, lengths depend
    /// on q alone).
    pub fn path_lengths(&self, q: &[f64]) -> Vec<f64> {
        let mut ws = self.multibody.workspace::<f64>();
        let rest = vec![0.0; self.nq()];
        let q_of = &self.system.q_of_model_coordinate;
        let view = ModelView::at(&self.multibody, &mut ws, q_of, q, &rest);
        self.muscles
            .iter()
            .map(|&m| {
                self.model.muscles[m]
                    .path
                    .calc::<f64, _, GeneralizedForces<f64>>(&view, self.smoothing, None)
                    .length
            })
            .collect()
    }

    /// The carried muscles' path lengths, lengthening speeds and unit-
    /// tension generalised forces at (q, q̇), into `out` (see [`GivenPaths`];
    /// `out.unit` holds n values per muscle).
    pub fn path_values<S: Scalar>(
        &self,
        ws: &mut StateWorkspace<S>,
        q: &[S],
        qd: &[S],
        out: &mut GivenPaths<S>,
    ) -> Result<(), OdeError> {
        let (n, nm) = (self.nq(), self.nm());
        check_lengths([("q", q.len(), n), ("qdot", qd.len(), n)])?;
        out.at.clear();
        out.at.extend(q.iter().chain(qd).map(|v| v.re()));
        out.length.resize(nm, S::zero());
        out.speed.resize(nm, S::zero());
        out.unit.resize(nm * n, S::zero());
        self.multibody.set_state(&mut ws.mb, q, qd);
        let q_of = &self.system.q_of_model_coordinate;
        let view = ModelView {
            mb: &self.multibody,
            ws: &ws.mb,
            q_of,
        };
        let mut unit = crate::multibody::UnitGeneralizedForces::new(
            &self.multibody,
            &ws.mb,
            q_of,
            &mut ws.tau_unit,
            &mut ws.wrench,
        );
        for (k, &mi) in self.muscles.iter().enumerate() {
            use crate::path::UnitForces;
            unit.clear();
            let pv = self.model.muscles[mi].path.calc(
                &view,
                self.smoothing,
                Some((S::one(), &mut unit)),
            );
            out.length[k] = pv.length;
            out.speed[k] = pv.lengthening_speed;
            let g = &mut out.unit[k * n..(k + 1) * n];
            g.iter_mut().for_each(|v| *v = S::zero());
            let mut sink = GeneralizedForces {
                mb: &self.multibody,
                ws: &ws.mb,
                q_of,
                tau: g,
            };
            unit.apply_scaled(S::one(), &mut sink);
        }
        Ok(())
    }

    /// ẋ = f(x, u): writes `xdot` (length [`Self::nx`]).
    pub fn rhs<S: Scalar, L: ForceLaws<S>>(
        &self,
        laws: &L,
        ws: &mut StateWorkspace<S>,
        x: &[S],
        u: &[S],
        xdot: &mut [S],
    ) -> Result<(), OdeError> {
        let (n, nm) = (self.nq(), self.nm());
        check_lengths([
            ("x", x.len(), self.nx()),
            ("u", u.len(), nm),
            ("xdot", xdot.len(), self.nx()),
        ])?;
        let (q, rest) = x.split_at(n);
        let (qd, rest) = rest.split_at(n);
        let (lm, act) = rest.split_at(nm);
        if let Some(g) = &ws.given_paths {
            let sizes = g.length.len() == nm && g.speed.len() == nm && g.unit.len() == nm * n;
            if !sizes
                || g.at.len() != 2 * n
                || g.at.iter().zip(&x[..2 * n]).any(|(a, b)| *a != b.re())
            {
                return Err(OdeError::StaleGivenPaths);
            }
        }
        self.multibody.set_state(&mut ws.mb, q, qd);
        for t in ws.tau.iter_mut() {
            *t = S::zero();
        }
        let q_of = &self.system.q_of_model_coordinate;
        {
            let view = ModelView {
                mb: &self.multibody,
                ws: &ws.mb,
                q_of,
            };
            let mut sink = GeneralizedForces {
                mb: &self.multibody,
                ws: &ws.mb,
                q_of,
                tau: &mut ws.tau,
            };
            let mut unit = crate::multibody::UnitGeneralizedForces::new(
                &self.multibody,
                &ws.mb,
                q_of,
                &mut ws.tau_unit,
                &mut ws.wrench,
            );
            let given = ws.given_paths.as_ref();
            self.apply_forces(
                laws,
                &view,
                &mut sink,
                lm,
                act,
                u,
                &mut xdot[2 * n..],
                Outputs {
                    mtu_length: &mut ws.mtu_length,
                    mtu_speed: &mut ws.mtu_speed,
                    tendon_force: &mut ws.tendon_force,
                    sphere_force: &mut ws.sphere_force,
                    ligament_torque: &mut ws.ligament_torque,
                },
                &mut unit,
                given,
            )?;
            if let Some(g) = given {
                for (k, (&f, &m)) in ws.tendon_force.iter().zip(&self.multiplicity).enumerate() {
                    let t = f * m;
                    for (tau, &gk) in ws.tau.iter_mut().zip(&g.unit[k * n..(k + 1) * n]) {
                        *tau += gk * t;
                    }
                }
            }
        }
        self.multibody
            .forward_dynamics(&mut ws.mb, &ws.tau, &mut ws.qdd)?;
        xdot[..n].copy_from_slice(qd);
        xdot[n..2 * n].copy_from_slice(&ws.qdd);
        Ok(())
    }

    /// The contact spheres' forces alone at state `x` (they depend on q and
    /// q̇ only) into `ws.sphere_force`, as [`Self::rhs`] leaves them: the
    /// ground forces of a state whose muscles cannot be evaluated (an
    /// explicit fibre velocity that does not exist).
    pub fn contact_forces<L: ForceLaws<f64>>(
        &self,
        laws: &L,
        ws: &mut StateWorkspace<f64>,
        x: &[f64],
    ) -> Result<(), OdeError> {
        let n = self.nq();
        check_lengths([("x", x.len(), self.nx())])?;
        self.multibody.set_state(&mut ws.mb, &x[..n], &x[n..2 * n]);
        let view = ModelView {
            mb: &self.multibody,
            ws: &ws.mb,
            q_of: &self.system.q_of_model_coordinate,
        };
        if let Some(contact) = &self.model.contact {
            for (k, sp) in contact.spheres.iter().enumerate() {
                ws.sphere_force[k] = sphere_force(laws, &view, k, sp).0;
            }
        }
        Ok(())
    }

    /// The forces of every element at the state `view` shows, into `sink`;
    /// muscle rates into `zdot` = [d l^M/dt, da/dt]. Shared by both backends.
    #[allow(clippy::too_many_arguments)]
    pub fn apply_forces<
        S: Scalar,
        L: ForceLaws<S>,
        K: BodyKinematics<S>,
        F: ForceSink<S>,
        U: crate::path::UnitForces<S, F>,
    >(
        &self,
        laws: &L,
        view: &K,
        sink: &mut F,
        lm: &[S],
        act: &[S],
        u: &[S],
        zdot: &mut [S],
        out: Outputs<'_, S>,
        unit: &mut U,
        given: Option<&GivenPaths<S>>,
    ) -> Result<(), OdeError> {
        let nm = self.nm();
        // Passive joint torques.
        for (l, lig) in self.model.ligaments.iter().enumerate() {
            let (qc, qdc) = view.coordinate(lig.coordinate);
            let t = laws.ligament(l, qc, qdc);
            out.ligament_torque[l] = t;
            sink.add_generalized_force(lig.coordinate, t);
        }
        // Foot-ground contact.
        if let Some(contact) = &self.model.contact {
            for (k, sp) in contact.spheres.iter().enumerate() {
                let (f, at) = sphere_force(laws, view, k, sp);
                out.sphere_force[k] = f;
                if f.iter().any(|c| c.re() != 0.0) {
                    let station = view.station_at(sp.body, at);
                    sink.add_point_force(sp.body, station, f);
                }
            }
        }
        // Muscles: one pass over each path gives its length, speed and the
        // forces of a unit tension, replayed scaled by the tendon force.
        for (k, &mi) in self.muscles.iter().enumerate() {
            let muscle = &self.model.muscles[mi];
            // Given paths: their forces are added by the caller.
            let pv = match given {
                Some(g) => crate::path::PathValue {
                    length: g.length[k],
                    lengthening_speed: g.speed[k],
                },
                None => {
                    unit.clear();
                    muscle
                        .path
                        .calc(view, self.smoothing, Some((S::one(), &mut *unit)))
                }
            };
            let rates = laws
                .muscle(mi, act[k], lm[k], pv.length, pv.lengthening_speed, u[k])
                .map_err(|reason| OdeError::Muscle {
                    muscle: muscle.spec.name.clone(),
                    reason,
                })?;
            out.mtu_length[k] = pv.length;
            out.mtu_speed[k] = pv.lengthening_speed;
            out.tendon_force[k] = rates.tendon_force;
            zdot[k] = rates.fiber_velocity;
            zdot[nm + k] = rates.activation_rate;
            if given.is_none() {
                unit.apply_scaled(rates.tendon_force * self.multiplicity[k], sink);
            }
        }
        Ok(())
    }
}

/// Each (what, length, wanted length) of an evaluation's arguments.
fn check_lengths<const N: usize>(args: [(&'static str, usize, usize); N]) -> Result<(), OdeError> {
    match args.into_iter().find(|&(_, got, want)| got != want) {
        Some((what, got, want)) => Err(OdeError::Length { what, got, want }),
        None => Ok(()),
    }
}

/// Contact sphere `k`'s force and point of application (ground) at the
/// state `view` shows.
fn sphere_force<S: Scalar, L: ForceLaws<S>, K: BodyKinematics<S>>(
    laws: &L,
    view: &K,
    k: usize,
    sp: &crate::model::Sphere,
) -> ([S; 3], [S; 3]) {
    let loc = [
        S::from(sp.location[0]),
        S::from(sp.location[1]),
        S::from(sp.location[2]),
    ];
    let p = view.position(sp.body, loc);
    // Simbody's contact point is mid-overlap, R − δ/2 below the centre; its
    // slip includes the foot's rotation.
    let p_contact = [p[0], (p[1] - sp.radius) * 0.5, p[2]];
    let v = view.velocity(sp.body, view.station_at(sp.body, p_contact));
    laws.sphere(k, p, v)
}

/// Where [`StateEquation::apply_forces`] reports per-element results.
pub struct Outputs<'a, S> {
    pub mtu_length: &'a mut [S],
    pub mtu_speed: &'a mut [S],
    pub tendon_force: &'a mut [S],
    pub sphere_force: &'a mut [[S; 3]],
    pub ligament_torque: &'a mut [S],
}

/// How far the lowest contact sphere of a jump model may lie above or
/// below the ground at the standing pose (m). The jump height is the apex
/// of the centre of mass above its height at that pose, so feet off the
/// ground there shift every height reported; resting on Hunt–Crossley
/// spheres the shipped models sink by under a millimetre (their standing
/// poses put the lowest sphere 7e-7 m into the ground).
pub const STANDING_GROUND_TOLERANCE: f64 = 0.005;

/// A jump model's standing pose (`poses.standing`, else the coordinates'
/// default values) must put its feet on the ground: its lowest contact
/// sphere within [`STANDING_GROUND_TOLERANCE`] of it. Checked for
/// `HuntCrossleyForce` only: `SmoothSphereHalfSpaceForce` pushes before
/// touching (its constant_contact_force), so its spheres rest above the
/// ground by an amount of its constants.
fn check_standing_pose(model: &Model, system: &SystemSpec, mb: &Multibody) -> Result<(), OdeError> {
    let Some(contact) = model.contact.as_ref().filter(|c| {
        model.poses.contains_key("squat")
            && c.spec.law == crate::model::ContactLaw::HuntCrossleyForce
    }) else {
        return Ok(());
    };
    let defaults: Vec<f64> = model.coordinates.iter().map(|c| c.default_value).collect();
    let (field, pose) = match model.poses.get("standing") {
        Some(p) => ("poses.standing", p),
        None => ("poses", &defaults),
    };
    let q = system.q_from_model(pose);
    let mut ws = mb.workspace::<f64>();
    mb.set_state(&mut ws, &q, &vec![0.0; q.len()]);
    let lowest = lowest_sphere_bottom(mb, &ws, contact);
    if lowest.is_finite() && lowest.abs() <= STANDING_GROUND_TOLERANCE {
        return Ok(());
    }
    let which = if field == "poses" {
        "the coordinates' default values (the model has no standing pose)"
    } else {
        "the standing pose"
    };
    let place = if !lowest.is_finite() {
        format!("the lowest contact sphere's height is {lowest}")
    } else if lowest > 0.0 {
        format!("the feet are {:.1} mm above the ground", lowest * 1e3)
    } else {
        format!("the feet are {:.1} mm into the ground", -lowest * 1e3)
    };
    Err(OdeError::Model(ModelError::Invalid {
        file: model.file.clone(),
        path: field.into(),
        reason: format!(
            "at {which} {place} (the lowest contact sphere; at most {:.0} mm either way): the jump height is measured from the centre of mass at this pose, standing on the ground",
            STANDING_GROUND_TOLERANCE * 1e3
        ),
    }))
}

/// The height above the ground of the lowest contact sphere's bottom at
/// the state set in `ws` (negative: into the ground; infinite without
/// spheres).
pub fn lowest_sphere_bottom(
    mb: &Multibody,
    ws: &Workspace<f64>,
    contact: &crate::model::Contact,
) -> f64 {
    lowest_sphere(mb, ws, contact).map_or(f64::INFINITY, |(_, h)| h)
}

/// The contact sphere whose bottom lies lowest (sunk deepest) at the state
/// set in `ws`: its index and that height (m; negative: into the ground).
pub fn lowest_sphere(
    mb: &Multibody,
    ws: &Workspace<f64>,
    contact: &crate::model::Contact,
) -> Option<(usize, f64)> {
    contact
        .spheres
        .iter()
        .map(|sp| mb.model_point_position(ws, sp.body, sp.location)[1] - sp.radius)
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// Every muscle path has a positive finite length at the coordinates'
/// default values and at each of the model's poses, so that a path point or
/// spline value far off (1e300 is finite) is named here rather than met as
/// a non-finite fibre velocity, or an asymmetry, later.
fn check_path_lengths(
    model: &Model,
    system: &SystemSpec,
    mb: &Multibody,
    smoothing: PathSmoothing,
) -> Result<(), OdeError> {
    let rest = vec![0.0; system.nq()];
    let mut ws = mb.workspace::<f64>();
    let defaults: Vec<f64> = model.coordinates.iter().map(|c| c.default_value).collect();
    let poses = std::iter::once(("the coordinates' default values".to_string(), &defaults))
        .chain(model.poses.iter().map(|(k, v)| (format!("poses.{k}"), v)));
    for (pose, model_q) in poses {
        let q = system.q_from_model(model_q);
        let view = ModelView::at(mb, &mut ws, &system.q_of_model_coordinate, &q, &rest);
        for (index, m) in model.muscles.iter().enumerate() {
            let length = m
                .path
                .calc::<f64, _, GeneralizedForces<f64>>(&view, smoothing, None)
                .length;
            // Each conditional point switched on too, so that one inactive
            // at these poses is checked as well.
            let with_each_on =
                (0..m.path.num_conditional()).map(|j| (j, m.path.length_with(&view, j, true)));
            let bad = std::iter::once((None, length))
                .chain(with_each_on.map(|(j, l)| (Some(j), l)))
                .find(|&(_, l)| !(l.is_finite() && l > 0.0));
            if let Some((j, length)) = bad {
                return Err(OdeError::PathLength(Box::new(PathLengthError {
                    file: model.file.display().to_string(),
                    index,
                    muscle: m.spec.name.clone(),
                    pose: match j {
                        None => pose,
                        Some(j) => format!(
                            "{pose} with its conditional point path[{}] active",
                            m.path.conditional_points()[j].0
                        ),
                    },
                    length,
                })));
            }
        }
    }
    Ok(())
}

/// Check that muscle `j` (left) mirrors muscle `i` (right) in the symmetric
/// system: equal parameters and equal path lengths at several poses.
fn check_mirror(
    model: &Model,
    system: &SystemSpec,
    mb: &Multibody,
    i: usize,
    j: usize,
) -> Result<(), OdeError> {
    let (a, b) = (&model.muscles[i].spec, &model.muscles[j].spec);
    if a.parameters() != b.parameters() {
        return Err(OdeError::Symmetry(format!("{}: forces.muscles[{j}]: muscle '{}' has parameters different from '{}' (forces.muscles[{i}]); the symmetric system needs mirror images", model.file.display(), b.name, a.name)));
    }
    let rest = vec![0.0; system.nq()];
    let mut ws = mb.workspace::<f64>();
    for k in 0..4 {
        let q: Vec<f64> = system
            .coordinates
            .iter()
            .map(|&c| {
                let [lo, hi] = model.coordinates[c].range;
                let s = 0.5 + 0.4 * ((k * 7 + c) as f64).sin();
                lo + s * (hi - lo).min(3.0)
            })
            .collect();
        let view = ModelView::at(mb, &mut ws, &system.q_of_model_coordinate, &q, &rest);
        let sm = PathSmoothing::Smooth { delta: 0.02 };
        let li = model.muscles[i]
            .path
            .calc::<f64, _, GeneralizedForces<f64>>(&view, sm, None)
            .length;
        let lj = model.muscles[j]
            .path
            .calc::<f64, _, GeneralizedForces<f64>>(&view, sm, None)
            .length;
        // (Fails on NaN too.)
        let mirrored = (li - lj).abs() <= 1e-12 * li.abs().max(1.0);
        if !mirrored {
            return Err(OdeError::Symmetry(format!(
                "{}: forces.muscles[{j}].path: muscle '{}' is not the mirror image of '{}' (forces.muscles[{i}]): path lengths {lj} m and {li} m at the same symmetric pose",
                model.file.display(),
                b.name,
                a.name
            )));
        }
    }
    Ok(())
}

/// In the symmetric system both legs move as one, which a model whose
/// contact is not symmetric cannot do (one foot bearing the body would roll
/// it): every contact sphere of the left leg (a body the system welds onto
/// its right partner, or one fixed below such a body: the calcaneus and
/// toes below the talus) needs a sphere of the right leg of the same radius
/// at the same place in the plane (x and y in the ground frame; the legs'
/// frames then coincide in the plane), and every sphere of the right leg
/// one of the left, one to one (each leg as many spheres of a radius at a
/// place). z does not act in the plane and is not compared; a sphere on a
/// midline body (the pelvis) needs no partner.
fn check_contact_mirror(
    model: &Model,
    system: &SystemSpec,
    mb: &Multibody,
) -> Result<(), OdeError> {
    let Some(contact) = model.contact.as_ref() else {
        return Ok(());
    };
    // The side of each body: that of the nearest welded body (left) or
    // weld partner (right) on its way to the ground.
    #[derive(Clone, Copy, PartialEq)]
    enum Side {
        Left,
        Right,
        Middle,
    }
    let nb = model.bodies.len();
    let mut own = vec![Side::Middle; nb];
    for (left, right) in system.mirror_of.iter().enumerate() {
        if let Some(r) = *right {
            own[left] = Side::Left;
            own[r] = Side::Right;
        }
    }
    let parent_of = |b: usize| {
        model
            .joints
            .iter()
            .find(|j| j.child == b)
            .and_then(|j| j.parent)
    };
    let side: Vec<Side> = (0..nb)
        .map(|b| {
            let mut at = Some(b);
            // At most nb steps: the joint tree has no loops.
            for _ in 0..=nb {
                match at {
                    Some(c) if own[c] != Side::Middle => return own[c],
                    Some(c) => at = parent_of(c),
                    None => break,
                }
            }
            Side::Middle
        })
        .collect();
    let defaults: Vec<f64> = model.coordinates.iter().map(|c| c.default_value).collect();
    let q = system.q_from_model(&defaults);
    let mut ws = mb.workspace::<f64>();
    mb.set_state(&mut ws, &q, &vec![0.0; q.len()]);
    let at: Vec<[f64; 3]> = contact
        .spheres
        .iter()
        .map(|sp| mb.model_point_position(&ws, sp.body, sp.location))
        .collect();
    const TOL: f64 = 1e-9;
    for (i, a) in contact.spheres.iter().enumerate() {
        let other = match side[a.body] {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
            Side::Middle => continue,
        };
        let distance = |j: usize| (at[i][0] - at[j][0]).hypot(at[i][1] - at[j][1]);
        let candidates: Vec<usize> = (0..contact.spheres.len())
            .filter(|&j| side[contact.spheres[j].body] == other)
            .collect();
        // One to one: as many spheres of this radius at this x and y on
        // each leg (a foot's two spheres that differ only in z are not
        // both mirrored by one of the other's). (Fails on NaN too.)
        let coincide = |j: usize| distance(j) <= TOL && contact.spheres[j].radius == a.radius;
        let here = (0..contact.spheres.len())
            .filter(|&j| side[contact.spheres[j].body] == side[a.body] && coincide(j))
            .count();
        let there = candidates.iter().filter(|&&j| coincide(j)).count();
        if here > 0 && there == here {
            continue;
        }
        if there > 0 {
            let leg = |s: Side| if s == Side::Left { "left" } else { "right" };
            return Err(OdeError::Symmetry(format!(
                "{}: forces.contact.spheres[{i}]: sphere '{}' of the {} leg (on '{}', radius {} m) has {here} sphere(s) of its radius at its x and y on its leg and {there} on the {} leg: the symmetric system moves both legs as one, so each foot needs the other's spheres one to one, of the same radius at the same x and y (z negated); give both feet the same spheres, or use the full system (`leap eval --full`, `leap squat --full`, `leap analyze --full`)",
                model.file.display(),
                a.name,
                leg(side[a.body]),
                model.bodies[a.body].name,
                a.radius,
                leg(other),
            )));
        }
        let nearest = candidates
            .iter()
            .min_by(|&&x, &&y| distance(x).total_cmp(&distance(y)))
            .map(|&j| {
                format!(
                    "; the nearest, '{}' (radius {} m), lies {:.1} mm away in the plane",
                    contact.spheres[j].name,
                    contact.spheres[j].radius,
                    1e3 * distance(j)
                )
            })
            .unwrap_or_else(|| "; the other leg has no spheres".into());
        let leg = if side[a.body] == Side::Left {
            "left"
        } else {
            "right"
        };
        return Err(OdeError::Symmetry(format!(
            "{}: forces.contact.spheres[{i}]: sphere '{}' of the {leg} leg (on '{}', radius {} m) has no mirror image: the symmetric system moves both legs as one, so each foot needs the other's spheres, of the same radius at the same x and y (z negated){nearest}; give both feet the same spheres, or use the full system (`leap eval --full`, `leap squat --full`, `leap analyze --full`)",
            model.file.display(),
            a.name,
            model.bodies[a.body].name,
            a.radius,
        )));
    }
    Ok(())
}

/// Excitations seen by the Simbody force element: fixed values, or a
/// function of time (controls file, bang-bang pattern).
pub enum Excitation {
    Constant(Vec<f64>),
    OfTime(ExcitationOfTime),
}

/// Excitations as a function of time: fills the slice at time t.
pub type ExcitationOfTime = Box<dyn Fn(f64, &mut [f64]) + Send>;

/// The same state equation evaluated by Simbody: q and q̇ in Simbody's
/// multibody system, fibre lengths and activations as Simbody auxiliary (z)
/// states, and every force computed by the Rust laws inside a Simbody force
/// element from Simbody's own kinematics.
pub struct SimbodyStateEquation {
    pub equation: std::sync::Arc<StateEquation>,
    pub simbody: crate::simbody::SimbodyModel,
    excitation: std::sync::Arc<std::sync::Mutex<Excitation>>,
    /// The contact force on each sphere (ground) at the last force
    /// evaluation.
    spheres: std::sync::Arc<std::sync::Mutex<Vec<[f64; 3]>>>,
    /// No applied generalized forces (`rhs`).
    zero_forces: Vec<f64>,
    perm: Vec<usize>,
}

impl SimbodyStateEquation {
    /// Build Simbody's system for `equation` with force laws `laws`.
    pub fn new<L>(
        equation: std::sync::Arc<StateEquation>,
        laws: std::sync::Arc<L>,
    ) -> Result<Self, crate::simbody::SimbodyError>
    where
        L: ForceLaws<f64> + Send + Sync + 'static,
    {
        let sys = &equation.system;
        let perm = crate::simbody::simbody_q_order(sys);
        let q_index: Vec<usize> = sys.q_of_model_coordinate.iter().map(|&k| perm[k]).collect();
        let mobod: Vec<i32> = sys.system_body_of.iter().map(|&s| s as i32 + 1).collect();
        let nm = equation.nm();
        let excitation =
            std::sync::Arc::new(std::sync::Mutex::new(Excitation::Constant(vec![0.0; nm])));
        let exc = excitation.clone();
        let eq = equation.clone();
        let mut buf = crate::simbody::ForceBuffer::default();
        let mut unit = crate::path::CollectedForces::<f64>::default();
        let mut u = vec![0.0; nm];
        let ns = eq
            .model
            .contact
            .as_ref()
            .map(|c| c.spheres.len())
            .unwrap_or(0);
        let (mut o1, mut o2, mut o3, mut o5) = (
            vec![0.0; nm],
            vec![0.0; nm],
            vec![0.0; nm],
            vec![0.0; eq.model.ligaments.len()],
        );
        let spheres = std::sync::Arc::new(std::sync::Mutex::new(vec![[0.0; 3]; ns]));
        let o4 = spheres.clone();
        let f: Box<crate::simbody::ForceFn> = Box::new(move |ctx, t, q, qd, z, zdot| {
            match &*exc
                .lock()
                .map_err(|_| "excitation lock poisoned".to_string())?
            {
                Excitation::Constant(v) => u.copy_from_slice(v),
                Excitation::OfTime(g) => g(t, &mut u),
            }
            buf.clear();
            {
                let kin = crate::simbody::SimbodyKinematics {
                    ctx,
                    mobod: &mobod,
                    q_index: &q_index,
                    q,
                    u: qd,
                    error: Default::default(),
                };
                let (lm, act) = z.split_at(nm);
                let mut sphere_force = o4
                    .lock()
                    .map_err(|_| "sphere force lock poisoned".to_string())?;
                eq.apply_forces(
                    &*laws,
                    &kin,
                    &mut buf,
                    lm,
                    act,
                    &u,
                    zdot,
                    Outputs {
                        mtu_length: &mut o1,
                        mtu_speed: &mut o2,
                        tendon_force: &mut o3,
                        sphere_force: &mut sphere_force,
                        ligament_torque: &mut o5,
                    },
                    &mut unit,
                    None,
                )
                .map_err(|e| e.to_string())?;
                if let Some(e) = kin.error.into_inner() {
                    return Err(e);
                }
            }
            buf.flush(ctx, &mobod, &q_index)
        });
        let simbody = crate::simbody::SimbodyModel::with_force(
            &equation.model,
            &equation.system,
            Some((f, 2 * nm)),
        )?;
        let nq = equation.nq();
        Ok(SimbodyStateEquation {
            equation,
            simbody,
            excitation,
            spheres,
            zero_forces: vec![0.0; nq],
            perm,
        })
    }

    /// Set the excitations the force element sees.
    pub fn set_excitation(&mut self, e: Excitation) {
        if let Ok(mut g) = self.excitation.lock() {
            *g = e;
        }
    }

    /// The contact force on each sphere (ground frame, N) at the state of
    /// the last force evaluation (after [`Self::rhs`]: at its x and u).
    pub fn sphere_forces(&self, out: &mut [[f64; 3]]) -> Result<(), crate::simbody::SimbodyError> {
        let f = self.spheres.lock().map_err(|_| {
            crate::simbody::SimbodyError::Input("sphere force lock poisoned".into())
        })?;
        if out.len() != f.len() {
            return Err(crate::simbody::SimbodyError::Input(format!(
                "{} sphere forces asked for, the model has {}",
                out.len(),
                f.len()
            )));
        }
        out.copy_from_slice(&f);
        Ok(())
    }

    /// Simbody's q index of each system coordinate.
    pub fn simbody_q_index(&self) -> &[usize] {
        &self.perm
    }

    /// Set the full state x = (q, q̇, l^M, a) at time t.
    pub fn set_state(&mut self, t: f64, x: &[f64]) -> Result<(), crate::simbody::SimbodyError> {
        let n = self.equation.nq();
        if x.len() != self.equation.nx() {
            return Err(crate::simbody::SimbodyError::Input(format!(
                "x has length {}, expected {}",
                x.len(),
                self.equation.nx()
            )));
        }
        self.simbody.set_state(t, &x[..n], &x[n..2 * n])?;
        self.simbody.set_z(&x[2 * n..])
    }

    /// The current state x.
    pub fn state(&mut self, x: &mut [f64]) -> Result<f64, crate::simbody::SimbodyError> {
        let n = self.equation.nq();
        let (q, rest) = x.split_at_mut(n);
        let (u, z) = rest.split_at_mut(n);
        let t = self.simbody.state(q, u)?;
        self.simbody.z(z)?;
        Ok(t)
    }

    /// ẋ = f(x, u) computed by Simbody.
    pub fn rhs(
        &mut self,
        x: &[f64],
        u: &[f64],
        xdot: &mut [f64],
    ) -> Result<(), crate::simbody::SimbodyError> {
        let n = self.equation.nq();
        if u.len() != self.equation.nm() || xdot.len() != self.equation.nx() {
            return Err(crate::simbody::SimbodyError::Input(
                "wrong length of u or xdot".into(),
            ));
        }
        // The excitations in place (this runs for every difference of
        // `Backend::Simbody`'s Jacobians).
        if let Ok(mut e) = self.excitation.lock() {
            match &mut *e {
                Excitation::Constant(v) if v.len() == u.len() => v.copy_from_slice(u),
                other => *other = Excitation::Constant(u.to_vec()),
            }
        }
        // Setting the state invalidates every cached force (the excitation
        // lives outside Simbody's state).
        self.set_state(0.0, x)?;
        self.simbody.set_applied_forces(&self.zero_forces, &[])?;
        xdot[..n].copy_from_slice(&x[n..2 * n]);
        self.simbody.accelerations(&mut xdot[n..2 * n])?;
        self.simbody.zdot(&mut xdot[2 * n..])
    }
}
