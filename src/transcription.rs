//! Direct collocation of the jump problem ([`crate::ocp::JumpOcp`]) as a
//! sparse nonlinear program ([`crate::nlp::Nlp`]), after Porsa, Lin & Pandy
//! (2016, eq. 7).
//!
//! **Mesh.** N uniform intervals (Moco's `num_mesh_intervals`, default 28)
//! on [0, t_f], nodes t_k = k·h, h = t_f/N, k = 0..N. Node 0 is the fixed
//! static squat and carries no variables.
//!
//! **Variables** (n = N·(n_x + n_u) + 1 = 2,409 for the paper's problem):
//! `[x_1, u_1, x_2, u_2, …, x_N, u_N, t_f]` with x_k the 62 states and u_k
//! the 24 excitations of node k.
//!
//! **Constraints** (m = N·n_x + n_cm + 1 = 1,744):
//! - defects of interval k = 1..N (equalities, N·62 = 1,736 rows), see
//!   [`Scheme`]:
//!   - midpoint Euler (eq. 7, default):
//!     d_k = x_k − x_{k−1} − h·f((x_{k−1} + x_k)/2, (u_{k−1} + u_k)/2);
//!   - trapezoidal: d_k = x_k − x_{k−1} − (h/2)·(f(x_{k−1}, u_{k−1}) + f(x_k, u_k));
//!   - Hermite–Simpson (compressed): d_k = x_k − x_{k−1} − (h/6)·(f_{k−1} + 4 f_c + f_k);
//!   - with [`FiberDynamics::Implicit`] (midpoint Euler) the fibre-length
//!     rows are the muscle-tendon force balances at the midpoint instead,
//!     with the interval's fibre velocity (l^M_k − l^M_{k−1})/h as an input:
//!     the same variables and solutions, a row smooth in the activation;
//! - no countermovement (eq. 4), row j = 0..n_cm−1:
//!   Ÿ_C(t_j) − Ÿ_C(t_{j+1}) ≤ 0 (Ÿ_C from q, q̇ and q̈ = f(x, u) at the node);
//! - lift-off: F_y(t_f)/(m g) ≤ ε (or = ε), see [`crate::ocp::LiftOff`];
//! - no descent (with [`crate::ocp::OcpOptions::no_com_descent`], default):
//!   Ẏ_C(t_k) ≥ 0 at nodes k = 1..N (rows after the lift-off row; Ẏ_C from
//!   the node's q and q̇).
//!
//! **Objective**: −J = −(Y_C(t_f) + Ẏ_C(t_f)²/(2g)) (eq. 3).
//!
//! **Derivatives.** Exact, from forward dual numbers (num-dual
//! `DualSVec64<8>`, 8 directions per pass) through the Rust-native state
//! equation. Each defect block depends only on its two nodes and t_f:
//!
//! ```text
//!   ∂d_k/∂(x,u)_{k−1} = −[I 0] − (h/2)·F,   ∂d_k/∂(x,u)_k = [I 0] − (h/2)·F,
//!   ∂d_k/∂t_f = −f/N   (trapezoidal: −(f_{k−1} + f_k)/(2N), F at each node)
//! ```
//!
//! with F = ∂f/∂(x, u) at the midpoint (or node), whose sparsity
//! ([`StatePattern`]) is a structural superset found once per problem:
//! q̇ rows are the identity on q̇; q̈ rows are dense over q, q̇ and every fibre
//! length (the mass matrix couples all coordinates); a fibre-length row
//! depends on the muscle's own l^M and a and on the coordinates its path
//! spans; an activation row on a_i and u_i; united with every entry found
//! above roundoff at random states in and out of ground contact. For the
//! jumper that is 399 of the 5,332 entries (Porsa et al. count 406; the
//! difference is which coordinates the 24 paths span), 874 non-zeros per
//! midpoint or trapezoidal defect block (2·(382 + 24) node columns + 62 in
//! the t_f column) and 24,574 in the whole Jacobian. The columns of F are
//! compressed by a greedy colouring (columns that share no row share a dual
//! direction; Curtis, Powell & Reid 1974): 38 directions instead of 86,
//! since the q̈ rows need q, q̇ and l^M apart while every a_i and u_i fits
//! beside them.
//!
//! **Hessians.** Exact element Hessians of the Lagrangian from hyper-dual
//! passes at the same points (see `HESS_Q`): per group of defect rows
//! with the same node columns (midpoint, trapezoidal, backward Euler), per
//! interval for Hermite–Simpson, whose centre state couples every row to
//! the dynamics at both nodes (`hermite_simpson_hessian`).
//!
//! **Threads.** The Jacobian's point evaluations (28 midpoints plus the
//! nodes of the path rows) are split between [`TranscriptionOptions::threads`]
//! scoped threads; constraint values run on the calling thread.

use crate::hyperdual::HyperDualS;
use crate::nlp::{Element, EvalError, Nlp};
use crate::ocp::JumpOcp;
use crate::ode::{GivenPaths, StateWorkspace};
use crate::scalar::Dual64;
use crate::simulate::{JumpSummary, SimulationFailure};
use num_dual::{DualSVec64, HyperDual64};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::Arc;

/// Dual directions per pass of the Jacobian evaluation (see
/// [`time_point_jacobian`] for the measurements behind the choice).
pub const LANES: usize = 8;

/// Lanes of a point Jacobian of direct shooting ([`PointJacobian`]): with
/// the paths walked once per point, the jump's 38 colours take two passes
/// (gait2392's jumper, `transcription::timing`: 55 µs per point against
/// 68 µs with 8 lanes and 89 µs with 8 lanes and the paths walked in every
/// pass).
const POINT_LANES: usize = 19;

/// The collocation scheme of the defects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Scheme {
    /// x_k − x_{k−1} − h·f(x̄, ū) with x̄, ū the interval means (Porsa et al. eq. 7).
    MidpointEuler,
    /// x_k − x_{k−1} − (h/2)·(f_{k−1} + f_k).
    Trapezoidal,
    /// Hermite–Simpson in compressed form (the centre state eliminated, the
    /// centre excitations the mean, as Moco's `hermite-simpson` with
    /// `interpolate_control_mesh_interior_points`):
    /// x_k − x_{k−1} − (h/6)·(f_{k−1} + 4 f_c + f_k), f_c = f(x_c, u_c),
    /// x_c = (x_{k−1} + x_k)/2 + (h/8)·(f_{k−1} − f_k), u_c = (u_{k−1} + u_k)/2.
    HermiteSimpson,
    /// x_k − x_{k−1} − h·f(x_k, u_k) (implicit Euler; Ackermann & van den
    /// Bogert 2010). First order, but L-stable: the stiff foot contact
    /// cannot ring from node to node, and the dynamics, ground force and
    /// lift-off condition all hold at the nodes that are reported.
    BackwardEuler,
}

impl Scheme {
    /// Whether the defects evaluate the dynamics at the mesh nodes (all
    /// but midpoint Euler, which evaluates them at the interval means):
    /// there a fibre may rest on its lower bound with its tendon slack, on
    /// Thelen's clamp (see [`crate::ocp::OcpOptions::fiber_clamp_smoothing`]).
    pub fn evaluates_dynamics_at_nodes(self) -> bool {
        self != Scheme::MidpointEuler
    }
}

/// How the defects state the fibre dynamics of the muscles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum FiberDynamics {
    /// The fibre-length defect l^M_k − l^M_{k−1} − h·v^M(x̄, ū), with v^M
    /// from the muscle's inverted force–velocity curve (OpenSim's explicit
    /// Thelen2003Muscle; the paper's eq. 7).
    #[default]
    Explicit,
    /// The force balance at the midpoint, with the interval's fibre velocity
    /// v̄ = (l^M_k − l^M_{k−1})/h in place of the inverted curve:
    /// f_T − (a·f_al·f_v(v̄/(v_max l_o)) + f_pe)·cos φ = 0 (units of F_0;
    /// [`crate::laws::Thelen::force_balance`]). The variables and the
    /// solutions are those of the explicit form (the two rows vanish
    /// together), but the row is smooth in a: the explicit row's 1/a
    /// (Thelen's inverted curve at the minimum activation) is gone. As
    /// Moco's implicit muscle dynamics; midpoint Euler only.
    Implicit,
}

/// Where the state equation of the points is evaluated, and how its
/// Jacobian is found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum Backend {
    /// Leap's Rust-native dynamics, the Jacobian exact from coloured dual
    /// numbers (default).
    #[default]
    RustNative,
    /// Simbody's multibody system with the same force laws in a Simbody
    /// force element ([`crate::ocp::SimbodyRates`]), the Jacobian by central
    /// differences over the same column colouring: the cross-check path of
    /// the Rust-native derivatives. Each column c of a colour moves by
    /// ±[`FD_STEP`]·max(1, |v_c|) and by half that at once (columns of one
    /// colour share no row), the two differences extrapolated. The Hessians
    /// stay the Rust-native ones: they steer the steps, and the solution is
    /// the point where the Simbody rows and their Jacobian satisfy the
    /// optimality conditions.
    Simbody,
}

/// Central-difference step of [`Backend::Simbody`] in input c:
/// `FD_STEP`·max(1, |v_c|), with Richardson's extrapolation from it and
/// its half. Far below the textbook steps (∛ε ≈ 6e-6 for plain central
/// differences, ε^(1/5) ≈ 7e-4 with the extrapolation): the muscles' curves
/// bend on scales far below their variables' (a tendon's toe region spans
/// fractions of a millimetre of fibre length), so truncation, not
/// rounding, dominates. Measured on the jump (test
/// `simbody_backend_matches_rust_native_rows_and_jacobian`, perturbed
/// bang-bang guesses, entries against the exact Jacobian relative to their
/// row's largest): plain central differences of step 6e-6 left 1,165 of
/// 24,966 entries above 1e-6, 1e-7 left 50; extrapolated, 1e-5 and 1e-6
/// left 238 and 10, 1e-7 none (worst 2.6e-7 in midpoint Euler, implicit
/// fibre dynamics and Hermite–Simpson).
pub const FD_STEP: f64 = 1e-7;

/// How [`Backend::Simbody`] differences its columns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Differences {
    /// Central differences of relative steps h and h/2, extrapolated
    /// (default, h = [`FD_STEP`]).
    Central {
        step: f64,
    },
    /// One-sided, (g(x + h) − g(x))/h: with `Backward`, the two sides of a
    /// kink where the derivative jumps (a clamp, a slack tendon), which
    /// central differences average.
    Forward {
        step: f64,
    },
    Backward {
        step: f64,
    },
}

/// Settings of the transcription.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TranscriptionOptions {
    /// Mesh intervals N (Moco's name); N + 1 nodes.
    pub num_mesh_intervals: usize,
    pub scheme: Scheme,
    /// The fibre-length rows (default explicit).
    #[serde(default)]
    pub fiber_dynamics: FiberDynamics,
    /// Threads of the Jacobian evaluation (its points are split between
    /// them); constraint values always run on the calling thread.
    pub threads: usize,
    /// Compress the columns of ∂f/∂(x, u) by colouring (exact given a
    /// complete pattern); false evaluates every column separately.
    pub compress_columns: bool,
    /// Random states at which the pattern of ∂f/∂(x, u) is sampled.
    pub pattern_samples: usize,
    pub pattern_seed: u64,
    /// Where the points' state equation is evaluated (default Rust-native).
    #[serde(default)]
    pub backend: Backend,
}

impl Default for TranscriptionOptions {
    fn default() -> Self {
        TranscriptionOptions {
            num_mesh_intervals: 28,
            scheme: Scheme::MidpointEuler,
            fiber_dynamics: FiberDynamics::Explicit,
            threads: 2,
            compress_columns: true,
            pattern_samples: 60,
            pattern_seed: 1,
            backend: Backend::RustNative,
        }
    }
}

/// The transcription could not be built, or a guess not made.
#[derive(Debug, thiserror::Error)]
pub enum TranscriptionError {
    #[error("transcription: {0}")]
    Invalid(String),
    #[error("transcription: sparsity of ∂f/∂(x, u): {0}")]
    Pattern(String),
    #[error("initial guess: {0}")]
    Guess(String),
    #[error("initial guess: bang-bang jump: {0}")]
    Simulation(Box<SimulationFailure>),
}

/// The sparsity of the node outputs g(x, u) = (f(x, u), Ÿ_C, F_y/(m g))
/// with respect to (x, u): rows 0..n_x are f, row n_x is Ÿ_C, row n_x + 1
/// the lift-off force; columns 0..n_x are x, then u. With implicit fibre
/// dynamics the fibre-length rows are the force balances and u holds the
/// excitations and then the normalised fibre velocities (`nu` = 2·n_m).
#[derive(Debug, Clone, PartialEq)]
pub struct StatePattern {
    pub nx: usize,
    pub nu: usize,
    /// Per output row, its columns (increasing).
    pub rows: Vec<Vec<usize>>,
    /// Sample states evaluated, and those the model rejected.
    pub samples_used: usize,
    pub samples_rejected: usize,
}

impl StatePattern {
    /// Entries of ∂f/∂(x, u) (the 62 rows of f only; the paper's count).
    pub fn nnz_f(&self) -> usize {
        self.rows[..self.nx].iter().map(|r| r.len()).sum()
    }

    /// Whether output row `r` may depend on input column `c`.
    pub fn contains(&self, r: usize, c: usize) -> bool {
        self.rows[r].binary_search(&c).is_ok()
    }

    /// The pattern of `ocp`'s state equation: the structural part (see the
    /// module documentation; a fibre-length row gets every coordinate its
    /// muscle-tendon length depends on at any sample) united with every
    /// entry above [`ROUNDOFF`] in exact dual Jacobians at `samples` random
    /// states (seed `seed`): a third anywhere inside the bounds (speeds up
    /// to 5) with the feet placed from 1 cm above to 1 cm into the ground, a
    /// third with random heights and full speeds, a third near the static
    /// squat (in contact). [`StatePattern::violations`] checks the result at
    /// fresh states.
    pub fn detect(ocp: &JumpOcp, samples: usize, seed: u64) -> Result<Self, TranscriptionError> {
        Self::detect_for(ocp, FiberDynamics::Explicit, samples, seed)
    }

    /// [`StatePattern::detect`] for the given fibre dynamics.
    pub fn detect_for(
        ocp: &JumpOcp,
        fiber: FiberDynamics,
        samples: usize,
        seed: u64,
    ) -> Result<Self, TranscriptionError> {
        let (n, nm) = (ocp.nq(), ocp.nm());
        let nx = ocp.nx();
        let nu = point_inputs(ocp, fiber);
        let (nin, nout) = (nx + nu, nx + 2);
        if samples < 3 {
            return Err(TranscriptionError::Pattern(format!(
                "pattern_samples = {samples}: at least 3 sample states are needed (the coordinates each muscle path spans are found at them)"
            )));
        }
        let mut found = vec![vec![false; nin]; nout];
        // Structural part.
        for i in 0..n {
            found[i][n + i] = true;
            for c in 0..2 * n + nm {
                found[n + i][c] = true;
            }
        }
        for k in 0..nm {
            found[2 * n + k][2 * n + k] = true;
            found[2 * n + k][2 * n + nm + k] = true;
            found[2 * n + nm + k][2 * n + nm + k] = true;
            found[2 * n + nm + k][nx + k] = true;
            if nu > ocp.nu() {
                found[2 * n + k][nx + ocp.nu() + k] = true;
            }
        }
        for c in 0..2 * n {
            found[nx][c] = true;
            found[nx + 1][c] = true;
        }
        // Sampled part: dense dual Jacobians.
        let dense = Compiled::new(&vec![(0..nin).collect::<Vec<_>>(); nout], nin, false, LANES);
        let mut w = Worker::<LANES>::new(ocp, nu);
        let mut out = vec![0.0; nout];
        let mut jac = vec![0.0; dense.entries.len()];
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (mut used, mut rejected) = (0, 0);
        for s in 0..samples {
            sample_state(ocp, s % 3, &mut rng, &mut w.x, &mut w.u);
            match eval_jac(
                ocp,
                &dense,
                &mut w,
                &mut out,
                &mut jac,
                Some(&mut found),
                None,
            ) {
                Ok(()) => used += 1,
                Err(_) => {
                    rejected += 1;
                    continue;
                }
            }
            mark_significant(&dense, &jac, nin, |r, c, _| found[r][c] = true);
        }
        if used == 0 {
            return Err(TranscriptionError::Pattern(format!(
                "the model rejected all {samples} sample states"
            )));
        }
        // Ÿ_C depends on whatever q̈ depends on.
        for i in 0..n {
            for c in 0..nin {
                if found[n + i][c] {
                    found[nx][c] = true;
                }
            }
        }
        let rows = found
            .iter()
            .map(|r| (0..nin).filter(|&c| r[c]).collect())
            .collect();
        Ok(StatePattern {
            nx,
            nu,
            rows,
            samples_used: used,
            samples_rejected: rejected,
        })
    }

    /// Entries outside the pattern that are significant (see
    /// [`ROUNDOFF`]) at `samples` fresh random states (seed `seed`):
    /// (row, column, largest |∂g_r/∂c| / max_c' |∂g_r/∂c'|). Empty when the
    /// pattern holds there.
    pub fn violations(&self, ocp: &JumpOcp, samples: usize, seed: u64) -> Vec<(usize, usize, f64)> {
        let (nx, nu) = (self.nx, self.nu);
        let (nin, nout) = (nx + nu, nx + 2);
        let dense = Compiled::new(&vec![(0..nin).collect::<Vec<_>>(); nout], nin, false, LANES);
        let mut w = Worker::<LANES>::new(ocp, nu);
        let mut out = vec![0.0; nout];
        let mut jac = vec![0.0; dense.entries.len()];
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut worst = vec![0.0f64; nout * nin];
        for s in 0..samples {
            sample_state(ocp, s % 3, &mut rng, &mut w.x, &mut w.u);
            if eval_jac(ocp, &dense, &mut w, &mut out, &mut jac, None, None).is_err() {
                continue;
            }
            mark_significant(&dense, &jac, nin, |r, c, ratio| {
                if !self.contains(r, c) {
                    worst[r * nin + c] = worst[r * nin + c].max(ratio);
                }
            });
        }
        (0..nout * nin)
            .filter(|&i| worst[i] > 0.0)
            .map(|i| (i / nin, i % nin, worst[i]))
            .collect()
    }
}

/// Entries of a sampled Jacobian below this fraction of their row's
/// largest entry count as roundoff: a muscle-tendon length computed from
/// ground-frame point positions depends on the floating-base coordinates
/// (and a knee muscle's on the hip angle) by ~1e-16 relative, although it
/// depends mathematically only on the joint angles its path spans.
pub const ROUNDOFF: f64 = 1e-10;

/// Call `mark(row, column, |J_rc| / max_c' |J_rc'|)` for every entry of a
/// dense sampled Jacobian above [`ROUNDOFF`] relative to its row (and every
/// non-finite entry).
fn mark_significant(
    dense: &Compiled,
    jac: &[f64],
    nin: usize,
    mut mark: impl FnMut(usize, usize, f64),
) {
    for r in 0..dense.row_start.len() - 1 {
        let row = &jac[r * nin..(r + 1) * nin];
        let big = row
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for (c, &v) in row.iter().enumerate() {
            if !v.is_finite() {
                mark(r, c, f64::INFINITY);
            } else if v != 0.0 && v.abs() > ROUNDOFF * big {
                mark(r, c, v.abs() / big);
            }
        }
    }
}

/// Moment arms below this (m/rad or m/m) are roundoff (see [`ROUNDOFF`]).
const PATH_ROUNDOFF: f64 = 1e-9;

/// A random state and excitation for pattern detection (`kind` 0, 1, 2:
/// feet near the ground, anywhere, near the squat).
fn sample_state(ocp: &JumpOcp, kind: usize, rng: &mut ChaCha8Rng, x: &mut [f64], u: &mut [f64]) {
    let (n, nm) = (ocp.nq(), ocp.nm());
    let (lo, hi) = (&ocp.state_lower, &ocp.state_upper);
    let mut uni = |a: f64, b: f64| if b > a { rng.random_range(a..=b) } else { a };
    for i in 0..n {
        if kind == 2 {
            x[i] = ocp.squat.x[i] + uni(-0.15, 0.15);
            x[n + i] = uni(-3.0, 3.0);
        } else {
            // Ranges beyond ±π say nothing new about a rotation.
            x[i] = uni(
                lo[i].max(-std::f64::consts::PI),
                hi[i].min(std::f64::consts::PI),
            );
            let s = if kind == 0 {
                ocp.options.speed_bound.min(5.0)
            } else {
                ocp.options.speed_bound
            };
            x[n + i] = uni(-s, s);
        }
    }
    for k in 0..nm {
        let j = 2 * n + k;
        x[j] = if kind == 2 {
            (ocp.squat.x[j] * uni(0.9, 1.1)).clamp(lo[j], hi[j])
        } else {
            uni(lo[j], hi[j])
        };
        let a = 2 * n + nm + k;
        x[a] = uni(lo[a], hi[a]);
        u[k] = uni(ocp.control_lower[k], ocp.control_upper[k]);
    }
    // Normalised fibre velocities of the implicit form.
    for v in u.iter_mut().skip(ocp.nu()) {
        *v = uni(-1.0, 1.0);
    }
    if kind != 1 {
        let depth = if kind == 0 {
            uni(-0.01, 0.01)
        } else {
            uni(0.0, 0.01)
        };
        place_feet(ocp, x, depth);
    }
}

/// Shift pelvis_ty so that the lowest contact sphere reaches `depth` into
/// the ground (negative: above it). No-op without contact or pelvis_ty.
fn place_feet(ocp: &JumpOcp, x: &mut [f64], depth: f64) {
    let eq = &ocp.eq;
    let n = eq.nq();
    let (Some(contact), Some(c)) = (&eq.model.contact, eq.model.coordinate_index("pelvis_ty"))
    else {
        return;
    };
    let ty = eq.system.q_of_model_coordinate[c];
    let mut ws = eq.multibody.workspace::<f64>();
    for _ in 0..3 {
        eq.multibody.set_state(&mut ws, &x[..n], &x[n..2 * n]);
        let lowest = crate::ode::lowest_sphere_bottom(&eq.multibody, &ws, contact);
        if !lowest.is_finite() {
            return;
        }
        x[ty] += -depth - lowest;
    }
}

/// A row-major sparse pattern with its dual seeding plan.
#[derive(Debug, Clone)]
struct Compiled {
    /// (row, column), row-major; the position is the entry index.
    entries: Vec<(usize, usize)>,
    row_start: Vec<usize>,
    num_colors: usize,
    passes: Vec<Pass>,
}

#[derive(Debug, Clone, Default)]
struct Pass {
    /// Input columns seeded in this pass and their lane.
    seeds: Vec<(usize, usize)>,
    /// (entry, row, lane) read after this pass.
    extract: Vec<(usize, usize, usize)>,
}

impl Compiled {
    fn new(rows: &[Vec<usize>], nin: usize, compress: bool, lanes: usize) -> Self {
        let lanes = lanes.max(1);
        let mut entries = Vec::new();
        let mut row_start = vec![0];
        for (r, cols) in rows.iter().enumerate() {
            for &c in cols {
                entries.push((r, c));
            }
            row_start.push(entries.len());
        }
        // Greedy colouring: columns sharing a row get different colours.
        let mut color = vec![usize::MAX; nin];
        if compress {
            let mut rows_of = vec![Vec::new(); nin];
            for &(r, c) in &entries {
                rows_of[c].push(r);
            }
            let mut forbidden = vec![usize::MAX; nin];
            for j in 0..nin {
                for &r in &rows_of[j] {
                    for &c in &rows[r] {
                        if color[c] != usize::MAX {
                            forbidden[color[c]] = j;
                        }
                    }
                }
                color[j] = (0..nin).find(|&k| forbidden[k] != j).unwrap_or(j);
            }
        } else {
            for (j, c) in color.iter_mut().enumerate() {
                *c = j;
            }
        }
        let num_colors = color.iter().map(|&c| c + 1).max().unwrap_or(0);
        let mut passes = vec![Pass::default(); num_colors.div_ceil(lanes)];
        for j in 0..nin {
            passes[color[j] / lanes].seeds.push((j, color[j] % lanes));
        }
        for (e, &(r, c)) in entries.iter().enumerate() {
            passes[color[c] / lanes]
                .extract
                .push((e, r, color[c] % lanes));
        }
        Compiled {
            entries,
            row_start,
            num_colors,
            passes,
        }
    }

    /// Entry index of (r, c), if in the pattern.
    fn entry(&self, r: usize, c: usize) -> Option<usize> {
        let s = self.row_start[r];
        self.entries[s..self.row_start[r + 1]]
            .binary_search_by_key(&c, |&(_, cc)| cc)
            .ok()
            .map(|i| s + i)
    }
}

/// Buffers of one evaluation thread.
struct Worker<const W: usize> {
    ws: StateWorkspace<f64>,
    wd: StateWorkspace<DualSVec64<W>>,
    x: Vec<f64>,
    u: Vec<f64>,
    xdot: Vec<f64>,
    xd: Vec<DualSVec64<W>>,
    ud: Vec<DualSVec64<W>>,
    xdotd: Vec<DualSVec64<W>>,
    /// [`Backend::Simbody`]'s evaluator.
    simbody: Option<SimbodyPoint>,
}

/// A point's evaluator under [`Backend::Simbody`]: the Simbody rates, g at
/// x + h and x − h, and the point's inputs (x, u).
struct SimbodyPoint {
    rates: crate::ocp::SimbodyRates,
    /// How columns are differenced (central of [`FD_STEP`] unless set).
    differences: Differences,
    gp: Vec<f64>,
    gm: Vec<f64>,
    base: Vec<f64>,
}

impl<const W: usize> Worker<W> {
    /// A worker for `nu` point inputs u ([`point_inputs`]).
    fn new(ocp: &JumpOcp, nu: usize) -> Self {
        let nx = ocp.nx();
        let z = DualSVec64::<W>::from(0.0);
        Worker {
            ws: ocp.eq.workspace(),
            wd: ocp.eq.workspace(),
            x: vec![0.0; nx],
            u: vec![0.0; nu],
            xdot: vec![0.0; nx],
            xd: vec![z; nx],
            ud: vec![z; nu],
            xdotd: vec![z; nx],
            simbody: None,
        }
    }

    /// A worker evaluating the points by `backend`.
    fn with_backend(ocp: &JumpOcp, nu: usize, backend: Backend) -> Result<Self, String> {
        let mut w = Self::new(ocp, nu);
        if backend == Backend::Simbody {
            let rates = ocp
                .simbody_rates()
                .map_err(|e| format!("backend simbody: the Simbody system cannot be built: {e}"))?;
            let nout = ocp.nx() + 2;
            w.simbody = Some(SimbodyPoint {
                rates,
                differences: Differences::Central { step: FD_STEP },
                gp: vec![0.0; nout],
                gm: vec![0.0; nout],
                base: vec![0.0; ocp.nx() + nu],
            });
        }
        Ok(w)
    }
}

/// The point inputs u per point: the excitations, and with implicit fibre
/// dynamics the normalised fibre velocities after them.
fn point_inputs(ocp: &JumpOcp, fiber: FiberDynamics) -> usize {
    match fiber {
        FiberDynamics::Explicit => ocp.nu(),
        FiberDynamics::Implicit => ocp.nu() + ocp.nm(),
    }
}

/// ẋ = f(x, u) into `xdot` and (Ÿ_C, F_y/(m g)); where u holds more than
/// the excitations, the fibre-length rows are the force balances at the
/// normalised fibre velocities u[n_u..] ([`FiberDynamics::Implicit`]).
fn point_rates<S: crate::scalar::Scalar>(
    ocp: &JumpOcp,
    ws: &mut StateWorkspace<S>,
    x: &[S],
    u: &[S],
    xdot: &mut [S],
) -> Result<(S, S), String> {
    let nu = ocp.nu();
    let out = if u.len() > nu {
        let laws = crate::laws::BalanceLaws {
            laws: &ocp.laws,
            vn: &u[nu..],
            slot: &ocp.muscle_slot,
        };
        ocp.state_rates_with(&laws, ws, x, &u[..nu], xdot)
    } else {
        ocp.state_rates(ws, x, u, xdot)
    };
    out.map_err(|e| e.to_string())
}

/// g(x, u) = (f, Ÿ_C, F_y/(m g)) at the worker's (x, u) into `out`.
fn eval_value<const W: usize>(
    ocp: &JumpOcp,
    w: &mut Worker<W>,
    out: &mut [f64],
) -> Result<(), String> {
    let nx = w.x.len();
    let (ydd, fy) = match &mut w.simbody {
        Some(sb) => sb.rates.eval(&w.x, &w.u, &mut w.xdot)?,
        None => point_rates(ocp, &mut w.ws, &w.x, &w.u, &mut w.xdot)?,
    };
    out[..nx].copy_from_slice(&w.xdot);
    out[nx] = ydd;
    out[nx + 1] = fy;
    Ok(())
}

#[inline]
fn lane<const W: usize>(d: &DualSVec64<W>, l: usize) -> f64 {
    d.eps.0.as_ref().map_or(0.0, |m| m[l])
}

/// g and its Jacobian entries in `cp`'s pattern at the worker's (x, u).
/// With `path_columns`, marks the fibre-length rows' dependence on every
/// coordinate its muscle-tendon length depends on (pattern detection).
fn eval_jac<const W: usize>(
    ocp: &JumpOcp,
    cp: &Compiled,
    w: &mut Worker<W>,
    out: &mut [f64],
    jac: &mut [f64],
    mut path_columns: Option<&mut Vec<Vec<bool>>>,
    mut paths: Option<&mut FirstOrderPaths>,
) -> Result<(), String> {
    if w.simbody.is_some() {
        return simbody_jac(ocp, cp, w, out, jac);
    }
    let (nx, nu) = (w.x.len(), w.u.len());
    let (n, nm) = (ocp.nq(), ocp.nm());
    if let Some(p) = paths.as_deref_mut() {
        p.walk.run(ocp, &w.x)?;
    }
    for (s, pass) in cp.passes.iter().enumerate() {
        match paths.as_deref() {
            Some(p) => p.walk.lift_first_order(&p.lanes[s], &mut w.wd.given_paths),
            None => w.wd.given_paths = None,
        }
        for i in 0..nx {
            w.xd[i] = DualSVec64::from(w.x[i]);
        }
        for k in 0..nu {
            w.ud[k] = DualSVec64::from(w.u[k]);
        }
        for &(c, l) in &pass.seeds {
            if c < nx {
                w.xd[c] = DualSVec64::from_re(w.x[c]).derivative(l);
            } else {
                w.ud[c - nx] = DualSVec64::from_re(w.u[c - nx]).derivative(l);
            }
        }
        let (ydd, fy) = point_rates(ocp, &mut w.wd, &w.xd, &w.ud, &mut w.xdotd)?;
        if s == 0 {
            for i in 0..nx {
                out[i] = w.xdotd[i].re;
            }
            out[nx] = ydd.re;
            out[nx + 1] = fy.re;
        }
        for &(e, r, l) in &pass.extract {
            let d = if r < nx {
                &w.xdotd[r]
            } else if r == nx {
                &ydd
            } else {
                &fy
            };
            jac[e] = lane(d, l);
        }
        if let Some(found) = path_columns.as_deref_mut() {
            for &(c, l) in &pass.seeds {
                if c < n {
                    for k in 0..nm {
                        if lane(&w.wd.mtu_length[k], l).abs() > PATH_ROUNDOFF {
                            found[2 * n + k][c] = true;
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// Point input c of (x, u): a state, or after them an input u.
fn input<'a>(x: &'a mut [f64], u: &'a mut [f64], c: usize) -> &'a mut f64 {
    let nx = x.len();
    if c < nx {
        &mut x[c]
    } else {
        &mut u[c - nx]
    }
}

/// g and its Jacobian entries in `cp`'s pattern at the worker's (x, u) by
/// Simbody ([`Backend::Simbody`]): central differences, all columns of one
/// colour moved together, each entry read from its column's colour.
fn simbody_jac<const W: usize>(
    ocp: &JumpOcp,
    cp: &Compiled,
    w: &mut Worker<W>,
    out: &mut [f64],
    jac: &mut [f64],
) -> Result<(), String> {
    eval_value(ocp, w, out)?;
    let nx = w.x.len();
    let Some(SimbodyPoint {
        rates,
        differences,
        gp,
        gm,
        base,
    }) = w.simbody.as_mut()
    else {
        return Err("the Simbody backend is not built".into());
    };
    base.clear();
    base.extend(w.x.iter().chain(&w.u));
    let base = &*base;
    // Relative step; the steps taken (one-sided: one, central: h and
    // h/2, each to both sides).
    let (rel, steps): (f64, &[f64]) = match *differences {
        Differences::Central { step } => (step, &[1.0, 0.5]),
        Differences::Forward { step } => (step, &[1.0]),
        Differences::Backward { step } => (step, &[-1.0]),
    };
    let central = steps.len() == 2;
    let step = |c: usize, sign: f64| base[c] + sign * rel * base[c].abs().max(1.0);
    for pass in &cp.passes {
        let lanes = pass.seeds.iter().map(|&(_, l)| l + 1).max().unwrap_or(0);
        for lane in 0..lanes {
            let colour = || pass.seeds.iter().filter(move |&&(_, l)| l == lane);
            // Central differences of steps h and h/2, then Richardson's
            // extrapolation (4·D(h/2) − D(h))/3, whose error is O(h⁴); or
            // one difference to one side of x.
            for &half in steps {
                let sides: &[f64] = if central { &[1.0, -1.0] } else { &[1.0] };
                for (&side, g) in sides.iter().zip([&mut *gp, &mut *gm]) {
                    for &(c, _) in colour() {
                        *input(&mut w.x, &mut w.u, c) = step(c, side * half);
                    }
                    let r = rates.eval(&w.x, &w.u, &mut g[..nx]);
                    for &(c, _) in colour() {
                        *input(&mut w.x, &mut w.u, c) = base[c];
                    }
                    let (ydd, fy) = r?;
                    g[nx] = ydd;
                    g[nx + 1] = fy;
                }
                for &(e, r, _) in pass.extract.iter().filter(|&&(_, _, l)| l == lane) {
                    let c = cp.entries[e].1;
                    jac[e] = if !central {
                        (gp[r] - out[r]) / (step(c, half) - base[c])
                    } else {
                        let d = (gp[r] - gm[r]) / (step(c, half) - step(c, -half));
                        if half == 1.0 {
                            d
                        } else {
                            (4.0 * d - jac[e]) / 3.0
                        }
                    };
                }
            }
        }
    }
    Ok(())
}

/// g(x, u) = (f(x, u), Ÿ_C, F_y/(m g)) and its Jacobian entries in a
/// [`StatePattern`] (explicit fibre dynamics) by the same coloured forward
/// dual passes as collocation's Jacobian: the point derivatives of direct
/// shooting's sensitivities ([`crate::shooting`]).
pub struct PointJacobian {
    cp: Compiled,
    w: Worker<POINT_LANES>,
    /// The muscle paths walked once per point (models of at most
    /// [`HESS_Q`] coordinates; others walk them in every pass).
    paths: Option<FirstOrderPaths>,
}

/// The muscle paths of a point Jacobian, walked once per point in dual
/// numbers over (q, q̇) and lifted into each pass's lanes (see
/// [`GivenPaths`]): the paths depend on (q, q̇) alone, so a pass's lane
/// holds the path's derivative along the (q, q̇) column seeded in it. The
/// jump's point Jacobian has 5 passes; walking the paths in each was most
/// of its cost.
struct FirstOrderPaths {
    walk: PathPass,
    /// Per pass, the lane of each (q, q̇) direction seeded in it.
    lanes: Vec<Vec<Option<usize>>>,
}

impl FirstOrderPaths {
    fn new(ocp: &JumpOcp, cp: &Compiled) -> Option<Self> {
        let n2 = 2 * ocp.nq();
        (ocp.nq() <= HESS_Q).then(|| FirstOrderPaths {
            walk: PathPass::new(ocp),
            lanes: cp
                .passes
                .iter()
                .map(|pass| {
                    let mut lanes = vec![None; n2];
                    for &(c, l) in &pass.seeds {
                        if c < n2 {
                            lanes[c] = Some(l);
                        }
                    }
                    lanes
                })
                .collect(),
        })
    }
}

impl PointJacobian {
    /// For `ocp`'s state equation in `pattern` (whose inputs must be x and
    /// the excitations).
    pub fn new(ocp: &JumpOcp, pattern: &StatePattern) -> Result<Self, TranscriptionError> {
        if pattern.nx != ocp.nx() || pattern.nu != ocp.nu() || pattern.rows.len() != ocp.nx() + 2 {
            return Err(TranscriptionError::Pattern(format!(
                "a pattern of {} states, {} inputs and {} rows does not fit a model of {} states and {} excitations",
                pattern.nx,
                pattern.nu,
                pattern.rows.len(),
                ocp.nx(),
                ocp.nu()
            )));
        }
        let cp = Compiled::new(&pattern.rows, pattern.nx + pattern.nu, true, POINT_LANES);
        Ok(PointJacobian {
            paths: FirstOrderPaths::new(ocp, &cp),
            cp,
            w: Worker::new(ocp, ocp.nu()),
        })
    }

    /// Whether the muscle paths are walked once per point (models of at
    /// most 7 coordinates) rather than in every pass.
    pub fn walks_paths_once(&self) -> bool {
        self.paths.is_some()
    }

    /// Walk the muscle paths in every pass, as collocation's Jacobian does,
    /// instead of once per point (for comparisons: the two agree to
    /// rounding).
    pub fn walk_paths_in_every_pass(&mut self) {
        self.paths = None;
    }

    /// The Jacobian's entries (output row, input column), in the order
    /// [`PointJacobian::eval`] writes their values.
    pub fn entries(&self) -> &[(usize, usize)] {
        &self.cp.entries
    }

    /// g at (x, u) into `g` (n_x + 2 values) and the entries' values into
    /// `jac`.
    pub fn eval(
        &mut self,
        ocp: &JumpOcp,
        x: &[f64],
        u: &[f64],
        g: &mut [f64],
        jac: &mut [f64],
    ) -> Result<(), String> {
        let (nx, nu) = (self.w.x.len(), self.w.u.len());
        if x.len() != nx || u.len() != nu || g.len() < nx + 2 || jac.len() < self.cp.entries.len() {
            return Err(format!(
                "point Jacobian: {} states, {} excitations, {} outputs and {} entries given for {nx}, {nu}, {} and {}",
                x.len(),
                u.len(),
                g.len(),
                jac.len(),
                nx + 2,
                self.cp.entries.len()
            ));
        }
        if let Some((i, v)) = x.iter().chain(u).enumerate().find(|(_, v)| !v.is_finite()) {
            let what = if i < nx {
                format!("state {i}")
            } else {
                format!("excitation {}", i - nx)
            };
            return Err(format!("point Jacobian: {what} is {v}"));
        }
        self.w.x.copy_from_slice(x);
        self.w.u.copy_from_slice(u);
        eval_jac(
            ocp,
            &self.cp,
            &mut self.w,
            g,
            jac,
            None,
            self.paths.as_mut(),
        )
    }
}

/// Where the state equation is evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Point {
    /// Node k (1..N).
    Node(usize),
    /// The mean of nodes k−1 and k (interval k = 1..N).
    Mid(usize),
    /// The Hermite–Simpson centre of interval k: states
    /// (x_{k−1} + x_k)/2 + h(f_{k−1} − f_k)/8, excitations the mean.
    Center(usize),
}

impl std::fmt::Display for Point {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Point::Node(k) => write!(f, "node {k}"),
            Point::Mid(k) => write!(f, "midpoint of interval {k}"),
            Point::Center(k) => write!(f, "centre of interval {k}"),
        }
    }
}

/// The inputs (x, u) of point `p`: a node's values (point inputs beyond
/// its excitations zero), the midpoint's ([`midpoint_inputs`]), or the
/// Hermite–Simpson centre's from the nodes and their f (`node_f`).
fn set_point_inputs<'a, 'b>(
    p: Point,
    node: impl Fn(usize) -> (&'a [f64], &'a [f64]),
    node_f: impl Fn(usize) -> &'b [f64],
    h: f64,
    speeds: (usize, &[f64]),
    x: &mut [f64],
    u: &mut [f64],
) {
    match p {
        Point::Node(k) => {
            let (xn, un) = node(k);
            x.copy_from_slice(xn);
            u[..un.len()].copy_from_slice(un);
            u[un.len()..].fill(0.0);
        }
        Point::Mid(k) => midpoint_inputs(node(k - 1), node(k), h, speeds, x, u),
        Point::Center(k) => {
            let ((xa, ua), (xb, ub)) = (node(k - 1), node(k));
            let (fa, fb) = (node_f(k - 1), node_f(k));
            for j in 0..x.len() {
                x[j] = 0.5 * (xa[j] + xb[j]) + 0.125 * h * (fa[j] - fb[j]);
            }
            for j in 0..ua.len() {
                u[j] = 0.5 * (ua[j] + ub[j]);
            }
            u[ua.len()..].fill(0.0);
        }
    }
}

/// f at node `k` for the Hermite–Simpson centres: from the values of the
/// points evaluated so far (`stride` values per point, f first), or the
/// fixed start's `node0` at node 0, which is no point.
fn node_f<'a>(
    node_point: &[Option<usize>],
    done: &'a [f64],
    stride: usize,
    node0: &'a [f64],
    k: usize,
) -> &'a [f64] {
    node_point[k]
        .and_then(|p| done.get(p * stride..p * stride + node0.len()))
        .unwrap_or(node0)
}

/// Run `jobs` on `workers`, the first on this thread and each other on a
/// scoped thread of its own (on this thread too where the system refuses
/// the thread). The first error in job order is returned; a thread that
/// panicked is an error at point `lo`.
fn run_jobs<W: Send, J: Send>(
    workers: &mut [W],
    jobs: impl Iterator<Item = J>,
    lo: usize,
    run: &(impl Fn(&mut W, J) -> Result<(), (usize, String)> + Sync),
) -> Result<(), (usize, String)> {
    // Each job in a slot that its thread takes: a job whose thread the
    // system refuses (a process limit) stays there for this thread, which
    // runs the first job and then the refused ones in turn.
    let slots: Vec<std::sync::Mutex<Option<(&mut W, J)>>> = workers
        .iter_mut()
        .zip(jobs)
        .map(|p| std::sync::Mutex::new(Some(p)))
        .collect();
    let run_slot = |slot: &std::sync::Mutex<Option<(&mut W, J)>>| match slot
        .lock()
        .ok()
        .and_then(|mut g| g.take())
    {
        Some((w, j)) => run(w, j),
        None => Ok(()),
    };
    std::thread::scope(|s| {
        let handles: Vec<_> = slots
            .iter()
            .enumerate()
            .map(|(i, slot)| {
                (i > 0)
                    .then(|| {
                        std::thread::Builder::new()
                            .spawn_scoped(s, move || run_slot(slot))
                            .ok()
                    })
                    .flatten()
            })
            .collect();
        // Every job ends (joined or run here) before the first error in job
        // order is returned.
        let results: Vec<_> = slots
            .iter()
            .zip(handles)
            .map(|(slot, h)| match h {
                Some(h) => h
                    .join()
                    .unwrap_or_else(|_| Err((lo, "an evaluation thread panicked".into()))),
                None => run_slot(slot),
            })
            .collect();
        results.into_iter().collect()
    })
}

/// How one Jacobian entry is computed from the point evaluations.
#[derive(Debug, Clone, Copy)]
enum Src {
    /// diag − weight·h·J_point[entry] (defect w.r.t. a node variable;
    /// weight ½, backward Euler's node k 1).
    Dyn {
        point: usize,
        entry: Option<usize>,
        diag: f64,
        weight: f64,
    },
    /// −(f_row at `a` + f_row at `b`)·`scale` (defect w.r.t. t_f).
    Tf {
        a: Term,
        b: usize,
        row: usize,
        scale: f64,
    },
    /// A force-balance row (implicit fibre dynamics) w.r.t. a node
    /// variable: ½·J_point[entry], plus for the muscle's own fibre length
    /// ±J_point[velocity entry]/(h·v_max·l_o) (speed: (entry, ±1/(v_max l_o))).
    Balance {
        point: usize,
        entry: Option<usize>,
        speed: Option<(usize, f64)>,
    },
    /// A force-balance row w.r.t. t_f: −J_point[entry]·v̄/t_f, v̄ = (l^M_k −
    /// l^M_{k−1})/(h·v_max·l_o) of state row `row` in interval `k`.
    BalanceTf {
        point: usize,
        entry: usize,
        row: usize,
        k: usize,
        inv_speed: f64,
    },
    /// A Hermite–Simpson defect entry (filled block by block).
    Hs,
    /// scale·J_point[entry] (Ÿ_C and lift-off rows).
    Out {
        point: usize,
        entry: usize,
        scale: f64,
    },
    /// ∂Ẏ_C/∂(q, q̇) of a node (filled node by node).
    ComVelocity,
}

/// The first term of a t_f column entry.
#[derive(Debug, Clone, Copy)]
enum Term {
    Point(usize),
    /// The fixed start (trapezoidal interval 1).
    Start,
    None,
}

/// What [`Transcription::integrate_on_mesh`] reached.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct MeshIntegration {
    /// Mesh intervals, and those whose defects reached [`MESH_NEWTON_TOL`].
    pub intervals: usize,
    pub converged: usize,
    /// Intervals whose Newton iteration stopped short with a state held at
    /// its bound against its last step (by a hundredth of the step or
    /// more): the defects' solution lies outside the bounds (e.g. an
    /// activation the scheme would take below a_min, a fibre shorter than
    /// its shortest).
    pub at_bound: usize,
    /// Intervals whose Newton iteration stopped short inside the bounds: no
    /// backtracked step reduced the defects, the Jacobian was singular, or
    /// the iterations ran out.
    pub stopped_short: usize,
    /// The first interval left unsolved, of either kind.
    pub first_unsolved: Option<UnsolvedInterval>,
    /// The largest defect left (the problem's units), and its interval
    /// (1-based) and state (index and OpenSim path).
    pub worst_defect: f64,
    pub worst_interval: usize,
    pub worst_state: usize,
    pub worst_state_name: String,
}

/// An interval of [`Transcription::integrate_on_mesh`] left unsolved:
/// 1-based, its defect left, and the state held at its bound if one was
/// (the largest component of the last step against a bound).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct UnsolvedInterval {
    pub interval: usize,
    pub defect: f64,
    pub held: Option<HeldState>,
}

/// A state that held an interval of [`Transcription::integrate_on_mesh`] at
/// its bound: its index, OpenSim path and whether the bound is the lower.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HeldState {
    pub state: usize,
    pub name: String,
    pub lower: bool,
}

/// A state of a guess that lay outside its bounds at some nodes and was
/// projected into them ([`Transcription::guess_from_trajectory`]): at how
/// many nodes, and the farthest value with its time and bounds.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct GuessProjection {
    /// The state's OpenSim path.
    pub name: String,
    pub nodes: usize,
    pub value: f64,
    pub time_s: f64,
    pub lower: f64,
    pub upper: f64,
    /// Where the bound comes from.
    pub bound: String,
    /// A rotational coordinate's value or speed whose farthest value, read
    /// as degrees, lies within the bounds: a file in degrees whose header
    /// does not say so.
    pub likely_degrees: bool,
}

impl std::fmt::Display for GuessProjection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use crate::io::readable;
        write!(
            f,
            "{} lies outside [{}, {}] ({}) at {} node(s), farthest {} at t = {:.4} s",
            self.name,
            readable(self.lower),
            readable(self.upper),
            self.bound,
            self.nodes,
            readable(self.value),
            self.time_s
        )?;
        if self.likely_degrees {
            write!(
                f,
                " (in degrees? a .sto in degrees says inDegrees=yes in its header)"
            )?;
        }
        Ok(())
    }
}

/// Newton on one interval's defects in [`Transcription::integrate_on_mesh`]:
/// the tolerance on the largest defect, the iteration limit and the step
/// halvings per iteration.
pub const MESH_NEWTON_TOL: f64 = 1e-10;
const MESH_NEWTON_ITERATIONS: usize = 30;
const MESH_NEWTON_BACKTRACKS: usize = 12;

/// Jacobian sizes.
#[derive(Debug, Clone, serde::Serialize)]
pub struct JacobianStats {
    /// Non-zeros of the whole constraint Jacobian.
    pub nnz: usize,
    /// Of the defect rows, of the no-countermovement rows, of the lift-off row.
    pub nnz_defects: usize,
    pub nnz_no_countermovement: usize,
    pub nnz_liftoff: usize,
    /// Of the Ẏ_C ≥ 0 rows (zero without them).
    pub nnz_no_descent: usize,
    /// Per defect block (interval 1 has no previous-node columns).
    pub nnz_first_interval: usize,
    pub nnz_interval: usize,
    /// Of ∂f/∂(x, u) (n_x × (n_x + n_u) = 5,332 entries for the jump).
    pub nnz_state_equation: usize,
    pub state_equation_entries: usize,
    /// Dual directions per Jacobian of f (colours) and passes of `LANES`.
    pub colors: usize,
    pub passes: usize,
    pub lanes: usize,
}

/// Evaluation counts and times (s), for solver reports.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct EvalCounters {
    pub constraints: usize,
    pub constraints_time: f64,
    pub jacobians: usize,
    pub jacobian_time: f64,
    /// Second-order sweeps over the points (one per x the element
    /// Hessians are asked at) and their time.
    pub hessians: usize,
    pub hessian_time: f64,
}

/// A trajectory on the mesh: node times, states and excitations (node 0
/// included).
#[derive(Debug, Clone)]
pub struct MeshTrajectory {
    pub time: Vec<f64>,
    pub states: Vec<Vec<f64>>,
    pub controls: Vec<Vec<f64>>,
}

/// The jump problem transcribed by direct collocation.
pub struct Transcription {
    pub ocp: Arc<JumpOcp>,
    options: TranscriptionOptions,
    pattern: StatePattern,
    pub counters: EvalCounters,
    compiled: Compiled,
    nx: usize,
    nu: usize,
    /// v_max·l_o per carried muscle (m/s).
    fiber_speed: Vec<f64>,
    n_cm: usize,
    /// Rows Ẏ_C(t_k) ≥ 0, k = 1..n_cv (N with `no_com_descent`, else 0).
    n_cv: usize,
    points: Vec<Point>,
    /// The midpoint (or Hermite–Simpson centre) of interval k at [k − 1].
    interval_point: Vec<usize>,
    /// Points before this index are evaluated first (Hermite–Simpson
    /// centres need the node values).
    first_stage: usize,
    /// Hermite–Simpson: per state row, the node columns of its defect
    /// (F ∪ I ∪ F^x·F) with the entry of F and the identity; the x-columns
    /// s of F's row with their entries (for F_c^x·F); a scratch row.
    hs_rows: Vec<Vec<(usize, Option<usize>, f64)>>,
    hs_prods: Vec<Vec<(usize, usize)>>,
    scratch: Vec<f64>,
    /// The point of node k, if evaluated.
    node_point: Vec<Option<usize>>,
    /// g at node 0 (fixed).
    node0: Vec<f64>,
    structure: Vec<(usize, usize)>,
    sources: Vec<Src>,
    /// Offsets into `structure` of the defect, no-countermovement, lift-off
    /// and no-descent rows, and its end.
    block_offsets: [usize; 5],
    point_vals: Vec<f64>,
    point_jac: Vec<f64>,
    workers: Vec<Worker<LANES>>,
    initial: Vec<f64>,
    /// Column layout of node k's element in the no-countermovement rows etc.
    ydd_cols: Vec<usize>,
    fy_cols: Vec<usize>,
    /// The final node's columns of the objective and lift-off element.
    final_cols: Vec<usize>,
    /// [`Transcription::defect_row_groups`].
    groups: Vec<(Vec<usize>, Vec<usize>)>,
    /// Exact Hessians: the seeding (None: not available), what each
    /// element holds, and the point derivatives of the last x.
    hess_plan: Option<HessPlan>,
    hess_elements: Vec<HessElement>,
    hess: Option<Box<HessCache>>,
}

impl Transcription {
    /// Transcribe `ocp`, detecting the pattern of ∂f/∂(x, u) first.
    pub fn new(
        ocp: Arc<JumpOcp>,
        options: TranscriptionOptions,
    ) -> Result<Self, TranscriptionError> {
        let pattern = StatePattern::detect_for(
            &ocp,
            options.fiber_dynamics,
            options.pattern_samples,
            options.pattern_seed,
        )?;
        Self::with_pattern(ocp, options, pattern)
    }

    /// Transcribe `ocp` with a known pattern (e.g. shared between meshes).
    pub fn with_pattern(
        ocp: Arc<JumpOcp>,
        options: TranscriptionOptions,
        pattern: StatePattern,
    ) -> Result<Self, TranscriptionError> {
        let (nx, nu) = (ocp.nx(), ocp.nu());
        let big_n = options.num_mesh_intervals;
        let n_cm = ocp.options.no_countermovement_nodes;
        if big_n == 0 {
            return Err(TranscriptionError::Invalid(
                "num_mesh_intervals must be at least 1".into(),
            ));
        }
        if n_cm > big_n {
            return Err(TranscriptionError::Invalid(format!(
                "{n_cm} no-countermovement rows need at least {n_cm} mesh intervals, got num_mesh_intervals = {big_n}"
            )));
        }
        let implicit = options.fiber_dynamics == FiberDynamics::Implicit;
        if implicit && options.scheme != Scheme::MidpointEuler {
            return Err(TranscriptionError::Invalid(format!(
                "implicit fibre dynamics need the midpoint-euler scheme, not {:?}",
                options.scheme
            )));
        }
        let npu = point_inputs(&ocp, options.fiber_dynamics);
        if pattern.nx != nx || pattern.nu != npu || pattern.rows.len() != nx + 2 {
            return Err(TranscriptionError::Pattern(format!(
                "the pattern is for {} states and {} point inputs, the problem has {nx} and {npu}",
                pattern.nx, pattern.nu
            )));
        }
        let (lm0, nm) = (2 * ocp.nq(), ocp.nm());
        // The inputs beyond the excitations (the normalised fibre
        // velocities of implicit dynamics) feed only the force balances:
        // another row's entry for one (every row of the dense pattern of
        // `leap crosscheck --jacobian`) would map it onto the next node's
        // columns, so it is dropped.
        let balance_row = |r: usize| implicit && (lm0..lm0 + nm).contains(&r);
        let mut pattern = pattern;
        for (r, row) in pattern.rows.iter_mut().enumerate() {
            if !balance_row(r) {
                row.retain(|&c| c < nx + nu);
            }
        }
        let fiber_speed: Vec<f64> = ocp
            .eq
            .muscles
            .iter()
            .map(|&mi| ocp.laws.muscles[mi].max_fiber_speed())
            .collect();
        if options.threads == 0 {
            return Err(TranscriptionError::Invalid(
                "threads must be at least 1".into(),
            ));
        }
        let nin = nx + npu;
        let compiled = Compiled::new(&pattern.rows, nin, options.compress_columns, LANES);
        // Evaluation points.
        let mut points = Vec::new();
        let mut interval_point = Vec::new();
        let mut node_point = vec![None; big_n + 1];
        match options.scheme {
            Scheme::MidpointEuler => {
                for k in 1..=big_n {
                    interval_point.push(points.len());
                    points.push(Point::Mid(k));
                }
                for k in (1..=n_cm).chain(std::iter::once(big_n)) {
                    if node_point[k].is_none() {
                        node_point[k] = Some(points.len());
                        points.push(Point::Node(k));
                    }
                }
            }
            Scheme::Trapezoidal | Scheme::BackwardEuler => {
                for k in 1..=big_n {
                    node_point[k] = Some(points.len());
                    points.push(Point::Node(k));
                }
            }
            Scheme::HermiteSimpson => {
                for k in 1..=big_n {
                    node_point[k] = Some(points.len());
                    points.push(Point::Node(k));
                }
                for k in 1..=big_n {
                    interval_point.push(points.len());
                    points.push(Point::Center(k));
                }
            }
        }
        let first_stage = if options.scheme == Scheme::HermiteSimpson {
            big_n
        } else {
            points.len()
        };
        let nv = nx + nu;
        let var = |k: usize, c: usize| (k - 1) * nv + c;
        let tf = big_n * nv;
        // Defect rows: per state row, the node columns (pattern ∪ identity).
        let blk: Vec<Vec<(usize, Option<usize>, f64)>> = (0..nx)
            .map(|r| {
                let mut cols: Vec<usize> = pattern.rows[r].clone();
                if !cols.contains(&r) {
                    cols.push(r);
                    cols.sort_unstable();
                }
                cols.iter()
                    .map(|&c| (c, compiled.entry(r, c), if c == r { 1.0 } else { 0.0 }))
                    .collect()
            })
            .collect();
        // Hermite–Simpson: F_c^x·F adds, to row r, the columns of every row
        // s < n_x that row r depends on.
        let (mut hs_rows, mut hs_prods) = (Vec::new(), Vec::new());
        if options.scheme == Scheme::HermiteSimpson {
            for r in 0..nx {
                let mut cols: Vec<usize> = pattern.rows[r]
                    .iter()
                    .copied()
                    .chain(std::iter::once(r))
                    .collect();
                let prods: Vec<(usize, usize)> = pattern.rows[r]
                    .iter()
                    .filter(|&&c| c < nx)
                    .map(|&c| (c, compiled.entry(r, c).unwrap_or(usize::MAX)))
                    .collect();
                for &(sr, _) in &prods {
                    cols.extend(pattern.rows[sr].iter().copied());
                }
                cols.sort_unstable();
                cols.dedup();
                hs_rows.push(
                    cols.iter()
                        .map(|&c| (c, compiled.entry(r, c), if c == r { 1.0 } else { 0.0 }))
                        .collect::<Vec<_>>(),
                );
                hs_prods.push(prods);
            }
        }
        let mut structure = Vec::new();
        let mut sources = Vec::new();
        let inv_n = 1.0 / big_n as f64;
        for k in 1..=big_n {
            let row0 = (k - 1) * nx;
            let (pa, pb) = match options.scheme {
                Scheme::MidpointEuler => (interval_point[k - 1], interval_point[k - 1]),
                Scheme::Trapezoidal | Scheme::HermiteSimpson | Scheme::BackwardEuler => (
                    node_point[k - 1].unwrap_or(usize::MAX),
                    node_point[k].unwrap_or(usize::MAX),
                ),
            };
            for r in 0..nx {
                if balance_row(r) {
                    // The force balance at the midpoint: the node columns
                    // of its pattern (and its own fibre length), with the
                    // fibre velocity v̄ = (l^M_k − l^M_{k−1})/(h v_max l_o).
                    let i = r - lm0;
                    let ve = compiled.entry(r, nx + nu + i).unwrap_or(usize::MAX);
                    let inv_speed = 1.0 / fiber_speed[i];
                    let cols: Vec<usize> = node_columns(&pattern.rows[r], r, nv);
                    for (node, sign) in [(k - 1, -1.0), (k, 1.0)] {
                        if node == 0 {
                            continue;
                        }
                        for &c in &cols {
                            structure.push((row0 + r, var(node, c)));
                            sources.push(Src::Balance {
                                point: pa,
                                entry: compiled.entry(r, c),
                                speed: (c == r).then_some((ve, sign * inv_speed)),
                            });
                        }
                    }
                    structure.push((row0 + r, tf));
                    sources.push(Src::BalanceTf {
                        point: pa,
                        entry: ve,
                        row: r,
                        k,
                        inv_speed,
                    });
                    continue;
                }
                let cols = if options.scheme == Scheme::HermiteSimpson {
                    &hs_rows[r]
                } else {
                    &blk[r]
                };
                let be = options.scheme == Scheme::BackwardEuler;
                if k >= 2 && be {
                    // Backward Euler: the previous node only through −x_{k−1}.
                    structure.push((row0 + r, var(k - 1, r)));
                    sources.push(Src::Dyn {
                        point: pa,
                        entry: None,
                        diag: -1.0,
                        weight: 0.0,
                    });
                } else if k >= 2 {
                    for &(c, e, d) in cols {
                        structure.push((row0 + r, var(k - 1, c)));
                        sources.push(if options.scheme == Scheme::HermiteSimpson {
                            Src::Hs
                        } else {
                            Src::Dyn {
                                point: pa,
                                entry: e,
                                diag: -d,
                                weight: 0.5,
                            }
                        });
                    }
                }
                for &(c, e, d) in cols {
                    structure.push((row0 + r, var(k, c)));
                    sources.push(if options.scheme == Scheme::HermiteSimpson {
                        Src::Hs
                    } else {
                        Src::Dyn {
                            point: pb,
                            entry: e,
                            diag: d,
                            weight: if be { 1.0 } else { 0.5 },
                        }
                    });
                }
                structure.push((row0 + r, tf));
                sources.push(match options.scheme {
                    Scheme::MidpointEuler | Scheme::BackwardEuler => Src::Tf {
                        a: Term::None,
                        b: pb,
                        row: r,
                        scale: inv_n,
                    },
                    Scheme::Trapezoidal => Src::Tf {
                        a: node_point[k - 1].map_or(Term::Start, Term::Point),
                        b: pb,
                        row: r,
                        scale: 0.5 * inv_n,
                    },
                    Scheme::HermiteSimpson => Src::Hs,
                });
            }
        }
        let off_cm = structure.len();
        let ydd_cols = pattern.rows[nx].clone();
        let fy_cols = pattern.rows[nx + 1].clone();
        for j in 0..n_cm {
            let row = big_n * nx + j;
            for (node, scale) in [(j, 1.0), (j + 1, -1.0)] {
                if node == 0 {
                    continue;
                }
                let p = node_point[node].unwrap_or(usize::MAX);
                for &c in &ydd_cols {
                    structure.push((row, var(node, c)));
                    sources.push(Src::Out {
                        point: p,
                        entry: compiled.entry(nx, c).unwrap_or(usize::MAX),
                        scale,
                    });
                }
            }
        }
        let off_lo = structure.len();
        {
            let row = big_n * nx + n_cm;
            let p = node_point[big_n].unwrap_or(usize::MAX);
            for &c in &fy_cols {
                structure.push((row, var(big_n, c)));
                sources.push(Src::Out {
                    point: p,
                    entry: compiled.entry(nx + 1, c).unwrap_or(usize::MAX),
                    scale: 1.0,
                });
            }
        }
        let off_cv = structure.len();
        let n_cv = if ocp.options.no_com_descent { big_n } else { 0 };
        for k in 1..=n_cv {
            let row = big_n * nx + n_cm + k;
            for c in 0..2 * ocp.nq() {
                structure.push((row, var(k, c)));
                sources.push(Src::ComVelocity);
            }
        }
        let off_end = structure.len();
        let mut workers: Vec<Worker<LANES>> = (0..options.threads)
            .map(|_| Worker::with_backend(&ocp, npu, options.backend))
            .collect::<Result<_, _>>()
            .map_err(TranscriptionError::Invalid)?;
        // Node 0 by the first worker (threads ≥ 1).
        let w0 = &mut workers[0];
        w0.x.copy_from_slice(ocp.x0());
        w0.u.fill(0.0);
        w0.u[..nu].copy_from_slice(ocp.u0());
        let mut node0 = vec![0.0; nx + 2];
        eval_value(&ocp, w0, &mut node0).map_err(|e| {
            TranscriptionError::Invalid(format!("the state equation fails at the fixed start: {e}"))
        })?;
        let npts = points.len();
        let nnz_g = compiled.entries.len();
        let mut me = Transcription {
            ocp,
            options,
            pattern,
            counters: EvalCounters::default(),
            compiled,
            nx,
            nu,
            fiber_speed,
            n_cm,
            n_cv,
            points,
            interval_point,
            first_stage,
            hs_rows,
            hs_prods,
            scratch: vec![0.0; nin],
            node_point,
            node0,
            structure,
            sources,
            block_offsets: [0, off_cm, off_lo, off_cv, off_end],
            point_vals: vec![0.0; npts * (nx + 2)],
            point_jac: vec![0.0; npts * nnz_g],
            workers,
            initial: Vec::new(),
            ydd_cols,
            fy_cols,
            final_cols: Vec::new(),
            groups: Vec::new(),
            hess_plan: None,
            hess_elements: Vec::new(),
            hess: None,
        };
        me.groups = me.defect_row_groups();
        {
            let n = me.ocp.nq();
            let mut cols: Vec<usize> = (0..2 * n).chain(me.fy_cols.iter().copied()).collect();
            cols.sort_unstable();
            cols.dedup();
            me.final_cols = cols;
        }
        me.hess_plan = HessPlan::new(&me.pattern, me.ocp.nq(), me.ocp.nm());
        if me.options.scheme == Scheme::HermiteSimpson {
            me.hess_elements
                .extend((1..=big_n).map(HessElement::Interval));
        } else {
            for g in 0..me.groups.len() {
                for k in 1..=big_n {
                    me.hess_elements.push(HessElement::Defect { group: g, k });
                }
            }
        }
        for j in 0..n_cm {
            me.hess_elements.push(HessElement::NoCountermovement(j));
        }
        me.hess_elements.push(HessElement::Final);
        for k in 1..=n_cv {
            me.hess_elements.push(HessElement::ComVelocity(k));
        }
        // Until a guess is set: the squat held, t_f = 0.3 s within its bounds.
        let [t0, t1] = me.ocp.options.final_time_bounds;
        me.initial = me.constant_guess(0.3f64.clamp(t0, t1));
        Ok(me)
    }

    /// The settings it was built with.
    pub fn options(&self) -> &TranscriptionOptions {
        &self.options
    }

    /// The sparsity of ∂(f, Ÿ_C, F_y)/∂(x, u) it uses.
    pub fn pattern(&self) -> &StatePattern {
        &self.pattern
    }

    /// Mesh intervals N.
    pub fn num_intervals(&self) -> usize {
        self.options.num_mesh_intervals
    }

    /// Variables per node (n_x + n_u).
    pub fn node_size(&self) -> usize {
        self.nx + self.nu
    }

    /// Whether defect row `r` of an interval is a fibre force balance
    /// ([`FiberDynamics::Implicit`]).
    pub fn is_balance_row(&self, r: usize) -> bool {
        let lm0 = 2 * self.ocp.nq();
        self.options.fiber_dynamics == FiberDynamics::Implicit
            && (lm0..lm0 + self.ocp.nm()).contains(&r)
    }

    /// Index of state `i` of node `k` (None for node 0, which is fixed).
    pub fn state_index(&self, k: usize, i: usize) -> Option<usize> {
        (k >= 1 && k <= self.num_intervals() && i < self.nx).then(|| (k - 1) * self.node_size() + i)
    }

    /// Index of control `i` of node `k` (None for node 0).
    pub fn control_index(&self, k: usize, i: usize) -> Option<usize> {
        (k >= 1 && k <= self.num_intervals() && i < self.nu)
            .then(|| (k - 1) * self.node_size() + self.nx + i)
    }

    /// Index of t_f (the last variable).
    pub fn final_time_index(&self) -> usize {
        self.num_intervals() * self.node_size()
    }

    /// t_f of a variable vector.
    pub fn final_time(&self, v: &[f64]) -> f64 {
        v[self.final_time_index()]
    }

    /// The states of node k (node 0: the fixed start).
    pub fn node_state<'a>(&'a self, v: &'a [f64], k: usize) -> &'a [f64] {
        if k == 0 {
            self.ocp.x0()
        } else {
            let o = (k - 1) * self.node_size();
            &v[o..o + self.nx]
        }
    }

    /// The excitations of node k (node 0: the fixed start).
    pub fn node_control<'a>(&'a self, v: &'a [f64], k: usize) -> &'a [f64] {
        if k == 0 {
            self.ocp.u0()
        } else {
            let o = (k - 1) * self.node_size() + self.nx;
            &v[o..o + self.nu]
        }
    }

    /// Node times for final time `tf`.
    pub fn mesh_times(&self, tf: f64) -> Vec<f64> {
        let big_n = self.num_intervals();
        (0..=big_n).map(|k| tf * k as f64 / big_n as f64).collect()
    }

    /// The trajectory a variable vector holds (node 0 included).
    pub fn unpack(&self, v: &[f64]) -> MeshTrajectory {
        let big_n = self.num_intervals();
        MeshTrajectory {
            time: self.mesh_times(self.final_time(v)),
            states: (0..=big_n)
                .map(|k| self.node_state(v, k).to_vec())
                .collect(),
            controls: (0..=big_n)
                .map(|k| self.node_control(v, k).to_vec())
                .collect(),
        }
    }

    /// The variable vector of node states and excitations (N + 1 each,
    /// node 0's ignored: it is fixed) and final time `tf`.
    pub fn pack(
        &self,
        states: &[Vec<f64>],
        controls: &[Vec<f64>],
        tf: f64,
    ) -> Result<Vec<f64>, TranscriptionError> {
        let big_n = self.num_intervals();
        if states.len() != big_n + 1 || controls.len() != big_n + 1 {
            return Err(TranscriptionError::Guess(format!(
                "need {} node states and controls (node 0 included), got {} and {}",
                big_n + 1,
                states.len(),
                controls.len()
            )));
        }
        let mut v = vec![0.0; self.num_variables()];
        for k in 1..=big_n {
            if states[k].len() != self.nx || controls[k].len() != self.nu {
                return Err(TranscriptionError::Guess(format!(
                    "node {k}: {} states and {} controls, expected {} and {}",
                    states[k].len(),
                    controls[k].len(),
                    self.nx,
                    self.nu
                )));
            }
            let o = (k - 1) * self.node_size();
            v[o..o + self.nx].copy_from_slice(&states[k]);
            v[o + self.nx..o + self.nx + self.nu].copy_from_slice(&controls[k]);
        }
        v[self.final_time_index()] = tf;
        Ok(v)
    }

    /// The static squat held at every node, final time `tf`.
    pub fn constant_guess(&self, tf: f64) -> Vec<f64> {
        let nv = self.node_size();
        let mut v = vec![0.0; self.num_variables()];
        for node in v[..self.final_time_index()].chunks_mut(nv) {
            node[..self.nx].copy_from_slice(self.ocp.x0());
            node[self.nx..].copy_from_slice(self.ocp.u0());
        }
        v[self.final_time_index()] = tf;
        v
    }

    /// An initial guess from a trajectory (times increasing, from 0, states
    /// and excitations per time) resampled linearly onto the mesh for final
    /// time `tf`, then clipped into the variable bounds (t_f too), with the
    /// states that lay outside them.
    pub fn guess_from_trajectory(
        &self,
        time: &[f64],
        states: &[Vec<f64>],
        controls: &[Vec<f64>],
        tf: f64,
    ) -> Result<(Vec<f64>, Vec<GuessProjection>), TranscriptionError> {
        if time.is_empty() || time.len() != states.len() || time.len() != controls.len() {
            return Err(TranscriptionError::Guess(format!(
                "{} times, {} states and {} controls; need equally many, at least one",
                time.len(),
                states.len(),
                controls.len()
            )));
        }
        if let Some(i) = time
            .windows(2)
            .position(|w| w[0].is_nan() || w[1].is_nan() || w[1] < w[0])
        {
            return Err(TranscriptionError::Guess(format!(
                "times not increasing at index {}: {} then {}",
                i + 1,
                time[i],
                time[i + 1]
            )));
        }
        if let Some(i) = states.iter().position(|s| s.len() != self.nx) {
            return Err(TranscriptionError::Guess(format!(
                "state {i} has {} values, expected {}",
                states[i].len(),
                self.nx
            )));
        }
        if let Some(i) = controls.iter().position(|c| c.len() != self.nu) {
            return Err(TranscriptionError::Guess(format!(
                "control {i} has {} values, expected {}",
                controls[i].len(),
                self.nu
            )));
        }
        if !(tf.is_finite() && tf > 0.0) {
            return Err(TranscriptionError::Guess(format!(
                "final time must be positive, got {tf}"
            )));
        }
        let t_end = *time.last().unwrap_or(&0.0);
        if tf > t_end + 1e-12 * t_end.abs().max(1.0) {
            return Err(TranscriptionError::Guess(format!(
                "the trajectory ends at {t_end} s, before the final time {tf} s"
            )));
        }
        let big_n = self.num_intervals();
        let times = self.mesh_times(tf);
        let mut xs = vec![self.ocp.x0().to_vec(); big_n + 1];
        let mut us = vec![self.ocp.u0().to_vec(); big_n + 1];
        let mut j = 0;
        for k in 1..=big_n {
            let t = times[k];
            while j + 1 < time.len() && time[j + 1] < t {
                j += 1;
            }
            let (a, b) = if j + 1 < time.len() {
                (j, j + 1)
            } else {
                (j, j)
            };
            let s = if b > a && time[b] > time[a] {
                ((t - time[a]) / (time[b] - time[a])).clamp(0.0, 1.0)
            } else {
                0.0
            };
            for i in 0..self.nx {
                xs[k][i] = states[a][i] + s * (states[b][i] - states[a][i]);
            }
            for i in 0..self.nu {
                us[k][i] = controls[a][i] + s * (controls[b][i] - controls[a][i]);
            }
        }
        let projected = self.states_out_of_bounds(&xs, &times);
        let mut v = self.pack(&xs, &us, tf)?;
        let n = v.len();
        let (mut lo, mut hi) = (vec![0.0; n], vec![0.0; n]);
        self.variable_bounds(&mut lo, &mut hi);
        for i in 0..n {
            v[i] = v[i].clamp(lo[i], hi[i]);
        }
        Ok((v, projected))
    }

    /// The node states `xs` (node 0, the fixed squat, skipped) outside the
    /// problem's state bounds (beyond rounding: 1e-9 relative), one entry
    /// per state over the nodes at `times`.
    fn states_out_of_bounds(&self, xs: &[Vec<f64>], times: &[f64]) -> Vec<GuessProjection> {
        let (lo, hi) = (&self.ocp.state_lower, &self.ocp.state_upper);
        let names = self.ocp.eq.state_names();
        let angular = crate::io::angular_columns(&self.ocp.eq);
        let mut out = Vec::new();
        for i in 0..self.nx {
            let tol = 1e-9 * (1.0 + lo[i].abs().max(hi[i].abs()));
            let mut entry: Option<GuessProjection> = None;
            let mut largest = 0.0;
            for (x, &t) in xs.iter().zip(times).skip(1) {
                let excess = (lo[i] - x[i]).max(x[i] - hi[i]);
                if excess.is_nan() || excess <= tol {
                    continue;
                }
                let e = entry.get_or_insert_with(|| GuessProjection {
                    name: names[i].clone(),
                    nodes: 0,
                    value: x[i],
                    time_s: t,
                    lower: lo[i],
                    upper: hi[i],
                    bound: self.ocp.state_bound_source(i),
                    likely_degrees: false,
                });
                e.nodes += 1;
                if excess > largest {
                    largest = excess;
                    (e.value, e.time_s) = (x[i], t);
                }
            }
            if let Some(e) = &mut entry {
                e.likely_degrees = angular.contains(&e.name)
                    && (e.lower..=e.upper).contains(&e.value.to_radians());
            }
            out.extend(entry);
        }
        out
    }

    /// The bang-bang guess: the built-in bang-bang jump integrated forward
    /// (Rust-native Dormand–Prince, accuracy 1e-6) and resampled onto the
    /// mesh with t_f the lift-off time; returns the guess and the jump.
    pub fn bang_bang_guess(&self) -> Result<(Vec<f64>, JumpSummary), TranscriptionError> {
        let (summary, traj) = self
            .ocp
            .simulate_bang_bang(1e-6)
            .map_err(TranscriptionError::Simulation)?;
        let tf = summary.liftoff_time_s.ok_or_else(|| {
            TranscriptionError::Guess(format!(
                "the bang-bang jump does not lift off within {} s",
                summary.final_time_s
            ))
        })?;
        let (v, _) = self.guess_from_trajectory(&traj.time, &traj.states, &traj.controls, tf)?;
        Ok((v, summary))
    }

    /// The node (1-based) of variable i and its column in the node (states,
    /// then excitations); None for t_f and beyond.
    fn node_column(&self, i: usize) -> Option<(usize, usize)> {
        let nv = self.node_size();
        (i < self.final_time_index()).then(|| (i / nv + 1, i % nv))
    }

    /// Integrate a guess's excitations on the mesh, by the transcription's
    /// own scheme: node by node, the states of node k are solved from the
    /// defect rows of interval k with node k−1, the excitations and t_f
    /// held (damped Newton on the nx × nx block of the Jacobian, states
    /// kept in their bounds; each step evaluates only the points that read
    /// node k, so the whole integration costs O(N) point evaluations). A
    /// guess resampled from a continuous trajectory violates the defects by
    /// its discretisation error, which
    /// on a 10 ms mesh through stiff foot contact is large (the bang-bang
    /// jump: 0.39 in the ankle's velocity defects); the SQP then spends
    /// its first iterations in elastic mode restoring what the mesh's own
    /// integration gives at once. An interval whose Newton iteration stops
    /// short keeps its best point and the next goes on from it.
    pub fn integrate_on_mesh(&mut self, v: &mut [f64]) -> Result<MeshIntegration, EvalError> {
        let (nx, big_n) = (self.nx, self.num_intervals());
        let n = self.num_variables();
        if v.len() != n {
            return Err(EvalError::new(
                "guess",
                format!("{} values, the problem has {n} variables", v.len()),
            ));
        }
        finite("guess", v, |i| self.variable_name(i))?;
        let (mut lo, mut hi) = (vec![0.0; n], vec![0.0; n]);
        self.variable_bounds(&mut lo, &mut hi);
        let (mut rows, mut scratch) = (vec![0.0; nx], vec![0.0; nx]);
        let mut jac = nalgebra::DMatrix::<f64>::zeros(nx, nx);
        let mut trial = v.to_vec();
        let mut report = MeshIntegration {
            intervals: big_n,
            converged: 0,
            at_bound: 0,
            stopped_short: 0,
            first_unsolved: None,
            worst_defect: 0.0,
            worst_interval: 0,
            worst_state: 0,
            worst_state_name: String::new(),
        };
        let names = self.ocp.eq.state_names();
        for k in 1..=big_n {
            let cols = (0..nx)
                .map(|i| self.state_index(k, i))
                .collect::<Option<Vec<usize>>>()
                .ok_or_else(|| {
                    EvalError::new("guess", format!("node {k} has no state variables"))
                })?;
            let mut res = self.interval_residual(v, k, &mut rows)?;
            // The state the last Newton step pushed hardest against its
            // bound, if any (index, whether the lower bound).
            let mut held: Option<(usize, bool)> = None;
            for _ in 0..MESH_NEWTON_ITERATIONS {
                if res <= MESH_NEWTON_TOL {
                    break;
                }
                held = None;
                self.interval_state_jacobian(v, k, &mut jac)?;
                let rhs = nalgebra::DVector::from_iterator(nx, rows.iter().map(|r| -r));
                let Some(step) = jac.clone().lu().solve(&rhs) else {
                    break;
                };
                if step.iter().any(|s| !s.is_finite()) {
                    break;
                }
                // A component of a hundredth of the step or more: the clamp
                // removes part of the Newton step, not roundoff.
                let significant = 1e-2 * step.amax();
                held = cols
                    .iter()
                    .zip(step.iter())
                    .enumerate()
                    .filter(|&(_, (&col, &d))| {
                        d.abs() >= significant
                            && ((v[col] <= lo[col] && d < 0.0) || (v[col] >= hi[col] && d > 0.0))
                    })
                    .max_by(|a, b| a.1 .1.abs().total_cmp(&b.1 .1.abs()))
                    .map(|(i, (_, &d))| (i, d < 0.0));
                let mut alpha = 1.0;
                let mut taken = false;
                for _ in 0..MESH_NEWTON_BACKTRACKS {
                    for (i, &col) in cols.iter().enumerate() {
                        trial[col] = (v[col] + alpha * step[i]).clamp(lo[col], hi[col]);
                    }
                    // A trial the model cannot evaluate, here or in the
                    // points after node k, is a rejected step.
                    if let Ok(r) = self.interval_residual(&trial, k, &mut rows) {
                        if r < res && self.node_evaluates(&trial, k, &mut scratch) {
                            for &col in &cols {
                                v[col] = trial[col];
                            }
                            res = r;
                            taken = true;
                            break;
                        }
                    }
                    alpha *= 0.5;
                }
                for &col in &cols {
                    trial[col] = v[col];
                }
                if !taken {
                    break;
                }
                // rows hold the defects of the step taken: v's now.
            }
            report.converged += usize::from(res <= MESH_NEWTON_TOL);
            if res > MESH_NEWTON_TOL {
                match held {
                    Some(_) => report.at_bound += 1,
                    None => report.stopped_short += 1,
                }
                report
                    .first_unsolved
                    .get_or_insert_with(|| UnsolvedInterval {
                        interval: k,
                        defect: res,
                        held: held.map(|(state, lower)| HeldState {
                            state,
                            name: names.get(state).cloned().unwrap_or_default(),
                            lower,
                        }),
                    });
            }
            if res > report.worst_defect {
                // rows may hold a rejected trial's defects: v's again.
                self.interval_residual(v, k, &mut rows)?;
                report.worst_state = (0..nx)
                    .max_by(|&a, &b| rows[a].abs().total_cmp(&rows[b].abs()))
                    .unwrap_or(0);
                report.worst_state_name =
                    names.get(report.worst_state).cloned().unwrap_or_default();
                report.worst_defect = res;
                report.worst_interval = k;
            }
        }
        Ok(report)
    }

    /// Set the point [`Nlp::initial_point`] returns (default: the squat
    /// held at every node, t_f = 0.3 s; see [`Self::bang_bang_guess`]).
    pub fn set_initial_point(&mut self, v: &[f64]) -> Result<(), TranscriptionError> {
        if v.len() != self.num_variables() {
            return Err(TranscriptionError::Guess(format!(
                "{} values, the problem has {} variables",
                v.len(),
                self.num_variables()
            )));
        }
        self.initial = v.to_vec();
        Ok(())
    }

    /// Non-zeros of the constraint Jacobian.
    pub fn jacobian_nnz(&self) -> usize {
        self.structure.len()
    }

    /// [`Backend::Simbody`]: how the columns are differenced (default
    /// central, [`FD_STEP`]); e.g. a smaller step or one side to tell a
    /// curve's kink from a wrong derivative.
    pub fn set_differences(&mut self, d: Differences) -> Result<(), TranscriptionError> {
        let (Differences::Central { step }
        | Differences::Forward { step }
        | Differences::Backward { step }) = d;
        if !(step.is_finite() && step > 0.0 && step < 1.0) {
            return Err(TranscriptionError::Invalid(format!(
                "difference step must lie in (0, 1), got {step}"
            )));
        }
        if self.options.backend != Backend::Simbody {
            return Err(TranscriptionError::Invalid(
                "differences need the Simbody backend".into(),
            ));
        }
        for w in &mut self.workers {
            if let Some(p) = &mut w.simbody {
                p.differences = d;
            }
        }
        Ok(())
    }

    /// Points where the state equation is evaluated (midpoints, nodes,
    /// Hermite–Simpson centres).
    pub fn num_points(&self) -> usize {
        self.points.len()
    }

    /// Sizes of the Jacobian and its blocks.
    pub fn jacobian_stats(&self) -> JacobianStats {
        let [_, cm, lo, cv, end] = self.block_offsets;
        let nx = self.nx;
        let first = self.structure.iter().take_while(|&&(r, _)| r < nx).count();
        let second = self
            .structure
            .iter()
            .filter(|&&(r, _)| (nx..2 * nx).contains(&r))
            .count();
        JacobianStats {
            nnz: end,
            nnz_defects: cm,
            nnz_no_countermovement: lo - cm,
            nnz_liftoff: cv - lo,
            nnz_no_descent: end - cv,
            nnz_first_interval: first,
            nnz_interval: if self.num_intervals() >= 2 { second } else { 0 },
            nnz_state_equation: self.pattern.nnz_f(),
            state_equation_entries: nx * (nx + self.nu),
            colors: self.compiled.num_colors,
            passes: self.compiled.passes.len(),
            lanes: LANES,
        }
    }

    /// Rows of the defects, the no-countermovement inequalities and the lift-off row.
    pub fn defect_rows(&self) -> std::ops::Range<usize> {
        0..self.num_intervals() * self.nx
    }
    pub fn no_countermovement_rows(&self) -> std::ops::Range<usize> {
        let s = self.num_intervals() * self.nx;
        s..s + self.n_cm
    }
    pub fn liftoff_row(&self) -> usize {
        self.num_intervals() * self.nx + self.n_cm
    }
    /// Rows Ẏ_C(t_k) ≥ 0, k = 1..N (empty without `no_com_descent`).
    pub fn no_descent_rows(&self) -> std::ops::Range<usize> {
        let s = self.liftoff_row() + 1;
        s..s + self.n_cv
    }

    /// (q, q̇) of node k: the columns of J and of the no-descent rows.
    fn node_kinematic_state<'a>(&'a self, v: &'a [f64], k: usize) -> &'a [f64] {
        &self.node_state(v, k)[..2 * self.ocp.nq()]
    }

    /// The defect rows grouped by their node columns S_r = pattern(f_r) ∪
    /// {r} (increasing), in order of each group's first row.
    fn defect_row_groups(&self) -> Vec<(Vec<usize>, Vec<usize>)> {
        let mut groups: Vec<(Vec<usize>, Vec<usize>)> = Vec::new();
        for r in 0..self.nx {
            let cols = node_columns(&self.pattern.rows[r], r, self.node_size());
            match groups.iter_mut().find(|g| g.0 == cols) {
                Some(g) => g.1.push(r),
                None => groups.push((cols, vec![r])),
            }
        }
        groups
    }

    /// Y_C, Ẏ_C and J = Y_C + Ẏ_C²/(2g) at the final node.
    pub fn jump_objective(&self, v: &[f64]) -> (f64, f64, f64) {
        let mut ws = self.ocp.eq.multibody.workspace::<f64>();
        self.ocp
            .jump_objective(&mut ws, self.node_state(v, self.num_intervals()))
    }

    /// Evaluate g (and with `jac` its Jacobian) at every point, in parallel:
    /// the nodes and midpoints, then (Hermite–Simpson) the interval centres,
    /// whose states depend on the node values.
    fn eval_points(&mut self, v: &[f64], jac: bool) -> Result<(), EvalError> {
        let what = if jac { "jacobian" } else { "constraints" };
        if v.len() != self.num_variables() {
            return Err(EvalError::new(
                what,
                format!(
                    "{} values, the problem has {} variables",
                    v.len(),
                    self.num_variables()
                ),
            ));
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(EvalError::new(
                what,
                format!("{} is {}", self.variable_name(i), v[i]),
            ));
        }
        let first_stage = self.first_stage;
        self.eval_stage(v, jac, 0, first_stage)
            .map_err(|e| EvalError::new(what, e))?;
        if first_stage < self.points.len() {
            let all = self.points.len();
            self.eval_stage(v, jac, first_stage, all)
                .map_err(|e| EvalError::new(what, e))?;
        }
        Ok(())
    }

    /// Evaluate points `lo..hi`; earlier points' values are available.
    fn eval_stage(&mut self, v: &[f64], jac: bool, lo: usize, hi: usize) -> Result<(), String> {
        let (nx, nu) = (self.nx, self.nu);
        let lm0 = 2 * self.ocp.nq();
        let fiber_speed = &self.fiber_speed[..];
        let nv = nx + nu;
        let nout = nx + 2;
        let ocp: &JumpOcp = &self.ocp;
        let cp = &self.compiled;
        let nnz = cp.entries.len();
        let points = &self.points[lo..hi];
        let node_point = &self.node_point;
        let node0 = &self.node0;
        let h = v[self.final_time_index()] / self.num_intervals() as f64;
        let (done_vals, todo_vals) = self.point_vals.split_at_mut(lo * nout);
        let todo_vals = &mut todo_vals[..(hi - lo) * nout];
        let todo_jac = &mut self.point_jac[lo * nnz..hi * nnz];
        let done_vals: &[f64] = done_vals;
        let node = |k: usize| -> (&[f64], &[f64]) {
            if k == 0 {
                (ocp.x0(), ocp.u0())
            } else {
                let o = (k - 1) * nv;
                (&v[o..o + nx], &v[o + nx..o + nv])
            }
        };
        // f at node k from the first stage (node 0: the fixed start).
        let node_f = |k: usize| node_f(node_point, done_vals, nout, &node0[..nx], k);
        let run = |w: &mut Worker<LANES>,
                   (first, pts, vals, jacs): (usize, &[Point], &mut [f64], &mut [f64])|
         -> Result<(), (usize, String)> {
            for (i, &p) in pts.iter().enumerate() {
                set_point_inputs(p, node, node_f, h, (lm0, fiber_speed), &mut w.x, &mut w.u);
                let out = &mut vals[i * nout..(i + 1) * nout];
                let r = if jac {
                    eval_jac(
                        ocp,
                        cp,
                        w,
                        out,
                        &mut jacs[i * nnz..(i + 1) * nnz],
                        None,
                        None,
                    )
                } else {
                    eval_value(ocp, w, out)
                };
                r.map_err(|e| (first + i, e))?;
            }
            Ok(())
        };
        // Values alone (36 evaluations of ~10 µs) do not repay starting a
        // thread: measured 0.35 ms on one thread, 0.5-0.7 ms on two.
        let threads = if jac { self.workers.len() } else { 1 };
        let nt = threads.min(points.len()).max(1);
        let per = points.len().div_ceil(nt).max(1);
        let jobs = todo_vals
            .chunks_mut(per * nout)
            .zip(todo_jac.chunks_mut(per * nnz.max(1)))
            .zip(points.chunks(per).enumerate())
            .map(|((vals, jacs), (ci, pts))| (lo + ci * per, pts, vals, jacs));
        run_jobs(&mut self.workers, jobs, lo, &run)
            .map_err(|(p, e)| format!("{}: {e}", self.points[p]))
    }

    /// The defect block values of the Hermite–Simpson scheme, in structure
    /// order (see [`Scheme::HermiteSimpson`]):
    ///
    /// ```text
    ///   ∂d/∂z_{k−1} = −[I 0] − (h/6)F_{k−1} − (h/3)F_c − (h²/12)·F_c^x·F_{k−1}
    ///   ∂d/∂z_k     =  [I 0] − (h/6)F_k     − (h/3)F_c + (h²/12)·F_c^x·F_k
    ///   ∂d/∂t_f     = −(f_{k−1} + 4f_c + f_k)/(6N) − (h/(12N))·F_c^x·(f_{k−1} − f_k)
    /// ```
    fn hermite_simpson_jacobian(&mut self, h: f64, values: &mut [f64]) {
        for k in 1..=self.num_intervals() {
            let e = self.defect_entries(k);
            self.hermite_simpson_interval_jacobian(k, h, &mut values[e]);
        }
    }

    /// The entries (a range of [`Nlp::jacobian_structure`]) of interval k's
    /// defect rows, which the structure holds interval by interval.
    fn defect_entries(&self, k: usize) -> std::ops::Range<usize> {
        let block = &self.structure[..self.block_offsets[1]];
        let nx = self.nx;
        block.partition_point(|&(r, _)| r < (k - 1) * nx)
            ..block.partition_point(|&(r, _)| r < k * nx)
    }

    /// [`Self::hermite_simpson_jacobian`] of interval k into `values`, its
    /// entries, from the point evaluations of its nodes and centre.
    fn hermite_simpson_interval_jacobian(&mut self, k: usize, h: f64, values: &mut [f64]) {
        let (nx, big_n) = (self.nx, self.num_intervals());
        let nout = nx + 2;
        let nnz = self.compiled.entries.len();
        let inv_n = 1.0 / big_n as f64;
        let mut scratch = std::mem::take(&mut self.scratch);
        let mut out = values.iter_mut();
        let pc = self.interval_point[k - 1];
        let jc = &self.point_jac[pc * nnz..(pc + 1) * nnz];
        let fc = &self.point_vals[pc * nout..pc * nout + nx];
        let fval = |k: usize| -> &[f64] {
            match self.node_point[k] {
                Some(p) => &self.point_vals[p * nout..p * nout + nx],
                None => &self.node0[..nx],
            }
        };
        let (fa, fb) = (fval(k - 1), fval(k));
        let pb = self.node_point[k].unwrap_or(0);
        let jb = &self.point_jac[pb * nnz..(pb + 1) * nnz];
        for r in 0..nx {
            let cols = &self.hs_rows[r];
            let prods = &self.hs_prods[r];
            for (node_jac, sign) in [
                (
                    if k >= 2 {
                        self.node_point[k - 1].map(|p| &self.point_jac[p * nnz..(p + 1) * nnz])
                    } else {
                        None
                    },
                    -1.0,
                ),
                (Some(jb), 1.0),
            ] {
                let Some(jn) = node_jac else { continue };
                // scratch = row r of F_c^x·F_node.
                for &(sr, e_rs) in prods {
                    let a = jc[e_rs];
                    for e in self.compiled.row_start[sr]..self.compiled.row_start[sr + 1] {
                        scratch[self.compiled.entries[e].1] += a * jn[e];
                    }
                }
                for &(c, e, d) in cols {
                    let (fnode, fcen) = e.map_or((0.0, 0.0), |e| (jn[e], jc[e]));
                    let v = sign * d - h / 6.0 * fnode - h / 3.0 * fcen
                        + sign * h * h / 12.0 * scratch[c];
                    scratch[c] = 0.0;
                    if let Some(o) = out.next() {
                        *o = v;
                    }
                }
            }
            let mut corr = 0.0;
            for &(sr, e_rs) in prods {
                corr += jc[e_rs] * (fa[sr] - fb[sr]);
            }
            if let Some(o) = out.next() {
                *o = -(fa[r] + 4.0 * fc[r] + fb[r]) * inv_n / 6.0 - h * inv_n / 12.0 * corr;
            }
        }
        self.scratch = scratch;
    }

    /// Evaluate the points interval k's defect rows read (with `jac`, their
    /// Jacobians too): its midpoint, or its nodes and then its
    /// Hermite–Simpson centre, which reads their values.
    fn eval_interval(&mut self, v: &[f64], k: usize, jac: bool) -> Result<(), EvalError> {
        let points = match self.options.scheme {
            Scheme::MidpointEuler => [Some(self.interval_point[k - 1]), None, None],
            Scheme::BackwardEuler => [self.node_point[k], None, None],
            Scheme::Trapezoidal => [self.node_point[k - 1], self.node_point[k], None],
            Scheme::HermiteSimpson => [
                self.node_point[k - 1],
                self.node_point[k],
                Some(self.interval_point[k - 1]),
            ],
        };
        for p in points.into_iter().flatten() {
            self.eval_stage(v, jac, p, p + 1)
                .map_err(|e| EvalError::new(if jac { "jacobian" } else { "constraints" }, e))?;
        }
        Ok(())
    }

    /// Interval k's defects (1..N) at v into `rows` (n_x values), and their
    /// largest magnitude: the values of those rows of [`Nlp::constraints`],
    /// from the interval's own points alone.
    pub fn interval_residual(
        &mut self,
        v: &[f64],
        k: usize,
        rows: &mut [f64],
    ) -> Result<f64, EvalError> {
        self.check_interval(v, k)?;
        check_len("constraints", "rows", rows.len(), self.nx)?;
        self.eval_interval(v, k, false)?;
        self.interval_defects(v, k, rows);
        if let Some(r) = rows.iter().position(|x| !x.is_finite()) {
            let row = (k - 1) * self.nx + r;
            return Err(EvalError::new(
                "constraints",
                format!("{} is {}", self.constraint_name(row), rows[r]),
            ));
        }
        Ok(crate::sqp::norm_inf(rows))
    }

    /// The n_x × n_x block of interval k's defect rows (1..N) in node k's
    /// states at v: those entries of [`Nlp::jacobian_values`], from the
    /// interval's own points alone.
    pub fn interval_state_jacobian(
        &mut self,
        v: &[f64],
        k: usize,
        jac: &mut nalgebra::DMatrix<f64>,
    ) -> Result<(), EvalError> {
        self.check_interval(v, k)?;
        let nx = self.nx;
        if jac.shape() != (nx, nx) {
            return Err(EvalError::new(
                "jacobian",
                format!("a {:?} block, the states are {nx}", jac.shape()),
            ));
        }
        self.eval_interval(v, k, true)?;
        let h = self.final_time(v) / self.num_intervals() as f64;
        let range = self.defect_entries(k);
        let mut hs = Vec::new();
        if self.options.scheme == Scheme::HermiteSimpson {
            hs = vec![0.0; range.len()];
            self.hermite_simpson_interval_jacobian(k, h, &mut hs);
        }
        jac.fill(0.0);
        for e in range.clone() {
            let (r, c) = self.structure[e];
            let Some((node, i)) = self.node_column(c) else {
                continue;
            };
            if node != k || i >= nx {
                continue;
            }
            jac[(r % nx, i)] += match self.source_value(self.sources[e], v, h) {
                Some(value) => value,
                None => hs.get(e - range.start).copied().unwrap_or(f64::NAN),
            };
        }
        Ok(())
    }

    /// v's length, k in 1..=N, and the values interval k reads (nodes k−1
    /// and k, t_f) finite, a bad one named.
    fn check_interval(&self, v: &[f64], k: usize) -> Result<(), EvalError> {
        check_len("interval", "v", v.len(), self.num_variables())?;
        if k == 0 || k > self.num_intervals() {
            return Err(EvalError::new(
                "interval",
                format!(
                    "interval {k}: the mesh has intervals 1..={}",
                    self.num_intervals()
                ),
            ));
        }
        let nv = self.node_size();
        let first = k.saturating_sub(2) * nv;
        finite("interval", &v[first..k * nv], |i| {
            self.variable_name(first + i)
        })?;
        let tf = self.final_time_index();
        finite("interval", &v[tf..=tf], |_| self.variable_name(tf))
    }

    /// Whether the points outside interval k that read node k (interval
    /// k + 1's, and node k's own point, whose Ÿ_C and ground force feed the
    /// no-countermovement and lift-off rows) evaluate to finite values at
    /// v: a step of node k in [`Self::integrate_on_mesh`] must keep the
    /// whole problem evaluable, not only its interval. `rows`: scratch.
    fn node_evaluates(&mut self, v: &[f64], k: usize, rows: &mut [f64]) -> bool {
        if k < self.num_intervals() && self.interval_residual(v, k + 1, rows).is_err() {
            return false;
        }
        let Some(p) = self.node_point[k] else {
            return true;
        };
        if self.eval_stage(v, false, p, p + 1).is_err() {
            return false;
        }
        let nout = self.nx + 2;
        self.point_vals[p * nout..(p + 1) * nout]
            .iter()
            .all(|x| x.is_finite())
    }

    /// The defect rows of interval `k` (1..N) into `c` (n_x values), from
    /// the point values of the last evaluation that covered its points.
    fn interval_defects(&self, x: &[f64], k: usize, c: &mut [f64]) {
        let nx = self.nx;
        let h = self.final_time(x) / self.num_intervals() as f64;
        let (xa, xb) = (self.node_state(x, k - 1), self.node_state(x, k));
        match self.options.scheme {
            Scheme::MidpointEuler => {
                let p = self.interval_point[k - 1];
                let f = &self.point_vals[p * (nx + 2)..p * (nx + 2) + nx];
                for r in 0..nx {
                    c[r] = if self.is_balance_row(r) {
                        f[r]
                    } else {
                        xb[r] - xa[r] - h * f[r]
                    };
                }
            }
            Scheme::BackwardEuler => {
                let pb = self.node_point[k];
                for r in 0..nx {
                    c[r] = xb[r] - xa[r] - h * self.point_val(pb, r);
                }
            }
            Scheme::Trapezoidal => {
                let (pa, pb) = (self.node_point[k - 1], self.node_point[k]);
                for r in 0..nx {
                    c[r] =
                        xb[r] - xa[r] - 0.5 * h * (self.point_val(pa, r) + self.point_val(pb, r));
                }
            }
            Scheme::HermiteSimpson => {
                let (pa, pb, pc) = (
                    self.node_point[k - 1],
                    self.node_point[k],
                    Some(self.interval_point[k - 1]),
                );
                for r in 0..nx {
                    c[r] = xb[r]
                        - xa[r]
                        - h / 6.0
                            * (self.point_val(pa, r)
                                + 4.0 * self.point_val(pc, r)
                                + self.point_val(pb, r));
                }
            }
        }
    }

    /// Jacobian entry `src` from the point evaluations at x (h = t_f/N);
    /// None for the entries filled block by block (Hermite–Simpson defects,
    /// Ẏ_C rows).
    fn source_value(&self, src: Src, x: &[f64], h: f64) -> Option<f64> {
        let nout = self.nx + 2;
        let nnz = self.compiled.entries.len();
        Some(match src {
            Src::Hs | Src::ComVelocity => return None,
            Src::Dyn {
                point,
                entry,
                diag,
                weight,
            } => match entry {
                Some(e) => diag - weight * h * self.point_jac[point * nnz + e],
                None => diag,
            },
            Src::Tf { a, b, row, scale } => {
                let fa = match a {
                    Term::Point(p) => self.point_vals[p * nout + row],
                    Term::Start => self.node0[row],
                    Term::None => 0.0,
                };
                -(fa + self.point_vals[b * nout + row]) * scale
            }
            Src::Out {
                point,
                entry,
                scale,
            } => scale * self.point_jac[point * nnz + entry],
            Src::Balance {
                point,
                entry,
                speed,
            } => {
                let j = &self.point_jac[point * nnz..(point + 1) * nnz];
                entry.map_or(0.0, |e| 0.5 * j[e]) + speed.map_or(0.0, |(e, s)| j[e] * s / h)
            }
            Src::BalanceTf {
                point,
                entry,
                row,
                k,
                inv_speed,
            } => {
                let dl = self.node_state(x, k)[row] - self.node_state(x, k - 1)[row];
                let vbar = dl * inv_speed / h;
                -self.point_jac[point * nnz + entry] * vbar / self.final_time(x)
            }
        })
    }

    fn point_val(&self, p: Option<usize>, r: usize) -> f64 {
        match p {
            Some(p) => self.point_vals[p * (self.nx + 2) + r],
            None => self.node0[r],
        }
    }
}

/// The inputs of the midpoint between nodes a and b into `x` and `u`: the
/// means, and after the excitations (implicit fibre dynamics, `u` longer
/// than the nodes' excitations) the normalised fibre velocities
/// (l^M_b − l^M_a)/(h·v_max·l_o) of the fibre lengths from `lm0` on.
fn midpoint_inputs(
    (xa, ua): (&[f64], &[f64]),
    (xb, ub): (&[f64], &[f64]),
    h: f64,
    (lm0, speed): (usize, &[f64]),
    x: &mut [f64],
    u: &mut [f64],
) {
    for j in 0..x.len() {
        x[j] = 0.5 * (xa[j] + xb[j]);
    }
    let nu = ua.len();
    for j in 0..nu {
        u[j] = 0.5 * (ua[j] + ub[j]);
    }
    for (i, v) in u[nu..].iter_mut().enumerate() {
        *v = (xb[lm0 + i] - xa[lm0 + i]) / (h * speed[i]);
    }
}

/// Row `r`'s columns among the node variables (below `nv`; a force
/// balance also depends on a fibre velocity, which is no variable) with
/// its own state, increasing.
fn node_columns(pattern_row: &[usize], r: usize, nv: usize) -> Vec<usize> {
    let mut cols: Vec<usize> = pattern_row.iter().copied().filter(|&c| c < nv).collect();
    cols.push(r);
    cols.sort_unstable();
    cols.dedup();
    cols
}

fn check_len(what: &str, name: &str, got: usize, want: usize) -> Result<(), EvalError> {
    if got == want {
        Ok(())
    } else {
        Err(EvalError::new(
            what,
            format!("{name} has length {got}, expected {want}"),
        ))
    }
}

fn finite(what: &str, v: &[f64], name: impl Fn(usize) -> String) -> Result<(), EvalError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(EvalError::new(what, format!("{} is {}", name(i), v[i]))),
        None => Ok(()),
    }
}

impl Nlp for Transcription {
    fn num_variables(&self) -> usize {
        self.num_intervals() * self.node_size() + 1
    }

    fn num_constraints(&self) -> usize {
        self.num_intervals() * self.nx + self.n_cm + 1 + self.n_cv
    }

    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        let ocp = &self.ocp;
        for k in 1..=self.num_intervals() {
            let o = (k - 1) * self.node_size();
            lower[o..o + self.nx].copy_from_slice(&ocp.state_lower);
            upper[o..o + self.nx].copy_from_slice(&ocp.state_upper);
            lower[o + self.nx..o + self.node_size()].copy_from_slice(&ocp.control_lower);
            upper[o + self.nx..o + self.node_size()].copy_from_slice(&ocp.control_upper);
        }
        let t = self.final_time_index();
        lower[t] = ocp.options.final_time_bounds[0];
        upper[t] = ocp.options.final_time_bounds[1];
    }

    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        for i in self.defect_rows() {
            lower[i] = 0.0;
            upper[i] = 0.0;
        }
        for i in self.no_countermovement_rows() {
            lower[i] = f64::NEG_INFINITY;
            upper[i] = 0.0;
        }
        let (a, b) = self.ocp.liftoff_bounds();
        lower[self.liftoff_row()] = a;
        upper[self.liftoff_row()] = b;
        for i in self.no_descent_rows() {
            lower[i] = 0.0;
            upper[i] = f64::INFINITY;
        }
    }

    fn initial_point(&self, x: &mut [f64]) {
        x.copy_from_slice(&self.initial);
    }

    fn objective(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        check_len("objective", "x", x.len(), self.num_variables())?;
        let (_, _, j) = self.jump_objective(x);
        if !j.is_finite() {
            return Err(EvalError::new(
                "objective",
                format!("J = {j} at the final node"),
            ));
        }
        Ok(-j)
    }

    fn gradient(&mut self, x: &[f64], g: &mut [f64]) -> Result<(), EvalError> {
        check_len("gradient", "x", x.len(), self.num_variables())?;
        check_len("gradient", "g", g.len(), self.num_variables())?;
        g.iter_mut().for_each(|v| *v = 0.0);
        let n2 = 2 * self.ocp.nq();
        let big_n = self.num_intervals();
        let o = (big_n - 1) * self.node_size();
        let mut ws = self.ocp.eq.multibody.workspace::<Dual64>();
        let mut xd = vec![Dual64::from(0.0); n2];
        jump_objective_gradient(
            &self.ocp,
            (&mut ws, &mut xd),
            self.node_kinematic_state(x, big_n),
            2,
            &mut g[o..o + n2],
        );
        g[o..o + n2].iter_mut().for_each(|v| *v = -*v);
        finite("gradient", g, |i| self.variable_name(i))
    }

    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        check_len("constraints", "c", c.len(), self.num_constraints())?;
        let start = std::time::Instant::now();
        self.eval_points(x, false)?;
        let (nx, big_n) = (self.nx, self.num_intervals());
        for k in 1..=big_n {
            self.interval_defects(x, k, &mut c[(k - 1) * nx..k * nx]);
        }
        for j in 0..self.n_cm {
            c[big_n * nx + j] =
                self.point_val(self.node_point[j], nx) - self.point_val(self.node_point[j + 1], nx);
        }
        c[self.liftoff_row()] = self.point_val(self.node_point[big_n], nx + 1);
        if self.n_cv > 0 {
            let mut ws = self.ocp.eq.multibody.workspace::<f64>();
            for (k, row) in (1..).zip(self.no_descent_rows()) {
                c[row] = self
                    .ocp
                    .jump_objective(&mut ws, self.node_kinematic_state(x, k))
                    .1;
            }
        }
        self.counters.constraints += 1;
        self.counters.constraints_time += start.elapsed().as_secs_f64();
        finite("constraints", c, |i| self.constraint_name(i))
    }

    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        self.structure.clone()
    }

    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        check_len("jacobian", "values", values.len(), self.jacobian_nnz())?;
        let start = std::time::Instant::now();
        self.eval_points(x, true)?;
        let h = self.final_time(x) / self.num_intervals() as f64;
        if self.options.scheme == Scheme::HermiteSimpson {
            self.hermite_simpson_jacobian(h, &mut values[..self.block_offsets[1]]);
        }
        for (v, &src) in values.iter_mut().zip(&self.sources) {
            if let Some(value) = self.source_value(src, x, h) {
                *v = value;
            }
        }
        if self.n_cv > 0 {
            let n2 = 2 * self.ocp.nq();
            let rows = &mut values[self.block_offsets[3]..self.block_offsets[4]];
            let mut ws = self.ocp.eq.multibody.workspace::<Dual64>();
            let mut xd = vec![Dual64::from(0.0); n2];
            for (k, g) in (1..).zip(rows.chunks_exact_mut(n2)) {
                let xk = self.node_kinematic_state(x, k);
                jump_objective_gradient(&self.ocp, (&mut ws, &mut xd), xk, 1, g);
            }
        }
        self.counters.jacobians += 1;
        self.counters.jacobian_time += start.elapsed().as_secs_f64();
        finite("jacobian", values, |i| {
            let (r, c) = self.structure[i];
            format!("∂{}/∂{}", self.constraint_name(r), self.variable_name(c))
        })
    }

    fn elements(&self) -> Vec<Element> {
        let big_n = self.num_intervals();
        let nv = self.node_size();
        let nx = self.nx;
        let tf = self.final_time_index();
        let mut out = Vec::with_capacity(big_n + self.n_cm + 1);
        if self.options.scheme == Scheme::HermiteSimpson {
            // The centre state couples every row to all of f at both nodes:
            // one element per interval.
            for k in 1..=big_n {
                let start = if k >= 2 { (k - 2) * nv } else { 0 };
                let mut variables: Vec<usize> = (start..k * nv).collect();
                variables.push(tf);
                out.push(Element {
                    variables,
                    constraints: ((k - 1) * nx..k * nx).collect(),
                    objective: false,
                    blocks: Vec::new(),
                });
            }
        } else {
            // Midpoint and trapezoidal defect row r depends on the node
            // columns S_r = pattern(f_r) ∪ {r} of both nodes and on t_f.
            // Rows with the same S_r form one element per interval: the q̈
            // rows (dense over q, q̇, l^M) together, every other row alone
            // (q_j with q̇_j; l^M_i with a_i and the coordinates its path
            // spans; a_i with u_i). Small elements keep the stiff curvature
            // of contact and tendons out of the excitations' BFGS blocks
            // and the QP's Hessian sparse.
            //
            // Blocks for the block-diagonal approximation: in an element
            // with several fibre lengths (the q̈ rows), each l^M_i (at both
            // nodes) is a block of its own and the rest (q, q̇, t_f) one
            // block. Dropping the l^M–q curvature shrinks the QP's KKT
            // factor from 363k to 149k non-zeros and a QP solve from 2.2 to
            // 0.5 s (a QP of iteration 20, `examples/sqp_jump_dump` and
            // `qp_replay`).
            let (lm0, nm) = (2 * self.ocp.nq(), self.ocp.nm());
            let is_lm = |c: usize| (lm0..lm0 + nm).contains(&c);
            for group in &self.groups {
                let cols = &group.0;
                let fibre_cols = cols.iter().filter(|&&c| is_lm(c)).count();
                for k in 1..=big_n {
                    let mut variables = Vec::with_capacity(2 * cols.len() + 1);
                    let mut local_cols = Vec::with_capacity(2 * cols.len());
                    for node in [k - 1, k] {
                        if node >= 1 {
                            variables.extend(cols.iter().map(|&c| (node - 1) * nv + c));
                            local_cols.extend(cols.iter().copied());
                        }
                    }
                    variables.push(tf);
                    let blocks = if fibre_cols >= 2 {
                        let mut head = Vec::new();
                        let mut leaves: Vec<Vec<usize>> = vec![Vec::new(); nm];
                        for (a, &c) in local_cols.iter().enumerate() {
                            if is_lm(c) {
                                leaves[c - lm0].push(a);
                            } else {
                                head.push(a);
                            }
                        }
                        head.push(local_cols.len());
                        leaves.retain(|l| !l.is_empty());
                        leaves.insert(0, head);
                        leaves
                    } else {
                        Vec::new()
                    };
                    out.push(Element {
                        variables,
                        constraints: group.1.iter().map(|&r| (k - 1) * nx + r).collect(),
                        objective: false,
                        blocks,
                    });
                }
            }
        }
        for j in 0..self.n_cm {
            let mut variables = Vec::new();
            for node in [j, j + 1] {
                if node >= 1 {
                    variables.extend(self.ydd_cols.iter().map(|&c| (node - 1) * nv + c));
                }
            }
            out.push(Element {
                variables,
                constraints: vec![big_n * nx + j],
                objective: false,
                blocks: Vec::new(),
            });
        }
        out.push(Element {
            variables: self
                .final_cols
                .iter()
                .map(|&c| (big_n - 1) * nv + c)
                .collect(),
            constraints: vec![self.liftoff_row()],
            objective: true,
            blocks: Vec::new(),
        });
        for (k, row) in (1..=self.n_cv).zip(self.no_descent_rows()) {
            out.push(Element {
                variables: (0..2 * self.ocp.nq()).map(|c| (k - 1) * nv + c).collect(),
                constraints: vec![row],
                objective: false,
                blocks: Vec::new(),
            });
        }
        out
    }

    /// Every scheme, for models whose point passes separate (see `HessPlan`).
    fn has_hessian(&self) -> bool {
        self.hess_plan.is_some()
    }

    fn element_hessian(
        &mut self,
        x: &[f64],
        e: usize,
        sigma: f64,
        lambda: &[f64],
        h: &mut [f64],
    ) -> Result<(), EvalError> {
        self.hessian_of_element(x, e, sigma, lambda, h)
    }

    fn element_hessians(
        &mut self,
        x: &[f64],
        sigma: f64,
        lambda: &[f64],
        blocks: &mut [Vec<f64>],
    ) -> Result<(), EvalError> {
        self.hessians_of_elements(x, sigma, lambda, blocks)
    }

    fn variable_name(&self, i: usize) -> String {
        if i == self.final_time_index() {
            return "t_f".into();
        }
        let Some((k, c)) = self.node_column(i) else {
            return format!("variable {i}");
        };
        if c < self.nx {
            format!("node {k} {}", self.ocp.eq.state_names()[c])
        } else {
            format!("node {k} {}", self.ocp.eq.control_names()[c - self.nx])
        }
    }

    fn constraint_name(&self, i: usize) -> String {
        let nx = self.nx;
        if i < self.num_intervals() * nx && self.is_balance_row(i % nx) {
            let name = &self.ocp.eq.model.muscles[self.ocp.eq.muscles[i % nx - 2 * self.ocp.nq()]]
                .spec
                .name;
            format!("force balance of interval {} in {name}", i / nx + 1)
        } else if i < self.num_intervals() * nx {
            format!(
                "defect of interval {} in {}",
                i / nx + 1,
                self.ocp.eq.state_names()[i % nx]
            )
        } else if self.no_countermovement_rows().contains(&i) {
            let j = i - self.num_intervals() * nx;
            format!("no countermovement: Ÿ_C(node {j}) ≤ Ÿ_C(node {})", j + 1)
        } else if self.no_descent_rows().contains(&i) {
            let k = i - self.liftoff_row();
            format!("no descent: Ẏ_C(node {k}) ≥ 0")
        } else {
            "lift-off: vertical ground force at t_f / body weight".into()
        }
    }
}

/// Median time (s) of one Jacobian of g = (f, Ÿ_C, F_y/(m g)) at (x, u)
/// in `pattern` with `W` dual lanes per pass, over `reps` evaluations
/// (for choosing [`LANES`]; `W = 1` is one direction per pass).
pub fn time_point_jacobian<const W: usize>(
    ocp: &JumpOcp,
    pattern: &StatePattern,
    compress: bool,
    walk_paths_once: bool,
    x: &[f64],
    u: &[f64],
    reps: usize,
) -> Result<f64, String> {
    let nin = pattern.nx + pattern.nu;
    let cp = Compiled::new(&pattern.rows, nin, compress, W);
    let mut paths = FirstOrderPaths::new(ocp, &cp).filter(|_| walk_paths_once);
    let mut w = Worker::<W>::new(ocp, ocp.nu());
    w.x.copy_from_slice(x);
    w.u.copy_from_slice(u);
    let mut out = vec![0.0; pattern.nx + 2];
    let mut jac = vec![0.0; cp.entries.len()];
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps.max(1) {
        let t = std::time::Instant::now();
        eval_jac(ocp, &cp, &mut w, &mut out, &mut jac, None, paths.as_mut())?;
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(|a, b| a.total_cmp(b));
    Ok(times[times.len() / 2])
}

// ---------------------------------------------------------------------------
// Exact element Hessians of the Lagrangian (every scheme; Hermite–Simpson
// composes its centre's second derivatives with the nodes', see
// `hermite_simpson_hessian`).

/// The second-order passes over the state equation (HyperDualS<M, N>:
/// M eps1 and N eps2 directions; the cost of an operation grows with M·N):
/// 1. eps1 = q, eps2 = (q, q̇): every output's (q, q̇) × q block;
/// 2. eps1 = q̇, eps2 = q̇: the q̇ × q̇ block (position-level work stays f64);
/// 3. eps1 = (each l^M_i, Σa, Σu), eps2 = (q, q̇, Σl^M, Σa, Σu): the
///    rest. Kinematics and muscle paths depend on q and q̇ only, so there
///    they carry eps2 alone (first order); the second-order work is the
///    muscle forces and the dynamics.
///
/// Passes 2 and 3 take the muscle paths from one first-order evaluation
/// per point ([`PathPass`]) instead of walking them in their own numbers.
/// Pass 3 runs in chunks of [`HESS_B`] eps1 directions. Models with more
/// than [`HESS_Q`] coordinates have no exact Hessian.
const HESS_Q: usize = 7;
const HESS_B: usize = 13;
const HESS_N: usize = 2 * HESS_Q + 3;

/// How an input column of (x, u) is seeded in the second-order passes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ColClass {
    /// q and q̇: its own direction in eps1 and eps2.
    Full,
    /// A fibre length: its own eps1 direction, the sum of all fibre lengths in eps2.
    Fibre,
    /// An activation or excitation: the sum over its kind in eps1 and eps2.
    Summed,
}

/// The seeding of the second-order passes (see [`Transcription::element_hessian`]).
#[derive(Debug, Clone)]
struct HessPlan {
    /// eps1 and eps2 directions in total.
    m1: usize,
    n2: usize,
    /// Per input column: eps1 and eps2 direction, class.
    e1: Vec<usize>,
    e2: Vec<usize>,
    class: Vec<ColClass>,
    /// (n_x + 2) × n_in: whether output r depends on input c.
    in_pat: Vec<bool>,
    nin: usize,
    /// Values per output in the point data: m1 first derivatives, then the
    /// m1 × n2 second derivatives.
    block: usize,
}

impl HessPlan {
    /// The plan for `pattern`, or None where the seeding would not separate
    /// the second derivatives: more than 2·7 + 3 eps2 directions, or an
    /// output depending on several activations or excitations, or on
    /// activations or excitations and several fibre lengths.
    fn new(pattern: &StatePattern, n: usize, nm: usize) -> Option<Self> {
        let (nx, nu) = (pattern.nx, pattern.nu);
        let nin = nx + nu;
        // The point inputs u: excitations, or excitations and fibre
        // velocities (implicit fibre dynamics), both seeded as one sum.
        if nx != 2 * n + 2 * nm || (nu != nm && nu != 2 * nm) || n > HESS_Q {
            return None;
        }
        let (m1, n2) = (2 * n + nm + 2, 2 * n + 3);
        let mut e1 = vec![0; nin];
        let mut e2 = vec![0; nin];
        let mut class = vec![ColClass::Full; nin];
        for c in 0..nin {
            (e1[c], e2[c], class[c]) = if c < 2 * n {
                (c, c, ColClass::Full)
            } else if c < 2 * n + nm {
                (c, 2 * n, ColClass::Fibre)
            } else if c < nx {
                (2 * n + nm, 2 * n + 1, ColClass::Summed)
            } else {
                (2 * n + nm + 1, 2 * n + 2, ColClass::Summed)
            };
        }
        let mut in_pat = vec![false; (nx + 2) * nin];
        for (r, cols) in pattern.rows.iter().enumerate() {
            let (mut nl, mut na, mut nuu) = (0, 0, 0);
            for &c in cols {
                in_pat[r * nin + c] = true;
                if c >= 2 * n && c < 2 * n + nm {
                    nl += 1;
                } else if c >= 2 * n + nm && c < nx {
                    na += 1;
                } else if c >= nx {
                    nuu += 1;
                }
            }
            if na > 1 || nuu > 1 || (na + nuu > 0 && nl > 1) {
                return None;
            }
        }
        Some(HessPlan {
            m1,
            n2,
            e1,
            e2,
            class,
            in_pat,
            nin,
            block: m1 + m1 * n2,
        })
    }

    /// ∂²g_r/∂c∂d from output r's block of point data.
    #[inline]
    fn hess(&self, data: &[f64], r: usize, c: usize, d: usize) -> f64 {
        if !(self.in_pat[r * self.nin + c] && self.in_pat[r * self.nin + d]) {
            return 0.0;
        }
        let (i, j) = match (self.class[c], self.class[d]) {
            // q before q̇ (passes 1 and 2 fill the q and q̇ × q̇ rows only).
            (ColClass::Full, ColClass::Full) => (self.e1[c.min(d)], self.e2[c.max(d)]),
            (_, ColClass::Full) => (self.e1[c], self.e2[d]),
            (ColClass::Full, _) => (self.e1[d], self.e2[c]),
            // Muscle forces are separate: no fibre length couples another
            // (the eps2 direction is the sum over all of them).
            (ColClass::Fibre, ColClass::Fibre) if c != d => return 0.0,
            _ => (self.e1[c], self.e2[d]),
        };
        data[r * self.block + self.m1 + i * self.n2 + j]
    }

    /// ∂g_r/∂c from output r's block of point data.
    #[inline]
    fn grad(&self, data: &[f64], r: usize, c: usize) -> f64 {
        if !self.in_pat[r * self.nin + c] {
            return 0.0;
        }
        data[r * self.block + self.e1[c]]
    }
}

/// What an element of [`Nlp::elements`] holds.
#[derive(Debug, Clone, Copy)]
enum HessElement {
    /// The defect rows of group `group` in interval `k` (midpoint,
    /// trapezoidal, backward Euler).
    Defect { group: usize, k: usize },
    /// Every defect row of interval `k` (Hermite–Simpson).
    Interval(usize),
    /// No-countermovement row j.
    NoCountermovement(usize),
    /// Objective and lift-off row.
    Final,
    /// The no-descent row Ẏ_C(t_k) ≥ 0 of node k.
    ComVelocity(usize),
}

/// Buffers of one second-order pass.
struct PassBuf<const M: usize, const N: usize> {
    ws: StateWorkspace<HyperDualS<M, N>>,
    xd: Vec<HyperDualS<M, N>>,
    ud: Vec<HyperDualS<M, N>>,
    xdotd: Vec<HyperDualS<M, N>>,
}

impl<const M: usize, const N: usize> PassBuf<M, N> {
    fn new(ocp: &JumpOcp, nu: usize) -> Self {
        let nx = ocp.nx();
        let z = HyperDualS::<M, N>::from_re(0.0);
        PassBuf {
            ws: ocp.eq.workspace(),
            xd: vec![z; nx],
            ud: vec![z; nu],
            xdotd: vec![z; nx],
        }
    }

    /// One pass at (x, u): input column c seeded in eps1 direction
    /// `s1(c)` and eps2 direction `s2(c)`; output r's first derivatives
    /// along eps1 direction i go to plan row `row0 + i`, its second
    /// derivatives (i, j) to (`row0 + i`, `col0 + j`), for i < `m`, j < `n`.
    #[allow(clippy::too_many_arguments)]
    fn run(
        &mut self,
        ocp: &JumpOcp,
        plan: &HessPlan,
        x: &[f64],
        u: &[f64],
        s1: impl Fn(usize) -> Option<usize>,
        s2: impl Fn(usize) -> Option<usize>,
        (row0, m, col0, n): (usize, usize, usize, usize),
        out: &mut [f64],
    ) -> Result<(), String> {
        let nx = x.len();
        for c in 0..nx + u.len() {
            let v = if c < nx { x[c] } else { u[c - nx] };
            let mut d = HyperDualS::<M, N>::from_re(v);
            if let Some(i) = s1(c) {
                d = d.derivative1(i);
            }
            if let Some(j) = s2(c) {
                d = d.derivative2(j);
            }
            if c < nx {
                self.xd[c] = d;
            } else {
                self.ud[c - nx] = d;
            }
        }
        let (ydd, fy) = point_rates(ocp, &mut self.ws, &self.xd, &self.ud, &mut self.xdotd)?;
        let (m1, n2, block) = (plan.m1, plan.n2, plan.block);
        for r in 0..nx + 2 {
            let d = if r < nx {
                &self.xdotd[r]
            } else if r == nx {
                &ydd
            } else {
                &fy
            };
            // Every value of this pass's region is written, zeros where
            // the derivative is absent: the block is not cleared between
            // points (clearing it cost a tenth of the Hessian's time).
            let o = &mut out[r * block..(r + 1) * block];
            match &d.eps1 {
                Some(g) => o[row0..row0 + m].copy_from_slice(&g[..m]),
                None => o[row0..row0 + m].fill(0.0),
            }
            for i in 0..m {
                let base = m1 + (row0 + i) * n2 + col0;
                match &d.eps1eps2 {
                    Some(hm) => o[base..base + n].copy_from_slice(&hm[i][..n]),
                    None => o[base..base + n].fill(0.0),
                }
            }
        }
        Ok(())
    }
}

/// The muscle paths at one point to first order in (q, q̇), for the passes
/// that need no more of them (see [`GivenPaths`]): pass 2 seeds q̇ alone,
/// in which the paths are linear (lengths and unit forces do not depend on
/// q̇, speeds are linear in it), and pass 3 seeds q and q̇ in eps2 alone.
/// Walking the paths in those passes' hyper-dual numbers cost about as
/// much as the rest of the state equation.
struct PathPass {
    ws: StateWorkspace<DualSVec64<{ 2 * HESS_Q }>>,
    q: Vec<DualSVec64<{ 2 * HESS_Q }>>,
    qd: Vec<DualSVec64<{ 2 * HESS_Q }>>,
    out: GivenPaths<DualSVec64<{ 2 * HESS_Q }>>,
}

impl PathPass {
    fn new(ocp: &JumpOcp) -> Self {
        let n = ocp.nq();
        let z = DualSVec64::<{ 2 * HESS_Q }>::from(0.0);
        PathPass {
            ws: ocp.eq.workspace(),
            q: vec![z; n],
            qd: vec![z; n],
            out: GivenPaths::default(),
        }
    }

    /// The paths at the (q, q̇) of `x`, q_i seeded in direction i and q̇_i
    /// in direction n + i.
    fn run(&mut self, ocp: &JumpOcp, x: &[f64]) -> Result<(), String> {
        let n = ocp.nq();
        for i in 0..n {
            self.q[i] = DualSVec64::from_re(x[i]).derivative(i);
            self.qd[i] = DualSVec64::from_re(x[n + i]).derivative(n + i);
        }
        ocp.eq
            .path_values(&mut self.ws, &self.q, &self.qd, &mut self.out)
            .map_err(|e| e.to_string())
    }

    /// The paths' values mapped one by one into `to` by `one`.
    fn lift_each<T: crate::scalar::Scalar>(
        &self,
        one: impl Fn(&DualSVec64<{ 2 * HESS_Q }>) -> T,
        to: &mut Option<GivenPaths<T>>,
    ) {
        let to = to.get_or_insert_with(GivenPaths::default);
        to.at.clone_from(&self.out.at);
        for (dst, src) in [
            (&mut to.length, &self.out.length),
            (&mut to.speed, &self.out.speed),
            (&mut to.unit, &self.out.unit),
        ] {
            dst.clear();
            dst.extend(src.iter().map(&one));
        }
    }

    /// The paths lifted into a first-order pass's numbers: direction c of
    /// (q, q̇) goes to lane `lanes[c]` (summed where two share one).
    fn lift_first_order<const W: usize>(
        &self,
        lanes: &[Option<usize>],
        to: &mut Option<GivenPaths<DualSVec64<W>>>,
    ) {
        let one = |d: &DualSVec64<{ 2 * HESS_Q }>| {
            let mut e = [0.0; W];
            let mut any = false;
            if let Some(src) = &d.eps.0 {
                for (c, lane) in lanes.iter().enumerate() {
                    if let Some(l) = *lane {
                        if src[c] != 0.0 {
                            e[l] += src[c];
                            any = true;
                        }
                    }
                }
            }
            let mut v = DualSVec64::<W>::from(d.re);
            if any {
                v.eps = num_dual::Derivative::some(nalgebra::SVector::from(e));
            }
            v
        };
        self.lift_each(one, to);
    }

    /// The paths lifted into a pass's numbers: direction c of (q, q̇) goes
    /// to eps1 direction `s1(c)` and eps2 direction `s2(c)`; no second
    /// derivatives (exact where the pass's seeds enter the paths at most
    /// linearly, or in eps2 alone).
    fn lift<const M: usize, const N: usize>(
        &self,
        s1: impl Fn(usize) -> Option<usize>,
        s2: impl Fn(usize) -> Option<usize>,
        to: &mut Option<GivenPaths<HyperDualS<M, N>>>,
    ) {
        let dirs = 2 * self.q.len();
        let one = |d: &DualSVec64<{ 2 * HESS_Q }>| {
            let mut h = HyperDualS::<M, N>::from_re(d.re);
            if let Some(e) = &d.eps.0 {
                let mut e1 = [0.0; M];
                let mut e2 = [0.0; N];
                let (mut any1, mut any2) = (false, false);
                for c in 0..dirs {
                    if e[c] == 0.0 {
                        continue;
                    }
                    if let Some(i) = s1(c) {
                        e1[i] = e[c];
                        any1 = true;
                    }
                    if let Some(j) = s2(c) {
                        e2[j] = e[c];
                        any2 = true;
                    }
                }
                h.eps1 = any1.then_some(e1);
                h.eps2 = any2.then_some(e2);
            }
            h
        };
        self.lift_each(one, to);
    }
}

/// Buffers of one second-order evaluation thread.
struct HessWorker {
    a: PassBuf<HESS_Q, { 2 * HESS_Q }>,
    b: PassBuf<HESS_Q, HESS_Q>,
    c: PassBuf<HESS_B, HESS_N>,
    paths: PathPass,
    x: Vec<f64>,
    u: Vec<f64>,
}

impl HessWorker {
    /// A worker for `nu` point inputs ([`point_inputs`]).
    fn new(ocp: &JumpOcp, nu: usize) -> Self {
        HessWorker {
            a: PassBuf::new(ocp, nu),
            b: PassBuf::new(ocp, nu),
            c: PassBuf::new(ocp, nu),
            paths: PathPass::new(ocp),
            x: vec![0.0; ocp.nx()],
            u: vec![0.0; nu],
        }
    }
}

/// The point second derivatives, computed once per x.
struct HessCache {
    workers: Vec<HessWorker>,
    /// The x the data belong to (empty: none).
    x: Vec<f64>,
    /// Per point, per output g_r: [`HessPlan::block`] values.
    data: Vec<f64>,
    /// Per point, f (n_x values).
    vals: Vec<f64>,
    /// Hessian of J over the final node's (q, q̇), 2n × 2n.
    objective: Vec<f64>,
    /// Scratch: a λ-weighted block and gradient.
    hw: Vec<f64>,
    gw: Vec<f64>,
}

/// Pass 1's seeding: q_i in eps1 direction i, (q, q̇) in eps2.
fn pass1_seeds(
    n: usize,
) -> (
    impl Fn(usize) -> Option<usize>,
    impl Fn(usize) -> Option<usize>,
) {
    (
        move |c| (c < n).then_some(c),
        move |c| (c < 2 * n).then_some(c),
    )
}

/// Pass 2's seeding: q̇_i in eps1 and eps2 direction i.
fn pass2_seed(n: usize) -> impl Fn(usize) -> Option<usize> + Copy {
    move |c| (n..2 * n).contains(&c).then(|| c - n)
}

/// The muscle paths of passes 2 and 3 at the worker's (q, q̇) (see
/// [`PathPass`]).
fn given_paths(ocp: &JumpOcp, plan: &HessPlan, w: &mut HessWorker) -> Result<(), String> {
    let n = ocp.nq();
    w.paths.run(ocp, &w.x)?;
    w.paths
        .lift(pass2_seed(n), pass2_seed(n), &mut w.b.ws.given_paths);
    w.paths
        .lift(|_| None, |c| Some(plan.e2[c]), &mut w.c.ws.given_paths);
    Ok(())
}

/// First and second derivatives of g = (f, Ÿ_C, F_y/(m g)) at the worker's
/// (x, u) into `out` (per output, [`HessPlan::block`] values; see
/// [`HESS_Q`] for the passes), and f into `vals`.
fn eval_hess_point(
    ocp: &JumpOcp,
    plan: &HessPlan,
    w: &mut HessWorker,
    out: &mut [f64],
    vals: &mut [f64],
) -> Result<(), String> {
    let (n, nm) = (ocp.nq(), ocp.nm());
    // The passes write every value they own (see `PassBuf::run`); the
    // rest of `out` (second derivatives of q̇ × q and of (q, q̇) × the
    // muscle directions, read through symmetry) stays as allocated, zero.
    given_paths(ocp, plan, w)?;
    let (x, u) = (&w.x[..], &w.u[..]);
    // 1. q × (q, q̇).
    let (s1, s2) = pass1_seeds(n);
    w.a.run(ocp, plan, x, u, s1, s2, (0, n, 0, 2 * n), out)?;
    for (v, d) in vals.iter_mut().zip(&w.a.xdotd) {
        *v = d.re;
    }
    // 2. q̇ × q̇.
    w.b.run(
        ocp,
        plan,
        x,
        u,
        pass2_seed(n),
        pass2_seed(n),
        (n, n, n, n),
        out,
    )?;
    // 3. (l^M_i, Σa, Σu) × (q, q̇, Σl^M, Σa, Σu).
    // Muscles outside a chunk stay first order in their own work.
    for lo in (0..nm + 2).step_by(HESS_B) {
        let hi = (lo + HESS_B).min(nm + 2);
        w.c.run(
            ocp,
            plan,
            x,
            u,
            |c| {
                let i = plan.e1[c];
                (c >= 2 * n && (2 * n + lo..2 * n + hi).contains(&i)).then(|| i - 2 * n - lo)
            },
            |c| Some(plan.e2[c]),
            (2 * n + lo, hi - lo, 0, plan.n2),
            out,
        )?;
    }
    let block = plan.block;
    if let Some(i) = out.iter().position(|v| !v.is_finite()) {
        return Err(format!(
            "derivative {} of output {} is {}",
            i % block,
            i / block,
            out[i]
        ));
    }
    Ok(())
}

impl Transcription {
    /// Compute the second derivatives at every point (in parallel) and of
    /// the objective, unless they are cached for this x.
    fn refresh_hessian(&mut self, v: &[f64]) -> Result<(), EvalError> {
        let Some(plan) = &self.hess_plan else {
            return Err(EvalError::new(
                "hessian",
                "no exact Hessian for this scheme or model",
            ));
        };
        if self.hess.as_ref().is_some_and(|h| h.x == v) {
            return Ok(());
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(EvalError::new(
                "hessian",
                format!("{} is {}", self.variable_name(i), v[i]),
            ));
        }
        let start = std::time::Instant::now();
        let ocp: &JumpOcp = &self.ocp;
        let npts = self.points.len();
        let nout = self.nx + 2;
        let block = plan.block;
        let threads = self.options.threads;
        // The point inputs (excitations, and implicit: fibre velocities).
        let npu = self.pattern.nu;
        let h = v[self.final_time_index()] / self.num_intervals() as f64;
        let cache = self.hess.get_or_insert_with(|| {
            Box::new(HessCache {
                workers: (0..threads).map(|_| HessWorker::new(ocp, npu)).collect(),
                x: Vec::new(),
                data: vec![0.0; npts * nout * block],
                vals: vec![0.0; npts * self.nx],
                objective: Vec::new(),
                hw: Vec::new(),
                gw: Vec::new(),
            })
        });
        cache.x.clear();
        let (nx, nu) = (self.nx, self.nu);
        let nv = nx + nu;
        let (lm0, fiber_speed) = (2 * ocp.nq(), &self.fiber_speed[..]);
        let node = |k: usize| -> (&[f64], &[f64]) {
            if k == 0 {
                (ocp.x0(), ocp.u0())
            } else {
                let o = (k - 1) * nv;
                (&v[o..o + nx], &v[o + nx..o + nv])
            }
        };
        // Node f values (Hermite–Simpson centres are placed by them).
        let node0 = &self.node0[..nx];
        let node_point = &self.node_point;
        let run = |w: &mut HessWorker,
                   (first, pts, done_vals, out, vals): (
            usize,
            &[Point],
            &[f64],
            &mut [f64],
            &mut [f64],
        )|
         -> Result<(), (usize, String)> {
            let node_f = |k: usize| node_f(node_point, done_vals, nx, node0, k);
            for (i, &p) in pts.iter().enumerate() {
                set_point_inputs(p, node, node_f, h, (lm0, fiber_speed), &mut w.x, &mut w.u);
                let o = &mut out[i * nout * block..(i + 1) * nout * block];
                eval_hess_point(ocp, plan, w, o, &mut vals[i * nx..(i + 1) * nx])
                    .map_err(|e| (first + i, e))?;
            }
            Ok(())
        };
        let points = &self.points[..];
        // Hermite–Simpson: the nodes first, then the centres.
        let stages: &[(usize, usize)] = if self.first_stage < npts {
            &[(0, self.first_stage), (self.first_stage, npts)]
        } else {
            &[(0, npts)]
        };
        for &(lo, hi) in stages {
            let (done_vals, todo_vals) = cache.vals.split_at_mut(lo * nx);
            let done_vals: &[f64] = done_vals;
            let todo_vals = &mut todo_vals[..(hi - lo) * nx];
            let todo_data = &mut cache.data[lo * nout * block..hi * nout * block];
            let pts = &points[lo..hi];
            let nt = cache.workers.len().min(pts.len()).max(1);
            let per = pts.len().div_ceil(nt).max(1);
            let jobs = todo_data
                .chunks_mut(per * nout * block)
                .zip(todo_vals.chunks_mut(per * nx))
                .zip(pts.chunks(per).enumerate())
                .map(|((out, vals), (ci, pts))| (lo + ci * per, pts, done_vals, out, vals));
            run_jobs(&mut cache.workers, jobs, lo, &run)
                .map_err(|(p, e)| EvalError::new("hessian", format!("{}: {e}", self.points[p])))?;
        }
        // Hessian of J over the final node's q, q̇.
        let n2 = 2 * self.ocp.nq();
        let mut obj = vec![0.0; n2 * n2];
        jump_objective_hessian(
            &self.ocp,
            self.node_kinematic_state(v, self.num_intervals()),
            2,
            &mut obj,
        );
        if let Some(i) = obj.iter().position(|v| !v.is_finite()) {
            return Err(EvalError::new(
                "hessian",
                format!("∂²J/∂x_{}∂x_{} is {}", i / n2, i % n2, obj[i]),
            ));
        }
        let Some(cache) = self.hess.as_mut() else {
            return Err(EvalError::new("hessian", "no cache"));
        };
        cache.objective = obj;
        cache.x.extend_from_slice(v);
        self.counters.hessians += 1;
        self.counters.hessian_time += start.elapsed().as_secs_f64();
        Ok(())
    }

    /// λ-weighted Hessian (into `hw`, |cols|², symmetric) and gradient
    /// (into `gw`) of Σ_r λ_r g_r over node-local columns `cols` at point `p`.
    fn weighted_block(
        plan: &HessPlan,
        data: &[f64],
        rows: &[(usize, f64)],
        cols: &[usize],
        hw: &mut Vec<f64>,
        gw: &mut Vec<f64>,
    ) {
        let ks = cols.len();
        hw.clear();
        hw.resize(ks * ks, 0.0);
        gw.clear();
        gw.resize(ks, 0.0);
        for &(r, l) in rows {
            if l == 0.0 {
                continue;
            }
            for a in 0..ks {
                gw[a] += l * plan.grad(data, r, cols[a]);
                for b in a..ks {
                    hw[a * ks + b] += l * plan.hess(data, r, cols[a], cols[b]);
                }
            }
        }
        for a in 0..ks {
            for b in 0..a {
                hw[a * ks + b] = hw[b * ks + a];
            }
        }
    }

    fn hessian_of_element(
        &mut self,
        x: &[f64],
        e: usize,
        sigma: f64,
        lambda: &[f64],
        h: &mut [f64],
    ) -> Result<(), EvalError> {
        // A COM-velocity element needs no point data.
        let refresh = self
            .hess_elements
            .get(e)
            .is_some_and(|k| !matches!(k, HessElement::ComVelocity(_)));
        self.prepare_hessian(x, lambda, refresh)?;
        self.hessian_of_fresh_element(x, e, sigma, lambda, h)
    }

    /// Check the lengths of x and λ and, if `refresh`, bring the point
    /// derivatives to x.
    fn prepare_hessian(
        &mut self,
        x: &[f64],
        lambda: &[f64],
        refresh: bool,
    ) -> Result<(), EvalError> {
        check_len("hessian", "x", x.len(), self.num_variables())?;
        check_len("hessian", "lambda", lambda.len(), self.num_constraints())?;
        if refresh {
            self.refresh_hessian(x)?;
        }
        Ok(())
    }

    /// Every element's Hessian, the point derivatives refreshed (and x
    /// compared with the last point's) once, not once per element.
    fn hessians_of_elements(
        &mut self,
        x: &[f64],
        sigma: f64,
        lambda: &[f64],
        blocks: &mut [Vec<f64>],
    ) -> Result<(), EvalError> {
        // Every transcription has defect elements, which need point data.
        self.prepare_hessian(x, lambda, true)?;
        for (e, h) in blocks.iter_mut().enumerate() {
            self.hessian_of_fresh_element(x, e, sigma, lambda, h)?;
        }
        Ok(())
    }

    /// [`Self::hessian_of_element`] once the point derivatives are
    /// refreshed at x and the lengths of x and λ checked.
    fn hessian_of_fresh_element(
        &mut self,
        x: &[f64],
        e: usize,
        sigma: f64,
        lambda: &[f64],
        h: &mut [f64],
    ) -> Result<(), EvalError> {
        let Some(&kind) = self.hess_elements.get(e) else {
            return Err(EvalError::new(
                "hessian",
                format!(
                    "element {e} does not exist ({} elements)",
                    self.hess_elements.len()
                ),
            ));
        };
        if let HessElement::ComVelocity(k) = kind {
            // Kinematics only: no point data needed.
            let n2 = 2 * self.ocp.nq();
            check_len("hessian", "h", h.len(), n2 * n2)?;
            let l = lambda[self.liftoff_row() + k];
            jump_objective_hessian(&self.ocp, self.node_kinematic_state(x, k), 1, h);
            h.iter_mut().for_each(|v| *v *= l);
            return finite("hessian", h, |i| format!("element {e} entry {i}"));
        }
        // A force balance's row, point input of v̄, Δl^M, t_f and v_max l_o.
        let balance = match kind {
            HessElement::Defect { group, k } => {
                let g = &self.groups[group].1;
                (g.len() == 1 && self.is_balance_row(g[0])).then(|| {
                    let r = g[0];
                    let i = r - 2 * self.ocp.nq();
                    (
                        r,
                        self.nx + self.nu + i,
                        self.node_state(x, k)[r] - self.node_state(x, k - 1)[r],
                        x[self.final_time_index()],
                        self.fiber_speed[i],
                    )
                })
            }
            _ => None,
        };
        let (Some(plan), Some(cache)) = (self.hess_plan.as_ref(), self.hess.as_mut()) else {
            return Err(EvalError::new("hessian", "no Hessian data"));
        };
        let (nx, big_n) = (self.nx, self.options.num_mesh_intervals);
        let stride = (nx + 2) * plan.block;
        let data = |p: usize| &cache.data[p * stride..(p + 1) * stride];
        let hstep = x[big_n * (nx + self.nu)] / big_n as f64;
        let inv_n = 1.0 / big_n as f64;
        let (mut hw, mut gw) = (std::mem::take(&mut cache.hw), std::mem::take(&mut cache.gw));
        match kind {
            HessElement::Defect { group, k } => {
                let (cols, grows) = &self.groups[group];
                let ks = cols.len();
                let nodes: Vec<usize> = [k - 1, k].into_iter().filter(|&n| n >= 1).collect();
                let kk = nodes.len() * ks + 1;
                check_len("hessian", "h", h.len(), kk * kk)?;
                h.iter_mut().for_each(|v| *v = 0.0);
                let rows: Vec<(usize, f64)> = grows
                    .iter()
                    .map(|&r| (r, lambda[(k - 1) * nx + r]))
                    .collect();
                let t = kk - 1;
                if let Some((r, vcol, dl, tf, speed)) = balance {
                    let p = self.interval_point[k - 1];
                    balance_hessian(
                        plan,
                        data(p),
                        (&rows, cols),
                        (r, vcol),
                        (hstep, tf, speed),
                        (dl, nodes.len()),
                        (&mut hw, &mut gw),
                        h,
                    );
                    cache.hw = hw;
                    cache.gw = gw;
                    return finite("hessian", h, |i| format!("element {e} entry {i}"));
                }
                match self.options.scheme {
                    Scheme::MidpointEuler => {
                        let p = self.interval_point[k - 1];
                        Self::weighted_block(plan, data(p), &rows, cols, &mut hw, &mut gw);
                        for bi in 0..nodes.len() {
                            for bj in 0..nodes.len() {
                                for a in 0..ks {
                                    for b in 0..ks {
                                        h[(bi * ks + a) * kk + bj * ks + b] =
                                            -0.25 * hstep * hw[a * ks + b];
                                    }
                                }
                            }
                            for a in 0..ks {
                                let v = -0.5 * inv_n * gw[a];
                                h[(bi * ks + a) * kk + t] = v;
                                h[t * kk + bi * ks + a] = v;
                            }
                        }
                    }
                    Scheme::Trapezoidal | Scheme::BackwardEuler => {
                        // Trapezoidal: both nodes with weight ½; backward
                        // Euler: node k with weight 1 (node k − 1 enters
                        // linearly). Per node: −w·h·∇²f_r, and −(w/N)·∇f_r
                        // with t_f.
                        let be = self.options.scheme == Scheme::BackwardEuler;
                        let w = if be { 1.0 } else { 0.5 };
                        for (bi, &node) in nodes.iter().enumerate() {
                            if be && node != k {
                                continue;
                            }
                            let Some(p) = self.node_point[node] else {
                                return Err(EvalError::new(
                                    "hessian",
                                    format!("node {node} is not evaluated"),
                                ));
                            };
                            Self::weighted_block(plan, data(p), &rows, cols, &mut hw, &mut gw);
                            for a in 0..ks {
                                for b in 0..ks {
                                    h[(bi * ks + a) * kk + bi * ks + b] =
                                        -w * hstep * hw[a * ks + b];
                                }
                                let v = -w * inv_n * gw[a];
                                h[(bi * ks + a) * kk + t] = v;
                                h[t * kk + bi * ks + a] = v;
                            }
                        }
                    }
                    Scheme::HermiteSimpson => {
                        return Err(EvalError::new(
                            "hessian",
                            "Hermite–Simpson's elements are whole intervals",
                        ))
                    }
                }
            }
            HessElement::Interval(k) => {
                let node_data = |node: usize| self.node_point[node].map(&data);
                let node_f = |node: usize| {
                    node_f(&self.node_point, &cache.vals, nx, &self.node0[..nx], node)
                };
                let Some(db) = node_data(k) else {
                    return Err(EvalError::new(
                        "hessian",
                        format!("node {k} is not evaluated"),
                    ));
                };
                hermite_simpson_hessian(
                    plan,
                    &self.pattern.rows,
                    (nx, self.nu),
                    (node_data(k - 1), db, data(self.interval_point[k - 1])),
                    (node_f(k - 1), node_f(k)),
                    &lambda[(k - 1) * nx..k * nx],
                    (hstep, big_n),
                    &mut hw,
                    h,
                )?;
            }
            HessElement::NoCountermovement(j) => {
                let cols = &self.ydd_cols;
                let ks = cols.len();
                let nodes: Vec<(usize, f64)> = [(j, 1.0), (j + 1, -1.0)]
                    .into_iter()
                    .filter(|&(n, _)| n >= 1)
                    .collect();
                let kk = nodes.len() * ks;
                check_len("hessian", "h", h.len(), kk * kk)?;
                h.iter_mut().for_each(|v| *v = 0.0);
                let l = lambda[big_n * nx + j];
                for (bi, &(node, sign)) in nodes.iter().enumerate() {
                    let Some(p) = self.node_point[node] else {
                        return Err(EvalError::new(
                            "hessian",
                            format!("node {node} is not evaluated"),
                        ));
                    };
                    Self::weighted_block(plan, data(p), &[(nx, sign * l)], cols, &mut hw, &mut gw);
                    for a in 0..ks {
                        for b in 0..ks {
                            h[(bi * ks + a) * kk + bi * ks + b] = hw[a * ks + b];
                        }
                    }
                }
            }
            // Returned above, before the point data are needed.
            HessElement::ComVelocity(_) => {}
            HessElement::Final => {
                let n2 = 2 * self.ocp.nq();
                let cols = &self.final_cols;
                let ks = cols.len();
                check_len("hessian", "h", h.len(), ks * ks)?;
                let Some(p) = self.node_point[big_n] else {
                    return Err(EvalError::new("hessian", "the final node is not evaluated"));
                };
                let l = lambda[big_n * nx + self.n_cm];
                Self::weighted_block(plan, data(p), &[(nx + 1, l)], cols, &mut hw, &mut gw);
                for a in 0..ks {
                    for b in 0..ks {
                        let (c, d) = (cols[a], cols[b]);
                        let obj = if c < n2 && d < n2 {
                            -sigma * cache.objective[c * n2 + d]
                        } else {
                            0.0
                        };
                        h[a * ks + b] = obj + hw[a * ks + b];
                    }
                }
            }
        }
        cache.hw = hw;
        cache.gw = gw;
        finite("hessian", h, |i| format!("element {e} entry {i}"))
    }
}

/// The Hessian (into `h`, row-major over the element's variables: node
/// k − 1's columns if it has variables, node k's, then t_f) of λᵀd_k for
/// the Hermite–Simpson defects of interval k,
///
/// ```text
///   d = x_b − x_a − (h/6)(f_a + f_b) − (2h/3) f_c(x_c, u_c),   h = t_f/N,
///   x_c = (x_a + x_b)/2 + (h/8)(f_a − f_b),   u_c = (u_a + u_b)/2,
/// ```
///
/// from the point data of the nodes (`da`, `db`) and the centre (`dc`) and
/// the node values f_a, f_b. With g = Σ_r λ_r ∇f_c,r, H = Σ_r λ_r ∇²f_c,r
/// at the centre and J = ∂(x_c, u_c)/∂(z_a, z_b, t_f):
///
/// ```text
///   ∇²(λᵀd) = −(2h/3) JᵀHJ + Σ_i w_a,i ∇²f_a,i + Σ_i w_b,i ∇²f_b,i  (node blocks)
///   w_a = −(h/6)λ − (h²/12)g_x,   w_b = −(h/6)λ + (h²/12)g_x
///   ∂²/∂t_f∂z = (1/N)[(1/h)Σ_i w_i ∇f_i (per node) − (2/3) J_zᵀg] (+ JᵀHJ's)
///   ∂²/∂t_f²  = −(4/3) g_xᵀ(f_a − f_b)/(8N²) (+ JᵀHJ's)
/// ```
///
/// (the node terms carry the centre's dependence on the dynamics at the
/// nodes, x_c's curvature; g_x is g's state part). `scratch` holds the
/// work arrays (kept by the caller between elements).
#[allow(clippy::too_many_arguments)]
fn hermite_simpson_hessian(
    plan: &HessPlan,
    rows: &[Vec<usize>],
    (nx, nu): (usize, usize),
    (da, db, dc): (Option<&[f64]>, &[f64], &[f64]),
    (fa, fb): (&[f64], &[f64]),
    lambda: &[f64],
    (hstep, big_n): (f64, usize),
    scratch: &mut Vec<f64>,
    h: &mut [f64],
) -> Result<(), EvalError> {
    let nin = nx + nu;
    let nn = if da.is_some() { 2 } else { 1 };
    let kk = nn * nin + 1;
    let t = kk - 1;
    check_len("hessian", "h", h.len(), kk * kk)?;
    h.iter_mut().for_each(|v| *v = 0.0);
    scratch.clear();
    scratch.resize(2 * nin * nin + 2 * nin * kk + 2 * nin + t, 0.0);
    let (hc, rest) = scratch.split_at_mut(nin * nin);
    let (hn, rest) = rest.split_at_mut(nin * nin);
    let (jm, rest) = rest.split_at_mut(nin * kk);
    let (m, rest) = rest.split_at_mut(nin * kk);
    let (g, rest) = rest.split_at_mut(nin);
    let (gn, tcol) = rest.split_at_mut(nin);
    let inv_n = 1.0 / big_n as f64;
    // Σ_r w_r ∇²f_r (dense nin × nin, into `hm`) and Σ_r w_r ∇f_r (into
    // `gv`) from a point's data, over each row's own columns.
    let weighted = |d: &[f64], w: &dyn Fn(usize) -> f64, hm: &mut [f64], gv: &mut [f64]| {
        for (r, cols) in rows.iter().enumerate().take(nx) {
            let l = w(r);
            if l == 0.0 {
                continue;
            }
            for (ia, &c) in cols.iter().enumerate() {
                gv[c] += l * plan.grad(d, r, c);
                for &e in &cols[ia..] {
                    let v = l * plan.hess(d, r, c, e);
                    hm[c * nin + e] += v;
                    if c != e {
                        hm[e * nin + c] += v;
                    }
                }
            }
        }
    };
    // The centre: g and −(2h/3)H.
    weighted(dc, &|r| lambda[r], hc, g);
    hc.iter_mut().for_each(|v| *v *= -2.0 * hstep / 3.0);
    // The nodes present, with their offsets and the sign of their f in x_c.
    let (both, one);
    let nodes: &[(&[f64], usize, f64)] = match da {
        Some(da) => {
            both = [(da, 0, 1.0), (db, nin, -1.0)];
            &both
        }
        None => {
            one = [(db, 0, -1.0)];
            &one
        }
    };
    // J = ∂(x_c, u_c)/∂(element variables), nin × kk.
    for j in 0..nin {
        for &(d, off, sign) in nodes {
            jm[j * kk + off + j] += 0.5;
            if j < nx {
                for &c in &rows[j] {
                    jm[j * kk + off + c] += sign * 0.125 * hstep * plan.grad(d, j, c);
                }
            }
        }
        if j < nx {
            jm[j * kk + t] = 0.125 * inv_n * (fa[j] - fb[j]);
        }
    }
    // JᵀHJ with H = −(2h/3)·Σλ∇²f_c: M = HJ, then JᵀM.
    add_product(hc, (nin, nin), false, jm, kk, m);
    add_product(jm, (nin, kk), true, m, kk, h);
    // The node terms, with x_c's curvature in the weights.
    let c2 = hstep * hstep / 12.0;
    // `tcol`: the t_f column's terms besides JᵀHJ's.
    for &(d, off, sign) in nodes {
        hn.iter_mut().for_each(|v| *v = 0.0);
        gn.iter_mut().for_each(|v| *v = 0.0);
        let w = |r: usize| -hstep / 6.0 * lambda[r] - sign * c2 * g[r];
        weighted(d, &w, hn, gn);
        for a in 0..nin {
            for b in 0..nin {
                h[(off + a) * kk + off + b] += hn[a * nin + b];
            }
            tcol[off + a] += inv_n / hstep * gn[a];
        }
    }
    // −(2/3)(1/N)·J_zᵀg, and ∂²/∂t_f².
    for a in 0..t {
        let mut v = 0.0;
        for c in 0..nin {
            v += jm[c * kk + a] * g[c];
        }
        tcol[a] -= 2.0 / 3.0 * inv_n * v;
    }
    let gx: f64 = (0..nx).map(|i| g[i] * (fa[i] - fb[i])).sum();
    h[t * kk + t] -= 4.0 / 3.0 * gx * 0.125 * inv_n * inv_n;
    for (a, v) in tcol.iter().enumerate() {
        h[a * kk + t] += v;
        h[t * kk + a] += v;
    }
    // JᵀHJ is symmetric up to rounding: make it exact.
    for a in 0..kk {
        for b in 0..a {
            let v = 0.5 * (h[a * kk + b] + h[b * kk + a]);
            h[a * kk + b] = v;
            h[b * kk + a] = v;
        }
    }
    Ok(())
}

/// out += A·B (or Aᵀ·B with `transpose`), A dense `rows` × `cols` with
/// many zeros (skipped), B and out row-major with `width` columns.
fn add_product(
    a: &[f64],
    (rows, cols): (usize, usize),
    transpose: bool,
    b: &[f64],
    width: usize,
    out: &mut [f64],
) {
    for r in 0..rows {
        for c in 0..cols {
            let v = a[r * cols + c];
            if v == 0.0 {
                continue;
            }
            let (dst, src) = if transpose { (c, r) } else { (r, c) };
            let (o, bs) = (
                &mut out[dst * width..(dst + 1) * width],
                &b[src * width..(src + 1) * width],
            );
            for (o, bv) in o.iter_mut().zip(bs) {
                *o += v * bv;
            }
        }
    }
}

/// The Hessian (into `h`, row-major over the element's variables: the
/// node columns `cols` of node k − 1 (if `nodes` is 2) and of node k, then
/// t_f) of λ·R for the force balance R of state row `r` at the midpoint of
/// interval k, whose inputs are the node means and the fibre velocity
/// v̄ = Δ/(h·s), Δ = l^M_k − l^M_{k−1}, h = t_f/N, s = v_max l_o, at point
/// input column `vcol`:
///
/// ```text
///   ∇²(λR) = Jᵀ·∇²_p(λR)·J + λ·∂R/∂v̄·∇²v̄,
///   ∂v̄/∂l^M_k = −∂v̄/∂l^M_{k−1} = 1/(h s),  ∂v̄/∂t_f = −v̄/t_f,
///   ∂²v̄/∂l^M_k∂t_f = −∂²v̄/∂l^M_{k−1}∂t_f = −1/(h s t_f),  ∂²v̄/∂t_f² = 2v̄/t_f²,
/// ```
///
/// with J the map from the element's variables to the point inputs
/// (½ on each node column, the v̄ row above).
#[allow(clippy::too_many_arguments)]
fn balance_hessian(
    plan: &HessPlan,
    data: &[f64],
    (rows, cols): (&[(usize, f64)], &[usize]),
    (r, vcol): (usize, usize),
    (hstep, tf, speed): (f64, f64, f64),
    (dl, nodes): (f64, usize),
    (hw, gw): (&mut Vec<f64>, &mut Vec<f64>),
    h: &mut [f64],
) {
    let ks = cols.len();
    let mut pcols = cols.to_vec();
    pcols.push(vcol);
    Transcription::weighted_block(plan, data, rows, &pcols, hw, gw);
    let np = ks + 1;
    let kk = nodes * ks + 1;
    let t = kk - 1;
    let own = cols.iter().position(|&c| c == r).unwrap_or(0);
    let dv = 1.0 / (hstep * speed);
    let vbar = dl * dv;
    // J row by row: (element column, value) per point input; node k − 1
    // (if present) first, then node k.
    let sign = |bi: usize| if bi + 1 == nodes { 1.0 } else { -1.0 };
    let mut jrows: Vec<Vec<(usize, f64)>> = (0..ks)
        .map(|a| (0..nodes).map(|bi| (bi * ks + a, 0.5)).collect())
        .collect();
    let mut vrow: Vec<(usize, f64)> = (0..nodes)
        .map(|bi| (bi * ks + own, sign(bi) * dv))
        .collect();
    vrow.push((t, -vbar / tf));
    jrows.push(vrow);
    h.iter_mut().for_each(|v| *v = 0.0);
    for a in 0..np {
        for b in 0..np {
            let w = hw[a * np + b];
            if w == 0.0 {
                continue;
            }
            for &(c1, j1) in &jrows[a] {
                for &(c2, j2) in &jrows[b] {
                    h[c1 * kk + c2] += j1 * w * j2;
                }
            }
        }
    }
    let g = gw[ks];
    for bi in 0..nodes {
        let e = g * sign(bi) * (-dv / tf);
        h[(bi * ks + own) * kk + t] += e;
        h[t * kk + bi * ks + own] += e;
    }
    h[t * kk + t] += g * 2.0 * vbar / (tf * tf);
    // Exactly symmetric (the sums above run in different orders).
    for c1 in 0..kk {
        for c2 in 0..c1 {
            h[c1 * kk + c2] = h[c2 * kk + c1];
        }
    }
}

/// The gradient over (q, q̇) (into `g`) of output `which` of
/// [`JumpOcp::jump_objective`] (0 Y_C, 1 Ẏ_C, 2 J) at `xk`, by dual numbers,
/// in the caller's workspace `ws` and seed buffer `xd` (length of `xk`).
pub(crate) fn jump_objective_gradient(
    ocp: &JumpOcp,
    (ws, xd): (&mut crate::multibody::Workspace<Dual64>, &mut [Dual64]),
    xk: &[f64],
    which: usize,
    g: &mut [f64],
) {
    for (d, &x) in xd.iter_mut().zip(xk) {
        *d = Dual64::from(x);
    }
    for i in 0..xk.len() {
        xd[i] = Dual64::from(xk[i]).derivative();
        let (y, yd, j) = ocp.jump_objective(ws, xd);
        xd[i] = Dual64::from(xk[i]);
        g[i] = [y, yd, j][which].eps;
    }
}

/// The Hessian over (q, q̇) (2n × 2n, row-major, into `h`) of output
/// `which` of [`JumpOcp::jump_objective`] (0 Y_C, 1 Ẏ_C, 2 J) at `xk`, by
/// hyper-dual numbers.
fn jump_objective_hessian(ocp: &JumpOcp, xk: &[f64], which: usize, h: &mut [f64]) {
    let n2 = xk.len();
    let mut ws = ocp.eq.multibody.workspace::<HyperDual64>();
    let mut xd: Vec<HyperDual64> = xk.iter().map(|&x| HyperDual64::from(x)).collect();
    for i in 0..n2 {
        for j in i..n2 {
            for (l, x) in xd.iter_mut().enumerate() {
                *x = HyperDual64::new(
                    xk[l],
                    if l == i { 1.0 } else { 0.0 },
                    if l == j { 1.0 } else { 0.0 },
                    0.0,
                );
            }
            let (y, yd, jv) = ocp.jump_objective(&mut ws, &xd);
            let out = [y, yd, jv][which];
            h[i * n2 + j] = out.eps1eps2;
            h[j * n2 + i] = out.eps1eps2;
        }
    }
}

/// Median times (s) of the first two second-order passes of the exact
/// Hessian (see [`HESS_Q`]; the second with the first-order paths it
/// takes from [`PathPass`]) and of all passes at (x, u), over `reps`
/// evaluations.
pub fn time_hessian_passes(
    ocp: &JumpOcp,
    pattern: &StatePattern,
    x: &[f64],
    u: &[f64],
    reps: usize,
) -> Result<[f64; 3], String> {
    let plan = HessPlan::new(pattern, ocp.nq(), ocp.nm()).ok_or("no Hessian for this model")?;
    let n = ocp.nq();
    let mut w = HessWorker::new(ocp, ocp.nu());
    let mut out = vec![0.0; (ocp.nx() + 2) * plan.block];
    let mut vals = vec![0.0; ocp.nx()];
    let mut times = [vec![], vec![], vec![]];
    w.x.copy_from_slice(x);
    w.u.copy_from_slice(u);
    for _ in 0..reps.max(1) {
        let (s1, s2) = pass1_seeds(n);
        let t = std::time::Instant::now();
        w.a.run(ocp, &plan, x, u, s1, s2, (0, n, 0, 2 * n), &mut out)?;
        times[0].push(t.elapsed().as_secs_f64());
        let t = std::time::Instant::now();
        given_paths(ocp, &plan, &mut w)?;
        w.b.run(
            ocp,
            &plan,
            x,
            u,
            pass2_seed(n),
            pass2_seed(n),
            (n, n, n, n),
            &mut out,
        )?;
        times[1].push(t.elapsed().as_secs_f64());
        let t = std::time::Instant::now();
        eval_hess_point(ocp, &plan, &mut w, &mut out, &mut vals)?;
        times[2].push(t.elapsed().as_secs_f64());
    }
    Ok(times.map(|mut v| {
        v.sort_by(|a, b| a.total_cmp(b));
        v[v.len() / 2]
    }))
}
