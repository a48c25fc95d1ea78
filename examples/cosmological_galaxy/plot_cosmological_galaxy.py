"""The paper's Figs 6-8 (Marri & White 2003; COSMOLOGY.md C11.4) from the four cosmological runs.

    python3 plot_cosmological_galaxy.py OUTPUT_FOLDER

OUTPUT_FOLDER holds SPH/, MSPH/, MFB/ and MFB100/, each with snapshot_NNNN.hdf5 and HOP
catalogues hop_NNNN.hdf5 (examples/cosmological_galaxy/run.sh writes both). Writes fig6.png
(the most massive HOP group of baryons against redshift: baryons, stars, cold gas, hot + warm
gas, promoted gas not cold now; and the star formation rates), fig7.png (the high-resolution
region's baryons by temperature and by density), fig8.png (Fig 6 for MFB/100) and claims.md
(the paper's claims at z = 0 beside the measured numbers).

Phases as the paper's: cold gas rho > 0.1 rho* (physical) and T < 2 T*, T* = 4e4 K; stars
include the gas's hidden stellar mass. The star formation rate of a group is the stellar mass
formed in it between outputs (its gas's growth of hidden stellar mass and its star particles
born since, not the stars its mergers bring) over the cosmic time between them.
"""
import glob
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from figure_stamp import save  # noqa: E402

T_STAR = 4e4
RHO_STAR_CGS = 5e-26
RHO_UNIT_CGS = 6.767906e-41  # (Msun/h) / (Mpc/h)^3 in g cm^-3, times h^2
OMEGA_B, RHO_CRIT0 = 0.03, 2.775366e11
YEARS_PER_TIME = 9.77792e11  # the internal time unit (Mpc/h)/(km/s) in years/h


def cosmic_time(a, om=0.3, ol=0.7):
    """t(a) in units of 1/H0 (flat LCDM)."""
    return 2.0 / (3.0 * np.sqrt(ol)) * np.arcsinh(np.sqrt(ol / om) * a**1.5)


def measure(run_dir):
    """Per output: the largest HOP group's masses and the whole region's fractions."""
    rows = []
    hidden_before = {}  # gas ID -> hidden stellar mass at the previous output
    a_before = None
    for snap in sorted(glob.glob(os.path.join(run_dir, "snapshot_*.hdf5"))):
        hop = os.path.join(run_dir, "hop_" + os.path.basename(snap)[len("snapshot_"):])
        with h5py.File(snap, "r") as f:
            a = f["Header"].attrs["Time"]
            h = f["Header"].attrs["HubbleParam"]
            n = f["Header"].attrs["NumPart_ThisFile"]
            if n[0] == 0:
                continue
            g = f["PartType0"]
            ids, m = g["ParticleIDs"][:], g["Masses"][:]
            hidden = g["HiddenStellarMasses"][:] if "HiddenStellarMasses" in g else np.zeros_like(m)
            rho = g["Density"][:]  # comoving
            temp = g["Temperature"][:]
            promoted = g["Promoted"][:] if "Promoted" in g else np.zeros(len(m), dtype=bool)
            star_ids = f["PartType4/ParticleIDs"][:] if n[4] > 0 else np.zeros(0, dtype=np.uint64)
            star_m = f["PartType4/Masses"][:] if n[4] > 0 else np.zeros(0)
            born = f["PartType4/BirthTime"][:] if n[4] > 0 else np.zeros(0)
        rho_star = RHO_STAR_CGS / (RHO_UNIT_CGS * h * h) * a**3  # comoving
        cold = (rho > 0.1 * rho_star) & (temp < 2 * T_STAR)
        total = m.sum() + hidden.sum() + star_m.sum()
        mean_b = OMEGA_B * RHO_CRIT0
        row = {
            "a": a,
            "z": 1 / a - 1,
            "region": {
                "cool": m[temp < T_STAR].sum() / total,
                "warm": m[(temp >= T_STAR) & (temp < 10 * T_STAR)].sum() / total,
                "hot": m[temp >= 10 * T_STAR].sum() / total,
                "stars": (hidden.sum() + star_m.sum()) / total,
                "dense": m[rho > 10 * mean_b].sum() / total,
                "diffuse": m[rho <= 10 * mean_b].sum() / total,
            },
        }
        group = dict(baryons=0.0, stars=0.0, cold=0.0, hot_warm=0.0, promoted=0.0, formed=0.0)
        if os.path.exists(hop):
            with h5py.File(hop, "r") as c:
                if c["Header"].attrs["Ngroups_Total"] > 0:
                    start, length = c["Group/GroupOffset"][0], c["Group/GroupLen"][0]
                    members = set(c["IDs/ID"][start:start + length].tolist())
                    in_gas = np.fromiter((i in members for i in ids), bool, len(ids))
                    in_stars = np.fromiter((i in members for i in star_ids), bool, len(star_ids))
                    group["stars"] = hidden[in_gas].sum() + star_m[in_stars].sum()
                    group["cold"] = m[in_gas & cold].sum()
                    group["hot_warm"] = m[in_gas & ~cold].sum()
                    group["promoted"] = m[in_gas & ~cold & (promoted > 0)].sum()
                    group["baryons"] = m[in_gas].sum() + group["stars"]
                    # Stars formed in the group since the previous output: its gas's growth of
                    # hidden stellar mass, and its star particles born since (a merger's stars
                    # are not counted).
                    if a_before is not None:
                        grown = [hidden[k] - hidden_before.get(i, 0.0) for k, i in enumerate(ids) if in_gas[k]]
                        group["formed"] = sum(max(g, 0.0) for g in grown)
                        group["formed"] += star_m[in_stars & (born > a_before)].sum()
        row["group"] = group
        rows.append(row)
        hidden_before = dict(zip(ids.tolist(), hidden))
        a_before = a
    for before, after in zip(rows, rows[1:]):
        # 1/H0 is a hundredth of the internal time unit; the h of years/h cancels that of Msun/h.
        dt = (cosmic_time(after["a"]) - cosmic_time(before["a"])) / 100.0 * YEARS_PER_TIME
        after["group"]["sfr"] = after["group"]["formed"] / dt
    if rows:
        rows[0]["group"]["sfr"] = 0.0
    return rows


def series(rows, key, part="group"):
    return np.array([r[part][key] for r in rows])


def galaxy_panel(ax, rows, title, promoted):
    z = np.array([r["z"] for r in rows])
    ax.plot(z, series(rows, "baryons"), "k-", label="baryons")
    ax.plot(z, series(rows, "stars"), "k--", label="stars")
    ax.plot(z, series(rows, "cold"), "k-.", label="cold gas")
    ax.plot(z, series(rows, "hot_warm"), "k", dashes=(8, 3), label="hot + warm gas")
    if promoted:
        ax.plot(z, series(rows, "promoted"), "k:", label="promoted, not cold")
    ax.set_yscale("log")
    ax.set_xlim(10, 0)
    ax.set_xlabel("z")
    ax.set_ylabel("mass [Msun/h]")
    ax.set_title(title)
    ax.legend(fontsize=7)


def main(folder):
    runs = {r: measure(os.path.join(folder, r)) for r in ("SPH", "MSPH", "MFB", "MFB100")
            if os.path.isdir(os.path.join(folder, r))}
    runs = {k: v for k, v in runs.items() if v}
    if not runs:
        sys.exit(f"{folder}: no runs with snapshots")
    fig, axes = plt.subplots(2, 2, figsize=(10, 8))
    for (name, promoted), ax in zip([("SPH", False), ("MFB", True), ("MSPH", False)], [axes[0, 0], axes[0, 1], axes[1, 0]]):
        if name in runs:
            galaxy_panel(ax, runs[name], {"SPH": "SPH", "MSPH": "MSPH", "MFB": "MSPH+MFB"}[name], promoted)
    for name, style in (("SPH", ":"), ("MSPH", "--"), ("MFB", "-")):
        if name in runs:
            axes[1, 1].plot([r["z"] for r in runs[name]], series(runs[name], "sfr"), "k" + style, label=name)
    axes[1, 1].set_xlim(10, 0)
    axes[1, 1].set_xlabel("z")
    axes[1, 1].set_ylabel("SFR [Msun/yr]")
    axes[1, 1].legend(fontsize=7)
    fig.suptitle("Fig 6: the most massive HOP group of baryons")
    fig.tight_layout()
    save(fig, os.path.join(folder, "fig6.png"))

    fig, axes = plt.subplots(2, 2, figsize=(10, 8), sharex=True)
    for col, (thick, thin) in enumerate((("MSPH", "SPH"), ("MFB", "MSPH"))):
        for name, width in ((thick, 2.0), (thin, 0.8)):
            if name not in runs:
                continue
            z = [r["z"] for r in runs[name]]
            for key, style in (("cool", "-"), ("warm", ":"), ("hot", "--")):
                axes[0, col].plot(z, series(runs[name], key, "region"), "k" + style, lw=width,
                                  label=f"{name} {key}")
            for key, style in (("stars", "-"), ("dense", ":"), ("diffuse", "--")):
                axes[1, col].plot(z, series(runs[name], key, "region"), "k" + style, lw=width,
                                  label=f"{name} {key}")
        for row in range(2):
            axes[row, col].set_xlim(10, 0)
            axes[row, col].set_ylim(0, 1)
            axes[row, col].legend(fontsize=6)
        axes[1, col].set_xlabel("z")
    axes[0, 0].set_ylabel("gas by T: < T*, T* - 10 T*, > 10 T*")
    axes[1, 0].set_ylabel("stars; gas above / below 10 x mean")
    fig.suptitle("Fig 7: the high-resolution region's baryons (fractions)")
    fig.tight_layout()
    save(fig, os.path.join(folder, "fig7.png"))

    if "MFB100" in runs:
        fig, axes = plt.subplots(1, 2, figsize=(10, 4))
        galaxy_panel(axes[0], runs["MFB100"], "MFB/100", True)
        axes[1].plot([r["z"] for r in runs["MFB100"]], series(runs["MFB100"], "sfr"), "k-")
        axes[1].set_xlim(10, 0)
        axes[1].set_xlabel("z")
        axes[1].set_ylabel("SFR [Msun/yr]")
        fig.suptitle("Fig 8: as Fig 6, for MFB/100")
        fig.tight_layout()
        save(fig, os.path.join(folder, "fig8.png"))

    lines = ["| claim (paper, z = 0) | " + " | ".join(runs) + " |", "|---|" + "---|" * len(runs)]

    def last(name, key, part="group"):
        return runs[name][-1][part][key]

    def row(text, values):
        lines.append(f"| {text} | " + " | ".join(values) + " |")

    row("z of the last output", [f"{runs[n][-1]['z']:.3g}" for n in runs])
    row("largest group: stars / baryons", [f"{last(n, 'stars') / max(last(n, 'baryons'), 1e-30):.3f}" for n in runs])
    row("largest group: cold gas / baryons", [f"{last(n, 'cold') / max(last(n, 'baryons'), 1e-30):.3f}" for n in runs])
    row("largest group: stellar mass [Msun/h]", [f"{last(n, 'stars'):.3g}" for n in runs])
    row("region: stars (of all baryons)", [f"{last(n, 'stars', 'region'):.3f}" for n in runs])
    row("region: gas above 10 T* (of all baryons)", [f"{last(n, 'hot', 'region'):.3f}" for n in runs])
    with open(os.path.join(folder, "claims.md"), "w") as out:
        out.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main(sys.argv[1])
