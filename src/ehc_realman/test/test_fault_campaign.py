#!/usr/bin/python3
"""Runs test/fault_campaign.py --quick (its own private master) and asserts 0 crashes, 0 hangs,
0 unsafe outputs and 0 unclear messages (fault_campaign.test). The campaign's checks are counts,
not timings: the only time bounds are its watchdog grace (timeout + 0.1 s), the 5 s a node has to
show life or to exit after SIGINT, and the 60 s a program has to start."""
import json
import os
import subprocess
import sys
import tempfile
import unittest

import rostest

WS = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


class FaultCampaign(unittest.TestCase):
    def test_quick_campaign_has_no_crash_hang_or_unsafe_output(self):
        out = tempfile.mkdtemp(prefix="fault_campaign_")
        env = dict(os.environ)
        for k in ("ROS_MASTER_URI", "ROS_HOME", "ROS_LOG_DIR"):
            env.pop(k, None)  # the campaign runs its own master, never the rostest one
        p = subprocess.run([os.path.join(WS, "test", "fault_campaign.py"), "--quick", "--out", out], cwd=WS,
                           env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
                           timeout=540)
        sys.stdout.write(p.stdout)
        with open(os.path.join(out, "campaign.json")) as f:
            result = json.load(f)
        self.assertEqual(result["totals"], {"crashes": 0, "hangs": 0, "unsafe": 0, "unclear": 0}, p.stdout[-3000:])
        self.assertEqual(p.returncode, 0)
        self.assertEqual(set(result["phases"]), {"startup", "params", "lockstep", "signals", "runtime"})
        self.assertGreaterEqual(len(result["cases"]), 60)


if __name__ == "__main__":
    rostest.rosrun("ehc_realman", "fault_campaign_quick", FaultCampaign, sys.argv)
