"""Seed claims put to numbers (docs/reproductions.md): seed 001 Sec. 3.4's perturbed scenario (Figs. 3.6-3.9),
seed 000 Fig. 4 per road and its Sec. III-E noise remark on the encoder-fed run, seed 001 Fig. 4.7.

The runs are the pages' (:class:`switchobs.experiments.Runs`, one per module); each margin is said beside its
assertion, against the value the run gives today (``switchobs reproduce`` prints them on the page)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from switchobs.experiments import (FIG4_OBSERVERS, SEC34_PERTURBED_ENCODER, SEC34_WINDOWS, Runs, eccentric_x2,
                                   fig4_roads, noise_gains)
from switchobs.plants import BrakingScenario, road, simulate, table41
from switchobs.sensors import Encoder

#: The windows of the perturbed scenario: the ideal comparison's and the last second of the run.
WINDOWS = (*SEC34_WINDOWS, ("last second", 9.0, 10.0))


@pytest.fixture(scope="module")
def runs():
    return Runs()


def test_aguado2020_sec53_eccentric_x2_is_the_second_derivative_of_the_eq57_angle_law():
    # the finite differences of eccentric_x2 against the closed-form derivatives of (5.7), f = asin(e sin(th + phi))
    enc = Encoder(ppr=60, eccentricity=0.01, eccentricity_phase_rad=0.7)
    res = simulate(BrakingScenario("dry-asphalt", speed_m_s=20.0, duration_s=0.3))
    s = res.series
    t, om = s["t"], s["omega"]
    th = np.concatenate([[0.0], np.cumsum(0.5 * (om[1:] + om[:-1]) * np.diff(t))]) + enc.eccentricity_phase_rad
    g, g1, g2 = (enc.eccentricity * fn(th) for fn in (np.sin, np.cos, lambda x: -np.sin(x)))
    f1 = g1 / np.sqrt(1 - g * g)
    f2 = g2 / np.sqrt(1 - g * g) + g * g1 * g1 / (1 - g * g) ** 1.5
    expected = s["x2"] + res.scenario.vehicle.radius_m * (s["omega_dot"] * f1 + om * om * f2)
    # truncation h² f''''/12 with h = 1e-3 rad: 1e-7 of the perturbation's amplitude (R ω² e = 13 m/s² here)
    assert np.max(np.abs(eccentric_x2(res, enc) - expected)) < 1e-5
    # and the perturbation is not nothing: the test would pass for a zero perturbation otherwise
    assert np.max(np.abs(eccentric_x2(res, enc) - s["x2"])) > 5.0


@pytest.mark.slow
def test_aguado2020_sec34_fig36_perturbation_is_periodic_and_falls_with_the_speed_squared(runs):
    p = runs.sec34_perturbed
    s, R, e = p.result.series, p.result.scenario.vehicle.radius_m, SEC34_PERTURBED_ENCODER.eccentricity
    for _, a, b in WINDOWS:
        keep = (s["t"] >= a) & (s["t"] < b)
        # amplitude R ω² e/r at the window's fastest wheel: ours 0.92-1.00 of it (below 1 where the largest ω and
        # the crest of the sine miss each other), so 0.85-1.05
        assert 0.85 < p.amplitude(a, b) / (R * e * np.max(s["omega"][keep]) ** 2) < 1.05
        # periodic in one revolution: the spectrum's peak at the wheel's frequency, within the 1 Hz bin of a
        # one-second window and the wheel's change of speed over it (0.4 Hz at most)
        d = (p.x2_measured - s["x2"])[keep]
        freq = np.fft.rfftfreq(d.size, float(np.median(np.diff(s["t"][keep]))))
        peak = freq[np.argmax(np.abs(np.fft.rfft(d - d.mean())))]
        assert abs(peak - np.mean(s["omega"][keep]) / (2 * math.pi)) < 1.5


@pytest.mark.slow
def test_aguado2020_sec34_fig37_fig39_both_estimation_errors_perturbed(runs):
    p = runs.sec34_perturbed
    _, a, b = WINDOWS[0]
    for label in p.estimates:
        # dry asphalt at 21 m/s: ours 41-68 times the ideal RMS error; 10 leaves a factor 4
        assert p.rms(label, True, a, b) > 10 * p.rms(label, False, a, b), label


@pytest.mark.slow
def test_aguado2020_sec34_fig37_adaptive_error_approaches_zero_as_the_speed_falls(runs):
    p = runs.sec34_perturbed
    first, last = WINDOWS[0], WINDOWS[-1]
    effects = [p.effect("adaptive", a, b) for _, a, b in WINDOWS]
    # what the perturbation adds falls window after window (0.694, 0.395, 0.036, 0.020) ...
    assert all(later < earlier for earlier, later in zip(effects, effects[1:]))
    # ... 35-fold from the first to the last window, while the perturbation falls 8.5-fold: more than 10-fold
    assert effects[0] > 10 * effects[-1]
    assert p.amplitude(*first[1:]) > 5 * p.amplitude(*last[1:])
    # and the error left is small: 1.7 % of the XBS's range in the last second; 3 % leaves a factor 1.8
    s = p.result.series
    keep = (s["t"] >= last[1]) & (s["t"] < last[2])
    assert p.rms("adaptive", True, *last[1:]) < 0.03 * np.ptp(s["xbs"][keep])


@pytest.mark.slow
def test_aguado2020_sec34_fig39_augmented_more_sensitive_but_its_error_floor_is_its_own(runs):
    p = runs.sec34_perturbed
    augmented = [k for k in p.estimates if k.startswith("xbs4")]
    assert len(augmented) == 3
    last = WINDOWS[-1][1:]
    for k in augmented:
        for _, a, b in WINDOWS:
            # "greater sensitivity": ours 1.26-2.15 times the adaptive observer's perturbation effect
            assert p.effect(k, a, b) > 1.1 * p.effect("adaptive", a, b), (k, a)
        # the seed: its error "does not converge to zero": in the last second it stays above the adaptive
        # observer's (ours 0.050-0.158 against 0.042) ...
        assert p.rms(k, True, *last) > p.rms("adaptive", True, *last)
        # ... but what the perturbation adds there (0.030-0.035) is below the error it has in the ideal run
        # (0.041-0.154): the floor is the observer's own, which the page flags as a partial contradiction
        assert p.effect(k, *last) < p.rms(k, False, *last)


@pytest.mark.slow
def test_hoang2014_fig4_tracking_achieved_and_pressure_follows_the_friction_per_road(runs):
    rows = fig4_roads(runs.braking("hoang-fig4", "xbs4"))
    assert [r.road for r in rows] == ["dry", "wet", "snow"]
    for r in rows:
        # settled tracking error: ours 0.1-0.2 % of the reference's RMS with the exact x2; 1 % leaves a factor 4
        assert r.settled_rms < 0.01 * r.reference_rms, r
        assert 0.1 < r.tracking_share < 0.5
    # right after a road change the tracking error is far larger (the page's "road" column: 5.5 and 2.2 m/s²)
    assert all(r.tracking_rms > 20 * r.settled_rms for r in rows[1:])
    # "the brake pressure is reduced and follows the available tyre force potential": the mean pressure falls at
    # each change and, per unit of peak friction, is the same on the three roads to within 10 % (ours 42, 41, 45
    # bar); 20 % allowed
    assert rows[0].pressure_mean > rows[1].pressure_mean > rows[2].pressure_mean
    per_mu = [r.pressure_mean / abs(road(f"hoang-{r.road}").peak_friction) for r in rows]
    assert max(per_mu) < 1.2 * min(per_mu)


@pytest.mark.slow
def test_hoang2014_sec3e_noise_bigger_while_wheel_accelerates_and_not_explained_by_the_gain_norms(runs):
    fed = runs.fig4_encoder
    for label, spec in FIG4_OBSERVERS.items():
        g = noise_gains(spec)
        plus, minus = fed.noise(label)
        # the seed's remark holds on our encoder-fed run: ours 2.98 (xbs4) and 1.85 (xbs3) times
        assert plus > 1.4 * minus, label
        # its explanation does not: the norms of K_plus and K_minus are equal to 0.53 % and 0.09 %
        assert abs(g.norm_plus / g.norm_minus - 1) < 0.01, label
        # the H2 norms to z2 predict the ratio: measured / predicted 1.17 for both observers; 0.8-1.4 allowed
        assert 0.8 < (plus / minus) / (g.h2_plus / g.h2_minus) < 1.4, label
    # the 3D observer of Sec. III-E at beta = 100: the norms differ by 0.1 % (0.09 % here)
    g3 = noise_gains(FIG4_OBSERVERS["xbs3"])
    assert 0.0005 < g3.norm_plus / g3.norm_minus - 1 < 0.0015


def test_aguado2020_fig47_two_phase_smaller_slip_deviation_on_wet_asphalt_at_120_kmh(runs):
    f = runs.fig47
    # the Table 4.1 cell's runs: the same braking distances
    row = table41(roads=["wet-asphalt"], speeds_kmh=[120.0]).rows[0]
    assert (f.five.metrics.braking_distance_m, f.two.metrics.braking_distance_m) == (row.five_phase_m,
                                                                                     row.two_phase_m)
    # "a smaller variation of the wheel slip with respect to its optimal value": ours 5.5 times smaller; 3 allowed
    assert f.slip_deviation(f.five) > 3 * f.slip_deviation(f.two)
    lo5, hi5 = f.slip_range(f.five)
    lo2, hi2 = f.slip_range(f.two)
    assert lo5 < lo2 < road("wet-asphalt").optimal_slip < hi2 < hi5
