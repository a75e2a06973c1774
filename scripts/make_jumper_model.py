#!/usr/bin/env python3
"""Write models/jumper_gait2392.json: the planar jumper skeleton of
models/model-data.md §4-§6 and §8.2 (sole stations).

Data: gait2392 (opensim-org/opensim-models, Models/Gait2392_Simbody/
gait2392_thelen2003muscle.osim, CC BY 3.0, Delp et al. 1990; Anderson & Pandy
1999; Yamaguchi & Zajac 1989) and its planar version gait10dof18musc.
Run from the repository root:  python3 scripts/make_jumper_model.py

This is the jumper with gait2392's muscle strengths unchanged: the model of
the OpenSim reference data in tests/data. Leap's default model,
models/jumper.json, is this one with the OpenSim Jumper's maximum isometric
forces (scripts/make_jumper_jmp_strength.py --forces-only).

Muscles (24 per side, §7), passive joint torques (§9) and the 8 contact
spheres per foot (§8.2) are read from the tables of model-data.md, so the
numbers are the published ones, not a re-typing. Pass another path to
model-data.md as the first argument to read another copy.
"""
import json
import pathlib
import re
import sys

CREDITS = [
    "Skeleton from OpenSim's gait2392 model (opensim-org/opensim-models, "
    "Models/Gait2392_Simbody/gait2392_thelen2003muscle.osim), licensed CC BY 3.0: "
    "Delp et al. 1990, Anderson & Pandy 1999, Yamaguchi & Zajac 1989; planar joints "
    "as in its planar version gait10dof18musc.",
    "Reconstructed for leap from models/model-data.md §4-§6 (segments, joints, "
    "knee splines, poses) and §8.2 (sole contact sites, from the OpenSim Jumper and "
    "Falisse et al. 3dpredictsim, MIT). Not the Porsa, Lin & Pandy 2016 model files, "
    "which are not available.",
    "Units: kg, m, rad, s. Frames: x anterior, y superior, z to the right.",
]

TX = {
    "x": [-2.0944, -1.74533, -1.39626, -1.0472, -0.698132, -0.349066, -0.174533, 0.197344, 0.337395, 0.490178, 1.52146, 2.0944],
    "y": [-0.0032, 0.00179, 0.00411, 0.0041, 0.00212, -0.001, -0.0031, -0.005227, -0.005435, -0.005574, -0.005435, -0.00525],
}
TY = {
    "x": [-2.0944, -1.22173, -0.523599, -0.349066, -0.174533, 0.159149, 2.0944],
    "y": [-0.4226, -0.4082, -0.399, -0.3976, -0.3966, -0.395264, -0.396],
}


def body(name, mass, com, inertia):
    return {"name": name, "mass": mass, "mass_center": com, "inertia": list(inertia) + [0.0, 0.0, 0.0]}


def side_bodies(s):
    z = 1.0 if s == "r" else -1.0
    return [
        body(f"femur_{s}", 9.3014, [0.0, -0.17, 0.0], [0.1339, 0.0351, 0.1412]),
        body(f"tibia_{s}", 3.7075, [0.0, -0.1867, 0.0], [0.0504, 0.0051, 0.0511]),
        body(f"talus_{s}", 0.1, [0.0, 0.0, 0.0], [0.001, 0.001, 0.001]),
        body(f"calcn_{s}", 1.25, [0.1, 0.03, 0.0], [0.0014, 0.0039, 0.0041]),
        body(f"toes_{s}", 0.2166, [0.0346, 0.006, -0.0175 * z], [0.0001, 0.0002, 0.0001]),
    ]


def side_joints(s):
    z = 1.0 if s == "r" else -1.0
    return [
        {"type": "pin", "name": f"hip_{s}", "parent": "pelvis", "child": f"femur_{s}",
         "location_in_parent": [-0.0707, -0.0661, 0.0835 * z], "coordinate": f"hip_flexion_{s}"},
        {"type": "translating_hinge", "name": f"knee_{s}", "parent": f"femur_{s}", "child": f"tibia_{s}",
         "location_in_parent": [0.0, 0.0, 0.0], "coordinate": f"knee_angle_{s}",
         "translation_x": TX, "translation_y": TY},
        {"type": "pin", "name": f"ankle_{s}", "parent": f"tibia_{s}", "child": f"talus_{s}",
         "location_in_parent": [0.0, -0.43, 0.0], "coordinate": f"ankle_angle_{s}"},
        {"type": "weld", "name": f"subtalar_{s}", "parent": f"talus_{s}", "child": f"calcn_{s}",
         "location_in_parent": [-0.04877, -0.04195, 0.00792 * z]},
        {"type": "weld", "name": f"mtp_{s}", "parent": f"calcn_{s}", "child": f"toes_{s}",
         "location_in_parent": [0.1788, -0.002, 0.00108 * z]},
    ]


def side_coordinates(s):
    return [
        {"name": f"hip_flexion_{s}", "range": [-2.0944, 2.0944], "default_value": 0.0},
        {"name": f"knee_angle_{s}", "range": [-2.0944, 0.174533], "default_value": 0.0},
        {"name": f"ankle_angle_{s}", "range": [-1.5708, 1.5708], "default_value": 0.0},
    ]


# Sole contact sites (model-data.md §8.2): on the sole plane, calcn y = -0.010,
# toes y = -0.008. Contact spheres sit at these sites raised by their radius.
SITES = [
    ("heel_lat", "calcn", 0.0, -0.010, 0.025),
    ("heel_med", "calcn", 0.0, -0.010, -0.035),
    ("midfoot_lat", "calcn", 0.07247, -0.010, 0.02885),
    ("meta5", "calcn", 0.1425, -0.010, 0.041),
    ("meta1", "calcn", 0.185, -0.010, -0.0275),
    ("hallux", "toes", 0.06565, -0.008, -0.02053),
    ("toes_central", "toes", 0.071, -0.008, 0.014),
    ("toes_lat", "toes", 0.04924, -0.008, 0.06768),
]


def stations():
    out = []
    for s in ("r", "l"):
        z = 1.0 if s == "r" else -1.0
        for name, b, x, y, zz in SITES:
            out.append({"name": f"sole_{name}_{s}", "body": f"{b}_{s}", "location": [x, y, zz * z]})
    return out


def parse_model_data(path):
    text = pathlib.Path(path).read_text()
    sec72 = text[text.index("### 7.2 Parameters"):text.index("### 7.3 Path points")]
    sec73 = text[text.index("### 7.3 Path points"):text.index("### 7.4 Moving path points")]
    sec74 = text[text.index("### 7.4 Moving path points"):text.index("### 7.5 Check table")]
    params = []
    for line in sec72.splitlines():
        m = re.match(r"\|\s*(\d+)\s*\|\s*(\w+)\s*\|\s*([\d.]+)\s*\|\s*([\d.]+)\s*\|\s*([\d.]+)\s*\|\s*([\d.]+)\s*\|", line)
        if m:
            params.append((m.group(2), float(m.group(3)), float(m.group(4)), float(m.group(5)), float(m.group(6))))
    assert len(params) == 24, len(params)
    points = {}
    for line in sec73.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 7 or not re.match(r"P\d+$", cells[1]):
            continue
        name, _, body, x, y, z, kind = cells
        if kind.startswith("moving"):
            pt = {"type": "moving", "body": body, "moving": name}
        elif kind.startswith("conditional"):
            m = re.search(r"iff (\w+) in \[([-\d.]+), ([-\d.]+)\]", kind)
            pt = {"type": "conditional", "body": body, "location": [float(x), float(y), float(z)],
                  "coordinate": m.group(1), "range": [float(m.group(2)), float(m.group(3))]}
        else:
            pt = {"type": "fixed", "body": body, "location": [float(x), float(y), float(z)]}
        points.setdefault(name, []).append(pt)
    moving = {}
    blocks = re.split(r"\*\*M-(\w+)\*\*", sec74)
    for name, body in zip(blocks[1::2], blocks[2::2]):
        splines = {}
        for axis in ("x", "y", "z"):
            m = re.search(axis + r"_location: x = \[([^\]]*)\]\s*y = \[([^\]]*)\]", body)
            splines[axis] = {"x": [float(v) for v in m.group(1).split(",")], "y": [float(v) for v in m.group(2).split(",")]}
        moving[name] = splines
    return params, points, moving


def side_name(value, s):
    """Map a right-side body or coordinate name to side s."""
    return re.sub(r"_r$", "_" + s, value)


def muscles(model_data):
    params, points, moving = parse_model_data(model_data)
    out = []
    for s in ("r", "l"):
        z = 1.0 if s == "r" else -1.0
        for name, fmax, lopt, lts, phi in params:
            path = []
            for pt in points[name]:
                q = {"type": pt["type"], "body": side_name(pt["body"], s)}
                if pt["type"] == "moving":
                    sp = moving[pt["moving"]]
                    q["coordinate"] = f"knee_angle_{s}"
                    q["x_location"] = sp["x"]
                    q["y_location"] = sp["y"]
                    q["z_location"] = {"x": sp["z"]["x"], "y": [v * z for v in sp["z"]["y"]]}
                else:
                    q["location"] = [pt["location"][0], pt["location"][1], pt["location"][2] * z]
                    if pt["type"] == "conditional":
                        q["coordinate"] = side_name(pt["coordinate"], s)
                        q["range"] = pt["range"]
                path.append(q)
            out.append({
                "name": f"{name}_{s}", "max_isometric_force": fmax, "optimal_fiber_length": lopt,
                "tendon_slack_length": lts, "pennation_angle_at_optimal": phi,
                "max_contraction_velocity": 10.0, "activation_time_constant": 0.01,
                "deactivation_time_constant": 0.04, "FmaxTendonStrain": 0.033, "FmaxMuscleStrain": 0.6,
                "KshapeActive": 0.5, "KshapePassive": 4.0, "Af": 0.3, "Flen": 1.8, "path": path,
            })
    return out


# Anderson & Pandy (1999) passive torques as given in Falisse et al.'s
# 3dpredictsim (MIT), model-data.md §9; damping 0.1 N·m·s/rad (PredSim_all_v2.m).
LIGAMENTS = {
    "hip_flexion": (-2.44, 5.05, 1.51, -21.88, -0.6981, 1.81),
    "knee_angle": (-6.09, 33.94, 11.03, -11.33, -2.4, 0.13),
    "ankle_angle": (-2.03, 38.11, 0.18, -12.12, -0.74, 0.52),
    "lumbar_extension": (-0.35, 30.72, 0.25, -20.36, -0.5235987755982988, 0.17),
}


def ligaments():
    out = []
    for coord, k in LIGAMENTS.items():
        names = [coord] if coord == "lumbar_extension" else [f"{coord}_r", f"{coord}_l"]
        for n in names:
            out.append({"coordinate": n, "k1": k[0], "k2": k[1], "k3": k[2], "k4": k[3],
                        "theta1": k[4], "theta2": k[5], "damping": 0.1})
    return out


# Contact (model-data.md §8): Falisse et al. subject 1 HuntCrossleyForce set
# (radius 0.032 m, E = 3777162 Pa, c = 2 s/m, mu = 0.8, viscous 0.5,
# v_t = 0.1 m/s), the collocation-friendly set §8.2 recommends; each sphere
# centre sits one radius above the sole site.
RADIUS = 0.032


def contact():
    spheres = []
    for s in ("r", "l"):
        z = 1.0 if s == "r" else -1.0
        for name, b, x, y, zz in SITES:
            spheres.append({"name": f"{name}_{s}", "body": f"{b}_{s}", "location": [x, y + RADIUS, zz * z],
                            "radius": RADIUS})
    return {"law": "HuntCrossleyForce", "stiffness": 3777162.0, "dissipation": 2.0, "static_friction": 0.8,
            "dynamic_friction": 0.8, "viscous_friction": 0.5, "transition_velocity": 0.1, "spheres": spheres}


def main():
    model = {
        "name": "jumper_gait2392",
        "credits": CREDITS,
        "gravity": [0.0, -9.80665, 0.0],
        "bodies": [
            body("pelvis", 11.777, [-0.0707, 0.0, 0.0], [0.1028, 0.0871, 0.0579]),
            body("torso", 34.2366, [-0.03, 0.32, 0.0], [1.4745, 0.7555, 1.4314]),
        ] + side_bodies("r") + side_bodies("l"),
        "joints": [
            {"type": "planar", "name": "ground_pelvis", "parent": "ground", "child": "pelvis",
             "location_in_parent": [0.0, 0.0, 0.0], "coordinates": ["pelvis_tilt", "pelvis_tx", "pelvis_ty"]},
        ] + side_joints("r") + side_joints("l") + [
            {"type": "pin", "name": "back", "parent": "pelvis", "child": "torso",
             "location_in_parent": [-0.1007, 0.0815, 0.0], "coordinate": "lumbar_extension"},
        ],
        "coordinates": [
            {"name": "pelvis_tilt", "range": [-1.5708, 1.5708], "default_value": 0.0},
            {"name": "pelvis_tx", "range": [-5.0, 5.0], "default_value": 0.0},
            {"name": "pelvis_ty", "range": [-1.0, 2.0], "default_value": 0.94387},
        ] + side_coordinates("r") + side_coordinates("l") + [
            {"name": "lumbar_extension", "range": [-1.5708, 1.5708], "default_value": 0.0},
        ],
        "stations": stations(),
        "symmetry": [["hip_flexion_r", "hip_flexion_l"], ["knee_angle_r", "knee_angle_l"],
                     ["ankle_angle_r", "ankle_angle_l"]],
        "poses": {
            # Feet flat on the ground (sole plane at calcn y = -0.010), model-data.md §5.
            "standing": {"pelvis_ty": 0.94387},
            # The OpenSim Jumper's squat with the ankle set for a flat foot
            # in the planar skeleton (model-data.md §5).
            "squat": {
                "pelvis_tilt": -0.435195, "pelvis_tx": -0.000925, "pelvis_ty": 0.71353,
                "hip_flexion_r": 1.32645, "knee_angle_r": -1.3962634, "ankle_angle_r": 0.505008,
                "hip_flexion_l": 1.32645, "knee_angle_l": -1.3962634, "ankle_angle_l": 0.505008,
                "lumbar_extension": -0.174533,
            },
        },
    }
    root = pathlib.Path(__file__).resolve().parent.parent
    model_data = sys.argv[1] if len(sys.argv) > 1 else root / "models" / "model-data.md"
    model["forces"] = {"muscle_model": "Thelen2003Muscle", "muscles": muscles(model_data),
                       "ligaments": ligaments(), "contact": contact()}
    model["credits"].append(
        "Muscles: the 24 gait2392 Thelen2003Muscle units per side chosen in model-data.md §7 "
        "(parameters and paths of gait2392, CC BY 3.0). Passive joint torques: Anderson & Pandy 1999 "
        "coefficients from Falisse et al. 3dpredictsim (MIT). Contact: 8 spheres per foot, "
        "model-data.md §8.2, with the Falisse et al. subject-1 HuntCrossleyForce parameters.")
    path = root / "models" / "jumper_gait2392.json"
    path.write_text(json.dumps(model, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
