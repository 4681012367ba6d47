"""README.md for the integrator of a generated observer, with a compilable example program."""

from __future__ import annotations

from .._papers import cite
from ._emit import float_literal
from ._misra import misra_summary
from ._observer import GeneratedObserver, divisor_gaps, proof_command
from ..spec import METHODS, STATUS_TEXT, STEP_METHODS, StepStatus

__all__ = ["readme", "example_program"]

#: The sliding-mode observers of seed 003 (no time scale, no certificate) and the sentence on their gains.
SLIDING_MODE_GAINS = {"super-twisting": "The gains `lam` and `alpha` of seed 003 eq. (9).",
                      "vehicle-speed": "The gain `beta` of seed 003 eq. (15) (Theorem 3: above the bound on |dx3/dt|)."}


def example_program(gen: "GeneratedObserver") -> str:
    """A complete C program that runs the observer on constant signals and checks the status codes.

    It returns 0 when the observer stepped, refused ``dt = 0`` with
    ``BAD_DT`` and left the state untouched, so that it can be compiled and
    run as a test.
    """
    P, p, real = gen.prefix.upper(), gen.prefix, gen.real
    lit = lambda v: float_literal(v, real)  # noqa: E731 - one-line formatter
    rows = []
    for name in gen.signal_names:
        value = 1.0
        if gen.guards:
            for g in gen.guards:
                if g.expr.is_Symbol and g.expr.name == name and g.kind == "negative":
                    value = -1.0
        rows.append(f"    signals[{P}_S_{name.upper()}] = {lit(value)};")
    return "\n".join([
        "#include <stdio.h>",
        f'#include "{p}.h"',
        "",
        "int main(void)",
        "{",
        f"    {real} xhat[{P}_NX] = {{0}};",
        f"    {real} saved[{P}_NX];",
        f"    {real} signals[{P}_NS];",
        f"    {real} params[{P}_NP];",
        "    int i;",
        "    int32_t status;",
        f"    for (i = 0; i < {P}_NP; ++i) params[i] = {p}_default_params[i];",
        *rows,
        f"    status = {p}_step(xhat, signals, params, {lit(1e-3)});",
        f"    if (status != {P}_OK) {{",
        f'        printf("step failed: %s\\n", {p}_status_message(status));',
        "        return 1;",
        "    }",
        f"    for (i = 0; i < {P}_NX; ++i) saved[i] = xhat[i];",
        f"    status = {p}_step(xhat, signals, params, {lit(0.0)});  /* refused: dt <= 0 */",
        f"    if (status != {P}_ERR_BAD_DT) return 2;",
        f"    for (i = 0; i < {P}_NX; ++i) if (xhat[i] < saved[i] || xhat[i] > saved[i]) return 3;",
        f"    for (i = 0; i < {P}_NX; ++i) printf(\"xhat[%d] = %.17g\\n\", i, (double)xhat[i]);",
        "    return 0;",
        "}",
        "",
    ])


def _bound_section(gen: "GeneratedObserver") -> list[str]:
    """The step bound: what it guarantees (a certificate only where one exists), the worst case, the status beyond."""
    P = gen.prefix.upper()
    if gen.h_max is None:
        if gen.kind in SLIDING_MODE_GAINS:
            return []
        return ["## Step bound", "",
                "None: every call takes one step of `dt`, whatever `|s|*dt` is; regenerate with `--h-max` to split",
                "longer steps (see below which methods need it).", ""]
    certified = gen.certificate is not None
    claim = (f"The sampled error dynamics are certified for every step `h = |s|*dt` (rescaled time) up to "
             f"`h_max = {gen.h_max}` ({gen.certificate})." if certified else
             f"Every step `h = |s|*dt` (rescaled time) is kept at or below `h_max = {gen.h_max}`, a bound you "
             "chose: it is NOT a certificate (for rk4 and euler none exists at any bound, see below); it keeps "
             "each mode's step inside the method's stability region when `h_max` is below that bound.")
    return [
        "## Step bound (sub-stepping)", "",
        claim,
        f"`{P}_H_MAX` = `{float_literal(gen.h_max_c, gen.real)}` is `h_max` rounded DOWN to `{gen.real}`, "
        "so the C never steps beyond it.  A call computes `s` once (signals held) and:",
        "",
        f"- `|s|*dt <= {P}_H_MAX`: one step of `dt`, exactly as without a bound;",
        f"- otherwise `n = ceil(|s|*dt / {P}_H_MAX)` sub-steps of `dt/n`, signals held;",
        f"- more than `{P}_MAX_SUBSTEPS` = {gen.max_substeps} sub-steps: `{P}_ERR_SUBSTEP_LIMIT` = "
        f"{int(StepStatus.SUBSTEP_LIMIT)}, `xhat` unchanged.",
        "",
        f"Worst-case time of one call: `{P}_MAX_SUBSTEPS` = {gen.max_substeps} evaluations of the step kernel "
        "(plus the checks).",
        "The bound is for the default gains and parameters: other `params` need their own bound.", ""]


def _ranges_section(gen: "GeneratedObserver") -> list[str]:
    """The declared ranges the step checks and, when every input has one, the proof that relies on them."""
    if not gen.ranges:
        return []
    out = ["## Declared ranges and the proof of no run-time errors", "",
           "The step refuses a value outside its declared range before computing anything: a state (also the "
           f"new state) with `STATE_RANGE` = {int(StepStatus.STATE_RANGE)}, a signal with `SIGNAL_RANGE` = "
           f"{int(StepStatus.SIGNAL_RANGE)}, a parameter with `BAD_PARAM`, `dt` with `BAD_DT`.", "",
           "| name | min | max |", "| --- | ---: | ---: |",
           *[f"| `{n}` | {lo!r} | {hi!r} |" for n, (lo, hi) in gen.ranges.items()], ""]
    if gen.unranged:
        out += [f"No proof driver: {', '.join(f'`{n}`' for n in gen.unranged)} have no declared range.", ""]
    else:
        out += [f"`{gen.prefix}_proof.c` is the Frama-C EVA driver of the proof that no call of the API has a "
                "run-time error for any finite input (`switchobs codegen --prove` runs it and writes "
                f"`{gen.prefix}_proof.md`); in this directory:", "",
                "    " + " ".join(proof_command(gen)), ""]
        gaps = divisor_gaps(gen)
        if gaps:
            out += ["The step refuses a divisor of the model only when it is exactly 0, and the declared ranges do "
                    "not keep these away from 0, so the proof will report their divisions (declare ranges that do):",
                    "", *(f"- `{g}`" for g in gaps), ""]
    return out


def _certificate_section(gen: "GeneratedObserver") -> list[str]:
    """Which step methods keep the design's Lyapunov function decreasing for every dt (docs/codegen.md)."""
    every = [m for m in METHODS if not STEP_METHODS[m].explicit]
    out = ["## Certified step lengths", "",
           "In the rescaled time `tau = ∫|s| dt` one step is a step `h = |s|*dt` of the sampled error dynamics "
           "`e+ = R(h A) e`, and `h` is not under your control (a slow wheel makes `|s|` large).",
           f"Certified for every `dt` ({', '.join(every)}: algebraically stable, `switchobs.certify."
           "discrete_certificate` proves exactly that the design's Lyapunov function decreases at every step of "
           "either mode); "
           f"{' and '.join(m for m in METHODS if STEP_METHODS[m].explicit)}: no quadratic discrete certificate for "
           "any step bound (n >= 3 for rk4, n >= 2 for euler), so bound the step with `--h-max VALUE` "
           "(uncertified) or use `--method radau3`.",
           f"This file: `{gen.method}`" + (f"; {gen.certificate}." if gen.certificate else "."), ""]
    return out


def _original_section(gen: "GeneratedObserver") -> list[str]:
    if not gen.original_names:
        return []
    P, p = gen.prefix.upper(), gen.prefix
    return [f"`{p}_original` writes the estimate in the original coordinates of the system file, "
            f"x = phi^-1(xhat) (`{P}_NO` = {len(gen.original_names)}: "
            + ", ".join(f"`{P}_O_{n.upper()}` = {i} `{n}`" for i, n in enumerate(gen.original_names)) + "), ",
            "with the step's signals row (phi^-1 may use the external signals).  It checks its inputs as the "
            "step does",
            f"and returns `{P}_ERR_NONFINITE_RESULT`, with `x` unchanged, where phi^-1 is undefined.", ""]


def readme(gen: "GeneratedObserver", *, command: str | None) -> str:
    P, p, real = gen.prefix.upper(), gen.prefix, gen.real
    rt = f"{p}_real"
    method = {"rk4": "classic fourth-order Runge-Kutta (RK4)", "euler": "forward Euler"}.get(
        gen.method, STEP_METHODS[gen.method].description)
    kind = cite({"adaptive": "switched adaptive observer of seed 001 eq. (3.4)",
                 "super-twisting": "super-twisting observer of seed 003 eq. (8)-(9)",
                 "vehicle-speed": "sliding-mode observer of the vehicle speed of seed 003 eq. (15)"}.get(
        gen.kind, "switched observer (seed 000 eq. (8)-(9), seed 004)"), ascii=True)
    out = [
        f"# `{p}`: generated C {gen.kind} observer for model `{gen.model_name}`",
        "",
        f"Generated by switchobs with casadi {gen.casadi_version}; do not edit, regenerate"
        + (f" with\n\n```sh\n{command}\n```" if command else "."),
        "",
        f"The {kind} for `{gen.model_name}` ({gen.description}), discretised with {method}, the signals "
        f"held constant over the step (zero-order hold).  Real type: `{real}`.",
        "",
        "```text",
        *gen.equations,
        "```",
        "",
        "## Files and build",
        "",
        f"- `{p}.h`: the API (macros, prototypes); `{p}.c`: the implementation;",
        f"  `{p}_misra.md`: the MISRA C:2012 deviation record.",
        f"- Plain C99, no heap allocation, no global mutable state (re-entrant, thread-safe), libm only:",
        "",
        "```sh",
        f"cc -std=c99 -O2 -c {p}.c   # link with -lm",
        "```",
        "",
        "- Do not compile with `-ffast-math` or `-ffinite-math-only`: they let the compiler assume that no value is",
        "  NaN or infinite and delete the checks that refuse such inputs, so the file refuses them with `#error`.",
        "- With clang, `-DSWITCHOBS_BRANCH_HINTS` marks the refusals unlikely (`__builtin_expect`, a language",
        "  extension, so off by default): clang then inlines the step's kernel, which it keeps out of line without",
        "  the hint (slower steps).  gcc ignores the macro.",
        "",
        *misra_summary(gen.prefix, gen.header, gen.source),
        "## API",
        "",
        "```c",
        f"typedef {real} {p}_real;",
        f"extern const {rt} {p}_default_params[{P}_NP];",
        f"int32_t {p}_step({rt} *xhat, const {rt} *signals, const {rt} *params, {rt} dt);",
        f"int32_t {p}_run({rt} *xhat, const {rt} *signals, int32_t n_steps, const {rt} *params,",
        f"    {rt} dt, {rt} *trajectory);",
        f"int32_t {p}_run_dt({rt} *xhat, const {rt} *signals, int32_t n_steps, const {rt} *params,",
        f"    const {rt} *dt, {rt} *trajectory);",
        *([f"int32_t {p}_original(const {rt} *xhat, const {rt} *signals, const {rt} *params, {rt} *x);"]
          if gen.original_names else []),
        f"const char *{p}_status_message(int32_t status);",
        "```",
        "",
        f"`{p}_step` advances `xhat` in place by `dt` seconds; `params` may be `NULL` for the defaults.",
        f"`{p}_run` does `n_steps` steps through the rows of `signals` (row-major, `{P}_NS` per row) and writes",
        "every new state to `trajectory` (may be `NULL`).  `_run_dt` does the same with a step length per row,",
        "`dt[k]` for row `k` (irregular sampling; `dt` has `n_steps` entries).  Each returns 0 or a status code",
        "below; a failed step leaves `xhat` unchanged (for `_run` and `_run_dt`: `xhat` holds the state after",
        "the steps that succeeded).",
        "Status and counts are `int32_t` (`<stdint.h>`), the same width on every target.",
        "",
        *_original_section(gen),
        *_bound_section(gen),
        *_ranges_section(gen),
        *([] if gen.kind in SLIDING_MODE_GAINS else _certificate_section(gen)),
        f"## State (`{P}_NX` = {gen.nx})",
        "",
        "| index macro | state |",
        "| --- | --- |",
        *[f"| `{P}_X_{n.upper()}` = {i} | `{n}` |" for i, n in enumerate(gen.state_names)],
        "",
        f"## Signals (`{P}_NS` = {gen.ns}), one row per step",
        "",
        "| index macro | signal | role |",
        "| --- | --- | --- |",
        *[f"| `{P}_S_{n.upper()}` = {i} | `{n}` | {role} |"
          for i, (n, role) in enumerate(zip(gen.signal_names, gen.signal_roles))],
        "",
        f"## Parameters (`{P}_NP` = {gen.np})",
        "",
        (cite(SLIDING_MODE_GAINS[gen.kind], ascii=True) if gen.kind in SLIDING_MODE_GAINS else
         "Model parameters, then the gains `K_plus_<state>` (used where s > 0) and `K_minus_<state>`"
         + (", then the adaptation gain `Gamma` (row-major)" if gen.kind == "adaptive" else "")
         + ".  The gains do not follow a change of a model parameter: set them too, or regenerate."),
        "",
        "| index macro | parameter | default |",
        "| --- | --- | --- |",
        *[f"| `{P}_P_{n.upper()}` = {i} | `{n}` | {v!r} |"
          for i, (n, v) in enumerate(zip(gen.param_names, gen.default_params))],
        "",
        "## Status codes",
        "",
        "Checked in this order; the first failure is returned and nothing is written.",
        "",
        "| macro | value | meaning |",
        "| --- | --- | --- |",
        *[f"| `{P}_{'OK' if s == StepStatus.OK else 'ERR_' + s.name}` | {int(s)} | {STATUS_TEXT[s]} |"
          for s in StepStatus],
        "",
        "Model-specific checks, in order:",
        "",
        *([f"- `{cite(str(g), ascii=True)}`" for g in gen.guards] or ["- none beyond finiteness"]),
        *([] if gen.kind in SLIDING_MODE_GAINS else ["- `s` finite, else `UNDEFINED_TIME_SCALE`."]),
        *([] if gen.h_max is None else ["- at most `MAX_SUBSTEPS` sub-steps of `H_MAX` (then the domain of d, b), "
                                        "else `SUBSTEP_LIMIT`."]),
        "",
        "## Memory",
        "",
        f"One step keeps at most `{P}_STACK_REALS` = {gen.stack_reals} `{real}`s on the stack "
        f"(`{P}_SZ_W` = {gen.temporaries} temporaries of the step kernel plus the current and the new state); no other memory.",
        "",
        "## Example",
        "",
        "```c",
        example_program(gen).rstrip("\n"),
        "```",
        "",
    ]
    return "\n".join(out)
