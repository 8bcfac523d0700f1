#!/usr/bin/python3
"""Direct-sun illuminance per sensor and hour from rcontrib's sun coefficients.

Usage: direct_sun.py SCENE.json OUTDIR

Reads from OUTDIR: suns.txt (suns.py), direct_coef.txt (rcontrib -ab 0 over the suns, one
row per sensor, RGB triples per sun in suns.mod order) and sun_only.mtx (gendaymtx -d -od,
visible, the sun spread over 4 patches).

The sun coefficient divided by the disc's solid angle is visibility x cosine: irradiance per
unit direct normal irradiance. The direct normal illuminance of each hour is 179 lm/W x the
sum over patches of radiance x patch solid angle (gendaymtx's AddDirect conserves the sun's
normal flux). Writes:
  direct_sun_lux.txt  sensors x records, direct-sun illuminance [lx], one row per sensor
  direct_sun_coef.txt sensors x records, irradiance per unit direct normal irradiance [-]
  dni_lux.txt         one line per record: direct normal illuminance [lx]
  direct_sun_summary.txt per-sensor annual sums and sunlit-hour counts
"""
import json
import math
import os
import sys

import numpy as np

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import radmtx  # noqa: E402

HALF_ANGLE_RAD = math.radians(0.533 / 2)
SUN_SOLID_ANGLE = 2 * math.pi * (1 - math.cos(HALF_ANGLE_RAD))  # Radiance's srcsupp.c
EFFICACY = 179.0
OCCUPIED = (8.0, 18.0)  # record centre in [8, 18) h local standard time


def direct_normal_lux(path):
    _, sun = radmtx.read(path)
    dom = radmtx.tregenza_solid_angles()
    return EFFICACY * (sun[:, :, 0] * dom[:, None]).sum(axis=0)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    scene_path, out = sys.argv[1:]
    with open(scene_path) as f:
        names = [s["name"] for s in json.load(f)["sensors"]]
    suns = np.loadtxt(os.path.join(out, "suns.txt"), ndmin=2)
    records = suns[:, 0].astype(int)
    coef = np.loadtxt(os.path.join(out, "direct_coef.txt"), ndmin=2)
    if coef.shape != (len(names), 3 * len(records)):
        sys.exit(f"direct_coef.txt is {coef.shape}, expected {len(names)} x {3 * len(records)}")
    dni = direct_normal_lux(os.path.join(out, "sun_only.mtx"))
    nrec = dni.size
    vis_cos = np.zeros((len(names), nrec))
    vis_cos[:, records] = coef[:, 0::3] / SUN_SOLID_ANGLE
    lux = vis_cos * dni[None, :]
    radmtx.write_text(os.path.join(out, "direct_sun_coef.txt"), vis_cos)
    radmtx.write_text(os.path.join(out, "direct_sun_lux.txt"), lux)
    np.savetxt(os.path.join(out, "dni_lux.txt"), dni, fmt="%.6g")

    with open(os.path.join(out, "site.txt")) as f:
        epw = f.read().split()[3]
    with open(epw) as f:
        hours = [int(l.split(",")[3]) for l in f.readlines()[8:] if l.strip()]
    if len(hours) != nrec:
        sys.exit(f"{epw}: {len(hours)} records, the sky matrix has {nrec}")
    centre = np.array(hours) - 0.5  # hourly records: the centre of hour h-1 .. h
    occupied = (centre >= OCCUPIED[0]) & (centre < OCCUPIED[1])
    lost = dni[np.setdiff1d(np.arange(nrec), records)]
    lines = [
        f"suns: {len(records)} sun-up records (centre above -0.2665 deg) of {nrec}; "
        f"records with direct normal > 0: {(dni > 0).sum()}, of them outside the suns: "
        f"{(lost > 0).sum()} ({lost.sum():.6g} lx h)",
        f"annual direct normal illuminance (gendaymtx): {dni.sum():.6g} lx h; "
        f"occupied hours: {occupied.sum()}",
        f"sun solid angle {SUN_SOLID_ANGLE:.6e} sr; max visibility x cosine {vis_cos.max():.6f}",
        "",
        "sensor  annual_lxh  hours_gt1000_occupied  hours_gt1000_all  hours_sunlit_all"
        "  max_lx",
    ]
    for i, n in enumerate(names):
        e = lux[i]
        lines.append(f"{n:6s} {e.sum():12.6g} {int(((e > 1000) & occupied).sum()):22d} "
                     f"{int((e > 1000).sum()):17d} {int((vis_cos[i] > 0).sum()):17d} "
                     f"{e.max():9.6g}")
    text = "\n".join(lines) + "\n"
    with open(os.path.join(out, "direct_sun_summary.txt"), "w") as f:
        f.write(text)
    sys.stdout.write(text)


if __name__ == "__main__":
    main()
