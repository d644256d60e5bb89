#!/usr/bin/env bash
# Idempotent set-up from the project's own files, for a fresh machine (and CI):
# the toolchain of rust-toolchain.toml with its target and components (also when
# RUSTUP_AUTO_INSTALL=0), flip-link for the firmware, and with `--qemu` Debian's
# qemu-system-arm for the on-target tests.
set -euo pipefail
cd "$(dirname "$0")/.."
rustup show active-toolchain >/dev/null 2>&1 || rustup toolchain install stable --profile minimal
rustup target add thumbv7m-none-eabi >/dev/null
rustup component add llvm-tools clippy rustfmt >/dev/null
command -v flip-link >/dev/null 2>&1 || cargo install flip-link --locked --quiet
if [ "${1:-}" = "--qemu" ] && ! command -v qemu-system-arm >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ]; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq qemu-system-arm >/dev/null
  else
    echo "qemu-system-arm missing: run 'sudo apt-get install qemu-system-arm'" >&2
    exit 1
  fi
fi
# rtcan-emu links Debian's libunicorn (Unicorn 2); a prebuilt package installs in seconds,
# where the unicorn-engine crate would compile Unicorn from C source with cmake.
if [ "${1:-}" = "--qemu" ] && [ ! -e /usr/include/unicorn/unicorn.h ]; then
  if [ "$(id -u)" = 0 ]; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libunicorn-dev >/dev/null
  else
    echo "libunicorn-dev missing: run 'sudo apt-get install libunicorn-dev'" >&2
    exit 1
  fi
fi
# Third-party readers of our output (rtcan-cli/tests/interop.rs, with RTCAN_REQUIRE_INTEROP=1
# set by scripts/test.sh): can-utils' log2asc reads our candump logs, cantools our DBC.
if [ "${1:-}" = "--qemu" ] && ! command -v log2asc >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ]; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq can-utils >/dev/null
  else
    echo "can-utils missing: run 'sudo apt-get install can-utils'" >&2
    exit 1
  fi
fi
if [ "${1:-}" = "--qemu" ] && ! python3 -c "import cantools" >/dev/null 2>&1; then
  # Debian's python3 has no pip until python3-pip is installed, and refuses installs into
  # the system interpreter (PEP 668) unless told; a pyenv/venv python3 takes the first form.
  if ! python3 -m pip --version >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-pip >/dev/null
  fi
  python3 -m pip install --quiet -r scripts/interop-requirements.txt ||
    python3 -m pip install --quiet --break-system-packages -r scripts/interop-requirements.txt
fi
