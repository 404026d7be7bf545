"""``python -m mbcomp.cli``: the mbcomp command line."""
import sys

from .main import main

if __name__ == "__main__":
    sys.exit(main())
