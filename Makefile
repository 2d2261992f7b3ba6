# coin: two commands set everything up on a fresh machine:
#   make demo   installs into .venv, runs a small basin sweep and one simulation, writes out/
#   make test   installs into .venv and runs the test suite
#   make test-oldest   installs the oldest versions pyproject.toml allows (constraints/oldest.txt)
#               into .venv-oldest and runs the tests of kernels, stores, the CLI and the API there
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
COIN   := $(BIN)/coin
OUT    ?= out

.PHONY: install install-oldest demo test test-oldest bench lint docs docs-build clean

$(BIN)/activate:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip

# An editable install leaves the package uncompiled; where PYTHONDONTWRITEBYTECODE is set (as in
# some containers) Python would then compile every module from source on each start (0.1 s).
$(VENV)/.installed: pyproject.toml $(BIN)/activate
	$(BIN)/pip install --quiet -e ".[test,docs,notebook]"
	$(BIN)/python -m compileall -q coincli
	touch $@

# The kernels compile as a step of their own (once per version and machine, about a minute,
# with a live clock), not silently inside the first command that needs them.
install: $(VENV)/.installed
	$(COIN) compile

demo: install
	mkdir -p $(OUT)
	$(COIN) stability
	$(COIN) simulate --vy 1.197 --vphi 3.508 --rrd $(OUT)/fig2.rrd
	$(COIN) basin $(OUT)/basin.zarr --res 128
	$(COIN) basin render $(OUT)/basin.zarr -o $(OUT)/basin.png
	$(COIN) basin stats $(OUT)/basin.zarr
	@echo "outputs in $(OUT)/: fig2.rrd (open with: $(BIN)/rerun $(OUT)/fig2.rrd), basin.zarr, basin.png"
	@echo "to type coin and rerun as the hints print them: source $(BIN)/activate"

test: install
	$(BIN)/python -m pytest -n 2 -q

# The oldest environment: each lower bound of pyproject.toml is a version these tests pass on
# (kernels, stores, the CLI and the API: a third of the suite's time; the one long resume test
# of the fractions store, 45 s, runs on the newest versions only).
OLDEST      ?= .venv-oldest
OLDEST_TESTS = tests/test_api.py tests/test_store.py tests/test_store_metadata.py \
               tests/test_basin.py tests/test_cli.py tests/test_inputs.py \
               tests/test_engines.py tests/test_jit_cache.py tests/test_threads.py \
               tests/test_fractions.py tests/test_export.py --deselect \
               tests/test_fractions.py::test_an_interrupted_store_resumes_to_the_same_store_and_results

$(OLDEST)/.installed: pyproject.toml constraints/oldest.txt
	$(PYTHON) -m venv $(OLDEST)
	$(OLDEST)/bin/pip install --quiet --upgrade pip
	$(OLDEST)/bin/pip install --quiet -c constraints/oldest.txt -e ".[test]"
	$(OLDEST)/bin/python -m compileall -q coincli
	touch $@

install-oldest: $(OLDEST)/.installed

test-oldest: install-oldest
	$(OLDEST)/bin/python -m pytest -n 2 -q $(OLDEST_TESTS)

bench: install
	$(COIN) bench

# The documentation site, into site/ (CI runs this: every warning is an error).
docs-build: install
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --quiet

# Regenerate every table and picture under docs/, then run the pages' commands marked
# <!-- long --> (tests/test_docs.py, which also checks that every picture was made by this
# version): some three hours on 2 idle cores. The pictures and their commands are listed in one
# place, benchmarks/docs_pictures.py (`--list` shows each with the version that made it); the
# screenshots of Rerun's viewer need Debian's xvfb and mesa-vulkan-drivers.
docs: install
	$(BIN)/python benchmarks/docs_tables.py
	$(BIN)/python benchmarks/docs_notebook.py
	$(BIN)/python benchmarks/docs_pictures.py --make --out $(OUT)
	COIN_DOCS_LONG=1 $(BIN)/python -m pytest -q -n 0 tests/test_docs.py

lint: install
	$(BIN)/ruff check coincli tests

clean:
	rm -rf $(OUT) .pytest_cache
