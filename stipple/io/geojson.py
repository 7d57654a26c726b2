"""GeoJSON: sphere points as one MultiPoint feature."""

import json

import numpy as np


def geojson_bytes(lon_lat, properties=None):
    """A FeatureCollection with one MultiPoint feature (lon, lat in degrees)."""
    feature = {
        "type": "Feature",
        "properties": properties or {},
        "geometry": {"type": "MultiPoint", "coordinates": np.round(lon_lat, 7).tolist()},
    }
    return (json.dumps({"type": "FeatureCollection", "features": [feature]}) + "\n").encode()
