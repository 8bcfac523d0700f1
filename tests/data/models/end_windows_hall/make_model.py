#!/usr/bin/env python3
"""Writes end_windows_hall.hbjson: a Honeybee model (honeybee-schema Model) of one hall,
10 m x 29 m x 3.6 m, with a 9.8 m x 2.2 m window in each end wall and three sensor grids at
0.762 m on a 0.5 m raster: two named "perimeter" (300 and 220 sensors) and "core" (640).
Usage: make_model.py > end_windows_hall.hbjson"""
import json
import sys

X, Y, H = 5.0, 14.5, 3.6  # half width, half length, height [m]
SILL, HEAD, HALF_GLASS = 0.8, 3.0, 4.9


def face(name, kind, boundary, points, apertures=()):
    out = {"type": "Face", "identifier": "Hall..%s" % name, "display_name": name,
           "face_type": kind, "boundary_condition": {"type": boundary},
           "geometry": {"type": "Face3D", "boundary": [list(p) for p in points]},
           "properties": {"type": "FacePropertiesAbridged",
                          "radiance": {"type": "FaceRadiancePropertiesAbridged"}}}
    if apertures:
        out["apertures"] = [
            {"type": "Aperture", "identifier": "Hall..%s_Window" % name,
             "display_name": "%s window" % name, "is_operable": False,
             "boundary_condition": {"type": "Outdoors"},
             "geometry": {"type": "Face3D", "boundary": [list(p) for p in a]},
             "properties": {"type": "AperturePropertiesAbridged",
                            "radiance": {"type": "ApertureRadiancePropertiesAbridged"}}}
            for a in apertures]
    return out


def end_window(y, sign):
    # counter-clockwise seen from outside (normal -y at the south end, +y at the north end)
    return [(-sign * HALF_GLASS, y, HEAD), (-sign * HALF_GLASS, y, SILL),
            (sign * HALF_GLASS, y, SILL), (sign * HALF_GLASS, y, HEAD)]


faces = [
    face("South", "Wall", "Outdoors", [(-X, -Y, H), (-X, -Y, 0), (X, -Y, 0), (X, -Y, H)],
         [end_window(-Y, 1)]),
    face("East", "Wall", "Outdoors", [(X, -Y, H), (X, -Y, 0), (X, Y, 0), (X, Y, H)]),
    face("North", "Wall", "Outdoors", [(X, Y, H), (X, Y, 0), (-X, Y, 0), (-X, Y, H)],
         [end_window(Y, -1)]),
    face("West", "Wall", "Outdoors", [(-X, Y, H), (-X, Y, 0), (-X, -Y, 0), (-X, -Y, H)]),
    face("Floor", "Floor", "Ground", [(-X, -Y, 0), (-X, Y, 0), (X, Y, 0), (X, -Y, 0)]),
    face("Roof", "RoofCeiling", "Outdoors", [(-X, -Y, H), (X, -Y, H), (X, Y, H), (-X, Y, H)]),
]


def grid(name, y_first, rows):
    sensors = [{"pos": [-4.75 + 0.5 * i, y_first + 0.5 * j, 0.762], "dir": [0.0, 0.0, 1.0]}
               for j in range(rows) for i in range(20)]
    return {"type": "SensorGrid", "identifier": name, "display_name": name, "sensors": sensors}


model = {
    "type": "Model", "identifier": "End_Windows_Hall", "display_name": "End windows hall",
    "version": "1.0.0", "units": "Meters", "tolerance": 0.01, "angle_tolerance": 1.0,
    "rooms": [{"type": "Room", "identifier": "Hall", "display_name": "Hall", "faces": faces,
               "properties": {"type": "RoomPropertiesAbridged",
                              "radiance": {"type": "RoomRadiancePropertiesAbridged"}}}],
    "properties": {"type": "ModelProperties",
                   "radiance": {"type": "ModelRadianceProperties", "modifiers": [],
                                "modifier_sets": [],
                                "sensor_grids": [grid("perimeter", -14.25, 15),
                                                 grid("perimeter", 9.25, 11),
                                                 grid("core", -6.75, 32)]}},
}
json.dump(model, sys.stdout, indent=1)
sys.stdout.write("\n")
