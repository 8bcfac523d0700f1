#!/usr/bin/python3
"""Fenestra's direct sun and total annual illuminance of one design against Radiance's.

Usage: compare.py RESULT.json [RESULT_OTHER_SEED.json] RADIANCE_DIR
RESULT.json: `fenestra optimize --local` of a job whose design variables are all fixed (its
best_hourly holds the design's illuminance and direct sun, sensors x EPW records, lx).
RADIANCE_DIR: the output of direct_sun.sh and five_phase.sh (direct_sun_lux.txt,
E_five_phase_lux.txt; Radiance's own error is in five_phase_summary.txt). With a second
result of another seed, Fenestra's error of an annual sum is half the difference of the two,
as Radiance's is of its two halves.
"""
import json
import sys

import numpy as np


def load(path):
    r = json.load(open(path))
    h = r["best_hourly"]
    sensors, steps = len(h["sensors"]), len(h["hour"])
    shape = (sensors, steps)
    direct = np.array(h.get("direct_sun_lux", [0.0] * sensors * steps), float).reshape(shape)
    total = np.array(h["illuminance_lux"], float).reshape(shape)
    occupied = np.array([8 <= x < 18 for x in h["hour"]])
    return direct, total, occupied


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(__doc__)
    direct, total, occupied = load(sys.argv[1])
    other = load(sys.argv[2])[1] if len(sys.argv) == 4 else None
    rad = sys.argv[-1]
    rad_direct = np.loadtxt(f"{rad}/direct_sun_lux.txt")
    rad_total = np.loadtxt(f"{rad}/E_five_phase_lux.txt")
    print("sensor  direct_fen_lxh  direct_rad_lxh  ratio    sunlit_fen  sunlit_rad  "
          "gt1000occ_fen  gt1000occ_rad  total_fen_lxh  total_rad_lxh  diff_%  fen_err_%")
    for i in range(direct.shape[0]):
        df, dr = direct[i].sum(), rad_direct[i].sum()
        tf, tr = total[i].sum(), rad_total[i].sum()
        err = abs(tf - other[i].sum()) / 2 / tf * 100 if other is not None else float("nan")
        print(f"S{i + 1:<6} {df:14.6g}  {dr:14.6g}  {df / dr if dr > 0 else float('nan'):7.4f}  "
              f"{(direct[i] > 0).sum():10d}  {(rad_direct[i] > 0).sum():10d}  "
              f"{((direct[i] > 1000) & occupied).sum():13d}  "
              f"{((rad_direct[i] > 1000) & occupied).sum():13d}  {tf:13.6g}  {tr:13.6g}  "
              f"{100 * (tf / tr - 1):+6.2f}  {err:9.2f}")
    lit_f, lit_r = direct > 0, rad_direct > 0
    both = lit_f & lit_r
    print(f"(sensor, record) pairs lit: Fenestra {lit_f.sum()}, Radiance {lit_r.sum()}, "
          f"lit in one only {(lit_f != lit_r).sum()}")
    if both.any():
        rel = np.abs(direct - rad_direct)[both] / rad_direct[both]
        print(f"where both are lit: largest relative difference {rel.max():.2e}")


if __name__ == "__main__":
    main()
