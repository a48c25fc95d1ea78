"""Writes a gas-only cosmological box as GADGET HDF5 initial conditions in Fountain's default
units (Mpc/h, Msun/h, km/s), for the examples that build their own exact set-ups.

    sys.path.insert(0, "<repo>/scripts"); from gas_box_ics import write_gas_box, critical_density, energy_of_temperature
"""
import h5py
import numpy as np

MPC_CM, MSUN_G, KM_CM = 3.0856775814913673e24, 1.988409870698051e33, 1e5
G_CGS, K_B, M_P = 6.6743e-8, 1.380649e-16, 1.67262192369e-24


def critical_density():
    """3 H0^2 / (8 pi G) in (Msun/h) / (Mpc/h)^3, H0 = 100 km/s per Mpc/h."""
    g = G_CGS * MSUN_G / (MPC_CM * KM_CM**2)  # Mpc (km/s)^2 / Msun
    return 3 * 100.0**2 / (8 * np.pi * g)


def energy_of_temperature(t, mu):
    """Specific internal energy (km/s)^2 of gas at temperature t (K), gamma = 5/3."""
    return 1.5 * K_B * t / (mu * M_P) / KM_CM**2


def write_gas_box(path, box, a, omega_m, omega_lambda, hubble_param, pos, vel, mass, u):
    """pos in Mpc/h, vel in GADGET's v_pec / sqrt(a) (km/s), mass in Msun/h, u physical (km/s)^2."""
    n = len(pos)
    with h5py.File(path, "w") as f:
        h = f.create_group("Header")
        h.attrs["NumPart_ThisFile"] = np.array([n, 0, 0, 0, 0, 0], dtype=np.uint32)
        h.attrs["NumPart_Total"] = np.array([n, 0, 0, 0, 0, 0], dtype=np.uint32)
        h.attrs["MassTable"] = np.zeros(6)
        h.attrs["BoxSize"] = box
        h.attrs["Time"] = a
        h.attrs["Redshift"] = 1.0 / a - 1.0
        h.attrs["Omega0"] = omega_m
        h.attrs["OmegaLambda"] = omega_lambda
        h.attrs["HubbleParam"] = hubble_param
        units = f.create_group("Units")
        units.attrs["UnitLength_in_cm"] = MPC_CM
        units.attrs["UnitMass_in_g"] = MSUN_G
        units.attrs["UnitVelocity_in_cm_per_s"] = KM_CM
        p = f.create_group("PartType0")
        p["Coordinates"] = pos
        p["Velocities"] = vel
        p["Masses"] = mass
        p["ParticleIDs"] = np.arange(1, n + 1, dtype=np.uint64)
        p["InternalEnergy"] = u
