// Simbody facade for leap (see leap_simbody.h).
#include "leap/cpp/leap_simbody.h"
#include "leap/src/simbody.rs.h"

#include <Simbody.h>
#include <stdexcept>
#include <string>
#include <vector>

using namespace SimTK;

namespace leap {

namespace {

// OpenSim's SimmSpline evaluated from coefficients computed on the Rust side
// (Forsythe-Malcolm-Moler): y = y_k + dx (b_k + dx (c_k + dx d_k)), linear
// extrapolation with the end slope outside the knots.
class CoefficientSpline : public SimTK::Function {
public:
    std::vector<double> x, y, b, c, d;
    CoefficientSpline(rust::Slice<const double> blocks) {
        const std::size_t n = blocks.size() / 5;
        const double* p = blocks.data();
        x.assign(p, p + n);
        y.assign(p + n, p + 2 * n);
        b.assign(p + 2 * n, p + 3 * n);
        c.assign(p + 3 * n, p + 4 * n);
        d.assign(p + 4 * n, p + 5 * n);
    }
    std::size_t interval(double t) const {
        const std::size_t n = x.size();
        if (n == 2 || t <= x[1]) return 0;
        if (t >= x[n - 2]) return n - 2;
        std::size_t lo = 1, hi = n - 2;
        while (hi - lo > 1) {
            const std::size_t mid = (lo + hi) / 2;
            if (t < x[mid]) hi = mid; else lo = mid;
        }
        return lo;
    }
    double eval(double t, int order) const {
        const std::size_t n = x.size();
        if (t < x[0]) {
            if (order == 0) return y[0] + b[0] * (t - x[0]);
            return order == 1 ? b[0] : 0.0;
        }
        if (t > x[n - 1]) {
            if (order == 0) return y[n - 1] + b[n - 1] * (t - x[n - 1]);
            return order == 1 ? b[n - 1] : 0.0;
        }
        const std::size_t k = interval(t);
        const double dx = t - x[k];
        switch (order) {
            case 0: return y[k] + dx * (b[k] + dx * (c[k] + dx * d[k]));
            case 1: return b[k] + dx * (2.0 * c[k] + dx * 3.0 * d[k]);
            case 2: return 2.0 * c[k] + dx * 6.0 * d[k];
            case 3: return 6.0 * d[k];
            default: return 0.0;
        }
    }
    Real calcValue(const Vector& v) const override { return eval(v[0], 0); }
    Real calcDerivative(const Array_<int>& comps, const Vector& v) const override {
        return eval(v[0], (int)comps.size());
    }
    int getArgumentSize() const override { return 1; }
    int getMaxDerivativeOrder() const override { return 3; }
    SimTK::Function* clone() const override { return new CoefficientSpline(*this); }
};

void check_len(const char* what, std::size_t got, std::size_t want) {
    if (got != want)
        throw std::invalid_argument(std::string(what) + ": wrong length " + std::to_string(got) +
                                    " (expected " + std::to_string(want) + ")");
}

Vec3 vec3(rust::Slice<const double> s, std::size_t offset = 0) {
    return Vec3(s[offset], s[offset + 1], s[offset + 2]);
}

}  // namespace

struct ForceCtx::Inner {
    const SimbodyMatterSubsystem& matter;
    const State& s;
    Vector_<SpatialVec>& body_forces;
    Vector& mobility_forces;
};

namespace {
const MobilizedBody& ctx_body(const ForceCtx::Inner* in, std::int32_t body) {
    if (body < 0 || body >= in->matter.getNumBodies())
        throw std::out_of_range("force callback: body index " + std::to_string(body) + " out of range");
    return in->matter.getMobilizedBody(MobilizedBodyIndex(body));
}
}  // namespace

void ForceCtx::station_position(std::int32_t body, rust::Slice<const double> point, rust::Slice<double> out) const {
    check_len("point", point.size(), 3);
    check_len("out", out.size(), 3);
    const Vec3 r = ctx_body(in, body).findStationLocationInGround(in->s, vec3(point));
    for (int i = 0; i < 3; ++i) out[(std::size_t)i] = r[i];
}

void ForceCtx::station_velocity(std::int32_t body, rust::Slice<const double> point, rust::Slice<double> out) const {
    check_len("point", point.size(), 3);
    check_len("out", out.size(), 3);
    const Vec3 v = ctx_body(in, body).findStationVelocityInGround(in->s, vec3(point));
    for (int i = 0; i < 3; ++i) out[(std::size_t)i] = v[i];
}

void ForceCtx::express_in_ground(std::int32_t body, rust::Slice<const double> v, rust::Slice<double> out) const {
    check_len("vector", v.size(), 3);
    check_len("out", out.size(), 3);
    const Vec3 g = ctx_body(in, body).expressVectorInGroundFrame(in->s, vec3(v));
    for (int i = 0; i < 3; ++i) out[(std::size_t)i] = g[i];
}

void ForceCtx::express_in_body(std::int32_t body, rust::Slice<const double> v, rust::Slice<double> out) const {
    check_len("vector", v.size(), 3);
    check_len("out", out.size(), 3);
    const Vec3 b = ctx_body(in, body).expressGroundVectorInBodyFrame(in->s, vec3(v));
    for (int i = 0; i < 3; ++i) out[(std::size_t)i] = b[i];
}

void ForceCtx::add_station_force(std::int32_t body, rust::Slice<const double> point, rust::Slice<const double> force) {
    check_len("point", point.size(), 3);
    check_len("force", force.size(), 3);
    ctx_body(in, body).applyForceToBodyPoint(in->s, vec3(point), vec3(force), in->body_forces);
}

void ForceCtx::add_mobility_force(std::int32_t u_index, double force) {
    if (u_index < 0 || u_index >= in->mobility_forces.size())
        throw std::out_of_range("force callback: mobility index " + std::to_string(u_index) + " out of range");
    in->mobility_forces[u_index] += force;
}

namespace {
// A Simbody force element whose forces (and auxiliary-state derivatives) a
// Rust callback computes. calcForce must be a pure function of (t, q, u, z):
// integrators call it at trial states.
class RustForceImpl : public Force::Custom::Implementation {
public:
    RustForceImpl(GeneralForceSubsystem& forces, rust::Box<ForceCallback> cb, int nz)
        : forces(forces), cb(std::move(cb)), nz(nz) {}
    void realizeTopology(State& s) const override {
        if (nz > 0) zstart = forces.allocateZ(s, Vector(nz, 0.0));
    }
    void calcForce(const State& s, Vector_<SpatialVec>& body_forces, Vector_<Vec3>&, Vector& mobility_forces) const override {
        zdot.resize(nz);
        zdot = 0;
        ForceCtx::Inner inner{matter(), s, body_forces, mobility_forces};
        ForceCtx ctx(&inner);
        const Vector& q = s.getQ();
        const Vector& u = s.getU();
        rust::Slice<const double> qs(q.size() ? &q[0] : nullptr, (std::size_t)q.size());
        rust::Slice<const double> us(u.size() ? &u[0] : nullptr, (std::size_t)u.size());
        const Vector& zall = forces.getZ(s);
        rust::Slice<const double> zs(nz ? &zall[zstart] : nullptr, (std::size_t)nz);
        rust::Slice<double> zds(nz ? &zdot[0] : nullptr, (std::size_t)nz);
        cb->calc_forces(ctx, s.getTime(), qs, us, zs, zds);  // throws rust::Error on Err
    }
    void realizeAcceleration(const State& s) const override {
        if (nz > 0) forces.updZDot(s)(zstart, nz) = zdot;
    }
    Real calcPotentialEnergy(const State&) const override { return 0; }
    bool dependsOnlyOnPositions() const override { return false; }
    const SimbodyMatterSubsystem& matter() const { return *matter_ptr; }
    const SimbodyMatterSubsystem* matter_ptr = nullptr;
    GeneralForceSubsystem& forces;
    mutable rust::Box<ForceCallback> cb;
    int nz;
    mutable ZIndex zstart;
    // One System per thread (see simbody-bridge-notes.md §7).
    mutable Vector zdot;
};
}  // namespace

struct SimbodySystem::Impl {
    MultibodySystem system;
    SimbodyMatterSubsystem matter;
    GeneralForceSubsystem forces;
    Force::DiscreteForces discrete;
    State state;
    bool finalized = false;
    Vec3 gravity{0, 0, 0};
    RustForceImpl* rust_force = nullptr;  // owned by its Force::Custom
    std::unique_ptr<Integrator> integ;
    std::unique_ptr<TimeStepper> stepper;
    std::int32_t max_steps = 0;  // of the persistent integration; 0: no cap
    std::vector<MobilizedBody> bodies;  // index 0 is Ground
    Impl() : matter(system), forces(system), discrete(forces, matter) {
        bodies.push_back(matter.Ground());
    }
    void require_final(const char* what) const {
        if (!finalized) throw std::logic_error(std::string(what) + ": the system is not finalized");
    }
    const MobilizedBody& body(std::int32_t i) const {
        if (i < 0 || (std::size_t)i >= bodies.size())
            throw std::out_of_range("body index " + std::to_string(i) + " out of range");
        return bodies[(std::size_t)i];
    }
};

SimbodySystem::SimbodySystem() : p(new Impl) {}
SimbodySystem::~SimbodySystem() = default;

std::unique_ptr<SimbodySystem> new_simbody_system() { return std::make_unique<SimbodySystem>(); }

std::int32_t SimbodySystem::add_body(std::int32_t parent, std::int32_t kind,
                                     rust::Slice<const double> location, double mass,
                                     rust::Slice<const double> mass_center,
                                     rust::Slice<const double> inertia,
                                     rust::Slice<const double> spline_x,
                                     rust::Slice<const double> spline_y) {
    if (p->finalized) throw std::logic_error("add_body: the system is already finalized");
    check_len("location", location.size(), 3);
    check_len("mass_center", mass_center.size(), 3);
    check_len("inertia", inertia.size(), 6);
    if (!(mass > 0)) throw std::invalid_argument("add_body: mass must be positive");
    const MobilizedBody& par = p->body(parent);
    const Vec3 com = vec3(mass_center);
    const Inertia about_com(Vec3(inertia[0], inertia[1], inertia[2]), Vec3(inertia[3], inertia[4], inertia[5]));
    // MassProperties wants the inertia about the body origin.
    Body::Rigid info(MassProperties(mass, com, about_com.shiftFromMassCenter(com, mass)));
    const Transform X_PF(vec3(location));
    switch (kind) {
        case 0: p->bodies.push_back(MobilizedBody::Planar(p->bodies[(std::size_t)parent], X_PF, info, Transform())); break;
        case 1: p->bodies.push_back(MobilizedBody::Pin(p->bodies[(std::size_t)parent], X_PF, info, Transform())); break;
        case 2: {
            if (spline_x.size() % 5 != 0 || spline_x.size() < 10 || spline_y.size() % 5 != 0 || spline_y.size() < 10)
                throw std::invalid_argument("add_body: spline blocks must hold 5 arrays of at least 2 knots");
            std::vector<const SimTK::Function*> fns(6);
            std::vector<std::vector<int>> idx(6);
            fns[0] = new SimTK::Function::Constant(0, 0);
            fns[1] = new SimTK::Function::Constant(0, 0);
            fns[2] = new SimTK::Function::Linear(Vector(Vec2(1, 0)));
            idx[2] = {0};
            fns[3] = new CoefficientSpline(spline_x);
            idx[3] = {0};
            fns[4] = new CoefficientSpline(spline_y);
            idx[4] = {0};
            fns[5] = new SimTK::Function::Constant(0, 0);
            p->bodies.push_back(MobilizedBody::FunctionBased(p->bodies[(std::size_t)parent], X_PF, info, Transform(), 1, fns, idx));
            break;
        }
        case 3: p->bodies.push_back(MobilizedBody::Weld(p->bodies[(std::size_t)parent], X_PF, info, Transform())); break;
        default: throw std::invalid_argument("add_body: unknown mobilizer kind " + std::to_string(kind));
    }
    (void)par;
    return (std::int32_t)(p->bodies.size() - 1);
}

void SimbodySystem::add_rust_force(rust::Box<ForceCallback> callback, std::int32_t nz) {
    if (p->finalized) throw std::logic_error("add_rust_force: the system is already finalized");
    if (p->rust_force) throw std::logic_error("add_rust_force: a Rust force element is already installed");
    if (nz < 0) throw std::invalid_argument("add_rust_force: negative number of states");
    auto* impl = new RustForceImpl(p->forces, std::move(callback), nz);
    impl->matter_ptr = &p->matter;
    Force::Custom(p->forces, impl);  // takes ownership
    p->rust_force = impl;
}

void SimbodySystem::set_z(rust::Slice<const double> z) {
    p->require_final("set_z");
    const int nz = p->rust_force ? p->rust_force->nz : 0;
    check_len("z", z.size(), (std::size_t)nz);
    if (nz == 0) return;
    Vector& zall = p->forces.updZ(p->state);
    for (int i = 0; i < nz; ++i) zall[p->rust_force->zstart + i] = z[(std::size_t)i];
}

void SimbodySystem::get_z(rust::Slice<double> z) const {
    p->require_final("get_z");
    const int nz = p->rust_force ? p->rust_force->nz : 0;
    check_len("z", z.size(), (std::size_t)nz);
    if (nz == 0) return;
    const Vector& zall = p->forces.getZ(p->state);
    for (int i = 0; i < nz; ++i) z[(std::size_t)i] = zall[p->rust_force->zstart + i];
}

void SimbodySystem::calc_zdot(rust::Slice<double> zdot) {
    p->require_final("calc_zdot");
    const int nz = p->rust_force ? p->rust_force->nz : 0;
    check_len("zdot", zdot.size(), (std::size_t)nz);
    p->system.realize(p->state, Stage::Acceleration);
    if (nz == 0) return;
    const Vector& zd = p->forces.getZDot(p->state);
    for (int i = 0; i < nz; ++i) zdot[(std::size_t)i] = zd[p->rust_force->zstart + i];
}

void SimbodySystem::finalize(rust::Slice<const double> gravity) {
    if (p->finalized) throw std::logic_error("finalize: already finalized");
    check_len("gravity", gravity.size(), 3);
    p->gravity = vec3(gravity);
    Force::Gravity(p->forces, p->matter, p->gravity);
    p->state = p->system.realizeTopology();
    p->system.realizeModel(p->state);
    p->system.realize(p->state, Stage::Instance);
    p->finalized = true;
}

std::int32_t SimbodySystem::nq() const {
    p->require_final("nq");
    return p->state.getNQ();
}

std::int32_t SimbodySystem::first_q_index(std::int32_t body) const {
    p->require_final("first_q_index");
    const MobilizedBody& mb = p->body(body);
    if (mb.getNumQ(p->state) == 0) return -1;
    return (std::int32_t)mb.getFirstQIndex(p->state);
}

void SimbodySystem::set_state(double t, rust::Slice<const double> q, rust::Slice<const double> u) {
    p->require_final("set_state");
    check_len("set_state q", q.size(), (std::size_t)p->state.getNQ());
    check_len("set_state u", u.size(), (std::size_t)p->state.getNU());
    p->state.setTime(t);
    Vector& sq = p->state.updQ();
    for (int i = 0; i < sq.size(); ++i) sq[i] = q[(std::size_t)i];
    Vector& su = p->state.updU();
    for (int i = 0; i < su.size(); ++i) su[i] = u[(std::size_t)i];
}

void SimbodySystem::get_state(rust::Slice<double> q, rust::Slice<double> u) const {
    p->require_final("get_state");
    check_len("get_state q", q.size(), (std::size_t)p->state.getNQ());
    check_len("get_state u", u.size(), (std::size_t)p->state.getNU());
    for (int i = 0; i < p->state.getNQ(); ++i) q[(std::size_t)i] = p->state.getQ()[i];
    for (int i = 0; i < p->state.getNU(); ++i) u[(std::size_t)i] = p->state.getU()[i];
}

double SimbodySystem::time() const { return p->state.getTime(); }

void SimbodySystem::calc_mass_matrix(rust::Slice<double> m) {
    p->require_final("calc_mass_matrix");
    const int n = p->state.getNU();
    check_len("mass matrix", m.size(), (std::size_t)(n * n));
    p->system.realize(p->state, Stage::Position);
    Matrix M;
    p->matter.calcM(p->state, M);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) m[(std::size_t)(i * n + j)] = M(i, j);
}

void SimbodySystem::calc_bias(rust::Slice<double> bias) {
    p->require_final("calc_bias");
    const int n = p->state.getNU();
    check_len("bias", bias.size(), (std::size_t)n);
    // Residual of M*0 + C - g with only gravity applied: the bias forces.
    p->system.realize(p->state, Stage::Velocity);
    Vector_<SpatialVec> gravity_forces(p->matter.getNumBodies(), SpatialVec(Vec3(0), Vec3(0)));
    const Vec3 g = p->gravity;
    for (MobilizedBodyIndex i(1); i < p->matter.getNumBodies(); ++i) {
        const MobilizedBody& mb = p->matter.getMobilizedBody(i);
        const MassProperties& mp = mb.getBodyMassProperties(p->state);
        const Vec3 com_G = mb.getBodyRotation(p->state) * mp.getMassCenter();
        const Vec3 f = mp.getMass() * g;
        gravity_forces[i] = SpatialVec(com_G % f, f);
    }
    Vector residual;
    p->matter.calcResidualForceIgnoringConstraints(p->state, Vector(), gravity_forces, Vector(), residual);
    for (int i = 0; i < n; ++i) bias[(std::size_t)i] = residual[i];
}

void SimbodySystem::set_applied_forces(rust::Slice<const double> tau,
                                       rust::Slice<const std::int32_t> bodies,
                                       rust::Slice<const double> points,
                                       rust::Slice<const double> forces) {
    p->require_final("set_applied_forces");
    check_len("tau", tau.size(), (std::size_t)p->state.getNU());
    check_len("points", points.size(), 3 * bodies.size());
    check_len("forces", forces.size(), 3 * bodies.size());
    for (std::size_t k = 0; k < bodies.size(); ++k) p->body(bodies[k]);  // validate first
    p->discrete.clearAllForces(p->state);
    Vector t(p->state.getNU());
    for (int i = 0; i < t.size(); ++i) t[i] = tau[(std::size_t)i];
    p->discrete.setAllMobilityForces(p->state, t);
    // Shifting a point force to the body origin needs the body's orientation.
    if (bodies.size() > 0) p->system.realize(p->state, Stage::Position);
    for (std::size_t k = 0; k < bodies.size(); ++k)
        p->discrete.addForceToBodyPoint(p->state, p->body(bodies[k]), vec3(points, 3 * k), vec3(forces, 3 * k));
}

void SimbodySystem::calc_udot(rust::Slice<double> udot) {
    p->require_final("calc_udot");
    check_len("udot", udot.size(), (std::size_t)p->state.getNU());
    p->system.realize(p->state, Stage::Acceleration);
    const Vector& ud = p->state.getUDot();
    for (int i = 0; i < ud.size(); ++i) udot[(std::size_t)i] = ud[i];
}

void SimbodySystem::station_position(std::int32_t body, rust::Slice<const double> point, rust::Slice<double> out) {
    p->require_final("station_position");
    check_len("point", point.size(), 3);
    check_len("out", out.size(), 3);
    const MobilizedBody& mb = p->body(body);
    p->system.realize(p->state, Stage::Position);
    const Vec3 r = mb.findStationLocationInGround(p->state, vec3(point));
    for (int i = 0; i < 3; ++i) out[(std::size_t)i] = r[i];
}

void SimbodySystem::station_velocity(std::int32_t body, rust::Slice<const double> point, rust::Slice<double> out) {
    p->require_final("station_velocity");
    check_len("point", point.size(), 3);
    check_len("out", out.size(), 3);
    const MobilizedBody& mb = p->body(body);
    p->system.realize(p->state, Stage::Velocity);
    const Vec3 v = mb.findStationVelocityInGround(p->state, vec3(point));
    for (int i = 0; i < 3; ++i) out[(std::size_t)i] = v[i];
}

void SimbodySystem::com_position(rust::Slice<double> out) {
    p->require_final("com_position");
    check_len("out", out.size(), 3);
    p->system.realize(p->state, Stage::Position);
    const Vec3 r = p->matter.calcSystemMassCenterLocationInGround(p->state);
    for (int i = 0; i < 3; ++i) out[(std::size_t)i] = r[i];
}

void SimbodySystem::com_velocity(rust::Slice<double> out) {
    p->require_final("com_velocity");
    check_len("out", out.size(), 3);
    p->system.realize(p->state, Stage::Velocity);
    const Vec3 v = p->matter.calcSystemMassCenterVelocityInGround(p->state);
    for (int i = 0; i < 3; ++i) out[(std::size_t)i] = v[i];
}

void SimbodySystem::com_acceleration(rust::Slice<double> out) {
    p->require_final("com_acceleration");
    check_len("out", out.size(), 3);
    p->system.realize(p->state, Stage::Acceleration);
    const Vec3 a = p->matter.calcSystemMassCenterAccelerationInGround(p->state);
    for (int i = 0; i < 3; ++i) out[(std::size_t)i] = a[i];
}

double SimbodySystem::total_mass() {
    p->require_final("total_mass");
    return p->matter.calcSystemMass(p->state);
}

double SimbodySystem::energy() {
    p->require_final("energy");
    p->system.realize(p->state, Stage::Dynamics);
    return p->system.calcEnergy(p->state);
}

namespace {
std::unique_ptr<Integrator> make_integrator(MultibodySystem& system, std::int32_t method, double accuracy) {
    if (!(accuracy > 0)) throw std::invalid_argument("integrator: accuracy must be positive");
    // Simbody's error-controlled integrators assert an accuracy below 1
    // (the process aborts); explicit Euler takes it as its step.
    if (method != 4 && !(accuracy < 1))
        throw std::invalid_argument("integrator: accuracy must be below 1");
    std::unique_ptr<Integrator> integ;
    switch (method) {
        case 0: integ.reset(new RungeKuttaMersonIntegrator(system)); break;
        case 1: integ.reset(new RungeKuttaFeldbergIntegrator(system)); break;
        case 2: integ.reset(new RungeKutta3Integrator(system)); break;
        case 3: integ.reset(new CPodesIntegrator(system, CPodes::BDF, CPodes::Newton)); break;
        case 4: integ.reset(new ExplicitEulerIntegrator(system, accuracy)); break;
        default: throw std::invalid_argument("integrator: unknown method " + std::to_string(method));
    }
    if (method != 4) integ->setAccuracy(accuracy);
    else integ->setFixedStepSize(accuracy);  // explicit Euler: fixed step
    return integ;
}

IntegratorStats stats_of(const Integrator& integ, double t) {
    IntegratorStats s;
    s.steps_taken = integ.getNumStepsTaken();
    s.steps_attempted = integ.getNumStepsAttempted();
    s.realizations = integ.getNumRealizations();
    s.error_test_failures = integ.getNumErrorTestFailures();
    s.final_time = t;
    return s;
}
}  // namespace

void SimbodySystem::integration_start(std::int32_t method, double accuracy, double min_step, double max_step,
                                      std::int32_t max_steps) {
    p->require_final("integration_start");
    p->stepper.reset();
    p->max_steps = max_steps;
    p->integ = make_integrator(p->system, method, accuracy);
    if (method != 4) {
        if (min_step > 0) p->integ->setMinimumStepSize(min_step);
        if (max_step > 0) p->integ->setMaximumStepSize(max_step);
    }
    p->integ->setAllowInterpolation(false);
    p->stepper.reset(new TimeStepper(p->system, *p->integ));
    // Return to the loop below at the integrator's step limit instead of
    // stepping on inside TimeStepper::stepTo.
    p->stepper->setReportAllSignificantStates(true);
    p->stepper->initialize(p->state);
}

IntegratorStats SimbodySystem::integration_step_to(double t) {
    if (!p->stepper) throw std::logic_error("integration_step_to: call integration_start first");
    if (!(t >= p->integ->getTime())) throw std::invalid_argument("integration_step_to: time goes backwards");
    while (p->integ->getTime() < t) {
        if (p->max_steps > 0) {
            // A stiff model (say, a contact transition velocity of 1e-6 m/s)
            // would otherwise take steps without end. (CPodes reads the
            // internal limit only when initialised; this check still stops
            // it between reports.)
            const int used = p->integ->getNumStepsAttempted();
            if (used >= p->max_steps)
                throw std::runtime_error("the step limit of " + std::to_string(p->max_steps) +
                                         " integrator steps reached at t = " +
                                         std::to_string(p->integ->getTime()) +
                                         " s: the model is too stiff to integrate at this accuracy");
            p->integ->setInternalStepLimit(p->max_steps - used);
        }
        const Integrator::SuccessfulStepStatus st = p->stepper->stepTo(t);
        if (st == Integrator::EndOfSimulation) break;
        if (p->integ->isSimulationOver()) break;
    }
    p->state = p->integ->getState();
    return stats_of(*p->integ, p->state.getTime());
}

IntegratorStats SimbodySystem::integrate(std::int32_t method, double accuracy, double t_final) {
    p->require_final("integrate");
    if (!(accuracy > 0)) throw std::invalid_argument("integrate: accuracy must be positive");
    if (!(t_final >= p->state.getTime())) throw std::invalid_argument("integrate: t_final is before the current time");
    std::unique_ptr<Integrator> integ = make_integrator(p->system, method, accuracy);
    TimeStepper ts(p->system, *integ);
    ts.initialize(p->state);
    ts.stepTo(t_final);
    p->state = integ->getState();
    return stats_of(*integ, p->state.getTime());
}

void SimbodySystem::throw_for_test(std::int32_t kind) {
    if (kind == 0) {
        p->require_final("throw_for_test");
        State s = p->system.getDefaultState();  // realized to Model only
        Matrix M;
        p->matter.calcM(s, M);
    }
    if (kind == 1) SimTK_THROW1(Exception::Cant, "thrown on purpose from the facade");
    throw std::runtime_error("plain std::runtime_error");
}

}  // namespace leap
