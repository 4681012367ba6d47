"""A libFuzzer harness of the generated C API, with the contract of docs/codegen.md as its oracle.

:func:`fuzz_harness` writes ``LLVMFuzzerTestOneInput`` for one generated
observer.  Each input is read as a sequence of calls of the public functions
(``_step``, ``_run``, ``_run_dt``, ``_status_message`` and ``_original`` when
present) on reals decoded from the bytes: raw bit patterns (NaN, infinities,
subnormals, anything), values of a table of edge cases, or values near the
nominal operating point (the middle of a declared range, the default
parameters), so that the fuzzer reaches both the refusals and the computing
paths.  After every call the harness checks, and aborts on a violation:

* the status is one of :class:`switchobs.spec.StepStatus`;
* a refused step leaves ``xhat`` byte for byte as it was;
* status OK means a finite state (and one within its declared ranges);
* ``_run`` and ``_run_dt`` equal a loop of ``_step`` on the same rows: the same status, the same first
  failing row, the same state bit for bit, the trajectory rows of the successful steps and no other row
  written; with no row the zero-step contract (``_run``: ``BAD_DT`` for a bad ``dt``, also one outside its
  declared range, then both ``NONFINITE_STATE`` for a non-finite ``xhat`` and ``STATE_RANGE`` for one outside
  its declared ranges, else OK), ``xhat`` unchanged;
* ``_status_message`` returns a non-NULL text for every code, the documented one for each status.

Compiled with ``clang -fsanitize=fuzzer,address,undefined`` every memory error
and undefined behaviour is a crash too (``tests/test_codegen_fuzz.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..spec import STATUS_TEXT, StepStatus
from ._emit import float_literal

if TYPE_CHECKING:
    from ._observer import GeneratedObserver

__all__ = ["fuzz_harness", "FUZZ_ROWS"]

#: Most rows of one fuzzed ``_run`` / ``_run_dt`` call.
FUZZ_ROWS = 4

#: Edge values a decoded real may take (the table mode of the decoder).
_EDGES = ("0.0", "-0.0", "1.0", "-1.0", "1e-3", "0.5", "2.0", "1e-300", "-1e-300", "1e300", "-1e300", "1e30",
          "-1e30", "1e6", "-1e6", "INFINITY", "-INFINITY", "NAN")


def fuzz_harness(gen: GeneratedObserver) -> str:
    """The C text of a libFuzzer harness of ``gen``'s API (include ``<prefix>.h``, link ``<prefix>.c``)."""
    p, P, real = gen.prefix, gen.prefix.upper(), gen.real
    nominal_x = [_middle(gen, n, 0.1) for n in gen.state_names]
    nominal_s = [_middle(gen, n, 1.0) for n in gen.signal_names]
    nominal_dt = _middle(gen, "dt", 1e-3)
    edges = ", ".join(f"({real}){e}" for e in _EDGES)
    texts = "\n".join(f'    if (strcmp({p}_status_message({int(s)}), "{STATUS_TEXT[s]}") != 0) '
                      f'fail("status_message({int(s)})");' for s in StepStatus)
    ranged = [(i, gen.ranges[n]) for i, n in enumerate(gen.state_names) if n in gen.ranges]
    in_range = "".join(f" && x[{i}] >= {float_literal(lo, real)} && x[{i}] <= {float_literal(hi, real)}"
                       for i, (lo, hi) in ranged)
    dt_ok = (f"dt >= {float_literal(gen.ranges['dt'][0], real)} && dt <= {float_literal(gen.ranges['dt'][1], real)}"
             if "dt" in gen.ranges else f"dt > ({real})0 && isfinite(dt)")
    original = "" if not gen.original_names else f"""
    case 4: {{ /* _original: status in the set, x untouched on failure, finite on OK */
        {real} x[{P}_NX], sig[{P}_NS], out[{P}_NO], copy[{P}_NO];
        int32_t i, st;
        for (i = 0; i < {P}_NX; ++i) x[i] = any_real(r, nominal_x[i]);
        for (i = 0; i < {P}_NS; ++i) sig[i] = any_real(r, nominal_s[i]);
        for (i = 0; i < {P}_NO; ++i) out[i] = copy[i] = ({real})i;
        st = {p}_original(x, sig, take_byte(r) & 1u ? params_of(r, par) : NULL, out);
        check_status(st, "original");
        if (st != 0 && memcmp(out, copy, sizeof out) != 0) fail("original wrote x on failure");
        for (i = 0; st == 0 && i < {P}_NO; ++i) if (!isfinite(out[i])) fail("original OK with a non-finite x");
        break;
    }}"""
    return f"""/* libFuzzer harness of {p} (switchobs.codegen.fuzz_harness): every public function, the API contract
 * as the oracle; a violation aborts with its name.  Build:
 *   clang -std=c99 -g -O1 -fsanitize=fuzzer,address,undefined {p}_fuzz.c {p}.c -lm */
#include "{p}.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define ROWS {FUZZ_ROWS}

typedef struct {{ const uint8_t *data; size_t size; }} reader;

static void fail(const char *what)
{{
    fprintf(stderr, "{p} contract violated: %s\\n", what);
    abort();
}}

static uint8_t take_byte(reader *r)
{{
    uint8_t b = 0;
    if (r->size > 0) {{ b = r->data[0]; r->data++; r->size--; }}
    return b;
}}

static const {real} edges[] = {{{edges}}};

/* One real: a raw bit pattern, an edge value, or the nominal value scaled by a factor near 1. */
static {real} any_real(reader *r, {real} nominal)
{{
    uint8_t mode = take_byte(r), b = take_byte(r);
    {real} v;
    unsigned char raw[sizeof v];
    size_t i;
    switch (mode % 4u) {{
    case 0:
        for (i = 0; i < sizeof v; ++i) raw[i] = take_byte(r);
        memcpy(&v, raw, sizeof v);
        return v;
    case 1:
        return edges[b % (sizeof edges / sizeof edges[0])];
    case 2:
        return nominal * ({real})(b - 128) / ({real})32;
    default:
        return nominal * (({real})1 + ({real})(b - 128) / ({real})1024);
    }}
}}

static const {real} nominal_x[{P}_NX] = {{{", ".join(float_literal(v, real) for v in nominal_x)}}};
static const {real} nominal_s[{P}_NS] = {{{", ".join(float_literal(v, real) for v in nominal_s)}}};

static const {real} *params_of(reader *r, {real} *par)
{{
    int32_t i;
    for (i = 0; i < {P}_NP; ++i) {{
        par[i] = take_byte(r) < 224u ? {p}_default_params[i] : any_real(r, {p}_default_params[i]);
    }}
    return par;
}}

static void check_status(int32_t st, const char *where)
{{
    if (st < 0 || st > {max(int(s) for s in StepStatus)}) fail(where);
}}

static int finite_state(const {real} *x)
{{
    int32_t i;
    for (i = 0; i < {P}_NX; ++i) if (!isfinite(x[i])) return 0;
    return 1{in_range};
}}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{{
    reader rd = {{data, size}}, *r = &rd;
    {real} par[{P}_NP];
{texts}
    if ({p}_status_message(-1) == NULL || {p}_status_message(2147483647) == NULL) fail("status_message NULL");
    while (r->size > 0) {{
        switch (take_byte(r) % {5 if gen.original_names else 4}u) {{
        case 0: {{ /* _step: status in the set; refused: xhat untouched; OK: finite (and in range) */
            {real} x[{P}_NX], copy[{P}_NX], sig[{P}_NS], dt;
            const {real} *pp;
            int32_t i, st;
            for (i = 0; i < {P}_NX; ++i) x[i] = any_real(r, nominal_x[i]);
            for (i = 0; i < {P}_NS; ++i) sig[i] = any_real(r, nominal_s[i]);
            dt = any_real(r, {float_literal(nominal_dt, real)});
            pp = take_byte(r) & 1u ? params_of(r, par) : NULL;
            memcpy(copy, x, sizeof x);
            i = take_byte(r);  /* now and then a NULL pointer: BAD_ARGUMENT */
            st = {p}_step(i == 255 ? NULL : x, i == 254 ? NULL : sig, pp, dt);
            if ((i == 255 || i == 254) && st != {int(StepStatus.BAD_ARGUMENT)}) fail("a NULL pointer is not BAD_ARGUMENT");
            check_status(st, "step status");
            if (st != 0 && memcmp(x, copy, sizeof x) != 0) fail("a refused step changed xhat");
            if (st == 0 && !finite_state(x)) fail("step OK with a non-finite or out-of-range state");
            break;
        }}
        case 1:
        case 2: {{ /* _run / _run_dt against a loop of _step on the same rows */
            {real} x[{P}_NX], y[{P}_NX], sig[ROWS * {P}_NS], dts[ROWS], traj[ROWS * {P}_NX],
                   mark[ROWS * {P}_NX], dt;
            const {real} *pp;
            int32_t i, k, n, st, st_loop = 0, failed = -1, per_row = (take_byte(r) & 1u);
            for (i = 0; i < {P}_NX; ++i) x[i] = any_real(r, nominal_x[i]);
            n = (int32_t)(take_byte(r) % (ROWS + 2)) - 1;  /* -1 .. ROWS */
            for (i = 0; i < ROWS * {P}_NS; ++i) sig[i] = any_real(r, nominal_s[i % {P}_NS]);
            dt = any_real(r, {float_literal(nominal_dt, real)});
            for (k = 0; k < ROWS; ++k) dts[k] = take_byte(r) < 192u ? dt : any_real(r, dt);
            pp = take_byte(r) & 1u ? params_of(r, par) : NULL;
            for (i = 0; i < ROWS * {P}_NX; ++i) traj[i] = mark[i] = ({real})(i + 7);
            memcpy(y, x, sizeof x);
            st = per_row ? {p}_run_dt(x, sig, n, pp, dts, traj) : {p}_run(x, sig, n, pp, dt, traj);
            check_status(st, "run status");
            if (n < 0) {{
                if (st != {int(StepStatus.BAD_ARGUMENT)}) fail("run with n_steps < 0 is not BAD_ARGUMENT");
                if (memcmp(x, y, sizeof x) != 0) fail("run with n_steps < 0 changed xhat");
                break;
            }}
            if (n == 0) {{ /* no row: _run checks dt (BAD_DT), then both check xhat (NONFINITE_STATE, STATE_RANGE) */
                int32_t want = 0;
                if (!per_row && !({dt_ok})) want = {int(StepStatus.BAD_DT)};
                else for (i = 0; i < {P}_NX; ++i) if (!isfinite(y[i])) want = {int(StepStatus.NONFINITE_STATE)};
                if (want == 0 && !finite_state(y)) want = {int(StepStatus.STATE_RANGE)};
                if (st != want) fail("run with n_steps = 0 does not keep the zero-step contract");
                if (memcmp(x, y, sizeof x) != 0) fail("run with n_steps = 0 changed xhat");
                break;
            }}
            for (k = 0; k < n; ++k) {{
                st_loop = {p}_step(y, sig + k * {P}_NS, pp, per_row ? dts[k] : dt);
                if (st_loop != 0) {{ failed = k; break; }}
                if (memcmp(traj + k * {P}_NX, y, sizeof y) != 0) fail("run's trajectory row differs from _step");
            }}
            if (st != st_loop) fail("run's status differs from the loop of _step");
            if (memcmp(x, y, sizeof x) != 0) fail("run's state differs from the loop of _step");
            for (k = failed < 0 ? n : failed; k < ROWS; ++k) {{
                if (memcmp(traj + k * {P}_NX, mark + k * {P}_NX, sizeof y) != 0) fail("run wrote a row after the failure");
            }}
            break;
        }}
        case 3: {{ /* _status_message of any code */
            int32_t code = (int32_t)take_byte(r) - 128;
            const char *text = {p}_status_message(code);
            if (text == NULL) fail("status_message NULL");
            if ((code < 0 || code > {max(int(s) for s in StepStatus)}) && strcmp(text, "unknown status code") != 0) {{
                fail("status_message of an unknown code");
            }}
            break;
        }}{original}
        default:
            break;
        }}
    }}
    return 0;
}}
"""


def _middle(gen: GeneratedObserver, name: str, default: float) -> float:
    """The middle of a declared range, else ``default``."""
    if name in gen.ranges:
        lo, hi = gen.ranges[name]
        return 0.5 * (lo + hi)
    return default
