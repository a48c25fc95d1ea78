#!/usr/bin/env python3
"""Azimuthal velocity of a Gresho vortex snapshot against the exact (steady) profile; prints the L1 error."""
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



def v_exact(r):
    return np.where(r < 0.2, 5 * r, np.where(r < 0.4, 2 - 5 * r, 0.0))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("snapshot")
    ap.add_argument("-o", "--output", default="gresho.png")
    args = ap.parse_args()
    with h5py.File(args.snapshot, "r") as f:
        t = float(f["Header"].attrs["Time"])
        x = f["PartType0/Coordinates"][...]
        v = f["PartType0/Velocities"][...]
    dx, dy = x[:, 0] - 0.5, x[:, 1] - 0.5
    r = np.hypot(dx, dy)
    vphi = np.where(r > 0, (-v[:, 0] * dy + v[:, 1] * dx) / np.maximum(r, 1e-300), 0.0)
    l1 = np.mean(np.abs(vphi - v_exact(r)))
    print(f"t = {t:.3g}: v_phi L1 per particle = {l1:.5f}")
    rr = np.linspace(0, 0.7, 300)
    plt.figure(figsize=(6, 4))
    plt.plot(r, vphi, ",", color="C0", alpha=0.4)
    plt.plot(rr, v_exact(rr), "k-")
    plt.xlim(0, 0.7)
    plt.xlabel("r")
    plt.ylabel("v_phi")
    plt.title(f"Gresho vortex, {len(r)} particles, t = {t:.3g}, L1 = {l1:.4f}")
    plt.tight_layout()
    save(plt.gcf(), args.output, dpi=110)
    print("wrote", args.output)


if __name__ == "__main__":
    main()
