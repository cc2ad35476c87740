#!/usr/bin/python3
"""End-to-end grasp of config/scenes/single_object.yaml, run by rostest.

For one grasp orientation (~orientation: forward | downward | sideways) the whole headless
pipeline (src/ehc_bringup/scripts/demo.sh: sim in lock-step sim time, tag node, grasp node,
obstacle node, EHC controller, grasp sequencer; its own private ROS master) runs twice:
with MPBS (controller _mpbs:=true) and without (plain PBVS to the grasp pose, _mpbs:=false).

Asserted: with MPBS the object is grasped and lifted (the simulator's gripper/lift result) and
TfM >= 95 % (TfM: the approach at a distance, until the arm takes over; see grasp_sequencer.h). Without MPBS the TfM is reported; for downward and sideways grasps it must be lower
than with MPBS (the direction of the difference, no made-up number). No wall-clock assertion:
the .test time-limit only guards against a hang.
"""
import os
import sys
import unittest

import rospy
import rostest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from demo_run import results_dir, run_demo  # noqa: E402


def run_scenario(orientation, mpbs, out):
    return run_demo({"SCENE": "config/scenes/single_object.yaml",
                     "SEQUENCER_CONFIG": "config/demo/grasp_single_%s.yaml" % orientation,
                     "TAG_OBJECTS": "target",
                     "MPBS": "true" if mpbs else "false"}, out)


class GraspSingle(unittest.TestCase):
    def test_grasp_with_and_without_mpbs(self):
        orientation = rospy.get_param("~orientation")
        base = results_dir("grasp_%s_" % orientation)
        with_mpbs, log1 = run_scenario(orientation, True, os.path.join(base, "mpbs"))
        without, log2 = run_scenario(orientation, False, os.path.join(base, "pbvs"))
        a, b = with_mpbs["objects"][0], without["objects"][0]
        print("[%s] EHC + MPBS: success %s, time %.2f s, TfM %.1f %% (%.1f %% to the pre-grasp switch) | "
              "EHC without MPBS: success %s, time %.2f s, TfM %.1f %% (%.1f %%)"
              % (orientation, a["success"], a["time_s"], 100 * a["tfm"], 100 * a["tfm_until_switch"],
                 b["success"], b["time_s"], 100 * b["tfm"], 100 * b["tfm_until_switch"]))
        self.assertEqual(with_mpbs["mpbs"], True)
        self.assertEqual(without["mpbs"], False)
        self.assertTrue(a["success"], "EHC + MPBS did not grasp (%s: %s)\n%s" % (a["failed_phase"], a["reason"], log1[-2000:]))
        self.assertGreater(a["tfm_cycles"], 0)
        self.assertGreaterEqual(a["tfm"], 0.95, "TfM with MPBS %.3f < 0.95" % a["tfm"])
        if orientation in ("downward", "sideways"):
            self.assertGreater(b["tfm_cycles"], 0)
            self.assertLess(b["tfm"], a["tfm"], "without MPBS the TfM (%.3f) should be lower than with MPBS (%.3f)"
                            % (b["tfm"], a["tfm"]))


if __name__ == "__main__":
    rospy.init_node("test_grasp_single")
    rostest.rosrun("ehc_bringup", "test_grasp_single", GraspSingle, sys.argv)
