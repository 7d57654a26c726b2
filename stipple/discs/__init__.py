"""EXPERIMENTAL: dots as discs, their positions and sizes optimised together by the same CG (docs/discs.md).

No command uses it yet; ``bench/discs.py`` compares it with sizes set after the fact (``stipple.tone``). Its
interface may change.

Modules: ``problem`` (``disc_problem`` and ``optimise_discs``: the problem and its run), ``measure`` (the discs'
measure: its Fourier coefficients by a separable approximation, its discrepancy and the metric of the sizes).
"""

from .measure import DiscFactors, disc_factor
from .problem import DiscProblem, DiscResult, disc_problem, optimise_discs, tone_radius

__all__ = ["DiscFactors", "DiscProblem", "DiscResult", "disc_factor", "disc_problem", "optimise_discs", "tone_radius"]
