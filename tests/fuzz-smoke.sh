#!/usr/bin/env bash
# Short fuzz run of every cargo-fuzz target (fuzz/fuzz_targets), for the test suite.
#
# Builds the targets once (cargo-fuzz, sanitizer-coverage instrumented; on a stable toolchain
# RUSTC_BOOTSTRAP=1 unlocks the nightly flags for this build only), then runs each target for
# FUZZ_SECONDS over the committed seed corpus (fuzz/corpus/<target>, only read: new inputs go
# to a scratch directory) and fails on any crash, panic, hang (> FUZZ_TIMEOUT_S per input) or
# memory blow-up (> FUZZ_RSS_MB). Prints executions and time per target.
#
# Usage: tests/fuzz-smoke.sh [target ...]          (default: every target)
# Environment:
#   FUZZ_SECONDS      seconds per target (default 5)
#   FUZZ_TIMEOUT_S    per-input time limit, s (default 2)
#   FUZZ_RSS_MB       memory limit, MiB (default 1024)
#   FUZZ_SANITIZER    none | address (default none: fastest; address for long runs)
#   FUZZ_JOBS         targets run at once (default: the CPUs, nproc)
#   FUZZ_TARGET_DIR   cargo target dir of the fuzz build (default: $CARGO_TARGET_DIR-fuzz or
#                     target/fuzz under the repo)
#   FUZZ_REPORT_JSON  if set, also write the per-target figures there as JSON (a relative
#                     path is taken from the directory the script was started in)
#   FUZZ_KEEP         if 1, keep the scratch directory (grown corpus, crash artifacts)
# Exit: 0 all clean, 1 a target crashed/hung/OOMed, 2 setup error (cargo-fuzz missing, build).
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
fuzz_dir="$repo/fuzz"
seconds="${FUZZ_SECONDS:-5}"
timeout_s="${FUZZ_TIMEOUT_S:-2}"
rss_mb="${FUZZ_RSS_MB:-1024}"
sanitizer="${FUZZ_SANITIZER:-none}"
if [[ -n "${FUZZ_TARGET_DIR:-}" ]]; then
  target_dir="$FUZZ_TARGET_DIR"
elif [[ -n "${CARGO_TARGET_DIR:-}" ]]; then
  target_dir="${CARGO_TARGET_DIR%/}-fuzz"
else
  target_dir="$repo/target/fuzz"
fi

if ! cargo fuzz --version >/dev/null 2>&1; then
  echo "fuzz-smoke: cargo-fuzz is not installed (cargo install cargo-fuzz)" >&2
  exit 2
fi

if [[ -n "${FUZZ_REPORT_JSON:-}" && "$FUZZ_REPORT_JSON" != /* ]]; then
  FUZZ_REPORT_JSON="$PWD/$FUZZ_REPORT_JSON"
fi
cd "$fuzz_dir"
if [[ $# -gt 0 ]]; then
  targets=("$@")
else
  mapfile -t targets < <(cargo fuzz list)
fi
[[ ${#targets[@]} -gt 0 ]] || { echo "fuzz-smoke: no targets" >&2; exit 2; }

echo "fuzz-smoke: building ${#targets[@]} target(s) (sanitizer=$sanitizer, target dir $target_dir)"
build_start=$(date +%s)
# `cargo fuzz build` takes one target or none (= all).
one=()
[[ ${#targets[@]} -eq 1 ]] && one=("${targets[0]}")
build_log="${TMPDIR:-/tmp}/fuzz-smoke-build.$$.log"
if ! RUSTC_BOOTSTRAP=1 cargo fuzz build -s "$sanitizer" --target-dir "$target_dir" "${one[@]}" \
     >"$build_log" 2>&1; then
  tail -40 "$build_log" >&2
  echo "fuzz-smoke: build failed (log: $build_log)" >&2
  exit 2
fi
rm -f "$build_log"
echo "fuzz-smoke: build took $(( $(date +%s) - build_start )) s"

host="$(rustc -vV | sed -n 's/^host: //p')"
bin_dir="$target_dir/$host/release"
scratch="$(mktemp -d "${TMPDIR:-/tmp}/fuzz-smoke.XXXXXX")"
[[ "${FUZZ_KEEP:-0}" == 1 ]] || trap 'rm -rf "$scratch"' EXIT

# The targets run side by side, FUZZ_JOBS at a time (default: one per CPU; libFuzzer is single-
# threaded), each into its own log; the table below is printed in target order when all are done.
jobs_max="${FUZZ_JOBS:-$(nproc)}"
run_one() {
  local t=$1 start_ns rc
  start_ns=$(date +%s%N)
  set +e
  # Outer timeout: a hang the per-input limit cannot catch (e.g. in libFuzzer's own startup).
  timeout --kill-after=5 $(( seconds * 3 + 60 )) "$bin_dir/$t" \
    -max_total_time="$seconds" -timeout="$timeout_s" -rss_limit_mb="$rss_mb" \
    -malloc_limit_mb="$rss_mb" -max_len=16384 -print_final_stats=1 \
    -artifact_prefix="$scratch/$t/artifacts/" \
    "$scratch/$t/corpus" "$fuzz_dir/corpus/$t" >"$scratch/$t/log" 2>&1
  rc=$?
  echo "$rc $(( ($(date +%s%N) - start_ns) / 1000000 ))" >"$scratch/$t/result"
}
running=0
for t in "${targets[@]}"; do
  if [[ ! -x "$bin_dir/$t" ]]; then
    echo "fuzz-smoke: no binary $bin_dir/$t" >&2
    exit 2
  fi
  mkdir -p "$scratch/$t/corpus" "$scratch/$t/artifacts" "$fuzz_dir/corpus/$t"
  run_one "$t" &
  running=$((running + 1))
  if (( running >= jobs_max )); then wait -n || true; running=$((running - 1)); fi
done
wait

failed=0
json="["
printf '%-16s %12s %8s %12s %7s  %s\n' target execs time_s execs_per_s corpus status
for t in "${targets[@]}"; do
  log="$scratch/$t/log"
  read -r rc elapsed_ms <"$scratch/$t/result" || { rc=125; elapsed_ms=0; }
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  units=$(sed -n 's/.*DONE *cov: [0-9]* ft: [0-9]* corp: \([0-9]*\)\/.*/\1/p' "$log" | tail -1)
  execs=${execs:-0}; rate=${rate:-0}; units=${units:-?}
  if [[ $rc -eq 0 ]]; then
    status=ok
  else
    status="FAILED (exit $rc)"
    failed=1
  fi
  printf '%-16s %12s %8s %12s %7s  %s\n' "$t" "$execs" "$(awk "BEGIN{printf \"%.1f\", $elapsed_ms/1000}")" "$rate" "$units" "$status"
  if [[ $rc -ne 0 ]]; then
    echo "---- $t: last lines of the libFuzzer log ----" >&2
    grep -v '^#[0-9]' "$log" | tail -40 >&2
    for a in "$scratch/$t/artifacts/"*; do
      [[ -e "$a" ]] || continue
      echo "reproduce: (cd fuzz && RUSTC_BOOTSTRAP=1 cargo fuzz run -s $sanitizer $t <saved copy of $(basename "$a")>)" >&2
      mkdir -p "$fuzz_dir/artifacts/$t" && cp "$a" "$fuzz_dir/artifacts/$t/" && \
        echo "artifact saved: fuzz/artifacts/$t/$(basename "$a")" >&2
    done
  fi
  json+="$( [[ "$json" == "[" ]] || echo ,){\"target\":\"$t\",\"execs\":$execs,\"time_ms\":$elapsed_ms,\"execs_per_s\":$rate,\"ok\":$( [[ $rc -eq 0 ]] && echo true || echo false)}"
done
json+="]"
if [[ -n "${FUZZ_REPORT_JSON:-}" ]]; then
  printf '%s\n' "$json" >"$FUZZ_REPORT_JSON"
fi
if [[ $failed -ne 0 ]]; then
  echo "fuzz-smoke: FAILED" >&2
  exit 1
fi
echo "fuzz-smoke: all ${#targets[@]} target(s) clean"
