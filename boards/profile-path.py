#!/usr/bin/env python3
"""Where a named path's instructions go: runs a QEMU benchmark (bench_paths by default)
one instruction per translation block with `-d exec,nochain`, cuts the trace into the
measured calls (from `PathMeter::measure` to the return to its caller) and prints, for
the worst call that touches every function named by --with, the instructions per
function (the meter's own bookkeeping, e.g. `to_instructions`, shows up too: subtract it).

  python3 boards/profile-path.py [--elf ELF] [--with SofClock --with SlotClock] [--top N]

Defaults to the opt-level z build of `bash boards/run-qemu.sh` and the sync path
(`task_sync_slave`: calls touching both `SofClock` and `SlotClock`). The trace is
streamed through a FIFO, never written to disk; a run takes 1–2 minutes (nice it).
Issue 10: found the 64-bit division by 4, the variable 64-bit shifts (library calls at
opt-level z) and the byte packing on the receive path.
"""
import argparse, bisect, collections, os, re, subprocess, sys, tempfile

here = os.path.dirname(os.path.abspath(__file__))
ap = argparse.ArgumentParser()
ap.add_argument("--elf", default=os.path.join(
    here, "target/opt-z/thumbv7m-none-eabi/release/bench_paths"))
ap.add_argument("--with", dest="needles", action="append")
ap.add_argument("--top", type=int, default=30)
a = ap.parse_args()
needles = a.needles or ["SofClock", "SlotClock"]
sysroot = subprocess.run(["rustc", "--print", "sysroot"], capture_output=True,
                         text=True).stdout.strip()
host = re.search(r"host: (\S+)", subprocess.run(["rustc", "-vV"], capture_output=True,
                                                text=True).stdout).group(1)
nm = os.path.join(sysroot, "lib/rustlib", host, "bin/llvm-nm")
syms = []
for line in subprocess.run([nm, "-S", "-C", a.elf], capture_output=True,
                           text=True).stdout.splitlines():
    p = line.split(None, 3)
    if len(p) == 4 and p[2] in "tT":
        syms.append((int(p[0], 16) & ~1, int(p[1], 16), p[3]))
syms.sort()
starts = [s[0] for s in syms]


def sym(pc):
    i = bisect.bisect_right(starts, pc) - 1
    return syms[i][2] if i >= 0 and pc < syms[i][0] + syms[i][1] else "?"


def ranges(pat):
    return [(s, s + n) for s, n, name in syms if re.search(pat, name)]


measure = ranges(r"PathMeter::measure")
callers = ranges(r"protocol_task::h|Node\$GT\$::(poll|rx|tx_done)::h")
inr = lambda pc, rs: any(lo <= pc < hi for lo, hi in rs)
with tempfile.TemporaryDirectory() as d:
    fifo = os.path.join(d, "trace")
    os.mkfifo(fifo)
    qemu = subprocess.Popen(
        ["qemu-system-arm", "-cpu", "cortex-m3", "-machine", "lm3s6965evb", "-nographic",
         "-semihosting-config", "enable=on,target=native", "-icount", "shift=10,sleep=off",
         "-singlestep", "-d", "exec,nochain", "-D", fifo, "-kernel", a.elf],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    pat = re.compile(r"\[[0-9a-f]+/([0-9a-f]+)/")
    worst, cur = None, None
    with open(fifo) as f:
        for line in f:
            m = pat.search(line)
            if not m:
                continue
            pc = int(m.group(1), 16)
            if cur is None:
                if inr(pc, measure):
                    cur = collections.Counter()
                continue
            if inr(pc, callers):
                names = {sym(p) for p in cur}
                if all(any(n in s for s in names) for n in needles):
                    if worst is None or sum(cur.values()) > sum(worst.values()):
                        worst = cur
                cur = None
            elif not inr(pc, measure):
                cur[pc] += 1
    qemu.wait()
if worst is None:
    sys.exit("no measured call touches " + ", ".join(needles))
by = collections.Counter()
for pc, n in worst.items():
    by[sym(pc)] += n
print("worst call:", sum(worst.values()), "instructions")
for name, n in by.most_common(a.top):
    print(f"{n:6d}  {name[:120]}")
