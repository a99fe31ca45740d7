# OmniNoise: `make demo` and `make test` work on a fresh machine with Python 3.11 and pip.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: all setup kernel demo test test-long test-blender bench docs assets dist clean

all: test

$(STAMP): requirements.txt pyproject.toml
	@$(PY) -c 'import sys; sys.exit(0 if sys.version_info[:2] == (3, 11) else "OmniNoise needs Python 3.11 (bpy 5.0.1); set PY=python3.11")'
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -r requirements.txt
	$(BIN)/python -m pip install -q --no-deps -e .
	@touch $(STAMP)

# the C row kernel of wave noise (optional: without a compiler the numba kernel runs); rebuilt when rows.c changes
kernel: $(STAMP)
	@$(BIN)/python tools/build_kernel.py

setup: $(STAMP) kernel

demo: $(STAMP) kernel
	$(BIN)/python demo/showcase.py out/demo
	$(BIN)/python demo/showcase_blend.py out/demo
	$(BIN)/omninoise bake demo/volumes.toml
	$(BIN)/python demo/showcase_volume.py out/demo
	$(BIN)/python demo/neural.py out/demo
	$(BIN)/python demo/solid.py out/demo
	$(BIN)/python demo/solid_box.py out/demo
	$(BIN)/python demo/procedural.py out/demo

$(VENV)/.train: $(STAMP) requirements-train.txt
	$(BIN)/python -m pip install -q -r requirements-train.txt -c requirements.txt
	@touch $@

# the quick tests (a few minutes on two cores); test-long: the long integration tests (Blender, training, whole
# commands); CI runs both, and test-blender
test: $(STAMP) $(VENV)/.train kernel
	$(BIN)/python -m pytest -q -m "not long"

test-long: $(STAMP) $(VENV)/.train kernel
	$(BIN)/python -m pytest -q -m long

# The Blender tests on the other supported Blenders' bpy modules, one cached venv each: 4.2 LTS (4.2.0, the extension's
# least version, and the latest 4.2), 4.3, 4.4 and 4.5 LTS (Python 3.11), 5.1, 5.2 and 5.3 (Python 3.13; Blender 5.1+
# runs 3.13), two at once. .venv keeps the pinned 5.0.1 of requirements.txt.
PY313 ?= $(firstword $(wildcard $(HOME)/.pyenv/versions/3.13*/bin/python3.13) $(shell command -v python3.13))
BPY_VENVS := .venv-bpy420 .venv-bpy42 .venv-bpy43 .venv-bpy44 .venv-bpy45 .venv-bpy51 .venv-bpy52 .venv-bpy53
NUMBA_311 := numba==0.68.1 llvmlite==0.50.0
BPY_420 := 4.2.0
BPY_42 := 4.2.23
BPY_43 := 4.3.0
BPY_44 := 4.4.0
BPY_45 := 4.5.15
BPY_51 := 5.1.2
BPY_52 := 5.2.3
BPY_53 := 5.3.0
PY_420 := $(PY)
PY_42 := $(PY)
PY_43 := $(PY)
PY_44 := $(PY)
PY_45 := $(PY)
PY_51 := $(PY313)
PY_52 := $(PY313)
PY_53 := $(PY313)
EXTRA_420 := $(NUMBA_311)
EXTRA_42 := $(NUMBA_311)
EXTRA_43 := $(NUMBA_311)
EXTRA_44 := $(NUMBA_311)
EXTRA_45 := $(NUMBA_311)
.venv-bpy%/.installed: requirements-blender.txt pyproject.toml
	@test -n "$(PY_$*)" || { echo "make test-blender: Python 3.13 is needed for bpy $(BPY_$*) (set PY313=...)"; exit 2; }
	$(PY_$*) -m venv .venv-bpy$*
	.venv-bpy$*/bin/python -m pip install -q bpy==$(BPY_$*) -r requirements-blender.txt $(EXTRA_$*)
	.venv-bpy$*/bin/python -m pip install -q --no-deps -e .
	@touch $@

test-blender: $(STAMP) kernel $(addsuffix /.installed,$(BPY_VENVS))
	$(BIN)/python tools/blender_versions.py $(BPY_VENVS)

$(VENV)/.bench: $(STAMP) requirements-bench.txt
	$(BIN)/python -m pip install -q setuptools wheel
	$(BIN)/python -m pip install -q --no-build-isolation -r requirements-bench.txt
	@touch $@

# the speed suites (python -m bench speed: wave, neural, solid), whose JSON docs/benchmarks.md shows;
# python -m bench lists every suite
bench: $(VENV)/.bench kernel
	$(BIN)/python -m bench speed

# the README's pictures from make demo's output, and docs/benchmarks.md from the benchmarks' JSON
README_PICTURES := gallery.png showcase_render.png volumes_render.png neural.png neural_panel.png solid_slices.png solid_render.png \
	procedural.png
docs: $(STAMP)
	@for f in $(README_PICTURES); do test -f out/demo/$$f || { echo "make docs: out/demo/$$f is missing: run make demo first"; exit 2; }; done
	cp $(addprefix out/demo/,$(README_PICTURES)) docs/img/
	$(BIN)/python tools/benchmarks_md.py
	$(BIN)/python -m tools.job_reference
	$(BIN)/python -m tools.make_presets

# the shipped asset library (blender_addon/assets) and its sheet (docs/img/assets.png), saved by the oldest
# supported Blender so that every newer one opens it
assets: .venv-bpy42/.installed kernel
	.venv-bpy42/bin/python -m tools.make_assets

# installable extension zips (linux-x64, windows-x64, macos-arm64) in dist/, built and validated
# with Blender's own extension builder from the bpy wheel; Zig (PyPI's ziglang) cross-compiles the
# C row kernel of wave noise for each platform
dist: $(STAMP)
	$(BIN)/python -m pip install -q ziglang==0.17.1
	$(BIN)/python tools/build_dist.py --out dist

clean:
	rm -rf $(VENV) $(BPY_VENVS) out build dist wheels *.egg-info
