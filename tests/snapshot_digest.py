#!/usr/bin/env python3
"""Prints one SHA-256 over a snapshot's particle data (every /PartType*/ dataset, in name
order, and /Header/Time): equal digests mean bitwise-identical particles."""
import hashlib
import sys

import h5py
import numpy as np


def digest(path):
    h = hashlib.sha256()
    with h5py.File(path, "r") as f:
        h.update(np.float64(f["Header"].attrs["Time"]).tobytes())
        for group in sorted(g for g in f if g.startswith("PartType")):
            for name in sorted(f[group]):
                data = f[group][name][...]
                h.update(f"{group}/{name}:{data.dtype.str}:{data.shape}".encode())
                h.update(np.ascontiguousarray(data).tobytes())
    return h.hexdigest()


if __name__ == "__main__":
    print(digest(sys.argv[1]))
