# OmniNoise: `make demo` and `make test` work on a fresh machine with Python 3.11 and pip.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: all setup demo test bench dist clean

all: test

$(STAMP): requirements.txt pyproject.toml
	@$(PY) -c 'import sys; sys.exit(0 if sys.version_info[:2] == (3, 11) else "OmniNoise needs Python 3.11 (bpy 5.0.1); set PY=python3.11")'
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -r requirements.txt
	$(BIN)/python -m pip install -q --no-deps -e .
	@touch $(STAMP)

setup: $(STAMP)

demo: $(STAMP)
	$(BIN)/python demo/showcase.py out/demo
	$(BIN)/python demo/showcase_blend.py out/demo
	$(BIN)/omninoise bake demo/volumes.toml
	$(BIN)/python demo/showcase_volume.py out/demo
	$(BIN)/python demo/neural.py out/demo
	$(BIN)/python demo/solid.py out/demo

$(VENV)/.train: $(STAMP) requirements-train.txt
	$(BIN)/python -m pip install -q -r requirements-train.txt -c requirements.txt
	@touch $@

test: $(STAMP) $(VENV)/.train
	$(BIN)/python -m pytest -q

$(VENV)/.bench: $(STAMP) requirements-bench.txt
	$(BIN)/python -m pip install -q setuptools wheel
	$(BIN)/python -m pip install -q --no-build-isolation -r requirements-bench.txt
	@touch $@

bench: $(VENV)/.bench
	$(BIN)/python bench/bench_wave.py

# installable extension zips (linux-x64, windows-x64, macos-arm64) in dist/, built and validated
# with Blender's own extension builder from the bpy wheel
dist: $(STAMP)
	$(BIN)/python tools/build_dist.py --out dist

clean:
	rm -rf $(VENV) out build dist wheels *.egg-info
