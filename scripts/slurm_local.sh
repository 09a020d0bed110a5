#!/usr/bin/env bash
# Runs docs/scale-out.md's two Slurm job arrays on a real, single-node Slurm started here, and
# checks them against local runs (issue 44 item 5):
#   - scripts/slurm/render_frames.sbatch for frames 0-3: each task's image_hash must equal the
#     same frame's image_hash from one local `render --frames 0..4` run;
#   - scripts/slurm/report_cases.sbatch for 5 cases of the quick report, one of each family (an
#     edge, a disk, a scene, a narrow-band and a light-direction case; their errors are not zero, unlike
#     the first cases'): the gathered report.csv must equal the local `report --quick --case K`
#     rows, every column but time_ms (a measurement).
#
# Needs root (it installs slurm-wlm, munge and jq with apt-get when missing and runs the daemons as
# root). Everything it starts (munged, slurmctld, slurmd) uses a private temporary directory, a
# private munge socket and free ports, so it touches no system Slurm/munge and two runs on one
# machine do not collide; the daemons are stopped on exit, also on failure.
#
# Environment: CONVSHADOW (the binary; default: built with `cargo build --release`),
# SLURM_LOCAL_KEEP=1 (keep the temporary directory), SLURM_LOCAL_TIMEOUT (seconds to wait for
# the jobs, default 900).
# Prints PASS or FAIL lines; exits 0 only when every hash and row matched.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
FRAMES=4 # frames 0..4: enough for an array, quick to run
# Quick-report cases, one per family in the order of report.csv (edge, disk, scene,
# narrowband, direction; `convshadow report --quick --case 100000` prints the count). When the report's
# grid changes, the family check below fails: pick one case of each family again.
CASE_LIST=(100 395 411 415 419)
CASE_FAMILIES=edge,disk,scene,narrowband,direction
CASES=${#CASE_LIST[@]}
CASE_ARRAY=$(IFS=,; echo "${CASE_LIST[*]}")
START=$(date +%s)
log() { printf '[slurm_local %3ds] %s\n' "$(($(date +%s) - START))" "$*"; }
fail() { log "FAIL: $*"; exit 1; }

[ "$(id -u)" = 0 ] || fail "needs root (apt-get, and the Slurm daemons run as root here)"

# Debian's packages (jq for the hash check of docs/scale-out.md); idempotent: dpkg -s succeeds
# when all are installed.
if ! dpkg -s slurm-wlm munge jq >/dev/null 2>&1; then
  log "installing slurm-wlm, munge and jq"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends slurm-wlm munge jq >/dev/null
fi
log "$(slurmctld -V) on $(hostname -s), nproc=$(nproc)"

# The binary: the one given, else the release build (a no-op when it is up to date, as after the
# README's test command).
if [ -z "${CONVSHADOW:-}" ]; then
  (cd "$ROOT" && cargo build --release --quiet --bin convshadow)
  CONVSHADOW="${CARGO_TARGET_DIR:-$ROOT/target}/release/convshadow"
  case "$CONVSHADOW" in /*) ;; *) CONVSHADOW="$ROOT/$CONVSHADOW" ;; esac
fi
[ -x "$CONVSHADOW" ] || fail "no binary at $CONVSHADOW"
export CONVSHADOW SCENE="$ROOT/scenes/default.toml"

# 0711: munged wants its socket's directory searchable by all, and nobody else needs to list it.
T=$(mktemp -d /tmp/convshadow-slurm.XXXXXX)
chmod 711 "$T"
PIDS=()    # the daemons, stopped in reverse order
WAITERS=() # the `sbatch --wait` processes
cleanup() {
  local rc=$?
  # Cancel whatever still runs (a failed or timed-out run) before the daemons go, so no task
  # outlives them; this controller is private, so every job on it is ours (SLURM_CONF names it
  # only once it is written, never a cluster the caller's environment pointed at).
  # The controller and munged must outlive the cancelled tasks: a batch step whose completion
  # cannot reach slurmctld retries for ever, and slurmd waits for it.
  if [ "${SLURM_CONF:-}" = "$T/slurm.conf" ]; then
    scancel --quiet --user=root 2>/dev/null || true
    for _ in $(seq 60); do
      [ -z "$(squeue -h -o %i 2>/dev/null)" ] && break
      sleep 0.5
    done
  fi
  for pid in "${WAITERS[@]}"; do kill "$pid" 2>/dev/null || true; done
  # slurmd, slurmctld, munged in that order, each given 10 s to stop before SIGKILL.
  for ((i = ${#PIDS[@]} - 1; i >= 0; i--)); do
    kill "${PIDS[i]}" 2>/dev/null || true
    for _ in $(seq 100); do kill -0 "${PIDS[i]}" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "${PIDS[i]}" 2>/dev/null || true
    wait "${PIDS[i]}" 2>/dev/null || true
  done
  if [ "$rc" != 0 ]; then
    for f in slurmctld.log slurmd.log munged.log; do
      [ -f "$T/$f" ] && { echo "--- last lines of $T/$f"; tail -n 20 "$T/$f"; }
    done
  fi
  if [ "${SLURM_LOCAL_KEEP:-0}" = 1 ] || [ "$rc" != 0 ]; then
    log "kept $T"
  else
    rm -rf "$T"
  fi
  log "daemons stopped; total $(($(date +%s) - START)) s"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# What runs is what the documentation shows: docs/scale-out.md must hold each job script
# verbatim, and the report array must cover the quick report's cases (the binary's count).
python3 - "$ROOT/docs/scale-out.md" "$ROOT"/scripts/slurm/*.sbatch <<'EOF' ||
import sys
doc = open(sys.argv[1]).read()
stale = [p for p in sys.argv[2:] if open(p).read() not in doc]
for p in stale:
    print(f"{p} is not in {sys.argv[1]} verbatim")
sys.exit(1 if stale else 0)
EOF
  fail "docs/scale-out.md and scripts/slurm/*.sbatch differ: copy the scripts into the doc"
QUICK_CASES=$("$CONVSHADOW" report --quick --case 1000000000 --out "$T/count" 2>&1 \
  | sed -n 's/.*the quick report has \([0-9]*\) cases.*/\1/p' || true)
grep -q "^#SBATCH --array=0-$((QUICK_CASES - 1))\$" "$ROOT/scripts/slurm/report_cases.sbatch" ||
  fail "the quick report has ${QUICK_CASES:-?} cases: update --array in report_cases.sbatch and the doc"

# munge: a fresh key in the private directory (0400, owned by the daemon's user, as munged
# checks); --force because it runs as root here.
dd if=/dev/urandom of="$T/munge.key" bs=1024 count=1 status=none
chmod 400 "$T/munge.key"
munged --force --foreground --socket="$T/munge.socket" --key-file="$T/munge.key" \
  --pid-file="$T/munged.pid" --log-file="$T/munged.log" --seed-file="$T/munged.seed" \
  >"$T/munged.out" 2>&1 &
PIDS+=($!)
for _ in $(seq 50); do [ -S "$T/munge.socket" ] && break; sleep 0.1; done
munge -S "$T/munge.socket" -n | unmunge -S "$T/munge.socket" >/dev/null || fail "munge does not work"

# Two free TCP ports for slurmctld and slurmd (the defaults, 6817/6818, may be taken by a
# system Slurm or a concurrent run).
read -r CTLD_PORT SLURMD_PORT < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*(x.getsockname()[1] for x in s))')

# One node, described by slurmd itself (`slurmd -C`: CPUs, topology, RealMemory): a node whose
# configuration claims more than slurmd finds is drained. No cgroups (the sandbox and many CI
# containers have no systemd or cgroup delegation): processes are tracked through /proc, tasks
# are not bound. No accounting database: `sbatch --wait` gives the exit codes.
NODE=$(hostname -s)
NODE_LINE=$(slurmd -C | head -n1 | sed "s/^NodeName=[^ ]*/NodeName=$NODE/")
mkdir -p "$T/state" "$T/spool" "$T/work"
export SLURM_CONF="$T/slurm.conf"
cat >"$SLURM_CONF" <<EOF
ClusterName=convshadow
SlurmctldHost=$NODE(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$T/munge.socket
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/slurmctld.log
SlurmdLogFile=$T/slurmd.log
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MailProg=/bin/true
MpiDefault=none
SwitchType=switch/none
ReturnToService=2
$NODE_LINE NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=local Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF
log "node: $NODE_LINE"

# -D: stay in the foreground, so $! is the daemon and cleanup can stop it; -i: ignore the
# (empty) state; the logs go to $T.
slurmctld -D -i -f "$SLURM_CONF" >"$T/slurmctld.out" 2>&1 &
PIDS+=($!)
slurmd -D -N "$NODE" -f "$SLURM_CONF" >"$T/slurmd.out" 2>&1 &
PIDS+=($!)
STATE=
for _ in $(seq 120); do
  STATE=$(sinfo -h -N -n "$NODE" -o %T 2>/dev/null || true)
  [ "$STATE" = idle ] && break
  sleep 0.5
done
if [ "$STATE" != idle ]; then
  scontrol show node "$NODE" 2>&1 || true
  fail "node $NODE is '${STATE:-unreachable}', not idle, after 60 s"
fi
log "node $NODE idle"

# The two arrays, submitted together from a submit directory with the logs/ folder their
# --output names (Slurm does not create it). The command line overrides the scripts' #SBATCH
# --array (the real sizes) and, on a machine with fewer than 4 CPUs, --cpus-per-task.
W="$T/work"
mkdir -p "$W/logs" "$W/out" "$W/report"
CPT=$(($(nproc) < 4 ? $(nproc) : 4))
WAIT_S=${SLURM_LOCAL_TIMEOUT:-900}
cd "$W"
timeout "$WAIT_S" sbatch --wait --quiet --array=0-$((FRAMES - 1)) --cpus-per-task="$CPT" \
  "$ROOT/scripts/slurm/render_frames.sbatch" &
SB_FRAMES=$!
WAITERS+=($!)
timeout "$WAIT_S" sbatch --wait --quiet --array="$CASE_ARRAY" \
  "$ROOT/scripts/slurm/report_cases.sbatch" &
SB_CASES=$!
WAITERS+=($!)
log "submitted: frames 0-$((FRAMES - 1)) (cpus-per-task=$CPT), report cases $CASE_ARRAY"
# While Slurm runs the arrays, the local runs they are checked against (on the same cores, so
# all of it is the cost of the check).
mkdir -p "$T/local"
"$CONVSHADOW" render "$SCENE" --frames 0..$FRAMES --time-step 0.02 --quiet \
  -o "$T/local/frame_%04d.png" --stats-json "$T/local/sequence.json"
for k in "${CASE_LIST[@]}"; do
  "$CONVSHADOW" report --quick --case "$k" --threads 1 \
    --out "$T/local/case_$(printf %04d "$k")" >/dev/null
done
log "local runs done"
RC_FRAMES=0 RC_CASES=0
wait "$SB_FRAMES" || RC_FRAMES=$?
wait "$SB_CASES" || RC_CASES=$?
log "Slurm arrays done: sbatch --wait exit codes frames=$RC_FRAMES cases=$RC_CASES"
# slurmctld's own record: which array task ran where, on how many CPUs, and its exit status.
grep -E 'Allocate JobId|WEXITSTATUS' "$T/slurmctld.log" | sed 's/^/slurmctld: /' || true
for f in logs/*.log; do
  [ -s "$f" ] && { echo "--- $f"; cat "$f"; }
done
[ "$RC_FRAMES" = 0 ] || fail "the frame array failed (exit $RC_FRAMES)"
[ "$RC_CASES" = 0 ] || fail "the report array failed (exit $RC_CASES)"

# The check from docs/scale-out.md: "frame image_hash" per task JSON, sorted, against the local
# --frames run's.
for f in out/frame_*.json; do jq -r '.frames[0] | "\(.frame) \(.image_hash)"' "$f"; done \
  | sort -n >hashes.txt
jq -r '.frames[] | "\(.frame) \(.image_hash)"' "$T/local/sequence.json" | sort -n \
  >expected_hashes.txt
echo "Slurm task: frame image_hash  |  local --frames 0..$FRAMES: frame image_hash"
paste -d'|' hashes.txt expected_hashes.txt | sed 's/^/            /; s/|/  |  /'
[ "$(wc -l <hashes.txt)" = "$FRAMES" ] || fail "expected $FRAMES frame hashes from Slurm"
if diff hashes.txt expected_hashes.txt >/dev/null; then
  log "PASS: the $FRAMES Slurm frames' image_hash equal the local --frames run's"
else
  fail "the Slurm frames' image_hash differ from the local run's"
fi

# The report rows, gathered in index order as docs/scale-out.md says (the header from the first
# case's folder: here that is not case_0000), against the local rows; every column but time_ms.
gather() {
  local dirs=("$1"/case_*)
  head -n1 "${dirs[0]}/report.csv"
  for d in "${dirs[@]}"; do tail -n +2 "$d/report.csv"; done
}
gather report >report.csv
gather "$T/local" >expected_report.csv
if python3 - report.csv expected_report.csv "$CASE_ARRAY" "$CASE_FAMILIES" <<'EOF'
import csv, sys
got_path, want_path, cases, families = sys.argv[1:5]
cases, families = cases.split(","), families.split(",")
def rows(path):
    with open(path, newline="") as f:
        r = list(csv.DictReader(f))
    for row in r:
        row.pop("time_ms")  # a measurement, not a result
    return r
got, want = rows(got_path), rows(want_path)
# The error columns and the note; the other columns say which case it is.
shown = ["family", "kernel", "penumbra", "slabs", "rmse_correct", "rmse_iterated", "rmse_reference"]
for case, row in zip(cases, got):
    print(f"case {case}: " + ", ".join(f"{k}={row[k]}" for k in shown))
ok = True
if [r["family"] for r in got] != families:
    print(f"families {[r['family'] for r in got]}, expected {families}: the report's grid "
          "changed; choose CASE_LIST again (scripts/slurm_local.sh)")
    ok = False
if len(got) != len(cases) or len(want) != len(cases):
    print(f"{len(got)} rows from Slurm, {len(want)} local, {len(cases)} cases")
    ok = False
for case, g, w in zip(cases, got, want):
    for k in w:
        if g.get(k) != w[k]:
            print(f"case {case}: {k}: Slurm {g.get(k)!r}, local {w[k]!r}")
            ok = False
sys.exit(0 if ok else 1)
EOF
then
  log "PASS: the $CASES Slurm report rows equal the local rows (all columns but time_ms)"
else
  fail "the Slurm report rows differ from the local rows"
fi
log "PASS"
