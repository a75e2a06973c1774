//! How well a collocation mesh resolves its solution: each mesh interval
//! integrated from its first node by the variable-step Dormand–Prince
//! integrator, its end compared with the next node.
//!
//! The defects of a solved transcription hold to the constraint tolerance,
//! but a defect of one midpoint (or trapezoidal) step is not the dynamics:
//! the difference between the step and the true flow over the interval is
//! the scheme's local error, O(h³) for the midpoint rule where the dynamics
//! are smooth. Per interval the largest state error relative to 1 + the
//! state's largest magnitude over the mesh: a one-step re-integration error
//! with the relative weighting of Betts' mesh refinement (*Practical
//! Methods for Optimal Control Using Nonlinear Programming*, 2nd ed.,
//! §4.7), whose own estimate integrates the interpolant's ODE residual. The
//! states mix units (rad, m, rad/s, activations), so each interval also
//! reports the absolute error of its worst state; for the jump the speeds,
//! the largest magnitudes, are usually the worst.
//!
//! The forward check integrates the whole jump from the squat, where local
//! errors add up and an unstable movement amplifies them; this check
//! restarts at every node, so it tells where the mesh is too coarse from
//! where the open-loop movement diverges.
//!
//! With implicit fibre dynamics the transcription states the force balance
//! at the midpoint with the interval's fibre velocity; its solutions are
//! the explicit ODE's (the force–velocity curve is inverted exactly), so the
//! same ODE measures both, but for Thelen's fibre clamp (v = 0 at the
//! minimum fibre length), which the balance rows do not state.

use crate::integrator::{Dopri5, Dopri5Options, OdeSystem};
use crate::ode::{ForceLaws, StateEquation, StateWorkspace};
use crate::transcription::MeshTrajectory;

/// The local error of one mesh interval.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct IntervalError {
    /// 1-based, as the transcription's interval numbers.
    pub interval: usize,
    pub t_start: f64,
    pub t_end: f64,
    /// max_j |x̃_j(t_end) − x_j(t_end)| / (1 + max_k |x_kj|): x̃ integrated
    /// from the interval's first node, x the mesh's next node. None where
    /// the integration failed (`failure` says why).
    pub relative_error: Option<f64>,
    /// The state of that largest error (its name in the solution files)
    /// and its error |x̃_j − x_j| in the state's units (rad, m, rad/s, m/s
    /// or activation).
    pub state: String,
    pub absolute_error: Option<f64>,
    pub failure: Option<String>,
}

/// The local errors of all intervals of a mesh trajectory.
#[derive(Debug, Clone, serde::Serialize)]
pub struct MeshError {
    /// The integrator's accuracy (relative and absolute).
    pub accuracy: f64,
    /// The largest and the median relative error over the intervals that
    /// integrated, and the interval (1-based) of the largest.
    pub largest_relative_error: Option<f64>,
    pub worst_interval: Option<usize>,
    pub median_relative_error: Option<f64>,
    pub intervals: Vec<IntervalError>,
}

impl MeshError {
    fn new(accuracy: f64, intervals: Vec<IntervalError>) -> Self {
        let worst = intervals
            .iter()
            .filter_map(|e| e.relative_error.map(|r| (r, e.interval)))
            .max_by(|a, b| a.0.total_cmp(&b.0));
        let e: Vec<f64> = intervals.iter().filter_map(|e| e.relative_error).collect();
        let median = (!e.is_empty()).then(|| crate::sqp::median(e));
        MeshError {
            accuracy,
            largest_relative_error: worst.map(|w| w.0),
            worst_interval: worst.map(|w| w.1),
            median_relative_error: median,
            intervals,
        }
    }
}

/// How the excitations vary over an interval, as the scheme reads them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Excitations {
    /// Linear between the nodes: the midpoint rule's mean, the trapezoidal
    /// rule's nodes, Hermite–Simpson's centre mean, shooting and the
    /// forward check.
    Linear,
    /// The interval's end value held (backward Euler's f(x_k, u_k)).
    HeldAtEnd,
}

impl Excitations {
    /// The excitations of `scheme`'s defects.
    pub fn of(scheme: crate::transcription::Scheme) -> Self {
        match scheme {
            crate::transcription::Scheme::BackwardEuler => Excitations::HeldAtEnd,
            _ => Excitations::Linear,
        }
    }
}

/// ẋ = f(x, u(t)) with u over an interval as [`Excitations`] says.
struct IntervalRhs<'a, F> {
    f: &'a mut F,
    nx: usize,
    t: (f64, f64),
    u: (&'a [f64], &'a [f64]),
    u_t: Vec<f64>,
    excitations: Excitations,
}

impl<F> OdeSystem for IntervalRhs<'_, F>
where
    F: FnMut(&[f64], &[f64], &mut [f64]) -> Result<(), String>,
{
    fn dim(&self) -> usize {
        self.nx
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), String> {
        let (t0, t1) = self.t;
        let s = match self.excitations {
            Excitations::Linear => ((t - t0) / (t1 - t0)).clamp(0.0, 1.0),
            Excitations::HeldAtEnd => 1.0,
        };
        for ((o, a), b) in self.u_t.iter_mut().zip(self.u.0).zip(self.u.1) {
            *o = a + s * (b - a);
        }
        (self.f)(x, &self.u_t, dx)
    }
}

/// The most Dormand–Prince steps per interval: a stiff or infeasible
/// iterate costs at most this many, not minutes.
const MAX_STEPS_PER_INTERVAL: usize = 20_000;

/// Integrate every interval of `mesh` from its first node with ẋ = f(x, u)
/// (`f(x, u, ẋ)`; u over the interval as `excitations` says; Dormand–Prince
/// at `accuracy`) and compare with the next node. An interval whose
/// integration fails, or whose nodes are not finite, is recorded with its
/// failure; a mesh whose rows do not fit is an error.
pub fn local_errors<F>(
    mut f: F,
    mesh: &MeshTrajectory,
    excitations: Excitations,
    accuracy: f64,
    state_name: &dyn Fn(usize) -> String,
) -> Result<MeshError, String>
where
    F: FnMut(&[f64], &[f64], &mut [f64]) -> Result<(), String>,
{
    let n = mesh.time.len();
    if mesh.states.len() != n || mesh.controls.len() != n {
        return Err(format!(
            "{n} times, {} state rows and {} control rows",
            mesh.states.len(),
            mesh.controls.len()
        ));
    }
    let nx = mesh.states.first().map_or(0, Vec::len);
    let nu = mesh.controls.first().map_or(0, Vec::len);
    if let Some(k) = (0..n).find(|&k| mesh.states[k].len() != nx || mesh.controls[k].len() != nu) {
        return Err(format!(
            "node {k} has {} states and {} controls, node 0 {nx} and {nu}",
            mesh.states[k].len(),
            mesh.controls[k].len()
        ));
    }
    let increases =
        |k: usize| mesh.time[k].partial_cmp(&mesh.time[k - 1]) == Some(std::cmp::Ordering::Greater);
    if let Some(k) = (1..n).find(|&k| !increases(k)) {
        return Err(format!(
            "times {} and {} of nodes {} and {k} do not increase",
            mesh.time[k - 1],
            mesh.time[k],
            k - 1
        ));
    }
    let mut scale = vec![0.0f64; nx];
    for x in &mesh.states {
        for (s, v) in scale.iter_mut().zip(x) {
            *s = s.max(v.abs());
        }
    }
    let mut intervals = Vec::with_capacity(n.saturating_sub(1));
    for k in 1..n {
        let (t0, t1) = (mesh.time[k - 1], mesh.time[k]);
        let mut sys = IntervalRhs {
            f: &mut f,
            nx,
            t: (t0, t1),
            u: (&mesh.controls[k - 1], &mesh.controls[k]),
            u_t: vec![0.0; nu],
            excitations,
        };
        let options = Dopri5Options {
            accuracy,
            min_step: 1e-14,
            max_step: t1 - t0,
            max_steps: MAX_STEPS_PER_INTERVAL,
        };
        let mut e = IntervalError {
            interval: k,
            t_start: t0,
            t_end: t1,
            relative_error: None,
            state: String::new(),
            absolute_error: None,
            failure: None,
        };
        let finite = |r: &[f64]| r.iter().all(|v| v.is_finite());
        if !(finite(&mesh.states[k - 1])
            && finite(&mesh.states[k])
            && finite(&mesh.controls[k - 1])
            && finite(&mesh.controls[k]))
        {
            e.failure = Some("a node's states or excitations are not finite".into());
            intervals.push(e);
            continue;
        }
        let end = Dopri5::new(&mut sys, t0, &mesh.states[k - 1], options).and_then(|mut ig| {
            while ig.t() < t1 {
                ig.step(&mut sys, t1)?;
            }
            Ok(ig.x().to_vec())
        });
        match end {
            Ok(x) => {
                let mut worst = (0, f64::NEG_INFINITY);
                for (j, ((a, b), s)) in x.iter().zip(&mesh.states[k]).zip(&scale).enumerate() {
                    let r = (a - b).abs() / (1.0 + s);
                    if r > worst.1 {
                        worst = (j, r);
                    }
                }
                let j = worst.0;
                e.state = state_name(j);
                e.relative_error = Some(worst.1.max(0.0));
                e.absolute_error = Some((x[j] - mesh.states[k][j]).abs());
            }
            Err(err) => e.failure = Some(err.to_string()),
        }
        intervals.push(e);
    }
    Ok(MeshError::new(accuracy, intervals))
}

/// [`local_errors`] of a jump's mesh trajectory with the state equation
/// `eq` and its force laws.
pub fn mesh_error<L: ForceLaws<f64>>(
    eq: &StateEquation,
    laws: &L,
    mesh: &MeshTrajectory,
    excitations: Excitations,
    accuracy: f64,
) -> Result<MeshError, String> {
    if let Some(k) = mesh.states.iter().position(|x| x.len() != eq.nx()) {
        return Err(format!(
            "node {k} has {} states, the model {}",
            mesh.states[k].len(),
            eq.nx()
        ));
    }
    let mut ws: StateWorkspace<f64> = eq.workspace();
    let names = eq.state_names();
    local_errors(
        |x, u, dx| eq.rhs(laws, &mut ws, x, u, dx).map_err(|e| e.to_string()),
        mesh,
        excitations,
        accuracy,
        &|j| {
            names
                .get(j)
                .cloned()
                .unwrap_or_else(|| format!("state {j}"))
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn name(j: usize) -> String {
        format!("x{j}")
    }

    /// Nodes of the midpoint rule x_k = x_{k−1} + h·f((x_{k−1} + x_k)/2, ū)
    /// for the linear ẋ = A x + b u, solved exactly.
    fn midpoint_mesh(
        a: [[f64; 2]; 2],
        b: [f64; 2],
        x0: [f64; 2],
        u: &[f64],
        h: f64,
    ) -> MeshTrajectory {
        let mut x = vec![x0.to_vec()];
        for k in 1..u.len() {
            let p = &x[k - 1];
            let ub = 0.5 * (u[k - 1] + u[k]);
            // (I − hA/2) x_k = (I + hA/2) x_{k−1} + h b ū
            let m = [
                [1.0 - 0.5 * h * a[0][0], -0.5 * h * a[0][1]],
                [-0.5 * h * a[1][0], 1.0 - 0.5 * h * a[1][1]],
            ];
            let r = [
                p[0] + 0.5 * h * (a[0][0] * p[0] + a[0][1] * p[1]) + h * b[0] * ub,
                p[1] + 0.5 * h * (a[1][0] * p[0] + a[1][1] * p[1]) + h * b[1] * ub,
            ];
            let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
            x.push(vec![
                (r[0] * m[1][1] - m[0][1] * r[1]) / det,
                (m[0][0] * r[1] - m[1][0] * r[0]) / det,
            ]);
        }
        MeshTrajectory {
            time: (0..u.len()).map(|k| k as f64 * h).collect(),
            states: x,
            controls: u.iter().map(|&v| vec![v]).collect(),
        }
    }

    fn linear(
        a: [[f64; 2]; 2],
        b: [f64; 2],
    ) -> impl FnMut(&[f64], &[f64], &mut [f64]) -> Result<(), String> {
        move |x, u, dx| {
            dx[0] = a[0][0] * x[0] + a[0][1] * x[1] + b[0] * u[0];
            dx[1] = a[1][0] * x[0] + a[1][1] * x[1] + b[1] * u[0];
            Ok(())
        }
    }

    /// The harmonic oscillator: the midpoint rule is the Cayley transform
    /// of the rotation, so each interval's local error is
    /// |(e^{hA} − C(h)) x_{k−1}| in closed form.
    #[test]
    fn local_error_of_the_midpoint_rule_is_its_closed_form() {
        let (w, h) = (2.0, 0.15);
        let a = [[0.0, 1.0], [-w * w, 0.0]];
        let mesh = midpoint_mesh(a, [0.0, 0.0], [1.0, 0.5], &[0.0; 11], h);
        let e = local_errors(
            linear(a, [0.0, 0.0]),
            &mesh,
            Excitations::Linear,
            1e-12,
            &name,
        )
        .unwrap();
        let mut scale = [0.0f64; 2];
        for x in &mesh.states {
            scale[0] = scale[0].max(x[0].abs());
            scale[1] = scale[1].max(x[1].abs());
        }
        let (c, s) = ((w * h).cos(), (w * h).sin());
        assert_eq!(e.intervals.len(), 10);
        for (k, ie) in e.intervals.iter().enumerate() {
            let (p, q) = (&mesh.states[k], &mesh.states[k + 1]);
            let exact = [c * p[0] + s / w * p[1], -w * s * p[0] + c * p[1]];
            let r = [
                (exact[0] - q[0]).abs() / (1.0 + scale[0]),
                (exact[1] - q[1]).abs() / (1.0 + scale[1]),
            ];
            let (j, want) = if r[0] >= r[1] { (0, r[0]) } else { (1, r[1]) };
            let got = ie.relative_error.unwrap();
            assert!(
                (got - want).abs() <= 1e-9 * want,
                "interval {}: {got} against {want}",
                k + 1
            );
            assert_eq!(ie.state, name(j));
            assert!(want > 1e-4, "the mesh is coarse: {want}");
        }
        let worst = e.largest_relative_error.unwrap();
        let w_i = e.worst_interval.unwrap();
        assert_eq!(e.intervals[w_i - 1].relative_error, Some(worst));
        assert!(e
            .intervals
            .iter()
            .all(|i| i.relative_error.unwrap() <= worst));
        // Halving the step: the midpoint rule's local error is O(h³).
        let fine = midpoint_mesh(a, [0.0, 0.0], [1.0, 0.5], &[0.0; 21], h / 2.0);
        let ef = local_errors(
            linear(a, [0.0, 0.0]),
            &fine,
            Excitations::Linear,
            1e-12,
            &name,
        )
        .unwrap();
        let ratio = worst / ef.largest_relative_error.unwrap();
        assert!((7.0..9.0).contains(&ratio), "ratio {ratio}");
    }

    /// ẋ = u with u linear between the nodes: the midpoint rule's mean
    /// excitation integrates it exactly, so the mesh has no error; an
    /// excitation held over each interval would leave h·|Δu|/2.
    #[test]
    fn excitations_are_linear_between_the_nodes() {
        let u = [0.0, 1.0, 0.2, 0.9, 0.9, 0.0];
        let a = [[0.0, 0.0], [0.0, 0.0]];
        let mesh = midpoint_mesh(a, [1.0, 0.0], [0.3, 0.0], &u, 0.05);
        let e = local_errors(
            linear(a, [1.0, 0.0]),
            &mesh,
            Excitations::Linear,
            1e-12,
            &name,
        )
        .unwrap();
        assert!(e.largest_relative_error.unwrap() < 1e-12, "{e:?}");
        // The same nodes with the excitation halved: the error is the
        // missing half of the integral, h·ū/2 per interval.
        let mut f = linear(a, [0.5, 0.0]);
        let e = local_errors(&mut f, &mesh, Excitations::Linear, 1e-12, &name).unwrap();
        let scale = 1.0 + mesh.states.iter().map(|x| x[0].abs()).fold(0.0, f64::max);
        for (k, ie) in e.intervals.iter().enumerate() {
            let want = 0.5 * 0.05 * 0.5 * (u[k] + u[k + 1]) / scale;
            let got = ie.relative_error.unwrap();
            assert!(
                (got - want).abs() < 1e-12,
                "interval {}: {got} against {want}",
                k + 1
            );
        }
    }

    /// The double integrator ẋ₀ = u, ẋ₁ = x₀ sees when u changes within an
    /// interval. From the midpoint nodes, with u linear the exact x₀ agrees
    /// and x₁ differs by h²|u_k − u_{k−1}|/12 in closed form; with u_k held,
    /// x₀ differs by h|u_k − u_{k−1}|/2. An excitation held at the
    /// interval's mean would show no error at all.
    #[test]
    fn the_timing_of_the_excitations_within_an_interval_counts() {
        let (u, h) = ([0.0, 1.0, 0.2, 0.9, 0.9, 0.0], 0.05);
        let a = [[0.0, 0.0], [1.0, 0.0]];
        let mesh = midpoint_mesh(a, [1.0, 0.0], [0.3, 0.1], &u, h);
        let scale = |j: usize| 1.0 + mesh.states.iter().map(|x| x[j].abs()).fold(0.0, f64::max);
        for (excitations, j, factor) in [
            (Excitations::Linear, 1, h * h / 12.0),
            (Excitations::HeldAtEnd, 0, h / 2.0),
        ] {
            let e = local_errors(linear(a, [1.0, 0.0]), &mesh, excitations, 1e-12, &name).unwrap();
            for (k, ie) in e.intervals.iter().enumerate() {
                let want = factor * (u[k + 1] - u[k]).abs();
                let got = ie.absolute_error.unwrap();
                let at = format!("{excitations:?}, interval {}", k + 1);
                assert!((got - want).abs() < 1e-12, "{at}: {got} against {want}");
                if want > 0.0 {
                    assert_eq!(ie.state, name(j), "{at}");
                    let r = ie.relative_error.unwrap();
                    assert!((r - want / scale(j)).abs() < 1e-12, "{at}: {r}");
                }
            }
        }
    }

    /// Backward Euler's nodes x_k = x_{k−1} + h·u_k of ẋ = u are exact for
    /// u_k held over the interval, the scheme's reading.
    #[test]
    fn backward_euler_holds_the_interval_end_excitation() {
        let u = [0.0, 1.0, 0.2, 0.9];
        let h = 0.1;
        let mut x = vec![vec![0.3]];
        for k in 1..u.len() {
            let next = x[k - 1][0] + h * u[k];
            x.push(vec![next]);
        }
        let mesh = MeshTrajectory {
            time: (0..u.len()).map(|k| k as f64 * h).collect(),
            states: x,
            controls: u.iter().map(|&v| vec![v]).collect(),
        };
        let f = |_: &[f64], u: &[f64], dx: &mut [f64]| {
            dx[0] = u[0];
            Ok(())
        };
        let scheme = crate::transcription::Scheme::BackwardEuler;
        let e = local_errors(f, &mesh, Excitations::of(scheme), 1e-12, &name).unwrap();
        assert!(e.largest_relative_error.unwrap() < 1e-14, "{e:?}");
        let e = local_errors(f, &mesh, Excitations::Linear, 1e-12, &name).unwrap();
        assert!(
            (e.intervals[0].absolute_error.unwrap() - 0.05).abs() < 1e-12,
            "{e:?}"
        );
    }

    #[test]
    fn a_failing_interval_is_recorded_and_bad_meshes_are_refused() {
        let a = [[0.0, 0.0], [0.0, 0.0]];
        let u = [0.0, 1.0, 1.0, 1.0];
        let mesh = midpoint_mesh(a, [1.0, 0.0], [0.0, 0.0], &u, 0.1);
        // The right-hand side fails beyond x = 0.12: within interval 2, and
        // at once in interval 3, which starts at its node, 0.15.
        let f = |x: &[f64], u: &[f64], dx: &mut [f64]| {
            if x[0] > 0.12 {
                return Err(format!("x = {} beyond 0.12", x[0]));
            }
            dx[0] = u[0];
            dx[1] = 0.0;
            Ok(())
        };
        let e = local_errors(f, &mesh, Excitations::Linear, 1e-10, &name).unwrap();
        assert!(e.intervals[0].relative_error.unwrap() < 1e-12);
        for i in &e.intervals[1..] {
            assert!(i.relative_error.is_none());
            assert!(
                i.failure.as_deref().unwrap().contains("beyond 0.12"),
                "{i:?}"
            );
        }
        assert_eq!(e.worst_interval, Some(1));
        let mut nan = mesh.clone();
        nan.states[1][1] = f64::NAN;
        let e = local_errors(f, &nan, Excitations::Linear, 1e-10, &name).unwrap();
        for i in &e.intervals[..2] {
            assert_eq!(
                i.failure.as_deref(),
                Some("a node's states or excitations are not finite")
            );
        }
        let mut bad = mesh.clone();
        bad.time[2] = bad.time[1];
        let r = local_errors(f, &bad, Excitations::Linear, 1e-10, &name).unwrap_err();
        assert!(r.contains("do not increase"), "{r}");
        let mut bad = mesh.clone();
        bad.states[3].pop();
        let r = local_errors(f, &bad, Excitations::Linear, 1e-10, &name).unwrap_err();
        assert!(r.contains("node 3"), "{r}");
    }
}
