#!/usr/bin/env bash
# Issue 14's CI check: `rtcan new` writes the workspaces of two robots that are not
# Triskar2 (robots/kapeck.toml, robots/arm12.toml) into a temporary directory; every
# image of both is built (release, thumbv7m-none-eabi, flip-link) and checked against
# its budget (firmware/size-check.sh), then each robot's nodes run in the simulator
# (`cargo run -p sim`, 2 s: exit 1 unless every module synchronised and the HRT misses
# are 0). Prints the wall time.
#
# Cost: the two robots share one firmware target dir (target/scaffold-fw: dependencies
# built once; not examples/triskar2/target, whose images rtcan-emu reads and which
# same-named modules, e.g. `gateway`, would overwrite) and the host target dir (target/,
# where the workspace tests already built rtcan-sim). SCAFFOLD_KEEP=DIR keeps the
# workspaces in DIR instead of a deleted temporary directory.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
start=$(date +%s)
command -v flip-link >/dev/null || { echo "flip-link not found: cargo install flip-link"; exit 1; }
host_target="${CARGO_TARGET_DIR:-$root/target}"
fw_target="$host_target/scaffold-fw"
if [ -n "${SCAFFOLD_KEEP:-}" ]; then
    work="$SCAFFOLD_KEEP"; mkdir -p "$work"
else
    work="$(mktemp -d)"; trap 'rm -rf "$work"' EXIT
fi
CARGO_TARGET_DIR="$host_target" cargo build -q -p rtcan-cli
rtcan="$host_target/debug/rtcan"
for robot in kapeck arm12; do
    echo "== $robot: rtcan new, images within budgets, simulation"
    "$rtcan" new "$work/$robot" --robot "robots/$robot.toml" > /dev/null
    (cd "$work/$robot/firmware" && CARGO_TARGET_DIR="$fw_target" bash size-check.sh)
    (cd "$work/$robot" && CARGO_TARGET_DIR="$host_target" cargo run -q -p sim -- --seconds 2)
done
echo "scaffold-check: ok, wall time $(( $(date +%s) - start )) s"
