"""``python -m gaitpref``: the same command line as the ``gaitpref`` script."""

from gaitpref.cli import main

if __name__ == "__main__":
    main()
