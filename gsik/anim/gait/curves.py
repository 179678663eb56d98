"""Smooth 1-D profiles of the gait: monotone cubics through knots and fixed swing shapes."""

from __future__ import annotations

import numpy as np


def pchip_slopes(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Fritsch-Carlson slopes: a monotone, C1 cubic through the knots (zero slope at the ends)."""
    h = np.diff(t)
    delta = np.diff(y, axis=0) / h[:, None]
    d = np.zeros_like(y)
    for k in range(1, len(t) - 1):
        a, b = delta[k - 1], delta[k]
        same = a * b > 0.0
        w1 = 2.0 * h[k] + h[k - 1]
        w2 = h[k] + 2.0 * h[k - 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            harmonic = (w1 + w2) / (w1 / a + w2 / b)
        d[k] = np.where(same, harmonic, 0.0)
    return d


def pchip(t_knots, y_knots, t_eval: np.ndarray) -> np.ndarray:
    """Evaluate the monotone cubic through ``(t_knots, y_knots (k, dim))`` at ``t_eval``; held outside."""
    t = np.asarray(t_knots, dtype=float)
    y = np.asarray(y_knots, dtype=float)
    if y.ndim == 1:
        return pchip(t, y[:, None], t_eval)[:, 0]
    d = pchip_slopes(t, y)
    te = np.clip(t_eval, t[0], t[-1])
    k = np.clip(np.searchsorted(t, te, side="right") - 1, 0, len(t) - 2)
    h = (t[k + 1] - t[k])[:, None]
    s = ((te - t[k]) / (t[k + 1] - t[k]))[:, None]
    h00 = 2 * s**3 - 3 * s**2 + 1
    h10 = s**3 - 2 * s**2 + s
    h01 = -2 * s**3 + 3 * s**2
    h11 = s**3 - s**2
    return h00 * y[k] + h10 * h * d[k] + h01 * y[k + 1] + h11 * h * d[k + 1]


def min_jerk(s: np.ndarray) -> np.ndarray:
    """0 to 1 with zero velocity and acceleration at both ends."""
    s = np.clip(s, 0.0, 1.0)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s**2)


def lift(s: np.ndarray) -> np.ndarray:
    """0 at both ends, 1 at the middle, zero slope at both ends: the swing foot's height profile."""
    s = np.clip(s, 0.0, 1.0)
    return 16.0 * s**2 * (1.0 - s) ** 2


def toe_off(s: np.ndarray) -> np.ndarray:
    """0 at both ends with zero slope, 1 at s = 0.4: the swing foot's toes-down pitch profile."""
    s = np.clip(s, 0.0, 1.0)
    return s**2 * (1.0 - s) ** 3 / (0.4**2 * 0.6**3)
