#!/usr/bin/env python3
"""A differential-drive robot as a ROS 2 base driver presents it, played by Cyclone DDS.

The other side of ubf's ROS 2 interop tests: an implementation nobody here
wrote, speaking what a real robot speaks, without a ROS installation.

It subscribes /cmd_vel (geometry_msgs/msg/Twist, reliable, keep last 10),
integrates linear.x and angular.z as a unicycle at the odometry rate (a
command older than 0.5 s counts as zero, as base drivers do), and publishes
nav_msgs/msg/Odometry on /odom (reliable, keep last 10, frame "odom", child
"base_link", wall-clock stamps, twist = the command in force). With --scan it
also publishes sensor_msgs/msg/LaserScan on /scan (sensor data QoS: best
effort, keep last 5), frame "base_link" ("laser" with --laser-mount or
--tf-static, which publishes where it sits on /tf_static), 360 beams seeing the wall x = --wall-x
of the odom frame, or nothing (every beam at range_max).

Prints "robot ready" once its readers and writers exist. On SIGTERM, SIGINT or
--duration it stops; --record FILE has then got one JSON line per Twist
received ({"twist": ..., "t": monotonic receive time}, the clock Rust's
Instant reads; "odom_age", how old the newest odometry published was when the
command arrived) and a last line {"summary": {"pose": ..., "last_twist": ...}}.
Run it inside scripts/ros2/netns.sh.
"""
import argparse
import json
import math
import os
import signal
import sys
import time
from dataclasses import asdict, dataclass, field

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import script_env  # noqa: E402

script_env.ensure(".venv-ros2", ["cyclonedds==11.0.1"], ["cyclonedds"])

from cyclonedds.core import ReadCondition, SampleState, ViewState, InstanceState, WaitSet  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

from ros2_types import (Header, LaserScan, Odometry, Quaternion, TFMessage, Time, Transform,  # noqa: E402
                        TransformStamped, Twist, TwistStamped, Vector3, qos, ros_topic, static_qos)

COMMAND_TIMEOUT = 0.5
BEAMS = 360
RANGE_MIN, RANGE_MAX = 0.1, 10.0


@dataclass
class ShortOdometry(IdlStruct, typename=Odometry.__idl_typename__):
    """What a stranger might publish under odometry's name: a header and nothing else."""
    header: Header = field(default_factory=Header)


@dataclass
class ShortLaserScan(IdlStruct, typename=LaserScan.__idl_typename__):
    """Likewise under the scan's name."""
    header: Header = field(default_factory=Header)


def stamp():
    ns = time.time_ns()
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def scan_ranges(x, y, theta, wall_x):
    """Each beam's range to the line x = wall_x, or range_max where it sees nothing."""
    ranges = []
    for i in range(BEAMS):
        heading = theta - math.pi + i * 2 * math.pi / BEAMS
        cos = math.cos(heading)
        distance = (wall_x - x) / cos if wall_x is not None and abs(cos) > 1e-9 else -1.0
        ranges.append(distance if RANGE_MIN <= distance <= RANGE_MAX else RANGE_MAX)
    return ranges


def transform(parent, child, x=0.0, z=0.0, yaw=0.0):
    """The transform of `child` in `parent`: x ahead, z up, yawed `yaw` rad."""
    return TransformStamped(header=Header(stamp=stamp(), frame_id=parent), child_frame_id=child,
                            transform=Transform(translation=Vector3(x=x, z=z),
                                                rotation=Quaternion(z=math.sin(yaw / 2), w=math.cos(yaw / 2))))


def publish_static_transforms(participant, args):
    """The scanner's mount on /tf_static, from two writers as from two static broadcasters (a robot's description
    and a mount added later): each writes one message holding all of its transforms, once. Returns the writers."""
    topic = Topic(participant, ros_topic("tf_static", args.namespace), TFMessage)
    mount_x, mount_heading_deg = args.laser_mount
    description = DataWriter(participant, topic, static_qos())
    description.write(TFMessage(transforms=[
        transform("base_footprint", "base_link", z=0.1),
        transform("base_link", "laser_plate", x=mount_x, z=0.3)]))
    mount = DataWriter(participant, topic, static_qos())
    mount.write(TFMessage(transforms=[transform("laser_plate", "laser", z=0.05, yaw=math.radians(mount_heading_deg))]))
    return [description, mount]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--namespace", default="", help="ROS namespace of the topics, e.g. robot1")
    parser.add_argument("--rate", type=float, default=20.0, help="odometry rate, Hz")
    parser.add_argument("--scan", action="store_true", help="also publish /scan")
    parser.add_argument("--wall-x", type=float, help="x of a wall (odom frame) that the scan sees")
    parser.add_argument("--laser-mount", type=float, nargs=2, metavar=("X", "HEADING_DEG"), default=(0.0, 0.0),
                        help="the scanner X m ahead of the robot's centre, its angle 0 HEADING_DEG "
                             "counter-clockwise from the robot's heading (frame \"laser\")")
    parser.add_argument("--tf-static-turn-after", type=float, metavar="S",
                        help="with --tf-static, S seconds after the robot first moved, publish the scanner turned a "
                             "quarter further, as a second broadcaster of its mount would")
    parser.add_argument("--cmd-vel-reader-after", type=float, metavar="S",
                        help="subscribe /cmd_vel only S seconds after starting, odometry flowing meanwhile, as a "
                             "driver whose controller comes up late")
    parser.add_argument("--stamped-cmd-vel", action="store_true",
                        help="read geometry_msgs/msg/TwistStamped on /cmd_vel, as ros2_control's diff drive controller "
                             "does from Jazzy on (recorded lines then also hold the command's header)")
    parser.add_argument("--tf-static", action="store_true",
                        help="publish the scanner's mount on /tf_static before starting, as a robot's static "
                             "broadcasters do: base_footprint > base_link > laser_plate (X ahead, 0.3 m up) from one "
                             "writer, laser_plate > laser (the heading) from another")
    parser.add_argument("--stop-odom-after", type=float, metavar="S",
                        help="stop publishing odometry S seconds after the robot first moved")
    parser.add_argument("--odom-jump-after", type=float, metavar="S",
                        help="S seconds after the robot first moved, put its odometry 100 m further on in x, "
                             "as corrupt data would")
    parser.add_argument("--second-odom-after", type=float, metavar="S",
                        help="S seconds after the robot first moved, publish a second odometry on /odom from "
                             "another writer, at x = -10 m, as a stray driver would")
    parser.add_argument("--short-odom-after", type=float, metavar="S",
                        help="S seconds after the robot first moved, a stranger on the domain (a participant of "
                             "its own) also publishes on /odom messages named nav_msgs/msg/Odometry that hold a "
                             "header only, which cannot be read as odometry")
    parser.add_argument("--short-scan-after", type=float, metavar="S",
                        help="likewise on /scan: messages named sensor_msgs/msg/LaserScan that hold a header only")
    parser.add_argument("--scan-nan-after", type=float, metavar="S",
                        help="S seconds after the robot first moved, publish scans whose every beam is NaN")
    parser.add_argument("--odom-best-effort", action="store_true",
                        help="publish /odom best effort, as some drivers do (a reliable reader then hears nothing)")
    parser.add_argument("--record", metavar="FILE", help="write received Twists and a summary as JSON lines")
    parser.add_argument("--duration", type=float, metavar="S", help="exit after S seconds")
    parser.add_argument("--start-x", type=float, default=0.0, help="initial odom x, m")
    parser.add_argument("--start-y", type=float, default=0.0, help="initial odom y, m")
    parser.add_argument("--start-theta", type=float, default=0.0, help="initial odom yaw, rad")
    args = parser.parse_args()

    participant = DomainParticipant(int(os.environ.get("ROS_DOMAIN_ID", "0")))
    cmd_type = TwistStamped if args.stamped_cmd_vel else Twist

    def command_reader():
        return DataReader(participant, Topic(participant, ros_topic("cmd_vel", args.namespace), cmd_type), qos())

    cmd_reader = command_reader() if args.cmd_vel_reader_after is None else None
    odom_writer = DataWriter(participant, Topic(participant, ros_topic("odom", args.namespace), Odometry),
                             qos(sensor_data=args.odom_best_effort))
    second_odom_writer = DataWriter(participant, Topic(participant, ros_topic("odom", args.namespace), Odometry),
                                    qos()) if args.second_odom_after is not None else None
    stranger = DomainParticipant(int(os.environ.get("ROS_DOMAIN_ID", "0"))) \
        if args.short_odom_after is not None or args.short_scan_after is not None else None
    short_odom_writer = DataWriter(stranger, Topic(stranger, ros_topic("odom", args.namespace), ShortOdometry),
                                   qos()) if args.short_odom_after is not None else None
    short_scan_writer = DataWriter(stranger, Topic(stranger, ros_topic("scan", args.namespace), ShortLaserScan),
                                   qos(sensor_data=True)) if args.short_scan_after is not None else None
    scan_writer = DataWriter(participant, Topic(participant, ros_topic("scan", args.namespace), LaserScan),
                             qos(sensor_data=True)) if args.scan else None
    # Kept alive for the whole run: a static broadcaster's last message
    # reaches readers that join later (transient local).
    broadcasters = publish_static_transforms(participant, args) if args.tf_static else []
    waitset = WaitSet(participant)

    def listen_for_commands():
        waitset.attach(ReadCondition(cmd_reader, SampleState.Any | ViewState.Any | InstanceState.Any))

    if cmd_reader is not None:
        listen_for_commands()
    record = open(args.record, "w") if args.record else None

    stopping = []
    for signum in (signal.SIGTERM, signal.SIGINT):
        signal.signal(signum, lambda *_: stopping.append(True))
    print("robot ready", flush=True)

    x, y, theta = args.start_x, args.start_y, args.start_theta
    last_twist, last_twist_at = None, -math.inf
    started = last_tick = time.monotonic()
    moved_at = None
    odom_at = -math.inf
    period = 1.0 / args.rate
    next_tick = started + period
    while not stopping and (args.duration is None or time.monotonic() - started < args.duration):
        if cmd_reader is None and time.monotonic() - started >= args.cmd_vel_reader_after:
            cmd_reader = command_reader()
            listen_for_commands()
        if cmd_reader is None:
            time.sleep(max(0.0, next_tick - time.monotonic()))
        else:
            waitset.wait(int(max(0.0, next_tick - time.monotonic()) * 1e9))
        commands = cmd_reader.take(N=100) if cmd_reader is not None else []
        for command in (s for s in commands if s.sample_info.valid_data):
            twist = command.twist if args.stamped_cmd_vel else command
            last_twist, last_twist_at = twist, time.monotonic()
            if record:
                line = {"twist": asdict(twist), "t": last_twist_at, "odom_age": last_twist_at - odom_at}
                if args.stamped_cmd_vel:
                    line["header"] = asdict(command.header)
                record.write(json.dumps(line) + "\n")
        now = time.monotonic()
        if now < next_tick:
            continue
        next_tick += period * max(1, math.ceil((now - next_tick) / period))

        command = last_twist if last_twist is not None and now - last_twist_at <= COMMAND_TIMEOUT else Twist()
        v, w, dt = command.linear.x, command.angular.z, now - last_tick
        x += v * math.cos(theta + w * dt / 2) * dt
        y += v * math.sin(theta + w * dt / 2) * dt
        theta = math.atan2(math.sin(theta + w * dt), math.cos(theta + w * dt))
        last_tick = now
        if moved_at is None and (v or w):
            moved_at = now

        header = Header(stamp=stamp(), frame_id="odom")
        if args.stop_odom_after is None or moved_at is None or now - moved_at < args.stop_odom_after:
            odom = Odometry(header=header, child_frame_id="base_link")
            jumped = args.odom_jump_after is not None and moved_at is not None \
                and now - moved_at >= args.odom_jump_after
            odom.pose.pose.position.x, odom.pose.pose.position.y = x + (100.0 if jumped else 0.0), y
            odom.pose.pose.orientation = Quaternion(z=math.sin(theta / 2), w=math.cos(theta / 2))
            odom.twist.twist = command
            odom_writer.write(odom)
            odom_at = time.monotonic()
        if second_odom_writer and moved_at is not None and now - moved_at >= args.second_odom_after:
            stray = Odometry(header=header, child_frame_id="base_link")
            stray.pose.pose.position.x = -10.0
            stray.pose.pose.orientation = Quaternion(z=0.0, w=1.0)
            second_odom_writer.write(stray)
        if broadcasters and args.tf_static_turn_after is not None and moved_at is not None \
                and now - moved_at >= args.tf_static_turn_after:
            turned = math.radians(args.laser_mount[1] + 90.0)
            broadcasters[1].write(TFMessage(transforms=[transform("laser_plate", "laser", z=0.05, yaw=turned)]))
            args.tf_static_turn_after = None
        if short_odom_writer and moved_at is not None and now - moved_at >= args.short_odom_after:
            short_odom_writer.write(ShortOdometry(header=header))
        if short_scan_writer and moved_at is not None and now - moved_at >= args.short_scan_after:
            short_scan_writer.write(ShortLaserScan(header=header))
        if scan_writer:
            mount_x, mount_heading_deg = args.laser_mount
            scan_writer.write(LaserScan(
                header=Header(stamp=header.stamp, frame_id="laser" if any(args.laser_mount) or args.tf_static else "base_link"),
                angle_min=-math.pi, angle_max=math.pi - 2 * math.pi / BEAMS,
                angle_increment=2 * math.pi / BEAMS, scan_time=period,
                range_min=RANGE_MIN, range_max=RANGE_MAX,
                ranges=[math.nan] * BEAMS if args.scan_nan_after is not None and moved_at is not None
                and now - moved_at >= args.scan_nan_after else scan_ranges(
                    x + mount_x * math.cos(theta), y + mount_x * math.sin(theta),
                    theta + math.radians(mount_heading_deg), args.wall_x)))

    if record:
        summary = {"pose": {"x": x, "y": y, "theta": theta},
                   "last_twist": asdict(last_twist) if last_twist is not None else None}
        record.write(json.dumps({"summary": summary}) + "\n")
        record.close()


if __name__ == "__main__":
    main()
