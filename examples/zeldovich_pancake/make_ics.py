"""Zel'dovich's pancake (COSMOLOGY.md C10.3) as GADGET HDF5 initial conditions: Einstein-de
Sitter, gas only, one plane wave of wavelength L = 64 Mpc/h along x, caustic at a_c = 1/2,
N^3 particles on a lattice displaced to z = 100, 100 K at the mean density (adiabatic elsewhere).
  python3 make_ics.py N OUTPUT"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from gas_box_ics import critical_density, energy_of_temperature, write_gas_box  # noqa: E402

BOX, A_C, A_BEGIN = 64.0, 0.5, 1.0 / 101.0


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
    mass = np.full(n**3, critical_density() * BOX**3 / n**3)  # h = 1
    contrast = 1.0 / (1.0 - d * np.cos(k * q))
    u = energy_of_temperature(100.0, 1.22) * contrast ** (2.0 / 3.0)  # 100 K at the mean density
    write_gas_box(path, BOX, A_BEGIN, 1.0, 0.0, 1.0, pos, vel, mass, u)


if __name__ == "__main__":
    main(int(sys.argv[1]), sys.argv[2])
