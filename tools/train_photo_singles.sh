#!/bin/bash
# Train the single-exemplar photo models one after another: configs/solid/photo_singles/NAME.json -> runs/solid/NAME
# (the card reads each run's log there).  Usage: bash tools/train_photo_singles.sh NAME...
# A finished run resumes at its last step and stops at once; PY names the Python (default .venv/bin/python).
set -e
PY=${PY:-.venv/bin/python}
for name in "$@"; do
  "$PY" -m omninoise.training.solid.train --config "configs/solid/photo_singles/$name.json" --out "runs/solid/$name"
done
