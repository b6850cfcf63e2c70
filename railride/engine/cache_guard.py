"""A guard on numba's cache of the engine: the machine code of a kernel is stale when any engine
source changed, not only its own file.

numba keys a cached kernel by a hash of the file that defines it, so an edit to a function
inlined from another file (an intrinsic of `railride.engine._simd`, a layout constant, a damper
law in kernels.py inlined into lanes.py) leaves the other files' cached machine code in use,
silently. `guard` keeps a hash (sha256) of every ``railride/engine/*.py`` beside numba's cache
(``engine-sources.sha256``, in ``railride/engine/__pycache__`` or in numba's folder for this
package under ``NUMBA_CACHE_DIR``); when it differs from the sources' hash, it removes the engine
modules' ``*.nbi``/``*.nbc`` files there and stores the new hash, so that the next call compiles
from the sources as they are. `railride.engine.kernels` runs it at import, before any kernel is
compiled or loaded. The package's build (setup.py) compiles the engine after the guard has run,
so the hash ships beside the machine code and an installed package loads that code at once. A
cache folder that cannot be read or written is left alone, quietly: numba then caches elsewhere
or not at all. Imports nothing of railride.
"""

from __future__ import annotations

import glob
import hashlib
import os

#: the file beside numba's cache that holds the hash of the sources its machine code came from
MARKER = "engine-sources.sha256"

#: the engine's folder: the sources hashed, and (as numba does) the cache's place
ENGINE_DIR = os.path.dirname(os.path.abspath(__file__))


def sources_hash(engine_dir: str = ENGINE_DIR) -> str:
    """sha256 of the engine's sources: every ``*.py`` of ``engine_dir``, by name, in name order."""
    digest = hashlib.sha256()
    for path in sorted(glob.glob(os.path.join(engine_dir, "*.py"))):
        digest.update(os.path.basename(path).encode() + b"\0")
        with open(path, "rb") as f:
            digest.update(f.read())
        digest.update(b"\0")
    return digest.hexdigest()


def cache_dir(engine_dir: str = ENGINE_DIR) -> str:
    """The folder numba caches the engine's kernels in: the engine's ``__pycache__``, or its
    folder under numba's NUMBA_CACHE_DIR when that is set (numba names it after the source
    folder and a hash of its path, `numba.core.caching._CacheLocator.get_suitable_cache_subpath`)."""
    from numba.core import config

    root = getattr(config, "CACHE_DIR", "")  # NUMBA_CACHE_DIR, read when numba was imported
    if not root:
        return os.path.join(engine_dir, "__pycache__")
    try:
        from numba.core.caching import _CacheLocator

        sub = _CacheLocator.get_suitable_cache_subpath(os.path.join(engine_dir, "kernels.py"))
    except (ImportError, AttributeError):  # numba's internals moved: its rule as of numba 0.59-0.61
        folder = os.path.abspath(engine_dir)
        sub = os.path.basename(folder) + "_" + hashlib.sha1(folder.encode()).hexdigest()
    return os.path.join(root, sub)


def guard(engine_dir: str = ENGINE_DIR, cache: str | None = None) -> str:
    """Clear the engine's machine code in ``cache`` (default `cache_dir`) if it was compiled from
    other sources than those in ``engine_dir`` now. Returns what it did: "kept" (the stored hash
    matches), "cleared" (it did not, or there was none: the engine modules' cache files removed,
    the new hash stored; a new cache folder is made, as numba would), or "skipped" (the folder
    could not be made, read or written)."""
    cache = cache_dir(engine_dir) if cache is None else cache
    marker = os.path.join(cache, MARKER)
    try:
        current = sources_hash(engine_dir)
        os.makedirs(cache, exist_ok=True)  # numba's next compile fills it: the hash must be there first
        try:
            with open(marker, encoding="ascii") as f:
                if f.read().strip() == current:
                    return "kept"
        except (FileNotFoundError, UnicodeDecodeError):
            pass
        modules = {os.path.splitext(os.path.basename(p))[0] for p in glob.glob(os.path.join(engine_dir, "*.py"))}
        for name in os.listdir(cache):
            # numba's files: <module>.<function>-<line>.py<version>.nbi, and .<n>.nbc beside it
            if name.endswith((".nbi", ".nbc")) and name.split(".", 1)[0] in modules:
                try:
                    os.remove(os.path.join(cache, name))
                except FileNotFoundError:  # another process cleared it first
                    pass
        tmp = f"{marker}.{os.getpid()}.tmp"
        with open(tmp, "w", encoding="ascii") as f:
            f.write(current + "\n")
        os.replace(tmp, marker)  # whole or not at all, should processes race
    except OSError:  # read-only install, another user's folder: numba copes without us
        return "skipped"
    return "cleared"
