#!/usr/bin/python3
"""One Radiance sun per sun-up hour of an EPW file, from gensky.

Usage: suns.py RADBIN EPW OUTDIR

Record hour h (1..24) is evaluated at h - 0.5 local standard time, no daylight saving (as
gendaymtx reads an hourly EPW). Each record's sun direction comes from
`gensky M D H -a LAT -o LON_WEST -m MERIDIAN_WEST` (no -y: the IES formulas of sun.c, the
ones gendaymtx uses), site from the EPW header. A record is sun-up when the sun's centre is
above -0.2665 degrees (part of the 0.533-degree disc above the horizon: gendaymtx's test).
Each sun-up record gets a `light` of radiance 1 in every channel and a 0.533-degree distant
`source`, named solar<record>; rcontrib's coefficient for it divided by the disc's solid
angle 2 pi (1 - cos 0.2665 deg) is the irradiance per unit direct normal irradiance.

Writes OUTDIR/suns.rad, OUTDIR/suns.mod (modifier names, one a line, in record order) and
OUTDIR/suns.txt (record index 0..8759, month, day, hour of the centre, dx, dy, dz,
altitude [deg]).
"""
import concurrent.futures
import math
import os
import subprocess
import sys

HALF_ANGLE_DEG = 0.2665
DAYS_BEFORE = [0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334]


def read_epw(path):
    with open(path) as f:
        loc = f.readline().split(",")
        lat, lon, tz = float(loc[6]), float(loc[7]), float(loc[8])
        records = []
        for line in f:
            tok = line.split(",")
            if len(tok) < 20 or not tok[0].strip().lstrip("-").isdigit():
                continue
            records.append((int(tok[1]), int(tok[2]), int(tok[3]), int(tok[4])))
    return lat, lon, tz, records


def rough_altitude_deg(lat, lon, tz, month, day, hour):
    # sun.c's formulas, only to skip night records before asking gensky
    jd = DAYS_BEFORE[month - 1] + day
    sd = 0.4093 * math.sin(2 * math.pi * (jd - 81) / 365)
    st = (hour + 0.170 * math.sin(4 * math.pi * (jd - 80) / 373) -
          0.129 * math.sin(2 * math.pi * (jd - 8) / 355) +
          12 * math.radians(-15 * tz + lon) / math.pi)
    la = math.radians(lat)
    return math.degrees(math.asin(math.sin(la) * math.sin(sd) -
                                  math.cos(la) * math.cos(sd) * math.cos(st * math.pi / 12)))


def gensky_direction(radbin, month, day, hour, lat, lon_west, mer_west):
    out = subprocess.run([os.path.join(radbin, "gensky"), str(month), str(day), f"{hour:.4f}",
                          "-a", f"{lat}", "-o", f"{lon_west}", "-m", f"{mer_west}"],
                         check=True, capture_output=True, text=True).stdout
    # The skyfunc's last three real arguments are the sun direction, sun up or down.
    lines = [l for l in out.splitlines() if l.strip()]
    for i, l in enumerate(lines):
        if l.startswith("void brightfunc skyfunc"):
            vals = lines[i + 3].split()
            return tuple(float(v) for v in vals[-3:])
    raise RuntimeError(f"no skyfunc in gensky output for {month}/{day} {hour}")


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    radbin, epw, out = sys.argv[1:]
    os.makedirs(out, exist_ok=True)
    lat, lon, tz, records = read_epw(epw)
    lon_west, mer_west = -lon, -15.0 * tz
    jobs = []
    for k, (m, d, h, minute) in enumerate(records):
        centre = h - 0.5  # hourly file: the record's interval h-1 .. h, at its centre
        if rough_altitude_deg(lat, lon, tz, m, d, centre) > -3.0:
            jobs.append((k, m, d, centre))
    with concurrent.futures.ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        dirs = list(pool.map(lambda j: gensky_direction(radbin, j[1], j[2], j[3], lat, lon_west,
                                                        mer_west), jobs))
    sin_min = math.sin(math.radians(-HALF_ANGLE_DEG))
    n = 0
    with open(os.path.join(out, "suns.rad"), "w") as rad, \
            open(os.path.join(out, "suns.mod"), "w") as mod, \
            open(os.path.join(out, "suns.txt"), "w") as txt:
        rad.write(f"# suns from gensky, site {lat} N, {lon_west} W, meridian {mer_west} W\n")
        for (k, m, d, centre), v in zip(jobs, dirs):
            norm = math.sqrt(sum(x * x for x in v))
            dz = v[2] / norm
            if dz <= sin_min:
                continue
            rad.write(f"\nvoid light solar{k}\n0\n0\n3 1 1 1\n"
                      f"\nsolar{k} source sun{k}\n0\n0\n4 {v[0]:.6f} {v[1]:.6f} {v[2]:.6f} 0.533\n")
            mod.write(f"solar{k}\n")
            txt.write(f"{k} {m} {d} {centre:.4f} {v[0]:.6f} {v[1]:.6f} {v[2]:.6f} "
                      f"{math.degrees(math.asin(dz)):.4f}\n")
            n += 1
    print(f"suns: {n} sun-up records of {len(records)} (site {lat} N, {lon_west} W, "
          f"meridian {mer_west} W)")


if __name__ == "__main__":
    main()
