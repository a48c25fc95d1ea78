#!/usr/bin/env python3
"""Star formation and feedback time series of rotating-sphere runs (like Marri & White 2003,
Figs 4 and 5): gas phases, stars and promoted gas as fractions of the baryons, the star
formation rate, and the energy budget, from each run's statistics.txt.

    /usr/bin/python3 examples/rotating_sphere/plot_star_formation.py out/R02 out/R04 \
        --labels R02 R04 -o star_formation.png [--table table.md]

Times in Gyr for h = 1 (the internal time unit Mpc/(km/s) is 977.8 Gyr). Phases as in the
paper's section 3.2: hot T > 2 T*, cold T <= 2 T* and rho > 0.1 rho*, warm otherwise.
`--warm-and-hot` plots warm + hot gas in the hot panel, as the paper's Fig 5 does for its mass
sequence (the virial temperatures of G09-G12 differ too much for the split to mean much).
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import sys  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from figure_stamp import save  # noqa: E402


GYR_PER_TIME = 977.8


def read_statistics(path):
    with open(path) as f:
        names = [line for line in f if line.startswith("#")][-1].lstrip("#").split()
    data = np.loadtxt(path, comments="#", ndmin=2)
    if data.shape[1] != len(names):
        raise SystemExit(f"{path}: {data.shape[1]} columns but the header names {len(names)}")
    s = {n: data[:, k] for k, n in enumerate(names)}
    if "mass_stars" not in s:
        raise SystemExit(f"{path}: no star formation columns (written by an older Fountain?)")
    return s


def baryons(s):
    return s["mass_gas"] + s["mass_stars"] + s["mass_stars_hidden"]


def summary(s, at_gyr=None):
    """Figures at the last line (or the last at or before at_gyr): fractions of the baryons
    and the total stellar mass."""
    k = len(s["time"]) - 1
    if at_gyr is not None:
        k = int(np.searchsorted(s["time"] * GYR_PER_TIME, at_gyr * (1 + 1e-9), side="right")) - 1
    b = baryons(s)[k]
    stars = s["mass_stars"][k] + s["mass_stars_hidden"][k]
    return {
        "t_gyr": s["time"][k] * GYR_PER_TIME,
        "stars": stars / b,
        "hot": s["mass_hot"][k] / b,
        "warm": s["mass_warm"][k] / b,
        "cold": s["mass_cold"][k] / b,
        "unbound": s["mass_unbound"][k] / b,
        "promoted": s["mass_promoted_diffuse"][k] / b,
        "stellar_mass": stars,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", help="run folders (each with statistics.txt)")
    ap.add_argument("--labels", nargs="*")
    ap.add_argument("-o", "--output", default="star_formation.png")
    ap.add_argument("--table", help="also write a Markdown table of the last line's fractions here")
    ap.add_argument("--title", default="")
    ap.add_argument("--at", type=float, help="table at this time (Gyr; default: each run's last line)")
    ap.add_argument("--warm-and-hot", action="store_true",
                    help="the hot panel shows warm + hot gas (the paper's Fig 5)")
    a = ap.parse_args()
    labels = a.labels if a.labels else [os.path.basename(os.path.normpath(r)) for r in a.runs]
    if len(labels) != len(a.runs):
        raise SystemExit("give one label per run")
    stats = [read_statistics(os.path.join(r, "statistics.txt")) for r in a.runs]

    fig, ax = plt.subplots(2, 3, figsize=(15, 8.5))
    panels = [
        (ax[0, 0], "cold gas", lambda s: s["mass_cold"] / baryons(s)),
        (ax[0, 1], "warm + hot gas", lambda s: (s["mass_warm"] + s["mass_hot"]) / baryons(s))
        if a.warm_and_hot else (ax[0, 1], "hot gas", lambda s: s["mass_hot"] / baryons(s)),
        (ax[0, 2], "stars (particles + hidden)", lambda s: (s["mass_stars"] + s["mass_stars_hidden"]) / baryons(s)),
        (ax[1, 1], "unbound gas", lambda s: s["mass_unbound"] / baryons(s)),
        (ax[1, 2], "promoted gas still diffuse", lambda s: s["mass_promoted_diffuse"] / baryons(s)),
    ]
    for s, label in zip(stats, labels):
        t = s["time"] * GYR_PER_TIME
        for axis, _, f in panels:
            axis.plot(t, f(s), label=label)
        ax[1, 0].plot(t[1:], s["sfr_msun_per_yr"][1:], label=label)
    for axis, title, _ in panels:
        axis.set_title(title)
        axis.set_ylabel("fraction of baryons")
    ax[1, 0].set_title("star formation rate")
    ax[1, 0].set_ylabel(r"SFR [M$_\odot$/yr]")
    for axis in ax.flat:
        axis.set_xlabel("t [Gyr]")
        axis.grid(alpha=0.3)
    ax[0, 0].legend()
    if a.title:
        fig.suptitle(a.title)
    fig.tight_layout()
    save(fig, a.output, dpi=110)
    print(f"wrote {a.output}")

    rows = [(label, summary(s, a.at)) for s, label in zip(stats, labels)]
    text = ("| run | t [Gyr] | stars | cold | warm | hot | unbound | promoted, diffuse | M* [Msun/h] |\n"
            "|---|---|---|---|---|---|---|---|---|\n")
    for label, r in rows:
        text += (f"| {label} | {r['t_gyr']:.2f} | {r['stars']:.3f} | {r['cold']:.3f} | {r['warm']:.3f} | "
                 f"{r['hot']:.3f} | {r['unbound']:.3f} | {r['promoted']:.3f} | {r['stellar_mass']:.3e} |\n")
    print(text, end="")
    if a.table:
        with open(a.table, "w") as f:
            f.write(text)


if __name__ == "__main__":
    main()
