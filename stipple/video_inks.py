"""A colour video's inks (``stipple video --palette``): one class of dots per ink, the same dots in every frame.

The inks and the dots each gets are fixed by the first frame (``class_counts`` of its inks' masses), so that dot i
is ink c's in every frame; each frame is then the inks' joint problem with those counts (``multiclass_problem``:
every dot carries its frame's share of its ink), and its ``coarse`` version is the same problem at a lower
bandwidth without the near field, for the warm frames' low-frequency correction (``stipple.video``).
"""

from dataclasses import replace

import numpy as np

from .colour import check_union_weight, placement_scale, separate
from .multiclass import class_counts, class_slices, multiclass_problem

# An ink with dots but no ink in a frame gets this even density: its dots spread out (and are drawn with no area).
EMPTY_INK = 1e-6


class Inks:
    """A colour video's inks, fixed by the first frame (or the key frame's densities): their names and colours
    and the dots each gets (in proportion to its ink there, ``class_counts``), so that dot i stays ink i's."""

    def __init__(self, settings, key=None):
        check_union_weight(settings.union_weight)
        self.settings, self.layers, self.counts = settings, None, None
        self.names, self.term_weights = [], []
        self._key = key

    def densities(self, rgb):
        """The inks' densities ``(K, H, W)`` of an RGB frame, in the first frame's order. An ink that has no dot
        is left out; one that has dots but no ink in this frame gets a faint even density (its dots spread out
        and are drawn with no area)."""
        found = {layer.name: layer for layer in separate(rgb, self.settings.palette, self.settings.black)}
        if self.layers is None:
            self._fix([(layer.name, layer.colour) for layer in found.values()], found)
        zeros = np.zeros(rgb.shape[:2])
        stack = np.stack([found[name].density if name in found else zeros for name in self.names])
        if self.settings.placement is not None:
            scale = placement_scale(stack.sum(axis=0), self.settings.placement)
            stack = stack if scale is None else stack * scale
        empty = stack.reshape(len(stack), -1).max(axis=1) <= 0
        stack[empty] = EMPTY_INK
        return stack

    def _fix(self, inks, found):
        masses = [found[name].density.sum() for name, _ in inks]
        if self._key is not None and len(self._key) == len(inks):
            masses = [float(np.sum(density)) for density in self._key]
        counts = class_counts(masses, self.settings.n_points)
        kept = [k for k, count in enumerate(counts) if count > 0]
        self.names = [inks[k][0] for k in kept]
        self.counts = [int(counts[k]) for k in kept]
        slices = class_slices(self.counts)
        self.layers = tuple((inks[k][0], inks[k][1], part) for k, part in zip(kept, slices, strict=True))
        union = float(self.settings.union_weight) if len(kept) > 1 else 0.0
        self.term_weights = [1.0] * len(kept) + [union]

    def problem(self, weights, bandwidth):
        """The joint problem of the inks' densities ``weights`` ``(K, H, W)`` with the dots per ink kept, and its
        ``coarse`` version."""
        settings = self.settings
        options = {
            "backend": settings.backend,
            "threads": settings.threads,
            "epsilon": settings.epsilon,
            "hessian": settings.hessian,
        }

        def joint(bandwidth, near_field):
            return multiclass_problem(
                list(weights),
                settings.n_points,
                bandwidth,
                names=self.names,
                term_weights=self.term_weights,
                counts=self.counts,
                near_field=near_field,
                **options,
            )

        return replace(joint(bandwidth, settings.near_field), coarse=lambda coarse: joint(coarse, False))
