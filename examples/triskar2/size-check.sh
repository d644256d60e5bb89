#!/usr/bin/env bash
# Builds every Triskar2 module image (release, thumbv7m-none-eabi, flip-link) and checks
# its flash and static RAM against budgets.toml with llvm-size (boards/size-check.sh).
# Prints a table; exits non-zero when an image is over budget or does not build.
# Also prints the proximity module's goal (16 KiB flash / 4 KiB RAM), not enforced.
set -euo pipefail
cd "$(dirname "$0")"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}"
command -v flip-link >/dev/null || { echo "flip-link not found: cargo install flip-link"; exit 1; }
cargo build --release --bins
dir="$CARGO_TARGET_DIR/thumbv7m-none-eabi/release"
status=0
bash ../../boards/size-check.sh budgets.toml "$dir" || status=$?
goal=$(mktemp)
trap 'rm -f "$goal"' EXIT
printf '[proximity]\nflash = 16384\nram = 4096\n' > "$goal"
echo "goal (not enforced):"
bash ../../boards/size-check.sh "$goal" "$dir" | tail -n +2 | sed 's/OVER$/over goal/' || true
exit $status
