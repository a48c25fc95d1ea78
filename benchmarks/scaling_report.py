#!/usr/bin/env python3
"""The strong-scaling table (Markdown) from benchmarks/results/scaling_*.json, as docs/performance.md shows it.

    /usr/bin/python3 benchmarks/scaling_report.py benchmarks/results
"""
import glob
import json
import os
import sys


def main(folder):
    runs = {}
    for path in sorted(glob.glob(os.path.join(folder, "scaling_*.json"))):
        with open(path) as f:
            r = json.load(f)
        runs.setdefault(r["problem"], {})[r["ranks_x_threads"]] = r
    lines = ["| problem | ranks x threads | wall (s) | steps | time per step (ms) | speed-up | efficiency | "
             "sent per step, rank 0 (ghost messages; recuts) | messages per step | waiting share |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for problem, by_layout in runs.items():
        base = by_layout.get("1x1")
        for layout in sorted(by_layout):
            r = by_layout[layout]
            cores = r["ranks"] * r["threads"]
            speed = base["step_ms"] / r["step_ms"] if base else float("nan")
            lines.append(
                f"| {problem} {r['particles']} | {layout} | {r['wall_s']:.1f} | {r['steps']} | {r['step_ms']:.1f} | "
                f"{speed:.2f} | {speed / cores:.0%} | {r['bytes_sent_per_step_rank0'] / 1e6:.2f} MB "
                f"({r.get('ghost_bytes_sent_per_step_rank0', 0) / 1e6:.2f} MB; "
                f"{r.get('recut_bytes_sent_per_step_rank0', 0) / 1e6:.2f} MB) | "
                f"{r['messages_sent_per_step_rank0']:.0f} | {r['waiting_share_rank0']:.0%} |")
    print("\n".join(lines))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "benchmarks/results")
