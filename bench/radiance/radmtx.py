"""Read and write Radiance matrices (gendaymtx, rcontrib, rmtxop output) with numpy."""
import gzip
import numpy as np


def read(path):
    """Return (header dict, array [rows, cols, ncomp]) of a Radiance matrix file.

    Reads ASCII, float and double formats (optionally gzipped) and plain whitespace text
    without a header (then NCOMP is taken as 1)."""
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rb") as f:
        data = f.read()
    hdr = {}
    if data.startswith(b"#?RADIANCE"):
        end = data.index(b"\n\n")
        for line in data[:end].decode("latin-1").splitlines():
            if "=" in line:
                k, v = line.split("=", 1)
                hdr[k.strip()] = v.strip()
        body = data[end + 2:]
    else:
        body = data
    fmt = hdr.get("FORMAT", "ascii")
    ncomp = int(hdr.get("NCOMP", "1"))
    if fmt == "double":
        arr = np.frombuffer(body, dtype="<f8" if hdr.get("BigEndian", "0") == "0" else ">f8")
    elif fmt == "float":
        arr = np.frombuffer(body, dtype="<f4" if hdr.get("BigEndian", "0") == "0" else ">f4")
        arr = arr.astype(np.float64)
    else:
        arr = np.array(body.split(), dtype=np.float64)
    if "NROWS" in hdr and "NCOLS" in hdr:
        rows, cols = int(hdr["NROWS"]), int(hdr["NCOLS"])
    else:
        rows, cols = -1, None
    if cols is None:
        # plain text: one row per line
        lines = [l for l in body.decode().splitlines() if l.strip()]
        rows = len(lines)
        cols = len(lines[0].split()) // ncomp
    return hdr, arr.reshape(rows, cols, ncomp)


def tregenza_solid_angles():
    """Solid angles [sr] of gendaymtx's 146 bins (rh_init with -m 1), bin 0 = ground (2 pi)."""
    tnaz = [30, 30, 24, 24, 18, 12, 6]
    alpha = (np.pi / 2) / (7 + 0.5)
    dom = [2 * np.pi]
    for i, n in enumerate(tnaz):
        d = np.float32(2 * np.pi * (np.sin(alpha * (i + 1)) - np.sin(alpha * i)) / n)
        dom += [float(d)] * n
    dom.append(float(np.float32(2 * np.pi * (1 - np.cos(alpha * 0.5)))))
    return np.array(dom)


def write_text(path, mat, fmt="%.6g"):
    """Write a 2-D array as whitespace-separated text, one row per line."""
    np.savetxt(path, mat, fmt=fmt, delimiter=" ")
