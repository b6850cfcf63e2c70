"""`railride._version.versions`: the versions of the software that made a result, which every
result's document records (``versions``)."""

from __future__ import annotations

import platform
from importlib.metadata import version

import railride as rr
from railride._version import __version__, versions

KEYS = ["railride", "python", "numpy", "scipy", "numba", "pandas", "xarray"]


def test_versions_names_railride_python_and_every_numerical_package():
    got = versions()
    assert list(got) == KEYS
    assert got["railride"] == __version__ and got["python"] == platform.python_version()
    assert all(got[k] == version(k) for k in KEYS[2:])


def test_a_document_records_them_after_its_railride_version():
    doc = rr.frequency_responses(points=8).to_dict()
    keys = list(doc)
    assert keys.index("versions") == keys.index("railride_version") + 1
    assert doc["versions"] == versions()
