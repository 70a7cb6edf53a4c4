#!/usr/bin/env bash
# Measures the stop chain of `ubf drive` against the emulated Powerbot, as
# docs/deploy.md reports it: time from the last SIP to the last motion
# command and to STOP, when the link is declared lost, time from SIGTERM to
# exit (STOP, standstill, ENABLE 0, CLOSE), time from SIGTERM to the STOP
# that ends the motion (over four times RUNS signals, at random points of
# the tick), and rows lost on SIGKILL.
#
#   scripts/measure-safety.sh [RUNS]      (default 5; needs a release build,
#                                          or UBF=path/to/ubf)
set -euo pipefail
runs=${1:-5}
here=$(cd "$(dirname "$0")/.." && pwd)
ubf="${UBF:-$here/target/release/ubf}"
[ -x "$ubf" ] || { echo "build first: cargo build --release" >&2; exit 2; }
work=$(mktemp -d)
trap 'pkill -f "$ubf emulate-powerbot --listen 127.0.0.1:0" 2>/dev/null || true; rm -rf "$work"' EXIT

# Starts an emulator with the given options; sets $emu_pid and $address.
start_emulator() {
    "$ubf" emulate-powerbot --listen 127.0.0.1:0 "$@" > "$work/emu.txt" &
    emu_pid=$!
    for _ in $(seq 50); do
        address=$(head -1 "$work/emu.txt" | awk '{print $NF}')
        [ -n "$address" ] && return
        sleep 0.1
    done
    echo "the emulator did not start" >&2; exit 1
}

robot_file() { # LOG EXTRA
    cat > "$work/robot.ron" <<EOF
RobotConfig(name: "measure", connection: "$address", model: Powerbot, log: "$1",
    goal: (x: 20.0, y: 0.0), $2
    root: Composite(arbiter: CommandFusion, children: [(behavior: GoTo(cruise_speed: 0.3))]))
EOF
}

# `name=value` from the emulator's report line.
field() { grep -o "$1=[^ ]*" "$work/emu.txt" | tail -1 | cut -d= -f2; }

median() { sort -g | awk '{a[NR]=$1} END {m=(NR%2)?a[(NR+1)/2]:(a[NR/2]+a[NR/2+1])/2; printf "%.3f (max %.3f)", m, a[NR]}'; }

: > "$work/motion"; : > "$work/stop"; : > "$work/lost"; : > "$work/term"; : > "$work/wait"; : > "$work/killed"
: > "$work/term-stop"
for run in $(seq "$runs"); do
    # Stale data: SIPs stop 3 s in, commands still reach the robot.
    start_emulator --silence 3:5
    robot_file "$work/stale-$run.csv" "on_link_loss: Exit,"
    "$ubf" drive "$work/robot.ron" 2> "$work/drive.txt" || true
    sleep 0.3; kill "$emu_pid"; wait "$emu_pid" 2>/dev/null || true
    field last_motion_after_silence_s >> "$work/motion"
    field stop_after_silence_s >> "$work/stop"
    grep -o "no sensor data for [0-9.]*" "$work/drive.txt" | awk '{print $NF}' >> "$work/lost"

    # SIGTERM while driving at 0.3 m/s.
    start_emulator
    robot_file "$work/term-$run.csv" ""
    "$ubf" drive "$work/robot.ron" 2> /dev/null &
    drive=$!
    sleep 3
    t0=$(date +%s.%N); kill -TERM "$drive"; wait "$drive" || true; t1=$(date +%s.%N)
    sleep 0.3; kill "$emu_pid"; wait "$emu_pid" 2>/dev/null || true
    echo "$t1 - $t0" | bc -l >> "$work/term"
    field stop_to_disable_s >> "$work/wait"

    # SIGTERM → the STOP that ends the motion, at four random points of a tick.
    for _ in 1 2 3 4; do
        start_emulator
        robot_file "$work/term-stop-$run.csv" ""
        "$ubf" drive "$work/robot.ron" 2> /dev/null &
        drive=$!
        sleep "2.$((RANDOM % 100))"
        t0=$(date +%s.%N); kill -TERM "$drive"; wait "$drive" || true
        sleep 0.3; kill "$emu_pid"; wait "$emu_pid" 2>/dev/null || true
        echo "$(field motion_stopped_at) - $t0" | bc -l >> "$work/term-stop"
    done

    # SIGKILL 4.5 s in: rows on disk against ticks run.
    start_emulator
    robot_file "$work/kill-$run.csv" ""
    "$ubf" drive "$work/robot.ron" 2> /dev/null &
    drive=$!
    sleep 4.5
    kill -KILL "$drive"; wait "$drive" 2>/dev/null || true
    kill "$emu_pid"; wait "$emu_pid" 2>/dev/null || true
    rows=$(($(wc -l < "$work/kill-$run.csv") - 1))
    echo "$rows" | awk '{printf "%.1f\n", 4.5 - $1 * 0.1}' >> "$work/killed"
done

echo "| measured over $runs runs, median (max) | seconds |"
echo "| --- | --- |"
echo "| last SIP → last motion command received | $(median < "$work/motion") |"
echo "| last SIP → first STOP received | $(median < "$work/stop") |"
echo "| last SIP → link declared lost | $(median < "$work/lost") |"
echo "| SIGTERM → the STOP that ends the motion ($(wc -l < "$work/term-stop") signals) | $(median < "$work/term-stop") |"
echo "| SIGTERM → process exit (robot at 0.3 m/s) | $(median < "$work/term") |"
echo "| of which STOP → ENABLE 0 (standstill wait) | $(median < "$work/wait") |"
echo "| rows lost on SIGKILL, as seconds of ticks | $(median < "$work/killed") |"
