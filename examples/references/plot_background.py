"""The background cosmology of `fountain reference background` against answers computed here
independently (COSMOLOGY.md C10.1): Einstein-de Sitter's closed forms, and for (0.3, 0.7) the
closed-form time, Gauss-Legendre quadrature of the growth and factor integrals, and a
fine-step Runge-Kutta solution of the second-order growth equation.
  python3 plot_background.py EDS_TABLE LCDM_TABLE OUTPUT.png"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from figure_stamp import save  # noqa: E402

H0 = 100.0
COLUMNS = ["a", "z", "E", "t", "D", "f", "D2", "f2", "drift", "gravity_kick", "hydro_kick", "time"]
NODES, WEIGHTS = np.polynomial.legendre.leggauss(200)


def read(path):
    table = np.loadtxt(path)
    return {name: table[:, i] for i, name in enumerate(COLUMNS)}


def quad(f, lo, hi):
    """Gauss-Legendre on [lo, hi] (200 nodes: round-off for these smooth integrands)."""
    x = 0.5 * (hi - lo) * NODES + 0.5 * (hi + lo)
    return 0.5 * (hi - lo) * np.sum(WEIGHTS * f(x))


def exact_eds(a, a_begin):
    return {
        "E": a**-1.5, "t": 2 / (3 * H0) * a**1.5, "D": a, "f": np.ones_like(a), "D2": -3 / 7 * a**2,
        "f2": 2 * np.ones_like(a), "drift": 2 / H0 * (a_begin**-0.5 - a**-0.5),
        "gravity_kick": 2 / H0 * (a**0.5 - a_begin**0.5), "hydro_kick": 2 / H0 * (a_begin**-0.5 - a**-0.5),
        "time": 2 / (3 * H0) * (a**1.5 - a_begin**1.5),
    }


def second_order_growth(om, ol, a_out):
    """RK4 in s = ln a from a = 1e-4 (C2.2's start), steps of 2.5e-4: D, D2 and their slopes."""
    ok = 1 - om - ol

    def rhs(s, y):
        a = np.exp(s)
        e2 = om / a**3 + ok / a**2 + ol
        dlne = -(3 * om / a**3 + 2 * ok / a**2) / (2 * e2)
        omega = om / a**3 / e2
        d, dp, d2, d2p = y
        return np.array([dp, -(2 + dlne) * dp + 1.5 * omega * d, d2p,
                         -(2 + dlne) * d2p + 1.5 * omega * d2 - 1.5 * omega * d * d])

    a0 = 1e-4
    y = np.array([a0, a0, -3 / 7 * a0**2, -6 / 7 * a0**2])
    s, out = np.log(a0), []
    for target in np.log(a_out):
        n = max(1, int(np.ceil((target - s) / 2.5e-4)))
        h = (target - s) / n
        for _ in range(n):
            k1 = rhs(s, y)
            k2 = rhs(s + h / 2, y + h / 2 * k1)
            k3 = rhs(s + h / 2, y + h / 2 * k2)
            k4 = rhs(s + h, y + h * k3)
            y, s = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), s + h
        out.append(y.copy())
    out = np.array(out)
    return out[:, 2], out[:, 3] / out[:, 2]


def exact_lcdm(a, a_begin, om=0.3, ol=0.7):
    def e(x):
        return np.sqrt(om / x**3 + (1 - om - ol) / x**2 + ol)

    # int_0^a da'/(a' E)^3 with a' = a u^2: smooth in u, so Gauss-Legendre reaches round-off.
    growth = np.array([2.5 * om * e(x) * quad(lambda u: 2 * x * u / (x * u**2 * e(x * u**2)) ** 3, 0, 1) for x in a])
    rate = (2.5 * om / (a**2 * growth) - 1.5 * om / a**3 - (1 - om - ol) / a**2) / e(a) ** 2

    def factor(power):  # int_{a_begin}^a da / (a^power H), in ln a
        return np.array([quad(lambda s: np.exp(s) ** (1 - power) / (H0 * e(np.exp(s))), np.log(a_begin), np.log(x))
                         for x in a])

    d2, f2 = second_order_growth(om, ol, a)
    t = 2 / (3 * H0 * np.sqrt(ol)) * np.arcsinh(np.sqrt(ol / om) * a**1.5)
    return {"E": e(a), "t": t, "D": growth, "f": rate, "D2": d2, "f2": f2, "drift": factor(3),
            "gravity_kick": factor(2), "hydro_kick": factor(3), "time": factor(1)}


def main(eds_path, lcdm_path, out):
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.3))
    worst = {}
    for column, (label, path, exact) in enumerate([("Einstein-de Sitter", eds_path, exact_eds),
                                                   ("flat LCDM (0.3, 0.7)", lcdm_path, exact_lcdm)]):
        t = read(path)
        a = t["a"]
        ref = exact(a, a[0])
        ax = axes[column + 1]
        for name in ["E", "t", "D", "f", "D2", "f2", "drift", "gravity_kick", "time"]:
            scale = np.max(np.abs(ref[name]))  # factors start at 0: relative to their largest value
            err = np.abs(t[name] - ref[name]) / (np.abs(ref[name]) if name in ("E", "t", "D", "f", "D2", "f2") else scale)
            worst[(label, name)] = err.max()
            ax.semilogx(a, np.maximum(err, 1e-17), label=name, lw=1)
        ax.axhline(1e-8, color="k", ls="--", lw=0.8)
        ax.text(a[0] * 1.1, 1.4e-8, "C10.1 bound 1e-8", fontsize=8)
        ax.set_yscale("log")
        ax.set_ylim(1e-17, 1e-6)
        ax.set_xlabel("a")
        ax.set_ylabel("|Fountain - reference| / reference")
        ax.set_title(f"{label}: relative error")
        ax.legend(fontsize=7, ncol=3, loc="upper right")
        if column == 1:
            ax0 = axes[0]
            ax0.semilogx(a, t["D"] / a, label="D/a")
            ax0.semilogx(a, t["f"], label="f")
            ax0.semilogx(a, t["D2"] / (-3 / 7 * t["D"] ** 2), label="D2 / (-3/7 D^2)")
            ax0.semilogx(a, t["f2"] / 2, label="f2 / 2")
            ax0.semilogx(a, H0 * t["t"] / (H0 * t["t"][-1]), label="t / t_0")
            ax0.set_xlabel("a")
            ax0.set_title("flat LCDM (0.3, 0.7)")
            ax0.legend(fontsize=8)
    fig.tight_layout()
    save(fig, out, dpi=110)
    for (label, name), e in worst.items():
        print(f"{label:22s} {name:13s} largest relative error {e:.2e}")


if __name__ == "__main__":
    main(*sys.argv[1:4])
