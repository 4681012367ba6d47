"""Comparing a braking run of the Python loop with its compiled (or replayed) twin, bit for bit."""

import numpy as np


def assert_same(ref, fast) -> None:
    """``fast`` (compiled) equals ``ref`` (the Python loop): status, message, steps, events, series, metrics."""
    assert not ref.compiled and fast.compiled
    assert (ref.status, ref.message, ref.steps, ref.events) == (fast.status, fast.message, fast.steps, fast.events)
    for key, col in ref.series.items():
        assert np.array_equal(col, fast.series[key], equal_nan=True), key
    assert ref.metrics == fast.metrics
