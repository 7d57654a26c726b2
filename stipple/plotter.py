"""Ordering dots for pen plotters: a short pen-up path by greedy nearest neighbour, then 2-opt."""

import numpy as np
from scipy.spatial import cKDTree

NEIGHBOURS = 8


def path_length(centres):
    """Total travel between consecutive dots, in the units of ``centres``."""
    return float(np.sum(np.linalg.norm(np.diff(centres, axis=0), axis=1)))


def greedy_order(centres):
    """Visit order starting at the dot nearest the origin, always moving to the nearest unvisited dot."""
    count = len(centres)
    tree = cKDTree(centres)
    visited = np.zeros(count, dtype=bool)
    order = np.empty(count, dtype=int)
    current = int(np.argmin(np.sum(centres**2, axis=1)))
    for step in range(count):
        order[step] = current
        visited[current] = True
        if step == count - 1:
            break
        k = NEIGHBOURS
        while True:
            _, candidates = tree.query(centres[current], k=min(k, count))
            free = [c for c in np.atleast_1d(candidates) if not visited[c]]
            if free:
                current = int(free[0])
                break
            if k >= count:
                current = int(np.flatnonzero(~visited)[0])
                break
            k *= 4
    return order


def two_opt(centres, order, passes=4):
    """Improve an open path by 2-opt moves between each dot and its nearest neighbours."""
    order = order.copy()
    count = len(order)
    if count < 4:
        return order
    position = np.empty(count, dtype=int)
    position[order] = np.arange(count)
    _, neighbours = cKDTree(centres).query(centres, k=min(NEIGHBOURS + 1, count))

    def distance(a, b):
        return float(np.sqrt(np.sum((centres[a] - centres[b]) ** 2)))

    for _ in range(passes):
        improved = False
        for i in range(count - 1):
            a, b = order[i], order[i + 1]
            for c in neighbours[a][1:]:
                j = position[c]
                if j <= i + 1:
                    continue
                d_next = distance(c, order[j + 1]) if j + 1 < count else 0.0
                new = distance(a, c) + (distance(b, order[j + 1]) if j + 1 < count else 0.0)
                if new < distance(a, b) + d_next - 1e-12:
                    order[i + 1 : j + 1] = order[i + 1 : j + 1][::-1].copy()
                    position[order[i + 1 : j + 1]] = np.arange(i + 1, j + 1)
                    improved = True
                    break
        if not improved:
            break
    return order


def plotter_order(centres):
    """A short visiting order (greedy nearest neighbour improved by 2-opt) and the path lengths before/after."""
    order = two_opt(centres, greedy_order(centres))
    return order, path_length(centres), path_length(centres[order])
