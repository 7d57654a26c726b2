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
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from . import allocator
from .errors import StippleError
from .parallel import map_blocks, map_items


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
        """One component of differences of positions in ``[0, scale)``, made shortest along ``axis`` (in place;
        two masked passes, about a third of the time of ``np.rint``'s division and product)."""
        length = self.scale[axis]
        np.subtract(delta, length, out=delta, where=delta > length / 2)
        np.add(delta, length, out=delta, where=delta < -length / 2)
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


@dataclass
class _PairBlock:
    """The pairs of one block closer than the radius: indices, the sum of their kernel values, ``K'/r`` (the
    force), the Hessian's curvatures (``tangential`` ``K'/r`` and ``excess`` ``(K'' - K'/r) / r²``, both made
    positive for the Gauss-Newton stand-in) and the displacements from ``second`` to ``first`` (one array per
    coordinate)."""

    first: np.ndarray
    second: np.ndarray
    value_sum: float
    force: np.ndarray
    tangential: np.ndarray
    excess: np.ndarray
    delta: list


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

        The pairs stay in the blocks in which they were found (``_PairBlock``, one per thread): the gradient and
        the Hessian forms are summed block by block on the same threads and the blocks' sums added in block
        order, so the results do not depend on scheduling.
        """
        positions = self.geometry.positions(points)
        self._update_candidates(positions)
        first, second = self._candidates
        if self.exclude is not None:
            kept = ~self.exclude(first, second)
            first, second = first[kept], second[kept]
        columns = np.ascontiguousarray(positions.T)
        self._blocks = map_blocks(self.threads, functools.partial(self._pair_block, columns), first, second)
        self._points = points
        value_sum = sum(block.value_sum for block in self._blocks)
        self._energy = self.self_energy_per_point * len(points) + self.pair_factor * value_sum
        self._gradient = None

    def _pair_block(self, columns, first, second):
        """The candidate pairs ``(first, second)`` of one block that lie closer than the radius."""
        delta = [self.geometry.wrap(_difference(column, first, second), axis) for axis, column in enumerate(columns)]
        square = _sum_of_squares(delta)
        inside = np.flatnonzero(square < self.kernel.radius**2)
        distance = np.maximum(np.sqrt(square[inside]), 1e-9 * self.kernel.radius)
        distance_square = distance * distance
        value_sum, force, curvature = self.kernel.pair_terms(distance, distance_square)
        radial, tangential = curvature, force
        if self.hessian == "gauss-newton":
            radial, tangential = np.abs(radial, out=radial), np.abs(tangential)
        excess = np.subtract(radial, tangential, out=radial)
        return _PairBlock(
            first=first.take(inside),
            second=second.take(inside),
            value_sum=value_sum,
            force=force,
            tangential=tangential,
            excess=np.divide(excess, distance_square, out=excess),
            delta=[component.take(inside) for component in delta],
        )

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
        reach = self.kernel.radius * (1 + self.skin)
        check_pair_memory(self._tree, positions, reach)
        found = self._tree.query_pairs(reach, output_type="ndarray")
        self._verlet = self._candidates = _ordered(found[:, 0], found[:, 1], len(positions))
        self._reference = positions.copy()
        self.counts["pair_searches"] += 1

    @property
    def pair_count(self):
        return sum(len(block.first) for block in self._blocks)

    def pairs(self):
        """``(first, second)``: the pairs closer than the radius, in index order."""
        return tuple(_concatenate([getattr(block, name) for block in self._blocks]) for name in ("first", "second"))

    def energy(self):
        return self._energy

    def gradient(self):
        """``dE/dx_i = 2 lam² factor sum_j K_near'(r_ij) (x_i - x_j) / r_ij`` as a differential."""
        if self._gradient is None:
            self._gradient = self.geometry.covector(self._sum_over_blocks(self._block_gradient))
            # Kept for later calls and returned as it is (not copied): read-only.
            self._gradient.flags.writeable = False
        return self._gradient

    def _block_gradient(self, block):
        force = self.pair_factor * block.force
        return self._scatter(block, [force * component for component in block.delta])

    def _sum_over_blocks(self, function):
        """``function(block)`` for every block on the threads, the results added in block order."""
        return functools.reduce(np.add, map_items(self.threads, function, self._blocks))

    def _scatter(self, block, pair_components):
        """``sum_j v_ij`` at ``i`` minus the same at ``j``, for one vector per pair of ``block`` (by components)."""
        count = len(self._points)
        columns = [
            np.bincount(block.first, weights=column, minlength=count)
            - np.bincount(block.second, weights=column, minlength=count)
            for column in pair_components
        ]
        return np.stack(columns, axis=1)

    def _pair_components(self, block, columns):
        """``(d_i - d_j) . (x_i - x_j)`` and the components of ``d_i - d_j`` of a tangent field (given by its
        physical ``columns``), per pair of ``block``."""
        difference = [column[block.first] - column[block.second] for column in columns]
        along = sum(component * delta for component, delta in zip(difference, block.delta, strict=True))
        return along, difference

    def _physical_columns(self, vector):
        return np.ascontiguousarray(self.geometry.to_physical(vector).T)

    def hessian_gram(self, vectors):
        """``G[a, b] = sum_pairs 2 lam² factor (K'' ra rb + K'/r (da . db - ra rb))`` (+ Weingarten, see class)."""
        columns = [self._physical_columns(vector) for vector in vectors]
        gram = self.pair_factor * self._sum_over_blocks(functools.partial(self._block_gram, columns))
        for a in range(len(vectors)):
            for b in range(a, len(vectors)):
                gram[a, b] += self._weingarten(vectors[a], vectors[b])
                gram[b, a] = gram[a, b]
        return gram

    def _block_gram(self, columns, block):
        """``sum_pairs (K'' - K'/r) ra rb + K'/r da . db`` of one block, for every pair of fields (``ra``: the
        radial component ``da . (x_i - x_j) / r``, here as ``excess`` times the two dot products)."""
        components = [self._pair_components(block, field) for field in columns]
        gram = np.empty((len(columns), len(columns)))
        for a in range(len(columns)):
            for b in range(a, len(columns)):
                (dot_a, da), (dot_b, db) = components[a], components[b]
                across = sum(np.einsum("i,i,i->", block.tangential, x, y) for x, y in zip(da, db, strict=True))
                along = np.einsum("i,i,i->", block.excess, dot_a, dot_b)
                gram[a, b] = gram[b, a] = across + along
        return gram

    def hessian_vectors(self, vectors):
        """The same Hessian applied to each field (as differentials)."""
        products = []
        for vector in vectors:
            block_product = functools.partial(self._block_hessian_vector, self._physical_columns(vector))
            product = self.geometry.covector(self._sum_over_blocks(block_product))
            products.append(product + self._weingarten_vector(vector))
        return products

    def _block_hessian_vector(self, columns, block):
        along, difference = self._pair_components(block, columns)
        radial = block.excess * along
        pair_components = [
            self.pair_factor * (radial * delta + block.tangential * component)
            for component, delta in zip(difference, block.delta, strict=True)
        ]
        return self._scatter(block, pair_components)

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


def _difference(column, first, second):
    """``column[first] - column[second]`` with one temporary array fewer (the same values)."""
    difference = column.take(first)
    return np.subtract(difference, column.take(second), out=difference)


def _sum_of_squares(components):
    """``sum(c * c for c in components)``, in place: the same additions in the same order."""
    total = components[0] * components[0]
    square = np.empty_like(total)
    for component in components[1:]:
        total += np.multiply(component, component, out=square)
    return total


# What a candidate pair costs (its indices, its block's arrays, the temporaries): 4000 coincident dots, 8.0 million
# pairs, raised stipple evaluate's peak by 0.94 GB (118 bytes a pair). PAIR_SAMPLE points, or one in
# PAIR_SAMPLE_EVERY where there are more, estimate the pairs: a clump that cannot fit (about 16000 coincident
# points in 20 GiB) then holds at least four of them however many points there are.
PAIR_BYTES, PAIR_SAMPLE, PAIR_SAMPLE_EVERY = 150, 1000, 4000


def check_pair_memory(tree, positions, reach):
    """Refuse ``positions`` so clumped that their pairs within ``reach`` would not fit in the memory available,
    estimated from the neighbours of evenly chosen points (``tree`` holds ``positions``). 40000
    coincident dots given to ``stipple evaluate`` asked for 800 million pairs, and the kernel's OOM killer ended
    the process after a minute."""
    count = min(len(positions), max(PAIR_SAMPLE, len(positions) // PAIR_SAMPLE_EVERY))
    sample = positions[np.linspace(0, len(positions) - 1, count).astype(np.intp)]
    neighbours = np.asarray(tree.query_ball_point(sample, reach, return_length=True)) - 1
    pairs = float(neighbours.mean()) * len(positions) / 2
    available = allocator.available_memory()
    if pairs * PAIR_BYTES > available:
        raise StippleError(
            f"the points are clumped: about {pairs:.2g} pairs lie within reach of each other, "
            f"needing about {pairs * PAIR_BYTES / 2**30:.1f} GiB, more than the {available / 2**30:.1f} GiB "
            "available (many points in one place?)"
        )


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
