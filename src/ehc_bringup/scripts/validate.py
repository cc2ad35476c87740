#!/usr/bin/python3
"""`make validate`: Exp-1 reaching on seeds nobody tuned on, every robot x target generator x method.

  validate.py --out DIR [--seed S] [--robots all|NAME,...] [--generators paper,any]
              [--methods neo_c,neo_e,ehc] [--sets 4] [--points 50] [--jobs 2] [--bar 0.002]
              [--devel devel] [--config controller.yaml]

Draws a fresh random seed per run (or takes --seed) and prints it first, so that the whole run
reproduces; then runs `ehc_experiment reach` (noise on, back to back, ideal base) for every
shipped robot (config/robots/*/robot.yaml) and every target generator, all methods on the same
targets, at most --jobs at a time, with progress and ETA on stderr. Only targets that whole-body
IK reaches inside the joint stops are drawn (the runner redraws the others), so every failure
counts against the controller.

Prints every failed target with its cause and the command that reruns its set alone
(`--first-set K --sets 1`: set K's targets and noise depend only on the seed and K), and per
robot x generator x method: failures per target with a 95 % Wilson interval, the mean time per
reached target with a 95 % bootstrap interval over the sets (make_results.bootstrap), failures
per cause. Writes DIR/validate.md, DIR/validate.json, DIR/failures.csv, DIR/validate.png and each
run's folder DIR/<robot>/<generator>/.

Exit code: 0 when every robot x generator x method fails at most --bar of its targets (the bar:
1 failure per 500 targets), 1 above it, 2 on an error.
"""
import argparse
import csv
import glob
import json
import math
import os
import random
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_results import ROOT, bootstrap, code_version, per_set  # noqa: E402  (one home for the statistics)

GENERATORS = ("paper", "any")
METHODS = ("neo_c", "neo_e", "ehc")


def shipped_robots():
    return sorted(os.path.basename(os.path.dirname(p)) for p in glob.glob(os.path.join(ROOT, "config/robots/*/robot.yaml")))


def wilson(k, n, z=1.96):
    """95 % Wilson score interval of a proportion k/n (valid for rare failures, unlike p +- z s)."""
    if n == 0:
        return None
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--seed", type=int, default=None)
    ap.add_argument("--robots", default="all")
    ap.add_argument("--generators", default=",".join(GENERATORS))
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--sets", type=int, default=4)
    ap.add_argument("--points", type=int, default=50)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--bar", type=float, default=1.0 / 500.0)
    ap.add_argument("--devel", default=os.path.join(ROOT, "devel"))
    ap.add_argument("--config", default=None, help="controller.yaml for every run (default: the stack's)")
    a = ap.parse_args(argv)
    robots = shipped_robots()
    a.robots = robots if a.robots == "all" else a.robots.split(",")
    a.generators = a.generators.split(",")
    a.methods = a.methods.split(",")
    for r in a.robots:
        if r not in robots:
            ap.error("--robots: unknown robot '%s' (shipped: %s)" % (r, ", ".join(robots)))
    for g in a.generators:
        if g not in GENERATORS:
            ap.error("--generators: unknown generator '%s' (%s)" % (g, ", ".join(GENERATORS)))
    for m in a.methods:
        if m not in METHODS:
            ap.error("--methods: unknown method '%s' (%s)" % (m, ", ".join(METHODS)))
    if a.sets < 1 or a.points < 1 or a.jobs < 1 or not 0 <= a.bar < 1:
        ap.error("--sets, --points and --jobs must be >= 1, --bar in [0, 1)")
    if a.seed is None:
        a.seed = random.SystemRandom().randrange(1, 1000000)
    exe = os.path.join(a.devel, "lib", "ehc_bringup", "ehc_experiment")
    if not os.access(exe, os.X_OK):
        ap.error("%s not found: build first (make build)" % exe)
    a.exe = exe
    try:
        os.makedirs(a.out, exist_ok=True)
        probe = os.path.join(a.out, ".write_test")
        open(probe, "w").close()
        os.remove(probe)
    except OSError as e:
        ap.error("--out %s is not writable: %s" % (a.out, e))
    return a


def reach_command(a, robot, generator, methods, first_set, sets, out):
    return [a.exe, "reach", "--robot", robot, "--generator", generator,
            "--method", methods[0] if len(methods) == 1 else "all", "--sets", str(sets),
            "--points", str(a.points), "--seed", str(a.seed), "--first-set", str(first_set), "--out", out] + \
        (["--config", os.path.abspath(a.config)] if a.config else [])


DONE_FILE = "done.json"  # written into a run's folder when its command succeeded


def finished_before(r):
    """The record of an earlier successful run of exactly r["cmd"] into r["out"], or None."""
    try:
        with open(os.path.join(r["out"], DONE_FILE)) as f:
            done = json.load(f)
    except (OSError, ValueError):
        return None
    return done if done.get("cmd") == r["cmd"] else None


def run_all(runs, jobs, tag, label, resume=False):
    """Runs the commands of `runs` (dicts with "cmd" and "out"), at most `jobs` at a time, each
    one's output in its out/run.log and, on success, out/done.json (the command, its CPU time and
    the code version). Sets run["cpu_s"] (the process's user + sys time, s); progress, `label(run)`
    and ETA on stderr prefixed [tag]. A failed run raises RuntimeError naming its command and log.
    resume: a run whose done.json records the same command is not run again (its record is kept;
    its cpu_s may be None: not recorded)."""
    t0 = time.time()
    pending, active, done = list(runs), [], 0
    if resume:
        for r in [r for r in pending if finished_before(r)]:
            rec = finished_before(r)
            r["cpu_s"], r["code_version"] = rec["cpu_s"], rec.get("code_version", "?")
            pending.remove(r)
        sys.stderr.write("[%s] resuming: %d of %d runs done before, %d to run\n" % (
            tag, len(runs) - len(pending), len(runs), len(pending)))
        runs = pending[:]
    version = code_version()
    try:
        while pending or active:
            while pending and len(active) < jobs:
                r = pending.pop(0)
                os.makedirs(r["out"], exist_ok=True)
                with open(os.path.join(r["out"], "run.log"), "w") as log:
                    r["proc"] = subprocess.Popen(r["cmd"], stdout=log, stderr=subprocess.STDOUT)
                active.append(r)
            time.sleep(0.2)
            for r in list(active):
                pid, status, usage = os.wait4(r["proc"].pid, os.WNOHANG)
                if pid == 0:
                    continue
                r["proc"].returncode = os.waitstatus_to_exitcode(status)
                r["cpu_s"] = usage.ru_utime + usage.ru_stime
                active.remove(r)
                done += 1
                if r["proc"].returncode != 0:
                    raise RuntimeError("%s failed (exit %d), see %s/run.log" % (
                        " ".join(r["cmd"]), r["proc"].returncode, r["out"]))
                r["code_version"] = version
                with open(os.path.join(r["out"], DONE_FILE), "w") as f:
                    json.dump({"cmd": r["cmd"], "cpu_s": r["cpu_s"], "code_version": version}, f)
                el = time.time() - t0
                sys.stderr.write("[%s] %d/%d runs done (%s)  elapsed %.0f s  ETA %.0f s\n"
                                 % (tag, done, len(runs), label(r), el, el * (len(runs) - done) / done))
    finally:
        for r in active:  # an error or a stop: no orphaned runs
            r["proc"].terminate()
            r["proc"].wait()


def read_trials(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def summarise(a, runs):
    rows, failures = [], []
    for r in runs:
        trials = read_trials(os.path.join(r["out"], "trials.csv"))
        for m in a.methods:
            mine = [t for t in trials if t["method"] == m]
            n, reached = len(mine), sum(int(t["reached"]) for t in mine)
            k = n - reached
            causes = {}
            for t in mine:
                if int(t["reached"]):
                    continue
                cause = t["failure"] + ("(" + t["failure_joint"] + ")" if t["failure_joint"] else "")
                causes[cause] = causes.get(cause, 0) + 1
                rerun = reach_command(a, r["robot"], r["generator"], [m], int(t["set"]), 1, "/tmp/rerun")
                failures.append({"robot": r["robot"], "generator": r["generator"], "method": m, "seed": a.seed,
                                 "set": int(t["set"]), "index": int(t["index"]), "cause": t["failure"],
                                 "joint": t["failure_joint"], "position_error_m": float(t["final_position_error_m"]),
                                 "rerun": "rosrun ehc_bringup ehc_experiment " + " ".join(rerun[1:])})
            sets = per_set([dict(t, _r=int(t["reached"]), _t=float(t["time_s"])) for t in mine],
                           lambda t: (t["_t"] * t["_r"], t["_r"]))
            time_point, time_ci = bootstrap(*zip(*sets)) if reached else (float("nan"), None)
            rows.append({"robot": r["robot"], "generator": r["generator"], "method": m, "targets": n, "failed": k,
                         "failure_rate": k / n if n else float("nan"), "failure_rate_ci95": wilson(k, n),
                         "mean_time_s": time_point, "mean_time_s_ci95": time_ci, "causes": causes,
                         "passes_bar": n > 0 and k / n <= a.bar})
    return rows, failures


def ci_text(ci, scale=1.0, digits=2):
    return "-" if ci is None else "[%.*f, %.*f]" % (digits, ci[0] * scale, digits, ci[1] * scale)


def write_outputs(a, rows, failures, wall):
    with open(os.path.join(a.out, "validate.json"), "w") as f:
        json.dump({"seed": a.seed, "sets": a.sets, "points": a.points, "bar": a.bar, "wall_s": round(wall, 1),
                   "rows": rows, "failures": failures}, f, indent=1)
    with open(os.path.join(a.out, "failures.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["robot", "generator", "method", "seed", "set", "index", "cause", "joint",
                                          "position_error_m", "rerun"])
        w.writeheader()
        w.writerows(failures)
    with open(os.path.join(a.out, "validate.md"), "w") as f:
        f.write("# Reaching validation (Exp-1 protocol, fresh seed)\n\nSeed %d (drawn for this run, not tuned on); %d sets x %d "
                "targets per robot and generator, noise on, back to back, ideal base; bar: at most %.4f failures per "
                "target. Command: `%s`. %.0f s wall.\n\n" % (a.seed, a.sets, a.points, a.bar, " ".join(sys.argv), wall))
        f.write("| Robot | Generator | Method | Targets | Failed | Failures per target (95 % CI) | Time per reached target, s (95 % CI) | Causes | Bar |\n")
        f.write("|---|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            causes = ", ".join("%s %d" % kv for kv in sorted(r["causes"].items())) or "-"
            f.write("| %s | %s | %s | %d | %d | %.3f %s | %.2f %s | %s | %s |\n" % (
                r["robot"], r["generator"], r["method"], r["targets"], r["failed"], r["failure_rate"],
                ci_text(r["failure_rate_ci95"], digits=3), r["mean_time_s"], ci_text(r["mean_time_s_ci95"]), causes,
                "pass" if r["passes_bar"] else "FAIL"))
        f.write("\nEvery failure and the command that reruns its set: `failures.csv`.\n")
    plot(a, rows)


def plot(a, rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(max(6, 0.6 * len(rows)), 4))
    xs = range(len(rows))
    rates = [100 * r["failure_rate"] for r in rows]
    lo = [100 * (r["failure_rate"] - r["failure_rate_ci95"][0]) if r["failure_rate_ci95"] else 0 for r in rows]
    hi = [100 * (r["failure_rate_ci95"][1] - r["failure_rate"]) if r["failure_rate_ci95"] else 0 for r in rows]
    ax.bar(xs, rates, yerr=[lo, hi], capsize=3, color=["C%d" % a.methods.index(r["method"]) for r in rows])
    ax.axhline(100 * a.bar, color="k", linestyle="--", linewidth=1, label="bar")
    ax.set_xticks(list(xs))
    ax.set_xticklabels(["%s\n%s\n%s" % (r["robot"].split("_")[0], r["generator"], r["method"]) for r in rows], fontsize=7)
    ax.set_ylabel("failed targets, % (95 % CI)")
    ax.set_title("Reaching validation, seed %d" % a.seed)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "validate.png"), dpi=100)


def main(argv):
    a = parse_args(argv)
    sys.stderr.write("[validate] seed %d (rerun with --seed %d); robots %s; generators %s; methods %s; %d x %d targets each\n"
                     % (a.seed, a.seed, ",".join(a.robots), ",".join(a.generators), ",".join(a.methods), a.sets, a.points))
    runs = []
    for robot in a.robots:
        for g in a.generators:
            out = os.path.join(a.out, robot, g)
            runs.append({"robot": robot, "generator": g, "out": out,
                         "cmd": reach_command(a, robot, g, a.methods if len(a.methods) == 1 else ["all"], 0, a.sets, out)})
    t0 = time.time()
    try:
        run_all(runs, a.jobs, "validate", lambda r: "%s %s" % (r["robot"], r["generator"]))
        rows, failures = summarise(a, runs)
    except (RuntimeError, OSError, KeyError, ValueError) as e:
        sys.stderr.write("validate.py: %s\n" % e)
        return 2
    write_outputs(a, rows, failures, time.time() - t0)
    for fl in failures:
        print("FAILED %s %s %s set %d target %d: %s%s (%.3f m short); rerun: %s" % (
            fl["robot"], fl["generator"], fl["method"], fl["set"], fl["index"], fl["cause"],
            " " + fl["joint"] if fl["joint"] else "", fl["position_error_m"], fl["rerun"]))
    bad = [r for r in rows if not r["passes_bar"]]
    for r in rows:
        print("%-24s %-6s %-6s %4d targets %3d failed  %.3f per target  %s" % (
            r["robot"], r["generator"], r["method"], r["targets"], r["failed"], r["failure_rate"],
            "pass" if r["passes_bar"] else "ABOVE THE BAR"))
    print("validate: seed %d, %d of %d robot x generator x method above the bar of %.4f; %s/validate.md"
          % (a.seed, len(bad), len(rows), a.bar, a.out))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
