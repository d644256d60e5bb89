#!/usr/bin/env bash
# Fuzzing only (README "Fuzzing"): a nightly toolchain (libFuzzer's sanitizer-coverage
# flags need it) and cargo-fuzz. CI and every other script stay on the stable toolchain
# of rust-toolchain.toml; the corpora are replayed on stable by `cargo test -p rtcan-fuzz`.
# Idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."
rustup toolchain list | grep -q '^nightly' || rustup toolchain install nightly --profile minimal
command -v cargo-fuzz >/dev/null 2>&1 || cargo +stable install cargo-fuzz --version 0.13.2 --locked --quiet
cargo +nightly fuzz --version
