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

# vm_host_tools [COMMAND:PACKAGE ...]: qemu, musl-gcc and the Rust musl target, plus each
# COMMAND (from Debian's PACKAGE); installed here when root.
vm_host_tools() {
  local need_apt=() pair
  command -v qemu-system-x86_64 >/dev/null || need_apt+=(qemu-system-x86)
  command -v musl-gcc >/dev/null || need_apt+=(musl-tools)
  for pair in "$@"; do
    command -v "${pair%%:*}" >/dev/null || need_apt+=("${pair#*:}")
  done
  if [ ${#need_apt[@]} -gt 0 ]; then
    [ "$(id -u)" = 0 ] || missing "${need_apt[*]}" "apt-get install ${need_apt[*]} (as root)"
    say "apt-get install ${need_apt[*]}"
    apt-get install -y -q --no-install-recommends "${need_apt[@]}" >/dev/null ||
      missing "${need_apt[*]}" "apt-get update && apt-get install ${need_apt[*]}"
  fi
  rustup target list --installed | grep -q x86_64-unknown-linux-musl ||
    rustup target add x86_64-unknown-linux-musl >/dev/null ||
    missing "Rust target x86_64-unknown-linux-musl" "rustup target add x86_64-unknown-linux-musl"
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

# vm_binaries: the static (musl) bearingd and firmware-sim every VM test runs, built by one
# cargo command with the default features (SocketCAN, iceoryx2, TLS) so that the three VM
# tests share one build: the first builds (about 5 min on 2 cores), the next two find it
# done. A different package set or feature list would unify features differently and rebuild
# every crate whose features changed. Sets MUSL_BIN, the directory of both binaries. A failed
# build stops the calling script (set -e) with cargo's errors above.
vm_binaries() {
  say "cargo build --release --locked (musl: bearingd, firmware-sim; shared by the VM tests)"
  (cd "$ROOT" && cargo build --release --locked --quiet --target x86_64-unknown-linux-musl \
    -p bearingd -p firmware-sim)
  MUSL_BIN=$ROOT/target/x86_64-unknown-linux-musl/release
}
