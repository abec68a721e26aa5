"""Wind with gusts: w(t) = w0 (1 + a g(t)), g a seeded sum of three sines scaled into [-1, 1]."""
from __future__ import annotations

import numpy as np


class Wind:
    """A constant wind vector ``base`` (m/s, world frame) whose strength gusts by +-``gust``."""

    def __init__(self, base, gust: float = 0.0, seed: int = 0):
        self.base = np.asarray(base, np.float64)
        self.gust = float(gust)
        rng = np.random.default_rng(seed)
        self.frequencies = rng.uniform(0.2, 1.5, 3)  # Hz
        self.phases = rng.uniform(0.0, 2.0 * np.pi, 3)
        self.weights = rng.uniform(0.5, 1.0, 3)
        self.weights /= self.weights.sum()

    def at(self, time: float) -> np.ndarray:
        """The wind vector at ``time`` seconds."""
        g = float(np.dot(self.weights, np.sin(2.0 * np.pi * self.frequencies * time + self.phases)))
        return self.base * (1.0 + self.gust * g)
