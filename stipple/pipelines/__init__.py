"""Pipelines: a run from its inputs to its outputs' bytes, recipe -> problem -> solve -> drawing -> outputs, the
one layer between the command line and the method.

Modules: ``image`` (one image on the torus: ``stipple torus`` and each image of ``stipple batch``), ``colour``
(one layer of dots per ink), ``inputs`` (saved points, ``--init`` starts, the canvas of saved torus points),
``outputs`` (each format's bytes: points as CSV or GeoJSON, pictures from one ``Drawing``).
"""
