"""Ewald's periodic field of a unit mass in a unit box (G = 1), from `fountain reference ewald`
(COSMOLOGY.md C6 and C10.6): the correction field along three lines with the published values,
and the largest error of sums cut narrower than the reference.
  python3 plot_ewald.py TABLE_DIR OUTPUT.png"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from figure_stamp import save  # noqa: E402

# COSMOLOGY.md C6: (point, correction field) as published.
PUBLISHED = [((0.25, 0, 0), (1.2464596, 0, 0)), ((0.1, 0.2, 0.3), (0.2128998, 0.5644484, 1.2980756)),
             ((0.4, 0.3, 0.2), (1.4671331, 0.5997325, 0.2116052)), ((0.5, 0, 0), (4, 0, 0)),
             ((0.5, 0.5, 0.5), (0.7698004, 0.7698004, 0.7698004))]
SELF_POTENTIAL = 2.8372975
# C6's convergence table: (images, h^2) -> largest error against (8, 64) at random points.
PUBLISHED_CUTS = {(2, 4): 3.6e-5, (3, 8): 1.1e-9, (4, 10): 9.5e-12}


def main(folder, out):
    lines = np.loadtxt(os.path.join(folder, "lines.txt"))
    points = np.loadtxt(os.path.join(folder, "published.txt"))
    cuts = np.loadtxt(os.path.join(folder, "convergence.txt"))
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.3))

    ax = axes[0]
    styles = {0: ("(s, 0, 0)", 1), 1: ("(s, s, s)", 1), 2: ("(s, 0.3, 0.2)", 1)}
    for line, (label, _) in styles.items():
        rows = lines[lines[:, 0] == line]
        s = rows[:, 1]
        for comp, ls in zip(range(3), ["-", "--", ":"]):
            if line == 1 and comp > 0:
                continue  # equal components on the diagonal
            if line == 0 and comp > 0:
                continue  # zero by symmetry
            ax.plot(s, rows[:, 4 + comp], ls, label=f"a_c,{'xyz'[comp]} on {label}")
    s = np.linspace(0, 0.2, 20)
    ax.plot(s, 4 * np.pi / 3 * s, "k:", lw=0.8, label="(4 pi/3) s (small s)")
    ax.set_xlabel("s")
    ax.set_ylabel("correction field a_c [G m / L^2]")
    ax.set_title("correction field along three lines")
    ax.legend(fontsize=7)

    ax = axes[1]
    errors = []
    for (x, ac) in PUBLISHED:
        row = next(r for r in points if np.allclose(r[:3], x))
        errors.append(np.max(np.abs(row[3:6] - np.array(ac))))
    self_err = abs(points[0, 6] - SELF_POTENTIAL)
    labels = [str(x) for x, _ in PUBLISHED] + ["phi_c(0)"]
    ax.bar(range(len(labels)), np.maximum(errors + [self_err], 1e-17), color="C0")
    ax.axhline(1e-7, color="k", ls="--", lw=0.8)
    ax.text(-0.4, 1.3e-7, "C10.6 bound 1e-7 (the published digits)", fontsize=8)
    ax.set_yscale("log")
    ax.set_ylim(1e-16, 1e-6)
    ax.set_xticks(range(len(labels)), labels, rotation=30, fontsize=7)
    ax.set_ylabel("|Fountain - published|, largest component")
    ax.set_title("published reference values")

    ax = axes[2]
    wide = (cuts[:, 2] == 2.0)
    by_images = cuts[wide & (cuts[:, 1] == 64) & (cuts[:, 0] < 8)]
    by_waves = cuts[wide & (cuts[:, 0] == 8)]
    floor = 1e-18
    ax.semilogy(by_images[:, 0], np.maximum(by_images[:, 3], floor), "o-", label="images |n_d| <= N (h^2 <= 64)")
    ax.semilogy(np.sqrt(by_waves[:, 1]), np.maximum(by_waves[:, 3], floor), "s-", label="waves h^2 <= H, N = 8 (x: sqrt H)")
    for (n, h2), e in PUBLISHED_CUTS.items():
        mine = cuts[wide & (cuts[:, 0] == n) & (cuts[:, 1] == h2)][0, 3]
        ax.semilogy([np.sqrt(h2)], [mine], "k^", ms=7, label="published cuts: Fountain" if n == 2 else None)
        ax.semilogy([np.sqrt(h2)], [e], "rv", ms=7, label="published cuts: published" if n == 2 else None)
        ax.annotate(f"({n}, {h2})", (np.sqrt(h2), mine), textcoords="offset points", xytext=(6, 4), fontsize=7)
    alpha = cuts[cuts[:, 2] != 2.0]
    if len(alpha):
        ax.axhline(alpha[0, 3], color="0.5", ls=":", lw=0.8)
        ax.text(0.1, alpha[0, 3] * 2, f"alpha 1.5/L against 2/L: {alpha[0, 3]:.1e}", fontsize=7)
    default = cuts[cuts[:, 0] == -1]
    if len(default):
        ax.text(0.1, 1e-17 if default[0, 3] < 1e-17 else default[0, 3] * 2,
                f"Fountain's default sums (reach 2.9 L, H = 36): {default[0, 3]:.1e}", fontsize=7)
    ax.set_xlabel("N  or  sqrt(H)")
    ax.set_ylabel("largest |a - a_reference| [G m / L^2]")
    ax.set_ylim(floor / 2, 10)
    ax.set_title("convergence against (N = 8, H = 64)")
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    save(fig, out, dpi=110)
    for label, e in zip(labels, errors + [self_err]):
        print(f"{label:16s} largest difference from the published value {e:.2e}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
