# Two commands do all set-up on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
DEMO_ARGS ?=

.PHONY: demo test bench docs install clean cc-tools fuzz

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test,docs]"
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/switchobs demo $(DEMO_ARGS)

# clang checks the generated C next to gcc (tests/test_codegen_hygiene.py): installed when missing and possible.
cc-tools:
	@command -v clang >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing clang (checks the generated C)"; \
	    export DEBIAN_FRONTEND=noninteractive; \
	    apt-get install -y -q clang >/dev/null 2>&1 || \
	      { apt-get update -q >/dev/null && apt-get install -y -q clang >/dev/null; } || \
	      echo "!!! could not install clang: the clang checks of the generated C will be SKIPPED !!!"; \
	  else \
	    echo "!!! clang is missing and cannot be installed here (needs root and apt-get): the clang checks of the generated C will be SKIPPED !!!"; \
	  fi; }

test: $(STAMP) cc-tools
	$(PY) -m pytest -n 2 -q

# The fuzzing suites with many more examples than `make test` runs (random, not derandomised).
FUZZ_EXAMPLES ?= 500
fuzz: $(STAMP)
	SWITCHOBS_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) $(PY) -m pytest -q tests/test_fuzz_options.py

# Every benchmark script (benchmarks/_*.py are helpers), then their result tables into the docs pages.
bench: $(STAMP)
	@$(PY) -m pip install --quiet -e ".[bench]" || echo "!!! could not install numba: codegen_step.py will say that its numba column is missing !!!"
	@for f in benchmarks/[!_]*.py; do \
	  [ "$$f" = benchmarks/render_docs.py ] && continue; \
	  echo "== $$f"; $(PY) $$f || exit 1; done
	$(PY) benchmarks/render_docs.py

docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --site-dir site

clean:
	rm -rf $(VENV) site out build *.egg-info src/*.egg-info
