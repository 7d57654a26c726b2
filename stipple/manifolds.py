"""Geometry of the point sets: the torus (T²)^M, the sphere (S²)^M, and the image's rectangle (one-line drawings).

The optimiser only calls these methods, so one CG serves both domains. Points are ``(M, 2)`` arrays
in [0, 1)² on the torus and ``(M, 3)`` unit vectors on the sphere; tangent vectors have the same shape.
"""

import numpy as np

from .parallel import map_blocks, sum_blocks
from .sampling import pixel_indices, wrap_unit


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
        return wrap_unit(points + v)

    def transport(self, points, v, w):
        """Parallel transport along ``exp(t v)`` is the identity on a flat torus."""
        return w

    def canonical(self, points):
        """Points wrapped into [0, 1)²."""
        return wrap_unit(points)

    def random(self, rng, count):
        return rng.random((count, 2))

    @property
    def area(self):
        """The domain's area in the metric's units (of ``scale``)."""
        return float(np.prod(self.scale))

    def offset(self, points, lengths, angles):
        """Each point moved ``lengths`` (in the units of ``scale``) in the direction at ``angles`` from the x axis."""
        directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
        return self.retract(points, np.asarray(lengths, dtype=float)[:, None] * directions / self.scale)


class PointFactors:
    """A factor (or a row of them) per point from a lookup, kept for the last ``points`` array, which CG asks about
    several times per iteration (read-only): the per-dot scale of ``ScaledTorus`` and ``ScaledSphere``."""

    def __init__(self, lookup):
        self.lookup = lookup
        self._cached = None

    def __call__(self, points):
        if self._cached is not None and self._cached[0] is points:
            return self._cached[1]
        values = np.asarray(self.lookup(points), dtype=float)
        values.flags.writeable = False
        self._cached = (points, values)
        return values


class ScaledTorus(Torus):
    """The torus with the metric scaled at every point by a factor read from a field over the image's cells.

    ``<u, v> = sum_i f(p_i) sum_j scale_j^2 u_ij v_ij``: CG in this metric is CG preconditioned by ``1 / f(p_i)``
    per dot (a Jacobi preconditioner). On the torus ``f`` is the local stiffness of the dots' arrangement, which
    grows with the density (``stipple.torus.stiffness_field``): in the Euclidean metric the one Newton step of an
    iteration is sized for the densest region, and dots in light regions settle many times more slowly.

    Parameters
    ----------
    scale : array_like
        As for ``Torus``.
    field : array_like, shape (H, W)
        Positive factors per cell, row 0 at the top (y down), like the image.
    """

    def __init__(self, scale, field):
        super().__init__(scale)
        self.field = np.asarray(field, dtype=float)
        if self.field.ndim != 2 or not np.all(np.isfinite(self.field)) or not np.all(self.field > 0):
            raise ValueError("field must be a 2-D array of positive numbers")
        self.factor = PointFactors(lambda points: self.field[pixel_indices(points, self.field.shape)])
        # Per dot, the metric's weight of each coordinate and its reciprocal: one product per inner product and
        # per Riesz map instead of a three-operand einsum and a division (a sixth of an iteration's time at M =
        # 200000 was the main thread's vector arithmetic).
        self._weights = PointFactors(lambda points: self.factor(points)[:, None] * self._metric)
        self._inverse = PointFactors(lambda points: 1.0 / self._weights(points))

    def inner(self, points, u, v):
        return float(np.einsum("i,i->", (u * v).ravel(), self._weights(points).ravel()))

    def riesz(self, points, covector):
        return covector * self._inverse(points)


class PinnedTorus(Torus):
    """A torus manifold ``base`` (``Torus`` or ``ScaledTorus``) with some points held where they are (a video's
    still dots, ``stipple.video``).

    The metric is ``base``'s; every gradient and every transported direction is zero at the pinned points, so CG
    moves only the free ones.

    Parameters
    ----------
    base : Torus
        The manifold whose metric the free points keep.
    free : array_like of bool, shape (M,)
        The points that may move.
    """

    def __init__(self, base, free):
        super().__init__(base.scale)
        self.base = base
        self.free = np.asarray(free, dtype=bool)[:, None]

    def inner(self, points, u, v):
        return self.base.inner(points, u, v)

    def riesz(self, points, covector):
        return np.where(self.free, self.base.riesz(points, covector), 0.0)

    def transport(self, points, v, w):
        return np.where(self.free, w, 0.0)


class Sphere:
    """Unit sphere S² with tangent vectors in R³ (nothing is singular at the poles).

    The per-point arithmetic runs in row blocks on ``threads`` (``stipple.parallel``): the same values as in one
    piece, and inner products added block by block in order (the same bits for the same thread count). At M =
    200000 it was a fifth of an iteration's time on one thread while the other waited.
    """

    dimension = 3

    def __init__(self, threads=1):
        self.threads = threads
        # The last ``(points, step, geodesics)`` of ``_geodesics``.
        self._last = None

    def inner(self, points, u, v):
        return sum_blocks(self.threads, _dot_rows, u, v)

    def norm(self, points, v):
        return np.sqrt(self.inner(points, v, v))

    def project(self, points, v):
        """Tangential part ``v - (x . v) x`` at every point."""
        return self._rows(_project_rows, points, v)

    def riesz(self, points, covector):
        return self.project(points, covector)

    def retract(self, points, v):
        """Exponential map ``cos|v| x + sin|v| v/|v|``, re-normalised against drift."""
        return self._geodesics(points, v)[3]

    def transport(self, points, v, w):
        """Parallel transport of ``w`` along the geodesic ``t -> exp_x(t v)`` to ``t = 1``: its component along
        the unit direction ``u`` of ``v`` turns into ``cos|v| u - sin|v| x``, the rest stays."""
        return self._rows(_transport_rows, w, points, *self._geodesics(points, v))

    def _geodesics(self, points, v):
        """``(cos|v|, sin|v|, v / |v|, exp_x(v))`` per point, kept for the last ``(points, v)`` pair: CG retracts
        along its step and then transports two vectors along the same step."""
        if self._last is not None and self._last[0] is points and self._last[1] is v:
            return self._last[2]
        geodesics = (np.empty((len(v), 1)), np.empty((len(v), 1)), np.empty_like(v), np.empty_like(v))
        map_blocks(self.threads, _geodesic_rows, *geodesics, points, v)
        self._last = (points, v, geodesics)
        return geodesics

    def _rows(self, function, like, *arrays):
        """``function(out, like, *arrays)`` per row block, into a new array ``out`` shaped like ``like``."""
        out = np.empty_like(like)
        map_blocks(self.threads, function, out, like, *arrays)
        return out

    def canonical(self, points):
        """Points scaled onto the unit sphere."""
        return points / np.linalg.norm(points, axis=1, keepdims=True)

    def random(self, rng, count):
        points = rng.standard_normal((count, 3))
        return points / np.linalg.norm(points, axis=1, keepdims=True)

    area = 4 * np.pi

    def offset(self, points, lengths, angles):
        """Each point moved ``lengths`` (radians) along the great circle at ``angles`` in its tangent plane,
        measured from the tangent ``x × e`` with ``e`` the coordinate axis least aligned with the point ``x``."""
        axes = np.eye(3)[np.argmin(np.abs(points), axis=1)]
        first = np.cross(points, axes)
        first /= np.linalg.norm(first, axis=1, keepdims=True)
        second = np.cross(points, first)
        directions = np.cos(angles)[:, None] * first + np.sin(angles)[:, None] * second
        return self.retract(points, np.asarray(lengths, dtype=float)[:, None] * directions)


def _dot_rows(u, v):
    return float(np.einsum("ij,ij->", u, v))


def _project_rows(out, points, v):
    """``out = v - (x . v) x``: ``Sphere.project``'s rows."""
    np.multiply(np.einsum("ij,ij->i", points, v)[:, None], points, out=out)
    np.subtract(v, out, out=out)


def _transport_rows(out, w, points, cosine, sine, direction, end):
    """``Sphere.transport``'s rows: ``w + (w . u) ((cos - 1) u - sin x)``, projected onto the tangent plane at the
    end point against drift."""
    along = np.einsum("ij,ij->i", w, direction)[:, None]
    _project_rows(out, end, w + along * ((cosine - 1) * direction - sine * points))


def _geodesic_rows(cosine, sine, direction, end, points, v):
    """``Sphere._geodesics``' rows, written into the first four arrays."""
    length = np.sqrt(np.einsum("ij,ij->i", v, v))[:, None]
    np.cos(length, out=cosine)
    np.sin(length, out=sine)
    moved = cosine * points + np.sinc(length / np.pi) * v
    np.divide(moved, np.sqrt(np.einsum("ij,ij->i", moved, moved))[:, None], out=end)
    np.copyto(direction, np.where(length > 0, v / np.where(length > 0, length, 1.0), 0.0))


class ScaledSphere(Sphere):
    """The sphere with the metric scaled at every point, ``<u, v> = sum_i f(p_i) u_i . v_i``: CG preconditioned per
    dot, as on the torus (``ScaledTorus``; ``f`` from ``stipple.sphere.stiffness_map``).

    Parameters
    ----------
    factor_at : callable
        ``(M, 3)`` unit vectors -> ``(M,)`` positive factors.
    threads : int
        As for ``Sphere``.
    """

    def __init__(self, factor_at, threads=1):
        super().__init__(threads)
        self.factor = PointFactors(factor_at)

    def inner(self, points, u, v):
        return sum_blocks(self.threads, _scaled_dot_rows, self.factor(points), u, v)

    def riesz(self, points, covector):
        return self._rows(_scaled_riesz_rows, covector, points, self.factor(points))


def _scaled_dot_rows(factor, u, v):
    return float(np.einsum("i,ij,ij->", factor, u, v))


def _scaled_riesz_rows(out, covector, points, factor):
    _project_rows(out, points, covector)
    np.divide(out, factor[:, None], out=out)


class Rectangle(Torus):
    """The image's rectangle inside a larger torus: a step is clipped to the rectangle instead of wrapped.

    The torus is the image with a blank margin on every side (``stipple.line.blank_margin``). The transforms stay
    periodic, but opposite edges of the image are two margins of white paper apart. Without the margin, vertices clipped
    to the top and to the bottom edge sit on the same line of the torus (on the portrait, M = 20000: PSNR
    22.8/25.0 dB at sigma 2/4 px without it, 26.2/28.1 with it). Points are stored in the torus's unit
    coordinates; ``inward`` and ``outward`` convert from and to the image's unit coordinates.

    Parameters
    ----------
    scale : array_like
        Physical side lengths of the torus (``torus_scale`` of the padded grid).
    low, high : array_like
        Corners ``(x, y)`` of the image's rectangle in the torus's unit coordinates.
    """

    def __init__(self, scale, low=(0.0, 0.0), high=(1.0, 1.0)):
        super().__init__(scale)
        self.low = np.asarray(low, dtype=float)
        self.high = np.asarray(high, dtype=float)

    def retract(self, points, v):
        return np.clip(points + v, self.low, self.high)

    def riesz(self, points, covector):
        """The gradient, less its components into a wall at the vertices resting on one.

        Those components cannot be followed; left in, CG's Newton step and conjugate directions count motion
        that the clip takes away (measured on the portrait: the speed constraint then never held, max/mean
        segment 1.63 after eight penalty phases, against 1.001 after four).
        """
        gradient = super().riesz(points, covector)
        return np.where(self._blocked(points, -gradient), 0.0, gradient)

    def transport(self, points, v, w):
        """``w`` at the retracted points, less its components into a wall there."""
        moved = self.retract(points, v)
        return np.where(self._blocked(moved, w), 0.0, w)

    def _blocked(self, points, motion):
        """Components of ``motion`` that push a vertex resting on a wall further out."""
        return ((points <= self.low) & (motion < 0)) | ((points >= self.high) & (motion > 0))

    def canonical(self, points):
        return np.clip(np.asarray(points, dtype=np.float64), self.low, self.high)

    @property
    def area(self):
        return float(np.prod(self.scale * (self.high - self.low)))

    def inward(self, points):
        """Image unit coordinates to torus unit coordinates."""
        return self.low + np.asarray(points, dtype=np.float64) * (self.high - self.low)

    def outward(self, points):
        """Torus unit coordinates to image unit coordinates."""
        return (np.asarray(points, dtype=np.float64) - self.low) / (self.high - self.low)
