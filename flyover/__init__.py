"""flyover: diverse, simulation-ready highway interchanges (FLYOVER, ITSC 2023)."""

__version__ = "0.1.0"
__all__ = ["__version__"]
