"""Value specs of the config schema: each checks one value and says in words what it allows.

A spec's ``allowed`` is the phrase every error uses: ``[table].key: must be <allowed>, got
<value>`` (:func:`fail` raises it as a :class:`ConfigError` carrying ``table`` and ``key``).
Every number is finite and at most :data:`MAX_MAGNITUDE` in size; lists are checked for length
before their items, so no check walks a list longer than its bound.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Final, NoReturn, Protocol

from gaitpref.errors import ConfigError

#: Every number is at most this large in magnitude; every scale is at least :data:`MIN_SCALE`.
MAX_MAGNITUDE: Final = 1e12
MIN_SCALE: Final = 1e-12
#: Length of a name, a unit, a word.
MAX_NAME: Final = 200


def clipped(name: str, most: int = 80) -> str:
    """A name (a table's, a key's, a feature's) as an error shows it: at most ``most``
    characters, so that a config's megabyte-long key is not echoed whole."""
    return name if len(name) <= most else name[: most - 3] + "..."


def place(table: str, key: str | None) -> str:
    """``[table].key``, ``[table]`` or (for the top level) ``key`` / ``top level`` (each name
    :func:`clipped`)."""
    table = clipped(table)
    key = None if key is None else clipped(key)
    if not table:
        return key if key is not None else "top level"
    return f"[{table}]" if key is None else f"[{table}].{key}"


def fail(table: str, key: str | None, what: str) -> NoReturn:
    """Raise the :class:`ConfigError` ``[table].key: what``."""
    raise ConfigError(f"{place(table, key)}: {what}", table=table, key=key)


def shown(value: object) -> str:
    """A value as an error shows it (short: a huge list is not echoed whole)."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


class Spec(Protocol):
    """Checks one value; ``allowed`` says in words what it accepts."""

    @property
    def allowed(self) -> str: ...

    def check(self, value: object, table: str, key: str) -> Any: ...


def _bad(spec: Spec, value: object, table: str, key: str) -> NoReturn:
    fail(table, key, f"must be {spec.allowed}, got {shown(value)}")


@dataclass(frozen=True)
class Integer:
    lo: int
    hi: int

    @property
    def allowed(self) -> str:
        return f"an integer from {self.lo} to {self.hi}"

    def check(self, value: object, table: str, key: str) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            _bad(self, value, table, key)
        if value < self.lo:
            fail(table, key, f"must be an integer >= {self.lo}, got {shown(value)}")
        if value > self.hi:
            fail(table, key, f"must be an integer <= {self.hi}, got {shown(value)}")
        return value


@dataclass(frozen=True)
class Number:
    """A finite number in ``[lo, hi]`` (an open end with ``open_lo`` or ``open_hi``)."""

    lo: float = -MAX_MAGNITUDE
    hi: float = MAX_MAGNITUDE
    open_lo: bool = False
    open_hi: bool = False

    @property
    def allowed(self) -> str:
        low = f"> {self.lo:g}" if self.open_lo else f">= {self.lo:g}"
        high = f"< {self.hi:g}" if self.open_hi else f"<= {self.hi:g}"
        return f"a finite number {low} and {high}"

    def check(self, value: object, table: str, key: str) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            _bad(self, value, table, key)
        try:
            number = float(value)
        except OverflowError:  # an integer beyond float range
            _bad(self, value, table, key)
        if not math.isfinite(number) or number > self.hi or (self.open_hi and number == self.hi):
            _bad(self, value, table, key)
        if number < self.lo or (self.open_lo and number == self.lo):
            _bad(self, value, table, key)
        return number


#: A scale (a variance, a noise, a lengthscale): positive, not vanishing, not huge.
SCALE: Final = Number(MIN_SCALE, MAX_MAGNITUDE)


@dataclass(frozen=True)
class Choice:
    values: tuple[str, ...]

    @property
    def allowed(self) -> str:
        return f"one of {', '.join(self.values)}"

    def check(self, value: object, table: str, key: str) -> str:
        if not isinstance(value, str) or value not in self.values:
            _bad(self, value, table, key)
        return value


@dataclass(frozen=True)
class Text:
    max_len: int

    @property
    def allowed(self) -> str:
        return f"text of at most {self.max_len} characters"

    def check(self, value: object, table: str, key: str) -> str:
        if not isinstance(value, str) or len(value) > self.max_len:
            _bad(self, value, table, key)
        return value


@dataclass(frozen=True)
class Numbers:
    """A list of ``min_len..max_len`` numbers, each checked by ``item`` (length checked first)."""

    item: Number
    min_len: int
    max_len: int

    @property
    def allowed(self) -> str:
        size = (
            f"{self.min_len}" if self.min_len == self.max_len else f"{self.min_len}..{self.max_len}"
        )
        return f"a list of {size} numbers, each {self.item.allowed[2:]}"

    def check(self, value: object, table: str, key: str) -> list[float]:
        if not isinstance(value, list) or not self.min_len <= len(value) <= self.max_len:
            _bad(self, value, table, key)
        out = []
        for item in value:
            if isinstance(item, bool) or not isinstance(item, int | float):
                _bad(self, value, table, key)
            try:
                out.append(self.item.check(item, table, key))
            except ConfigError:
                _bad(self, value, table, key)
        return out


@dataclass(frozen=True)
class Words:
    @property
    def allowed(self) -> str:
        return f'two words, e.g. ["longer", "shorter"] (each 1..{MAX_NAME} characters)'

    def check(self, value: object, table: str, key: str) -> tuple[str, str]:
        if (
            not isinstance(value, list)
            or len(value) != 2
            or not all(isinstance(w, str) and 0 < len(w) <= MAX_NAME for w in value)
        ):
            _bad(self, value, table, key)
        return (value[0], value[1])


@dataclass(frozen=True)
class Coactive:
    @property
    def allowed(self) -> str:
        return "[small, big] with 0 < small <= big <= 1 (fractions of the range)"

    def check(self, value: object, table: str, key: str) -> tuple[float, float]:
        pair = Numbers(Number(0.0, 1.0, open_lo=True), 2, 2)
        try:
            small, big = pair.check(value, table, key)
        except ConfigError:
            _bad(self, value, table, key)
        if small > big:
            _bad(self, value, table, key)
        return (small, big)


@dataclass(frozen=True)
class LogNormalPair:
    """A log-normal prior ``[median, sd of the log]``."""

    @property
    def allowed(self) -> str:
        return f"[median, sd] with {MIN_SCALE:g} <= median <= {MAX_MAGNITUDE:g}, 0 <= sd <= 10"

    def check(self, value: object, table: str, key: str) -> tuple[float, float]:
        if not isinstance(value, list) or len(value) != 2:
            _bad(self, value, table, key)
        try:
            return (
                SCALE.check(value[0], table, key),
                Number(0.0, 10.0).check(value[1], table, key),
            )
        except ConfigError:
            _bad(self, value, table, key)


@dataclass(frozen=True)
class ScaleOrFit:
    """``tie_band``: a scale, or ``"fit"`` (learnt by the evidence fit)."""

    @property
    def allowed(self) -> str:
        return f'"fit" or {SCALE.allowed}'

    def check(self, value: object, table: str, key: str) -> float | str:
        if value == "fit":
            return "fit"
        try:
            return SCALE.check(value, table, key)
        except ConfigError:
            _bad(self, value, table, key)


@dataclass(frozen=True)
class Table:
    """A sub-table, checked by its own declaration (``what`` says what it holds)."""

    what: str

    @property
    def allowed(self) -> str:
        return f"a table ({self.what})"

    def check(self, value: object, table: str, key: str) -> dict[str, Any]:
        if not isinstance(value, dict):
            _bad(self, value, table, key)
        return value


@dataclass(frozen=True)
class ScaleOrTable:
    """``lengthscale``: one scale for every feature, or a table ``{feature = scale}``."""

    @property
    def allowed(self) -> str:
        return f"{SCALE.allowed}, or a table {{feature = number}}"

    def check(self, value: object, table: str, key: str) -> float | dict[str, Any]:
        if isinstance(value, dict):
            return value
        try:
            return SCALE.check(value, table, key)
        except ConfigError:
            _bad(self, value, table, key)


@dataclass(frozen=True)
class Labels:
    """``min_len..max_len`` distinct category names, worst first."""

    min_len: int = 2
    max_len: int = 10

    @property
    def allowed(self) -> str:
        return (
            f"a list of {self.min_len} to {self.max_len} distinct names, worst first, e.g. "
            '["very bad", "bad", "okay", "good"]'
        )

    def check(self, value: object, table: str, key: str) -> tuple[str, ...]:
        if (
            not isinstance(value, list)
            or not self.min_len <= len(value) <= self.max_len
            or not all(isinstance(w, str) and 0 < len(w) <= MAX_NAME for w in value)
            or len(set(value)) != len(value)
        ):
            _bad(self, value, table, key)
        return tuple(value)


@dataclass(frozen=True)
class Gaits:
    """A list of at most ``max_len`` gaits, each a gait id (a library's), an action index of the
    grid (C order, from 0) or a table of feature values; which gaits they name is checked against
    the space (``feedback.py``)."""

    max_len: int

    @property
    def allowed(self) -> str:
        return (
            f"a list of at most {self.max_len} gaits, each a gait id, an action index >= 0 or a "
            "table of feature values, e.g. [{step_length = 0.12, step_duration = 0.9}]"
        )

    def check(self, value: object, table: str, key: str) -> list[str | int | dict[str, float]]:
        if not isinstance(value, list) or len(value) > self.max_len:
            _bad(self, value, table, key)
        out: list[str | int | dict[str, float]] = []
        for item in value:
            if (isinstance(item, str) and 0 < len(item) <= MAX_NAME) or (
                isinstance(item, int) and not isinstance(item, bool) and item >= 0
            ):
                out.append(item)
            elif isinstance(item, dict) and 0 < len(item) <= 4 * MAX_NAME:
                out.append({str(k): Number().check(v, table, key) for k, v in item.items()})
            else:
                fail(table, key, f"must be {self.allowed}; gait {len(out) + 1} is {shown(item)}")
        return out
