#!/usr/bin/env python3
"""Gantt chart and summary of Fountain task timelines.

Reads one or more timeline CSV files written by fountain::tasks::write_timeline_csv, e.g. the
files of all ranks for one step:

    plot_tasks.py timeline_step10_rank*.csv -o gantt.png
    plot_tasks.py timeline.csv --summary-only

Each file starts with a comment line ("# fountain task timeline: step=S rank=R") and then has
the columns type,subtype,category,ci,cj,rank,thread,start_ns,end_ns (ns since the step began).
The chart has one row per (rank, thread) and one bar per task, coloured by task type
(type_subtype). On stdout it prints the time spent per task type and, per (rank, thread), the
busy time and the idle fraction 1 - busy / (latest end - earliest start over all files).
Runs across MPI ranks add, per rank, a row of thread -1: the exchanges after the task graph
(waiting for the other ranks, then every rank's changed cells), shown as the rank's
"exchanges" lane, with the share of the span it took; a worker's idle time includes its
waits for messages inside the graph (the recv tasks run once their message is in).

Needs only numpy and matplotlib (Agg backend).
"""
import argparse
import csv
import sys

import numpy as np

COLUMNS = ("type", "subtype", "category", "ci", "cj", "rank", "thread", "start_ns", "end_ns")


def read_timeline(path, cells=False):
    """Returns a list of (task_type, rank, thread, start_ns, end_ns) read from one file; with
    `cells`, each tuple also ends with the task's cell (ci)."""
    rows = []
    with open(path, newline="") as f:
        lines = (l for l in f if l.strip() and not l.lstrip().startswith("#"))
        reader = csv.reader(lines)
        header = next(reader, None)
        if header is None:
            return rows
        header = [h.strip() for h in header]
        missing = [c for c in COLUMNS if c not in header]
        if missing:
            raise ValueError("%s: missing column(s) %s" % (path, ", ".join(missing)))
        col = {name: header.index(name) for name in COLUMNS}
        for n, rec in enumerate(reader, start=2):
            if len(rec) < len(header):
                raise ValueError("%s: line %d has %d fields, expected %d" % (path, n, len(rec), len(header)))
            t = rec[col["type"]].strip()
            s = rec[col["subtype"]].strip()
            name = t + "_" + s if s else t
            row = (name, int(rec[col["rank"]]), int(rec[col["thread"]]),
                   int(rec[col["start_ns"]]), int(rec[col["end_ns"]]))
            rows.append(row + (int(rec[col["ci"]]),) if cells else row)
    return rows


def summarise(names, rank, thread, start, end):
    """Prints the per-type and per-(rank, thread) tables."""
    dur = (end - start).astype(np.float64)
    busy_total = dur.sum()
    t0, t1 = start.min(), end.max()
    span = float(t1 - t0)
    print("Timeline: %d tasks, span %.3f ms, busy %.3f ms summed over %d (rank, thread) rows"
          % (len(names), span * 1e-6, busy_total * 1e-6,
             len(set(zip(rank.tolist(), thread.tolist())))))
    print()

    types = sorted(set(names.tolist()))
    per_type = []
    for ty in types:
        sel = names == ty
        per_type.append((ty, dur[sel].sum(), int(sel.sum())))
    per_type.sort(key=lambda r: -r[1])
    width = max(len("task type"), max(len(r[0]) for r in per_type))
    print("%-*s %12s %8s %8s" % (width, "task type", "time [ms]", "share", "count"))
    for ty, t, n in per_type:
        share = 100.0 * t / busy_total if busy_total > 0 else 0.0
        print("%-*s %12.3f %7.1f%% %8d" % (width, ty, t * 1e-6, share, n))
    print()

    print("%6s %6s %12s %8s %8s" % ("rank", "thread", "busy [ms]", "idle", "tasks"))
    for r, th in sorted(set(zip(rank.tolist(), thread.tolist()))):
        sel = (rank == r) & (thread == th)
        busy = dur[sel].sum()
        if th < 0:  # the exchanges after the graph: time spent communicating, not idle
            share = busy / span if span > 0 else 0.0
            print("%6d %6s %12.3f %7.1f%% of the span in exchanges with other ranks" % (r, "-", busy * 1e-6, 100.0 * share))
            continue
        idle = 1.0 - busy / span if span > 0 else 0.0
        print("%6d %6d %12.3f %7.1f%% %8d" % (r, th, busy * 1e-6, 100.0 * idle, int(sel.sum())))


def type_colours(types):
    import matplotlib.pyplot as plt

    n = len(types)
    if n <= 10:
        cmap = plt.get_cmap("tab10")
        return {t: cmap(i) for i, t in enumerate(types)}
    if n <= 20:
        cmap = plt.get_cmap("tab20")
        return {t: cmap(i) for i, t in enumerate(types)}
    cmap = plt.get_cmap("hsv")
    return {t: cmap(i / n) for i, t in enumerate(types)}


def plot_gantt(names, rank, thread, start, end, output, title):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    lanes = sorted(set(zip(rank.tolist(), thread.tolist())))
    lane_of = {lane: i for i, lane in enumerate(lanes)}
    y = np.array([lane_of[(r, th)] for r, th in zip(rank.tolist(), thread.tolist())])
    t0 = start.min()
    left = (start - t0) * 1e-6
    width = (end - start) * 1e-6

    types = sorted(set(names.tolist()))
    colours = type_colours(types)

    height = max(2.5, 0.45 * len(lanes) + 1.5)
    fig, ax = plt.subplots(figsize=(12, height))
    for ty in types:
        sel = names == ty
        ax.barh(y[sel], width[sel], left=left[sel], height=0.8, color=colours[ty],
                edgecolor="none", align="center")
    ax.set_yticks(range(len(lanes)))
    ax.set_yticklabels(["rank %d exchanges" % lane[0] if lane[1] < 0 else "rank %d thread %d" % lane for lane in lanes])
    ax.set_ylim(-0.6, len(lanes) - 0.4)
    ax.invert_yaxis()
    ax.set_xlim(0, max(float((end.max() - t0) * 1e-6), 1e-6))
    ax.set_xlabel("time since step start [ms]")
    ax.set_title(title)
    handles = [Patch(facecolor=colours[t], label=t) for t in types]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small",
              frameon=False)
    fig.tight_layout()
    fig.savefig(output, dpi=120)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("files", nargs="+", help="timeline CSV file(s)")
    parser.add_argument("-o", "--output", default="gantt.png", help="output PNG (default: gantt.png)")
    parser.add_argument("--summary-only", action="store_true", help="print the summary, draw nothing")
    parser.add_argument("--title", default=None, help="title of the chart")
    args = parser.parse_args(argv)

    rows = []
    for path in args.files:
        try:
            rows.extend(read_timeline(path))
        except (OSError, ValueError) as e:
            print("plot_tasks.py: %s" % e, file=sys.stderr)
            return 2

    if not rows:
        print("No tasks in the timeline (%s): nothing to summarise." % ", ".join(args.files))
        return 0

    names = np.array([r[0] for r in rows])
    rank = np.array([r[1] for r in rows], dtype=np.int64)
    thread = np.array([r[2] for r in rows], dtype=np.int64)
    start = np.array([r[3] for r in rows], dtype=np.int64)
    end = np.array([r[4] for r in rows], dtype=np.int64)

    summarise(names, rank, thread, start, end)

    if not args.summary_only:
        title = args.title or "Fountain tasks: " + ", ".join(args.files)
        if len(title) > 100:
            title = title[:97] + "..."
        plot_gantt(names, rank, thread, start, end, args.output, title)
        print()
        print("Gantt chart written to %s" % args.output)
    return 0


if __name__ == "__main__":
    sys.exit(main())
