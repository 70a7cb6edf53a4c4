#!/usr/bin/env python3
"""Listen to ROS 2 topics with Cyclone DDS and report what arrived, as JSON.

    listen.py /odom=nav_msgs/msg/Odometry /scan=sensor_msgs/msg/LaserScan:best_effort --duration 5

Checks from outside that a ROS 2 publisher (ubf's) is heard by an
implementation nobody here wrote. Each topic is read with ROS 2's default
QoS (reliable, keep last 10), with `:best_effort` sensor data QoS (best
effort, keep last 5), which also hears reliable writers, or with `:latched`
tf2's static listener QoS (reliable, transient local, keep all). After --duration
seconds, or as soon as every topic has --min samples when --min is given, it
prints one JSON object {topic: {"type", "count", "last", "recent"}} ("last" is
the last sample as a dict, or null; "recent" the last ten, oldest first: two
topics published each tick may stop a tick apart) and exits 0 if every topic
got at least --min samples (default 1; a latched topic, one), else 1. Prints "listen ready" to stderr once subscribed.
Run it inside scripts/ros2/netns.sh.
"""
import argparse
import json
import math
import os
import sys
import time
from collections import deque
from dataclasses import asdict

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import script_env  # noqa: E402

script_env.ensure(".venv-ros2", ["cyclonedds==11.0.1"], ["cyclonedds"])

from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

from ros2_types import TYPES, qos, ros_topic, static_qos  # noqa: E402


QOS_OPTIONS = {"": lambda: qos(), "best_effort": lambda: qos(sensor_data=True),
               "latched": lambda: static_qos(reader=True)}


def subscription(spec):
    """`/odom=nav_msgs/msg/Odometry[:best_effort|:latched]` as (topic, type name, QoS option)."""
    topic, sep, type_name = spec.partition("=")
    type_name, _, option = type_name.partition(":")
    if not sep or type_name not in TYPES or option not in QOS_OPTIONS:
        raise argparse.ArgumentTypeError(f"{spec!r}: want /topic=pkg/msg/Type[:best_effort|:latched], "
                                         f"Type one of {', '.join(TYPES)}")
    return topic, type_name, option


def finite(value):
    """`value` with every infinite or NaN float as the string JSON cannot hold otherwise ("inf", "-inf", "nan")."""
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [finite(v) for v in value]
    return value


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("topics", nargs="+", type=subscription,
                        metavar="/topic=pkg/msg/Type[:best_effort|:latched]")
    parser.add_argument("--duration", type=float, default=5.0, help="listen at most this long, seconds")
    parser.add_argument("--min", type=int, help="stop once every topic has this many samples")
    args = parser.parse_args()
    needed = args.min if args.min is not None else 1

    participant = DomainParticipant(int(os.environ.get("ROS_DOMAIN_ID", "0")))
    waitset = WaitSet(participant)
    readers, report = {}, {}
    for topic, type_name, option in args.topics:
        reader = DataReader(participant, Topic(participant, ros_topic(topic), TYPES[type_name]), QOS_OPTIONS[option]())
        waitset.attach(ReadCondition(reader, SampleState.Any | ViewState.Any | InstanceState.Any))
        readers[topic] = reader
        report[topic] = {"type": type_name, "count": 0, "last": None, "recent": deque(maxlen=10),
                         # A latched topic holds one message a writer: one is enough.
                         "needed": 1 if option == "latched" else needed}
    print("listen ready", file=sys.stderr, flush=True)

    deadline = time.monotonic() + args.duration
    while time.monotonic() < deadline:
        if args.min is not None and all(entry["count"] >= entry["needed"] for entry in report.values()):
            break
        waitset.wait(int(max(0.0, deadline - time.monotonic()) * 1e9))
        for topic, reader in readers.items():
            for sample in reader.take(N=1000):
                if sample.sample_info.valid_data:
                    report[topic]["count"] += 1
                    report[topic]["last"] = asdict(sample)
                    report[topic]["recent"].append(report[topic]["last"])

    heard_enough = all(entry.pop("needed") <= entry["count"] for entry in report.values())
    for entry in report.values():
        entry["recent"] = list(entry["recent"])
    print(json.dumps(finite(report)))
    sys.exit(0 if heard_enough else 1)


if __name__ == "__main__":
    main()
