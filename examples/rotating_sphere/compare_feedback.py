#!/usr/bin/env python3
"""Compares runs R01-R05 and G09-G12 of run_feedback.sh with what Marri & White (2003)
report in their section 3.3, point by point, as a Markdown table (at the runs' last line).

    /usr/bin/python3 examples/rotating_sphere/compare_feedback.py examples/rotating_sphere/output/feedback_2000 [T_GYR]

With T_GYR, every run is read at its last line at or before that time (runs of different
lengths compare at a common time), and a run that stopped before it (at dt_min, say) is left
out of the claims and named.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_star_formation import GYR_PER_TIME, read_statistics, summary  # noqa: E402


def main(folder, at_gyr=None):
    runs, short = {}, []
    for name in ("R01", "R02", "R03", "R04", "R05", "G09", "G10", "G11", "G12"):
        path = os.path.join(folder, name, "statistics.txt")
        if os.path.exists(path):
            s = read_statistics(path)
            end_gyr = s["time"][-1] * GYR_PER_TIME
            if at_gyr is not None and end_gyr < 0.99 * at_gyr:
                short.append(f"{name} (ends at {end_gyr:.2f} Gyr)")
                continue
            runs[name] = summary(s, at_gyr)
    if short:
        print(f"Left out, as they stopped before {at_gyr:g} Gyr: {', '.join(short)}.\n")
    rows = []

    def row(claim, ours, holds):
        rows.append(f"| {claim} | {ours} | {'yes' if holds else 'no'} |")

    if {"R01", "R02"} <= runs.keys():
        r1, r2 = runs["R01"], runs["R02"]
        row("MSPH alone (R02) forms fewer stars than SPH (R01)",
            f"stars {r2['stars']:.3f} vs {r1['stars']:.3f} of the baryons", r2["stars"] < r1["stars"])
        row("... and keeps more hot gas", f"hot {r2['hot']:.3f} vs {r1['hot']:.3f}", r2["hot"] > r1["hot"])
    if "R02" in runs:
        for name in ("R03", "R04", "R05"):
            if name in runs:
                cut = 1.0 - runs[name]["stars"] / runs["R02"]["stars"]
                row(f"{name} cuts star formation ~20% below R02", f"{100 * cut:.0f}% less stellar mass",
                    0.1 <= cut <= 0.3)
    if {"R03", "R05"} <= runs.keys():
        r3, r5 = runs["R03"], runs["R05"]
        row("high eps_h (R03) gives more hot gas than high eps_c (R05)", f"hot {r3['hot']:.3f} vs {r5['hot']:.3f}",
            r3["hot"] > r5["hot"])
        row("... and more unbound gas", f"unbound {r3['unbound']:.3f} vs {r5['unbound']:.3f}",
            r3["unbound"] > r5["unbound"])
    if {"G09", "G12"} <= runs.keys():
        ratio = runs["G12"]["stars"] / max(runs["G09"]["stars"], 1e-30)
        row("G09 turns baryons into stars ~9x less efficiently than G12",
            f"G12/G09 stellar fractions {runs['G12']['stars']:.3f}/{runs['G09']['stars']:.3f} = {ratio:.1f}",
            6.0 <= ratio <= 13.5)  # within a factor 1.5 of 9
    g = [n for n in ("G09", "G10", "G11", "G12") if n in runs]
    if len(g) >= 2:
        unbound = [runs[n]["unbound"] for n in g]
        row("less massive objects lose a larger fraction of their gas (unbound)",
            ", ".join(f"{n} {u:.3f}" for n, u in zip(g, unbound)), all(a >= b for a, b in zip(unbound, unbound[1:])))
    if not runs:
        print(f"No run of R01-R05 or G09-G12 has statistics in {folder}.")
        return
    if not rows:
        print(f"The paper's claims (section 3.3) each compare two or more of R01-R05 or G09-G12; of these, "
              f"only {', '.join(runs)} ran here, so there is nothing to compare. Run the full set with "
              f"sh examples/rotating_sphere/run_feedback.sh.")
        return
    times = sorted({round(r["t_gyr"], 2) for r in runs.values()})
    print(f"At t = {', '.join(f'{t:.2f}' for t in times)} Gyr (fractions of each run's baryons):\n")
    print("| the paper (section 3.3) | these runs | holds |\n|---|---|---|")
    print("\n".join(rows))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "examples/rotating_sphere/output/feedback_2000",
         float(sys.argv[2]) if len(sys.argv) > 2 else None)
