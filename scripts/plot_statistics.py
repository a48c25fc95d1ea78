#!/usr/bin/env python3
"""Plots Fountain statistics files (<output>/statistics.txt): gas phase fractions, thermal
energy, unbound gas, and the conservation of total energy and momentum.

    /usr/bin/python3 scripts/plot_statistics.py run_a/statistics.txt run_b/statistics.txt \
        --labels SPH MSPH -o stats.png [--time-unit-gyr 977.8]

Times are multiplied by --time-unit-gyr (the default internal unit Mpc/(km/s) is 977.8 Gyr, h = 1).
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import sys  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from figure_stamp import save  # noqa: E402



def read(path):
    with open(path) as f:
        header = [line for line in f if line.startswith("#")]
    names = header[-1].lstrip("#").split()
    data = np.loadtxt(path, comments="#", ndmin=2)
    if data.shape[1] != len(names):
        raise SystemExit(f"{path}: {data.shape[1]} columns but the header names {len(names)}")
    return {n: data[:, k] for k, n in enumerate(names)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--labels", nargs="*")
    ap.add_argument("-o", "--output", default="statistics.png")
    ap.add_argument("--time-unit-gyr", type=float, default=977.8)
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    labels = a.labels if a.labels else a.files
    if len(labels) != len(a.files):
        raise SystemExit("give one label per file")

    fig, ax = plt.subplots(2, 3, figsize=(14, 7.5))
    styles = ["-", "--", ":", "-."]
    for k, (path, label) in enumerate(zip(a.files, labels)):
        s = read(path)
        t = s["time"] * a.time_unit_gyr
        gas = s["mass_gas"]
        ls = styles[k % len(styles)]
        lw = 1.0 + 0.6 * k
        for name, colour in (("hot", "tab:red"), ("warm", "tab:green"), ("cold", "tab:blue")):
            ax[0, 0].plot(t, s[f"mass_{name}"] / gas, ls, color=colour, lw=lw, label=f"{name}, {label}")
        ax[0, 1].plot(t, s["thermal_energy"], ls, lw=lw, label=label)
        ax[0, 2].plot(t, s["mass_unbound"] / gas, ls, lw=lw, label=label)
        # Radiated energy (column added later; older files lack it) closes the budget.
        e = s["total_energy"] + s.get("radiated_energy", 0.0)
        ax[1, 0].plot(t, (e - e[0]) / abs(e[0]), ls, lw=lw, label=label)
        scale = np.sqrt(2.0 * s["kinetic_energy"] * (s["mass_gas"] + s["mass_dark_matter"]))
        p = np.sqrt(s["momentum_x"] ** 2 + s["momentum_y"] ** 2 + s["momentum_z"] ** 2)
        ax[1, 1].semilogy(t, np.maximum(p / np.maximum(scale, 1e-300), 1e-20), ls, lw=lw, label=label)
        lz0 = s["angular_momentum_z"][0]
        if lz0 != 0:
            ax[1, 2].plot(t, s["angular_momentum_z"] / lz0 - 1.0, ls, lw=lw, label=label)
    ax[0, 0].set_ylabel("gas mass fraction")
    ax[0, 0].legend(fontsize=7, ncol=2)
    ax[0, 1].set_ylabel("total thermal energy (internal units)")
    ax[0, 2].set_ylabel("unbound gas fraction")
    ax[1, 0].set_ylabel("(E + E_radiated) / |E0| - 1")
    ax[1, 1].set_ylabel("|total momentum| / sqrt(2 K M)")
    ax[1, 2].set_ylabel("L_z / L_z(0) - 1")
    for x in ax.flat:
        x.set_xlabel("t (Gyr)")
        x.grid(alpha=0.3)
    ax[0, 1].legend(fontsize=8)
    if a.title:
        fig.suptitle(a.title)
    fig.tight_layout()
    save(fig, a.output, dpi=110)
    print(f"wrote {a.output}")


if __name__ == "__main__":
    main()
