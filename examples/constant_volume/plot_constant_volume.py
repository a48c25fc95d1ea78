"""The uniform expanding box (COSMOLOGY.md C10.2) from the snapshots of run.sh: the largest
change over all particles of u a^2 (T a^2), of the comoving density and of the place on the
lattice, against a, for each run given.
  python3 plot_constant_volume.py RUN_DIR [RUN_DIR ...] OUTPUT.png"""
import glob
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from figure_stamp import save  # noqa: E402

BOUND = 1e-3  # C10.2, for each of the three measures


def read(path):
    with h5py.File(path, "r") as f:
        p = f["PartType0"]
        order = np.argsort(p["ParticleIDs"][:])
        return {"a": float(f["Header"].attrs["Time"]), "box": float(f["Header"].attrs["BoxSize"]),
                "omega_m": float(f["Header"].attrs["Omega0"]), "x": p["Coordinates"][:][order],
                "rho": p["Density"][:][order], "u": p["InternalEnergy"][:][order], "T": p["Temperature"][:][order]}


def measures(run):
    snaps = [read(s) for s in sorted(glob.glob(os.path.join(run, "snapshot_*.hdf5")))]
    first = snaps[0]
    n = round(len(first["x"]) ** (1 / 3))
    spacing = first["box"] / n
    rows = []
    for s in snaps:
        du = np.abs(s["u"] * s["a"] ** 2 / (first["u"] * first["a"] ** 2) - 1).max()
        drho = np.abs(s["rho"] / first["rho"] - 1).max()
        d = s["x"] - first["x"]
        d -= s["box"] * np.round(d / s["box"])
        dx = np.sqrt((d**2).sum(axis=1)).max() / spacing
        rows.append((s["a"], du, drho, dx, np.median(s["T"])))
    return first, np.array(rows)


def main(runs, out):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.3))
    for run, color in zip(runs, ["C0", "C1", "C2"]):
        first, rows = measures(run)
        label = f"{os.path.basename(run.rstrip('/'))} (Omega_m {first['omega_m']:g})"
        a = rows[:, 0]
        floor = 1e-12
        for col, marker, what in [(1, "o", "u a^2"), (2, "s", "rho'"), (3, "^", "place / spacing")]:
            axes[0].loglog(a[1:], np.maximum(rows[1:, col], floor), marker + "-", color=color, lw=1,
                           label=f"{label}: {what}")
        axes[1].loglog(a, rows[:, 4], marker="o", color=color, lw=0, label=f"{label}: median T")
        print(f"{label}: at a = {a[-1]:.4g} |u a^2 change| <= {rows[-1, 1]:.2e}, |rho' change| <= {rows[-1, 2]:.2e}, "
              f"displacement <= {rows[-1, 3]:.2e} spacings; largest over the snapshots "
              f"{rows[1:, 1].max():.2e}, {rows[1:, 2].max():.2e}, {rows[1:, 3].max():.2e}")
    axes[0].axhline(BOUND, color="k", ls="--", lw=0.8)
    axes[0].text(a[1], BOUND * 1.3, "C10.2 bound", fontsize=8)
    axes[0].set_ylim(1e-12, 1e-2)
    axes[0].set_xlabel("a")
    axes[0].set_ylabel("largest change over the particles since a = 1/64")
    axes[0].set_title("32^3 gas lattice at rest, gravity and hydro")
    axes[0].legend(fontsize=6.5, ncol=2, loc="lower right")
    grid = np.geomspace(a[0], 1, 50)
    axes[1].loglog(grid, rows[0, 4] * (a[0] / grid) ** 2, "k-", lw=0.8, label="T_i (a_i / a)^2")
    axes[1].set_xlabel("a")
    axes[1].set_ylabel("T [K]")
    axes[1].set_title("temperature of adiabatic expansion")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    save(fig, out, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1:-1], sys.argv[-1])
