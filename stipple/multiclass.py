"""Multi-class halftoning: every class of dots and their union reproduce their own densities at once.

For classes ``c`` with densities ``w_c`` and dots ``p[s_c]`` (index slices of one ``(M, 2)`` array) the joint
objective is

    E(p) = sum_c a_c E(p[s_c]; w_c) + a_u E(p; sum_c w_c)

(Wei 2010, *Multi-class blue noise sampling*; Schmaltz et al. 2012 for the electrostatic form): each colour is
a blue-noise stipple of its ink, and so are all dots together, so dots of different colours avoid each other
too. Each term is a torus problem's own objective (discrepancy with its near field) on its subset; the one CG
drives the sum like any other objective.
"""

import hashlib
from dataclasses import dataclass, field

import numpy as np

from .errors import StippleError
from .halftone import Problem, check_bandwidth, check_threads, default_threads, run
from .parallel import map_items
from .torus import DEFAULT_EPSILON, check_weights, default_bandwidth, torus_problem, unit_scaled


def class_counts(masses, total):
    """Dots per class in proportion to the masses, rounded by largest remainder (Hamilton's method).

    Every count is the quota ``total * mass / sum(masses)`` rounded down or up, and the counts add up to
    ``total``; the remainders are handed out largest first (ties to the earlier class).

    Parameters
    ----------
    masses : sequence of float
        Non-negative masses, at least one positive.
    total : int
        Number of dots to share out.

    Returns
    -------
    numpy.ndarray
        Integer counts, one per class.
    """
    masses = np.asarray(masses, dtype=np.float64)
    if masses.ndim != 1 or np.any(masses < 0) or not masses.sum() > 0 or not np.all(np.isfinite(masses)):
        raise StippleError("class masses must be finite, non-negative and not all zero")
    quotas = total * masses / masses.sum()
    counts = np.floor(quotas).astype(int)
    remainders = quotas - counts
    order = np.argsort(-remainders, kind="stable")
    counts[order[: total - counts.sum()]] += 1
    return counts


class MulticlassObjective:
    """``sum_t a_t E_t(p[s_t])``: objectives on index slices of one point array, weighted.

    Parameters
    ----------
    terms : sequence of objects
        Objectives (``set_points``, ``energy``, ``gradient``, ``hessian_gram``, ``hessian_vectors``).
    slices : sequence of slice
        The points each term sees (``slice(None)`` for all of them).
    weights : sequence of float
        The factors ``a_t``.
    threads : int
        Terms evaluated at once on the process's pool (``stipple.parallel``); more than 1 only for terms that use
        no thread of the pool themselves (built with one thread). The terms' results are added in term order:
        the same bits for any count.
    """

    def __init__(self, terms, slices, weights, threads=1):
        if not len(terms) == len(slices) == len(weights):
            raise ValueError("terms, slices and weights must have the same length")
        self.terms = list(terms)
        self.slices = list(slices)
        self.weights = [float(weight) for weight in weights]
        self.threads = threads
        self._shape = None

    def set_points(self, points):
        """Move every term with a non-zero factor to its points."""
        self._shape = points.shape
        # The terms with the most points start first (the union before the inks): the threads then finish nearly
        # together (colour, 100 iterations on 2 cores: 7.0-7.3 s against 9.0 s in term order).
        sizes = [len(points[part]) for _, part, _ in self._weighted()]
        self._order = sorted(range(len(sizes)), key=lambda index: -sizes[index])
        self._each(lambda term, part: term.set_points(points[part]))

    def energy(self):
        return float(sum(weight * term.energy() for term, _, weight in self._weighted()))

    def gradient(self):
        total = np.zeros(self._shape)
        gradients = self._each(lambda term, _: term.gradient())
        for (_, part, weight), gradient in zip(self._weighted(), gradients, strict=True):
            total[part] += weight * gradient
        return total

    def hessian_gram(self, vectors):
        grams = self._each(lambda term, part: term.hessian_gram([v[part] for v in vectors]))
        return sum(weight * gram for (_, _, weight), gram in zip(self._weighted(), grams, strict=True))

    def hessian_vectors(self, vectors):
        products = [np.zeros(self._shape) for _ in vectors]
        values = self._each(lambda term, part: term.hessian_vectors([v[part] for v in vectors]))
        for (_, part, weight), term_products in zip(self._weighted(), values, strict=True):
            for product, value in zip(products, term_products, strict=True):
                product[part] += weight * value
        return products

    def _each(self, function):
        """``[function(term, part) for each weighted term]``, on ``threads`` of the pool in ``_order``."""
        items = self._weighted()
        results = map_items(self.threads, lambda index: function(*items[index][:2]), self._order)
        by_term = dict(zip(self._order, results, strict=True))
        return [by_term[index] for index in range(len(items))]

    def _weighted(self):
        return [item for item in zip(self.terms, self.slices, self.weights, strict=True) if item[2] != 0]


@dataclass
class MulticlassProblem(Problem):
    """A ``Problem`` whose points are classes one after another; ``classes`` are each class's own problem.

    ``discrepancy`` is the union's (``stipple.measures.evaluate`` measures the union on this problem, and a class
    ``c`` on ``classes[c]`` with the points ``points[slices[c]]``).
    """

    names: list = field(default_factory=list)
    classes: list = field(default_factory=list)
    slices: list = field(default_factory=list)


def class_slices(counts):
    """Consecutive slices of a point array holding ``counts[c]`` points of class ``c``."""
    ends = np.cumsum(counts)
    return [slice(int(end - count), int(end)) for count, end in zip(counts, ends, strict=True)]


def class_bandwidth(bandwidth, class_points, n_points):
    """A class's bandwidth for a union bandwidth ``N``: ``N sqrt(M_c / M)`` (even), as the default rule scales."""
    return max(2, int(2 * round(bandwidth * np.sqrt(class_points / n_points) / 2)))


# The terms' problems keep the flat metric and the full default bandwidth: the classes' run stops by ``tol``, whose
# meaning the density-scaled metric would change. At 0.7 of the bandwidth colour's iterations cost a tenth less but
# ``tol`` stopped later, and the held-out pictures did not gain (docs/performance.md, thirteenth round); a
# density-scaled metric per ink changed nothing on colour (same file). Neither was measured on the progressive
# order's levels (docs/plotters.md).
TERM_SETTINGS = {"precondition": False, "bandwidth_factor": 1.0}


def term_problem(density, count, n_points, bandwidth, options):
    """The torus problem of one term: ``count`` of the ``n_points`` dots on ``density``, at its own default
    bandwidth, or ``class_bandwidth`` of the whole set's ``bandwidth`` when given; ``options`` are
    ``torus_problem``'s, with ``TERM_SETTINGS``."""
    band = (
        default_bandwidth(int(count), density)
        if bandwidth is None
        else class_bandwidth(check_bandwidth(bandwidth), count, n_points)
    )
    return torus_problem(density, int(count), band, **options, **TERM_SETTINGS)


def multiclass_problem(
    densities,
    n_points,
    bandwidth=None,
    *,
    names=None,
    term_weights=None,
    backend="ducc0",
    threads=None,
    epsilon=DEFAULT_EPSILON,
    hessian="gauss-newton",
    near_field=True,
    counts=None,
):
    """The joint problem of several densities on one image with ``n_points`` dots in all.

    Parameters
    ----------
    densities : sequence of numpy.ndarray
        One density ``w_c >= 0`` per class, all of the same ``(H, W)`` shape, rows top to bottom.
    n_points : int
        Total number of dots M; class ``c`` gets ``M_c`` of them in proportion to its mass
        (``class_counts``). Classes that get no dot are left out.
    bandwidth : int, optional
        The union's bandwidth (default ``default_bandwidth(M, sum w_c)``); class ``c`` gets its own default
        ``default_bandwidth(M_c, w_c)``, or ``N sqrt(M_c / M)`` when ``bandwidth`` is given.
    names : sequence of str, optional
        Class names (default ``class0``, ``class1``, ...).
    term_weights : sequence of float, optional
        Factors ``a_c`` of the class terms and, last, ``a_u`` of the union term (default all 1).
    backend, threads, epsilon, hessian, near_field :
        As for ``stipple.torus.torus_problem``, for every term.
    counts : sequence of int, optional
        Dots per class, adding up to ``n_points`` (a video keeps them from frame to frame). Each density then
        enters the union's in proportion to its dots: ``w_c (M_c / M) / (m_c / m)``, so that every dot carries the
        same mass in the union's term as in its class's.

    Returns
    -------
    MulticlassProblem
    """
    densities = [check_weights(weights) for weights in densities]
    if not densities or any(weights.shape != densities[0].shape for weights in densities):
        raise StippleError("class densities must be one or more arrays of the same shape")
    peak = max(float(weights.max()) for weights in densities)  # one scale for all: their masses stay in proportion
    densities = [unit_scaled(weights, peak) for weights in densities]
    names = [f"class{index}" for index in range(len(densities))] if names is None else list(names)
    term_weights = [1.0] * (len(densities) + 1) if term_weights is None else [float(a) for a in term_weights]
    if len(names) != len(densities) or len(term_weights) != len(densities) + 1:
        raise StippleError("give one name per class and one term weight per class plus one for the union")
    if not all(np.isfinite(a) and a >= 0 for a in term_weights) or not any(term_weights):
        raise StippleError(f"term weights must be finite, non-negative and not all zero, not {term_weights}")
    masses = np.array([weights.sum() for weights in densities])
    union_density = sum(densities)
    if counts is None:
        counts = class_counts(masses, n_points)
    else:
        counts = np.asarray(counts)
        if counts.shape != masses.shape or np.any(counts < 0) or counts.sum() != n_points:
            raise StippleError(f"class counts must be one per class, non-negative, adding up to {n_points}")
        shares = np.where(masses > 0, (counts / n_points) * masses.sum() / np.maximum(masses, 1e-300), 0.0)
        union_density = sum(share * weights for share, weights in zip(shares, densities, strict=True))
    kept = [index for index, count in enumerate(counts) if count > 0]
    weights = [term_weights[index] for index in kept] + [term_weights[-1]]
    threads = default_threads() if threads is None else check_threads(threads)
    # Several terms run at once, each on one thread: their transforms are too small for the blocks of one term to
    # pay (colour, 100 iterations on 2 cores: 9.3 s against 10.4-10.8 s; docs/performance.md).
    term_threads = 1 if sum(weight != 0 for weight in weights) > 1 else threads
    options = {
        "backend": backend,
        "threads": term_threads,
        "epsilon": epsilon,
        "hessian": hessian,
        "near_field": near_field,
    }
    union = torus_problem(union_density, n_points, bandwidth, **options, **TERM_SETTINGS)
    classes = [term_problem(densities[index], counts[index], n_points, bandwidth, options) for index in kept]
    slices = class_slices(counts[kept])
    terms = [part.objective for part in classes] + [union.objective]
    objective = MulticlassObjective(terms, [*slices, slice(None)], weights, threads=threads if term_threads == 1 else 1)
    return MulticlassProblem(
        domain="torus",
        manifold=union.manifold,
        objective=objective,
        discrepancy=union.discrepancy,
        n_points=union.n_points,
        bandwidth=union.bandwidth,
        sample=lambda rng, count: _sample_classes(classes, rng, count),
        settings={
            **union.settings,
            "classes": [names[index] for index in kept],
            "class_points": [part.n_points for part in classes],
            "class_bandwidths": [part.bandwidth for part in classes],
            "term_weights": weights,
            "class_fingerprint": _fingerprint(classes),
        },
        names=[names[index] for index in kept],
        classes=classes,
        slices=slices,
    )


def _sample_classes(classes, rng, count):
    """``count`` i.i.d. points, each class's share (by its count) from its own density, classes in order."""
    shares = class_counts([part.n_points for part in classes], count)
    return np.concatenate([part.sample(rng, int(share)) for part, share in zip(classes, shares, strict=True)])


def _fingerprint(classes):
    """SHA-256 of the classes' exact Fourier coefficients (the checkpoint's own fingerprint covers the union)."""
    digest = hashlib.sha256()
    for part in classes:
        digest.update(np.ascontiguousarray(part.discrepancy.target).tobytes())
    return digest.hexdigest()


def halftone_classes(densities, n_points, bandwidth=None, *, names=None, term_weights=None, **options):
    """Joint halftone of several densities: ``(problem, result)``; class ``c`` is ``result.points[slices[c]]``.

    ``options`` are ``multiclass_problem``'s (``backend``, ``threads``, ``epsilon``, ``hessian``,
    ``near_field``) and ``stipple.halftone.run``'s (``init``, ``seed``, ``tol``, ``iterations``, ...).
    """
    problem_keys = ("backend", "threads", "epsilon", "hessian", "near_field")
    problem_options = {key: options.pop(key) for key in problem_keys if key in options}
    problem = multiclass_problem(
        densities, n_points, bandwidth, names=names, term_weights=term_weights, **problem_options
    )
    return problem, run(problem, **options)
