"""An error names a config's key or feature shortened, never echoing a megabyte-long name whole.

An unknown key, a feature's table and a start gait's unknown feature were written into the
error as they were: a key of 1,000,000 characters made an error of 1,000,000 characters (on the
terminal, in the console's answer), where every value is shown shortened (``specs.shown``).
"""

from __future__ import annotations

import pytest

from gaitpref.config import parse_config
from gaitpref.errors import ConfigError

BASE = """
[space.a]
min = 0.0
max = 1.0
num = 5
[model]
lengthscale = 0.3
signal_variance = 1.0
noise = 0.1
"""
LONG = "k" * 1_000_000


@pytest.mark.parametrize(
    ("text", "start"),
    [
        (BASE + f'[cospar]\n"{LONG}" = 1\n', "[cospar]: unknown key 'kkk"),
        (BASE.replace("[space.a]", f'[space."{LONG} x"]'), "[space.kkk"),
        (
            BASE.replace("[space.a]", f"[space.{LONG}]").replace("num = 5", "num = 5\nx = 1"),
            "[space.k",
        ),
        (
            BASE.replace("lengthscale = 0.3", f'lengthscale = {{ "{LONG}" = 1 }}'),
            "[model.lengthscale]",
        ),
        (BASE + f'[safety]\nstart = [{{ "{LONG}" = 1.0 }}]\n', "[safety].start: gait 1"),
        (
            BASE.replace("[space.a]", f"[space.{LONG}]")
            + '[cospar]\nsubspace = "grid"\n[safety]\nstart = [{ b = 1.0 }]\n',
            "[safety].start: gait 1",
        ),
    ],
)
def test_a_long_name_is_shortened_in_the_error(text: str, start: str) -> None:
    with pytest.raises(ConfigError) as e:
        parse_config(text)
    message = str(e.value)
    assert message.startswith(start) and len(message) < 500 and "..." in message
