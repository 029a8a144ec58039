# Curved Fold developer commands. The two the README promises:
#   make test   set up (once), lint, run the whole suite on bpy 4.5 LTS, 5.0.1 and 5.2 LTS (Python 3.11, 3.11, 3.13)
#   make demo   fold every example pattern into out/ (or say where it stopped)
# Others: make setup | lint | format | build | clean

VENV      := .venv
VENV_LTS  := .venv-4.5
VENV_52   := .venv-5.2
PY        := $(VENV)/bin/python
PY_LTS    := $(VENV_LTS)/bin/python
PY_52     := $(VENV_52)/bin/python
STAMP     := $(VENV)/.curved_fold-setup.stamp
PYTEST_ARGS ?=
PYTEST    := -m pytest -q --durations=10 $(PYTEST_ARGS)

.PHONY: setup test lint format build demo clean

# Run $(1) with Blender's user folder (prefs, extensions) in a fresh temporary directory, removed afterwards.
# One OpenBLAS thread: on the shared 2-core machines the suite runs on, numpy 2.5's OpenBLAS threads spin against
# the other jobs (the 20 000-face solve took 173 s instead of 29 s on bpy 5.2; numpy 1.26: 39 s instead of 30 s).
isolated = d="$$(mktemp -d)"; OPENBLAS_NUM_THREADS=1 BLENDER_USER_RESOURCES="$$d" $(1); rc=$$?; rm -rf "$$d"; exit $$rc

# Re-run the set-up only when the script changed or a venv is missing (second `make setup` is instant).
setup:
	@for py in $(PY) $(PY_LTS) $(PY_52); do [ -x "$$py" ] || rm -f $(STAMP); done
	@$(MAKE) --no-print-directory $(STAMP)

$(STAMP): tools/setup.sh
	bash tools/setup.sh
	touch $(STAMP)

lint: setup
	$(VENV)/bin/ruff check .

format: setup
	$(VENV)/bin/ruff format .

# pytest exit code 5 ("no tests collected") is non-zero, so make fails on it as on any failure.
# Three runs, each ~100 s on 2 cores: 4.5 LTS and 5.0 (CPython 3.11, numpy 1.26), 5.2 LTS (CPython 3.13, numpy 2).
test: setup lint
	@echo "== pytest on bpy 4.5 LTS ($(VENV_LTS)) =="
	$(call isolated,$(PY_LTS) $(PYTEST))
	@echo "== pytest on bpy 5.0.1 ($(VENV)) =="
	$(call isolated,$(PY) $(PYTEST))
	@echo "== pytest on bpy 5.2 LTS ($(VENV_52)) =="
	$(call isolated,$(PY_52) $(PYTEST))

build: setup
	$(PY) tools/build_extension.py --bundle-triangle --out dist/

# The main job: set up, fold every examples/*.svg into out/ (.fold, .json, .glb), render docs/img/ pictures.
demo: setup
	$(PY) tools/demo.py

clean:
	rm -rf dist out .pytest_cache .hypothesis

# Benchmarks (issue 6): Table 1 beside the paper, speed vs error, scaling, fast/faithful ratios, under a time
# budget (~8 min on 2 shared cores); writes docs/benchmarks.md, docs/img/bench_*.png and out/benchmarks.json.
.PHONY: bench
bench: setup
	$(PY) -m curved_fold.benchmarks.run

# Long property-based fuzz of the engine and of the FOLD/SVG readers (docs/errors.md); the CI profile is tests/test_fuzz.py.
.PHONY: fuzz
fuzz: setup
	$(PY) tools/fuzz_long.py --examples 2000 --readers 3000 --seed 1
