"""The short range of the kernel, summed directly over neighbouring pairs.

A bandlimited kernel cannot repel dots closer than about ``1/N``. The kernel is therefore split as
``K = K_R + K_near`` (``stipple.kernels.NearKernel``): the transforms handle the smooth ``K_R`` and this module
the part supported in a ball of radius ``eps``, as the pair energy

    E_near(p) = lam² sum_{i, j} K_near(p_i - p_j)        (``i = j`` included: a constant)

with neighbours found by a k-d tree (periodic on the torus, chordal distance on the sphere) and kept in a Verlet
list: pairs within ``eps (1 + skin)`` are searched again only when a point has moved more than ``eps skin / 2``.
"""

import numpy as np
from scipy.spatial import cKDTree


class TorusPairs:
    """Pairs on the torus ``[0, 1)²`` whose axes have physical lengths ``scale``; distances are physical."""

    def __init__(self, scale):
        self.scale = np.asarray(scale, dtype=float)

    def positions(self, points):
        return np.mod(points, 1.0) * self.scale

    def pairs(self, positions, radius):
        tree = cKDTree(positions, boxsize=self.scale * (1 + 1e-12))
        return tree.query_pairs(radius, output_type="ndarray")

    def displacement(self, start, end):
        """Shortest periodic displacement from ``end`` to ``start`` (``start - end``), row by row."""
        delta = start - end
        delta -= self.scale * np.round(delta / self.scale)
        return delta

    def to_physical(self, vectors):
        """Tangent vectors in unit coordinates as physical displacements."""
        return vectors * self.scale

    def covector(self, physical_gradient):
        """A gradient with respect to physical positions as a differential in unit coordinates."""
        return physical_gradient * self.scale


class SpherePairs:
    """Pairs of unit vectors by chordal distance; tangent vectors are ambient vectors in R³."""

    def positions(self, points):
        return points

    def pairs(self, positions, radius):
        return cKDTree(positions).query_pairs(radius, output_type="ndarray")

    def displacement(self, start, end):
        return start - end

    def to_physical(self, vectors):
        return vectors

    def covector(self, physical_gradient):
        return physical_gradient


class NearField:
    """``lam² factor sum_{i,j} K_near(|x_i - x_j|)`` as an objective: energy, differential, Hessian forms.

    Parameters
    ----------
    kernel : NearKernel
        The short-range kernel and its support radius (physical units, chordal on the sphere).
    weight : float
        Quadrature weight ``lam`` of every point.
    geometry : TorusPairs or SpherePairs
    factor : float
        Constant in front of the kernel: ``W H / L²`` on the torus (the area of the rectangle), 1 on the sphere.
    hessian : {"gauss-newton", "full"}
        "full": the exact second variation (on the sphere the Riemannian one, with the Weingarten term).
        "gauss-newton": a positive semi-definite stand-in that takes the absolute value of the radial and
        tangential curvatures of each pair, so that the Newton step of CG stays a descent step.
    skin : float
        Verlet-list margin as a fraction of the radius.
    exclude : callable, optional
        ``exclude(first, second) -> bool array``: index pairs left out of the sum (e.g. neighbours along a curve).
    """

    def __init__(self, kernel, weight, geometry, factor=1.0, hessian="gauss-newton", skin=0.3, exclude=None):
        self.kernel = kernel
        self.geometry = geometry
        self.pair_factor = 2 * weight**2 * factor
        self.self_energy_per_point = weight**2 * factor * float(kernel.values(np.zeros(1))[0][0])
        self.hessian = hessian
        self.skin = skin
        self.exclude = exclude
        self._reference = None
        self.counts = {"pair_searches": 0}

    def set_points(self, points):
        """Find the pairs closer than the radius and evaluate the kernel on them."""
        positions = self.geometry.positions(points)
        self._update_candidates(positions)
        first, second = self._candidates
        delta = self.geometry.displacement(positions[first], positions[second])
        distance = np.sqrt(np.einsum("ij,ij->i", delta, delta))
        inside = np.flatnonzero(distance < self.kernel.radius)
        first, second, delta, distance = first[inside], second[inside], delta[inside], distance[inside]
        value, slope, curvature = self.kernel.values(distance)
        safe = np.maximum(distance, 1e-9 * self.kernel.radius)
        self._points = points
        self._pairs = (first, second, len(points))
        self._unit = delta / safe[:, None]
        self._energy = self.self_energy_per_point * len(points) + self.pair_factor * float(value.sum())
        self._slope = np.where(distance > 0, slope, 0.0)
        self._radial, self._tangential = curvature, slope / safe
        if self.hessian == "gauss-newton":
            self._radial, self._tangential = np.abs(self._radial), np.abs(self._tangential)
        self._radial_excess = self._radial - self._tangential
        self._gradient = None

    def _update_candidates(self, positions):
        """Search pairs within ``radius (1 + skin)`` again once some point moved more than ``radius skin / 2``."""
        if self._reference is not None and len(self._reference) == len(positions):
            moved = self.geometry.displacement(positions, self._reference)
            if np.max(np.einsum("ij,ij->i", moved, moved), initial=0.0) < (self.kernel.radius * self.skin / 2) ** 2:
                return
        found = self.geometry.pairs(positions, self.kernel.radius * (1 + self.skin))
        if self.exclude is not None:
            found = found[~self.exclude(found[:, 0], found[:, 1])]
        self._candidates = (found[:, 0], found[:, 1])
        self._reference = positions.copy()
        self.counts["pair_searches"] += 1

    @property
    def pair_count(self):
        return len(self._pairs[0])

    def energy(self):
        return self._energy

    def gradient(self):
        """``dE/dx_i = 2 lam² factor sum_j K_near'(r_ij) (x_i - x_j) / r_ij`` as a differential."""
        if self._gradient is None:
            force = self.pair_factor * self._slope[:, None] * self._unit
            self._gradient = self._scatter(force)
        return self.geometry.covector(self._gradient)

    def _scatter(self, pair_vectors):
        """``sum_j v_ij`` at ``i`` minus the same at ``j``, for one vector per pair."""
        first, second, count = self._pairs
        columns = [
            np.bincount(first, weights=column, minlength=count) - np.bincount(second, weights=column, minlength=count)
            for column in pair_vectors.T
        ]
        return np.stack(columns, axis=1)

    def _pair_components(self, vector):
        """Radial component and full difference ``d_i - d_j`` of a tangent field, per pair."""
        first, second, _ = self._pairs
        physical = self.geometry.to_physical(vector)
        difference = physical[first] - physical[second]
        return np.einsum("ij,ij->i", difference, self._unit), difference

    def hessian_gram(self, vectors):
        """``G[a, b] = sum_pairs 2 lam² factor (K'' ra rb + K'/r (da . db - ra rb))`` (+ Weingarten, see class)."""
        components = [self._pair_components(v) for v in vectors]
        count = len(vectors)
        gram = np.empty((count, count))
        for a in range(count):
            for b in range(a, count):
                (ra, da), (rb, db) = components[a], components[b]
                across = np.dot(self._tangential, np.einsum("ij,ij->i", da, db))
                along = np.dot(self._radial_excess, ra * rb)
                gram[a, b] = gram[b, a] = self.pair_factor * (across + along) + self._weingarten(vectors[a], vectors[b])
        return gram

    def hessian_vectors(self, vectors):
        """The same Hessian applied to each field (as differentials)."""
        products = []
        for vector in vectors:
            radial, difference = self._pair_components(vector)
            along = radial[:, None] * self._unit
            pair_vectors = self._radial[:, None] * along + self._tangential[:, None] * (difference - along)
            product = self.geometry.covector(self._scatter(self.pair_factor * pair_vectors))
            products.append(product + self._weingarten_vector(vector))
        return products

    def _curvature_weights(self):
        """``-(x_i . dE/dx_i)``: the sphere's second fundamental form against the ambient gradient."""
        if self.hessian != "full" or not isinstance(self.geometry, SpherePairs):
            return None
        return -np.einsum("ij,ij->i", self._points, self.gradient())

    def _weingarten(self, u, v):
        weights = self._curvature_weights()
        return 0.0 if weights is None else float(np.dot(weights, np.einsum("ij,ij->i", u, v)))

    def _weingarten_vector(self, vector):
        weights = self._curvature_weights()
        return 0.0 if weights is None else weights[:, None] * vector
