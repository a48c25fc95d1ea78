#!/usr/bin/env python3
"""Exits 0 when two snapshots hold bitwise-identical particle data, else names what differs."""
import sys

import h5py
import numpy as np


def main(a_path, b_path):
    with h5py.File(a_path, "r") as a, h5py.File(b_path, "r") as b:
        differ = []
        groups_a = sorted(g for g in a if g.startswith("PartType"))
        groups_b = sorted(g for g in b if g.startswith("PartType"))
        if groups_a != groups_b:
            differ.append(f"particle groups {groups_a} vs {groups_b}")
        for group in [g for g in groups_a if g in groups_b]:
            if sorted(a[group]) != sorted(b[group]):
                differ.append(f"/{group} datasets {sorted(a[group])} vs {sorted(b[group])}")
            for name in [n for n in a[group] if n in b[group]]:
                x, y = a[group][name][...], b[group][name][...]
                if x.shape != y.shape or x.dtype != y.dtype or x.tobytes() != y.tobytes():
                    differ.append(f"/{group}/{name}")
        if a["Header"].attrs["Time"] != b["Header"].attrs["Time"]:
            differ.append("/Header/Time")
    if differ:
        print("snapshots differ in:", ", ".join(differ))
        return 1
    print("identical:", a_path, b_path, "(" + ", ".join(groups_a) + ")")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
