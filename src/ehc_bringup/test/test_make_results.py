#!/usr/bin/python3
"""make_results.py (docs/RESULTS.md) on the small result folders of test/fixtures/results.

test/fixtures/results holds what experiments.sh and bench.sh write, kept to the files the
generator reads: summary.json and trials.csv of a reduced ehc_experiment run (seed 7; Exp-1 and
Exp-2 two sets, Exp-3 one), bench.jsonl lines in the bench executables' format, and a meta.json
each; it has no demo folder. The tests run the generator as `make results` does and check that every
table comes with its command, code version, machine, date, seeds and the paper's figures, that
a folder that is not there is reported as not run, that a malformed file is an error naming the
file (and nothing is written), and that the means and intervals are those of the fixture data.

  /usr/bin/python3 -m pytest src/ehc_bringup/test/test_make_results.py
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
SCRIPT = os.path.join(ROOT, "src", "ehc_bringup", "scripts", "make_results.py")
FIXTURE = os.path.join(ROOT, "test", "fixtures", "results")

_spec = importlib.util.spec_from_file_location("make_results", SCRIPT)
make_results = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(make_results)


def run(*args):
    """make_results.py with `args`: (exit code, stdout + stderr)."""
    r = subprocess.run([sys.executable, SCRIPT] + list(args), capture_output=True, text=True, check=False)
    return r.returncode, r.stdout + r.stderr


def generate(tmp_path, results=FIXTURE, *extra):
    out = tmp_path / "RESULTS.md"
    code, log = run("--results", str(results), "--out", str(out), *extra)
    assert code == 0, log
    return out.read_text()


def sections(text):
    """{title: body} of the '## ' sections."""
    out, title = {}, None
    for line in text.splitlines():
        if line.startswith("## "):
            title = line[3:]
            out[title] = []
        elif title:
            out[title].append(line)
    return {k: "\n".join(v) for k, v in out.items()}


def table_rows(body):
    """The rows of the (only) markdown table of a section, header first, as lists of cells."""
    rows = [[c.strip() for c in line.strip().strip("|").split("|")] for line in body.splitlines()
            if line.startswith("|") and not line.startswith("|---")]
    return rows


def test_every_table_has_its_provenance_and_the_papers_figures(tmp_path):
    text = generate(tmp_path)
    secs = sections(text)
    assert sum(s.startswith(("Exp-1", "Exp-2", "Exp-3", "Benchmarks")) for s in secs) == 4, list(secs)
    for title, body in secs.items():
        for field in ("- command: `", "- code version: `ef2b0fb`", "- machine: AMD EPYC, 2 core(s)",
                      "- date: 2026-11-27 05:", "- seeds: "):
            assert field in body, "%s: no '%s'" % (title, field)
        header = table_rows(body)[0]
        if title.startswith("Everyday"):  # the paper has no such figure: the bar instead
            assert any(h.startswith("bar") for h in header), header
            continue
        assert any(h.startswith("paper") for h in header), "%s: no paper column in %s" % (title, header)
    # Each experiment names the ehc_experiment run that made it and its seeds.
    assert "ehc_experiment reach" in secs[next(s for s in secs if s.startswith("Exp-1"))]
    assert "ehc_experiment grasp" in secs[next(s for s in secs if s.startswith("Exp-2"))]
    exp3 = secs[next(s for s in secs if s.startswith("Exp-3"))]
    assert "ehc_experiment poses" in exp3
    assert "run seed = seed*1000 + set*10 + index (1 run seed: 7000)" in exp3
    assert "run seed = seed*1000 + set*10 (2 run seeds: 7000, 7010)" in secs[next(s for s in secs if s.startswith("Exp-2"))]


def test_the_papers_figures_stand_beside_ours(tmp_path):
    secs = sections(generate(tmp_path))
    rows = {title.split(":")[0]: {r[0]: r for r in table_rows(body)[1:]} for title, body in secs.items()}
    assert rows["Exp-1"]["EHC"][2] == "9.98" and rows["Exp-1"]["EHC"][4] == "18"
    assert rows["Exp-1"]["NEO(e)"][2] == "11.81" and rows["Exp-1"]["NEO(e)"][4] == "35"
    assert rows["Exp-1"]["NEO(c)"][2] == "11.69" and rows["Exp-1"]["NEO(c)"][4] == "37"
    assert rows["Exp-2"]["EHC"][2] == "13.54" and rows["Exp-2"]["EHC"][4] == "95.6"
    assert rows["Exp-2"]["TSMM"][4] == "80.0" and rows["Exp-2"]["NEO(e)"][4] == "51.1"
    assert rows["Exp-2"]["NEO(c)"][4] == "11.1"
    # Table IV: forward, downward, sideways TfM
    neo, ehc_nompbs, ehc = (rows["Exp-3"][k] for k in ("NEO (without MPBS)", "EHC (without MPBS)", "EHC (MPBS)"))
    assert (neo[2], neo[4], neo[6]) == ("100.0", "31.6", "38.7")
    assert (ehc_nompbs[2], ehc_nompbs[4], ehc_nompbs[6]) == ("100.0", "34.3", "36.2")
    assert (ehc[2], ehc[4], ehc[6]) == ("100.0", "100.0", "100.0")


def test_a_missing_folder_is_reported_as_not_run(tmp_path):
    text = generate(tmp_path)  # the fixture has no demo folder
    assert "| Demo | `test/fixtures/results/demo` | not run (`make demo`) |" in text
    assert not any(t.startswith("Demo") for t in sections(text))
    text = generate(tmp_path, FIXTURE, "--bench", str(tmp_path / "nothing_here"))
    assert "| Benchmarks | `%s` | not run (`make bench`) |" % (tmp_path / "nothing_here") in text
    assert not any(t.startswith("Benchmarks") for t in sections(text))
    text = generate(tmp_path, tmp_path / "no_results_at_all")
    assert text.count("not run") == 7  # experiments 1-3, everyday, bench, demo, sweep (verdicts)


def test_everyday_objects_report_both_halves_with_the_bar_and_the_misses(tmp_path):
    secs = sections(generate(tmp_path))
    body = secs[next(s for s in secs if s.startswith("Everyday"))]
    assert "- seeds: tuning half: 7; validation half: 7" in body
    assert "ehc_experiment grasp" in body and "--library <half>" in body
    rows = {r[0]: r for r in table_rows(body)[1:]}
    assert set(rows) == {"tuning", "validation"}
    # The fixture's trials: 6 objects per half, all with a valid grasp in view, 1 grasped each;
    # in the validation half 4 of them with one the robot reaches (the grasped one among them),
    # the tuning half's run written before that column.
    for half in ("tuning", "validation"):
        assert rows[half][2:5] == ["2", "6", "6"], rows[half]
        assert rows[half][5].startswith("16.7 [") and rows[half][5].endswith("(1/6)"), rows[half]
        assert rows[half][7] == "0"
    assert rows["validation"][6].startswith("25.0 [") and rows["validation"][6].endswith("(1/4)"), rows["validation"]
    assert rows["tuning"][6] == "-"
    assert rows["validation"][8] == "not met" and rows["tuning"][8] == "-"
    assert "Misses where a valid grasp was in view, validation half, ehc: " in body
    assert "(obstacle: left_finger_link at mug_02 (the target)) in PRE_GRASP: 1" in body  # its own points
    assert "(obstacle: right_finger_link at mug_02) in PRE_GRASP: 1" in body  # a neighbour
    # A half's folder alone is reported; a run without trials.csv is an error naming it.
    results = tmp_path / "results"
    shutil.copytree(FIXTURE, results)
    shutil.rmtree(results / "everyday" / "tuning")
    secs = sections(generate(tmp_path, results))
    body = secs[next(s for s in secs if s.startswith("Everyday"))]
    assert [r[0] for r in table_rows(body)[1:]] == ["validation"]
    os.remove(results / "everyday" / "validation" / "seed_7" / "trials.csv")
    code, log = run("--results", str(results), "--out", str(tmp_path / "R.md"))
    assert code == 2 and "everyday/validation/seed_7/trials.csv: cannot read" in log, log


def test_a_demo_run_gets_its_table(tmp_path):
    results = tmp_path / "results"
    shutil.copytree(FIXTURE, results)
    (results / "demo").mkdir()
    (results / "demo" / "summary.json").write_text(json.dumps({
        "mode": "ehc", "successes": 2, "objects_total": 3, "mpbs": True, "objects": [
            {"name": "front", "success": True, "time_s": 12.5, "tfm": 0.9},
            {"name": "middle", "success": True, "time_s": 13.25, "tfm": 0.85},
            {"name": "back", "success": False, "time_s": 30.0, "tfm": 0.5}]}))
    shutil.copy(results / "bench" / "meta.json", results / "demo" / "meta.json")
    secs = sections(generate(tmp_path, results))
    demo = secs[next(s for s in secs if s.startswith("Demo"))]
    assert "- code version: `ef2b0fb`" in demo and "- seeds: " in demo
    rows = table_rows(demo)
    assert rows[0][-1].startswith("paper") and [r[:3] for r in rows[1:]] == [
        ["front", "yes", "12.50"], ["middle", "yes", "13.25"], ["back", "no", "30.00"]]
    assert "2/3 grasped, mode ehc, MPBS on." in demo


def test_every_robots_demo_gets_a_row(tmp_path):
    results = tmp_path / "results"
    shutil.copytree(FIXTURE, results)
    runs = {"demo": (None, [True, True, True]), "demo_ur5e_ridgeback": ("ur5e_ridgeback", [True, False, True]),
            "demo_kinova_gen3_husky": ("kinova_gen3_husky", [True, True, True])}
    for folder, (robot, success) in runs.items():
        (results / folder).mkdir()
        (results / folder / "summary.json").write_text(json.dumps({"mode": "ehc", "objects": [
            {"name": n, "success": ok, "time_s": 5.0 + i, "tfm": 1.0} for i, (n, ok) in
            enumerate(zip(["front", "middle", "back"], success))]}))
        meta = json.loads((results / "bench" / "meta.json").read_text())
        meta.update({"seed": "2", "robot": robot})
        (results / folder / "meta.json").write_text(json.dumps(meta))
    text = generate(tmp_path, results)
    secs = sections(text)
    rows = table_rows(secs[next(s for s in secs if s.startswith("Demo on every robot"))])
    assert rows[0][:3] == ["Robot", "Grasped", "Time per object (s)"]
    assert [r[:3] for r in rows[1:]] == [["the configs' default", "3/3", "5.00, 6.00, 7.00"],
                                        ["kinova_gen3_husky", "3/3", "5.00, 6.00, 7.00"],
                                        ["ur5e_ridgeback", "2/3", "5.00, 6.00, 7.00"]]
    assert all(r[5] == "2" and r[6] == "`ef2b0fb`" for r in rows[1:])
    assert "| Demo on every robot |" in text
    assert "Demo on every robot" not in generate(tmp_path)  # no demo run: no table


@pytest.mark.parametrize("name, damage, says", [
    ("experiments/exp2/summary.json", lambda t: t[: len(t) // 2], "not valid JSON"),
    ("experiments/exp1/trials.csv", lambda t: t.replace(",1,", ",yes,", 1), "is not a number"),
    ("experiments/exp3/trials.csv", lambda t: t.replace("approach,", "approach_,", 1), "missing column(s) approach"),
    ("experiments/exp1/summary.json", lambda t: t.replace('"targets"', '"target_count"', 1), "missing field 'targets'"),
    ("bench/bench.jsonl", lambda t: t.replace('"n":20000,', '"n":20000', 1), "line 1 is not valid JSON"),
    ("experiments/meta.json", lambda t: "[1, 2]", "expected a JSON object"),
])
def test_a_malformed_file_is_an_error_naming_it(tmp_path, name, damage, says):
    results = tmp_path / "results"
    shutil.copytree(FIXTURE, results)
    path = results / name
    path.write_text(damage(path.read_text()))
    out = tmp_path / "RESULTS.md"
    code, log = run("--results", str(results), "--out", str(out))
    assert code == 2, log
    assert "make_results.py: error: %s" % path in log, log
    assert says in log, log
    assert not out.exists(), "a report was written from a malformed folder"


def test_the_means_are_the_fixture_datas_and_the_output_is_deterministic(tmp_path):
    text = generate(tmp_path)
    assert generate(tmp_path) == text  # fixed bootstrap seed
    with open(os.path.join(FIXTURE, "experiments", "exp1", "trials.csv")) as f:
        ehc = [r for r in csv.DictReader(f) if r["method"] == "ehc"]
    reached = [float(r["time_s"]) for r in ehc if r["reached"] == "1"]
    failed = sum(r["reached"] == "0" for r in ehc)
    secs = sections(text)
    row = {r[0]: r for r in table_rows(secs[next(s for s in secs if s.startswith("Exp-1"))])}["EHC"]
    time, lo_hi = row[1].split(" ", 1)
    assert float(time) == pytest.approx(sum(reached) / len(reached), abs=0.005)
    lo, hi = (float(x) for x in lo_hi.strip("[]").split(","))
    assert min(reached) <= lo <= float(time) <= hi <= max(reached)
    assert row[3].startswith("%d [" % failed) and row[3].endswith("(/%d)" % len(ehc))
    with open(os.path.join(FIXTURE, "experiments", "exp2", "trials.csv")) as f:
        tsmm = [r for r in csv.DictReader(f) if r["method"] == "tsmm"]
    ok = sum(r["success"] == "1" for r in tsmm)
    row = {r[0]: r for r in table_rows(secs[next(s for s in secs if s.startswith("Exp-2"))])}["TSMM"]
    assert row[3].startswith("%.1f [" % (100.0 * ok / len(tsmm))) and row[3].endswith("(%d/%d)" % (ok, len(tsmm)))


def test_bootstrap_interval_over_sets():
    # Pooled ratio; one set: no interval; identical sets: a zero-width interval.
    assert make_results.bootstrap([3.0], [2.0]) == (1.5, None)
    point, ci = make_results.bootstrap([1.0, 1.0, 1.0], [2.0, 2.0, 2.0], scale=100.0)
    assert point == 50.0 and ci == (50.0, 50.0)
    point, ci = make_results.bootstrap([0.0, 10.0], [1.0, 1.0])
    assert point == 5.0 and 0.0 <= ci[0] < 5.0 < ci[1] <= 10.0


def test_meta_records_command_code_version_machine_and_dates(tmp_path):
    out = tmp_path / "run"
    code, log = run("meta", str(out), "--command", "SEED=3 experiments.sh", "--run", "exp1", "ehc_experiment reach --seed 3",
                    "--seed", "3", "--robot", "kuka_iiwa14_kmr")
    assert code == 0, log
    meta = json.loads((out / "meta.json").read_text())
    assert meta["command"] == "SEED=3 experiments.sh" and meta["runs"] == {"exp1": "ehc_experiment reach --seed 3"}
    assert meta["seed"] == "3" and meta["robot"] == "kuka_iiwa14_kmr"
    assert meta["code_version"] and meta["machine"]["cores"] >= 1 and meta["machine"]["cpu"]
    assert meta["started"].endswith("UTC") and "finished" not in meta
    code, log = run("meta", str(out), "--finish")
    assert code == 0, log
    meta = json.loads((out / "meta.json").read_text())
    assert meta["finished"].endswith("UTC") and meta["wall_s"] >= 0
    # A run that did not finish says so in its tables.
    lines = make_results.provenance({"command": "x", "started": "then"}, None, str(out), "s")
    assert any("the run did not finish" in line for line in lines)


def test_paired_bootstrap_resamples_both_series_together():
    # The same per-set offset in both series: the paired difference has no spread.
    a = ([3.0, 5.0, 9.0, 4.0], [1.0, 1.0, 1.0, 1.0])
    b = ([2.0, 4.0, 8.0, 3.0], [1.0, 1.0, 1.0, 1.0])
    p = make_results.paired_bootstrap(a, b)
    assert p["diff"] == (1.0, (1.0, 1.0))
    assert p["ratio"][0] == pytest.approx(21.0 / 17.0) and p["ratio"][1][0] <= p["ratio"][0] <= p["ratio"][1][1]
    assert make_results.paired_bootstrap(([1.0], [1.0]), ([2.0], [1.0]))["diff"] == (-1.0, None)


def test_the_verdict_rule():
    v = make_results.verdict
    # The paper's figure inside our interval, or the interval wholly on its better side: reproduced.
    assert v(9.98, 10.2, (9.5, 11.0), "lower") == "inside"
    assert v(9.98, 8.0, (7.5, 8.6), "lower") == "better"
    assert v(9.98, 12.0, (11.0, 13.0), "lower") == "worse"
    assert v(95.6, 97.0, (96.0, 98.0), "higher") == "better"
    assert v(95.6, 80.0, (70.0, 90.0), "higher") == "worse"
    assert v(95.6, 95.6, None, "higher") == "inside"  # no interval: the mean alone
    assert v(9.98, float("nan"), None, "lower") == "no data"  # nothing reached: no time
    c = make_results.combined_verdict
    # EHC's figures and the comparisons are one-sided (better reproduces), a baseline's figure two-sided.
    assert c([("0", "inside"), ("1", "better")], True) == "reproduced"
    assert c([("0", "inside"), ("1", "better")], False) == "reproduced at imprecision level 0 only"
    assert c([("0", "worse"), ("1", "worse")], True) == "not reproduced"
    assert c([("0", "better")], False) == "not reproduced"
    assert c([("0", "no data")], True) == "not measured"
    assert c([("0", "no data"), ("1", "inside")], True) == "reproduced at imprecision level 1 only"
    assert c([("0", "worse"), ("2", "better"), ("4", "inside")], True) == "reproduced at imprecision level 2, 4 only"


def write_sweep(folder, seeds, cells, paired):
    folder.mkdir(parents=True)
    (folder / "sweep.json").write_text(json.dumps({
        "plan": {}, "rerun": "src/ehc_bringup/scripts/sweep.py run --out DIR --seeds %s" % ",".join(map(str, seeds)),
        "seeds": [{"seed": s, "role": make_results.seed_role(s)} for s in seeds], "bootstrap_seed": 1,
        "bootstrap_resamples": 2000, "code_version": "abc1234", "machine": "AMD EPYC, 2 core(s)",
        "cells": cells, "paired": paired}))


def test_the_verdicts_section_judges_every_measured_claim(tmp_path):
    def cell(exp, method, metric, better, level, mean, lo, hi):
        return {"experiment": exp, "method": method, "metric": metric, "better": better, "level": level,
                "mean": mean, "ci95": [lo, hi], "sets": 20, "trials": 100}
    cells = [cell("exp1_sequence", "ehc", "time_s", "lower", 0.0, 9.0, 8.5, 9.5),        # paper 9.98: better
             cell("exp1_sequence", "ehc", "time_s", "lower", 1.0, 11.0, 10.5, 11.5),      # worse
             cell("exp2", "neo_e", "success_pct", "higher", 0.0, 20.0, 10.0, 30.0),       # paper 51.1: worse
             cell("exp2", "neo_c", "success_pct", "higher", 0.0, 90.0, 80.0, 100.0),      # paper 11.1: better
             cell("exp3", "ehc", "tfm_downward_pct", "higher", 0.0, 99.0, 97.0, 100.0)]   # paper 100: inside
    paired = [{"experiment": "exp1_sequence", "level": 0.0, "metric": "time_s", "better": "lower", "a": "ehc",
               "b": "neo_e", "diff": -1.0, "diff_ci95": [-2.0, 0.0], "ratio": 0.9, "ratio_ci95": [0.8, 1.0], "sets": 20}]
    results = tmp_path / "results"
    write_sweep(results / "sweep", [12345, 67890], cells, paired)
    secs = sections(generate(tmp_path, results))
    body = secs["Verdicts: the paper's claims against the sweep"]
    rows = {r[0]: r for r in table_rows(body)[1:]}
    assert set(rows) == {"Table II EHC time (s), back to back", "Table III NEO(e) success (%)", "Table III NEO(c) success (%)",
                         "Table IV EHC (MPBS) TfM downward (%)", "Table II EHC / NEO(e) time, back to back"}
    assert rows["Table II EHC time (s), back to back"][1:] == [
        "9.98", "L0: 9.00 [8.50, 9.50] (better); L1: 11.00 [10.50, 11.50] (worse)", "reproduced at imprecision level 0 only"]
    assert rows["Table III NEO(e) success (%)"][3] == "not reproduced"
    assert rows["Table III NEO(c) success (%)"][3] == "not reproduced"  # a baseline better than the paper's
    assert rows["Table IV EHC (MPBS) TfM downward (%)"][3] == "reproduced"
    assert rows["Table II EHC / NEO(e) time, back to back"][1:] == ["0.845", "L0: 0.90 [0.80, 1.00] (inside)", "reproduced"]
    assert "sweep.py run --out DIR --seeds 12345,67890" in body and "make results" in body
    assert "reporting seeds only" in body and "Rule:" in body
    # A sweep on a tuning seed is flagged as no report.
    write_sweep(tmp_path / "tuned" / "sweep", [7, 12345], cells, paired)
    body = sections(generate(tmp_path, tmp_path / "tuned"))["Verdicts: the paper's claims against the sweep"]
    assert "includes tuning seed(s) 7" in body
