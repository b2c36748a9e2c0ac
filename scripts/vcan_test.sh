#!/usr/bin/env bash
# The RMD-X gimbal driver over real SocketCAN (issue 11 item 3): runs tests/vcan/rmd_vcan_test.cpp
# (hal_real_can_vcan_tests) against the simulated motor on vcan0 inside QEMU, because the machines
# we build on have no CAN in their kernels. Debian 12's stock kernel boots under TCG (no KVM needed)
# from a small initramfs: busybox as the shell, the modules can, can-raw, can-dev, vcan (and what
# they depend on), iproute2's ip to create vcan0, the test binary and the shared libraries of both.
# The script exits with the test's status, read from a marker line on the serial console; a boot
# that gives no result within VCAN_TIMEOUT_S (default 180) is a failure, one line.
#
#   scripts/vcan_test.sh [TEST_BINARY] [-- GTEST_ARGS...]
#
# Without TEST_BINARY it builds the target in $AEROTRACK_VCAN_BUILD_DIR (default build-vcan).
# Cached in .cache/vcan/ (git-ignored): the kernel and its modules (fetched once with apt-get
# download, 70.5 MB; delete .cache/vcan to take a newer one), the initramfs's fixed part; the test
# part is repacked only when the binary changes. Installs with apt-get, only when missing:
# qemu-system-x86 (qemu-system-x86_64), busybox-static (/bin/busybox), cpio, xz-utils (xz).
# TCG, not KVM: CI runners often have no /dev/kvm, and where nested KVM is offered it can hang.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cache=$root/.cache/vcan
timeout_s=${VCAN_TIMEOUT_S:-180}
say() { echo "vcan_test.sh: $*" >&2; }

binary=""
if [[ $# -gt 0 && $1 != "--" ]]; then
  binary=$(realpath "$1")
  shift
fi
[[ $# -gt 0 && $1 == "--" ]] && shift
gtest_args=("$@")

# --- Tools, installed only when missing. ---
missing=()
command -v qemu-system-x86_64 > /dev/null || missing+=(qemu-system-x86)
[[ -x /bin/busybox ]] || missing+=(busybox-static)
command -v cpio > /dev/null || missing+=(cpio)
command -v xz > /dev/null || missing+=(xz-utils)
if [[ ${#missing[@]} -gt 0 ]]; then
  say "installing ${missing[*]}"
  sudo_=()
  [[ $(id -u) -eq 0 ]] || sudo_=(sudo)
  "${sudo_[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" > /dev/null
fi

# --- The test binary. ---
if [[ -z $binary ]]; then
  build=${AEROTRACK_VCAN_BUILD_DIR:-$root/build-vcan}
  [[ -f $build/build.ninja || -f $build/Makefile ]] ||
    cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$build" --target hal_real_can_vcan_tests > /dev/null
  binary=$build/bin/hal_real_can_vcan_tests
fi
[[ -x $binary ]] || {
  say "$binary: no such test binary"
  exit 2
}

# --- Debian 12's stock kernel, fetched once: the image and the CAN modules, decompressed. ---
mkdir -p "$cache"
version_file=$cache/kernel-version
if [[ ! -s $version_file || ! -f $cache/kernel/vmlinuz || ! -s $cache/kernel/modules.order ]]; then
  # The current Debian 12 kernel: what the linux-image-amd64 meta package points at.
  package=$(apt-cache depends linux-image-amd64 | awk '/Depends: linux-image-[0-9]/ {print $2; exit}')
  [[ -n $package ]] || {
    say "cannot find Debian's current kernel package (apt-cache depends linux-image-amd64)"
    exit 2
  }
  version=${package#linux-image-}
  say "fetching $package"
  rm -rf "$cache/kernel" "$cache/unpack" "$cache"/*.deb
  # apt's sandbox user may not reach the cache folder: the download then runs as root, which is fine.
  if ! download_log=$( (cd "$cache" && apt-get download -qq "$package") 2>&1); then
    say "apt-get download $package failed: $(grep -v unsandboxed <<< "$download_log" | tail -n 1)"
    exit 2
  fi
  dpkg-deb -x "$cache"/"$package"_*.deb "$cache/unpack"
  mkdir -p "$cache/kernel/modules"
  cp "$cache/unpack/boot/vmlinuz-$version" "$cache/kernel/vmlinuz"
  moddir=$cache/unpack/lib/modules/$version
  # Each module after the modules it depends on (their .modinfo 'depends=' field).
  declare -A loaded=()
  order=()
  load() {
    local name=$1 file dep
    [[ -n ${loaded[$name]:-} ]] && return
    loaded[$name]=1
    file=$(find "$moddir" -name "$name.ko*" | head -n 1)
    [[ -n $file ]] || file=$(find "$moddir" -name "${name//-/_}.ko*" | head -n 1)
    [[ -n $file ]] || {
      say "$package has no module $name"
      exit 2
    }
    case $file in
      *.xz) xz -dc "$file" > "$cache/kernel/modules/$name.ko" ;;
      *.zst) zstd -qdc "$file" > "$cache/kernel/modules/$name.ko" ;;
      *) cp "$file" "$cache/kernel/modules/$name.ko" ;;
    esac
    for dep in $(tr '\0' '\n' < "$cache/kernel/modules/$name.ko" | sed -n 's/^depends=//p' | tr ',' ' '); do
      load "$dep"
    done
    order+=("$name")
  }
  for m in can can-raw can-dev vcan; do load "$m"; done
  printf '%s\n' "${order[@]}" > "$cache/kernel/modules.order"
  rm -rf "$cache/unpack" "$cache"/*.deb
  echo "$version" > "$version_file"
fi
version=$(cat "$version_file")

# Copies executables and the shared libraries they load (ldd) into an image tree.
copy_with_libs() {
  local tree=$1 file lib
  shift
  for file in "$@"; do
    cp -L --parents "$file" "$tree"
    for lib in $(ldd "$file" | awk '/=> \// {print $3} /^\t\/[^ ]*ld-linux/ {print $1}'); do
      [[ -e $tree$lib ]] || cp -L --parents "$lib" "$tree"
    done
  done
}
pack() { (cd "$1" && find . | LC_ALL=C sort | cpio -o -H newc --quiet -R 0:0 | gzip -1); }

# --- The initramfs: a fixed part (busybox, ip, modules, /init) and the test part, concatenated
#     (the kernel unpacks one cpio after the other). ---
base=$cache/base-$version.cpio.gz
if [[ ! -s $base || $0 -nt $base ]]; then
  tree=$cache/base-tree
  rm -rf "$tree"
  mkdir -p "$tree"/{bin,sbin,proc,sys,dev,tmp,lib/modules,test}
  cp /bin/busybox "$tree/bin/busybox"
  ip_path=$(command -v ip)
  copy_with_libs "$tree" "$ip_path"
  mv "$tree$ip_path" "$tree/sbin/ip-full"  # busybox's ip knows no 'type vcan'
  cp "$cache/kernel/modules"/*.ko "$cache/kernel/modules.order" "$tree/lib/modules/"
  cat > "$tree/init" << 'EOF'
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/bin:/sbin:/usr/bin:/usr/sbin
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
for m in $(cat /lib/modules/modules.order); do
  insmod /lib/modules/$m.ko || echo "VCAN-SETUP-FAILED insmod $m"
done
/sbin/ip-full link add dev vcan0 type vcan && /sbin/ip-full link set vcan0 up || echo "VCAN-SETUP-FAILED ip link vcan0"
echo
echo "VCAN-TEST-BEGIN uptime $(cut -d' ' -f1 /proc/uptime) s"
cd /tmp
/test/rmd_vcan_tests --gtest_color=no $(cat /test/args)
status=$?
echo "VCAN-TEST-STATUS $status uptime $(cut -d' ' -f1 /proc/uptime) s"
poweroff -f
EOF
  chmod +x "$tree/init"
  pack "$tree" > "$base.tmp"
  mv "$base.tmp" "$base"
  rm -rf "$tree"
fi

sum=$(sha256sum "$binary" | cut -c1-16)
part=$cache/test-$sum.cpio.gz
if [[ ! -s $part ]]; then
  rm -f "$cache"/test-*.cpio.gz
  tree=$cache/test-tree
  rm -rf "$tree"
  mkdir -p "$tree/test"
  copy_with_libs "$tree" "$binary"
  mv "$tree$binary" "$tree/test/rmd_vcan_tests"
  pack "$tree" > "$part.tmp"
  mv "$part.tmp" "$part"
  rm -rf "$tree"
fi
# The arguments: a third, tiny archive, so that changing them repacks nothing else.
tree=$cache/args-tree
rm -rf "$tree"
mkdir -p "$tree/test"
printf '%s ' "${gtest_args[@]}" > "$tree/test/args"
pack "$tree" > "$cache/args.cpio.gz"
rm -rf "$tree"
cat "$base" "$part" "$cache/args.cpio.gz" > "$cache/initrd.cpio.gz"

# --- Boot, run, power off. ---
log=$cache/console.log
started_ns=$(date +%s%N)
set +e
timeout --kill-after=5 "$timeout_s" qemu-system-x86_64 -accel tcg -m 1G -nographic -no-reboot \
  -nic none -kernel "$cache/kernel/vmlinuz" -initrd "$cache/initrd.cpio.gz" \
  -append "console=ttyS0 panic=-1 quiet" < /dev/null 2>&1 |
  sed -e 's/\r$//' -e 's/\x1b\[[0-9;?]*[A-Za-z]//g' -e 's/\x1bc//g' > "$log"  # the console's escapes out
qemu_status=${PIPESTATUS[0]}
set -e
elapsed_ms=$((($(date +%s%N) - started_ns) / 1000000))

sed -n -e 's/.*\(VCAN-TEST-BEGIN\)/\1/' -e '/^VCAN-TEST-BEGIN/,/VCAN-TEST-STATUS/p' "$log"
grep '^VCAN-SETUP-FAILED' "$log" >&2 || true
status_line=$(grep -ao 'VCAN-TEST-STATUS [0-9]*' "$log" | tail -n 1 || true)
if [[ -z $status_line ]]; then
  if [[ $qemu_status -eq 124 || $qemu_status -eq 137 ]]; then
    say "no result from QEMU within ${timeout_s} s (kernel $version); console log: $log"
  else
    say "QEMU exited ($qemu_status) before the test reported (kernel $version); console log: $log"
  fi
  exit 1
fi
status=$(echo "$status_line" | awk '{print $2}')
say "kernel $version under QEMU TCG: test status $status, QEMU ran ${elapsed_ms} ms"
exit "$status"
