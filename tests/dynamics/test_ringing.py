"""Ringing windows and stop/corner detection on constructed motions."""

import numpy as np

from nnik.dynamics.ringing import events, ringing, tip_track


def test_stops_and_corners_are_found():
    fs = 1000
    x = np.concatenate([np.linspace(0, 10, 101), np.full(50, 10.0), np.full(100, 10.0)])
    y = np.concatenate([np.zeros(151), np.linspace(0, 10, 100)])
    t = events(np.stack([x, y], 1), fs)
    # rest from sample 101 (the stop), then a 90-degree turn is a new start, and the final stop
    assert np.isclose(t[0], 0.100) and len(t) == 2 and t[-1] == (len(x) - 1) / fs
    # a smooth arc has no corners
    a = np.linspace(0, np.pi, 500)
    assert len(events(np.stack([np.cos(a), np.sin(a)], 1), fs)) == 1


def test_ringing_is_the_window_peak_after_each_event():
    tick = 10_000
    dev = np.zeros(5000)
    dev[100 + 150] = 7.0  # 15 ms after an event at 10 ms: outside the window
    dev[100 + 500] = 3.0  # 50 ms after: inside
    r = ringing(dev, tick, np.array([0.010]))
    assert r == {"max": 3.0, "mean": 3.0, "n": 1}


def test_tip_of_a_stopped_base_settles_and_rings_first():
    tick = 10_000
    base = np.concatenate([np.linspace(0, 5, 1000), np.full(10, 5.0)])[:, None] * np.array([[1.0, 0.0]])
    tip = tip_track(base, tick, {"f_hz": (40.0, 40.0), "zeta": (0.1, 0.1)})
    assert len(tip) == len(base) + 3000
    over = np.abs(tip[:, 0] - 5.0)
    assert over[1100:1400].max() > 0.05 and over[-100:].max() < over[1100:1400].max() / 5


def test_a_corner_taken_at_speed_is_an_event():
    x = np.concatenate([np.linspace(0, 10, 101), np.full(100, 10.0)])
    y = np.concatenate([np.zeros(101), np.linspace(0.1, 10, 100)])
    t = events(np.stack([x, y], 1), 1000)
    assert len(t) == 2 and np.isclose(t[0], 0.100)
