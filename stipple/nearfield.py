"""The short range of the kernel, summed directly over neighbouring pairs.

A bandlimited kernel cannot repel dots closer than about ``1/N``. The kernel is therefore split as
``K = K_R + K_near`` (``stipple.kernels.NearKernel``): the transforms handle the smooth ``K_R`` and this module
the part supported in a ball of radius ``eps``, as the pair energy

    E_near(p) = lam² sum_{i, j} K_near(p_i - p_j)        (``i = j`` included: a constant)

with neighbours found by a k-d tree (periodic on the torus, chordal distance on the sphere) and kept in a Verlet
list: pairs within ``eps (1 + skin)`` are searched again only when many points have moved more than
``eps skin / 2``; the few that did are looked up on their own.
"""

import functools

import numpy as np
from scipy.spatial import cKDTree

from .parallel import map_blocks


class TorusPairs:
    """Pairs on the torus ``[0, 1)²`` whose axes have physical lengths ``scale``; distances are physical."""

    def __init__(self, scale):
        self.scale = np.asarray(scale, dtype=float)
        # A square image needs no scaling (each (M, 2) product took about 10 ms at M = 10^6).
        self._unit_square = bool(np.all(self.scale == 1))

    def positions(self, points):
        """Physical positions in ``[0, scale)`` (``np.mod`` only when needed: it is slow, and CG's points are
        already wrapped)."""
        if points.min(initial=0.0) < 0 or points.max(initial=0.0) >= 1:
            points = np.mod(points, 1.0)
        return points if self._unit_square else points * self.scale

    def tree(self, positions):
        return cKDTree(positions, boxsize=self.scale * (1 + 1e-12))

    def displacement(self, start, end):
        """Shortest periodic displacement from ``end`` to ``start`` (``start - end``), row by row."""
        delta = start - end
        for axis in range(delta.shape[1]):
            self.wrap(delta[:, axis], axis)
        return delta

    def wrap(self, delta, axis):
        """One component of displacements, made shortest along ``axis`` (in place)."""
        delta -= self.scale[axis] * np.rint(delta / self.scale[axis])
        return delta

    def to_physical(self, vectors):
        """Tangent vectors in unit coordinates as physical displacements."""
        return vectors if self._unit_square else vectors * self.scale

    def covector(self, physical_gradient):
        """A gradient with respect to physical positions as a differential in unit coordinates."""
        return physical_gradient if self._unit_square else physical_gradient * self.scale


class SpherePairs:
    """Pairs of unit vectors by chordal distance; tangent vectors are ambient vectors in R³."""

    def positions(self, points):
        return points

    def tree(self, positions):
        return cKDTree(positions)

    def displacement(self, start, end):
        return start - end

    def wrap(self, delta, axis):
        return delta

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
    threads : int
        Threads for the per-pair arithmetic (blocks of pairs, ``stipple.parallel``): the same bits for the same
        count.
    """

    def __init__(self, kernel, weight, geometry, factor=1.0, hessian="gauss-newton", skin=0.3, exclude=None, threads=1):
        self.kernel = kernel
        self.geometry = geometry
        self.pair_factor = 2 * weight**2 * factor
        self.self_energy_per_point = weight**2 * factor * float(kernel.values(np.zeros(1))[0][0])
        self.hessian = hessian
        self.skin = skin
        self.exclude = exclude
        self.threads = threads
        self._reference = None
        self.counts = {"pair_searches": 0}

    def set_points(self, points):
        """Find the pairs closer than the radius and evaluate the kernel on them.

        Per-pair quantities are kept as one 1-D array per coordinate: numpy's reductions over them are several
        times faster than over ``(pairs, 2)`` arrays.
        """
        positions = self.geometry.positions(points)
        self._update_candidates(positions)
        first, second = self._candidates
        if self.exclude is not None:
            kept = ~self.exclude(first, second)
            first, second = first[kept], second[kept]
        columns = np.ascontiguousarray(positions.T)
        blocks = map_blocks(self.threads, functools.partial(self._pairs_inside, columns), first, second)
        first, second, value_sum, slope, curvature, safe, *unit = (
            _concatenate([block[item] for block in blocks]) for item in range(len(blocks[0]))
        )
        self._points = points
        self._pairs = (first, second, len(points))
        self._unit = unit
        self._energy = self.self_energy_per_point * len(points) + self.pair_factor * float(value_sum.sum())
        self._slope = slope
        self._radial, self._tangential = curvature, slope / safe
        if self.hessian == "gauss-newton":
            self._radial, self._tangential = np.abs(self._radial), np.abs(self._tangential)
        self._radial_excess = self._radial - self._tangential
        self._gradient = None

    def _pairs_inside(self, columns, first, second):
        """The candidate pairs ``(first, second)`` closer than the radius (one block), as ``(first, second,
        [sum of kernel values], slope, curvature, safe distance, *unit vector components)``."""
        delta = [self.geometry.wrap(column[first] - column[second], axis) for axis, column in enumerate(columns)]
        distance = np.sqrt(sum(component * component for component in delta))
        inside = np.flatnonzero(distance < self.kernel.radius)
        distance = distance[inside]
        value, slope, curvature = self.kernel.values_inside(distance)
        safe = np.maximum(distance, 1e-9 * self.kernel.radius)
        unit = [component[inside] / safe for component in delta]
        return first[inside], second[inside], np.array([value.sum()]), slope, curvature, safe, *unit

    def _update_candidates(self, positions):
        """Candidate pairs for the current positions: the Verlet list, patched for the few points that moved far.

        Pairs are kept in index order (``_ordered``). Pairs within ``radius (1 + skin)`` at the reference
        positions contain every pair now within the radius unless one of its points moved more than
        ``radius skin / 2`` (a "mover"). Pairs of movers are taken again from the reference tree (around their
        current positions) and among themselves (a small tree of the movers); the whole list is searched again
        when movers are more than 1 % of the points (at least 16).
        """
        if self._reference is None or len(self._reference) != len(positions):
            return self._search(positions)
        moved = self.geometry.displacement(positions, self._reference)
        limit = self.kernel.radius * self.skin / 2
        movers = np.flatnonzero(np.einsum("ij,ij->i", moved, moved) > limit**2)
        if movers.size > max(16, 0.01 * len(positions)):
            return self._search(positions)
        first, second = self._verlet
        if movers.size == 0:
            self._candidates = self._verlet
            return
        is_mover = np.zeros(len(positions), dtype=bool)
        is_mover[movers] = True
        settled = ~(is_mover[first] | is_mover[second])
        found = self._tree.query_ball_point(positions[movers], self.kernel.radius + limit)
        near_first = np.repeat(movers, [len(items) for items in found])
        near_second = np.concatenate([np.asarray(items, dtype=np.intp) for items in found] + [np.empty(0, np.intp)])
        others = ~is_mover[near_second]
        among = self.geometry.tree(positions[movers]).query_pairs(self.kernel.radius + limit, output_type="ndarray")
        among_first, among_second = among[:, 0], among[:, 1]
        added = _ordered(
            np.concatenate([near_first[others], movers[among_first]]),
            np.concatenate([near_second[others], movers[among_second]]),
            len(positions),
        )
        self._candidates = _merge_ordered((first[settled], second[settled]), added, len(positions))

    def _search(self, positions):
        """A new Verlet list: all pairs within ``radius (1 + skin)``, and the tree for later patches."""
        self._tree = self.geometry.tree(positions)
        found = self._tree.query_pairs(self.kernel.radius * (1 + self.skin), output_type="ndarray")
        self._verlet = self._candidates = _ordered(found[:, 0], found[:, 1], len(positions))
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
            force = self.pair_factor * self._slope
            self._gradient = self.geometry.covector(self._scatter([force * unit for unit in self._unit]))
            # Kept for later calls and returned as it is (not copied): read-only.
            self._gradient.flags.writeable = False
        return self._gradient

    def _scatter(self, pair_components):
        """``sum_j v_ij`` at ``i`` minus the same at ``j``, for one vector per pair (given by components)."""
        first, second, count = self._pairs
        columns = [
            np.bincount(first, weights=column, minlength=count) - np.bincount(second, weights=column, minlength=count)
            for column in pair_components
        ]
        return np.stack(columns, axis=1)

    def _pair_components(self, vector):
        """Radial component and components of the difference ``d_i - d_j`` of a tangent field, per pair."""
        first, second, _ = self._pairs
        columns = np.ascontiguousarray(self.geometry.to_physical(vector).T)
        difference = [column[first] - column[second] for column in columns]
        radial = sum(component * unit for component, unit in zip(difference, self._unit, strict=True))
        return radial, difference

    def hessian_gram(self, vectors):
        """``G[a, b] = sum_pairs 2 lam² factor (K'' ra rb + K'/r (da . db - ra rb))`` (+ Weingarten, see class)."""
        components = [self._pair_components(v) for v in vectors]
        count = len(vectors)
        gram = np.empty((count, count))
        for a in range(count):
            for b in range(a, count):
                (ra, da), (rb, db) = components[a], components[b]
                across = sum(np.einsum("i,i,i->", self._tangential, x, y) for x, y in zip(da, db, strict=True))
                along = np.einsum("i,i,i->", self._radial_excess, ra, rb)
                gram[a, b] = gram[b, a] = self.pair_factor * (across + along) + self._weingarten(vectors[a], vectors[b])
        return gram

    def hessian_vectors(self, vectors):
        """The same Hessian applied to each field (as differentials)."""
        products = []
        for vector in vectors:
            radial, difference = self._pair_components(vector)
            pair_components = [
                self.pair_factor * (self._radial_excess * radial * unit + self._tangential * component)
                for component, unit in zip(difference, self._unit, strict=True)
            ]
            product = self.geometry.covector(self._scatter(pair_components))
            products.append(product + self._weingarten_vector(vector))
        return products

    def _curvature_weights(self):
        """``-(x_i . dE/dx_i)``: the sphere's second fundamental form against the ambient gradient."""
        if self.hessian != "full" or not isinstance(self.geometry, SpherePairs):
            return None
        return -np.einsum("ij,ij->i", self._points, self.gradient())

    def _weingarten(self, u, v):
        weights = self._curvature_weights()
        return 0.0 if weights is None else float(np.einsum("i,ij,ij->", weights, u, v))

    def _weingarten_vector(self, vector):
        weights = self._curvature_weights()
        return 0.0 if weights is None else weights[:, None] * vector


def _concatenate(blocks):
    """One array from one or more blocks (no copy for one)."""
    return blocks[0] if len(blocks) == 1 else np.concatenate(blocks)


def _ordered(first, second, count):
    """Pairs as ``(min, max)``, sorted: the sums then do not depend on how the list was found (so a resumed run,
    which searches its list afresh, repeats the uninterrupted run bit for bit)."""
    low, high = np.minimum(first, second), np.maximum(first, second)
    order = np.argsort(low.astype(np.int64) * count + high, kind="stable")
    return low[order], high[order]


def _merge_ordered(pairs, added, count):
    """Two sorted pair lists with no pair in common as one sorted list."""
    keys = pairs[0].astype(np.int64) * count + pairs[1]
    where = np.searchsorted(keys, added[0].astype(np.int64) * count + added[1])
    return np.insert(pairs[0], where, added[0]), np.insert(pairs[1], where, added[1])
