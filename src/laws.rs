//! OpenSim's force laws for the state equation: Thelen2003Muscle with
//! first-order activation, HuntCrossleyForce and SmoothSphereHalfSpaceForce
//! for sphere-ground contact, and exponential passive joint torques,
//! generic over the scalar type. Equations and their sources are in
//! `docs/model-equations.md` (§1.1, §2.2-§2.7, §4.2-§4.3, §5.3).

use crate::model::{ContactLaw, ContactSpec, Model, MuscleModel, MuscleSpec};
use crate::ode::{ForceLaws, MuscleRates};
use crate::scalar::{c, Scalar};

/// Thelen's maximum pennation angle, acos(0.1) (OpenSim 3.2 `buildMuscle`).
const MAX_PENNATION: f64 = 1.4706289056333368;
/// Thelen's minimum activation (3.2: fixed; 4.x `minimum_activation`).
pub const MIN_ACTIVATION: f64 = 0.01;
/// Thelen's force-velocity extrapolation threshold (default, absent in 3.x files).
pub const FV_THRESHOLD: f64 = 0.95;

/// Thelen2003Muscle with its constants precomputed.
#[derive(Debug, Clone)]
pub struct Thelen {
    pub f0: f64,
    pub lopt: f64,
    pub lts: f64,
    pub vmax: f64,
    pub tau_act: f64,
    pub tau_deact: f64,
    #[allow(dead_code)]
    e0_t: f64,
    e0_m: f64,
    gamma: f64,
    kpe: f64,
    af: f64,
    flen: f64,
    /// Parallelogram height l_o·sin φ_o and minimum fibre length.
    height: f64,
    pub min_fiber_length: f64,
    pennated: bool,
    e_toe: f64,
    k_lin: f64,
    /// None: OpenSim's switch between the activation and deactivation time
    /// constants at u = a (a kink in da/dt). Some(b): the switch blended by
    /// ½ + ½·tanh(b·(u − a)), De Groote et al.'s (2016) smoothing, for
    /// gradient-based optimal control (see [`Thelen::activation_rate`]).
    pub activation_smoothing: Option<f64>,
    /// None: OpenSim's clamp, which stops a shortening fibre at l_min (a
    /// jump in the fibre velocity). Some: the clamp spread over a band above
    /// a floor, for gradient-based optimal control (see
    /// [`FiberClampSmoothing`]).
    pub fiber_clamp_smoothing: Option<FiberClampSmoothing>,
}

/// Thelen's fibre clamp made smooth: between `floor` and `floor + width`
/// (m) a shortening fibre velocity v is scaled by a C² ramp g, 0 at the
/// floor, 1 at the band's top, and the switch between shortening and
/// lengthening is blended over |v| ≈ [`CLAMP_VELOCITY_BLEND`]:
/// v_eff = v − (1 − g)·½(v − √(v² + ε²)). Above the band the velocity is
/// the model's own; at the floor a shortening fibre stops, as at OpenSim's
/// l_min. With the tendon slack the inverted force-velocity curve asks a
/// fibre to shorten at about v_max·(0.25 + 0.75·a) whatever its length; at
/// OpenSim's clamp that velocity drops to zero in a step, which a Newton
/// step cannot cross (an explicit fibre-length defect evaluated at a node
/// where the tendon is slack, as Hermite–Simpson and trapezoidal
/// collocation do at lift-off).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiberClampSmoothing {
    pub floor: f64,
    pub width: f64,
}

/// ε of [`FiberClampSmoothing`]'s blend between shortening and lengthening,
/// in units of v_max·l_o.
pub const CLAMP_VELOCITY_BLEND: f64 = 0.01;

impl FiberClampSmoothing {
    /// The smoothed normalised fibre velocity at fibre length `lm`.
    fn apply<S: Scalar>(&self, lm: S, vn: S) -> S {
        let r = (lm.re() - self.floor) / self.width;
        if r >= 1.0 {
            return vn;
        }
        // 1 − g with g = 6r⁵ − 15r⁴ + 10r³ (C² at both ends of the band).
        let stop = if r <= 0.0 {
            S::one()
        } else {
            let r = (lm - self.floor) / self.width;
            let g = r * r * r * (r * (r * 6.0 - 15.0) + 10.0);
            g * -1.0 + 1.0
        };
        let shortening =
            (vn - (vn * vn + CLAMP_VELOCITY_BLEND * CLAMP_VELOCITY_BLEND).sqrt()) * 0.5;
        vn - stop * shortening
    }
}

/// Everything Thelen2003Muscle computes at one state (OpenSim's names).
#[derive(Debug, Clone, Copy)]
pub struct ThelenInfo<S> {
    pub activation_rate: S,
    pub fiber_velocity: S,
    pub fiber_length: S,
    pub pennation_angle: S,
    pub tendon_length: S,
    pub tendon_force: S,
    pub active_fiber_force: S,
    pub passive_fiber_force: S,
    pub normalized_fiber_length: S,
    pub normalized_fiber_velocity: S,
    pub active_force_length_multiplier: S,
    pub force_velocity_multiplier: S,
    pub fiber_clamped: bool,
}

impl Thelen {
    pub fn new(m: &MuscleSpec) -> Self {
        let e = std::f64::consts::E;
        let e3 = e * e * e;
        let e_toe = 99.0 * m.FmaxTendonStrain * e3 / (166.0 * e3 - 67.0);
        let height = m.optimal_fiber_length * m.pennation_angle_at_optimal.sin();
        Thelen {
            f0: m.max_isometric_force,
            lopt: m.optimal_fiber_length,
            lts: m.tendon_slack_length,
            vmax: m.max_contraction_velocity,
            tau_act: m.activation_time_constant,
            tau_deact: m.deactivation_time_constant,
            e0_t: m.FmaxTendonStrain,
            e0_m: m.FmaxMuscleStrain,
            gamma: m.KshapeActive,
            kpe: m.KshapePassive,
            af: m.Af,
            flen: m.Flen,
            height,
            min_fiber_length: height / MAX_PENNATION.sin(),
            pennated: m.pennation_angle_at_optimal > f64::EPSILON,
            e_toe,
            k_lin: 0.67 / (m.FmaxTendonStrain - e_toe),
            activation_smoothing: None,
            fiber_clamp_smoothing: None,
        }
    }

    /// Active force-length multiplier (Gaussian).
    pub fn fal<S: Scalar>(&self, ln: S) -> S {
        let d = ln - 1.0;
        (-(d * d) / self.gamma).exp()
    }

    /// Passive force-length multiplier.
    pub fn fpe<S: Scalar>(&self, ln: S) -> S {
        if ln.re() <= 1.0 {
            S::zero()
        } else {
            (((ln - 1.0) * (self.kpe / self.e0_m)).exp() - 1.0) / (self.kpe.exp() - 1.0)
        }
    }

    /// Tendon force-strain multiplier with Thelen's exact toe constants.
    pub fn fse<S: Scalar>(&self, strain: S) -> S {
        let ftoe = 0.33;
        let ktoe = 3.0;
        if strain.re() <= 0.0 {
            S::zero()
        } else if strain.re() <= self.e_toe {
            ((strain * (ktoe / self.e_toe)).exp() - 1.0) * (ftoe / (ktoe.exp() - 1.0))
        } else {
            (strain - self.e_toe) * self.k_lin + ftoe
        }
    }

    /// Pennation angle at fibre length `lm` (already clamped to l_min).
    fn pennation<S: Scalar>(&self, lm: S) -> S {
        let (s, _) = self.pennation_sin_cos(lm);
        if s.re() == 0.0 {
            S::zero()
        } else if s.re() >= MAX_PENNATION.sin() {
            c(MAX_PENNATION)
        } else {
            s.asin()
        }
    }

    /// sin φ and cos φ at fibre length `lm` (already clamped), without trig.
    #[inline]
    fn pennation_sin_cos<S: Scalar>(&self, lm: S) -> (S, S) {
        if !self.pennated {
            return (S::zero(), S::one());
        }
        let s = lm.recip() * self.height;
        if lm.re() > self.min_fiber_length && s.re() < MAX_PENNATION.sin() {
            (s, (s * s * -1.0 + 1.0).sqrt())
        } else {
            (c(MAX_PENNATION.sin()), c(MAX_PENNATION.cos()))
        }
    }

    /// cos φ, the normalised fibre length and the tendon force multiplier
    /// at fibre length `lm_state` (clamped to l_min) and muscle-tendon
    /// length `lmt`.
    #[inline]
    fn fibre_and_tendon<S: Scalar>(&self, lm_state: S, lmt: S) -> (S, S, S) {
        let lm = if lm_state.re() < self.min_fiber_length {
            c(self.min_fiber_length)
        } else {
            lm_state
        };
        let (_, cos_phi) = self.pennation_sin_cos(lm);
        let fse = self.fse((lmt - lm * cos_phi) / self.lts - 1.0);
        (cos_phi, lm / self.lopt, fse)
    }

    /// The state derivatives and tendon force only (the hot path).
    #[inline]
    pub fn rates<S: Scalar>(&self, a: S, lm_state: S, lmt: S, u: S) -> MuscleRates<S> {
        let ac = clamp(a, MIN_ACTIVATION, 1.0);
        let (cos_phi, ln, fse) = self.fibre_and_tendon(lm_state, lmt);
        let f = fse / cos_phi - self.fpe(ln);
        let mut vn = self.dlce_n(ac, self.fal(ln), f);
        if let Some(sm) = &self.fiber_clamp_smoothing {
            vn = sm.apply(lm_state, vn);
        }
        if lm_state.re() <= self.min_fiber_length && vn.re() <= 0.0 {
            vn = S::zero();
        }
        MuscleRates {
            tendon_force: fse * self.f0,
            fiber_velocity: vn * (self.vmax * self.lopt),
            activation_rate: self.activation_rate(a, u),
        }
    }

    /// Normalised fibre velocity from Thelen's inverted force-velocity curve
    /// with linear extrapolation (`calcdlceN`).
    fn dlce_n<S: Scalar>(&self, act: S, fal: S, f: S) -> S {
        let a_big = act * fal;
        let k = act * 0.75 + 0.25;
        let (af, flen) = (self.af, self.flen);
        let b_of = |f: S| -> (S, S) {
            if f.re() <= a_big.re() {
                (a_big + f / af, c(1.0 / af))
            } else {
                (
                    (a_big * flen - f) * ((2.0 + 2.0 / af) / (flen - 1.0)),
                    c(-(2.0 + 2.0 / af) / (flen - 1.0)),
                )
            }
        };
        let knee = a_big * (FV_THRESHOLD * flen);
        if f.re() > 0.0 && f.re() < knee.re() {
            let (b, _) = b_of(f);
            k * (f - a_big) / b
        } else {
            let f0 = if f.re() <= 0.0 { S::zero() } else { knee };
            let (b0, db0) = b_of(f0);
            let g0 = k * (f0 - a_big) / b0;
            let slope = k / b0 - k * (f0 - a_big) * db0 / (b0 * b0);
            g0 + slope * (f - f0)
        }
    }

    /// Thelen's force-velocity multiplier at normalised fibre velocity `vn`
    /// (lengthening positive, units of v_max·l_o) and clamped activation
    /// `act`: the exact inverse of [`Thelen::dlce_n`], its linear
    /// extrapolations included, so that act·f_al·f_v(dlce_n(act, f_al, f))
    /// = f. With k = 0.25 + 0.75·act, c = (2 + 2/A_f)/(F_len − 1) and the
    /// knee at f_v = 0.95·F_len:
    /// * v ≤ −k (tendon slack): (v + k)/(k·(1 + 1/A_f));
    /// * −k < v ≤ 0 (shortening): (k + v)/(k − v/A_f);
    /// * 0 < v below the knee (lengthening): (k + c·F_len·v)/(k + c·v);
    /// * beyond the knee: linear with the curve's slope there.
    ///
    /// Unlike its inverse, f_v has no 1/act in it: the implicit fibre
    /// dynamics ([`Thelen::force_balance`]) stay mild at the minimum
    /// activation.
    pub fn fv<S: Scalar>(&self, act: S, vn: S) -> S {
        let k = act * 0.75 + 0.25;
        let (af, flen) = (self.af, self.flen);
        let cc = (2.0 + 2.0 / af) / (flen - 1.0);
        let knee = FV_THRESHOLD * flen;
        let knee_v = k * ((knee - 1.0) / ((flen - knee) * cc));
        if vn.re() <= -k.re() {
            (vn + k) / (k * (1.0 + 1.0 / af))
        } else if vn.re() <= 0.0 {
            (vn + k) / (k - vn / af)
        } else if vn.re() < knee_v.re() {
            (vn * (cc * flen) + k) / (vn * cc + k)
        } else {
            let slope = k * ((flen - 1.0) / ((flen - knee) * (flen - knee) * cc));
            (vn - knee_v) / slope + knee
        }
    }

    /// The muscle-tendon force balance in units of F_0 at fibre length
    /// `lm_state`, muscle-tendon length `lmt` and normalised fibre velocity
    /// `vn`: f_se − (a·f_al·f_v + f_pe)·cos φ. Zero exactly where `vn` is
    /// the velocity [`Thelen::rates`] gives (the implicit form of the
    /// same fibre dynamics; activation and fibre length clamped as there).
    pub fn force_balance<S: Scalar>(&self, a: S, lm_state: S, lmt: S, vn: S) -> S {
        let ac = clamp(a, MIN_ACTIVATION, 1.0);
        let (cos_phi, ln, fse) = self.fibre_and_tendon(lm_state, lmt);
        self.balance(ac, cos_phi, ln, fse, vn)
    }

    /// f_se − (a·f_al·f_v + f_pe)·cos φ from the fibre and tendon state.
    fn balance<S: Scalar>(&self, ac: S, cos_phi: S, ln: S, fse: S, vn: S) -> S {
        fse - (ac * self.fal(ln) * self.fv(ac, vn) + self.fpe(ln)) * cos_phi
    }

    /// [`Thelen::rates`] with the force balance at normalised fibre
    /// velocity `vn` ([`Thelen::force_balance`]) in place of the fibre
    /// velocity: the implicit fibre dynamics, without inverting the
    /// force-velocity curve.
    pub fn balance_rates<S: Scalar>(
        &self,
        a: S,
        lm_state: S,
        lmt: S,
        u: S,
        vn: S,
    ) -> MuscleRates<S> {
        let ac = clamp(a, MIN_ACTIVATION, 1.0);
        let (cos_phi, ln, fse) = self.fibre_and_tendon(lm_state, lmt);
        MuscleRates {
            tendon_force: fse * self.f0,
            fiber_velocity: self.balance(ac, cos_phi, ln, fse, vn),
            activation_rate: self.activation_rate(a, u),
        }
    }

    /// Activation rate (OpenSim 4.x: excitation not clamped; §1.1).
    pub fn activation_rate<S: Scalar>(&self, a: S, u: S) -> S {
        let ac = clamp(a, MIN_ACTIVATION, 1.0);
        let z = ac * 1.5 + 0.5;
        if let Some(b) = self.activation_smoothing {
            // 1/τ = s/(τ_act z) + (1 − s) z/τ_deact, s = ½ + ½ tanh(b (u − a)):
            // the same rates as OpenSim's away from u = a, smooth across it.
            let s = crate::scalar::tanh((u - ac) * b) * 0.5 + 0.5;
            return (u - ac) * (s / (z * self.tau_act) + (s * -1.0 + 1.0) * z / self.tau_deact);
        }
        let tau = if u.re() > ac.re() {
            z * self.tau_act
        } else {
            z.recip() * self.tau_deact
        };
        (u - ac) / tau
    }

    /// The muscle's state derivatives and outputs (§2.2-§2.6).
    pub fn calc<S: Scalar>(&self, a: S, lm_state: S, lmt: S, _vmt: S, u: S) -> ThelenInfo<S> {
        let ac = clamp(a, MIN_ACTIVATION, 1.0);
        let lm = if lm_state.re() < self.min_fiber_length {
            c(self.min_fiber_length)
        } else {
            lm_state
        };
        let phi = self.pennation(lm);
        let (_, cos_phi) = self.pennation_sin_cos(lm);
        let lt = lmt - lm * cos_phi;
        let ln = lm / self.lopt;
        let fse = self.fse(lt / self.lts - 1.0);
        let fal = self.fal(ln);
        let fpe = self.fpe(ln);
        let f = fse / cos_phi - fpe;
        let mut vn = self.dlce_n(ac, fal, f);
        if let Some(sm) = &self.fiber_clamp_smoothing {
            vn = sm.apply(lm_state, vn);
        }
        let clamped = lm_state.re() <= self.min_fiber_length && vn.re() <= 0.0;
        if clamped {
            vn = S::zero();
        }
        let fv = if clamped { S::one() } else { f / (ac * fal) };
        ThelenInfo {
            activation_rate: self.activation_rate(a, u),
            fiber_velocity: vn * (self.vmax * self.lopt),
            fiber_length: lm,
            pennation_angle: phi,
            tendon_length: lt,
            tendon_force: fse * self.f0,
            active_fiber_force: if clamped {
                S::zero()
            } else {
                ac * fal * fv * self.f0
            },
            passive_fiber_force: if clamped { S::zero() } else { fpe * self.f0 },
            normalized_fiber_length: ln,
            normalized_fiber_velocity: vn,
            active_force_length_multiplier: fal,
            force_velocity_multiplier: fv,
            fiber_clamped: clamped,
        }
    }

    /// Fibre length in static equilibrium (v_MT = 0, so f_v = 1) at
    /// activation `a` and muscle-tendon length `lmt`: the root of
    /// (a·f_al + f_pe)·cos φ = f_se, by bisection (OpenSim's
    /// `computeInitialFiberEquilibrium` solves the same equation, §2.7).
    pub fn equilibrium_fiber_length(&self, a: f64, lmt: f64) -> f64 {
        let ac = a.clamp(MIN_ACTIVATION, 1.0);
        let resid = |lm: f64| {
            let (_, cos_phi): (f64, f64) = self.pennation_sin_cos(lm);
            let lt = lmt - lm * cos_phi;
            let ln = lm / self.lopt;
            (ac * self.fal(ln) + self.fpe(ln)) * cos_phi - self.fse(lt / self.lts - 1.0)
        };
        let lo = self.min_fiber_length.max(1e-6 * self.lopt);
        bisect_increasing(resid, lo, lmt.max(lo * 2.0), 1e-15 * self.lopt)
    }
}

/// The root of an increasing residual in [lo, hi] by bisection (the fibre
/// length of muscle-tendon equilibrium: the residual rises with l_M as the
/// tendon shortens); an end if the root lies outside.
fn bisect_increasing(resid: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64, tol: f64) -> f64 {
    if resid(lo) > 0.0 {
        return lo;
    }
    if resid(hi) < 0.0 {
        return hi;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if resid(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
        if hi - lo < tol {
            break;
        }
    }
    0.5 * (lo + hi)
}

fn clamp<S: Scalar>(x: S, lo: f64, hi: f64) -> S {
    if x.re() < lo {
        c(lo)
    } else if x.re() > hi {
        c(hi)
    } else {
        x
    }
}

/// Force on a sphere of radius `r` (centre `p`) from the ground half-space
/// (normal +y) and its point of application, for the contact law of `spec`
/// (§4.2-§4.3); `v` is the velocity of the sphere's material point at the
/// contact point (centre velocity plus ω × r: rolling does not slip).
/// One contact element per sphere, so HuntCrossleyForce's "return" quirk
/// across spheres does not arise.
pub fn sphere_ground_force<S: Scalar>(
    spec: &ContactSpec,
    r: f64,
    p: [S; 3],
    v: [S; 3],
) -> ([S; 3], [S; 3]) {
    sphere_ground_force_k(spec, hertz_k(spec.stiffness), r, p, v)
}

/// Simbody stores E^(2/3); two equal surfaces combine to k = ½·E^(2/3).
pub fn hertz_k(stiffness: f64) -> f64 {
    0.5 * stiffness.cbrt() * stiffness.cbrt()
}

/// [`sphere_ground_force`] with the combined Hertz constant `k` precomputed.
#[inline]
pub fn sphere_ground_force_k<S: Scalar>(
    spec: &ContactSpec,
    k: f64,
    r: f64,
    p: [S; 3],
    v: [S; 3],
) -> ([S; 3], [S; 3]) {
    let depth = p[1] * -1.0 + r;
    // v_n: penetration rate (the sphere moving into the ground).
    let vn = v[1] * -1.0;
    let (mus, mud, muv, vt) = (
        spec.static_friction,
        spec.dynamic_friction,
        spec.viscous_friction,
        spec.transition_velocity,
    );
    let point = [p[0], p[1] - (depth * -0.5 + r), p[2]];
    match spec.law {
        ContactLaw::HuntCrossleyForce => {
            if depth.re() <= 0.0 {
                return ([S::zero(); 3], point);
            }
            let fh = (depth * r).sqrt() * depth * (4.0 / 3.0 * k * k.sqrt());
            let f = fh * (vn * (1.5 * spec.dissipation) + 1.0);
            if f.re() <= 0.0 {
                return ([S::zero(); 3], point);
            }
            let vs2 = v[0] * v[0] + v[2] * v[2];
            if vs2.re() == 0.0 {
                return ([S::zero(), f, S::zero()], point);
            }
            let vs = vs2.sqrt();
            let vr = vs / vt;
            let ff =
                f * (min1(vr) * ((vr * vr + 1.0).recip() * (2.0 * (mus - mud)) + mud) + vs * muv);
            ([v[0] / vs * -ff, f, v[2] / vs * -ff], point)
        }
        ContactLaw::SmoothSphereHalfSpaceForce => {
            let cf = spec.derivative_smoothing.unwrap_or(1e-5);
            let bd = spec.hertz_smoothing.unwrap_or(300.0);
            let bv = spec.hunt_crossley_smoothing.unwrap_or(50.0);
            let d2 = (depth * depth + cf).sqrt();
            let fh = d2
                * d2.sqrt()
                * (4.0 / 3.0 * k * (r * k).sqrt())
                * (crate::scalar::tanh(depth * bd) * 0.5 + 0.5);
            let shift = if spec.dissipation == 0.0 {
                f64::INFINITY
            } else {
                2.0 / (3.0 * spec.dissipation)
            };
            let sw = if shift.is_infinite() {
                S::one()
            } else {
                crate::scalar::tanh((vn + shift) * bv) * 0.5 + 0.5
            };
            let f = fh * (vn * (1.5 * spec.dissipation) + 1.0) * sw;
            let vs = (v[0] * v[0] + v[2] * v[2] + cf).sqrt();
            let vr = vs / vt;
            let ff =
                f * (min1(vr) * ((vr * vr + 1.0).recip() * (2.0 * (mus - mud)) + mud) + vs * muv);
            ([v[0] / vs * -ff, f, v[2] / vs * -ff], point)
        }
    }
}

fn min1<S: Scalar>(x: S) -> S {
    if x.re() < 1.0 {
        x
    } else {
        S::one()
    }
}

/// Anderson & Pandy's exponential passive torque with damping (§5.3). A
/// term with k = 0 is switched off: zero, not 0·exp(…), which is NaN where
/// the exponential overflows.
pub fn passive_torque<S: Scalar>(l: &crate::model::LigamentSpec, q: S, qd: S) -> S {
    let term = |k: f64, rate: f64, theta: f64| {
        if k == 0.0 {
            S::zero()
        } else {
            ((q - theta) * rate).exp() * k
        }
    };
    term(l.k1, l.k2, l.theta2) + term(l.k3, l.k4, l.theta1) - qd * l.damping
}

/// DeGrooteFregly2016Muscle's curves (De Groote et al., Ann. Biomed. Eng.
/// 2016; constants as in OpenSim 4.6, model-equations.md §3.2) in leap's
/// explicit fibre-length formulation: the tendon force follows from the
/// tendon length, and the fibre velocity from the closed-form inverse of the
/// force-velocity curve. `FmaxTendonStrain` and `FmaxMuscleStrain` play the
/// roles of `tendon_strain_at_one_norm_force` and
/// `passive_fiber_strain_at_one_norm_force`.
#[derive(Debug, Clone)]
pub struct DeGroote {
    pub f0: f64,
    pub lopt: f64,
    pub lts: f64,
    pub vmax: f64,
    pub tau_act: f64,
    pub tau_deact: f64,
    /// `activation_dynamics_smoothing` b (OpenSim default 0.1).
    pub smoothing: f64,
    width: f64,
    k_t: f64,
    e0: f64,
}

const DG_B: [[f64; 4]; 3] = [
    [
        0.8150671134243542,
        1.055033428970575,
        0.162384573599574,
        0.063303448465465,
    ],
    [
        0.433004984392647,
        0.716775413397760,
        -0.029947116970696,
        0.200356847296188,
    ],
    [0.1, 1.0, 0.353553390593274, 0.0],
];
const DG_D: [f64; 4] = [-0.3211346127989808, -8.149, -0.374, 0.8825327733249912];
const DG_KPE: f64 = 4.0;
const DG_LMIN: f64 = 0.2;
const DG_C: [f64; 3] = [0.2, 1.0, 0.2];

impl DeGroote {
    pub fn new(m: &MuscleSpec) -> Self {
        DeGroote {
            f0: m.max_isometric_force,
            lopt: m.optimal_fiber_length,
            lts: m.tendon_slack_length,
            vmax: m.max_contraction_velocity,
            tau_act: m.activation_time_constant,
            tau_deact: m.deactivation_time_constant,
            smoothing: 0.1,
            width: m.optimal_fiber_length * m.pennation_angle_at_optimal.sin(),
            k_t: ((1.0 + DG_C[2]) / DG_C[0]).ln() / (1.0 + m.FmaxTendonStrain - DG_C[1]),
            e0: m.FmaxMuscleStrain,
        }
    }

    /// Active force-length multiplier (three Gaussian-like terms).
    pub fn fal<S: Scalar>(&self, ln: S) -> S {
        let mut f = S::zero();
        for b in DG_B {
            let den = ln * b[3] + b[2];
            let d = ln - b[1];
            f += (d * d * -0.5 / (den * den)).exp() * b[0];
        }
        f
    }

    /// Passive force-length multiplier (zero at l̃ = 0.2).
    pub fn fpe<S: Scalar>(&self, ln: S) -> S {
        let e_min = (DG_KPE * (DG_LMIN - 1.0) / self.e0).exp();
        (((ln - 1.0) * (DG_KPE / self.e0)).exp() - e_min) / (DG_KPE.exp() - e_min)
    }

    /// Force-velocity multiplier and its inverse.
    pub fn fv<S: Scalar>(&self, v: S) -> S {
        let t = v * DG_D[1] + DG_D[2];
        // asinh(t) = ln(t + √(t² + 1)), odd: for t < 0 the sum cancels
        // (fast lengthening: t = −1e7 leaves a few digits), so −asinh(−t).
        let asinh_pos = |t: S| (t + (t * t + 1.0).sqrt()).ln();
        let asinh = if t.re() < 0.0 {
            -asinh_pos(-t)
        } else {
            asinh_pos(t)
        };
        asinh * DG_D[0] + DG_D[3]
    }
    pub fn fv_inv<S: Scalar>(&self, f: S) -> S {
        (((f - DG_D[3]) / DG_D[0]).sinh() - DG_D[2]) / DG_D[1]
    }

    /// Tendon force multiplier of the normalised tendon length.
    pub fn ft<S: Scalar>(&self, lt_n: S) -> S {
        ((lt_n - DG_C[1]) * self.k_t).exp() * DG_C[0] - DG_C[2]
    }

    /// De Groote's smooth activation dynamics (model-equations.md §1.2).
    pub fn activation_rate<S: Scalar>(&self, a: S, u: S) -> S {
        let f = crate::scalar::tanh((u - a) * self.smoothing) * 0.5;
        let z = a * 1.5 + 0.5;
        ((f + 0.5) / (z * self.tau_act) + (f * -1.0 + 0.5) * z / self.tau_deact) * (u - a)
    }

    /// State derivatives and outputs at (a, l_M, l_MT, u).
    pub fn calc<S: Scalar>(&self, a: S, lm: S, lmt: S, u: S) -> ThelenInfo<S> {
        let along = (lm * lm - self.width * self.width).sqrt();
        let cos_phi = along / lm;
        let lt = lmt - along;
        let ft = self.ft(lt / self.lts);
        let ln = lm / self.lopt;
        let fal = self.fal(ln);
        let fpe = self.fpe(ln);
        let fv = (ft / cos_phi - fpe) / (a * fal);
        let vn = self.fv_inv(fv);
        ThelenInfo {
            activation_rate: self.activation_rate(a, u),
            fiber_velocity: vn * (self.vmax * self.lopt),
            fiber_length: lm,
            pennation_angle: (lm.recip() * self.width).asin(),
            tendon_length: lt,
            tendon_force: ft * self.f0,
            active_fiber_force: a * fal * fv * self.f0,
            passive_fiber_force: fpe * self.f0,
            normalized_fiber_length: ln,
            normalized_fiber_velocity: vn,
            active_force_length_multiplier: fal,
            force_velocity_multiplier: fv,
            fiber_clamped: false,
        }
    }

    /// The force balance in units of F_0 at normalised fibre velocity `vn`:
    /// f_T − (a·f_al·f_v(vn) + f_pe)·cos φ, zero where [`DeGroote::calc`]'s
    /// velocity is `vn`.
    pub fn force_balance<S: Scalar>(&self, a: S, lm: S, lmt: S, vn: S) -> S {
        let along = (lm * lm - self.width * self.width).sqrt();
        let cos_phi = along / lm;
        let ln = lm / self.lopt;
        let ft = self.ft((lmt - along) / self.lts);
        ft - (a * self.fal(ln) * self.fv(vn) + self.fpe(ln)) * cos_phi
    }

    /// Fibre length in static equilibrium: (a·f_al + f_pe)·cos φ = f_T.
    pub fn equilibrium_fiber_length(&self, a: f64, lmt: f64) -> f64 {
        let resid = |lm: f64| {
            let along = (lm * lm - self.width * self.width).sqrt();
            let ln = lm / self.lopt;
            (a * self.fal(ln) + self.fpe(ln)) * along / lm - self.ft((lmt - along) / self.lts)
        };
        let lo = (self.width * (1.0 + 1e-9)).max(DG_LMIN * self.lopt);
        bisect_increasing(resid, lo, lmt, 1e-15 * self.lopt)
    }
}

/// One muscle's law.
#[derive(Debug, Clone)]
pub enum MuscleLaw {
    Thelen(Thelen),
    DeGroote(DeGroote),
}

impl MuscleLaw {
    /// State derivatives and outputs (`vmt` only matters to Thelen's clamp).
    pub fn calc<S: Scalar>(&self, a: S, lm: S, lmt: S, vmt: S, u: S) -> ThelenInfo<S> {
        match self {
            MuscleLaw::Thelen(t) => t.calc(a, lm, lmt, vmt, u),
            MuscleLaw::DeGroote(d) => d.calc(a, lm, lmt, u),
        }
    }
    /// Fibre length in static muscle-tendon equilibrium.
    pub fn equilibrium_fiber_length(&self, a: f64, lmt: f64) -> f64 {
        match self {
            MuscleLaw::Thelen(t) => t.equilibrium_fiber_length(a, lmt),
            MuscleLaw::DeGroote(d) => d.equilibrium_fiber_length(a, lmt),
        }
    }
    /// The force balance of the implicit fibre dynamics (units of F_0) at
    /// normalised fibre velocity `vn`; see [`Thelen::force_balance`].
    pub fn force_balance<S: Scalar>(&self, a: S, lm: S, lmt: S, vn: S) -> S {
        match self {
            MuscleLaw::Thelen(t) => t.force_balance(a, lm, lmt, vn),
            MuscleLaw::DeGroote(d) => d.force_balance(a, lm, lmt, vn),
        }
    }
    /// The muscle's rates with the force balance at normalised fibre
    /// velocity `vn` in place of the fibre velocity (implicit fibre
    /// dynamics; see [`Thelen::balance_rates`]).
    pub fn balance_rates<S: Scalar>(&self, a: S, lm: S, lmt: S, u: S, vn: S) -> MuscleRates<S> {
        match self {
            MuscleLaw::Thelen(t) => t.balance_rates(a, lm, lmt, u, vn),
            MuscleLaw::DeGroote(d) => {
                let info = d.calc(a, lm, lmt, u);
                MuscleRates {
                    tendon_force: info.tendon_force,
                    fiber_velocity: d.force_balance(a, lm, lmt, vn),
                    activation_rate: info.activation_rate,
                }
            }
        }
    }
    /// v_max·l_o (m/s): the fibre speed of a normalised velocity of 1.
    pub fn max_fiber_speed(&self) -> f64 {
        match self {
            MuscleLaw::Thelen(t) => t.vmax * t.lopt,
            MuscleLaw::DeGroote(d) => d.vmax * d.lopt,
        }
    }
    /// The smallest excitation the law takes (OpenSim's min_control).
    pub fn min_excitation(&self) -> f64 {
        match self {
            MuscleLaw::Thelen(_) => MIN_ACTIVATION,
            MuscleLaw::DeGroote(_) => 0.0,
        }
    }
}

/// The laws a model file names, ready for the state equation.
#[derive(Debug, Clone)]
pub struct OpenSimLaws {
    pub muscles: Vec<MuscleLaw>,
    contact: Option<ContactSpec>,
    contact_k: f64,
    radii: Vec<f64>,
    ligaments: Vec<crate::model::LigamentSpec>,
}

/// The model asks for a law leap does not have.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{0}")]
pub struct UnsupportedLaw(pub String);

impl OpenSimLaws {
    pub fn new(model: &Model) -> Result<Self, UnsupportedLaw> {
        Ok(OpenSimLaws {
            muscles: model
                .muscles
                .iter()
                .map(|m| match model.muscle_model {
                    MuscleModel::Thelen2003Muscle => MuscleLaw::Thelen(Thelen::new(&m.spec)),
                    MuscleModel::DeGrooteFregly2016Muscle => {
                        MuscleLaw::DeGroote(DeGroote::new(&m.spec))
                    }
                })
                .collect(),
            contact: model.contact.as_ref().map(|c| c.spec.clone()),
            contact_k: model
                .contact
                .as_ref()
                .map(|c| hertz_k(c.spec.stiffness))
                .unwrap_or(0.0),
            radii: model
                .contact
                .as_ref()
                .map(|c| c.spheres.iter().map(|s| s.radius).collect())
                .unwrap_or_default(),
            ligaments: model.ligaments.iter().map(|l| l.spec.clone()).collect(),
        })
    }
}

/// `r`, or the error that names what turned non-finite.
pub(crate) fn finite_rates<S: Scalar>(
    r: MuscleRates<S>,
    a: S,
    lm: S,
    lmt: S,
) -> Result<MuscleRates<S>, String> {
    if !r.fiber_velocity.re().is_finite() || !r.tendon_force.re().is_finite() {
        return Err(format!(
            "non-finite fibre velocity (or force balance) or tendon force (a = {}, l_M = {}, l_MT = {})",
            crate::io::readable(a.re()),
            crate::io::readable(lm.re()),
            crate::io::readable(lmt.re())
        ));
    }
    Ok(r)
}

/// OpenSim's laws with each muscle's fibre velocity replaced by its force
/// balance at a given normalised fibre velocity (implicit fibre dynamics):
/// `vn[slot[m]]` for model muscle m.
pub struct BalanceLaws<'a, S> {
    pub laws: &'a OpenSimLaws,
    pub vn: &'a [S],
    pub slot: &'a [usize],
}

impl<S: Scalar> ForceLaws<S> for BalanceLaws<'_, S>
where
    OpenSimLaws: ForceLaws<S>,
{
    fn muscle(
        &self,
        m: usize,
        a: S,
        lm: S,
        lmt: S,
        _vmt: S,
        u: S,
    ) -> Result<MuscleRates<S>, String> {
        let vn = self
            .slot
            .get(m)
            .and_then(|&k| self.vn.get(k))
            .copied()
            .ok_or_else(|| format!("muscle {m} has no fibre velocity among the inputs"))?;
        let r = self.laws.muscles[m].balance_rates(a, lm, lmt, u, vn);
        finite_rates(r, a, lm, lmt)
    }
    fn sphere(&self, k: usize, p: [S; 3], v: [S; 3]) -> ([S; 3], [S; 3]) {
        self.laws.sphere(k, p, v)
    }
    fn ligament(&self, l: usize, q: S, qd: S) -> S {
        self.laws.ligament(l, q, qd)
    }
}

/// OpenSim's laws owned, with settable normalised fibre velocities: while
/// `vn` is empty, [`OpenSimLaws`]' own; while it holds one velocity per
/// carried muscle, each fibre-length rate is that muscle's force balance
/// ([`BalanceLaws`]). The laws of [`crate::ocp::SimbodyRates`]' force
/// element, which outlives any borrowed velocities.
pub struct SettableBalanceLaws {
    pub laws: OpenSimLaws,
    pub slot: Vec<usize>,
    pub vn: std::sync::Mutex<Vec<f64>>,
}

impl ForceLaws<f64> for SettableBalanceLaws {
    fn muscle(
        &self,
        m: usize,
        a: f64,
        lm: f64,
        lmt: f64,
        vmt: f64,
        u: f64,
    ) -> Result<MuscleRates<f64>, String> {
        let vn = self
            .vn
            .lock()
            .map_err(|_| "fibre velocity lock poisoned".to_string())?;
        if vn.is_empty() {
            self.laws.muscle(m, a, lm, lmt, vmt, u)
        } else {
            let balance = BalanceLaws {
                laws: &self.laws,
                vn: &vn,
                slot: &self.slot,
            };
            balance.muscle(m, a, lm, lmt, vmt, u)
        }
    }
    fn sphere(&self, k: usize, p: [f64; 3], v: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        self.laws.sphere(k, p, v)
    }
    fn ligament(&self, l: usize, q: f64, qd: f64) -> f64 {
        self.laws.ligament(l, q, qd)
    }
}

impl OpenSimLaws {
    /// Muscle `m`'s rates as its law gives them, possibly non-finite (an
    /// explicit fibre velocity that does not exist: De Groote's inverted
    /// force–velocity curve overflows where no fibre speed balances the
    /// tendon force); [`ForceLaws::muscle`] refuses those.
    pub fn raw_muscle_rates<S: Scalar>(
        &self,
        m: usize,
        a: S,
        lm: S,
        lmt: S,
        vmt: S,
        u: S,
    ) -> MuscleRates<S> {
        match &self.muscles[m] {
            MuscleLaw::Thelen(t) => t.rates(a, lm, lmt, u),
            law => {
                let info = law.calc(a, lm, lmt, vmt, u);
                MuscleRates {
                    tendon_force: info.tendon_force,
                    fiber_velocity: info.fiber_velocity,
                    activation_rate: info.activation_rate,
                }
            }
        }
    }
}

impl<S: Scalar> ForceLaws<S> for OpenSimLaws {
    fn muscle(
        &self,
        m: usize,
        a: S,
        lm: S,
        lmt: S,
        vmt: S,
        u: S,
    ) -> Result<MuscleRates<S>, String> {
        finite_rates(self.raw_muscle_rates(m, a, lm, lmt, vmt, u), a, lm, lmt)
    }
    fn sphere(&self, k: usize, p: [S; 3], v: [S; 3]) -> ([S; 3], [S; 3]) {
        match &self.contact {
            Some(spec) => sphere_ground_force_k(spec, self.contact_k, self.radii[k], p, v),
            None => ([S::zero(); 3], p),
        }
    }
    fn ligament(&self, l: usize, q: S, qd: S) -> S {
        passive_torque(&self.ligaments[l], q, qd)
    }
}
