#!/usr/bin/env python3
"""Prints the Markdown table of docs/performance.md from benchmarks/results/*.json."""
import glob
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    runs = []
    spheres = []
    for path in sorted(glob.glob(os.path.join(HERE, "results", "*_t*.json"))):
        with open(path) as f:
            r = json.load(f)
        (spheres if r["problem"] == "rotating_sphere" else runs).append(r)
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

    generated = [r for r in spheres if r.get("initial_conditions", "generated") == "generated"]
    from_file = [r for r in spheres if r.get("initial_conditions", "generated") != "generated"]
    for label, group in (("rotating sphere", [r for r in generated if not r.get("star_formation")]),
                         ("rotating sphere, star formation + MFB", [r for r in generated if r.get("star_formation")]),
                         ("rotating sphere, collapsed (from a snapshot)", from_file)):
        if not group:
            continue
        print(f"\n| {label} | particles | threads | wall (s) | steps | updates/s | hydro | gravity | cooling "
              "| star formation | feedback | integration | outside tasks | in tasks |")
        print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for r in group:
            c = r["task_seconds_by_category"]
            total = sum(c.values())
            share = {k: f"{100 * v / total:.0f}%" if 100 * v / total >= 1 else f"{100 * v / total:.1f}%"
                     for k, v in c.items()}
            print(f"| {r['particles_per_species']} per species | {r['particles']:,} | {r['threads']} | {r['wall_s']:.1f} "
                  f"| {r['steps']} | {r['updates_per_s']:.3g} | {share.get('hydro', '-')} | {share.get('gravity', '-')} "
                  f"| {share.get('cooling', '-')} | {share.get('star_formation', '-')} | {share.get('feedback', '-')} "
                  f"| {share.get('integration', '-')} | {share.get('outside_tasks', '-')} "
                  f"| {100 * r['tasks_busy_share_of_thread_time']:.1f}% |")
        by_t = {r["threads"]: r for r in group}
        if 1 in by_t and 2 in by_t:
            print(f"\n{label}: parallel efficiency on 2 threads {by_t[1]['wall_s'] / (2 * by_t[2]['wall_s']):.0%}")

if __name__ == "__main__":
    main()
