"""Power of the three longest-wave shells of a dark-matter box against linear theory.

    python3 plot_linear_growth.py RUN_FOLDER

Reads RUN_FOLDER/snapshot_0000..0003.hdf5 (a = a_begin, 0.25, 0.5, 1), puts the particles on
a mesh twice as fine as their lattice by cloud-in-cell, divides by the assignment window, and
sums |delta_k|^2 over the shells k/k_f in (0.5, 1.5], (1.5, 2.5], (2.5, 3.5]. Linear theory
is the first snapshot's sums times (D(a)/D(a_begin))^2, D from the snapshot's cosmology.
Prints the ratios and writes linear_growth.png beside this script's docs figure.
"""
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from figure_stamp import save  # noqa: E402


def growth(a, om, ol):
    """Linear growth D(a) (normalised to a at early times) for matter + Lambda + curvature."""
    ok = 1.0 - om - ol
    x = np.linspace(1e-6, a, 20001)
    e = np.sqrt(om / x**3 + ok / x**2 + ol)
    integrand = 1.0 / (x * e) ** 3
    ea = np.sqrt(om / a**3 + ok / a**2 + ol)
    return 2.5 * om * ea * np.trapz(integrand, x)


def shell_power(path):
    with h5py.File(path, "r") as f:
        x = f["/PartType1/Coordinates"][...]
        box = float(np.ravel(f["/Header"].attrs["BoxSize"])[0])
        a = float(f["/Header"].attrs["Time"])
        om = float(f["/Header"].attrs["Omega0"])
        ol = float(f["/Header"].attrs["OmegaLambda"])
    n = int(round(len(x) ** (1 / 3)))
    mesh = 2 * n
    u = x / box * mesh - 0.5
    i0 = np.floor(u).astype(np.int64)
    w1 = u - i0
    rho = np.zeros((mesh, mesh, mesh))
    for c in range(8):
        bits = [(c >> d) & 1 for d in range(3)]
        w = np.ones(len(x))
        idx = []
        for d in range(3):
            w *= w1[:, d] if bits[d] else 1.0 - w1[:, d]
            idx.append((i0[:, d] + bits[d]) % mesh)
        np.add.at(rho, tuple(idx), w)
    delta = rho / rho.mean() - 1.0
    dk = np.fft.rfftn(delta)
    m = np.fft.fftfreq(mesh, 1.0 / mesh)
    mz = np.fft.rfftfreq(mesh, 1.0 / mesh)
    mx, my, mzz = np.meshgrid(m, m, mz, indexing="ij")
    window = (np.sinc(mx / mesh) * np.sinc(my / mesh) * np.sinc(mzz / mesh)) ** 2
    p = np.abs(dk / window) ** 2
    # Modes with kz > 0 stand for their conjugates too.
    weight = np.where((mzz > 0) & (mzz < mesh // 2), 2.0, 1.0)
    kk = np.sqrt(mx**2 + my**2 + mzz**2)
    sums = [float(np.sum((p * weight)[(kk > s - 0.5) & (kk <= s + 0.5)])) for s in (1, 2, 3)]
    return a, om, ol, sums


def main(argv):
    folder = argv[1] if len(argv) > 1 else "run"
    a0, om, ol, p0 = shell_power(os.path.join(folder, "snapshot_0000.hdf5"))
    rows = []
    for k in (1, 2, 3):
        a, _, _, p = shell_power(os.path.join(folder, f"snapshot_000{k}.hdf5"))
        g = (growth(a, om, ol) / growth(a0, om, ol)) ** 2
        rows.append((a, [p[s] / (g * p0[s]) for s in range(3)]))
    limits = {0.25: 0.03, 0.5: 0.05, 1.0: 0.08}
    ok = True
    for a, ratios in rows:
        lim = limits.get(round(a, 2), 0.08)
        verdict = all(abs(r - 1) <= lim for r in ratios)
        ok = ok and verdict
        print(f"a = {a:.3f}: shell power / linear = " + ", ".join(f"{r:.3f}" for r in ratios)
              + f"   (within {lim:.0%}: {'yes' if verdict else 'no'})")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for s in range(3):
        ax.plot([r[0] for r in rows], [r[1][s] for r in rows], "o-", label=f"k = {s + 1} k_f")
    for a, lim in limits.items():
        ax.plot([a, a], [1 - lim, 1 + lim], color="0.6", lw=4, alpha=0.4)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("scale factor a")
    ax.set_ylabel("P(k, a) / [D(a)/D(a_i)]^2 P(k, a_i)")
    ax.set_title("64^3 dark matter in 256 Mpc/h: longest waves grow as D(a)^2", fontsize=9)
    ax.legend(fontsize=8)
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "docs", "validation", "linear_growth.png")
    save(fig, out, dpi=110, bbox_inches="tight")
    print(f"wrote {os.path.normpath(out)}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
