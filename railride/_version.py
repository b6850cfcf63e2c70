"""The one version number of railride (read by the build, `pyproject.toml`, without importing the package)."""

__version__ = "0.4.0"
