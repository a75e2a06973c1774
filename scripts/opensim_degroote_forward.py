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
import sys

import opensim as osim

from opensim_forward_jump import leap_simulate, mirror, prescribe_excitations

ROOT = pathlib.Path(__file__).resolve().parent.parent


def main():
    osim.Logger.setLevelString("warn")
    controls = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ROOT / "tests/data/controls/jump_optimal.sto")
    _, x0 = leap_simulate(controls, 1e-5)

    model = osim.Model(str(ROOT / "models/jumper.osim"))
    osim.DeGrooteFregly2016Muscle.replaceMuscles(model)
    prescribe_excitations(model, controls)
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
