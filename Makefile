# lasa: reproduce "Shared Autonomy with Learned Latent Actions" (RSS 2020).
#
#   make                  this list (make help)
#   make figures          regenerate every figure, CSV, video and the claims table (paper scale),
#                         the eating study (notebooks 10-11, Panda only) included, and the executed
#                         notebooks as pages to read (figures/notebooks/)
#   make figures QUICK=1  the same pipeline at toy scale, into build/quick/ (figures/ untouched)
#   make figures LARGE=1  paper scale with the cluster-sized verdict map (configs/large.yaml),
#                         into build/large/; LASA_SCHEDULER=tcp://host:8786 runs its grid on Dask
#   make verify           regenerate everything (paper scale) into build/verify/, then compare it with
#                         figures/: CSV values, bytes of images and videos, the notebook pages' outputs
#                         and every claim's verdict (fails if and only if a verdict differs)
#   make test             lint + pytest, including every notebook run in QUICK mode
#   make book             a static site of the executed notebooks, claims table first -> build/book/html
#   make teleop ARGS=...  drive the robot live in MuJoCo's viewer (gamepad or keyboard), sessions logged
#   make study-server ARGS=...  the eating study in participants' browsers (python -m lasa.live.web),
#                         on 127.0.0.1 unless ARGS has --host; links from `python -m lasa.live.web schedule`
#   make bench            performance benchmarks (benchmarks/bench.py) -> benchmarks/results.json, scaling.png
#   make setup            create .venv from environment.lock (+ system libraries for rendering)
#   make clean            remove build/ (keeps .venv and the committed figures)
#
# Each figure notebook is a Make target (its executed copy in $(BUILD)/notebooks), which
# depends on the notebook, the lasa files it runs, the config and the notebooks it reads from:
# after a change, `make figures` re-runs only what is stale. Two notebooks run at a time (JOBS=2,
# one torch thread each): the study's chain and the robots'; OUT=dir runs the pipeline into dir instead.

SHELL := /bin/bash
.SHELLFLAGS := -eu -o pipefail -c
.DELETE_ON_ERROR:

# The first target, so the default goal (a bare `make`): the usage block at the top of this file,
# its leading comment lines up to the first blank line, without the comment marks.
help:
	@sed -n '1,/^$$/{/^#/s/^# \{0,1\}//p}' $(firstword $(MAKEFILE_LIST))

PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.lasa-installed
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
export MUJOCO_GL ?= osmesa

ifeq ($(QUICK),1)
CONFIG := configs/quick.yaml
BUILD := build/quick
else ifeq ($(LARGE),1)
CONFIG := configs/large.yaml
BUILD := build/large
else
CONFIG := configs/paper.yaml
BUILD := build
endif
# OUT=dir: the same pipeline with every artifact, figure and the claims table under dir.
ifdef OUT
BUILD := $(OUT)
OUT_PARAMS := --param build_dir=$(OUT) --param figures_dir=$(OUT)/figures
endif
EXEC := $(BUILD)/notebooks
JOBS ?= 2
NPROC := $(shell nproc 2>/dev/null || echo 2)
# One torch and one OpenMP/BLAS thread per notebook, on every machine: more threads round
# float reductions differently, and the figures would then depend on the core count
# (lasa.base.config.set_threads). Idle BLAS threads of two processes also spin against each
# other on tiny operations (measured: demonstration collection 8 s alone, 166 s
# oversubscribed). The parallelism is the notebooks side by side (JOBS).
export LASA_THREADS ?= 1
export OMP_NUM_THREADS ?= 1
# The numerical kernels on their AVX2 paths on every x86 CPU, for the same bytes everywhere: the
# values of lasa/runtime.py (PINNED), which lasa.runtime.pin() sets too; exported here so that
# every process Make starts has them before numpy or torch loads.
# One you set yourself is kept. make figures records those in effect in figures/kernels.json.
export ATEN_CPU_CAPABILITY ?= avx2
export ONEDNN_MAX_CPU_ISA ?= AVX2
export DNNL_MAX_CPU_ISA ?= AVX2
export MKL_CBWR ?= AVX2
export MKL_ENABLE_INSTRUCTIONS ?= AVX2
export NPY_DISABLE_CPU_FEATURES ?= X86_V4 AVX512F AVX512_SKX AVX512_CLX AVX512_CNL AVX512_ICL AVX512_SPR
export OPENBLAS_CORETYPE ?= Haswell
# llvmpipe (OSMesa) render threads: the cores shared among the notebooks that run at once
export LP_NUM_THREADS ?= $(shell n=$$(( $(NPROC) / $(JOBS) )); echo $$(( n > 0 ? n : 1 )))
# What each notebook runs: the lasa modules it reaches by imports, read from the source by
# lasa/pipeline/makedeps.py into NB_SRC_<notebook> (build/make-deps.mk, remade when a module or a
# notebook changes). A notebook re-runs only when a file it runs changed: no notebook reaches live
# use (lasa/live/), so an edit there leaves `make figures` with nothing to do, and an edit to one
# figure's module re-runs that figure's notebooks (and those that read their outputs) alone.
NOTEBOOK_FILES := $(sort $(wildcard notebooks/[0-9]*.ipynb))
MAKE_DEPS := build/make-deps.mk
$(MAKE_DEPS): lasa/pipeline/makedeps.py $(NOTEBOOK_FILES) $(shell find lasa -name '*.py')
	@mkdir -p $(@D)
	@# a temp file of its own per process: the study and robot sub-makes may remake it at once (-B)
	@$(PYTHON) lasa/pipeline/makedeps.py $(NOTEBOOK_FILES) > $@.$$$$.tmp && mv $@.$$$$.tmp $@
include $(MAKE_DEPS)
PIP_NOISE := is ignored: it is neither a file nor a directory
RUN = $(BIN)/python -m lasa.pipeline.execute $< --config $(CONFIG) --out $(EXEC) --timings $(BUILD)/timings.jsonl $(OUT_PARAMS)

.PHONY: help setup sysdeps figures notebooks study-notebooks robot-notebooks verify test lint bench clean teleop \
  study-server book

# npm packages, pinned here (the Python ones are in environment.lock), each served by lasa itself
# (no CDN at view time): MathJax for the book (its es5 build); MuJoCo's official WebAssembly
# bindings (@mujoco/mujoco, the single-threaded build: mujoco.js + mujoco.wasm) and three.js
# (its build/ ES modules) for the web study's page, which draws the robot with them
# (`--frames browser`). A stamp per version keeps `make setup` fast once they are there.
MATHJAX_VERSION := 3.2.2
MATHJAX := $(VENV)/mathjax/es5/tex-chtml.js
MUJOCO_JS_VERSION := 3.14.0
MUJOCO_JS := $(VENV)/mujoco-js/.installed-$(MUJOCO_JS_VERSION)
THREE_VERSION := 0.187.0
THREE := $(VENV)/three/.installed-$(THREE_VERSION)
setup: $(STAMP) sysdeps $(MATHJAX) $(MUJOCO_JS) $(THREE)

$(MATHJAX): | sysdeps
	@rm -rf $(VENV)/mathjax && mkdir -p $(VENV)/mathjax
	cd $(VENV)/mathjax && npm pack mathjax@$(MATHJAX_VERSION) --silent >/dev/null && tar xzf mathjax-$(MATHJAX_VERSION).tgz \
	  && mv package/es5 es5 && rm -rf package mathjax-$(MATHJAX_VERSION).tgz

$(MUJOCO_JS): | sysdeps
	@rm -rf $(VENV)/mujoco-js && mkdir -p $(VENV)/mujoco-js
	cd $(VENV)/mujoco-js && npm pack @mujoco/mujoco@$(MUJOCO_JS_VERSION) --silent >/dev/null \
	  && tar xzf mujoco-mujoco-$(MUJOCO_JS_VERSION).tgz \
	  && mv package/mujoco.js package/mujoco.wasm package/package.json package/README.md . \
	  && rm -rf package mujoco-mujoco-$(MUJOCO_JS_VERSION).tgz
	touch $@

$(THREE): | sysdeps
	@rm -rf $(VENV)/three && mkdir -p $(VENV)/three
	cd $(VENV)/three && npm pack three@$(THREE_VERSION) --silent >/dev/null && tar xzf three-$(THREE_VERSION).tgz \
	  && mv package/build/three.module.js package/build/three.core.js package/LICENSE package/package.json . \
	  && rm -rf package three-$(THREE_VERSION).tgz
	touch $@

# The lock's packages with the most files (pip's RECORD), heaviest first: cmeel-boost 16k, torch 15k, ...
PIP_HEAVY := cmeel-boost torch PyOpenGL jedi sympy pandas statsmodels scipy mypy numpy
$(STAMP): environment.lock pyproject.toml
	@test -n "$(PYTHON)" || { echo "error: Python 3.11 not found (set PYTHON=...)"; exit 1; }
	$(PYTHON) -m venv $(VENV)
	@# The lock names every package at its version, so each half installs as it is (--no-deps), in two
	@# pip processes at once: pip unpacks and byte-compiles on one core (measured: 104 s for the whole lock
	@# in one process). The halves take turns at PIP_HEAVY, then at the rest (67 s for the slower half
	@# when every other line went to each, 61 s so). `pip check` then proves the lock complete (lasa's
	@# own requirements too).
	grep -v '^#' environment.lock | awk -v heavy="$(PIP_HEAVY)" -v out=$(VENV)/lock-half- \
	  'BEGIN { n = split(heavy, h, " "); for (i = 1; i <= n; i++) rank[tolower(h[i])] = i } \
	   NF { name = tolower($$0); sub(/==.*/, "", name); \
	        half = (name in rank) ? rank[name] % 2 : (rest++) % 2; print > (out half ".txt") }'
	printf '%s\n' $(VENV)/lock-half-0.txt $(VENV)/lock-half-1.txt \
	  | xargs -P 2 -I {} $(BIN)/pip install --quiet --disable-pip-version-check --no-deps -r {} 2>&1 \
	  | { grep -v "$(PIP_NOISE)" || true; }
	@# an older build's lasa.egg-info in the tree would shadow the installed version (lasa.__version__)
	rm -rf lasa.egg-info
	$(BIN)/pip install --quiet --disable-pip-version-check --no-deps --no-build-isolation -e . 2>&1 | { grep -v "$(PIP_NOISE)" || true; }
	$(BIN)/pip check
	touch $@

# Software rendering (OSMesa); for MuJoCo's viewer (make teleop, and its test under a virtual
# display) GLX from Mesa and Xvfb; Chromium and its driver for the book's and the web study's
# browser tests; npm for MathJax, MuJoCo's WebAssembly bindings and three.js. ffmpeg comes from the
# imageio-ffmpeg wheel.
sysdeps:
	@missing=""; \
	ldconfig -p | grep -q 'libOSMesa\.so' || missing="$$missing libosmesa6"; \
	ldconfig -p | grep -q 'libGLX_mesa\.so' || missing="$$missing libglx-mesa0 libgl1-mesa-dri"; \
	command -v Xvfb >/dev/null || missing="$$missing xvfb"; \
	command -v xauth >/dev/null || missing="$$missing xauth"; \
	command -v chromium >/dev/null || missing="$$missing chromium"; \
	command -v chromedriver >/dev/null || missing="$$missing chromium-driver"; \
	command -v npm >/dev/null || missing="$$missing npm"; \
	if [ -n "$$missing" ]; then \
	  echo "installing$$missing (off-screen rendering, the viewer under a virtual display, the book's browser test)"; \
	  $(SUDO) apt-get update -qq; \
	  DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing >/dev/null; \
	fi

ROBOTS := planar5 panda
# Executed notebooks are the pipeline's stamps: never delete them as "intermediate" files.
.SECONDARY:

FIGURE_NBS := 04_fixed_expertise 05_changing_goals 06_learning_users 07_new_goals 08_claims_robustness 09_convergence
# The paper-scale build and the QUICK one record their wall times in benchmarks/results.json
# (figures_s, figures_s.quick) from this invocation's timings.jsonl, then the READMEs' wall times
# from it (lasa.pipeline.timings); a run in which Make skipped up-to-date notebooks records nothing.
# Then each executed notebook, cleaned and light, becomes a page to read in $(FIGURES_DIR)/notebooks
# (lasa.pipeline.pages: a second or two).
TIMED_PART := $(if $(filter build,$(BUILD)),paper,$(if $(filter build/quick,$(BUILD)),quick))
FIGURES_DIR := $(if $(filter build,$(BUILD)),figures,$(BUILD)/figures)
figures: setup
	@rm -f $(BUILD)/timings.jsonl
	@$(BIN)/python -m lasa.runtime --out $(FIGURES_DIR)/kernels.json
	@$(MAKE) --no-print-directory -j$(JOBS) notebooks
ifeq ($(BUILD),build)
	@$(BIN)/python -m lasa.evidence.claims README.md figures/claims.csv
else
	@$(BIN)/python -m lasa.evidence.claims $(FIGURES_DIR)/claims.csv
endif
	@$(BIN)/python -m lasa.pipeline.pages --notebooks $(EXEC) --figures $(FIGURES_DIR)
ifneq ($(TIMED_PART),)
	@$(BIN)/python -m lasa.pipeline.timings $(BUILD)/timings.jsonl --part $(TIMED_PART) \
	  --command "make figures$(if $(filter quick,$(TIMED_PART)), QUICK=1)" --expect $(RUNS)
endif
	@echo "figures written by $(CONFIG) (executed notebooks in $(EXEC); wall times in $(BUILD)/timings.jsonl)"

# The eating study (Sec. VI) runs on the Panda only: its own chain, beside the robots'.
STUDY_NBS := 10_eating_task 11_eating_study
# The study chain is the longest (10 then 11, which also use two worker processes each; measured per
# notebook: benchmarks/results.json, figures_s), and it reads no other notebook's output: it runs in
# a sub-make of its own, one notebook at a time, beside the robots' chains (JOBS - 1 slots), so 11
# starts the moment 10 ends. In one shared job queue the slot 10 freed went to a robot's notebook
# first, and 11 waited for the next one (measured: 51 s). The robots' costliest notebooks go first:
# each robot's 07 (sim4, the longest of the sims), then the rest, Panda first.
FIRST_NBS := $(foreach r,panda planar5,$(EXEC)/07_new_goals-$(r).ipynb)
ROBOT_JOBS := $(shell j=$$(( $(JOBS) - 1 )); echo $$(( j > 0 ? j : 1 )))
notebooks:
	@$(MAKE) --no-print-directory -j1 study-notebooks & study=$$!; robots=0; \
	$(MAKE) --no-print-directory -j$(ROBOT_JOBS) robot-notebooks || robots=$$?; \
	study_rc=0; wait $$study || study_rc=$$?; exit $$(( robots || study_rc ))
study-notebooks: $(foreach n,$(STUDY_NBS),$(EXEC)/$(n).ipynb)
robot-notebooks: $(FIRST_NBS) $(foreach r,panda planar5,$(foreach n,$(FIGURE_NBS),$(EXEC)/$(n)-$(r).ipynb))
# Every notebook run of a whole `make figures`, as lasa.pipeline.execute names them in timings.jsonl.
RUNS := $(STUDY_NBS) $(foreach r,$(ROBOTS),$(foreach n,01_demonstrations 02_decoder_training 03_entropy_ablation $(FIGURE_NBS),$(n)-$(r)))

# The robots' chains run side by side. Notebooks that share a figure merge their rows
# and redraw it under a lock (lasa.base.io.locked), and the merged rows are ordered by robot,
# so the files come out the same whichever robot finishes first.

# One executed copy per (notebook, robot); `$*` is the robot.
$(EXEC)/01_demonstrations-%.ipynb: notebooks/01_demonstrations.ipynb $(NB_SRC_01_demonstrations) $(CONFIG) | setup
	$(RUN) --robot $*

$(EXEC)/02_decoder_training-%.ipynb: notebooks/02_decoder_training.ipynb $(EXEC)/01_demonstrations-%.ipynb $(NB_SRC_02_decoder_training) $(CONFIG) | setup
	$(RUN) --robot $*

$(EXEC)/03_entropy_ablation-%.ipynb: notebooks/03_entropy_ablation.ipynb $(EXEC)/02_decoder_training-%.ipynb $(NB_SRC_03_entropy_ablation) $(CONFIG) | setup
	$(RUN) --robot $*

# The sweeps read notebook 03's pair of decoders: the lambda = 0 control and the entropy one.
$(EXEC)/04_fixed_expertise-%.ipynb: notebooks/04_fixed_expertise.ipynb $(EXEC)/03_entropy_ablation-%.ipynb $(NB_SRC_04_fixed_expertise) $(CONFIG) | setup
	$(RUN) --robot $*

$(EXEC)/05_changing_goals-%.ipynb: notebooks/05_changing_goals.ipynb $(EXEC)/03_entropy_ablation-%.ipynb $(NB_SRC_05_changing_goals) $(CONFIG) | setup
	$(RUN) --robot $*

$(EXEC)/06_learning_users-%.ipynb: notebooks/06_learning_users.ipynb $(EXEC)/03_entropy_ablation-%.ipynb $(NB_SRC_06_learning_users) $(CONFIG) | setup
	$(RUN) --robot $*

# New goals read the base decoder only (no retraining: that is the point of Sec. IV-C).
$(EXEC)/07_new_goals-%.ipynb: notebooks/07_new_goals.ipynb $(EXEC)/02_decoder_training-%.ipynb $(NB_SRC_07_new_goals) $(CONFIG) | setup
	$(RUN) --robot $*

# The verdict map re-runs sims 1-3 over a grid of settings with notebook 03's decoders; its
# default and members' cells are the first look of notebooks 04-06 (their CSVs), not run again.
# Its cells go through joblib (a Dask cluster if LASA_SCHEDULER=tcp://... is set).
$(EXEC)/08_claims_robustness-%.ipynb: notebooks/08_claims_robustness.ipynb $(EXEC)/04_fixed_expertise-%.ipynb $(EXEC)/05_changing_goals-%.ipynb $(EXEC)/06_learning_users-%.ipynb $(NB_SRC_08_claims_robustness) $(CONFIG) | setup
	$(RUN) --robot $*

# Sec. IV-A's ball along LA+SA rollouts of the lambda = 0 control decoder.
$(EXEC)/09_convergence-%.ipynb: notebooks/09_convergence.ipynb $(EXEC)/03_entropy_ablation-%.ipynb $(NB_SRC_09_convergence) $(CONFIG) | setup
	$(RUN) --robot $*

# The eating task: scene, demonstrations and the 2-D decoder readings; then the simulated study.
# The property figure holds the cup decoders too (notebook 02's), whichever publishes first: its
# CSV's rows are ordered by source and the figure is drawn from the file, so 10 starts at once.
$(EXEC)/10_eating_task.ipynb: notebooks/10_eating_task.ipynb $(NB_SRC_10_eating_task) $(CONFIG) | setup
	$(RUN)

$(EXEC)/11_eating_study.ipynb: notebooks/11_eating_study.ipynb $(EXEC)/10_eating_task.ipynb $(NB_SRC_11_eating_study) $(CONFIG) | setup
	$(RUN)

# Did this machine reproduce the committed figures? The whole pipeline, fresh, into its own folder
# (figures/ and README.md untouched: the claims/README sync runs only when BUILD is build), then
# lasa.pipeline.verify compares the two figures folders and fails if any claim's verdict differs.
VERIFY_OUT := build/verify
verify: setup
	@if [ "$(QUICK)$(LARGE)" != "" ]; then echo "error: make verify compares a paper-scale run with figures/; drop QUICK/LARGE"; exit 2; fi
	@$(MAKE) --no-print-directory figures OUT=$(VERIFY_OUT)
	$(BIN)/python -m lasa.pipeline.verify figures $(VERIFY_OUT)/figures

# mypy in two worker processes: on a fresh clone (no cache) 19 s instead of 30 s on one core.
lint: setup
	$(BIN)/ruff check lasa tests benchmarks
	$(BIN)/ruff format --check lasa tests benchmarks
	$(BIN)/mypy --num-workers 2 lasa
	$(BIN)/lint-imports --no-cache

# The tests in TEST_JOBS processes (pytest-xdist), a test file per process at a time: the QUICK
# notebook pipeline (about 6 of the suite's 11 minutes alone) runs beside the other files. Many
# tests wait on real time (a Franka's 10 Hz sessions in franky-sim, browsers, kernels starting) as
# much as they compute, so three processes keep 2 cores busier than two (measured: pytest 5:33 with
# 3, 5:47 and 5:51 with 2). TEST_JOBS=0 runs them all in this process.
TEST_JOBS ?= 3
# lasa's bytecode is written first: the suite starts Python processes by the hundred (notebook kernels,
# CLIs, servers), and under PYTHONDONTWRITEBYTECODE each one would compile the package again.
test: setup lint
	$(BIN)/python -m compileall -q lasa
	$(BIN)/python -m pytest -q -n $(TEST_JOBS) --dist loadfile

# Benchmarks (not timed tests): control-step latency, sweep throughput, training, the
# pipeline's wall time (a fresh paper-scale and QUICK run under build/bench).
bench: setup
	$(BIN)/python benchmarks/bench.py --out benchmarks

# A browsable book of the executed notebooks of the last `make figures` (Jupyter Book, offline).
book: setup
	$(BIN)/python -m lasa.pipeline.book --notebooks $(EXEC) --figures $(if $(filter build,$(BUILD)),figures,$(BUILD)/figures) --out $(BUILD)/book

# Drive the robot yourself in MuJoCo's viewer (a gamepad, or the keyboard): after make figures.
#   make teleop ARGS="--task Dessert --condition LA+SA --participant p01"
teleop: setup
	MUJOCO_GL=glfw $(BIN)/python -m lasa.live.teleop run $(ARGS)

# The study in participants' browsers: the server runs the control step and logs the sessions.
#   $(BIN)/python -m lasa.live.web schedule --participants 10 --sessions build/sessions   (the links)
#   make study-server ARGS="--port 8000 --sessions build/sessions"
study-server: setup
	$(BIN)/python -m lasa.live.web $(ARGS)

clean:
	rm -rf build

# `make print-VAR`: a variable's value (tests read NB_SRC_<notebook> with it)
print-%:
	@echo $($*)
