#!/usr/bin/env bash
# Trains several solid-texture configs side by side on one GPU, each with its schedule fitted to a time
# budget (python -m omninoise.training.solid.train --budget-seconds), and leaves for each run its checkpoint without
# the optimiser's moments (RUN.pt: config, model, step, hardware; export it with
# python -m omninoise.training.solid.export) and one archive of the logs in OUTDIR.
#
#   tools/gpu_solid_campaign.sh BUDGET_SECONDS OUTDIR CONFIG.json [CONFIG.json ...]
#
# SWA_FROM=STEP: each run that keeps weight snapshots (snapshot_every in its config) also comes back as
# NAME_swa.pt, the mean of its snapshots from that step on (python -m omninoise.training.solid.average --snapshots); the
# tool brings back at most 8 files, so at most 3 runs with SWA_FROM.
# PYTHON (default python3) runs training; EXTRA_SET adds --set KEY=JSON to every run, several separated by ';'
# (a CPU rehearsal: EXTRA_SET='device="cpu";batch=2;crop=64').  Each run's log is runs/solid/NAME.log; the
# script polls them every POLL seconds.
set -u
if [ $# -lt 3 ]; then
    echo "usage: tools/gpu_solid_campaign.sh BUDGET_SECONDS OUTDIR CONFIG.json [CONFIG.json ...]" >&2
    exit 2
fi
budget=$1; out=$2; shift 2
py=${PYTHON:-python3}
poll=${POLL:-60}
mkdir -p "$out" runs/solid
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader
IFS=';' read -r -a extra <<<"${EXTRA_SET:-}"
names=(); pids=()
for cfg in "$@"; do
    name=$(basename "$cfg" .json)
    args=(-m omninoise.training.solid.train --config "$cfg" --out "runs/solid/$name" --budget-seconds "$budget")
    for kv in "${extra[@]}"; do args+=(--set "$kv"); done
    PYTHONUNBUFFERED=1 "$py" "${args[@]}" >"runs/solid/$name.log" 2>&1 &
    pids+=($!); names+=("$name")
done
while :; do
    alive=0
    for p in "${pids[@]}"; do kill -0 "$p" 2>/dev/null && alive=$((alive + 1)); done
    date +%T
    command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv,noheader
    for n in "${names[@]}"; do echo "  $n: $(tail -n 1 "runs/solid/$n.log")"; done
    [ "$alive" -eq 0 ] && break
    sleep "$poll"
done
status=0
for i in "${!pids[@]}"; do
    wait "${pids[$i]}" || { echo "${names[$i]} failed:"; tail -n 20 "runs/solid/${names[$i]}.log"; status=1; }
done
for n in "${names[@]}"; do
    [ -f "runs/solid/$n/ckpt.pt" ] || continue
    "$py" - "runs/solid/$n/ckpt.pt" "$out/$n.pt" <<'PY'
import sys, torch
state = torch.load(sys.argv[1], map_location="cpu", weights_only=False)
state.pop("opt", None)
torch.save(state, sys.argv[2])
print(sys.argv[2], "step", state["step"], "of", state["config"]["steps"], "-", state["hardware"])
PY
    grep -h "schedule fitted" "runs/solid/$n.log" | sed "s/^/  $n: /"
    if [ -n "${SWA_FROM:-}" ] && [ -d "runs/solid/$n/snapshots" ]; then
        "$py" -m omninoise.training.solid.average --out "runs/solid/${n}_swa" --snapshots "runs/solid/$n" --from "$SWA_FROM" \
            && cp "runs/solid/${n}_swa/ckpt.pt" "$out/${n}_swa.pt" || status=1
    fi
done
tar czf "$out/logs.tar.gz" $(for n in "${names[@]}"; do echo "runs/solid/$n.log"; [ -f "runs/solid/$n/log.jsonl" ] && echo "runs/solid/$n/log.jsonl"; done)
exit $status
