"""Public names of a package imported on first use, so that importing the package (as ``stipple --help`` does)
loads none of its modules."""

import importlib


def lazy_names(package, where):
    """A module ``__getattr__`` for ``package`` that imports ``where[name]`` (a module relative to ``package``)
    on the first access of ``name`` and keeps it in the package's namespace."""
    namespace = importlib.import_module(package).__dict__

    def __getattr__(name):
        if name not in where:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(where[name], package), name)
        namespace[name] = value
        return value

    return __getattr__
