"""How peaked a density is: the level above which its darkest share of the mass lies, against its mean."""

import numpy as np


def darkest_level(values, areas=None, mass_fraction=0.01):
    """The density level above which ``mass_fraction`` of the mass lies (blind to a few dark pixels that hold
    little mass, unlike the maximum), and the mean density: ``(level, mean)``."""
    values = np.asarray(values, dtype=float).ravel()
    masses = values if areas is None else values * np.ravel(areas)
    total = float(np.sum(masses))
    # Only the darkest values are sorted (a 12-megapixel photo took 1.7 s a call to sort them all): the darkest
    # mass_fraction of the pixels hold at least mass_fraction of the mass where every pixel has the same area.
    count = max(1, int(np.ceil(mass_fraction * len(values))))
    while True:
        darkest = np.argpartition(values, len(values) - count)[len(values) - count :]
        darkest = darkest[np.argsort(values[darkest], kind="stable")[::-1]]
        mass = np.cumsum(masses[darkest])
        if mass[-1] >= mass_fraction * total or count == len(values):
            break
        count = min(2 * count, len(values))
    level = values[darkest][min(np.searchsorted(mass, mass_fraction * total), count - 1)]
    return float(level), total / (len(values) if areas is None else np.sum(areas))


def peak_ratio(values, areas=None, mass_fraction=0.01):
    """How much denser than average the densest ``mass_fraction`` of the density is: ``darkest_level`` over the
    mean density, 1 for a constant density, about the peak-to-mean ratio for a bump."""
    if np.ptp(values) == 0:  # constant (the even input a peak is compared with): no sort at all
        return 1.0
    level, mean = darkest_level(values, areas, mass_fraction)
    return float(max(level / mean, 1.0))
