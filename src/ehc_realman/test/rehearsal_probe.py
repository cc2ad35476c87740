"""RehearsalProbe: the deployment rehearsal's measurements (REALMAN.md "Rehearsal"), recorded by
test_realman_rehearsal.py while run_realman.sh grasps the demo's objects against the hardware
stand-in. Ground truth comes from the stand-in's metrics topics (/sim/base_pose: the true base
pose; /sim/tcp_pose: the true TCP; /sim/object_poses; /sim/status); the estimates from what the
stack uses (/odom from water2_base_bridge, whose tf odom -> base_link carries the same pose; each
object's perceived pose from its tag node; the sequencer's goal /ehc/target_pose). The TCP the
stack believes in is the true base_link -> TCP (joint states are exact, robot_state_publisher's
tf is the controller's model: test_run_realman_script) on the /odom base pose. Nothing here
feeds back into the stack.

Recorded:
  - odometry error: every /odom pose against the true base pose at its stamp (interpolated);
    the largest step of that error between consecutive /odom messages (a jump when a
    robot_status reply replaces the dead-reckoned pose);
  - perception error per object: each perceived pose against the true object, and how much of
    it the odometry error at the image stamp explains (the pose of the object seen from the
    estimated instead of the true base); the residual also horizontally ("residual_horizontal"):
    a tag node's target is the object's grasp point, which the demo raises above the centre for
    the middle and back objects (grasp_offset 2 and 3 cm up, config/demo/tag_*.yaml), so the
    3-D residual includes that designed offset and the horizontal one does not;
  - per gripper closing (/sim/status gripper_state open -> closing): the goal vs the true
    object (the planned grasp's error), the TCP the stack believes in vs the true TCP, the closing distance (true TCP to true object),
    the age of the newest /odom and the outcome (holding / closed_empty).
Pure Python (no numpy, tf2_ros or tf2_msgs for Python on the test machines).
"""
import bisect
import math
import threading

import rospy
from ehc_msgs.msg import SimObjectPoses, SimStatus
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Odometry


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def planar_apply(base, p):
    """World point of `p` (x, y, z in the base frame) for the planar base pose (x, y, yaw)."""
    c, s = math.cos(base[2]), math.sin(base[2])
    return (base[0] + c * p[0] - s * p[1], base[1] + s * p[0] + c * p[1], p[2])


def planar_inverse_apply(base, p):
    c, s = math.cos(base[2]), math.sin(base[2])
    dx, dy = p[0] - base[0], p[1] - base[1]
    return (c * dx + s * dy, -s * dx + c * dy, p[2])


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def vec(p):
    return (p.x, p.y, p.z)


def rounded(v, n=4):
    return [round(x, n) for x in v]


class RehearsalProbe:
    def __init__(self, objects=None):
        self.lock = threading.Lock()
        self.truth_t, self.truth = [], []   # stamps (s), (x, y, yaw)
        self.odom_t, self.odom = [], []     # the bridge's /odom: stamps, (x, y, yaw)
        self.tcp_t, self.tcp = [], []       # the true TCP: stamps, positions
        self.objects = {}                   # name -> true position (latest)
        self.odom_errors = []               # (t, position error m, yaw error rad)
        self.odom_last = None               # (t, error vector) for the jumps
        self.odom_jumps = []                # m, |change of the error| between consecutive /odom
        self.last_odom_stamp = None
        self.goal = None                    # latest /ehc/target_pose (PoseStamped)
        self.perceived = {}                 # name -> list of dicts
        self.closings = []
        self.gripper_state = None
        self.subs = [
            rospy.Subscriber("/sim/base_pose", Odometry, self.on_truth, queue_size=200),
            rospy.Subscriber("/sim/tcp_pose", PoseStamped, self.on_tcp, queue_size=200),
            rospy.Subscriber("/sim/object_poses", SimObjectPoses, self.on_objects, queue_size=10),
            rospy.Subscriber("/odom", Odometry, self.on_odom, queue_size=200),
            rospy.Subscriber("/ehc/target_pose", PoseStamped, self.on_goal, queue_size=10),
            rospy.Subscriber("/sim/status", SimStatus, self.on_status, queue_size=1000),
        ]
        for name in objects or []:
            self.subs.append(rospy.Subscriber("/ehc/perception/%s/target_pose" % name, PoseStamped,
                                              self.on_perceived, callback_args=name, queue_size=20))

    # ---------------------------------------------------------------- truth
    def on_truth(self, m):
        t = m.header.stamp.to_sec()
        pose = (m.pose.pose.position.x, m.pose.pose.position.y, yaw_of(m.pose.pose.orientation))
        with self.lock:
            if self.truth_t and t <= self.truth_t[-1]:
                return
            self.truth_t.append(t)
            self.truth.append(pose)

    def on_tcp(self, m):
        with self.lock:
            self.tcp_t.append(m.header.stamp.to_sec())
            self.tcp.append(vec(m.pose.position))

    def true_tcp(self, t):
        with self.lock:
            i = bisect.bisect_left(self.tcp_t, t)
            if i >= len(self.tcp_t):
                return None
            return self.tcp[i]  # the first at or after t (published with /sim/status)

    def _interpolate(self, ts, poses, t):
        """The planar pose at t from a stamped record (linear), None outside it."""
        with self.lock:
            i = bisect.bisect_left(ts, t)
            if i == 0 or i >= len(ts):
                if ts and abs(ts[-1] - t) < 0.03:
                    return poses[-1]
                return None
            t0, t1 = ts[i - 1], ts[i]
            a, b = poses[i - 1], poses[i]
        f = (t - t0) / (t1 - t0) if t1 > t0 else 0.0
        return (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), a[2] + f * wrap(b[2] - a[2]))

    def true_base(self, t):
        return self._interpolate(self.truth_t, self.truth, t)

    def est_base(self, t):
        """The bridge's base pose (/odom, = its tf odom -> base_link) at t."""
        return self._interpolate(self.odom_t, self.odom, t)

    def on_objects(self, m):
        with self.lock:
            for name, pose in zip(m.names, m.poses):
                self.objects[name] = vec(pose.position)

    # ---------------------------------------------------------------- estimates
    def on_odom(self, m):
        t = m.header.stamp.to_sec()
        self.last_odom_stamp = t
        truth = self.true_base(t)
        if truth is None:
            return
        est = (m.pose.pose.position.x, m.pose.pose.position.y, yaw_of(m.pose.pose.orientation))
        with self.lock:
            if not self.odom_t or t > self.odom_t[-1]:
                self.odom_t.append(t)
                self.odom.append(est)
        err = (est[0] - truth[0], est[1] - truth[1], wrap(est[2] - truth[2]))
        with self.lock:
            self.odom_errors.append((t, math.hypot(err[0], err[1]), abs(err[2])))
            if self.odom_last is not None and t - self.odom_last[0] < 0.1:
                self.odom_jumps.append(math.hypot(err[0] - self.odom_last[1][0], err[1] - self.odom_last[1][1]))
            self.odom_last = (t, err)

    def on_goal(self, m):
        self.goal = m

    def on_perceived(self, m, name):
        t = m.header.stamp.to_sec()
        truth, est = self.true_base(t), self.est_base(t)
        with self.lock:
            true_obj = self.objects.get(name)
        if truth is None or est is None or true_obj is None:
            return
        seen = vec(m.pose.position)
        # Where the object appears if the camera pose is taken from the estimated base (the
        # odometry's share of the error); the rest is detection and timing.
        explained = planar_apply(est, planar_inverse_apply(truth, true_obj))
        self.perceived.setdefault(name, []).append({
            "t": t, "error": dist(seen, true_obj), "odometry_share": dist(explained, true_obj),
            "residual": dist(seen, explained), "residual_horizontal": dist(seen[:2], explained[:2])})

    # ---------------------------------------------------------------- closings
    def on_status(self, m):
        state = m.gripper_state
        previous, self.gripper_state = self.gripper_state, state
        if previous == "closing" and state in ("holding", "closed_empty") and self.closings:
            self.closings[-1]["outcome"] = state
        if state != "closing" or previous == "closing":
            return
        t = m.header.stamp.to_sec()
        with self.lock:
            objects = dict(self.objects)
        # Evaluated in summary(): the truth published with this status may arrive after it.
        self.closings.append({"t": t, "outcome": None, "objects": objects,
                              "goal": vec(self.goal.pose.position) if self.goal is not None else None,
                              "odom_age": None if self.last_odom_stamp is None else round(t - self.last_odom_stamp, 4)})

    def _closing(self, c):
        t, objects = c["t"], c["objects"]
        record = {"t": round(t, 3), "outcome": c["outcome"], "odom_age": c["odom_age"]}
        truth, est, true_tcp = self.true_base(t), self.est_base(t), self.true_tcp(t)
        if truth is None or est is None or true_tcp is None or not objects:
            record["error"] = "no ground truth at t"
            return record
        est_tcp = planar_apply(est, planar_inverse_apply(truth, true_tcp))
        name = min(objects, key=lambda n: dist(objects[n], true_tcp))
        frame = (0.0, 0.0, truth[2])  # offsets in the true base frame (x forward, y left, z up)
        record.update({
            "object": name,
            "tcp_estimate_error": round(dist(est_tcp, true_tcp), 4),
            "closing_distance": round(dist(true_tcp, objects[name]), 4),
            "closing_offset_base": rounded(planar_inverse_apply(frame, tuple(a - b for a, b in zip(true_tcp, objects[name])))),
        })
        if c["goal"] is not None:
            record["goal_error"] = round(dist(c["goal"], objects[name]), 4)
            record["goal_offset_base"] = rounded(planar_inverse_apply(frame, tuple(a - b for a, b in zip(c["goal"], objects[name]))))
        return record

    # ---------------------------------------------------------------- summary
    @staticmethod
    def _stats(xs):
        if not xs:
            return None
        s = sorted(xs)
        return {"n": len(s), "median": round(s[len(s) // 2], 4), "p95": round(s[int(0.95 * (len(s) - 1))], 4),
                "max": round(s[-1], 4)}

    def summary(self):
        with self.lock:
            pos = [e[1] for e in self.odom_errors]
            yaw = [e[2] for e in self.odom_errors]
            jumps = list(self.odom_jumps)
        perception = {}
        for name, rows in self.perceived.items():
            perception[name] = {k: self._stats([r[k] for r in rows]) for k in ("error", "odometry_share", "residual", "residual_horizontal")}
        return {"odometry_position_error": self._stats(pos), "odometry_yaw_error": self._stats(yaw),
                "odometry_error_step": self._stats(jumps), "perception": perception,
                "closings": [self._closing(c) for c in self.closings]}
