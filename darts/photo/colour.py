"""Colour models of image regions: CIELAB colours and small Gaussian mixtures over them.

``lab``: sRGB (D65) uint8 -> CIE L*a*b* (L 0..100; a, b about -100..100), the standard formulas:
linearise each channel (c <= 0.04045: c / 12.92, else ((c + 0.055) / 1.055)^2.4), XYZ = M rgb,
f(t) = t^(1/3) above (6/29)^3 else t / (3 (6/29)^2) + 4/29, L = 116 f(Y) - 16,
a = 500 (f(X/Xn) - f(Y)), b = 200 (f(Y) - f(Z/Zn)).

``ColourModel``: a mixture of K Gaussians over Lab colours, fitted by k-means (scipy, fixed seed:
deterministic) and one Gaussian per cluster, each covariance regularised by ``FLOOR`` on its
diagonal so that a flat colour (a render's uniform cloth) still has a spread. Its log-density
log p(x) = logsumexp_k (log w_k + log N(x; mu_k, S_k)).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: variance (Lab units squared) added to each covariance's diagonal: 3 units of noise each way
FLOOR = 9.0
_RGB_TO_XYZ = np.array([[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750],
                        [0.0193339, 0.1191920, 0.9503041]])
_WHITE = np.array([0.95047, 1.0, 1.08883])


def lab(rgb: np.ndarray) -> np.ndarray:
    """CIE L*a*b* [..., 3] float32 of sRGB colours ``rgb`` [..., 3] uint8 (module docstring)."""
    c = np.asarray(rgb, np.float32) / 255.0
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    xyz = linear @ _RGB_TO_XYZ.T.astype(np.float32) / _WHITE.astype(np.float32)
    delta = 6.0 / 29.0
    f = np.where(xyz > delta ** 3, np.cbrt(xyz), xyz / (3 * delta ** 2) + 4.0 / 29.0)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])], -1)


@dataclass
class ColourModel:
    """A Gaussian mixture over Lab colours: weights [K], means [K,3], covariances [K,3,3]."""

    weights: np.ndarray
    means: np.ndarray
    covariances: np.ndarray

    @classmethod
    def fit(cls, colours: np.ndarray, components: int = 3, seed: int = 0) -> ColourModel | None:
        """The mixture of ``colours`` [N,3] (Lab) with up to ``components`` clusters (fewer when
        there are few colours; empty clusters dropped); None for fewer than 8 colours."""
        from scipy.cluster.vq import kmeans2

        colours = np.asarray(colours, np.float64)
        if len(colours) < 8:
            return None
        k = int(min(components, max(1, len(colours) // 20)))
        if k == 1:
            assignment = np.zeros(len(colours), int)
        else:
            _, assignment = kmeans2(colours, k, minit="++", seed=np.random.default_rng(seed))
        weights, means, covariances = [], [], []
        for cluster in range(k):
            members = colours[assignment == cluster]
            if len(members) < 4:
                continue
            weights.append(len(members))
            means.append(members.mean(0))
            covariances.append(np.cov(members.T) + FLOOR * np.eye(3))
        weights = np.array(weights, np.float64)
        return cls(weights / weights.sum(), np.array(means), np.array(covariances))

    def log_density(self, colours: np.ndarray) -> np.ndarray:
        """log p(x) [N] of Lab ``colours`` [N,3] (module docstring)."""
        x = np.asarray(colours, np.float64)
        terms = []
        for w, mu, cov in zip(self.weights, self.means, self.covariances):
            inverse = np.linalg.inv(cov)
            d = x - mu
            mahalanobis = np.einsum("ni,ij,nj->n", d, inverse, d)
            terms.append(np.log(w) - 0.5 * (mahalanobis + np.log(np.linalg.det(cov)) + 3 * np.log(2 * np.pi)))
        return np.logaddexp.reduce(np.stack(terms), axis=0)
