"""Counted nouns in what the terminal and the commands print: ``1 trial``, ``2 trials``."""

from __future__ import annotations


def plural(count: int, word: str, words: str | None = None) -> str:
    """``count`` and ``word``, in the plural (``words``, else ``word + "s"``) unless it is 1:
    ``plural(1, "trial")`` is ``'1 trial'`` (it said "1 trials"), ``plural(0, "trial")`` is
    ``'0 trials'``."""
    return f"{count} {word}" if count == 1 else f"{count} {words or word + 's'}"
