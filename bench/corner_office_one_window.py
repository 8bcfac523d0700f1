#!/usr/bin/env python3
"""Writes the corner office (examples/corner_office) with one window of the same total area:
the east window walled up, the north window 3.2 m wide instead of 1.6 m (x 0.4 to 3.6), the
same blind, sensors and site. Usage: corner_office_one_window.py OUT_DIR (writes
OUT_DIR/scene.json and OUT_DIR/tilt_and_spacing.json, the example's job)."""
import json
import os
import sys

repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
example = os.path.join(repo, "examples", "corner_office")
out = sys.argv[1]
os.makedirs(out, exist_ok=True)
scene = json.load(open(os.path.join(example, "scene.json")))

surfaces = []
for s in scene["surfaces"]:
    name = s["name"]
    if name.startswith("east wall") or name.startswith("east reveal") or name.startswith("facade east"):
        continue
    if name.startswith("north") or name.startswith("facade north"):
        for v in s["polygon"]["vertices"]:
            if abs(v["x"] - 2.0) < 1e-9:
                v["x"] = 0.4
    surfaces.append(s)


def quad(name, side, material, corners):
    return {"name": name, "side": side, "material": material,
            "polygon": {"vertices": [dict(zip("xyz", c)) for c in corners]}}


surfaces.append(quad("east wall", "SIDE_INDOOR", "wall",
                     [(4.0, 0, 0), (4.0, 5.0, 0), (4.0, 5.0, 3.0), (4.0, 0, 3.0)]))
surfaces.append(quad("facade east", "SIDE_OUTDOOR", "facade",
                     [(4.25, -0.25, 0), (4.25, 5.25, 0), (4.25, 5.25, 3.25), (4.25, -0.25, 3.25)]))
scene["surfaces"] = surfaces
north = [w for w in scene["windows"] if w["name"] == "north"][0]
north["center"]["x"] = 2.0
north["widthM"] = 3.2
scene["windows"] = [north]
scene["name"] = scene.get("name", "corner office") + ", one window of both windows' area"
scene["site"]["weatherFile"] = os.path.relpath(
    os.path.join(repo, "examples", "weather", os.path.basename(scene["site"]["weatherFile"])), out)
json.dump(scene, open(os.path.join(out, "scene.json"), "w"), indent=1)
job = json.load(open(os.path.join(example, "tilt_and_spacing.json")))
json.dump(job, open(os.path.join(out, "tilt_and_spacing.json"), "w"), indent=1)
