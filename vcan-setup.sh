#!/usr/bin/env bash
# vcan-setup.sh — where the bench finds vcan: the host's own kernel, or a QEMU guest running
# a real Debian kernel (PREEMPT_RT flavour) with vcan up.
#
#   ./vcan-setup.sh [--can NAME]                    set up (idempotent): host vcan, else prepare the guest; name the route
#   ./vcan-setup.sh [--can NAME] --check            print the route and its clock ("qemu-tcg virtual",
#                                                   "qemu-kvm host", "host host"); exit 0 host, 3 guest,
#                                                   4 none (reason on stderr)
#   ./vcan-setup.sh [--can NAME] --run -- CMD…      run CMD where vcan is: on the host, else inside the guest
#   ./vcan-setup.sh [--can NAME] --guest -- CMD…    always inside the guest (tests of the guest route)
#
# Routes (printed as route=…, and given to the command as $VCAN_ROUTE):
#   host      the host kernel has SocketCAN: vcan is created here. Real timing.
#   qemu-kvm  no SocketCAN here; QEMU with KVM runs Debian's kernel: real kernel, real timers.
#   qemu-tcg  no SocketCAN and no KVM that can run a stock kernel (no VT-x/AMD-V, or a PVM
#             /dev/kvm): QEMU software emulation. Kernel, vcan, iceoryx2 and the programs are
#             real; time is VIRTUAL (QEMU icount: one guest instruction = 1 ns on one emulated
#             CPU, idle time skipped), so the host's load slows the run but cannot starve the
#             guest. Timing is EMULATED — a 1-GIPS machine's, for function only, not a real-time
#             figure. VCAN_GUEST_ICOUNT=0: the guest clock follows the host's instead (2 CPUs,
#             faster, and then timing depends on the host's load).
# No route is ever skipped silently: if none works the script says why and how to fix it (exit 4).
#
# The guest sees the host's / read-only (virtio-9p), so host-built binaries run unchanged; the
# working directory, this checkout, $CARGO_TARGET_DIR and $VCAN_GUEST_RW (colon-separated) are
# shared read-write at the same paths; /tmp, /run and /dev/shm are fresh tmpfs. The command
# starts in the working directory with the caller's exported environment plus VCAN, VCAN_ROUTE,
# VCAN_GUEST=1, VCAN_GUEST_KERNEL, VCAN_HOST_LOADAVG (the host's 1-min load at the start) and
# VCAN_GUEST_SCHED (QEMU's scheduling) and VCAN_GUEST_CLOCK (virtual: TCG icount; host: real or host time);
# its stdout and stderr come back separately, its exit status is ours.
# Nothing is installed into /boot or /lib/modules: the kernel and busybox .debs (and QEMU's, when
# qemu-system-x86 cannot be installed) are unpacked once into the cache (≈ 150 MB).
#
# Environment: VCAN (interface, default vcan0); VCAN_NO_INSTALL=1 (never apt-get);
#   VCAN_GUEST_CACHE (default /var/tmp/vcan-guest), VCAN_GUEST_ACCEL (auto|kvm|tcg, default auto),
#   VCAN_GUEST_FLAVOUR (rt|std, default rt), VCAN_GUEST_CPUS (2; always 1 in virtual time), VCAN_GUEST_MEM
#   (MiB, 1024), VCAN_GUEST_ICOUNT (1 = TCG in virtual time, the default; 0 = host time),
#   VCAN_GUEST_TIMEOUT (s for the whole run, 3600), VCAN_GUEST_BOOT_TIMEOUT (s until the command
#   runs under KVM, 60; a KVM guest that misses it falls back to TCG), VCAN_GUEST_RW,
#   VCAN_GUEST_RT_PRIO (QEMU's SCHED_RR priority where permitted, default 5; 0 = normal),
#   VCAN_GUEST_TICK_US (the ticker that bounds waits for the host in virtual time, µs, 2000; 0 = none),
#   VCAN_GUEST_VERBOSE=1 (boot timing, keep the run directory).
set -euo pipefail

IFACE=${VCAN:-vcan0}
MODE=setup
CACHE=${VCAN_GUEST_CACHE:-/var/tmp/vcan-guest}
FLAVOUR=${VCAN_GUEST_FLAVOUR:-rt}
CPUS=${VCAN_GUEST_CPUS:-}
ICOUNT=${VCAN_GUEST_ICOUNT:-1}
MEM=${VCAN_GUEST_MEM:-1024}
TIMEOUT=${VCAN_GUEST_TIMEOUT:-3600}
TICK_US=${VCAN_GUEST_TICK_US:-2000}
# Bump when the guest's init below changes: the cached initramfs is rebuilt.
INIT_REV=4

usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'; }

while [ $# -gt 0 ]; do
  case "$1" in
    --can|--iface) [ $# -ge 2 ] || { usage >&2; exit 2; }; IFACE=$2; shift 2 ;;
    --can=*) IFACE=${1#--can=}; shift ;;
    --iface=*) IFACE=${1#--iface=}; shift ;;
    --check) MODE=check; shift ;;
    --run|run) MODE=run; shift ;;
    --guest) MODE=guest; shift ;;
    setup) MODE=setup; shift ;;
    -h|--help) usage; exit 0 ;;
    --) shift; break ;;
    *) break ;;
  esac
done
case "$MODE" in
  run|guest) [ $# -ge 1 ] || { echo "vcan-setup: --$MODE needs a command after --" >&2; exit 2; } ;;
esac

say() { echo "vcan-setup: $*" >&2; }
verbose() { [ "${VCAN_GUEST_VERBOSE:-0}" = 1 ] && say "$@" || true; }
# No route: the reason and the fix, exit 4.
no_route() { say "ERROR: no vcan route: $*"; exit 4; }

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"
  elif command -v sudo >/dev/null 2>&1; then sudo -n "$@"
  else return 1; fi
}

apt_updated=0
apt_update() { [ $apt_updated = 1 ] || { as_root apt-get update -qq >/dev/null 2>&1 || true; apt_updated=1; }; }

# install_pkgs CMD:PKG … — apt-get install the packages whose command is missing (never removes any).
install_pkgs() {
  local missing=() pair
  for pair in "$@"; do
    command -v "${pair%%:*}" >/dev/null 2>&1 || missing+=("${pair#*:}")
  done
  [ ${#missing[@]} -gt 0 ] || return 0
  if [ "${VCAN_NO_INSTALL:-0}" = 1 ]; then say "missing: ${missing[*]} (VCAN_NO_INSTALL=1, not installing)"; return 1; fi
  command -v apt-get >/dev/null 2>&1 || { say "missing: ${missing[*]} and no apt-get: install them by hand"; return 1; }
  say "installing: ${missing[*]}"
  if ! as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends --no-remove "${missing[@]}" >/dev/null 2>&1; then
    apt_update
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends --no-remove "${missing[@]}" >/dev/null || return 1
  fi
}

# ------------------------------------------------------------------------------ host route
# host_vcan create|nocreate — 0 if IFACE is an up CAN link here (creating it if allowed).
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

# ------------------------------------------------------------------------------ guest route
# The acceleration: kvm where /dev/kvm can run a stock kernel, else tcg. Sets ACCEL and ACCEL_WHY.
# A KVM that failed to boot the guest on this host boot is remembered (kvm-failed.<boot id>).
choose_accel() {
  local want=${VCAN_GUEST_ACCEL:-auto} boot_id
  boot_id=$(cat /proc/sys/kernel/random/boot_id 2>/dev/null || echo unknown)
  case "$want" in
    kvm) ACCEL=kvm; ACCEL_WHY="VCAN_GUEST_ACCEL=kvm"; return ;;
    tcg) ACCEL=tcg; ACCEL_WHY="VCAN_GUEST_ACCEL=tcg"; return ;;
    auto) ;;
    *) say "VCAN_GUEST_ACCEL must be auto, kvm or tcg"; exit 2 ;;
  esac
  ACCEL=tcg
  if [ ! -e /dev/kvm ]; then ACCEL_WHY="no /dev/kvm"
  elif [ ! -r /dev/kvm ] || [ ! -w /dev/kvm ]; then ACCEL_WHY="/dev/kvm is not read-writable by $(id -un)"
  elif ! grep -qwE 'vmx|svm' /proc/cpuinfo; then
    # PVM ("pagetable-based virtual machine", module kvm_pvm) offers /dev/kvm inside cloud VMs
    # without VT-x/AMD-V but runs only kernels built as PVM guests, not Debian's.
    if [ -d /sys/module/kvm_pvm ]; then ACCEL_WHY="/dev/kvm is PVM (kvm_pvm), which cannot run a stock kernel"
    else ACCEL_WHY="the CPU offers no VT-x/AMD-V"; fi
  elif [ -f "$CACHE/kvm-failed.$boot_id" ]; then ACCEL_WHY="KVM failed to boot the guest earlier on this host boot"
  else ACCEL=kvm; ACCEL_WHY="/dev/kvm with hardware virtualisation"; fi
}

route_name() { echo "qemu-$ACCEL"; }
route_words() {
  if [ "$ACCEL" = kvm ]; then echo "QEMU/KVM guest, Debian kernel $KVER: real timers"
  elif virtual_time; then echo "QEMU guest under software emulation (TCG) in virtual time (icount), Debian kernel $KVER: timing EMULATED ($ACCEL_WHY)"
  else echo "QEMU guest under software emulation (TCG), Debian kernel $KVER: timing EMULATED and following the host's load ($ACCEL_WHY; VCAN_GUEST_ICOUNT=0)"; fi
}
# True when the guest runs in virtual time: TCG with icount (the default under TCG).
virtual_time() { [ "$ACCEL" = tcg ] && [ "$ICOUNT" != 0 ]; }
# The guest's clock in one word (VCAN_GUEST_CLOCK, and the second word of --check): the only
# place that decides it; the test harness reads it from --check.
clock_name() { if virtual_time; then echo virtual; else echo host; fi; }

# deb_of PKG — the package's .deb in the cache (downloaded once); prints its path.
deb_of() {
  local f
  f=$(ls "$CACHE"/debs/"$1"_*.deb 2>/dev/null | head -n1 || true)
  if [ -z "$f" ]; then
    [ "${VCAN_NO_INSTALL:-0}" != 1 ] || { say "$1 is not cached and VCAN_NO_INSTALL=1"; return 1; }
    mkdir -p "$CACHE/debs"
    (cd "$CACHE/debs" && apt-get download -qq "$1" >/dev/null 2>&1) ||
      { apt_update; (cd "$CACHE/debs" && apt-get download -qq "$1" >/dev/null 2>&1); } || return 1
    f=$(ls "$CACHE"/debs/"$1"_*.deb | head -n1)
  fi
  echo "$f"
}

# QEMU: the system's qemu-system-x86_64; else apt-get (never removing a package); else the
# .debs unpacked into the cache (e.g. a host whose qemu-utils comes from backports, where
# qemu-system-x86 from the main archive could only be installed by removing it). Sets QEMU.
prepare_qemu() {
  local q="$CACHE/qemu" p f libs=() missing
  if command -v qemu-system-x86_64 >/dev/null 2>&1; then QEMU=(qemu-system-x86_64); return 0; fi
  if [ ! -x "$q/usr/bin/qemu-system-x86_64" ]; then
    if install_pkgs qemu-system-x86_64:qemu-system-x86 2>/dev/null && command -v qemu-system-x86_64 >/dev/null; then
      QEMU=(qemu-system-x86_64); return 0
    fi
    say "unpacking QEMU into $q (qemu-system-x86 cannot be installed here without removing packages)"
    rm -rf "$q.tmp"; mkdir -p "$q.tmp"
    for p in qemu-system-x86 qemu-system-common qemu-system-data seabios ipxe-qemu; do
      f=$(deb_of "$p") || { say "cannot download $p"; return 1; }
      dpkg-deb -x "$f" "$q.tmp"
    done
    # QEMU's shared libraries are ordinary packages: install those not installed yet.
    for p in $(apt-cache depends --no-recommends --no-suggests --no-conflicts --no-breaks \
                 --no-replaces --no-enhances qemu-system-x86 qemu-system-common 2>/dev/null |
               awk '$1=="Depends:" && $2 !~ /^[<]/ {print $2}' | grep -vE '^(qemu-|seabios|ipxe-qemu)' | sort -u); do
      [ "$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)" = "install ok installed" ] || libs+=("$p")
    done
    if [ ${#libs[@]} -gt 0 ]; then
      apt_update
      as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends --no-remove "${libs[@]}" >/dev/null ||
        { say "cannot install QEMU's libraries: ${libs[*]}"; return 1; }
    fi
    missing=$(ldd "$q.tmp/usr/bin/qemu-system-x86_64" | grep 'not found' || true)
    [ -z "$missing" ] || { say "QEMU libraries missing: $(echo $missing)"; return 1; }
    rm -rf "$q"; mv "$q.tmp" "$q"
  fi
  QEMU=("$q/usr/bin/qemu-system-x86_64" -L "$q/usr/share/qemu" -L "$q/usr/share/seabios" -L "$q/usr/lib/ipxe/qemu")
}

# The kernel and its initramfs, built once into $CACHE/<kernel version>/. The kernel version is
# pinned on first use (delete the cache to move on). Sets K and KVER.
prepare_kernel() {
  local meta kpkg
  case "$FLAVOUR" in rt) meta=linux-image-rt-amd64 ;; std) meta=linux-image-amd64 ;;
    *) say "VCAN_GUEST_FLAVOUR must be rt or std"; exit 2 ;; esac
  kpkg=$(cat "$CACHE/$meta.pin" 2>/dev/null || true)
  if [ -z "$kpkg" ]; then
    resolve() { apt-cache depends "$meta" 2>/dev/null | awk '$1=="Depends:" && $2 ~ /^linux-image-[0-9]/ {print $2; exit}'; }
    kpkg=$(resolve)
    [ -n "$kpkg" ] || { apt_update; kpkg=$(resolve); }
    [ -n "$kpkg" ] || { say "apt knows no $meta (the guest needs Debian's kernel packages in the apt sources)"; return 1; }
    echo "$kpkg" > "$CACHE/$meta.pin"
  fi
  KVER=${kpkg#linux-image-}
  K="$CACHE/$KVER"
  [ -f "$K/initrd.gz" ] && [ "$(cat "$K/rev" 2>/dev/null)" = "$INIT_REV" ] && return 0

  say "preparing the guest kernel $KVER and its initramfs in $K (once per machine)"
  local t="$K.tmp" moddir= d f
  rm -rf "$t"; mkdir -p "$t/x" "$t/ir/bin" "$t/ir/proc" "$t/ir/sys" "$t/ir/dev"
  f=$(deb_of "$kpkg") || { say "cannot download $kpkg"; return 1; }
  dpkg-deb -x "$f" "$t/x"
  cp "$t/x/boot/vmlinuz-$KVER" "$t/vmlinuz"
  for d in "$t/x/lib/modules/$KVER" "$t/x/usr/lib/modules/$KVER"; do [ -d "$d" ] && moddir=$d && break; done
  [ -n "$moddir" ] || { say "no modules in $kpkg"; return 1; }
  f=$(deb_of busybox-static) || { say "cannot download busybox-static"; return 1; }
  dpkg-deb -x "$f" "$t/bb"
  cp "$t/bb/bin/busybox" "$t/ir/bin/busybox"

  # The modules the guest loads, with their dependencies (each module's modinfo), in load
  # order. A module built into the kernel is not found and simply skipped.
  local order=()
  add_mod() {
    local name=$1 file dep m dec
    for m in "${order[@]}"; do [ "$m" = "$name" ] && return 0; done
    file=$(find "$moddir" \( -name "$name.ko*" -o -name "${name//_/-}.ko*" -o -name "${name//-/_}.ko*" \) | head -n1 || true)
    [ -n "$file" ] || return 0
    case "$file" in *.ko.xz) dec=(xz -dc) ;; *.ko.zst) dec=(zstd -dqc) ;; *.ko.gz) dec=(gzip -dc) ;; *) dec=(cat) ;; esac
    "${dec[@]}" "$file" > "$t/ir/$name.ko" || { say "cannot unpack $file"; return 1; }
    for dep in $(tr '\0' '\n' < "$t/ir/$name.ko" | sed -n 's/^depends=//p' | tr ',' ' '); do add_mod "$dep"; done
    order+=("$name")
  }
  for m in virtio_pci 9pnet_virtio 9p virtio_console can can-raw can-bcm can-gw can-isotp vcan vxcan; do add_mod "$m"; done
  printf '%s\n' "${order[@]}" > "$t/ir/modules"

  # /init (busybox sh): modules, the shares, vcan, then the command chrooted into the host's
  # root with stdout on hvc0 and stderr on hvc1; its exit status goes back through /ctl.
  cat > "$t/ir/init" <<'INIT'
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev
while read -r m; do insmod /$m.ko 2>/dev/null || echo "insmod $m failed"; done < /modules
mkdir -p /ctl /newroot
mount -t 9p -o trans=virtio,version=9p2000.L,cache=none ctl /ctl || { echo "ctl mount failed"; poweroff -f; }
. /ctl/config
O="trans=virtio,version=9p2000.L,msize=262144"
mount -t 9p -o "$O,ro,cache=loose" hostroot /newroot || { echo "root mount failed"; poweroff -f; }
R=/newroot
mount -t proc proc $R/proc; mount -t sysfs sys $R/sys; mount -t devtmpfs dev $R/dev
mkdir -p $R/dev/shm $R/dev/pts $R/dev/mqueue
mount -t tmpfs -o mode=1777 shm $R/dev/shm
mount -t devpts -o mode=620,ptmxmode=666 devpts $R/dev/pts
mount -t mqueue mqueue $R/dev/mqueue 2>/dev/null
mount -t tmpfs -o mode=1777 tmp $R/tmp
mount -t tmpfs -o mode=755 run $R/run
mkdir -p $R/run/vcan-guest $R/run/lock
mount -o bind /ctl $R/run/vcan-guest
i=0
for d in $SHARES; do
  mkdir -p "$R$d" 2>/dev/null
  # cache=loose: reads are cached in the guest. Safe as the bench uses it: nobody else writes
  # the files a guest writes while it runs (guests side by side write apart). Each write() is
  # still one request to the host (measured: the demo run made 8 500 before its logs were
  # buffered, 510 after), so the bench's processes write their logs through buffers.
  mount -t 9p -o "$O,rw,cache=loose" "rw$i" "$R$d" || echo "mount of $d failed"
  i=$((i + 1))
done
hostname vcan-guest
chroot $R /bin/sh -c "export PATH=/usr/sbin:/usr/bin:/sbin:/bin
  ip link set lo up; ip link add dev $IFACE type vcan && ip link set $IFACE up" || echo "$IFACE setup failed"
# stdout and stderr on two virtio consoles, raw (no \n -> \r\n); fds 3 and 4 stay open
# because a console resets its settings on last close
exec 3<>/dev/hvc0 4<>/dev/hvc1
stty -opost <&3 2>/dev/null; stty -opost <&4 2>/dev/null
cut -d' ' -f1 /proc/uptime > /ctl/booted
chroot $R /bin/bash /run/vcan-guest/stage2 </dev/null >&3 2>&4
echo $? > /ctl/rc
sync
poweroff -f
INIT
  chmod +x "$t/ir/init"
  (cd "$t/ir" && find . | "$t/ir/bin/busybox" cpio -o -H newc 2>/dev/null | gzip -1) > "$t/initrd.gz"
  echo "$INIT_REV" > "$t/rev"
  rm -rf "$t/x" "$t/bb" "$t/ir" "$CACHE"/debs/"$kpkg"_*.deb
  rm -rf "$K"; mv "$t" "$K"
}

# The kernel unpacked once (K/vmlinux) where it can boot that way: QEMU then starts it at its PVH
# entry point (the Xen PHYS32_ENTRY ELF note), skipping the real-mode set-up and, above all, the
# kernel's own decompression, which under TCG took ≈ 5 s of every guest boot (13.5 → 8.6 s to
# the command, measured with Debian's xz-compressed 6.1 kernel). A kernel without the note, or
# one that cannot be unpacked, boots as before from K/vmlinuz (K/vmlinux.none remembers that).
prepare_pvh() {
  [ -f "$K/vmlinux" ] || [ -f "$K/vmlinux.none" ] && return 0
  local off magic dec t="$K/vmlinux.tmp"
  for magic in xz zstd gzip; do
    case $magic in
      xz) magic='\xfd7zXZ\x00'; dec=(xz -dc) ;;
      zstd) magic='\x28\xb5\x2f\xfd'; dec=(zstd -dqc) ;;
      gzip) magic='\x1f\x8b\x08'; dec=(gzip -dc) ;;
    esac
    off=$( { LC_ALL=C grep -m1 -obUaP "$magic" "$K/vmlinuz" || true; } | awk -F: 'NR == 1 { print $1 }')
    [ -n "$off" ] || continue
    # the compressed payload is followed by the boot stub's data: the decompressor's complaint
    # about it is expected, the ELF header and the PVH note below are what count
    tail -c +$((off + 1)) "$K/vmlinuz" | "${dec[@]}" > "$t" 2>/dev/null || true
    if [ "$(head -c 4 "$t" | od -An -c | tr -d ' ')" = '177ELF' ] &&
      LC_ALL=C grep -qaP '\x04\x00\x00\x00[\x04\x08]\x00\x00\x00\x12\x00\x00\x00Xen\x00' "$t"; then
      mv "$t" "$K/vmlinux"; return 0
    fi
  done
  rm -f "$t"; touch "$K/vmlinux.none"
}

# What the guest needs on the host, and the cached kernel and QEMU (under a lock: one
# preparation at a time per cache).
prepare_guest() {
  [ "$(uname -m)" = x86_64 ] || no_route "$(kernel_reason), and the QEMU guest route supports x86-64 hosts only"
  command -v apt-get >/dev/null 2>&1 ||
    no_route "$(kernel_reason), and the QEMU guest route needs apt (Debian/Ubuntu) to fetch its kernel and QEMU"
  mkdir -p "$CACHE" 2>/dev/null && [ -w "$CACHE" ] ||
    no_route "cannot create the guest's cache $CACHE (set VCAN_GUEST_CACHE to a writable folder with ≈ 200 MB)"
  install_pkgs ip:iproute2 candump:can-utils cyclictest:rt-tests xz:xz-utils zstd:zstd flock:util-linux ||
    no_route "cannot install the packages the guest needs (run as root, or with sudo)"
  exec 9>"$CACHE/.lock"
  flock 9
  prepare_qemu || no_route "QEMU is not available (apt-get install qemu-system-x86)"
  prepare_kernel || no_route "the guest kernel could not be prepared (see above)"
  prepare_pvh
  flock -u 9
}

# The host directories the guest gets read-write: the working directory, this checkout,
# $CARGO_TARGET_DIR and $VCAN_GUEST_RW, without nesting duplicates. Sets SHARES.
shares() {
  local cand=() d e keep out=()
  cand+=("$(pwd -P)" "$(cd "$(dirname "$0")" && pwd -P)")
  [ -n "${CARGO_TARGET_DIR:-}" ] && [ -d "$CARGO_TARGET_DIR" ] && cand+=("$(cd "$CARGO_TARGET_DIR" && pwd -P)")
  local IFS=:
  for d in ${VCAN_GUEST_RW:-}; do [ -d "$d" ] && cand+=("$(cd "$d" && pwd -P)"); done
  unset IFS
  for d in "${cand[@]}"; do
    [ "$d" != / ] || continue
    case "$d" in *[[:space:]]*) say "warning: cannot share $d (whitespace in the path)"; continue ;; esac
    keep=1
    for e in "${cand[@]}"; do
      [ "$e" != / ] && [ "$e" != "$d" ] && case "$d/" in "$e"/*) keep=0 ;; esac
    done
    for e in "${out[@]}"; do [ "$e" = "$d" ] && keep=0; done
    [ $keep = 1 ] && out+=("$d")
  done
  SHARES=("${out[@]}")
}

# QEMU's threads run at SCHED_RR (priority VCAN_GUEST_RT_PRIO, default 5; 0 = off) where that is
# permitted and the guest's clock follows the host's (KVM; TCG with VCAN_GUEST_ICOUNT=0), as the
# device under test on a bench would: the emulated CPUs then run whenever they are runnable
# instead of queueing behind the host's other work. Measured under TCG with two niced cargo
# builds beside it (load ≈ 6.5): cyclictest in the guest max 50.6 ms at normal priority, 13.9 ms
# at nice -10, 9.4 ms at SCHED_RR 5 (a quiet host: 9.6 ms), and the demo's ECU went from 575 to
# 91 overruns. The kernel's RT throttling keeps 5 % of each CPU for the rest.
# In virtual time (TCG icount) QEMU stays at normal priority: its one thread is busy whenever it
# runs (idle time is skipped, not slept), so at SCHED_RR it would take a host CPU from everyone,
# and the guest's timing no longer depends on the host's scheduling anyway.
# Sets QEMU_SCHED (the command prefix) and QEMU_SCHED_WORDS.
qemu_sched() {
  local prio=${VCAN_GUEST_RT_PRIO:-5}
  QEMU_SCHED=(); QEMU_SCHED_WORDS="normal priority"
  if virtual_time; then QEMU_SCHED_WORDS="virtual time (icount, 1 instruction = 1 ns), normal priority"
  elif [ "$prio" = 0 ]; then QEMU_SCHED_WORDS="normal priority (VCAN_GUEST_RT_PRIO=0)"
  elif chrt -r "$prio" true 2>/dev/null; then QEMU_SCHED=(chrt -r "$prio"); QEMU_SCHED_WORDS="SCHED_RR $prio"
  else say "note: QEMU runs at normal priority (SCHED_RR not permitted): the guest's timing then follows the host's load"
  fi
}

# run_guest CMD ARGS… — CMD inside the guest with IFACE up; exit status propagated.
run_guest() {
  shares
  local opid epid t0 t1 acc cpus fs i
  # global: the EXIT trap reads them after this function returned
  qpid=
  run=$(mktemp -d "${TMPDIR:-/tmp}/vcan-guest.XXXXXX")
  cleanup() {
    [ -n "$qpid" ] && kill "$qpid" 2>/dev/null || true
    if [ "${VCAN_GUEST_VERBOSE:-0}" = 1 ]; then say "run directory kept: $run"; else rm -rf "$run"; fi
  }
  trap cleanup EXIT
  trap 'exit 130' INT TERM
  { printf 'IFACE=%q\n' "$IFACE"; printf 'SHARES=%q\n' "${SHARES[*]}"; } > "$run/config"
  # The caller's exported variables (minus those that describe this shell), then ours.
  declare -px | grep -vE '^declare -[a-zA-Z-]* (PWD|OLDPWD|SHLVL|_|HOSTNAME)(=|$)' > "$run/env" || true
  # the host's load when the guest starts and QEMU's scheduling: emulated timing depends on
  # them, so reports name them
  qemu_sched
  printf 'export VCAN=%q VCAN_ROUTE=%q VCAN_GUEST=1 VCAN_GUEST_KERNEL=%q VCAN_HOST_LOADAVG=%q VCAN_GUEST_SCHED=%q VCAN_GUEST_CLOCK=%q\n' \
    "$IFACE" "$(route_name)" "$KVER" "$(cut -d' ' -f1 /proc/loadavg)" "$QEMU_SCHED_WORDS" \
    "$(clock_name)" >> "$run/env"
  {
    echo 'source /run/vcan-guest/env'
    echo '[ -z "${TMPDIR:-}" ] || [ -d "$TMPDIR" ] || unset TMPDIR'
    # the host's root is read-only in the guest: caches (fontconfig for the plots) go to /tmp
    echo 'mkdir -p /tmp/.cache && export XDG_CACHE_HOME=/tmp/.cache'
    printf 'cd -- %q || exit 125\n' "$(pwd -P)"
    # In virtual time a wait for the host (a file read over 9p) passes as idle time, and idle
    # time jumps to the next timer: with none near, one fc-list of the plots' fonts took 3.8 s
    # of guest time and a bench process's 20 s exit timeout ran out once. A ticker at normal
    # priority (cyclictest, SCHED_OTHER) bounds each such wait to its period; anything at
    # real-time priority preempts it. Its cost is the host's: every wake-up of the emulated CPU
    # (on the RT kernel two, through ktimers) takes ≈ 0.1 ms of emulation. At 1 kHz it took
    # ≈ 9 % of four library runs' time (19.8 s; 500 Hz 18.1 s, none 17.4 s), so 500 Hz (2 ms, as
    # VCAN_GUEST_TICK_US=2000): the plots are drawn on the host now, and while the ECU runs its
    # 1 kHz cycle keeps a timer near anyway.
    if virtual_time && [ "$TICK_US" != 0 ]; then echo "cyclictest -q -i $TICK_US -p 0 -t 1 </dev/null >/dev/null 2>&1 &"; fi
    printf 'exec'; printf ' %q' "$@"; echo
  } > "$run/stage2"

  # TCG in virtual time: QEMU's icount makes the guest's clock count executed instructions
  # (shift=0: 1 ns each) and skip idle time (sleep=off), so the host's load slows the run but
  # never starves the guest: with host time, a loaded CI host left the accelerometer stale for
  # seconds, and a fault campaign failed 4 of 26 cases three runs in a row (112–737 overruns per
  # case); in virtual time the same campaign passes every case at the first run with 0
  # overruns. icount runs one emulated CPU (single-threaded TCG; two CPUs hang at SMP bring-up).
  if [ "$ACCEL" = kvm ]; then acc=(-accel kvm -cpu host); cpus=${CPUS:-2}
  elif virtual_time; then
    acc=(-accel tcg,thread=single -cpu max -icount shift=0,sleep=off); cpus=1
    [ "${CPUS:-1}" = 1 ] || say "note: VCAN_GUEST_CPUS=$CPUS ignored: virtual time runs one emulated CPU (VCAN_GUEST_ICOUNT=0 for more)"
  else acc=(-accel tcg -cpu max); cpus=${CPUS:-2}; fi
  # passthrough keeps the host's owners and modes (root); without root QEMU cannot chown
  if [ "$(id -u)" -eq 0 ]; then fs=security_model=passthrough,multidevs=remap; else fs=security_model=none,multidevs=remap; fi
  local rw=()
  for i in "${!SHARES[@]}"; do
    rw+=(-fsdev "local,id=rw$i,path=${SHARES[$i]},$fs" -device "virtio-9p-pci,fsdev=rw$i,mount_tag=rw$i")
  done
  # The command's stdout and stderr arrive through FIFOs that cat copies to ours.
  mkfifo "$run/out" "$run/err"
  cat "$run/out" & opid=$!
  cat "$run/err" >&2 & epid=$!
  local kernel="$K/vmlinuz"
  [ -f "$K/vmlinux" ] && kernel="$K/vmlinux"
  local boot_timeout=${VCAN_GUEST_BOOT_TIMEOUT:-60}
  [ "$ACCEL" = tcg ] && boot_timeout=${VCAN_GUEST_BOOT_TIMEOUT_TCG:-240}
  t0=$(date +%s.%N)
  "${QEMU_SCHED[@]}" "${QEMU[@]}" "${acc[@]}" -m "$MEM" -smp "$cpus" \
    -nodefaults -no-user-config -display none -no-reboot -nic none \
    -kernel "$kernel" -initrd "$K/initrd.gz" \
    -append "console=ttyS0 loglevel=4 panic=-1 no_timer_check ${VCAN_GUEST_APPEND:-}" \
    -serial "file:$run/console.log" \
    -fsdev "local,id=root,path=/,readonly=on,$fs" -device virtio-9p-pci,fsdev=root,mount_tag=hostroot \
    "${rw[@]}" \
    -fsdev "local,id=ctl,path=$run,$fs" -device virtio-9p-pci,fsdev=ctl,mount_tag=ctl \
    -device virtio-serial-pci \
    -chardev "file,id=out,path=$run/out" -device virtconsole,chardev=out \
    -chardev "file,id=err,path=$run/err" -device virtconsole,chardev=err \
    </dev/null >"$run/qemu.out" 2>"$run/qemu.err" &
  qpid=$!

  console() { say "guest console (tail):"; tail -n 30 "$run/console.log" >&2 2>/dev/null || true
              tail -n 5 "$run/qemu.err" >&2 2>/dev/null || true; }
  while [ ! -s "$run/booted" ]; do
    if ! kill -0 "$qpid" 2>/dev/null; then
      wait "$qpid" 2>/dev/null || true; qpid=
      console
      [ "$ACCEL" = kvm ] && return 77
      no_route "QEMU exited before the guest started the command"
    fi
    if (( $(date +%s) - ${t0%.*} >= boot_timeout )); then
      console
      [ "$ACCEL" = kvm ] && { kill "$qpid" 2>/dev/null; wait "$qpid" 2>/dev/null || true; qpid=; return 77; }
      no_route "the guest did not boot within ${boot_timeout} s"
    fi
    sleep 0.05
  done
  t1=$(date +%s.%N)
  verbose "$(route_name) guest $KVER: command started $(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.2f", b-a}') s after QEMU start (guest uptime $(cat "$run/booted") s)"
  while kill -0 "$qpid" 2>/dev/null; do
    if (( $(date +%s) - ${t0%.*} >= TIMEOUT )); then
      say "the guest run exceeded VCAN_GUEST_TIMEOUT=${TIMEOUT} s: stopped"; kill "$qpid"; wait "$qpid" || true; qpid=; return 124
    fi
    sleep 0.1
  done
  wait "$qpid" 2>/dev/null || true; qpid=
  wait "$opid" "$epid" 2>/dev/null || true
  [ -s "$run/rc" ] || { console; say "the guest did not finish the command"; return 125; }
  return "$(cat "$run/rc")"
}

# guest CMD… — run_guest, falling back from a KVM that cannot boot the guest to TCG.
guest() {
  local rc=0 why=$1; shift
  prepare_guest
  say "route=$(route_name): $why; running inside a $(route_words)"
  run_guest "$@" || rc=$?
  if [ "$rc" = 77 ]; then
    # auto's choice is remembered for this host boot; a forced kvm is not a probe
    [ "${VCAN_GUEST_ACCEL:-auto}" != auto ] ||
      touch "$CACHE/kvm-failed.$(cat /proc/sys/kernel/random/boot_id 2>/dev/null || echo unknown)"
    ACCEL=tcg; ACCEL_WHY="KVM could not boot the guest"
    say "KVM could not boot the guest; route=$(route_name): $(route_words)"
    rc=0; run_guest "$@" || rc=$?
  fi
  exit "$rc"
}

case "$MODE" in
  check)
    if host_vcan nocreate || host_vcan create; then echo "host host"; exit 0; fi
    say "$(kernel_reason)"
    choose_accel
    prepare_guest
    echo "$(route_name) $(clock_name)"
    say "route=$(route_name): $(route_words)"
    exit 3 ;;
  setup)
    install_pkgs candump:can-utils cansend:can-utils ip:iproute2 modprobe:kmod || say "warning: could not install the CAN tools"
    if host_vcan create; then
      say "route=host: $IFACE is up on this kernel ($(uname -r)); timing is real"
      say "watch it: candump -L $IFACE | python3 -m cantools decode bus/restraint.dbc"
      exit 0
    fi
    say "$(kernel_reason)."
    choose_accel
    prepare_guest
    say "route=$(route_name): the bench and the tests run inside a $(route_words)"
    say "run a command there with: $0 --can $IFACE --run -- CMD [ARG...]"
    exit 0 ;;
  guest)
    choose_accel
    guest "--guest asked for the guest" "$@" ;;
  run)
    if host_vcan nocreate || host_vcan create; then
      say "route=host: $IFACE on this kernel ($(uname -r)); timing is real"
      export VCAN="$IFACE" VCAN_ROUTE=host
      exec "$@"
    fi
    choose_accel
    guest "$(kernel_reason)" "$@" ;;
esac
