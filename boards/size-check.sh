#!/usr/bin/env bash
# size-check.sh BUDGETS.toml ELF_DIR
# Measures every image named in BUDGETS.toml with llvm-size (llvm-tools component) and
# fails when one exceeds its budget. Budget file format, one table per image:
#   [proximity]
#   flash = 16384   # bytes: .vector_table + .text + .rodata + .data
#   ram = 4096      # bytes: .data + .bss + .uninit (static RAM, stack excluded)
# Also fails when a generated topic static (`robot_toml::<module>::topics::…`) is in
# .data: its state must start all-zero (.bss), or its initial value is stored in flash
# a second time (rtcan-pubsub topic.rs, "Flash").
set -euo pipefail
budgets=$1; dir=$2
tools="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin"
size="$tools/llvm-size"
status=0
printf '%-14s %8s %8s %8s %8s  %s\n' image flash budget ram budget result
for img in $(sed -n 's/^\[\([A-Za-z0-9_-]*\)\]$/\1/p' "$budgets"); do
    fb=$(awk -v s="[$img]" '$0==s{f=1;next} /^\[/{f=0} f&&$1=="flash"{print $3}' "$budgets")
    rb=$(awk -v s="[$img]" '$0==s{f=1;next} /^\[/{f=0} f&&$1=="ram"{print $3}' "$budgets")
    if [ ! -f "$dir/$img" ]; then echo "$img: missing image $dir/$img"; status=1; continue; fi
    read -r flash ram < <("$size" -A "$dir/$img" | awk '
        $1==".vector_table"||$1==".text"||$1==".rodata"{f+=$2}
        $1==".data"{f+=$2; r+=$2} $1==".bss"||$1==".uninit"{r+=$2}
        END{print f+0, r+0}')
    res=ok
    if [ "$flash" -gt "$fb" ] || [ "$ram" -gt "$rb" ]; then res=OVER; status=1; fi
    printf '%-14s %8s %8s %8s %8s  %s\n' "$img" "$flash" "$fb" "$ram" "$rb" "$res"
    data_topics=$("$tools/llvm-nm" -C "$dir/$img" | awk '$2=="d"||$2=="D"' | grep '::topics::' || true)
    if [ -n "$data_topics" ]; then
        echo "$img: topic statics in .data (initial state not all zeros):"
        echo "$data_topics"
        status=1
    fi
done
exit $status
