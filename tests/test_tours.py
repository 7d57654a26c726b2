"""2-opt tours: permutations, never longer, and free of crossings on small exact cases."""

import numpy as np

from stipple.tours import two_opt


def tour_length(points, tour):
    ordered = points[tour]
    return float(np.sum(np.linalg.norm(np.roll(ordered, -1, axis=0) - ordered, axis=1)))


def test_two_opt_uncrosses_a_bow_tie():
    corners = np.array([[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0], [0.5, -0.2]])
    tour = two_opt(corners, [0, 4, 2, 3, 1])
    assert sorted(tour) == list(range(5))
    assert tour_length(corners, tour) == np.float64(tour_length(corners, [0, 4, 2, 1, 3]))


def test_two_opt_shortens_a_random_tour_to_near_the_known_constant(rng):
    points = rng.random((3000, 2))
    start = rng.permutation(3000)
    tour = two_opt(points, start)
    assert sorted(tour) == list(range(3000))
    # A random order is ~0.52 n long; an optimal tour ~0.7124 sqrt(n A) (Beardwood-Halton-Hammersley, plus a
    # boundary term at this n). Candidate-list 2-opt from a random order measured 1.38 times that.
    assert tour_length(points, tour) < 0.05 * tour_length(points, start)
    assert tour_length(points, tour) < 0.7124 * np.sqrt(3000) * 1.45


def path_length(points, order):
    return float(np.sum(np.linalg.norm(np.diff(points[order], axis=0), axis=1)))


def test_an_open_path_has_no_improving_move_left_by_brute_force(rng):
    """With every point a candidate, no reversal of a stretch (ends included) shortens the path: checked over all
    O(n^2) reversals."""
    points = rng.random((40, 2))
    start = rng.permutation(40)
    path = two_opt(points, start, candidates=39, closed=False)
    assert sorted(path) == list(range(40)) and path_length(points, path) < path_length(points, start)
    best = path_length(points, path)
    for first in range(40):
        for last in range(first + 1, 40):
            moved = path.copy()
            moved[first : last + 1] = moved[first : last + 1][::-1]
            assert path_length(points, moved) >= best - 1e-9, (first, last)


def test_an_open_path_keeps_its_ends_free():
    """On a line of points visited out of order, the open path is the line itself, end to end (a closed tour would
    pay for the way back)."""
    points = np.stack([np.arange(6.0), np.zeros(6)], axis=1)
    path = two_opt(points, [0, 3, 1, 4, 2, 5], candidates=5, closed=False)
    assert path_length(points, path) == 5.0
