"""One-line drawings: an image drawn as one closed polygon whose length measure minimises the discrepancy.

Modules: ``problem`` (the curve's problem, ``LineProblem``, and its defaults: length, bandwidth, subdivisions),
``draw`` (``draw_line``: the phases that drive the speed penalty up until every segment has the same length),
``terms`` (the curve's objectives: the speed penalty and the quadrature nodes along the segments), ``start`` (the
first loop: a tour of density samples shortened by ``stipple.tours.two_opt``, resampled). ``stipple line`` and the
vpype plugin call ``draw_line`` and ``line_points``.
"""

from .draw import draw_line, line_points
from .problem import LINE_ITERATIONS, LineProblem, default_length, line_problem

__all__ = ["LINE_ITERATIONS", "LineProblem", "default_length", "draw_line", "line_points", "line_problem"]
