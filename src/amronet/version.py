"""amronet's version: at the bottom of the layers, so that any module may name it without importing the package."""

__all__ = ["__version__"]

__version__ = "0.1.0"
