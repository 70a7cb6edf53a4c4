#!/usr/bin/env bash
# How long ubf takes from odometry to command on a ROS 2 robot: the Cyclone
# DDS robot (robot.py) records, for each Twist it receives, how old the
# newest odometry it had published was; ubf drives it to a goal 2 m ahead
# RUNS times, in a private network namespace. Prints the median and the
# 99th percentile of that age over every command, with the control period
# beside them: ubf ticks on its own clock, so the age includes the wait
# for the next tick, up to one period.
#
#   scripts/ros2/latency.sh [RUNS] [UBF]    (defaults: 5, target/release/ubf)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
runs=${1:-5}
ubf=$(realpath "${2:-$root/target/release/ubf}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 "$root/scripts/ros2/robot.py" --help >/dev/null   # its environment, made outside the namespace
cat >"$work/robot.ron" <<'RON'
RobotConfig(
    name: "latency",
    connection: "ros2",
    model: Powerbot,
    period_s: 0.1,
    on_link_loss: Exit,
    goal: (x: 2.0, y: 0.0, tolerance: 0.2),
    root: Composite(arbiter: CommandFusion, children: [(behavior: Stop(), weight: 1.0), (behavior: GoTo(cruise_speed: 0.3))]),
)
RON
for run in $(seq "$runs"); do
    "$root/scripts/ros2/netns.sh" bash -c '
        python3 "$0/scripts/ros2/robot.py" --record "$1/record-$2.jsonl" --duration 60 >"$1/robot.out" 2>&1 & robot=$!
        until grep -q "robot ready" "$1/robot.out"; do sleep 0.1; done
        (cd "$1" && "$3" drive robot.ron --until-goal 2>/dev/null)
        kill -TERM $robot; wait $robot' "$root" "$work" "$run" "$ubf"
done
python3 - "$work" <<'PY'
import glob, json, statistics, sys
ages = [line["odom_age"] for path in glob.glob(sys.argv[1] + "/record-*.jsonl")
        for line in map(json.loads, open(path)) if "odom_age" in line]
ages.sort()
p99 = ages[min(len(ages) - 1, int(0.99 * len(ages)))]
print(f"{len(ages)} commands: odometry age at command, median {1000 * statistics.median(ages):.1f} ms, "
      f"p99 {1000 * p99:.1f} ms (control period 100 ms, odometry every 50 ms)")
PY
