#!/usr/bin/python3
"""Fault and bad-input campaign: replays malformed messages against the
running nodes and counts crashes, hangs and unsafe outputs. Goal: 0, 0, 0.

    source devel/setup.bash; test/fault_campaign.py [--quick] [--out DIR]

One command, its own private ROS master (a free port, wall clock as on the robot). It starts
ehc_controller_node (config/realman/controller.yaml: timer trigger, obstacles required),
ehc_obstacle_node, ehc_grasp_node, ehc_tag_node and rm_arm_adapter, and plays a healthy robot
around them (this script): /joint_states + /odom at 50 Hz, a target 1 m ahead, a valid depth
cloud at 5 Hz with the camera's tf, so the controller is TRACKING and commanding. Each case then
breaks one input for a few seconds, followed by a probe with healthy inputs again.

Counted, per case:
  crash   a node process exited (it is restarted for the next case);
  hang    after the case a node gives no sign of life within 5 s of healthy input (a node
          restarted after being killed on purpose: within 60 s, its start-up)
          (controller: /ehc/status, obstacle node: /ehc/obstacles, adapter: /arm/adapter_status;
          the tag and grasp nodes: their process is alive);
  unsafe  any non-finite value in /cmd_vel, /arm/joint_velocity_cmd, /rm_driver/JointPos or
          /ehc/obstacles; a JointPos frame more than 10 deg from the previous one; and, in the
          cases where the controller must stop (state / target / obstacles lost or invalid), a
          non-zero command later than the watchdog timeout + 0.1 s after the fault began
          (state, target: 0.2 + 0.1 s; obstacles: 0.5 + 0.1 s).
Also measured: the watchdog latency in timer mode (last good input -> first zero command, on
this script's receipt clock) per lost input, and /ehc/obstacles' longest gap under huge clouds.
Writes DIR/campaign.json and DIR/campaign.md (default build/fault_campaign). Exit 0 iff 0/0/0.
--quick: a reduced set (one case per kind), as the test suite runs it.
"""
import argparse
import json
import math
import os
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time

WS = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
# s after the fault began: the controller's watchdog timeout (config/control/controller.yaml:
# state_timeout and target_timeout 0.2 s, obstacle_timeout 0.5 s) + one 50 Hz cycle + margin.
MUST_STOP_GRACE = 0.3
OBSTACLE_STOP_GRACE = 0.6
PROBE_TIMEOUT = 5.0    # s of healthy input within which every node must show life again
STARTUP_TIMEOUT = 60.0  # s for a node restarted after the case (killed on purpose): its start-up


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
        rospy.init_node("fault_campaign", disable_signals=True)
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
    def start(self, name):
        pkg, exe, *args = NODES[name]
        log = open(os.path.join(self.log_dir, name + ".log"), "a")
        self.procs[name] = subprocess.Popen(["rosrun", pkg, exe] + args, cwd=WS, stdout=log,
                                            stderr=subprocess.STDOUT, start_new_session=True)

    def stop(self, name, sig=signal.SIGINT):
        p = self.procs.get(name)
        if p and p.poll() is None:
            os.killpg(p.pid, sig)
            try:
                p.wait(5)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()

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
                js.position = [0.0, 0.5, -1.9, 0.0, -0.5, 0.0]
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

    def unsafe_in(self, t0, t1, must_stop_from=None, grace=MUST_STOP_GRACE):
        """Non-finite outputs, JointPos jumps, and non-zero commands after must_stop_from."""
        bad = []
        last_frame = None
        for t, kind, m in self.window(t0, t1, {"cmd_vel", "armcmd", "jointpos", "obstacles"}):
            if kind == "cmd_vel":
                v = [m.linear.x, m.linear.y, m.linear.z, m.angular.x, m.angular.y, m.angular.z]
            elif kind == "armcmd":
                v = list(m.velocities)
            elif kind == "jointpos":
                v = list(m.joint)
                if last_frame is not None and len(v) == len(last_frame) and all(map(math.isfinite, v)):
                    if max(abs(a - b) for a, b in zip(v, last_frame)) > math.radians(10.0) + 1e-4:
                        bad.append("JointPos jump")
                last_frame = v
            else:
                v = [o.distance for o in m.obstacles]
            if not all(map(math.isfinite, v)):
                bad.append("non-finite " + kind)
            elif must_stop_from is not None and kind in ("cmd_vel", "armcmd") and t > must_stop_from \
                    and any(abs(x) > 0.0 for x in v):
                bad.append("non-zero %s %.3f s after the fault" % (kind, t - (must_stop_from - grace)))
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
        end = t0 + duration
        while time.monotonic() < end:
            if inject:
                inject(self)
            time.sleep(case.get("inject_period", 0.05))
        self.mode.update({"state": "ok", "target": "ok", "cloud": "ok", "cloud_ticks": 10})
        if teardown:
            teardown(self)
        t1 = time.monotonic()
        must = t0 + case.get("grace", MUST_STOP_GRACE) if case.get("must_stop") else None
        unsafe = self.unsafe_in(t0, t1, must, case.get("grace", MUST_STOP_GRACE))
        latency = self.first_zero_after(t0) if case.get("must_stop") else None
        crashed = [n for n in self.dead() if n not in case.get("killed", [])]
        restarted = self.dead()
        for n in restarted:
            self.start(n)
        hung = self.alive_after(t1, restarted) if not crashed else []
        result = {"case": name, "target": case["target"], "crashes": crashed, "hangs": hung,
                  "unsafe": sorted(set(unsafe)), "unsafe_count": len(unsafe),
                  "stop_latency_s": latency}
        if case.get("measure_gap"):
            ts = [e[0] for e in self.window(t0, t1, {"obstacles"})]
            result["obstacles_max_gap_s"] = max((b - a for a, b in zip(ts, ts[1:])), default=None)
            result["obstacles_rate_hz"] = len(ts) / (t1 - t0)
            result["clouds_per_s"] = case.get("cloud_hz")
        return result


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
                "obstacles: obstacle node killed (SIGKILL)", "cloud: point_step 0, width 10^6, no data",
                "cloud: field offset beyond point_step", "cloud: UINT8 xyz", "image: step x height > data",
                "arm command: NaN velocity"]
        out = [o for o in out if o["name"] in keep]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="one case per kind (the test suite's run)")
    ap.add_argument("--out", default=os.path.join(WS, "build", "fault_campaign"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    log_dir = tempfile.mkdtemp(prefix="logs_", dir=a.out)
    port = free_port()
    os.environ.update({"ROS_MASTER_URI": "http://127.0.0.1:%d" % port, "ROS_HOSTNAME": "127.0.0.1",
                       "ROS_HOME": os.path.join(a.out, "ros_home")})
    os.environ.pop("ROS_IP", None)
    core = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    c = None
    try:
        deadline = time.monotonic() + 30
        while subprocess.call(["rosparam", "list"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) != 0:
            if time.monotonic() > deadline:
                raise RuntimeError("roscore did not start")
            time.sleep(0.5)
        subprocess.call(["rosparam", "set", "use_sim_time", "false"])
        c = Campaign(log_dir)
        for n in NODES:
            c.start(n)
        c.thread.start()
        t_up = time.monotonic()
        while not c.window(t_up, t_up + 60, {"obstacles"}) or not c.window(t_up, t_up + 60, {"status"}):
            if time.monotonic() > t_up + 60:
                raise RuntimeError("the nodes did not come up (see %s)" % log_dir)
            time.sleep(0.5)
        results = []
        for case in cases(c, a.quick):
            r = c.run_case(case)
            results.append(r)
            print("%-62s crashes %d hangs %d unsafe %d%s%s" % (
                r["case"], len(r["crashes"]), len(r["hangs"]), r["unsafe_count"],
                "  stop %.3f s" % r["stop_latency_s"] if r["stop_latency_s"] is not None else "",
                "  /ehc/obstacles %.1f Hz, max gap %.3f s" % (r["obstacles_rate_hz"], r["obstacles_max_gap_s"])
                if r.get("obstacles_max_gap_s") else ""),
                flush=True)
    finally:
        if c:
            c.running = False
            for n in list(c.procs):
                c.stop(n)
        os.killpg(core.pid, signal.SIGINT)
        core.wait()
    totals = {k: sum(len(r[k]) if k != "unsafe" else r["unsafe_count"] for r in results)
              for k in ("crashes", "hangs", "unsafe")}
    with open(os.path.join(a.out, "campaign.json"), "w") as f:
        json.dump({"quick": a.quick, "totals": totals, "cases": results}, f, indent=1)
    with open(os.path.join(a.out, "campaign.md"), "w") as f:
        f.write("| case | node(s) | crashes | hangs | unsafe | stop latency |\n|---|---|---|---|---|---|\n")
        for r in results:
            f.write("| %s | %s | %d | %d | %d | %s |\n" % (
                r["case"], r["target"], len(r["crashes"]), len(r["hangs"]), r["unsafe_count"],
                "%.3f s" % r["stop_latency_s"] if r["stop_latency_s"] is not None else ""))
    print("%d cases: %d crashes, %d hangs, %d unsafe outputs (logs %s)" % (
        len(results), totals["crashes"], totals["hangs"], totals["unsafe"], log_dir))
    return 0 if not any(totals.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
