//! The Simbody backend: the only module that touches the C++ bridge.
//!
//! [`SimbodyModel`] builds a Simbody `MultibodySystem` from a
//! [`SystemSpec`] (Planar, Pin, FunctionBased and Weld mobilizers; the
//! translating knee as `MobilizedBody::FunctionBased` with OpenSim's
//! `SimmSpline`) and answers the same questions as [`crate::multibody`]. All
//! vectors are in leap's coordinate order; the permutation to Simbody's q
//! order happens here. Every C++ exception becomes a [`SimbodyError`].
//!
//! Simbody's `System` is not safe to share between threads (see
//! the team's `shared/reference/simbody-bridge-notes.md` §7, outside the
//! repository): a `SimbodyModel` is `Send`
//! but not `Sync`; build one per thread.

use crate::model::{Mobilizer, Model, SystemSpec};

#[cxx::bridge(namespace = "leap")]
mod ffi {
    /// Counters of one integration.
    #[derive(Debug, Clone, Copy, Default)]
    struct IntegratorStats {
        steps_taken: i32,
        steps_attempted: i32,
        realizations: i32,
        error_test_failures: i32,
        final_time: f64,
    }

    extern "Rust" {
        type ForceCallback;
        fn calc_forces(
            self: &mut ForceCallback,
            ctx: Pin<&mut ForceCtx>,
            t: f64,
            q: &[f64],
            u: &[f64],
            z: &[f64],
            zdot: &mut [f64],
        ) -> Result<()>;
    }

    unsafe extern "C++" {
        include!("leap/cpp/leap_simbody.h");

        type SimbodySystem;
        type ForceCtx;

        fn station_position(
            self: &ForceCtx,
            body: i32,
            point: &[f64],
            out: &mut [f64],
        ) -> Result<()>;
        fn station_velocity(
            self: &ForceCtx,
            body: i32,
            point: &[f64],
            out: &mut [f64],
        ) -> Result<()>;
        fn express_in_ground(self: &ForceCtx, body: i32, v: &[f64], out: &mut [f64]) -> Result<()>;
        fn express_in_body(self: &ForceCtx, body: i32, v: &[f64], out: &mut [f64]) -> Result<()>;
        fn add_station_force(
            self: Pin<&mut ForceCtx>,
            body: i32,
            point: &[f64],
            force: &[f64],
        ) -> Result<()>;
        fn add_mobility_force(self: Pin<&mut ForceCtx>, u_index: i32, force: f64) -> Result<()>;

        fn add_rust_force(
            self: Pin<&mut SimbodySystem>,
            callback: Box<ForceCallback>,
            nz: i32,
        ) -> Result<()>;
        fn set_z(self: Pin<&mut SimbodySystem>, z: &[f64]) -> Result<()>;
        fn get_z(self: &SimbodySystem, z: &mut [f64]) -> Result<()>;
        fn calc_zdot(self: Pin<&mut SimbodySystem>, zdot: &mut [f64]) -> Result<()>;

        fn new_simbody_system() -> UniquePtr<SimbodySystem>;
        #[allow(clippy::too_many_arguments)]
        fn add_body(
            self: Pin<&mut SimbodySystem>,
            parent: i32,
            kind: i32,
            location: &[f64],
            mass: f64,
            mass_center: &[f64],
            inertia: &[f64],
            spline_x: &[f64],
            spline_y: &[f64],
        ) -> Result<i32>;
        fn finalize(self: Pin<&mut SimbodySystem>, gravity: &[f64]) -> Result<()>;
        fn nq(self: &SimbodySystem) -> Result<i32>;
        fn first_q_index(self: &SimbodySystem, body: i32) -> Result<i32>;
        fn set_state(self: Pin<&mut SimbodySystem>, t: f64, q: &[f64], u: &[f64]) -> Result<()>;
        fn get_state(self: &SimbodySystem, q: &mut [f64], u: &mut [f64]) -> Result<()>;
        fn time(self: &SimbodySystem) -> f64;
        fn calc_mass_matrix(self: Pin<&mut SimbodySystem>, m: &mut [f64]) -> Result<()>;
        fn calc_bias(self: Pin<&mut SimbodySystem>, bias: &mut [f64]) -> Result<()>;
        fn set_applied_forces(
            self: Pin<&mut SimbodySystem>,
            tau: &[f64],
            bodies: &[i32],
            points: &[f64],
            forces: &[f64],
        ) -> Result<()>;
        fn calc_udot(self: Pin<&mut SimbodySystem>, udot: &mut [f64]) -> Result<()>;
        fn station_position(
            self: Pin<&mut SimbodySystem>,
            body: i32,
            point: &[f64],
            out: &mut [f64],
        ) -> Result<()>;
        fn station_velocity(
            self: Pin<&mut SimbodySystem>,
            body: i32,
            point: &[f64],
            out: &mut [f64],
        ) -> Result<()>;
        fn com_position(self: Pin<&mut SimbodySystem>, out: &mut [f64]) -> Result<()>;
        fn com_velocity(self: Pin<&mut SimbodySystem>, out: &mut [f64]) -> Result<()>;
        fn com_acceleration(self: Pin<&mut SimbodySystem>, out: &mut [f64]) -> Result<()>;
        fn total_mass(self: Pin<&mut SimbodySystem>) -> Result<f64>;
        fn energy(self: Pin<&mut SimbodySystem>) -> Result<f64>;
        fn integrate(
            self: Pin<&mut SimbodySystem>,
            method: i32,
            accuracy: f64,
            t_final: f64,
        ) -> Result<IntegratorStats>;
        fn integration_start(
            self: Pin<&mut SimbodySystem>,
            method: i32,
            accuracy: f64,
            min_step: f64,
            max_step: f64,
            max_steps: i32,
        ) -> Result<()>;
        fn integration_step_to(self: Pin<&mut SimbodySystem>, t: f64) -> Result<IntegratorStats>;
        fn throw_for_test(self: Pin<&mut SimbodySystem>, kind: i32) -> Result<()>;
    }
}

pub use ffi::IntegratorStats;

// SAFETY: a SimbodySystem owns its Simbody objects and is used from one
// thread at a time (`&mut` for every mutating call); it is not `Sync`.
unsafe impl Send for ffi::SimbodySystem {}

/// A failure inside Simbody or the facade, with Simbody's own message.
#[derive(Debug, Clone, thiserror::Error)]
pub enum SimbodyError {
    #[error("Simbody: {0}")]
    Simbody(String),
    #[error("{0}")]
    Input(String),
}

impl From<cxx::Exception> for SimbodyError {
    fn from(e: cxx::Exception) -> Self {
        SimbodyError::Simbody(e.what().to_string())
    }
}

/// Simbody's integrators, as OpenSim offers them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimbodyIntegrator {
    RungeKuttaMerson,
    RungeKuttaFeldberg,
    RungeKutta3,
    CPodes,
    /// Fixed step; the step is the `accuracy` argument.
    ExplicitEuler,
}

impl SimbodyIntegrator {
    fn code(self) -> i32 {
        match self {
            SimbodyIntegrator::RungeKuttaMerson => 0,
            SimbodyIntegrator::RungeKuttaFeldberg => 1,
            SimbodyIntegrator::RungeKutta3 => 2,
            SimbodyIntegrator::CPodes => 3,
            SimbodyIntegrator::ExplicitEuler => 4,
        }
    }
}

/// The Rust side of Simbody's custom force element: a closure computing
/// forces and auxiliary-state derivatives from (t, q, u, z). Errors and
/// panics become C++ exceptions (never unwinding through C++); the last
/// message is kept, since Simbody's integrators swallow exceptions.
pub struct ForceCallback {
    f: Box<ForceFn>,
    last_error: std::sync::Arc<std::sync::Mutex<Option<(f64, String)>>>,
    calls: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

/// The signature of a Rust force element: context, t, q, u, z (Simbody's
/// order) and the z derivatives to write.
pub type ForceFn = dyn FnMut(&mut ForceContext<'_>, f64, &[f64], &[f64], &[f64], &mut [f64]) -> Result<(), String>
    + Send;

impl ForceCallback {
    fn calc_forces(
        &mut self,
        ctx: std::pin::Pin<&mut ffi::ForceCtx>,
        t: f64,
        q: &[f64],
        u: &[f64],
        z: &[f64],
        zdot: &mut [f64],
    ) -> Result<(), String> {
        self.calls
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let mut context = ForceContext { ctx };
        let f = &mut self.f;
        let r = match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            f(&mut context, t, q, u, z, zdot)
        })) {
            Ok(r) => r,
            Err(p) => {
                let what = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_else(|| "unknown panic".into());
                Err(format!("panic in Rust force element: {what}"))
            }
        };
        if let Err(e) = &r {
            if let Ok(mut g) = self.last_error.lock() {
                *g = Some((t, e.clone()));
            }
        }
        r
    }
}

/// Point kinematics and force application inside a force callback (Simbody
/// body indices: 0 is ground, 1.. in creation order).
pub struct ForceContext<'a> {
    ctx: std::pin::Pin<&'a mut ffi::ForceCtx>,
}

impl ForceContext<'_> {
    pub fn station_position(&self, body: i32, point: [f64; 3]) -> Result<[f64; 3], String> {
        let mut out = [0.0; 3];
        self.ctx
            .station_position(body, &point, &mut out)
            .map_err(|e| e.what().to_string())?;
        Ok(out)
    }
    pub fn station_velocity(&self, body: i32, point: [f64; 3]) -> Result<[f64; 3], String> {
        let mut out = [0.0; 3];
        self.ctx
            .station_velocity(body, &point, &mut out)
            .map_err(|e| e.what().to_string())?;
        Ok(out)
    }
    pub fn express_in_ground(&self, body: i32, v: [f64; 3]) -> Result<[f64; 3], String> {
        let mut out = [0.0; 3];
        self.ctx
            .express_in_ground(body, &v, &mut out)
            .map_err(|e| e.what().to_string())?;
        Ok(out)
    }
    pub fn express_in_body(&self, body: i32, v: [f64; 3]) -> Result<[f64; 3], String> {
        let mut out = [0.0; 3];
        self.ctx
            .express_in_body(body, &v, &mut out)
            .map_err(|e| e.what().to_string())?;
        Ok(out)
    }
    pub fn add_station_force(
        &mut self,
        body: i32,
        point: [f64; 3],
        force: [f64; 3],
    ) -> Result<(), String> {
        self.ctx
            .as_mut()
            .add_station_force(body, &point, &force)
            .map_err(|e| e.what().to_string())
    }
    pub fn add_mobility_force(&mut self, u_index: i32, force: f64) -> Result<(), String> {
        self.ctx
            .as_mut()
            .add_mobility_force(u_index, force)
            .map_err(|e| e.what().to_string())
    }
}

/// A model built in Simbody.
pub struct SimbodyModel {
    sys: cxx::UniquePtr<ffi::SimbodySystem>,
    n: usize,
    /// Simbody q index of each leap coordinate.
    perm: Vec<usize>,
    /// Simbody mobilized-body index of each model body.
    mobod_of_model_body: Vec<i32>,
    q_sb: Vec<f64>,
    u_sb: Vec<f64>,
    tmp: Vec<f64>,
    bodies_buf: Vec<i32>,
    points_buf: Vec<f64>,
    forces_buf: Vec<f64>,
    nz: usize,
    last_error: std::sync::Arc<std::sync::Mutex<Option<(f64, String)>>>,
    callback_calls: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

impl std::fmt::Debug for SimbodyModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimbodyModel").field("nq", &self.n).finish()
    }
}

impl SimbodyModel {
    /// Build the Simbody system of `system` (from `model`).
    pub fn new(model: &Model, system: &SystemSpec) -> Result<Self, SimbodyError> {
        Self::with_force(model, system, None)
    }

    /// Build the system with a Rust force element with `nz` auxiliary states.
    /// The closure sees q and u in Simbody's order: use [`Self::simbody_q_index`]
    /// (computed by [`simbody_q_order`] before building) to map.
    pub fn with_force(
        model: &Model,
        system: &SystemSpec,
        force: Option<(Box<ForceFn>, usize)>,
    ) -> Result<Self, SimbodyError> {
        let mut sys = ffi::new_simbody_system();
        let mut q_slots: Vec<(i32, Vec<usize>)> = Vec::new();
        for (k, sb) in system.bodies.iter().enumerate() {
            let b = &model.bodies[sb.body];
            let parent = sb.parent.map(|p| p as i32 + 1).unwrap_or(0);
            let (kind, sx, sy, qs) = match &sb.mobilizer {
                Mobilizer::Planar { q } => (0, Vec::new(), Vec::new(), q.to_vec()),
                Mobilizer::Pin { q } => (1, Vec::new(), Vec::new(), vec![*q]),
                Mobilizer::TranslatingHinge {
                    q,
                    translation_x,
                    translation_y,
                } => (
                    2,
                    translation_x.coefficient_blocks(),
                    translation_y.coefficient_blocks(),
                    vec![*q],
                ),
                Mobilizer::Weld => (3, Vec::new(), Vec::new(), Vec::new()),
            };
            let idx = sys.pin_mut().add_body(
                parent,
                kind,
                &sb.location,
                b.mass,
                &b.mass_center,
                &b.inertia,
                &sx,
                &sy,
            )?;
            debug_assert_eq!(idx as usize, k + 1);
            if !qs.is_empty() {
                q_slots.push((idx, qs));
            }
        }
        let last_error = std::sync::Arc::new(std::sync::Mutex::new(None));
        let callback_calls = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
        let mut nz = 0;
        if let Some((f, n)) = force {
            nz = n;
            let cb = Box::new(ForceCallback {
                f,
                last_error: last_error.clone(),
                calls: callback_calls.clone(),
            });
            sys.pin_mut().add_rust_force(cb, n as i32)?;
        }
        sys.pin_mut().finalize(&model.gravity)?;
        let n = system.nq();
        let nq_sb = sys.nq()? as usize;
        if nq_sb != n {
            return Err(SimbodyError::Input(format!(
                "Simbody built {nq_sb} coordinates, leap expects {n}"
            )));
        }
        let mut perm = vec![usize::MAX; n];
        for (body, qs) in &q_slots {
            let first = sys.first_q_index(*body)?;
            for (j, &q) in qs.iter().enumerate() {
                perm[q] = first as usize + j;
            }
        }
        if perm.contains(&usize::MAX) {
            return Err(SimbodyError::Input(
                "a coordinate has no Simbody mobility".into(),
            ));
        }
        if perm != simbody_q_order(system) {
            return Err(SimbodyError::Input(format!(
                "Simbody ordered the coordinates {perm:?}, leap predicted {:?}",
                simbody_q_order(system)
            )));
        }
        let mobod_of_model_body = system
            .system_body_of
            .iter()
            .map(|&s| s as i32 + 1)
            .collect();
        Ok(SimbodyModel {
            sys,
            n,
            perm,
            mobod_of_model_body,
            q_sb: vec![0.0; n],
            u_sb: vec![0.0; n],
            tmp: vec![0.0; n * n],
            bodies_buf: Vec::new(),
            points_buf: Vec::new(),
            forces_buf: Vec::new(),
            nz,
            last_error,
            callback_calls,
        })
    }

    /// Simbody's q index of each leap coordinate.
    pub fn simbody_q_index(&self) -> &[usize] {
        &self.perm
    }

    /// Simbody mobilized-body index of each model body.
    pub fn mobilized_body_of_model_body(&self) -> &[i32] {
        &self.mobod_of_model_body
    }

    /// Number of auxiliary states of the Rust force element.
    pub fn nz(&self) -> usize {
        self.nz
    }

    /// Set the auxiliary states.
    pub fn set_z(&mut self, z: &[f64]) -> Result<(), SimbodyError> {
        self.check("z", z.len(), self.nz)?;
        Ok(self.sys.pin_mut().set_z(z)?)
    }

    /// The auxiliary states.
    pub fn z(&self, z: &mut [f64]) -> Result<(), SimbodyError> {
        self.check("z", z.len(), self.nz)?;
        Ok(self.sys.get_z(z)?)
    }

    /// The auxiliary states' derivatives at the current state.
    pub fn zdot(&mut self, zdot: &mut [f64]) -> Result<(), SimbodyError> {
        self.check("zdot", zdot.len(), self.nz)?;
        self.take_force_error();
        self.sys
            .pin_mut()
            .calc_zdot(zdot)
            .map_err(|e| self.with_callback_error(e))
    }

    /// The last error the Rust force element reported, if any (taken): the
    /// time and the reason.
    pub fn take_force_error(&self) -> Option<(f64, String)> {
        self.last_error.lock().ok().and_then(|mut g| g.take())
    }

    /// How often Simbody called the Rust force element.
    pub fn force_calls(&self) -> u64 {
        self.callback_calls
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    fn with_callback_error(&self, e: cxx::Exception) -> SimbodyError {
        match self.take_force_error() {
            // Simbody's text only wraps the force element's reason ("SimTK
            // Exception thrown at AbstractIntegratorRep.cpp:428: Integrator
            // step failed at time … apparently because: <reason>"): say it once.
            Some((t, rust)) if e.what().contains(rust.as_str()) => SimbodyError::Simbody(format!(
                "the muscle, contact and ligament forces (leap's force element) failed at t = {t:.6} s: {rust}"
            )),
            // Simbody's own reason (a step that collapsed after the force
            // element's failures, a step cap), and the last such failure in
            // this call.
            Some((t, rust)) => SimbodyError::Simbody(format!(
                "{} (the last failure of the muscle, contact and ligament forces in this call, at t = {t:.6} s: {rust})",
                e.what()
            )),
            None => e.into(),
        }
    }

    /// Number of generalized coordinates.
    pub fn nq(&self) -> usize {
        self.n
    }

    fn check(&self, what: &str, len: usize, want: usize) -> Result<(), SimbodyError> {
        if len != want {
            return Err(SimbodyError::Input(format!(
                "{what}: wrong length {len} (expected {want})"
            )));
        }
        Ok(())
    }

    /// Set time, q and q̇ (leap order).
    pub fn set_state(&mut self, t: f64, q: &[f64], u: &[f64]) -> Result<(), SimbodyError> {
        self.check("q", q.len(), self.n)?;
        self.check("u", u.len(), self.n)?;
        for k in 0..self.n {
            self.q_sb[self.perm[k]] = q[k];
            self.u_sb[self.perm[k]] = u[k];
        }
        self.sys.pin_mut().set_state(t, &self.q_sb, &self.u_sb)?;
        Ok(())
    }

    /// Current time, q and q̇ (leap order).
    pub fn state(&mut self, q: &mut [f64], u: &mut [f64]) -> Result<f64, SimbodyError> {
        self.check("q", q.len(), self.n)?;
        self.check("u", u.len(), self.n)?;
        self.sys.get_state(&mut self.q_sb, &mut self.u_sb)?;
        for k in 0..self.n {
            q[k] = self.q_sb[self.perm[k]];
            u[k] = self.u_sb[self.perm[k]];
        }
        Ok(self.sys.time())
    }

    /// Mass matrix (row-major, leap order).
    pub fn mass_matrix(&mut self, out: &mut [f64]) -> Result<(), SimbodyError> {
        let n = self.n;
        self.check("mass matrix", out.len(), n * n)?;
        self.sys.pin_mut().calc_mass_matrix(&mut self.tmp)?;
        for i in 0..n {
            for j in 0..n {
                out[i * n + j] = self.tmp[self.perm[i] * n + self.perm[j]];
            }
        }
        Ok(())
    }

    /// Bias forces C(q, q̇)q̇ − g(q) (leap order).
    pub fn bias(&mut self, out: &mut [f64]) -> Result<(), SimbodyError> {
        self.check("bias", out.len(), self.n)?;
        self.sys.pin_mut().calc_bias(&mut self.tmp[..self.n])?;
        for k in 0..self.n {
            out[k] = self.tmp[self.perm[k]];
        }
        Ok(())
    }

    /// Apply generalized forces `tau` (leap order) and point forces
    /// `(model body, point in body frame, force in ground)`; they stay applied
    /// for later evaluations and integration.
    pub fn set_applied_forces(
        &mut self,
        tau: &[f64],
        point_forces: &[(usize, [f64; 3], [f64; 3])],
    ) -> Result<(), SimbodyError> {
        self.check("tau", tau.len(), self.n)?;
        for k in 0..self.n {
            self.u_sb[self.perm[k]] = tau[k];
        }
        self.bodies_buf.clear();
        self.points_buf.clear();
        self.forces_buf.clear();
        for (body, p, f) in point_forces {
            let mobod = *self
                .mobod_of_model_body
                .get(*body)
                .ok_or_else(|| SimbodyError::Input(format!("no model body {body}")))?;
            self.bodies_buf.push(mobod);
            self.points_buf.extend_from_slice(p);
            self.forces_buf.extend_from_slice(f);
        }
        let r = self.sys.pin_mut().set_applied_forces(
            &self.u_sb,
            &self.bodies_buf,
            &self.points_buf,
            &self.forces_buf,
        );
        // u_sb was borrowed as scratch: restore the state's speeds.
        self.sys.get_state(&mut self.q_sb, &mut self.u_sb)?;
        r.map_err(Into::into)
    }

    /// Accelerations q̈ under the applied forces (leap order).
    pub fn accelerations(&mut self, qdd: &mut [f64]) -> Result<(), SimbodyError> {
        self.check("qdd", qdd.len(), self.n)?;
        let n = self.n;
        self.take_force_error();
        if let Err(e) = self.sys.pin_mut().calc_udot(&mut self.tmp[..n]) {
            return Err(self.with_callback_error(e));
        }
        for k in 0..self.n {
            qdd[k] = self.tmp[self.perm[k]];
        }
        Ok(())
    }

    /// Position in ground of a point fixed on a model body.
    pub fn station_position(
        &mut self,
        body: usize,
        point: [f64; 3],
    ) -> Result<[f64; 3], SimbodyError> {
        let mobod = self.mobod(body)?;
        let mut out = [0.0; 3];
        self.sys
            .pin_mut()
            .station_position(mobod, &point, &mut out)?;
        Ok(out)
    }

    /// Velocity in ground of a point fixed on a model body.
    pub fn station_velocity(
        &mut self,
        body: usize,
        point: [f64; 3],
    ) -> Result<[f64; 3], SimbodyError> {
        let mobod = self.mobod(body)?;
        let mut out = [0.0; 3];
        self.sys
            .pin_mut()
            .station_velocity(mobod, &point, &mut out)?;
        Ok(out)
    }

    fn mobod(&self, body: usize) -> Result<i32, SimbodyError> {
        self.mobod_of_model_body
            .get(body)
            .copied()
            .ok_or_else(|| SimbodyError::Input(format!("no model body {body}")))
    }

    /// Whole-body centre of mass position.
    pub fn com_position(&mut self) -> Result<[f64; 3], SimbodyError> {
        let mut out = [0.0; 3];
        self.sys.pin_mut().com_position(&mut out)?;
        Ok(out)
    }

    /// Whole-body centre of mass velocity.
    pub fn com_velocity(&mut self) -> Result<[f64; 3], SimbodyError> {
        let mut out = [0.0; 3];
        self.sys.pin_mut().com_velocity(&mut out)?;
        Ok(out)
    }

    /// Whole-body centre of mass acceleration under the applied forces.
    pub fn com_acceleration(&mut self) -> Result<[f64; 3], SimbodyError> {
        let mut out = [0.0; 3];
        self.sys.pin_mut().com_acceleration(&mut out)?;
        Ok(out)
    }

    /// Total mass (kg).
    pub fn total_mass(&mut self) -> Result<f64, SimbodyError> {
        Ok(self.sys.pin_mut().total_mass()?)
    }

    /// Kinetic plus potential energy (J).
    pub fn energy(&mut self) -> Result<f64, SimbodyError> {
        Ok(self.sys.pin_mut().energy()?)
    }

    /// Integrate to `t_final` with the applied forces held constant.
    pub fn integrate(
        &mut self,
        integrator: SimbodyIntegrator,
        accuracy: f64,
        t_final: f64,
    ) -> Result<IntegratorStats, SimbodyError> {
        self.take_force_error();
        match self
            .sys
            .pin_mut()
            .integrate(integrator.code(), accuracy, t_final)
        {
            Ok(s) => Ok(s),
            Err(e) => Err(self.with_callback_error(e)),
        }
    }

    /// Start a persistent integration from the current state (and applied
    /// forces); `min_step`/`max_step` ≤ 0 keep Simbody's defaults;
    /// `max_steps` > 0 caps the steps attempted from here, beyond which
    /// [`Self::integration_step_to`] fails.
    pub fn integration_start(
        &mut self,
        integrator: SimbodyIntegrator,
        accuracy: f64,
        min_step: f64,
        max_step: f64,
        max_steps: i32,
    ) -> Result<(), SimbodyError> {
        self.take_force_error();
        self.sys
            .pin_mut()
            .integration_start(integrator.code(), accuracy, min_step, max_step, max_steps)
            .map_err(|e| self.with_callback_error(e))
    }

    /// Advance the persistent integration to `t`; the model's state is then
    /// the integrator's. Counters are cumulative since the start.
    pub fn integration_step_to(&mut self, t: f64) -> Result<IntegratorStats, SimbodyError> {
        self.take_force_error();
        match self.sys.pin_mut().integration_step_to(t) {
            Ok(s) => Ok(s),
            Err(e) => Err(self.with_callback_error(e)),
        }
    }

    /// Make the facade throw (kind 0: a Simbody stage error; 1: a SimTK
    /// exception; other: `std::runtime_error`), to test error propagation.
    pub fn throw_for_test(&mut self, kind: i32) -> Result<(), SimbodyError> {
        Ok(self.sys.pin_mut().throw_for_test(kind)?)
    }
}

/// Simbody's q index of each leap coordinate of `system`: mobilizers take
/// their q's in body creation order (Planar: rotation, x, y).
pub fn simbody_q_order(system: &SystemSpec) -> Vec<usize> {
    let mut perm = vec![usize::MAX; system.nq()];
    let mut next = 0;
    for sb in &system.bodies {
        let qs: Vec<usize> = match &sb.mobilizer {
            Mobilizer::Planar { q } => q.to_vec(),
            Mobilizer::Pin { q } | Mobilizer::TranslatingHinge { q, .. } => vec![*q],
            Mobilizer::Weld => vec![],
        };
        for q in qs {
            perm[q] = next;
            next += 1;
        }
    }
    perm
}

/// Point kinematics at the state Simbody is realizing, seen through model
/// bodies and model coordinates (for force elements inside a callback).
/// The first FFI error is kept in `error` and NaN returned.
pub struct SimbodyKinematics<'c, 'a> {
    pub ctx: &'c ForceContext<'a>,
    /// Simbody mobilized body of each model body.
    pub mobod: &'c [i32],
    /// Simbody q index of each model coordinate.
    pub q_index: &'c [usize],
    pub q: &'c [f64],
    pub u: &'c [f64],
    pub error: std::cell::RefCell<Option<String>>,
}

impl SimbodyKinematics<'_, '_> {
    fn keep(&self, r: Result<[f64; 3], String>) -> [f64; 3] {
        match r {
            Ok(v) => v,
            Err(e) => {
                self.error.borrow_mut().get_or_insert(e);
                [f64::NAN; 3]
            }
        }
    }
}

impl crate::path::BodyKinematics<f64> for SimbodyKinematics<'_, '_> {
    fn position(&self, body: usize, loc: [f64; 3]) -> [f64; 3] {
        self.keep(self.ctx.station_position(self.mobod[body], loc))
    }
    fn velocity(&self, body: usize, loc: [f64; 3]) -> [f64; 3] {
        self.keep(self.ctx.station_velocity(self.mobod[body], loc))
    }
    fn to_ground(&self, body: usize, v: [f64; 3]) -> [f64; 3] {
        self.keep(self.ctx.express_in_ground(self.mobod[body], v))
    }
    fn to_body(&self, body: usize, v: [f64; 3]) -> [f64; 3] {
        self.keep(self.ctx.express_in_body(self.mobod[body], v))
    }
    fn coordinate(&self, coordinate: usize) -> (f64, f64) {
        let k = self.q_index[coordinate];
        (self.q[k], self.u[k])
    }
}

/// Forces collected during a callback, then handed to Simbody in one go
/// (buffers keep their capacity between calls).
#[derive(Debug, Default, Clone)]
pub struct ForceBuffer {
    pub points: Vec<(usize, [f64; 3], [f64; 3])>,
    pub generalized: Vec<(usize, f64)>,
}

impl ForceBuffer {
    pub fn clear(&mut self) {
        self.points.clear();
        self.generalized.clear();
    }

    /// Apply the collected forces (model bodies and model coordinates).
    pub fn flush(
        &self,
        ctx: &mut ForceContext<'_>,
        mobod: &[i32],
        u_index: &[usize],
    ) -> Result<(), String> {
        for (b, p, f) in &self.points {
            ctx.add_station_force(mobod[*b], *p, *f)?;
        }
        for (c, f) in &self.generalized {
            ctx.add_mobility_force(u_index[*c] as i32, *f)?;
        }
        Ok(())
    }
}

impl crate::path::ForceSink<f64> for ForceBuffer {
    fn add_point_force(&mut self, body: usize, loc: [f64; 3], force: [f64; 3]) {
        self.points.push((body, loc, force));
    }
    fn add_generalized_force(&mut self, coordinate: usize, force: f64) {
        self.generalized.push((coordinate, force));
    }
}
