#!/usr/bin/env bash
# The whole test suite, from a fresh Debian/Ubuntu machine with Rust:
#   installs what it needs, checks formatting and lints, runs every test (those that need
#   vcan run inside a QEMU guest with a real Debian kernel when this kernel has no SocketCAN; a small
#   characteristic diagram is built end to end), fuzzes every decoder and parser briefly,
#   and checks the deterministic instruction-count budget of the worst-case ECU cycle.
# Wall-clock budgets are a separate command (docs/results.md, "Timing"): this VM is too noisy
# for a test to fail on them.
set -euo pipefail
cd "$(dirname "$0")"
# (A plain assignment, not `export PATH="$(…)"`: only so does a failed set-up stop the script.)
venv_bin=$(tests/setup-host.sh --disk-gb 4 | tail -n1)
export PATH="$venv_bin:$PATH"
export CARGO_TERM_COLOR=${CARGO_TERM_COLOR:-never}

# Where the suite's time goes: each step's wall time, printed at the end.
times=() last_name="set-up (packages, venv, vcan route, disk check)" last_t=0
step() {
  times+=("$(printf '%5d s  %s' $((SECONDS - last_t)) "$last_name")")
  last_name=${1%% (*}; last_name=${last_name%%:*}; last_t=$SECONDS
  printf '\n=== %s ===\n' "$*"
}

step "format and lints"
cargo fmt --all --check
cargo clippy --workspace --all-targets --release -- -D warnings

step "build the bench processes and the tests"
# One build with the test suite's feature set (dev-dependencies switch features on in shared
# crates, e.g. bitflags/std): the bench binaries the end-to-end tests run, the tests
# themselves, and the budget tools below all come from it, so nothing is compiled twice
# (tests/src/lib.rs `harness::build_bench_bins` runs this same command: a no-op here).
cargo build --workspace --release --features bus/socket --bins --tests --examples

step "docs: every README command run (or its tool and flags checked), every printed number regenerated (≈ 5 s)"
# A block that differs from what its command prints now fails here; `target/release/docs-check
# --fix` rewrites it (markers and rules: tests/src/docs.rs).
target/release/docs-check

step "tests (unit, property, physics oracles, LUT build, real vcan + iceoryx2 end to end)"
log=$(mktemp); trap 'rm -f "$log"' EXIT
cargo test --workspace --release --features bus/socket 2>&1 | tee "$log"
totals=$(awk '/^test result:/ { p += $4; f += $6 } END { printf "%d passed, %d failed", p, f }' "$log")

step "misuse matrix gate: 16 000 seeded misuse / single-fault / must-fire variants through the core (≈ 10 s on 2 cores)"
# Every family that holds must stay at 0 fires where none may, 0 misses, 0 stuck crash phases;
# the families still open (e2e_tests::misuse::OPEN) and the beyond-physics sweep are printed.
target/release/misuse-matrix --variants 16000 --seed 7 --gate --quiet

step "fuzz smoke: every cargo-fuzz target for ${FUZZ_SECONDS:=4} s"
cargo fuzz --version >/dev/null 2>&1 || cargo install --locked cargo-fuzz
mkdir -p target/robustness
FUZZ_SECONDS=$FUZZ_SECONDS FUZZ_REPORT_JSON="$PWD/target/robustness/fuzz.json" tests/fuzz-smoke.sh

step "deterministic budget: instructions per worst-case ECU cycle (valgrind)"
target/release/budget --no-criterion --prebuilt

step "wall clock: the full-cycle rows beside a reference workload (a report, not judged)"
target/release/cycle-timing --rounds 100000

step "worst-case search: a short run from the committed seeds, no case above the budget"
# Seconds; the long search that found the seeds is in benches/README.md ("Worst case, searched").
# Each search fails above the line benches/budgets.toml gives its seed's row (written once).
target/release/worst-cycle search --generations 3 --population 16 --cycles no-crash \
  --start benches/worst-case/seed.json --budgets benches/budgets.toml
target/release/worst-cycle search --generations 3 --population 16 --cycles no-crash \
  --secoc on --start benches/worst-case/seed-secoc.json --budgets benches/budgets.toml
target/release/worst-cycle search --generations 3 --population 16 --cycles crash \
  --secoc on --start benches/worst-case/seed-crash-phase.json --budgets benches/budgets.toml

step "robustness report (fault campaign of the tests above + fuzz smoke)"
target/release/fault-campaign report --campaign target/robustness/campaign.json \
  --fuzz target/robustness/fuzz.json --host-timing target/robustness/host-timing.json

step "done"
echo
echo "test.sh: all steps passed"
echo "cargo tests: $totals"
echo "where the time went ($SECONDS s in all):"
printf '  %s\n' "${times[@]}"
