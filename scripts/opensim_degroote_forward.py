#!/usr/bin/env python3
"""Does OpenSim 4.6 itself integrate the jump with DeGrooteFregly2016Muscle?

leap's `muscle_model: DeGrooteFregly2016Muscle` cannot start the jump from the
squat: its state is the fibre length, and the inverted force–velocity curve
(a sinh) overflows at the minimum activation (README, "The model"). OpenSim
states this muscle by its normalised tendon force instead. This script asks
whether that carries OpenSim's own explicit integration through the push-off:
models/jumper.osim with every muscle replaced by DeGrooteFregly2016Muscle
(`DeGrooteFregly2016Muscle.replaceMuscles`, OpenSim's defaults for the curves),
the coordinates and activations of leap's static squat (row 0 of
`leap simulate --controls CONTROLS.sto`), the muscles equilibrated by OpenSim,
the excitations of CONTROLS.sto (linear between its rows, a left muscle without
its own column taking its right partner's) integrated by RungeKuttaMerson at
1e-5 in steps of 10 ms. It prints the centre of mass's height and vertical
speed until the integration ends or fails.

    python3 -m venv .venv && .venv/bin/pip install opensim==4.6
    cargo build --release
    .venv/bin/python scripts/opensim_degroote_forward.py [CONTROLS.sto]

CONTROLS.sto defaults to tests/data/controls/jump_optimal.sto. Measured
2026-12-06: OpenSim integrates to 0.248 s (the centre of mass rising at
0.84 m/s) and then stops ("Unable to advance time past 0.248381"); leap's
`leap simulate --model <the same model with DeGrooteFregly2016Muscle>` fails
within 1 ms.
"""
import pathlib
import subprocess
import sys
import tempfile

import opensim as osim

ROOT = pathlib.Path(__file__).resolve().parent.parent


def read_sto(path):
    lines = pathlib.Path(path).read_text().splitlines()
    end = next(i for i, l in enumerate(lines) if l.strip() == "endheader")
    labels = lines[end + 1].split("\t")
    rows = [[float(v) for v in l.split("\t")] for l in lines[end + 2:] if l.strip()]
    return labels, rows


def mirror(name):
    """The left partner of a right-side name (coordinate or muscle)."""
    return name[:-2] + "_l" if name.endswith("_r") else None


def main():
    osim.Logger.setLevelString("warn")
    controls = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ROOT / "tests/data/controls/jump_optimal.sto")
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([str(ROOT / "target/release/leap"), "simulate", "--controls", str(controls),
                        "--out", out, "--json"], capture_output=True, text=True, check=True)
        labels, rows = read_sto(pathlib.Path(out) / "jump_states.sto")
    x0 = dict(zip(labels, rows[0]))

    model = osim.Model(str(ROOT / "models/jumper.osim"))
    osim.DeGrooteFregly2016Muscle.replaceMuscles(model)
    clabels, crows = read_sto(controls)
    ctrl = osim.PrescribedController()
    muscles = model.getMuscles()
    in_file = {label.split("/")[-1] for label in clabels[1:]}
    for k, label in enumerate(clabels[1:], start=1):
        name = label.split("/")[-1]
        for side in (name, mirror(name)):
            if side is None or (side != name and side in in_file):
                continue
            f = osim.PiecewiseLinearFunction()
            for row in crows:
                f.addPoint(row[0], row[k])
            f.addPoint(crows[-1][0] + 10.0, crows[-1][k])
            ctrl.addActuator(muscles.get(side))
            ctrl.prescribeControlForActuator(side, f)
    model.addController(ctrl)
    state = model.initSystem()

    coords = model.getCoordinateSet()
    for label, value in x0.items():
        parts = label.split("/")
        if len(parts) == 5 and parts[1] == "jointset" and parts[-1] == "value":
            for n in (parts[3], mirror(parts[3])):
                if n and coords.contains(n):
                    coords.get(n).setValue(state, value, False)
        elif len(parts) == 4 and parts[-1] == "activation":
            for n in (parts[2], mirror(parts[2])):
                if n:
                    model.setStateVariableValue(state, f"/forceset/{n}/activation", value)
    model.assemble(state)
    model.equilibrateMuscles(state)

    manager = osim.Manager(model)
    manager.setIntegratorMethod(osim.Manager.IntegratorMethod_RungeKuttaMerson)
    manager.setIntegratorAccuracy(1e-5)
    manager.initialize(state)
    t = 0.0
    while t < 0.5:
        t += 0.01
        try:
            s = manager.integrate(t)
        except Exception as e:  # OpenSim raises its integrator's failure
            lines = [l.strip() for l in str(e).splitlines() if l.strip()]
            why = next((l for l in lines if "Unable to advance" in l), lines[-1] if lines else "")
            print(f"integration failed before t = {t:.2f} s: {why}")
            return
        model.realizeVelocity(s)
        print(f"t = {t:.2f} s: COM height {model.calcMassCenterPosition(s)[1]:.4f} m, "
              f"vertical speed {model.calcMassCenterVelocity(s)[1]:.3f} m/s")


if __name__ == "__main__":
    main()
