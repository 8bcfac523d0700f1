#!/usr/bin/python3
"""Compare Radiance's sky sums (glossy.sh's two rcontrib halves) with Fenestra's.

Usage: glossy.py OUTDIR BACKEND

Radiance: per sensor the mean of the groups' sums over bins 1..145 (rcontrib's rows are the
daylight coefficients of the Reinhart MF 1 bins, bin 0 the ground; every dc_*.txt in OUTDIR is
one rcontrib process of its own seed with 8 groups of paths per sensor), its standard error
from their scatter. Fenestra: the sky sums and standard errors
`fenestra dc` prints. Each line: both, the difference in % and in combined standard errors, and
whether it lies within 3 combined standard errors and 2%.
"""
import glob
import os
import re
import sys

import numpy as np


def radiance_sums(out):
    """Per sensor the mean of the groups' sky sums over every rcontrib output in OUTDIR
    (dc_*.txt, 8 rows per sensor each) and its standard error from their scatter."""
    groups = []
    for name in sorted(glob.glob(os.path.join(out, "dc_*.txt"))):
        a = np.loadtxt(name, ndmin=2)
        if a.shape[1] != 3 * 146 or a.shape[0] % 8:
            sys.exit(f"{name} is {a.shape}, expected 8 rows per sensor of {3 * 146} (RGB)")
        sums = a[:, 0::3][:, 1:146].sum(axis=1)  # grey: the red channel
        groups.append(sums.reshape(-1, 8))
    g = np.hstack(groups)
    return g.mean(axis=1), g.std(axis=1, ddof=1) / np.sqrt(g.shape[1])


def fenestra_sums(log):
    sums, errors, seconds = [], [], None
    for line in open(log):
        m = re.search(r"sky sum ([0-9.e+-]+) sr \+- ([0-9.e+-]+)", line)
        if m:
            sums.append(float(m.group(1)))
            errors.append(float(m.group(2)))
        t = re.search(r"wall time ([0-9.]+) s", line)
        if t:
            seconds = float(t.group(1))
    return np.array(sums), np.array(errors), seconds


def main():
    out, backend = sys.argv[1], sys.argv[2]
    rad, rad_se = radiance_sums(out)
    worst = {}
    for method in ("one_stage", "two_stage"):
        sums, errors, seconds = fenestra_sums(os.path.join(out, f"{method}_{backend}.log"))
        print(f"{method} ({backend}, {seconds} s of tracing) against Radiance:")
        held = True
        for i, (r, rs, f, fs) in enumerate(zip(rad, rad_se, sums, errors)):
            se = np.hypot(rs, fs)
            ok = abs(f - r) <= 3 * se and abs(f - r) <= 0.02 * r
            held &= ok
            print(f"  sensor {i}: radiance {r:.5e} +- {rs:.1e}, fenestra {f:.5e} +- {fs:.1e}: "
                  f"{100 * (f / r - 1):+.2f}% ({(f - r) / se:+.1f} SE) {'ok' if ok else 'OUTSIDE'}")
        worst[method] = (max(abs(sums / rad - 1)) * 100, max(abs(sums - rad) / np.hypot(rad_se, errors)))
        print(f"  largest: {worst[method][0]:.2f}%, {worst[method][1]:.2f} SE; "
              f"{'every sensor within 3 SE and 2%' if held else 'NOT every sensor within 3 SE and 2%'}")


if __name__ == "__main__":
    main()
