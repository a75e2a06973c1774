#!/usr/bin/env python3
"""Write models/jumper.json: the planar jumper skeleton of
shared/reference/model-data.md §4-§6 and §8.2 (sole stations).

Data: gait2392 (opensim-org/opensim-models, Models/Gait2392_Simbody/
gait2392_thelen2003muscle.osim, CC BY 3.0, Delp et al. 1990; Anderson & Pandy
1999; Yamaguchi & Zajac 1989) and its planar version gait10dof18musc.
Run from the repository root:  python3 scripts/make_jumper_model.py
"""
import json
import pathlib

CREDITS = [
    "Skeleton from OpenSim's gait2392 model (opensim-org/opensim-models, "
    "Models/Gait2392_Simbody/gait2392_thelen2003muscle.osim), licensed CC BY 3.0: "
    "Delp et al. 1990, Anderson & Pandy 1999, Yamaguchi & Zajac 1989; planar joints "
    "as in its planar version gait10dof18musc.",
    "Reconstructed for leap from shared/reference/model-data.md §4-§6 (segments, joints, "
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


def main():
    model = {
        "name": "jumper",
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
    path = root / "models" / "jumper.json"
    path.write_text(json.dumps(model, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
