#!/usr/bin/env python3
"""Density against radius of a Sedov snapshot, over the self-similar solution (PNG)."""
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


def exact_profile(t, energy=1.0, rho0=1.0):
    table = np.loadtxt(os.path.join(ROOT, "data", "hydro_tests", "sedov_selfsimilar_gamma5_3.txt"))
    r_shock = 1.15167 * (energy * t * t / rho0) ** 0.2
    eta, rho = table[:, 0], table[:, 1]
    order = np.argsort(eta)
    r = np.concatenate([eta[order] * r_shock, [r_shock, 0.5]])
    return r, np.concatenate([rho[order] * rho0, [rho0, rho0]]), r_shock


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("snapshot")
    ap.add_argument("-o", "--output", default="sedov_density.png")
    args = ap.parse_args()
    with h5py.File(args.snapshot, "r") as f:
        t = float(f["Header"].attrs["Time"])
        box = np.atleast_1d(f["Header"].attrs["BoxSize"]).astype(float)
        x = f["PartType0/Coordinates"][...]
        rho = f["PartType0/Density"][...]
    d = x - 0.5 * box
    d -= box * np.round(d / box)
    r = np.sqrt((d * d).sum(axis=1))
    bins = np.linspace(0, 0.5, 51)
    which = np.digitize(r, bins) - 1
    mean = np.array([rho[which == k].mean() if np.any(which == k) else np.nan for k in range(50)])
    centres = 0.5 * (bins[1:] + bins[:-1])
    re, rhoe, r_shock = exact_profile(t)
    peak = centres[np.nanargmax(mean)]
    print(f"t = {t:.4g}: binned density peaks at r = {peak:.4f}; exact shock radius {r_shock:.4f}")
    plt.figure(figsize=(6, 4.2))
    plt.plot(r, rho, ",", color="0.6", alpha=0.5, label="particles")
    plt.plot(centres, mean, "o-", ms=3, color="C0", label="binned mean")
    plt.plot(re, rhoe, "k-", lw=1.2, label="Sedov-Taylor (exact)")
    plt.xlim(0, 0.5)
    plt.xlabel("r")
    plt.ylabel("density")
    plt.title(f"Sedov blast, {len(r)} particles, t = {t:.3g}")
    plt.legend()
    plt.tight_layout()
    save(plt.gcf(), args.output, dpi=120)
    print("wrote", args.output)


if __name__ == "__main__":
    main()
