#!/usr/bin/env python3
"""Figures like Marri & White (2003) Figs 1-3 from the runs of run_convergence.sh, the table
of gas phases at the last output (about 1.2 Gyr), and the table of where the hot gas lies
about the disc (sphere_hot_halo_table.md): hot particles within 5, 10, 15 and 20 kpc/h of the
cold gas's centre of mass at the last output, and the hot particles' number density in shells
about that centre, averaged over the last three outputs (the paper's Fig 3 shows MSPH's hot gas
peaked at the centre and SPH's with a hole there).

    /usr/bin/python3 examples/rotating_sphere/plot_convergence.py examples/rotating_sphere/output \
        [--docs docs/validation]

Phases (docs/physics.md section 7, the paper's section 3.2): hot T > 2 T* = 8e4 K; cold T <= 2 T*
and rho > 0.1 rho* (rho* = 5e-26 g/cm^3); warm otherwise. Times in Gyr for h = 1.
"""
import argparse
import glob
import os

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import sys  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from figure_stamp import save  # noqa: E402


T_STAR = 4.0e4
RHO_STAR_CGS = 5.0e-26
K_B, M_P = 1.380649e-16, 1.67262192e-24


def read_statistics(path):
    with open(path) as f:
        names = [line for line in f if line.startswith("#")][-1].lstrip("#").split()
    data = np.loadtxt(path, comments="#", ndmin=2)
    return {n: data[:, k] for k, n in enumerate(names)}


def runs(folder):
    """{(n, scheme): run folder} for every run with a statistics file."""
    found = {}
    for d in sorted(glob.glob(os.path.join(folder, "*_*"))):
        name = os.path.basename(d)
        n, _, scheme = name.partition("_")
        if n.isdigit() and os.path.exists(os.path.join(d, "statistics.txt")):
            found[(int(n), scheme)] = d
    return found


def last_snapshot(run):
    snaps = sorted(glob.glob(os.path.join(run, "snapshot_*.hdf5")))
    return snaps[-1] if snaps else None


SHELLS_KPC = (0, 4, 8, 12, 16, 20, 30)


def hot_halo(run):
    """Hot particles about the cold gas's centre: counts within 5/10/15/20 kpc/h and the hot
    mass within 15 kpc/h (fraction of the gas) at the last output; number density per 1000
    (kpc/h)^3 in SHELLS_KPC, averaged over the last three outputs."""
    snaps = sorted(glob.glob(os.path.join(run, "snapshot_*.hdf5")))[-3:]
    volume = 4.0 / 3.0 * np.pi * np.diff(np.power(SHELLS_KPC, 3))
    density = np.zeros(len(SHELLS_KPC) - 1)
    times = []
    for path in snaps:
        x, rho, temp, m, t = gas_state(path)
        times.append(t)
        hot = temp > 2 * T_STAR
        cold = ~hot & (rho > 0.1 * RHO_STAR_CGS)
        centre = np.average(x[cold], axis=0, weights=m[cold]) if cold.any() else np.zeros(3)
        r = np.linalg.norm(x - centre, axis=1) * 1e3
        counts, _ = np.histogram(r[hot], bins=SHELLS_KPC)
        density += 1e3 * counts / volume / len(snaps)
    # The counts and the mass are of the last output, the one the loop ended on.
    last_hot, last_r, last_m = hot, r, m
    within = [int(np.sum(last_hot & (last_r < R))) for R in (5, 10, 15, 20)]
    hot_mass_15 = float(np.sum(last_m[last_hot & (last_r < 15)]) / np.sum(last_m))
    return within, hot_mass_15, density, times


def gas_state(path):
    with h5py.File(path, "r") as f:
        units = f["Units"].attrs
        length, mass, velocity = units["UnitLength_in_cm"], units["UnitMass_in_g"], units["UnitVelocity_in_cm_per_s"]
        g = f["PartType0"]
        x = g["Coordinates"][...]
        rho_cgs = g["Density"][...] * mass / length**3
        if "Temperature" in g:
            temp = g["Temperature"][...]
        else:  # older snapshots: a fully ionised primordial gas
            temp = (2.0 / 3.0) * 0.59 * M_P / K_B * g["InternalEnergy"][...] * velocity**2
        m = g["Masses"][...]
        t_gyr = f["Header"].attrs["Time"] * length / velocity / 3.15576e16
    return x, rho_cgs, temp, m, t_gyr


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folder")
    ap.add_argument("--docs", default=None, help="also write the figures and the table here")
    a = ap.parse_args()
    found = runs(a.folder)
    if not found:
        raise SystemExit(f"no runs with statistics in {a.folder}")
    out = a.docs or a.folder
    os.makedirs(out, exist_ok=True)
    sizes = sorted({n for n, _ in found})
    width = {n: 0.8 + 1.0 * k for k, n in enumerate(sizes)}

    # Fig 1: phase fractions and thermal energy against time.
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    panels = [("mass_hot", "hot", ax[0, 0]), ("mass_warm", "warm", ax[0, 1]), ("mass_cold", "cold", ax[1, 0])]
    for (n, scheme), run in sorted(found.items()):
        s = read_statistics(os.path.join(run, "statistics.txt"))
        t = s["time"] * 977.8
        style = "-" if scheme == "sph" else "--"
        colour = "tab:red" if scheme == "sph" else "tab:blue"
        label = f"{scheme.upper()} {n}"
        for key, _, axis in panels:
            axis.plot(t, s[key] / s["mass_gas"], style, color=colour, lw=width[n], label=label)
        ax[1, 1].plot(t, s["thermal_energy"], style, color=colour, lw=width[n], label=label)
    for key, name, axis in panels:
        axis.set_ylabel(f"{name} gas fraction")
    ax[1, 1].set_ylabel("total thermal energy (Msun/h (km/s)^2)")
    for axis in ax.flat:
        axis.set_xlabel("t (Gyr)")
        axis.grid(alpha=0.3)
    ax[0, 0].legend(fontsize=8)
    fig.suptitle("Rotating sphere with cooling: SPH (solid) vs MSPH (dashed); thicker = more particles")
    fig.tight_layout()
    save(fig, os.path.join(out, "sphere_phases.png"), dpi=110)
    plt.close(fig)

    # Table at the last output of each run.
    rows = ["| run | t (Gyr) | hot | warm | cold |", "|---|---|---|---|---|"]
    for (n, scheme), run in sorted(found.items()):
        s = read_statistics(os.path.join(run, "statistics.txt"))
        g = s["mass_gas"][-1]
        rows.append(f"| {scheme.upper()} {n} | {s['time'][-1] * 977.8:.3f} | {s['mass_hot'][-1] / g:.3f} | "
                    f"{s['mass_warm'][-1] / g:.3f} | {s['mass_cold'][-1] / g:.3f} |")
    table = "\n".join(rows) + "\n"
    with open(os.path.join(out, "sphere_phases_table.md"), "w") as f:
        f.write(table)
    print(table)

    # Where the hot gas lies about the disc, every run.
    rows = ["| run | hot within 5 / 10 / 15 / 20 kpc/h | hot mass within 15 kpc/h (of the gas) | "
            + " | ".join(f"{a}-{b}" for a, b in zip(SHELLS_KPC[:-1], SHELLS_KPC[1:])) + " |",
            "|---|---|---|" + "---|" * (len(SHELLS_KPC) - 1)]
    times = None
    for (n, scheme), run in sorted(found.items()):
        if last_snapshot(run) is None:
            continue
        within, hot15, density, times = hot_halo(run)
        rows.append(f"| {scheme.upper()} {n} | {' / '.join(str(w) for w in within)} | {hot15:.4f} | "
                    + " | ".join(f"{d:.2f}" for d in density) + " |")
    if times is not None:
        halo = ("Hot particles about the cold gas's centre of mass: counts at the last output; number density "
                "of hot particles per 1000 (kpc/h)^3 in shells (kpc/h), averaged over the outputs at "
                + ", ".join(f"{t:.2f}" for t in times) + " Gyr.\n\n" + "\n".join(rows) + "\n")
        with open(os.path.join(out, "sphere_hot_halo_table.md"), "w") as f:
            f.write(halo)
        print(halo)

    # Figs 2 and 3 at the largest resolution with both schemes.
    both = [n for n in sizes if (n, "sph") in found and (n, "msph") in found]
    if not both:
        return
    n = both[-1]
    fig2, ax2 = plt.subplots(2, 2, figsize=(9, 9))
    fig3, ax3 = plt.subplots(2, 1, figsize=(7, 9), sharex=True)
    for row, scheme in enumerate(("sph", "msph")):
        snap = last_snapshot(found[(n, scheme)])
        x, rho, temp, m, t = gas_state(snap)
        hot = temp > 2 * T_STAR
        cold = ~hot & (rho > 0.1 * RHO_STAR_CGS)
        kpc = x * 1e3
        for col, (sel, name) in enumerate(((hot, "hot"), (cold, "cold"))):
            a2 = ax2[row, col]
            a2.scatter(kpc[sel, 0], kpc[sel, 1], s=1.5, color="tab:red" if name == "hot" else "tab:blue")
            a2.set_xlim(-60, 60)
            a2.set_ylim(-60, 60)
            a2.set_aspect("equal")
            a2.set_title(f"{scheme.upper()} {n}: {name} ({sel.sum()} particles), t = {t:.2f} Gyr", fontsize=9)
            a2.set_xlabel("x (kpc/h)")
            a2.set_ylabel("y (kpc/h)")
        r = np.linalg.norm(kpc, axis=1)
        a3 = ax3[row]
        a3.loglog(r[~hot], rho[~hot], ".", ms=2, color="tab:blue", label="T <= 2 T*")
        a3.loglog(r[hot], rho[hot], "x", ms=3, color="tab:red", label="hot (T > 2 T*)")
        a3.set_ylabel("gas density (g/cm^3)")
        a3.set_title(f"{scheme.upper()} {n}, t = {t:.2f} Gyr", fontsize=9)
        a3.legend(fontsize=8)
        a3.grid(alpha=0.3)
    ax3[-1].set_xlabel("r (kpc/h)")
    fig2.tight_layout()
    save(fig2, os.path.join(out, "sphere_faceon.png"), dpi=110)
    fig3.tight_layout()
    save(fig3, os.path.join(out, "sphere_density_profile.png"), dpi=110)
    print(f"figures in {out}")


if __name__ == "__main__":
    main()
