#!/usr/bin/env bash
# Installs everything the bench and its test suite need on a fresh Debian/Ubuntu machine
# with Rust: Debian packages (idempotent: only what is missing), a Python venv with cantools, mcap,
# asammdf and matplotlib
# (fresh Debian/Ubuntu Pythons refuse system-wide pip installs, PEP 668), and the vcan route
# (vcan-setup.sh: the host's vcan, or the QEMU guest's kernel and QEMU, cached once per machine).
# Prints the venv's bin directory on its last line so callers can put it on PATH.
#
# Usage: tests/setup-host.sh [--disk-gb N]
#   --disk-gb N  fail at once, with the figures, unless the cargo target directory holds or can
#                still get N GB (what it holds already counts): a full disk otherwise shows up
#                as "No space left on device" deep inside a 20-minute build.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)

disk_gb=0
while [ $# -gt 0 ]; do
    case "$1" in
        --disk-gb) [ $# -ge 2 ] || { echo "setup: --disk-gb needs a number" >&2; exit 2; }; disk_gb=$2; shift 2 ;;
        *) echo "setup: unknown argument $1" >&2; exit 2 ;;
    esac
done
if [ "$disk_gb" != 0 ]; then
    target=${CARGO_TARGET_DIR:-$here/target}
    probe=$target; while [ ! -d "$probe" ]; do probe=$(dirname "$probe"); done
    free_mb=$(df -Pm "$probe" | awk 'NR == 2 { print $4 }')
    held_mb=0; [ -d "$target" ] && held_mb=$(du -sm "$target" | cut -f1)
    need_mb=$(( disk_gb * 1024 - held_mb ))
    if [ "$free_mb" -lt "$need_mb" ]; then
        echo "setup: not enough disk for the build: $target needs ≈ $disk_gb GB, holds $held_mb MB," \
             "and its file system has $free_mb MB free (needed: $need_mb MB). Free some space" \
             "(e.g. old cargo target directories) or set CARGO_TARGET_DIR to a larger disk." >&2
        exit 1
    fi
fi

# can-utils: candump/cansend/cangen; kmod+iproute2: vcan; rt-tests: cyclictest; valgrind:
# instruction-count gate; python3-venv: cantools; slurm-wlm + munge: the one-node Slurm
# cluster of lut/tests/slurm.rs (tests/slurm-cluster.sh). (The QEMU guest's own needs are
# installed by vcan-setup.sh, only where the host has no SocketCAN.)
pkgs=(can-utils kmod iproute2 rt-tests valgrind python3-venv slurm-wlm munge)
missing=()
for p in "${pkgs[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
    echo "setup: installing ${missing[*]}" >&2
    $sudo apt-get update -qq >&2
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "${missing[@]}" >&2
fi

venv="$here/target/pyenv"
# cantools decodes the bus with the DBC; python-can sends on it (examples/python); mcap reads the
# recordings (record/check_mcap.py, record/plot_mcap.py with matplotlib), asammdf the MDF ones
# (record/check_mf4.py): independent of the project's code.
if ! "$venv/bin/python3" -c "import can, cantools, mcap, matplotlib, asammdf" 2>/dev/null; then
    echo "setup: creating $venv with python-can, cantools, mcap, asammdf and matplotlib" >&2
    [ -x "$venv/bin/pip" ] || python3 -m venv "$venv" >&2
    "$venv/bin/pip" install -q --disable-pip-version-check "python-can>=4.2" "cantools>=39" "mcap>=1.2" \
        "matplotlib>=3.7" "asammdf>=8.0" >&2
fi

# The vcan route, prepared now (downloads happen here, not in the middle of a test) and named.
"$here/vcan-setup.sh" >&2
echo "$venv/bin"
