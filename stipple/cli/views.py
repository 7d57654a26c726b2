"""A sphere picture's view on the command line: ``--view LON,LAT``, longitudes, and the refusal of a view where no
sphere is drawn."""

import math

from ..errors import StippleError
from ..io.units import parse_number
from .options import given_on_command_line


def check_view_drawn(ctx, formats, drawn=True, names=("view", "projection")):
    """Refuse ``--view`` and ``--projection`` (``names``) given on the command line where no picture of the sphere
    is drawn: no .png or .svg output, or (``drawn`` False) torus points; they would be ignored (a fifth sweep).
    ``stipple sphere``'s pen dots are placed for their size in the projection's picture, which it keeps."""
    given = [f"--{name}" for name in names if given_on_command_line(ctx, name)]
    if given and not (drawn and {".png", ".svg"} & set(formats)):
        raise StippleError(
            f"{' and '.join(given)}: for a picture of the sphere (.png or .svg); here it would be ignored"
        )


def check_longitude(name, value):
    """A finite longitude in [-360, 360] degrees."""
    if not -360 <= value <= 360:
        raise StippleError(f"{name} must be a longitude in [-360, 360] degrees, not {value!r}")
    return float(value)


def parse_view(text, projection="ortho"):
    """``--view LON,LAT`` in degrees; the equirectangular map is centred on a longitude only (a latitude there
    was silently ignored)."""
    try:
        lon, lat = (parse_number(part) for part in text.split(","))
    except ValueError:
        raise StippleError(f"view must be LON,LAT in degrees, not {text!r}") from None
    if not (-90 <= lat <= 90 and math.isfinite(lon)):
        raise StippleError(f"view must be a finite longitude and a latitude in [-90, 90], not {text!r}")
    if projection == "equirect" and lat != 0:
        raise StippleError(
            f"view {text}: the equirectangular map is centred on a longitude only; give {lon:g},0 (a latitude is "
            "for the globe, --projection ortho)"
        )
    return lon, lat
