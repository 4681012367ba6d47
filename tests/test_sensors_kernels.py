"""The C kernels of the encoder chain (sensors/_kernels.c) against the Python reference they port.

The TSA fit's C Householder QR and numpy's LAPACK QR solve the same least-squares problems with their own
rounding: the exact rational least-squares fit of the same float inputs is the arbiter.  Both are within
1e-12 of the signal's range of it (measured: 6e-14 for the acceleration, the worst), the C kernel no
further from it than LAPACK is (measured: 0.9 of LAPACK's worst error), and the two within 1e-12 of each
other on orders 2-4 and windows 5-40.
The three-stage estimator's C port sums its dot products left to right where numpy's BLAS does not, so
the two agree to rounding: within 1e-12 of the signal's range (measured: some 1e-16 of it); the notch
and the stages' decisions (which samples the detrend hands the identification) are the same bit for bit.
"""

from __future__ import annotations

import sys
from importlib import resources

import numpy as np
import pytest

from switchobs.exceptions import CodegenError, SimulationError
from switchobs.plants._compiled import compiler_available
from switchobs.sensors import (Encoder, NotchFilter, ThreeStageEstimator, TimeStamper, controller_times, notch,
                               notch_series, three_stage, time_stamping, varying_speed)

from test_codegen_hygiene import COMPILERS, STRICT, compile_c, compiler

needs_compiler = pytest.mark.skipif(not compiler_available(), reason="no C compiler")
#: Largest difference between the C port and the Python reference, relative to the signal's range.
TOLERANCE = 1e-12


@pytest.fixture(scope="module")
def tsa():
    """3 s of a wheel swinging 600 rpm +- 40 rad/s at 1 Hz through an imperfect 60-ppr encoder."""
    traj = varying_speed(600.0, 3.0)
    ev = Encoder(ppr=60, dnl_cycles=0.01, eccentricity=0.003, clock_hz=1e6, seed=1).events(traj)
    return time_stamping(ev.times, ev.angles, controller_times(0.0, 3.0, 1000.0))


@needs_compiler
@pytest.mark.parametrize("highpass_hz, harmonics", [(None, 5), (None, 2), (1.0, 5)])
def test_the_c_three_stage_estimator_equals_the_python_reference_to_rounding(tsa, highpass_hz, harmonics):
    ref = three_stage(tsa, harmonics=harmonics, highpass_hz=highpass_hz, compiled=False)
    ours = three_stage(tsa, harmonics=harmonics, highpass_hz=highpass_hz, compiled=True)
    ok = tsa.valid
    assert np.array_equal(np.isnan(ours.omega), np.isnan(ref.omega))
    for name in ("omega", "alpha"):
        a, b, raw = getattr(ours, name)[ok], getattr(ref, name)[ok], getattr(tsa, name)[ok]
        assert np.max(np.abs(a - b)) <= TOLERANCE * np.max(np.abs(raw)), name
        # and the compensation is not nothing
        assert np.max(np.abs(b - raw)) > 1e-3 * np.max(np.abs(raw)), name


def _exact_fit(times, angles, at, order):
    """The least-squares polynomial of ``order`` through the events, in exact rationals, and its derivatives
    at ``at`` (seed 001 (5.2)-(5.5)): the normal equations solved by Gaussian elimination on Fractions."""
    from fractions import Fraction

    t0, th0 = Fraction(float(times[0])), Fraction(float(angles[0]))
    d = [Fraction(float(x)) - t0 for x in times]
    y = [Fraction(float(x)) - th0 for x in angles]
    e = Fraction(float(at)) - t0
    size = order + 1
    rows = [[sum(x ** (j + k) for x in d) for k in range(size)] + [sum(x ** j * v for x, v in zip(d, y))]
            for j in range(size)]
    for c in range(size):
        for r in range(c + 1, size):
            f = rows[r][c] / rows[c][c]
            rows[r] = [u - f * v for u, v in zip(rows[r], rows[c])]
    p = [Fraction(0)] * size
    for c in range(size - 1, -1, -1):
        p[c] = (rows[c][size] - sum(rows[c][k] * p[k] for k in range(c + 1, size))) / rows[c][c]
    return (float(th0 + sum(p[k] * e ** k for k in range(size))),
            float(sum(k * p[k] * e ** (k - 1) for k in range(1, size))),
            float(sum(k * (k - 1) * p[k] * e ** (k - 2) for k in range(2, size))))


@needs_compiler
def test_the_c_tsa_fit_is_as_close_to_the_exact_least_squares_fit_as_lapack():
    traj = varying_speed(600.0, 3.0)
    ev = Encoder(ppr=60, dnl_cycles=0.01, eccentricity=0.003, clock_hz=1e6, seed=1).events(traj)
    ts = controller_times(0.0, 3.0, 1000.0)[::20]
    ours, ref = (time_stamping(ev.times, ev.angles, ts, compiled=c) for c in (True, False))
    rows = np.flatnonzero(ref.valid)
    assert np.array_equal(ours.valid, ref.valid) and rows.size > 100
    exact = np.array([_exact_fit(ev.times[i - 14:i + 1], ev.angles[i - 14:i + 1], ts[k], 2)
                      for k, i in zip(rows, ref.last_event[rows])])
    for j, name in enumerate(("theta", "omega", "alpha")):
        scale = np.max(np.abs(exact[:, j]))
        err_c = np.max(np.abs(getattr(ours, name)[rows] - exact[:, j]))
        err_lapack = np.max(np.abs(getattr(ref, name)[rows] - exact[:, j]))
        assert err_c <= TOLERANCE * scale and err_lapack <= TOLERANCE * scale, name
        assert err_c <= max(1.5 * err_lapack, 4e-16 * scale), name


@needs_compiler
@pytest.mark.parametrize("order, window", [(2, 15), (3, 15), (2, 5), (4, 40)])
def test_the_c_tsa_fit_equals_the_lapack_reference_to_rounding_and_streams_alike(order, window):
    traj = varying_speed(600.0, 2.0)
    ev = Encoder(ppr=100, dnl_cycles=0.01, eccentricity=0.003, clock_hz=1e6, seed=2).events(traj)
    ts = controller_times(0.0, 2.0, 1000.0)
    ours, ref = (time_stamping(ev.times, ev.angles, ts, order=order, window=window, compiled=c) for c in (True, False))
    ok = ref.valid
    assert np.array_equal(np.isnan(ours.omega), np.isnan(ref.omega)) and np.count_nonzero(ok) > 1500
    for name in ("theta", "omega", "alpha"):
        a, b = getattr(ours, name)[ok], getattr(ref, name)[ok]
        assert np.max(np.abs(a - b)) <= TOLERANCE * np.max(np.abs(b)), name
    # the streaming TSA with the kernel gives the batch's numbers bit for bit
    stamper, pushed, got = TimeStamper(order=order, window=window, compiled=True), 0, []
    for t in ts[::7]:
        while pushed < ev.times.size and ev.times[pushed] <= t:
            stamper.push(float(ev.times[pushed]), float(ev.angles[pushed]))
            pushed += 1
        got.append(stamper.estimate(float(t)))
    assert np.array_equal(np.array(got), np.column_stack([ours.theta, ours.omega, ours.alpha])[::7], equal_nan=True)


@needs_compiler
def test_the_c_coefficients_follow_the_python_ones_and_update_equals_run(tsa):
    ok = np.flatnonzero(tsa.valid)
    ref, one, run = (ThreeStageEstimator(5, compiled=c) for c in (False, True, True))
    assert (ref.compiled, one.compiled, run.compiled) == (False, True, True)
    step = np.array([one.update(float(tsa.theta[i]), float(tsa.omega[i]), float(tsa.alpha[i])) for i in ok])
    for i in ok:
        ref.update(float(tsa.theta[i]), float(tsa.omega[i]), float(tsa.alpha[i]))
    om, al = run.run(tsa.theta[ok], tsa.omega[ok], tsa.alpha[ok])
    assert np.array_equal(step, np.column_stack([om, al]))
    for name in ("coefficients_velocity", "coefficients_acceleration"):
        c, r = getattr(one, name), getattr(ref, name)
        assert np.array_equal(c, getattr(run, name))
        assert np.max(np.abs(c - r)) <= 1e-9 * np.max(np.abs(r)) and np.max(np.abs(r)) > 0.0, name


@needs_compiler
def test_the_c_notch_is_the_python_notch_bit_for_bit(tsa):
    ok = tsa.valid
    for a, b in zip((notch(tsa, compiled=True), ), (notch(tsa, compiled=False), )):
        assert np.array_equal(a.omega, b.omega, equal_nan=True) and np.array_equal(a.alpha, b.alpha, equal_nan=True)
    filt = NotchFilter(dt_s=1e-3, damping=0.3)
    by_hand = [filt.update(float(u), float(c)) for u, c in zip(tsa.alpha[ok], tsa.omega[ok])]
    assert np.array_equal(notch_series(tsa.alpha[ok], tsa.omega[ok], dt_s=1e-3, damping=0.3, compiled=True),
                          by_hand)


def test_run_refuses_samples_of_unequal_lengths():
    with pytest.raises(SimulationError, match="3, 2 and 3 samples"):
        ThreeStageEstimator(compiled=False).run([0.0, 1.0, 2.0], [1.0, 1.0], [0.0, 0.0, 0.0])
    with pytest.raises(SimulationError, match="one centre per sample"):
        notch_series([1.0, 2.0], [3.0], dt_s=1e-3, compiled=False)


def test_without_a_compiler_or_casadi_the_python_reference_runs(monkeypatch):
    import switchobs.codegen

    def missing(compiler=None):
        raise CodegenError("no C compiler found")

    monkeypatch.setattr(switchobs.codegen, "find_compiler", missing)
    assert not ThreeStageEstimator().compiled
    monkeypatch.setitem(sys.modules, "switchobs.codegen", None)    # an import of it fails, as a broken casadi
    assert not ThreeStageEstimator().compiled
    with pytest.raises(CodegenError, match="cannot be built"):
        ThreeStageEstimator(compiled=True)


@pytest.mark.parametrize("cc", COMPILERS)
def test_the_kernels_compile_clean_with_strict_flags(tmp_path, cc):
    """-std=c99 -Wall -Wextra -Wpedantic -Wconversion -Wfloat-conversion -Wdouble-promotion -Werror."""
    source = tmp_path / "kernels.c"
    source.write_text(resources.files("switchobs.sensors").joinpath("_kernels.c").read_text(encoding="utf-8"))
    compile_c(compiler(cc), STRICT + ["-O2"], [source], tmp_path / "kernels.o")
