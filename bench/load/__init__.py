"""Load benchmark: 1,000 simulated vehicles against the real processes (`python -m bench.load`).

See `bench.load.run` for what is started and measured, and docs/LOAD.md for the results.
"""
