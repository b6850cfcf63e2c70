"""``python -m railride.cli``: the ``railride`` command line."""

from . import main

if __name__ == "__main__":
    main()
