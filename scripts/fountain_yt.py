"""Opens a Fountain snapshot in yt with its units and box, whatever the box's shape.

    import sys; sys.path.insert(0, "scripts")
    import fountain_yt
    ds = fountain_yt.load("output/snapshot_0001.hdf5")

yt reads Fountain snapshots with its GADGET HDF5 frontend, which takes GADGET's default
units unless told otherwise, and understands only a scalar /Header/BoxSize (a cube). This
passes the units of /Units as `unit_base` and, for a box that is not a cube (the Sod
problem's 2 x 0.5 x 0.5), the box as `bounding_box`. Other keywords go to yt.load.
"""
import h5py
import numpy as np


def load_arguments(path):
    """The keywords yt.load needs for this snapshot: unit_base, and bounding_box if not a cube."""
    with h5py.File(path, "r") as f:
        units = dict(f["/Units"].attrs)
        box = np.ravel(f["/Header"].attrs["BoxSize"]).astype(np.float64)
    length_cgs = float(np.ravel(units["Unit length in cgs (U_L)"])[0])
    mass_cgs = float(np.ravel(units["Unit mass in cgs (U_M)"])[0])
    time_cgs = float(np.ravel(units["Unit time in cgs (U_t)"])[0])
    args = {"unit_base": {"UnitLength_in_cm": length_cgs, "UnitMass_in_g": mass_cgs,
                          "UnitVelocity_in_cm_per_s": length_cgs / time_cgs}}
    if box.size == 3:
        args["bounding_box"] = [[0.0, box[0]], [0.0, box[1]], [0.0, box[2]]]
    return args


def load(path, **kwargs):
    import yt
    return yt.load(path, **load_arguments(path), **kwargs)
