"""stipple: halftoning on the torus and the sphere by minimising a discrepancy with NUFFT-based CG.

The public names below are imported on first use, so that ``import stipple.cli`` and ``stipple --help`` load
neither the sphere nor scipy.
"""

from .lazy import lazy_names

__version__ = "0.1.0"
_WHERE = {
    "HalftoneResult": ".halftone",
    "StippleError": ".errors",
    "halftone_sphere": ".sphere",
    "halftone_torus": ".torus",
    "load_density": ".io.images",
    "spherical_design": ".design",
}
__all__ = [*sorted(_WHERE), "__version__"]
__getattr__ = lazy_names(__name__, _WHERE)
