#!/usr/bin/env python3
"""Density, velocity and pressure of a Sod snapshot against the exact solution (PNG), and the L1 error."""
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


ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("snapshot")
    ap.add_argument("-o", "--output", default="sod.png")
    args = ap.parse_args()
    exact = np.loadtxt(os.path.join(ROOT, "data", "hydro_tests", "sod_exact_gamma5_3_t0.2.txt"))
    with h5py.File(args.snapshot, "r") as f:
        t = float(f["Header"].attrs["Time"])
        x = f["PartType0/Coordinates"][:, 0] - 1.0
        v = f["PartType0/Velocities"][:, 0]
        rho = f["PartType0/Density"][...]
        p = f["PartType0/Pressure"][...]
    central = np.abs(x) < 0.5
    l1 = np.mean(np.abs(rho[central] - np.interp(x[central], exact[:, 0], exact[:, 1])))
    print(f"t = {t:.3g}: density L1 per particle (|x - 1| < 0.5) = {l1:.5f}")
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6))
    for ax, data, col, name in zip(axes, (rho, v, p), (1, 2, 3), ("density", "velocity", "pressure")):
        ax.plot(x[central], data[central], ",", color="C0", alpha=0.4)
        ax.plot(exact[:, 0], exact[:, col], "k-", lw=1)
        ax.set_xlabel("x - 1")
        ax.set_ylabel(name)
        ax.set_xlim(-0.5, 0.5)
    fig.suptitle(f"Sod shock, {len(x)} particles, t = {t:.3g}, density L1 = {l1:.4f}")
    fig.tight_layout()
    save(fig, args.output, dpi=110)
    print("wrote", args.output)


if __name__ == "__main__":
    main()
