import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)


def taylor_slope(function, steps):
    """Least-squares slope of log|remainder| against log(step)."""
    remainders = np.array([abs(function(t)) for t in steps])
    return np.polyfit(np.log(steps), np.log(remainders), 1)[0]
