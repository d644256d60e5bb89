#!/usr/bin/env bash
# Builds and runs the QEMU (lm3s6965evb, Cortex-M3) on-target tests and benchmarks.
# Tests pass/fail by semihosting exit code; benchmarks run under -icount shift=10 so
# SysTick counts instructions deterministically (see qemu/src/meter.rs).
# Prints a table of the figures; exits non-zero if a test or benchmark fails.
set -euo pipefail
cd "$(dirname "$0")"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}"
QEMU=(qemu-system-arm -cpu cortex-m3 -machine lm3s6965evb -nographic
      -semihosting-config enable=on,target=native)
TESTS=(bus_exchange pubsub_exchange param_exchange ceiling)
BENCHES=(bench bench_engine pubsub_bench bench_paths)

cargo build --release -p rtcan-board-qemu --bins
# The critical-section ceiling test needs the check the benchmarks leave out; built
# after them (the feature rebuilds the library), it writes only its own binary.
cargo build --release -p rtcan-board-qemu --bin ceiling --features ceiling-check
# The named interrupt paths (bench_paths) are measured in the firmware images' build:
# opt-level z (examples/triskar2/Cargo.toml), not this workspace's s.
CARGO_PROFILE_RELEASE_OPT_LEVEL=z cargo build --release -p rtcan-board-qemu --bin bench_paths \
    --target-dir "$CARGO_TARGET_DIR/opt-z"
bin="$CARGO_TARGET_DIR/thumbv7m-none-eabi/release"
status=0
for t in "${TESTS[@]}"; do
    if timeout 300 "${QEMU[@]}" -kernel "$bin/$t" > "$CARGO_TARGET_DIR/$t.out" 2>&1; then
        echo "test $t ... ok"
    else
        echo "test $t ... FAILED"; cat "$CARGO_TARGET_DIR/$t.out"; status=1
    fi
done
for b in "${BENCHES[@]}"; do
    out="$CARGO_TARGET_DIR/$b.out"
    elf="$bin/$b"
    [ "$b" = bench_paths ] && elf="$CARGO_TARGET_DIR/opt-z/thumbv7m-none-eabi/release/$b"
    if ! timeout 300 "${QEMU[@]}" -icount shift=10,sleep=off -kernel "$elf" > "$out" 2>&1; then
        echo "bench $b ... FAILED"; cat "$out"; status=1; continue
    fi
    printf '%-28s %10s %10s %8s\n' "Cortex-M3 instructions" "max" "mean" "samples"
    awk '/^BENCH/ { printf "%-28s %10s %10s %8s\n", $2, $4, $6, $8 }' "$out"
done
exit $status
