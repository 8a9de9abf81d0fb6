#!/bin/sh
# /init of the CAN test VM (see can_vm_test.sh): loads the CAN modules, creates vcan0 with FD
# MTU, runs each case with firmware-sim and bearingd ingest as separate processes, prints
# "VMTEST <case>: PASS|FAIL" and powers off.
export PATH=/bin
mount -t proc proc /proc; mount -t sysfs sysfs /sys; mount -t devtmpfs devtmpfs /dev
mount -t tmpfs tmpfs /tmp
# iceoryx2 (bearingd run's alert service) keeps its shared memory in /dev/shm.
mkdir -p /dev/shm; mount -t tmpfs tmpfs /dev/shm
echo "INIT: userspace up at $(cut -d' ' -f1 /proc/uptime)s kernel $(uname -r)"
for m in can can-raw can-dev vcan; do insmod /lib/modules/$m.ko || echo "INIT: insmod $m FAILED"; done
firmware-sim --transport can --interface vcan0 --create-vcan --duration 0 || echo "INIT: vcan0 FAILED"

# The cases to run: all, or those the kernel command line names (cases=a,b; for iterating).
cases=$(sed -n 's/.*cases=\([^ ]*\).*/\1/p' /proc/cmdline)
wants() { [ -z "$cases" ] && return 0; case ",$cases," in *,$1,*) return 0;; esac; return 1; }

# run_case NAME "INGEST ARGS" "SIM ARGS" [EXTRA CHECK]
run_case() {
  name=$1; ingest_args=$2; sim_args=$3
  wants $name || return 0
  rm -f /tmp/ready
  # 64 MiB receive buffer (SO_RCVBUFFORCE as root): a short stall of the receiver on a busy
  # vCPU must not overflow the socket queue.
  bearingd ingest --can vcan0 --ready-file /tmp/ready --until-idle 2 --rcvbuf 67108864 \
    $ingest_args > /tmp/$name.ingest 2>&1 &
  pid=$!
  n=0
  while [ ! -f /tmp/ready ] && [ $n -lt 100 ]; do sleep 0.1; n=$((n + 1)); done
  t0=$(cut -d' ' -f1 /proc/uptime)
  firmware-sim --transport can --interface vcan0 --speed-factor 0 $sim_args > /tmp/$name.sim 2>&1
  sim_rc=$?
  wait $pid
  ingest_rc=$?
  t1=$(cut -d' ' -f1 /proc/uptime)
  cat /tmp/$name.sim
  grep -v '^(' /tmp/$name.ingest
  if [ -f /tmp/$name.capture ]; then sed "s/^/CAPTURE $name /" /tmp/$name.capture; fi
  verdict=PASS
  [ $sim_rc = 0 ] || verdict=FAIL
  [ $ingest_rc = 0 ] || verdict=FAIL
  if [ -n "$4" ]; then $4 $name || verdict=FAIL; fi
  echo "VMTEST $name: $verdict (sender exit $sim_rc, receiver exit $ingest_rc, ${t0}s..${t1}s uptime)"
}

# The receiver counted exactly the malformed frames the sender injected.
same_malformed() {
  sent=$(sed -n 's/.* malformed=\([0-9]*\).*/\1/p' /tmp/$1.sim)
  got=$(sed -n 's/^malformed \([0-9]*\).*/\1/p' /tmp/$1.ingest)
  echo "INIT: $1 malformed sent $sent, counted $got"
  [ -n "$sent" ] && [ "$sent" -gt 0 ] && [ "$sent" = "$got" ]
}

run_case classic \
  "--expect-samples 384000 --expect-streams 1 --expect-gaps 0 --expect-malformed 0 --expect-restarts 0 --sensor-timeout-ms 1500 --expect-sensor-lost 1 --capture /tmp/classic.capture --capture-frames 300" \
  "--fs 6400 --duration 60 --bitrate 1000000 --node 1 --seed 1"
run_case fd \
  "--expect-samples 1536000 --expect-streams 1 --expect-gaps 0 --expect-malformed 0 --expect-restarts 0 --capture /tmp/fd.capture --capture-frames 300" \
  "--fd --fs 25600 --duration 60 --bitrate 1000000 --data-bitrate 5000000 --node 2 --seed 2"
run_case malformed \
  "--expect-samples 256000 --expect-streams 3 --expect-gaps 0 --expect-restarts 0" \
  "--fd --fs 25600 --duration 10 --nodes 3 --node 4 --inject-malformed-every 200 --seed 3" \
  same_malformed
run_case restart \
  "--expect-samples 256000 --expect-streams 1 --expect-gaps 0 --expect-malformed 0 --expect-restarts 1" \
  "--fd --fs 25600 --duration 10 --node 7 --restart-at-sample 112000 --seed 4"
# `bearingd run` on vcan0: a CAN FD node with an outer-race fault from the start and a speed
# frame every second (the config has no nominal speed, so the speed frames are what makes the
# channel score), 24 s of signal at twice real time; then the log replayed with the same config
# must raise the same flags at the same samples.
run_daemon() {
  wants run || return 0
  rm -rf /tmp/run; mkdir -p /tmp/run
  t0=$(cut -d' ' -f1 /proc/uptime)
  bearingd run --config /etc/bearingd-run.toml --duration 20 --quiet > /tmp/run.out 2>&1 &
  pid=$!
  # The log opens before the sources start; a second more for the socket to be bound.
  n=0
  while ! ls /tmp/run/mcap/*.mcap >/dev/null 2>&1 && [ $n -lt 100 ]; do sleep 0.1; n=$((n + 1)); done
  sleep 1
  firmware-sim --transport can --interface vcan0 --fd --fs 12000 --duration 24 --speed-factor 2 \
    --node 9 --fault outer --onset 0 --rpm 1772 --noise 0.1 --seed 5 --speed-every 1 > /tmp/run.sim 2>&1
  sim_rc=$?
  wait $pid
  run_rc=$?
  t1=$(cut -d' ' -f1 /proc/uptime)
  cat /tmp/run.sim
  sed 's/^/RUN /' /tmp/run.out
  bearingd replay /tmp/run/mcap/*.mcap --config /etc/bearingd-run.toml --out /tmp/run/replay \
    --quiet > /tmp/run.replay 2>&1
  replay_rc=$?
  t2=$(cut -d' ' -f1 /proc/uptime)
  sed 's/^/REPLAY /' /tmp/run.replay
  sed -n 's/^  flag //p' /tmp/run.out > /tmp/run.flags
  sed -n 's/^flag //p' /tmp/run.replay > /tmp/replay.flags
  verdict=PASS
  [ $sim_rc = 0 ] && [ $run_rc = 0 ] && [ $replay_rc = 0 ] || verdict=FAIL
  grep -q 'outer_race ok -> ' /tmp/run.flags || { echo "INIT: run: no outer-race flag"; verdict=FAIL; }
  if grep -q -E ': (inner_race|ball|cage) ' /tmp/run.flags; then echo "INIT: run: another fault's flag"; verdict=FAIL; fi
  ls /tmp/run/mcap/*.mcap >/dev/null 2>&1 || { echo "INIT: run: no MCAP log"; verdict=FAIL; }
  if [ "$(cat /tmp/run.flags)" != "$(cat /tmp/replay.flags)" ]; then echo "INIT: run: the replay's flags differ"; verdict=FAIL; fi
  echo "VMTEST run: $verdict (sender exit $sim_rc, run exit $run_rc, replay exit $replay_rc, run ${t0}s..${t1}s, replay ..${t2}s uptime)"
}
run_daemon
echo "INIT: done at $(cut -d' ' -f1 /proc/uptime)s"
poweroff -f
