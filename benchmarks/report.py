#!/usr/bin/env python3
"""Prints the Markdown table of docs/performance.md from benchmarks/results/*.json."""
import glob
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    runs = []
    for path in sorted(glob.glob(os.path.join(HERE, "results", "*_t*.json"))):
        with open(path) as f:
            runs.append(json.load(f))
    print("| problem | particles | threads | wall (s) | steps | full steps | full step (us/particle) "
          "| updates/s | in tasks | peak RSS (B/particle) | accuracy |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in runs:
        if r["problem"] == "sod":
            acc = f"L1 = {r['sod_density_l1']:.4f}"
        elif r["problem"] == "sedov":
            acc = f"R = {r['shock_radius']:.4f} ({100 * (r['shock_radius'] / r['shock_radius_exact'] - 1):+.1f}%)"
        else:
            acc = f"L1 = {r.get('gresho_velocity_l1', 0):.4f}"
        print(f"| {r['problem']} | {r['particles']:,} | {r['threads']} | {r['wall_s']:.1f} | {r['steps']} "
              f"| {r['full_steps']} | {r['full_step_us_per_particle']:.2f} | {r['updates_per_s']:.3g} "
              f"| {100 * r['tasks_busy_share_of_thread_time']:.1f}% | {r['peak_rss_bytes_per_particle']:.0f} | {acc} |")
    by = {(r["problem"], r["threads"]): r for r in runs}
    for p in ("sod", "sedov"):
        if (p, 1) in by and (p, 2) in by:
            one, two = by[(p, 1)], by[(p, 2)]
            print(f"\n{p}: parallel efficiency on 2 threads {one['wall_s'] / (2 * two['wall_s']):.0%} (wall), "
                  f"{one['full_step_us_per_particle'] / (2 * two['full_step_us_per_particle']):.0%} (full steps)")


if __name__ == "__main__":
    main()
