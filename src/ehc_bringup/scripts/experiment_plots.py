#!/usr/bin/python3
"""PNG plots of an `ehc_experiment grasp|poses` result folder.

  experiment_plots.py DIR

Reads DIR/trace.csv and DIR/trials.csv, writes
  DIR/distance.png  ||TCP - object|| over the time of each attempt, per method: mean and the
                    10-90 % spread over every set and object (the paper's figure of the
                    end-effector-to-target distance over time)
  DIR/speeds.png    base translation / rotation and arm speed profiles (mean per method)
  DIR/tfm.png       TfM per approach and method (Exp-3; Exp-2: per object)
Without matplotlib it says so and exits 0 (the tables do not depend on it).
"""
import csv
import os
import sys
from collections import defaultdict


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    d = sys.argv[1]
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import numpy as np
    except ImportError as e:
        print("experiment_plots.py: no plots (%s)" % e, file=sys.stderr)
        return 0
    trace = defaultdict(lambda: defaultdict(list))  # method -> bin -> [values...]
    speeds = defaultdict(lambda: defaultdict(lambda: [[], [], []]))
    period = 0.1
    with open(os.path.join(d, "trace.csv")) as f:
        for r in csv.DictReader(f):
            b = int(round(float(r["t"]) / period))
            trace[r["method"]][b].append(float(r["distance"]))
            s = speeds[r["method"]][b]
            s[0].append(float(r["base_speed"]))
            s[1].append(float(r["base_turn"]))
            s[2].append(float(r["arm_speed"]))
    methods = list(trace.keys())

    fig, ax = plt.subplots(figsize=(8, 4.5))
    for m in methods:
        bins = sorted(trace[m])
        t = np.array(bins) * period
        v = [trace[m][b] for b in bins]
        mean = np.array([np.mean(x) for x in v])
        lo = np.array([np.percentile(x, 10) for x in v])
        hi = np.array([np.percentile(x, 90) for x in v])
        ax.plot(t, mean, label=m)
        ax.fill_between(t, lo, hi, alpha=0.2)
    ax.set_xlabel("time since the object's attempt began (s)")
    ax.set_ylabel("||TCP - object|| (m)")
    ax.set_title("End-effector to object distance (mean, 10-90 % over sets and objects)")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(d, "distance.png"), dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    labels = ["base |v| (m/s)", "base |w| (rad/s)", "arm sum |qd| (rad/s)"]
    for m in methods:
        bins = sorted(speeds[m])
        t = np.array(bins) * period
        for k in range(3):
            axes[k].plot(t, [np.mean(speeds[m][b][k]) for b in bins], label=m)
    for k in range(3):
        axes[k].set_ylabel(labels[k])
        axes[k].grid(True, alpha=0.3)
    axes[0].legend()
    axes[-1].set_xlabel("time since the object's attempt began (s)")
    fig.suptitle("Commanded speed profiles (mean over sets and objects)")
    fig.tight_layout()
    fig.savefig(os.path.join(d, "speeds.png"), dpi=110)
    plt.close(fig)

    tfm = defaultdict(lambda: defaultdict(list))
    with open(os.path.join(d, "trials.csv")) as f:
        for r in csv.DictReader(f):
            key = r["approach"] if r["object"] == "target" else r["object"]
            tfm[r["method"]][key].append(100.0 * float(r["tfm"]))
    keys = []
    for m in tfm:
        for k in tfm[m]:
            if k not in keys:
                keys.append(k)
    fig, ax = plt.subplots(figsize=(7, 4))
    width = 0.8 / max(1, len(tfm))
    for i, m in enumerate(tfm):
        ax.bar([j + i * width for j in range(len(keys))], [np.mean(tfm[m][k]) if tfm[m][k] else 0 for k in keys],
               width, label=m)
    ax.set_xticks([j + 0.4 - width / 2 for j in range(len(keys))])
    ax.set_xticklabels(keys)
    ax.set_ylabel("TfM (%)")
    ax.set_ylim(0, 105)
    ax.legend()
    ax.set_title("Time for monitoring")
    fig.tight_layout()
    fig.savefig(os.path.join(d, "tfm.png"), dpi=110)
    plt.close(fig)
    print("experiment_plots.py: %s/{distance,speeds,tfm}.png" % d, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
