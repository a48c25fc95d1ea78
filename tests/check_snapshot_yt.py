#!/usr/bin/python3
"""Check that yt opens a Fountain snapshot and sees the same gas (and dark matter) mass as h5py.

Usage: check_snapshot_yt.py SNAPSHOT.hdf5

yt recognises Fountain snapshots with its GADGET HDF5 frontend (GadgetHDF5Dataset; see the
comment at the top of io/Snapshot.cpp for why not the SWIFT one). That frontend ignores
/Units and reads only a cubic box, so the snapshot is loaded as users load it, through
scripts/fountain_yt.py (units as unit_base, a non-cubic box as bounding_box).
Prints OK and exits 0 when the total gas mass -- and, for a snapshot with /PartType1, the
total dark matter mass -- agree to 1e-10 (relative), else prints the difference and exits 1.
A comoving run's snapshot (OmegaLambda != 0 in /Header) must open as a cosmological data set
at the header's redshift and Hubble parameter; its masses are then in h-scaled units (Msun/h),
so h5py's sums are divided by h.
"""
import logging
import os
import sys
import tempfile
import warnings


def main(argv):
    if len(argv) != 2:
        print(f"usage: {argv[0]} SNAPSHOT.hdf5", file=sys.stderr)
        return 2
    path = argv[1]

    warnings.simplefilter("ignore")
    import h5py
    import numpy as np
    import yt

    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
    import fountain_yt

    yt.set_log_level(50)
    logging.getLogger("yt").setLevel(logging.CRITICAL)

    try:
        with h5py.File(path, "r") as f:
            masses = np.asarray(f["/PartType0/Masses"][...], dtype=np.float64)
            dm_masses = (
                np.asarray(f["/PartType1/Masses"][...], dtype=np.float64) if "PartType1" in f else None
            )
            header = dict(f["/Header"].attrs)
        extra = fountain_yt.load_arguments(path)
        mass_cgs = extra["unit_base"]["UnitMass_in_g"]
        cosmological = float(header.get("OmegaLambda", 0.0)) != 0.0
        if cosmological:
            mass_cgs /= float(header["HubbleParam"])
    except Exception as e:  # noqa: BLE001 -- not a Fountain snapshot
        print(f"FAIL: h5py cannot read /PartType0/Masses and /Units from {path}: {type(e).__name__}: {e}")
        return 1
    expected_g = float(np.sum(masses)) * mass_cgs

    # Keep yt's index file out of the snapshot folder.
    with tempfile.TemporaryDirectory() as tmp:
        index = os.path.join(tmp, os.path.basename(path) + ".ewah")
        try:
            ds = yt.load(path, index_filename=index, **extra)
        except Exception as e:  # noqa: BLE001 -- any failure to load is the answer
            print(f"FAIL: yt cannot load {path}: {type(e).__name__}: {e}")
            return 1
        if cosmological:
            problems = []
            if not ds.cosmological_simulation:
                problems.append("not opened as a cosmological simulation")
            if abs(ds.current_redshift - float(header["Redshift"])) > 1e-9 * (1.0 + float(header["Redshift"])):
                problems.append(f"redshift {ds.current_redshift}, header {header['Redshift']}")
            if abs(ds.hubble_constant - float(header["HubbleParam"])) > 1e-12:
                problems.append(f"hubble_constant {ds.hubble_constant}, header {header['HubbleParam']}")
            if abs(ds.omega_matter - float(header["Omega0"])) > 1e-12:
                problems.append(f"omega_matter {ds.omega_matter}, header {header['Omega0']}")
            if problems:
                print(f"FAIL ({type(ds).__name__}): " + "; ".join(problems))
                return 1
        ad = ds.all_data()
        try:
            total = ad["gas", "mass"].sum()
        except Exception:  # noqa: BLE001 -- fall back to the raw particle field
            total = ad["PartType0", "Masses"].sum()
        got_g = float(total.in_cgs())
        frontend = type(ds).__name__
        dm_got_g = None
        if dm_masses is not None:
            try:
                dm_got_g = float(ad["PartType1", "Masses"].sum().in_cgs())
            except Exception as e:  # noqa: BLE001 -- yt does not see the dark matter
                print(f"FAIL ({frontend}): yt cannot read /PartType1/Masses: {type(e).__name__}: {e}")
                return 1

    def relative(got, expected):
        return abs(got - expected) / abs(expected) if expected != 0 else abs(got)

    rel = relative(got_g, expected_g)
    if rel > 1e-10:
        print(
            f"FAIL ({frontend}): yt total gas mass {got_g:.17e} g, h5py {expected_g:.17e} g, "
            f"relative difference {rel:.3e}"
        )
        return 1
    dm_text = ""
    if dm_masses is not None:
        dm_expected_g = float(np.sum(dm_masses)) * mass_cgs
        dm_rel = relative(dm_got_g, dm_expected_g)
        if dm_rel > 1e-10:
            print(
                f"FAIL ({frontend}): yt total dark matter mass {dm_got_g:.17e} g, h5py {dm_expected_g:.17e} g, "
                f"relative difference {dm_rel:.3e}"
            )
            return 1
        dm_text = f"; {dm_masses.size} dark matter particles, total mass {dm_got_g:.12e} g"
    cosmo_text = f", cosmological at z = {float(header['Redshift']):.6g}" if cosmological else ""
    print(f"OK ({frontend}{cosmo_text}: {masses.size} gas particles, total mass {got_g:.12e} g{dm_text})")
    return 0

if __name__ == "__main__":
    sys.exit(main(sys.argv))
