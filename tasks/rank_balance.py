#!/usr/bin/env python3
"""Where a run across MPI ranks loses time to its ranks' differences, step by step.

Reads the task timelines of a run (output.dump_timeline_every: 1 writes
timeline_step<S>_rank<R>.csv for every step and rank) and prints, for full steps (every
particle active) and partial steps apart:

- each rank's time inside tasks (busy) and the graph's span, summed over the steps;
- the imbalance: the sum over steps of the busiest rank's busy time minus the ranks' mean.
  A rank with less to do, or whose core ran faster in that step, waits that long for the
  other's messages or in the exchange after the graph;
- the tail: the span beyond the busiest rank's busy time (latency, polling, idle starts);
- per task type, how much faster the faster rank ran in the median step, relative to the
  slower (the same work on both ranks, as in a symmetric problem, measures the cores);
- with --reference, the timelines of the same run on one rank (1 x 2, say): per rank and
  task type, the time the rank took for its tasks against the time the reference took for
  the same tasks (step, type, cell). The runs do the same work task by task (their results
  are bitwise the same), so a ratio above 1 is the rank running slower, not a cut that gave
  it more; where one rank's ratio stands above the other's, its core (or its cache, shared
  with other tenants) was the slower.

    tasks/rank_balance.py output/                 # a folder of timeline files
    tasks/rank_balance.py output/ --per-step      # also one line per full step
    tasks/rank_balance.py output/ --reference output_1x2/

Reads the files with plot_tasks.py's reader (numpy).
"""
import argparse
import glob
import os
import re
import statistics
import sys
from collections import defaultdict

from plot_tasks import read_timeline  # the same folder: the timeline files' one reader


def read_step(path):
    """(busy ns of tasks, span ns of tasks, {type: ns}, tasks) of one rank's timeline of one step."""
    busy = 0
    first, last = None, None
    by_type = defaultdict(int)
    tasks = 0
    for name, _rank, thread, start, end in read_timeline(path):
        if end <= start or thread < 0:  # not run, or the exchanges after the graph
            continue
        busy += end - start
        by_type[name] += end - start
        tasks += 1
        first = start if first is None else min(first, start)
        last = end if last is None else max(last, end)
    return busy, (last - first) if first is not None else 0, by_type, tasks


def task_times(path):
    """{(type, cell): ns} of the tasks of one timeline file that ran for a cell."""
    times = defaultdict(int)
    for name, _rank, thread, start, end, cell in read_timeline(path, cells=True):
        if end > start and thread >= 0 and cell >= 0:
            times[(name, cell)] += end - start
    return times


def compare_with_reference(steps, ranks, folder):
    """Prints each rank's task time per type against the reference's for the same tasks."""
    pattern = re.compile(r"timeline_step(\d+)(?:_rank0)?\.csv$")
    reference = {}
    for path in glob.glob(os.path.join(folder, "timeline_step*.csv")):
        m = pattern.search(path)
        if m:
            reference[int(m.group(1))] = path
    if not reference:
        sys.exit(f"error: no one-rank timelines (timeline_step<S>.csv) in {folder}")
    mine = defaultdict(lambda: defaultdict(float))    # rank -> type -> s
    theirs = defaultdict(lambda: defaultdict(float))  # rank -> type -> s, the same tasks
    unmatched = 0
    matched = 0
    for s, files in sorted(steps.items()):
        if s not in reference or len(files) != len(ranks):
            continue
        ref = task_times(reference[s])
        for r in ranks:
            for (name, cell), ns in task_times(files[r]).items():
                if (name, cell) not in ref:
                    unmatched += 1  # messages, or a step that differs from the reference
                    continue
                matched += 1
                mine[r][name] += ns / 1e9
                theirs[r][name] += ref[(name, cell)] / 1e9
    if matched == 0:
        sys.exit(f"error: no task of {folder} matches a task of the ranks (not the same run?)")
    types = sorted({t for r in ranks for t in mine[r]}, key=lambda t: -sum(theirs[r][t] for r in ranks))
    print(f"against {folder}, the same tasks (step, type, cell): rank's time / reference's (s)")
    for t in types:
        print(f"  {t}: " + "; ".join(f"rank {r} {mine[r][t]:.3f} / {theirs[r][t]:.3f} ({mine[r][t] / theirs[r][t]:.2f})"
                                     if theirs[r][t] > 0 else f"rank {r} -" for r in ranks))
    def ratio(a, b):
        return f"{a / b:.2f}" if b > 0 else "-"
    print("  all: " + "; ".join(f"rank {r} {sum(mine[r].values()):.3f} / {sum(theirs[r].values()):.3f} "
                                f"({ratio(sum(mine[r].values()), sum(theirs[r].values()))})" for r in ranks))
    print(f"  ({matched} tasks matched; {unmatched} without a counterpart, such as sends and receives)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder", help="folder with timeline_step<S>_rank<R>.csv files")
    parser.add_argument("--per-step", action="store_true", help="print each full step's ranks")
    parser.add_argument("--reference", metavar="FOLDER",
                        help="timelines of the same run on one rank, to compare each rank's tasks with")
    args = parser.parse_args(argv)
    pattern = re.compile(r"timeline_step(\d+)_rank(\d+)\.csv$")
    steps = defaultdict(dict)
    for path in glob.glob(os.path.join(args.folder, "timeline_step*_rank*.csv")):
        m = pattern.search(path)
        if m:
            steps[int(m.group(1))][int(m.group(2))] = path
    if not steps:
        sys.exit(f"error: no timeline_step*_rank*.csv files in {args.folder}")
    ranks = sorted({r for s in steps.values() for r in s})
    if len(ranks) < 2:
        sys.exit(f"error: {args.folder} holds the timelines of one rank; this compares ranks")
    data = {s: {r: read_step(p) for r, p in files.items()} for s, files in sorted(steps.items()) if len(files) == len(ranks)}
    most_tasks = max(sum(d[r][3] for r in ranks) for d in data.values())
    totals = defaultdict(lambda: defaultdict(float))
    speed = defaultdict(list)  # per task type: faster rank's time over the slower's, full steps
    for s, d in data.items():
        # Full steps run every task of the graph; a partial step fewer.
        kind = "full" if sum(d[r][3] for r in ranks) >= 0.9 * most_tasks else "partial"
        t = totals[kind]
        busy = [d[r][0] for r in ranks]
        t["steps"] += 1
        for r in ranks:
            t[f"busy rank {r}"] += d[r][0] / 1e9
        span = max(d[r][1] for r in ranks)
        t["span"] += span / 1e9
        t["imbalance"] += (max(busy) - statistics.mean(busy)) / 1e9
        t["tail"] += max(0, span - max(busy)) / 1e9
        t[f"busiest is rank {ranks[busy.index(max(busy))]}"] += 1
        if kind == "full":
            for typ in d[ranks[0]][2]:
                times = [d[r][2].get(typ, 0) for r in ranks]
                if min(times) > 0:
                    speed[typ].append(min(times) / max(times))
            if args.per_step:
                print(f"step {s}: busy " + " ".join(f"{d[r][0] / 1e6:.1f}" for r in ranks) + f" ms, span {span / 1e6:.1f} ms")
    for kind in ("full", "partial"):
        t = totals[kind]
        if not t:
            continue
        print(f"{kind} steps: {int(t['steps'])}")
        print("  busy per rank (s): " + ", ".join(f"{t[f'busy rank {r}']:.3f}" for r in ranks))
        print(f"  graph span (s): {t['span']:.3f}; imbalance (busiest minus mean): {t['imbalance']:.3f}; "
              f"tail beyond the busiest: {t['tail']:.3f}")
        print("  steps in which each rank was the busiest: " + ", ".join(f"rank {r} {int(t[f'busiest is rank {r}'])}" for r in ranks))
    if speed:
        print("full steps, per task type: faster rank's time / slower rank's, median (10th percentile)")
        for typ, v in sorted(speed.items(), key=lambda kv: -len(kv[1])):
            v = sorted(v)
            print(f"  {typ}: {statistics.median(v):.3f} ({v[len(v) // 10]:.3f}) over {len(v)} steps")
    if args.reference:
        compare_with_reference(steps, ranks, args.reference)
    return 0


if __name__ == "__main__":
    sys.exit(main())
