//! The maximum-height jump as an optimal control problem (Porsa, Lin &
//! Pandy 2016, eqs. 1-6), apart from any transcription:
//!
//! ```text
//!   minimise   −J = −( Y_C(t_f) + Ẏ_C(t_f)² / (2g) )                  (eq. 3)
//!   subject to ẋ = f(x, u)                                            (eqs. 1-2)
//!              Ÿ_C(t_n) − Ÿ_C(t_{n+1}) ≤ 0,   n = 1..7                (eq. 4)
//!              u_min ≤ u ≤ 1                                          (eq. 5)
//!              x_L ≤ x ≤ x_U                                          (eq. 6)
//!              x(0) = x_squat, u(0) = u_squat (the static squat)
//!              Ẏ_C(t_k) ≥ 0 at every node (optional, see
//!                [`OcpOptions::no_com_descent`])
//!              F_y(t_f) / (m g) ≤ ε  (lift-off, see [`LiftOff`])
//!              t_f free in [t_min, t_max]
//! ```
//!
//! with x = (q, q̇, l^M, a) the 62 states of the symmetric model (7
//! coordinates, 24 carried muscles), u the 24 excitations, Y_C the height of
//! the whole-body centre of mass and g the magnitude of the model's gravity
//! (9.80665 m/s² in OpenSim). J is the apex height of a ballistic centre of
//! mass leaving the ground at t_f (model-equations.md §6). The paper
//! numbers its nodes from t_1 = 0, so eq. 4 constrains the first eight
//! nodes (the fixed start and the next seven).
//!
//! Ÿ_C at a node follows from q, q̇ and q̈ = f(x, u) at that node
//! ([`crate::multibody::Multibody::com_acceleration`]).
//!
//! Bounds ([`OcpOptions`]): coordinates within the model's ranges, speeds
//! within ±30 rad/s or m/s, fibre lengths within [0.2, 2]·l_o but above
//! the law's minimum fibre length, activations within [0.01, 1] (Thelen's
//! minimum activation), excitations within [u_min, 1]. The paper's eq. 5
//! reads 0 ≤ u ≤ 1; OpenSim's Thelen2003Muscle clamps its excitation to
//! min_control = 0.01 (as `leap simulate` does), and below it u would
//! only pull a under its bound, so u_min = 0.01 for Thelen muscles and 0
//! for DeGrooteFregly2016Muscle.

use crate::laws::{MuscleLaw, OpenSimLaws, UnsupportedLaw, MIN_ACTIVATION};
use crate::model::{Model, ModelError};
use crate::ode::{ForceLaws, OdeError, StateEquation, StateWorkspace};
use crate::path::PathSmoothing;
use crate::scalar::Scalar;
use crate::simulate::{
    extensor_moments, simulate_rust, BangBang, JumpSummary, SimulateOptions, SimulationFailure,
    Trajectory,
};
use crate::squat::{static_squat, SquatError, StaticSquat};

/// How the final time is tied to lift-off.
///
/// J is constant during flight (only gravity acts on the centre of mass,
/// so Y_C + Ẏ_C²/(2g) is conserved), and while the feet push,
/// dJ/dt = Ẏ_C·(1 + Ÿ_C/g) = Ẏ_C·F_y/(m g) ≥ 0 for a rising body, where F_y
/// is the total vertical ground force. Maximising J therefore drives t_f to
/// lift-off or beyond, where J no longer depends on t_f; the constraint
/// below keeps the final node at or after the instant the ground force has
/// fallen to ε·body weight, and t_f is reported as the lift-off time. A
/// fraction ε > 0 keeps the constraint's gradient nonzero where it is
/// active (the Hunt–Crossley force, ∝ depth^{3/2}, has a zero gradient at
/// zero force).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum LiftOff {
    /// F_y(t_f)/(m g) ≤ fraction (default, fraction 0.01): the final node
    /// is at or after lift-off. An inequality, so a trial step into flight
    /// (zero force, zero gradient) stays feasible.
    ForceAtMost { fraction: f64 },
    /// F_y(t_f)/(m g) = fraction: the final node is exactly where the force
    /// falls through that level, which removes the flat direction of J in
    /// flight at the price of an equality on a stiff contact force.
    ForceEquals { fraction: f64 },
}

impl Default for LiftOff {
    fn default() -> Self {
        LiftOff::ForceAtMost { fraction: 0.01 }
    }
}

impl LiftOff {
    /// The ground force level (fraction of body weight) that marks lift-off.
    pub fn fraction(self) -> f64 {
        match self {
            LiftOff::ForceAtMost { fraction } | LiftOff::ForceEquals { fraction } => fraction,
        }
    }
}

/// Settings of the jump problem.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OcpOptions {
    /// How conditional path points switch. Default: smooth over 0.02 rad,
    /// because a gradient-based optimizer needs derivatives that do not jump
    /// (model-data.md §10); the path is exact more than 0.02 rad from a
    /// switch.
    pub smoothing: PathSmoothing,
    /// Bounds on the final time t_f (s). Default [0.1, 1.0]: the bang-bang
    /// jump of the model lifts off at about 0.27 s, human squat jumps push
    /// for 0.25-0.45 s.
    pub final_time_bounds: [f64; 2],
    /// |q̇| bound for every coordinate (rad/s or m/s). Default 30: the
    /// bang-bang jump reaches an ankle speed of 19.8 rad/s at lift-off, so
    /// ±20 would be active already.
    pub speed_bound: f64,
    /// Fibre-length bounds as multiples of the optimal fibre length
    /// (default [0.2, 2.0]); the lower bound is raised to
    /// (1 + `min_fiber_length_margin`) times the law's minimum fibre length
    /// (Thelen: l_o sin φ_o / sin(acos 0.1); DeGroote: l_o sin φ_o), below
    /// which Thelen clamps the fibre (a kink in f).
    pub fiber_length_bounds: [f64; 2],
    pub min_fiber_length_margin: f64,
    /// Number of no-countermovement rows (eq. 4; the paper's 7).
    pub no_countermovement_nodes: usize,
    /// Ẏ_C(t_k) ≥ 0 at every node k = 1..N: the centre of mass never moves
    /// down. Default true. Eq. 4 alone constrains only the first seven
    /// intervals (the first ~0.08 s); after them nothing in the paper's
    /// problem forbids a countermovement, and on this model the optimizer
    /// takes one: with eq. 4 alone the 600-iteration solve of 2026-12-02
    /// unloaded the feet from 0.19 s, dropped the pelvis 12 cm and pushed
    /// off at 0.67 s. A squat jump starts from rest and rises throughout
    /// (the paper's predicted and measured jumps do), so these rows state
    /// "no countermovement" for the whole push-off. False gives the paper's
    /// eq. 4 alone.
    pub no_com_descent: bool,
    pub liftoff: LiftOff,
    /// Thelen's activation dynamics switch time constants at u = a, a kink
    /// the optimizer cannot step across (muscles at rest sit on it: u = a =
    /// 0.01). Some(b) blends the switch by ½ + ½·tanh(b·(u − a)) (De Groote
    /// et al. 2016; Moco's `activation_dynamics_smoothing`). Default 200:
    /// the rates are OpenSim's within 1% once |u − a| > 0.018 (at a_min,
    /// where the blended rates differ most; 0.013 at a ≈ 0.5). The forward
    /// check integrates OpenSim's own switch, so a softer blend shows as
    /// a gap between predicted and simulated jump: at b = 10 (an earlier
    /// default) the reduced jump at 28 intervals predicted 1.19 cm more
    /// than its forward check, of which 1.13 cm vanished when the forward
    /// check used the blended switch too; at b = 50 (the default until
    /// 2026-12-06) the gap is 0.34 cm. On the full jump the forward check's
    /// gap is 0.37–0.51 cm at b = 50 and 0.08–0.24 cm at b = 200 on 24–30
    /// mesh intervals (docs/model-strength.md, "Mesh error and open-loop sensitivity").
    pub activation_smoothing: Option<f64>,
    /// Thelen's fibre clamp spread over a band (see
    /// [`crate::laws::FiberClampSmoothing`]) from the fibre-length lower
    /// bound, (1 + `min_fiber_length_margin`)·l_min, up by this fraction of
    /// l_min, so that a fibre can rest on its bound with its tendon slack.
    /// None (default): the model's velocity down to the bound. `leap solve`
    /// takes [`FIBER_CLAMP_BAND`] for the schemes that evaluate the
    /// dynamics at the nodes
    /// ([`crate::transcription::Scheme::evaluates_dynamics_at_nodes`]).
    pub fiber_clamp_smoothing: Option<f64>,
}

/// The default b of [`OcpOptions::activation_smoothing`].
pub const DEFAULT_ACTIVATION_SMOOTHING: f64 = 200.0;

/// The band of [`OcpOptions::fiber_clamp_smoothing`] that `leap solve`
/// takes where the scheme evaluates the dynamics at the nodes: 2% of l_min
/// above the fibre-length bound (0.4 mm for soleus).
pub const FIBER_CLAMP_BAND: f64 = 0.02;

/// [`OcpOptions::fiber_length_bounds`]' default, in optimal fibre lengths.
pub const DEFAULT_FIBER_LENGTH_BOUNDS: [f64; 2] = [0.2, 2.0];

impl Default for OcpOptions {
    fn default() -> Self {
        OcpOptions {
            smoothing: PathSmoothing::Smooth { delta: 0.02 },
            final_time_bounds: [0.1, 1.0],
            speed_bound: 30.0,
            fiber_length_bounds: DEFAULT_FIBER_LENGTH_BOUNDS,
            min_fiber_length_margin: 1e-3,
            no_countermovement_nodes: 7,
            no_com_descent: true,
            liftoff: LiftOff::default(),
            activation_smoothing: Some(DEFAULT_ACTIVATION_SMOOTHING),
            fiber_clamp_smoothing: None,
        }
    }
}

/// The jump problem could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum OcpError {
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Law(#[from] UnsupportedLaw),
    #[error(transparent)]
    Ode(#[from] OdeError),
    #[error(transparent)]
    Squat(#[from] SquatError),
    #[error("jump problem: {0}")]
    Invalid(String),
    #[error("bang-bang jump: {0}")]
    Simulation(String),
    /// The fixed start, the static squat, lies outside the problem's bounds.
    #[error(transparent)]
    StartOutOfBounds(Box<StartOutOfBounds>),
}

/// The static squat outside the problem's bounds: `bound` says whose (a
/// coordinate's range in the model file, or one of the problem's options).
#[derive(Debug, thiserror::Error)]
#[error("{file}: poses.squat: the static squat violates the bounds of {name}: {value} not in [{lower}, {upper}] ({bound})")]
pub struct StartOutOfBounds {
    pub file: String,
    pub name: String,
    pub value: f64,
    pub lower: f64,
    pub upper: f64,
    pub bound: String,
}

/// The jump problem: the state equation, its laws, the fixed start, bounds.
#[derive(Debug, Clone)]
pub struct JumpOcp {
    pub eq: StateEquation,
    pub laws: OpenSimLaws,
    /// For each model muscle, its index among the system's muscles
    /// (`eq.muscles`; usize::MAX for a mirrored one).
    pub(crate) muscle_slot: Vec<usize>,
    pub options: OcpOptions,
    /// The fixed initial node (states and excitations).
    pub squat: StaticSquat,
    /// Magnitude of the model's gravity (m/s²).
    pub gravity: f64,
    /// m·g (N).
    pub body_weight: f64,
    /// Centre-of-mass height standing (m), for reporting jump heights.
    pub standing_com_height: f64,
    pub state_lower: Vec<f64>,
    pub state_upper: Vec<f64>,
    pub control_lower: Vec<f64>,
    pub control_upper: Vec<f64>,
}

/// Where the bound of state `i` comes from (for messages): the model's
/// coordinate range, or one of the problem's settings.
fn state_bound_source(eq: &StateEquation, i: usize) -> String {
    let (n, nm) = (eq.nq(), eq.muscles.len());
    if i < n {
        format!(
            "the range of coordinates[{}] in the model file",
            eq.system.coordinates[i]
        )
    } else if i < 2 * n {
        "the problem's speed_bound".into()
    } else if i < 2 * n + nm {
        "the problem's fiber_length_bounds times the optimal fibre length, above the muscle law's minimum fibre length by min_fiber_length_margin".into()
    } else {
        format!("activations lie in [{MIN_ACTIVATION}, 1]")
    }
}

impl JumpOcp {
    /// The jump of `model`'s symmetric system from the static squat of its
    /// `squat` pose.
    pub fn new(model: &Model, options: OcpOptions) -> Result<Self, OcpError> {
        if let Some(w) = options.fiber_clamp_smoothing {
            if !(w.is_finite() && w > 0.0) {
                return Err(OcpError::Invalid(format!(
                    "fiber_clamp_smoothing: the band must be a positive fraction of l_min, got {w}"
                )));
            }
        }
        let mut laws = OpenSimLaws::new(model)?;
        for law in &mut laws.muscles {
            if let MuscleLaw::Thelen(t) = law {
                t.activation_smoothing = options.activation_smoothing;
                t.fiber_clamp_smoothing =
                    options
                        .fiber_clamp_smoothing
                        .map(|w| crate::laws::FiberClampSmoothing {
                            floor: t.min_fiber_length * (1.0 + options.min_fiber_length_margin),
                            width: w * t.min_fiber_length,
                        });
            }
        }
        let eq = StateEquation::new(model, true, options.smoothing)?;
        let pose = model.squat_pose()?;
        let squat = static_squat(&eq, &laws, &pose)?;
        Self::from_parts(eq, laws, squat, options)
    }

    /// The jump problem from its parts (the start need not be a squat).
    pub fn from_parts(
        eq: StateEquation,
        laws: OpenSimLaws,
        squat: StaticSquat,
        options: OcpOptions,
    ) -> Result<Self, OcpError> {
        let (n, nm) = (eq.nq(), eq.nm());
        let nx = eq.nx();
        if squat.x.len() != nx || squat.excitation.len() != nm {
            return Err(OcpError::Invalid(format!(
                "the start has {} states and {} excitations, the system {nx} and {nm}",
                squat.x.len(),
                squat.excitation.len()
            )));
        }
        let [t0, t1] = options.final_time_bounds;
        if !(t0.is_finite() && t1.is_finite() && 0.0 < t0 && t0 <= t1) {
            return Err(OcpError::Invalid(format!(
                "final_time_bounds: need 0 < t_min ≤ t_max, got [{t0}, {t1}]"
            )));
        }
        if options.speed_bound.is_nan() || options.speed_bound <= 0.0 {
            return Err(OcpError::Invalid(format!(
                "speed_bound: must be positive, got {}",
                options.speed_bound
            )));
        }
        let [f0, f1] = options.fiber_length_bounds;
        if !(0.0 <= f0 && f0 < f1 && f1.is_finite()) {
            return Err(OcpError::Invalid(format!(
                "fiber_length_bounds: need 0 ≤ lower < upper, got [{f0}, {f1}]"
            )));
        }
        let fraction = options.liftoff.fraction();
        if !(fraction.is_finite() && fraction >= 0.0) {
            return Err(OcpError::Invalid(format!(
                "liftoff: the force fraction must be ≥ 0, got {fraction}"
            )));
        }
        let model = &eq.model;
        let gravity =
            (model.gravity[0].powi(2) + model.gravity[1].powi(2) + model.gravity[2].powi(2)).sqrt();
        if gravity.is_nan() || gravity <= 0.0 {
            return Err(OcpError::Invalid(format!(
                "{}: gravity is zero; the jump objective needs g > 0",
                model.file.display()
            )));
        }
        let body_weight = model.total_mass() * gravity;
        let mut lo = vec![0.0; nx];
        let mut hi = vec![0.0; nx];
        for (i, &c) in eq.system.coordinates.iter().enumerate() {
            let [a, b] = model.coordinates[c].range;
            lo[i] = a;
            hi[i] = b;
            lo[n + i] = -options.speed_bound;
            hi[n + i] = options.speed_bound;
        }
        let mut ulo = vec![0.0; nm];
        let uhi = vec![1.0; nm];
        for (k, &mi) in eq.muscles.iter().enumerate() {
            let spec = &model.muscles[mi].spec;
            let lopt = spec.optimal_fiber_length;
            let (lmin, umin) = match &laws.muscles[mi] {
                MuscleLaw::Thelen(t) => (t.min_fiber_length, laws.muscles[mi].min_excitation()),
                MuscleLaw::DeGroote(_) => (
                    lopt * spec.pennation_angle_at_optimal.sin(),
                    laws.muscles[mi].min_excitation(),
                ),
            };
            lo[2 * n + k] = (f0 * lopt).max(lmin * (1.0 + options.min_fiber_length_margin));
            hi[2 * n + k] = f1 * lopt;
            lo[2 * n + nm + k] = MIN_ACTIVATION;
            hi[2 * n + nm + k] = 1.0;
            ulo[k] = umin;
        }
        let names = eq.state_names();
        for i in 0..nx {
            if !(lo[i] <= squat.x[i] && squat.x[i] <= hi[i]) {
                return Err(OcpError::StartOutOfBounds(Box::new(StartOutOfBounds {
                    file: eq.model.file.display().to_string(),
                    name: names[i].clone(),
                    value: squat.x[i],
                    lower: lo[i],
                    upper: hi[i],
                    bound: state_bound_source(&eq, i),
                })));
            }
        }
        let cnames = eq.control_names();
        for k in 0..nm {
            let v = squat.excitation[k];
            if !(ulo[k] <= v && v <= uhi[k]) {
                return Err(OcpError::StartOutOfBounds(Box::new(StartOutOfBounds {
                    file: eq.model.file.display().to_string(),
                    name: cnames[k].clone(),
                    value: v,
                    lower: ulo[k],
                    upper: uhi[k],
                    bound: "excitations lie between the muscle's minimum and 1".into(),
                })));
            }
        }
        let standing_com_height = crate::simulate::standing_com_height(&eq);
        let mut muscle_slot = vec![usize::MAX; laws.muscles.len()];
        for (k, &mi) in eq.muscles.iter().enumerate() {
            muscle_slot[mi] = k;
        }
        Ok(JumpOcp {
            eq,
            laws,
            muscle_slot,
            options,
            squat,
            gravity,
            body_weight,
            standing_com_height,
            state_lower: lo,
            state_upper: hi,
            control_lower: ulo,
            control_upper: uhi,
        })
    }

    pub fn nq(&self) -> usize {
        self.eq.nq()
    }

    /// Where state `i`'s bound comes from (for messages).
    pub fn state_bound_source(&self, i: usize) -> String {
        state_bound_source(&self.eq, i)
    }
    pub fn nm(&self) -> usize {
        self.eq.nm()
    }
    pub fn nx(&self) -> usize {
        self.eq.nx()
    }
    /// Excitations (= muscles carried).
    pub fn nu(&self) -> usize {
        self.eq.nm()
    }

    /// The fixed initial state and excitations.
    pub fn x0(&self) -> &[f64] {
        &self.squat.x
    }
    pub fn u0(&self) -> &[f64] {
        &self.squat.excitation
    }

    /// Y_C, Ẏ_C and J = Y_C + Ẏ_C²/(2g) at state x (eq. 3).
    pub fn jump_objective<S: Scalar>(
        &self,
        ws: &mut crate::multibody::Workspace<S>,
        x: &[S],
    ) -> (S, S, S) {
        let n = self.nq();
        self.eq.multibody.set_state(ws, &x[..n], &x[n..2 * n]);
        let y = self.eq.multibody.com_position(ws)[1];
        let v = self.eq.multibody.com_velocity(ws)[1];
        (y, v, y + v * v * (0.5 / self.gravity))
    }

    /// ẋ = f(x, u) into `xdot`, and the node outputs the constraints use:
    /// Ÿ_C (m/s², from q, q̇ and the q̈ just computed) and the total vertical
    /// ground force over body weight.
    pub fn state_rates<S: Scalar>(
        &self,
        ws: &mut StateWorkspace<S>,
        x: &[S],
        u: &[S],
        xdot: &mut [S],
    ) -> Result<(S, S), OdeError>
    where
        OpenSimLaws: ForceLaws<S>,
    {
        self.state_rates_with(&self.laws, ws, x, u, xdot)
    }

    /// [`JumpOcp::state_rates`] under other force laws (the implicit fibre
    /// dynamics' [`crate::laws::BalanceLaws`]).
    pub fn state_rates_with<S: Scalar, L: ForceLaws<S>>(
        &self,
        laws: &L,
        ws: &mut StateWorkspace<S>,
        x: &[S],
        u: &[S],
        xdot: &mut [S],
    ) -> Result<(S, S), OdeError> {
        let n = self.nq();
        self.eq.rhs(laws, ws, x, u, xdot)?;
        let ydd = self.eq.multibody.com_acceleration(&ws.mb, &xdot[n..2 * n])[1];
        Ok((
            ydd,
            vertical_ground_force_bw(&ws.sphere_force, self.body_weight),
        ))
    }

    /// The same rates as [`JumpOcp::state_rates`] computed by Simbody
    /// ([`SimbodyRates`]).
    pub fn simbody_rates(&self) -> Result<SimbodyRates, crate::simbody::SimbodyError> {
        SimbodyRates::new(self)
    }

    /// Bounds of the lift-off row F_y(t_f)/(m g).
    pub fn liftoff_bounds(&self) -> (f64, f64) {
        match self.options.liftoff {
            LiftOff::ForceAtMost { fraction } => (f64::NEG_INFINITY, fraction),
            LiftOff::ForceEquals { fraction } => (fraction, fraction),
        }
    }

    /// The built-in bang-bang pattern (as `leap simulate`): the muscles that
    /// extend the joints at the squat pose fully on from t = 0, the others
    /// at the minimum excitation.
    pub fn bang_bang(&self) -> BangBang {
        let pose = self.eq.system.model_from_q(&self.squat.x[..self.nq()]);
        let ext = extensor_moments(&self.eq, &pose);
        BangBang {
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
            off_level: MIN_ACTIVATION,
        }
    }

    /// Integrate the bang-bang jump from the fixed start with the
    /// Rust-native Dormand–Prince 5(4) (`accuracy` as `leap simulate`).
    pub fn simulate_bang_bang(
        &self,
        accuracy: f64,
    ) -> Result<(JumpSummary, Trajectory), Box<SimulationFailure>> {
        let opts = SimulateOptions {
            integrator: crate::integrator::Dopri5Options {
                accuracy,
                ..Default::default()
            },
            t_max: 2.0,
        };
        simulate_rust(
            &self.eq,
            &self.laws,
            &self.bang_bang(),
            &self.squat.x,
            self.standing_com_height,
            opts,
        )
    }
}

/// The vertical ground force on the contact spheres in body weights (the
/// lift-off row's F_y/(m g)), from each sphere's force.
fn vertical_ground_force_bw<S: Scalar>(sphere_force: &[[S; 3]], body_weight: f64) -> S {
    let mut fy = S::zero();
    for f in sphere_force {
        fy += f[1];
    }
    fy * (1.0 / body_weight)
}

/// The point rates of [`JumpOcp::state_rates_with`], ẋ = f(x, u), Ÿ_C and
/// F_y/(m g), evaluated by Simbody: q and q̇ in Simbody's multibody system,
/// the muscle states as its auxiliary states, the muscle, contact and
/// ligament laws (the problem's, with its smoothing) inside a Simbody force
/// element from Simbody's kinematics ([`crate::ode::SimbodyStateEquation`]),
/// Ÿ_C Simbody's mass-centre acceleration. Inputs beyond the excitations
/// are normalised fibre velocities: the fibre-length rows are then the
/// force balances (implicit fibre dynamics), as in the Rust-native rates.
pub struct SimbodyRates {
    sb: crate::ode::SimbodyStateEquation,
    laws: std::sync::Arc<crate::laws::SettableBalanceLaws>,
    spheres: Vec<[f64; 3]>,
    nu: usize,
    body_weight: f64,
}

impl SimbodyRates {
    fn new(ocp: &JumpOcp) -> Result<Self, crate::simbody::SimbodyError> {
        let laws = std::sync::Arc::new(crate::laws::SettableBalanceLaws {
            laws: ocp.laws.clone(),
            slot: ocp.muscle_slot.clone(),
            vn: std::sync::Mutex::new(Vec::new()),
        });
        let sb = crate::ode::SimbodyStateEquation::new(
            std::sync::Arc::new(ocp.eq.clone()),
            laws.clone(),
        )?;
        let ns = ocp.eq.model.contact.as_ref().map_or(0, |c| c.spheres.len());
        Ok(SimbodyRates {
            sb,
            laws,
            spheres: vec![[0.0; 3]; ns],
            nu: ocp.nu(),
            body_weight: ocp.body_weight,
        })
    }

    /// ẋ into `xdot` and (Ÿ_C, F_y/(m g)) at (x, u).
    pub fn eval(&mut self, x: &[f64], u: &[f64], xdot: &mut [f64]) -> Result<(f64, f64), String> {
        let nu = self.nu.min(u.len());
        {
            let mut vn = self
                .laws
                .vn
                .lock()
                .map_err(|_| "fibre velocity lock poisoned".to_string())?;
            vn.clear();
            vn.extend_from_slice(&u[nu..]);
        }
        self.sb.rhs(x, &u[..nu], xdot).map_err(|e| e.to_string())?;
        let ydd = self
            .sb
            .simbody
            .com_acceleration()
            .map_err(|e| e.to_string())?[1];
        self.sb
            .sphere_forces(&mut self.spheres)
            .map_err(|e| e.to_string())?;
        Ok((
            ydd,
            vertical_ground_force_bw(&self.spheres, self.body_weight),
        ))
    }
}
