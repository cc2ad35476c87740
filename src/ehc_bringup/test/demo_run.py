"""Runs src/ehc_bringup/scripts/demo.sh (the ROS pipeline: its own private master on a free port,
lock-step sim time) for the end-to-end rostests, and finds this workspace's binaries."""
import json
import os
import socket
import subprocess
import sys

WS = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


def devel_space():
    # CMAKE_PREFIX_PATH's first entry is this workspace's devel space (setup.bash sourced).
    for d in os.environ.get("CMAKE_PREFIX_PATH", "").split(":"):
        if d and os.path.exists(os.path.join(d, "setup.bash")) and d.startswith(WS):
            return d
    return os.path.join(WS, "devel")


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def run_demo(overrides, out):
    """demo.sh with the environment `overrides` (MODE, SEED, MPBS, SCENE, ...) writing to `out`
    (relative to the workspace); returns (summary.json as a dict, the script's output)."""
    env = dict(os.environ)
    # The pipeline gets its own master: never the rostest master of the calling test.
    for k in ("ROS_MASTER_URI", "ROS_HOME", "ROS_LOG_DIR"):
        env.pop(k, None)
    env.update({"EHC_DEVEL": os.environ.get("EHC_DEVEL", os.path.relpath(devel_space(), WS)),
                "OUT": out, "EHC_DEMO_PORT": str(free_port())})
    env.update(overrides)
    p = subprocess.run([os.path.join(WS, "src/ehc_bringup/scripts/demo.sh")], cwd=WS, env=env,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
    sys.stdout.write(p.stdout)
    summary = os.path.join(WS, out, "summary.json")
    if not os.path.exists(summary):
        raise AssertionError("no summary (exit %d):\n%s" % (p.returncode, p.stdout[-3000:]))
    with open(summary) as f:
        return json.load(f), p.stdout


def results_dir(prefix):
    """A fresh folder under results/ (else the system's temp dir), relative to the workspace."""
    import tempfile
    parent = os.path.join(WS, "results")
    d = tempfile.mkdtemp(prefix=prefix, dir=parent) if os.path.isdir(parent) else tempfile.mkdtemp(prefix=prefix)
    return os.path.relpath(d, WS)
