"""Compile the traffic planner's search loop (`traffic/sipp_native.pyx`) with Cython.

Run by `make venv` and `make native`. Optional: without a C++ compiler the build fails with a
message and `traffic` runs the same search in plain Python (`traffic/sipp_loop.py`), slower.
"""

import sys

from Cython.Build import cythonize
from setuptools import Distribution, Extension

EXTENSIONS = [Extension("traffic.sipp_native", ["traffic/sipp_native.pyx"], language="c++")]


def main() -> int:
    modules = cythonize(EXTENSIONS, language_level=3, quiet=True)  # type: ignore[no-untyped-call]
    dist = Distribution({"name": "fleet-native", "ext_modules": modules})
    dist.script_args = ["build_ext", "--inplace", "--build-temp", ".native-build/temp"]
    dist.parse_command_line()
    dist.run_commands()
    return 0


if __name__ == "__main__":
    sys.exit(main())
