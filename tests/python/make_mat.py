"""Writes synthetic MATLAB fixtures with scipy.io.savemat, the way people's own files look.

Usage: make_mat.py LAYOUT SAMPLES.csv OUT.mat FS_HZ RPM

SAMPLES.csv is one column of samples in g under a header line (`bearingd simulate --out`).
Layouts:
  mfpt    the MFPT data set's layout: struct `bearing` with `gs` (the signal, a column),
          `sr` (sample rate, Hz), `rate` (shaft rate, Hz), `load` (lbs); uncompressed (-v6).
  nested  struct `test` holding `fs`, `rpm` and a struct `sensors` with two signals `de` and
          `fe`, beside a text variable and a cell array; zlib-compressed (-v7).
"""

import sys

import numpy as np
import scipy.io


def main() -> None:
    layout, samples_csv, out, fs, rpm = sys.argv[1:6]
    fs, rpm = float(fs), float(rpm)
    x = np.loadtxt(samples_csv, skiprows=1, dtype=np.float64)
    if layout == "mfpt":
        bearing = {"gs": x.reshape(-1, 1), "sr": fs, "rate": rpm / 60.0, "load": 270.0}
        scipy.io.savemat(out, {"bearing": bearing}, do_compression=False)
    elif layout == "nested":
        test = {
            "fs": fs,
            "rpm": rpm,
            "sensors": {"de": x.reshape(-1, 1), "fe": (0.5 * x).reshape(1, -1)},
        }
        cells = np.empty((1, 2), dtype=object)
        cells[0, 0] = "a note"
        cells[0, 1] = np.arange(3.0)
        scipy.io.savemat(
            out,
            {"test": test, "operator": "synthetic fixture", "extras": cells},
            do_compression=True,
        )
    else:
        raise SystemExit(f"unknown layout {layout!r}; use mfpt or nested")


if __name__ == "__main__":
    main()
