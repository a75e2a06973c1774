#!/usr/bin/env python3
"""Golden reference values for leap's force laws, computed by OpenSim 4.6.
(Whether OpenSim reads leap's output files: scripts/opensim_reads_leap_files.py.)

Writes tests/data/opensim_forces.json with
- Thelen2003Muscle tendon force, fibre velocity, force-velocity multiplier,
  pennation angle and activation rate over a grid of muscle-tendon lengths,
  lengthening speeds, fibre lengths, activations and excitations, for both
  parameter sets (OpenSim defaults and the legacy 3.x values the jumper
  carries) and two pennation angles; static equilibrium fibre lengths
  (Model::equilibrateMuscles);
- HuntCrossleyForce and SmoothSphereHalfSpaceForce on a sphere over a grid of
  penetrations, velocities and spins, for two parameter sets;
- the jumper's passive joint torques as ExpressionBasedCoordinateForces.

    python3 -m venv .venv && .venv/bin/pip install opensim==4.6
    .venv/bin/python scripts/reference_opensim.py
"""
import itertools
import json
import math
import pathlib
import sys

import opensim as osim

ROOT = pathlib.Path(__file__).resolve().parent.parent
DEFAULTS = dict(FmaxTendonStrain=0.04, KshapeActive=0.45, KshapePassive=5.0, Af=0.25, Flen=1.4, tau_act=0.015, tau_deact=0.05)
LEGACY = dict(FmaxTendonStrain=0.033, KshapeActive=0.5, KshapePassive=4.0, Af=0.3, Flen=1.8, tau_act=0.01, tau_deact=0.04)


def muscle_model(penn, p):
    m = osim.Model()
    m.setGravity(osim.Vec3(0))
    b = osim.Body("block", 1.0, osim.Vec3(0), osim.Inertia(0.01))
    m.addBody(b)
    j = osim.SliderJoint("slider", m.getGround(), osim.Vec3(0), osim.Vec3(0), b, osim.Vec3(0), osim.Vec3(0))
    m.addJoint(j)
    mus = osim.Thelen2003Muscle("mus", 1000.0, 0.1, 0.2, penn)
    mus.set_FmaxTendonStrain(p["FmaxTendonStrain"])
    mus.set_KshapeActive(p["KshapeActive"])
    mus.set_KshapePassive(p["KshapePassive"])
    mus.set_Af(p["Af"])
    mus.set_Flen(p["Flen"])
    mus.set_activation_time_constant(p["tau_act"])
    mus.set_deactivation_time_constant(p["tau_deact"])
    mus.addNewPathPoint("o", m.updGround(), osim.Vec3(0))
    mus.addNewPathPoint("i", b, osim.Vec3(0))
    m.addForce(mus)
    s = m.initSystem()
    return m, s, mus, j.updCoordinate()


def muscles():
    out = []
    for label, p in (("defaults", DEFAULTS), ("legacy", LEGACY)):
        for penn in (0.0, 0.3):
            m, s, mus, c = muscle_model(penn, p)
            rows = []
            for lmt, vmt, lm, a, u in itertools.product((0.27, 0.29, 0.30, 0.31, 0.33), (-1.0, 0.0, 0.6),
                                                         (0.06, 0.09, 0.1, 0.12), (0.05, 0.5, 1.0), (0.02, 0.7)):
                c.setValue(s, lmt, False)
                c.setSpeedValue(s, vmt)
                mus.setActivation(s, a)
                mus.setFiberLength(s, lm)
                m.realizeVelocity(s)
                ctrl = m.updControls(s)
                ctrl.set(0, u)
                m.setControls(s, ctrl)
                m.realizeAcceleration(s)
                rows.append([lmt, vmt, lm, a, u, mus.getTendonForce(s), mus.getFiberVelocity(s),
                             mus.getForceVelocityMultiplier(s), mus.getPennationAngle(s),
                             mus.getStateVariableDerivativeValue(s, "activation")])
            eq = []
            for lmt, a in itertools.product((0.27, 0.28, 0.29, 0.30, 0.31, 0.32), (0.02, 0.3, 1.0)):
                c.setValue(s, lmt, False)
                c.setSpeedValue(s, 0.0)
                mus.setActivation(s, a)
                m.equilibrateMuscles(s)
                m.realizeVelocity(s)
                eq.append([lmt, a, mus.getFiberLength(s), mus.getTendonForce(s)])
            out.append({"parameters": label, "params": p, "pennation_angle_at_optimal": penn,
                        "columns": ["lmt", "vmt", "lm", "a", "u", "tendon_force", "fiber_velocity", "fv", "pennation", "adot"],
                        "rows": rows, "equilibrium_columns": ["lmt", "a", "lm", "tendon_force"], "equilibrium": eq})
    return out


def degroote():
    """DeGrooteFregly2016Muscle on the slider: OpenSim's state is the
    normalised tendon force; it reports the fibre length and velocity that
    leap's fibre-length formulation must reproduce."""
    out = []
    for penn in (0.0, 0.3):
        m = osim.Model()
        m.setGravity(osim.Vec3(0))
        b = osim.Body("block", 1.0, osim.Vec3(0), osim.Inertia(0.01))
        m.addBody(b)
        j = osim.SliderJoint("slider", m.getGround(), osim.Vec3(0), osim.Vec3(0), b, osim.Vec3(0), osim.Vec3(0))
        m.addJoint(j)
        mus = osim.DeGrooteFregly2016Muscle()
        mus.setName("mus")
        mus.set_max_isometric_force(1000.0)
        mus.set_optimal_fiber_length(0.1)
        mus.set_tendon_slack_length(0.2)
        mus.set_pennation_angle_at_optimal(penn)
        mus.set_tendon_strain_at_one_norm_force(0.033)
        mus.set_activation_time_constant(0.01)
        mus.set_deactivation_time_constant(0.04)
        mus.addNewPathPoint("o", m.updGround(), osim.Vec3(0))
        mus.addNewPathPoint("i", b, osim.Vec3(0))
        m.addForce(mus)
        s = m.initSystem()
        c = j.updCoordinate()
        rows = []
        for lmt, vmt, ftn, a, u in itertools.product((0.28, 0.3, 0.31), (-0.5, 0.0, 0.4), (0.1, 0.5, 1.0), (0.1, 0.6, 1.0), (0.0, 0.8)):
            c.setValue(s, lmt, False)
            c.setSpeedValue(s, vmt)
            mus.setStateVariableValue(s, "activation", a)
            mus.setStateVariableValue(s, "normalized_tendon_force", ftn)
            m.realizeVelocity(s)
            ctrl = m.updControls(s)
            ctrl.set(0, u)
            m.setControls(s, ctrl)
            m.realizeAcceleration(s)
            rows.append([lmt, vmt, a, u, mus.getFiberLength(s), mus.getFiberVelocity(s), mus.getTendonForce(s),
                         mus.getPennationAngle(s), mus.getStateVariableDerivativeValue(s, "activation")])
        out.append({"pennation_angle_at_optimal": penn, "tendon_strain_at_one_norm_force": 0.033,
                    "activation_time_constant": 0.01, "deactivation_time_constant": 0.04,
                    "columns": ["lmt", "vmt", "a", "u", "fiber_length", "fiber_velocity", "tendon_force", "pennation", "adot"],
                    "rows": rows})
    return out


def contact_model(law, E, cdiss, us, ud, uv, vt, R):
    m = osim.Model()
    m.setGravity(osim.Vec3(0))
    b = osim.Body("ball", 1.0, osim.Vec3(0), osim.Inertia(0.001))
    m.addBody(b)
    j = osim.PlanarJoint("pj", m.getGround(), osim.Vec3(0), osim.Vec3(0), b, osim.Vec3(0), osim.Vec3(0))
    m.addJoint(j)
    sph = osim.ContactSphere(R, osim.Vec3(0), b, "sph")
    floor = osim.ContactHalfSpace(osim.Vec3(0), osim.Vec3(0, 0, -0.5 * math.pi), m.getGround(), "floor")
    m.addContactGeometry(sph)
    m.addContactGeometry(floor)
    if law == "HuntCrossleyForce":
        f = osim.HuntCrossleyForce()
        f.setStiffness(E)
        f.setDissipation(cdiss)
        f.setStaticFriction(us)
        f.setDynamicFriction(ud)
        f.setViscousFriction(uv)
        f.setTransitionVelocity(vt)
        f.addGeometry("sph")
        f.addGeometry("floor")
    else:
        f = osim.SmoothSphereHalfSpaceForce("f", sph, floor)
        f.set_stiffness(E)
        f.set_dissipation(cdiss)
        f.set_static_friction(us)
        f.set_dynamic_friction(ud)
        f.set_viscous_friction(uv)
        f.set_transition_velocity(vt)
    m.addForce(f)
    s = m.initSystem()
    return m, s, f, j


def contacts():
    out = []
    sets = [(1e6, 1.0, 0.9, 0.6, 0.1, 0.01), (3777162.0, 2.0, 0.8, 0.8, 0.5, 0.1)]
    for law in ("HuntCrossleyForce", "SmoothSphereHalfSpaceForce"):
        for E, cd, us, ud, uv, vt in sets:
            R = 0.032
            m, s, f, j = contact_model(law, E, cd, us, ud, uv, vt, R)
            rows = []
            for depth, vy, vx, w in itertools.product((-0.002, 0.0005, 0.002, 0.006), (-0.4, 0.0, 0.3), (-0.5, 0.0, 0.003, 0.2), (0.0, 4.0)):
                j.getCoordinate(0).setValue(s, 0.0, False)
                j.getCoordinate(1).setValue(s, 0.0, False)
                j.getCoordinate(2).setValue(s, R - depth, False)
                j.getCoordinate(0).setSpeedValue(s, w)
                j.getCoordinate(1).setSpeedValue(s, vx)
                j.getCoordinate(2).setSpeedValue(s, vy)
                m.realizeDynamics(s)
                la = f.getRecordLabels()
                va = f.getRecordValues(s)
                labels = [la.get(i) for i in range(la.getSize())]
                vals = [va.get(i) for i in range(va.getSize())]
                # The first six records are the force and torque (about the
                # body origin = sphere centre) on the sphere's body.
                assert labels[0].endswith("force.X") and labels[5].endswith("torque.Z"), labels
                rows.append([depth, vy, vx, w, vals[0], vals[1], vals[5]])
            out.append({"law": law, "radius": R, "stiffness": E, "dissipation": cd, "static_friction": us,
                        "dynamic_friction": ud, "viscous_friction": uv, "transition_velocity": vt,
                        "columns": ["depth", "vy", "vx", "omega_z", "fx_on_sphere", "fy_on_sphere", "torque_z_about_centre"], "rows": rows})
    return out


def ligaments():
    model_json = json.loads((ROOT / "models" / "jumper_gait2392.json").read_text())
    out = []
    for lig in model_json["forces"]["ligaments"]:
        m = osim.Model()
        b = osim.Body("b", 1.0, osim.Vec3(0), osim.Inertia(0.01))
        m.addBody(b)
        j = osim.PinJoint("pin", m.getGround(), osim.Vec3(0), osim.Vec3(0), b, osim.Vec3(0), osim.Vec3(0))
        j.updCoordinate().setName("q")
        m.addJoint(j)
        e = "{k1}*exp({k2}*(q-({t2})))+{k3}*exp({k4}*(q-({t1})))-{d}*qdot".format(
            k1=lig["k1"], k2=lig["k2"], k3=lig["k3"], k4=lig["k4"], t1=lig["theta1"], t2=lig["theta2"], d=lig["damping"])
        f = osim.ExpressionBasedCoordinateForce("q", e)
        m.addForce(f)
        s = m.initSystem()
        rows = []
        for q, qd in itertools.product((-2.0, -1.2, -0.5, 0.0, 0.3, 1.0, 1.6), (-3.0, 0.0, 2.0)):
            j.updCoordinate().setValue(s, q, False)
            j.updCoordinate().setSpeedValue(s, qd)
            m.realizeDynamics(s)
            rows.append([q, qd, f.getForceMagnitude(s)])
        out.append({"coordinate": lig["coordinate"], "expression": e, "rows": rows})
    return out


def main():
    out = {"opensim_version": osim.GetVersionAndDate(), "thelen": muscles(), "degroote": degroote(), "contact": contacts(), "ligaments": ligaments()}
    path = ROOT / "tests" / "data" / "opensim_forces.json"
    path.write_text(json.dumps(out) + "\n")
    print(f"wrote {path}")
    return 0

if __name__ == "__main__":
    sys.exit(main())
