"""Zel'dovich's pancake against its exact solution (COSMOLOGY.md C10.3) at z = 4 and z = 1.5,
for runs with the paper's and the reconstructed viscosity: velocity, density and specific
internal energy against position along the wave, and the checks of C10.3 printed for each run.
  python3 plot_pancake.py PAPER_DIR RECONSTRUCTED_DIR OUTPUT.png"""
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from figure_stamp import save  # noqa: E402

BOX, A_C, A_BEGIN = 64.0, 0.5, 1.0 / 101.0
K = 2 * np.pi / BOX
U_BEGIN = 1.5 * 1.380649e-16 * 100.0 / (1.22 * 1.67262192369e-24) / 1e10  # 100 K, mu = 1.22, (km/s)^2


def read(path):
    with h5py.File(path, "r") as f:
        a = float(f["Header"].attrs["Time"])
        p = f["PartType0"]
        ids = p["ParticleIDs"][:].astype(np.int64) - 1
        n = round(len(ids) ** (1 / 3))
        q = ((ids // (n * n)) + 0.5) * BOX / n - 0.5 * BOX  # the lattice's x index gives q
        rho = p["Density"][:]
        rho_mean = p["Masses"][:].sum() / BOX**3
        return a, q, p["Coordinates"][:, 0], p["Velocities"][:, 0], rho / rho_mean, p["InternalEnergy"][:]


def exact(a, q):
    d = a / A_C
    x = q - d * np.sin(K * q) / K + 0.5 * BOX
    vel = -100.0 * np.sin(K * q) / (A_C * K)  # GADGET's v_pec / sqrt(a): constant in EdS
    contrast = 1.0 / (1.0 - d * np.cos(K * q))
    return x, vel, contrast, U_BEGIN * (A_BEGIN / a) ** 2 * contrast ** (2.0 / 3.0)  # physical u, adiabatic


def checks(a, q, x, vel, rho, u):
    xe, ve, re, te = exact(a, q)
    dx = x - xe
    dx -= BOX * np.round(dx / BOX)
    x_amp, v_amp = (a / A_C) / K, 100.0 / (A_C * K)
    return (np.sqrt(np.mean(dx**2)) / x_amp, np.sqrt(np.mean((vel - ve) ** 2)) / v_amp,
            np.median(np.abs(rho / re - 1)), np.median(np.abs(u / te - 1)))


def main(paper, reconstructed, out):
    runs = [("paper's viscosity", paper, "tab:red"), ("reconstructed viscosity", reconstructed, "tab:blue")]
    fig, axes = plt.subplots(2, 3, figsize=(13, 7), sharex=True)
    for row, snap in enumerate(("snapshot_0001.hdf5", "snapshot_0002.hdf5")):
        for label, directory, colour in runs:
            a, q, x, vel, rho, u = read(os.path.join(directory, snap))
            ex, ev, er, et = checks(a, q, x, vel, rho, u)
            print(f"{label}, z = {1 / a - 1:.2f}: rms x {ex:.2e}, rms v {ev:.2e} (of the amplitudes), median "
                  f"|rho/rho_exact - 1| {er:.2e}, median |u/u_exact - 1| {et:.2e}")
            axes[row, 0].plot(x, vel, ".", ms=2, color=colour, label=label)
            axes[row, 1].plot(x, rho, ".", ms=2, color=colour)
            axes[row, 2].plot(x, u, ".", ms=2, color=colour)
        qq = np.linspace(-BOX / 2, BOX / 2, 2001)
        xe, ve, re, te = exact(a, qq)
        for col, values in enumerate((ve, re, te)):
            axes[row, col].plot(xe, values, "k-", lw=1, label="exact" if col == 0 else None)
        axes[row, 0].set_ylabel(f"z = {1 / a - 1:.1f}\nv_pec / sqrt(a) [km/s]")
        axes[row, 1].set_ylabel("rho / mean")
        axes[row, 2].set_ylabel("u [(km/s)^2, physical]")
        axes[row, 2].set_yscale("log")
    for col in range(3):
        axes[1, col].set_xlabel("x [Mpc/h, comoving]")
    axes[0, 0].legend(markerscale=5, fontsize=8)
    fig.suptitle("Zel'dovich pancake, 32^3 gas particles, caustic at z = 1")
    fig.tight_layout()
    save(fig, out, dpi=110)


if __name__ == "__main__":
    main(*sys.argv[1:4])
