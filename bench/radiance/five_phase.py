#!/usr/bin/python3
"""Annual illuminance with the sun separated, from two independent halves of Radiance DCs.

Usage: five_phase.py SCENE.json OUTDIR

Reads from OUTDIR: dc_a.txt, dc_b.txt (rcontrib -ab 30, sensors x 146 RGB), dd_a.txt,
dd_b.txt (the same, black materials, -ab 1), sky_only.mtx (gendaymtx -s), sun_patches.mtx
(-d), sky_full.mtx (neither), direct_sun_lux.txt (direct_sun.py). Per half h:

  E_h     = 179 (DC_h S_sky + (DC_h - D_d,h) S_sun) + E_direct_sun
  E_old_h = 179 DC_h S_full

Writes E_five_phase_lux.txt and E_old_lux.txt (sensors x records [lx], the mean of the
halves), dc.txt and dd.txt (the mean coefficients, sensors x 146 [sr]) and
five_phase_summary.txt: per-sensor annual sums [lx h], their errors (half the difference of
the halves' sums, the standard error of their mean) and the parts of E.
"""
import json
import os
import sys

import numpy as np

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import radmtx  # noqa: E402

EFFICACY = 179.0


def coefficients(path, nsensors):
    a = np.loadtxt(path, ndmin=2)
    if a.shape != (nsensors, 3 * 146):
        sys.exit(f"{path} is {a.shape}, expected {nsensors} x {3 * 146}")
    if np.abs(a[:, 0::3] - a[:, 1::3]).max() > 1e-6 * max(a.max(), 1e-30):
        sys.exit(f"{path}: channels differ, expected grey")
    return a[:, 0::3]


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    scene_path, out = sys.argv[1:]
    p = lambda name: os.path.join(out, name)  # noqa: E731
    with open(scene_path) as f:
        names = [s["name"] for s in json.load(f)["sensors"]]
    n = len(names)
    dc = [coefficients(p(f"dc_{h}.txt"), n) for h in "ab"]
    dd = [coefficients(p(f"dd_{h}.txt"), n) for h in "ab"]
    s_sky = radmtx.read(p("sky_only.mtx"))[1][:, :, 0]
    s_sun = radmtx.read(p("sun_patches.mtx"))[1][:, :, 0]
    s_full = radmtx.read(p("sky_full.mtx"))[1][:, :, 0]
    e_dir = np.loadtxt(p("direct_sun_lux.txt"), ndmin=2)
    split_err = np.abs(s_sky + s_sun - s_full).max() / s_full.max()

    parts = []
    for h in range(2):
        sky = EFFICACY * dc[h] @ s_sky
        sun_ir = EFFICACY * (dc[h] - dd[h]) @ s_sun
        sun_patch_direct = EFFICACY * dd[h] @ s_sun
        old = EFFICACY * dc[h] @ s_full
        parts.append(dict(E=sky + sun_ir + e_dir, old=old, sky=sky, sun_ir=sun_ir,
                          sun_patch_direct=sun_patch_direct))
    mean = {k: 0.5 * (parts[0][k] + parts[1][k]) for k in parts[0]}
    half = {k: 0.5 * np.abs(parts[0][k].sum(1) - parts[1][k].sum(1)) for k in parts[0]}
    radmtx.write_text(p("E_five_phase_lux.txt"), mean["E"])
    radmtx.write_text(p("E_old_lux.txt"), mean["old"])
    radmtx.write_text(p("dc.txt"), 0.5 * (dc[0] + dc[1]), fmt="%.6e")
    radmtx.write_text(p("dd.txt"), 0.5 * (dd[0] + dd[1]), fmt="%.6e")

    dcm = 0.5 * (dc[0] + dc[1])
    ddm = 0.5 * (dd[0] + dd[1])
    lines = [
        f"S_sky + S_sun against S_full: max difference {split_err:.2e} of S_full's maximum",
        "",
        "annual sums [lx h] (mean of the two halves; +- half their difference)",
        "sensor  E_five_phase            E_old                   E/E_old-1  "
        "sky part    sun interreflected  direct sun (exact)  direct sun in E_old (D_d S_sun)",
    ]
    for i, nm in enumerate(names):
        e, o = mean["E"][i].sum(), mean["old"][i].sum()
        lines.append(
            f"{nm:6s} {e:12.6g} +- {half['E'][i]:9.3g} {o:12.6g} +- {half['old'][i]:9.3g} "
            f"{e / o - 1:+9.4f}  {mean['sky'][i].sum():10.5g}  {mean['sun_ir'][i].sum():12.5g}"
            f"        {e_dir[i].sum():12.5g}        {mean['sun_patch_direct'][i].sum():12.5g}")
    lines += [
        "",
        "daylight coefficients: sky sums over bins 1..145 [sr] (+- half the halves' difference)",
        "sensor  DC_sky_sum               DC_ground(bin0)  D_d_sky_sum              D_d_ground",
    ]
    for i, nm in enumerate(names):
        s = [dc[h][i, 1:].sum() for h in range(2)]
        t = [dd[h][i, 1:].sum() for h in range(2)]
        lines.append(f"{nm:6s} {dcm[i, 1:].sum():.6e} +- {abs(s[0] - s[1]) / 2:.2e} "
                     f"{dcm[i, 0]:.3e}        {ddm[i, 1:].sum():.6e} +- {abs(t[0] - t[1]) / 2:.2e} "
                     f"{ddm[i, 0]:.3e}")
    text = "\n".join(lines) + "\n"
    with open(p("five_phase_summary.txt"), "w") as f:
        f.write(text)
    sys.stdout.write(text)


if __name__ == "__main__":
    main()
