#!/usr/bin/env bash
# The project's test command (README): host tests, then on-target tests under QEMU,
# then the firmware images and their size budgets. Fails on the first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --qemu
# setup.sh installed log2asc and cantools: the interop tests must use them, not skip them.
export RTCAN_REQUIRE_INTEROP=1

echo "== host tests (cargo test --workspace, with rtcan-fuzz replaying the fuzz corpora on stable; rtcan-emu after the images are built)"
cargo test --workspace --exclude rtcan-emu

echo "== simulator on the modelled CPU: issue 10's before/after table (docs/SIM.md)"
cargo run --release -q -p rtcan-sim --example cpu_before_after

echo "== shortened fault campaign (issue 11; README's table: --seconds 1000)"
# 30 cases x 7 s on the modelled CPU (~5 s release): exits 1 if any case has a bad
# delivery, more cycles with two syncs than it allows, a wrong safe state or master, or
# frames out of their slots (rtcan_sim::campaign::Row::goals).
cargo run --release -q -p rtcan-cli -- sim robot.toml --campaign --seconds 7 > /dev/null

host=$(rustc -vV | sed -n 's/^host: //p')
echo "== host tests of the firmware workspaces' portable crates"
(cd boards && cargo test -p rtcan-board-common --target "$host")
(cd examples/triskar2 && cargo test -p triskar2-link --target "$host")

echo "== on-target tests under QEMU (Cortex-M3, lm3s6965evb)"
bash boards/run-qemu.sh
# The committed cost table (simulator CPU model, timing check) matches the QEMU rows.
bash scripts/update-costs.sh --check

echo "== Triskar2 firmware images and size budgets"
bash examples/triskar2/size-check.sh

echo "== the Triskar2 images on emulated STM32F103 (rtcan-emu, docs/EMULATOR.md)"
cargo test --release -p rtcan-emu
echo "== issue 15: bootloader image (thumbv7m) within its 8 KiB budget; rtcan param on the simulated robot"
(cd rtcan-boot/bootloader && cargo build --release -q && \
    bash ../../boards/size-check.sh budget.toml target/thumbv7m-none-eabi/release)
cargo run -q -p rtcan-cli -- param set motor1.kp 0.8 --sim robot.toml
echo "== issue 15: firmware update over the simulated bus (28 KiB to motor1, robot running)"
cargo run -q -p rtcan-cli -- flash robot.toml --module motor1
echo "== issue 14: two robots that are not Triskar2 scaffolded by rtcan new, every image built within budget, their nodes simulated (HRT misses 0)"
bash scripts/scaffold-check.sh
echo "== issue 14: moved-node test (kinematics on motor2, odometry on motor3: the same node code simulated, every image within budget)"
bash scripts/moved-node-check.sh
