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
