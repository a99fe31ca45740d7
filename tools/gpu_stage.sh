#!/bin/bash
# One GPU training stage in one call: train CONFIG for SECONDS of wall time from its init_onnx,
# then write the EMA weights (two halves, each under the 16 MiB a returned file may have), the log and the config
# into OUT_DIR. Locally: tools/gpu_export.py turns them back into a run folder that training.export_onnx reads.
#   tools/gpu_stage.sh CONFIG SECONDS OUT_DIR [PYTHON]
# With EVAL_CLF=DIR (a carried classifier cache, runs/clf) the stage is also exported and evaluated there on every
# core, by the model card's instrument command (6000-step classifier, 64², 32 per class, the default sampler), into
# OUT_DIR/eval.json, so one call brings back an evaluated candidate.
set -u
cfg=$1; secs=$2; out=$3; py=${4:-python3}
export PYTHONUNBUFFERED=1
run=$(mktemp -d)
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv,noheader 2>/dev/null
$py -c "import torch, numpy, numba; print('torch', torch.__version__, 'cuda', torch.cuda.is_available(), 'numpy', numpy.__version__, 'numba', numba.__version__)"
t0=$(date +%s)
$py -m omninoise.training.train --config "$cfg" --out "$run" --max-seconds "$secs" 2>&1 | tee "$out/train.log"
if [ ! -f "$run/ckpt.pt" ]; then
    # nothing trained (data workers stuck, see training/batches.py): spend what is left making batches in the loop
    left=$(( secs - ($(date +%s) - t0) ))
    if [ "$left" -gt 60 ]; then
        $py -c "import json, sys; c = json.load(open(sys.argv[1])); c['workers'] = 0; json.dump(c, open(sys.argv[2], 'w'))" "$cfg" "$out/config_workers0.json"
        echo "no checkpoint: again without data workers for $left s" | tee -a "$out/train.log"
        $py -m omninoise.training.train --config "$out/config_workers0.json" --out "$run" --max-seconds "$left" 2>&1 | tee -a "$out/train.log"
    fi
fi
$py - "$run" "$out" <<'PY'
import json, os, shutil, sys, torch
run, out = sys.argv[1:]
st = torch.load(os.path.join(run, "ckpt.pt"), map_location="cpu", weights_only=False)
keys = list(st["ema"])
half = len(keys) // 2
for name, ks in (("ema_a.pt", keys[:half]), ("ema_b.pt", keys[half:])):
    torch.save({k: st["ema"][k].float().contiguous() for k in ks}, os.path.join(out, name))
json.dump(dict(step=st["step"], config=st["config"]), open(os.path.join(out, "stage.json"), "w"), indent=1)
shutil.copy(os.path.join(run, "log.jsonl"), os.path.join(out, "log.jsonl"))
print("saved step", st["step"], sorted(os.listdir(out)))
PY
if [ -n "${EVAL_CLF:-}" ]; then
    exp=$(mktemp -d)
    $py tools/gpu_export.py "$out" "$exp/run" && $py -m omninoise.training.export_onnx "$exp/run" "$exp/model" > "$out/export.log" 2>&1 \
      && $py -m bench neural-eval --model "$exp/model" --eval-size 64 --clf-stages 3 --clf-steps 6000 --clf-threads 2 \
           --n "${EVAL_N:-32}" --threads "$(nproc)" --classifier-cache "$EVAL_CLF" --sampler dpmpp_2m --steps 10 --spacing truncated \
           --eta 0.3 --no-timing -o "$out/eval.json" > "$out/eval.log" 2>&1
    tail -3 "$out/eval.log"
fi
