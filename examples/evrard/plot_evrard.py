#!/usr/bin/env python3
"""Evrard collapse at t = 0.8: density, radial velocity and entropy A = P / rho^gamma against
radius for two resolutions, and the energy budget of a run's statistics file.

    /usr/bin/python3 examples/evrard/plot_evrard.py low.hdf5 high.hdf5 low_statistics.txt -o evrard.png
"""
import argparse
import os

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import sys  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from figure_stamp import save  # noqa: E402


GAMMA = 5.0 / 3.0


def profiles(path, bins):
    with h5py.File(path, "r") as f:
        g = f["PartType0"]
        x, v, rho, u = g["Coordinates"][...], g["Velocities"][...], g["Density"][...], g["InternalEnergy"][...]
        m = g["Masses"][...]
        t = f["Header"].attrs["Time"]
    com = (x * m[:, None]).sum(0) / m.sum()
    d = x - com
    r = np.linalg.norm(d, axis=1)
    vr = (d * v).sum(1) / np.maximum(r, 1e-30)
    entropy = (GAMMA - 1.0) * u / rho ** (GAMMA - 1.0)
    idx = np.digitize(r, bins)
    out = {}
    for name, q in (("density", rho), ("radial velocity", vr), ("entropy P/rho^gamma", entropy)):
        out[name] = np.array([np.mean(q[idx == k]) if np.any(idx == k) else np.nan for k in range(1, len(bins))])
    return t, len(m), out


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("low")
    ap.add_argument("high")
    ap.add_argument("statistics")
    ap.add_argument("-o", "--output", default="evrard.png")
    a = ap.parse_args()
    bins = np.logspace(-2, 0, 25)
    centres = np.sqrt(bins[1:] * bins[:-1])
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    for path, style in ((a.high, "-"), (a.low, "o")):
        t, n, prof = profiles(path, bins)
        for axis, (name, values) in zip((ax[0, 0], ax[0, 1], ax[1, 0]), prof.items()):
            axis.plot(centres, values, style, ms=4, label=f"{n} particles, t = {t:.2f}")
            axis.set_xscale("log")
            axis.set_xlabel("r")
            axis.set_ylabel(name)
    ax[0, 0].set_yscale("log")
    ax[1, 0].set_yscale("log")
    ax[0, 0].legend(fontsize=8)
    names = open(a.statistics).read().splitlines()
    cols = [line for line in names if line.startswith("#")][-1].lstrip("#").split()
    s = np.loadtxt(a.statistics, comments="#", ndmin=2)
    col = {c: s[:, k] for k, c in enumerate(cols)}
    for key, label in (("kinetic_energy", "kinetic"), ("thermal_energy", "thermal"), ("potential_energy", "potential"),
                       ("total_energy", "total")):
        ax[1, 1].plot(col["time"], col[key], label=label)
    e0 = col["total_energy"][0]
    drift = np.max(np.abs(col["total_energy"] - e0)) / abs(e0)
    ax[1, 1].set_title(f"energies ({a.statistics.split('/')[0]}): max |dE/E| = {drift:.1e}", fontsize=9)
    ax[1, 1].set_xlabel("t")
    ax[1, 1].legend(fontsize=8)
    for axis in ax.flat:
        axis.grid(alpha=0.3)
    fig.tight_layout()
    save(fig, a.output, dpi=110)
    print(f"wrote {a.output}; max |dE/E| = {drift:.2e}")


if __name__ == "__main__":
    main()
