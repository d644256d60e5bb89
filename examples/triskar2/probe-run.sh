#!/usr/bin/env bash
# Cargo runner of the module images (.cargo/config.toml): flashes and runs an image with
# probe-rs on the chip its module's board names in ../../robot.toml (`board = ...`), so
# the gateway (stm32f103re) is not flashed as a C8. Usage (by cargo): probe-run.sh ELF [ARGS]
set -euo pipefail
elf="$1"; shift
module="$(basename "$elf")"
toml="$(dirname "$0")/../../robot.toml"
board="$(awk -v m="[modules.$module]" '
    $1 == m { found = 1; next }
    /^\[/ { found = 0 }
    found && $1 == "board" { gsub(/"/, "", $3); print $3; exit }' "$toml")"
case "$board" in
    stm32f103c8) chip=STM32F103C8 ;;
    stm32f103rb) chip=STM32F103RB ;;
    stm32f103re) chip=STM32F103RE ;;
    "") echo "probe-run: module '$module' has no board in $toml" >&2; exit 1 ;;
    *) echo "probe-run: board '$board' of module '$module' has no probe-rs chip here" >&2; exit 1 ;;
esac
if [ "${PROBE_RUN_DRY:-}" = 1 ]; then
    echo "probe-rs run --chip $chip $elf $*"
    exit 0
fi
exec probe-rs run --chip "$chip" "$elf" "$@"
