"""Zel'dovich's pancake (COSMOLOGY.md C10.3) as GADGET HDF5 initial conditions: Einstein-de
Sitter, gas only, one plane wave of wavelength L = 64 Mpc/h along x, caustic at a_c = 1/2,
N^3 particles on a lattice displaced to z = 100, 100 K at the mean density (adiabatic elsewhere).
  python3 make_ics.py N OUTPUT"""
import sys

import h5py
import numpy as np

BOX, A_C, A_BEGIN = 64.0, 0.5, 1.0 / 101.0
MPC_CM, MSUN_G, KM_CM = 3.0856775814913673e24, 1.988409870698051e33, 1e5
G_CGS, K_B, M_P = 6.6743e-8, 1.380649e-16, 1.67262192369e-24


def main(n, path):
    k = 2 * np.pi / BOX
    cells = (np.arange(n) + 0.5) * BOX / n
    x, y, z = np.meshgrid(cells, cells, cells, indexing="ij")
    q = x.ravel() - 0.5 * BOX  # Lagrangian coordinate in [-L/2, L/2)
    d = A_BEGIN / A_C  # D(a) / D(a_c) in Einstein-de Sitter
    pos = np.stack([q - d * np.sin(k * q) / k + 0.5 * BOX, y.ravel(), z.ravel()], axis=1)
    # GADGET's velocity variable v_pec / sqrt(a) = v' / a^(3/2): -H0 sin(kq) / (a_c k), constant.
    vel = np.zeros_like(pos)
    vel[:, 0] = -100.0 * np.sin(k * q) / (A_C * k)
    g = G_CGS * MSUN_G / (MPC_CM * KM_CM**2)  # Mpc (km/s)^2 / Msun
    rho_crit = 3 * 100.0**2 / (8 * np.pi * g)  # Msun/h per (Mpc/h)^3, h = 1
    mass = np.full(n**3, rho_crit * BOX**3 / n**3)
    contrast = 1.0 / (1.0 - d * np.cos(k * q))
    u_mean = 1.5 * K_B * 100.0 / (1.22 * M_P) / KM_CM**2  # physical, (km/s)^2: 100 K, mu = 1.22
    u = u_mean * contrast ** (2.0 / 3.0)
    with h5py.File(path, "w") as f:
        h = f.create_group("Header")
        h.attrs["NumPart_ThisFile"] = np.array([n**3, 0, 0, 0, 0, 0], dtype=np.uint32)
        h.attrs["NumPart_Total"] = np.array([n**3, 0, 0, 0, 0, 0], dtype=np.uint32)
        h.attrs["MassTable"] = np.zeros(6)
        h.attrs["BoxSize"] = BOX
        h.attrs["Time"] = A_BEGIN
        h.attrs["Redshift"] = 1.0 / A_BEGIN - 1.0
        h.attrs["Omega0"] = 1.0
        h.attrs["OmegaLambda"] = 0.0
        h.attrs["HubbleParam"] = 1.0
        units = f.create_group("Units")
        units.attrs["UnitLength_in_cm"] = MPC_CM
        units.attrs["UnitMass_in_g"] = MSUN_G
        units.attrs["UnitVelocity_in_cm_per_s"] = KM_CM
        p = f.create_group("PartType0")
        p["Coordinates"] = pos
        p["Velocities"] = vel
        p["Masses"] = mass
        p["ParticleIDs"] = np.arange(1, n**3 + 1, dtype=np.uint64)
        p["InternalEnergy"] = u


if __name__ == "__main__":
    main(int(sys.argv[1]), sys.argv[2])
