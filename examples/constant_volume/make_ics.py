"""A uniform box at rest in comoving coordinates (COSMOLOGY.md C10.2) as GADGET HDF5 initial
conditions: N^3 gas particles on a lattice in 64 Mpc/h, h = 1, no peculiar velocities, 1e4 K
at a = 1/64, all the matter in gas (Omega_b = Omega_m).
  python3 make_ics.py N OMEGA_M OMEGA_LAMBDA OUTPUT"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from gas_box_ics import critical_density, energy_of_temperature, write_gas_box  # noqa: E402

BOX, A_BEGIN, T_BEGIN, MU = 64.0, 1.0 / 64.0, 1e4, 1.22


def main(n, omega_m, omega_lambda, path):
    cells = (np.arange(n) + 0.5) * BOX / n
    x, y, z = np.meshgrid(cells, cells, cells, indexing="ij")
    pos = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    mass = np.full(n**3, omega_m * critical_density() * BOX**3 / n**3)
    u = np.full(n**3, energy_of_temperature(T_BEGIN, MU))  # physical, (km/s)^2
    write_gas_box(path, BOX, A_BEGIN, omega_m, omega_lambda, 1.0, pos, np.zeros_like(pos), mass, u)


if __name__ == "__main__":
    main(int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]), sys.argv[4])
