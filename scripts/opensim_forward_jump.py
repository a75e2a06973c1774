#!/usr/bin/env python3
"""OpenSim 4.6's own forward simulation of a predicted jump: golden data for
tests/opensim_forward.rs.

leap's forward check integrates a solution's excitations with Simbody through
leap's own model code. This script integrates the same excitations with
OpenSim itself, on models/jumper.osim (the export of models/jumper.json by
scripts/jumper_osim.py): OpenSim's Thelen2003Muscle, HuntCrossleyForce,
ExpressionBasedCoordinateForce and CustomJoint, both legs, no symmetry
imposed. What it writes is therefore an independent reference for the whole
forward model, not only for its parts.

    python3 -m venv .venv && .venv/bin/pip install opensim==4.6
    cargo build --release
    .venv/bin/python scripts/opensim_forward_jump.py [CONTROLS.sto]

CONTROLS.sto defaults to tests/data/controls/jump_optimal.sto, the excitations
at the 29 nodes of leap's default solve (`leap solve`; `/forceset/<muscle>_r`
columns, linear between nodes, held after the last node; a left muscle
without its own column takes its right partner's excitation). The initial state is leap's static
squat, read from `leap simulate --controls CONTROLS.sto` (row 0 of its
states file), since OpenSim has no squat solver; the script checks it is at
rest in OpenSim too (coordinate accelerations, and OpenSim's own muscle
equilibrium against leap's fibre lengths). OpenSim integrates with
RungeKuttaMerson at accuracy 1e-8 (at `leap simulate`'s default 1e-5 the
integrator's own error is some 3e-5 m in the jump height, the same in leap
and OpenSim, and would hide model differences of that size), to lift-off as
`leap simulate` defines it: the first time the total vertical ground force
is zero (every sphere off the ground), located by bisection like leap's.

Writes tests/data/opensim_forward_jump.json (samples every millisecond of the
push-off, lift-off and jump height) and prints OpenSim's numbers beside
leap's.
"""
import json
import pathlib
import subprocess
import sys
import tempfile

import opensim as osim

ROOT = pathlib.Path(__file__).resolve().parent.parent
ACCURACY = 1e-8
SAMPLE = 1e-3
BISECTIONS = 30  # of the millisecond in which the ground force vanishes: 1e-12 s


def read_sto(path):
    lines = pathlib.Path(path).read_text().splitlines()
    end = next(i for i, l in enumerate(lines) if l.strip() == "endheader")
    labels = lines[end + 1].split("\t")
    rows = [[float(v) for v in l.split("\t")] for l in lines[end + 2:] if l.strip()]
    return labels, rows


def vertical_contact_force(model, s, side=None):
    """The vertical force of the ground on the feet (N) at state s, realized
    to Dynamics: the contact forces' records on the spheres' bodies, of
    every foot, or with side "r" or "l" of the forces named *_<side>."""
    total = 0.0
    forces = model.getForceSet()
    for i in range(forces.getSize()):
        f = forces.get(i)
        if f.getConcreteClassName() not in ("HuntCrossleyForce", "SmoothSphereHalfSpaceForce"):
            continue
        if side is not None and not f.getName().endswith("_" + side):
            continue
        labels = f.getRecordLabels()
        values = f.getRecordValues(s)
        for j in range(labels.getSize()):
            lab = labels.get(j)
            if lab.endswith(".force.Y") and ".ground." not in lab:
                total += values.get(j)
    return total


def mirror(name):
    """The left partner of a right-side name (coordinate or muscle)."""
    return name[:-2] + "_l" if name.endswith("_r") else None


def leap_simulate(controls, accuracy):
    """`leap simulate --controls CONTROLS` at the given accuracy: its JSON
    summary and row 0 of its states file (leap's static squat, by label)."""
    with tempfile.TemporaryDirectory() as out:
        run = subprocess.run([str(ROOT / "target/release/leap"), "simulate", "--controls", str(controls),
                              "--accuracy", str(accuracy), "--out", out, "--json"], capture_output=True, text=True, check=True)
        labels, rows = read_sto(pathlib.Path(out) / "forward_states.sto")
    return json.loads(run.stdout), dict(zip(labels, rows[0]))


def prescribe_excitations(model, controls):
    """Add a PrescribedController to model that plays the excitations of
    the controls file (`/forceset/<muscle>` columns, linear between rows,
    held after the last)."""
    clabels, crows = read_sto(controls)
    ctrl = osim.PrescribedController()
    ctrl.setName("leap_excitations")
    muscles = model.getMuscles()
    in_file = {label.split("/")[-1] for label in clabels[1:]}
    for k, label in enumerate(clabels[1:], start=1):
        name = label.split("/")[-1]
        # A left muscle takes its own column where the file has one (leap's
        # files have both legs), else its right partner's.
        for side in (name, mirror(name)):
            if side is None or (side != name and side in in_file):
                continue
            f = osim.PiecewiseLinearFunction()
            for row in crows:
                f.addPoint(row[0], row[k])
            f.addPoint(crows[-1][0] + 10.0, crows[-1][k])  # held after the last node
            ctrl.addActuator(muscles.get(side))
            ctrl.prescribeControlForActuator(side, f)
    model.addController(ctrl)


def main():
    osim.Logger.setLevelString("warn")
    controls = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ROOT / "tests/data/controls/jump_optimal.sto")
    model_json = json.loads((ROOT / "models/jumper.json").read_text())

    # leap's squat and leap's own forward simulation of the same controls.
    leap, x0 = leap_simulate(controls, ACCURACY)

    model = osim.Model(str(ROOT / "models/jumper.osim"))
    prescribe_excitations(model, controls)
    muscles = model.getMuscles()
    state = model.initSystem()

    # leap's initial state on both legs: every state variable of OpenSim's.
    set_names = set()
    for label, value in x0.items():
        if label == "time":
            continue
        parts = label.split("/")
        names = [label]
        left = mirror(parts[-2])
        if left is not None:
            parts[-2] = left
            if parts[1] == "jointset":
                parts[2] = mirror(parts[2])
            names.append("/".join(parts))
        for n in names:
            model.setStateVariableValue(state, n, value)
            set_names.add(n)
    all_names = model.getStateVariableNames()
    missing = [all_names.get(i) for i in range(all_names.getSize()) if all_names.get(i) not in set_names]
    if missing:
        raise RuntimeError(f"leap's states file leaves OpenSim's {missing} unset")

    mass = model.getTotalMass(state)
    g = -model.getGravity()[1]
    weight = mass * g
    def grf_y(s):
        model.realizeDynamics(s)
        return vertical_contact_force(model, s)

    coords = model.getCoordinateSet()
    right_coords = [c["name"] for c in model_json["coordinates"] if not c["name"].endswith("_l")]

    # Is leap's squat at rest in OpenSim?
    model.realizeAcceleration(state)
    qdd = {coords.get(i).getName(): coords.get(i).getAccelerationValue(state) for i in range(coords.getSize())}
    grf0 = grf_y(state)
    eq = osim.State(state)
    model.equilibrateMuscles(eq)
    fibre_diff = max(abs(muscles.get(i).getFiberLength(eq) - muscles.get(i).getFiberLength(state))
                     for i in range(muscles.getSize()))

    # Standing COM height, from the model file's standing pose.
    stand = osim.State(state)
    for c in model_json["coordinates"]:
        coords.get(c["name"]).setValue(stand, model_json["poses"]["standing"].get(c["name"], c["default_value"]), False)
    model.realizePosition(stand)
    standing = model.calcMassCenterPosition(stand)[1]

    def manager_from(s0):
        m = osim.Manager(model)
        m.setIntegratorMethod(osim.Manager.IntegratorMethod_RungeKuttaMerson)
        m.setIntegratorAccuracy(ACCURACY)
        m.initialize(osim.State(s0))
        return m

    def sample(s):
        model.realizeDynamics(s)
        return {
            "time": s.getTime(),
            "com_y": model.calcMassCenterPosition(s)[1],
            "com_vy": model.calcMassCenterVelocity(s)[1],
            "grf_y_bw": grf_y(s) / weight,
            "q": {n: coords.get(n).getValue(s) for n in right_coords},
        }

    # Millisecond steps; lift-off is located inside the millisecond in which
    # the force vanishes by bisection, re-integrating from the last sample.
    state.setTime(0.0)
    manager = manager_from(state)
    samples = [sample(state)]
    prev_state, liftoff, k = osim.State(state), None, 0
    while liftoff is None and k * SAMPLE < 1.0:
        k += 1
        s = manager.integrate(k * SAMPLE)
        cur = sample(s)
        if cur["grf_y_bw"] > 0.0:
            samples.append(cur)
            prev_state = osim.State(s)
            continue
        lo, hi, at_hi = prev_state.getTime(), k * SAMPLE, cur
        for _ in range(BISECTIONS):
            mid = 0.5 * (lo + hi)
            m = manager_from(prev_state)  # kept alive: integrate() returns its state
            c = sample(m.integrate(mid))
            if c["grf_y_bw"] > 0.0:
                lo = mid
            else:
                hi, at_hi = mid, c
        liftoff = {key: at_hi[key] for key in ("time", "com_y", "com_vy")}
    if liftoff is None:
        raise RuntimeError("no lift-off within 1 s")

    height = liftoff["com_y"] + liftoff["com_vy"] ** 2 / (2 * g) - standing
    peak = max(sm["grf_y_bw"] for sm in samples)
    out = {
        "opensim_version": osim.GetVersionAndDate(),
        "model": "models/jumper.osim (scripts/jumper_osim.py models/jumper.json)",
        "controls": str(controls.relative_to(ROOT)) if controls.is_absolute() and ROOT in controls.parents else str(controls),
        "integrator": "RungeKuttaMerson",
        "accuracy": ACCURACY,
        "liftoff": "the total vertical ground force is zero, by %d bisections of a millisecond" % BISECTIONS,
        "initial_state": {l: v for l, v in x0.items() if l != "time"},
        "squat_max_abs_qdd": max(abs(v) for v in qdd.values()),
        "squat_vertical_grf_bw": grf0 / weight,
        "squat_max_fibre_length_difference_to_opensim_equilibrium_m": fibre_diff,
        "body_weight_n": weight,
        "standing_com_height_m": standing,
        "liftoff_time_s": liftoff["time"],
        "liftoff_com_height_m": liftoff["com_y"],
        "liftoff_com_velocity_mps": liftoff["com_vy"],
        "jump_height_m": height,
        "peak_vertical_grf_bw": peak,
        "samples": samples,
    }
    path = ROOT / "tests/data/opensim_forward_jump.json"
    path.write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {path} ({len(samples)} samples)")
    print(f"squat in OpenSim: max |qdd| {out['squat_max_abs_qdd']:.3e}, vertical GRF {out['squat_vertical_grf_bw']:.6f} BW, "
          f"fibre lengths vs OpenSim's equilibrium {fibre_diff:.3e} m")
    print(f"{'':24}{'OpenSim 4.6':>16}{'leap simulate':>16}")
    for key in ("liftoff_time_s", "liftoff_com_height_m", "liftoff_com_velocity_mps", "jump_height_m",
                "peak_vertical_grf_bw", "standing_com_height_m"):
        print(f"{key:24}{out[key]:16.8f}{leap[key]:16.8f}")


if __name__ == "__main__":
    sys.exit(main())
