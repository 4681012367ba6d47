# Two commands do all set-up on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
DEMO_ARGS ?=

.PHONY: demo test bench docs install clean cc-tools figures fuzz prove

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test,docs,sweep]"
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/switchobs demo $(DEMO_ARGS)

# The C tools that check the generated C (tests/test_codegen_hygiene.py, test_codegen_target.py, ...): clang next
# to gcc, cppcheck (MISRA addon), the Arm cross compiler with newlib, qemu-system-arm (processor in the loop) and
# frama-c.  Missing ones are installed in one apt-get call when root with apt-get; otherwise (or if that fails)
# each missing tool is named loudly and the tests that need it skip, saying so.
CC_TOOLS := clang:clang cppcheck:cppcheck arm-none-eabi-gcc:gcc-arm-none-eabi newlib:libnewlib-arm-none-eabi \
	qemu-system-arm:qemu-system-arm frama-c:frama-c-base clang-tidy:clang-tidy
cc-tools:
	@missing=""; for pair in $(CC_TOOLS); do tool=$${pair%%:*}; pkg=$${pair#*:}; \
	  if [ "$$tool" = newlib ]; then \
	    [ -f "$$(arm-none-eabi-gcc -print-file-name=libc.a 2>/dev/null)" ] || missing="$$missing $$pkg"; \
	  else command -v $$tool >/dev/null 2>&1 || missing="$$missing $$pkg"; fi; done; \
	if [ -n "$$missing" ] && [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	  echo "installing$$missing (they check the generated C)"; \
	  export DEBIAN_FRONTEND=noninteractive; \
	  apt-get install -y -q $$missing >/dev/null 2>&1 || \
	    { apt-get update -q >/dev/null && apt-get install -y -q $$missing >/dev/null; } || true; \
	fi; \
	for pair in $(CC_TOOLS); do tool=$${pair%%:*}; pkg=$${pair#*:}; \
	  if [ "$$tool" = newlib ]; then [ -f "$$(arm-none-eabi-gcc -print-file-name=libc.a 2>/dev/null)" ] && continue; \
	  else command -v $$tool >/dev/null 2>&1 && continue; fi; \
	  echo "!!! $$pkg is missing and could not be installed (needs root and apt-get): the tests that need $$tool are SKIPPED !!!"; \
	done

test: $(STAMP) cc-tools
	$(PY) -m pytest -n 2 -q

# The fuzzing suites with many more examples than `make test` runs (random, not derandomised): model files,
# certificates and sweep spec files (tests/test_fuzz_inputs.py, test_errors.py), CLI option values of encoder,
# simulate and sweep (tests/test_fuzz_options.py), and libFuzzer on the generated C API for FUZZ_C_SECONDS per
# observer (tests/test_codegen_fuzz.py; 10 s in make test).
FUZZ_EXAMPLES ?= 300
FUZZ_C_SECONDS ?= 300
fuzz: $(STAMP) cc-tools
	SWITCHOBS_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) SWITCHOBS_FUZZ_C_SECONDS=$(FUZZ_C_SECONDS) $(PY) -m pytest -q -p no:cacheprovider tests/test_fuzz_inputs.py tests/test_errors.py tests/test_fuzz_options.py tests/test_codegen_fuzz.py

# The proof of no run-time errors (Frama-C EVA, tests/test_codegen_proof.py) of every observer, method and real
# type, sub-stepped rk4 too (make test proves a subset, and the table of docs/codegen.md "On the target").
prove: $(STAMP) cc-tools
	SWITCHOBS_PROVE_ALL=1 nice $(PY) -m pytest -q -p no:cacheprovider tests/test_codegen_proof.py

# Every benchmark script (benchmarks/_*.py are helpers), then their result tables into the docs pages.
# BENCH_QUICK=1: every script with --quick (smaller sizes, fewer runs), printed only: nothing is published.
BENCH_QUICK ?=
bench: $(STAMP)
	@$(PY) -m pip install --quiet -e ".[bench]" || echo "!!! could not install numba: codegen_step.py will say that its numba column is missing !!!"
	@for f in benchmarks/[!_]*.py; do \
	  [ "$$f" = benchmarks/render_docs.py ] && continue; \
	  echo "== $$f"; t0=$$(date +%s); $(PY) $$f $(if $(BENCH_QUICK),--quick) || exit 1; \
	  echo "== $$f: $$(( $$(date +%s) - t0 )) s wall"; done
	$(if $(BENCH_QUICK),@echo "BENCH_QUICK: smoke run - the results files and docs are unchanged",$(PY) benchmarks/render_docs.py)

docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --site-dir site

# The figures of the docs drawn by commands (tests/test_figures.py runs these lines into a temporary directory).
figures: $(STAMP)
	$(VENV)/bin/switchobs certify abs-adaptive2 --gains-plus 8,-2/25 --gains-minus -3,-1/25 --plot docs/figures/certify_abs_adaptive2.png
	$(VENV)/bin/switchobs classify "[[-0.1,-1],[2,-0.1]]" "[[-0.1,-2],[1,-0.1]]" --plot docs/figures/classify_case_iv.png
	$(VENV)/bin/switchobs simulate hoang-fig4 --plot docs/abs_hoang_fig4.png
	$(VENV)/bin/switchobs simulate aguado-sec36 --plot docs/abs_sec36.png
	$(VENV)/bin/switchobs simulate table41 --plot docs/abs_table41.png
	$(VENV)/bin/switchobs simulate --road wet-asphalt --speed-kmh 120 --controller two-phase --observer adaptive --plot docs/abs_two_phase_wet.png
	$(VENV)/bin/switchobs encoder --profile varying --plot docs/encoders_varying.png

clean:
	rm -rf $(VENV) site out build *.egg-info src/*.egg-info
