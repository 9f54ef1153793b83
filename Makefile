# The two commands: `make demo` and `make test`. Both set up .venv on first use.
SHELL := /bin/bash
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.treebook-installed
FLAGS ?=

.PHONY: install demo test test-slow readme book export clean lint elm species

$(PY):
	python3 -m venv $(VENV)

# The system library open3d's wheel needs (libusb-1.0), installed by apt-get only when missing; a warning if it cannot be.
define SYSTEM_DEPS
ldconfig -p 2>/dev/null | grep -q 'libusb-1.0.so.0' && exit 0; \
echo "installing system packages: libusb-1.0-0"; \
command -v apt-get >/dev/null || { echo "warning: no apt-get; install libusb-1.0-0 with your package manager (open3d needs it)" >&2; exit 0; }; \
sudo=""; [ "$$(id -u)" -ne 0 ] && sudo="sudo"; \
$$sudo apt-get install -y -q libusb-1.0-0 >/dev/null 2>&1 \
  || { $$sudo apt-get update -q >/dev/null 2>&1 && $$sudo apt-get install -y -q libusb-1.0-0 >/dev/null; } \
  || echo "warning: could not install libusb-1.0-0; open3d will not import" >&2; exit 0
endef

# torch==2.13.0 first: it is the CPU build on local disk; the package's own torch range then adds nothing.
$(STAMP): settings.ini setup.py | $(PY)
	@$(SYSTEM_DEPS)
	$(PY) -m pip install -q torch==2.13.0
	$(PY) -m pip install -q -e ".[dev]"
	@touch $(STAMP)

# dash (which open3d pulls in) leaves a JupyterLab source extension that only a `jupyter lab build` with node could
# include, so every start of `jupyter lab` asks "Build Recommended". treebook never uses it: remove it.
install: $(STAMP)
	@rm -f $(VENV)/share/jupyter/lab/extensions/dash-jupyterlab.tgz

demo: install
	$(VENV)/bin/treebook demo

test: install
	$(PY) scripts/run_tests.py

test-slow: install
	$(PY) scripts/run_tests.py --flags slow

# README.md from nbs/index.ipynb, executed, hidden cells removed (quarto is not available here).
readme: install
	$(PY) scripts/make_readme.py

# Run chapters as nbdev_test does and keep their outputs (figures, show_doc tables) in the notebooks, so that a reader
# sees them without running anything: `make book` (every chapter) or `make book NBS="nbs/00_tree.ipynb ..."`
# (`NBS="--slow nbs/05_train.ipynb"` runs the cells flagged slow too).
NBS ?= $(wildcard nbs/*.ipynb)
book: install
	$(PY) scripts/run_book.py $(NBS)
	$(VENV)/bin/nbdev_clean

# What to run before a commit: notebooks are the source.
export: install
	$(VENV)/bin/nbdev_clean
	$(VENV)/bin/nbdev_export

# The shipped `elm` model (resumable: run again after a kill, each training call stops after 100 minutes): 10,000
# procedural elms (<= 200 branches; 9,000 train / 1,000 test by the dataset's split), DFS / Full training (dim 128,
# 8 layers, 4 heads, batch 16, 4,000 steps), then the card's evaluation of best.pt and the copy into the package.
RUN ?= runs/elm2
elm:
	$(PY) -c "from treebook.datasets import generate_dataset; generate_dataset('elm', 10000, 'data/elm', max_branches=200, workers=2, seed=0)"
	$(PY) -m treebook.train --data data/elm --out $(RUN) --order dfs --arch full --dim 128 --depth 8 --heads 4 \
	    --batch-size 16 --steps 4000 --lr 2e-3 --warmup 100 --val-every 500 --val-trees 128 --ckpt-every 50 \
	    --time-limit 6000 --threads 2 --seed 0 --quiet $$([ -f $(RUN)/last.pt ] && echo --resume)
	$(PY) scripts/ship_elm.py --run $(RUN) --data data/elm --temperature 1.0 --top-p 1.0

# Every other species' model (chapter 05a), made as `make elm` makes the elm's and as resumable: `make species
# SPECIES=spruce` grows data/spruce (TREES trees up to the preset's max_branches), trains runs/spruce by the elm's
# recipe in calls of 100 minutes (a call that ends before the schedule does exits with status 3: run the same command
# again), then evaluates it and ships spruce.{pt,tok.json,md}, results/spruce_eval.json and results/spruce_loss.png.
# TRAIN_FLAGS go to the training (e.g. --window 128), SHIP_FLAGS to the evaluation (e.g. --n-samples 500 --n-test
# 500: the held-out trees it is scored against). A run from `scripts/gpu.sh species`: `$(PY) -m
# treebook.species_runs unpack OUT/spruce.tar runs/spruce-gpu`, then `make species SPECIES=spruce
# SPECIES_RUN=runs/spruce-gpu TREES=...` (TREES as on the GPU): the run is evaluated and shipped as it is.
SPECIES ?= spruce
TREES ?= 10000
SPECIES_RUN ?= runs/$(SPECIES)
TRAIN_FLAGS ?=
SHIP_FLAGS ?=
species:
	$(PY) -m treebook.species_runs data $(SPECIES) --trees $(TREES) --workers 2
	$(PY) -m treebook.species_runs train $(SPECIES) --run $(SPECIES_RUN) --threads 2 --time-limit 6000 --quiet $(TRAIN_FLAGS)
	$(PY) scripts/ship_elm.py --species $(SPECIES) --run $(SPECIES_RUN) --temperature 1.0 --top-p 1.0 $(SHIP_FLAGS) \
	    --recipe "make species SPECIES=$(SPECIES)$(if $(filter 10000,$(TREES)),, TREES=$(TREES))$(if \
	    $(filter runs/$(SPECIES),$(SPECIES_RUN)),, SPECIES_RUN=$(SPECIES_RUN))$(if $(strip $(TRAIN_FLAGS)),\
	    TRAIN_FLAGS='$(strip $(TRAIN_FLAGS))')$(if $(strip $(SHIP_FLAGS)), SHIP_FLAGS='$(strip $(SHIP_FLAGS))')"

clean:
	rm -rf build dist *.egg-info treebook-demo _proc
