"""stipple: halftoning on the torus and the sphere by minimising a discrepancy with NUFFT-based CG."""

from .design import spherical_design
from .errors import StippleError
from .halftone import HalftoneResult
from .io.images import load_density
from .sphere import halftone_sphere
from .torus import halftone_torus

__version__ = "0.1.0"
__all__ = [
    "HalftoneResult",
    "StippleError",
    "halftone_sphere",
    "halftone_torus",
    "load_density",
    "spherical_design",
    "__version__",
]
