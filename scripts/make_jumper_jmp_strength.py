#!/usr/bin/env python3
"""Write models/jumper_jmp_strength.json: models/jumper.json with the muscle
strengths of the OpenSim Jumper (opensim-org/opensim-models,
Models/Jumper/DynamicJumperModel.osim), as listed in the last column of
shared/reference/model-data.md §7.2, for the sensitivity study of issue 5
point 8 ("how the OpenSim Jumper's stronger values change it").

This is not leap's model: the default stays models/jumper.json (gait2392
parameters). What changes, per side:
  * muscles the Jumper shares with gait2392 take its max_isometric_force,
    optimal_fiber_length and tendon_slack_length where they differ: bifemlh,
    med_gas, soleus, tib_post, tib_ant;
  * the Jumper's single vas_int "stands for all vasti" (model-data.md §7.2)
    with 5000 N against gait2392's 1294 + 1365 + 1871 = 4530 N, so the three
    vasti keep their own fibre and tendon lengths and their forces are scaled
    by 5000 / 4530;
  * lat_gas, which the Jumper lacks, keeps its gait2392 values.
With --forces-only it writes models/jumper_jmp_forces.json instead: the
same max_isometric_force values, but every muscle keeps gait2392's
optimal_fiber_length and tendon_slack_length, to separate strength from the
Jumper's longer (hence faster: v_max = 10 l_opt/s) soleus and gastrocnemius
fibres.
Run from the repository root:  python3 scripts/make_jumper_jmp_strength.py [--forces-only]
"""
import json
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
SRC = ROOT / "models" / "jumper.json"
FORCES_ONLY = "--forces-only" in sys.argv[1:]
NAME = "jumper_jmp_forces" if FORCES_ONLY else "jumper_jmp_strength"
DST = ROOT / "models" / f"{NAME}.json"

# model-data.md §7.2, last column: Fmax (N) / l_opt (m) / l_ts (m).
JUMPER = {
    "bifemlh": (2700.0, 0.109, 0.326),
    "med_gas": (2500.0, 0.09, 0.36),
    "soleus": (4000.0, 0.08, 0.22),
    "tib_post": (3600.0, 0.031, 0.31),
    "tib_ant": (3000.0, 0.098, 0.223),
}
VASTI = ("vas_med", "vas_int", "vas_lat")
VASTI_JUMPER = 5000.0


def main():
    model = json.loads(SRC.read_text())
    muscles = model["forces"]["muscles"]
    by_name = {m["name"]: m for m in muscles}
    for side in ("r", "l"):
        for base, (fmax, lopt, lts) in JUMPER.items():
            m = by_name[f"{base}_{side}"]
            m["max_isometric_force"] = fmax
            if not FORCES_ONLY:
                m["optimal_fiber_length"] = lopt
                m["tendon_slack_length"] = lts
        total = sum(by_name[f"{v}_{side}"]["max_isometric_force"] for v in VASTI)
        for v in VASTI:
            by_name[f"{v}_{side}"]["max_isometric_force"] *= VASTI_JUMPER / total
    model["name"] = NAME
    taken = (
        "max_isometric_force (gait2392's fibre and tendon lengths kept)"
        if FORCES_ONLY
        else "max_isometric_force, optimal_fiber_length and tendon_slack_length"
    )
    model["credits"] = model["credits"] + [
        f"Variant for a sensitivity study, written by scripts/make_jumper_jmp_strength.py"
        f"{' --forces-only' if FORCES_ONLY else ''}: "
        "bifemlh, med_gas, soleus, tib_post and tib_ant take the OpenSim Jumper's "
        f"(opensim-org/opensim-models, Models/Jumper/DynamicJumperModel.osim) {taken}, and the three "
        "vasti are scaled to the Jumper's lumped vas_int force of 5000 N "
        "(shared/reference/model-data.md §7.2). Not leap's default model."
    ]
    DST.write_text(json.dumps(model, indent=1, ensure_ascii=False) + "\n")
    print(f"wrote {DST.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
