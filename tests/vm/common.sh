# Shared by the qemu VM tests (sourced, not run): progress lines, the host tools, and the
# Debian kernel and busybox the VMs boot. The sourcing script sets NAME, ROOT and WORK first.
# With CI=true nothing is skipped: a missing piece is installed (as root) or is a failure that
# names it and the fix.

started=$(date +%s)
say() { printf '[%s %3ss] %s\n' "$NAME" "$(( $(date +%s) - started ))" "$*"; }
missing() {
  echo "$NAME: missing $1; install it with: $2" >&2
  exit 1
}

# vm_host_tools [COMMAND:PACKAGE ...]: qemu, plus each COMMAND (from Debian's PACKAGE);
# installed here when root.
vm_host_tools() {
  local need_apt=() pair
  command -v qemu-system-x86_64 >/dev/null || need_apt+=(qemu-system-x86)
  for pair in "$@"; do
    command -v "${pair%%:*}" >/dev/null || need_apt+=("${pair#*:}")
  done
  if [ ${#need_apt[@]} -gt 0 ]; then
    [ "$(id -u)" = 0 ] || missing "${need_apt[*]}" "apt-get install ${need_apt[*]} (as root)"
    say "apt-get install ${need_apt[*]}"
    apt-get install -y -q --no-install-recommends "${need_apt[@]}" >/dev/null ||
      missing "${need_apt[*]}" "apt-get update && apt-get install ${need_apt[*]}"
  fi
}

# vm_kernel: Debian's current kernel package and busybox-static, downloaded and unpacked (not
# installed) into $WORK, once; sets KPKG, KVER, MODDIR (its modules) and BB (busybox).
vm_kernel() {
  KPKG=$(apt-cache depends linux-image-amd64 | awk '/Depends: linux-image-[0-9]/{print $2; exit}')
  [ -n "$KPKG" ] || missing "the Debian kernel package name" "apt-get update"
  KVER=${KPKG#linux-image-}
  if [ ! -f "$WORK/kroot/boot/vmlinuz-$KVER" ] || [ ! -x "$WORK/bbroot/bin/busybox" ]; then
    say "download $KPKG busybox-static"
    (cd "$WORK" && rm -f ./*.deb && apt-get download -q "$KPKG" busybox-static >/dev/null) ||
      missing "$KPKG or busybox-static from the Debian mirror" "apt-get update (network to the mirror)"
    rm -rf "$WORK/kroot" "$WORK/bbroot"
    dpkg-deb -x "$WORK/$KPKG"_*.deb "$WORK/kroot"
    dpkg-deb -x "$WORK"/busybox-static_*.deb "$WORK/bbroot"
    rm -f "$WORK"/*.deb
  fi
  MODDIR=$WORK/kroot/lib/modules/$KVER/kernel
  BB=$WORK/bbroot/bin/busybox
}

# vm_binaries: the bearingd and firmware-sim every VM test runs are the host build of the test
# step (`cargo test --workspace --release`, default features: SocketCAN, iceoryx2, TLS), so the
# VMs run what the tests ran and, in CI, nothing is compiled here (a musl build of its own cost
# CI 335 s). The same cargo command as the test step, so it unifies features as that step does
# and finds its build done; by hand, the first VM test builds it. Sets HOST_BIN, the directory
# of both binaries. A failed build stops the calling script (set -e) with cargo's errors above.
vm_binaries() {
  say "cargo test --workspace --release --no-run (the test step's build: bearingd, firmware-sim)"
  (cd "$ROOT" && cargo test --workspace --release --locked --quiet --no-run)
  HOST_BIN=$ROOT/target/release
  local bin
  for bin in bearingd firmware-sim; do
    [ -x "$HOST_BIN/$bin" ] || missing "$HOST_BIN/$bin" "cargo test --workspace --release --no-run"
  done
}

# vm_install_binary BINARY ROOT: BINARY stripped (the release profile's line tables would only
# fatten the initramfs) into ROOT/bin, with every shared library it links (glibc's loader, libc,
# libm, libgcc_s, as ldd lists them) at the same path under ROOT: the busybox VMs have no C
# library of their own, and the VM's kernel runs the host's C library as it is. The sources
# are the host's system libraries (root's, read through their symlinks); ROOT is the VM test's
# own fresh work directory.
vm_install_binary() {
  local binary=$1 root=$2 lib
  mkdir -p "$root/bin"
  strip -o "$root/bin/$(basename "$binary")" "$binary"
  for lib in $(ldd "$binary" | grep -o '/[^ ]*'); do
    cp -L --parents "$lib" "$root"
  done
}
