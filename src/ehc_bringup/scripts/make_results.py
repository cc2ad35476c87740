#!/usr/bin/python3
"""docs/RESULTS.md from the result folders (`make results`; the end of `make experiments`).

  make_results.py [--results DIR] [--experiments DIR] [--bench DIR] [--demo DIR] [--sweep DIR]
                  [--everyday DIR] [--out FILE]
      Reads DIR/experiments/{exp1,exp2,exp3} (ehc_experiment reach / grasp / poses, written by
      experiments.sh), DIR/everyday/{tuning,validation}/seed_<N> (everyday.sh: Exp-2 on the object
      library), DIR/bench (bench.sh), DIR/demo (demo.sh) and DIR/sweep (sweep.py: the verdict of
      each paper claim), DIR = results/ by default, and writes FILE (docs/RESULTS.md). A folder
      that is not there is listed as "not run". The
      demo folder and every DIR/demo_<robot> (demo.sh with ROBOT=<name>) make one row each of
      the per-robot demo table.
      Every table comes with the command that made it, the code version, the machine, the date
      and the seeds (from the folder's meta.json) and the paper's figure beside ours. Means of
      per-set data come with a 95 % bootstrap interval over the sets (fixed bootstrap seed:
      the same folders give the same file). A malformed file is an error naming the file;
      nothing is written then. Exit code 0, or 2 on an error.

  make_results.py meta DIR --command CMD [--run NAME CMD]... [--seed S] [--robot R]
  make_results.py meta DIR --finish
      Writes DIR/meta.json at the start of a run (the command, the per-table commands, the seed,
      the robot, `git describe --always --dirty`, CPU model and cores, the start time) and adds
      the end time and wall time with --finish. Called by experiments.sh and bench.sh.
"""
import argparse
import csv
import datetime
import json
import math
import os
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))
BOOTSTRAP_SEED = 1
BOOTSTRAP_RESAMPLES = 2000

# The paper's figures (Tables II, III, IV): config/paper/figures.yaml, the one copy (the C++
# result writers print the same file's figures in table.md).
PAPER_FILE = os.path.join(ROOT, "config", "paper", "figures.yaml")


def load_paper_figures(path=PAPER_FILE):
    """{table2, table3, table4}: method -> {field: text} from the paper-figures file."""
    import yaml
    with open(path) as f:
        d = yaml.safe_load(f)
    return {k: {m: {f: str(v) for f, v in row.items()} for m, row in d[k].items()}
            for k in ("table2", "table3", "table4")}


_PAPER = load_paper_figures()
PAPER_TABLE2, PAPER_TABLE3, PAPER_TABLE4 = _PAPER["table2"], _PAPER["table3"], _PAPER["table4"]
APPROACHES = ("forward", "downward", "sideways")
# Design bars of the benchmarks (the paper reports no timings): bench name -> (field, op, bar, text).
BENCH_BARS = {
    "controller.step_obstacles_10": ("median_us", "<=", 10.0, "median <= 10 us"),
    "grasp_pipeline_exp2_set": ("cpu_real_time_factor", ">=", 10.0, ">= 10x real time per core"),
    "grasp_pipeline_exp3_set": ("cpu_real_time_factor", ">=", 10.0, ">= 10x real time per core"),
    "perception.obstacle_distances_2cm": ("median_us", "<=", 1000.0, "<= 1 ms per cycle"),
    "perception.tag_detect_pose_640x480": ("mean_us", "<=", 1e6 / 30.0, ">= 30 Hz"),
    "perception.grasps_object_20k": ("median_us", "<=", 100000.0, "<= 100 ms"),
    "perception.obstacle_node_rate_640x480": ("max_gap_ms", "<=", 100.0, "gaps <= 0.1 s"),
    "perception.obstacle_node_rate_1920x1080": ("max_gap_ms", "<=", 100.0, "gaps <= 0.1 s"),
    "perception.obstacle_cloud_2M": ("median_us", "<=", 20000.0, "<= 20 ms (one 50 Hz cycle)"),
    "perception.grasp_cloud_2M": ("median_us", "<=", 500000.0, "<= 0.5 s (one 2 Hz cycle)"),
    "perception.grasp_cloud_2M_blob": ("median_us", "<=", 500000.0, "<= 0.5 s (one 2 Hz cycle)"),
}


class ResultsError(Exception):
    """A result file that cannot be read; the message starts with the file's path."""


def rel(path):
    """`path` relative to the workspace root when inside it (stable text in the report)."""
    a = os.path.abspath(path)
    return os.path.relpath(a, ROOT) if a.startswith(ROOT + os.sep) else a


# ------------------------------------------------------------------------------ reading
def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except json.JSONDecodeError as e:
        raise ResultsError("%s: not valid JSON (line %d: %s)" % (rel(path), e.lineno, e.msg)) from None
    except OSError as e:
        raise ResultsError("%s: cannot read (%s)" % (rel(path), e.strerror)) from None


def read_csv(path, columns):
    """Rows of a CSV file as dicts; every column in `columns` must be in its header."""
    try:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            missing = [c for c in columns if c not in (reader.fieldnames or [])]
            if missing:
                raise ResultsError("%s: missing column(s) %s (header: %s)" % (
                    rel(path), ", ".join(missing), ",".join(reader.fieldnames or []) or "empty file"))
            rows = []
            for row in reader:
                if None in row or any(row[c] is None for c in columns):
                    raise ResultsError("%s: line %d has %s fields than the header" % (
                        rel(path), reader.line_num, "more" if None in row else "fewer"))
                row["_line"] = reader.line_num
                rows.append(row)
            return rows
    except OSError as e:
        raise ResultsError("%s: cannot read (%s)" % (rel(path), e.strerror)) from None


def number(row, key, path, kind=float):
    try:
        v = kind(row[key])
    except (TypeError, ValueError):
        raise ResultsError("%s: line %d: column '%s' is not a number ('%s')" % (
            rel(path), row["_line"], key, row[key])) from None
    if not math.isfinite(v):
        raise ResultsError("%s: line %d: column '%s' is not finite" % (rel(path), row["_line"], key))
    return v


def field(obj, keys, path):
    """obj[k1][k2]... with an error naming the file and the missing field."""
    cur = obj
    for i, k in enumerate(keys):
        if not isinstance(cur, dict) or k not in cur:
            raise ResultsError("%s: missing field '%s'" % (rel(path), ".".join(keys[: i + 1])))
        cur = cur[k]
    return cur


def read_meta(folder):
    """folder/meta.json (or None when the folder has none)."""
    path = os.path.join(folder, "meta.json")
    if not os.path.exists(path):
        return None
    meta = read_json(path)
    if not isinstance(meta, dict):
        raise ResultsError("%s: expected a JSON object" % rel(path))
    return meta


# ------------------------------------------------------------------------------ statistics
def resamples(n, seed=BOOTSTRAP_SEED):
    """BOOTSTRAP_RESAMPLES x n indices of n sets drawn with replacement (seeded: the same seed
    gives the same resamples, so paired statistics resample both series' sets together)."""
    import numpy as np
    return np.random.default_rng(seed).integers(0, n, size=(BOOTSTRAP_RESAMPLES, n))


def percentile_ci(stats):
    """The 95 % percentile interval of the finite bootstrap statistics (None when there are none)."""
    import numpy as np
    stats = stats[np.isfinite(stats)]
    if stats.size == 0:
        return None
    lo, hi = np.percentile(stats, [2.5, 97.5])
    return float(lo), float(hi)


def ratios(nums, dens, idx, scale):
    """sum(nums)/sum(dens) * scale of every resample in idx (NaN where the denominator is 0)."""
    import numpy as np
    d = dens[idx].sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(d > 0, nums[idx].sum(axis=1) / d * scale, np.nan)


def bootstrap(nums, dens, scale=1.0, seed=BOOTSTRAP_SEED):
    """Pooled ratio sum(nums)/sum(dens) * scale over the sets and its 95 % percentile interval
    from resampling the sets with replacement (None when there are fewer than two sets)."""
    import numpy as np
    nums = np.asarray(nums, dtype=float)
    dens = np.asarray(dens, dtype=float)
    point = float(nums.sum() / dens.sum() * scale) if dens.sum() > 0 else float("nan")
    if len(nums) < 2:
        return point, None
    return point, percentile_ci(ratios(nums, dens, resamples(len(nums), seed), scale))


def paired_bootstrap(a, b, scale=1.0, seed=BOOTSTRAP_SEED):
    """Two series measured on the same sets, a = (nums, dens) and b = (nums, dens) in the same set
    order: {"diff": (ratio_a - ratio_b, 95 % CI), "ratio": (ratio_a / ratio_b, 95 % CI)}, each
    ratio as in bootstrap(); the sets are resampled together (a paired interval)."""
    import numpy as np
    an, ad, bn, bd = (np.asarray(x, dtype=float) for x in (a[0], a[1], b[0], b[1]))
    if len(an) != len(bn):
        raise ValueError("paired_bootstrap: %d sets against %d" % (len(an), len(bn)))
    pa = an.sum() / ad.sum() * scale if ad.sum() > 0 else float("nan")
    pb = bn.sum() / bd.sum() * scale if bd.sum() > 0 else float("nan")
    ratio = pa / pb if pb != 0 and math.isfinite(pb) else float("nan")
    if len(an) < 2:
        return {"diff": (float(pa - pb), None), "ratio": (float(ratio), None)}
    idx = resamples(len(an), seed)
    ra, rb = ratios(an, ad, idx, scale), ratios(bn, bd, idx, scale)
    with np.errstate(invalid="ignore", divide="ignore"):
        rr = np.where(rb != 0, ra / rb, np.nan)
    return {"diff": (float(pa - pb), percentile_ci(ra - rb)), "ratio": (float(ratio), percentile_ci(rr))}


def per_set(rows, key_fn):
    """{set: (num, den)} summed with key_fn(row) -> (num, den)."""
    out = {}
    for r in rows:
        n, d = key_fn(r)
        a = out.setdefault(r["set"], [0.0, 0.0])
        a[0] += n
        a[1] += d
    return [tuple(out[k]) for k in sorted(out, key=lambda s: int(s) if s.isdigit() else s)]


def fmt_ci(point, ci, digits):
    if point is None or math.isnan(point):
        return "-"
    text = "%.*f" % (digits, point)
    return text + (" [%.*f, %.*f]" % (digits, ci[0], digits, ci[1]) if ci else "")


def fmt_speeds(s):
    return "%.3f/%.3f/%.3f" % (s["base_t"], s["base_r"], s["arm"])


# ------------------------------------------------------------------------------ metadata
def provenance(meta, run_key, folder, seeds_text):
    """The bullet list every table starts with."""
    if meta is None:
        missing = "not recorded (no meta.json in %s)" % rel(folder)
        lines = ["- command: " + missing, "- code version: " + missing, "- machine: " + missing,
                 "- date: " + missing]
    else:
        command = "`%s`" % meta.get("command", "?")
        run = meta.get("runs", {}).get(run_key) if run_key else None
        if run:
            command += ", which ran `%s`" % run
        machine = meta.get("machine", {})
        date = meta.get("started", "?")
        if meta.get("finished"):
            date += " to %s (%s s wall)" % (meta["finished"], meta.get("wall_s", "?"))
        else:
            date += " (no end recorded: the run did not finish)"
        lines = ["- command: " + command,
                 "- code version: `%s`" % meta.get("code_version", "?"),
                 "- machine: %s, %s core(s)" % (machine.get("cpu", "?"), machine.get("cores", "?")),
                 "- date: " + date]
        if meta.get("robot"):
            lines.append("- robot: " + meta["robot"])
    lines.append("- seeds: " + seeds_text)
    lines.append("- folder: `%s`" % rel(folder))
    return lines


# ------------------------------------------------------------------------------ Exp-1
def exp1_section(folder, meta):
    summary_path = os.path.join(folder, "summary.json")
    trials_path = os.path.join(folder, "trials.csv")
    summaries = read_json(summary_path)
    if isinstance(summaries, dict):
        summaries = [summaries]
    if not isinstance(summaries, list) or not summaries:
        raise ResultsError("%s: expected a method summary or a list of them" % rel(summary_path))
    rows = read_csv(trials_path, ["method", "set", "reached", "time_s"])
    seed = (meta or {}).get("seed") or "not recorded"
    seeds = ("--seed %s: targets of set k drawn with seed*1000 + k, Table I noise of set k seeded seed + k"
             % seed)
    out = ["## Exp-1: random reaching (paper Table II, simulation)", ""]
    out += provenance(meta, "exp1", folder, seeds)
    out += ["", "| Method | Time (s) [95 % CI] | paper Time (s) | Failed (/N) [95 % CI] | paper Failed (/500) "
            "| Distant (Base-T/Base-R/Arm) | paper Distant | Close (Base-T/Base-R/Arm) | paper Close |",
            "|---|---|---|---|---|---|---|---|---|"]
    causes = []
    for s in summaries:
        m = field(s, ["method"], summary_path)
        mine = [r for r in rows if r["method"] == m]
        for r in mine:
            r["_reached"] = number(r, "reached", trials_path, int)
            r["_time"] = number(r, "time_s", trials_path)
        targets = int(field(s, ["targets"], summary_path))
        failed = int(field(s, ["failed"], summary_path))
        if mine:
            t = bootstrap(*zip(*per_set(mine, lambda r: (r["_time"] * r["_reached"], r["_reached"]))))
            f = bootstrap(*zip(*per_set(mine, lambda r: (1 - r["_reached"], 1))), scale=len(mine))
        else:
            t, f = (float(field(s, ["mean_time_s"], summary_path)), None), (float(failed), None)
        p = PAPER_TABLE2.get(m, {})
        out.append("| %s | %s | %s | %s (/%d) | %s | %s | %s | %s | %s |" % (
            p.get("name", m), fmt_ci(t[0], t[1], 2), p.get("time", "-"), fmt_ci(f[0], f[1], 0), targets,
            p.get("failed", "-"), fmt_speeds(field(s, ["distant"], summary_path)), p.get("distant", "-"),
            fmt_speeds(field(s, ["close"], summary_path)), p.get("close", "-")))
        fc = s.get("failure_causes", {})
        causes.append("%s: %s" % (m, ", ".join("%s %s" % (k, v) for k, v in fc.items() if v) or "none"))
    out += ["", "Failure causes (not in the paper): " + "; ".join(causes) + "."]
    return out


# ------------------------------------------------------------------------------ Exp-2 and Exp-3
def grasp_rows(folder):
    path = os.path.join(folder, "trials.csv")
    rows = read_csv(path, ["method", "set", "index", "seed", "object", "approach", "success", "time_s", "tfm"])
    for r in rows:
        r["_success"] = number(r, "success", path, int)
        r["_time"] = number(r, "time_s", path)
        r["_tfm"] = number(r, "tfm", path)
        number(r, "seed", path, int)
    return rows


def grasp_summary(folder):
    path = os.path.join(folder, "summary.json")
    s = read_json(path)
    methods = field(s, ["methods"], path)
    if not isinstance(methods, list):
        raise ResultsError("%s: field 'methods' is not a list" % rel(path))
    return s, methods, path


def run_seeds(summary, rows, rule):
    seeds = sorted({int(r["seed"]) for r in rows})
    listed = ", ".join(str(x) for x in seeds[:6]) + (", ..." if len(seeds) > 6 else "")
    return "--seed %s: run seed = %s (%d run seed%s: %s)" % (
        summary.get("seed", "?"), rule, len(seeds), "" if len(seeds) == 1 else "s", listed)


def success_and_time(rows):
    ok = bootstrap(*zip(*per_set(rows, lambda r: (r["_success"], 1))), scale=100.0)
    t = bootstrap(*zip(*per_set(rows, lambda r: (r["_time"] * r["_success"], r["_success"]))))
    return ok, t


def safety_text(methods, path):
    parts = []
    for s in methods:
        margin = s.get("min_obstacle_margin", {}) or {}
        m = margin.get("margin")
        parts.append("%s: %s sim steps in contact, %s joint-limit violations, min margin d - d_s %s" % (
            field(s, ["method"], path), s.get("contact_steps", "?"), s.get("joint_limit_violations", "?"),
            "%.1f mm" % (round(1000.0 * m, 1) + 0.0) if isinstance(m, (int, float)) else "n/a"))
    return "Safety (not in the paper; contacts and violations must be zero): " + "; ".join(parts) + "."


def method_rows(rows, method, folder, path):
    """The trials.csv rows of `method`; an error naming both files when there are none."""
    mine = [r for r in rows if r["method"] == method]
    if not mine:
        raise ResultsError("%s: no trials of method '%s' listed in %s" % (
            rel(os.path.join(folder, "trials.csv")), method, rel(path)))
    return mine


def exp2_section(folder, meta):
    summary, methods, path = grasp_summary(folder)
    rows = grasp_rows(folder)
    out = ["## Exp-2: grasping three objects in sequence (paper Table III, real robot)", ""]
    out += provenance(meta, "exp2", folder, run_seeds(summary, rows, "seed*1000 + set*10"))
    out += ["", "| Method | Time (s) [95 % CI] | paper Time (s) | Success (%) [95 % CI] | paper Success (%) "
            "| Distant (Base-T/Base-R/Arm) | paper Distant | Close (Base-T/Base-R/Arm) | paper Close |",
            "|---|---|---|---|---|---|---|---|---|"]
    for s in methods:
        m = field(s, ["method"], path)
        mine = method_rows(rows, m, folder, path)
        ok, t = success_and_time(mine)
        p = PAPER_TABLE3.get(m, {})
        n_ok = sum(r["_success"] for r in mine)
        out.append("| %s | %s | %s | %s (%d/%d) | %s | %s | %s | %s | %s |" % (
            p.get("name", m), fmt_ci(t[0], t[1], 2), p.get("time", "-"), fmt_ci(ok[0], ok[1], 1), n_ok, len(mine),
            p.get("success", "-"), fmt_speeds(field(s, ["distant"], path)), p.get("distant", "-"),
            fmt_speeds(field(s, ["close"], path)), p.get("close", "-")))
    out += ["", safety_text(methods, path)]
    return out


def exp3_section(folder, meta):
    summary, methods, path = grasp_summary(folder)
    rows = grasp_rows(folder)
    out = ["## Exp-3: grasp orientations, TfM (paper Table IV, real robot)", ""]
    out += provenance(meta, "exp3", folder, run_seeds(summary, rows, "seed*1000 + set*10 + index"))
    head = "| Method |"
    for a in APPROACHES:
        head += " TfM %s (%%) [95 %% CI] | paper %s |" % (a, a)
    out += ["", head + " Success (%) [95 % CI] | paper Success (%) |", "|---" * (2 * len(APPROACHES) + 3) + "|"]
    for s in methods:
        m = field(s, ["method"], path)
        mine = method_rows(rows, m, folder, path)
        p = PAPER_TABLE4.get(m, {})
        line = "| %s |" % p.get("name", m)
        for a in APPROACHES:
            sub = [r for r in mine if r["approach"] == a]
            tfm = bootstrap(*zip(*per_set(sub, lambda r: (r["_tfm"], 1))), scale=100.0) if sub else (None, None)
            line += " %s | %s |" % (fmt_ci(tfm[0], tfm[1], 1), p.get(a, "-"))
        ok, _ = success_and_time(mine)
        n_ok = sum(r["_success"] for r in mine)
        line += " %s (%d/%d) | not reported |" % (fmt_ci(ok[0], ok[1], 1), n_ok, len(mine))
        out.append(line)
    out += ["", "TfM: the share of the time at a distance with the object in the camera's view.",
            "", safety_text(methods, path)]
    return out


# ------------------------------------------------------------------------------ bench, demo
def read_bench_lines(path):
    records = []
    try:
        with open(path) as f:
            lines = f.readlines()
    except OSError as e:
        raise ResultsError("%s: cannot read (%s)" % (rel(path), e.strerror)) from None
    for i, line in enumerate(lines, 1):
        if not line.startswith("{"):
            continue  # a launcher's text line
        try:
            r = json.loads(line)
        except json.JSONDecodeError as e:
            raise ResultsError("%s: line %d is not valid JSON (%s)" % (rel(path), i, e.msg)) from None
        if not isinstance(r, dict) or "bench" not in r:
            raise ResultsError("%s: line %d has no \"bench\" field" % (rel(path), i))
        records.append(r)
    return records


def fmt_us(v):
    """A duration given in microseconds, in us below 1 ms, else in ms."""
    if not isinstance(v, (int, float)):
        return "?"
    return "%.2f us" % v if v < 10 else "%.1f us" % v if v < 1000 else "%.1f ms" % (v / 1000.0)


def bench_figure(r):
    if "median_us" in r:
        runs = r.get("run_medians_us")
        of_runs = "; the lowest of %d runs' medians: %s" % (len(runs), ", ".join(fmt_us(v) for v in runs)) \
            if isinstance(runs, list) and len(runs) > 1 else ""
        return "median %s, p99 %s (n %s%s)" % (fmt_us(r["median_us"]), fmt_us(r.get("p99_us")), r.get("n", "?"),
                                              of_runs)
    if "cpu_real_time_factor" in r:
        return "%.2fx real time per core (wall %.2fx), %s/%s grasped" % (
            r["cpu_real_time_factor"], r.get("wall_real_time_factor", float("nan")), r.get("successes", "?"),
            r.get("grasps", "?"))
    if "rate_hz" in r:
        return "%.1f Hz" % r["rate_hz"]
    if "found" in r:
        return "%s of %s found" % (r["found"], r.get("expected", "?"))
    if "mean" in r:
        return "mean %s" % r["mean"]
    return ", ".join("%s %s" % (k, v) for k, v in r.items() if k != "bench")


def bench_bar(r):
    if "bar_hz" in r:
        return ">= %s Hz" % r["bar_hz"], ("yes" if r.get("meets_bar") else "no")
    bar = BENCH_BARS.get(r["bench"])
    if not bar or bar[0] not in r:
        return "-", "-"
    key, op, limit, text = bar
    ok = r[key] <= limit if op == "<=" else r[key] >= limit
    return text, "yes" if ok else "no"


def bench_section(folder, meta):
    path = os.path.join(folder, "bench.jsonl")
    records = read_bench_lines(path)
    out = ["## Benchmarks (`make bench`; design bars, the paper reports no timings)", ""]
    out += provenance(meta, None, folder, "none (fixed inputs)")
    out += ["", "| Benchmark | ours | design bar | meets bar | paper |", "|---|---|---|---|---|"]
    for r in records:
        bar, ok = bench_bar(r)
        out.append("| %s | %s | %s | %s | not reported |" % (r["bench"], bench_figure(r), bar, ok))
    if not records:
        out.append("| (no JSON lines in %s) | - | - | - | - |" % rel(path))
    return out


def demo_section(folder, meta):
    path = os.path.join(folder, "summary.json")
    s = read_json(path)
    objects = field(s, ["objects"], path)
    if not isinstance(objects, list):
        raise ResultsError("%s: field 'objects' is not a list" % rel(path))
    out = ["## Demo (`make demo`: the ROS nodes on the Exp-2 table, one run)", ""]
    out += provenance(meta, None, folder, "SEED %s (simulator noise)" % (meta or {}).get("seed", "not recorded"))
    out += ["", "| Object | Success | Time (s) | TfM (%) | paper (Table III, EHC) |", "|---|---|---|---|---|"]
    for o in objects:
        out.append("| %s | %s | %.2f | %.1f | 13.54 s mean, 95.6 %% success |" % (
            field(o, ["name"], path), "yes" if field(o, ["success"], path) else "no", float(field(o, ["time_s"], path)),
            100.0 * float(field(o, ["tfm"], path))))
    mpbs = {True: "on", False: "off"}.get(s.get("mpbs"), "n/a")
    out += ["", "%s/%s grasped, mode %s, MPBS %s." % (
        s.get("successes", "?"), s.get("objects_total", "?"), s.get("mode", "?"), mpbs)]
    return out


def demo_folders(args):
    """Every demo run: the demo folder and the results' demo_<robot> folders (`make demo
    ROBOT=<name>` writes there), each with a summary.json."""
    folders = [args.demo or os.path.join(args.results, "demo")]
    if os.path.isdir(args.results):
        folders += [os.path.join(args.results, n) for n in sorted(os.listdir(args.results)) if n.startswith("demo_")]
    return [f for f in folders if os.path.isfile(os.path.join(f, "summary.json"))]


def robots_section(folders):
    """One row per demo run, i.e. per robot: what `make demo ROBOT=<name>` grasped."""
    out = ["## Demo on every robot (`make demo ROBOT=<name>`, one run each)", "",
           "| Robot | Grasped | Time per object (s) | TfM (%) | Mode | Seed | Code version | Folder |",
           "|---|---|---|---|---|---|---|---|"]
    for folder in folders:
        path = os.path.join(folder, "summary.json")
        s = read_json(path)
        objects = field(s, ["objects"], path)
        if not isinstance(objects, list):
            raise ResultsError("%s: field 'objects' is not a list" % rel(path))
        meta = read_meta(folder) or {}
        times = ", ".join("%.2f" % float(field(o, ["time_s"], path)) for o in objects)
        tfm = ", ".join("%.1f" % (100.0 * float(field(o, ["tfm"], path))) for o in objects)
        out.append("| %s | %s/%s | %s | %s | %s | %s | `%s` | `%s` |" % (
            meta.get("robot") or "the configs' default", sum(1 for o in objects if field(o, ["success"], path)),
            len(objects), times, tfm, s.get("mode", "?"), meta.get("seed", "not recorded"),
            meta.get("code_version", "not recorded"), rel(folder)))
    return out


# ------------------------------------------------------------------------------ verdicts (sweep)
# The rule: our 95 % CI against the paper's figure, "inside" (the figure is in the interval),
# "better" (the interval lies wholly on the better side: lower time or failures, higher success
# or TfM) or "worse". The paper claims EHC's advantage, so for a figure of EHC (with MPBS) or a
# difference / ratio EHC against its baseline, inside and better reproduce the claim; a
# baseline's own figure must be matched (inside only: a baseline that does better than the paper
# says weakens the claim). Across the sweep's imprecision levels: reproduced at every level, at
# none, or at the levels named (the stated condition). A cell without an interval (fewer than two
# sets) is judged on its mean.
RULE_TEXT = ("Rule: at each level, where our 95 % CI lies from the paper's figure: inside, better (wholly on the "
             "better side: lower time and failures, higher success and TfM) or worse. A figure of EHC (with MPBS) or "
             "an EHC-against-baseline difference or ratio is reproduced when inside or better (the paper claims EHC's "
             "advantage); a baseline's own figure only when inside (a baseline better than the paper's weakens the "
             "claim). Over the levels: reproduced at every level, at none, or at the levels named (the condition).")
TUNING_SEEDS_BELOW = 1000  # seeds below are tuning seeds, the others reporting seeds (sweep.py draws these)


def seed_role(seed):
    return "tuning" if seed < TUNING_SEEDS_BELOW else "reporting"


def verdict(paper, point, ci, better):
    """'inside', 'better' or 'worse': where our interval (or the mean alone) lies from the paper's figure;
    'no data' without a mean (e.g. a time when nothing was reached)."""
    if ci is None and (point is None or not math.isfinite(point)):
        return "no data"
    lo, hi = ci if ci else (point, point)
    if lo <= paper <= hi:
        return "inside"
    if better == "lower":
        return "better" if hi < paper else "worse"
    return "better" if lo > paper else "worse"


def combined_verdict(per_level, one_sided):
    """[(level text, verdict)] -> the claim's verdict over the levels; one_sided: 'better' reproduces too."""
    ok = [lv for lv, v in per_level if v == "inside" or (one_sided and v == "better")]
    if all(v == "no data" for _, v in per_level):
        return "not measured"
    if len(ok) == len(per_level):
        return "reproduced"
    if not ok:
        return "not reproduced"
    return "reproduced at imprecision level %s only" % ", ".join(ok)


def paper_number(text):
    try:
        v = float(text)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


# The methods held against NEO(e) on the paper's EHC claims: the paper's EHC, and ehc_place (EHC whose base
# goal comes from its reachability map; not a paper method, judged by the same claim).
PAIRED_METHODS = (("ehc", "EHC"), ("ehc_place", "EHC-place"))


def sweep_claims(sweep):
    """(claim text, paper figure, [(level, mean, ci)], better, one-sided) of every paper claim the sweep
    measured; one-sided: EHC's (with MPBS) own figures and the EHC-against-baseline comparisons."""
    cells, paired = sweep["cells"], sweep["paired"]
    claims = []

    def cell_claim(text, paper, exp, method, metric):
        mine = [c for c in cells if c["experiment"] == exp and c["method"] == method and c["metric"] == metric]
        if mine and paper is not None:
            claims.append((text, paper, [(c["level"], c["mean"], c["ci95"]) for c in mine], mine[0]["better"],
                           method == "ehc"))

    def pair_claim(text, paper, exp, metric, key, method="ehc"):
        mine = [p for p in paired if p["experiment"] == exp and p["metric"] == metric and p.get("a", "ehc") == method]
        if mine and paper is not None:
            claims.append((text, paper, [(p["level"], p[key], p[key + "_ci95"]) for p in mine], mine[0]["better"], True))

    t2, t3 = PAPER_TABLE2, PAPER_TABLE3
    for exp, proto in (("exp1_sequence", "back to back"), ("exp1_reset", "from the ready pose")):
        for m, p in t2.items():
            cell_claim("Table II %s time (s), %s" % (p["name"], proto), paper_number(p["time"]), exp, m, "time_s")
            cell_claim("Table II %s failures /500, %s" % (p["name"], proto), paper_number(p["failed"]), exp, m,
                       "failures_per_500")
        for m, name in PAIRED_METHODS:
            pair_claim("Table II %s / NEO(e) time, %s" % (name, proto),
                       paper_number(t2["ehc"]["time"]) / paper_number(t2["neo_e"]["time"]), exp, "time_s", "ratio", m)
            pair_claim("Table II %s - NEO(e) failures /500, %s" % (name, proto),
                       paper_number(t2["ehc"]["failed"]) - paper_number(t2["neo_e"]["failed"]), exp,
                       "failures_per_500", "diff", m)
    for m, p in t3.items():
        cell_claim("Table III %s success (%%)" % p["name"], paper_number(p["success"]), "exp2", m, "success_pct")
        cell_claim("Table III %s time (s)" % p["name"], paper_number(p["time"]), "exp2", m, "time_s")
    for m, name in PAIRED_METHODS:
        pair_claim("Table III %s - NEO(e) success (points)" % name,
                   paper_number(t3["ehc"]["success"]) - paper_number(t3["neo_e"]["success"]), "exp2", "success_pct",
                   "diff", m)
    for m, p in PAPER_TABLE4.items():
        for a in APPROACHES:
            cell_claim("Table IV %s TfM %s (%%)" % (p["name"], a), paper_number(p[a]), "exp3", m, "tfm_%s_pct" % a)
    return claims


def seeds_text(sweep):
    seeds = [s["seed"] for s in sweep["seeds"]]
    tuning = [s for s in seeds if seed_role(s) == "tuning"]
    text = ("%d seed(s): %s. Tuning seeds are those below %d (the development runs' fixed seeds: `make experiments` "
            "SEED=1, the test fixtures' 7, ...); reporting seeds, %d and above, are drawn fresh by "
            "`sweep.py seeds N` and never tuned on. " % (len(seeds), ", ".join(map(str, seeds)), TUNING_SEEDS_BELOW,
                                                        TUNING_SEEDS_BELOW))
    if tuning:
        return text + "**This sweep includes tuning seed(s) %s: its verdicts are not a report.**" % (
            ", ".join(map(str, tuning)))
    return text + "These verdicts rest on reporting seeds only."


def verdict_section(folder, meta):
    path = os.path.join(folder, "sweep.json")
    sweep = read_json(path)
    for k in ("plan", "cells", "paired", "seeds", "rerun"):
        field(sweep, [k], path)
    command = "`%s && make results` (DIR = `%s`)" % (sweep["rerun"], rel(folder))
    out = ["## Verdicts: the paper's claims against the sweep", "",
           "- command: " + command, "- code version: `%s`" % sweep.get("code_version", "?"),
           "- machine: %s" % sweep.get("machine", "?"), "- seeds: " + seeds_text(sweep),
           "- bootstrap: %s resamples over the sets (seed x set), bootstrap seed %s" % (
               sweep.get("bootstrap_resamples", "?"), sweep.get("bootstrap_seed", "?")),
           "- folder: `%s`" % rel(folder), "",
           RULE_TEXT + " Tables III and IV are the paper's real robot, ours the simulation.", "",
           "| Claim | paper | ours per level: mean [95 % CI] (where the figure lies) | verdict |", "|---|---|---|---|"]
    for text, paper, per_level, better, one_sided in sweep_claims(sweep):
        judged = [(("%g" % lv), verdict(paper, mean, ci, better)) for lv, mean, ci in per_level]
        ours = "; ".join("L%g: %s (%s)" % (lv, fmt_ci(mean, ci, 2), v) for (lv, mean, ci), (_, v) in zip(per_level, judged))
        out.append("| %s | %s | %s | %s |" % (text, "%g" % round(paper, 3), ours, combined_verdict(judged, one_sided)))
    return out


# ------------------------------------------------------------------------------ everyday objects
EVERYDAY_BAR = 90.0  # % of the objects with a valid grasp in view, grasped and lifted (validation half)
EVERYDAY_HALVES = ("tuning", "validation")


def everyday_rows(folder, half):
    """The trials.csv rows of every seed_<N> run of one half; the set key made unique per run."""
    runs = sorted(d for d in os.listdir(os.path.join(folder, half)) if d.startswith("seed_"))
    rows, seeds = [], []
    for d in runs:
        path = os.path.join(folder, half, d, "trials.csv")
        mine = read_csv(path, ["method", "set", "object", "success", "valid_exists", "attempted", "cause",
                               "failed_phase", "stall_cause", "stall_link", "stall_body"])
        for r in mine:
            for k in ("success", "valid_exists", "attempted"):
                r["_" + k] = number(r, k, path, int)
            # Where a valid grasp exists, whether one the robot reaches does (empty: not judged,
            # None: a run written before the column).
            reach = r.get("valid_reachable_exists")
            r["_reachable"] = int(reach) if reach in ("0", "1") else None
            r["set"] = "%s/%s" % (d, r["set"])
        seeds.append(d[len("seed_"):])
        rows += mine
    return rows, seeds


def everyday_miss(r):
    """A miss's class: the cause, the stall's link and body, the phase."""
    text = r["cause"] or "?"
    if r["stall_cause"]:
        body = r["stall_body"] + (" (the target)" if r["stall_body"] == r["object"] else "")
        text += " (%s%s)" % (r["stall_cause"], ": %s at %s" % (r["stall_link"], body) if r["stall_link"] else "")
    return text + (" in " + r["failed_phase"] if r["failed_phase"] else "")


def everyday_reachable(rows):
    """Grasped and lifted among the objects where a valid grasp the robot reaches was in view
    (ehc_experiment's valid_reachable_exists): mean [95 % CI] (n/N); "-" when not judged."""
    judged = [r for r in rows if r["_valid_exists"] and r["_reachable"] is not None]
    if not judged or any(r["_valid_exists"] and r["_reachable"] is None for r in rows):
        return "-"
    reach = [r for r in judged if r["_reachable"]]
    if not reach:
        return "- (0/0)"
    ok = bootstrap(*zip(*per_set(judged, lambda r: (r["_success"] * r["_reachable"], r["_reachable"]))), scale=100.0)
    return "%s (%d/%d)" % (fmt_ci(ok[0], ok[1], 1), sum(r["_success"] for r in reach), len(reach))


def everyday_section(folder, meta):
    out = ["## Everyday objects: Exp-2 on the object library (bar: %g %% on the validation half)" % EVERYDAY_BAR, ""]
    halves = [h for h in EVERYDAY_HALVES if os.path.isdir(os.path.join(folder, h))]
    if not halves:
        raise ResultsError("%s: neither a tuning nor a validation folder" % rel(folder))
    data = {h: everyday_rows(folder, h) for h in halves}
    seeds = "; ".join("%s half: %s" % (h, ", ".join(data[h][1]) or "none") for h in halves)
    out += provenance(meta, "everyday", folder, seeds + " (run seed = seed*1000 + set*10; the tuning half and the "
                      "seeds used while developing are for tuning, the validation half's seeds are drawn fresh)")
    out += ["", "| Half | Method | Sets | Objects | Valid grasp in view | Grasped and lifted where one exists (%) [95 % CI] "
            "| ... where one the robot reaches exists (%) [95 % CI] | Grasps attempted where none exists | bar (validation) |",
            "|---|---|---|---|---|---|---|---|---|"]
    misses = {}
    for h in halves:
        rows = data[h][0]
        for m in sorted({r["method"] for r in rows}):
            mine = [r for r in rows if r["method"] == m]
            valid = [r for r in mine if r["_valid_exists"]]
            ok = bootstrap(*zip(*per_set(mine, lambda r: (r["_success"] * r["_valid_exists"], r["_valid_exists"]))),
                           scale=100.0) if valid else (None, None)
            n_ok = sum(r["_success"] for r in valid)
            reach = everyday_reachable(mine)
            none = sum(1 for r in mine if not r["_valid_exists"] and r["_attempted"])
            bar = "-" if h != "validation" else ("met" if ok[1] and ok[1][0] >= EVERYDAY_BAR else
                                                 "met by the mean only" if ok[0] is not None and ok[0] >= EVERYDAY_BAR
                                                 else "not met")
            out.append("| %s | %s | %d | %d | %d | %s (%d/%d) | %s | %d | %s |" % (
                h, m, len({r["set"] for r in mine}), len(mine), len(valid), fmt_ci(ok[0], ok[1], 1), n_ok, len(valid),
                reach, none, bar))
            for r in valid:
                if not r["_success"]:
                    misses.setdefault((h, m), {}).setdefault(everyday_miss(r), 0)
                    misses[(h, m)][everyday_miss(r)] += 1
    for (h, m), counts in sorted(misses.items()):
        text = "; ".join("%s: %d" % (k, n) for k, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])))
        out += ["", "Misses where a valid grasp was in view, %s half, %s: %s." % (h, m, text)]
    return out


# ------------------------------------------------------------------------------ report
def sources(args):
    exp = args.experiments or os.path.join(args.results, "experiments")
    return [
        ("Verdicts", args.sweep or os.path.join(args.results, "sweep"), None, verdict_section, "make sweep"),
        ("Exp-1", os.path.join(exp, "exp1"), exp, exp1_section, "make experiments"),
        ("Exp-2", os.path.join(exp, "exp2"), exp, exp2_section, "make experiments"),
        ("Exp-3", os.path.join(exp, "exp3"), exp, exp3_section, "make experiments"),
        ("Everyday objects", args.everyday or os.path.join(args.results, "everyday"), None, everyday_section,
         "make everyday"),
        ("Benchmarks", args.bench or os.path.join(args.results, "bench"), None, bench_section, "make bench"),
        ("Demo", args.demo or os.path.join(args.results, "demo"), None, demo_section, "make demo"),
    ]


def build_report(args):
    header = ["# EHC-MM results", "",
              "Generated by `make results` (src/ehc_bringup/scripts/make_results.py) from the result folders; "
              "do not edit by hand. Our figures come from the simulator; the paper's Table II is its simulation, "
              "Tables III and IV its real robot. Mean [95 %% CI]: percentile bootstrap over the sets "
              "(%d resamples, seed %d)." % (BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED), "",
              "| Results | folder | status |", "|---|---|---|"]
    body = []
    for name, folder, meta_folder, section, command in sources(args):
        if not os.path.isdir(folder):
            header.append("| %s | `%s` | not run (`%s`) |" % (name, rel(folder), command))
            continue
        meta = read_meta(meta_folder or folder)
        header.append("| %s | `%s` | below |" % (name, rel(folder)))
        body += [""] + section(folder, meta)
    demos = demo_folders(args)
    if demos:
        header.append("| Demo on every robot | %s | below |" % ", ".join("`%s`" % rel(f) for f in demos))
        body += [""] + robots_section(demos)
    return "\n".join(header + body) + "\n"


def main_report(argv):
    ap = argparse.ArgumentParser(description="docs/RESULTS.md from the result folders")
    ap.add_argument("--results", default=os.path.join(ROOT, "results"), help="root of the result folders [results]")
    ap.add_argument("--experiments", help="the experiments folder [RESULTS/experiments]")
    ap.add_argument("--bench", help="the bench folder [RESULTS/bench]")
    ap.add_argument("--demo", help="the demo folder [RESULTS/demo]")
    ap.add_argument("--sweep", help="the sweep folder, for the verdicts [RESULTS/sweep]")
    ap.add_argument("--everyday", help="the everyday objects folder [RESULTS/everyday]")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "RESULTS.md"), help="report file [docs/RESULTS.md]")
    args = ap.parse_args(argv)
    try:
        text = build_report(args)
    except ResultsError as e:
        print("make_results.py: error: %s" % e, file=sys.stderr)
        return 2
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w") as f:
        f.write(text)
    print("make_results.py: %s" % rel(args.out), file=sys.stderr)
    return 0


# ------------------------------------------------------------------------------ meta.json
def code_version():
    try:
        r = subprocess.run(["git", "-C", ROOT, "describe", "--always", "--dirty"], capture_output=True, text=True,
                           check=False)
    except OSError:
        return "unknown (git not found)"
    return r.stdout.strip() if r.returncode == 0 and r.stdout.strip() else "unknown (not a git checkout)"


def machine():
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = " ".join(line.split(":", 1)[1].split())
                    break
    except OSError:
        pass
    return {"cpu": cpu, "cores": len(os.sched_getaffinity(0))}  # as nproc: the cores this run may use


def now():
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")


def main_meta(argv):
    ap = argparse.ArgumentParser(prog="make_results.py meta", description="writes DIR/meta.json")
    ap.add_argument("dir")
    ap.add_argument("--command", help="the command line of the run")
    ap.add_argument("--run", nargs=2, action="append", default=[], metavar=("NAME", "CMD"),
                    help="the command that made the result folder NAME")
    ap.add_argument("--seed")
    ap.add_argument("--robot")
    ap.add_argument("--finish", action="store_true", help="add the end time to an existing meta.json")
    a = ap.parse_args(argv)
    path = os.path.join(a.dir, "meta.json")
    if a.finish:
        try:
            meta = read_json(path)
        except ResultsError as e:
            print("make_results.py meta: %s" % e, file=sys.stderr)
            return 2
        meta["finished"] = now()
        start = meta.get("started_epoch")
        if isinstance(start, (int, float)):
            meta["wall_s"] = round(datetime.datetime.now().timestamp() - start)
    else:
        if not a.command:
            ap.error("--command is required (or --finish)")
        meta = {"command": a.command, "runs": dict(a.run), "seed": a.seed, "robot": a.robot,
                "code_version": code_version(), "machine": machine(), "started": now(),
                "started_epoch": round(datetime.datetime.now().timestamp())}
    os.makedirs(a.dir, exist_ok=True)
    with open(path, "w") as f:
        json.dump(meta, f, indent=1)
        f.write("\n")
    return 0


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "meta":
        sys.exit(main_meta(sys.argv[2:]))
    sys.exit(main_report(sys.argv[1:]))
