#!/usr/bin/env python3
"""Write models/jumper_reduced.json: a 10-muscle-per-side version of
models/jumper_gait2392.json for the reduced jump instance that CI solves (issue 5,
point 9). Not a model to predict with: leap's model is models/jumper.json.

The muscle set is OpenSim's planar gait10dof18musc (opensim-org/
opensim-models, gait10dof18musc.osim; shared/ref-models), nine muscles per
side, plus the erector spinae for the lumbar joint, which gait10dof18musc
locks. Each gait10dof18musc muscle is represented by one gait2392 muscle of
models/jumper_gait2392.json, whose path, fibre and tendon lengths it keeps (so path
and fibre stay consistent), with the gait10dof18musc max_isometric_force:

    hamstrings  <- bifemlh     glut_max <- glut_max2   iliopsoas <- iliacus
    bifemsh     <- bifemsh     rect_fem <- rect_fem    vasti     <- vas_int
    gastroc     <- med_gas     soleus   <- soleus      tib_ant   <- tib_ant
    ercspn      <- ercspn (gait2392 values)

Run from the repository root:  python3 scripts/make_jumper_reduced.py
"""
import json
import pathlib

ROOT = pathlib.Path(__file__).resolve().parent.parent
SRC = ROOT / "models" / "jumper_gait2392.json"
DST = ROOT / "models" / "jumper_reduced.json"

# gait10dof18musc name: (gait2392 representative, gait10dof18musc Fmax in N).
MUSCLES = {
    "ercspn": ("ercspn", None),
    "iliopsoas": ("iliacus", 2342.0),
    "glut_max": ("glut_max2", 1944.0),
    "rect_fem": ("rect_fem", 1169.0),
    "hamstrings": ("bifemlh", 2700.0),
    "bifemsh": ("bifemsh", 804.0),
    "vasti": ("vas_int", 5000.0),
    "gastroc": ("med_gas", 2500.0),
    "soleus": ("soleus", 5137.0),
    "tib_ant": ("tib_ant", 3000.0),
}


def main():
    model = json.loads(SRC.read_text())
    by_name = {m["name"]: m for m in model["forces"]["muscles"]}
    kept = []
    for side in ("r", "l"):
        for name, (rep, fmax) in MUSCLES.items():
            m = dict(by_name[f"{rep}_{side}"])
            m["name"] = f"{name}_{side}"
            if fmax is not None:
                m["max_isometric_force"] = fmax
            kept.append(m)
    model["forces"]["muscles"] = kept
    model["name"] = "jumper_reduced"
    model["credits"] = model["credits"] + [
        "Reduced variant for CI, written by scripts/make_jumper_reduced.py: the muscle set "
        "of OpenSim's gait10dof18musc (opensim-org/opensim-models, gait10dof18musc.osim) "
        "plus ercspn, each muscle with the path, fibre and tendon lengths of one gait2392 "
        "muscle (hamstrings: bifemlh, glut_max: glut_max2, iliopsoas: iliacus, vasti: "
        "vas_int, gastroc: med_gas) and gait10dof18musc's max_isometric_force. "
        "Not leap's model."
    ]
    DST.write_text(json.dumps(model, indent=1, ensure_ascii=False) + "\n")
    print(f"wrote {DST.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
