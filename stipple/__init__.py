"""stipple: halftoning on the torus and the sphere by minimising a discrepancy with NUFFT-based CG.

The public names below are imported on first use (``__getattr__``), so that ``import stipple.cli`` and
``stipple --help`` load neither the sphere nor scipy.
"""

import importlib

__version__ = "0.1.0"
# Public name -> the module that defines it.
_PUBLIC = {
    "HalftoneResult": ".halftone",
    "StippleError": ".errors",
    "halftone_sphere": ".sphere",
    "halftone_torus": ".torus",
    "load_density": ".io.images",
    "spherical_design": ".design",
}
__all__ = [*sorted(_PUBLIC), "__version__"]


def __getattr__(name):
    if name not in _PUBLIC:
        raise AttributeError(f"module 'stipple' has no attribute {name!r}")
    value = getattr(importlib.import_module(_PUBLIC[name], __name__), name)
    globals()[name] = value
    return value
