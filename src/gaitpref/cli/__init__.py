"""The ``gaitpref`` command: one root Typer app (``main.py``) and its sub-apps.

``session``/``db`` (``session.py``), ``bench`` (``simulate.py``), ``gaits`` (``gaits.py``) and the
``console`` command (``console.py``); one Rich console and one error helper for all of them
(``output.py``).  Every module imports only Typer when loaded; commands import what they use.
"""

from gaitpref.cli.main import app, main

__all__ = ["app", "main"]
