#!/bin/sh
# vcan-setup.sh — bring up the bench's virtual CAN interface, or fall back to user-mode Linux.
#
#   ./vcan-setup.sh [--iface NAME]                 set up vcan (idempotent); report the mode
#   ./vcan-setup.sh [--iface NAME] --check         exit 0 if host vcan works, 3 if UML is needed,
#                                                  4 if neither is available (no install attempted)
#   ./vcan-setup.sh [--iface NAME] --uml -- CMD…   run CMD inside a UML guest with NAME up
#   ./vcan-setup.sh [--iface NAME] --run -- CMD…   run CMD on the host if host vcan works,
#                                                  otherwise inside UML (tests and demo use this)
#
# Environment: VCAN (interface name, default vcan0), VCAN_UML_MEM (guest RAM, default 1024M),
# VCAN_PASS_ENV (extra variable names to pass into the guest), VCAN_NO_INSTALL=1 (never apt-get).
#
# Why UML: many kernels have no SocketCAN at all (CONFIG_CAN off: this project's CI machines,
# WSL2, many containers). A user-mode Linux kernel (Debian package `user-mode-linux`) has the
# vcan module; it mounts the host's / as its root (hostfs), so host-built binaries run unchanged.
# Inside the guest /tmp and /dev/shm are fresh tmpfs (host paths under /tmp that matter — the
# checkout, the working directory, the command's directory, CARGO_TARGET_DIR — are mounted back). Timing measured inside UML is meaningless (syscalls are
# emulated): use it for function, not for latency.
set -eu

IFACE=${VCAN:-vcan0}
MODE=setup
UML_MEM=${VCAN_UML_MEM:-1024M}

usage() { sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; }

while [ $# -gt 0 ]; do
  case "$1" in
    --iface) [ $# -ge 2 ] || { usage >&2; exit 2; }; IFACE=$2; shift 2 ;;
    --iface=*) IFACE=${1#--iface=}; shift ;;
    --check) MODE=check; shift ;;
    --uml) MODE=uml; shift ;;
    --run) MODE=run; shift ;;
    setup) MODE=setup; shift ;;
    run) MODE=run; shift ;;
    -h|--help) usage; exit 0 ;;
    --) shift; break ;;
    *) break ;;
  esac
done
case "$MODE" in
  uml|run) [ $# -ge 1 ] || { echo "vcan-setup: --$MODE needs a command after --" >&2; exit 2; } ;;
esac

say() { echo "vcan-setup: $*" >&2; }

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"
  elif command -v sudo >/dev/null 2>&1; then sudo -n "$@"
  else return 1; fi
}

# install_pkgs CMD:PKG ... — apt-get install only the packages whose command is missing.
install_pkgs() {
  missing=""
  for pair in "$@"; do
    cmd=${pair%%:*}; pkg=${pair#*:}
    command -v "$cmd" >/dev/null 2>&1 || missing="$missing $pkg"
  done
  [ -n "$missing" ] || return 0
  if [ "${VCAN_NO_INSTALL:-0}" = 1 ]; then
    say "missing:$missing (VCAN_NO_INSTALL=1, not installing)"; return 1
  fi
  command -v apt-get >/dev/null 2>&1 || { say "missing:$missing and no apt-get: install them by hand"; return 1; }
  say "installing:$missing"
  # apt-get update only if the package is unknown to the cache.
  # shellcheck disable=SC2086
  if ! as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q $missing >/dev/null 2>&1; then
    as_root apt-get update -q >/dev/null 2>&1 || true
    # shellcheck disable=SC2086
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q $missing >/dev/null || return 1
  fi
}

# Host vcan: 0 if IFACE exists as a CAN link and is up (creating it if we can).
host_vcan() {
  command -v ip >/dev/null 2>&1 || return 1
  if ip link show "$IFACE" >/dev/null 2>&1; then
    ip -d link show "$IFACE" 2>/dev/null | grep -q 'link/can' || { say "$IFACE exists but is not a CAN interface"; return 1; }
    ip link show "$IFACE" | grep -q ',UP' || as_root ip link set up "$IFACE" 2>/dev/null || return 1
    return 0
  fi
  [ "$1" = create ] || return 1
  as_root modprobe vcan 2>/dev/null || true
  as_root ip link add dev "$IFACE" type vcan 2>/dev/null || return 1
  as_root ip link set up "$IFACE" 2>/dev/null || return 1
}

kernel_reason() {
  if [ ! -d /proc/net/can ] && ! grep -qw vcan /proc/modules 2>/dev/null; then
    echo "this kernel ($(uname -r)) has no SocketCAN (no /proc/net/can, vcan module not loadable)"
  else
    echo "could not create $IFACE on this kernel ($(uname -r)) (not root, or vcan unavailable)"
  fi
}

uml_ready() { command -v linux.uml >/dev/null 2>&1 && [ -d /usr/lib/uml/modules ]; }

ensure_uml() {
  uml_ready || install_pkgs linux.uml:user-mode-linux || true
  uml_ready || { say "user-mode Linux is not available (apt-get install user-mode-linux)"; return 1; }
}

# run_uml CMD ARGS… — run inside a UML guest with IFACE up; exit code propagated.
run_uml() {
  ensure_uml || exit 4
  work=$(mktemp -d "${TMPDIR:-/tmp}/vcan-uml.XXXXXX")
  # Host directories under /tmp the guest must see again (its /tmp is a fresh tmpfs): this
  # script's checkout, the working directory, the command's own directory, the cargo target.
  repo_dir=$(cd "$(dirname "$0")" && pwd)
  cmd_dir=$(cd "$(dirname "$1")" 2>/dev/null && pwd || true)
  trap 'rm -rf "$work"' EXIT INT TERM
  printf '%s\n' "$@" > "$work/argv"
  # Environment for the guest: the kernel's init starts with an empty one.
  : > "$work/env"
  names="PATH HOME USER LANG LC_ALL TERM CARGO_TARGET_DIR CARGO_HOME RUSTUP_HOME RUST_LOG RUST_BACKTRACE RUST_TEST_THREADS RUST_MIN_STACK PYENV_ROOT PYENV_VERSION PYTHONPATH PYTHONHOME VIRTUAL_ENV NO_COLOR ${VCAN_PASS_ENV:-}"
  names="$names $(env | sed -n 's/^\(BENCH_[A-Za-z0-9_]*\)=.*/\1/p; s/^\(VCAN_[A-Za-z0-9_]*\)=.*/\1/p' | tr '\n' ' ')"
  for n in $names; do
    eval "isset=\${$n+x}"
    [ -n "$isset" ] || continue
    eval "val=\$$n"
    printf "export %s='%s'\n" "$n" "$(printf '%s' "$val" | sed "s/'/'\\\\''/g")" >> "$work/env"
  done
  printf "export VCAN='%s'\nexport VCAN_IN_UML=1\n" "$IFACE" >> "$work/env"
  cat > "$work/init" <<EOF
#!/bin/sh
export PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
mount -t proc proc /proc; mount -t sysfs sys /sys
mount -t tmpfs tmpfs /tmp; mkdir -p /dev/shm; mount -t tmpfs tmpfs /dev/shm
# the fresh /tmp hides host paths under it: mount back the ones we need
for d in "$work" "$repo_dir" "$PWD" "$cmd_dir" "${CARGO_TARGET_DIR:-}"; do
  case "\$d" in /tmp/*) mkdir -p "\$d"; mount -t hostfs none "\$d" -o "\$d" ;; esac
done
M=/usr/lib/uml/modules/\$(uname -r)/kernel
for m in net/can/can.ko net/can/can-raw.ko net/can/can-bcm.ko drivers/net/can/dev/can-dev.ko drivers/net/can/vcan.ko; do
  insmod \$M/\$m 2>/dev/null || true
done
ip link set up lo 2>/dev/null || true
if ! { ip link add dev "$IFACE" type vcan && ip link set up "$IFACE"; }; then
  echo "vcan-setup: guest could not create $IFACE" >&2; echo 125 > "$work/rc"; poweroff -f
fi
. "$work/env"
cd "$PWD"
set --; while IFS= read -r a; do set -- "\$@" "\$a"; done < "$work/argv"
echo "@@VCAN-START@@"
"\$@"; echo \$? > "$work/rc"
echo "@@VCAN-END@@"
poweroff -f
EOF
  chmod +x "$work/init"
  # con0 = our stdout; the guest's stdin is /dev/null. The kernel's own boot chatter is
  # filtered out, the command's output streams through as it is produced.
  ( linux.uml mem="$UML_MEM" rootfstype=hostfs rootflags=/ rw quiet init="$work/init" \
      con=null con0=fd:0,fd:1 </dev/null 2>&1 || true ) \
    | sed -u 's/\r$//' | tee "$work/console" \
    | awk '/^@@VCAN-END@@/ { on = 0; next }
           on && !/^(random: |reboot: |Powering off)/ { print; fflush() }
           /^@@VCAN-START@@/ { on = 1 }' || true
  if [ ! -f "$work/rc" ]; then
    say "the UML guest did not finish the command; its console:"
    cat "$work/console" >&2
    exit 1
  fi
  rc=$(cat "$work/rc")
  exit "$rc"
}

case "$MODE" in
  check)
    if host_vcan nocreate || host_vcan create; then exit 0; fi
    uml_ready && exit 3
    exit 4 ;;
  setup)
    install_pkgs candump:can-utils cansend:can-utils ip:iproute2 modprobe:kmod || say "warning: could not install CAN tools"
    if host_vcan create; then
      say "$IFACE is up on the host kernel ($(uname -r)): mode=host"
      say "watch it: candump -L $IFACE | python3 -m cantools decode bus/restraint.dbc"
      exit 0
    fi
    say "$(kernel_reason)."
    say "FALLBACK: this kernel has no usable SocketCAN; the bench and tests will run inside a user-mode Linux (UML) guest that has $IFACE: mode=uml"
    if ensure_uml; then
      say "UML ready ($(command -v linux.uml)). Run a command there with:  $0 --iface $IFACE --run -- CMD [ARG...]"
      exit 0
    fi
    say "ERROR: neither host vcan nor user-mode Linux is available"
    exit 4 ;;
  uml)
    install_pkgs candump:can-utils ip:iproute2 || true
    run_uml "$@" ;;
  run)
    install_pkgs candump:can-utils ip:iproute2 || true
    if host_vcan nocreate || host_vcan create; then
      export VCAN="$IFACE"
      exec "$@"
    fi
    say "$(kernel_reason); running inside user-mode Linux (mode=uml)"
    run_uml "$@" ;;
esac
