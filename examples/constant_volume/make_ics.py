"""A uniform box at rest in comoving coordinates (COSMOLOGY.md C10.2) as GADGET HDF5 initial
conditions: N^3 gas particles on a lattice in 64 Mpc/h, h = 1, no peculiar velocities, 1e4 K
at a = 1/64, all the matter in gas (Omega_b = Omega_m).
  python3 make_ics.py N OMEGA_M OMEGA_LAMBDA OUTPUT"""
import sys

import h5py
import numpy as np

BOX, A_BEGIN, T_BEGIN, MU = 64.0, 1.0 / 64.0, 1e4, 1.22
MPC_CM, MSUN_G, KM_CM = 3.0856775814913673e24, 1.988409870698051e33, 1e5
G_CGS, K_B, M_P = 6.6743e-8, 1.380649e-16, 1.67262192369e-24


def main(n, omega_m, omega_lambda, path):
    cells = (np.arange(n) + 0.5) * BOX / n
    x, y, z = np.meshgrid(cells, cells, cells, indexing="ij")
    pos = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    g = G_CGS * MSUN_G / (MPC_CM * KM_CM**2)  # Mpc (km/s)^2 / Msun
    rho_crit = 3 * 100.0**2 / (8 * np.pi * g)  # Msun/h per (Mpc/h)^3
    mass = np.full(n**3, omega_m * rho_crit * BOX**3 / n**3)
    u = np.full(n**3, 1.5 * K_B * T_BEGIN / (MU * M_P) / KM_CM**2)  # physical, (km/s)^2
    with h5py.File(path, "w") as f:
        h = f.create_group("Header")
        h.attrs["NumPart_ThisFile"] = np.array([n**3, 0, 0, 0, 0, 0], dtype=np.uint32)
        h.attrs["NumPart_Total"] = np.array([n**3, 0, 0, 0, 0, 0], dtype=np.uint32)
        h.attrs["MassTable"] = np.zeros(6)
        h.attrs["BoxSize"] = BOX
        h.attrs["Time"] = A_BEGIN
        h.attrs["Redshift"] = 1.0 / A_BEGIN - 1.0
        h.attrs["Omega0"] = omega_m
        h.attrs["OmegaLambda"] = omega_lambda
        h.attrs["HubbleParam"] = 1.0
        units = f.create_group("Units")
        units.attrs["UnitLength_in_cm"] = MPC_CM
        units.attrs["UnitMass_in_g"] = MSUN_G
        units.attrs["UnitVelocity_in_cm_per_s"] = KM_CM
        p = f.create_group("PartType0")
        p["Coordinates"] = pos
        p["Velocities"] = np.zeros_like(pos)
        p["Masses"] = mass
        p["ParticleIDs"] = np.arange(1, n**3 + 1, dtype=np.uint64)
        p["InternalEnergy"] = u


if __name__ == "__main__":
    main(int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]), sys.argv[4])
