#!/usr/bin/env python3
"""Drive a ROS 2 robot from Cyclone DDS, as a teleop node would, and report its odometry.

    teleop.py --linear 0.3 --angular 0.0 --duration 3

Waits for the robot's /odom, publishes geometry_msgs/msg/Twist on /cmd_vel
(reliable, keep last 10) at 10 Hz for --duration seconds, then a zero Twist,
and prints one JSON object: the first and the last odometry pose heard
({"x", "y", "theta"}), and how many odometry messages came. Exits 1 if no
odometry came within --wait seconds. The other side of the test of
`ubf simulate --ros2`: a controller nobody here wrote. Run it inside
scripts/ros2/netns.sh.
"""
import argparse
import json
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import script_env  # noqa: E402

script_env.ensure(".venv-ros2", ["cyclonedds==11.0.1"], ["cyclonedds"])

from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

from ros2_types import Header, Odometry, Time, Twist, TwistStamped, Vector3, qos, ros_topic  # noqa: E402


def pose(odom):
    q = odom.pose.pose.orientation
    theta = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
    return {"x": odom.pose.pose.position.x, "y": odom.pose.pose.position.y, "theta": theta}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--linear", type=float, default=0.3, help="forward speed, m/s")
    parser.add_argument("--angular", type=float, default=0.0, help="turn rate, rad/s")
    parser.add_argument("--duration", type=float, default=3.0, help="seconds of driving")
    parser.add_argument("--wait", type=float, default=20.0, help="seconds to wait for the first odometry")
    parser.add_argument("--stamped", action="store_true",
                        help="publish geometry_msgs/msg/TwistStamped (frame base_link, wall-clock stamps), as Nav2 "
                             "does from Kilted on")
    args = parser.parse_args()

    participant = DomainParticipant(int(os.environ.get("ROS_DOMAIN_ID", "0")))
    cmd = DataWriter(participant, Topic(participant, ros_topic("cmd_vel"), TwistStamped if args.stamped else Twist),
                     qos())

    def command(twist):
        if not args.stamped:
            return twist
        now = time.time()
        return TwistStamped(header=Header(stamp=Time(sec=int(now), nanosec=int(now % 1 * 1e9)), frame_id="base_link"),
                            twist=twist)

    odom = DataReader(participant, Topic(participant, ros_topic("odom"), Odometry), qos())
    heard = []

    def listen():
        heard.extend(s for s in odom.take(N=100) if s.sample_info.valid_data)

    deadline = time.monotonic() + args.wait
    while not heard and time.monotonic() < deadline:
        listen()
        time.sleep(0.05)
    if not heard:
        sys.exit(f"no odometry on /odom within {args.wait} s")
    first = pose(heard[0])
    end = time.monotonic() + args.duration
    while time.monotonic() < end:
        cmd.write(command(Twist(linear=Vector3(x=args.linear), angular=Vector3(z=args.angular))))
        listen()
        time.sleep(0.1)
    cmd.write(command(Twist()))
    time.sleep(1.0)  # the robot stops; its last odometry comes in
    listen()
    print(json.dumps({"first": first, "last": pose(heard[-1]), "odometry": len(heard)}))


if __name__ == "__main__":
    main()
