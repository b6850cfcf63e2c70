"""Build hook: compile the engine while the wheel is built (the rest is in pyproject.toml).

`railride.engine.compiled.build_cache` compiles the kernels that `railride compare` needs, with numba's
cache next to the built package (``railride/engine/__pycache__``), so the machine code ships inside the
wheel and the first run after ``pip install .`` loads it instead of compiling for ten seconds.
numba keys that cache by a hash of the source, the numba version and this processor: a wheel
carried to another machine, or run with another numba, compiles on its first run as before.
Skipped for editable installs (the cache then lives in the source tree) and when
RAILRIDE_NO_PRECOMPILE is set. A failed compile never fails the build.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildWithEngine(build_py):
    def run(self) -> None:
        super().run()
        # an earlier build's machine code in the build folder: never shipped unless made now
        cache = os.path.join(self.build_lib, "railride", "engine", "__pycache__")
        for name in os.listdir(cache) if os.path.isdir(cache) else []:
            if name.endswith((".nbi", ".nbc")):
                os.remove(os.path.join(cache, name))
        if getattr(self, "editable_mode", False) or os.environ.get("RAILRIDE_NO_PRECOMPILE"):
            return
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        # in front of pip's own entries, which make the isolated build environment's numba visible
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [os.path.abspath(self.build_lib), env.get("PYTHONPATH")]))
        started = time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-c", "import railride.engine.compiled as c; c.build_cache()"],
            cwd=self.build_lib,
            env=env,
            capture_output=True,
            text=True,
        )
        took = time.perf_counter() - started
        if done.returncode == 0:
            print(f"railride: compiled the engine in {took:.0f} s; it ships in the package")
        else:  # the package still works: its first run compiles instead
            tail = (done.stderr or "").strip().splitlines()[-1:]
            print(f"railride: the engine was not precompiled ({' '.join(tail)}); the first run compiles it")


setup(cmdclass={"build_py": BuildWithEngine})
