#!/usr/bin/python3
"""Convert a Fenestra scene (JSON) and its exported OBJ to Radiance.

Usage: scene2rad.py SCENE.json SCENE.obj OUTDIR [--black]

Writes OUTDIR/materials.rad (or materials_black.rad with --black), OUTDIR/geometry.rad
(one `polygon` per OBJ triangle, the modifier named by the OBJ group's material),
OUTDIR/sensors.pts (x y z dx dy dz per sensor, the scene's order) and OUTDIR/site.txt
(latitude, longitude, time zone from the EPW header, and the EPW path).

Materials: Lambertian grey `plastic` with specularity 0 and roughness 0, the scene's
reflectance; with --black every reflectance is 0. A material with a glazing transmittance
becomes Radiance `glass` whose normal transmittance equals it (Radiance's glass is
angle-dependent, Fenestra's glazing is not: a scene with glazing is not compared exactly).
"""
import json
import math
import os
import sys


def rad_name(name):
    return "".join(c if (c.isalnum() or c in "_-.") else "_" for c in name)


def glass_transmissivity(tn):
    # Radiance glass takes the transmissivity; this gives normal transmittance tn.
    if tn <= 0:
        return 0.0
    return (math.sqrt(0.8402528435 + 0.0072522239 * tn * tn) - 0.9166530661) / 0.0036261119 / tn


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    black = "--black" in sys.argv[1:]
    if len(args) != 3:
        sys.exit(__doc__)
    scene_path, obj_path, out = args
    os.makedirs(out, exist_ok=True)
    with open(scene_path) as f:
        scene = json.load(f)

    # Materials
    lines = []
    names = {}
    for m in scene["materials"]:
        n = rad_name(m["name"])
        names[m["name"]] = n
        rho = 0.0 if black else float(m.get("reflectance", 0.0))
        if "transmittance" in m:
            t = glass_transmissivity(float(m["transmittance"]))
            lines.append(f"# {m['name']}: glazing, normal transmittance {m['transmittance']}")
            lines.append(f"void glass {n}\n0\n0\n3 {t:.6f} {t:.6f} {t:.6f}\n")
        else:
            lines.append(f"# {m['name']}: Lambertian, reflectance {rho}")
            lines.append(f"void plastic {n}\n0\n0\n5 {rho} {rho} {rho} 0 0\n")
    mat_file = os.path.join(out, "materials_black.rad" if black else "materials.rad")
    with open(mat_file, "w") as f:
        f.write("\n".join(lines))

    # Geometry: one polygon per triangle, the modifier of the current OBJ group
    verts = []
    polys = []
    current = None
    with open(obj_path) as f:
        for line in f:
            tok = line.split()
            if not tok:
                continue
            if tok[0] == "v":
                verts.append(tuple(float(x) for x in tok[1:4]))
            elif tok[0] == "usemtl":
                current = line.strip()[len("usemtl"):].strip()
            elif tok[0] == "f":
                if current not in names:
                    sys.exit(f"OBJ material '{current}' is not in {scene_path}")
                idx = [int(t.split("/")[0]) for t in tok[1:]]
                idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
                polys.append((names[current], [verts[i] for i in idx]))
    with open(os.path.join(out, "geometry.rad"), "w") as f:
        f.write(f"# {len(polys)} polygons from {os.path.basename(obj_path)}\n")
        for k, (mod, vs) in enumerate(polys):
            f.write(f"\n{mod} polygon t{k}\n0\n0\n{3 * len(vs)}\n")
            for v in vs:
                f.write(f"  {v[0]:.9g} {v[1]:.9g} {v[2]:.9g}\n")

    # Sensors
    with open(os.path.join(out, "sensors.pts"), "w") as f:
        for s in scene["sensors"]:
            p, d = s["position"], s["direction"]
            f.write(" ".join(f"{float(p.get(c, 0.0)):.9g}" for c in "xyz") + " " +
                    " ".join(f"{float(d.get(c, 0.0)):.9g}" for c in "xyz") + "\n")

    # Site, from the EPW header (gendaymtx reads the same fields)
    site = scene["site"]
    epw = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(scene_path)),
                                        site["weather_file"]))
    with open(epw) as f:
        loc = f.readline().strip().split(",")
    lat, lon, tz = float(loc[6]), float(loc[7]), float(loc[8])
    with open(os.path.join(out, "site.txt"), "w") as f:
        f.write(f"{lat} {lon} {tz} {epw}\n")
    print(f"{mat_file}: {len(scene['materials'])} materials; geometry.rad: {len(polys)} polygons; "
          f"sensors.pts: {len(scene['sensors'])} sensors; site {lat} N {lon} E UTC{tz:+g}")


if __name__ == "__main__":
    main()
