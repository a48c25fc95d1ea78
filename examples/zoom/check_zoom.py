"""A dark-matter zoom against its parent (COSMOLOGY.md C8.4): the zoom's halo nearest the
parent's chosen one has M_200 within 15% and its centre within 0.2 R_200, and the
low-resolution mass inside its R_200 is below 1e-3 of M_200.
  python3 check_zoom.py PARENT_FOF ZOOM_FOF ZOOM_SNAPSHOT IC_ZOOM_OUTPUT"""
import re
import sys

import h5py
import numpy as np


def main(parent_fof, zoom_fof, snapshot, ic_text):
    halo = int(re.search(r"zoom on group (\d+)", open(ic_text).read()).group(1))
    with h5py.File(parent_fof, "r") as f:
        centre, m200, r200 = (f["Group/GroupPos"][halo], f["Group/Group_M_Crit200"][halo],
                              f["Group/Group_R_Crit200"][halo])
        box = f["Header"].attrs["BoxSize"]
    with h5py.File(zoom_fof, "r") as f:
        d = f["Group/GroupPos"][:] - centre
        d -= box * np.round(d / box)
        k = int(np.argmin(np.linalg.norm(d, axis=1)))
        zc, zm, zr = f["Group/GroupPos"][k], f["Group/Group_M_Crit200"][k], f["Group/Group_R_Crit200"][k]
    offset = np.linalg.norm(d[k]) / r200
    with h5py.File(snapshot, "r") as f:
        x = f["PartType2/Coordinates"][:]
        m = f["PartType2/Masses"][:]
    dx = x - zc
    dx -= box * np.round(dx / box)
    r = np.linalg.norm(dx, axis=1)
    contamination = m[r < zr].sum() / zm
    print(f"parent group {halo}: M_200 = {m200:.4g}, R_200 = {r200:.4g}; zoom group {k}: M_200 = {zm:.4g} "
          f"(ratio {zm / m200:.3f}), centre {offset:.3f} R_200 away; low-resolution mass within R_200 "
          f"{contamination:.2g} of M_200, nearest low-resolution particle at {r.min() / zr:.2f} R_200")
    ok = abs(zm / m200 - 1) <= 0.15 and offset <= 0.2 and contamination < 1e-3
    print("PASS" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:5]))
