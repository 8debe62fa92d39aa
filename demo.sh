#!/usr/bin/env bash
# The bench's main command: one crash scenario through the real processes on vcan.
#
#   ./demo.sh [--scenario FILE] [--out DIR] [--mf4]
#
# Installs what it needs (tests/setup-host.sh: can-utils, a Python venv with cantools, the vcan
# route), builds the bench, then runs `hil-bench` (candump + actuator-stubs + ecu +
# sensor-feeds) for the scenario — on the host if its kernel has vcan, otherwise inside a QEMU
# guest with a real Debian kernel (vcan-setup.sh says which route) — and decodes the CAN log
# with the DBC. Every run leaves run.mcap (Foxglove); --mf4 adds run.mf4 (CANape, asammdf).
# Default scenario: the paper's Taurus vs Taurus 48 + 48 km/h ABS case.
set -euo pipefail
cd "$(dirname "$0")"
scenario=scenarios/taurus-48-48-abs.toml
out=out
mf4=()
while [ $# -gt 0 ]; do
    case "$1" in
        --scenario) [ $# -ge 2 ] || { echo "demo: --scenario needs a file" >&2; exit 2; }; scenario=$2; shift 2 ;;
        --out) [ $# -ge 2 ] || { echo "demo: --out needs a folder" >&2; exit 2; }; out=$2; shift 2 ;;
        --mf4) mf4=(--mf4); shift ;;
        -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
        *) echo "demo: unknown argument $1 (try --help)" >&2; exit 2 ;;
    esac
done
[ -f "$scenario" ] || { echo "demo: no scenario file $scenario (see scenarios/)" >&2; exit 2; }

echo "demo: setting up the host (packages, cantools venv)…" >&2
# (A plain assignment, not `export PATH="$(…)"`: only so does a failed set-up stop the script.)
venv_bin=$(tests/setup-host.sh --disk-gb 1 | tail -n1)
export PATH="$venv_bin:$PATH"
target=${CARGO_TARGET_DIR:-target}
echo "demo: building the bench (release)…" >&2
cargo build --release --workspace --bins
name=$(sed -n 's/^name *= *"\(.*\)".*/\1/p' "$scenario" | head -n1)

# The output folder may be anywhere: the guest routes see the host read-only except the shares,
# so it is shared read-write too (vcan-setup.sh's VCAN_GUEST_RW).
mkdir -p "$out"
out=$(cd "$out" && pwd -P)
export VCAN_GUEST_RW="$out${VCAN_GUEST_RW:+:$VCAN_GUEST_RW}"

rc=0
# The run's recording (run.mcap, run.mf4) is written here on the host once the run has ended:
# inside an emulated guest it would cost ≈ 15× as much (record/src/pending.rs).
export RECORD_ON_HOST=1
./vcan-setup.sh --run -- "$target/release/hil-bench" --scenario "$scenario" --out "$out" --repo "$PWD" "${mf4[@]}" || rc=$?
"$target/release/record" pending "$out" || rc=$(( rc == 0 ? 1 : rc ))
"$target/release/actuator-stubs" draw-pending "$out" || rc=$(( rc == 0 ? 1 : rc ))

dir="$out/$name"
if [ -s "$dir/candump.log" ]; then
    python3 -m cantools decode bus/restraint.dbc < "$dir/candump.log" > "$dir/candump-decoded.txt"
    echo
    echo "CAN log decoded with bus/restraint.dbc (first commands):"
    grep -m 6 -E "AirbagStageCmd|BeltLimiterCmd" -A 9 "$dir/candump-decoded.txt" | head -n 24 || true
fi
echo
if [ "$rc" != 0 ]; then
    # A failed run never prints a success summary.
    echo "demo: FAILED (exit $rc): see the messages above; what the run left is in $dir/" >&2
    exit "$rc"
fi
echo "demo: everything is in $dir/:"
echo "  summary.txt           the summary above"
echo "  report.json           actuator stubs: commands, actions, occupant outcome (adaptive vs reference vs ideal)"
echo "  outcome.png           occupant deceleration and excursion over time, adaptive vs reference"
echo "  commands.jsonl        every received command frame with its CLOCK_MONOTONIC receive time and E2E verdict"
echo "  ecu-report.json       ECU timing report"
echo "  candump.log           raw bus log (candump -L), candump-decoded.txt decoded with cantools"
echo "  run.mcap              the whole run on one clock: open in Foxglove (layout record/foxglove-layout.json)"
[ -f "$dir/run.mf4" ] && echo "  run.mf4               CAN bus logging (DBC attached) + ECU diagnostics: open in asammdf or CANape"
exit "$rc"
