//! Muscle paths: OpenSim's `GeometryPath` of fixed, conditional and moving
//! path points, on any skeleton that can report point kinematics.
//!
//! The path length is the sum of the straight 3D segments between the active
//! points (gait2392 has no wrapping surfaces); the lengthening speed is its
//! time derivative; a tension `T` along the path produces the generalized
//! forces `τ = −T·∂L/∂q`, so the moment arm is `r = −∂L/∂q` (OpenSim's sign,
//! `MomentArmSolver`, model-equations.md §7.3). Forces are applied as point
//! forces at the path points (plus, for a moving point, the work its sliding
//! does on its coordinate), exactly as OpenSim's `PointForceDirection`s do.
//!
//! A conditional point is active iff its coordinate lies in `range`; at the
//! range ends the length jumps. For gradient-based solvers the
//! [`PathSmoothing::Smooth`] option blends the path with and without each
//! conditional point by a smooth step of the coordinate,
//! `L = Σ_S Π_i w_i^{[i∈S]}(1 − w_i)^{[i∉S]} L(S)`, with
//! `w(q) = s((q − lo)/δ)·s((hi − q)/δ)` and `s` the quintic (C²) smoothstep
//! from 0 at −1 to 1 at +1, so the path is exact more than δ from a switch.

use crate::scalar::{c, Scalar};
use crate::spline::{SimmSpline, SplineData};
use serde::{Deserialize, Serialize};

/// A path point as written in a model file (body and coordinate by name).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", try_from = "PathPointFields")]
pub enum PathPointSpec {
    /// OpenSim `PathPoint`: fixed in `body` at `location` (m).
    Fixed { body: String, location: [f64; 3] },
    /// OpenSim `ConditionalPathPoint`: active iff `range[0] ≤ coordinate ≤ range[1]`.
    Conditional {
        body: String,
        location: [f64; 3],
        coordinate: String,
        range: [f64; 2],
    },
    /// OpenSim `MovingPathPoint`: location components are SimmSplines of `coordinate`.
    Moving {
        body: String,
        coordinate: String,
        x_location: SplineData,
        y_location: SplineData,
        z_location: SplineData,
    },
}

/// A path point as a file gives it: the fields of every point type, each
/// read with its own JSON path (serde's internally tagged enums lose the
/// path of an error inside a variant), then checked against its `type`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PathPointFields {
    #[serde(rename = "type")]
    kind: PathPointType,
    body: String,
    #[serde(default, deserialize_with = "crate::model::present")]
    location: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "crate::model::present")]
    coordinate: Option<String>,
    #[serde(default, deserialize_with = "crate::model::present")]
    range: Option<[f64; 2]>,
    #[serde(default, deserialize_with = "crate::model::present")]
    x_location: Option<SplineData>,
    #[serde(default, deserialize_with = "crate::model::present")]
    y_location: Option<SplineData>,
    #[serde(default, deserialize_with = "crate::model::present")]
    z_location: Option<SplineData>,
}

/// Read from a string only: serde's enums also take `{"fixed": null}`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(try_from = "String")]
enum PathPointType {
    Fixed,
    Conditional,
    Moving,
}

const PATH_POINT_TYPES: [(&str, PathPointType); 3] = [
    ("fixed", PathPointType::Fixed),
    ("conditional", PathPointType::Conditional),
    ("moving", PathPointType::Moving),
];

impl TryFrom<String> for PathPointType {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        crate::model::variant_named(&s, &PATH_POINT_TYPES)
    }
}

/// The fields every path point has.
const PATH_POINT_COMMON_FIELDS: [&str; 2] = ["type", "body"];

impl PathPointType {
    /// The fields a path point of this type has besides the common ones.
    fn fields(self) -> &'static [&'static str] {
        match self {
            PathPointType::Fixed => &["location"],
            PathPointType::Conditional => &["location", "coordinate", "range"],
            PathPointType::Moving => &["coordinate", "x_location", "y_location", "z_location"],
        }
    }
}

/// The common fields of a path point and those of the type named `kind`
/// (None for no such type).
pub(crate) fn path_point_fields(
    kind: &str,
) -> Option<(&'static [&'static str], &'static [&'static str])> {
    let t = crate::model::variant_named(kind, &PATH_POINT_TYPES).ok()?;
    Some((&PATH_POINT_COMMON_FIELDS, t.fields()))
}

impl TryFrom<PathPointFields> for PathPointSpec {
    type Error = String;
    fn try_from(p: PathPointFields) -> Result<Self, String> {
        let kind = crate::model::variant_name(p.kind, &PATH_POINT_TYPES);
        crate::model::variant_fields(
            &format!("a {kind} path point"),
            &PATH_POINT_COMMON_FIELDS,
            p.kind.fields(),
            &[
                ("location", p.location.is_some()),
                ("coordinate", p.coordinate.is_some()),
                ("range", p.range.is_some()),
                ("x_location", p.x_location.is_some()),
                ("y_location", p.y_location.is_some()),
                ("z_location", p.z_location.is_some()),
            ],
        )?;
        // `variant_fields` has checked that each field taken is given.
        let missing = || format!("a {kind} path point misses a field");
        let body = p.body;
        Ok(match p.kind {
            PathPointType::Fixed => PathPointSpec::Fixed {
                body,
                location: p.location.ok_or_else(missing)?,
            },
            PathPointType::Conditional => PathPointSpec::Conditional {
                body,
                location: p.location.ok_or_else(missing)?,
                coordinate: p.coordinate.ok_or_else(missing)?,
                range: p.range.ok_or_else(missing)?,
            },
            PathPointType::Moving => PathPointSpec::Moving {
                body,
                coordinate: p.coordinate.ok_or_else(missing)?,
                x_location: p.x_location.ok_or_else(missing)?,
                y_location: p.y_location.ok_or_else(missing)?,
                z_location: p.z_location.ok_or_else(missing)?,
            },
        })
    }
}

/// What makes a validated path point move.
#[derive(Debug, Clone)]
pub enum PointKind {
    Fixed,
    Conditional {
        coordinate: usize,
        range: [f64; 2],
    },
    Moving {
        coordinate: usize,
        x: SimmSpline,
        y: SimmSpline,
        z: SimmSpline,
    },
}

/// A validated path point on model body `body`.
#[derive(Debug, Clone)]
pub struct PathPoint {
    pub body: usize,
    pub location: [f64; 3],
    pub kind: PointKind,
}

/// A validated muscle path.
#[derive(Debug, Clone)]
pub struct GeometryPath {
    pub points: Vec<PathPoint>,
    /// Indices (into `points`) of the conditional points.
    conditional: Vec<usize>,
    /// For each point, its index among the conditional points.
    conditional_of: Vec<Option<u32>>,
}

/// How conditional path points switch.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "mode")]
pub enum PathSmoothing {
    /// Exactly as OpenSim: on or off.
    Exact,
    /// Blended over a width `delta` (rad) at each range end.
    Smooth { delta: f64 },
}

/// Point kinematics of a skeleton at its current state, by model body and
/// model coordinate.
pub trait BodyKinematics<S: Scalar> {
    /// Position in ground of the point at `loc` in the body frame.
    fn position(&self, body: usize, loc: [S; 3]) -> [S; 3];
    /// Velocity in ground of the body's material point at `loc`.
    fn velocity(&self, body: usize, loc: [S; 3]) -> [S; 3];
    /// A body-frame vector expressed in ground.
    fn to_ground(&self, body: usize, v: [S; 3]) -> [S; 3];
    /// A ground vector expressed in the body frame.
    fn to_body(&self, body: usize, v: [S; 3]) -> [S; 3];
    /// The body-frame location of the body point now at ground point `p`.
    fn station_at(&self, body: usize, p: [S; 3]) -> [S; 3] {
        let o = self.position(body, [S::zero(); 3]);
        self.to_body(body, [p[0] - o[0], p[1] - o[1], p[2] - o[2]])
    }
    /// Value and speed of a model coordinate.
    fn coordinate(&self, coordinate: usize) -> (S, S);
}

/// Where forces go: point forces on bodies and generalized forces on
/// model coordinates.
pub trait ForceSink<S: Scalar> {
    fn add_point_force(&mut self, body: usize, loc: [S; 3], force: [S; 3]);
    fn add_generalized_force(&mut self, coordinate: usize, force: S);
}

/// The quintic smoothstep of x ∈ [−1, 1] mapped to [0, 1], and its
/// derivative with respect to x.
#[inline]
fn smoothstep<S: Scalar>(x: S) -> (S, S) {
    let u = x * 0.5 + 0.5;
    if u.re() <= 0.0 {
        (S::zero(), S::zero())
    } else if u.re() >= 1.0 {
        (S::one(), S::zero())
    } else {
        let u2 = u * u;
        let one_minus = S::one() - u;
        (
            (u * 6.0 - 15.0) * u2 * u2 + u2 * u * 10.0,
            u2 * one_minus * one_minus * 15.0,
        )
    }
}

/// A path point's kinematics at one state.
#[derive(Debug, Clone, Copy)]
struct PointState<S> {
    i: usize,
    p: [S; 3],
    v: [S; 3],
    loc: [S; 3],
    slide: [S; 3],
    coord: Option<usize>,
}

/// The path's configuration-level results at one state.
#[derive(Debug, Clone, Copy)]
pub struct PathValue<S> {
    pub length: S,
    pub lengthening_speed: S,
}

/// Why a path cannot be built.
#[derive(Debug, Clone, thiserror::Error)]
pub enum PathError {
    #[error("{0}")]
    Invalid(String),
}

impl GeometryPath {
    /// Build a path; `body` and `coordinate` resolve names (None: unknown).
    pub fn new(
        points: &[PathPointSpec],
        body: impl Fn(&str) -> Option<usize>,
        coordinate: impl Fn(&str) -> Option<usize>,
    ) -> Result<Self, (usize, String, String)> {
        if points.len() < 2 {
            return Err((
                0,
                String::new(),
                format!("a path needs at least 2 points, got {}", points.len()),
            ));
        }
        // Conditional points can all switch off, leaving no path (length 0,
        // no direction to pull in).
        let always = points
            .iter()
            .filter(|p| !matches!(p, PathPointSpec::Conditional { .. }))
            .count();
        if always < 2 {
            return Err((
                0,
                String::new(),
                format!(
                    "a path needs at least 2 points that are always active (fixed or moving), got {always}: conditional points can all switch off"
                ),
            ));
        }
        let mut out = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            let b = |name: &str| {
                body(name).ok_or_else(|| (i, "body".to_string(), format!("unknown body '{name}'")))
            };
            let cd = |name: &str| {
                coordinate(name).ok_or_else(|| {
                    (
                        i,
                        "coordinate".to_string(),
                        format!("unknown coordinate '{name}'"),
                    )
                })
            };
            let pp = match p {
                PathPointSpec::Fixed { body, location } => {
                    if let Some(r) = crate::model::location_problem(location) {
                        return Err((i, "location".into(), r));
                    }
                    PathPoint {
                        body: b(body)?,
                        location: *location,
                        kind: PointKind::Fixed,
                    }
                }
                PathPointSpec::Conditional {
                    body,
                    location,
                    coordinate,
                    range,
                } => {
                    if let Some(r) = crate::model::location_problem(location) {
                        return Err((i, "location".into(), r));
                    }
                    if !(range[0].is_finite() && range[1].is_finite() && range[0] < range[1]) {
                        return Err((
                            i,
                            "range".into(),
                            format!("range must be finite with min < max, got {range:?}"),
                        ));
                    }
                    PathPoint {
                        body: b(body)?,
                        location: *location,
                        kind: PointKind::Conditional {
                            coordinate: cd(coordinate)?,
                            range: *range,
                        },
                    }
                }
                PathPointSpec::Moving {
                    body,
                    coordinate,
                    x_location,
                    y_location,
                    z_location,
                } => {
                    let s = |d: &SplineData, f: &str| {
                        // Its values are a location's coordinates: bounded
                        // as a fixed point's are.
                        if let Some(&y) =
                            d.y.iter()
                                .find(|y| y.is_nan() || y.abs() > crate::model::MAX_LOCATION_M)
                        {
                            return Err((
                                i,
                                f.to_string(),
                                format!(
                                    "values must be finite and within ±{} m of the body's origin, got {}",
                                    crate::model::MAX_LOCATION_M,
                                    crate::io::readable(y)
                                ),
                            ));
                        }
                        SimmSpline::new(d).map_err(|e| (i, f.to_string(), e.to_string()))
                    };
                    PathPoint {
                        body: b(body)?,
                        location: [0.0; 3],
                        kind: PointKind::Moving {
                            coordinate: cd(coordinate)?,
                            x: s(x_location, "x_location")?,
                            y: s(y_location, "y_location")?,
                            z: s(z_location, "z_location")?,
                        },
                    }
                }
            };
            out.push(pp);
        }
        // Two points fixed on the same body at the same location, with at
        // most conditional points between them, can make a segment of zero
        // length: its direction, and with it the lengthening speed and the
        // forces, would be 0/0.
        let fixed_on = |p: &PathPoint| match p.kind {
            PointKind::Moving { .. } => None,
            _ => Some((p.body, p.location)),
        };
        for j in 1..out.len() {
            for i in (0..j).rev() {
                if let (Some(a), Some(b)) = (fixed_on(&out[i]), fixed_on(&out[j])) {
                    if a == b {
                        return Err((
                            j,
                            "location".into(),
                            format!(
                                "coincides with path point {i} on the same body ({:?}){}: a segment of zero length has no direction",
                                b.1,
                                if j > i + 1 { " when the conditional points between them are inactive" } else { "" }
                            ),
                        ));
                    }
                }
                if !matches!(out[i].kind, PointKind::Conditional { .. }) {
                    break;
                }
            }
        }
        let conditional: Vec<usize> = out
            .iter()
            .enumerate()
            .filter(|(_, p)| matches!(p.kind, PointKind::Conditional { .. }))
            .map(|(i, _)| i)
            .collect();
        let conditional_of = (0..out.len())
            .map(|i| conditional.iter().position(|&c| c == i).map(|j| j as u32))
            .collect();
        Ok(GeometryPath {
            points: out,
            conditional,
            conditional_of,
        })
    }

    /// Number of conditional points.
    pub fn num_conditional(&self) -> usize {
        self.conditional.len()
    }

    /// Length of the exact (OpenSim) path with conditional point `j`
    /// (index among the conditional points) forced on or off, the others as
    /// their coordinates say.
    pub fn length_with<S: Scalar, K: BodyKinematics<S>>(&self, k: &K, j: usize, on: bool) -> S {
        let nc = self.conditional.len();
        let mut w = [S::zero(); 8];
        let mut dw = [S::zero(); 8];
        self.weights(k, PathSmoothing::Exact, &mut w[..nc], &mut dw[..nc]);
        let mut mask = (0..nc).fold(0u32, |m, i| if w[i].re() > 0.5 { m | (1 << i) } else { m });
        if on {
            mask |= 1 << j;
        } else {
            mask &= !(1 << j);
        }
        self.subpath::<S, K, CollectedForces<S>>(k, mask, None)
            .length
    }

    /// The conditional points: (point index, coordinate, range).
    pub fn conditional_points(&self) -> Vec<(usize, usize, [f64; 2])> {
        self.conditional
            .iter()
            .filter_map(|&i| match &self.points[i].kind {
                PointKind::Conditional { coordinate, range } => Some((i, *coordinate, *range)),
                _ => None,
            })
            .collect()
    }

    /// Location in the body frame and its derivative with respect to the
    /// point's coordinate (zero unless moving).
    #[inline]
    fn local<S: Scalar, K: BodyKinematics<S>>(
        &self,
        k: &K,
        i: usize,
    ) -> ([S; 3], [S; 3], Option<usize>) {
        let p = &self.points[i];
        match &p.kind {
            PointKind::Moving {
                coordinate,
                x,
                y,
                z,
            } => {
                let (q, _) = k.coordinate(*coordinate);
                let (x0, x1, _) = x.eval(q);
                let (y0, y1, _) = y.eval(q);
                let (z0, z1, _) = z.eval(q);
                ([x0, y0, z0], [x1, y1, z1], Some(*coordinate))
            }
            _ => (
                [c(p.location[0]), c(p.location[1]), c(p.location[2])],
                [S::zero(); 3],
                None,
            ),
        }
    }

    /// Ground position and velocity of point `i`, its body-frame location,
    /// and (moving points) its coordinate and the ground direction in which
    /// it slides per unit of that coordinate.
    #[inline]
    fn point<S: Scalar, K: BodyKinematics<S>>(&self, k: &K, i: usize) -> PointState<S> {
        let (loc, dloc, coord) = self.local(k, i);
        let body = self.points[i].body;
        let p = k.position(body, loc);
        let mut v = k.velocity(body, loc);
        let mut slide = [S::zero(); 3];
        if let Some(cd) = coord {
            let (_, qd) = k.coordinate(cd);
            slide = k.to_ground(body, dloc);
            for d in 0..3 {
                v[d] += slide[d] * qd;
            }
        }
        PointState {
            i,
            p,
            v,
            loc,
            slide,
            coord,
        }
    }

    /// Weight of each conditional point (1 = active) under `smoothing`,
    /// written into `w` (length [`Self::num_conditional`]).
    fn weights<S: Scalar, K: BodyKinematics<S>>(
        &self,
        k: &K,
        smoothing: PathSmoothing,
        w: &mut [S],
        dw: &mut [S],
    ) {
        for (j, &i) in self.conditional.iter().enumerate() {
            let PointKind::Conditional { coordinate, range } = &self.points[i].kind else {
                continue;
            };
            let (q, _) = k.coordinate(*coordinate);
            match smoothing {
                PathSmoothing::Exact => {
                    let on = q.re() >= range[0] && q.re() <= range[1];
                    w[j] = if on { S::one() } else { S::zero() };
                    dw[j] = S::zero();
                }
                PathSmoothing::Smooth { delta } => {
                    // Quintic smoothstep over [edge − δ, edge + δ]: C², and
                    // exactly 0 or 1 outside the window.
                    let (sa, da) = smoothstep((q - range[0]) / delta);
                    let (sb, db) = smoothstep((q * -1.0 + range[1]) / delta);
                    w[j] = sa * sb;
                    dw[j] = (da * sb - sa * db) / delta;
                }
            }
        }
    }

    /// Length and speed of the path with conditional points on where bit j of
    /// `mask` is set; optionally applies `tension` along it.
    fn subpath<S: Scalar, K: BodyKinematics<S>, F: ForceSink<S>>(
        &self,
        k: &K,
        mask: u32,
        tension: Option<(S, &mut F)>,
    ) -> PathValue<S> {
        let mut length = S::zero();
        let mut speed = S::zero();
        let active = |i: usize| -> bool {
            match self.conditional_of[i] {
                Some(j) => mask & (1 << j) != 0,
                None => true,
            }
        };
        let mut prev: Option<PointState<S>> = None;
        let mut sink = tension;
        let mut prev_dir: Option<[S; 3]> = None;
        let n = self.points.len();
        for i in 0..n {
            if !active(i) {
                continue;
            }
            let cur = self.point(k, i);
            let mut dir_out = None;
            if let Some(pp) = &prev {
                let d = [cur.p[0] - pp.p[0], cur.p[1] - pp.p[1], cur.p[2] - pp.p[2]];
                let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let e = [d[0] / len, d[1] / len, d[2] / len];
                length += len;
                speed += e[0] * (cur.v[0] - pp.v[0])
                    + e[1] * (cur.v[1] - pp.v[1])
                    + e[2] * (cur.v[2] - pp.v[2]);
                dir_out = Some(e);
                // Force on the previous point: tension toward this one.
                if let Some((t, sink)) = sink.as_mut() {
                    let pull_prev = [e[0] * *t, e[1] * *t, e[2] * *t];
                    self.apply(pp, pull_prev, prev_dir, *sink, *t);
                }
            }
            prev_dir = dir_out;
            prev = Some(cur);
        }
        // Last point: pulled back toward its predecessor.
        if let (Some((t, sink)), Some(last), Some(e)) = (sink.as_mut(), &prev, prev_dir) {
            let pull = [e[0] * -*t, e[1] * -*t, e[2] * -*t];
            self.apply(last, pull, None, *sink, *t);
        }
        PathValue {
            length,
            lengthening_speed: speed,
        }
    }

    /// Apply the force on a point: `pull` toward its successor plus, if
    /// `incoming` (unit vector from its predecessor) is given, `−T·incoming`.
    #[inline]
    fn apply<S: Scalar, F: ForceSink<S>>(
        &self,
        pt: &PointState<S>,
        pull: [S; 3],
        incoming: Option<[S; 3]>,
        sink: &mut F,
        t: S,
    ) {
        let mut f = pull;
        if let Some(e) = incoming {
            for d in 0..3 {
                f[d] -= e[d] * t;
            }
        }
        sink.add_point_force(self.points[pt.i].body, pt.loc, f);
        if let Some(cd) = pt.coord {
            // The moving point slides in its body as its coordinate changes.
            let g = pt.slide;
            sink.add_generalized_force(cd, f[0] * g[0] + f[1] * g[1] + f[2] * g[2]);
        }
    }

    /// Length and lengthening speed; if `tension` is given, also applies it
    /// along the path (generalized forces `−T ∂L/∂q`).
    pub fn calc<S: Scalar, K: BodyKinematics<S>, F: ForceSink<S>>(
        &self,
        k: &K,
        smoothing: PathSmoothing,
        tension: Option<(S, &mut F)>,
    ) -> PathValue<S> {
        let nc = self.conditional.len();
        if nc == 0 {
            return self.subpath(k, 0, tension);
        }
        assert!(nc <= 8, "validated: at most 8 conditional points per path");
        let mut w = [S::zero(); 8];
        let mut dw = [S::zero(); 8];
        self.weights(k, smoothing, &mut w[..nc], &mut dw[..nc]);
        let mut total = PathValue {
            length: S::zero(),
            lengthening_speed: S::zero(),
        };
        let mut sink = tension;
        // Σ over subsets S of Π weights · L(S); the weights' rates add
        // Σ_i ∂Π/∂w_i · ẇ_i · L(S) to the speed and −T Σ ∂Π/∂w_i w_i' L(S)
        // to the generalized force of coordinate i.
        for mask in 0u32..(1 << nc) {
            let mut prod = S::one();
            for j in 0..nc {
                prod *= if mask & (1 << j) != 0 {
                    w[j]
                } else {
                    S::one() - w[j]
                };
            }
            // A saturated weight is exactly 0 with a zero derivative.
            if prod.re() == 0.0 {
                continue;
            }
            let sub = match sink.as_mut() {
                Some((t, s)) => self.subpath(k, mask, Some((*t * prod, &mut **s))),
                None => self.subpath::<S, K, F>(k, mask, None),
            };
            total.length += prod * sub.length;
            total.lengthening_speed += prod * sub.lengthening_speed;
            if let PathSmoothing::Smooth { .. } = smoothing {
                for j in 0..nc {
                    // ∂prod/∂w_j
                    let mut dp = S::one();
                    for m in 0..nc {
                        if m == j {
                            dp *= if mask & (1 << m) != 0 {
                                S::one()
                            } else {
                                -S::one()
                            };
                        } else {
                            dp *= if mask & (1 << m) != 0 {
                                w[m]
                            } else {
                                S::one() - w[m]
                            };
                        }
                    }
                    let PointKind::Conditional { coordinate, .. } =
                        &self.points[self.conditional[j]].kind
                    else {
                        continue;
                    };
                    let (_, qd) = k.coordinate(*coordinate);
                    let dl_dq = dp * dw[j] * sub.length;
                    total.lengthening_speed += dl_dq * qd;
                    if let Some((t, s)) = sink.as_mut() {
                        s.add_generalized_force(*coordinate, -(*t * dl_dq));
                    }
                }
            }
        }
        total
    }
}

/// Forces collected in memory (to be scaled and replayed into another sink).
#[derive(Debug, Clone, Default)]
pub struct CollectedForces<S> {
    pub points: Vec<(usize, [S; 3], [S; 3])>,
    pub generalized: Vec<(usize, S)>,
}

impl<S: Scalar> CollectedForces<S> {
    pub fn clear(&mut self) {
        self.points.clear();
        self.generalized.clear();
    }

    /// Replay every force times `factor` into `sink`.
    pub fn replay_scaled<F: ForceSink<S>>(&self, factor: S, sink: &mut F) {
        for (b, loc, f) in &self.points {
            sink.add_point_force(*b, *loc, [f[0] * factor, f[1] * factor, f[2] * factor]);
        }
        for (c, g) in &self.generalized {
            sink.add_generalized_force(*c, *g * factor);
        }
    }
}

impl<S: Scalar> ForceSink<S> for CollectedForces<S> {
    fn add_point_force(&mut self, body: usize, loc: [S; 3], force: [S; 3]) {
        self.points.push((body, loc, force));
    }
    fn add_generalized_force(&mut self, coordinate: usize, force: S) {
        self.generalized.push((coordinate, force));
    }
}

/// A sink for the forces of a unit tension along one path, which can then
/// add them, scaled by the actual tension, into the real sink `F`.
pub trait UnitForces<S: Scalar, F>: ForceSink<S> {
    fn clear(&mut self);
    fn apply_scaled(&self, factor: S, sink: &mut F);
}

impl<S: Scalar, F: ForceSink<S>> UnitForces<S, F> for CollectedForces<S> {
    fn clear(&mut self) {
        CollectedForces::clear(self)
    }
    fn apply_scaled(&self, factor: S, sink: &mut F) {
        self.replay_scaled(factor, sink)
    }
}
