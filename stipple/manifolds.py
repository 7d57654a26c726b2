"""Geometry of the point sets: the torus (T²)^M and the sphere (S²)^M.

The optimiser only calls these methods, so one CG serves both domains. Points are ``(M, 2)`` arrays
in [0, 1)² on the torus and ``(M, 3)`` unit vectors on the sphere; tangent vectors have the same shape.
"""

import numpy as np


class Torus:
    """Flat torus [0, 1)² whose axes have physical lengths ``scale`` (``(W/L, H/L)`` for a W×H image).

    The metric is ``<u, v> = sum_i sum_j scale_j^2 u_ij v_ij``, so a rectangular image is optimised
    isotropically although points are stored in unit coordinates.
    """

    dimension = 2

    def __init__(self, scale=(1.0, 1.0)):
        self.scale = np.asarray(scale, dtype=float)
        self._metric = self.scale**2

    def inner(self, points, u, v):
        # Per-axis sums first: einsum makes one pass without a temporary (M, 2) array.
        return float(np.einsum("ij,ij->j", u, v) @ self._metric)

    def norm(self, points, v):
        return np.sqrt(self.inner(points, v, v))

    def riesz(self, points, covector):
        """The tangent vector representing a differential: ``G^{-1} covector``."""
        return covector / self._metric

    def retract(self, points, v):
        """``(p + v) mod 1``, the exponential map of the flat torus."""
        return np.mod(points + v, 1.0)

    def transport(self, points, v, w):
        """Parallel transport along ``exp(t v)`` is the identity on a flat torus."""
        return w

    def canonical(self, points):
        """Points wrapped into [0, 1)²."""
        return np.mod(points, 1.0)

    def random(self, rng, count):
        return rng.random((count, 2))


class Sphere:
    """Unit sphere S² with tangent vectors in R³ (nothing is singular at the poles)."""

    dimension = 3

    def inner(self, points, u, v):
        return float(np.sum(u * v))

    def norm(self, points, v):
        return np.sqrt(self.inner(points, v, v))

    def project(self, points, v):
        """Tangential part ``v - (x . v) x`` at every point."""
        return v - np.sum(points * v, axis=1, keepdims=True) * points

    def riesz(self, points, covector):
        return self.project(points, covector)

    def retract(self, points, v):
        """Exponential map ``cos|v| x + sin|v| v/|v|``, re-normalised against drift."""
        length = np.linalg.norm(v, axis=1, keepdims=True)
        moved = np.cos(length) * points + np.sinc(length / np.pi) * v
        return moved / np.linalg.norm(moved, axis=1, keepdims=True)

    def transport(self, points, v, w):
        """Parallel transport of ``w`` along the geodesic ``t -> exp_x(t v)`` to ``t = 1``."""
        length = np.linalg.norm(v, axis=1, keepdims=True)
        safe = np.where(length > 0, length, 1.0)
        direction = np.where(length > 0, v / safe, 0.0)
        along = np.sum(w * direction, axis=1, keepdims=True)
        moved = along * (np.cos(length) * direction - np.sin(length) * points) + w - along * direction
        return self.project(self.retract(points, v), moved)

    def canonical(self, points):
        """Points scaled onto the unit sphere."""
        return points / np.linalg.norm(points, axis=1, keepdims=True)

    def random(self, rng, count):
        points = rng.standard_normal((count, 3))
        return points / np.linalg.norm(points, axis=1, keepdims=True)
