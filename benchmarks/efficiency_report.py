"""Summary of benchmarks/efficiency_pairs.sh: per-pair 2-thread efficiency T1 / (2 T2), its
median, the ratio of the median times, and the ratio of the fastest times. Other load on the
host only ever adds time, so the fastest run of each kind is the estimate of the code's own
speed least disturbed by it; the median pair is the more conservative figure. Writes
summary.json beside the pairs."""
import glob
import json
import os
import statistics
import sys


def main(folder):
    pairs = []
    for t1 in sorted(glob.glob(os.path.join(folder, "pair_*_t1.json")),
                     key=lambda p: int(os.path.basename(p).split("_")[1])):
        t2 = t1.replace("_t1.json", "_t2.json")
        if not os.path.exists(t2):
            continue
        a, b = json.load(open(t1)), json.load(open(t2))
        pairs.append((a["wall_s"], b["wall_s"], a["task_seconds_by_category"], b["task_seconds_by_category"]))
    if not pairs:
        sys.exit(f"no pairs in {folder}")
    print("| pair | 1 thread (s) | 2 threads (s) | efficiency |")
    print("|---|---|---|---|")
    effs = []
    for k, (w1, w2, _, _) in enumerate(pairs, 1):
        effs.append(w1 / (2.0 * w2))
        print(f"| {k} | {w1:.2f} | {w2:.2f} | {100 * effs[-1]:.1f}% |")
    one = [p[0] for p in pairs]
    two = [p[1] for p in pairs]
    summary = {
        "pairs": len(pairs),
        "median_pair_efficiency": statistics.median(effs),
        "median_times_s": [statistics.median(one), statistics.median(two)],
        "efficiency_of_median_times": statistics.median(one) / (2.0 * statistics.median(two)),
        "fastest_times_s": [min(one), min(two)],
        "efficiency_of_fastest_times": min(one) / (2.0 * min(two)),
    }
    print(f"median pair {100 * summary['median_pair_efficiency']:.1f}%; median times "
          f"{summary['median_times_s'][0]:.2f} / {summary['median_times_s'][1]:.2f} s: "
          f"{100 * summary['efficiency_of_median_times']:.1f}%; fastest times "
          f"{min(one):.2f} / {min(two):.2f} s: {100 * summary['efficiency_of_fastest_times']:.1f}%")
    json.dump(summary, open(os.path.join(folder, "summary.json"), "w"), indent=1)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "benchmarks/results/efficiency")
