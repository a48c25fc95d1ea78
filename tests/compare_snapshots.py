#!/usr/bin/env python3
"""Exits 0 when two snapshots hold bitwise-identical particle data, else names what differs."""
import sys

import h5py
import numpy as np


def main(a_path, b_path):
    with h5py.File(a_path, "r") as a, h5py.File(b_path, "r") as b:
        differ = []
        for group in [g for g in a if g.startswith("PartType")]:
            for name in a[group]:
                x, y = a[group][name][...], b[group][name][...]
                if x.shape != y.shape or x.tobytes() != y.tobytes():
                    differ.append(f"/{group}/{name}")
        if a["Header"].attrs["Time"] != b["Header"].attrs["Time"]:
            differ.append("/Header/Time")
    if differ:
        print("snapshots differ in:", ", ".join(differ))
        return 1
    print("identical:", a_path, b_path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
