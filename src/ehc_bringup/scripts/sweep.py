#!/usr/bin/python3
"""`make sweep`: the paper's experiments for every method x base-imprecision level x seed, with
95 % bootstrap intervals over the sets and paired differences EHC - baseline on the same sets.

  sweep.py run --out DIR [--seeds S1,S2,...] [--seed-count 10] [--levels 0,1,2,4]
               [--experiments exp1_sequence,exp1_reset,exp2,exp3] [--methods all]
               [--robot realman_rm65_water2] [--exp1-sets 2] [--exp1-points 25] [--exp2-sets 2]
               [--exp3-sets 1] [--exp3-per-set 2] [--object-time-limit S] [--bootstrap-seed 1]
               [--jobs 2] [--shard K/N] [--devel devel]
  sweep.py merge --out DIR SHARD_DIR...
  sweep.py seeds N

Experiments: exp1_sequence / exp1_reset = `ehc_experiment reach` (paper Table II) with the
targets back to back / each from the ready pose; exp2 = `ehc_experiment grasp` (Table III);
exp3 = `ehc_experiment poses` (Table IV, TfM). Each (experiment, level, seed, method) is one job:
one ehc_experiment run with `--seed S --base-imprecision L` (level 0 = the ideal base; an
ehc_experiment without --base-imprecision runs level 0 only and other levels are refused). All
methods of an experiment, level and seed run on the same targets and noise (they depend only on
the seed and the set), so EHC - baseline is paired set by set.

Seeds: --seeds, or --seed-count fresh ones drawn for this run and printed first. Seeds below
1000 are tuning seeds (the development runs' fixed seeds: make experiments SEED=1, the test
fixtures' 7, ...); `sweep.py seeds N` draws N reporting seeds (>= 1000, never tuned on). The
report names each seed's role, and make_results.py's verdicts say whether they rest on
reporting seeds only.

Statistics: the unit is a set (seed, set number): per experiment, method and level, each metric
is the pooled ratio over all sets with its 95 % percentile bootstrap interval from resampling
the sets (make_results.bootstrap; --bootstrap-seed, recorded); paired: the difference and ratio
EHC - baseline (Exp-1/2: NEO(e), Exp-3: NEO without MPBS) with the sets resampled together.

Sharding: --shard K/N runs the K-th of N parts of the plan's jobs, balanced by their estimated
CPU time (each part a mix of experiments and methods; the same split on every machine), and
writes DIR/shard-K-of-N.json; `merge` checks that the shard folders'
plans agree and cover every job once and writes the report. The shards may share one DIR (GNU
parallel on one machine) or use one DIR each (cluster array jobs). Sharded runs need --seeds
(every shard must draw the same). Without --shard the run is shard 1/1 and writes the report.

Writes to DIR: sweep.json (plan, seeds and roles, bootstrap seed, every cell and paired
difference), sweep.csv, paired.csv, sweep.md, <experiment>.png (each metric against the level,
one line per method, CI bands), runs/<experiment>/L<level>/s<seed>/<method>/ (ehc_experiment's
folder). Progress and ETA on stderr. Exit code 0, 2 on an error.
"""
import argparse
import hashlib
import json
import math
import os
import random
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_results as mr  # noqa: E402  (one home for the statistics and the result readers)
from validate import run_all  # noqa: E402  (one home for the job runner)

REPORTING_SEED_RANGE = (mr.TUNING_SEEDS_BELOW, 1000000)  # seed*1000 + set*10 + index fits 32 bits

# experiment -> ehc_experiment command, extra arguments, methods, the paired (method, baseline) comparisons,
# paper table
EXPERIMENTS = {
    "exp1_sequence": {"command": "reach", "args": ["--protocol", "sequence"], "methods": ("neo_c", "neo_e", "ehc", "ehc_place"),
                      "pairs": (("ehc", "neo_e"), ("ehc_place", "neo_e")), "table": "Table II",
                      "title": "Exp-1 random reaching, back to back"},
    "exp1_reset": {"command": "reach", "args": ["--protocol", "reset"], "methods": ("neo_c", "neo_e", "ehc", "ehc_place"),
                   "pairs": (("ehc", "neo_e"), ("ehc_place", "neo_e")), "table": "Table II",
                   "title": "Exp-1 random reaching, each from the ready pose"},
    "exp2": {"command": "grasp", "args": [], "methods": ("tsmm", "neo_c", "neo_e", "ehc", "ehc_place"),
             "pairs": (("ehc", "neo_e"), ("ehc_place", "neo_e")),
             "table": "Table III", "title": "Exp-2 three objects in sequence"},
    "exp3": {"command": "poses", "args": [], "methods": ("neo_nompbs", "ehc_nompbs", "ehc"),
             "pairs": (("ehc", "neo_nompbs"),), "table": "Table IV", "title": "Exp-3 grasp orientations (TfM)"},
}


def _ratio(num_key, den_key=None, approach=None):
    """A metric's per-trial (numerator, denominator): num * den / den over the trials (approach only)."""
    def fn(r):
        on = 1.0 if approach is None or r["approach"] == approach else 0.0
        den = r[den_key] if den_key else 1.0
        num = r[num_key] if num_key else 1.0 - r["_reached"]
        return num * den * on, den * on
    return fn


# command -> [(metric, better, scale, per-trial (num, den))]; the pooled ratio sum(num)/sum(den)*scale
METRICS = {
    "reach": [("time_s", "lower", 1.0, _ratio("_time", "_reached")),
              ("failures_per_500", "lower", 500.0, _ratio(None))],
    "grasp": [("success_pct", "higher", 100.0, _ratio("_success")),
              ("time_s", "lower", 1.0, _ratio("_time", "_success"))],
    "poses": [("tfm_%s_pct" % a, "higher", 100.0, _ratio("_tfm", approach=a)) for a in mr.APPROACHES] +
             [("success_pct", "higher", 100.0, _ratio("_success"))],
}
PLAN_SIZES = ("exp1_sets", "exp1_points", "exp2_sets", "exp3_sets", "exp3_per_set")


class SweepError(Exception):
    """A plan, shard or result that cannot be used; the message says which and why."""


def draw_seeds(n):
    rng = random.SystemRandom()
    seeds = set()
    while len(seeds) < n:
        seeds.add(rng.randrange(*REPORTING_SEED_RANGE))
    return sorted(seeds)


def level_text(level):
    return "%g" % level


# ------------------------------------------------------------------------------ plan and jobs
def has_imprecision_flag(exe):
    """Whether this ehc_experiment takes --base-imprecision (from its usage text)."""
    r = subprocess.run([exe, "--help"], capture_output=True, text=True, check=False)
    return "--base-imprecision" in r.stdout + r.stderr


def job_id(exp, level, seed, method):
    return "/".join(("runs", exp, "L" + level_text(level), "s%d" % seed, method))


def plan_jobs(plan):
    """The plan's jobs in their fixed order: experiment, level, seed, method."""
    return [{"id": job_id(e, lv, s, m), "experiment": e, "level": lv, "seed": s, "method": m}
            for e in plan["experiments"] for lv in plan["levels"] for s in plan["seeds"] for m in plan["methods"][e]]


def job_cost(plan, job):
    """A job's estimated CPU time in s at level 0 (balances the shards only: per Exp-1 target about
    0.15 s, per Exp-2 set of three objects or Exp-3 grasp x 3 approaches about 4.5 s, on this
    project's 2-core AMD EPYC; any machine keeps the ratios roughly)."""
    command = EXPERIMENTS[job["experiment"]]["command"]
    if command == "reach":
        return 0.3 + 0.15 * plan["exp1_sets"] * plan["exp1_points"]
    if command == "grasp":
        return 4.5 * plan["exp2_sets"]
    return 4.5 * plan["exp3_sets"] * plan["exp3_per_set"]


def shard_jobs(plan, jobs, k, n):
    """Shard k of n: the jobs, dearest first (ties in the order of a hash of their id, so that no
    shard gets one method's jobs only), each to the least loaded shard (the first on a tie);
    shard k's in the plan's order. The same plan gives the same split on every machine."""
    order = sorted(range(len(jobs)), key=lambda i: (-job_cost(plan, jobs[i]),
                                                    hashlib.sha1(jobs[i]["id"].encode()).hexdigest()))
    load, owner = [0.0] * n, {}
    for i in order:
        s = min(range(n), key=lambda x: (load[x], x))
        load[s] += job_cost(plan, jobs[i])
        owner[i] = s
    return [j for i, j in enumerate(jobs) if owner[i] == k - 1]


def job_command(plan, exe, job, out):
    e = EXPERIMENTS[job["experiment"]]
    cmd = [exe, e["command"], "--robot", plan["robot"], "--method", job["method"], "--seed", str(job["seed"]),
           "--out", out] + e["args"]
    if e["command"] == "reach":
        cmd += ["--sets", str(plan["exp1_sets"]), "--points", str(plan["exp1_points"])]
    else:
        cmd += ["--sets", str(plan["exp2_sets"] if e["command"] == "grasp" else plan["exp3_sets"])]
        if e["command"] == "poses":
            cmd += ["--per-set", str(plan["exp3_per_set"])]
        if plan["object_time_limit"] is not None:
            cmd += ["--object-time-limit", repr(plan["object_time_limit"])]
    if plan["imprecision_flag"]:
        cmd += ["--base-imprecision", level_text(job["level"])]
    return cmd


def rerun_command(plan):
    """The unsharded `sweep.py run` that reproduces the plan (its folder: DIR)."""
    cmd = ["src/ehc_bringup/scripts/sweep.py", "run", "--out", "DIR", "--robot", plan["robot"],
           "--seeds", ",".join(str(s) for s in plan["seeds"]),
           "--levels", ",".join(level_text(v) for v in plan["levels"]),
           "--experiments", ",".join(plan["experiments"]),
           "--methods", ",".join(sorted({m for e in plan["experiments"] for m in plan["methods"][e]}))]
    for k in PLAN_SIZES:
        cmd += ["--" + k.replace("_", "-"), str(plan[k])]
    if plan["object_time_limit"] is not None:
        cmd += ["--object-time-limit", repr(plan["object_time_limit"])]
    return " ".join(cmd + ["--bootstrap-seed", str(plan["bootstrap_seed"])])


def parse_list(text, kind, what):
    try:
        return [kind(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise SweepError("%s: '%s' is not a comma-separated list of %s" % (what, text, kind.__name__)) from None


def make_plan(a, imprecision_flag):
    """The plan (everything that decides the results) from the run's arguments."""
    levels = parse_list(a.levels, float, "--levels")
    if not levels or any(not math.isfinite(v) or v < 0 for v in levels) or len(set(levels)) != len(levels):
        raise SweepError("--levels: distinct finite levels >= 0 expected, got '%s'" % a.levels)
    if not imprecision_flag and any(v != 0 for v in levels):
        raise SweepError("--levels %s: this ehc_experiment has no --base-imprecision option (see `ehc_experiment "
                         "--help`), so only level 0 (no base imprecision) can run" % a.levels)
    experiments = parse_list(a.experiments, str, "--experiments")
    unknown = [e for e in experiments if e not in EXPERIMENTS]
    if unknown or not experiments:
        raise SweepError("--experiments: unknown '%s' (%s)" % (",".join(unknown), ", ".join(EXPERIMENTS)))
    wanted = None if a.methods == "all" else parse_list(a.methods, str, "--methods")
    known = {m for e in experiments for m in EXPERIMENTS[e]["methods"]}
    if wanted is not None and (not wanted or any(m not in known for m in wanted)):
        raise SweepError("--methods: '%s' not a method of %s (%s)" % (a.methods, ",".join(experiments), ", ".join(sorted(known))))
    methods = {e: [m for m in EXPERIMENTS[e]["methods"] if wanted is None or m in wanted] for e in experiments}
    experiments = [e for e in experiments if methods[e]]
    seeds = parse_list(a.seeds, int, "--seeds") if a.seeds else draw_seeds(a.seed_count)
    if not seeds or len(set(seeds)) != len(seeds) or any(not 0 <= s < REPORTING_SEED_RANGE[1] for s in seeds):
        raise SweepError("--seeds: distinct seeds in [0, %d) expected" % REPORTING_SEED_RANGE[1])
    for k in PLAN_SIZES:
        if getattr(a, k) < 1:
            raise SweepError("--%s must be >= 1" % k.replace("_", "-"))
    return {"robot": a.robot, "experiments": experiments, "methods": {e: methods[e] for e in experiments},
            "levels": sorted(levels), "seeds": sorted(seeds), **{k: getattr(a, k) for k in PLAN_SIZES},
            "object_time_limit": a.object_time_limit, "bootstrap_seed": a.bootstrap_seed,
            "imprecision_flag": imprecision_flag}


def parse_shard(text):
    try:
        k, n = (int(x) for x in text.split("/"))
    except ValueError:
        raise SweepError("--shard: K/N expected (e.g. 2/8), got '%s'" % text) from None
    if not 1 <= k <= n:
        raise SweepError("--shard %s: 1 <= K <= N expected" % text)
    return k, n


def manifest_name(k, n):
    return "shard-%d-of-%d.json" % (k, n)


# ------------------------------------------------------------------------------ statistics
def read_job_trials(folder, command):
    """A job's trials.csv, numbers parsed (make_results' readers: errors name the file)."""
    if command != "reach":
        return mr.grasp_rows(folder)
    path = os.path.join(folder, "trials.csv")
    rows = mr.read_csv(path, ["method", "set", "index", "reached", "time_s"])
    for r in rows:
        r["_reached"] = mr.number(r, "reached", path, int)
        r["_time"] = mr.number(r, "time_s", path)
    return rows


def unit_sums(trials, fn):
    """{(seed, set): [num, den]} of one method's trials under the metric's per-trial fn."""
    out = {}
    for seed, r in trials:
        n, d = fn(r)
        acc = out.setdefault((seed, int(r["set"])), [0.0, 0.0])
        acc[0] += n
        acc[1] += d
    return out


def ci_list(ci):
    return None if ci is None else [ci[0], ci[1]]


def experiment_stats(plan, exp, level, folders):
    """The cells and paired rows of one experiment at one level."""
    spec = EXPERIMENTS[exp]
    trials = {}
    for m in plan["methods"][exp]:
        trials[m] = []
        for s in plan["seeds"]:
            folder = folders[job_id(exp, level, s, m)]
            rows = [r for r in read_job_trials(folder, spec["command"]) if r["method"] == m]
            if not rows:
                raise SweepError("%s: no trials of method '%s'" % (mr.rel(os.path.join(folder, "trials.csv")), m))
            trials[m] += [(s, r) for r in rows]
    cells, paired = [], []
    for metric, better, scale, fn in METRICS[spec["command"]]:
        sums = {m: unit_sums(trials[m], fn) for m in trials}
        for m in trials:
            keys = sorted(sums[m])
            point, ci = mr.bootstrap([sums[m][k][0] for k in keys], [sums[m][k][1] for k in keys], scale,
                                     plan["bootstrap_seed"])
            cells.append({"experiment": exp, "method": m, "level": level, "metric": metric, "better": better,
                          "mean": point, "ci95": ci_list(ci), "sets": len(keys), "trials": len(trials[m])})
        for a, b in spec["pairs"]:
            if a not in sums or b not in sums:
                continue
            keys = sorted(sums[a])
            if keys != sorted(sums[b]):
                raise SweepError("%s level %s: %s and %s ran different sets" % (exp, level_text(level), a, b))
            p = mr.paired_bootstrap(([sums[a][k][0] for k in keys], [sums[a][k][1] for k in keys]),
                                    ([sums[b][k][0] for k in keys], [sums[b][k][1] for k in keys]), scale,
                                    plan["bootstrap_seed"])
            paired.append({"experiment": exp, "level": level, "metric": metric, "better": better, "a": a, "b": b,
                           "diff": p["diff"][0], "diff_ci95": ci_list(p["diff"][1]), "ratio": p["ratio"][0],
                           "ratio_ci95": ci_list(p["ratio"][1]), "sets": len(keys)})
    return cells, paired


def summarise(plan, folders):
    cells, paired = [], []
    for exp in plan["experiments"]:
        for level in plan["levels"]:
            c, p = experiment_stats(plan, exp, level, folders)
            cells += c
            paired += p
    return cells, paired


# ------------------------------------------------------------------------------ outputs
def fmt(v, ci, digits=2):
    return mr.fmt_ci(v, ci, digits)


def write_csvs(out, cells, paired):
    """sweep.csv (one row per cell) and paired.csv; every float in full (repr), no interval: empty."""
    import csv

    def point_ci(v, ci):
        return [repr(v)] + ([repr(ci[0]), repr(ci[1])] if ci else ["", ""])
    with open(os.path.join(out, "sweep.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["experiment", "method", "level", "metric", "better", "mean", "ci95_lo", "ci95_hi", "sets", "trials"])
        for c in cells:
            w.writerow([c["experiment"], c["method"], level_text(c["level"]), c["metric"], c["better"],
                        *point_ci(c["mean"], c["ci95"]), c["sets"], c["trials"]])
    with open(os.path.join(out, "paired.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["experiment", "level", "metric", "a", "b", "diff", "diff_ci95_lo", "diff_ci95_hi", "ratio",
                    "ratio_ci95_lo", "ratio_ci95_hi", "sets"])
        for p in paired:
            w.writerow([p["experiment"], level_text(p["level"]), p["metric"], p["a"], p["b"],
                        *point_ci(p["diff"], p["diff_ci95"]), *point_ci(p["ratio"], p["ratio_ci95"]), p["sets"]])


def write_markdown(out, report):
    plan, cells, paired = report["plan"], report["cells"], report["paired"]
    lines = ["# Sweep: method x base imprecision x seed", "",
             "- command: `%s` (DIR = this folder)" % report["rerun"],
             "- run as: %s" % "; ".join("`%s`" % c for c in report["commands"]),
             "- code version: `%s`; machine: %s" % (report["code_version"], report["machine"]),
             "- seeds: %s" % ", ".join("%d (%s)" % (s["seed"], s["role"]) for s in report["seeds"]),
             "- levels: %s%s" % (", ".join(level_text(v) for v in plan["levels"]),
                                 "" if plan["imprecision_flag"] else " (ehc_experiment without --base-imprecision)"),
             "- mean [95 %% CI]: percentile bootstrap over the sets (seed x set), %d resamples, bootstrap seed %d"
             % (mr.BOOTSTRAP_RESAMPLES, plan["bootstrap_seed"]),
             "- CPU time of the jobs: %.0f s (user + sys)%s" % (report["cpu_s"], (
                 ", %d resumed run(s) without a record of theirs" % report["cpu_unrecorded"])
                 if report.get("cpu_unrecorded") else "")]
    for exp in plan["experiments"]:
        metrics = [m[0] for m in METRICS[EXPERIMENTS[exp]["command"]]]
        lines += ["", "## %s (%s)" % (EXPERIMENTS[exp]["title"], exp), "",
                  "| Method | Level | " + " | ".join(metrics) + " | sets |", "|---" * (len(metrics) + 3) + "|"]
        for m in plan["methods"][exp]:
            for lv in plan["levels"]:
                mine = {c["metric"]: c for c in cells if c["experiment"] == exp and c["method"] == m and c["level"] == lv}
                lines.append("| %s | %s | %s | %d |" % (m, level_text(lv), " | ".join(
                    fmt(mine[k]["mean"], mine[k]["ci95"]) for k in metrics), mine[metrics[0]]["sets"]))
        for a, b in EXPERIMENTS[exp]["pairs"]:
            mine = [p for p in paired if p["experiment"] == exp and p["a"] == a and p["b"] == b]
            if not mine:
                continue
            lines += ["", "Paired on the same sets:", "", "| Level | Metric | %s - %s [95 %% CI] | %s / %s [95 %% CI] |"
                      % (a, b, a, b), "|---|---|---|---|"]
            lines += ["| %s | %s | %s | %s |" % (level_text(p["level"]), p["metric"], fmt(p["diff"], p["diff_ci95"]),
                                                 fmt(p["ratio"], p["ratio_ci95"], 3)) for p in mine]
        lines += ["", "![%s](%s.png)" % (exp, exp)]
    with open(os.path.join(out, "sweep.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


def plot(out, plan, cells):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as e:
        sys.stderr.write("[sweep] no plots (%s)\n" % e)
        return
    for exp in plan["experiments"]:
        metrics = [m[0] for m in METRICS[EXPERIMENTS[exp]["command"]]]
        fig, axes = plt.subplots(1, len(metrics), figsize=(4.2 * len(metrics), 3.6), squeeze=False)
        for ax, metric in zip(axes[0], metrics):
            for i, m in enumerate(plan["methods"][exp]):
                mine = [c for c in cells if c["experiment"] == exp and c["method"] == m and c["metric"] == metric]
                xs = [c["level"] for c in mine]
                lo = [c["ci95"][0] if c["ci95"] else c["mean"] for c in mine]
                hi = [c["ci95"][1] if c["ci95"] else c["mean"] for c in mine]
                ax.plot(xs, [c["mean"] for c in mine], "o-", color="C%d" % i, label=m)
                ax.fill_between(xs, lo, hi, color="C%d" % i, alpha=0.2)
                if len(xs) == 1:  # a band needs two levels: the interval as an error bar
                    ax.errorbar(xs, [c["mean"] for c in mine], yerr=[[mine[0]["mean"] - lo[0]], [hi[0] - mine[0]["mean"]]],
                                color="C%d" % i, capsize=4)
            ax.set_xlabel("base imprecision level")
            ax.set_ylabel(metric + " (95 % CI)")
            ax.grid(True, alpha=0.3)
        axes[0][0].legend(fontsize=8)
        fig.suptitle("%s: %d seeds" % (EXPERIMENTS[exp]["title"], len(plan["seeds"])))
        fig.tight_layout()
        fig.savefig(os.path.join(out, exp + ".png"), dpi=100)
        plt.close(fig)


def write_report(out, plan, manifests, folders):
    cells, paired = summarise(plan, folders)
    report = {"plan": plan, "rerun": rerun_command(plan),
              "seeds": [{"seed": s, "role": mr.seed_role(s)} for s in plan["seeds"]],
              "bootstrap_seed": plan["bootstrap_seed"], "bootstrap_resamples": mr.BOOTSTRAP_RESAMPLES,
              "commands": [m["command"] for m in manifests], "code_version": manifests[0]["code_version"],
              "machine": "%s, %s core(s)" % (manifests[0]["machine"]["cpu"], manifests[0]["machine"]["cores"]),
              "cpu_s": round(sum(j["cpu_s"] or 0.0 for m in manifests for j in m["jobs"]), 1),
              "cpu_unrecorded": sum(j["cpu_s"] is None for m in manifests for j in m["jobs"]),
              "wall_s": round(sum(m["wall_s"] for m in manifests), 1), "cells": cells, "paired": paired}
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "sweep.json"), "w") as f:
        json.dump(report, f, indent=1)
        f.write("\n")
    write_csvs(out, cells, paired)
    write_markdown(out, report)
    plot(out, plan, cells)
    return report


# ------------------------------------------------------------------------------ commands
def parse_run_args(argv):
    ap = argparse.ArgumentParser(prog="sweep.py run", description="runs the sweep (or one shard of it)")
    ap.add_argument("--out", required=True)
    ap.add_argument("--seeds", help="comma-separated seeds (default: --seed-count fresh reporting seeds)")
    ap.add_argument("--seed-count", type=int, default=10)
    ap.add_argument("--levels", default="0,1,2,4")
    ap.add_argument("--experiments", default=",".join(EXPERIMENTS))
    ap.add_argument("--methods", default="all")
    ap.add_argument("--robot", default="realman_rm65_water2")
    ap.add_argument("--exp1-sets", type=int, default=2)
    ap.add_argument("--exp1-points", type=int, default=25)
    ap.add_argument("--exp2-sets", type=int, default=2)
    ap.add_argument("--exp3-sets", type=int, default=1)
    ap.add_argument("--exp3-per-set", type=int, default=2)
    ap.add_argument("--object-time-limit", type=float, default=None, help="per object (Exp-2/3; default the sequencer's)")
    ap.add_argument("--bootstrap-seed", type=int, default=mr.BOOTSTRAP_SEED)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--shard", default="1/1")
    ap.add_argument("--devel", default=os.path.join(mr.ROOT, "devel"))
    ap.add_argument("--resume", action="store_true",
                    help="keep the runs of an earlier, interrupted run into --out that finished (same command)")
    a = ap.parse_args(argv)
    if a.jobs < 1 or a.seed_count < 1:
        ap.error("--jobs and --seed-count must be >= 1")
    a.exe = os.path.join(a.devel, "lib", "ehc_bringup", "ehc_experiment")
    if not os.access(a.exe, os.X_OK):
        ap.error("%s not found: build first (make build)" % a.exe)
    return a


def main_run(argv):
    a = parse_run_args(argv)
    k, n = parse_shard(a.shard)
    if n > 1 and not a.seeds:
        raise SweepError("--shard %s needs --seeds (every shard must run the same seeds): "
                         "--seeds $(src/ehc_bringup/scripts/sweep.py seeds 10)" % a.shard)
    plan = make_plan(a, has_imprecision_flag(a.exe))
    jobs = plan_jobs(plan)
    mine = shard_jobs(plan, jobs, k, n)
    sys.stderr.write("[sweep] seeds %s (%s; rerun with --seeds %s); levels %s; bootstrap seed %d; %d jobs, shard %d/%d "
                     "runs %d\n" % (",".join(map(str, plan["seeds"])), ", ".join(sorted({mr.seed_role(s) for s in plan["seeds"]})),
                                    ",".join(map(str, plan["seeds"])), ",".join(level_text(v) for v in plan["levels"]),
                                    plan["bootstrap_seed"], len(jobs), k, n, len(mine)))
    for j in mine:
        j["out"] = os.path.join(a.out, j["id"])
        j["cmd"] = job_command(plan, a.exe, j, j["out"])
    t0 = time.time()
    run_all(mine, a.jobs, "sweep", lambda j: j["id"][len("runs/"):], resume=a.resume)
    versions = sorted({j["code_version"] for j in mine})
    manifest = {"plan": plan, "shard": [k, n], "command": " ".join([mr.rel(sys.argv[0])] + sys.argv[1:]),
                "code_version": " + ".join(versions), "machine": mr.machine(), "finished": mr.now(),
                "wall_s": round(time.time() - t0, 1),
                "jobs": [{"id": j["id"], "cpu_s": None if j["cpu_s"] is None else round(j["cpu_s"], 2),
                          "cmd": " ".join(j["cmd"])} for j in mine]}
    with open(os.path.join(a.out, manifest_name(k, n)), "w") as f:
        json.dump(manifest, f, indent=1)
        f.write("\n")
    cpu = sum(j["cpu_s"] or 0.0 for j in mine)
    if n > 1:
        sys.stderr.write("[sweep] shard %d/%d done: %.0f s CPU; when every shard is done: sweep.py merge --out DIR %s ...\n"
                         % (k, n, cpu, a.out))
        return 0
    report = write_report(a.out, plan, [manifest], {j["id"]: j["out"] for j in mine})
    sys.stderr.write("[sweep] %s/sweep.md (%.0f s CPU, %.0f s wall)\n" % (a.out, report["cpu_s"], manifest["wall_s"]))
    return 0


def load_manifests(dirs):
    """(plan, manifests, {job id: folder}) from the shard folders; the plans must agree and the
    shards cover every job of the plan once."""
    found = []
    for d in dirs:
        names = sorted(x for x in os.listdir(d) if x.startswith("shard-") and x.endswith(".json")) if os.path.isdir(d) else []
        if not names:
            raise SweepError("%s: no shard-K-of-N.json (not a sweep shard folder)" % d)
        found += [(d, mr.read_json(os.path.join(d, x)), x) for x in names]
    plan = found[0][1]["plan"]
    folders = {}
    for d, m, name in found:
        if m["plan"] != plan:
            raise SweepError("%s/%s: its plan differs from %s/%s's (seeds, levels, sizes or methods)"
                             % (d, name, found[0][0], found[0][2]))
        if m["code_version"] != found[0][1]["code_version"]:
            raise SweepError("%s/%s: code version %s, %s/%s: %s" % (d, name, m["code_version"], found[0][0],
                                                                   found[0][2], found[0][1]["code_version"]))
        for j in m["jobs"]:
            if j["id"] in folders:
                raise SweepError("job %s is in two shards (%s and %s)" % (j["id"], folders[j["id"]], d))
            folders[j["id"]] = os.path.join(d, j["id"])
    missing = [j["id"] for j in plan_jobs(plan) if j["id"] not in folders]
    if missing:
        raise SweepError("%d job(s) of the plan in no shard (a shard not run or not finished?), e.g. %s"
                         % (len(missing), missing[0]))
    return plan, [m for _, m, _ in found], folders


def main_merge(argv):
    ap = argparse.ArgumentParser(prog="sweep.py merge", description="the report from the shard folders")
    ap.add_argument("--out", required=True)
    ap.add_argument("dirs", nargs="+")
    a = ap.parse_args(argv)
    plan, manifests, folders = load_manifests(a.dirs)
    report = write_report(a.out, plan, manifests, folders)
    sys.stderr.write("[sweep] merged %d shard(s): %s/sweep.md (%.0f s CPU)\n" % (len(manifests), a.out, report["cpu_s"]))
    return 0


def main(argv):
    if len(argv) == 2 and argv[0] == "seeds":
        if not argv[1].isdigit() or int(argv[1]) < 1:
            sys.stderr.write("sweep.py seeds: N >= 1 expected, got '%s'\n" % argv[1])
            return 2
        print(",".join(str(s) for s in draw_seeds(int(argv[1]))))
        return 0
    commands = {"run": main_run, "merge": main_merge}
    if not argv or argv[0] not in commands:
        sys.stderr.write(__doc__)
        return 2
    try:
        return commands[argv[0]](argv[1:])
    except (SweepError, mr.ResultsError, RuntimeError, OSError, KeyError) as e:
        sys.stderr.write("sweep.py: error: %s\n" % e)
        return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
