#!/usr/bin/env bash
# The main job on a machine without hardware: check the robot description, build every
# module's firmware image from it, then run the whole robot in the simulator.
# Usage: bash scripts/run.sh [robot.toml] [extra `rtcan sim` options, e.g. --seconds 20 --out sim-out]
set -euo pipefail
cd "$(dirname "$0")/.."
robot="${1:-robot.toml}"
shift || true

bash scripts/setup.sh

echo "== rtcan check $robot (admission, IDs, filters, calendar)"
cargo run --release --quiet -p rtcan-cli -- check "$robot"

echo "== firmware images (thumbv7m-none-eabi), one per module, with size budgets"
bash examples/triskar2/size-check.sh

echo "== simulation"
cargo run --release --quiet -p rtcan-cli -- sim "$robot" "$@"
