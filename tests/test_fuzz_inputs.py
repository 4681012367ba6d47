"""Fuzzing the input boundaries: random model files, mutated certificates and hostile sweep spec files
(issues 13 and 25, docs/errors.md).

Every generated input is run through the real command line (``design`` for a model file, ``verify``
for a certificate, ``sweep`` for a sweep spec, under small ``--max-cases`` and ``--max-steps`` so that an
accepted sweep stays a few short runs); each run must end with exit 0, 1 or 2, and a failure must be exactly one line on
stderr, never a traceback or an internal error. Hypothesis draws ``SWITCHOBS_FUZZ_EXAMPLES`` inputs
per test (10 by default, derandomised so that ``make test`` is repeatable; ``make fuzz`` draws many
more, at random); a subprocess per input would cost seconds of start-up each, so the inputs are
collected first and run in one subprocess capped at 1 GiB of address space, and a failure names its
input (it is not shrunk).
"""

from __future__ import annotations

import json
import os
import random
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from _cli_batch import run_batch, valid_certificate

EXAMPLES = int(os.environ.get("SWITCHOBS_FUZZ_EXAMPLES", "10"))
FUZZING = "SWITCHOBS_FUZZ_EXAMPLES" in os.environ
DRAW = settings(max_examples=EXAMPLES, deadline=None, derandomize=not FUZZING, database=None,
                suppress_health_check=list(HealthCheck))
#: Wall time allowed per input (the subprocess's timeout is this times the batch size, plus start-up).
SECONDS_PER_INPUT = 20

PARAMETERS = ["a", "b", "c"]
NUMBERS = st.one_of(
    st.integers(-10**6, 10**6).map(str),
    st.floats(allow_nan=False, allow_infinity=False, width=64).map(repr),
    st.sampled_from(["1e400", "1e-400", "-1e308", "2.2e-308", "5e-324", "1e999999999", "1e-999999999", "0",
                     "1/3", "375/2", "1/0", "9" * 1200, "0.1", "1_000", "nan", "inf", "-0.0"]),
)
NAMES = st.sampled_from(PARAMETERS + ["pi", "E", "zz", "t", "y"])


def _expressions() -> st.SearchStrategy[str]:
    leaves = st.one_of(NUMBERS, NAMES)

    def extend(inner: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
        return st.one_of(
            st.tuples(inner, st.sampled_from(["+", "-", "*", "/", "**", "^"]), inner).map(lambda t: f"({t[0]}{t[1]}{t[2]})"),
            st.tuples(st.sampled_from(["exp", "log", "sqrt", "sin", "abs", "sign", "open", "__import__"]), inner)
            .map(lambda t: f"{t[0]}({t[1]})"),
            st.tuples(st.integers(1, 3000), inner).map(lambda t: "-" * t[0] + t[1]),
            st.tuples(inner, st.sampled_from(["10**10", "9**9**9", "100000", "1/3", "a", "-2", "0.5"]))
            .map(lambda t: f"({t[0]})**({t[1]})"),
            # long sums, kept under a megabyte of text
            st.tuples(inner, st.integers(2, 60_000)).map(lambda t: "+".join([t[0]] * min(t[1], 10**6 // len(t[0])))),
        )
    return st.recursive(leaves, extend, max_leaves=6)


#: Expressions a model would hold: small numbers, the parameters, + - * / and small powers.
BENIGN = st.recursive(st.one_of(st.integers(-50, 50).map(str), st.sampled_from(PARAMETERS)),
                      lambda inner: st.tuples(inner, st.sampled_from(["+", "-", "*", "/"]), inner)
                      .map(lambda t: f"({t[0]}{t[1]}{t[2]})") | inner.map(lambda e: f"{e}^2"), max_leaves=4)
EXPRESSIONS = st.one_of(BENIGN, BENIGN, _expressions())
JUNK = st.one_of(st.none(), st.booleans(), st.integers(), st.lists(st.integers(), max_size=3),
                 st.dictionaries(st.text(max_size=3), st.integers(), max_size=2), st.text(max_size=20))


@st.composite
def model_files(draw: st.DrawFn) -> tuple[str, int]:
    """A TOML model and its state count: mostly well-formed, hostile expressions and values, sometimes a broken key."""
    n = draw(st.integers(1, 3))
    states = [f"z{i + 1}" for i in range(n)]
    data: dict = {
        "name": "fuzz", "states": states, "parameters": PARAMETERS,
        "A": [[draw(EXPRESSIONS) if draw(st.booleans()) else "0" for _ in range(n)] for _ in range(n)],
        "C": ["1"] + ["0"] * (n - 1),
        "time_scale": draw(st.one_of(st.just("y"), EXPRESSIONS)),
        "values": {p: draw(st.one_of(st.integers(-100, 100).map(str), st.integers(-100, 100).map(str), NUMBERS))
                   for p in PARAMETERS if draw(st.integers(0, 3))},
    }
    if draw(st.integers(0, 9)) == 0:  # a structural mutation
        data[draw(st.sampled_from(["A", "C", "states", "values", "time_scale", "name", "bogus"]))] = draw(JUNK)
    return _toml(data), n


def _toml(data: dict) -> str:
    def value(v) -> str:
        if v is None:
            return '""'
        if isinstance(v, dict):
            return "{" + ", ".join(f"{json.dumps(str(k), ensure_ascii=False)} = {value(x)}" for k, x in v.items()) + "}"
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return json.dumps(v, ensure_ascii=False)  # astral characters as they are, not as surrogate pairs
    return "".join(f"{k} = {value(v)}\n" for k, v in data.items())


def _check(cases: list[dict], results: list[dict], label: str) -> None:
    assert len(results) == len(cases), f"{label}: hung or crashed on input {len(results)}: {cases[len(results)]}"
    for case, result in zip(cases, results):
        err = result["stderr"]
        assert result["rc"] in (0, 1, 2), (case, result)
        assert "Traceback" not in err and "internal error" not in err, (case, result)
        if result["rc"] == 2:
            assert err.count("\n") == 1 and err.startswith("switchobs "), (case, result)


def _draw(strategy: st.SearchStrategy) -> list:
    """``EXAMPLES`` inputs drawn by Hypothesis (collected, to be run in one batch)."""
    drawn: list = []

    @DRAW
    @given(strategy)
    def collect(example) -> None:
        drawn.append(example)
    collect()
    return drawn


def test_random_model_files_end_in_one_line_and_a_documented_status():
    poles = st.lists(st.sampled_from(["-1", "-2", "-1e400", "-beta1", "-10**100", "1"]), min_size=3, max_size=3)
    cases = [{"argv": ["design", "m.toml", f"--spectrum={','.join(p[:n])}"], "files": {"m.toml": text}}
             for (text, n), p in _draw(st.tuples(model_files(), poles))]
    _check(cases, run_batch(cases, timeout=30 + SECONDS_PER_INPUT * len(cases)), "model files")


def _paths(node, prefix=()):
    """Every path into a JSON tree (keys and list indices)."""
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, (*prefix, i))


CERT_VALUES = st.one_of(
    JUNK, NUMBERS, st.floats(), st.just([[["1"]]]), st.just("1" * 3999 + "/7"),
    st.integers(1, 30).map(lambda d: [[[["1"]]] * d]), st.just({"kind": "dwell-time", "tau_D": "1e3000", "P": []}),
)


@st.composite
def certificates(draw: st.DrawFn) -> str:
    """The valid certificate with 1 to 3 mutations: a value replaced, a key deleted, a list emptied or grown."""
    doc = json.loads(valid_certificate())
    rng = random.Random(draw(st.integers(0, 2**32)))
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in _paths(doc) if p]
        path = rng.choice(paths)
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        action = draw(st.sampled_from(["replace", "replace", "delete", "grow"]))
        if action == "delete" and isinstance(parent, dict):
            del parent[path[-1]]
        elif action == "grow" and isinstance(parent[path[-1]], list):
            parent[path[-1]] = parent[path[-1]] * draw(st.integers(0, 3))
        else:
            parent[path[-1]] = draw(CERT_VALUES)
    return json.dumps(doc)


def test_mutated_certificates_end_in_one_line_and_a_documented_status():
    flags = st.sampled_from([[], ["--strict"], ["--json"]])
    cases = [{"argv": ["verify", "c.json", *f], "files": {"c.json": text}}
             for text, f in _draw(st.tuples(certificates(), flags))]
    _check(cases, run_batch(cases, timeout=30 + SECONDS_PER_INPUT * len(cases)), "certificates")


#: Field names a table, heatmap or grid may name: real ones, near misses and hostile ones.
SWEEP_FIELDS = st.sampled_from(["road", "speed_kmh", "beta1", "observer", "status", "controller", "load_n", "speed",
                                "case_id", "kind", "to_json", "", "../x", "a\x00b", "é"])
SWEEP_METRICS = st.sampled_from(["braking_distance_m", "stop_time_s", "xbs_rms", "certified", "verdict", "segments",
                                 "bogus", "", "box_certified", "../../m"])
SWEEP_NAMES = st.one_of(st.sampled_from(["../../evil", "/tmp/evil", "a/b", "a\x00b", "..", "", "-", "x" * 3000,
                                         "é" * 200, "C:\\x", ".hidden"]),
                        st.text(st.characters(blacklist_categories=("Cs",)), max_size=20))
SWEEP_NUMBERS = st.one_of(st.sampled_from([0, -1, 1, 2, 10**6, 10**18, 1e-300, 1e300, -1e308, 0.5, 10.0, 30.0]),
                          st.floats(allow_nan=False, allow_infinity=False), st.integers(-10**6, 10**6))
SWEEP_JUNK = st.one_of(JUNK.filter(lambda v: not isinstance(v, str) or v.isprintable()), SWEEP_NUMBERS,
                       st.lists(SWEEP_NUMBERS, max_size=3))
#: Each part of a spec is well-formed three times in four, so that most inputs fail in one place (or not at all).
HOSTILE = st.integers(0, 3).map(lambda k: k == 0)


@st.composite
def sweep_axes(draw: st.DrawFn) -> object:
    """A grid axis: a list, a {start, stop, num} or {start, stop, step} range with hostile bounds, or junk."""
    start, stop = draw(SWEEP_NUMBERS), draw(SWEEP_NUMBERS)
    return draw(st.sampled_from([
        [draw(SWEEP_NUMBERS) for _ in range(draw(st.integers(0, 3)))],
        {"start": start, "stop": stop, "num": draw(st.one_of(st.integers(-2, 10**12), SWEEP_NUMBERS))},
        {"start": start, "stop": stop, "step": draw(SWEEP_NUMBERS)},
        {"start": start}, draw(SWEEP_JUNK), ["dry-asphalt", "snow", "mud"]]))


@st.composite
def sweep_draws(draw: st.DrawFn) -> dict:
    pair = st.lists(SWEEP_NUMBERS, min_size=0, max_size=3)
    return {draw(st.sampled_from(["speed_kmh", "road", "changes", "encoder_seed", "load_n", "bogus"])): draw(
        st.sampled_from([{"uniform": draw(pair)}, {"integers": draw(pair)}, {"choice": draw(st.lists(SWEEP_JUNK,
                         max_size=2))}, {"roads": ["snow", draw(SWEEP_FIELDS)], "count": draw(pair),
                         "window_s": draw(pair)}, {"normal": [1, 2]}, draw(SWEEP_JUNK)]))}


@st.composite
def sweep_specs(draw: st.DrawFn) -> str:
    """A small sweep spec (a few short brakings or certifications) with hostile names, sizes, ranges, draws,
    tables and heatmaps; sometimes a structural mutation."""
    certify = draw(st.integers(0, 4)) == 0
    data: dict = {"name": draw(SWEEP_NAMES) if draw(st.booleans()) else "fuzz",
                  "kind": "certify" if certify else "braking"}
    if certify:
        data["base"] = {"model": "abs-xbs3", "spectrum": "-beta1,-beta1,-beta1", "betas": [["beta1", 10.0]]}
        axis, values, fields, metric = "beta1", [10.0, 20.0], ["beta1", "model"], "certified"
    else:
        data["base"] = {"speed_kmh": draw(st.sampled_from([10.0, 20.0, 2.0])),
                        "duration_s": draw(st.sampled_from([1.0, 2.0, 0.5])),
                        "observer": draw(st.sampled_from(["none", "none", "xbs4", "adaptive"]))}
        axis, values, fields, metric = "road", ["dry-asphalt", "snow"], ["road", "speed_kmh"], "stop_time_s"
        if draw(HOSTILE):
            data["base"][draw(st.sampled_from(["changes", "dt_s", "encoder_ppr", "load_n", "duration_s", "bogus"]))] \
                = draw(SWEEP_JUNK)
    if draw(st.booleans()):
        data["grid"] = ({draw(st.sampled_from(["beta1", "speed_kmh", "load_n", "road", "bogus", "../x"])):
                         draw(sweep_axes())} if draw(HOSTILE) else {axis: values})
    if not certify and draw(st.booleans()):
        hostile = draw(HOSTILE)
        data["monte_carlo"] = {
            "count": draw(st.one_of(st.integers(-1, 10**7), SWEEP_JUNK)) if hostile else draw(st.integers(1, 2)),
            "root_seed": draw(st.one_of(st.integers(-1, 2**64), SWEEP_JUNK)) if draw(HOSTILE) else 7,
            "draw": draw(sweep_draws()) if draw(HOSTILE) else {"speed_kmh": {"uniform": [10.0, 20.0]}}}
    for key, names in (("table", ("rows", "column", "metric")), ("heatmap", ("y", "x", "metric"))):
        if draw(st.booleans()):
            entry = dict(zip(names, [[fields[0]] if key == "table" else fields[0], fields[1], metric]))
            if draw(HOSTILE):
                part = draw(st.sampled_from(names))
                entry[part] = draw(SWEEP_METRICS if part == "metric" else SWEEP_FIELDS)
            data[key] = [entry]
    if draw(st.integers(0, 4)) == 0:
        data["tune"] = draw(st.sampled_from([{}, {"enabled": True}, {"enabled": "yes"}, {"x": 1}]))
    if draw(st.integers(0, 5)) == 0:  # a structural mutation
        data[draw(st.sampled_from(["base", "grid", "monte_carlo", "table", "heatmap", "tune", "kind", "name",
                                   "description", "bogus"]))] = draw(SWEEP_JUNK)
    return _toml(data)


def test_random_sweep_spec_files_end_in_one_line_and_a_documented_status():
    flags = st.sampled_from([[], ["--json"], ["--tune"], ["--plots", "."], ["--resume"]])
    cases = [{"argv": ["sweep", "s.toml", "--scheduler", "none", "--max-cases", "4", "--max-steps", "20000", *f],
              "files": {"s.toml": text}} for text, f in _draw(st.tuples(sweep_specs(), flags))]
    _check(cases, run_batch(cases, timeout=30 + SECONDS_PER_INPUT * len(cases)), "sweep specs")


#: Text a model's name or description may hold in a hostile file: comment ends, quotes, control characters,
#: line breaks, non-ASCII letters, C and shell metacharacters.
HOSTILE_TEXT = st.text(alphabet=st.sampled_from(list("aZ_09 */\\\"'\n\r\t\x00\x1b{};#<>$`\u00e9\u2013\u202e")),
                       min_size=0, max_size=40)


@st.composite
def named_models(draw: st.DrawFn) -> str:
    """A well-formed 2-state model whose name and description are hostile text."""
    name, description = draw(HOSTILE_TEXT), draw(HOSTILE_TEXT)
    return (f"name = {json.dumps(name)}\ndescription = {json.dumps(description)}\nstates = [\"z1\", \"z2\"]\n"
            "A = [[0, 1], [0, 0]]\nC = [1, 0]\ntime_scale = \"y\"\n")


def test_codegen_of_hostile_names_and_descriptions_ends_in_one_line_or_writes_the_files():
    prefixes = st.one_of(st.none(), st.sampled_from(["", "a__b", "x_", "9x", "ok", "int", "a-b"]))
    drawn = _draw(st.tuples(named_models(), prefixes))[:max(3, EXAMPLES // 2)]  # each one designs and generates
    # first a name casadi refused before (non-ASCII, a space: "__" in the default prefix), which must now generate
    unicode = (f"name = {json.dumps('caf' + chr(233) + ' ' + chr(8211) + ' x')}\nstates = [\"z1\", \"z2\"]\n"
               "A = [[0, 1], [0, 0]]\nC = [1, 0]\ntime_scale = \"y\"\n")
    cases = [{"argv": ["codegen", "m.toml", "--spectrum=-1,-2", "--out", "c", *([] if p is None else ["--prefix", p])],
              "files": {"m.toml": text}} for text, p in [(unicode, None), *drawn]]
    results = run_batch(cases, timeout=30 + SECONDS_PER_INPUT * len(cases))
    _check(cases, results, "codegen names")
    assert results[0]["rc"] == 0, results[0]


def test_devices_directories_and_empty_inputs_end_in_one_line():
    """The one bounded reader: devices are read up to the limit plus one byte, never by their stat size."""
    inputs = [p for p in ("/dev/zero", "/dev/urandom", "/dev/null") if Path(p).exists()] + [".", "missing.toml",
                                                                                            "empty.toml"]
    cases = [{"argv": [command, path, *extra], "files": {"empty.toml": ""}}
             for path in inputs for command, extra in (("design", ["--spectrum=-1"]), ("verify", []),
                                                       ("transform", []))]
    results = run_batch(cases, timeout=30 + SECONDS_PER_INPUT * len(cases))
    _check(cases, results, "devices")
    assert all(r["rc"] == 2 for r in results), results
    assert all(r["seconds"] < SECONDS_PER_INPUT for r in results), [(c["argv"], r["seconds"])
                                                                     for c, r in zip(cases, results)]


def _big_certificate(n: int, digits: int) -> str:
    """A strict-cqlf certificate of n states whose matrices hold integers of ``digits`` digits."""
    big = 10 ** (digits - 1)
    A = [[str(-3 * n * big) if i == j else str(big + i * n + j) for j in range(n)] for i in range(n)]
    P = [[str(3 * n * big) if i == j else "0" for j in range(n)] for i in range(n)]
    return json.dumps({"format": "switchobs-certificate", "version": 1,
                       "family": {"names": ["A_plus", "A_minus"], "matrices": [A, A]},
                       "certificates": [{"kind": "strict-cqlf", "P": P}],
                       "verdict": {"arbitrary_switching": "UGES", "dwell_time": "any", "strict_cqlf": "exists",
                                   "common_lyapunov": "exists"}, "provenance": {}})


def test_certificates_near_the_size_limits_end_in_bounded_time():
    """Sizes around MAX_DIMENSION, MAX_CERTIFICATE_DIGITS and MAX_CERTIFICATE_WORK: each is checked or refused
    within the time bound (the products estimate refuses the expensive ones before any arithmetic, the
    elimination stops at MAX_CERTIFICATE_WORK)."""
    from switchobs._limits import MAX_CERTIFICATE_DIGITS, MAX_DIMENSION

    sizes = st.tuples(st.sampled_from([1, 2, 8, 16, MAX_DIMENSION + 1]),
                      st.sampled_from([1, 20, MAX_CERTIFICATE_DIGITS - 1, MAX_CERTIFICATE_DIGITS + 1]))
    # at the dimension limit, 400 digits (checked: the arb enclosure decides) and 3999 (refused by the products
    # estimate)
    drawn = sorted(set(_draw(sizes)) | {(MAX_DIMENSION, MAX_CERTIFICATE_DIGITS - 1), (MAX_DIMENSION, 400)})
    cases = [{"argv": ["verify", "c.json", *flag], "files": {"c.json": _big_certificate(n, d)}}
             for (n, d), flag in zip(drawn, [[], ["--arithmetic", "interval"]] * len(drawn))
             if n * d < 2_000_000]  # a file of n*n*d bytes: at most some 50 MB
    results = run_batch(cases, timeout=30 + SECONDS_PER_INPUT * len(cases), memory=2 << 30)
    _check(cases, results, "certificate sizes")
    assert all(r["seconds"] < SECONDS_PER_INPUT for r in results), [(c["argv"], r["seconds"])
                                                                     for c, r in zip(cases, results)]
