#!/usr/bin/env bash
# Admission on hostile period changes (README figures): robots/hrt200.toml with the
# period of one topic (t004: 64 slots, t100: 512, t180: 1024) set to every value
# 2..130, through `rtcan check`. Prints how many files end with each verdict and
# every run slower than 1 s. Usage: bash scripts/admission-sweep.sh [path/to/rtcan]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-target/release/rtcan}
[ -x "$bin" ] || cargo build --release -p rtcan-cli
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
declare -A verdicts=()
for topic in t004 t100 t180; do
    for period in $(seq 2 130); do
        # Replace the period_slots line of this topic's table only.
        awk -v t="[topics.$topic]" -v p="$period" '
            $0 == t { inside = 1 }
            /^\[/ && $0 != t { inside = 0 }
            inside && /^period_slots = / { $0 = "period_slots = " p }
            { print }' robots/hrt200.toml > "$tmp/r.toml"
        start=$(date +%s.%N)
        verdict=admissible
        if ! "$bin" check "$tmp/r.toml" > /dev/null 2> "$tmp/err"; then
            verdict=$(sed -n '1s/^error\[\([a-z-]*\)\].*/\1/p' "$tmp/err")
        fi
        end=$(date +%s.%N)
        verdicts[$verdict]=$(( ${verdicts[$verdict]:-0} + 1 ))
        if awk -v a="$start" -v b="$end" 'BEGIN { exit !(b - a > 1) }'; then
            echo "slow: $topic period $period: $verdict ($(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f s", b - a }'))"
        fi
    done
done
for v in "${!verdicts[@]}"; do echo "$v: ${verdicts[$v]}"; done | sort
