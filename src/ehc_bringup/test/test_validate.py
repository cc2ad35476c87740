#!/usr/bin/python3
"""validate.py (`make validate`) in a reduced form: every shipped robot, both target generators,
every method, 2 sets x 2 targets, on a fresh random seed that the test prints (a failure of this
test reproduces with that seed). Checks the run's bookkeeping rather than the bar (make validate
judges the bar on full-size runs): every robot x generator x method is reported with its
counts, every failed target is listed with its cause and a rerun command, the interval contains
the point estimate, and a set rerun alone with --first-set gives the same trials as in the run.

  /usr/bin/python3 -m pytest src/ehc_bringup/test/test_validate.py
"""
import csv
import glob
import json
import os
import random
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", ".."))
SCRIPT = os.path.join(ROOT, "src", "ehc_bringup", "scripts", "validate.py")
EXE = os.path.join(ROOT, "devel", "lib", "ehc_bringup", "ehc_experiment")
ROBOTS = sorted(os.path.basename(os.path.dirname(p)) for p in glob.glob(os.path.join(ROOT, "config/robots/*/robot.yaml")))


def trials(path, method):
    with open(path) as f:
        return [r for r in csv.DictReader(f) if r["method"] == method]


def test_reduced_validation_reports_every_case_and_reruns_a_set_alone(tmp_path):
    seed = random.SystemRandom().randrange(1, 1000000)
    print("validate seed %d" % seed)
    r = subprocess.run([sys.executable, SCRIPT, "--out", str(tmp_path), "--seed", str(seed), "--sets", "2", "--points", "2"],
                       capture_output=True, text=True, check=False)
    assert r.returncode in (0, 1), r.stdout + r.stderr
    assert "seed %d" % seed in r.stderr
    report = json.load(open(tmp_path / "validate.json"))
    assert report["seed"] == seed
    cases = {(x["robot"], x["generator"], x["method"]) for x in report["rows"]}
    assert cases == {(rb, g, m) for rb in ROBOTS for g in ("paper", "any") for m in ("neo_c", "neo_e", "ehc")}
    for row in report["rows"]:
        assert row["targets"] == 4
        assert sum(row["causes"].values()) == row["failed"]
        lo, hi = row["failure_rate_ci95"]
        assert lo <= row["failure_rate"] <= hi
        assert row["passes_bar"] == (row["failed"] / row["targets"] <= report["bar"])
    with open(tmp_path / "failures.csv") as f:
        listed = list(csv.DictReader(f))
    assert len(listed) == sum(x["failed"] for x in report["rows"])
    for fl in listed:
        assert fl["cause"] and "--first-set %s" % fl["set"] in fl["rerun"] and "--seed %d" % seed in fl["rerun"]
    assert ("above the bar" in r.stdout) and (r.returncode == (1 if any(not x["passes_bar"] for x in report["rows"]) else 0))
    # A failed target's set (or set 1 when nothing failed) rerun alone: the same trials.
    robot, generator, method, s = ((listed[0]["robot"], listed[0]["generator"], listed[0]["method"], int(listed[0]["set"]))
                                   if listed else (ROBOTS[0], "any", "ehc", 1))
    out = tmp_path / "rerun"
    subprocess.run([EXE, "reach", "--robot", robot, "--generator", generator, "--method", method, "--sets", "1",
                    "--points", "2", "--seed", str(seed), "--first-set", str(s), "--out", str(out)],
                   capture_output=True, text=True, check=True)
    keys = ("set", "index", "reached", "time_s", "final_position_error_m", "failure", "failure_joint")
    alone = [tuple(t[k] for k in keys) for t in trials(out / "trials.csv", method)]
    within = [tuple(t[k] for k in keys) for t in trials(tmp_path / robot / generator / "trials.csv", method) if int(t["set"]) == s]
    assert alone == within


def test_bad_arguments_are_errors_naming_the_option(tmp_path):
    for args, word in ((["--robots", "no_such_robot"], "--robots"), (["--generators", "spiral"], "--generators"),
                       (["--methods", "tsmm"], "--methods"), (["--sets", "0"], "--sets")):
        r = subprocess.run([sys.executable, SCRIPT, "--out", str(tmp_path)] + args, capture_output=True, text=True, check=False)
        assert r.returncode == 2 and word in r.stderr, r.stderr
