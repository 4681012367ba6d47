"""Resource bounds and failed runs of ``switchobs encoder`` and ``switchobs simulate`` (issue 13).

Each hostile option of the issue is replayed: it must end with one line on stderr and the exit status
of docs/errors.md (2 refused before any work, 1 a failed run), and the library refuses the same
settings from Python.  ``tests/test_fuzz_options.py`` draws many more, in a memory-capped process.
"""

import dataclasses
import functools
import math
import re
from pathlib import Path

import numpy as np
import pytest

import switchobs.cli._encoder as encoder_cli
import switchobs.cli._simulate as simulate_cli
from switchobs.cli.main import main
from switchobs.exceptions import SimulationError
from switchobs.plants import BrakingScenario, simulate
from switchobs.plants._hybrid import MAX_STEPS
from switchobs.sensors import ChainSettings, Encoder, compare_estimators, constant_speed
from switchobs.sensors import _tsa
from switchobs.plants._vehicle import MAX_DELAY_S, MAX_SPEED_KMH
from switchobs.sensors import _chain as chain
from switchobs.sensors._chain import MAX_EDGES, MAX_LAG_WORK, MAX_RLS_WORK, MAX_SAMPLES, MAX_TSA_WORK
from switchobs.sensors._encoder import MAX_PPR
from switchobs.sensors._three_stage import MAX_HARMONICS
from switchobs.sensors._trajectory import MAX_DURATION_S, MAX_RPM


def run(capsys, *argv):
    """Exit status, stdout, and stderr without the progress notes of a run that lasts over a second."""
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, "".join(line for line in out.err.splitlines(keepends=True)
                                  if not re.match(r"switchobs \w+: \[", line))


# (argv, exit status, words the one-line message must contain)
REFUSED = [
    (("encoder", "--rpm", "1e9"), "30000 rpm"),
    (("encoder", "--rate-hz", "1e9"), "limit of 1e+06"),
    (("encoder", "--duration", "1e9"), "3600 s"),
    (("encoder", "--harmonics", "1000"), "lies above 200"),
    (("encoder", "--events", "100000", "--duration", "2"), "never fills"),
    (("encoder", "--ppr", "1000000000"), "lies above 100000"),
    (("encoder", "--order", "1000", "--events", "1001", "--duration", "2"), "TSA least-squares numbers"),
    (("encoder", "--rate-hz", "0.01"), "the statistics need 2 samples"),
    (("encoder", "--profile", "braking", "--duration", "1e9"), "limit of 1e+06"),
    (("encoder", "--ppr", "4", "--harmonics", "5", "--estimator", "three-stage", "--duration", "2"), "half the edges"),
    (("simulate", "--dt", "1e-9"), "about 6e+10, above the limit of 1e+06"),
    (("simulate", "--duration", "1e9"), "limit of 1e+06"),
    (("simulate", "--speed-kmh", "1e9"), "(0, 500] km/h"),
    (("simulate", "--delay", "1e9"), "[0, 1] s"),
    (("simulate", "aguado-sec36", "--speed-kmh", "1e9"), "(0, 500] km/h"),
    (("simulate", "table41", "--dt", "1e-9"), "limit of 1e+06"),
]


@pytest.mark.parametrize("argv, words", REFUSED, ids=[" ".join(a) for a, _ in REFUSED])
def test_hostile_options_are_refused_before_any_work_in_one_line(capsys, argv, words):
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith(f"switchobs {argv[0]}: error: ") and words in err


def test_an_observer_that_fails_is_a_failed_run(capsys):
    # the explicit rk4 step overflows at this gain; the default radau3, certified for every step, does not
    code, out, err = run(capsys, "simulate", "--observer", "xbs4", "--beta", "1e9", "--method", "rk4", "-q")
    assert code == 1 and "status: observer-failed" in out
    assert err.count("\n") == 1 and err.startswith("switchobs simulate: failed: observer-failed: ")
    code, out, err = run(capsys, "simulate", "--observer", "xbs4", "--beta", "1e9")
    assert code == 0 and "observer-failed" not in out and err == ""


def test_an_observer_that_diverges_is_a_failed_run(capsys):
    code, out, err = run(capsys, "simulate", "--observer", "adaptive", "--gamma", "1e5", "--json")
    assert code == 1
    assert err.count("\n") == 1 and "diverged" in err and "not finite" in err
    assert '"failure": "the observer diverged' in out


def test_a_run_ended_by_the_duration_asked_for_is_not_a_failure(capsys):
    code, out, err = run(capsys, "simulate", "--duration", "0.5")
    assert code == 0 and err == ""
    assert "stop: not reached, distance travelled" in out
    assert "stopping distance" not in out and "braking distance" not in out


def test_the_default_braking_that_does_not_stop_is_a_failed_run(capsys, monkeypatch):
    # the default run brakes "to standstill": a default time bound too short to stop is a failure
    monkeypatch.setattr(simulate_cli, "BrakingScenario", functools.partial(BrakingScenario, duration_s=0.5))
    code, out, err = run(capsys, "simulate")
    assert code == 1 and "distance travelled" in out
    assert err.count("\n") == 1 and "did not stop within the default time bound of 0.5 s" in err


def test_a_run_that_did_not_stop_has_no_table41_braking_distance():
    res = simulate(BrakingScenario("dry-asphalt", speed_m_s=30.0, duration_s=0.3))
    assert res.status == "duration" and res.metrics.braking_distance_m is None and res.failure is None
    assert res.metrics.stopping_distance_m > 0


def test_the_library_refuses_the_same_settings_from_python():
    with pytest.raises(SimulationError, match=r"\(0, 500\] km/h"):
        BrakingScenario("dry-asphalt", speed_m_s=1e9)
    with pytest.raises(SimulationError, match=re.escape(f"limit of {MAX_STEPS:.3g}")):
        simulate(BrakingScenario("dry-asphalt", speed_m_s=30.0, dt_s=1e-9))
    with pytest.raises(SimulationError, match="30000 rpm"):
        constant_speed(1e9, 1.0)
    with pytest.raises(SimulationError, match=re.escape(f"limit of {MAX_EDGES:.3g}")):
        compare_estimators(constant_speed(20_000, 3600.0), Encoder(ppr=1000))
    with pytest.raises(SimulationError, match=re.escape(f"limit of {MAX_SAMPLES:.3g}")):
        compare_estimators(constant_speed(1020, 2.0), settings=ChainSettings(rate_hz=1e7))


def test_an_encoder_comparison_without_statistics_is_a_failed_run(capsys, monkeypatch):
    # the up-front checks leave no known settings without statistics: a NaN row is planted behind the CLI
    def nan_row(*args, **kwargs):
        comparison = compare_estimators(*args, **kwargs)
        rows = (dataclasses.replace(comparison.results[0], rms_omega=math.nan), *comparison.results[1:])
        return dataclasses.replace(comparison, results=rows)
    monkeypatch.setattr(encoder_cli, "compare_estimators", nan_row)
    code, out, err = run(capsys, "encoder", "--duration", "1.5", "--estimator", "tsa")
    assert code == 1 and "nan" in out
    assert err.count("\n") == 1 and err.startswith("switchobs encoder: failed: no finite RMS error for tsa")


def test_tsa_fits_in_chunks_equal_one_batch(monkeypatch):
    t = np.cumsum(np.full(400, 1e-3) * (1.0 + 0.1 * np.sin(np.arange(400))))
    theta = 3.0 * t + 5.0 * t**2 + 1e-4 * np.cos(40 * t)
    ts = np.linspace(0.05, float(t[-1]), 97)
    whole = _tsa.time_stamping(t, theta, ts, order=2, window=15)
    monkeypatch.setattr(_tsa, "_FIT_CHUNK", 15 * 3 * 7)     # 7 fits per chunk
    chunked = _tsa.time_stamping(t, theta, ts, order=2, window=15)
    for a, b in ((whole.theta, chunked.theta), (whole.omega, chunked.omega), (whole.alpha, chunked.alpha)):
        assert np.array_equal(np.isnan(a), np.isnan(b)) and np.allclose(a, b, rtol=1e-12, equal_nan=True)
    assert math.isfinite(float(whole.omega[-1]))


def _limits_section() -> str:
    text = (Path(__file__).parents[1] / "docs" / "errors.md").read_text("utf-8")
    start = text.index("## Simulation and encoder options")
    end = text.find("\n## ", start + 1)
    return text[start:] if end < 0 else text[start:end]


def test_the_documented_limits_are_the_constants_of_the_code():
    constants = {"MAX_SPEED_KMH": MAX_SPEED_KMH, "MAX_DELAY_S": MAX_DELAY_S, "MAX_STEPS": MAX_STEPS, "MAX_RPM": MAX_RPM,
                 "MAX_DURATION_S": MAX_DURATION_S, "MAX_PPR": MAX_PPR, "MAX_HARMONICS": MAX_HARMONICS,
                 "MAX_EDGES": MAX_EDGES, "MAX_SAMPLES": MAX_SAMPLES, "MAX_TSA_WORK": MAX_TSA_WORK,
                 "MAX_RLS_WORK": MAX_RLS_WORK, "MAX_LAG_WORK": MAX_LAG_WORK}
    rows = {m.group(1): float(m.group(2).replace(" ", ""))
            for m in re.finditer(r"^\| `(MAX_\w+)` \| ([0-9e .]+) \|", _limits_section(), re.MULTILINE)}
    assert rows == constants
    # every limit of the chain module is in the table
    assert {name for name in chain.__all__ if name.startswith("MAX_")} <= rows.keys()


def test_the_refusals_shown_in_the_docs_are_what_the_commands_print(capsys):
    shown = re.findall(r"^\$ switchobs (.+)\n(.+)$", _limits_section(), re.MULTILINE)
    assert len(shown) == 2
    for command, line in shown:
        code, _, err = run(capsys, *command.split())
        assert code == 2 and err == line + "\n"
