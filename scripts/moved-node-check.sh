#!/usr/bin/env bash
# Issue 14's moved-node test (R2P §5.2): robots/triskar2-moved.toml is the workspace
# robot.toml with the `kinematics` node on motor2 instead of motor1. With RTCAN_ROBOT
# pointing at it, the unchanged Triskar2 node code (examples/triskar2/nodes: the module
# apps are generated from robot.toml's placement by its build.rs)
#   1. simulates: rtcan-sim's tests/moved_node.rs runs the triskar2 scenario, asserts
#      kinematics runs on motor2 only (motor2 sends wheel_setpoints), the robot reaches
#      the wall and stops short of it, HRT misses 0;
#   2. builds: every Triskar2 image (release, thumbv7m, flip-link) within
#      examples/triskar2/budgets.toml (size-check.sh).
# Prints the wall time.
#
# Cost: RTCAN_ROBOT changes the `rtcan` facade's generated code, so the host build of
# rtcan, triskar2-nodes and rtcan-sim is redone in the host target dir (and again by the
# next plain build); the images go to target/scaffold-fw (shared with
# scripts/scaffold-check.sh), never to examples/triskar2/target, whose images rtcan-emu
# reads.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
start=$(date +%s)
command -v flip-link >/dev/null || { echo "flip-link not found: cargo install flip-link"; exit 1; }
host_target="${CARGO_TARGET_DIR:-$root/target}"
export RTCAN_ROBOT="$root/robots/triskar2-moved.toml"
echo "== moved node: kinematics on motor2 ($RTCAN_ROBOT), simulated"
CARGO_TARGET_DIR="$host_target" MOVED_NODE_KINEMATICS=motor2 \
    cargo test -q -p rtcan-sim --test moved_node -- --nocapture 2>&1 | grep -E "^(kinematics on|gateway|motor[0-9]|proximity|psu) |test result"
echo "== moved node: every Triskar2 image within its budget"
(cd examples/triskar2 && CARGO_TARGET_DIR="$host_target/scaffold-fw" bash size-check.sh)
echo "moved-node-check: ok, wall time $(( $(date +%s) - start )) s"
