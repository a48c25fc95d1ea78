#!/usr/bin/python3
"""A model of a large zoom's parallel efficiency on many nodes, from figures measured here.

Usage: /usr/bin/python3 benchmarks/scaling_model.py [--box benchmarks/results/scaling_model_box.json]
       [--particles 1e8] [--cores 64] [--markdown]

It models the distributed state (docs/design.md, "Next: the distributed state"): one rank per
node, TBB threads within, each rank holding its own particles and foreign copies of the cells
within reach. The work per particle comes from the measured 2 x 64^3 cosmological box; the
message sizes from the layouts of the present messages; the network's bandwidth and latency
are assumptions, printed with the table. docs/performance.md ("Beyond one machine") explains
every term.
"""
import argparse
import json
import math

p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
p.add_argument("--box", default="benchmarks/results/scaling_model_box.json",
               help="the cosmological box benchmark's JSON (fountain_cosmo_bench)")
p.add_argument("--particles", type=float, default=1e8, help="high-resolution particles, gas and dark matter")
p.add_argument("--cores", type=int, default=64, help="cores per node (one rank per node)")
p.add_argument("--small-step-share", type=float, default=0.25,
               help="share of the ranks holding a small step's active particles")
p.add_argument("--markdown", action="store_true", help="print Markdown tables")
a = p.parse_args()

box = json.load(open(a.box))
n_box = box["particles"]
threads = box["threads"]
busy = sum(v for k, v in box["task_seconds"].items() if k != "outside_tasks")
# Thread time measured on the box: per particle update in the tasks, and outside them (per
# particle per step; outside_tasks = wall x threads - busy, so serial work outside the graph
# counts once per thread: its wall time is outside / threads).
updates = box["particle_updates"]
steps_box = box["steps"]
# Of the tasks' time, what every step costs whatever is active: the drift and the refit of
# every particle (a step with ~20 active particles: 38 ms of thread time at 524,288 particles,
# the z = 3 timelines of docs/performance.md).
fixed_per_particle_step = 0.038 / 524288
fixed_total = fixed_per_particle_step * n_box * steps_box
per_update = (busy - fixed_total) / updates
# Rebuilds (the recut, the neighbour lists, the gravity tree's build, which is serial): a
# rebuild step took 116-123 ms against 21-23 ms for a step with as few particles active, at
# 524,288 particles on 2 threads (z = 3 timelines), and came every ~8 steps (the 2 x 32^3
# box: 490 rebuilds in 3,970 steps). Taken as serial: more threads are assumed not to help.
rebuild_per_particle = 0.095 / 524288
steps_per_rebuild = 8.1
# The drift and refit run in tasks, but the refit in 8 groups: at most 8 threads share it.
refit_groups = 8

N = a.particles
scale = (N / n_box) ** (1.0 / 3.0)  # mean spacing ratio
# Assumptions about the zoom's run, against the box's: steps grow as the spacing shrinks (the
# steps follow softening / velocity); updates per particle grow more slowly (only the dense
# part steps often); the walk grows as log N.
steps = steps_box * scale
updates_per_particle = updates / n_box * math.sqrt(scale)
walk_growth = math.log(N) / math.log(n_box)
per_update_zoom = per_update * walk_growth
active_fraction = updates_per_particle / steps

# Messages of the distributed state, per active boundary particle and step: gas sends its state
# before the density loop (x, v, h, m, u: ~80 B), its ghost results (97 B, CellMessages) and
# what the kick changed (~100 B); dark matter its velocity after the kick and position (48 B).
bytes_gas, bytes_dm, gas_share = 280.0, 48.0, 0.5
halo_width = 3.0          # spacings: a rank reads whole leaves near its surface
neighbour_ranks = 26      # messages per phase
phases = 3                # before density, ghost results, after kick
top_cells = 64 ** 3
multipole_bytes = 100.0   # per top cell, allgathered when changed (assumed: every step)
mesh = 512                # N_M for 1e8 particles
mesh_steps = 600          # the mesh's own steps (the box had ~512 full steps)
# Imbalance of the curve cut at many leaves per rank (Sedov 250k: 0.1 / 0.5 / 1.8% at 2 / 4 / 8
# ranks, docs/performance.md "Partitioner"); a zoom's small steps are clustered, which the
# per-step cut cannot follow: their active work is taken to fall on a quarter of the ranks.
def imbalance(P):
    return 0.02 * math.log2(P)
small_step_ranks_share = a.small_step_share
thread_efficiency = 0.9   # within a node of `cores` threads (0.98 measured at 2)

networks = {"InfiniBand HDR (100 Gb/s, 1.5 us)": (12.5e9, 1.5e-6), "25 GbE (3 GB/s, 10 us)": (3.0e9, 10e-6)}


def model(P, bandwidth, latency):
    local = N / P
    c = a.cores * thread_efficiency
    # Compute: full-equivalent updates spread over the ranks; the small steps' share falls on
    # a quarter of them. Taken as half the updates (the box: 597 full-step equivalents, of
    # which 512 full steps).
    updates_total = N * updates_per_particle
    compute_full = 0.5 * updates_total * per_update_zoom / (P * c) * (1 + imbalance(P))
    compute_small = 0.5 * updates_total * per_update_zoom / (max(1.0, P * small_step_ranks_share) * c)
    fixed = steps * local * fixed_per_particle_step / min(c, refit_groups)
    serial = steps / steps_per_rebuild * local * rebuild_per_particle
    boundary = 6 * halo_width * local ** (2.0 / 3.0)
    bytes_step = boundary * active_fraction * (gas_share * bytes_gas + (1 - gas_share) * bytes_dm)
    messages = steps * (neighbour_ranks * phases + 2 * math.log2(P)) * latency
    traffic = steps * (bytes_step + top_cells * multipole_bytes) / bandwidth
    transposed = 4 * 16.0 * mesh * mesh * (mesh // 2 + 1) / P
    mesh_comm = mesh_steps * (transposed / bandwidth + 4 * P * latency)
    total = compute_full + compute_small + fixed + serial + messages + traffic + mesh_comm
    ideal = (updates_total * per_update_zoom + steps * N * fixed_per_particle_step) / (P * a.cores)
    return dict(P=P, total_h=total / 3600, ideal_h=ideal / 3600, efficiency=ideal / total,
                compute=(compute_full + compute_small) / total, fixed=fixed / total, serial=serial / total,
                comm=(messages + traffic + mesh_comm) / total)


print(f"Measured ({a.box}): {per_update * 1e6:.2f} us of task time per particle update, "
      f"{fixed_per_particle_step * 1e9:.0f} ns per particle per step for the drift and refit, "
      f"{rebuild_per_particle * 1e9:.0f} ns per particle per rebuild, a rebuild every {steps_per_rebuild} steps.")
print(f"Zoom of {N:.3g} particles: {steps:.0f} steps, {updates_per_particle:.0f} updates per particle, "
      f"walk x{walk_growth:.2f}; {a.cores} cores per node.")
for name, (bw, lat) in networks.items():
    print(f"\n{name}")
    rows = [model(P, bw, lat) for P in (16, 32, 64, 128, 256)]
    for r in rows:  # strong scaling from the smallest node count
        r["against_16"] = rows[0]["total_h"] * rows[0]["P"] / (r["total_h"] * r["P"])
    if a.markdown:
        print("| nodes | run (h) | ideal (h) | efficiency | against 16 nodes | tasks | drift+refit | rebuilds | messages |")
        print("|---|---|---|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {r['P']} | {r['total_h']:.2f} | {r['ideal_h']:.2f} | {100 * r['efficiency']:.0f}% | "
                  f"{100 * r['against_16']:.0f}% | "
                  f"{100 * r['compute']:.0f}% | {100 * r['fixed']:.0f}% | {100 * r['serial']:.0f}% | "
                  f"{100 * r['comm']:.0f}% |")
    else:
        for r in rows:
            print(r)
