"""``stipple.peaks``: the darkest share of a density's mass found by partial sorting, against the full sort."""

import numpy as np
import pytest

from stipple.peaks import darkest_level, peak_ratio


def sorted_level(values, areas=None, mass_fraction=0.01):
    """The definition: every value sorted, darkest first, and the mass accumulated until its share is reached."""
    values = np.ravel(values).astype(float)
    areas = np.ones_like(values) if areas is None else np.ravel(areas)
    order = np.argsort(values)[::-1]
    mass = np.cumsum(values[order] * areas[order])
    return values[order][min(np.searchsorted(mass, mass_fraction * mass[-1]), len(values) - 1)]


def inputs(rng):
    photo = rng.integers(0, 256, (300, 400)) / 255.0  # many ties, as an 8-bit image has
    peaked = np.full((200, 300), 0.02)
    peaked[100, 150] = 500.0  # one pixel holds far more than 1 % of the mass
    dark_corner = np.full((150, 150), 0.1)
    dark_corner[:20, :20] = 1.0
    return {"photo": photo, "peaked": peaked, "dark corner": dark_corner, "constant": np.full((50, 70), 0.3)}


@pytest.mark.parametrize("name", ["photo", "peaked", "dark corner", "constant"])
@pytest.mark.parametrize("mass_fraction", [0.001, 0.01, 0.2, 1.0])
def test_level_is_the_full_sorts(rng, name, mass_fraction):
    values = inputs(rng)[name]
    level, mean = darkest_level(values, mass_fraction=mass_fraction)
    assert level == sorted_level(values, mass_fraction=mass_fraction)
    assert mean == pytest.approx(values.mean(), rel=1e-12)


@pytest.mark.parametrize("mass_fraction", [0.001, 0.01, 0.3])
def test_areas_where_the_darkest_pixels_hold_little_mass(rng, mass_fraction):
    """With areas (a sphere's map) the darkest 1 % of the cells may hold far less than 1 % of the mass: the
    partial sort widens until they hold it."""
    values = rng.random(20000)
    areas = np.where(values > 0.5, 1e-4, 1.0) * rng.uniform(0.5, 1.5, values.size)
    level, mean = darkest_level(values, areas, mass_fraction)
    assert level == sorted_level(values, areas, mass_fraction)
    assert mean == pytest.approx(np.sum(values * areas) / areas.sum(), rel=1e-12)


def test_peak_ratio_of_exact_cases():
    assert peak_ratio(np.full((40, 60), 0.7)) == 1.0
    bump = np.full((100, 100), 1.0)
    bump[:10, :10] = 11.0  # 1100 of 11000: the darkest 1 % of the mass is inside the square
    assert peak_ratio(bump) == pytest.approx(11.0 / 1.1)
