"""Power of the three longest-wave shells of a dark-matter box against linear theory.

    python3 plot_linear_growth.py RUN_FOLDER [PARTNER_FOLDER]

Reads RUN_FOLDER/snapshot_0000..0003.hdf5 (a = a_begin, 0.25, 0.5, 1), puts the particles on
a mesh twice as fine as their lattice by cloud-in-cell, divides by the assignment window, and
sums |delta_k|^2 over the shells k/k_f in (0.5, 1.5], (1.5, 2.5], (2.5, 3.5]. Linear theory
is the first snapshot's sums times (D(a)/D(a_begin))^2, D from the snapshot's cosmology.
With a partner run (the same field with its sign reversed), the pair's mean power is judged:
the realisation's second-order term, odd in the field, cancels in it, and what is left is the
linear growth the bounds are about. Each run's own ratios are printed too, and the pair's
half-difference (the odd part, led by the realisation's second-order term) against what
second-order perturbation theory predicts for this field: delta_1 from the two initial
snapshots (x_A - x_B = 2 D psi_1 exactly), delta_2 = (17/21) delta_1^2 - psi_1.grad delta_1
+ (2/7) s_ij s_ij, odd part 2 D(a) sum Re(delta_1* delta_2) / sum |delta_1|^2 per shell.
Prints the ratios and writes linear_growth.png beside this script's docs figure.
"""
import functools
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


@functools.lru_cache(maxsize=None)
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


def ratios_of(folders):
    """Rows (a, [ratio per shell]) of the runs' summed shell power against linear theory."""
    first = [shell_power(os.path.join(f, "snapshot_0000.hdf5")) for f in folders]
    a0, om, ol = first[0][:3]
    p0 = [sum(r[3][s] for r in first) for s in range(3)]
    rows = []
    for k in (1, 2, 3):
        later = [shell_power(os.path.join(f, f"snapshot_000{k}.hdf5")) for f in folders]
        a = later[0][0]
        g = (growth(a, om, ol) / growth(a0, om, ol)) ** 2
        rows.append((a, [sum(r[3][s] for r in later) / (g * p0[s]) for s in range(3)]))
    return rows


def lattice_positions(path):
    """Positions in ID order (ID 1 + n for lattice cell n = (i N + j) N + k), box, a, N."""
    with h5py.File(path, "r") as f:
        x = f["/PartType1/Coordinates"][...]
        ids = f["/PartType1/ParticleIDs"][...]
        box = float(np.ravel(f["/Header"].attrs["BoxSize"])[0])
        a = float(f["/Header"].attrs["Time"])
    n = int(round(len(x) ** (1 / 3)))
    return x[np.argsort(ids)], box, a, n


def second_order_odd_part(folders):
    """Per shell, 2 sum Re(delta_1* delta_2) / sum |delta_1|^2 at D = 1, of the pair's field."""
    xa, box, a0, n = lattice_positions(os.path.join(folders[0], "snapshot_0000.hdf5"))
    xb = lattice_positions(os.path.join(folders[1], "snapshot_0000.hdf5"))[0]
    om, ol = shell_power(os.path.join(folders[0], "snapshot_0000.hdf5"))[1:3]
    d = xa - xb
    d -= box * np.round(d / box)
    psi = (0.5 * d / (growth(a0, om, ol) / growth(1.0, om, ol))).reshape(n, n, n, 3)
    m = np.fft.fftfreq(n, 1.0 / n)
    k = np.array(np.meshgrid(m, m, m, indexing="ij")) * (2 * np.pi / box)
    k2 = np.sum(k * k, axis=0)
    k2[0, 0, 0] = 1.0
    psi_k = [np.fft.fftn(psi[..., c]) for c in range(3)]
    delta_k = -1j * sum(k[c] * psi_k[c] for c in range(3))
    delta = np.fft.ifftn(delta_k).real
    grad = [np.fft.ifftn(1j * k[c] * delta_k).real for c in range(3)]
    tidal2 = 0.0
    for i in range(3):
        for j in range(3):
            s_ij = np.fft.ifftn(k[i] * k[j] / k2 * delta_k).real - (delta / 3 if i == j else 0.0)
            tidal2 = tidal2 + s_ij * s_ij
    # The displacement of the linear field itself (-grad phi_1), so that the term is exact
    # second order whatever the small second-order part of the snapshots' own displacements.
    psi_lin = [np.fft.ifftn(1j * k[c] / k2 * delta_k).real for c in range(3)]
    delta2 = 17 / 21 * delta**2 - sum(p * g for p, g in zip(psi_lin, grad)) + 2 / 7 * tidal2
    delta2_k = np.fft.fftn(delta2)
    kk = np.sqrt(k2) / (2 * np.pi / box)
    out = []
    for s in (1, 2, 3):
        sel = (kk > s - 0.5) & (kk <= s + 0.5)
        out.append(2 * np.sum((np.conj(delta_k[sel]) * delta2_k[sel]).real) / np.sum(np.abs(delta_k[sel]) ** 2))
    return out, om, ol


def main(argv):
    folders = argv[1:] if len(argv) > 1 else ["run"]
    limits = {0.25: 0.03, 0.5: 0.05, 1.0: 0.08}
    runs = {f: ratios_of([f]) for f in folders}
    for f, rows in runs.items():
        print(f"{f}: " + "; ".join(f"a = {a:.3f}: " + ", ".join(f"{r:.3f}" for r in ratios) for a, ratios in rows))
    rows = ratios_of(folders) if len(folders) > 1 else runs[folders[0]]
    if len(folders) == 2:
        odd, om, ol = second_order_odd_part(folders)
        for (a, ra), (_, rb) in zip(runs[folders[0]], runs[folders[1]]):
            dratio = growth(a, om, ol) / growth(1.0, om, ol)
            print(f"a = {a:.3f}: odd part (first - second)/2 = "
                  + ", ".join(f"{(x - y) / 2:+.3f}" for x, y in zip(ra, rb))
                  + "; second-order theory " + ", ".join(f"{dratio * o:+.3f}" for o in odd))
    ok = True
    for a, ratios in rows:
        lim = limits.get(round(a, 2), 0.08)
        verdict = all(abs(r - 1) <= lim for r in ratios)
        ok = ok and verdict
        print(f"a = {a:.3f}: {'pair mean' if len(folders) > 1 else 'shell power'} / linear = "
              + ", ".join(f"{r:.3f}" for r in ratios) + f"   (within {lim:.0%}: {'yes' if verdict else 'no'})")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for s in range(3):
        line, = ax.plot([r[0] for r in rows], [r[1][s] for r in rows], "o-",
                        label=f"k = {s + 1} k_f" + (", pair mean" if len(folders) > 1 else ""))
        if len(folders) > 1:
            for style, f in zip((":", "--"), folders):
                ax.plot([r[0] for r in runs[f]], [r[1][s] for r in runs[f]], style, color=line.get_color(), lw=0.9)
    for a, lim in limits.items():
        ax.plot([a, a], [1 - lim, 1 + lim], color="0.6", lw=4, alpha=0.4)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("scale factor a")
    ax.set_ylabel("P(k, a) / [D(a)/D(a_i)]^2 P(k, a_i)")
    title = "64^3 dark matter in 256 Mpc/h: longest waves grow as D(a)^2"
    if len(folders) > 1:
        title += "\n(dotted: seed 1, dashed: its sign-reversed partner)"
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "docs", "validation", "linear_growth.png")
    save(fig, out, dpi=110, bbox_inches="tight")
    print(f"wrote {os.path.normpath(out)}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
