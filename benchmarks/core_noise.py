#!/usr/bin/env python3
"""Step-by-step speed of two runs of the same deterministic work, set side by side.

Usage: core_noise.py LOG_A LOG_B [--label TEXT] [--json OUT]

LOG_A and LOG_B are `fountain_run_bench --step-log` files: either two independent one-thread
processes run at the same time on two cores (benchmarks/core_noise.sh: the host's noise floor),
or the two ranks of one 2 x 1 run (FILE.rank0, FILE.rank1). Only the full steps (every
particle active, no rebuild) are compared, where both sides do the same work. A layout that
waits for the slower side at the end of each step loses sum(max) / sum(mean) - 1 of its
time in those steps to the difference; one process whose threads share a queue loses none of
it.
"""
import argparse
import csv
import json
import math
import sys


def read(path):
    with open(path, newline="") as f:
        return {int(r["step"]): r for r in csv.DictReader(f)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("log_a")
    ap.add_argument("log_b")
    ap.add_argument("--json")
    ap.add_argument("--label", default="", help="what the two logs are, kept in the JSON")
    args = ap.parse_args()
    a, b = read(args.log_a), read(args.log_b)
    full = max(int(r["active"]) for r in a.values())
    steps = sorted(s for s in a if s in b and int(a[s]["active"]) == full and int(b[s]["active"]) == full
                   and a[s]["rebuilt"] == "0" and b[s]["rebuilt"] == "0")
    if len(steps) < 2:
        sys.exit(f"core_noise.py: fewer than two full steps common to {args.log_a} and {args.log_b}")
    ta = [float(a[s]["tasks_busy_s"]) for s in steps]
    tb = [float(b[s]["tasks_busy_s"]) for s in steps]
    ratio = [x / y for x, y in zip(ta, tb)]
    mean_ratio = sum(ratio) / len(ratio)
    sd = math.sqrt(sum((r - mean_ratio) ** 2 for r in ratio) / (len(ratio) - 1))
    # Whether one side stays the slower for a while (a cut or a rebalance could then follow
    # it) or changes step to step (nothing but shared work can): the correlation of the
    # ratio's log from one full step to the next.
    lr = [math.log(r) for r in ratio]
    m = sum(lr) / len(lr)
    var = sum((x - m) ** 2 for x in lr)
    lag1 = sum((lr[k] - m) * (lr[k + 1] - m) for k in range(len(lr) - 1)) / var if var > 0 else 0.0
    loss = sum(max(x, y) for x, y in zip(ta, tb)) / sum(0.5 * (x + y) for x, y in zip(ta, tb)) - 1
    out = {
        "label": args.label, "full_steps": len(steps), "particles": full,
        "task_s_a": round(sum(ta), 3), "task_s_b": round(sum(tb), 3),
        "step_ratio_mean": round(mean_ratio, 4), "step_ratio_sd": round(sd, 4),
        "step_ratio_min": round(min(ratio), 4), "step_ratio_max": round(max(ratio), 4),
        "step_ratio_lag1_correlation": round(lag1, 3),
        "loss_waiting_for_slower_side": round(loss, 4),
    }
    print(f"{len(steps)} full steps of {full} particles: task time {out['task_s_a']} s against {out['task_s_b']} s; "
          f"per-step ratio {mean_ratio:.3f} +- {sd:.3f} ({min(ratio):.3f}-{max(ratio):.3f}), "
          f"correlated {lag1:.2f} with the next full step's; "
          f"waiting for the slower side each step would cost {100 * loss:.1f}% of these steps")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)
            f.write("\n")


if __name__ == "__main__":
    main()
