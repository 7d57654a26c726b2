"""Pipelines: a run from its inputs to its outputs' bytes, recipe -> problem -> solve -> drawing -> outputs, the
one layer between the command line and the method.

Modules: ``image`` (one image on the torus: ``stipple torus`` and each image of ``stipple batch``), ``colour``
(one layer of dots per ink), ``inputs`` (saved points, ``--init`` starts, the canvas of saved torus points),
``outputs`` (each format's bytes: points as CSV or GeoJSON, pictures from one ``Drawing``). A video's pipeline
is ``stipple.video.stipple_video``; a batch's jobs are ``stipple.batch``'s. The public names load on first use.
"""

from ..lazy import lazy_names

_WHERE = {
    "TorusRecipe": ".image",
    "ImageOutputs": ".image",
    "stipple_image": ".image",
    "ColourRecipe": ".colour",
    "stipple_colour": ".colour",
    "read_points": ".inputs",
}
__all__ = sorted(_WHERE)
__getattr__ = lazy_names(__name__, _WHERE)
