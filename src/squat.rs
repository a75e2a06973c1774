//! The paper's start: a static squat with known states and controls.
//!
//! 1. Pose: the model's `squat` pose (flat feet), q̇ = 0.
//! 2. Ground support: pelvis height and ankle angle (foot pitch) such that
//!    the contact spheres carry the body weight with the centre of pressure
//!    under the centre of mass, i.e. the generalized forces on the floating
//!    base vanish (friction is zero at rest, so the horizontal one does).
//! 3. Muscles: static optimisation, minimise Σ a² subject to the joint
//!    equations M q̈ = 0 with every fibre in muscle-tendon equilibrium
//!    (v_MT = 0) and excitation = activation, solved as a sequence of QPs
//!    (clarabel) on the linearised tendon forces.

use crate::laws::{OpenSimLaws, MIN_ACTIVATION};
use crate::multibody::{GeneralizedForces, ModelView};
use crate::ode::{OdeError, StateEquation};
use serde::Serialize;

/// The static squat: state x, excitations u = a, and how well it holds.
#[derive(Debug, Clone, Serialize)]
pub struct StaticSquat {
    pub x: Vec<f64>,
    pub excitation: Vec<f64>,
    /// Largest |q̈| at x (rad/s² or m/s²).
    pub max_abs_qdd: f64,
    /// Total vertical ground force / body weight.
    pub vertical_grf_bw: f64,
    pub pelvis_ty: f64,
    pub ankle_angle: f64,
    pub qp_iterations: usize,
    /// Σ a² of the solution.
    pub effort: f64,
}

/// Why the squat cannot be held.
#[derive(Debug, thiserror::Error)]
pub enum SquatFailure {
    #[error(transparent)]
    Ode(#[from] OdeError),
    #[error("{0}")]
    Failed(String),
}

/// The squat of a model file's pose (`poses.squat`) cannot be held: the
/// file, the pose and why. (The reason may lie in other fields: the bodies,
/// the contact spheres, the ligaments.)
#[derive(Debug, thiserror::Error)]
#[error("{file}: {pose}: static squat: {why}")]
pub struct SquatError {
    pub file: String,
    /// `poses.<name>` when the pose is one of the model's (`poses.squat`
    /// first), else "the given pose".
    pub pose: String,
    pub why: Box<SquatFailure>,
}

struct Setup<'a> {
    eq: &'a StateEquation,
    laws: &'a OpenSimLaws,
    n: usize,
    nm: usize,
}

impl Setup<'_> {
    /// The state at q, q̇ = 0, activations a, fibres in equilibrium.
    fn state(&self, q: &[f64], a: &[f64], lmt: &[f64]) -> Vec<f64> {
        let (n, nm) = (self.n, self.nm);
        let mut x = vec![0.0; 2 * n + 2 * nm];
        x[..n].copy_from_slice(q);
        for k in 0..nm {
            let th = &self.laws.muscles[self.eq.muscles[k]];
            x[2 * n + k] = th.equilibrium_fiber_length(a[k], lmt[k]);
            x[2 * n + nm + k] = a[k];
        }
        x
    }

    /// Generalized-force residual M·q̈ (zero iff q̈ = 0) and q̈.
    fn residual(&self, x: &[f64], u: &[f64]) -> Result<(Vec<f64>, Vec<f64>, f64), SquatFailure> {
        let eq = self.eq;
        let mut ws = eq.workspace::<f64>();
        let mut dx = vec![0.0; x.len()];
        eq.rhs(self.laws, &mut ws, x, u, &mut dx)?;
        let n = self.n;
        let m = eq.multibody.mass_matrix(&ws.mb);
        let qdd = dx[n..2 * n].to_vec();
        let r = (0..n)
            .map(|i| (0..n).map(|j| m[i * n + j] * qdd[j]).sum())
            .collect();
        let fy: f64 = ws.sphere_force.iter().map(|f| f[1]).sum();
        Ok((r, qdd, fy))
    }
}

/// Compute the static squat of `eq` from the model's pose `pose` (model
/// coordinate values).
pub fn static_squat(
    eq: &StateEquation,
    laws: &OpenSimLaws,
    pose: &[f64],
) -> Result<StaticSquat, SquatError> {
    squat_of(eq, laws, pose).map_err(|why| SquatError {
        file: eq.model.file.display().to_string(),
        // The squat pose if it is that one, else another of the model's.
        pose: std::iter::once("squat")
            .chain(eq.model.poses.keys().map(String::as_str))
            .find(|name| {
                eq.model
                    .poses
                    .get(*name)
                    .is_some_and(|q| q.as_slice() == pose)
            })
            .map_or("the given pose".into(), |name| format!("poses.{name}")),
        why: Box::new(why),
    })
}

fn squat_of(
    eq: &StateEquation,
    laws: &OpenSimLaws,
    pose: &[f64],
) -> Result<StaticSquat, SquatFailure> {
    let (n, nm) = (eq.nq(), eq.nm());
    let s = Setup { eq, laws, n, nm };
    let model = &eq.model;
    let idx = |name: &str| -> Result<usize, SquatFailure> {
        model
            .coordinate_index(name)
            .map(|c| eq.system.q_of_model_coordinate[c])
            .ok_or_else(|| SquatFailure::Failed(format!("the model has no coordinate '{name}'")))
    };
    let (i_ty, i_tilt) = (idx("pelvis_ty")?, idx("pelvis_tilt")?);
    let ankles: Vec<usize> = {
        let mut v: Vec<usize> = model
            .coordinates
            .iter()
            .enumerate()
            .filter(|(_, c)| c.name.starts_with("ankle_angle"))
            .map(|(i, _)| eq.system.q_of_model_coordinate[i])
            .collect();
        v.sort();
        v.dedup();
        v
    };
    if ankles.is_empty() {
        return Err(SquatFailure::Failed(
            "the model has no ankle_angle coordinate".into(),
        ));
    }
    let mut q = eq.system.q_from_model(pose);
    let a_min = vec![MIN_ACTIVATION; nm];
    let weight = model.total_mass() * model.gravity[1].abs();
    // 2. Ground support: Newton on (pelvis_ty, ankle) for the base residuals.
    let base = |q: &[f64]| -> Result<[f64; 2], SquatFailure> {
        let lmt = eq.path_lengths(q);
        let x = s.state(q, &a_min, &lmt);
        let (r, _, _) = s.residual(&x, &a_min)?;
        Ok([r[i_ty] / weight, r[i_tilt] / weight])
    };
    let set = |q: &mut Vec<f64>, ty: f64, ank: f64| {
        q[i_ty] = ty;
        for &k in &ankles {
            q[k] = ank;
        }
    };
    let (mut ty, mut ank) = (q[i_ty], q[ankles[0]]);
    let mut converged = false;
    for _ in 0..60 {
        set(&mut q, ty, ank);
        let r0 = base(&q)?;
        if r0[0].abs() < 1e-13 && r0[1].abs() < 1e-13 {
            converged = true;
            break;
        }
        let h = 1e-7;
        let mut qa = q.clone();
        set(&mut qa, ty + h, ank);
        let ra = base(&qa)?;
        set(&mut qa, ty, ank + h);
        let rb = base(&qa)?;
        let j = [
            [(ra[0] - r0[0]) / h, (rb[0] - r0[0]) / h],
            [(ra[1] - r0[1]) / h, (rb[1] - r0[1]) / h],
        ];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det.abs() < 1e-300 || !det.is_finite() {
            return Err(SquatFailure::Failed(
                "the feet do not touch the ground near the squat pose".into(),
            ));
        }
        let d_ty = -(j[1][1] * r0[0] - j[0][1] * r0[1]) / det;
        let d_an = -(-j[1][0] * r0[0] + j[0][0] * r0[1]) / det;
        // Damped steps: penetrations are millimetres.
        ty += d_ty.clamp(-0.005, 0.005);
        ank += d_an.clamp(-0.05, 0.05);
    }
    if !converged {
        return Err(SquatFailure::Failed(
            "no pelvis height and ankle angle put the centre of pressure under the centre of mass"
                .into(),
        ));
    }
    set(&mut q, ty, ank);
    // 3. Static optimisation.
    let lmt = eq.path_lengths(&q);
    let joints: Vec<usize> = (0..n)
        .filter(|&i| {
            let name = &model.coordinates[eq.system.coordinates[i]].name;
            !name.starts_with("pelvis_")
        })
        .collect();
    // Generalized force per unit tension of each carried muscle (×multiplicity).
    let arms: Vec<Vec<f64>> = {
        let mut ws = eq.multibody.workspace::<f64>();
        eq.multibody.set_state(&mut ws, &q, &vec![0.0; n]);
        eq.muscles
            .iter()
            .enumerate()
            .map(|(k, &m)| {
                let mut tau = vec![0.0; n];
                let view = ModelView {
                    mb: &eq.multibody,
                    ws: &ws,
                    q_of: &eq.system.q_of_model_coordinate,
                };
                let mut sink = GeneralizedForces {
                    mb: &eq.multibody,
                    ws: &ws,
                    q_of: &eq.system.q_of_model_coordinate,
                    tau: &mut tau,
                };
                eq.model.muscles[m].path.calc(
                    &view,
                    eq.smoothing,
                    Some((eq.multiplicity[k], &mut sink)),
                );
                tau
            })
            .collect()
    };
    let tendon = |k: usize, a: f64| -> f64 {
        let th = &laws.muscles[eq.muscles[k]];
        let lm = th.equilibrium_fiber_length(a, lmt[k]);
        th.calc(a, lm, lmt[k], 0.0, a).tendon_force
    };
    let mut a = vec![MIN_ACTIVATION; nm];
    let mut iterations = 0;
    let mut last_res = f64::INFINITY;
    for it in 0..50 {
        iterations = it + 1;
        let x = s.state(&q, &a, &lmt);
        let (r, _, _) = s.residual(&x, &a)?;
        let res = joints.iter().map(|&j| r[j].abs()).fold(0.0, f64::max);
        last_res = res;
        if res < 1e-9 {
            break;
        }
        // Linearised tendon forces: F(a) ≈ F(a_k) + s_k (a − a_k).
        let slope: Vec<f64> = (0..nm)
            .map(|k| {
                let h = 1e-6;
                let (lo, hi) = ((a[k] - h).max(MIN_ACTIVATION), (a[k] + h).min(1.0));
                (tendon(k, hi) - tendon(k, lo)) / (hi - lo)
            })
            .collect();
        // Rows: Σ_m arms[m][j] s_m (a_m − a_k,m) = −r_j.
        let (ne, nv) = (joints.len(), nm);
        let mut trip_i = Vec::new();
        let mut trip_j = Vec::new();
        let mut trip_v = Vec::new();
        let mut b = vec![0.0; ne + 2 * nv];
        for (row, &j) in joints.iter().enumerate() {
            let mut rhs = -r[j];
            for m in 0..nv {
                let g = arms[m][j] * slope[m];
                if g != 0.0 {
                    trip_i.push(row);
                    trip_j.push(m);
                    trip_v.push(g);
                    rhs += g * a[m];
                }
            }
            b[row] = rhs;
        }
        // Bounds: a ≤ 1 and −a ≤ −a_min.
        for m in 0..nv {
            trip_i.push(ne + m);
            trip_j.push(m);
            trip_v.push(1.0);
            b[ne + m] = 1.0;
            trip_i.push(ne + nv + m);
            trip_j.push(m);
            trip_v.push(-1.0);
            b[ne + nv + m] = -MIN_ACTIVATION;
        }
        use clarabel::algebra::CscMatrix;
        use clarabel::solver::{
            DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
            ZeroConeT,
        };
        let amat = CscMatrix::new_from_triplets(ne + 2 * nv, nv, trip_i, trip_j, trip_v);
        let pmat = CscMatrix::new_from_triplets(
            nv,
            nv,
            (0..nv).collect(),
            (0..nv).collect(),
            vec![2.0; nv],
        );
        let qv = vec![0.0; nv];
        let cones = [ZeroConeT(ne), NonnegativeConeT(2 * nv)];
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .max_threads(1)
            .build()
            .map_err(|e| SquatFailure::Failed(format!("{e:?}")))?;
        let mut solver = DefaultSolver::new(&pmat, &qv, &amat, &b, &cones, settings)
            .map_err(|e| SquatFailure::Failed(e.to_string()))?;
        solver.solve();
        match solver.solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {}
            other => return Err(SquatFailure::Failed(format!("the muscles cannot hold the squat (static optimisation QP: {other:?}, joint residual {res:.3e} N·m)"))),
        }
        let anew: Vec<f64> = solver
            .solution
            .x
            .iter()
            .map(|v| v.clamp(MIN_ACTIVATION, 1.0))
            .collect();
        a = anew;
    }
    if last_res >= 1e-9 {
        return Err(SquatFailure::Failed(format!(
            "static optimisation did not converge: joint residual {last_res:.3e} N·m"
        )));
    }
    let x = s.state(&q, &a, &lmt);
    let (_, qdd, fy) = s.residual(&x, &a)?;
    Ok(StaticSquat {
        max_abs_qdd: qdd.iter().fold(0.0, |m, v| m.max(v.abs())),
        vertical_grf_bw: fy / weight,
        pelvis_ty: ty,
        ankle_angle: ank,
        qp_iterations: iterations,
        effort: a.iter().map(|v| v * v).sum(),
        excitation: a,
        x,
    })
}
