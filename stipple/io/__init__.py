"""Every reader and writer, one module per format family.

``sources`` (bounded reads), ``images`` (images and maps into densities), ``points`` (point CSVs), ``svg``,
``plot_svg`` and ``plot_svg_path`` (any stipple or vpype SVG read back as pen paths per layer),
``png``, ``geojson``, ``checkpoint`` (optimiser state), ``commit`` (the all-or-nothing multi-file commit),
``safety`` (distinct files, one process per checkpoint), ``units`` (lengths and colours); ``writers`` picks the
format's bytes for a point set.
"""
