#!/usr/bin/env python3
"""Export models/jumper_gait2392.json to an OpenSim model
(models/jumper_gait2392.osim) and compute golden reference values with
OpenSim 4.6 itself:

- muscle-tendon lengths, lengthening speeds and moment arms of all 48 muscle
  paths at the standing and squat poses and at random poses and speeds;
- the knee SimmSplines (value, first and second derivative).

Results go to tests/data/opensim_paths.json, which tests/paths_opensim.rs
compares leap against. Needs `opensim==4.6` from PyPI, e.g.

    python3 -m venv .venv && .venv/bin/pip install opensim==4.6
    .venv/bin/python scripts/jumper_osim.py

(run from the repository root). With a model file as argument it only exports
that model beside it, e.g. `scripts/jumper_osim.py models/jumper.json` writes
models/jumper.osim, leap's default model for OpenSim's GUI and tools.
"""
import json
import math
import pathlib
import random
import sys

import opensim as osim

ROOT = pathlib.Path(__file__).resolve().parent.parent


def vec3(v):
    return osim.Vec3(float(v[0]), float(v[1]), float(v[2]))


def simm_spline(d):
    f = osim.SimmSpline()
    for x, y in zip(d["x"], d["y"]):
        f.addPoint(float(x), float(y))
    return f


def coordinate_paths(model_json):
    """OpenSim component path of each coordinate: /jointset/<joint>/<coordinate>."""
    out = {}
    for j in model_json["joints"]:
        for c in j.get("coordinates", [j["coordinate"]] if "coordinate" in j else []):
            out[c] = f"/jointset/{j['name']}/{c}"
    return out


def build(model_json):
    cpath = coordinate_paths(model_json)
    m = osim.Model()
    m.setName(model_json["name"])
    m.setGravity(vec3(model_json["gravity"]))
    bodies = {}
    for b in model_json["bodies"]:
        i = b["inertia"]
        body = osim.Body(b["name"], b["mass"], vec3(b["mass_center"]), osim.Inertia(*[float(v) for v in i]))
        m.addBody(body)
        bodies[b["name"]] = body
    frame = lambda name: m.getGround() if name == "ground" else bodies[name]
    coords = {c["name"]: c for c in model_json["coordinates"]}
    custom_coords = []

    def set_coord(joint, k, name):
        c = joint.upd_coordinates(k)
        c.setName(name)
        c.setRangeMin(coords[name]["range"][0])
        c.setRangeMax(coords[name]["range"][1])
        c.setDefaultValue(coords[name]["default_value"])

    for j in model_json["joints"]:
        loc = vec3(j["location_in_parent"])
        zero = osim.Vec3(0, 0, 0)
        parent, child = frame(j["parent"]), bodies[j["child"]]
        t = j["type"]
        if t == "weld":
            joint = osim.WeldJoint(j["name"], parent, loc, zero, child, zero, zero)
        elif t == "pin":
            joint = osim.PinJoint(j["name"], parent, loc, zero, child, zero, zero)
            set_coord(joint, 0, j["coordinate"])
        elif t in ("planar", "translating_hinge"):
            st = osim.SpatialTransform()
            axes = [st.upd_rotation1(), st.upd_rotation2(), st.upd_rotation3(),
                    st.upd_translation1(), st.upd_translation2(), st.upd_translation3()]
            dirs = [(0, 0, 1), (1, 0, 0), (0, 1, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
            for ax, d in zip(axes, dirs):
                ax.setAxis(vec3(d))
            names = []
            if t == "planar":
                rot, tx, ty = j["coordinates"]
                for ax, cname in ((axes[0], rot), (axes[3], tx), (axes[4], ty)):
                    ax.append_coordinates(cname)
                    ax.set_function(osim.LinearFunction(1.0, 0.0))
                names = [rot, tx, ty]
            else:
                cname = j["coordinate"]
                for ax, fn in ((axes[0], osim.LinearFunction(1.0, 0.0)),
                               (axes[3], simm_spline(j["translation_x"])),
                               (axes[4], simm_spline(j["translation_y"]))):
                    ax.append_coordinates(cname)
                    ax.set_function(fn)
                names = [cname]
            for ax in (axes[1], axes[2], axes[5]):
                ax.set_function(osim.Constant(0.0))
            joint = osim.CustomJoint(j["name"], parent, loc, zero, child, zero, zero, st)
            custom_coords.extend(names)
        else:
            raise ValueError(t)
        m.addJoint(joint)

    # CustomJoint coordinates exist once the model is finalized.
    m.finalizeFromProperties()
    for n in custom_coords:
        c = m.updCoordinateSet().get(n)
        c.setRangeMin(coords[n]["range"][0])
        c.setRangeMax(coords[n]["range"][1])
        c.setDefaultValue(coords[n]["default_value"])
    forces = model_json.get("forces", {})
    for mu in forces.get("muscles", []):
        muscle = osim.Thelen2003Muscle(mu["name"], mu["max_isometric_force"], mu["optimal_fiber_length"],
                                       mu["tendon_slack_length"], mu["pennation_angle_at_optimal"])
        muscle.set_max_contraction_velocity(mu["max_contraction_velocity"])
        muscle.set_activation_time_constant(mu["activation_time_constant"])
        muscle.set_deactivation_time_constant(mu["deactivation_time_constant"])
        muscle.set_FmaxTendonStrain(mu["FmaxTendonStrain"])
        muscle.set_FmaxMuscleStrain(mu["FmaxMuscleStrain"])
        muscle.set_KshapeActive(mu["KshapeActive"])
        muscle.set_KshapePassive(mu["KshapePassive"])
        muscle.set_Af(mu["Af"])
        muscle.set_Flen(mu["Flen"])
        pps = muscle.updGeometryPath().updPathPointSet()
        for k, p in enumerate(mu["path"]):
            name = f"{mu['name']}-P{k + 1}"
            body = bodies[p["body"]]
            if p["type"] == "fixed":
                pt = osim.PathPoint()
                pt.setName(name)
                pt.setParentFrame(body)
                pt.set_location(vec3(p["location"]))
            elif p["type"] == "conditional":
                pt = osim.ConditionalPathPoint()
                pt.setName(name)
                pt.setParentFrame(body)
                pt.set_location(vec3(p["location"]))
                pt.setRangeMin(p["range"][0])
                pt.setRangeMax(p["range"][1])
                pt.updSocket("coordinate").setConnecteePath(cpath[p["coordinate"]])
            else:
                pt = osim.MovingPathPoint()
                pt.setName(name)
                pt.setParentFrame(body)
                pt.set_x_location(simm_spline(p["x_location"]))
                pt.set_y_location(simm_spline(p["y_location"]))
                pt.set_z_location(simm_spline(p["z_location"]))
                for ax in ("x", "y", "z"):
                    pt.updSocket(f"{ax}_coordinate").setConnecteePath(cpath[p["coordinate"]])
            pt.updSocket("parent_frame").setConnecteePath(f"/bodyset/{p['body']}")
            pps.cloneAndAppend(pt)
        m.addForce(muscle)
    m.finalizeConnections()
    for lig in forces.get("ligaments", []):
        e = "{k1}*exp({k2}*(q-({t2})))+{k3}*exp({k4}*(q-({t1})))-{d}*qdot".format(
            k1=lig["k1"], k2=lig["k2"], k3=lig["k3"], k4=lig["k4"], t1=lig["theta1"], t2=lig["theta2"], d=lig["damping"])
        f = osim.ExpressionBasedCoordinateForce(lig["coordinate"], e)
        f.setName("passive_" + lig["coordinate"])
        m.addForce(f)
    contact = forces.get("contact")
    if contact:
        floor = osim.ContactHalfSpace(osim.Vec3(0, 0, 0), osim.Vec3(0, 0, -math.pi / 2), m.getGround(), "floor")
        m.addContactGeometry(floor)
        for s in contact["spheres"]:
            sph = osim.ContactSphere(s["radius"], vec3(s["location"]), bodies[s["body"]], s["name"])
            m.addContactGeometry(sph)
            if contact["law"] == "HuntCrossleyForce":
                hc = osim.HuntCrossleyForce()
                hc.setName("contact_" + s["name"])
                hc.addGeometry(s["name"])
                hc.addGeometry("floor")
                hc.setStiffness(contact["stiffness"])
                hc.setDissipation(contact["dissipation"])
                hc.setStaticFriction(contact["static_friction"])
                hc.setDynamicFriction(contact["dynamic_friction"])
                hc.setViscousFriction(contact["viscous_friction"])
                hc.setTransitionVelocity(contact["transition_velocity"])
            else:
                hc = osim.SmoothSphereHalfSpaceForce("contact_" + s["name"], sph, floor)
                hc.set_stiffness(contact["stiffness"])
                hc.set_dissipation(contact["dissipation"])
                hc.set_static_friction(contact["static_friction"])
                hc.set_dynamic_friction(contact["dynamic_friction"])
                hc.set_viscous_friction(contact["viscous_friction"])
                hc.set_transition_velocity(contact["transition_velocity"])
            m.addForce(hc)
    m.finalizeConnections()
    return m


def main():
    if len(sys.argv) > 1:
        src = pathlib.Path(sys.argv[1])
        m = build(json.loads(src.read_text()))
        m.printToXML(str(src.with_suffix(".osim")))
        m.initSystem()
        print(f"wrote {src.with_suffix('.osim')}")
        return
    model_json = json.loads((ROOT / "models" / "jumper_gait2392.json").read_text())
    m = build(model_json)
    m.printToXML(str(ROOT / "models" / "jumper_gait2392.osim"))
    state = m.initSystem()
    cs = m.getCoordinateSet()
    names = [c["name"] for c in model_json["coordinates"]]
    rng = random.Random(20261124)
    poses = []
    for label, values in (("standing", model_json["poses"]["standing"]), ("squat", model_json["poses"]["squat"])):
        q = {c["name"]: c["default_value"] for c in model_json["coordinates"]}
        q.update(values)
        poses.append((label, q, {n: 0.0 for n in names}))
    for k in range(12):
        q = {}
        for c in model_json["coordinates"]:
            lo, hi = c["range"]
            if c["name"] in ("pelvis_tx", "pelvis_ty"):
                lo, hi = -0.5, 1.0
            if c["name"].startswith("knee"):
                lo, hi = -2.0, 0.1
            q[c["name"]] = rng.uniform(lo, hi)
        u = {n: rng.uniform(-3.0, 3.0) for n in names}
        poses.append((f"random{k}", q, u))
    out = {"opensim_version": osim.GetVersionAndDate(), "model": "models/jumper_gait2392.json (exported to models/jumper_gait2392.osim)",
           "poses": []}
    muscles = [mu["name"] for mu in model_json["forces"]["muscles"]]
    for label, q, u in poses:
        for n in names:
            cs.get(n).setValue(state, q[n], False)
        for n in names:
            cs.get(n).setSpeedValue(state, u[n])
        m.realizeVelocity(state)
        rows = {}
        for mn in muscles:
            mus = osim.Muscle.safeDownCast(m.getForceSet().get(mn))
            path = mus.getGeometryPath()
            rows[mn] = {
                "length": path.getLength(state),
                "lengthening_speed": path.getLengtheningSpeed(state),
                "moment_arms": {n: path.computeMomentArm(state, cs.get(n)) for n in names},
            }
        out["poses"].append({"name": label, "q": q, "u": u, "muscles": rows})
    # Knee splines.
    knee = next(j for j in model_json["joints"] if j["name"] == "knee_r")
    spl = {}
    for key in ("translation_x", "translation_y"):
        f = simm_spline(knee[key])
        xs = [-2.3, -2.0944, -1.9, -1.3962634, -1.0, -0.5, -0.2, 0.0, 0.1, 0.174533, 0.3]
        vals = []
        for x in xs:
            v = osim.Vector(1, x)
            d1 = osim.StdVectorInt(); d1.push_back(0)
            d2 = osim.StdVectorInt(); d2.push_back(0); d2.push_back(0)
            vals.append([x, f.calcValue(v), f.calcDerivative(d1, v), f.calcDerivative(d2, v)])
        spl[key] = vals
    out["knee_r_splines"] = spl
    path = ROOT / "tests" / "data" / "opensim_paths.json"
    path.write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {path} and models/jumper_gait2392.osim ({len(out['poses'])} poses, {len(muscles)} muscles)")


if __name__ == "__main__":
    sys.exit(main())
