#!/usr/bin/env python3
"""Rate of /ehc/obstacles under a full D435 depth stream (issue 16 item 2).

Starts its own ROS master (free port) and ehc_obstacle_node with CONFIG, then publishes for
SECONDS of wall time: organised 640x480 XYZ+RGB clouds (4.9 MB each; a wall 2 m ahead, a table
box, 10 % invalid pixels as NaN) at --cloud-hz, /joint_states and /odom at 100 Hz, and a static
tf odom -> camera. Counts /ehc/obstacles messages after a warm-up and prints both rates.

  source devel/setup.bash
  python3 src/ehc_perception/bench/obstacle_node_rate.py config/perception/obstacle_node.yaml \
      [--cloud-hz 30] [--seconds 20]

Wall-clock figures: noisy on a shared machine; the node's configured rate is publish_rate_hz.
"""
import argparse
import os
import socket
import subprocess
import sys
import time

import numpy as np


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("config")
    ap.add_argument("--cloud-hz", type=float, default=30.0)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--warmup", type=float, default=5.0)
    args = ap.parse_args()

    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port)
    os.environ.update(env)
    procs = [subprocess.Popen(["rosmaster", "--core", "-p", str(port)], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    time.sleep(2.0)
    procs.append(subprocess.Popen(["rosrun", "ehc_perception", "ehc_obstacle_node",
                                   "_config:=" + os.path.abspath(args.config)], env=env,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
    try:
        run(args)
    finally:
        for p in reversed(procs):
            p.terminate()
            p.wait()


def d435_cloud(frame):
    from sensor_msgs.msg import PointCloud2, PointField
    w, h, f = 640, 480, 615.0
    u, v = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
    depth = np.full((h, w), 2.0, dtype=np.float32)          # wall 2 m ahead
    depth[300:, 100:540] = 1.2                               # a table edge, lower image part
    rng = np.random.default_rng(0)
    depth[rng.random((h, w)) < 0.1] = np.nan                 # invalid pixels
    x = (u - 320.0) / f * depth                              # optical frame: x right, y down, z ahead
    y = (v - 240.0) / f * depth
    pts = np.zeros((h, w, 4), dtype=np.float32)
    pts[..., 0], pts[..., 1], pts[..., 2] = x, y, depth
    pts[..., 3] = np.frombuffer(np.uint32(0x00808080).tobytes(), dtype=np.float32)[0]
    msg = PointCloud2()
    msg.header.frame_id = frame
    msg.height, msg.width = h, w
    msg.fields = [PointField(n, 4 * i, PointField.FLOAT32, 1) for i, n in enumerate(["x", "y", "z", "rgb"])]
    msg.is_bigendian = False
    msg.point_step, msg.row_step = 16, 16 * w
    msg.is_dense = False
    msg.data = pts.tobytes()
    return msg


def run(args):
    import rospy
    import tf2_ros
    from ehc_msgs.msg import ObstacleArray
    from geometry_msgs.msg import TransformStamped
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import JointState, PointCloud2

    rospy.init_node("obstacle_node_rate", disable_signals=True)
    cloud_pub = rospy.Publisher("/camera/depth/points", PointCloud2, queue_size=1)
    js_pub = rospy.Publisher("/joint_states", JointState, queue_size=5)
    odom_pub = rospy.Publisher("/odom", Odometry, queue_size=5)
    stamps = []
    rospy.Subscriber("/ehc/obstacles", ObstacleArray, lambda m: stamps.append(time.monotonic()), queue_size=100)
    static = tf2_ros.StaticTransformBroadcaster()
    t = TransformStamped()
    t.header.frame_id, t.child_frame_id = "odom", "bench_camera_optical"
    t.transform.translation.x, t.transform.translation.z = 0.3, 1.0
    # optical (z ahead, x right, y down) -> odom (x ahead, y left, z up)
    t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z, t.transform.rotation.w = -0.5, 0.5, -0.5, 0.5
    static.sendTransform(t)
    cloud = d435_cloud("bench_camera_optical")
    js = JointState(name=["joint%d" % i for i in range(1, 7)], position=[0.0, 0.5, -1.9, 0.0, -0.5, 0.0])
    odom = Odometry()
    odom.header.frame_id = "odom"
    odom.pose.pose.orientation.w = 1.0
    time.sleep(2.0)  # connections

    start = time.monotonic()
    next_cloud = next_state = start
    clouds = 0
    clouds_measured = 0
    while time.monotonic() - start < args.warmup + args.seconds:
        now = time.monotonic()
        if now >= next_state:
            stamp = rospy.Time.now()
            js.header.stamp = odom.header.stamp = stamp
            js_pub.publish(js)
            odom_pub.publish(odom)
            next_state += 0.01
        if now >= next_cloud:
            cloud.header.stamp = rospy.Time.now()
            cloud_pub.publish(cloud)
            clouds += 1
            if now - start >= args.warmup:
                clouds_measured += 1
            next_cloud += 1.0 / args.cloud_hz
        time.sleep(0.0005)
    t0 = start + args.warmup
    n = sum(1 for s in stamps if s >= t0)
    gaps = np.diff([s for s in stamps if s >= t0]) if n > 1 else np.array([0.0])
    print("config %s: clouds 640x480 published at %.1f Hz; /ehc/obstacles %.1f Hz over %.0f s "
          "(largest gap %.0f ms)" % (args.config, clouds_measured / args.seconds, n / args.seconds, args.seconds,
                                      1e3 * gaps.max()))
    sys.stdout.flush()


if __name__ == "__main__":
    main()
