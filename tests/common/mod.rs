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
