#!/usr/bin/env python3
"""Write leap's default model, models/jumper.json, with --forces-only, or the
sensitivity variant models/jumper_jmp_strength.json without it: both are
models/jumper_gait2392.json (gait2392's muscles on the paper's skeleton) with
muscle strengths of the OpenSim Jumper (opensim-org/opensim-models,
Models/Jumper/DynamicJumperModel.osim), as listed in the last column of
models/model-data.md §7.2 (issue 5 point 8: "how the OpenSim
Jumper's stronger values change it").

What changes, per side:
  * the Jumper keeps one muscle of several groups of gait2392 and gives it
    the force of the whole group: its vas_int "stands for all vasti"
    (model-data.md §7.2), and its bifemlh (2700 N / 0.109 / 0.326), med_gas
    (2500 N) and tib_ant (3000 N / 0.098 / 0.223) carry the forces of
    gait10dof18musc's lumped hamstrings, gastroc and tib_ant (model-data.md
    §7.2, [G10]); the Jumper has no semimem, semiten, lat_gas or ext_dig.
    Each group of gait2392 muscles therefore takes the Jumper's force in
    all, shared in proportion to gait2392's forces, every muscle keeping its
    own path, fibre and tendon lengths:
        vasti        vas_med, vas_int, vas_lat   5000 N (gait2392 4530 N)
        hamstrings   bifemlh, semimem, semiten   2700 N (gait2392 2594 N)
        gastrocnemii med_gas, lat_gas            2500 N (gait2392 2241 N)
        dorsiflexors tib_ant, ext_dig            3000 N (gait2392 1417 N)
    (Until 2026-12-05 only the vasti were treated as a group: bifemlh took
    2700 N beside semimem and semiten, 4398 N of hamstrings, and med_gas
    2500 N beside lat_gas, more than either source has.)
  * soleus (4000 N) and tib_post (3600 N), which the Jumper keeps as
    gait2392 does, take its forces.
With --forces-only (models/jumper.json, the default model) every muscle keeps
gait2392's optimal_fiber_length and tendon_slack_length: those are fitted to
gait2392's own muscle paths, which the model keeps, while a maximum isometric
force is a scale that carries over between models. Without it
(models/jumper_jmp_strength.json) the five shared muscles also take the
Jumper's optimal_fiber_length and tendon_slack_length, fitted to the Jumper's
paths (longer, hence faster, soleus and gastrocnemius fibres: v_max =
10 l_opt/s).
Run from the repository root:  python3 scripts/make_jumper_jmp_strength.py [--forces-only]
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
SRC = ROOT / "models" / "jumper_gait2392.json"
FORCES_ONLY = "--forces-only" in sys.argv[1:]
NAME = "jumper" if FORCES_ONLY else "jumper_jmp_strength"
DST = ROOT / "models" / f"{NAME}.json"

# model-data.md §7.2, last column: Fmax (N) / l_opt (m) / l_ts (m) of the
# muscles the Jumper shares with gait2392, and the groups its muscle stands
# for (the muscle itself first).
JUMPER = {
    "bifemlh": (2700.0, 0.109, 0.326),
    "med_gas": (2500.0, 0.09, 0.36),
    "soleus": (4000.0, 0.08, 0.22),
    "tib_post": (3600.0, 0.031, 0.31),
    "tib_ant": (3000.0, 0.098, 0.223),
    # The vasti keep gait2392's lengths in both models (as before groups).
    "vas_int": (5000.0, None, None),
}
GROUPS = {
    "vas_int": ("vas_int", "vas_med", "vas_lat"),
    "bifemlh": ("bifemlh", "semimem", "semiten"),
    "med_gas": ("med_gas", "lat_gas"),
    "tib_ant": ("tib_ant", "ext_dig"),
}


def main():
    model = json.loads(SRC.read_text())
    muscles = model["forces"]["muscles"]
    by_name = {m["name"]: m for m in muscles}
    for side in ("r", "l"):
        for base, (fmax, lopt, lts) in JUMPER.items():
            group = [by_name[f"{g}_{side}"] for g in GROUPS.get(base, (base,))]
            total = sum(m["max_isometric_force"] for m in group)
            for m in group:
                m["max_isometric_force"] = m["max_isometric_force"] * fmax / total
            m = by_name[f"{base}_{side}"]
            if not FORCES_ONLY and lopt is not None:
                m["optimal_fiber_length"] = lopt
                m["tendon_slack_length"] = lts
    model["name"] = NAME
    lengths = (
        "gait2392's fibre and tendon lengths kept"
        if FORCES_ONLY
        else "bifemlh, med_gas, soleus, tib_post and tib_ant also take the Jumper's "
        "optimal_fiber_length and tendon_slack_length"
    )
    role = (
        "leap's default model"
        if FORCES_ONLY
        else "a sensitivity study, not leap's default model"
    )
    model["credits"] = model["credits"] + [
        f"Muscle strengths, written by scripts/make_jumper_jmp_strength.py"
        f"{' --forces-only' if FORCES_ONLY else ''} ({role}): "
        "soleus and tib_post take the OpenSim Jumper's "
        "(opensim-org/opensim-models, Models/Jumper/DynamicJumperModel.osim) max_isometric_force; "
        "the groups that one Jumper muscle stands for (as gait10dof18musc's lumped muscles, "
        "models/model-data.md §7.2) take its force in all, in proportion to gait2392's: "
        "vasti (vas_int) 5000 N, hamstrings bifemlh + semimem + semiten (bifemlh) 2700 N, "
        f"gastrocnemii med_gas + lat_gas (med_gas) 2500 N, dorsiflexors tib_ant + ext_dig (tib_ant) 3000 N; {lengths}."
    ]
    DST.write_text(json.dumps(model, indent=1, ensure_ascii=False) + "\n")
    print(f"wrote {DST.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
