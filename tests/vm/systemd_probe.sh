#!/bin/sh
# The probe of the systemd VM test (tests/vm/systemd_vm_test.sh), run in the VM as the oneshot
# unit vmtest-probe.service after bearingd.service. Prints "VMTEST <name>: PASS|FAIL <detail>"
# for: active, cpu-latency, alert, stop, mcap-sent; and on any failure `systemctl status` and
# the journal of bearingd ("DIAG" lines). Sends /var/log/bearingd/*.mcap base64-encoded over /dev/ttyS1.
# No `set -e`: every check runs and reports, whatever the previous one did.
set -u
CONF=/etc/bearingd/bearingd.toml
SENSOR=${SENSOR:-vm-sim}
failed=0
up() { cut -d' ' -f1 /proc/uptime; }
say() { echo "PROBE [$(up)s] $*"; }
verdict() { # NAME PASS|FAIL DETAIL
  echo "VMTEST $1: $2 $3"
  [ "$2" = PASS ] || failed=1
}
prop() { systemctl show -p "$1" --value bearingd; }
# A monotonic timestamp in µs (systemctl show ...Monotonic) as seconds with one decimal.
secs() { awk -v us="$1" 'BEGIN { printf "%.1f", us / 1e6 }'; }
diag() {
  echo "DIAG ---- systemctl status bearingd"
  systemctl status bearingd --no-pager -l 2>&1 | cut -c1-400 | sed 's/^/DIAG /'
  echo "DIAG ---- journalctl -u bearingd (last 80 lines, cut at 400 characters)"
  journalctl -u bearingd --no-pager -o short-monotonic -n 80 2>&1 | cut -c1-400 | sed 's/^/DIAG /'
}

say "probe started; $(systemctl is-system-running 2>&1)"

# 1. The service is active: Type=notify, so bearingd itself said READY=1.
state=$(systemctl is-active bearingd)
n=0
while [ "$state" != active ] && [ $n -lt 120 ]; do
  sleep 1; n=$((n + 1)); state=$(systemctl is-active bearingd)
done
if [ "$state" = active ]; then
  sleep 3 # one status interval (2 s) for the first STATUS=
  verdict active PASS "started at $(secs "$(prop ExecMainStartTimestampMonotonic)")s, active at $(secs "$(prop ActiveEnterTimestampMonotonic)")s uptime (READY=1), user $(stat -c %U "/proc/$(prop MainPID)" 2>/dev/null || echo "?"), STATUS=\"$(prop StatusText)\""
else
  verdict active FAIL "bearingd is $state after waiting ${n}s"
fi
active_s=$(secs "$(prop ActiveEnterTimestampMonotonic)")

# 1b. outputs.cpu_wakeup_latency_us (50 in the test config): the unit lets bearingd (no
#     capabilities, a private /dev) open the PM QoS device, whose group tmpfiles.d set, and
#     hold it for as long as it runs.
pid=$(prop MainPID)
capped=$(journalctl -u bearingd --no-pager -o cat 2>/dev/null | grep -a -m1 'wake-up latency')
if ls -l "/proc/$pid/fd" 2>/dev/null | grep -q '/dev/cpu_dma_latency' &&
  echo "$capped" | grep -q 'capped at 50 '; then
  verdict cpu-latency PASS "bearingd (pid $pid) holds /dev/cpu_dma_latency ($(stat -c '%U:%G %a' /dev/cpu_dma_latency)): $capped"
else
  verdict cpu-latency FAIL "pid $pid, device $(stat -c '%U:%G %a' /dev/cpu_dma_latency 2>&1), journal: ${capped:-no line on the wake-up latency}"
fi

# 1c. The unit's GLIBC_TUNABLES (the heap in huge pages) reach bearingd: systemd passes them,
#     and bearingd, which names what is missing when the kernel gives huge pages and glibc is
#     not told (src/daemon/heap_pages.rs), says nothing of 4 KiB pages. (Not read from
#     /proc/PID/environ: glibc 2.36 cuts the variable there at the first ':' as it parses it;
#     the process' own environment keeps the whole value.)
tunables=$(systemctl show -p Environment --value bearingd | tr ' ' '\n' | grep -a '^GLIBC_TUNABLES=')
note=$(journalctl -u bearingd --no-pager -o cat 2>/dev/null | grep -a -m1 '4 KiB pages')
thp=$(cat /sys/kernel/mm/transparent_hugepage/enabled 2>/dev/null || echo "none")
if echo "$tunables" | grep -q 'glibc.malloc.hugetlb=1:glibc.malloc.mmap_threshold=' && [ -z "$note" ]; then
  verdict heap-pages PASS "$tunables; kernel THP: $thp; no note on 4 KiB pages"
else
  verdict heap-pages FAIL "unit environment: ${tunables:-no GLIBC_TUNABLES}; kernel THP: $thp; journal: ${note:-nothing}"
fi

# 2. An alert over iceoryx2, received by the command-line subscriber run as user bearingd (as
#    an operator would: runuser -u bearingd -- bearingd alerts). iceoryx2 0.10 creates its
#    files owner-only, so the daemon (no capabilities) cannot connect to a root subscriber;
#    `bearingd alerts` started as root refuses with that fix and never changes its user
#    (issue 32). Then a second, late subscriber as user bearingd (as an HMI or the Python
#    example would run) must get the active alert from the history.
# alerts OUT TIMEOUT [PREFIX...]: bearingd alerts --json --count 1, output in OUT and OUT.err.
alerts() {
  out=$1 secs=$2
  shift 2
  timeout $((secs + 60)) "$@" bearingd alerts --config "$CONF" --json --count 1 \
    --timeout "$secs" > "$out" 2> "$out.err"
}
raised() { # FILE: its first JSON line is the raised outer-race alert of $SENSOR
  line=$(grep -m1 '^{' "$1")
  echo "$line" | grep -q '"state": *"raised"' && echo "$line" | grep -q '"fault": *"outer_race"' &&
    echo "$line" | grep -q "\"sensor\": *\"$SENSOR\""
}
alerts /tmp/alerts-root.out 5
rc=$?
if [ $rc = 2 ] && grep -q 'runuser -u' /tmp/alerts-root.out.err && ! grep -q '^{' /tmp/alerts-root.out; then
  verdict alert-root-refused PASS "root's bearingd alerts: exit 2, $(head -c 300 /tmp/alerts-root.out.err)"
else
  verdict alert-root-refused FAIL "root's bearingd alerts: exit $rc, stderr: $(head -c 400 /tmp/alerts-root.out.err)"
fi
t0=$(up)
alerts /tmp/alerts.out 240 setpriv --reuid=bearingd --regid=bearingd --init-groups
rc=$?
t1=$(up)
sed 's/^/ALERT /' /tmp/alerts.out
cut -c1-400 /tmp/alerts.out.err | sed 's/^/ALERT stderr: /'
line=$(grep -m1 '^{' /tmp/alerts.out)
if [ $rc = 0 ] && raised /tmp/alerts.out; then
  verdict alert PASS "as user bearingd, exit 0 after $(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b-a}')s (at ${t1}s uptime; bearingd active at ${active_s}s): $line"
else
  verdict alert FAIL "as user bearingd, exit $rc after ${t0}s..${t1}s uptime; no JSON line with \"state\":\"raised\" for outer_race of $SENSOR (got: ${line:-nothing}; stderr: $(head -c 400 /tmp/alerts.out.err))"
fi
alerts /tmp/alerts-late.out 30 setpriv --reuid=bearingd --regid=bearingd --init-groups
rc=$?
line=$(grep -m1 '^{' /tmp/alerts-late.out)
if [ $rc = 0 ] && echo "$line" | grep -q '"active_at_start": *true' &&
  echo "$line" | grep -q '"fault": *"outer_race"'; then
  verdict alert-history PASS "a late subscriber (user bearingd) got the active alert: $line"
else
  verdict alert-history FAIL "late subscriber as user bearingd, exit $rc: ${line:-nothing}; stderr: $(head -c 400 /tmp/alerts-late.out.err)"
fi

# 3. The flag in bearingd's STATUS= line (systemd's view of it), before stopping: then the MCAP
#    file must hold it. Independent of the alerts subscriber.
n=0
st=$(prop StatusText)
while ! echo "$st" | grep -q "outer_race=" && [ $n -lt 60 ]; do
  sleep 1; n=$((n + 1)); st=$(prop StatusText)
done
if echo "$st" | grep -q 'outer_race='; then
  verdict status-flag PASS "at $(up)s uptime: STATUS=\"$st\""
else
  verdict status-flag FAIL "no outer_race flag in STATUS= after ${n}s more: \"$st\""
fi

# 4. A clean stop: SIGTERM, the MCAP file finished, exit 0.
pid=$(prop MainPID)
t0=$(up)
timeout 60 systemctl stop bearingd
rc=$?
t1=$(up)
state=$(systemctl is-active bearingd)
result=$(prop Result)
code=$(prop ExecMainCode)     # 1 = exited (CLD_EXITED), 2 = killed by a signal
status=$(prop ExecMainStatus)
detail="systemctl stop exit $rc in $(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b-a}')s (pid $pid), is-active=$state, Result=$result, ExecMainCode=$code, ExecMainStatus=$status"
if [ $rc = 0 ] && [ "$state" = inactive ] && [ "$result" = success ] && [ "$code" = 1 ] &&
  [ "$status" = 0 ]; then
  verdict stop PASS "$detail"
else
  verdict stop FAIL "$detail (expected exit 0, inactive, success, code 1 = exited, status 0)"
fi

# 5. The MCAP file(s) to the host: "MCAP-BEGIN name size sha256", base64, "MCAP-END name".
files=$(ls /var/log/bearingd/*.mcap 2>/dev/null)
if [ -z "$files" ]; then
  verdict mcap-sent FAIL "no *.mcap in /var/log/bearingd: $(ls -la /var/log/bearingd 2>&1 | tr '\n' ' ')"
elif ! stty -F /dev/ttyS1 raw -echo 2>/tmp/stty.err; then
  verdict mcap-sent FAIL "cannot set up /dev/ttyS1: $(cat /tmp/stty.err)"
else
  t0=$(up)
  sent=
  for f in $files; do
    size=$(stat -c %s "$f")
    sum=$(sha256sum "$f" | cut -d' ' -f1)
    { echo "MCAP-BEGIN $(basename "$f") $size $sum"; base64 -w 76 "$f"; echo "MCAP-END $(basename "$f")"; } > /dev/ttyS1
    sent="$sent $(basename "$f") ($size bytes, owner $(stat -c %U:%G "$f"), mode $(stat -c %a "$f"))"
  done
  t1=$(up)
  verdict mcap-sent PASS "$sent in $(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.1f", b-a}')s"
fi

echo "PROBE journal excerpt of bearingd:"
journalctl -u bearingd --no-pager -o short-monotonic -n 15 2>&1 | cut -c1-300 | sed 's/^/PROBE   /'
[ $failed = 0 ] || diag
say "probe done"
