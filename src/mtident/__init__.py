"""mtident: machine-tool identification with unscented Kalman filters."""

__version__ = "0.1.0"
__all__ = ["__version__"]
