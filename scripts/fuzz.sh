#!/usr/bin/env bash
# Runs one fuzz target (README "Fuzzing"), niced so it never starves other work:
#   bash scripts/fuzz.sh TARGET SECONDS [RUNS]   fuzz for SECONDS (or until RUNS executions)
#   bash scripts/fuzz.sh --cmin TARGET            minimise fuzz/corpus/TARGET (`cargo fuzz cmin`)
# TARGET: robot_toml, engine_rx or candump. New inputs go to fuzz/target/new-corpus/TARGET
# (not committed); `--cmin` merges them into the committed corpus, keeping only inputs
# that add coverage. libFuzzer's last lines give the execution count and exec/s.
# FUZZ_TIMEOUT=S raises the per-input timeout (default 10 s): under nice -n 19 on a loaded
# machine a starved process can pass 10 s on an input that takes 0.25 s alone.
# FUZZ_NICE=N sets the niceness (default 19; 0 gives a long run its own core).
# A crash is written to fuzz/artifacts/TARGET/: fix the bug, keep the file (the stable
# replay test `cargo test -p rtcan-fuzz` runs it from then on).
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
bash ../scripts/fuzz-setup.sh >/dev/null
export CARGO_INCREMENTAL=0

flags() {
  case "$1" in
    robot_toml) echo "-max_len=8192 -dict=robot_toml.dict" ;;
    engine_rx) echo "-max_len=4096" ;;
    candump) echo "-max_len=4096 -dict=candump.dict" ;;
    *) echo "unknown target '$1' (robot_toml, engine_rx, candump)" >&2; exit 2 ;;
  esac
}

if [ "${1:-}" = "--cmin" ]; then
  target=${2:?usage: fuzz.sh --cmin TARGET}
  extra=$(flags "$target")
  mkdir -p "corpus/$target"
  if [ -d "target/new-corpus/$target" ]; then
    cp -n "target/new-corpus/$target"/* "corpus/$target/" 2>/dev/null || true
  fi
  # shellcheck disable=SC2086
  nice -n "${FUZZ_NICE:-19}" cargo +nightly fuzz cmin -s none "$target" -- $extra -timeout=10
  rm -rf "target/new-corpus/$target"
  du -sh "corpus/$target"
  exit 0
fi

target=${1:?usage: fuzz.sh TARGET SECONDS [RUNS]}
seconds=${2:?usage: fuzz.sh TARGET SECONDS [RUNS]}
runs=${3:--1}
extra=$(flags "$target")
mkdir -p "target/new-corpus/$target" "corpus/$target"
# shellcheck disable=SC2086
exec nice -n "${FUZZ_NICE:-19}" cargo +nightly fuzz run -s none "$target" "target/new-corpus/$target" "corpus/$target" -- \
  $extra -timeout="${FUZZ_TIMEOUT:-10}" -max_total_time="$seconds" -runs="$runs" -print_final_stats=1
