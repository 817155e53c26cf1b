#!/usr/bin/env bash
# A labgrid board farm in a box, for cli/tests/it/cli_labgrid.rs: run
# inside a network namespace of its own (`unshare -n`), so the coordinator,
# the exporter and the ser2net the exporter starts (which binds every
# address) are reachable from nowhere else. Serves one place, `rig1`,
# whose serial port is a `ppmc bridge-sim` pseudo-terminal, and runs ppmc
# against it: first not acquired (it must refuse), then acquired.
#
# Arguments: PPMC LABGRID_BIN_DIR SCRATCH_DIR. Prints `MARK name value`
# lines for the test to check; everything it started is stopped on exit.
set -uo pipefail
ppmc=$1 lg=$2 dir=$3
export PATH="$lg:$PATH" LG_COORDINATOR=127.0.0.1:20408

pids=()
# rig3's bridge (recovery by power) is served from a folder under /dev,
# as labgrid's exporter wants a port's path to be: a link that the power
# switch points at each new bridge-sim.
power=$(mktemp -d /dev/shm/ppmc-power-XXXXXX)
script=$(cd "$(dirname "$0")/../../../.." && pwd)/scripts/bridge-sim-power
export PPMC=$ppmc
# The labgrid clients that export a port in this network namespace (a
# run on another, a test beside this one, is none of ours).
exports_here() {
    local me p n=0
    me=$(readlink /proc/$$/ns/net)
    for p in $(pgrep -f 'labgrid-client -c .* export'); do
        [ "$(readlink "/proc/$p/ns/net" 2>/dev/null)" = "$me" ] && n=$((n + 1))
    done
    echo "$n"
}
cleanup() {
    "$script" "$power" off 2>/dev/null
    for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null; done
    wait 2>/dev/null
    rm -rf "$power"
}
trap cleanup EXIT
trap 'exit 143' TERM INT
# The farm's files and logs, as docs/board-farm.md ("Try it on one
# machine") writes them: in the folder it runs in.
cd "$dir"

# Only loopback exists here. ser2net 4 refuses to listen on a host with no
# address but 127.0.0.1 ("Unable to find a valid name"), so loopback gets a
# second, private one (dummy and veth links need modules).
ip link set lo up
ip addr add 10.254.0.1/32 dev lo

"$ppmc" bridge-sim --link "$dir/pty" > "$dir/bridge-sim.log" 2>&1 &
pids+=($!)
"$ppmc" bridge-sim --link "$dir/pty2" > "$dir/bridge-sim2.log" 2>&1 &
pids+=($!)
labgrid-coordinator -l 127.0.0.1:20408 > coordinator.log 2>&1 &
pids+=($!)
for _ in $(seq 100); do [ -L "$dir/pty" ] && [ -L "$dir/pty2" ] && break; sleep 0.1; done
cat > "$dir/exporter.yaml" <<YAML
bridge:
  RawSerialPort:
    port: $(readlink "$dir/pty")
    speed: 115200
bridge2:
  RawSerialPort:
    port: $(readlink "$dir/pty2")
    speed: 115200
bridge3:
  RawSerialPort:
    port: $power/pty
    speed: 115200
YAML
# The exporter gives up on a coordinator that is not listening yet.
for _ in $(seq 150); do
    (exec 3<>/dev/tcp/127.0.0.1/20408) 2>/dev/null && break
    sleep 0.2
done
labgrid-exporter -c 127.0.0.1:20408 --hostname 127.0.0.1 -n bench1 exporter.yaml > exporter.log 2>&1 &
pids+=($!)
for _ in $(seq 150); do
    [ "$(labgrid-client resources 2>/dev/null | grep -c '^bench1/bridge[23]\?/')" = 3 ] && break
    sleep 0.2
done
resources=$(labgrid-client resources 2>&1 | tr '\n' ' ')
echo "MARK resources $resources"
case $resources in
*bench1/bridge/*) ;;
*) echo "the exporter published nothing" >&2; exit 1 ;;
esac

# The place, as docs/board-farm.md sets it up.
labgrid-client -p rig1 create
labgrid-client -p rig1 add-match 'bench1/bridge/*'

"$ppmc" run --target labgrid:rig1 > unacquired.out 2> unacquired.err
echo "MARK unacquired-exit $?"

# The CI job of docs/board-farm.md: acquire, run, release.
labgrid-client -p rig1 acquire
"$ppmc" run --target labgrid:rig1 --junit report.xml > run.out 2> run.err
echo "MARK run-exit $?"
# ppmc stopped the labgrid-client it started to learn the port.
echo "MARK exports-left $(exports_here)"

# Two places in one run (docs/board-farm.md, several boards).
labgrid-client -p rig2 create
labgrid-client -p rig2 add-match 'bench1/bridge2/*'
labgrid-client -p rig2 acquire
mkdir two && cd two
"$ppmc" run --target labgrid:rig1,rev=B2 --target labgrid:rig2,rev=C1 --skip-tag long --junit report.xml > run.out 2> run.err
echo "MARK two-exit $?"
cd ..
echo "MARK exports-left-two $(exports_here)"
labgrid-client -p rig2 release
labgrid-client -p rig1 release

# Leases (issue 44, docs/board-farm.md "Leases"): ppmc acquires rig1
# itself (`,acquire`) and lets go of it however the run ends.
acquired() { labgrid-client -p rig1 show 2>/dev/null | sed -n 's/^ *acquired: //p'; }
mkdir lease && cd lease
"$ppmc" run --target labgrid:rig1,acquire --filter s3_4_1 > ok.out 2> ok.err
echo "MARK lease-ok-exit $?"
echo "MARK lease-after-ok $(acquired)"
# Stopped by SIGINT in the middle of a soak: released too.
"$ppmc" run --target labgrid:rig1,acquire --filter s3_4_1 --repeat 100000 > int.out 2> int.err &
run=$!
for _ in $(seq 300); do labgrid-client -p rig1 show 2>/dev/null | grep -q 'ppmc_pid=' && break; sleep 0.1; done
sleep 1
kill -INT "$run"; wait "$run"
echo "MARK lease-int-exit $?"
echo "MARK lease-after-int $(acquired)"
# Killed outright: its lock stays, and the next run names whose it is.
"$ppmc" run --target labgrid:rig1,acquire --filter s3_4_1 --repeat 100000 > killed.out 2> killed.err &
run=$!
for _ in $(seq 300); do labgrid-client -p rig1 show 2>/dev/null | grep -q 'ppmc_pid=' && break; sleep 0.1; done
# The client it started to learn the port outlives it (nothing can stop
# it for a process killed outright): stopped here, so nothing is left.
orphans=$(pgrep -P "$run")
kill -KILL "$run"; wait "$run" 2>/dev/null
for p in $orphans; do kill -TERM "$p" 2>/dev/null; done
echo "MARK lease-killed-pid $run"
echo "MARK lease-after-kill $(acquired)"
"$ppmc" run --target labgrid:rig1,acquire --filter s3_4_1 > stale.out 2> stale.err
echo "MARK lease-stale-exit $?"
echo "MARK lease-stale-says $(tr '\n' ' ' < stale.err)"
"$ppmc" run --target labgrid:rig1,acquire --steal-stale --filter s3_4_1 > steal.out 2> steal.err
echo "MARK lease-steal-exit $?"
echo "MARK lease-steal-says $(tr '\n' ' ' < steal.err)"
echo "MARK lease-after-steal $(acquired)"
cd ..

# Recovery by power (issue 44, docs/board-farm.md "A board that hangs"):
# rig3's bridge stops answering after 60 frames. Its power is labgrid's
# ExternalPowerDriver, in the environment LG_ENV names, whose command
# restarts the bridge-sim; ppmc cycles it through `labgrid-client power
# cycle`, asks labgrid again where the port is, and goes on.
"$script" "$power" on --stall-after 60
labgrid-client -p rig3 create
labgrid-client -p rig3 add-match 'bench1/bridge3/*'
mkdir power && cd power
cat > power-env.yaml <<YAML
targets:
  rig3:
    resources:
      RemotePlace:
        name: rig3
    drivers:
      ExternalPowerDriver:
        cmd_on: "$script $power on"
        cmd_off: "$script $power off"
        cmd_cycle: "$script $power cycle"
YAML
export LG_ENV=power-env.yaml
"$ppmc" run --target labgrid:rig3,acquire --skip-tag long --link-timeout 500ms --link-retries 3 --junit report.xml > run.out 2> run.err
echo "MARK power-exit $?"
# Each bridge-sim started says where it serves, once.
echo "MARK power-starts $(grep -c 'serving on' "$power/bridge-sim.log")"
echo "MARK power-after $(labgrid-client -p rig3 show 2>/dev/null | sed -n 's/^ *acquired: //p')"
cd ..
