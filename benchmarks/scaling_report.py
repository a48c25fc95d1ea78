#!/usr/bin/env python3
"""The strong-scaling table (Markdown) from benchmarks/results/scaling_*.json, as docs/performance.md shows it.

    /usr/bin/python3 benchmarks/scaling_report.py benchmarks/results

Files are scaling_<problem>_<R>x<T>_<repeat>.json (strong_scaling.sh). Each row shows the run
of median time per step among a layout's repeats, the range of its repeats, and its time per
step over 1 x 2's in the same repeat (median and range of those ratios): the layouts of one
repeat ran minutes apart, so the ratio is what the host's drift disturbs least. It also shows
the layout's fastest repeat over 1 x 2's fastest: on a shared host a burst of load slows one
run by up to 40% and never speeds one up, so the fastest run is the best estimate of what the
layout costs undisturbed.
"""
import glob
import json
import os
import statistics
import sys


def main(folder):
    runs = {}
    for path in sorted(glob.glob(os.path.join(folder, "scaling_*.json"))):
        stem = os.path.basename(path)[: -len(".json")]
        repeat = stem.rsplit("_", 1)[1] if stem.count("_") >= 3 else "1"
        with open(path) as f:
            r = json.load(f)
        runs.setdefault(r["problem"], {}).setdefault(r["ranks_x_threads"], {})[repeat] = r
    lines = ["| problem | ranks x threads | runs | time per step (ms): median (range) | against 1 x 2, same run: "
             "median (range) | fastest against fastest 1 x 2 | speed-up | efficiency | sent per step, rank 0 (ghost messages; recuts) | "
             "messages per step | waiting share |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for problem, by_layout in runs.items():
        def median_run(layout):
            reps = by_layout[layout]
            ordered = sorted(reps.values(), key=lambda r: r["step_ms"])
            return ordered[(len(ordered) - 1) // 2]
        base = median_run("1x1")["step_ms"] if "1x1" in by_layout else float("nan")
        pair_base = by_layout.get("1x2", {})
        for layout in sorted(by_layout):
            reps = by_layout[layout]
            r = median_run(layout)
            steps = [x["step_ms"] for x in reps.values()]
            ratios = [reps[k]["step_ms"] / pair_base[k]["step_ms"] for k in reps if k in pair_base]
            against = (f"{statistics.median(ratios):.2f} ({min(ratios):.2f}-{max(ratios):.2f})"
                       if ratios and layout != "1x2" else "-")
            fastest = (f"{min(steps) / min(x['step_ms'] for x in pair_base.values()):.2f}"
                       if pair_base and layout != "1x2" else "-")
            cores = r["ranks"] * r["threads"]
            speed = base / r["step_ms"]
            lines.append(
                f"| {problem} {r['particles']} | {layout} | {len(reps)} | {r['step_ms']:.1f} "
                f"({min(steps):.1f}-{max(steps):.1f}) | {against} | {fastest} | {speed:.2f} | {speed / cores:.0%} | "
                f"{r['bytes_sent_per_step_rank0'] / 1e6:.2f} MB "
                f"({r.get('ghost_bytes_sent_per_step_rank0', 0) / 1e6:.2f} MB; "
                f"{r.get('recut_bytes_sent_per_step_rank0', 0) / 1e6:.2f} MB) | "
                f"{r['messages_sent_per_step_rank0']:.0f} | {r['waiting_share_rank0']:.0%} |")
    # The host's noise floor, when strong_scaling.sh measured it with the table.
    for name in ("core_noise.json", "core_noise_2x1_ranks.json"):
        path = os.path.join(folder, name)
        if os.path.exists(path):
            with open(path) as f:
                n = json.load(f)
            lines.append("")
            lines.append(f"{name}: {n['label']}: per full step {n['step_ratio_mean']:.2f} +- {n['step_ratio_sd']:.2f} "
                         f"({n['step_ratio_min']:.2f}-{n['step_ratio_max']:.2f})"
                         + (f", correlated {n['step_ratio_lag1_correlation']:.2f} with the next"
                            if "step_ratio_lag1_correlation" in n else "")
                         + f"; waiting for the slower side costs {100 * n['loss_waiting_for_slower_side']:.1f}% of the full steps")
    print("\n".join(lines))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "benchmarks/results")
