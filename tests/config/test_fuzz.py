"""Property: no config text makes parsing do anything but succeed or raise a named ConfigError.

Configs are drawn as TOML from a valid one with keys replaced by garbage (wrong types, NaN, inf,
negative, huge numbers and sizes, long lists), removed, or added (unknown keys).  Parsing must
return a config or raise :class:`ConfigError` with a table or key that its message names, must
never allocate past a bound (``tracemalloc``), and an accepted config's loop must propose.
"""

from __future__ import annotations

import json
import math
import tracemalloc
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from gaitpref import ConfigError, GaitprefError
from gaitpref.config import parse_config
from gaitpref.config.specs import place

PEAK_BYTES = 50_000_000

HUGE = st.sampled_from([10**7, 10**9, 2**63 - 1, 2**80, 10**300])
NUMBERS = st.one_of(
    st.integers(-5, 20),
    HUGE,
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-300, 5e-324, 1e-12, 1e300, -1e300]),
)
GARBAGE = st.one_of(
    NUMBERS,
    st.booleans(),
    st.text(alphabet=st.characters(min_codepoint=32, max_codepoint=126), max_size=8),
    st.lists(NUMBERS, max_size=4),
    st.sampled_from(["fit", "auto", "drop", "model", "gated-eubo", "eubo"]),
    st.just({}),
)


def _toml(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        return ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return "{ " + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + " }"


def _text(tables: dict[str, dict[str, Any]]) -> str:
    out = []
    for name, table in tables.items():
        out.append(f"[{name}]" if name else "")
        out.extend(f"{key} = {_toml(value)}" for key, value in table.items())
    return "\n".join(out) + "\n"


GOOD: dict[str, dict[str, Any]] = {
    "": {"name": "fuzz", "description": "x"},
    "space.x": {"min": 0.0, "max": 1.0, "num": 5, "coactive": [0.1, 0.2], "unit": "m"},
    "space.y": {"values": [0.1, 0.2, 0.4], "words": ["up", "down"]},
    "model": {
        "lengthscale": {"x": 0.2, "y": 0.1},
        "signal_variance": 0.005,
        "noise": 0.02,
        "jitter": 1e-7,
        "ties": "model",
        "fit": "evidence",
        "refit_every": 5,
    },
    "model.prior": {"signal_variance": [0.005, 0.5]},
    "cospar": {"n": 1, "buffer": 1, "coactive_weight": 1.0, "seed": 0, "strategy": "gated-eubo"},
    "cospar.strategy_settings": {"gates": 2},
}
KEYS = [(table, key) for table, keys in GOOD.items() for key in keys]
SIZES = [("space.x", "num"), ("cospar", "n"), ("cospar", "buffer"), ("model", "refit_every"),
         ("cospar.strategy_settings", "gates"), ("cospar", "seed")]  # fmt: skip


@st.composite
def configs(draw: st.DrawFn) -> str:
    tables = {name: dict(table) for name, table in GOOD.items()}
    for table, key in draw(st.lists(st.sampled_from(KEYS), max_size=3, unique=True)):
        if draw(st.booleans()):
            del tables[table][key]
        else:
            tables[table][key] = draw(GARBAGE)
    for table, key in draw(st.lists(st.sampled_from(SIZES), max_size=2, unique=True)):
        tables[table][key] = draw(st.one_of(HUGE, st.integers(-2, 12)))
    if draw(st.integers(0, 3)) == 0:
        table = draw(st.sampled_from(list(tables)))
        tables[table][draw(st.sampled_from(["noize", "sead", "x", "num", "gate"]))] = 1
    if draw(st.integers(0, 3)) == 0:
        for key in ("min", "max", "num"):
            tables["space.x"].pop(key, None)
        tables["space.x"]["values"] = draw(st.lists(NUMBERS, max_size=6))
    return _text(tables)


@settings(max_examples=300)
@given(configs())
def test_parsing_never_fails_unnamed_never_allocates_past_a_bound(text: str) -> None:
    tracemalloc.start()
    try:
        try:
            cfg = parse_config(text)
        except ConfigError as exc:
            cfg = None
            assert exc.table is not None or exc.key is not None, str(exc)
            assert str(exc).startswith(place(exc.table or "", exc.key) + ":"), str(exc)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < PEAK_BYTES
    if cfg is not None:
        if cfg.subspace == "grid":
            assert len(cfg.space) <= 13 * 13
        else:  # no num, or one past any grid: continuous, on the line path (issue 13)
            assert cfg.space.continuous
        try:
            loop = cfg.make_loop()
            query = loop.ask()
        except GaitprefError:
            return  # a named error (say, a prior that is not positive definite) is an answer
        assert 1 <= len(query.actions) <= len(loop.space)
