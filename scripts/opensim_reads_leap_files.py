#!/usr/bin/env python3
"""Does OpenSim 4.6 read the files leap writes as whole states of the model?
Golden data for tests/opensim_files.rs.

leap solves and simulates the symmetric system (one leg carries both), but a
user opens its results on models/jumper.osim, which has both legs. This
script asks OpenSim itself:

- the states file of `leap simulate` (`forward_states.sto`): does it hold every
  state variable of jumper.osim, no more (StatesTrajectory.
  createFromStatesTable with neither missing nor extra columns allowed)?
- its controls file (`forward_controls.sto`): one column per actuator, by
  Moco's control names?
- every file, the ground forces' `.mot` too: does Storage, which the GUI's
  File > Load Motion uses, load it with all its columns?
- the solution file of `leap solve` (`jump_solution.sto`): does Moco read it
  (MocoTrajectory), with every state and control of the model where its
  header's num_states and num_controls put them, and does its states table
  make a complete StatesTrajectory too?

and, at a few rows of the states file, what OpenSim computes from the row
with both legs: the centre of mass, and the vertical contact force under
each foot (the contact forces named *_r and *_l). The rows are stored
whole, so the test compares leap's own values at the same states whatever
later changes do to the simulated trajectory.

    python3 -m venv .venv && .venv/bin/pip install opensim==4.6
    cargo build --release
    .venv/bin/python scripts/opensim_reads_leap_files.py

Writes tests/data/opensim_reads_leap_files.json.
"""
import json
import pathlib
import subprocess
import sys
import tempfile

import opensim as osim

from opensim_forward_jump import vertical_contact_force

ROOT = pathlib.Path(__file__).resolve().parent.parent
LEAP = ROOT / "target/release/leap"
CONTROLS = "tests/data/controls/jump_optimal.sto"
SAMPLE_EVERY = 0.04  # s between the stored rows of the push-off


def labels_of(table):
    return list(table.getColumnLabels())


def strings(v):
    return [v.get(i) for i in range(v.getSize())]


def main():
    osim.Logger.setLevelString("warn")
    model = osim.Model(str(ROOT / "models/jumper.osim"))
    state = model.initSystem()
    state_variables = strings(model.getStateVariableNames())
    actuators = model.getActuators()
    controls = [actuators.get(i).getAbsolutePathString() for i in range(actuators.getSize())]
    weight = model.getTotalMass(state) * -model.getGravity()[1]

    with tempfile.TemporaryDirectory() as tmp:
        sim = pathlib.Path(tmp) / "simulate"
        sol = pathlib.Path(tmp) / "solve"
        subprocess.run([str(LEAP), "simulate", "--controls", str(ROOT / CONTROLS), "--out", str(sim), "--json"],
                       capture_output=True, text=True, check=True, cwd=ROOT)
        # One SQP iteration is enough for the file's layout (exit status 1:
        # the iteration limit).
        run = subprocess.run([str(LEAP), "solve", "--max-iterations", "1", "--no-forward-check", "--out", str(sol),
                              "--json"], capture_output=True, text=True, cwd=ROOT)
        if run.returncode not in (0, 1):
            raise RuntimeError(run.stderr)

        # The GUI's File > Load Motion reads with Storage: every file must
        # load there with all its columns (time among them).
        storage = {}
        for path in (sim / "forward_states.sto", sim / "forward_controls.sto", sim / "forward_grf.mot",
                     sol / "jump_solution.sto", sol / "jump_grf.mot"):
            st = osim.Storage(str(path))
            storage[f"{path.parent.name}/{path.name}"] = {"rows": st.getSize(),
                                                        "columns": st.getColumnLabels().getSize()}

        states = osim.TimeSeriesTable(str(sim / "forward_states.sto"))
        ctrl = osim.TimeSeriesTable(str(sim / "forward_controls.sto"))
        # Raises unless every state variable has its column and no column is
        # unknown to the model.
        traj = osim.StatesTrajectory.createFromStatesTable(model, states, False, False, False)

        solution = osim.MocoTrajectory(str(sol / "jump_solution.sto"))
        sol_states = solution.exportToStatesTable()
        osim.StatesTrajectory.createFromStatesTable(model, sol_states, False, False, False)
        sol_state_names = list(solution.getStateNames())
        sol_control_names = list(solution.getControlNames())

        grf = osim.TimeSeriesTable(str(sim / "forward_grf.mot"))
        grf_times = list(grf.getIndependentColumn())
        col = labels_of(states)
        samples, next_t = [], 0.0
        for k in range(traj.getSize()):
            s = traj.get(k)
            t = s.getTime()
            right_y = grf.getDependentColumn("ground_force_r_vy")[grf_times.index(t)] if t in grf_times else None
            if t + 1e-12 < next_t or right_y is None:
                continue
            if right_y <= 0.0:
                break  # lift-off: the push-off's rows only
            next_t += SAMPLE_EVERY
            model.realizeDynamics(s)
            row = states.getRowAtIndex(k)
            samples.append({
                "time": t,
                "state": {c: row[j] for j, c in enumerate(col)},
                "com_position": list(model.calcMassCenterPosition(s).to_numpy()),
                "com_velocity": list(model.calcMassCenterVelocity(s).to_numpy()),
                "vertical_grf_r_bw": vertical_contact_force(model, s, "r") / weight,
                "vertical_grf_l_bw": vertical_contact_force(model, s, "l") / weight,
            })

        out = {
            "opensim_version": osim.GetVersionAndDate(),
            "model": "models/jumper.osim (scripts/jumper_osim.py models/jumper.json)",
            "made_by": "scripts/opensim_reads_leap_files.py: leap simulate --controls " + CONTROLS
                       + "; leap solve --max-iterations 1 --no-forward-check",
            "state_variables": state_variables,
            "controls": controls,
            "states_file_columns": col,
            "controls_file_columns": labels_of(ctrl),
            "solution_num_states": len(sol_state_names),
            "solution_num_controls": len(sol_control_names),
            "solution_state_names": sol_state_names,
            "solution_control_names": sol_control_names,
            "storage": storage,
            "body_weight_n": weight,
            "samples": samples,
        }
    path = ROOT / "tests/data/opensim_reads_leap_files.json"
    path.write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {path}: {len(state_variables)} state variables, {len(controls)} controls, "
          f"{len(samples)} rows")
    for sm in samples:
        print(f"t {sm['time']:.3f}: COM y {sm['com_position'][1]:.9f} m, vertical GRF right "
              f"{sm['vertical_grf_r_bw']:.9f} BW, left {sm['vertical_grf_l_bw']:.9f} BW")


if __name__ == "__main__":
    sys.exit(main())
