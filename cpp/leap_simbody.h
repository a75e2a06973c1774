// The C++ facade over Simbody that leap's Rust code drives through cxx.
// No Simbody type appears here (pimpl); data cross as slices of doubles.
// Every method that can reach Simbody is declared `-> Result` on the Rust
// side, so a thrown exception becomes an `Err`.
#pragma once
#include "rust/cxx.h"
#include <cstdint>
#include <memory>

namespace leap {

struct IntegratorStats;
struct ForceCallback;

// What the Rust force callback sees while Simbody computes forces: point
// kinematics at the state being realized (Velocity stage) and places to put
// forces. Only valid during the callback.
class ForceCtx {
public:
    struct Inner;
    explicit ForceCtx(Inner* in) : in(in) {}
    void station_position(std::int32_t body, rust::Slice<const double> point, rust::Slice<double> out) const;
    void station_velocity(std::int32_t body, rust::Slice<const double> point, rust::Slice<double> out) const;
    void express_in_ground(std::int32_t body, rust::Slice<const double> v, rust::Slice<double> out) const;
    void express_in_body(std::int32_t body, rust::Slice<const double> v, rust::Slice<double> out) const;
    void add_station_force(std::int32_t body, rust::Slice<const double> point, rust::Slice<const double> force);
    void add_mobility_force(std::int32_t u_index, double force);
private:
    Inner* in;
};

class SimbodySystem {
public:
    SimbodySystem();
    ~SimbodySystem();
    SimbodySystem(const SimbodySystem&) = delete;
    SimbodySystem& operator=(const SimbodySystem&) = delete;

    // Building (before finalize). Body indices count from 1 (0 is ground) in
    // the order of creation. kind: 0 planar, 1 pin, 2 translating hinge, 3 weld.
    // inertia: about the centre of mass, [Ixx, Iyy, Izz, Ixy, Ixz, Iyz].
    // For kind 2, spline_x/spline_y are (x, y, b, c, d) blocks of equal length.
    std::int32_t add_body(std::int32_t parent, std::int32_t kind,
                          rust::Slice<const double> location, double mass,
                          rust::Slice<const double> mass_center,
                          rust::Slice<const double> inertia,
                          rust::Slice<const double> spline_x,
                          rust::Slice<const double> spline_y);
    // Install the Rust force element with nz auxiliary (z) states that
    // Simbody integrates along with q and u. Before finalize.
    void add_rust_force(rust::Box<ForceCallback> callback, std::int32_t nz);
    void finalize(rust::Slice<const double> gravity);

    std::int32_t nq() const;
    std::int32_t first_q_index(std::int32_t body) const;

    // State (Simbody's q and u order).
    void set_state(double t, rust::Slice<const double> q, rust::Slice<const double> u);
    void get_state(rust::Slice<double> q, rust::Slice<double> u) const;
    double time() const;
    // Auxiliary states of the Rust force element and their derivatives.
    void set_z(rust::Slice<const double> z);
    void get_z(rust::Slice<double> z) const;
    void calc_zdot(rust::Slice<double> zdot);

    // Dynamics quantities at the current state.
    void calc_mass_matrix(rust::Slice<double> m_row_major);
    void calc_bias(rust::Slice<double> bias);
    // Applied forces stay in the State until changed: mobility forces tau and
    // point forces (body index, point in body frame, force in ground; 3 per).
    void set_applied_forces(rust::Slice<const double> tau,
                            rust::Slice<const std::int32_t> bodies,
                            rust::Slice<const double> points,
                            rust::Slice<const double> forces);
    void calc_udot(rust::Slice<double> udot);
    void station_position(std::int32_t body, rust::Slice<const double> point, rust::Slice<double> out);
    void station_velocity(std::int32_t body, rust::Slice<const double> point, rust::Slice<double> out);
    void com_position(rust::Slice<double> out);
    void com_velocity(rust::Slice<double> out);
    void com_acceleration(rust::Slice<double> out);
    double total_mass();
    double energy();

    // Integrate from the current state to t_final with the applied forces
    // held constant. method: 0 RungeKuttaMerson, 1 RungeKuttaFeldberg,
    // 2 RungeKutta3, 3 CPodes, 4 explicit Euler (fixed step = accuracy).
    IntegratorStats integrate(std::int32_t method, double accuracy, double t_final);
    // A persistent integration: start from the current state, then advance
    // to successive times (the integrator keeps its step size between them).
    // min_step/max_step <= 0 leave Simbody's defaults; max_steps > 0 caps
    // the steps attempted (integration_step_to then throws).
    void integration_start(std::int32_t method, double accuracy, double min_step, double max_step,
                           std::int32_t max_steps);
    IntegratorStats integration_step_to(double t);

    // For tests of the bridge itself: throws a SimTK or std exception.
    void throw_for_test(std::int32_t kind);

    struct Impl;
private:
    std::unique_ptr<Impl> p;
};

std::unique_ptr<SimbodySystem> new_simbody_system();

}  // namespace leap
