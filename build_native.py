"""Compile the traffic planner's hot parts (`traffic/_holds.pyx`, `traffic/_search.pyx`).

Run by `make venv` and `make native`. Optional: without a C++ compiler the build fails with a
message and `traffic` makes the same plans in plain Python, slower (`traffic/speedups.py`).
"""

import sys

from Cython.Build import cythonize
from setuptools import Distribution, Extension

EXTENSIONS = [
    Extension(f"traffic.{name}", [f"traffic/{name}.pyx"], language="c++")
    for name in ("_holds", "_search")
]


def main() -> int:
    modules = cythonize(EXTENSIONS, language_level=3, quiet=True)  # type: ignore[no-untyped-call]
    dist = Distribution({"name": "fleet-native", "ext_modules": modules})
    dist.script_args = ["build_ext", "--inplace", "--build-temp", ".native-build/temp"]
    dist.parse_command_line()
    dist.run_commands()
    return 0


if __name__ == "__main__":
    sys.exit(main())
