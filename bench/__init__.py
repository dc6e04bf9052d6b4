"""Benchmarks: `python -m bench.<name> [--quick]`; each prints readable lines and writes its
figures as flat JSON to `bench/results/<name>.json`."""
