#!/usr/bin/python3
"""sweep.py (`make sweep`) in a reduced form: one robot, Exp-1 (both protocols) and Exp-2, NEO(e)
and EHC, level 0, two fresh seeds (printed: a failure reproduces with them), one set per seed.
The same plan runs once unsharded and once as two concurrent shards into one folder, merged: the reports
agree field by field (every cell, paired difference, CSV row and job's trials). Also: the bad
cases are errors that say why (a shard missing from a merge, sharding without --seeds, levels
above 0 without ehc_experiment's --base-imprecision).

  /usr/bin/python3 -m pytest src/ehc_bringup/test/test_sweep.py
"""
import csv
import importlib.util
import json
import os
import shutil
import subprocess
import sys

import pytest

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))
SCRIPT = os.path.join(ROOT, "src", "ehc_bringup", "scripts", "sweep.py")
EXE = os.path.join(ROOT, "devel", "lib", "ehc_bringup", "ehc_experiment")
sys.path.insert(0, os.path.dirname(SCRIPT))
_spec = importlib.util.spec_from_file_location("sweep", SCRIPT)
sweep = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sweep)

SMALL = ["--levels", "0", "--experiments", "exp1_sequence,exp1_reset,exp2", "--methods", "neo_e,ehc",
         "--exp1-sets", "1", "--exp1-points", "2", "--exp2-sets", "1", "--object-time-limit", "8"]


def same(x, y):
    """Field by field, a NaN (e.g. a ratio to zero failures) equal to a NaN."""
    return json.dumps(x, sort_keys=True) == json.dumps(y, sort_keys=True)


def run(*args):
    r = subprocess.run([sys.executable, SCRIPT] + list(args), capture_output=True, text=True, check=False)
    return r.returncode, r.stdout + r.stderr


@pytest.fixture(scope="module")
def sweeps(tmp_path_factory):
    """(one run's folder, the merged shards' folder, the seeds)."""
    seeds = sweep.draw_seeds(2)
    print("sweep seeds %s" % ",".join(map(str, seeds)))
    base = tmp_path_factory.mktemp("sweep")
    one, shards = base / "one", base / "shards"
    plan = ["--seeds", ",".join(map(str, seeds))] + SMALL
    code, log = run("run", "--out", str(one), "--jobs", "2", *plan)
    assert code == 0, log
    assert "seeds %s" % ",".join(map(str, seeds)) in log and "bootstrap seed 1" in log and "ETA" in log
    # both shards at once into one folder, as GNU parallel runs them
    procs = [subprocess.Popen([sys.executable, SCRIPT, "run", "--out", str(shards), "--jobs", "1", "--shard", "%d/2" % k]
                              + plan, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) for k in (1, 2)]
    for p in procs:
        log = p.communicate()[0]
        assert p.returncode == 0, log
    code, log = run("merge", "--out", str(shards), str(shards))
    assert code == 0, log
    return one, shards, seeds


def test_merged_shards_give_the_same_report_as_one_run(sweeps):
    one, shards, seeds = sweeps
    a, b = (json.load(open(d / "sweep.json")) for d in (one, shards))
    for key in ("plan", "rerun", "seeds", "bootstrap_seed", "bootstrap_resamples", "code_version"):
        assert a[key] == b[key], key
    assert len(a["cells"]) == len(b["cells"]) == 2 * (2 * 2 + 2)  # methods x (Exp-1 2 protocols x 2 metrics + Exp-2 2)
    for ca, cb in zip(a["cells"], b["cells"]):
        assert same(ca, cb), (ca, cb)
    assert len(a["paired"]) == 2 * 2 + 2
    for pa, pb in zip(a["paired"], b["paired"]):
        assert same(pa, pb), (pa, pb)
    for name in ("sweep.csv", "paired.csv"):
        assert (one / name).read_text() == (shards / name).read_text(), name
    # every job's trials, and the shards split the jobs between them
    jobs = sweep.plan_jobs(a["plan"])
    assert len(jobs) == 3 * 2 * 2
    m1, m2 = (json.load(open(shards / ("shard-%d-of-2.json" % k))) for k in (1, 2))
    assert sorted(j["id"] for j in m1["jobs"] + m2["jobs"]) == sorted(j["id"] for j in jobs)
    cost = {j["id"]: sweep.job_cost(a["plan"], j) for j in jobs}
    loads = [sum(cost[j["id"]] for j in m["jobs"]) for m in (m1, m2)]
    assert abs(loads[0] - loads[1]) <= max(cost.values())  # balanced to within one job
    for j in jobs:
        assert (one / j["id"] / "trials.csv").read_text() == (shards / j["id"] / "trials.csv").read_text(), j["id"]
    assert [s["seed"] for s in a["seeds"]] == seeds and all(s["role"] == "reporting" for s in a["seeds"])
    for exp in a["plan"]["experiments"]:
        assert (one / (exp + ".png")).stat().st_size > 0


def test_the_statistics_are_those_of_the_trials(sweeps):
    one, _, seeds = sweeps
    report = json.load(open(one / "sweep.json"))
    cells = {(c["experiment"], c["method"], c["metric"]): c for c in report["cells"]}
    for exp in ("exp1_sequence", "exp1_reset"):
        for m in ("neo_e", "ehc"):
            rows = []
            for s in seeds:
                with open(one / sweep.job_id(exp, 0.0, s, m) / "trials.csv") as f:
                    rows += [r for r in csv.DictReader(f) if r["method"] == m]
            failed = sum(1 - int(r["reached"]) for r in rows)
            c = cells[(exp, m, "failures_per_500")]
            assert c["sets"] == 2 and c["trials"] == len(rows) == 4
            assert c["mean"] == pytest.approx(500.0 * failed / len(rows))
            assert c["ci95"] is not None and c["ci95"][0] <= c["mean"] + 1e-9 and c["mean"] <= c["ci95"][1] + 1e-9
    for p in report["paired"]:
        a, b = cells[(p["experiment"], "ehc", p["metric"])], cells[(p["experiment"], "neo_e", p["metric"])]
        if a["mean"] == a["mean"] and b["mean"] == b["mean"]:  # both defined (not NaN)
            assert p["diff"] == pytest.approx(a["mean"] - b["mean"])


def test_a_merge_with_a_missing_shard_is_an_error(sweeps, tmp_path):
    _, shards, _ = sweeps
    shutil.copy(shards / "shard-1-of-2.json", tmp_path / "shard-1-of-2.json")
    code, log = run("merge", "--out", str(tmp_path / "out"), str(tmp_path))
    assert code == 2 and "in no shard" in log, log
    code, log = run("merge", "--out", str(tmp_path / "out"), str(tmp_path / "nothing"))
    assert code == 2 and "not a sweep shard folder" in log, log


def test_bad_plans_are_errors_that_say_why(tmp_path):
    code, log = run("run", "--out", str(tmp_path), "--shard", "1/2", *SMALL)
    assert code == 2 and "needs --seeds" in log, log
    for args, word in ((["--shard", "3/2"], "--shard"), (["--levels", "-1"], "--levels"),
                       (["--experiments", "exp9"], "--experiments"), (["--methods", "rrt"], "--methods"),
                       (["--seeds", "1,1"], "--seeds")):
        code, log = run("run", "--out", str(tmp_path), "--seeds", "1001,1002", *(SMALL + args))
        assert code == 2 and word in log, log
    if not sweep.has_imprecision_flag(EXE):
        code, log = run("run", "--out", str(tmp_path), "--seeds", "1001", *(SMALL + ["--levels", "0,1"]))
        assert code == 2 and "--base-imprecision" in log and "only level 0" in log, log


def test_shards_split_every_plan_into_balanced_disjoint_parts():
    plan = {"experiments": list(sweep.EXPERIMENTS), "methods": {e: list(s["methods"]) for e, s in sweep.EXPERIMENTS.items()},
            "levels": [0.0, 1.0, 2.0, 4.0], "seeds": list(range(1000, 1010)), "exp1_sets": 2, "exp1_points": 25,
            "exp2_sets": 2, "exp3_sets": 1, "exp3_per_set": 2}
    jobs = sweep.plan_jobs(plan)
    for n in (1, 3, 8, 32):
        parts = [sweep.shard_jobs(plan, jobs, k, n) for k in range(1, n + 1)]
        assert sorted(j["id"] for p in parts for j in p) == sorted(j["id"] for j in jobs)
        loads = [sum(sweep.job_cost(plan, j) for j in p) for p in parts]
        assert max(loads) - min(loads) <= max(sweep.job_cost(plan, j) for j in jobs)
        for p in parts:  # no shard of several jobs holds one method only
            assert len(p) < 2 * len(sweep.EXPERIMENTS) or len({j["method"] for j in p}) > 1


def test_the_job_command_passes_the_level_when_ehc_experiment_takes_it():
    plan = {"robot": "r", "exp1_sets": 1, "exp1_points": 2, "exp2_sets": 1, "exp3_sets": 1, "exp3_per_set": 1,
            "object_time_limit": None, "imprecision_flag": True}
    job = {"experiment": "exp1_reset", "level": 2.5, "seed": 1234, "method": "ehc"}
    cmd = sweep.job_command(plan, "x", job, "o")
    assert cmd[cmd.index("--base-imprecision") + 1] == "2.5" and cmd[cmd.index("--protocol") + 1] == "reset"
    assert "--base-imprecision" not in sweep.job_command(dict(plan, imprecision_flag=False), "x", job, "o")


def test_every_level_is_run_and_reported_when_ehc_experiment_takes_it(tmp_path):
    # A stand-in ehc_experiment that lists --base-imprecision in its usage and runs the real one
    # without it: the levels' jobs, commands and report rows, not the imprecision's effect.
    devel = tmp_path / "devel"
    (devel / "lib" / "ehc_bringup").mkdir(parents=True)
    stub = devel / "lib" / "ehc_bringup" / "ehc_experiment"
    stub.write_text("#!/bin/bash\n[ \"$1\" = --help ] && { echo 'usage: ... [--base-imprecision LEVEL]' >&2; exit 2; }\n"
                    "args=()\nwhile [ $# -gt 0 ]; do\n  if [ \"$1\" = --base-imprecision ]; then shift 2; continue; fi\n"
                    "  args+=(\"$1\"); shift\ndone\nexec %s \"${args[@]}\"\n" % EXE)
    stub.chmod(0o755)
    out = tmp_path / "out"
    code, log = run("run", "--out", str(out), "--devel", str(devel), "--seeds", "4321", "--levels", "2,0",
                    "--experiments", "exp1_sequence", "--methods", "neo_e,ehc", "--exp1-sets", "1", "--exp1-points", "2")
    assert code == 0, log
    report = json.load(open(out / "sweep.json"))
    assert report["plan"]["levels"] == [0.0, 2.0] and report["plan"]["imprecision_flag"]
    cmds = json.load(open(out / "shard-1-of-1.json"))["jobs"]
    assert sorted(c["cmd"].split("--base-imprecision ")[1].split()[0] for c in cmds) == ["0", "0", "2", "2"]
    by_level = {}
    for c in report["cells"]:
        by_level.setdefault(c["level"], []).append((c["method"], c["metric"], c["mean"]))
    assert json.dumps(by_level[0.0]) == json.dumps(by_level[2.0])  # the stand-in ignores the level: same seed, same result
    assert [p["level"] for p in report["paired"]] == [0.0, 0.0, 2.0, 2.0]
