"""railride: vertical ride of a railway vehicle with a semi-active secondary suspension."""
__version__ = "0.1.0"
