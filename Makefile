# The two commands: `make demo` and `make test`. Both set up .venv on first use.
SHELL := /bin/bash
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.treebook-installed
FLAGS ?=

.PHONY: install demo test test-slow readme book export clean lint

$(PY):
	python3 -m venv $(VENV)

# torch==2.13.0 first: it is the CPU build on local disk; the package's own torch range then adds nothing.
$(STAMP): settings.ini setup.py | $(PY)
	@bash scripts/system_deps.sh
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

clean:
	rm -rf build dist *.egg-info treebook-demo _proc
