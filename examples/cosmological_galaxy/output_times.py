"""Output scale factors of the paper's cosmological runs (COSMOLOGY.md C11.2): z = 20, 15, 12,
then COUNT equally spaced in cosmic time from z = 10 to z = 0 (Omega_m 0.3, Omega_Lambda 0.7).
  python3 output_times.py COUNT"""
import sys

import numpy as np


def cosmic_time(a):
    """t(a) in units of 1/H0, flat LCDM (closed form)."""
    om, ol = 0.3, 0.7
    return 2.0 / (3.0 * np.sqrt(ol)) * np.arcsinh(np.sqrt(ol / om) * a ** 1.5)


def main(count):
    t = np.linspace(cosmic_time(1 / 11), cosmic_time(1.0), count)
    grid = np.linspace(1 / 11, 1.0, 200001)
    a = np.interp(t, cosmic_time(grid), grid)
    a[-1] = 1.0
    early = [1 / 21, 1 / 16, 1 / 13]
    print(", ".join(f"{x:.8f}" for x in early + list(a[:-1])))


if __name__ == "__main__":
    main(int(sys.argv[1]))
