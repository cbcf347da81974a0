"""Positional arguments of the screens that read ``sys.argv`` themselves (no ``argparse``).

``-h``/``--help`` prints the script's docstring (its usage lines) and stops; a wrong number of
arguments, or an option, stops with the usage and status 2 before any work.
"""

from __future__ import annotations

import sys


def positional(doc: str | None, least: int, most: int | None = None) -> list[str]:
    """``sys.argv[1:]``, checked: between ``least`` and ``most`` (no limit: None), no options."""
    args = sys.argv[1:]
    if any(a in ("-h", "--help") for a in args):
        print(doc or "")
        raise SystemExit(0)
    options = [a for a in args if a.startswith("--")]
    if options or len(args) < least or (most is not None and len(args) > most):
        what = f"takes no options ({options[0]})" if options else "wrong number of arguments"
        print(f"{sys.argv[0]}: {what}\n\n{doc or ''}", file=sys.stderr)
        raise SystemExit(2)
    return args
