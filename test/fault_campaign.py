#!/usr/bin/python3
"""Fault and bad-input campaign: every node, loader and command-line tool of the stack, tried
with wrong types, ranges, paths, broken robot folders, signals and malformed messages, as a new
user and an unlucky operator would. Counts crashes, hangs, unsafe outputs and unclear messages.
Goal: 0 / 0 / 0 / 0.

    source devel/setup.bash; test/fault_campaign.py [--quick] [--out DIR] [--phase NAME ...]

One command, its own private ROS master (a free port, wall clock as on the robot). Phases:
  startup   every node and tool started with one bad input: a private parameter of the wrong
            type or out of range, an invalid argument, an unknown key, a config field of the
            wrong type (a sweep over every number and bool of every shipped YAML file, through
            an overlay file that `extends:` it), a range, a missing or unwritable path, a broken
            robot folder (an arm joint or the camera mount joint the URDF lacks, frames that are
            not links), EHC_ROBOTS_DIR with only the user's robot, `extends:` from another folder;
            and every node with its shipped config (it must start, then stop on SIGINT);
  params    a command-line private parameter applies to its run only (_mode:=tsmm, the node
            killed with SIGKILL, started again without it);
  lockstep  the simulator's acknowledgement gate with one far-future /sim/lockstep_ack;
  signals   SIGTERM / SIGINT to ehc_experiment (partial results, exit 143 / 130); full run:
            Ctrl-C and a node's death in demo.sh;
  runtime   the running stack (controller on its timer with obstacles required, the obstacle,
            grasp and tag nodes, rm_arm_adapter) with a healthy robot played around it (this
            script: /joint_states + /odom at 50 Hz, a target 1 m ahead, a depth cloud at 5 Hz),
            each case breaking one input for a few seconds, then a probe with healthy inputs.

Counted, per case:
  crash    a process died of a signal it was not sent (SIGSEGV, ...), or a running node exited;
  hang     a program neither exited nor reported ready within 60 s, did not exit within 5 s of
           SIGINT (or of the end of a demo run), or a node gives no sign of life within 5 s of
           healthy input after a runtime case (controller: /ehc/status, obstacle node:
           /ehc/obstacles, adapter: /arm/adapter_status; tag and grasp nodes: alive);
  unsafe   a non-finite value in /cmd_vel, /arm/joint_velocity_cmd, /rm_driver/JointPos or
           /ehc/obstacles; a JointPos frame more than 10 deg from the previous one of its stream
           (a stream restarts, from the measured position, after a gap); a non-zero
           command later than the watchdog timeout + 0.1 s after a fault that must stop the robot
           (state, target: 0.2 + 0.1 s; obstacles: 0.5 + 0.1 s); sim time moving while a node of
           the lock-step gate is silent; an earlier run's private parameter in force;
  unclear  a start-up failure whose message does not name the file, field, parameter or argument
           at fault; an abort (SIGABRT, rc 134, "terminate called"); a bad input accepted
           silently; a valid input rejected; an error that came after work had begun (a progress
           line first); a signal that did not give the documented result (exit code, partial
           results).
Also measured: the watchdog latency in timer mode per lost input, the obstacle list's longest
gap under huge clouds, demo.sh's exit time after Ctrl-C and after a node's death.
Writes DIR/campaign.json and DIR/campaign.md (default build/fault_campaign). Exit 0 iff 0/0/0/0.
--quick: a reduced set (one sweep field per file, one case per kind; under 3 min on 2 cores), as
the test suite runs it (src/ehc_realman/test/fault_campaign.test).
"""
import argparse
import concurrent.futures
import json
import math
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time

import yaml

WS = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
CONFIG = os.path.join(WS, "config")
KINDS = ("crashes", "hangs", "unsafe", "unclear")
# s after the fault began: the controller's watchdog timeout (config/control/controller.yaml:
# state_timeout and target_timeout 0.2 s, obstacle_timeout 0.5 s) + one cycle + margin. The stop is
# judged in the controller's own cycles, so that a loaded machine (late cycles) cannot fail it: after
# the fault, at most grace x (the command rate measured in the healthy second before it) + 1 non-zero
# commands per stream, and none later than STOP_HARD_LIMIT x grace on the wall clock.
MUST_STOP_GRACE = 0.3
OBSTACLE_STOP_GRACE = 0.6
STOP_HARD_LIMIT = 3.0
PROBE_TIMEOUT = 5.0    # s of healthy input within which every node must show life again
STARTUP_TIMEOUT = 60.0  # s for a node restarted after the case (killed on purpose): its start-up
STOP_LIMIT = 5.0       # s a program has to exit after SIGINT
ARM_READY = [0.0, 0.5, -1.9, 0.0, -0.5, 0.0]  # the arm joint positions this script publishes
READY = "private parameters:"  # logged by every node once its start-up is done (ehc_common::checkNodeParams)
PROGRESS = re.compile(r"\bETA\b")  # a progress line of a long tool: its work has begun


def free_port():
    for p in range(11900, 12100):
        s = socket.socket()
        try:
            s.bind(("127.0.0.1", p))
            s.close()
            return p
        except OSError:
            s.close()
    raise RuntimeError("no free port")


def default_sigint():
    """In the child: SIGINT as a terminal's Ctrl-C would find it (a test runner may ignore it)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def issue(kind, text):
    return {"kind": kind, "text": text}


# ================================================================== programs started once
class Outcome:
    """What one program did: exit code (negative: the signal), output, whether it reported ready."""

    def __init__(self):
        self.rc = None
        self.out = ""
        self.ready = False
        self.timed_out = False
        self.stop_hung = False
        self.stopped = False  # we sent SIGINT (after ready)
        self.seconds = 0.0


def launch(cmd, log_path, env=None, ready=None, limit=STARTUP_TIMEOUT, on_output=None):
    """Runs `cmd` from the workspace. Waits until it exits, or (with `ready`) until that text is in
    its output: then SIGINT and up to STOP_LIMIT s for it to exit. `on_output(proc, text)` is
    called with the output so far (it may signal the process)."""
    o = Outcome()
    t0 = time.monotonic()
    with open(log_path, "w") as log:  # line-buffered: a node's "ready" line is seen at once
        p = subprocess.Popen(["stdbuf", "-oL", "-eL"] + cmd, cwd=WS, env=env, stdout=log, stderr=subprocess.STDOUT,
                             start_new_session=True, preexec_fn=default_sigint)
    read = lambda: open(log_path, errors="replace").read()  # noqa: E731
    while p.poll() is None:
        text = read()
        if on_output:
            on_output(p, text)
        if ready and ready in text:
            o.ready = True
            break
        if time.monotonic() - t0 > limit:
            o.timed_out = True
            break
        time.sleep(0.05)
    if p.poll() is None:
        o.stopped = True
        os.killpg(p.pid, signal.SIGINT)
        try:
            p.wait(STOP_LIMIT)
        except subprocess.TimeoutExpired:
            o.stop_hung = not o.timed_out
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
    o.rc = p.returncode
    o.out = read()
    o.seconds = time.monotonic() - t0
    return o


def message_of(out):
    """The line that says what went wrong (FATAL / error / the last line), colours removed."""
    lines = [re.sub(r"\x1b\[[0-9;]*m", "", ln).strip() for ln in out.splitlines()]
    lines = [ln for ln in lines if ln]
    for ln in lines:
        if "FATAL" in ln or ": error" in ln.lower() or ln.startswith(("ehc_", "demo.sh:", "run_realman.sh:")):
            if "usage:" not in ln:
                return ln[:600]
    return lines[-1][:600] if lines else ""


def judge(case, o):
    """Issues of one start-up / tool case (see the file comment)."""
    found = []
    out = o.out
    sig = -o.rc if o.rc is not None and o.rc < 0 else None
    aborted = sig == signal.SIGABRT or o.rc == 134 or "terminate called" in out
    if o.timed_out:
        found.append(issue("hangs", "neither exited nor got ready within %.0f s" % STARTUP_TIMEOUT))
    if o.stop_hung:
        found.append(issue("hangs", "did not exit within %.0f s of SIGINT" % STOP_LIMIT))
    if aborted:
        found.append(issue("unclear", "aborted (SIGABRT / rc 134)"))
    elif sig and not (o.stopped and sig in (signal.SIGINT, signal.SIGKILL)):
        found.append(issue("crashes", "killed by signal %d" % sig))
    expect = case.get("expect", "error")
    if expect == "error" and not o.timed_out and not aborted:
        if o.ready or o.rc == 0:
            found.append(issue("unclear", "bad input accepted silently"))
        elif o.rc is not None and o.rc > 0:
            missing = [n for n in case.get("names", []) if n not in out]
            if missing:
                found.append(issue("unclear", "the message does not name %s" % ", ".join(repr(m) for m in missing)))
            first_error = out.find(message_of(out)[:40]) if message_of(out) else len(out)
            if PROGRESS.search(out[:max(first_error, 0)]):
                found.append(issue("unclear", "the error came after the work had begun"))
    elif expect == "ready" and not o.ready and not o.timed_out and not aborted and sig is None:
        found.append(issue("unclear", "a valid input was rejected (rc %s)" % o.rc))
    elif expect == "ok" and o.rc != 0 and not aborted and not o.timed_out:
        found.append(issue("unclear", "a valid input was rejected (rc %s)" % o.rc))
    for check in case.get("checks", []):
        found += check(o)
    return found


# ================================================================== start-up and tool cases
def rosrun(pkg, exe, *args):
    return ["rosrun", pkg, exe] + list(args)


def node(pkg, exe, *args):
    """A node case command (its name is made unique per case by the runner)."""
    return {"cmd": rosrun(pkg, exe, *args), "node": True}


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)
    return path


def overlay(path, base, patch):
    """A YAML file that `extends:` `base` (absolute) and sets `patch` (a nested mapping)."""
    return write(path, "extends: %s\n%s" % (base, yaml.safe_dump(patch, default_flow_style=False)))


def nested(keys, value):
    d = value
    for k in reversed(keys):
        d = {k: d}
    return d


def leaves(tree, prefix=()):
    """(keys, value) of every number and bool of a YAML mapping, lists excluded (an overlay
    replaces a list whole)."""
    out = []
    for k, v in (tree or {}).items():
        if k == "extends":
            continue
        if isinstance(v, dict):
            out += leaves(v, prefix + (k,))
        elif isinstance(v, (bool, int, float)):
            out.append((prefix + (k,), v))
    return out


def sweep_program(rel, path, tmp):
    """The command that loads config file `path` (an overlay of config/`rel`), and the overlay's
    own path when the program needs another file around it (a camera through a robot)."""
    P = lambda *a: node(*a)  # noqa: E731
    if rel.endswith("controller.yaml"):
        return P("ehc_control", "ehc_controller_node", "_config:=" + path)
    if "grasp_sequencer" in rel or "grasp_single" in rel:
        return P("ehc_bringup", "ehc_grasp_sequencer_node", "_config:=" + path)
    if rel.endswith("obstacle_node.yaml"):
        return P("ehc_perception", "ehc_obstacle_node", "_config:=" + path)
    if "/tag_" in "/" + rel:
        return P("ehc_perception", "ehc_tag_node", "_config:=" + path)
    if rel.endswith("grasp_node.yaml"):
        return P("ehc_perception", "ehc_grasp_node", "_config:=" + path)
    if rel.endswith("rm_arm_adapter.yaml"):
        return P("ehc_realman", "rm_arm_adapter", "_config:=" + path)
    if rel.endswith("water2_base_bridge.yaml"):
        return P("ehc_realman", "water2_base_bridge", "_config:=" + path)
    if rel.endswith("hardware_standin.yaml"):
        return P("ehc_sim", "ehc_hardware_standin_node", "_config:=" + path)
    if rel.endswith("bullet_sim.yaml"):
        return P("ehc_sim", "ehc_sim_node", "_config:=" + path)
    if rel.endswith("kinematic_sim.yaml"):
        return P("ehc_sim", "ehc_kinematic_sim_node", "_config:=" + path)
    if rel.startswith("scenes/"):
        return P("ehc_sim", "ehc_sim_node", "_config:=config/sim/bullet_sim.yaml", "_scene:=" + path)
    if rel.endswith("robot.yaml"):
        return {"cmd": rosrun("ehc_control", "ehc_kinematics", "--robot", path, "--summary")}
    if rel.endswith("camera.yaml"):  # read by the controller through the robot's camera_info
        robot = overlay(path[:-5] + "_robot.yaml", os.path.join(CONFIG, os.path.dirname(rel), "robot.yaml"),
                        {"robot": {"camera_info": path}})
        return P("ehc_control", "ehc_controller_node", "_config:=config/realman/controller.yaml", "_robot:=" + robot)
    return None


def sweep_cases(tmp, quick):
    """Every number / bool field of every shipped YAML file set to the wrong type, one at a time,
    through an overlay file; the error must name the overlay and the field. Quick: the first
    field of each file. Full: also every number set to NaN, and one misspelled key per file
    (the first field's name with a typo)."""
    cases = []
    for root, _, files in os.walk(CONFIG):
        for f in sorted(files):
            if not f.endswith(".yaml"):
                continue
            rel = os.path.relpath(os.path.join(root, f), CONFIG)
            with open(os.path.join(CONFIG, rel)) as fh:
                fields = leaves(yaml.safe_load(fh))
            variants = []
            for keys, value in fields[:1] if quick else fields:
                variants.append((keys, "maybe" if isinstance(value, bool) else "abc"))
                if not quick and not isinstance(value, bool):
                    variants.append((keys, float("nan")))
            if fields and not quick:
                keys = fields[0][0]
                variants.append((keys[:-1] + (str(keys[-1]) + "_typo",), fields[0][1]))
            for i, (keys, bad) in enumerate(variants):
                path = os.path.join(tmp, "sweep", rel.replace("/", "__")[:-5] + "__%d.yaml" % i)
                overlay(path, os.path.join(CONFIG, rel), nested(keys, bad))
                prog = sweep_program(rel, path, tmp)
                if prog is None:
                    continue
                field = ".".join(str(k) for k in keys)
                cases.append(dict(prog, name="sweep %s: %s = %s" % (rel, field, bad), names=[path, "'" + field + "'"]))
    return cases


def robot_folders(tmp):
    """Broken and user robot folders: overlays of the RealMan's robot.yaml (its URDF resolved
    against the shipped folder), and EHC_ROBOTS_DIR with only the user's robot."""
    shipped = os.path.join(CONFIG, "robots", "realman_rm65_water2", "robot.yaml")
    joints = ["joint1", "joint2", "joint3", "joint4", "joint5", "joint7"]
    r = {
        "arm_joint": overlay(os.path.join(tmp, "robots", "arm_joint", "robot.yaml"), shipped,
                             {"robot": {"arm": {"joints": joints}}}),
        "mount": overlay(os.path.join(tmp, "robots", "mount", "robot.yaml"), shipped,
                         {"robot": {"calibration": {"camera": {"joint": "no_camera_mount"}}}}),
        "tcp": overlay(os.path.join(tmp, "robots", "tcp", "robot.yaml"), shipped,
                       {"robot": {"frames": {"tcp": "no_tcp_link"}}}),
        "camera": overlay(os.path.join(tmp, "robots", "camera", "robot.yaml"), shipped,
                          {"robot": {"frames": {"camera_optical": "no_camera_link"}}}),
        "urdf": overlay(os.path.join(tmp, "robots", "urdf", "robot.yaml"), shipped,
                        {"robot": {"urdf": "missing.urdf"}}),
    }
    user = os.path.join(tmp, "user_robots")
    if not os.path.isdir(os.path.join(user, "my_robot")):
        shutil.copytree(os.path.join(CONFIG, "robots", "kuka_iiwa14_kmr"), os.path.join(user, "my_robot"))
    r["user_dir"] = user
    return r


def node_cases(tmp):
    """Nodes: the issue's cases, private parameters, arguments, ranges, paths, robot folders."""
    R = robot_folders(tmp)
    ctrl = lambda *a: node("ehc_control", "ehc_controller_node", *a)  # noqa: E731
    real = "_config:=config/realman/controller.yaml"
    other = os.path.join(tmp, "elsewhere")
    c = []
    add = lambda case, **kw: c.append(dict(case, **kw))  # noqa: E731
    # A misspelled key with the lock-step trigger (the demo's config) and with the timer.
    for base in ("demo/controller.yaml", "realman/controller.yaml"):
        p = overlay(os.path.join(tmp, "typo", base.replace("/", "_")), os.path.join(CONFIG, base),
                    {"controller": {"arm_wieght": 0.01}})
        add(ctrl("_config:=" + p), name="controller: misspelled key, %s" % base, names=[p, "controller.arm_wieght"],
            quick=True)
    add(ctrl(real, "[_mode:=ehc"), name="controller: pasted usage notation [_mode:=ehc", names=["[_mode"], quick=True)
    for arg, names in [("_require_obstacles:=maybe", ["_require_obstacles"]), ("_mpbs:=maybe", ["_mpbs"]),
                       ("_target_timeout:=abc", ["_target_timeout"]), ("_target_timeout:=-1", ["target_timeout", "_target_timeout:=-1"]),
                       ("_mode:=bogus", ["_mode", "bogus"]), ("_servo:=pid", ["_servo", "pid"]),
                       ("_trigger:=sometimes", ["_trigger"]), ("_mdoe:=tsmm", ["_mdoe"]),
                       ("_robot:=nobody", ["_robot", "nobody"]), ("_config:=", ["_config"])]:
        add(ctrl(real, arg) if not arg.startswith("_config") else ctrl(arg), name="controller: " + arg, names=names,
            quick=arg.split(":=")[0] in ("_require_obstacles", "_mdoe", "_target_timeout") or arg == "_mode:=bogus")
    add(ctrl(), name="controller: no _config", names=["_config"])
    add(ctrl("_config:=/nonexistent/controller.yaml"), name="controller: missing config file",
        names=["/nonexistent/controller.yaml"], quick=True)
    p = overlay(os.path.join(tmp, "range", "rate.yaml"), os.path.join(CONFIG, "realman/controller.yaml"), {"node": {"rate": 5000}})
    add(ctrl("_config:=" + p), name="controller: node.rate 5000", names=[p, "node.rate"], quick=True)
    p = overlay(os.path.join(tmp, "range", "nan.yaml"), os.path.join(CONFIG, "realman/controller.yaml"),
                {"weighting": {"sig_gain": float("nan")}})
    add(ctrl("_config:=" + p), name="controller: NaN in the config", names=[p, "weighting.sig_gain"])
    # extends: from another folder: the base's relative robot path stays the base's.
    p = overlay(os.path.join(other, "controller.yaml"), os.path.join(CONFIG, "realman/controller.yaml"), {"controller": {"mode": "neo_e"}})
    add(ctrl("_config:=" + p), name="controller: extends from another folder", expect="ready", quick=True)
    # EHC_ROBOTS_DIR with only the user's robot: the generic config's default robot still found.
    add(ctrl("_config:=config/control/controller.yaml", "_robot:=my_robot"), name="controller: EHC_ROBOTS_DIR with only the user's robot",
        env={"EHC_ROBOTS_DIR": R["user_dir"]}, expect="ready", quick=True)
    add(ctrl("_config:=config/control/controller.yaml", "_trigger:=timer"), name="controller: generic config on its timer",
        expect="ready")
    # Robot folders.
    add(ctrl(real, "_robot:=" + R["urdf"]), name="controller: robot.urdf missing", names=[R["urdf"], "robot.urdf"])
    ks = lambda *a: node("ehc_sim", "ehc_kinematic_sim_node", "_config:=config/sim/kinematic_sim.yaml", *a)  # noqa: E731
    add(ks("_robot:=" + R["arm_joint"]), name="kinematic sim: arm joint not in the URDF", names=[R["arm_joint"], "robot.arm.joints", "joint7"],
        quick=True)
    add(ks("_robot:=" + R["mount"]), name="kinematic sim: camera mount joint not in the URDF",
        names=[R["mount"], "robot.calibration.camera.joint", "no_camera_mount"], quick=True)
    add(ks("_seed:=abc"), name="kinematic sim: _seed:=abc", names=["_seed"], quick=True)
    add(ks("_seed:=-3"), name="kinematic sim: _seed:=-3", names=["_seed"])
    add(ks("_free_run:=yes_please"), name="kinematic sim: _free_run:=yes_please", names=["_free_run"])
    seq = lambda *a: node("ehc_bringup", "ehc_grasp_sequencer_node", "_config:=config/demo/grasp_sequencer.yaml", *a)  # noqa: E731
    add(seq("_robot:=" + R["tcp"]), name="sequencer: robot frames.tcp not in the URDF", names=[R["tcp"], "robot.frames.tcp"], quick=True)
    add(seq("_robot:=" + R["camera"]), name="sequencer: robot frames.camera_optical not in the URDF",
        names=[R["camera"], "robot.frames.camera_optical"])
    p = overlay(os.path.join(tmp, "seq", "tcp.yaml"), os.path.join(CONFIG, "demo/grasp_sequencer.yaml"), {"node": {"tcp_frame": "no_link"}})
    add(node("ehc_bringup", "ehc_grasp_sequencer_node", "_config:=" + p), name="sequencer: node.tcp_frame not in the URDF",
        names=[p, "node.tcp_frame"])
    add(seq("_exit_when_done:=sometimes"), name="sequencer: _exit_when_done:=sometimes", names=["_exit_when_done"])
    sim = lambda *a: node("ehc_sim", "ehc_sim_node", "_config:=config/sim/bullet_sim.yaml", *a)  # noqa: E731
    add(sim("_lockstep_acks:=[tag, grasp:depth]"), name="sim: unknown ack stream", names=["grasp:depth"], quick=True)
    add(sim("_lockstep_max_lag:=99"), name="sim: _lockstep_max_lag:=99", names=["max lag"])
    add(sim("_scene:=/nonexistent/scene.yaml"), name="sim: missing scene", names=["/nonexistent/scene.yaml"])
    add(sim("_robot:=" + R["arm_joint"]), name="sim: arm joint not in the URDF", names=[R["arm_joint"], "robot.arm.joints"])
    add(node("ehc_sim", "ehc_hardware_standin_node", "_config:=config/realman/hardware_standin.yaml", "_port:=http"),
        name="hardware stand-in: _port:=http", names=["_port"])
    w2 = lambda *a: node("ehc_realman", "water2_base_bridge", "_config:=config/realman/water2_base_bridge.yaml", *a)  # noqa: E731
    add(w2("_port:=http"), name="water2 bridge: _port:=http", names=["_port"], quick=True)
    add(w2("_port:=70000"), name="water2 bridge: _port:=70000", names=["_port"])
    add(w2("_host:=5"), name="water2 bridge: _host:=5", names=["_host"])
    add(node("ehc_realman", "rm_arm_adapter", "_config:=config/realman/rm_arm_adapter.yaml", "_status_every_step:=often"),
        name="rm_arm_adapter: _status_every_step:=often", names=["_status_every_step"])
    add(node("ehc_realman", "rm_arm_adapter"), name="rm_arm_adapter: no _config", names=["_config"])
    p = overlay(os.path.join(tmp, "range", "obstacle.yaml"), os.path.join(CONFIG, "perception/obstacle_node.yaml"),
                {"node": {"publish_rate_hz": 0}})
    add(node("ehc_perception", "ehc_obstacle_node", "_config:=" + p), name="obstacle node: node.publish_rate_hz 0",
        names=[p, "node.publish_rate_hz"], quick=True)
    add(node("ehc_perception", "ehc_obstacle_node", "_config:=config/perception/obstacle_node.yaml", "_robot:=" + R["tcp"]),
        name="obstacle node: broken robot folder", names=[R["tcp"], "robot.frames.tcp"])
    add(node("ehc_perception", "ehc_tag_node", "_config:=config/perception/tag_node.yaml", "_ack_topic:=5"),
        name="tag node: _ack_topic:=5", names=["_ack_topic"])
    add(node("ehc_perception", "ehc_grasp_node"), name="grasp node: no _config", names=["_config"])
    return c


def shipped_node_cases():
    """Every node with its shipped config: starts (reports ready), then exits on SIGINT."""
    out = []
    for pkg, exe, cfg, quick in [
            ("ehc_control", "ehc_controller_node", "config/realman/controller.yaml", True),
            ("ehc_control", "ehc_controller_node", "config/demo/controller.yaml", False),
            ("ehc_sim", "ehc_sim_node", "config/sim/bullet_sim.yaml", True),
            ("ehc_sim", "ehc_kinematic_sim_node", "config/sim/kinematic_sim.yaml", True),
            ("ehc_sim", "ehc_hardware_standin_node", "config/realman/hardware_standin.yaml", False),
            ("ehc_perception", "ehc_tag_node", "config/perception/tag_node.yaml", True),
            ("ehc_perception", "ehc_grasp_node", "config/perception/grasp_node.yaml", True),
            ("ehc_perception", "ehc_obstacle_node", "config/perception/obstacle_node.yaml", True),
            ("ehc_bringup", "ehc_grasp_sequencer_node", "config/demo/grasp_sequencer.yaml", True),
            ("ehc_realman", "rm_arm_adapter", "config/realman/rm_arm_adapter.yaml", True),
            ("ehc_realman", "water2_base_bridge", "config/realman/water2_base_bridge.yaml", True)]:
        out.append(dict(node(pkg, exe, "_config:=" + cfg), name="%s: shipped %s starts and stops on SIGINT" % (exe, cfg),
                        expect="ready", quick=quick))
    return out


def tool_cases(tmp):
    """Command-line tools and scripts (no master needed)."""
    R = robot_folders(tmp)
    tool = lambda pkg, exe, *a: {"cmd": rosrun(pkg, exe, *a)}  # noqa: E731
    realman = "realman_rm65_water2"
    c = []
    add = lambda case, **kw: c.append(dict(case, **kw))  # noqa: E731
    kin = lambda *a: tool("ehc_control", "ehc_kinematics", *a)  # noqa: E731
    add(kin("--robot", "nobody", "--summary"), name="ehc_kinematics: unknown robot", names=["nobody"], quick=True)
    add(kin("--robot", realman, "--q", "1,2"), name="ehc_kinematics: --q of 2 values", names=["--q"])
    add(kin("--robot", realman, "--q", "0,0.5,-1.9,0,-0.5,0", "--link", "no_link"), name="ehc_kinematics: unknown link",
        names=["no_link"])
    add(kin("--robot", realman, "--summary", "--bogus", "1"), name="ehc_kinematics: unknown flag", names=["--bogus"])
    add(kin("--robot", R["arm_joint"], "--summary"), name="ehc_kinematics: arm joint not in the URDF",
        names=[R["arm_joint"], "robot.arm.joints"])
    add(kin("--robot", realman, "--summary"), name="ehc_kinematics: EHC_ROBOTS_DIR with only the user's robot, a shipped robot",
        env={"EHC_ROBOTS_DIR": R["user_dir"]}, expect="ok", quick=True)
    add(kin("--robot", "my_robot", "--summary"), name="ehc_kinematics: EHC_ROBOTS_DIR, the user's robot",
        env={"EHC_ROBOTS_DIR": R["user_dir"]}, expect="ok")
    reach = lambda *a: tool("ehc_control", "ehc_reachability", "--robot", realman, *a)  # noqa: E731
    add(reach("--samples", "abc", "--out", os.path.join(tmp, "map.bin")), name="ehc_reachability: --samples abc", names=["--samples"])
    add(reach("--samples", "20000000", "--out", "/proc/ehc_map.bin"), name="ehc_reachability: unwritable --out",
        names=["/proc/ehc_map.bin"], quick=True)
    exp = lambda *a: tool("ehc_bringup", "ehc_experiment", *a)  # noqa: E731
    add(exp("reach", "--robot", realman, "--sets", "abc", "--out", os.path.join(tmp, "e1")), name="ehc_experiment: --sets abc",
        names=["--sets"])
    add(exp("grasp", "--method", "ehc", "--sets", "1", "--out", "/proc/ehc_exp"), name="ehc_experiment grasp: unwritable --out",
        names=["/proc/ehc_exp"], quick=True)
    add(exp("poses", "--method", "ehc", "--sets", "1", "--per-set", "1", "--out", "/proc/ehc_exp"),
        name="ehc_experiment poses: unwritable --out", names=["/proc/ehc_exp"])
    add(exp("poses", "--method", "tsmm", "--out", os.path.join(tmp, "e3")), name="ehc_experiment poses: unknown method",
        names=["tsmm"])
    p = overlay(os.path.join(tmp, "range", "exp_rate.yaml"), os.path.join(CONFIG, "control/controller.yaml"), {"node": {"rate": 5000}})
    add(exp("reach", "--robot", realman, "--sets", "1", "--points", "1", "--config", p, "--out", os.path.join(tmp, "e1")),
        name="ehc_experiment reach: --config with node.rate 5000", names=[p, "node.rate"])
    # --config-dir: the shipped folders, the demo's obstacle file with publish_rate_hz 0.
    cdir = os.path.join(tmp, "config_dir")
    if not os.path.isdir(cdir):
        os.makedirs(cdir)
        for sub in os.listdir(CONFIG):
            if sub != "demo":
                os.symlink(os.path.join(CONFIG, sub), os.path.join(cdir, sub))
        shutil.copytree(os.path.join(CONFIG, "demo"), os.path.join(cdir, "demo"))
        overlay(os.path.join(cdir, "demo", "obstacle_node.yaml"), os.path.join(CONFIG, "demo", "obstacle_node.yaml"),
                {"node": {"publish_rate_hz": 0}})
    add(exp("grasp", "--method", "ehc", "--sets", "1", "--config-dir", cdir, "--out", os.path.join(tmp, "e2")),
        name="ehc_experiment grasp: --config-dir with publish_rate_hz 0",
        names=[os.path.join(cdir, "demo", "obstacle_node.yaml"), "node.publish_rate_hz"], quick=True)
    add(exp("reach", "--robot", "my_robot", "--method", "ehc", "--sets", "1", "--points", "1", "--out", os.path.join(tmp, "e_user")),
        name="ehc_experiment reach: EHC_ROBOTS_DIR with only the user's robot", env={"EHC_ROBOTS_DIR": R["user_dir"]},
        expect="ok", quick=True)
    det = lambda *a: tool("ehc_perception", "ehc_detect_tags", *a)  # noqa: E731
    add(det("--image", "/nonexistent.png", "--camera", "config/robots/realman_rm65_water2/camera.yaml", "--tag-size", "0.04"),
        name="ehc_detect_tags: missing image", names=["/nonexistent.png"])
    add(det("--image", "x.png", "--camera", "c.yaml", "--tag-size", "big"), name="ehc_detect_tags: --tag-size big", names=["--tag-size"])
    gr = lambda *a: tool("ehc_perception", "ehc_grasps", *a)  # noqa: E731
    add(gr("--cloud", "/nonexistent.pcd", "--out", os.path.join(tmp, "g.json")), name="ehc_grasps: missing cloud",
        names=["/nonexistent.pcd"])
    add(gr("--cloud", "c.pcd", "--out", "g.json", "--top", "0"), name="ehc_grasps: --top 0", names=["--top"])
    demo = os.path.join(WS, "src", "ehc_bringup", "scripts", "demo.sh")
    add({"cmd": [demo]}, name="demo.sh: EHC_DEMO_PORT=abc", env={"EHC_DEMO_PORT": "abc", "OUT": os.path.join(tmp, "demo")},
        names=["EHC_DEMO_PORT", "abc"], quick=True)
    add({"cmd": [demo]}, name="demo.sh: unwritable OUT", env={"OUT": "/proc/ehc_demo"}, names=["OUT=/proc/ehc_demo"], quick=True)
    add({"cmd": [demo]}, name="demo.sh: unknown robot", env={"ROBOT": "nobody", "OUT": os.path.join(tmp, "demo")}, names=["nobody"])
    rr = os.path.join(WS, "src", "ehc_realman", "scripts", "run_realman.sh")
    add({"cmd": [rr, "--dry-run", "bogus"]}, name="run_realman.sh: unknown component", names=["bogus"])
    add({"cmd": [rr, "--dry-run", "controller"]}, name="run_realman.sh: missing CONTROLLER_CONFIG",
        env={"CONTROLLER_CONFIG": "/nonexistent/c.yaml"}, names=["/nonexistent/c.yaml"])
    add({"cmd": [rr, "--dry-run", "controller"]}, name="run_realman.sh: a lock-step config runs on the timer",
        env={"CONTROLLER_CONFIG": "config/control/controller.yaml"}, expect="ok",
        checks=[lambda o: [] if "_trigger:=timer" in o.out else [issue("unclear", "no _trigger:=timer in " + o.out[-200:])]])
    return c


def run_cases(cases, log_dir, workers=2):
    """Runs start-up / tool cases, two at a time; node cases get a unique name."""
    def one(i_case):
        i, case = i_case
        cmd = list(case["cmd"])
        if case.get("node"):
            cmd.append("__name:=fault_campaign_%d" % i)
        env = dict(os.environ)
        env.update(case.get("env", {}))
        o = launch(cmd, os.path.join(log_dir, "case_%03d.log" % i), env=env,
                   ready=READY if case.get("node") else None)
        found = judge(case, o)
        return {"case": case["name"], "phase": "startup", "issues": found, "rc": o.rc, "ready": o.ready,
                "seconds": round(o.seconds, 2), "message": message_of(o.out),
                "log": os.path.join(log_dir, "case_%03d.log" % i)}
    with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(one, enumerate(cases)))


def params_phase(log_dir):
    """A command-line private parameter applies to its run only: _mode:=tsmm, the node killed
    with SIGKILL (no clean shutdown), then started again without it."""
    name = "fault_campaign_stale"
    base = rosrun("ehc_control", "ehc_controller_node", "_config:=config/realman/controller.yaml",
                  "_require_obstacles:=false", "__name:=" + name)
    found = []
    log1 = os.path.join(log_dir, "params_1.log")
    with open(log1, "w") as log:
        p = subprocess.Popen(["stdbuf", "-oL", "-eL"] + base + ["_mode:=tsmm"], cwd=WS, stdout=log, stderr=subprocess.STDOUT,
                             start_new_session=True, preexec_fn=default_sigint)
    t0 = time.monotonic()
    while READY not in open(log1, errors="replace").read() and p.poll() is None and time.monotonic() - t0 < STARTUP_TIMEOUT:
        time.sleep(0.05)
    first = open(log1, errors="replace").read()
    if "_mode:=tsmm (command line)" not in first:
        found.append(issue("unclear", "the run with _mode:=tsmm did not say so"))
    left = subprocess.run(["rosparam", "get", "/%s/mode" % name], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                          universal_newlines=True)
    os.killpg(p.pid, signal.SIGKILL)
    p.wait()
    if left.returncode == 0:
        found.append(issue("unsafe", "_mode stays on the parameter server while the node runs: %s" % left.stdout.strip()))
    o = launch(base, os.path.join(log_dir, "params_2.log"), ready=READY)
    line = [ln for ln in o.out.splitlines() if READY in ln]
    if not o.ready:
        found.append(issue("unclear", "the second run did not start: " + message_of(o.out)))
    elif "_mode" in (line[0] if line else "") or "mode tsmm" in o.out:
        found.append(issue("unsafe", "the earlier run's _mode:=tsmm is in force: " + (line[0] if line else "")))
    found += judge({"expect": "ready"}, o)
    return [{"case": "params: a command-line private parameter applies to its run only (SIGKILL, then a run without it)",
             "phase": "params", "issues": found, "message": line[0].strip() if line else ""}]


def lockstep_phase(log_dir):
    """The simulator's acknowledgement gate with this script as a state-consuming node: after a
    few properly acknowledged states it sends one acknowledgement 1000 s ahead and then none;
    sim time must stay within one step of the last acknowledged state (the gate stays closed)."""
    import rospy
    from rosgraph_msgs.msg import Clock
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Header
    subprocess.call(["rosparam", "set", "/use_sim_time", "true"])
    gate = "fault_campaign_gate"
    procs = []
    for name, cmd in [("sim", rosrun("ehc_sim", "ehc_sim_node", "_config:=config/sim/bullet_sim.yaml",
                                     "_lockstep_acks:=[%s:state]" % gate, "__name:=fault_campaign_lockstep_sim")),
                      ("controller", rosrun("ehc_control", "ehc_controller_node", "_config:=config/control/controller.yaml",
                                            "_require_obstacles:=false", "__name:=fault_campaign_lockstep_controller"))]:
        log = open(os.path.join(log_dir, "lockstep_%s.log" % name), "w")
        procs.append(subprocess.Popen(["stdbuf", "-oL", "-eL"] + cmd, cwd=WS, stdout=log, stderr=subprocess.STDOUT,
                                      start_new_session=True, preexec_fn=default_sigint))
    state = {"clock": None, "stamp": None, "acking": True}
    pub = rospy.Publisher("/sim/lockstep_ack", Header, queue_size=50)

    def ack(stamp):
        h = Header()
        h.stamp = stamp
        h.frame_id = gate
        pub.publish(h)

    def on_state(m):
        state["stamp"] = m.header.stamp
        if state["acking"]:
            ack(m.header.stamp)
    subs = [rospy.Subscriber("/clock", Clock, lambda m: state.update(clock=m.clock.to_sec()), queue_size=10),
            rospy.Subscriber("/joint_states", JointState, on_state, queue_size=10)]
    found = []
    try:
        t0 = time.monotonic()
        while state["stamp"] is None and time.monotonic() - t0 < STARTUP_TIMEOUT:
            ack(rospy.Time(0))  # "ready"
            time.sleep(0.2)
        if state["stamp"] is None:
            found.append(issue("hangs", "the gated simulator published no state within %.0f s" % STARTUP_TIMEOUT))
            return [{"case": "lockstep: a far-future acknowledgement", "phase": "lockstep", "issues": found}]
        t1 = time.monotonic()
        while time.monotonic() - t1 < 2.0:
            time.sleep(0.05)
        running = state["clock"]
        state["acking"] = False
        time.sleep(0.2)
        held = state["stamp"]
        ack(held + rospy.Duration(1000.0))  # one stray, far-future acknowledgement
        time.sleep(2.0)
        advance = state["clock"] - held.to_sec()
        if running is None or running <= 1.0:
            found.append(issue("hangs", "sim time did not run while acknowledged"))
        if advance > 0.05:
            found.append(issue("unsafe", "sim time ran %.2f s past the last acknowledged state (the gate opened)" % advance))
        state["acking"] = True
        ack(state["stamp"])
        time.sleep(1.0)
        if state["clock"] - held.to_sec() < 0.02:
            found.append(issue("hangs", "sim time did not resume with acknowledgements"))
        return [{"case": "lockstep: one far-future /sim/lockstep_ack, then silence", "phase": "lockstep", "issues": found,
                 "message": "sim time %.2f s past the last acknowledged state after 2 s of silence" % advance}]
    finally:
        for s in subs:
            s.unregister()
        for p in procs:
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGINT)
                try:
                    p.wait(STOP_LIMIT)
                except subprocess.TimeoutExpired:
                    found.append(issue("hangs", "a lock-step node did not exit within %.0f s of SIGINT" % STOP_LIMIT))
                    os.killpg(p.pid, signal.SIGKILL)
                    p.wait()
            elif p.returncode != 0:
                found.append(issue("crashes", "a lock-step node exited with %d" % p.returncode))
        subprocess.call(["rosparam", "set", "/use_sim_time", "false"])


def experiment_stop_case(tmp, log_dir, command, sig, after):
    """ehc_experiment `command` gets `sig` after the first progress line matching `after`: exit
    128 + sig, summary.json saying partial."""
    out = os.path.join(tmp, "stop_" + command[0])
    shutil.rmtree(out, ignore_errors=True)
    sent = {"done": False}

    def on_output(p, text):
        if not sent["done"] and re.search(after, text):
            os.killpg(p.pid, sig)
            sent["done"] = True
    o = launch(rosrun("ehc_bringup", "ehc_experiment", *command, "--out", out), os.path.join(log_dir, "stop_%s.log" % command[0]),
               on_output=on_output, limit=300.0)
    found = judge({"expect": "any"}, o) if o.rc is None or o.rc >= 0 else []
    if not sent["done"]:
        found.append(issue("unclear", "no progress line to interrupt after"))
    elif o.rc != 128 + sig:
        found.append(issue("unclear", "exit code %s after signal %d (expected %d)" % (o.rc, sig, 128 + sig)))
    try:
        with open(os.path.join(out, "summary.json")) as f:
            s = json.load(f)
        partial = any(m.get("partial") for m in s) if isinstance(s, list) else s.get("partial")
        if not partial:
            found.append(issue("unclear", "summary.json does not say partial"))
    except (OSError, ValueError) as e:
        found.append(issue("unclear", "no partial results: %s" % e))
    return {"case": "signals: ehc_experiment %s, %s after the first progress line" % (command[0], signal.Signals(sig).name),
            "phase": "signals", "issues": found, "rc": o.rc, "message": message_of(o.out)}


def demo_stop_case(tmp, log_dir, how):
    """demo.sh interrupted as a terminal's Ctrl-C does (SIGINT to its process group), or one of
    its nodes killed, once the first object's approach began: every process it started must be
    gone within STOP_LIMIT s; exit 130 / 2."""
    out = os.path.join(tmp, "demo_" + how)
    env = dict(os.environ, OUT=out)
    for k in ("ROS_MASTER_URI", "ROS_HOME", "ROS_LOG_DIR"):
        env.pop(k, None)  # its own master
    log_path = os.path.join(log_dir, "demo_%s.log" % how)
    with open(log_path, "w") as log:
        p = subprocess.Popen([os.path.join(WS, "src/ehc_bringup/scripts/demo.sh")], cwd=WS, env=env, stdout=log,
                             stderr=subprocess.STDOUT, start_new_session=True, preexec_fn=default_sigint)
    found = []
    t0 = time.monotonic()
    while p.poll() is None and "APPROACH ->" not in open(log_path, errors="replace").read():
        if time.monotonic() - t0 > 300:
            found.append(issue("hangs", "the demo did not reach its first approach in 300 s"))
            break
        time.sleep(0.1)
    t_stop = time.monotonic()
    if how == "ctrlc":
        os.killpg(p.pid, signal.SIGINT)
    else:
        tag = subprocess.run(["pgrep", "-s", str(p.pid), "-f", "ehc_tag_node"], stdout=subprocess.PIPE,
                             universal_newlines=True).stdout.split()
        if tag:
            os.kill(int(tag[0]), signal.SIGKILL)
    try:
        p.wait(STOP_LIMIT)
    except subprocess.TimeoutExpired:
        found.append(issue("hangs", "demo.sh did not exit within %.0f s" % STOP_LIMIT))
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
    seconds = time.monotonic() - t_stop
    left = subprocess.run(["pgrep", "-s", str(p.pid)], stdout=subprocess.PIPE, universal_newlines=True).stdout.split()
    if left:
        found.append(issue("hangs", "processes left behind: %s" % " ".join(left)))
        for pid in left:
            try:
                os.kill(int(pid), signal.SIGKILL)
            except OSError:
                pass
    expected = 130 if how == "ctrlc" else 2
    if p.returncode != expected:
        found.append(issue("unclear", "exit code %s (expected %d)" % (p.returncode, expected)))
    return {"case": "signals: demo.sh, %s during the first approach" % ("Ctrl-C" if how == "ctrlc" else "a tag node killed"),
            "phase": "signals", "issues": found, "rc": p.returncode, "exit_s": round(seconds, 2),
            "message": "every process gone %.2f s after the %s" % (seconds, "Ctrl-C" if how == "ctrlc" else "kill")}


# ================================================================== runtime
NODES = {
    "controller": ["ehc_control", "ehc_controller_node", "_config:=config/realman/controller.yaml"],
    "obstacle": ["ehc_perception", "ehc_obstacle_node", "_config:=config/perception/obstacle_node.yaml"],
    "grasp": ["ehc_perception", "ehc_grasp_node", "_config:=config/perception/grasp_node.yaml"],
    "tag": ["ehc_perception", "ehc_tag_node", "_config:=config/perception/tag_node.yaml"],
    "adapter": ["ehc_realman", "rm_arm_adapter", "_config:=config/realman/rm_arm_adapter.yaml"],
}


class Campaign:
    def __init__(self, log_dir):
        import rospy
        from ehc_msgs.msg import ControllerStatus, JointVelocityCommand, ObstacleArray
        from geometry_msgs.msg import PoseStamped, Twist
        from nav_msgs.msg import Odometry
        from rm_msgs.msg import JointPos
        from sensor_msgs.msg import Image, JointState, PointCloud2, PointField
        self.rospy = rospy
        self.M = dict(JointState=JointState, Odometry=Odometry, PoseStamped=PoseStamped,
                      PointCloud2=PointCloud2, PointField=PointField, Image=Image,
                      JointVelocityCommand=JointVelocityCommand)
        self.log_dir = log_dir
        self.procs = {}
        self.lock = threading.Lock()
        self.events = []  # (receipt time, kind, payload)
        self.pub = {
            "joints": rospy.Publisher("/joint_states", JointState, queue_size=10),
            "odom": rospy.Publisher("/odom", Odometry, queue_size=10),
            "target": rospy.Publisher("/ehc/target_pose", PoseStamped, queue_size=10),
            "cloud": rospy.Publisher("/camera/depth/points", PointCloud2, queue_size=2),
            "image": rospy.Publisher("/camera/color/image_raw", Image, queue_size=2),
            "armcmd": rospy.Publisher("/arm/joint_velocity_cmd", JointVelocityCommand, queue_size=10),
        }
        # Clouds come in the world frame (odom): no tf needed (tf2_ros has no Python module here).
        rec = lambda kind: (lambda m: self.record(kind, m))
        self.subs = [
            rospy.Subscriber("/cmd_vel", Twist, rec("cmd_vel"), queue_size=100),
            rospy.Subscriber("/arm/joint_velocity_cmd", JointVelocityCommand, rec("armcmd"), queue_size=100),
            rospy.Subscriber("/rm_driver/JointPos", JointPos, rec("jointpos"), queue_size=200),
            rospy.Subscriber("/ehc/obstacles", ObstacleArray, rec("obstacles"), queue_size=100),
            rospy.Subscriber("/ehc/status", ControllerStatus, rec("status"), queue_size=100),
            rospy.Subscriber("/arm/adapter_status", rospy.AnyMsg, rec("adapter_status"), queue_size=10),
        ]
        self.mode = {"state": "ok", "target": "ok", "cloud": "ok", "cloud_ticks": 10}
        self.cloud_ok = self.make_cloud(points=[(3.0, y * 0.05, z * 0.05) for y in range(-20, 21) for z in range(0, 30)])
        self.running = True
        self.thread = threading.Thread(target=self.feed, daemon=True)

    # ------------------------------------------------------------ nodes
    def start(self, name, command=None):
        """Starts node `name` as NODES says, or with `command` ([package, executable, args...])."""
        pkg, exe, *args = command or NODES[name]
        log = open(os.path.join(self.log_dir, name + ".log"), "a")
        self.procs[name] = subprocess.Popen(["rosrun", pkg, exe] + args, cwd=WS, stdout=log,
                                            stderr=subprocess.STDOUT, start_new_session=True,
                                            preexec_fn=default_sigint)

    def stop(self, name, sig=signal.SIGINT):
        p = self.procs.get(name)
        if p and p.poll() is None:
            os.killpg(p.pid, sig)
            try:
                p.wait(5)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()

    def restart_controller(self, command=None):
        """Restarts the controller (with `command`, else as NODES says) and waits for its first status."""
        self.stop("controller")
        t = time.monotonic()
        self.start("controller", command)
        while not self.window(t, t + STARTUP_TIMEOUT, {"status"}) and time.monotonic() < t + STARTUP_TIMEOUT:
            time.sleep(0.05)

    def dead(self):
        return [n for n, p in self.procs.items() if p.poll() is not None]

    # ------------------------------------------------------------ messages
    def record(self, kind, m):
        if m._connection_header.get("callerid") == self.rospy.get_name():
            return  # our own injected commands are inputs, not outputs
        with self.lock:
            self.events.append((time.monotonic(), kind, m))

    def make_cloud(self, points, fields=None, point_step=None, data=None, width=None, height=1,
                   is_bigendian=False, row_step=None):
        PC, PF = self.M["PointCloud2"], self.M["PointField"]
        c = PC()
        c.header.frame_id = "odom"
        if fields is None:
            fields = [PF("x", 0, PF.FLOAT32, 1), PF("y", 4, PF.FLOAT32, 1), PF("z", 8, PF.FLOAT32, 1)]
        c.fields = fields
        c.point_step = 12 if point_step is None else point_step
        if data is None:
            data = b"".join(struct.pack("<fff", *p) for p in points)
        c.data = data
        c.width = len(points) if width is None else width
        c.height = height
        c.row_step = c.point_step * c.width if row_step is None else row_step
        c.is_bigendian = is_bigendian
        c.is_dense = False
        return c

    def feed(self):
        """The healthy robot (and the current fault) at 50 Hz; clouds at 5 Hz."""
        rospy = self.rospy
        k = 0
        while self.running and not rospy.is_shutdown():
            now = rospy.Time.now()
            st = self.mode["state"]
            if st != "silent":
                js = self.M["JointState"]()
                js.name = ["joint%d" % i for i in range(1, 7)]
                js.position = list(ARM_READY)
                od = self.M["Odometry"]()
                od.header.frame_id, od.child_frame_id = "odom", "base_link"
                od.pose.pose.orientation.w = 1.0
                stamp = now
                if st == "nan":
                    js.position[2] = float("nan")
                    od.pose.pose.position.x = float("nan")
                elif st == "stale_stamp":
                    stamp = now - rospy.Duration(100.0)
                elif st == "future_stamp":
                    stamp = now + rospy.Duration(100.0)
                elif st == "zero_quat":
                    od.pose.pose.orientation.w = 0.0
                elif st == "wrong_names":
                    js.name = ["a", "b", "c", "d", "e", "f"]
                js.header.stamp = od.header.stamp = stamp
                self.pub["joints"].publish(js)
                self.pub["odom"].publish(od)
            tm = self.mode["target"]
            if tm != "silent":
                t = self.M["PoseStamped"]()
                t.header.frame_id = "odom"
                t.header.stamp = now
                t.pose.position.x, t.pose.position.z = 1.5, 0.8
                t.pose.orientation.w = 1.0
                if tm == "nan":
                    t.pose.position.y = float("nan")
                elif tm == "bad_quat":
                    t.pose.orientation.w = 0.0
                elif tm == "wrong_frame":
                    t.header.frame_id = "map"
                self.pub["target"].publish(t)
            if k % self.mode["cloud_ticks"] == 0:
                c = self.mode["cloud"] if not isinstance(self.mode["cloud"], str) else self.cloud_ok
                c.header.stamp = now
                self.pub["cloud"].publish(c)
            k += 1
            time.sleep(0.02)

    # ------------------------------------------------------------ checks
    def window(self, t0, t1, kinds):
        with self.lock:
            return [e for e in self.events if t0 <= e[0] <= t1 and e[1] in kinds]

    def command_rate(self, t0, kind):
        """Messages per second of one command stream in the healthy second before t0."""
        return len(self.window(t0 - 1.0, t0, {kind})) / 1.0

    def unsafe_in(self, t0, t1, fault_from=None, grace=MUST_STOP_GRACE):
        """Non-finite outputs, JointPos jumps, and non-zero commands after the fault began at
        fault_from beyond the cycles its grace allows (see MUST_STOP_GRACE)."""
        bad = []
        last_frame, last_frame_t = None, None
        allowed = {} if fault_from is None else \
            {k: int(math.ceil(grace * self.command_rate(fault_from, k))) + 1 for k in ("cmd_vel", "armcmd")}
        moving = {"cmd_vel": 0, "armcmd": 0}
        for t, kind, m in self.window(t0, t1, {"cmd_vel", "armcmd", "jointpos", "obstacles"}):
            if kind == "cmd_vel":
                v = [m.linear.x, m.linear.y, m.linear.z, m.angular.x, m.angular.y, m.angular.z]
            elif kind == "armcmd":
                v = list(m.velocities)
            elif kind == "jointpos":
                v = list(m.joint)
                # Consecutive frames of one stream. After the adapter stopped (a hold ended), a new
                # stream starts at the measured position (this script's joint state), possibly
                # just one period after the last held frame.
                restart = last_frame is None or t - last_frame_t >= 0.1 or \
                    (len(v) == len(ARM_READY) and max(abs(a - b) for a, b in zip(v, ARM_READY)) < 1e-6)
                if not restart and len(v) == len(last_frame) and all(map(math.isfinite, v)):
                    jump = max(abs(a - b) for a, b in zip(v, last_frame))
                    if jump > math.radians(10.0) + 1e-4:
                        bad.append("JointPos jump of %.1f deg %.3f s after the previous frame" % (
                            math.degrees(jump), t - last_frame_t))
                last_frame, last_frame_t = v, t
            else:
                v = [o.distance for o in m.obstacles]
            if not all(map(math.isfinite, v)):
                bad.append("non-finite " + kind)
            elif fault_from is not None and kind in ("cmd_vel", "armcmd") and t > fault_from \
                    and any(abs(x) > 0.0 for x in v):
                moving[kind] += 1
                if moving[kind] > allowed[kind] or t > fault_from + STOP_HARD_LIMIT * grace:
                    bad.append("non-zero %s %.3f s after the fault (its %d-th; %d allowed)" % (
                        kind, t - fault_from, moving[kind], allowed[kind]))
        return bad

    def first_zero_after(self, t0):
        for t, kind, m in self.window(t0, t0 + 5.0, {"cmd_vel"}):
            if m.linear.x == 0.0 and m.angular.z == 0.0:
                return t - t0
        return None

    def alive_after(self, t0, restarted=()):
        """Every node shows life within PROBE_TIMEOUT of healthy input from t0 (a node restarted
        after the case: within STARTUP_TIMEOUT, its start-up is not a hang)."""
        need = {"controller": "status", "obstacle": "obstacles", "adapter": "adapter_status"}
        ends = {n: t0 + (STARTUP_TIMEOUT if n in restarted else PROBE_TIMEOUT) for n in need}
        while time.monotonic() < max(ends.values()):
            late = [n for n, k in need.items() if not self.window(t0, ends[n], {k})]
            if not late or all(time.monotonic() > ends[n] for n in late):
                return late
            time.sleep(0.1)
        return [n for n, k in need.items() if not self.window(t0, ends[n], {k})]

    # ------------------------------------------------------------ cases
    def run_case(self, case):
        name, duration = case["name"], case.get("duration", 2.0)
        setup, teardown = case.get("setup"), case.get("teardown")
        self.mode.update({"state": "ok", "target": "ok", "cloud": "ok", "cloud_ticks": 10})
        time.sleep(1.0)  # healthy: TRACKING again
        t0 = time.monotonic()
        if setup:
            setup(self)
        self.mode.update(case.get("mode", {}))
        inject = case.get("inject")
        end = max(t0, time.monotonic() - 1.0) + duration  # a long set-up (a node restarted) counts 1 s at most
        while time.monotonic() < end:
            if inject:
                inject(self)
            time.sleep(case.get("inject_period", 0.05))
        self.mode.update({"state": "ok", "target": "ok", "cloud": "ok", "cloud_ticks": 10})
        if teardown:
            teardown(self)
        t1 = time.monotonic()
        fault_from = t0 if case.get("must_stop") else None
        unsafe = self.unsafe_in(t0, t1, fault_from, case.get("grace", MUST_STOP_GRACE))
        latency = self.first_zero_after(t0) if case.get("must_stop") else None
        crashed = [n for n in self.dead() if n not in case.get("killed", [])]
        restarted = self.dead()
        for n in restarted:
            self.start(n)
        restarted += case.get("restarts", [])
        hung = self.alive_after(t1, restarted) if not crashed else []
        unclear = case["check"](self, t0, t1) if case.get("check") else []
        result = {"case": name, "target": case["target"], "crashes": crashed, "hangs": hung, "unclear": unclear,
                  "unsafe": sorted(set(unsafe)), "unsafe_count": len(unsafe),
                  "stop_latency_s": latency}
        if case.get("measure_gap"):
            ts = [e[0] for e in self.window(t0, t1, {"obstacles"})]
            result["obstacles_max_gap_s"] = max((b - a for a, b in zip(ts, ts[1:])), default=None)
            result["obstacles_rate_hz"] = len(ts) / (t1 - t0)
            result["clouds_per_s"] = case.get("cloud_hz")
        return result


def obstacles_required_reported(c, t0, t1):
    """The generic controller ran and said why it did not move: OBSTACLES_STALE, sensing required."""
    st = [m for _, _, m in c.window(t0, t1, {"status"})]
    if not any(m.phase == "OBSTACLES_STALE" and m.obstacles_required for m in st):
        return ["no /ehc/status with OBSTACLES_STALE and obstacles_required (%d statuses)" % len(st)]
    return []


def bad_clouds(c):
    PF = c.M["PointField"]
    pts = [(1.0 + 0.01 * i, 0.0, 0.5) for i in range(100)]
    f32 = lambda off=(0, 4, 8), dt=PF.FLOAT32: [PF("x", off[0], dt, 1), PF("y", off[1], dt, 1), PF("z", off[2], dt, 1)]
    return {
        "cloud: point_step 0, width 10^6, no data": c.make_cloud([], point_step=0, width=1000000, data=b""),
        "cloud: field offset beyond point_step": c.make_cloud(pts, fields=f32((0, 4, 400))),
        "cloud: data shorter than width x point_step": c.make_cloud(pts, width=100000),
        "cloud: FLOAT64 xyz (valid, converted)": c.make_cloud(
            pts, fields=f32((0, 8, 16), PF.FLOAT64), point_step=24,
            data=b"".join(struct.pack("<ddd", *p) for p in pts)),
        "cloud: UINT8 xyz": c.make_cloud(pts, fields=f32((0, 1, 2), PF.UINT8), point_step=3,
                                         data=bytes(3 * len(pts))),
        "cloud: missing z": c.make_cloud(pts, fields=f32()[:2]),
        "cloud: big-endian": c.make_cloud(pts, is_bigendian=True),
        "cloud: row_step wrong, height 7": c.make_cloud(pts, height=7, row_step=5),
        "cloud: all NaN": c.make_cloud([(float("nan"),) * 3] * 5000),
        "cloud: huge, 2 million points": c.make_cloud([], data=bytes(12 * 2000000), width=2000000),
        "cloud: full 640x480 D435 stream (valid)": c.make_cloud([], data=struct.pack("<fff", 0.1, 0.2, 2.5) * (640 * 480),
                                                        width=640, height=480),
    }


def bad_images(c):
    Image = c.M["Image"]

    def img(w, h, enc, step, n):
        m = Image()
        m.header.frame_id = "camera_color_optical_frame"
        m.width, m.height, m.encoding, m.step = w, h, enc, step
        m.data = bytes(n)
        return m
    return {
        "image: step x height > data": img(640, 480, "mono8", 640, 100),
        "image: unknown encoding": img(64, 48, "yuv422_weird", 64, 64 * 48),
        "image: zero size": img(0, 0, "mono8", 0, 0),
        "image: huge 8000x8000 rgb8": img(8000, 8000, "rgb8", 24000, 24000 * 8000),
    }


def cases(c, quick):
    out = []
    for name, mode in [("state: NaN joint state and odometry", "nan"), ("state: publisher killed (silent)", "silent"),
                       ("state: zero odometry quaternion", "zero_quat"), ("state: unknown joint names", "wrong_names")]:
        out.append({"name": name, "target": "controller, obstacle node", "mode": {"state": mode}, "must_stop": True})
    for name, mode in [("state: stamps 100 s old (clock offset; receipt time counts)", "stale_stamp"),
                       ("state: stamps 100 s ahead (clock offset)", "future_stamp")]:
        out.append({"name": name, "target": "controller, obstacle node", "mode": {"state": mode}})
    for name, mode in [("target: NaN position", "nan"), ("target: zero quaternion", "bad_quat"),
                       ("target: publisher killed (silent)", "silent"), ("target: wrong frame", "wrong_frame")]:
        out.append({"name": name, "target": "controller", "mode": {"target": mode}, "must_stop": True})
    out.append({"name": "obstacles: obstacle node killed (SIGKILL)", "target": "controller",
                "setup": lambda s: s.stop("obstacle", signal.SIGKILL), "must_stop": True, "killed": ["obstacle"],
                "grace": OBSTACLE_STOP_GRACE})
    # Safe by default: the generic controller config (obstacle sensing required unless a config
    # says otherwise) without an obstacle node never moves the robot.
    generic = ["ehc_control", "ehc_controller_node", "_config:=config/control/controller.yaml", "_trigger:=timer"]
    out.append({"name": "obstacles: generic controller config, no obstacle node (safe by default)", "target": "controller",
                "setup": lambda s: (s.stop("obstacle", signal.SIGKILL), s.restart_controller(generic)),
                "teardown": lambda s: (s.stop("controller"), s.start("controller"), s.start("obstacle")),
                "must_stop": True, "killed": ["obstacle", "controller"], "restarts": ["controller", "obstacle"],
                "grace": OBSTACLE_STOP_GRACE, "duration": 3.0, "check": obstacles_required_reported})
    for name, cloud in bad_clouds(c).items():
        stream = "D435" in name  # at the camera's rate (25 Hz: every second 50 Hz tick), else 5 Hz
        out.append({"name": name, "target": "obstacle node, grasp node",
                    "mode": {"cloud": cloud, "cloud_ticks": 2 if stream else 10},
                    "duration": 4.0 if "huge" in name or stream else 2.0, "cloud_hz": 25.0 if stream else 5.0,
                    "measure_gap": "huge" in name or stream})
    for name, m in bad_images(c).items():
        out.append({"name": name, "target": "tag node",
                    "inject": (lambda msg: (lambda s: s.pub["image"].publish(msg)))(m), "inject_period": 0.2})

    def arm_cmd(names, vel):
        m = c.M["JointVelocityCommand"]()
        m.names, m.velocities = names, vel
        return lambda s: (setattr(m.header, "stamp", s.rospy.Time.now()), s.pub["armcmd"].publish(m))
    j = ["joint%d" % i for i in range(1, 7)]
    for name, names, vel in [("arm command: NaN velocity", j, [0.1, float("nan"), 0, 0, 0, 0]),
                             ("arm command: 1000 rad/s", j, [1000.0] * 6),
                             ("arm command: wrong size", j[:2], [0.1, 0.1]),
                             ("arm command: unknown names", ["a", "b", "c", "d", "e", "f"], [0.1] * 6)]:
        out.append({"name": name, "target": "rm_arm_adapter", "inject": arm_cmd(names, vel), "inject_period": 0.01})
    if quick:
        keep = ["state: NaN joint state and odometry", "state: publisher killed (silent)",
                "state: zero odometry quaternion", "target: NaN position",
                "obstacles: obstacle node killed (SIGKILL)",
                "obstacles: generic controller config, no obstacle node (safe by default)",
                "cloud: point_step 0, width 10^6, no data",
                "cloud: field offset beyond point_step", "cloud: UINT8 xyz", "image: step x height > data",
                "arm command: NaN velocity"]
        out = [o for o in out if o["name"] in keep]
    return out




def runtime_result(r):
    """A runtime case's result in the common form."""
    found = [issue("crashes", "%s exited" % n) for n in r.pop("crashes")]
    found += [issue("hangs", "%s showed no sign of life" % n) for n in r.pop("hangs")]
    found += [issue("unsafe", u) for u in r.pop("unsafe")]
    found += [issue("unclear", u) for u in r.pop("unclear")]
    r.pop("unsafe_count", None)
    r.update({"phase": "runtime", "issues": found})
    return r


def runtime_phase(log_dir, quick):
    c = Campaign(log_dir)
    results = []
    try:
        for n in NODES:
            c.start(n)
        c.thread.start()
        t_up = time.monotonic()
        while not c.window(t_up, t_up + 60, {"obstacles"}) or not c.window(t_up, t_up + 60, {"status"}):
            if time.monotonic() > t_up + 60:
                raise RuntimeError("the nodes did not come up (see %s)" % log_dir)
            time.sleep(0.5)
        for case in cases(c, quick):
            r = c.run_case(case)
            results.append(runtime_result(r))
            report(results[-1])
    finally:
        c.running = False
        for n in list(c.procs):
            c.stop(n)
        for s in c.subs:
            s.unregister()
    return results


def report(r):
    counts = {k: sum(1 for i in r["issues"] if i["kind"] == k) for k in KINDS}
    extra = ""
    if r.get("stop_latency_s") is not None:
        extra += "  stop %.3f s" % r["stop_latency_s"]
    if r.get("obstacles_max_gap_s"):
        extra += "  /ehc/obstacles %.1f Hz, max gap %.3f s" % (r["obstacles_rate_hz"], r["obstacles_max_gap_s"])
    if r.get("exit_s") is not None:
        extra += "  exit %.2f s" % r["exit_s"]
    print("%-86s %s%s" % (r["case"][:86], " ".join("%s %d" % (k, counts[k]) for k in KINDS), extra), flush=True)
    for i in r["issues"]:
        print("    %s: %s%s" % (i["kind"], i["text"], ("  [" + r["message"][:300] + "]") if r.get("message") else ""),
              flush=True)


def start_master(out):
    port = free_port()
    os.environ.update({"ROS_MASTER_URI": "http://127.0.0.1:%d" % port, "ROS_HOSTNAME": "127.0.0.1",
                       "ROS_HOME": os.path.join(out, "ros_home")})
    os.environ.pop("ROS_IP", None)
    core = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    deadline = time.monotonic() + 30
    while subprocess.call(["rosparam", "list"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) != 0:
        if time.monotonic() > deadline:
            raise RuntimeError("roscore did not start")
        time.sleep(0.5)
    subprocess.call(["rosparam", "set", "use_sim_time", "false"])
    return core


PHASES = ("startup", "params", "lockstep", "signals", "runtime")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="the reduced set the test suite runs")
    ap.add_argument("--out", default=os.path.join(WS, "build", "fault_campaign"))
    ap.add_argument("--phase", action="append", choices=PHASES, help="only these phases (default: all)")
    a = ap.parse_args()
    phases = a.phase or list(PHASES)
    os.makedirs(a.out, exist_ok=True)
    log_dir = tempfile.mkdtemp(prefix="logs_", dir=a.out)
    tmp = os.path.join(log_dir, "inputs")
    os.makedirs(tmp)
    core = start_master(a.out)
    results = []
    t0 = time.monotonic()
    try:
        import rospy
        rospy.init_node("fault_campaign", disable_signals=True)
        if "startup" in phases:
            startup = sweep_cases(tmp, a.quick) + node_cases(tmp) + shipped_node_cases() + tool_cases(tmp)
            if a.quick:
                startup = [s for s in startup if s.get("quick") or s["name"].startswith("sweep ")]
            for r in run_cases(startup, log_dir):
                results.append(r)
                report(r)
        if "params" in phases:
            results += params_phase(log_dir)
            report(results[-1])
        if "lockstep" in phases:
            results += lockstep_phase(log_dir)
            report(results[-1])
        if "signals" in phases:
            stops = [experiment_stop_case(tmp, log_dir, ["reach", "--robot", "realman_rm65_water2", "--method", "all",
                                                         "--sets", "2", "--points", "20"], signal.SIGTERM, r"targets.*ETA")]
            if not a.quick:
                stops.append(experiment_stop_case(tmp, log_dir, ["poses", "--method", "ehc", "--sets", "1", "--per-set", "1",
                                                                 "--jobs", "1"], signal.SIGINT, r"\b1/3\b"))
                stops += [demo_stop_case(tmp, log_dir, "ctrlc"), demo_stop_case(tmp, log_dir, "kill")]
            for r in stops:
                results.append(r)
                report(r)
        if "runtime" in phases:
            results += runtime_phase(log_dir, a.quick)
    finally:
        os.killpg(core.pid, signal.SIGINT)
        core.wait()
    totals = {k: sum(1 for r in results for i in r["issues"] if i["kind"] == k) for k in KINDS}
    per_phase = {ph: {k: sum(1 for r in results if r["phase"] == ph for i in r["issues"] if i["kind"] == k) for k in KINDS}
                 for ph in PHASES if any(r["phase"] == ph for r in results)}
    with open(os.path.join(a.out, "campaign.json"), "w") as f:
        json.dump({"quick": a.quick, "totals": totals, "phases": per_phase, "cases": results,
                   "wall_s": round(time.monotonic() - t0, 1)}, f, indent=1, default=str)
    with open(os.path.join(a.out, "campaign.md"), "w") as f:
        f.write("| phase | case | crashes | hangs | unsafe | unclear | message / measured |\n|---|---|---|---|---|---|---|\n")
        for r in results:
            n = {k: sum(1 for i in r["issues"] if i["kind"] == k) for k in KINDS}
            note = r.get("message", "")
            if r.get("stop_latency_s") is not None:
                note = "stop %.3f s" % r["stop_latency_s"]
            f.write("| %s | %s | %d | %d | %d | %d | %s |\n" % (
                r["phase"], r["case"].replace("|", "/"), n["crashes"], n["hangs"], n["unsafe"], n["unclear"],
                str(note).replace("|", "/")[:300]))
    print("%d cases in %.0f s: %d crashes, %d hangs, %d unsafe, %d unclear (logs %s)" % (
        len(results), time.monotonic() - t0, totals["crashes"], totals["hangs"], totals["unsafe"], totals["unclear"], log_dir))
    return 0 if not any(totals.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
