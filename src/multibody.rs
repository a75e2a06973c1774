//! Rust-native planar multibody dynamics, generic over the scalar type.
//!
//! The system of [`SystemSpec`] moves in the x-y plane: every mobilizer
//! rotates about z (and the base and the translating hinge also translate in
//! x-y), so each body's pose is an angle `θ` and an origin `p` in ground. The
//! equations of motion are those of Simbody in its explicit form,
//!
//! `M(q)·q̈ + b(q, q̇) = τ + Σ J_sᵀ F_s`,  with `b = C(q, q̇)·q̇ − g(q)`,
//!
//! assembled from each body's centre-of-mass Jacobian `J_c` and angle
//! Jacobian `J_θ` (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, §3.3:
//! `M = Σ m J_cᵀJ_c + I_zz J_θᵀJ_θ`, `b = Σ m J_cᵀ(J̇_c q̇ − g)`). Welded
//! bodies are merged into composite bodies once, at construction. Out-of-plane
//! geometry (z offsets, Ixx, Iyy, products of inertia) cannot affect planar
//! motion about z and is kept only for reporting 3D station and COM positions.
//!
//! [`Multibody`] is immutable; [`Workspace`] holds every buffer, so
//! [`Multibody::set_state`] and the calls after it allocate nothing.

use crate::model::{Mobilizer, Model, SystemSpec};
use crate::scalar::{c, Scalar};
use crate::spline::SimmSpline;

/// A 2D vector of scalars.
pub type V2<S> = [S; 2];

#[derive(Debug, Clone)]
enum Joint {
    /// Base: rotation q[0] about z, translation (q[1], q[2]) in ground.
    Planar {
        q: [usize; 3],
    },
    Pin {
        q: usize,
    },
    TranslatingHinge {
        q: usize,
        tx: SimmSpline,
        ty: SimmSpline,
    },
}

/// A composite body: a mobilized body with everything welded to it.
#[derive(Debug, Clone)]
struct CompositeBody {
    parent: Option<usize>,
    /// Joint location in the parent composite's frame (x, y).
    location: [f64; 2],
    joint: Joint,
    mass: f64,
    /// Centre of mass in the body frame (x, y).
    com: [f64; 2],
    /// Moment of inertia about z through the centre of mass (kg·m²).
    izz: f64,
    /// z of the frame origin in ground, and of the centre of mass.
    z_origin: f64,
    z_com: f64,
    /// Coordinates that move this body: the parent's, then the joint's own.
    dofs: Vec<usize>,
    /// Whether each of `dofs` rotates the body (θ = Σ of those q).
    rot: Vec<bool>,
    /// Index in `dofs` of the joint's own first coordinate.
    own_start: usize,
}

/// Immutable planar multibody model built from a [`SystemSpec`].
#[derive(Debug, Clone)]
pub struct Multibody {
    nq: usize,
    /// Largest number of coordinates that move one body.
    dmax: usize,
    gravity: [f64; 2],
    bodies: Vec<CompositeBody>,
    total_mass: f64,
    /// For each system body: (composite index, origin offset in its frame, 3D).
    frame_of: Vec<(usize, [f64; 3])>,
    /// For each model body: system body index.
    system_body_of: Vec<usize>,
    /// Model stations as (composite, location in composite frame).
    stations: Vec<(usize, [f64; 3])>,
}

/// Preallocated buffers for one evaluation thread.
#[derive(Debug, Clone)]
pub struct Workspace<S: Scalar> {
    #[allow(dead_code)]
    n: usize,
    theta: Vec<S>,
    omega: Vec<S>,
    cos: Vec<S>,
    sin: Vec<S>,
    p: Vec<V2<S>>,
    v: Vec<V2<S>>,
    /// Origin acceleration at q̈ = 0.
    a0: Vec<V2<S>>,
    /// ∂p/∂q per body, for the body's columns `dofs` (stride `dmax`).
    jp: Vec<V2<S>>,
    /// Centre-of-mass Jacobian per body (same layout) and bias acceleration.
    jc: Vec<V2<S>>,
    a0c: Vec<V2<S>>,
    c: Vec<V2<S>>,
    vc: Vec<V2<S>>,
    mass_matrix: Vec<S>,
    chol: Vec<S>,
    bias: Vec<S>,
    rhs: Vec<S>,
    q: Vec<S>,
    u: Vec<S>,
}

/// The mass matrix was not positive definite (a degenerate model or NaN state).
#[derive(Debug, Clone, thiserror::Error)]
#[error("mass matrix is not positive definite at pivot {pivot} (value {value:e}): a body's mass properties not physical or far apart in scale, or a state not finite")]
pub struct SingularMassMatrix {
    pub pivot: usize,
    pub value: f64,
}

#[inline]
fn rot<S: Scalar>(cs: S, sn: S, v: [S; 2]) -> [S; 2] {
    [cs * v[0] - sn * v[1], sn * v[0] + cs * v[1]]
}

#[inline]
fn perp<S: Scalar>(v: [S; 2]) -> [S; 2] {
    [-v[1], v[0]]
}

impl Multibody {
    /// Build from a validated model and its system.
    pub fn new(model: &Model, system: &SystemSpec) -> Self {
        let ns = system.bodies.len();
        // Composite of every system body, and offset of its frame in it.
        let mut frame_of: Vec<(usize, [f64; 3])> = Vec::with_capacity(ns);
        let mut bodies: Vec<CompositeBody> = Vec::new();
        for sb in &system.bodies {
            let (parent_comp, parent_off, parent_z) = match sb.parent {
                None => (None, [0.0; 3], 0.0),
                Some(p) => {
                    let (ci, off) = frame_of[p];
                    (Some(ci), off, bodies[ci].z_origin)
                }
            };
            let loc = [
                parent_off[0] + sb.location[0],
                parent_off[1] + sb.location[1],
                parent_off[2] + sb.location[2],
            ];
            let joint = match &sb.mobilizer {
                Mobilizer::Weld => {
                    let ci = parent_comp.expect("validated: a weld has a parent body");
                    frame_of.push((ci, loc));
                    continue;
                }
                Mobilizer::Planar { q } => Joint::Planar { q: *q },
                Mobilizer::Pin { q } => Joint::Pin { q: *q },
                Mobilizer::TranslatingHinge {
                    q,
                    translation_x,
                    translation_y,
                } => Joint::TranslatingHinge {
                    q: *q,
                    tx: translation_x.clone(),
                    ty: translation_y.clone(),
                },
            };
            let (mut dofs, mut rots) = match parent_comp {
                Some(p) => (bodies[p].dofs.clone(), bodies[p].rot.clone()),
                None => (Vec::new(), Vec::new()),
            };
            let own_start = dofs.len();
            match &joint {
                Joint::Planar { q } => {
                    dofs.extend_from_slice(q);
                    rots.extend_from_slice(&[true, false, false]);
                }
                Joint::Pin { q } | Joint::TranslatingHinge { q, .. } => {
                    dofs.push(*q);
                    rots.push(true);
                }
            }
            frame_of.push((bodies.len(), [0.0; 3]));
            bodies.push(CompositeBody {
                dofs,
                rot: rots,
                own_start,
                parent: parent_comp,
                location: [loc[0], loc[1]],
                joint,
                mass: 0.0,
                com: [0.0; 2],
                izz: 0.0,
                z_origin: parent_z + loc[2],
                z_com: 0.0,
            });
        }
        // Mass properties: first centres of mass, then inertia about them.
        let mut first = vec![[0.0f64; 3]; bodies.len()];
        for (k, sb) in system.bodies.iter().enumerate() {
            let (ci, off) = frame_of[k];
            let b = &model.bodies[sb.body];
            for d in 0..3 {
                first[ci][d] += b.mass * (off[d] + b.mass_center[d]);
            }
            bodies[ci].mass += b.mass;
        }
        for (ci, cb) in bodies.iter_mut().enumerate() {
            cb.com = [first[ci][0] / cb.mass, first[ci][1] / cb.mass];
            cb.z_com = cb.z_origin + first[ci][2] / cb.mass;
        }
        for (k, sb) in system.bodies.iter().enumerate() {
            let (ci, off) = frame_of[k];
            let b = &model.bodies[sb.body];
            let dx = off[0] + b.mass_center[0] - bodies[ci].com[0];
            let dy = off[1] + b.mass_center[1] - bodies[ci].com[1];
            bodies[ci].izz += b.inertia[2] + b.mass * (dx * dx + dy * dy);
        }
        let stations = model
            .stations
            .iter()
            .map(|s| {
                let (ci, off) = frame_of[system.system_body_of[s.body]];
                (
                    ci,
                    [
                        off[0] + s.location[0],
                        off[1] + s.location[1],
                        off[2] + s.location[2],
                    ],
                )
            })
            .collect();
        let total_mass = bodies.iter().map(|b| b.mass).sum();
        let dmax = bodies.iter().map(|b| b.dofs.len()).max().unwrap_or(0);
        Multibody {
            nq: system.nq(),
            dmax,
            gravity: [model.gravity[0], model.gravity[1]],
            bodies,
            total_mass,
            frame_of,
            system_body_of: system.system_body_of.clone(),
            stations,
        }
    }

    /// Number of generalized coordinates (= speeds).
    pub fn nq(&self) -> usize {
        self.nq
    }

    /// Number of composite (mobilized) bodies.
    pub fn num_composite_bodies(&self) -> usize {
        self.bodies.len()
    }

    /// Total mass (kg).
    pub fn total_mass(&self) -> f64 {
        self.total_mass
    }

    /// A point fixed on a model body, as (composite body, location in its frame).
    pub fn body_point(&self, model_body: usize, location: [f64; 3]) -> (usize, [f64; 3]) {
        let (ci, off) = self.frame_of[self.system_body_of[model_body]];
        (
            ci,
            [
                off[0] + location[0],
                off[1] + location[1],
                off[2] + location[2],
            ],
        )
    }

    /// The model's stations as (composite body, location) pairs.
    pub fn stations(&self) -> &[(usize, [f64; 3])] {
        &self.stations
    }

    /// Buffers for evaluations with scalar type `S`.
    pub fn workspace<S: Scalar>(&self) -> Workspace<S> {
        let (n, nb) = (self.nq, self.bodies.len());
        let z = S::zero();
        Workspace {
            n,
            theta: vec![z; nb],
            omega: vec![z; nb],
            cos: vec![z; nb],
            sin: vec![z; nb],
            p: vec![[z; 2]; nb],
            v: vec![[z; 2]; nb],
            a0: vec![[z; 2]; nb],
            jp: vec![[z; 2]; nb * self.dmax],
            jc: vec![[z; 2]; nb * self.dmax],
            a0c: vec![[z; 2]; nb],
            c: vec![[z; 2]; nb],
            vc: vec![[z; 2]; nb],
            mass_matrix: vec![z; n * n],
            chol: vec![z; n * n],
            bias: vec![z; n],
            rhs: vec![z; n],
            q: vec![z; n],
            u: vec![z; n],
        }
    }

    /// Set q and q̇ and compute all position and velocity kinematics, the
    /// Jacobians, the mass matrix and the bias forces.
    pub fn set_state<S: Scalar>(&self, ws: &mut Workspace<S>, q: &[S], u: &[S]) {
        let n = self.nq;
        let dmax = self.dmax;
        debug_assert!(q.len() == n && u.len() == n);
        ws.q.copy_from_slice(q);
        ws.u.copy_from_slice(u);
        let z = S::zero();
        for (i, b) in self.bodies.iter().enumerate() {
            let o = i * dmax;
            // Parent quantities (ground: identity, at rest).
            let (th_p, om_p, cs_p, sn_p, p_p, v_p, a_p) = match b.parent {
                None => (z, z, S::one(), z, [z; 2], [z; 2], [z; 2]),
                Some(pi) => (
                    ws.theta[pi],
                    ws.omega[pi],
                    ws.cos[pi],
                    ws.sin[pi],
                    ws.p[pi],
                    ws.v[pi],
                    ws.a0[pi],
                ),
            };
            let loc: [S; 2] = [c(b.location[0]), c(b.location[1])];
            // Joint: origin offset d (ground axes), its rate and the own Jacobian columns.
            let (d, vrel, arel, qr, qd) = match &b.joint {
                Joint::Planar { q: [qr, qx, qy] } => {
                    // Translation along the parent (ground) axes, rotation about z.
                    let d = rot(cs_p, sn_p, [loc[0] + q[*qx], loc[1] + q[*qy]]);
                    let ex = rot(cs_p, sn_p, [S::one(), z]);
                    let ey = rot(cs_p, sn_p, [z, S::one()]);
                    let s0 = b.own_start;
                    ws.jp[o + s0] = [z; 2];
                    ws.jp[o + s0 + 1] = ex;
                    ws.jp[o + s0 + 2] = ey;
                    let vrel = [
                        ex[0] * u[*qx] + ey[0] * u[*qy],
                        ex[1] * u[*qx] + ey[1] * u[*qy],
                    ];
                    (d, vrel, [z; 2], q[*qr], u[*qr])
                }
                Joint::Pin { q: qi } | Joint::TranslatingHinge { q: qi, .. } => {
                    let (t, dt, ddt) = match &b.joint {
                        Joint::TranslatingHinge { tx, ty, .. } => {
                            let (x0, x1, x2) = tx.eval(q[*qi]);
                            let (y0, y1, y2) = ty.eval(q[*qi]);
                            ([x0, y0], [x1, y1], [x2, y2])
                        }
                        _ => ([z; 2], [z; 2], [z; 2]),
                    };
                    let d = rot(cs_p, sn_p, [loc[0] + t[0], loc[1] + t[1]]);
                    let rdt = rot(cs_p, sn_p, dt);
                    let rddt = rot(cs_p, sn_p, ddt);
                    ws.jp[o + b.own_start] = rdt;
                    let qd = u[*qi];
                    (
                        [d[0], d[1]],
                        [rdt[0] * qd, rdt[1] * qd],
                        [rddt[0] * qd * qd, rddt[1] * qd * qd],
                        q[*qi],
                        qd,
                    )
                }
            };
            let pd = perp(d);
            // Inherited Jacobian columns: the parent's, plus the lever arm for
            // columns that rotate the parent.
            if let Some(pi) = b.parent {
                let po = pi * dmax;
                for k in 0..b.own_start {
                    let mut j = ws.jp[po + k];
                    if b.rot[k] {
                        j[0] += pd[0];
                        j[1] += pd[1];
                    }
                    ws.jp[o + k] = j;
                }
            }
            ws.p[i] = [p_p[0] + d[0], p_p[1] + d[1]];
            ws.v[i] = [
                v_p[0] + pd[0] * om_p + vrel[0],
                v_p[1] + pd[1] * om_p + vrel[1],
            ];
            let pv = perp(vrel);
            let om2 = om_p * om_p;
            ws.a0[i] = [
                a_p[0] - d[0] * om2 + pv[0] * om_p * 2.0 + arel[0],
                a_p[1] - d[1] * om2 + pv[1] * om_p * 2.0 + arel[1],
            ];
            let th = th_p + qr;
            ws.theta[i] = th;
            ws.omega[i] = om_p + qd;
            let (sn, cs) = (th.sin(), th.cos());
            ws.cos[i] = cs;
            ws.sin[i] = sn;
            // Centre of mass.
            let s = rot(cs, sn, [c::<S>(b.com[0]), c::<S>(b.com[1])]);
            let ps = perp(s);
            let om = ws.omega[i];
            ws.c[i] = [ws.p[i][0] + s[0], ws.p[i][1] + s[1]];
            ws.vc[i] = [ws.v[i][0] + ps[0] * om, ws.v[i][1] + ps[1] * om];
            ws.a0c[i] = [ws.a0[i][0] - s[0] * om * om, ws.a0[i][1] - s[1] * om * om];
            for k in 0..b.dofs.len() {
                let j = ws.jp[o + k];
                ws.jc[o + k] = if b.rot[k] {
                    [j[0] + ps[0], j[1] + ps[1]]
                } else {
                    j
                };
            }
        }
        // Mass matrix and bias forces.
        for e in ws.mass_matrix.iter_mut() {
            *e = z;
        }
        for e in ws.bias.iter_mut() {
            *e = z;
        }
        let g = self.gravity;
        for (i, b) in self.bodies.iter().enumerate() {
            let o = i * dmax;
            let fx = (ws.a0c[i][0] - g[0]) * b.mass;
            let fy = (ws.a0c[i][1] - g[1]) * b.mass;
            let len = b.dofs.len();
            for a in 0..len {
                let ja = ws.jc[o + a];
                let da = b.dofs[a];
                ws.bias[da] += ja[0] * fx + ja[1] * fy;
                let (mx, my) = (ja[0] * b.mass, ja[1] * b.mass);
                for bb in a..len {
                    let jb = ws.jc[o + bb];
                    let mut add = mx * jb[0] + my * jb[1];
                    if b.rot[a] && b.rot[bb] {
                        add += b.izz;
                    }
                    let db = b.dofs[bb];
                    ws.mass_matrix[da * n + db] += add;
                    if da != db {
                        ws.mass_matrix[db * n + da] += add;
                    }
                }
            }
        }
    }

    /// The mass matrix M(q), row-major n×n (after [`Self::set_state`]).
    pub fn mass_matrix<'a, S: Scalar>(&self, ws: &'a Workspace<S>) -> &'a [S] {
        &ws.mass_matrix
    }

    /// The bias forces b = C(q, q̇)q̇ − g(q) (after [`Self::set_state`]).
    pub fn bias<'a, S: Scalar>(&self, ws: &'a Workspace<S>) -> &'a [S] {
        &ws.bias
    }

    /// Position of a point fixed on composite body `body` (3D, ground).
    pub fn point_position<S: Scalar>(
        &self,
        ws: &Workspace<S>,
        body: usize,
        loc: [f64; 3],
    ) -> [S; 3] {
        self.point_position_s(ws, body, [c(loc[0]), c(loc[1]), c(loc[2])])
    }

    /// Velocity of a point fixed on composite body `body` (3D, ground).
    pub fn point_velocity<S: Scalar>(
        &self,
        ws: &Workspace<S>,
        body: usize,
        loc: [f64; 3],
    ) -> [S; 3] {
        self.point_velocity_s(ws, body, [c(loc[0]), c(loc[1]), c(loc[2])])
    }

    /// [`Self::point_position`] for a location of scalar type.
    #[inline]
    pub fn point_position_s<S: Scalar>(
        &self,
        ws: &Workspace<S>,
        body: usize,
        loc: [S; 3],
    ) -> [S; 3] {
        let s = rot(ws.cos[body], ws.sin[body], [loc[0], loc[1]]);
        [
            ws.p[body][0] + s[0],
            ws.p[body][1] + s[1],
            loc[2] + self.bodies[body].z_origin,
        ]
    }

    /// [`Self::point_velocity`] for a location of scalar type.
    #[inline]
    pub fn point_velocity_s<S: Scalar>(
        &self,
        ws: &Workspace<S>,
        body: usize,
        loc: [S; 3],
    ) -> [S; 3] {
        let s = rot(ws.cos[body], ws.sin[body], [loc[0], loc[1]]);
        let ps = perp(s);
        let om = ws.omega[body];
        [
            ws.v[body][0] + ps[0] * om,
            ws.v[body][1] + ps[1] * om,
            S::zero(),
        ]
    }

    /// A vector fixed in composite body `body`, expressed in ground.
    #[inline]
    pub fn to_ground<S: Scalar>(&self, ws: &Workspace<S>, body: usize, v: [S; 3]) -> [S; 3] {
        let r = rot(ws.cos[body], ws.sin[body], [v[0], v[1]]);
        [r[0], r[1], v[2]]
    }

    /// Position (ground) of a point `loc` given in model body `body`'s
    /// frame, wherever that body sits in its composite body.
    pub fn model_point_position<S: Scalar>(
        &self,
        ws: &Workspace<S>,
        body: usize,
        loc: [f64; 3],
    ) -> [S; 3] {
        let (ci, off) = self.frame_of_model_body(body);
        self.point_position(ws, ci, [loc[0] + off[0], loc[1] + off[1], loc[2] + off[2]])
    }

    /// The composite body and frame offset of a model body.
    #[inline]
    pub fn frame_of_model_body(&self, model_body: usize) -> (usize, [f64; 3]) {
        self.frame_of[self.system_body_of[model_body]]
    }

    /// The generalized coordinates q and speeds q̇ of the current state.
    pub fn state<'a, S: Scalar>(&self, ws: &'a Workspace<S>) -> (&'a [S], &'a [S]) {
        (&ws.q, &ws.u)
    }

    /// Add the generalized force `J_pᵀ F` of a force `F` (ground frame; only
    /// x and y act on planar motion) applied at a point fixed on `body`.
    pub fn add_point_force<S: Scalar>(
        &self,
        ws: &Workspace<S>,
        body: usize,
        loc: [f64; 3],
        force: [S; 3],
        tau: &mut [S],
    ) {
        self.add_point_force_s(ws, body, [c(loc[0]), c(loc[1]), c(loc[2])], force, tau)
    }

    /// [`Self::add_point_force`] for a location of scalar type.
    #[inline]
    pub fn add_point_force_s<S: Scalar>(
        &self,
        ws: &Workspace<S>,
        body: usize,
        loc: [S; 3],
        force: [S; 3],
        tau: &mut [S],
    ) {
        let s = rot(ws.cos[body], ws.sin[body], [loc[0], loc[1]]);
        let ps = perp(s);
        let b = &self.bodies[body];
        let o = body * self.dmax;
        // Moment of the force about the body origin, carried by rotations.
        let moment = ps[0] * force[0] + ps[1] * force[1];
        for k in 0..b.dofs.len() {
            let j = ws.jp[o + k];
            let mut g = j[0] * force[0] + j[1] * force[1];
            if b.rot[k] {
                g += moment;
            }
            tau[b.dofs[k]] += g;
        }
    }

    /// Angle and angular velocity of composite body `body` about z.
    pub fn body_angle<S: Scalar>(&self, ws: &Workspace<S>, body: usize) -> (S, S) {
        (ws.theta[body], ws.omega[body])
    }

    /// Whole-body centre of mass position (3D, ground).
    pub fn com_position<S: Scalar>(&self, ws: &Workspace<S>) -> [S; 3] {
        let mut r = [S::zero(); 2];
        let mut zsum = 0.0;
        for (i, b) in self.bodies.iter().enumerate() {
            r[0] += ws.c[i][0] * b.mass;
            r[1] += ws.c[i][1] * b.mass;
            zsum += b.mass * b.z_com;
        }
        let m = self.total_mass;
        [r[0] / m, r[1] / m, c(zsum / m)]
    }

    /// Whole-body centre of mass velocity (3D, ground).
    pub fn com_velocity<S: Scalar>(&self, ws: &Workspace<S>) -> [S; 3] {
        let mut r = [S::zero(); 2];
        for (i, b) in self.bodies.iter().enumerate() {
            r[0] += ws.vc[i][0] * b.mass;
            r[1] += ws.vc[i][1] * b.mass;
        }
        [r[0] / self.total_mass, r[1] / self.total_mass, S::zero()]
    }

    /// Whole-body centre of mass acceleration for accelerations `qdd`.
    pub fn com_acceleration<S: Scalar>(&self, ws: &Workspace<S>, qdd: &[S]) -> [S; 3] {
        let mut r = [S::zero(); 2];
        for (i, b) in self.bodies.iter().enumerate() {
            let o = i * self.dmax;
            let mut a = ws.a0c[i];
            for (k, &d) in b.dofs.iter().enumerate() {
                let j = ws.jc[o + k];
                a[0] += j[0] * qdd[d];
                a[1] += j[1] * qdd[d];
            }
            r[0] += a[0] * b.mass;
            r[1] += a[1] * b.mass;
        }
        [r[0] / self.total_mass, r[1] / self.total_mass, S::zero()]
    }

    /// Forward dynamics: solve `M q̈ = tau − b` (tau already holds every
    /// applied generalized force, including `J_pᵀF` of point forces).
    pub fn forward_dynamics<S: Scalar>(
        &self,
        ws: &mut Workspace<S>,
        tau: &[S],
        qdd: &mut [S],
    ) -> Result<(), SingularMassMatrix> {
        let n = self.nq;
        for k in 0..n {
            ws.rhs[k] = tau[k] - ws.bias[k];
        }
        // Cholesky M = L Lᵀ (lower triangle in chol).
        ws.chol.copy_from_slice(&ws.mass_matrix);
        let l = &mut ws.chol;
        for j in 0..n {
            let mut d = l[j * n + j];
            for k in 0..j {
                d -= l[j * n + k] * l[j * n + k];
            }
            if d.re().is_nan() || d.re() <= 0.0 {
                return Err(SingularMassMatrix {
                    pivot: j,
                    value: d.re(),
                });
            }
            let djj = d.sqrt();
            l[j * n + j] = djj;
            let inv = djj.recip();
            for i in j + 1..n {
                let mut s = l[i * n + j];
                for k in 0..j {
                    s -= l[i * n + k] * l[j * n + k];
                }
                l[i * n + j] = s * inv;
            }
        }
        // L y = rhs, then Lᵀ x = y.
        for i in 0..n {
            let mut s = ws.rhs[i];
            for k in 0..i {
                s -= l[i * n + k] * qdd[k];
            }
            qdd[i] = s / l[i * n + i];
        }
        for i in (0..n).rev() {
            let mut s = qdd[i];
            for k in i + 1..n {
                s -= l[k * n + i] * qdd[k];
            }
            qdd[i] = s / l[i * n + i];
        }
        Ok(())
    }

    /// Kinetic plus gravitational potential energy (J) at the current state.
    pub fn energy<S: Scalar>(&self, ws: &Workspace<S>) -> S {
        let n = self.nq;
        let mut e = S::zero();
        for j in 0..n {
            for k in 0..n {
                e += ws.mass_matrix[j * n + k] * ws.u[j] * ws.u[k] * 0.5;
            }
        }
        for (i, b) in self.bodies.iter().enumerate() {
            e -= (ws.c[i][0] * self.gravity[0] + ws.c[i][1] * self.gravity[1]) * b.mass;
        }
        e
    }
}

/// A [`Multibody`] at its current state, seen through model bodies and
/// model coordinates (for paths, contact and other force elements).
pub struct ModelView<'a, S: Scalar> {
    pub mb: &'a Multibody,
    pub ws: &'a Workspace<S>,
    /// System coordinate of each model coordinate.
    pub q_of: &'a [usize],
}

impl<'a, S: Scalar> ModelView<'a, S> {
    /// The view of `mb` at (q, u) in `ws` (whose state it sets), the model
    /// coordinates at the system's `q_of`.
    pub fn at(
        mb: &'a Multibody,
        ws: &'a mut Workspace<S>,
        q_of: &'a [usize],
        q: &[S],
        u: &[S],
    ) -> Self {
        mb.set_state(ws, q, u);
        ModelView { mb, ws, q_of }
    }

    #[inline]
    fn frame(&self, body: usize, loc: [S; 3]) -> (usize, [S; 3]) {
        let (ci, off) = self.mb.frame_of_model_body(body);
        (ci, [loc[0] + off[0], loc[1] + off[1], loc[2] + off[2]])
    }
}

impl<'a, S: Scalar> crate::path::BodyKinematics<S> for ModelView<'a, S> {
    fn position(&self, body: usize, loc: [S; 3]) -> [S; 3] {
        let (ci, l) = self.frame(body, loc);
        self.mb.point_position_s(self.ws, ci, l)
    }
    fn velocity(&self, body: usize, loc: [S; 3]) -> [S; 3] {
        let (ci, l) = self.frame(body, loc);
        self.mb.point_velocity_s(self.ws, ci, l)
    }
    fn to_ground(&self, body: usize, v: [S; 3]) -> [S; 3] {
        let (ci, _) = self.mb.frame_of_model_body(body);
        self.mb.to_ground(self.ws, ci, v)
    }
    fn to_body(&self, body: usize, v: [S; 3]) -> [S; 3] {
        let (ci, _) = self.mb.frame_of_model_body(body);
        let (c, s) = (self.ws.cos[ci], self.ws.sin[ci]);
        [c * v[0] + s * v[1], c * v[1] - s * v[0], v[2]]
    }
    fn coordinate(&self, coordinate: usize) -> (S, S) {
        let k = self.q_of[coordinate];
        (self.ws.q[k], self.ws.u[k])
    }
}

/// Generalized forces of a [`Multibody`] collected from point forces and
/// model-coordinate forces.
pub struct GeneralizedForces<'a, S: Scalar> {
    pub mb: &'a Multibody,
    pub ws: &'a Workspace<S>,
    pub q_of: &'a [usize],
    pub tau: &'a mut [S],
}

impl<'a, S: Scalar> crate::path::ForceSink<S> for GeneralizedForces<'a, S> {
    fn add_point_force(&mut self, body: usize, loc: [S; 3], force: [S; 3]) {
        let (ci, off) = self.mb.frame_of_model_body(body);
        self.mb.add_point_force_s(
            self.ws,
            ci,
            [loc[0] + off[0], loc[1] + off[1], loc[2] + off[2]],
            force,
            self.tau,
        );
    }
    fn add_generalized_force(&mut self, coordinate: usize, force: S) {
        self.tau[self.q_of[coordinate]] += force;
    }
}

/// Generalized forces of a unit tension (the moment arms), added scaled into
/// a [`GeneralizedForces`] sink: the Rust backend's fast muscle path. Point
/// forces are summed per body into a wrench (force and moment about the body
/// origin) and mapped to generalized forces once per body.
pub struct UnitGeneralizedForces<'a, S: Scalar> {
    pub mb: &'a Multibody,
    pub ws: &'a Workspace<S>,
    pub q_of: &'a [usize],
    /// Generalized forces added directly (moving points sliding).
    pub tau: &'a mut [S],
    /// Per composite body: [Fx, Fy, Mz about the origin].
    pub wrench: &'a mut [[S; 3]],
    /// Bit i set: body i has a wrench.
    pub touched: u64,
}

impl<'a, S: Scalar> UnitGeneralizedForces<'a, S> {
    /// A sink over `mb`'s bodies at the state `ws` holds, whose first
    /// `clear` zeroes every body's wrench (`tau` and `wrench`: scratch of
    /// n and [`Multibody::num_composite_bodies`] entries).
    pub fn new(
        mb: &'a Multibody,
        ws: &'a Workspace<S>,
        q_of: &'a [usize],
        tau: &'a mut [S],
        wrench: &'a mut [[S; 3]],
    ) -> Self {
        let n = mb.num_composite_bodies();
        UnitGeneralizedForces {
            mb,
            ws,
            q_of,
            tau,
            wrench,
            touched: if n >= 64 { u64::MAX } else { (1u64 << n) - 1 },
        }
    }
}

impl<'a, S: Scalar> crate::path::ForceSink<S> for UnitGeneralizedForces<'a, S> {
    #[inline]
    fn add_point_force(&mut self, body: usize, loc: [S; 3], force: [S; 3]) {
        let (ci, off) = self.mb.frame_of_model_body(body);
        let s = rot(
            self.ws.cos[ci],
            self.ws.sin[ci],
            [loc[0] + off[0], loc[1] + off[1]],
        );
        let w = &mut self.wrench[ci];
        w[0] += force[0];
        w[1] += force[1];
        w[2] += s[0] * force[1] - s[1] * force[0];
        self.touched |= 1 << ci;
    }
    fn add_generalized_force(&mut self, coordinate: usize, force: S) {
        self.tau[self.q_of[coordinate]] += force;
    }
}

impl<'a, 'b, S: Scalar> crate::path::UnitForces<S, GeneralizedForces<'b, S>>
    for UnitGeneralizedForces<'a, S>
{
    fn clear(&mut self) {
        for t in self.tau.iter_mut() {
            *t = S::zero();
        }
        let mut bits = self.touched;
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            self.wrench[i] = [S::zero(); 3];
            bits &= bits - 1;
        }
        self.touched = 0;
    }
    fn apply_scaled(&self, factor: S, sink: &mut GeneralizedForces<'b, S>) {
        for (t, u) in sink.tau.iter_mut().zip(self.tau.iter()) {
            *t += *u * factor;
        }
        let mut bits = self.touched;
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let w = self.wrench[i];
            let (f, m) = ([w[0] * factor, w[1] * factor], w[2] * factor);
            let b = &self.mb.bodies[i];
            let o = i * self.mb.dmax;
            for k in 0..b.dofs.len() {
                let j = self.ws.jp[o + k];
                let mut g = j[0] * f[0] + j[1] * f[1];
                if b.rot[k] {
                    g += m;
                }
                sink.tau[b.dofs[k]] += g;
            }
        }
    }
}
