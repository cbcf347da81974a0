"""The ``gaitpref`` command: one root Typer app (``main.py``) and its sub-apps.

``session``/``db`` (``session.py``), ``simulate``/``bench`` (``simulate.py``), ``gaits``
(``gaits.py``) and ``console`` (``console.py``).
"""

from gaitpref.cli.main import app, main

__all__ = ["app", "main"]
