#!/usr/bin/env python3
"""The halo mass function of the validation run against Jenkins et al. (2001) and Sheth &
Tormen (1999): the table of `fountain mass-function`, drawn, and COSMOLOGY.md C10.9's test
(every 0.25-dex bin in 10^12.6-13.6 Msun/h holding at least 70 halos within 25% of the Jenkins
count, and the mean ratio of those bins between 0.85 and 1.15). Exit status 1 if it fails.

    /usr/bin/python3 plot_mass_function.py mass_function.txt -o mass_function.png
"""
import argparse
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from figure_stamp import save  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("table")
    parser.add_argument("-o", "--output", default="mass_function.png")
    parser.add_argument("--test-range", type=float, nargs=2, default=[12.6, 13.6], metavar=("LO", "HI"))
    args = parser.parse_args()
    t = np.loadtxt(args.table, ndmin=2)
    lo, hi, count, jenkins, st = t.T
    mid = 0.5 * (lo + hi)

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6, 6), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    seen = count > 0
    top.errorbar(mid[seen], count[seen], yerr=np.sqrt(count[seen]), fmt="o", color="k", label="Fountain, FOF b = 0.2")
    top.plot(mid, jenkins, "-", color="C0", label="Jenkins et al. (2001)")
    top.plot(mid, st, "--", color="C1", label="Sheth & Tormen (1999)")
    top.set_yscale("log")
    top.set_ylabel("halos per bin")
    top.legend()
    with np.errstate(divide="ignore", invalid="ignore"):
        for ref, style, colour in ((jenkins, "o", "C0"), (st, "s", "C1")):
            ratio = count / ref
            bottom.errorbar(mid[seen], ratio[seen], yerr=np.sqrt(count[seen]) / ref[seen], fmt=style, color=colour,
                            mfc="none")
    bottom.axhline(1.0, color="0.5", lw=0.8)
    bottom.axhspan(0.75, 1.25, color="0.9", zorder=0)
    bottom.axvspan(*args.test_range, color="0.95", zorder=-1)
    bottom.set_ylim(0.4, 1.6)
    bottom.set_xlabel(r"$\log_{10} M_{\rm FOF}$ [$M_\odot/h$]")
    bottom.set_ylabel("counted / expected")
    fig.tight_layout()
    save(fig, args.output, dpi=110)

    test = (lo >= args.test_range[0] - 1e-9) & (hi <= args.test_range[1] + 1e-9)
    ok = bool(test.any())
    print("bin (log10 M)   count   Jenkins   ratio   Sheth-Tormen   ratio")
    for k in np.flatnonzero(test):
        ratio = count[k] / jenkins[k]
        print(f"{lo[k]:.2f}-{hi[k]:.2f}   {int(count[k]):5d}   {jenkins[k]:7.1f}   {ratio:5.3f}   {st[k]:7.1f}   "
              f"{count[k] / st[k]:5.3f}")
        ok = ok and count[k] >= 70 and abs(ratio - 1.0) <= 0.25
    mean = float(np.mean(count[test] / jenkins[test])) if test.any() else float("nan")
    ok = ok and 0.85 <= mean <= 1.15
    print(f"mean ratio to Jenkins in 10^{args.test_range[0]}-{args.test_range[1]}: {mean:.3f}; "
          f"C10.9 {'holds' if ok else 'fails'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
