"""``python -m railride``: the ``railride`` command line."""

from railride.cli import main

if __name__ == "__main__":
    main()
