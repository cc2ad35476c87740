#!/usr/bin/python3
"""The in-process pipeline (ehc_experiment grasp, GraspPipeline) and the ROS
pipeline (scripts/demo.sh: the same cores as nodes, lock-step sim time) agree, run by rostest.

For each method in ~methods (space-separated; default "ehc") one Exp-2 set runs through both
paths on the same scene (config/scenes/table_three_objects.yaml, no placement jitter: the ROS
path reads the scene file as it is) with the same noise seed (run seed = ~seed * 1000, as
ehc_experiment's set 0; demo.sh SEED) and the same MPBS setting (from the in-process summary).

Asserted per object: success agrees, and for objects both grasped the times agree within
TIME_TOLERANCE_S. Why that tolerance: the two paths differ only in when perception results
arrive. In-process an image's tag pose and the grasp candidates are used in the cycle the image
is taken; over ROS they arrive after the nodes' processing (wall time during which the lock-step
sim may go on for a few cycles) and the grasp node runs at 2 Hz, so a candidate can be one grasp
period (0.5 s) later at the start of the approach and again at the lock; the sequencer's stall
rule decides in steps of stall_time (1 s). One stall step plus two grasp periods: 2.0 s. The
ROS path is not bit-reproducible (a goal can leave the sequencer just after an acknowledgement and
be used a cycle later; see the README), hence a tolerance and not equality. No wall-clock
assertion; the .test time-limit only guards a hang.

One stated exception to "success agrees": an object at the arm's reach limit. When one path
grasps it and the other times out in GRASP with the TCP within REACH_LIMIT_M of the grasp (the
sequencer's reason says how far), the arm got there but not into it: which side of the limit a
run falls on is decided by where the base stopped, i.e. by the few cycles of perception latency
that separate the paths (TSMM's base stops d = 0.2 m from the perceived centre; at its measured
0.49 m/s distant speed, Table III, each 10 ms cycle of delay moves the stop by up to 0.5 cm). Table III's TSMM misses are all of this kind: the
back object, the TCP 1.0-2.2 cm short after 30 s. Such a disagreement is printed,
not failed; any other (a miss in another phase, or farther than REACH_LIMIT_M) fails.

Objects are put back before the gripper opens (a cylinder released at the lift height could
fall over and roll against the next object, which depends on the exact motion and made the
paths disagree). make test runs all four methods (methods:="ehc" runs one).
"""
import csv
import json
import os
import re
import subprocess
import sys
import unittest

import rospy
import rostest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from demo_run import WS, devel_space, results_dir, run_demo  # noqa: E402

TIME_TOLERANCE_S = 2.0
REACH_LIMIT_M = 0.03


def reach_limit_miss(reason):
    """The TCP's distance (m) from the grasp if `reason` is a GRASP time-out (the sequencer's
    "time limit 30 s in GRASP (TCP 1.4 cm from the grasp, ...)"), else None."""
    m = re.search(r"time limit \S+ s in GRASP \(TCP ([0-9.]+) cm from the grasp", reason or "")
    return float(m.group(1)) / 100.0 if m else None


def run_in_process(method, seed, out):
    exe = os.path.join(devel_space(), "lib", "ehc_bringup", "ehc_experiment")
    p = subprocess.run([exe, "grasp", "--method", method, "--sets", "1", "--seed", str(seed), "--jobs", "1",
                        "--jitter-xy", "0", "--jitter-yaw", "0", "--out", out], cwd=WS,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
    sys.stdout.write(p.stdout[-3000:])
    if p.returncode != 0:
        raise AssertionError("ehc_experiment exited %d:\n%s" % (p.returncode, p.stdout[-3000:]))
    with open(os.path.join(WS, out, "summary.json")) as f:
        summary = json.load(f)["methods"][0]
    with open(os.path.join(WS, out, "trials.csv")) as f:
        trials = {r["object"]: r for r in csv.DictReader(f)}
    return summary, trials


class GraspAgreement(unittest.TestCase):
    def test_in_process_and_ros_agree(self):
        methods = rospy.get_param("~methods", "tsmm neo_c neo_e ehc").split()
        seed = int(rospy.get_param("~seed", 1))
        base = results_dir("grasp_agreement_")
        lines, problems = [], []
        for m in methods:
            summary, inproc = run_in_process(m, seed, os.path.join(base, m + "_in_process"))
            ros, log = run_demo({"MODE": summary["mode"], "MPBS": "true" if summary["mpbs"] else "false",
                                 "SEED": str(seed * 1000)}, os.path.join(base, m + "_ros"))
            self.assertEqual(ros["mpbs"], summary["mpbs"])
            self.assertEqual([o["name"] for o in ros["objects"]], list(inproc.keys()))
            for o in ros["objects"]:
                i = inproc[o["name"]]
                ok_in = i["success"] == "1"
                t_in = float(i["time_s"])
                lines.append("%-6s %-6s in-process %-7s %6.2f s (%s) | ROS %-7s %6.2f s (%s)" % (
                    m, o["name"], ok_in, t_in, i["failed_phase"] or "-", o["success"], o["time_s"],
                    o["failed_phase"] or "-"))
                if ok_in != o["success"]:
                    short = reach_limit_miss(o.get("reason") if ok_in else i["reason"])
                    what = "%s %s: success in-process %s, ROS %s" % (m, o["name"], ok_in, o["success"])
                    if short is not None and short <= REACH_LIMIT_M:
                        lines.append("%s %s: at the reach limit (the miss ended %.1f cm short in GRASP, <= %.1f cm): "
                                     "tolerated" % (m, o["name"], 100.0 * short, 100.0 * REACH_LIMIT_M))
                    else:
                        problems.append(what)
                elif ok_in and abs(t_in - o["time_s"]) > TIME_TOLERANCE_S:
                    problems.append("%s %s: time in-process %.2f s, ROS %.2f s (tolerance %.1f s)"
                                    % (m, o["name"], t_in, o["time_s"], TIME_TOLERANCE_S))
        print("\n".join(["[agreement] " + l for l in lines]))
        self.assertEqual(problems, [], "\n".join(problems + lines))


if __name__ == "__main__":
    rospy.init_node("test_grasp_agreement")
    rostest.rosrun("ehc_bringup", "test_grasp_agreement", GraspAgreement, sys.argv)
