"""The objective terms of a one-line drawing: constant speed, quadrature nodes along the segments, and which
pairs of nodes the near field leaves out."""

import numpy as np


class SpeedConstraint:
    """``(mu / 2) sum_i (|p_{i+1} - p_i|² / h² - 1)²`` over the segments of a closed polygon: constant speed ``h``.

    Both sides are penalised: the equal-weight quadrature at the vertices is the curve's length measure only if
    the vertices are equally spaced (a shorter segment would put more mass on less ink), so the curve has length
    ``M h = L`` once the constraint holds.

    Parameters
    ----------
    step : float
        Segment length ``h`` (physical units: the image's longer side is 1).
    weight : float
        Penalty weight ``mu``.
    scale : array_like
        Physical side lengths of the unit coordinates (``torus_scale``).
    hessian : {"gauss-newton", "full"}
        "full": the exact second variation. "gauss-newton": the curvature of compressed segments
        (``g_i < 0``) is left out, which keeps the form positive semi-definite for CG's Newton step.
    """

    def __init__(self, step, weight, scale, hessian="gauss-newton"):
        self.step = float(step)
        self.weight = float(weight)
        self.scale = np.asarray(scale, dtype=float)
        self.hessian = hessian

    def set_points(self, points):
        physical = points * self.scale
        self._delta = np.roll(physical, -1, axis=0) - physical
        self._excess = np.einsum("ij,ij->i", self._delta, self._delta) / self.step**2 - 1
        self._bend = self._excess if self.hessian == "full" else np.maximum(self._excess, 0.0)

    def segment_lengths(self):
        return np.sqrt(np.einsum("ij,ij->i", self._delta, self._delta))

    def energy(self):
        return 0.5 * self.weight * float(np.dot(self._excess, self._excess))

    def _scatter(self, segment_vectors):
        """Covector of per-segment physical vectors ``f_i`` (acting on ``p_{i+1} - p_i``) in unit coordinates."""
        return (np.roll(segment_vectors, 1, axis=0) - segment_vectors) * self.scale

    def gradient(self):
        force = (2 * self.weight / self.step**2) * self._excess[:, None] * self._delta
        return self._scatter(force)

    def _differences(self, vector):
        physical = vector * self.scale
        return np.roll(physical, -1, axis=0) - physical

    def hessian_gram(self, vectors):
        """``mu sum_i [4/h⁴ (D_i.a_i)(D_i.b_i) + 2 g_i/h² a_i.b_i]`` with ``a_i, b_i`` the fields' differences."""
        differences = [self._differences(v) for v in vectors]
        radial = [np.einsum("ij,ij->i", self._delta, d) for d in differences]
        count = len(vectors)
        gram = np.empty((count, count))
        for a in range(count):
            for b in range(a, count):
                along = 4 / self.step**4 * np.dot(radial[a], radial[b])
                across = 2 / self.step**2 * np.dot(self._bend, np.einsum("ij,ij->i", differences[a], differences[b]))
                gram[a, b] = gram[b, a] = self.weight * (along + across)
        return gram

    def hessian_vectors(self, vectors):
        products = []
        for vector in vectors:
            difference = self._differences(vector)
            radial = np.einsum("ij,ij->i", self._delta, difference)
            segment = 4 / self.step**4 * radial[:, None] * self._delta
            segment += 2 / self.step**2 * self._bend[:, None] * difference
            products.append(self._scatter(self.weight * segment))
        return products


class CurveNodes:
    """An objective of quadrature nodes along the polygon, pulled back to its vertices.

    Node ``k`` of segment ``i`` is ``p_i + (k / K) (p_{i+1} - p_i)``, ``k = 0..K-1``: with equal weights, the
    composite trapezoidal rule of the curve's length measure on its ``K M`` nodes (``K = 1``: the vertices).
    The map ``B`` from vertices to nodes is linear, so the energy is ``E(B p)``, the gradient ``B^T grad E``, and
    the Hessian ``B^T H B``.

    Parameters
    ----------
    inner : objective
        Defined on the ``K M`` nodes, in segment order.
    subdivisions : int
        Nodes per segment ``K``.
    """

    def __init__(self, inner, subdivisions):
        self.inner = inner
        self.subdivisions = int(subdivisions)
        self._along = np.arange(self.subdivisions) / self.subdivisions

    def nodes(self, points):
        """``B p``: the ``K M`` nodes of the polygon through ``points`` (M, 2)."""
        following = np.roll(points, -1, axis=0)
        nodes = points[:, None, :] + self._along[None, :, None] * (following - points)[:, None, :]
        return nodes.reshape(-1, points.shape[1])

    def pull_back(self, node_covectors):
        """``B^T c``: a covector on the nodes as one on the vertices."""
        per_segment = node_covectors.reshape(-1, self.subdivisions, node_covectors.shape[1])
        start = np.einsum("k,ikd->id", 1 - self._along, per_segment)
        return start + np.roll(np.einsum("k,ikd->id", self._along, per_segment), 1, axis=0)

    def set_points(self, points):
        self.inner.set_points(self.nodes(points))

    def energy(self):
        return self.inner.energy()

    def gradient(self):
        return self.pull_back(self.inner.gradient())

    def hessian_gram(self, vectors):
        return self.inner.hessian_gram([self.nodes(vector) for vector in vectors])

    def hessian_vectors(self, vectors):
        products = self.inner.hessian_vectors([self.nodes(vector) for vector in vectors])
        return [self.pull_back(product) for product in products]


def curve_neighbours(count, steps):
    """``exclude(first, second)`` for ``NearField``: pairs fewer than ``steps + 1`` apart along a closed curve."""

    def exclude(first, second):
        gap = np.abs(first - second)
        return np.minimum(gap, count - gap) <= steps

    return exclude
