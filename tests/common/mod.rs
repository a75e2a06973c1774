//! Shared test helpers.
#![allow(dead_code)]

use leap::model::Model;
use leap::ode::{ForceLaws, MuscleRates};
use leap::scalar::Scalar;

/// Simple smooth laws with known structure (not OpenSim's; those have their
/// own golden tests): tendon force F0·a·(l_MT/0.3), fibre velocity
/// proportional to the MTU speed, first-order activation; a penalty contact;
/// a linear-spring ligament.
pub struct TestLaws(pub Model);

impl<S: Scalar> ForceLaws<S> for TestLaws {
    fn muscle(
        &self,
        m: usize,
        a: S,
        lm: S,
        lmt: S,
        vmt: S,
        u: S,
    ) -> Result<MuscleRates<S>, String> {
        let f0 = self.0.muscles[m].spec.max_isometric_force;
        Ok(MuscleRates {
            tendon_force: a * lmt * (f0 / 0.3),
            fiber_velocity: vmt * 0.5 - lm * 0.1,
            activation_rate: (u - a) * 25.0,
        })
    }
    fn sphere(&self, _k: usize, p: [S; 3], v: [S; 3]) -> ([S; 3], [S; 3]) {
        let r = 0.032;
        let pen = p[1] * -1.0 + r;
        if pen.re() <= 0.0 {
            return ([S::zero(); 3], p);
        }
        let fy = pen * pen * 1e6 * (S::one() - v[1] * 2.0);
        ([v[0] * -100.0, fy, S::zero()], [p[0], p[1] - r, p[2]])
    }
    fn ligament(&self, _l: usize, q: S, qd: S) -> S {
        q * -3.0 - qd * 0.1
    }
}

/// ẋ = f(x, u) of a state equation with OpenSim's laws at fixed excitations.
pub struct FixedExcitation<'a> {
    pub eq: &'a leap::ode::StateEquation,
    pub laws: &'a leap::laws::OpenSimLaws,
    pub ws: leap::ode::StateWorkspace<f64>,
    pub u: Vec<f64>,
}

impl leap::integrator::OdeSystem for FixedExcitation<'_> {
    fn dim(&self) -> usize {
        self.eq.nx()
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), String> {
        self.eq
            .rhs(self.laws, &mut self.ws, x, &self.u, dx)
            .map_err(|e| e.to_string())
    }
}

/// Full excitation from t = 0 for every muscle with an extensor moment at
/// `pose` (the bang-bang jump), 0.01 for the others.
pub fn extensor_bang_bang(eq: &leap::ode::StateEquation, pose: &[f64]) -> leap::simulate::BangBang {
    leap::simulate::BangBang {
        intervals: leap::simulate::extensor_moments(eq, pose)
            .iter()
            .map(|&e| if e > 0.0 { Some((0.0, 10.0)) } else { None })
            .collect(),
        off_level: 0.01,
    }
}

/// A push-off analysis checked against physics and against the jump it
/// came from: Newton's second law for the whole body (the vertical ground
/// impulse less the weight's equals the COM momentum change, within
/// `impulse_rel`) and the jump height of the simulation that produced the
/// trajectory (`reference_height_m`, named `reference`), within 5 mm.
pub fn assert_push_off_consistent(
    a: &leap::analyze::JumpAnalysis,
    impulse_rel: f64,
    reference_height_m: f64,
    reference: &str,
) {
    assert!(
        (a.vertical_impulse_ns - a.com_momentum_change_ns).abs()
            <= impulse_rel * a.com_momentum_change_ns.abs(),
        "impulse {} N·s, momentum change {} N·s",
        a.vertical_impulse_ns,
        a.com_momentum_change_ns
    );
    assert!(
        (a.jump_height_m - reference_height_m).abs() <= 5e-3,
        "analysis {} m, {reference} {reference_height_m} m",
        a.jump_height_m
    );
}

/// Clarabel's verdict on a QP the SQP wrote (clarabel JSON), read back
/// with clarabel's own loader and solved with the settings saved in it.
pub fn clarabel_status(path: &std::path::Path) -> clarabel::solver::SolverStatus {
    use clarabel::solver::{DefaultSolver, IPSolver, SolverJSONReadWrite};
    let mut f = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut s = DefaultSolver::<f64>::load_from_file(&mut f, None)
        .unwrap_or_else(|e| panic!("{}: {e:?}", path.display()));
    s.solve();
    s.solution.status
}

/// Run `cmd`, a `leap` command that must refuse its input: exit code 2 and
/// no panic (`what` labels a failure). Returns its standard error.
pub fn refused(cmd: &mut assert_cmd::Command, what: &str) -> String {
    let o = cmd.output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{what}: {err}");
    assert!(!err.contains("panicked"), "{what}: {err}");
    err
}
