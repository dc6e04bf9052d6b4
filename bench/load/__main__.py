"""`python -m bench.load`: see bench.load.run."""

from bench.load.run import main

if __name__ == "__main__":
    main()
