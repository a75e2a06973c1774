#!/usr/bin/env python3
"""Write leap's default model, models/jumper.json, with --forces-only, or the
sensitivity variant models/jumper_jmp_strength.json without it: both are
models/jumper_gait2392.json (gait2392's muscles on the paper's skeleton) with
muscle strengths of the OpenSim Jumper (opensim-org/opensim-models,
Models/Jumper/DynamicJumperModel.osim), as listed in the last column of
shared/reference/model-data.md §7.2 (issue 5 point 8: "how the OpenSim
Jumper's stronger values change it").

What changes, per side:
  * muscles the Jumper shares with gait2392 take its max_isometric_force:
    bifemlh, med_gas, soleus, tib_post, tib_ant;
  * the Jumper's single vas_int "stands for all vasti" (model-data.md §7.2)
    with 5000 N against gait2392's 1294 + 1365 + 1871 = 4530 N, so the three
    vasti keep their own fibre and tendon lengths and their forces are scaled
    by 5000 / 4530;
  * lat_gas, which the Jumper lacks, keeps its gait2392 values.
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
    role = (
        "leap's default model"
        if FORCES_ONLY
        else "a sensitivity study, not leap's default model"
    )
    model["credits"] = model["credits"] + [
        f"Muscle strengths, written by scripts/make_jumper_jmp_strength.py"
        f"{' --forces-only' if FORCES_ONLY else ''} ({role}): "
        "bifemlh, med_gas, soleus, tib_post and tib_ant take the OpenSim Jumper's "
        f"(opensim-org/opensim-models, Models/Jumper/DynamicJumperModel.osim) {taken}, and the three "
        "vasti are scaled to the Jumper's lumped vas_int force of 5000 N "
        "(shared/reference/model-data.md §7.2)."
    ]
    DST.write_text(json.dumps(model, indent=1, ensure_ascii=False) + "\n")
    print(f"wrote {DST.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
