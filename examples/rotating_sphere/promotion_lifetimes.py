#!/usr/bin/python3
"""How long feedback's promoted gas stays out of the cold phase, run by run: a markdown table.

    /usr/bin/python3 examples/rotating_sphere/promotion_lifetimes.py RUN_DIR... [--from GYR] [--to GYR]

Each RUN_DIR holds a run's statistics.txt (with its `promotions` column: promotions since the
start) and snapshot_0000.hdf5 (for the gas particles' mass). Over [from, to] (default 0.3 Gyr,
where star formation is under way, to the run's end) the promoted gas that is not cold,
mass_promoted_diffuse, averages M_d; promotions add mass at the rate R = (promotions in the
interval) x m_gas / (to - from), m_gas the mean initial gas particle mass. In a steady state
M_d = R tau, so tau = M_d / R is the mean time a promoted particle stays out of the cold phase
(Little's law; particles promoted again count once per promotion). Times in Myr, h = 1.
"""
import argparse
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_star_formation import GYR_PER_TIME  # noqa: E402
from plot_star_formation import read_statistics as read_star_formation_statistics  # noqa: E402

trapezoid = getattr(np, "trapezoid", None) or np.trapz  # numpy 2 renamed it


def read_statistics(path):
    s = read_star_formation_statistics(path)
    if "promotions" not in s:
        raise SystemExit(f"{path}: no promotions column (written by an older Fountain)")
    return s


def lifetime(run, t_from, t_to):
    s = read_statistics(os.path.join(run, "statistics.txt"))
    t = s["time"] * GYR_PER_TIME
    t_to = t[-1] if t_to is None else t_to
    inside = (t >= t_from) & (t <= t_to)
    if inside.sum() < 2:
        raise SystemExit(f"{run}: fewer than two statistics lines within [{t_from}, {t_to}] Gyr")
    tt, diffuse, promotions = t[inside], s["mass_promoted_diffuse"][inside], s["promotions"][inside]
    span = tt[-1] - tt[0]
    mean_diffuse = trapezoid(diffuse, tt) / span
    with h5py.File(os.path.join(run, "snapshot_0000.hdf5"), "r") as f:
        m_gas = float(np.mean(f["PartType0/InitialMasses"][...]))
    count = promotions[-1] - promotions[0]
    baryons = s["mass_gas"][0] + s["mass_stars"][0] + s["mass_stars_hidden"][0]
    rate = count * m_gas / span  # mass per Gyr
    tau_myr = 1e3 * mean_diffuse / rate if rate > 0 else float("inf")
    return {
        "run": os.path.basename(os.path.normpath(run)), "from": tt[0], "to": tt[-1], "count": int(count),
        "per_myr": count / (1e3 * span), "diffuse": mean_diffuse / baryons, "tau": tau_myr,
        "total": int(promotions[-1]),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--from", dest="t_from", type=float, default=0.3, help="Gyr (default 0.3)")
    ap.add_argument("--to", dest="t_to", type=float, default=None, help="Gyr (default: the run's end)")
    a = ap.parse_args()
    print("| run | interval (Gyr) | promotions in it | per Myr | promoted, not cold (mean, of the baryons) "
          "| mean time out of the cold phase (Myr) | promotions since the start |")
    print("|---|---|---|---|---|---|---|")
    for run in a.runs:
        r = lifetime(run, a.t_from, a.t_to)
        tau = f"{r['tau']:.2f}" if r["count"] > 0 else "- (no promotion)"
        print(f"| {r['run']} | {r['from']:.2f}-{r['to']:.2f} | {r['count']:,} | {r['per_myr']:.1f} | "
              f"{r['diffuse']:.4f} | {tau} | {r['total']:,} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
